/* terrain_columns.c — a mutable region of columns for editing (000 §3.4, §4).
 *
 * Stacks are packed and immutable; editing and stabilization need columns they can change a
 * quantum at a time, laid out for the stabilization loop. A column here is two parts:
 *
 *   lower layers   everything up to and including its highest stable layer (bedrock or a custom
 *                  material), as {material, quanta} in a pool: caves, overhangs, the granular
 *                  material lying in them. Stabilization never moves these (000 §3.4: bedrock
 *                  "is always considered as stable", and a cave roof holds what lies on it).
 *   the pile       sand, rocks and water above that, in this order (000 §3.4, Figure 6), kept as
 *                  heights in quanta above TERRAIN_FLOOR_Y in padded arrays: base (top of the
 *                  lower layers), sand_top = base + sand, ground = sand_top + rocks, plus the
 *                  water thickness. This is all the stabilization loop reads and writes.
 *
 * A column read from stacks is split from the top: its last layer if water, then rocks, then
 * sand make the pile; the rest is lower. Writing back pushes the lower layers and the pile in
 * order, so an unedited column comes back layer for layer (the stacks builder merges the same
 * adjacent materials the split separated). A column whose lower layers are out of 000 §3.4's
 * order (a run between stable layers not sorted sand, rocks, water, air; or lower layers that do
 * not end on a stable one) is flagged unsorted; stabilization sorts it before moving anything.
 */
#include "terrain/edit/terrain_edit_internal.h"

#include "core/core.h"

#include <assert.h>
#include <math.h>
#include <string.h>

const int8_t terrain__dir[8][2] = { { -1, -1 }, { 0, -1 }, { 1, -1 }, { -1, 0 },
                                    { 1, 0 },   { -1, 1 }, { 0, 1 },  { 1, 1 } };

/* Rank in a run between stable layers (000 §3.4: "sand, rocks and air"; water, being a fluid,
 * sits on the granular material and under the air). */
static int run_rank(uint32_t material) {
    switch (material) {
    case TERRAIN_SAND: return 0;
    case TERRAIN_ROCKS: return 1;
    case TERRAIN_WATER: return 2;
    default: return 3;                             /* air */
    }
}

static size_t flat(const terrain_columns *c, int i, int k) {
    return (size_t)k * (size_t)c->width + (size_t)i;
}

/* ---- creation -------------------------------------------------------------------------- */

static bool valid_desc(const terrain_columns_desc *d) {
    if (d->width < 1 || d->depth < 1 || d->width > TERRAIN__MAX_SIDE || d->depth > TERRAIN__MAX_SIDE ||
        (int64_t)d->width * d->depth > TERRAIN__MAX_REGION_COLUMNS) {
        core_log_error("terrain", "columns: a region of %d x %d columns (each side 1 ... %d, at most %d in all)",
                   d->width, d->depth, TERRAIN__MAX_SIDE, TERRAIN__MAX_REGION_COLUMNS);
        return false;
    }
    const int64_t limit = (int64_t)1 << 52;
    if (d->x < -limit || d->x > limit || d->z < -limit || d->z > limit) {
        core_log_error("terrain", "columns: a region at column (%lld, %lld), beyond +-2^52",
                   (long long)d->x, (long long)d->z);
        return false;
    }
    return true;
}

terrain_columns *terrain_columns_create(const terrain_columns_desc *desc) {
    if (!desc || !valid_desc(desc)) return NULL;
    terrain_columns *c = core_calloc(1, sizeof *c);
    c->x0 = desc->x;
    c->z0 = desc->z;
    c->width = desc->width;
    c->depth = desc->depth;
    c->pitch = desc->width + 2;
    c->cells = (size_t)c->pitch * (size_t)(desc->depth + 2);
    size_t columns = (size_t)desc->width * (size_t)desc->depth, rows = (size_t)desc->depth + 2;
    c->base = core_calloc(c->cells, sizeof *c->base);
    c->sand_top = core_calloc(c->cells, sizeof *c->sand_top);
    c->ground = core_calloc(c->cells, sizeof *c->ground);
    c->changed = core_calloc(c->cells, sizeof *c->changed);
    c->gift_sand = core_calloc(c->cells, sizeof *c->gift_sand);
    c->gift_rocks = core_calloc(c->cells, sizeof *c->gift_rocks);
    c->changed_span = core_calloc(rows, sizeof *c->changed_span);
    c->row_moved = core_calloc(rows, sizeof *c->row_moved);
    c->row_gifts = core_calloc(rows, sizeof *c->row_gifts);
    c->water = core_calloc(columns, sizeof *c->water);
    c->lower_start = core_calloc(columns, sizeof *c->lower_start);
    c->lower_count = core_calloc(columns, sizeof *c->lower_count);
    c->lower_capacity = core_calloc(columns, sizeof *c->lower_capacity);
    c->flags = core_calloc(columns, sizeof *c->flags);
    /* Never NULL, so that an empty column's layers are a valid (empty) range of it. */
    c->pool_capacity = 64;
    c->pool = core_alloc(c->pool_capacity * sizeof *c->pool);
    c->clock = TERRAIN__CLOCK_START;
    /* The halo starts as walls; the stabilizer overwrites the sides that have a neighbour. */
    for (size_t n = 0; n < c->cells; n++) c->base[n] = c->sand_top[n] = c->ground[n] = TERRAIN__WALL_HEIGHT;
    for (int k = 0; k < c->depth; k++)
        for (int i = 0; i < c->width; i++) {
            size_t n = terrain__cell(c, i, k);
            c->base[n] = c->sand_top[n] = c->ground[n] = 0;
        }
    return c;
}

