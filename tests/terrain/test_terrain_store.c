/* The world folder's database (terrain.h, "the world folder"): round trips, named values, saves
 * in the background, a saver killed at random moments (200 rounds, zero torn states), the import
 * of the old per-file layout, damaged and foreign databases set aside, another world refused, a
 * second process refused. Expected states are the ones the test made by hand or through the
 * tools (a deposit adds exactly its volume), compared by bytes and by the sand they hold. */
#include "../engine/test.h"
#include "test_files.h"
#include "terrain/terrain.h"
#include "terrain_quanta_test.h"

#include "core/core.h"

#include <math.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <time.h>

#define N TERRAIN_CHUNK_COLUMNS
#define QPM 32                              /* quanta per metre */
#define SEED 5

/* ---- a flat world and two states of four chunks ------------------------------------------ */

/* Bedrock from the floor up to y = 0 everywhere: what the chunks are before any edit. */
static void flat_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
}

static terrain_stacks *flat_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, flat_column, user);
}

static uint64_t world_key(uint64_t seed) {
    terrain_generation_desc params = terrain_generation_defaults(seed);
    return terrain_generation_key(&params);
}

static bool same_bytes(const terrain_stacks *a, const terrain_stacks *b) {
    return a && b && terrain_stacks_bytes(a) == terrain_stacks_bytes(b) &&
           memcmp(a, b, terrain_stacks_bytes(a)) == 0;
}

/* The four chunks around the origin's corner, as generated (G), after one deposit of 40 m³ on
 * the corner (A) and after a second of 60 m³ (B): the two states of one edit that spans
 * chunks. A deposit adds exactly its volume, so A holds 40·32 quanta·columns of sand and B
 * 100·32, whatever the pile's shape. The world keeps the stacks valid (never trimmed). */
typedef struct corner_states {
    terrain_world *world;
    terrain_chunk_coord coord[4];
    terrain_stacks *generated[4];
    const terrain_stacks *a[4], *b[4];
} corner_states;

#define SAND_A (40 * QPM)
#define SAND_B (100 * QPM)

static void corner_states_make(corner_states *s) {
    s->world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(SEED),
                                                           .generate = flat_chunk });
    for (int n = 0; n < 4; n++) {
        s->coord[n] = (terrain_chunk_coord){ n % 2 - 1, n / 2 - 1 };
        s->generated[n] = flat_chunk(NULL, s->coord[n]);
    }
    const float volumes[2] = { 40, 60 };
    for (int step = 0; step < 2; step++) {
        terrain_chunk_coord changed[8];
        int count = terrain_world_edit(s->world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
            .deposit = { .x = 0, .z = 0, .radius = 5, .volume = volumes[step] } }, changed, 8);
        cr_assert_eq(count, 4);
        for (int n = 0; n < 4; n++) {
            const terrain_stacks *now = terrain_world_stacks(s->world, s->coord[n]);
            if (step == 0) s->a[n] = now;
            else s->b[n] = now;
        }
    }
}

static void corner_states_free(corner_states *s) {
    for (int n = 0; n < 4; n++) terrain_stacks_destroy(s->generated[n]);
    terrain_world_destroy(s->world);
}

/* Records `from` → `to` for the four chunks. */
static void record_states(terrain_edit_log *log, const corner_states *s, const terrain_stacks *const *from,
                          const terrain_stacks *const *to) {
    for (int n = 0; n < 4; n++) cr_assert(terrain_edit_log_record(log, s->coord[n], TERRAIN_EDIT_DEPOSIT, from[n], to[n]));
}

/* Which state the log replays the four chunks to: 'A', 'B', 'G' (no entries), or '?' for a
 * mix; *sand the sand over the four. */
static char replayed_state(terrain_edit_log *log, const corner_states *s, int64_t *sand) {
    int as = 0, bs = 0, gs = 0;
    *sand = 0;
    for (int n = 0; n < 4; n++) {
        terrain_stacks *got = terrain_edit_log_replay(log, s->coord[n], s->generated[n]);
        const terrain_stacks *now = got ? got : s->generated[n];
        *sand += chunk_quanta(now, TERRAIN_SAND);
        as += same_bytes(now, s->a[n]), bs += same_bytes(now, s->b[n]), gs += got == NULL;
        terrain_stacks_destroy(got);
    }
    return as == 4 ? 'A' : bs == 4 ? 'B' : gs == 4 ? 'G' : '?';
}

