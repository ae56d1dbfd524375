/* bench_terrain_ao.c — what the terrain's ambient occlusion costs a frame, through OSMesa's
 * llvmpipe (the "GPU" is these same two cores; a frame ends with glFinish).
 *
 * Rows:
 *   gfx.ao.frame_ms.640x360       frame ms the occlusion adds on the world walk's start view
 *                                 (seed 1, the spawn, facing +z, the walker's pitch; grass off),
 *                                 640×360: the frame's wall time lit with the vertices' openness
 *                                 less the same frame with terrain_renderer_desc.no_occlusion
 *                                 (peers in one run). The openness is computed when a chunk is
 *                                 meshed (terrain.mesh.chunk32 against .no_ao), so a frame only
 *                                 reads one more byte a vertex and does two multiplies a fragment:
 *                                 expected ≈ 0, within the noise.
 *   gfx.ao.frame_ms.640x360.off   that frame without occlusion (the base of the row above)
 */
#include "bench.h"

#include "core/core.h"
#include "game/app.h"

#include <math.h>

#define AO_BENCH_FRAMES 20
#define AO_BENCH_RUNS 7

static double sample_frames(void *user) {
    game_app *app = user;
    uint64_t start = core_time_ns();
    for (int i = 0; i < AO_BENCH_FRAMES; i++) game_app_frame(app);
    return (double)(core_time_ns() - start) * 1e-6 / AO_BENCH_FRAMES;
}

/* AO_BENCH_RUNS samples of AO_BENCH_FRAMES frames each, once the start area is loaded. */
static bool view_frames(bench_context *ctx, bool no_occlusion, double *frame_ms) {
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 640, .height = 360, .headless = true,
                                                      .threads = bench_threads(ctx), .frames = 1000000,
                                                      .grass = GRASS_OFF, .no_hud = true,
                                                      .no_occlusion = no_occlusion,
                                                      .look_set = true, .look = { 0, -0.1 * 180 / M_PI } });
    if (!app) return false;
    while (!game_app_loaded(app)) game_app_frame(app);
    for (int i = 0; i < 30; i++) game_app_frame(app);   /* what streams in after loading */
    for (int r = 0; r < AO_BENCH_RUNS; r++) frame_ms[r] = sample_frames(app);
    game_app_destroy(app);
    return true;
}

static double median_of(const double *samples, int count) {
    double sorted[AO_BENCH_RUNS];
    for (int i = 0; i < count; i++) sorted[i] = samples[i];
    for (int i = 1; i < count; i++)
        for (int j = i; j > 0 && sorted[j] < sorted[j - 1]; j--) {
            double t = sorted[j];
            sorted[j] = sorted[j - 1], sorted[j - 1] = t;
        }
    return sorted[count / 2];
}

void bench_group_terrain_ao(bench_context *ctx) {
    if (!bench_wants(ctx, "gfx.ao.frame_ms")) return;
    double with[AO_BENCH_RUNS], without[AO_BENCH_RUNS], added[AO_BENCH_RUNS];
    if (!view_frames(ctx, true, without) || !view_frames(ctx, false, with)) {
        core_error("bench", "gfx.ao: the world did not start; rows skipped");
        return;
    }
    double base = median_of(without, AO_BENCH_RUNS);
    for (int r = 0; r < AO_BENCH_RUNS; r++) added[r] = with[r] - base;
    bench_record(ctx, "gfx.ao.frame_ms.640x360", "ms", added, AO_BENCH_RUNS);
    bench_record(ctx, "gfx.ao.frame_ms.640x360.off", "ms", without, AO_BENCH_RUNS);
}