void terrain_columns_destroy(terrain_columns *c) {
    if (!c) return;
    size_t columns = (size_t)c->width * (size_t)c->depth, rows = (size_t)c->depth + 2;
    core_free(c->base, c->cells * sizeof *c->base);
    core_free(c->sand_top, c->cells * sizeof *c->sand_top);
    core_free(c->ground, c->cells * sizeof *c->ground);
    core_free(c->changed, c->cells * sizeof *c->changed);
    core_free(c->gift_sand, c->cells * sizeof *c->gift_sand);
    core_free(c->gift_rocks, c->cells * sizeof *c->gift_rocks);
    core_free(c->changed_span, rows * sizeof *c->changed_span);
    core_free(c->row_moved, rows * sizeof *c->row_moved);
    core_free(c->row_gifts, rows * sizeof *c->row_gifts);
    core_free(c->water, columns * sizeof *c->water);
    core_free(c->lower_start, columns * sizeof *c->lower_start);
    core_free(c->lower_count, columns * sizeof *c->lower_count);
    core_free(c->lower_capacity, columns * sizeof *c->lower_capacity);
    core_free(c->flags, columns * sizeof *c->flags);
    core_free(c->pool, c->pool_capacity * sizeof *c->pool);
    core_free(c, sizeof *c);
}

terrain_columns_desc terrain_columns_extent(const terrain_columns *c) {
    return (terrain_columns_desc){ .x = c->x0, .z = c->z0, .width = c->width, .depth = c->depth };
}

/* ---- the lower layers' pool ------------------------------------------------------------- */

/* Drops the space of replaced columns once it is most of the pool: copies every column's
 * layers to a fresh pool, in column order. */
static void pool_compact(terrain_columns *c) {
    size_t columns = (size_t)c->width * (size_t)c->depth, used = c->pool_count - c->pool_garbage;
    size_t capacity = used > 8 ? used : 8;
    terrain__clayer *pool = core_alloc(capacity * sizeof *pool);
    size_t at = 0;
    for (size_t n = 0; n < columns; n++) {
        memcpy(pool + at, c->pool + c->lower_start[n], c->lower_count[n] * sizeof *pool);
        c->lower_start[n] = (uint32_t)at;
        c->lower_capacity[n] = c->lower_count[n];
        at += c->lower_count[n];
    }
    core_free(c->pool, c->pool_capacity * sizeof *c->pool);
    c->pool = pool;
    c->pool_count = at;
    c->pool_capacity = capacity;
    c->pool_garbage = 0;
}

/* Room for `count` lower layers of column n; returns where they go. */
static terrain__clayer *lower_reserve(terrain_columns *c, size_t n, int count) {
    if (count <= c->lower_capacity[n]) return c->pool + c->lower_start[n];
    if (count > UINT16_MAX) core_fatal("terrain", "a column of over 65535 layers");
    c->pool_garbage += c->lower_capacity[n];
    if (c->pool_garbage > 4096 && c->pool_garbage * 2 > c->pool_count) pool_compact(c);
    if (c->pool_count + (size_t)count > UINT32_MAX) core_fatal("terrain", "a region of over 2^32 layers");
    c->pool = core_grow(c->pool, &c->pool_capacity, c->pool_count + (size_t)count, sizeof *c->pool);
    c->lower_start[n] = (uint32_t)c->pool_count;
    c->lower_capacity[n] = (uint16_t)count;
    c->pool_count += (size_t)count;
    return c->pool + c->lower_start[n];
}

