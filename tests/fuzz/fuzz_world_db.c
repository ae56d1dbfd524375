/* fuzz_world_db — libFuzzer target for opening a world folder's database (terrain_store_create,
 * modules/terrain/data/terrain_store.c): each input is written as DIR/world.db and opened.
 *
 *   tests/fuzz/run.sh 60 fuzz_world_db
 * Seeds: tests/fuzz/corpus/fuzz_world_db/, databases saved by terrain_store_save for the world
 * of terrain_generation_defaults(1): one chunk with one entry and a value; two chunks, one of
 * three entries.
 *
 * SQLite parses the file and our code decides what it is, so the contract checked is ours:
 * opening never crashes, and ends in exactly one of
 *   - a store, the file kept (every chunk it holds in the log, each replaying over a generated
 *     chunk twice the same);
 *   - a store over a new world, the file set aside as world.db.bad with a notice naming it and
 *     nothing in the log;
 *   - NULL with a reason naming world.db (another world, a newer format), the file untouched.
 * Any other outcome traps.
 */
#include "core/core.h"
#include "terrain/terrain.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

static char dir[64];
static terrain_generation_desc params;
static terrain_stacks *generated[2];

static void setup(void) {
    if (dir[0]) return;
    core_log_set_level(CORE_LOG_OFF);             /* set-aside notices log; the traps speak */
    snprintf(dir, sizeof dir, "/tmp/fuzz_world_db_%ld", (long)getpid());
    if (!core_make_dirs(dir)) __builtin_trap();
    params = terrain_generation_defaults(1);
    for (int n = 0; n < 2; n++) generated[n] = terrain_generate_chunk(&params, (terrain_chunk_coord){ n, 0 });
}

static void remove_files(void) {
    const char *names[] = { "world.db", "world.db-wal", "world.db-journal", "world.db.bad", "world.db.bad-wal",
                            "world.db.bad-journal" };
    for (size_t n = 0; n < sizeof names / sizeof names[0]; n++) {
        char path[128];
        snprintf(path, sizeof path, "%s/%s", dir, names[n]);
        unlink(path);
    }
}

static bool file_exists(const char *name) {
    char path[128];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return access(path, F_OK) == 0;
}

/* The seeds' chunks are (0, 0) and (1, 0); a mutated blob naming another coordinate fails its
 * own check (the row's key must match), so only those two can be in the log. */
static void check_replays(terrain_edit_log *log) {
    for (int n = 0; n < 2; n++) {
        terrain_chunk_coord coord = { n, 0 };
        terrain_stacks *once = terrain_edit_log_replay(log, coord, generated[n]);
        terrain_stacks *twice = terrain_edit_log_replay(log, coord, generated[n]);
        if (!once != !twice) __builtin_trap();
        if (once && terrain_stacks_hash(once) != terrain_stacks_hash(twice)) __builtin_trap();
        terrain_stacks_destroy(once);
        terrain_stacks_destroy(twice);
    }
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    setup();
    remove_files();
    char path[128];
    snprintf(path, sizeof path, "%s/world.db", dir);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(bytes, 1, size, f) != size || fclose(f) != 0) __builtin_trap();
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
    terrain_store_report report;
    core_error error = { 0 };
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = 1 }, &report,
                                                &error);
    if (store) {
        if (report.set_aside) {
            if (!strstr(report.notice, "world.db.bad") || !file_exists("world.db.bad")) __builtin_trap();
            if (terrain_edit_log_chunks(log) != 0 || report.chunks_loaded != 0) __builtin_trap();
        } else if (terrain_edit_log_chunks(log) != report.chunks_loaded) __builtin_trap();
        check_replays(log);
        terrain_store_destroy(store);
    } else {
        if (error.code == CORE_ERROR_NONE || !strstr(error.message, "world.db") || report.in_use) __builtin_trap();
        if (file_exists("world.db.bad") || terrain_edit_log_chunks(log) != 0) __builtin_trap();
    }
    terrain_edit_log_destroy(log);
    remove_files();
    return 0;
}
