/* bench_rocks_world.c — rocks placed in a world and drawn (modules/rocks, rocks_place_box and
 * rocks_draw), through OSMesa's llvmpipe for the frame rows.
 *
 * Rows:
 *   rocks.instance.chunk          ms to place the rocks of one 32 m chunk whose columns all hold
 *                                 a 1.5 m rock layer over flat bedrock (a full chunk: the worst
 *                                 case a chunk of the world meets); target ≤ 0.5 ms
 *   rocks.instance.chunk.rocks    rocks that chunk holds
 *   rocks.instance.chunk.world    ms a chunk over the 64 level-0 chunk boxes (32 m cubes) of seed 1
 *                                 around the spawn that hold any rock layer (the generator's talus,
 *                                 scree and lake stones): what the game pays a chunk
 *   rocks.instance.chunk.world.rocks   rocks a chunk over those
 *   rocks.instance.index          ms to lay the tile set out for placement (rocks_place_index_create),
 *                                 once per set: the rows above place with one, as the game does
 *   rocks.draw.640x360            frame ms the rocks add on the world walk's start view (seed 1,
 *                                 the spawn, facing +z; world.walk's first view), 640×360: the
 *                                 frame with rocks less the same frame without (peers in one run)
 *   rocks.draw.640x360.off        that frame without rocks (the base of the row above)
 *   rocks.draw.640x360.drawn      rocks drawn in that view
 *   rocks.draw.640x360.cpu        CPU ms of rocks_draw a frame on that view (rocks_system_stats'
 *                                 draw_ms, the mean over a sample's frames): picking the rocks,
 *                                 writing the batch and the draw call, which on llvmpipe shades
 *                                 the vertices and bins the triangles on this thread
 * The tile set is the game's default, read from out/rocks_tiles.bin when that file holds it.
 */
#include "bench.h"
#include "bench_start_view.h"

#include "core/core.h"
#include "rocks/rocks.h"
#include "terrain/terrain.h"

#include <math.h>

/* ---- placing one chunk ------------------------------------------------------------------------ */

static void layer_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y + 10);
    terrain_stacks_builder_push(b, TERRAIN_ROCKS, 1.5f);
}

static terrain_stacks *layer_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, layer_column, user);
}

typedef struct place_bench {
    rocks_place_desc desc;
    rocks_placement placement;
    int chunk;
} place_bench;

static double sample_place(void *user) {
    place_bench *b = user;
    /* a different chunk each sample: other tiles, the same amount of layer */
    double min[3] = { 32.0 * (b->chunk % 8), 0, 32.0 * (b->chunk / 8 % 8) }, max[3] = { min[0] + 32, 32, min[2] + 32 };
    b->chunk++;
    uint64_t start = core_time_ns();
    rocks_place_box(&b->desc, min, max, &b->placement);
    return (double)(core_time_ns() - start) * 1e-6;
}

static void bench_place(bench_context *ctx, const rocks_tileset *set, const rocks_place_index *index) {
    if (!bench_wants(ctx, "rocks.instance")) return;
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(1),
                                                                      .generate = layer_chunk });
    place_bench b = { .desc = { .tiles = set, .index = index, .world = world } };
    /* the stacks of every chunk the samples read, generated before timing */
    for (int z = -1; z <= 8; z++)
        for (int x = -1; x <= 8; x++) terrain_world_stacks(world, (terrain_chunk_coord){ x, z });
    bench_run(ctx, "rocks.instance.chunk", "ms", 15, sample_place, &b);
    double rocks = (double)b.placement.count;
    bench_record(ctx, "rocks.instance.chunk.rocks", "rocks", &rocks, 1);
    rocks_placement_free(&b.placement);
    terrain_world_destroy(world);
}

/* The world's own chunks: seed 1's 8 × 8 columns of chunks around the spawn, each column's
 * 32 m boxes that meet its rock layers. */
typedef struct world_bench {
    rocks_place_desc desc;
    rocks_placement placement;
    double boxes[256][3];
    int box_count;
    double rocks;
} world_bench;

static double sample_world(void *user) {
    world_bench *b = user;
    uint64_t start = core_time_ns();
    double rocks = 0;
    for (int i = 0; i < b->box_count; i++) {
        double max[3] = { b->boxes[i][0] + 32, b->boxes[i][1] + 32, b->boxes[i][2] + 32 };
        rocks_place_box(&b->desc, b->boxes[i], max, &b->placement);
        rocks += b->placement.count;
    }
    b->rocks = rocks / b->box_count;
    return (double)(core_time_ns() - start) * 1e-6 / b->box_count;
}

