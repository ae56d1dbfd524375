/* The terrain world shared by jobs: many threads asking for the same chunks at once get the same
 * bytes a lone thread generates, and fields sampled concurrently agree; the far terrain's
 * clipmap computes the same heights on jobs as alone. Also built into test_threads, which
 * tools/test runs under ThreadSanitizer. */
#include "../engine/test.h"

#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define THREAD_CHUNKS 6
#define THREAD_REQUESTS 48

typedef struct world_job {
    terrain_world *world;
    uint64_t hashes[THREAD_REQUESTS];
    float samples[THREAD_REQUESTS];
} world_job;

static terrain_chunk_coord chunk_of(int request) {
    return (terrain_chunk_coord){ request % THREAD_CHUNKS - 3, (request / 7) % 2 };
}

static void fetch_range(void *user, size_t begin, size_t end) {
    world_job *job = user;
    for (int r = (int)begin; r < (int)end; r++) {
        terrain_chunk_coord c = chunk_of(r);
        job->hashes[r] = terrain_stacks_hash(terrain_world_stacks(job->world, c));
        /* A field sample on the chunk's corner reads it and its neighbours. */
        terrain_field field;
        cr_assert(terrain_field_sample(job->world, &(terrain_field_desc){
            .first = { c.x * TERRAIN_CHUNK_COLUMNS, 20, c.z * TERRAIN_CHUNK_COLUMNS }, .size = { 2, 2, 2 } }, &field));
        job->samples[r] = field.values[0];
        terrain_field_free(&field);
    }
}

Test(terrain_threads, shared_world_gives_the_bytes_of_a_lone_thread) {
    terrain_generation_desc params = terrain_generation_defaults(11);
    terrain_world *lone = terrain_world_create(&(terrain_world_desc){ .generation = params });
    terrain_world *shared = terrain_world_create(&(terrain_world_desc){ .generation = params });
    world_job expected = { .world = lone }, got = { .world = shared };
    fetch_range(&expected, 0, THREAD_REQUESTS);
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 4 });
    job_parallel_for(jobs, THREAD_REQUESTS, 1, fetch_range, &got, "fetch");
    for (int r = 0; r < THREAD_REQUESTS; r++) {
        cr_assert_eq(got.hashes[r], expected.hashes[r], "request %d", r);
        cr_assert_eq(got.samples[r], expected.samples[r], "request %d", r);
    }
    cr_assert_leq(terrain_world_chunk_count(shared), (size_t)(THREAD_CHUNKS * 2 * 9), "each chunk cached once");
    job_system_destroy(jobs);
    terrain_world_destroy(lone);
    terrain_world_destroy(shared);
}

/* ---- the mesher's passes over slabs on the job system ---- */

static float threads_ball(int x, int y, int z) {
    double dx = x - 33.3, dy = y - 34.1, dz = z - 32.7;
    return (float)(29.5 - sqrt(dx * dx + dy * dy + dz * dz) + 2.0 * sin(0.4 * x) * cos(0.3 * z));
}

/* A field past the size that splits over threads (64³ cells): the same bytes as the calling
 * thread alone, and no race between the slabs (this suite runs under ThreadSanitizer). */
Test(terrain_threads, mesher_slabs_on_jobs_give_the_bytes_of_one_thread) {
    terrain_field f = { .nx = 68, .ny = 68, .nz = 68, .spacing = 1.0f };
    f.values = malloc((size_t)f.nx * f.ny * f.nz * sizeof *f.values);
    for (int z = 0; z < f.nz; z++)
        for (int y = 0; y < f.ny; y++)
            for (int x = 0; x < f.nx; x++) f.values[((size_t)z * f.ny + y) * f.nx + x] = threads_ball(x, y, z);
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 3 });
    terrain_mesh lone, shared;
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .apron = 1, .no_optimize = true }, &lone));
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .apron = 1, .no_optimize = true, .jobs = jobs }, &shared));
    cr_assert_gt(lone.index_count, 0);
    cr_assert_eq(shared.vertex_count, lone.vertex_count);
    cr_assert_eq(shared.index_count, lone.index_count);
    cr_expect(!memcmp(shared.vertices, lone.vertices, lone.vertex_count * sizeof *lone.vertices));
    cr_expect(!memcmp(shared.indices, lone.indices, lone.index_count * sizeof *lone.indices));
    terrain_mesh_free(&shared);
    terrain_mesh_free(&lone);
    job_system_destroy(jobs);
    free(f.values);
}

