/* terrain_internal.h — the terrain module's private declarations. Only the module's .c files and
 * the module's own tests include this; the public API is terrain.h.
 *
 * Sections are owned by whoever wrote them; add new declarations in a section of your own.
 */
#ifndef TERRAIN_INTERNAL_H
#define TERRAIN_INTERNAL_H

#include "terrain/terrain.h"

#include "core/core.h"

#include <math.h>
#include <stdint.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* ==== stacks, noise, generation (terrain_stacks.c, terrain_noise.c, terrain_generate.c) ===== */

/* ---- packed stacks (terrain_stacks.c) ----
 * A layer is one 16-bit word: material in bits 0–3, thickness in quanta in bits 4–15
 * (1…4095, i.e. up to 127.97 m). A thickness field of 0 marks a long layer: the next word holds
 * its thickness in quanta (4096…65535, up to 2048 m); longer runs are split into several
 * entries of the same material, which every reader merges back into one logical layer. */
#define TERRAIN__LAYER_MATERIAL_BITS 4
#define TERRAIN__LAYER_SHORT_MAX 4095u
#define TERRAIN__LAYER_LONG_MAX 65535u
#define TERRAIN__QUANTA_PER_METRE 32      /* 1 / TERRAIN_HEIGHT_QUANTUM */
#define TERRAIN__COLUMNS (TERRAIN_CHUNK_COLUMNS * TERRAIN_CHUNK_COLUMNS)

/* A logical layer in quanta: what readers walk. */
typedef struct terrain__qlayer {
    uint8_t material;
    uint32_t quanta;
} terrain__qlayer;

/* Walks column (i, k): the range of words and a cursor over logical layers (split entries
 * merged). */
typedef struct terrain__column_cursor {
    const uint16_t *word, *end;
} terrain__column_cursor;

terrain__column_cursor terrain__stacks_cursor(const terrain_stacks *stacks, int i, int k);
/* Next logical layer; false at the end of the column (the implicit air above). */
bool terrain__cursor_next(terrain__column_cursor *cursor, terrain__qlayer *out);

/* ---- noise (terrain_noise.c) ----
 * Seeds are folded to 32 bits once (terrain__seed32) so that the hot loops hash with 32-bit
 * integer operations, which SSE2 vectorises. */
uint32_t terrain__seed32(uint64_t seed);
/* Improved gradient noise (Perlin 2002 gradients, quintic fade) with a 32-bit seed; in [-1, 1]. */
float terrain__noise3(uint32_t seed, float x, float y, float z);
/* 2D gradient noise in [-1, 1] (the macro relief is a height field: 2D is half the work). */
float terrain__noise2(uint32_t seed, float x, float z);
/* A row of 2D noise at (xs[j]·scale, z), vectorised; unclamped (measured within ±0.99), else
 * equal to terrain__noise2. */
void terrain__noise2_row(uint32_t seed, const float *xs, float scale, float z, int count, float *out);
/* The column batch: out[j] = terrain__noise3(seed, x, y0 + j·dy, z) for j < count. */
void terrain__noise3_column(uint32_t seed, float x, float y0, float dy, float z, int count, float *out);
/* The code path of the batches above and terrain__multifractal2_row. AUTO picks, on first use,
 * the widest the CPU has (AVX-512, else AVX2, else SSE2, x86-64's baseline; PORTABLE, plain C,
 * off x86-64). Every path gives the scalar functions' bits exactly, so forcing one (tests,
 * benchmarks) changes only speed.
 * terrain__noise_set_path returns false, changing nothing, for a path this CPU cannot run;
 * terrain__noise_get_path returns the path in use (never AUTO). */
typedef enum terrain__noise_path {
    TERRAIN__NOISE_AUTO,
    TERRAIN__NOISE_PORTABLE,
    TERRAIN__NOISE_SSE2,
    TERRAIN__NOISE_AVX2,
    TERRAIN__NOISE_AVX512,
    TERRAIN__NOISE_PATH_COUNT
} terrain__noise_path;
bool terrain__noise_path_supported(terrain__noise_path path);
bool terrain__noise_set_path(terrain__noise_path path);
terrain__noise_path terrain__noise_get_path(void);
const char *terrain__noise_path_name(terrain__noise_path path);

/* Rescale-and-add multifractal with domain warping (004 §2.1, §2.2) over a 2D domain measured
 * in wavelengths of the lowest octave. */
typedef struct terrain__multifractal {
    uint32_t seed;
    float lacunarity;        /* r */
    float hurst;             /* H */
    float octaves;           /* ν: floor(ν) full octaves, then one weighted by its fraction (004 §4) */
    float warp;              /* 0 = no domain warping; 1 = 004's control vectors as published */
} terrain__multifractal;

/* Octave count for sampling spacing `spacing` (same unit as the first octave's amplitude):
 * ν = log(spacing) / log(r^−H) (004 §4), capped to [1, max_octaves]. */
