/* Water planes (terrain.h, "water planes"; 002 §3.4): the water surfaces a mesh chunk holds,
 * found from the stacks, and the WaterPlane component the ECS gives mesh chunks. The worlds are
 * made by hand, so every plane, mask and depth below is worked out from the column functions. */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define N TERRAIN_CHUNK_COLUMNS

/* Bedrock from the floor up to `top`, then water up to `water` (none when water ≤ top). */
static void push_column(terrain_stacks_builder *builder, float top, float water) {
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, top - TERRAIN_FLOOR_Y);
    if (water > top) terrain_stacks_builder_push(builder, TERRAIN_WATER, water - top);
}

/* In chunk (0, 0): a sea (x < 16) over a floor at −4 with its surface at 0, a lake (20 ≤ x < 28,
 * 8 ≤ z < 16) on a bed at 6 with its surface at 10, dry land at 12 elsewhere. In chunk (2, 0):
 * eight strips 4 columns wide, strip s holding water from s to s + 1 m (surfaces 1 … 8). Dry
 * land at 12 everywhere else. */
static void sea_and_lake_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    bool in_first = x >= 0 && x < N && z >= 0 && z < N;
    if (in_first && x < 16) push_column(builder, -4.0f, 0.0f);
    else if (in_first && x >= 20 && x < 28 && z >= 8 && z < 16) push_column(builder, 6.0f, 10.0f);
    else if (x >= 2 * N && x < 3 * N && z >= 0 && z < N) {
        float s = (float)((x - 2 * N) / 4);
        push_column(builder, s, s + 1.0f);
    } else push_column(builder, 12.0f, 0.0f);
}

static terrain_stacks *sea_and_lake_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, sea_and_lake_column, user);
}

static terrain_world *sea_and_lake_world(void) {
    return terrain_world_create(&(terrain_world_desc){ .generate = sea_and_lake_chunk });
}

static uint32_t bits(int first, int last) {
    uint32_t mask = 0;
    for (int i = first; i <= last; i++) mask |= 1u << i;
    return mask;
}

Test(terrain_water_planes, a_sea_and_a_lake_give_exactly_their_planes_and_masks) {
    terrain_world *world = sea_and_lake_world();
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
    int n = terrain_water_planes_find(world, 0, 0, 0, 0, planes, TERRAIN_WATER_PLANES_MAX);
    cr_assert_eq(n, 2, "the sea and the lake: %d planes", n);
    /* The sea has 16 × 32 cells, the lake 8 × 8: the sea first. */
    cr_expect_eq(planes[0].height, 0.0f);
    cr_expect_eq(planes[0].deepest, -4.0f);
    cr_expect_eq(planes[1].height, 10.0f);
    cr_expect_eq(planes[1].deepest, 6.0f);
    for (int k = 0; k < N; k++) {
        cr_expect_eq(planes[0].rows[k], bits(0, 15), "sea row %d: %08x", k, planes[0].rows[k]);
        uint32_t lake = k >= 8 && k < 16 ? bits(20, 27) : 0u;
        cr_expect_eq(planes[1].rows[k], lake, "lake row %d: %08x", k, planes[1].rows[k]);
    }
    terrain_world_destroy(world);
}

Test(terrain_water_planes, coarser_cells_read_the_column_at_their_centre) {
    terrain_world *world = sea_and_lake_world();
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
    /* Level 1: cells of 2 m, cell i reads column 2i + 1. Sea columns x < 16, z < 32: cells
     * i ≤ 7, k ≤ 15 (128). Lake columns 20 … 27 × 8 … 15: cells i = 10 … 13, k = 4 … 7 (16). */
    int n = terrain_water_planes_find(world, 0, 0, 0, 1, planes, TERRAIN_WATER_PLANES_MAX);
    cr_assert_eq(n, 2);
    cr_expect_eq(planes[0].height, 0.0f);
    cr_expect_eq(planes[1].height, 10.0f);
    for (int k = 0; k < N; k++) {
        cr_expect_eq(planes[0].rows[k], k < 16 ? bits(0, 7) : 0u, "row %d: %08x", k, planes[0].rows[k]);
        cr_expect_eq(planes[1].rows[k], k >= 4 && k < 8 ? bits(10, 13) : 0u, "row %d: %08x", k, planes[1].rows[k]);
    }
    terrain_world_destroy(world);
}

