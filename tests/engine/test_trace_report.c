/* Tests of the trace report (engine/trace/trace_report.c) on hand-built traces whose frame
 * percentiles and zone statistics are worked out by hand in the comments. */
#include "core/core.h"
#include "trace/trace.h"

#include "test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The error of the last parse_text. */
static core_error parse_error;

static bool parse_text(const char *json, trace_report *report) {
    parse_error = (core_error){ 0 };
    return trace_report_parse(json, strlen(json), report, &parse_error);
}

static const trace_zone_stats *zone_named(const trace_report *report, const char *name) {
    for (size_t i = 0; i < report->zone_count; i++)
        if (strcmp(report->zones[i].name, name) == 0) return &report->zones[i];
    return NULL;
}

/* ---- percentiles ------------------------------------------------------------------------ */

Test(trace_report, nearest_rank_percentile) {
    /* 1..20: rank = ceil(p · 20 / 100). p50 → 10, p95 → 19, p99 → ceil(19.8) = 20,
     * p0 and anything below rank 1 → the smallest, p100 → 20. */
    double values[20];
    for (int i = 0; i < 20; i++) values[i] = i + 1;
    cr_expect(trace_percentile(values, 20, 50) == 10);
    cr_expect(trace_percentile(values, 20, 95) == 19);
    cr_expect(trace_percentile(values, 20, 99) == 20);
    cr_expect(trace_percentile(values, 20, 100) == 20);
    cr_expect(trace_percentile(values, 20, 0) == 1);
    cr_expect(trace_percentile(values, 20, 5) == 1);  /* ceil(1) = 1 */
    cr_expect(trace_percentile(values, 20, 6) == 2);  /* ceil(1.2) = 2 */
    /* n = 5: p50 → ceil(2.5) = 3, p99 → ceil(4.95) = 5, p20 → ceil(1) = 1. */
    cr_expect(trace_percentile(values, 5, 50) == 3);
    cr_expect(trace_percentile(values, 5, 99) == 5);
    cr_expect(trace_percentile(values, 5, 20) == 1);
    cr_expect(trace_percentile(values, 1, 50) == 1);
    cr_expect(trace_percentile(values, 0, 50) == 0);
}

/* ---- a hand-built trace ----------------------------------------------------------------- */

/* Main thread (tid 1): five frames, ts in µs.
 *   frame 1     0 → 12000   12 ms   update 1000 → 5000 (4 ms), in it physics 2000 → 3500 (1.5 ms)
 *   frame 2 12000 → 30000   18 ms
 *   frame 3 30000 → 65000   35 ms   update 31000 → 61000 (30 ms)
 *   frame 4 65000 → 81000   16 ms
 *   frame 5 81000 → 101000  20 ms   update 82000 → 84500 (2.5 ms)
 * Worker (tid 2), interleaved with the main thread's events in the file:
 *   mesh 500 → 8500 (8 ms), mesh 40000 → 42000 (2 ms)
 * GPU lane (tid 3), X events: gpu 3 ms and 5 ms.  Two counters, thread names (ignored).
 * An "E" carries a wrong name on purpose: like Chrome, an E closes the innermost open B. */
static const char *const hand_built_trace =
    "{\"traceEvents\":[\n"
    "{\"ph\":\"M\",\"name\":\"thread_name\",\"pid\":1,\"tid\":1,\"args\":{\"name\":\"main\"}},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":0,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"mesh\",\"ts\":500,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"B\",\"name\":\"update\",\"ts\":1000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"X\",\"name\":\"gpu\",\"ts\":1000,\"dur\":3000,\"pid\":1,\"tid\":3},\n"
    "{\"ph\":\"B\",\"name\":\"physics\",\"ts\":2000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"name\":\"not physics\",\"ts\":3500,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"ts\":5000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"C\",\"name\":\"chunks\",\"ts\":6000,\"pid\":1,\"tid\":1,\"args\":{\"value\":3}},\n"
    "{\"ph\":\"E\",\"ts\":8500,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"E\",\"ts\":12000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":12000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"ts\":30000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":30000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"update\",\"ts\":31000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"mesh\",\"ts\":40000,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"E\",\"ts\":42000,\"pid\":1,\"tid\":2},\n"
    "{\"ph\":\"E\",\"ts\":61000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"ts\":65000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":65000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"X\",\"name\":\"gpu\",\"ts\":66000,\"dur\":5000,\"pid\":1,\"tid\":3},\n"
    "{\"ph\":\"E\",\"ts\":81000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"frame\",\"ts\":81000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"B\",\"name\":\"update\",\"ts\":82000,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"E\",\"ts\":84500,\"pid\":1,\"tid\":1},\n"
    "{\"ph\":\"C\",\"name\":\"chunks\",\"ts\":90000,\"pid\":1,\"tid\":1,\"args\":{\"value\":4}},\n"
    "{\"ph\":\"E\",\"ts\":101000,\"pid\":1,\"tid\":1}\n"
    "],\"displayTimeUnit\":\"ms\"}\n";

