/* rocks_place.c — instancing the tile set's rocks in a support (001 §6, 000 §5).
 *
 * Space is tiled by the lattice of tile_size-metre cubes, each lattice point coloured by a hash,
 * so every cube is one of the 256 tiles (001 §6: "a stochastic tiling is obtained by assigning a
 * random color to each integer grid point"). Every rock of every tile whose seed point lies in
 * the asked box is tested: kept when at least `threshold` of its anchor points (the seed and
 * voxel centres spread over it, rocks_tiles) are inside the support, skipped when it is buried
 * deeper than twice the set's largest embedding radius (001 §6).
 *
 * The support of a world is its rock layers. Reading the stacks per anchor would cost a chunk
 * lookup each, so the box's columns (plus the reach of a rock) are read once into a table of
 * rock intervals. A tile set's index (rocks_place_index) holds each rock's anchor box and sorted
 * anchor heights and each tile's rocks by the height of their lowest anchor, so a tile reads only
 * the rocks whose anchors reach the heights of the rock under its columns (two binary searches).
 * Those are decided, fastest first:
 *   - over columns that all hold the same one interval (a flat layer), in the tile's frame in
 *     floats, where a margin proves the rounding cannot matter: every anchor in, none in, or, for
 *     a rock across one face of the layer, the one anchor that decides the count (frame_kept_one);
 *   - over differing columns, a quick float test that the anchors clear the rock in every column
 *     they can reach (frame_rejects), then the exact test of entry_kept: the columns under the
 *     anchor box (all in, none in, one shared interval: count heights), else anchor by anchor.
 * Every shortcut gives what the anchor-by-anchor test gives (tests/rocks: placement against the
 * definition applied to every rock of every tile).
 */
#include "rocks_world_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/core.h"

#define PLACE_DEFAULT_TILE 3.0f
#define PLACE_DEFAULT_THRESHOLD 0.6f
#define INTERVALS_PER_COLUMN 4          /* rock intervals kept per column (more merge) */
#define NEED_CACHED 32                  /* anchor counts whose threshold is worked out once a call */

int rocks_lattice_colour(uint64_t seed, int64_t i, int64_t j, int64_t k) {
    uint64_t h = core_hash_combine(core_hash_combine(core_hash_combine(seed ^ 0x726f636b73ull, (uint64_t)i),
                                                     (uint64_t)j), (uint64_t)k);
    return (int)(h >> 63);
}

/* fminf and fmaxf as glibc's x86-64 minss/maxss give them for numbers (the first when it is
 * smaller, else the second), without the call GCC makes of them. */
static inline float min_f(float a, float b) { return a < b ? a : b; }
static inline float max_f(float a, float b) { return a > b ? a : b; }

/* floor() without the libm call that baseline x86-64 makes of it (no SSE4.1 rounding). */
static inline int64_t floor_int(double v) {
    int64_t i = (int64_t)v;
    return i - (v < (double)i);
}

/* ---- the index: the tile set laid out for placement ------------------------------------------ */

/* One entry of a tile, with what deciding it in the tile's frame reads (tile units, offset +
 * rock coordinate; rounded, so compared with a margin), in one place. */
typedef struct index_entry {
    float y_lo, y_hi;                 /* its anchors' lowest and highest height */
    float seed[3];
    uint32_t entry;                   /* in set->entries */
    uint32_t rock;                    /* the entry's rock */
    uint32_t heights;                 /* its anchors: set.anchors[heights …] and their heights,
                                         index.anchor_y[heights …] */
    uint16_t anchor_count;            /* ROCKS__ANCHORS (16) a rock */
    int8_t offset[3];                 /* the entry's offset */
    uint8_t reserved;
} index_entry;

/* What placement reads of a rock, in one place (region frame, tile units). */
typedef struct index_rock {
    float seed[3];
    float box[2][3];                  /* the lowest and highest coordinate of its anchors */
    uint32_t anchor_first, anchor_count;   /* its anchors' heights in index.anchor_y */
} index_rock;

/* An entry's offset (−1 … 1 a coordinate) as one of 27: (o + 1)·(1, 3, 9). */
static inline int offset_class(const int8_t offset[3]) {
    return (offset[0] + 1) + 3 * (offset[1] + 1) + 9 * (offset[2] + 1);
}

/* Per tile, per offset_class: the bounds of the meshes of every rock the tile lists with that
 * offset (tile units; lo > hi when none). A placement's bounds are the union of those of the
 * (tile, offset) pairs it keeps a rock of: no rock is read to write one. */
typedef struct offset_bounds {
    float lo[27][3], hi[27][3];
} offset_bounds;

struct rocks_place_index {
    const rocks_tileset *set;
    index_rock *rocks;
    float *anchor_y;                  /* each rock's anchor heights, ascending */
    index_entry *entries;             /* tile t's are [tiles[t].first, + count), by y_lo */
    float (*entry_xz)[4];             /* beside each: its anchors' x and z ranges, tile frame
                                         (x_lo, x_hi, z_lo, z_hi; rounded) */
    offset_bounds tile_bounds[256];
    float reach[3];                   /* largest |anchor − seed| of any rock, per axis (tile units) */
    float tallest;                    /* largest y_hi − y_lo */
    float y_lo, y_hi;                 /* over every entry */
    uint32_t most_entries;            /* in one tile */
};

static int index_entry_order(const void *a, const void *b) {
    const index_entry *x = a, *y = b;
    if (x->y_lo != y->y_lo) return x->y_lo < y->y_lo ? -1 : 1;
    return x->entry < y->entry ? -1 : x->entry > y->entry;
}

static void sort_heights(float *heights, uint32_t n) {   /* insertion: a rock has 16 */
    for (uint32_t a = 1; a < n; a++) {
        float v = heights[a];
        uint32_t b = a;
        for (; b > 0 && heights[b - 1] > v; b--) heights[b] = heights[b - 1];
        heights[b] = v;
    }
}

static void index_rocks(rocks_place_index *index) {
    const rocks_tileset *set = index->set;
    for (uint32_t r = 0; r < set->rock_count; r++) {
        const rocks_rock *rock = &set->rocks[r];
        index_rock *out = &index->rocks[r];
        const float *first = rock->anchor_count ? set->anchors[rock->anchor_first] : rock->seed;
        memcpy(out->seed, rock->seed, sizeof out->seed);
        memcpy(out->box[0], first, sizeof out->box[0]);
        memcpy(out->box[1], first, sizeof out->box[1]);
        out->anchor_first = rock->anchor_first, out->anchor_count = rock->anchor_count;
        float *heights = &index->anchor_y[rock->anchor_first];
        for (uint32_t a = 0; a < rock->anchor_count; a++) {
            const float *q = set->anchors[rock->anchor_first + a];
            for (int c = 0; c < 3; c++) out->box[0][c] = min_f(out->box[0][c], q[c]), out->box[1][c] = max_f(out->box[1][c], q[c]);
            heights[a] = q[1];
        }
        sort_heights(heights, rock->anchor_count);
        for (int c = 0; c < 3; c++)
            index->reach[c] = max_f(index->reach[c], max_f(rock->seed[c] - out->box[0][c], out->box[1][c] - rock->seed[c]));
    }
}

