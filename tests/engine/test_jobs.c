/* Tests of the job system (engine/jobs). Also built under ThreadSanitizer by tools/test. */
#include "core/core.h"
#include "jobs/jobs.h"

#include "test.h"
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

/* ---- dependency order ------------------------------------------------------------------ */

typedef struct order_log {
    _Atomic int next;
    int position[16]; /* position[job] = when it finished */
} order_log;

typedef struct logged_job {
    order_log *log;
    int id;
} logged_job;

static void log_finish(void *arg) {
    logged_job *job = arg;
    job->log->position[job->id] = atomic_fetch_add(&job->log->next, 1);
}

Test(job_system, chain_runs_in_dependency_order) {
    for (int threads = 1; threads <= 4; threads++) {
        job_system *jobs = job_system_create(&(job_system_desc){ .threads = threads });
        order_log log = { 0 };
        logged_job items[8];
        job_handle previous = { 0, 0 };
        for (int i = 0; i < 8; i++) {
            items[i] = (logged_job){ &log, i };
            previous = job_submit(jobs, &(job_desc){ .fn = log_finish, .user = &items[i], .after = &previous,
                                                    .after_count = 1 });
        }
        job_wait(jobs, previous);
        for (int i = 0; i < 8; i++) cr_expect_eq(log.position[i], i, "threads %d: job %d ran %d-th", threads, i, log.position[i]);
        job_system_destroy(jobs);
    }
}

Test(job_system, diamond_joins_after_both_branches) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    for (int round = 0; round < 200; round++) {
        order_log log = { 0 };
        logged_job items[4] = { { &log, 0 }, { &log, 1 }, { &log, 2 }, { &log, 3 } };
        job_handle top = job_submit(jobs, &(job_desc){ .fn = log_finish, .user = &items[0] });
        job_handle left = job_submit(jobs, &(job_desc){ .fn = log_finish, .user = &items[1], .after = &top, .after_count = 1 });
        job_handle right = job_submit(jobs, &(job_desc){ .fn = log_finish, .user = &items[2], .after = &top, .after_count = 1 });
        job_handle both[2] = { left, right };
        job_handle bottom = job_submit(jobs, &(job_desc){ .fn = log_finish, .user = &items[3], .after = both, .after_count = 2 });
        job_wait(jobs, bottom);
        cr_assert_eq(log.position[0], 0);
        cr_assert_eq(log.position[3], 3);
    }
    job_system_destroy(jobs);
}

/* ---- stress ----------------------------------------------------------------------------- */

enum { STRESS_JOBS = 1000000, STRESS_MAX_DEPS = 3, STRESS_WINDOW = 64 };

typedef struct stress_state {
    _Atomic int64_t clock;
    int64_t *finished_at;      /* per job; 0 = not run */
    _Atomic int *runs;         /* per job: must end at exactly 1 */
} stress_state;

typedef struct stress_job {
    stress_state *state;
    int id;
} stress_job;

static void stress_run(void *arg) {
    stress_job *job = arg;
    atomic_fetch_add(&job->state->runs[job->id], 1);
    job->state->finished_at[job->id] = atomic_fetch_add(&job->state->clock, 1) + 1;
}

Test(job_system, million_jobs_with_random_dependencies, .timeout = 240) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    stress_state state = { 0 };
    state.finished_at = calloc(STRESS_JOBS, sizeof *state.finished_at);
    state.runs = calloc(STRESS_JOBS, sizeof *state.runs);
    stress_job *items = calloc(STRESS_JOBS, sizeof *items);
    job_handle *handles = calloc(STRESS_JOBS, sizeof *handles);
    int (*deps)[STRESS_MAX_DEPS] = calloc(STRESS_JOBS, sizeof *deps);
    int *dep_count = calloc(STRESS_JOBS, sizeof *dep_count);
    uint64_t random = 12345;

    for (int i = 0; i < STRESS_JOBS; i++) {
        job_handle after[STRESS_MAX_DEPS];
        random = core_hash_u64(random + (uint64_t)i);
        int want = i == 0 ? 0 : (int)(random % (STRESS_MAX_DEPS + 1));
        for (int d = 0; d < want; d++) {
            /* Recent jobs, so that many dependencies are still unfinished when added. */
            int window = i < STRESS_WINDOW ? i : STRESS_WINDOW;
            int before = i - 1 - (int)((random >> (16 + 8 * d)) % (uint64_t)window);
            deps[i][dep_count[i]] = before;
            after[dep_count[i]++] = handles[before];
        }
        items[i] = (stress_job){ &state, i };
        handles[i] = job_submit(jobs, &(job_desc){ .fn = stress_run, .user = &items[i], .after = after,
                                                  .after_count = dep_count[i] });
    }
    job_wait_all(jobs);

    int wrong_runs = 0, wrong_order = 0;
    for (int i = 0; i < STRESS_JOBS; i++) {
        wrong_runs += atomic_load(&state.runs[i]) != 1;
        for (int d = 0; d < dep_count[i]; d++) wrong_order += state.finished_at[deps[i][d]] >= state.finished_at[i];
    }
    cr_expect_eq(wrong_runs, 0, "%d jobs did not run exactly once", wrong_runs);
    cr_expect_eq(wrong_order, 0, "%d jobs ran before a dependency", wrong_order);
    job_system_stats_info stats = job_system_stats(jobs);
    cr_expect_eq(stats.submitted, (uint64_t)STRESS_JOBS);
    cr_expect_eq(stats.completed, (uint64_t)STRESS_JOBS);
    job_system_destroy(jobs);
    free(state.finished_at); free(state.runs); free(items); free(handles); free(deps); free(dep_count);
}

