/* jobs.c — worker threads, queues, stealing, sleeping and waiting (see jobs.h). */
#include "jobs_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <sched.h>
#include <stdio.h>
#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define JOB_CPU_PAUSE() _mm_pause()
#else
#define JOB_CPU_PAUSE() ((void)0)
#endif

/* The worker record of the calling thread, when it is one of a job system's workers. */
static _Thread_local job_thread *current_worker;
/* The system whose background job the calling thread is running, if it is running one: what
 * that job submits is background too (jobs.h). */
static _Thread_local job_system *running_background_of;

/* ---- queues ----------------------------------------------------------------------------- */

static void queue_init(job_queue *queue) {
    pthread_mutex_init(&queue->lock, NULL);
    queue->capacity = 256;
    queue->items = core_alloc(queue->capacity * sizeof *queue->items);
    queue->head = queue->count = 0;
}

static void queue_release(job_queue *queue) {
    core_free(queue->items, queue->capacity * sizeof *queue->items);
    pthread_mutex_destroy(&queue->lock);
}

static void queue_grow(job_queue *queue) {
    size_t capacity = queue->capacity * 2;
    uint32_t *items = core_alloc(capacity * sizeof *items);
    for (size_t i = 0; i < queue->count; i++)
        items[i] = queue->items[(queue->head + i) % queue->capacity];
    core_free(queue->items, queue->capacity * sizeof *queue->items);
    queue->items = items;
    queue->capacity = capacity;
    queue->head = 0;
}

static void queue_push(job_queue *queue, uint32_t index) {
    pthread_mutex_lock(&queue->lock);
    if (queue->count == queue->capacity) queue_grow(queue);
    queue->items[(queue->head + queue->count) % queue->capacity] = index;
    atomic_store_explicit(&queue->size_hint, ++queue->count, memory_order_relaxed);
    pthread_mutex_unlock(&queue->lock);
}

static bool queue_pop_back(job_queue *queue, uint32_t *index) {
    pthread_mutex_lock(&queue->lock);
    bool found = queue->count > 0;
    if (found) {
        *index = queue->items[(queue->head + --queue->count) % queue->capacity];
        atomic_store_explicit(&queue->size_hint, queue->count, memory_order_relaxed);
    }
    pthread_mutex_unlock(&queue->lock);
    return found;
}

static bool queue_looks_empty(job_queue *queue) {
    return atomic_load_explicit(&queue->size_hint, memory_order_relaxed) == 0;
}

/* Takes up to `max` of the oldest items; returns how many. Taking several per lock means a
 * thief does not come back for every job (one cache-line transfer for many jobs). */
static int queue_steal(job_queue *queue, uint32_t *out, int max) {
    if (queue_looks_empty(queue)) return 0;
    if (pthread_mutex_trylock(&queue->lock) != 0) return 0; /* busy: try another victim */
    int taken = (int)CORE_MIN(queue->count - queue->count / 2, (size_t)max); /* half, rounded up */
    for (int i = 0; i < taken; i++) {
        out[i] = queue->items[queue->head];
        queue->head = (queue->head + 1) % queue->capacity;
    }
    queue->count -= (size_t)taken;
    atomic_store_explicit(&queue->size_hint, queue->count, memory_order_relaxed);
    pthread_mutex_unlock(&queue->lock);
    return taken;
}

/* ---- slots ------------------------------------------------------------------------------ */

static job_slot *slot_at(job_system *jobs, uint32_t index) {
    job_slot *block = atomic_load_explicit(&jobs->blocks[index / JOB_BLOCK_SIZE], memory_order_acquire);
    return &block[index % JOB_BLOCK_SIZE];
}

static void slot_lock(job_slot *slot) {
    while (atomic_flag_test_and_set_explicit(&slot->lock, memory_order_acquire)) JOB_CPU_PAUSE();
}
static void slot_unlock(job_slot *slot) { atomic_flag_clear_explicit(&slot->lock, memory_order_release); }

