/* Generation: flat worlds worked out by hand, determinism over threads and orders, overhangs
 * and caves really there (and absent when switched off), water below sea level, no period,
 * continuity across chunk borders, memory per column under the budget. */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <math.h>

#define N TERRAIN_CHUNK_COLUMNS
#define Q TERRAIN_HEIGHT_QUANTUM

/* A world with no relief, no perturbation and no caves: every column is the same by hand. */
static terrain_generation_desc flat_params(float base, float sea) {
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.base_height = base;
    p.sea_level = sea;
    p.relief_height = 0.0f;
    p.vertical_perturbation = 0.0f;
    p.horizontal_perturbation = 0.0f;
    p.cave_threshold = 0.0f;
    p.sand_depth = 2.0f;
    p.sand_max_slope = 0.5f;
    p.lake_spacing = 0.0f;                 /* no lakes either: a flat plain would get basins */
    return p;
}

Test(terrain_generate, flat_land_is_bedrock_under_sand) {
    /* Ground at 10 m: bedrock from −256 to 8, then 2 m of sand (slope 0: full depth), no water. */
    terrain_generation_desc p = flat_params(10.0f, 0.0f);
    terrain_stacks *s = terrain_generate_chunk(&p, (terrain_chunk_coord){ 3, -2 });
    terrain_layer layers[8];
    for (int k = 0; k < N; k += 7) {
        for (int i = 0; i < N; i += 5) {
            cr_assert_eq(terrain_stacks_column(s, i, k, layers, 8), 2, "column (%d, %d)", i, k);
            cr_expect_eq(layers[0].material, TERRAIN_BEDROCK);
            cr_expect_float_eq(layers[0].thickness, 264.0f, Q);
            cr_expect_eq(layers[1].material, TERRAIN_SAND);
            cr_expect_float_eq(layers[1].thickness, 2.0f, Q);
            cr_expect_float_eq(terrain_stacks_top(s, i, k), 10.0f, Q);
        }
    }
    terrain_stacks_destroy(s);
}

Test(terrain_generate, flat_sea_floor_under_water) {
    /* Ground at −12 m under a sea at 0: bedrock to −14, sand to −12, 12 m of water. */
    terrain_generation_desc p = flat_params(-12.0f, 0.0f);
    terrain_stacks *s = terrain_generate_chunk(&p, (terrain_chunk_coord){ -5, 9 });
    terrain_layer layers[8];
    cr_assert_eq(terrain_stacks_column(s, 4, 30, layers, 8), 3);
    cr_expect_eq(layers[2].material, TERRAIN_WATER);
    cr_expect_float_eq(layers[2].thickness, 12.0f, Q);
    cr_expect_float_eq(terrain_stacks_top(s, 4, 30), -12.0f, Q);
    cr_expect_float_eq(terrain_stacks_surface(s, 4, 30), 0.0f, Q);
    cr_expect_eq(terrain_stacks_material_at(s, 4, 30, -5.0f), TERRAIN_WATER);
    cr_expect_eq(terrain_stacks_material_at(s, 4, 30, 0.5f), TERRAIN_AIR);
    /* No sand where the slope limit is 0. */
    p.sand_max_slope = 0.0f;
    terrain_stacks *bare = terrain_generate_chunk(&p, (terrain_chunk_coord){ -5, 9 });
    cr_assert_eq(terrain_stacks_column(bare, 4, 30, layers, 8), 2);
    cr_expect_eq(layers[0].material, TERRAIN_BEDROCK);
    cr_expect_eq(layers[1].material, TERRAIN_WATER);
    terrain_stacks_destroy(bare);
    terrain_stacks_destroy(s);
}

/* ---- determinism ---------------------------------------------------------------------------- */

#define DET_SIDE 4

typedef struct generate_job {
    terrain_generation_desc params;
    bool reverse;
    uint64_t hashes[DET_SIDE * DET_SIDE];
} generate_job;

