/* The edit log: record and replay on generated chunks (edits made by hand through a columns
 * region), compaction, files (the format checked against its description, byte by byte, with
 * files written here by hand), corruption of every kind, and a saver killed at random moments.
 * Expected stacks are always the hand-edited ones, compared by hash and by bytes. */
#include "../engine/test.h"
#include "test_files.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define N TERRAIN_CHUNK_COLUMNS
#define SEED 3
#define HEADER 40                            /* bytes before the first entry (the format) */
#define TRAILER 4                            /* the CRC-32 */

/* ---- helpers -------------------------------------------------------------------------- */

static uint64_t key_of(uint64_t seed) {
    terrain_generation_desc params = terrain_generation_defaults(seed);
    return terrain_generation_key(&params);
}

static terrain_stacks *generated(terrain_chunk_coord coord) {
    terrain_generation_desc params = terrain_generation_defaults(SEED);
    return terrain_generate_chunk(&params, coord);
}

/* `from` with about `count` columns (picked by hashing `salt`) replaced by hand: bedrock, sand,
 * sometimes a cave of air and rocks, sometimes water, of hashed thicknesses. */
static terrain_stacks *edited(const terrain_stacks *from, terrain_chunk_coord coord, uint64_t salt, int count) {
    terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
        .x = coord.x * N, .z = coord.z * N, .width = N, .depth = N });
    cr_assert(terrain_columns_load(region, coord, from));
    for (int j = 0; j < count; j++) {
        uint64_t h = core_hash_u64(salt * 1000003u + (uint64_t)j);
        terrain_layer layers[6];
        int n = 0;
        layers[n++] = (terrain_layer){ TERRAIN_BEDROCK, 200.0f + (float)(h >> 20 & 4095) / 32.0f };
        if (h & 1) layers[n++] = (terrain_layer){ TERRAIN_AIR, (float)(h >> 32 & 127) / 32.0f + 2.0f };
        if (h & 2) layers[n++] = (terrain_layer){ TERRAIN_BEDROCK, (float)(h >> 40 & 63) / 32.0f + 1.0f };
        layers[n++] = (terrain_layer){ TERRAIN_SAND, (float)(h >> 46 & 63) / 32.0f };
        if (h & 4) layers[n++] = (terrain_layer){ TERRAIN_ROCKS, (float)(h >> 52 & 31) / 32.0f };
        if (h & 8) layers[n++] = (terrain_layer){ TERRAIN_WATER, 3.0f };
        cr_assert(terrain_columns_set(region, (int)(h % N), (int)(h >> 8 & (N - 1)), layers, n));
    }
    terrain_stacks *out = terrain_columns_to_stacks(region, coord);
    terrain_columns_destroy(region);
    cr_assert_not_null(out);
    return out;
}

static bool same_bytes(const terrain_stacks *a, const terrain_stacks *b) {
    return a && b && terrain_stacks_bytes(a) == terrain_stacks_bytes(b) &&
           memcmp(a, b, terrain_stacks_bytes(a)) == 0;
}

/* Replays the chunk over `base` and checks the result equals `expected`, hash and bytes. */
static void expect_replay(terrain_edit_log *log, terrain_chunk_coord coord, const terrain_stacks *base,
                          const terrain_stacks *expected) {
    terrain_stacks *got = terrain_edit_log_replay(log, coord, base);
    cr_assert_not_null(got, "chunk (%lld, %lld) has entries", (long long)coord.x, (long long)coord.z);
    cr_expect_eq(terrain_stacks_hash(got), terrain_stacks_hash(expected));
    cr_expect(same_bytes(got, expected), "chunk (%lld, %lld): replay bytes differ", (long long)coord.x,
              (long long)coord.z);
    terrain_stacks_destroy(got);
}

/* Columns (index k·N + i) where the two stacks read differently; their count. */
static int changed_columns(const terrain_stacks *a, const terrain_stacks *b, bool *changed) {
    int count = 0;
    for (int n = 0; n < N * N; n++) {
        terrain_layer la[64], lb[64];
        int ca = terrain_stacks_column(a, n % N, n / N, la, 64), cb = terrain_stacks_column(b, n % N, n / N, lb, 64);
        cr_assert(ca <= 64 && cb <= 64);
        bool same = ca == cb;
        for (int l = 0; l < ca && same; l++)
            same = la[l].material == lb[l].material && la[l].thickness == lb[l].thickness;
        changed[n] = !same;
        count += !same;
    }
    return count;
}

static void chunk_path(char *out, size_t size, const char *dir, terrain_chunk_coord c) {
    snprintf(out, size, "%s/edits/%lld_%lld.tel", dir, (long long)c.x, (long long)c.z);
}

/* Count of names in DIR/edits containing `part`. */
static int count_names(const char *dir, const char *part) {
    char folder[512];
    snprintf(folder, sizeof folder, "%s/edits", dir);
    DIR *d = opendir(folder);
    if (!d) return 0;
    int count = 0;
    for (struct dirent *e; (e = readdir(d));) count += strstr(e->d_name, part) != NULL;
    closedir(d);
    return count;
}

/* A new log with `key`, loaded from `dir` (the load itself must succeed). */
static terrain_edit_log *load_new(const char *dir, uint64_t key, terrain_edit_log_load_result *result) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key });
    core_error error = { 0 };
    cr_assert(terrain_edit_log_load(log, dir, result, &error), "%s", error.message);
    return log;
}

/* ---- names, keys, the stacks helpers ---------------------------------------------------- */

Test(terrain_edit_log, tool_names) {
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_SET), "set");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_SCULPT_ADD), "sculpt_add");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_SCULPT_CARVE), "sculpt_carve");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_SWEEP), "sweep");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_DEPOSIT), "deposit");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_ERODE), "erode");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_STABILIZE), "stabilize");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_COMPACTED), "compacted");
    cr_expect_str_eq(terrain_edit_tool_name((terrain_edit_tool)0), "unknown");
    cr_expect_str_eq(terrain_edit_tool_name(TERRAIN_EDIT_TOOL_COUNT), "unknown");
    cr_expect_str_eq(terrain_edit_tool_name((terrain_edit_tool)-1), "unknown");
}

