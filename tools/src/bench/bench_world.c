/* bench_world.c — the walkable world (game/app.h) headless at 1280×720 over a scripted 2 km path,
 * and how fast streaming fills in the start area.
 *
 * The path climbs to 230 m above the start (sprint flying, 48 m/s), then flies 2 km ahead at the
 * walking fly speed, 12 m/s: faster than a sprint on foot (8 m/s), so streaming works harder than
 * on foot, yet slower than the streaming keeps up with (world.stream.keep_up_speed), so the rings
 * are full as on a walk. (Sprint flying all the way, 48 m/s, left two thirds of the wanted chunks
 * pending and drew less than a walk does.) 230 m clears the generator's highest ground (base
 * 25 m + relief 150 m + its perturbation), which a flight at 120 m did not: it ended against a
 * mountain at 790 m. llvmpipe rasterises each 1280×720 frame for tens of milliseconds, which the
 * CPU frame time does not include but the wall clock does: the run takes about fifteen minutes.
 * A leg that runs out of time ends the run early; the log line says so.
 *
 * Rocks are on as in the game, their tile set read from the game's cache (out/rocks_tiles.bin),
 * which is made before the clock starts when it is missing: building it is rocks.tiles.n5's work,
 * not streaming's. `bench --rocks off` runs the same rows without rocks, for a comparison in one
 * session.
 *
 * Rows (one run each; the frame rows are percentiles over the run's frames):
 *   world.walk.cpu_frame.p50 / .p99   ms from a frame's start to the hand-over to the driver
 *                                     (on llvmpipe it includes the driver's waits: water's copy
 *                                     of the frame for refraction, the default "low" water, waits
 *                                     there for the whole terrain to be rasterised whenever water
 *                                     is in view; the trace's terrain_water_draw zone shows it)
 *   world.walk.engine_frame.p50 / .p99  the same less the draw calls (llvmpipe shades vertices
 *                                     inside them on this thread; a GPU would not)
 *   world.walk.thread_cpu.p50 / .p99  the main thread's own CPU time over the cpu_frame span
 *                                     (CLOCK_THREAD_CPUTIME_ID): the work, without the waits
 *   world.walk.triangles              triangles drawn a frame, the median (gfx_context_stats: every draw
 *                                     but the grass's GPU-generated ones)
 *   world.walk.hitches                frames over 33 ms
 *   world.walk.memory                 peak process RSS, MB (driver memory included)
 *   world.walk.terrain_memory         peak terrain stacks + meshes, MB
 *   world.stream.chunks_per_s         mesh chunks made ready per second while the start area
 *                                     loads (meshed or found empty; all cores): the walk's own
 *                                     load and STREAM_LOADS − 1 more of the same world before it,
 *                                     each a fresh app (one load swung from 48 to 70 m/s between
 *                                     runs of one build on this machine: the median of five is
 *                                     the row)
 *   world.stream.keep_up_speed        m/s of travel the streaming can sustain: each load's
 *                                     chunks_per_s over the chunks a metre of the path needed
 */
#include "bench.h"

#include "core/core.h"
#include "game/app.h"
#include "rocks/rocks.h"

#include <string.h>

static const char walk_text[] = "ahead\n0 1 fly y=230\n0 2001 fly walk y=230\n";
/* With only the world.stream rows asked for (--filter world.stream), the same path cut to 400 m
 * and drawn at 640×360: a couple of minutes instead of fifteen (llvmpipe's rasteriser threads
 * share the cores with the streaming jobs either way), the chunks a metre measured over a fifth
 * of the path. */
static const char stream_text[] = "ahead\n0 1 fly y=230\n0 401 fly walk y=230\n";

#define STREAM_LOADS 5

/* Frames `app` until the start area has loaded: the seconds that took and the chunks then ready. */
static void run_load(game_app *app, double *seconds, double *ready) {
    uint64_t start = core_time_ns();
    *seconds = 0.0, *ready = 0.0;
    while (game_app_frame(app)) {
        game_app_stats_info s = game_app_stats(app);
        if (s.frames > 0) {
            *seconds = (double)(core_time_ns() - start) * 1e-9;
            *ready = (double)(s.stream.chunks_meshed + s.stream.chunks_skipped_empty);
            return;
        }
    }
}

