/* bench_terrain_mesh.c — the convolution field and marching cubes, one core.
 *
 *   terrain.field_mesh.chunk32   ms to sample the field of one 32³-cell chunk (35³ samples: the
 *                                chunk's 33³ plus a one-sample apron) and mesh it with weights
 *                                and vertex-cache optimisation: what the ECS's mesh job does.
 *                                Mean over 8 chunks at the surface of a generated world, whose
 *                                generation is done before timing (the chunks and their
 *                                neighbours are cached first). Target ≤ 2 ms.
 *   terrain.field.chunk32, terrain.mesh.chunk32   the two halves of the row above, same runs.
 *   terrain.mesh.chunk32.no_ao   the meshing half again on the same fields without ambient
 *                                occlusion (terrain_mesh_desc.no_occlusion), same runs: the
 *                                occlusion's cost is the difference.
 *   terrain.mesh.256             ms to mesh a 256³-sample field (a generated region across the
 *                                surface, sampled beforehand, read from memory), same options.
 *   terrain.mesh.*.ns_per_cell   both meshing rows per cell, and their ratio: how meshing scales
 *                                from a chunk to a large grid (cache effects, skipped cells).
 *   terrain.mesh_lod1.chunk32, terrain.mesh_lod2.chunk32   ms for terrain_mesh_chunk of one
 *                                32³-cell chunk at level 1 / 2 (cells 2 / 4 m) with all 26
 *                                neighbours finer, the worst case for transition cells: coarse
 *                                and fine face samples, meshing, weights. Mean over 8 chunks at
 *                                the surface; every column the kernel reaches generated first.
 *   terrain.water_planes.chunk32 ms for terrain_water_planes_find on one level-0 mesh chunk at
 *                                sea level (y layer 0) whose centre column is sea: the water
 *                                surfaces the mesh phase finds beside each mesh (32² columns read,
 *                                grouped by height). Mean over 8 such chunks, generated first.
 *
 * Peer: scikit-image's marching_cubes or VTK's vtkFlyingEdges3D would be the natural peer on the
 * same field, but neither is in Debian 12's default install here (`python3 -c "import skimage"`
 * and `import vtk` both fail), so there is no peer row; terrain_export writes the field as
 * PREFIX.raw/.json for running one by hand where it is installed.
 */
#include "bench.h"

#include "core/core.h"
#include "terrain/terrain.h"

#include <math.h>
#include <stdio.h>

#define CHUNK_CELLS 32
#define CHUNK_APRON 1
#define CHUNK_COUNT 8
#define BIG_SAMPLES 256

typedef struct mesh_bench {
    terrain_world *world;
    int64_t chunks[CHUNK_COUNT][3];
    /* Per-run halves of the chunk row, recorded as rows of their own afterwards. */
    double field_ms[64], mesh_ms[64], mesh_no_ao_ms[64];
    int runs_seen;
    double cells_meshed;            /* per chunk, for ns/cell */
    uint64_t triangles;
    terrain_field big;
    double big_ms[16];
    int big_runs_seen;
} mesh_bench;

static int64_t bench_floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

/* Eight chunks in a row whose vertical slab holds the ground at their centre column. */
static void pick_chunks(mesh_bench *b) {
    for (int c = 0; c < CHUNK_COUNT; c++) {
        int64_t cx = c % 4, cz = c / 4;
        const terrain_stacks *stacks = terrain_world_stacks(b->world, (terrain_chunk_coord){ cx, cz });
        float top = terrain_stacks_top(stacks, TERRAIN_CHUNK_COLUMNS / 2, TERRAIN_CHUNK_COLUMNS / 2);
        b->chunks[c][0] = cx;
        b->chunks[c][1] = bench_floor_div((int64_t)floorf(top), CHUNK_CELLS);
        b->chunks[c][2] = cz;
        /* The kernel reaches one column into each neighbour: generate them now, untimed. */
        for (int dz = -1; dz <= 1; dz++)
            for (int dx = -1; dx <= 1; dx++) terrain_world_stacks(b->world, (terrain_chunk_coord){ cx + dx, cz + dz });
    }
}

