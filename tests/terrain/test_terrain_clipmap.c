/* Geometry clipmaps for the far terrain (002 §3.2, §3.5): heights are the generator's ground at
 * the level's spacing and lie within the generator's own bound of the stacks' top, and under the
 * sea within what the octaves the spacing drops can change of the columns' ground; incremental
 * updates equal fresh builds; finer borders lie on coarser edges (no T-junction gaps); levels
 * nest on each other's vertex lines anywhere in the world; culling keeps what can be seen. */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A small clipmap keeps the debug build's tests quick; the code has no special case for size. */
static terrain_clipmap *small_clipmap(uint64_t seed, int levels, int cells, float spacing, job_system *jobs) {
    return terrain_clipmap_create(&(terrain_clipmap_desc){ .levels = levels, .cells = cells, .finest_spacing = spacing,
                                                           .generation = terrain_generation_defaults(seed), .jobs = jobs });
}

/* Every texel a level holds: its vertices and one more ring. */
#define FOR_WINDOW(info, i, k)                                                              \
    for (int64_t k = (info).first[1] - 1; k <= (info).first[1] + (info).cells + 1; k++)     \
        for (int64_t i = (info).first[0] - 1; i <= (info).first[0] + (info).cells + 1; i++)

/* ---- heights ---- */

Test(terrain_clipmap, texels_are_the_ground_at_the_levels_spacing) {
    terrain_clipmap *c = small_clipmap(42, 4, 32, 4.0f, NULL);
    terrain_generation_desc p = terrain_generation_defaults(42);
    uint64_t texels = terrain_clipmap_update(c, (double[3]){ 123.4, 50.0, -987.6 });
    cr_assert_eq(texels, 4u * 35u * 35u, "the first update computes every level's window");
    float previous_octaves = 100;
    for (int l = 0; l < 4; l++) {
        terrain__clipmap_level_info info = terrain__clipmap_level(c, l);
        cr_assert_eq(info.spacing, 4.0 * (1 << l));
        /* 004 §4.1 as terrain_generate.c reads it: ν = log(λ/4s) / log r, no octave shorter than
         * four texels; one octave fewer at every coarser level (6.23, 5.23, 4.23, 3.23 from 4 m). */
        float expected = logf(p.relief_wavelength / (4.0f * (float)info.spacing)) / logf(p.lacunarity);
        cr_assert_float_eq(info.octaves, fmaxf(expected, 1.0f), 1e-4, "level %d: %f octaves", l, info.octaves);
        cr_assert_float_eq(info.octaves, 6.2288f - (float)l, 1e-3, "level %d: %f octaves", l, info.octaves);
        cr_assert_lt(info.octaves, previous_octaves);
        previous_octaves = info.octaves;
        float row[64];
        for (int64_t k = info.first[1] - 1; k <= info.first[1] + info.cells + 1; k++) {
            int count = info.cells + 3;
            terrain__ground_row_spaced(&p, (double)(info.first[0] - 1) * info.spacing, info.spacing,
                                       (double)k * info.spacing, count, (float)info.spacing, row, NULL);
            for (int j = 0; j < count; j++)
                cr_assert_eq(terrain__clipmap_texel(c, l, info.first[0] - 1 + j, k), row[j], "level %d texel (%lld, %lld)", l,
                             (long long)(info.first[0] - 1 + j), (long long)k);
        }
    }
    cr_assert(isnan(terrain__clipmap_texel(c, 0, terrain__clipmap_level(c, 0).first[0] - 2, 0)), "outside the window");
    terrain_clipmap_destroy(c);
}

Test(terrain_clipmap, at_column_spacing_the_texels_are_the_generators_ground_bit_for_bit) {
    terrain_clipmap *c = small_clipmap(7, 2, 16, TERRAIN_COLUMN_SIZE, NULL);
    terrain_generation_desc p = terrain_generation_defaults(7);
    terrain_clipmap_update(c, (double[3]){ -3000.2, 0, 411.7 });
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    FOR_WINDOW(info, i, k)
        cr_assert_eq(terrain__clipmap_texel(c, 0, i, k), terrain__ground_height(&p, (double)i, (double)k));
    terrain_clipmap_destroy(c);
}

