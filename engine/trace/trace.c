/* trace.c — capture: per-thread event buffers written out as Chrome Trace Event JSON (trace.h).
 *
 * Each thread appends fixed-size events to a chunk of its own, reached through a thread-local
 * pointer, so recording takes no lock. A full chunk (and at trace_frame_end the frame thread's
 * chunk) is handed to a global list, the only time a recording thread locks, and a writer thread
 * of the capture's own formats that list and writes it to the file: no thread that records ever
 * formats JSON or waits on the disk. The writer's work is a zone ("trace.write") on its own lane.
 * The registry, not the thread, owns the chunks: a thread that exits hands its last chunk over,
 * and trace_stop joins the writer and writes whatever every thread still holds.
 *
 * Locks: `trace_lock` guards the registry (threads, chunk lists, names, lanes, the writer's
 * requests). The file and `trace_writer` belong to the writer thread while it runs, and to
 * trace_start / trace_stop before it starts and after it is joined, so they need no lock.
 */
#include "trace/trace.h"

#include "core/core.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#if defined(__x86_64__)
#include <cpuid.h>
#include <x86intrin.h>
#define TRACE_HAS_TSC 1
#else
#define TRACE_HAS_TSC 0
#endif

enum {
    TRACE_CHUNK_EVENTS = 2048, /* 64 KiB chunks of 32-byte events */
    /* Full chunks queued before the writer is woken without a frame end: a thread that records
     * fast wakes it every 4 MiB, not every chunk (each wake is a context switch, and on a
     * machine with few cores the writer then runs in the recording thread's time). */
    TRACE_WRITER_BATCH = 64,
    TRACE_PID = 1,
};

typedef enum trace_event_kind {
    TRACE_EVENT_BEGIN,
    TRACE_EVENT_END,
    TRACE_EVENT_COUNTER,
    TRACE_EVENT_COMPLETE,
    TRACE_EVENT_ARG, /* an argument of the BEGIN just before it (after its other arguments) */
} trace_event_kind;

/* An ARG event's `lane` says what its payload holds. */
enum { TRACE_ARG_INT, TRACE_ARG_STRING };

typedef struct trace_event {
    uint64_t time;    /* clock ticks; for COMPLETE, trace_now() nanoseconds */
    const char *name; /* NULL for END */
    uint64_t payload; /* COUNTER: the double's bits; COMPLETE: duration in nanoseconds;
                         ARG: the int64's bits or the string's pointer */
    uint32_t kind;
    uint32_t lane;    /* COMPLETE: the lane's tid; ARG: TRACE_ARG_INT or TRACE_ARG_STRING */
} trace_event;

typedef struct trace_chunk {
    struct trace_chunk *next; /* in the full list, the kept list or the pool */
    uint64_t handed;          /* clock ticks when handed to the writer (trace_keep_frames) */
    uint32_t tid;             /* the thread whose events these are */
    /* Stored with release by the owner after each event, so trace_stop can read a live
     * thread's events [0, count) without a lock on the recording side. */
    _Atomic uint32_t count;
    trace_event events[TRACE_CHUNK_EVENTS];
} trace_chunk;

/* One per thread that ever recorded or named itself; lives until that thread exits. */
typedef struct trace_thread {
    struct trace_thread *next;
    trace_chunk *chunk;  /* being filled; swapped only under trace_lock */
    uint32_t session;    /* the capture that `tid` and `chunk` belong to */
    uint32_t tid;
    const char *name;    /* interned; kept across captures */
} trace_thread;

/* A tid's name, written as an "M" event by the next flush after it is set. */
typedef struct trace_tid_name {
    const char *name; /* interned */
    bool is_lane;     /* a trace_complete lane rather than a thread */
    bool pending;
} trace_tid_name;

typedef struct trace_clock_map {
    uint64_t start_ticks;
    double ns_per_tick;
} trace_clock_map;

int trace__active;
static _Atomic uint32_t trace_session; /* bumped by every trace_start */
static _Thread_local trace_thread *trace_local;
static pthread_mutex_t trace_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t trace_work_ready = PTHREAD_COND_INITIALIZER; /* the writer waits on it */
static pthread_cond_t trace_written = PTHREAD_COND_INITIALIZER;    /* trace_flush waits on it */
static pthread_once_t trace_once = PTHREAD_ONCE_INIT;
static pthread_key_t trace_exit_key;
static bool trace_use_tsc; /* set once in trace_init, before any capture */

/* Guarded by trace_lock. */
static struct {
    trace_thread *threads;
    trace_chunk *full_first, **full_last; /* handed over, oldest first */
    size_t full_count;
    /* trace_keep_frames: the window, and the ticks of the last frame ends (a ring). A chunk
     * handed over no later than `cutoff` holds only events from before the window. */
    int keep_frames;       /* 0 = keep everything */
    uint64_t *frame_ends;  /* keep_frames entries */
    uint64_t frame_count, cutoff;
    trace_chunk *pool;
    _Atomic size_t chunks_made; /* allocated and not freed (trace_memory_bytes reads it lock-free) */
    trace_tid_name *names; /* indexed by tid; tid 0 is unused */
    uint32_t tid_count;    /* next tid to give out */
    size_t name_capacity;
    /* The writer thread and what it has been asked to do. */
    pthread_t writer;
    bool writer_running;   /* started by trace_start, joined by trace_stop */
    bool writer_stop;      /* trace_stop asks it to write what is left and exit */
    bool stopping;         /* trace_stop is running: a second call returns at once */
    uint64_t flush_requested, flush_done; /* trace_flush tickets */
} trace_registry;

