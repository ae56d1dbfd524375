/* rocks_strata — a cliff whose blocks follow its rock (paper 003 §5, Fig. 11): a wall made by
 * hand of two rock materials, bedrock up to 10 m and a game's own rock above it to 24 m, and the
 * world's cliffs (rocks_cliffs) told which block type each rock breaks into: irregular
 * polyhedral blocks in the bedrock, slabs in the rock above. The block type changes where the stacks change material,
 * whatever the height: a game lays its strata out in its own generator, the cliffs follow.
 *
 *   rocks_strata [--size WxH] [--headless] [--frames N] [--screenshot FILE] [--threads N]
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

/* A game's own material: ids from TERRAIN_MATERIAL_BUILTIN_COUNT up are the game's. The terrain
 * holds it solid and stable like bedrock; the cliffs give it the block type it is mapped to. */
#define SANDSTONE ((terrain_material)TERRAIN_MATERIAL_BUILTIN_COUNT)
#define BEDROCK_TOP 10.0f             /* the face is x = 0, rock behind it (x < 0) */
#define WALL_TOP 24.0f

static void wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)z;
    if (x < 0) {
        terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, BEDROCK_TOP - TERRAIN_FLOOR_Y);
        terrain_stacks_builder_push(builder, SANDSTONE, WALL_TOP - BEDROCK_TOP);
    } else {
        terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, 0.0f - TERRAIN_FLOOR_Y);   /* the floor */
    }
}

static terrain_stacks *wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, wall_column, user);
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
    core_cli cli = { .program = "rocks_strata", .summary = "a cliff of two rocks in two block types",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 1280, height = 720;
    if (size && !gfx_parse_size(size, &width, &height)) {
        fprintf(stderr, "rocks_strata: bad value for '--size'\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* Which block type each rock breaks into (zero: no entry). Bedrock with no entry would follow
     * the strata by height instead (rocks_cliffs_desc.strata); a material with none gets no
     * blocks. The tiles, one per type used, are built at once on the job system. */
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    rocks_cliffs *cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){
        .material_blocks = { [TERRAIN_BEDROCK] = ROCKS_BLOCK_POLYHEDRAL, [SANDSTONE] = ROCKS_BLOCK_TABULAR },
        .jobs = jobs });
    if (!cliffs) return 1;
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "rocks_strata", .headless = headless });
    if (!gfx) return 1;
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk,
                                                                      .amplify = rocks_cliffs_amplify, .amplify_user = cliffs });
    terrain_ecs *terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(terrain, 0, 0, 2, -1, 0);   /* the floor is on a layer boundary */
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    if (!renderer) return 1;

    int status = 0;
    if (!frames && gfx_backend_get(gfx) == GFX_BACKEND_OFFSCREEN) frames = 30;
    terrain_view view = { .pitch = 0.25f, .aspect = (float)width / (float)height,
                          .sun_direction = { 0.35f, 0.5f, -0.8f } };   /* raking along the face */
    for (int frame = 0; (!frames || frame < frames) && !gfx_window_should_close(gfx); frame++) {
        double swing = sin(frame * 0.01);               /* along the wall, looking at it */
        view.camera[0] = 18.0, view.camera[1] = 6.0, view.camera[2] = 4.0 + 6.0 * swing;
        view.yaw = (float)(-M_PI / 2 - 0.6 + 0.2 * swing);   /* facing −x, turned along +z (yaw 0 looks along −z) */   /* facing −x, turned along +z (yaw 0 looks along −z) */
        gfx_frame_begin(gfx);
        terrain_ecs_set_view(terrain, &view);
        ecs_progress(ecs, 1.0f / 60.0f);                 /* mesh (through the hook), cull, upload */
        terrain_ecs_draw(terrain, renderer, &view);
        if (screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, screenshot)) status = 1;
        gfx_frame_end(gfx);
    }
    rocks_cliffs_stats_info cliff = rocks_cliffs_stats(cliffs);
    terrain_ecs_stats_info stats = terrain_ecs_stats(terrain);
    printf("rocks_strata: bedrock in %s blocks, the game's rock (material %d) in %s blocks: %u blocks in the tiles, "
           "built in %.2f s\n", rocks_block_type_name(ROCKS_BLOCK_POLYHEDRAL), (int)SANDSTONE,
           rocks_block_type_name(ROCKS_BLOCK_TABULAR), cliff.blocks, cliff.build_seconds);
    printf("rocks_strata: %llu block copies raised in %llu fields; %d mesh chunks, %llu triangles\n",
           (unsigned long long)cliff.copies_present, (unsigned long long)cliff.fields, stats.mesh_chunks_uploaded,
           (unsigned long long)stats.triangles);
    terrain_renderer_destroy(renderer);
    terrain_ecs_destroy(terrain);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    rocks_cliffs_destroy(cliffs);
    job_system_destroy(jobs);
    gfx_context_destroy(gfx);
    trace_stop();
    return status;
}

/* Expected output:
 * Run: skip: its two block tiles take over 4 s to build in the debug build; tests/rocks/test_rocks_strata.c covers it
 * ^rocks_strata: bedrock in polyhedral blocks, the game's rock \(material [0-9]+\) in tabular blocks: [1-9][0-9]* blocks in the tiles, built in [0-9.]+ s$
 * ^rocks_strata: [1-9][0-9]* block copies raised in [1-9][0-9]* fields; [1-9][0-9]* mesh chunks, [1-9][0-9]* triangles$
 */