static terrain_store *open_store(const char *dir, terrain_edit_log *log, terrain_store_report *report) {
    core_error error = { 0 };
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = SEED }, report,
                                                &error);
    cr_assert_not_null(store, "%s", error.message);
    return store;
}

static void db_path(char *out, size_t size, const char *dir) { snprintf(out, size, "%s/world.db", dir); }

/* A folder whose world.db holds state A of the corner. */
static void save_state_a(const char *dir, const corner_states *s) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(dir, log, &report);
    record_states(log, s, (const terrain_stacks *const *)s->generated, s->a);
    core_error error = { 0 };
    cr_assert(terrain_store_save(store, &error), "%s", error.message);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);
}

/* ---- round trips ---------------------------------------------------------------------------- */

Test(terrain_store, a_new_world_saves_and_comes_back_byte_for_byte) {
    corner_states s;
    corner_states_make(&s);
    char dir[128], nested[160];
    make_temp_dir(dir, sizeof dir);
    snprintf(nested, sizeof nested, "%s/saves/one", dir);     /* parents made as needed */
    uint64_t seed = 0;
    cr_expect_eq(terrain_store_read_seed(nested, &seed, NULL), 0, "no database yet");
    save_state_a(nested, &s);
    cr_expect_eq(terrain_store_read_seed(nested, &seed, NULL), 1);
    cr_expect_eq(seed, SEED);

    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(nested, log, &report);
    cr_expect_eq(report.chunks_loaded, 4);
    cr_expect_eq(report.chunks_imported, 0);
    cr_expect(!report.set_aside && !report.notice[0], "%s", report.notice);
    int64_t sand;
    cr_expect_eq(replayed_state(log, &s, &sand), 'A');
    cr_expect_eq(sand, SAND_A);
    /* Loaded chunks are clean: a save with nothing new writes nothing (and succeeds). */
    core_error error = { 0 };
    cr_expect(terrain_store_save(store, &error), "%s", error.message);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
    corner_states_free(&s);
}

