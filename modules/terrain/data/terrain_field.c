/* terrain_field.c — the convolution field of 000 §3.3 on a regular grid.
 *
 *     f(p) = 2·V(p) / (8σ³) − 1,   V(p) = volume of sand and bedrock in the cube [p − σ, p + σ]³
 *
 * The cube kernel is separable, so V is a box filter of the solid indicator, done in three
 * one-dimensional passes that each cost O(1) per sample:
 *
 *   y: per column, the solid length L(y) in [y − σ, y + σ] is S(y + σ) − S(y − σ), with S the
 *      solid length from the world floor up (a prefix sum over the column's layers); two cursors
 *      walk up the layers as y advances, so a column of n samples costs O(n + layers).
 *   x: a sliding window over the columns of a row of columns.
 *   z: a sliding window over the rows.
 *
 * Samples sit on column corners (000 §3.3 leaves the sampling to the polygoniser; we put the
 * grid on the column lattice so that with σ = c the kernel covers exactly 2 × 2 columns). When σ
 * is not a multiple of the column size c, the kernel covers the two outermost columns along x
 * (and along z) only partly: with s = σ/c and R = ⌈s⌉, the columns at offsets −R and R − 1 from
 * the sample have weight e = s − R + 1 and the 2R − 2 between them weight 1. Hence
 *
 *     V = c² · (S₁ + e·Sₑ + e²·Sₑₑ)
 *
 * where S₁ sums L over the interior × interior columns, Sₑ over edge × interior and interior ×
 * edge, Sₑₑ over the four corner columns.
 *
 * Bit-identical results whatever region asked: L is a function of the column and the sample
 * height only, rounded to fixed point (TERRAIN_FIELD_FIXED units per metre; exact when σ is a
 * multiple of the height quantum, as the defaults are), and the three sums are 64-bit integer
 * sums, exact, so the sliding windows' add/subtract order cannot change them. The last step is
 * the same few floating-point operations on the same integers for every sample, so two adjacent
 * chunks agree exactly on the samples they share.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <math.h>
#include <string.h>

#define TERRAIN_FIELD_MAX_SIZE 1024
#define TERRAIN_FIELD_MAX_SIGMA_COLUMNS 16       /* σ up to 16 columns */
#define TERRAIN_FIELD_FIXED 1048576.0            /* 2^20 fixed-point units per metre of L */
#define TERRAIN_FIELD_MAX_STEP 65536

static int64_t terrain_floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

/* ---- the columns the kernel reaches ------------------------------------------------------- */

/* Fetches columns by global column index, keeping the last chunk's stacks at hand (a row of
 * columns crosses at most a few chunks). */
#define FIELD_INLINE_LAYERS 64          /* a column's layers read without the allocator (most have a few) */

typedef struct field_column_source {
    terrain_world *world;
    terrain_chunk_coord chunk;
    const terrain_stacks *stacks;
    terrain_layer *layers;            /* `inline_layers` until a column needs more */
    size_t layer_capacity;
    terrain_layer inline_layers[FIELD_INLINE_LAYERS];
} field_column_source;

/* Point queries run by the hundred thousand (an amplifier's presence tests): no allocation. */
static void field_column_source_begin(field_column_source *src, terrain_world *world) {
    src->world = world;
    src->stacks = NULL;
    src->layers = src->inline_layers;
    src->layer_capacity = FIELD_INLINE_LAYERS;
}

