/* input_system.c — the input system: devices in, actions out, record and replay (input.h, "the
 * input system").
 *
 * Each frame input_update gathers raw events into one list — GLFW's callbacks append to it during
 * glfwPollEvents, the gamepad slots the hidapi thread published are turned into snapshot events,
 * and input_feed_* (tests, scripts, the examples) append to it between frames — or, when replaying, takes the
 * recorded list instead. input_actions.c turns the list into the frame's actions; the recorder
 * writes list, dt and actions; a replay compares what it recomputed with what was recorded.
 *
 * GLFW: the input system owns the window's key, mouse-button, cursor-position and scroll
 * callbacks and its user pointer. The cursor mode follows the logical capture at the end of each
 * update (only live, never in a replay).
 */
#include "input/input_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <math.h>
#include <string.h>

struct input_system {
    input_state state;
    float frame_dt;

    /* this frame's raw events (live) */
    input_event *events;
    size_t event_count, event_capacity;
    bool warned_overflow, warned_dt;

    /* GLFW */
    GLFWwindow *window;
    bool callbacks_installed;
    bool cursor_disabled;           /* what GLFW was last told */
    bool have_cursor;               /* cursor_x/y hold a position to take deltas from */
    double cursor_x, cursor_y;

    /* gamepads: the slots the thread publishes, and what the main thread last took from them */
    input_pads_shared pads;
    input_gamepads *gamepads;
    input_glfw_pads glfw_pads;      /* pads hidraw cannot read, through GLFW (main thread) */
    bool pad_connected[INPUT_MAX_GAMEPADS];
    uint32_t pad_generation[INPUT_MAX_GAMEPADS];
    input_gamepad_state pad_taken[INPUT_MAX_GAMEPADS];

    /* record and replay */
    input_recorder *recorder;
    input_replayer *replayer;
    char *replay_path;
    bool replay_over;
    uint64_t replay_mismatches;
};

/* ---- the event list ------------------------------------------------------------------------- */

static void input_push(input_system *in, const input_event *e) {
    if (in->replayer) return; /* a replay's events come from its file */
    if (e->kind == INPUT_EVENT_MOUSE_MOTION && in->event_count > 0 &&
        in->events[in->event_count - 1].kind == INPUT_EVENT_MOUSE_MOTION) {
        /* Consecutive motion sums to the same look; one event keeps records small at 1000 Hz. */
        in->events[in->event_count - 1].x += e->x;
        in->events[in->event_count - 1].y += e->y;
        return;
    }
    if (in->event_count == INPUT_MAX_EVENTS) {
        if (!in->warned_overflow) core_warn("input", "more than %d input events in one frame: the rest dropped", INPUT_MAX_EVENTS);
        in->warned_overflow = true;
        return;
    }
    in->events = core_grow(in->events, &in->event_capacity, in->event_count + 1, sizeof *in->events);
    in->events[in->event_count++] = *e;
}

void input_feed_key(input_system *in, int key, bool down) {
    if (key < 0 || key >= INPUT_KEY_COUNT) return;
    input_push(in, &(input_event){ .kind = INPUT_EVENT_KEY, .code = (uint16_t)key, .down = down });
}

void input_feed_mouse_button(input_system *in, int button, bool down) {
    if (button < 0 || button >= INPUT_MOUSE_BUTTON_COUNT) return;
    input_push(in, &(input_event){ .kind = INPUT_EVENT_MOUSE_BUTTON, .code = (uint16_t)button, .down = down });
}

void input_feed_mouse_motion(input_system *in, float dx, float dy) {
    if (!isfinite(dx) || !isfinite(dy)) return;
    input_push(in, &(input_event){ .kind = INPUT_EVENT_MOUSE_MOTION, .x = dx, .y = dy });
}

void input_feed_scroll(input_system *in, float dx, float dy) {
    if (!isfinite(dx) || !isfinite(dy)) return;
    input_push(in, &(input_event){ .kind = INPUT_EVENT_SCROLL, .x = dx, .y = dy });
}