void bench_group_world(bench_context *ctx) {
    if (!bench_wants(ctx, "world.walk") && !bench_wants(ctx, "world.stream")) return;   /* not world.save */
    game_walk walk;
    core_error error = { 0 };
    const bool full = bench_wants(ctx, "world.walk");   /* else only the stream rows: the short path */
    const char *text = full ? walk_text : stream_text;
    if (!game_walk_parse_text(text, strlen(text), "bench", &walk, &error)) {
        core_log_error("bench", "world: %s", error.message);
        return;
    }
    rocks_quality rocks = bench_rocks_off(ctx) ? ROCKS_OFF : ROCKS_ON;
    const char *rocks_cache = bench_rocks_cache_path();
    if (rocks == ROCKS_ON && rocks_cache) rocks_tileset_destroy(rocks_tileset_create(&(rocks_tileset_desc){ .cache_path = rocks_cache }));
    const game_app_desc desc = { .seed = 1, .width = full ? 1280 : 640, .height = full ? 720 : 360, .headless = true,
                                 .threads = bench_threads(ctx), .walk = &walk, .frames = 20000, .rocks = rocks,
                                 .rocks_cache_path = rocks_cache };
    double load_seconds[STREAM_LOADS] = { 0 }, ready[STREAM_LOADS] = { 0 };
    for (int k = 0; k + 1 < STREAM_LOADS; k++) {   /* the loads before the walk's own */
        game_app *app = game_app_create(&desc);
        if (!app) break;
        run_load(app, &load_seconds[k], &ready[k]);
        game_app_destroy(app);
    }
    game_app *app = game_app_create(&desc);
    if (!app) {
        core_log_error("bench", "world: the world did not start; rows skipped");
        game_walk_free(&walk);
        return;
    }
    run_load(app, &load_seconds[STREAM_LOADS - 1], &ready[STREAM_LOADS - 1]);
    while (game_app_frame(app)) {
    }
    game_app_stats_info s = game_app_stats(app);
    game_app_destroy(app);
    game_walk_free(&walk);
    const double ready_at_load = ready[STREAM_LOADS - 1];
    double walked_chunks = (double)(s.stream.chunks_meshed + s.stream.chunks_skipped_empty) - ready_at_load;
    double per_metre = s.walked > 0 ? walked_chunks / s.walked : 0.0;
    double chunks_per_s[STREAM_LOADS], keep_up[STREAM_LOADS];
    for (int k = 0; k < STREAM_LOADS; k++) {
        chunks_per_s[k] = load_seconds[k] > 0 ? ready[k] / load_seconds[k] : 0.0;
        keep_up[k] = per_metre > 0 ? chunks_per_s[k] / per_metre : 0.0;
    }
    double rows[][1] = { { s.cpu_ms_p50 }, { s.cpu_ms_p99 }, { s.engine_ms_p50 }, { s.engine_ms_p99 },
                         { (double)s.hitches }, { (double)s.peak_rss_bytes / 1048576.0 },
                         { (double)s.stream.peak_resident_bytes / 1048576.0 } };
    if (full) {
        bench_record(ctx, "world.walk.cpu_frame.p50", "ms", rows[0], 1);
        bench_record(ctx, "world.walk.cpu_frame.p99", "ms", rows[1], 1);
        bench_record(ctx, "world.walk.engine_frame.p50", "ms", rows[2], 1);
        bench_record(ctx, "world.walk.engine_frame.p99", "ms", rows[3], 1);
        bench_record(ctx, "world.walk.thread_cpu.p50", "ms", (double[]){ s.thread_ms_p50 }, 1);
        bench_record(ctx, "world.walk.thread_cpu.p99", "ms", (double[]){ s.thread_ms_p99 }, 1);
        bench_record(ctx, "world.walk.triangles", "triangles", (double[]){ s.triangles_p50 }, 1);
        bench_record(ctx, "world.walk.hitches", "frames", rows[4], 1);
        bench_record(ctx, "world.walk.memory", "MB", rows[5], 1);
        bench_record(ctx, "world.walk.terrain_memory", "MB", rows[6], 1);
    }
    bench_record(ctx, "world.stream.chunks_per_s", "chunks/s", chunks_per_s, STREAM_LOADS);
    bench_record(ctx, "world.stream.keep_up_speed", "m/s", keep_up, STREAM_LOADS);
    core_info("bench", "world: %d frames, %.0f m walked%s, %d loading frames (%.1f s), %.3f chunks a metre",
              s.frames, s.walked, s.walk_stuck ? " (stuck)" : "", s.loading_frames, load_seconds[STREAM_LOADS - 1],
              per_metre);
}
