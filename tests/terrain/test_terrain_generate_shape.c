/* Generation against the papers' shape rules (issue 16, "Generation that matches the paper"):
 * no floating islands (every solid voxel reaches the floor), the cave map perturbed like the
 * surface (002 §3.1.3.2, Fig. 11), and the relief's octave count set by its wavelength against
 * the sampling spacing (004 §4.1). */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdlib.h>

#define N TERRAIN_CHUNK_COLUMNS
#define Q TERRAIN_HEIGHT_QUANTUM

/* ---- connectivity: runs of solid, joined where they share a face ---------------------------- */

/* The solid set of a column is a few runs [lo, hi) of solid layers (bedrock, sand, rocks: what
 * the field meshes) between air or water. Layer thicknesses are multiples of Q, so the set is a
 * union of voxels 1 m × Q × 1 m; two voxels share a face when they are in one run next to each
 * other, or in face-adjacent columns at the same height. Two runs in face-adjacent columns
 * therefore share a face exactly when their y intervals overlap by at least Q (by a positive
 * length: the ends lie on the quantum grid), and the flood fill over voxels is a union-find over
 * runs. */
typedef struct solid_run {
    float lo, hi;
} solid_run;

typedef struct run_area {
    int side;                /* columns along each side of the sample */
    int *first;              /* [column]: index of its first run; [side²] = run count */
    solid_run *runs;
    int *parent;             /* union-find */
    int run_count, capacity;
} run_area;

static void area_push_run(run_area *a, float lo, float hi) {
    if (a->run_count == a->capacity) {
        int grown = a->capacity ? 2 * a->capacity : 4096;
        a->runs = realloc(a->runs, (size_t)grown * sizeof *a->runs);
        a->capacity = grown;
    }
    a->runs[a->run_count++] = (solid_run){ lo, hi };
}

/* The runs of one column of `s` (local i, k), appended. */
static void area_add_column(run_area *a, const terrain_stacks *s, int i, int k) {
    terrain_layer layers[256];
    int count = terrain_stacks_column(s, i, k, layers, 256);
    cr_assert_leq(count, 256);
    float y = TERRAIN_FLOOR_Y, run_lo = NAN;
    for (int l = 0; l < count; l++) {
        bool solid = terrain_material_in_field(layers[l].material);
        if (solid && isnan(run_lo)) run_lo = y;
        if (!solid && !isnan(run_lo)) area_push_run(a, run_lo, y), run_lo = NAN;
        y += layers[l].thickness;
    }
    if (!isnan(run_lo)) area_push_run(a, run_lo, y);
}

static int find_root(int *parent, int r) {
    while (parent[r] != r) r = parent[r] = parent[parent[r]];
    return r;
}

static void join(int *parent, int a, int b) {
    a = find_root(parent, a), b = find_root(parent, b);
    if (a != b) parent[a < b ? b : a] = a < b ? a : b;
}

/* Joins the runs of two face-adjacent columns that share a face (overlap ≥ Q). */
static void join_columns(run_area *a, int c0, int c1) {
    for (int r = a->first[c0]; r < a->first[c0 + 1]; r++)
        for (int t = a->first[c1]; t < a->first[c1 + 1]; t++)
            if (fminf(a->runs[r].hi, a->runs[t].hi) - fmaxf(a->runs[r].lo, a->runs[t].lo) >= 0.5f * Q)
                join(a->parent, r, t);
}

/* Floating solid in a side × side column area: the runs that no chain of shared faces links to
 * the floor. The area's border is open: a run in its outermost ring of columns counts as held
 * (what holds it may lie outside the sample, which the test cannot see), so only islands wholly
 * inside the sample are found; samples are chosen several chunks wide so that islands (metres
 * across) fit inside. Returns the island runs' count; *volume gets their volume in m³. */
static int area_islands(run_area *a, double *volume, int *example) {
    int side = a->side, count = a->run_count;
    a->parent = malloc((size_t)(count + 1) * sizeof *a->parent);
    int anchor = count;                           /* the floor and the open border */
    for (int r = 0; r <= count; r++) a->parent[r] = r;
    for (int k = 0; k < side; k++) {
        for (int i = 0; i < side; i++) {
            int c = k * side + i;
            bool border = i == 0 || k == 0 || i == side - 1 || k == side - 1;
            for (int r = a->first[c]; r < a->first[c + 1]; r++)
                if (border || a->runs[r].lo <= TERRAIN_FLOOR_Y) join(a->parent, r, anchor);
            if (i + 1 < side) join_columns(a, c, c + 1);
            if (k + 1 < side) join_columns(a, c, c + side);
        }
    }
    int islands = 0;
    *volume = 0.0;
    *example = -1;
    for (int r = 0; r < count; r++) {
        if (find_root(a->parent, r) == find_root(a->parent, anchor)) continue;
        islands++;
        *volume += a->runs[r].hi - a->runs[r].lo;
        if (*example < 0) *example = r;
    }
    free(a->parent);
    return islands;
}