/* ---- parallel loops --------------------------------------------------------------------- */

typedef struct coverage {
    _Atomic int *visits;
} coverage;

static void visit_range(void *arg, size_t begin, size_t end) {
    coverage *c = arg;
    cr_assert_lt(begin, end);
    for (size_t i = begin; i < end; i++) atomic_fetch_add(&c->visits[i], 1);
}

Test(job_system, parallel_for_visits_every_index_once) {
    const size_t counts[] = { 1, 2, 7, 64, 1000, 100003 };
    const size_t batches[] = { 0, 1, 3, 64, 5000 };
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    for (size_t c = 0; c < CORE_COUNTOF(counts); c++) {
        for (size_t b = 0; b < CORE_COUNTOF(batches); b++) {
            coverage cov = { calloc(counts[c], sizeof(_Atomic int)) };
            job_parallel_for(jobs, counts[c], batches[b], visit_range, &cov, "visit");
            for (size_t i = 0; i < counts[c]; i++)
                cr_assert_eq(atomic_load(&cov.visits[i]), 1, "count %zu batch %zu: index %zu visited %d times",
                             counts[c], batches[b], i, atomic_load(&cov.visits[i]));
            free(cov.visits);
        }
    }
    job_parallel_for(jobs, 0, 0, visit_range, NULL, "empty"); /* nothing to do, returns at once */
    job_system_destroy(jobs);
}

/* ---- main-thread jobs ------------------------------------------------------------------- */

typedef struct pinned {
    job_system *jobs;
    _Atomic int ran_on_main, ran_elsewhere;
    job_handle inner;
} pinned;

static void record_thread(void *arg) {
    pinned *p = arg;
    if (job_thread_index(p->jobs) == 0) atomic_fetch_add(&p->ran_on_main, 1);
    else atomic_fetch_add(&p->ran_elsewhere, 1);
}

static void submit_pinned_from_worker(void *arg) {
    pinned *p = arg;
    for (int i = 0; i < 10; i++) job_submit(p->jobs, &(job_desc){ .fn = record_thread, .user = p, .main_thread = true });
}

Test(job_system, main_thread_jobs_run_on_the_main_thread) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    pinned p = { .jobs = jobs };
    job_handle spawner = job_submit(jobs, &(job_desc){ .fn = submit_pinned_from_worker, .user = &p });
    for (int i = 0; i < 10; i++) job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p, .main_thread = true });
    job_wait(jobs, spawner);
    job_wait_all(jobs);
    cr_expect_eq(atomic_load(&p.ran_on_main), 20);
    cr_expect_eq(atomic_load(&p.ran_elsewhere), 0);
    job_system_destroy(jobs);
}

Test(job_system, run_main_thread_jobs_drains_the_pinned_queue) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    pinned p = { .jobs = jobs };
    for (int i = 0; i < 5; i++) job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p, .main_thread = true });
    cr_expect_eq(job_run_main_thread_jobs(jobs), 5);
    cr_expect_eq(atomic_load(&p.ran_on_main), 5);
    job_system_destroy(jobs);
}

/* ---- waiting ---------------------------------------------------------------------------- */

static void count_main_thread_work(void *arg) {
    pinned *p = arg;
    record_thread(p);
    struct timespec pause = { 0, 100000 }; /* 0.1 ms: long enough for both threads to take some */
    nanosleep(&pause, NULL);
}

