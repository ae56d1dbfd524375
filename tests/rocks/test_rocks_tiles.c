/* The rock tile set (paper 001): the tiles' guarantee checked by an independent path (a global
 * brute-force Voronoi over a block of randomly coloured tiles), no doubled rocks, contacts kept
 * by both meshes, erosion against a plain step-by-step erosion, no interpenetration, closed
 * meshes at every level of detail, determinism across
 * thread counts, the cache file against cuts, flipped bytes and old versions, bad parameters.
 * Small sets (n = 5 cells, 5 voxels a cell: odd, so a voxel sits on each cell centre and the dual-block side rule is tested at its tie) so the suite runs in seconds. */
#include "../engine/test.h"
#include "core/core.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define N 5
#define M 5
#define BLOCK 3                       /* tiles a side of the test's block */
#define CELLS (BLOCK * N)
#define VOXELS (N * M)                /* voxels a tile side */

static rocks_tileset_desc small_desc(void) {
    return (rocks_tileset_desc){ .seed = 7, .cells = N, .voxels_per_cell = M, .shape = ROCKS_SHAPE_MIXED };
}

/* For the tests that need no block: n = 4 (every seed then comes from a vertex feature, but
 * contacts, meshes and threads do not care), a sixth of the rocks. */
static rocks_tileset_desc quick_desc(void) {
    return (rocks_tileset_desc){ .seed = 7, .cells = 4, .voxels_per_cell = 6, .shape = ROCKS_SHAPE_MIXED };
}

static rocks__set *build_full(void) {
    rocks_tileset_desc desc = small_desc();
    rocks_tileset *set = rocks__tiles_create(&desc, &(rocks__build_options){ .keep_voxels = true, .keep_empty = true });
    cr_assert_not_null(set);
    return (rocks__set *)set;
}

/* ---- a block of 3×3×3 tiles with random corner colours, and its global Voronoi ------------------ */

typedef struct block {
    uint8_t colour[BLOCK + 1][BLOCK + 1][BLOCK + 1];   /* [z][y][x] lattice points 0 … 3 */
    rocks__seed seeds[CELLS][CELLS][CELLS][ROCKS__MAX_SEEDS_PER_CELL];
    int seed_count[CELLS][CELLS][CELLS];
} block;

static int block_colour(const void *user, int x, int y, int z) {
    const block *b = user;
    cr_assert(x >= 0 && x <= BLOCK && y >= 0 && y <= BLOCK && z >= 0 && z <= BLOCK, "colour asked outside the block");
    return b->colour[z][y][x];
}

static block *block_make(const rocks__params *params, uint64_t seed) {
    block *b = calloc(1, sizeof *b);
    for (int z = 0; z <= BLOCK; z++)
        for (int y = 0; y <= BLOCK; y++)
            for (int x = 0; x <= BLOCK; x++)
                b->colour[z][y][x] = core_hash_combine(seed, (uint64_t)(x + 5 * y + 25 * z)) & 1;
    for (int z = 0; z < CELLS; z++)
        for (int y = 0; y < CELLS; y++)
            for (int x = 0; x < CELLS; x++) {
                int cell[3] = { x, y, z };
                b->seed_count[z][y][x] = rocks__cell_seeds(params, cell, block_colour, b, b->seeds[z][y][x]);
            }
    return b;
}

static int tile_of(const block *b, int lx, int ly, int lz) {
    uint8_t c[8];
    for (int i = 0; i < 8; i++) c[i] = b->colour[lz + ((i >> 2) & 1)][ly + ((i >> 1) & 1)][lx + (i & 1)];
    return rocks_tile_index(c);
}

/* Owner key of a seed: its global cell and index. */
static int32_t seed_key(const int cell[3], int k) { return ((cell[2] * CELLS + cell[1]) * CELLS + cell[0]) * 8 + k; }

/* The dual-block owner of global voxel v (inside the middle tile, so its block is in range),
 * computed from scratch: every seed of the 8 cells, smallest d, ties to the smaller id. */
static int32_t brute_owner(const block *b, const int v[3]) {
    int first[3];
    for (int a = 0; a < 3; a++) {
        int c = v[a] / M, s = v[a] - c * M;
        first[a] = 2 * s + 1 < M ? c - 1 : c;
    }
    float best = INFINITY;
    uint64_t best_id = 0;
    int32_t owner = -1;
    for (int i = 0; i < 8; i++) {
        int c[3] = { first[0] + (i & 1), first[1] + ((i >> 1) & 1), first[2] + ((i >> 2) & 1) };
        for (int k = 0; k < b->seed_count[c[2]][c[1]][c[0]]; k++) {
            const rocks__seed *s = &b->seeds[c[2]][c[1]][c[0]][k];
            float d = rocks__distance(s->q, (float)(v[0] - c[0] * M) + 0.5f - s->u[0], (float)(v[1] - c[1] * M) + 0.5f - s->u[1],
                                      (float)(v[2] - c[2] * M) + 0.5f - s->u[2]);
            if (d < best || (d == best && s->id < best_id)) best = d, best_id = s->id, owner = seed_key(c, k);
        }
    }
    return owner;
}