Test(terrain_edit_log, generation_key_covers_every_parameter) {
    terrain_generation_desc a = terrain_generation_defaults(42), b = terrain_generation_defaults(42);
    cr_expect_eq(terrain_generation_key(&a), terrain_generation_key(&b), "equal parameters, equal keys");
    b.seed = 43;
    cr_expect_neq(terrain_generation_key(&a), terrain_generation_key(&b), "another seed");
    /* Each field changed alone gives a key of its own. */
    const size_t floats[] = {
        offsetof(terrain_generation_desc, sea_level), offsetof(terrain_generation_desc, relief_height),
        offsetof(terrain_generation_desc, base_height), offsetof(terrain_generation_desc, relief_wavelength),
        offsetof(terrain_generation_desc, lacunarity), offsetof(terrain_generation_desc, hurst),
        offsetof(terrain_generation_desc, warp_strength),
        offsetof(terrain_generation_desc, vertical_perturbation),
        offsetof(terrain_generation_desc, horizontal_perturbation),
        offsetof(terrain_generation_desc, perturbation_wavelength),
        offsetof(terrain_generation_desc, cave_threshold), offsetof(terrain_generation_desc, cave_wavelength),
        offsetof(terrain_generation_desc, cave_fade_height), offsetof(terrain_generation_desc, sand_max_slope),
        offsetof(terrain_generation_desc, sand_depth), offsetof(terrain_generation_desc, lake_spacing),
        offsetof(terrain_generation_desc, lake_probability), offsetof(terrain_generation_desc, lake_radius_min),
        offsetof(terrain_generation_desc, lake_radius_max), offsetof(terrain_generation_desc, lake_depth),
        offsetof(terrain_generation_desc, talus_depth), offsetof(terrain_generation_desc, scree_depth),
        offsetof(terrain_generation_desc, scree_min_slope), offsetof(terrain_generation_desc, lake_rocks_depth) };
    const size_t ints[] = { offsetof(terrain_generation_desc, relief_octaves),
                            offsetof(terrain_generation_desc, perturbation_octaves) };
    enum { FIELDS = CORE_COUNTOF(floats) + CORE_COUNTOF(ints) };
    uint64_t keys[FIELDS + 1];
    keys[FIELDS] = terrain_generation_key(&a);
    for (size_t f = 0; f < FIELDS; f++) {
        terrain_generation_desc p = a;
        if (f < CORE_COUNTOF(floats)) *(float *)((char *)&p + floats[f]) += 0.5f;
        else *(int *)((char *)&p + ints[f - CORE_COUNTOF(floats)]) += 1;
        keys[f] = terrain_generation_key(&p);
    }
    for (int x = 0; x <= FIELDS; x++)
        for (int y = x + 1; y <= FIELDS; y++) cr_expect_neq(keys[x], keys[y], "fields %d and %d", x, y);
    /* −0 and +0 are equal parameters. */
    terrain_generation_desc plus = a, minus = a;
    plus.warp_strength = 0.0f, minus.warp_strength = -0.0f;
    cr_expect_eq(terrain_generation_key(&plus), terrain_generation_key(&minus));
}

Test(terrain_edit_log, crc32_is_zlibs) {
    /* The standard check value of CRC-32/ISO-HDLC (zlib.crc32(b"123456789")). */
    cr_expect_eq(terrain__crc32(0, "123456789", 9), 0xcbf43926u);
    cr_expect_eq(terrain__crc32(0, "", 0), 0u);
    cr_expect_eq(terrain__crc32(terrain__crc32(0, "1234", 4), "56789", 5), 0xcbf43926u, "continued");
}

/* A column of one layer of q quanta packs as the rules of terrain_internal.h say: 1 word up to
 * 4095, 2 up to 65 535, longer ones split into 65 535-quanta entries. */
Test(terrain_edit_log, layer_words_match_the_packing) {
    const uint32_t quanta[] = { 1, 4095, 4096, 65535, 65536, 65535 + 4096, 131070, 1000000 };
    const uint32_t words[] = { 1, 1, 2, 2, 3, 4, 4, 2 * 15 + 2 };   /* 1e6 = 15·65535 + 16975 */
    for (size_t n = 0; n < CORE_COUNTOF(quanta); n++) {
        cr_expect_eq(terrain__stacks_layer_words(quanta[n]), words[n], "%u quanta", quanta[n]);
        terrain_stacks_builder *b = terrain_stacks_builder_create();
        for (int c = 0; c < N * N; c++) {
            if (c == 0) terrain__stacks_builder_push_quanta(b, TERRAIN_BEDROCK, quanta[n]);
            terrain_stacks_builder_end_column(b);
        }
        terrain_stacks *s = terrain_stacks_builder_finish(b);
        terrain__column_cursor cursor = terrain__stacks_cursor(s, 0, 0);
        cr_expect_eq((uint32_t)(cursor.end - cursor.word), words[n], "%u quanta packed", quanta[n]);
        terrain__qlayer layer;
        cr_expect(terrain__cursor_next(&cursor, &layer));
        cr_expect_eq(layer.quanta, quanta[n], "read back exactly");
        terrain_stacks_destroy(s);
        terrain_stacks_builder_destroy(b);
    }
}

/* Beyond 2^24 quanta a float cannot carry every thickness; the quanta push stays exact. */
Test(terrain_edit_log, quanta_push_is_exact_beyond_float_precision) {
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    const uint32_t tall = (1u << 25) + 1;          /* not a float */
    for (int c = 0; c < N * N; c++) {
        terrain__stacks_builder_push_quanta(b, TERRAIN_BEDROCK, tall);
        terrain__stacks_builder_push_quanta(b, TERRAIN_SAND, 3);
        terrain__stacks_builder_push_quanta(b, TERRAIN_SAND, 4);       /* merges */
        terrain_stacks_builder_push(b, TERRAIN_WATER, 0.5f);          /* float after quanta */
        terrain_stacks_builder_end_column(b);
    }
    terrain_stacks *s = terrain_stacks_builder_finish(b);
    terrain__column_cursor cursor = terrain__stacks_cursor(s, 7, 9);
    terrain__qlayer layer;
    cr_assert(terrain__cursor_next(&cursor, &layer));
    cr_expect(layer.material == TERRAIN_BEDROCK && layer.quanta == tall);
    cr_assert(terrain__cursor_next(&cursor, &layer));
    cr_expect(layer.material == TERRAIN_SAND && layer.quanta == 7);
    cr_assert(terrain__cursor_next(&cursor, &layer));
    cr_expect(layer.material == TERRAIN_WATER && layer.quanta == 16);
    cr_expect_not(terrain__cursor_next(&cursor, &layer));
    terrain_stacks_destroy(s);
    terrain_stacks_builder_destroy(b);
}

/* ---- record, replay, compact ------------------------------------------------------------ */

