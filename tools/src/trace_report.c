/* trace_report — prints a summary of a Chrome trace (frame-time percentiles, slow frames,
 * counters' min / max / mean / last, the zones that took the most self time, with their
 * inclusive time beside it) and writes an SVG plot of frame times beside it.
 *
 *     trace_report run.json                  # summary; plot in run.frames.svg
 *     trace_report run.json --svg plot.svg   # plot elsewhere
 *     trace_report run.json --slowest 5      # and the 5 slowest frames: their top zones by
 *                                            # self time (args of the longest) and counters
 *     trace_report run.json --over 8 --series game.cpu_frame_ms
 *                                            # the frames over 8 ms of the game's CPU frame
 *                                            # time: how many, in which runs of the trace, and
 *                                            # the zones they spend more on than the others
 *
 * Exit status: 0 done, 1 the trace could not be read or the plot written, 2 bad arguments or
 * an unwritable --trace (the report can trace itself, like every program).
 */
#include "core/core.h"
#include "trace/trace.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>

enum { TRACE_REPORT_TOP_ZONES = 8 }; /* zones listed per slow frame */

/* "dir/run.json" → "dir/run.frames.svg"; a name without an extension just gets the suffix. */
static char *trace_report_svg_path_for(const char *trace_path) {
    const char *base = strrchr(trace_path, '/');
    base = base ? base + 1 : trace_path;
    const char *dot = strrchr(base, '.');
    size_t stem = dot && dot != base ? (size_t)(dot - trace_path) : strlen(trace_path);
    static const char suffix[] = ".frames.svg";
    char *path = core_alloc(stem + sizeof suffix);
    memcpy(path, trace_path, stem);
    memcpy(path + stem, suffix, sizeof suffix);
    return path;
}

/* --over: false (after saying why) for a series the trace does not have. */
static bool trace_report_print_over(const trace_report *report, double over_ms, const char *series) {
    trace_over_budget over;
    core_error error = { 0 };
    if (!trace_report_over_budget(report, &(trace_budget_desc){ .budget_ms = over_ms, .series = series }, &over, &error)) {
        fprintf(stderr, "trace_report: %s\n", error.message);
        return false;
    }
    fputc('\n', stdout);
    trace_over_budget_print(&over, stdout);
    trace_over_budget_free(&over);
    return true;
}

int main(int argc, char **argv) {
    const char *svg_path = NULL;
    const char *trace_path = NULL;
    int slowest_count = 0;
    double over_ms = 0.0;
    const char *series = NULL;
    int positional_count = 0;
    core_common_args common = { 0 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(common), /* every program takes them; --threads changes nothing here */
        { .name = "svg", .kind = CORE_OPTION_STRING, .value = &svg_path, .metavar = "OUT",
          .help = "where to write the frame-time plot (default: FILE with .frames.svg)" },
        { .name = "slowest", .kind = CORE_OPTION_INT, .value = &slowest_count, .metavar = "N", .min = 1,
          .max = INT_MAX, .help = "also list the N slowest frames: top zones by self time, counters" },
        { .name = "over", .kind = CORE_OPTION_DOUBLE, .value = &over_ms, .metavar = "MS", .min_double = 0.001,
          .max_double = 1e9, .help = "also list the frames over MS: their runs, and the zones they spend more on" },
        { .name = "series", .kind = CORE_OPTION_STRING, .value = &series, .metavar = "NAME",
          .help = "with --over: compare a counter's value at each frame's end instead of the frame's duration "
                  "(the game's game.cpu_frame_ms, say)" },
    };
    core_cli cli = {
        .program = "trace_report",
        .summary = "Summarise a Chrome trace: frame times, counters, zones (self and inclusive time), "
                   "the slowest frames; plot frame times.",
        .options = options,
        .option_count = (int)CORE_COUNTOF(options),
        .positional_name = "FILE",
        .positional = &trace_path,
        .positional_min = 1,
        .positional_max = 1,
        .positional_count = &positional_count,
    };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (series && !(over_ms > 0)) {
        fprintf(stderr, "trace_report: '--series' needs '--over MS'\n");
        return 2;
    }

    trace_thread_name("main");
    if (common.trace_path && !trace_start(common.trace_path)) return 2;

    trace_report report;
    core_error error = { 0 };
    trace_zone_begin("load");
    bool loaded = trace_report_load(trace_path, &report, &error);
    trace_zone_end();
    bool plotted = false;
    if (loaded) {
        trace_report_print(&report, stdout);
        if (slowest_count > 0) {
            trace_slowest slowest;
            trace_report_slowest(&report, (size_t)slowest_count, TRACE_REPORT_TOP_ZONES, &slowest);
            fputc('\n', stdout);
            trace_slowest_print(&slowest, stdout);
            trace_slowest_free(&slowest);
        }
        if (over_ms > 0 && !trace_report_print_over(&report, over_ms, series)) {
            trace_report_free(&report);
            trace_stop();
            return 2;
        }
        char *default_svg = svg_path ? NULL : trace_report_svg_path_for(trace_path);
        const char *plot_path = svg_path ? svg_path : default_svg;
        trace_zone_begin("plot");
        plotted = trace_report_write_svg(&report, plot_path, &error);
        trace_zone_end();
        if (plotted) printf("\nframe-time plot: %s\n", plot_path);
        else fprintf(stderr, "trace_report: %s\n", error.message);
        if (default_svg) core_free(default_svg, strlen(default_svg) + 1);
        trace_report_free(&report);
    } else {
        fprintf(stderr, "trace_report: %s\n", error.message);
    }
    trace_stop();
    return loaded && plotted ? 0 : 1;
}