/* ---- columns: split, store, read ----------------------------------------------------------- */

/* Whether lower layers are in 000 §3.4's order: empty or ending on a stable layer, and every
 * run between stable layers sorted with each material once. */
static bool lower_sorted(const terrain__clayer *layers, int count) {
    int rank = -1;
    for (int l = 0; l < count; l++) {
        if (terrain__stable_material(layers[l].material)) {
            rank = -1;
            continue;
        }
        int r = run_rank(layers[l].material);
        if (r <= rank) return false;
        rank = r;
    }
    return count == 0 || terrain__stable_material(layers[count - 1].material);
}

/* Appends a layer, merging it into the previous one of the same material. */
static int push_layer(terrain__clayer *out, int count, uint32_t material, int32_t quanta) {
    if (quanta <= 0) return count;
    if (count > 0 && out[count - 1].material == material) {
        out[count - 1].quanta += quanta;
        return count;
    }
    out[count] = (terrain__clayer){ material, quanta };
    return count + 1;
}

void terrain__columns_store(terrain_columns *c, int i, int k, const terrain__clayer *layers, int count) {
    /* Air on top is implicit; then the pile, taken from the top: water, rocks, sand. */
    while (count > 0 && (layers[count - 1].material == TERRAIN_AIR || layers[count - 1].quanta <= 0)) count--;
    int32_t pile[3] = { 0, 0, 0 };                 /* sand, rocks, water */
    const uint32_t order[3] = { TERRAIN_WATER, TERRAIN_ROCKS, TERRAIN_SAND };
    for (int p = 0; p < 3; p++)
        while (count > 0 && layers[count - 1].material == order[p]) pile[2 - p] += layers[--count].quanta;

    size_t n = flat(c, i, k);
    terrain__clayer *lower = lower_reserve(c, n, count);
    int stored = 0;
    int64_t base = 0;
    for (int l = 0; l < count; l++) {
        stored = push_layer(lower, stored, layers[l].material, layers[l].quanta);
        base += layers[l].quanta;
    }
    c->lower_count[n] = (uint16_t)stored;
    bool was_unsorted = c->flags[n] & TERRAIN__COLUMN_UNSORTED;
    bool unsorted = !lower_sorted(lower, stored);
    c->flags[n] = (uint8_t)((c->flags[n] & ~TERRAIN__COLUMN_UNSORTED) | (unsorted ? TERRAIN__COLUMN_UNSORTED : 0));
    c->unsorted = c->unsorted - was_unsorted + unsorted;
    /* Sand or rocks among the lower layers lie under a stable layer: a pile on a cave floor. */
    bool was_cave = c->flags[n] & TERRAIN__COLUMN_CAVE_PILE, cave = false;
    for (int l = 0; l < stored && !cave; l++) cave = lower[l].material == TERRAIN_SAND || lower[l].material == TERRAIN_ROCKS;
    c->flags[n] = (uint8_t)((c->flags[n] & ~TERRAIN__COLUMN_CAVE_PILE) | (cave ? TERRAIN__COLUMN_CAVE_PILE : 0));
    c->cave_piles = c->cave_piles - was_cave + cave;

    size_t cell = terrain__cell(c, i, k);
    c->base[cell] = (int32_t)base;
    c->sand_top[cell] = (int32_t)(base + pile[0]);
    c->ground[cell] = (int32_t)(base + pile[0] + pile[1]);
    c->water[n] = pile[2];
}

int terrain__columns_layers(const terrain_columns *c, int i, int k, terrain__clayer **scratch, size_t *capacity) {
    size_t n = flat(c, i, k), cell = terrain__cell(c, i, k);
    int lower = c->lower_count[n];
    *scratch = core_grow(*scratch, capacity, (size_t)lower + 3, sizeof **scratch);
    terrain__clayer *out = *scratch;
    const terrain__clayer *from = c->pool + c->lower_start[n];
    int count = 0;
    for (int l = 0; l < lower; l++) count = push_layer(out, count, from[l].material, from[l].quanta);
    count = push_layer(out, count, TERRAIN_SAND, c->sand_top[cell] - c->base[cell]);
    count = push_layer(out, count, TERRAIN_ROCKS, c->ground[cell] - c->sand_top[cell]);
    count = push_layer(out, count, TERRAIN_WATER, c->water[n]);
    return count;
}

void terrain__columns_touch(terrain_columns *c, int i, int k) {
    c->changed[terrain__cell(c, i, k)] = c->clock;
    c->flags[flat(c, i, k)] |= TERRAIN__COLUMN_EDITED;
    c->last_change = c->clock;
    terrain__span_extend(&c->changed_span[k + 1], i, c->clock);
}

