/* terrain_streaming — chunks that follow a viewer (modules/terrain/ecs/terrain_ecs.h, "streaming"):
 *
 * terrain_ecs_stream turns the terrain's ECS systems from a fixed area into rings of mesh
 * chunks around each viewer; generation and meshing run as background jobs that span frames,
 * so no frame waits for them. A clipmap (terrain_clipmap) draws the far ground and sinks under
 * the square the rings cover once their chunks are in. Here a viewer moves one chunk (32 m)
 * along −x at each step (seed 1's ground stays near the start's height that way; along +x it
 * climbs a mountain); after each step the frames run until every wanted chunk is ready, and the
 * counts are printed: the chunks the rings want, how many are ready, how many left behind are
 * kept while memory allows; at the end, the triangles the chunks hold.
 *
 * --levels adds coarser rings, and --simplify says which levels' chunks are simplified by their
 * level's own error (terrain_stream_desc.simplify; none by default): coarse leaves level 0
 * whole, so with one level it is none; try --levels 2 with each to see the triangles it saves.
 *
 *   terrain_streaming [--seed S] [--hills] [--steps N] [--levels N] [--simplify none|coarse|all]
 *                     [--size WxH] [--headless] [--screenshot FILE] [--threads N] [--trace FILE]
 *
 * The rings here are small (2 × 2 chunks of full detail, over 32 m of height); a generated
 * chunk takes a few hundred ms to mesh in a debug build, so the check runs over --hills, a world
 * of gentle hills made by hand that streams in well under a second. Nothing is drawn offscreen
 * unless --screenshot asks for a picture.
 *
 * The world program (game/) streams the same way around the player, with wider rings.
 */
#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

/* --hills: a world made by hand, one layer of bedrock a column over gentle hills (a pure
 * function of the column), instead of the generator's caves and cliffs: it streams in a blink
 * even in a debug build. */
