/* terrain_stacks.c — one chunk's material stacks, packed (000 §3.2, 002 §3.1.1).
 *
 * Layout: one allocation holding the header, the per-row and per-column offsets, then every
 * column's layers as 16-bit words (terrain_internal.h describes a word). Column (i, k) is
 * words[row_start[k] + column_start[k·N + i] … end), where the end is the next column's start
 * (or the next row's). Offsets are 16-bit relative to their row so that a column costs 2 bytes
 * of index; a row would need 65 536 words (2 048 layers per column) to overflow them.
 *
 * Typical generated column: a long bedrock layer from the floor (2 words), sand (1), maybe
 * water (1), plus 2 per cave or overhang: 8–10 bytes with its index, against 512 bytes for a
 * byte voxel per metre of a 512 m column.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <assert.h>
#include <math.h>
#include <string.h>

struct terrain_stacks {
    size_t bytes;                                  /* the whole allocation */
    uint32_t word_count;
    float interface_low, interface_high;           /* terrain_stacks_interface_range */
    uint32_t row_start[TERRAIN_CHUNK_COLUMNS + 1];
    uint16_t column_start[TERRAIN__COLUMNS];       /* relative to the row's start */
    uint16_t words[];
};

/* The lowest and highest heights where a column changes between material in the field and
 * material out of it. The floor counts (bedrock is below it), and so does the top of the last
 * layer (air is above it). */
static void stacks_find_interfaces(terrain_stacks *s) {
    int64_t low = INT64_MAX, high = INT64_MIN;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            terrain__column_cursor cursor = terrain__stacks_cursor(s, i, k);
            terrain__qlayer layer;
            int64_t height = 0;
            bool solid = true;                     /* below the floor */
            while (terrain__cursor_next(&cursor, &layer)) {
                bool in_field = terrain_material_in_field((terrain_material)layer.material);
                if (in_field != solid && layer.quanta > 0) {
                    low = height < low ? height : low;
                    high = height > high ? height : high;
                    solid = in_field;
                }
                height += layer.quanta;
            }
            if (solid) {                           /* air above the last layer */
                low = height < low ? height : low;
                high = height > high ? height : high;
            }
        }
    s->interface_low = TERRAIN_FLOOR_Y + (float)low * TERRAIN_HEIGHT_QUANTUM;
    s->interface_high = TERRAIN_FLOOR_Y + (float)high * TERRAIN_HEIGHT_QUANTUM;
}

struct terrain_stacks_builder {
    uint16_t *words;
    size_t word_count, word_capacity;
    uint32_t row_start[TERRAIN_CHUNK_COLUMNS + 1];
    uint16_t column_start[TERRAIN__COLUMNS];
    int columns;                                   /* columns ended so far */
    size_t column_begin;                           /* first word of the column being built */
    /* The column being built. Rounding is of cumulative heights (exact sum → nearest quantum),
     * so the quantized column never drifts more than half a quantum from the exact one. */
    double exact_top;                              /* metres above the floor, unrounded */
    int64_t rounded_top;                           /* quanta */
    int pending_material;                          /* -1 = none */
    int64_t pending_quanta;
};

/* ---- materials ------------------------------------------------------------------------- */

const char *terrain_material_name(terrain_material material) {
    switch (material) {
    case TERRAIN_AIR: return "air";
    case TERRAIN_BEDROCK: return "bedrock";
    case TERRAIN_SAND: return "sand";
    case TERRAIN_ROCKS: return "rocks";
    case TERRAIN_WATER: return "water";
    default: break;
    }
    return (unsigned)material < TERRAIN_MATERIAL_MAX ? "custom" : "invalid";
}

bool terrain_material_in_field(terrain_material material) {
    /* a game's own materials are rock like bedrock (the edits hold them stable too) */
    return material == TERRAIN_BEDROCK || material == TERRAIN_SAND ||
           (material >= TERRAIN_MATERIAL_BUILTIN_COUNT && material < TERRAIN_MATERIAL_MAX);
}

/* ---- building -------------------------------------------------------------------------- */

terrain_stacks_builder *terrain_stacks_builder_create(void) {
    terrain_stacks_builder *b = core_calloc(1, sizeof *b);
    b->pending_material = -1;
    return b;
}

void terrain_stacks_builder_destroy(terrain_stacks_builder *builder) {
    if (!builder) return;
    core_free(builder->words, builder->word_capacity * sizeof *builder->words);
    core_free(builder, sizeof *builder);
}