static size_t middle_index(const int v[3]) {
    return ((size_t)(v[2] - VOXELS) * VOXELS + (v[1] - VOXELS)) * VOXELS + (v[0] - VOXELS);
}
static bool in_middle(const int v[3]) {
    for (int a = 0; a < 3; a++)
        if (v[a] < VOXELS || v[a] >= 2 * VOXELS) return false;
    return true;
}

/* Places every tile of the block and writes each placed rock's voxels into `claimed` (middle
 * tile only); counts voxels claimed twice. Calls `each` per placed rock when given. */
typedef void (*placed_fn)(void *user, const rocks__set *full, uint32_t rock, const int region_origin[3]);
static int place_block(const rocks__set *full, const block *b, int32_t *claimed, placed_fn each, void *user) {
    const rocks_tileset *set = &full->set;
    int twice = 0;
    for (int lz = 0; lz < BLOCK; lz++)
        for (int ly = 0; ly < BLOCK; ly++)
            for (int lx = 0; lx < BLOCK; lx++) {
                const rocks_tile *tile = &set->tiles[tile_of(b, lx, ly, lz)];
                for (uint32_t e = tile->first; e < tile->first + tile->count; e++) {
                    const rocks_tile_entry *entry = &set->entries[e];
                    uint32_t r = entry->rock;
                    int origin[3] = { lx + entry->offset[0], ly + entry->offset[1], lz + entry->offset[2] };
                    int cell[3];
                    for (int a = 0; a < 3; a++) cell[a] = origin[a] * N + full->rock_cell[r][a];
                    int32_t key = seed_key(cell, full->rock_k[r]);
                    if (each) each(user, full, r, origin);
                    if (!claimed) continue;
                    for (uint32_t i = 0; i < full->voxel_count[r]; i++) {
                        const int16_t *vx = full->voxels[full->voxel_first[r] + i];
                        int v[3] = { origin[0] * VOXELS + vx[0], origin[1] * VOXELS + vx[1], origin[2] * VOXELS + vx[2] };
                        if (!in_middle(v)) continue;
                        size_t at = middle_index(v);
                        if (claimed[at] != -1) twice++;
                        claimed[at] = key;
                    }
                }
            }
    return twice;
}

static void check_consistency(const rocks__set *full, uint64_t colouring) {
    block *b = block_make(&full->params, colouring);
    size_t total = (size_t)VOXELS * VOXELS * VOXELS;
    int32_t *claimed = malloc(total * sizeof *claimed);
    for (size_t i = 0; i < total; i++) claimed[i] = -1;
    int twice = place_block(full, b, claimed, NULL, NULL);
    cr_expect_eq(twice, 0, "colouring %llu: %d voxels claimed by two rocks", (unsigned long long)colouring, twice);
    int wrong = 0, unclaimed = 0;
    int v[3];
    for (v[2] = VOXELS; v[2] < 2 * VOXELS; v[2]++)
        for (v[1] = VOXELS; v[1] < 2 * VOXELS; v[1]++)
            for (v[0] = VOXELS; v[0] < 2 * VOXELS; v[0]++) {
                int32_t want = brute_owner(b, v), got = claimed[middle_index(v)];
                unclaimed += got == -1;
                wrong += got != want;
            }
    cr_expect_eq(wrong, 0, "colouring %llu: %d voxels (%d unclaimed) differ from the global Voronoi",
                 (unsigned long long)colouring, wrong, unclaimed);
    free(claimed);
    free(b);
}

static void tiles_equal_the_global_voronoi(rocks__set *full) {
    for (uint64_t colouring = 1; colouring <= 4; colouring++) check_consistency(full, colouring * 7919);
}

Test(rocks_tiles, closures_of_same_dimension_features_do_not_overlap) {
    /* Per axis the closure of the plane below a tile is cells 0, 1 and of the plane above
     * n − 2, n − 1 (and the interior the rest): disjoint for every n ≥ 4, so each cell has one
     * feature. Checked by counting, for every cell of a tile, the feature closures holding it. */
    for (int n = 4; n <= 8; n++)
        for (int i = 0; i < n; i++) {
            int holders = (i <= 1) + (i >= n - 2) + (i >= 2 && i <= n - 3);
            cr_expect_eq(holders, 1, "n = %d, cell %d: %d closures", n, i, holders);
        }
}

/* A face rock that straddles its face, checked against the global Voronoi in two colourings that
 * agree on the face's corners and differ everywhere else. */
