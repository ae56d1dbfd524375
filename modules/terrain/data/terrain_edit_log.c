/* terrain_edit_log.c — the persistent edit log (terrain.h, "the edit log").
 *
 * In memory: a hash map from chunk coordinate to the chunk's entries, oldest first. An entry is
 * the tool and the columns it changed, each with its whole new column as logical layers
 * {material, quanta} (merged, bottom-up, no air on top): replaying sets those columns, so an
 * entry does not depend on what the column held before and later entries simply override
 * earlier ones. Replay reads the generated stacks and each column's last setting, and packs the
 * result with the stacks builder's exact (quanta) push: the same logical layers give the same
 * words, so a replayed chunk equals the recorded one byte for byte.
 *
 * One file per chunk, DIR/edits/<x>_<z>.tel (x, z in signed decimal, as "%lld"). Format
 * version 1, every integer little-endian:
 *
 *   offset    size  field
 *   0         8     magic "TEDITLOG"
 *   8         4     format version: 1
 *   12        8     world key (terrain_generation_key of the generation parameters)
 *   20        8     chunk x, two's complement
 *   28        8     chunk z
 *   36        4     entry count, ≥ 1
 *   40        …     the entries, oldest first; each is
 *                     1  tool (terrain_edit_tool: 1 … 8)
 *                     2  column count, 1 … 1024
 *                     and per column, column indices strictly increasing:
 *                     2  column index k·32 + i (i along x, k along z), < 1024
 *                     2  layer count; 0 = an empty column (air down to the floor)
 *                     and per layer, bottom-up from TERRAIN_FLOOR_Y:
 *                     1  material, < TERRAIN_MATERIAL_MAX (16)
 *                     4  thickness in quanta (1/32 m), > 0
 *   size − 4  4     CRC-32 (IEEE, as zlib's crc32) of every byte before it
 *
 * A column is stored as the stacks hold it: no two adjacent layers of one material, no air on
 * top, and a total height under TERRAIN__COLUMN_MAX_QUANTA (2^26 quanta). The reader refuses
 * anything else (a file we did not write), as well as a wrong magic, version, checksum or world
 * key and bytes after the last entry. The checksum is CRC-32 rather than core_hash_bytes so that
 * the format never changes with the engine's hash, and other tools can check it.
 *
 * Saving writes DIR/edits/.<x>_<z>.tel.tmp.<pid>, flushes and fsyncs it, renames it over
 * <x>_<z>.tel, then fsyncs the folder: after a crash at any point the file is the old one or the
 * new one. Loading removes such temporaries (one process saves into a folder at a time).
 *
 * Threads: `lock` guards the map and the entries; every call holds it only briefly (replay
 * while it picks each column's last layers and copies them out, a few microseconds; it builds
 * the stacks after). `io_lock` serialises saves and loads, which write and read files outside
 * `lock`, so that replays on workers never wait for a disk.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define EDIT_MAGIC "TEDITLOG"
#define EDIT_FORMAT_VERSION 1u
#define EDIT_HEADER_BYTES 40u
#define EDIT_CHECKSUM_BYTES 4u
#define EDIT_MIN_ENTRY_BYTES 7u          /* tool, column count, one empty column */
#define EDIT_MAX_LAYERS 65535u           /* per column: the file's 16-bit count */
/* Files are read whole; save compacts a chunk whose file would be larger (a compacted chunk
 * takes at most 1024 columns × 65 535 layers × 5 bytes, about 336 MB). */
#define EDIT_FILE_MAX_BYTES ((size_t)1 << 30)
#define EDIT_SUFFIX ".tel"
#define EDIT_TEMP_MARK ".tel.tmp."

/* ---- names and the world key ------------------------------------------------------------ */

const char *terrain_edit_tool_name(terrain_edit_tool tool) {
    switch (tool) {
    case TERRAIN_EDIT_SET: return "set";
    case TERRAIN_EDIT_SCULPT_ADD: return "sculpt_add";
    case TERRAIN_EDIT_SCULPT_CARVE: return "sculpt_carve";
    case TERRAIN_EDIT_SWEEP: return "sweep";
    case TERRAIN_EDIT_DEPOSIT: return "deposit";
    case TERRAIN_EDIT_ERODE: return "erode";
    case TERRAIN_EDIT_STABILIZE: return "stabilize";
    case TERRAIN_EDIT_COMPACTED: return "compacted";
    default: return "unknown";
    }
}

static bool tool_valid(unsigned tool) {
    return tool >= TERRAIN_EDIT_SET && tool < TERRAIN_EDIT_TOOL_COUNT;
}

/* A field added to terrain_generation_desc must be added to the key too: this fails to
 * compile until someone looks (8 bytes of seed + 26 four-byte fields). */
_Static_assert(sizeof(terrain_generation_desc) == 112,
               "terrain_generation_desc changed: hash the new field in terrain_generation_key");

/* Bumped whenever terrain_generate_chunk's output changes for the same parameters, so that edit
 * logs of the old generator are refused instead of replayed over different ground. */
#define EDIT_GENERATOR_REVISION 5u          /* 2: lakes; 3: rock layers; 4: perturbed caves, no islands,
                                               octaves from the wavelength (terrain_generate.c);
                                               5: noise positions as lattice cell and offset
                                               (terrain_generate.c, terrain_noise.c) */

static uint64_t key_float(uint64_t h, float value) {
    uint32_t bits;
    if (value == 0.0f) value = 0.0f;             /* −0 equals +0: one key for both */
    memcpy(&bits, &value, sizeof bits);
    return core_hash_combine(h, bits);
}

uint64_t terrain_generation_key(const terrain_generation_desc *p) {
    /* Field by field, never the struct's bytes: padding is not part of the parameters. */
    uint64_t h = core_hash_combine(0x6b657973ull /* "keys" */, EDIT_GENERATOR_REVISION);
    h = core_hash_combine(h, p->seed);
    h = key_float(h, p->sea_level);
    h = key_float(h, p->relief_height);
    h = key_float(h, p->base_height);
    h = key_float(h, p->relief_wavelength);
    h = key_float(h, p->lacunarity);
    h = key_float(h, p->hurst);
    h = core_hash_combine(h, (uint64_t)(int64_t)p->relief_octaves);
    h = key_float(h, p->warp_strength);
    h = key_float(h, p->vertical_perturbation);
    h = key_float(h, p->horizontal_perturbation);
    h = key_float(h, p->perturbation_wavelength);
    h = core_hash_combine(h, (uint64_t)(int64_t)p->perturbation_octaves);
    h = key_float(h, p->cave_threshold);
    h = key_float(h, p->cave_wavelength);
    h = key_float(h, p->cave_fade_height);
    h = key_float(h, p->sand_max_slope);
    h = key_float(h, p->sand_depth);
    h = key_float(h, p->lake_spacing);
    h = key_float(h, p->lake_probability);
    h = key_float(h, p->lake_radius_min);
    h = key_float(h, p->lake_radius_max);
    h = key_float(h, p->lake_depth);
    h = key_float(h, p->talus_depth);
    h = key_float(h, p->scree_depth);
    h = key_float(h, p->scree_min_slope);
    h = key_float(h, p->lake_rocks_depth);
    return h;
}