Test(terrain_water_planes, no_water_or_water_outside_the_y_range_gives_none) {
    terrain_world *world = sea_and_lake_world();
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
    cr_expect_eq(terrain_water_planes_find(world, 1, 0, 0, 0, planes, TERRAIN_WATER_PLANES_MAX), 0, "dry land");
    /* The layer below holds [−32, 0): the sea's surface at 0 belongs to the layer above. */
    cr_expect_eq(terrain_water_planes_find(world, 0, -1, 0, 0, planes, TERRAIN_WATER_PLANES_MAX), 0);
    cr_expect_eq(terrain_water_planes_find(world, 0, 1, 0, 0, planes, TERRAIN_WATER_PLANES_MAX), 0);
    cr_expect_eq(terrain_water_planes_find(world, 0, 0, 0, 0, planes, 0), 0, "no room asked for");
    terrain_world_destroy(world);
}

Test(terrain_water_planes, more_surfaces_than_fit_keep_the_largest_then_the_highest) {
    terrain_world *world = sea_and_lake_world();
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX + 2];
    /* Eight strips of 4 × 32 cells each: a tie, so the highest four, highest first. */
    int n = terrain_water_planes_find(world, 2, 0, 0, 0, planes, TERRAIN_WATER_PLANES_MAX + 2);
    cr_assert_eq(n, TERRAIN_WATER_PLANES_MAX);
    for (int p = 0; p < n; p++) {
        float s = (float)(7 - p);
        cr_expect_eq(planes[p].height, s + 1.0f, "plane %d at %g", p, (double)planes[p].height);
        cr_expect_eq(planes[p].deepest, s);
        for (int k = 0; k < N; k++) cr_expect_eq(planes[p].rows[k], bits(4 * (7 - p), 4 * (7 - p) + 3));
    }
    terrain_world_destroy(world);
}

Test(terrain_water_planes, a_bad_request_is_an_error_not_a_crash) {
    terrain_world *world = sea_and_lake_world();
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);
    cr_expect_eq(terrain_water_planes_find(NULL, 0, 0, 0, 0, planes, 4), -1);
    cr_expect_eq(terrain_water_planes_find(world, 0, 0, 0, 17, planes, 4), -1);
    cr_expect_eq(terrain_water_planes_find(world, 0, 0, 0, -1, planes, 4), -1);
    cr_expect_eq(terrain_water_planes_find(world, 0, 0, 0, 0, planes, -1), -1);
    cr_expect_eq(terrain_water_planes_find(world, (int64_t)1 << 40, 0, 0, 0, planes, 4), -1);
    core_log_set_level(level);
    terrain_world_destroy(world);
}

/* ---- the component ------------------------------------------------------------------------ */

/* All sea: a floor at −100 and the surface at 8, or (drained) the floor alone. The mesh layers
 * used below lie above −100 − the field's reach: their meshes are empty, so the upload needs no
 * GL context, and layer 0 ([0, 32)) holds the surface. */
static void deep_sea_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)x, (void)z;
    const float *surface = user;          /* NULL: the sea at 8 */
    push_column(builder, -100.0f, surface ? *surface : 8.0f);
}

static terrain_stacks *deep_sea_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, deep_sea_column, user);
}

typedef struct water_ecs {
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
    ecs_component water;
    ecs_query *with_water;
} water_ecs;

static water_ecs water_ecs_open(void) {
    water_ecs w = { 0 };
    w.jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    w.ecs = ecs_world_create(&(ecs_world_desc){ .jobs = w.jobs });
    w.world = terrain_world_create(&(terrain_world_desc){ .generate = deep_sea_chunk });
    w.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = w.ecs, .terrain = w.world });
    w.water = ecs_component_lookup(w.ecs, "WaterPlane");
    w.with_water = ecs_query_create(w.ecs, &(ecs_query_desc){ .with = { w.water } });
    return w;
}

static void water_ecs_close(water_ecs *w) {
    terrain_ecs_destroy(w->te);
    ecs_world_destroy(w->ecs);
    terrain_world_destroy(w->world);
    job_system_destroy(w->jobs);
}

