/* terrain_edit — terrain editing in one short program, no window: pick a point on the ground, carve
 * a crater and an arched tunnel (a sweep with a profile curve), drop sand on the rim and inside the
 * tunnel (on its floor, not on the hill above), let it slide to its angle of repose, save the edits
 * in a world folder (one transaction), and see them come back in a fresh world.
 *
 *   terrain_edit [--seed S] [--world DIR] [--threads N] [--trace FILE]
 *
 * The steps are the ones a game takes (game/tools.c does the same from the mouse): aim with
 * terrain_raycast, apply with terrain_world_edit, stabilize the chunks that changed, keep an edit
 * log and keep it in a world folder (terrain_store: DIR/world.db). A running world (terrain_ecs) does the stabilizing and remeshing itself:
 * terrain_ecs_edit queues a stroke and the next frame shows it.
 */
#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <stdio.h>

/* Sand of a chunk, in m³. */
static double chunk_sand(terrain_world *world, terrain_chunk_coord coord) {
    const terrain_stacks *stacks = terrain_world_stacks(world, coord);
    terrain_layer layers[64];
    double sand = 0;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            int n = terrain_stacks_column(stacks, i, k, layers, 64);
            for (int l = 0; l < n && l < 64; l++)
                if (layers[l].material == TERRAIN_SAND) sand += layers[l].thickness;
        }
    return sand;
}