static void generate_range(void *user, size_t begin, size_t end) {
    generate_job *job = user;
    for (size_t n = begin; n < end; n++) {
        size_t index = job->reverse ? DET_SIDE * DET_SIDE - 1 - n : n;
        terrain_chunk_coord c = { (int64_t)(index % DET_SIDE) - 1, (int64_t)(index / DET_SIDE) - 2 };
        terrain_stacks *s = terrain_generate_chunk(&job->params, c);
        job->hashes[index] = terrain_stacks_hash(s);
        terrain_stacks_destroy(s);
    }
}

Test(terrain_generate, same_bytes_on_any_thread_count_and_order) {
    static generate_job one, two;
    one.params = two.params = terrain_generation_defaults(42);
    two.reverse = true;
    job_system *serial = job_system_create(&(job_system_desc){ .threads = 1 });
    job_parallel_for(serial, DET_SIDE * DET_SIDE, 1, generate_range, &one, "generate");
    job_system_destroy(serial);
    job_system *parallel = job_system_create(&(job_system_desc){ .threads = 2 });
    job_parallel_for(parallel, DET_SIDE * DET_SIDE, 1, generate_range, &two, "generate");
    job_system_destroy(parallel);
    for (int n = 0; n < DET_SIDE * DET_SIDE; n++) {
        cr_assert_eq(one.hashes[n], two.hashes[n], "chunk %d", n);
        for (int m = 0; m < n; m++) cr_assert_neq(one.hashes[n], one.hashes[m], "chunks %d and %d equal", n, m);
    }
    /* The world's cached copy is the same chunk. */
    terrain_world *w = terrain_world_create(&(terrain_world_desc){ .generation = one.params });
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(w, (terrain_chunk_coord){ -1, -2 })), one.hashes[0]);
    terrain_world_destroy(w);
}

Test(terrain_generate, seed_changes_the_world) {
    terrain_generation_desc a = terrain_generation_defaults(1), b = terrain_generation_defaults(2);
    terrain_stacks *sa = terrain_generate_chunk(&a, (terrain_chunk_coord){ 0, 0 });
    terrain_stacks *sb = terrain_generate_chunk(&b, (terrain_chunk_coord){ 0, 0 });
    cr_expect_neq(terrain_stacks_hash(sa), terrain_stacks_hash(sb));
    terrain_stacks_destroy(sa);
    terrain_stacks_destroy(sb);
}

/* ---- what the world contains ---------------------------------------------------------------- */

typedef struct area_stats {
    int columns;
    int gaps;              /* columns with air between two solid layers */
    int water_columns, low_columns, bad_water;
    int sand_columns;
    size_t bytes;
    float lowest, highest;
} area_stats;

static area_stats survey(const terrain_generation_desc *p, int64_t x0, int64_t z0, int side) {
    area_stats st = { .lowest = INFINITY, .highest = -INFINITY };
    terrain_layer layers[256];
    for (int64_t cz = z0; cz < z0 + side; cz++) {
        for (int64_t cx = x0; cx < x0 + side; cx++) {
            terrain_stacks *s = terrain_generate_chunk(p, (terrain_chunk_coord){ cx, cz });
            st.bytes += terrain_stacks_bytes(s);
            for (int k = 0; k < N; k++) {
                for (int i = 0; i < N; i++) {
                    int count = terrain_stacks_column(s, i, k, layers, 256);
                    bool seen_solid = false, gap = false, water = false, sand = false;
                    for (int l = 0; l < count && l < 256; l++) {
                        bool solid = terrain_material_in_field(layers[l].material);
                        if (solid && seen_solid && layers[l - 1].material == TERRAIN_AIR) gap = true;
                        seen_solid |= solid;
                        water |= layers[l].material == TERRAIN_WATER;
                        sand |= layers[l].material == TERRAIN_SAND;
                    }
                    float top = terrain_stacks_top(s, i, k);
                    float surface = terrain_stacks_surface(s, i, k);
                    st.columns++;
                    st.gaps += gap;
                    st.water_columns += water;
                    st.sand_columns += sand;
                    if (top < p->sea_level - Q) {
                        st.low_columns++;
                        /* Water from the ground up to the sea level, exactly. */
                        if (!water || fabsf(surface - p->sea_level) > Q ||
                            terrain_stacks_material_at(s, i, k, top + 0.5f * (p->sea_level - top)) != TERRAIN_WATER)
                            st.bad_water++;
                    } else if (top >= p->sea_level && water) {
                        st.bad_water++;   /* no water where the ground is above the sea level */
                    }
                    st.lowest = fminf(st.lowest, top);
                    st.highest = fmaxf(st.highest, surface);
                }
            }
            terrain_stacks_destroy(s);
        }
    }
    return st;
}

