/* terrain_export — sample the terrain's field over a region and write it with its mesh:
 *
 *   terrain_export --seed S --region X,Y,Z:NX,NY,NZ --out PREFIX [--sigma M]
 *
 * The region is in sample indices (metres, with 1 m columns): NX × NY × NZ samples starting at
 * sample (X, Y, Z), i.e. (NX − 1) × (NY − 1) × (NZ − 1) cells. Writes PREFIX.raw + PREFIX.json
 * (the field, terrain.h's field file format: what tools/terrain_mesh and other meshers read) and
 * PREFIX.ply (our mesh of exactly those samples, binary PLY). A bad command line prints the usage
 * and exits 2, an unwritable --out too (before any work); a failure while writing exits 1.
 */
#include "core/core.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define EXPORT_MAX_SAMPLES 1024   /* per axis, as terrain_field_sample allows */

/* Reads a decimal integer from *text up to one of `stops` (or the end); advances past it. */
static bool parse_int64(const char **text, int64_t *out) {
    const char *s = *text;
    if (!(*s == '-' || *s == '+' || (*s >= '0' && *s <= '9'))) return false;
    errno = 0;
    char *end;
    long long value = strtoll(s, &end, 10);
    if (end == s || errno == ERANGE) return false;
    *out = value;
    *text = end;
    return true;
}

/* "X,Y,Z:NX,NY,NZ" → first and size; on failure a message naming what was wrong. */
static bool parse_region(const char *text, int64_t first[3], int size[3], char *error, size_t error_size) {
    static const char *names[3] = { "NX", "NY", "NZ" };
    const char *s = text;
    for (int a = 0; a < 3; a++) {
        if (!parse_int64(&s, &first[a]) || first[a] < -((int64_t)1 << 40) || first[a] > ((int64_t)1 << 40)) {
            snprintf(error, error_size, "the %s coordinate is not a whole number within ±2^40", a == 0 ? "first" : a == 1 ? "second" : "third");
            return false;
        }
        char want = a < 2 ? ',' : ':';
        if (*s != want) {
            snprintf(error, error_size, "expected '%c' after the %s coordinate", want, a == 0 ? "first" : a == 1 ? "second" : "third");
            return false;
        }
        s++;
    }
    for (int a = 0; a < 3; a++) {
        int64_t count;
        if (!parse_int64(&s, &count)) {
            snprintf(error, error_size, "%s is not a whole number", names[a]);
            return false;
        }
        if (count < 2 || count > EXPORT_MAX_SAMPLES) {
            snprintf(error, error_size, "%s = %" PRId64 " must be 2 … %d samples", names[a], count, EXPORT_MAX_SAMPLES);
            return false;
        }
        size[a] = (int)count;
        if (a < 2 && *s != ',') {
            snprintf(error, error_size, "expected ',' after %s", names[a]);
            return false;
        }
        if (a < 2) s++;
    }
    if (*s != '\0') {
        snprintf(error, error_size, "unexpected '%s' at the end", s);
        return false;
    }
    return true;
}

static bool parse_seed(const char *text, uint64_t *out) {
    if (!text[0] || text[0] == '-' || text[0] == '+') return false;
    errno = 0;
    char *end;
    unsigned long long value = strtoull(text, &end, 0);
    if (*end != '\0' || errno == ERANGE) return false;
    *out = value;
    return true;
}

/* Whether a file can be created beside PREFIX (the outputs go to temporaries there). */
static bool can_write_beside(const char *prefix) {
    char *probe = core_strjoin(prefix, ".probe.tmp");
    FILE *file = fopen(probe, "wb");
    bool ok = file != NULL;
    if (file) {
        fclose(file);
        remove(probe);
    }
    core_free(probe, strlen(probe) + 1);
    return ok;
}

