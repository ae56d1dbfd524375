/* trace.h — captured traces: zones, counters, frame markers and thread names, written as Chrome
 * Trace Event JSON that Perfetto (ui.perfetto.dev) and chrome://tracing open.
 *
 * CAPTURE
 *     if (!trace_start("run.json")) return 2;   // opens the file now: a bad path fails here
 *     trace_thread_name("main");                // every program names its main thread
 *     for (;;) {
 *         trace_frame_begin();
 *         { TRACE_ZONE("stream"); ... }          // zone closes at the end of the block
 *         trace_zone_begin("mesh"); ...; trace_zone_end();
 *         trace_counter("chunks.resident", n);
 *         trace_frame_end();                     // hands the frame's events to the writer
 *     }
 *     trace_stop();                              // drains the writer, closes the JSON
 *
 *   Zone and counter names must outlive the capture: string literals, or trace_intern(s) for a
 *   name built at run time. Each thread records into its own buffer (no lock on the hot path).
 *   Full buffers, and at trace_frame_end the calling thread's buffer, are handed to a writer
 *   thread that trace_start starts: it formats and writes them, and its work shows as
 *   "trace.write" zones on a lane of its own named "trace.write". No recording thread ever
 *   formats or writes. trace_flush waits until the writer has written everything the calling
 *   thread recorded so far (for tests and benchmarks; it blocks, so not in a frame loop).
 *   With no capture running every call returns after one load of a flag.
 *   trace_keep_frames(n) before trace_start keeps only the last n frames (--trace-frames N).
 *   trace_frame_end also records the counters "memory.bytes" (core_memory_in_use) and
 *   "memory.trace" (trace_memory_bytes: the capture's own buffers). A thread may
 *   name itself before any capture starts; the name is kept. Stop the capture once the other
 *   threads are idle: events recorded while trace_stop runs may be dropped. See README.md.
 *
 * ZONE ARGUMENTS
 *     trace_zone_begin("mesh");                  // or TRACE_ZONE, or a job's zone
 *     trace_zone_arg_int("x", chunk.x);          // right after the zone opens
 *     trace_zone_arg_str("kind", "column");
 *   Arguments go to the zone the calling thread opened last, and are written as the "args" of
 *   its B event (Chrome and Perfetto show them on the slice). Add them before the thread records
 *   anything else (another zone, a counter): an argument that does not directly follow its
 *   zone's begin (or its other arguments) is dropped, as is any past TRACE_ZONE_ARGS_MAX. Keys
 *   and string values must outlive the capture, like names. Each costs about what an event does.
 *
 * FILE
 *   {"traceEvents":[ ... ],"displayTimeUnit":"ms"} with events
 *     {"ph":"B"/"E", "name", "ts", "pid", "tid"}         zones (frames are zones named "frame")
 *     {"ph":"B", ..., "args":{"x":3,"kind":"column"}}    a zone with arguments
 *     {"ph":"X", ..., "dur"}                             zones recorded whole (trace_complete)
 *     {"ph":"C", "name", "ts", "args":{"value":v}}       counters
 *     {"ph":"M", "name":"thread_name", "args":{"name"}}  thread names
 *   ts and dur in microseconds since trace_start. Timestamps are non-decreasing per thread.
 *
 * REPORT
 *   trace_report_load reads such a file back (any Chrome trace with B/E or X events) and
 *   computes frame-time percentiles, per-zone inclusive and self times and per-counter
 *   min / max / mean / last; tools/trace_report prints them and writes an SVG plot of frame
 *   times beside the trace.
 *
 *     trace_report report;
 *     core_error error = {0};
 *     if (!trace_report_load("run.json", &report, &error)) { fprintf(stderr, "%s\n", error.message); return 1; }
 *     trace_report_print(&report, stdout);
 *     trace_slowest slowest;                          // the 5 slowest frames, 8 zones each
 *     trace_report_slowest(&report, 5, 8, &slowest);
 *     trace_slowest_print(&slowest, stdout);
 *     trace_slowest_free(&slowest);                   // its names point into the report
 *     trace_over_budget over;                         // the frames over 8 ms of CPU time
 *     trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 8, .series = "game.cpu_frame_ms" },
 *                              &over, &error);        // false: no such series (error says)
 *     trace_over_budget_print(&over, stdout);
 *     trace_over_budget_free(&over);
 *     trace_report_free(&report);
 *
 *   Self time is a zone's time minus the time of the zones directly nested in it on the same
 *   thread (B/E pairs and X events, nested by time).
 */
#ifndef TRACE_H
#define TRACE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/core.h"   /* core_error */
#include <stdio.h>

/* ---- capture ---------------------------------------------------------------------------- */

