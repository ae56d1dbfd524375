/* grass_meadow — a meadow: rolling soil made by hand, its chunks meshed by the terrain module, and
 * grass grown over them on the GPU by the vegetation module, seen from a camera that walks a
 * slow circle through it (the grass bends away from its feet).
 *
 *   grass_meadow [--grass off|low|high] [--size WxH] [--headless] [--frames N] [--screenshot FILE]
 *               [--threads N] [--trace FILE]
 */
#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"
#include "vegetation/vegetation.h"

#include <math.h>
#include <stdio.h>

/* Soil rolling 3 m up and down around 10 m: every column a single bedrock layer. */
static float meadow_height(double x, double z) { return 10.0f + 1.5f * (float)(sin(x * 0.09) + cos(z * 0.07)); }

static void meadow_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, meadow_height((double)x, (double)z) - TERRAIN_FLOOR_Y);
}

static terrain_stacks *meadow_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, meadow_column, user);
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL, *quality = "high";
    int frames = 0;
    bool headless = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "grass", CORE_OPTION_STRING, &quality, "off|low|high", "grass quality (default high)" },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "grass_meadow", .summary = "grass grown on the GPU over a meadow",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 1280, height = 720;
    grass_quality grass_level;
    const char *bad = size && !gfx_parse_size(size, &width, &height) ? "size"
                      : !grass_parse_quality(quality, &grass_level)   ? "grass" : NULL;
    if (bad) {
        fprintf(stderr, "grass_meadow: bad value for '--%s'\n", bad);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* The terrain: 5 × 5 chunks of 32 m around the origin, meshed as entities. */
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "grass_meadow", .headless = headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = meadow_chunk });
    terrain_ecs *terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(terrain, 0, 0, 2, 0, 0);
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    /* The grass: one call; it follows the terrain's mesh chunks from then on. */
    grass_system *grass = grass_system_create(&(grass_system_desc){ .gfx = gfx, .ecs = ecs, .world = world, .quality = grass_level });
    if (!renderer || !grass) return 1;

    int status = 0;
    if (!frames && gfx_backend_get(gfx) == GFX_BACKEND_OFFSCREEN) frames = 60;
    terrain_view view = { .pitch = -0.22f, .aspect = (float)width / (float)height };
    for (int frame = 0; (!frames || frame < frames) && !gfx_window_should_close(gfx); frame++) {
        double angle = frame * 0.004, feet[3] = { 30 * sin(angle) + 16, 0, 30 * cos(angle) + 16 };
        feet[1] = meadow_height(feet[0], feet[2]);
        view.camera[0] = feet[0], view.camera[1] = feet[1] + 1.7, view.camera[2] = feet[2];
        view.yaw = (float)(-angle - 1.5707963);          /* along the circle */
        view.time = (float)frame / 60.0f;
        gfx_frame_begin(gfx);
        terrain_ecs_set_view(terrain, &view);
        grass_set_view(grass, &view, feet);
        ecs_progress(ecs, 1.0f / 60.0f);                 /* mesh, cull, upload, place the grass */
        terrain_ecs_draw(terrain, renderer, &view);      /* the ground and the sky */
        grass_draw(grass, &view);                        /* the grass over them */
        if (screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, screenshot)) status = 1;
        gfx_frame_end(gfx);
    }
    grass_system_stats_info stats = grass_system_stats(grass);
    printf("grass_meadow: %d patches, %llu tufts placed, %llu drawn in the last frame, %.2f ms CPU\n", stats.patches,
           (unsigned long long)stats.tufts, (unsigned long long)grass_visible_tufts(grass), stats.cpu_ms);
    grass_system_destroy(grass);
    terrain_renderer_destroy(renderer);
    terrain_ecs_destroy(terrain);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    gfx_context_destroy(gfx);
    trace_stop();
    return status;
}

/* Expected output:
 * Run: --headless --size 96x64 --frames 4 --grass low --screenshot $TMP/grass.png
 * ^grass_meadow: [1-9][0-9]* patches, [1-9][0-9]* tufts placed, [1-9][0-9]* drawn in the last frame, [0-9.]+ ms CPU$
 */