Test(terrain_store, named_values_are_saved_with_the_edits) {
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(dir, log, &report);
    const double pose[5] = { 12.5, 40.25, -3.0, 1.5, -0.25 };
    cr_assert(terrain_store_put(store, "game.player", pose, sizeof pose));
    cr_assert(terrain_store_put(store, "empty", "", 0));
    cr_expect(!terrain_store_put(store, "", pose, 8), "an empty name");
    char long_name[80];
    memset(long_name, 'n', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    cr_expect(!terrain_store_put(store, long_name, pose, 8), "a 79-byte name");
    cr_expect(!terrain_store_put(store, "big", pose, ((size_t)1 << 20) + 1), "over 1 MiB");
    cr_expect(!terrain_store_put(store, "null", NULL, 4));
    core_error error = { 0 };
    cr_assert(terrain_store_save(store, &error), "%s", error.message);
    terrain_store_destroy(store);

    terrain_edit_log *again = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    store = open_store(dir, again, &report);
    double got[5] = { 0 };
    cr_expect_eq(terrain_store_get(store, "game.player", got, sizeof got), (int64_t)sizeof pose);
    cr_expect(memcmp(got, pose, sizeof pose) == 0);
    cr_expect_eq(terrain_store_get(store, "empty", NULL, 0), 0);
    cr_expect_eq(terrain_store_get(store, "missing", got, sizeof got), -1);
    /* A short buffer gets the start; the size says how much there is. */
    double first = 0;
    cr_expect_eq(terrain_store_get(store, "game.player", &first, sizeof first), (int64_t)sizeof pose);
    cr_expect_eq(first, 12.5);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(again);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
}

Test(terrain_store, saves_in_the_background_keep_what_changed_meanwhile) {
    corner_states s;
    corner_states_make(&s);
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(dir, log, &report);
    record_states(log, &s, (const terrain_stacks *const *)s.generated, s.a);
    cr_assert(terrain_store_save_async(store));
    /* Changes after the snapshot are not in that save; they stay dirty for the next one. */
    record_states(log, &s, s.a, s.b);
    const int32_t marker = 7;
    cr_assert(terrain_store_put(store, "marker", &marker, sizeof marker));
    core_error error = { 0 };
    cr_expect(terrain_store_wait(store, &error), "%s", error.message);
    cr_assert(terrain_store_save_async(store));
    cr_expect(terrain_store_wait(store, &error), "%s", error.message);
    cr_expect(terrain_store_save_async(store), "nothing changed: true, nothing written");
    terrain_store_destroy(store);

    terrain_edit_log *again = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    store = open_store(dir, again, &report);
    int64_t sand;
    cr_expect_eq(replayed_state(again, &s, &sand), 'B');
    cr_expect_eq(sand, SAND_B);
    int32_t got = 0;
    cr_expect_eq(terrain_store_get(store, "marker", &got, sizeof got), 4);
    cr_expect_eq(got, 7);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(again);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
    corner_states_free(&s);
}

/* ---- a saver killed at random moments ------------------------------------------------------ */

/* The child opens the world (its own connection: none crosses the fork) and saves forever,
 * switching the four chunks between A and B in each save, writing a byte to `progress` after
 * each, until killed. */
static _Noreturn void save_forever(const char *dir, const corner_states *s, int progress) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = SEED }, NULL,
                                                NULL);
    if (!store) _exit(3);
    int64_t sand;
    bool at_a = replayed_state(log, s, &sand) == 'A';
    uint64_t end = core_time_ns() + 10000000000ull;    /* a safeguard: ten seconds */
    while (core_time_ns() < end) {
        for (int n = 0; n < 4; n++)
            terrain_edit_log_record(log, s->coord[n], TERRAIN_EDIT_DEPOSIT, at_a ? s->a[n] : s->b[n],
                                    at_a ? s->b[n] : s->a[n]);
        terrain_edit_log_compact(log);
        if (!terrain_store_save(store, NULL)) _exit(4);
        at_a = !at_a;
        if (write(progress, "s", 1) != 1) _exit(5);
    }
    _exit(0);
}

/* Nanoseconds one save of the four chunks takes here (a child is killed at a random moment
 * within about one save after the saves it was let finish). */
static uint64_t time_one_save(const char *dir, const corner_states *s) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = SEED }, NULL,
                                                NULL);
    cr_assert_not_null(store);
    uint64_t total = 0;
    for (int n = 0; n < 8; n++) {              /* even: the world is at A again */
        record_states(log, s, n % 2 ? s->b : s->a, n % 2 ? s->a : s->b);
        uint64_t start = core_time_ns();
        cr_assert(terrain_store_save(store, NULL));
        total += core_time_ns() - start;
    }
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);
    return total / 8;
}

/* Kills land in the child's open (none of its saves done), between saves and inside them: each
 * round lets 0 to 3 saves finish (the child reports each on a pipe), then kills after a random
 * pause of up to one and a half saves. */
