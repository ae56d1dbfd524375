/* rocks.h — piles of rocks from aperiodic corner-cube tiles (paper 001), placed in the terrain's
 * rock layers (000 §5).
 *
 * Two parts. The tile set is built once (or read from its cache file): 256 corner cubes, each
 * with the rocks whose seed point lies in it, every rock a closed mesh with levels of detail.
 *
 *     rocks_tileset *set = rocks_tileset_create(&(rocks_tileset_desc){ .shape = ROCKS_SHAPE_MIXED,
 *                                                                  .cache_path = "out/rocks.bin" });
 *     for (uint32_t e = set->tiles[t].first; e < set->tiles[t].first + set->tiles[t].count; e++)
 *         ... set->entries[e].rock, set->entries[e].offset ...
 *     rocks_tileset_destroy(set);
 *
 * Rocks in the world (the second part, below) tile space with those cubes, colouring the
 * integer lattice by a hash, and keep the rocks whose anchor points fall in a support: the rock
 * layers of the terrain's stacks, or any point-membership function.
 *
 * ---- tile space (001 §2–§3) ----
 * A tile is the unit cube [0, 1)³ with corners on the integer lattice. Each lattice point has one
 * of 2 colours; tile t (0 … 255) is the cube whose corner (x, y, z) ∈ {0, 1}³ has colour
 * (t >> (x + 2y + 4z)) & 1. A tile is cut into n³ cells (n = desc.cells). Cells are sorted into
 * regions, shared between the tiles that meet there:
 *   vertex  the 2×2×2 cells around a lattice point (one cell in each of the 8 tiles around it)
 *   edge    the 2×2×(n−2) cells along a lattice edge (4 tiles), less the vertex cells
 *   face    the 2×(n−2)² cells across a face (2 tiles), less the edge and vertex cells
 *   centre  the (n−2)³ cells inside a tile.
 * A region's seed points depend only on the colours of its lattice feature's corners (1 vertex,
 * 2 for an edge, 4 for a face, 8 for the centre), and so do the seeds of its neighbouring cells,
 * which the lower-dimensional regions fix first and the others copy (001 §3). So there are
 * 2 vertex, 12 edge, 48 face and 256 centre regions, and a rock (the Voronoi cell of one seed,
 * eroded) has one shape whatever tiles are placed around its own: tiles placed by matching
 * corner colours join without seams, gaps or doubled rocks.
 *
 * A rock's geometry is stored once, in tile units relative to its region's origin (the lattice
 * point of a vertex region, the first end of an edge, the lowest corner of a face, the tile's
 * origin for a centre); a tile lists each of its rocks with the integer offset from the tile's
 * origin to that region origin. Rock r of entry e of tile t at lattice point L is at
 *     L + entries[e].offset + (rock-local coordinates)        (tile units)
 * Every rock is listed by exactly one tile of any tiling: the tile holding the cell of its seed.
 *
 * Threads: building uses the job system given (or runs on the calling thread); a built set is
 * read-only and may be read from any thread.
 */
#ifndef ROCKS_H
#define ROCKS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "terrain/terrain.h"

typedef struct job_system job_system;

/* ---- the tile set (001 §2–§5) -------------------------------------------------------------- */

typedef enum rocks_shape {
    ROCKS_SHAPE_DEFAULT = 0,          /* mixed */
    ROCKS_SHAPE_ROUND,                /* pebbles: α = β = γ = 1, g ∈ [1, 2], one seed a cell (Fig. 11) */
    ROCKS_SHAPE_SLAB,                 /* flat slabs: α, β ∈ [4, 5], γ = 1, g ∈ [1, 3] (Fig. 13) */
    ROCKS_SHAPE_MIXED,                /* rocks and gravel: α, β, γ ∈ [1, 2], g ∈ [1, 4],
                                         1 … 3 seeds a cell (Fig. 12) */
} rocks_shape;

#define ROCKS_LODS 3                  /* levels of detail per rock mesh: full, ~1/4, ~1/12 */
#define ROCKS_HULL_AXES 13            /* a rock's collision hull: a 26-DOP (below) */