static void straddling_rock_is_the_same_whatever_the_neighbours(rocks__set *full) {
    const rocks__params *params = &full->params;
    block *a = block_make(params, 11), *b = block_make(params, 11);
    /* the face x = 2 between tiles (1,1,1) and (2,1,1): its corners (2, 1…2, 1…2) */
    for (int z = 0; z <= BLOCK; z++)
        for (int y = 0; y <= BLOCK; y++)
            for (int x = 0; x <= BLOCK; x++)
                if (!(x == 2 && y >= 1 && y <= 2 && z >= 1 && z <= 2)) b->colour[z][y][x] ^= 1;
    free(b);
    uint8_t saved[BLOCK + 1][BLOCK + 1][BLOCK + 1];
    memcpy(saved, a->colour, sizeof saved);
    b = calloc(1, sizeof *b);
    memcpy(b->colour, saved, sizeof saved);
    for (int z = 0; z <= BLOCK; z++)
        for (int y = 0; y <= BLOCK; y++)
            for (int x = 0; x <= BLOCK; x++)
                if (!(x == 2 && y >= 1 && y <= 2 && z >= 1 && z <= 2)) b->colour[z][y][x] ^= 1;
    for (int z = 0; z < CELLS; z++)
        for (int y = 0; y < CELLS; y++)
            for (int x = 0; x < CELLS; x++) {
                int cell[3] = { x, y, z };
                b->seed_count[z][y][x] = rocks__cell_seeds(params, cell, block_colour, b, b->seeds[z][y][x]);
            }
    cr_assert_neq(tile_of(a, 1, 1, 1), tile_of(b, 1, 1, 1));
    cr_assert_neq(tile_of(a, 2, 1, 1), tile_of(b, 2, 1, 1));
    /* the region instance of that face: normal x, corners (y, z) ∈ {0, 1}² in bit y + 2z */
    int bits = 0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) bits |= a->colour[1 + j][1 + i][2] << (i + 2 * j);
    int region = 14 + 0 * 16 + bits, checked = 0;
    for (uint32_t r = 0; r < full->set.rock_count && checked < 3; r++) {
        if (full->rock_region[r] != region || full->voxel_count[r] == 0) continue;
        bool below = false, above = false;
        for (uint32_t i = 0; i < full->voxel_count[r]; i++) {
            int x = full->voxels[full->voxel_first[r] + i][0];
            below |= x < 0, above |= x >= 0;
        }
        if (!(below && above)) continue;
        /* every voxel of the rock, moved to the face at lattice (2, 1, 1), is owned by its seed in
         * both colourings, and so is nothing else near it */
        int cell[3] = { 2 * N + full->rock_cell[r][0], N + full->rock_cell[r][1], N + full->rock_cell[r][2] };
        int32_t key = seed_key(cell, full->rock_k[r]);
        for (int which = 0; which < 2; which++) {
            const block *blk = which ? b : a;
            uint32_t owned = 0;
            int v[3];
            for (v[2] = cell[2] * M - M; v[2] < cell[2] * M + 2 * M; v[2]++)
                for (v[1] = cell[1] * M - M; v[1] < cell[1] * M + 2 * M; v[1]++)
                    for (v[0] = cell[0] * M - M; v[0] < cell[0] * M + 2 * M; v[0]++) owned += brute_owner(blk, v) == key;
            cr_expect_eq(owned, full->voxel_count[r], "rock %u: %u voxels in the tile set, %u in colouring %d", r,
                         full->voxel_count[r], owned, which);
            for (uint32_t i = 0; i < full->voxel_count[r]; i++) {
                const int16_t *vx = full->voxels[full->voxel_first[r] + i];
                int g[3] = { 2 * VOXELS + vx[0], VOXELS + vx[1], VOXELS + vx[2] };
                cr_expect_eq(brute_owner(blk, g), key);
            }
        }
        checked++;
    }
    cr_expect_gt(checked, 0, "no rock straddles the face");
    free(a);
    free(b);
}

/* ---- no doubled rocks ------------------------------------------------------------------------- */

typedef struct listing {
    uint8_t *seen;
    int doubled;
} listing;

static void list_rock(void *user, const rocks__set *full, uint32_t r, const int origin[3]) {
    listing *l = user;
    int cell[3];
    for (int a = 0; a < 3; a++) cell[a] = origin[a] * N + full->rock_cell[r][a];
    int32_t key = seed_key(cell, full->rock_k[r]);
    if (l->seen[key]) l->doubled++;
    l->seen[key] = 1;
}

static void every_seed_is_listed_by_exactly_one_tile(rocks__set *full) {
    block *b = block_make(&full->params, 99);
    listing l = { .seen = calloc((size_t)CELLS * CELLS * CELLS * 8, 1) };
    place_block(full, b, NULL, list_rock, &l);
    cr_expect_eq(l.doubled, 0);
    int missing = 0;
    for (int z = 0; z < CELLS; z++)
        for (int y = 0; y < CELLS; y++)
            for (int x = 0; x < CELLS; x++)
                for (int k = 0; k < b->seed_count[z][y][x]; k++) {
                    int cell[3] = { x, y, z };
                    missing += !l.seen[seed_key(cell, k)];
                }
    cr_expect_eq(missing, 0, "%d seeds of the block are in no tile", missing);
    free(l.seen);
    free(b);
}

/* ---- contacts, interpenetration ----------------------------------------------------------------- */

