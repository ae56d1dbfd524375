/* bench_terrain_stabilize.c — stabilization by the angle of repose after the editing brushes
 * (000 §3.4, §4).
 *
 *   terrain.stabilize.deposit   ms for terrain_stabilize_region to converge after depositing
 *       10 000 m³ of sand (smooth brush, radius 16 m: a mound 37 m high that has to spread to a
 *       cone of about 25 m radius at 33°) at the centre of a fresh 256 × 256-column region of
 *       flat bedrock, with bench_threads() threads. Target ≤ 50 ms on 2 cores. Each run loads
 *       the region and deposits before the clock starts; default parameters (step 1 m, no
 *       tolerance: every slope ends at or under the angle of repose).
 *   terrain.stabilize.deposit.iterations, .moved_m3   iterations to converge, volume moved
 *       between columns (m³, one quantum·column is 1/32 m³).
 *   terrain.stabilize.deposit.1thread   the same on one thread (no job system).
 *   terrain.stabilize.deposit.step_quarter   the same with step = 1/4 m, nearer the paper's
 *       "small constant amount": more iterations.
 *   terrain.stabilize.deposit.chunks   the same with the region split into 8 × 8 regions of one
 *       chunk stabilized together (terrain_stabilize_regions), as the engine keeps them: the
 *       cost of the halos. Same result, byte for byte.
 *   terrain.stabilize.deposit.generated   the same deposit on generated terrain (seed 42, the
 *       8 × 8 chunks from (0, 0)): only the pile's columns are marked, so the generated slopes
 *       around it move only where the pile reaches them.
 *   terrain.stabilize.erode   ms to converge after a collapse erosion (ball of radius 12 m,
 *       ρ = 0.3) at the ground of the generated region's centre.
 */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

#include <stdio.h>
#include <stdlib.h>

enum { REGION_CHUNKS = 8, REGION_COLUMNS = REGION_CHUNKS * TERRAIN_CHUNK_COLUMNS, STABILIZE_RUNS = 7 };
#define PILE_VOLUME 10000.0
#define PILE_RADIUS 16.0f

typedef struct stabilize_bench {
    job_system *jobs;                 /* NULL: one thread */
    terrain_stacks *stacks[REGION_CHUNKS * REGION_CHUNKS];
    terrain_stabilize_desc params;
    bool erode;
    bool per_chunk;                   /* one region per chunk instead of one big region */
    double iterations[32], moved[32];
    int runs_seen;
} stabilize_bench;

static void flat_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, 256.0f);   /* up to y = 0 */
}

static void load_flat(stabilize_bench *b) {
    for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++)
        b->stacks[n] = terrain_stacks_from_columns((terrain_chunk_coord){ n % REGION_CHUNKS, n / REGION_CHUNKS },
                                                   flat_column, NULL);
}

static void load_generated(stabilize_bench *b) {
    terrain_generation_desc params = terrain_generation_defaults(42);
    for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++)
        b->stacks[n] = terrain_generate_chunk(&params, (terrain_chunk_coord){ n % REGION_CHUNKS, n / REGION_CHUNKS });
}

static void free_chunks(stabilize_bench *b) {
    for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++) terrain_stacks_destroy(b->stacks[n]);
}

static terrain_columns *fresh_region(const stabilize_bench *b) {
    terrain_columns *region = terrain_columns_create(
        &(terrain_columns_desc){ .width = REGION_COLUMNS, .depth = REGION_COLUMNS });
    for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++)
        terrain_columns_load(region, (terrain_chunk_coord){ n % REGION_CHUNKS, n / REGION_CHUNKS }, b->stacks[n]);
    return region;
}

static void edit(const stabilize_bench *b, terrain_columns *region) {
    double centre = REGION_COLUMNS / 2;
    if (b->erode) {
        float ground = terrain_columns_top(region, REGION_COLUMNS / 2, REGION_COLUMNS / 2);
        terrain_erode(region, &(terrain_erode_desc){ .mode = TERRAIN_ERODE_COLLAPSE, .x = centre, .y = ground,
                                                     .z = centre, .radius = 12.0f, .rocks_ratio = 0.3f }, NULL);
    } else {
        terrain_deposit(region, &(terrain_deposit_desc){ .material = TERRAIN_BRUSH_SAND, .x = centre, .z = centre,
                                                         .radius = PILE_RADIUS, .volume = PILE_VOLUME }, NULL);
    }
}

/* The edited region cut into one region per chunk, with the columns under the brush marked as
 * the brush marked them (copied with terrain_columns_set, which marks; the few extra columns at
 * the rim hold no sand on flat ground and stay as they are). */