Test(terrain_generate, overhangs_and_caves_exist) {
    /* A fixed sample area of 4 × 4 chunks with cliffs (seed 42, chunks x 12…15, z −4…−1). */
    terrain_generation_desc p = terrain_generation_defaults(42);
    /* Caves off: only overhangs (the sideways displacement shearing steep ground) make gaps. */
    terrain_generation_desc no_caves = p;
    no_caves.cave_threshold = 0.0f;
    area_stats overhangs = survey(&no_caves, 12, -4, 4);
    cr_expect_gt(overhangs.gaps, overhangs.columns / 50, "%d overhang columns of %d", overhangs.gaps, overhangs.columns);
    /* Caves on: many more. */
    area_stats all = survey(&p, 12, -4, 4);
    cr_expect_gt(all.gaps, overhangs.gaps + all.columns / 10, "%d gap columns of %d", all.gaps, all.columns);
    /* Neither: a pure height field, no gaps at all. */
    terrain_generation_desc height_field = no_caves;
    height_field.horizontal_perturbation = 0.0f;
    area_stats none = survey(&height_field, 12, -4, 2);
    cr_expect_eq(none.gaps, 0);
}

Test(terrain_generate, water_exactly_where_the_ground_is_low) {
    /* Seed 7 has sea near the origin; lowering the base adds more. Every column whose ground is
     * below the sea level holds water up to it, no other column holds any. */
    terrain_generation_desc p = terrain_generation_defaults(7);
    p.base_height = -20.0f;
    area_stats st = survey(&p, 0, 0, 3);
    cr_expect_gt(st.low_columns, st.columns / 10, "%d low columns", st.low_columns);
    cr_expect_eq(st.bad_water, 0);
    cr_expect_geq(st.water_columns, st.low_columns);
    cr_expect_gt(st.sand_columns, 0);
}

Test(terrain_generate, relief_spans_tens_of_metres_within_the_floor) {
    terrain_generation_desc p = terrain_generation_defaults(42);
    area_stats st = survey(&p, -6, -6, 4);
    area_stats other = survey(&p, 20, 5, 4);
    float lowest = fminf(st.lowest, other.lowest), highest = fmaxf(st.highest, other.highest);
    cr_expect_gt(highest - lowest, 40.0f, "relief %g … %g", lowest, highest);
    cr_expect_gt(lowest, TERRAIN_FLOOR_Y);
    cr_expect_lt(highest, TERRAIN_FLOOR_Y + 2048.0f);
}

Test(terrain_generate, not_periodic) {
    /* Chunks far apart — including 384 chunks (12 288 m = 256 × 48 m, where a 256-entry
     * permutation table would repeat at the perturbation wavelength) — all differ. */
    terrain_generation_desc p = terrain_generation_defaults(42);
    terrain_chunk_coord coords[] = { { 0, 0 }, { 384, 0 }, { 0, 384 }, { 8192, 0 }, { -65536, 4096 }, { 1 << 16, 1 << 16 } };
    uint64_t hashes[6];
    for (int n = 0; n < 6; n++) {
        terrain_stacks *s = terrain_generate_chunk(&p, coords[n]);
        hashes[n] = terrain_stacks_hash(s);
        terrain_stacks_destroy(s);
        for (int m = 0; m < n; m++) cr_expect_neq(hashes[n], hashes[m], "chunks %d and %d", n, m);
    }
}

