/* bench_grass.c — grass patches (modules/vegetation) through OSMesa's llvmpipe, where the "GPU"
 * is these same two cores: every GPU pass runs on the CPU, and a frame ends with glFinish.
 *
 * Rows:
 *   grass.frame_ms.640x360.low / .high   frame ms the grass adds on the world walk's start view
 *                                        (seed 1, the spawn, facing +z; world.walk's first
 *                                        view), 640×360: frame wall time with the grass at that
 *                                        quality less the same frame without it (peers in one run)
 *   grass.frame_ms.640x360.off           that frame without grass (the base of the two above)
 *   grass.cpu_ms                         ms a frame in the grass code (placing, culling and
 *                                        drawing calls) on that view at the default quality; on
 *                                        llvmpipe the compute passes execute inside those calls
 *   grass.instances.max                  billboards drawn in one frame, in view, by the same code
 *                                        path (2 per tuft), over a dense meadow seen from above
 *   grass.instances.max.frame_ms         that frame's wall ms
 *   grass.place.patch_ms                 ms to place one 32 m patch of the meadow (9 tufts a m²)
 */
#include "bench.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "game/app.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "vegetation/vegetation.h"

#include <math.h>

#define GRASS_BENCH_FRAMES 20

/* ---- the world walk's start view --------------------------------------------------------- */

typedef struct world_view { game_app *app; double grass_ms; } world_view;

static double sample_world_frames(void *user) {
    world_view *w = user;
    uint64_t start = core_time_ns();
    double grass_ms = 0;
    for (int i = 0; i < GRASS_BENCH_FRAMES; i++) {
        game_app_frame(w->app);
        grass_system *grass = game_app_grass(w->app);
        if (grass) grass_ms += grass_stats_get(grass).cpu_ms;
    }
    w->grass_ms = grass_ms / GRASS_BENCH_FRAMES;
    return (double)(core_time_ns() - start) * 1e-6 / GRASS_BENCH_FRAMES;
}

static void median_of(const double *samples, int count, double *out) {
    double sorted[16];
    for (int i = 0; i < count; i++) sorted[i] = samples[i];
    for (int i = 1; i < count; i++)
        for (int j = i; j > 0 && sorted[j] < sorted[j - 1]; j--) {
            double t = sorted[j];
            sorted[j] = sorted[j - 1], sorted[j - 1] = t;
        }
    *out = sorted[count / 2];
}

/* `runs` samples of GRASS_BENCH_FRAMES frames each, once loaded and the grass placed. */
static bool world_frames(bench_context *ctx, grass_quality quality, int runs, double *frame_ms, double *grass_ms) {
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 640, .height = 360, .headless = true,
                                                      .threads = bench_threads(ctx), .frames = 1000000,
                                                      .grass = quality, .no_hud = true,
                                                      /* world.walk's first view: along +z, the
                                                         walker's pitch (−0.1 rad) */
                                                      .look_set = true, .look = { 0, -0.1 * 180 / M_PI } });
    if (!app) return false;
    while (!game_app_loaded(app)) game_app_frame(app);
    for (int i = 0; i < 60; i++) game_app_frame(app);      /* patches placed, a few a frame */
    world_view w = { .app = app };
    for (int r = 0; r < runs; r++) {
        frame_ms[r] = sample_world_frames(&w);
        grass_ms[r] = w.grass_ms;
    }
    game_app_destroy(app);
    return true;
}

static void bench_world_view(bench_context *ctx) {
    if (!bench_wants(ctx, "grass.frame_ms") && !bench_wants(ctx, "grass.cpu_ms")) return;
    enum { RUNS = 7 };
    const grass_quality qualities[3] = { GRASS_OFF, GRASS_LOW, GRASS_HIGH };
    double frames[3][RUNS], grass[3][RUNS], median[3];
    for (int q = 0; q < 3; q++) {
        if (!world_frames(ctx, qualities[q], RUNS, frames[q], grass[q])) {
            core_error("bench", "grass: the world did not start; rows skipped");
            return;
        }
        median_of(frames[q], RUNS, &median[q]);
    }
    bench_record(ctx, "grass.frame_ms.640x360.off", "ms", frames[0], RUNS);
    for (int q = 1; q < 3; q++) {
        double added[RUNS];
        for (int r = 0; r < RUNS; r++) added[r] = frames[q][r] - median[0];
        bench_record(ctx, q == 1 ? "grass.frame_ms.640x360.low" : "grass.frame_ms.640x360.high", "ms", added, RUNS);
    }
    bench_record(ctx, "grass.cpu_ms", "ms", grass[1], RUNS);
    bench_record(ctx, "grass.cpu_ms.high", "ms", grass[2], RUNS);
}

/* ---- a dense meadow from above ----------------------------------------------------------- */

static void meadow_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    float height = 10.0f + 1.5f * (float)(sin((double)x * 0.09) + cos((double)z * 0.07));
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, height - TERRAIN_FLOOR_Y);
}

