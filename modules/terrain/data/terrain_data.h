/* terrain_data.h — the terrain's data (modules/terrain/data/): materials and packed stacks,
 * 3D-noise generation, the world's chunk cache, the convolution implicit field, marching-cubes
 * meshes and their levels of detail, field and mesh files, screen-space errors, water planes,
 * the edit log and the world folder's database. No OpenGL and no ECS here: the other areas
 * (edit/, render/, ecs/) build on this one, never the other way. terrain/terrain.h includes it.
 *
 * The world is a 2D grid of columns, each a stack of material layers {material, thickness} from
 * the world floor up (paper 000 §3.2, 002 §3.1.1): bedrock, sand, rocks, water, air. Caves and
 * overhangs are air layers between solid ones. Columns are grouped in chunks of
 * TERRAIN_CHUNK_COLUMNS² columns, addressed by 64-bit chunk coordinates, generated on demand and
 * deterministically from (seed, chunk coordinate) alone (002 §3.1.3, 004 §2):
 *
 *     terrain_world *world = terrain_world_create(&(terrain_world_desc){
 *         .generation = terrain_generation_defaults(42) });
 *     const terrain_stacks *chunk = terrain_world_stacks(world, (terrain_chunk_coord){ 3, -7 });
 *     terrain_layer layers[16];
 *     int n = terrain_stacks_column(chunk, 5, 9, layers, 16);   // column (5, 9) of that chunk
 *
 * The surface is the zero set of a convolution field over the solid materials (000 §3.3):
 *     f(p) = 2·V(p) / (8σ³) − 1
 * where V(p) is the volume of sand and bedrock inside the cube of radius σ around p; f > 0 is
 * solid, f < 0 air, f = 0 the surface. terrain_field_sample evaluates it on a regular grid, and
 * terrain_mesh_build turns such a grid into an indexed triangle mesh (marching cubes) with normals
 * from the field's gradient and per-vertex material weights (000 §6).
 *
 * Units are metres; +y is up. Column (i, k) of chunk (cx, cz) covers x ∈ [X, X + TERRAIN_COLUMN_SIZE)
 * with X = (cx·TERRAIN_CHUNK_COLUMNS + i)·TERRAIN_COLUMN_SIZE, and the same for z.
 *
 * Threads: stacks, fields and meshes are plain data; terrain_world_stacks may be called from any
 * thread (jobs generate chunks in parallel).
 */
#ifndef TERRAIN_DATA_H
#define TERRAIN_DATA_H

#include "gfx/gfx.h"                  /* handles in terrain_gpu_mesh */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/core.h"   /* core_error */

/* ---- materials ---------------------------------------------------------------------------- */

/* A game may add materials after TERRAIN_MATERIAL_BUILTIN_COUNT, up to TERRAIN_MATERIAL_MAX. */
typedef enum terrain_material {
    TERRAIN_AIR,
    TERRAIN_BEDROCK,
    TERRAIN_SAND,
    TERRAIN_ROCKS,
    TERRAIN_WATER,
    TERRAIN_MATERIAL_BUILTIN_COUNT,
    TERRAIN_MATERIAL_MAX = 16,
} terrain_material;

const char *terrain_material_name(terrain_material material);
/* Whether the material belongs to the implicit surface's skeleton: sand, bedrock and a game's
 * own materials (solid rock like bedrock: cliffs' strata, rocks_blocks.h); rocks are the rocks
 * module's own skeleton, water has its own surface. */
bool terrain_material_in_field(terrain_material material);

/* ---- layout ------------------------------------------------------------------------------- */

#define TERRAIN_CHUNK_COLUMNS 32          /* columns along each side of a chunk */
#define TERRAIN_COLUMN_SIZE 1.0f          /* metres between column edges (and field samples) */
#define TERRAIN_FLOOR_Y (-256.0f)         /* where every stack starts; below is bedrock */
#define TERRAIN_HEIGHT_QUANTUM (1.0f / 32.0f)   /* layer thicknesses are multiples of this */

typedef struct terrain_chunk_coord { int64_t x, z; } terrain_chunk_coord;

typedef struct terrain_layer {
    terrain_material material;
    float thickness;                      /* metres, a multiple of TERRAIN_HEIGHT_QUANTUM, > 0 */
} terrain_layer;

/* ---- stacks: one chunk's columns, packed ------------------------------------------------- */

/* Immutable once built. Layers of all columns in one array with per-column offsets; thicknesses
 * quantized; the air above the last solid layer is implicit. */
typedef struct terrain_stacks terrain_stacks;

/* Building: columns in order z-major (column index = k·N + i), layers bottom-up. Adjacent layers
 * of the same material merge; zero-thickness layers are dropped; thicknesses are rounded to the
 * quantum. */
typedef struct terrain_stacks_builder terrain_stacks_builder;
terrain_stacks_builder *terrain_stacks_builder_create(void);
void terrain_stacks_builder_push(terrain_stacks_builder *builder, terrain_material material, float thickness);
void terrain_stacks_builder_end_column(terrain_stacks_builder *builder);
/* After exactly TERRAIN_CHUNK_COLUMNS² columns; resets the builder for another chunk. */
terrain_stacks *terrain_stacks_builder_finish(terrain_stacks_builder *builder);
void terrain_stacks_builder_destroy(terrain_stacks_builder *builder);
/* A chunk built by asking `column` for the layers of each of its columns (global column indices
 * x, z), bottom-up through terrain_stacks_builder_push: worlds made by hand for tests and tools,
 * or a game's own generator behind terrain_world_desc.generate. */
typedef void (*terrain_column_fn)(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder);
terrain_stacks *terrain_stacks_from_columns(terrain_chunk_coord coord, terrain_column_fn column, void *user);
void terrain_stacks_destroy(terrain_stacks *stacks);

/* Layers of column (i, k), 0 ≤ i, k < N, bottom-up from TERRAIN_FLOOR_Y; returns how many there
 * are (writes at most `capacity`). */
int terrain_stacks_column(const terrain_stacks *stacks, int i, int k, terrain_layer *layers, int capacity);
/* Material at height y in column (i, k): TERRAIN_BEDROCK below the floor, TERRAIN_AIR above. */
terrain_material terrain_stacks_material_at(const terrain_stacks *stacks, int i, int k, float y);
/* Height of the top of the highest layer that is not air or water (the ground a player stands
 * on from above), or TERRAIN_FLOOR_Y for an empty column. */
