/* tools.h — the terrain editing tools a player holds (000 §4): sculpt, tunnel, deposit, erode.
 *
 *     game_tools tools;
 *     game_tools_init(&tools);
 *     each frame, after the player moved:
 *         game_tools_update(&tools, terrain, world, eye, yaw, pitch, actions, dt);
 *         gfx_text_print(hud, …, "%s", game_tools_hint(&tools));
 *
 * The tool in hand aims where the view ray meets the surface (terrain_raycast, up to
 * GAME_TOOLS_REACH metres, or a rock first: obstacle_raycast) and queues its edit with terrain_ecs_edit; the next frame's stabilize
 * phase applies it and the stroke is drawn that frame. A held button strokes again every
 * GAME_TOOLS_REPEAT seconds. next_tool (Tab, right shoulder) cycles the tools.
 *
 *   tool        tool (left button, right trigger)         tool_alt (right button, left trigger)
 *   sculpt      add a ball of bedrock (δ = R/2, 000 §4.1)  carve one away
 *   tunnel      carve a tunnel 12 m on along the view      a short one (4 m): a doorway
 *   sand        drop sand (§4.3)                          drop rocks
 *   erode       surface erosion to sand and rocks (§4.4)  collapse a ball of rock into rubble
 */
#ifndef GAME_TOOLS_H
#define GAME_TOOLS_H

#include <stdbool.h>
#include <stdint.h>

#include "input/input.h"
#include "terrain/terrain.h"

#define GAME_TOOLS_REACH 48.0f       /* metres the view ray looks for a surface */
#define GAME_TOOLS_REPEAT 0.12f      /* seconds between strokes while a button is held */

typedef enum game_tool {
    GAME_TOOL_SCULPT,
    GAME_TOOL_TUNNEL,
    GAME_TOOL_SAND,
    GAME_TOOL_ERODE,
    GAME_TOOL_COUNT
} game_tool;

typedef struct game_tools {
    game_tool tool;
    float radius;                    /* metres; 0 = the tool's own default */
    float cooldown;                  /* seconds until a held button strokes again */
    bool aimed;                      /* the view ray met a surface this frame */
    terrain_ray_hit aim;
    uint64_t strokes;                /* edits queued so far */
    /* Solid things besides the terrain that the view ray stops at (the rocks: rocks_raycast).
     * True with the hit's position, unit normal and distance when one is met within
     * max_distance. NULL = the terrain alone. */
    bool (*obstacle_raycast)(void *user, const double origin[3], const float direction[3], float max_distance,
                             terrain_ray_hit *hit);
    void *obstacle_user;
} game_tools;

void game_tools_init(game_tools *tools);
const char *game_tool_name(game_tool tool);
/* The edit a stroke of `tool` makes at `hit`, looking along `forward` (unit); alt = the second
 * use; a tunnel's two skeleton points are written to `points`, which the edit points at. Pure:
 * the tests and the benchmarks use it without a running world. */
terrain_edit game_tools_edit(game_tool tool, bool alt, float radius, const terrain_ray_hit *hit,
                             const float forward[3], double points[2][3]);
/* Aims, handles next_tool, queues a stroke when tool / tool_alt is pressed or held; returns
 * whether it queued one. */
bool game_tools_update(game_tools *tools, terrain_ecs *terrain, terrain_world *world, const double eye[3],
                       float yaw, float pitch, const input_actions *actions, float dt);
/* One line for the HUD: the tool, what its buttons do, how to switch. */
const char *game_tools_hint(const game_tools *tools);

#endif