/* Makes room for `more` entries in the shared free list. Called with slot_lock held. */
static void reserve_shared_free(job_system *jobs, size_t more) {
    jobs->shared_free = core_grow(jobs->shared_free, &jobs->shared_free_capacity, jobs->shared_free_count + more,
                                  sizeof *jobs->shared_free);
}

/* Adds a block of fresh slots to the shared free list. Called with slot_lock held. */
static void grow_slots(job_system *jobs) {
    uint32_t block_index = atomic_load(&jobs->block_count);
    if (block_index == JOB_MAX_BLOCKS)
        core_fatal("jobs", "more than %d jobs in flight", JOB_MAX_BLOCKS * JOB_BLOCK_SIZE);
    job_slot *block = core_alloc_aligned(JOB_BLOCK_SIZE * sizeof *block, alignof(job_slot));
    memset(block, 0, JOB_BLOCK_SIZE * sizeof *block);
    for (int i = 0; i < JOB_BLOCK_SIZE; i++) {
        atomic_flag_clear(&block[i].lock);
        atomic_init(&block[i].generation, 1);
    }
    atomic_store_explicit(&jobs->blocks[block_index], block, memory_order_release);
    atomic_store(&jobs->block_count, block_index + 1);

    reserve_shared_free(jobs, JOB_BLOCK_SIZE);
    /* Push in reverse so the lowest index is handed out first. */
    for (int i = JOB_BLOCK_SIZE - 1; i >= 0; i--)
        jobs->shared_free[jobs->shared_free_count++] = block_index * JOB_BLOCK_SIZE + (uint32_t)i;
}

static uint32_t take_shared_slots(job_system *jobs, uint32_t *out, int want) {
    pthread_mutex_lock(&jobs->slot_lock);
    if (jobs->shared_free_count == 0) grow_slots(jobs);
    int taken = 0;
    while (taken < want && jobs->shared_free_count > 0) out[taken++] = jobs->shared_free[--jobs->shared_free_count];
    pthread_mutex_unlock(&jobs->slot_lock);
    return (uint32_t)taken;
}

static void give_shared_slots(job_system *jobs, const uint32_t *slots, int count) {
    pthread_mutex_lock(&jobs->slot_lock);
    reserve_shared_free(jobs, (size_t)count);
    memcpy(jobs->shared_free + jobs->shared_free_count, slots, (size_t)count * sizeof *slots);
    jobs->shared_free_count += (size_t)count;
    pthread_mutex_unlock(&jobs->slot_lock);
}

/* The job_thread record of the caller in this system, or NULL for a foreign thread. */
static job_thread *caller_thread(job_system *jobs) {
    if (current_worker && current_worker->system == jobs) return current_worker;
    if (pthread_equal(pthread_self(), jobs->main_thread)) return &jobs->threads[0];
    return NULL;
}

static uint32_t alloc_slot(job_system *jobs, job_thread *self) {
    if (!self) {
        uint32_t index;
        take_shared_slots(jobs, &index, 1);
        return index;
    }
    if (self->free_count == 0)
        self->free_count = (int)take_shared_slots(jobs, self->free_slots, JOB_SLOT_CACHE / 2);
    return self->free_slots[--self->free_count];
}

static void free_slot(job_system *jobs, job_thread *self, uint32_t index) {
    if (!self) {
        give_shared_slots(jobs, &index, 1);
        return;
    }
    if (self->free_count == JOB_SLOT_CACHE) {
        give_shared_slots(jobs, self->free_slots + JOB_SLOT_CACHE / 2, JOB_SLOT_CACHE / 2);
        self->free_count = JOB_SLOT_CACHE / 2;
    }
    self->free_slots[self->free_count++] = index;
}

/* A full fence for the sleep protocol below. ThreadSanitizer does not model fences, so its
 * build uses a sequentially consistent read-modify-write instead (stronger, and slower: it
 * writes a shared line, which the normal build avoids on the per-job path). */
static inline void full_fence(void) {
#ifdef ENGINE_TSAN
    static _Atomic int fence_word;
    atomic_fetch_add(&fence_word, 0);
#else
    atomic_thread_fence(memory_order_seq_cst);
#endif
}

/* ---- waking ----------------------------------------------------------------------------- */

