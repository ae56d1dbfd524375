/* Sculpting, sweeping (000 §4.1, §4.2) and picking. Expectations are worked out independently:
 * the region's field against terrain_field_at on the same stacks; on flat ground the field along
 * a column axis is f(y) = −y for |y| ≤ 1 (σ = 1: the cube holds 1 − y metres of ground in each of
 * its columns), so the new heights after a sculpt are roots of closed forms solved here by
 * bisection; tunnels by their geometry (distance to the skeleton, connectivity); rays by planes. */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"
#include "distance_test.h"

#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N TERRAIN_CHUNK_COLUMNS
#define Q TERRAIN_HEIGHT_QUANTUM
#define MAX_LAYERS 64

/* ---- worlds made by hand ------------------------------------------------------------------ */

/* Bedrock up to `ground` (sand on its top `sand` metres); from column step_x on (when step),
 * up to step_ground instead; column (48, 48) up to bump_top (when bump). */
typedef struct hand_world {
    double ground, sand;
    bool step, bump;
    int64_t step_x;
    double step_ground, bump_top;
} hand_world;

static void hand_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const hand_world *w = user;
    double top = w->step && x >= w->step_x ? w->step_ground : w->ground;
    if (w->bump && x == 48 && z == 48) top = w->bump_top;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(top - w->sand - TERRAIN_FLOOR_Y));
    if (w->sand > 0.0) terrain_stacks_builder_push(b, TERRAIN_SAND, (float)w->sand);
}

static terrain_stacks *hand_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, hand_column, user);
}

static terrain_world *hand_world_create(hand_world *hand) {
    return terrain_world_create(&(terrain_world_desc){ .generate = hand_generate, .generate_user = hand });
}

/* A region of chunks_x × chunks_z chunks from (cx, cz), loaded from the world. */
static terrain_columns *load_region(terrain_world *world, int64_t cx, int64_t cz, int chunks_x, int chunks_z) {
    terrain_columns *c = terrain_columns_create(&(terrain_columns_desc){
        .x = cx * N, .z = cz * N, .width = chunks_x * N, .depth = chunks_z * N });
    cr_assert_not_null(c);
    for (int k = 0; k < chunks_z; k++)
        for (int i = 0; i < chunks_x; i++) {
            terrain_chunk_coord coord = { cx + i, cz + k };
            cr_assert(terrain_columns_load(c, coord, terrain_world_stacks(world, coord)));
        }
    return c;
}

/* Material of the region at a world point (bedrock below the floor, air above the columns). */
static terrain_material region_material(const terrain_columns *c, double x, double y, double z) {
    terrain_columns_desc e = terrain_columns_extent(c);
    terrain_layer layers[MAX_LAYERS];
    int n = terrain_columns_get(c, (int)(floor(x) - (double)e.x), (int)(floor(z) - (double)e.z), layers, MAX_LAYERS);
    cr_assert(n >= 0 && n <= MAX_LAYERS, "a column of the region at (%g, %g)", x, z);
    double bottom = TERRAIN_FLOOR_Y;
    if (y < bottom) return TERRAIN_BEDROCK;
    for (int l = 0; l < n; l++) {
        bottom += layers[l].thickness;
        if (y < bottom) return layers[l].material;
    }
    return TERRAIN_AIR;
}

/* Every column's layers, to compare regions and states. */
typedef struct snapshot {
    int width, depth;
    int *count;
    terrain_layer *layers;           /* MAX_LAYERS per column */
} snapshot;

static snapshot snapshot_take(const terrain_columns *c) {
    terrain_columns_desc e = terrain_columns_extent(c);
    snapshot s = { e.width, e.depth, calloc((size_t)e.width * e.depth, sizeof(int)),
                   calloc((size_t)e.width * e.depth * MAX_LAYERS, sizeof(terrain_layer)) };
    for (int k = 0; k < e.depth; k++)
        for (int i = 0; i < e.width; i++) {
            size_t n = (size_t)k * e.width + i;
            s.count[n] = terrain_columns_get(c, i, k, s.layers + n * MAX_LAYERS, MAX_LAYERS);
            cr_assert_leq(s.count[n], MAX_LAYERS);
        }
    return s;
}

static bool snapshot_column_equal(const snapshot *a, const snapshot *b, int i, int k) {
    size_t n = (size_t)k * a->width + i;
    return a->count[n] == b->count[n] &&
           memcmp(a->layers + n * MAX_LAYERS, b->layers + n * MAX_LAYERS, (size_t)a->count[n] * sizeof(terrain_layer)) == 0;
}

static int snapshot_differences(const snapshot *a, const snapshot *b) {
    int differ = 0;
    for (int k = 0; k < a->depth; k++)
        for (int i = 0; i < a->width; i++) differ += !snapshot_column_equal(a, b, i, k);
    return differ;
}

static void snapshot_free(snapshot *s) {
    free(s->count);
    free(s->layers);
}

typedef struct masses { int64_t bedrock, sand, rocks, water; } masses;

static masses mass_of(const terrain_columns *c) {
    return (masses){ terrain_columns_mass(c, TERRAIN_BEDROCK), terrain_columns_mass(c, TERRAIN_SAND),
                     terrain_columns_mass(c, TERRAIN_ROCKS), terrain_columns_mass(c, TERRAIN_WATER) };
}