static int compare_floats(const void *a, const void *b) {
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Largest |∇G| (1 m differences of the column ground) over the disc of radius r around (x, z). */
static float ground_slope_max(const terrain_generation_desc *p, double x, double z, int r) {
    float grid[2 * 16 + 3][2 * 16 + 3];
    int size = 2 * r + 3;
    for (int k = 0; k < size; k++)
        terrain__ground_row_spaced(p, x - r - 1, 1.0, z - r - 1 + k, size, 1.0f, grid[k], NULL);
    float slope = 0;
    for (int k = 1; k + 1 < size; k++)
        for (int i = 1; i + 1 < size; i++) {
            if ((i - r - 1) * (i - r - 1) + (k - r - 1) * (k - r - 1) > r * r) continue;
            float gx = 0.5f * (grid[k][i + 1] - grid[k][i - 1]), gz = 0.5f * (grid[k + 1][i] - grid[k - 1][i]);
            slope = fmaxf(slope, sqrtf(gx * gx + gz * gz));
        }
    return slope;
}

/* Σ of the multifractal's octave weights r^(−kH) for ν octaves, the last weighted by frac ν. */
static double octave_weights(const terrain_generation_desc *p, float octaves) {
    double r0 = pow(p->lacunarity, -p->hurst), sum = 0.0;
    int full = (int)octaves;
    for (int k = 0; k < full; k++) sum += pow(r0, k);
    return sum + (octaves - (float)full) * pow(r0, full);
}

/* How far the clipmap's G at 4 m can be from the columns' G under the sea, from the octaves the
 * spacing drops (004 §4.1). The 4 m ground keeps octaves 0 … ⌊ν₄⌋ (the last weighted frac ν₄)
 * of the columns' 0 … ⌊ν₁⌋, each the same noise under the same warp (an octave's warp comes from
 * the octaves before it), and rescales the sum by Σ kept / Σ all: the normalised relief M moves
 * by at most (Σ all − Σ kept) / Σ all, |noise| ≤ 1. At 4 m the y perturbation's two octaves
 * (48 and 24 m, ≥ 4 spacings) and the cliffs stay whole. Where the macro height lies under the
 * sea at both spacings there are no cliffs and the shape is linear, 0.6·m with m = 2.5·M, so
 *     |G₄ − G₁| ≤ relief · 0.6 · 2.5 · (Σ all − Σ kept) / Σ all.
 * G = macro + V·fbm with |fbm| ≤ 1, so G₁ < sea − V − that bound puts both macro heights under
 * the sea. On land the terraces can steepen M's change ninefold: no bound worth testing. */
static float dropped_octaves_bound_under_sea(const terrain_generation_desc *p) {
    double all = octave_weights(p, terrain__ground_octaves(p, TERRAIN_COLUMN_SIZE));
    double kept = octave_weights(p, terrain__ground_octaves(p, 4.0f));
    return (float)(p->relief_height * 0.6 * 2.5 * (all - kept) / all) + 1e-3f;   /* + float rounding */
}

static bool deep_under_the_sea(const terrain_generation_desc *p, float g1, float dropped) {
    return g1 < p->sea_level - p->vertical_perturbation - dropped;
}

Test(terrain_clipmap, under_the_sea_the_4m_ground_differs_only_by_the_octaves_it_drops) {
    terrain_generation_desc p = terrain_generation_defaults(42);
    float dropped = dropped_octaves_bound_under_sea(&p), worst = 0.0f;
    int sea = 0;
    for (int k = 0; k < 32; k++)
        for (int i = 0; i < 32; i++) {
            double x = -2003.7 + 121.3 * i, z = 1501.1 - 109.9 * k;
            float g1, g4;
            terrain__ground_row_spaced(&p, x, 1.0, z, 1, 1.0f, &g1, NULL);
            terrain__ground_row_spaced(&p, x, 4.0, z, 1, 4.0f, &g4, NULL);
            if (!deep_under_the_sea(&p, g1, dropped)) continue;
            sea++;
            worst = fmaxf(worst, fabsf(g4 - g1));
            cr_expect_leq(fabsf(g4 - g1), dropped, "(%.1f, %.1f): G₁ %.3f, G₄ %.3f, bound %.3f", x, z, (double)g1, (double)g4,
                          (double)dropped);
        }
    printf("under the sea (%d of 1024 points): |G4 - G1| at most %.3f m, bound %.3f m\n", sea, (double)worst, (double)dropped);
    cr_expect_geq(sea, 60, "too few points under the sea for the test to say anything");
}

/* The stacks' top is G at the sample point moved sideways by A·(u, w), |u|, |w| ≤ 1 (002 Fig. 8;
 * terrain_generate.c), so |top − G| ≤ A·√2·max|∇G| within A·√2, plus half a height quantum for
 * the packing and a few centimetres for the generator's linear placement of the crossing
 * between 1 m density samples. 1 m differences under-estimate the steepest gradient by the
 * detail finer than a metre: a margin of 25 % on the slope. The clipmap's G at spacing s
 * differs from the columns' G by the octaves the spacing drops (004 §4.1): bounded from their
 * weights where the ground lies deep under the sea (above), a regression guard elsewhere.
 * Caves are switched off: a cave mouth cuts the top, and the clipmap does not draw caves. */
Test(terrain_clipmap, heights_match_the_stacks_top_within_the_generators_bound) {
    terrain_generation_desc p = terrain_generation_defaults(42);
    p.cave_threshold = 0.0f;
    const float a = p.horizontal_perturbation, quantum = TERRAIN_HEIGHT_QUANTUM;
    const int reach = (int)ceilf(a * 1.41422f);
    enum { CHUNKS = 6, PER_CHUNK = 9 };
    float errors_1m[CHUNKS * PER_CHUNK], errors_4m[CHUNKS * PER_CHUNK], errors_drawn[CHUNKS * PER_CHUNK];
    float slopes[CHUNKS * PER_CHUNK], worst_ratio = 0, worst_gentle_1m = 0, worst_gentle_4m = 0;
    int count = 0;
    const float dropped = dropped_octaves_bound_under_sea(&p);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = p });
    /* What is drawn: level 0 of a clipmap of the default spacing around each chunk. */
    terrain_clipmap *level0 = terrain_clipmap_create(&(terrain_clipmap_desc){ .levels = 1, .cells = 32, .generation = p });
    for (int chunk = 0; chunk < CHUNKS; chunk++) {
        terrain_chunk_coord coord = { chunk * 5 - 13, 7 - chunk * 3 };
        const terrain_stacks *s = terrain_world_stacks(world, coord);
        terrain_clipmap_update(level0, (double[3]){ coord.x * 32.0 + 16.0, 0.0, coord.z * 32.0 + 16.0 });
        for (int sample = 0; sample < PER_CHUNK; sample++, count++) {
            int i = 4 + (sample % 3) * 11, k = 4 + (sample / 3) * 11;
            double x = (double)coord.x * TERRAIN_CHUNK_COLUMNS + i + 0.5, z = (double)coord.z * TERRAIN_CHUNK_COLUMNS + k + 0.5;
            float top = terrain_stacks_top(s, i, k), g1, g4;
            terrain__ground_row_spaced(&p, x, 1.0, z, 1, 1.0f, &g1, NULL);
            terrain__ground_row_spaced(&p, x, 4.0, z, 1, 4.0f, &g4, NULL);
            slopes[count] = ground_slope_max(&p, x, z, reach);
            float bound = a * 1.41422f * 1.25f * slopes[count] + 0.5f * quantum + 0.05f;
            errors_1m[count] = fabsf(top - g1);
            errors_4m[count] = fabsf(top - g4);
            errors_drawn[count] = fabsf(top - terrain_clipmap_height(level0, x, z));
            cr_expect_leq(errors_1m[count], bound, "(%.1f, %.1f): top %.3f, G %.3f, bound %.3f", x, z, top, g1, bound);
            /* The 4 m ground within the dropped octaves' reach of the 1 m ground where that has a
             * bound (|top − G₄| ≤ bound + it then follows). */
            if (deep_under_the_sea(&p, g1, dropped))
                cr_expect_leq(fabsf(g4 - g1), dropped, "(%.1f, %.1f) at 4 m: %.3f from the 1 m ground", x, z, (double)fabsf(g4 - g1));
            worst_ratio = fmaxf(worst_ratio, errors_1m[count] / bound);
        }
    }
    terrain_clipmap_destroy(level0);
    terrain_world_destroy(world);
    /* The gentler half of the points (by the slope around them) says what a flat stretch gets. */
    float sorted_slopes[CHUNKS * PER_CHUNK];
    memcpy(sorted_slopes, slopes, sizeof slopes);
    qsort(sorted_slopes, (size_t)count, sizeof(float), compare_floats);
    for (int n = 0; n < count; n++)
        if (slopes[n] <= sorted_slopes[count / 2]) {
            worst_gentle_1m = fmaxf(worst_gentle_1m, errors_1m[n]);
            worst_gentle_4m = fmaxf(worst_gentle_4m, errors_4m[n]);
        }
    qsort(errors_1m, (size_t)count, sizeof(float), compare_floats);
    qsort(errors_4m, (size_t)count, sizeof(float), compare_floats);
    qsort(errors_drawn, (size_t)count, sizeof(float), compare_floats);
    printf("clipmap vs stacks top over %d columns: |top - G(1 m)| median %.2f max %.2f m (gentle half max %.2f), "
           "|top - G(4 m)| median %.2f max %.2f m (gentle half max %.2f), drawn at 4 m median %.2f max %.2f m; "
           "worst share of the bound %.2f\n",
           count, errors_1m[count / 2], errors_1m[count - 1], worst_gentle_1m, errors_4m[count / 2], errors_4m[count - 1],
           worst_gentle_4m, errors_drawn[count / 2], errors_drawn[count - 1], worst_ratio);
    /* A regression guard on what the far view shows: the typical column within a metre or so. */
    cr_expect_lt(errors_4m[count / 2], 1.5f);
    cr_expect_lt(errors_drawn[count / 2], 1.5f);
}

