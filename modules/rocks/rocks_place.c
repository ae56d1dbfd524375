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
 * rock intervals; a cell of a tile whose neighbourhood holds no interval is skipped whole, so
 * the rocks far from any rock layer cost nothing but that test.
 */
#include "rocks_world_internal.h"

#include <math.h>
#include <string.h>

#include "core/core.h"

#define PLACE_DEFAULT_TILE 3.0f
#define PLACE_DEFAULT_THRESHOLD 0.6f
#define INTERVALS_PER_COLUMN 4          /* rock intervals kept per column (more merge) */

int rocks_lattice_colour(uint64_t seed, int64_t i, int64_t j, int64_t k) {
    uint64_t h = core_hash_combine(core_hash_combine(core_hash_combine(seed ^ 0x726f636b73ull, (uint64_t)i),
                                                     (uint64_t)j), (uint64_t)k);
    return (int)(h >> 63);
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
    float y_lo, y_hi;                 /* over all intervals */
    size_t bytes;
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
    core_free(t->count, t->bytes);
    core_free(t->intervals, (size_t)t->w * (size_t)t->d * INTERVALS_PER_COLUMN * sizeof *t->intervals);
    memset(t, 0, sizeof *t);
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
    t->bytes = columns;
    t->y_lo = INFINITY, t->y_hi = -INFINITY;
    const int N = TERRAIN_CHUNK_COLUMNS;
    terrain_layer layers[64];
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
                    if (tx < 0 || tx >= t->w) continue;
                    int n = terrain_stacks_column(stacks, i, k, layers, 64);
                    if (n > 64) n = 64;
                    size_t c = (size_t)tz * (size_t)t->w + (size_t)tx;
                    int got = column_intervals(layers, n, &t->intervals[c * INTERVALS_PER_COLUMN]);
                    t->count[c] = (uint8_t)got;
                    for (int g = 0; g < got; g++) {
                        t->y_lo = fminf(t->y_lo, t->intervals[c * INTERVALS_PER_COLUMN + g].lo);
                        t->y_hi = fmaxf(t->y_hi, t->intervals[c * INTERVALS_PER_COLUMN + g].hi);
                    }
                }
            }
        }
    }
}

/* floor() without the libm call that baseline x86-64 makes of it (no SSE4.1 rounding): the
 * anchor tests, ten a rock, are most of a placement's time. */
static inline int64_t floor_int(double v) {
    int64_t i = (int64_t)v;
    return i - (v < (double)i);
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
    for (int i = 0; i < n; i++)
        if (p[1] >= iv[i].lo && p[1] < iv[i].hi) return true;
    return false;
}

/* Whether any rock interval meets the box [lo, hi] (world metres). */
static bool table_meets(const column_table *t, const double lo[3], const double hi[3]) {
    if (hi[1] < t->y_lo || lo[1] > t->y_hi) return false;
    for (double z = floor(lo[2]); z <= hi[2]; z += 1.0)
        for (double x = floor(lo[0]); x <= hi[0]; x += 1.0) {
            int n;
            const rock_interval *iv = table_column(t, x, z, &n);
            for (int i = 0; i < n; i++)
                if (iv[i].hi >= lo[1] && iv[i].lo <= hi[1]) return true;
        }
    return false;
}

/* The lowest and highest rock of the columns under the footprint [lo, hi] (x, z); false when
 * none holds any. */
static bool table_span(const column_table *t, const double lo[3], const double hi[3], float *y_lo, float *y_hi) {
    *y_lo = INFINITY, *y_hi = -INFINITY;
    for (double z = floor(lo[2]); z <= hi[2]; z += 1.0)
        for (double x = floor(lo[0]); x <= hi[0]; x += 1.0) {
            int n;
            const rock_interval *iv = table_column(t, x, z, &n);
            for (int i = 0; i < n; i++) *y_lo = fminf(*y_lo, iv[i].lo), *y_hi = fmaxf(*y_hi, iv[i].hi);
        }
    return *y_lo <= *y_hi;
}

/* Buried: the solid run over the seed's rock layer rises more than `depth` above the seed. */
static bool table_buried(const column_table *t, const double seed[3], float depth) {
    int n;
    const rock_interval *iv = table_column(t, seed[0], seed[2], &n);
    for (int i = 0; i < n; i++)
        if (seed[1] >= iv[i].lo - depth && seed[1] < iv[i].hi + depth) return iv[i].run_top - seed[1] > depth;
    return false;
}

/* ---- placement ------------------------------------------------------------------------------ */

