/* Tests of trace capture (engine/trace/trace.c): captures are written to temporary files and
 * read back with core_json, then checked for the invariants trace.h promises. Also built under
 * ThreadSanitizer (see test.h): every test here starts and stops its own capture. */
#include "core/core.h"
#include "trace/trace.h"

#include "test.h"
#include "trace_file.h"
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- helpers ---------------------------------------------------------------------------- */

typedef struct capture {
    core_arena arena;
    core_json_value *root;
    const core_json_value *events; /* the traceEvents array */
} capture;

static void temp_trace_path(char *path, size_t size, const char *tag) {
    snprintf(path, size, "/tmp/engine_test_trace_%d_%s.json", (int)getpid(), tag);
}


/* Reads a trace file back (and deletes it); fails the test unless it is valid JSON of the
 * {"traceEvents":[...],"displayTimeUnit":"ms"} shape. */
static void capture_load(capture *c, const char *path) {
    *c = (capture){ 0 };
    c->events = trace_file_load(path, &c->arena, &c->root);
    cr_expect(core_json_string_equals(core_json_get(c->root, "displayTimeUnit"), "ms"));
}

static void capture_free(capture *c) { core_arena_release(&c->arena); }

static const core_json_value *event_at(const capture *c, size_t i) { return &c->events->array.items[i]; }
static bool event_is(const core_json_value *e, const char *ph) { return core_json_string_equals(core_json_get(e, "ph"), ph); }
static double event_number(const core_json_value *e, const char *key) { return core_json_number_or(core_json_get(e, key), NAN); }

/* Events of phase `ph` (and name, unless NULL), on `tid` unless tid < 0. */
static size_t count_events(const capture *c, const char *ph, const char *name, double tid) {
    size_t n = 0;
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = event_at(c, i);
        if (!event_is(e, ph)) continue;
        if (name && !core_json_string_equals(core_json_get(e, "name"), name)) continue;
        if (tid >= 0 && event_number(e, "tid") != tid) continue;
        n++;
    }
    return n;
}

/* The tid a thread_name metadata event gives `name`; -1 when there is none. */
static double tid_named(const capture *c, const char *name) {
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = event_at(c, i);
        if (!event_is(e, "M") || !core_json_string_equals(core_json_get(e, "name"), "thread_name")) continue;
        if (core_json_string_equals(core_json_get(core_json_get(e, "args"), "name"), name)) return event_number(e, "tid");
    }
    return -1;
}

/* B events other than the writer's own "trace.write" zones. */
static size_t count_recorded_zones(const capture *c) {
    return count_events(c, "B", NULL, -1) - count_events(c, "B", "trace.write", -1);
}

static const core_json_value *first_event_named(const capture *c, const char *ph, const char *name) {
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = event_at(c, i);
        if (event_is(e, ph) && core_json_string_equals(core_json_get(e, "name"), name)) return e;
    }
    return NULL;
}

/* trace.h's promises for every tid: ts never goes back in file order, every E closes an open
 * B, and nothing is left open once the capture stopped. */
static void check_invariants(const capture *c) {
    enum { MAX_TIDS = 64 };
    double last_ts[MAX_TIDS];
    int depth[MAX_TIDS] = { 0 };
    for (int t = 0; t < MAX_TIDS; t++) last_ts[t] = -1;
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = event_at(c, i);
        cr_assert_eq(e->type, CORE_JSON_OBJECT);
        cr_assert(event_number(e, "pid") == 1, "event %zu: pid", i);
        double tid = event_number(e, "tid");
        cr_assert(tid >= 0 && tid < MAX_TIDS, "event %zu: tid %g", i, tid);
        if (event_is(e, "M")) continue;
        double ts = event_number(e, "ts");
        cr_assert(ts >= 0, "event %zu: ts %g", i, ts);
        int t = (int)tid;
        cr_assert(ts >= last_ts[t], "event %zu: ts %.3f after %.3f on tid %d", i, ts, last_ts[t], t);
        last_ts[t] = ts;
        if (event_is(e, "B")) depth[t]++;
        if (event_is(e, "E")) cr_assert(--depth[t] >= 0, "event %zu: E with no open B on tid %d", i, t);
    }
    for (int t = 0; t < MAX_TIDS; t++) cr_expect_eq(depth[t], 0, "tid %d left %d zones open", t, depth[t]);
}