static void builder_emit(terrain_stacks_builder *b, uint16_t word) {
    b->words = core_grow(b->words, &b->word_capacity, b->word_count + 1, sizeof *b->words);
    b->words[b->word_count++] = word;
}

/* Writes the pending layer as one or more entries (long runs split at 65 535 quanta). */
static void builder_flush(terrain_stacks_builder *b) {
    if (b->pending_material < 0) return;
    int64_t quanta = b->pending_quanta;
    uint16_t material = (uint16_t)b->pending_material;
    while (quanta > 0) {
        int64_t part = quanta > TERRAIN__LAYER_LONG_MAX ? TERRAIN__LAYER_LONG_MAX : quanta;
        if (part <= TERRAIN__LAYER_SHORT_MAX) {
            builder_emit(b, (uint16_t)(material | (part << TERRAIN__LAYER_MATERIAL_BITS)));
        } else {
            builder_emit(b, material);               /* thickness field 0: long layer */
            builder_emit(b, (uint16_t)part);
        }
        quanta -= part;
    }
    b->pending_material = -1;
    b->pending_quanta = 0;
}

uint32_t terrain__stacks_layer_words(uint32_t quanta) {
    /* As builder_flush splits: whole long entries of 2 words, then the rest in 1 or 2. */
    uint32_t whole = quanta / TERRAIN__LAYER_LONG_MAX, rest = quanta % TERRAIN__LAYER_LONG_MAX;
    return 2 * whole + (rest == 0 ? 0 : rest <= TERRAIN__LAYER_SHORT_MAX ? 1 : 2);
}

/* Adds `quanta` (> 0) of `material` on top of the column being built. */
static void builder_append(terrain_stacks_builder *b, terrain_material material, int64_t quanta) {
    if (b->pending_material == (int)material) {
        b->pending_quanta += quanta;               /* same as the layer below: merged */
        return;
    }
    builder_flush(b);
    b->pending_material = (int)material;
    b->pending_quanta = quanta;
}

void terrain_stacks_builder_push(terrain_stacks_builder *builder, terrain_material material, float thickness) {
    assert((unsigned)material < TERRAIN_MATERIAL_MAX);
    if (!(thickness > 0.0f)) return;               /* zero, negative and NaN add nothing */
    builder->exact_top += thickness;
    int64_t rounded = llround(builder->exact_top * TERRAIN__QUANTA_PER_METRE);
    int64_t quanta = rounded - builder->rounded_top;
    builder->rounded_top = rounded;
    if (quanta <= 0) return;                       /* rounds to nothing: dropped */
    builder_append(builder, material, quanta);
}

void terrain__stacks_builder_push_quanta(terrain_stacks_builder *builder, terrain_material material,
                                         uint32_t quanta) {
    assert((unsigned)material < TERRAIN_MATERIAL_MAX);
    if (quanta == 0) return;
    /* Both tops move by exactly `quanta` (a double holds quanta / 32 exactly), so float pushes
     * after this one round as if the layer had been pushed in metres. */
    builder->exact_top += (double)quanta / TERRAIN__QUANTA_PER_METRE;
    builder->rounded_top += quanta;
    builder_append(builder, material, quanta);
}

void terrain_stacks_builder_end_column(terrain_stacks_builder *builder) {
    assert(builder->columns < TERRAIN__COLUMNS && "more columns than a chunk has");
    if (builder->columns >= TERRAIN__COLUMNS) return;
    /* The air above the last non-air layer is implicit. */
    if (builder->pending_material == TERRAIN_AIR) builder->pending_material = -1;
    builder_flush(builder);

    int column = builder->columns, row = column / TERRAIN_CHUNK_COLUMNS;
    size_t begin = builder->column_begin;
    if (column % TERRAIN_CHUNK_COLUMNS == 0) {
        if (begin > UINT32_MAX) core_fatal("terrain", "a chunk of over 2^32 layer words");
        builder->row_start[row] = (uint32_t)begin;
    }
    size_t relative = begin - builder->row_start[row];
    if (relative > UINT16_MAX)
        core_fatal("terrain", "row %d of a chunk holds over 65535 layer words", row);
    builder->column_start[column] = (uint16_t)relative;
    builder->column_begin = builder->word_count;
    builder->columns++;
    builder->exact_top = 0.0;
    builder->rounded_top = 0;
}