float terrain__multifractal_octaves(float lacunarity, float hurst, float spacing, int max_octaves);
/* Σ_k r^(−kH)·S(r^k·x_k), the sum normalised by Σ_k r^(−kH) so the result lies in [-1, 1]. */
float terrain__multifractal2(const terrain__multifractal *mf, float x, float z);
/* The same at (xs[j], z) for j < count, several points per instruction; equal to the scalar. */
void terrain__multifractal2_row(const terrain__multifractal *mf, const float *xs, float z, int count, float *out);

/* Ridged multifractal (Musgrave) of `octaves` octaves at lacunarity 2, octave k's amplitude
 * gain^k, in [0, 1]; 1 on the ridges, where the underlying noise crosses zero. Scalar
 * reference; generation uses the form from raw octave values below. */
float terrain__ridged3(uint32_t seed, float x, float y, float z, int octaves, float gain);
/* The same from the raw octave values n[0…octaves-1] (octave k at frequency 2^k), so a caller
 * that interpolates the smooth raw noise can apply the ridge (a kink) at full resolution. */
float terrain__ridged_from_octaves(const float *n, int octaves, float gain);

/* ---- generation (terrain_generate.c) ---- */

/* Macro ground height (metres) at world column position (x, z): base + relief·multifractal,
 * plus the vertical fBm perturbation (002 §3.1.3.1's "fractal sampled along y = 0"). */
float terrain__ground_height(const terrain_generation_desc *params, double x, double z);

/* G for a grid `spacing` metres apart, at (x0 + j·dx, z) for j < count (the far terrain's
 * clipmap, 002 §3.2). Only the detail such a grid can carry: the multifractal's octave count
 * from the spacing (004 §4.1), the dropped octaves simply missing (the kept ones keep their
 * weight); the y perturbation's octaves fade out towards their Nyquist spacing; cliff terraces
 * fade out between 4 and 16 m. spacing ≤ TERRAIN_COLUMN_SIZE gives terrain__ground_height's
 * values bit for bit. A value depends only on (params, x, z, spacing), not on the row. */
void terrain__ground_row_spaced(const terrain_generation_desc *params, double x0, double dx, double z, int count,
                                float spacing, float *out, float *lakes);
/* The far terrain's lakes, on the same grid (terrain__ground_row_spaced's `lakes`, NULL for
 * none, in the same pass): the level of the lake whose water circle holds (x0 + j·dx, z) (the
 * level generated chunks fill with water there, where their ground lies below it), else
 * TERRAIN__NO_LAKE. None for spacings whose G has no basins (coarser than 8 m). Finite, so that
 * the clipmap's morph may average it with a neighbour's level: any mix with it stays far below
 * the ground. */
#define TERRAIN__NO_LAKE (-1.0e30f)
void terrain__lake_row_spaced(const terrain_generation_desc *params, double x0, double dx, double z, int count,
                              float spacing, float *out);
/* The multifractal octave count ν that terrain__ground_row_spaced uses for `spacing`. */
float terrain__ground_octaves(const terrain_generation_desc *params, float spacing);

/* ==== end of the stacks/noise/generation section ========================================== */


/* ==== field and meshing (terrain_field.c, terrain_mesh.c, terrain_mesh_tables.c) ========== */

/* The marching-cubes case table (terrain_mesh_tables.c says how it is derived): for the cell
 * configuration `config` (bit v set when corner v = x | y << 1 | z << 2 is inside, f > 0), the
 * triangles as triples of cell edges, counter-clockwise seen from the outside. Edge 4·a + m runs
 * along axis a between terrain__mc_edge_corners[e][0] and [1]. Built once, thread-safely. */
typedef struct terrain__mc_case {
    uint8_t triangle_count;          /* 0xff would mean a loop without a valid triangulation */
    uint8_t loop_count;              /* surface pieces in the cell */
    uint16_t edge_mask;              /* crossed edges */
    uint8_t edges[12][3];
} terrain__mc_case;

const terrain__mc_case *terrain__mc_table(void);
extern const uint8_t terrain__mc_edge_corners[12][2];

/* ---- shared by the mesher (terrain_mesh.c) and level of detail (terrain_lod.c) ---- */

/* Edge parameter of the crossing from sample value f0 (the lower-index end) to f1: f0/(f0 − f1)
 * rounded to 1/8192 and clamped to [0, 1], so (index + t)·spacing is exact in a float. Every
 * mesh computes a crossing with this, from the lower-index end, so shared crossings agree. */
static inline float terrain__mesh_edge_t(float f0, float f1) {
    float t = f0 / (f0 - f1);
#if defined(__SSE2__)
    /* cvtss2si rounds half to even in the default rounding mode, as nearbyintf does, without a
     * library call; out of int range (or NaN) it gives INT_MIN, which the clamp below takes to 0
     * as it does NaN. t is in [0, 1] for samples of different signs. */
    t = (float)_mm_cvtss_si32(_mm_set_ss(t * 8192.0f)) / 8192.0f;
#else
    t = nearbyintf(t * 8192.0f) / 8192.0f;
#endif
    if (!(t >= 0.0f)) t = 0.0f;  /* NaN too */
    if (t > 1.0f) t = 1.0f;
    return t;
}