/* The layers of global column (gx, gz); returns how many (valid until the next call). */
static int field_column_layers(field_column_source *src, int64_t gx, int64_t gz) {
    terrain_chunk_coord chunk = { terrain_floor_div(gx, TERRAIN_CHUNK_COLUMNS),
                                  terrain_floor_div(gz, TERRAIN_CHUNK_COLUMNS) };
    if (!src->stacks || chunk.x != src->chunk.x || chunk.z != src->chunk.z) {
        src->stacks = terrain_world_stacks(src->world, chunk);
        src->chunk = chunk;
    }
    int i = (int)(gx - chunk.x * TERRAIN_CHUNK_COLUMNS), k = (int)(gz - chunk.z * TERRAIN_CHUNK_COLUMNS);
    for (;;) {
        int count = terrain_stacks_column(src->stacks, i, k, src->layers, (int)src->layer_capacity);
        if (count <= (int)src->layer_capacity) return count;
        size_t old = src->layer_capacity;
        src->layer_capacity = (size_t)count * 2;
        if (src->layers == src->inline_layers) {
            src->layers = core_alloc(src->layer_capacity * sizeof *src->layers);
            memcpy(src->layers, src->inline_layers, sizeof src->inline_layers);
        } else {
            src->layers = core_realloc(src->layers, old * sizeof *src->layers, src->layer_capacity * sizeof *src->layers);
        }
    }
}

static void field_column_source_end(field_column_source *src) {
    if (src->layers != src->inline_layers) core_free(src->layers, src->layer_capacity * sizeof *src->layers);
}

/* A column as runs of solid (in-field) and empty material: adjacent layers of the same kind
 * merged (a generated column is typically one solid run, maybe water above it), each with the
 * solid length below its bottom. Heights and prefix sums are sums of multiples of the height
 * quantum: exact in double, whatever order they are walked in. */
typedef struct field_run {
    double bottom, top, solid_below;
    bool solid;
} field_run;

typedef struct field_runs {
    field_run *runs;
    int count;
    size_t capacity;
} field_runs;

static void field_runs_push(field_runs *out, double *bottom, double *solid_below, bool solid, double thickness) {
    double top = *bottom + thickness;
    if (out->count > 0 && out->runs[out->count - 1].solid == solid) {
        out->runs[out->count - 1].top = top;
    } else {
        out->runs = core_grow(out->runs, &out->capacity, (size_t)out->count + 1, sizeof *out->runs);
        out->runs[out->count++] = (field_run){ *bottom, top, *solid_below, solid };
    }
    if (solid) *solid_below += thickness;
    *bottom = top;
}

/* The runs of global column (gx, gz) below `limit`, straight from the packed stacks: the same
 * thicknesses as terrain_stacks_column's layers (the same float), without copying every layer
 * out first (coarse chunks read 3.8× a level-0 chunk's columns, so per-column costs count). */
static void field_runs_of_column(field_runs *out, field_column_source *src, int64_t gx, int64_t gz, double limit) {
    terrain_chunk_coord chunk = { terrain_floor_div(gx, TERRAIN_CHUNK_COLUMNS),
                                  terrain_floor_div(gz, TERRAIN_CHUNK_COLUMNS) };
    if (!src->stacks || chunk.x != src->chunk.x || chunk.z != src->chunk.z) {
        src->stacks = terrain_world_stacks(src->world, chunk);
        src->chunk = chunk;
    }
    terrain__column_cursor cursor = terrain__stacks_cursor(src->stacks, (int)(gx - chunk.x * TERRAIN_CHUNK_COLUMNS),
                                                           (int)(gz - chunk.z * TERRAIN_CHUNK_COLUMNS));
    out->count = 0;
    double bottom = TERRAIN_FLOOR_Y, solid_below = 0.0;
    terrain__qlayer layer;
    /* Runs above `limit` are never read: once a run's top is above every height asked, the
     * cursors stop in it (it is not the last run, so S does not take the whole solid length),
     * and S there depends only on its bottom and solid_below, which later layers leave alone. */
    while (bottom <= limit && terrain__cursor_next(&cursor, &layer)) {
        float thickness = (float)layer.quanta * TERRAIN_HEIGHT_QUANTUM;
        field_runs_push(out, &bottom, &solid_below, terrain_material_in_field((terrain_material)layer.material), thickness);
    }
}

/* S(y): solid length from the world floor up to y, with a cursor that only moves up. Below the
 * floor everything is bedrock, so S(y) = y − floor there (negative); above the last run it is
 * the column's whole solid length. */
