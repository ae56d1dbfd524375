/* Editing: columns regions and stabilization by the angle of repose (000 §3.4); the brushes
 * (§4.3, §4.4) are tested in test_terrain_brush.c.
 * Expectations come from the paper's formulas worked by hand, from invariants (mass of every
 * material, slopes at rest) and from equalities between runs that must agree (threads, splits,
 * budgets), never from printed output. */
#include "terrain_columns_test.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <math.h>
#include <string.h>

#define N TERRAIN_CHUNK_COLUMNS
#define Q TERRAIN_HEIGHT_QUANTUM

static const double PI = 3.14159265358979323846;

/* ---- helpers (more in terrain_columns_test.h) ------------------------------------------ */

/* Bedrock, then sand and rocks on top (metres). */
static void set_pile(terrain_columns *c, int i, int k, float bedrock, float sand, float rocks) {
    terrain_layer layers[3] = { { TERRAIN_BEDROCK, bedrock }, { TERRAIN_SAND, sand }, { TERRAIN_ROCKS, rocks } };
    cr_assert(terrain_columns_set(c, i, k, layers, 3));
}

/* The top of the column's highest bedrock, of the sand and of the rocks on it (the sand surface
 * and the ground), in quanta above the floor. */
static void surfaces(const terrain_columns *c, int i, int k, int64_t *base_out, int64_t *sand_top, int64_t *ground) {
    terrain_layer layers[64];
    int n = terrain_columns_get(c, i, k, layers, 64);
    int64_t top = 0, base = 0, sand = 0, rocks = 0;
    for (int l = 0; l < n; l++) {
        int64_t q = llroundf(layers[l].thickness * QPM);
        if (layers[l].material == TERRAIN_BEDROCK) base = top + q, sand = rocks = 0;
        if (layers[l].material == TERRAIN_SAND) sand += q;
        if (layers[l].material == TERRAIN_ROCKS) rocks += q;
        top += q;
    }
    *base_out = base;
    *sand_top = base + sand;
    *ground = base + sand + rocks;
}

/* The most any slope may exceed the angle of repose (metres over the distance d), checked on
 * both surfaces: the sand surface where a column holds sand, the ground where it holds rocks.
 * Returns the worst excess found (≤ 0 when every slope is at rest). */
static double worst_excess(const terrain_columns *c, double sand_deg, double rocks_deg) {
    terrain_columns_desc e = terrain_columns_extent(c);
    double tan_s = tan(sand_deg * PI / 180.0), tan_r = tan(rocks_deg * PI / 180.0), worst = -1e9;
    for (int k = 0; k < e.depth; k++) {
        for (int i = 0; i < e.width; i++) {
            int64_t base, hs, hr;
            surfaces(c, i, k, &base, &hs, &hr);
            bool has_sand = hs > base, has_rocks = hr > hs;
            for (int dz = -1; dz <= 1; dz++) {
                for (int dx = -1; dx <= 1; dx++) {
                    int ni = i + dx, nk = k + dz;
                    if ((!dx && !dz) || ni < 0 || nk < 0 || ni >= e.width || nk >= e.depth) continue;
                    int64_t nb, ns, nr;
                    surfaces(c, ni, nk, &nb, &ns, &nr);
                    double d = dx && dz ? sqrt(2.0) : 1.0;
                    if (has_sand) worst = fmax(worst, (double)(hs - ns) / QPM - d * tan_s);
                    if (has_rocks) worst = fmax(worst, (double)(hr - nr) / QPM - d * tan_r);
                }
            }
        }
    }
    return worst;
}

/* Column (i, k) of `a` equals (i + di, k + dk) of `b`, layer for layer. */
static bool same_column(const terrain_columns *a, int i, int k, const terrain_columns *b, int bi, int bk) {
    terrain_layer x[64], y[64];
    int n = terrain_columns_get(a, i, k, x, 64), m = terrain_columns_get(b, bi, bk, y, 64);
    return n == m && memcmp(x, y, (size_t)CORE_MIN(n, 64) * sizeof *x) == 0;
}

/* ---- sorting (000 §3.4, Figure 6) ----------------------------------------------------- */