/* ---- CRC-32 ----------------------------------------------------------------------------- */

static uint32_t crc_table[256];
static pthread_once_t crc_once = PTHREAD_ONCE_INIT;

static void crc_table_build(void) {
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int bit = 0; bit < 8; bit++) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
        crc_table[n] = c;
    }
}

uint32_t terrain__crc32(uint32_t crc, const void *data, size_t size) {
    pthread_once(&crc_once, crc_table_build);
    const uint8_t *bytes = data;
    crc = ~crc;
    for (size_t n = 0; n < size; n++) crc = crc_table[(crc ^ bytes[n]) & 0xffu] ^ (crc >> 8);
    return ~crc;
}

/* ---- entries ---------------------------------------------------------------------------- */

/* One edit: `column_count` columns, column columns[c]'s new layers are
 * layers[starts[c] … starts[c + 1]). One allocation of `bytes` holds the three arrays. */
typedef struct edit_entry {
    uint8_t tool;
    uint16_t column_count;
    uint32_t layer_count;
    terrain__qlayer *layers;
    uint32_t *starts;
    uint16_t *columns;
    size_t bytes;
} edit_entry;

/* Collects an entry's columns (record, parse and compact all build entries through it). */
typedef struct entry_builder {
    uint16_t *columns;
    uint32_t *starts;
    terrain__qlayer *layers;
    size_t column_capacity, start_capacity, layer_capacity;
    uint32_t column_count, layer_count;
} entry_builder;

static void builder_begin_column(entry_builder *b, int column) {
    b->columns = core_grow(b->columns, &b->column_capacity, b->column_count + 1, sizeof *b->columns);
    b->starts = core_grow(b->starts, &b->start_capacity, b->column_count + 1, sizeof *b->starts);
    b->columns[b->column_count] = (uint16_t)column;
    b->starts[b->column_count] = b->layer_count;
    b->column_count++;
}

static void builder_push_layer(entry_builder *b, terrain__qlayer layer) {
    b->layers = core_grow(b->layers, &b->layer_capacity, (size_t)b->layer_count + 1, sizeof *b->layers);
    b->layers[b->layer_count++] = layer;
}

/* The collected columns as an entry; the builder is emptied for the next one. */
static edit_entry builder_finish(entry_builder *b, terrain_edit_tool tool) {
    edit_entry e = { .tool = (uint8_t)tool, .column_count = (uint16_t)b->column_count,
                     .layer_count = b->layer_count };
    size_t layer_bytes = (size_t)e.layer_count * sizeof *e.layers;
    size_t start_bytes = ((size_t)e.column_count + 1) * sizeof *e.starts;
    e.bytes = layer_bytes + start_bytes + (size_t)e.column_count * sizeof *e.columns;
    uint8_t *memory = core_alloc(e.bytes);
    e.layers = (terrain__qlayer *)memory;
    e.starts = (uint32_t *)(memory + layer_bytes);
    e.columns = (uint16_t *)(memory + layer_bytes + start_bytes);
    if (layer_bytes) memcpy(e.layers, b->layers, layer_bytes);
    memcpy(e.starts, b->starts, start_bytes - sizeof *e.starts);
    e.starts[e.column_count] = e.layer_count;
    memcpy(e.columns, b->columns, (size_t)e.column_count * sizeof *e.columns);
    b->column_count = b->layer_count = 0;
    return e;
}

static void builder_free(entry_builder *b) {
    core_free(b->columns, b->column_capacity * sizeof *b->columns);
    core_free(b->starts, b->start_capacity * sizeof *b->starts);
    core_free(b->layers, b->layer_capacity * sizeof *b->layers);
}

static void entry_free(edit_entry *e) {
    core_free(e->layers, e->bytes);   /* the allocation starts with the layers */
}

/* ---- chunks and the map ----------------------------------------------------------------- */

/* A chunk's log. `version` counts changes; the file holds `saved_version` (dirty when they
 * differ). A chunk, once in the map, stays until the log is destroyed. */
typedef struct edit_chunk {
    terrain_chunk_coord coord;
    edit_entry *entries;
    size_t entry_count, entry_capacity;
    uint64_t version, saved_version;
} edit_chunk;

struct terrain_edit_log {
    pthread_mutex_t lock;            /* the map and every chunk's entries */
    pthread_mutex_t io_lock;         /* one save or load at a time (temporary names are per pid) */
    uint64_t world_key;
    edit_chunk **chunks;             /* in the order they first got entries */
    size_t chunk_count, chunk_capacity;
    uint32_t *slots;                 /* open addressing: index into chunks + 1, 0 = empty */
    size_t slot_count;               /* a power of two, at least twice chunk_count */
};

static uint64_t coord_hash(terrain_chunk_coord c) {
    return core_hash_combine(core_hash_u64((uint64_t)c.x), (uint64_t)c.z);
}

static edit_chunk *map_find(const terrain_edit_log *log, terrain_chunk_coord coord) {
    size_t mask = log->slot_count - 1;
    for (size_t s = coord_hash(coord) & mask;; s = (s + 1) & mask) {
        uint32_t slot = log->slots[s];
        if (slot == 0) return NULL;
        edit_chunk *c = log->chunks[slot - 1];
        if (c->coord.x == coord.x && c->coord.z == coord.z) return c;
    }
}

static void map_insert_slot(terrain_edit_log *log, size_t index) {
    size_t mask = log->slot_count - 1, s = coord_hash(log->chunks[index]->coord) & mask;
    while (log->slots[s]) s = (s + 1) & mask;
    log->slots[s] = (uint32_t)(index + 1);
}

/* The chunk's log, created empty when the map has none. */
static edit_chunk *map_get(terrain_edit_log *log, terrain_chunk_coord coord) {
    edit_chunk *c = map_find(log, coord);
    if (c) return c;
    if ((log->chunk_count + 1) * 2 > log->slot_count) {
        core_free(log->slots, log->slot_count * sizeof *log->slots);
        log->slot_count *= 2;
        log->slots = core_calloc(log->slot_count, sizeof *log->slots);
        for (size_t n = 0; n < log->chunk_count; n++) map_insert_slot(log, n);
    }
    c = core_calloc(1, sizeof *c);
    c->coord = coord;
    log->chunks = core_grow(log->chunks, &log->chunk_capacity, log->chunk_count + 1, sizeof *log->chunks);
    log->chunks[log->chunk_count] = c;
    map_insert_slot(log, log->chunk_count++);
    return c;
}

