/* Detail from a screen-space error (terrain.h; terrain_screen_error.c): K = H / (2·τ·tan(θ/2)),
 * the errors of chunk levels and clipmap spacings, the rings' half width and the clipmap's
 * cells, finest spacing and levels derived from them. Expectations are worked by hand in the
 * comments; the rest are invariants (every level starts where its error is under the target;
 * more pixels or a smaller target never give less detail anywhere). */
#include "../engine/test.h"
#include "terrain/terrain.h"

#include <math.h>

#define PI 3.14159265358979323846

/* 720 px, 60°, 1 px: K = 720 / (2·tan 30°) = 720 / 1.1547005 = 623.5383. */
Test(terrain_screen_error, scale_is_the_viewport_over_twice_the_tangent) {
    cr_assert_float_eq(terrain_screen_error_scale(720, (float)(PI / 3.0), 1.0f), 623.5383, 1e-3);
    cr_assert_float_eq(terrain_screen_error_scale(720, (float)(PI / 3.0), 2.0f), 311.7691, 1e-3);
    /* 90°: tan 45° = 1, K = 1080 / 2 = 540. */
    cr_assert_float_eq(terrain_screen_error_scale(1080, (float)(PI / 2.0), 1.0f), 540.0, 1e-3);
    /* Zero height and fov are 720 px and 60°; no target is no scale. */
    cr_assert_float_eq(terrain_screen_error_scale(0, 0.0f, 1.0f), 623.5383, 1e-3);
    cr_assert_eq(terrain_screen_error_scale(720, 0.0f, 0.0f), 0.0);
    cr_assert_eq(terrain_screen_error_scale(720, 0.0f, -1.0f), 0.0);
}

/* ε = h/8 · min(1, h / 6.25 m): h²/50 under 6.25 m, h/8 over. */
Test(terrain_screen_error, level_errors_grow_with_the_cell) {
    cr_assert_float_eq(terrain_chunk_level_error(1), 4.0 / 50.0, 1e-9);      /* 0.08 m */
    cr_assert_float_eq(terrain_chunk_level_error(2), 16.0 / 50.0, 1e-9);     /* 0.32 m */
    cr_assert_float_eq(terrain_chunk_level_error(3), 1.0, 1e-9);             /* 8 / 8 */
    cr_assert_float_eq(terrain_chunk_level_error(4), 2.0, 1e-9);
    for (int level = 1; level < 10; level++) cr_assert_gt(terrain_chunk_level_error(level), terrain_chunk_level_error(level - 1));
    cr_assert_float_eq(terrain_clipmap_spacing_error(4.0), 1.0, 1e-9);
}

/* Level L's area reaches w·32·2^L m from a centre up to half a coarsest chunk (16·2^(levels−1))
 * from the viewer. */
Test(terrain_screen_error, clearance_takes_off_the_snapping) {
    cr_assert_float_eq(terrain_rings_clearance(2, 3, 0), 0.0, 1e-9);        /* 64 − 64: today's level 1 can be at the eye */
    cr_assert_float_eq(terrain_rings_clearance(2, 3, 1), 64.0, 1e-9);       /* 128 − 64 */
    cr_assert_float_eq(terrain_rings_clearance(2, 3, 2), 192.0, 1e-9);      /* 256 − 64 */
    cr_assert_float_eq(terrain_rings_clearance(3, 1, 0), 80.0, 1e-9);       /* 96 − 16 */
}

/* 720 px, 60°, 1 px, 3 levels (K = 623.54), by hand:
 *   level 1 from ε₁·K = 0.08·623.54 = 49.9 m:   32w − 64 ≥ 49.9   → w ≥ 3.56
 *   level 2 from ε₂·K = 0.32·623.54 = 199.5 m:  64w − 64 ≥ 199.5  → w ≥ 4.12
 *   clipmap from 2·623.54 = 1247.1 m:          128w − 64 ≥ 1247.1 → w ≥ 10.24
 * so w = 11, made even (rings align with coarser chunks): 12.
 * 360 px (K = 311.77): 2.78, 2.56, 5.37 → 6. 2 levels at 720 px: 32w − 32 ≥ 49.9 → 2.56;
 * 64w − 32 ≥ 1247.1 → 19.99 → 20. One level: 32w − 16 ≥ 1247.1 → 39.47 → 40 (any w). */