/* ---- several threads -------------------------------------------------------------------- */

enum { WORKERS = 4, WORKER_ITERATIONS = 3000 };

static void *record_work(void *arg) {
    char name[32];
    snprintf(name, sizeof name, "worker %d", (int)(intptr_t)arg);
    trace_thread_name(name); /* the name is copied */
    for (int i = 0; i < WORKER_ITERATIONS; i++) {
        TRACE_ZONE("outer");
        trace_zone_begin("inner");
        trace_zone_end();
        trace_counter("progress", i);
    }
    return NULL;
}

Test(trace_capture, capture_from_several_threads) {
    char path[128];
    temp_trace_path(path, sizeof path, "threads");
    cr_assert(trace_start(path));
    trace_thread_name("main");
    pthread_t workers[WORKERS];
    for (int i = 0; i < WORKERS; i++) pthread_create(&workers[i], NULL, record_work, (void *)(intptr_t)i);
    /* Frames on the main thread flush handed-over chunks while the workers record. */
    for (int frame = 0; frame < 3; frame++) {
        trace_frame_begin();
        { TRACE_ZONE("update"); usleep(1000); }
        trace_frame_end();
    }
    for (int i = 0; i < WORKERS; i++) pthread_join(workers[i], NULL);
    size_t buffers = trace_memory_bytes();
    trace_stop();
    /* Every worker filled buffers of its own (64 KiB: 2048 events of 32 bytes, trace.c), which
     * go back to the pool, not away. */
    cr_expect_geq(buffers, (size_t)WORKERS * 2048 * 32, "%zu bytes of buffers", buffers);

    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    /* Each iteration is 5 events, 15 000 per worker: several 2048-event chunks each, so the
     * hand-over path and the exit of a thread with a half-full chunk both ran. */
    cr_expect_eq(count_events(&c, "B", "outer", -1), WORKERS * WORKER_ITERATIONS);
    cr_expect_eq(count_events(&c, "B", "inner", -1), WORKERS * WORKER_ITERATIONS);
    cr_expect_eq(count_events(&c, "C", "progress", -1), WORKERS * WORKER_ITERATIONS);
    cr_expect_eq(count_events(&c, "B", "frame", -1), 3);
    cr_expect_eq(count_events(&c, "B", "update", -1), 3);
    cr_expect_eq(count_events(&c, "C", "memory.bytes", -1), 3); /* one per trace_frame_end */
    cr_expect_eq(count_events(&c, "C", "memory.trace", -1), 3);
    cr_expect_eq(count_events(&c, "B", NULL, -1), count_events(&c, "E", NULL, -1));

    double main_tid = tid_named(&c, "main");
    cr_expect_gt(main_tid, 0);
    cr_expect_eq(count_events(&c, "B", "frame", main_tid), 3);
    for (int w = 0; w < WORKERS; w++) {
        char name[32];
        snprintf(name, sizeof name, "worker %d", w);
        double tid = tid_named(&c, name);
        cr_assert_gt(tid, 0, "no thread_name for %s", name);
        cr_expect_neq(tid, main_tid);
        cr_expect_eq(count_events(&c, "B", "outer", tid), WORKER_ITERATIONS);
        /* The counter of one thread reads 0, 1, 2, … in file order: no chunk lost or swapped. */
        double expected = 0;
        for (size_t i = 0; i < c.events->array.count; i++) {
            const core_json_value *e = event_at(&c, i);
            if (!event_is(e, "C") || event_number(e, "tid") != tid) continue;
            double value = core_json_number_or(core_json_get(core_json_get(e, "args"), "value"), NAN);
            cr_assert(value == expected, "%s: counter %g, expected %g", name, value, expected);
            expected++;
        }
        cr_expect(expected == WORKER_ITERATIONS);
    }
    capture_free(&c);
}