static void chunk_append(edit_chunk *c, edit_entry entry) {
    c->entries = core_grow(c->entries, &c->entry_capacity, c->entry_count + 1, sizeof *c->entries);
    c->entries[c->entry_count++] = entry;
}

static void chunk_clear(edit_chunk *c) {
    for (size_t n = 0; n < c->entry_count; n++) entry_free(&c->entries[n]);
    c->entry_count = 0;
}

/* Hands `from`'s entries to `to` (whose old ones are freed); `from` ends empty. */
static void chunk_take_entries(edit_chunk *to, edit_chunk *from) {
    chunk_clear(to);
    core_free(to->entries, to->entry_capacity * sizeof *to->entries);
    to->entries = from->entries;
    to->entry_count = from->entry_count;
    to->entry_capacity = from->entry_capacity;
    from->entries = NULL;
    from->entry_count = from->entry_capacity = 0;
}

static void chunk_free(edit_chunk *c) {
    chunk_clear(c);
    core_free(c->entries, c->entry_capacity * sizeof *c->entries);
    core_free(c, sizeof *c);
}

terrain_edit_log *terrain_edit_log_create(const terrain_edit_log_desc *desc) {
    uint64_t world_key = desc ? desc->world_key : 0;
    terrain_edit_log *log = core_calloc(1, sizeof *log);
    pthread_mutex_init(&log->lock, NULL);
    pthread_mutex_init(&log->io_lock, NULL);
    log->world_key = world_key;
    log->slot_count = 64;
    log->slots = core_calloc(log->slot_count, sizeof *log->slots);
    return log;
}

void terrain_edit_log_destroy(terrain_edit_log *log) {
    if (!log) return;
    for (size_t n = 0; n < log->chunk_count; n++) chunk_free(log->chunks[n]);
    core_free(log->chunks, log->chunk_capacity * sizeof *log->chunks);
    core_free(log->slots, log->slot_count * sizeof *log->slots);
    pthread_mutex_destroy(&log->io_lock);
    pthread_mutex_destroy(&log->lock);
    core_free(log, sizeof *log);
}

int terrain_edit_log_entries(terrain_edit_log *log, terrain_chunk_coord coord) {
    pthread_mutex_lock(&log->lock);
    edit_chunk *c = map_find(log, coord);
    int count = c ? (int)CORE_MIN(c->entry_count, (size_t)INT32_MAX) : 0;
    pthread_mutex_unlock(&log->lock);
    return count;
}

int terrain_edit_log_chunks(terrain_edit_log *log) {
    pthread_mutex_lock(&log->lock);
    int count = 0;
    for (size_t n = 0; n < log->chunk_count; n++) count += log->chunks[n]->entry_count > 0;
    pthread_mutex_unlock(&log->lock);
    return count;
}

/* ---- recording -------------------------------------------------------------------------- */

/* Whether column n reads the same in both stacks, logical layer for logical layer. */
static bool column_equal(const terrain_stacks *a, const terrain_stacks *b, int n) {
    int i = n % TERRAIN_CHUNK_COLUMNS, k = n / TERRAIN_CHUNK_COLUMNS;
    terrain__column_cursor ca = terrain__stacks_cursor(a, i, k), cb = terrain__stacks_cursor(b, i, k);
    terrain__qlayer la, lb;
    for (;;) {
        bool more_a = terrain__cursor_next(&ca, &la), more_b = terrain__cursor_next(&cb, &lb);
        if (more_a != more_b) return false;
        if (!more_a) return true;
        if (la.material != lb.material || la.quanta != lb.quanta) return false;
    }
}

/* Appends column n of `stacks` to the entry; false (message logged) when a file could not hold
 * it: taller than the columns' limit or with more layers than the format counts. */
static bool builder_copy_column(entry_builder *b, const terrain_stacks *stacks, int n, terrain_chunk_coord coord) {
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, n % TERRAIN_CHUNK_COLUMNS, n / TERRAIN_CHUNK_COLUMNS);
    terrain__qlayer layer;
    uint64_t height = 0;
    uint32_t layers = 0;
    builder_begin_column(b, n);
    while (terrain__cursor_next(&cursor, &layer)) {
        builder_push_layer(b, layer);
        height += layer.quanta;
        layers++;
    }
    if (height < TERRAIN__COLUMN_MAX_QUANTA && layers <= EDIT_MAX_LAYERS) return true;
    core_log_error("terrain", "edit log: chunk (%lld, %lld) column %d has %u layers, %.0f m (at most %u layers, under "
               "%d m): not recorded", (long long)coord.x, (long long)coord.z, n, layers,
               (double)height * TERRAIN_HEIGHT_QUANTUM, EDIT_MAX_LAYERS, TERRAIN__COLUMN_MAX_QUANTA / 32);
    return false;
}

bool terrain_edit_log_record(terrain_edit_log *log, terrain_chunk_coord coord, terrain_edit_tool tool,
                             const terrain_stacks *before, const terrain_stacks *after) {
    if (!log || !before || !after) {
        core_log_error("terrain", "edit log: record with a NULL %s", !log ? "log" : "stacks");
        return false;
    }
    if (!tool_valid((unsigned)tool)) {
        core_log_error("terrain", "edit log: record with unknown tool %d", (int)tool);
        return false;
    }
    /* The diff reads only the caller's stacks: no lock yet. */
    entry_builder b = { 0 };
    bool ok = true;
    for (int n = 0; n < TERRAIN__COLUMNS && ok; n++)
        if (!column_equal(before, after, n)) ok = builder_copy_column(&b, after, n, coord);
    if (ok && b.column_count > 0) {
        edit_entry entry = builder_finish(&b, tool);
        pthread_mutex_lock(&log->lock);
        edit_chunk *c = map_get(log, coord);
        chunk_append(c, entry);
        c->version++;
        pthread_mutex_unlock(&log->lock);
    }
    builder_free(&b);
    return ok;
}

/* ---- replaying -------------------------------------------------------------------------- */

/* What column n holds during a replay: its layers from the last entry that set it, or (layers
 * NULL) the generated column. */
typedef struct replay_column {
    const terrain__qlayer *layers;
    uint32_t count;
    uint32_t words;                  /* packed size, for the row check */
} replay_column;

typedef struct replay_state {
    replay_column column[TERRAIN__COLUMNS];
    uint64_t row_head[TERRAIN_CHUNK_COLUMNS];   /* words of each row's columns but the last */
    terrain__qlayer *own;                       /* the set columns' layers, copied */
    size_t own_count;
} replay_state;