Test(terrain_store, a_saver_killed_at_any_moment_leaves_the_world_before_or_after_never_torn, .timeout = 300) {
    corner_states s;
    corner_states_make(&s);
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    save_state_a(dir, &s);
    uint64_t save_ns = time_one_save(dir, &s);
    enum { ROUNDS = 200 };
    int seen_a = 0, seen_b = 0, torn = 0;
    for (int round = 0; round < ROUNDS; round++) {
        int progress[2];
        cr_assert_eq(pipe(progress), 0);
        fflush(NULL);
        pid_t child = fork();
        cr_assert_geq(child, 0);
        if (child == 0) {
            close(progress[0]);
            save_forever(dir, &s, progress[1]);
        }
        close(progress[1]);
        uint64_t h = core_hash_u64((uint64_t)round + 1000);
        char byte;
        for (uint64_t done = 0; done < h % 4; done++) cr_assert_eq(read(progress[0], &byte, 1), 1, "round %d", round);
        uint64_t pause_ns = (h >> 8) % (save_ns * 3 / 2 + 1);
        struct timespec pause = { (time_t)(pause_ns / 1000000000u), (long)(pause_ns % 1000000000u) };
        nanosleep(&pause, NULL);
        kill(child, SIGKILL);
        int status;
        cr_assert_eq(waitpid(child, &status, 0), child);
        close(progress[0]);
        cr_assert(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL, "round %d: the child ended by itself (%d)",
                  round, WIFEXITED(status) ? WEXITSTATUS(status) : -1);

        terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
        terrain_store_report report;
        terrain_store *store = open_store(dir, log, &report);
        cr_expect(!report.set_aside, "round %d: %s", round, report.notice);
        int64_t sand;
        char state = replayed_state(log, &s, &sand);
        bool ok = (state == 'A' && sand == SAND_A) || (state == 'B' && sand == SAND_B);
        cr_expect(ok, "round %d: state %c with %lld quanta of sand (A holds %d, B %d)", round, state, (long long)sand,
                  SAND_A, SAND_B);
        torn += !ok;
        seen_a += state == 'A', seen_b += state == 'B';
        terrain_store_destroy(store);
        terrain_edit_log_destroy(log);
    }
    cr_log_info("killed savers left A %d times, B %d times, torn %d times (a save takes %.2f ms)", seen_a, seen_b,
                torn, (double)save_ns * 1e-6);
    cr_expect_eq(torn, 0);
    /* Both states seen: kills landed after saves as well as before them. */
    cr_expect(seen_a > 0 && seen_b > 0, "A %d, B %d", seen_a, seen_b);
    remove_tree(dir);
    corner_states_free(&s);
}

/* ---- the old layout ------------------------------------------------------------------------- */

Test(terrain_store, an_old_folder_is_imported_once_with_the_same_bytes_as_loading_it) {
    corner_states s;
    corner_states_make(&s);
    char dir[128], path[256];
    make_temp_dir(dir, sizeof dir);
    /* The old layout: DIR/edits/<x>_<z>.tel, plus one damaged file and a crash's temporary. */
    terrain_edit_log *old = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    record_states(old, &s, (const terrain_stacks *const *)s.generated, s.a);
    record_states(old, &s, s.a, s.b);
    core_error error = { 0 };
    cr_assert(terrain_edit_log_save(old, dir, &error), "%s", error.message);
    snprintf(path, sizeof path, "%s/edits/9_9.tel", dir);
    write_all(path, "not an edit file", 16);
    snprintf(path, sizeof path, "%s/edits/.0_0.tel.tmp.123", dir);
    write_all(path, "half", 4);
    snprintf(path, sizeof path, "%s/notes.txt", dir);
    write_all(path, "mine", 4);
    /* What loading the folder gives today (from a copy: loading renames the damaged file). */
    char copy[128];
    make_temp_dir(copy, sizeof copy);
    terrain_edit_log *copied = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    record_states(copied, &s, (const terrain_stacks *const *)s.generated, s.a);
    record_states(copied, &s, s.a, s.b);
    cr_assert(terrain_edit_log_save(copied, copy, &error), "%s", error.message);
    terrain_edit_log *today = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_edit_log_load_result loaded;
    cr_assert(terrain_edit_log_load(today, copy, &loaded, NULL));
    cr_assert_eq(loaded.chunks_loaded, 4);
    terrain_edit_log_destroy(copied);
    remove_tree(copy);

    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(dir, log, &report);
    cr_expect_eq(report.chunks_imported, 4);
    cr_expect_eq(report.chunks_loaded, 4);
    cr_expect_eq(report.files_rejected, 1, "9_9.tel: %d rejected", report.files_rejected);
    cr_expect(strstr(report.notice, "imported 4 chunk(s)") && strstr(report.notice, "edits.imported"), "%s",
              report.notice);
    for (int n = 0; n < 4; n++) {
        terrain_stacks *a = terrain_edit_log_replay(log, s.coord[n], s.generated[n]);
        terrain_stacks *b = terrain_edit_log_replay(today, s.coord[n], s.generated[n]);
        cr_expect(same_bytes(a, b), "chunk %d: imported and loaded replay the same bytes", n);
        cr_expect(same_bytes(a, s.b[n]), "chunk %d: state B", n);
        terrain_stacks_destroy(a);
        terrain_stacks_destroy(b);
    }
    snprintf(path, sizeof path, "%s/edits", dir);
    cr_expect(!exists(path), "the old folder is renamed once the import committed");
    snprintf(path, sizeof path, "%s/edits.imported/-1_-1.tel", dir);
    cr_expect(exists(path), "the old files are kept");
    snprintf(path, sizeof path, "%s/edits.imported/9_9.tel.bad", dir);
    cr_expect(exists(path), "the damaged file is kept as .bad");
    snprintf(path, sizeof path, "%s/notes.txt", dir);
    cr_expect(exists(path));
    terrain_store_destroy(store);

    /* A stale old folder after the import (a crash between the commit and the rename, or an old
     * build run since) is not imported again: it would replace newer saves. It is renamed. */
    terrain_edit_log *stale = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    record_states(stale, &s, (const terrain_stacks *const *)s.generated, s.a);
    cr_assert(terrain_edit_log_save(stale, dir, &error), "%s", error.message);
    terrain_edit_log *again = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    store = open_store(dir, again, &report);
    cr_expect_eq(report.chunks_imported, 0);
    cr_expect_eq(report.chunks_loaded, 4);
    int64_t sand;
    cr_expect_eq(replayed_state(again, &s, &sand), 'B', "the database's state, not the stale folder's");
    snprintf(path, sizeof path, "%s/edits.imported.2", dir);
    cr_expect(exists(path));
    terrain_store_destroy(store);
    terrain_edit_log_destroy(again);
    terrain_edit_log_destroy(stale);
    terrain_edit_log_destroy(log);
    terrain_edit_log_destroy(today);
    terrain_edit_log_destroy(old);
    remove_tree(dir);
    corner_states_free(&s);
}