Test(terrain_stabilize, runs_between_bedrock_are_merged_and_sorted_sand_rocks_air) {
    /* A lone column (a 1 × 1 region: its neighbours are walls, nothing flows). Run 1, between
     * bedrock layers: rocks 1, sand 1, air 2, sand 1 → sand 2, rocks 1, air 2. The top run:
     * air 1, water 1, sand 0.5 → sand 0.5, water 1 (top air implicit). */
    terrain_columns *c = region(0, 0, 1, 1);
    terrain_layer in[] = { { TERRAIN_BEDROCK, 1 }, { TERRAIN_ROCKS, 1 }, { TERRAIN_SAND, 1 }, { TERRAIN_AIR, 2 },
                           { TERRAIN_SAND, 1 },    { TERRAIN_BEDROCK, 1 }, { TERRAIN_AIR, 1 }, { TERRAIN_WATER, 1 },
                           { TERRAIN_SAND, 0.5f } };
    cr_assert(terrain_columns_set(c, 0, 0, in, 9));
    masses before = mass_of(c);
    terrain_stabilize_result r = stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect(r.converged);
    cr_expect_eq(r.moved, 0);
    terrain_layer out[16];
    terrain_layer want[] = { { TERRAIN_BEDROCK, 1 }, { TERRAIN_SAND, 2 },    { TERRAIN_ROCKS, 1 }, { TERRAIN_AIR, 2 },
                             { TERRAIN_BEDROCK, 1 }, { TERRAIN_SAND, 0.5f }, { TERRAIN_WATER, 1 } };
    cr_assert_eq(terrain_columns_get(c, 0, 0, out, 16), 7);
    for (int l = 0; l < 7; l++) {
        cr_expect_eq(out[l].material, want[l].material, "layer %d", l);
        cr_expect_eq(out[l].thickness, want[l].thickness, "layer %d", l);
    }
    expect_same_mass(before, mass_of(c));
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, sand_over_a_cave_roof_stays_and_sand_without_a_roof_falls) {
    /* Bedrock 2, air 3, bedrock 1, sand 1: the roof holds the sand. Bedrock 2, air 3, sand 1:
     * nothing holds it, it falls to the cave floor (sorted: sand, then air, dropped on top). */
    terrain_columns *c = region(0, 0, 1, 1);
    terrain_layer roof[] = { { TERRAIN_BEDROCK, 2 }, { TERRAIN_AIR, 3 }, { TERRAIN_BEDROCK, 1 }, { TERRAIN_SAND, 1 } };
    cr_assert(terrain_columns_set(c, 0, 0, roof, 4));
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_layer out[8];
    cr_assert_eq(terrain_columns_get(c, 0, 0, out, 8), 4);
    cr_expect_eq(out[3].material, TERRAIN_SAND);
    cr_expect_float_eq(terrain_columns_top(c, 0, 0), TERRAIN_FLOOR_Y + 7.0f, 0.0f);

    terrain_layer floating[] = { { TERRAIN_BEDROCK, 2 }, { TERRAIN_AIR, 3 }, { TERRAIN_SAND, 1 } };
    cr_assert(terrain_columns_set(c, 0, 0, floating, 3));
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_assert_eq(terrain_columns_get(c, 0, 0, out, 8), 2);
    cr_expect_eq(out[1].material, TERRAIN_SAND);
    cr_expect_eq(out[1].thickness, 1.0f);
    cr_expect_float_eq(terrain_columns_top(c, 0, 0), TERRAIN_FLOOR_Y + 3.0f, 0.0f);
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, custom_materials_hold_like_bedrock) {
    /* A game's own material (after the built-in ones) is stable: runs end at it. Bedrock 1, air 1,
     * sand 1, custom 1, rocks 1, sand 1 → bedrock 1, sand 1, air 1, custom 1, sand 1, rocks 1. */
    terrain_columns *c = region(0, 0, 1, 1);
    terrain_material custom = TERRAIN_MATERIAL_BUILTIN_COUNT;
    terrain_layer in[] = { { TERRAIN_BEDROCK, 1 }, { TERRAIN_AIR, 1 }, { TERRAIN_SAND, 1 }, { custom, 1 },
                           { TERRAIN_ROCKS, 1 },   { TERRAIN_SAND, 1 } };
    cr_assert(terrain_columns_set(c, 0, 0, in, 6));
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_layer out[8];
    const terrain_material want[] = { TERRAIN_BEDROCK, TERRAIN_SAND, TERRAIN_AIR, custom, TERRAIN_SAND, TERRAIN_ROCKS };
    cr_assert_eq(terrain_columns_get(c, 0, 0, out, 8), 6);
    for (int l = 0; l < 6; l++) {
        cr_expect_eq(out[l].material, want[l], "layer %d", l);
        cr_expect_eq(out[l].thickness, 1.0f, "layer %d", l);
    }
    terrain_columns_destroy(c);
}

/* ---- one iteration by hand (000 §3.4) ------------------------------------------------- */

/* Sand of height 2 m on one column of a flat 3 × 3 field. Its drop to every neighbour is 2 m;
 * the excess is 2 − tan 33° = 1.3506 m to the four sides and 2 − √2·tan 33° = 1.0816 m to the
 * corners (Δh̃_i = Δh_i − s·tan α), Σ = 9.7287 m over k = 8 neighbours. The column gives
 * a = min(step, 2 m held, ⌈Σ/(k + 1)⌉ = ⌈1.0810 m⌉ = 35 quanta), Δz_i = a·Δh̃_i/Σ. */
static void one_step_case(float step, const int64_t want_side[4], const int64_t want_corner[4]) {
    terrain_columns *c = region(0, 0, 3, 3);
    fill_flat(c, 10.0f);
    set_pile(c, 1, 1, 10.0f, 2.0f, 0.0f);
    masses before = mass_of(c);
    terrain_stabilize_result r = stabilize(c, &(terrain_stabilize_desc){ .step = step, .max_iterations = 1 }, NULL);
    cr_expect_eq(r.iterations, 1);
    const int side[4][2] = { { 1, 0 }, { 0, 1 }, { 2, 1 }, { 1, 2 } }, corner[4][2] = { { 0, 0 }, { 2, 0 }, { 0, 2 }, { 2, 2 } };
    int64_t given = 0;
    for (int n = 0; n < 4; n++) {
        cr_expect_eq(column_quanta(c, side[n][0], side[n][1], TERRAIN_SAND), want_side[n], "side %d", n);
        cr_expect_eq(column_quanta(c, corner[n][0], corner[n][1], TERRAIN_SAND), want_corner[n], "corner %d", n);
        given += want_side[n] + want_corner[n];
    }
    cr_expect_eq(column_quanta(c, 1, 1, TERRAIN_SAND), 64 - given);
    cr_expect_eq(r.moved, given);
    expect_same_mass(before, mass_of(c));
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, one_iteration_on_three_by_three_matches_the_formula) {
    /* Step 2 m: a = 35 quanta. Sides 35·1.3506/9.7287 = 4.859, corners 35·1.0816/9.7287 =
     * 3.891: 4·4 + 4·3 = 28, the 7 left over go to the largest remainders, the corners (.891)
     * then three sides (.859, equal: the lowest direction index first — directions go z-major
     * from (−1, −1): side (1, 0) is 1, (0, 1) is 3, (2, 1) is 4, (1, 2) is 6). The other
     * columns of the iteration then hold at most 5 quanta over their lowest neighbour, less
     * than tan 33° = 20.8 quanta, and the centre (29 quanta) is higher than them all: nothing
     * else moves. */
    const int64_t side[4] = { 5, 5, 5, 4 }, corner[4] = { 4, 4, 4, 4 };
    one_step_case(2.0f, side, corner);
}