static uint32_t layers_words(const terrain__qlayer *layers, uint32_t count) {
    uint32_t words = 0;
    for (uint32_t l = 0; l < count; l++) words += terrain__stacks_layer_words(layers[l].quanta);
    return words;
}

static void replay_start(replay_state *r, const terrain_stacks *generated) {
    memset(r->row_head, 0, sizeof r->row_head);
    for (int n = 0; n < TERRAIN__COLUMNS; n++) {
        terrain__column_cursor cursor = terrain__stacks_cursor(generated, n % TERRAIN_CHUNK_COLUMNS,
                                                               n / TERRAIN_CHUNK_COLUMNS);
        /* Stacks hold each layer as the builder split it, so the words are the span's length. */
        r->column[n] = (replay_column){ NULL, 0, (uint32_t)(cursor.end - cursor.word) };
        if (n % TERRAIN_CHUNK_COLUMNS != TERRAIN_CHUNK_COLUMNS - 1)
            r->row_head[n / TERRAIN_CHUNK_COLUMNS] += r->column[n].words;
    }
}

/* Applies the entry unless a row would outgrow the stacks' 16-bit column offsets (only a file
 * made by hand gets there: recorded stacks fit by construction); false then, nothing applied. */
static bool replay_apply(replay_state *r, const edit_entry *e) {
    uint64_t head[TERRAIN_CHUNK_COLUMNS];
    memcpy(head, r->row_head, sizeof head);
    for (uint32_t c = 0; c < e->column_count; c++) {
        int n = e->columns[c];
        if (n % TERRAIN_CHUNK_COLUMNS == TERRAIN_CHUNK_COLUMNS - 1) continue;
        uint32_t words = layers_words(e->layers + e->starts[c], e->starts[c + 1] - e->starts[c]);
        head[n / TERRAIN_CHUNK_COLUMNS] += (uint64_t)words - r->column[n].words;
    }
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        if (head[k] > TERRAIN__ROW_OFFSET_MAX) return false;
    memcpy(r->row_head, head, sizeof head);
    for (uint32_t c = 0; c < e->column_count; c++) {
        const terrain__qlayer *layers = e->layers + e->starts[c];
        uint32_t count = e->starts[c + 1] - e->starts[c];
        r->column[e->columns[c]] = (replay_column){ layers, count, layers_words(layers, count) };
    }
    return true;
}

/* Copies the layers the columns point to out of the entries, so that the stacks can be built
 * without the lock (load and compact may free entries meanwhile). */
static void replay_detach(replay_state *r) {
    size_t total = 0, at = 0;
    for (int n = 0; n < TERRAIN__COLUMNS; n++) total += r->column[n].layers ? r->column[n].count : 0;
    r->own_count = total ? total : 1;            /* never NULL: a set empty column points here */
    r->own = core_alloc(r->own_count * sizeof *r->own);
    for (int n = 0; n < TERRAIN__COLUMNS; n++) {
        replay_column *col = &r->column[n];
        if (!col->layers) continue;
        if (col->count) memcpy(r->own + at, col->layers, col->count * sizeof *r->own);
        col->layers = r->own + at;
        at += col->count;
    }
}

static terrain_stacks *replay_build(const replay_state *r, const terrain_stacks *generated) {
    terrain_stacks_builder *builder = terrain_stacks_builder_create();
    for (int n = 0; n < TERRAIN__COLUMNS; n++) {
        const replay_column *col = &r->column[n];
        if (col->layers) {
            for (uint32_t l = 0; l < col->count; l++)
                terrain__stacks_builder_push_quanta(builder, (terrain_material)col->layers[l].material,
                                                    col->layers[l].quanta);
        } else {
            terrain__column_cursor cursor = terrain__stacks_cursor(generated, n % TERRAIN_CHUNK_COLUMNS,
                                                                   n / TERRAIN_CHUNK_COLUMNS);
            terrain__qlayer layer;
            while (terrain__cursor_next(&cursor, &layer))
                terrain__stacks_builder_push_quanta(builder, (terrain_material)layer.material, layer.quanta);
        }
        terrain_stacks_builder_end_column(builder);
    }
    terrain_stacks *stacks = terrain_stacks_builder_finish(builder);
    terrain_stacks_builder_destroy(builder);
    return stacks;
}

terrain_stacks *terrain_edit_log_replay(terrain_edit_log *log, terrain_chunk_coord coord,
                                        const terrain_stacks *generated) {
    if (!log || !generated) {
        core_log_error("terrain", "edit log: replay with a NULL %s", !log ? "log" : "stacks");
        return NULL;
    }
    replay_state *r = core_alloc(sizeof *r);
    r->own = NULL;
    /* Under the lock only what reads entries: which layers each column ends with, copied out. */
    pthread_mutex_lock(&log->lock);
    edit_chunk *c = map_find(log, coord);
    if (c && c->entry_count > 0) {
        replay_start(r, generated);
        for (size_t n = 0; n < c->entry_count; n++)
            if (!replay_apply(r, &c->entries[n]))
                core_log_error("terrain", "edit log: chunk (%lld, %lld) entry %zu (%s) makes a row of the chunk too "
                           "long for stacks (over %u layer words); skipped", (long long)coord.x,
                           (long long)coord.z, n, terrain_edit_tool_name((terrain_edit_tool)c->entries[n].tool),
                           TERRAIN__ROW_OFFSET_MAX);
        replay_detach(r);
    }
    pthread_mutex_unlock(&log->lock);
    terrain_stacks *stacks = r->own ? replay_build(r, generated) : NULL;
    if (r->own) core_free(r->own, r->own_count * sizeof *r->own);
    core_free(r, sizeof *r);
    return stacks;
}

/* ---- compaction ------------------------------------------------------------------------- */

/* One entry with each column's final layers (columns in increasing order, as entries keep them). */
static edit_entry chunk_fold(const edit_chunk *c, entry_builder *b) {
    int32_t last[TERRAIN__COLUMNS];               /* entry that set the column last, −1 none */
    uint16_t position[TERRAIN__COLUMNS];          /* the column's place in that entry */
    for (int n = 0; n < TERRAIN__COLUMNS; n++) last[n] = -1;
    for (size_t e = 0; e < c->entry_count; e++)
        for (uint32_t p = 0; p < c->entries[e].column_count; p++) {
            last[c->entries[e].columns[p]] = (int32_t)e;
            position[c->entries[e].columns[p]] = (uint16_t)p;
        }
    for (int n = 0; n < TERRAIN__COLUMNS; n++) {
        if (last[n] < 0) continue;
        const edit_entry *from = &c->entries[last[n]];
        builder_begin_column(b, n);
        for (uint32_t l = from->starts[position[n]]; l < from->starts[position[n] + 1]; l++)
            builder_push_layer(b, from->layers[l]);
    }
    return builder_finish(b, TERRAIN_EDIT_COMPACTED);
}

