/* The player's terrain tools (game/tools.h): which edit a stroke makes, worked out from the
 * table in tools.h, and the selector. The edits themselves are the terrain module's (its tests). */
#include "../engine/test.h"
#include "game/tools.h"

#include "ecs/ecs.h"
#include "jobs/jobs.h"

#include <math.h>

static const terrain_ray_hit hit = { .position = { 10, 20, -30 }, .normal = { 0, 1, 0 }, .distance = 5 };
static const float forward[3] = { 0.6f, -0.8f, 0.0f };

Test(game_tools, sculpt_adds_with_the_primary_and_carves_with_the_alternative) {
    double points[2][3];
    terrain_edit add = game_tools_edit(GAME_TOOL_SCULPT, false, 0, &hit, forward, points);
    terrain_edit carve = game_tools_edit(GAME_TOOL_SCULPT, true, 4, &hit, forward, points);
    cr_expect_eq(add.tool, TERRAIN_EDIT_SCULPT_ADD);
    cr_expect_eq(carve.tool, TERRAIN_EDIT_SCULPT_CARVE);
    cr_expect_eq(add.sculpt.target[0], 10.0);
    cr_expect_eq(add.sculpt.target[1], 20.0);
    cr_expect_eq(add.sculpt.target[2], -30.0);
    cr_expect_gt(add.sculpt.radius, 0.0f, "a default radius");
    cr_expect_eq(carve.sculpt.radius, 4.0f, "the radius given");
}

Test(game_tools, a_tunnel_starts_a_metre_before_the_surface_and_runs_along_the_view) {
    double points[2][3];
    terrain_edit long_one = game_tools_edit(GAME_TOOL_TUNNEL, false, 2, &hit, forward, points);
    cr_expect_eq(long_one.tool, TERRAIN_EDIT_SWEEP);
    cr_expect_eq(long_one.sweep.point_count, 2);
    cr_expect_eq((const void *)long_one.sweep.points, (const void *)points);
    /* 1 m back along the view, 12 m on. */
    cr_expect_float_eq(points[0][0], 10 - 0.6, 1e-6);
    cr_expect_float_eq(points[0][1], 20 + 0.8, 1e-6);
    cr_expect_float_eq(points[1][0], 10 + 12 * 0.6, 1e-6);
    cr_expect_float_eq(points[1][1], 20 - 12 * 0.8, 1e-6);
    cr_expect_float_eq(points[1][2], -30.0, 1e-9);
    game_tools_edit(GAME_TOOL_TUNNEL, true, 2, &hit, forward, points);
    double length = sqrt(pow(points[1][0] - points[0][0], 2) + pow(points[1][1] - points[0][1], 2));
    cr_expect_float_eq(length, 5.0, 1e-6, "the doorway: 1 m before, 4 m in");
}

Test(game_tools, sand_drops_sand_or_rocks_and_erode_wears_or_collapses) {
    double points[2][3];
    terrain_edit sand = game_tools_edit(GAME_TOOL_SAND, false, 0, &hit, forward, points);
    terrain_edit rocks = game_tools_edit(GAME_TOOL_SAND, true, 0, &hit, forward, points);
    cr_expect_eq(sand.tool, TERRAIN_EDIT_DEPOSIT);
    cr_expect_eq(sand.deposit.material, TERRAIN_BRUSH_SAND);
    cr_expect_eq(rocks.deposit.material, TERRAIN_BRUSH_ROCKS);
    cr_expect_gt(sand.deposit.volume, 0.0);
    cr_expect_eq(sand.deposit.x, 10.0);
    cr_expect_eq(sand.deposit.z, -30.0);
    cr_expect(sand.deposit.at_height && rocks.deposit.at_height, "deposits land at the hit's height");
    cr_expect_eq(sand.deposit.y, 20.0);
    terrain_edit wear = game_tools_edit(GAME_TOOL_ERODE, false, 0, &hit, forward, points);
    terrain_edit collapse = game_tools_edit(GAME_TOOL_ERODE, true, 0, &hit, forward, points);
    cr_expect_eq(wear.tool, TERRAIN_EDIT_ERODE);
    cr_expect_eq(wear.erode.mode, TERRAIN_ERODE_SURFACE);
    cr_expect_eq(collapse.erode.mode, TERRAIN_ERODE_COLLAPSE);
    cr_expect_eq(collapse.erode.y, 20.0, "the ball sits where the view met the rock");
    cr_expect(wear.erode.at_height, "surface erosion wears the floor the view met");
    cr_expect_eq(wear.erode.y, 20.0);
    cr_expect(wear.erode.rocks_ratio > 0 && wear.erode.rocks_ratio < 1);
}

/* Flat bedrock up to y = 0. */
static void flat_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
}

static terrain_stacks *flat_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, flat_column, user);
}

/* A cave everywhere: bedrock up to y = 0, air up to y = 4, a roof of bedrock up to y = 10. */
static void cave_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
    terrain_stacks_builder_push(builder, TERRAIN_AIR, 4.0f);
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, 6.0f);
}

static terrain_stacks *cave_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, cave_column, user);
}

