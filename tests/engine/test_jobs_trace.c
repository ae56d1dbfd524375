/* What the job system shows in a trace (engine/jobs, jobs.h TRACES): "wait" zones while a
 * thread waits, "sleep" zones while one sleeps, and the per-frame jobs.* counters. Captures are
 * read back with core_json. Also built under ThreadSanitizer (test_threads). */
#include "core/core.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include "test.h"
#include "trace_file.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct jobs_capture {
    core_arena arena;
    core_json_value *root;
    const core_json_value *events;
} jobs_capture;

static void jobs_capture_load(jobs_capture *c, const char *path) {
    *c = (jobs_capture){ 0 };
    c->events = trace_file_load(path, &c->arena, &c->root);
}

static const core_json_value *jobs_event(const jobs_capture *c, size_t i) { return &c->events->array.items[i]; }
static bool jobs_event_is(const core_json_value *e, const char *ph) {
    return core_json_string_equals(core_json_get(e, "ph"), ph);
}
static bool jobs_event_named(const core_json_value *e, const char *name) {
    return core_json_string_equals(core_json_get(e, "name"), name);
}
static double jobs_tid(const core_json_value *e) { return core_json_number_or(core_json_get(e, "tid"), NAN); }

static double jobs_tid_named(const jobs_capture *c, const char *name) {
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = jobs_event(c, i);
        if (jobs_event_is(e, "M") && jobs_event_named(e, "thread_name") &&
            core_json_string_equals(core_json_get(core_json_get(e, "args"), "name"), name))
            return jobs_tid(e);
    }
    return -1;
}

static size_t jobs_count_zones(const jobs_capture *c, const char *name, double tid) {
    size_t n = 0;
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = jobs_event(c, i);
        n += jobs_event_is(e, "B") && jobs_event_named(e, name) && (tid < 0 || jobs_tid(e) == tid);
    }
    return n;
}

static void slow_job(void *user) {
    (void)user;
    usleep(2000);
}

/* The main thread waits on slow jobs: each wait is a "wait" zone on its lane, and every job it
 * runs meanwhile nests inside one. An idle worker's sleep is a "sleep" zone on its lane. */
Test(job_trace, waits_and_sleeps_are_zones) {
    char path[128];
    snprintf(path, sizeof path, "/tmp/engine_test_jobs_trace_%d_wait.json", (int)getpid());
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    cr_assert(trace_start(path));
    trace_thread_name("main");
    enum { FRAMES = 4, SLOW = 4 };
    for (int frame = 0; frame < FRAMES; frame++) {
        trace_frame_begin();
        job_handle last = { 0, 0 };
        for (int i = 0; i < SLOW; i++) last = job_submit(jobs, &(job_desc){ .fn = slow_job, .name = "slow" });
        job_wait(jobs, last);
        job_wait_all(jobs);
        trace_frame_end();
        usleep(5000); /* long past the worker's spinning: it sleeps */
    }
    job_system_destroy(jobs);
    trace_stop();

    jobs_capture c;
    jobs_capture_load(&c, path);
    double main_tid = jobs_tid_named(&c, "main"), worker_tid = jobs_tid_named(&c, "worker 1");
    cr_assert_gt(main_tid, 0);
    cr_assert_gt(worker_tid, 0);
    cr_expect_geq(jobs_count_zones(&c, "wait", main_tid), (size_t)FRAMES, "a wait zone per frame at least");
    cr_expect_eq(jobs_count_zones(&c, "slow", -1), (size_t)(FRAMES * SLOW));
    cr_expect_geq(jobs_count_zones(&c, "sleep", worker_tid), (size_t)FRAMES - 1, "the worker slept between frames");
    /* On the main lane a job only ever runs inside a wait (depth of open "wait" zones). */
    int stack_wait[64], depth = 0, waits_open = 0;
    for (size_t i = 0; i < c.events->array.count; i++) {
        const core_json_value *e = jobs_event(&c, i);
        if (jobs_tid(e) != main_tid) continue;
        if (jobs_event_is(e, "B")) {
            cr_assert_lt(depth, 64);
            bool is_wait = jobs_event_named(e, "wait");
            if (jobs_event_named(e, "slow")) cr_expect_gt(waits_open, 0, "event %zu: a job on the main lane outside a wait", i);
            stack_wait[depth++] = is_wait;
            waits_open += is_wait;
        } else if (jobs_event_is(e, "E")) {
            cr_assert_gt(depth, 0);
            waits_open -= stack_wait[--depth];
        }
    }
    core_arena_release(&c.arena);
}

/* Each frame runs exactly JOBS jobs and waits for all of them: jobs.run reads JOBS every frame
 * and jobs.queued 0; the other counters are there, each once a frame. */
Test(job_trace, counters_once_a_frame) {
    char path[128];
    snprintf(path, sizeof path, "/tmp/engine_test_jobs_trace_%d_counters.json", (int)getpid());
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 3 });
    cr_assert(trace_start(path));
    enum { FRAMES = 5, JOBS = 37 };
    for (int frame = 0; frame < FRAMES; frame++) {
        trace_frame_begin();
        for (int i = 0; i < JOBS; i++) job_submit(jobs, &(job_desc){ .fn = slow_job, .name = "slow" });
        job_wait_all(jobs);
        job_system_trace_counters(jobs);
        trace_frame_end();
    }
    job_system_destroy(jobs);
    trace_stop();

    jobs_capture c;
    jobs_capture_load(&c, path);
    const char *names[] = { "jobs.run", "jobs.stolen", "jobs.sleeps", "jobs.wakes", "jobs.queued" };
    for (size_t n = 0; n < sizeof names / sizeof *names; n++) {
        size_t seen = 0;
        for (size_t i = 0; i < c.events->array.count; i++) {
            const core_json_value *e = jobs_event(&c, i);
            if (!jobs_event_is(e, "C") || !jobs_event_named(e, names[n])) continue;
            double value = core_json_number_or(core_json_get(core_json_get(e, "args"), "value"), NAN);
            cr_expect_geq(value, 0, "%s = %g", names[n], value);
            if (n == 0) cr_expect(value == JOBS, "jobs.run = %g in a frame of %d jobs", value, JOBS);
            if (n == 4) cr_expect(value == 0, "jobs.queued = %g after job_wait_all", value);
            seen++;
        }
        cr_expect_eq(seen, (size_t)FRAMES, "%s: %zu events", names[n], seen);
    }
    core_arena_release(&c.arena);
}