/* ---- incremental updates ---- */

static void expect_same_texels(terrain_clipmap *updated, terrain_clipmap *fresh, int levels, const double camera[3]) {
    for (int l = 0; l < levels; l++) {
        terrain__clipmap_level_info a = terrain__clipmap_level(updated, l), b = terrain__clipmap_level(fresh, l);
        cr_assert_eq(a.first[0], b.first[0]);
        cr_assert_eq(a.first[1], b.first[1]);
        FOR_WINDOW(a, i, k) {
            float x = terrain__clipmap_texel(updated, l, i, k), y = terrain__clipmap_texel(fresh, l, i, k);
            cr_assert(x == y, "camera (%.1f, %.1f) level %d texel (%lld, %lld): %f != %f", camera[0], camera[2], l,
                      (long long)i, (long long)k, x, y);
        }
    }
}

static void random_walk(job_system *jobs) {
    const int levels = 4, cells = 32;
    terrain_clipmap *c = small_clipmap(3, levels, cells, 4.0f, jobs);
    double camera[3] = { -50.0, 30.0, 77.0 };
    uint64_t state = 99;
    uint64_t full = (uint64_t)levels * (cells + 3) * (cells + 3);
    for (int step = 0; step < 40; step++) {
        state = core_hash_u64(state);
        double scale = step % 10 == 9 ? 3000.0 : step % 3 == 2 ? 90.0 : 9.0;   /* walks, runs and jumps */
        camera[0] += ((double)(state & 0xffff) / 65536.0 - 0.5) * 2.0 * scale;
        camera[2] += ((double)((state >> 16) & 0xffff) / 65536.0 - 0.5) * 2.0 * scale;
        if (step == 20) camera[0] = -100000.3, camera[2] = -99999.1;           /* far out, negative */
        uint64_t texels = terrain_clipmap_update(c, camera);
        if (scale == 9.0 && step != 0 && step != 20) cr_assert_lt(texels, full / 3, "a short walk recomputes a few rows: %llu", (unsigned long long)texels);
        terrain_clipmap *fresh = small_clipmap(3, levels, cells, 4.0f, NULL);
        cr_assert_eq(terrain_clipmap_update(fresh, camera), full);
        expect_same_texels(c, fresh, levels, camera);
        terrain_clipmap_destroy(fresh);
    }
    terrain_clipmap_destroy(c);
}

Test(terrain_clipmap, incremental_updates_equal_fresh_builds_on_a_random_walk) { random_walk(NULL); }

Test(terrain_clipmap, incremental_updates_on_the_job_system_equal_fresh_builds) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    random_walk(jobs);
    job_system_destroy(jobs);
}

/* ---- nesting and seams ---- */

static double random_coordinate(uint64_t *state, double range) {
    *state = core_hash_u64(*state);
    return ((double)(*state >> 11) / 9007199254740992.0 - 0.5) * 2.0 * range;
}