static void index_tiles(rocks_place_index *index) {
    const rocks_tileset *set = index->set;
    index->y_lo = INFINITY, index->y_hi = -INFINITY;
    for (int t = 0; t < 256; t++) {
        const rocks_tile *tile = &set->tiles[t];
        index_entry *out = index->entries + tile->first;
        offset_bounds *bounds = &index->tile_bounds[t];
        for (int c = 0; c < 27; c++)
            for (int a = 0; a < 3; a++) bounds->lo[c][a] = INFINITY, bounds->hi[c][a] = -INFINITY;
        for (uint32_t e = 0; e < tile->count; e++) {
            const rocks_tile_entry *entry = &set->entries[tile->first + e];
            const index_rock *rock = &index->rocks[entry->rock];
            const rocks_rock *mesh = &set->rocks[entry->rock];
            int c = offset_class(entry->offset);
            for (int a = 0; a < 3; a++)
                bounds->lo[c][a] = min_f(bounds->lo[c][a], mesh->bounds_min[a]),
                bounds->hi[c][a] = max_f(bounds->hi[c][a], mesh->bounds_max[a]);
            out[e] = (index_entry){
                .y_lo = (float)entry->offset[1] + rock->box[0][1], .y_hi = (float)entry->offset[1] + rock->box[1][1],
                .seed = { entry->offset[0] + rock->seed[0], entry->offset[1] + rock->seed[1], entry->offset[2] + rock->seed[2] },
                .entry = tile->first + e, .rock = entry->rock, .heights = rock->anchor_first,
                .anchor_count = (uint16_t)rock->anchor_count,
                .offset = { (int8_t)entry->offset[0], (int8_t)entry->offset[1], (int8_t)entry->offset[2] } };
            index->tallest = max_f(index->tallest, out[e].y_hi - out[e].y_lo);
            index->y_lo = min_f(index->y_lo, out[e].y_lo), index->y_hi = max_f(index->y_hi, out[e].y_hi);
        }
        qsort(out, tile->count, sizeof *out, index_entry_order);
        for (uint32_t e = 0; e < tile->count; e++) {
            const rocks_tile_entry *entry = &set->entries[out[e].entry];
            const index_rock *rock = &index->rocks[entry->rock];
            float *xz = index->entry_xz[tile->first + e];
            xz[0] = (float)entry->offset[0] + rock->box[0][0], xz[1] = (float)entry->offset[0] + rock->box[1][0];
            xz[2] = (float)entry->offset[2] + rock->box[0][2], xz[3] = (float)entry->offset[2] + rock->box[1][2];
        }
        if (tile->count > index->most_entries) index->most_entries = tile->count;
    }
}

rocks_place_index *rocks_place_index_create(const rocks_tileset *set) {
    if (!set) return NULL;
    rocks_place_index *index = core_calloc(1, sizeof *index);
    index->set = set;
    index->rocks = core_alloc((set->rock_count ? set->rock_count : 1) * sizeof *index->rocks);
    index->anchor_y = core_alloc((set->anchor_count ? set->anchor_count : 1) * sizeof *index->anchor_y);
    index->entries = core_alloc((set->entry_count ? set->entry_count : 1) * sizeof *index->entries);
    index->entry_xz = core_alloc((set->entry_count ? set->entry_count : 1) * sizeof *index->entry_xz);
    index_rocks(index);
    index_tiles(index);
    return index;
}

void rocks_place_index_destroy(rocks_place_index *index) {
    if (!index) return;
    const rocks_tileset *set = index->set;
    core_free(index->rocks, (set->rock_count ? set->rock_count : 1) * sizeof *index->rocks);
    core_free(index->anchor_y, (set->anchor_count ? set->anchor_count : 1) * sizeof *index->anchor_y);
    core_free(index->entries, (set->entry_count ? set->entry_count : 1) * sizeof *index->entries);
    core_free(index->entry_xz, (set->entry_count ? set->entry_count : 1) * sizeof *index->entry_xz);
    core_free(index, sizeof *index);
}

/* ---- the world's rock layers as intervals per column ---------------------------------------- */

typedef struct rock_interval {
    float lo, hi;                     /* the rock layer */
    float run_top;                    /* top of the solid run it belongs to (burial) */
} rock_interval;

typedef struct column_table {
    int64_t x0, z0;                   /* global column of entry 0 */
    int w, d;
    uint8_t *count;                   /* intervals per column */
    rock_interval *intervals;         /* INTERVALS_PER_COLUMN per column */
    float (*span)[2];                 /* per column: its lowest and highest rock (+∞, −∞: none) */
    float y_lo, y_hi;                 /* over all intervals */
} column_table;

