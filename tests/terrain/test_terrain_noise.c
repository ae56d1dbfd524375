/* Noise: range, continuity, zeros at lattice points, determinism and seeds, the column batch
 * against the scalar function, fBm bounds, ridged values worked out by hand, the rescale-and-add
 * multifractal's octave count and fractional last octave (004 §2, §4). */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A small deterministic sequence of test points (an LCG: the tests' own, not the noise's). */
static float next_coordinate(uint64_t *state, float extent) {
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return ((float)(*state >> 40) / 16777216.0f * 2.0f - 1.0f) * extent;
}

Test(terrain_noise, stays_in_range_and_varies) {
    uint64_t state = 1;
    double sum = 0.0, squares = 0.0;
    float lowest = 0.0f, highest = 0.0f;
    int count = 200000;
    for (int n = 0; n < count; n++) {
        float x = next_coordinate(&state, 300.0f), y = next_coordinate(&state, 300.0f), z = next_coordinate(&state, 300.0f);
        float v = terrain_noise3(42, x, y, z);
        cr_assert(v >= -1.0f && v <= 1.0f, "noise3(%g, %g, %g) = %g", x, y, z, v);
        float w = terrain__noise2(7, x, z);
        cr_assert(w >= -1.0f && w <= 1.0f, "noise2(%g, %g) = %g", x, z, w);
        sum += v;
        squares += (double)v * v;
        lowest = fminf(lowest, v);
        highest = fmaxf(highest, v);
    }
    /* Zero mean (gradient noise is odd-symmetric on average), a real spread, reaching far out. */
    cr_expect(fabs(sum / count) < 0.01, "mean %g", sum / count);
    cr_expect(sqrt(squares / count) > 0.15, "rms %g", sqrt(squares / count));
    cr_expect(highest > 0.6f && lowest < -0.6f, "range [%g, %g]", lowest, highest);
}

Test(terrain_noise, zero_at_lattice_points) {
    /* Every corner's offset vector is 0 at its own lattice point and the fade weights select that
     * corner alone, so gradient noise vanishes there, for any seed. */
    for (uint64_t seed = 0; seed < 4; seed++) {
        for (int x = -3; x <= 3; x++) {
            for (int y = -3; y <= 3; y++) {
                for (int z = -3; z <= 3; z++) {
                    cr_assert_eq(terrain_noise3(seed, (float)x, (float)y, (float)z), 0.0f);
                    cr_assert_eq(terrain__noise2((uint32_t)seed, (float)x, (float)z), 0.0f);
                }
            }
        }
    }
}

Test(terrain_noise, continuous) {
    /* |∇n| is bounded: each corner term has gradient length √2 over offsets up to √3 and the
     * quintic fade's slope is at most 15/8, so a generous bound is 8 per unit. A step of 10⁻³
     * must move the value by less than 0.008 — also across cell borders. */
    uint64_t state = 9;
    for (int n = 0; n < 20000; n++) {
        float x = next_coordinate(&state, 50.0f), y = next_coordinate(&state, 50.0f), z = next_coordinate(&state, 50.0f);
        if (n % 4 == 0) x = floorf(x) - 0.0005f;          /* straddle a cell border */
        float a = terrain_noise3(3, x, y, z);
        float b = terrain_noise3(3, x + 1e-3f, y, z), c = terrain_noise3(3, x, y + 1e-3f, z), d = terrain_noise3(3, x, y, z + 1e-3f);
        cr_assert(fabsf(b - a) < 0.008f && fabsf(c - a) < 0.008f && fabsf(d - a) < 0.008f,
                  "jump near (%g, %g, %g)", x, y, z);
    }
}

Test(terrain_noise, deterministic_and_seeded) {
    uint64_t state = 5;
    int differ = 0, count = 1000;
    for (int n = 0; n < count; n++) {
        float x = next_coordinate(&state, 100.0f), y = next_coordinate(&state, 100.0f), z = next_coordinate(&state, 100.0f);
        cr_assert_eq(terrain_noise3(11, x, y, z), terrain_noise3(11, x, y, z));
        if (terrain_noise3(11, x, y, z) != terrain_noise3(12, x, y, z)) differ++;
    }
    cr_expect_gt(differ, count * 95 / 100, "seeds 11 and 12 agree at %d of %d points", count - differ, count);
}