/* Sleepers put themselves on the list (holding sleep_lock) before their last look at the queues,
 * and producers publish work before they look for sleepers, with a full fence between: one of
 * the two always sees the other, so no wake-up is lost. Each sleeper has a condition variable of
 * its own; a wake picks one sleeper and marks it, so two wakes never go to the same one. */
static void wake_one(job_system *jobs, job_sleeper *sleeper) {
    sleeper->signalled = true;
    atomic_fetch_add_explicit(&jobs->wakes, 1, memory_order_relaxed);
    pthread_cond_signal(&sleeper->wake);
}

typedef enum job_kind { JOB_KIND_ANY, JOB_KIND_MAIN, JOB_KIND_BACKGROUND } job_kind;

static bool takes_background(const job_system *jobs, const job_thread *self);

static bool sleeper_can_run(const job_system *jobs, const job_sleeper *sleeper, job_kind kind) {
    if (sleeper->signalled) return false;
    if (kind == JOB_KIND_MAIN) return sleeper->self && sleeper->self->index == 0;
    if (kind == JOB_KIND_BACKGROUND) return takes_background(jobs, sleeper->self);
    return true;
}

/* A job of `kind` was queued: wakes one sleeper that can run it, an idle worker before a thread
 * that waits (the waiter would run it in its own wait). */
static void wake_for_job(job_system *jobs, job_kind kind) {
    full_fence();
    if (atomic_load(&jobs->sleepers) == 0) return;
    pthread_mutex_lock(&jobs->sleep_lock);
    job_sleeper *chosen = NULL;
    for (job_sleeper *s = jobs->sleeper_list; s && (!chosen || chosen->done); s = s->next)
        if (sleeper_can_run(jobs, s, kind) && (!chosen || !s->done)) chosen = s;
    if (chosen) wake_one(jobs, chosen);
    pthread_mutex_unlock(&jobs->sleep_lock);
}

/* A job finished: wakes the threads whose wait it ends, and no one else. */
static void wake_finished_waiters(job_system *jobs) {
    full_fence();
    if (atomic_load(&jobs->waiters) == 0) return;
    pthread_mutex_lock(&jobs->sleep_lock);
    for (job_sleeper *s = jobs->sleeper_list; s; s = s->next)
        if (s->done && !s->signalled && s->done(jobs, s->arg)) wake_one(jobs, s);
    pthread_mutex_unlock(&jobs->sleep_lock);
}

static void make_ready(job_system *jobs, job_thread *self, uint32_t index) {
    job_slot *slot = slot_at(jobs, index);
    if (slot->main_thread) {
        queue_push(&jobs->main_queue, index);
        wake_for_job(jobs, JOB_KIND_MAIN);
        return;
    }
    if (slot->background) {
        queue_push(&jobs->background_queue, index);
        wake_for_job(jobs, JOB_KIND_BACKGROUND);
        return;
    }
    queue_push(self ? &self->queue : &jobs->threads[0].queue, index);
    wake_for_job(jobs, JOB_KIND_ANY);
}

/* ---- running ---------------------------------------------------------------------------- */

static void add_dependent(job_slot *slot, uint32_t dependent) {
    if (slot->dependent_count < JOB_INLINE_DEPENDENTS) {
        slot->inline_dependents[slot->dependent_count++] = dependent;
        return;
    }
    int extra = slot->dependent_count - JOB_INLINE_DEPENDENTS;
    /* The slot keeps an int capacity to stay within its cache line. */
    size_t capacity = (size_t)slot->dependent_capacity;
    slot->more_dependents = core_grow(slot->more_dependents, &capacity, (size_t)extra + 1, sizeof(uint32_t));
    slot->dependent_capacity = (int)capacity;
    slot->more_dependents[extra] = dependent;
    slot->dependent_count++;
}

static uint32_t dependent_at(const job_slot *slot, int i) {
    return i < JOB_INLINE_DEPENDENTS ? slot->inline_dependents[i] : slot->more_dependents[i - JOB_INLINE_DEPENDENTS];
}

/* Adds one to a counter. A thread's own counters have one writer, so a load and a release
 * store suffice (no locked instruction); counters of foreign threads are shared. */