Test(terrain_screen_error, half_width_worked_by_hand) {
    double k720 = terrain_screen_error_scale(720, 0.0f, 1.0f), k360 = terrain_screen_error_scale(360, 0.0f, 1.0f);
    cr_assert_eq(terrain_rings_half_width(3, k720), 12);
    cr_assert_eq(terrain_rings_half_width(3, k360), 6);
    cr_assert_eq(terrain_rings_half_width(2, k720), 20);
    cr_assert_eq(terrain_rings_half_width(1, k720), 40);
    /* A tiny scale still keeps the smallest rings the layout allows. */
    cr_assert_eq(terrain_rings_half_width(1, 1e-6), 1);
    cr_assert_eq(terrain_rings_half_width(3, 1e-6), 4);   /* w = 2 leaves 0 m before level 1 */
}

/* The coarsest chunk level drawn at distance d from a viewer anywhere in its snapped cell: the
 * first level whose clearance lies beyond d; `levels` past the rings (the clipmap). */
static int level_at(int half_width, int levels, double d) {
    for (int level = 0; level < levels; level++)
        if (d < terrain_rings_clearance(half_width, levels, level)) return level;
    return levels;
}

Test(terrain_screen_error, rings_meet_the_target_and_more_pixels_never_give_less_detail) {
    const float targets[] = { 8, 6, 4, 3, 2, 1.5f, 1, 0.75f, 0.5f };
    const int heights[] = { 240, 360, 480, 720, 1080, 1440, 2160 };
    for (int levels = 1; levels <= 5; levels++)
        for (int h = 0; h < 7; h++) {
            int previous = 0;
            for (int t = 0; t < 9; t++) {               /* smaller targets: K grows */
                double k = terrain_screen_error_scale(heights[h], 0.0f, targets[t]);
                int w = terrain_rings_half_width(levels, k);
                if (w == 64) continue;                  /* the cap */
                for (int level = 0; level + 1 < levels; level++)
                    cr_assert_geq(terrain_rings_clearance(w, levels, level), terrain_chunk_level_error(level + 1) * k - 1e-9,
                                  "%d levels, %d px, %g px: level %d starts too near", levels, heights[h], targets[t], level + 1);
                cr_assert_geq(terrain_rings_clearance(w, levels, levels - 1), TERRAIN_GROUND_ERROR * k - 1e-9);
                cr_assert_geq(w, previous, "%d levels, %d px: %g px gives %d < %d", levels, heights[h], targets[t], w, previous);
                if (previous)
                    for (double d = 0; d < 4096; d += 8)
                        cr_assert_leq(level_at(w, levels, d), level_at(previous, levels, d), "coarser at %g m", d);
                previous = w;
            }
        }
    /* The same target on a taller viewport is at least as much detail too. */
    for (int h = 1; h < 7; h++)
        cr_assert_geq(terrain_rings_half_width(3, terrain_screen_error_scale(heights[h], 0.0f, 1.0f)),
                      terrain_rings_half_width(3, terrain_screen_error_scale(heights[h - 1], 0.0f, 1.0f)));
}

/* ---- the clipmap ---- */

static terrain_clipmap_stats_info clipmap_for(float pixel_error, int height, float inner_distance) {
    terrain_clipmap *c = terrain_clipmap_create(&(terrain_clipmap_desc){ .pixel_error = pixel_error, .viewport_height = height,
                                                                          .inner_distance = inner_distance,
                                                                          .generation = terrain_generation_defaults(1) });
    terrain_clipmap_stats_info stats = terrain_clipmap_stats(c);
    terrain_clipmap_destroy(c);
    return stats;
}