/* Root of fn in [lo, hi] (fn(lo), fn(hi) of opposite signs), by bisection. */
static double solve(double (*fn)(const void *, double), const void *user, double lo, double hi) {
    double f_lo = fn(user, lo);
    for (int step = 0; step < 100; step++) {
        double mid = 0.5 * (lo + hi), f_mid = fn(user, mid);
        if ((f_mid > 0.0) == (f_lo > 0.0)) lo = mid, f_lo = f_mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* 000 §4.1's g(r) = (1 − r²/R²)², 0 beyond R. */
static double falloff(double r, double radius) {
    double t = r * r / (radius * radius);
    return t < 1.0 ? (1.0 - t) * (1.0 - t) : 0.0;
}

/* ---- the field from the region's columns ---------------------------------------------------- */

Test(terrain_sculpt, region_field_equals_terrain_field_at_on_generated_chunks) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    terrain_columns *c = load_region(world, -1, -1, 3, 3);
    terrain__region_field field;
    terrain__region_field_init(&field, c, 0, 0, 3 * N, 3 * N);
    int solid = 0, air = 0;
    uint64_t h = 1234;
    for (int n = 0; n < 3000; n++) {
        /* Anywhere in the middle chunk and a column beyond it (the kernel reads one more), around
         * the ground there; every fourth point on a column axis, every fourth on a corner. */
        h = core_hash_u64(h + 1);
        double x = -1.5 + (double)(h % 35000) / 1000.0;
        h = core_hash_u64(h + 1);
        double z = -1.5 + (double)(h % 35000) / 1000.0;
        if (n % 4 == 1) x = floor(x) + 0.5, z = floor(z) + 0.5;
        if (n % 4 == 2) x = floor(x), z = floor(z);
        terrain_columns_desc e = terrain_columns_extent(c);
        float top = terrain_columns_top(c, (int)(floor(x) - (double)e.x), (int)(floor(z) - (double)e.z));
        h = core_hash_u64(h + 1);
        double y = top - 4.0 + (double)(h % 8000) / 1000.0;
        float reference = terrain_field_at(world, x, y, z, 0.0f);
        double value = terrain__region_field_at(&field, x, y, z);
        cr_expect(fabs(value - reference) <= 1e-5, "f at (%g, %g, %g): %.7f, terrain_field_at %.7f", x, y, z, value,
                  (double)reference);
        solid += reference > 0.0f, air += reference < 0.0f;
    }
    cr_expect_gt(solid, 300, "ground among the points");
    cr_expect_gt(air, 300, "air among the points");
    terrain__region_field_free(&field);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

/* ---- sculpting on flat ground, by hand -------------------------------------------------------- */

/* Flat ground at y = 0, target (48.5, 0, 48.5) on a column axis, R = 4, δ = R/2: n = (0, 1, 0),
 * c = (48.5, ∓2, 48.5). On the axis of a column ρ from the target, fe(y) = −y ± g(√(ρ² + (y ± 2)²))
 * and the new ground is where it crosses zero. */
typedef struct flat_case {
    double rho, radius, delta, ground;
    bool carve;
} flat_case;

static double flat_fe(const void *user, double y) {
    const flat_case *k = user;
    double f = k->ground - y;                    /* valid for |y − ground| ≤ 1 */
    double centre = k->carve ? k->ground + k->delta : k->ground - k->delta;
    double g = falloff(sqrt(k->rho * k->rho + (y - centre) * (y - centre)), k->radius);
    return k->carve ? f - g : f + g;
}

/* The new top of a column ρ from the target: the root above the ground (add) or below it
 * (carve); the ground itself where the blend does not reach. */
static double flat_expected_top(double rho, double radius, double ground, bool carve) {
    flat_case k = { rho, radius, radius / 2, ground, carve };
    if (!carve) return flat_fe(&k, ground) > 0.0 ? solve(flat_fe, &k, ground, ground + 1.0) : ground;
    return flat_fe(&k, ground) < 0.0 ? solve(flat_fe, &k, ground - 1.0, ground) : ground;
}

static void expect_flat_sculpt(bool carve) {
    hand_world hand = { .ground = 0.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 3, 3);
    const double tx = 48.5, tz = 48.5, radius = 4.0;
    int64_t changed = -1;
    cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { tx, 0.0, tz }, .radius = (float)radius,
                                                        .carve = carve }, &changed));
    int expected_changed = 0;
    for (int k = 40; k < 58; k++)
        for (int i = 40; i < 58; i++) {
            double rho = hypot(i + 0.5 - tx, k + 0.5 - tz);
            double expected = flat_expected_top(rho, radius, 0.0, carve);
            float top = terrain_columns_top(c, i, k);
            cr_expect(fabs(top - expected) <= Q, "%s: column (%d, %d), %.3f m out: top %.5f, expected %.5f",
                      carve ? "carve" : "add", i, k, rho, (double)top, expected);
            expected_changed += fabs(expected) > 0.5 * Q;
        }
    /* At the centre, by hand: h = g(h + 2), h ≈ 0.41 m (and −h for the carve). */
    double h = flat_expected_top(0.0, radius, 0.0, false);
    cr_expect(h > 0.40 && h < 0.42, "h = %g", h);
    cr_expect_float_eq(terrain_columns_top(c, 48, 48), carve ? -h : h, Q);
    /* Columns whose root lies within half a quantum of the ground may round either way. */
    cr_expect(llabs(changed - expected_changed) <= 4, "%lld columns changed, about %d expected", (long long)changed,
              expected_changed);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, add_on_flat_ground_raises_it_to_the_root_of_fe) { expect_flat_sculpt(false); }

Test(terrain_sculpt, carve_on_flat_ground_lowers_it_to_the_root_of_fe) { expect_flat_sculpt(true); }

/* Added material fills only what the field calls air: sand under the ball stays sand. */
Test(terrain_sculpt, add_keeps_the_sand_it_covers_and_carve_removes_it) {
    hand_world hand = { .ground = 0.0, .sand = 1.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 3, 3);
    masses before = mass_of(c);
    cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { 48.5, 0.0, 48.5 }, .radius = 4 }, NULL));
    masses added = mass_of(c);
    cr_expect_eq(added.sand, before.sand, "sand stays");
    cr_expect_gt(added.bedrock, before.bedrock, "bedrock is added");
    cr_expect_eq(region_material(c, 48.5, -0.5, 48.5), TERRAIN_SAND);
    cr_expect_eq(region_material(c, 48.5, 0.2, 48.5), TERRAIN_BEDROCK);
    /* Carving right beside it (on the level ground) takes sand, not bedrock. */
    cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { 60.5, 0.0, 60.5 }, .radius = 4, .carve = true },
                             NULL));
    masses carved = mass_of(c);
    cr_expect_lt(carved.sand, added.sand);
    cr_expect_eq(carved.bedrock, added.bedrock);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

/* A column whose top is not where the field's zero crosses its axis: one column of flat ground
 * at 0 raised to 0.75 m (a crest) or lowered to −0.75 m (a pit). On its axis f(y) =
 * (1·(top + 1 − y) + 3·(1 − y))/4 − 1 (weights: itself 1, the eight around it 3 in all), so the
 * field's zero is at top/4: 0.1875 m or −0.1875 m. Carving the crest flips [root, 0.1875) and
 * must take the 0.5625 m of bedrock above it too (fe < 0 there), or it would float over the
 * carved gap; adding over the pit flips (−0.1875, root] and must fill the air below it down to
 * the pit's floor. Either way the column ends as one bedrock layer, its top where the flat case
 * puts it: h ≈ 0.41 m from the field's zero (fe = f ± g, f = zero − y on the axis). */