Test(trace_report, frames_of_a_hand_built_trace) {
    trace_report report;
    cr_assert(parse_text(hand_built_trace, &report), "%s", parse_error.message);
    cr_assert_eq(report.frame_count, 5);
    /* In file order. */
    const double expected[] = { 12, 18, 35, 16, 20 };
    for (int i = 0; i < 5; i++) cr_expect_float_eq(report.frame_ms[i], expected[i], 1e-9, "frame %d", i);
    /* Sorted: 12 16 18 20 35. p50 → rank ceil(2.5) = 3 → 18; p95 → ceil(4.75) = 5 → 35;
     * p99 → ceil(4.95) = 5 → 35; max 35. Over 16.7 ms: 18, 35, 20 → 3. Over 33.3: 35 → 1. */
    cr_expect_float_eq(report.frame_p50_ms, 18, 1e-9);
    cr_expect_float_eq(report.frame_p95_ms, 35, 1e-9);
    cr_expect_float_eq(report.frame_p99_ms, 35, 1e-9);
    cr_expect_float_eq(report.frame_max_ms, 35, 1e-9);
    cr_expect_eq(report.frames_over_16ms, 3);
    cr_expect_eq(report.frames_over_33ms, 1);
    cr_expect_eq(report.counter_count, 2);
    trace_report_free(&report);
    cr_expect_null(report.frame_ms);
    cr_expect_eq(report.zone_count, 0);
}

Test(trace_report, zones_of_a_hand_built_trace) {
    trace_report report;
    cr_assert(parse_text(hand_built_trace, &report), "%s", parse_error.message);
    cr_assert_eq(report.zone_count, 5);
    /* By self time, largest first (inclusive totals, and self = total − zones nested in them on
     * the same thread):
     *   frame    5 zones  12+18+35+16+20 = 101 ms   self 101 − 36.5 (updates) = 64.5
     *                                               p99 rank ceil(4.95) = 5 of 12 16 18 20 35 → 35
     *   update   3 zones  4+30+2.5 = 36.5 ms        self 36.5 − 1.5 (physics) = 35
     *                                               p99 rank ceil(2.97) = 3 of 2.5 4 30 → 30
     *   mesh     2 zones  8+2 = 10 ms (own thread)  self 10; p99 rank ceil(1.98) = 2 of 2 8 → 8
     *   gpu      2 zones  3+5 = 8 ms (own lane)     self 8; p99 → 5
     *   physics  1 zone   1.5 ms                    self 1.5; p99 → 1.5 */
    const char *order[] = { "frame", "update", "mesh", "gpu", "physics" };
    const size_t counts[] = { 5, 3, 2, 2, 1 };
    const double totals[] = { 101, 36.5, 10, 8, 1.5 };
    const double selfs[] = { 64.5, 35, 10, 8, 1.5 };
    const double p99s[] = { 35, 30, 8, 5, 1.5 };
    for (size_t i = 0; i < 5; i++) {
        const trace_zone_stats *zone = &report.zones[i];
        cr_expect_str_eq(zone->name, order[i]);
        cr_expect_eq(zone->count, counts[i], "%s count %zu", zone->name, zone->count);
        cr_expect_float_eq(zone->total_ms, totals[i], 1e-9, "%s total %g", zone->name, zone->total_ms);
        cr_expect_float_eq(zone->self_ms, selfs[i], 1e-9, "%s self %g", zone->name, zone->self_ms);
        cr_expect_float_eq(zone->p99_ms, p99s[i], 1e-9, "%s p99 %g", zone->name, zone->p99_ms);
        cr_expect_float_eq(zone->max_ms, p99s[i], 1e-9, "%s max %g", zone->name, zone->max_ms);
    }
    cr_expect_null(zone_named(&report, "not physics"));
    trace_report_free(&report);
}

