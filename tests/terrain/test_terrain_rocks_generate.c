/* Rock layers from the generator (terrain_generate.c, "Rocks"): talus at the feet of walls,
 * scree on slopes too steep for sand, stones at lakes' waterlines. Each pile is ordered sand,
 * rocks, water, air (000 §3.4); the share of stony columns is sane; talus lies where walls
 * rise, scree only where the ground falls faster than sand holds; and the stabilizer (rocks
 * hold 42°) leaves generated rocks where they are. */
#include "../engine/test.h"
#include "terrain/terrain.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define N TERRAIN_CHUNK_COLUMNS
#define Q TERRAIN_HEIGHT_QUANTUM

/* A column's rock layer on its top run and the ground under it (top of sand or bedrock). */
typedef struct column_rocks {
    float rocks, ground;
    bool ordered;          /* rocks only right over sand or bedrock, with water or nothing above */
} column_rocks;

static column_rocks column_read(const terrain_stacks *s, int i, int k) {
    terrain_layer layers[256];
    int count = terrain_stacks_column(s, i, k, layers, 256);
    column_rocks c = { .ordered = true };
    float y = TERRAIN_FLOOR_Y;
    for (int l = 0; l < count && l < 256; l++) {
        if (layers[l].material == TERRAIN_ROCKS) {
            c.rocks += layers[l].thickness;
            bool below = l > 0 && (layers[l - 1].material == TERRAIN_SAND || layers[l - 1].material == TERRAIN_BEDROCK);
            bool above = l + 1 == count || (layers[l + 1].material == TERRAIN_WATER && l + 2 == count);
            c.ordered &= below && above;
        }
        y += layers[l].thickness;
    }
    c.ground = terrain_stacks_top(s, i, k) - c.rocks;
    return c;
}

/* The steepest rise and fall (metres a metre) from column (i, k) of the chunk to its 8
 * neighbours' ground (rocks left out), 1 ≤ i, k ≤ N − 2. */
static void slopes(const terrain_stacks *s, int i, int k, float *rise, float *fall) {
    float here = column_read(s, i, k).ground;
    *rise = *fall = 0.0f;
    for (int dz = -1; dz <= 1; dz++)
        for (int dx = -1; dx <= 1; dx++) {
            if (!dx && !dz) continue;
            float step = (column_read(s, i + dx, k + dz).ground - here) / sqrtf((float)(dx * dx + dz * dz));
            *rise = fmaxf(*rise, step);
            *fall = fmaxf(*fall, -step);
        }
}

typedef struct rock_survey {
    int columns, stony, stony_half_metre, disordered;
    double mass;
} rock_survey;

static rock_survey survey(const terrain_generation_desc *p, int64_t x0, int64_t z0, int side) {
    rock_survey r = { 0 };
    for (int64_t cz = z0; cz < z0 + side; cz++)
        for (int64_t cx = x0; cx < x0 + side; cx++) {
            terrain_stacks *s = terrain_generate_chunk(p, (terrain_chunk_coord){ cx, cz });
            for (int k = 0; k < N; k++)
                for (int i = 0; i < N; i++) {
                    column_rocks c = column_read(s, i, k);
                    r.columns++;
                    r.stony += c.rocks > 0.0f;
                    r.stony_half_metre += c.rocks >= 0.5f;
                    r.disordered += !c.ordered;
                    r.mass += c.rocks;
                    /* Thicknesses are whole quanta (the builder's rule, checked here for rocks). */
                    cr_expect_float_eq(c.rocks / Q, roundf(c.rocks / Q), 1e-3, "rocks %g", (double)c.rocks);
                }
            terrain_stacks_destroy(s);
        }
    return r;
}

Test(terrain_rocks_generate, the_default_world_has_rock_layers_in_a_sane_share) {
    /* 8 × 8 chunks around the origin (256 m square) of seeds 1 and 2. Measured when written:
     * seed 1 5.3 % of columns with 0.5 m or more (10.1 % with any), seed 2 4.0 % (8.9 %). */
    for (uint64_t seed = 1; seed <= 2; seed++) {
        terrain_generation_desc p = terrain_generation_defaults(seed);
        rock_survey r = survey(&p, -4, -4, 8);
        double share = (double)r.stony_half_metre / r.columns;
        cr_log_info("seed %llu: %.2f %% of columns hold 0.5 m of rocks or more, %.2f %% any, %.2f m on average",
                    (unsigned long long)seed, 100.0 * share, 100.0 * r.stony / r.columns, r.mass / r.stony);
        cr_expect_geq(share, 0.02, "seed %llu: %.2f %%", (unsigned long long)seed, 100.0 * share);
        cr_expect_leq((double)r.stony / r.columns, 0.25, "seed %llu: %d of %d", (unsigned long long)seed, r.stony,
                      r.columns);
        cr_expect_eq(r.disordered, 0, "seed %llu: %d columns with rocks out of order", (unsigned long long)seed,
                     r.disordered);
    }
}