/* A tid and its name, copied out of the registry so the writer can write it without the lock. */
typedef struct trace_name_entry {
    uint32_t tid;
    const char *name;
} trace_name_entry;

/* The writer's state: the writer thread's while it runs (see the locks above). */
static struct {
    FILE *file;
    char *path;
    uint64_t start_ns;    /* core_time_ns() at trace_start */
    uint64_t start_ticks; /* the clock's ticks at the same moment */
    uint64_t *last_ns;    /* per tid: the last timestamp written */
    size_t last_capacity;
    size_t events_written;
    trace_name_entry *names; /* pending names of the batch being written */
    size_t name_count, name_capacity;
    uint32_t *depth;         /* per tid: zones open in what was written */
    size_t depth_capacity;
    trace_chunk *kept_first, **kept_last; /* trace_keep_frames: chunks held back, oldest first */
} trace_writer;

/* ---- clock ------------------------------------------------------------------------------ */

#if TRACE_HAS_TSC
/* The TSC is a usable clock only when it ticks at a constant rate through frequency changes
 * and sleep states ("invariant TSC", CPUID 0x80000007 EDX bit 8); otherwise use the OS clock. */
static bool trace_tsc_is_invariant(void) {
    unsigned eax, ebx, ecx, edx;
    if (!__get_cpuid(0x80000000u, &eax, &ebx, &ecx, &edx) || eax < 0x80000007u) return false;
    __get_cpuid(0x80000007u, &eax, &ebx, &ecx, &edx);
    return (edx & (1u << 8)) != 0;
}
#endif

/* ~7 ns for rdtsc against ~20 ns for clock_gettime: most of a zone's cost is reading the time. */
static inline uint64_t trace_ticks(void) {
#if TRACE_HAS_TSC
    if (trace_use_tsc) return __rdtsc();
#endif
    return core_time_ns();
}

/* Maps ticks to nanoseconds through two points read on both clocks: the start of the capture and
 * now. The longer the capture runs, the more exact the rate. */
static trace_clock_map trace_clock_map_now(void) {
    trace_clock_map map = { .start_ticks = trace_writer.start_ticks, .ns_per_tick = 1.0 };
    if (!trace_use_tsc) return map;
    uint64_t ns = core_time_ns(), ticks = trace_ticks();
    if (ticks > map.start_ticks && ns > trace_writer.start_ns)
        map.ns_per_tick = (double)(ns - trace_writer.start_ns) / (double)(ticks - map.start_ticks);
    return map;
}

static uint64_t trace_ticks_to_ns(const trace_clock_map *map, uint64_t ticks) {
    if (ticks <= map->start_ticks) return 0;
    return (uint64_t)((double)(ticks - map->start_ticks) * map->ns_per_tick + 0.5);
}

/* ---- interned strings ------------------------------------------------------------------- */

/* An open-addressing set of copies that live until the process ends, so a name handed out once
 * stays valid in every later capture. */
static struct {
    pthread_mutex_t lock;
    char **slots;
    size_t capacity, count;
} trace_interned = { .lock = PTHREAD_MUTEX_INITIALIZER };

static char **trace_intern_slot(char **slots, size_t capacity, const char *s) {
    size_t mask = capacity - 1;
    for (size_t i = core_hash_bytes(s, strlen(s), 0) & mask;; i = (i + 1) & mask)
        if (!slots[i] || strcmp(slots[i], s) == 0) return &slots[i];
}

static void trace_intern_grow(void) {
    size_t capacity = trace_interned.capacity ? trace_interned.capacity * 2 : 256;
    char **slots = core_calloc(capacity, sizeof *slots);
    for (size_t i = 0; i < trace_interned.capacity; i++) {
        char *s = trace_interned.slots[i];
        if (s) *trace_intern_slot(slots, capacity, s) = s;
    }
    core_free(trace_interned.slots, trace_interned.capacity * sizeof *slots);
    trace_interned.slots = slots;
    trace_interned.capacity = capacity;
}

const char *trace_intern(const char *s) {
    if (!s) return NULL;
    pthread_mutex_lock(&trace_interned.lock);
    if (2 * (trace_interned.count + 1) > trace_interned.capacity) trace_intern_grow();
    char **slot = trace_intern_slot(trace_interned.slots, trace_interned.capacity, s);
    if (!*slot) {
        *slot = core_strdup(s);
        trace_interned.count++;
    }
    const char *copy = *slot;
    pthread_mutex_unlock(&trace_interned.lock);
    return copy;
}

/* ---- registry (trace_lock held) --------------------------------------------------------- */

static trace_chunk *trace_chunk_take(uint32_t tid) {
    trace_chunk *chunk = trace_registry.pool;
    if (chunk) trace_registry.pool = chunk->next;
    else chunk = core_alloc(sizeof *chunk), atomic_fetch_add_explicit(&trace_registry.chunks_made, 1, memory_order_relaxed);
    chunk->next = NULL;
    chunk->tid = tid;
    atomic_store_explicit(&chunk->count, 0, memory_order_relaxed);
    return chunk;
}

