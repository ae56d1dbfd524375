/* terrain_water — a lake: a round basin made by hand and filled with a water layer up to 8 m, its
 * chunks meshed by the terrain module and its surface drawn by terrain_water, seen from a camera
 * that circles the shore.
 *
 *   terrain_water [--water off|low|medium|high] [--size WxH] [--headless] [--frames N] [--screenshot FILE]
 *               [--threads N] [--trace FILE]
 */
#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

#define LAKE_LEVEL 8.0f
static const double lake_centre[2] = { 16, 16 };

/* A bowl 6 m deep at the centre rising to a flat rim at 14 m, gently rolling. */
static float basin_height(double x, double z) {
    double dx = x - lake_centre[0], dz = z - lake_centre[1];
    double bowl = 2.0 + 0.0045 * (dx * dx + dz * dz) + 0.6 * sin(x * 0.21) * cos(z * 0.17);
    return (float)fmin(bowl, 14.0 + 0.6 * sin(x * 0.05));
}

static void basin_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    float ground = roundf(basin_height((double)x, (double)z) * 32.0f) / 32.0f;
    terrain_stacks_builder_push(builder, ground < LAKE_LEVEL + 1 ? TERRAIN_SAND : TERRAIN_BEDROCK, ground - TERRAIN_FLOOR_Y);
    if (ground < LAKE_LEVEL) terrain_stacks_builder_push(builder, TERRAIN_WATER, LAKE_LEVEL - ground);
}

static terrain_stacks *basin_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, basin_column, user);
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL, *quality = "low";
    int frames = 0;
    bool headless = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "water", CORE_OPTION_STRING, &quality, "off|low|medium|high", "water quality (default low)" },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "terrain_water", .summary = "a lake drawn by terrain_water",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 1280, height = 720;
    terrain_water_quality water_level;
    const char *bad = size && !gfx_parse_size(size, &width, &height)    ? "size"
                      : !terrain_water_parse_quality(quality, &water_level) ? "water" : NULL;
    if (bad) {
        fprintf(stderr, "terrain_water: bad value for '--%s'\n", bad);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* The terrain: 5 × 5 chunks of 32 m around the origin, meshed as entities. */
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "terrain_water", .headless = headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = basin_chunk });
    terrain_ecs *terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(terrain, 0, 0, 2, 0, 0);
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = LAKE_LEVEL });
    /* The water: one call. The mesh phase gives the chunks that hold the lake's surface a
     * WaterPlane; a world made by hand has no sea (terrain_world_desc.sea). */
    terrain_water *water = terrain_water_create(&(terrain_water_desc){ .gfx = gfx, .ecs = ecs, .world = world,
                                                                       .quality = water_level });
    if (!renderer || !water) return 1;

    int status = 0;
    if (!frames && gfx_backend_get(gfx) == GFX_BACKEND_OFFSCREEN) frames = 60;
    terrain_view view = { .pitch = -0.2f, .aspect = (float)width / (float)height };
    for (int frame = 0; (!frames || frame < frames) && !gfx_window_should_close(gfx); frame++) {
        double angle = 0.6 + frame * 0.003;              /* around the lake, looking at its middle */
        view.camera[0] = lake_centre[0] + 52 * sin(angle), view.camera[2] = lake_centre[1] + 52 * cos(angle);
        view.camera[1] = basin_height(view.camera[0], view.camera[2]) + 3.0;
        view.yaw = (float)-angle;
        view.time = (float)frame / 60.0f;
        gfx_frame_begin(gfx);
        terrain_ecs_set_view(terrain, &view);
        ecs_progress(ecs, 1.0f / 60.0f);                 /* mesh, cull, upload */
        terrain_ecs_draw(terrain, renderer, &view);      /* the ground and the sky */
        terrain_water_draw(water, terrain, renderer, &view);   /* the lake over them */
        if (screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, screenshot)) status = 1;
        gfx_frame_end(gfx);
    }
    terrain_water_stats_info stats = terrain_water_stats(water);
    printf("terrain_water: water %s, %d planes drawn in the last frame, %.2f ms CPU\n",
           terrain_water_quality_name(water_level), stats.planes_drawn, stats.cpu_ms);
    terrain_water_destroy(water);
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
 * Run: --headless --size 96x64 --frames 4 --water low --screenshot $TMP/water.png
 * ^terrain_water: water low, [1-9][0-9]* planes drawn in the last frame, [0-9.]+ ms CPU$
 */
