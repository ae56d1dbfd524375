/* bench_terrain_edit_log.c — the persistent edit log (terrain.h, "the edit log").
 *
 *   terrain.edit_log.save     ms for terrain_edit_log_save to write 64 edited chunks (8 × 8 from
 *       (0, 0), seed 42), each with one entry of about 40 changed columns (bedrock, sand, water
 *       of hashed heights), into a folder in /tmp: 64 files written, fsynced and renamed, and the
 *       folder fsynced. Each run records the chunks into a fresh log before the clock starts, so
 *       every chunk is dirty; the files of the previous run are replaced, as in a game that
 *       saves. Bound by the disk's fsync, not by the encoding.
 *   terrain.edit_log.load     ms for terrain_edit_log_load to read those 64 files back into a
 *       fresh log (checksums, checks, entries).
 *   terrain.edit_log.replay   µs for terrain_edit_log_replay of one chunk with 10 entries of
 *       about 40 columns each over its generated stacks (what a worker adds to generating an
 *       edited chunk); mean of 200 replays per run.
 */
#include "bench.h"

#include "core/core.h"
#include "terrain/terrain.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { SAVE_SIDE = 8, SAVE_CHUNKS = SAVE_SIDE * SAVE_SIDE, EDIT_COLUMNS = 40, REPLAY_ENTRIES = 10,
       REPLAYS_PER_RUN = 200 };

typedef struct edit_log_bench {
    uint64_t key;
    terrain_chunk_coord coord[SAVE_CHUNKS];
    terrain_stacks *generated[SAVE_CHUNKS], *edited[SAVE_CHUNKS];
    terrain_stacks *steps[REPLAY_ENTRIES + 1];   /* chunk 0 edited ten times in a row */
    terrain_edit_log *replay_log;
    char dir[64];
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
    terrain_generation_params params = terrain_generation_defaults(42);
    b->key = terrain_generation_key(&params);
    for (int n = 0; n < SAVE_CHUNKS; n++) {
        b->coord[n] = (terrain_chunk_coord){ n % SAVE_SIDE, n / SAVE_SIDE };
        b->generated[n] = terrain_generate_chunk(&params, b->coord[n]);
        b->edited[n] = edit_chunk(b->generated[n], b->coord[n], (uint64_t)n);
    }
    b->replay_log = terrain_edit_log_create(b->key);
    b->steps[0] = b->generated[0];
    for (int e = 1; e <= REPLAY_ENTRIES; e++) {
        b->steps[e] = edit_chunk(b->steps[e - 1], b->coord[0], 1000u + (uint64_t)e);
        terrain_edit_log_record(b->replay_log, b->coord[0], TERRAIN_EDIT_SET, b->steps[e - 1], b->steps[e]);
    }
    snprintf(b->dir, sizeof b->dir, "/tmp/bench_edit_log_XXXXXX");
    if (!mkdtemp(b->dir)) core_fatal("bench", "cannot make a folder in /tmp");
}

static void remove_saves(const char *dir) {
    char folder[128], path[512];
    snprintf(folder, sizeof folder, "%s/edits", dir);
    DIR *listing = opendir(folder);
    for (struct dirent *e; listing && (e = readdir(listing));) {
        if (e->d_name[0] == '.') continue;
        snprintf(path, sizeof path, "%s/%s", folder, e->d_name);
        unlink(path);
    }
    if (listing) closedir(listing);
    rmdir(folder);
    rmdir(dir);
}

static void bench_teardown(edit_log_bench *b) {
    for (int n = 0; n < SAVE_CHUNKS; n++) terrain_stacks_destroy(b->generated[n]), terrain_stacks_destroy(b->edited[n]);
    for (int e = 1; e <= REPLAY_ENTRIES; e++) terrain_stacks_destroy(b->steps[e]);
    terrain_edit_log_destroy(b->replay_log);
    remove_saves(b->dir);
}

static terrain_edit_log *recorded_log(const edit_log_bench *b) {
    terrain_edit_log *log = terrain_edit_log_create(b->key);
    for (int n = 0; n < SAVE_CHUNKS; n++)
        terrain_edit_log_record(log, b->coord[n], TERRAIN_EDIT_SET, b->generated[n], b->edited[n]);
    return log;
}

static double sample_save(void *user) {
    edit_log_bench *b = user;
    terrain_edit_log *log = recorded_log(b);
    char error[512];
    uint64_t start = core_time_ns();
    if (!terrain_edit_log_save(log, b->dir, error, sizeof error)) core_fatal("bench", "%s", error);
    double ms = core_ns_to_ms(core_time_ns() - start);
    terrain_edit_log_destroy(log);
    return ms;
}

static double sample_load(void *user) {
    edit_log_bench *b = user;
    terrain_edit_log *log = terrain_edit_log_create(b->key);
    terrain_edit_log_load_result result;
    uint64_t start = core_time_ns();
    bool ok = terrain_edit_log_load(log, b->dir, &result);
    double ms = core_ns_to_ms(core_time_ns() - start);
    if (!ok || result.chunks_loaded != SAVE_CHUNKS || result.files_rejected)
        core_fatal("bench", "edit log load: %d loaded, %s", result.chunks_loaded, result.first_problem);
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

void bench_group_terrain_edit_log(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.edit_log")) return;
    edit_log_bench *b = core_calloc(1, sizeof *b);
    bench_setup(b);
    /* The replayed chunk must be the last edit, byte for byte, or the row measures nothing. */
    terrain_stacks *check = terrain_edit_log_replay(b->replay_log, b->coord[0], b->generated[0]);
    if (!check || terrain_stacks_hash(check) != terrain_stacks_hash(b->steps[REPLAY_ENTRIES]))
        core_fatal("bench", "edit log replay differs from the recorded chunk");
    terrain_stacks_destroy(check);
    bench_run(ctx, "terrain.edit_log.save", "ms", 9, sample_save, b);
    if (bench_wants(ctx, "terrain.edit_log.load")) {
        sample_save(b);                               /* the files to load, whatever the filter */
        bench_run(ctx, "terrain.edit_log.load", "ms", 9, sample_load, b);
    }
    if (bench_wants(ctx, "terrain.edit_log.replay")) bench_run(ctx, "terrain.edit_log.replay", "us", 9, sample_replay, b);
    bench_teardown(b);
    core_free(b, sizeof *b);
}
