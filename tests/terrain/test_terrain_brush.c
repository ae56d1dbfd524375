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
            /* Every other deposit at a height some metres under the ground there: into a cave
             * where one is, on the top elsewhere; a cave that fills takes less (never more). */
            bool at_height = (h >> 50) & 1;
            double y = terrain_columns_top(c, (int)x, (int)z) - (double)((h >> 52) % 24);
            cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .material = brush, .x = x, .z = z,
                                                                  .radius = radius, .volume = volume,
                                                                  .at_height = at_height, .y = y }, &q));
            if (at_height) cr_expect(q >= 0 && q <= llround(volume * QPM));
            else cr_expect_eq(q, llround(volume * QPM));
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
                                                               .depth = 3.0f, .rocks_ratio = rho,
                                                               .at_height = (h >> 50) & 1 }, &q));
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

/* ---- at the hit point's height (000 §4.3, §4.4) ------------------------------------------- */

/* A synthetic cave in every column: bedrock floor up to 10 m, `cave` metres of air, a bedrock
 * roof 5 m thick above it. */
static void fill_cave(terrain_columns *c, float cave) {
    terrain_columns_desc e = terrain_columns_extent(c);
    terrain_layer layers[3] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_AIR, cave }, { TERRAIN_BEDROCK, 5.0f } };
    for (int k = 0; k < e.depth; k++)
        for (int i = 0; i < e.width; i++) cr_assert(terrain_columns_set(c, i, k, layers, 3));
}

/* Column (i, k) is floor 10 m, then `sand` quanta of sand (if any), then air, then the 5 m roof
 * from 10 + cave metres up: the roof exactly where it was. */
static void expect_cave_column(const terrain_columns *c, int i, int k, float cave, int64_t sand) {
    terrain_layer layers[8];
    int n = terrain_columns_get(c, i, k, layers, 8);
    int64_t air = llroundf(cave * QPM) - sand;
    terrain_layer want[4] = { { TERRAIN_BEDROCK, 10.0f } };
    int m = 1;
    if (sand) want[m++] = (terrain_layer){ TERRAIN_SAND, (float)sand / QPM };
    if (air) want[m++] = (terrain_layer){ TERRAIN_AIR, (float)air / QPM };
    want[m++] = (terrain_layer){ TERRAIN_BEDROCK, 5.0f };
    cr_assert_eq(n, m, "column (%d, %d): %d layers, %d expected", i, k, n, m);
    for (int l = 0; l < m; l++) {
        cr_expect_eq(layers[l].material, want[l].material, "column (%d, %d) layer %d", i, k, l);
        cr_expect_float_eq(layers[l].thickness, want[l].thickness, 1e-6, "column (%d, %d) layer %d", i, k, l);
    }
}

Test(terrain_brush, deposit_at_a_height_in_a_cave_lands_on_its_floor_under_the_roof) {
    /* The hit lies on the cave floor (10 m above the world's floor). 8 m³ = 256 quanta·column on
     * the columns within 3 m of (10.5, 10.5), each on the cave's floor: the roof (16 … 21 m) and
     * the column tops stay where they were; without at_height the sand would lie on the roof. */
    terrain_columns *c = region(0, 0, 21, 21);
    fill_cave(c, 6.0f);
    masses before = mass_of(c);
    int64_t q;
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 10.5, .z = 10.5, .radius = 3, .volume = 8,
                                                          .at_height = true, .y = TERRAIN_FLOOR_Y + 10.0 }, &q));
    cr_expect_eq(q, 256);
    before.sand += 256;
    expect_same_mass(before, mass_of(c));
    int64_t on_floor = 0;
    for (int k = 0; k < 21; k++)
        for (int i = 0; i < 21; i++) {
            int64_t sand = column_quanta(c, i, k, TERRAIN_SAND);
            int r2 = (i - 10) * (i - 10) + (k - 10) * (k - 10);
            if (r2 >= 9) cr_expect_eq(sand, 0, "(%d, %d) is outside the brush", i, k);
            expect_cave_column(c, i, k, 6.0f, sand);
            cr_expect_float_eq(terrain_columns_top(c, i, k), TERRAIN_FLOOR_Y + 21.0f, 0.0f);
            on_floor += sand;
        }
    cr_expect_eq(on_floor, 256);
    cr_expect_gt(column_quanta(c, 10, 10, TERRAIN_SAND), 0);
    /* The same hit height a little inside the floor (a sloped floor's hit) still means the cave;
     * one over the roof means the roof's top, as without at_height. */
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 3.5, .z = 3.5, .radius = 1, .volume = 1,
                                                          .at_height = true, .y = TERRAIN_FLOOR_Y + 9.7 }, &q));
    cr_expect_eq(q, 32);
    expect_cave_column(c, 3, 3, 6.0f, 32);
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 17.5, .z = 17.5, .radius = 1, .volume = 1,
                                                          .at_height = true, .y = TERRAIN_FLOOR_Y + 21.2 }, &q));
    cr_expect_eq(q, 32);
    cr_expect_float_eq(terrain_columns_top(c, 17, 17), TERRAIN_FLOOR_Y + 22.0f, 0.0f);
    cr_expect_eq(column_quanta(c, 17, 17, TERRAIN_SAND), 32);
    expect_cave_column(c, 16, 17, 6.0f, 0);
    terrain_columns_destroy(c);
}