float terrain_stacks_top(const terrain_stacks *stacks, int i, int k);
/* Height of the top of the highest non-air layer (water included). */
float terrain_stacks_surface(const terrain_stacks *stacks, int i, int k);
/* The lowest and highest heights, over all columns, where material in the field (sand, bedrock,
 * rocks) meets material out of it (air, water), the world floor and the top of each column
 * included. The field is solid below and empty above these heights' range, farther than its
 * kernel reaches: streaming skips mesh chunks that lie wholly outside it. */
void terrain_stacks_interface_range(const terrain_stacks *stacks, float *lowest, float *highest);
size_t terrain_stacks_bytes(const terrain_stacks *stacks);   /* memory held, headers included */
uint64_t terrain_stacks_hash(const terrain_stacks *stacks);  /* of the logical content */

/* ---- generation (002 §3.1.3, 004 §2) ------------------------------------------------------ */

typedef struct terrain_generation_desc {
    uint64_t seed;
    float sea_level;                  /* water fills air below this height */
    /* Macro relief: rescale-and-add multifractal with domain warping (004 §2). */
    float relief_height;              /* metres of relief around base_height */
    float base_height;
    float relief_wavelength;          /* metres of the lowest octave */
    float lacunarity;                 /* r */
    float hurst;                      /* H */
    int relief_octaves;               /* at most: the count stops where an octave would be shorter
                                         than two samples (004 §4.1) */
    float warp_strength;
    /* 3D detail: ground/sky split by the height gradient, perturbed by fBm (002 §3.1.3). */
    float vertical_perturbation;      /* metres the fBm moves the ground up and down */
    float horizontal_perturbation;    /* metres it moves it sideways (overhangs) */
    float perturbation_wavelength;
    int perturbation_octaves;
    /* Caves where the product of two ridged multifractals is near zero. */
    float cave_threshold;
    float cave_wavelength;
    float cave_fade_height;           /* metres below the surface height over which caves fade in */
    /* Sand over bedrock on low slopes. */
    float sand_max_slope;             /* tan of the steepest slope sand stays on */
    float sand_depth;
    /* Lakes above the sea in basins (terrain_generate.c, "Lakes"): one candidate site per
     * lake_spacing² cell, kept with lake_probability; a bowl of radius lake_radius_min …
     * lake_radius_max, up to lake_depth deep, its water level below the lowest ground on the
     * site's rim, so that the rim holds it. lake_spacing 0 = no lakes. */
    float lake_spacing;               /* metres between candidate sites */
    float lake_probability;           /* share of candidates kept, 0 … 1 */
    float lake_radius_min, lake_radius_max;   /* metres, the bowl's */
    float lake_depth;                 /* metres of water at the deepest */
    /* Rock layers over the top run's sand or bedrock (terrain_generate.c, "Rocks"), where the
     * rocks module draws piles; each 0 = its default, < 0 = none. Never steeper than rocks hold
     * (the stabilizer leaves them alone). */
    float talus_depth;                /* metres of rocks leaning on a cliff's foot; 0 = 2.5 */
    float scree_depth;                /* metres of scree on slopes too steep for sand; 0 = 1 */
    float scree_min_slope;            /* tan of the gentlest slope with scree; 0 = 0.58 (30°) */
    float lake_rocks_depth;           /* metres of stones near a lake's waterline; 0 = 0.8 */
} terrain_generation_desc;

/* Parameters that make a varied, good-looking world for this seed. */
terrain_generation_desc terrain_generation_defaults(uint64_t seed);

/* The stacks of one chunk; depends only on (params, coord). Free with terrain_stacks_destroy. */
terrain_stacks *terrain_generate_chunk(const terrain_generation_desc *params, terrain_chunk_coord coord);

/* ---- noise -------------------------------------------------------------------------------- */

/* Our gradient noise in [-1, 1], seeded. The batch form evaluates `count` points along y (a
 * column) so the loop vectorises. */
float terrain_noise3(uint64_t seed, float x, float y, float z);
void terrain_noise3_column(uint64_t seed, float x, float y0, float dy, float z, int count, float *out);
/* fBm of `octaves` octaves (lacunarity 2, gain 0.5), like stb_perlin_fbm_noise3's defaults. */
float terrain_fbm3(uint64_t seed, float x, float y, float z, int octaves);

/* ---- the world: generated chunks, cached -------------------------------------------------- */

/* generate (for tests and tools that need chunks they control, e.g. hand-made stacks for the
 * field's exact cases): if set, called instead of terrain_generate_chunk(&generation, coord)
 * whenever a chunk is needed; the world owns the stacks it returns (frees them with
 * terrain_stacks_destroy) as it does generated ones. It must be a pure function of the
 * coordinate and safe to call from any thread. */
typedef struct terrain_edit_log terrain_edit_log;   /* persistent edits, below */
typedef struct terrain_world terrain_world;
typedef struct terrain_field terrain_field;         /* the field's samples, below */

typedef struct terrain_world_desc {
    terrain_generation_desc generation;
    size_t max_chunks;                /* cached chunks kept (least recently used go); 0 = 4096 */
    terrain_stacks *(*generate)(void *user, terrain_chunk_coord coord);  /* NULL = generation */
    void *generate_user;              /* passed to generate */
    terrain_edit_log *edits;          /* not owned; NULL = edits live only in the cache (an
                                         edited chunk is then never evicted). See "edits in
                                         the world" (edit/terrain_edit.h) */
    bool sea;                         /* with `generate`: edits let the sea at
                                         generation.sea_level in, as in a generated world (see
                                         "the sea after edits", edit/terrain_edit.h); false =
                                         a hand-made world has no sea. A generated world
                                         always has it */
    /* amplify (003 §5): if set, every field the world samples (terrain_field_sample, and
     * terrain_field_at as a one-sample field) passes through it after f is computed. It may
     * raise values, f̃ = max(f, t), and meshes, collision and picking then all see what it
     * adds (cliff blocks: rocks_blocks.h). It must be a pure function of the samples' world
     * positions and the world's stacks, read the field only through terrain_field_base_at (so
     * it never calls itself), keep values in [−1, 1], and be safe from any thread. */
    void (*amplify)(void *user, terrain_world *world, terrain_field *field);
    void *amplify_user;               /* passed to amplify */
    /* Metres along x, y and z: how far from a column the values amplify adds may change when
     * that column's stacks change (what it adds near p may depend on columns that far from p).
     * An edit then meshes again every chunk within this distance of the columns it changed,
     * not only those whose own samples read them (rocks_cliffs_reach for cliff blocks). Zeros
     * = amplify reads only the field's own kernel. */
    float amplify_reach[3];
} terrain_world_desc;