Test(terrain_noise, column_batch_equals_scalar) {
    /* Counts below, at and past the batch's block size, negative and positive y, several seeds. */
    int counts[] = { 1, 7, 8, 9, 31, 100 };
    float out[128];
    uint64_t state = 77;
    for (int c = 0; c < (int)(sizeof counts / sizeof counts[0]); c++) {
        for (int trial = 0; trial < 20; trial++) {
            float x = next_coordinate(&state, 200.0f), z = next_coordinate(&state, 200.0f);
            float y0 = next_coordinate(&state, 50.0f), dy = 0.01f + fabsf(next_coordinate(&state, 0.7f));
            uint64_t seed = (uint64_t)trial * 1000003u;
            for (int j = 0; j < 128; j++) out[j] = 12345.0f;
            terrain_noise3_column(seed, x, y0, dy, z, counts[c], out);
            for (int j = 0; j < counts[c]; j++)
                cr_assert_eq(out[j], terrain_noise3(seed, x, y0 + (float)j * dy, z), "count %d, sample %d", counts[c], j);
            cr_assert_eq(out[counts[c]], 12345.0f, "wrote past count");
        }
    }
}

/* One of n choices from the same sequence, so that the choices of one trial do not move in step. */
static int next_choice(uint64_t *state, int n) {
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return (int)((*state >> 33) % (uint64_t)n);
}