static void area_free(run_area *a) {
    free(a->first);
    free(a->runs);
}

/* The column owning run r (for messages). */
static int run_column(const run_area *a, int r) {
    int c = 0;
    while (a->first[c + 1] <= r) c++;
    return c;
}

/* Generates chunks [x0, x0 + chunks) × [z0, z0 + chunks) and collects their runs. */
static run_area area_generate(const terrain_generation_desc *p, int64_t x0, int64_t z0, int chunks) {
    run_area a = { .side = chunks * N };
    a.first = malloc(((size_t)a.side * a.side + 1) * sizeof *a.first);
    terrain_stacks **row = malloc((size_t)chunks * sizeof *row);
    for (int cz = 0; cz < chunks; cz++) {
        for (int cx = 0; cx < chunks; cx++)
            row[cx] = terrain_generate_chunk(p, (terrain_chunk_coord){ x0 + cx, z0 + cz });
        for (int k = 0; k < N; k++) {
            for (int gx = 0; gx < a.side; gx++) {
                a.first[(cz * N + k) * a.side + gx] = a.run_count;
                area_add_column(&a, row[gx / N], gx % N, k);
            }
        }
        for (int cx = 0; cx < chunks; cx++) terrain_stacks_destroy(row[cx]);
    }
    a.first[a.side * a.side] = a.run_count;
    free(row);
    return a;
}

/* Columns with air between two solid runs: overhangs and caves, what makes islands possible. */
static int area_gap_columns(const run_area *a) {
    int gaps = 0;
    for (int c = 0; c < a->side * a->side; c++) gaps += a->first[c + 1] - a->first[c] > 1;
    return gaps;
}

static void expect_no_islands(const terrain_generation_desc *p, int64_t x0, int64_t z0, int chunks,
                              int min_gap_columns) {
    run_area a = area_generate(p, x0, z0, chunks);
    int gaps = area_gap_columns(&a);
    /* The sample must hold what could float: else it proves nothing. */
    cr_expect_geq(gaps, min_gap_columns, "seed %llu at (%lld, %lld): only %d columns with gaps",
                  (unsigned long long)p->seed, (long long)x0, (long long)z0, gaps);
    double volume;
    int example;
    int islands = area_islands(&a, &volume, &example);
    int column = example >= 0 ? run_column(&a, example) : 0;
    cr_expect_eq(islands, 0,
                 "seed %llu at chunks (%lld, %lld): %d floating runs, %.1f m³ in all; e.g. column (%d, %d) "
                 "y %.2f … %.2f",
                 (unsigned long long)p->seed, (long long)x0, (long long)z0, islands, volume, column % a.side,
                 column / a.side, example >= 0 ? a.runs[example].lo : 0.0, example >= 0 ? a.runs[example].hi : 0.0);
    area_free(&a);
}

/* The checker itself finds a floating block, and one held by a face, by hand. */
static void block_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    int mode = *(const int *)user;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 256.0f);            /* ground at y = 0 */
    bool block = x >= 10 && x < 13 && z >= 10 && z < 12;
    bool pillar = mode == 1 && x == 10 && z == 10;                     /* holds the block up */
    if (pillar) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 6.0f);
    } else if (block) {
        terrain_stacks_builder_push(b, TERRAIN_AIR, 4.0f);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 2.0f);
    }
}

Test(terrain_generate_shape, island_checker_finds_a_floating_block) {
    for (int mode = 0; mode < 2; mode++) {
        terrain_stacks *s = terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, block_column, &mode);
        run_area a = { .side = N };
        a.first = malloc(((size_t)N * N + 1) * sizeof *a.first);
        for (int k = 0; k < N; k++)
            for (int i = 0; i < N; i++) a.first[k * N + i] = a.run_count, area_add_column(&a, s, i, k);
        a.first[N * N] = a.run_count;
        double volume;
        int example;
        int islands = area_islands(&a, &volume, &example);
        /* Mode 0: a 3 × 2 block of 2 m floating 4 m up: 6 runs, 12 m³. Mode 1: a pillar under
         * one of its corners holds it. */
        cr_expect_eq(islands, mode == 0 ? 6 : 0, "mode %d: %d islands, %g m³", mode, islands, volume);
        cr_expect_float_eq(volume, mode == 0 ? 12.0 : 0.0, 1e-6, "mode %d", mode);
        area_free(&a);
        terrain_stacks_destroy(s);
    }
}