terrain_world *terrain_world_create(const terrain_world_desc *desc);
void terrain_world_destroy(terrain_world *world);
/* The chunk's stacks, generated on first use (thread-safe: any thread, any number at once).
 * EVICTION RULE: terrain_world_stacks never evicts. A returned pointer stays valid until the next
 * terrain_world_trim (or terrain_world_destroy) — so within a frame every pointer a job got stays
 * good — and across trims for as long as its chunk is retained. */
const terrain_stacks *terrain_world_stacks(terrain_world *world, terrain_chunk_coord coord);
/* Reference counts (generating the chunk if needed): a retained chunk is never evicted. A
 * release without a matching retain is logged and ignored. */
void terrain_world_retain(terrain_world *world, terrain_chunk_coord coord);
void terrain_world_release(terrain_world *world, terrain_chunk_coord coord);
/* Evicts least recently used, unretained chunks until at most max_chunks are cached (retained
 * ones may keep it above); returns how many went. Call it where no thread holds an unretained
 * pointer: once a frame, between phases (the frame loop), never from a job. A world that is
 * never trimmed keeps every chunk it generated. */
size_t terrain_world_trim(terrain_world *world);
/* Work that spans trims (a background job) brackets its reads: stacks it got between begin and
 * end stay valid however many trims happen meanwhile (evicted ones are freed after its end).
 *     uint64_t token = terrain_world_read_begin(world);  ...  terrain_world_read_end(world, token); */
uint64_t terrain_world_read_begin(terrain_world *world);
void terrain_world_read_end(terrain_world *world, uint64_t token);
size_t terrain_world_chunk_count(terrain_world *world);   /* chunks cached now */
size_t terrain_world_bytes(terrain_world *world);         /* bytes of the stacks cached now */
/* Whether the chunk is cached now (never generates it). */
bool terrain_world_has(terrain_world *world, terrain_chunk_coord coord);
/* Changes terrain_world_desc.max_chunks (0 = 4096); the next trim applies it. */
void terrain_world_set_max_chunks(terrain_world *world, size_t max_chunks);
const terrain_generation_desc *terrain_world_generation(const terrain_world *world);
/* Whether the world has a sea at generation.sea_level (terrain_world_desc.sea): generated worlds
 * always, hand-made ones when asked. The water renderer draws it; edits let it in. */
bool terrain_world_has_sea(const terrain_world *world);
/* Material at a world point (generating its chunk if needed). */
terrain_material terrain_world_material_at(terrain_world *world, double x, double y, double z);
/* The top of the highest solid layer (terrain_stacks_top) of the column under world (x, z). */
float terrain_world_top(terrain_world *world, double x, double z);
/* Whether water lies on top of the column under world (x, z): its highest non-air layer is water
 * (the sea, a lake, a flooded pit). Then *surface is the water's top and *ground the top of the
 * highest solid layer under it (terrain_stacks_surface and terrain_stacks_top); either pointer
 * may be NULL. False (nothing written) for a dry column. Generates the chunk if needed. */
bool terrain_world_water_at(terrain_world *world, double x, double z, float *surface, float *ground);

/* ---- the implicit field (000 §3.3) -------------------------------------------------------- */

/* One 32³-cell chunk (cx, cy, cz) meshed, with a one-sample apron so that normals on its border
 * agree with the neighbours':
 *     terrain_field field;
 *     terrain_field_sample(world, &(terrain_field_desc){
 *         .first = { 32 * cx - 1, 32 * cy - 1, 32 * cz - 1 }, .size = { 35, 35, 35 } }, &field);
 *     terrain_mesh mesh;
 *     terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = world, .apron = 1 }, &mesh);
 *     terrain_field_free(&field);
 *     ...                              // upload mesh.vertices / mesh.indices at mesh.origin
 *     terrain_mesh_free(&mesh);
 */

/* A regular grid of samples: values[(z·ny + y)·nx + x] at origin + (x, y, z)·spacing. */
typedef struct terrain_field {
    int nx, ny, nz;
    double origin[3];
    float spacing;
    float *values;
} terrain_field;

typedef struct terrain_field_desc {
    int64_t first[3];                 /* the first sample's grid index (x, y, z) */
    int size[3];                      /* samples along each axis */
    float sigma;                      /* kernel radius in metres; 0 = TERRAIN_COLUMN_SIZE */
    int step;                         /* grid indices between samples (a coarser grid for level
                                         of detail; the kernel stays sigma); 0 = 1 */
} terrain_field_desc;

/* Samples f on the grid of spacing c = TERRAIN_COLUMN_SIZE: index (i, j, k) is the world point
 * (i·c, j·c, k·c), so samples sit on column corners. With a step, sample (x, y, z) of the result
 * is grid index first + (x, y, z)·step (field.spacing = step·c): the same point-sampled f, the
 * kernel unchanged. Reads whatever chunks the kernel reaches (generating them). O(1) amortised
 * per sample (O(⌈σ/c⌉) with a step). Shared samples of two requests are bit-identical, whatever
 * their steps (adjacent chunks' meshes meet exactly, across levels of detail too). False
 * (message logged) only when the request is absurd: a size ≤ 0 or over 1024, sigma ≤ 0 or over
 * 16 columns, a step < 0 or over 65536, an index beyond ±2^52.
 * Free with terrain_field_free. */
bool terrain_field_sample(terrain_world *world, const terrain_field_desc *desc, terrain_field *out);
void terrain_field_free(terrain_field *field);
/* The field at one point, by direct summation (slow; for tests and single queries), amplified
 * as terrain_field_sample's samples are (terrain_world_desc.amplify). */