typedef struct field_cursor {
    const field_runs *column;
    int run;
} field_cursor;

/* Forced inline: GCC otherwise calls it twice per sample from the column loop, a fifth of the
 * field's time. */
static inline __attribute__((always_inline)) double field_cursor_solid_to(field_cursor *cur, double y) {
    if (y <= TERRAIN_FLOOR_Y) return y - TERRAIN_FLOOR_Y;
    const field_run *runs = cur->column->runs;
    int count = cur->column->count;
    while (cur->run < count && runs[cur->run].top <= y) cur->run++;
    if (cur->run == count) {
        if (count == 0) return 0.0;
        const field_run *last = &runs[count - 1];
        return last->solid_below + (last->solid ? last->top - last->bottom : 0.0);
    }
    const field_run *run = &runs[cur->run];
    return run->solid ? run->solid_below + (y - run->bottom) : run->solid_below;
}

/* L at the samples y = (first + j)·c, j < count, in fixed point, written with stride `stride`.
 * L ≥ 0 (S only grows), so adding ½ and truncating rounds it. S is a function of the height
 * alone (the cursors only save walking), so two shortcuts keep every value as it was: a low end
 * at the height of the previous sample's high end (σ = step/2, as at level 1 with the default
 * σ) takes its S instead of walking again, and once the low end is above the column's last run
 * both ends read the column's whole solid length, L = 0 for the rest of the column. */
static void field_column_lengths(const field_runs *column, int64_t first_y, int count, int step, double sigma,
                                 int64_t *out, size_t stride) {
    field_cursor low = { column, 0 }, high = low;
    const double last_top = column->count ? column->runs[column->count - 1].top : TERRAIN_FLOOR_Y;
    double previous_high = -INFINITY, previous_s_high = 0.0;
    for (int j = 0; j < count; j++) {
        double y = (double)(first_y + (int64_t)j * step) * TERRAIN_COLUMN_SIZE;
        double y_low = y - sigma, y_high = y + sigma;
        if (y_low >= last_top && y_low > TERRAIN_FLOOR_Y) {
            for (; j < count; j++) out[(size_t)j * stride] = 0;
            return;
        }
        double s_high = field_cursor_solid_to(&high, y_high);
        double s_low = y_low == previous_high ? previous_s_high : field_cursor_solid_to(&low, y_low);
        previous_high = y_high, previous_s_high = s_high;
        double length = (s_high - s_low) * TERRAIN_FIELD_FIXED;
        out[(size_t)j * stride] = length > 0.0 ? (int64_t)(length + 0.5) : 0;
    }
}

/* ---- sampling ------------------------------------------------------------------------------ */

static float field_sigma(float sigma) { return sigma == 0.0f ? TERRAIN_COLUMN_SIZE : sigma; }

static bool field_desc_valid(const terrain_field_desc *desc, float sigma) {
    for (int a = 0; a < 3; a++) {
        if (desc->size[a] <= 0 || desc->size[a] > TERRAIN_FIELD_MAX_SIZE) {
            core_log_error("terrain", "field: size[%d] = %d is outside 1 … %d", a, desc->size[a], TERRAIN_FIELD_MAX_SIZE);
            return false;
        }
        /* Keep every index (and the kernel's reach) far from int64 overflow. */
        int64_t last = desc->first[a] + (int64_t)(desc->size[a] - 1) * (desc->step > 0 ? desc->step : 1);
        if (desc->first[a] < -((int64_t)1 << 52) || desc->first[a] > ((int64_t)1 << 52) || last > ((int64_t)1 << 52)) {
            core_log_error("terrain", "field: first[%d] = %lld is too far out", a, (long long)desc->first[a]);
            return false;
        }
    }
    if (desc->step < 0 || desc->step > TERRAIN_FIELD_MAX_STEP) {
        core_log_error("terrain", "field: step = %d is outside 0 … %d", desc->step, TERRAIN_FIELD_MAX_STEP);
        return false;
    }
    if (!(sigma > 0.0f) || sigma > TERRAIN_FIELD_MAX_SIGMA_COLUMNS * TERRAIN_COLUMN_SIZE) {
        core_log_error("terrain", "field: sigma = %g is outside (0, %g]", (double)sigma,
                   (double)(TERRAIN_FIELD_MAX_SIGMA_COLUMNS * TERRAIN_COLUMN_SIZE));
        return false;
    }
    return true;
}