typedef struct terrain__mesh_builder {
    const terrain_field *field;
    int n[3];                    /* samples per axis */
    int lo[3], hi[3];            /* meshed samples: lo … hi inclusive */
    size_t slice;                /* samples per z slice */
    terrain_vertex *vertices;
    size_t vertex_count, vertex_capacity;
    uint32_t *indices;
    size_t index_count, index_capacity;
} terrain__mesh_builder;

/* −∇f at sample (x, y, z) up to the factor 1/spacing (central differences, one-sided at the
 * field's outermost samples). */
void terrain__mesh_gradient(const terrain__mesh_builder *b, int x, int y, int z, float g[3]);
/* The vertex on the grid edge from sample (x, y, z) one step along `axis` (terrain_mesh.c). */
uint32_t terrain__mesh_add_vertex(terrain__mesh_builder *b, int x, int y, int z, int axis, float f0, float f1);
/* Weights, vertex-cache order, exact-size arrays into `out` (the builder's arrays move there);
 * false (arrays freed, message logged) past 32-bit indices. */
bool terrain__mesh_finish(terrain__mesh_builder *b, const terrain_mesh_desc *desc, const double origin[3], terrain_mesh *out);

/* Level of detail (terrain_lod.c) with the field coming from `sample` instead of a world (tests
 * give an analytic field): sample must fill `out` like terrain_field_sample (steps included) and
 * give a grid point the same value whatever the request. `weights_world` may be NULL. */
typedef bool (*terrain__field_sampler)(void *user, const terrain_field_desc *desc, terrain_field *out);
bool terrain__mesh_chunk_with(terrain__field_sampler sample, void *user, terrain_world *weights_world, int64_t x,
                              int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out);
/* The same without the shortcuts (every transition cell contoured, corner signs read one by
 * one), for tests: its output must equal terrain__mesh_chunk_with's byte for byte. */
bool terrain__mesh_chunk_reference(terrain__field_sampler sample, void *user, terrain_world *weights_world, int64_t x,
                                   int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out);

/* How far (metres, columns) beyond its vertices a mesh's occlusion reads the stacks: its rays'
 * lift and reach, the tent and a slab (terrain_mesh.c). An edit that near remeshes the chunk. */
#define TERRAIN__MESH_OCCLUSION_REACH 11

/* The material weights the mesher gives a vertex at world position p with unit normal n (000 §6;
 * terrain_mesh.c says how), summing to 255: for tests that work them out by hand. */
void terrain__mesh_vertex_weights(terrain_world *world, const double p[3], const float n[3], uint8_t out[4]);

/* ==== end of the field and meshing section ================================================ */

/* ==== the terrain in the ECS, streaming (terrain_ecs.c, terrain_stream.c) ================= */

#include "ecs/ecs.h"

typedef struct terrain__streamer terrain__streamer;
typedef struct terrain__editor terrain__editor;

struct terrain_ecs {
    ecs_world *ecs;
    terrain_world *terrain;
    ecs_component chunk, mesh_chunk;
    /* Tags that move finished entities out of the systems' queries, so a frame with nothing to
     * generate or mesh schedules no jobs at all; `streamed` marks the streamer's mesh chunks,
     * which the synchronous systems leave alone. */
    ecs_component chunk_ready, mesh_ready, mesh_uploaded, streamed;
    ecs_component water_plane;           /* WaterPlane (terrain.h, "water planes") */
    /* Resources (ecs.h): this object (the streamer's and the editor's state, the view), and the
     * far terrain's clipmap, which systems declare instead of reaching them behind the
     * scheduler's back. */
    ecs_component self_resource, clipmap_resource;
    ecs_query *chunks, *mesh_chunks;
    terrain_frustum frustum;             /* of the view set for the cull phase */
    bool culling;
    terrain_gpu_mesh *draw_list;         /* gathered each draw */
    size_t draw_capacity;
    terrain_gpu_mesh *caster_list;       /* every mesh on the GPU: the shadows' casters */
    size_t caster_capacity;
    terrain__streamer *stream;           /* NULL unless terrain_ecs_stream was called */
    terrain__editor *editor;             /* created by the first edit call */
    terrain_world_change *changed;       /* column chunks committed before this frame's mesh phase */
    size_t changed_count, changed_capacity;
};

/* Bytes a mesh holds, on the CPU or (the same arrays) on the GPU. */
size_t terrain__mesh_bytes(uint32_t vertex_count, uint32_t index_count);
/* The upload system's budget: nanoseconds of uploads and frees this frame (UINT64_MAX when not
 * streaming: everything at once). */
