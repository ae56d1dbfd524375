/* rocks_internal.h — the tile set's private parts (paper 001), shared by rocks_tiles.c,
 * rocks_voronoi.c, rocks_mesh.c, rocks_cache.c and the tests (which may include it); and the
 * block tiles' cache file (rocks_blocks_cache.c, paper 003), shared with rocks_blocks.c.
 *
 * Frames. Everything inside the builder is in integer cells and voxels relative to one origin
 * (a region's origin, or the test's block origin): cell C covers voxels C·m … C·m + m − 1 on each
 * axis (m = voxels_per_cell). A seed is (its cell, its position inside the cell in voxel units,
 * its quadratic form), and the offset from a seed to a voxel centre V + ½ is computed as
 *     (float)(V − P·m) + 0.5 − u
 * which depends on integers that do not change when both are moved by whole cells. So a voxel's
 * distances, and its owner, are the same bits whatever frame computes them: the per-region
 * builder and the test's global brute force agree exactly, not just up to rounding.
 */
#ifndef ROCKS_INTERNAL_H
#define ROCKS_INTERNAL_H

#include "rocks/rocks.h"

#include <stdbool.h>
#include <stdint.h>

#define ROCKS__MAX_SEEDS_PER_CELL 8
#define ROCKS__REGION_COUNT (2 + 12 + 48 + 256)   /* 318 region instances (001 §3) */
#define ROCKS__LOD0_ERROR 0.6f                    /* voxels LOD 0 may stray from the marching cubes
                                                     (0.5 from the dual surface: rocks_mesh.c) */
#define ROCKS__ANCHORS 16                         /* the seed and up to 15 voxel centres */
/* Bump it with ANY change to what a build makes (seeds, ownership, contacts, erosion, meshes,
 * anchors): a cache holds a build's output under its desc, so an old one would read as valid. */
#define ROCKS__CACHE_CHECKSUM_SEED 0x726f636b63616368ull   /* core_hash_bytes' seed for the file's checksum */
#define ROCKS__CACHE_VERSION 5u   /* 2: LOD 0 at 0.6 voxel; contacts across the nearest face;
                                     3: LODs by rocks_simplify.c, closed without falling back;
                                     4: LODs from the dual surface at two voxels (rocks_surface.c);
                                     5: its normals' agreement at 0.35 */

enum { ROCKS__VERTEX = 0, ROCKS__EDGE = 1, ROCKS__FACE = 2, ROCKS__CENTRE = 3 };

/* One seed point p_k with its anisotropic distance d_k (001 §4). */
typedef struct rocks__seed {
    uint64_t id;        /* hash of its feature, colours, offset and index: orders ties */
    int cell[3];        /* in the frame's cells */
    float u[3];         /* position inside the cell, in voxels (0 … m) */
    float q[6];         /* d(δ) = δᵀ·Q·δ with Q = (α x xᵀ + β y yᵀ + γ z zᵀ)/g:
                           q00, q11, q22, 2q01, 2q02, 2q12 */
    float q_min;        /* Q's smallest eigenvalue, min(α, β, γ)/g: d ≥ q_min·|δ|² */
    int k;              /* index within its cell */
} rocks__seed;

/* The vector path of the ownership loop (rocks_voronoi.c) and the anchors' farthest-point
 * rounds (rocks_mesh.c): the widest the CPU has unless set.
 * Every path gives the same bits; the tests set each the CPU has. rocks__lanes_set returns false,
 * changing nothing, for a path this CPU lacks. */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define ROCKS__HAS_AVX2 1
#else
#define ROCKS__HAS_AVX2 0
#endif
typedef enum rocks__lanes { ROCKS__LANES_AUTO, ROCKS__LANES_BASELINE, ROCKS__LANES_AVX2 } rocks__lanes;
bool rocks__lanes_supported(rocks__lanes path);
bool rocks__lanes_set(rocks__lanes path);
bool rocks__lanes_wide(void);   /* the path in use is AVX2 */

/* d_k(δ) for an offset δ from the seed in voxels. The one formula both the builder's loops and
 * the tests use (the same operations in the same order give the same bits; no FMA contraction
 * on the portable x86-64 target). */