Test(terrain_edit_log, record_then_replay_gives_the_edited_bytes) {
    terrain_chunk_coord coord = { 2, -1 };
    terrain_stacks *g = generated(coord), *a = edited(g, coord, 1, 40);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    cr_expect_eq(terrain_edit_log_chunks(log), 0);
    cr_expect_null(terrain_edit_log_replay(log, coord, g), "no entries: NULL");
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, a));
    cr_expect_eq(terrain_edit_log_entries(log, coord), 1);
    cr_expect_eq(terrain_edit_log_entries(log, (terrain_chunk_coord){ 2, 1 }), 0);
    cr_expect_eq(terrain_edit_log_chunks(log), 1);
    cr_expect_neq(terrain_stacks_hash(g), terrain_stacks_hash(a), "the edit changed something");
    expect_replay(log, coord, g, a);
    expect_replay(log, coord, g, a);               /* replay leaves the log as it was */
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(a);
    terrain_stacks_destroy(g);
}

Test(terrain_edit_log, later_entries_override_earlier_columns) {
    terrain_chunk_coord coord = { -3, 5 };
    terrain_stacks *g = generated(coord), *a = edited(g, coord, 2, 40), *b = edited(a, coord, 3, 60);
    terrain_stacks *c = edited(b, coord, 2, 20);   /* the first 20 of a's columns, set again alike */
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SCULPT_ADD, g, a));
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_DEPOSIT, a, b));
    cr_expect_eq(terrain_edit_log_entries(log, coord), 2);
    expect_replay(log, coord, g, b);
    /* Back to generated ground in some columns: a later entry holding the generated layers. */
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_ERODE, b, g));
    cr_expect_eq(terrain_edit_log_entries(log, coord), 3);
    expect_replay(log, coord, g, g);
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, c));
    expect_replay(log, coord, g, c);
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(c);
    terrain_stacks_destroy(b);
    terrain_stacks_destroy(a);
    terrain_stacks_destroy(g);
}

Test(terrain_edit_log, equal_stacks_record_nothing) {
    terrain_chunk_coord coord = { 0, 0 };
    terrain_stacks *g = generated(coord), *same = edited(g, coord, 9, 0);   /* loaded, written back */
    cr_assert(same_bytes(g, same));
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    cr_expect(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, g));
    cr_expect(terrain_edit_log_record(log, coord, TERRAIN_EDIT_STABILIZE, g, same));
    cr_expect_eq(terrain_edit_log_entries(log, coord), 0);
    cr_expect_eq(terrain_edit_log_chunks(log), 0);
    cr_expect_null(terrain_edit_log_replay(log, coord, g));
    cr_expect_not(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, NULL, g), "NULL stacks");
    cr_expect_not(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, NULL));
    cr_expect_not(terrain_edit_log_record(log, coord, (terrain_edit_tool)0, g, same), "unknown tool");
    cr_expect_null(terrain_edit_log_replay(log, coord, NULL));
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(same);
    terrain_stacks_destroy(g);
}

/* `base` with column n replaced: `layers` layers alternating bedrock and sand, `quanta` each. */
static terrain_stacks *with_column(const terrain_stacks *base, int column, uint32_t layers, uint32_t quanta) {
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    for (int n = 0; n < N * N; n++) {
        terrain__column_cursor cursor = terrain__stacks_cursor(base, n % N, n / N);
        terrain__qlayer layer;
        if (n == column)
            for (uint32_t l = 0; l < layers; l++)
                terrain__stacks_builder_push_quanta(b, l % 2 ? TERRAIN_SAND : TERRAIN_BEDROCK, quanta);
        else
            while (terrain__cursor_next(&cursor, &layer))
                terrain__stacks_builder_push_quanta(b, (terrain_material)layer.material, layer.quanta);
        terrain_stacks_builder_end_column(b);
    }
    terrain_stacks *s = terrain_stacks_builder_finish(b);
    terrain_stacks_builder_destroy(b);
    return s;
}

/* Columns no file could hold (65 536 layers; 2^26 quanta, where columns regions stop too) are
 * refused whole; one layer less, one quantum less, they are recorded. The last column of a row
 * may be that long in stacks. */
Test(terrain_edit_log, record_refuses_columns_no_file_could_hold) {
    terrain_chunk_coord coord = { 0, 0 };
    terrain_stacks *g = generated(coord);
    terrain_stacks *many = with_column(g, N - 1, 65536, 1), *tall = with_column(g, 40, 1, 1u << 26);
    terrain_stacks *most = with_column(g, N - 1, 65535, 1), *tallest = with_column(g, 40, 1, (1u << 26) - 1);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    cr_expect_not(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, many));
    cr_expect_not(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, tall));
    cr_expect_eq(terrain_edit_log_entries(log, coord), 0);
    cr_expect(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, most));
    expect_replay(log, coord, g, most);
    cr_expect(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, most, tallest));
    expect_replay(log, coord, g, tallest);   /* column 31 back to generated, column 40 tall */
    /* And both survive a file. */
    char dir[128];
    core_error error = { 0 };
    make_temp_dir(dir, sizeof dir);
    cr_assert(terrain_edit_log_save(log, dir, &error), "%s", error.message);
    terrain_edit_log_load_result result;
    terrain_edit_log *loaded = load_new(dir, key_of(SEED), &result);
    cr_expect_eq(result.chunks_loaded, 1, "%s", result.first_problem.message);
    expect_replay(loaded, coord, g, tallest);
    terrain_edit_log_destroy(loaded);
    remove_tree(dir);
    terrain_edit_log_destroy(log);
    terrain_stacks *stacks[] = { g, many, tall, most, tallest };
    for (size_t n = 0; n < CORE_COUNTOF(stacks); n++) terrain_stacks_destroy(stacks[n]);
}

Test(terrain_edit_log, compact_folds_to_one_entry_with_the_same_replay) {
    terrain_chunk_coord one = { 1, 1 }, two = { 4, -2 };
    terrain_stacks *g1 = generated(one), *g2 = generated(two);
    terrain_stacks *s[4] = { g1, NULL, NULL, NULL };
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    for (int n = 1; n < 4; n++) {
        s[n] = edited(s[n - 1], one, (uint64_t)(10 + n), 30);
        cr_assert(terrain_edit_log_record(log, one, TERRAIN_EDIT_SWEEP, s[n - 1], s[n]));
    }
    terrain_stacks *single = edited(g2, two, 20, 10);
    cr_assert(terrain_edit_log_record(log, two, TERRAIN_EDIT_ERODE, g2, single));
    cr_expect_eq(terrain_edit_log_entries(log, one), 3);
    terrain_edit_log_compact(log);
    cr_expect_eq(terrain_edit_log_entries(log, one), 1);
    cr_expect_eq(terrain_edit_log_entries(log, two), 1);
    cr_expect_eq(terrain_edit_log_chunks(log), 2);
    expect_replay(log, one, g1, s[3]);
    expect_replay(log, two, g2, single);
    /* Recording goes on after compaction. */
    terrain_stacks *more = edited(s[3], one, 99, 5);
    cr_assert(terrain_edit_log_record(log, one, TERRAIN_EDIT_SET, s[3], more));
    cr_expect_eq(terrain_edit_log_entries(log, one), 2);
    expect_replay(log, one, g1, more);
    terrain_edit_log_compact(log);
    expect_replay(log, one, g1, more);
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(more);
    terrain_stacks_destroy(single);
    for (int n = 0; n < 4; n++) terrain_stacks_destroy(s[n]);
    terrain_stacks_destroy(g2);
}