uint64_t terrain__stream_upload_budget(const terrain_ecs *te);
/* Called by the upload system: a mesh went from the CPU to the GPU (replacing `old_gpu_bytes`). */
void terrain__stream_uploaded(terrain_ecs *te, size_t cpu_bytes, size_t gpu_bytes, size_t old_gpu_bytes);
/* Frees queued GPU meshes until the deadline (core_time_ns), at least a few a frame. */
void terrain__stream_free_pending(terrain_ecs *te, uint64_t deadline);
/* Queues a GPU mesh for terrain__stream_free_pending (from TerrainMeshChunk's on_remove hook). */
void terrain__stream_free_later(terrain_ecs *te, terrain_gpu_mesh gpu);
void terrain__stream_destroy(terrain_ecs *te);

/* Editing (terrain_ecs_edit.c): the stabilize phase's system, and the editor's memory. */
void terrain__editor_register(terrain_ecs *te);
void terrain__editor_destroy(terrain_ecs *te);
/* Whether mesh chunk (level, x, y, z) reads a column of the changed chunk at a changed height
 * (samples, apron, kernel and material weights): it must be meshed again. */
bool terrain__mesh_reads_change(int level, int64_t x, int64_t y, int64_t z, const terrain_world_change *change);

/* ==== end of the ECS and streaming section ================================================ */

/* ==== water planes (terrain_water_planes.c) ====================================================== */

/* Whether column (i, k) has water on top (its highest non-air layer is water): then *surface is
 * that layer's top and *ground the top of the highest solid layer, in quanta above the floor. */
bool terrain__stacks_water(const terrain_stacks *stacks, int i, int k, int64_t *surface, int64_t *ground);
/* terrain_water_planes_find for a mesh chunk, as a WaterPlane (core_alloc'd; free with
 * terrain__water_free), or NULL when it has none. */
WaterPlane *terrain__water_find(terrain_world *world, int64_t x, int64_t y, int64_t z, int level);
void terrain__water_free(WaterPlane **water);   /* sets *water to NULL; NULL is fine */

/* ==== end of the water planes section ===================================================== */

/* ==== far terrain: geometry clipmaps (terrain_clipmap.c) =================================== */

/* Level L's vertex (i, k), 0 ≤ i, k ≤ cells, is the world point ((first[0] + i)·s, (first[1] +
 * k)·s) with s = finest_spacing·2^L; first[] is even, so the level's border lies on level L + 1's
 * vertex lines. Each level is cut into 6 × 6 blocks along the cell cuts 0, n/4, n/4 + 1, n/2,
 * 3n/4, 3n/4 + 1, n: the finer level always covers exactly the blocks of segments 1–3 or 2–4 on
 * each axis, so a block is either all covered or not at all. */
#define TERRAIN__CLIPMAP_SEGMENTS 6
#define TERRAIN__CLIPMAP_BLOCKS (TERRAIN__CLIPMAP_SEGMENTS * TERRAIN__CLIPMAP_SEGMENTS)

typedef struct terrain__clipmap_level_info {
    int64_t first[2];                 /* grid index of vertex (0, 0), in units of `spacing` */
    double spacing;
    int cells;
    float octaves;                    /* of the multifractal (004 §4.1) */
    float morph_start, morph_width;   /* metres (see terrain__clipmap_morph) */
} terrain__clipmap_level_info;

terrain__clipmap_level_info terrain__clipmap_level(const terrain_clipmap *clipmap, int level);
/* The stored height of grid point (i, k) of a level (world (i·s, k·s)); NAN when the level's
 * window (its vertices and one more on every side) does not hold it. */
float terrain__clipmap_texel(const terrain_clipmap *clipmap, int level, int64_t i, int64_t k);

/* Geomorphing (Losasso & Hoppe's transition regions): a vertex at (dx, dz) from the camera of
 * the clipmap's last update (the one its levels were placed for, not the one drawing them, so
 * the guarantees below hold however far the view moved since) blends towards the coarser
 * level's surface by
 *     α = clamp((max(|dx|, |dz|) − start) / width, 0, 1),  and α = 1 on the level's border,
 *     h = (1 − α)·h_fine + α·h_coarse,
 * where h_coarse is the coarser level's triangle surface under the vertex: its vertex, the
 * midpoint of its edge, or the midpoint of its cell's diagonal (from (i, k) to (i + 1, k + 1),
 * the diagonal the triangles use), i.e. ½(H(c) + H(c + odd)) with c = the coarse vertex at or
 * before the fine one and odd = the fine index's parity. start = half the footprint − the most
 * the level's centre can be off the camera − width, so α reaches 1 before the border (the
 * border term makes that exact against rounding), and the coarser level's own transition
 * starts far outside the finer level, so the coarser vertices under the finer border are its
 * unmorphed heights, the very ones the finer level reads. shaders/clipmap.vert
 * computes the same expressions (`precise`), so the finer border's vertices lie exactly on the
 * coarser level's edges (T-junctions without gaps; zero-area triangles along every level's
 * border cover what rounding leaves). */