/* Standing in the cave and looking down: the view meets the cave's floor at y = 0, and the sand
 * a stroke drops lies there, under the roof (000 §4.3 at the hit's height), not on the hill's top
 * at y = 10; a surface erosion stroke wears that floor, not the roof. */
Test(game_tools, sand_and_erosion_act_at_the_height_the_view_met_in_a_cave) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = cave_chunk });
    const double eye[3] = { 16.5, 2, 16.5 };
    const float down[3] = { 0, -1, 0 };
    terrain_ray_hit aim;
    cr_assert(terrain_raycast(world, eye, down, 16, &aim));
    cr_expect_float_eq(aim.position[1], 0.0, 0.05);
    double points[2][3];
    terrain_edit sand = game_tools_edit(GAME_TOOL_SAND, false, 0, &aim, down, points);
    terrain_chunk_coord changed[16];
    cr_assert_gt(terrain_world_edit(world, &sand, changed, 16), 0);
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    terrain_layer layers[8];
    int n = terrain_stacks_column(stacks, 16, 16, layers, 8);
    cr_assert_eq(n, 4, "floor, sand, air, roof");
    cr_expect_eq(layers[1].material, TERRAIN_SAND);
    cr_expect_gt(layers[1].thickness, 0.0f);
    cr_expect_float_eq(layers[1].thickness + layers[2].thickness, 4.0f, 1e-5, "the cave keeps its height");
    cr_expect_eq(layers[3].material, TERRAIN_BEDROCK);
    cr_expect_float_eq(layers[3].thickness, 6.0f, 1e-5, "the roof is untouched");
    cr_expect_float_eq(terrain_stacks_top(stacks, 16, 16), 10.0f, 1e-5, "nothing on the hill above");
    terrain_edit wear = game_tools_edit(GAME_TOOL_ERODE, false, 0, &aim, down, points);
    cr_assert_gt(terrain_world_edit(world, &wear, changed, 16), 0);
    stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    n = terrain_stacks_column(stacks, 16, 16, layers, 8);
    cr_assert_gt(n, 2);
    cr_expect_lt(layers[0].thickness, -TERRAIN_FLOOR_Y, "the floor wore down");
    cr_expect_eq(layers[n - 1].material, TERRAIN_BEDROCK);
    cr_expect_float_eq(layers[n - 1].thickness, 6.0f, 1e-5, "the roof is untouched");
    cr_expect_float_eq(terrain_stacks_top(stacks, 16, 16), 10.0f, 1e-5);
    terrain_world_destroy(world);
}

/* Looking straight down from 5 m over flat ground: the tool aims at the ground 5 m below; Tab
 * cycles the tools; a press strokes at once, a held button again every GAME_TOOLS_REPEAT s. */
Test(game_tools, update_aims_switches_and_repeats_while_held) {
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 1 });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = flat_chunk });
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    game_tools tools;
    game_tools_init(&tools);
    const double eye[3] = { 0.5, 5, 0.5 };
    const float down = -1.5707963f;
    input_actions none = { 0 }, next = { .pressed = INPUT_ACTION_BIT(INPUT_ACTION_NEXT_TOOL) };
    cr_expect(!game_tools_update(&tools, te, world, eye, 0, down, &none, 0.01f));
    cr_assert(tools.aimed);
    cr_expect_float_eq(tools.aim.distance, 5.0f, 0.05f);
    cr_expect_float_eq(tools.aim.position[1], 0.0, 0.05);
    for (int i = 1; i <= GAME_TOOL_COUNT; i++) {
        game_tools_update(&tools, te, world, eye, 0, down, &next, 0.01f);
        cr_expect_eq(tools.tool, (game_tool)(i % GAME_TOOL_COUNT));
        cr_expect_str_neq(game_tools_hint(&tools), "");
    }
    input_actions press = { .pressed = INPUT_ACTION_BIT(INPUT_ACTION_TOOL), .down = INPUT_ACTION_BIT(INPUT_ACTION_TOOL) };
    input_actions hold = { .down = INPUT_ACTION_BIT(INPUT_ACTION_TOOL) };
    cr_expect(game_tools_update(&tools, te, world, eye, 0, down, &press, 0.01f), "a press strokes at once");
    cr_expect(!game_tools_update(&tools, te, world, eye, 0, down, &hold, GAME_TOOLS_REPEAT / 2));
    cr_expect(game_tools_update(&tools, te, world, eye, 0, down, &hold, GAME_TOOLS_REPEAT / 2 + 0.001f),
              "held: again after the repeat time");
    cr_expect_eq(tools.strokes, 2);
    cr_expect_eq(terrain_ecs_edit_stats(te).queued, 2, "queued for the next stabilize phase");
    /* Looking up at the sky: nothing to aim at, nothing queued. */
    cr_expect(!game_tools_update(&tools, te, world, eye, 0, -down, &press, 0.5f));
    cr_expect(!tools.aimed);
    cr_expect_str_eq(game_tool_name(GAME_TOOL_COUNT), "unknown");
    terrain_ecs_destroy(te);
    terrain_world_destroy(world);
    ecs_world_destroy(ecs);
    job_system_destroy(jobs);
}
