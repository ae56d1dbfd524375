/* rocks_export — write tiles of the rock tile set (paper 001), or the rocks a world places, for
 * looking at them elsewhere:
 *
 *   rocks_export --tiles N --out DIR [--cells N] [--voxels N] [--shape round|slab|mixed]
 *                [--seed S] [--cache FILE]
 *   rocks_export --seed S --region X,Y,Z:NX,NY,NZ --out PREFIX [--cells N] [--voxels N] [--shape …]
 *                [--cache FILE]
 *
 * Writes DIR/tile_000.ply … (binary PLY, tile units, the tile's origin at 0: the rocks whose seed
 * lies in the tile, full detail) for tiles 0 … N − 1, and DIR/tiles.json: per tile its corner
 * colours, per rock its id, seed point and the tile faces it straddles. A bad command line prints
 * the usage and exits 2, an unwritable --out too (before any work); a failure while writing
 * exits 1.
 *
 * With --region, the world of seed S (default 1) places its rocks in the box of NX × NY × NZ
 * metres from (X, Y, Z) with the game's tile set (the flags' defaults) and tiling (rocks_place_box over the generated
 * rock layers, 3 m tiles), and PREFIX.ply gets every rock whose seed lies in the box, each its own
 * closed mesh (full detail) in world coordinates; PREFIX.json the count and, per rock, its shape's
 * id, seed point and bounds. Other meshing tools can check our rocks with these.
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

typedef struct export_args {
    core_common_args common;
    int tiles, cells, voxels;
    const char *out, *shape, *cache, *region;
    int seed;
} export_args;

#define EXPORT_TILE_SIZE 3.0          /* metres: the game's (rocks_system_desc.tile_size's default) */

/* Files are written to PATH.tmp and renamed over PATH once complete (CONVENTIONS: nothing half
 * written is left under the real name). */
static FILE *temp_open(const char *path, char *temp, size_t size, const char *mode) {
    snprintf(temp, size, "%s.tmp", path);
    FILE *f = fopen(temp, mode);
    if (!f) fprintf(stderr, "rocks_export: cannot write %s: %s\n", temp, strerror(errno));
    return f;
}

static bool temp_close(FILE *f, const char *temp, const char *path) {
    bool ok = !ferror(f);
    ok &= fclose(f) == 0;
    if (!ok || rename(temp, path) != 0) {
        fprintf(stderr, "rocks_export: cannot write %s\n", path);
        remove(temp);
        return false;
    }
    return true;
}

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
    char path[4096];
    core_error error = { 0 };
    for (int t = 0; t < tiles; t++) {
        snprintf(path, sizeof path, "%s/tile_%03d.ply", dir, t);
        if (!rocks_tile_write_ply(set, t, path, &error)) {
            fprintf(stderr, "rocks_export: %s\n", error.message);
            return 1;
        }
    }
    snprintf(path, sizeof path, "%s/tiles.json", dir);
    char temp[4200];
    FILE *f = temp_open(path, temp, sizeof temp, "w");
    if (!f) return 1;
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
    if (!temp_close(f, temp, path)) return 1;
    printf("rocks_export: %d tiles, %u rocks in the set (%.1f s%s, %.1f MB: %u vertices, %u indices) → %s\n", tiles,
           set->rock_count, set->build_seconds, set->from_cache ? ", from the cache" : "", (double)set->bytes / 1e6,
           set->vertex_count, set->index_count, dir);
    return 0;
}

/* ---- a region of a world -------------------------------------------------------------------- */