static void count_one(_Atomic uint64_t *own, _Atomic uint64_t *shared) {
    if (own) atomic_store_explicit(own, atomic_load_explicit(own, memory_order_relaxed) + 1, memory_order_release);
    else atomic_fetch_add_explicit(shared, 1, memory_order_release);
}

static void finish_job(job_system *jobs, job_thread *self, uint32_t index) {
    job_slot *slot = slot_at(jobs, index);
    slot_lock(slot);
    slot->finished = true; /* from here on nobody adds a dependent */
    slot_unlock(slot);
    for (int i = 0; i < slot->dependent_count; i++) {
        uint32_t dependent = dependent_at(slot, i);
        if (atomic_fetch_sub(&slot_at(jobs, dependent)->pending, 1) == 1) make_ready(jobs, self, dependent);
    }
    if (slot->more_dependents) {
        core_free(slot->more_dependents, (size_t)slot->dependent_capacity * sizeof(uint32_t));
        slot->more_dependents = NULL;
        slot->dependent_capacity = 0;
    }
    /* The generation bump is what waiters watch: after it the handle reads as done. */
    uint32_t next = atomic_load_explicit(&slot->generation, memory_order_relaxed) + 1;
    atomic_store_explicit(&slot->generation, next ? next : 1, memory_order_release);
    free_slot(jobs, self, index);
    count_one(self ? &self->completed : NULL, &jobs->foreign_completed);
    /* Someone may be waiting for exactly this job (or for all of them). */
    wake_finished_waiters(jobs);
}

static void run_job(job_system *jobs, job_thread *self, uint32_t index) {
    job_slot *slot = slot_at(jobs, index);
    job_system *outer = running_background_of;
    running_background_of = slot->background ? jobs : NULL;
    trace_zone_begin(slot->name ? slot->name : "job");
    slot->fn(slot->user);
    trace_zone_end();
    running_background_of = outer;
    finish_job(jobs, self, index);
}

/* Whether the caller may run background jobs while looking for work: workers always; the main
 * thread only when it is the only thread (someone has to). */
static bool takes_background(const job_system *jobs, const job_thread *self) {
    return self && (self->index > 0 || jobs->thread_count == 1);
}

static bool take_background(job_system *jobs, uint32_t *index) {
    return !queue_looks_empty(&jobs->background_queue) && queue_steal(&jobs->background_queue, index, 1) == 1;
}

/* Finds a ready job for the caller: main-thread jobs (main thread only), its own queue, then
 * the others' (stealing), then (if `background`) the oldest background job. Returns false when
 * there is none. */
static bool find_job(job_system *jobs, job_thread *self, uint32_t *index, bool background) {
    bool on_main = self && self->index == 0;
    if (on_main && !queue_looks_empty(&jobs->main_queue) && queue_pop_back(&jobs->main_queue, index)) return true;
    if (self && !queue_looks_empty(&self->queue) && queue_pop_back(&self->queue, index)) return true;

    uint32_t start = 0;
    if (self) {
        self->steal_seed = self->steal_seed * 1664525u + 1013904223u;
        start = self->steal_seed >> 16;
    }
    for (int i = 0; i < jobs->thread_count; i++) {
        job_thread *victim = &jobs->threads[(start + (uint32_t)i) % (uint32_t)jobs->thread_count];
        if (victim == self) continue;
        uint32_t loot[JOB_STEAL_MAX];
        int taken = queue_steal(&victim->queue, loot, self ? JOB_STEAL_MAX : 1);
        if (taken == 0) continue;
        /* Run the oldest now; keep the rest in our queue, where others may steal them back. */
        for (int k = taken - 1; k >= 1; k--) queue_push(&self->queue, loot[k]);
        if (self) atomic_fetch_add_explicit(&self->stolen, (uint64_t)taken, memory_order_relaxed);
        *index = loot[0];
        return true;
    }
    return background && take_background(jobs, index);
}

typedef bool (*wait_predicate)(job_system *jobs, const void *arg);