/* Zero means the default (the shape preset's) for every field. */
typedef struct rocks_tileset_desc {
    uint64_t seed;                    /* 0 = 1 */
    int cells;                        /* n, cells along a tile's side; 0 = 5; 4 … 8 */
    int voxels_per_cell;              /* n_G / n (001 §7: 10); 0 = 10; 4 … 16 */
    rocks_shape shape;
    int max_seeds_per_cell;           /* s: each cell gets n_k ∈ [1, s] seeds; 0 = the preset's */
    float scale_min[3], scale_max[3]; /* α, β, γ ranges (001 §4); 0 = the preset's */
    float g_max;                      /* g_k ∈ [1, g_max]; 0 = the preset's (4 at most) */
    float contact_radius;             /* a (001 §5), in cells; 0 = 0.12 */
    float blend_radius;               /* b, in cells; 0 = 0.35 */
    int erosion_steps;                /* spheroidal erosion iterations; 0 = 6 */
    float erosion_rate;               /* ε a step at a fully exposed voxel; 0 = 0.25 */
    job_system *jobs;                 /* build on these workers; NULL = the calling thread */
    const char *cache_path;           /* read from / written to this file; NULL = no cache */
} rocks_tileset_desc;

/* A rock's vertex: position in tile units relative to its region origin, unit normal. */
typedef struct rocks_vertex {
    float position[3];
    int8_t normal[3];                 /* ×127, pointing out of the rock */
    int8_t reserved;                  /* 0 */
} rocks_vertex;

/* One rock, all in tile units relative to its region origin. */
typedef struct rocks_rock {
    float seed[3];                    /* p_k */
    float bounds_min[3], bounds_max[3];   /* of its full-detail mesh */
    float radius;                     /* of its embedding sphere: farthest mesh point from seed */
    uint32_t vertex_first, vertex_count;  /* in rocks_tileset.vertices */
    uint32_t index_first[ROCKS_LODS], index_count[ROCKS_LODS];
                                      /* triangles in rocks_tileset.indices, local to the rock's
                                         vertices (add vertex_first; 16 bits: a rock has fewer
                                         than 65 536 vertices); LOD 0 is the full mesh,
                                         simplified (≤ 0.5 voxel from its dual surface at two
                                         voxels, or 0.6 from marching cubes), LOD 1 and 2 about
                                         1/4 and 1/12 of its triangles; every level closed */
    uint32_t anchor_first, anchor_count;  /* in rocks_tileset.anchors: the seed first, then
                                         voxel centres spread over the rock (001 §6) */
    uint32_t contact_first, contact_count;  /* in rocks_tileset.contacts */
    float hull[2 * ROCKS_HULL_AXES];  /* collision hull: hull[2a] = min and hull[2a+1] = max of
                                         dot(v, rocks_hull_axes[a]) over its vertices */
    uint8_t region;                   /* 0 vertex, 1 edge, 2 face, 3 centre */
    uint8_t reserved[3];              /* 0 (no padding: the cache file is the struct's bytes) */
} rocks_rock;

/* A contact point c_ij kept by erosion (001 §5), relative to the rock's region origin. */
#define ROCKS_CONTACT_VARIES UINT32_MAX
typedef struct rocks_contact {
    float point[3];
    uint32_t other;                   /* the rock on the other side, in the same region-origin
                                         frame shifted by other_offset, when this rock's region
                                         fixes it (the same region or a vertex, edge or face of
                                         it); ROCKS_CONTACT_VARIES when it lies in a region of
                                         higher dimension, which the tiles around decide */
    int8_t other_offset[3];           /* the other rock's region origin minus this one's, in
                                         tiles (when other is a rock) */
    int8_t reserved;
} rocks_contact;

typedef struct rocks_tile_entry {
    uint32_t rock;
    int8_t offset[3];                 /* tile origin → the rock's region origin (−1 … 1 each) */
    int8_t reserved;
} rocks_tile_entry;

typedef struct rocks_tile {
    uint32_t first, count;            /* in rocks_tileset.entries */
} rocks_tile;