Test(terrain_stabilize, one_iteration_with_a_small_step_matches_the_formula) {
    /* Step 1/4 m = 8 quanta: sides 8·1.3506/9.7287 = 1.1106, corners 0.8894: floors 4·1 + 0 = 4,
     * the 4 left over to the corners (.889 > .111): every neighbour gets 1 quantum. */
    const int64_t side[4] = { 1, 1, 1, 1 }, corner[4] = { 1, 1, 1, 1 };
    one_step_case(0.25f, side, corner);
}

/* ---- at rest ------------------------------------------------------------------------------ */

Test(terrain_stabilize, tall_sand_column_spreads_to_the_angle_of_repose) {
    /* 20 m of sand on one column of a flat 41 × 41 field: 640 quanta·column = 20 m³. At rest no
     * slope exceeds tan 33° (the check reads the layers back, independently of the code's fixed
     * point); the pile is then a cone of about V = π r³ tan α / 3: r = 3.1 m, h = 2.0 m — it must
     * be well below 20 m and within a few metres of the column. */
    terrain_columns *c = region(0, 0, 41, 41);
    fill_flat(c, 100.0f);
    set_pile(c, 20, 20, 100.0f, 20.0f, 0.0f);
    masses before = mass_of(c);
    terrain_stabilize_result r = stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect(r.converged);
    expect_same_mass(before, mass_of(c));
    cr_expect_leq(worst_excess(c, 33.0, 42.0), 0.0);
    float peak = terrain_columns_top(c, 20, 20) - (TERRAIN_FLOOR_Y + 100.0f);
    cr_expect(peak > 1.0f && peak < 4.0f, "peak %g m", (double)peak);
    for (int k = 0; k < 41; k++)
        for (int i = 0; i < 41; i++)
            if ((i - 20) * (i - 20) + (k - 20) * (k - 20) > 8 * 8)
                cr_expect_eq(column_quanta(c, i, k, TERRAIN_SAND), 0, "sand at (%d, %d)", i, k);
    /* Converged means stable: another call finds nothing to do. */
    terrain_stabilize_result again = stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect(again.converged);
    cr_expect_eq(again.moved, 0);
    terrain_columns_destroy(c);
}

/* ---- piles on cave floors (000 §3.4: "all material layers located between two stable bedrock
 * layers") ----------------------------------------------------------------------------------- */

/* The sand of column (i, k) between its 10 m floor and its roof, after checking that the column
 * is still floor 10 m, a 6 m cave (sand and air) and a 5 m roof: the roof never moves. */
static int64_t cave_sand(const terrain_columns *c, int i, int k) {
    terrain_layer layers[8];
    int n = terrain_columns_get(c, i, k, layers, 8);
    cr_assert(n >= 3 && n <= 4, "column (%d, %d): %d layers", i, k, n);
    cr_expect_eq(layers[0].material, TERRAIN_BEDROCK);
    cr_expect_eq(layers[0].thickness, 10.0f, "column (%d, %d): the floor", i, k);
    cr_expect_eq(layers[n - 1].material, TERRAIN_BEDROCK);
    cr_expect_eq(layers[n - 1].thickness, 5.0f, "column (%d, %d): the roof", i, k);
    int64_t sand = 0, cave = 0;
    for (int l = 1; l < n - 1; l++) {
        cr_expect(layers[l].material == TERRAIN_SAND || layers[l].material == TERRAIN_AIR);
        if (layers[l].material == TERRAIN_SAND) sand += llroundf(layers[l].thickness * QPM);
        cave += llroundf(layers[l].thickness * QPM);
    }
    cr_expect_eq(cave, 6 * QPM, "column (%d, %d): the roof starts 16 m up", i, k);
    return sand;
}