static void trace_chunks_to_pool(trace_chunk *first) {
    while (first) {
        trace_chunk *next = first->next;
        first->next = trace_registry.pool;
        trace_registry.pool = first;
        first = next;
    }
}

/* Queues a chunk for the writer, and wakes it once TRACE_WRITER_BATCH are waiting (a frame end
 * wakes it whatever the count: trace_wake_writer). */
static void trace_chunk_append_full(trace_chunk *chunk) {
    chunk->next = NULL;
    chunk->handed = trace_ticks();
    *trace_registry.full_last = chunk;
    trace_registry.full_last = &chunk->next;
    if (++trace_registry.full_count >= TRACE_WRITER_BATCH) pthread_cond_signal(&trace_work_ready);
}

static void trace_wake_writer(void) {
    if (trace_registry.full_first) pthread_cond_signal(&trace_work_ready);
}

static trace_chunk *trace_take_full_list(void) {
    trace_chunk *first = trace_registry.full_first;
    trace_registry.full_first = NULL;
    trace_registry.full_last = &trace_registry.full_first;
    trace_registry.full_count = 0;
    return first;
}

/* trace__active is a plain int shared with the inline fast path in trace.h, hence __atomic. */
static bool trace_capturing(void) { return __atomic_load_n(&trace__active, __ATOMIC_RELAXED) != 0; }
static void trace_set_capturing(bool on) { __atomic_store_n(&trace__active, on, __ATOMIC_RELEASE); }

static uint32_t trace_tid_new(const char *name, bool is_lane) {
    uint32_t tid = trace_registry.tid_count++;
    trace_registry.names = core_grow(trace_registry.names, &trace_registry.name_capacity, (size_t)tid + 1,
                                     sizeof *trace_registry.names);
    trace_registry.names[tid] = (trace_tid_name){ .name = name, .is_lane = is_lane, .pending = name != NULL };
    return tid;
}

/* Whether the thread's tid and chunk belong to the running capture. */
static bool trace_thread_is_current(const trace_thread *thread) {
    return thread && trace_capturing() && thread->session == atomic_load(&trace_session);
}

/* Runs on a thread that exits (a pthread key destructor): its events outlive it. */
static void trace_thread_exit(void *arg) {
    trace_thread *thread = arg;
    pthread_mutex_lock(&trace_lock);
    for (trace_thread **link = &trace_registry.threads; *link; link = &(*link)->next) {
        if (*link == thread) {
            *link = thread->next;
            break;
        }
    }
    trace_chunk *chunk = thread->chunk;
    if (chunk) {
        if (trace_thread_is_current(thread) && atomic_load_explicit(&chunk->count, memory_order_relaxed) > 0)
            trace_chunk_append_full(chunk);
        else
            trace_chunks_to_pool(chunk);
    }
    pthread_mutex_unlock(&trace_lock);
    core_free(thread, sizeof *thread);
    trace_local = NULL;
}

static void trace_init(void) {
    pthread_key_create(&trace_exit_key, trace_thread_exit);
    trace_registry.full_last = &trace_registry.full_first;
#if TRACE_HAS_TSC
    trace_use_tsc = trace_tsc_is_invariant();
#endif
}

static trace_thread *trace_thread_self(void) {
    if (trace_local) return trace_local;
    trace_thread *thread = core_calloc(1, sizeof *thread);
    thread->next = trace_registry.threads;
    trace_registry.threads = thread;
    pthread_setspecific(trace_exit_key, thread);
    trace_local = thread;
    return thread;
}

/* Hands the calling thread's chunk to the writer however full it is, so what the thread has
 * recorded reaches the file soon (trace_frame_end, trace_flush). */
static void trace_hand_over_partial(trace_thread *thread) {
    if (!trace_thread_is_current(thread) || !thread->chunk) return;
    if (atomic_load_explicit(&thread->chunk->count, memory_order_relaxed) == 0) return;
    trace_chunk_append_full(thread->chunk);
    thread->chunk = trace_chunk_take(thread->tid);
}

/* The slow path of recording: the first event of this thread in the running capture. */
static trace_thread *trace_thread_join(void) {
    pthread_once(&trace_once, trace_init);
    pthread_mutex_lock(&trace_lock);
    trace_thread *thread = NULL;
    uint32_t session = atomic_load(&trace_session);
    if (trace_capturing()) {
        thread = trace_thread_self();
        if (thread->session != session) {
            thread->session = session;
            thread->tid = trace_tid_new(thread->name, false);
            if (!thread->chunk) thread->chunk = trace_chunk_take(thread->tid);
            /* Whatever the chunk held belongs to an earlier capture, already written. */
            thread->chunk->tid = thread->tid;
            atomic_store_explicit(&thread->chunk->count, 0, memory_order_relaxed);
        }
    }
    pthread_mutex_unlock(&trace_lock);
    return thread;
}