/* Read-only once built. */
typedef struct rocks_tileset {
    rocks_tileset_desc desc;            /* with the defaults filled in (jobs and cache_path NULL) */
    rocks_tile tiles[256];
    rocks_tile_entry *entries;
    rocks_rock *rocks;
    rocks_vertex *vertices;
    uint16_t *indices;                /* rock-local (see rocks_rock.index_first) */
    float (*anchors)[3];
    rocks_contact *contacts;
    uint32_t entry_count, rock_count, vertex_count, index_count, anchor_count, contact_count;
    float max_radius;                 /* largest rock radius (tile units) */
    double build_seconds;             /* 0 when read from the cache */
    bool from_cache;
    size_t bytes;                     /* memory held */
} rocks_tileset;

/* The 13 directions of the collision hulls: the 3 axes, 6 face diagonals, 4 body diagonals
 * (unnormalised: (1,0,0), (1,1,0), (1,1,1), …). */
extern const float rocks_hull_axes[ROCKS_HULL_AXES][3];

/* Builds the set, or reads it from desc->cache_path when that file holds the same parameters.
 * A missing, old or damaged cache is rebuilt and rewritten, with a one-line notice; never fatal.
 * NULL (message logged) for parameters out of range. */
rocks_tileset *rocks_tileset_create(const rocks_tileset_desc *desc);
void rocks_tileset_destroy(rocks_tileset *set);
/* Frees the CPU copies of the meshes (vertices and indices: about 80 % of the set) once something
 * else holds them — the renderer uploads them in rocks_system_create — and sets those pointers to NULL
 * (the counts and each rock's ranges stay: they describe the GPU copy). Placement and collision
 * read anchors and hulls only; rocks_tile_write_ply fails after it, and a later rocks_system_create on
 * the set would have nothing to upload. */
void rocks_tiles_release_meshes(rocks_tileset *set);

/* Tile index for corner colours: bit (x + 2y + 4z) is corner (x, y, z)'s colour. */
static inline int rocks_tile_index(const uint8_t colour[8]) {
    int t = 0;
    for (int i = 0; i < 8; i++) t |= (colour[i] & 1) << i;
    return t;
}

/* Signed distance estimate from a point (rock-local tile units) to a rock's hull: the largest
 * of the 26 plane distances; < 0 inside. Exact inside, never more than the true distance
 * outside. */
float rocks_hull_distance(const rocks_rock *rock, const float p[3], float normal[3]);

/* Writes tile t's rocks as one binary PLY (tile units, tile origin at 0). False with `error`
 * set: CORE_ERROR_IO when the file cannot be written, CORE_ERROR_RANGE for a tile outside
 * 0 … 255, CORE_ERROR_ARGUMENT for a set whose meshes were released or a path over 4 KiB. */
bool rocks_tile_write_ply(const rocks_tileset *set, int t, const char *path, core_error *error);

/* ---- placing rocks (001 §6, 000 §5) --------------------------------------------------------- */
/*
 * Space is tiled with tiles of tile_size metres, the corner at lattice point L = (i, j, k) at
 * world (i, j, k)·tile_size. The lattice is coloured by a hash of (seed, i, j, k): deterministic,
 * and aperiodic in practice (a stochastic tiling, 001 §6). A rock is instanced when at least
 * `threshold` of its anchor points (its seed point and voxel centres spread over it) lie in the
 * support, and skipped when its seed lies deeper than twice the set's largest rock radius under
 * the top of its column (buried: nobody sees it). The support is the rock layers of the world's
 * stacks (material TERRAIN_ROCKS), or a developer's point-membership function.
 *
 *     rocks_place_index *index = rocks_place_index_create(set);   // once per tile set
 *     rocks_placement p = { 0 };
 *     rocks_place_box(&(rocks_place_desc){ .tiles = set, .index = index, .world = world }, min, max, &p);
 *     ... p.instances[i].position (relative to p.origin), p.instances[i].rock ...
 *     rocks_placement_free(&p);
 *     rocks_place_index_destroy(index);                          // before rocks_tileset_destroy
 */
typedef bool (*rocks_support_fn)(void *user, const double point[3]);