static void split_region(terrain_columns *region, terrain_columns **chunks) {
    for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++) {
        terrain_chunk_coord c = { n % REGION_CHUNKS, n / REGION_CHUNKS };
        chunks[n] = terrain_columns_create(&(terrain_columns_desc){ .x = c.x * TERRAIN_CHUNK_COLUMNS,
                                                                    .z = c.z * TERRAIN_CHUNK_COLUMNS,
                                                                    .width = TERRAIN_CHUNK_COLUMNS,
                                                                    .depth = TERRAIN_CHUNK_COLUMNS });
        terrain_stacks *stacks = terrain_columns_to_stacks(region, c);
        terrain_columns_load(chunks[n], c, stacks);
        terrain_stacks_destroy(stacks);
    }
    int centre = REGION_COLUMNS / 2, reach = (int)PILE_RADIUS + 1;
    terrain_layer layers[16];
    for (int z = centre - reach; z <= centre + reach; z++)
        for (int x = centre - reach; x <= centre + reach; x++) {
            int count = terrain_columns_get(region, x, z, layers, 16);
            int n = (z / TERRAIN_CHUNK_COLUMNS) * REGION_CHUNKS + x / TERRAIN_CHUNK_COLUMNS;
            terrain_columns_set(chunks[n], x % TERRAIN_CHUNK_COLUMNS, z % TERRAIN_CHUNK_COLUMNS, layers, count);
        }
}

static double sample_stabilize(void *user) {
    stabilize_bench *b = user;
    terrain_columns *region = fresh_region(b);
    edit(b, region);
    terrain_columns *chunks[REGION_CHUNKS * REGION_CHUNKS];
    if (b->per_chunk) split_region(region, chunks);
    terrain_stabilize_result result;
    uint64_t start = core_time_ns();
    if (b->per_chunk) terrain_stabilize_regions(chunks, REGION_CHUNKS * REGION_CHUNKS, &b->params, b->jobs, &result);
    else terrain_stabilize_region(region, &b->params, b->jobs, &result);
    double ms = core_ns_to_ms(core_time_ns() - start);
    if (!result.converged) core_warn("bench", "stabilize: not converged");
    int slot = b->runs_seen++ % 32;
    b->iterations[slot] = result.iterations;
    b->moved[slot] = (double)result.moved / 32.0;
    if (b->per_chunk)
        for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++) terrain_columns_destroy(chunks[n]);
    terrain_columns_destroy(region);
    return ms;
}

/* Records a row and, for the deposit, its iterations and moved volume (the warm-up excluded). */
static void run_row(bench_context *ctx, const char *name, stabilize_bench *b, bool extra) {
    if (!bench_wants(ctx, name)) return;
    b->runs_seen = 0;
    bench_run(ctx, name, "ms", STABILIZE_RUNS, sample_stabilize, b);
    int runs = b->runs_seen - 1 < 32 ? b->runs_seen - 1 : 31;
    if (!extra || runs <= 0) return;
    char row[96];
    snprintf(row, sizeof row, "%s.iterations", name);
    bench_record(ctx, row, "count", b->iterations + 1, runs);
    snprintf(row, sizeof row, "%s.moved_m3", name);
    bench_record(ctx, row, "m3", b->moved + 1, runs);
}

void bench_group_terrain_stabilize(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.stabilize")) return;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    stabilize_bench flat = { .jobs = jobs };
    load_flat(&flat);
    run_row(ctx, "terrain.stabilize.deposit", &flat, true);
    flat.jobs = NULL;
    run_row(ctx, "terrain.stabilize.deposit.1thread", &flat, false);
    flat.jobs = jobs;
    flat.per_chunk = true;
    run_row(ctx, "terrain.stabilize.deposit.chunks", &flat, true);
    flat.per_chunk = false;
    flat.params.step = 0.25f;
    run_row(ctx, "terrain.stabilize.deposit.step_quarter", &flat, true);
    free_chunks(&flat);

    if (bench_wants(ctx, "terrain.stabilize.deposit.generated") || bench_wants(ctx, "terrain.stabilize.erode")) {
        stabilize_bench generated = { .jobs = jobs };
        load_generated(&generated);
        run_row(ctx, "terrain.stabilize.deposit.generated", &generated, true);
        generated.erode = true;
        run_row(ctx, "terrain.stabilize.erode", &generated, true);
        free_chunks(&generated);
    }
    job_system_destroy(jobs);
}
