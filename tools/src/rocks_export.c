/* rocks_export — write tiles of the rock tile set (paper 001) for looking at them elsewhere:
 *
 *   rocks_export --tiles N --out DIR [--cells N] [--voxels N] [--shape round|slab|mixed]
 *                [--seed S] [--cache FILE]
 *
 * Writes DIR/tile_000.ply … (binary PLY, tile units, the tile's origin at 0: the rocks whose seed
 * lies in the tile, full detail) for tiles 0 … N − 1, and DIR/tiles.json: per tile its corner
 * colours, per rock its id, seed point and the tile faces it straddles. A bad command line prints
 * the usage and exits 2, an unwritable --out too (before any work); a failure while writing
 * exits 1. Modes are separate functions so that more (a region of the world) can join main().
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

typedef struct export_args {
    core_common_args common;
    int tiles, cells, voxels;
    const char *out, *shape, *cache;
    int seed;
} export_args;

/* The faces of the tile [0, 1)³ the rock crosses: "-x" when it reaches below x = 0, "+x" above 1. */
static void write_straddles(FILE *f, const rocks_rock *rock, const int8_t offset[3]) {
    static const char axes[3] = { 'x', 'y', 'z' };
    bool first = true;
    fputc('[', f);
    for (int a = 0; a < 3; a++) {
        float lo = rock->bounds_min[a] + offset[a], hi = rock->bounds_max[a] + offset[a];
        if (lo < 0.0f) fprintf(f, "%s\"-%c\"", first ? "" : ",", axes[a]), first = false;
        if (hi > 1.0f) fprintf(f, "%s\"+%c\"", first ? "" : ",", axes[a]), first = false;
    }
    fputc(']', f);
}

static int export_tiles(const rocks_tileset *set, int tiles, const char *dir) {
    char path[4096], error[512];
    for (int t = 0; t < tiles; t++) {
        snprintf(path, sizeof path, "%s/tile_%03d.ply", dir, t);
        if (!rocks_tile_write_ply(set, t, path, error, sizeof error)) {
            fprintf(stderr, "rocks_export: %s\n", error);
            return 1;
        }
    }
    snprintf(path, sizeof path, "%s/tiles.json", dir);
    char temp[4200];
    snprintf(temp, sizeof temp, "%s.tmp", path);
    FILE *f = fopen(temp, "w");
    if (!f) {
        fprintf(stderr, "rocks_export: cannot write %s: %s\n", temp, strerror(errno));
        return 1;
    }
    fprintf(f, "{\"cells\":%d,\"voxels_per_cell\":%d,\"tiles\":[\n", set->desc.cells, set->desc.voxels_per_cell);
    for (int t = 0; t < tiles; t++) {
        const rocks_tile *tile = &set->tiles[t];
        fprintf(f, "{\"tile\":%d,\"ply\":\"tile_%03d.ply\",\"colours\":[", t, t);
        for (int c = 0; c < 8; c++) fprintf(f, "%s%d", c ? "," : "", (t >> c) & 1);
        fprintf(f, "],\"rocks\":[");
        for (uint32_t e = tile->first; e < tile->first + tile->count; e++) {
            const rocks_tile_entry *entry = &set->entries[e];
            const rocks_rock *rock = &set->rocks[entry->rock];
            fprintf(f, "%s\n {\"id\":%u,\"seed\":[%.6f,%.6f,%.6f],\"straddles\":", e == tile->first ? "" : ",", entry->rock,
                    rock->seed[0] + entry->offset[0], rock->seed[1] + entry->offset[1], rock->seed[2] + entry->offset[2]);
            write_straddles(f, rock, entry->offset);
            fputc('}', f);
        }
        fprintf(f, "]}%s\n", t + 1 < tiles ? "," : "");
    }
    fprintf(f, "]}\n");
    bool ok = !ferror(f);
    ok &= fclose(f) == 0;
    if (!ok || rename(temp, path) != 0) {
        fprintf(stderr, "rocks_export: cannot write %s\n", path);
        remove(temp);
        return 1;
    }
    printf("rocks_export: %d tiles, %u rocks in the set (%.1f s%s, %.1f MB: %u vertices, %u indices) → %s\n", tiles,
           set->rock_count, set->build_seconds, set->from_cache ? ", from the cache" : "", (double)set->bytes / 1e6,
           set->vertex_count, set->index_count, dir);
    return 0;
}

int main(int argc, char **argv) {
    export_args args = { .tiles = 1, .cells = 5, .voxels = 10, .shape = "mixed", .seed = 1 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(args.common),
        { .name = "tiles", .kind = CORE_OPTION_INT, .value = &args.tiles, .min = 1, .max = 256, .metavar = "N",
          .help = "write tiles 0 … N − 1" },
        { .name = "out", .kind = CORE_OPTION_STRING, .value = &args.out, .metavar = "DIR", .help = "output folder (required)" },
        { .name = "cells", .kind = CORE_OPTION_INT, .value = &args.cells, .min = 4, .max = 8, .metavar = "N",
          .help = "cells along a tile's side (default 5)" },
        { .name = "voxels", .kind = CORE_OPTION_INT, .value = &args.voxels, .min = 4, .max = 16, .metavar = "N",
          .help = "voxels along a cell's side (default 10)" },
        { .name = "shape", .kind = CORE_OPTION_STRING, .value = &args.shape, .metavar = "KIND",
          .help = "round, slab or mixed (default)" },
        { .name = "seed", .kind = CORE_OPTION_INT, .value = &args.seed, .min = 1, .max = 2147483647, .metavar = "S",
          .help = "the tile set's seed (default 1)" },
        { .name = "cache", .kind = CORE_OPTION_STRING, .value = &args.cache, .metavar = "FILE",
          .help = "read or write the tile set's cache here" },
    };
    core_cli cli = { .program = "rocks_export", .summary = "write rock tiles (paper 001) as PLY files and a JSON index",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    rocks_shape shape;
    if (strcmp(args.shape, "round") == 0) shape = ROCKS_SHAPE_ROUND;
    else if (strcmp(args.shape, "slab") == 0) shape = ROCKS_SHAPE_SLAB;
    else if (strcmp(args.shape, "mixed") == 0) shape = ROCKS_SHAPE_MIXED;
    else {
        fprintf(stderr, "rocks_export: --shape must be round, slab or mixed, not '%s'\n", args.shape);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (!args.out) {
        fprintf(stderr, "rocks_export: --out DIR is required\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (!core_make_dirs(args.out) || access(args.out, W_OK) != 0) {
        fprintf(stderr, "rocks_export: cannot write into %s: %s\n", args.out, strerror(errno));
        return 2;
    }
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = args.common.threads });
    rocks_tileset *set = rocks_tiles_create(&(rocks_tiles_desc){ .seed = (uint64_t)args.seed, .cells = args.cells,
                                                                 .voxels_per_cell = args.voxels, .shape = shape,
                                                                 .jobs = jobs, .cache_path = args.cache });
    int status = set ? export_tiles(set, args.tiles, args.out) : 1;
    rocks_tiles_destroy(set);
    job_system_destroy(jobs);
    return status;
}