static void expect_no_gap(double bump_top, bool carve) {
    hand_world hand = { .ground = 0.0, .bump = true, .bump_top = bump_top };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 3, 3);
    double zero = bump_top / 4.0;
    cr_expect_float_eq(terrain_field_at(world, 48.5, zero, 48.5, 0.0f), 0.0f, 1e-6f);
    cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { 48.5, zero, 48.5 }, .radius = 4, .carve = carve },
                             NULL));
    terrain_layer layers[MAX_LAYERS];
    int n = terrain_columns_get(c, 48, 48, layers, MAX_LAYERS);
    cr_expect_eq(n, 1, "one layer, no gap (%d layers)", n);
    cr_expect_eq(layers[0].material, TERRAIN_BEDROCK);
    double h = flat_expected_top(0.0, 4.0, 0.0, false);
    cr_expect_float_eq(terrain_columns_top(c, 48, 48), carve ? zero - h : zero + h, Q);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, carving_a_crest_takes_the_bedrock_above_the_field_zero_too) { expect_no_gap(0.75, true); }

Test(terrain_sculpt, adding_over_a_pit_fills_the_air_below_the_field_zero_too) { expect_no_gap(-0.75, false); }

/* Add, then carve at the same target. Both worked out by hand: the add's tops a(ρ) are the roots
 * above (as in the test before), rounded to the quantum as quanta are classified by their centres.
 * After it the field on the axis of column (i, k) is ā − y, ā the kernel-weighted mean of the
 * 3 × 3 tops (weights 1, ½, ¼; valid while every top is within 1 m of y), so the target, moved
 * onto the surface along n = (0, 1, 0) (the bump is symmetric about the centre axis), lands at
 * y = ā(centre) and the carve's centre is δ above that. The carve removes the bedrock where
 * ā − y − g(|p − c'|) ≤ 0 below the top (the column's crest above its field zero goes with it):
 * the new top is min(a, root). Whatever the code does, the result must match this model to two
 * quanta per column; and since f is a box filter of the solid, |f_after − f_before| at a point is
 * at most the largest change of a top in the 3 × 3 columns around it, which the model bounds. */
typedef struct carve_case {
    double x, z, abar, centre_y, radius;
} carve_case;

static double carve_fe(const void *user, double y) {
    const carve_case *k = user;
    double dy = y - k->centre_y;
    return k->abar - y - falloff(sqrt(k->x * k->x + k->z * k->z + dy * dy), k->radius);
}

Test(terrain_sculpt, add_then_carve_at_the_same_target_returns_nearly_the_original) {
    hand_world hand = { .ground = 0.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 3, 3);
    const double tx = 48.5, tz = 48.5, radius = 4.0, delta = 2.0;
    terrain__region_field field;
    terrain__region_field_init(&field, c, 0, 0, 3 * N, 3 * N);
    masses original = mass_of(c);
    enum { W = 15 };                              /* columns 41 … 55 around the centre 48 */
    double added[W + 2][W + 2];                   /* the model's tops after the add, with a ring */
    for (int k = 0; k < W + 2; k++)
        for (int i = 0; i < W + 2; i++) {
            double rho = hypot(40 + i + 0.5 - tx, 40 + k + 0.5 - tz);
            added[k][i] = round(flat_expected_top(rho, radius, 0.0, false) / Q) * Q;
        }
    cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { tx, 0.0, tz }, .radius = (float)radius }, NULL));
    cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { tx, 0.0, tz }, .radius = (float)radius, .carve = true },
                             NULL));
    const double w[3] = { 0.5, 1.0, 0.5 };
    double abar_centre = 0.0;
    for (int dk = -1; dk <= 1; dk++)
        for (int di = -1; di <= 1; di++) abar_centre += w[di + 1] * w[dk + 1] * added[8 + dk][8 + di] / 4.0;
    double worst_residual = 0.0;
    int64_t residual_quanta = 0, touched = 0;
    for (int k = 1; k <= W; k++)
        for (int i = 1; i <= W; i++) {
            double abar = 0.0;
            for (int dk = -1; dk <= 1; dk++)
                for (int di = -1; di <= 1; di++) abar += w[di + 1] * w[dk + 1] * added[k + dk][i + di] / 4.0;
            carve_case kc = { 40 + i + 0.5 - tx, 40 + k + 0.5 - tz, abar, abar_centre + delta, radius };
            double expected = added[k][i];
            if (carve_fe(&kc, added[k][i]) <= 0.0 && carve_fe(&kc, added[k][i] - 1.0) > 0.0)
                expected = round(solve(carve_fe, &kc, added[k][i] - 1.0, added[k][i]) / Q) * Q;
            float top = terrain_columns_top(c, 40 + i, 40 + k);
            cr_expect(fabs(top - expected) <= 2 * Q + 1e-9, "column (%d, %d): top %.5f, model %.5f", 40 + i, 40 + k,
                      (double)top, expected);
            worst_residual = fmax(worst_residual, fabs(expected));
            residual_quanta += llround(fabs(expected) / Q);
            touched += added[k][i] != 0.0 || expected != 0.0;
        }
    /* The model itself says the carve undoes the add to within a tenth of a metre (the add
     * raised the centre by h ≈ 0.41 m), and f to within that plus the two quanta above. */
    cr_expect_lt(worst_residual, 0.1, "model residual %g m", worst_residual);
    terrain__region_field after;
    terrain__region_field_init(&after, c, 0, 0, 3 * N, 3 * N);
    double tolerance = worst_residual + 2 * Q, worst = 0.0;
    for (double z = tz - 6; z <= tz + 6; z += 0.25)
        for (double x = tx - 6; x <= tx + 6; x += 0.25)
            for (double y = -1.5; y <= 1.5; y += 0.25) {
                double d = fabs(terrain__region_field_at(&after, x, y, z) - terrain__region_field_at(&field, x, y, z));
                worst = fmax(worst, d);
            }
    cr_expect_leq(worst, tolerance, "f moved by up to %g (tolerance %g)", worst, tolerance);
    /* Mass: every residual quantum of the model, and two quanta of rounding per column the model
     * says the strokes reach. */
    masses now = mass_of(c);
    cr_expect_leq(llabs(now.bedrock - original.bedrock), residual_quanta + 2 * touched, "bedrock %lld, was %lld",
                  (long long)now.bedrock, (long long)original.bedrock);
    cr_expect_eq(now.sand, original.sand);
    terrain__region_field_free(&after);
    terrain__region_field_free(&field);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

/* ---- sculpting generated ground --------------------------------------------------------------- */

/* The target found by a ray straight down at (x, z). */
static void ground_below(terrain_world *world, double x, double z, double target[3]) {
    terrain_ray_hit hit;
    cr_assert(terrain_raycast(world, (double[3]){ x, 400.0, z }, (float[3]){ 0, -1, 0 }, 1000.0f, &hit));
    memcpy(target, hit.position, sizeof hit.position);
}