/* ---- damaged, foreign, another world's, in use ------------------------------------------- */

/* Opens a folder whose world.db was damaged: the store opens as a new world, says so naming
 * the file, keeps the damaged bytes as world.db.bad and touches nothing else. */
static void expect_set_aside(const char *dir, const uint8_t *bytes, size_t size, const char *reason_part) {
    char path[256], bad[300], notes[256];
    db_path(path, sizeof path, dir);
    snprintf(bad, sizeof bad, "%s.bad", path);
    snprintf(notes, sizeof notes, "%s/notes.txt", dir);
    write_all(notes, "mine", 4);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(dir, log, &report);
    cr_expect(report.set_aside);
    cr_expect(strstr(report.notice, path) && strstr(report.notice, "world.db.bad"), "%s", report.notice);
    cr_expect(strstr(report.notice, reason_part), "'%s' in: %s", reason_part, report.notice);
    cr_expect_eq(report.chunks_loaded, 0);
    cr_expect_eq(terrain_edit_log_chunks(log), 0, "the world opens as generated");
    size_t kept_size;
    uint8_t *kept = read_all(bad, &kept_size);
    cr_expect(kept_size == size && memcmp(kept, bytes, size) == 0, "the damaged file is kept as it was");
    free(kept);
    size_t notes_size;
    uint8_t *notes_bytes = read_all(notes, &notes_size);
    cr_expect(notes_size == 4 && memcmp(notes_bytes, "mine", 4) == 0, "other files untouched");
    free(notes_bytes);
    /* The new world works. */
    const int one = 1;
    cr_expect(terrain_store_put(store, "x", &one, sizeof one));
    core_error error = { 0 };
    cr_expect(terrain_store_save(store, &error), "%s", error.message);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);
}

/* A world.db holding state A, closed, its bytes read back. */
static uint8_t *saved_database(const char *dir, const corner_states *s, size_t *size) {
    save_state_a(dir, s);
    char path[256];
    db_path(path, sizeof path, dir);
    return read_all(path, size);
}