/* Lock held. */
static void chunk_compact(edit_chunk *c, entry_builder *b) {
    if (c->entry_count < 2) return;               /* already one entry */
    edit_entry folded = chunk_fold(c, b);
    chunk_clear(c);
    chunk_append(c, folded);
    c->version++;                                 /* the file shrinks at the next save */
}

void terrain_edit_log_compact(terrain_edit_log *log) {
    if (!log) return;
    entry_builder b = { 0 };
    pthread_mutex_lock(&log->lock);
    for (size_t n = 0; n < log->chunk_count; n++) chunk_compact(log->chunks[n], &b);
    pthread_mutex_unlock(&log->lock);
    builder_free(&b);
}

/* ---- the file format: writing ----------------------------------------------------------- */

static uint8_t *put_u16(uint8_t *at, uint16_t v) {
    at[0] = (uint8_t)v, at[1] = (uint8_t)(v >> 8);
    return at + 2;
}

static uint8_t *put_u32(uint8_t *at, uint32_t v) {
    for (int b = 0; b < 4; b++) at[b] = (uint8_t)(v >> (8 * b));
    return at + 4;
}

static uint8_t *put_u64(uint8_t *at, uint64_t v) {
    for (int b = 0; b < 8; b++) at[b] = (uint8_t)(v >> (8 * b));
    return at + 8;
}

static size_t chunk_file_bytes(const edit_chunk *c) {
    size_t bytes = EDIT_HEADER_BYTES + EDIT_CHECKSUM_BYTES;
    for (size_t e = 0; e < c->entry_count; e++)
        bytes += 3 + 4 * (size_t)c->entries[e].column_count + 5 * (size_t)c->entries[e].layer_count;
    return bytes;
}

/* The chunk's file, in a new buffer of *size bytes (free with core_free). */
static uint8_t *chunk_serialize(const edit_chunk *c, uint64_t world_key, size_t *size) {
    *size = chunk_file_bytes(c);
    uint8_t *bytes = core_alloc(*size), *at = bytes;
    memcpy(at, EDIT_MAGIC, 8);
    at = put_u32(at + 8, EDIT_FORMAT_VERSION);
    at = put_u64(at, world_key);
    at = put_u64(at, (uint64_t)c->coord.x);
    at = put_u64(at, (uint64_t)c->coord.z);
    at = put_u32(at, (uint32_t)c->entry_count);
    for (size_t e = 0; e < c->entry_count; e++) {
        const edit_entry *entry = &c->entries[e];
        *at++ = entry->tool;
        at = put_u16(at, entry->column_count);
        for (uint32_t p = 0; p < entry->column_count; p++) {
            at = put_u16(at, entry->columns[p]);
            at = put_u16(at, (uint16_t)(entry->starts[p + 1] - entry->starts[p]));
            for (uint32_t l = entry->starts[p]; l < entry->starts[p + 1]; l++) {
                *at++ = entry->layers[l].material;
                at = put_u32(at, entry->layers[l].quanta);
            }
        }
    }
    put_u32(at, terrain__crc32(0, bytes, *size - EDIT_CHECKSUM_BYTES));
    return bytes;
}

/* ---- the file format: reading ----------------------------------------------------------- */

/* The bytes not yet read; every read checks that they hold what it takes. */
typedef struct reader {
    const uint8_t *at, *end;
} reader;

static bool read_u8(reader *r, uint8_t *v) {
    if (r->end - r->at < 1) return false;
    *v = *r->at++;
    return true;
}

static bool read_u16(reader *r, uint16_t *v) {
    if (r->end - r->at < 2) return false;
    *v = (uint16_t)(r->at[0] | r->at[1] << 8);
    r->at += 2;
    return true;
}

static uint32_t get_u32(const uint8_t *at) {
    return (uint32_t)at[0] | (uint32_t)at[1] << 8 | (uint32_t)at[2] << 16 | (uint32_t)at[3] << 24;
}

static bool read_u32(reader *r, uint32_t *v) {
    if (r->end - r->at < 4) return false;
    *v = get_u32(r->at);
    r->at += 4;
    return true;
}

static bool read_u64(reader *r, uint64_t *v) {
    if (r->end - r->at < 8) return false;
    *v = (uint64_t)get_u32(r->at) | (uint64_t)get_u32(r->at + 4) << 32;
    r->at += 8;
    return true;
}

static size_t reader_left(const reader *r) { return (size_t)(r->end - r->at); }

/* One column's layers into the builder, each checked; the column index was read already. */
static bool parse_layers(reader *r, entry_builder *b, const char *where, core_error *error) {
    uint16_t count;
    if (!read_u16(r, &count)) return core_error_set(error, CORE_ERROR_CORRUPT, "%s: ends before its layer count", where);
    if (reader_left(r) < 5 * (size_t)count)
        return core_error_set(error, CORE_ERROR_CORRUPT, "%s: %u layers need %zu bytes, %zu are left", where, count,
                                 5 * (size_t)count, reader_left(r));
    uint64_t height = 0;
    for (uint32_t l = 0; l < count; l++) {
        uint8_t material = 0;
        uint32_t quanta = 0;
        read_u8(r, &material);                    /* the size was checked above */
        read_u32(r, &quanta);
        if (material >= TERRAIN_MATERIAL_MAX)
            return core_error_set(error, CORE_ERROR_RANGE, "%s: layer %u has material %u (at most %d)", where, l,
                                     material, TERRAIN_MATERIAL_MAX - 1);
        if (quanta == 0) return core_error_set(error, CORE_ERROR_FORMAT, "%s: layer %u is 0 quanta thick", where, l);
        if (l > 0 && b->layers[b->layer_count - 1].material == material)
            return core_error_set(error, CORE_ERROR_FORMAT, "%s: layers %u and %u are both %s (unmerged)", where, l - 1,
                                     l, terrain_material_name((terrain_material)material));
        height += quanta;
        if (height >= TERRAIN__COLUMN_MAX_QUANTA)
            return core_error_set(error, CORE_ERROR_RANGE, "%s: over %d m tall", where, TERRAIN__COLUMN_MAX_QUANTA / 32);
        builder_push_layer(b, (terrain__qlayer){ material, quanta });
    }
    if (count > 0 && b->layers[b->layer_count - 1].material == TERRAIN_AIR)
        return core_error_set(error, CORE_ERROR_FORMAT, "%s: ends with air (air on top is implicit)", where);
    return true;
}

