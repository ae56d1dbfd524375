/* Tests of the trace report's drill-down (engine/trace/trace_report.c): self times, counter
 * series and the slowest frames, on a hand-built trace whose numbers are worked out by hand in
 * the comments below. */
#include "core/core.h"
#include "trace/trace.h"

#include "test.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* All times in µs in the file, ms in the comments.
 *
 * tid 1 (main)
 *   frame 0   0 → 10      A 2 → 8 (args chunk "3,0,-2") holds B 3 → 5 and an X "x1" 6 → 7
 *                         (an X nested by time in a B/E zone).
 *             self: B 2, x1 1, A 6 − 2 − 1 = 3, frame 10 − 6 = 4
 *   frame 1  10 → 40      wait 12 → 36 holds a stolen job gen 13 → 33 (chunk "1,0,0"), which
 *                         holds an X "noise" 14 → 19 (args octaves 4, scale 0.5).
 *             self: noise 5, gen 20 − 5 = 15, wait 24 − 20 = 4, frame 30 − 24 = 6
 *   frame 2  40 → 55      A 41 → 43 (chunk "0,0,1").  self: A 2, frame 15 − 2 = 13
 * tid 2 (worker)
 *   gen 1 → 9 (chunk "2,0,0") holds mesh 4 → 6, whose args come on its E (bytes 512).
 *             self: mesh 2, gen 8 − 2 = 6
 *   gen 38 → 46 (chunk "5,0,5"), straddling frames 1 and 2.  self 8
 * tid 3
 *   outer 0 → 4 and inner 0 → 4: equal spans nest in the order of their B events.
 *             self: inner 4, outer 0
 *
 * Per zone (count, inclusive total, self total, max):
 *   gen    3   20 + 8 + 8 = 36   15 + 6 + 8 = 29   20
 *   frame  3   10 + 30 + 15 = 55  4 + 6 + 13 = 23  30
 *   A      2   6 + 2 = 8          3 + 2 = 5         6
 *   noise  1   5                  5                 5
 *   wait   1   24                 4                 24
 *   inner  1   4                  4                 4
 *   B      1   2                  2                 2
 *   mesh   1   2                  2                 2
 *   x1     1   1                  1                 1
 *   outer  1   4                  0                 4
 * By self time, largest first; ties by inclusive total (A 8 before noise 5, wait 24 before
 * inner 4), then by name (B before mesh).
 * The self times add up to the time the threads' outermost zones cover:
 * tid 1 55 + tid 2 16 + tid 3 4 = 75 = 29 + 23 + 5 + 5 + 4 + 4 + 2 + 2 + 1 + 0.
 *
 * Counters (C events; ts in ms):
 *   mem     {"value"}: 100 @5, 200 @45 (written by tid 2, earlier in the file), 300 @20
 *           → min 100, max 300, mean 200, last 200 (latest ts, not the file's last)
 *   jobs    {"run","stolen"}: (4, 1) @9, (10, 3) @40 (exactly frame 1's end)
 *           → jobs.run 4/10/7/10, jobs.stolen 1/3/2/3
 *   queue   {"value","peak"}: (7, 9) @50 → two keys, so queue.value 7 and queue.peak 9
 *   odd     {"value":"x"}: not a number, no series
 *   7 C events, 5 series: jobs.run, jobs.stolen, mem, queue.peak, queue.value.
 */
static const char *const drill_trace =
    "{\"traceEvents\":[\n"
    "{\"ph\":\"M\",\"name\":\"thread_name\",\"pid\":1,\"tid\":1,\"args\":{\"name\":\"main\"}},\n"
    "{\"ph\":\"B\",\"name\":\"outer\",\"ts\":0,\"pid\":1,\"tid\":3},\n"
    "{\"ph\":\"B\",\"name\":\"inner\",\"ts\":0,\"pid\":1,\"tid\":3},\n"
    "{\"ph\":\"E\",\"ts\":4000,\"pid\":1,\"tid\":3},\n"
    "{\"ph\":\"E\",\"ts\":4000,\"pid\":1,\"tid\":3},\n"
    "{\"ph\":\"B\",\"name\":\"gen\",\"ts\":1000,\"pid\":1,\"tid\":2,\"args\":{\"chunk\":\"2,0,0\"}},\n"
    "{\"ph\":\"B\",\"name\":\"mesh\",\"ts\":4000,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"E\",\"ts\":6000,\"pid\":1,\"tid\":2,\"args\":{\"bytes\":512}},\n"
    "{\"ph\":\"E\",\"ts\":9000,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"C\",\"name\":\"mem\",\"ts\":45000,\"pid\":1,\"tid\":2,\"args\":{\"value\":200}},\n"
    "{\"ph\":\"B\",\"name\":\"gen\",\"ts\":38000,\"pid\":1,\"tid\":2,\"args\":{\"chunk\":\"5,0,5\"}},\n"
    "{\"ph\":\"E\",\"ts\":46000,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":0,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"A\",\"ts\":2000,\"pid\":1,\"tid\":1,\"args\":{\"chunk\":\"3,0,-2\"}},\n"
    "{\"ph\":\"B\",\"name\":\"B\",\"ts\":3000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"C\",\"name\":\"mem\",\"ts\":5000,\"pid\":1,\"tid\":1,\"args\":{\"value\":100}},\n"
    "{\"ph\":\"E\",\"ts\":5000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"X\",\"name\":\"x1\",\"ts\":6000,\"dur\":1000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"ts\":8000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"C\",\"name\":\"jobs\",\"ts\":9000,\"pid\":1,\"tid\":1,\"args\":{\"run\":4,\"stolen\":1}},\n"
    "{\"ph\":\"E\",\"ts\":10000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":10000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"wait\",\"ts\":12000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"gen\",\"ts\":13000,\"pid\":1,\"tid\":1,\"args\":{\"chunk\":\"1,0,0\"}},\n"
    "{\"ph\":\"X\",\"name\":\"noise\",\"ts\":14000,\"dur\":5000,\"pid\":1,\"tid\":1,"
    "\"args\":{\"octaves\":4,\"scale\":0.5}},\n"
    "{\"ph\":\"C\",\"name\":\"mem\",\"ts\":20000,\"pid\":1,\"tid\":1,\"args\":{\"value\":300}},\n"
    "{\"ph\":\"E\",\"ts\":33000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"ts\":36000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"C\",\"name\":\"jobs\",\"ts\":40000,\"pid\":1,\"tid\":1,\"args\":{\"run\":10,\"stolen\":3}},\n"
    "{\"ph\":\"E\",\"ts\":40000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":40000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"A\",\"ts\":41000,\"pid\":1,\"tid\":1,\"args\":{\"chunk\":\"0,0,1\"}},\n"
    "{\"ph\":\"E\",\"ts\":43000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"C\",\"name\":\"queue\",\"ts\":50000,\"pid\":1,\"tid\":1,\"args\":{\"value\":7,\"peak\":9}},\n"
    "{\"ph\":\"C\",\"name\":\"odd\",\"ts\":51000,\"pid\":1,\"tid\":1,\"args\":{\"value\":\"x\"}},\n"
    "{\"ph\":\"E\",\"ts\":55000,\"pid\":1,\"tid\":1}\n"
    "],\"displayTimeUnit\":\"ms\"}\n";

static void load_drill(trace_report *report) {
    core_error error = { 0 };
    cr_assert(trace_report_parse(drill_trace, strlen(drill_trace), report, &error), "%s", error.message);
}

/* ---- self times ------------------------------------------------------------------------- */

Test(trace_report_detail, self_times_of_nested_zones) {
    trace_report report;
    load_drill(&report);
    cr_assert_eq(report.zone_count, 10);
    const char *order[] = { "gen", "frame", "A", "noise", "wait", "inner", "B", "mesh", "x1", "outer" };
    const size_t counts[] = { 3, 3, 2, 1, 1, 1, 1, 1, 1, 1 };
    const double totals[] = { 36, 55, 8, 5, 24, 4, 2, 2, 1, 4 };
    const double selfs[] = { 29, 23, 5, 5, 4, 4, 2, 2, 1, 0 };
    const double maxes[] = { 20, 30, 6, 5, 24, 4, 2, 2, 1, 4 };
    for (size_t i = 0; i < 10; i++) {
        const trace_zone_stats *zone = &report.zones[i];
        cr_expect_str_eq(zone->name, order[i], "row %zu", i);
        cr_expect_eq(zone->count, counts[i], "%s count %zu", zone->name, zone->count);
        cr_expect_float_eq(zone->total_ms, totals[i], 1e-9, "%s total %g", zone->name, zone->total_ms);
        cr_expect_float_eq(zone->self_ms, selfs[i], 1e-9, "%s self %g", zone->name, zone->self_ms);
        cr_expect_float_eq(zone->max_ms, maxes[i], 1e-9, "%s max %g", zone->name, zone->max_ms);
    }
    trace_report_free(&report);
}

Test(trace_report_detail, self_times_add_up_to_the_outermost_zones) {
    /* Invariant: every zone's duration is its self time plus its children's durations, so the
     * self times of all zones add up to the outermost zones' durations (75 ms, see above). */
    trace_report report;
    load_drill(&report);
    double self_sum = 0;
    for (size_t i = 0; i < report.zone_count; i++) {
        cr_expect_geq(report.zones[i].self_ms, 0.0);
        cr_expect_leq(report.zones[i].self_ms, report.zones[i].total_ms + 1e-9);
        self_sum += report.zones[i].self_ms;
    }
    cr_expect_float_eq(self_sum, 75, 1e-9);
    trace_report_free(&report);
}

Test(trace_report_detail, threads_do_not_nest_in_each_other) {
    /* tid 1: a 0 → 10 ms; tid 2: b 2 → 4 ms, inside a's span but on another thread: a keeps
     * 10 ms of self time. An X on tid 1 from 5 to 7 ms is inside a: a's self is 10 − 2 = 8. */
    const char *json = "[{\"ph\":\"B\",\"name\":\"a\",\"ts\":0,\"tid\":1},"
                       "{\"ph\":\"X\",\"name\":\"b\",\"ts\":2000,\"dur\":2000,\"tid\":2},"
                       "{\"ph\":\"X\",\"name\":\"c\",\"ts\":5000,\"dur\":2000,\"tid\":1},"
                       "{\"ph\":\"E\",\"ts\":10000,\"tid\":1}]";
    trace_report report;
    core_error error = { 0 };
    cr_assert(trace_report_parse(json, strlen(json), &report, &error), "%s", error.message);
    cr_assert_eq(report.zone_count, 3);
    cr_expect_str_eq(report.zones[0].name, "a");
    cr_expect_float_eq(report.zones[0].self_ms, 8, 1e-9);
    cr_expect_float_eq(report.zones[1].self_ms, 2, 1e-9);
    cr_expect_float_eq(report.zones[2].self_ms, 2, 1e-9);
    trace_report_free(&report);
}

/* ---- counters --------------------------------------------------------------------------- */

Test(trace_report_detail, counter_series_statistics) {
    trace_report report;
    load_drill(&report);
    cr_expect_eq(report.counter_count, 7);
    cr_assert_eq(report.counter_series_count, 5);
    const char *names[] = { "jobs.run", "jobs.stolen", "mem", "queue.peak", "queue.value" };
    const size_t counts[] = { 2, 2, 3, 1, 1 };
    const double mins[] = { 4, 1, 100, 9, 7 }, maxes[] = { 10, 3, 300, 9, 7 };
    const double means[] = { 7, 2, 200, 9, 7 }, lasts[] = { 10, 3, 200, 9, 7 };
    for (size_t i = 0; i < 5; i++) {
        const trace_counter_stats *c = &report.counters[i];
        cr_expect_str_eq(c->name, names[i]);
        cr_expect_eq(c->count, counts[i], "%s", c->name);
        cr_expect_float_eq(c->min, mins[i], 1e-9, "%s min %g", c->name, c->min);
        cr_expect_float_eq(c->max, maxes[i], 1e-9, "%s max %g", c->name, c->max);
        cr_expect_float_eq(c->mean, means[i], 1e-9, "%s mean %g", c->name, c->mean);
        cr_expect_float_eq(c->last, lasts[i], 1e-9, "%s last %g", c->name, c->last);
    }
    trace_report_free(&report);
}

Test(trace_report_detail, print_shows_self_and_counters) {
    trace_report report;
    load_drill(&report);
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    trace_report_print(&report, out);
    fclose(out);
    cr_expect(strstr(text, "counters     7 events, 5 series\n") != NULL, "%s", text);
    /* mem: 3 samples, min 100, max 300, mean 200, last 200. */
    const char *mem = strstr(text, "\nmem ");
    cr_assert_not_null(mem, "%s", text);
    int samples = 0;
    double min = 0, max = 0, mean = 0, last = 0;
    cr_expect_eq(sscanf(mem, " mem %d %lf %lf %lf %lf", &samples, &min, &max, &mean, &last), 5);
    cr_expect(samples == 3 && min == 100 && max == 300 && mean == 200 && last == 200, "%s", mem);
    /* The zone table says its order; its first row is gen: 3, self 29, total 36. */
    const char *header = strstr(text, "zone (by self time)");
    cr_assert_not_null(header, "%s", text);
    const char *row = strchr(header, '\n') + 1;
    char name[16] = "";
    size_t count = 0;
    double self = 0, total = 0;
    cr_expect_eq(sscanf(row, "%15s %zu %lf %lf", name, &count, &self, &total), 4);
    cr_expect_str_eq(name, "gen");
    cr_expect(count == 3 && self == 29 && total == 36, "%s", row);
    free(text);
    trace_report_free(&report);
}

/* ---- the slowest frames ----------------------------------------------------------------- */

typedef struct expected_zone {
    const char *name;
    size_t count;
    double self_ms, slowest_ms;
    const char *args; /* NULL: none */
} expected_zone;

static void expect_frame_zones(const trace_slow_frame *frame, const expected_zone *expected, size_t n) {
    cr_assert_eq(frame->zone_count, n, "frame %zu: %zu zones", frame->index, frame->zone_count);
    for (size_t i = 0; i < n; i++) {
        const trace_frame_zone *zone = &frame->zones[i];
        cr_expect_str_eq(zone->name, expected[i].name, "frame %zu row %zu", frame->index, i);
        cr_expect_eq(zone->count, expected[i].count, "frame %zu %s", frame->index, zone->name);
        cr_expect_float_eq(zone->self_ms, expected[i].self_ms, 1e-9, "frame %zu %s self %g", frame->index,
                           zone->name, zone->self_ms);
        cr_expect_float_eq(zone->slowest_ms, expected[i].slowest_ms, 1e-9, "frame %zu %s", frame->index, zone->name);
        if (expected[i].args) cr_expect(zone->args && strcmp(zone->args, expected[i].args) == 0,
                                        "frame %zu %s args '%s'", frame->index, zone->name, zone->args);
        else cr_expect_null(zone->args, "frame %zu %s", frame->index, zone->name);
    }
}

static void expect_frame_counters(const trace_slow_frame *frame, const char *const *names, const double *values,
                                  size_t n) {
    cr_assert_eq(frame->counter_count, n, "frame %zu: %zu counters", frame->index, frame->counter_count);
    for (size_t i = 0; i < n; i++) {
        cr_expect_str_eq(frame->counters[i].name, names[i]);
        cr_expect_float_eq(frame->counters[i].value, values[i], 1e-9, "frame %zu %s", frame->index, names[i]);
    }
}

Test(trace_report_detail, slowest_frames) {
    /* Frames 10, 30 and 15 ms: the two slowest are frame 1 (30 ms at 10 ms), then frame 2
     * (15 ms at 40 ms). Three zones each.
     * Frame 1 spans 10 → 40: frame self 6, wait 4, noise 5; gen on tid 1 (self 15, 20 ms,
     * chunk 1,0,0) and gen on tid 2 (38 → 46, self 8, 2 of its 8 ms inside: 8 · 2/8 = 2), so gen
     * 17 from 2 instances, the longest 20 ms. Frames 0 and 2 only touch its edges: left out.
     * Top 3 by self: gen 17, frame 6, noise 5.
     * Counters at 40 ms: jobs.run 10 and jobs.stolen 3 (@40: at its end counts), mem 300 (@20;
     * the 200 is @45);
     * queue comes at 50: none yet.
     * Frame 2 spans 40 → 55: frame 13, gen (tid 2) 8 · 6/8 = 6, A 2 (chunk 0,0,1).
     * Counters at 55 ms: jobs 10 / 3, mem 200, queue.peak 9, queue.value 7. */
    trace_report report;
    load_drill(&report);
    trace_slowest slowest;
    trace_report_slowest(&report, 2, 3, &slowest);
    cr_assert_eq(slowest.frame_count, 2);

    const trace_slow_frame *first = &slowest.frames[0];
    cr_expect_eq(first->index, 1);
    cr_expect_float_eq(first->start_ms, 10, 1e-9);
    cr_expect_float_eq(first->duration_ms, 30, 1e-9);
    expect_frame_zones(first, (const expected_zone[]){ { "gen", 2, 17, 20, "chunk=1,0,0" },
                                                       { "frame", 1, 6, 30, NULL },
                                                       { "noise", 1, 5, 5, "octaves=4 scale=0.5" } }, 3);
    expect_frame_counters(first, (const char *const[]){ "jobs.run", "jobs.stolen", "mem" },
                          (const double[]){ 10, 3, 300 }, 3);

    const trace_slow_frame *second = &slowest.frames[1];
    cr_expect_eq(second->index, 2);
    cr_expect_float_eq(second->start_ms, 40, 1e-9);
    cr_expect_float_eq(second->duration_ms, 15, 1e-9);
    expect_frame_zones(second, (const expected_zone[]){ { "frame", 1, 13, 15, NULL },
                                                        { "gen", 1, 6, 8, "chunk=5,0,5" },
                                                        { "A", 1, 2, 2, "chunk=0,0,1" } }, 3);
    expect_frame_counters(second,
                          (const char *const[]){ "jobs.run", "jobs.stolen", "mem", "queue.peak", "queue.value" },
                          (const double[]){ 10, 3, 200, 9, 7 }, 5);
    trace_slowest_free(&slowest);
    trace_report_free(&report);
}

Test(trace_report_detail, slowest_frame_zones_on_every_thread) {
    /* Asking for more frames than there are gives all three; the last is frame 0 (10 ms), whose
     * span 0 → 10 holds every thread's zones: gen 6 (tid 2, chunk 2,0,0), frame 4, inner 4
     * (tid 3), A 3 (chunk 3,0,-2), B 2, mesh 2 (args from its E: bytes=512), x1 1, outer 0.
     * Ties by name: frame before inner, B before mesh. Counters at 10 ms: jobs 4 / 1, mem 100. */
    trace_report report;
    load_drill(&report);
    trace_slowest slowest;
    trace_report_slowest(&report, 100, 100, &slowest);
    cr_assert_eq(slowest.frame_count, 3);
    cr_expect_eq(slowest.frames[0].index, 1);
    cr_expect_eq(slowest.frames[1].index, 2);
    const trace_slow_frame *last = &slowest.frames[2];
    cr_expect_eq(last->index, 0);
    expect_frame_zones(last, (const expected_zone[]){ { "gen", 1, 6, 8, "chunk=2,0,0" },
                                                      { "frame", 1, 4, 10, NULL },
                                                      { "inner", 1, 4, 4, NULL },
                                                      { "A", 1, 3, 6, "chunk=3,0,-2" },
                                                      { "B", 1, 2, 2, NULL },
                                                      { "mesh", 1, 2, 2, "bytes=512" },
                                                      { "x1", 1, 1, 1, NULL },
                                                      { "outer", 1, 0, 4, NULL } }, 8);
    expect_frame_counters(last, (const char *const[]){ "jobs.run", "jobs.stolen", "mem" },
                          (const double[]){ 4, 1, 100 }, 3);
    trace_slowest_free(&slowest);

    trace_report_slowest(&report, 0, 3, &slowest);
    cr_expect_eq(slowest.frame_count, 0);
    cr_expect_null(slowest.frames);
    trace_slowest_free(&slowest);
    trace_report_free(&report);
}

/* A memory stream for a print call's output; fclose it, then read and free *text. */
static FILE *text_stream(char **text, size_t *size) {
    *text = NULL, *size = 0;
    FILE *out = open_memstream(text, size);
    cr_assert_not_null(out);
    return out;
}

Test(trace_report_detail, slowest_print) {
    trace_report report;
    load_drill(&report);
    trace_slowest slowest;
    trace_report_slowest(&report, 1, 2, &slowest);
    char *text;
    size_t size;
    FILE *out = text_stream(&text, &size);
    trace_slowest_print(&slowest, out);
    fclose(out);
    cr_expect(strstr(text, "slowest 1 frames") != NULL, "%s", text);
    cr_expect(strstr(text, "frame 1   at 10.000 ms   30.000 ms\n") != NULL, "%s", text);
    const char *gen = strstr(text, "\n  gen ");
    cr_assert_not_null(gen, "%s", text);
    cr_expect(strstr(gen, "17.000") && strstr(gen, "chunk=1,0,0"), "%s", text);
    cr_expect(strstr(text, "noise") == NULL, "only the top 2 zones: %s", text);
    cr_expect(strstr(text, "counters at its end: jobs.run 10, jobs.stolen 3, mem 300\n") != NULL, "%s", text);
    free(text);
    trace_slowest_free(&slowest);
    trace_report_free(&report);
}

Test(trace_report_detail, slowest_of_a_trace_without_frames) {
    trace_report report;
    core_error error = { 0 };
    cr_assert(trace_report_parse("[]", 2, &report, &error), "%s", error.message);
    trace_slowest slowest;
    trace_report_slowest(&report, 5, 8, &slowest);
    cr_expect_eq(slowest.frame_count, 0);
    trace_slowest_free(&slowest);
    trace_report_free(&report);
}

/* ---- bad input -------------------------------------------------------------------------- */

static void expect_detail_error(const char *json, core_error_code code) {
    trace_report report;
    core_error error = { 0 };
    cr_expect_not(trace_report_parse(json, strlen(json), &report, &error), "parsed: %s", json);
    cr_expect_eq(error.code, code, "%s: code %s, expected %s (%s)", json, core_error_code_name(error.code),
                 core_error_code_name(code), error.message);
    cr_expect_null(report.counters);
    cr_expect_null(report.detail);
    trace_report_free(&report);
}

Test(trace_report_detail, bad_input_is_named) {
    /* A trace cut off in the middle of an event (a run killed while writing). */
    expect_detail_error("{\"traceEvents\":[{\"ph\":\"B\",\"name\":\"frame\",\"ts\":0,\"tid\":1},{\"ph\":\"E\",\"ts\":12",
                        CORE_ERROR_FORMAT);
    /* More E than B on a thread, after zones and counters were already collected. */
    expect_detail_error("[{\"ph\":\"C\",\"name\":\"m\",\"ts\":0,\"args\":{\"value\":1}},"
                        "{\"ph\":\"B\",\"name\":\"a\",\"ts\":0,\"tid\":1,\"args\":{\"k\":1}},"
                        "{\"ph\":\"E\",\"ts\":1,\"tid\":1},{\"ph\":\"E\",\"ts\":2,\"tid\":1}]",
                        CORE_ERROR_FORMAT);
    expect_detail_error("[{\"ph\":\"C\",\"name\":\"m\",\"args\":{\"value\":1}}]", CORE_ERROR_FORMAT);
}

Test(trace_report_detail, odd_args_are_parsed) {
    /* Args of every JSON type, an empty args object, args that are not an object, and a long
     * one that is cut: all parse, and only the slowest frame's zones show them. */
    const char *json =
        "[{\"ph\":\"X\",\"name\":\"frame\",\"ts\":0,\"dur\":1000,\"tid\":1,\"args\":[1,2]},"
        "{\"ph\":\"X\",\"name\":\"a\",\"ts\":100,\"dur\":100,\"tid\":1,"
        "\"args\":{\"s\":\"x\",\"n\":-1.5,\"t\":true,\"f\":false,\"z\":null,\"l\":[1],\"o\":{\"p\":1}}},"
        "{\"ph\":\"X\",\"name\":\"b\",\"ts\":300,\"dur\":50,\"tid\":1,\"args\":{}},"
        "{\"ph\":\"X\",\"name\":\"c\",\"ts\":400,\"dur\":10,\"tid\":1,\"args\":{\"long\":\""
        "0123456789012345678901234567890123456789012345678901234567890123456789012345678901234567890123456789"
        "0123456789012345678901234567890123456789012345678901234567890123456789012345678901234567890123456789"
        "\"}},"
        "{\"ph\":\"X\",\"name\":\"d\",\"ts\":500,\"dur\":5,\"tid\":1,\"args\":{\"lon\":\""
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9\u00e9"
        "\"}},"
        "{\"ph\":\"C\",\"name\":\"c\",\"ts\":0,\"args\":7}]";
    trace_report report;
    core_error error = { 0 };
    cr_assert(trace_report_parse(json, strlen(json), &report, &error), "%s", error.message);
    cr_expect_eq(report.counter_series_count, 0);
    trace_slowest slowest;
    trace_report_slowest(&report, 1, 8, &slowest);
    cr_assert_eq(slowest.frame_count, 1);
    /* frame self 1 − 0.1 − 0.05 − 0.01 − 0.005 = 0.835, a 0.1, b 0.05, c 0.01, d 0.005. */
    cr_assert_eq(slowest.frames[0].zone_count, 5);
    const trace_frame_zone *zones = slowest.frames[0].zones;
    cr_expect_str_eq(zones[0].name, "frame");
    cr_expect_float_eq(zones[0].self_ms, 0.835, 1e-9);
    cr_expect_null(zones[0].args);
    cr_expect_str_eq(zones[1].name, "a");
    cr_expect_str_eq(zones[1].args, "s=x n=-1.5 t=true f=false z=null l=[...] o={...}");
    cr_expect_str_eq(zones[2].name, "b");
    cr_expect_null(zones[2].args);
    cr_expect_str_eq(zones[3].name, "c");
    cr_assert_not_null(zones[3].args);
    cr_expect_leq(strlen(zones[3].args), 160);
    cr_expect(strncmp(zones[3].args, "long=0123", 9) == 0, "%s", zones[3].args);
    cr_expect(strcmp(zones[3].args + strlen(zones[3].args) - 3, "...") == 0, "%s", zones[3].args);
    /* "lon=" and 100 two-byte characters: cut before 157 bytes, on a character boundary, so
     * an even number of bytes of é (0xc3 0xa9) come before the "...". */
    cr_expect_str_eq(zones[4].name, "d");
    const char *cut = zones[4].args;
    cr_assert_not_null(cut);
    size_t length = strlen(cut);
    cr_expect_leq(length, 160);
    cr_expect(strncmp(cut, "lon=\xc3\xa9", 6) == 0 && strcmp(cut + length - 3, "...") == 0, "%s", cut);
    cr_expect_eq((length - 4 - 3) % 2, 0, "%zu bytes", length);
    for (size_t i = 4; i + 3 < length; i += 2)
        cr_expect((unsigned char)cut[i] == 0xc3 && (unsigned char)cut[i + 1] == 0xa9, "byte %zu", i);
    trace_slowest_free(&slowest);
    trace_report_free(&report);
}

Test(trace_report_detail, memory_is_returned) {
    /* Everything the report and the slowest frames allocate is counted, and freeing them gives
     * it all back (the sizes passed to core_free match the allocations). */
    size_t before = core_memory_in_use();
    trace_report report;
    load_drill(&report);
    trace_slowest slowest;
    trace_report_slowest(&report, 3, 4, &slowest);
    cr_expect_gt(core_memory_in_use(), before);
    trace_slowest_free(&slowest);
    trace_report_free(&report);
    cr_expect_eq(core_memory_in_use(), before);
    /* And after a failed parse that had collected zones, counters and args. */
    const char *bad = "[{\"ph\":\"C\",\"name\":\"m\",\"ts\":0,\"args\":{\"a\":1,\"b\":2}},"
                      "{\"ph\":\"X\",\"name\":\"x\",\"ts\":0,\"dur\":1,\"args\":{\"k\":\"v\"}},"
                      "{\"ph\":\"E\",\"ts\":2}]";
    cr_expect_not(trace_report_parse(bad, strlen(bad), &report, NULL));
    trace_report_free(&report);
    cr_expect_eq(core_memory_in_use(), before);
}

/* ---- frames over a budget ----------------------------------------------------------------- */

typedef struct expected_budget_zone {
    const char *name;
    double over_ms, within_ms;
} expected_budget_zone;

static void expect_budget_zones(const trace_over_budget *over, const expected_budget_zone *expected, size_t n) {
    cr_assert_eq(over->zone_count, n, "%zu zones", over->zone_count);
    for (size_t i = 0; i < n; i++) {
        cr_expect_str_eq(over->zones[i].name, expected[i].name, "row %zu", i);
        cr_expect_float_eq(over->zones[i].over_ms, expected[i].over_ms, 1e-9, "%s over %g", expected[i].name,
                           over->zones[i].over_ms);
        cr_expect_float_eq(over->zones[i].within_ms, expected[i].within_ms, 1e-9, "%s within %g", expected[i].name,
                           over->zones[i].within_ms);
    }
}

static void expect_budget_run(const trace_budget_run *run, size_t first, size_t last, size_t count, double worst) {
    cr_expect(run->first == first && run->last == last && run->over == count, "run %zu-%zu (%zu over)", run->first,
              run->last, run->over);
    cr_expect_float_eq(run->worst_ms, worst, 1e-9, "run %zu-%zu worst %g", run->first, run->last, run->worst_ms);
}

Test(trace_report_detail, frames_over_a_budget_of_duration) {
    /* Durations 10, 30 and 15 ms; over 12 ms: frames 1 and 2, one run (1 apart), worst 30.
     * Zones on the frames' own thread (tid 1) only, by self time inside each frame:
     *   frame 0: frame 4, A 3, B 2, x1 1 (tid 2's gen and mesh, tid 3's zones left out)
     *   frame 1: gen 15, frame 6, noise 5, wait 4 (tid 2's gen 38 → 46 left out)
     *   frame 2: frame 13, A 2
     * Over (frames 1, 2), means a frame: gen 7.5, frame 9.5, noise 2.5, wait 2, A 1; within
     * (frame 0): frame 4, A 3, B 2, x1 1. By over − within: gen +7.5, frame +5.5, noise +2.5,
     * wait +2, x1 −1, then A and B both −2 (by name). */
    trace_report report;
    load_drill(&report);
    trace_over_budget over;
    core_error error = { 0 };
    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 12 }, &over, &error), "%s",
              error.message);
    cr_expect_eq(over.frames, 3);
    cr_expect_eq(over.over, 2);
    cr_expect_null(over.series);
    cr_assert_eq(over.run_count, 1);
    expect_budget_run(&over.runs[0], 1, 2, 2, 30);
    expect_budget_zones(&over, (const expected_budget_zone[]){ { "gen", 7.5, 0 }, { "frame", 9.5, 4 },
                                                               { "noise", 2.5, 0 }, { "wait", 2, 0 },
                                                               { "x1", 0, 1 }, { "A", 1, 3 }, { "B", 0, 2 } }, 7);
    trace_over_budget_free(&over);
    trace_report_free(&report);
}