/* 720 px, 1 px, rings reaching 1472 m (w = 12, 3 levels: 128·12 − 64), by hand:
 *   cells ≥ 4·(K/4 + 2) = 623.54 + 8 = 631.5 → 640 (a multiple of 16)
 *   finest spacing: ε(s)·K = s/4·623.54 ≤ 1472 → s ≤ 9.44 → 8 m
 *   levels: 640/2 · 8 · 2^(L−1) = 2560 · 2^(L−1) ≥ 8192 → 2^(L−1) ≥ 3.2 → L = 3
 * With rings reaching 704 m: s ≤ 4.52 → 4 m, 1280 · 2^(L−1) ≥ 8192 → L = 4.
 * pixel_error 0 is today's 6 levels of 128 cells from 4 m. */
Test(terrain_screen_error, clipmap_derived_by_hand_and_zero_is_the_fixed_default) {
    terrain_clipmap_stats_info s = clipmap_for(1.0f, 720, 1472.0f);
    cr_assert_eq(s.cells, 640);
    cr_assert_eq(s.finest_spacing, 8.0f);
    cr_assert_eq(s.levels, 3);
    terrain_clipmap_stats_info nearer = clipmap_for(1.0f, 720, 704.0f);
    cr_assert_eq(nearer.finest_spacing, 4.0f);
    cr_assert_eq(nearer.levels, 4);
    terrain_clipmap_stats_info fixed = clipmap_for(0.0f, 720, 704.0f);
    cr_assert_eq(fixed.cells, 128);
    cr_assert_eq(fixed.finest_spacing, 4.0f);
    cr_assert_eq(fixed.levels, 6);
    /* Given fields win over derived ones. */
    terrain_clipmap *c = terrain_clipmap_create(&(terrain_clipmap_desc){ .pixel_error = 1.0f, .cells = 64, .levels = 3,
                                                                          .generation = terrain_generation_defaults(1) });
    terrain_clipmap_stats_info given = terrain_clipmap_stats(c);
    cr_assert_eq(given.cells, 64);
    cr_assert_eq(given.levels, 3);
    cr_assert_eq(given.finest_spacing, 1.0f, "no inner distance: the finest spacing is 1 m");
    terrain_clipmap_destroy(c);
}

Test(terrain_screen_error, every_clipmap_level_starts_where_its_error_is_under_the_target) {
    const float targets[] = { 8, 4, 2, 1, 0.5f };
    const int heights[] = { 360, 720, 1080 };
    for (int h = 0; h < 3; h++) {
        int previous_cells = 0;
        for (int t = 0; t < 5; t++) {
            double k = terrain_screen_error_scale(heights[h], 0.0f, targets[t]);
            float inner = (float)terrain_rings_clearance(terrain_rings_half_width(3, k), 3, 2);
            terrain_clipmap_stats_info s = clipmap_for(targets[t], heights[h], inner);
            cr_assert_geq(s.cells, previous_cells, "more pixels, fewer cells");
            previous_cells = s.cells;
            if (s.cells == 1024) continue;                                         /* the cap */
            cr_assert(s.finest_spacing == 1.0f || terrain_clipmap_spacing_error(s.finest_spacing) * k <= inner);
            for (int level = 1; level < s.levels; level++) {
                double spacing = ldexp(s.finest_spacing, level);
                /* Drawn from where the finer level ends, n·s/4, less the camera's offset < 2·s. */
                cr_assert_geq(s.cells * spacing / 4.0 - 2.0 * spacing, terrain_clipmap_spacing_error(spacing) * k,
                              "%d px, %g px: level %d", heights[h], targets[t], level);
            }
            cr_assert_geq(0.5 * s.cells * ldexp(s.finest_spacing, s.levels - 1), 8192.0);
        }
    }
}