/* ---- the far terrain's clipmap, its heights computed on the job system ---- */

#include "terrain/terrain_internal.h"

/* Jumps make every update big enough to fan out (over 4096 heights); the heights must be those
 * the calling thread alone computes. */
Test(terrain_threads, clipmap_heights_on_jobs_equal_a_lone_threads) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    terrain_clipmap_desc desc = { .levels = 3, .cells = 64, .generation = terrain_generation_defaults(5) };
    terrain_clipmap *lone = terrain_clipmap_create(&desc);
    desc.jobs = jobs;
    terrain_clipmap *shared = terrain_clipmap_create(&desc);
    const double cameras[][3] = { { 0, 0, 0 }, { 5000, 0, -300 }, { 5100, 0, -260 }, { -90000, 0, 4000 } };
    for (int n = 0; n < 4; n++) {
        cr_assert_eq(terrain_clipmap_update(shared, cameras[n]), terrain_clipmap_update(lone, cameras[n]));
        for (int l = 0; l < 3; l++) {
            terrain__clipmap_level_info info = terrain__clipmap_level(lone, l);
            for (int64_t k = info.first[1] - 1; k <= info.first[1] + info.cells + 1; k++)
                for (int64_t i = info.first[0] - 1; i <= info.first[0] + info.cells + 1; i++)
                    cr_assert(terrain__clipmap_texel(shared, l, i, k) == terrain__clipmap_texel(lone, l, i, k),
                              "camera %d level %d texel (%lld, %lld)", n, l, (long long)i, (long long)k);
        }
    }
    terrain_clipmap_destroy(shared);
    terrain_clipmap_destroy(lone);
    job_system_destroy(jobs);
}

/* A hand-made world (cheap to generate under ThreadSanitizer): bedrock rolling by ±3 m. */
static void threads_rolling_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.0f + 3.0f * sinf((float)x / 7.0f) * cosf((float)z / 5.0f) - TERRAIN_FLOOR_Y);
}

static terrain_stacks *threads_rolling_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, threads_rolling_column, user);
}

/* With a world (002 §3.5): the jobs read the cached stacks under the world's lock, the first
 * build and the pass over the texels of chunks generated since both fan out, and the heights
 * are those of a lone thread on a world with the same chunks. */
Test(terrain_threads, clipmap_heights_from_the_stacks_on_jobs_equal_a_lone_threads) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    terrain_world *worlds[2];
    terrain_clipmap *clipmaps[2];
    for (int w = 0; w < 2; w++) {
        worlds[w] = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5),
                                                                .generate = threads_rolling_chunk });
        for (int64_t cz = -2; cz < 2; cz++)
            for (int64_t cx = -2; cx < 0; cx++) terrain_world_stacks(worlds[w], (terrain_chunk_coord){ cx, cz });
        clipmaps[w] = terrain_clipmap_create(&(terrain_clipmap_desc){ .levels = 2, .cells = 96, .finest_spacing = 1.0f,
            .generation = terrain_generation_defaults(5), .jobs = w ? jobs : NULL, .world = worlds[w] });
    }
    const double camera[3] = { 10, 20, -10 };
    for (int round = 0; round < 2; round++) {
        if (round == 1)   /* 8 more chunks: about 61 × 99 texels of level 0 to redo, over 4096 */
            for (int w = 0; w < 2; w++)
                for (int64_t cz = -2; cz < 2; cz++)
                    for (int64_t cx = 0; cx < 2; cx++) terrain_world_stacks(worlds[w], (terrain_chunk_coord){ cx, cz });
        cr_assert_eq(terrain_clipmap_update(clipmaps[1], camera), terrain_clipmap_update(clipmaps[0], camera));
        for (int l = 0; l < 2; l++) {
            terrain__clipmap_level_info info = terrain__clipmap_level(clipmaps[0], l);
            for (int64_t k = info.first[1] - 1; k <= info.first[1] + info.cells + 1; k++)
                for (int64_t i = info.first[0] - 1; i <= info.first[0] + info.cells + 1; i++)
                    cr_assert(terrain__clipmap_texel(clipmaps[1], l, i, k) == terrain__clipmap_texel(clipmaps[0], l, i, k),
                              "round %d level %d texel (%lld, %lld)", round, l, (long long)i, (long long)k);
        }
    }
    for (int w = 0; w < 2; w++) {
        terrain_clipmap_destroy(clipmaps[w]);
        terrain_world_destroy(worlds[w]);
    }
    job_system_destroy(jobs);
}