static void replace_database(const char *dir, const uint8_t *bytes, size_t size) {
    char path[256];
    db_path(path, sizeof path, dir);
    write_all(path, bytes, size);
}

Test(terrain_store, a_file_that_is_not_sqlite_is_set_aside) {
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    const char text[] = "seed 3\nthis is not a database, but it has a few lines of text in it.\n";
    replace_database(dir, (const uint8_t *)text, sizeof text - 1);
    expect_set_aside(dir, (const uint8_t *)text, sizeof text - 1, "not a database");
    remove_tree(dir);
}

Test(terrain_store, a_truncated_database_is_set_aside) {
    corner_states s;
    corner_states_make(&s);
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    size_t size;
    uint8_t *bytes = saved_database(dir, &s, &size);
    cr_assert_geq(size, 4 * 4096, "several pages");
    size_t cut = (size / 2 / 4096) * 4096 + 100;        /* mid-page, past the first pages */
    replace_database(dir, bytes, cut);
    expect_set_aside(dir, bytes, cut, "world.db");
    free(bytes);
    remove_tree(dir);
    corner_states_free(&s);
}

Test(terrain_store, flipped_pages_are_set_aside) {
    corner_states s;
    corner_states_make(&s);
    size_t size;
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    uint8_t *bytes = saved_database(dir, &s, &size);
    size_t pages = size / 4096;
    int set_aside_count = 0;
    /* Each page after the first in turn, its first 64 bytes (a b-tree page's header and cell
     * pointers, or an overflow page's link and the start of a blob) overwritten. */
    for (size_t page = 1; page < pages; page++) {
        uint8_t *damaged = malloc(size);
        memcpy(damaged, bytes, size);
        for (int b = 0; b < 64; b++) damaged[page * 4096 + (size_t)b] ^= 0xa5;
        remove_tree(dir);
        cr_assert_eq(mkdir(dir, 0700), 0);
        replace_database(dir, damaged, size);
        expect_set_aside(dir, damaged, size, "world.db");
        set_aside_count++;
        free(damaged);
    }
    cr_expect_eq(set_aside_count, (int)pages - 1);
    free(bytes);
    remove_tree(dir);
    corner_states_free(&s);
}

Test(terrain_store, a_flipped_byte_inside_a_chunk_is_caught_by_its_checksum) {
    corner_states s;
    corner_states_make(&s);
    char dir[128], path[256];
    make_temp_dir(dir, sizeof dir);
    size_t size;
    uint8_t *bytes = saved_database(dir, &s, &size);
    free(bytes);
    /* Through SQLite itself, so every page stays well-formed: only the CRC can tell. */
    db_path(path, sizeof path, dir);
    sqlite3 *db;
    cr_assert_eq(sqlite3_open(path, &db), SQLITE_OK);
    cr_assert_eq(sqlite3_exec(db, "UPDATE chunks SET edits = CAST(substr(edits, 1, 50) || X'FF' || "
                                  "substr(edits, 52) AS BLOB) WHERE x = 0 AND z = 0", NULL, NULL, NULL), SQLITE_OK);
    cr_assert_eq(sqlite3_changes(db), 1);
    sqlite3_close(db);
    bytes = read_all(path, &size);
    expect_set_aside(dir, bytes, size, "chunk (0, 0)");
    free(bytes);
    remove_tree(dir);
    corner_states_free(&s);
}

Test(terrain_store, a_foreign_sqlite_database_is_set_aside) {
    char dir[128], path[256];
    make_temp_dir(dir, sizeof dir);
    db_path(path, sizeof path, dir);
    sqlite3 *db;
    cr_assert_eq(sqlite3_open(path, &db), SQLITE_OK);
    cr_assert_eq(sqlite3_exec(db, "CREATE TABLE recipes(name TEXT); INSERT INTO recipes VALUES ('bread');", NULL,
                              NULL, NULL), SQLITE_OK);
    sqlite3_close(db);
    size_t size;
    uint8_t *bytes = read_all(path, &size);
    expect_set_aside(dir, bytes, size, "not a world database");
    free(bytes);
    remove_tree(dir);
}