static bool has_work_for(job_system *jobs, const job_thread *self) {
    if (self && self->index == 0 && !queue_looks_empty(&jobs->main_queue)) return true;
    for (int i = 0; i < jobs->thread_count; i++)
        if (!queue_looks_empty(&jobs->threads[i].queue)) return true;
    return takes_background(jobs, self) && !queue_looks_empty(&jobs->background_queue);
}

static void sleeper_unlink(job_system *jobs, job_sleeper *sleeper) {
    for (job_sleeper **link = &jobs->sleeper_list; *link; link = &(*link)->next) {
        if (*link == sleeper) {
            *link = sleeper->next;
            return;
        }
    }
}

/* Sleeps until there may be work for `self` or `done` holds (a NULL predicate: work only). The
 * time asleep is a trace zone "sleep". */
static void sleep_until(job_system *jobs, const job_thread *self, wait_predicate done, const void *arg) {
    job_sleeper sleeper = { .self = self, .done = done, .arg = arg };
    pthread_cond_init(&sleeper.wake, NULL);
    pthread_mutex_lock(&jobs->sleep_lock);
    sleeper.next = jobs->sleeper_list;
    jobs->sleeper_list = &sleeper;
    atomic_fetch_add(&jobs->sleepers, 1);
    if (done) atomic_fetch_add(&jobs->waiters, 1);
    full_fence(); /* pairs with the fences in wake_for_job and wake_finished_waiters */
    bool slept = false;
    while (!has_work_for(jobs, self) && !(done && done(jobs, arg)) && !atomic_load(&jobs->stopping)) {
        if (!slept) trace_zone_begin("sleep");
        slept = true;
        atomic_fetch_add_explicit(&jobs->sleeps, 1, memory_order_relaxed);
        sleeper.signalled = false;
        pthread_cond_wait(&sleeper.wake, &jobs->sleep_lock);
    }
    if (slept) trace_zone_end();
    if (done) atomic_fetch_sub(&jobs->waiters, 1);
    atomic_fetch_sub(&jobs->sleepers, 1);
    sleeper_unlink(jobs, &sleeper);
    pthread_mutex_unlock(&jobs->sleep_lock);
    pthread_cond_destroy(&sleeper.wake);
}

/* Runs jobs on the calling thread until `done` holds; never just blocks while work exists. The
 * wait is a trace zone "wait", the jobs it runs nested in it. */
static void wait_until(job_system *jobs, wait_predicate done, const void *arg) {
    if (done(jobs, arg)) return;
    TRACE_ZONE("wait");
    job_thread *self = caller_thread(jobs);
    while (!done(jobs, arg)) {
        uint32_t index;
        /* A frame waiting for its own jobs never runs a background one on the main thread: that
         * would stall the frame behind work meant to span frames. */
        if (find_job(jobs, self, &index, self && self->index > 0) ||
            (takes_background(jobs, self) && take_background(jobs, &index))) {
            run_job(jobs, self, index);
            continue;
        }
        sleep_until(jobs, self, done, arg);
    }
}

/* A woken worker waits for the running thread's turn to end rather than preempting it (Linux's
 * SCHED_BATCH: the same share of the CPU, no preemption on wake-up). The thread that wakes a
 * worker is mostly the main one handing out jobs, and where every core is busy (a 2-core
 * machine whose other core rasterises for llvmpipe) the woken worker used to land on its core
 * and run a chunk's meshing there before it could go on: a walk's streaming submissions took
 * up to 4.5 ms of the frame (0.14 ms since). Without SCHED_BATCH, or if refused, the default. */
static void worker_yield_on_wake(void) {
#ifdef SCHED_BATCH
    (void)pthread_setschedparam(pthread_self(), SCHED_BATCH, &(struct sched_param){ 0 });
#endif
}