float terrain_field_at(terrain_world *world, double x, double y, double z, float sigma);
/* The same without the amplification: f of the stacks alone (what an amplifier reads). */
float terrain_field_base_at(terrain_world *world, double x, double y, double z, float sigma);

/* ---- meshes ------------------------------------------------------------------------------- */

/* 32 bytes, laid out for the GPU (terrain_render.c's attributes; grass_place.comp reads the
 * buffer as 8 words a vertex): position at byte 0, normal at 12, weights at 24, occlusion at 28. */
typedef struct terrain_vertex {
    float position[3];                /* metres, relative to terrain_mesh.origin */
    float normal[3];                  /* unit, pointing into the air */
    uint8_t weights[4];               /* visible bedrock, sand, rocks, water around the vertex;
                                         they sum to 255 (000 §6) */
    uint8_t occlusion;                /* ambient occlusion, /255: 0 = open sky (so a zeroed vertex
                                         is open), 255 = enclosed; openness = 1 − occlusion/255 */
    uint8_t reserved[3];              /* 0 */
} terrain_vertex;
_Static_assert(sizeof(terrain_vertex) == 32, "terrain_vertex is 8 words on the GPU");

/* A mesh's triangles come in parts: runs of its indices, each with its own box, so that a
 * renderer leaves out the parts outside the view (a chunk that the frustum's edge crosses draws
 * only the parts in view). The mesher sorts the triangles by the cell of a
 * TERRAIN_MESH_PART_GRID² grid over the mesh's box (in x and z) that their centroid falls in. */
#define TERRAIN_MESH_PART_GRID 4
#define TERRAIN_MESH_PARTS (TERRAIN_MESH_PART_GRID * TERRAIN_MESH_PART_GRID)

typedef struct terrain_mesh_part {
    uint32_t first_index, index_count;
    float bounds_min[3], bounds_max[3];   /* of its triangles' vertices, relative to origin */
} terrain_mesh_part;

typedef struct terrain_mesh {
    double origin[3];                 /* world position of the vertices' (0, 0, 0) */
    terrain_vertex *vertices;
    uint32_t *indices;                /* triangles, counter-clockwise seen from the air */
    uint32_t vertex_count, index_count;
    float bounds_min[3], bounds_max[3];   /* of the vertices, relative to origin */
    terrain_mesh_part parts[TERRAIN_MESH_PARTS];   /* in index order, none empty, together all
                                                      the indices */
    uint32_t part_count;              /* 0 = one part, the whole mesh (desc.no_optimize) */
} terrain_mesh;

typedef struct terrain_mesh_desc {
    terrain_world *world;             /* for material weights and occlusion; NULL = all
                                         bedrock, occlusion 0 (open) */
    int apron;                        /* samples along each border that are read for gradients
                                         but not meshed (1 makes normals agree across chunks) */
    bool no_optimize;                 /* skip the parts and meshoptimizer's vertex-cache
                                         order: the mesher's raw output */
    bool no_occlusion;                /* occlusion 0 everywhere (skips its cost) */
    float max_error;                  /* metres: > 0 simplifies the triangles (edge collapses
                                         that move the surface at most about this far, never a
                                         vertex of the mesh's open border, so a chunk still meets
                                         its neighbours exactly); 0 = every marching-cubes
                                         triangle (README, "Simplified chunks") */
    struct job_system *jobs;          /* large fields (64³ cells and up) are meshed on its
                                         threads; NULL = the calling thread only. Same mesh
                                         either way */
} terrain_mesh_desc;

/* Marching cubes over every cell of the field (nx−1 × ny−1 × nz−1 cells, less the apron) with
 * shared vertices; watertight for closed surfaces (ambiguous faces always keep the inside
 * corners apart). mesh.origin is the field's origin. With a world, each vertex also gets its
 * material weights (000 §6: each material's share of a 1 m segment just under the surface,
 * exact layer lengths, bilinear over the four columns around it) and its ambient occlusion
 * (rays through the stacks up to 8 m around the normal; 0 on open ground), both functions of the
 * vertex's world position and normal alone, so neighbouring chunks agree on shared vertices. An empty or full field gives an empty mesh
 * (NULL arrays) at once. False (message logged) for a field without values or a negative apron.
 * Free with terrain_mesh_free. */
bool terrain_mesh_build(const terrain_field *field, const terrain_mesh_desc *desc, terrain_mesh *out);
void terrain_mesh_free(terrain_mesh *mesh);

/* TERRAIN_MESH_CELLS³ cells of the sample grid; (x, y, z) counts mesh chunks. */
#define TERRAIN_MESH_CELLS 32

/* Level of detail. A mesh chunk at level L has TERRAIN_MESH_CELLS cells per side, each 2^L
 * columns wide: it covers TERRAIN_MESH_CELLS·2^L metres, its samples are f at every 2^L-th grid
 * point (the kernel stays one column). Chunks of a level tile space; a chunk whose neighbours
 * are one level finer closes the seams with them by "subdivided transition faces" (README,
 * Level of detail): its cell edges on a boundary shared with a finer neighbour get their midpoint
 * sample, its cell faces on a face shared with one their centre too, and those cells are
 * contoured face by face with the same rule as the regular cells, so both sides draw the same
 * segments on the shared faces and the union is watertight. The finer chunk needs nothing.
 *     terrain_mesh mesh;
 *     terrain_mesh_chunk(world, cx, cy, cz, &(terrain_lod_desc){ .level = 1,
 *         .finer_neighbours = terrain_lod_neighbour_bit(-1, 0, 0) }, &mesh);   // finer at −x
 *
 * finer_neighbours: bit terrain_lod_neighbour_bit(dx, dy, dz) is set when the chunk-sized region
 * at offset (dx, dy, dz) ∈ {−1, 0, 1}³ \ {0} is meshed one level finer (level L − 1). The bit is
 * index (dz+1)·9 + (dy+1)·3 + (dx+1), less one above the centre (13): 26 bits. Corner bits are
 * accepted but change nothing (a corner neighbour shares a point only). Chunks that touch (faces,
 * edges or corners) must be at most one level apart, and every chunk's mask must say the truth
 * about its neighbours (those of an octree do). */