Test(terrain_rocks_generate, off_when_every_depth_is_negative) {
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.talus_depth = p.scree_depth = p.lake_rocks_depth = -1.0f;
    rock_survey r = survey(&p, 1, 0, 2);
    cr_expect_eq(r.stony, 0);
}

/* ---- talus and scree where the ground says -------------------------------------------------- */

Test(terrain_rocks_generate, talus_lies_at_the_feet_of_walls) {
    /* Talus only. A foot: a neighbour at least 3 m higher a metre (a wall: twice the generator's
     * 1.5 m, where it puts the full depth), no neighbour more than 0.7 m a metre lower (the
     * foot is not itself on a steep slope), above the sea. Most hold half a metre or more (the
     * rest: rocks thinned where the ground beyond falls fast, or a wall too narrow). */
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.scree_depth = p.lake_rocks_depth = -1.0f;
    int feet = 0, stony_feet = 0, stony = 0, stony_near_wall = 0;
    for (int64_t cz = 0; cz < 4; cz++)
        for (int64_t cx = 1; cx < 5; cx++) {
            terrain_stacks *s = terrain_generate_chunk(&p, (terrain_chunk_coord){ cx, cz });
            for (int k = 4; k < N - 4; k++)
                for (int i = 4; i < N - 4; i++) {
                    float rise, fall;
                    slopes(s, i, k, &rise, &fall);
                    column_rocks c = column_read(s, i, k);
                    if (rise >= 3.0f && fall <= 0.7f && c.ground > p.sea_level) {
                        feet++;
                        stony_feet += c.rocks >= 0.5f;
                    }
                    if (c.rocks <= 0.0f) continue;
                    /* Every talus column is within 3 columns of a rise of 1.5 m a metre. */
                    stony++;
                    bool wall = false;
                    for (int dz = -3; dz <= 3 && !wall; dz++)
                        for (int dx = -3; dx <= 3 && !wall; dx++) {
                            float r, f;
                            slopes(s, i + dx, k + dz, &r, &f);
                            wall = r >= 1.5f;
                        }
                    stony_near_wall += wall;
                }
            terrain_stacks_destroy(s);
        }
    cr_log_info("talus: %d of %d feet hold 0.5 m or more", stony_feet, feet);
    cr_expect_gt(feet, 50, "%d feet", feet);
    cr_expect_geq(stony_feet, feet * 8 / 10, "%d of %d feet hold talus", stony_feet, feet);
    cr_expect_eq(stony_near_wall, stony, "%d of %d talus columns near a wall", stony_near_wall, stony);
}

Test(terrain_rocks_generate, scree_only_on_slopes_steeper_than_sand_holds) {
    /* Scree only: every stony column's ground falls faster than scree_min_slope (sand's angle
     * of repose) towards some neighbour (a quantum of rounding either side). */
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.talus_depth = p.lake_rocks_depth = -1.0f;
    int stony = 0, steep = 0;
    for (int64_t cz = 0; cz < 4; cz++)
        for (int64_t cx = 1; cx < 5; cx++) {
            terrain_stacks *s = terrain_generate_chunk(&p, (terrain_chunk_coord){ cx, cz });
            for (int k = 1; k < N - 1; k++)
                for (int i = 1; i < N - 1; i++) {
                    if (column_read(s, i, k).rocks <= 0.0f) continue;
                    float rise, fall;
                    slopes(s, i, k, &rise, &fall);
                    stony++;
                    steep += fall > p.scree_min_slope - 2.0f * Q;
                }
            terrain_stacks_destroy(s);
        }
    cr_log_info("scree: %d columns", stony);
    cr_expect_gt(stony, 100, "%d scree columns", stony);
    cr_expect_eq(steep, stony, "%d of %d scree columns on slopes steeper than sand's", steep, stony);
}

