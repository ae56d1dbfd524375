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

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

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
size_t terrain_stacks_bytes(const terrain_stacks *stacks);   /* memory held, headers included */
uint64_t terrain_stacks_hash(const terrain_stacks *stacks);  /* of the logical content */

/* ---- generation (002 §3.1.3, 004 §2) ------------------------------------------------------ */

typedef struct terrain_generation_params {
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
} terrain_generation_params;

/* Parameters that make a varied, good-looking world for this seed. */
terrain_generation_params terrain_generation_defaults(uint64_t seed);

/* The stacks of one chunk; depends only on (params, coord). Free with terrain_stacks_destroy. */
terrain_stacks *terrain_generate_chunk(const terrain_generation_params *params, terrain_chunk_coord coord);

/* ---- noise -------------------------------------------------------------------------------- */

/* Our gradient noise in [-1, 1], seeded. The batch form evaluates `count` points along y (a
 * column) so the loop vectorises. */
float terrain_noise3(uint64_t seed, float x, float y, float z);
void terrain_noise3_column(uint64_t seed, float x, float y0, float dy, float z, int count, float *out);
/* fBm of `octaves` octaves (lacunarity 2, gain 0.5), like stb_perlin_fbm_noise3's defaults. */
float terrain_fbm3(uint64_t seed, float x, float y, float z, int octaves);

/* ---- the world: generated chunks, cached -------------------------------------------------- */

typedef struct terrain_world_desc {
    terrain_generation_params generation;
    size_t max_chunks;                /* cached chunks kept (least recently used go); 0 = 4096 */
} terrain_world_desc;

typedef struct terrain_world terrain_world;
terrain_world *terrain_world_create(const terrain_world_desc *desc);
void terrain_world_destroy(terrain_world *world);
/* The chunk's stacks, generated on first use (thread-safe; valid until the world is destroyed or
 * the chunk is evicted — callers that keep a pointer across frames hold a reference). */
const terrain_stacks *terrain_world_stacks(terrain_world *world, terrain_chunk_coord coord);
void terrain_world_retain(terrain_world *world, terrain_chunk_coord coord);
void terrain_world_release(terrain_world *world, terrain_chunk_coord coord);
/* Material at a world point (generating its chunk if needed). */
terrain_material terrain_world_material_at(terrain_world *world, double x, double y, double z);

/* ---- the implicit field (000 §3.3) -------------------------------------------------------- */

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
} terrain_field_desc;

/* Samples f on the grid of spacing c = TERRAIN_COLUMN_SIZE: index (i, j, k) is the world point
 * (i·c, j·c, k·c), so samples sit on column corners. Reads whatever chunks the kernel reaches
 * (generating them). O(1) amortised per sample. False (message logged) only when the request is
 * absurd (a size ≤ 0 or over 1024). */
bool terrain_field_sample(terrain_world *world, const terrain_field_desc *desc, terrain_field *out);
void terrain_field_free(terrain_field *field);
/* The field at one point, by direct summation (slow; for tests and single queries). */
float terrain_field_at(terrain_world *world, double x, double y, double z, float sigma);

/* ---- meshes ------------------------------------------------------------------------------- */

typedef struct terrain_vertex {
    float position[3];                /* metres, relative to terrain_mesh.origin */
    float normal[3];                  /* unit, pointing into the air */
    uint8_t weights[4];               /* visible bedrock, sand, rocks, water around the vertex, /255 */
} terrain_vertex;

typedef struct terrain_mesh {
    double origin[3];                 /* world position of the vertices' (0, 0, 0) */
    terrain_vertex *vertices;
    uint32_t *indices;                /* triangles, counter-clockwise seen from the air */
    uint32_t vertex_count, index_count;
    float bounds_min[3], bounds_max[3];   /* of the vertices, relative to origin */
} terrain_mesh;

typedef struct terrain_mesh_desc {
    terrain_world *world;             /* for material weights; NULL = all bedrock */
    int apron;                        /* samples along each border that are read for gradients
                                         but not meshed (1 makes normals agree across chunks) */
    bool no_optimize;                 /* skip meshoptimizer's vertex-cache reordering */
} terrain_mesh_desc;

/* Marching cubes over every cell of the field (nx−1 × ny−1 × nz−1 cells) with shared vertices;
 * an empty or full field gives an empty mesh at once. */
bool terrain_mesh_build(const terrain_field *field, const terrain_mesh_desc *desc, terrain_mesh *out);
void terrain_mesh_free(terrain_mesh *mesh);

#endif