typedef struct terrain_lod_desc {
    int level;                        /* 0 … 16; cells 2^level columns wide */
    uint32_t finer_neighbours;        /* 26 bits (above); must be 0 at level 0 */
    float max_error;                  /* terrain_mesh_desc.max_error: metres the triangles may be
                                         simplified by, the border kept; 0 = none. Streaming asks
                                         for terrain_simplify_error (terrain_ecs.h) */
} terrain_lod_desc;

uint32_t terrain_lod_neighbour_bit(int dx, int dy, int dz);   /* 0 for (0, 0, 0) or out of range */

/* Samples what chunk (x, y, z) of level lod->level needs (its first sample is grid index
 * (x, y, z)·TERRAIN_MESH_CELLS·2^L, with a one-sample apron for gradients, plus the transition
 * samples) and meshes it with weights from `world`; mesh.origin is its apron's first sample.
 * lod NULL = level 0 with no finer neighbours, which gives exactly the terrain_field_sample +
 * terrain_mesh_build pair of the example above. False (message logged) for a bad level or
 * mask, or a chunk too far out. Free with terrain_mesh_free. */
bool terrain_mesh_chunk(terrain_world *world, int64_t x, int64_t y, int64_t z, const terrain_lod_desc *lod,
                        terrain_mesh *out);

/* ---- field and mesh files ----------------------------------------------------------------- */

/* A field on disk is two files: PREFIX.raw, the values as little-endian float32 (x fastest, then
 * y, then z; f > 0 inside), and PREFIX.json, its header:
 *     {"dims":[NX,NY,NZ],"origin":[x,y,z],"spacing":s}
 * Both are written to a temporary beside the target and renamed over it. Reading checks
 * everything (keys, types, 1 ≤ dims ≤ TERRAIN_FIELD_FILE_MAX_DIM, finite origin, spacing > 0,
 * the .raw's size, finite values) and on failure returns false (out is then zeroed) with `error`
 * (may be NULL) saying why, its message naming the file: CORE_ERROR_IO (cannot open, read or
 * write), CORE_ERROR_FORMAT (not JSON, a missing key, a wrong type), CORE_ERROR_RANGE (dims
 * outside 1 … TERRAIN_FIELD_FILE_MAX_DIM or over the sample limit, a spacing ≤ 0, a value or
 * origin that is not finite), CORE_ERROR_CORRUPT (the .raw's size disagrees with the dims),
 * CORE_ERROR_ARGUMENT (writing an empty field). Free a read field with terrain_field_free. */
#define TERRAIN_FIELD_FILE_MAX_DIM 4096

typedef struct terrain_field_header {
    int dims[3];
    double origin[3];
    float spacing;
} terrain_field_header;

bool terrain_field_write(const terrain_field *field, const char *prefix, core_error *error);
/* `path` is PREFIX, PREFIX.json or PREFIX.raw. */
bool terrain_field_read(const char *path, terrain_field *out, core_error *error);
/* The header parser alone (text need not be NUL-terminated); the message names no file. */
bool terrain_field_header_parse(const char *text, size_t size, terrain_field_header *out,
                                core_error *error);

/* Binary little-endian PLY: vertex x y z nx ny nz (float, positions in world units relative to
 * mesh->origin), faces as a uchar count and uint indices. */
bool terrain_mesh_write_ply(const terrain_mesh *mesh, const char *path, core_error *error);
/* Total area of the triangles (m²). */
double terrain_mesh_area(const terrain_mesh *mesh);

/* ---- detail from a screen-space error ---------------------------------------------------
 *
 * A surface that is off by ε metres, seen from d metres away across the view direction, is off
 * by ε·H / (2·d·tan(θ/2)) pixels on a viewport H pixels tall with a vertical field of view θ (the
 * perspective projection's scale at the centre of the view). With a pixel error target τ a
 * level of detail whose geometric error is ε is therefore good enough beyond
 *     d = ε·K,   K = H / (2·τ·tan(θ/2))            (terrain_screen_error_scale)
 * Streaming (terrain_stream_desc.pixel_error) and the clipmap (terrain_clipmap_desc.pixel_error)
 * derive their extents from K and the errors below instead of fixed numbers:
 *     double k = terrain_screen_error_scale(720, 0, 1.0f);   // 623.5: 720 px, 60°, 1 px
 *     int w = terrain_rings_half_width(3, k);                 // 12 (README)
 * The errors are mean distances between a level's surface and the finest one, measured on
 * generated terrain (README, "Detail from a screen-space error"). */
#define TERRAIN_SCREEN_DEFAULT_HEIGHT 720 /* viewport_height 0 means this */
#define TERRAIN_GROUND_ERROR 2.0f         /* metres between the clipmap's ground G and the stacks'
                                             top, 90th percentile (README): the volumetric rings
                                             reach at least this error's distance */
/* K above, in pixels per metre of error per metre of distance; 0 when pixel_error ≤ 0.
 * viewport_height 0 = TERRAIN_SCREEN_DEFAULT_HEIGHT, fov_y 0 = 60° (terrain_view's default). */
double terrain_screen_error_scale(int viewport_height, float fov_y, float pixel_error);
/* ε of a mesh-chunk level (cells 2^L m): h²/50 m below h = 6.25 m, h/8 above (see the README). */
double terrain_chunk_level_error(int level);
/* ε of a clipmap level of `spacing` metres: spacing/4 (mean vertical error of G at that spacing,
 * its triangles, against G at 1 m). */
double terrain_clipmap_spacing_error(double spacing);
/* The metres from a viewer to the outer border of level `level`'s area at least, wherever the
 * viewer stands within its snapped centre (rings of `levels` levels, half_width w): the area
 * reaches w·32·2^L m from a centre that is up to half a coarsest chunk (16·2^(levels−1) m) from
 * the viewer along each axis. level = levels − 1 is the rings' reach, where the clipmap starts. */
double terrain_rings_clearance(int half_width, int levels, int level);
/* The smallest half_width (even when levels > 1, at most 64) whose rings meet scale K: every
 * level L + 1 starts at least ε(L + 1)·K from the viewer, and the clipmap at least
 * TERRAIN_GROUND_ERROR·K. */
int terrain_rings_half_width(int levels, double scale);