/* "X,Y,Z:NX,NY,NZ" (metres; sizes > 0, at most 4 096 each). */
static bool parse_region(const char *text, double min[3], double max[3]) {
    double v[6];
    char tail;
    if (sscanf(text, "%lf,%lf,%lf:%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &tail) != 6) return false;
    for (int a = 0; a < 3; a++) {
        if (!isfinite(v[a]) || fabs(v[a]) > 1e12 || !(v[3 + a] > 0) || v[3 + a] > 4096) return false;
        min[a] = v[a], max[a] = v[a] + v[3 + a];
    }
    return true;
}

static void rock_world_point(const rocks_placement *p, const rocks_instance *in, const float local[3], double out[3]) {
    for (int a = 0; a < 3; a++) out[a] = p->origin[a] + in->position[a] + (double)local[a] * EXPORT_TILE_SIZE;
}

static bool write_region_ply(const rocks_tileset *set, const rocks_placement *p, const char *path) {
    uint64_t vertices = 0, faces = 0;
    for (uint32_t i = 0; i < p->count; i++) {
        const rocks_rock *rock = &set->rocks[p->instances[i].rock];
        vertices += rock->vertex_count, faces += rock->index_count[0] / 3;
    }
    char temp[4200];
    FILE *f = temp_open(path, temp, sizeof temp, "wb");
    if (!f) return false;
    fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment rocks placed by rocks_export (world metres)\n"
               "element vertex %llu\nproperty float x\nproperty float y\nproperty float z\n"
               "property float nx\nproperty float ny\nproperty float nz\n"
               "element face %llu\nproperty list uchar int vertex_indices\nend_header\n",
            (unsigned long long)vertices, (unsigned long long)faces);
    for (uint32_t i = 0; i < p->count; i++) {
        const rocks_rock *rock = &set->rocks[p->instances[i].rock];
        for (uint32_t v = rock->vertex_first; v < rock->vertex_first + rock->vertex_count; v++) {
            double w[3];
            rock_world_point(p, &p->instances[i], set->vertices[v].position, w);
            float out[6] = { (float)w[0], (float)w[1], (float)w[2], set->vertices[v].normal[0] / 127.0f,
                             set->vertices[v].normal[1] / 127.0f, set->vertices[v].normal[2] / 127.0f };
            fwrite(out, sizeof out, 1, f);
        }
    }
    int32_t base = 0;
    for (uint32_t i = 0; i < p->count; i++) {
        const rocks_rock *rock = &set->rocks[p->instances[i].rock];
        const uint16_t *idx = set->indices + rock->index_first[0];
        for (uint32_t t = 0; t < rock->index_count[0]; t += 3) {
            uint8_t three = 3;
            int32_t tri[3] = { base + idx[t], base + idx[t + 1], base + idx[t + 2] };
            fwrite(&three, 1, 1, f);
            fwrite(tri, sizeof tri, 1, f);
        }
        base += (int32_t)rock->vertex_count;
    }
    return temp_close(f, temp, path);
}

static bool write_region_json(const rocks_tileset *set, const rocks_placement *p, int seed, const double min[3],
                              const double max[3], const char *path) {
    char temp[4200];
    FILE *f = temp_open(path, temp, sizeof temp, "w");
    if (!f) return false;
    fprintf(f, "{\"seed\":%d,\"tile_size\":%g,\"region\":{\"min\":[%.3f,%.3f,%.3f],\"max\":[%.3f,%.3f,%.3f]},"
               "\"count\":%u,\"rocks\":[", seed, EXPORT_TILE_SIZE, min[0], min[1], min[2], max[0], max[1], max[2], p->count);
    for (uint32_t i = 0; i < p->count; i++) {
        const rocks_rock *rock = &set->rocks[p->instances[i].rock];
        double s[3], lo[3], hi[3];
        rock_world_point(p, &p->instances[i], rock->seed, s);
        rock_world_point(p, &p->instances[i], rock->bounds_min, lo);
        rock_world_point(p, &p->instances[i], rock->bounds_max, hi);
        fprintf(f, "%s\n {\"shape\":%u,\"seed\":[%.4f,%.4f,%.4f],\"min\":[%.4f,%.4f,%.4f],\"max\":[%.4f,%.4f,%.4f]}",
                i ? "," : "", p->instances[i].rock, s[0], s[1], s[2], lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
    fprintf(f, "]}\n");
    return temp_close(f, temp, path);
}

static int export_region(const export_args *args, rocks_shape shape, const double min[3], const double max[3],
                         job_system *jobs) {
    /* the flags' defaults are the game's set: 5 cells, 10 voxels, mixed, seed 1 */
    rocks_tileset *set = rocks_tileset_create(&(rocks_tileset_desc){ .cells = args->cells, .voxels_per_cell = args->voxels,
                                                                 .shape = shape, .jobs = jobs,   /* seed: the game's */
                                                                 .cache_path = args->cache });
    if (!set) return 1;
    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generation = terrain_generation_defaults((uint64_t)args->seed) });
    rocks_placement placement = { 0 };
    int status = 1;
    if (rocks_place_box(&(rocks_place_desc){ .tiles = set, .world = world, .tile_size = (float)EXPORT_TILE_SIZE },
                        min, max, &placement)) {
        char ply[4096], json[4096];
        snprintf(ply, sizeof ply, "%s.ply", args->out);
        snprintf(json, sizeof json, "%s.json", args->out);
        if (write_region_ply(set, &placement, ply) && write_region_json(set, &placement, args->seed, min, max, json)) {
            printf("rocks_export: %u rocks in [%.1f, %.1f, %.1f] … [%.1f, %.1f, %.1f] of seed %d → %s, %s\n",
                   placement.count, min[0], min[1], min[2], max[0], max[1], max[2], args->seed, ply, json);
            status = 0;
        }
    }
    rocks_placement_free(&placement);
    terrain_world_destroy(world);
    rocks_tileset_destroy(set);
    return status;
}

int main(int argc, char **argv) {
    export_args args = { .tiles = 1, .cells = 5, .voxels = 10, .shape = "mixed", .seed = 1 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(args.common),
        { .name = "tiles", .kind = CORE_OPTION_INT, .value = &args.tiles, .min = 1, .max = 256, .metavar = "N",
          .help = "write tiles 0 … N − 1" },
        { .name = "out", .kind = CORE_OPTION_STRING, .value = &args.out, .metavar = "DIR", .help = "output folder (required; with --region a file prefix)" },
        { .name = "cells", .kind = CORE_OPTION_INT, .value = &args.cells, .min = 4, .max = 8, .metavar = "N",
          .help = "cells along a tile's side (default 5)" },
        { .name = "voxels", .kind = CORE_OPTION_INT, .value = &args.voxels, .min = 4, .max = 16, .metavar = "N",
          .help = "voxels along a cell's side (default 10)" },
        { .name = "shape", .kind = CORE_OPTION_STRING, .value = &args.shape, .metavar = "KIND",
          .help = "round, slab or mixed (default)" },
        { .name = "seed", .kind = CORE_OPTION_INT, .value = &args.seed, .min = 1, .max = 2147483647, .metavar = "S",
          .help = "the tile set's seed (default 1, the game's); with --region the world's" },
        { .name = "cache", .kind = CORE_OPTION_STRING, .value = &args.cache, .metavar = "FILE",
          .help = "read or write the tile set's cache here" },
        { .name = "region", .kind = CORE_OPTION_STRING, .value = &args.region, .metavar = "X,Y,Z:NX,NY,NZ",
          .help = "instead of tiles: the rocks the world places in this box (metres), to PREFIX.ply/.json" },
    };
    core_cli cli = { .program = "rocks_export", .summary = "write rock tiles (paper 001), or the rocks a world places, as PLY files and JSON",
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
        fprintf(stderr, "rocks_export: --out %s is required\n", args.region ? "PREFIX" : "DIR");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (args.region) {
        double min[3], max[3];
        if (!parse_region(args.region, min, max)) {
            fprintf(stderr, "rocks_export: --region '%s' is not X,Y,Z:NX,NY,NZ (metres, sizes 0 < N ≤ 4096)\n",
                    args.region);
            core_cli_print_usage(&cli, stderr);
            return 2;
        }
        job_system *jobs = job_system_create(&(job_system_desc){ .threads = args.common.threads });
        int status = export_region(&args, shape, min, max, jobs);
        job_system_destroy(jobs);
        return status;
    }
    if (!core_make_dirs(args.out) || access(args.out, W_OK) != 0) {
        fprintf(stderr, "rocks_export: cannot write into %s: %s\n", args.out, strerror(errno));
        return 2;
    }
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = args.common.threads });
    rocks_tileset *set = rocks_tileset_create(&(rocks_tileset_desc){ .seed = (uint64_t)args.seed, .cells = args.cells,
                                                                 .voxels_per_cell = args.voxels, .shape = shape,
                                                                 .jobs = jobs, .cache_path = args.cache });
    int status = set ? export_tiles(set, args.tiles, args.out) : 1;
    rocks_tileset_destroy(set);
    job_system_destroy(jobs);
    return status;
}
