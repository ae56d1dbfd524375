/* bench_terrain_mesh.c — the convolution field and marching cubes, one core.
 *
 *   terrain.field_mesh.chunk32   ms to sample the field of one 32³-cell chunk (35³ samples: the
 *                                chunk's 33³ plus a one-sample apron) and mesh it with weights
 *                                and vertex-cache optimisation: what the ECS's mesh job does.
 *                                Mean over 8 chunks at the surface of a generated world, whose
 *                                generation is done before timing (the chunks and their
 *                                neighbours are cached first). Target ≤ 2 ms.
 *   terrain.field.chunk32, terrain.mesh.chunk32   the two halves of the row above, same runs.
 *   terrain.mesh.chunk32.isosurface   the meshing half with no world (no weights, occlusion or
 *                                reordering): the mesher's own part, same runs.
 *   terrain.mesh.chunk32.no_ao   the meshing half again on the same fields without ambient
 *                                occlusion (terrain_mesh_desc.no_occlusion), same runs: the
 *                                occlusion's cost is the difference.
 *   terrain.mesh.chunk32.simplified   the meshing half as streaming makes it: simplified by
 *                                level 0's error (terrain_lod_desc.max_error =
 *                                terrain_chunk_level_error(0), 0.02 m), same runs; the
 *                                triangles it keeps are printed beside the full count.
 *   terrain.mesh.256             ms to mesh a 256³-sample field (a generated region across the
 *                                surface, sampled beforehand, read from memory) on every core
 *                                (--threads): the isosurface alone, positions, normals and
 *                                triangles, no weights, occlusion or reordering, every cell (no
 *                                apron): what VTK's vtkFlyingEdges3D makes from the same file.
 *   terrain.mesh.256.one_core    the same on the calling thread alone.
 *   terrain.mesh.256.vtk_flying_edges, terrain.mesh.256.vs_vtk   the peer on the same field in
 *                                the same run (tools/peers/vtk_flying_edges.py: vtkFlyingEdges3D
 *                                with normals, the same thread count; Debian's python3-vtk9), and
 *                                ours over its, run by run. Left out when VTK is not installed.
 *   terrain.mesh.256.full        ms for the game's options on that field, one core: weights,
 *                                occlusion and vertex-cache order (this row was terrain.mesh.256
 *                                before the isosurface alone was).
 *   terrain.mesh.*.ns_per_cell   the chunk's meshing half and the one-core 256 row per cell.
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
 * The peer needs /usr/bin/python3 with VTK; the field goes to a file in $TMPDIR (or /tmp) for it.
 */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define CHUNK_CELLS 32
#define CHUNK_APRON 1
#define CHUNK_COUNT 8
#define BIG_SAMPLES 256

typedef struct mesh_bench {
    terrain_world *world;
    int64_t chunks[CHUNK_COUNT][3];
    /* Per-run halves of the chunk row, recorded as rows of their own afterwards. */
    double field_ms[64], mesh_ms[64], mesh_no_ao_ms[64], mesh_iso_ms[64], mesh_simplified_ms[64];
    int runs_seen;
    double cells_meshed;            /* per chunk, for ns/cell */
    uint64_t triangles, triangles_simplified;
    terrain_field big;
    job_system *jobs;               /* the 256 rows' threads; NULL = one core */
    bool full;                      /* the game's options (weights, occlusion, reordering) */
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
    double field_total = 0.0, mesh_total = 0.0, no_ao_total = 0.0, iso_total = 0.0, simplified_total = 0.0;
    uint64_t triangles = 0, simplified = 0;
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
        /* And the isosurface alone: no weights, occlusion or reordering. */
        uint64_t t4 = core_time_ns();
        terrain_mesh_build(&field, &(terrain_mesh_desc){ .apron = CHUNK_APRON, .no_optimize = true }, &mesh);
        iso_total += core_ns_to_ms(core_time_ns() - t4);
        terrain_mesh_free(&mesh);
        /* And as streaming makes it, simplified by level 0's error. */
        uint64_t t5 = core_time_ns();
        terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = b->world, .apron = CHUNK_APRON,
                                                         .max_error = (float)terrain_chunk_level_error(0) }, &mesh);
        simplified_total += core_ns_to_ms(core_time_ns() - t5);
        simplified += mesh.index_count / 3;
        terrain_mesh_free(&mesh);
        terrain_field_free(&field);
    }
    /* The harness calls once to warm up, then `runs` times: keep the timed runs' halves. */
    if (b->runs_seen > 0 && b->runs_seen <= (int)CORE_COUNTOF(b->field_ms)) {
        b->field_ms[b->runs_seen - 1] = field_total / CHUNK_COUNT;
        b->mesh_ms[b->runs_seen - 1] = mesh_total / CHUNK_COUNT;
        b->mesh_no_ao_ms[b->runs_seen - 1] = no_ao_total / CHUNK_COUNT;
        b->mesh_iso_ms[b->runs_seen - 1] = iso_total / CHUNK_COUNT;
        b->mesh_simplified_ms[b->runs_seen - 1] = simplified_total / CHUNK_COUNT;
    }
    b->runs_seen++;
    b->triangles = triangles / CHUNK_COUNT;
    b->triangles_simplified = simplified / CHUNK_COUNT;
    bench_consume((double)triangles);
    return (field_total + mesh_total) / CHUNK_COUNT;
}