/* Entities with a WaterPlane; the first one's value in *first. */
static int count_water(water_ecs *w, WaterPlane *first) {
    int count = 0;
    ecs_iter it = ecs_query_iter(w->ecs, w->with_water);
    while (ecs_query_next(&it)) {
        WaterPlane *planes = ecs_field(&it, 0);
        if (count == 0 && it.count > 0 && first) *first = planes[0];
        count += it.count;
    }
    return count;
}

Test(terrain_water_planes, the_component_comes_with_the_upload_follows_an_edit_and_goes_when_drained) {
    water_ecs w = water_ecs_open();
    cr_assert_neq(w.water, 0, "terrain_ecs_create registers WaterPlane");
    terrain_ecs_spawn_area(w.te, 0, 0, 0, 0, 0);   /* one column chunk, mesh layer 0 */
    cr_expect_eq(count_water(&w, NULL), 0, "nothing before the first frame");
    for (int f = 0; f < 3; f++) ecs_progress(w.ecs, 1.0f / 60.0f);
    WaterPlane plane;
    cr_assert_eq(count_water(&w, &plane), 1, "the meshed and uploaded chunk has its sea");
    cr_expect_eq(plane.count, 1);
    cr_expect_eq(plane.cell, 1.0f);
    cr_expect_eq(plane.origin[0], 0.0);
    cr_expect_eq(plane.origin[1], 0.0);
    cr_expect_eq(plane.planes[0].height, 8.0f);
    cr_expect_eq(plane.planes[0].deepest, -100.0f);
    for (int k = 0; k < N; k++) cr_expect_eq(plane.planes[0].rows[k], 0xffffffffu);

    /* An edit (a commit by other code) raises the water to 20: remeshed, the component follows. */
    float raised = 20.0f, drained = -100.0f;
    terrain_world_commit(w.world, (terrain_chunk_coord){ 0, 0 },
                         terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, deep_sea_column, &raised),
                         TERRAIN_EDIT_SET);
    for (int f = 0; f < 3; f++) ecs_progress(w.ecs, 1.0f / 60.0f);
    cr_assert_eq(count_water(&w, &plane), 1);
    cr_expect_eq(plane.planes[0].height, 20.0f, "the new surface: %g", (double)plane.planes[0].height);
    /* Another drains it: the component goes. */
    terrain_world_commit(w.world, (terrain_chunk_coord){ 0, 0 },
                         terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, deep_sea_column, &drained),
                         TERRAIN_EDIT_SET);
    for (int f = 0; f < 3; f++) ecs_progress(w.ecs, 1.0f / 60.0f);
    cr_expect_eq(count_water(&w, NULL), 0, "drained: no WaterPlane left");
    water_ecs_close(&w);
}

Test(terrain_water_planes, streamed_chunks_get_the_component_and_lose_it_when_evicted) {
    water_ecs w = water_ecs_open();
    terrain_ecs_stream(w.te, &(terrain_stream_desc){ .half_width = 2, .levels = 2, .y_min = -20, .y_max = 20,
                                                     .memory_budget = 1 });   /* evict whatever is hidden */
    const double eye[1][3] = { { 10, 5, 10 } };
    /* Rings: level 0 is 4 × 4 chunks, level 1 4 × 4 less the 2 × 2 inside; the surface at 8 lies
     * in one layer of each level. */
    int expected = 16 + 12, seen = 0;
    /* Streaming meshes within a time budget a frame, so a loaded machine (the debug build, other
     * suites beside it) needs more frames: bounded by a minute of wall time, not a frame count. */
    uint64_t give_up = core_time_ns() + 60ull * 1000000000ull;
    for (int f = 0; seen != expected && (f < 2000 || core_time_ns() < give_up); f++) {
        terrain_ecs_set_viewers(w.te, eye, 1);
        ecs_progress(w.ecs, 1.0f / 60.0f);
        terrain_world_trim(w.world);
        seen = count_water(&w, NULL);
    }
    cr_expect_eq(seen, expected, "%d chunks with water, expected %d", seen, expected);
    /* Far away: what was around the origin is evicted, with its components. */
    const double far[1][3] = { { 100000, 5, 100000 } };
    for (int f = 0; f < 4000; f++) {
        terrain_ecs_set_viewers(w.te, far, 1);
        ecs_progress(w.ecs, 1.0f / 60.0f);
        terrain_world_trim(w.world);
        if (terrain_ecs_stream_stats(w.te).chunks_evicted >= (uint64_t)expected && count_water(&w, NULL) == expected)
            break;
    }
    int near_origin = 0;
    ecs_iter it = ecs_query_iter(w.ecs, w.with_water);
    while (ecs_query_next(&it)) {
        WaterPlane *planes = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) near_origin += fabs(planes[i].origin[0]) < 1000.0;
    }
    cr_expect_gt(terrain_ecs_stream_stats(w.te).chunks_evicted, 0);
    cr_expect_eq(near_origin, 0, "evicted chunks took their WaterPlane along");
    water_ecs_close(&w);
}