/* The columns a strided axis reads: sample i (grid index first + i·step) reads columns
 * first + i·step − R + d, d < window. Overlapping windows (step ≤ window) share one contiguous
 * run of columns; disjoint ones get window columns each. map[i·window + d] is the column's place
 * in the list; returns the list's length (its columns from columns_out). */
static int field_strided_columns(int n, int step, int reach, int64_t first, int64_t *columns_out, int *map) {
    const int window = 2 * reach;
    int count = step <= window ? (n - 1) * step + window : n * window;
    for (int i = 0; i < n; i++)
        for (int d = 0; d < window; d++) {
            int place = step <= window ? i * step + d : i * window + d;
            map[i * window + d] = place;
            columns_out[place] = first - reach + (int64_t)i * step + d;
        }
    return count;
}

/* The z pass of the strided path for sample row k: its window's x-filtered rows, found at
 * (map place) mod `slots` in rows_inner/rows_edge. */
static void field_strided_z(terrain_field *out, const int *map_z, int k, int window, int slots, size_t row_samples,
                            const int64_t *rows_inner, const int64_t *rows_edge, float sigma, double e, double e2) {
    const double c = TERRAIN_COLUMN_SIZE;
    const double scale = c * c / TERRAIN_FIELD_FIXED, to_f = 1.0 / (4.0 * (double)sigma * sigma * sigma);
    const int *m = map_z + k * window;
    float *values = out->values + (size_t)k * row_samples;
    for (size_t n = 0; n < row_samples; n++) {
        int64_t s1 = 0, se = 0, see = 0;
        for (int d = 1; d < window - 1; d++) {
            s1 += rows_inner[(size_t)(m[d] % slots) * row_samples + n];
            se += rows_edge[(size_t)(m[d] % slots) * row_samples + n];
        }
        const size_t first = (size_t)(m[0] % slots) * row_samples + n;
        const size_t last = (size_t)(m[window - 1] % slots) * row_samples + n;
        se += rows_inner[first] + rows_inner[last];
        see = rows_edge[first] + rows_edge[last];
        double volume = scale * ((double)s1 + e * (double)se + e2 * (double)see);
        values[n] = (float)(volume * to_f - 1.0);
    }
}

/* step > 1: the samples are sparse, so the sliding windows would slide over columns no sample
 * reads. Instead L is computed for exactly the columns some kernel reaches (at the strided
 * heights), then the same interior/edge sums per sample, x then z. They are the same 64-bit
 * integer sums as the step-1 path's (exact, so the order is free) followed by the same float
 * operations, hence a sample equals the step-1 sample at the same grid point bit for bit. */