/* Every solid voxel of the real generator's world reaches the floor (issue 16). Two samples of
 * 2 × 2 chunks, default parameters: chunks x 8…9, z 9…10 of seed 1 hold two floating slivers
 * (1.4 m³ at y ≈ 123, where a cave cuts through an overhang's root) unless the generator removes
 * islands; seed 2's is another cut-up place. Each has 1 000 or more columns of overhangs and
 * caves (measured 1 680 and 2 230: the bound only says that the sample is cut up enough to prove
 * something). */
Test(terrain_generate_shape, every_solid_voxel_reaches_the_floor) {
    terrain_generation_desc one = terrain_generation_defaults(1), two = terrain_generation_defaults(2);
    expect_no_islands(&one, 8, 9, 2, 1000);
    expect_no_islands(&two, 4, 8, 2, 1000);
}

/* A generation desc that makes islands likely: a shear of 30 m over 24 m wavelengths (the overhang
 * map folds over itself) and wide caves. Without the removal these three chunks, each seen on
 * its own, hold 20, 24 and 2 floating runs (8, 10 and 0.1 m³). The generator removes every island that lies inside one
 * chunk, which is what a chunk can see: its outermost columns count as held, as in the check
 * (terrain_generate.c, "Islands"; an island across a chunk border stays, a limit the README
 * states with its measured rate). */
Test(terrain_generate_shape, no_island_inside_a_chunk_even_where_islands_are_likely) {
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.horizontal_perturbation = 30.0f;
    p.perturbation_wavelength = 24.0f;
    p.cave_threshold = 0.35f;
    const int64_t chunks[3][2] = { { 1, 8 }, { 2, 8 }, { 2, 9 } };
    for (int n = 0; n < 3; n++) expect_no_islands(&p, chunks[n][0], chunks[n][1], 1, 500);
}

/* ---- the relief's octaves against the sampling spacing (004 §4.1) ----------------------------- */

/* With relief_height 600 (four times the default) no octave of the macro relief is shorter than
 * twice the spacing it is sampled at, for the generator's 1 m columns and the clipmap's coarser
 * grids. Octave k of the rescale-and-add multifractal has wavelength λ·r^−k; with ν octaves,
 * k = 0 … ⌈ν⌉ − 1 are summed (the last weighted by frac ν). Before, ν came from the amplitudes
 * (004 §4.1's formula): 10.85 at 1 m for a 600 m relief (octave 10 is 1.2 m long) and 7.33 at
 * 8 m (octave 7 is 9.4 m long, under two 8 m texels). The generator keeps four samples a
 * wavelength (terrain_generate.c, relief_octaves): ν = log2(1200 / 4σ), worked out by hand:
 * 8.23 at 1 m, 6.23 at 4 m, 3.23 at 32 m; the relief's height plays no part. */
Test(terrain_generate_shape, no_octave_finer_than_twice_the_spacing) {
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.relief_height = 600.0f;
    p.relief_octaves = 16;                     /* so that the cap does not hide the rule */
    cr_assert_eq(p.lacunarity, 2.0f);
    const float spacings[] = { 1, 2, 4, 8, 16, 32, 64 };
    for (int n = 0; n < 7; n++) {
        float spacing = spacings[n];
        float octaves = terrain__ground_octaves(&p, spacing);
        int finest = (int)ceilf(octaves) - 1;  /* the last octave summed with a weight > 0 */
        double wavelength = p.relief_wavelength / pow(p.lacunarity, finest);
        cr_expect_geq(wavelength, 2.0 * spacing, "spacing %g m: %g octaves, the finest %.2f m long", spacing, octaves,
                      wavelength);
        cr_expect_float_eq(octaves, (float)log2(p.relief_wavelength / (4.0 * spacing)), 1e-4f, "spacing %g m", spacing);
    }
    cr_expect_float_eq(terrain__ground_octaves(&p, 1.0f), 8.2288f, 1e-3f);
    /* The same counts whatever the relief: the count follows the wavelength alone. */
    terrain_generation_desc low = p;
    low.relief_height = 20.0f;
    for (int n = 0; n < 7; n++)
        cr_expect_float_eq(terrain__ground_octaves(&low, spacings[n]), terrain__ground_octaves(&p, spacings[n]), 0.0f);
    /* And the cap still caps. */
    p.relief_octaves = 6;
    cr_expect_float_eq(terrain__ground_octaves(&p, 1.0f), 6.0f, 0.0f);
}

/* ---- the perturbed cave map (002 §3.1.3.2, Fig. 11) ------------------------------------------- */

/* The scattered-point batch that the perturbed cave lookups use is terrain__noise3, bit for bit,
 * on every SIMD path this CPU runs (the world's bytes must not depend on the CPU). */
