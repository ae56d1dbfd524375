/* bench_grass.c — grass patches (modules/vegetation) through OSMesa's llvmpipe, where the "GPU"
 * is these same two cores: every GPU pass runs on the CPU, and a frame ends with glFinish.
 *
 * Rows:
 *   grass.frame_ms.640x360.low / .high   frame ms the grass adds on the world walk's start view
 *                                        (seed 1, the spawn, facing +z; world.walk's first
 *                                        view; shadows low, the game's default), 640×360: frame
 *                                        wall time with the grass at that
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
#include "bench_start_view.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "game/app.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "vegetation/vegetation.h"

#include <math.h>

/* ---- the world walk's start view --------------------------------------------------------- */

static void add_grass_ms(game_app *app, void *user) {
    grass_system *grass = game_app_grass(app);
    if (grass) *(double *)user += grass_system_stats(grass).cpu_ms;
}

/* `runs` samples of the start view's frames at a grass quality (shadows at the game's default). */
static bool world_frames(bench_context *ctx, grass_quality quality, int runs, double *frame_ms, double *grass_ms) {
    game_app_desc desc = bench_start_view_desc(ctx);
    desc.grass = quality;
    game_app *app = bench_start_view_open(&desc);
    if (!app) return false;
    for (int r = 0; r < runs; r++) {
        double sum = 0;
        frame_ms[r] = bench_start_view_frames(app, add_grass_ms, &sum);
        grass_ms[r] = sum / BENCH_START_VIEW_FRAMES;
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
            core_log_error("bench", "grass: the world did not start; rows skipped");
            return;
        }
        median[q] = bench_median(frames[q], RUNS);
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
    *m = (meadow){ .gfx = gfx_context_create(&(gfx_context_desc){ .width = 640, .height = 360, .headless = true }) };
    if (!m->gfx) return false;
    m->jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    m->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = m->jobs });
    m->world = terrain_world_create(&(terrain_world_desc){ .generate = meadow_chunk });
    m->terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = m->ecs, .terrain = m->world });
    terrain_ecs_spawn_area(m->terrain, 0, 0, 3, 0, 0);
    m->renderer = terrain_renderer_create(m->gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    m->grass = grass_system_create(&(grass_system_desc){ .gfx = m->gfx, .ecs = m->ecs, .world = m->world, .quality = GRASS_HIGH,
                                           .density = density, .range = range, .max_placements = 64 });
    m->view = (terrain_view){ .camera = { 16, 10 + height, 16 }, .pitch = pitch, .aspect = 640.0f / 360.0f };
    return m->renderer && m->grass;
}

static void meadow_close(meadow *m) {
    grass_system_destroy(m->grass);
    terrain_renderer_destroy(m->renderer);
    if (m->terrain) terrain_ecs_destroy(m->terrain);
    ecs_world_destroy(m->ecs);
    terrain_world_destroy(m->world);
    job_system_destroy(m->jobs);
    gfx_context_destroy(m->gfx);
}

static void bench_instances(bench_context *ctx) {
    if (!bench_wants(ctx, "grass.instances")) return;
    meadow m;
    /* 64 tufts a m², out to 200 m, seen from 60 m up, looking 70° down. */
    if (!meadow_open(&m, ctx, 8, 200.0f, 60.0, -1.22f)) {
        core_log_error("bench", "grass.instances: no context; rows skipped");
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
    grass_system_destroy(m->grass);
    m->grass = grass_system_create(&(grass_system_desc){ .gfx = m->gfx, .ecs = m->ecs, .world = m->world, .quality = GRASS_HIGH,
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
    uint64_t patches = grass_system_stats(m->grass).placements;
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
