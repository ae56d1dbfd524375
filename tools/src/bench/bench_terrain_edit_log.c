/* bench_terrain_edit_log.c — saving edits (terrain.h, "the edit log", "the world folder").
 *
 * The input: 64 edited chunks (8 × 8 from (0, 0), seed 42), each with one entry of about 40
 * changed columns (bedrock, sand, water of hashed heights).
 *
 *   terrain.edit_log.save     ms for terrain_store_save to write the 64 chunks into world.db: one
 *       transaction, one fsync of the write-ahead log. The store stays open across runs, as in a
 *       game; each run flips every chunk between edited and generated and compacts (before the
 *       clock starts), so all 64 are dirty and each holds one entry.
 *   terrain.edit_log.save.tel_files  the same 64 chunks written the old way for comparison in the
 *       same run (terrain_edit_log_save: one file each, fsynced and renamed, then the folder).
 *   world.save.frame_ms       ms the calling thread spends in terrain_store_save_async on those
 *       64 chunks (the snapshot; the commit runs on the store's thread): a game's frame cost.
 *   terrain.edit_log.load     ms for terrain_store_create on that world.db into a fresh log
 *       (open, lock, SQLite's quick_check, read and parse 64 blobs).
 *   terrain.edit_log.load.tel_files  ms for terrain_edit_log_load of the 64 old files.
 *   terrain.edit_log.replay   µs for terrain_edit_log_replay of one chunk with 10 entries of
 *       about 40 columns each over its generated stacks (what a worker adds to generating an
 *       edited chunk); mean of 200 replays per run.
 *   terrain.edit_log.soak_bytes  bytes of a world folder after a slide of 10 000 stabilization
 *       frames on chunk (0, 0) (the same 16 columns changed every frame), saved every 500 frames
 *       and closed: bounded by the columns edited, since each save folds a chunk's entries.
 */
#include "bench.h"

#include "core/core.h"
#include "terrain/terrain.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { SAVE_SIDE = 8, SAVE_CHUNKS = SAVE_SIDE * SAVE_SIDE, EDIT_COLUMNS = 40, REPLAY_ENTRIES = 10,
       REPLAYS_PER_RUN = 200 };

typedef struct edit_log_bench {
    uint64_t key;
    terrain_chunk_coord coord[SAVE_CHUNKS];
    terrain_stacks *generated[SAVE_CHUNKS], *edited[SAVE_CHUNKS];
    terrain_stacks *steps[REPLAY_ENTRIES + 1];   /* chunk 0 edited ten times in a row */
    terrain_edit_log *replay_log;
    char dir[64], store_dir[96], files_dir[96];
    terrain_edit_log *store_log;      /* the open store's log, and the state its chunks are in */
    terrain_store *store;
    bool store_edited;
} edit_log_bench;

/* `from` with EDIT_COLUMNS columns, picked by hashing `salt`, set by hand. */
static terrain_stacks *edit_chunk(const terrain_stacks *from, terrain_chunk_coord coord, uint64_t salt) {
    terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
        .x = coord.x * TERRAIN_CHUNK_COLUMNS, .z = coord.z * TERRAIN_CHUNK_COLUMNS,
        .width = TERRAIN_CHUNK_COLUMNS, .depth = TERRAIN_CHUNK_COLUMNS });
    terrain_columns_load(region, coord, from);
    for (int n = 0; n < EDIT_COLUMNS; n++) {
        uint64_t h = core_hash_u64(salt * 977 + (uint64_t)n);
        terrain_layer layers[3] = { { TERRAIN_BEDROCK, 230.0f + (float)(h >> 20 & 1023) / 32.0f },
                                    { TERRAIN_SAND, (float)(h >> 40 & 63) / 32.0f },
                                    { TERRAIN_WATER, (h & 1) ? 2.0f : 0.0f } };
        terrain_columns_set(region, (int)(h % TERRAIN_CHUNK_COLUMNS), (int)(h >> 8 & 31), layers, 3);
    }
    terrain_stacks *out = terrain_columns_to_stacks(region, coord);
    terrain_columns_destroy(region);
    return out;
}

static void bench_setup(edit_log_bench *b) {
    terrain_generation_desc params = terrain_generation_defaults(42);
    b->key = terrain_generation_key(&params);
    for (int n = 0; n < SAVE_CHUNKS; n++) {
        b->coord[n] = (terrain_chunk_coord){ n % SAVE_SIDE, n / SAVE_SIDE };
        b->generated[n] = terrain_generate_chunk(&params, b->coord[n]);
        b->edited[n] = edit_chunk(b->generated[n], b->coord[n], (uint64_t)n);
    }
    b->replay_log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = b->key });
    b->steps[0] = b->generated[0];
    for (int e = 1; e <= REPLAY_ENTRIES; e++) {
        b->steps[e] = edit_chunk(b->steps[e - 1], b->coord[0], 1000u + (uint64_t)e);
        terrain_edit_log_record(b->replay_log, b->coord[0], TERRAIN_EDIT_SET, b->steps[e - 1], b->steps[e]);
    }
    snprintf(b->dir, sizeof b->dir, "/tmp/bench_edit_log_XXXXXX");
    if (!mkdtemp(b->dir)) core_fatal("bench", "cannot make a folder in /tmp");
    snprintf(b->store_dir, sizeof b->store_dir, "%s/db", b->dir);
    snprintf(b->files_dir, sizeof b->files_dir, "%s/files", b->dir);
}