static float point_triangle_distance(const float p[3], const float a[3], const float b[3], const float c[3]) {
    /* Ericson, Real-Time Collision Detection §5.1.5 */
    float ab[3], ac[3], ap[3], q[3];
    for (int i = 0; i < 3; i++) ab[i] = b[i] - a[i], ac[i] = c[i] - a[i], ap[i] = p[i] - a[i];
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    float d1 = DOT(ab, ap), d2 = DOT(ac, ap);
    if (d1 <= 0 && d2 <= 0) memcpy(q, a, sizeof q);
    else {
        float bp[3], cp[3];
        for (int i = 0; i < 3; i++) bp[i] = p[i] - b[i], cp[i] = p[i] - c[i];
        float d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
        float vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0 && d4 <= d3) memcpy(q, b, sizeof q);
        else if (d6 >= 0 && d5 <= d6) memcpy(q, c, sizeof q);
        else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
            float v = d1 / (d1 - d3);
            for (int i = 0; i < 3; i++) q[i] = a[i] + v * ab[i];
        } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
            float w = d2 / (d2 - d6);
            for (int i = 0; i < 3; i++) q[i] = a[i] + w * ac[i];
        } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
            float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            for (int i = 0; i < 3; i++) q[i] = b[i] + w * (c[i] - b[i]);
        } else {
            float denom = 1.0f / (va + vb + vc), v = vb * denom, w = vc * denom;
            for (int i = 0; i < 3; i++) q[i] = a[i] + ab[i] * v + ac[i] * w;
        }
    }
#undef DOT
    float d = 0;
    for (int i = 0; i < 3; i++) d += (p[i] - q[i]) * (p[i] - q[i]);
    return sqrtf(d);
}

static float mesh_distance(const rocks_tileset *set, uint32_t r, const float p[3]) {
    const rocks_rock *rock = &set->rocks[r];
    float best = INFINITY;
    for (uint32_t i = 0; i < rock->index_count[0]; i += 3) {
        const uint16_t *t = set->indices + rock->index_first[0] + i;
        const rocks_vertex *v = set->vertices + rock->vertex_first;
        float d = point_triangle_distance(p, v[t[0]].position, v[t[1]].position, v[t[2]].position);
        if (d < best) best = d;
    }
    return best;
}

/* The marching-cubes surfaces of two touching rocks meet within a voxel of c_ij (the kept
 * contact has the other rock across the voxel face nearest to it); LOD 0 may then stray by the
 * simplifier's error bound, ROCKS__LOD0_ERROR voxels. */
Test(rocks_tiles, both_meshes_pass_within_a_voxel_and_the_simplifier_s_error_of_every_contact) {
    rocks_tileset_desc desc = quick_desc();
    rocks_tileset *set = rocks_tileset_create(&desc);
    cr_assert_not_null(set);
    const float voxel = (1.0f + ROCKS__LOD0_ERROR) / (float)(desc.cells * desc.voxels_per_cell);
    uint32_t checked = 0, far = 0, far_other = 0;
    float worst = 0;
    for (uint32_t r = 0; r < set->rock_count; r++) {
        const rocks_rock *rock = &set->rocks[r];
        for (uint32_t c = rock->contact_first; c < rock->contact_first + rock->contact_count; c++) {
            const rocks_contact *contact = &set->contacts[c];
            float d = mesh_distance(set, r, contact->point);
            if (d > worst) worst = d;
            far += d > voxel;
            if (contact->other != ROCKS_CONTACT_VARIES) {
                float p[3];
                for (int a = 0; a < 3; a++) p[a] = contact->point[a] - contact->other_offset[a];
                float e = mesh_distance(set, contact->other, p);
                if (e > worst) worst = e;
                far_other += e > voxel;
            }
            checked++;
        }
    }
    cr_expect_gt(checked, 1000u, "%u contacts", checked);
    cr_expect_eq(far, 0u, "%u of %u contacts are further than the bound from their rock (worst %.2f of it)", far, checked,
                 (double)(worst / voxel));
    cr_expect_eq(far_other, 0u, "%u contacts are further than the bound from the other rock (worst %.2f of it)", far_other,
                 (double)(worst / voxel));
    rocks_tileset_destroy(set);
}

/* A vertex of one rock may not lie deeper than a voxel inside another: the voxel holding it and
 * its 26 neighbours all in the other rock's (pre-erosion, global brute-force) voxel set. */
typedef struct penetration {
    const int32_t *owner;             /* middle tile, global Voronoi */
    int deep, vertices;
} penetration;