/* The tile set laid out for placement: each rock's anchor box and sorted anchor heights, each
 * tile's rocks by the height of their lowest anchor (5.3 MB for the default set, about 10 ms to
 * make). Read-only once made: any number of threads may place with one index. Made from the
 * set's rocks and anchors (not its meshes), so it may be made after rocks_tiles_release_meshes;
 * destroy it before the set. */
typedef struct rocks_place_index rocks_place_index;
rocks_place_index *rocks_place_index_create(const rocks_tileset *set);   /* NULL for a NULL set */
void rocks_place_index_destroy(rocks_place_index *index);

typedef struct rocks_place_desc {
    const rocks_tileset *tiles;       /* required */
    const rocks_place_index *index;   /* made from `tiles`; NULL = one is made for the call (about
                                         10 ms: pass one to place more than once) */
    terrain_world *world;             /* the support's stacks (when support is NULL) */
    rocks_support_fn support;         /* NULL = rock layers of `world` */
    void *support_user;
    float tile_size;                  /* metres a tile; 0 = 3 */
    uint64_t seed;                    /* of the colouring; 0 = the world's generation seed, or 1 */
    float threshold;                  /* share of anchors in the support; 0 = 0.6 */
} rocks_place_desc;

typedef struct rocks_instance {
    float position[3];                /* metres: the rock's region origin, relative to the
                                         placement's origin (the rock's vertices scale by
                                         tile_size from there) */
    uint32_t rock;                    /* in tiles->rocks */
    uint32_t key;                     /* a hash of (lattice point, entry): per-rock variation */
} rocks_instance;

typedef struct rocks_placement {
    double origin[3];                 /* world metres */
    rocks_instance *instances;        /* in lattice order (a pure function of the box), owned */
    uint32_t count, capacity;
    float bounds_min[3], bounds_max[3];   /* relative to origin: a box round the instances' rocks
                                             for culling (per tile and offset, the bounds of every
                                             rock the tile lists there that it keeps any of) */
} rocks_placement;

/* Places the rocks whose seed point lies in the world box [min, max) (x, y, z metres), reusing
 * `out`'s memory; origin = min. The result is a pure function of (desc, box, support): each
 * rock belongs to exactly one box of any partition of space, so boxes can be placed
 * independently (per chunk, per thread). False (message logged) for a bad desc. */
bool rocks_place_box(const rocks_place_desc *desc, const double min[3], const double max[3],
                     rocks_placement *out);
void rocks_placement_free(rocks_placement *placement);
/* The colour (0 or 1) of lattice point (i, j, k) under a desc's seed. */
int rocks_lattice_colour(uint64_t seed, int64_t i, int64_t j, int64_t k);

/* ---- rocks in the running world: the RockTiles component, drawing, collision ---------------- */
/*
 *     rocks_system *rocks = rocks_system_create(&(rocks_system_desc){ .gfx = gfx, .ecs = ecs, .world = world,
 *                                                        .tiles = set });
 *     each frame:
 *         rocks_set_view(rocks, &view);                 // before ecs_progress
 *         ecs_progress(ecs, dt);                        // "rocks_place" runs in the draw phase
 *         terrain_ecs_draw(terrain, renderer, &view);   // the ground first
 *         rocks_draw(rocks, &view);
 *     rocks_system_destroy(rocks);                             // before ecs_world_destroy and gfx_context_destroy
 *
 * Every level-0 TerrainMeshChunk within range of the view gets a RockTiles component: the rocks
 * whose seeds lie in its 32 m box (rocks_place_box over the world's rock layers), placed by jobs
 * on the ECS world's job system. A chunk is placed again in the frame any of the column chunks
 * its rocks can reach changes (an edit: digging removes exactly the rocks whose anchors left the
 * support; a rock dropped with the sand tool shows in the frame it lands).
 *
 * Drawing: one multi-draw-indirect, one command per rock mesh and level of detail in view, its
 * instances from one buffer. Each rock's switch distances are spread by its key, so no ring of
 * popping moves with the player; past range the rocks shrink into the ground.
 *
 * Collision: rocks_distance and rocks_raycast answer against each rock's hull (a 26-DOP of its
 * vertices), for the player's capsule and the tools' aim.
 *
 * Threads: main thread (OpenGL). The GPU pass is "rocks".
 */

