/* terrain.h — volumetric terrain: material stacks, 3D-noise generation, the convolution implicit
 * field, marching-cubes meshes.
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
#ifndef TERRAIN_H
#define TERRAIN_H

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
/* Whether the material belongs to the implicit surface's skeleton: sand and bedrock (rocks are
 * the rocks module's own skeleton, water has its own surface). */
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
    int relief_octaves;
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
                                         the world" below */
    bool sea;                         /* with `generate`: edits let the sea at
                                         generation.sea_level in, as in a generated world (see
                                         "edits in the world"); false = a hand-made world has
                                         no sea. A generated world always has it */
    /* amplify (003 §5): if set, every field the world samples (terrain_field_sample, and
     * terrain_field_at as a one-sample field) passes through it after f is computed. It may
     * raise values, f̃ = max(f, t), and meshes, collision and picking then all see what it
     * adds (cliff blocks: rocks_blocks.h). It must be a pure function of the samples' world
     * positions and the world's stacks, read the field only through terrain_field_base_at (so
     * it never calls itself), keep values in [−1, 1], and be safe from any thread. */
    void (*amplify)(void *user, terrain_world *world, terrain_field *field);
    void *amplify_user;               /* passed to amplify */
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

typedef struct terrain_mesh {
    double origin[3];                 /* world position of the vertices' (0, 0, 0) */
    terrain_vertex *vertices;
    uint32_t *indices;                /* triangles, counter-clockwise seen from the air */
    uint32_t vertex_count, index_count;
    float bounds_min[3], bounds_max[3];   /* of the vertices, relative to origin */
} terrain_mesh;