/* A full chunk goes to the list trace_flush writes; the thread carries on in a fresh one. */
static trace_chunk *trace_chunk_hand_over(trace_thread *thread) {
    pthread_mutex_lock(&trace_lock);
    if (trace_capturing() && thread->session == atomic_load(&trace_session)) {
        trace_chunk_append_full(thread->chunk);
        thread->chunk = trace_chunk_take(thread->tid);
    } else {
        /* The capture these events belong to has ended: drop them. */
        atomic_store_explicit(&thread->chunk->count, 0, memory_order_relaxed);
    }
    trace_chunk *chunk = thread->chunk;
    pthread_mutex_unlock(&trace_lock);
    return chunk;
}

/* ---- recording (the hot path) ----------------------------------------------------------- */

static inline trace_chunk *trace_local_chunk(void) {
    trace_thread *thread = trace_local;
    uint32_t session = atomic_load_explicit(&trace_session, memory_order_relaxed);
    if (__builtin_expect(!thread || thread->session != session, 0)) {
        thread = trace_thread_join();
        if (!thread) return NULL;
    }
    trace_chunk *chunk = thread->chunk;
    if (__builtin_expect(atomic_load_explicit(&chunk->count, memory_order_relaxed) == TRACE_CHUNK_EVENTS, 0))
        chunk = trace_chunk_hand_over(thread);
    return chunk;
}

/* Fields are stored one by one: building a trace_event on the stack and copying it made the
 * compiler reload it with 16-byte loads right after 8-byte stores, a store-forwarding stall. */
static inline void trace_chunk_push(trace_chunk *chunk, uint32_t kind, const char *name, uint64_t time,
                                    uint64_t payload, uint32_t lane) {
    uint32_t n = atomic_load_explicit(&chunk->count, memory_order_relaxed);
    trace_event *event = &chunk->events[n];
    event->time = time;
    event->name = name;
    event->payload = payload;
    event->kind = kind;
    event->lane = lane;
    atomic_store_explicit(&chunk->count, n + 1, memory_order_release);
}

void trace__zone_begin(const char *name) {
    trace_chunk *chunk = trace_local_chunk();
    if (chunk) trace_chunk_push(chunk, TRACE_EVENT_BEGIN, name, trace_ticks(), 0, 0);
}

void trace__zone_end(void) {
    trace_chunk *chunk = trace_local_chunk();
    if (chunk) trace_chunk_push(chunk, TRACE_EVENT_END, NULL, trace_ticks(), 0, 0);
}

/* A full chunk whose last events are a BEGIN and its arguments: they move to the fresh chunk
 * with the argument about to be added, so the writer always finds a zone's arguments in the
 * same chunk as its BEGIN. */
static trace_chunk *trace_chunk_carry_over(trace_thread *thread, uint32_t from) {
    pthread_mutex_lock(&trace_lock);
    trace_chunk *old = thread->chunk, *fresh = trace_chunk_take(thread->tid);
    uint32_t count = atomic_load_explicit(&old->count, memory_order_relaxed);
    memcpy(fresh->events, old->events + from, (count - from) * sizeof *old->events);
    atomic_store_explicit(&fresh->count, count - from, memory_order_release);
    atomic_store_explicit(&old->count, from, memory_order_release);
    if (from > 0) trace_chunk_append_full(old);
    else trace_chunks_to_pool(old);
    thread->chunk = fresh;
    pthread_mutex_unlock(&trace_lock);
    return fresh;
}

void trace__zone_arg(const char *key, uint64_t value, uint32_t type) {
    trace_thread *thread = trace_local;
    if (!thread || thread->session != atomic_load_explicit(&trace_session, memory_order_relaxed)) return;
    trace_chunk *chunk = thread->chunk;
    uint32_t count = atomic_load_explicit(&chunk->count, memory_order_relaxed), first = count;
    while (first > 0 && chunk->events[first - 1].kind == TRACE_EVENT_ARG) first--;
    /* Only the zone opened just before takes arguments (trace.h), and only so many. */
    if (first == 0 || chunk->events[first - 1].kind != TRACE_EVENT_BEGIN) return;
    if (count - first >= TRACE_ZONE_ARGS_MAX) return;
    if (count == TRACE_CHUNK_EVENTS) chunk = trace_chunk_carry_over(thread, first - 1);
    trace_chunk_push(chunk, TRACE_EVENT_ARG, key, 0, value, type);
}

void trace_counter(const char *name, double value) {
    /* NaN and infinities have no JSON spelling. */
    if (!trace_active() || !isfinite(value)) return;
    trace_chunk *chunk = trace_local_chunk();
    if (!chunk) return;
    uint64_t bits;
    memcpy(&bits, &value, sizeof bits);
    trace_chunk_push(chunk, TRACE_EVENT_COUNTER, name, trace_ticks(), bits, 0);
}

/* The tid of a trace_complete lane, made on first use; 0 when no capture runs. */
static uint32_t trace_lane_tid(const char *lane) {
    pthread_mutex_lock(&trace_lock);
    uint32_t tid = 0;
    if (trace_capturing()) {
        for (uint32_t i = 1; i < trace_registry.tid_count && !tid; i++) {
            const trace_tid_name *entry = &trace_registry.names[i];
            if (entry->is_lane && strcmp(entry->name, lane) == 0) tid = i;
        }
        if (!tid) tid = trace_tid_new(trace_intern(lane), true);
    }
    pthread_mutex_unlock(&trace_lock);
    return tid;
}

