/* bench.h — the benchmark harness behind tools/bench.
 *
 * A row is a named measurement repeated `runs` times; the harness prints median, min and max
 * and writes every row to JSON:
 *     {"results":[{"name":…,"unit":…,"median":…,"min":…,"max":…,"runs":…}, …]}
 *
 * Adding rows: write `void bench_group_NAME(bench_context *ctx)` in a file of its own under
 * tools/src/bench/, declare it in the list below, and add it to the table in bench_main.c.
 *     static double sample_empty_jobs(void *user) { ...; return ns_per_job; }
 *     bench_run(ctx, "jobs.empty", "ns", 9, sample_empty_jobs, &state);
 * A row whose value is derived from other rows (a ratio, a speedup) records its samples with
 * bench_record. Use bench_wants(ctx, name) to skip set-up work for rows the --filter excludes.
 * Peers (OpenMP, stb_perlin, …) are measured in the same run, on the same input, as rows of
 * their own beside ours.
 */
#ifndef BENCH_H
#define BENCH_H

#include <stdbool.h>

typedef struct bench_context bench_context;
typedef double (*bench_sample_fn)(void *user);

/* Whether a group should set up rows that start with `name` (true when --filter names one). */
bool bench_wants(const bench_context *ctx, const char *name);
/* Calls fn `runs` times (after one warm-up call) and records what it returns. */
void bench_run(bench_context *ctx, const char *name, const char *unit, int runs,
               bench_sample_fn fn, void *user);
void bench_record(bench_context *ctx, const char *name, const char *unit, const double *samples,
                  int count);
/* Threads the benchmarks may use (--threads, 0 = one per core). */
int bench_threads(const bench_context *ctx);
/* Whether --rocks off asked for the world rows without rock piles. */
bool bench_rocks_off(const bench_context *ctx);
/* The game's cache of the default rock tile set, out/rocks_tiles.bin, when out/ exists (as
 * game/main.c does); NULL otherwise. */
const char *bench_rocks_cache_path(void);
/* Keeps the optimiser from deleting a computation whose result is otherwise unused. */
void bench_consume(double value);

void bench_group_ecs(bench_context *ctx);
void bench_group_jobs(bench_context *ctx);
void bench_group_trace(bench_context *ctx);
void bench_group_trace_overhead(bench_context *ctx);
void bench_group_input(bench_context *ctx);
void bench_group_gfx(bench_context *ctx);
void bench_group_terrain_generate(bench_context *ctx);
void bench_group_terrain_mesh(bench_context *ctx);
void bench_group_terrain_clipmap(bench_context *ctx);
void bench_group_world(bench_context *ctx);
void bench_group_world_seam(bench_context *ctx);
void bench_group_terrain_stabilize(bench_context *ctx);
void bench_group_terrain_sculpt(bench_context *ctx);
void bench_group_terrain_edit(bench_context *ctx);
void bench_group_terrain_edit_log(bench_context *ctx);
void bench_group_play(bench_context *ctx);
void bench_group_grass(bench_context *ctx);
void bench_group_terrain_ao(bench_context *ctx);
void bench_group_terrain_detail(bench_context *ctx);
void bench_group_shadows(bench_context *ctx);
void bench_group_water(bench_context *ctx);
void bench_group_rocks(bench_context *ctx);
void bench_group_rocks_world(bench_context *ctx);

#endif