Test(terrain_store, another_worlds_database_is_refused_and_left_alone) {
    corner_states s;
    corner_states_make(&s);
    char dir[128], path[256];
    make_temp_dir(dir, sizeof dir);
    size_t size;
    uint8_t *bytes = saved_database(dir, &s, &size);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED + 1) });
    terrain_store_report report;
    core_error error = { 0 };
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = SEED + 1 },
                                                &report, &error);
    cr_expect_null(store);
    cr_expect(report.other_world);
    cr_expect_eq(report.recorded_seed, SEED);
    cr_expect_eq(error.code, CORE_ERROR_MISMATCH, "%s: %s", core_error_code_name(error.code), error.message);
    cr_expect(strstr(error.message, "world.db"), "names the file: %s", error.message);
    cr_expect_eq(terrain_edit_log_chunks(log), 0);
    db_path(path, sizeof path, dir);
    size_t after_size;
    uint8_t *after = read_all(path, &after_size);
    cr_expect(after_size == size && memcmp(after, bytes, size) == 0, "left as it was");
    free(after);
    free(bytes);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
    corner_states_free(&s);
}

Test(terrain_store, a_second_process_is_refused_and_the_first_goes_on_saving) {
    corner_states s;
    corner_states_make(&s);
    char dir[128];
    make_temp_dir(dir, sizeof dir);
    save_state_a(dir, &s);
    int ready[2];
    cr_assert_eq(pipe(ready), 0);
    fflush(NULL);
    /* Forked before the parent opens anything, so no SQLite state crosses the fork. */
    pid_t child = fork();
    cr_assert_geq(child, 0);
    if (child == 0) {
        char byte;
        close(ready[1]);
        if (read(ready[0], &byte, 1) != 1) _exit(10);
        terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
        terrain_store_report report;
        core_error error = { 0 }, seed_error = { 0 };
        terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = SEED },
                                                    &report, &error);
        uint64_t seed;
        int read_seed = terrain_store_read_seed(dir, &seed, &seed_error);
        _exit(store ? 11 : !report.in_use ? 12 : error.code != CORE_ERROR_IO || !strstr(error.message, "world.db") ? 13
              : terrain_edit_log_chunks(log) != 0 ? 14 : read_seed != -1 ? 15
              : seed_error.code != CORE_ERROR_IO ? 16 : 0);
    }
    close(ready[0]);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    terrain_store_report report;
    terrain_store *store = open_store(dir, log, &report);
    cr_assert_eq(write(ready[1], "x", 1), 1);
    int status;
    cr_assert_eq(waitpid(child, &status, 0), child);
    cr_expect(WIFEXITED(status) && WEXITSTATUS(status) == 0, "the second opener: code %d (see the test)",
              WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    record_states(log, &s, s.a, s.b);
    core_error error = { 0 };
    cr_expect(terrain_store_save(store, &error), "the first goes on saving: %s", error.message);
    terrain_store_destroy(store);
    terrain_edit_log *again = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    store = open_store(dir, again, &report);
    int64_t sand;
    cr_expect_eq(replayed_state(again, &s, &sand), 'B');
    terrain_store_destroy(store);
    terrain_edit_log_destroy(again);
    terrain_edit_log_destroy(log);
    close(ready[1]);
    remove_tree(dir);
    corner_states_free(&s);
}