int main(int argc, char **argv) {
    const char *seed_text = NULL, *region_text = NULL, *out_prefix = NULL;
    double sigma = 0.0;
    core_common_args common = { 0 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(common), /* every program takes them; the export runs on one thread */
        { .name = "seed", .kind = CORE_OPTION_STRING, .value = &seed_text, .metavar = "S",
          .help = "world seed (a whole number ≥ 0; default 42)" },
        { .name = "region", .kind = CORE_OPTION_STRING, .value = &region_text, .metavar = "X,Y,Z:NX,NY,NZ",
          .help = "first sample (X, Y, Z) and samples per axis (2 … 1024), in metres (required)" },
        { .name = "out", .kind = CORE_OPTION_STRING, .value = &out_prefix, .metavar = "PREFIX",
          .help = "write PREFIX.raw, PREFIX.json (the field) and PREFIX.ply (the mesh) (required)" },
        { .name = "sigma", .kind = CORE_OPTION_DOUBLE, .value = &sigma, .metavar = "M",
          .min_double = 0.0, .max_double = 16.0, .help = "kernel radius in metres (default 0 = one column)" },
    };
    core_cli cli = {
        .program = "terrain_export",
        .summary = "Sample the terrain's implicit field over a region; write it (raw + json) and its mesh (ply).",
        .options = options,
        .option_count = (int)CORE_COUNTOF(options),
    };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;

    uint64_t seed = 42;
    int64_t first[3];
    int size[3];
    char message[256];
    const char *problem = NULL;
    if (seed_text && !parse_seed(seed_text, &seed)) {
        snprintf(message, sizeof message, "bad value for '--seed': '%s' is not a whole number ≥ 0", seed_text);
        problem = message;
    } else if (!region_text) {
        problem = "missing '--region X,Y,Z:NX,NY,NZ'";
    } else if (!out_prefix) {
        problem = "missing '--out PREFIX'";
    } else {
        char detail[160];
        if (!parse_region(region_text, first, size, detail, sizeof detail)) {
            snprintf(message, sizeof message, "bad value for '--region': '%s': %s (want X,Y,Z:NX,NY,NZ, e.g. 0,-16,0:64,48,64)",
                     region_text, detail);
            problem = message;
        }
    }
    if (problem) {
        fprintf(stderr, "terrain_export: %s\n", problem);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (!can_write_beside(out_prefix)) {
        fprintf(stderr, "terrain_export: cannot write --out %s: %s\n", out_prefix, strerror(errno));
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    int status = 1;
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(seed) });
    terrain_field field = { 0 };
    terrain_mesh mesh = { 0 };
    char *ply = core_strjoin(out_prefix, ".ply");
    trace_zone_begin("field");
    bool sampled = terrain_field_sample(world, &(terrain_field_desc){ .first = { first[0], first[1], first[2] },
                                                                      .size = { size[0], size[1], size[2] },
                                                                      .sigma = (float)sigma },
                                        &field);
    trace_zone_end();
    if (!sampled) goto done;
    trace_zone_begin("mesh");
    bool meshed = terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = world }, &mesh);
    trace_zone_end();
    if (!meshed) goto done;
    core_error error = { 0 };
    if (!terrain_field_write(&field, out_prefix, &error) || !terrain_mesh_write_ply(&mesh, ply, &error)) {
        fprintf(stderr, "terrain_export: %s\n", error.message);
        goto done;
    }
    printf("terrain_export: %s.raw + %s.json: %d x %d x %d samples from (%" PRId64 ", %" PRId64 ", %" PRId64
           "); %s: %u vertices, %u triangles\n",
           out_prefix, out_prefix, size[0], size[1], size[2], first[0], first[1], first[2], ply, mesh.vertex_count,
           mesh.index_count / 3);
    status = 0;
done:
    core_free(ply, strlen(ply) + 1);
    terrain_mesh_free(&mesh);
    terrain_field_free(&field);
    terrain_world_destroy(world);
    trace_stop();
    return status;
}