/* Stabilization's passes split into row jobs (000 §3.4): rows of one colour are three apart, so
 * their 3 × 3 writes never meet. Under ThreadSanitizer this checks that claim; everywhere it
 * checks that four threads give the bytes of one. */
#define STABILIZE_SIDE 112

/* Bumpy piles of sand and rocks on flat bedrock, a pure function of the world column: the region
 * of `side` columns from (x, z). */
static terrain_columns *bumpy_part(int x, int z, int side) {
    terrain_columns *c = terrain_columns_create(&(terrain_columns_desc){ .x = x, .z = z, .width = side, .depth = side });
    for (int k = 0; k < side; k++)
        for (int i = 0; i < side; i++) {
            uint64_t h = (uint64_t)((z + k) * STABILIZE_SIDE + x + i) * 0x9e3779b97f4a7c15ull;
            terrain_layer layers[3] = { { TERRAIN_BEDROCK, 10.0f },
                                        { TERRAIN_SAND, (float)(h >> 59) * 0.25f },
                                        { TERRAIN_ROCKS, (float)((h >> 54) & 15) * 0.125f } };
            terrain_columns_set(c, i, k, layers, 3);   /* marks the column for stabilization */
        }
    return c;
}

static terrain_columns *bumpy_region(void) { return bumpy_part(0, 0, STABILIZE_SIDE); }

/* Of columns [x0, x0 + side) × [z0, z0 + side) of the region. */
static uint64_t part_hash(const terrain_columns *c, int x0, int z0, int side) {
    uint64_t h = 0;
    terrain_layer layers[8];
    for (int k = z0; k < z0 + side; k++)
        for (int i = x0; i < x0 + side; i++) {
            int n = terrain_columns_get(c, i, k, layers, 8);
            for (int l = 0; l < n && l < 8; l++)
                h = h * 1000003u + (uint64_t)layers[l].material * 7919u + (uint64_t)(layers[l].thickness * 32.0f);
            h = h * 31u + 1u;
        }
    return h;
}

static uint64_t columns_hash(const terrain_columns *c) { return part_hash(c, 0, 0, STABILIZE_SIDE); }

Test(terrain_threads, stabilization_on_four_threads_gives_the_bytes_of_one) {
    terrain_columns *lone = bumpy_region(), *shared = bumpy_region();
    int64_t sand = terrain_columns_mass(lone, TERRAIN_SAND), rocks = terrain_columns_mass(lone, TERRAIN_ROCKS);
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 4 });
    terrain_stabilize_result a, b;
    cr_assert(terrain_stabilize_region(lone, &(terrain_stabilize_desc){ 0 }, NULL, &a));
    cr_assert(terrain_stabilize_region(shared, &(terrain_stabilize_desc){ 0 }, jobs, &b));
    cr_expect(a.converged && b.converged);
    cr_expect_gt(a.moved, 0);
    cr_expect_eq(a.moved, b.moved);
    cr_expect_eq(a.iterations, b.iterations);
    cr_expect_eq(columns_hash(lone), columns_hash(shared));
    cr_expect_eq(terrain_columns_mass(shared, TERRAIN_SAND), sand);
    cr_expect_eq(terrain_columns_mass(shared, TERRAIN_ROCKS), rocks);
    job_system_destroy(jobs);
    terrain_columns_destroy(lone);
    terrain_columns_destroy(shared);
}

