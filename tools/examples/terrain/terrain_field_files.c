/* terrain_field_files — the implicit field and its files (modules/terrain/data/terrain_data.h,
 * "the implicit field", "meshes", "field and mesh files"):
 *
 *   1. sample the field f of a generated world over a box (f > 0 solid, f < 0 air);
 *   2. write it as PREFIX.json + PREFIX.raw (terrain_field_write), read it back
 *      (terrain_field_read) and check that every value came back;
 *   3. mesh what was read (marching cubes, terrain_mesh_build, on the job system's threads) and
 *      print its size, area and parts (what a renderer culls on its own); with --ply, write the
 *      mesh as a binary PLY too.
 *
 *   terrain_field_files [--seed S] [--size N] [--out PREFIX] [--ply FILE] [--threads N] [--trace FILE]
 *
 * The files are what tools/terrain_export writes and tools/terrain_mesh reads, for other
 * programs (ParaView, Blender, a peer's mesher) to open. Without --out they go to a temporary
 * folder that is removed at the end.
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *out = NULL, *ply = NULL;
    int seed = 3, size = 24;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "seed", CORE_OPTION_INT, &seed, "S", "world seed (default 3)", 0, 2147483647 },
        { "size", CORE_OPTION_INT, &size, "N", "samples along x and z (default 24; y is 64)", 2, 1024 },
        { "out", CORE_OPTION_STRING, &out, "PREFIX", "write PREFIX.json and PREFIX.raw (default: a temporary)" },
        { "ply", CORE_OPTION_STRING, &ply, "FILE", "write the mesh as a binary PLY" },
    };
    core_cli cli = { .program = "terrain_field_files", .summary = "sample a field, write it, read it back, mesh it",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");
    char folder[64] = "/tmp/terrain_field_files-XXXXXX", prefix[128];
    if (!out) {
        if (!mkdtemp(folder)) { perror("terrain_field_files: temporary folder"); return 1; }
        snprintf(prefix, sizeof prefix, "%s/field", folder);
        out = prefix;
    }
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generation = terrain_generation_defaults((uint64_t)seed) });

    /* 1. A box of size × 64 × size samples, 1 m apart, from 24 m under the ground at (4, 4)
     * (with the default size, inside chunk (0, 0): one chunk to generate). */
    int64_t ground = (int64_t)terrain_world_top(world, 4, 4);
    terrain_field field;
    if (!terrain_field_sample(world, &(terrain_field_desc){ .first = { 4, ground - 24, 4 }, .size = { size, 64, size } },
                              &field))
        return 1;
    size_t count = (size_t)field.nx * (size_t)field.ny * (size_t)field.nz, solid = 0;
    for (size_t i = 0; i < count; i++) solid += field.values[i] > 0;
    printf("terrain_field_files: sampled %d x %d x %d, %.0f%% solid\n", field.nx, field.ny, field.nz,
           100.0 * (double)solid / (double)count);

    /* 2. Written and read back. Errors are a code (CORE_ERROR_IO, CORE_ERROR_FORMAT, …) and a
     * message naming the file and the problem. */
    core_error error = { 0 };
    terrain_field back;
    if (!terrain_field_write(&field, out, &error) || !terrain_field_read(out, &back, &error)) {
        fprintf(stderr, "terrain_field_files: %s (%s)\n", error.message, core_error_code_name(error.code));
        return 1;
    }
    bool same = back.nx == field.nx && back.ny == field.ny && back.nz == field.nz &&
                memcmp(back.values, field.values, count * sizeof(float)) == 0;
    const char *shown = out == prefix ? "field" : out;   /* the temporary's name, without its folder */
    printf("terrain_field_files: wrote %s.json and %s.raw, read back %s\n", shown, shown,
           same ? "the same values" : "DIFFERENT values");
    terrain_field_free(&field);

    /* 3. Meshed from the file's field. With a world, the vertices get material weights and
     * occlusion; `.jobs` lets the mesher split a big field over the threads. */
    terrain_mesh mesh;
    if (!terrain_mesh_build(&back, &(terrain_mesh_desc){ .world = world, .jobs = jobs }, &mesh)) return 1;
    printf("terrain_field_files: mesh of %u vertices, %u triangles, %.0f m2\n", mesh.vertex_count,
           mesh.index_count / 3, terrain_mesh_area(&mesh));
    /* The triangles come in parts, runs of the indices by a grid over the mesh's box in x and z,
     * each with its box: a renderer draws only the parts its view can see. */
    uint32_t largest = 0;
    for (uint32_t p = 0; p < mesh.part_count; p++)
        if (mesh.parts[p].index_count > largest) largest = mesh.parts[p].index_count;
    printf("terrain_field_files: in %u parts of up to %d, the largest %u triangles\n", mesh.part_count,
           TERRAIN_MESH_PARTS, largest / 3);
    if (ply && !terrain_mesh_write_ply(&mesh, ply, &error)) {
        fprintf(stderr, "terrain_field_files: %s\n", error.message);
        rc = 1;
    } else if (ply) {
        printf("terrain_field_files: wrote %s\n", ply);
    }
    terrain_mesh_free(&mesh);
    terrain_field_free(&back);

    if (out == prefix) {
        char path[160];
        snprintf(path, sizeof path, "%s.json", prefix);
        remove(path);
        snprintf(path, sizeof path, "%s.raw", prefix);
        remove(path);
        rmdir(folder);
    }
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    trace_stop();
    return rc < 0 ? 0 : rc;
}

/* Expected output:
 * Run: --seed 3 --threads 2
 * ^terrain_field_files: sampled 24 x 64 x 24, [0-9]+% solid$
 * ^terrain_field_files: wrote field\.json and field\.raw, read back the same values$
 * ^terrain_field_files: mesh of [1-9][0-9]* vertices, [1-9][0-9]* triangles, [1-9][0-9]* m2$
 * ^terrain_field_files: in [1-9][0-9]* parts of up to 16, the largest [1-9][0-9]* triangles$
 */