bool trace_start(const char *path);
/* Keep only the last `frames` frames (trace_frame_end marks them) of the next captures; 0 (the
 * default) keeps everything. Called with no capture running. The writer then holds chunks in
 * memory instead of writing them, drops those wholly before the window, and trace_stop writes
 * the window: a long run's file stays the size of `frames` frames. An E whose B fell before
 * the window is left out, so every zone in the file is whole or (at the end) open. */
void trace_keep_frames(int frames);
void trace_stop(void);
void trace_flush(void);

extern int trace__active; /* internal: read by the inline fast paths below */
static inline bool trace_active(void) { return __atomic_load_n(&trace__active, __ATOMIC_RELAXED) != 0; }

void trace__zone_begin(const char *name);
void trace__zone_end(void);
static inline void trace_zone_begin(const char *name) { if (trace_active()) trace__zone_begin(name); }
static inline void trace_zone_end(void) { if (trace_active()) trace__zone_end(); }

static inline void trace__scope_end(int *unused) { (void)unused; trace_zone_end(); }
#define TRACE__CAT2(a, b) a##b
#define TRACE__CAT(a, b) TRACE__CAT2(a, b)
/* Opens a zone that closes when the enclosing block ends. */
#define TRACE_ZONE(name)                                                                       \
    int TRACE__CAT(trace__scope_, __LINE__) __attribute__((cleanup(trace__scope_end), unused)) = \
        (trace_zone_begin(name), 0)

enum { TRACE_ZONE_ARGS_MAX = 8 }; /* arguments one zone can carry */
void trace__zone_arg(const char *key, uint64_t value, uint32_t type);
/* An argument of the zone just opened (ZONE ARGUMENTS above). */
static inline void trace_zone_arg_int(const char *key, int64_t value) {
    if (trace_active()) trace__zone_arg(key, (uint64_t)value, 0);
}
static inline void trace_zone_arg_str(const char *key, const char *value) {
    if (trace_active()) trace__zone_arg(key, (uint64_t)(uintptr_t)value, 1);
}

void trace_counter(const char *name, double value);
void trace_thread_name(const char *name);
void trace_frame_begin(void);
void trace_frame_end(void);
/* Bytes of event buffers the capture holds (in use, waiting for the writer or pooled). */
size_t trace_memory_bytes(void);

/* A zone measured elsewhere (e.g. a GPU timer query), on a named lane of its own. Times are
 * trace_now() values. */
void trace_complete(const char *lane, const char *name, uint64_t begin_ns, uint64_t end_ns);
uint64_t trace_now(void);          /* nanoseconds on the trace's clock (CLOCK_MONOTONIC) */
/* A copy of s that lives until the process ends; equal strings share one copy. */
const char *trace_intern(const char *s);

/* ---- report ----------------------------------------------------------------------------- */

typedef struct trace_zone_stats {
    const char *name;
    size_t count;
    double total_ms;               /* inclusive: the sum of the zone's durations */
    double self_ms;                /* total_ms minus the zones directly nested in it, same thread */
    double p99_ms, max_ms;         /* of the inclusive durations */
} trace_zone_stats;

/* One counter series: a "C" event's args {"value": v} is the series NAME; any other args are
 * one series per key, NAME.KEY. Non-numeric values are skipped. */
typedef struct trace_counter_stats {
    const char *name;
    size_t count;                  /* samples */
    double min, max, mean;         /* mean of the samples, not weighted by time */
    double last;                   /* the sample with the latest ts (the later in the file on ties) */
} trace_counter_stats;

typedef struct trace_report_detail trace_report_detail; /* internal: zones and samples for --slowest */

typedef struct trace_report {
    size_t frame_count;
    double *frame_ms;              /* frame durations in file order (the order their ends appear) */
    double frame_p50_ms, frame_p95_ms, frame_p99_ms, frame_max_ms;
    size_t frames_over_16ms, frames_over_33ms;  /* > 16.7 ms and > 33.3 ms */
    trace_zone_stats *zones;       /* sorted by self time, largest first */
    size_t zone_count;
    size_t counter_count;          /* "C" events seen */
    trace_counter_stats *counters; /* one per series, sorted by name */
    size_t counter_series_count;
    trace_report_detail *detail;
} trace_report;

/* False with `error` (may be NULL) set when the trace cannot be read: CORE_ERROR_IO (cannot read
 * the file; load's messages start with the path), CORE_ERROR_FORMAT (not JSON, no traceEvents,
 * an event without its fields, an unbalanced "E", a zone that ends before it begins),
 * CORE_ERROR_RANGE (a negative duration, a time out of range). The report is then empty (free
 * it all the same). */
