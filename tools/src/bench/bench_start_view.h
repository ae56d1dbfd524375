/* bench_start_view.h — the world walk's start view as rows that compare the game's qualities
 * (grass, shadows) measure it: seed 1, the spawn, facing +z with the walker's pitch (−0.1 rad),
 * 640×360 through OSMesa's llvmpipe, once loaded and settled. Peers run in the same process one
 * after another, so every row of a comparison sees the same machine.
 *
 *     game_app_desc desc = bench_start_view_desc(ctx);
 *     desc.shadows = TERRAIN_SHADOWS_HIGH;
 *     game_app *app = bench_start_view_open(&desc);        // NULL: no context, rows skipped
 *     double frame_ms[RUNS];
 *     for (int r = 0; r < RUNS; r++) frame_ms[r] = bench_start_view_frames(app, NULL, NULL);
 *     game_app_destroy(app);
 */
#ifndef BENCH_START_VIEW_H
#define BENCH_START_VIEW_H

#include "bench.h"
#include "game/app.h"

#define BENCH_START_VIEW_FRAMES 20        /* frames a sample averages */

game_app_desc bench_start_view_desc(const bench_context *ctx);
/* The app loaded and 60 frames past loading (grass patches are placed a few a frame). */
game_app *bench_start_view_open(const game_app_desc *desc);
/* Wall ms a frame over BENCH_START_VIEW_FRAMES frames; `each` (if any) runs after every frame. */
double bench_start_view_frames(game_app *app, void (*each)(game_app *app, void *user), void *user);
/* The median of up to 64 samples. */
double bench_median(const double *samples, int count);

#endif
