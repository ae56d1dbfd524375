/* Stacks: the builder's merge/drop/rounding rules, queries on hand-made stacks, the packing's
 * size, and the world's cache (with a hand-made generator, independent of terrain_generate). */
#include "../engine/test.h"
#include "terrain/terrain.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <math.h>
#include <stdatomic.h>

#define N TERRAIN_CHUNK_COLUMNS
#define Q TERRAIN_HEIGHT_QUANTUM

typedef struct hand_layer { terrain_material material; float thickness; } hand_layer;

/* Every column gets the same layers. */
static terrain_stacks *build_uniform(terrain_stacks_builder *b, const hand_layer *layers, int count) {
    for (int c = 0; c < N * N; c++) {
        for (int l = 0; l < count; l++) terrain_stacks_builder_push(b, layers[l].material, layers[l].thickness);
        terrain_stacks_builder_end_column(b);
    }
    return terrain_stacks_builder_finish(b);
}

static terrain_stacks *make_uniform(const hand_layer *layers, int count) {
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    terrain_stacks *s = build_uniform(b, layers, count);
    terrain_stacks_builder_destroy(b);
    return s;
}

Test(terrain_stacks, materials_named_and_in_field) {
    cr_expect_str_eq(terrain_material_name(TERRAIN_AIR), "air");
    cr_expect_str_eq(terrain_material_name(TERRAIN_BEDROCK), "bedrock");
    cr_expect_str_eq(terrain_material_name(TERRAIN_SAND), "sand");
    cr_expect_str_eq(terrain_material_name(TERRAIN_ROCKS), "rocks");
    cr_expect_str_eq(terrain_material_name(TERRAIN_WATER), "water");
    cr_expect(terrain_material_in_field(TERRAIN_BEDROCK));
    cr_expect(terrain_material_in_field(TERRAIN_SAND));
    cr_expect_not(terrain_material_in_field(TERRAIN_AIR));
    cr_expect_not(terrain_material_in_field(TERRAIN_ROCKS));
    cr_expect_not(terrain_material_in_field(TERRAIN_WATER));
    /* a game's own materials are rock, solid like bedrock; past the last there are none */
    cr_expect(terrain_material_in_field(TERRAIN_MATERIAL_BUILTIN_COUNT));
    cr_expect(terrain_material_in_field((terrain_material)(TERRAIN_MATERIAL_MAX - 1)));
    cr_expect_not(terrain_material_in_field(TERRAIN_MATERIAL_MAX));
}

