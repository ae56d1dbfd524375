/* bench_water.c — water surfaces (terrain_water.c) through OSMesa's llvmpipe, where the "GPU" is
 * these same two cores: every pass runs on the CPU, and a frame ends with glFinish.
 *
 * Rows:
 *   water.frame_ms.low / .medium / .high
 *                                frame ms the water adds at 640×360 on a view over the sea: a
 *                                hand-made coast (a sand shelf falling from a beach to 30 m
 *                                deep), the camera 6 m over the water looking out to sea with
 *                                the beach in view; frame wall time with the water at that
 *                                quality less the median of the same frames with it off (the
 *                                same process, context and chunks: peers in one run, their
 *                                samples interleaved). Far terrain, flat 10 m under the sea,
 *                                gives low its depths (without it low would read the frame as
 *                                medium does); it is drawn at every quality alike.
 *   water.frame_ms.off           those frames with the water off (the base of the two above)
 */
#include "bench.h"
#include "bench_start_view.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

#include <math.h>

#define WATER_BENCH_FRAMES 10             /* frames a sample averages */

/* The coast: dry sand above 0 m for z > 40, the bed falling 0.4 m a metre out to sea (−z) to
 * 30 m deep, water above it up to the sea at 0 m. */
static void coast_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    double ground = fmax(-30.0, fmin(4.0, 0.4 * ((double)z - 40.0) + 0.8 * sin((double)x * 0.13)));
    float quantized = roundf((float)ground * 32.0f) / 32.0f;
    terrain_stacks_builder_push(builder, TERRAIN_SAND, quantized - TERRAIN_FLOOR_Y);
    if (quantized < 0) terrain_stacks_builder_push(builder, TERRAIN_WATER, -quantized);
}

static terrain_stacks *coast_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, coast_column, user);
}

typedef struct coast {
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *terrain;
    terrain_renderer *renderer;
    terrain_clipmap *far;
    terrain_water *water;
    terrain_view view;
} coast;

static void coast_frame(coast *c) {
    gfx_frame_begin(c->gfx);
    terrain_clipmap_update(c->far, c->view.camera);
    terrain_ecs_set_view(c->terrain, &c->view);
    ecs_progress(c->ecs, 1.0f / 60.0f);
    terrain_ecs_draw(c->terrain, c->renderer, &c->view);
    terrain_water_draw(c->water, c->terrain, c->renderer, &c->view);
    gfx_frame_end(c->gfx);
}

static double sample_coast_frames(void *user) {
    coast *c = user;
    uint64_t start = core_time_ns();
    for (int frame = 0; frame < WATER_BENCH_FRAMES; frame++) coast_frame(c);
    return (double)(core_time_ns() - start) * 1e-6 / WATER_BENCH_FRAMES;
}

static bool coast_open(coast *c, bench_context *ctx) {
    *c = (coast){ .gfx = gfx_context_create(&(gfx_context_desc){ .width = 640, .height = 360, .headless = true }) };
    if (!c->gfx) return false;
    c->jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    c->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = c->jobs });
    terrain_generation_desc generation = terrain_generation_defaults(1);
    generation.sea_level = 0;
    c->world = terrain_world_create(&(terrain_world_desc){ .generation = generation, .generate = coast_chunk });
    c->terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = c->ecs, .terrain = c->world });
    terrain_ecs_spawn_area(c->terrain, 0, 0, 2, -1, 0);
    c->renderer = terrain_renderer_create(c->gfx, &(terrain_renderer_desc){ .sea_level = 0 });
    terrain_generation_desc flat = generation;
    flat.relief_height = flat.vertical_perturbation = flat.horizontal_perturbation = 0;
    flat.base_height = -10;
    flat.cave_threshold = flat.lake_spacing = 0;
    c->far = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = flat });
    if (c->renderer) terrain_renderer_set_clipmap(c->renderer, c->far);
    c->water = terrain_water_create(&(terrain_water_desc){ .gfx = c->gfx, .ecs = c->ecs, .world = c->world,
                                                           .quality = TERRAIN_WATER_OFF });
    /* On the beach's edge looking out to sea (−z), a little down. */
    c->view = (terrain_view){ .camera = { 16, 6, 48 }, .pitch = -0.12f, .aspect = 640.0f / 360.0f };
    return c->renderer && c->water;
}

static void coast_close(coast *c) {
    terrain_water_destroy(c->water);
    terrain_renderer_destroy(c->renderer);
    terrain_clipmap_destroy(c->far);
    if (c->terrain) terrain_ecs_destroy(c->terrain);
    ecs_world_destroy(c->ecs);
    terrain_world_destroy(c->world);
    job_system_destroy(c->jobs);
    gfx_context_destroy(c->gfx);
}

void bench_group_water(bench_context *ctx) {
    if (!bench_wants(ctx, "water.frame_ms")) return;
    enum { RUNS = 7 };
    coast c;
    if (!coast_open(&c, ctx)) {
        core_log_error("bench", "water: no context; rows skipped");
        if (c.gfx) coast_close(&c);
        return;
    }
    for (int frame = 0; frame < 5; frame++) coast_frame(&c);     /* meshed and uploaded */
    enum { QUALITIES = 4 };
    const terrain_water_quality qualities[QUALITIES] = { TERRAIN_WATER_OFF, TERRAIN_WATER_LOW, TERRAIN_WATER_MEDIUM,
                                                         TERRAIN_WATER_HIGH };
    static const char *const rows[QUALITIES] = { "water.frame_ms.off", "water.frame_ms.low", "water.frame_ms.medium",
                                                 "water.frame_ms.high" };
    double frames[QUALITIES][RUNS];
    /* Interleaved (off, low, medium, high, off, …) so that a change in the machine's load during
     * the run weighs on all alike. */
    for (int r = 0; r < RUNS; r++)
        for (int q = 0; q < QUALITIES; q++) {
            terrain_water_set_quality(c.water, qualities[q]);
            coast_frame(&c);                                      /* targets made, caches warm */
            frames[q][r] = sample_coast_frames(&c);
        }
    double base = bench_median(frames[0], RUNS);
    bench_record(ctx, rows[0], "ms", frames[0], RUNS);
    for (int q = 1; q < QUALITIES; q++) {
        double added[RUNS];
        for (int r = 0; r < RUNS; r++) added[r] = frames[q][r] - base;
        bench_record(ctx, rows[q], "ms", added, RUNS);
    }
    coast_close(&c);
}