static int64_t floor_div64(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

static bool solid_material(terrain_material m) { return m != TERRAIN_AIR && m != TERRAIN_WATER; }

/* The rock intervals of one column, from its layers bottom-up. */
static int column_intervals(const terrain_layer *layers, int n, rock_interval *out) {
    int count = 0;
    float y = TERRAIN_FLOOR_Y;
    int run_first = 0;                /* first interval of the current solid run */
    for (int l = 0; l < n; l++) {
        float top = y + layers[l].thickness;
        terrain_material m = layers[l].material;
        if (!solid_material(m)) {
            run_first = count;
        } else {
            if (m == TERRAIN_ROCKS) {
                if (count > 0 && count > run_first && out[count - 1].hi >= y - 1e-4f) {
                    out[count - 1].hi = top;
                } else if (count < INTERVALS_PER_COLUMN) {
                    out[count++] = (rock_interval){ y, top, top };
                } else {
                    out[count - 1].hi = top;      /* too many: merge into the last */
                }
            }
            for (int i = run_first; i < count; i++) out[i].run_top = top;
        }
        y = top;
    }
    return count;
}

static void table_free(column_table *t) {
    size_t columns = (size_t)t->w * (size_t)t->d;
    core_free(t->count, columns);
    core_free(t->intervals, columns * INTERVALS_PER_COLUMN * sizeof *t->intervals);
    core_free(t->span, columns * sizeof *t->span);
    memset(t, 0, sizeof *t);
}

static void table_column_read(column_table *t, const terrain_stacks *stacks, int i, int k, size_t c) {
    terrain_layer layers[64];
    int n = terrain_stacks_column(stacks, i, k, layers, 64);
    if (n > 64) n = 64;
    const rock_interval *iv = &t->intervals[c * INTERVALS_PER_COLUMN];
    int got = column_intervals(layers, n, &t->intervals[c * INTERVALS_PER_COLUMN]);
    t->count[c] = (uint8_t)got;
    for (int g = got; g < INTERVALS_PER_COLUMN; g++)      /* slots no height is in: tests need no count */
        t->intervals[c * INTERVALS_PER_COLUMN + g] = (rock_interval){ INFINITY, -INFINITY, -INFINITY };
    for (int g = 0; g < got; g++) t->span[c][0] = min_f(t->span[c][0], iv[g].lo), t->span[c][1] = max_f(t->span[c][1], iv[g].hi);
    t->y_lo = min_f(t->y_lo, t->span[c][0]), t->y_hi = max_f(t->y_hi, t->span[c][1]);
}

static void table_build(column_table *t, terrain_world *world, double x_min, double z_min, double x_max,
                        double z_max) {
    t->x0 = (int64_t)floor(x_min / TERRAIN_COLUMN_SIZE);
    t->z0 = (int64_t)floor(z_min / TERRAIN_COLUMN_SIZE);
    t->w = (int)((int64_t)floor(x_max / TERRAIN_COLUMN_SIZE) - t->x0 + 1);
    t->d = (int)((int64_t)floor(z_max / TERRAIN_COLUMN_SIZE) - t->z0 + 1);
    size_t columns = (size_t)t->w * (size_t)t->d;
    t->count = core_calloc(columns, 1);
    t->intervals = core_alloc(columns * INTERVALS_PER_COLUMN * sizeof *t->intervals);
    for (size_t c = 0; c < columns * INTERVALS_PER_COLUMN; c++) t->intervals[c] = (rock_interval){ INFINITY, -INFINITY, -INFINITY };
    t->span = core_alloc(columns * sizeof *t->span);
    for (size_t c = 0; c < columns; c++) t->span[c][0] = INFINITY, t->span[c][1] = -INFINITY;
    t->y_lo = INFINITY, t->y_hi = -INFINITY;
    const int N = TERRAIN_CHUNK_COLUMNS;
    for (int64_t cz = floor_div64(t->z0, N); cz <= floor_div64(t->z0 + t->d - 1, N); cz++) {
        for (int64_t cx = floor_div64(t->x0, N); cx <= floor_div64(t->x0 + t->w - 1, N); cx++) {
            const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
            if (!stacks) continue;
            int64_t gx0 = cx * N, gz0 = cz * N;
            for (int k = 0; k < N; k++) {
                int64_t tz = gz0 + k - t->z0;
                if (tz < 0 || tz >= t->d) continue;
                for (int i = 0; i < N; i++) {
                    int64_t tx = gx0 + i - t->x0;
                    if (tx >= 0 && tx < t->w) table_column_read(t, stacks, i, k, (size_t)tz * (size_t)t->w + (size_t)tx);
                }
            }
        }
    }
}

static const rock_interval *table_column(const column_table *t, double x, double z, int *count) {
    int64_t tx = floor_int(x * (1.0 / TERRAIN_COLUMN_SIZE)) - t->x0;
    int64_t tz = floor_int(z * (1.0 / TERRAIN_COLUMN_SIZE)) - t->z0;
    if (tx < 0 || tz < 0 || tx >= t->w || tz >= t->d) {
        *count = 0;
        return NULL;
    }
    size_t c = (size_t)tz * (size_t)t->w + (size_t)tx;
    *count = t->count[c];
    return &t->intervals[c * INTERVALS_PER_COLUMN];
}

static bool table_inside(const column_table *t, const double p[3]) {
    int n;
    const rock_interval *iv = table_column(t, p[0], p[2], &n);
    if (!iv) return false;
    bool inside = false;
    for (int i = 0; i < INTERVALS_PER_COLUMN; i++) inside |= (p[1] >= iv[i].lo) & (p[1] < iv[i].hi);
    return inside;
}

/* Buried: the solid run over the seed's rock layer rises more than `depth` above the seed. */
static bool intervals_bury(const rock_interval *iv, int n, double seed_y, float depth) {
    for (int i = 0; i < n; i++)
        if (seed_y >= iv[i].lo - depth && seed_y < iv[i].hi + depth) return iv[i].run_top - seed_y > depth;
    return false;
}

static bool table_buried(const column_table *t, const double seed[3], float depth) {
    int n;
    const rock_interval *iv = table_column(t, seed[0], seed[2], &n);
    return intervals_bury(iv, n, seed[1], depth);
}

/* What the columns [x0, x1] × [z0, z1] (table indices) say of anchors whose heights lie in
 * [lo, hi]: all inside, none inside, inside exactly when the height is in [band[0], band[1])
 * (every column meets that one interval, the same, in those heights), or each anchor must be
 * looked up. Exact, not conservative: an interval that [lo, hi] misses holds no anchor. */
typedef enum anchors_are { ANCHORS_EACH, ANCHORS_NONE, ANCHORS_ALL, ANCHORS_BAND } anchors_are;

static anchors_are table_classify(const column_table *t, int64_t x0, int64_t x1, int64_t z0, int64_t z1, double lo,
                                  double hi, double band[2]) {
    bool met_any = false, one_each = true, all_in = true;
    float band_lo = 0, band_hi = 0;
    for (int64_t z = z0; z <= z1; z++)
        for (int64_t x = x0; x <= x1; x++) {
            size_t c = (size_t)z * (size_t)t->w + (size_t)x;
            const rock_interval *iv = &t->intervals[c * INTERVALS_PER_COLUMN];
            int met = 0;
            for (int i = 0; i < t->count[c]; i++) {
                if (!(iv[i].hi > lo && iv[i].lo <= hi)) continue;
                all_in = all_in && lo >= iv[i].lo && hi < iv[i].hi;
                if (!met_any) band_lo = iv[i].lo, band_hi = iv[i].hi;
                one_each = one_each && band_lo == iv[i].lo && band_hi == iv[i].hi;
                met_any = true, met++;
            }
            one_each = one_each && met == 1;
        }
    if (!met_any) return ANCHORS_NONE;
    if (!one_each) return ANCHORS_EACH;
    if (all_in) return ANCHORS_ALL;
    band[0] = band_lo, band[1] = band_hi;
    return ANCHORS_BAND;
}

/* ---- placement ------------------------------------------------------------------------------ */

typedef struct placer {
    const rocks_place_desc *desc;
    const rocks_tileset *set;
    const rocks_place_index *index;
    double tile;                      /* metres */
    uint64_t seed;
    float threshold;
    const column_table *table;        /* NULL: desc->support */
    double min[3], max[3];
    double reach[3];                  /* metres: an anchor from its seed, at most (per axis) */
    float bury;                       /* metres: deeper is buried */
    uint8_t need[NEED_CACHED + 1];    /* anchors a rock with that many must have in */
    uint64_t *kept;                   /* the current tile's kept entries (bits) */
    rocks_placement *out;
} placer;

static uint32_t anchors_needed(const placer *p, uint32_t n) {
    if (n <= NEED_CACHED) return p->need[n];
    uint32_t need = (uint32_t)ceilf(p->threshold * (float)n - 1e-4f);
    return need < 1 ? 1 : need;
}

/* Per column of tiles (i, k): the columns its rocks' anchors can reach (their seeds lie in it),
 * the rock in them, and whether they all hold the same intervals. */
typedef struct tile_column {
    int64_t x0, x1, z0, z1;           /* table indices, clipped to the table */
    float span[2];                    /* lowest, highest rock in them; lo > hi: none */
    bool same;                        /* every one holds the intervals of (x0, z0) */
} tile_column;

static bool columns_same(const column_table *t, size_t a, size_t b) {
    return t->count[a] == t->count[b] &&
           memcmp(&t->intervals[a * INTERVALS_PER_COLUMN], &t->intervals[b * INTERVALS_PER_COLUMN],
                  t->count[a] * sizeof *t->intervals) == 0;
}

static void tile_column_make(const placer *p, int64_t i, int64_t k, tile_column *out) {
    const column_table *t = p->table;
    int64_t x0 = floor_int((double)i * p->tile - p->reach[0]) - t->x0;
    int64_t x1 = floor_int((double)(i + 1) * p->tile + p->reach[0]) - t->x0;
    int64_t z0 = floor_int((double)k * p->tile - p->reach[2]) - t->z0;
    int64_t z1 = floor_int((double)(k + 1) * p->tile + p->reach[2]) - t->z0;
    out->x0 = x0 < 0 ? 0 : x0, out->z0 = z0 < 0 ? 0 : z0;
    out->x1 = x1 >= t->w ? t->w - 1 : x1, out->z1 = z1 >= t->d ? t->d - 1 : z1;
    out->span[0] = INFINITY, out->span[1] = -INFINITY;
    out->same = true;
    size_t first = (size_t)out->z0 * (size_t)t->w + (size_t)out->x0;
    for (int64_t z = out->z0; z <= out->z1; z++)
        for (int64_t x = out->x0; x <= out->x1; x++) {
            size_t c = (size_t)z * (size_t)t->w + (size_t)x;
            out->span[0] = min_f(out->span[0], t->span[c][0]), out->span[1] = max_f(out->span[1], t->span[c][1]);
            out->same = out->same && columns_same(t, first, c);
        }
}

/* The rock's anchors, world metres, lie in [lo, hi]: each bound is one anchor's coordinate mapped
 * the way rock_kept maps every anchor (origin + a·tile), and that mapping rounds monotonically. */
static void rock_anchor_box(const placer *p, const index_rock *rock, const double origin[3], double lo[3], double hi[3]) {
    for (int a = 0; a < 3; a++)
        lo[a] = origin[a] + rock->box[0][a] * p->tile, hi[a] = origin[a] + rock->box[1][a] * p->tile;
}

static uint32_t anchors_in_band(const placer *p, const index_rock *rock, double origin_y, const double band[2]) {
    const float *heights = &p->index->anchor_y[rock->anchor_first];
    uint32_t inside = 0;
    for (uint32_t a = 0; a < rock->anchor_count; a++) {
        double y = origin_y + heights[a] * p->tile;          /* as anchors_inside computes it */
        inside += (y >= band[0]) & (y < band[1]);
    }
    return inside;
}

static uint32_t anchors_inside(const placer *p, const index_rock *rock, const double origin[3], uint32_t need) {
    const float (*anchors)[3] = (const float (*)[3])p->set->anchors + rock->anchor_first;
    uint32_t n = rock->anchor_count, inside = 0;
    for (uint32_t a = 0; a < n && inside < need && inside + (n - a) >= need; a++) {
        double q[3] = { origin[0] + anchors[a][0] * p->tile, origin[1] + anchors[a][1] * p->tile,
                        origin[2] + anchors[a][2] * p->tile };
        inside += p->table ? table_inside(p->table, q) : p->desc->support(p->desc->support_user, q);
    }
    return inside;
}

static void entry_origin(const placer *p, const index_entry *entry, int64_t i, int64_t j, int64_t k, double origin[3]) {
    origin[0] = ((double)i + entry->offset[0]) * p->tile;
    origin[1] = ((double)j + entry->offset[1]) * p->tile;
    origin[2] = ((double)k + entry->offset[2]) * p->tile;
}

/* What the columns under the rock's anchor box say of its anchors (table_classify); the box's
 * columns (table indices) in foot: x0, x1, z0, z1. */
static anchors_are rock_columns(const placer *p, const tile_column *column, const double lo[3], const double hi[3],
                                double band[2], int64_t foot[4]) {
    const column_table *t = p->table;
    int64_t x0 = floor_int(lo[0]) - t->x0, x1 = floor_int(hi[0]) - t->x0;
    int64_t z0 = floor_int(lo[2]) - t->z0, z1 = floor_int(hi[2]) - t->z0;
    foot[0] = x0, foot[1] = x1, foot[2] = z0, foot[3] = z1;
    if (column->same && x0 >= column->x0 && x1 <= column->x1 && z0 >= column->z0 && z1 <= column->z1)
        return table_classify(t, column->x0, column->x0, column->z0, column->z0, lo[1], hi[1], band);
    if (x0 >= 0 && z0 >= 0 && x1 < t->w && z1 < t->d) return table_classify(t, x0, x1, z0, z1, lo[1], hi[1], band);
    return ANCHORS_EACH;
}

static bool seed_buried(const placer *p, const tile_column *column, const double seed[3]) {
    if (!column->same) return table_buried(p->table, seed, p->bury);
    size_t c = (size_t)column->z0 * (size_t)p->table->w + (size_t)column->x0;
    return intervals_bury(&p->table->intervals[c * INTERVALS_PER_COLUMN], p->table->count[c], seed[1], p->bury);
}

/* The rock's anchors in the support, anchor by anchor, when its anchor box lies over the 2 × 2
 * columns from table column (x0, z0): an anchor's column is which side of the columns' shared
 * edges it lies (floor(x) ≥ X + 1 exactly when x ≥ X + 1), its intervals a copy in doubles. */
static uint32_t anchors_inside_2x2(const placer *p, const index_entry *entry, const double origin[3], int64_t x0,
                                   int64_t z0, uint32_t need) {
    const column_table *t = p->table;
    double edge_x = (double)(t->x0 + x0 + 1) * TERRAIN_COLUMN_SIZE, edge_z = (double)(t->z0 + z0 + 1) * TERRAIN_COLUMN_SIZE;
    double lo[4][INTERVALS_PER_COLUMN], hi[4][INTERVALS_PER_COLUMN];
    int slots = 0;
    for (int q = 0; q < 4; q++) {
        int64_t x = x0 + (q & 1), z = z0 + (q >> 1);
        size_t c = (size_t)(z < t->d ? z : z0) * (size_t)t->w + (size_t)(x < t->w ? x : x0);
        for (int i = 0; i < INTERVALS_PER_COLUMN; i++)
            lo[q][i] = t->intervals[c * INTERVALS_PER_COLUMN + i].lo, hi[q][i] = t->intervals[c * INTERVALS_PER_COLUMN + i].hi;
        slots = t->count[c] > slots ? t->count[c] : slots;
    }
    const float (*anchors)[3] = (const float (*)[3])p->set->anchors + entry->heights;
    uint32_t n = entry->anchor_count, inside = 0;
    for (uint32_t a = 0; a < n && inside < need && inside + (n - a) >= need; a++) {
        double x = origin[0] + anchors[a][0] * p->tile, y = origin[1] + anchors[a][1] * p->tile,
               z = origin[2] + anchors[a][2] * p->tile;
        int q = (x >= edge_x) + 2 * (z >= edge_z);
        bool in = false;
        for (int i = 0; i < slots; i++) in |= (y >= lo[q][i]) & (y < hi[q][i]);
        inside += in;
    }
    return inside;
}

/* Entry e of the tile at (i, j, k): seed in the box, not buried, at least `need` anchors in the
 * support; from the columns under its anchor box when they settle it, anchor by anchor
 * otherwise. */
static bool entry_kept(const placer *p, const tile_column *column, const index_entry *entry, int64_t i, int64_t j, int64_t k) {
    const index_rock *rock = &p->index->rocks[entry->rock];
    if (entry->anchor_count == 0) return false;
    double origin[3], seed[3];
    entry_origin(p, entry, i, j, k, origin);
    for (int a = 0; a < 3; a++) {
        seed[a] = origin[a] + rock->seed[a] * p->tile;
        if (!(seed[a] >= p->min[a] && seed[a] < p->max[a])) return false;
    }
    uint32_t need = anchors_needed(p, entry->anchor_count);
    if (!p->table) return anchors_inside(p, rock, origin, need) >= need;
    __builtin_prefetch(p->set->anchors + entry->heights);   /* read below when the columns differ */
    double lo[3], hi[3], band[2];
    int64_t foot[4];
    rock_anchor_box(p, rock, origin, lo, hi);
    anchors_are what = rock_columns(p, column, lo, hi, band, foot);
    if (what == ANCHORS_NONE || seed_buried(p, column, seed)) return false;
    switch (what) {
    case ANCHORS_ALL: return true;                              /* need ≤ anchor_count */
    case ANCHORS_BAND: return anchors_in_band(p, rock, origin[1], band) >= need;
    default: break;
    }
    const column_table *t = p->table;
    int64_t x0 = foot[0], x1 = foot[1], z0 = foot[2], z1 = foot[3];
    if (x0 >= 0 && z0 >= 0 && x1 < t->w && z1 < t->d && x1 - x0 <= 1 && z1 - z0 <= 1)
        return anchors_inside_2x2(p, entry, origin, x0, z0, need) >= need;
    return anchors_inside(p, rock, origin, need) >= need;
}

/* ---- deciding in the tile's frame ------------------------------------------------------------ */

/* Over a tile whose columns all hold the same intervals, a rock is decided in the tile's frame:
 * heights in tile units above its lattice point, where a rock's coordinates are offset + a, floats
 * near 0 … 1. A comparison that clears its bound by `margin` there gives what the exact test
 * (origin + a·tile in doubles against the world bound) gives: the two roundings (a float's 2⁻²³
 * near 1, and the doubles') are far smaller. A rock that comes closer than that to any bound goes
 * through entry_kept. */
#define FRAME_MARGIN 1e-5f

typedef enum frame_says { FRAME_NO, FRAME_YES, FRAME_EXACT } frame_says;

typedef struct tile_frame {
    int count;                        /* intervals of the columns */
    float lo[INTERVALS_PER_COLUMN], hi[INTERVALS_PER_COLUMN];
    float bury_lo, bury_hi, bury_top; /* one interval: a seed in [bury_lo, bury_hi) below bury_top is buried */
    float box_lo[3], box_hi[3];       /* the placement's box */
    bool box_edge[3];                 /* the box's sides cut the tile on that axis (else every
                                         seed is surely in) */
    bool any_edge;
    float column_x, column_z;         /* the tile's corner in the table's columns (x − x0 metres) */
    float tile;                       /* metres */
    float margin;
    float grow;                       /* frame_rejects' margin round an anchor box, metres */
} tile_frame;

static float to_frame(double world, double base, double tile) { return (float)((world - base) / tile); }

static void tile_frame_make(const placer *p, const tile_column *column, int64_t i, int64_t j, int64_t k, tile_frame *f) {
    const column_table *t = p->table;
    size_t c = (size_t)column->z0 * (size_t)t->w + (size_t)column->x0;
    const rock_interval *iv = &t->intervals[c * INTERVALS_PER_COLUMN];
    double base[3] = { (double)i * p->tile, (double)j * p->tile, (double)k * p->tile };
    /* far from the origin the doubles' rounding grows with the coordinates */
    f->margin = FRAME_MARGIN + (float)(4e-16 * (fabs(base[0]) + fabs(base[1]) + fabs(base[2]) + 1e3) / p->tile);
    f->count = column->same ? t->count[c] : 0;
    for (int n = 0; n < f->count; n++) f->lo[n] = to_frame(iv[n].lo, base[1], p->tile), f->hi[n] = to_frame(iv[n].hi, base[1], p->tile);
    if (f->count == 1) {                /* the bounds intervals_bury compares with, as it computes them */
        f->bury_lo = to_frame(iv[0].lo - p->bury, base[1], p->tile);
        f->bury_hi = to_frame(iv[0].hi + p->bury, base[1], p->tile);
        f->bury_top = to_frame((double)iv[0].run_top - p->bury, base[1], p->tile);
    }
    for (int a = 0; a < 3; a++) {
        f->box_lo[a] = to_frame(p->min[a], base[a], p->tile), f->box_hi[a] = to_frame(p->max[a], base[a], p->tile);
        f->box_edge[a] = !(f->box_lo[a] < -2 * f->margin && f->box_hi[a] >= 1 + 2 * f->margin);   /* seeds: [0, 1) */
    }
    f->any_edge = f->box_edge[0] || f->box_edge[1] || f->box_edge[2];
    f->column_x = (float)(base[0] - (double)t->x0 * TERRAIN_COLUMN_SIZE);
    f->column_z = (float)(base[2] - (double)t->z0 * TERRAIN_COLUMN_SIZE);
    f->tile = (float)p->tile;
    /* the margin covers the floats' rounding (a few ulps of coordinates no larger than the table) */
    f->grow = f->margin * f->tile + 1e-3f + 1e-6f * (float)(t->w + t->d);
}

/* 1: v is surely at or above the bound, −1: surely below, 0: too close to tell in floats. */
static inline int frame_side(float v, float bound, float margin) {
    return (v >= bound + margin) - (v < bound - margin);
}

/* From the rock's anchor heights alone: all in one interval, none in any, or one interval partly
 * (*band, to count). */
static frame_says frame_heights(const tile_frame *f, const index_entry *e, int *band) {
    *band = -1;
    for (int n = 0; n < f->count; n++) {
        if (e->y_hi < f->lo[n] - f->margin || e->y_lo >= f->hi[n] + f->margin) continue;
        if (e->y_lo >= f->lo[n] + f->margin && e->y_hi < f->hi[n] - f->margin) return FRAME_YES;
        if (*band >= 0) return FRAME_EXACT;
        *band = n;
    }
    return *band < 0 ? FRAME_NO : FRAME_EXACT;
}

static frame_says frame_in_box(const tile_frame *f, const float seed[3]) {
    for (int a = 0; f->any_edge && a < 3; a++) {
        if (!f->box_edge[a]) continue;
        int lo = frame_side(seed[a], f->box_lo[a], f->margin), hi = frame_side(seed[a], f->box_hi[a], f->margin);
        if (lo < 0 || hi > 0) return FRAME_NO;
        if (lo == 0 || hi == 0) return FRAME_EXACT;
    }
    return FRAME_YES;
}

/* The seed in the box and not buried (one interval; EXACT for more). */
static frame_says frame_seed(const tile_frame *f, const float seed[3]) {
    frame_says in_box = frame_in_box(f, seed);
    if (in_box != FRAME_YES) return in_box;
    if (f->count != 1) return FRAME_EXACT;
    int lo = frame_side(seed[1], f->bury_lo, f->margin), hi = frame_side(seed[1], f->bury_hi, f->margin);
    if (lo < 0 || hi > 0) return FRAME_YES;                     /* not by the layer: not buried */
    if (lo == 0 || hi == 0) return FRAME_EXACT;
    int top = frame_side(seed[1], f->bury_top, f->margin);
    return top > 0 ? FRAME_YES : top < 0 ? FRAME_NO : FRAME_EXACT;
}

/* How many of the n ascending heights, moved by offset, lie below y: a binary search by halving
 * steps, arithmetic rather than branches on the data (the heights straddle y at random). */
static inline uint32_t heights_below(const float *heights, uint32_t n, float offset, float y) {
    uint32_t below = 0, step = 1;
    while (step * 2 <= n) step *= 2;
    for (; step; step /= 2) {
        uint32_t next = below + step;
        uint32_t at = next <= n ? next - 1 : n - 1;
        below += step * (uint32_t)((next <= n) & (offset + heights[at] < y));
    }
    return below;
}

/* The rock's anchors in interval `band`: enough, too few, or too close to its bounds to tell.
 * Its heights are sorted, so when the rock crosses one bound only, one anchor decides: the
 * need-th from the other side. */
static frame_says frame_band(const placer *p, const tile_frame *f, const index_entry *e, const index_rock *rock,
                             float offset, int band) {
    const float *heights = &p->index->anchor_y[rock->anchor_first];
    uint32_t n = rock->anchor_count, need = anchors_needed(p, n);
    bool above_lo = e->y_lo >= f->lo[band] + f->margin, below_hi = e->y_hi < f->hi[band] - f->margin;
    if (above_lo && need <= n) {        /* in below hi: the need-th from the bottom is */
        int side = frame_side(offset + heights[need - 1], f->hi[band], f->margin);
        return side < 0 ? FRAME_YES : side > 0 ? FRAME_NO : FRAME_EXACT;
    }
    if (below_hi && need <= n) {        /* in above lo: the need-th from the top is */
        int side = frame_side(offset + heights[n - need], f->lo[band], f->margin);
        return side > 0 ? FRAME_YES : side < 0 ? FRAME_NO : FRAME_EXACT;
    }
    uint32_t out_lo = heights_below(heights, n, offset, f->lo[band] - f->margin);
    uint32_t in_lo = heights_below(heights, n, offset, f->lo[band] + f->margin);
    uint32_t in_hi = heights_below(heights, n, offset, f->hi[band] - f->margin);
    uint32_t out_hi = heights_below(heights, n, offset, f->hi[band] + f->margin);
    if (out_lo != in_lo || in_hi != out_hi) return FRAME_EXACT;
    return in_hi - in_lo >= need ? FRAME_YES : FRAME_NO;
}

/* Whether sorted entry `e` of a tile over differing columns is surely not kept: its seed surely
 * outside the box, or its anchors' heights surely clear of the rock in every column they can
 * reach (the columns under its anchor box grown by the margin). */
static bool frame_rejects(const placer *p, const tile_frame *f, const tile_column *column, const index_entry *e,
                          const float xz[4], int64_t j) {
    if (f->any_edge && frame_in_box(f, e->seed) == FRAME_NO) return true;
    const column_table *t = p->table;
    /* the table's columns under the anchors, a superset (grown by f->grow); truncation is floor
     * at or above 0, and below 0 there is no column to miss */
    const float grow = f->grow;
    int64_t x0 = (int64_t)(f->column_x + xz[0] * f->tile - grow), x1 = (int64_t)(f->column_x + xz[1] * f->tile + grow);
    int64_t z0 = (int64_t)(f->column_z + xz[2] * f->tile - grow), z1 = (int64_t)(f->column_z + xz[3] * f->tile + grow);
    x0 = x0 < column->x0 ? column->x0 : x0, x1 = x1 > column->x1 ? column->x1 : x1;
    z0 = z0 < column->z0 ? column->z0 : z0, z1 = z1 > column->z1 ? column->z1 : z1;
    float span_lo = INFINITY, span_hi = -INFINITY;
    if (x1 - x0 <= 1 && z1 - z0 <= 1) {  /* the usual rock: the 2 × 2 columns from (x0, z0), read whatever they are */
        size_t c = (size_t)z0 * (size_t)t->w + (size_t)x0, dx = (size_t)(x1 - x0), dz = (size_t)(z1 - z0) * (size_t)t->w;
        span_lo = min_f(min_f(t->span[c][0], t->span[c + dx][0]), min_f(t->span[c + dz][0], t->span[c + dz + dx][0]));
        span_hi = max_f(max_f(t->span[c][1], t->span[c + dx][1]), max_f(t->span[c + dz][1], t->span[c + dz + dx][1]));
    } else {
        for (int64_t z = z0; z <= z1; z++)
            for (int64_t x = x0; x <= x1; x++) {
                const float *span = t->span[(size_t)z * (size_t)t->w + (size_t)x];
                span_lo = min_f(span_lo, span[0]), span_hi = max_f(span_hi, span[1]);
            }
    }
    double m = f->margin;
    return ((double)j + e->y_hi + m) * p->tile < span_lo || ((double)j + e->y_lo - m) * p->tile > span_hi;
}

/* frame_kept for the usual columns, one interval each: the same tests as frame_heights,
 * frame_band and frame_seed, folded into arithmetic so that only the rare rock too close to a
 * bound branches away (to entry_kept: -1). */
static int frame_kept_one(const placer *p, const tile_frame *f, const index_entry *e) {
    float m = f->margin, lo = f->lo[0], hi = f->hi[0];
    if (e->y_hi < lo - m || e->y_lo >= hi + m) return 0;       /* clear of the layer (runs: entries by height) */
    uint32_t n = e->anchor_count;
    if (n == 0) return 0;
    if (f->any_edge) {
        frame_says in_box = frame_in_box(f, e->seed);
        if (in_box != FRAME_YES) return in_box == FRAME_NO ? 0 : -1;
    }
    float y = e->seed[1];
    int by = (y >= f->bury_lo + m) & (y < f->bury_hi - m), away = (y < f->bury_lo - m) | (y >= f->bury_hi + m);
    int buried = by & (y < f->bury_top - m), safe = away | (by & (y >= f->bury_top + m));
    int above_lo = e->y_lo >= lo + m, below_hi = e->y_hi < hi - m;
    if (!(buried | safe)) return -1;
    if (above_lo & below_hi) return safe;                       /* every anchor in: the burial decides */
    /* across hi only, the need-th height from the bottom decides; across lo, the need-th from the top */
    uint32_t need = anchors_needed(p, n);
    float deciding = (float)e->offset[1] + p->index->anchor_y[e->heights + (above_lo ? need - 1 : n - need)];
    int side = frame_side(deciding, above_lo ? hi : lo, m);
    int anchors_in = above_lo ? side < 0 : side > 0;
    if ((side == 0) | !(above_lo | below_hi)) return -1;
    return anchors_in & safe;
}

/* Whether sorted entry `e` of a same-column tile is kept, decided in the frame where it can be. */
static bool frame_kept(const placer *p, const tile_frame *f, const tile_column *column, const index_entry *e,
                       int64_t i, int64_t j, int64_t k) {
    int band;
    frame_says heights = frame_heights(f, e, &band);
    if (heights == FRAME_NO) return false;
    const index_rock *rock = &p->index->rocks[e->rock];
    float seed[3] = { e->offset[0] + rock->seed[0], e->offset[1] + rock->seed[1], e->offset[2] + rock->seed[2] };
    frame_says seeded = frame_seed(f, seed);
    if (seeded == FRAME_NO || rock->anchor_count == 0) return false;
    if (seeded == FRAME_YES && heights == FRAME_EXACT && band >= 0) heights = frame_band(p, f, e, rock, e->offset[1], band);
    if (seeded == FRAME_YES && heights != FRAME_EXACT) return heights == FRAME_YES;
    return entry_kept(p, column, e, i, j, k);
}

/* Room for `more` instances (doubling, as one push at a time would). */
static void placement_reserve(rocks_placement *out, uint32_t more) {
    uint32_t capacity = out->capacity;
    while (out->count + more > capacity) capacity = capacity ? capacity * 2 : 64;
    if (capacity == out->capacity) return;
    out->instances = core_realloc(out->instances, out->capacity * sizeof *out->instances, capacity * sizeof *out->instances);
    out->capacity = capacity;
}

/* The kept entries of a tile (bits of p->kept), placed in the tile's order. What depends on the
 * tile alone is worked out once: each offset's position and the key's lattice part. The bounds
 * grow by the index's bounds of each offset the tile keeps a rock at (offset_bounds): they hold
 * every kept rock, and no rock is read for them. */
static void place_kept(placer *p, int t, size_t words, int64_t i, int64_t j, int64_t k) {
    const rocks_tile *tile = &p->set->tiles[t];
    rocks_placement *out = p->out;
    const int64_t lattice[3] = { i, j, k };
    float position[3][3];             /* [axis][offset + 1] */
    for (int a = 0; a < 3; a++)
        for (int o = 0; o < 3; o++) position[a][o] = (float)(((double)lattice[a] + (o - 1)) * p->tile - out->origin[a]);
    uint32_t kept = 0;
    for (size_t w = 0; w < words; w++) kept += (uint32_t)__builtin_popcountll(p->kept[w]);
    placement_reserve(out, kept);
    uint64_t key = p->seed ^ ((uint64_t)i * 0x9e3779b97f4a7c15ull) ^ ((uint64_t)j * 0xc2b2ae3d27d4eb4full) ^
                   ((uint64_t)k * 0x165667b19e3779f9ull);
    rocks_instance *instance = out->instances + out->count;
    uint32_t offsets = 0;             /* bit offset_class: a rock kept with that offset */
    for (size_t w = 0; w < words; w++)
        for (uint64_t bits = p->kept[w]; bits; bits &= bits - 1) {
            uint32_t e = tile->first + (uint32_t)(w * 64 + (uint32_t)__builtin_ctzll(bits));
            const rocks_tile_entry *entry = &p->set->entries[e];
            int ox = entry->offset[0] + 1, oy = entry->offset[1] + 1, oz = entry->offset[2] + 1;
            *instance++ = (rocks_instance){ .position = { position[0][ox], position[1][oy], position[2][oz] },
                                            .rock = entry->rock, .key = (uint32_t)core_hash_u64(key ^ ((uint64_t)e << 40)) };
            offsets |= 1u << offset_class(entry->offset);
        }
    out->count += kept;
    const offset_bounds *bounds = &p->index->tile_bounds[t];
    for (; offsets; offsets &= offsets - 1) {
        const int c = __builtin_ctz(offsets), o[3] = { c % 3, c / 3 % 3, c / 9 };
        for (int a = 0; a < 3; a++) {
            out->bounds_min[a] = min_f(out->bounds_min[a], position[a][o[a]] + (float)(bounds->lo[c][a] * p->tile));
            out->bounds_max[a] = max_f(out->bounds_max[a], position[a][o[a]] + (float)(bounds->hi[c][a] * p->tile));
        }
    }
}

static int tile_at(const placer *p, int64_t i, int64_t j, int64_t k) {
    uint8_t colour[8];
    for (int c = 0; c < 8; c++)
        colour[c] = (uint8_t)rocks_lattice_colour(p->seed, i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
    return rocks_tile_index(colour);
}

/* The first of the sorted entries [first, last) whose y_lo is not below y. */
static uint32_t entries_from(const index_entry *entries, uint32_t first, uint32_t last, float y) {
    while (first < last) {
        uint32_t mid = first + (last - first) / 2;
        if (entries[mid].y_lo < y) first = mid + 1;
        else last = mid;
    }
    return first;
}

/* The heights, in the tile's frame (tile units), that a kept rock's anchors must reach: the rock
 * of the tile's columns, grown by the rounding of index_entry's heights. False when none. */
static bool tile_window(const placer *p, const tile_column *column, int64_t j, float window[2]) {
    if (!column) {
        window[0] = -INFINITY, window[1] = INFINITY;
        return true;
    }
    if (column->span[0] > column->span[1]) return false;
    double base = (double)j * p->tile;
    window[0] = (float)((column->span[0] - base) / p->tile) - 1e-4f;
    window[1] = (float)((column->span[1] - base) / p->tile) + 1e-4f;
    return window[1] >= p->index->y_lo && window[0] <= p->index->y_hi;
}

/* The tile at lattice point (i, j, k): every rock it lists whose seed is in the box, in the
 * tile's order. Only entries whose anchor heights meet the window are looked at (a range of the
 * index's order, then their y_hi); kept ones are marked, then placed in order. */
static void place_tile(placer *p, const tile_column *column, int64_t i, int64_t j, int64_t k) {
    float window[2];
    if (!tile_window(p, column, j, window)) return;
    const int t = tile_at(p, i, j, k);
    const rocks_tile *tile = &p->set->tiles[t];
    const index_entry *sorted = p->index->entries;
    uint32_t end = tile->first + tile->count;
    uint32_t from = entries_from(sorted, tile->first, end, window[0] - p->index->tallest);
    uint32_t to = entries_from(sorted, from, end, nextafterf(window[1], INFINITY));
    if (from == to) return;
    size_t words = (tile->count + 63) / 64;
    memset(p->kept, 0, words * sizeof *p->kept);
    int any = 0;
    tile_frame frame;
    if (column) tile_frame_make(p, column, i, j, k, &frame);
    if (column && column->same && frame.count == 1) {   /* the usual case, a loop of its own */
        for (uint32_t s = from; s < to; s++) {
            if (sorted[s].y_hi < window[0]) continue;
            int kept = frame_kept_one(p, &frame, &sorted[s]);
            if (kept < 0) kept = entry_kept(p, column, &sorted[s], i, j, k);
            uint32_t local = sorted[s].entry - tile->first;
            p->kept[local / 64] |= (uint64_t)kept << (local % 64);   /* no branch on the answer */
            any |= kept;
        }
    } else {
        for (uint32_t s = from; s < to; s++) {
            /* the rock a few entries on, which entry_kept reads if the cheap tests pass it: the
             * entries' rocks lie all over the index, and waiting on each cost ~7 % here */
            if (s + 8 < to) __builtin_prefetch(&p->index->rocks[sorted[s + 8].rock]);
            if (sorted[s].y_hi < window[0]) continue;
            int kept = !column ? entry_kept(p, column, &sorted[s], i, j, k)
                       : column->same ? frame_kept(p, &frame, column, &sorted[s], i, j, k)
                       : !frame_rejects(p, &frame, column, &sorted[s], p->index->entry_xz[s], j) &&
                         entry_kept(p, column, &sorted[s], i, j, k);
            uint32_t local = sorted[s].entry - tile->first;
            p->kept[local / 64] |= (uint64_t)kept << (local % 64);
            any |= kept;
        }
    }
    if (any) place_kept(p, t, words, i, j, k);
}

/* The tiles of lattice [lo, hi), in lattice order (k, j, i); each row of tile columns is worked out
 * once for every height above it. */
static void place_tiles(placer *p, const int64_t lo[3], const int64_t hi[3]) {
    size_t row = (size_t)(hi[0] - lo[0]);
    tile_column *columns = p->table ? core_alloc(row * sizeof *columns) : NULL;
    for (int64_t k = lo[2]; k < hi[2]; k++) {
        for (int64_t i = lo[0]; columns && i < hi[0]; i++) tile_column_make(p, i, k, &columns[i - lo[0]]);
        for (int64_t j = lo[1]; j < hi[1]; j++)
            for (int64_t i = lo[0]; i < hi[0]; i++) place_tile(p, columns ? &columns[i - lo[0]] : NULL, i, j, k);
    }
    if (columns) core_free(columns, row * sizeof *columns);
}

static bool place_desc_check(const rocks_place_desc *desc) {
    if (!desc || !desc->tiles) {
        core_log_error("rocks", "rocks_place_box needs .tiles");
        return false;
    }
    if (!desc->support && !desc->world) {
        core_log_error("rocks", "rocks_place_box needs .world or .support");
        return false;
    }
    if (desc->tile_size < 0 || !isfinite(desc->tile_size) || desc->threshold < 0 || desc->threshold > 1) {
        core_log_error("rocks", "rocks_place_box: tile_size %g (> 0) or threshold %g (0 … 1) out of range",
                   (double)desc->tile_size, (double)desc->threshold);
        return false;
    }
    if (desc->index && desc->index->set != desc->tiles) {
        core_log_error("rocks", "rocks_place_box: .index was made for another tile set");
        return false;
    }
    return true;
}

/* The colouring seed a desc means (its own, else the world's generation seed, else 1). */
static uint64_t place_seed(const rocks_place_desc *desc) {
    if (desc->seed) return desc->seed;
    if (desc->world) return terrain_world_generation(desc->world)->seed ^ 0x726f636b73ull;
    return 1;
}

static void placer_init(placer *p, const rocks_place_desc *desc, const rocks_place_index *index,
                        const double min[3], const double max[3], rocks_placement *out) {
    *p = (placer){
        .desc = desc, .set = desc->tiles, .index = index,
        .tile = desc->tile_size > 0 ? desc->tile_size : PLACE_DEFAULT_TILE,
        .seed = place_seed(desc),
        .threshold = desc->threshold > 0 ? desc->threshold : PLACE_DEFAULT_THRESHOLD,
        .out = out,
    };
    /* a hair over the index's reach: the tile and the rounding of a·tile */
    for (int a = 0; a < 3; a++) p->reach[a] = (double)index->reach[a] * p->tile * (1 + 1e-6) + 1e-6;
    p->bury = 2.0f * p->set->max_radius * (float)p->tile;
    for (uint32_t n = 0; n <= NEED_CACHED; n++) {
        uint32_t need = (uint32_t)ceilf(p->threshold * (float)n - 1e-4f);
        p->need[n] = (uint8_t)(need < 1 ? 1 : need);
    }
    memcpy(p->min, min, sizeof p->min);
    memcpy(p->max, max, sizeof p->max);
}

bool rocks_place_box(const rocks_place_desc *desc, const double min[3], const double max[3], rocks_placement *out) {
    if (!place_desc_check(desc)) return false;
    rocks_place_index *own = desc->index ? NULL : rocks_place_index_create(desc->tiles);
    placer p;
    placer_init(&p, desc, desc->index ? desc->index : own, min, max, out);
    memcpy(out->origin, min, sizeof out->origin);
    out->count = 0;
    for (int a = 0; a < 3; a++) out->bounds_min[a] = INFINITY, out->bounds_max[a] = -INFINITY;

    column_table table = { 0 };
    double y_lo = min[1], y_hi = max[1];
    if (!desc->support) {
        table_build(&table, desc->world, min[0] - p.reach[0], min[2] - p.reach[2], max[0] + p.reach[0],
                    max[2] + p.reach[2]);
        p.table = &table;
        y_lo = fmax(y_lo, (double)table.y_lo - p.reach[1]);
        y_hi = fmin(y_hi, (double)table.y_hi + p.reach[1]);
    }
    if (y_lo < y_hi) {
        int64_t lo[3] = { (int64_t)floor(min[0] / p.tile), (int64_t)floor(y_lo / p.tile), (int64_t)floor(min[2] / p.tile) };
        int64_t hi[3] = { (int64_t)ceil(max[0] / p.tile), (int64_t)ceil(y_hi / p.tile), (int64_t)ceil(max[2] / p.tile) };
        size_t words = (p.index->most_entries + 63) / 64 + 1;
        p.kept = core_alloc(words * sizeof *p.kept);
        place_tiles(&p, lo, hi);
        core_free(p.kept, words * sizeof *p.kept);
    }
    if (p.table) table_free(&table);
    rocks_place_index_destroy(own);
    if (out->count == 0)
        for (int a = 0; a < 3; a++) out->bounds_min[a] = out->bounds_max[a] = 0.0f;
    return true;
}

void rocks_placement_free(rocks_placement *placement) {
    if (!placement) return;
    core_free(placement->instances, placement->capacity * sizeof *placement->instances);
    memset(placement, 0, sizeof *placement);
}