/* ---- a thread still alive at trace_stop ------------------------------------------------- */

typedef struct handshake {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    bool recorded, stopped;
} handshake;

static void *record_then_wait(void *arg) {
    handshake *h = arg;
    for (int i = 0; i < 100; i++) { TRACE_ZONE("held"); }
    pthread_mutex_lock(&h->lock);
    h->recorded = true;
    pthread_cond_broadcast(&h->changed);
    while (!h->stopped) pthread_cond_wait(&h->changed, &h->lock);
    pthread_mutex_unlock(&h->lock);
    return NULL;
}

Test(trace_capture, stop_writes_threads_that_are_still_running) {
    char path[128];
    temp_trace_path(path, sizeof path, "live");
    handshake h = { .lock = PTHREAD_MUTEX_INITIALIZER, .changed = PTHREAD_COND_INITIALIZER };
    cr_assert(trace_start(path));
    pthread_t thread;
    pthread_create(&thread, NULL, record_then_wait, &h);
    pthread_mutex_lock(&h.lock);
    while (!h.recorded) pthread_cond_wait(&h.changed, &h.lock);
    pthread_mutex_unlock(&h.lock);
    trace_stop(); /* the thread is alive, its 200 events in a chunk it still holds */
    pthread_mutex_lock(&h.lock);
    h.stopped = true;
    pthread_cond_broadcast(&h.changed);
    pthread_mutex_unlock(&h.lock);
    pthread_join(thread, NULL);

    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    cr_expect_eq(count_events(&c, "B", "held", -1), 100);
    cr_expect_eq(count_events(&c, "E", NULL, -1), 100);
    capture_free(&c);
}

/* ---- start and stop --------------------------------------------------------------------- */

Test(trace_capture, start_fails_on_an_unwritable_path) {
    cr_expect_not(trace_start("/nonexistent-dir/x.json"));
    cr_expect_not(trace_active());
    /* With no capture these are no-ops. */
    trace_zone_begin("nothing");
    trace_zone_end();
    trace_counter("nothing", 1);
    trace_flush();
    trace_stop();
    /* A failed start leaves the module ready for a good one. */
    char path[128];
    temp_trace_path(path, sizeof path, "after_failure");
    cr_assert(trace_start(path));
    { TRACE_ZONE("ok"); }
    trace_stop();
    capture c;
    capture_load(&c, path);
    cr_expect_eq(count_events(&c, "B", "ok", -1), 1);
    capture_free(&c);
}

static void *record_second(void *unused) {
    (void)unused;
    { TRACE_ZONE("second"); }
    return NULL;
}

Test(trace_capture, start_and_stop_twice_in_one_process) {
    char first_path[128], second_path[128];
    temp_trace_path(first_path, sizeof first_path, "first");
    temp_trace_path(second_path, sizeof second_path, "second");
    trace_thread_name("control"); /* named before any capture: kept for both */

    cr_assert(trace_start(first_path));
    cr_expect_not(trace_start(second_path)); /* one capture at a time */
    for (int i = 0; i < 3; i++) { TRACE_ZONE("first"); }
    trace_stop();
    trace_stop(); /* a second stop is harmless */
    { TRACE_ZONE("between"); } /* not captured */

    cr_assert(trace_start(second_path));
    { TRACE_ZONE("second"); }
    pthread_t thread;
    pthread_create(&thread, NULL, record_second, NULL);
    pthread_join(thread, NULL);
    trace_stop();

    capture first, second;
    capture_load(&first, first_path);
    capture_load(&second, second_path);
    check_invariants(&first);
    check_invariants(&second);
    cr_expect_eq(count_events(&first, "B", "first", -1), 3);
    cr_expect_eq(count_recorded_zones(&first), 3);
    cr_expect_eq(count_events(&second, "B", "second", -1), 2);
    cr_expect_eq(count_recorded_zones(&second), 2);
    /* tids restart with each capture: this thread recorded first both times. */
    cr_expect(tid_named(&first, "control") == 1);
    cr_expect(tid_named(&second, "control") == 1);
    cr_expect_eq(count_events(&second, "B", "second", 1), 1);
    cr_expect_eq(count_events(&second, "B", "second", 2), 1);
    capture_free(&first);
    capture_free(&second);
}