Test(terrain_stacks, adjacent_same_material_layers_merge) {
    hand_layer in[] = { { TERRAIN_BEDROCK, 1.0f }, { TERRAIN_BEDROCK, 2.0f }, { TERRAIN_SAND, 0.5f },
                        { TERRAIN_SAND, 0.25f } };
    terrain_stacks *s = make_uniform(in, 4);
    terrain_layer out[8];
    cr_assert_eq(terrain_stacks_column(s, 3, 7, out, 8), 2);
    cr_expect_eq(out[0].material, TERRAIN_BEDROCK);
    cr_expect_float_eq(out[0].thickness, 3.0f, 1e-6f);
    cr_expect_eq(out[1].material, TERRAIN_SAND);
    cr_expect_float_eq(out[1].thickness, 0.75f, 1e-6f);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, zero_layers_dropped_and_neighbours_merge) {
    /* The air of thickness 0 vanishes, so the bedrock on both sides becomes one layer; negative
     * and NaN thicknesses add nothing either. */
    hand_layer in[] = { { TERRAIN_BEDROCK, 2.0f }, { TERRAIN_AIR, 0.0f }, { TERRAIN_WATER, -1.0f },
                        { TERRAIN_SAND, NAN }, { TERRAIN_BEDROCK, 1.0f }, { TERRAIN_SAND, 1.0f } };
    terrain_stacks *s = make_uniform(in, 6);
    terrain_layer out[8];
    cr_assert_eq(terrain_stacks_column(s, 0, 0, out, 8), 2);
    cr_expect_eq(out[0].material, TERRAIN_BEDROCK);
    cr_expect_float_eq(out[0].thickness, 3.0f, 1e-6f);
    cr_expect_eq(out[1].material, TERRAIN_SAND);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, rounding_is_of_cumulative_heights) {
    /* Quantum 1/32 = 0.03125 m. Cumulative heights 0.02, 0.04, 0.06 m round to 1, 1, 2 quanta:
     * bedrock 1 quantum, sand 0 (dropped), bedrock 1 → merged: one bedrock layer of 2 quanta. */
    hand_layer in[] = { { TERRAIN_BEDROCK, 0.02f }, { TERRAIN_SAND, 0.02f }, { TERRAIN_BEDROCK, 0.02f } };
    terrain_stacks *s = make_uniform(in, 3);
    terrain_layer out[4];
    cr_assert_eq(terrain_stacks_column(s, 1, 1, out, 4), 1);
    cr_expect_eq(out[0].material, TERRAIN_BEDROCK);
    cr_expect_float_eq(out[0].thickness, 2.0f * Q, 1e-7f);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, rounding_conserves_column_height) {
    /* 400 layers of 0.1 m = 3.2 quanta each, alternating materials: rounding each thickness
     * would give 3 quanta each (37.5 m in all, 2.5 m lost); rounding cumulative heights gives 3
     * or 4 so the column is 40 m to within a quantum, and every top stays within half a quantum
     * of its exact height. */
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    for (int c = 0; c < N * N; c++) {
        for (int l = 0; l < 400; l++) terrain_stacks_builder_push(b, l % 2 ? TERRAIN_SAND : TERRAIN_BEDROCK, 0.1f);
        terrain_stacks_builder_end_column(b);
    }
    terrain_stacks *s = terrain_stacks_builder_finish(b);
    terrain_stacks_builder_destroy(b);
    static terrain_layer out[512];
    cr_assert_eq(terrain_stacks_column(s, 31, 31, out, 512), 400);
    double top = 0.0;
    for (int l = 0; l < 400; l++) {
        cr_assert(out[l].thickness == 3 * Q || out[l].thickness == 4 * Q, "layer %d: %g", l, out[l].thickness);
        cr_assert_eq(out[l].material, l % 2 ? TERRAIN_SAND : TERRAIN_BEDROCK);
        top += out[l].thickness;
        cr_assert(fabs(top - 0.1 * (l + 1)) <= 0.5 * Q + 1e-4, "top of layer %d at %g", l, top);
    }
    cr_expect(fabs(top - 40.0) <= Q);
    cr_expect_float_eq(terrain_stacks_surface(s, 31, 31), TERRAIN_FLOOR_Y + 40.0f, Q);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, trailing_air_is_implicit_inner_air_kept) {
    hand_layer with_cave[] = { { TERRAIN_BEDROCK, 5.0f }, { TERRAIN_AIR, 3.0f }, { TERRAIN_BEDROCK, 2.0f },
                               { TERRAIN_AIR, 50.0f } };
    terrain_stacks *s = make_uniform(with_cave, 4);
    terrain_layer out[8];
    cr_assert_eq(terrain_stacks_column(s, 4, 4, out, 8), 3);
    cr_expect_eq(out[1].material, TERRAIN_AIR);
    cr_expect_float_eq(out[1].thickness, 3.0f, 1e-6f);
    cr_expect_eq(out[2].material, TERRAIN_BEDROCK);
    terrain_stacks_destroy(s);

    hand_layer only_air[] = { { TERRAIN_AIR, 10.0f } };
    s = make_uniform(only_air, 1);
    cr_expect_eq(terrain_stacks_column(s, 0, 0, out, 8), 0);
    cr_expect_float_eq(terrain_stacks_top(s, 0, 0), TERRAIN_FLOOR_Y, 0.0f);
    cr_expect_float_eq(terrain_stacks_surface(s, 0, 0), TERRAIN_FLOOR_Y, 0.0f);
    cr_expect_eq(terrain_stacks_material_at(s, 0, 0, TERRAIN_FLOOR_Y + 1.0f), TERRAIN_AIR);
    cr_expect_eq(terrain_stacks_material_at(s, 0, 0, TERRAIN_FLOOR_Y - 1.0f), TERRAIN_BEDROCK);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, queries_on_a_hand_stack) {
    /* Floor −256. Bedrock [−256, −246), air [−246, −241), sand [−241, −239), water [−239, −236). */
    hand_layer in[] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_AIR, 5.0f }, { TERRAIN_SAND, 2.0f },
                        { TERRAIN_WATER, 3.0f } };
    terrain_stacks *s = make_uniform(in, 4);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -300.0f), TERRAIN_BEDROCK);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -250.0f), TERRAIN_BEDROCK);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -246.01f), TERRAIN_BEDROCK);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -246.0f), TERRAIN_AIR);   /* [bottom, top) */
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -243.0f), TERRAIN_AIR);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -240.0f), TERRAIN_SAND);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -237.0f), TERRAIN_WATER);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, -236.0f), TERRAIN_AIR);
    cr_expect_eq(terrain_stacks_material_at(s, 9, 2, 1000.0f), TERRAIN_AIR);
    cr_expect_float_eq(terrain_stacks_top(s, 9, 2), -239.0f, 0.0f);      /* water is not ground */
    cr_expect_float_eq(terrain_stacks_surface(s, 9, 2), -236.0f, 0.0f);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, long_layers_read_back_whole) {
    /* 300 m (9 600 quanta, over the short form's 4 095) and 5 000 m (160 000 quanta, over one
     * long entry's 65 535): each still reads as one layer of its exact thickness. */
    hand_layer in[] = { { TERRAIN_BEDROCK, 300.0f }, { TERRAIN_SAND, 5000.0f }, { TERRAIN_WATER, 1.0f } };
    terrain_stacks *s = make_uniform(in, 3);
    terrain_layer out[8];
    cr_assert_eq(terrain_stacks_column(s, 17, 30, out, 8), 3);
    cr_expect_float_eq(out[0].thickness, 300.0f, 0.0f);
    cr_expect_float_eq(out[1].thickness, 5000.0f, 0.0f);
    cr_expect_eq(out[1].material, TERRAIN_SAND);
    cr_expect_eq(terrain_stacks_material_at(s, 17, 30, 43.9f), TERRAIN_BEDROCK);
    cr_expect_eq(terrain_stacks_material_at(s, 17, 30, 44.0f), TERRAIN_SAND);
    cr_expect_eq(terrain_stacks_material_at(s, 17, 30, 4000.0f), TERRAIN_SAND);
    cr_expect_eq(terrain_stacks_material_at(s, 17, 30, 5044.5f), TERRAIN_WATER);
    cr_expect_float_eq(terrain_stacks_top(s, 17, 30), 5044.0f, 0.0f);
    terrain_stacks_destroy(s);
}

