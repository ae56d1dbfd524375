/* bench_rocks.c — building the rock tile set (paper 001), all cores.
 *
 *   rocks.tiles.n5, rocks.tiles.n6, rocks.tiles.n7
 *       seconds to build the 256-tile set with n = 5, 6, 7 cells a side, the round preset (one
 *       seed a cell, as 001 Table 1 counts), voxels_per_cell 10 (001 §7: n_G = 10·n), on all
 *       cores (--threads), no cache. One build a sample (a build takes seconds).
 *   rocks.tiles.n5.stones, .n6.stones, .n7.stones
 *       rocks in those sets (after dropping rocks that eroded away).
 *   rocks.tiles.n5.cpu, .n6.cpu, .n7.cpu
 *       CPU seconds of all threads for the same builds: on a loaded machine the wall time above
 *       holds other programs' share of the cores, this does not (wall ≈ cpu / cores when idle).
 *   rocks.tiles.n5.mb   memory the n = 5 set holds (set->bytes), MB.
 *   rocks.blocks.tile.* block tiles for cliffs (paper 003), below.
 *
 * Peer: the paper's own figures, printed beside (no code of theirs to run): 7 355 / 17 166 /
 * 33 217 stones in 23 / 73 / 176 s (001 Table 1, a 2010 machine). Targets on this project's
 * 2-core machine: ≤ 1 / 3 / 8 s.
 */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"

#include <math.h>
#include <stdio.h>
#include <time.h>

static double process_cpu_seconds(void) {
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define ROCKS_BENCH_RUNS 3

/* ---- a chunk with a cliff of blocks (003 §5) ---- */

static void bench_wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user, (void)z;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (x < 16 ? 24.0f : 2.0f) - TERRAIN_FLOOR_Y);
}

static terrain_stacks *bench_wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, bench_wall_column, user);
}

typedef struct wall_bench {
    rocks_cliffs *cliffs;
    terrain_world *world;
    uint64_t triangles;
} wall_bench;

static double sample_wall_chunk(void *user) {
    wall_bench *w = user;
    terrain_mesh mesh;
    uint64_t start = core_time_ns();
    if (!terrain_mesh_chunk(w->world, 0, 0, 0, &(terrain_lod_desc){ 0 }, &mesh)) return NAN;
    double ms = (double)(core_time_ns() - start) * 1e-6;
    w->triangles = mesh.index_count / 3;
    terrain_mesh_free(&mesh);
    return ms;
}

/*   rocks.blocks.field_mesh.chunk32         ms for terrain_mesh_chunk (field, meshing, weights,
 *                                           occlusion) of a 32³ chunk crossed by a 22 m wall of
 *                                           bedrock at x = 16, with columnar blocks through the
 *                                           world's hook as the game makes them (rocks_cliffs: the
 *                                           presence of a tile cell is kept after the warm-up)
 *   rocks.blocks.field_mesh.chunk32.plain   the same chunk of the same wall without blocks (the
 *                                           peer, same run); .ratio is the first over it.
 * Target (issue): ≤ 2 × terrain.field_mesh.chunk32. */
static void bench_blocks_chunk(bench_context *ctx) {
    if (!bench_wants(ctx, "rocks.blocks.field_mesh")) return;
    /* the world's own cliffs (rocks_cliffs: joints of 0.6 m, no relief, presence kept per tile
     * cell as every chunk after the first finds it), one stratum of columnar blocks */
    wall_bench with = { .cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 1,
                                                                           .strata = { ROCKS_BLOCK_COLUMNAR } }) };
    wall_bench plain = { 0 };
    with.world = terrain_world_create(&(terrain_world_desc){ .generate = bench_wall_chunk, .amplify = rocks_cliffs_amplify,
                                                            .amplify_user = with.cliffs });
    plain.world = terrain_world_create(&(terrain_world_desc){ .generate = bench_wall_chunk });
    bench_run(ctx, "rocks.blocks.field_mesh.chunk32", "ms", 15, sample_wall_chunk, &with);
    bench_run(ctx, "rocks.blocks.field_mesh.chunk32.plain", "ms", 15, sample_wall_chunk, &plain);
    double a[15], b[15];
    for (int i = 0; i < 15; i++) a[i] = sample_wall_chunk(&with), b[i] = sample_wall_chunk(&plain);
    double ratio[15];
    for (int i = 0; i < 15; i++) ratio[i] = a[i] / b[i];
    bench_record(ctx, "rocks.blocks.field_mesh.chunk32.ratio", "x", ratio, 15);
    printf("  (%llu triangles with blocks, %llu without)\n", (unsigned long long)with.triangles,
           (unsigned long long)plain.triangles);
    terrain_world_destroy(with.world);
    terrain_world_destroy(plain.world);
    rocks_cliffs_destroy(with.cliffs);
}