Test(terrain_sculpt, columns_beyond_the_ball_stay_byte_identical_and_changed_chunks_hold_the_changes) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    for (int pass = 0; pass < 2; pass++) {
        terrain_columns *c = load_region(world, 0, 0, 3, 3);
        terrain_chunk_coord chunks[9];
        cr_expect_eq(terrain_columns_changed_chunks(c, chunks, 9, true), 0, "loading is not a change");
        snapshot before = snapshot_take(c);
        /* Near the corner of four chunks, so the ball spans several. */
        double target[3];
        ground_below(world, 64.3, 31.6, target);
        const float radius = 5.0f;
        int64_t changed = 0;
        cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { target[0], target[1], target[2] },
                                                            .radius = radius, .carve = pass == 1 }, &changed));
        snapshot after = snapshot_take(c);
        /* The centre lies within δ of the target moved onto the surface (at most ½ m). */
        double reach = radius + 0.5 * radius + 0.5;
        bool differs_in[3][3] = { { false } };
        int differ = 0;
        for (int k = 0; k < 3 * N; k++)
            for (int i = 0; i < 3 * N; i++) {
                if (snapshot_column_equal(&before, &after, i, k)) continue;
                differ++;
                differs_in[k / N][i / N] = true;
                double d = hypot(i + 0.5 - target[0], k + 0.5 - target[2]);
                cr_expect_lt(d, reach, "column (%d, %d), %g m from the target, changed", i, k, d);
            }
        cr_expect_gt(differ, 20, "the sculpt changed something");
        cr_expect_eq(changed, differ, "reported %lld changed columns, %d differ", (long long)changed, differ);
        int count = terrain_columns_changed_chunks(c, chunks, 9, true), expected = 0;
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) {
                if (!differs_in[k][i]) continue;
                cr_expect(expected < count && chunks[expected].x == i && chunks[expected].z == k,
                          "chunk (%d, %d) holds changed columns", i, k);
                expected++;
            }
        cr_expect_eq(count, expected);
        cr_expect_geq(expected, 2, "the ball spans chunks");
        /* Carving takes solid away, adding puts it there. */
        terrain_columns *fresh = load_region(world, 0, 0, 3, 3);
        masses edited = mass_of(c), original = mass_of(fresh);
        if (pass == 0) cr_expect_gt(edited.bedrock + edited.sand, original.bedrock + original.sand);
        else cr_expect_lt(edited.bedrock + edited.sand, original.bedrock + original.sand);
        terrain_columns_destroy(fresh);
        snapshot_free(&before);
        snapshot_free(&after);
        terrain_columns_destroy(c);
    }
    terrain_world_destroy(world);
}

Test(terrain_sculpt, the_same_edits_on_two_fresh_regions_give_the_same_columns) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    double target[3], second[3];
    ground_below(world, 40.7, 52.2, target);
    ground_below(world, 43.7, 50.2, second);
    snapshot results[2];
    for (int run = 0; run < 2; run++) {
        terrain_columns *c = load_region(world, 0, 0, 3, 3);
        cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { target[0], target[1], target[2] }, .radius = 6,
                                                            .offset = 0.3f }, NULL));
        cr_assert(terrain_sculpt(c, &(terrain_sculpt_desc){ .target = { second[0], second[1], second[2] },
                                                            .radius = 4, .carve = true }, NULL));
        const double points[2][3] = { { 20, target[1] - 8, 30 }, { 70, target[1] - 5, 60 } };
        cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 2.5f }, NULL));
        results[run] = snapshot_take(c);
        terrain_columns_destroy(c);
    }
    cr_expect_eq(snapshot_differences(&results[0], &results[1]), 0);
    snapshot_free(&results[0]);
    snapshot_free(&results[1]);
    terrain_world_destroy(world);
}

/* ---- sweeping ------------------------------------------------------------------------------ */

static double polyline_distance(const double p[3], const double (*points)[3], int count) {
    double best = INFINITY;
    for (int s = 0; s + 1 < count; s++) best = fmin(best, point_segment_distance(p, points[s], points[s + 1]));
    return best;
}

/* Breadth-first search over the air cells of a 0.25 m grid (box lo … hi) from the cell holding
 * `from` to the one holding `to`, through faces. */
static bool air_path(const terrain_columns *c, const double lo[3], const double hi[3], const double from[3],
                     const double to[3]) {
    const double cell = 0.25;
    int n[3];
    for (int a = 0; a < 3; a++) n[a] = (int)ceil((hi[a] - lo[a]) / cell);
    size_t total = (size_t)n[0] * n[1] * n[2];
    uint8_t *air = calloc(total, 1), *seen = calloc(total, 1);
    uint32_t *queue = malloc(total * sizeof *queue);
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++)
            for (int x = 0; x < n[0]; x++)
                air[((size_t)z * n[1] + y) * n[0] + x] =
                    region_material(c, lo[0] + (x + 0.5) * cell, lo[1] + (y + 0.5) * cell, lo[2] + (z + 0.5) * cell) ==
                    TERRAIN_AIR;
    int start[3], goal[3];
    for (int a = 0; a < 3; a++) start[a] = (int)((from[a] - lo[a]) / cell), goal[a] = (int)((to[a] - lo[a]) / cell);
    size_t s = ((size_t)start[2] * n[1] + start[1]) * n[0] + start[0];
    size_t g = ((size_t)goal[2] * n[1] + goal[1]) * n[0] + goal[0];
    cr_assert(air[s] && air[g], "both ends are air");
    size_t head = 0, tail = 0;
    queue[tail++] = (uint32_t)s, seen[s] = 1;
    bool found = false;
    while (head < tail && !found) {
        size_t at = queue[head++];
        int p[3] = { (int)(at % n[0]), (int)(at / n[0] % n[1]), (int)(at / ((size_t)n[0] * n[1])) };
        for (int d = 0; d < 6; d++) {
            int q[3] = { p[0], p[1], p[2] };
            q[d / 2] += d % 2 ? 1 : -1;
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= n[0] || q[1] >= n[1] || q[2] >= n[2]) continue;
            size_t next = ((size_t)q[2] * n[1] + q[1]) * n[0] + q[0];
            if (!air[next] || seen[next]) continue;
            seen[next] = 1, queue[tail++] = (uint32_t)next;
            found |= next == g;
        }
    }
    free(air);
    free(seen);
    free(queue);
    return found;
}