Test(trace_capture, nothing_recorded_is_still_a_valid_file) {
    char path[128];
    temp_trace_path(path, sizeof path, "empty");
    cr_assert(trace_start(path));
    trace_stop();
    capture c;
    capture_load(&c, path);
    /* Only the process name. */
    cr_expect_eq(c.events->array.count, 1);
    cr_expect(core_json_string_equals(core_json_get(event_at(&c, 0), "name"), "process_name"));
    capture_free(&c);
}

/* ---- contents --------------------------------------------------------------------------- */

Test(trace_capture, complete_events_go_on_named_lanes) {
    char path[128];
    temp_trace_path(path, sizeof path, "lanes");
    cr_assert(trace_start(path));
    { TRACE_ZONE("cpu"); }
    uint64_t t0 = trace_now();
    trace_complete("GPU", "shadows", t0, t0 + 2000000);          /* 2 ms = 2000 µs */
    trace_complete("GPU", "lights", t0 + 2000000, t0 + 2500000); /* 0.5 ms = 500 µs */
    trace_complete("copy", "upload", t0, t0 + 1000);             /* 1 µs */
    trace_stop();

    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    double cpu_tid = event_number(first_event_named(&c, "B", "cpu"), "tid");
    double gpu_tid = tid_named(&c, "GPU"), copy_tid = tid_named(&c, "copy");
    cr_expect_gt(gpu_tid, 0);
    cr_expect_gt(copy_tid, 0);
    cr_expect_neq(gpu_tid, cpu_tid);
    cr_expect_neq(copy_tid, cpu_tid);
    cr_expect_neq(gpu_tid, copy_tid);

    const core_json_value *shadows = first_event_named(&c, "X", "shadows");
    const core_json_value *lights = first_event_named(&c, "X", "lights");
    const core_json_value *upload = first_event_named(&c, "X", "upload");
    cr_assert(shadows && lights && upload);
    cr_expect(event_number(shadows, "tid") == gpu_tid);
    cr_expect(event_number(lights, "tid") == gpu_tid);
    cr_expect(event_number(upload, "tid") == copy_tid);
    cr_expect_float_eq(event_number(shadows, "dur"), 2000.0, 1e-9);
    cr_expect_float_eq(event_number(lights, "dur"), 500.0, 1e-9);
    cr_expect_float_eq(event_number(upload, "dur"), 1.0, 1e-9);
    /* lights starts where shadows ends. */
    cr_expect_float_eq(event_number(lights, "ts") - event_number(shadows, "ts"), 2000.0, 1e-6);
    cr_expect(event_number(shadows, "ts") == event_number(upload, "ts"));
    capture_free(&c);
}

Test(trace_capture, lane_times_never_go_back) {
    /* Lane events are written in the order they were recorded. One that starts before the one
     * written last is moved to start with it and keeps its end: "late" spans 1–2 µs, "early"
     * 0–5 µs, so "early" is written as 1–5 µs, a duration of 4 µs. */
    char path[128];
    temp_trace_path(path, sizeof path, "lane_order");
    cr_assert(trace_start(path));
    uint64_t t0 = trace_now();
    trace_complete("GPU", "late", t0 + 1000, t0 + 2000);
    trace_complete("GPU", "early", t0, t0 + 5000);
    trace_stop();
    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    const core_json_value *late = first_event_named(&c, "X", "late");
    const core_json_value *early = first_event_named(&c, "X", "early");
    cr_assert(late && early);
    cr_expect(event_number(early, "ts") == event_number(late, "ts"));
    cr_expect_float_eq(event_number(late, "dur"), 1.0, 1e-9);
    cr_expect_float_eq(event_number(early, "dur"), 4.0, 1e-9);
    capture_free(&c);
}