/* Block tiles for cliffs (paper 003 §4), one per type at the defaults (16 m, ~8 000 points):
 *   rocks.blocks.tile.<type>          seconds to build the tile, one thread
 *   rocks.blocks.tile.<type>.blocks   its blocks (003 Table 1's #B)
 * Paper 003 Table 1: 6.9 (equidimensional), 12.0 (rhombohedral), 25.4 (polyhedral) and
 * 16.3 s (tabular) for ~14 500 points in a 20 m tile; target here ≤ 1 s. */
static void bench_rocks_blocks(bench_context *ctx) {
    static const double paper_seconds[ROCKS_BLOCK_TYPE_END] = {
        [ROCKS_BLOCK_EQUIDIMENSIONAL] = 6.9, [ROCKS_BLOCK_RHOMBOHEDRAL] = 12.0, [ROCKS_BLOCK_POLYHEDRAL] = 25.4,
        [ROCKS_BLOCK_TABULAR] = 16.3,
    };
    for (int type = ROCKS_BLOCK_EQUIDIMENSIONAL; type < ROCKS_BLOCK_TYPE_END; type++) {
        char name[64], blocks_name[80];
        snprintf(name, sizeof name, "rocks.blocks.tile.%s", rocks_block_type_name((rocks_block_type)type));
        snprintf(blocks_name, sizeof blocks_name, "%s.blocks", name);
        if (!bench_wants(ctx, name)) continue;
        double seconds[ROCKS_BENCH_RUNS], blocks[ROCKS_BENCH_RUNS];
        for (int r = 0; r < ROCKS_BENCH_RUNS; r++) {
            rocks_block_tile *tile = rocks_block_tile_create(&(rocks_block_tile_desc){
                .type = (rocks_block_type)type, .seed = (uint64_t)r + 1 });
            seconds[r] = tile->build_seconds;
            blocks[r] = tile->block_count;
            rocks_block_tile_destroy(tile);
        }
        bench_record(ctx, name, "s", seconds, ROCKS_BENCH_RUNS);
        bench_record(ctx, blocks_name, "blocks", blocks, ROCKS_BENCH_RUNS);
        if (paper_seconds[type] > 0)
            printf("  paper (003 Table 1): %.1f s; target here ≤ 1 s\n", paper_seconds[type]);
        else
            printf("  paper (003 Table 1): no columnar row; target here ≤ 1 s\n");
    }
}

void bench_group_rocks(bench_context *ctx) {
    static const int cells[3] = { 5, 6, 7 };
    static const int paper_stones[3] = { 7355, 17166, 33217 };
    static const int paper_seconds[3] = { 23, 73, 176 };
    static const double target_seconds[3] = { 1, 3, 8 };
    job_system *jobs = NULL;
    for (int i = 0; i < 3; i++) {
        char name[64], stones_name[64];
        snprintf(name, sizeof name, "rocks.tiles.n%d", cells[i]);
        snprintf(stones_name, sizeof stones_name, "rocks.tiles.n%d.stones", cells[i]);
        if (!bench_wants(ctx, name) && !bench_wants(ctx, stones_name)) continue;
        if (!jobs) jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
        double seconds[ROCKS_BENCH_RUNS], stones[ROCKS_BENCH_RUNS], mb[ROCKS_BENCH_RUNS], cpu[ROCKS_BENCH_RUNS];
        for (int r = 0; r < ROCKS_BENCH_RUNS; r++) {
            double cpu0 = process_cpu_seconds();
            rocks_tileset *set = rocks_tileset_create(&(rocks_tileset_desc){
                .cells = cells[i], .shape = ROCKS_SHAPE_ROUND, .voxels_per_cell = 10, .jobs = jobs });
            cpu[r] = process_cpu_seconds() - cpu0;
            seconds[r] = set->build_seconds;
            stones[r] = set->rock_count;
            mb[r] = (double)set->bytes / 1e6;
            rocks_tileset_destroy(set);
        }
        bench_record(ctx, name, "s", seconds, ROCKS_BENCH_RUNS);
        bench_record(ctx, stones_name, "stones", stones, ROCKS_BENCH_RUNS);
        char cpu_name[64];
        snprintf(cpu_name, sizeof cpu_name, "rocks.tiles.n%d.cpu", cells[i]);
        bench_record(ctx, cpu_name, "s", cpu, ROCKS_BENCH_RUNS);
        if (i == 0) bench_record(ctx, "rocks.tiles.n5.mb", "MB", mb, ROCKS_BENCH_RUNS);
        printf("  paper (001 Table 1): n = %d: %d stones in %d s; target here ≤ %.0f s\n", cells[i], paper_stones[i],
               paper_seconds[i], target_seconds[i]);
    }
    if (jobs) job_system_destroy(jobs);
    bench_rocks_blocks(ctx);
    bench_blocks_chunk(ctx);
}