/* ---- the sea after edits (terrain.h, "the sea after edits"; 000 §4) ------------------------ */

/* Sea level 0 (the zeroed generation parameters). A sea (x < 16) on a floor at −4; a beach 1 m
 * above the sea for 16 ≤ x < 32; a hill at 10 m from x = 32 on. The same for every z. */
static void beach_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)z;
    if (x < 16) push_column(builder, -4.0f, 0.0f);
    else push_column(builder, x < 32 ? 1.0f : 10.0f, 0.0f);
}

static terrain_stacks *beach_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, beach_column, user);
}

static terrain_world *beach_world(terrain_edit_log *log) {
    return terrain_world_create(&(terrain_world_desc){ .generate = beach_chunk, .sea = true, .edits = log });
}

/* A ball of radius 3.2 m carved at (x + ½, y, z + ½) by a sweep (exact: what lies within the
 * radius of the point becomes air, along each column's axis). */
static int carve_ball(terrain_world *world, double x, double y, double z) {
    const double point[1][3] = { { x + 0.5, y, z + 0.5 } };
    terrain_chunk_coord changed[16];
    return terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
                                                      .sweep = { .points = point, .point_count = 1, .radius = 3.2f } },
                              changed, 16);
}

Test(terrain_water_sea, a_pit_carved_below_sea_level_on_a_beach_fills_exactly_to_sea_level) {
    terrain_world *world = beach_world(NULL);
    cr_assert_gt(carve_ball(world, 24, 1, 16), 0);
    /* Column (24 + a, 16 + b) loses sqrt(3.2² − a² − b²) m under the beach at 1 m: below the sea
     * (0 m) where that exceeds 1, i.e. a² + b² ≤ 9 (the next, 10, leaves 0.49 m). */
    int expected = 0, flooded = 0;
    for (int b = -5; b <= 5; b++)
        for (int a = -5; a <= 5; a++) {
            bool below = a * a + b * b <= 9;
            expected += below;
            float surface = NAN, ground = NAN;
            bool wet = terrain_world_water_at(world, 24.5 + a, 16.5 + b, &surface, &ground);
            float top = terrain_world_top(world, 24.5 + a, 16.5 + b);
            cr_expect_eq(top < 0.0f, below, "column (%d, %d): ground at %g", 24 + a, 16 + b, (double)top);
            cr_expect_eq(wet, below, "column (%d, %d) %s", 24 + a, 16 + b, below ? "dry below the sea" : "wet");
            if (!wet) continue;
            flooded++;
            cr_expect_eq(surface, 0.0f, "column (%d, %d): water up to %g", 24 + a, 16 + b, (double)surface);
            cr_expect_eq(ground, top);
            cr_expect_eq(terrain_world_material_at(world, 24.5 + a, top + 0.01, 16.5 + b), TERRAIN_WATER);
            cr_expect_eq(terrain_world_material_at(world, 24.5 + a, 0.01, 16.5 + b), TERRAIN_AIR);
        }
    cr_expect_eq(flooded, expected, "%d columns flooded, %d below the sea", flooded, expected);
    cr_expect_eq(expected, 29);
    terrain_world_destroy(world);
}

Test(terrain_water_sea, a_pit_carved_above_sea_level_stays_dry) {
    terrain_world *world = beach_world(NULL);
    cr_assert_gt(carve_ball(world, 48, 10, 16), 0);
    cr_expect_lt(terrain_world_top(world, 48.5, 16.5), 7.0f, "the pit is there");
    for (int z = 0; z < N; z++)
        for (int x = 32; x < 3 * N; x++)
            cr_expect(!terrain_world_water_at(world, x + 0.5, z + 0.5, NULL, NULL), "column (%d, %d) is wet", x, z);
    terrain_world_destroy(world);
}