Test(trace_capture, names_are_escaped) {
    char path[128];
    temp_trace_path(path, sizeof path, "escaped");
    const char *odd = "say \"hi\"\n\\ \xe2\x82\xac";
    cr_assert(trace_start(path));
    { TRACE_ZONE(odd); }
    trace_counter(odd, 1);
    trace_thread_name("tab\there");
    trace_stop();
    capture c;
    capture_load(&c, path);
    cr_expect_eq(count_events(&c, "B", odd, -1), 1);
    cr_expect_eq(count_events(&c, "C", odd, -1), 1);
    cr_expect_gt(tid_named(&c, "tab\there"), 0);
    capture_free(&c);
    trace_thread_name("main"); /* do not leave an odd name to later tests in this process */
}

Test(trace_capture, counter_values_read_back_exactly) {
    char path[128];
    temp_trace_path(path, sizeof path, "counters");
    const double values[] = { 0.1, -3.5, 1e300, 12345678901234567.0, 0.0, 1.0 / 3.0 };
    cr_assert(trace_start(path));
    for (size_t i = 0; i < CORE_COUNTOF(values); i++) trace_counter("value", values[i]);
    trace_counter("value", NAN);      /* not representable in JSON: skipped */
    trace_counter("value", INFINITY); /* likewise */
    trace_stop();
    capture c;
    capture_load(&c, path);
    cr_assert_eq(count_events(&c, "C", "value", -1), CORE_COUNTOF(values));
    size_t next = 0;
    for (size_t i = 0; i < c.events->array.count; i++) {
        const core_json_value *e = event_at(&c, i);
        if (!event_is(e, "C")) continue;
        double value = core_json_number_or(core_json_get(core_json_get(e, "args"), "value"), NAN);
        cr_expect(value == values[next], "counter %zu: %.17g, expected %.17g", next, value, values[next]);
        next++;
    }
    capture_free(&c);
}

Test(trace_capture, zone_times_follow_the_clock) {
    char path[128];
    temp_trace_path(path, sizeof path, "clock");
    uint64_t before = core_time_ns();
    cr_assert(trace_start(path));
    { TRACE_ZONE("sleep"); usleep(20000); } /* at least 20 ms = 20 000 µs */
    trace_stop();
    uint64_t elapsed_us = (core_time_ns() - before) / 1000;
    capture c;
    capture_load(&c, path);
    const core_json_value *begin = first_event_named(&c, "B", "sleep");
    cr_assert_not_null(begin);
    double end_ts = NAN;
    for (size_t i = 0; i < c.events->array.count; i++)
        if (event_is(event_at(&c, i), "E")) end_ts = event_number(event_at(&c, i), "ts");
    double duration_us = end_ts - event_number(begin, "ts");
    /* The tick rate is measured against CLOCK_MONOTONIC; allow 0.5 % for the estimate. */
    cr_expect_geq(duration_us, 20000 * 0.995, "zone lasted %.3f µs", duration_us);
    cr_expect_leq(end_ts, (double)elapsed_us * 1.005, "zone ended at %.3f µs of %llu", end_ts,
                  (unsigned long long)elapsed_us);
    capture_free(&c);
}

