/* bench_jobs.c — job-system rows: the cost of one job, and parallel loops beside OpenMP. */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

/* ---- jobs.empty ------------------------------------------------------------------------- */

enum { EMPTY_JOBS = 200000 };

static void empty_job(void *user) { (void)user; }

static double sample_empty_jobs(void *user) {
    job_system *jobs = user;
    uint64_t start = core_time_ns();
    for (int i = 0; i < EMPTY_JOBS; i++) job_submit(jobs, &(job_desc){ .fn = empty_job });
    job_wait_all(jobs);
    return (double)(core_time_ns() - start) / EMPTY_JOBS;
}

/* ---- jobs.wake_latency ------------------------------------------------------------------ */

/* From a submit to a sleeping worker to that job starting: what a frame pays when it hands work
 * to an idle engine. The main thread does not wait with job_wait (it would run the job itself);
 * it spins on the start time the job writes, and only then collects the handle. */
enum { WAKE_RUNS = 101, WAKE_IDLE_US = 3000 };

typedef struct wake_probe {
    _Atomic uint64_t started_ns;
} wake_probe;

static void note_start(void *user) {
    wake_probe *probe = user;
    atomic_store_explicit(&probe->started_ns, core_time_ns(), memory_order_release);
}

static double sample_wake_latency(void *user) {
    job_system *jobs = user;
    wake_probe probe = { 0 };
    usleep(WAKE_IDLE_US); /* long past a worker's spinning (~0.3 ms): every worker sleeps */
    uint64_t submitted = core_time_ns();
    job_handle job = job_submit(jobs, &(job_desc){ .fn = note_start, .user = &probe, .name = "bench.wake" });
    uint64_t started;
    while ((started = atomic_load_explicit(&probe.started_ns, memory_order_acquire)) == 0) { }
    job_wait(jobs, job);
    return (double)(started - submitted) * 1e-3;
}

/* ---- parallel loops --------------------------------------------------------------------- */

enum { LOOP_COUNT = 1 << 20, LOOP_ROUNDS = 24 };

typedef struct loop_state {
    job_system *jobs;
    float *out;
} loop_state;

/* Compute-bound: a few dozen dependent multiply-adds and a square root per element and one
 * store, so the loop measures scheduling, not memory bandwidth. */
static inline float loop_kernel(size_t i) {
    float x = (float)(i & 1023) * (1.0f / 1024.0f);
    for (int r = 0; r < LOOP_ROUNDS; r++) x = sqrtf(x * x * 0.75f + 0.25f) * 0.999f + 0.0001f * (float)r;
    return x;
}

static void loop_range(void *user, size_t begin, size_t end) {
    loop_state *state = user;
    for (size_t i = begin; i < end; i++) state->out[i] = loop_kernel(i);
}

static double sample_parallel_for(void *user) {
    loop_state *state = user;
    uint64_t start = core_time_ns();
    job_parallel_for(state->jobs, LOOP_COUNT, 0, loop_range, state, "bench.loop");
    return core_ns_to_ms(core_time_ns() - start);
}

static double sample_openmp(void *user) {
    loop_state *state = user;
    float *out = state->out;
    uint64_t start = core_time_ns();
#pragma omp parallel for schedule(static)
    for (long i = 0; i < LOOP_COUNT; i++) out[i] = loop_kernel((size_t)i);
    return core_ns_to_ms(core_time_ns() - start);
}

enum { LOOP_RUNS = 11 };

static void measure(double *samples, double (*fn)(void *), void *user) {
    bench_consume(fn(user));
    for (int i = 0; i < LOOP_RUNS; i++) samples[i] = fn(user);
}

static void bench_parallel_loops(bench_context *ctx) {
    if (!bench_wants(ctx, "jobs.parallel_for")) return;
    int threads = bench_threads(ctx);
    loop_state one = { job_system_create(&(job_system_desc){ .threads = 1 }), malloc(LOOP_COUNT * sizeof(float)) };
    loop_state all = { job_system_create(&(job_system_desc){ .threads = threads }), one.out };
    omp_set_num_threads(threads);

    /* Interleave the three so that a disturbance on the machine hits all of them alike. */
    double t_one[LOOP_RUNS], t_all[LOOP_RUNS], t_omp[LOOP_RUNS];
    measure(t_one, sample_parallel_for, &one);
    measure(t_all, sample_parallel_for, &all);
    measure(t_omp, sample_openmp, &all);
    double speedup[LOOP_RUNS], vs_openmp[LOOP_RUNS];
    for (int i = 0; i < LOOP_RUNS; i++) {
        speedup[i] = t_one[i] / t_all[i];
        vs_openmp[i] = t_all[i] / t_omp[i];
    }
    bench_record(ctx, "jobs.parallel_for.1thread", "ms", t_one, LOOP_RUNS);
    bench_record(ctx, "jobs.parallel_for.all", "ms", t_all, LOOP_RUNS);
    bench_record(ctx, "jobs.parallel_for.openmp", "ms", t_omp, LOOP_RUNS);
    bench_record(ctx, "jobs.parallel_for.speedup", "x", speedup, LOOP_RUNS);
    bench_record(ctx, "jobs.parallel_for.vs_openmp", "ratio", vs_openmp, LOOP_RUNS);
    job_system_destroy(one.jobs);
    job_system_destroy(all.jobs);
    free(one.out);
}

void bench_group_jobs(bench_context *ctx) {
    if (bench_wants(ctx, "jobs.empty")) {
        job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
        bench_run(ctx, "jobs.empty", "ns", 11, sample_empty_jobs, jobs);
        job_system_destroy(jobs);
    }
    if (bench_wants(ctx, "jobs.wake_latency")) {
        /* At least one worker, whatever --threads says: the row is about waking one. */
        int threads = bench_threads(ctx) > 1 ? bench_threads(ctx) : 2;
        job_system *jobs = job_system_create(&(job_system_desc){ .threads = threads });
        bench_run(ctx, "jobs.wake_latency", "us", WAKE_RUNS, sample_wake_latency, jobs);
        job_system_destroy(jobs);
    }
    bench_parallel_loops(ctx);
}