Test(job_system, wait_runs_other_jobs_instead_of_blocking) {
    /* One thread: nobody else could run the jobs, so finishing proves the wait runs them. */
    job_system *alone = job_system_create(&(job_system_desc){ .threads = 1 });
    pinned p = { .jobs = alone };
    job_handle last = { 0, 0 };
    for (int i = 0; i < 100; i++) last = job_submit(alone, &(job_desc){ .fn = record_thread, .user = &p, .after = &last, .after_count = 1 });
    job_wait(alone, last);
    cr_expect_eq(atomic_load(&p.ran_on_main), 100);
    job_system_destroy(alone);

    /* Two threads: the waiting main thread takes a share of independent work. */
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    pinned q = { .jobs = jobs };
    job_handle parts[200];
    for (int i = 0; i < 200; i++) parts[i] = job_submit(jobs, &(job_desc){ .fn = count_main_thread_work, .user = &q });
    job_handle join = job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &q, .after = parts, .after_count = 200 });
    job_wait(jobs, join);
    cr_expect_gt(atomic_load(&q.ran_on_main), 0, "the main thread ran none of the jobs it waited for");
    cr_expect_gt(atomic_load(&q.ran_elsewhere), 0, "the worker ran none of the jobs");
    job_system_destroy(jobs);
}

Test(job_system, stale_and_zero_handles_read_as_done) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    pinned p = { .jobs = jobs };
    job_handle first = job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p });
    job_wait(jobs, first);
    /* Reuse the slot many times over; the old handle must still read as done, never as the
     * new job that took its slot. */
    for (int i = 0; i < 1000; i++) job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p });
    cr_expect(job_is_done(jobs, first));
    job_wait(jobs, first);
    cr_expect(job_is_done(jobs, (job_handle){ 0, 0 }));
    job_wait_all(jobs);
    job_system_destroy(jobs);
}

/* ---- idle, growth, shutdown ------------------------------------------------------------- */

static double process_cpu_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

Test(job_system, idle_workers_sleep) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 4 });
    pinned p = { .jobs = jobs };
    for (int i = 0; i < 1000; i++) job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p });
    job_wait_all(jobs);
    usleep(20000); /* let the workers finish spinning and go to sleep */
    double before = process_cpu_ms();
    usleep(300000);
    double used = process_cpu_ms() - before;
    /* Busy workers would burn ~900 ms of CPU here (3 workers × 300 ms). */
    cr_expect_lt(used, 30.0, "idle job system used %.1f ms of CPU in 300 ms", used);
    job_system_destroy(jobs);
}

Test(job_system, queues_grow_instead_of_dropping_jobs) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 1 });
    pinned p = { .jobs = jobs };
    for (int i = 0; i < 100000; i++) job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p });
    cr_expect_eq(job_system_stats(jobs).queued, 100000);
    job_wait_all(jobs);
    cr_expect_eq(atomic_load(&p.ran_on_main), 100000);
    job_system_destroy(jobs);
}

Test(job_system, destroy_runs_what_is_still_queued) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 3 });
    pinned p = { .jobs = jobs };
    for (int i = 0; i < 5000; i++) job_submit(jobs, &(job_desc){ .fn = record_thread, .user = &p, .main_thread = (i % 10) == 0 });
    job_system_destroy(jobs);
    cr_expect_eq(atomic_load(&p.ran_on_main) + atomic_load(&p.ran_elsewhere), 5000);
}

Test(job_system, thread_indices) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 3 });
    cr_expect_eq(job_thread_count(jobs), 3);
    cr_expect_eq(job_thread_index(jobs), 0);
    job_system_destroy(jobs);
}

/* ---- background jobs ------------------------------------------------------------------- */

typedef struct background_probe {
    _Atomic int ran_on_main, ran_on_worker, ran;
    job_system *jobs;
} background_probe;

static void background_job(void *arg) {
    background_probe *probe = arg;
    if (job_thread_index(probe->jobs) == 0) atomic_fetch_add(&probe->ran_on_main, 1);
    else atomic_fetch_add(&probe->ran_on_worker, 1);
    atomic_fetch_add(&probe->ran, 1);
}

static void noop_range(void *user, size_t begin, size_t end) {
    (void)user, (void)begin, (void)end;
}

/* A frame that waits for its own parallel loop must never run queued background work on the
 * main thread: that is the whole point of the flag. */
Test(job_system, background_jobs_never_run_inside_a_main_thread_wait) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    background_probe probe = { .jobs = jobs };
    job_handle last = { 0, 0 };
    for (int i = 0; i < 64; i++)
        last = job_submit(jobs, &(job_desc){ .fn = background_job, .user = &probe, .background = true });
    for (int frame = 0; frame < 50; frame++) job_parallel_for(jobs, 256, 8, noop_range, NULL, "frame");
    job_wait(jobs, last);                       /* waits without running it: a worker does */
    job_wait_all(jobs);
    cr_expect_eq(atomic_load(&probe.ran), 64);
    cr_expect_eq(atomic_load(&probe.ran_on_main), 0, "%d background jobs ran on the main thread",
                 atomic_load(&probe.ran_on_main));
    job_system_destroy(jobs);
}