typedef struct terrain_mesh_desc {
    terrain_world *world;             /* for material weights and occlusion; NULL = all
                                         bedrock, occlusion 0 (open) */
    int apron;                        /* samples along each border that are read for gradients
                                         but not meshed (1 makes normals agree across chunks) */
    bool no_optimize;                 /* skip meshoptimizer's vertex-cache reordering */
    bool no_occlusion;                /* occlusion 0 everywhere (skips its cost) */
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

/* ---- rendering (main thread; needs a gfx context) ---------------------------------------- */

/* Triplanar texturing with blend exponent 8 (000 §6), materials mixed by the vertices' weights,
 * bedrock tinted by height band and slope (002 §4.1), sun, sky ambient and fog, and shadows of
 * the sun from a cascaded shadow map (desc.shadows: off, low by default, high). Material
 * textures are generated procedurally when the renderer is made. Meshes are drawn
 * camera-relative (origins subtracted in double precision), so a view 100 km from the world's
 * origin renders exactly as one near it. */
typedef struct gfx_context gfx_context;
typedef struct terrain_renderer terrain_renderer;

/* Sun shadows: a cascaded shadow map over the near terrain (terrain_shadow.c; the README's
 * "Sun shadows" says what each costs). The meshes cast; the meshes and the far terrain receive. */
typedef enum terrain_shadow_quality {
    TERRAIN_SHADOWS_DEFAULT = 0,      /* low */
    TERRAIN_SHADOWS_OFF,              /* no shadow pass, nothing sampled */
    TERRAIN_SHADOWS_LOW,              /* 2 cascades of 1024² out to 50 m, one bilinear tap */
    TERRAIN_SHADOWS_HIGH,             /* 3 cascades of 2048² out to 300 m, 3 × 3 bilinear taps */
} terrain_shadow_quality;

/* Parses "off", "low" or "high" (--shadows); false for anything else. */
bool terrain_parse_shadow_quality(const char *text, terrain_shadow_quality *out);
const char *terrain_shadow_quality_name(terrain_shadow_quality quality);

typedef struct terrain_renderer_desc {
    float sea_level;                  /* for the shore band; 0 = 0 m */
    float snow_height;                /* 0 = 120 m */
    float fog_density;                /* per metre; 0 = 0.0025 */
    float cloud_cover;                /* 0 = 0.45; negative = a clear sky */
    bool no_occlusion;                /* ignore the vertices' openness (ambient occlusion off) */
    float detail_distance;            /* metres to which the 1 m detail layer (grains, cracks,
                                         pebbles) reaches, fading out over the second half;
                                         0 = 16 m; negative = the low quality: no detail layer
                                         and no 25 m scale blend (their fetches skipped; normal
                                         maps and the macro variation stay) */
    terrain_shadow_quality shadows;   /* 0 = low */
    bool sky_apart;                   /* terrain_renderer_draw leaves the sky out: the caller
                                         draws it with terrain_renderer_draw_sky (a system of its
                                         own); reflections keep theirs */
} terrain_renderer_desc;

/* NULL when the shaders do not build (their errors printed at file:line). */
terrain_renderer *terrain_renderer_create(gfx_context *gfx, const terrain_renderer_desc *desc);
void terrain_renderer_destroy(terrain_renderer *renderer);
/* Milliseconds terrain_renderer_create spent making the material textures (CPU and upload). */
double terrain_renderer_texture_ms(const terrain_renderer *renderer);

/* A mesh on the GPU. */
typedef struct terrain_gpu_mesh {
    gfx_buffer vertex_buffer, index_buffer;
    gfx_vertex_array vertex_array;    /* { 0 } for an empty mesh (nothing to draw) */
    uint32_t index_count;
    uint64_t serial;                  /* unique per upload: what was derived from a mesh (grass)
                                         knows when it changed */
    double origin[3];
    float bounds_min[3], bounds_max[3];
} terrain_gpu_mesh;

terrain_gpu_mesh terrain_gpu_mesh_upload(const terrain_mesh *mesh);
void terrain_gpu_mesh_destroy(terrain_gpu_mesh *mesh);

typedef struct terrain_view {
    double camera[3];                 /* world position of the eye */
    float yaw, pitch;                 /* radians; yaw 0 looks along −z, positive turns right */
    float fov_y;                      /* radians; 0 = 60° */
    float aspect;                     /* width / height */
    float far_distance;               /* 0 = 4000 m */
    float sun_direction[3];           /* towards the sun; 0 = a morning sun */
    float time;                       /* seconds; the clouds drift with it */
} terrain_view;

/* The view's projection × camera rotation (column-major, the camera at the origin: draw
 * camera-relative positions with it), and its unit sun direction (the default when unset): for
 * modules that draw into the terrain's frame (grass, water). */
void terrain_view_matrix(const terrain_view *view, float out[16]);
void terrain_view_sun(const terrain_view *view, float out[3]);

/* The view's frustum as six planes in camera-relative space, for culling mesh bounds. */
typedef struct terrain_frustum {
    float planes[6][4];               /* a·x + b·y + c·z + d ≥ 0 inside */
    double camera[3];
} terrain_frustum;

terrain_frustum terrain_frustum_from_view(const terrain_view *view);
/* Whether any part of the box origin + [bounds_min, bounds_max] may be inside (conservative:
 * boxes near a corner of the frustum may pass; a box that is seen never fails). */
bool terrain_frustum_sees(const terrain_frustum *frustum, const double origin[3], const float bounds_min[3],
                          const float bounds_max[3]);

/* Changes the shadows' quality (the map is made or freed now); false, shadows unchanged, when
 * the shadow map cannot be made (logged). */
bool terrain_renderer_set_shadows(terrain_renderer *renderer, terrain_shadow_quality quality);

/* Draws the meshes, then the sky behind them, inside one pass named "terrain". With shadows on,
 * a pass named "shadows" comes first: the sun's shadow map, cast by the meshes given to
 * terrain_renderer_draw_shadows since the last draw or else by these. */
void terrain_renderer_draw(terrain_renderer *renderer, const terrain_view *view,
                           const terrain_gpu_mesh *meshes, int mesh_count);
/* The sky alone, in a pass named "sky", behind what the bound framebuffer holds (its depth at
 * the far plane): after terrain_renderer_draw with desc.sky_apart. */
void terrain_renderer_draw_sky(terrain_renderer *renderer, const terrain_view *view);
/* The shadow pass for the next terrain_renderer_draw, cast by `casters`: every mesh on the GPU
 * near the view, not only those in it (a hill behind the camera shades the ground in front). Each
 * cascade draws those whose bounds reach its footprint. Nothing happens with shadows off. */
void terrain_renderer_draw_shadows(terrain_renderer *renderer, const terrain_view *view,
                                   const terrain_gpu_mesh *casters, int caster_count);

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

/* ---- far terrain: geometry clipmaps (002 §3.2, §3.5) ---- */

/* The terrain beyond the volumetric chunks, out to many kilometres: nested square grids of
 * cells×cells cells around the camera, level L's vertices finest_spacing·2^L apart, displaced by
 * heights kept in a toroidal array per level (GPU: one R32F texture layer per level) and
 * recomputed only where a level moved (Losasso & Hoppe's geometry clipmaps, 002 §3.2). The
 * heights are the generator's macro ground G (the stacks' top surface before the overhang shear
 * and the caves) with the octave count the level's spacing can carry (004 §4.1), so distant
 * levels do not alias. Each level's vertices morph towards the next coarser level's surface
 * near its border and meet it exactly there: no cracks between levels. Where the volumetric
 * chunks are drawn (terrain_clipmap_set_holes: one square per viewer's rings) the clipmap sinks
 * into a pit under them, deeper than any cave, whose walls skirt the chunks' open border:
 * whatever the mismatch between the two surfaces, a gap shows ground, never sky, from any side
 * (002 §3.5 bends the meso mesh to the clipmap instead; that would be the chunks' mesher's
 * work). The outermost level and the
 * far plane fade into the sky (002 §4.4), so the world has no visible end.
 *
 *     terrain_clipmap *far = terrain_clipmap_create(&(terrain_clipmap_desc){
 *         .generation = terrain_generation_defaults(42), .jobs = jobs });
 *     terrain_renderer_set_clipmap(renderer, far);
 *     each frame:
 *         terrain_clipmap_update(far, camera);                 // CPU: recentre, new heights
 *         terrain_clipmap_set_holes(far, volume_min, volume_max, n);  // where chunks are (x, z)
 *         terrain_frustum frustum = terrain_frustum_from_view(&view);
 *         terrain_clipmap_cull(far, &frustum);                 // CPU: visible blocks
 *         terrain_clipmap_upload(far);                         // main thread: changed texels
 *         terrain_renderer_draw(renderer, &view, meshes, count);  // meshes, clipmap, sky
 *     terrain_clipmap_destroy(far);                            // main thread (GL objects)
 *
 * With the defaults (6 levels of 128² cells from 4 m) the finest level covers 512 m around the
 * camera and the outermost 16 km (8 km each way); the far plane (terrain_view.far_distance,
 * 4 km by default) ends the view first. Threads: update, set_holes and cull are CPU work for any
 * one thread at a time, not while the clipmap is uploaded or drawn (update may fan out on
 * desc.jobs); upload, the draw and destroy use OpenGL: main thread. */
#define TERRAIN_CLIPMAP_MAX_LEVELS 12
#define TERRAIN_CLIPMAP_MAX_HOLES 8       /* one per viewer: TERRAIN_MAX_VIEWERS */

typedef struct job_system job_system;
typedef struct terrain_clipmap terrain_clipmap;

typedef struct terrain_clipmap_desc {
    int levels;                       /* nested levels; 0 = 6, at most TERRAIN_CLIPMAP_MAX_LEVELS */
    int cells;                        /* cells along each side of a level, a multiple of 16 (16 …
                                         1024); 0 = 128 */
    float finest_spacing;             /* metres between level 0's vertices; 0 = 4 */
    float hole_band;                  /* metres inside the hole's border over which the clipmap
                                         sinks (the pit's wall); 0 = 2·finest_spacing */
    float hole_depth;                 /* how deep it sinks (the pit's floor below the ground);
                                         0 = below the generator's caves (156 m by default) */
    terrain_generation_desc generation;  /* copied; the world whose ground is drawn */
    job_system *jobs;                 /* computes new heights in parallel; NULL = the caller */
    /* Detail from a screen-space error (above): with pixel_error > 0 the fields left 0 among
     * cells, finest_spacing and levels are derived from K = terrain_screen_error_scale(
     * viewport_height, fov_y, pixel_error): cells ≥ 4·(ε(s)/s·K + 2) (level L is drawn from
     * cells·s_L/4 out, less the camera's 2·s_L offset, and needs ε(s_L)·K), finest_spacing the
     * largest power of two (1 … 32 m) with ε(s)·K ≤ inner_distance, levels the fewest whose
     * outermost reaches 8192 m from its centre (as far as the defaults). */
    float pixel_error;                /* pixels; 0 = the fixed defaults */
    int viewport_height;              /* pixels; 0 = 720 */
    float fov_y;                      /* radians; 0 = 60° */
    float inner_distance;             /* metres from the camera that the volumetric rings cover
                                         surely (terrain_rings_clearance of their outermost level);
                                         0 = none, the finest spacing is then 1 m */
} terrain_clipmap_desc;

typedef struct terrain_clipmap_stats_info {
    int levels, cells;
    float finest_spacing;
    double reach;                     /* metres the outermost level reaches at least from the
                                         camera of the last update, along x and z */
    uint64_t texels_updated;          /* heights computed by the last terrain_clipmap_update */
    int blocks_visible;               /* blocks the last terrain_clipmap_cull kept */
    uint64_t triangles_visible;       /* in those blocks */
    int blocks_drawn;                 /* by the last draw */
    uint64_t triangles;               /* drawn by the last draw */
} terrain_clipmap_stats_info;

/* CPU only (no GL): the heights are computed on the first update. NULL never (bad fields are
 * clamped to their range, with a warning). */
terrain_clipmap *terrain_clipmap_create(const terrain_clipmap_desc *desc);
/* Frees the CPU data and, if terrain_clipmap_upload made any, the GL objects: main thread. */
void terrain_clipmap_destroy(terrain_clipmap *clipmap);
/* A new viewport height, field of view and inner distance for a desc with pixel_error (a resized
 * window, rings derived again): when the derived cells, finest spacing or levels change, the
 * levels are made anew (heights recomputed on the next update, GL objects remade on the next
 * upload: main thread, not while the clipmap is drawn); holes are kept. True when they changed. */
bool terrain_clipmap_set_screen(terrain_clipmap *clipmap, int viewport_height, float fov_y, float inner_distance);
/* Recentres the levels on the camera (world metres) and computes the heights that came into
 * them (all of them the first time or after a jump); returns how many. */
uint64_t terrain_clipmap_update(terrain_clipmap *clipmap, const double camera[3]);
/* The rectangles of the world (x, z in metres; hole h spans min_xz[h] … max_xz[h]) where the
 * volumetric chunks are drawn instead, typically one square per viewer's rings: inside a hole
 * the clipmap sinks, over desc.hole_band from its border, to desc.hole_depth below the ground
 * (hidden under the chunks). Where holes overlap, a point sinks by the deepest of their pits
 * there, so no wall rises inside the union where the overlap is at least 2·hole_band wide
 * (holes that only touch leave a ridge along the shared edge, rising to the ground). Put the
 * borders on level 0's vertex lines (multiples of finest_spacing: chunk borders are), else the
 * sinking starts up to a cell outside them. Replaces the previous holes; count is 0 …
 * TERRAIN_CLIPMAP_MAX_HOLES (more are clamped, with a warning); holes with min ≥ max on either
 * axis are left out. */
void terrain_clipmap_set_holes(terrain_clipmap *clipmap, const double (*min_xz)[2], const double (*max_xz)[2], int count);
/* One hole (terrain_clipmap_set_holes with count 1); min ≥ max on either axis (or NULL) = none. */
void terrain_clipmap_set_hole(terrain_clipmap *clipmap, const double min_xz[2], const double max_xz[2]);
/* Marks the blocks (each level is cut into 36) whose bounds the frustum may see, skipping those
 * a finer level covers; returns how many will be drawn. Without a cull since the last update
 * every uncovered block is drawn. */
int terrain_clipmap_cull(terrain_clipmap *clipmap, const terrain_frustum *frustum);
/* Main thread, with a GL context: makes the GL objects on the first call, then uploads the
 * heights that changed since the last call. The draw does it too when an update left heights
 * behind, so calling it is only a way to choose when the upload's time is spent. */
void terrain_clipmap_upload(terrain_clipmap *clipmap);
/* The ground height drawn at (x, z) by the finest level around it (its triangles, morphed as
 * for the camera of the last update; the hole's sinking not included); NAN outside every level
 * or before the first update. */
float terrain_clipmap_height(const terrain_clipmap *clipmap, double x, double z);
terrain_clipmap_stats_info terrain_clipmap_stats(const terrain_clipmap *clipmap);

/* terrain_renderer_draw draws the clipmap after the meshes and before the sky (NULL = none);
 * the clipmap is not owned and must outlive its use here. */
void terrain_renderer_set_clipmap(terrain_renderer *renderer, terrain_clipmap *clipmap);
/* Turns the vertices' ambient occlusion on or off from the next draw (as the desc's
 * no_occlusion; for comparisons and benchmarks). */
void terrain_renderer_set_occlusion(terrain_renderer *renderer, bool on);

/* ---- in the ECS --------------------------------------------------------------------------- */

/* Column chunks and mesh chunks are entities. Systems (registered by terrain_ecs_create):
 *   generate  "terrain_generate"  TerrainChunk without stacks → stacks (parallel)
 *   mesh      "terrain_mesh"      TerrainMeshChunk waiting → field + marching cubes (parallel)
 *   cull      "terrain_cull"      meshed TerrainMeshChunk → visible in the view? (parallel)
 *   draw      "terrain_upload"    meshed TerrainMeshChunk → GPU (main thread)
 * terrain_ecs_draw then draws every uploaded mesh chunk and trims the world's cache (call it
 * outside ecs_progress, on the main thread). */
typedef struct ecs_world ecs_world;
typedef uint32_t ecs_component;                /* as ecs.h's (C11 allows the same typedef twice) */

typedef struct TerrainChunk {
    terrain_chunk_coord coord;
    const terrain_stacks *stacks;        /* NULL until the generate phase has run; after an edit
                                            the stabilize phase points it at the new stacks */
} TerrainChunk;

/* TERRAIN_MESH_CELLS³ cells of the sample grid; (x, y, z) counts mesh chunks. */
#define TERRAIN_MESH_CELLS 32

typedef enum terrain_mesh_state {
    TERRAIN_MESH_WAITING,               /* to be meshed */
    TERRAIN_MESH_MESHED,                /* CPU mesh ready, not uploaded */
    TERRAIN_MESH_UPLOADED,              /* on the GPU (the CPU copy is freed) */
} terrain_mesh_state;

typedef struct WaterPlane WaterPlane;   /* "water planes", at the end */

typedef struct TerrainMeshChunk {
    int64_t x, y, z;                    /* in chunks of its level */
    terrain_lod_desc lod;               /* level and finer neighbours (terrain_mesh_chunk) */
    terrain_mesh_state state;
    bool visible;                       /* in the view's frustum (cull phase) */
    bool hidden;                        /* streaming: out of range and replaced, not drawn */
    terrain_mesh mesh;                  /* the newest mesh until uploaded */
    terrain_gpu_mesh gpu;               /* drawn; an older one stays until its successor is up */
    size_t gpu_bytes;
    bool edited;                        /* meshed again after an edit: uploaded this frame,
                                           whatever the upload budget */
    WaterPlane *water;                  /* the water surfaces found with the newest mesh (NULL =
                                           none; owned): the upload copies them into the
                                           entity's WaterPlane component */
} TerrainMeshChunk;

typedef struct terrain_ecs terrain_ecs;
typedef struct terrain_ecs_stats_info {
    int chunks, chunks_generated;
    int mesh_chunks, mesh_chunks_waiting, mesh_chunks_uploaded;
    uint64_t triangles;
} terrain_ecs_stats_info;

typedef struct terrain_ecs_desc {
    ecs_world *ecs;                   /* required: the world the components and systems go on */
    terrain_world *terrain;           /* required: the stacks they read and write (not owned) */
} terrain_ecs_desc;
/* Registers the components and systems on desc->ecs; NULL (message logged) without .ecs or
 * .terrain. */
terrain_ecs *terrain_ecs_create(const terrain_ecs_desc *desc);
/* Destroys the mesh-chunk entities; TerrainMeshChunk's on_remove hook frees their meshes (GPU
 * ones too: call on the main thread, with the context), as it does for any other removal. */
void terrain_ecs_destroy(terrain_ecs *te);
/* Spawns the column chunks within `radius` chunks of (cx, cz) and their mesh chunks for mesh
 * layers y_first … y_last (each TERRAIN_MESH_CELLS metres tall). */
void terrain_ecs_spawn_area(terrain_ecs *te, int64_t cx, int64_t cz, int radius, int64_t y_first, int64_t y_last);
/* Nested rings of detail around the origin: level 0 covers mesh chunks x, z ∈ [−w, w) (w =
 * half_width, even when levels > 1), and each coarser level L covers its own chunks in [−w, w)
 * but not the finer area inside, so level L reaches w·32·2^L metres out. Seams between levels
 * are closed (terrain_mesh_chunk). All levels cover [y_min, y_max] rounded out to the coarsest
 * chunk height. Column-chunk entities are spawned for the level-0 area. */
void terrain_ecs_spawn_rings(terrain_ecs *te, int half_width, int levels, double y_min, double y_max);
/* ---- streaming ----------------------------------------------------------------------------
 *
 * Instead of a fixed area, chunks follow viewers (the player, a second camera):
 *     terrain_ecs_stream(te, &(terrain_stream_desc){ .half_width = 2, .levels = 3,
 *                                                   .y_min = -200, .y_max = 240 });
 *     each frame:  terrain_ecs_set_viewers(te, &eye, 1);  ecs_progress(ecs, dt);  terrain_ecs_draw(...)
 *
 * Around each viewer the mesh chunks form nested rings as terrain_ecs_spawn_rings's, centred on
 * the viewer snapped to the coarsest level's chunk grid; the union over viewers is kept, each
 * place at the finest level any viewer wants there (levels of touching chunks then differ by at
 * most one, as the seams need). Systems, all on the main thread and cheap:
 *   stream    "terrain_stream"    re-centres the rings when a viewer crosses a chunk line:
 *                                 creates the chunks that came into range, cancels work for
 *                                 those that left, keeps their meshes while memory allows
 *   generate  "terrain_stream_generate"  column chunks around each viewer (collision_radius)
 *                                 generated by background jobs, then retained
 *   mesh      "terrain_stream_mesh"      mesh jobs in flight kept topped up, nearest and in-view
 *                                 first; finished ones collected
 *   draw      "terrain_upload"    at most upload_budget_ms of GPU uploads and frees a frame
 * Generation and meshing run as background jobs (jobs.h), so they span frames and a frame never
 * waits for them. A mesh chunk whose samples cannot reach any interface of its column chunks
 * (terrain_stacks_interface_range) is empty without being sampled. */
typedef struct terrain_stream_desc {
    int half_width;                   /* level-0 mesh chunks each way from the viewer; 0 = 2, or
                                         with pixel_error terrain_rings_half_width(levels, K) */
    int levels;                       /* rings of detail (level 0 included); 0 = 3 */
    float pixel_error;                /* screen-space error target τ in pixels ("detail from a
                                         screen-space error"); 0 = none: the fixed rings above.
                                         Only a half_width of 0 is derived; levels stay as given */
    int viewport_height;              /* pixels, for pixel_error; 0 = 720. The window's size
                                         changes: terrain_ecs_stream_set_screen */
    float fov_y;                      /* radians, for pixel_error; 0 = 60° */
    double y_min, y_max;              /* metres the mesh layers cover. Equal (the default):
                                         the generation parameters' base ± relief ± 48 m at
                                         first, then grown (never shrunk) to reach every
                                         interface of the column chunks generated or edited,
                                         so no peak or tower is cut off. Given: exactly that */
    int collision_radius;             /* column chunks each way kept generated; 0 = 2 */
    float upload_budget_ms;           /* main-thread GPU uploads and frees a frame; 0 = 2 ms */
    size_t memory_budget;             /* bytes of stacks and meshes kept (CPU + GPU); 0 = 384 MB */
    int max_jobs;                     /* background jobs in flight; 0 = 2 per worker, at least 2 */
} terrain_stream_desc;

#define TERRAIN_MAX_VIEWERS 8

/* Turns streaming on (call once, before the first frame; spawned areas stay as they are). */
void terrain_ecs_stream(terrain_ecs *te, const terrain_stream_desc *desc);
/* A new viewport height and field of view (a resized window) for a desc with pixel_error: the
 * half width is derived again and, if it changed, the rings are laid out anew on the next frame
 * (what left them stays drawn until replaced, as when walking). No effect without pixel_error. */
void terrain_ecs_stream_set_screen(terrain_ecs *te, int viewport_height, float fov_y);
/* The desc streaming runs with: defaults filled in, half_width derived (terrain_ecs_stream). */
terrain_stream_desc terrain_ecs_stream_desc(terrain_ecs *te);
/* Where the viewers' eyes are (world metres; copied; at most TERRAIN_MAX_VIEWERS). */
void terrain_ecs_set_viewers(terrain_ecs *te, const double (*eyes)[3], int count);
/* Whether every column chunk the field reads inside [min, max] (plus the kernel) is generated:
 * the player's region_ready hook (game/player.h). Never generates anything. */
bool terrain_ecs_region_ready(terrain_ecs *te, const double min[3], const double max[3]);

/* The terrain's resource (ecs.h, RESOURCES): this terrain_ecs, whose state (streaming, editing,
 * the view) its systems declare through it. A system of yours that calls terrain_ecs functions
 * names it in its reads (stats, region checks) or writes (edits, viewers, the view). */
ecs_component terrain_ecs_resource(const terrain_ecs *te);

typedef struct terrain_ecs_stream_stats_info {
    int mesh_chunks_wanted;           /* in the viewers' rings */
    int mesh_chunks_ready;            /* of those, drawn or empty */
    int mesh_chunks_kept;             /* out of range, kept while memory allows */
    int jobs_in_flight;
    uint64_t chunks_meshed, chunks_skipped_empty, chunks_cancelled, chunks_evicted;
    size_t resident_bytes, peak_resident_bytes;   /* stacks cached + CPU and GPU meshes */
    size_t stacks_bytes;              /* of resident_bytes: the column chunks' stacks cached */
    size_t cpu_mesh_bytes;            /* meshes made and not uploaded yet */
    size_t gpu_mesh_bytes;            /* meshes uploaded (their vertex and index buffers) */
} terrain_ecs_stream_stats_info;
terrain_ecs_stream_stats_info terrain_ecs_stream_stats(terrain_ecs *te);
/* Far terrain (after terrain_ecs_stream; the clipmap is not owned): the lod phase
 * ("terrain_clipmap") re-centres it on viewer 0 and sinks it under the squares every viewer's
 * rings cover (one hole each, duplicates dropped; terrain_clipmap_set_holes) once all their
 * chunks are in, keeping the previous squares until then; the cull phase
 * ("terrain_clipmap_cull") culls its blocks against the view. Give the renderer the same
 * clipmap (terrain_renderer_set_clipmap). */
typedef struct terrain_clipmap terrain_clipmap;
void terrain_ecs_set_clipmap(terrain_ecs *te, terrain_clipmap *clipmap);

/* The view the cull phase tests against (copied); NULL = no culling, every chunk is drawn. */
void terrain_ecs_set_view(terrain_ecs *te, const terrain_view *view);
/* Draws the uploaded chunks the cull phase found visible. */
void terrain_ecs_draw(terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view);
terrain_ecs_stats_info terrain_ecs_stats(terrain_ecs *te);


/* ---- editing: columns, stabilization, brushes (000 §3.4, §4) ---- */

/* Editing works on a mutable copy of some columns, a terrain_columns region: any W × D columns
 * (one chunk, or several), thicknesses in integer quanta so that every edit conserves the mass
 * of each material exactly. Brushes drop sand or rocks (000 §4.3) or turn bedrock into them
 * (§4.4); stabilization then moves sand and rocks down slopes steeper than their angle of
 * repose (§3.4), a little per iteration, until nothing moves or the call's budget is spent.
 *
 *     terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
 *         .x = 0, .z = 0, .width = 64, .depth = 64 });           // chunks (0,0) … (1,1)
 *     for (int n = 0; n < 4; n++) terrain_columns_load(region, chunks[n], stacks[n]);
 *     terrain_deposit(region, &(terrain_deposit_desc){ .x = 32, .z = 32, .radius = 8,
 *                                                      .volume = 500 }, NULL);    // sand
 *     terrain_stabilize_result result;
 *     terrain_stabilize_region(region, &(terrain_stabilize_desc){ .budget_ns = 2000000 },
 *                              jobs, &result);                   // again next frame until
 *                                                                // result.converged
 *     terrain_chunk_coord changed[4];
 *     int n = terrain_columns_changed_chunks(region, changed, 4, true);
 *     for (int c = 0; c < n; c++) replace(changed[c], terrain_columns_to_stacks(region, changed[c]));
 *     terrain_columns_destroy(region);
 *
 * Layer order (000 §3.4): between two stable layers (bedrock, or a custom material) granular
 * material is merged and sorted sand, rocks, water, air — what lies over a cave falls to its
 * floor. Only the pile above a column's highest stable layer flows; sand and rocks on a cave's
 * floor stay there (a cave roof holds what lies on it). Stabilization moves each material on its
 * own surface, bottom layer first (sand on the sand surface, rocks on the ground), so a stable
 * column has no neighbour lower than d·tan(angle) + tolerance below either surface, d the
 * distance between column centres (1 m, or √2 m diagonally).
 *
 * Determinism: an iteration is nine passes, one per colour of a 3 × 3 pattern of columns (by
 * world column index); columns of one colour are three apart, so their moves never touch the
 * same column and a pass can move them all at once, in integer quanta. The result does not
 * depend on the thread count, on how a pass is split into jobs, or on how the columns are split
 * into regions (terrain_stabilize_regions), and a call that stops on its budget continues exactly
 * where it stopped. Only columns next to a change are looked at: edits (brushes,
 * terrain_columns_set, terrain_columns_touch) are changes, and so is every moved quantum.
 *
 * Threads: a region is plain data; one call at a time on it. Errors (a bad size, NaN, an unknown
 * material) return false or NULL with a message logged, never a crash. */

typedef struct job_system job_system;

typedef struct terrain_columns terrain_columns;

typedef struct terrain_columns_desc {
    int64_t x, z;                     /* world column index of the first column (chunk c's first
                                         column is c·TERRAIN_CHUNK_COLUMNS) */
    int width, depth;                 /* columns along x and z: 1 … 4096, at most 2^22 in all */
} terrain_columns_desc;

/* Every column empty (only the implicit bedrock below the floor). NULL (message logged) for a
 * bad size. Free with terrain_columns_destroy. */
terrain_columns *terrain_columns_create(const terrain_columns_desc *desc);
void terrain_columns_destroy(terrain_columns *columns);
terrain_columns_desc terrain_columns_extent(const terrain_columns *columns);

/* Copies the chunk's columns that lie in the region over the region's (not marked for
 * stabilization; columns out of order are sorted by the next stabilization). False (message
 * logged) when the chunk does not overlap the region or a column is absurdly tall. */
bool terrain_columns_load(terrain_columns *columns, terrain_chunk_coord coord, const terrain_stacks *stacks);
/* The chunk's columns as stacks (an unedited chunk comes back byte for byte); the chunk must lie
 * inside the region, else NULL (message logged). Free with terrain_stacks_destroy. */
terrain_stacks *terrain_columns_to_stacks(const terrain_columns *columns, terrain_chunk_coord coord);

/* Column (i, k) of the region (0 ≤ i < width, 0 ≤ k < depth), bottom-up from TERRAIN_FLOOR_Y,
 * adjacent equal materials merged; returns the count (writes at most `capacity`), −1 for a
 * column outside the region. */
int terrain_columns_get(const terrain_columns *columns, int i, int k, terrain_layer *layers, int capacity);
/* Replaces column (i, k) by `layers` (bottom-up; thicknesses rounded to the quantum by their
 * cumulative heights, as the stacks builder does) and marks it changed. False (message logged,
 * column unchanged) for a column outside the region, an unknown material, or a thickness that is
 * negative, NaN or too large. */
bool terrain_columns_set(terrain_columns *columns, int i, int k, const terrain_layer *layers, int count);
/* Top of the highest layer that is not air or water (as terrain_stacks_top). */
float terrain_columns_top(const terrain_columns *columns, int i, int k);
/* Volume of `material` in the region, in quanta·column (1/32 m³). */
int64_t terrain_columns_mass(const terrain_columns *columns, terrain_material material);
/* Marks columns [i0, i1) × [k0, k1) (clipped to the region) changed, so that the next
 * stabilization looks at them — e.g. every column of a freshly generated chunk. */
void terrain_columns_touch(terrain_columns *columns, int i0, int k0, int i1, int k1);
/* The chunks with a column whose content changed (edits, sorting, stabilization) since the last
 * clear, in z-major order; returns how many there are (writes at most `capacity`). With `clear`
 * the record starts afresh. A remesh must also take the neighbours the field's kernel reaches. */
int terrain_columns_changed_chunks(terrain_columns *columns, terrain_chunk_coord *out, int capacity, bool clear);

/* ---- stabilization (000 §3.4) ---- */

typedef enum terrain_stabilize_edge {
    TERRAIN_EDGE_WALL,                /* beyond the regions nothing exists: nothing flows there */
    TERRAIN_EDGE_WAKE,                /* stop before a pass that needs columns beyond the regions
                                         and name their regions in result.woken; add them and call
                                         again (at the world's end, call with WALL instead) */
} terrain_stabilize_edge;

typedef struct terrain_stabilize_desc {
    float sand_angle;                 /* degrees of repose, 0 < angle < 90; 0 = 33 (000: 30–35) */
    float rocks_angle;                /* 0 = 42 (000: 40–45) */
    float step;                       /* metres a column gives away per material and look at most
                                         (000 §3.4's "small constant amount a"; it also never gives
                                         more than levels it with its neighbours); rounded to the
                                         quantum, at least one; 0 = 1 m */
    float tolerance;                  /* metres a slope may exceed d·tan(angle) by; 0 = none */
    int max_iterations;               /* per call (an iteration looks at every column once);
                                         0 = no limit */
    uint64_t budget_ns;               /* per call, checked between passes once an iteration has
                                         run; 0 = no limit. For a world that is a pure function of
                                         its edit log, budget in iterations: where a time budget
                                         stops depends on the machine */
    terrain_stabilize_edge edge;
} terrain_stabilize_desc;

#define TERRAIN_STABILIZE_MAX_WOKEN 32

typedef struct terrain_stabilize_result {
    bool converged;                   /* nothing left to move: the regions are stable */
    int iterations;                   /* run by this call */
    int64_t moved;                    /* quanta·column moved between columns by this call */
    /* Regions missing beyond the edge where material reached it (WALL) or is about to cross it
     * (WAKE: add them and call again), as grid coordinates in units of the region size —
     * chunk coordinates for regions of one chunk. woken_count may exceed the array. */
    int woken_count;
    terrain_chunk_coord woken[TERRAIN_STABILIZE_MAX_WOKEN];
} terrain_stabilize_result;

/* Stabilizes the region (its border is the edge). jobs may be NULL (one thread); the result is
 * the same for any thread count. False (message logged, nothing changed) for bad parameters. */
bool terrain_stabilize_region(terrain_columns *columns, const terrain_stabilize_desc *params, job_system *jobs,
                              terrain_stabilize_result *result);
/* Stabilizes regions side by side as one: material flows across their borders, and the outcome
 * equals that of a single region covering them all (same iterations, same bytes). The regions
 * must have one size and lie on the grid of that size (origins multiples of it apart), e.g. one
 * per chunk; the edge is where no region continues. False (message logged) for bad parameters,
 * unequal sizes, misaligned or repeated regions. */
bool terrain_stabilize_regions(terrain_columns *const *regions, int count, const terrain_stabilize_desc *params,
                               job_system *jobs, terrain_stabilize_result *result);

/* ---- brushes (000 §4.3, §4.4) ---- */

typedef enum terrain_falloff {
    TERRAIN_FALLOFF_DEFAULT = 0,      /* smooth */
    TERRAIN_FALLOFF_SMOOTH,           /* (1 − r²/R²)², 000 §4.1's g(r) */
    TERRAIN_FALLOFF_FLAT,             /* the same everywhere inside R */
} terrain_falloff;

/* What a brush adds, as a desc names it. Zero is the tool's default (CONVENTIONS.md: no zero is
 * also a real value), so these are not terrain_material's values: the stored material (bytes in
 * stacks and edit files) stays as it is; each tool maps these onto it. */
typedef enum terrain_brush_material {
    TERRAIN_BRUSH_DEFAULT = 0,        /* the tool's own: sand for a deposit, bedrock for a sculpt */
    TERRAIN_BRUSH_BEDROCK,
    TERRAIN_BRUSH_SAND,
    TERRAIN_BRUSH_ROCKS,
} terrain_brush_material;

/* Drops `volume` m³ of sand or rocks on the columns whose centres lie within `radius` of (x, z)
 * (world metres), distributed by the falloff and rounded so that the total is exact (to the
 * quantum·column): a brush that overhangs the region's border puts it all on the columns inside.
 * It lands on each column's pile (sorted: sand goes under rocks, both under water). */
typedef struct terrain_deposit_desc {
    terrain_brush_material material;  /* TERRAIN_BRUSH_SAND or _ROCKS; 0 = sand */
    double x, z;
    float radius;                     /* metres, > 0 */
    double volume;                    /* m³, ≥ 0 */
    terrain_falloff falloff;
} terrain_deposit_desc;

typedef enum terrain_erode_mode {
    TERRAIN_ERODE_DEFAULT = 0,        /* surface */
    TERRAIN_ERODE_SURFACE,            /* each column under the disc whose highest stable layer is
                                         bedrock loses depth·falloff from its top */
    TERRAIN_ERODE_COLLAPSE,           /* all bedrock inside the ball of radius R around (x, y, z)
                                         turns granular; with what lay on it, it falls to the next
                                         stable layer below (bedrock above stays: it is stable) */
} terrain_erode_mode;

/* Turns bedrock into granular material where the tool reaches (000 §4.4): a share rocks_ratio
 * (ρ) of it into rocks, the rest into sand, exactly (per column, bedrock quanta removed = sand +
 * rocks quanta added). The material stays in its column until stabilization moves it. */
typedef struct terrain_erode_desc {
    terrain_erode_mode mode;
    double x, y, z;                   /* centre, world metres (y: collapse only) */
    float radius;                     /* metres, > 0 */
    float depth;                      /* surface: metres eroded at the centre, ≥ 0 */
    float rocks_ratio;                /* ρ ∈ [0, 1]; 0 = all sand */
    terrain_falloff falloff;          /* surface only */
} terrain_erode_desc;

/* Both return false (message logged, region unchanged) for bad parameters or a deposit that
 * misses the region; `quanta` (may be NULL) receives the quanta·column deposited or eroded.
 * Changed columns are marked for the next stabilization. */
bool terrain_deposit(terrain_columns *columns, const terrain_deposit_desc *desc, int64_t *quanta);
bool terrain_erode(terrain_columns *columns, const terrain_erode_desc *desc, int64_t *quanta);

/* ---- sculpting and sweeping (000 §4.1, §4.2), picking ---- */

/* Sculpt (000 §4.1): a point primitive f*(p) = g(|p − c|), g(r) = (1 − r²/R²)² inside R, is
 * blended into the field — fe = f + f* to add, fe = f − f* to carve — with its centre δ inside
 * the surface to add (c = v − δn) or outside to carve (c = v + δn), v the target moved onto the
 * surface f = 0 along the field's normal n = −∇f/|∇f| (which points into the air), at most half a
 * metre. The columns under the ball are rebuilt along their central axes: over the ball's chord,
 * the signs of f and fe are sampled and their roots bisected to the height quantum (a quantum is
 * solid where the field at its centre is > 0). Only the quanta the edit flips change, so a column
 * stays exactly as it was wherever the edit does not change the field's sign (the ball's rim,
 * above and below): adding turns the air and water where f ≤ 0 < fe into `material` (solid that
 * is there keeps its kind), carving turns everything where fe ≤ 0 < f into air. A flipped stretch
 * takes along the column's own quanta next to it that the field does not see — air over which
 * added material would float (fe > 0), bedrock that would float over a carved gap (fe ≤ 0) — so
 * no edit leaves a hidden sliver or gap. Granular material left over a carved span stays until
 * stabilization.
 *
 *     terrain_ray_hit hit;
 *     if (terrain_raycast(world, eye, forward, 64, &hit))
 *         terrain_sculpt(region, &(terrain_sculpt_desc){ .target = { hit.position[0], … },
 *                                                        .radius = 3, .carve = true }, NULL);
 *
 * The field is computed from the region's own columns (a snapshot taken before anything is
 * written), so the region must hold every column within R + δ + 2 metres of the target along x
 * and z (the ball's centre may lie δ to the side on a wall; the field reads a column beyond the
 * ball) — a region of whole chunks around it; terrain_world_edit does this. False (message
 * logged, region unchanged) for bad parameters (NaN, R outside (0, 32], an offset outside
 * [0, 1], a material other than bedrock or sand), a region without that margin, or a target
 * with no surface within half a metre (the field is flat there). `changed` (may be NULL)
 * receives how many columns changed; only those are marked for stabilization and reported by
 * terrain_columns_changed_chunks. */
typedef struct terrain_sculpt_desc {
    double target[3];                 /* v: a point on the surface or within ½ m of it (world
                                         metres; y within the floor − 64 … floor + 2^20) */
    float radius;                     /* R, metres, 0 < R ≤ 32 */
    float offset;                     /* δ / R, 0 … 1; 0 = 0.5 (000: δ = R/2 works well) */
    bool carve;                       /* false: add material; true: carve it away */
    terrain_brush_material material;  /* what added material is: TERRAIN_BRUSH_BEDROCK or _SAND
                                         (in the field); 0 = bedrock */
} terrain_sculpt_desc;

bool terrain_sculpt(terrain_columns *columns, const terrain_sculpt_desc *desc, int64_t *changed);

/* Sweep (000 §4.2): carves the union of swept balls around a graph of segments — a tunnel, a
 * crack, a ravine, a cave network — as fe = min(f, −f*): everything within the profile radius
 * of the skeleton becomes air, exactly (no surface projection: the graph is where it is). The
 * radius is interpolated linearly along each segment from its end points' radii (a segment's
 * volume is the convex hull of its two end balls). Columns are rebuilt along their axes by the
 * roots of fe as for sculpting: a quantum whose centre lies inside the volume becomes air,
 * whatever it held; outside the volume the layers stay as they were. Granular material above a
 * carved span stays where it is until stabilization lets it fall. Same region rule as
 * terrain_sculpt: every column within the largest radius + 2 metres of the skeleton (its
 * bounding box grown by that). False (message logged, region unchanged) for bad parameters:
 * no points, a count out of range, a NaN point, a radius outside (0, 32], a segment naming a
 * point that does not exist. `changed` (may be NULL) receives how many columns changed. */
typedef struct terrain_sweep_desc {
    const double (*points)[3];        /* skeleton vertices, world metres */
    const float *radii;               /* per vertex, metres, 0 < r ≤ 32; NULL = `radius` for all */
    int point_count;                  /* 1 … 4096 (1: a ball) */
    const int (*segments)[2];         /* pairs of vertex indices (equal: a ball); NULL = the
                                         polyline 0-1-2-… */
    int segment_count;                /* with segments: 1 … 16384; ignored without */
    float radius;                     /* when radii is NULL */
} terrain_sweep_desc;

bool terrain_sweep(terrain_columns *columns, const terrain_sweep_desc *desc, int64_t *changed);

/* Picking: the first point along the ray where the field f crosses from air to solid (what the
 * mesh shows; water is not in the field, so a ray goes through it to the ground), within
 * max_distance metres; marches terrain_field_at in steps of at most half a metre and bisects the
 * crossing. A feature the field shows over less than half a metre of the ray may be missed. An
 * origin already inside (f > 0) is a hit at distance 0 there. The direction need not be unit
 * length. Generates the chunks it reads. Thread-safe as terrain_world_stacks. False (message
 * logged) for a NaN or zero direction, a NaN origin or max_distance outside (0, 100000]; false
 * without a message for a miss. `hit` may be NULL. */
typedef struct terrain_ray_hit {
    double position[3];
    float normal[3];                  /* unit, into the air (−∇f / |∇f|, central differences ½ m
                                         apart); −direction where the field is flat (deep inside) */
    float distance;                   /* metres from the origin along the unit direction */
    terrain_material material;        /* of the column layer just inside the surface: the first
                                         sand or bedrock within 1 m along −normal, else what is at
                                         the hit */
} terrain_ray_hit;

bool terrain_raycast(terrain_world *world, const double origin[3], const float direction[3], float max_distance,
                     terrain_ray_hit *hit);

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

/* ---- edits in the world ----
 *
 * With terrain_world_desc.edits set, the world replays a chunk's log whenever it generates the
 * chunk, and terrain_world_commit records what changes. A tool applied to the world:
 *
 *     terrain_chunk_coord changed[16];
 *     int n = terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
 *                                 .sculpt = { .target = { x, y, z }, .radius = 3 } },
 *                                changed, 16);
 *
 * loads a region of the chunks the tool reaches (with the field's margin), applies the tool
 * there and commits each changed chunk. Stabilization is separate (terrain_ecs does it on the
 * chunks that changed, a few iterations a frame). */
typedef struct terrain_edit {
    terrain_edit_tool tool;           /* SCULPT_ADD/CARVE, SWEEP, DEPOSIT or ERODE */
    terrain_sculpt_desc sculpt;       /* for SCULPT_* (carve is set from the tool) */
    terrain_sweep_desc sweep;
    terrain_deposit_desc deposit;
    terrain_erode_desc erode;
} terrain_edit;

/* The sea after edits (000 §4: "carving below sea level next to the sea lets the sea in: no dry
 * hole below the water line"). Generation fills the air above each column's highest solid layer
 * up to sea_level with water; edits keep that rule, as a water table at sea level: every column
 * an edit or stabilization changed whose highest solid (sand, rocks, bedrock) lies below
 * sea_level gets water from there exactly up to sea_level — air in that span becomes water, and
 * water of that run above sea_level goes (added material displaced it: it flows off into the
 * sea). Columns whose highest solid is at or above sea_level keep their water as it is (lakes).
 * Added material displaces water everywhere (lakes too): a deposit lowers the water standing on
 * the pile by as much as the pile rises, and a stabilization commit caps the water on a changed
 * column at the surface the column had before (sand that slid under water pushes it out).
 * The rule is applied where the change is committed (terrain_world_edit, and the stabilize
 * phase's commits), column by column from the column alone, so it keeps every determinism
 * invariant (same bytes whatever the thread count or region split; the edit log records the
 * flooded columns, so a replay gives the same bytes). Water is not conserved — it comes from and
 * goes to the sea — while sand and rocks still are, exactly. Worlds with `generate` set have the
 * sea only with terrain_world_desc.sea. */

/* Applies the edit; returns how many chunks changed (their coordinates in `changed`, at most
 * `capacity` written), or −1 (message logged, nothing changed) for a bad edit. Main thread,
 * between frames' jobs (it replaces cached stacks; see terrain_world_commit). */
int terrain_world_edit(terrain_world *world, const terrain_edit *edit, terrain_chunk_coord *changed, int capacity);
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

/* ---- editing in the ECS ----
 *
 * A running world (terrain_ecs) edits through a queue:
 *     terrain_ecs_edit(te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
 *                                           .deposit = { .x = x, .z = z, .radius = 4, .volume = 20 } });
 * In the next frame's stabilize phase ("terrain_stabilize", main thread) queued edits are
 * applied (terrain_world_edit) and the chunks they changed are stabilized (000 §3.4) as jobs,
 * a budget's worth a frame, continuing over the next frames until nothing moves; material that
 * reaches a chunk's border wakes the chunk beyond, so a slide crosses any number of chunks.
 * Whatever changed is committed to the world (and its log) each frame. In the mesh phase every
 * mesh chunk that reads a changed chunk is meshed again — streamed ones at once, as the frame's
 * own jobs, and uploaded whatever the upload budget — so a stroke is drawn in the frame its
 * edit is applied. Changes committed to the world by other code are remeshed the same way. */
typedef struct terrain_editing_desc {
    terrain_stabilize_desc stabilize;   /* angles, step, tolerance; budget_ns per frame (0 with
                                             max_iterations 0 = 2 ms); the edge is always WAKE */
    int max_regions;                      /* chunks stabilized at once; 0 = 256 (beyond, the
                                             border holds like a wall, with a warning) */
} terrain_editing_desc;

typedef struct terrain_ecs_edit_stats_info {
    int queued;                           /* edits waiting for the next stabilize phase */
    int stabilizing_chunks;               /* chunks not yet stable */
    uint64_t edits_applied, edits_refused;
    uint64_t iterations;                  /* of stabilization, in all */
    uint64_t chunks_committed;            /* by stabilization */
    double last_frame_ms;                 /* the stabilize phase's cost, the last frame it had work */
} terrain_ecs_edit_stats_info;

/* Queues the edit (copied, sweep arrays too); false (message logged) for a tool that is not a
 * brush or a sweep without points. */
bool terrain_ecs_edit(terrain_ecs *te, const terrain_edit *edit);
void terrain_ecs_set_editing(terrain_ecs *te, const terrain_editing_desc *settings);
terrain_ecs_edit_stats_info terrain_ecs_edit_stats(terrain_ecs *te);

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

/* ---- drawing water (terrain_water.c; 002 §3.4, 004 §4.3) ----------------------------------
 *
 * The sea (one plane at the generation's sea_level, out to the view's far distance, so it
 * reaches the horizon beyond the far terrain) and the lakes (the WaterPlane components whose
 * height is above the sea's), drawn over the opaque frame:
 *
 *     terrain_water *water = terrain_water_create(&(terrain_water_desc){
 *         .gfx = gfx, .ecs = ecs, .world = world, .quality = TERRAIN_WATER_LOW });
 *     each frame:
 *         terrain_ecs_draw(te, renderer, &view);       // ground, far terrain, sky
 *         grass_draw(grass, &view);                    // everything opaque first
 *         terrain_water_draw(water, te, renderer, &view);
 *     terrain_water_destroy(water);                    // main thread, before gfx_context_destroy
 *
 * Low (the default: no extra scene pass, for llvmpipe): the opaque frame's colour and depth are
 * copied to textures, and each surface samples them. Refraction is the copy at a position
 * distorted by a dudv map, masked by depth: where the scene at the distorted position lies in
 * front of the surface (something above the water), the undistorted position is used, so
 * nothing above the water leaks into it and the shore has no halo. Reflection is the sky along
 * the reflected ray (as sky.frag draws it) plus the sun's highlight on a scrolling normal map.
 * High: the sea's reflection comes from a pass of its own (the camera mirrored about the sea,
 * what lies under it clipped, half resolution; pass "water.reflection"), and its refraction
 * from another (what lies above it clipped, half resolution; "water.refraction"); lakes keep
 * the low path. A Schlick Fresnel term blends the two; the thickness of water along the view
 * ray (from the scene's depth) darkens and greens deep water, keeps shallow water clear and
 * less reflective, and fades the surface out towards the shore (no hard line). Below the
 * surface (terrain_world_water_at at the camera) the surface is seen from underneath (total
 * internal reflection past the critical angle) and a water fog tints the frame. The surfaces
 * are drawn in a pass named "water". While no water shows (an occlusion query of the previous
 * frame: all of it behind hills or out of view), the surfaces are only probed, depth-tested
 * with no colour, and nothing is copied or shaded; water that comes into view appears a frame
 * later. Off: nothing drawn, no cost. A lake's plane covers the
 * cells of its row mask and one cell around them (the ground and the shore's fade draw the
 * waterline there, not the cells' square edges). Lakes beyond the volumetric rings are the far
 * terrain's own (its clipmap stands their surface at the lake's level and shades it with the
 * same optics, without maps), drawn whatever the quality, as its sea tint is. */
typedef enum terrain_water_quality {
    TERRAIN_WATER_DEFAULT = 0,        /* low */
    TERRAIN_WATER_OFF,                /* nothing drawn */
    TERRAIN_WATER_LOW,                /* the frame's copy refracted; the sky reflected */
    TERRAIN_WATER_HIGH,               /* the sea's reflection and refraction passes */
} terrain_water_quality;

/* Parses "off", "low" or "high" (--water); false for anything else. */
bool terrain_water_parse_quality(const char *text, terrain_water_quality *out);
const char *terrain_water_quality_name(terrain_water_quality quality);

/* Zero means the default for every field. */
typedef struct terrain_water_desc {
    gfx_context *gfx;                 /* required */
    terrain_world *world;             /* required: the sea level, and whether the camera is under
                                         water */
    ecs_world *ecs;                   /* the world terrain_ecs_create registered on; NULL = the
                                         sea alone, no lakes */
    terrain_water_quality quality;
    float fog_density;                /* as terrain_renderer_desc's; 0 = the renderer's */
    float cloud_cover;                /* as terrain_renderer_desc's; 0 = the renderer's */
} terrain_water_desc;

typedef struct terrain_water terrain_water;

/* NULL (the reason logged) when a required field is missing or the shaders do not build. */
terrain_water *terrain_water_create(const terrain_water_desc *desc);
void terrain_water_destroy(terrain_water *water);
/* Changes the quality (passes' targets made or freed now); false, unchanged, when they cannot be. */
bool terrain_water_set_quality(terrain_water *water, terrain_water_quality quality);
/* Draws the water over the frame drawn so far into the default framebuffer (after
 * terrain_ecs_draw and the grass), with the same view. `te` gives the lakes and the high
 * quality's meshes; NULL = the sea alone, its passes with the far terrain and sky only. */
void terrain_water_draw(terrain_water *water, terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view);

typedef struct terrain_water_stats_info {
    int planes_drawn;                 /* surfaces the last draw drew (the sea counts one) */
    bool under_water;                 /* the last draw's camera was below a surface */
    double cpu_ms;                    /* CPU ms of the last draw; on llvmpipe its GPU work too,
                                         and the frame's before it (the copy waits for it) */
} terrain_water_stats_info;
terrain_water_stats_info terrain_water_stats(const terrain_water *water);

#endif