/* ---- the edit log: persistent edits ----
 *
 * Every edit of a chunk is recorded as one entry of that chunk's log: the tool that made it and
 * the columns it changed with their new layers (in quanta, exact). A chunk generated again —
 * after eviction, or in a later run — replays its log over the generated stacks and comes back
 * byte for byte as it was. The world does this itself when given a log
 * (terrain_world_desc.edits, terrain_world_commit). A world folder keeps the log in one
 * database with terrain_store (below), whose every save is one transaction:
 *
 *     terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
 *     core_error error = {0};
 *     terrain_store *store = terrain_store_create(&(terrain_store_desc){
 *         .dir = "saves/world1", .edits = log, .seed = params.seed }, &report, &error);
 *     ... edits ...
 *     terrain_store_save(store, &error);
 *
 * The per-file layout (terrain_edit_log_save and _load) is how world folders were kept before
 * world.db; terrain_store imports such a folder once. It stays for exporting and importing one
 * chunk a file. Each file is atomic on its own, but a save that spans chunks is several files:
 * a crash part-way leaves some chunks new and others old. Do not keep a world in it.
 *
 * Files: one per chunk, DIR/edits/<x>_<z>.tel, written to a temporary file in the same folder,
 * flushed (fsync) and renamed over the old one, so a crash at any moment leaves the previous
 * file or the new one, never a torn one. Each file carries the world's key (a different seed or
 * generator refuses it) and a checksum. A file that is corrupt, truncated, from another world or
 * otherwise unreadable is reported in the load result, renamed to <name>.bad (kept for a human
 * to look at) and its chunk stays as generated; loading never crashes on a file's content.
 *
 * Threads: one mutex inside; record and replay may be called from any thread. Saves and loads
 * write and read files outside it (replays never wait for a disk), one at a time per log. One
 * process saves into a folder at a time (loading removes the temporaries a crash left). */

typedef enum terrain_edit_tool {
    TERRAIN_EDIT_SET = 1,             /* columns set directly (terrain_columns_set) */
    TERRAIN_EDIT_SCULPT_ADD,
    TERRAIN_EDIT_SCULPT_CARVE,
    TERRAIN_EDIT_SWEEP,
    TERRAIN_EDIT_DEPOSIT,
    TERRAIN_EDIT_ERODE,
    TERRAIN_EDIT_STABILIZE,
    TERRAIN_EDIT_COMPACTED,           /* several entries folded into one (terrain_edit_log_compact) */
    TERRAIN_EDIT_TOOL_COUNT
} terrain_edit_tool;

const char *terrain_edit_tool_name(terrain_edit_tool tool);

/* A key for the generator: equal for equal parameters (seed included; −0 and +0 alike),
 * different otherwise with overwhelming probability. It also hashes a revision of the generator
 * (EDIT_GENERATOR_REVISION in terrain_edit_log.c): a change to what terrain_generate_chunk makes
 * of the same parameters must bump it, so that old logs are refused, not replayed over other
 * ground. */
uint64_t terrain_generation_key(const terrain_generation_desc *params);

typedef struct terrain_edit_log terrain_edit_log;
typedef struct terrain_edit_log_desc {
    uint64_t world_key;               /* terrain_generation_key of the world the edits apply to
                                         (required: 0 is a key like any other, so pass it) */
} terrain_edit_log_desc;
terrain_edit_log *terrain_edit_log_create(const terrain_edit_log_desc *desc);
void terrain_edit_log_destroy(terrain_edit_log *log);

/* Appends an entry for `coord`: the columns where `after` differs from `before` (nothing when
 * they are equal: returns true, no entry). False (message logged, nothing recorded) for NULL
 * stacks, an unknown tool, or a changed column no file could hold (over 65 535 layers, or 2^26
 * quanta tall: columns regions refuse those too). */
bool terrain_edit_log_record(terrain_edit_log *log, terrain_chunk_coord coord, terrain_edit_tool tool,
                             const terrain_stacks *before, const terrain_stacks *after);
/* The chunk's entries replayed in order over `generated`: new stacks (free with
 * terrain_stacks_destroy), or NULL when the chunk has no entries (or `generated` is NULL,
 * message logged). An entry whose columns would overflow packed stacks (a row over 65 535
 * layer words; only a file made by hand gets there) is skipped with a message logged. */
terrain_stacks *terrain_edit_log_replay(terrain_edit_log *log, terrain_chunk_coord coord,
                                        const terrain_stacks *generated);
int terrain_edit_log_entries(terrain_edit_log *log, terrain_chunk_coord coord);   /* 0 = unedited */
int terrain_edit_log_chunks(terrain_edit_log *log);                              /* chunks with entries */
/* Folds each chunk's entries into one (TERRAIN_EDIT_COMPACTED: the final layers of every column
 * ever changed), so the log stops growing with repeated strokes; replay gives the same bytes.
 * Chunks of one entry are left as they are; folded ones are written again by the next save. */
void terrain_edit_log_compact(terrain_edit_log *log);

/* Writes the chunks whose entries changed since the last save (or load, or parse) as above,
 * creating DIR and DIR/edits as needed (nothing to write: nothing touched). A log loaded from one
 * folder and saved to another writes only what changed. False with CORE_ERROR_IO and
 * "PATH: reason (strerror)" in `error` when a file cannot be written (the first such; each is
 * also logged; the others are still written; the chunks that failed stay marked, a later save
 * retries them), CORE_ERROR_ARGUMENT for a NULL log or no folder. A chunk whose file would pass
 * 1 GiB is compacted first. */
bool terrain_edit_log_save(terrain_edit_log *log, const char *dir, core_error *error);

typedef struct terrain_edit_log_load_result {
    int chunks_loaded;                /* files read into the log */
    int files_rejected;               /* files reported and renamed to .bad */
    core_error first_problem;         /* the first rejected file: its code (CORE_ERROR_CORRUPT for a
                                         checksum mismatch, …) and "DIR/edits/3_-7.tel: checksum
                                         mismatch …"; code CORE_ERROR_NONE when none was */
} terrain_edit_log_load_result;

/* Reads every chunk file DIR/edits/<x>_<z>.tel into the log (replacing what it held for those
 * chunks; they are then clean). A rejected file changes nothing in the log (in a fresh log its
 * chunk has no entries: it stays as generated). Leftover temporaries of a crashed save are
 * removed; other names are left alone. A missing DIR or DIR/edits is an empty world (true).
 * False (CORE_ERROR_IO in `error`, naming the folder) only when DIR or DIR/edits exists but is
 * not a folder or cannot be listed; CORE_ERROR_ARGUMENT for a NULL log or no folder. */
