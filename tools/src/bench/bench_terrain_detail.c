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
 *   terrain.detail.flat.frame_ms.640x360.off / .on
 *                                          frame wall ms of flat bare bedrock seen from 1.7 m,
 *                                          50° down (the terrain pass alone, no world to load),
 *                                          and .added: on less off, pair by pair
 *   terrain.detail.flat.cpu_ms.640x360.*
 *                                          the same in CPU time of the process (llvmpipe's
 *                                          threads included): steadier than wall time while
 *                                          other jobs share the cores
 */
#include "bench.h"

#include "core/core.h"
#include "game/app.h"
#include "gfx/gfx.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <time.h>

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

/* ---- flat bedrock ---- */

typedef struct flat_ground { gfx_context *gfx; terrain_renderer *renderer; terrain_gpu_mesh mesh; double cpu_ms; } flat_ground;

static double process_cpu_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

static double sample_flat(void *user) {
    flat_ground *f = user;
    double cpu_start = process_cpu_ms();
    terrain_view view = { .camera = { 3.3, 1.7, 5.6 }, .pitch = -50 * 3.14159265f / 180, .aspect = 640.0f / 360 };
    uint64_t start = core_time_ns();
    for (int i = 0; i < DETAIL_BENCH_FRAMES; i++) {
        gfx_frame_begin(f->gfx);
        terrain_renderer_draw(f->renderer, &view, &f->mesh, 1);
        gfx_frame_end(f->gfx);
    }
    f->cpu_ms = (process_cpu_ms() - cpu_start) / DETAIL_BENCH_FRAMES;
    return (double)(core_time_ns() - start) * 1e-6 / DETAIL_BENCH_FRAMES;
}

static void bench_flat(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.detail.flat.frame_ms.640x360")) return;
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 640, .height = 360, .headless = true });
    if (!gfx) return;
    terrain_vertex vertices[4] = { { .position = { -500, 0, -500 } }, { .position = { -500, 0, 500 } },
                                   { .position = { 500, 0, 500 } }, { .position = { 500, 0, -500 } } };
    for (int i = 0; i < 4; i++) vertices[i].normal[1] = 1, vertices[i].weights[0] = 255;
    uint32_t indices[6] = { 0, 1, 2, 0, 2, 3 };
    terrain_mesh mesh = { .vertices = vertices, .indices = indices, .vertex_count = 4, .index_count = 6,
                          .bounds_min = { -500, 0, -500 }, .bounds_max = { 500, 0, 500 } };
    /* Both renderers in one context, their samples interleaved: on a shared machine the load
     * drifts, and pairs see the same drift. */
    enum { RUNS = 9 };
    flat_ground f[2];
    double samples[2][RUNS], added[RUNS], cpu[2][RUNS], cpu_added[RUNS];
    for (int on = 0; on < 2; on++)
        f[on] = (flat_ground){ .gfx = gfx, .mesh = terrain_gpu_mesh_upload(&mesh),
                               .renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){
                                   .sea_level = -50, .detail_distance = on ? 0.0f : -1.0f }) };
    if (f[0].renderer && f[1].renderer) {
        for (int on = 0; on < 2; on++) sample_flat(&f[on]);
        for (int r = 0; r < RUNS; r++) {
            for (int on = 0; on < 2; on++) {
                samples[on][r] = sample_flat(&f[on]);
                cpu[on][r] = f[on].cpu_ms;
            }
            added[r] = samples[1][r] - samples[0][r];
            cpu_added[r] = cpu[1][r] - cpu[0][r];
        }
        bench_record(ctx, "terrain.detail.flat.frame_ms.640x360.off", "ms", samples[0], RUNS);
        bench_record(ctx, "terrain.detail.flat.frame_ms.640x360.on", "ms", samples[1], RUNS);
        bench_record(ctx, "terrain.detail.flat.frame_ms.640x360.added", "ms", added, RUNS);
        bench_record(ctx, "terrain.detail.flat.cpu_ms.640x360.off", "ms", cpu[0], RUNS);
        bench_record(ctx, "terrain.detail.flat.cpu_ms.640x360.on", "ms", cpu[1], RUNS);
        bench_record(ctx, "terrain.detail.flat.cpu_ms.640x360.added", "ms", cpu_added, RUNS);
    }
    for (int on = 0; on < 2; on++) {
        terrain_renderer_destroy(f[on].renderer);
        terrain_gpu_mesh_destroy(&f[on].mesh);
    }
    gfx_context_destroy(gfx);
}

/* ---- the world ---- */

static void bench_view(bench_context *ctx, const char *name, double pitch_degrees, bool detail) {
    if (!bench_wants(ctx, name)) return;
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 640, .height = 360, .headless = true,
                                                      .threads = bench_threads(ctx), .frames = 1000000,
                                                      .grass = GRASS_OFF, .no_hud = true,
                                                      .no_terrain_detail = !detail,
                                                      .look_set = true, .look = { 0, pitch_degrees } });
    if (!app) {
        core_log_error("bench", "terrain.detail: the world did not start; row %s skipped", name);
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
        gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 64, .height = 64, .headless = true });
        if (gfx) {
            bench_run(ctx, "terrain.textures.renderer_ms", "ms", 5, sample_renderer, gfx);
            gfx_context_destroy(gfx);
        }
    }
    bench_flat(ctx);
    const double start_pitch = -0.1 * 180 / 3.14159265358979;   /* world.walk's walker */
    bench_view(ctx, "terrain.detail.frame_ms.640x360.start.off", start_pitch, false);
    bench_view(ctx, "terrain.detail.frame_ms.640x360.start.on", start_pitch, true);
    bench_view(ctx, "terrain.detail.frame_ms.640x360.near.off", -50, false);
    bench_view(ctx, "terrain.detail.frame_ms.640x360.near.on", -50, true);
}
