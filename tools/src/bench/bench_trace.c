/* bench_trace.c — trace rows: what one zone (begin + end) costs with a capture running and
 * with none. DESIGN.md asks for "next to nothing" off; trace.h aims at ≤ 25 ns on. */
#include "bench.h"

#include "core/core.h"
#include "trace/trace.h"

#include <stdio.h>
#include <unistd.h>

/* A sample is FRAMES frames of ZONES_PER_FRAME zones each: 250 000 zones, 500 000 events. */
enum { TRACE_BENCH_ZONES_PER_FRAME = 50000, TRACE_BENCH_FRAMES = 5, TRACE_BENCH_RUNS = 9 };

typedef struct trace_bench {
    char path[96];
} trace_bench;

static double trace_bench_time_frame(void) {
    uint64_t start = core_time_ns();
    for (int i = 0; i < TRACE_BENCH_ZONES_PER_FRAME; i++) {
        trace_zone_begin("bench.zone");
        trace_zone_end();
    }
    return (double)(core_time_ns() - start);
}

/* Steady state, as in a game that flushes every frame: full chunks are handed over inside the
 * timed loop (a real frame pays that too), then written by the writer thread and recycled
 * within trace_flush, outside it. A frame here is 49 chunks, under the 64 that wake the writer
 * before a frame ends, so the row is the recording thread's own cost; what the writer costs a
 * frame on a machine short of cores shows in the frame times of a traced run instead.
 * One untimed frame first fills the chunk pool, so the samples measure recording rather than
 * the page faults of fresh memory. A capture per sample keeps the file at one sample's ~30 MB. */
static double trace_bench_sample_on(void *user) {
    trace_bench *bench = user;
    if (!trace_start(bench->path)) core_fatal("bench", "cannot trace to %s", bench->path);
    bench_consume(trace_bench_time_frame());
    trace_flush();
    double total_ns = 0;
    for (int frame = 0; frame < TRACE_BENCH_FRAMES; frame++) {
        total_ns += trace_bench_time_frame();
        trace_flush();
    }
    trace_stop();
    return total_ns / (TRACE_BENCH_FRAMES * TRACE_BENCH_ZONES_PER_FRAME);
}

static double trace_bench_sample_off(void *user) {
    (void)user;
    double total_ns = 0;
    for (int frame = 0; frame < TRACE_BENCH_FRAMES; frame++) total_ns += trace_bench_time_frame();
    return total_ns / (TRACE_BENCH_FRAMES * TRACE_BENCH_ZONES_PER_FRAME);
}

void bench_group_trace(bench_context *ctx) {
    bool on = bench_wants(ctx, "trace.zone"), off = bench_wants(ctx, "trace.zone.off");
    if (!on && !off) return;
    if (trace_active()) {
        /* Both rows need the capture to themselves: one to start their own, one to have none. */
        core_warn("bench", "trace rows skipped: the benchmark itself is being traced (--trace)");
        return;
    }
    trace_bench bench;
    snprintf(bench.path, sizeof bench.path, "/tmp/bench_trace_%d.json", (int)getpid());
    if (on) bench_run(ctx, "trace.zone", "ns", TRACE_BENCH_RUNS, trace_bench_sample_on, &bench);
    if (off) bench_run(ctx, "trace.zone.off", "ns", TRACE_BENCH_RUNS, trace_bench_sample_off, &bench);
    unlink(bench.path);
}
