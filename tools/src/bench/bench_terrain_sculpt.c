/* bench_terrain_sculpt.c — sculpting, sweeping and picking (000 §4.1, §4.2).
 *
 *   terrain.edit.sculpt   ms for one terrain_sculpt stroke (add, R = 3 m, δ = R/2) on a region of
 *       3 × 3 generated chunks (seed 42, chunks (0, 0) … (2, 2)), at the surface point that a ray
 *       straight down at the region's centre finds (terrain_raycast). Each run loads the region
 *       afresh before the clock starts: the time is the stroke alone (its field snapshot, the
 *       projection onto the surface, the columns' roots and rewrites).
 *   terrain.edit.sculpt.carve   the same stroke carving.
 *   terrain.edit.sweep    ms for terrain_sweep of a straight 30 m tunnel of radius 2 m, 6 m under
 *       that point, across the region's centre; region loaded afresh per run.
 *   terrain.edit.sweep.profile   the same tunnel with a profile curve {1, 0.6, 1, 0.6} (000 §4.2:
 *       a cross-section 4 m high and 2.4 m wide): its quanta tested one by one.
 *   terrain.edit.raycast  µs for a ray from 30 m above that point, 45° down towards it (the march
 *       of terrain_field_at samples half a metre apart and the bisection).
 */
#include "bench.h"

#include "core/core.h"
#include "terrain/terrain.h"

enum { REGION_CHUNKS = 3, REGION_COLUMNS = REGION_CHUNKS * TERRAIN_CHUNK_COLUMNS, EDIT_RUNS = 21 };

typedef struct sculpt_bench {
    terrain_world *world;
    double target[3];
    bool sweep, carve, profile;
} sculpt_bench;

static terrain_columns *fresh_region(const sculpt_bench *b) {
    terrain_columns *region = terrain_columns_create(
        &(terrain_columns_desc){ .width = REGION_COLUMNS, .depth = REGION_COLUMNS });
    for (int n = 0; n < REGION_CHUNKS * REGION_CHUNKS; n++) {
        terrain_chunk_coord coord = { n % REGION_CHUNKS, n / REGION_CHUNKS };
        terrain_columns_load(region, coord, terrain_world_stacks(b->world, coord));
    }
    return region;
}

static double sample_edit(void *user) {
    const sculpt_bench *b = user;
    terrain_columns *region = fresh_region(b);
    int64_t changed = 0;
    bool ok;
    uint64_t start = core_time_ns();
    if (b->sweep) {
        const double *t = b->target;
        const double points[2][3] = { { t[0] - 15.0, t[1] - 6.0, t[2] - 1.0 }, { t[0] + 15.0, t[1] - 6.0, t[2] + 1.0 } };
        static const float profile[4] = { 1.0f, 0.6f, 1.0f, 0.6f };
        ok = terrain_sweep(region, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 2.0f,
                                                          .profile = b->profile ? profile : NULL,
                                                          .profile_count = b->profile ? 4 : 0 }, &changed);
    } else {
        ok = terrain_sculpt(region, &(terrain_sculpt_desc){ .target = { b->target[0], b->target[1], b->target[2] },
                                                           .radius = 3.0f, .carve = b->carve }, &changed);
    }
    double ms = core_ns_to_ms(core_time_ns() - start);
    if (!ok || changed == 0) core_warn("bench", "terrain.edit: the edit changed nothing");
    terrain_columns_destroy(region);
    return ms;
}

static double sample_raycast(void *user) {
    const sculpt_bench *b = user;
    const double origin[3] = { b->target[0] - 30.0, b->target[1] + 30.0, b->target[2] };
    terrain_ray_hit hit;
    uint64_t start = core_time_ns();
    bool found = terrain_raycast(b->world, origin, (const float[3]){ 1.0f, -1.0f, 0.0f }, 64.0f, &hit);
    double us = (double)(core_time_ns() - start) / 1000.0;
    bench_consume(found ? hit.distance : -1.0);
    return us;
}

void bench_group_terrain_sculpt(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.edit")) return;
    sculpt_bench b = { .world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) }) };
    terrain_ray_hit hit;
    double centre = REGION_COLUMNS / 2 + 0.3;
    if (!terrain_raycast(b.world, (const double[3]){ centre, 400.0, centre }, (const float[3]){ 0.0f, -1.0f, 0.0f },
                         1000.0f, &hit)) {
        core_log_error("bench", "terrain.edit: no ground under the region's centre");
        terrain_world_destroy(b.world);
        return;
    }
    for (int a = 0; a < 3; a++) b.target[a] = hit.position[a];
    if (bench_wants(ctx, "terrain.edit.sculpt")) {
        bench_run(ctx, "terrain.edit.sculpt", "ms", EDIT_RUNS, sample_edit, &b);
        b.carve = true;
        bench_run(ctx, "terrain.edit.sculpt.carve", "ms", EDIT_RUNS, sample_edit, &b);
        b.carve = false;
    }
    b.sweep = true;
    if (bench_wants(ctx, "terrain.edit.sweep")) bench_run(ctx, "terrain.edit.sweep", "ms", EDIT_RUNS, sample_edit, &b);
    b.profile = true;
    if (bench_wants(ctx, "terrain.edit.sweep.profile"))
        bench_run(ctx, "terrain.edit.sweep.profile", "ms", EDIT_RUNS, sample_edit, &b);
    b.profile = false;
    if (bench_wants(ctx, "terrain.edit.raycast"))
        bench_run(ctx, "terrain.edit.raycast", "us", EDIT_RUNS, sample_raycast, &b);
    terrain_world_destroy(b.world);
}
