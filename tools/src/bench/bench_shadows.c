/* bench_shadows.c — the sun's cascaded shadow map (modules/terrain/render/terrain_shadow.c) through
 * OSMesa's llvmpipe, where the "GPU" is these same two cores.
 *
 * Rows:
 *   gfx.shadows.frame_ms.640x360        frame ms that shadows low (the default) add on the world
 *                                       walk's start view (bench_start_view.h; grass low): frame
 *                                       wall time with them less the same frame with shadows off
 *                                       in the same round (the qualities take turns on one world)
 *   gfx.shadows.frame_ms.640x360.high   the same for shadows high
 *   gfx.shadows.frame_ms.640x360.off    that frame with shadows off (the base of the two above)
 */
#include "bench.h"
#include "bench_start_view.h"

#include "core/core.h"
#include "terrain/terrain.h"

/* The three qualities take turns on one running world, a sample each in every round: the
 * machine is shared, and a load that comes and goes then weighs on every quality alike (three
 * worlds one after another saw it on one only). */
void bench_group_shadows(bench_context *ctx) {
    if (!bench_wants(ctx, "gfx.shadows")) return;
    enum { RUNS = 7 };
    const terrain_shadow_quality qualities[3] = { TERRAIN_SHADOWS_OFF, TERRAIN_SHADOWS_LOW, TERRAIN_SHADOWS_HIGH };
    game_app_desc desc = bench_start_view_desc(ctx);
    game_app *app = bench_start_view_open(&desc);
    if (!app) {
        core_log_error("bench", "shadows: the world did not start; rows skipped");
        return;
    }
    double frames[3][RUNS], added[2][RUNS];
    for (int r = 0; r < RUNS; r++)
        for (int q = 0; q < 3; q++) {
            terrain_renderer_set_shadows(game_app_renderer(app), qualities[q]);
            for (int i = 0; i < 3; i++) game_app_frame(app);     /* the new map made and drawn */
            frames[q][r] = bench_start_view_frames(app, NULL, NULL);
        }
    game_app_destroy(app);
    for (int r = 0; r < RUNS; r++)
        for (int q = 1; q < 3; q++) added[q - 1][r] = frames[q][r] - frames[0][r];   /* same round */
    bench_record(ctx, "gfx.shadows.frame_ms.640x360.off", "ms", frames[0], RUNS);
    bench_record(ctx, "gfx.shadows.frame_ms.640x360", "ms", added[0], RUNS);
    bench_record(ctx, "gfx.shadows.frame_ms.640x360.high", "ms", added[1], RUNS);
}
