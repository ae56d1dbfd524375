/* fuzz_json — libFuzzer target for the JSON reader (engine/core/json.c), the JSON string
 * writer, and the trace report built on them (engine/trace/trace_report.c).
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's sources, runs each 20 s)
 * Seeds: tests/fuzz/corpus/fuzz_json/ (a small trace, a bare-array trace, every kind of value,
 * a trace with nested zones, zone args and counter series for the slowest frames and the
 * frames over a budget).
 *
 * Besides "no crash, no leak, no read out of bounds" it checks two properties and traps when
 * one fails: a failed parse always says where (line and column from 1), and whatever bytes the
 * writer is given, its output parses back as one JSON string.
 */
#include "core/core.h"
#include "trace/trace.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Visits every value, so each pointer the parser produced is read at least once. */
static size_t fuzz_walk(const core_json_value *value) {
    size_t seen = 1;
    if (value->type == CORE_JSON_ARRAY) {
        for (size_t i = 0; i < value->array.count; i++) seen += fuzz_walk(&value->array.items[i]);
    } else if (value->type == CORE_JSON_OBJECT) {
        for (size_t i = 0; i < value->object.count; i++) {
            if (value->object.keys[i].chars[value->object.keys[i].length] != '\0') __builtin_trap();
            seen += fuzz_walk(&value->object.values[i]);
        }
        (void)core_json_get(value, "traceEvents");
    } else if (value->type == CORE_JSON_STRING) {
        if (value->string.chars[value->string.length] != '\0') __builtin_trap();
    }
    return seen;
}

static void fuzz_parse(const char *data, size_t size) {
    core_arena arena = { 0 };
    core_json_value *root;
    core_error error = { 0 };
    int line = 0, column = 0;
    if (core_json_parse(data, size, &arena, &root, &error)) fuzz_walk(root);
    else if (error.code != CORE_ERROR_FORMAT || sscanf(error.message, "line %d, column %d:", &line, &column) != 2 ||
             line < 1 || column < 1 || (size_t)line > size + 1 || (size_t)column > size + 1)
        __builtin_trap();
    core_arena_release(&arena);
}

/* The writer's output for any C string must read back as a string; for valid UTF-8 it must read
 * back as the same bytes. */
static void fuzz_write_round_trip(const char *data, size_t size) {
    char *text = malloc(size + 1);
    memcpy(text, data, size);
    text[size] = '\0';
    char *written = NULL;
    size_t written_size = 0;
    FILE *out = open_memstream(&written, &written_size);
    core_json_write_string(out, text);
    fclose(out);
    core_arena arena = { 0 };
    core_json_value *root;
    if (!core_json_parse(written, written_size, &arena, &root, NULL) || root->type != CORE_JSON_STRING)
        __builtin_trap();
    if (!strstr(written, "\\ufffd") && strcmp(root->string.chars, text) != 0) __builtin_trap();
    core_arena_release(&arena);
    free(written);
    free(text);
}

static void fuzz_report(const char *data, size_t size) {
    trace_report report;
    core_error error = { 0 };
    if (trace_report_parse(data, size, &report, &error)) {
        FILE *sink = fopen("/dev/null", "w");
        /* The drill-down reads what the summary kept (zone instances, counter samples, args). */
        trace_slowest slowest;
        trace_report_slowest(&report, 3, 4, &slowest);
        /* Frames over a budget, by duration and by the first counter series if there is one. */
        trace_over_budget by_duration, by_series;
        const char *series = report.counter_series_count ? report.counters[0].name : NULL;
        if (!trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 1, .gap = 2 }, &by_duration, NULL))
            __builtin_trap(); /* a budget above 0 and no series is always accepted */
        bool series_read = trace_report_over_budget(&report, &(trace_budget_desc){ .budget_ms = 1, .series = series },
                                                    &by_series, NULL);
        if (sink) {
            trace_report_print(&report, sink);
            trace_slowest_print(&slowest, sink);
            trace_over_budget_print(&by_duration, sink);
            if (series_read) trace_over_budget_print(&by_series, sink);
            fclose(sink);
        }
        trace_over_budget_free(&by_duration);
        trace_over_budget_free(&by_series);
        trace_slowest_free(&slowest);
    } else if (error.code == CORE_ERROR_NONE || error.message[0] == '\0') {
        __builtin_trap(); /* a failure always says what kind and why */
    }
    trace_report_free(&report);
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    const char *data = (const char *)bytes;
    fuzz_parse(data, size);
    fuzz_write_round_trip(data, size);
    fuzz_report(data, size);
    return 0;
}
