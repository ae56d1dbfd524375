/* gfx_scene — the platform in one short program: a window (or OSMesa offscreen), shaders from
 * shaders/, keyboard, mouse and gamepads through input actions, screenshots and a trace.
 *
 *   gfx_scene [--size WxH] [--headless] [--frames N] [--screenshot FILE] [--bindings FILE]
 *               [--record FILE] [--replay FILE] [--no-vsync] [--fullscreen] [--trace FILE]
 *
 * Fly around the reference scene: WASD or the left stick to move, the mouse (click to capture
 * it, Escape to let go) or the right stick to look, Space / Ctrl to rise and sink, Shift to
 * hurry, F11 fullscreen, F12 screenshot. With no display it renders offscreen and, after
 * --frames (default 120 there), writes --screenshot.
 */
#include "core/core.h"
#include "gfx/gfx.h"
#include "input/input.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

typedef struct options {
    core_common_args common;
    const char *size, *screenshot, *bindings, *record, *replay;
    int frames;
    bool headless, no_vsync, fullscreen;
} options;

static int parse_options(int argc, char **argv, options *o, int *width, int *height) {
    const core_option list[] = {
        CORE_COMMON_OPTIONS(o->common),
        { "size", CORE_OPTION_STRING, &o->size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &o->headless, NULL, "render offscreen with OSMesa, no window" },
        { "frames", CORE_OPTION_INT, &o->frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &o->screenshot, "FILE", "write the last frame as a PNG" },
        { "bindings", CORE_OPTION_STRING, &o->bindings, "FILE", "input bindings (data/input/bindings.txt)" },
        { "record", CORE_OPTION_STRING, &o->record, "FILE", "record every frame's input" },
        { "replay", CORE_OPTION_STRING, &o->replay, "FILE", "play recorded input back" },
        { "no-vsync", CORE_OPTION_FLAG, &o->no_vsync, NULL, "do not wait for the display's refresh" },
        { "fullscreen", CORE_OPTION_FLAG, &o->fullscreen, NULL, "start fullscreen" },
    };
    core_cli cli = { .program = "gfx_scene", .summary = "fly around the reference scene",
                     .options = list, .option_count = CORE_COUNTOF(list) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    *width = 1280;
    *height = 720;
    if (o->size && !gfx_parse_size(o->size, width, height)) {
        fprintf(stderr, "gfx_scene: bad value for '--size': '%s' is not WxH (16 to 16384 each)\n", o->size);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    return -1;
}

/* A fly camera driven by the actions: walk on the look direction's heading, rise and sink. */
static void fly(gfx_camera *camera, const input_actions *a, float dt) {
    camera->yaw += a->look_x;
    camera->pitch = fmaxf(-1.5f, fminf(1.5f, camera->pitch + a->look_y));
    float speed = (a->down & INPUT_ACTION_BIT(INPUT_ACTION_SPRINT)) ? 12.0f : 4.0f;
    float forward_x = sinf(camera->yaw), forward_z = -cosf(camera->yaw);
    camera->position[0] += (forward_x * a->move_y + -forward_z * a->move_x) * speed * dt;
    camera->position[2] += (forward_z * a->move_y + forward_x * a->move_x) * speed * dt;
    float rise = ((a->down & INPUT_ACTION_BIT(INPUT_ACTION_JUMP)) ? 1.0f : 0.0f)
               - ((a->down & INPUT_ACTION_BIT(INPUT_ACTION_CROUCH)) ? 1.0f : 0.0f);
    camera->position[1] = fmaxf(0.2f, camera->position[1] + rise * speed * dt);
}

/* What the keys ask of the renderer rather than of the camera. (Mouse capture the input system
 * does by itself: a click captures, Escape lets go, Escape again quits.) */
static bool handle_commands(gfx_context *gfx, const input_actions *a) {
    if (a->pressed & INPUT_ACTION_BIT(INPUT_ACTION_SCREENSHOT)) {
        char path[64];
        snprintf(path, sizeof path, "screenshot-%06llu.png", (unsigned long long)gfx_frame_index(gfx));
        gfx_screenshot(gfx, path);
    }
    if (a->pressed & INPUT_ACTION_BIT(INPUT_ACTION_FULLSCREEN)) gfx_window_toggle_fullscreen(gfx);
    return !(a->pressed & INPUT_ACTION_BIT(INPUT_ACTION_QUIT));
}

int main(int argc, char **argv) {
    options o = { 0 };
    int width, height;
    int rc = parse_options(argc, argv, &o, &width, &height);
    if (rc >= 0) return rc;
    if (o.common.trace_path && !trace_start(o.common.trace_path)) return 2;
    trace_thread_name("main");

    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "gfx_scene",
                                               .headless = o.headless, .no_vsync = o.no_vsync,
                                               .fullscreen = o.fullscreen });
    if (!gfx) return 1;
    gfx_scene *scene = gfx_scene_create(gfx);
    if (!scene) return 1;                 /* the shader errors are printed at file:line */
    input_bindings *bindings = NULL;
    core_error error = { 0 };
    if (o.bindings && !(bindings = input_bindings_load(o.bindings, NULL, &error))) {
        fprintf(stderr, "gfx_scene: %s\n", error.message);
        return 1;
    }
    input_system *input = input_system_create(&(input_system_desc){ .bindings = bindings, .glfw_window = gfx_glfw_window(gfx),
                                                      .record_path = o.record, .replay_path = o.replay }, &error);
    if (!input) {
        fprintf(stderr, "gfx_scene: %s\n", error.message);
        return 1;
    }
    bool windowed = gfx_backend_get(gfx) == GFX_BACKEND_WINDOW;
    int frames = o.frames ? o.frames : (windowed || o.replay ? 0 : 120);

    gfx_camera camera = gfx_scene_default_camera();
    uint64_t start = core_time_ns(), last = start;
    for (int frame = 0; frames == 0 || frame < frames; frame++) {
        trace_frame_begin();
        uint64_t now = core_time_ns();
        /* Offscreen runs use a fixed step, so the same flags give the same images. */
        float dt = windowed ? (float)((now - last) * 1e-9) : 1.0f / 60.0f;
        last = now;
        if (!input_update(input, dt)) break;          /* a replay ran out */
        dt = input_frame_dt(input);                   /* a replay's recorded step */
        const input_actions *actions = input_actions_get(input);
        if (!handle_commands(gfx, actions) || gfx_window_should_close(gfx)) break;
        fly(&camera, actions, dt);
        gfx_frame_begin(gfx);
        gfx_scene_draw(scene, &camera, windowed ? (now - start) * 1e-9 : frame / 60.0);
        bool last_frame = frames && frame + 1 == frames;
        if (last_frame && o.screenshot) {
            if (!gfx_screenshot(gfx, o.screenshot)) rc = 1;
            o.screenshot = NULL;
        }
        gfx_frame_end(gfx);
        trace_frame_end();
    }
    if (o.screenshot) {    /* the loop ended early (closed, quit, replay over): one more frame */
        gfx_frame_begin(gfx);
        gfx_scene_draw(scene, &camera, (core_time_ns() - start) * 1e-9);
        if (!gfx_screenshot(gfx, o.screenshot)) rc = 1;
        gfx_frame_end(gfx);
    }
    double seconds = (core_time_ns() - start) * 1e-9;
    printf("gfx_scene: %llu frames in %.2f s (%.2f ms a frame), %s %dx%d, camera at (%.4f, %.4f, %.4f)\n",
           (unsigned long long)gfx_frame_index(gfx), seconds,
           gfx_frame_index(gfx) ? seconds * 1e3 / (double)gfx_frame_index(gfx) : 0.0,
           windowed ? "window" : "offscreen", width, height, camera.position[0], camera.position[1],
           camera.position[2]);
    input_system_destroy(input);
    input_bindings_destroy(bindings);
    gfx_scene_destroy(scene);
    gfx_context_destroy(gfx);
    trace_stop();
    return rc < 0 ? 0 : rc;
}

/* Expected output:
 * Run: --headless --size 160x90 --frames 10 --screenshot $TMP/scene.png --trace $TMP/scene.json
 * ^gfx_scene: 10 frames in [0-9.]+ s \([0-9.]+ ms a frame\), offscreen 160x90, camera at \(
 */