typedef struct placer {
    const rocks_place_desc *desc;
    const rocks_tileset *set;
    double tile;                      /* metres */
    uint64_t seed;
    float threshold;
    const column_table *table;        /* NULL: desc->support */
    double min[3], max[3];
    float reach;                      /* metres: the largest rock radius */
    rocks_placement *out;
} placer;

static bool support_inside(const placer *p, const double point[3]) {
    if (p->table) return table_inside(p->table, point);
    return p->desc->support(p->desc->support_user, point);
}

static bool rock_kept(const placer *p, const rocks_rock *rock, const double origin[3]) {
    const float (*anchors)[3] = (const float (*)[3])p->set->anchors + rock->anchor_first;
    uint32_t n = rock->anchor_count;
    uint32_t need = (uint32_t)ceilf(p->threshold * (float)n - 1e-4f);
    if (need < 1) need = 1;
    uint32_t inside = 0;
    for (uint32_t a = 0; a < n; a++) {
        double q[3] = { origin[0] + anchors[a][0] * p->tile, origin[1] + anchors[a][1] * p->tile,
                        origin[2] + anchors[a][2] * p->tile };
        if (support_inside(p, q)) inside++;
        if (inside >= need) return true;
        if (inside + (n - a - 1) < need) return false;
    }
    return inside >= need;
}

static void placement_push(rocks_placement *out, const rocks_instance *instance, const rocks_rock *rock, double tile) {
    if (out->count == out->capacity) {
        uint32_t capacity = out->capacity ? out->capacity * 2 : 64;
        out->instances = core_realloc(out->instances, out->capacity * sizeof *out->instances,
                                      capacity * sizeof *out->instances);
        out->capacity = capacity;
    }
    out->instances[out->count++] = *instance;
    for (int a = 0; a < 3; a++) {
        out->bounds_min[a] = fminf(out->bounds_min[a], instance->position[a] + (float)(rock->bounds_min[a] * tile));
        out->bounds_max[a] = fmaxf(out->bounds_max[a], instance->position[a] + (float)(rock->bounds_max[a] * tile));
    }
}