/* Stabilizes the chunks around (cx, cz) until nothing moves, then writes them back. */
static int settle(terrain_world *world, job_system *jobs, int64_t cx, int64_t cz) {
    enum { SIDE = 3 };
    terrain_columns *regions[SIDE * SIDE];
    for (int n = 0; n < SIDE * SIDE; n++) {
        terrain_chunk_coord c = { cx + n % SIDE - 1, cz + n / SIDE - 1 };
        regions[n] = terrain_columns_create(&(terrain_columns_desc){
            .x = c.x * TERRAIN_CHUNK_COLUMNS, .z = c.z * TERRAIN_CHUNK_COLUMNS,
            .width = TERRAIN_CHUNK_COLUMNS, .depth = TERRAIN_CHUNK_COLUMNS });
        terrain_columns_load(regions[n], c, terrain_world_stacks(world, c));
        terrain_columns_touch(regions[n], 0, 0, TERRAIN_CHUNK_COLUMNS, TERRAIN_CHUNK_COLUMNS);
    }
    terrain_stabilize_result result;
    terrain_stabilize_regions(regions, SIDE * SIDE, &(terrain_stabilize_desc){ 0 }, jobs, &result);
    for (int n = 0; n < SIDE * SIDE; n++) {
        terrain_chunk_coord c = { cx + n % SIDE - 1, cz + n / SIDE - 1 };
        if (terrain_columns_changed_chunks(regions[n], NULL, 0, true))
            terrain_world_commit(world, c, terrain_columns_to_stacks(regions[n], c), TERRAIN_EDIT_STABILIZE);
        terrain_columns_destroy(regions[n]);
    }
    return result.iterations;
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    int seed = 7;
    const char *dir = "out/terrain_edit";
    core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { .name = "seed", .kind = CORE_OPTION_INT, .value = &seed, .min = 0, .max = 2147483647, .metavar = "S",
          .help = "world seed (default 7)" },
        { .name = "world", .kind = CORE_OPTION_STRING, .value = &dir, .metavar = "DIR",
          .help = "where the edits are saved (default out/terrain_edit)" },
    };
    core_cli cli = { .program = "terrain_edit", .summary = "Carve, deposit, stabilize, save and reload terrain edits.",
                     .options = options, .option_count = (int)CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    terrain_generation_desc params = terrain_generation_defaults((uint64_t)seed);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
    /* The world folder: its earlier edits (if any) come into the log, and it is held until
     * destroyed (a second program opening it is refused). */
    terrain_store_report report;
    core_error error = { 0 };   /* .code says what kind of failure (CORE_ERROR_MISMATCH: another world's) */
    terrain_store *store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = log,
                                                                       .seed = (uint64_t)seed }, &report, &error);
    if (!store) {
        fprintf(stderr, "terrain_edit: %s\n", error.message);
        return 1;
    }
    if (report.notice[0]) printf("%s\n", report.notice);
    if (report.chunks_loaded) printf("%s holds %d edited chunk(s) from earlier runs\n", dir, report.chunks_loaded);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = params, .edits = log });

    /* Aim: straight down onto the ground at (16, 16). */
    terrain_ray_hit hit;
    if (!terrain_raycast(world, (const double[3]){ 16.5, 400, 16.5 }, (const float[3]){ 0, -1, 0 }, 1000, &hit)) {
        fprintf(stderr, "terrain_edit: no ground under (16, 16)\n");
        return 1;
    }
    printf("ground at (%.1f, %.2f, %.1f), %s\n", hit.position[0], hit.position[1], hit.position[2],
           terrain_material_name(hit.material));

    /* A crater, a 20 m tunnel into the ground beside it, and 60 m³ of sand on the crater's rim. The
     * tunnel's cross-section is a profile curve (radius scales around the axis, the first one
     * towards the surface, up here): an arch half as high again as it is wide, and a lower floor. */
    int crater = terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
        .sculpt = { .target = { hit.position[0], hit.position[1], hit.position[2] }, .radius = 4 } }, NULL, 0);
    double tunnel[2][3] = { { 10, hit.position[1] - 3, 4 }, { 30, hit.position[1] - 8, 4 } };
    const float arch[4] = { 1.5f, 1.0f, 0.8f, 1.0f };   /* up, side, down, side */
    int tunnelled = terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
        .sweep = { .points = (const double (*)[3])tunnel, .point_count = 2, .radius = 2,
                   .profile = arch, .profile_count = 4 } }, NULL, 0);
    int sanded = terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
        .deposit = { .x = hit.position[0] + 4, .z = hit.position[2], .radius = 3, .volume = 60 } }, NULL, 0);
    printf("crater: %d chunk(s), tunnel: %d, sand: %d; sand in chunk (0, 0): %.1f m³\n", crater, tunnelled, sanded,
           chunk_sand(world, (terrain_chunk_coord){ 0, 0 }));
    /* 4 m³ of sand dropped at the tunnel's axis height (as the game's sand tool does at the hit
     * point): it lands on the tunnel's floor, 1.6 m below the axis, and the hill above keeps its
     * ground. */
    double axis = hit.position[1] - 5.5, floor = axis - 0.8 * 2;
    terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
        .deposit = { .x = 20, .z = 4, .radius = 1, .volume = 4, .at_height = true, .y = axis } }, NULL, 0);
    printf("in the tunnel at x = 20: %s on the floor, %s at the axis\n",
           terrain_material_name(terrain_world_material_at(world, 20, floor + 0.1, 4)),
           terrain_material_name(terrain_world_material_at(world, 20, axis, 4)));
    printf("stabilized in %d iterations; the tunnel's axis at x = 20 is %s\n", settle(world, jobs, 0, 0),
           terrain_material_name(terrain_world_material_at(world, 20, hit.position[1] - 5.5, 4)));

    /* Save (every changed chunk in one transaction), close, then a fresh world from the folder:
     * the same chunk, byte for byte. */
    bool saved = terrain_store_save(store, &error);
    terrain_store_destroy(store);
    if (!saved) {
        fprintf(stderr, "terrain_edit: %s\n", error.message);
        return 1;
    }
    uint64_t edited = terrain_stacks_hash(terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 }));
    terrain_edit_log *loaded = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
    terrain_store *reopened = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = loaded }, &report,
                                                   NULL);
    terrain_world *again = terrain_world_create(&(terrain_world_desc){ .generation = params, .edits = loaded });
    uint64_t reloaded = terrain_stacks_hash(terrain_world_stacks(again, (terrain_chunk_coord){ 0, 0 }));
    printf("saved %d chunk(s) to %s/world.db; reloaded: %s\n", terrain_edit_log_chunks(log), dir,
           reopened && reloaded == edited ? "the same bytes" : "DIFFERENT");

    terrain_world_destroy(again);
    terrain_store_destroy(reopened);
    terrain_edit_log_destroy(loaded);
    terrain_world_destroy(world);
    terrain_edit_log_destroy(log);
    job_system_destroy(jobs);
    trace_stop();
    return reopened && reloaded == edited ? 0 : 1;
}

/* Expected output:
 * Run: --threads 2 --world $TMP/terrain_edit
 * ^ground at \([0-9.-]+, [0-9.-]+, [0-9.-]+\), 
 * ^crater: [1-9][0-9]* chunk\(s\), tunnel: [1-9][0-9]*, sand: [1-9][0-9]*; 
 * ^in the tunnel at x = 20: sand on the floor, air at the axis$
 * ^stabilized in [0-9]+ iterations; the tunnel.s axis at x = 20 is air$
 * ^saved [1-9][0-9]* chunk\(s\) to [^ ]+world\.db; reloaded: the same bytes$
 */