static inline float terrain__clipmap_morph(float dx, float dz, float start, float inverse_width, bool border) {
    float a = (fmaxf(fabsf(dx), fabsf(dz)) - start) * inverse_width;
    a = a < 0.0f ? 0.0f : a > 1.0f ? 1.0f : a;
    return border ? 1.0f : a;
}

/* What clipmap.vert computes for vertex (i, k) of a level with the camera at `camera`: its
 * camera-relative x and z (floats, from one anchor shared by every level, so vertices that two
 * levels share come out bit-identical) and its drawn height (morphed; hole sinking excluded). */
void terrain__clipmap_vertex(const terrain_clipmap *clipmap, int level, int i, int k, const double camera[3],
                             float position[2], float *height);

/* The holes as clipmap.vert receives them (u_holes, u_hole_count) for the camera: min x, min z,
 * max x, max z, camera-relative; returns how many (the empty ones are never kept). */
int terrain__clipmap_holes(const terrain_clipmap *clipmap, const double camera[3], float holes[][4]);

/* What clipmap.vert sinks a camera-relative position (terrain__clipmap_vertex's) by: the
 * deepest of the holes' pits there, 0 outside every hole (the drawn height is height − sink). */
float terrain__clipmap_sink(const terrain_clipmap *clipmap, const double camera[3], const float position[2]);

typedef struct terrain__clipmap_block_info {
    int cells_min[2], cells_max[2];   /* cells [min, max) of the level's grid along x and z */
    double box_min[3], box_max[3];    /* world bounds the cull tests (heights conservative) */
    bool covered;                     /* by the finer level: never drawn */
    bool visible;                     /* drawn (not covered and, if culled, in the frustum) */
} terrain__clipmap_block_info;

terrain__clipmap_block_info terrain__clipmap_block(const terrain_clipmap *clipmap, int level, int block);

/* Draws the visible blocks with `program` (shaders/clipmap.*), which terrain_renderer_draw has
 * made current with the shared uniforms set; sets the draw counters and stats. Main thread. */
void terrain__clipmap_draw(terrain_clipmap *clipmap, gfx_context *gfx, uint32_t program, const terrain_view *view);

/* ==== end of the clipmap section ========================================================== */

/* ==== sun shadows (terrain_shadow.c) ====================================================== */

typedef struct terrain__shadows terrain__shadows;

/* NULL with quality off, or when the shaders or the depth target cannot be made (logged). */
terrain__shadows *terrain__shadows_create(gfx_context *gfx, terrain_shadow_quality quality);
void terrain__shadows_destroy(terrain__shadows *shadows);
/* Fits the cascades to `view` and renders `casters` into them: one pass named "shadows". */
void terrain__shadows_render(terrain__shadows *shadows, const terrain_view *view, const float sun[3],
                             const terrain_gpu_mesh *casters, int caster_count);
/* Sets shadow.glsl's uniforms on `program` (in use) and binds the map to texture `unit`;
 * shadows NULL sets u_shadow_cascades = 0 (the sampler still gets a unit of its own: GL refuses
 * a draw whose samplers of two types share one). */
void terrain__shadows_bind(const terrain__shadows *shadows, gfx_context *gfx, uint32_t program, int unit);

/* ==== end of the shadows section ========================================================== */

/* ==== the renderer's scene for water's passes (terrain_render.c, terrain_water.c) ========== */

/* Draws the meshes, the far terrain and the sky as terrain_renderer_draw does, but into the
 * framebuffer and pass the caller opened, without shadows, and keeping only what lies where
 * dot((p − camera, 1), clip_plane) ≥ 0 (camera-relative; all zero keeps everything; the sky is
 * never clipped): water's reflection and refraction passes. Main thread. */
void terrain__renderer_draw_clipped(terrain_renderer *renderer, const terrain_view *view,
                                    const terrain_gpu_mesh *meshes, int mesh_count, const float clip_plane[4]);
/* Whether terrain_water draws the sea over the frame: the far terrain then leaves out its own
 * tint of the ground under the sea (clipmap.frag), which would show through the shore's fade.
 * Takes effect from the next frame drawn; terrain_water_draw sets it every call (off clears
 * it), and it outlives the water object. */
void terrain__renderer_set_water_drawn(terrain_renderer *renderer, bool drawn);
float terrain__renderer_fog_density(const terrain_renderer *renderer);
float terrain__renderer_cloud_cover(const terrain_renderer *renderer);   /* 0 = a clear sky */

/* ==== end of the water section ============================================================ */

/* ==== editing: columns, stabilization, brushes (terrain_columns.c, terrain_stabilize.c,
 * terrain_brush.c) ============================================================================ */

/* A layer in quanta, as a terrain_columns region keeps it. */
typedef struct terrain__clayer {
    uint32_t material;
    int32_t quanta;
} terrain__clayer;

