/* The brushes on a columns region: deposit (000 §4.3) and surface and collapse erosion (§4.4).
 * Expectations come from the paper's formulas worked by hand and from invariants (mass of every
 * material), never from printed output. */
#include "terrain_columns_test.h"

#include "core/core.h"

#include <math.h>
#include <stdlib.h>

/* ---- random edits: mass of every material ------------------------------------------------ */

Test(terrain_brush, random_deposits_and_erosions_conserve_every_material) {
    terrain_columns *c = region(0, 0, 64, 64);
    load_generated(c, 7);
    masses m = mass_of(c);
    for (int n = 0; n < 24; n++) {
        uint64_t h = core_hash_u64(0x5eed + (uint64_t)n);
        double x = (double)(h % 6400) / 100.0, z = (double)((h >> 16) % 6400) / 100.0;
        float radius = 1.0f + (float)((h >> 32) % 100) / 10.0f;
        int64_t q = 0;
        if (n % 3 == 0) {
            terrain_material material = (h >> 40) & 1 ? TERRAIN_ROCKS : TERRAIN_SAND;
            double volume = (double)((h >> 44) % 3000) / 10.0;
            terrain_brush_material brush = material == TERRAIN_ROCKS ? TERRAIN_BRUSH_ROCKS : TERRAIN_BRUSH_SAND;
            cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .material = brush, .x = x, .z = z,
                                                                  .radius = radius, .volume = volume }, &q));
            cr_expect_eq(q, llround(volume * QPM));
            if (material == TERRAIN_SAND) m.sand += q;
            else m.rocks += q;
            /* The deposit displaces the water standing on the pile (terrain.h, "the sea after
             * edits"): some goes, at most as much as was dropped, none comes. */
            int64_t water = terrain_columns_mass(c, TERRAIN_WATER);
            cr_expect(water <= m.water && water >= m.water - q, "water %lld from %lld after %lld dropped",
                      (long long)water, (long long)m.water, (long long)q);
            m.water = water;
        } else {
            /* ρ = 0 or 1 makes each material's share exact; in between only the sum is. */
            float rho = n % 3 == 1 ? 0.0f : 1.0f;
            bool collapse = (h >> 41) & 1;
            float ground = terrain_columns_top(c, (int)x, (int)z);
            cr_assert(terrain_erode(c, &(terrain_erode_desc){ .mode = collapse ? TERRAIN_ERODE_COLLAPSE : TERRAIN_ERODE_SURFACE,
                                                               .x = x, .y = ground - 2.0f, .z = z, .radius = radius,
                                                               .depth = 3.0f, .rocks_ratio = rho }, &q));
            m.bedrock -= q;
            if (rho == 0.0f) m.sand += q;
            else m.rocks += q;
        }
        expect_same_mass(m, mass_of(c));
        if (n % 4 == 3) {
            /* In steps, with a budget of a few iterations: stopping anywhere conserves mass too. */
            stabilize(c, &(terrain_stabilize_desc){ .max_iterations = 3 }, NULL);
            expect_same_mass(m, mass_of(c));
        }
    }
    terrain_stabilize_result r = stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect(r.converged);
    expect_same_mass(m, mass_of(c));
    terrain_columns_destroy(c);
}

/* ---- brushes (000 §4.3, §4.4) ------------------------------------------------------------- */