Test(trace_capture, flush_writes_full_chunks_and_memory_stays_bounded) {
    char path[128];
    temp_trace_path(path, sizeof path, "bounded");
    cr_assert(trace_start(path));
    size_t memory_at_frame_5 = 0;
    for (int frame = 0; frame < 40; frame++) {
        trace_frame_begin();
        for (int i = 0; i < 3000; i++) { TRACE_ZONE("busy"); }
        trace_frame_end();
        /* The writer runs beside this thread; waiting for it here makes the memory bound below
         * exact (a writer that keeps up), which a game relies on but cannot wait for. */
        trace_flush();
        if (frame == 5) memory_at_frame_5 = core_memory_in_use();
        if (frame == 10) {
            /* 11 frames × 6000 events, all handed over at frame ends and written by now. */
            struct stat st;
            cr_assert_eq(stat(path, &st), 0);
            cr_expect_gt(st.st_size, 11 * 4000 * 40, "only %lld bytes on disk", (long long)st.st_size);
        }
    }
    /* Chunks the writer wrote are reused, so 34 more frames took no more memory. Two chunks
     * (2 × 64 KiB) of slack cover a frame that happens to straddle one more. */
    size_t memory_at_frame_39 = core_memory_in_use();
    cr_expect_leq(memory_at_frame_39, memory_at_frame_5 + 2 * 66000, "grew from %zu to %zu bytes",
                  memory_at_frame_5, memory_at_frame_39);
    trace_stop();
    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    cr_expect_eq(count_events(&c, "B", "busy", -1), 40 * 3000);
    cr_expect_eq(count_events(&c, "B", "frame", -1), 40);
    capture_free(&c);
}

Test(trace_capture, intern_keeps_one_copy_per_string) {
    char buffer[32] = "chunk 12";
    const char *a = trace_intern(buffer);
    cr_expect_neq((const void *)a, (const void *)buffer);
    cr_expect_str_eq(a, "chunk 12");
    strcpy(buffer, "chunk 13");
    const char *b = trace_intern(buffer);
    cr_expect_str_eq(a, "chunk 12"); /* unchanged by the caller's buffer */
    cr_expect_str_eq(b, "chunk 13");
    cr_expect_eq((const void *)trace_intern("chunk 12"), (const void *)a);
    /* Many strings: the table grows and keeps every earlier copy. */
    for (int i = 0; i < 2000; i++) {
        snprintf(buffer, sizeof buffer, "name %d", i);
        cr_assert_str_eq(trace_intern(buffer), buffer);
    }
    cr_expect_eq((const void *)trace_intern("chunk 13"), (const void *)b);
}

/* ---- the writer thread ------------------------------------------------------------------ */

/* The frame thread never formats or writes: every "trace.write" zone is on the writer's own
 * named lane, and none on the lane of the thread that ends the frames. */
Test(trace_capture, writing_happens_on_the_writer_lane) {
    char path[128];
    temp_trace_path(path, sizeof path, "writer");
    cr_assert(trace_start(path));
    trace_thread_name("main");
    pthread_t workers[WORKERS];
    for (int i = 0; i < WORKERS; i++) pthread_create(&workers[i], NULL, record_work, (void *)(intptr_t)i);
    for (int frame = 0; frame < 10; frame++) {
        trace_frame_begin();
        for (int i = 0; i < 3000; i++) { TRACE_ZONE("busy"); } /* several chunks a frame */
        usleep(1000);
        trace_frame_end();
    }
    for (int i = 0; i < WORKERS; i++) pthread_join(workers[i], NULL);
    trace_stop();

    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    double main_tid = tid_named(&c, "main"), writer_tid = tid_named(&c, "trace.write");
    cr_assert_gt(main_tid, 0);
    cr_assert_gt(writer_tid, 0, "no thread_name event for the writer's lane");
    cr_expect_neq(writer_tid, main_tid);
    size_t writes = count_events(&c, "B", "trace.write", -1);
    cr_expect_gt(writes, 0);
    cr_expect_eq(count_events(&c, "B", "trace.write", writer_tid), writes, "a write zone off the writer's lane");
    cr_expect_eq(count_events(&c, "B", "trace.write", main_tid), 0);
    /* The writer records only its own zones, and each says how many chunks it wrote. */
    for (size_t i = 0; i < c.events->array.count; i++) {
        const core_json_value *e = event_at(&c, i);
        if (event_number(e, "tid") != writer_tid || event_is(e, "M") || event_is(e, "E")) continue;
        cr_expect(core_json_string_equals(core_json_get(e, "name"), "trace.write"));
        cr_expect_geq(core_json_number_or(core_json_get(core_json_get(e, "args"), "chunks"), -1), 0);
    }
    capture_free(&c);
}