/* The tile at lattice point (i, j, k): every rock it lists whose seed is in the box. */
static void place_tile(placer *p, int64_t i, int64_t j, int64_t k) {
    const rocks_tileset *set = p->set;
    const double tile = p->tile;
    double lo[3] = { (double)i * tile - p->reach, (double)j * tile - p->reach, (double)k * tile - p->reach };
    double hi[3] = { (double)(i + 1) * tile + p->reach, (double)(j + 1) * tile + p->reach,
                     (double)(k + 1) * tile + p->reach };
    if (p->table && !table_meets(p->table, lo, hi)) return;
    uint8_t colour[8];
    for (int c = 0; c < 8; c++)
        colour[c] = (uint8_t)rocks_lattice_colour(p->seed, i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
    int t = rocks_tile_index(colour);
    const int n = set->desc.cells;
    /* Per cell of the tile: can a rock seeded in it reach a rock layer? Per column of cells the
     * span of rock under its footprint grown by the reach, then per cell its height range
     * against that span: conservative (a cave between two layers counts as near), never
     * skipping a rock the anchors would keep. */
    uint8_t near[8 * 8 * 8];
    for (int cz = 0; cz < n; cz++)
        for (int cx = 0; cx < n; cx++) {
            double flo[3] = { ((double)i + (double)cx / n) * tile - p->reach, 0, ((double)k + (double)cz / n) * tile - p->reach };
            double fhi[3] = { flo[0] + tile / n + 2 * p->reach, 0, flo[2] + tile / n + 2 * p->reach };
            float span_lo = 0, span_hi = -1;
            bool any = p->table ? table_span(p->table, flo, fhi, &span_lo, &span_hi) : true;
            for (int cy = 0; cy < n; cy++) {
                double ylo = ((double)j + (double)cy / n) * tile - p->reach, yhi = ylo + tile / n + 2 * p->reach;
                near[(cz * n + cy) * n + cx] = !p->table || (any && yhi >= span_lo && ylo <= span_hi);
            }
        }
    const float bury = 2.0f * set->max_radius * (float)tile;
    const rocks_tile *entries = &set->tiles[t];
    for (uint32_t e = entries->first; e < entries->first + entries->count; e++) {
        const rocks_tile_entry *entry = &set->entries[e];
        const rocks_rock *rock = &set->rocks[entry->rock];
        int cell[3];
        for (int a = 0; a < 3; a++) {   /* the seed lies in this tile: offset + seed ∈ [0, 1) */
            cell[a] = (int)(((float)entry->offset[a] + rock->seed[a]) * (float)n);
            cell[a] = cell[a] < 0 ? 0 : cell[a] >= n ? n - 1 : cell[a];
        }
        int c = (cell[2] * n + cell[1]) * n + cell[0];
        if (!near[c]) continue;
        double origin[3] = { ((double)i + entry->offset[0]) * tile, ((double)j + entry->offset[1]) * tile,
                             ((double)k + entry->offset[2]) * tile };
        double seed[3] = { origin[0] + rock->seed[0] * tile, origin[1] + rock->seed[1] * tile,
                           origin[2] + rock->seed[2] * tile };
        bool in_box = true;
        for (int a = 0; a < 3; a++) in_box = in_box && seed[a] >= p->min[a] && seed[a] < p->max[a];
        if (!in_box) continue;
        if (p->table && table_buried(p->table, seed, bury)) continue;
        if (!rock_kept(p, rock, origin)) continue;
        rocks_instance instance = {
            .position = { (float)(origin[0] - p->out->origin[0]), (float)(origin[1] - p->out->origin[1]),
                          (float)(origin[2] - p->out->origin[2]) },
            .rock = entry->rock,
            .key = (uint32_t)core_hash_u64(p->seed ^ ((uint64_t)i * 0x9e3779b97f4a7c15ull) ^
                                           ((uint64_t)j * 0xc2b2ae3d27d4eb4full) ^ ((uint64_t)k * 0x165667b19e3779f9ull) ^
                                           ((uint64_t)e << 40)),
        };
        placement_push(p->out, &instance, rock, tile);
    }
}

static bool place_desc_check(const rocks_place_desc *desc) {
    if (!desc || !desc->tiles) {
        core_error("rocks", "rocks_place_box needs .tiles");
        return false;
    }
    if (!desc->support && !desc->world) {
        core_error("rocks", "rocks_place_box needs .world or .support");
        return false;
    }
    if (desc->tile_size < 0 || !isfinite(desc->tile_size) || desc->threshold < 0 || desc->threshold > 1) {
        core_error("rocks", "rocks_place_box: tile_size %g (> 0) or threshold %g (0 … 1) out of range",
                   (double)desc->tile_size, (double)desc->threshold);
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

bool rocks_place_box(const rocks_place_desc *desc, const double min[3], const double max[3], rocks_placement *out) {
    if (!place_desc_check(desc)) return false;
    placer p = {
        .desc = desc, .set = desc->tiles,
        .tile = desc->tile_size > 0 ? desc->tile_size : PLACE_DEFAULT_TILE,
        .seed = place_seed(desc),
        .threshold = desc->threshold > 0 ? desc->threshold : PLACE_DEFAULT_THRESHOLD,
        .out = out,
    };
    p.reach = p.set->max_radius * (float)p.tile;
    memcpy(p.min, min, sizeof p.min);
    memcpy(p.max, max, sizeof p.max);
    memcpy(out->origin, min, sizeof out->origin);
    out->count = 0;
    for (int a = 0; a < 3; a++) out->bounds_min[a] = INFINITY, out->bounds_max[a] = -INFINITY;

    column_table table = { 0 };
    double y_lo = min[1], y_hi = max[1];
    if (!desc->support) {
        table_build(&table, desc->world, min[0] - p.reach - 1, min[2] - p.reach - 1, max[0] + p.reach + 1,
                    max[2] + p.reach + 1);
        p.table = &table;
        y_lo = fmax(y_lo, (double)table.y_lo - p.reach);
        y_hi = fmin(y_hi, (double)table.y_hi + p.reach);
    }
    if (y_lo < y_hi) {
        int64_t i0 = (int64_t)floor(min[0] / p.tile), i1 = (int64_t)ceil(max[0] / p.tile);
        int64_t j0 = (int64_t)floor(y_lo / p.tile), j1 = (int64_t)ceil(y_hi / p.tile);
        int64_t k0 = (int64_t)floor(min[2] / p.tile), k1 = (int64_t)ceil(max[2] / p.tile);
        for (int64_t k = k0; k < k1; k++)
            for (int64_t j = j0; j < j1; j++)
                for (int64_t i = i0; i < i1; i++) place_tile(&p, i, j, k);
    }
    if (p.table) table_free(&table);
    if (out->count == 0)
        for (int a = 0; a < 3; a++) out->bounds_min[a] = out->bounds_max[a] = 0.0f;
    return true;
}

void rocks_placement_free(rocks_placement *placement) {
    if (!placement) return;
    core_free(placement->instances, placement->capacity * sizeof *placement->instances);
    memset(placement, 0, sizeof *placement);
}