static void check_vertices(void *user, const rocks__set *full, uint32_t r, const int origin[3]) {
    penetration *p = user;
    const rocks_rock *rock = &full->set.rocks[r];
    int cell[3];
    for (int a = 0; a < 3; a++) cell[a] = origin[a] * N + full->rock_cell[r][a];
    int32_t self = seed_key(cell, full->rock_k[r]);
    for (uint32_t i = 0; i < rock->vertex_count; i++) {
        const rocks_vertex *v = &full->set.vertices[rock->vertex_first + i];
        int vox[3];
        for (int a = 0; a < 3; a++) vox[a] = (int)floorf((v->position[a] + (float)origin[a]) * VOXELS);
        int32_t other = -2;
        bool deep = true;
        for (int n = 0; n < 27 && deep; n++) {
            int w[3] = { vox[0] + n % 3 - 1, vox[1] + (n / 3) % 3 - 1, vox[2] + n / 9 - 1 };
            if (!in_middle(w)) { deep = false; break; }
            int32_t o = p->owner[middle_index(w)];
            if (other == -2) other = o;
            deep = o == other && o != self;
        }
        p->deep += deep;
        p->vertices++;
    }
}

static void no_rock_reaches_deeper_than_a_voxel_into_another(rocks__set *full) {
    block *b = block_make(&full->params, 31337);
    size_t total = (size_t)VOXELS * VOXELS * VOXELS;
    int32_t *owner = malloc(total * sizeof *owner);
    int v[3];
    for (v[2] = VOXELS; v[2] < 2 * VOXELS; v[2]++)
        for (v[1] = VOXELS; v[1] < 2 * VOXELS; v[1]++)
            for (v[0] = VOXELS; v[0] < 2 * VOXELS; v[0]++) owner[middle_index(v)] = brute_owner(b, v);
    penetration p = { .owner = owner };
    place_block(full, b, NULL, check_vertices, &p);
    cr_expect_gt(p.vertices, 10000);
    cr_expect_eq(p.deep, 0, "%d of %d vertices lie deep inside another rock", p.deep, p.vertices);
    free(owner);
    free(b);
}

/* The four checks above on one set: building it with its voxels kept is most of their time
 * under the sanitizers, so it is built once (each check reads it and leaves it as it was). */
Test(rocks_tiles, one_set_against_the_global_voronoi_its_seeds_its_straddling_rocks_and_overlaps) {
    rocks__set *full = build_full();
    tiles_equal_the_global_voronoi(full);
    straddling_rock_is_the_same_whatever_the_neighbours(full);
    every_seed_is_listed_by_exactly_one_tile(full);
    no_rock_reaches_deeper_than_a_voxel_into_another(full);
    rocks_tileset_destroy(&full->set);
}

/* ---- meshes ---------------------------------------------------------------------------------- */

static int compare_edge(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Erosion (001 §5) worked out again the plain way, from what a region keeps: each rock's
 * Voronoi voxels and its contacts. ω is the minimum over the contacts of 0 within a, linear to
 * 1 at b; each step every voxel with ρ > 0, ω > 0 and a face neighbour at ρ = 0 (outside the rock
 * or emptied) loses ε·k/26·ω, k its neighbours of 26 at ρ = 0, all reading the step's start (a
 * voxel that goes below 0 is 0). The builder keeps running counts instead; the two agree up to
 * the contact points' rounding (kept as floats in tile units, used in doubles by the builder). */
static float ramp(double r, float a, float b) {
    float rf = (float)r;
    return rf < a ? 0.0f : rf < b ? (rf - a) / (b - a) : 1.0f;
}

static void plain_erosion(const rocks__params *params, const rocks__region_result *res, uint32_t r, float *out) {
    const uint32_t first = res->voxel_first[r], count = res->voxel_count[r];
    int lo[3] = { INT32_MAX, INT32_MAX, INT32_MAX }, hi[3] = { INT32_MIN, INT32_MIN, INT32_MIN };
    for (uint32_t i = 0; i < count; i++)
        for (int a = 0; a < 3; a++) {
            int v = res->voxels[first + i][a];
            lo[a] = v - 1 < lo[a] ? v - 1 : lo[a], hi[a] = v + 1 > hi[a] ? v + 1 : hi[a];
        }
    const int sx = hi[0] - lo[0] + 1, sy = hi[1] - lo[1] + 1, sz = hi[2] - lo[2] + 1;
    const size_t total = (size_t)sx * sy * sz;
    float *rho = calloc(total, sizeof *rho), *next = calloc(total, sizeof *next), *omega = calloc(total, sizeof *omega);
#define AT(x, y, z) (((size_t)((z) - lo[2]) * sy + (size_t)((y) - lo[1])) * sx + (size_t)((x) - lo[0]))
    const double voxels_per_tile = params->n * params->m;
    const rocks_rock *rock = &res->rocks[r];
    for (uint32_t i = 0; i < count; i++) {
        const int16_t *v = res->voxels[first + i];
        size_t at = AT(v[0], v[1], v[2]);
        rho[at] = 1.0f, omega[at] = 1.0f;
        for (uint32_t c = rock->contact_first; c < rock->contact_first + rock->contact_count; c++) {
            double d2 = 0.0;
            for (int a = 0; a < 3; a++) {
                double d = v[a] + 0.5 - (double)res->contacts[c].point[a] * voxels_per_tile;
                d2 += d * d;
            }
            omega[at] = fminf(omega[at], ramp(sqrt(d2), params->contact_voxels, params->blend_voxels));
        }
    }
    for (int step = 0; step < params->desc.erosion_steps; step++) {
        memcpy(next, rho, total * sizeof *rho);
        for (int z = lo[2] + 1; z < hi[2]; z++)
            for (int y = lo[1] + 1; y < hi[1]; y++)
                for (int x = lo[0] + 1; x < hi[0]; x++) {
                    size_t at = AT(x, y, z);
                    if (!(rho[at] > 0.0f) || !(omega[at] > 0.0f)) continue;
                    int empty = 0;
                    bool exposed = false;
                    for (int n = 0; n < 27; n++) {
                        int dx = n % 3 - 1, dy = n / 3 % 3 - 1, dz = n / 9 - 1;
                        bool zero = rho[AT(x + dx, y + dy, z + dz)] == 0.0f;
                        empty += zero;
                        exposed |= zero && abs(dx) + abs(dy) + abs(dz) == 1;
                    }
                    if (!exposed) continue;
                    float value = rho[at] - params->desc.erosion_rate * ((float)empty / 26.0f) * omega[at];
                    next[at] = value > 0.0f ? value : 0.0f;
                }
        memcpy(rho, next, total * sizeof *rho);
    }
    for (uint32_t i = 0; i < count; i++) out[i] = rho[AT(res->voxels[first + i][0], res->voxels[first + i][1], res->voxels[first + i][2])];
#undef AT
    free(rho), free(next), free(omega);
}