/* With no workers the main thread is the only one that can run them: in job_help, and in a
 * wait that cannot finish otherwise (no deadlock). */
Test(job_system, background_jobs_run_on_a_lone_main_thread) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 1 });
    background_probe probe = { .jobs = jobs };
    for (int i = 0; i < 3; i++) job_submit(jobs, &(job_desc){ .fn = background_job, .user = &probe, .background = true });
    job_parallel_for(jobs, 64, 8, noop_range, NULL, "frame");
    cr_expect_eq(atomic_load(&probe.ran), 0, "a wait with other work done must not run background jobs");
    cr_expect_eq(job_help(jobs, 1000000000ull), 3);
    cr_expect_eq(atomic_load(&probe.ran), 3);
    job_handle more = job_submit(jobs, &(job_desc){ .fn = background_job, .user = &probe, .background = true });
    job_wait(jobs, more);
    cr_expect_eq(atomic_load(&probe.ran), 4);
    job_submit(jobs, &(job_desc){ .fn = background_job, .user = &probe, .background = true });
    job_system_destroy(jobs);                   /* runs what is still queued */
    cr_expect_eq(atomic_load(&probe.ran), 5);
}

/* Oldest first: submitted in priority order, they start in that order on a single worker. */
typedef struct fifo_probe {
    _Atomic int next;
    int order[32];
} fifo_probe;

typedef struct fifo_item {
    fifo_probe *probe;
    int id;
} fifo_item;

static void fifo_job(void *arg) {
    fifo_item *item = arg;
    item->probe->order[item->id] = atomic_fetch_add(&item->probe->next, 1);
}

Test(job_system, background_jobs_start_oldest_first) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    fifo_probe probe = { 0 };
    fifo_item items[32];
    for (int i = 0; i < 32; i++) {
        items[i] = (fifo_item){ &probe, i };
        job_submit(jobs, &(job_desc){ .fn = fifo_job, .user = &items[i], .background = true });
    }
    job_wait_all(jobs);
    for (int i = 0; i < 32; i++) cr_expect_eq(probe.order[i], i, "job %d ran %d-th", i, probe.order[i]);
    job_system_destroy(jobs);
}

/* ---- children of background jobs -------------------------------------------------------- */

typedef struct parent_probe {
    job_system *jobs;
    _Atomic int child_thread;       /* job_thread_index where the child ran; -2 until it ran */
    _Atomic bool child_submitted;
    job_handle child;
} parent_probe;

static void child_job(void *user) {
    parent_probe *probe = user;
    atomic_store(&probe->child_thread, job_thread_index(probe->jobs));
}

/* Submits a child, then holds the worker long enough for a main thread that steals normal jobs
 * to have taken the child, had it not been background. */
static void parent_job(void *user) {
    parent_probe *probe = user;
    probe->child = job_submit(probe->jobs, &(job_desc){ .fn = child_job, .user = probe, .name = "child" });
    atomic_store(&probe->child_submitted, true);
    usleep(50 * 1000);
}

/* A background job's children are background too: a main thread waiting for them never runs
 * them (jobs.h), a worker does once the parent is done. */
Test(job_system, children_of_background_jobs_are_background) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    parent_probe probe = { .jobs = jobs, .child_thread = -2 };
    job_handle parent = job_submit(jobs, &(job_desc){ .fn = parent_job, .user = &probe, .background = true });
    while (!atomic_load(&probe.child_submitted)) usleep(100);
    job_wait(jobs, probe.child);  /* steals normal jobs from the worker's queue while it waits */
    job_wait(jobs, parent);
    cr_expect_eq(atomic_load(&probe.child_thread), 1, "the child ran on thread %d, not the worker",
                 atomic_load(&probe.child_thread));
    job_system_destroy(jobs);
}

/* ---- workers do not preempt on wake-up -------------------------------------------------- */

static void record_policy(void *user) { atomic_store((_Atomic int *)user, sched_getscheduler(0)); }

/* Workers run under SCHED_BATCH (jobs.c, worker_yield_on_wake): a woken worker waits for the
 * running thread's turn instead of preempting the main thread that handed it the job. The main
 * thread's own policy is left as it was. */
Test(job_system, workers_do_not_preempt_the_thread_that_wakes_them) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    _Atomic int policy = -1;
    /* Background: the main thread never runs it while it waits, so the worker does. */
    job_wait(jobs, job_submit(jobs, &(job_desc){ .fn = record_policy, .user = &policy, .background = true }));
    cr_expect_eq(atomic_load(&policy), SCHED_BATCH, "a worker ran under policy %d", atomic_load(&policy));
    cr_expect_eq(sched_getscheduler(0), SCHED_OTHER, "the main thread's policy changed");
    job_system_destroy(jobs);
}
