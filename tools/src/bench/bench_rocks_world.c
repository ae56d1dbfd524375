/* bench_rocks_world.c — rocks placed in a world and drawn (modules/rocks, rocks_place_box and
 * rocks_draw), through OSMesa's llvmpipe for the frame rows.
 *
 * Rows:
 *   rocks.instance.chunk          ms to place the rocks of one 32 m chunk whose columns all hold
 *                                 a 1.5 m rock layer over flat bedrock (a full chunk: the worst
 *                                 case a chunk of the world meets); target ≤ 0.5 ms
 *   rocks.instance.chunk.rocks    rocks that chunk holds
 *   rocks.draw.640x360            frame ms the rocks add on the world walk's start view (seed 1,
 *                                 the spawn, facing +z; world.walk's first view), 640×360: the
 *                                 frame with rocks less the same frame without (peers in one run)
 *   rocks.draw.640x360.off        that frame without rocks (the base of the row above)
 *   rocks.draw.640x360.drawn      rocks drawn in that view
 * The tile set is the game's default, read from out/rocks_tiles.bin when that file holds it.
 */
#include "bench.h"
#include "bench_start_view.h"

#include "core/core.h"
#include "rocks/rocks.h"
#include "terrain/terrain.h"

#include <sys/stat.h>

static const char *cache_path(void) {
    struct stat st;
    return stat("out", &st) == 0 && S_ISDIR(st.st_mode) ? "out/rocks_tiles.bin" : NULL;
}

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

static void bench_place(bench_context *ctx, const rocks_tileset *set) {
    if (!bench_wants(ctx, "rocks.instance")) return;
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(1),
                                                                      .generate = layer_chunk });
    place_bench b = { .desc = { .tiles = set, .world = world } };
    /* the stacks of every chunk the samples read, generated before timing */
    for (int z = -1; z <= 8; z++)
        for (int x = -1; x <= 8; x++) terrain_world_stacks(world, (terrain_chunk_coord){ x, z });
    bench_run(ctx, "rocks.instance.chunk", "ms", 15, sample_place, &b);
    double rocks = (double)b.placement.count;
    bench_record(ctx, "rocks.instance.chunk.rocks", "rocks", &rocks, 1);
    rocks_placement_free(&b.placement);
    terrain_world_destroy(world);
}

/* ---- drawing the start view ------------------------------------------------------------------- */

static void bench_draw(bench_context *ctx) {
    if (!bench_wants(ctx, "rocks.draw")) return;
    enum { RUNS = 7 };
    double frames[2][RUNS], drawn = 0;
    for (int on = 0; on < 2; on++) {
        game_app_desc desc = bench_start_view_desc(ctx);
        desc.rocks = on ? ROCKS_ON : ROCKS_OFF;
        desc.rocks_cache_path = cache_path();
        game_app *app = bench_start_view_open(&desc);
        if (!app) {
            core_error("bench", "rocks: the world did not start; rows skipped");
            return;
        }
        for (int r = 0; r < RUNS; r++) frames[on][r] = bench_start_view_frames(app, NULL, NULL);
        if (on) drawn = (double)game_app_stats_get(app).rocks_drawn;
        game_app_destroy(app);
    }
    double base = bench_median(frames[0], RUNS), added[RUNS];
    for (int r = 0; r < RUNS; r++) added[r] = frames[1][r] - base;
    bench_record(ctx, "rocks.draw.640x360", "ms", added, RUNS);
    bench_record(ctx, "rocks.draw.640x360.off", "ms", frames[0], RUNS);
    bench_record(ctx, "rocks.draw.640x360.drawn", "rocks", &drawn, 1);
}

void bench_group_rocks_world(bench_context *ctx) {
    if (!bench_wants(ctx, "rocks.instance") && !bench_wants(ctx, "rocks.draw")) return;
    if (bench_wants(ctx, "rocks.instance")) {
        rocks_tileset *set = rocks_tiles_create(&(rocks_tiles_desc){ .cache_path = cache_path() });
        if (!set) {
            core_error("bench", "rocks: no tile set; rows skipped");
            return;
        }
        bench_place(ctx, set);
        rocks_tiles_destroy(set);
    }
    bench_draw(ctx);
}