void trace_complete(const char *lane, const char *name, uint64_t begin_ns, uint64_t end_ns) {
    if (!trace_active()) return;
    uint32_t lane_tid = trace_lane_tid(lane ? lane : "lane");
    trace_chunk *chunk = lane_tid ? trace_local_chunk() : NULL;
    if (!chunk) return;
    trace_chunk_push(chunk, TRACE_EVENT_COMPLETE, name, begin_ns, end_ns > begin_ns ? end_ns - begin_ns : 0, lane_tid);
}

void trace_thread_name(const char *name) {
    pthread_once(&trace_once, trace_init);
    const char *interned = trace_intern(name ? name : "");
    pthread_mutex_lock(&trace_lock);
    /* Kept on the thread even with no capture running, so a worker named at start-up shows its
     * name in a capture started later. */
    trace_thread *thread = trace_thread_self();
    thread->name = interned;
    if (trace_capturing() && thread->session == atomic_load(&trace_session)) {
        trace_registry.names[thread->tid].name = interned;
        trace_registry.names[thread->tid].pending = true;
    }
    pthread_mutex_unlock(&trace_lock);
}

/* trace_keep_frames: moves the window on by one frame (trace_lock held, after the frame's chunk
 * was handed over, so that chunk is inside the window's last frame). */
static void trace_note_frame_end(void) {
    int keep = trace_registry.keep_frames;
    if (!keep || !trace_registry.frame_ends) return;
    uint64_t now = trace_ticks();
    size_t slot = (size_t)(trace_registry.frame_count % (uint64_t)keep);
    if (trace_registry.frame_count >= (uint64_t)keep) trace_registry.cutoff = trace_registry.frame_ends[slot];
    trace_registry.frame_ends[slot] = now;
    trace_registry.frame_count++;
}

void trace_keep_frames(int frames) {
    pthread_mutex_lock(&trace_lock);
    if (!trace_capturing()) trace_registry.keep_frames = frames > 0 ? frames : 0;
    pthread_mutex_unlock(&trace_lock);
}

size_t trace_memory_bytes(void) {
    /* No lock: trace_frame_end reads it on the frame thread just before taking the lock itself. */
    return atomic_load_explicit(&trace_registry.chunks_made, memory_order_relaxed) * sizeof(trace_chunk);
}

void trace_frame_begin(void) { trace_zone_begin("frame"); }

void trace_frame_end(void) {
    if (!trace_active()) return;
    trace__zone_end();
    /* DESIGN.md: resident memory is a counter in every trace. */
    trace_counter("memory.bytes", (double)core_memory_in_use());
    trace_counter("memory.trace", (double)trace_memory_bytes());
    /* The frame's events go to the writer now; formatting and writing them is its work. */
    pthread_mutex_lock(&trace_lock);
    trace_hand_over_partial(trace_local);
    trace_note_frame_end();
    trace_wake_writer();
    pthread_mutex_unlock(&trace_lock);
}

uint64_t trace_now(void) { return core_time_ns(); }

/* ---- writing (the writer thread, or trace_stop once it is joined) ---------------------- */

static void trace_write_separator(void) {
    fputs(trace_writer.events_written++ ? ",\n" : "\n", trace_writer.file);
}

/* Microseconds with 3 decimals, formatted from integer nanoseconds so no rounding creeps in. */
static void trace_write_micros(uint64_t ns) {
    char buffer[32];
    char *end = buffer + sizeof buffer, *p = end;
    unsigned fraction = (unsigned)(ns % 1000);
    for (int i = 0; i < 3; i++, fraction /= 10) *--p = (char)('0' + fraction % 10);
    *--p = '.';
    uint64_t micros = ns / 1000;
    do *--p = (char)('0' + micros % 10); while ((micros /= 10) != 0);
    fwrite(p, 1, (size_t)(end - p), trace_writer.file);
}

/* The shortest of %.15g and %.17g that reads back as the same double. */
static void trace_write_double(double value) {
    char buffer[32];
    snprintf(buffer, sizeof buffer, "%.15g", value);
    if (strtod(buffer, NULL) != value) snprintf(buffer, sizeof buffer, "%.17g", value);
    fputs(buffer, trace_writer.file);
}

static void trace_write_head(const char *ph, const char *name) {
    FILE *out = trace_writer.file;
    trace_write_separator();
    fprintf(out, "{\"ph\":\"%s\",", ph);
    if (name) {
        fputs("\"name\":", out);
        core_json_write_string(out, name);
        fputc(',', out);
    }
}

static void trace_write_tail(uint32_t tid) { fprintf(trace_writer.file, "\"pid\":%d,\"tid\":%u}", TRACE_PID, tid); }

static void trace_write_thread_name(uint32_t tid, const char *name) {
    trace_write_head("M", "thread_name");
    fprintf(trace_writer.file, "\"pid\":%d,\"tid\":%u,\"args\":{\"name\":", TRACE_PID, tid);
    core_json_write_string(trace_writer.file, name);
    fputs("}}", trace_writer.file);
}

/* Timestamps of one tid never go backwards in the file. Viewers and trace_report nest B/E by
 * file order, and ticks can step back a little: a thread that migrates reads another core's
 * TSC, the tick rate is re-estimated at each flush, and trace_complete times come from the
 * caller. Clamping to the previous timestamp keeps nesting intact at the cost of a few ns. */