static void *worker_main(void *arg) {
    job_thread *self = arg;
    job_system *jobs = self->system;
    current_worker = self;
    char name[32];
    snprintf(name, sizeof name, "worker %d", self->index);
    pthread_setname_np(pthread_self(), name);
    worker_yield_on_wake();
    trace_thread_name(trace_intern(name));

    while (!atomic_load(&jobs->stopping)) {
        uint32_t index;
        bool found = false;
        /* Back off exponentially between looks: a thief that pounces on every job the moment it
         * is pushed steals one job per cache-line transfer; one that lets a few pile up takes
         * them in a batch. After the last round it sleeps. */
        for (int round = 0; round < JOB_SPIN_ROUNDS && !found; round++) {
            found = find_job(jobs, self, &index, true);
            for (int p = 0; !found && p < (1 << CORE_MIN(round, 10)); p++) JOB_CPU_PAUSE();
        }
        if (found) run_job(jobs, self, index);
        else sleep_until(jobs, self, NULL, NULL);
    }
    return NULL;
}

/* ---- public API ------------------------------------------------------------------------- */

job_system *job_system_create(const job_system_desc *desc) {
    int threads = desc && desc->threads > 0 ? desc->threads : core_cpu_count();
    job_system *jobs = core_calloc(1, sizeof *jobs);
    jobs->thread_count = jobs->thread_capacity = threads;
    jobs->main_thread = pthread_self();
    jobs->threads = core_calloc((size_t)threads, sizeof *jobs->threads);
    pthread_mutex_init(&jobs->slot_lock, NULL);
    pthread_mutex_init(&jobs->sleep_lock, NULL);
    queue_init(&jobs->main_queue);
    queue_init(&jobs->background_queue);
    for (int i = 0; i < threads; i++) {
        jobs->threads[i] = (job_thread){ .system = jobs, .index = i, .steal_seed = 2654435761u * (uint32_t)(i + 1) };
        queue_init(&jobs->threads[i].queue);
    }
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&jobs->threads[i].thread, NULL, worker_main, &jobs->threads[i]) != 0) {
            /* Carry on with the workers that did start: jobs still run, only slower. */
            core_warn("jobs", "could not start worker %d of %d; running with %d threads", i, threads - 1, i);
            jobs->thread_count = i;
            break;
        }
    }
    return jobs;
}

void job_system_destroy(job_system *jobs) {
    if (!jobs) return;
    job_wait_all(jobs);
    atomic_store(&jobs->stopping, true);
    pthread_mutex_lock(&jobs->sleep_lock);
    for (job_sleeper *s = jobs->sleeper_list; s; s = s->next) pthread_cond_signal(&s->wake);
    pthread_mutex_unlock(&jobs->sleep_lock);
    for (int i = 1; i < jobs->thread_count; i++) pthread_join(jobs->threads[i].thread, NULL);

    for (int i = 0; i < jobs->thread_capacity; i++) queue_release(&jobs->threads[i].queue);
    queue_release(&jobs->main_queue);
    queue_release(&jobs->background_queue);
    core_free(jobs->threads, (size_t)jobs->thread_capacity * sizeof *jobs->threads);
    uint32_t blocks = atomic_load(&jobs->block_count);
    for (uint32_t b = 0; b < blocks; b++) core_free(atomic_load(&jobs->blocks[b]), JOB_BLOCK_SIZE * sizeof(job_slot));
    core_free(jobs->shared_free, jobs->shared_free_capacity * sizeof(uint32_t));
    pthread_mutex_destroy(&jobs->slot_lock);
    pthread_mutex_destroy(&jobs->sleep_lock);
    core_free(jobs, sizeof *jobs);
}

int job_thread_count(const job_system *jobs) { return jobs->thread_count; }

int job_thread_index(const job_system *jobs) {
    if (current_worker && current_worker->system == jobs) return current_worker->index;
    return pthread_equal(pthread_self(), jobs->main_thread) ? 0 : -1;
}