/* trace_flush returns once the writer has written what the caller recorded. */
Test(trace_capture, flush_waits_for_the_writer) {
    char path[128];
    temp_trace_path(path, sizeof path, "flush_waits");
    cr_assert(trace_start(path));
    for (int i = 0; i < 10; i++) { TRACE_ZONE("before.flush"); }
    trace_flush();
    size_t size;
    char *text = trace_file_read(path, &size);
    size_t found = 0;
    for (const char *p = text; (p = strstr(p, "\"before.flush\"")) != NULL; p++) found++;
    free(text);
    cr_expect_eq(found, 10, "%zu of 10 zones on disk after trace_flush", found);
    trace_stop();
    capture c;
    capture_load(&c, path);
    capture_free(&c);
}

/* ---- zone arguments --------------------------------------------------------------------- */

static const core_json_value *zone_args(const capture *c, const char *name, size_t nth) {
    for (size_t i = 0; i < c->events->array.count; i++) {
        const core_json_value *e = event_at(c, i);
        if (!event_is(e, "B") || !core_json_string_equals(core_json_get(e, "name"), name)) continue;
        if (nth-- == 0) return core_json_get(e, "args");
    }
    return NULL;
}

Test(trace_capture, zone_arguments_are_written_as_args) {
    char path[128];
    temp_trace_path(path, sizeof path, "args");
    cr_assert(trace_start(path));
    {
        TRACE_ZONE("chunk");
        trace_zone_arg_int("x", -3);
        trace_zone_arg_int("big", INT64_C(1) << 40);
        trace_zone_arg_str("kind", "col\"umn");
        {
            TRACE_ZONE("inner"); /* nested: its argument is its own */
            trace_zone_arg_int("columns", 17);
        }
        trace_zone_arg_int("late", 1); /* not right after its zone's begin: dropped */
    }
    {
        TRACE_ZONE("plain");
        trace_counter("between", 1);
        trace_zone_arg_int("dropped", 2); /* after a counter: dropped */
    }
    {
        TRACE_ZONE("many");
        for (int i = 0; i < TRACE_ZONE_ARGS_MAX + 3; i++) trace_zone_arg_int(trace_intern((char[]){ (char)('a' + i), 0 }), i);
    }
    /* Zones whose begin lands at the end of a full chunk: their arguments must follow them into
     * the next chunk. 2048 events a chunk; zones of 1 B + 2 args + 1 E shift the phase by 4. */
    for (int i = 0; i < 1100; i++) {
        TRACE_ZONE("edge");
        trace_zone_arg_int("i", i);
        trace_zone_arg_int("twice", 2 * i);
        if (i % 3 == 0) trace_counter("pad", i); /* vary the phase so every offset occurs */
    }
    trace_stop();

    capture c;
    capture_load(&c, path); /* valid JSON, or the test fails here */
    check_invariants(&c);
    const core_json_value *args = zone_args(&c, "chunk", 0);
    cr_assert_not_null(args);
    cr_expect(core_json_number_or(core_json_get(args, "x"), 0) == -3);
    cr_expect(core_json_number_or(core_json_get(args, "big"), 0) == 1099511627776.0);
    cr_expect(core_json_string_equals(core_json_get(args, "kind"), "col\"umn"));
    cr_expect_null(core_json_get(args, "late"));
    cr_expect_null(core_json_get(args, "columns"));
    const core_json_value *inner = zone_args(&c, "inner", 0);
    cr_assert_not_null(inner);
    cr_expect(core_json_number_or(core_json_get(inner, "columns"), 0) == 17);
    cr_expect_null(zone_args(&c, "plain", 0));
    const core_json_value *many = zone_args(&c, "many", 0);
    cr_assert_not_null(many);
    cr_expect_eq(many->type, CORE_JSON_OBJECT);
    cr_expect_eq(many->object.count, (size_t)TRACE_ZONE_ARGS_MAX);
    for (int i = 0; i < 1100; i++) {
        const core_json_value *edge = zone_args(&c, "edge", (size_t)i);
        cr_assert_not_null(edge, "edge zone %d lost its arguments", i);
        cr_assert(core_json_number_or(core_json_get(edge, "i"), -1) == i, "edge zone %d", i);
        cr_assert(core_json_number_or(core_json_get(edge, "twice"), -1) == 2 * i, "edge zone %d", i);
    }
    capture_free(&c);
}

