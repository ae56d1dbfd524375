/* terrain_mesh — mesh a field file with the terrain's marching cubes:
 *
 *   terrain_mesh PREFIX.json [--apron N] [--no-optimize] [--ply OUT.ply] [--threads N] [--repeat N]
 *
 * Reads PREFIX.json + PREFIX.raw (terrain.h's field file format; terrain_export writes it) and
 * prints one JSON line: {"vertices":V,"triangles":T,"area":A,"ms":M,"threads":N}, where ms is
 * the meshing time alone (not the reading), the median (nearest rank) of --repeat runs
 * (default 1). Meshing uses every core (--threads 0, the default) for fields of 64³ cells and more, as VTK's
 * vtkFlyingEdges3D does; tools/peers/vtk_flying_edges.py runs that peer on the same file.
 * Weights are all bedrock (no world). A bad command line exits 2; a file that cannot be read or
 * is not a valid field gets a message naming the problem and exits 1.
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int compare_ms(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    int apron = 0;
    bool no_optimize = false;
    int repeat = 1;
    const char *ply_path = NULL;
    const char *positional[1] = { 0 };
    int positional_count = 0;
    core_common_args common = { 0 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { .name = "apron", .kind = CORE_OPTION_INT, .value = &apron, .metavar = "N", .min = 0, .max = 64,
          .help = "border samples read for normals but not meshed (default 0)" },
        { .name = "no-optimize", .kind = CORE_OPTION_FLAG, .value = &no_optimize,
          .help = "skip the vertex-cache reordering" },
        { .name = "repeat", .kind = CORE_OPTION_INT, .value = &repeat, .metavar = "N", .min = 1, .max = 1000,
          .help = "mesh N times and report the median time (default 1)" },
        { .name = "ply", .kind = CORE_OPTION_STRING, .value = &ply_path, .metavar = "OUT",
          .help = "also write the mesh as binary PLY" },
    };
    core_cli cli = {
        .program = "terrain_mesh",
        .summary = "Mesh a field file (PREFIX.json + PREFIX.raw) with marching cubes; print one JSON line.",
        .options = options,
        .option_count = (int)CORE_COUNTOF(options),
        .positional_name = "PREFIX.json",
        .positional = positional,
        .positional_min = 1,
        .positional_max = 1,
        .positional_count = &positional_count,
    };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (ply_path) {   /* an unwritable output fails now, not after the work */
        FILE *probe = fopen(ply_path, "ab");
        if (!probe) {
            fprintf(stderr, "terrain_mesh: cannot write --ply %s: %s\n", ply_path, strerror(errno));
            return 2;
        }
        fclose(probe);
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    int status = 1;
    core_error error = { 0 };
    terrain_field field;
    terrain_mesh mesh = { 0 };
    if (!terrain_field_read(positional[0], &field, &error)) {
        fprintf(stderr, "terrain_mesh: %s\n", error.message);
        goto done;
    }
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    const terrain_mesh_desc desc = { .apron = apron, .no_optimize = no_optimize, .jobs = jobs };
    double times[1000];
    int runs = 0;
    bool meshed = true;
    while (runs < repeat && meshed) {
        terrain_mesh_free(&mesh);
        trace_zone_begin("mesh");
        uint64_t start = core_time_ns();
        meshed = terrain_mesh_build(&field, &desc, &mesh);
        times[runs++] = core_ns_to_ms(core_time_ns() - start);
        trace_zone_end();
    }
    int threads = job_thread_count(jobs);
    job_system_destroy(jobs);
    qsort(times, (size_t)runs, sizeof *times, compare_ms);
    double ms = trace_percentile(times, (size_t)runs, 50);
    if (!meshed) {
        fprintf(stderr, "terrain_mesh: %s: cannot mesh this field\n", positional[0]);
        goto done;
    }
    if (ply_path && !terrain_mesh_write_ply(&mesh, ply_path, &error)) {
        fprintf(stderr, "terrain_mesh: %s\n", error.message);
        goto done;
    }
    printf("{\"vertices\":%u,\"triangles\":%u,\"area\":%.6g,\"ms\":%.4g,\"threads\":%d}\n", mesh.vertex_count,
           mesh.index_count / 3, terrain_mesh_area(&mesh), ms, threads);
    status = 0;
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "terrain_mesh: cannot write the output: %s\n", strerror(errno));
        status = 1;
    }
done:
    terrain_mesh_free(&mesh);
    terrain_field_free(&field);
    trace_stop();
    return status;
}