Test(terrain_threads, regions_side_by_side_on_four_threads_give_the_bytes_of_one_region) {
    enum { HALF = STABILIZE_SIDE / 2 };
    terrain_columns *whole = bumpy_region(), *parts[4];
    for (int n = 0; n < 4; n++) parts[n] = bumpy_part(n % 2 * HALF, n / 2 * HALF, HALF);
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 4 });
    terrain_stabilize_result a, b;
    cr_assert(terrain_stabilize_region(whole, &(terrain_stabilize_desc){ 0 }, NULL, &a));
    cr_assert(terrain_stabilize_regions(parts, 4, &(terrain_stabilize_desc){ 0 }, jobs, &b));
    cr_expect(a.converged && b.converged);
    cr_expect_eq(a.moved, b.moved);
    for (int n = 0; n < 4; n++)
        cr_expect_eq(part_hash(whole, n % 2 * HALF, n / 2 * HALF, HALF), part_hash(parts[n], 0, 0, HALF), "part %d", n);
    job_system_destroy(jobs);
    for (int n = 0; n < 4; n++) terrain_columns_destroy(parts[n]);
    terrain_columns_destroy(whole);
}

/* ---- a stabilization's batches in a trace ---- */

#include "core/core.h"
#include "trace/trace.h"
#include "../engine/trace_file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* Each batch of a stabilization pass is a job zone "terrain.stabilize.pass" carrying its rows and
 * the columns of the pass's colour they span. Every row of a 112-column region holds 37 or 38
 * columns of one colour (112 = 3 · 37 + 1), so a batch of r rows spans between 37 r and 38 r;
 * in the first pass every column of the bumpy region is marked and each row is whole. */
Test(terrain_threads, stabilize_batches_carry_their_columns) {
    char path[128];
    snprintf(path, sizeof path, "/tmp/terrain_test_stabilize_trace_%d.json", (int)getpid());
    terrain_columns *region = bumpy_region();
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 4 });
    cr_assert(trace_start(path));
    terrain_stabilize_result result;
    cr_assert(terrain_stabilize_region(region, &(terrain_stabilize_desc){ 0 }, jobs, &result));
    trace_stop();
    job_system_destroy(jobs);
    terrain_columns_destroy(region);

    core_arena arena = { 0 };
    const core_json_value *events = trace_file_load(path, &arena, NULL);

    /* The first pass's batches all begin before its join job does (the join waits on them). */
    double first_join = INFINITY;
    for (size_t i = 0; i < events->array.count; i++) {
        const core_json_value *e = &events->array.items[i];
        if (core_json_string_equals(core_json_get(e, "ph"), "B") &&
            core_json_string_equals(core_json_get(e, "name"), "parallel_for.join"))
            first_join = fmin(first_join, core_json_number_or(core_json_get(e, "ts"), INFINITY));
    }
    size_t batches = 0;
    double first_rows = 0, first_columns = 0;
    for (size_t i = 0; i < events->array.count; i++) {
        const core_json_value *e = &events->array.items[i];
        if (!core_json_string_equals(core_json_get(e, "ph"), "B") ||
            !core_json_string_equals(core_json_get(e, "name"), "terrain.stabilize.pass"))
            continue;
        const core_json_value *args = core_json_get(e, "args");
        double rows = core_json_number_or(core_json_get(args, "rows"), -1);
        double columns = core_json_number_or(core_json_get(args, "columns"), -1);
        cr_assert_geq(rows, 1, "batch %zu: rows %g", batches, rows);
        cr_assert_geq(columns, 0, "batch %zu: columns %g", batches, columns);
        cr_expect_leq(columns, 38 * rows, "batch %zu: %g columns in %g rows", batches, columns, rows);
        if (core_json_number_or(core_json_get(e, "ts"), INFINITY) < first_join) {
            first_rows += rows;
            first_columns += columns;
        }
        batches++;
    }
    cr_expect_gt(batches, 0, "no stabilization batch ran on the jobs");
    cr_expect_gt(first_rows, 0);
    cr_expect_geq(first_columns, 37 * first_rows, "first pass: %g columns in %g rows", first_columns, first_rows);
    cr_expect_leq(first_columns, 38 * first_rows, "first pass: %g columns in %g rows", first_columns, first_rows);
    core_arena_release(&arena);
}

/* ---- the edit log: four threads replay while one records, compacts and parses ---- */

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define LOG_REPLAYERS 4
#define LOG_STEPS 240

