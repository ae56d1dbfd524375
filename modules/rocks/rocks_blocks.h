/* rocks_blocks.h — fractured rock blocks for cliffs (paper 003 §3–§4). Part of the rocks module:
 * include "rocks/rocks.h", which includes this.
 *
 * A block tile is a cube of side s that repeats over all of space. Sample points fill it (a
 * periodic Poisson-disc set); fracture discs, laid out by the block type, cut the edges of the
 * points' neighbour graph; the clusters of points that still see each other become blocks. Each
 * block is the convex hull of its cluster, as the smooth intersection of the hull's planes
 * (R = 25 cm, 003 §4.2), warped by a relief along its gradient so its faces are not flat.
 *
 *     rocks_block_tile *tile = rocks_block_tile_create(&(rocks_block_tile_desc){
 *         .type = ROCKS_BLOCK_TABULAR, .seed = 7 });
 *     double p[3] = { 12.5, -3.0, 40.25 };                  // metres, anywhere: the tile repeats
 *     uint32_t block;
 *     float t = rocks_block_tile_field(tile, p, NULL, NULL, &block);   // > 0 inside a block
 *     rocks_block_tile_destroy(tile);
 *
 * Fields follow the terrain's sign: positive inside, negative outside, about a signed distance
 * in metres near the surface (planes are exact distances; the smooth intersection and the
 * warping bend that by at most R/6 and the relief's amplitude).
 *
 * Frames. A block's planes are in tile metres, with its anchor (its points' centroid) inside
 * [0, s)³; a block that straddles the tile's border reaches past it, and the tile field evaluates
 * the blocks of the neighbouring tiles' copies as well (003 §5), so a field is continuous across
 * tile borders and no block is cut there. The fracture discs and the neighbour graph are periodic
 * too, so blocks meet across the border as they do inside.
 *
 * Sign note. 003 §4.2 writes the smooth intersection as max(f_A, f_B) − R·k³/6 for half-spaces
 * positive outside. Read with that sign the term adds material at a convex edge; it rounds the
 * edge off (Fig. 8) only when the field is positive inside, where the intersection is the min.
 * So here: f_A∩̃B = min(f_A, f_B) − R·k(f_A, f_B)³/6, k = max(1 − |f_A − f_B|/R, 0), the paper's
 * k and term in the terrain's sign. rocks_smooth_intersection is that formula.
 *
 * Cache: with desc.cache_path a tile is read from that file when it holds this desc's tile
 * (under a millisecond for a 16 m tile, against a few tenths of a second of building), else
 * built and written there with a one-line notice; tiles with custom blocks are always built.
 *
 * Threads: creation runs on the calling thread (tiles are independent: build several at once on
 * jobs, as rocks_cliffs_desc.jobs does); a built tile is read-only and may be evaluated from any
 * thread.
 */
#ifndef ROCKS_BLOCKS_H
#define ROCKS_BLOCKS_H

#include <stdbool.h>
#include <stdint.h>

#include "terrain/terrain.h"

/* 003 §4.1, Fig. 2 and Fig. 5: how the fracture discs are laid out. */
typedef enum rocks_block_type {
    ROCKS_BLOCK_DEFAULT = 0,          /* = ROCKS_BLOCK_EQUIDIMENSIONAL */
    ROCKS_BLOCK_EQUIDIMENSIONAL,      /* three orthogonal sets (axis-aligned normals): near-cubes */
    ROCKS_BLOCK_RHOMBOHEDRAL,         /* three oblique sets (a sheared frame): rhombic blocks */
    ROCKS_BLOCK_POLYHEDRAL,           /* random normals, denser discs: irregular smaller blocks */
    ROCKS_BLOCK_TABULAR,              /* bedding planes across the tile, short cross joints: slabs */
    ROCKS_BLOCK_COLUMNAR,             /* continuous vertical sets, rare cross joints: tall prisms */
    ROCKS_BLOCK_TYPE_END              /* one past the last: an array indexed by type is this long */
} rocks_block_type;
/* How many real types there are: they are ROCKS_BLOCK_EQUIDIMENSIONAL + i for i < this. */
#define ROCKS_BLOCK_TYPE_COUNT (ROCKS_BLOCK_TYPE_END - ROCKS_BLOCK_EQUIDIMENSIONAL)

