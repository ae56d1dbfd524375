/* rocks_pile — a pile of rocks on a slope: bedrock made by hand, a cone of the rocks material on
 * it, and the rocks module filling that layer with rocks from its aperiodic tiles, seen from a
 * camera that circles the pile.
 *
 *   rocks_pile [--size WxH] [--headless] [--frames N] [--screenshot FILE] [--threads N]
 *               [--trace FILE]
 */
#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

#define PILE_X 16.0
#define PILE_Z 16.0

/* A slope rising 1 m in 4 towards −z, with a cone of rocks 3 m high at (PILE_X, PILE_Z). */
static float slope_height(double x, double z) { (void)x; return 8.0f - 0.25f * (float)(z - PILE_Z); }
static float pile_height(double x, double z) { return fmaxf(0.0f, 3.0f - 0.75f * (float)hypot(x - PILE_X, z - PILE_Z)); }

static void slope_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    double cx = (double)x + 0.5, cz = (double)z + 0.5;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, slope_height(cx, cz) - TERRAIN_FLOOR_Y);
    terrain_stacks_builder_push(builder, TERRAIN_ROCKS, pile_height(cx, cz));
}

static terrain_stacks *slope_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, slope_column, user);
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL;
    int frames = 0;
    bool headless = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "rocks_pile", .summary = "a pile of rocks from aperiodic tiles",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 1280, height = 720;
    if (size && !gfx_parse_size(size, &width, &height)) {
        fprintf(stderr, "rocks_pile: bad value for '--size'\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "rocks_pile", .headless = headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = slope_chunk });
    terrain_ecs *terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(terrain, 0, 0, 1, 0, 0);
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    /* The rocks: a tile set (built once, a few seconds; cached by a real game), then one call. */
    rocks_tileset *tiles = rocks_tileset_create(&(rocks_tileset_desc){ .jobs = jobs });
    rocks_system *rocks = tiles ? rocks_system_create(&(rocks_system_desc){ .gfx = gfx, .ecs = ecs, .world = world, .tiles = tiles }) : NULL;
    if (!renderer || !rocks) return 1;

    int status = 0;
    if (!frames && gfx_backend_get(gfx) == GFX_BACKEND_OFFSCREEN) frames = 30;
    terrain_view view = { .pitch = -0.3f, .aspect = (float)width / (float)height };
    for (int frame = 0; (!frames || frame < frames) && !gfx_window_should_close(gfx); frame++) {
        double angle = 3.6 + frame * 0.01;             /* from the sun's side */
        view.camera[0] = PILE_X + 9 * sin(angle), view.camera[2] = PILE_Z + 9 * cos(angle);
        view.camera[1] = slope_height(view.camera[0], view.camera[2]) + 4.0;
        view.yaw = (float)-angle;                        /* towards the pile */
        gfx_frame_begin(gfx);
        terrain_ecs_set_view(terrain, &view);
        rocks_set_view(rocks, &view);
        ecs_progress(ecs, 1.0f / 60.0f);                 /* mesh, cull, upload, place the rocks */
        terrain_ecs_draw(terrain, renderer, &view);      /* the ground and the sky */
        rocks_draw(rocks, &view);                        /* the rocks on it */
        if (screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, screenshot)) status = 1;
        gfx_frame_end(gfx);
    }
    rocks_system_stats_info stats = rocks_system_stats(rocks);
    printf("rocks_pile: %u rock shapes in %.2f s; %llu rocks placed in %d chunks, %llu drawn (%llu triangles)\n",
           tiles->rock_count, tiles->build_seconds, (unsigned long long)stats.instances, stats.chunks,
           (unsigned long long)stats.instances_drawn, (unsigned long long)stats.triangles_drawn);
    rocks_system_destroy(rocks);
    rocks_tileset_destroy(tiles);
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
 * Run: skip: its tile set takes over a minute in the debug build; tests/rocks and tests/render cover it
 * ^rocks_pile: [1-9][0-9]* rock shapes in [0-9.]+ s; [1-9][0-9]* rocks placed in [1-9][0-9]* chunks, [0-9]+ drawn with [0-9]+ commands$
 */