/* ---- keeping the last frames ------------------------------------------------------------ */

enum { KEEP_FRAMES = 5, KEEP_RUN = 30, KEEP_WORKER_ZONES = 3000 };

typedef struct keep_lockstep {
    pthread_barrier_t frame_started, worker_done;
} keep_lockstep;

/* Records KEEP_WORKER_ZONES zones (6000 events: ~3 chunks) inside each of the main thread's
 * frames, and a zone "long" open across all of them. */
static void *record_in_lockstep(void *arg) {
    keep_lockstep *lockstep = arg;
    trace_thread_name("keeper");
    trace_zone_begin("long");
    for (int frame = 0; frame < KEEP_RUN; frame++) {
        pthread_barrier_wait(&lockstep->frame_started);
        for (int i = 0; i < KEEP_WORKER_ZONES; i++) { TRACE_ZONE("w"); }
        if (frame == KEEP_RUN - 1) trace_zone_end(); /* "long" ends in the last frame */
        pthread_barrier_wait(&lockstep->worker_done);
    }
    return NULL;
}

/* trace_keep_frames(5) over 30 frames: the file has exactly the last 5 frames of the main thread
 * (their counters read 25 … 29), a worker's zones only from about those frames (a chunk of 2048
 * events spans at most two frames of 6000, so between 5 and 7 frames' worth), and it stays
 * balanced: "long", whose B fell before the window, is left out whole. */
Test(trace_capture, keep_frames_writes_only_the_last_frames) {
    char path[128];
    temp_trace_path(path, sizeof path, "keep");
    trace_keep_frames(KEEP_FRAMES);
    cr_assert(trace_start(path));
    keep_lockstep lockstep;
    pthread_barrier_init(&lockstep.frame_started, NULL, 2);
    pthread_barrier_init(&lockstep.worker_done, NULL, 2);
    pthread_t worker;
    pthread_create(&worker, NULL, record_in_lockstep, &lockstep);
    for (int frame = 0; frame < KEEP_RUN; frame++) {
        trace_frame_begin();
        trace_counter("frame.index", frame);
        pthread_barrier_wait(&lockstep.frame_started);
        pthread_barrier_wait(&lockstep.worker_done);
        trace_frame_end();
    }
    pthread_join(worker, NULL);
    trace_stop();
    trace_keep_frames(0); /* later captures in this process keep everything */
    pthread_barrier_destroy(&lockstep.frame_started);
    pthread_barrier_destroy(&lockstep.worker_done);

    capture c;
    capture_load(&c, path);
    check_invariants(&c);
    cr_expect_eq(count_events(&c, "B", "frame", -1), KEEP_FRAMES);
    cr_expect_eq(count_events(&c, "C", "frame.index", -1), KEEP_FRAMES);
    double expected = KEEP_RUN - KEEP_FRAMES;
    for (size_t i = 0; i < c.events->array.count; i++) {
        const core_json_value *e = event_at(&c, i);
        if (!event_is(e, "C") || !core_json_string_equals(core_json_get(e, "name"), "frame.index")) continue;
        double value = core_json_number_or(core_json_get(core_json_get(e, "args"), "value"), NAN);
        cr_expect(value == expected, "frame.index %g, expected %g", value, expected);
        expected++;
    }
    size_t worker_zones = count_events(&c, "B", "w", -1);
    cr_expect_geq(worker_zones, (size_t)(KEEP_FRAMES * KEEP_WORKER_ZONES));
    cr_expect_leq(worker_zones, (size_t)((KEEP_FRAMES + 2) * KEEP_WORKER_ZONES));
    cr_expect_eq(count_events(&c, "B", "long", -1), 0);
    cr_expect_gt(tid_named(&c, "keeper"), 0, "names are kept whatever the window");
    capture_free(&c);
}