/* "equidimensional", …; NULL for DEFAULT (not a type of its own) and values out of range. */
const char *rocks_block_type_name(rocks_block_type type);
bool rocks_parse_block_type(const char *text, rocks_block_type *out);

/* A block given by the developer (003 §4, user control: "directly placing several authored
 * blocks in the tile, and the system will adapt"): any implicit primitive or construction tree,
 * as a field in tile metres, > 0 inside, about a signed distance near its surface. The sample
 * points it holds (or comes within a joint of) are kept out of the generated clusters, so the
 * fractured blocks form around it. It may reach past the tile's border: it repeats with the tile. */
typedef struct rocks_block_custom {
    float (*field)(void *user, const float p[3]);   /* pure, safe from any thread */
    void *user;
    float bounds_min[3], bounds_max[3];   /* a box holding every point where field > 0 */
} rocks_block_custom;

#define ROCKS_BLOCK_MAX_CUSTOM 64

/* Zero means the default for every field. */
typedef struct rocks_block_tile_desc {
    rocks_block_type type;            /* DEFAULT = equidimensional */
    uint64_t seed;                    /* 0 = 1 */
    float size;                       /* s, the tile's side in metres; 0 = 16; 4 … 64 */
    float point_spacing;              /* Poisson radius of the sample points; 0 = s / 24 */
    float fracture_spacing;           /* Poisson radius of the disc centres; 0 = the type's */
    float fracture_radius;            /* radius of the type's main discs; 0 = the type's */
    float rounding;                   /* R (003 §4.2), metres; 0 = 0.25 */
    float joint;                      /* open gap between neighbouring blocks, metres; 0 = 0.15 */
    float relief;                     /* warping amplitude (003 §4.2), metres; 0 = 0.08; < 0 = none */
    float relief_scale;               /* the relief's wavelength, metres; 0 = 0.8 */
    const rocks_block_custom *custom; /* blocks placed by hand (copied); up to ROCKS_BLOCK_MAX_CUSTOM */
    int custom_count;
    /* Read from / written to this file; NULL = no cache. Ignored for a tile with custom blocks
     * (custom_count > 0): their fields are function pointers, which no file can hold, so such a
     * tile is always built. The file holds the desc's fields above (defaults filled) and the
     * build's arrays; one for other parameters, of another format version, cut short or damaged
     * is rebuilt and rewritten with one notice (a missing one too), never an error. */
    const char *cache_path;
} rocks_block_tile_desc;

typedef struct rocks_block {
    uint32_t plane_first, plane_count;   /* in tile->planes: (n, d), inside where d − n·p > 0 */
    uint32_t point_first, point_count;   /* its cluster, in tile->points (unwrapped: contiguous) */
    uint32_t custom;                  /* a block placed by hand: 1 + its index in desc.custom; 0 = generated */
    float anchor[3];                  /* centroid of its points, in [0, s)³: presence is asked here */
    float bounds_min[3], bounds_max[3];  /* where the field can be > −1 m (tile metres) */
} rocks_block;

typedef struct rocks_block_disc {
    float centre[3], normal[3], radius;
} rocks_block_disc;

