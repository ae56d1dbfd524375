/* jobs_internal.h — the job system's data, shared by its .c files (not a public header). */
#ifndef JOBS_INTERNAL_H
#define JOBS_INTERNAL_H

#include "jobs.h"

#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>

enum {
    JOB_BLOCK_SIZE = 1024,        /* slots per block; blocks are never moved or freed */
    JOB_MAX_BLOCKS = 16384,       /* 16 M jobs in flight at most */
    JOB_INLINE_DEPENDENTS = 3,    /* dependents stored in the slot before spilling to the heap */
    JOB_SLOT_CACHE = 64,          /* free slots a thread keeps for itself */
    JOB_SPIN_ROUNDS = 16,          /* looks for work (with back-off) before a worker sleeps */
    JOB_STEAL_MAX = 32,           /* jobs a thief moves to its own queue at once */
};

/* One job, in exactly one cache line: the submitting thread writes it and another thread runs
 * it, so every extra line is another transfer between cores per job. A slot is reused after
 * its job finishes, under a new generation: a handle whose generation no longer matches reads
 * as done. */
typedef struct job_slot {
    alignas(64) job_fn fn;
    void *user;
    const char *name;
    uint32_t *more_dependents;    /* dependents past the inline ones */
    _Atomic uint32_t generation;
    _Atomic int pending;          /* unfinished dependencies, +1 while job_submit still runs */
    int dependent_count, dependent_capacity;
    uint32_t inline_dependents[JOB_INLINE_DEPENDENTS];
    atomic_flag lock;             /* guards finished and the dependents */
    bool finished;
    bool main_thread;
    bool background;
} job_slot;
_Static_assert(sizeof(job_slot) == 64, "a job slot should fill one cache line");

/* A double-ended queue of slot indices. The owner pushes and pops at the back (newest first,
 * warm in cache); thieves take from the front (oldest, usually the biggest piece of work). A
 * mutex rather than a lock-free deque: at two to sixteen threads it is uncontended almost
 * always, it grows without a second protocol, and ThreadSanitizer understands it. */
typedef struct job_queue {
    pthread_mutex_t lock;
    uint32_t *items;
    size_t capacity, head, count;
    _Atomic size_t size_hint;     /* count, readable without the lock (for idle checks) */
} job_queue;

/* Per-thread state, each on cache lines of its own so that threads never write a shared line
 * for a job they run (the counters below are summed when read). */
typedef struct job_thread {
    alignas(64) job_system *system;
    int index;
    pthread_t thread;
    job_queue queue;
    uint32_t free_slots[JOB_SLOT_CACHE];
    int free_count;
    uint32_t steal_seed;
    _Atomic uint64_t submitted, completed, stolen;
} job_thread;

/* A thread asleep in the job system, on its own stack: a worker with nothing to do, or a thread
 * in job_wait / job_wait_all (`done` set). Each has a condition variable of its own, so a wake
 * reaches exactly the sleeper chosen for it (one that can run the new job, or the waiter whose
 * job finished) instead of every sleeper. Guarded by sleep_lock. */
typedef struct job_sleeper {
    struct job_sleeper *next;
    pthread_cond_t wake;
    const job_thread *self;       /* NULL for a thread the system does not own */
    bool (*done)(job_system *jobs, const void *arg); /* NULL for an idle worker */
    const void *arg;
    bool signalled;               /* woken and not yet running: not chosen again */
} job_sleeper;

struct job_system {
    int thread_count;             /* threads running (the main one included) */
    int thread_capacity;          /* job_thread records allocated */
    pthread_t main_thread;
    job_thread *threads;          /* [0] is the main thread's */
    job_queue main_queue;         /* jobs pinned to the main thread */
    job_queue background_queue;   /* long jobs, oldest first, for workers (jobs.h) */

    _Atomic(job_slot *) blocks[JOB_MAX_BLOCKS];
    _Atomic uint32_t block_count;
    pthread_mutex_t slot_lock;    /* guards the shared free list and block growth */
    uint32_t *shared_free;
    size_t shared_free_count, shared_free_capacity;

    _Atomic int sleepers;         /* threads in the sleeper list */
    _Atomic int waiters;          /* of those, threads waiting for a job to finish */
    pthread_mutex_t sleep_lock;
    job_sleeper *sleeper_list;    /* guarded by sleep_lock */
    _Atomic bool stopping;

    _Atomic uint64_t foreign_submitted, foreign_completed; /* by threads not in the pool */
    _Atomic uint64_t sleeps, wakes;
    job_system_stats_info traced;             /* at the last job_system_trace_counters (its caller's) */
};

#endif