Test(trace_report, print_shows_frames_and_zones) {
    trace_report report;
    cr_assert(parse_text(hand_built_trace, &report), "%s", parse_error.message);
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    trace_report_print(&report, out);
    fclose(out);
    cr_expect(strstr(text, "5 frames   p50 18.000 ms   p95 35.000 ms   p99 35.000 ms   max 35.000 ms\n") != NULL,
              "%s", text);
    cr_expect(strstr(text, "3 over 16.7 ms (60.0%), 1 over 33.3 ms (20.0%)") != NULL, "%s", text);
    cr_expect(strstr(text, "counters     2 events, 1 series") != NULL, "%s", text);
    /* The zone table, largest self time first: frame on the first row after the header, with
     * self 101 − 36.5 (the updates nested in it) = 64.5 beside its total 101. */
    const char *header = strstr(text, "zone (by self time) ");
    cr_assert_not_null(header);
    const char *frame_row = strchr(header, '\n') + 1;
    cr_expect(strncmp(frame_row, "frame ", 6) == 0, "%s", text);
    cr_expect(strstr(frame_row, "         5       64.500      101.000     35.000     35.000\n") != NULL, "%s", text);
    free(text);
    trace_report_free(&report);
}

Test(trace_report, svg_plot_is_a_standalone_document) {
    trace_report report;
    cr_assert(parse_text(hand_built_trace, &report), "%s", parse_error.message);
    char path[128];
    snprintf(path, sizeof path, "/tmp/engine_test_report_%d.svg", (int)getpid());
    cr_assert(trace_report_write_svg(&report, path, NULL));
    trace_report_free(&report);

    FILE *file = fopen(path, "rb");
    cr_assert_not_null(file);
    char text[16384];
    size_t size = fread(text, 1, sizeof text - 1, file);
    fclose(file);
    unlink(path);
    text[size] = '\0';
    const char *head = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"";
    cr_expect(strncmp(text, head, strlen(head)) == 0, "%.100s", text);
    cr_expect(strstr(text, "</svg>\n") != NULL);
    cr_expect(strstr(text, "16.7 ms") != NULL);
    cr_expect(strstr(text, "33.3 ms") != NULL);
    cr_expect(strstr(text, ">frame time (ms)<") != NULL);
    cr_expect(strstr(text, ">frame<") != NULL);
    /* One point per frame on the frame-time line: 5 "x,y " pairs. */
    const char *points = strstr(text, "stroke=\"#1f77b4\"");
    cr_assert_not_null(points);
    points = strstr(points, "points=\"") + 8;
    int pairs = 0;
    for (const char *c = points; *c != '"'; c++) pairs += *c == ',';
    cr_expect_eq(pairs, 5);
    /* Every element opened is closed: as many '<' as '>'. */
    int open = 0, close = 0;
    for (size_t i = 0; i < size; i++) open += text[i] == '<', close += text[i] == '>';
    cr_expect_eq(open, close);
}