static bool parse_entry(reader *r, uint32_t index, entry_builder *b, edit_entry *out, core_error *error) {
    uint8_t tool;
    uint16_t columns;
    if (!read_u8(r, &tool) || !read_u16(r, &columns))
        return core_error_set(error, CORE_ERROR_CORRUPT, "entry %u: ends inside its header", index);
    if (!tool_valid(tool)) return core_error_set(error, CORE_ERROR_FORMAT, "entry %u: unknown tool %u", index, tool);
    if (columns == 0 || columns > TERRAIN__COLUMNS)
        return core_error_set(error, CORE_ERROR_RANGE, "entry %u: %u columns (1 … %d)", index, columns, TERRAIN__COLUMNS);
    if (reader_left(r) < 4 * (size_t)columns)
        return core_error_set(error, CORE_ERROR_CORRUPT, "entry %u: %u columns need at least %zu bytes, %zu are left",
                                 index, columns, 4 * (size_t)columns, reader_left(r));
    b->column_count = b->layer_count = 0;
    for (uint32_t p = 0; p < columns; p++) {
        uint16_t column = 0;
        read_u16(r, &column);                     /* at least 4 bytes per column are left */
        if (column >= TERRAIN__COLUMNS)
            return core_error_set(error, CORE_ERROR_RANGE, "entry %u: column index %u (at most %d)", index, column,
                                     TERRAIN__COLUMNS - 1);
        if (p > 0 && column <= b->columns[p - 1])
            return core_error_set(error, CORE_ERROR_FORMAT, "entry %u: column %u %s", index, column,
                                     column == b->columns[p - 1] ? "twice" : "out of order (indices increase)");
        char where[64];
        snprintf(where, sizeof where, "entry %u, column %u", index, column);
        builder_begin_column(b, column);
        if (!parse_layers(r, b, where, error)) return false;
    }
    *out = builder_finish(b, (terrain_edit_tool)tool);
    return true;
}

/* The header up to the entry count, checksum included; the reader is left at the first entry. */
static bool parse_header(reader *r, uint64_t world_key, terrain_chunk_coord *coord, uint32_t *entry_count,
                         core_error *error) {
    size_t size = reader_left(r);
    if (size < EDIT_HEADER_BYTES + EDIT_CHECKSUM_BYTES)
        return core_error_set(error, CORE_ERROR_CORRUPT, "truncated: %zu bytes, a file has at least %u", size,
                                 EDIT_HEADER_BYTES + EDIT_CHECKSUM_BYTES);
    if (memcmp(r->at, EDIT_MAGIC, 8) != 0) return core_error_set(error, CORE_ERROR_FORMAT, "not an edit file (wrong magic)");
    uint32_t version = get_u32(r->at + 8);
    if (version != EDIT_FORMAT_VERSION)
        return core_error_set(error, CORE_ERROR_VERSION, "format version %u (this build reads %u)", version,
                                 EDIT_FORMAT_VERSION);
    r->end -= EDIT_CHECKSUM_BYTES;
    uint32_t stored = get_u32(r->end), computed = terrain__crc32(0, r->at, size - EDIT_CHECKSUM_BYTES);
    if (stored != computed)
        return core_error_set(error, CORE_ERROR_CORRUPT, "checksum mismatch (stored %08x, computed %08x: damaged or "
                                 "truncated)", stored, computed);
    r->at += 12;
    uint64_t key = 0, x = 0, z = 0;
    read_u64(r, &key), read_u64(r, &x), read_u64(r, &z), read_u32(r, entry_count);
    if (key != world_key)
        return core_error_set(error, CORE_ERROR_MISMATCH, "saved by another world (key %016" PRIx64 ", this world's is %016"
                                 PRIx64 ")", key, world_key);
    *coord = (terrain_chunk_coord){ (int64_t)x, (int64_t)z };
    if (*entry_count == 0) return core_error_set(error, CORE_ERROR_FORMAT, "no entries");
    if (*entry_count > reader_left(r) / EDIT_MIN_ENTRY_BYTES)
        return core_error_set(error, CORE_ERROR_CORRUPT, "%u entries cannot fit in the %zu bytes left", *entry_count,
                                 reader_left(r));
    return true;
}

/* A whole file into `out` (a chunk outside any map; free with chunk_free); false with the
 * reason in `error`, nothing allocated. */
static bool parse_file(const void *bytes, size_t size, uint64_t world_key, edit_chunk **out, core_error *error) {
    reader r = { bytes, (const uint8_t *)bytes + size };
    terrain_chunk_coord coord = { 0, 0 };
    uint32_t entry_count = 0;
    if (!bytes && size > 0) return core_error_set(error, CORE_ERROR_ARGUMENT, "no bytes");
    if (!bytes) r.at = r.end = (const uint8_t *)"";
    if (!parse_header(&r, world_key, &coord, &entry_count, error)) return false;
    edit_chunk *c = core_calloc(1, sizeof *c);
    c->coord = coord;
    entry_builder b = { 0 };
    bool ok = true;
    for (uint32_t e = 0; e < entry_count && ok; e++) {
        edit_entry entry;
        ok = parse_entry(&r, e, &b, &entry, error);
        if (ok) chunk_append(c, entry);
    }
    if (ok && reader_left(&r) > 0)
        ok = core_error_set(error, CORE_ERROR_CORRUPT, "%zu bytes after the last entry", reader_left(&r));
    builder_free(&b);
    if (!ok) {
        chunk_free(c);
        return false;
    }
    *out = c;
    return true;
}

/* Replaces the log's entries for the parsed chunk by its own and frees it; the chunk is as
 * its file says (clean). */
static void install(terrain_edit_log *log, edit_chunk *parsed) {
    pthread_mutex_lock(&log->lock);
    edit_chunk *c = map_get(log, parsed->coord);
    chunk_take_entries(c, parsed);
    c->version++;
    c->saved_version = c->version;
    pthread_mutex_unlock(&log->lock);
    chunk_free(parsed);
}

bool terrain_edit_log_parse(terrain_edit_log *log, const void *bytes, size_t size, core_error *error) {
    if (!log) return core_error_set(error, CORE_ERROR_ARGUMENT, "edit log: parse with a NULL log");
    edit_chunk *parsed;
    if (!parse_file(bytes, size, log->world_key, &parsed, error)) return false;
    install(log, parsed);
    return true;
}

/* ---- paths ------------------------------------------------------------------------------ */

char *terrain__text_format(const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    int length = vsnprintf(NULL, 0, fmt, args);
    va_end(args);
    char *path = core_alloc((size_t)length + 1);
    va_start(args, fmt);
    vsnprintf(path, (size_t)length + 1, fmt, args);
    va_end(args);
    return path;
}

void terrain__text_free(char *text) {
    if (text) core_free(text, strlen(text) + 1);
}

