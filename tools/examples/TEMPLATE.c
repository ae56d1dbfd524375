/* TEMPLATE — the file every example starts from. Copy it to tools/examples/AREA/MODULE_FEATURE.c
 * (AREA: engine, terrain, rocks, vegetation or game), replace TEMPLATE by the file's name
 * everywhere, and say here in a few lines what the example shows and why a developer wants it.
 * The program is built as bin/CONFIG/MODULE_FEATURE with warnings as errors (premake5.lua finds
 * it), and tests/programs.sh runs it with the Run: line of the closing comment and checks its
 * output against the lines after that (tools/examples/README.md).
 *
 *   TEMPLATE [--count N] [--threads N] [--trace FILE]
 *
 * Keep it short and in reading order: what is made, what is done with it, what it printed.
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include <stdio.h>

int main(int argc, char **argv) {
    core_common_args common = { 0 };                 /* --threads N, --trace FILE */
    int count = 3;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "count", CORE_OPTION_INT, &count, "N", "how many things to do (default 3)", 1, 1000 },
    };
    core_cli cli = { .program = "TEMPLATE", .summary = "the example every other one starts from",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (common.trace_path && !trace_start(common.trace_path)) return 2;  /* a bad path fails now */
    trace_thread_name("main");

    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    /* ... the feature, top to bottom ... */
    printf("TEMPLATE: did %d things on %d threads\n", count, job_thread_count(jobs));

    job_system_destroy(jobs);
    trace_stop();
    return 0;
}

/* Expected output:
 * Run: --count 2 --threads 2
 * ^TEMPLATE: did 2 things on 2 threads$
 */