static void bench_place_world(bench_context *ctx, const rocks_tileset *set, const rocks_place_index *index) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(1) });
    world_bench *b = core_calloc(1, sizeof *b);
    b->desc = (rocks_place_desc){ .tiles = set, .index = index, .world = world };
    terrain_layer layers[64];
    for (int cz = -4; cz < 4; cz++)
        for (int cx = -4; cx < 4; cx++) {
            const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
            float lo = INFINITY, hi = -INFINITY;
            for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
                for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
                    int n = terrain_stacks_column(stacks, i, k, layers, 64);
                    float y = TERRAIN_FLOOR_Y;
                    for (int l = 0; l < n && l < 64; l++) {
                        if (layers[l].material == TERRAIN_ROCKS) lo = fminf(lo, y), hi = fmaxf(hi, y + layers[l].thickness);
                        y += layers[l].thickness;
                    }
                }
            if (!(lo <= hi)) continue;
            for (double y = floor(lo / 32) * 32; y < hi && b->box_count < 256; y += 32) {
                b->boxes[b->box_count][0] = cx * 32.0, b->boxes[b->box_count][1] = y, b->boxes[b->box_count][2] = cz * 32.0;
                b->box_count++;
            }
        }
    for (int cz = -5; cz <= 4; cz++)                 /* the neighbours' stacks too, before timing */
        for (int cx = -5; cx <= 4; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    if (b->box_count) {
        bench_run(ctx, "rocks.instance.chunk.world", "ms", 7, sample_world, b);
        bench_record(ctx, "rocks.instance.chunk.world.rocks", "rocks", &b->rocks, 1);
    }
    rocks_placement_free(&b->placement);
    core_free(b, sizeof *b);
    terrain_world_destroy(world);
}

/* ---- the index ------------------------------------------------------------------------------- */

typedef struct index_bench {
    const rocks_tileset *set;
    rocks_place_index **index;        /* the last one made, kept for the rows above */
} index_bench;

static double sample_index(void *user) {
    index_bench *b = user;
    rocks_place_index_destroy(*b->index);
    uint64_t start = core_time_ns();
    *b->index = rocks_place_index_create(b->set);
    return (double)(core_time_ns() - start) * 1e-6;
}

/* ---- drawing the start view ------------------------------------------------------------------- */

typedef struct draw_cpu {
    double ms;
    int frames;
} draw_cpu;

static void add_draw_cpu(game_app *app, void *user) {
    draw_cpu *sum = user;
    sum->ms += rocks_system_stats(game_app_rocks(app)).draw_ms;
    sum->frames++;
}

static void bench_draw(bench_context *ctx) {
    if (!bench_wants(ctx, "rocks.draw")) return;
    enum { RUNS = 7 };
    double frames[2][RUNS], drawn = 0, cpu[RUNS];
    for (int on = 0; on < 2; on++) {
        game_app_desc desc = bench_start_view_desc(ctx);
        desc.rocks = on ? ROCKS_ON : ROCKS_OFF;
        desc.rocks_cache_path = bench_rocks_cache_path();
        game_app *app = bench_start_view_open(&desc);
        if (!app) {
            core_log_error("bench", "rocks: the world did not start; rows skipped");
            return;
        }
        for (int r = 0; r < RUNS; r++) {
            draw_cpu sum = { 0 };
            frames[on][r] = bench_start_view_frames(app, on ? add_draw_cpu : NULL, &sum);
            if (on) cpu[r] = sum.frames ? sum.ms / sum.frames : 0.0;
        }
        if (on) drawn = (double)game_app_stats(app).rocks_drawn;
        game_app_destroy(app);
    }
    double base = bench_median(frames[0], RUNS), added[RUNS];
    for (int r = 0; r < RUNS; r++) added[r] = frames[1][r] - base;
    bench_record(ctx, "rocks.draw.640x360", "ms", added, RUNS);
    bench_record(ctx, "rocks.draw.640x360.off", "ms", frames[0], RUNS);
    bench_record(ctx, "rocks.draw.640x360.drawn", "rocks", &drawn, 1);
    bench_record(ctx, "rocks.draw.640x360.cpu", "ms", cpu, RUNS);
}

void bench_group_rocks_world(bench_context *ctx) {
    if (!bench_wants(ctx, "rocks.instance") && !bench_wants(ctx, "rocks.draw")) return;
    if (bench_wants(ctx, "rocks.instance")) {
        rocks_tileset *set = rocks_tileset_create(&(rocks_tileset_desc){ .cache_path = bench_rocks_cache_path() });
        if (!set) {
            core_log_error("bench", "rocks: no tile set; rows skipped");
            return;
        }
        rocks_place_index *index = NULL;
        bench_run(ctx, "rocks.instance.index", "ms", 5, sample_index, &(index_bench){ set, &index });
        if (!index) index = rocks_place_index_create(set);      /* --filter left that row out */
        bench_place(ctx, set, index);
        bench_place_world(ctx, set, index);
        rocks_place_index_destroy(index);
        rocks_tileset_destroy(set);
    }
    bench_draw(ctx);
}