static void field_sample_strided(terrain_world *world, const terrain_field_desc *desc, float sigma, int step,
                                 terrain_field *out) {
    const int nx = desc->size[0], ny = desc->size[1], nz = desc->size[2];
    const double c = TERRAIN_COLUMN_SIZE, s = (double)sigma / c;
    const int reach = (int)ceil(s), window = 2 * reach;
    const double e = s - (reach - 1), e2 = e * e;
    int64_t *cols_x = core_alloc((size_t)nx * window * sizeof *cols_x);
    int64_t *cols_z = core_alloc((size_t)nz * window * sizeof *cols_z);
    int *map_x = core_alloc((size_t)nx * window * sizeof *map_x), *map_z = core_alloc((size_t)nz * window * sizeof *map_z);
    const int ncx = field_strided_columns(nx, step, reach, desc->first[0], cols_x, map_x);
    const int ncz = field_strided_columns(nz, step, reach, desc->first[2], cols_z, map_z);
    const size_t row_samples = (size_t)ny * nx;
    int64_t *lengths = core_alloc((size_t)ny * ncx * sizeof *lengths);
    /* Per column row (z), the x-filtered sums: [row][j][i]. */
    /* Disjoint windows (step ≥ window, as for every coarse level with the default σ) use each
     * column row for one sample k only, rows k·window … k·window + window − 1, so k is finished
     * as soon as its last row is in and `window` rows of storage do; at level 2 the full set of
     * rows would be 1.4 MB, fresh pages faulted in on every request. */
    const bool disjoint = step >= window;
    const int slots = disjoint ? window : ncz;
    int64_t *rows_inner = core_alloc((size_t)slots * row_samples * sizeof *rows_inner);
    int64_t *rows_edge = core_alloc((size_t)slots * row_samples * sizeof *rows_edge);
    field_column_source src;
    field_column_source_begin(&src, world);
    field_runs column = { 0 };
    const double limit = (double)(desc->first[1] + (int64_t)(ny - 1) * step) * TERRAIN_COLUMN_SIZE + (double)sigma;
    for (int row = 0; row < ncz; row++) {
        for (int col = 0; col < ncx; col++) {
            field_runs_of_column(&column, &src, cols_x[col], cols_z[row], limit);
            field_column_lengths(&column, desc->first[1], ny, step, (double)sigma, lengths + col, (size_t)ncx);
        }
        int64_t *inner = rows_inner + (size_t)(row % slots) * row_samples;
        int64_t *edge = rows_edge + (size_t)(row % slots) * row_samples;
        for (int j = 0; j < ny; j++) {
            const int64_t *l = lengths + (size_t)j * ncx;
            for (int i = 0; i < nx; i++) {
                const int *m = map_x + i * window;
                int64_t sum = 0;
                for (int d = 1; d < window - 1; d++) sum += l[m[d]];
                inner[(size_t)j * nx + i] = sum;
                edge[(size_t)j * nx + i] = l[m[0]] + l[m[window - 1]];
            }
        }
        if (disjoint && row % window == window - 1)
            field_strided_z(out, map_z, row / window, window, slots, row_samples, rows_inner, rows_edge, sigma, e, e2);
    }
    for (int k = 0; !disjoint && k < nz; k++)
        field_strided_z(out, map_z, k, window, slots, row_samples, rows_inner, rows_edge, sigma, e, e2);
    field_column_source_end(&src);
    if (column.runs) core_free(column.runs, column.capacity * sizeof *column.runs);
    core_free(lengths, (size_t)ny * ncx * sizeof *lengths);
    core_free(rows_inner, (size_t)slots * row_samples * sizeof *rows_inner);
    core_free(rows_edge, (size_t)slots * row_samples * sizeof *rows_edge);
    core_free(cols_x, (size_t)nx * window * sizeof *cols_x);
    core_free(cols_z, (size_t)nz * window * sizeof *cols_z);
    core_free(map_x, (size_t)nx * window * sizeof *map_x);
    core_free(map_z, (size_t)nz * window * sizeof *map_z);
}