void terrain__columns_set_clock(terrain_columns *c, uint32_t clock) {
    if (clock == c->clock) return;
    /* Stamps that the next nine passes would still look at become "changed now"; older ones
     * never match a later pass. */
    uint32_t old = c->clock;
    for (int k = -1; k <= c->depth; k++) {
        terrain__span *span = &c->changed_span[k + 1];
        if (!terrain__recent(span->clock, old + 1)) continue;
        span->clock = clock;
        for (int i = -1; i <= c->width; i++) {
            uint32_t *stamp = &c->changed[terrain__cell(c, i, k)];
            *stamp = terrain__recent(*stamp, old + 1) ? clock : 0;
        }
    }
    if (terrain__recent(c->last_change, old + 1)) c->last_change = clock;
    c->clock = clock;
}

/* ---- sorting (000 §3.4, Figure 6) --------------------------------------------------------- */

/* Merges the granular layers of each run between stable layers and orders them sand, rocks,
 * water, air; the top run's air is dropped (implicit). `in` and `out` may not overlap; out
 * needs room for count + 3 layers. */
static int sort_layers(const terrain__clayer *in, int count, terrain__clayer *out) {
    int32_t run[4] = { 0, 0, 0, 0 };
    const uint32_t materials[4] = { TERRAIN_SAND, TERRAIN_ROCKS, TERRAIN_WATER, TERRAIN_AIR };
    int n = 0;
    for (int l = 0; l < count; l++) {
        if (!terrain__stable_material(in[l].material)) {
            run[run_rank(in[l].material)] += in[l].quanta;
            continue;
        }
        for (int r = 0; r < 4; r++) n = push_layer(out, n, materials[r], run[r]);
        memset(run, 0, sizeof run);
        n = push_layer(out, n, in[l].material, in[l].quanta);
    }
    for (int r = 0; r < 3; r++) n = push_layer(out, n, materials[r], run[r]);
    return n;
}

void terrain__columns_sort(terrain_columns *c, int i, int k, terrain__clayer **scratch, size_t *capacity) {
    int count = terrain__columns_layers(c, i, k, scratch, capacity);
    /* Sorted layers go after the column's own in the same scratch. */
    *scratch = core_grow(*scratch, capacity, 2 * (size_t)count + 3, sizeof **scratch);
    terrain__clayer *in = *scratch, *out = in + count;
    int sorted = sort_layers(in, count, out);
    bool same = sorted == count && memcmp(in, out, (size_t)count * sizeof *in) == 0;
    terrain__columns_store(c, i, k, out, sorted);
    if (!same) terrain__columns_touch(c, i, k);
}

/* ---- spaces inside a column (terrain_edit_internal.h, terrain__gap) ------------------------ */

int terrain__column_gaps(const terrain__clayer *layers, int count, terrain__gap *gaps, int capacity) {
    int n = 0, first = 0;
    int64_t bottom = 0, floor = 0;
    terrain__gap g = { 0 };
    for (int l = 0; l <= count; l++) {
        bool stable = l < count && terrain__stable_material(layers[l].material);
        if (l == count || stable) {
            /* The space [floor, bottom) ends here: at a stable layer, or open at the top. */
            g.first = first, g.end = l, g.floor = floor;
            g.ceiling = l == count ? INT64_MAX : bottom;
            if ((l == count || bottom > floor) && n < capacity) gaps[n++] = g;
            g = (terrain__gap){ 0 };
            if (l < count) {
                bottom += layers[l].quanta;
                floor = bottom;
                first = l + 1;
            }
            continue;
        }
        g.amount[run_rank(layers[l].material)] += layers[l].quanta;
        bottom += layers[l].quanta;
    }
    return n;
}

int terrain__gap_nearest(const terrain__gap *gaps, int count, int64_t height) {
    int best = count - 1;
    int64_t best_distance = INT64_MAX;
    for (int g = 0; g < count; g++) {
        int64_t d = height < gaps[g].floor ? gaps[g].floor - height
                    : height >= gaps[g].ceiling ? height - gaps[g].ceiling + 1 : 0;
        if (d <= best_distance) best = g, best_distance = d;
    }
    return best;
}

int terrain__gap_holding(const terrain__gap *gaps, int count, int64_t height) {
    for (int g = 0; g < count; g++)
        if (height >= gaps[g].floor && height < gaps[g].ceiling) return g;
    return -1;
}