Test(terrain_clipmap, footprints_nest_on_the_coarser_levels_vertex_lines_anywhere) {
    const int levels = 8, cells = 16;
    terrain_clipmap *c = small_clipmap(5, levels, cells, 4.0f, NULL);
    uint64_t state = 1;
    for (int trial = 0; trial < 40; trial++) {
        double range = trial < 20 ? 3000.0 : 100000.0;
        double camera[3] = { random_coordinate(&state, range), 20.0, random_coordinate(&state, range) };
        terrain_clipmap_update(c, camera);
        for (int l = 0; l < levels; l++) {
            terrain__clipmap_level_info info = terrain__clipmap_level(c, l);
            double s = info.spacing;
            for (int axis = 0; axis < 2; axis++) {
                double lo = (double)info.first[axis] * s, hi = lo + cells * s, eye = camera[axis ? 2 : 0];
                /* The camera is near the level's centre: level 0 within s, each coarser level at
                 * most one of its cells further. */
                cr_assert_leq(fabs(0.5 * (lo + hi) - eye), 4.0 * (ldexp(1.0, l + 1) - 1.0), "level %d axis %d", l, axis);
                if (l + 1 == levels) continue;
                terrain__clipmap_level_info coarse = terrain__clipmap_level(c, l + 1);
                double coarse_lo = (double)coarse.first[axis] * coarse.spacing;
                /* Inside the coarser level, a quarter of it in from each side (± one cell), and
                 * both edges on its vertex lines. */
                double in_cells = (lo - coarse_lo) / coarse.spacing;
                cr_assert(in_cells == cells / 4 || in_cells == cells / 4 + 1, "level %d in %d: %f cells in", l, l + 1, in_cells);
                cr_assert_eq(fmod(lo / coarse.spacing, 1.0), 0.0);
                cr_assert_eq(fmod(hi / coarse.spacing, 1.0), 0.0);
                cr_assert_leq(hi, coarse_lo + cells * coarse.spacing - cells / 4 * coarse.spacing + coarse.spacing);
            }
        }
    }
    terrain_clipmap_destroy(c);
}

/* For every finer-level border vertex: its camera-relative position and drawn height are those
 * of the coarser level's vertex at the same place, or exactly the midpoint of the coarser edge
 * it sits on. The camera at draw time is not the one of the update (the player moved on). */
static void check_seams(terrain_clipmap *c, int levels, int cells, const double update_camera[3], const double draw_camera[3]) {
    terrain_clipmap_update(c, update_camera);
    double reach = terrain_clipmap_stats(c).reach;
    for (int l = 0; l + 1 < levels; l++) {
        terrain__clipmap_level_info fine = terrain__clipmap_level(c, l), coarse = terrain__clipmap_level(c, l + 1);
        for (int e = 0; e < 4 * (cells + 1); e++) {
            int side = e / (cells + 1), t = e % (cells + 1);
            int i = side < 2 ? t : side == 2 ? 0 : cells;
            int k = side == 0 ? 0 : side == 1 ? cells : t;
            float p[2], h;
            terrain__clipmap_vertex(c, l, i, k, draw_camera, p, &h);
            cr_assert_lt(fabsf(p[0]), reach * 1.5, "positions reach the GPU camera-relative and small");
            int64_t gx = fine.first[0] + i, gz = fine.first[1] + k;          /* in fine spacings */
            int ci = (int)((gx - (gx & 1)) / 2 - coarse.first[0]), ck = (int)((gz - (gz & 1)) / 2 - coarse.first[1]);
            if (gx % 2 == 0 && gz % 2 == 0) {
                float q[2], hc;
                terrain__clipmap_vertex(c, l + 1, ci, ck, draw_camera, q, &hc);
                cr_assert(p[0] == q[0] && p[1] == q[1], "level %d vertex (%d, %d): at (%.9g, %.9g), coarse (%.9g, %.9g)", l, i, k,
                          p[0], p[1], q[0], q[1]);
                cr_assert(h == hc, "level %d vertex (%d, %d): height %.9g, coarse %.9g", l, i, k, h, hc);
            } else {
                float q0[2], q1[2], h0, h1;
                int di = (int)(gx & 1), dk = (int)(gz & 1);
                terrain__clipmap_vertex(c, l + 1, ci, ck, draw_camera, q0, &h0);
                terrain__clipmap_vertex(c, l + 1, ci + di, ck + dk, draw_camera, q1, &h1);
                cr_assert(p[0] == 0.5f * (q0[0] + q1[0]) && p[1] == 0.5f * (q0[1] + q1[1]), "level %d vertex (%d, %d)", l, i, k);
                cr_assert(h == 0.5f * (h0 + h1), "level %d vertex (%d, %d): height %.9g, coarse edge %.9g … %.9g", l, i, k, h, h0, h1);
            }
        }
    }
}

Test(terrain_clipmap, finer_borders_lie_on_the_coarser_edges) {
    const int levels = 5, cells = 32;
    terrain_clipmap *c = small_clipmap(11, levels, cells, 4.0f, NULL);
    const double cameras[][3] = { { 0, 40, 0 }, { 1234.5, 80, -777.25 }, { -100003.7, 60, 100011.2 }, { 3.9, 10, 4.1 } };
    for (size_t n = 0; n < CORE_COUNTOF(cameras); n++) {
        check_seams(c, levels, cells, cameras[n], cameras[n]);
        const double moved[3] = { cameras[n][0] + 37.0, cameras[n][1], cameras[n][2] - 21.0 };
        check_seams(c, levels, cells, cameras[n], moved);
    }
    terrain_clipmap_destroy(c);
}

