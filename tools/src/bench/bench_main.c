/* bench_main.c — the benchmark program behind tools/bench (see bench.h).
 *   bench [--json FILE] [--filter TEXT] [--threads N] [--runs N] [--rocks on|off]
 * Rows whose name contains TEXT run; the rest are skipped. */
#include "bench.h"

#include "core/core.h"
#include "rocks/rocks.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

typedef struct bench_row {
    char name[96];
    char unit[16];
    double median, min, max;
    int runs;
} bench_row;

struct bench_context {
    const char *filter;
    int threads;
    int runs_override;
    bool rocks_off;
    bench_row *rows;
    size_t row_count, row_capacity;
};

static volatile double bench_sink;
void bench_consume(double value) { bench_sink += value; }

/* Whether row `name` is printed and recorded: its name contains the filter. */
static bool row_selected(const bench_context *ctx, const char *name) {
    return !ctx->filter || strstr(name, ctx->filter) != NULL;
}

/* Groups ask with their rows' common prefix ("ecs.iterate.1m"), so a filter naming one of the
 * rows ("ecs.iterate.1m.ratio") must let the group run too; only that row is then recorded. */
bool bench_wants(const bench_context *ctx, const char *name) {
    return row_selected(ctx, name) || strncmp(ctx->filter, name, strlen(name)) == 0;
}

int bench_threads(const bench_context *ctx) { return ctx->threads > 0 ? ctx->threads : core_cpu_count(); }
bool bench_rocks_off(const bench_context *ctx) { return ctx->rocks_off; }

const char *bench_rocks_cache_path(void) {
    struct stat st;
    return stat("out", &st) == 0 && S_ISDIR(st.st_mode) ? "out/rocks_tiles.bin" : NULL;
}

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void bench_record(bench_context *ctx, const char *name, const char *unit, const double *samples, int count) {
    if (!row_selected(ctx, name) || count <= 0) return;
    double *sorted = malloc((size_t)count * sizeof *sorted);
    memcpy(sorted, samples, (size_t)count * sizeof *sorted);
    qsort(sorted, (size_t)count, sizeof *sorted, compare_doubles);
    bench_row row = { .min = sorted[0], .max = sorted[count - 1], .runs = count };
    /* The median of an even count is the mean of the middle two. */
    row.median = count % 2 ? sorted[count / 2] : 0.5 * (sorted[count / 2 - 1] + sorted[count / 2]);
    snprintf(row.name, sizeof row.name, "%s", name);
    snprintf(row.unit, sizeof row.unit, "%s", unit);
    free(sorted);

    ctx->rows = core_grow(ctx->rows, &ctx->row_capacity, ctx->row_count + 1, sizeof *ctx->rows);
    ctx->rows[ctx->row_count++] = row;
    printf("%-36s %12.4g %12.4g %12.4g  %-6s %5d\n", row.name, row.median, row.min, row.max, row.unit, row.runs);
    fflush(stdout);
}

void bench_run(bench_context *ctx, const char *name, const char *unit, int runs, bench_sample_fn fn, void *user) {
    if (!row_selected(ctx, name)) return;
    if (ctx->runs_override > 0) runs = ctx->runs_override;
    bench_consume(fn(user)); /* warm-up: caches, page faults, lazily started threads */
    double *samples = malloc((size_t)runs * sizeof *samples);
    for (int i = 0; i < runs; i++) samples[i] = fn(user);
    bench_record(ctx, name, unit, samples, runs);
    free(samples);
}

static bool write_json(const bench_context *ctx, const char *path) {
    /* Write beside the target and rename, so a reader never sees half a file. */
    char temporary[4096];
    snprintf(temporary, sizeof temporary, "%s.tmp", path);
    FILE *file = fopen(temporary, "w");
    if (!file) return false;
    fprintf(file, "{\"results\":[");
    for (size_t i = 0; i < ctx->row_count; i++) {
        const bench_row *row = &ctx->rows[i];
        fprintf(file, "%s\n  {\"name\":\"%s\",\"unit\":\"%s\",\"median\":%.9g,\"min\":%.9g,\"max\":%.9g,\"runs\":%d}",
                i ? "," : "", row->name, row->unit, row->median, row->min, row->max, row->runs);
    }
    fprintf(file, "\n]}\n");
    bool ok = fclose(file) == 0;
    return ok && rename(temporary, path) == 0;
}

typedef void (*bench_group)(bench_context *ctx);

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *json_path = NULL, *filter = NULL;
    int runs = 0;
    const char *rocks = NULL;
    core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { .name = "json", .kind = CORE_OPTION_STRING, .value = &json_path, .metavar = "FILE",
          .help = "also write the rows as JSON" },
        { .name = "filter", .kind = CORE_OPTION_STRING, .value = &filter, .metavar = "TEXT",
          .help = "run only rows whose name contains TEXT" },
        { .name = "runs", .kind = CORE_OPTION_INT, .value = &runs, .metavar = "N", .min = 1, .max = 1000,
          .help = "runs per row (default: each row's own)" },
        { .name = "rocks", .kind = CORE_OPTION_STRING, .value = &rocks, .metavar = "on|off",
          .help = "rock piles in the world rows (default on; off for a same-session comparison)" },
    };
    core_cli cli = { .program = "bench", .summary = "Runs the engine's benchmarks: median, min and max over runs.",
                     .options = options, .option_count = (int)CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    rocks_quality rocks_on = ROCKS_ON;
    if (rocks && !rocks_parse_quality(rocks, &rocks_on)) {
        core_log_error("bench", "--rocks %s: expected on or off", rocks);
        return 2;
    }

    if (json_path) { /* find an unwritable path now, not after minutes of measuring */
        FILE *probe = fopen(json_path, "a");
        if (!probe) { core_log_error("bench", "cannot write --json %s", json_path); return 2; }
        fclose(probe);
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    bench_context ctx = { .filter = filter, .threads = common.threads, .runs_override = runs,
                          .rocks_off = rocks_on == ROCKS_OFF };
    printf("%-36s %12s %12s %12s  %-6s %5s\n", "name", "median", "min", "max", "unit", "runs");
    const bench_group groups[] = { bench_group_ecs, bench_group_jobs, bench_group_trace,
                                   bench_group_input, bench_group_gfx,
                                   bench_group_terrain_generate, bench_group_terrain_mesh,
                                   bench_group_terrain_clipmap, bench_group_terrain_stabilize,
                                   bench_group_terrain_sculpt, bench_group_terrain_edit,
                                   bench_group_terrain_edit_log,
                                   bench_group_world, bench_group_world_seam, bench_group_grass, bench_group_terrain_ao,
                                   bench_group_terrain_detail,
                                   bench_group_shadows, bench_group_water, bench_group_rocks,
                                   bench_group_rocks_world,
                                   bench_group_play, bench_group_trace_overhead };
    for (size_t i = 0; i < CORE_COUNTOF(groups); i++) groups[i](&ctx);

    if (common.trace_path) trace_stop();
    if (ctx.row_count == 0) core_warn("bench", "no row matches --filter %s", filter ? filter : "");
    if (json_path && !write_json(&ctx, json_path)) {
        core_log_error("bench", "could not write %s", json_path);
        return 1;
    }
    core_free(ctx.rows, ctx.row_capacity * sizeof *ctx.rows);
    return 0;
}