Test(terrain_brush, deposit_drops_exactly_the_volume_with_the_falloff) {
    terrain_columns *c = region(0, 0, 40, 40);
    fill_flat(c, 10.0f);
    int64_t q;
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .material = TERRAIN_BRUSH_ROCKS, .x = 20.5, .z = 20.5, .radius = 6,
                                                          .volume = 123.4 }, &q));
    cr_expect_eq(q, 3949);                                  /* 123.4 m³ · 32 = 3948.8 → 3949 */
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_ROCKS), 3949);
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_SAND), 0);
    /* (1 − r²/R²)²: most at the centre column, less at r = 3, nothing at r ≥ 6. */
    int64_t centre = column_quanta(c, 20, 20, TERRAIN_ROCKS), mid = column_quanta(c, 23, 20, TERRAIN_ROCKS);
    cr_expect_gt(centre, mid);
    cr_expect_gt(mid, 0);
    cr_expect_eq(column_quanta(c, 26, 20, TERRAIN_ROCKS), 0);
    /* The distribution's ratio: weights 1 and (1 − 9/36)² = 0.5625 (±1 quantum of rounding). */
    cr_expect_leq(llabs(mid - llround((double)centre * 0.5625)), 2);
    /* Flat: the same on every column under the disc, sand 0 meaning sand. */
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 5.5, .z = 5.5, .radius = 2.2f, .volume = 13,
                                                          .falloff = TERRAIN_FALLOFF_FLAT }, &q));
    cr_expect_eq(q, 416);
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_SAND), 416);
    /* 13 columns have centres within 2.2 of (5.5, 5.5) (r² ∈ {0, 1, 2, 4}): 416 = 13·32. */
    for (int k = 0; k < 12; k++)
        for (int i = 0; i < 12; i++) {
            int r2 = (i - 5) * (i - 5) + (k - 5) * (k - 5);
            cr_expect_eq(column_quanta(c, i, k, TERRAIN_SAND), r2 <= 4 ? 32 : 0, "(%d, %d)", i, k);
        }
    terrain_columns_destroy(c);
}

Test(terrain_brush, deposit_over_the_border_puts_it_all_inside) {
    terrain_columns *c = region(0, 0, 16, 16);
    fill_flat(c, 10.0f);
    int64_t q;
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = -2, .z = 8, .radius = 5, .volume = 50 }, &q));
    cr_expect_eq(q, 1600);
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_SAND), 1600);
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);
    cr_expect_not(terrain_deposit(c, &(terrain_deposit_desc){ .x = -20, .z = 8, .radius = 5, .volume = 50 }, &q));
    core_log_set_level(level);
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_SAND), 1600);
    terrain_columns_destroy(c);
}

Test(terrain_brush, surface_erosion_turns_bedrock_into_sand_and_rocks_in_place) {
    /* Flat bedrock 10 m, flat brush of radius 1.2 around (5.5, 5.5): five columns, each losing
     * 2 m = 64 quanta of bedrock, ρ = 0.25 → 16 rocks, 48 sand; the ground does not move. */
    terrain_columns *c = region(0, 0, 11, 11);
    fill_flat(c, 10.0f);
    int64_t q;
    cr_assert(terrain_erode(c, &(terrain_erode_desc){ .x = 5.5, .z = 5.5, .radius = 1.2f, .depth = 2,
                                                      .rocks_ratio = 0.25f, .falloff = TERRAIN_FALLOFF_FLAT }, &q));
    cr_expect_eq(q, 5 * 64);
    const int at[5][2] = { { 5, 5 }, { 4, 5 }, { 6, 5 }, { 5, 4 }, { 5, 6 } };
    for (int n = 0; n < 5; n++) {
        cr_expect_eq(column_quanta(c, at[n][0], at[n][1], TERRAIN_BEDROCK), 320 - 64);
        cr_expect_eq(column_quanta(c, at[n][0], at[n][1], TERRAIN_ROCKS), 16);
        cr_expect_eq(column_quanta(c, at[n][0], at[n][1], TERRAIN_SAND), 48);
        cr_expect_float_eq(terrain_columns_top(c, at[n][0], at[n][1]), TERRAIN_FLOOR_Y + 10.0f, 0.0f);
    }
    cr_expect_eq(column_quanta(c, 4, 4, TERRAIN_SAND), 0);
    /* Eroding deeper than the layer stops at the floor. */
    cr_assert(terrain_erode(c, &(terrain_erode_desc){ .x = 0.5, .z = 0.5, .radius = 0.6f, .depth = 50 }, &q));
    cr_expect_eq(q, 320);
    cr_expect_eq(column_quanta(c, 0, 0, TERRAIN_SAND), 320);
    terrain_columns_destroy(c);
}

