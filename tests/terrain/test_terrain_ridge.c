/* Ridges without saw teeth (issue 12): along the highest ridge near seed 1's spawn — terraced
 * cliffs under a snow-capped summit, the view a player gets flying 60 m over the spawn — no
 * triangle the terrain draws is longer than a stated multiple of its level's spacing, and the far
 * clipmap has no tooth: no vertex standing above (or sunk below) all four of its grid neighbours
 * by more than one spacing.
 *
 * The bounds, worked out from the geometry rather than read from the code's output:
 *   - marching cubes puts every vertex on an edge of its cell and every triangle inside one cell
 *     (a transition cell's fan spokes too: the centroid of a loop of the cell's own crossings), so
 *     no edge is longer than the cell's diagonal, √3 cell widths;
 *   - a clipmap triangle spans one grid step horizontally, so its length is the step times
 *     √(1 + slope²) and a spike shows as a vertex that all its neighbours lie far below. The
 *     generator's steepest ground is a terrace riser: the quintic fade's slope 15/8 over
 *     CLIFF_RISER = 0.2 of the step, on hillsides of slope up to about 0.4 — 3.75. A tooth one
 *     spacing tall on every side would be a slope of 1 all round a single sample, which nothing
 *     in G makes at the clipmap's spacings (measured: at most 0.46 spacing on this ridge, on
 *     levels 0–3; the threshold of 1 is a regression guard above that). The test can fail: the
 *     columns' own G sampled point-wise on the same grids (no octaves dropped, terraces and the
 *     y perturbation kept) has teeth 1.97, 1.67, 0.87 and 0.50 spacings tall on levels 0–3 —
 *     the staircase the spaced ground (terrain__ground_row_spaced) exists to remove. */
#include "../engine/test.h"
#include "core/core.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>

/* Seed 1's highest ground within 1 km of the spawn, on an 8 m search grid. */
static void ridge_summit(const terrain_generation_desc *p, double *x, double *z, double *height) {
    *height = -1e9;
    for (int k = -1000; k <= 1000; k += 8)
        for (int i = -1000; i <= 1000; i += 8) {
            double h = terrain__ground_height(p, i, k);
            if (h > *height) *height = h, *x = i, *z = k;
        }
}

/* The longest edge of the chunk's triangles, in units of the level's cell width. */
static double longest_edge(const terrain_mesh *m, double cell) {
    double longest = 0.0;
    for (uint32_t t = 0; t + 2 < m->index_count; t += 3)
        for (int e = 0; e < 3; e++) {
            const float *a = m->vertices[m->indices[t + e]].position;
            const float *b = m->vertices[m->indices[t + (e + 1) % 3]].position;
            double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
            longest = fmax(longest, sqrt(dx * dx + dy * dy + dz * dz) / cell);
        }
    return longest;
}

Test(terrain_ridge, no_chunk_triangle_is_longer_than_its_cells_diagonal_at_any_level) {
    terrain_generation_desc params = terrain_generation_defaults(1);
    double x = 0.0, z = 0.0, top;
    ridge_summit(&params, &x, &z, &top);
    cr_assert_gt(top, 120.0, "seed 1 has a mountain near the spawn (summit %.1f m)", top);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = params });
    /* The chunk holding the summit and the one beside it along x, with the finer neighbour on the
     * −x side where it can have one (transition cells on that face). */
    int triangles = 0;
    for (int level = 0; level <= 2; level++) {
        double cell = TERRAIN_COLUMN_SIZE * (double)(1 << level), size = TERRAIN_MESH_CELLS * cell;
        int64_t cx = (int64_t)floor(x / size), cz = (int64_t)floor(z / size), cy = (int64_t)floor(top / size);
        for (int64_t dx = 0; dx <= 1; dx++)
            for (int64_t dy = -1; dy <= 0; dy++) {
                terrain_mesh mesh;
                terrain_lod_desc lod = { .level = level,
                                         .finer_neighbours = level > 0 ? terrain_lod_neighbour_bit(-1, 0, 0) : 0 };
                cr_assert(terrain_mesh_chunk(world, cx + dx, cy + dy, cz, &lod, &mesh));
                double longest = longest_edge(&mesh, cell);
                cr_expect_leq(longest, sqrt(3.0) + 1e-4, "level %d chunk (%lld, %lld, %lld): an edge %.3f cells long",
                              level, (long long)(cx + dx), (long long)(cy + dy), (long long)cz, longest);
                triangles += (int)(mesh.index_count / 3);
                terrain_mesh_free(&mesh);
            }
    }
    cr_expect_gt(triangles, 1000, "the ridge was meshed (%d triangles)", triangles);
    terrain_world_destroy(world);
}

Test(terrain_ridge, the_far_clipmap_has_no_tooth_along_the_ridge) {
    terrain_generation_desc params = terrain_generation_defaults(1);
    double x = 0.0, z = 0.0, top;
    ridge_summit(&params, &x, &z, &top);
    terrain_clipmap *far = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = params });
    const double camera[3] = { 0.0, 62.0, 0.0 };   /* 60 m over the spawn */
    terrain_clipmap_update(far, camera);
    /* Levels 0–3 (4–32 m): the summit is ~800 m out, drawn by level 2; the ones around it draw
     * the ridge's flanks nearer and farther. Sample each on its own grid over a square centred
     * between the camera and the summit that the level covers. */
    for (int level = 0; level <= 3; level++) {
        double s = 4.0 * (double)(1 << level), reach = 60.0 * s;
        double mx = s * round(0.5 * x / s), mz = s * round(0.5 * z / s);
        if (level == 0) mx = mz = 0.0;     /* level 0 reaches 256 m: the spawn's own hills */
        double worst = 0.0, at_x = 0.0, at_z = 0.0;
        int samples = 0;
        for (double k = mz - reach + s; k < mz + reach - s; k += s)
            for (double i = mx - reach + s; i < mx + reach - s; i += s) {
                if (fabs(i) > 62.0 * s || fabs(k) > 62.0 * s) continue;   /* stay inside the level */
                double h = terrain_clipmap_height(far, i, k);
                double n[4] = { terrain_clipmap_height(far, i + s, k), terrain_clipmap_height(far, i - s, k),
                                terrain_clipmap_height(far, i, k + s), terrain_clipmap_height(far, i, k - s) };
                double highest = fmax(fmax(n[0], n[1]), fmax(n[2], n[3]));
                double lowest = fmin(fmin(n[0], n[1]), fmin(n[2], n[3]));
                double tooth = fmax(h - highest, lowest - h) / s;
                if (tooth > worst) worst = tooth, at_x = i, at_z = k;
                samples++;
            }
        cr_expect_gt(samples, 1000);
        cr_expect_leq(worst, 1.0, "level %d: a tooth %.2f spacings tall at (%.0f, %.0f)", level, worst, at_x, at_z);
    }
    terrain_clipmap_destroy(far);
}