Test(terrain_stacks, columns_are_independent_and_indexed_z_major) {
    /* Column (i, k) gets a bedrock layer of (1 + i + N·k) quanta and, for odd i, a sand cap of k+1
     * quanta: every column's own content must come back from its own index. */
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    for (int k = 0; k < N; k++) {
        for (int i = 0; i < N; i++) {
            terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(1 + i + N * k) * Q);
            if (i % 2) terrain_stacks_builder_push(b, TERRAIN_SAND, (float)(k + 1) * Q);
            terrain_stacks_builder_end_column(b);
        }
    }
    terrain_stacks *s = terrain_stacks_builder_finish(b);
    terrain_layer out[4];
    for (int k = 0; k < N; k++) {
        for (int i = 0; i < N; i++) {
            int count = terrain_stacks_column(s, i, k, out, 4);
            cr_assert_eq(count, i % 2 ? 2 : 1, "column (%d, %d)", i, k);
            cr_assert_float_eq(out[0].thickness, (float)(1 + i + N * k) * Q, 0.0f);
            if (i % 2) cr_assert_float_eq(out[1].thickness, (float)(k + 1) * Q, 0.0f);
            float expected_top = TERRAIN_FLOOR_Y + (float)(1 + i + N * k + (i % 2 ? k + 1 : 0)) * Q;
            cr_assert_float_eq(terrain_stacks_top(s, i, k), expected_top, 0.0f);
        }
    }
    /* The builder is reusable after finish. */
    hand_layer one[] = { { TERRAIN_WATER, 1.0f } };
    terrain_stacks *again = build_uniform(b, one, 1);
    cr_expect_eq(terrain_stacks_column(again, 5, 5, out, 4), 1);
    cr_expect_eq(out[0].material, TERRAIN_WATER);
    terrain_stacks_destroy(again);
    terrain_stacks_destroy(s);
    terrain_stacks_builder_destroy(b);
}

Test(terrain_stacks, hash_is_of_logical_content) {
    hand_layer a[] = { { TERRAIN_BEDROCK, 1.0f }, { TERRAIN_BEDROCK, 1.0f }, { TERRAIN_SAND, 1.0f } };
    hand_layer b[] = { { TERRAIN_BEDROCK, 2.0f }, { TERRAIN_AIR, 0.0f }, { TERRAIN_SAND, 1.0f }, { TERRAIN_AIR, 9.0f } };
    hand_layer c[] = { { TERRAIN_BEDROCK, 2.0f }, { TERRAIN_WATER, 1.0f } };
    hand_layer d[] = { { TERRAIN_BEDROCK, 2.0f }, { TERRAIN_SAND, 1.0f + Q } };
    terrain_stacks *sa = make_uniform(a, 3), *sb = make_uniform(b, 4), *sc = make_uniform(c, 2), *sd = make_uniform(d, 2);
    cr_expect_eq(terrain_stacks_hash(sa), terrain_stacks_hash(sb));
    cr_expect_neq(terrain_stacks_hash(sa), terrain_stacks_hash(sc));
    cr_expect_neq(terrain_stacks_hash(sa), terrain_stacks_hash(sd));
    terrain_stacks_destroy(sa);
    terrain_stacks_destroy(sb);
    terrain_stacks_destroy(sc);
    terrain_stacks_destroy(sd);
}