/* The coordinate a file name "<x>_<z>.tel" stands for; false for any other name (only the
 * spelling "%lld_%lld.tel" writes counts: no "+3", "03" or "-0"). */
static bool name_coord(const char *name, terrain_chunk_coord *coord) {
    char *end, canonical[64];
    errno = 0;
    long long x = strtoll(name, &end, 10);
    if (end == name || *end != '_' || errno) return false;
    const char *second = end + 1;
    long long z = strtoll(second, &end, 10);
    if (end == second || errno) return false;
    snprintf(canonical, sizeof canonical, "%lld_%lld" EDIT_SUFFIX, x, z);
    if (strcmp(canonical, name) != 0) return false;
    *coord = (terrain_chunk_coord){ x, z };
    return true;
}

/* ---- saving ----------------------------------------------------------------------------- */

/* Writes `bytes` to folder/name through a temporary beside it (see the top of the file). */
static bool write_atomic(const char *folder, const char *name, const uint8_t *bytes, size_t size, core_error *error) {
    char *path = terrain__text_format("%s/%s", folder, name);
    char *temporary = terrain__text_format("%s/.%s.tmp.%ld", folder, name, (long)getpid());
    const char *step = "cannot create the temporary";
    bool ok = false;
    FILE *file = fopen(temporary, "wb");
    if (file) {
        step = "cannot write";
        ok = fwrite(bytes, 1, size, file) == size && fflush(file) == 0;
        if (ok) step = "cannot flush to disk", ok = fsync(fileno(file)) == 0;
        if (fclose(file) != 0 && ok) step = "cannot write", ok = false;
        if (ok) step = "cannot rename the temporary over it", ok = rename(temporary, path) == 0;
    }
    if (!ok) {
        core_error_set(error, CORE_ERROR_IO, "%s: %s (%s)", path, step, strerror(errno));
        remove(temporary);
    }
    terrain__text_free(temporary);
    terrain__text_free(path);
    return ok;
}

/* fsync on the folder makes its renames durable; file systems that cannot (EINVAL) are taken
 * at their word. */
static bool sync_folder(const char *folder, core_error *error) {
    int fd = open(folder, O_RDONLY | O_DIRECTORY);
    bool ok = fd >= 0 && (fsync(fd) == 0 || errno == EINVAL);
    if (!ok) core_error_set(error, CORE_ERROR_IO, "%s: cannot flush the folder to disk (%s)", folder, strerror(errno));
    if (fd >= 0) close(fd);
    return ok;
}

/* ---- what the store and the file layout share (terrain_internal.h) ---------------------- */

uint64_t terrain__edit_log_key(const terrain_edit_log *log) { return log->world_key; }

static terrain__edit_files chunk_files(terrain_edit_log *log, bool all, size_t compact_above) {
    terrain__edit_files files = { 0 };
    entry_builder b = { 0 };
    pthread_mutex_lock(&log->lock);
    for (size_t n = 0; n < log->chunk_count; n++) {
        edit_chunk *c = log->chunks[n];
        if ((!all && c->version == c->saved_version) || c->entry_count == 0) continue;
        if (chunk_file_bytes(c) > compact_above) chunk_compact(c, &b);   /* else a reader refuses it */
        files.items = core_grow(files.items, &files.capacity, files.count + 1, sizeof *files.items);
        terrain__edit_file *f = &files.items[files.count++];
        *f = (terrain__edit_file){ .coord = c->coord, .version = c->version };
        f->bytes = chunk_serialize(c, log->world_key, &f->size);
    }
    pthread_mutex_unlock(&log->lock);
    builder_free(&b);
    return files;
}

terrain__edit_files terrain__edit_log_dirty_files(terrain_edit_log *log, size_t compact_above) {
    return chunk_files(log, false, compact_above);
}

terrain__edit_files terrain__edit_log_all_files(terrain_edit_log *log, size_t compact_above) {
    return chunk_files(log, true, compact_above);
}

/* A chunk changed meanwhile stays dirty (its version moved). */
void terrain__edit_log_mark_saved(terrain_edit_log *log, const terrain__edit_files *files) {
    pthread_mutex_lock(&log->lock);
    for (size_t n = 0; n < files->count; n++) {
        const terrain__edit_file *f = &files->items[n];
        edit_chunk *c = map_find(log, f->coord);
        if (f->written && c && f->version > c->saved_version) c->saved_version = f->version;
    }
    pthread_mutex_unlock(&log->lock);
}

void terrain__edit_files_free(terrain__edit_files *files) {
    for (size_t n = 0; n < files->count; n++) core_free(files->items[n].bytes, files->items[n].size);
    core_free(files->items, files->capacity * sizeof *files->items);
    *files = (terrain__edit_files){ 0 };
}

void terrain__edit_log_take(terrain_edit_log *to, terrain_edit_log *from) {
    pthread_mutex_lock(&from->lock);
    for (size_t n = 0; n < from->chunk_count; n++) {
        edit_chunk *parsed = from->chunks[n];
        if (parsed->entry_count == 0) continue;
        pthread_mutex_lock(&to->lock);
        edit_chunk *c = map_get(to, parsed->coord);
        chunk_take_entries(c, parsed);
        c->version++;
        c->saved_version = c->version;
        pthread_mutex_unlock(&to->lock);
    }
    pthread_mutex_unlock(&from->lock);
}

bool terrain__edit_log_parse_chunk(terrain_edit_log *log, const void *bytes, size_t size, terrain_chunk_coord named,
                                   core_error *error) {
    edit_chunk *parsed;
    if (!parse_file(bytes, size, log->world_key, &parsed, error)) return false;
    if (parsed->coord.x != named.x || parsed->coord.z != named.z) {
        core_error_set(error, CORE_ERROR_MISMATCH, "holds chunk (%lld, %lld), not (%lld, %lld)", (long long)parsed->coord.x,
                          (long long)parsed->coord.z, (long long)named.x, (long long)named.z);
        chunk_free(parsed);
        return false;
    }
    install(log, parsed);
    return true;
}

/* Logs a failure (a save may meet several) and keeps the first in the caller's error. */
static void save_failed(const core_error *reason, bool *failed, core_error *error) {
    core_log_error("terrain", "edit log: %s", reason->message);
    if (!*failed && error) *error = *reason;
    *failed = true;
}