Test(terrain_brush, deposit_at_a_height_stops_at_the_roof) {
    /* A cave of ½ m (16 quanta) under five columns (flat brush of radius 1.2): 5 m³ asks for 32
     * quanta a column, 16 fit; the region gains exactly the 80 reported. */
    terrain_columns *c = region(0, 0, 11, 11);
    fill_cave(c, 0.5f);
    int64_t q;
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 5.5, .z = 5.5, .radius = 1.2f, .volume = 5,
                                                          .falloff = TERRAIN_FALLOFF_FLAT, .at_height = true,
                                                          .y = TERRAIN_FLOOR_Y + 10.25 }, &q));
    cr_expect_eq(q, 80);
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_SAND), 80);
    const int at[5][2] = { { 5, 5 }, { 4, 5 }, { 6, 5 }, { 5, 4 }, { 5, 6 } };
    for (int n = 0; n < 5; n++) expect_cave_column(c, at[n][0], at[n][1], 0.5f, 16);
    terrain_columns_destroy(c);
}

Test(terrain_brush, deposit_at_a_height_on_open_ground_is_the_deposit_on_top) {
    /* Open ground: the only space is the top, so at_height changes nothing (same bytes). Water on
     * the ground too: it is displaced alike. */
    terrain_columns *top = region(0, 0, 16, 16), *at = region(0, 0, 16, 16);
    terrain_layer wet[2] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_WATER, 0.5f } };
    for (int k = 0; k < 16; k++)
        for (int i = 0; i < 16; i++) {
            cr_assert(terrain_columns_set(top, i, k, wet, i < 8 ? 2 : 1));
            cr_assert(terrain_columns_set(at, i, k, wet, i < 8 ? 2 : 1));
        }
    int64_t q_top, q_at;
    cr_assert(terrain_deposit(top, &(terrain_deposit_desc){ .x = 8, .z = 8, .radius = 5, .volume = 30 }, &q_top));
    cr_assert(terrain_deposit(at, &(terrain_deposit_desc){ .x = 8, .z = 8, .radius = 5, .volume = 30, .at_height = true,
                                                           .y = TERRAIN_FLOOR_Y + 10.0 }, &q_at));
    cr_expect_eq(q_top, 960);
    cr_expect_eq(q_at, 960);
    cr_expect_eq(region_hash(top), region_hash(at));
    cr_assert(terrain_erode(top, &(terrain_erode_desc){ .x = 4, .z = 4, .radius = 3, .depth = 1, .rocks_ratio = 0.5f }, NULL));
    cr_assert(terrain_erode(at, &(terrain_erode_desc){ .x = 4, .z = 4, .radius = 3, .depth = 1, .rocks_ratio = 0.5f,
                                                       .at_height = true, .y = TERRAIN_FLOOR_Y + 10.0 }, NULL));
    cr_expect_eq(region_hash(top), region_hash(at));
    terrain_columns_destroy(top);
    terrain_columns_destroy(at);
}

Test(terrain_brush, surface_erosion_at_a_height_wears_the_cave_floor_not_the_roof) {
    /* Flat brush of radius 1.2 (five columns), 2 m = 64 quanta, ρ = 0.25 → 16 rocks, 48 sand on
     * the cave floor; the roof keeps its 5 m and the cave its 6 m of air above the rubble (the
     * floor went down by as much as the rubble is thick). Without at_height the roof wears. */
    terrain_columns *c = region(0, 0, 11, 11), *roof = region(0, 0, 11, 11);
    fill_cave(c, 6.0f);
    fill_cave(roof, 6.0f);
    int64_t q;
    terrain_erode_desc desc = { .x = 5.5, .z = 5.5, .radius = 1.2f, .depth = 2, .rocks_ratio = 0.25f,
                                .falloff = TERRAIN_FALLOFF_FLAT, .at_height = true, .y = TERRAIN_FLOOR_Y + 10.0 };
    cr_assert(terrain_erode(c, &desc, &q));
    cr_expect_eq(q, 5 * 64);
    terrain_layer want[5] = { { TERRAIN_BEDROCK, 8.0f }, { TERRAIN_SAND, 1.5f }, { TERRAIN_ROCKS, 0.5f },
                              { TERRAIN_AIR, 6.0f }, { TERRAIN_BEDROCK, 5.0f } };
    terrain_layer layers[8];
    cr_assert_eq(terrain_columns_get(c, 5, 4, layers, 8), 5);
    for (int l = 0; l < 5; l++) {
        cr_expect_eq(layers[l].material, want[l].material, "layer %d", l);
        cr_expect_float_eq(layers[l].thickness, want[l].thickness, 1e-6, "layer %d", l);
    }
    expect_cave_column(c, 4, 4, 6.0f, 0);
    desc.at_height = false;
    cr_assert(terrain_erode(roof, &desc, &q));
    cr_expect_eq(column_quanta(roof, 5, 4, TERRAIN_BEDROCK), (10 + 5 - 2) * QPM);
    expect_cave_column(roof, 4, 4, 6.0f, 0);
    cr_assert_eq(terrain_columns_get(roof, 5, 4, layers, 8), 5);
    cr_expect_float_eq(layers[2].thickness, 3.0f, 1e-6, "the roof wore down to 3 m");
    terrain_columns_destroy(c);
    terrain_columns_destroy(roof);
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
        { .radius = 2, .volume = 1e12 },    { .radius = 2, .volume = 1, .at_height = true, .y = NAN },
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
        { .radius = 2, .depth = 1, .at_height = true, .y = INFINITY },
    };
    for (size_t n = 0; n < sizeof bad_erosions / sizeof *bad_erosions; n++)
        cr_expect_not(terrain_erode(c, &bad_erosions[n], NULL), "erosion %zu", n);
    cr_expect_eq(region_hash(c), before, "nothing refused changed the region");
    core_log_set_level(level);
    terrain_columns_destroy(c);
}