typedef struct log_share {
    terrain_edit_log *log;
    terrain_chunk_coord coord;
    const terrain_stacks *generated, *state[2];   /* A, B */
    const void *file_a;                           /* state A as its saved file */
    size_t file_a_size;
    atomic_bool done;
} log_share;

typedef struct log_replayer {
    log_share *share;
    int replays, wrong;
} log_replayer;

/* Column n set to bedrock of `height` quanta, plus `sand` quanta of sand. */
static void set_column(terrain_columns *c, int n, int height, int sand) {
    terrain_layer layers[2] = { { TERRAIN_BEDROCK, (float)height / 32.0f }, { TERRAIN_SAND, (float)sand / 32.0f } };
    cr_assert(terrain_columns_set(c, n % TERRAIN_CHUNK_COLUMNS, n / TERRAIN_CHUNK_COLUMNS, layers, 2));
}

static bool same_stacks(const terrain_stacks *a, const terrain_stacks *b) {
    return terrain_stacks_hash(a) == terrain_stacks_hash(b) && terrain_stacks_bytes(a) == terrain_stacks_bytes(b) &&
           memcmp(a, b, terrain_stacks_bytes(a)) == 0;
}

static void *replay_loop(void *user) {
    log_replayer *r = user;
    log_share *s = r->share;
    /* At least a few replays, however fast the recorder is. */
    while (!atomic_load(&s->done) || r->replays < 8) {
        terrain_stacks *got = terrain_edit_log_replay(s->log, s->coord, s->generated);
        r->wrong += !got || !(same_stacks(got, s->state[0]) || same_stacks(got, s->state[1]));
        r->replays++;
        terrain_stacks_destroy(got);
    }
    return NULL;
}

/* Alternates the chunk between A and B; now and then compacts, or parses A's file over it. */
static void record_loop(log_share *s) {
    int current = 0;
    core_error error = { 0 };
    for (int step = 0; step < LOG_STEPS; step++) {
        cr_assert(terrain_edit_log_record(s->log, s->coord, TERRAIN_EDIT_SET, s->state[current],
                                          s->state[1 - current]));
        current = 1 - current;
        if (step % 10 == 9) terrain_edit_log_compact(s->log);
        if (step % 25 == 24) {
            cr_assert(terrain_edit_log_parse(s->log, s->file_a, s->file_a_size, &error), "%s", error.message);
            current = 0;
        }
    }
}

/* State A saved by a log of its own; the file's bytes (free with free). */
static void *file_of(const terrain_stacks *generated, const terrain_stacks *a, terrain_chunk_coord coord,
                     uint64_t key, size_t *size) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key });
    cr_assert(terrain_edit_log_record(log, coord, TERRAIN_EDIT_SET, generated, a));
    char dir[64], path[160];
    core_error error = { 0 };
    snprintf(dir, sizeof dir, "/tmp/terrain_threads_log_XXXXXX");
    cr_assert(mkdtemp(dir));
    cr_assert(terrain_edit_log_save(log, dir, &error), "%s", error.message);
    snprintf(path, sizeof path, "%s/edits/%lld_%lld.tel", dir, (long long)coord.x, (long long)coord.z);
    FILE *f = fopen(path, "rb");
    cr_assert(f);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    void *bytes = malloc(*size);
    cr_assert_eq(fread(bytes, 1, *size, f), *size);
    fclose(f);
    unlink(path);
    snprintf(path, sizeof path, "%s/edits", dir);
    rmdir(path);
    rmdir(dir);
    terrain_edit_log_destroy(log);
    return bytes;
}