void terrain__columns_rewrite_gap(terrain_columns *c, int i, int k, const terrain__clayer *layers, int count,
                                  const terrain__gap *gap, const int64_t amount[4], terrain__clayer **scratch,
                                  size_t *capacity) {
    /* 000 §3.4's order inside the space; air on top of the open space is implicit. */
    const uint32_t materials[4] = { TERRAIN_SAND, TERRAIN_ROCKS, TERRAIN_WATER, TERRAIN_AIR };
    size_t room = (size_t)count + 4;
    *scratch = core_grow(*scratch, capacity, room, sizeof **scratch);
    terrain__clayer *out = *scratch;
    int n = 0;
    for (int l = 0; l < gap->first; l++) n = push_layer(out, n, layers[l].material, layers[l].quanta);
    for (int r = 0; r < 4; r++) n = push_layer(out, n, materials[r], (int32_t)amount[r]);
    for (int l = gap->end; l < count; l++) n = push_layer(out, n, layers[l].material, layers[l].quanta);
    terrain__columns_store(c, i, k, out, n);
}

int32_t terrain__columns_insert(terrain_columns *c, int i, int k, int64_t height, uint32_t material, int32_t quanta) {
    if (quanta <= 0) return 0;
    terrain__clayer *scratch = NULL, *rewritten = NULL;
    size_t capacity = 0, rewritten_capacity = 0;
    if (c->flags[flat(c, i, k)] & TERRAIN__COLUMN_UNSORTED) terrain__columns_sort(c, i, k, &scratch, &capacity);
    int count = terrain__columns_layers(c, i, k, &scratch, &capacity);
    /* Every space follows a stable layer but the first: at most count + 1 of them. */
    terrain__gap *gaps = core_alloc(((size_t)count + 1) * sizeof *gaps);
    int gap_count = terrain__column_gaps(scratch, count, gaps, count + 1);
    const terrain__gap *g = &gaps[terrain__gap_nearest(gaps, gap_count, height)];
    int64_t room;
    if (terrain__gap_open(g)) {
        int64_t top = 0;
        for (int l = 0; l < count; l++) top += scratch[l].quanta;
        /* Water on the pile is displaced (terrain_deposit): the column grows by what exceeds it. */
        int64_t growth_room = TERRAIN__COLUMN_MAX_QUANTA - 1 - top;
        room = CORE_MAX(growth_room + g->amount[2], (int64_t)0);
    } else {
        room = g->amount[2] + g->amount[3];
    }
    int32_t placed = (int32_t)CORE_MIN((int64_t)quanta, room);
    if (placed > 0) {
        int64_t amount[4] = { g->amount[0], g->amount[1], g->amount[2], g->amount[3] };
        amount[material == TERRAIN_ROCKS ? 1 : 0] += placed;
        /* The water goes first (it flows off, as on open ground), then the air. */
        int64_t displaced = CORE_MIN(amount[2], (int64_t)placed);
        amount[2] -= displaced;
        if (!terrain__gap_open(g)) amount[3] -= placed - displaced;
        terrain__columns_rewrite_gap(c, i, k, scratch, count, g, amount, &rewritten, &rewritten_capacity);
        terrain__columns_touch(c, i, k);
    }
    core_free(gaps, ((size_t)count + 1) * sizeof *gaps);
    core_free(scratch, capacity * sizeof *scratch);
    core_free(rewritten, rewritten_capacity * sizeof *rewritten);
    return placed;
}

/* ---- public: load, write back, read, set ------------------------------------------------- */

