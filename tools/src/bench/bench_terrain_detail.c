/* bench_terrain_detail.c — the terrain's material textures (issue 12: detail layers, normal maps,
 * macro variation): what they cost at start-up and per frame on llvmpipe (two CPU cores).
 *
 * Rows:
 *   terrain.textures.make_ms               the CPU making every layer (terrain_textures.c)
 *   terrain.textures.renderer_ms           the same inside terrain_renderer_create, uploads and
 *                                          mipmaps included (terrain_renderer_texture_ms)
 *   terrain.detail.frame_ms.640x360.start.off / .on
 *                                          frame wall ms on the world walk's start view (seed 1,
 *                                          the spawn, facing +z, pitch −5.7°; grass off), with
 *                                          the 1 m detail layer off and on (peers in one run)
 *   terrain.detail.frame_ms.640x360.near.off / .on
 *                                          the same looking 50° down at the ground from the
 *                                          spawn: almost every pixel within the detail's reach
 */
#include "bench.h"

#include "core/core.h"
#include "game/app.h"
#include "gfx/gfx.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#define DETAIL_BENCH_FRAMES 10

static double sample_make(void *user) {
    (void)user;
    uint64_t start = core_time_ns();
    terrain__material_texels texels;
    terrain__material_texels_make(&texels);
    double ms = (double)(core_time_ns() - start) * 1e-6;
    terrain__material_texels_free(&texels);
    return ms;
}

static double sample_renderer(void *user) {
    terrain_renderer *renderer = terrain_renderer_create(user, NULL);
    if (!renderer) return 0;
    double ms = terrain_renderer_texture_ms(renderer);
    terrain_renderer_destroy(renderer);
    return ms;
}

static double sample_frames(void *user) {
    game_app *app = user;
    uint64_t start = core_time_ns();
    for (int i = 0; i < DETAIL_BENCH_FRAMES; i++) game_app_frame(app);
    return (double)(core_time_ns() - start) * 1e-6 / DETAIL_BENCH_FRAMES;
}

static void bench_view(bench_context *ctx, const char *name, double pitch_degrees, bool detail) {
    if (!bench_wants(ctx, name)) return;
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 640, .height = 360, .headless = true,
                                                      .threads = bench_threads(ctx), .frames = 1000000,
                                                      .grass = GRASS_OFF, .no_hud = true,
                                                      .no_terrain_detail = !detail,
                                                      .look_set = true, .look = { 0, pitch_degrees } });
    if (!app) {
        core_error("bench", "terrain.detail: the world did not start; row %s skipped", name);
        return;
    }
    while (!game_app_loaded(app)) game_app_frame(app);
    for (int i = 0; i < 20; i++) game_app_frame(app);
    bench_run(ctx, name, "ms", 5, sample_frames, app);
    game_app_destroy(app);
}

void bench_group_terrain_detail(bench_context *ctx) {
    if (bench_wants(ctx, "terrain.textures.make_ms")) bench_run(ctx, "terrain.textures.make_ms", "ms", 5, sample_make, NULL);
    if (bench_wants(ctx, "terrain.textures.renderer_ms")) {
        gfx_context *gfx = gfx_create(&(gfx_desc){ .width = 64, .height = 64, .headless = true });
        if (gfx) {
            bench_run(ctx, "terrain.textures.renderer_ms", "ms", 5, sample_renderer, gfx);
            gfx_destroy(gfx);
        }
    }
    const double start_pitch = -0.1 * 180 / 3.14159265358979;   /* world.walk's walker */
    bench_view(ctx, "terrain.detail.frame_ms.640x360.start.off", start_pitch, false);
    bench_view(ctx, "terrain.detail.frame_ms.640x360.start.on", start_pitch, true);
    bench_view(ctx, "terrain.detail.frame_ms.640x360.near.off", -50, false);
    bench_view(ctx, "terrain.detail.frame_ms.640x360.near.on", -50, true);
}