static uint32_t bits_of(float f) {
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* One random column through the path in use, against terrain__noise3 point by point, bit for
 * bit (-0 and +0 differ here, which == would not see). */
static void check_column_bits(uint32_t seed, float x, float y0, float dy, float z, int count, const char *path) {
    enum { MAX_COUNT = 80 };
    float out[MAX_COUNT + 1];
    for (int j = 0; j <= MAX_COUNT; j++) out[j] = 12345.0f;
    terrain__noise3_column(seed, x, y0, dy, z, count, out);
    for (int j = 0; j < count; j++) {
        float expected = terrain__noise3(seed, x, y0 + (float)j * dy, z);
        cr_assert_eq(bits_of(out[j]), bits_of(expected),
                     "%s path: seed %u, column (%.9g, %.9g), y0 %.9g, dy %.9g, count %d, sample %d: %.9g, scalar %.9g",
                     path, seed, x, z, y0, dy, count, j, out[j], expected);
    }
    cr_assert_eq(out[count], 12345.0f, "%s path wrote past count %d", path, count);
}

/* A random row through the path in use: the 2D row batch against the portable path's row
 * (noise2_row is unclamped, so terrain__noise2_cell is its reference only inside [-1, 1],
 * checked too), and the multifractal's row against terrain__multifractal2, bit for bit. Origins
 * near 0, around ±10⁵ and ±10⁷ lattice units (cells past 2^23, where a float has no fraction
 * left, and the cell wraps modulo 2^32 in the multifractal's finer octaves), negative ones. */
static void check_rows_bits(uint64_t *state, int count, const char *path) {
    enum { MAX_COUNT = 80 };
    static const float extents[] = { 40.0f, 40.0f, 40.0f, 1e5f, 1e7f };
    float dxs[MAX_COUNT], out[MAX_COUNT + 1], portable[MAX_COUNT];
    float extent = extents[next_choice(state, 5)];
    double x0 = (double)next_coordinate(state, extent) + 0.37, z = (double)next_coordinate(state, extent) - 0.61;
    float scale = next_choice(state, 3) ? 1.0f : 2.5f;
    for (int j = 0; j < count; j++) dxs[j] = next_coordinate(state, 40.0f);
    uint32_t seed = (uint32_t)(*state >> 32);
    out[count] = 12345.0f;
    terrain__noise2_row(seed, x0, dxs, scale, z, count, out);
    cr_assert_eq(out[count], 12345.0f, "%s path: noise2_row wrote past count %d", path, count);
    terrain__noise_path path_in_use = terrain__noise_get_path();
    terrain__noise_set_path(TERRAIN__NOISE_PORTABLE);
    terrain__noise2_row(seed, x0, dxs, scale, z, count, portable);
    terrain__noise_set_path(path_in_use);
    terrain__lattice sx = terrain__lattice_split(x0), sz = terrain__lattice_split(z);
    for (int j = 0; j < count; j++) {
        cr_assert_eq(bits_of(out[j]), bits_of(portable[j]),
                     "%s path: noise2_row seed %u at (%.17g + %.9g·%g, %.17g): %.9g, portable %.9g", path, seed, x0, dxs[j],
                     scale, z, out[j], portable[j]);
        if (fabsf(out[j]) < 1.0f)
            cr_assert_eq(bits_of(out[j]), bits_of(terrain__noise2_cell(seed, sx.cell, sx.offset + dxs[j] * scale, sz.cell,
                                                                       sz.offset)),
                         "%s path: noise2 at %d", path, j);
    }
    terrain__multifractal mf = { .seed = seed, .lacunarity = 2.0f, .hurst = 0.85f,
                                 .octaves = 1.0f + (float)next_choice(state, 12) * 0.7f,
                                 .warp = next_choice(state, 4) ? 1.0f : 0.0f };
    for (int j = 0; j < count; j++) dxs[j] *= 0.01f;   /* a row's width, in wavelengths */
    out[count] = 12345.0f;
    terrain__multifractal2_row(&mf, x0, dxs, z, count, out);
    cr_assert_eq(out[count], 12345.0f, "%s path: multifractal2_row wrote past count %d", path, count);
    for (int j = 0; j < count; j++)
        cr_assert_eq(bits_of(out[j]), bits_of(terrain__multifractal2(&mf, x0, dxs[j], z)),
                     "%s path: multifractal2_row (%g octaves) at (%.17g + %.9g, %.17g): %.9g", path, mf.octaves, x0, dxs[j],
                     z, out[j]);
}

Test(terrain_noise, every_dispatch_path_equals_scalar_bit_for_bit) {
    /* The world must not depend on the CPU that generates it: each path the CPU runs, forced in
     * turn, over many random columns: coordinates near the origin and around ±10⁵ (where a
     * float's spacing is 1/128), negative y, steps from 0 to a few cells (the AVX2/AVX-512
     * level tables and their direct fallback), counts 0, 1, below, at and past each lane width
     * (8, 16), lattice seams inside one batch; the same for the 2D row batch and the
     * multifractal's row, which generation also calls. */
    static const int counts[] = { 0, 1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 23, 31, 33, 48, 63, 64, 65, 80 };
    int count_kinds = (int)(sizeof counts / sizeof counts[0]);
    terrain__noise_path before = terrain__noise_get_path();
    int paths_run = 0;
    for (int p = TERRAIN__NOISE_PORTABLE; p < TERRAIN__NOISE_PATH_COUNT; p++) {
        terrain__noise_path path = (terrain__noise_path)p;
        const char *name = terrain__noise_path_name(path);
        if (!terrain__noise_path_supported(path)) {
            fprintf(stderr, "terrain_noise: the %s path is not checked: this CPU cannot run it\n", name);
            cr_assert_not(terrain__noise_set_path(path), "%s accepted on a CPU without it", name);
            continue;
        }
        cr_assert(terrain__noise_set_path(path), "%s", name);
        cr_assert_eq(terrain__noise_get_path(), path, "%s", name);
        paths_run++;
        uint64_t state = 2024;
        for (int trial = 0; trial < 3000; trial++) {
            static const float extents[] = { 1e5f, 300.0f, 4.0f };
            float extent = extents[next_choice(&state, 3)];
            float x = next_coordinate(&state, extent), z = next_coordinate(&state, extent);
            float y0 = next_coordinate(&state, next_choice(&state, 2) ? 1e5f : 60.0f);
            float dy = fabsf(next_coordinate(&state, next_choice(&state, 5) ? 0.7f : 3.0f));
            uint32_t seed = (uint32_t)(trial * 2654435761u);
            check_column_bits(seed, x, y0, dy, z, counts[next_choice(&state, count_kinds)], name);
        }
        for (int trial = 0; trial < 1000; trial++) check_rows_bits(&state, counts[next_choice(&state, count_kinds)], name);
        /* Exactly on lattice planes, and negative steps (a column read downwards). */
        for (int trial = 0; trial < 200; trial++) {
            float x = (float)(trial % 7 - 3), z = (float)(trial % 5 - 2) + (trial % 2 ? 0.5f : 0.0f);
            check_column_bits((uint32_t)trial, x, (float)(trial - 100), trial % 3 ? 0.25f : -0.125f, z,
                              counts[trial % count_kinds], name);
        }
    }
    cr_assert(terrain__noise_set_path(TERRAIN__NOISE_AUTO));
    cr_expect_eq(terrain__noise_get_path(), before, "AUTO chooses the path the first batch chose");
    cr_expect_geq(paths_run, 1);
#if defined(__x86_64__)
    cr_expect(terrain__noise_path_supported(TERRAIN__NOISE_SSE2), "SSE2 is x86-64's baseline");
    cr_expect_geq(paths_run, 2, "portable and SSE2 at least");
#endif
}

Test(terrain_noise, fbm_bounded_by_its_amplitudes) {
    /* Octave amplitudes 1, 1/2, 1/4, … : |fbm| ≤ 2 − 2^(1−octaves). No octaves, no value. */
    uint64_t state = 3;
    for (int octaves = 1; octaves <= 6; octaves++) {
        float bound = 2.0f - ldexpf(1.0f, 1 - octaves);
        for (int n = 0; n < 2000; n++) {
            float x = next_coordinate(&state, 40.0f), y = next_coordinate(&state, 40.0f), z = next_coordinate(&state, 40.0f);
            float v = terrain_fbm3(8, x, y, z, octaves);
            cr_assert(fabsf(v) <= bound + 1e-6f, "fbm %d octaves = %g", octaves, v);
        }
    }
    cr_expect_eq(terrain_fbm3(8, 0.3f, 0.4f, 0.5f, 0), 0.0f);
    /* More octaves add detail: the values differ. */
    cr_expect_neq(terrain_fbm3(8, 0.3f, 0.4f, 0.5f, 2), terrain_fbm3(8, 0.3f, 0.4f, 0.5f, 3));
}

Test(terrain_noise, ridged_by_hand) {
    /* One octave: (1 − |n|)². Two octaves at gain g: s0 = (1 − |n0|)², weight = min(1, 2·s0),
     * s1 = (1 − |n1|)²·weight, result (s0 + g·s1) / (1 + g). */
    float zero[] = { 0.0f }, one[] = { 1.0f }, half[] = { -0.5f };
    cr_expect_float_eq(terrain__ridged_from_octaves(zero, 1, 0.5f), 1.0f, 1e-6f);
    cr_expect_float_eq(terrain__ridged_from_octaves(one, 1, 0.5f), 0.0f, 1e-6f);
    cr_expect_float_eq(terrain__ridged_from_octaves(half, 1, 0.5f), 0.25f, 1e-6f);
    float both_zero[] = { 0.0f, 0.0f }, ridge_only[] = { 0.0f, 1.0f }, off_ridge[] = { 0.5f, 0.0f };
    cr_expect_float_eq(terrain__ridged_from_octaves(both_zero, 2, 0.5f), 1.0f, 1e-6f);
    cr_expect_float_eq(terrain__ridged_from_octaves(ridge_only, 2, 0.5f), 1.0f / 1.5f, 1e-6f);
    cr_expect_float_eq(terrain__ridged_from_octaves(ridge_only, 2, 0.25f), 1.0f / 1.25f, 1e-6f);
    /* s0 = 0.25, weight 0.5, s1 = 0.5: (0.25 + 0.5·0.5) / 1.5. */
    cr_expect_float_eq(terrain__ridged_from_octaves(off_ridge, 2, 0.5f), 0.5f / 1.5f, 1e-6f);
    /* The 3D form stays in [0, 1] and is 1 at lattice points (every octave's noise is 0 there). */
    cr_expect_float_eq(terrain__ridged3(5, 2.0f, -3.0f, 7.0f, 3, 0.5f), 1.0f, 1e-6f);
    uint64_t state = 21;
    for (int n = 0; n < 5000; n++) {
        float x = next_coordinate(&state, 30.0f), y = next_coordinate(&state, 30.0f), z = next_coordinate(&state, 30.0f);
        float r = terrain__ridged3(5, x, y, z, 3, 0.5f);
        cr_assert(r >= 0.0f && r <= 1.0f, "ridged %g", r);
    }
}

Test(terrain_noise, multifractal_octave_count) {
    /* 004 §4: ν = log σ / log r^−H. r = 2, H = 0.5, σ = 1/16: log2(16) / 0.5 = 8. */
    cr_expect_float_eq(terrain__multifractal_octaves(2.0f, 0.5f, 1.0f / 16.0f, 20), 8.0f, 1e-4f);
    /* r = 2, H = 1, σ = 0.3: log2(1/0.3) = 1.737. */
    cr_expect_float_eq(terrain__multifractal_octaves(2.0f, 1.0f, 0.3f, 20), 1.7369656f, 1e-4f);
    /* Capped at the maximum, at least one. */
    cr_expect_float_eq(terrain__multifractal_octaves(2.0f, 0.5f, 1e-6f, 10), 10.0f, 0.0f);
    cr_expect_float_eq(terrain__multifractal_octaves(2.0f, 0.5f, 4.0f, 10), 1.0f, 0.0f);
}

Test(terrain_noise, multifractal_fractional_octave_interpolates) {
    /* The last octave is weighted by frac(ν) (004 §4), in the sum and in the normalisation.
     * With a = r^−H, the normalising totals are T(2) = 1 + a, T(3) = 1 + a + a²,
     * T(2.5) = 1 + a + a²/2, and the unnormalised sums U = value·T satisfy
     * U(2.5) = (U(2) + U(3)) / 2 — the warp state an octave sees comes from the octaves before
     * it, the same in all three. */
    terrain__multifractal mf = { .seed = 99, .lacunarity = 2.0f, .hurst = 0.8f, .warp = 1.0f };
    float a = powf(2.0f, -0.8f);
    float t2 = 1 + a, t3 = 1 + a + a * a, t25 = 1 + a + 0.5f * a * a;
    uint64_t state = 4;
    for (int n = 0; n < 200; n++) {
        float x = next_coordinate(&state, 20.0f), z = next_coordinate(&state, 20.0f);
        mf.octaves = 2.0f;
        float u2 = terrain__multifractal2(&mf, x, 0.0f, z) * t2;
        mf.octaves = 3.0f;
        float u3 = terrain__multifractal2(&mf, x, 0.0f, z) * t3;
        mf.octaves = 2.5f;
        float u25 = terrain__multifractal2(&mf, x, 0.0f, z) * t25;
        cr_assert_float_eq(u25, 0.5f * (u2 + u3), 1e-5f, "at (%g, %g)", x, z);
    }
}

Test(terrain_noise, multifractal_row_equals_scalar_and_is_bounded) {
    terrain__multifractal mf = { .seed = 3, .lacunarity = 2.0f, .hurst = 0.85f, .octaves = 8.5f, .warp = 1.0f };
    float dxs[37], out[37];
    uint64_t state = 8;
    for (int trial = 0; trial < 10; trial++) {
        double x0 = next_coordinate(&state, 50.0f), z = next_coordinate(&state, 50.0f);
        for (int j = 0; j < 37; j++) dxs[j] = next_coordinate(&state, 0.5f);
        terrain__multifractal2_row(&mf, x0, dxs, z, 37, out);
        for (int j = 0; j < 37; j++) {
            cr_assert_eq(out[j], terrain__multifractal2(&mf, x0, dxs[j], z), "point %d", j);
            /* Each octave's noise is within ±1 and the sum is normalised by its amplitudes. */
            cr_assert(fabsf(out[j]) <= 1.0f + 1e-5f);
        }
    }
}

Test(terrain_noise, multifractal_warp_changes_it_continuously) {
    terrain__multifractal plain = { .seed = 3, .lacunarity = 2.0f, .hurst = 0.85f, .octaves = 6.0f, .warp = 0.0f };
    terrain__multifractal warped = plain;
    warped.warp = 1.0f;
    uint64_t state = 12;
    int differ = 0;
    for (int n = 0; n < 500; n++) {
        float x = next_coordinate(&state, 20.0f), z = next_coordinate(&state, 20.0f);
        float v = terrain__multifractal2(&warped, x, 0.0f, z);
        if (v != terrain__multifractal2(&plain, x, 0.0f, z)) differ++;
        /* The warp is a continuous offset: no jumps at a step of 10⁻⁴ wavelengths. With 6
         * octaves at r = 2 the steepest octave has slope about 2⁵·8·r^(−5H) per wavelength. */
        float step = terrain__multifractal2(&warped, x, 1e-4f, z) - v;
        cr_assert(fabsf(step) < 0.05f, "jump %g at (%g, %g)", step, x, z);
    }
    cr_expect_gt(differ, 450);
}