Test(trace_report, svg_fails_on_an_unwritable_path) {
    trace_report report;
    cr_assert(parse_text(hand_built_trace, &report), "%s", parse_error.message);
    core_error error = { 0 };
    cr_expect_not(trace_report_write_svg(&report, "/nonexistent-dir/plot.svg", &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s: %s", core_error_code_name(error.code), error.message);
    cr_expect(strstr(error.message, "/nonexistent-dir/plot.svg") != NULL, "names the file: %s", error.message);
    trace_report_free(&report);
}

/* ---- other shapes of valid input -------------------------------------------------------- */

Test(trace_report, bare_array_and_x_frames) {
    /* The format also allows a bare array; frames may be X events: 16 ms and 40 ms. */
    trace_report report;
    cr_assert(parse_text("[{\"ph\":\"X\",\"name\":\"frame\",\"ts\":0,\"dur\":16000,\"tid\":1},"
                         " {\"ph\":\"X\",\"name\":\"frame\",\"ts\":16000,\"dur\":40000,\"tid\":1}]",
                         &report), "%s", parse_error.message);
    cr_assert_eq(report.frame_count, 2);
    cr_expect_float_eq(report.frame_ms[0], 16, 1e-9);
    cr_expect_float_eq(report.frame_ms[1], 40, 1e-9);
    cr_expect_eq(report.frames_over_16ms, 1);
    cr_expect_eq(report.frames_over_33ms, 1);
    trace_report_free(&report);
}

Test(trace_report, empty_and_truncated_traces) {
    trace_report report;
    cr_assert(parse_text("{\"traceEvents\":[]}", &report), "%s", parse_error.message);
    cr_expect_eq(report.frame_count, 0);
    cr_expect_eq(report.zone_count, 0);
    cr_expect(report.frame_p99_ms == 0);
    trace_report_free(&report);
    /* A zone still open at the end (a run that was cut off) is not counted, and not an error. */
    cr_assert(parse_text("{\"traceEvents\":[{\"ph\":\"B\",\"name\":\"frame\",\"ts\":0,\"tid\":1}]}", &report),
              "%s", parse_error.message);
    cr_expect_eq(report.frame_count, 0);
    trace_report_free(&report);
}

/* ---- bad input -------------------------------------------------------------------------- */

static void expect_report_error(const char *json, core_error_code code) {
    trace_report report;
    cr_expect_not(parse_text(json, &report), "parsed: %s", json);
    cr_expect_eq(parse_error.code, code, "%s: code %s, expected %s (%s)", json, core_error_code_name(parse_error.code),
                 core_error_code_name(code), parse_error.message);
    cr_expect_neq(parse_error.message[0], '\0');
    cr_expect_eq(report.frame_count, 0);
    cr_expect_null(report.zones);
    trace_report_free(&report);
}

Test(trace_report, bad_input_is_named) {
    /* Malformed: not JSON, not a trace, events without the fields their phase needs. */
    expect_report_error("not json", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":[", CORE_ERROR_FORMAT);
    expect_report_error("{\"events\":[]}", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":{}}", CORE_ERROR_FORMAT);
    expect_report_error("42", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":[1]}", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":[{\"name\":\"x\"}]}", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":[{\"ph\":\"B\",\"tid\":1}]}", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":[{\"ph\":\"B\",\"ts\":\"5\",\"tid\":1}]}", CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":[{\"ph\":\"X\",\"ts\":5,\"tid\":1}]}", CORE_ERROR_FORMAT);
    /* Well-formed, but a value no zone can have. */
    expect_report_error("{\"traceEvents\":[{\"ph\":\"X\",\"ts\":5,\"dur\":-1,\"tid\":1}]}", CORE_ERROR_RANGE);
}

Test(trace_report, unbalanced_end_is_named) {
    /* The E of tid 2 has no B on its own thread, though tid 1 has one open. */
    expect_report_error("{\"traceEvents\":["
                        "{\"ph\":\"B\",\"name\":\"a\",\"ts\":0,\"pid\":1,\"tid\":1},"
                        "{\"ph\":\"E\",\"ts\":5,\"pid\":1,\"tid\":2}]}",
                        CORE_ERROR_FORMAT);
    expect_report_error("{\"traceEvents\":["
                        "{\"ph\":\"B\",\"name\":\"a\",\"ts\":10,\"tid\":1},"
                        "{\"ph\":\"E\",\"ts\":5,\"tid\":1}]}",
                        CORE_ERROR_FORMAT);
}

Test(trace_report, load_names_the_file) {
    trace_report report;
    core_error error = { 0 };
    cr_expect_not(trace_report_load("/nonexistent-dir/run.json", &report, &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s: %s", core_error_code_name(error.code), error.message);
    cr_expect(strstr(error.message, "/nonexistent-dir/run.json") != NULL, "names the file: %s", error.message);
    trace_report_free(&report);

    char path[128];
    snprintf(path, sizeof path, "/tmp/engine_test_report_%d.json", (int)getpid());
    FILE *file = fopen(path, "w");
    fputs("{\"traceEvents\":\n[}", file);
    fclose(file);
    error = (core_error){ 0 };
    cr_expect_not(trace_report_load(path, &report, &error));
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "%s: %s", core_error_code_name(error.code), error.message);
    /* The file first, then where in it (JSON's line and column). */
    cr_expect(strncmp(error.message, path, strlen(path)) == 0, "names the file first: %s", error.message);
    cr_expect(strstr(error.message, "line 2, column 2") != NULL, "names the place: %s", error.message);
    trace_report_free(&report);
    unlink(path);
}

/* ---- capture, then report --------------------------------------------------------------- */

Test(trace_report, reads_back_a_capture) {
    char path[128];
    snprintf(path, sizeof path, "/tmp/engine_test_report_capture_%d.json", (int)getpid());
    cr_assert(trace_start(path));
    for (int frame = 0; frame < 3; frame++) {
        trace_frame_begin();
        { TRACE_ZONE("sleep"); usleep(2000); }
        trace_frame_end();
    }
    trace_stop();
    trace_report report;
    core_error error = { 0 };
    bool ok = trace_report_load(path, &report, &error);
    unlink(path);
    cr_assert(ok, "%s", error.message);
    cr_expect_eq(report.frame_count, 3);
    const trace_zone_stats *sleep = zone_named(&report, "sleep");
    cr_assert_not_null(sleep);
    cr_expect_eq(sleep->count, 3);
    /* Each sleep is at least 2 ms; each frame holds its sleep. */
    cr_expect_geq(sleep->total_ms, 3 * 2.0 * 0.995);
    cr_expect_geq(report.frame_p50_ms, sleep->total_ms / 3 * 0.5);
    cr_expect_eq(report.counter_count, 6); /* memory.bytes and memory.trace, once per frame */
    trace_report_free(&report);
}