/* rm -r of what the rows write: folders of files, two deep. */
static void remove_tree(const char *path) {
    DIR *listing = opendir(path);
    if (!listing) {
        unlink(path);
        return;
    }
    for (struct dirent *e; (e = readdir(listing));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char child[512];
        snprintf(child, sizeof child, "%s/%s", path, e->d_name);
        remove_tree(child);
    }
    closedir(listing);
    rmdir(path);
}

static void bench_teardown(edit_log_bench *b) {
    for (int n = 0; n < SAVE_CHUNKS; n++) terrain_stacks_destroy(b->generated[n]), terrain_stacks_destroy(b->edited[n]);
    for (int e = 1; e <= REPLAY_ENTRIES; e++) terrain_stacks_destroy(b->steps[e]);
    terrain_edit_log_destroy(b->replay_log);
    terrain_store_destroy(b->store);
    terrain_edit_log_destroy(b->store_log);
    remove_tree(b->dir);
}

static terrain_edit_log *recorded_log(const edit_log_bench *b) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = b->key });
    for (int n = 0; n < SAVE_CHUNKS; n++)
        terrain_edit_log_record(log, b->coord[n], TERRAIN_EDIT_SET, b->generated[n], b->edited[n]);
    return log;
}

static double sample_save_files(void *user) {
    edit_log_bench *b = user;
    terrain_edit_log *log = recorded_log(b);
    core_error error = { 0 };
    uint64_t start = core_time_ns();
    if (!terrain_edit_log_save(log, b->files_dir, &error)) core_fatal("bench", "%s", error.message);
    double ms = core_ns_to_ms(core_time_ns() - start);
    terrain_edit_log_destroy(log);
    return ms;
}

static void open_store(edit_log_bench *b) {
    if (b->store) return;
    b->store_log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = b->key });
    terrain_store_report report;
    core_error error = { 0 };
    b->store = terrain_store_create(&(terrain_store_desc){ .dir = b->store_dir, .edits = b->store_log, .seed = 42 },
                                    &report, &error);
    if (!b->store) core_fatal("bench", "%s", error.message);
}

/* Every chunk of the open store's log flipped between edited and generated, one entry each. */
static void dirty_all(edit_log_bench *b) {
    open_store(b);
    for (int n = 0; n < SAVE_CHUNKS; n++)
        terrain_edit_log_record(b->store_log, b->coord[n], TERRAIN_EDIT_SET, b->store_edited ? b->edited[n] : b->generated[n],
                                b->store_edited ? b->generated[n] : b->edited[n]);
    b->store_edited = !b->store_edited;
    terrain_edit_log_compact(b->store_log);
}

static double sample_save(void *user) {
    edit_log_bench *b = user;
    dirty_all(b);
    core_error error = { 0 };
    uint64_t start = core_time_ns();
    if (!terrain_store_save(b->store, &error)) core_fatal("bench", "%s", error.message);
    return core_ns_to_ms(core_time_ns() - start);
}

static double sample_save_frame(void *user) {
    edit_log_bench *b = user;
    dirty_all(b);
    uint64_t start = core_time_ns();
    if (!terrain_store_save_async(b->store)) core_fatal("bench", "a save still in flight");
    double ms = core_ns_to_ms(core_time_ns() - start);
    core_error error = { 0 };
    if (!terrain_store_wait(b->store, &error)) core_fatal("bench", "%s", error.message);
    return ms;
}

static double sample_load(void *user) {
    edit_log_bench *b = user;
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = b->key });
    terrain_store_report report;
    core_error error = { 0 };
    uint64_t start = core_time_ns();
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = b->store_dir, .edits = log }, &report,
                                                &error);
    double ms = core_ns_to_ms(core_time_ns() - start);
    if (!store || report.chunks_loaded != SAVE_CHUNKS || report.set_aside)
        core_fatal("bench", "store load: %d loaded, %s%s", report.chunks_loaded, error.message, report.notice);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);
    return ms;
}

static double sample_load_files(void *user) {
    edit_log_bench *b = user;
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = b->key });
    terrain_edit_log_load_result result;
    core_error error = { 0 };
    uint64_t start = core_time_ns();
    bool ok = terrain_edit_log_load(log, b->files_dir, &result, &error);
    double ms = core_ns_to_ms(core_time_ns() - start);
    if (!ok || result.chunks_loaded != SAVE_CHUNKS || result.files_rejected)
        core_fatal("bench", "edit log load: %d loaded, %s%s", result.chunks_loaded, error.message,
                   result.first_problem.message);
    terrain_edit_log_destroy(log);
    return ms;
}