typedef struct rocks_block_tile {
    rocks_block_tile_desc desc;       /* with the defaults filled in (cache_path NULL) */
    rocks_block *blocks;
    uint32_t block_count;
    float (*planes)[4];               /* n.x, n.y, n.z, d */
    uint32_t plane_count;
    float (*points)[3];               /* every block's cluster points, block by block */
    uint32_t point_count;             /* points in blocks (clusters too small for a hull are dropped) */
    uint32_t sample_count;            /* sample points made (003 Table 1's #P) */
    rocks_block_disc *discs;          /* the fractures (#D), centres in [0, s)³ */
    uint32_t disc_count;
    double build_seconds;             /* 0 when read from the cache (as rocks_tileset) */
    bool from_cache;                  /* read from desc.cache_path, not built */
    /* internal: the lookup grid of blocks (and their images) per cell of the tile */
    int grid;
    uint32_t *grid_first;             /* grid³ + 1 */
    uint32_t *grid_entries;           /* block << 5 | image (0 … 26: offset ∈ {−1, 0, 1}³) */
    uint32_t grid_entry_count;
    float reach_min[3], reach_max[3]; /* the union of the blocks' bounds with the tile's origin */
    float *widths;                    /* per block: its smallest width (metres), which decides
                                         whether a coarse field shows it (rocks_block_tile_amplify) */
} rocks_block_tile;

/* NULL with a message naming the field for a bad desc. With desc->cache_path (and no custom
 * blocks) the tile is read from that file when it holds this desc's tile, else built and the
 * file rewritten (a temporary beside it, renamed; its folder made if missing) with one notice
 * saying why: a tile read back is the built one, array for array. */
rocks_block_tile *rocks_block_tile_create(const rocks_block_tile_desc *desc);
void rocks_block_tile_destroy(rocks_block_tile *tile);

/* f_A ∩̃ f_B (above; 003 §4.2), R > 0. */
float rocks_smooth_intersection(float a, float b, float rounding);

/* Block `block` at p in its own tile metres (unbounded: no repetition), with the warping; the
 * gradient too when `gradient` is not NULL (of the unwarped base, normalised). A custom block is
 * its own field, unwarped (its gradient by central differences). */
float rocks_block_field(const rocks_block_tile *tile, uint32_t block, const float p[3], float gradient[3]);

/* Presence of a block copy (003 §5's e_i): `anchor` is the copy's anchor in world metres. */
typedef bool (*rocks_block_presence_fn)(void *user, uint32_t block, const double anchor[3]);

/* The replication t(p) = max_i b_i(p mod s)·e_i(a_i + s⌊p/s⌋) of 003 §5 at world point p
 * (metres), over the copies of the blocks around p (this tile's and its neighbours') that
 * `present` accepts (NULL = all). −INFINITY where no accepted block comes within a metre.
 * `block_out` (may be NULL) gets the block that gave the value, or UINT32_MAX. */
float rocks_block_tile_field(const rocks_block_tile *tile, const double p[3], rocks_block_presence_fn present,
                             void *user, uint32_t *block_out);

/* ---- blocks in a terrain field (003 §5) --------------------------------------------------- */

/* Raises a terrain field's samples to the tile's replication: f̃ = max(f, t) with t clamped to
 * [−1, 1] as the terrain's field is. Each block copy that reaches the field's box is asked for
 * presence once, then evaluated at the samples inside its bounds. Meant for a world's amplify
 * hook (terrain_world_desc.amplify): see tools/examples/rocks/rocks_blocks.c.
 *
 * Coarse fields (a level of detail: field->spacing = h > 1 m) get the blocks filtered to what
 * their grid can hold. The terrain's own f is its stacks under a box kernel of ±σ, σ = 1 m,
 * sampled every metre at level 0 (000 §3.3): the kernel spans two samples. Held to that ratio
 * at spacing h, a kernel of ±h turns a slab of thickness w into one of 2(w − h) when h < w < 2h
 * (its zero set is where more than half the kernel is solid), keeps it as it is when w ≥ 2h and
 * erases it when w ≤ h. Without the filter a block under 2h aliases: at 2 m a 1.5 m tabular slab
 * or a 2 m column is met by one row of samples or by none, and the mesh shows notches and
 * shards that move with the grid's phase. So a block of smallest width w (widths above: the
 * least extent along its planes' normals) is lowered by e = h − w/2 when w < 2h (0 above),
 * which thins it to 2(w − h), and is left out when w ≤ 1.5 h: what the filter would leave of it
 * is under h, which rows of samples would meet or miss by turns (bumps that move with the grid),
 * and leaving it out spares its presence. Its other sides go in by e too (they are at least w
 * long: a simplification of the separable kernel). Per block, not per sample: the
 * result is still a function of the position and the presence alone (the amplify hook's
 * contract), and every field at one spacing is treated alike, so chunks and their seams agree.
 * Fields at 1 m (level 0, collision, picking) see every block as it is. */