/* Column flags (terrain_columns.flags). */
#define TERRAIN__COLUMN_UNSORTED 1u   /* layers not in 000 §3.4's order: stabilize sorts them first */
#define TERRAIN__COLUMN_EDITED 2u     /* content changed since terrain_columns_changed_chunks cleared */

/* Heights in the halo of a region side with no neighbour: so high that nothing flows there and
 * no excess points that way (a wall). Real columns stay below TERRAIN__COLUMN_MAX_QUANTA. */
#define TERRAIN__WALL_HEIGHT (1 << 30)
#define TERRAIN__COLUMN_MAX_QUANTA (1 << 26)
#define TERRAIN__MAX_SIDE 4096
#define TERRAIN__MAX_REGION_COLUMNS (1 << 22)
#define TERRAIN__FLOW_MAX 65535       /* the largest step, in quanta (2 048 m) */

/* A span of columns [lo, hi] of one row and the last pass that widened it. */
typedef struct terrain__span {
    int32_t lo, hi;
    uint32_t clock;
} terrain__span;

/* The eight neighbour directions, (dx, dz) with d and 7 − d opposite. */
extern const int8_t terrain__dir[8][2];

/* Stabilization runs in passes, one per colour of a 3 × 3 pattern of columns (terrain_stabilize.c);
 * nine passes look at every column once. Clocks count passes and start here, so that "changed in
 * the last nine passes" never wraps below zero. */
#define TERRAIN__COLOURS 9
#define TERRAIN__CLOCK_START 16u

/* The mutable region (terrain.h: terrain_columns). Each column is its lower layers (everything
 * up to and including the highest stable layer: bedrock or a custom material) in a pool, and
 * on top the pile that stabilization moves: sand, rocks, water (000 §3.4's order, air above).
 * The pile is kept as heights in quanta above TERRAIN_FLOOR_Y, in arrays with a one-column halo
 * (cell (i, k) is (k + 1)·pitch + i + 1) so the 3 × 3 stencil never tests for borders; the halo
 * holds walls, or copies of the neighbouring region's columns. */
struct terrain_columns {
    int64_t x0, z0;                   /* world column index of column (0, 0) */
    int width, depth, pitch;          /* pitch = width + 2 */
    size_t cells;                     /* (width + 2)·(depth + 2) */
    /* Padded (halo included). */
    int32_t *base;                    /* top of the lower layers: where the pile starts */
    int32_t *sand_top;                /* base + sand */
    int32_t *ground;                  /* sand_top + rocks: the surface rocks flow on */
    uint32_t *changed;                /* the pass that last changed the column (edits: clock) */
    int32_t *gift_sand, *gift_rocks;  /* halo only: given to the neighbour region this pass */
    terrain__span *changed_span;      /* per row, halo rows too (row k at k + 1) */
    uint32_t clock;                   /* passes run */
    uint32_t last_change;             /* the highest `changed` stamp written */
    /* Per row, written by the job of the row during a pass: */
    int64_t *row_moved;               /* quanta its columns gave */
    uint8_t *row_gifts;               /* whether some of it went into the halo */
    /* Unpadded (index k·width + i). */
    int32_t *water;                   /* above the pile */
    uint32_t *lower_start;
    uint16_t *lower_count, *lower_capacity;
    uint8_t *flags;
    terrain__clayer *pool;
    size_t pool_count, pool_capacity, pool_garbage;
    size_t unsorted;                  /* columns flagged TERRAIN__COLUMN_UNSORTED */
    /* Set by the stabilizer for the duration of a call. */
    struct terrain_columns *neighbour[8];      /* by direction (terrain__dir); NULL = edge */
    uint8_t edge_sides;                        /* bit d: no neighbour in direction d */
    bool near_edge;                            /* this pass looks at columns by the border */
};

/* Whether a change stamped `stamp` still matters to pass `pass`: the columns around it have not
 * all been looked at since (one pass per colour). */
static inline bool terrain__recent(uint32_t stamp, uint32_t pass) {
    return stamp + TERRAIN__COLOURS >= pass;
}

/* Widens a row's span by column i changed at pass `clock`; a span whose changes no longer matter
 * starts afresh. */
static inline void terrain__span_extend(terrain__span *span, int i, uint32_t clock) {
    if (!terrain__recent(span->clock, clock)) {
        *span = (terrain__span){ i, i, clock };
        return;
    }
    if (i < span->lo) span->lo = i;
    if (i > span->hi) span->hi = i;
    if (clock > span->clock) span->clock = clock;
}

static inline size_t terrain__cell(const terrain_columns *c, int i, int k) {
    return (size_t)(k + 1) * (size_t)c->pitch + (size_t)(i + 1);
}

/* Whether a material holds up what lies on it and never moves (000 §3.4: bedrock is "always
 * considered as stable"; custom materials are treated alike). */