/* Not periodic, by the heights themselves (issue 16: equal chunk hashes would miss a period the
 * chunks do not line up with). A field with period P has h(x) = h(x + P) everywhere, so the
 * correlation of h(x) and h(x + P) over many x is 1. Noise built on a 256- or 4096-entry table
 * repeats after that many lattice cells: lags of 256 and 4096 wavelengths of the relief (1200 m)
 * and of the perturbation (48 m), plus an unrelated lag, must all show a correlation well under
 * 1. For an aperiodic field at lags far beyond its wavelengths it is near 0 (±1/√N ≈ 0.04 for
 * N = 600 samples); 0.5 leaves room for the relief's long reach. */
static double height_correlation(const terrain_generation_desc *p, double lag) {
    enum { SAMPLES = 600 };
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    for (int i = 0; i < SAMPLES; i++) {
        double x = -20000.0 + 53.7 * i, z = 1234.5 + 11.3 * (i % 7);
        double a = terrain__ground_height(p, x, z), b = terrain__ground_height(p, x + lag, z);
        sa += a, sb += b, saa += a * a, sbb += b * b, sab += a * b;
    }
    double n = SAMPLES, cov = sab / n - (sa / n) * (sb / n);
    double va = saa / n - (sa / n) * (sa / n), vb = sbb / n - (sb / n) * (sb / n);
    return cov / sqrt(va * vb);
}

Test(terrain_generate, heights_do_not_repeat_at_a_tables_period) {
    terrain_generation_desc p = terrain_generation_defaults(42);
    cr_assert_eq(p.relief_wavelength, 1200.0f, "the lags below assume the defaults' wavelengths");
    cr_assert_eq(p.perturbation_wavelength, 48.0f);
    cr_expect_gt(height_correlation(&p, 0.0), 0.999, "a lag of 0 correlates fully (the measure works)");
    const double lags[] = { 256 * 48.0, 4096 * 48.0, 256 * 1200.0, 4096 * 1200.0, 1000003.0 };
    for (int n = 0; n < 5; n++) {
        double r = height_correlation(&p, lags[n]);
        cr_expect_lt(fabs(r), 0.5, "heights %g m apart correlate at %.3f: a period?", lags[n], r);
    }
}

Test(terrain_generate, continuous_across_chunk_borders) {
    /* The step in ground height between the last column of one chunk and the first of the next
     * is no larger on average than steps between neighbours inside a chunk. */
    terrain_generation_desc p = terrain_generation_defaults(42);
    p.cave_threshold = 0.0f;             /* compare ground, not cave roofs */
    double inside = 0.0, across = 0.0;
    int inside_count = 0, across_count = 0;
    for (int64_t cx = 0; cx < 4; cx++) {
        terrain_stacks *a = terrain_generate_chunk(&p, (terrain_chunk_coord){ cx, 1 });
        terrain_stacks *b = terrain_generate_chunk(&p, (terrain_chunk_coord){ cx + 1, 1 });
        for (int k = 0; k < N; k++) {
            across += fabsf(terrain_stacks_top(a, N - 1, k) - terrain_stacks_top(b, 0, k));
            across_count++;
            for (int i = 0; i + 1 < N; i++) {
                inside += fabsf(terrain_stacks_top(a, i, k) - terrain_stacks_top(a, i + 1, k));
                inside_count++;
            }
        }
        terrain_stacks_destroy(a);
        terrain_stacks_destroy(b);
    }
    cr_expect_lt(across / across_count, 2.0 * inside / inside_count + 0.1,
                 "mean step across %g, inside %g", across / across_count, inside / inside_count);
}

Test(terrain_generate, memory_per_column_under_budget) {
    /* The 512 × 512-column region must fit in 3 MB: 3·2²⁰ / 512² = 12 bytes a column. Two
     * samples of 4 × 4 chunks, one with sea. */
    terrain_generation_desc p = terrain_generation_defaults(42);
    area_stats land = survey(&p, 0, 0, 4);
    terrain_generation_desc wet = terrain_generation_defaults(7);
    area_stats sea = survey(&wet, 0, 0, 4);
    double per_column = (double)(land.bytes + sea.bytes) / (land.columns + sea.columns);
    cr_expect_lt(per_column, 3.0 * 1024 * 1024 / (512.0 * 512.0), "%.2f bytes per column", per_column);
}
