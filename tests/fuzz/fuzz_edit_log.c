/* fuzz_edit_log — libFuzzer target for the edit log's file reader (terrain_edit_log_parse,
 * modules/terrain/data/terrain_edit_log.c) and the replay of what it accepted.
 *
 *   tests/fuzz/run.sh 60 fuzz_edit_log
 * Seeds: tests/fuzz/corpus/fuzz_edit_log/, files saved by terrain_edit_log_save for the world of
 * terrain_generation_defaults(1): one entry at chunk (0, 0); three entries (sculpt, deposit,
 * carve) at (−3, 12) with layers over 4 095 and over 65 535 quanta and caves; one compacted
 * entry at (5, −1).
 *
 * A mutated file almost never keeps its CRC, so each input is parsed twice: as it is (which
 * must fail unless unchanged) and with the checksum recomputed over the mutated bytes, which
 * lets the fuzzer reach every check behind it. Traps when a result breaks the contract: a
 * failure leaves the log empty and says why in a terminated message; a success puts exactly
 * that chunk in the log, and replaying it over a generated chunk (generated once, cached) gives
 * stacks whose every column stays under the columns' height limit, twice the same.
 */
#include "core/core.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

static const terrain_stacks *generated_chunk(uint64_t *key) {
    static terrain_stacks *stacks;
    static uint64_t world_key;
    if (!stacks) {
        core_log_set_level(CORE_LOG_OFF);         /* skipped entries log; the traps speak */
        terrain_generation_desc params = terrain_generation_defaults(1);
        stacks = terrain_generate_chunk(&params, (terrain_chunk_coord){ 0, 0 });
        world_key = terrain_generation_key(&params);
    }
    *key = world_key;
    return stacks;
}

static uint64_t get_u64(const unsigned char *at) {
    uint64_t v = 0;
    for (int b = 7; b >= 0; b--) v = v << 8 | at[b];
    return v;
}

static void check_replay(terrain_edit_log *log, terrain_chunk_coord coord, const terrain_stacks *generated) {
    terrain_stacks *once = terrain_edit_log_replay(log, coord, generated);
    terrain_stacks *twice = terrain_edit_log_replay(log, coord, generated);
    if (!once || !twice) __builtin_trap();
    if (terrain_stacks_bytes(once) != terrain_stacks_bytes(twice) ||
        memcmp(once, twice, terrain_stacks_bytes(once)) != 0)
        __builtin_trap();
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            terrain__column_cursor cursor = terrain__stacks_cursor(once, i, k);
            terrain__qlayer layer;
            uint64_t height = 0;
            while (terrain__cursor_next(&cursor, &layer)) {
                if (layer.material >= TERRAIN_MATERIAL_MAX || layer.quanta == 0) __builtin_trap();
                height += layer.quanta;
            }
            if (height >= TERRAIN__COLUMN_MAX_QUANTA) __builtin_trap();
        }
    terrain_stacks_destroy(once);
    terrain_stacks_destroy(twice);
}

/* Parses into a fresh log and checks the outcome; returns whether it was accepted. */
static bool parse_and_check(const unsigned char *bytes, size_t size, uint64_t key, const terrain_stacks *generated) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key });
    core_error error = { 0 };
    bool ok = terrain_edit_log_parse(log, bytes, size, &error);
    if (ok) {
        terrain_chunk_coord coord = { (int64_t)get_u64(bytes + 20), (int64_t)get_u64(bytes + 28) };
        if (terrain_edit_log_chunks(log) != 1 || terrain_edit_log_entries(log, coord) < 1) __builtin_trap();
        check_replay(log, coord, generated);
        terrain_edit_log_compact(log);
        if (terrain_edit_log_entries(log, coord) != 1) __builtin_trap();
        check_replay(log, coord, generated);
    } else {
        if (error.code == CORE_ERROR_NONE || error.code == CORE_ERROR_IO || error.code == CORE_ERROR_ARGUMENT)
            __builtin_trap();   /* bytes in memory: only a verdict on their content */
        if (error.message[0] == '\0' || memchr(error.message, '\0', sizeof error.message) == NULL) __builtin_trap();
        if (terrain_edit_log_chunks(log) != 0) __builtin_trap();
    }
    terrain_edit_log_destroy(log);
    return ok;
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    uint64_t key;
    const terrain_stacks *generated = generated_chunk(&key);
    bool as_is = parse_and_check(bytes, size, key, generated);
    if (size < 4) return 0;
    unsigned char *fixed = malloc(size);
    memcpy(fixed, bytes, size);
    uint32_t crc = terrain__crc32(0, fixed, size - 4);
    for (int b = 0; b < 4; b++) fixed[size - 4 + b] = (unsigned char)(crc >> (8 * b));
    bool unchanged = memcmp(fixed, bytes, size) == 0;
    bool with_crc = parse_and_check(fixed, size, key, generated);
    if (unchanged && as_is != with_crc) __builtin_trap();
    if (!unchanged && as_is) __builtin_trap();       /* a wrong checksum got through */
    free(fixed);
    return 0;
}