Test(terrain_stacks, packing_costs_two_bytes_a_layer) {
    /* 2 bytes of index per column plus 2 bytes per short layer and 4 per long one (more than
     * 4 095 quanta ≈ 128 m); a fixed header of well under 1 KiB on top. */
    hand_layer in[] = { { TERRAIN_BEDROCK, 300.0f }, { TERRAIN_SAND, 2.0f }, { TERRAIN_WATER, 3.0f } };
    terrain_stacks *s = make_uniform(in, 3);
    size_t per_column = 2 + 4 + 2 + 2;
    size_t bytes = terrain_stacks_bytes(s);
    cr_expect_geq(bytes, per_column * N * N);
    cr_expect_leq(bytes, per_column * N * N + 1024, "%zu bytes", bytes);
    terrain_stacks_destroy(s);
}

/* ---- the world ---------------------------------------------------------------------------- */

/* A hand-made generator: column (i, k) of chunk (x, z) is bedrock up to height
 * 10·x + z + i/32 (metres above the floor, plus 1 so it is never empty), nothing else. */
static atomic_int hand_generated;

static float hand_height(terrain_chunk_coord c, int i) {
    return 1.0f + 10.0f * (float)(c.x & 7) + (float)(c.z & 7) + (float)i / 32.0f;
}

static terrain_stacks *hand_generate(void *user, terrain_chunk_coord coord) {
    (void)user;
    atomic_fetch_add(&hand_generated, 1);
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    for (int k = 0; k < N; k++) {
        for (int i = 0; i < N; i++) {
            terrain_stacks_builder_push(b, TERRAIN_BEDROCK, hand_height(coord, i));
            terrain_stacks_builder_end_column(b);
        }
    }
    terrain_stacks *s = terrain_stacks_builder_finish(b);
    terrain_stacks_builder_destroy(b);
    return s;
}

Test(terrain_world, caches_and_finds_material) {
    atomic_store(&hand_generated, 0);
    terrain_world *w = terrain_world_create(&(terrain_world_desc){ .generate = hand_generate });
    terrain_chunk_coord c = { 2, -3 };
    const terrain_stacks *s = terrain_world_stacks(w, c);
    cr_assert_eq(terrain_world_stacks(w, c), s);
    cr_expect_eq(atomic_load(&hand_generated), 1);
    cr_expect_eq(terrain_world_chunk_count(w), 1);
    /* World x = 2·32 + 5 + 0.5 → chunk 2, column 5; z = −3·32 + 0.25 → chunk −3. Column height
     * 1 + 20 + (−3 & 7 = 5) + 5/32 = 26.15625 above the floor. */
    double x = 69.5, z = -95.75;
    float top = TERRAIN_FLOOR_Y + 26.15625f;
    cr_expect_eq(terrain_world_material_at(w, x, top - 0.01, z), TERRAIN_BEDROCK);
    cr_expect_eq(terrain_world_material_at(w, x, top + 0.01, z), TERRAIN_AIR);
    cr_expect_eq(terrain_world_material_at(w, x, -1000.0, z), TERRAIN_BEDROCK);
    /* x = −0.5 is in chunk −1, column 31. */
    terrain_chunk_coord west = { -1, 0 };
    float west_top = TERRAIN_FLOOR_Y + hand_height(west, 31);
    cr_expect_eq(terrain_world_material_at(w, -0.5, west_top - 0.01, 3.0), TERRAIN_BEDROCK);
    cr_expect_eq(terrain_world_material_at(w, -0.5, west_top + 0.01, 3.0), TERRAIN_AIR);
    cr_expect_eq(terrain_world_chunk_count(w), 2);   /* (2, −3) and (−1, 0) */
    terrain_world_destroy(w);
}