Test(terrain_water_sea, a_world_without_a_sea_keeps_its_pits_dry) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = beach_chunk });
    cr_assert_gt(carve_ball(world, 24, 1, 16), 0);
    cr_expect_lt(terrain_world_top(world, 24.5, 16.5), -1.0f);
    cr_expect(!terrain_world_water_at(world, 24.5, 16.5, NULL, NULL), "no sea asked for: dry");
    terrain_world_destroy(world);
}

Test(terrain_water_sea, replaying_the_edit_log_gives_the_flooded_bytes) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = 1234 });
    terrain_world *world = beach_world(log);
    cr_assert_gt(carve_ball(world, 30, 1, 16), 0);          /* across the chunk border at x = 32 */
    uint64_t hashes[2] = { terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 })),
                           terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 1, 0 })) };
    cr_expect(terrain_world_water_at(world, 30.5, 16.5, NULL, NULL), "flooded");
    terrain_world_destroy(world);
    terrain_world *again = beach_world(log);               /* generated afresh, the log replayed */
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(again, (terrain_chunk_coord){ 0, 0 })), hashes[0]);
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(again, (terrain_chunk_coord){ 1, 0 })), hashes[1]);
    terrain_world_destroy(again);
    terrain_edit_log_destroy(log);
}

/* No column of the beach world holds water above the sea. */
static void expect_sea_level_kept(terrain_world *world) {
    int wet = 0;
    for (int z = 0; z < N; z++)
        for (int x = 0; x < 2 * N; x++) {
            float surface, ground;
            if (!terrain_world_water_at(world, x + 0.5, z + 0.5, &surface, &ground)) continue;
            wet++;
            cr_expect_eq(surface, 0.0f, "column (%d, %d): water up to %g over ground at %g", x, z, (double)surface,
                         (double)ground);
        }
    cr_expect_gt(wet, 0);
}

Test(terrain_water_sea, a_deposit_into_the_sea_keeps_the_surface_at_sea_level) {
    terrain_world *world = beach_world(NULL);
    terrain_chunk_coord changed[16];
    /* 60 m³ on a radius of 2.5 m: the pile rises well above the sea at its centre. */
    cr_assert_gt(terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                            .deposit = { .x = 8.5, .z = 16.5, .radius = 2.5f,
                                                                         .volume = 60 } },
                                    changed, 16), 0);
    cr_expect_gt(terrain_world_top(world, 8.5, 16.5), 0.0f, "the pile stands out of the sea");
    expect_sea_level_kept(world);
    terrain_world_destroy(world);
}

Test(terrain_water_sea, sand_that_slides_into_the_sea_keeps_the_surface_at_sea_level) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = beach_world(NULL);
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    /* On the beach's edge: the pile slides down into the sea over the next frames. */
    cr_assert(terrain_ecs_edit(te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                    .deposit = { .x = 16.5, .z = 16.5, .radius = 2.5f, .volume = 80 } }));
    int frames = 0;
    do {
        ecs_progress(ecs, 1.0f / 60.0f);
        terrain_world_trim(world);
    } while (++frames < 2000 && (terrain_ecs_edit_stats(te).stabilizing_chunks > 0 || frames < 2));
    cr_expect_eq(terrain_ecs_edit_stats(te).stabilizing_chunks, 0, "stabilized");
    cr_expect_gt(terrain_ecs_edit_stats(te).iterations, 0);
    expect_sea_level_kept(world);
    /* Some sand came to rest under the sea: a column of the sea now stands higher than its floor. */
    bool raised = false;
    for (int z = 0; z < N && !raised; z++)
        for (int x = 0; x < 16 && !raised; x++) raised = terrain_world_top(world, x + 0.5, z + 0.5) > -4.0f;
    cr_expect(raised, "sand slid into the sea");
    terrain_ecs_destroy(te);
    terrain_world_destroy(world);
    ecs_world_destroy(ecs);
    job_system_destroy(jobs);
}

/* ---- lakes (terrain_generate.c, "Lakes") -------------------------------------------------- */

/* Seed 1's lakes within a rectangle of chunks, found from the water in the stacks alone: every
 * other chunk of it is read (a lake's water circle is at least 2·(24 + 12) m across, so it
 * covers a 50 m square, which overlaps one of them whatever its place). The rectangles are a
 * quarter of a square kilometre or less, where a scan of 6.5 km² found lakes (so a debug run
 * stays short). */