bool terrain_columns_load(terrain_columns *c, terrain_chunk_coord coord, const terrain_stacks *stacks) {
    int64_t cx = coord.x * TERRAIN_CHUNK_COLUMNS - c->x0, cz = coord.z * TERRAIN_CHUNK_COLUMNS - c->z0;
    int i0 = (int)CORE_MAX(cx, 0), k0 = (int)CORE_MAX(cz, 0);
    int64_t i1 = CORE_MIN(cx + TERRAIN_CHUNK_COLUMNS, (int64_t)c->width);
    int64_t k1 = CORE_MIN(cz + TERRAIN_CHUNK_COLUMNS, (int64_t)c->depth);
    if (cx >= c->width || cz >= c->depth || i1 <= 0 || k1 <= 0) {
        core_log_error("terrain", "columns: chunk (%lld, %lld) does not overlap the region", (long long)coord.x,
                   (long long)coord.z);
        return false;
    }
    terrain__clayer *scratch = NULL;
    size_t capacity = 0;
    bool ok = true;
    for (int k = k0; k < (int)k1; k++) {
        for (int i = i0; i < (int)i1; i++) {
            terrain__column_cursor cursor = terrain__stacks_cursor(stacks, (int)(i - cx), (int)(k - cz));
            terrain__qlayer layer;
            int count = 0;
            int64_t top = 0;
            while (terrain__cursor_next(&cursor, &layer)) {
                scratch = core_grow(scratch, &capacity, (size_t)count + 1, sizeof *scratch);
                scratch[count++] = (terrain__clayer){ layer.material, (int32_t)layer.quanta };
                top += layer.quanta;
            }
            if (top >= TERRAIN__COLUMN_MAX_QUANTA) {
                core_log_error("terrain", "columns: column (%d, %d) of chunk (%lld, %lld) is %.0f m tall (over %d m)",
                           (int)(i - cx), (int)(k - cz), (long long)coord.x, (long long)coord.z,
                           (double)top * TERRAIN_HEIGHT_QUANTUM, TERRAIN__COLUMN_MAX_QUANTA / 32);
                ok = false;
                count = 0;                         /* leave an empty column, never a torn one */
            }
            terrain__columns_store(c, i, k, scratch, count);
            /* Loading is not an edit: the column is what the stacks say. */
            c->flags[flat(c, i, k)] &= (uint8_t)~TERRAIN__COLUMN_EDITED;
            c->changed[terrain__cell(c, i, k)] = 0;
        }
    }
    core_free(scratch, capacity * sizeof *scratch);
    return ok;
}

terrain_stacks *terrain_columns_to_stacks(const terrain_columns *c, terrain_chunk_coord coord) {
    int64_t cx = coord.x * TERRAIN_CHUNK_COLUMNS - c->x0, cz = coord.z * TERRAIN_CHUNK_COLUMNS - c->z0;
    if (cx < 0 || cz < 0 || cx + TERRAIN_CHUNK_COLUMNS > c->width || cz + TERRAIN_CHUNK_COLUMNS > c->depth) {
        core_log_error("terrain", "columns: chunk (%lld, %lld) is not inside the region", (long long)coord.x,
                   (long long)coord.z);
        return NULL;
    }
    terrain_stacks_builder *builder = terrain_stacks_builder_create();
    terrain__clayer *scratch = NULL;
    size_t capacity = 0;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++) {
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            int count = terrain__columns_layers(c, (int)cx + i, (int)cz + k, &scratch, &capacity);
            /* A thickness below 2^24 quanta is exact in a float, and the builder's cumulative
             * rounding of exact sums gives back the same quanta. */
            for (int l = 0; l < count; l++)
                terrain_stacks_builder_push(builder, (terrain_material)scratch[l].material,
                                            (float)scratch[l].quanta * TERRAIN_HEIGHT_QUANTUM);
            terrain_stacks_builder_end_column(builder);
        }
    }
    core_free(scratch, capacity * sizeof *scratch);
    terrain_stacks *stacks = terrain_stacks_builder_finish(builder);
    terrain_stacks_builder_destroy(builder);
    return stacks;
}

static bool inside(const terrain_columns *c, int i, int k) {
    return i >= 0 && k >= 0 && i < c->width && k < c->depth;
}

int terrain_columns_get(const terrain_columns *c, int i, int k, terrain_layer *layers, int capacity) {
    if (!inside(c, i, k)) return -1;
    terrain__clayer *scratch = NULL;
    size_t scratch_capacity = 0;
    int count = terrain__columns_layers(c, i, k, &scratch, &scratch_capacity);
    for (int l = 0; l < count && l < capacity; l++)
        layers[l] = (terrain_layer){ (terrain_material)scratch[l].material,
                                     (float)scratch[l].quanta * TERRAIN_HEIGHT_QUANTUM };
    core_free(scratch, scratch_capacity * sizeof *scratch);
    return count;
}

