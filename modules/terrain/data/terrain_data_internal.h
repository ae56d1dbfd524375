/* terrain_data_internal.h — the private declarations of the terrain's data area
 * (modules/terrain/data/). The module's files include it (the other areas through their own
 * internal headers), and so do its tests (through terrain/terrain_internal.h); the public API is
 * data/terrain_data.h.
 *
 * Sections are owned by whoever wrote them; add new declarations in a section of your own.
 */
#ifndef TERRAIN_DATA_INTERNAL_H
#define TERRAIN_DATA_INTERNAL_H

#include "terrain/data/terrain_data.h"

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
/* A coordinate in lattice units split into its cell ⌊v⌋ (modulo 2^32, as the lattice hash
 * reads it) and the offset v − ⌊v⌋ in [0, 1], computed in double and then rounded to float.
 * The noises take horizontal positions this way, so that a point 10 000 km out is resolved
 * as finely as one at the origin (a float v would be quantised to its ulp: 1 m steps at
 * 10 000 km in the macro relief's finest octave). */
typedef struct terrain__lattice {
    uint32_t cell;
    float offset;
} terrain__lattice;
terrain__lattice terrain__lattice_split(double v);
/* Improved gradient noise (Perlin 2002 gradients, quintic fade) with a 32-bit seed; in [-1, 1].
 * x and z are split by terrain__lattice_split (a float argument gives its old value exactly). */
float terrain__noise3(uint32_t seed, double x, float y, double z);
/* 2D gradient noise in [-1, 1] (the macro relief is a height field: 2D is half the work). */
float terrain__noise2(uint32_t seed, float x, float z);
/* The same at (cell_x + x, cell_z + z): x, z are float offsets (any sign, a few hundred cells
 * at most for full precision) from the cells; terrain__noise2 is cells 0. */
float terrain__noise2_cell(uint32_t seed, uint32_t cell_x, float x, uint32_t cell_z, float z);
/* A row of 2D noise at (x0 + dxs[j]·scale, z) in lattice units, vectorised: x0 and z are split
 * once (terrain__lattice_split), then lane j is the noise at offset x0's offset + dxs[j]·scale
 * from x0's cell, so the row is as precise anywhere as at the origin while dxs[j]·scale stays
 * small. Unclamped (measured within ±0.99), else equal to terrain__noise2_cell there. */
void terrain__noise2_row(uint32_t seed, double x0, const float *dxs, float scale, double z, int count, float *out);
/* The column batch: out[j] = terrain__noise3(seed, x, y0 + j·dy, z) for j < count. */
void terrain__noise3_column(uint32_t seed, double x, float y0, float dy, double z, int count, float *out);
/* The noise at (cell_x + x, y, cell_z + z): x, z float offsets from the cells (as for
 * terrain__noise2_cell); terrain__noise3 is this at x's and z's split. */
float terrain__noise3_cell(uint32_t seed, uint32_t cell_x, float x, float y, uint32_t cell_z, float z);
/* Scattered points around an origin: out[j] = the noise at (x0 + dxs[j], ys[j], z0 + dzs[j]) for
 * j < count, x0 and z0 split once (terrain__lattice_split), so that lane j equals
 * terrain__noise3_cell(seed, x0's cell, x0's offset + dxs[j], ys[j], z0's cell, z0's offset +
 * dzs[j]) bit for bit; with x0 = z0 = 0 that is terrain__noise3(seed, dxs[j], ys[j], dzs[j]). A
 * portable block the compiler vectorises (the perturbed cave map's lookups). */
void terrain__noise3_points(uint32_t seed, double x0, double z0, const float *dxs, const float *ys, const float *dzs,
                            int count, float *out);
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
/* Σ_k r^(−kH)·S(r^k·x_k), the sum normalised by Σ_k r^(−kH) so the result lies in [-1, 1], at
 * (x0 + dx, z): each octave turns and scales the origin (x0, z) in double and splits it into
 * its lattice's cell and offset, and adds the float part from dx (small: a row's width). */
float terrain__multifractal2(const terrain__multifractal *mf, double x0, float dx, double z);
/* The same at (x0 + dxs[j], z) for j < count, several points per instruction; lane j equals
 * terrain__multifractal2(mf, x0, dxs[j], z) bit for bit. */
void terrain__multifractal2_row(const terrain__multifractal *mf, double x0, const float *dxs, double z, int count,
                                float *out);

/* Ridged multifractal (Musgrave) of `octaves` octaves at lacunarity 2, octave k's amplitude
 * gain^k, in [0, 1]; 1 on the ridges, where the underlying noise crosses zero. Scalar
 * reference; generation uses the form from raw octave values below. */
float terrain__ridged3(uint32_t seed, float x, float y, float z, int octaves, float gain);
/* The same from the raw octave values n[0…octaves-1] (octave k at frequency 2^k), so a caller
 * that interpolates the smooth raw noise can apply the ridge (a kink) at full resolution.
 * Inline: the generator's caves call it twice a density sample with two octaves, and a call
 * and a loop cost more than the sum. */