#define LAKES_MAX 16

typedef struct chunk_rect { int64_t x0, z0, x1, z1; } chunk_rect;   /* [x0, x1) × [z0, z1) */

static const chunk_rect lake_square = { 16, -8, 24, 20 };           /* 256 × 896 m */
static const chunk_rect lake_corner = { 18, -8, 24, -2 };           /* 192 × 192 m */

typedef struct lake_found {
    float level;
    int columns;                          /* sampled columns with this water on top */
    int64_t x, z;                         /* one of them */
} lake_found;

/* Water on top above the sea: a lake's (the sea's surface is at sea_level exactly). */
static bool lake_at(terrain_world *world, int64_t x, int64_t z, float sea, float *level) {
    float surface;
    if (!terrain_world_water_at(world, (double)x + 0.5, (double)z + 0.5, &surface, NULL) || !(surface > sea))
        return false;
    *level = surface;
    return true;
}

static int find_lakes(terrain_world *world, float sea, chunk_rect rect, lake_found *lakes) {
    int count = 0;
    for (int64_t cz = rect.z0; cz < rect.z1; cz += 2)
        for (int64_t cx = rect.x0; cx < rect.x1; cx += 2) {
            for (int k = 0; k < N; k++)
                for (int i = 0; i < N; i++) {
                    float level;
                    if (!lake_at(world, cx * N + i, cz * N + k, sea, &level)) continue;
                    int n = 0;
                    while (n < count && lakes[n].level != level) n++;
                    if (n == count && count < LAKES_MAX) lakes[count++] = (lake_found){ level, 0, cx * N + i, cz * N + k };
                    if (n < count) lakes[n].columns++;
                }
            terrain_world_trim(world);
        }
    return count;
}

static terrain_world *seed_1_world(void) {
    return terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(1), .max_chunks = 512 });
}

Test(terrain_water_lakes, seed_1_has_lakes_within_a_quarter_square_kilometre) {
    terrain_world *world = seed_1_world();
    lake_found lakes[LAKES_MAX];
    int count = find_lakes(world, terrain_world_generation(world)->sea_level, lake_square, lakes);
    int sizeable = 0;
    for (int n = 0; n < count; n++) sizeable += lakes[n].columns >= 100;
    cr_expect_geq(sizeable, 2, "%d lakes of 100 columns or more (%d levels above the sea)", sizeable, count);
    terrain_world_destroy(world);
}

/* Every lake column's 8 neighbours hold water at its level or ground at or above it: the water
 * is held, with no step in its surface. Checked over every column within 140 m of a column of
 * the lake (its water circle is at most 2·(56 + 12) m across). */
Test(terrain_water_lakes, every_lake_column_is_held_by_its_neighbours) {
    terrain_world *world = seed_1_world();
    float sea = terrain_world_generation(world)->sea_level;
    lake_found lakes[LAKES_MAX];
    int count = find_lakes(world, sea, lake_corner, lakes), checked = 0;
    cr_assert_gt(count, 0);
    for (int n = 0; n < 1; n++) {   /* the first lake the corner holds */
        for (int64_t z = lakes[n].z - 140; z <= lakes[n].z + 140; z++)
            for (int64_t x = lakes[n].x - 140; x <= lakes[n].x + 140; x++) {
                float level;
                if (!lake_at(world, x, z, sea, &level) || level != lakes[n].level) continue;
                checked++;
                for (int dz = -1; dz <= 1; dz++)
                    for (int dx = -1; dx <= 1; dx++) {
                        float other;
                        bool same_water = lake_at(world, x + dx, z + dz, sea, &other) && other == level;
                        float ground = terrain_world_top(world, (double)(x + dx) + 0.5, (double)(z + dz) + 0.5);
                        cr_expect(same_water || ground >= level,
                                  "lake at %g: column (%lld, %lld) beside (%lld, %lld) has ground at %g",
                                  (double)level, (long long)(x + dx), (long long)(z + dz), (long long)x, (long long)z,
                                  (double)ground);
                    }
            }
        terrain_world_trim(world);
    }
    cr_expect_gt(checked, 100, "%d lake columns checked", checked);
    terrain_world_destroy(world);
}

