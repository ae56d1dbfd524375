/* jobs.h — the job system: a pool of worker threads that run small functions (jobs) with
 * dependencies, parallel loops, and jobs pinned to the main thread.
 *
 * SETUP
 *     job_system *jobs = job_system_create(&(job_system_desc){ .threads = 0 }); // 0 = cores
 *     ...
 *     job_system_destroy(jobs);     // runs what is still queued, then joins the workers
 *
 *   `threads` counts the calling (main) thread: threads = 2 starts one worker, and the main
 *   thread works too whenever it waits. With threads = 1 there are no workers and jobs run
 *   inside job_wait / job_help on the main thread.
 *
 * JOBS AND DEPENDENCIES
 *     job_handle a = job_submit(jobs, &(job_desc){ .fn = load, .user = &chunk, .name = "load" });
 *     job_handle b = job_submit(jobs, &(job_desc){ .fn = mesh, .user = &chunk, .name = "mesh",
 *                                                 .after = &a, .after_count = 1 });
 *     job_wait(jobs, b);            // runs other jobs while b is not done; never just blocks
 *
 *   A job starts once every job in `after` has finished (a dependency counter per job). A
 *   handle of a finished job stays valid to wait on: its slot is reused under a new generation,
 *   and an old handle then simply reads as done. Submitting never fails: queues grow.
 *
 * PARALLEL LOOPS
 *     job_parallel_for(jobs, n, 0, update_range, &ctx, "update");  // batch 0 = automatic
 *   calls update_range(&ctx, begin, end) over disjoint ranges covering [0, n) on all threads
 *   and returns when all are done. job_parallel_for_async returns a handle instead.
 *
 * MAIN-THREAD JOBS
 *   A job with .main_thread = true runs only on the thread that created the job system (the
 *   OpenGL thread): inside job_wait / job_wait_all / job_help there, or in
 *   job_run_main_thread_jobs for a caller that wants them run without waiting on anything.
 *
 * BACKGROUND JOBS
 *     job_submit(jobs, &(job_desc){ .fn = mesh_chunk, .user = task, .background = true });
 *   Work that may take longer than a frame (streaming, generation) and that no frame waits for.
 *   Background jobs run on workers, oldest first, after the workers' other jobs; the main thread
 *   never picks one up while it waits for a frame's jobs (job_wait, job_parallel_for), so a
 *   frame is never stalled behind one. The main thread runs them only in job_help, or when it
 *   is the only thread (threads = 1) and has nothing else to do while it waits. Poll them with
 *   job_is_done; job_wait_all and job_system_destroy wait for them too. Jobs submitted by a
 *   running background job are background too, so a frame's wait never picks up a piece of a
 *   long job.
 *
 * THREADS AND SLEEP
 *   Each worker owns a queue; an idle worker steals from the others, and with nothing to steal
 *   it sleeps (an idle engine uses ~0% CPU). A new job wakes one sleeper that can run it (a
 *   worker first); a finished job wakes only a thread waiting for it. On Linux the workers run
 *   under SCHED_BATCH: the same share of the CPU, but a woken worker waits for a free core or
 *   the running thread's turn to end instead of preempting the thread that submitted the job.
 *
 * TRACES
 *   Every job runs inside a trace zone named by job_desc.name ("job" when NULL). A thread
 *   waiting in job_wait / job_wait_all is inside a zone "wait" (jobs it runs meanwhile nest in
 *   it), and a thread asleep in the job system inside a zone "sleep". Once a frame:
 *     job_system_trace_counters(jobs);   // before trace_frame_end
 *   records the counters jobs.run, jobs.stolen, jobs.sleeps, jobs.wakes (each since the last
 *   call) and jobs.queued (ready jobs not started, now).
 */
#ifndef JOBS_H
#define JOBS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct job_system job_system;

/* A reference to a submitted job. The zero handle means "no job" and reads as done. */
typedef struct job_handle {
    uint32_t index;
    uint32_t generation;
} job_handle;

typedef void (*job_fn)(void *user);
typedef void (*job_range_fn)(void *user, size_t begin, size_t end);

typedef struct job_system_desc {
    int threads;            /* total threads, the caller's included; 0 = one per core */
} job_system_desc;

typedef struct job_desc {
    job_fn fn;               /* required */
    void *user;
    const char *name;        /* trace zone name; static lifetime (or trace_intern) */
    const job_handle *after; /* jobs that must finish first (zero handles are ignored) */
    int after_count;
    bool main_thread;        /* run only on the main thread */
    bool background;         /* long work that may span frames (BACKGROUND JOBS above) */
} job_desc;

job_system *job_system_create(const job_system_desc *desc);
void job_system_destroy(job_system *jobs);

int job_thread_count(const job_system *jobs);
/* 0 on the main thread, 1..count-1 on workers, -1 on a thread the system does not own.
 * Use it to index per-thread scratch memory. */
int job_thread_index(const job_system *jobs);

job_handle job_submit(job_system *jobs, const job_desc *desc);
bool job_is_done(job_system *jobs, job_handle job);
void job_wait(job_system *jobs, job_handle job);
/* Waits for every job submitted so far (main thread only). */
void job_wait_all(job_system *jobs);
/* Runs queued jobs on the calling thread until none is left or `budget_ns` has passed;
 * returns how many ran. From the main thread this includes main-thread jobs. */
int job_help(job_system *jobs, uint64_t budget_ns);
/* Runs the main-thread jobs that are ready now, without waiting for anything; returns how many
 * ran. Main thread only. (job_wait and job_help run them too.) */
int job_run_main_thread_jobs(job_system *jobs);

/* batch = 0 picks a batch size that gives each thread about four ranges. */
void job_parallel_for(job_system *jobs, size_t count, size_t batch, job_range_fn fn,
                      void *user, const char *name);
job_handle job_parallel_for_async(job_system *jobs, size_t count, size_t batch,
                                  job_range_fn fn, void *user, const char *name);

/* Statistics, for counters and tests. */
typedef struct job_system_stats_info {
    uint64_t submitted, completed; /* completed = jobs run */
    uint64_t stolen;         /* jobs moved from one thread's queue to another's */
    uint64_t sleeps;         /* times a thread went to sleep for want of work */
    uint64_t wakes;          /* sleepers woken for a new job or a finished one */
    int queued;              /* ready jobs not yet started */
} job_system_stats_info;
job_system_stats_info job_system_stats(const job_system *jobs);
/* Records the TRACES counters above for the frame since the last call (one caller, once a
 * frame, from the thread that ends frames). Nothing when no capture runs. */
void job_system_trace_counters(job_system *jobs);

#endif /* JOBS_H */