terrain_stacks *terrain_stacks_builder_finish(terrain_stacks_builder *builder) {
    assert(builder->columns == TERRAIN__COLUMNS && "a chunk needs TERRAIN_CHUNK_COLUMNS² columns");
    while (builder->columns < TERRAIN__COLUMNS) terrain_stacks_builder_end_column(builder);
    size_t bytes = sizeof(terrain_stacks) + builder->word_count * sizeof(uint16_t);
    terrain_stacks *s = core_alloc(bytes);
    s->bytes = bytes;
    s->word_count = (uint32_t)builder->word_count;
    memcpy(s->row_start, builder->row_start, sizeof s->row_start);
    s->row_start[TERRAIN_CHUNK_COLUMNS] = s->word_count;
    memcpy(s->column_start, builder->column_start, sizeof s->column_start);
    if (builder->word_count) memcpy(s->words, builder->words, builder->word_count * sizeof(uint16_t));
    stacks_find_interfaces(s);
    builder->word_count = 0;
    builder->column_begin = 0;
    builder->columns = 0;
    builder->pending_material = -1;
    builder->pending_quanta = 0;
    builder->exact_top = 0.0;
    builder->rounded_top = 0;
    return s;
}

void terrain_stacks_interface_range(const terrain_stacks *stacks, float *lowest, float *highest) {
    *lowest = stacks->interface_low;
    *highest = stacks->interface_high;
}

void terrain_stacks_destroy(terrain_stacks *stacks) {
    if (stacks) core_free(stacks, stacks->bytes);
}

/* ---- reading ---------------------------------------------------------------------------- */

terrain__column_cursor terrain__stacks_cursor(const terrain_stacks *stacks, int i, int k) {
    assert(i >= 0 && i < TERRAIN_CHUNK_COLUMNS && k >= 0 && k < TERRAIN_CHUNK_COLUMNS);
    int column = k * TERRAIN_CHUNK_COLUMNS + i;
    uint32_t row = stacks->row_start[k];
    uint32_t begin = row + stacks->column_start[column];
    uint32_t end = i + 1 < TERRAIN_CHUNK_COLUMNS ? row + stacks->column_start[column + 1]
                                                 : stacks->row_start[k + 1];
    return (terrain__column_cursor){ stacks->words + begin, stacks->words + end };
}

/* One stored entry; the cursor is advanced past it. */
static inline uint32_t read_entry(const uint16_t **word, unsigned *material) {
    uint16_t w = *(*word)++;
    *material = w & ((1u << TERRAIN__LAYER_MATERIAL_BITS) - 1);
    uint32_t quanta = (uint32_t)w >> TERRAIN__LAYER_MATERIAL_BITS;
    if (quanta == 0) quanta = *(*word)++;        /* a long layer */
    return quanta;
}

bool terrain__cursor_next(terrain__column_cursor *cursor, terrain__qlayer *out) {
    if (cursor->word >= cursor->end) return false;
    unsigned material;
    uint32_t quanta = read_entry(&cursor->word, &material);
    /* Entries of one split layer follow each other; the builder never writes two different
     * layers of the same material back to back, so merging restores the logical layer. */
    while (cursor->word < cursor->end && (*cursor->word & 15u) == material) {
        unsigned next_material;
        quanta += read_entry(&cursor->word, &next_material);
    }
    out->material = (uint8_t)material;
    out->quanta = quanta;
    return true;
}

int terrain_stacks_column(const terrain_stacks *stacks, int i, int k, terrain_layer *layers, int capacity) {
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
    terrain__qlayer layer;
    int count = 0;
    while (terrain__cursor_next(&cursor, &layer)) {
        if (count < capacity)
            layers[count] = (terrain_layer){ (terrain_material)layer.material,
                                             (float)layer.quanta * TERRAIN_HEIGHT_QUANTUM };
        count++;
    }
    return count;
}

terrain_material terrain_stacks_material_at(const terrain_stacks *stacks, int i, int k, float y) {
    float height = (y - TERRAIN_FLOOR_Y) * (float)TERRAIN__QUANTA_PER_METRE;
    if (height < 0.0f) return TERRAIN_BEDROCK;
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
    /* No merging needed here: a split layer's entries have the same material. */
    uint32_t top = 0;
    while (cursor.word < cursor.end) {
        unsigned material;
        top += read_entry(&cursor.word, &material);
        if (height < (float)top) return (terrain_material)material;
    }
    return TERRAIN_AIR;
}