/* Zero in a brush's desc is its documented default, never a value of its own: a deposit of
 * material 0 is sand, falloff 0 smooth; an erosion of mode 0 wears the surface. Each pair of
 * regions gets the same edit spelt both ways and must end with the same bytes. */
Test(terrain_brush, zero_in_a_brush_desc_is_the_documented_default) {
    terrain_columns *zero = region(0, 0, 16, 16), *named = region(0, 0, 16, 16);
    fill_flat(zero, 10.0f);
    fill_flat(named, 10.0f);
    int64_t q_zero, q_named;
    cr_assert(terrain_deposit(zero, &(terrain_deposit_desc){ .x = 8, .z = 8, .radius = 4, .volume = 20 }, &q_zero));
    cr_assert(terrain_deposit(named, &(terrain_deposit_desc){ .material = TERRAIN_BRUSH_SAND, .x = 8, .z = 8,
                                                              .radius = 4, .volume = 20,
                                                              .falloff = TERRAIN_FALLOFF_SMOOTH }, &q_named));
    cr_expect_eq(q_zero, q_named);
    cr_expect_eq(terrain_columns_mass(zero, TERRAIN_SAND), 640, "20 m3 = 640 quanta-columns of sand");
    cr_expect_eq(region_hash(zero), region_hash(named));
    /* Smooth is not flat: the centre column gets more than one at r = 3 (a flat brush would not). */
    cr_expect_gt(column_quanta(zero, 8, 8, TERRAIN_SAND), column_quanta(zero, 11, 8, TERRAIN_SAND));
    cr_assert(terrain_erode(zero, &(terrain_erode_desc){ .x = 4.5, .z = 4.5, .radius = 2, .depth = 1 }, NULL));
    cr_assert(terrain_erode(named, &(terrain_erode_desc){ .mode = TERRAIN_ERODE_SURFACE, .x = 4.5, .z = 4.5,
                                                          .radius = 2, .depth = 1, .falloff = TERRAIN_FALLOFF_SMOOTH },
                            NULL));
    cr_expect_eq(region_hash(zero), region_hash(named));
    cr_expect_lt(column_quanta(zero, 4, 4, TERRAIN_BEDROCK), 320, "the surface wore down");
    terrain_columns_destroy(zero);
    terrain_columns_destroy(named);
}

Test(terrain_brush, collapse_erosion_drops_an_overhang_to_the_floor) {
    /* Bedrock 0–4 m, air 4–8 m, a bedrock roof 8–10 m with 1 m of sand: the ball of radius 3 m
     * around y = 9 m above the floor (world y = −247) takes the whole roof of the centre column
     * (the chord there is 2·3 = 6 m: 6–12 m) — 2 m = 64 quanta, ρ = 0.5 → 32 sand, 32 rocks.
     * With the roof gone the sand above falls into the cave: sand 1 + 1 m, rocks 1 m on the
     * floor at 4 m, sorted sand under rocks. */
    terrain_columns *c = region(0, 0, 1, 1);
    terrain_layer layers[] = { { TERRAIN_BEDROCK, 4 }, { TERRAIN_AIR, 4 }, { TERRAIN_BEDROCK, 2 }, { TERRAIN_SAND, 1 } };
    cr_assert(terrain_columns_set(c, 0, 0, layers, 4));
    int64_t q;
    cr_assert(terrain_erode(c, &(terrain_erode_desc){ .mode = TERRAIN_ERODE_COLLAPSE, .x = 0.5, .y = TERRAIN_FLOOR_Y + 9,
                                                      .z = 0.5, .radius = 3, .rocks_ratio = 0.5f }, &q));
    cr_expect_eq(q, 64);
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_layer out[8];
    cr_assert_eq(terrain_columns_get(c, 0, 0, out, 8), 3);
    cr_expect_eq(out[0].material, TERRAIN_BEDROCK);
    cr_expect_eq(out[0].thickness, 4.0f);
    cr_expect_eq(out[1].material, TERRAIN_SAND);
    cr_expect_eq(out[1].thickness, 2.0f);
    cr_expect_eq(out[2].material, TERRAIN_ROCKS);
    cr_expect_eq(out[2].thickness, 1.0f);
    terrain_columns_destroy(c);
}