static terrain_stacks *meadow_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, meadow_column, user);
}

typedef struct meadow {
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *terrain;
    terrain_renderer *renderer;
    grass_system *grass;
    terrain_view view;
} meadow;

static void meadow_frame(meadow *m) {
    gfx_frame_begin(m->gfx);
    terrain_ecs_set_view(m->terrain, &m->view);
    grass_set_view(m->grass, &m->view, NULL);
    ecs_progress(m->ecs, 1.0f / 60.0f);
    terrain_ecs_draw(m->terrain, m->renderer, &m->view);
    grass_draw(m->grass, &m->view);
    gfx_frame_end(m->gfx);
}

static double sample_meadow_frame(void *user) {
    meadow *m = user;
    uint64_t start = core_time_ns();
    meadow_frame(m);
    return (double)(core_time_ns() - start) * 1e-6;
}

/* 7 × 7 chunks (224 m square) of rolling soil, grass of `density` cells a metre out to `range`,
 * the camera `height` above the middle looking `pitch` down. */
static bool meadow_open(meadow *m, bench_context *ctx, int density, float range, double height, float pitch) {
    *m = (meadow){ .gfx = gfx_create(&(gfx_desc){ .width = 640, .height = 360, .headless = true }) };
    if (!m->gfx) return false;
    m->jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    m->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = m->jobs });
    m->world = terrain_world_create(&(terrain_world_desc){ .generate = meadow_chunk });
    m->terrain = terrain_ecs_create(m->ecs, m->world);
    terrain_ecs_spawn_area(m->terrain, 0, 0, 3, 0, 0);
    m->renderer = terrain_renderer_create(m->gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    m->grass = grass_create(&(grass_desc){ .gfx = m->gfx, .ecs = m->ecs, .world = m->world, .quality = GRASS_HIGH,
                                           .density = density, .range = range, .max_placements = 64 });
    m->view = (terrain_view){ .camera = { 16, 10 + height, 16 }, .pitch = pitch, .aspect = 640.0f / 360.0f };
    return m->renderer && m->grass;
}

static void meadow_close(meadow *m) {
    grass_destroy(m->grass);
    terrain_renderer_destroy(m->renderer);
    if (m->terrain) terrain_ecs_destroy(m->terrain);
    ecs_world_destroy(m->ecs);
    terrain_world_destroy(m->world);
    job_system_destroy(m->jobs);
    gfx_destroy(m->gfx);
}

static void bench_instances(bench_context *ctx) {
    if (!bench_wants(ctx, "grass.instances")) return;
    meadow m;
    /* 64 tufts a m², out to 200 m, seen from 60 m up, looking 70° down. */
    if (!meadow_open(&m, ctx, 8, 200.0f, 60.0, -1.22f)) {
        core_error("bench", "grass.instances: no context; rows skipped");
        meadow_close(&m);
        return;
    }
    for (int frame = 0; frame < 3; frame++) meadow_frame(&m);
    double billboards = 2.0 * (double)grass_visible_tufts(m.grass);
    bench_record(ctx, "grass.instances.max", "billboards", &billboards, 1);
    bench_run(ctx, "grass.instances.max.frame_ms", "ms", 3, sample_meadow_frame, &m);
    meadow_close(&m);
}

static double sample_place(void *user) {
    meadow *m = user;
    /* Every patch again: a new system over the same chunks places them all in its first frame. */
    grass_destroy(m->grass);
    m->grass = grass_create(&(grass_desc){ .gfx = m->gfx, .ecs = m->ecs, .world = m->world, .quality = GRASS_HIGH,
                                           .max_placements = 64 });
    /* The frame up to its draws: the draw phase places (and culls); glFinish waits for it. */
    gfx_frame_begin(m->gfx);
    terrain_ecs_set_view(m->terrain, &m->view);
    grass_set_view(m->grass, &m->view, NULL);
    glFinish();
    uint64_t start = core_time_ns();
    ecs_progress(m->ecs, 1.0f / 60.0f);
    glFinish();
    double ms = (double)(core_time_ns() - start) * 1e-6;
    terrain_ecs_draw(m->terrain, m->renderer, &m->view);
    grass_draw(m->grass, &m->view);
    gfx_frame_end(m->gfx);
    uint64_t patches = grass_stats_get(m->grass).placements;
    return patches ? ms / (double)patches : 0.0;
}

static void bench_place(bench_context *ctx) {
    if (!bench_wants(ctx, "grass.place")) return;
    meadow m;
    if (!meadow_open(&m, ctx, 3, 70.0f, 1.7, -0.2f)) {
        meadow_close(&m);
        return;
    }
    for (int frame = 0; frame < 3; frame++) meadow_frame(&m);
    bench_run(ctx, "grass.place.patch_ms", "ms", 5, sample_place, &m);
    meadow_close(&m);
}

void bench_group_grass(bench_context *ctx) {
    bench_place(ctx);
    bench_instances(ctx);
    bench_world_view(ctx);
}