void rocks_block_tile_amplify(const rocks_block_tile *tile, terrain_field *field, rocks_block_presence_fn present,
                              void *user);

/* 003 §5's presence on steep walls: a copy is kept where the world's own field (before any
 * amplification: terrain_field_base_at) at its anchor lies in [depth_min, depth_max] (near the
 * surface; f ≈ signed distance in metres there) and its gradient is steep, |∇f·ŷ| < steepness. */
typedef struct rocks_wall_presence {
    terrain_world *world;
    float steepness;                  /* ε; 0 = 0.5 (walls steeper than 60°) */
    float depth_min, depth_max;       /* both 0 = [−0.6, 0.9] */
} rocks_wall_presence;
bool rocks_block_on_walls(void *wall_presence, uint32_t block, const double anchor[3]);

/* ---- cliffs in a world (003 §5): a tile per type, presence cached -------------------------- */

/* Blocks on every steep rock wall of a world, through its amplify hook:
 *     rocks_cliffs *cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){ 0 });
 *     terrain_world_create(&(terrain_world_desc){ ..., .amplify = rocks_cliffs_amplify,
 *                                                 .amplify_user = cliffs });
 * Which type a wall breaks into (003 §5, "the material γ(a_k) corresponds to the material of the
 * underlying block"): the material of the stacks behind the face (three quarters of a metre
 * inside, along the field's gradient) decides. A rock material the game maps in material_blocks
 * gives its block type, wherever it lies, so cliffs change block type where the stacks change
 * material:
 *     .material_blocks = { [TERRAIN_BEDROCK] = ROCKS_BLOCK_EQUIDIMENSIONAL,
 *                          [MY_LIMESTONE] = ROCKS_BLOCK_TABULAR }   // MY_LIMESTONE ≥ BUILTIN_COUNT
 * Bedrock with no entry falls into strata by height: a copy belongs to the stratum of its
 * anchor's height, floor(y / stratum_height), whose type is strata[stratum mod strata_count]
 * (003 Fig. 11). Any other material (sand, a game's material with no entry) gets no blocks.
 * Presence is rocks_block_on_walls at the anchor (down to a metre inside the face) and, a metre
 * above and below it, a steep face within a metre (a wall, not a step); the wall must be a rock
 * material of the copy's type (sand slopes get no blocks), and 4 of the block's 6 extreme points
 * (along each axis) must lie inside the wall or within half a metre of its face (003 §5's
 * several anchors), the highest among them (no block stands over the wall's rim as a spike). It
 * is worked out once per tile cell and kept, checked against the versions of the column chunks
 * it read, so an edit brings it up to date. Fields sampled up to max_spacing get blocks; those
 * coarser than 1 m show only the blocks wider than 1.5 spacings, thinned as
 * rocks_block_tile_amplify says (a box filter of the spacing: no spikes from blocks thinner than
 * the grid), and a cell's presence is worked out only for those blocks until a finer field
 * asks. Every field at one spacing is treated alike, so chunks and their LOD seams agree. */