/* The far terrain's lakes (terrain__lake_row_spaced, which the clipmap draws) are the water the
 * chunks hold: over seed 1's first lake in lake_corner, every column whose top is that lake's
 * water gets its level from the row (to the layers' quantum, which the water's top is rounded
 * to), and every column the row puts in the lake with ground a quantum or more under the level
 * holds that water. The clipmap's own grids (4 and 8 m) give the same level as the columns' 1 m
 * grid, and grids coarser than 8 m (no basins) no lake. */
Test(terrain_water_lakes, the_far_terrains_lake_levels_are_the_chunks_water) {
    terrain_world *world = seed_1_world();
    const terrain_generation_desc *p = terrain_world_generation(world);
    float sea = p->sea_level;
    lake_found lakes[LAKES_MAX];
    cr_assert_gt(find_lakes(world, sea, lake_corner, lakes), 0);
    const lake_found *lake = &lakes[0];
    int wet = 0, filled = 0;
    for (int64_t z = lake->z - 90; z <= lake->z + 90; z += 3) {
        float row[61];
        terrain__lake_row_spaced(p, (double)(lake->x - 90) + 0.5, 3.0, (double)z + 0.5, 61, 1.0f, row);
        for (int j = 0; j < 61; j++) {
            int64_t x = lake->x - 90 + 3 * j;
            float level;
            if (lake_at(world, x, z, sea, &level) && level == lake->level) {
                wet++;
                cr_expect_leq(fabsf(row[j] - level), TERRAIN_HEIGHT_QUANTUM, "column (%lld, %lld) holds the lake at %g; the row says %g", (long long)x,
                             (long long)z, (double)level, (double)row[j]);
            }
            bool in_lake = fabsf(row[j] - lake->level) <= TERRAIN_HEIGHT_QUANTUM;
            if (in_lake && terrain_world_top(world, (double)x + 0.5, (double)z + 0.5) <= row[j] - TERRAIN_HEIGHT_QUANTUM) {
                filled++;
                cr_expect(lake_at(world, x, z, sea, &level) && level == lake->level,
                          "column (%lld, %lld) lies under the row's lake at %g and is dry", (long long)x, (long long)z,
                          (double)lake->level);
            }
        }
        terrain_world_trim(world);
    }
    cr_expect_gt(wet, 50, "%d lake columns sampled", wet);
    cr_expect_gt(filled, 50, "%d columns the row floods", filled);
    const float spacings[] = { 4.0f, 8.0f, 16.0f, 64.0f };
    float columns_level;
    terrain__lake_row_spaced(p, (double)lake->x + 0.5, 1.0, (double)lake->z + 0.5, 1, 1.0f, &columns_level);
    for (int s = 0; s < 4; s++) {
        float level;
        terrain__lake_row_spaced(p, (double)lake->x + 0.5, 1.0, (double)lake->z + 0.5, 1, spacings[s], &level);
        if (spacings[s] <= 8.0f) cr_expect_eq(level, columns_level, "at a %g m spacing: %g", (double)spacings[s], (double)level);
        else cr_expect_eq(level, TERRAIN__NO_LAKE, "at a %g m spacing: %g", (double)spacings[s], (double)level);
    }
    terrain_world_destroy(world);
}

/* ---- the same bytes on any thread count and order ---- */

#define LAKE_DET_SIDE 3

typedef struct lake_job {
    terrain_generation_desc params;
    terrain_chunk_coord first;
    bool reverse;
    uint64_t hashes[LAKE_DET_SIDE * LAKE_DET_SIDE];
} lake_job;

static void lake_generate_range(void *user, size_t begin, size_t end) {
    lake_job *job = user;
    for (size_t n = begin; n < end; n++) {
        size_t index = job->reverse ? LAKE_DET_SIDE * LAKE_DET_SIDE - 1 - n : n;
        terrain_chunk_coord c = { job->first.x + (int64_t)(index % LAKE_DET_SIDE),
                                  job->first.z + (int64_t)(index / LAKE_DET_SIDE) };
        terrain_stacks *s = terrain_generate_chunk(&job->params, c);
        job->hashes[index] = terrain_stacks_hash(s);
        terrain_stacks_destroy(s);
    }
}