Test(rocks_tiles, erosion_matches_a_plain_step_by_step_erosion) {
    rocks_tileset_desc desc = small_desc();
    rocks__params params;
    cr_assert(rocks__params_make(&desc, &params));
    uint32_t voxels = 0, far = 0, eroded = 0;
    double worst = 0.0;
    for (int region = ROCKS__REGION_COUNT - 6; region < ROCKS__REGION_COUNT; region++) {   /* six centre regions */
        rocks__region_result res;
        rocks__region_build(&params, &(rocks__build_options){ .keep_voxels = true }, region, &res);
        for (uint32_t r = 0; r < res.rock_count; r++) {
            float *plain = malloc((res.voxel_count[r] + 1) * sizeof *plain);
            plain_erosion(&params, &res, r, plain);
            for (uint32_t i = 0; i < res.voxel_count[r]; i++) {
                double d = fabs((double)plain[i] - (double)res.voxel_rho[res.voxel_first[r] + i]);
                worst = fmax(worst, d);
                far += d > 1e-4;
                eroded += plain[i] < 1.0f;
                voxels++;
            }
            free(plain);
        }
        rocks__region_result_free(&res);
    }
    cr_expect_gt(voxels, 10000u, "%u voxels", voxels);
    cr_expect_gt(eroded, voxels / 10, "%u of %u voxels eroded: the test would not see erosion", eroded, voxels);
    /* measured: every voxel within 2.2e-6 (the contacts' rounding); a tie at ρ = 0 could still go
     * either way, so a few voxels are let off, not a face of a rock */
    cr_expect_leq(far, voxels / 1000, "%u of %u voxels differ by more than 1e-4 (worst %.2g)", far, voxels, worst);
}

Test(rocks_tiles, every_level_of_every_rock_is_closed) {
    rocks_tileset_desc desc = quick_desc();
    rocks_tileset *set = rocks_tileset_create(&desc);
    cr_assert_not_null(set);
    int open = 0, empty = 0;
    double triangles[ROCKS_LODS] = { 0 };
    for (uint32_t r = 0; r < set->rock_count; r++) {
        const rocks_rock *rock = &set->rocks[r];
        for (int l = 0; l < ROCKS_LODS; l++) {
            uint32_t count = rock->index_count[l];
            triangles[l] += count / 3;
            if (count == 0) { empty++; continue; }
            /* undirected edges, each must appear exactly twice */
            uint64_t *edges = malloc(count * sizeof *edges);
            const uint16_t *t = set->indices + rock->index_first[l];
            for (uint32_t i = 0; i < count; i += 3)
                for (int e = 0; e < 3; e++) {
                    uint64_t a = t[i + e], b = t[i + (e + 1) % 3];
                    edges[i + e] = a < b ? a << 32 | b : b << 32 | a;
                }
            qsort(edges, count, sizeof *edges, compare_edge);
            for (uint32_t i = 0; i < count;) {
                uint32_t j = i;
                while (j < count && edges[j] == edges[i]) j++;
                if (j - i != 2) { open++; break; }
                i = j;
            }
            free(edges);
        }
    }
    cr_expect_eq(empty, 0);
    cr_expect_eq(open, 0, "%d rock levels are not closed", open);
    /* the levels shrink as promised: about 1/4 and 1/12 of LOD 0 (the simplifier stops early where
     * collapsing would change the shape too much, so only roughly) */
    cr_expect_lt(triangles[1], 0.6 * triangles[0]);
    cr_expect_lt(triangles[2], 0.3 * triangles[0]);
    rocks_tileset_destroy(set);
}