static inline float rocks__distance(const float q[6], float dx, float dy, float dz) {
    float b = q[3] * dy + q[4] * dz;
    float a = (q[1] * dy + q[5] * dz) * dy + q[2] * dz * dz;
    return (q[0] * dx + b) * dx + a;
}

static inline int rocks__floor_div(int a, int b) {
    int q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

/* The desc with its defaults filled in, and what follows from it. */
typedef struct rocks__params {
    rocks_tileset_desc desc;            /* jobs and cache_path NULL */
    int n, m;                         /* cells a tile side, voxels a cell side */
    int seeds_max;                    /* s */
    bool seeds_fixed;                 /* n_k = s in every cell (round and slab presets) */
    float contact_voxels, blend_voxels;   /* a and b in voxels, after the floor below */
} rocks__params;

/* Fills `out` from desc (defaults, ranges). False with a message for bad values. */
bool rocks__params_make(const rocks_tileset_desc *desc, rocks__params *out);

/* Colour of lattice point (x, y, z) of the caller's frame; only the points of the feature being
 * generated are asked for. */
typedef int (*rocks__colour_fn)(const void *user, int x, int y, int z);

/* The seeds of one cell (in the caller's frame): a pure function of the lowest-dimensional
 * feature whose closure holds the cell, that feature's corner colours, the cell's offset from the
 * feature's origin and desc.seed (001 §3). Writes up to ROCKS__MAX_SEEDS_PER_CELL; returns the
 * count. */
int rocks__cell_seeds(const rocks__params *params, const int cell[3], rocks__colour_fn colour,
                      const void *user, rocks__seed *out);

/* The dual block of voxel V on one axis: its cell and the neighbour on its side of the cell's
 * centre. */
static inline void rocks__dual_axis(int voxel, int m, int *first_cell) {
    int c = rocks__floor_div(voxel, m);
    int s = voxel - c * m;
    *first_cell = (2 * s + 1 < m) ? c - 1 : c;   /* the block is first_cell, first_cell + 1 */
}

/* A region instance (001 §3): its kind, the axis of an edge (along) or a face (normal), and the
 * colours of its feature's lattice points, which lie in {0, 1}³ of the region's frame. */
typedef struct rocks__region {
    int kind, axis;
    uint8_t colour[2][2][2];          /* [z][y][x]; only the feature's points are meaningful */
    bool known[2][2][2];
    int lo[3], hi[3];                 /* its cells, inclusive, in its own frame */
} rocks__region;

void rocks__region_make(const rocks__params *params, int index, rocks__region *out);
/* Instance index of the region that holds `cell` (a frame where `colour` knows the cell's
 * feature's corners), and that region's origin in the frame. -1 when the colours needed are not
 * known. */
int rocks__region_of_cell(const rocks__params *params, const int cell[3],
                          const bool known[2][2][2], const uint8_t colour[2][2][2], int origin[3]);

/* A contact whose other rock is not fixed by this rock's region (the tile around decides it). */
#define ROCKS__OTHER_UNRESOLVED UINT32_MAX

/* One region instance built: its rocks with geometry in the instance's own arrays. */
typedef struct rocks__region_result {
    rocks_rock *rocks;
    int (*rock_cell)[3];              /* seed cell of each rock, in the region's frame */
    int *rock_k;
    uint32_t rock_count;
    rocks_vertex *vertices;
    uint32_t vertex_count;
    uint16_t *indices;
    uint32_t index_count;
    float (*anchors)[3];
    uint32_t anchor_count;
    rocks_contact *contacts;          /* other = the other region's instance until resolved */
    int (*contact_other)[5];          /* other's instance (or -1), cell (3), k */
    uint32_t contact_count;
    /* kept for tests only (rocks__build_options.keep_voxels): each rock's Voronoi voxels before
     * erosion, in the region's voxel frame, and ρ after it */
    int16_t (*voxels)[3];
    float *voxel_rho;
    uint32_t *voxel_first, *voxel_count;
    uint32_t voxel_total;
    /* capacities of the arrays above (core_grow), for freeing */
    size_t rock_cap, vertex_cap, index_cap, anchor_cap, contact_cap, voxel_cap;
} rocks__region_result;

typedef struct rocks__build_options {
    bool keep_voxels;                 /* keep every rock's voxel set (tests) */
    bool keep_empty;                  /* keep rocks that eroded away (tests of ownership) */
} rocks__build_options;

/* Builds one region instance: seeds, ownership, contacts, erosion, meshes (rocks_voronoi.c and
 * rocks_mesh.c). Frees with rocks__region_result_free. */
void rocks__region_build(const rocks__params *params, const rocks__build_options *options, int index,
                         rocks__region_result *out);
void rocks__region_result_free(rocks__region_result *result);

/* Meshes, LODs, anchors and hull of one eroded rock (rocks_mesh.c). `rho` covers the box
 * [box_lo, box_lo + size) in region voxels with a border of ρ = 0 at least one voxel wide.
 * Appends to the result's arrays; false when nothing of the rock is left (no ρ ≥ 0.5). */
bool rocks__rock_mesh(const rocks__params *params, const float *rho, const int box_lo[3],
                      const int size[3], const rocks__seed *seed, rocks__region_result *result,
                      rocks_rock *rock);

/* The full set with the tests' extras. */
typedef struct rocks__set {
    rocks_tileset set;
    rocks__params params;
    /* per rock: its region instance and seed cell/k (region frame); voxels when kept */
    uint16_t *rock_region;
    int16_t (*rock_cell)[3];
    uint8_t *rock_k;
    int16_t (*voxels)[3];
    float *voxel_rho;
    uint32_t *voxel_first, *voxel_count;
    uint32_t voxel_total;
} rocks__set;

rocks_tileset *rocks__tiles_create(const rocks_tileset_desc *desc, const rocks__build_options *options);

/* The cache (rocks_cache.c). Read: true when `path` holds exactly this set's parameters and is
 * whole; otherwise false with *why set ("missing", "old version", …) and nothing kept. */
/* The caches' files (rocks_cache.c). The whole of `path` read into *data (free it with
 * core_free(*data, *size ? *size : 1)); false with *why "missing", "unreadable" or "too large". */
bool rocks__file_load(const char *path, unsigned char **data, size_t *size, const char **why);
/* data[0, size) written to a unique temporary beside `path` (its folder made if missing), then
 * renamed over it: a reader never sees half a file. False with a message naming `what`. */
bool rocks__file_store(const char *path, const void *data, size_t size, const char *what);
bool rocks__cache_read(const char *path, const rocks__params *params, rocks__set *out, const char **why);
bool rocks__cache_write(const char *path, const rocks__set *set);
/* The reader's checks on a file's bytes in memory (the tests cut and damage them). */
bool rocks__cache_parse(const unsigned char *data, size_t size, const rocks__params *params, rocks__set *out,
                        const char **why);
/* Bytes of the arrays, as set->bytes counts them. */
size_t rocks__set_bytes(const rocks_tileset *set);
void rocks__set_free_arrays(rocks__set *set);

/* ---- the block tiles' cache (rocks_blocks_cache.c; paper 003 cliff blocks) ------------------ */

/* Bump it with ANY change to what a block tile's build makes (points, discs, clusters, planes,
 * bounds, the lookup grid) or to the file's layout: a cache holds a build's output under its
 * desc, so an old one would read as valid. */
#define ROCKS__BLOCK_CACHE_VERSION 2u   /* 2: block types numbered from 1 (ROCKS_BLOCK_DEFAULT = 0) */
#define ROCKS__BLOCK_CACHE_CHECKSUM_SEED 0x726f636b626c6b73ull   /* core_hash_bytes' seed */

/* Writes `tile` (one without custom blocks) to `path`: a temporary beside it, renamed over it,
 * the folder made if missing. False with a message when it cannot. */
bool rocks__block_cache_write(const char *path, const rocks_block_tile *tile);
/* Reads `path` into `tile` (a zeroed struct: the reader sets its desc, arrays, counts and
 * grid): true when the file holds exactly the tile of `desc` (defaults filled,
 * no custom blocks) and is whole; otherwise false with *why ("missing", "cut short", …) and
 * nothing kept (the tile's arrays NULL, its counts 0). */
bool rocks__block_cache_read(const char *path, const rocks_block_tile_desc *desc, rocks_block_tile *tile,
                             const char **why);
/* The reader's checks on a file's bytes in memory (the tests and the fuzz target cut and damage
 * them); as rocks__block_cache_read. On success the tile's arrays are the caller's: free them
 * with rocks__block_tile_free_arrays (or rocks_block_tile_destroy for a core_alloc'd tile). */
bool rocks__block_cache_parse(const unsigned char *data, size_t size, const rocks_block_tile_desc *desc,
                              rocks_block_tile *tile, const char **why);
/* The lookup grid's cells a side for a tile of side `size` (rocks_blocks.c's build_grid). */
int rocks__block_grid_cells(float size);
/* Frees a tile's arrays (each allocated with one item more than its count; grid_first with
 * grid³ + 1) and sets them NULL; the struct itself stays. */
void rocks__block_tile_free_arrays(rocks_block_tile *tile);

/* ---- the cliffs' presence, read by the tests (rocks_cliffs.c) ------------------------------ */

/* The cliffs' tile of `type`; NULL when neither their strata nor their materials use it. */
const rocks_block_tile *rocks__cliffs_tile(const rocks_cliffs *cliffs, rocks_block_type type);
/* Which blocks of `type`'s tile copy at tile coordinate `cell` are present in `world`, a bit each
 * into bits ((block_count + 63) / 64 words), as rocks_cliffs_amplify finds them: its test of
 * which cells to ask, its shortcuts and its cache included (so the world must be the one the
 * cliffs serve). False, and no bit set, when the hook would not ask the cell. */
bool rocks__cliffs_present(rocks_cliffs *cliffs, terrain_world *world, rocks_block_type type, const int64_t cell[3],
                           uint64_t *bits);
/* The same worked out anchor by anchor, with none of the shortcuts that pass over anchors far
 * from any surface or from rock of the type, and nothing cached: what they must not change. */
bool rocks__cliffs_present_unfiltered(rocks_cliffs *cliffs, terrain_world *world, rocks_block_type type,
                                      const int64_t cell[3], uint64_t *bits);

/* A closed surface for a rock's levels of detail (rocks_surface.c, rocks_mesh.c): positions in
 * voxels, sample (x, y, z) of ρ's box at (x, y, z); unit normals out of the rock; triangles
 * counter-clockwise seen from outside. */
typedef struct rocks__surface {
    float *positions, *normals;       /* 3 a vertex (room for vertex_count + 1) */
    uint32_t *indices;
    uint32_t vertex_count, index_count;
    size_t index_cap;
} rocks__surface;

/* Dual contouring of r = 2ρ − 1 at two voxels (ρ over a box of `size` whose border voxels are
 * empty), with a vertex per surface piece of a coarse cell fitted to the voxel grid's crossings.
 * False, with *out empty, where the coarse grid misses detail the voxels have (a thin slab, a
 * fin): the caller then meshes the voxels themselves. */
bool rocks__dual_surface(const float *rho, const int size[3], rocks__surface *out);
void rocks__surface_free(rocks__surface *surface);

/* Levels of detail of a closed mesh by quadric edge collapse onto existing vertices
 * (rocks_simplify.c): begin with the mesh (positions in voxels), then run once a level, finest
 * first: each run collapses on until the next collapse would stray more than `error` voxels
 * (root mean square over the planes it merged) or the mesh has at most target_index_count
 * indices (0: no target), and writes the mesh so far to `out` (room for index_count). A closed
 * mesh stays closed. end frees. */
typedef struct rocks__simplifier rocks__simplifier;
rocks__simplifier *rocks__simplify_begin(const uint32_t *indices, size_t index_count, const float *positions,
                                         size_t vertex_count);
size_t rocks__simplify_run(rocks__simplifier *s, float error, size_t target_index_count, uint32_t *out);
void rocks__simplify_end(rocks__simplifier *s);

/* Each edge of triangles[0, index_count) in exactly two triangles (once in each direction). */
bool rocks__watertight(const uint32_t *indices, uint32_t index_count, uint32_t vertex_count);

#endif