bool trace_report_load(const char *path, trace_report *report, core_error *error);
bool trace_report_parse(const char *json, size_t size, trace_report *report, core_error *error);
void trace_report_print(const trace_report *report, FILE *out);
/* False with CORE_ERROR_IO in `error` when the file cannot be written. */
bool trace_report_write_svg(const trace_report *report, const char *svg_path, core_error *error);
void trace_report_free(trace_report *report);

/* ---- the slowest frames ----------------------------------------------------------------- */

/* A zone's share of one frame: every instance (any thread) that overlaps the frame's span
 * counts its self time times the part of its duration inside the span. */
typedef struct trace_frame_zone {
    const char *name;              /* points into the report */
    size_t count;                  /* instances overlapping the span */
    double self_ms;                /* self time inside the span */
    double slowest_ms;             /* the longest of those instances (inclusive) */
    const char *args;              /* that instance's args as "key=value key=value"; NULL if none */
} trace_frame_zone;

typedef struct trace_frame_counter {
    const char *name;              /* points into the report */
    double value;                  /* the last sample at or before the frame's end */
} trace_frame_counter;

typedef struct trace_slow_frame {
    size_t index;                  /* into report->frame_ms */
    double start_ms, duration_ms;  /* start on the trace's clock (ts / 1000) */
    trace_frame_zone *zones;       /* by self time inside the frame, largest first */
    size_t zone_count;
    trace_frame_counter *counters; /* series with a sample by the frame's end, by name */
    size_t counter_count;
} trace_slow_frame;

typedef struct trace_slowest {
    trace_slow_frame *frames;      /* slowest first; ties in file order */
    size_t frame_count;            /* min(n, report->frame_count) */
} trace_slowest;

/* Fills *out with the n slowest frames of a loaded report, each with its top_zones zones by
 * self time. Its names and args point into the report: read it while the report lives. The
 * caller frees it with trace_slowest_free. */
void trace_report_slowest(const trace_report *report, size_t n, size_t top_zones, trace_slowest *out);
void trace_slowest_print(const trace_slowest *slowest, FILE *out);
void trace_slowest_free(trace_slowest *slowest);

/* ---- frames over a budget ---------------------------------------------------------------- */

/* Which frames pass a budget, where in the run they fall, and what they spend more on than the
 * frames within it: where a p99 comes from. A frame's value is its duration, or with `series`
 * the last sample of that counter series at or before the frame's end (the game records
 * game.cpu_frame_ms: the main thread's part of a frame, without the wait for the GPU). */
typedef struct trace_budget_desc {
    double budget_ms;              /* frames whose value is over it are "over"; > 0 */
    const char *series;            /* NULL: the frame's duration */
    size_t gap;                    /* over frames this many frames apart or closer share a run
                                      (1: only neighbours); 0 = 30 */
    size_t top_zones;              /* zones kept; 0 = 8 */
} trace_budget_desc;

typedef struct trace_budget_run {
    size_t first, last;            /* its first and last over frame (indices into frame_ms) */
    size_t over;                   /* its frames over the budget */
    double worst_ms;               /* the largest value among them */
} trace_budget_run;

/* A zone's mean self time a frame in each group: its share of the frame's span (as
 * trace_frame_zone's), on the frame's own thread only, where a frame's work is (the other
 * threads' idle and sleep zones would grow with any long frame). */
typedef struct trace_budget_zone {
    const char *name;              /* points into the report */
    double over_ms, within_ms;
} trace_budget_zone;

typedef struct trace_over_budget {
    double budget_ms;
    const char *series;            /* the desc's (NULL: frame durations) */
    size_t frames;                 /* frames with a value: all, or those after the series' first sample */
    size_t over;                   /* of them, over the budget */
    trace_budget_run *runs;        /* in frame order */
    size_t run_count;
    trace_budget_zone *zones;      /* by over_ms − within_ms, largest first; ties by name */
    size_t zone_count;
} trace_over_budget;

/* Fills *out (free it with trace_over_budget_free; its names point into the report). False with
 * CORE_ERROR_ARGUMENT in `error` for a budget that is not > 0 or a series the trace does not
 * have; *out is then empty. */
bool trace_report_over_budget(const trace_report *report, const trace_budget_desc *desc, trace_over_budget *out,
                              core_error *error);
void trace_over_budget_print(const trace_over_budget *over, FILE *out);
void trace_over_budget_free(trace_over_budget *over);

/* Nearest-rank percentile of sorted values: sorted[ceil(p/100 · n) − 1]; 0 for n = 0. */
double trace_percentile(const double *sorted, size_t n, double p);

#endif /* TRACE_H */