static double sample_replay(void *user) {
    edit_log_bench *b = user;
    uint64_t start = core_time_ns(), check = 0;
    for (int r = 0; r < REPLAYS_PER_RUN; r++) {
        terrain_stacks *s = terrain_edit_log_replay(b->replay_log, b->coord[0], b->generated[0]);
        check += terrain_stacks_bytes(s);
        terrain_stacks_destroy(s);
    }
    double us = (double)(core_time_ns() - start) * 1e-3 / REPLAYS_PER_RUN;
    bench_consume((double)check);
    return us;
}

/* The soak: 16 columns of chunk 0's generated ground get a sand cover that changes every frame. */
static double sample_soak_bytes(void *user) {
    edit_log_bench *b = user;
    enum { FRAMES = 10000, SAVE_EVERY = 500, SIDE = 4 };
    char dir[160];
    snprintf(dir, sizeof dir, "%s/soak", b->dir);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = b->key });
    core_error error = { 0 };
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log }, NULL, &error);
    if (!store) core_fatal("bench", "%s", error.message);
    terrain_chunk_coord coord = b->coord[0];
    terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
        .x = coord.x * TERRAIN_CHUNK_COLUMNS, .z = coord.z * TERRAIN_CHUNK_COLUMNS,
        .width = TERRAIN_CHUNK_COLUMNS, .depth = TERRAIN_CHUNK_COLUMNS });
    terrain_columns_load(region, coord, b->generated[0]);
    terrain_stacks *before = terrain_columns_to_stacks(region, coord);
    for (int frame = 0; frame < FRAMES; frame++) {
        for (int k = 0; k < SIDE; k++)
            for (int i = 0; i < SIDE; i++) {
                terrain_layer layers[2] = { { TERRAIN_BEDROCK, 240.0f },
                                            { TERRAIN_SAND, (float)(1 + (frame + i + k) % 5) / 32.0f } };
                terrain_columns_set(region, i, k, layers, 2);
            }
        terrain_stacks *after = terrain_columns_to_stacks(region, coord);
        terrain_edit_log_record(log, coord, TERRAIN_EDIT_STABILIZE, before, after);
        terrain_stacks_destroy(before);
        before = after;
        if ((frame + 1) % SAVE_EVERY == 0 && !terrain_store_save(store, &error))
            core_fatal("bench", "%s", error.message);
    }
    terrain_store_destroy(store);
    terrain_edit_log_destroy(log);
    terrain_stacks_destroy(before);
    terrain_columns_destroy(region);
    double bytes = 0;
    DIR *listing = opendir(dir);
    for (struct dirent *e; listing && (e = readdir(listing));) {
        char path[512];
        struct stat info;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &info) == 0 && S_ISREG(info.st_mode)) bytes += (double)info.st_size;
    }
    if (listing) closedir(listing);
    remove_tree(dir);
    return bytes;
}

void bench_group_terrain_edit_log(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.edit_log") && !bench_wants(ctx, "world.save")) return;
    edit_log_bench *b = core_calloc(1, sizeof *b);
    bench_setup(b);
    /* The replayed chunk must be the last edit, byte for byte, or the row measures nothing. */
    terrain_stacks *check = terrain_edit_log_replay(b->replay_log, b->coord[0], b->generated[0]);
    if (!check || terrain_stacks_hash(check) != terrain_stacks_hash(b->steps[REPLAY_ENTRIES]))
        core_fatal("bench", "edit log replay differs from the recorded chunk");
    terrain_stacks_destroy(check);
    bench_run(ctx, "terrain.edit_log.save", "ms", 15, sample_save, b);
    bench_run(ctx, "terrain.edit_log.save.tel_files", "ms", 9, sample_save_files, b);
    bench_run(ctx, "world.save.frame_ms", "ms", 15, sample_save_frame, b);
    if (bench_wants(ctx, "terrain.edit_log.load")) {
        /* What to load, whatever the filter: the store closed (its WAL checkpointed) and the files. */
        dirty_all(b);
        core_error error = { 0 };
        if (!terrain_store_save(b->store, &error)) core_fatal("bench", "%s", error.message);
        terrain_store_destroy(b->store);
        b->store = NULL;
        sample_save_files(b);
        bench_run(ctx, "terrain.edit_log.load", "ms", 9, sample_load, b);
        bench_run(ctx, "terrain.edit_log.load.tel_files", "ms", 9, sample_load_files, b);
    }
    if (bench_wants(ctx, "terrain.edit_log.replay")) bench_run(ctx, "terrain.edit_log.replay", "us", 9, sample_replay, b);
    if (bench_wants(ctx, "terrain.edit_log.soak_bytes"))
        bench_run(ctx, "terrain.edit_log.soak_bytes", "bytes", 3, sample_soak_bytes, b);
    bench_teardown(b);
    core_free(b, sizeof *b);
}