float terrain_stacks_top(const terrain_stacks *stacks, int i, int k) {
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
    uint32_t top = 0, ground = 0;
    while (cursor.word < cursor.end) {
        unsigned material;
        top += read_entry(&cursor.word, &material);
        if (material != TERRAIN_AIR && material != TERRAIN_WATER) ground = top;
    }
    return TERRAIN_FLOOR_Y + (float)ground * TERRAIN_HEIGHT_QUANTUM;
}

float terrain_stacks_surface(const terrain_stacks *stacks, int i, int k) {
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
    uint32_t top = 0, surface = 0;
    while (cursor.word < cursor.end) {
        unsigned material;
        top += read_entry(&cursor.word, &material);
        if (material != TERRAIN_AIR) surface = top;  /* the builder drops trailing air anyway */
    }
    return TERRAIN_FLOOR_Y + (float)surface * TERRAIN_HEIGHT_QUANTUM;
}

size_t terrain_stacks_bytes(const terrain_stacks *stacks) {
    return stacks->bytes;
}

uint64_t terrain_stacks_hash(const terrain_stacks *stacks) {
    /* Of the logical layers, column by column, so the hash does not depend on how a layer
     * happens to be stored. */
    uint64_t h = 0x7465727261696eull;              /* "terrain" */
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++) {
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
            terrain__qlayer layer;
            while (terrain__cursor_next(&cursor, &layer))
                h = core_hash_combine(h, (uint64_t)layer.quanta << 8 | layer.material);
            h = core_hash_combine(h, 0);           /* end of column (a layer is never 0) */
        }
    }
    return h;
}

terrain_stacks *terrain_stacks_from_columns(terrain_chunk_coord coord, terrain_column_fn column, void *user) {
    terrain_stacks_builder *builder = terrain_stacks_builder_create();
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            column(user, coord.x * TERRAIN_CHUNK_COLUMNS + i, coord.z * TERRAIN_CHUNK_COLUMNS + k, builder);
            terrain_stacks_builder_end_column(builder);
        }
    terrain_stacks *stacks = terrain_stacks_builder_finish(builder);
    terrain_stacks_builder_destroy(builder);
    return stacks;
}

/* One column's layers as a walk over heights: the material from `height` up to `next`. */
typedef struct diff_walker {
    terrain__column_cursor cursor;
    int64_t next;                         /* where the current layer ends (INT64_MAX: air above) */
    unsigned material;
} diff_walker;

static void diff_walker_advance(diff_walker *w) {
    terrain__qlayer layer;
    if (terrain__cursor_next(&w->cursor, &layer)) {
        w->material = layer.material;
        w->next += layer.quanta;
    } else {
        w->material = TERRAIN_AIR;
        w->next = INT64_MAX;
    }
}

bool terrain__stacks_diff(const terrain_stacks *a, const terrain_stacks *b, terrain_world_change *box) {
    int64_t low = INT64_MAX, high = INT64_MIN;
    int i0 = TERRAIN_CHUNK_COLUMNS, k0 = TERRAIN_CHUNK_COLUMNS, i1 = -1, k1 = -1;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            diff_walker wa = { terrain__stacks_cursor(a, i, k), 0, 0 }, wb = { terrain__stacks_cursor(b, i, k), 0, 0 };
            diff_walker_advance(&wa);
            diff_walker_advance(&wb);
            int64_t height = 0;
            /* Past both columns' last layers both are air: nothing differs above. */
            while (wa.next != INT64_MAX || wb.next != INT64_MAX) {
                int64_t next = wa.next < wb.next ? wa.next : wb.next;
                if (wa.material != wb.material) {
                    if (height < low) low = height;
                    if (next > high) high = next;
                    i0 = i < i0 ? i : i0, i1 = i > i1 ? i : i1;
                    k0 = k < k0 ? k : k0, k1 = k > k1 ? k : k1;
                }
                height = next;
                if (wa.next == next) diff_walker_advance(&wa);
                if (wb.next == next) diff_walker_advance(&wb);
            }
        }
    if (low > high) return false;
    box->column_min[0] = i0, box->column_min[1] = k0;
    box->column_max[0] = i1, box->column_max[1] = k1;
    box->y_min = TERRAIN_FLOOR_Y + (float)low / TERRAIN__QUANTA_PER_METRE;
    box->y_max = TERRAIN_FLOOR_Y + (float)high / TERRAIN__QUANTA_PER_METRE;
    return true;
}