Test(terrain_stabilize, a_sand_heap_on_a_cave_floor_spreads_under_the_roof) {
    /* Every column: bedrock 10 m, a 6 m cave, a 5 m roof. One column's cave is full of sand to
     * the roof (6 m = 192 quanta·column): it spreads over the floor until no slope of the sand
     * surface exceeds d·tan 33° (checked from the layers read back, in metres), conserving the
     * sand; the roof and the column tops stay. At rest it is a cone of V = π r³ tan α / 3:
     * r ≈ 2.1 m, h ≈ 1.4 m — far below the 6 m it started at, and within a few metres. */
    terrain_columns *c = region(0, 0, 25, 25);
    terrain_layer cave[3] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_AIR, 6.0f }, { TERRAIN_BEDROCK, 5.0f } };
    for (int k = 0; k < 25; k++)
        for (int i = 0; i < 25; i++) cr_assert(terrain_columns_set(c, i, k, cave, 3));
    terrain_layer heap[3] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_SAND, 6.0f }, { TERRAIN_BEDROCK, 5.0f } };
    cr_assert(terrain_columns_set(c, 12, 12, heap, 3));
    masses before = mass_of(c);
    terrain_stabilize_result r = stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect(r.converged);
    cr_expect_gt(r.moved, 0);
    expect_same_mass(before, mass_of(c));
    double tan_s = tan(33.0 * PI / 180.0), worst = -1e9;
    int64_t total = 0;
    for (int k = 0; k < 25; k++)
        for (int i = 0; i < 25; i++) {
            int64_t h = cave_sand(c, i, k);
            total += h;
            cr_expect_float_eq(terrain_columns_top(c, i, k), TERRAIN_FLOOR_Y + 21.0f, 0.0f);
            if ((i - 12) * (i - 12) + (k - 12) * (k - 12) > 6 * 6)
                cr_expect_eq(h, 0, "sand at (%d, %d)", i, k);
            if (!h) continue;
            for (int dz = -1; dz <= 1; dz++)
                for (int dx = -1; dx <= 1; dx++)
                    if ((dx || dz) && i + dx >= 0 && k + dz >= 0 && i + dx < 25 && k + dz < 25) {
                        double d = dx && dz ? sqrt(2.0) : 1.0;
                        worst = fmax(worst, (double)(h - cave_sand(c, i + dx, k + dz)) / QPM - d * tan_s);
                    }
        }
    cr_expect_eq(total, 192);
    cr_expect_leq(worst, 0.0, "a slope exceeds tan 33 degrees by %g m", worst);
    double peak = (double)cave_sand(c, 12, 12) / QPM;
    cr_expect(peak > 0.8 && peak < 2.5, "peak %g m", peak);
    cr_expect(stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL).moved == 0, "at rest");
    /* Stopping after every iteration and going on gives the same bytes, as for top piles. */
    terrain_columns *steps = region(0, 0, 25, 25);
    for (int k = 0; k < 25; k++)
        for (int i = 0; i < 25; i++) cr_assert(terrain_columns_set(steps, i, k, cave, 3));
    cr_assert(terrain_columns_set(steps, 12, 12, heap, 3));
    int calls = 0;
    while (!stabilize(steps, &(terrain_stabilize_desc){ .max_iterations = 1 }, NULL).converged && calls < 1000) calls++;
    cr_expect_gt(calls, 1);
    cr_expect_eq(region_hash(steps), region_hash(c));
    terrain_columns_destroy(steps);
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, a_cave_pile_flows_out_of_the_mouth_and_not_into_rock) {
    /* A 1 × 5 strip: columns 0 … 2 a cave (floor 10 m, 2 m of air, 5 m roof), column 3 open
     * ground at 10 m (the mouth), column 4 solid rock up to 20 m. 1 m of sand on column 2 (at the
     * mouth) slides out: column 3's open pile takes its share; the rock at column 4 takes none.
     * Rocks at rest by tan 42°, sand by tan 33° (one metre apart: 0.65 m). */
    terrain_columns *c = region(0, 0, 5, 1);
    terrain_layer cave[3] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_AIR, 2.0f }, { TERRAIN_BEDROCK, 5.0f } };
    terrain_layer pile[4] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_SAND, 1.0f }, { TERRAIN_AIR, 1.0f },
                              { TERRAIN_BEDROCK, 5.0f } };
    terrain_layer open = { TERRAIN_BEDROCK, 10.0f }, rock = { TERRAIN_BEDROCK, 20.0f };
    cr_assert(terrain_columns_set(c, 0, 0, cave, 3));
    cr_assert(terrain_columns_set(c, 1, 0, cave, 3));
    cr_assert(terrain_columns_set(c, 2, 0, pile, 4));
    cr_assert(terrain_columns_set(c, 3, 0, &open, 1));
    cr_assert(terrain_columns_set(c, 4, 0, &rock, 1));
    masses before = mass_of(c);
    cr_expect(stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL).converged);
    expect_same_mass(before, mass_of(c));
    int64_t s[5];
    for (int i = 0; i < 5; i++) s[i] = column_quanta(c, i, 0, TERRAIN_SAND);
    cr_expect_eq(s[0] + s[1] + s[2] + s[3], 32);
    cr_expect_eq(s[4], 0, "rock takes nothing");
    cr_expect_gt(s[3], 0, "the open ground outside the mouth took some");
    cr_expect_gt(s[1], 0, "the cave floor inside took some");
    for (int i = 0; i < 3; i++)
        cr_expect_leq((double)llabs(s[i] - s[i + 1]) / QPM, tan(33.0 * PI / 180.0) + 1e-9, "slope %d-%d", i, i + 1);
    cr_expect_float_eq(terrain_columns_top(c, 4, 0), TERRAIN_FLOOR_Y + 20.0f, 0.0f);
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, tolerance_and_angles_bound_the_slopes_at_rest) {
    terrain_columns *c = region(0, 0, 31, 31);
    fill_flat(c, 50.0f);
    set_pile(c, 15, 15, 50.0f, 6.0f, 6.0f);
    set_pile(c, 10, 12, 50.0f, 0.0f, 9.0f);
    masses before = mass_of(c);
    terrain_stabilize_desc p = { .sand_angle = 30.0f, .rocks_angle = 45.0f, .tolerance = 0.25f };
    cr_expect(stabilize(c, &p, NULL).converged);
    expect_same_mass(before, mass_of(c));
    cr_expect_leq(worst_excess(c, 30.0, 45.0), 0.25);
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, rocks_rest_steeper_than_sand) {
    /* The same volume of rocks and of sand, each on its own flat field: rocks (42°) end in a
     * higher, narrower pile than sand (33°). */
    terrain_columns *sand = region(0, 0, 31, 31), *rocks = region(0, 0, 31, 31);
    fill_flat(sand, 10.0f);
    fill_flat(rocks, 10.0f);
    set_pile(sand, 15, 15, 10.0f, 16.0f, 0.0f);
    set_pile(rocks, 15, 15, 10.0f, 0.0f, 16.0f);
    stabilize(sand, &(terrain_stabilize_desc){ 0 }, NULL);
    stabilize(rocks, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect_gt(terrain_columns_top(rocks, 15, 15), terrain_columns_top(sand, 15, 15));
    cr_expect_leq(worst_excess(sand, 33.0, 42.0), 0.0);
    cr_expect_leq(worst_excess(rocks, 33.0, 42.0), 0.0);
    cr_expect_eq(terrain_columns_mass(rocks, TERRAIN_ROCKS), 16 * QPM);
    terrain_columns_destroy(sand);
    terrain_columns_destroy(rocks);
}

/* ---- determinism: threads, splits, budgets ----------------------------------------------- */

/* A region with piles and generated ground, edited the same way every time. */
static terrain_columns *edited_region(int64_t x, int64_t z, int size) {
    terrain_columns *c = region(x, z, size, size);
    load_generated(c, 3);
    terrain_columns_touch(c, 0, 0, size, size);   /* stabilize the generated chunks too */
    for (int n = 0; n < 6; n++) {
        double px = (double)x + 8 + n * (size - 16) / 5.0, pz = (double)z + size / 2.0 + (n % 2 ? 9 : -9);
        cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .material = n % 2 ? TERRAIN_BRUSH_ROCKS : TERRAIN_BRUSH_SAND,
                                                              .x = px, .z = pz, .radius = 6, .volume = 400 }, NULL));
    }
    return c;
}