typedef struct rocks_cliffs_desc {
    uint64_t seed;                    /* 0 = 1 */
    rocks_block_type strata[8];       /* bottom up, repeating; all zero with count 0 = tabular,
                                         columnar, equidimensional; a DEFAULT one = equidimensional */
    int strata_count;                 /* 0 = 3 */
    float stratum_height;             /* metres; 0 = 20 */
    /* The block type each rock material of the stacks breaks into, by terrain_material; zero
     * (ROCKS_BLOCK_DEFAULT) = none: bedrock then follows the strata above, any other material
     * gets no blocks. Only TERRAIN_BEDROCK and a game's own materials (from
     * TERRAIN_MATERIAL_BUILTIN_COUNT, solid in the field like bedrock) may have an entry. All
     * zero (the default) = bedrock in strata, the world's cliffs as they always were. */
    rocks_block_type material_blocks[TERRAIN_MATERIAL_MAX];
    float tile_size;                  /* s; 0 = 16 */
    float joint;                      /* 0 = 0.6 m (at most s / 24): fields sampled every metre
                                         lose thinner ones */
    float steepness, depth_min, depth_max;   /* rocks_wall_presence's; all 0 = ε 0.5 and the
                                         anchor in [−0.6, 1.0] (up to the field's clamp) */
    float max_spacing;                /* 0 = 4 m: fields sampled up to this get blocks (the
                                         rings of levels 0, 1 and 2), coarser ones none. At
                                         h > 1 m a block shows only when wider than 1.5 h,
                                         thinned by h − w/2 under 2h (rocks_block_tile_amplify); 1 =
                                         level 0 only (a block of a few metres at 2 m unfiltered
                                         aliased into spikes) */
    float block_scale;                /* 0 = 1: the blocks' size. The tiles' side (tile_size),
                                         their points' spacing and the types' fracture spacings
                                         and disc radii all scale by it, so the blocks keep their
                                         shapes and grow. Bigger blocks show more at the world's
                                         1 m sampling, but fewer have their anchor within the
                                         presence band, so a low wall gets fewer (a 20 m wall of
                                         columnar blocks: none at 2). 0.5 … 4, the scaled side at
                                         most 64 m */
    /* A folder for the tiles' cache files (rocks_block_tile_desc.cache_path), one a type:
     * blocks-<type>-<seed as 16 hex digits>.bin (the seed above, with its default), so worlds of
     * other seeds keep their own; made if missing. NULL = the tiles are built each run. */
    const char *cache_dir;
    /* Builds (or reads) the tiles, one per type the strata (when bedrock has no entry) or
     * material_blocks use, at once on these workers; NULL
     * = one after another on the calling thread. The tiles are the same either way. */
    job_system *jobs;
} rocks_cliffs_desc;

/* One rocks_cliffs serves one world (its cache is keyed by the world's chunk versions). */
typedef struct rocks_cliffs rocks_cliffs;
rocks_cliffs *rocks_cliffs_create(const rocks_cliffs_desc *desc);   /* NULL with a message */
void rocks_cliffs_destroy(rocks_cliffs *cliffs);
/* terrain_world_desc.amplify, with amplify_user = the cliffs (thread-safe). */
void rocks_cliffs_amplify(void *cliffs, terrain_world *world, terrain_field *field);
/* terrain_world_desc.amplify_reach for these cliffs, metres along x, y and z: an edit changes
 * which blocks stand as far as a block's extent and what their presence reads (about 2 m) from
 * the columns it changed, so the chunks that far are meshed again. Zeros for NULL. */
void rocks_cliffs_reach(const rocks_cliffs *cliffs, float reach[3]);
typedef struct rocks_cliffs_stats_info {
    uint64_t fields, cells_computed;
    uint64_t cells_reused;            /* answers from the shared cache (not those a thread kept itself) */
    uint64_t copies_present;          /* block copies present whose bounds met a field's samples, summed over fields */
    double amplify_seconds;           /* in rocks_cliffs_amplify, summed over threads (less the
                                         point samples a thread answers from its kept region) */
    double presence_seconds;          /* of which working out presence (cells_computed) */
    double build_seconds;             /* the tiles, built or read from cache_dir */
    uint32_t tiles_from_cache;        /* of the tiles, those read from cache_dir */
    uint32_t blocks;                  /* blocks in the tiles, all types */
    float tile_size;                  /* metres, the tiles' side: tile_size · block_scale */
} rocks_cliffs_stats_info;
rocks_cliffs_stats_info rocks_cliffs_stats(const rocks_cliffs *cliffs);

#endif