/* ---- files ------------------------------------------------------------------------------ */

/* Three chunks, one with three entries; saved, loaded into a new log, replayed. */
typedef struct world_fixture {
    terrain_chunk_coord coord[3];
    terrain_stacks *base[3], *final[3];
    terrain_edit_log *log;
    char dir[128];
} world_fixture;

static void fixture_make(world_fixture *w) {
    const terrain_chunk_coord coords[3] = { { 0, 0 }, { -1, 7 }, { 2000, -3000 } };
    w->log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    for (int c = 0; c < 3; c++) {
        w->coord[c] = coords[c];
        w->base[c] = generated(coords[c]);
        terrain_stacks *at = w->base[c];
        for (int e = 0; e < (c == 1 ? 3 : 1); e++) {
            terrain_stacks *next = edited(at, coords[c], (uint64_t)(100 * c + e), 40);
            cr_assert(terrain_edit_log_record(w->log, coords[c], TERRAIN_EDIT_SET + e, at, next));
            if (at != w->base[c]) terrain_stacks_destroy(at);
            at = next;
        }
        w->final[c] = at;
    }
    make_temp_dir(w->dir, sizeof w->dir);
}

static void fixture_free(world_fixture *w) {
    for (int c = 0; c < 3; c++) terrain_stacks_destroy(w->base[c]), terrain_stacks_destroy(w->final[c]);
    terrain_edit_log_destroy(w->log);
    remove_tree(w->dir);
}

Test(terrain_edit_log, save_then_load_replays_the_same_bytes) {
    world_fixture w;
    fixture_make(&w);
    char path[512];
    core_error error = { 0 };
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    for (int c = 0; c < 3; c++) {
        chunk_path(path, sizeof path, w.dir, w.coord[c]);
        cr_expect(exists(path), "%s", path);
    }
    cr_expect_eq(count_names(w.dir, ".tmp."), 0, "no temporaries left");
    terrain_edit_log_load_result result;
    terrain_edit_log *loaded = load_new(w.dir, key_of(SEED), &result);
    cr_expect_eq(result.chunks_loaded, 3);
    cr_expect_eq(result.files_rejected, 0);
    cr_expect_eq(result.first_problem.code, CORE_ERROR_NONE, "%s", result.first_problem.message);
    cr_expect_eq(terrain_edit_log_chunks(loaded), 3);
    cr_expect_eq(terrain_edit_log_entries(loaded, w.coord[1]), 3);
    for (int c = 0; c < 3; c++) expect_replay(loaded, w.coord[c], w.base[c], w.final[c]);
    terrain_edit_log_destroy(loaded);
    fixture_free(&w);
}

/* Sets a file's times to 2000-01-01, so that a rewrite (a new file, now) shows. */
static void age(const char *path) {
    struct timespec times[2] = { { 946684800, 0 }, { 946684800, 0 } };
    cr_assert_eq(utimensat(AT_FDCWD, path, times, 0), 0, "%s", path);
}

static bool rewritten(const char *path) {
    struct stat info;
    cr_assert_eq(stat(path, &info), 0, "%s", path);
    return info.st_mtime != 946684800;
}

Test(terrain_edit_log, save_writes_only_chunks_changed_since) {
    world_fixture w;
    fixture_make(&w);
    char path[3][512];
    core_error error = { 0 };
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    for (int c = 0; c < 3; c++) chunk_path(path[c], sizeof path[c], w.dir, w.coord[c]), age(path[c]);
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    for (int c = 0; c < 3; c++) cr_expect_not(rewritten(path[c]), "nothing changed: %s kept", path[c]);

    terrain_stacks *more = edited(w.final[2], w.coord[2], 77, 3);
    cr_assert(terrain_edit_log_record(w.log, w.coord[2], TERRAIN_EDIT_SET, w.final[2], more));
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    cr_expect_not(rewritten(path[0]));
    cr_expect_not(rewritten(path[1]));
    cr_expect(rewritten(path[2]), "the changed chunk is written");

    /* Compaction changes the file of a chunk with several entries only. */
    age(path[2]);
    terrain_edit_log_compact(w.log);
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    cr_expect_not(rewritten(path[0]), "one entry: not compacted");
    cr_expect(rewritten(path[1]));
    cr_expect(rewritten(path[2]));

    /* A loaded log is clean: saving it writes nothing. */
    for (int c = 0; c < 3; c++) age(path[c]);
    terrain_edit_log_load_result result;
    terrain_edit_log *loaded = load_new(w.dir, key_of(SEED), &result);
    cr_assert(terrain_edit_log_save(loaded, w.dir, &error), "%s", error.message);
    for (int c = 0; c < 3; c++) cr_expect_not(rewritten(path[c]));
    expect_replay(loaded, w.coord[2], w.base[2], more);
    terrain_edit_log_destroy(loaded);
    terrain_stacks_destroy(more);
    fixture_free(&w);
}

