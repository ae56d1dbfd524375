/* bench_terrain_ao.c — what the terrain's ambient occlusion costs a frame, through OSMesa's
 * llvmpipe (the "GPU" is these same two cores; a frame ends with glFinish).
 *
 * Rows:
 *   gfx.ao.frame_ms.640x360       frame ms the occlusion adds on the world walk's start view
 *                                 (seed 1, the spawn, facing +z, the walker's pitch; grass off),
 *                                 640×360: the frame's wall time lit with the vertices' openness
 *                                 less the same frames just before with the occlusion off
 *                                 (terrain_renderer_set_occlusion; paired runs in one app). The openness is computed when a chunk is
 *                                 meshed (terrain.mesh.chunk32 against .no_ao), so a frame only
 *                                 reads one more byte a vertex and does two multiplies a fragment:
 *                                 expected ≈ 0, within the noise.
 *   gfx.ao.frame_ms.640x360.off   that frame without occlusion (the base of the row above)
 */
#include "bench.h"

#include "core/core.h"
#include "game/app.h"
#include "terrain/terrain.h"

#include <math.h>

#define AO_BENCH_FRAMES 20
#define AO_BENCH_RUNS 7

static double sample_frames(game_app *app) {
    uint64_t start = core_time_ns();
    for (int i = 0; i < AO_BENCH_FRAMES; i++) game_app_frame(app);
    return (double)(core_time_ns() - start) * 1e-6 / AO_BENCH_FRAMES;
}

/* One app, loaded once; each run times AO_BENCH_FRAMES frames with the occlusion and as many
 * without, back to back, so that what else the machine does weighs on both alike. */
void bench_group_terrain_ao(bench_context *ctx) {
    if (!bench_wants(ctx, "gfx.ao.frame_ms")) return;
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 640, .height = 360, .headless = true,
                                                      .threads = bench_threads(ctx), .frames = 1000000,
                                                      .grass = GRASS_OFF, .no_hud = true,
                                                      .look_set = true, .look = { 0, -0.1 * 180 / M_PI } });
    if (!app) {
        core_log_error("bench", "gfx.ao: the world did not start; rows skipped");
        return;
    }
    while (!game_app_loaded(app)) game_app_frame(app);
    for (int i = 0; i < 30; i++) game_app_frame(app);   /* what streams in after loading */
    terrain_renderer *renderer = game_app_renderer(app);
    double added[AO_BENCH_RUNS], without[AO_BENCH_RUNS];
    for (int r = 0; r < AO_BENCH_RUNS; r++) {
        terrain_renderer_set_occlusion(renderer, false);
        without[r] = sample_frames(app);
        terrain_renderer_set_occlusion(renderer, true);
        added[r] = sample_frames(app) - without[r];
    }
    game_app_destroy(app);
    bench_record(ctx, "gfx.ao.frame_ms.640x360", "ms", added, AO_BENCH_RUNS);
    bench_record(ctx, "gfx.ao.frame_ms.640x360.off", "ms", without, AO_BENCH_RUNS);
}