static double sample_mesh_big(void *user) {
    mesh_bench *b = user;
    terrain_mesh_desc desc = { .no_optimize = true, .jobs = b->jobs };
    if (b->full) desc = (terrain_mesh_desc){ .world = b->world };
    uint64_t t0 = core_time_ns();
    terrain_mesh mesh;
    terrain_mesh_build(&b->big, &desc, &mesh);
    double ms = core_ns_to_ms(core_time_ns() - t0);
    b->triangles = mesh.index_count / 3;
    bench_consume((double)mesh.index_count);
    terrain_mesh_free(&mesh);
    return ms;
}

/* VTK's vtkFlyingEdges3D on the same field, `runs` times (ms each into `ms`); 0 when the peer
 * cannot run (no python3 with VTK). */
static int run_vtk_peer(const terrain_field *field, int threads, int runs, double *ms, uint64_t *triangles) {
    if (access("/usr/bin/python3", X_OK) != 0 || access("tools/peers/vtk_flying_edges.py", R_OK) != 0) return 0;
    const char *tmp = getenv("TMPDIR");
    char prefix[512], command[1200];
    core_error error = { 0 };
    snprintf(prefix, sizeof prefix, "%s/bench_mesh_256_%ld", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    if (!terrain_field_write(field, prefix, &error)) {
        fprintf(stderr, "bench: the VTK peer's field: %s\n", error.message);
        return 0;
    }
    snprintf(command, sizeof command, "/usr/bin/python3 tools/peers/vtk_flying_edges.py '%s.json' %d %d 2>/dev/null", prefix,
             threads, runs);
    FILE *out = popen(command, "r");
    int count = 0;
    char line[4096];
    if (out && fgets(line, sizeof line, out)) {   /* {"ms": [...], "triangles": T, ...} */
        core_arena arena = { 0 };
        core_json_value *root;
        if (core_json_parse(line, strlen(line), &arena, &root, NULL)) {
            const core_json_value *times = core_json_get(root, "ms");
            if (times && times->type == CORE_JSON_ARRAY)
                for (size_t i = 0; i < times->array.count && count < runs; i++)
                    ms[count++] = core_json_number_or(&times->array.items[i], NAN);
            *triangles = (uint64_t)core_json_number_or(core_json_get(root, "triangles"), 0.0);
        }
        core_arena_release(&arena);
    }
    if (out) pclose(out);
    for (const char *ext = ".json"; ext; ext = ext[1] == 'j' ? ".raw" : NULL) {
        char path[600];
        snprintf(path, sizeof path, "%s%s", prefix, ext);
        remove(path);
    }
    return count;
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
    bool want_chunk = bench_wants(ctx, "terrain.field_mesh.chunk32") ||
                      bench_wants(ctx, "terrain.field.chunk32") || bench_wants(ctx, "terrain.mesh.chunk32");
    if (!want_chunk && !want_big) {
        bench_terrain_mesh_lod(ctx);
        return;
    }
    mesh_bench *b = core_calloc(1, sizeof *b);
    b->world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    pick_chunks(b);
    const double chunk_cells = (double)CHUNK_CELLS * CHUNK_CELLS * CHUNK_CELLS;

    if (want_chunk) {
        const int runs = 15;
        bench_run(ctx, "terrain.field_mesh.chunk32", "ms", runs, sample_field_mesh_chunk, b);
        if (b->runs_seen == 0)   /* that row is filtered out, but the halves want it */
            for (int i = 0; i <= runs; i++) sample_field_mesh_chunk(b);
        int recorded = CORE_MIN(b->runs_seen - 1, (int)CORE_COUNTOF(b->field_ms));
        if (recorded > 0) {
            bench_record(ctx, "terrain.field.chunk32", "ms", b->field_ms, recorded);
            bench_record(ctx, "terrain.mesh.chunk32", "ms", b->mesh_ms, recorded);
            double per_cell[64];
            for (int i = 0; i < recorded; i++) per_cell[i] = b->mesh_ms[i] * 1e6 / chunk_cells;
            bench_record(ctx, "terrain.mesh.chunk32.ns_per_cell", "ns", per_cell, recorded);
            bench_record(ctx, "terrain.mesh.chunk32.no_ao", "ms", b->mesh_no_ao_ms, recorded);
            bench_record(ctx, "terrain.mesh.chunk32.isosurface", "ms", b->mesh_iso_ms, recorded);
            bench_record(ctx, "terrain.mesh.chunk32.simplified", "ms", b->mesh_simplified_ms, recorded);
        }
        printf("  (chunk32: %llu triangles per chunk on average, %llu simplified)\n", (unsigned long long)b->triangles,
               (unsigned long long)b->triangles_simplified);
    }

    if (want_big) {
        /* A 256³ region across the ground around the first chunk, sampled once, untimed. */
        int64_t ground = b->chunks[0][1] * CHUNK_CELLS + CHUNK_CELLS / 2;
        terrain_field_sample(b->world, &(terrain_field_desc){ .first = { -64, ground - BIG_SAMPLES / 2, -64 },
                                                              .size = { BIG_SAMPLES, BIG_SAMPLES, BIG_SAMPLES } },
                             &b->big);
        enum { RUNS = 7 };
        b->jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
        const int threads = job_thread_count(b->jobs);
        double ours[RUNS + 1], peer[RUNS], ratio[RUNS], one[RUNS + 1];
        for (int r = 0; r <= RUNS; r++) ours[r] = sample_mesh_big(b);   /* the first warms up */
        bench_record(ctx, "terrain.mesh.256", "ms", ours + 1, RUNS);
        printf("  (256: %llu triangles, %d threads)\n", (unsigned long long)b->triangles, threads);
        uint64_t peer_triangles = 0;
        int peer_runs = run_vtk_peer(&b->big, threads, RUNS, peer, &peer_triangles);
        if (peer_runs > 0) {
            for (int r = 0; r < peer_runs; r++) ratio[r] = ours[1 + r] / peer[r];
            bench_record(ctx, "terrain.mesh.256.vtk_flying_edges", "ms", peer, peer_runs);
            bench_record(ctx, "terrain.mesh.256.vs_vtk", "x", ratio, peer_runs);
            printf("  (vtkFlyingEdges3D: %llu triangles)\n", (unsigned long long)peer_triangles);
        }
        job_system_destroy(b->jobs);
        b->jobs = NULL;
        for (int r = 0; r <= RUNS; r++) one[r] = sample_mesh_big(b);
        bench_record(ctx, "terrain.mesh.256.one_core", "ms", one + 1, RUNS);
        double per_cell[RUNS];
        for (int i = 0; i < RUNS; i++) per_cell[i] = one[1 + i] * 1e6 / pow(BIG_SAMPLES - 1, 3);
        bench_record(ctx, "terrain.mesh.256.ns_per_cell", "ns", per_cell, RUNS);
        b->full = true;
        bench_run(ctx, "terrain.mesh.256.full", "ms", 3, sample_mesh_big, b);
        terrain_field_free(&b->big);
    }
    terrain_world_destroy(b->world);
    core_free(b, sizeof *b);
    bench_terrain_mesh_lod(ctx);
}