Test(trace_report_detail, frames_over_a_budget_of_a_counter) {
    /* mem at the frames' ends (10, 40, 55 ms): 100 (@5), 300 (@20), 200 (@45). Over 250: frame
     * 1 alone, worst 300. Within: frames 0 and 2, so frame (4 + 13) / 2 = 8.5, A (3 + 2) / 2 =
     * 2.5, B 1, x1 0.5. By over − within, the top 3: gen +15, noise +5, wait +4. */
    trace_report report;
    load_drill(&report);
    trace_over_budget over;
    core_error error = { 0 };
    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 250, .series = "mem", .top_zones = 3 },
                                       &over, &error), "%s", error.message);
    cr_expect_eq(over.frames, 3);
    cr_expect_eq(over.over, 1);
    cr_assert_eq(over.run_count, 1);
    expect_budget_run(&over.runs[0], 1, 1, 1, 300);
    expect_budget_zones(&over, (const expected_budget_zone[]){ { "gen", 15, 0 }, { "noise", 5, 0 }, { "wait", 4, 0 } }, 3);
    trace_over_budget_free(&over);

    /* queue.value's only sample is at 50 ms: frames 0 and 1 end before it and have no value, so
     * only frame 2 (7) counts; over 5 it is, and nothing is within. */
    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 5, .series = "queue.value" }, &over,
                                       &error), "%s", error.message);
    cr_expect_eq(over.frames, 1);
    cr_expect_eq(over.over, 1);
    cr_assert_eq(over.run_count, 1);
    expect_budget_run(&over.runs[0], 2, 2, 1, 7);
    expect_budget_zones(&over, (const expected_budget_zone[]){ { "frame", 13, 0 }, { "A", 2, 0 } }, 2);
    trace_over_budget_free(&over);
    trace_report_free(&report);
}