/* ---- determinism --------------------------------------------------------------------------------- */

static bool same_arrays(const rocks_tileset *a, const rocks_tileset *b) {
    return a->rock_count == b->rock_count && a->vertex_count == b->vertex_count && a->index_count == b->index_count &&
           a->anchor_count == b->anchor_count && a->contact_count == b->contact_count && a->entry_count == b->entry_count &&
           memcmp(a->tiles, b->tiles, sizeof a->tiles) == 0 &&
           memcmp(a->rocks, b->rocks, a->rock_count * sizeof *a->rocks) == 0 &&
           memcmp(a->vertices, b->vertices, a->vertex_count * sizeof *a->vertices) == 0 &&
           memcmp(a->indices, b->indices, a->index_count * sizeof *a->indices) == 0 &&
           memcmp(a->anchors, b->anchors, a->anchor_count * sizeof *a->anchors) == 0 &&
           memcmp(a->contacts, b->contacts, a->contact_count * sizeof *a->contacts) == 0 &&
           memcmp(a->entries, b->entries, a->entry_count * sizeof *a->entries) == 0;
}

Test(rocks_tiles, one_and_two_workers_give_the_same_bytes) {
    job_system *one = job_system_create(&(job_system_desc){ .threads = 1 });
    job_system *two = job_system_create(&(job_system_desc){ .threads = 2 });
    rocks_tileset_desc desc = quick_desc();
    desc.jobs = one;
    rocks_tileset *a = rocks_tileset_create(&desc);
    desc.jobs = two;
    rocks_tileset *b = rocks_tileset_create(&desc);
    cr_assert(a && b);
    cr_expect(same_arrays(a, b));
    cr_expect_gt(a->rock_count, 1000u);
    rocks_tileset_destroy(a);
    rocks_tileset_destroy(b);
    job_system_destroy(one);
    job_system_destroy(two);
}

/* The ownership loop's vector paths (rocks__lanes): the same bytes on each path this CPU has. */
Test(rocks_tiles, every_vector_path_gives_the_same_bytes) {
    rocks_tileset_desc desc = quick_desc();
    cr_assert(rocks__lanes_set(ROCKS__LANES_BASELINE));
    rocks_tileset *baseline = rocks_tileset_create(&desc);
    cr_assert_not_null(baseline);
    if (rocks__lanes_set(ROCKS__LANES_AVX2)) {
        rocks_tileset *wide = rocks_tileset_create(&desc);
        cr_assert_not_null(wide);
        cr_expect(same_arrays(baseline, wide), "the AVX2 path differs from the baseline");
        rocks_tileset_destroy(wide);
    } else {
        cr_log_info("no AVX2 on this CPU: the baseline path only");
    }
    cr_expect_not(rocks__lanes_set((rocks__lanes)99), "an unknown path accepted");
    rocks__lanes_set(ROCKS__LANES_AUTO);
    rocks_tileset_destroy(baseline);
}

/* ---- the cache ----------------------------------------------------------------------------------- */

static rocks_tileset_desc cache_desc(const char *path) {
    return (rocks_tileset_desc){ .seed = 3, .cells = 4, .voxels_per_cell = 4, .shape = ROCKS_SHAPE_ROUND, .cache_path = path };
}

static unsigned char *read_all(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *data = malloc(*size);
    cr_assert_eq(fread(data, 1, *size, f), *size);
    fclose(f);
    return data;
}

static void write_all(const char *path, const unsigned char *data, size_t size) {
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f);
    fwrite(data, 1, size, f);
    fclose(f);
}

/* Runs rocks_tileset_create with stderr in a file; returns the set and the lines logged. */
static rocks_tileset *create_counting_notices(const rocks_tileset_desc *desc, int *lines) {
    fflush(stderr);
    int saved = dup(2);
    FILE *log = tmpfile();
    dup2(fileno(log), 2);
    rocks_tileset *set = rocks_tileset_create(desc);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(log);
    *lines = 0;
    int c;
    while ((c = fgetc(log)) != EOF) *lines += c == '\n';
    fclose(log);
    return set;
}