static void hill_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    double height = 4.0 * sin((double)x * 0.157) + 2.0 * cos((double)z * 0.126);
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, (float)(height - TERRAIN_FLOOR_Y));
}
static terrain_stacks *hills(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, hill_column, user);
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL, *simplify_name = NULL;
    int seed = 1, steps = 3, levels = 1;
    bool headless = false, hand_made = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "seed", CORE_OPTION_INT, &seed, "S", "world seed (default 1)", 0, 2147483647 },
        { "steps", CORE_OPTION_INT, &steps, "N", "chunks the viewer moves, one a step (default 3)", 0, 100 },
        { "levels", CORE_OPTION_INT, &levels, "N", "rings of detail, each coarser one twice the cells (default 1)", 1, 4 },
        { "simplify", CORE_OPTION_STRING, &simplify_name, "none|coarse|all", "which levels' chunks are simplified "
          "(default none; coarse: levels 1 and up)" },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 320x180)" },
        { "hills", CORE_OPTION_FLAG, &hand_made, NULL, "gentle hills made by hand instead of the generator's world" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "terrain_streaming", .summary = "mesh chunks that follow a moving viewer",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 320, height = 180;
    if (size && !gfx_parse_size(size, &width, &height)) {
        fprintf(stderr, "terrain_streaming: bad value for '--size': '%s' is not WxH\n", size);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    terrain_simplify simplify = TERRAIN_SIMPLIFY_NONE;
    if (simplify_name && !terrain_parse_simplify(simplify_name, &simplify)) {
        fprintf(stderr, "terrain_streaming: bad value for '--simplify': '%s' is not none, coarse or all\n", simplify_name);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* Meshes are uploaded to the GPU, so there is a context (offscreen with --headless). */
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "terrain_streaming",
                                               .headless = headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_generation_desc params = terrain_generation_defaults((uint64_t)seed);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = params,
                                                                       .generate = hand_made ? hills : NULL });
    /* A renderer only when there is something to see: a window, or a screenshot to write
     * (making its material textures takes a second in a debug build). */
    terrain_renderer *renderer = NULL;
    if (gfx_backend_get(gfx) == GFX_BACKEND_WINDOW || screenshot) {
        renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = params.sea_level,
                                                                          .shadows = TERRAIN_SHADOWS_OFF });
        if (!renderer) return 1;
    }

    /* Small rings: 2 × 2 chunks of full detail around the viewer (4 × 4 with coarser levels:
     * their rings align with the coarser chunks), over the 32 m of height around the start's
     * ground; the far ground beyond is the clipmap's. */
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    double ground = terrain_world_top(world, 16, 16);
    terrain_ecs_stream(te, &(terrain_stream_desc){ .half_width = 1, .levels = levels, .y_min = ground - 16,
                                                   .y_max = ground + 16, .collision_radius = 1,
                                                   .simplify = simplify });
    terrain_clipmap *far = terrain_clipmap_create(&(terrain_clipmap_desc){ .levels = 3, .cells = 32,
                                                                          .generation = params, .jobs = jobs });
    terrain_ecs_set_clipmap(te, far);
    /* The clipmap's heights come from the generation parameters alone: over hand-made hills it
     * still follows the viewer and sinks under the rings, but would draw another world's ground. */
    if (renderer && !hand_made) terrain_renderer_set_clipmap(renderer, far);

    terrain_view view = { .camera = { 16, ground + 12, 16 }, .yaw = -1.57f, .pitch = -0.6f,   /* facing −x */
                          .aspect = (float)width / (float)height };
    for (int step = 0; step <= steps; step++) {
        view.camera[0] = 16 - 32.0 * step;             /* one chunk further along −x */
        const double eye[1][3] = { { view.camera[0], view.camera[1], view.camera[2] } };
        terrain_ecs_stream_stats_info stats = { 0 };
        for (int frame = 0; frame < 2000; frame++) {   /* until the rings are in */
            trace_frame_begin();
            terrain_ecs_set_viewers(te, eye, 1);
            terrain_ecs_set_view(te, &view);
            ecs_progress(ecs, 1.0f / 60.0f);            /* stream, generate, mesh, cull, upload */
            stats = terrain_ecs_stream_stats(te);
            bool ready = stats.mesh_chunks_ready == stats.mesh_chunks_wanted && stats.jobs_in_flight == 0;
            if (ready && renderer) {                   /* drawn once in: a frame is ms of llvmpipe */
                gfx_frame_begin(gfx);
                terrain_ecs_draw(te, renderer, &view); /* the chunks, the clipmap and the sky */
                if (step == steps && screenshot && !gfx_screenshot(gfx, screenshot)) rc = 1;
                gfx_frame_end(gfx);
            } else {
                terrain_world_trim(world);             /* what the draw does after drawing */
            }
            /* The rest of a frame's time: the main thread helps with the background jobs. */
            if (!ready) job_help(jobs, 2000000);
            trace_frame_end();
            if (ready) break;
        }
        printf("terrain_streaming: step %d at x %.0f: %d chunks wanted, %d ready, %d kept\n", step, view.camera[0],
               stats.mesh_chunks_wanted, stats.mesh_chunks_ready, stats.mesh_chunks_kept);
    }
    terrain_ecs_stream_stats_info stats = terrain_ecs_stream_stats(te);
    printf("terrain_streaming: %llu chunks meshed, %llu empty skipped unsampled, %.1f MB resident, %llu triangles\n",
           (unsigned long long)stats.chunks_meshed, (unsigned long long)stats.chunks_skipped_empty,
           (double)stats.resident_bytes / (1 << 20), (unsigned long long)terrain_ecs_stats(te).triangles);

    terrain_ecs_set_clipmap(te, NULL);
    terrain_ecs_destroy(te);
    terrain_clipmap_destroy(far);
    if (renderer) terrain_renderer_destroy(renderer);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    gfx_context_destroy(gfx);
    trace_stop();
    return rc < 0 ? 0 : rc;
}

/* Expected output:
 * Run: --hills --headless --size 64x48 --steps 2 --threads 2
 * ^terrain_streaming: step 0 at x 16: 8 chunks wanted, 8 ready, 0 kept$
 * ^terrain_streaming: step 1 at x -16: 8 chunks wanted, 8 ready, 4 kept$
 * ^terrain_streaming: step 2 at x -48: 8 chunks wanted, 8 ready, 8 kept$
 * ^terrain_streaming: [1-9][0-9]* chunks meshed, [0-9]+ empty skipped unsampled, [0-9.]+ MB resident, [1-9][0-9]* triangles$
 */