static double sample_field_mesh_chunk(void *user) {
    mesh_bench *b = user;
    double field_total = 0.0, mesh_total = 0.0, no_ao_total = 0.0;
    uint64_t triangles = 0;
    for (int c = 0; c < CHUNK_COUNT; c++) {
        const int64_t *chunk = b->chunks[c];
        terrain_field_desc desc = { .size = { CHUNK_CELLS + 1 + 2 * CHUNK_APRON, CHUNK_CELLS + 1 + 2 * CHUNK_APRON,
                                              CHUNK_CELLS + 1 + 2 * CHUNK_APRON } };
        for (int a = 0; a < 3; a++) desc.first[a] = chunk[a] * CHUNK_CELLS - CHUNK_APRON;
        uint64_t t0 = core_time_ns();
        terrain_field field;
        terrain_field_sample(b->world, &desc, &field);
        uint64_t t1 = core_time_ns();
        terrain_mesh mesh;
        terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = b->world, .apron = CHUNK_APRON }, &mesh);
        uint64_t t2 = core_time_ns();
        field_total += core_ns_to_ms(t1 - t0);
        mesh_total += core_ns_to_ms(t2 - t1);
        triangles += mesh.index_count / 3;
        terrain_mesh_free(&mesh);
        /* The same mesh without ambient occlusion (a peer in the same run; not in the row). */
        uint64_t t3 = core_time_ns();
        terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = b->world, .apron = CHUNK_APRON, .no_occlusion = true },
                           &mesh);
        no_ao_total += core_ns_to_ms(core_time_ns() - t3);
        terrain_mesh_free(&mesh);
        terrain_field_free(&field);
    }
    /* The harness calls once to warm up, then `runs` times: keep the timed runs' halves. */
    if (b->runs_seen > 0 && b->runs_seen <= (int)CORE_COUNTOF(b->field_ms)) {
        b->field_ms[b->runs_seen - 1] = field_total / CHUNK_COUNT;
        b->mesh_ms[b->runs_seen - 1] = mesh_total / CHUNK_COUNT;
        b->mesh_no_ao_ms[b->runs_seen - 1] = no_ao_total / CHUNK_COUNT;
    }
    b->runs_seen++;
    b->triangles = triangles / CHUNK_COUNT;
    bench_consume((double)triangles);
    return (field_total + mesh_total) / CHUNK_COUNT;
}

static double sample_mesh_big(void *user) {
    mesh_bench *b = user;
    uint64_t t0 = core_time_ns();
    terrain_mesh mesh;
    terrain_mesh_build(&b->big, &(terrain_mesh_desc){ .world = b->world }, &mesh);
    double ms = core_ns_to_ms(core_time_ns() - t0);
    b->triangles = mesh.index_count / 3;
    bench_consume((double)mesh.index_count);
    terrain_mesh_free(&mesh);
    if (b->big_runs_seen > 0 && b->big_runs_seen <= (int)CORE_COUNTOF(b->big_ms)) b->big_ms[b->big_runs_seen - 1] = ms;
    b->big_runs_seen++;
    return ms;
}

static double median(double *values, int count) {
    for (int i = 1; i < count; i++)   /* insertion sort: a handful of values */
        for (int j = i; j > 0 && values[j - 1] > values[j]; j--) {
            double t = values[j];
            values[j] = values[j - 1], values[j - 1] = t;
        }
    return count % 2 ? values[count / 2] : 0.5 * (values[count / 2 - 1] + values[count / 2]);
}

/* ---- level of detail ---------------------------------------------------------------------- */

typedef struct lod_bench {
    terrain_world *world;
    int level;
    int64_t chunks[CHUNK_COUNT][3];
    uint64_t triangles;
} lod_bench;

