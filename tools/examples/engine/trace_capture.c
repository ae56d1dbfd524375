/* trace_capture — capture a trace and read it back (engine/trace/trace.h):
 *
 *   1. a capture of a few frames, each with nested zones ("update" holding "physics", then
 *      "draw"), a zone argument and a counter;
 *   2. the file read back with trace_report_load, and its busiest zones and counters printed
 *      from the report's fields, the way tools/trace_report prints them whole.
 *
 *   trace_capture [--frames N] [--out FILE] [--threads N]
 *
 * The trace goes to --out (default: a temporary file, removed at the end); open it in
 * ui.perfetto.dev, or run tools/trace_report FILE for the full report.
 */
#include "core/core.h"
#include "trace/trace.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Busy work of about `us` microseconds, so the zones have sizes worth comparing. */
static void spend(int us) {
    uint64_t end = core_time_ns() + (uint64_t)us * 1000;
    while (core_time_ns() < end) {}
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    int frames = 10;
    const char *out = NULL;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "frames", CORE_OPTION_INT, &frames, "N", "frames to capture (default 10)", 1, 10000 },
        { "out", CORE_OPTION_STRING, &out, "FILE", "where the trace goes (default: a temporary file)" },
    };
    core_cli cli = { .program = "trace_capture", .summary = "capture a trace of zones and counters, read it back",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    /* This example is the capture: its file is --out (or --trace, the common flag), not a side output. */
    char path[64] = "/tmp/trace_capture-XXXXXX.json";
    const char *file = out ? out : common.trace_path;
    if (!file) {
        int fd = mkstemps(path, 5);
        if (fd < 0) { perror("trace_capture: temporary file"); return 1; }
        close(fd);
        file = path;
    }

    /* 1. The capture. */
    if (!trace_start(file)) return 2;              /* an unwritable path fails here, before any work */
    trace_thread_name("main");
    for (int frame = 0; frame < frames; frame++) {
        trace_frame_begin();
        {
            TRACE_ZONE("update");
            trace_zone_arg_int("frame", frame);    /* shows on the slice in Perfetto */
            spend(500);
            { TRACE_ZONE("physics"); spend(900); }  /* nested: update's self time excludes it */
        }
        trace_zone_begin("draw");
        spend(300);
        trace_zone_end();
        trace_counter("entities", 100 + 10 * frame);
        trace_frame_end();
    }
    trace_stop();                                  /* drains the writer and closes the JSON */

    /* 2. Read back. */
    trace_report report;
    core_error error = { 0 };
    if (!trace_report_load(file, &report, &error)) {
        fprintf(stderr, "trace_capture: %s\n", error.message);
        return 1;
    }
    printf("trace_capture: %zu frames, p50 %.2f ms\n", report.frame_count, report.frame_p50_ms);
    printf("trace_capture: the zones by self time\n");  /* "trace.write" is the capture's writer */
    for (size_t i = 0; i < report.zone_count && i < 5; i++) {  /* sorted, largest first */
        const trace_zone_stats *z = &report.zones[i];
        printf("  %-12s %3zu times, self %.1f ms of %.1f ms\n", z->name, z->count, z->self_ms, z->total_ms);
    }
    for (size_t i = 0; i < report.counter_series_count; i++) {
        const trace_counter_stats *c = &report.counters[i];
        if (strcmp(c->name, "entities") == 0)      /* ours; memory.bytes and memory.trace are the capture's */
            printf("trace_capture: counter %s from %.0f to %.0f\n", c->name, c->min, c->max);
    }
    trace_report_free(&report);
    if (file == path) remove(path);
    return 0;
}

/* The zones come in the order of their measured self time: physics first on a quiet machine, but
 * a busy one can stretch any of them, so the check below takes them in any order. */

/* Expected output:
 * Run: --frames 5
 * ^trace_capture: 5 frames, p50 [0-9.]+ ms$
 * ^trace_capture: the zones by self time$
 * ^  (physics|update|draw) +5 times, self [0-9.]+ ms of [0-9.]+ ms$
 * ^  (physics|update|draw) +5 times
 * ^  (physics|update|draw) +5 times
 * ^trace_capture: counter entities from 100 to 140$
 */