Test(terrain_screen_error, clipmap_set_screen_derives_again_and_keeps_fixed_ones) {
    terrain_clipmap *c = terrain_clipmap_create(&(terrain_clipmap_desc){ .pixel_error = 1.0f, .viewport_height = 720,
                                                                          .inner_distance = 1472.0f,
                                                                          .generation = terrain_generation_defaults(1) });
    terrain_clipmap_update(c, (double[3]){ 10, 50, 20 });
    cr_assert_not(terrain_clipmap_set_screen(c, 720, 0.0f, 1472.0f), "the same screen changes nothing");
    /* 360 px, rings of 704 m: K = 311.77, cells ≥ 311.77 + 8 → 320; s ≤ 704 / 77.9 = 9.03 → 8 m;
     * 160·8·2^(L−1) ≥ 8192 → 4. */
    cr_assert(terrain_clipmap_set_screen(c, 360, 0.0f, 704.0f));
    terrain_clipmap_stats_info s = terrain_clipmap_stats(c);
    cr_assert_eq(s.cells, 320);
    cr_assert_eq(s.finest_spacing, 8.0f);
    cr_assert_eq(s.levels, 4);
    cr_assert(isnan(terrain_clipmap_height(c, 10, 20)), "made anew: no heights until the next update");
    cr_assert_gt(terrain_clipmap_update(c, (double[3]){ 10, 50, 20 }), 0);
    cr_assert(!isnan(terrain_clipmap_height(c, 10, 20)));
    terrain_clipmap_destroy(c);
    terrain_clipmap *fixed = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = terrain_generation_defaults(1) });
    cr_assert_not(terrain_clipmap_set_screen(fixed, 360, 0.0f, 100.0f), "no pixel_error: fixed");
    cr_assert_eq(terrain_clipmap_stats(fixed).cells, 128);
    terrain_clipmap_destroy(fixed);
}

/* Which chunks streaming simplifies, each by its level's own error h²/50 (cells h = 2^L m):
 * none, the default (0), gives nothing; coarse leaves level 0 whole and gives levels 1 and 2
 * 0.08 and 0.32 m; all gives level 0 its 1/50 = 0.02 m too. The three names parse, and anything
 * else is refused with the output untouched. */
Test(terrain_screen_error, streaming_simplifies_the_levels_asked_for) {
    terrain_stream_desc zero = { 0 };
    cr_assert_eq(zero.simplify, TERRAIN_SIMPLIFY_NONE);
    cr_assert_eq(terrain_simplify_error(TERRAIN_SIMPLIFY_COARSE, 0), 0.0f);
    cr_assert_float_eq(terrain_simplify_error(TERRAIN_SIMPLIFY_COARSE, 1), 0.08, 1e-6);
    cr_assert_float_eq(terrain_simplify_error(TERRAIN_SIMPLIFY_COARSE, 2), 0.32, 1e-6);
    cr_assert_float_eq(terrain_simplify_error(TERRAIN_SIMPLIFY_ALL, 0), 0.02, 1e-6);
    cr_assert_float_eq(terrain_simplify_error(TERRAIN_SIMPLIFY_ALL, 2), 0.32, 1e-6);
    for (int level = 0; level < 3; level++) cr_assert_eq(terrain_simplify_error(TERRAIN_SIMPLIFY_NONE, level), 0.0f);
    terrain_simplify s = TERRAIN_SIMPLIFY_ALL;
    cr_assert(terrain_parse_simplify("none", &s) && s == TERRAIN_SIMPLIFY_NONE);
    cr_assert(terrain_parse_simplify("coarse", &s) && s == TERRAIN_SIMPLIFY_COARSE);
    cr_assert(terrain_parse_simplify("all", &s) && s == TERRAIN_SIMPLIFY_ALL);
    cr_assert_not(terrain_parse_simplify("some", &s));
    cr_assert_not(terrain_parse_simplify("", &s));
    cr_assert_not(terrain_parse_simplify(NULL, &s));
    cr_assert_eq(s, TERRAIN_SIMPLIFY_ALL, "a refused name leaves the output as it was");
}