Test(rocks_tiles, cache_reloads_and_rebuilds_whatever_is_wrong_with_it) {
    char dir[] = "/tmp/test_rocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/rocks.bin", dir);
    rocks_tileset_desc desc = cache_desc(path);
    int lines;
    rocks_tileset *built = create_counting_notices(&desc, &lines);
    cr_assert_not_null(built);
    cr_expect_not(built->from_cache);
    cr_expect_eq(lines, 1, "a missing cache: one notice");
    rocks_tileset *loaded = create_counting_notices(&desc, &lines);
    cr_expect(loaded->from_cache);
    cr_expect_eq(lines, 0);
    cr_expect(same_arrays(built, loaded));
    rocks_tileset_destroy(loaded);

    size_t size;
    unsigned char *good = read_all(path, &size);
    rocks__params params;
    cr_assert(rocks__params_make(&desc, &params));
    /* every truncation length: the reader refuses each (the size its counts imply is checked
     * before anything is read from the arrays) */
    int accepted = 0;
    for (size_t cut = 0; cut < size; cut++) {
        rocks__set scratch;
        memset(&scratch, 0, sizeof scratch);
        const char *why = NULL;
        if (rocks__cache_parse(good, cut, &params, &scratch, &why)) {
            accepted++;
            rocks__set_free_arrays(&scratch);
        }
    }
    cr_expect_eq(accepted, 0, "%d truncated caches accepted", accepted);
    /* flipped bytes at many positions: header, tiles, every array, the checksum */
    for (int i = 0; i < 64; i++) {
        size_t at = i < 32 ? (size_t)i * 7 : (size_t)(((uint64_t)(i - 32) * 2654435761u) % size);
        unsigned char *bad = malloc(size);
        memcpy(bad, good, size);
        bad[at] ^= (unsigned char)(1u << (i % 8));
        rocks__set scratch;
        memset(&scratch, 0, sizeof scratch);
        const char *why = NULL;
        bool ok = rocks__cache_parse(bad, size, &params, &scratch, &why);
        cr_expect_not(ok, "a flipped bit at byte %zu was accepted", at);
        if (ok) rocks__set_free_arrays(&scratch);
        free(bad);
    }
    /* through rocks_tileset_create: a cut file, a flipped byte, an old version number; each is
     * rebuilt with one notice, gives the same set, and leaves a good cache behind */
    for (int kind = 0; kind < 3; kind++) {
        unsigned char *bad = malloc(size);
        memcpy(bad, good, size);
        size_t bad_size = size;
        if (kind == 0) bad_size = size / 2;
        if (kind == 1) bad[size / 3] ^= 0x10;
        if (kind == 2) { uint32_t old = ROCKS__CACHE_VERSION - 1; memcpy(bad + 8, &old, sizeof old); }
        write_all(path, bad, bad_size);
        free(bad);
        rocks_tileset *again = create_counting_notices(&desc, &lines);
        cr_assert_not_null(again);
        cr_expect_not(again->from_cache, "case %d", kind);
        cr_expect_eq(lines, 1, "case %d: %d lines", kind, lines);
        cr_expect(same_arrays(built, again), "case %d", kind);
        rocks_tileset_destroy(again);
        rocks_tileset *reread = create_counting_notices(&desc, &lines);
        cr_expect(reread->from_cache, "case %d: the rewritten cache", kind);
        rocks_tileset_destroy(reread);
    }
    /* other parameters: rebuilt, not read */
    desc.seed = 4;
    rocks_tileset *other = create_counting_notices(&desc, &lines);
    cr_expect_not(other->from_cache);
    cr_expect_eq(lines, 1);
    rocks_tileset_destroy(other);
    free(good);
    rocks_tileset_destroy(built);
    remove(path);
    rmdir(dir);
}

/* ---- parameters ----------------------------------------------------------------------------------- */

Test(rocks_tiles, bad_parameters_give_null) {
    rocks_tileset_desc bad[] = {
        { .cells = 3 },
        { .cells = 9 },
        { .cells = -1 },
        { .voxels_per_cell = -4 },
        { .voxels_per_cell = 3 },
        { .max_seeds_per_cell = -1 },
        { .g_max = -2.0f },
        { .contact_radius = -0.1f },
        { .erosion_steps = -1 },
        { .erosion_rate = -0.5f },
        { .shape = (rocks_shape)7 },
        { .scale_min = { -1, 1, 1 }, .scale_max = { 1, 1, 1 } },
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) cr_expect_null(rocks_tileset_create(&bad[i]), "desc %zu", i);
    cr_expect_null(rocks_tileset_create(NULL));
}

Test(rocks_tiles, hull_distance_is_exact_inside_and_a_lower_bound_outside) {
    rocks_rock rock = { 0 };
    /* the unit cube [0, 1]³ as a 26-DOP */
    for (int a = 0; a < ROCKS_HULL_AXES; a++) {
        float lo = 0, hi = 0;
        for (int c = 0; c < 8; c++) {
            float d = rocks_hull_axes[a][0] * (c & 1) + rocks_hull_axes[a][1] * ((c >> 1) & 1) + rocks_hull_axes[a][2] * ((c >> 2) & 1);
            if (c == 0 || d < lo) lo = d;
            if (c == 0 || d > hi) hi = d;
        }
        rock.hull[2 * a] = lo, rock.hull[2 * a + 1] = hi;
    }
    float normal[3];
    float inside = rocks_hull_distance(&rock, (float[3]){ 0.5f, 0.5f, 0.2f }, normal);
    cr_expect(fabsf(inside + 0.2f) < 1e-5f, "%g", (double)inside);
    cr_expect(fabsf(normal[2] + 1.0f) < 1e-5f);
    float outside = rocks_hull_distance(&rock, (float[3]){ 2.0f, 2.0f, 2.0f }, normal);
    cr_expect(outside > 0.0f && outside <= sqrtf(3.0f) + 1e-5f, "%g", (double)outside);
}