Test(terrain_stabilize, result_is_the_same_for_one_two_and_four_threads) {
    /* 128² columns, all marked: passes big enough to be split into jobs. */
    terrain_columns *one = edited_region(0, 0, 128), *two = edited_region(0, 0, 128), *four = edited_region(0, 0, 128);
    job_system *jobs2 = job_system_create(&(job_system_desc){ .threads = 2 });
    job_system *jobs4 = job_system_create(&(job_system_desc){ .threads = 4 });
    terrain_stabilize_result r1 = stabilize(one, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_stabilize_result r2 = stabilize(two, &(terrain_stabilize_desc){ 0 }, jobs2);
    terrain_stabilize_result r4 = stabilize(four, &(terrain_stabilize_desc){ 0 }, jobs4);
    cr_expect(r1.converged && r2.converged && r4.converged);
    cr_expect_gt(r1.moved, 0);
    cr_expect_eq(r1.iterations, r2.iterations);
    cr_expect_eq(r1.iterations, r4.iterations);
    cr_expect_eq(r1.moved, r2.moved);
    cr_expect_eq(r1.moved, r4.moved);
    cr_expect_eq(region_hash(one), region_hash(two));
    cr_expect_eq(region_hash(one), region_hash(four));
    job_system_destroy(jobs2);
    job_system_destroy(jobs4);
    terrain_columns_destroy(one);
    terrain_columns_destroy(two);
    terrain_columns_destroy(four);
}

Test(terrain_stabilize, stopping_on_a_budget_and_continuing_gives_the_same_bytes) {
    terrain_columns *whole = edited_region(0, 0, 64), *steps = edited_region(0, 0, 64);
    terrain_stabilize_result r = stabilize(whole, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_assert(r.converged);
    int calls = 0, iterations = 0;
    int64_t moved = 0;
    terrain_stabilize_result s;
    do {
        s = stabilize(steps, &(terrain_stabilize_desc){ .max_iterations = 7 }, NULL);
        iterations += s.iterations;
        moved += s.moved;
        calls++;
    } while (!s.converged && calls < 10000);
    cr_expect_gt(calls, 2);
    cr_expect_eq(moved, r.moved);
    cr_expect_eq(region_hash(whole), region_hash(steps));
    /* A time budget stops anywhere between passes, and still continues to the same bytes. */
    terrain_columns *timed = edited_region(0, 0, 64);
    calls = 0;
    do {
        s = stabilize(timed, &(terrain_stabilize_desc){ .budget_ns = 200000 }, NULL);
        calls++;
    } while (!s.converged && calls < 100000);
    cr_expect_eq(region_hash(whole), region_hash(timed));
    terrain_columns_destroy(whole);
    terrain_columns_destroy(steps);
    terrain_columns_destroy(timed);
}

/* Copies region `big`'s columns into chunk-sized regions through stacks (as the engine would
 * load them), marking the same columns for stabilization. */
static terrain_columns *chunk_region(const terrain_columns *big, terrain_chunk_coord coord) {
    terrain_columns *c = region(coord.x * N, coord.z * N, N, N);
    terrain_stacks *s = terrain_columns_to_stacks(big, coord);
    cr_assert_not_null(s);
    cr_assert(terrain_columns_load(c, coord, s));
    terrain_stacks_destroy(s);
    return c;
}

static void expect_regions_equal_big(terrain_columns *big, terrain_columns **chunks, int count) {
    for (int r = 0; r < count; r++) {
        terrain_columns_desc e = terrain_columns_extent(chunks[r]);
        terrain_columns_desc b = terrain_columns_extent(big);
        int bad = 0;
        for (int k = 0; k < N; k++)
            for (int i = 0; i < N; i++)
                bad += !same_column(chunks[r], i, k, big, (int)(e.x - b.x) + i, (int)(e.z - b.z) + k);
        cr_expect_eq(bad, 0, "region %d: %d columns differ", r, bad);
    }
}

Test(terrain_stabilize, two_by_two_chunk_regions_equal_one_big_region) {
    /* Generated ground, all of it marked, and piles across the borders at (32, 32). */
    terrain_columns *big = edited_region(0, 0, 64);
    cr_assert(terrain_deposit(big, &(terrain_deposit_desc){ .x = 32, .z = 32, .radius = 10, .volume = 900 }, NULL));
    terrain_columns *chunks[4];
    for (int n = 0; n < 4; n++) {
        chunks[n] = chunk_region(big, (terrain_chunk_coord){ n % 2, n / 2 });
        terrain_columns_touch(chunks[n], 0, 0, N, N);
    }
    terrain_columns_touch(big, 0, 0, 64, 64);
    terrain_stabilize_result rb = stabilize(big, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_stabilize_result rs;
    cr_assert(terrain_stabilize_regions(chunks, 4, &(terrain_stabilize_desc){ 0 }, NULL, &rs));
    cr_expect(rb.converged && rs.converged);
    cr_expect_gt(rb.moved, 0);
    cr_expect_eq(rb.iterations, rs.iterations);
    cr_expect_eq(rb.moved, rs.moved);
    expect_regions_equal_big(big, chunks, 4);
    for (int n = 0; n < 4; n++) terrain_columns_destroy(chunks[n]);
    terrain_columns_destroy(big);
}

Test(terrain_stabilize, a_cave_heap_over_a_chunk_corner_spreads_as_in_one_big_region) {
    /* A 6 m cave (floor 10 m, roof 5 m) under 64 × 64 columns, a 6 m sand heap on the four
     * columns around the corner (32, 32) of four chunks, and a 5 m one on a chunk's side: split
     * into chunk regions, the heaps spread into every region they touch, and the bytes, the
     * iterations and the volume moved equal one big region's. */
    terrain_columns *big = region(0, 0, 64, 64);
    terrain_layer cave[3] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_AIR, 6.0f }, { TERRAIN_BEDROCK, 5.0f } };
    terrain_layer heap[3] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_SAND, 6.0f }, { TERRAIN_BEDROCK, 5.0f } };
    terrain_layer side[4] = { { TERRAIN_BEDROCK, 10.0f }, { TERRAIN_SAND, 5.0f }, { TERRAIN_AIR, 1.0f },
                              { TERRAIN_BEDROCK, 5.0f } };
    for (int k = 0; k < 64; k++)
        for (int i = 0; i < 64; i++) cr_assert(terrain_columns_set(big, i, k, cave, 3));
    for (int n = 0; n < 4; n++) cr_assert(terrain_columns_set(big, 31 + n % 2, 31 + n / 2, heap, 3));
    cr_assert(terrain_columns_set(big, 12, 31, side, 4));
    terrain_columns *chunks[4];
    for (int n = 0; n < 4; n++) {
        chunks[n] = chunk_region(big, (terrain_chunk_coord){ n % 2, n / 2 });
        terrain_columns_touch(chunks[n], 0, 0, N, N);
    }
    terrain_columns_touch(big, 0, 0, 64, 64);
    masses before = mass_of(big);
    terrain_stabilize_result rb = stabilize(big, &(terrain_stabilize_desc){ 0 }, NULL);
    terrain_stabilize_result rs;
    cr_assert(terrain_stabilize_regions(chunks, 4, &(terrain_stabilize_desc){ 0 }, NULL, &rs));
    cr_expect(rb.converged && rs.converged);
    cr_expect_gt(rb.moved, 0);
    cr_expect_eq(rb.iterations, rs.iterations);
    cr_expect_eq(rb.moved, rs.moved);
    expect_regions_equal_big(big, chunks, 4);
    expect_same_mass(before, mass_of(big));
    for (int n = 0; n < 4; n++) {
        int64_t sand = terrain_columns_mass(chunks[n], TERRAIN_SAND);
        cr_expect_gt(sand, 4 * 192 / 8, "region %d holds part of the heap (%lld)", n, (long long)sand);
    }
    cr_expect_gt(column_quanta(big, 12, 32, TERRAIN_SAND), 0, "the side heap crossed into chunk (0, 1)");
    for (int n = 0; n < 4; n++) terrain_columns_destroy(chunks[n]);
    terrain_columns_destroy(big);
}