static void lod_pick_chunks(lod_bench *b) {
    const int64_t span = (int64_t)CHUNK_CELLS << b->level;   /* columns per chunk side */
    for (int c = 0; c < CHUNK_COUNT; c++) {
        int64_t x = c % 4, z = c / 4;
        int64_t centre[2] = { x * span + span / 2, z * span + span / 2 };
        terrain_chunk_coord world_chunk = { bench_floor_div(centre[0], TERRAIN_CHUNK_COLUMNS),
                                            bench_floor_div(centre[1], TERRAIN_CHUNK_COLUMNS) };
        const terrain_stacks *stacks = terrain_world_stacks(b->world, world_chunk);
        float top = terrain_stacks_top(stacks, (int)(centre[0] - world_chunk.x * TERRAIN_CHUNK_COLUMNS),
                                       (int)(centre[1] - world_chunk.z * TERRAIN_CHUNK_COLUMNS));
        b->chunks[c][0] = x;
        b->chunks[c][1] = bench_floor_div((int64_t)floorf(top), span);
        b->chunks[c][2] = z;
        /* Every world chunk the samples' kernels and the weights reach, untimed. */
        int64_t lo[2] = { x * span - span - 2, z * span - span - 2 }, hi[2] = { lo[0] + 3 * span + 4, lo[1] + 3 * span + 4 };
        for (int64_t wz = bench_floor_div(lo[1], TERRAIN_CHUNK_COLUMNS); wz <= bench_floor_div(hi[1], TERRAIN_CHUNK_COLUMNS); wz++)
            for (int64_t wx = bench_floor_div(lo[0], TERRAIN_CHUNK_COLUMNS); wx <= bench_floor_div(hi[0], TERRAIN_CHUNK_COLUMNS); wx++)
                terrain_world_stacks(b->world, (terrain_chunk_coord){ wx, wz });
    }
}

static double sample_mesh_lod(void *user) {
    lod_bench *b = user;
    terrain_lod_desc lod = { .level = b->level, .finer_neighbours = (1u << 26) - 1 };
    double total = 0.0;
    uint64_t triangles = 0;
    for (int c = 0; c < CHUNK_COUNT; c++) {
        uint64_t t0 = core_time_ns();
        terrain_mesh mesh;
        terrain_mesh_chunk(b->world, b->chunks[c][0], b->chunks[c][1], b->chunks[c][2], &lod, &mesh);
        total += core_ns_to_ms(core_time_ns() - t0);
        triangles += mesh.index_count / 3;
        terrain_mesh_free(&mesh);
    }
    b->triangles = triangles / CHUNK_COUNT;
    bench_consume((double)triangles);
    return total / CHUNK_COUNT;
}

static void bench_terrain_mesh_lod(bench_context *ctx) {
    static const char *const names[] = { "terrain.mesh_lod1.chunk32", "terrain.mesh_lod2.chunk32" };
    for (int level = 1; level <= 2; level++) {
        if (!bench_wants(ctx, names[level - 1])) continue;
        lod_bench b = { .level = level };
        b.world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
        lod_pick_chunks(&b);
        bench_run(ctx, names[level - 1], "ms", 9, sample_mesh_lod, &b);
        printf("  (lod%d: %llu triangles per %lld m chunk on average)\n", level, (unsigned long long)b.triangles,
               (long long)(CHUNK_CELLS << level));
        terrain_world_destroy(b.world);
    }
}

/* ---- water planes ---------------------------------------------------------------------- */

typedef struct water_bench {
    terrain_world *world;
    int64_t chunks[CHUNK_COUNT][2];
    int planes;
} water_bench;

/* Eight chunks along z = 0 whose centre column is sea (the full cost: every column wet). */
static void water_pick_chunks(water_bench *b) {
    int found = 0;
    for (int64_t cx = 0; cx < 4096 && found < CHUNK_COUNT; cx++) {
        double x = (double)cx * TERRAIN_CHUNK_COLUMNS + 16.5, z = 16.5;
        if (!terrain_world_water_at(b->world, x, z, NULL, NULL) && cx < 4096 - CHUNK_COUNT + found) continue;
        b->chunks[found][0] = cx;
        b->chunks[found][1] = 0;
        found++;
    }
}

static double sample_water_planes(void *user) {
    water_bench *b = user;
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
    int total = 0;
    uint64_t t0 = core_time_ns();
    for (int c = 0; c < CHUNK_COUNT; c++)
        total += terrain_water_planes_find(b->world, b->chunks[c][0], 0, b->chunks[c][1], 0, planes,
                                           TERRAIN_WATER_PLANES_MAX);
    double ms = core_ns_to_ms(core_time_ns() - t0) / CHUNK_COUNT;
    b->planes = total;
    bench_consume((double)total);
    return ms;
}

