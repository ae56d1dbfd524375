/* jobs_basics — the job system's three ways of running work (engine/jobs/jobs.h):
 *
 *   1. jobs with dependencies: "load" → two "mesh" jobs → "upload" on the main thread, a small
 *      graph where each job starts once the jobs in its `after` list are done;
 *   2. job_parallel_for: a sum over a million numbers split into ranges on every thread;
 *   3. a background job: long work that no frame waits for, polled with job_is_done while the
 *      main thread goes on with its frames.
 *
 *   jobs_basics [--count N] [--threads N] [--trace FILE]
 *
 * With --trace, every job shows as a zone named after it (open the file in ui.perfetto.dev).
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

/* ---- 1. dependencies -------------------------------------------------------------------- */

/* Each job appends its name to a log, so the order they ran in can be printed. */
typedef struct graph {
    const char *log[4];
    atomic_int logged;
    int chunk[4];                 /* what "load" fills and the "mesh" jobs read */
} graph;

static void record(graph *g, const char *name) { g->log[atomic_fetch_add(&g->logged, 1)] = name; }

static void load(void *user) {
    graph *g = user;
    for (int i = 0; i < 4; i++) g->chunk[i] = i + 1;
    record(g, "load");
}
static void mesh_a(void *user) { record(user, "mesh"); }
static void mesh_b(void *user) { record(user, "mesh"); }
static void upload(void *user) { record(user, "upload"); }   /* a main-thread job: OpenGL goes here */

/* ---- 2. a parallel loop ----------------------------------------------------------------- */

typedef struct sum { const int *values; atomic_llong total; atomic_int ranges; } sum;

static void sum_range(void *user, size_t begin, size_t end) {
    sum *s = user;
    long long part = 0;                            /* summed alone, added once: no contention */
    for (size_t i = begin; i < end; i++) part += s->values[i];
    atomic_fetch_add(&s->total, part);
    atomic_fetch_add(&s->ranges, 1);
}

/* ---- 3. a background job ---------------------------------------------------------------- */

typedef struct slow_work { int steps; uint64_t result; } slow_work;

static void slow(void *user) {                     /* stands for generating a far chunk */
    slow_work *w = user;
    uint64_t h = 0;
    for (int i = 0; i < w->steps; i++) h = core_hash_u64(h + (uint64_t)i);
    w->result = h;
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    int count = 1000000;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "count", CORE_OPTION_INT, &count, "N", "numbers the parallel loop sums (default 1000000)", 1, 100000000 },
    };
    core_cli cli = { .program = "jobs_basics", .summary = "jobs with dependencies, a parallel loop, a background job",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });

    /* 1. load, then both meshes (in parallel), then upload on the main thread. */
    graph g = { 0 };
    job_handle loaded = job_submit(jobs, &(job_desc){ .fn = load, .user = &g, .name = "load" });
    job_handle meshed[2] = {
        job_submit(jobs, &(job_desc){ .fn = mesh_a, .user = &g, .name = "mesh", .after = &loaded, .after_count = 1 }),
        job_submit(jobs, &(job_desc){ .fn = mesh_b, .user = &g, .name = "mesh", .after = &loaded, .after_count = 1 }),
    };
    job_handle uploaded = job_submit(jobs, &(job_desc){ .fn = upload, .user = &g, .name = "upload",
                                                        .after = meshed, .after_count = 2, .main_thread = true });
    job_wait(jobs, uploaded);                      /* runs other jobs meanwhile, never just blocks */
    printf("jobs_basics: graph ran %s, %s, %s, %s\n", g.log[0], g.log[1], g.log[2], g.log[3]);

    /* 2. The numbers 1 … count, summed on every thread. */
    int *values = malloc(sizeof(int) * (size_t)count);
    if (!values) return 1;
    for (int i = 0; i < count; i++) values[i] = i + 1;
    sum s = { .values = values };
    job_parallel_for(jobs, (size_t)count, 0, sum_range, &s, "sum");   /* batch 0 = automatic */
    long long expected = (long long)count * (count + 1) / 2;
    printf("jobs_basics: parallel_for summed %d numbers to %lld (%s) in %d ranges on %d threads\n", count,
           (long long)s.total, s.total == expected ? "right" : "WRONG", (int)s.ranges, job_thread_count(jobs));
    free(values);

    /* 3. A background job, and frames that go on without waiting for it. */
    slow_work work = { .steps = 2000000 };
    job_handle background = job_submit(jobs, &(job_desc){ .fn = slow, .user = &work, .name = "slow",
                                                          .background = true });
    int frames = 0;
    while (!job_is_done(jobs, background)) {
        trace_frame_begin();
        frames++;
        nanosleep(&(struct timespec){ 0, 1000000 }, NULL);   /* stands for a frame's own work */
        if (job_thread_count(jobs) == 1) job_help(jobs, 1000000);   /* no worker: lend a hand */
        trace_frame_end();
    }
    printf("jobs_basics: background job done, result %016llx; the main thread ran %d frames meanwhile\n",
           (unsigned long long)work.result, frames);

    job_system_stats_info stats = job_system_stats(jobs);
    printf("jobs_basics: %llu jobs run\n", (unsigned long long)stats.completed);
    job_system_destroy(jobs);
    trace_stop();
    return 0;
}

/* Expected output:
 * Run: --count 100000 --threads 2
 * ^jobs_basics: graph ran load, mesh, mesh, upload$
 * ^jobs_basics: parallel_for summed 100000 numbers to 5000050000 \(right\) in [0-9]+ ranges on 2 threads$
 * ^jobs_basics: background job done, result 31a43cb35ccab8f1; the main thread ran [0-9]+ frames meanwhile$
 * ^jobs_basics: [0-9]+ jobs run$
 */