Test(terrain_sculpt, a_swept_tunnel_through_a_hill_connects_its_ends_and_carves_exactly_its_radius) {
    hand_world hand = { .ground = 40.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 4, 2);
    const double points[3][3] = { { 8.3, 10.0, 20.6 }, { 50.2, 11.0, 40.1 }, { 90.7, 12.0, 30.4 } };
    const double r = 2.0;
    int64_t changed = 0;
    masses before = mass_of(c);
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 3, .radius = (float)r }, &changed));
    cr_expect_gt(changed, 300);
    const double lo[3] = { 8.3 - r - 0.5, 10.0 - r - 0.5, 20.6 - r - 0.5 }, hi[3] = { 90.7 + r + 0.5, 12.0 + r + 0.5,
                                                                                       40.1 + r + 0.5 };
    cr_expect(air_path(c, lo, hi, points[0], points[2]), "a path of air from one end to the other");
    /* Along every column axis: air within r − 0.05 of the skeleton, untouched beyond r + 0.1. */
    int inside = 0, outside = 0;
    for (int k = (int)lo[2]; k <= (int)hi[2]; k++)
        for (int i = (int)lo[0]; i <= (int)hi[0]; i++)
            for (double y = 6.0; y <= 16.0; y += 0.01) {
                double p[3] = { i + 0.5, y, k + 0.5 };
                double d = polyline_distance(p, points, 3);
                if (d < r - 0.05) {
                    cr_expect_eq(region_material(c, p[0], y, p[2]), TERRAIN_AIR, "(%g, %g, %g), %g from the axis", p[0],
                                 y, p[2], d);
                    inside++;
                } else if (d > r + 0.1) {
                    cr_expect_eq(region_material(c, p[0], y, p[2]), TERRAIN_BEDROCK, "(%g, %g, %g), %g from the axis",
                                 p[0], y, p[2], d);
                    outside++;
                }
            }
    cr_expect_gt(inside, 10000);
    cr_expect_gt(outside, 10000);
    /* The carved volume is the tunnel's: π r² per metre of length plus the two end caps' ball.
     * The columns sample it on a 1 m grid (a midpoint rule across the tunnel, exact to the
     * quantum along it): a few tenths of a percent for a 2 m radius; 2 % allowed. */
    double length = 0.0;
    for (int s = 0; s < 2; s++) length += point_segment_distance(points[s], points[s + 1], points[s + 1]);   /* |ab| */
    const double pi = 3.14159265358979323846;
    double volume = pi * r * r * length + 4.0 / 3.0 * pi * r * r * r;
    double carved = (double)(before.bedrock - mass_of(c).bedrock) * Q;
    cr_expect(fabs(carved - volume) < 0.02 * volume, "carved %g m3, the tunnel holds about %g m3", carved, volume);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

/* ---- profile curves and projection (000 §4.2) ---------------------------------------------- */

/* Air quanta of column (i, k) (region indices) whose centres lie in [y0, y1). */
static int air_quanta(const terrain_columns *c, int i, int k, double y0, double y1) {
    int air = 0;
    for (int64_t q = (int64_t)floor((y0 - TERRAIN_FLOOR_Y) * 32); q < (int64_t)ceil((y1 - TERRAIN_FLOOR_Y) * 32); q++) {
        double y = TERRAIN_FLOOR_Y + ((double)q + 0.5) / 32;
        if (y >= y0 && y < y1) air += region_material(c, i + 0.5, y, k + 0.5) == TERRAIN_AIR;
    }
    return air;
}