void input_feed_gamepad(input_system *in, int slot, const input_gamepad_state *state) {
    if (slot < 0 || slot >= INPUT_MAX_GAMEPADS) return;
    if (state) input_push(in, &(input_event){ .kind = INPUT_EVENT_GAMEPAD, .code = (uint16_t)slot, .pad = *state });
    else input_push(in, &(input_event){ .kind = INPUT_EVENT_GAMEPAD_GONE, .code = (uint16_t)slot });
}

input_pads_shared *input__pads(input_system *in) { return &in->pads; }
bool input__mouse_captured(const input_system *in) { return in->state.captured; }
bool input__gamepad_thread_running(const input_system *in) { return in->gamepads != NULL; }
uint64_t input__replay_mismatches(const input_system *in) { return in->replay_mismatches; }
bool input__replay_failed(const input_system *in) { return in->replayer && input__replayer_failed(in->replayer); }

/* ---- GLFW ----------------------------------------------------------------------------------- */

static void input_key_callback(GLFWwindow *window, int key, int scancode, int action, int mods) {
    (void)scancode, (void)mods;
    if (action == GLFW_REPEAT) return;
    input_feed_key(glfwGetWindowUserPointer(window), key, action == GLFW_PRESS);
}

static void input_mouse_button_callback(GLFWwindow *window, int button, int action, int mods) {
    (void)mods;
    input_feed_mouse_button(glfwGetWindowUserPointer(window), button, action == GLFW_PRESS);
}

static void input_cursor_callback(GLFWwindow *window, double x, double y) {
    input_system *in = glfwGetWindowUserPointer(window);
    if (in->have_cursor) input_feed_mouse_motion(in, (float)(x - in->cursor_x), (float)(y - in->cursor_y));
    in->cursor_x = x;
    in->cursor_y = y;
    in->have_cursor = true;
}

static void input_scroll_callback(GLFWwindow *window, double x, double y) {
    input_feed_scroll(glfwGetWindowUserPointer(window), (float)x, (float)y);
}

static void input_glfw_attach(input_system *in) {
    glfwSetWindowUserPointer(in->window, in);
    glfwSetKeyCallback(in->window, input_key_callback);
    glfwSetMouseButtonCallback(in->window, input_mouse_button_callback);
    glfwSetCursorPosCallback(in->window, input_cursor_callback);
    glfwSetScrollCallback(in->window, input_scroll_callback);
    in->callbacks_installed = true;
}

static void input_glfw_detach(input_system *in) {
    if (!in->callbacks_installed) return;
    glfwSetKeyCallback(in->window, NULL);
    glfwSetMouseButtonCallback(in->window, NULL);
    glfwSetCursorPosCallback(in->window, NULL);
    glfwSetScrollCallback(in->window, NULL);
    if (in->cursor_disabled) glfwSetInputMode(in->window, GLFW_CURSOR, GLFW_CURSOR_NORMAL);
    glfwSetWindowUserPointer(in->window, NULL);
    in->callbacks_installed = false;
}

/* The cursor follows the logical capture; GLFW moves the cursor when the mode changes, so the
 * next position is a new origin rather than a jump. */
static void input_glfw_sync_cursor(input_system *in) {
    if (!in->callbacks_installed || in->state.captured == in->cursor_disabled) return;
    bool capture = in->state.captured;
    glfwSetInputMode(in->window, GLFW_CURSOR, capture ? GLFW_CURSOR_DISABLED : GLFW_CURSOR_NORMAL);
    if (glfwRawMouseMotionSupported()) glfwSetInputMode(in->window, GLFW_RAW_MOUSE_MOTION, capture ? GLFW_TRUE : GLFW_FALSE);
    in->cursor_disabled = capture;
    in->have_cursor = false;
}

/* ---- gamepads ------------------------------------------------------------------------------- */

/* Turns what the thread published since the last frame into events: a pad gone (or replaced:
 * its slot's generation moved), a new or changed state. A button pressed and released between
 * two frames (latched but no longer down) becomes a snapshot with it down, then the current one,
 * so a short tap still gives `pressed`. */