Test(terrain_clipmap, morph_is_zero_inside_one_at_the_border_and_continuous) {
    /* By hand: start 100 m, width 20 m. */
    cr_assert_eq(terrain__clipmap_morph(50, -99, 100, 0.05f, false), 0.0f);
    cr_assert_float_eq(terrain__clipmap_morph(-110, 30, 100, 0.05f, false), 0.5f, 1e-6);
    cr_assert_eq(terrain__clipmap_morph(20, 120, 100, 0.05f, false), 1.0f);
    cr_assert_eq(terrain__clipmap_morph(0, 0, 100, 0.05f, true), 1.0f);
    /* The drawn level 0 equals its texels where the morph is 0 (around the camera). */
    terrain_clipmap *c = small_clipmap(2, 3, 32, 4.0f, NULL);
    const double camera[3] = { 10, 20, 30 };
    terrain_clipmap_update(c, camera);
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    for (int k = 12; k <= 20; k++)
        for (int i = 12; i <= 20; i++) {
            float p[2], h;
            terrain__clipmap_vertex(c, 0, i, k, camera, p, &h);
            cr_assert_eq(h, terrain__clipmap_texel(c, 0, info.first[0] + i, info.first[1] + k));
        }
    cr_assert_gt(info.morph_start, 0.0f, "the transition lies inside the level");
    cr_assert_leq(info.morph_start + info.morph_width, 0.5f * 32 * 4 - 4.0f, "and ends where the border may be nearest");
    terrain_clipmap_destroy(c);
}

Test(terrain_clipmap, height_follows_the_finest_level_and_is_nan_outside) {
    terrain_clipmap *c = small_clipmap(4, 3, 32, 4.0f, NULL);
    cr_assert(isnan(terrain_clipmap_height(c, 0, 0)), "before the first update");
    const double camera[3] = { 501.0, 30.0, -250.0 };
    terrain_clipmap_update(c, camera);
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    /* At a vertex of level 0 near the camera: its texel; halfway along a cell's edge: the mean. */
    double x = (double)(info.first[0] + 16) * 4.0, z = (double)(info.first[1] + 15) * 4.0;
    float h00 = terrain__clipmap_texel(c, 0, info.first[0] + 16, info.first[1] + 15);
    float h10 = terrain__clipmap_texel(c, 0, info.first[0] + 17, info.first[1] + 15);
    cr_assert_float_eq(terrain_clipmap_height(c, x, z), h00, 1e-4);
    cr_assert_float_eq(terrain_clipmap_height(c, x + 2.0, z), 0.5f * (h00 + h10), 1e-4);
    /* Far out only the outermost level covers (it reaches 32·16/2 = 256 m, less its offset). */
    cr_assert(!isnan(terrain_clipmap_height(c, camera[0] + 200.0, camera[2])));
    cr_assert(isnan(terrain_clipmap_height(c, camera[0] + 400.0, camera[2])));
    terrain_clipmap_destroy(c);
}

/* ---- culling ---- */

Test(terrain_clipmap, culling_drops_blocks_behind_and_keeps_the_one_under_the_camera) {
    const int levels = 4;
    terrain_clipmap *c = small_clipmap(8, levels, 64, 4.0f, NULL);
    double camera[3] = { 2000.0, 0.0, -3000.0 };
    terrain_clipmap_update(c, camera);
    camera[1] = terrain_clipmap_height(c, camera[0], camera[2]) + 0.5;   /* standing on it */
    int total = 0;
    for (int l = 0; l < levels; l++)
        for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) total += !terrain__clipmap_block(c, l, b).covered;
    /* The finer level covers the middle half of each axis: the split long segments either side
     * of the one-cell strip at n/4 or n/4 + 1 (2·SPLIT + 1 segments across). */
    const int middle = 2 * TERRAIN__CLIPMAP_SPLIT + 1;
    cr_assert_eq(total, levels * TERRAIN__CLIPMAP_BLOCKS - (levels - 1) * middle * middle,
                 "each coarser level leaves %d × %d blocks to the finer", middle, middle);

    /* Looking north (−z), level: nothing wholly behind the camera is kept. */
    terrain_view view = { .camera = { camera[0], camera[1], camera[2] }, .aspect = 16.0f / 9.0f };
    terrain_frustum frustum = terrain_frustum_from_view(&view);
    int visible = terrain_clipmap_cull(c, &frustum);
    cr_assert_gt(visible, 0);
    /* Fewer than those not wholly behind the camera: the ~90° wide view drops blocks to the sides
     * too. (About half of all: "under half" failed by one block, 59 of 117, once the coarse levels
     * kept the octaves their spacing carries, 004 §4.1, and their bounds grew taller.) */
    int ahead = 0;
    for (int l = 0; l < levels; l++)
        for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) {
            terrain__clipmap_block_info info = terrain__clipmap_block(c, l, b);
            ahead += !info.covered && info.box_min[2] < camera[2];
        }
    cr_assert_lt(visible, ahead, "%d of %d blocks kept looking one way, %d not behind", visible, total, ahead);
    cr_assert_eq(terrain_clipmap_stats(c).blocks_visible, visible);
    for (int l = 0; l < levels; l++)
        for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) {
            terrain__clipmap_block_info info = terrain__clipmap_block(c, l, b);
            if (info.visible) cr_assert_lt(info.box_min[2], camera[2], "level %d block %d lies behind", l, b);
        }

    /* Any direction: the block under the camera stays. */
    uint64_t state = 5;
    for (int trial = 0; trial < 24; trial++) {
        view.yaw = (float)random_coordinate(&state, 3.14159);
        view.pitch = (float)random_coordinate(&state, 1.5);
        frustum = terrain_frustum_from_view(&view);
        terrain_clipmap_cull(c, &frustum);
        bool found = false;
        for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) {
            terrain__clipmap_block_info info = terrain__clipmap_block(c, 0, b);
            bool under = camera[0] >= info.box_min[0] && camera[0] <= info.box_max[0] && camera[2] >= info.box_min[2] &&
                         camera[2] <= info.box_max[2];
            if (!under) continue;
            found = true;
            cr_assert(info.visible, "yaw %.2f pitch %.2f culled block %d under the camera", view.yaw, view.pitch, b);
        }
        cr_assert(found);
    }

    /* A hole over the middle of level 0: the blocks reaching into it are drawn sunk there (the pit
     * under the volumetric chunks), so their bounds reach down by hole_depth; none is skipped. */
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    double lo[2] = { (double)(info.first[0] + 10) * 4.0, (double)(info.first[1] + 10) * 4.0 };
    double hi[2] = { (double)(info.first[0] + 30) * 4.0, (double)(info.first[1] + 30) * 4.0 };
    terrain__clipmap_block_info before[TERRAIN__CLIPMAP_BLOCKS];
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) before[b] = terrain__clipmap_block(c, 0, b);
    terrain_clipmap_set_hole(c, lo, hi);
    int sunk = 0;
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) {
        terrain__clipmap_block_info block = terrain__clipmap_block(c, 0, b);
        /* Cells [10, 30) on both axes; a block's box has one cell more around. */
        bool reaches = block.cells_max[0] + 1 > 10 && block.cells_min[0] - 1 < 30 && block.cells_max[1] + 1 > 10 &&
                       block.cells_min[1] - 1 < 30;
        cr_assert_not(block.covered);
        /* 156 m: the default pit below the generator's caves (12 + 1.5·64 + 48). */
        cr_assert_float_eq(block.box_min[1], before[b].box_min[1] - (reaches ? 156.0 : 0.0), 1e-3, "block %d", b);
        sunk += reaches;
    }
    /* Cuts at 0, 8, 16, 17, 24, 32, 40, …: segments 1–4 ([8, 16) … [24, 32)) reach [10, 30). */
    _Static_assert(TERRAIN__CLIPMAP_SPLIT == 2, "the counts here are worked out for long segments split in two");
    cr_assert_eq(sunk, 16, "the blocks of segments 1–4 along both axes");
    terrain_clipmap_set_hole(c, hi, lo);   /* min ≥ max: no hole */
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) cr_assert_eq(terrain__clipmap_block(c, 0, b).box_min[1], before[b].box_min[1]);
    terrain_clipmap_destroy(c);
}