Test(trace_report_detail, frames_over_a_budget_refuse_bad_input) {
    trace_report report;
    load_drill(&report);
    trace_over_budget over;
    core_error error = { 0 };
    cr_expect_not(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 5, .series = "absent" }, &over,
                                           &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT);
    cr_expect(strstr(error.message, "absent") != NULL, "%s", error.message);
    cr_expect(over.run_count == 0 && over.runs == NULL && over.zones == NULL);
    const double bad[] = { 0, -1, NAN, INFINITY };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        error = (core_error){ 0 };
        cr_expect_not(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = bad[i] }, &over, &error),
                      "budget %g", bad[i]);
        cr_expect_eq(error.code, CORE_ERROR_ARGUMENT);
    }
    cr_expect_not(trace_report_over_budget(&report, NULL, &over, NULL));
    trace_over_budget_free(&over);
    trace_report_free(&report);
}

/* Frames of the given durations (ms), one after another on one thread, nothing else. */
static void load_frames(trace_report *report, const double *durations, size_t n) {
    char json[4096] = "{\"traceEvents\":[";
    size_t used = strlen(json);
    double ts = 0;
    for (size_t i = 0; i < n; i++) {
        used += (size_t)snprintf(json + used, sizeof json - used,
                                 "%s{\"ph\":\"X\",\"name\":\"frame\",\"ts\":%.0f,\"dur\":%.0f,\"pid\":1,\"tid\":1}",
                                 i ? "," : "", ts, durations[i] * 1000.0);
        ts += durations[i] * 1000.0;
    }
    snprintf(json + used, sizeof json - used, "]}");
    core_error error = { 0 };
    cr_assert(trace_report_parse(json, strlen(json), report, &error), "%s", error.message);
}