Test(terrain_store, bad_calls_are_refused_with_a_reason) {
    terrain_store_report report;
    core_error error = { 0 };
    cr_expect_null(terrain_store_create(NULL, &report, &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s", error.message);
    error = (core_error){ 0 };
    cr_expect_null(terrain_store_create(&(terrain_store_desc){ .dir = "/tmp" }, &report, &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s", error.message);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = 1 });
    error = (core_error){ 0 };
    cr_expect_null(terrain_store_create(&(terrain_store_desc){ .dir = "", .edits = log }, &report, &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s", error.message);
    cr_expect_null(terrain_store_create(&(terrain_store_desc){ .dir = "", .edits = log }, NULL, NULL), "NULLs are fine");
    /* A folder that cannot be made: a file stands where a parent would be. */
    char dir[128], blocked[200];
    make_temp_dir(dir, sizeof dir);
    snprintf(blocked, sizeof blocked, "%s/file", dir);
    write_all(blocked, "x", 1);
    snprintf(blocked, sizeof blocked, "%s/file/world", dir);
    cr_expect_null(terrain_store_create(&(terrain_store_desc){ .dir = blocked, .edits = log }, &report, &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s", error.message);
    cr_expect(strstr(error.message, blocked), "names the folder: %s", error.message);
    uint64_t seed;
    error = (core_error){ 0 };
    cr_expect_eq(terrain_store_read_seed(NULL, &seed, &error), -1);
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s", error.message);
    terrain_edit_log_destroy(log);
    remove_tree(dir);
}

/* ---- a long slide: the folder's size is bounded by the columns edited, not the frames -------
 * 10 000 stabilization frames each change the same 16 columns of chunk (0, 0) (sand sliding
 * back and forth), and the world is saved every 500 frames. Each save folds the chunk's entries
 * into one (terrain_edit_log_compact), so every save writes one entry of 16 columns and the
 * folder stays at its size after the first save, give or take SQLite's pages: the bound below
 * allows 256 KiB for the database's free pages and its write-ahead log. Without the fold the
 * chunk's blob holds every frame's entry: 16 columns of at least 6 bytes each a frame, over
 * 960 KB by the end. Replay cost follows the entries, so one entry also bounds the replay. */

typedef struct slide_state {
    int frame;
} slide_state;

static void slide_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    const slide_state *s = user;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
    if (x < 4 && z < 4)
        terrain_stacks_builder_push(builder, TERRAIN_SAND, (float)(1 + (s->frame + x + z) % 5) / QPM);
}

Test(terrain_store, ten_thousand_stabilization_frames_save_as_one_entry_a_chunk) {
    enum { FRAMES = 10000, SAVE_EVERY = 500 };
    char dir[64];
    make_temp_dir(dir, sizeof dir);
    terrain_chunk_coord c = { 0, 0 };
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    core_error error = { 0 };
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = SEED }, NULL,
                                                &error);
    cr_assert_not_null(store, "%s", error.message);
    terrain_stacks *generated = terrain_stacks_from_columns(c, flat_column, NULL);
    terrain_stacks *before = terrain_stacks_from_columns(c, flat_column, NULL);
    slide_state slide = { 0 };
    long long first_save_bytes = 0;
    for (slide.frame = 0; slide.frame < FRAMES; slide.frame++) {
        terrain_stacks *after = terrain_stacks_from_columns(c, slide_column, &slide);
        cr_assert(terrain_edit_log_record(log, c, TERRAIN_EDIT_STABILIZE, before, after));
        terrain_stacks_destroy(before);
        before = after;
        if ((slide.frame + 1) % SAVE_EVERY) continue;
        cr_assert(terrain_store_save(store, &error), "%s", error.message);
        if (!first_save_bytes) first_save_bytes = folder_bytes(dir);
    }
    cr_expect_eq(terrain_edit_log_entries(log, c), 1, "the last save folded the chunk");
    long long bytes = folder_bytes(dir);
    cr_expect_leq(bytes, first_save_bytes + 256 * 1024, "%lld bytes after the soak, %lld after the first save",
                  bytes, first_save_bytes);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);

    terrain_edit_log *reopened = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = world_key(SEED) });
    store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = reopened, .seed = SEED }, NULL, &error);
    cr_assert_not_null(store, "%s", error.message);
    cr_expect_eq(terrain_edit_log_entries(reopened, c), 1);
    terrain_stacks *replayed = terrain_edit_log_replay(reopened, c, generated);
    cr_expect(same_bytes(replayed, before), "the replay gives the last frame's columns");
    terrain_stacks_destroy(replayed);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(reopened);
    terrain_stacks_destroy(before);
    terrain_stacks_destroy(generated);
    remove_tree(dir);
}