/* Flat bedrock with a step and a cave, pure functions of the column, for regions made on demand. */
static void waking_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, x + z > 100 ? 205.0f : 200.0f);
    if ((x / 7 + z / 5) % 4 == 0) {           /* an overhang: air, then a thin roof */
        terrain_stacks_builder_push(b, TERRAIN_AIR, 3.0f);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 1.0f);
    }
}

Test(terrain_stabilize, a_pile_wakes_the_chunks_it_spreads_into) {
    /* A pile near the corner of chunk (1, 1) of a 3 × 3-chunk world. One big region of all nine
     * chunks (walls beyond, never reached) against a set that starts with chunk (1, 1) alone and
     * adds the chunks the stabilizer asks for: the same bytes. */
    terrain_columns *big = region(0, 0, 96, 96);
    for (int n = 0; n < 9; n++) {
        terrain_stacks *s = terrain_stacks_from_columns((terrain_chunk_coord){ n % 3, n / 3 }, waking_column, NULL);
        terrain_columns_load(big, (terrain_chunk_coord){ n % 3, n / 3 }, s);
        terrain_stacks_destroy(s);
    }
    terrain_deposit_desc pile = { .x = 60, .z = 58, .radius = 3, .volume = 1500 };
    cr_assert(terrain_deposit(big, &pile, NULL));
    terrain_stabilize_result rb = stabilize(big, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_assert(rb.converged);

    terrain_columns *set[9];
    int count = 0;
    terrain_stacks *s = terrain_stacks_from_columns((terrain_chunk_coord){ 1, 1 }, waking_column, NULL);
    set[count] = region(N, N, N, N);
    terrain_columns_load(set[count++], (terrain_chunk_coord){ 1, 1 }, s);
    terrain_stacks_destroy(s);
    cr_assert(terrain_deposit(set[0], &pile, NULL));
    terrain_stabilize_desc wake = { .edge = TERRAIN_EDGE_WAKE };
    terrain_stabilize_result r;
    int calls = 0, woken = 0;
    do {
        cr_assert(terrain_stabilize_regions(set, count, &wake, NULL, &r));
        for (int w = 0; w < r.woken_count && w < TERRAIN_STABILIZE_MAX_WOKEN; w++) {
            terrain_chunk_coord c = r.woken[w];
            cr_assert(c.x >= 0 && c.x < 3 && c.z >= 0 && c.z < 3, "woke (%lld, %lld)", (long long)c.x, (long long)c.z);
            s = terrain_stacks_from_columns(c, waking_column, NULL);
            set[count] = region(c.x * N, c.z * N, N, N);
            terrain_columns_load(set[count++], c, s);
            terrain_stacks_destroy(s);
            woken++;
        }
    } while (!r.converged && ++calls < 1000);
    cr_expect(r.converged);
    cr_expect_gt(woken, 0, "the pile spreads over the chunk's border");
    expect_regions_equal_big(big, set, count);
    /* Chunks never woken hold nothing the big region changed. */
    for (int n = 0; n < 9; n++) {
        bool present = false;
        for (int r2 = 0; r2 < count; r2++) {
            terrain_columns_desc e = terrain_columns_extent(set[r2]);
            present |= e.x == (n % 3) * N && e.z == (n / 3) * N;
        }
        if (present) continue;
        for (int k = 0; k < N; k++)
            for (int i = 0; i < N; i++)
                cr_expect_eq(column_quanta(big, (n % 3) * N + i, (n / 3) * N + k, TERRAIN_SAND), 0);
    }
    for (int n = 0; n < count; n++) terrain_columns_destroy(set[n]);
    terrain_columns_destroy(big);
}

Test(terrain_stabilize, walls_report_the_regions_material_reaches) {
    /* A region of one chunk with a big pile at its east border: material piles against the wall
     * and the chunk to the east is named. */
    terrain_columns *c = region(N, 0, N, N);
    fill_flat(c, 10.0f);
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 2 * N - 1, .z = 16, .radius = 2, .volume = 300 }, NULL));
    terrain_stabilize_result r = stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    cr_expect(r.converged);
    bool east = false;
    for (int w = 0; w < r.woken_count && w < TERRAIN_STABILIZE_MAX_WOKEN; w++)
        east |= r.woken[w].x == 2 && r.woken[w].z == 0;
    cr_expect(east);
    terrain_columns_destroy(c);
}