static void input_gather_gamepads(input_system *in) {
    input_pad_slot slots[INPUT_MAX_GAMEPADS];
    pthread_mutex_lock(&in->pads.lock);
    memcpy(slots, in->pads.slots, sizeof slots);
    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++) in->pads.slots[i].latched = 0;
    pthread_mutex_unlock(&in->pads.lock);

    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++) {
        input_pad_slot *slot = &slots[i];
        if (in->pad_connected[i] && (!slot->connected || slot->generation != in->pad_generation[i])) {
            input_feed_gamepad(in, i, NULL);
            in->pad_connected[i] = false;
        }
        if (!slot->connected) continue;
        uint32_t taps = slot->latched & ~slot->state.buttons;
        bool changed = memcmp(&slot->state, &in->pad_taken[i], sizeof slot->state) != 0;
        if (taps) {
            input_gamepad_state tapped = slot->state;
            tapped.buttons |= taps;
            input_feed_gamepad(in, i, &tapped);
        }
        if (!in->pad_connected[i] || changed || taps) input_feed_gamepad(in, i, &slot->state);
        in->pad_connected[i] = true;
        in->pad_generation[i] = slot->generation;
        in->pad_taken[i] = slot->state;
    }
}

/* ---- create, destroy ------------------------------------------------------------------------ */

input_system *input_system_create(const input_system_desc *desc, core_error *error) {
    input_system_desc d = desc ? *desc : (input_system_desc){ 0 };
    input_bindings bindings;
    if (d.bindings && input__bindings_valid(d.bindings)) {
        bindings = *d.bindings;
    } else {
        if (d.bindings) core_warn("input", "input_system_desc.bindings holds values out of range: using the defaults");
        input__bindings_set_default(&bindings);
    }
    /* input_system_desc.dead_zone wins when set; else the bindings' dead_zone (default 0.15). */
    float dead_zone = bindings.dead_zone;
    if (d.dead_zone != 0.0f) {
        if (d.dead_zone > 0.0f && d.dead_zone <= INPUT_DEAD_ZONE_MAX) dead_zone = d.dead_zone;
        else core_warn("input", "dead zone %g is outside (0, %g]: using %g", (double)d.dead_zone,
                       (double)INPUT_DEAD_ZONE_MAX, (double)dead_zone);
    }

    input_system *in = core_calloc(1, sizeof *in);
    input__pads_shared_init(&in->pads);
    /* GLFW's pads need its joystick API, so a window (GLFW initialised); a replay opens no device. */
    bool glfw_pads = d.glfw_window && !d.no_gamepads && !d.replay_path;
    if (!input__glfw_pads_init(&in->glfw_pads, d.gamepad_mappings_path, glfw_pads, error)) {
        input_system_destroy(in);
        return NULL;
    }
    if (d.replay_path) {
        in->replay_path = core_strdup(d.replay_path);
        in->replayer = input__replayer_open(d.replay_path, &bindings, &dead_zone, error);
        if (!in->replayer) {
            input_system_destroy(in);
            return NULL;
        }
        if (d.bindings && !input__bindings_equal(d.bindings, &bindings))
            core_info("input", "replay %s: using the bindings it was recorded with", d.replay_path);
    }
    if (d.record_path) {
        in->recorder = input__recorder_open(d.record_path, &bindings, dead_zone, error);
        if (!in->recorder) {
            input_system_destroy(in);
            return NULL;
        }
    }
    input__state_init(&in->state, &bindings, dead_zone);
    in->window = d.glfw_window;
    if (!in->replayer) { /* a replay opens no device */
        if (in->window) input_glfw_attach(in);
        if (!d.no_gamepads) in->gamepads = input__gamepads_start(&in->pads);
    }
    return in;
}