Test(terrain_threads, edit_log_replays_on_four_threads_while_one_records) {
    terrain_generation_desc params = terrain_generation_defaults(17);
    terrain_chunk_coord coord = { 1, -2 };
    terrain_stacks *generated = terrain_generate_chunk(&params, coord);
    terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
        .x = coord.x * TERRAIN_CHUNK_COLUMNS, .z = coord.z * TERRAIN_CHUNK_COLUMNS,
        .width = TERRAIN_CHUNK_COLUMNS, .depth = TERRAIN_CHUNK_COLUMNS });
    cr_assert(terrain_columns_load(region, coord, generated));
    for (int n = 0; n < 40; n++) set_column(region, n * 7, 8000 + n, 3);
    terrain_stacks *a = terrain_columns_to_stacks(region, coord);
    for (int n = 20; n < 60; n++) set_column(region, n * 7, 7000 - n, 40);
    terrain_stacks *b = terrain_columns_to_stacks(region, coord);
    terrain_columns_destroy(region);

    uint64_t key = terrain_generation_key(&params);
    log_share share = { .log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = key }), .coord = coord, .generated = generated,
                        .state = { a, b } };
    share.file_a = file_of(generated, a, coord, key, &share.file_a_size);
    cr_assert(terrain_edit_log_record(share.log, coord, TERRAIN_EDIT_SET, generated, a));
    log_replayer replayers[LOG_REPLAYERS];
    pthread_t threads[LOG_REPLAYERS];
    for (int t = 0; t < LOG_REPLAYERS; t++) {
        replayers[t] = (log_replayer){ .share = &share };
        cr_assert_eq(pthread_create(&threads[t], NULL, replay_loop, &replayers[t]), 0);
    }
    record_loop(&share);
    atomic_store(&share.done, true);
    for (int t = 0; t < LOG_REPLAYERS; t++) {
        pthread_join(threads[t], NULL);
        cr_expect_eq(replayers[t].wrong, 0, "thread %d: %d of %d replays gave neither A nor B", t, replayers[t].wrong,
                     replayers[t].replays);
    }
    cr_expect_leq(terrain_edit_log_entries(share.log, coord), 10, "compacted every 10 steps");
    free((void *)share.file_a);
    terrain_edit_log_destroy(share.log);
    terrain_stacks_destroy(b);
    terrain_stacks_destroy(a);
    terrain_stacks_destroy(generated);
}

/* ---- edits committed while workers read (terrain_world_commit) ---- */

typedef struct commit_share {
    terrain_world *world;
    _Atomic bool stop;
    _Atomic long reads;
} commit_share;

/* A background reader: brackets its reads as a streaming job does, and walks every column of
 * the chunk the main thread keeps editing (ASan/TSan catch a freed or racing read). */
static void *commit_reader(void *user) {
    commit_share *s = user;
    terrain_layer layers[64];
    while (!atomic_load(&s->stop)) {
        uint64_t token = terrain_world_read_begin(s->world);
        const terrain_stacks *stacks = terrain_world_stacks(s->world, (terrain_chunk_coord){ 0, 0 });
        long columns = 0;
        for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
            for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) columns += terrain_stacks_column(stacks, i, k, layers, 64) > 0;
        terrain_world_read_end(s->world, token);
        atomic_fetch_add(&s->reads, columns > 0);
    }
    return NULL;
}

Test(terrain_threads, workers_read_while_the_main_thread_commits_and_trims) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = 1 });
    commit_share s = { .world = terrain_world_create(&(terrain_world_desc){
                           .generation = terrain_generation_defaults(11), .edits = log, .max_chunks = 4 }) };
    pthread_t readers[3];
    for (int t = 0; t < 3; t++) pthread_create(&readers[t], NULL, commit_reader, &s);
    for (int stroke = 0; stroke < 40; stroke++) {
        terrain_world_edit(s.world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                     .deposit = { .x = 4 + stroke % 24, .z = 16, .radius = 3,
                                                                  .volume = 2 } }, NULL, 0);
        terrain_world_change changes[8];
        terrain_world_take_changes(s.world, changes, 8);
        terrain_world_trim(s.world);
    }
    atomic_store(&s.stop, true);
    for (int t = 0; t < 3; t++) pthread_join(readers[t], NULL);
    cr_expect_gt(atomic_load(&s.reads), 0);
    cr_expect_eq(terrain_edit_log_entries(log, (terrain_chunk_coord){ 0, 0 }), 40, "every stroke logged");
    terrain_world_destroy(s.world);
    terrain_edit_log_destroy(log);
}

/* ---- generation, commits and eviction interleaved (terrain_world's chunk cache) ----
 * Readers keep asking for three chunks of a world that caches one, so the chunk the main thread
 * edits is evicted and regenerated (from the log) over and over, often by a reader while the
 * main thread commits. Whatever the interleaving, each cached chunk must equal the log's replay
 * over the generated ground, and the edited chunk's version is the stamp of the last commit. */