Test(terrain_generate_shape, scattered_noise_equals_the_scalar_noise) {
    enum { COUNT = 37 };                       /* not a multiple of a block: the tail too */
    float xs[COUNT], ys[COUNT], zs[COUNT], out[COUNT];
    for (int j = 0; j < COUNT; j++) {
        xs[j] = -40.3f + 7.31f * (float)j;
        ys[j] = 3.7f - 1.93f * (float)j;
        zs[j] = 1000.25f + 0.37f * (float)(j * j);
    }
    terrain__noise_path before = terrain__noise_get_path();
    for (int path = TERRAIN__NOISE_PORTABLE; path < TERRAIN__NOISE_PATH_COUNT; path++) {
        if (!terrain__noise_set_path((terrain__noise_path)path)) continue;
        terrain__noise3_points(0x1234567u, 0.0, 0.0, xs, ys, zs, COUNT, out);
        for (int j = 0; j < COUNT; j++)
            cr_expect_eq(out[j], terrain__noise3(0x1234567u, xs[j], ys[j], zs[j]), "path %d, point %d", path, j);
        /* Around an origin 10⁶ cells out (issue 16, precision far out): the cell and offset form. */
        const double x0 = 1000003.7, z0 = -2000001.3;
        terrain__lattice sx = terrain__lattice_split(x0), sz = terrain__lattice_split(z0);
        terrain__noise3_points(0x1234567u, x0, z0, xs, ys, zs, COUNT, out);
        for (int j = 0; j < COUNT; j++)
            cr_expect_eq(out[j], terrain__noise3_cell(0x1234567u, sx.cell, sx.offset + xs[j], ys[j], sz.cell, sz.offset + zs[j]),
                         "path %d, point %d far out", path, j);
    }
    terrain__noise_set_path(before);
}

/* Air volume below y = top in a chunk's columns, and how many columns' layers differ from b's. */
static double cave_air(const terrain_stacks *s) {
    terrain_layer layers[256];
    double air = 0.0;
    for (int k = 0; k < N; k++) {
        for (int i = 0; i < N; i++) {
            int count = terrain_stacks_column(s, i, k, layers, 256);
            for (int l = 0; l + 1 < count; l++) air += layers[l].material == TERRAIN_AIR ? layers[l].thickness : 0.0f;
        }
    }
    return air;
}

/* On flat ground (no relief, no y perturbation, no lakes) the sideways displacement moves nothing
 * of the ground: G is the same everywhere. Whatever it changes is the caves', so the caves with a
 * shear A = 10 m must differ from those with A = 0 in most columns (a cave map sampled undisplaced,
 * as before, gives the same chunk byte for byte). The displacement moves the map by at most A, a
 * fraction of the caves' 64 m wavelength: it bends tunnels, it does not make or fill them, so the
 * cave volume stays within ±30 % (measured: 1.3 % apart, 1 568 of 2 048 columns differ; the bounds
 * are a regression guard). */
Test(terrain_generate_shape, the_cave_map_is_perturbed_like_the_surface) {
    terrain_generation_desc flat = terrain_generation_defaults(3);
    flat.relief_height = 0.0f;
    flat.vertical_perturbation = 0.0f;
    flat.lake_spacing = 0.0f;
    flat.base_height = 40.0f;
    flat.cave_threshold = 0.35f;
    terrain_generation_desc still = flat;
    still.horizontal_perturbation = 0.0f;
    double air_bent = 0.0, air_still = 0.0;
    int differ = 0;
    for (int n = 0; n < 2; n++) {
        terrain_chunk_coord coord = { n, 5 };
        terrain_stacks *bent = terrain_generate_chunk(&flat, coord), *straight = terrain_generate_chunk(&still, coord);
        air_bent += cave_air(bent), air_still += cave_air(straight);
        terrain_layer a[256], b[256];
        for (int c = 0; c < N * N; c++) {
            int ca = terrain_stacks_column(bent, c % N, c / N, a, 256);
            int cb = terrain_stacks_column(straight, c % N, c / N, b, 256);
            bool same = ca == cb;
            for (int l = 0; same && l < ca; l++)
                same = a[l].material == b[l].material && a[l].thickness == b[l].thickness;
            differ += !same;
        }
        terrain_stacks_destroy(bent);
        terrain_stacks_destroy(straight);
    }
    cr_expect_gt(air_still, 1000.0, "the sample has caves (%.0f m³)", air_still);
    cr_expect_gt(differ, N * N, "%d of %d columns differ", differ, 2 * N * N);
    cr_expect_lt(fabs(air_bent - air_still), 0.3 * air_still, "cave air %.0f m³ bent, %.0f m³ straight", air_bent,
                 air_still);
}