static inline float terrain__ridged_from_octaves(const float *n, int octaves, float gain) {
    /* Musgrave's ridged multifractal (offset 1, weight gain 2): each octave's ridge (1 − |n|)²
     * is weighted by the previous octave's, so detail gathers along the main ridges. Octave k's
     * amplitude is gain^k; the sum is normalised by Σ gain^k, so the result is in [0, 1] with 1
     * where every octave's noise is 0. On the first octave's ridge alone the value is at least
     * 1 / Σ gain^k (0.8 for two octaves at gain 0.25, 0.67 at 0.5). */
    float result = 0.0f, total = 0.0f, weight = 1.0f, amplitude = 1.0f;
    for (int k = 0; k < octaves; k++) {
        float signal = 1.0f - fabsf(n[k]);
        signal *= signal * weight;
        weight = signal * 2.0f;
        weight = weight > 1.0f ? 1.0f : weight;
        result += signal * amplitude;
        total += amplitude;
        amplitude *= gain;
    }
    return total > 0.0f ? result / total : 0.0f;
}

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

/* ==== water planes (terrain_water_planes.c) ====================================================== */

/* Whether column (i, k) has water on top (its highest non-air layer is water): then *surface is
 * that layer's top and *ground the top of the highest solid layer, in quanta above the floor. */
bool terrain__stacks_water(const terrain_stacks *stacks, int i, int k, int64_t *surface, int64_t *ground);
/* terrain_water_planes_find for a mesh chunk, as a WaterPlane (core_alloc'd; free with
 * terrain__water_free), or NULL when it has none. */
WaterPlane *terrain__water_find(terrain_world *world, int64_t x, int64_t y, int64_t z, int level);
void terrain__water_free(WaterPlane **water);   /* sets *water to NULL; NULL is fine */

/* ==== end of the water planes section ===================================================== */

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
/* Columns stay below this many quanta: an edit file and a terrain_columns region hold no taller. */
#define TERRAIN__COLUMN_MAX_QUANTA (1 << 26)

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
                                   core_error *error);
/* Moves every chunk with entries from `from` into `to` (replacing to's entries for those chunks;
 * they are clean in `to`); `from` keeps its chunks, empty. */
void terrain__edit_log_take(terrain_edit_log *to, terrain_edit_log *from);

/* ==== end of the edit log section ========================================================= */

/* ==== edits in the world: the data side (terrain_stacks.c, terrain_world.c) ============== */

/* Where two chunks' stacks hold different materials: the columns and heights of the box around
 * every difference (change->coord is left alone); false when they are equal (terrain_stacks.c). */
bool terrain__stacks_diff(const terrain_stacks *a, const terrain_stacks *b, terrain_world_change *box);

/* The sea after edits (edit/terrain_edit.h, "the sea after edits"): whether the world's edits let the sea
 * in, and its level in quanta above the floor. */
bool terrain__world_sea(const terrain_world *world, int32_t *sea_quanta);

/* Passes a sampled field through terrain_world_desc.amplify, if the world has one. */
void terrain__world_amplify(terrain_world *world, terrain_field *field);
/* terrain_world_desc.amplify_reach, x y z (zeros without amplify). */
const float *terrain__world_amplify_reach(const terrain_world *world);
/* For tests of the chunk cache's races: `fn` runs on the generating thread after a chunk was
 * generated and replayed, before it is inserted (set before any thread uses the world). */
void terrain__world_on_generated(terrain_world *world, void (*fn)(void *user, terrain_chunk_coord coord),
                                  void *user);

/* The far terrain's view of the cache (render/terrain_clipmap.c draws the stacks' surface
 * wherever chunks are cached, 002 §3.5). terrain__world_cached: the chunk's stacks if it is
 * cached now, else NULL; never generates, and does not count as a use (the LRU order stays).
 * The pointer lasts as terrain_world_stacks's do (until the next trim). While watched
 * (one watcher per world: the clipmap made with it), every chunk inserted, committed with a
 * change or evicted is queued once per event; take_surface_changes hands them over in order
 * (at most `capacity`, the rest stay). Turning the watch on or off empties the queue. */
const terrain_stacks *terrain__world_cached(terrain_world *world, terrain_chunk_coord coord);
/* terrain__world_cached, or for a chunk the edit log holds edits of, the chunk itself, made
 * again (generated and replayed, and cached) when it was evicted: edits show from afar however
 * long ago they were made. Unedited chunks are never made here. */
const terrain_stacks *terrain__world_surface_stacks(terrain_world *world, terrain_chunk_coord coord);
void terrain__world_watch_surface(terrain_world *world, bool on);
int terrain__world_take_surface_changes(terrain_world *world, terrain_chunk_coord *out, int capacity);

/* ==== end of the edits-in-the-world section (edit/terrain_edit_internal.h has the rest) ==== */

#endif
