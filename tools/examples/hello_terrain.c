/* hello_terrain — the terrain module on the engine: column chunks and mesh chunks as entities,
 * generated and meshed in parallel by the generate and mesh phases, culled, drawn with triplanar
 * materials, and walked by the game's player controller (game/player.h): WASD or the left stick
 * to walk, the mouse (click to capture) or the right stick to look, Space to jump, Shift to
 * sprint, Ctrl or C to crouch, F to fly, F12 for a screenshot.
 *
 *   hello_terrain [--seed S] [--radius R] [--rings N] [--size WxH] [--headless] [--frames N]
 *                 [--walk straight:METRES] [--record FILE] [--replay FILE] [--bindings FILE]
 *                 [--screenshot FILE] [--threads N] [--trace FILE]
 *
 * --walk straight:M walks the player M metres ahead, sprinting and jumping when it stalls, then
 * stops, and reports how far it went and on how many frames its eye was inside the ground
 * (which must be none).
 *
 * Full detail covers 2R × 2R chunks of 32 m around the start; each of N rings beyond it is meshed
 * at half the resolution of the one inside, out to 2R·32·2^N metres, with closed seams.
 */
#include "core/core.h"
#include "game/player.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "input/input.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct options {
    core_common_args common;
    const char *size, *screenshot, *walk, *record, *replay, *bindings;
    int seed, radius, rings, frames;
    double walk_metres;
    bool headless;
} options;

