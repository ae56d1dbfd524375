/* input_actions.c — raw events + held state → the frame's actions (input.h, "actions").
 *
 * No device here: input_system.c feeds events from GLFW, the gamepad thread, a replay file or a
 * test, and this file alone decides what they mean, so a replay recomputes exactly what the
 * recorded run computed.
 *
 * Button actions are re-evaluated after every event, in order, so a key that goes down and up
 * within one frame still gives that frame a `pressed` and a `released` edge (with `down` clear).
 * Axes (move, look) are computed once, at the end of the frame, from what is held then plus the
 * frame's summed mouse motion.
 *
 * The mouse-capture rules (README.md, "Mouse capture"):
 *   - A mouse button pressed while the mouse is free feeds only capture_mouse until it is
 *     released; one pressed while captured feeds everything but capture_mouse. So the click that
 *     captures the mouse does not also use the tool.
 *   - capture_mouse going down captures the mouse.
 *   - quit going down while the mouse is captured releases the capture instead: that press is
 *     hidden from the game (no down, pressed or released) until it is let go.
 *   - Mouse motion turns the view only while captured.
 */
#include "input/input_internal.h"

#include <math.h>
#include <string.h>

static const char *const input_target_names[INPUT_TARGET_COUNT] = {
    [INPUT_ACTION_JUMP] = "jump",
    [INPUT_ACTION_SPRINT] = "sprint",
    [INPUT_ACTION_CROUCH] = "crouch",
    [INPUT_ACTION_TOOL] = "tool",
    [INPUT_ACTION_TOOL_ALT] = "tool_alt",
    [INPUT_ACTION_TOGGLE_FLY] = "toggle_fly",
    [INPUT_ACTION_SCREENSHOT] = "screenshot",
    [INPUT_ACTION_FULLSCREEN] = "fullscreen",
    [INPUT_ACTION_CAPTURE_MOUSE] = "capture_mouse",
    [INPUT_ACTION_QUIT] = "quit",
    [INPUT_ACTION_NEXT_TOOL] = "next_tool",
    [INPUT_ACTION_TOGGLE_HUD] = "toggle_hud",
    [INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_UP)] = "move_up",
    [INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_DOWN)] = "move_down",
    [INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_LEFT)] = "move_left",
    [INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_RIGHT)] = "move_right",
    [INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_UP)] = "look_up",
    [INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_DOWN)] = "look_down",
    [INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_LEFT)] = "look_left",
    [INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_RIGHT)] = "look_right",
};

const char *input__target_name(int target) {
    return target >= 0 && target < INPUT_TARGET_COUNT ? input_target_names[target] : "unknown";
}

const char *input_action_name(input_action action) {
    return (unsigned)action < INPUT_ACTION_COUNT ? input_target_names[action] : "unknown";
}

input_action input_action_from_name(const char *name) {
    if (!name) return INPUT_ACTION_COUNT;
    for (int a = 0; a < INPUT_ACTION_COUNT; a++)
        if (strcmp(name, input_target_names[a]) == 0) return (input_action)a;
    return INPUT_ACTION_COUNT;
}

/* ---- sources -------------------------------------------------------------------------------- */

static float input_pad_axis_value(const input_gamepad_state *pad, int axis) {
    switch (axis) {
    case INPUT_PAD_LT: return pad->lt;
    case INPUT_PAD_RT: return pad->rt;
    case INPUT_PAD_LEFT_STICK_UP: return fmaxf(-pad->ly, 0.0f);    /* y is down positive */
    case INPUT_PAD_LEFT_STICK_DOWN: return fmaxf(pad->ly, 0.0f);
    case INPUT_PAD_LEFT_STICK_LEFT: return fmaxf(-pad->lx, 0.0f);
    case INPUT_PAD_LEFT_STICK_RIGHT: return fmaxf(pad->lx, 0.0f);
    case INPUT_PAD_RIGHT_STICK_UP: return fmaxf(-pad->ry, 0.0f);
    case INPUT_PAD_RIGHT_STICK_DOWN: return fmaxf(pad->ry, 0.0f);
    case INPUT_PAD_RIGHT_STICK_LEFT: return fmaxf(-pad->rx, 0.0f);
    case INPUT_PAD_RIGHT_STICK_RIGHT: return fmaxf(pad->rx, 0.0f);
    default: return 0.0f;
    }
}