Test(terrain_water_lakes, lake_chunks_are_the_same_on_any_thread_count_and_order) {
    terrain_world *world = seed_1_world();
    lake_found lakes[LAKES_MAX];
    cr_assert_gt(find_lakes(world, terrain_world_generation(world)->sea_level, lake_corner, lakes), 0);
    static lake_job one, two;
    one.params = two.params = terrain_generation_defaults(1);
    /* The 3 × 3 chunks around a lake column. */
    int64_t lake_cx = (lakes[0].x - ((lakes[0].x % N + N) % N)) / N, lake_cz = (lakes[0].z - ((lakes[0].z % N + N) % N)) / N;
    one.first = two.first = (terrain_chunk_coord){ lake_cx - 1, lake_cz - 1 };
    two.reverse = true;
    job_system *serial = job_system_create(&(job_system_desc){ .threads = 1 });
    job_parallel_for(serial, LAKE_DET_SIDE * LAKE_DET_SIDE, 1, lake_generate_range, &one, "generate");
    job_system_destroy(serial);
    job_system *parallel = job_system_create(&(job_system_desc){ .threads = 2 });
    job_parallel_for(parallel, LAKE_DET_SIDE * LAKE_DET_SIDE, 1, lake_generate_range, &two, "generate");
    job_system_destroy(parallel);
    for (int n = 0; n < LAKE_DET_SIDE * LAKE_DET_SIDE; n++) cr_expect_eq(one.hashes[n], two.hashes[n], "chunk %d", n);
    /* The world's copy (generated in the scan's order, with other chunks before) is the same. */
    terrain_chunk_coord centre = { one.first.x + 1, one.first.z + 1 };
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(world, centre)), one.hashes[4]);
    terrain_world_destroy(world);
}

/* ---- what a mesh chunk holds is freed by its on_remove hook ------------------------------- */

/* A TerrainMeshChunk holding a CPU mesh and its water planes, as one meshed but not uploaded
 * holds them; `bytes` receives what it holds. */
static ecs_entity mesh_chunk_holding(water_ecs *w, ecs_component mesh_chunk, size_t *bytes) {
    terrain_mesh mesh = { .vertex_count = 4, .index_count = 6 };
    mesh.vertices = core_alloc(mesh.vertex_count * sizeof *mesh.vertices);
    mesh.indices = core_alloc(mesh.index_count * sizeof *mesh.indices);
    WaterPlane *water = core_alloc(sizeof *water);
    memset(water, 0, sizeof *water);
    *bytes = mesh.vertex_count * sizeof *mesh.vertices + mesh.index_count * sizeof *mesh.indices +
             sizeof *water;
    ecs_entity e = ecs_entity_create(w->ecs);
    ecs_set(w->ecs, e, mesh_chunk, &(TerrainMeshChunk){ .state = TERRAIN_MESH_MESHED,
                                                         .mesh = mesh, .water = water });
    return e;
}

/* Destroying the entity, removing the component and terrain_ecs_destroy each free the chunk's
 * mesh and water once (core_memory_in_use drops by exactly what it held), and nothing counted
 * is left once everything is closed. */
Test(terrain_water_planes, a_mesh_chunk_frees_what_it_holds_through_its_hook) {
    water_ecs warm = water_ecs_open();   /* what lives as long as the process is made now */
    water_ecs_close(&warm);
    size_t at_start = core_memory_in_use();
    water_ecs w = water_ecs_open();
    ecs_component mesh_chunk = ecs_component_lookup(w.ecs, "TerrainMeshChunk");
    size_t held[3];
    ecs_entity e[3];
    for (int i = 0; i < 3; i++) e[i] = mesh_chunk_holding(&w, mesh_chunk, &held[i]);

    size_t before = core_memory_in_use();
    ecs_entity_destroy(w.ecs, e[0]);
    cr_expect_eq(before - core_memory_in_use(), held[0], "destroy frees the chunk's mesh and water");
    before = core_memory_in_use();
    ecs_remove(w.ecs, e[1], mesh_chunk);
    cr_expect_eq(before - core_memory_in_use(), held[1], "so does removing the component");
    water_ecs_close(&w);                 /* e[2] goes with terrain_ecs_destroy */
    cr_expect_eq(core_memory_in_use(), at_start, "nothing counted is left: %zd bytes",
                 (ptrdiff_t)(core_memory_in_use() - at_start));
}