/* ---- stacks round trip and changed chunks ----------------------------------------------------- */

Test(terrain_stabilize, stacks_round_trip_byte_for_byte) {
    terrain_generation_desc params = terrain_generation_defaults(11);
    terrain_columns *c = region(-48, 16, 96, 64);            /* chunks (−2 … 1, 0 … 2), partly covered */
    for (int cz = 0; cz < 3; cz++)
        for (int cx = -2; cx < 2; cx++) {
            terrain_stacks *s = terrain_generate_chunk(&params, (terrain_chunk_coord){ cx, cz });
            cr_assert(terrain_columns_load(c, (terrain_chunk_coord){ cx, cz }, s));
            terrain_stacks_destroy(s);
        }
    /* Chunks (−1, 1) and (0, 1) lie inside the region. */
    for (int cx = -1; cx <= 0; cx++) {
        terrain_chunk_coord coord = { cx, 1 };
        terrain_stacks *original = terrain_generate_chunk(&params, coord), *back = terrain_columns_to_stacks(c, coord);
        cr_assert_not_null(back);
        cr_expect_eq(terrain_stacks_hash(back), terrain_stacks_hash(original));
        cr_expect_eq(terrain_stacks_bytes(back), terrain_stacks_bytes(original));
        cr_expect_eq(memcmp(back, original, terrain_stacks_bytes(original)), 0);
        terrain_stacks_destroy(original);
        terrain_stacks_destroy(back);
    }
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);
    cr_expect_null(terrain_columns_to_stacks(c, (terrain_chunk_coord){ -2, 1 }));   /* half outside */
    core_log_set_level(level);
    terrain_columns_destroy(c);
}

static void odd_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    /* Out of 000 §3.4's order on purpose: rocks under sand, sand over air, water under sand. */
    (void)user;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.0f + (float)(x % 3));
    if ((x + z) % 2) terrain_stacks_builder_push(b, TERRAIN_ROCKS, 1.0f);
    terrain_stacks_builder_push(b, TERRAIN_SAND, 0.5f);
    if (z % 3 == 0) terrain_stacks_builder_push(b, TERRAIN_AIR, 2.0f);
    if (z % 4 == 1) terrain_stacks_builder_push(b, TERRAIN_WATER, 1.0f);
    if (x % 5 == 0) terrain_stacks_builder_push(b, TERRAIN_SAND, 0.25f);
}

