/* bench_shadows.c — the sun's cascaded shadow map (modules/terrain/terrain_shadow.c) through
 * OSMesa's llvmpipe, where the "GPU" is these same two cores.
 *
 * Rows:
 *   gfx.shadows.frame_ms.640x360        frame ms that shadows low (the default) add on the world
 *                                       walk's start view (bench_start_view.h; grass low): frame
 *                                       wall time with them less the same frame with shadows off,
 *                                       both in this run
 *   gfx.shadows.frame_ms.640x360.high   the same for shadows high
 *   gfx.shadows.frame_ms.640x360.off    that frame with shadows off (the base of the two above)
 */
#include "bench.h"
#include "bench_start_view.h"

#include "core/core.h"
#include "terrain/terrain.h"

void bench_group_shadows(bench_context *ctx) {
    if (!bench_wants(ctx, "gfx.shadows")) return;
    enum { RUNS = 7 };
    const terrain_shadow_quality qualities[3] = { TERRAIN_SHADOWS_OFF, TERRAIN_SHADOWS_LOW, TERRAIN_SHADOWS_HIGH };
    double frames[3][RUNS];
    for (int q = 0; q < 3; q++) {
        game_app_desc desc = bench_start_view_desc(ctx);
        desc.shadows = qualities[q];
        game_app *app = bench_start_view_open(&desc);
        if (!app) {
            core_error("bench", "shadows: the world did not start; rows skipped");
            return;
        }
        for (int r = 0; r < RUNS; r++) frames[q][r] = bench_start_view_frames(app, NULL, NULL);
        game_app_destroy(app);
    }
    double base = bench_median(frames[0], RUNS);
    bench_record(ctx, "gfx.shadows.frame_ms.640x360.off", "ms", frames[0], RUNS);
    for (int q = 1; q < 3; q++) {
        double added[RUNS];
        for (int r = 0; r < RUNS; r++) added[r] = frames[q][r] - base;
        bench_record(ctx, q == 1 ? "gfx.shadows.frame_ms.640x360" : "gfx.shadows.frame_ms.640x360.high", "ms", added,
                     RUNS);
    }
}