bool terrain_edit_log_load(terrain_edit_log *log, const char *dir, terrain_edit_log_load_result *result,
                           core_error *error);
/* One file's bytes (what load reads; the fuzz target's entry point): true and the chunk's entries
 * put in the log in place of those it held (the chunk clean, as after a load), or false with
 * the reason in `error` and the log unchanged: CORE_ERROR_CORRUPT (truncated, checksum
 * mismatch, sizes that run past the end, bytes after the last entry), CORE_ERROR_FORMAT (wrong
 * magic, unknown tool, columns out of order, unmerged layers, no entries), CORE_ERROR_VERSION
 * (another format version), CORE_ERROR_MISMATCH (saved by another world), CORE_ERROR_RANGE (a
 * material, column index, count or height past its limit). The file name's check is load's. */
bool terrain_edit_log_parse(terrain_edit_log *log, const void *bytes, size_t size, core_error *error);

/* ---- the world folder: one database, every save one transaction ----
 *
 * A world folder DIR keeps everything a world saves in DIR/world.db, an SQLite database: the
 * world's settings (its seed and generator key), every edited chunk's entries (each chunk as
 * the bytes of its edit file, checksum included) and named values other code saves beside them
 * (the game's player; the rocks' removals once rocks exist). A save writes every chunk and value
 * that changed in one transaction, so a crash at any moment (kill -9, power loss) leaves the
 * world as it was before the save or as it is after it, never some chunks of each.
 *
 *     terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
 *     terrain_store_report report;
 *     core_error error = {0};
 *     terrain_store *store = terrain_store_create(&(terrain_store_desc){
 *         .dir = "saves/world1", .edits = log, .seed = params.seed }, &report, &error);
 *     if (!store) fprintf(stderr, "%s\n", error.message);   // in use, another world, unwritable
 *     if (report.notice[0]) printf("%s\n", report.notice);  // a damaged file set aside, an import
 *     ... a world with .edits = log ...
 *     terrain_store_put(store, "game.player", &pose, sizeof pose);   // goes with the next save
 *     terrain_store_save_async(store);       // from the frame: takes a snapshot, writes elsewhere
 *     ...
 *     terrain_store_save(store, &error);     // at the end: waits, then saves
 *     terrain_store_destroy(store);
 *
 * Opening (terrain_store_create):
 *   - A missing folder or database is a new world: created, with the seed and key recorded.
 *   - Another process that has the world open makes create fail with CORE_ERROR_IO, "in use by
 *     another process" (report.in_use). The store holds SQLite's exclusive lock from create to
 *     destroy. A folder that cannot be made or a file that cannot be opened: CORE_ERROR_IO.
 *   - A database of another world (another seed or generator) makes it fail with
 *     CORE_ERROR_MISMATCH (report.other_world, report.recorded_seed). A database of a newer format
 *     makes it fail with CORE_ERROR_VERSION. Neither is touched.
 *   - A damaged or foreign file (not SQLite, not a world database, failing SQLite's checks, or
 *     a chunk whose bytes fail their checksum) is reported in report.notice naming the file,
 *     renamed to world.db.bad (then .bad.2, …; its -wal file goes with it) and replaced by a new
 *     world: the world opens as generated. Nothing else in the folder is touched.
 *   - A folder in the old layout (DIR/edits/X_Z.tel files) is imported once, in one transaction; after
 *     the commit the old folder is renamed DIR/edits.imported (kept, never deleted). Old files
 *     that cannot be read are reported and renamed .bad as terrain_edit_log_load does.
 *   - Every chunk in the database is put in the log (replacing what it held for those chunks),
 *     clean: the next save writes only what changes after.
 *
 * Saving: WAL mode, synchronous FULL: a commit appends to the write-ahead log and flushes it
 * once, however many chunks it holds. terrain_store_save_async takes a snapshot of the changed
 * chunks and values on the calling thread (serializing them: microseconds a chunk) and commits
 * it on the store's own thread (trace zone "terrain.store.save" on the lane "terrain.store").
 * A failed save (disk full, I/O error) rolls back and leaves everything marked changed, so the
 * next save writes it again.
 *
 * Threads: every call may come from any thread; calls on one store are serialized inside. The
 * store never reads the database after create: the log and the values live in memory. */

typedef struct terrain_store terrain_store;

typedef struct terrain_store_desc {
    const char *dir;                  /* the world folder; created (with its parents) if missing */
    terrain_edit_log *edits;          /* required, not owned: loaded into on create, saved from;
                                         its key is the world's */
    uint64_t seed;                    /* recorded in a new world (terrain_store_read_seed) */
} terrain_store_desc;

typedef struct terrain_store_report {
    int chunks_loaded;                /* chunks with edits put in the log */
    int chunks_imported;              /* of those, from an old DIR/edits folder this time */
    int files_rejected;               /* old-layout files that could not be imported (.bad) */
    bool set_aside;                   /* a damaged or foreign world.db was renamed (notice says) */
    bool in_use;                      /* create failed: another process has the world open */
    bool other_world;                 /* create failed: the database holds another world */
    uint64_t recorded_seed;           /* with other_world: the seed the database records */
    char notice[512];                 /* what was set aside or imported, or "" */
} terrain_store_report;

/* The world folder's store, its edits put in desc->edits; NULL with `error` (naming the file)
 * when the folder cannot be made, the world is in use or is another world's (see above), or
 * CORE_ERROR_ARGUMENT for a desc without dir or edits. `report` and `error` may be NULL. */
terrain_store *terrain_store_create(const terrain_store_desc *desc, terrain_store_report *report, core_error *error);
/* Waits for a save in flight and closes the database; it does not save (call terrain_store_save). */
void terrain_store_destroy(terrain_store *store);

/* Everything changed since the last save, in one transaction; waits for a save in flight first.
 * Each changed chunk's entries are folded into one first (terrain_edit_log_compact), so a
 * folder's size follows the columns edited, not the frames played.
 * False with CORE_ERROR_IO and "DIR/world.db: reason" in `error` (nothing of this save is kept;
 * retried next time). */