Test(terrain_edit_log, save_failure_keeps_chunks_for_the_next_save) {
    world_fixture w;
    fixture_make(&w);
    char blocker[512], path[512];
    core_error error = { 0 };
    /* DIR/edits is a file: the folder cannot be made. */
    snprintf(blocker, sizeof blocker, "%s/edits", w.dir);
    write_all(blocker, "x", 1);
    cr_expect_not(terrain_edit_log_save(w.log, w.dir, &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s: %s", core_error_code_name(error.code), error.message);
    cr_expect(strstr(error.message, blocker) == error.message, "names the path: %s", error.message);
    unlink(blocker);
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    for (int c = 0; c < 3; c++) {
        chunk_path(path, sizeof path, w.dir, w.coord[c]);
        cr_expect(exists(path), "%s", path);
    }
    /* A folder made on the way (mkdir -p). */
    char deep[256];
    snprintf(deep, sizeof deep, "%s/a/b/c", w.dir);
    cr_assert(terrain_edit_log_save(w.log, deep, &error), "nothing dirty: %s", error.message);
    cr_expect_not(exists(deep), "nothing to write, nothing made");
    terrain_edit_log_compact(w.log);
    cr_assert(terrain_edit_log_save(w.log, deep, &error), "%s", error.message);
    chunk_path(path, sizeof path, deep, w.coord[1]);
    cr_expect(exists(path), "%s", path);
    fixture_free(&w);
}

Test(terrain_edit_log, missing_folder_is_an_empty_world_and_a_file_is_refused) {
    char dir[128], path[512];
    make_temp_dir(dir, sizeof dir);
    terrain_edit_log_load_result result;
    snprintf(path, sizeof path, "%s/none", dir);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    core_error error = { 0 };
    cr_expect(terrain_edit_log_load(log, path, &result, &error));
    cr_expect_eq(result.chunks_loaded + result.files_rejected, 0);
    cr_expect(terrain_edit_log_load(log, dir, &result, &error), "no edits folder yet");
    cr_expect_eq(error.code, CORE_ERROR_NONE, "%s", error.message);
    snprintf(path, sizeof path, "%s/file", dir);
    write_all(path, "x", 1);
    cr_expect_not(terrain_edit_log_load(log, path, &result, &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s: %s", core_error_code_name(error.code), error.message);
    cr_expect(strstr(error.message, path) == error.message, "names the path: %s", error.message);
    cr_expect_not(terrain_edit_log_load(log, NULL, &result, &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s", error.message);
    cr_expect_eq(terrain_edit_log_chunks(log), 0);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
}

Test(terrain_edit_log, load_ignores_other_files_and_removes_temporaries) {
    world_fixture w;
    fixture_make(&w);
    char path[512];
    core_error error = { 0 };
    cr_assert(terrain_edit_log_save(w.log, w.dir, &error), "%s", error.message);
    const char *others[] = { "notes.txt", "1_2.tel.bad", "01_2.tel", "+1_2.tel", "1_2.tel~", "1_2_3.tel" };
    for (size_t n = 0; n < CORE_COUNTOF(others); n++)
        snprintf(path, sizeof path, "%s/edits/%s", w.dir, others[n]), write_all(path, "junk", 4);
    snprintf(path, sizeof path, "%s/edits/.0_0.tel.tmp.12345", w.dir);
    write_all(path, "half a file", 11);
    terrain_edit_log_load_result result;
    terrain_edit_log *loaded = load_new(w.dir, key_of(SEED), &result);
    cr_expect_eq(result.chunks_loaded, 3);
    cr_expect_eq(result.files_rejected, 0, "%s", result.first_problem.message);
    cr_expect_not(exists(path), "the leftover temporary is gone");
    for (size_t n = 0; n < CORE_COUNTOF(others); n++) {
        snprintf(path, sizeof path, "%s/edits/%s", w.dir, others[n]);
        cr_expect(exists(path), "%s kept", path);
    }
    terrain_edit_log_destroy(loaded);
    fixture_free(&w);
}

/* The file of an entry is what the format says: header, then per changed column 4 bytes and 5
 * per layer, then the CRC; the size follows from the columns that changed alone. */
Test(terrain_edit_log, file_size_and_header_follow_the_format) {
    terrain_chunk_coord coord = { -5, 3 };
    terrain_stacks *g = generated(coord), *a = edited(g, coord, 5, 40);
    bool changed[N * N];
    int columns = changed_columns(g, a, changed);
    cr_assert_gt(columns, 30);
    size_t expected = HEADER + 3 + TRAILER;
    for (int n = 0; n < N * N; n++)
        if (changed[n]) expected += 4 + 5 * (size_t)terrain_stacks_column(a, n % N, n / N, NULL, 0);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_DEPOSIT, g, a));
    char dir[128], path[512];
    core_error error = { 0 };
    make_temp_dir(dir, sizeof dir);
    cr_assert(terrain_edit_log_save(log, dir, &error), "%s", error.message);
    chunk_path(path, sizeof path, dir, coord);
    size_t size;
    uint8_t *bytes = read_all(path, &size);
    cr_expect_eq(size, expected);
    cr_expect_eq(memcmp(bytes, "TEDITLOG", 8), 0);
    uint64_t key = 0, x = 0, z = 0;
    for (int b = 7; b >= 0; b--) key = key << 8 | bytes[12 + b], x = x << 8 | bytes[20 + b], z = z << 8 | bytes[28 + b];
    cr_expect_eq(bytes[8] | bytes[9] << 8 | bytes[10] << 16 | bytes[11] << 24, 1, "version 1");
    cr_expect_eq(key, key_of(SEED));
    cr_expect_eq((int64_t)x, -5);
    cr_expect_eq((int64_t)z, 3);
    cr_expect_eq(bytes[36] | bytes[37] << 8, 1, "one entry");
    cr_expect_eq(bytes[40], TERRAIN_EDIT_DEPOSIT);
    cr_expect_eq(bytes[41] | bytes[42] << 8, columns);
    uint32_t crc = (uint32_t)bytes[size - 4] | (uint32_t)bytes[size - 3] << 8 | (uint32_t)bytes[size - 2] << 16 |
                   (uint32_t)bytes[size - 1] << 24;
    cr_expect_eq(crc, terrain__crc32(0, bytes, size - 4));
    free(bytes);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
    terrain_stacks_destroy(a);
    terrain_stacks_destroy(g);
}

/* File names and headers carry any coordinate (the log does not care what the stacks are). */
Test(terrain_edit_log, extreme_coordinates_round_trip) {
    const terrain_chunk_coord coord = { INT64_MIN, INT64_MAX };
    terrain_stacks *g = generated((terrain_chunk_coord){ 0, 0 }), *a = edited(g, (terrain_chunk_coord){ 0, 0 }, 8, 10);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, a));
    char dir[128], path[512];
    core_error error = { 0 };
    make_temp_dir(dir, sizeof dir);
    cr_assert(terrain_edit_log_save(log, dir, &error), "%s", error.message);
    snprintf(path, sizeof path, "%s/edits/-9223372036854775808_9223372036854775807.tel", dir);
    cr_expect(exists(path), "%s", path);
    terrain_edit_log_load_result result;
    terrain_edit_log *loaded = load_new(dir, key_of(SEED), &result);
    cr_expect_eq(result.chunks_loaded, 1, "%s", result.first_problem.message);
    expect_replay(loaded, coord, g, a);
    terrain_edit_log_destroy(loaded);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
    terrain_stacks_destroy(a);
    terrain_stacks_destroy(g);
}

/* ---- files written by hand ---------------------------------------------------------------- */

typedef struct bytes_out {
    uint8_t *data;
    size_t size, capacity;
} bytes_out;

static void put(bytes_out *o, uint64_t value, int count) {
    if (o->size + (size_t)count > o->capacity) {
        o->capacity = (o->size + (size_t)count) * 2;
        o->data = realloc(o->data, o->capacity);
    }
    for (int b = 0; b < count; b++) o->data[o->size++] = (uint8_t)(value >> (8 * b));
}

static void put_header(bytes_out *o, uint64_t key, terrain_chunk_coord c, uint32_t entries) {
    for (const char *m = "TEDITLOG"; *m; m++) put(o, (uint8_t)*m, 1);
    put(o, 1, 4);
    put(o, key, 8);
    put(o, (uint64_t)c.x, 8);
    put(o, (uint64_t)c.z, 8);
    put(o, entries, 4);
}

static void put_crc(bytes_out *o) { put(o, terrain__crc32(0, o->data, o->size), 4); }

/* One entry setting column (5, 0) to bedrock 100, sand 7, water 3 quanta and column (31, 31) to
 * nothing; the expected stacks built from the generated ones with the public builder. */
Test(terrain_edit_log, a_file_written_by_hand_replays_as_described) {
    terrain_chunk_coord coord = { 7, 7 };
    terrain_stacks *g = generated(coord);
    bytes_out o = { 0 };
    put_header(&o, key_of(SEED), coord, 1);
    put(&o, TERRAIN_EDIT_SET, 1);
    put(&o, 2, 2);
    put(&o, 5, 2), put(&o, 3, 2);
    put(&o, TERRAIN_BEDROCK, 1), put(&o, 100, 4);
    put(&o, TERRAIN_SAND, 1), put(&o, 7, 4);
    put(&o, TERRAIN_WATER, 1), put(&o, 3, 4);
    put(&o, 1023, 2), put(&o, 0, 2);
    put_crc(&o);

    terrain_stacks_builder *b = terrain_stacks_builder_create();
    for (int n = 0; n < N * N; n++) {
        terrain_layer layers[64];
        int count = terrain_stacks_column(g, n % N, n / N, layers, 64);
        if (n == 5) {
            terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 100 / 32.0f);
            terrain_stacks_builder_push(b, TERRAIN_SAND, 7 / 32.0f);
            terrain_stacks_builder_push(b, TERRAIN_WATER, 3 / 32.0f);
        } else if (n != 1023) {
            for (int l = 0; l < count; l++) terrain_stacks_builder_push(b, layers[l].material, layers[l].thickness);
        }
        terrain_stacks_builder_end_column(b);
    }
    terrain_stacks *expected = terrain_stacks_builder_finish(b);
    terrain_stacks_builder_destroy(b);

    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    core_error error = { 0 };
    cr_assert(terrain_edit_log_parse(log, o.data, o.size, &error), "%s", error.message);
    cr_expect_eq(terrain_edit_log_entries(log, coord), 1);
    expect_replay(log, coord, g, expected);
    /* Parsing the chunk again replaces its entries, never adds to them. */
    cr_assert(terrain_edit_log_parse(log, o.data, o.size, &error), "%s", error.message);
    cr_expect_eq(terrain_edit_log_entries(log, coord), 1);
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(expected);
    terrain_stacks_destroy(g);
    free(o.data);
}

/* A file with a valid checksum but content we never write: each is refused with its reason. */
typedef struct bad_case {
    const char *why;                  /* what is wrong, for a failing case's message */
    core_error_code code;             /* CORE_ERROR_FORMAT: content we never write; _RANGE: a value past
                                         its limit; _CORRUPT: sizes that disagree with the bytes */
    int tool, columns;                /* entry header */
    int index[2], layer_count[2];     /* up to two columns */
    int material[3];                  /* layers of the first column */
    uint32_t quanta[3];
    int entries;                      /* in the file header: 0 = 1, −1 = 0 */
    int trailing;                     /* bytes after the entry */
} bad_case;

static bytes_out bad_file(const bad_case *c) {
    bytes_out o = { 0 };
    put_header(&o, key_of(SEED), (terrain_chunk_coord){ 0, 0 }, c->entries == 0 ? 1u : c->entries < 0 ? 0u : (uint32_t)c->entries);
    put(&o, (uint64_t)c->tool, 1);
    put(&o, (uint64_t)c->columns, 2);
    for (int p = 0; p < c->columns && p < 2; p++) {
        put(&o, (uint64_t)c->index[p], 2);
        put(&o, (uint64_t)c->layer_count[p], 2);
        for (int l = 0; l < c->layer_count[p] && l < 3; l++) put(&o, (uint64_t)c->material[l], 1), put(&o, c->quanta[l], 4);
    }
    for (int t = 0; t < c->trailing; t++) put(&o, 0xab, 1);
    put_crc(&o);
    return o;
}

Test(terrain_edit_log, content_we_never_write_is_refused) {
    const bad_case cases[] = {
        { "unknown tool", CORE_ERROR_FORMAT, 0, 1, { 0 }, { 0 }, { 0 }, { 0 }, 0, 0 },
        { "unknown tool", CORE_ERROR_FORMAT, 9, 1, { 0 }, { 0 }, { 0 }, { 0 }, 0, 0 },
        { "0 columns", CORE_ERROR_RANGE, 1, 0, { 0 }, { 0 }, { 0 }, { 0 }, 0, 4 },
        { "1025 columns", CORE_ERROR_RANGE, 1, 1025, { 0 }, { 0 }, { 0 }, { 0 }, 0, 0 },
        { "column index 1024", CORE_ERROR_RANGE, 1, 1, { 1024 }, { 0 }, { 0 }, { 0 }, 0, 0 },
        { "twice", CORE_ERROR_FORMAT, 1, 2, { 9, 9 }, { 0, 0 }, { 0 }, { 0 }, 0, 0 },
        { "out of order", CORE_ERROR_FORMAT, 1, 2, { 9, 8 }, { 0, 0 }, { 0 }, { 0 }, 0, 0 },
        { "material 16", CORE_ERROR_RANGE, 1, 1, { 3 }, { 1 }, { 16 }, { 5 }, 0, 0 },
        { "0 quanta", CORE_ERROR_FORMAT, 1, 1, { 3 }, { 2 }, { 1, 2 }, { 5, 0 }, 0, 0 },
        { "both sand", CORE_ERROR_FORMAT, 1, 1, { 3 }, { 3 }, { 1, 2, 2 }, { 5, 1, 1 }, 0, 0 },
        { "ends with air", CORE_ERROR_FORMAT, 1, 1, { 3 }, { 2 }, { 1, 0 }, { 5, 1 }, 0, 0 },
        { "tall", CORE_ERROR_RANGE, 1, 1, { 3 }, { 2 }, { 1, 2 }, { 1u << 25, 1u << 25 }, 0, 0 },
        { "1000 layers need", CORE_ERROR_CORRUPT, 1, 1, { 3 }, { 1000 }, { 1, 2 }, { 5, 1 }, 0, 0 },
        { "after the last entry", CORE_ERROR_CORRUPT, 1, 1, { 3 }, { 1 }, { 1 }, { 5 }, 0, 1 },
        { "cannot fit", CORE_ERROR_CORRUPT, 1, 1, { 3 }, { 1 }, { 1 }, { 5 }, 1000, 0 },
        { "entry 1: unknown tool 171", CORE_ERROR_FORMAT, 1, 1, { 3 }, { 1 }, { 1 }, { 5 }, 2, 7 },
        { "no entries", CORE_ERROR_FORMAT, 1, 1, { 3 }, { 1 }, { 1 }, { 5 }, -1, 0 },
    };
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    for (size_t n = 0; n < CORE_COUNTOF(cases); n++) {
        bad_case c = cases[n];
        bytes_out o = bad_file(&c);
        core_error error = { 0 };
        cr_expect_not(terrain_edit_log_parse(log, o.data, o.size, &error), "case %zu (%s)", n, c.why);
        cr_expect_eq(error.code, c.code, "case %zu (%s): code %s, expected %s (%s)", n, c.why,
                     core_error_code_name(error.code), core_error_code_name(c.code), error.message);
        free(o.data);
    }
    /* The same shape with good values is accepted (the cases differ from it in one thing). */
    bad_case good = { "", CORE_ERROR_NONE, 1, 2, { 3, 4 }, { 2, 0 }, { 1, 2 }, { 5, 1 }, 0, 0 };
    bytes_out o = bad_file(&good);
    core_error error = { 0 };
    cr_expect(terrain_edit_log_parse(log, o.data, o.size, &error), "%s", error.message);
    free(o.data);
    cr_expect_eq(terrain_edit_log_chunks(log), 1, "only the good file got in");
    terrain_edit_log_destroy(log);
}

/* 31 columns of row 0 with 2 200 one-quantum layers each: 68 200 words before the row's last
 * column, past the stacks' 16-bit offsets. Valid as a file; replay skips the entry, no crash. */
Test(terrain_edit_log, an_entry_too_big_for_stacks_is_skipped_on_replay) {
    terrain_chunk_coord coord = { 0, 0 };
    terrain_stacks *g = generated(coord);
    bytes_out o = { 0 };
    put_header(&o, key_of(SEED), coord, 1);
    put(&o, TERRAIN_EDIT_SET, 1);
    put(&o, 31, 2);
    for (int i = 0; i < 31; i++) {
        put(&o, (uint64_t)i, 2), put(&o, 2200, 2);
        for (int l = 0; l < 2200; l++) put(&o, l % 2 ? TERRAIN_SAND : TERRAIN_BEDROCK, 1), put(&o, 1, 4);
    }
    put_crc(&o);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    core_error error = { 0 };
    cr_assert(terrain_edit_log_parse(log, o.data, o.size, &error), "%s", error.message);
    expect_replay(log, coord, g, g);
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(g);
    free(o.data);
}

/* ---- corruption --------------------------------------------------------------------------- */

/* The bytes of chunk 1 of the fixture, saved (three entries). */
static uint8_t *fixture_file(world_fixture *w, size_t *size) {
    char path[512];
    core_error error = { 0 };
    cr_assert(terrain_edit_log_save(w->log, w->dir, &error), "%s", error.message);
    chunk_path(path, sizeof path, w->dir, w->coord[1]);
    return read_all(path, size);
}

Test(terrain_edit_log, every_flipped_bit_and_every_truncation_is_refused) {
    world_fixture w;
    fixture_make(&w);
    size_t size;
    uint8_t *bytes = fixture_file(&w, &size);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    core_error error = { 0 };
    cr_assert(terrain_edit_log_parse(log, bytes, size, &error), "%s", error.message);
    terrain_edit_log_destroy(log);
    log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
    for (size_t at = 0; at < size; at++)
        for (int bit = 0; bit < 8; bit++) {
            bytes[at] ^= (uint8_t)(1u << bit);
            error = (core_error){ 0 };
            cr_expect_not(terrain_edit_log_parse(log, bytes, size, &error), "byte %zu bit %d", at, bit);
            /* Bytes 0-7 are the magic, 8-11 the version, the rest under the checksum. */
            core_error_code code = at < 8 ? CORE_ERROR_FORMAT : at < 12 ? CORE_ERROR_VERSION : CORE_ERROR_CORRUPT;
            cr_expect_eq(error.code, code, "byte %zu bit %d: code %s (%s)", at, bit, core_error_code_name(error.code),
                         error.message);
            cr_expect_neq(error.message[0], '\0');
            bytes[at] ^= (uint8_t)(1u << bit);
        }
    for (size_t length = 0; length < size; length++) {
        cr_expect_not(terrain_edit_log_parse(log, bytes, length, &error), "%zu of %zu bytes", length, size);
        cr_expect_eq(error.code, CORE_ERROR_CORRUPT, "%zu of %zu bytes: %s", length, size, error.message);
    }
    cr_expect_not(terrain_edit_log_parse(log, NULL, 0, &error));
    cr_expect_eq(error.code, CORE_ERROR_CORRUPT, "no bytes are a truncated file: %s", error.message);
    cr_expect_eq(terrain_edit_log_chunks(log), 0, "nothing got in");
    terrain_edit_log_destroy(log);
    free(bytes);
    fixture_free(&w);
}

/* Writes `bytes` as chunk 1's file, loads the folder into a new log with `key`: the file must be
 * reported with its path and error `code`, renamed .bad, its chunk left without entries, the
 * others loaded. */
static void expect_rejected(world_fixture *w, const uint8_t *bytes, size_t size, const char *name, uint64_t key,
                            core_error_code code) {
    char path[512], bad[600];
    snprintf(path, sizeof path, "%s/edits/%s", w->dir, name);
    snprintf(bad, sizeof bad, "%s.bad", path);
    unlink(bad);
    write_all(path, bytes, size);
    terrain_edit_log_load_result result;
    terrain_edit_log *log = load_new(w->dir, key, &result);
    cr_expect_eq(result.files_rejected, key == key_of(SEED) ? 1 : 3, "%s", name);
    cr_expect(strstr(result.first_problem.message, w->dir) == result.first_problem.message, "names the path: %s",
              result.first_problem.message);
    if (key == key_of(SEED)) {
        cr_expect_not_null(strstr(result.first_problem.message, path), "%s", result.first_problem.message);
        cr_expect_eq(result.chunks_loaded, 2);
        cr_expect(exists(bad), "%s", bad);
        cr_expect_not(exists(path), "%s renamed", path);
    }
    cr_expect_eq(result.first_problem.code, code, "%s: code %s, expected %s (%s)", name,
                 core_error_code_name(result.first_problem.code), core_error_code_name(code),
                 result.first_problem.message);
    cr_expect_eq(terrain_edit_log_entries(log, w->coord[1]), 0, "chunk 1 stays as generated");
    terrain_stacks *replayed = terrain_edit_log_replay(log, w->coord[1], w->base[1]);
    cr_expect_null(replayed);
    terrain_stacks_destroy(replayed);
    terrain_edit_log_destroy(log);
}

Test(terrain_edit_log, damaged_files_are_reported_renamed_and_skipped) {
    world_fixture w;
    fixture_make(&w);
    size_t size;
    uint8_t *bytes = fixture_file(&w, &size);
    const char *name = "-1_7.tel";
    /* Flipped bytes: a sample across the file (every byte is covered by the parse test). */
    for (size_t at = 0; at < size; at += size / 13 + 1) {
        bytes[at] ^= 0x5a;
        expect_rejected(&w, bytes, size, name, key_of(SEED),
                        at < 8 ? CORE_ERROR_FORMAT : at < 12 ? CORE_ERROR_VERSION : CORE_ERROR_CORRUPT);
        bytes[at] ^= 0x5a;
    }
    /* Many random bytes. */
    for (int trial = 0; trial < 12; trial++) {
        uint8_t *copy = malloc(size);
        memcpy(copy, bytes, size);
        for (int n = 0; n < 1 + trial; n++) {
            uint64_t h = core_hash_u64((uint64_t)(trial * 100 + n));
            copy[12 + h % (size - 12)] ^= (uint8_t)(1 + (h >> 32) % 255);
        }
        expect_rejected(&w, copy, size, name, key_of(SEED), CORE_ERROR_CORRUPT);
        free(copy);
    }
    /* Truncations. */
    const size_t lengths[] = { 0, 1, 8, 43, 44, 45, 100, size / 2, size - 5, size - 4, size - 1 };
    for (size_t n = 0; n < CORE_COUNTOF(lengths); n++)
        expect_rejected(&w, bytes, lengths[n], name, key_of(SEED), CORE_ERROR_CORRUPT);   /* too short, or its checksum */
    /* Garbage appended. */
    uint8_t *longer = malloc(size + 100);
    memcpy(longer, bytes, size);
    memset(longer + size, 0x33, 100);
    expect_rejected(&w, longer, size + 1, name, key_of(SEED), CORE_ERROR_CORRUPT);
    expect_rejected(&w, longer, size + 100, name, key_of(SEED), CORE_ERROR_CORRUPT);
    free(longer);
    /* Another chunk's name. */
    expect_rejected(&w, bytes, size, "-1_8.tel", key_of(SEED), CORE_ERROR_MISMATCH);   /* holds chunk (-1, 7) */
    /* Back intact: loads again. */
    char path[512];
    chunk_path(path, sizeof path, w.dir, w.coord[1]);
    write_all(path, bytes, size);
    terrain_edit_log_load_result result;
    terrain_edit_log *log = load_new(w.dir, key_of(SEED), &result);
    cr_expect_eq(result.files_rejected, 0, "%s", result.first_problem.message);
    expect_replay(log, w.coord[1], w.base[1], w.final[1]);
    terrain_edit_log_destroy(log);
    /* Another world: every file refused. */
    expect_rejected(&w, bytes, size, name, key_of(SEED + 1), CORE_ERROR_MISMATCH);   /* saved by another world */
    free(bytes);
    fixture_free(&w);
}

/* ---- a saver killed at random moments ------------------------------------------------------ */

/* The child saves forever, alternating the chunk between states A and B, until killed (or, as a
 * safeguard, after ten seconds). */
static _Noreturn void save_forever(terrain_edit_log *log, terrain_chunk_coord coord, terrain_stacks *a,
                                   terrain_stacks *b, const char *dir) {
    core_error error = { 0 };
    uint64_t end = core_time_ns() + 10000000000ull;
    for (int n = 0; core_time_ns() < end; n++) {
        terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, n % 2 ? b : a, n % 2 ? a : b);
        terrain_edit_log_compact(log);
        if (!terrain_edit_log_save(log, dir, &error)) _exit(3);
    }
    _exit(0);
}