static inline bool terrain__stable_material(uint32_t material) {
    return material == TERRAIN_BEDROCK || material >= TERRAIN_MATERIAL_BUILTIN_COUNT;
}

/* Column (i, k)'s layers bottom-up, adjacent equal materials merged, into *scratch (grown with
 * core_grow); returns the count. */
int terrain__columns_layers(const terrain_columns *c, int i, int k, terrain__clayer **scratch, size_t *capacity);
/* Replaces column (i, k) by `layers` (bottom-up, quanta > 0, adjacent equal materials may
 * repeat): splits off the pile and flags the column unsorted when it is not in order. Does not
 * mark it changed. */
void terrain__columns_store(terrain_columns *c, int i, int k, const terrain__clayer *layers, int count);
/* Marks column (i, k) changed now: it and its neighbours are looked at by the next nine passes,
 * and its chunk is reported by terrain_columns_changed_chunks. */
void terrain__columns_touch(terrain_columns *c, int i, int k);
/* Sorts column (i, k)'s runs (000 §3.4, Figure 6); touches it when that changed anything. */
void terrain__columns_sort(terrain_columns *c, int i, int k, terrain__clayer **scratch, size_t *capacity);
/* Moves the region's clock forward to `clock`; changes the old clock's next nine passes would
 * still have looked at become changes at the new one. */
void terrain__columns_set_clock(terrain_columns *c, uint32_t clock);

/* ==== end of the editing section ========================================================== */

/* ==== sculpting, sweeping, picking (terrain_sculpt.c) ===================================== */

/* The field of 000 §3.3 with σ = one column, computed from a terrain_columns region's own
 * columns: a snapshot of the solid (sand and bedrock) runs of the region's columns
 * [i0, i1) × [k0, k1), so that an edit computes f from the state before it wrote anything.
 * Columns outside the window count as empty (only the implicit bedrock below the floor). */
typedef struct terrain__region_field {
    int64_t x0, z0;                   /* world column index of window column (0, 0) */
    int width, depth;
    uint32_t *first;                  /* per column (k·width + i): its first run; first[n + 1] ends it */
    int32_t (*runs)[2];               /* solid runs [bottom, top) in quanta above the floor, bottom-up */
    size_t run_capacity;
} terrain__region_field;

/* Snapshots the window (clipped to the region); free with terrain__region_field_free. */
void terrain__region_field_init(terrain__region_field *field, const terrain_columns *columns, int i0, int k0, int i1,
                                int k1);
void terrain__region_field_free(terrain__region_field *field);
/* f at the world point (x, y, z): what terrain_field_at(world, x, y, z, 0) gives for a world
 * holding the same columns (to float rounding). */
double terrain__region_field_at(const terrain__region_field *field, double x, double y, double z);

/* ==== end of the sculpting section ======================================================== */

/* ==== the edit log (terrain_edit_log.c; the two stacks helpers in terrain_stacks.c) ======== */

/* Adds a layer of exactly `quanta` (no rounding through metres: any thickness up to 2^32 − 1
 * quanta) on top of the column being built; merges with the layer below as the float push does. */
void terrain__stacks_builder_push_quanta(terrain_stacks_builder *builder, terrain_material material,
                                         uint32_t quanta);
/* 16-bit words a logical layer of `quanta` takes in packed stacks (long runs split). A row of a
 * chunk holds at most 65 535 words before its last column (column offsets are 16-bit), which
 * the edit log checks before it builds stacks from a file's columns. */
uint32_t terrain__stacks_layer_words(uint32_t quanta);
#define TERRAIN__ROW_OFFSET_MAX 65535u

/* CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320, as zlib's crc32): the edit files'
 * checksum. `crc` is 0 to start, or the result so far to continue over more bytes. */
uint32_t terrain__crc32(uint32_t crc, const void *data, size_t size);

/* What the per-file layout (terrain_edit_log_save/load) and the world database (terrain_store.c)
 * share: a chunk's edits travel as its file's bytes (the format at the top of
 * terrain_edit_log.c, CRC-32 included) in both. */
typedef struct terrain__edit_file {
    terrain_chunk_coord coord;
    uint64_t version;                 /* the chunk's version these bytes hold */
    uint8_t *bytes;
    size_t size;
    bool written;                     /* set by the writer once durable */
} terrain__edit_file;

typedef struct terrain__edit_files {
    terrain__edit_file *items;
    size_t count, capacity;
} terrain__edit_files;

/* printf into a new string (paths, messages); free with terrain__text_free (NULL is fine). */
char *terrain__text_format(const char *fmt, ...) CORE_PRINTF(1, 2);
void terrain__text_free(char *text);
uint64_t terrain__edit_log_key(const terrain_edit_log *log);
/* A snapshot of the chunks changed since their last save, each serialized (under the log's
 * lock, for a few microseconds a chunk); a chunk whose bytes would pass `compact_above` is
 * compacted first. Free with terrain__edit_files_free. */