typedef enum rocks_quality {
    ROCKS_DEFAULT = 0,                /* on */
    ROCKS_OFF,                        /* nothing placed, drawn or collided with */
    ROCKS_ON,
} rocks_quality;

/* Parses "off" or "on" (--rocks); false for anything else. */
bool rocks_parse_quality(const char *text, rocks_quality *out);

/* Zero means the default for every field. */
typedef struct rocks_system_desc {
    gfx_context *gfx;                 /* required */
    ecs_world *ecs;                   /* required: the world terrain_ecs_create registered on */
    terrain_world *world;             /* required */
    const rocks_tileset *tiles;       /* required; not owned, outlives the system */
    rocks_quality quality;
    float tile_size;                  /* as rocks_place_desc's; 0 = 3 m */
    float range;                      /* metres to the last rock drawn; 0 = 70 */
    float lod_distance[ROCKS_LODS - 1];   /* metres where LOD 1 and 2 start; 0 = 10, 25 */
    float fog_density;                /* as terrain_renderer_desc's; 0 = 0.0025 */
} rocks_system_desc;

typedef struct rocks_system rocks_system;
/* NULL (the reason logged) when a required field is missing or the shaders do not build. */
rocks_system *rocks_system_create(const rocks_system_desc *desc);
/* Removes every RockTiles component, disables the systems, frees the GPU data. */
void rocks_system_destroy(rocks_system *rocks);
void rocks_set_view(rocks_system *rocks, const terrain_view *view);
/* Draws the rocks of the chunks in view, in one pass named "rocks" (after the terrain). */
void rocks_draw(rocks_system *rocks, const terrain_view *view);

/* The RockTiles component of a level-0 mesh chunk entity. */
typedef struct RockTiles {
    rocks_placement placement;        /* owned; freed when the component leaves the entity */
    uint64_t source;                  /* what it was placed from (the chunk versions it reads) */
} RockTiles;

/* Gathers the placed rocks that reach into [min, max] (world metres), so that the queries below
 * inside that box read a short list instead of every chunk's rocks: call it once before many
 * queries in one place (the player's update). A placement made since drops the gathering. */
void rocks_focus(rocks_system *rocks, const double min[3], const double max[3]);
/* Signed distance from a world point to the nearest rock (its hull), looking no further than
 * max_distance (returns max_distance when none is nearer); the unit normal out of that rock in
 * `normal` (may be NULL). */
float rocks_distance(rocks_system *rocks, const double point[3], float max_distance, float normal[3]);

typedef struct rocks_ray_hit {
    double position[3];
    float normal[3];
    float distance;
    uint32_t rock;                    /* in the tile set */
} rocks_ray_hit;
/* The first rock hull along the ray within max_distance; false for a miss. */
bool rocks_raycast(rocks_system *rocks, const double origin[3], const float direction[3], float max_distance,
                   rocks_ray_hit *hit);

typedef struct rocks_system_stats_info {
    int chunks;                       /* RockTiles components now */
    uint64_t instances;               /* rocks placed over them */
    uint64_t instances_drawn;         /* by the last rocks_draw */
    uint64_t triangles_drawn;         /* their triangles (all in one draw call) */
    uint64_t placements;              /* chunks placed since creation */
    double place_ms;                  /* CPU ms placing, last frame */
    double draw_ms;                   /* CPU ms of the last rocks_draw */
    size_t tiles_bytes;               /* the tile set (rocks_tileset.bytes; shared, not owned) */
    size_t placed_bytes;              /* the placed rocks' instances, CPU side */
    size_t draw_bytes;                /* the renderer's CPU side: every rock level's vertices and
                                         indices, kept compact, and the frame's staging */
    size_t gpu_bytes;                 /* the renderer's buffers: the frame's batch of vertices
                                         and indices */
} rocks_system_stats_info;
rocks_system_stats_info rocks_system_stats(const rocks_system *rocks);
/* A hash of every placed rock (chunk coordinates, rock, key, position): tests and tools. */
uint64_t rocks_digest(rocks_system *rocks);

/* ---- cliff blocks (003 §3–§5): rocks_blocks.h ------------------------------------------- */
#include "rocks/rocks_blocks.h"

#endif