bool terrain_field_sample(terrain_world *world, const terrain_field_desc *desc, terrain_field *out) {
    memset(out, 0, sizeof *out);
    float sigma = field_sigma(desc->sigma);
    if (!field_desc_valid(desc, sigma)) return false;
    const int step = desc->step > 0 ? desc->step : 1;
    if (step > 1) {
        out->nx = desc->size[0], out->ny = desc->size[1], out->nz = desc->size[2];
        for (int a = 0; a < 3; a++) out->origin[a] = (double)desc->first[a] * TERRAIN_COLUMN_SIZE;
        out->spacing = (float)(step * TERRAIN_COLUMN_SIZE);
        out->values = core_alloc((size_t)out->nx * out->ny * out->nz * sizeof *out->values);
        field_sample_strided(world, desc, sigma, step, out);
        terrain__world_amplify(world, out);
        return true;
    }
    const int nx = desc->size[0], ny = desc->size[1], nz = desc->size[2];
    const double c = TERRAIN_COLUMN_SIZE, s = (double)sigma / c;
    const int reach = (int)ceil(s);                    /* R */
    const int window = 2 * reach;                      /* columns the kernel touches per axis */
    const double e = s - (reach - 1), e2 = e * e;      /* the outermost columns' coverage */
    const int ncx = nx + window - 1, ncz = nz + window - 1;
    const int64_t column_x0 = desc->first[0] - reach, column_z0 = desc->first[2] - reach;

    out->nx = nx, out->ny = ny, out->nz = nz;
    for (int a = 0; a < 3; a++) out->origin[a] = (double)desc->first[a] * c;
    out->spacing = (float)c;
    out->values = core_alloc((size_t)nx * ny * nz * sizeof *out->values);

    /* One row of columns' L (layout [j][column]) and a ring of `window` x-filtered rows, each
     * holding the interior sum and the two edge columns' sum per (j, i). */
    const size_t row_samples = (size_t)ny * nx;
    int64_t *lengths = core_alloc((size_t)ny * ncx * sizeof *lengths);
    int64_t *ring_inner = core_alloc((size_t)window * row_samples * sizeof *ring_inner);
    int64_t *ring_edge = core_alloc((size_t)window * row_samples * sizeof *ring_edge);
    /* Running z sums over the interior rows of the window. */
    int64_t *z_inner = core_calloc(row_samples, sizeof *z_inner);   /* Σ interior-row inner */
    int64_t *z_edge = core_calloc(row_samples, sizeof *z_edge);     /* Σ interior-row edge  */
    field_column_source src;
    field_column_source_begin(&src, world);
    field_runs column = { 0 };
    const double scale = c * c / TERRAIN_FIELD_FIXED, to_f = 1.0 / (4.0 * (double)sigma * sigma * sigma);
    const double limit = (double)(desc->first[1] + ny - 1) * TERRAIN_COLUMN_SIZE + (double)sigma;

    for (int row = 0; row < ncz; row++) {
        /* y pass: L for every column of this row. */
        for (int col = 0; col < ncx; col++) {
            field_runs_of_column(&column, &src, column_x0 + col, column_z0 + row, limit);
            field_column_lengths(&column, desc->first[1], ny, 1, (double)sigma, lengths + col, (size_t)ncx);
        }
        /* x pass: for sample i the columns are i … i + window − 1 of the row. */
        int64_t *inner = ring_inner + (size_t)(row % window) * row_samples;
        int64_t *edge = ring_edge + (size_t)(row % window) * row_samples;
        for (int j = 0; j < ny; j++) {
            const int64_t *l = lengths + (size_t)j * ncx;
            int64_t *in = inner + (size_t)j * nx, *ed = edge + (size_t)j * nx;
            int64_t sum = 0;
            for (int d = 1; d < window - 1; d++) sum += l[d];
            for (int i = 0; i < nx; i++) {
                in[i] = sum;
                ed[i] = l[i] + l[i + window - 1];
                if (window > 2) sum += l[i + window - 1] - l[i + 1];
            }
        }
        /* z pass: sample k uses rows k … k + window − 1; rows k + 1 … k + window − 2 are the
         * interior, whose running sums z_inner/z_edge hold once `row` reaches k + window − 1. */
        int k = row - (window - 1);
        if (k < 0) {
            if (row >= 1) {   /* rows 1 … window − 2 are the first sample's interior */
                for (size_t n = 0; n < row_samples; n++) z_inner[n] += inner[n], z_edge[n] += edge[n];
            }
            continue;
        }
        const int64_t *first_inner = ring_inner + (size_t)(k % window) * row_samples;
        const int64_t *first_edge = ring_edge + (size_t)(k % window) * row_samples;
        float *values = out->values + (size_t)k * row_samples;
        for (size_t n = 0; n < row_samples; n++) {
            int64_t s1 = z_inner[n];
            int64_t se = z_edge[n] + first_inner[n] + inner[n];
            int64_t see = first_edge[n] + edge[n];
            double volume = scale * ((double)s1 + e * (double)se + e2 * (double)see);
            values[n] = (float)(volume * to_f - 1.0);
        }
        if (window > 2) {   /* slide: row k + window − 1 joins the interior, row k + 1 leaves */
            const int64_t *leave_inner = ring_inner + (size_t)((k + 1) % window) * row_samples;
            const int64_t *leave_edge = ring_edge + (size_t)((k + 1) % window) * row_samples;
            for (size_t n = 0; n < row_samples; n++) {
                z_inner[n] += inner[n] - leave_inner[n];
                z_edge[n] += edge[n] - leave_edge[n];
            }
        }
    }
    field_column_source_end(&src);
    if (column.runs) core_free(column.runs, column.capacity * sizeof *column.runs);
    core_free(lengths, (size_t)ny * ncx * sizeof *lengths);
    core_free(ring_inner, (size_t)window * row_samples * sizeof *ring_inner);
    core_free(ring_edge, (size_t)window * row_samples * sizeof *ring_edge);
    core_free(z_inner, row_samples * sizeof *z_inner);
    core_free(z_edge, row_samples * sizeof *z_edge);
    terrain__world_amplify(world, out);
    return true;
}