Test(terrain_sculpt, a_profile_shapes_the_cross_section_by_hand) {
    /* Deep in rock (ground at 40, skeleton at y = 20 along x from 20 to 36 at z = 24.5): the field
     * is flat, so θ = 0 is up, and along +x the frame's v = t × u is +z. Profile {0.5, 1, 0.5, 1}
     * at θ = 0°, 90°, 180°, 270° with zero Catmull-Rom slopes at every point: ρ(θ) = 0.5 +
     * 0.5·(3s² − 2s³), s = θ/90° from the top. Radius 2:
     *   on the axis (k = 24): ρ = 0.5 up and down, air exactly where |dy| < 1: 64 quanta (a round
     *   sweep: |dy| < 2, 128);
     *   1 m to the side (k = 25): at dy = ±1.0, θ = 45°, ρ = 0.75, 1.414 < 1.5: air; at dy = ±1.1,
     *   θ = 42.3°, ρ = 0.727, 1.487 > 1.455: rock (a round sweep: air to ±1.73);
     *   2 m to the side (k = 26): ρ ≤ 1, |w| ≥ 2: untouched;
     *   the prism's ends are flat: x = 19.5 and 36.5 untouched (a round sweep's caps reach them). */
    hand_world hand = { .ground = 40.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 2, 2);
    const double points[2][3] = { { 20.0, 20.0, 24.5 }, { 36.0, 20.0, 24.5 } };
    const float profile[4] = { 0.5f, 1.0f, 0.5f, 1.0f };
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 2,
                                                      .profile = profile, .profile_count = 4 }, NULL));
    for (int i = 20; i <= 35; i++) {
        cr_expect_eq(air_quanta(c, i, 24, 10, 30), 64, "column (%d, 24)", i);
        cr_expect_eq(air_quanta(c, i, 24, 19, 21), 64, "column (%d, 24): the air centred on the skeleton", i);
        cr_expect_eq(region_material(c, i + 0.5, 21.0, 25.5), TERRAIN_AIR, "(%d, 25) at +1.0", i);
        cr_expect_eq(region_material(c, i + 0.5, 19.0, 25.5), TERRAIN_AIR, "(%d, 25) at -1.0", i);
        cr_expect_eq(region_material(c, i + 0.5, 21.1, 25.5), TERRAIN_BEDROCK, "(%d, 25) at +1.1", i);
        cr_expect_eq(region_material(c, i + 0.5, 18.9, 25.5), TERRAIN_BEDROCK, "(%d, 25) at -1.1", i);
        cr_expect_eq(region_material(c, i + 0.5, 21.0, 23.5), TERRAIN_AIR, "(%d, 23): the other side alike", i);
        cr_expect_eq(region_material(c, i + 0.5, 21.1, 23.5), TERRAIN_BEDROCK, "(%d, 23)", i);
        cr_expect_eq(air_quanta(c, i, 26, 10, 30), 0, "column (%d, 26)", i);
    }
    cr_expect_eq(air_quanta(c, 19, 24, 10, 30), 0, "before the flat start");
    cr_expect_eq(air_quanta(c, 36, 24, 10, 30), 0, "after the flat end");
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, a_profile_turns_with_the_surface_normal) {
    /* A wall: ground at 30 for x < 26, at 10 from x = 26 on. A crack along the wall's face (x =
     * 26, y = 20, z from 20.5 to 28.5): ∇f there is horizontal (the tops are 10 m away), so θ = 0
     * points out of the wall (+x), v = t × u = +y. Profile {0.3, 0.3, 1, 0.3}: deep at θ = 180°,
     * into the wall; radius 4. At x = 22.5 (3.5 m in) and y = 20: θ = 180°, ρ = 1, 3.5 < 4: air;
     * at x = 21.5 (4.5 m in): rock. At x = 25.5 (0.5 m in), y = 18: θ = 256°, s = 0.84 from 180°,
     * ρ = 1 − 0.7·(3s² − 2s³) = 0.35, 2.06 > 1.38: rock — an upright profile (θ = 0 up) would
     * reach 4 m down and carve it. */
    hand_world hand = { .ground = 30.0, .step = true, .step_x = 26, .step_ground = 10.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 2, 2);
    const double points[2][3] = { { 26.0, 20.0, 20.5 }, { 26.0, 20.0, 28.5 } };
    const float profile[4] = { 0.3f, 0.3f, 1.0f, 0.3f };
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 4,
                                                      .profile = profile, .profile_count = 4 }, NULL));
    for (int k = 21; k <= 27; k++) {
        cr_expect_eq(region_material(c, 22.5, 20.0, k + 0.5), TERRAIN_AIR, "3.5 m into the wall, row %d", k);
        cr_expect_eq(region_material(c, 21.5, 20.0, k + 0.5), TERRAIN_BEDROCK, "4.5 m into the wall, row %d", k);
        cr_expect_eq(region_material(c, 25.5, 20.0, k + 0.5), TERRAIN_AIR, "at the face, row %d", k);
        cr_expect_eq(region_material(c, 25.5, 18.0, k + 0.5), TERRAIN_BEDROCK, "2 m below, row %d", k);
        cr_expect_eq(region_material(c, 25.5, 22.0, k + 0.5), TERRAIN_BEDROCK, "2 m above, row %d", k);
    }
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, a_projected_graph_runs_on_the_ground) {
    /* Ground at 40. A graph drawn 20 m up (y = 60) carves nothing; projected, it lies on the
     * ground and a round sweep of radius 2 cuts a trench: on the axis (z = 20.5) the ground
     * drops to 38; 1 m aside to the quanta whose centres lie within √3 m of y = 40: 55 of
     * them ((j + ½)/32 < 1.732 for j ≤ 54), the top at 40 − 55/32. */
    hand_world hand = { .ground = 40.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 2, 2);
    const double points[2][3] = { { 8.5, 60.0, 20.5 }, { 40.5, 60.0, 20.5 } };
    int64_t changed;
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 2 }, &changed));
    cr_expect_eq(changed, 0, "in the air: nothing to carve");
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 2, .project = true },
                            &changed));
    cr_expect_gt(changed, 0);
    for (int i = 10; i <= 38; i++) {
        cr_expect_float_eq(terrain_columns_top(c, i, 20), 38.0f, 1e-6, "column (%d, 20)", i);
        cr_expect_float_eq(terrain_columns_top(c, i, 21), 40.0f - 55.0f / 32.0f, 1e-6, "column (%d, 21)", i);
        cr_expect_float_eq(terrain_columns_top(c, i, 23), 40.0f, 0.0f, "column (%d, 23)", i);
    }
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, a_branching_graph_carves_every_arm) {
    hand_world hand = { .ground = 40.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 3, 3);
    const double points[4][3] = { { 48, 20, 48 }, { 28, 20, 48 }, { 66, 23, 38 }, { 50, 14, 70 } };
    const int segments[3][2] = { { 0, 1 }, { 0, 2 }, { 3, 0 } };
    const float radii[4] = { 2.0f, 1.5f, 1.5f, 1.0f };
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .radii = radii, .point_count = 4,
                                                      .segments = segments, .segment_count = 3 }, NULL));
    for (int s = 0; s < 3; s++) {
        const double *a = points[segments[s][0]], *b = points[segments[s][1]];
        double ra = radii[segments[s][0]], rb = radii[segments[s][1]];
        for (double t = 0.0; t <= 1.0; t += 0.02) {
            double r = ra + t * (rb - ra);
            double p[3] = { a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]) };
            /* The axis of p's column passes within √½ m of p: inside for a radius of 1 or more
             * the points straight above and below p within r − 0.75 are air. */
            for (double dy = -(r - 0.75); dy <= r - 0.75; dy += 0.125)
                cr_expect_eq(region_material(c, p[0], p[1] + dy, p[2]), TERRAIN_AIR, "arm %d at t = %g, dy = %g", s, t,
                             dy);
            cr_expect_eq(region_material(c, p[0], p[1] + r + 1.0, p[2]), TERRAIN_BEDROCK, "above arm %d", s);
        }
    }
    /* Beyond the arms' ends the hill is whole. */
    cr_expect_eq(region_material(c, 24.5, 20.0, 48.5), TERRAIN_BEDROCK);
    cr_expect_eq(region_material(c, 50.5, 14.0, 74.5), TERRAIN_BEDROCK);
    cr_expect_eq(region_material(c, 70.5, 23.5, 36.5), TERRAIN_BEDROCK);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

/* The contract to the quantum: a quantum whose centre lies inside the volume is air, one whose
 * centre lies outside keeps its material. */
Test(terrain_sculpt, one_point_sweeps_a_ball_exactly_to_the_quantum) {
    hand_world hand = { .ground = 40.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 2, 2);
    const double centre[1][3] = { { 31.7, 20.2, 33.1 } };
    /* Column (35, 31)'s axis passes 4 mm inside the ball: a chord of about 0.37 m. */
    const float radius = (float)(hypot(35.5 - 31.7, 31.5 - 33.1) + 0.004);
    const double r = radius;
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = centre, .point_count = 1, .radius = radius }, NULL));
    int inside = 0, grazed = 0;
    for (int k = 25; k <= 39; k++)
        for (int i = 25; i <= 39; i++) {
            double horizontal = hypot(i + 0.5 - centre[0][0], k + 0.5 - centre[0][2]);
            int column_inside = 0;
            for (int q = (int)((14.0 - TERRAIN_FLOOR_Y) / Q); q <= (int)((26.0 - TERRAIN_FLOOR_Y) / Q); q++) {
                double y = TERRAIN_FLOOR_Y + (q + 0.5) * Q;
                double d = hypot(horizontal, y - centre[0][1]);
                if (fabs(d - r) < 1e-9) continue;
                cr_expect_eq(region_material(c, i + 0.5, y, k + 0.5), d < r ? TERRAIN_AIR : TERRAIN_BEDROCK,
                             "quantum at (%d, %g, %d), %g m from the centre", i, y, k, d);
                column_inside += d < r;
            }
            inside += column_inside;
            grazed += column_inside > 0 && column_inside < 16;
        }
    cr_expect_gt(inside, 1000);
    cr_expect_gt(grazed, 0, "some columns only just reach into the ball");
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, a_sweep_leaves_granular_material_above_it) {
    hand_world hand = { .ground = 10.0, .sand = 3.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 2, 1);
    const double points[2][3] = { { 10.5, 6.5, 16.5 }, { 50.5, 6.5, 16.5 } };
    cr_assert(terrain_sweep(c, &(terrain_sweep_desc){ .points = points, .point_count = 2, .radius = 2.0f }, NULL));
    /* Bedrock to 7, sand 7 … 10 over it: the tunnel (4.5 … 8.5 on the axis) cuts 1.5 m of sand
     * away from under the rest, which stays where it is until stabilization. */
    cr_expect_eq(region_material(c, 30.5, 6.0, 16.5), TERRAIN_AIR);
    cr_expect_eq(region_material(c, 30.5, 8.0, 16.5), TERRAIN_AIR);
    cr_expect_eq(region_material(c, 30.5, 9.0, 16.5), TERRAIN_SAND);
    cr_expect_eq(region_material(c, 30.5, 4.0, 16.5), TERRAIN_BEDROCK);
    cr_expect_float_eq(terrain_columns_top(c, 30, 16), 10.0f, 1e-6f);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
}

