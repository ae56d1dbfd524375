/* tools.c — the player's terrain tools (tools.h). */
#include "tools.h"

#include <math.h>

static const char *const tool_names[GAME_TOOL_COUNT] = { "sculpt", "tunnel", "sand", "erode" };

/* Sizes a player can see the effect of from a few metres away without wrecking a hill. */
static const float default_radius[GAME_TOOL_COUNT] = { 2.5f, 2.0f, 3.0f, 3.0f };

#define TOOL_TUNNEL_LENGTH 12.0
#define TOOL_DOORWAY_LENGTH 4.0
#define TOOL_TUNNEL_BACK 1.0         /* starts a metre in front of the surface: an open mouth */
#define TOOL_DEPOSIT_VOLUME 8.0      /* m³ a stroke drops */
#define TOOL_ERODE_DEPTH 0.75f       /* metres a stroke erodes at its centre */
#define TOOL_ROCKS_RATIO 0.3f        /* ρ: the share of eroded bedrock that becomes rocks */

void game_tools_init(game_tools *tools) { *tools = (game_tools){ 0 }; }

const char *game_tool_name(game_tool tool) {
    return (unsigned)tool < GAME_TOOL_COUNT ? tool_names[tool] : "unknown";
}

terrain_edit game_tools_edit(game_tool tool, bool alt, float radius, const terrain_ray_hit *hit,
                             const float forward[3], double points[2][3]) {
    if ((unsigned)tool >= GAME_TOOL_COUNT) return (terrain_edit){ 0 };
    float r = radius > 0 ? radius : default_radius[tool];
    const double *p = hit->position;
    switch (tool) {
    case GAME_TOOL_SCULPT:
        return (terrain_edit){ .tool = alt ? TERRAIN_EDIT_SCULPT_CARVE : TERRAIN_EDIT_SCULPT_ADD,
                               .sculpt = { .target = { p[0], p[1], p[2] }, .radius = r } };
    case GAME_TOOL_TUNNEL: {
        double length = alt ? TOOL_DOORWAY_LENGTH : TOOL_TUNNEL_LENGTH;
        for (int a = 0; a < 3; a++) {
            points[0][a] = p[a] - TOOL_TUNNEL_BACK * forward[a];
            points[1][a] = p[a] + length * forward[a];
        }
        return (terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
                               .sweep = { .points = (const double (*)[3])points, .point_count = 2, .radius = r } };
    }
    case GAME_TOOL_SAND:
        return (terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                               .deposit = { .material = alt ? TERRAIN_BRUSH_ROCKS : TERRAIN_BRUSH_SAND, .x = p[0], .z = p[2],
                                            .radius = r, .volume = TOOL_DEPOSIT_VOLUME,
                                            /* where the view met the ground: a cave's floor
                                               inside a cave, not the hill above it */
                                            .at_height = true, .y = p[1] } };
    case GAME_TOOL_ERODE:
        return (terrain_edit){ .tool = TERRAIN_EDIT_ERODE,
                               .erode = { .mode = alt ? TERRAIN_ERODE_COLLAPSE : TERRAIN_ERODE_SURFACE,
                                          .x = p[0], .y = p[1], .z = p[2], .radius = r,
                                          .depth = TOOL_ERODE_DEPTH, .rocks_ratio = TOOL_ROCKS_RATIO,
                                          .at_height = true } };
    default:
        return (terrain_edit){ 0 };
    }
}

bool game_tools_update(game_tools *tools, terrain_ecs *terrain, terrain_world *world, const double eye[3],
                       float yaw, float pitch, const input_actions *actions, float dt) {
    if (actions->pressed & INPUT_ACTION_BIT(INPUT_ACTION_NEXT_TOOL))
        tools->tool = (game_tool)((tools->tool + 1) % GAME_TOOL_COUNT);
    /* The renderer's view direction (terrain_render.c): yaw about +y from −z, pitch up. */
    float forward[3] = { sinf(yaw) * cosf(pitch), sinf(pitch), -cosf(yaw) * cosf(pitch) };
    tools->aimed = terrain_raycast(world, eye, forward, GAME_TOOLS_REACH, &tools->aim);
    terrain_ray_hit obstacle;
    if (tools->obstacle_raycast &&
        tools->obstacle_raycast(tools->obstacle_user, eye, forward,
                                tools->aimed ? tools->aim.distance : GAME_TOOLS_REACH, &obstacle) &&
        (!tools->aimed || obstacle.distance < tools->aim.distance)) {
        tools->aim = obstacle;
        tools->aimed = true;
    }
    tools->cooldown = tools->cooldown > dt ? tools->cooldown - dt : 0.0f;
    uint32_t use = INPUT_ACTION_BIT(INPUT_ACTION_TOOL), alt_use = INPUT_ACTION_BIT(INPUT_ACTION_TOOL_ALT);
    bool pressed = actions->pressed & (use | alt_use);
    bool held = actions->down & (use | alt_use);
    if (!tools->aimed || !(pressed || (held && tools->cooldown <= 0.0f))) return false;
    bool alt = ((pressed ? actions->pressed : actions->down) & use) == 0;
    double points[2][3];
    terrain_edit edit = game_tools_edit(tools->tool, alt, tools->radius, &tools->aim, forward, points);
    tools->cooldown = GAME_TOOLS_REPEAT;
    if (!terrain_ecs_edit(terrain, &edit)) return false;
    tools->strokes++;
    return true;
}

const char *game_tools_hint(const game_tools *tools) {
    static const char *const hints[GAME_TOOL_COUNT] = {
        "tool: sculpt  [left] add  [right] carve  [tab] next",
        "tool: tunnel  [left] 12 m  [right] 4 m  [tab] next",
        "tool: sand    [left] sand  [right] rocks  [tab] next",
        "tool: erode   [left] surface  [right] collapse  [tab] next",
    };
    return (unsigned)tools->tool < GAME_TOOL_COUNT ? hints[tools->tool] : "";
}