static int parse(int argc, char **argv, options *o, int *width, int *height) {
    const core_option list[] = {
        CORE_COMMON_OPTIONS(o->common),
        { "seed", CORE_OPTION_INT, &o->seed, "S", "world seed", 0, 2147483647 },
        { "radius", CORE_OPTION_INT, &o->radius, "R", "full-detail chunks each way from the start (default 2)", 1, 16 },
        { "rings", CORE_OPTION_INT, &o->rings, "N", "coarser rings of detail beyond (default 2)", 0, 5 },
        { "size", CORE_OPTION_STRING, &o->size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &o->headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &o->frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &o->screenshot, "FILE", "write the last frame as a PNG" },
        { "walk", CORE_OPTION_STRING, &o->walk, "SCRIPT", "scripted walk: straight:METRES" },
        { "record", CORE_OPTION_STRING, &o->record, "FILE", "record every frame's input" },
        { "replay", CORE_OPTION_STRING, &o->replay, "FILE", "play recorded input back" },
        { "bindings", CORE_OPTION_STRING, &o->bindings, "FILE", "input bindings (data/input/bindings.txt)" },
    };
    core_cli cli = { .program = "hello_terrain", .summary = "generate, mesh and fly over terrain",
                     .options = list, .option_count = CORE_COUNTOF(list) };
    o->seed = 1;
    o->radius = 2;
    o->rings = 2;
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    *width = 1280;
    *height = 720;
    if (o->size && !gfx_parse_size(o->size, width, height)) {
        fprintf(stderr, "hello_terrain: bad value for '--size': '%s' is not WxH (16 to 16384 each)\n", o->size);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    char *end = NULL;
    if (o->walk && (strncmp(o->walk, "straight:", 9) != 0 || (o->walk_metres = strtod(o->walk + 9, &end)) <= 0 ||
                    *end || o->walk_metres > 100000)) {
        fprintf(stderr, "hello_terrain: bad value for '--walk': '%s' is not straight:METRES (0 < METRES <= 100000)\n",
                o->walk);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    return -1;
}

/* The scripted walk: ahead at a sprint, with a jump (and a small turn) whenever the last half
 * second covered less than half the distance a sprint would (a ledge or a slope too steep). The
 * distance counts from the start in a straight line. */
typedef struct walker {
    double start[2], recent[30][2];
    int frames;
} walker;

static input_actions walker_actions(walker *w, const game_player *player) {
    int slot = w->frames % 30;
    double moved = hypot(player->position[0] - w->recent[slot][0], player->position[2] - w->recent[slot][1]);
    bool stalled = w->frames >= 30 && moved < 0.5 * 8.0 * 0.5;
    w->recent[slot][0] = player->position[0];
    w->recent[slot][1] = player->position[2];
    w->frames++;
    uint32_t down = INPUT_ACTION_BIT(INPUT_ACTION_SPRINT) | (stalled ? INPUT_ACTION_BIT(INPUT_ACTION_JUMP) : 0);
    /* Stalled: jump, and turn a little, so a wall too high to jump is walked around. */
    return (input_actions){ .move_y = 1, .look_x = stalled ? 0.05f : 0.0f, .down = down,
                            .pressed = stalled ? INPUT_ACTION_BIT(INPUT_ACTION_JUMP) : 0 };
}

/* Frame rate, chunk counts, position and seed in the top-left corner. */
static void draw_hud(gfx_text *hud, terrain_ecs *te, const terrain_view *view, double frame_seconds, int seed) {
    terrain_ecs_stats s = terrain_ecs_stats_get(te);
    const float white[4] = { 1, 1, 1, 1 };
    gfx_text_print(hud, 8, 8, 2, white, "%.0f fps  %.1f ms", frame_seconds > 0 ? 1.0 / frame_seconds : 0.0,
                   frame_seconds * 1e3);
    gfx_text_print(hud, 8, 30, 2, white, "chunks %d of %d meshed, %d waiting, %.2f M triangles",
                   s.mesh_chunks_uploaded, s.mesh_chunks, s.mesh_chunks_waiting, (double)s.triangles * 1e-6);
    gfx_text_print(hud, 8, 52, 2, white, "x %.1f  y %.1f  z %.1f  seed %d", view->camera[0], view->camera[1],
                   view->camera[2], seed);
    gfx_text_draw(hud);
}

int main(int argc, char **argv) {
    options o = { 0 };
    int width, height;
    int rc = parse(argc, argv, &o, &width, &height);
    if (rc >= 0) return rc;
    if (o.common.trace_path && !trace_start(o.common.trace_path)) return 2;
    gfx_context *gfx = gfx_create(&(gfx_desc){ .width = width, .height = height, .title = "hello_terrain (loading)",
                                               .headless = o.headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = o.common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_generation_params params = terrain_generation_defaults((uint64_t)o.seed);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = params });
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = params.sea_level });
    if (!renderer) return 1;
    terrain_ecs *te = terrain_ecs_create(ecs, world);
    /* Mesh layers that cover the relief, with a margin for overhangs. */
    double low = params.base_height - params.relief_height - 48, high = params.base_height + params.relief_height + 48;
    terrain_ecs_spawn_rings(te, 2 * o.radius, o.rings + 1, low, high);
    input_bindings *bindings = NULL;
    if (o.bindings && !(bindings = input_bindings_load(o.bindings, NULL))) return 1;
    input_system *input = input_create(&(input_desc){ .glfw_window = gfx_glfw_window(gfx), .bindings = bindings,
                                                      .record_path = o.record, .replay_path = o.replay });
    gfx_text *hud = gfx_text_create(gfx);
    if (!input || !hud) return 1;

    /* The player stands on solid ground near the middle of chunk (0, 0). */
    game_player player;
    game_player_init(&player, &(game_player_params){ 0 });
    game_player_spawn(&player, world, 16.0, 16.0);
    player.yaw = 3.14159265f;                  /* towards +z: the slopes in view face the sun */
    player.pitch = -0.1f;
    terrain_view view = { 0 };
    bool windowed = gfx_backend_get(gfx) == GFX_BACKEND_WINDOW;
    int frames = o.frames ? o.frames : (windowed || o.walk || o.replay ? 0 : 30);
    walker walk = { .start = { player.position[0], player.position[2] } };
    int eye_in_solid = 0;
    double walked = 0;
    uint64_t start = core_time_ns(), last = start;
    for (int frame = 0; frames == 0 || frame < frames; frame++) {
        trace_frame_begin();
        uint64_t now = core_time_ns();
        double frame_seconds = (double)(now - last) * 1e-9;   /* measured, for the HUD */
        float dt = windowed ? (float)frame_seconds : 1.0f / 60.0f;
        last = now;
        if (!input_update(input, dt)) break;
        const input_actions *actions = input_actions_get(input);
        if ((actions->pressed & INPUT_ACTION_BIT(INPUT_ACTION_QUIT)) || gfx_window_should_close(gfx)) break;
        if (actions->pressed & INPUT_ACTION_BIT(INPUT_ACTION_SCREENSHOT)) gfx_screenshot(gfx, "terrain.png");
        input_actions scripted;
        if (o.walk) {
            scripted = walker_actions(&walk, &player);
            actions = &scripted;
        }
        game_player_update(&player, world, actions, input_frame_dt(input));
        game_player_eye(&player, view.camera);
        eye_in_solid += terrain_field_at(world, view.camera[0], view.camera[1], view.camera[2], 0) >= 0;
        walked = hypot(player.position[0] - walk.start[0], player.position[2] - walk.start[1]);
        /* A walk ends at its distance, or after twice the time a sprint would take (stuck). */
        bool walk_over = o.walk && (walked >= o.walk_metres || frame > (int)(o.walk_metres / 8.0 * 120.0) + 60);
        view.yaw = player.yaw;
        view.pitch = player.pitch;
        gfx_size(gfx, &width, &height);
        view.aspect = (float)width / (float)height;
        view.time = windowed ? (float)((now - start) * 1e-9) : (float)frame / 60.0f;
        terrain_ecs_set_view(te, &view);          /* what the cull phase tests against */
        gfx_frame_begin(gfx);
        ecs_progress(ecs, dt);                     /* generate, mesh, cull and upload */
        terrain_ecs_draw(te, renderer, &view);
        draw_hud(hud, te, &view, frame_seconds, o.seed);
        bool last_frame = (frames && frame + 1 == frames) || walk_over;
        if (o.screenshot && last_frame && !gfx_screenshot(gfx, o.screenshot)) rc = 1;
        gfx_frame_end(gfx);
        trace_frame_end();
        if (frame == 0) gfx_window_set_title(gfx, "hello_terrain");   /* the first frame is meshed */
        if (walk_over) break;
    }
    if (o.walk) printf("hello_terrain: walked %.1f m in %d frames, eye in solid on %d frames\n", walked, walk.frames,
                       eye_in_solid);
    terrain_ecs_stats stats = terrain_ecs_stats_get(te);
    printf("hello_terrain: %d chunks, %d mesh chunks (%d drawn), %llu triangles, %llu frames\n", stats.chunks,
           stats.mesh_chunks, stats.mesh_chunks_uploaded, (unsigned long long)stats.triangles,
           (unsigned long long)gfx_frame_index(gfx));
    printf("hello_terrain: player at (%.4f, %.4f, %.4f)\n", player.position[0], player.position[1], player.position[2]);
    input_destroy(input);
    input_bindings_destroy(bindings);
    gfx_text_destroy(hud);
    terrain_ecs_destroy(te);
    terrain_renderer_destroy(renderer);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    gfx_destroy(gfx);
    trace_stop();
    return rc < 0 ? 0 : rc;
}