/* Writes every file; each that fails is logged, the rest go on (save what can be saved). */
static void write_files(const char *folder, terrain__edit_files *files, bool *failed, core_error *error) {
    core_error reason = { 0 };
    for (size_t n = 0; n < files->count; n++) {
        terrain__edit_file *f = &files->items[n];
        char name[64];
        snprintf(name, sizeof name, "%lld_%lld" EDIT_SUFFIX, (long long)f->coord.x, (long long)f->coord.z);
        f->written = write_atomic(folder, name, f->bytes, f->size, &reason);
        if (!f->written) save_failed(&reason, failed, error);
    }
    if (!sync_folder(folder, &reason)) {
        save_failed(&reason, failed, error);
        for (size_t n = 0; n < files->count; n++) files->items[n].written = false;   /* not durable: write again */
    }
}

bool terrain_edit_log_save(terrain_edit_log *log, const char *dir, core_error *error) {
    if (!log || !dir || !dir[0])
        return core_error_set(error, CORE_ERROR_ARGUMENT, "edit log: save with no %s", !log ? "log" : "folder");
    pthread_mutex_lock(&log->io_lock);
    terrain__edit_files files = terrain__edit_log_dirty_files(log, EDIT_FILE_MAX_BYTES);
    char *folder = terrain__text_format("%s/edits", dir);
    bool failed = false;
    core_error reason = { 0 };
    if (files.count > 0 && !core_make_dirs(folder)) {
        core_error_set(&reason, CORE_ERROR_IO, "%s: cannot create the folder (%s)", folder, strerror(errno));
        save_failed(&reason, &failed, error);
    }
    else if (files.count > 0) write_files(folder, &files, &failed, error);
    terrain__edit_log_mark_saved(log, &files);
    terrain__edit_files_free(&files);
    terrain__text_free(folder);
    pthread_mutex_unlock(&log->io_lock);
    return !failed;
}

/* ---- loading ---------------------------------------------------------------------------- */

/* The whole file, checked to be a regular file of at most EDIT_FILE_MAX_BYTES. */
static bool read_file(const char *path, uint8_t **bytes, size_t *size, core_error *error) {
    FILE *file = fopen(path, "rb");
    if (!file) return core_error_set(error, CORE_ERROR_IO, "cannot open (%s)", strerror(errno));
    struct stat info;
    bool ok = fstat(fileno(file), &info) == 0;
    if (!ok) core_error_set(error, CORE_ERROR_IO, "cannot read (%s)", strerror(errno));
    else if (!S_ISREG(info.st_mode)) ok = core_error_set(error, CORE_ERROR_FORMAT, "not a regular file");
    else if ((uint64_t)info.st_size > EDIT_FILE_MAX_BYTES)
        ok = core_error_set(error, CORE_ERROR_RANGE, "%lld bytes, over the limit of %zu", (long long)info.st_size,
                               EDIT_FILE_MAX_BYTES);
    if (ok) {
        *size = (size_t)info.st_size;
        *bytes = core_alloc(*size + 1);           /* + 1: the file may have grown meanwhile */
        size_t got = fread(*bytes, 1, *size + 1, file);
        if (got != *size) {
            ok = core_error_set(error, CORE_ERROR_IO, "cannot read (%s)", ferror(file) ? strerror(errno) : "its size changed");
            core_free(*bytes, *size + 1);
        }
    }
    fclose(file);
    return ok;
}

/* One chunk file into the log; false with the reason (without the path) in `error`. */
static bool load_file(terrain_edit_log *log, const char *path, terrain_chunk_coord named, core_error *error) {
    uint8_t *bytes = NULL;
    size_t size = 0;
    if (!read_file(path, &bytes, &size, error)) return false;
    bool ok = terrain__edit_log_parse_chunk(log, bytes, size, named, error);
    core_free(bytes, size + 1);
    return ok;
}

/* A file that failed: reported, renamed to <name>.bad for a human to look at. */
static void reject(const char *path, const core_error *reason, terrain_edit_log_load_result *result) {
    core_log_error("terrain", "edit log: %s: %s; renamed to .bad, the chunk stays as generated", path, reason->message);
    if (result->files_rejected++ == 0)
        core_error_set(&result->first_problem, reason->code, "%s: %s", path, reason->message);
    char *bad = terrain__text_format("%s.bad", path);
    if (rename(path, bad) != 0) core_log_error("terrain", "edit log: cannot rename %s to %s: %s", path, bad, strerror(errno));
    terrain__text_free(bad);
}

/* Handles one folder entry: a chunk file, a leftover temporary, or something else (left). */
static void load_entry(terrain_edit_log *log, const char *folder, const char *name,
                       terrain_edit_log_load_result *result) {
    terrain_chunk_coord coord;
    if (name[0] == '.' && strstr(name, EDIT_TEMP_MARK)) {
        char *path = terrain__text_format("%s/%s", folder, name);
        if (remove(path) != 0) core_warn("terrain", "edit log: cannot remove %s: %s", path, strerror(errno));
        terrain__text_free(path);
        return;
    }
    if (!name_coord(name, &coord)) return;
    char *path = terrain__text_format("%s/%s", folder, name);
    core_error reason = { 0 };
    if (load_file(log, path, coord, &reason)) result->chunks_loaded++;
    else reject(path, &reason, result);
    terrain__text_free(path);
}

/* Whether `path` is a folder: true and *exists false when it is missing. */
static bool check_folder(const char *path, bool *exists, core_error *error) {
    struct stat info;
    *exists = stat(path, &info) == 0;
    if (!*exists && errno == ENOENT) return true;
    if (!*exists) core_error_set(error, CORE_ERROR_IO, "%s: cannot look at it (%s)", path, strerror(errno));
    else if (!S_ISDIR(info.st_mode)) core_error_set(error, CORE_ERROR_IO, "%s: not a folder", path);
    return *exists && S_ISDIR(info.st_mode);
}

bool terrain_edit_log_load(terrain_edit_log *log, const char *dir, terrain_edit_log_load_result *result,
                           core_error *error) {
    terrain_edit_log_load_result ignored;
    if (!result) result = &ignored;
    memset(result, 0, sizeof *result);
    if (!log || !dir || !dir[0])
        return core_error_set(error, CORE_ERROR_ARGUMENT, "edit log: load with no %s", !log ? "log" : "folder");
    bool exists;
    if (!check_folder(dir, &exists, error)) return false;
    if (!exists) return true;                     /* a new world */
    char *folder = terrain__text_format("%s/edits", dir);
    bool ok = check_folder(folder, &exists, error);
    DIR *listing = ok && exists ? opendir(folder) : NULL;
    if (ok && exists && !listing)
        ok = core_error_set(error, CORE_ERROR_IO, "%s: cannot list (%s)", folder, strerror(errno));
    if (listing) {
        pthread_mutex_lock(&log->io_lock);
        for (struct dirent *entry; (entry = readdir(listing));) load_entry(log, folder, entry->d_name, result);
        pthread_mutex_unlock(&log->io_lock);
        closedir(listing);
    }
    terrain__text_free(folder);
    return ok;
}
