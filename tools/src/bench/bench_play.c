/* bench_play.c — the first run a new user makes.
 *
 *   play.headless.seconds   wall seconds of the default headless `tools/play` (no display: the
 *       tour at 640×360 with its pictures, the trace and the trace report), after the build:
 *       the script's set-up and build steps find nothing to do and are counted. Target ≤ 60 s on
 *       the 2-core machine. Its output goes to out/ as a user's run would.
 */
#include "bench.h"

#include "core/core.h"

#include <libgen.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct play_bench { char command[PATH_MAX + 128]; } play_bench;

static double sample_play(void *user) {
    play_bench *b = user;
    uint64_t start = core_time_ns();
    int status = system(b->command);
    double seconds = (double)(core_time_ns() - start) * 1e-9;
    if (status != 0) core_fatal("bench", "'%s' failed (status %d)", b->command, status);
    return seconds;
}

void bench_group_play(bench_context *ctx) {
    if (!bench_wants(ctx, "play.headless")) return;
    /* The repository: this program is ROOT/bin/release/bench. */
    char exe[PATH_MAX];
    ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (length <= 0) core_fatal("bench", "cannot find this program's path");
    exe[length] = '\0';
    char *root = dirname(dirname(dirname(exe)));
    play_bench b;
    snprintf(b.command, sizeof b.command, "cd '%s' && env -u DISPLAY -u WAYLAND_DISPLAY tools/play >/dev/null 2>&1",
             root);
    sample_play(&b);                    /* the build, if anything is left to build: not counted */
    bench_run(ctx, "play.headless.seconds", "s", 3, sample_play, &b);
}