job_handle job_submit(job_system *jobs, const job_desc *desc) {
    job_thread *self = caller_thread(jobs);
    uint32_t index = alloc_slot(jobs, self);
    job_slot *slot = slot_at(jobs, index);
    /* No lock to fill the slot: others look at `finished` and the dependents only when their
     * handle's generation matches the slot's, and nobody holds this generation's handle yet. */
    slot->fn = desc->fn;
    slot->user = desc->user;
    slot->name = desc->name;
    slot->main_thread = desc->main_thread;
    /* What a background job submits is background too: a frame waiting on it must not run it. */
    slot->background = (desc->background || running_background_of == jobs) && !desc->main_thread;
    slot->finished = false;
    slot->dependent_count = 0;
    job_handle handle = { index, atomic_load_explicit(&slot->generation, memory_order_relaxed) };
    count_one(self ? &self->submitted : NULL, &jobs->foreign_submitted);

    if (desc->after_count == 0) {
        make_ready(jobs, self, index);
        return handle;
    }
    /* One count for ourselves, so the job cannot start before all its dependencies are in. */
    atomic_store_explicit(&slot->pending, 1, memory_order_relaxed);
    for (int i = 0; i < desc->after_count; i++) {
        job_handle dependency = desc->after[i];
        if (dependency.generation == 0) continue;
        job_slot *before = slot_at(jobs, dependency.index);
        slot_lock(before);
        /* Only a job still unfinished in the same generation can hold us back. */
        bool waits = atomic_load_explicit(&before->generation, memory_order_relaxed) == dependency.generation &&
                     !before->finished;
        if (waits) {
            atomic_fetch_add_explicit(&slot->pending, 1, memory_order_relaxed);
            add_dependent(before, index);
        }
        slot_unlock(before);
    }
    if (atomic_fetch_sub(&slot->pending, 1) == 1) make_ready(jobs, self, index);
    return handle;
}

bool job_is_done(job_system *jobs, job_handle job) {
    if (job.generation == 0) return true;
    return atomic_load_explicit(&slot_at(jobs, job.index)->generation, memory_order_acquire) != job.generation;
}

static bool handle_done(job_system *jobs, const void *arg) { return job_is_done(jobs, *(const job_handle *)arg); }
static uint64_t sum_completed(const job_system *jobs) {
    uint64_t total = atomic_load_explicit(&jobs->foreign_completed, memory_order_acquire);
    for (int i = 0; i < jobs->thread_count; i++)
        total += atomic_load_explicit(&jobs->threads[i].completed, memory_order_acquire);
    return total;
}

static uint64_t sum_submitted(const job_system *jobs) {
    uint64_t total = atomic_load_explicit(&jobs->foreign_submitted, memory_order_acquire);
    for (int i = 0; i < jobs->thread_count; i++)
        total += atomic_load_explicit(&jobs->threads[i].submitted, memory_order_acquire);
    return total;
}

/* Completed is summed before submitted. A job submits its children before it completes, so if
 * the two sums match, no job was running when the first sum ended, and none could have
 * submitted another since: everything is done. */
static bool nothing_live(job_system *jobs, const void *arg) {
    (void)arg;
    uint64_t completed = sum_completed(jobs);
    return completed == sum_submitted(jobs);
}

void job_wait(job_system *jobs, job_handle job) { wait_until(jobs, handle_done, &job); }
void job_wait_all(job_system *jobs) { wait_until(jobs, nothing_live, NULL); }

int job_help(job_system *jobs, uint64_t budget_ns) {
    job_thread *self = caller_thread(jobs);
    uint64_t start = core_time_ns();
    int ran = 0;
    uint32_t index;
    while (find_job(jobs, self, &index, true)) {
        run_job(jobs, self, index);
        ran++;
        if (core_time_ns() - start >= budget_ns) break;
    }
    return ran;
}

int job_run_main_thread_jobs(job_system *jobs) {
    job_thread *self = caller_thread(jobs);
    if (!self || self->index != 0) return 0;
    int ran = 0;
    uint32_t index;
    while (!queue_looks_empty(&jobs->main_queue) && queue_pop_back(&jobs->main_queue, &index)) {
        run_job(jobs, self, index);
        ran++;
    }
    return ran;
}

/* ---- parallel loops --------------------------------------------------------------------- */

typedef struct parallel_for_batch {
    job_range_fn fn;
    void *user;
    size_t begin, end;
} parallel_for_batch;

typedef struct parallel_for_group {
    parallel_for_batch *batches;
    size_t batch_count;
} parallel_for_group;

static void run_batch(void *arg) {
    parallel_for_batch *batch = arg;
    batch->fn(batch->user, batch->begin, batch->end);
}