Test(terrain_rocks_generate, lake_beds_are_partly_stony_and_mostly_sand) {
    /* Seed 1's lake in chunks (19…21, −5…−4) (test_terrain_water.c finds it from the water):
     * of the columns under its water, some have rocks right under the water (the ring at the
     * waterline), most keep the basin's sand. Measured when written: 861 of 3377, 25 %. */
    terrain_generation_desc p = terrain_generation_defaults(1);
    int wet = 0, stony = 0, sandy = 0;
    terrain_layer layers[256];
    for (int64_t cz = -5; cz <= -4; cz++)
        for (int64_t cx = 19; cx <= 21; cx++) {
            terrain_stacks *s = terrain_generate_chunk(&p, (terrain_chunk_coord){ cx, cz });
            for (int k = 0; k < N; k++)
                for (int i = 0; i < N; i++) {
                    int count = terrain_stacks_column(s, i, k, layers, 256);
                    if (count < 2 || layers[count - 1].material != TERRAIN_WATER ||
                        terrain_stacks_surface(s, i, k) < p.sea_level + 1.0f)
                        continue;
                    wet++;
                    stony += layers[count - 2].material == TERRAIN_ROCKS;
                    sandy += layers[count - 2].material == TERRAIN_SAND;
                }
            terrain_stacks_destroy(s);
        }
    cr_log_info("lake: %d columns under its water, %d on rocks, %d on sand", wet, stony, sandy);
    cr_assert_gt(wet, 1000, "%d lake columns", wet);
    cr_expect_geq(stony, wet / 10, "%d of %d lake columns on rocks", stony, wet);
    cr_expect_geq(sandy, wet / 2, "%d of %d lake columns on sand", sandy, wet);
    cr_expect_eq(stony + sandy, wet, "lake beds are sand or rocks");
}

/* ---- stability ------------------------------------------------------------------------------ */

static int64_t rocks_quanta(const terrain_columns *c, int i, int k) {
    terrain_layer layers[256];
    int count = terrain_columns_get(c, i, k, layers, 256);
    int64_t q = 0;
    for (int l = 0; l < count && l < 256; l++)
        if (layers[l].material == TERRAIN_ROCKS) q += llroundf(layers[l].thickness / Q);
    return q;
}

Test(terrain_rocks_generate, the_stabilizer_leaves_generated_rocks_in_place) {
    /* 4 × 4 chunks of seed 1 with cliffs and scree, all marked, stabilized with the defaults
     * (rocks 42°, sand 33°) until at rest: the rocks that change columns are at most 2 % of
     * them (the generator keeps its rock surfaces at 38°; what can move is where a chunk's
     * estimate of its neighbour's ground was off). */
    terrain_generation_desc p = terrain_generation_defaults(1);
    enum { SIDE = 4 };
    terrain_columns *c = terrain_columns_create(&(terrain_columns_desc){ .x = N, .z = 0, .width = SIDE * N,
                                                                        .depth = SIDE * N });
    for (int64_t cz = 0; cz < SIDE; cz++)
        for (int64_t cx = 1; cx <= SIDE; cx++) {
            terrain_stacks *s = terrain_generate_chunk(&p, (terrain_chunk_coord){ cx, cz });
            cr_assert(terrain_columns_load(c, (terrain_chunk_coord){ cx, cz }, s));
            terrain_stacks_destroy(s);
        }
    int64_t *before = calloc((size_t)SIDE * N * SIDE * N, sizeof *before);
    int64_t total = 0;
    for (int k = 0; k < SIDE * N; k++)
        for (int i = 0; i < SIDE * N; i++) total += before[k * SIDE * N + i] = rocks_quanta(c, i, k);
    cr_assert_gt(total, 0);
    terrain_columns_touch(c, 0, 0, SIDE * N, SIDE * N);
    terrain_stabilize_result result;
    cr_assert(terrain_stabilize_region(c, &(terrain_stabilize_desc){ 0 }, NULL, &result));
    cr_expect(result.converged);
    int64_t changed = 0;
    for (int k = 0; k < SIDE * N; k++)
        for (int i = 0; i < SIDE * N; i++) changed += llabs(rocks_quanta(c, i, k) - before[k * SIDE * N + i]);
    cr_expect_eq(terrain_columns_mass(c, TERRAIN_ROCKS), total, "rocks are conserved");
    cr_log_info("stabilizing generated rocks: %lld of %lld quanta·columns moved (%.3f %%), all moves %lld",
                (long long)(changed / 2), (long long)total, 100.0 * (double)(changed / 2) / (double)total,
                (long long)result.moved);
    cr_expect_leq((double)(changed / 2), 0.02 * (double)total, "%lld of %lld rock quanta moved", (long long)(changed / 2),
                  (long long)total);
    free(before);
    terrain_columns_destroy(c);
}