Test(terrain_brush, collapse_inside_rock_leaves_rubble_under_the_rock_above) {
    /* Bedrock 0–20 m; a ball of radius 2 at 10 m above the floor: the centre column's chord
     * 8–12 m turns to rubble between bedrock 0–8 and 12–20 (bedrock is stable: it stays). */
    terrain_columns *c = region(0, 0, 1, 1);
    terrain_layer rock = { TERRAIN_BEDROCK, 20 };
    cr_assert(terrain_columns_set(c, 0, 0, &rock, 1));
    int64_t q;
    cr_assert(terrain_erode(c, &(terrain_erode_desc){ .mode = TERRAIN_ERODE_COLLAPSE, .x = 0.5, .y = TERRAIN_FLOOR_Y + 10,
                                                      .z = 0.5, .radius = 2 }, &q));
    cr_expect_eq(q, 4 * QPM);
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_layer out[8];
    cr_assert_eq(terrain_columns_get(c, 0, 0, out, 8), 3);
    cr_expect_eq(out[1].material, TERRAIN_SAND);
    cr_expect_eq(out[1].thickness, 4.0f);
    cr_expect_eq(out[2].thickness, 8.0f);
    terrain_columns_destroy(c);
}

/* ---- bad input ------------------------------------------------------------------------------ */

Test(terrain_brush, bad_parameters_are_refused_not_crashed_on) {
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);          /* each refusal logs a message */
    terrain_columns *c = region(0, 0, 8, 8);
    fill_flat(c, 5.0f);
    uint64_t before = region_hash(c);
    const terrain_deposit_desc bad_deposits[] = {
        { .radius = -1, .volume = 1 },   { .radius = NAN, .volume = 1 },  { .radius = 2, .volume = -1 },
        { .radius = 2, .volume = NAN },  { .x = NAN, .radius = 2 },       { .material = TERRAIN_BRUSH_ROCKS + 1, .radius = 2 },
        { .material = TERRAIN_BRUSH_BEDROCK, .radius = 2 }, { .material = 99, .radius = 2 }, { .radius = 2, .falloff = 5 },
        { .radius = 2, .volume = 1e12 },
    };
    for (size_t n = 0; n < sizeof bad_deposits / sizeof *bad_deposits; n++)
        cr_expect_not(terrain_deposit(c, &bad_deposits[n], NULL), "deposit %zu", n);
    cr_expect_not(terrain_deposit(NULL, &(terrain_deposit_desc){ .radius = 1 }, NULL));
    cr_expect_not(terrain_deposit(c, NULL, NULL));
    /* A whole cubic kilometre on one column would overflow it. */
    cr_expect_not(terrain_deposit(c, &(terrain_deposit_desc){ .x = 1.5, .z = 1.5, .radius = 0.5f, .volume = 1e8 }, NULL));
    const terrain_erode_desc bad_erosions[] = {
        { .radius = -1 }, { .radius = 2, .depth = -1 }, { .radius = 2, .rocks_ratio = 1.5f }, { .radius = 2, .rocks_ratio = NAN },
        { .radius = 2, .mode = 9 }, { .radius = 2, .mode = TERRAIN_ERODE_COLLAPSE, .y = NAN }, { .z = INFINITY, .radius = 2 },
    };
    for (size_t n = 0; n < sizeof bad_erosions / sizeof *bad_erosions; n++)
        cr_expect_not(terrain_erode(c, &bad_erosions[n], NULL), "erosion %zu", n);
    cr_expect_eq(region_hash(c), before, "nothing refused changed the region");
    core_log_set_level(level);
    terrain_columns_destroy(c);
}
