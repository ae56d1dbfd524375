/* rocks_blocks — a cliff of fractured rock (paper 003): a 16 m wall of bedrock made by hand, a
 * block tile of the type asked for, and the world's amplify hook raising the field to
 * f̃ = max(f, t) wherever a block straddles a steep wall (003 §5). The terrain's own systems
 * then mesh, light and draw the blocks like any terrain; the camera swings along the wall.
 *
 *   rocks_blocks [--type equidimensional|rhombohedral|polyhedral|tabular|columnar]
 *                [--size WxH] [--headless] [--frames N] [--screenshot FILE] [--threads N]
 *                [--trace FILE]
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

#define WALL_TOP 16.0f                /* the wall's face is x = 0, bedrock behind it (x < 0) */

static void wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, (x < 0 ? WALL_TOP : 0.0f) - TERRAIN_FLOOR_Y);
}

static terrain_stacks *wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, wall_column, user);
}

/* The world's amplify hook: the tile's blocks where 003 §5's presence finds a steep wall. */
typedef struct cliff_blocks { rocks_block_tile *tile; rocks_wall_presence walls; } cliff_blocks;

static void add_blocks(void *user, terrain_world *world, terrain_field *field) {
    cliff_blocks *c = user;
    c->walls.world = world;
    rocks_block_tile_amplify(c->tile, field, rocks_block_on_walls, &c->walls);
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL, *type_name = NULL;
    int frames = 0;
    bool headless = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "type", CORE_OPTION_STRING, &type_name, "TYPE", "block type (default columnar)" },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "rocks_blocks", .summary = "fractured rock blocks on a cliff",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    rocks_block_type type = ROCKS_BLOCK_COLUMNAR;
    int width = 1280, height = 720;
    bool bad_type = type_name && !rocks_parse_block_type(type_name, &type);
    if (bad_type || (size && !gfx_parse_size(size, &width, &height))) {
        fprintf(stderr, "rocks_blocks: bad value for '%s'\n", bad_type ? "--type" : "--size");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* The tile first: the world's hook reads it from the first chunk on. */
    /* joints of 0.6 m: the terrain samples its field every metre, and a thinner joint would not
     * show between the blocks */
    cliff_blocks cliff = { .tile = rocks_block_tile_create(&(rocks_block_tile_desc){ .type = type, .joint = 0.6f }) };
    if (!cliff.tile) return 1;
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "rocks_blocks", .headless = headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk,
                                                                      .amplify = add_blocks, .amplify_user = &cliff });
    terrain_ecs *terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(terrain, 0, 0, 2, -1, 0);   /* the floor is on a layer boundary */
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    if (!renderer) return 1;

    int status = 0;
    if (!frames && gfx_backend_get(gfx) == GFX_BACKEND_OFFSCREEN) frames = 30;
    terrain_view view = { .pitch = -0.1f, .aspect = (float)width / (float)height,
                          .sun_direction = { 0.45f, 0.55f, -0.7f } };   /* raking along the face */
    for (int frame = 0; (!frames || frame < frames) && !gfx_window_should_close(gfx); frame++) {
        double swing = sin(frame * 0.01);               /* along the wall, looking at it */
        view.camera[0] = 9.0, view.camera[1] = 6.0, view.camera[2] = 2.0 + 6.0 * swing;
        view.yaw = (float)(-M_PI / 2 - 0.6 + 0.2 * swing);   /* facing −x, turned along +z (yaw 0 looks along −z) */
        gfx_frame_begin(gfx);
        terrain_ecs_set_view(terrain, &view);
        ecs_progress(ecs, 1.0f / 60.0f);                 /* mesh (through the hook), cull, upload */
        terrain_ecs_draw(terrain, renderer, &view);
        if (screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, screenshot)) status = 1;
        gfx_frame_end(gfx);
    }
    terrain_ecs_stats_info stats = terrain_ecs_stats(terrain);
    printf("rocks_blocks: %s tile: %u blocks from %u points and %u fractures in %.2f s; %d mesh chunks, %llu triangles\n",
           rocks_block_type_name(type), cliff.tile->block_count, cliff.tile->sample_count, cliff.tile->disc_count,
           cliff.tile->build_seconds, stats.mesh_chunks_uploaded, (unsigned long long)stats.triangles);
    terrain_renderer_destroy(renderer);
    terrain_ecs_destroy(terrain);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    rocks_block_tile_destroy(cliff.tile);
    job_system_destroy(jobs);
    gfx_context_destroy(gfx);
    trace_stop();
    return status;
}

/* Expected output:
 * Run: --headless --size 96x64 --frames 2 --type columnar --screenshot $TMP/blocks.png
 * ^rocks_blocks: columnar tile: [1-9][0-9]* blocks from [1-9][0-9]* points and [0-9]+ fractures in [0-9.]+ s; [1-9][0-9]* mesh chunks, [1-9][0-9]* triangles$
 */