static void churn_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
}

static terrain_stacks *churn_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, churn_column, user);
}

static void *churn_reader(void *user) {
    commit_share *s = user;
    for (long round = 0; !atomic_load(&s->stop); round++) {
        uint64_t token = terrain_world_read_begin(s->world);
        for (int n = 0; n < 3; n++)
            (void)terrain_stacks_hash(terrain_world_stacks(s->world, (terrain_chunk_coord){ (round + n) % 3, 0 }));
        terrain_world_read_end(s->world, token);
        atomic_fetch_add(&s->reads, 1);
    }
    return NULL;
}

Test(terrain_threads, chunks_regenerated_while_committed_and_evicted_match_the_log) {
    enum { STROKES = 200 };
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = 7 });
    terrain_world_desc desc = { .generation = terrain_generation_defaults(7), .generate = churn_chunk,
                                .edits = log, .max_chunks = 1 };
    commit_share s = { .world = terrain_world_create(&desc) };
    pthread_t readers[3];
    for (int t = 0; t < 3; t++) pthread_create(&readers[t], NULL, churn_reader, &s);
    for (int stroke = 0; stroke < STROKES; stroke++) {
        /* Inside chunk (0, 0) only: x and z stay 4 m from its borders. */
        terrain_world_edit(s.world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                     .deposit = { .x = 4 + stroke % 24, .z = 4 + (stroke * 7) % 24,
                                                                  .radius = 2, .volume = 1 } }, NULL, 0);
        terrain_world_change changes[8];
        terrain_world_take_changes(s.world, changes, 8);
        terrain_world_trim(s.world);
    }
    atomic_store(&s.stop, true);
    for (int t = 0; t < 3; t++) pthread_join(readers[t], NULL);
    cr_expect_gt(atomic_load(&s.reads), 0);
    /* One commit a stroke, all to chunk (0, 0): its version is the last one's stamp. */
    cr_expect_eq(terrain_edit_log_entries(log, (terrain_chunk_coord){ 0, 0 }), STROKES);
    cr_expect_eq(terrain_world_chunk_version(s.world, (terrain_chunk_coord){ 0, 0 }), STROKES);
    terrain_world *fresh = terrain_world_create(&desc);
    for (int x = 0; x < 3; x++) {
        terrain_chunk_coord c = { x, 0 };
        cr_expect(same_stacks(terrain_world_stacks(s.world, c), terrain_world_stacks(fresh, c)),
                  "chunk (%d, 0) equals the log's replay", x);
    }
    terrain_world_destroy(fresh);
    terrain_world_destroy(s.world);
    terrain_edit_log_destroy(log);
}

/* The interleaving itself, forced: a reader has generated chunk (0, 0) from the log as it was,
 * and before it inserts its copy the main thread commits a stroke there and evicts the chunk.
 * The reader's copy lacks the stroke: it must not be the one cached. */
typedef struct late_insert {
    _Atomic int state;                 /* 0 reader generating, 1 reader waits, 2 main done */
    pthread_t reader;
} late_insert;

static void hold_first_copy(void *user, terrain_chunk_coord coord) {
    late_insert *l = user;
    if (coord.x != 0 || coord.z != 0 || !pthread_equal(pthread_self(), l->reader)) return;
    int expected = 0;
    if (!atomic_compare_exchange_strong(&l->state, &expected, 1)) return;   /* only the first copy */
    while (atomic_load(&l->state) != 2) usleep(100);
}

static void *late_reader(void *user) {
    commit_share *s = user;
    uint64_t token = terrain_world_read_begin(s->world);
    (void)terrain_stacks_hash(terrain_world_stacks(s->world, (terrain_chunk_coord){ 0, 0 }));
    terrain_world_read_end(s->world, token);
    return NULL;
}