/* ---- picking ------------------------------------------------------------------------------- */

Test(terrain_sculpt, raycast_hits_flat_ground_where_the_plane_says) {
    hand_world hand = { .ground = 0.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_ray_hit hit;
    cr_assert(terrain_raycast(world, (double[3]){ 0.3, 10.0, 0.7 }, (float[3]){ 0, -1, 0 }, 64.0f, &hit));
    cr_expect_float_eq(hit.distance, 10.0f, 0.02f);
    cr_expect_float_eq(hit.position[1], 0.0, 0.02);
    cr_expect_float_eq(hit.normal[0], 0.0f, 1e-4f);
    cr_expect_float_eq(hit.normal[1], 1.0f, 1e-4f);
    cr_expect_float_eq(hit.normal[2], 0.0f, 1e-4f);
    cr_expect_eq(hit.material, TERRAIN_BEDROCK);
    /* Oblique, not a unit vector: (2, −1, 1.5)/|…| reaches y = 0 after 10·|d|/1 metres. */
    const float d[3] = { 2.0f, -1.0f, 1.5f };
    double length = sqrt(4.0 + 1.0 + 2.25);
    cr_assert(terrain_raycast(world, (double[3]){ -5.2, 10.0, 3.1 }, d, 64.0f, &hit));
    cr_expect_float_eq(hit.distance, 10.0 * length, 0.02);
    cr_expect_float_eq(hit.position[0], -5.2 + 20.0, 0.02);
    cr_expect_float_eq(hit.position[2], 3.1 + 15.0, 0.02);
    /* Up, or too short, misses. */
    cr_expect_not(terrain_raycast(world, (double[3]){ 0.3, 10.0, 0.7 }, (float[3]){ 0.1f, 1, 0 }, 64.0f, &hit));
    cr_expect_not(terrain_raycast(world, (double[3]){ 0.3, 10.0, 0.7 }, (float[3]){ 0, -1, 0 }, 9.5f, &hit));
    /* An origin in the ground is a hit where it is. */
    cr_assert(terrain_raycast(world, (double[3]){ 0.3, -3.0, 0.7 }, (float[3]){ 1, 0, 0 }, 64.0f, &hit));
    cr_expect_float_eq(hit.distance, 0.0f, 1e-9f);
    cr_expect_float_eq(hit.position[1], -3.0, 1e-9);
    terrain_world_destroy(world);
}

Test(terrain_sculpt, raycast_hits_the_wall_of_a_step) {
    /* Ground at 0, and at 10 from x = 40 on: a wall facing −x between y = 0 and 10. */
    hand_world hand = { .ground = 0.0, .step = true, .step_x = 40, .step_ground = 10.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_ray_hit hit;
    cr_assert(terrain_raycast(world, (double[3]){ 30.0, 5.0, 7.3 }, (float[3]){ 1, 0, 0 }, 64.0f, &hit));
    cr_expect_float_eq(hit.distance, 10.0f, 0.02f);
    cr_expect_float_eq(hit.normal[0], -1.0f, 1e-3f);
    cr_expect_float_eq(hit.normal[1], 0.0f, 1e-3f);
    cr_expect_eq(hit.material, TERRAIN_BEDROCK);
    /* A metre from the wall (f = −1 at the origin). */
    cr_assert(terrain_raycast(world, (double[3]){ 39.0, 5.0, 7.3 }, (float[3]){ 1, 0, 0 }, 5.0f, &hit));
    cr_expect_float_eq(hit.distance, 1.0f, 0.02f);
    terrain_world_destroy(world);
}

/* The first crossing by plain bisection, 40 halvings of each half-metre step: the answer the
 * secant must reach (its own steps are not the test's). */
static double crossing_by_halving(terrain_world *world, const double o[3], const double d[3], double reach) {
    const int steps = (int)ceil(reach / 0.5);
    double before = 0.0;
    for (int s = 1; s <= steps; s++) {
        const double t = s == steps ? reach : s * (reach / steps);
        if (terrain_field_at(world, o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2], 0) > 0.0f) {
            double air = before, solid = t;
            for (int h = 0; h < 40; h++) {
                const double m = 0.5 * (air + solid);
                if (terrain_field_at(world, o[0] + m * d[0], o[1] + m * d[1], o[2] + m * d[2], 0) > 0.0f) solid = m;
                else air = m;
            }
            return 0.5 * (air + solid);
        }
        before = t;
    }
    return -1.0;
}

/* Rays fanned over generated ground (hills, cliffs, overhangs of seed 3): every hit is where
 * halving finds the first crossing, to a float's step at the distance. */
Test(terrain_sculpt, raycast_finds_the_crossing_that_halving_finds) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(3) });
    const double o[3] = { 5.0, 0.0, 5.0 };
    double eye[3] = { o[0], terrain_world_top(world, o[0], o[2]) + 6.0, o[2] };
    int hits = 0;
    for (int i = 0; i < 48; i++) {
        const float yaw = 0.1309f * (float)i, pitch = -0.05f - 0.02f * (float)(i % 12);
        const float dir[3] = { cosf(yaw) * cosf(pitch), sinf(pitch), sinf(yaw) * cosf(pitch) };
        const double d[3] = { dir[0], dir[1], dir[2] };
        const double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double unit[3] = { d[0] / length, d[1] / length, d[2] / length };
        terrain_ray_hit hit;
        const bool hitting = terrain_raycast(world, eye, dir, 64.0f, &hit);
        const double expected = crossing_by_halving(world, eye, unit, 64.0);
        cr_expect_eq(hitting, expected >= 0.0, "ray %d: %s, halving %s", i, hitting ? "hits" : "misses",
                     expected >= 0.0 ? "hits" : "misses");
        if (!hitting || expected < 0.0) continue;
        hits++;
        cr_expect_float_eq((double)hit.distance, expected, 1e-5 + 4e-7 * expected, "ray %d: %.7f m, halving %.7f m", i,
                           (double)hit.distance, expected);
    }
    cr_expect_gt(hits, 24, "most rays meet the ground (%d of 48)", hits);
    terrain_world_destroy(world);
}

