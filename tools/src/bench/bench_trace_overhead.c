/* bench_trace_overhead.c — what capturing a trace costs the game (issue 19's trace.frame_overhead).
 *
 *   trace.frame_overhead   the median frame with a trace being captured over the median frame
 *                          without, in one run: the world at 320×180 (seed 1) walks 60 m on foot,
 *                          capturing in every other block of BLOCK_FRAMES frames (a capture
 *                          started at a block's first frame and stopped at its end), so both
 *                          kinds of frame meet the same ground, streaming and machine load. The
 *                          first frames of each block (the capture's start or stop) are left
 *                          out. Each frame is timed whole, from one game_app_frame call to the
 *                          next, so the trace's own work on the frame thread (its zones,
 *                          trace_frame_end) is in it. Samples: three runs. Target ≤ 1.03.
 *   trace.frame_overhead.bytes_per_frame   the captures' bytes a traced frame.
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

#define OVERHEAD_RUNS 3
#define BLOCK_FRAMES 40
#define BLOCK_SETTLE 3                /* frames at a block's start left out */
#define FRAMES_MAX 8000

static const char overhead_walk[] = "ahead\n0 60 walk\n";

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *values, int count) {
    qsort(values, (size_t)count, sizeof *values, compare_doubles);
    return count ? values[count / 2] : 0.0;
}

typedef struct overhead_run {
    double ratio, bytes_per_frame;
    bool ok;
} overhead_run;

static overhead_run overhead_walk_once(bench_context *ctx, const game_walk *walk, const char *path) {
    overhead_run run = { 0 };
    game_app *app = game_app_create(&(game_app_desc){ .seed = 1, .width = 320, .height = 180, .headless = true,
                                                      .threads = bench_threads(ctx), .walk = walk, .frames = 20000,
                                                      .rocks = ROCKS_OFF, .cliffs = ROCKS_OFF, .no_hud = true });
    if (!app) return run;
    double *plain = malloc(FRAMES_MAX * sizeof *plain), *traced = malloc(FRAMES_MAX * sizeof *traced);
    int plain_count = 0, traced_count = 0, traced_frames = 0, frame = 0;
    double bytes = 0;
    bool capturing = false;
    uint64_t last = core_time_ns();
    for (;;) {
        bool loaded = game_app_loaded(app);
        int in_block = frame % BLOCK_FRAMES;
        bool traced_block = (frame / BLOCK_FRAMES) % 2 == 1;
        if (loaded && in_block == 0) {
            if (capturing) {
                trace_stop();
                struct stat st;
                if (stat(path, &st) == 0) bytes += (double)st.st_size;
                capturing = false;
            }
            if (traced_block) capturing = trace_start(path);
        }
        bool running = game_app_frame(app);
        uint64_t now = core_time_ns();
        double ms = (double)(now - last) * 1e-6;
        last = now;
        if (!running) break;
        if (!loaded) continue;
        traced_frames += capturing;
        if (in_block >= BLOCK_SETTLE && frame < FRAMES_MAX) {
            if (capturing) traced[traced_count++] = ms;
            else plain[plain_count++] = ms;
        }
        frame++;
    }
    if (capturing) {
        trace_stop();
        struct stat st;
        if (stat(path, &st) == 0) bytes += (double)st.st_size;
    }
    game_app_destroy(app);
    if (plain_count > 0 && traced_count > 0 && traced_frames > 0) {
        double p = median(plain, plain_count), t = median(traced, traced_count);
        run = (overhead_run){ .ratio = t / p, .bytes_per_frame = bytes / traced_frames, .ok = p > 0 };
    }
    free(plain);
    free(traced);
    return run;
}

void bench_group_trace_overhead(bench_context *ctx) {
    if (!bench_wants(ctx, "trace.frame_overhead")) return;
    if (trace_active()) {
        core_warn("bench", "trace.frame_overhead skipped: the benchmark itself is being traced (--trace)");
        return;
    }
    game_walk walk;
    char path[] = "/tmp/bench_trace_overhead_XXXXXX.json";
    core_error error = { 0 };
    if (!game_walk_parse_text(overhead_walk, strlen(overhead_walk), "bench", &walk, &error)) {
        core_log_error("bench", "trace.frame_overhead: %s", error.message);
        return;
    }
    int fd = mkstemps(path, 5);
    if (fd < 0) {
        core_log_error("bench", "trace.frame_overhead: no temporary file");
        game_walk_free(&walk);
        return;
    }
    close(fd);
    double ratios[OVERHEAD_RUNS], bytes_per_frame[OVERHEAD_RUNS];
    int runs = 0;
    for (int r = 0; r < OVERHEAD_RUNS; r++) {
        overhead_run run = overhead_walk_once(ctx, &walk, path);
        if (!run.ok) break;
        ratios[runs] = run.ratio;
        bytes_per_frame[runs] = run.bytes_per_frame;
        runs++;
    }
    remove(path);
    game_walk_free(&walk);
    if (runs == 0) {
        core_log_error("bench", "trace.frame_overhead: the walk did not run; rows skipped");
        return;
    }
    bench_record(ctx, "trace.frame_overhead", "ratio", ratios, runs);
    bench_record(ctx, "trace.frame_overhead.bytes_per_frame", "bytes", bytes_per_frame, runs);
}