Test(terrain_edit_log, a_saver_killed_at_any_moment_leaves_state_a_or_b, .timeout = 120) {
    terrain_chunk_coord coord = { 3, -4 };
    terrain_stacks *g = generated(coord), *a = edited(g, coord, 31, 40), *b = edited(a, coord, 32, 40);
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    int seen_a = 0, seen_b = 0;
    for (int round = 0; round < 20; round++) {
        terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key_of(SEED) });
        cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, g, a));
        core_error error = { 0 };
        cr_assert(terrain_edit_log_save(log, dir, &error), "%s", error.message);
        fflush(NULL);
        pid_t child = fork();
        cr_assert_geq(child, 0);
        if (child == 0) save_forever(log, coord, a, b, dir);
        uint64_t h = core_hash_u64((uint64_t)round);
        struct timespec pause = { 0, (long)(500000 + h % 8000000) };   /* 0.5 … 8.5 ms */
        nanosleep(&pause, NULL);
        kill(child, SIGKILL);
        int status;
        cr_assert_eq(waitpid(child, &status, 0), child);
        cr_expect(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL, "round %d: the child was still saving", round);
        terrain_edit_log_destroy(log);

        terrain_edit_log_load_result result;
        terrain_edit_log *loaded = load_new(dir, key_of(SEED), &result);
        cr_expect_eq(result.files_rejected, 0, "round %d: %s", round, result.first_problem.message);
        cr_expect_eq(result.chunks_loaded, 1, "round %d", round);
        cr_expect_eq(count_names(dir, ".tmp."), 0, "round %d: temporaries removed", round);
        terrain_stacks *got = terrain_edit_log_replay(loaded, coord, g);
        cr_assert_not_null(got, "round %d", round);
        bool is_a = same_bytes(got, a), is_b = same_bytes(got, b);
        cr_expect(is_a || is_b, "round %d: state A or B", round);
        seen_a += is_a, seen_b += is_b;
        terrain_stacks_destroy(got);
        terrain_edit_log_destroy(loaded);
    }
    cr_log_info("killed savers left A %d times, B %d times", seen_a, seen_b);
    remove_tree(dir);
    terrain_stacks_destroy(b);
    terrain_stacks_destroy(a);
    terrain_stacks_destroy(g);
}