/* ---- bad input ------------------------------------------------------------------------------ */

Test(terrain_sculpt, bad_parameters_are_refused_and_change_nothing) {
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);            /* each refusal logs a message */
    hand_world hand = { .ground = 0.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_columns *c = load_region(world, 0, 0, 2, 2);
    snapshot before = snapshot_take(c);
    masses mass = mass_of(c);
    const terrain_sculpt_desc bad_sculpts[] = {
        { .target = { NAN, 0, 32 }, .radius = 3 },          { .target = { 32, INFINITY, 32 }, .radius = 3 },
        { .target = { 32, 0, 32 }, .radius = 0 },            { .target = { 32, 0, 32 }, .radius = -1 },
        { .target = { 32, 0, 32 }, .radius = NAN },          { .target = { 32, 0, 32 }, .radius = 32.5f },
        { .target = { 32, 0, 32 }, .radius = 3, .offset = -0.1f }, { .target = { 32, 0, 32 }, .radius = 3, .offset = 1.5f },
        { .target = { 32, 0, 32 }, .radius = 3, .offset = NAN },
        { .target = { 32, 0, 32 }, .radius = 3, .material = TERRAIN_BRUSH_ROCKS + 1 },
        { .target = { 32, 0, 32 }, .radius = 3, .material = TERRAIN_BRUSH_ROCKS },
        { .target = { 32, 0, 32 }, .radius = 3, .material = 99 },
        { .target = { 4, 0, 32 }, .radius = 3 },             /* R + δ + 2 = 6.5 m: over the border */
        { .target = { 32, 0, 60 }, .radius = 3 },
        { .target = { 32, 0, 32 }, .radius = 30 },           /* 47 m of margin in a 64 m region */
        { .target = { 32, 10, 32 }, .radius = 3 },           /* no surface within ½ m */
        { .target = { 32, -1e7, 32 }, .radius = 3 },
    };
    for (size_t n = 0; n < CORE_COUNTOF(bad_sculpts); n++) {
        int64_t changed = 7;
        cr_expect_not(terrain_sculpt(c, &bad_sculpts[n], &changed), "sculpt %zu", n);
        cr_expect_eq(changed, 0);
    }
    cr_expect_not(terrain_sculpt(NULL, &bad_sculpts[0], NULL));
    cr_expect_not(terrain_sculpt(c, NULL, NULL));

    const double points[3][3] = { { 20, -5, 20 }, { 40, -5, 40 }, { 30, NAN, 30 } };
    const float bad_radii[2] = { 2.0f, 0.0f };
    const int out_of_range[1][2] = { { 0, 2 } }, negative[1][2] = { { -1, 1 } };
    const double near_border[2][3] = { { 2, -5, 20 }, { 40, -5, 40 } };
    const float bad_profile[65] = { -1.0f, NAN, 5.0f, 1.0f, 1.0f };
    const terrain_sweep_desc bad_sweeps[] = {
        { .points = NULL, .point_count = 2, .radius = 2 },
        { .points = points, .point_count = 0, .radius = 2 },
        { .points = points, .point_count = 4097, .radius = 2 },
        { .points = points, .point_count = 3, .radius = 2 },            /* a NaN point */
        { .points = points, .point_count = 2, .radius = 0 },
        { .points = points, .point_count = 2, .radius = -2 },
        { .points = points, .point_count = 2, .radius = NAN },
        { .points = points, .point_count = 2, .radius = 33 },
        { .points = points, .point_count = 2, .radii = bad_radii },
        { .points = points, .point_count = 2, .radius = 2, .segments = out_of_range, .segment_count = 1 },
        { .points = points, .point_count = 2, .radius = 2, .segments = negative, .segment_count = 1 },
        { .points = points, .point_count = 2, .radius = 2, .segments = negative, .segment_count = 0 },
        { .points = near_border, .point_count = 2, .radius = 2 },       /* 4 m of margin, 2 m to the edge */
        { .points = points, .point_count = 2, .radius = 2, .profile = bad_profile, .profile_count = 2 },
        { .points = points, .point_count = 2, .radius = 2, .profile = bad_profile, .profile_count = 65 },
        { .points = points, .point_count = 2, .radius = 2, .profile = bad_profile, .profile_count = 3 },  /* −1 */
        { .points = points, .point_count = 2, .radius = 2, .profile = bad_profile + 1, .profile_count = 3 }, /* NaN */
        { .points = points, .point_count = 2, .radius = 2, .profile = bad_profile + 2, .profile_count = 3 }, /* 5 */
    };
    for (size_t n = 0; n < CORE_COUNTOF(bad_sweeps); n++) {
        int64_t changed = 7;
        cr_expect_not(terrain_sweep(c, &bad_sweeps[n], &changed), "sweep %zu", n);
        cr_expect_eq(changed, 0);
    }
    cr_expect_not(terrain_sweep(NULL, &bad_sweeps[4], NULL));
    cr_expect_not(terrain_sweep(c, NULL, NULL));

    snapshot after = snapshot_take(c);
    cr_expect_eq(snapshot_differences(&before, &after), 0, "nothing changed");
    masses now = mass_of(c);
    cr_expect(now.bedrock == mass.bedrock && now.sand == mass.sand && now.rocks == mass.rocks && now.water == mass.water);
    terrain_chunk_coord chunks[4];
    cr_expect_eq(terrain_columns_changed_chunks(c, chunks, 4, false), 0);

    terrain_ray_hit hit;
    const double origin[3] = { 0.3, 10.0, 0.7 };
    cr_expect_not(terrain_raycast(world, origin, (float[3]){ NAN, -1, 0 }, 64.0f, &hit));
    cr_expect_not(terrain_raycast(world, origin, (float[3]){ 0, 0, 0 }, 64.0f, &hit));
    cr_expect_not(terrain_raycast(world, origin, (float[3]){ 0, -1, 0 }, 0.0f, &hit));
    cr_expect_not(terrain_raycast(world, origin, (float[3]){ 0, -1, 0 }, NAN, &hit));
    cr_expect_not(terrain_raycast(world, (double[3]){ 0, NAN, 0 }, (float[3]){ 0, -1, 0 }, 64.0f, &hit));
    cr_expect_not(terrain_raycast(NULL, origin, (float[3]){ 0, -1, 0 }, 64.0f, &hit));
    cr_expect_not(terrain_raycast(world, NULL, (float[3]){ 0, -1, 0 }, 64.0f, &hit));

    snapshot_free(&before);
    snapshot_free(&after);
    terrain_columns_destroy(c);
    terrain_world_destroy(world);
    core_log_set_level(level);
}