void terrain_field_free(terrain_field *field) {
    if (field->values) core_free(field->values, (size_t)field->nx * field->ny * field->nz * sizeof *field->values);
    memset(field, 0, sizeof *field);
}

/* ---- the reference: direct summation --------------------------------------------------------- */

static double field_overlap(double a0, double a1, double b0, double b1) {
    double lo = a0 > b0 ? a0 : b0, hi = a1 < b1 ? a1 : b1;
    return hi > lo ? hi - lo : 0.0;
}

/* The sum of the volumes of the in-field layer boxes inside the kernel's cube (000 §3.3: "the
 * sum of the volume of the boxes of material layers intersecting the kernel support box"). */
float terrain_field_at(terrain_world *world, double x, double y, double z, float sigma) {
    float value = terrain_field_base_at(world, x, y, z, sigma);
    terrain_field one = { .nx = 1, .ny = 1, .nz = 1, .origin = { x, y, z }, .spacing = TERRAIN_COLUMN_SIZE,
                          .values = &value };
    terrain__world_amplify(world, &one);
    return value;
}

float terrain_field_base_at(terrain_world *world, double x, double y, double z, float sigma_in) {
    const double sigma = field_sigma(sigma_in), c = TERRAIN_COLUMN_SIZE;
    int64_t gx0 = (int64_t)floor((x - sigma) / c), gx1 = (int64_t)ceil((x + sigma) / c);
    int64_t gz0 = (int64_t)floor((z - sigma) / c), gz1 = (int64_t)ceil((z + sigma) / c);
    field_column_source src;
    field_column_source_begin(&src, world);
    double volume = 0.0;
    for (int64_t gz = gz0; gz < gz1; gz++) {
        double wz = field_overlap((double)gz * c, (double)(gz + 1) * c, z - sigma, z + sigma);
        for (int64_t gx = gx0; gx < gx1; gx++) {
            double wx = field_overlap((double)gx * c, (double)(gx + 1) * c, x - sigma, x + sigma);
            if (wx == 0.0 || wz == 0.0) continue;
            int count = field_column_layers(&src, gx, gz);
            double length = field_overlap(-INFINITY, TERRAIN_FLOOR_Y, y - sigma, y + sigma);
            double bottom = TERRAIN_FLOOR_Y;
            for (int l = 0; l < count; l++) {
                double top = bottom + src.layers[l].thickness;
                if (terrain_material_in_field(src.layers[l].material))
                    length += field_overlap(bottom, top, y - sigma, y + sigma);
                bottom = top;
            }
            volume += wx * wz * length;
        }
    }
    field_column_source_end(&src);
    return (float)(2.0 * volume / (8.0 * sigma * sigma * sigma) - 1.0);
}