static uint64_t trace_clamp_to_tid(uint32_t tid, uint64_t ns) {
    if (tid >= trace_writer.last_capacity) {
        size_t old = trace_writer.last_capacity;
        trace_writer.last_ns = core_grow(trace_writer.last_ns, &trace_writer.last_capacity, (size_t)tid + 1,
                                         sizeof *trace_writer.last_ns);
        memset(trace_writer.last_ns + old, 0, (trace_writer.last_capacity - old) * sizeof *trace_writer.last_ns);
    }
    if (ns < trace_writer.last_ns[tid]) ns = trace_writer.last_ns[tid];
    trace_writer.last_ns[tid] = ns;
    return ns;
}

/* Whether to write a BEGIN or END, keeping count of open zones per tid: an END whose BEGIN was
 * not written (dropped with the frames before a trace_keep_frames window) is left out, so the
 * file stays balanced. A capture of everything never meets one. */
static bool trace_balance(uint32_t tid, uint32_t kind) {
    if (kind != TRACE_EVENT_BEGIN && kind != TRACE_EVENT_END) return true;
    if (tid >= trace_writer.depth_capacity) {
        size_t old = trace_writer.depth_capacity;
        trace_writer.depth = core_grow(trace_writer.depth, &trace_writer.depth_capacity, (size_t)tid + 1,
                                       sizeof *trace_writer.depth);
        memset(trace_writer.depth + old, 0, (trace_writer.depth_capacity - old) * sizeof *trace_writer.depth);
    }
    if (kind == TRACE_EVENT_BEGIN) {
        trace_writer.depth[tid]++;
        return true;
    }
    if (trace_writer.depth[tid] == 0) return false;
    trace_writer.depth[tid]--;
    return true;
}

static void trace_write_complete(const trace_event *event) {
    uint64_t begin = event->time > trace_writer.start_ns ? event->time - trace_writer.start_ns : 0;
    uint64_t end = begin + event->payload;
    uint64_t ts = trace_clamp_to_tid(event->lane, begin);
    trace_write_head("X", event->name);
    fputs("\"ts\":", trace_writer.file);
    trace_write_micros(ts);
    fputs(",\"dur\":", trace_writer.file);
    trace_write_micros(end > ts ? end - ts : 0);
    fputc(',', trace_writer.file);
    trace_write_tail(event->lane);
}

/* "args":{...}, for a BEGIN followed by ARG events; returns how many it wrote. */
static uint32_t trace_write_args(const trace_event *args, uint32_t available) {
    FILE *out = trace_writer.file;
    uint32_t n = 0;
    for (; n < available && args[n].kind == TRACE_EVENT_ARG; n++) {
        fputs(n ? "," : "\"args\":{", out);
        core_json_write_string(out, args[n].name ? args[n].name : "");
        fputc(':', out);
        if (args[n].lane == TRACE_ARG_STRING) {
            const char *text = (const char *)(uintptr_t)args[n].payload;
            core_json_write_string(out, text ? text : "");
        } else {
            fprintf(out, "%" PRId64, (int64_t)args[n].payload);
        }
    }
    if (n) fputs("},", out);
    return n;
}

/* Writes one event (a BEGIN with the ARG events after it); returns how many it used. */
static uint32_t trace_write_event(const trace_event *event, uint32_t available, uint32_t tid,
                                  const trace_clock_map *map) {
    if (event->kind == TRACE_EVENT_COMPLETE) {
        trace_write_complete(event);
        return 1;
    }
    if (event->kind == TRACE_EVENT_ARG) return 1; /* its zone was left out: nothing to attach to */
    if (!trace_balance(tid, event->kind)) return 1;
    static const char *const phases[] = { [TRACE_EVENT_BEGIN] = "B", [TRACE_EVENT_END] = "E",
                                          [TRACE_EVENT_COUNTER] = "C" };
    uint64_t ts = trace_clamp_to_tid(tid, trace_ticks_to_ns(map, event->time));
    trace_write_head(phases[event->kind], event->name);
    fputs("\"ts\":", trace_writer.file);
    trace_write_micros(ts);
    fputc(',', trace_writer.file);
    if (event->kind == TRACE_EVENT_COUNTER) {
        double value;
        memcpy(&value, &event->payload, sizeof value);
        fputs("\"args\":{\"value\":", trace_writer.file);
        trace_write_double(value);
        fputs("},", trace_writer.file);
    }
    uint32_t used = 1;
    if (event->kind == TRACE_EVENT_BEGIN) used += trace_write_args(event + 1, available - 1);
    trace_write_tail(tid);
    return used;
}

static void trace_write_events(const trace_chunk *chunk, uint32_t count, const trace_clock_map *map) {
    for (uint32_t i = 0; i < count;) i += trace_write_event(&chunk->events[i], count - i, chunk->tid, map);
}

static void trace_write_chunks(const trace_chunk *first, const trace_clock_map *map) {
    for (const trace_chunk *chunk = first; chunk; chunk = chunk->next)
        trace_write_events(chunk, atomic_load_explicit(&chunk->count, memory_order_acquire), map);
}

/* Copies the names set since the last batch into trace_writer.names (trace_lock held), so that
 * they are written outside the lock. */