terrain__edit_files terrain__edit_log_dirty_files(terrain_edit_log *log, size_t compact_above);
/* The same for every chunk with entries, changed or not. */
terrain__edit_files terrain__edit_log_all_files(terrain_edit_log *log, size_t compact_above);
/* Marks the files whose `written` is set as saved; a chunk changed since its snapshot stays dirty. */
void terrain__edit_log_mark_saved(terrain_edit_log *log, const terrain__edit_files *files);
void terrain__edit_files_free(terrain__edit_files *files);
/* One chunk's bytes into the log in place of what it held (clean), when they parse and hold
 * chunk `named`; false with the reason in `error` and the log unchanged. */
bool terrain__edit_log_parse_chunk(terrain_edit_log *log, const void *bytes, size_t size, terrain_chunk_coord named,
                                   char *error, size_t error_size);
/* Moves every chunk with entries from `from` into `to` (replacing to's entries for those chunks;
 * they are clean in `to`); `from` keeps its chunks, empty. */
void terrain__edit_log_take(terrain_edit_log *to, terrain_edit_log *from);

/* ==== end of the edit log section ========================================================= */

/* ==== edits in the world (terrain_world.c, terrain_world_edit.c, terrain_ecs_edit.c) ======= */

/* Where two chunks' stacks hold different materials: the columns and heights of the box around
 * every difference (change->coord is left alone); false when they are equal (terrain_stacks.c). */
bool terrain__stacks_diff(const terrain_stacks *a, const terrain_stacks *b, terrain_world_change *box);

/* The sea after edits (terrain.h, "the sea after edits"): whether the world's edits let the sea
 * in, and its level in quanta above the floor. */
bool terrain__world_sea(const terrain_world *world, int32_t *sea_quanta);
/* Applies that rule to every column of the region changed since terrain_columns_changed_chunks
 * last cleared (TERRAIN__COLUMN_EDITED); returns how many it changed (terrain_columns.c). */
int terrain__columns_flood(terrain_columns *columns, int32_t sea_quanta);
/* Displacement by stabilization: in the chunk's changed columns, the water on the pile reaches no
 * higher than the water surface the column had in `before` (the chunk as last committed): sand
 * and rocks that slid under water push it out rather than lift it. Returns the columns capped. */
int terrain__columns_cap_water(terrain_columns *columns, terrain_chunk_coord coord, const terrain_stacks *before);

/* ==== end of the edits-in-the-world section =============================================== */

/* ---- material textures (terrain_textures.c) ---- */

/* Base layers: TERRAIN__BASE_SIZE² RGBA8 per material, one repeat per TERRAIN__BASE_METRES:
 * R the shade (albedo = tint · R), GB the tangent-space normal's x, y (0.5 + 0.5·n).
 * Detail layers: TERRAIN__DETAIL_SIZE² RGBA8 per material, one repeat per
 * TERRAIN__DETAIL_METRES: R an albedo multiplier as 2·R with a mean of 1, GB the normal as above;
 * then one macro layer of the same size, one repeat per TERRAIN__MACRO_METRES: R brightness and
 * G hue (2·texel, mean 1), B the share of the coarser base sample (TERRAIN__BASE2_METRES). */
#define TERRAIN__MATERIAL_LAYERS 4          /* bedrock, sand, rocks, water bed */
#define TERRAIN__DETAIL_LAYERS (TERRAIN__MATERIAL_LAYERS + 1)
#define TERRAIN__BASE_SIZE 256
#define TERRAIN__DETAIL_SIZE 256
#define TERRAIN__BASE_METRES 8.0f
#define TERRAIN__BASE2_METRES 25.0f         /* the base again, coarser, against repeats */
#define TERRAIN__DETAIL_METRES 1.0f
#define TERRAIN__MACRO_METRES 200.0f        /* a multiple of every period above: texture
                                               coordinates wrap the origin modulo this */

typedef struct terrain__material_texels {
    uint8_t *base, *detail;                 /* layouts above; core_alloc'd */
    size_t base_bytes, detail_bytes;
    float tints[TERRAIN__MATERIAL_LAYERS][3];
    float means[TERRAIN__MATERIAL_LAYERS][3];  /* tint · mean shade: the far colour */
} terrain__material_texels;

/* Fills `out`; free with terrain__material_texels_free. Deterministic. */
void terrain__material_texels_make(terrain__material_texels *out);
void terrain__material_texels_free(terrain__material_texels *texels);

/* Passes a sampled field through terrain_world_desc.amplify, if the world has one. */
void terrain__world_amplify(terrain_world *world, terrain_field *field);
/* For tests of the chunk cache's races: `fn` runs on the generating thread after a chunk was
 * generated and replayed, before it is inserted (set before any thread uses the world). */
void terrain__world_on_generated(terrain_world *world, void (*fn)(void *user, terrain_chunk_coord coord),
                                  void *user);

#endif