Test(terrain_threads, a_copy_generated_before_a_commit_and_eviction_is_not_cached) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = 8 });
    terrain_world_desc desc = { .generation = terrain_generation_defaults(8), .generate = churn_chunk,
                                .edits = log };
    commit_share s = { .world = terrain_world_create(&desc) };
    late_insert l = { 0 };
    terrain__world_on_generated(s.world, hold_first_copy, &l);
    cr_assert_eq(pthread_create(&l.reader, NULL, late_reader, &s), 0);
    while (atomic_load(&l.state) != 1) usleep(100);
    terrain_world_edit(s.world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                 .deposit = { .x = 16, .z = 16, .radius = 3, .volume = 4 } }, NULL, 0);
    (void)terrain_world_stacks(s.world, (terrain_chunk_coord){ 1, 0 });   /* (0, 0) the least recent */
    terrain_world_set_max_chunks(s.world, 1);
    terrain_world_trim(s.world);
    cr_assert(!terrain_world_has(s.world, (terrain_chunk_coord){ 0, 0 }), "evicted");
    atomic_store(&l.state, 2);
    pthread_join(l.reader, NULL);
    terrain_world *fresh = terrain_world_create(&desc);
    terrain_chunk_coord c = { 0, 0 };
    cr_expect(same_stacks(terrain_world_stacks(s.world, c), terrain_world_stacks(fresh, c)),
              "the cached chunk holds the stroke");
    terrain_world_destroy(fresh);
    terrain_world_destroy(s.world);
    terrain_edit_log_destroy(log);
}

/* ---- saves in the background while the main thread edits (terrain_store) ---- */

typedef struct store_share {
    terrain_store *store;
    atomic_bool stop;
    int saves, failures;
} store_share;

/* Another thread saving now and then: snapshots must still commit in the order taken. */
static void *store_saver(void *user) {
    store_share *s = user;
    while (!atomic_load(&s->stop)) {
        s->failures += !terrain_store_save(s->store, NULL);
        s->saves++;
        usleep(2000);
    }
    return NULL;
}

/* The game's pattern: strokes committed every frame, an autosave now and then from the frame
 * (a snapshot; the commit on the store's thread), values put between; then the last save and a
 * fresh open that must hold every stroke. TSan watches the log, the values and the hand-over. */
Test(terrain_threads, the_store_saves_in_the_background_while_the_main_thread_edits) {
    char dir[64];
    snprintf(dir, sizeof dir, "/tmp/terrain_threads_store_XXXXXX");
    cr_assert(mkdtemp(dir));
    terrain_generation_desc params = terrain_generation_defaults(11);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
    terrain_store_report report;
    core_error error = { 0 };
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log, .seed = 11 }, &report,
                                                &error);
    cr_assert(store, "%s", error.message);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = params, .edits = log });
    store_share share = { .store = store };
    pthread_t saver;
    cr_assert_eq(pthread_create(&saver, NULL, store_saver, &share), 0);
    int async_saves = 0;
    for (int stroke = 0; stroke < 40; stroke++) {
        terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                   .deposit = { .x = 4 + stroke % 40, .z = 16, .radius = 3,
                                                                .volume = 2 } }, NULL, 0);
        terrain_world_trim(world);
        int frame = stroke;
        terrain_store_put(store, "frame", &frame, sizeof frame);
        if (stroke % 3 == 0) async_saves += terrain_store_save_async(store);
    }
    atomic_store(&share.stop, true);
    pthread_join(saver, NULL);
    cr_expect_eq(share.failures, 0, "of %d saves on the other thread", share.saves);
    cr_expect(terrain_store_save(store, &error), "%s", error.message);
    cr_expect_gt(async_saves, 0);
    uint64_t hash = terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 }));
    uint64_t hash_east = terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 1, 0 }));
    terrain_world_destroy(world);
    terrain_store_destroy(store);

    terrain_edit_log *again = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
    store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = again }, &report, &error);
    cr_assert(store, "%s", error.message);
    world = terrain_world_create(&(terrain_world_desc){ .generation = params, .edits = again });
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 })), hash);
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 1, 0 })), hash_east);
    int frame = -1;
    cr_expect_eq(terrain_store_get(store, "frame", &frame, sizeof frame), (int64_t)sizeof frame);
    cr_expect_eq(frame, 39);
    terrain_world_destroy(world);
    terrain_store_destroy(store);
    terrain_edit_log_destroy(again);
    terrain_edit_log_destroy(log);
    char command[128];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    cr_expect_eq(system(command), 0);
}
