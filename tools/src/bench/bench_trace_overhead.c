/* bench_trace_overhead.c — what capturing a trace costs the game (issue 19's trace.frame_overhead).
 *
 *   trace.frame_overhead   the median frame of a short scripted walk with a trace being captured,
 *                          over the same walk without one: a ratio (target ≤ 1.03). The walk is
 *                          the world at 320×180 (seed 1, 30 m on foot after loading; a small
 *                          frame, so the trace's share of it is large) run in pairs, untraced
 *                          and traced in turns (the order swapped every pair), so both halves of
 *                          a pair meet the same machine load; the row's samples are the pairs'
 *                          ratios. Each frame is timed
 *                          whole, from one game_app_frame call to the next, so the trace's own
 *                          work on the frame thread (its zones, trace_frame_end) is in it.
 *   trace.frame_overhead.bytes_per_frame   the traced walks' trace file, bytes a frame.
 */
#include "bench.h"

#include "core/core.h"
#include "game/app.h"
#include "trace/trace.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define OVERHEAD_PAIRS 5
#define OVERHEAD_FRAMES_MAX 4000

static const char overhead_walk[] = "ahead\n0 30 walk\n";

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The walk's median frame, ms, from the first frame past loading; frames counted in *frames. */
static double walk_median_frame(bench_context *ctx, const game_walk *walk, int *frames) {
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 320, .height = 180, .headless = true,
                                                      .threads = bench_threads(ctx), .walk = walk, .frames = 20000,
                                                      .rocks = ROCKS_OFF, .cliffs = ROCKS_OFF, .no_hud = true });
    if (!app) return 0.0;
    double *ms = malloc(OVERHEAD_FRAMES_MAX * sizeof *ms);
    int count = 0;
    uint64_t last = core_time_ns();
    while (game_app_frame(app)) {
        uint64_t now = core_time_ns();
        if (game_app_loaded(app) && count < OVERHEAD_FRAMES_MAX) ms[count++] = (double)(now - last) * 1e-6;
        last = now;
    }
    game_app_destroy(app);
    qsort(ms, (size_t)count, sizeof *ms, compare_doubles);
    double median = count ? ms[count / 2] : 0.0;
    free(ms);
    *frames = count;
    return median;
}

void bench_group_trace_overhead(bench_context *ctx) {
    if (!bench_wants(ctx, "trace.frame_overhead")) return;
    game_walk walk;
    char error[256], path[] = "/tmp/bench_trace_overhead_XXXXXX.json";
    if (!game_walk_parse_text(overhead_walk, strlen(overhead_walk), "bench", &walk, error, sizeof error)) {
        core_error("bench", "trace.frame_overhead: %s", error);
        return;
    }
    int fd = mkstemps(path, 5);
    if (fd < 0) {
        core_error("bench", "trace.frame_overhead: no temporary file");
        game_walk_free(&walk);
        return;
    }
    close(fd);
    double ratios[OVERHEAD_PAIRS], bytes_per_frame[OVERHEAD_PAIRS];
    int pairs = 0;
    for (int p = 0; p < OVERHEAD_PAIRS; p++) {
        int plain_frames = 0, traced_frames = 0;
        double plain = 0, traced = 0;
        for (int half = 0; half < 2; half++) {
            if ((half + p) % 2 == 0) {
                plain = walk_median_frame(ctx, &walk, &plain_frames);
            } else {
                if (!trace_start(path)) break;
                traced = walk_median_frame(ctx, &walk, &traced_frames);
                trace_stop();
            }
        }
        struct stat st;
        if (!(plain > 0 && traced > 0) || stat(path, &st) != 0 || traced_frames == 0) break;
        ratios[pairs] = traced / plain;
        bytes_per_frame[pairs] = (double)st.st_size / traced_frames;
        pairs++;
    }
    remove(path);
    game_walk_free(&walk);
    if (pairs == 0) {
        core_error("bench", "trace.frame_overhead: the walk did not run; rows skipped");
        return;
    }
    bench_record(ctx, "trace.frame_overhead", "ratio", ratios, pairs);
    bench_record(ctx, "trace.frame_overhead.bytes_per_frame", "bytes", bytes_per_frame, pairs);
}