/* A level wholly inside a hole is all pit (the game's level 0 is the rings' hole itself): it is
 * not drawn, and the next coarser level draws its middle, sunk, in its place. A hole that leaves
 * any of the level outside changes nothing. */
static int blocks_drawn_at(const terrain_clipmap *c, int level) {
    int drawn = 0;
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) drawn += !terrain__clipmap_block(c, level, b).covered;
    return drawn;
}

Test(terrain_clipmap, a_level_inside_a_hole_is_left_to_the_coarser_one) {
    const int levels = 3, all = TERRAIN__CLIPMAP_BLOCKS, middle = 2 * TERRAIN__CLIPMAP_SPLIT + 1;
    terrain_clipmap *c = small_clipmap(8, levels, 64, 4.0f, NULL);
    terrain_clipmap_update(c, (const double[3]){ 300.0, 0.0, -700.0 });
    terrain__clipmap_level_info fine = terrain__clipmap_level(c, 0);
    const double lo[2] = { (double)fine.first[0] * 4.0, (double)fine.first[1] * 4.0 };
    const double hi[2] = { lo[0] + 64 * 4.0, lo[1] + 64 * 4.0 };
    cr_assert_eq(blocks_drawn_at(c, 0), all);
    cr_assert_eq(blocks_drawn_at(c, 1), all - middle * middle);
    terrain__clipmap_block_info before[TERRAIN__CLIPMAP_BLOCKS];
    for (int b = 0; b < all; b++) before[b] = terrain__clipmap_block(c, 1, b);

    /* Exactly level 0's square, and a wider one: level 0 is buried in both. */
    for (int wider = 0; wider < 2; wider++) {
        const double m = wider ? 40.0 : 0.0;
        terrain_clipmap_set_hole(c, (const double[2]){ lo[0] - m, lo[1] - m }, (const double[2]){ hi[0] + m, hi[1] + m });
        cr_assert_eq(blocks_drawn_at(c, 0), 0, "level 0 lies in the hole: none of it is drawn");
        cr_assert_eq(blocks_drawn_at(c, 1), all, "level 1 draws its middle too");
        cr_assert_eq(blocks_drawn_at(c, 2), all - middle * middle, "level 2 is unchanged");
        /* Level 1's middle blocks lie in the hole: their boxes reach down to the pit's floor
         * (156 m: 12 + 1.5·64 + 48, the default below the generator's caves). */
        for (int b = 0; b < all; b++)
            if (before[b].covered) cr_assert_float_eq(terrain__clipmap_block(c, 1, b).box_min[1], before[b].box_min[1] - 156.0, 1e-3);
    }

    /* One cell of level 0 outside the hole, on any side: level 0 draws as before. */
    for (int side = 0; side < 4; side++) {
        double a[2] = { lo[0], lo[1] }, z[2] = { hi[0], hi[1] };
        if (side < 2) a[side] += 4.0;
        else z[side - 2] -= 4.0;
        terrain_clipmap_set_hole(c, a, z);
        cr_assert_eq(blocks_drawn_at(c, 0), all, "side %d", side);
        cr_assert_eq(blocks_drawn_at(c, 1), all - middle * middle, "side %d", side);
    }
    terrain_clipmap_destroy(c);
}

/* ---- holes: one pit per viewer's rings (002 §3.5) ---- */

#define PIT_BAND 8.0f      /* two level-0 cells */
#define PIT_DEPTH 100.0f

/* A hole over level-0 cells [lo, hi) along x and z, in cell indices of the level's grid. */
typedef struct cell_rect {
    int lo[2], hi[2];
} cell_rect;