static void trace_take_pending_names(void) {
    trace_writer.name_count = 0;
    for (uint32_t tid = 1; tid < trace_registry.tid_count; tid++) {
        trace_tid_name *entry = &trace_registry.names[tid];
        if (!entry->pending) continue;
        trace_writer.names = core_grow(trace_writer.names, &trace_writer.name_capacity, trace_writer.name_count + 1,
                                       sizeof *trace_writer.names);
        trace_writer.names[trace_writer.name_count++] = (trace_name_entry){ tid, entry->name };
        entry->pending = false;
    }
}

static void trace_write_names(void) {
    for (size_t i = 0; i < trace_writer.name_count; i++)
        trace_write_thread_name(trace_writer.names[i].tid, trace_writer.names[i].name);
    trace_writer.name_count = 0;
}

static size_t trace_chunk_list_length(const trace_chunk *first) {
    size_t n = 0;
    for (; first; first = first->next) n++;
    return n;
}

/* trace_keep_frames: holds the chunks back instead of writing them, and returns those now
 * wholly before the window (to go back to the pool). */
static trace_chunk *trace_keep(trace_chunk *full, uint64_t cutoff) {
    if (full) {
        *trace_writer.kept_last = full;
        while (full->next) full = full->next;
        trace_writer.kept_last = &full->next;
    }
    trace_chunk *dropped = NULL, **dropped_last = &dropped;
    while (trace_writer.kept_first && trace_writer.kept_first->handed <= cutoff) {
        trace_chunk *chunk = trace_writer.kept_first;
        trace_writer.kept_first = chunk->next;
        chunk->next = NULL;
        *dropped_last = chunk;
        dropped_last = &chunk->next;
    }
    if (!trace_writer.kept_first) trace_writer.kept_last = &trace_writer.kept_first;
    return dropped;
}

/* One batch: the names and chunks taken under trace_lock, written without it (or, keeping only
 * the last frames, held back). Returns the chunks done with. */
static trace_chunk *trace_write_batch(trace_chunk *full, bool keep, uint64_t cutoff) {
    if (!full && !trace_writer.name_count) return NULL;
    TRACE_ZONE("trace.write");
    trace_zone_arg_int("chunks", (int64_t)trace_chunk_list_length(full));
    trace_write_names();
    if (keep) {
        trace_chunk *dropped = trace_keep(full, cutoff);
        fflush(trace_writer.file);
        return dropped;
    }
    trace_clock_map map = trace_clock_map_now(); /* after the events were taken */
    trace_write_chunks(full, &map);
    /* A run that crashes later still leaves every written event on disk. */
    fflush(trace_writer.file);
    return full;
}

/* The writer thread: waits for chunks (or a flush or stop request), writes them, recycles them.
 * On a stop request it writes what is queued and exits; trace_stop writes the rest. */
static void *trace_writer_main(void *arg) {
    (void)arg;
    trace_thread_name("trace.write");
    pthread_mutex_lock(&trace_lock);
    for (;;) {
        while (!trace_registry.full_first && trace_registry.flush_requested == trace_registry.flush_done &&
               !trace_registry.writer_stop)
            pthread_cond_wait(&trace_work_ready, &trace_lock);
        bool stop = trace_registry.writer_stop, keep = trace_registry.keep_frames > 0;
        uint64_t request = trace_registry.flush_requested, cutoff = trace_registry.cutoff;
        trace_chunk *full = trace_take_full_list();
        trace_take_pending_names();
        pthread_mutex_unlock(&trace_lock);
        trace_chunk *done = trace_write_batch(full, keep, cutoff);
        pthread_mutex_lock(&trace_lock);
        trace_chunks_to_pool(done);
        trace_registry.flush_done = request;
        pthread_cond_broadcast(&trace_written);
        if (stop) break;
    }
    pthread_mutex_unlock(&trace_lock);
    return NULL;
}

/* ---- capture control -------------------------------------------------------------------- */

static void trace_write_header(void) {
    fputs("{\"traceEvents\":[", trace_writer.file);
    trace_write_head("M", "process_name");
    fprintf(trace_writer.file, "\"pid\":%d,\"tid\":0,\"args\":{\"name\":", TRACE_PID);
    core_json_write_string(trace_writer.file, program_invocation_short_name); /* glibc */
    fputs("}}", trace_writer.file);
}