Test(terrain_stabilize, unsorted_columns_round_trip_until_stabilized) {
    terrain_stacks *original = terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, odd_column, NULL);
    terrain_columns *c = region(0, 0, N, N);
    cr_assert(terrain_columns_load(c, (terrain_chunk_coord){ 0, 0 }, original));
    terrain_chunk_coord changed[4];
    cr_expect_eq(terrain_columns_changed_chunks(c, changed, 4, false), 0, "loading is not an edit");
    terrain_stacks *back = terrain_columns_to_stacks(c, (terrain_chunk_coord){ 0, 0 });
    cr_expect_eq(terrain_stacks_hash(back), terrain_stacks_hash(original));
    cr_expect_eq(memcmp(back, original, terrain_stacks_bytes(original)), 0);
    terrain_stacks_destroy(back);
    masses before = mass_of(c);
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    expect_same_mass(before, mass_of(c));
    cr_expect_eq(terrain_columns_changed_chunks(c, changed, 4, true), 1, "sorting changed the chunk");
    cr_expect_eq(terrain_columns_changed_chunks(c, changed, 4, false), 0, "cleared");
    terrain_stacks_destroy(original);
    terrain_columns_destroy(c);
}

Test(terrain_stabilize, changed_chunks_name_the_edited_and_the_reached_chunks) {
    terrain_columns *c = region(0, 0, 3 * N, N);             /* chunks (0, 0) … (2, 0) */
    fill_flat(c, 10.0f);
    terrain_chunk_coord changed[8];
    terrain_columns_changed_chunks(c, changed, 8, true);     /* the fill was an edit */
    cr_assert(terrain_deposit(c, &(terrain_deposit_desc){ .x = 34, .z = 16, .radius = 1.5f, .volume = 200 }, NULL));
    cr_assert_eq(terrain_columns_changed_chunks(c, changed, 8, false), 1);
    cr_expect(changed[0].x == 1 && changed[0].z == 0);
    stabilize(c, &(terrain_stabilize_desc){ 0 }, NULL);
    /* 200 m³ at 33° spread over a radius of about 6.6 m: across x = 32 into chunk 0, not to 64. */
    cr_assert_eq(terrain_columns_changed_chunks(c, changed, 8, true), 2);
    cr_expect(changed[0].x == 0 && changed[1].x == 1);
    terrain_columns_destroy(c);
}

/* ---- bad input ------------------------------------------------------------------------------ */

Test(terrain_stabilize, bad_parameters_are_refused_not_crashed_on) {
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);          /* each refusal logs a message */
    cr_expect_null(terrain_columns_create(&(terrain_columns_desc){ .width = 0, .depth = 4 }));
    cr_expect_null(terrain_columns_create(&(terrain_columns_desc){ .width = 5000, .depth = 4 }));
    cr_expect_null(terrain_columns_create(NULL));
    terrain_columns *c = region(0, 0, 8, 8);
    fill_flat(c, 5.0f);
    uint64_t before = region_hash(c);
    terrain_stabilize_result r;
    const terrain_stabilize_desc bad[] = {
        { .sand_angle = -5 }, { .sand_angle = 90 }, { .rocks_angle = NAN }, { .step = -1 }, { .step = NAN },
        { .step = 1e9f },     { .tolerance = -1 },  { .tolerance = NAN },  { .max_iterations = -2 }, { .edge = 7 },
    };
    for (size_t n = 0; n < sizeof bad / sizeof *bad; n++)
        cr_expect_not(terrain_stabilize_region(c, &bad[n], NULL, &r), "parameters %zu", n);
    cr_expect_not(terrain_stabilize_region(c, NULL, NULL, &r));
    cr_expect_not(terrain_stabilize_regions(NULL, 1, &(terrain_stabilize_desc){ 0 }, NULL, &r));
    cr_expect_not(terrain_stabilize_regions(&c, 0, &(terrain_stabilize_desc){ 0 }, NULL, &r));
    terrain_columns *pair[2] = { c, c };
    cr_expect_not(terrain_stabilize_regions(pair, 2, &(terrain_stabilize_desc){ 0 }, NULL, &r), "twice at one place");
    terrain_columns *odd = region(3, 0, 8, 8), *small = region(8, 0, 4, 4);
    pair[1] = odd;
    cr_expect_not(terrain_stabilize_regions(pair, 2, &(terrain_stabilize_desc){ 0 }, NULL, &r), "off the grid");
    pair[1] = small;
    cr_expect_not(terrain_stabilize_regions(pair, 2, &(terrain_stabilize_desc){ 0 }, NULL, &r), "sizes differ");
    terrain_layer bad_layer = { TERRAIN_SAND, -1.0f }, nan_layer = { TERRAIN_SAND, NAN }, odd_material = { 42, 1.0f };
    cr_expect_not(terrain_columns_set(c, 0, 0, &bad_layer, 1));
    cr_expect_not(terrain_columns_set(c, 0, 0, &nan_layer, 1));
    cr_expect_not(terrain_columns_set(c, 0, 0, &odd_material, 1));
    cr_expect_not(terrain_columns_set(c, 8, 0, &bad_layer, 0));
    cr_expect_eq(terrain_columns_get(c, -1, 0, NULL, 0), -1);
    cr_expect_eq(region_hash(c), before, "nothing refused changed the region");
    core_log_set_level(level);
    terrain_columns_destroy(odd);
    terrain_columns_destroy(small);
    terrain_columns_destroy(c);
}