/* How far a non-mouse-motion source is pushed, 0…1 (keys and buttons are 0 or 1). Several pads:
 * the one pushed furthest. */
static float input_source_value(const input_state *s, int target, input_source source) {
    switch (source.kind) {
    case INPUT_SOURCE_KEY: return source.code < INPUT_KEY_COUNT && s->keys[source.code] ? 1.0f : 0.0f;
    case INPUT_SOURCE_MOUSE_BUTTON: {
        if (source.code >= INPUT_MOUSE_BUTTON_COUNT) return 0.0f;
        uint8_t bit = (uint8_t)(1u << source.code);
        if (!(s->mouse_down & bit)) return 0.0f;
        bool pressed_captured = (s->mouse_down_captured & bit) != 0;
        return (target == INPUT_ACTION_CAPTURE_MOUSE) != pressed_captured ? 1.0f : 0.0f;
    }
    case INPUT_SOURCE_PAD_BUTTON:
        for (int i = 0; i < INPUT_MAX_GAMEPADS; i++)
            if (s->pads[i].connected && source.code < 32 && (s->pads[i].state.buttons & (1u << source.code)))
                return 1.0f;
        return 0.0f;
    case INPUT_SOURCE_PAD_AXIS: {
        float value = 0.0f;
        for (int i = 0; i < INPUT_MAX_GAMEPADS; i++)
            if (s->pads[i].connected) value = fmaxf(value, input_pad_axis_value(&s->pads[i].state, source.code));
        return fminf(value, 1.0f);
    }
    default: return 0.0f; /* mouse motion is counted by input_mouse_counts */
    }
}

static float input_mouse_counts(const input_state *s, int axis) {
    switch (axis) {
    case INPUT_MOUSE_LEFT: return fmaxf(-s->mouse_dx, 0.0f);
    case INPUT_MOUSE_RIGHT: return fmaxf(s->mouse_dx, 0.0f);
    case INPUT_MOUSE_UP: return fmaxf(-s->mouse_dy, 0.0f);    /* screen y is down positive */
    case INPUT_MOUSE_DOWN: return fmaxf(s->mouse_dy, 0.0f);
    default: return 0.0f;
    }
}

/* A button action is down when any of its sources is pushed past half way (triggers and stick
 * directions included). */
static bool input_target_down(const input_state *s, int target) {
    for (int i = 0; i < s->bindings.source_count[target]; i++)
        if (input_source_value(s, target, s->bindings.sources[target][i]) > 0.5f) return true;
    return false;
}

/* ---- state ---------------------------------------------------------------------------------- */

void input__state_init(input_state *s, const input_bindings *bindings, float dead_zone) {
    memset(s, 0, sizeof *s);
    s->bindings = *bindings;
    s->dead_zone = dead_zone;
}

void input__state_begin_frame(input_state *s) {
    s->actions.pressed = s->actions.released = 0;
    s->actions.move_x = s->actions.move_y = s->actions.look_x = s->actions.look_y = 0.0f;
    s->mouse_dx = s->mouse_dy = s->scroll_x = s->scroll_y = 0.0f;
}

/* Re-evaluates the button actions after an event and records their edges. */
static void input_buttons_update(input_state *s) {
    uint32_t raw = 0;
    for (int a = 0; a < INPUT_ACTION_COUNT; a++)
        if (input_target_down(s, a)) raw |= INPUT_ACTION_BIT(a);
    uint32_t rose = raw & ~s->raw_down;
    s->raw_down = raw;
    s->swallowed &= raw; /* a hidden press ends when its sources let go */
    const uint32_t quit = INPUT_ACTION_BIT(INPUT_ACTION_QUIT), capture = INPUT_ACTION_BIT(INPUT_ACTION_CAPTURE_MOUSE);
    if ((rose & quit) && s->captured) {
        s->captured = false;
        s->swallowed |= quit;
    }
    uint32_t before = s->actions.down, now = raw & ~s->swallowed;
    s->actions.pressed |= now & ~before;
    s->actions.released |= before & ~now;
    s->actions.down = now;
    if ((now & ~before & capture) && !s->captured) s->captured = true;
}