static void bench_terrain_water_planes(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.water_planes.chunk32")) return;
    water_bench b = { 0 };
    b.world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    water_pick_chunks(&b);
    bench_run(ctx, "terrain.water_planes.chunk32", "ms", 15, sample_water_planes, &b);
    printf("  (water planes: %d over %d chunks at sea level)\n", b.planes, CHUNK_COUNT);
    terrain_world_destroy(b.world);
}

void bench_group_terrain_mesh(bench_context *ctx) {
    bench_terrain_water_planes(ctx);
    bool want_big = bench_wants(ctx, "terrain.mesh.256");
    /* The 256 row's per-cell ratio needs the chunk's meshing time. */
    bool want_chunk = want_big || bench_wants(ctx, "terrain.field_mesh.chunk32") ||
                      bench_wants(ctx, "terrain.field.chunk32") || bench_wants(ctx, "terrain.mesh.chunk32");
    if (!want_chunk && !want_big) {
        bench_terrain_mesh_lod(ctx);
        return;
    }
    mesh_bench *b = core_calloc(1, sizeof *b);
    b->world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    pick_chunks(b);
    const double chunk_cells = (double)CHUNK_CELLS * CHUNK_CELLS * CHUNK_CELLS;
    double chunk_mesh_ms = NAN;

    if (want_chunk) {
        const int runs = 15;
        bench_run(ctx, "terrain.field_mesh.chunk32", "ms", runs, sample_field_mesh_chunk, b);
        if (b->runs_seen == 0)   /* that row is filtered out, but the halves or the 256 row want it */
            for (int i = 0; i <= runs; i++) sample_field_mesh_chunk(b);
        int recorded = CORE_MIN(b->runs_seen - 1, (int)CORE_COUNTOF(b->field_ms));
        if (recorded > 0) {
            bench_record(ctx, "terrain.field.chunk32", "ms", b->field_ms, recorded);
            bench_record(ctx, "terrain.mesh.chunk32", "ms", b->mesh_ms, recorded);
            double per_cell[64];
            for (int i = 0; i < recorded; i++) per_cell[i] = b->mesh_ms[i] * 1e6 / chunk_cells;
            bench_record(ctx, "terrain.mesh.chunk32.ns_per_cell", "ns", per_cell, recorded);
            bench_record(ctx, "terrain.mesh.chunk32.no_ao", "ms", b->mesh_no_ao_ms, recorded);
            chunk_mesh_ms = median(b->mesh_ms, recorded);
        }
        printf("  (chunk32: %llu triangles per chunk on average)\n", (unsigned long long)b->triangles);
    }

    if (want_big) {
        /* A 256³ region across the ground around the first chunk, sampled once, untimed. */
        int64_t ground = b->chunks[0][1] * CHUNK_CELLS + CHUNK_CELLS / 2;
        terrain_field_sample(b->world, &(terrain_field_desc){ .first = { -64, ground - BIG_SAMPLES / 2, -64 },
                                                              .size = { BIG_SAMPLES, BIG_SAMPLES, BIG_SAMPLES } },
                             &b->big);
        const int runs = 5;
        bench_run(ctx, "terrain.mesh.256", "ms", runs, sample_mesh_big, b);
        printf("  (256: %llu triangles)\n", (unsigned long long)b->triangles);
        /* Per cell, beside the chunk's meshing half, from the same runs. */
        int recorded = CORE_MIN(b->big_runs_seen - 1, (int)CORE_COUNTOF(b->big_ms));
        double per_cell[16], ratio[16];
        double big_cells = pow(BIG_SAMPLES - 1, 3);
        for (int i = 0; i < recorded; i++) {
            per_cell[i] = b->big_ms[i] * 1e6 / big_cells;
            ratio[i] = per_cell[i] / (chunk_mesh_ms * 1e6 / chunk_cells);
        }
        if (recorded > 0) bench_record(ctx, "terrain.mesh.256.ns_per_cell", "ns", per_cell, recorded);
        if (recorded > 0 && !isnan(chunk_mesh_ms))
            bench_record(ctx, "terrain.mesh.256.per_cell_vs_chunk32", "x", ratio, recorded);
        terrain_field_free(&b->big);
    }
    terrain_world_destroy(b->world);
    core_free(b, sizeof *b);
    bench_terrain_mesh_lod(ctx);
}