bool trace_start(const char *path) {
    pthread_once(&trace_once, trace_init);
    pthread_mutex_lock(&trace_lock);
    if (trace_capturing()) {
        core_log_error("trace", "cannot start a trace to '%s': one is already being written to '%s'",
                   path, trace_writer.path);
        pthread_mutex_unlock(&trace_lock);
        return false;
    }
    FILE *file = fopen(path, "w");
    if (!file) {
        core_log_error("trace", "cannot write trace file '%s': %s", path, strerror(errno));
        pthread_mutex_unlock(&trace_lock);
        return false;
    }
    /* Chunks handed over after the last stop belong to no capture. */
    trace_chunks_to_pool(trace_take_full_list());
    trace_registry.tid_count = 1;

    setvbuf(file, NULL, _IOFBF, 1 << 20);
    trace_writer.file = file;
    trace_writer.path = core_strdup(path);
    trace_writer.events_written = 0;
    if (trace_writer.last_ns) memset(trace_writer.last_ns, 0, trace_writer.last_capacity * sizeof(uint64_t));
    if (trace_writer.depth) memset(trace_writer.depth, 0, trace_writer.depth_capacity * sizeof(uint32_t));
    trace_writer.kept_first = NULL;
    trace_writer.kept_last = &trace_writer.kept_first;
    trace_registry.frame_count = trace_registry.cutoff = 0;
    if (trace_registry.keep_frames)
        trace_registry.frame_ends = core_calloc((size_t)trace_registry.keep_frames, sizeof(uint64_t));
    trace_writer.start_ns = core_time_ns();
    trace_writer.start_ticks = trace_ticks();
    trace_write_header();

    atomic_fetch_add(&trace_session, 1);
    trace_set_capturing(true);
    trace_registry.writer_stop = false;
    trace_registry.flush_requested = trace_registry.flush_done = 0;
    int error = pthread_create(&trace_registry.writer, NULL, trace_writer_main, NULL);
    trace_registry.writer_running = error == 0;
    pthread_mutex_unlock(&trace_lock);
    if (error) {
        core_log_error("trace", "cannot start the writer thread for '%s': %s", path, strerror(error));
        trace_stop();
        return false;
    }
    return true;
}

void trace_flush(void) {
    if (!trace_active()) return;
    pthread_mutex_lock(&trace_lock);
    if (trace_registry.writer_running && !pthread_equal(pthread_self(), trace_registry.writer)) {
        trace_hand_over_partial(trace_local);
        uint64_t ticket = ++trace_registry.flush_requested;
        pthread_cond_signal(&trace_work_ready);
        while (trace_registry.flush_done < ticket && trace_registry.writer_running && !trace_registry.writer_stop)
            pthread_cond_wait(&trace_written, &trace_lock);
    }
    pthread_mutex_unlock(&trace_lock);
}

/* Live threads keep their chunk (they may still be inside a push), so only their events are
 * read, up to the count each one has published. */
static void trace_write_live_threads(const trace_clock_map *map) {
    uint32_t session = atomic_load(&trace_session);
    for (trace_thread *thread = trace_registry.threads; thread; thread = thread->next) {
        if (thread->session != session || !thread->chunk) continue;
        trace_write_events(thread->chunk, atomic_load_explicit(&thread->chunk->count, memory_order_acquire), map);
    }
}

static void trace_close_file(void) {
    FILE *file = trace_writer.file;
    fputs("\n],\"displayTimeUnit\":\"ms\"}\n", file);
    bool failed = ferror(file) != 0;
    int error = errno;
    if (fclose(file) != 0 && !failed) {
        failed = true;
        error = errno;
    }
    if (failed) core_log_error("trace", "writing trace file '%s' failed: %s", trace_writer.path, strerror(error));
    core_free(trace_writer.path, strlen(trace_writer.path) + 1);
    trace_writer.file = NULL;
    trace_writer.path = NULL;
}

static void trace_free_pool(void) {
    while (trace_registry.pool) {
        trace_chunk *next = trace_registry.pool->next;
        core_free(trace_registry.pool, sizeof *trace_registry.pool);
        atomic_fetch_sub_explicit(&trace_registry.chunks_made, 1, memory_order_relaxed);
        trace_registry.pool = next;
    }
}

/* Asks the writer to write what is queued and exit, and waits for it (trace_lock not held). */
static void trace_join_writer(void) {
    pthread_mutex_lock(&trace_lock);
    bool running = trace_registry.writer_running;
    trace_registry.writer_stop = true;
    pthread_cond_signal(&trace_work_ready);
    pthread_cond_broadcast(&trace_written); /* a trace_flush waiting now returns */
    pthread_mutex_unlock(&trace_lock);
    if (running) pthread_join(trace_registry.writer, NULL);
}

void trace_stop(void) {
    pthread_mutex_lock(&trace_lock);
    bool mine = trace_capturing() && !trace_registry.stopping;
    trace_registry.stopping = trace_registry.stopping || mine;
    pthread_mutex_unlock(&trace_lock);
    if (!mine) return;
    /* The writer's last chunk (its own zones) is handed over as it exits, while the capture runs. */
    trace_join_writer();

    pthread_mutex_lock(&trace_lock);
    trace_set_capturing(false);
    trace_registry.writer_running = false;
    trace_chunk *full = trace_take_full_list();
    trace_take_pending_names();
    trace_clock_map map = trace_clock_map_now();
    trace_write_names();
    if (trace_registry.keep_frames) {
        /* What the writer had not yet taken joins the window, and what is before it goes. */
        trace_chunks_to_pool(trace_keep(full, trace_registry.cutoff));
        full = NULL;
    }
    trace_chunk *kept = trace_writer.kept_first;
    trace_writer.kept_first = NULL;
    trace_writer.kept_last = &trace_writer.kept_first;
    trace_write_chunks(kept, &map);
    trace_write_chunks(full, &map);
    trace_write_live_threads(&map);
    trace_close_file();
    trace_chunks_to_pool(kept);
    trace_chunks_to_pool(full);
    if (trace_registry.frame_ends) core_free(trace_registry.frame_ends, (size_t)trace_registry.keep_frames * sizeof(uint64_t));
    trace_registry.frame_ends = NULL;
    trace_free_pool();
    trace_registry.stopping = false;
    pthread_mutex_unlock(&trace_lock);
}