Test(terrain_world, trim_evicts_least_recently_used_but_not_retained) {
    terrain_world *w = terrain_world_create(&(terrain_world_desc){ .generate = hand_generate, .max_chunks = 3 });
    terrain_chunk_coord a = { 0, 0 }, b = { 1, 0 }, c = { 2, 0 }, d = { 3, 0 }, e = { 4, 0 };
    terrain_world_retain(w, a);                    /* generates a */
    terrain_world_stacks(w, b);
    terrain_world_stacks(w, c);
    terrain_world_stacks(w, d);
    terrain_world_stacks(w, e);                    /* recency, oldest first: a b c d e */
    cr_expect_eq(terrain_world_chunk_count(w), 5, "terrain_world_stacks never evicts");
    terrain_world_stacks(w, b);                    /* now: a c d e b */
    cr_expect_eq(terrain_world_trim(w), 2);        /* c and d go; a is retained */
    cr_expect_eq(terrain_world_chunk_count(w), 3);
    atomic_store(&hand_generated, 0);
    terrain_world_stacks(w, a);
    terrain_world_stacks(w, b);
    terrain_world_stacks(w, e);
    cr_expect_eq(atomic_load(&hand_generated), 0, "a, b and e were kept");
    terrain_world_stacks(w, c);
    cr_expect_eq(atomic_load(&hand_generated), 1, "c was evicted");
    terrain_world_release(w, a);
    terrain_world_stacks(w, b);
    terrain_world_stacks(w, c);
    terrain_world_stacks(w, e);                    /* a is now the oldest and free to go */
    cr_expect_eq(terrain_world_trim(w), 1);
    atomic_store(&hand_generated, 0);
    terrain_world_stacks(w, a);
    cr_expect_eq(atomic_load(&hand_generated), 1, "a was evicted once released");
    terrain_world_destroy(w);
}

typedef struct fetch_job {
    terrain_world *world;
    const terrain_stacks *seen[64];
} fetch_job;

static void fetch_range(void *user, size_t begin, size_t end) {
    fetch_job *job = user;
    for (size_t n = begin; n < end; n++) {
        /* Four threads' worth of requests for the same 16 chunks, interleaved. */
        terrain_chunk_coord c = { (int64_t)(n % 16), -(int64_t)(n % 16) };
        job->seen[n] = terrain_world_stacks(job->world, c);
    }
}

Test(terrain_world, concurrent_requests_share_one_chunk) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 4 });
    fetch_job job = { .world = terrain_world_create(&(terrain_world_desc){ .generate = hand_generate }) };
    job_parallel_for(jobs, 64, 1, fetch_range, &job, "fetch");
    for (int n = 0; n < 64; n++) {
        terrain_chunk_coord c = { n % 16, -(n % 16) };
        cr_assert_eq(job.seen[n], terrain_world_stacks(job.world, c), "request %d", n);
    }
    cr_expect_eq(terrain_world_chunk_count(job.world), 16);
    terrain_world_destroy(job.world);
    job_system_destroy(jobs);
}

/* Interfaces: where in-field material meets air or water, over all columns. One column has a
 * cave (bedrock 0–10 m, air 10–12, sand 12–14, water 14–20 above the floor); the rest are 5 m
 * of bedrock under 3 m of water. Lowest: 5 m (the others' top); highest: 14 m (sand under water). */

static void interface_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    if (x == 7 && z == 3) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.0f);
        terrain_stacks_builder_push(b, TERRAIN_AIR, 2.0f);
        terrain_stacks_builder_push(b, TERRAIN_SAND, 2.0f);
        terrain_stacks_builder_push(b, TERRAIN_WATER, 6.0f);
    } else {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 5.0f);
        terrain_stacks_builder_push(b, TERRAIN_WATER, 3.0f);
    }
}

Test(terrain_stacks, interface_range_spans_caves_and_tops) {
    terrain_stacks *s = terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, interface_column, NULL);
    float low, high;
    terrain_stacks_interface_range(s, &low, &high);
    cr_expect_float_eq(low, TERRAIN_FLOOR_Y + 5.0f, 1e-4f, "lowest %g", (double)low);
    cr_expect_float_eq(high, TERRAIN_FLOOR_Y + 14.0f, 1e-4f, "highest %g", (double)high);
    terrain_stacks_destroy(s);
    /* An empty chunk (air from the floor up): the floor itself is the interface. */
    const hand_layer air[] = { { TERRAIN_AIR, 4.0f } };
    s = make_uniform(air, 1);
    terrain_stacks_interface_range(s, &low, &high);
    cr_expect_float_eq(low, TERRAIN_FLOOR_Y, 1e-4f);
    cr_expect_float_eq(high, TERRAIN_FLOOR_Y, 1e-4f);
    terrain_stacks_destroy(s);
}