bool terrain_store_save(terrain_store *store, core_error *error);
/* A snapshot of what changed, committed on the store's thread; returns at once. False when the
 * previous save is still in flight (nothing taken: call again later). Nothing changed: true,
 * nothing written. */
bool terrain_store_save_async(terrain_store *store);
/* Waits for the save in flight, if any; its outcome (true when there was none), the reason in
 * `error` as terrain_store_save gives it (a failed save in flight is also logged, as nobody may
 * wait for it). */
bool terrain_store_wait(terrain_store *store, core_error *error);

/* A named value saved with the next save (names up to 63 bytes, values up to 1 MiB); the same
 * bytes as before change nothing. False for a bad name, size or NULL bytes (message logged). */
bool terrain_store_put(terrain_store *store, const char *name, const void *bytes, size_t size);
/* Copies up to `capacity` bytes of the named value; its size, or −1 when there is none. */
int64_t terrain_store_get(terrain_store *store, const char *name, void *bytes, size_t capacity);

/* The seed DIR/world.db records, without keeping the world open: 1 and *seed set; 0 when the
 * folder has no world.db; −1 with the reason in `error` when it cannot be read: CORE_ERROR_IO
 * (in use by another process, unreadable), CORE_ERROR_CORRUPT (not a sound database),
 * CORE_ERROR_FORMAT (no seed recorded), CORE_ERROR_ARGUMENT (no folder given). */
int terrain_store_read_seed(const char *dir, uint64_t *seed, core_error *error);

/* ---- commits: a chunk's stacks replaced (terrain_world.c) ----
 *
 * What edits go through (edit/terrain_edit.h: terrain_world_edit; ecs/terrain_ecs.h: the
 * stabilize phase), and what the streamer remeshes from. */

/* Replaces the chunk's stacks by `stacks` (taken over) and records the difference in the log,
 * tagged `tool`. The old stacks stay valid for readers until the next terrain_world_trim (and
 * for terrain_world_read_begin readers until they end), like evicted ones. The chunk is
 * retained while it differs from generation and no log keeps its edits (else evicting it would
 * lose them). */
void terrain_world_commit(terrain_world *world, terrain_chunk_coord coord, terrain_stacks *stacks,
                          terrain_edit_tool tool);
/* A chunk committed since the last terrain_world_take_changes, and the box in which its
 * materials changed (over all its commits since). */
typedef struct terrain_world_change {
    terrain_chunk_coord coord;
    int column_min[2], column_max[2]; /* changed columns (i, k) of the chunk, inclusive */
    float y_min, y_max;               /* world metres */
} terrain_world_change;
/* Chunks committed since the last call (each once, in commit order; a commit that changed
 * nothing is not one); returns how many (writes at most `capacity`; the rest stay for the next
 * call). The streamer remeshes the mesh chunks that read them. */
int terrain_world_take_changes(terrain_world *world, terrain_world_change *out, int capacity);
/* A version that changes with every commit of the chunk: the world's commit count at the
 * chunk's last commit (0 = never committed in this world: as generated, or replayed from a log
 * it was opened with). It survives the chunk's eviction and regeneration, so a cache keyed on it
 * stays right. */
uint32_t terrain_world_chunk_version(terrain_world *world, terrain_chunk_coord coord);
/* The world's commit count: every chunk's version is a count it had, so while this stays the
 * same no chunk's version has changed, and a cache keyed on versions need not ask again. */
uint32_t terrain_world_commit_count(terrain_world *world);

/* ---- water planes (002 §3.4, 004 §4.3) ---------------------------------------------------
 * Water is a material layer of the stacks; where it lies on top of a column its flat top is a
 * water surface. The mesh phase finds, for each mesh chunk, the water surfaces whose height lies
 * in the chunk's y range, grouped by height, and the streaming/upload step gives the chunk's
 * entity a WaterPlane component with them (removed again when the chunk holds none). The sea at
 * generation's sea_level reaches beyond the rings (the renderer draws it out to the horizon);
 * lakes above it come from the WaterPlane components. */

#define TERRAIN_WATER_PLANES_MAX 4

typedef struct terrain_water_plane {
    float height;                         /* world y of the surface */
    float deepest;                        /* world y of the lowest ground under it in this chunk */
    uint32_t rows[TERRAIN_MESH_CELLS];    /* bit i of rows[k]: cell column (i, k) of the mesh chunk
                                             (cells of 2^level metres) has this water on top */
} terrain_water_plane;

/* The water surfaces of mesh chunk (x, y, z) of level `level` (cells of 2^level metres, as
 * terrain_mesh_chunk's): for each of its 32 × 32 cell columns, whether the stacks have water on
 * top there (the column at the cell's centre while a cell is at most a column chunk wide, else
 * the cell's first column: columns the mesher's samples read anyway), grouped by surface height
 * (equal within one height quantum) when the height lies in the chunk's y range
 * [y·32·2^level, (y + 1)·32·2^level), most cells first (ties: the higher first), at most
 * min(capacity, TERRAIN_WATER_PLANES_MAX). Returns how many were written; 0 for a chunk without
 * water at its height; −1 (message logged) for a NULL world, a level outside 0 … 16, a chunk
 * index beyond ±2^30 or a negative capacity. Generates the column chunks it reads; thread-safe
 * as terrain_world_stacks. The mesh phase calls it for every mesh chunk it meshes. */
int terrain_water_planes_find(terrain_world *world, int64_t x, int64_t y, int64_t z, int level,
                              terrain_water_plane *out, int capacity);

/* On TerrainMeshChunk entities whose cells hold water on top (see above): set when the chunk's
 * mesh is uploaded (terrain_upload, main thread), replaced when an edit remeshes it, removed when
 * it holds water no more; an entity that streaming evicts takes it along. Registered by
 * terrain_ecs_create as ECS_COMPONENT(ecs, WaterPlane): another module finds its id with
 * ecs_component_lookup(ecs, "WaterPlane"). */
typedef struct WaterPlane {
    double origin[3];                     /* the mesh chunk's corner, world metres */
    float cell;                           /* metres per cell: 2^level */
    int count;                            /* planes used, highest share of cells first */
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
} WaterPlane;

#endif