void input__state_apply(input_state *s, const input_event *e) {
    switch (e->kind) {
    case INPUT_EVENT_KEY:
        if (e->code < INPUT_KEY_COUNT) s->keys[e->code] = e->down != 0;
        break;
    case INPUT_EVENT_MOUSE_BUTTON: {
        if (e->code >= INPUT_MOUSE_BUTTON_COUNT) return;
        uint8_t bit = (uint8_t)(1u << e->code);
        if (e->down && !(s->mouse_down & bit)) {
            s->mouse_down |= bit;
            if (s->captured) s->mouse_down_captured |= bit;
            else s->mouse_down_captured &= (uint8_t)~bit;
        } else if (!e->down) {
            s->mouse_down &= (uint8_t)~bit;
            s->mouse_down_captured &= (uint8_t)~bit;
        }
        break;
    }
    case INPUT_EVENT_MOUSE_MOTION:
        if (s->captured) {
            s->mouse_dx += e->x;
            s->mouse_dy += e->y;
        }
        return;
    case INPUT_EVENT_SCROLL:
        s->scroll_x += e->x;
        s->scroll_y += e->y;
        return;
    case INPUT_EVENT_GAMEPAD:
        if (e->code >= INPUT_MAX_GAMEPADS) return;
        s->pads[e->code].connected = true;
        s->pads[e->code].state = e->pad;
        input_apply_dead_zone(&s->pads[e->code].state, s->dead_zone);
        break;
    case INPUT_EVENT_GAMEPAD_GONE:
        if (e->code >= INPUT_MAX_GAMEPADS) return;
        s->pads[e->code] = (input_pad_view){ 0 };
        break;
    case INPUT_EVENT_CAPTURE:
        s->captured = e->down != 0;
        break;
    default: return;
    }
    input_buttons_update(s);
}

/* A half-axis: the furthest-pushed of its sources; for look, mouse counts × look_speed plus
 * that × stick_look_speed × dt (radians this frame). */
static float input_half_axis(const input_state *s, int axis, float dt) {
    int target = INPUT_TARGET_AXIS(axis);
    float pushed = 0.0f, counts = 0.0f;
    for (int i = 0; i < s->bindings.source_count[target]; i++) {
        input_source source = s->bindings.sources[target][i];
        if (source.kind == INPUT_SOURCE_MOUSE_AXIS) counts += input_mouse_counts(s, source.code);
        else pushed = fmaxf(pushed, input_source_value(s, target, source));
    }
    if (axis < INPUT_AXIS_LOOK_UP) return pushed;
    return counts * s->bindings.look_speed + pushed * s->bindings.stick_look_speed * dt;
}

void input__state_end_frame(input_state *s, float dt) {
    float half[INPUT_AXIS_COUNT];
    for (int axis = 0; axis < INPUT_AXIS_COUNT; axis++) half[axis] = input_half_axis(s, axis, dt);
    float x = half[INPUT_AXIS_MOVE_RIGHT] - half[INPUT_AXIS_MOVE_LEFT];
    float y = half[INPUT_AXIS_MOVE_UP] - half[INPUT_AXIS_MOVE_DOWN];
    float length = sqrtf(x * x + y * y);
    if (length > 1.0f) { /* keys on a diagonal, or a stick in a square gate's corner */
        x /= length;
        y /= length;
    }
    s->actions.move_x = x;
    s->actions.move_y = y;
    s->actions.look_x = half[INPUT_AXIS_LOOK_RIGHT] - half[INPUT_AXIS_LOOK_LEFT];
    float look_y = half[INPUT_AXIS_LOOK_UP] - half[INPUT_AXIS_LOOK_DOWN];
    s->actions.look_y = s->bindings.invert_y ? -look_y : look_y;
}