Test(trace_report_detail, frames_over_a_budget_make_runs_by_gap) {
    /* Over 10 ms: frames 1 (21), 4 (22), 5 (23) and 10 (24). Frames 3 or fewer apart share a
     * run: 1 → 4 is 3, 5 → 10 is 5, so [1, 5] (3 over, worst 23) and [10] (24). Only
     * neighbours (gap 1): [1], [4, 5], [10]. The default (30): one run of all four. */
    const double durations[] = { 5, 21, 5, 5, 22, 23, 5, 5, 5, 5, 24 };
    trace_report report;
    load_frames(&report, durations, sizeof durations / sizeof durations[0]);
    trace_over_budget over;
    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 10, .gap = 3 }, &over, NULL));
    cr_expect_eq(over.over, 4);
    cr_assert_eq(over.run_count, 2);
    expect_budget_run(&over.runs[0], 1, 5, 3, 23);
    expect_budget_run(&over.runs[1], 10, 10, 1, 24);
    trace_over_budget_free(&over);

    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 10, .gap = 1 }, &over, NULL));
    cr_assert_eq(over.run_count, 3);
    expect_budget_run(&over.runs[0], 1, 1, 1, 21);
    expect_budget_run(&over.runs[1], 4, 5, 2, 23);
    expect_budget_run(&over.runs[2], 10, 10, 1, 24);
    trace_over_budget_free(&over);

    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 10 }, &over, NULL));
    cr_assert_eq(over.run_count, 1);
    expect_budget_run(&over.runs[0], 1, 10, 4, 24);
    trace_over_budget_free(&over);

    /* A budget above every frame: nothing over, no run. */
    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 24 }, &over, NULL));
    cr_expect(over.over == 0 && over.run_count == 0 && over.runs == NULL);
    trace_over_budget_free(&over);
    trace_report_free(&report);
}

Test(trace_report_detail, frames_over_a_budget_print) {
    trace_report report;
    load_drill(&report);
    trace_over_budget over;
    cr_assert(trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 12, .top_zones = 2 }, &over, NULL));
    char *text;
    size_t size;
    FILE *out = text_stream(&text, &size);
    trace_over_budget_print(&over, out);
    fclose(out);
    cr_expect(strstr(text, "frames over 12.000 ms (frame duration): 2 of 3 (66.67%) in 1 runs\n") != NULL, "%s", text);
    cr_expect(strstr(text, "frames       1 - 2            2 over   worst 30.000 ms\n") != NULL, "%s", text);
    const char *gen = strstr(text, "\n  gen ");
    cr_assert(gen != NULL, "%s", text);
    double over_ms = 0, within_ms = 0, more = 0;
    cr_expect_eq(sscanf(gen + 7, "%lf %lf %lf", &over_ms, &within_ms, &more), 3, "%s", gen);
    cr_expect(over_ms == 7.5 && within_ms == 0 && more == 7.5, "%s", gen);
    free(text);
    trace_over_budget_free(&over);
    trace_report_free(&report);
}