static terrain_clipmap *pit_clipmap(const double camera[3]) {
    terrain_clipmap *c = terrain_clipmap_create(&(terrain_clipmap_desc){
        .levels = 2, .cells = 64, .finest_spacing = 4.0f, .hole_band = PIT_BAND, .hole_depth = PIT_DEPTH,
        .generation = terrain_generation_defaults(3) });
    terrain_clipmap_update(c, camera);
    return c;
}

static void set_cell_holes(terrain_clipmap *c, const cell_rect *rects, int count) {
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    double lo[16][2], hi[16][2];
    for (int h = 0; h < count; h++)
        for (int a = 0; a < 2; a++) {
            lo[h][a] = (double)(info.first[a] + rects[h].lo[a]) * 4.0;
            hi[h][a] = (double)(info.first[a] + rects[h].hi[a]) * 4.0;
        }
    terrain_clipmap_set_holes(c, lo, hi, count);
}

/* Level-0 cells from vertex (i, k) inside the rectangle to its nearest side (≤ 0 outside). */
static int cells_inside(const cell_rect *r, int i, int k) {
    return CORE_MIN(CORE_MIN(i - r->lo[0], r->hi[0] - i), CORE_MIN(k - r->lo[1], r->hi[1] - k));
}

/* The pit's depth d cells from the border of the sunk area: a wall over the band, then the floor. */
static float pit_at(int d) { return d <= 0 ? 0.0f : PIT_DEPTH * fminf((float)d * 4.0f / PIT_BAND, 1.0f); }

/* What clipmap.vert sinks level-0 vertex (i, k) by, through the CPU mirror. */
static float vertex_sink(const terrain_clipmap *c, const double camera[3], int i, int k) {
    float p[2], h;
    terrain__clipmap_vertex(c, 0, i, k, camera, p, &h);
    return terrain__clipmap_sink(c, camera, p);
}

static bool block_reaches(const terrain__clipmap_block_info *b, const cell_rect *r) {
    /* A block's box has one cell more around it. */
    return b->cells_max[0] + 1 > r->lo[0] && b->cells_min[0] - 1 < r->hi[0] && b->cells_max[1] + 1 > r->lo[1] &&
           b->cells_min[1] - 1 < r->hi[1];
}

Test(terrain_clipmap, two_disjoint_holes_sink_inside_either_and_nowhere_else) {
    const double camera[3] = { 2000.0, 0.0, -3000.0 };   /* multiples of 4 m: every offset exact */
    terrain_clipmap *c = pit_clipmap(camera);
    terrain__clipmap_block_info before[TERRAIN__CLIPMAP_BLOCKS];
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) before[b] = terrain__clipmap_block(c, 0, b);
    const cell_rect holes[2] = { { { 4, 6 }, { 14, 16 } }, { { 40, 36 }, { 60, 58 } } };
    set_cell_holes(c, holes, 2);
    int floor_in[2] = { 0, 0 }, wall_in[2] = { 0, 0 }, outside = 0;
    for (int k = 0; k <= 64; k++)
        for (int i = 0; i <= 64; i++) {
            float sink = vertex_sink(c, camera, i, k);
            int in0 = cells_inside(&holes[0], i, k), in1 = cells_inside(&holes[1], i, k);
            cr_assert(in0 <= 0 || in1 <= 0, "the holes are disjoint");
            int h = in0 > 0 ? 0 : in1 > 0 ? 1 : -1, d = h == 0 ? in0 : in1;
            if (h < 0) {
                cr_assert_eq(sink, 0.0f, "vertex (%d, %d) outside both holes sinks by %g", i, k, sink);
                outside++;
            } else if (d >= 2) {   /* a band (8 m = 2 cells) or more inside: on the floor */
                cr_assert_eq(sink, PIT_DEPTH, "vertex (%d, %d), %d cells inside hole %d, sinks by %g", i, k, d, h, sink);
                floor_in[h]++;
            } else {               /* one cell (4 m) in: half way down the wall */
                cr_assert_eq(sink, 0.5f * PIT_DEPTH, "vertex (%d, %d) on hole %d's wall sinks by %g", i, k, h, sink);
                wall_in[h]++;
            }
        }
    /* Hole 0 is 10 × 10 cells: 9 × 9 vertices inside, of which those 2 or more cells in from
     * every side, 7 × 7, on the floor; hole 1 is 20 × 22 cells. */
    cr_assert_eq(floor_in[0], 7 * 7);
    cr_assert_eq(floor_in[1], 17 * 19);
    cr_assert_eq(wall_in[0], 9 * 9 - 7 * 7);
    cr_assert_eq(wall_in[1], 19 * 21 - 17 * 19);
    cr_assert_eq(outside, 65 * 65 - 9 * 9 - 19 * 21);

    /* Culling: a block's box reaches hole_depth lower where it reaches into either hole. */
    int sunk[2] = { 0, 0 };
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) {
        terrain__clipmap_block_info block = terrain__clipmap_block(c, 0, b);
        bool r0 = block_reaches(&block, &holes[0]), r1 = block_reaches(&block, &holes[1]);
        cr_assert_float_eq(block.box_min[1], before[b].box_min[1] - (r0 || r1 ? PIT_DEPTH : 0.0), 1e-3, "block %d", b);
        sunk[0] += r0;
        sunk[1] += r1 && !r0;
    }
    /* Cuts at 0, 8, 16, 17, 24, 32, 40, 48, 49, 56, 64 (the four long segments of 0, 16, 17, 32,
     * 48, 49, 64 split in two), boxes a cell wider: hole 0 (cells 4 … 14, 6 … 16) reaches
     * segments 0–1 along x and 0–2 along z, hole 1 (40 … 60, 36 … 58) segments 5–9 along both. */
    _Static_assert(TERRAIN__CLIPMAP_SPLIT == 2, "the counts here are worked out for long segments split in two");
    cr_assert_eq(sunk[0], 2 * 3);
    cr_assert_eq(sunk[1], 5 * 5, "the blocks of the second hole are sunk too");

    /* The one-hole form replaces them all: the second hole is gone. */
    double lo[2], hi[2];
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    for (int a = 0; a < 2; a++) {
        lo[a] = (double)(info.first[a] + holes[0].lo[a]) * 4.0;
        hi[a] = (double)(info.first[a] + holes[0].hi[a]) * 4.0;
    }
    terrain_clipmap_set_hole(c, lo, hi);
    cr_assert_eq(vertex_sink(c, camera, 8, 10), PIT_DEPTH);
    cr_assert_eq(vertex_sink(c, camera, 50, 47), 0.0f);
    /* More than TERRAIN_CLIPMAP_MAX_HOLES: the ninth is left out (with a warning). */
    cell_rect nine[9];
    for (int h = 0; h < 9; h++) nine[h] = (cell_rect){ { 2 + 6 * h, 2 }, { 6 + 6 * h, 6 } };
    set_cell_holes(c, nine, 9);
    cr_assert_eq(vertex_sink(c, camera, 4 + 6 * 7, 4), PIT_DEPTH, "the eighth hole is kept");
    cr_assert_eq(vertex_sink(c, camera, 4 + 6 * 8, 4), 0.0f, "the ninth is not");
    terrain_clipmap_set_holes(c, NULL, NULL, 0);
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) cr_assert_eq(terrain__clipmap_block(c, 0, b).box_min[1], before[b].box_min[1]);
    terrain_clipmap_destroy(c);
}