static void join_batches(void *arg) { (void)arg; }

/* Runs after every batch: the batches' memory lives exactly as long as they do. */
static void release_group(void *arg) {
    parallel_for_group *group = arg;
    core_free(group->batches, group->batch_count * sizeof *group->batches);
    core_free(group, sizeof *group);
}

static size_t pick_batch_size(job_system *jobs, size_t count, size_t batch) {
    if (batch) return batch;
    size_t ranges = (size_t)jobs->thread_count * 4; /* about four per thread balances uneven work */
    return count / ranges + (count % ranges != 0);
}

job_handle job_parallel_for_async(job_system *jobs, size_t count, size_t batch, job_range_fn fn,
                                  void *user, const char *name) {
    if (count == 0) return (job_handle){ 0, 0 };
    batch = pick_batch_size(jobs, count, batch);
    /* The last job submitted below frees `group`, possibly before job_submit returns: after
     * that nothing here may touch it, hence the local batch_count. */
    size_t batch_count = count / batch + (count % batch != 0);
    parallel_for_group *group = core_alloc(sizeof *group);
    group->batch_count = batch_count;
    group->batches = core_alloc(batch_count * sizeof *group->batches);

    /* Batches go in as dependencies of the release job; handles are gathered in chunks so
     * that a loop of millions of batches needs no array of millions of handles. */
    enum { CHUNK = 256 };
    job_handle handles[CHUNK];
    job_handle previous_release = { 0, 0 };
    size_t b = 0;
    while (b < batch_count) {
        int in_chunk = 0;
        for (; b < batch_count && in_chunk < CHUNK - 1; b++) {
            size_t begin = b * batch;
            group->batches[b] = (parallel_for_batch){ fn, user, begin, CORE_MIN(begin + batch, count) };
            handles[in_chunk++] = job_submit(jobs, &(job_desc){ .fn = run_batch, .user = &group->batches[b],
                                                                .name = name });
        }
        handles[in_chunk++] = previous_release;
        bool last = b == batch_count;
        previous_release = job_submit(jobs, &(job_desc){ .fn = last ? release_group : join_batches,
                                                         .user = group, .name = "parallel_for.join", .after = handles,
                                                         .after_count = in_chunk });
    }
    return previous_release;
}

void job_parallel_for(job_system *jobs, size_t count, size_t batch, job_range_fn fn, void *user,
                      const char *name) {
    job_wait(jobs, job_parallel_for_async(jobs, count, batch, fn, user, name));
}

job_system_stats_info job_system_stats(const job_system *jobs) {
    job_system_stats_info stats = {
        .completed = sum_completed(jobs),
        .submitted = sum_submitted(jobs),
        .sleeps = atomic_load_explicit(&jobs->sleeps, memory_order_relaxed),
        .wakes = atomic_load_explicit(&jobs->wakes, memory_order_relaxed),
        .queued = (int)(atomic_load_explicit(&jobs->main_queue.size_hint, memory_order_relaxed) +
                        atomic_load_explicit(&jobs->background_queue.size_hint, memory_order_relaxed)),
    };
    for (int i = 0; i < jobs->thread_count; i++) {
        stats.stolen += atomic_load_explicit(&jobs->threads[i].stolen, memory_order_relaxed);
        stats.queued += (int)atomic_load_explicit(&jobs->threads[i].queue.size_hint, memory_order_relaxed);
    }
    return stats;
}

/* The one place the job system's counters are recorded (jobs.h, TRACES). */
void job_system_trace_counters(job_system *jobs) {
    if (!trace_active()) return;
    job_system_stats_info now = job_system_stats(jobs), *last = &jobs->traced;
    trace_counter("jobs.run", (double)(now.completed - last->completed));
    trace_counter("jobs.stolen", (double)(now.stolen - last->stolen));
    trace_counter("jobs.sleeps", (double)(now.sleeps - last->sleeps));
    trace_counter("jobs.wakes", (double)(now.wakes - last->wakes));
    trace_counter("jobs.queued", (double)now.queued);
    *last = now;
}