void input_system_destroy(input_system *in) {
    if (!in) return;
    input__gamepads_stop(in->gamepads);
    input__glfw_pads_close(&in->glfw_pads, &in->pads);
    if (in->window) input_glfw_detach(in);
    input__recorder_close(in->recorder);
    input__replayer_close(in->replayer);
    input__pads_shared_destroy(&in->pads);
    if (in->events) core_free(in->events, in->event_capacity * sizeof *in->events);
    if (in->replay_path) core_free(in->replay_path, strlen(in->replay_path) + 1);
    core_free(in, sizeof *in);
}

/* ---- the frame ------------------------------------------------------------------------------ */

static bool input_same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static void input_check_replay(input_system *in, const input_frame *frame) {
    const input_actions *got = &in->state.actions, *want = &frame->actions;
    if (input_same_bits(got->move_x, want->move_x) && input_same_bits(got->move_y, want->move_y) &&
        input_same_bits(got->look_x, want->look_x) && input_same_bits(got->look_y, want->look_y) &&
        got->down == want->down && got->pressed == want->pressed && got->released == want->released)
        return;
    if (in->replay_mismatches++ == 0)
        core_warn("input",
                  "replay %s: frame %u: the actions computed now differ from the recorded ones (move %.9g,%.9g "
                  "look %.9g,%.9g down %#x pressed %#x released %#x; recorded move %.9g,%.9g look %.9g,%.9g down "
                  "%#x pressed %#x released %#x): this build does not reproduce the recording (warned once)",
                  in->replay_path, frame->index, (double)got->move_x, (double)got->move_y, (double)got->look_x,
                  (double)got->look_y, got->down, got->pressed, got->released, (double)want->move_x,
                  (double)want->move_y, (double)want->look_x, (double)want->look_y, want->down, want->pressed,
                  want->released);
}

static int input_connected_pads(const input_system *in) {
    int count = 0;
    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++) count += in->state.pads[i].connected;
    return count;
}

bool input_update(input_system *in, float dt) {
    TRACE_ZONE("input_update");
    if (in->window) glfwPollEvents(); /* also in a replay, to keep the window alive */
    const input_event *events = in->events;
    size_t count = in->event_count;
    input_frame frame = { 0 };
    if (in->replayer) {
        in->event_count = 0;
        if (in->replay_over || !input__replayer_next(in->replayer, &frame)) {
            in->replay_over = true;
            in->state.actions = (input_actions){ 0 };
            return false;
        }
        events = frame.events;
        count = frame.event_count;
        dt = frame.dt;
    } else {
        if (!(dt >= 0.0f) || !isfinite(dt)) {
            if (!in->warned_dt) core_warn("input", "input_update: dt %g is not a time step: using 0", (double)dt);
            in->warned_dt = true;
            dt = 0.0f;
        }
        input__glfw_pads_poll(&in->glfw_pads, &in->pads, in->gamepads != NULL);
        input_gather_gamepads(in);
        events = in->events;
        count = in->event_count;
    }

    input__state_begin_frame(&in->state);
    for (size_t i = 0; i < count; i++) input__state_apply(&in->state, &events[i]);
    input__state_end_frame(&in->state, dt);
    in->frame_dt = dt;

    if (in->replayer) input_check_replay(in, &frame);
    if (in->recorder) input__recorder_write(in->recorder, dt, events, (uint32_t)count, &in->state.actions);
    in->event_count = 0;
    input_glfw_sync_cursor(in);
    trace_counter("input.gamepads", input_connected_pads(in));
    return true;
}

const input_actions *input_actions_get(const input_system *in) { return &in->state.actions; }

float input_frame_dt(const input_system *in) { return in->frame_dt; }

input_gamepad_state input_gamepad(const input_system *in) {
    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++)
        if (in->state.pads[i].connected) return in->state.pads[i].state;
    return (input_gamepad_state){ 0 };
}

int input_gamepad_count(const input_system *in) { return input_connected_pads(in); }

void input_capture_mouse(input_system *in, bool captured) {
    input_push(in, &(input_event){ .kind = INPUT_EVENT_CAPTURE, .down = captured });
}