bool terrain_columns_set(terrain_columns *c, int i, int k, const terrain_layer *layers, int count) {
    if (!inside(c, i, k)) {
        core_log_error("terrain", "columns: set column (%d, %d) outside the %d x %d region", i, k, c->width, c->depth);
        return false;
    }
    if (count < 0 || (count > 0 && !layers)) {
        core_log_error("terrain", "columns: set column (%d, %d) with %d layers", i, k, count);
        return false;
    }
    terrain__clayer *q = core_alloc(((size_t)count + 1) * sizeof *q);
    /* Cumulative rounding, as terrain_stacks_builder_push: the column's top and every layer's
     * stay within half a quantum of the exact ones. */
    double exact = 0.0;
    int64_t rounded = 0;
    int n = 0;
    bool ok = true;
    for (int l = 0; l < count && ok; l++) {
        float t = layers[l].thickness;
        if ((unsigned)layers[l].material >= TERRAIN_MATERIAL_MAX) {
            core_log_error("terrain", "columns: set column (%d, %d): layer %d has unknown material %d", i, k, l,
                       (int)layers[l].material);
            ok = false;
        } else if (!(t >= 0.0f) || !isfinite(t)) {
            core_log_error("terrain", "columns: set column (%d, %d): layer %d has thickness %g", i, k, l, (double)t);
            ok = false;
        } else {
            exact += t;
            int64_t top = llround(exact * (double)TERRAIN__QUANTA_PER_METRE);
            if (top >= TERRAIN__COLUMN_MAX_QUANTA) {
                core_log_error("terrain", "columns: set column (%d, %d) over %d m tall", i, k,
                           TERRAIN__COLUMN_MAX_QUANTA / 32);
                ok = false;
            } else {
                n = push_layer(q, n, (uint32_t)layers[l].material, (int32_t)(top - rounded));
                rounded = top;
            }
        }
    }
    if (ok) {
        terrain__columns_store(c, i, k, q, n);
        terrain__columns_touch(c, i, k);
    }
    core_free(q, ((size_t)count + 1) * sizeof *q);
    return ok;
}

float terrain_columns_top(const terrain_columns *c, int i, int k) {
    if (!inside(c, i, k)) return TERRAIN_FLOOR_Y;
    size_t cell = terrain__cell(c, i, k), n = flat(c, i, k);
    int32_t top = c->ground[cell];
    if (top == c->base[cell]) {
        /* No sand or rocks: the highest lower layer that is not air or water. */
        const terrain__clayer *lower = c->pool + c->lower_start[n];
        int l = c->lower_count[n];
        while (l > 0 && (lower[l - 1].material == TERRAIN_AIR || lower[l - 1].material == TERRAIN_WATER))
            top -= lower[--l].quanta;
    }
    return TERRAIN_FLOOR_Y + (float)top * TERRAIN_HEIGHT_QUANTUM;
}

int64_t terrain_columns_mass(const terrain_columns *c, terrain_material material) {
    int64_t total = 0;
    for (int k = 0; k < c->depth; k++) {
        for (int i = 0; i < c->width; i++) {
            size_t n = flat(c, i, k), cell = terrain__cell(c, i, k);
            const terrain__clayer *lower = c->pool + c->lower_start[n];
            for (int l = 0; l < c->lower_count[n]; l++)
                if (lower[l].material == (uint32_t)material) total += lower[l].quanta;
            if (material == TERRAIN_SAND) total += c->sand_top[cell] - c->base[cell];
            if (material == TERRAIN_ROCKS) total += c->ground[cell] - c->sand_top[cell];
            if (material == TERRAIN_WATER) total += c->water[n];
        }
    }
    return total;
}

/* ---- the sea after edits (terrain.h, "the sea after edits") ------------------------------- */

/* `in` (bottom-up, merged, no air on top) with the sea rule applied into `out` (room for
 * count + 2): water from the highest solid exactly up to `sea`, the water run that reached above
 * it cut off there; the count, or −1 when the highest solid is at or above the sea (unchanged). */
static int flood_layers(const terrain__clayer *in, int count, int32_t sea, terrain__clayer *out) {
    int top = count - 1;
    while (top >= 0 && (in[top].material == TERRAIN_AIR || in[top].material == TERRAIN_WATER)) top--;
    int64_t solid = 0;
    for (int l = 0; l <= top; l++) solid += in[l].quanta;
    if (solid >= sea) return -1;
    int n = 0;
    for (int l = 0; l <= top; l++) n = push_layer(out, n, in[l].material, in[l].quanta);
    n = push_layer(out, n, TERRAIN_WATER, (int32_t)(sea - solid));
    /* Above the sea: the same layers, less the water that stood on the run below (displaced). */
    bool displaced = true;
    int64_t bottom = solid;
    for (int l = top + 1; l < count; l++) {
        int64_t lo = CORE_MAX(bottom, (int64_t)sea), hi = bottom + in[l].quanta;
        bottom = hi;
        if (hi <= sea) continue;
        displaced = displaced && in[l].material == TERRAIN_WATER;
        n = push_layer(out, n, displaced ? TERRAIN_AIR : in[l].material, (int32_t)(hi - lo));
    }
    while (n > 0 && out[n - 1].material == TERRAIN_AIR) n--;
    return n;
}