/* Chebyshev distance, in cells, from vertex (i, k) to the part of the plane outside every
 * rectangle: brute force over the unit cells (each wholly in or wholly out; all rectangles lie
 * well inside 0 … 64, so the cells there that are out are the nearest). */
static int cells_to_outside(const cell_rect *rects, int count, int i, int k) {
    int best = INT32_MAX;
    for (int z = -1; z <= 64; z++)
        for (int x = -1; x <= 64; x++) {
            bool in = false;
            for (int h = 0; h < count; h++)
                in |= x >= rects[h].lo[0] && x < rects[h].hi[0] && z >= rects[h].lo[1] && z < rects[h].hi[1];
            if (in) continue;
            int dx = i < x ? x - i : i > x + 1 ? i - (x + 1) : 0, dz = k < z ? z - k : k > z + 1 ? k - (z + 1) : 0;
            best = CORE_MIN(best, CORE_MAX(dx, dz));
        }
    return best;
}

/* Overlapping holes (by 8 cells, more than twice the band) make one pit: everywhere its depth is
 * that of the union's own pit, the wall rising only at the union's border, none along a hole's
 * side that runs inside the other hole. Once side by side (the union a rectangle), once offset
 * (an L, with two inner corners). */
Test(terrain_clipmap, overlapping_holes_sink_as_one_pit_without_a_wall_inside) {
    const double camera[3] = { -4000.0, 0.0, 1200.0 };
    terrain_clipmap *c = pit_clipmap(camera);
    const cell_rect cases[2][2] = {
        { { { 8, 8 }, { 24, 24 } }, { { 16, 8 }, { 32, 24 } } },    /* union: x 8 … 32, z 8 … 24 */
        { { { 8, 8 }, { 24, 24 } }, { { 16, 16 }, { 32, 32 } } },   /* an L-shaped union */
    };
    for (int n = 0; n < 2; n++) {
        set_cell_holes(c, cases[n], 2);
        int floor = 0, inner_sides = 0;
        for (int k = 0; k <= 64; k++)
            for (int i = 0; i <= 64; i++) {
                int d = cells_to_outside(cases[n], 2, i, k);
                float sink = vertex_sink(c, camera, i, k);
                cr_assert_eq(sink, pit_at(d), "case %d vertex (%d, %d): %d cells inside the union, sinks by %g", n, i, k, d, sink);
                floor += d >= 2;
                /* On one hole's side, inside the other: a single hole's pit would be 0 there. */
                for (int h = 0; h < 2; h++)
                    if (cells_inside(&cases[n][h], i, k) == 0 && cells_inside(&cases[n][1 - h], i, k) >= 2) {
                        cr_assert_eq(sink, PIT_DEPTH, "case %d vertex (%d, %d): a wall inside the union", n, i, k);
                        inner_sides++;
                    }
            }
        /* Side by side, the floor is that of the 24 × 16-cell union: vertices 10 … 30 by 10 … 22. */
        if (n == 0) cr_assert_eq(floor, 21 * 13);
        cr_assert_gt(inner_sides, 0);
    }

    /* A block reaching into both holes is sunk once, by hole_depth. */
    terrain_clipmap_set_holes(c, NULL, NULL, 0);
    terrain__clipmap_block_info before[TERRAIN__CLIPMAP_BLOCKS];
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) before[b] = terrain__clipmap_block(c, 0, b);
    set_cell_holes(c, cases[0], 2);
    int both = 0;
    for (int b = 0; b < TERRAIN__CLIPMAP_BLOCKS; b++) {
        terrain__clipmap_block_info block = terrain__clipmap_block(c, 0, b);
        bool r0 = block_reaches(&block, &cases[0][0]), r1 = block_reaches(&block, &cases[0][1]);
        cr_assert_float_eq(block.box_min[1], before[b].box_min[1] - (r0 || r1 ? PIT_DEPTH : 0.0), 1e-3, "block %d", b);
        both += r0 && r1;
    }
    cr_assert_gt(both, 0);
    terrain_clipmap_destroy(c);
}