int terrain__columns_flood(terrain_columns *c, int32_t sea) {
    terrain__clayer *scratch = NULL;
    size_t capacity = 0;
    int flooded = 0;
    for (int k = 0; k < c->depth; k++)
        for (int i = 0; i < c->width; i++) {
            if (!(c->flags[flat(c, i, k)] & TERRAIN__COLUMN_EDITED)) continue;
            int count = terrain__columns_layers(c, i, k, &scratch, &capacity);
            scratch = core_grow(scratch, &capacity, 2 * (size_t)count + 2, sizeof *scratch);
            terrain__clayer *in = scratch, *out = scratch + count;
            int n = flood_layers(in, count, sea, out);
            if (n < 0 || (n == count && memcmp(in, out, (size_t)n * sizeof *in) == 0)) continue;
            /* Water only: stabilization moves sand and rocks, so nothing is marked for it. */
            terrain__columns_store(c, i, k, out, n);
            flooded++;
        }
    core_free(scratch, capacity * sizeof *scratch);
    return flooded;
}

int terrain__columns_cap_water(terrain_columns *c, terrain_chunk_coord coord, const terrain_stacks *before) {
    int64_t ci = coord.x * TERRAIN_CHUNK_COLUMNS - c->x0, ck = coord.z * TERRAIN_CHUNK_COLUMNS - c->z0;
    if (ci < 0 || ck < 0 || ci + TERRAIN_CHUNK_COLUMNS > c->width || ck + TERRAIN_CHUNK_COLUMNS > c->depth) return 0;
    int capped = 0;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            int ri = (int)ci + i, rk = (int)ck + k;
            size_t n = flat(c, ri, rk), cell = terrain__cell(c, ri, rk);
            int64_t surface, ground;
            if (!(c->flags[n] & TERRAIN__COLUMN_EDITED) || c->water[n] == 0 ||
                !terrain__stacks_water(before, i, k, &surface, &ground))
                continue;
            int64_t allowed = CORE_MAX(surface - (int64_t)c->ground[cell], (int64_t)0);
            if (c->water[n] <= allowed) continue;
            c->water[n] = (int32_t)allowed;
            capped++;
        }
    return capped;
}

void terrain_columns_touch(terrain_columns *c, int i0, int k0, int i1, int k1) {
    i0 = CORE_MAX(i0, 0);
    k0 = CORE_MAX(k0, 0);
    i1 = CORE_MIN(i1, c->width);
    k1 = CORE_MIN(k1, c->depth);
    for (int k = k0; k < k1; k++)
        for (int i = i0; i < i1; i++) terrain__columns_touch(c, i, k);
}

/* Floor division for chunk coordinates of negative columns. */
static int64_t floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

int terrain_columns_changed_chunks(terrain_columns *c, terrain_chunk_coord *out, int capacity, bool clear) {
    int64_t cx0 = floor_div(c->x0, TERRAIN_CHUNK_COLUMNS), cz0 = floor_div(c->z0, TERRAIN_CHUNK_COLUMNS);
    int64_t cx1 = floor_div(c->x0 + c->width - 1, TERRAIN_CHUNK_COLUMNS);
    int64_t cz1 = floor_div(c->z0 + c->depth - 1, TERRAIN_CHUNK_COLUMNS);
    int count = 0;
    for (int64_t cz = cz0; cz <= cz1; cz++) {
        for (int64_t cx = cx0; cx <= cx1; cx++) {
            int i0 = (int)CORE_MAX(cx * TERRAIN_CHUNK_COLUMNS - c->x0, 0);
            int k0 = (int)CORE_MAX(cz * TERRAIN_CHUNK_COLUMNS - c->z0, 0);
            int i1 = (int)CORE_MIN((cx + 1) * TERRAIN_CHUNK_COLUMNS - c->x0, (int64_t)c->width);
            int k1 = (int)CORE_MIN((cz + 1) * TERRAIN_CHUNK_COLUMNS - c->z0, (int64_t)c->depth);
            bool changed = false;
            for (int k = k0; k < k1 && !changed; k++)
                for (int i = i0; i < i1 && !changed; i++) changed = c->flags[flat(c, i, k)] & TERRAIN__COLUMN_EDITED;
            if (!changed) continue;
            if (count < capacity) out[count] = (terrain_chunk_coord){ cx, cz };
            count++;
        }
    }
    if (clear) {
        size_t columns = (size_t)c->width * (size_t)c->depth;
        for (size_t n = 0; n < columns; n++) c->flags[n] &= (uint8_t)~TERRAIN__COLUMN_EDITED;
    }
    return count;
}
