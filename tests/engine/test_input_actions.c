/* Tests of the input system's actions (engine/input/input_actions.c, input_system.c): raw events
 * injected through the internal seam, actions checked against values worked out by hand from the
 * rules in input.h and engine/input/README.md. Default bindings unless a test says otherwise:
 * look_speed 0.0025 rad/count, stick_look_speed 3 rad/s, dead zone 0.15. */
#include "input/input.h"
#include "input/input_internal.h"
#include "test.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <math.h>
#include <string.h>

#define BIT(action) INPUT_ACTION_BIT(INPUT_ACTION_##action)

static input_system *make(void) {
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true }, NULL);
    cr_assert_not_null(in);
    return in;
}

static const input_actions *frame(input_system *in, float dt) {
    cr_assert(input_update(in, dt));
    return input_actions_get(in);
}

static const input_actions *step(input_system *in) { return frame(in, 1.0f / 60.0f); }

static void key_tap(input_system *in, int key, bool down) { input_feed_key(in, key, down); }

/* Captures the mouse the way a player does: a click (button 1) while the cursor is free. */
static void capture_by_click(input_system *in) {
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_1, true);
    step(in);
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_1, false);
    step(in);
    cr_assert(input__mouse_captured(in));
}

/* ---- button edges --------------------------------------------------------------------------- */

Test(input_actions, key_press_hold_release_edges) {
    input_system *in = make();
    key_tap(in, GLFW_KEY_SPACE, true);
    const input_actions *a = step(in);
    cr_expect_eq(a->down, BIT(JUMP));
    cr_expect_eq(a->pressed, BIT(JUMP));
    cr_expect_eq(a->released, 0u);

    a = step(in); /* held: no edges */
    cr_expect_eq(a->down, BIT(JUMP));
    cr_expect_eq(a->pressed, 0u);
    cr_expect_eq(a->released, 0u);

    key_tap(in, GLFW_KEY_SPACE, false);
    a = step(in);
    cr_expect_eq(a->down, 0u);
    cr_expect_eq(a->pressed, 0u);
    cr_expect_eq(a->released, BIT(JUMP));

    a = step(in);
    cr_expect_eq(a->down | a->pressed | a->released, 0u);
    input_system_destroy(in);
}

Test(input_actions, tap_within_one_frame_gives_both_edges) {
    input_system *in = make();
    key_tap(in, GLFW_KEY_F, true);
    key_tap(in, GLFW_KEY_F, false);
    const input_actions *a = step(in);
    cr_expect_eq(a->down, 0u);
    cr_expect_eq(a->pressed, BIT(TOGGLE_FLY));
    cr_expect_eq(a->released, BIT(TOGGLE_FLY));
    a = step(in);
    cr_expect_eq(a->pressed | a->released, 0u);
    input_system_destroy(in);
}

Test(input_actions, two_keys_on_one_action_release_once) {
    const input_actions *a;
    input_system *in = make();
    key_tap(in, GLFW_KEY_LEFT_CONTROL, true);
    a = step(in);
    cr_expect_eq(a->pressed, BIT(CROUCH));
    key_tap(in, GLFW_KEY_C, true);
    a = step(in); /* already down: no second press */
    cr_expect_eq(a->pressed, 0u);
    cr_expect_eq(a->down, BIT(CROUCH));
    key_tap(in, GLFW_KEY_LEFT_CONTROL, false);
    a = step(in); /* c still holds it */
    cr_expect_eq(a->released, 0u);
    cr_expect_eq(a->down, BIT(CROUCH));
    key_tap(in, GLFW_KEY_C, false);
    a = step(in);
    cr_expect_eq(a->released, BIT(CROUCH));
    input_system_destroy(in);
}

Test(input_actions, default_keys_reach_their_actions) {
    const input_actions *a;
    input_system *in = make();
    const struct { int key; uint32_t bit; } cases[] = {
        { GLFW_KEY_SPACE, BIT(JUMP) },        { GLFW_KEY_LEFT_SHIFT, BIT(SPRINT) },
        { GLFW_KEY_LEFT_CONTROL, BIT(CROUCH) }, { GLFW_KEY_C, BIT(CROUCH) },
        { GLFW_KEY_F, BIT(TOGGLE_FLY) },     { GLFW_KEY_F12, BIT(SCREENSHOT) },
        { GLFW_KEY_F11, BIT(FULLSCREEN) },   { GLFW_KEY_ESCAPE, BIT(QUIT) },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        key_tap(in, cases[i].key, true);
        a = step(in);
        cr_expect_eq(a->pressed, cases[i].bit, "key %d", cases[i].key);
        key_tap(in, cases[i].key, false);
        a = step(in);
        cr_expect_eq(a->released, cases[i].bit, "key %d", cases[i].key);
    }
    input_system_destroy(in);
}

/* ---- move ----------------------------------------------------------------------------------- */

Test(input_actions, single_keys_move_along_axes) {
    input_system *in = make();
    const struct { int key; float x, y; } cases[] = {
        { GLFW_KEY_W, 0, 1 }, { GLFW_KEY_S, 0, -1 }, { GLFW_KEY_A, -1, 0 }, { GLFW_KEY_D, 1, 0 },
        { GLFW_KEY_UP, 0, 1 }, { GLFW_KEY_DOWN, 0, -1 }, { GLFW_KEY_LEFT, -1, 0 }, { GLFW_KEY_RIGHT, 1, 0 },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        key_tap(in, cases[i].key, true);
        const input_actions *a = step(in);
        cr_expect_eq(a->move_x, cases[i].x, "key %d", cases[i].key);
        cr_expect_eq(a->move_y, cases[i].y, "key %d", cases[i].key);
        key_tap(in, cases[i].key, false);
        a = step(in);
        cr_expect_eq(a->move_x, 0.0f);
        cr_expect_eq(a->move_y, 0.0f);
    }
    input_system_destroy(in);
}

Test(input_actions, diagonal_move_is_normalised) {
    input_system *in = make();
    key_tap(in, GLFW_KEY_W, true);
    key_tap(in, GLFW_KEY_D, true);
    const input_actions *a = step(in);
    /* (1, 1) / √2 */
    cr_expect_float_eq(a->move_x, 0.70710678f, 1e-6f);
    cr_expect_float_eq(a->move_y, 0.70710678f, 1e-6f);
    cr_expect_float_eq(sqrtf(a->move_x * a->move_x + a->move_y * a->move_y), 1.0f, 1e-6f);
    key_tap(in, GLFW_KEY_D, false);
    key_tap(in, GLFW_KEY_LEFT, true); /* arrows too: up-left */
    key_tap(in, GLFW_KEY_W, false);
    key_tap(in, GLFW_KEY_UP, true);
    a = step(in);
    cr_expect_float_eq(a->move_x, -0.70710678f, 1e-6f);
    cr_expect_float_eq(a->move_y, 0.70710678f, 1e-6f);
    input_system_destroy(in);
}

Test(input_actions, opposite_keys_cancel_and_same_direction_does_not_add) {
    input_system *in = make();
    key_tap(in, GLFW_KEY_W, true);
    key_tap(in, GLFW_KEY_S, true);
    const input_actions *a = step(in);
    cr_expect_eq(a->move_x, 0.0f);
    cr_expect_eq(a->move_y, 0.0f);
    key_tap(in, GLFW_KEY_S, false);
    key_tap(in, GLFW_KEY_UP, true); /* w and up: still 1, not 2 */
    a = step(in);
    cr_expect_eq(a->move_y, 1.0f);
    input_system_destroy(in);
}

Test(input_actions, left_stick_moves_after_the_dead_zone) {
    input_system *in = make();
    /* Inside the radius 0.15: nothing. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .lx = 0.1f, .ly = -0.1f });
    const input_actions *a = step(in);
    cr_expect_eq(a->move_x, 0.0f);
    cr_expect_eq(a->move_y, 0.0f);
    /* r = 0.5 to the right: (0.5 − 0.15) / (1 − 0.15) = 0.41176471 */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .lx = 0.5f });
    a = step(in);
    cr_expect_float_eq(a->move_x, 0.41176471f, 1e-6f);
    cr_expect_eq(a->move_y, 0.0f);
    /* Stick pushed up (y is down positive on the pad) walks forward. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .ly = -0.5f });
    a = step(in);
    cr_expect_eq(a->move_x, 0.0f);
    cr_expect_float_eq(a->move_y, 0.41176471f, 1e-6f);
    /* Full deflection on a diagonal (0.6, −0.8), r = 1: unchanged by the dead zone. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .lx = 0.6f, .ly = -0.8f });
    a = step(in);
    cr_expect_float_eq(a->move_x, 0.6f, 1e-6f);
    cr_expect_float_eq(a->move_y, 0.8f, 1e-6f);
    input_system_destroy(in);
}

Test(input_actions, dead_zone_from_the_desc) {
    const input_actions *a;
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .dead_zone = 0.3f }, NULL);
    cr_assert_not_null(in);
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .lx = -0.5f });
    /* (0.5 − 0.3) / 0.7 = 0.28571429, to the left */
    a = step(in);
    cr_expect_float_eq(a->move_x, -0.28571429f, 1e-6f);
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .lx = -0.25f });
    a = step(in);
    cr_expect_eq(a->move_x, 0.0f);
    input_system_destroy(in);
}

Test(input_actions, stick_and_keys_take_the_larger_push) {
    const input_actions *a;
    input_system *in = make();
    key_tap(in, GLFW_KEY_D, true);
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .lx = 0.5f });
    a = step(in);
    cr_expect_eq(a->move_x, 1.0f);
    input_system_destroy(in);
}

/* ---- look ----------------------------------------------------------------------------------- */

Test(input_actions, mouse_motion_turns_the_view_only_while_captured) {
    input_system *in = make();
    input_feed_mouse_motion(in, 10.0f, 5.0f);
    const input_actions *a = step(in);
    cr_expect_eq(a->look_x, 0.0f);
    cr_expect_eq(a->look_y, 0.0f);
    capture_by_click(in);
    /* 10 + 30 counts right, 8 up (screen y is down): 40 × 0.0025 = 0.1 rad, 8 × 0.0025 = 0.02 rad up. */
    input_feed_mouse_motion(in, 10.0f, -3.0f);
    input_feed_mouse_motion(in, 30.0f, -5.0f);
    a = step(in);
    cr_expect_float_eq(a->look_x, 0.1f, 1e-7f);
    cr_expect_float_eq(a->look_y, 0.02f, 1e-7f);
    /* Left and down. */
    input_feed_mouse_motion(in, -4.0f, 12.0f);
    a = step(in);
    cr_expect_float_eq(a->look_x, -0.01f, 1e-7f);
    cr_expect_float_eq(a->look_y, -0.03f, 1e-7f);
    /* No motion, no turn (looks are per frame, not held). */
    a = step(in);
    cr_expect_eq(a->look_x, 0.0f);
    cr_expect_eq(a->look_y, 0.0f);
    input_system_destroy(in);
}

Test(input_actions, right_stick_turns_by_speed_times_dt) {
    input_system *in = make();
    /* Full right: 1 × 3 rad/s × 0.02 s = 0.06 rad. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .rx = 1.0f });
    const input_actions *a = frame(in, 0.02f);
    cr_expect_float_eq(a->look_x, 0.06f, 1e-6f);
    cr_expect_eq(a->look_y, 0.0f);
    /* The same stick over half a second: 1.5 rad. */
    a = frame(in, 0.5f);
    cr_expect_float_eq(a->look_x, 1.5f, 1e-6f);
    /* Pushed up (ry = −1: the pad's y is down positive) looks up: look_y positive. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .ry = -1.0f });
    a = frame(in, 0.02f);
    cr_expect_eq(a->look_x, 0.0f);
    cr_expect_float_eq(a->look_y, 0.06f, 1e-6f);
    /* (0.6, −0.8), r = 1: 0.6 × 0.06 = 0.036 right, 0.8 × 0.06 = 0.048 up. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .rx = 0.6f, .ry = -0.8f });
    a = frame(in, 0.02f);
    cr_expect_float_eq(a->look_x, 0.036f, 1e-6f);
    cr_expect_float_eq(a->look_y, 0.048f, 1e-6f);
    /* Inside the dead zone. */
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .rx = 0.1f, .ry = 0.1f });
    a = frame(in, 0.02f);
    cr_expect_eq(a->look_x, 0.0f);
    cr_expect_eq(a->look_y, 0.0f);
    input_system_destroy(in);
}

Test(input_actions, invert_y_flips_mouse_and_stick) {
    const input_actions *a;
    const char text[] = "invert_y = true\nlook_speed = 0.01\nstick_look_speed = 2\n";
    input_bindings *b = input_bindings_parse(text, sizeof text - 1, "invert", NULL);
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .bindings = b }, NULL);
    input_bindings_destroy(b);
    cr_assert_not_null(in);
    capture_by_click(in);
    input_feed_mouse_motion(in, 0.0f, -10.0f); /* mouse up: 10 × 0.01 = 0.1, inverted */
    a = step(in);
    cr_expect_float_eq(a->look_y, -0.1f, 1e-7f);
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .ry = -1.0f }); /* 2 × 0.25 = 0.5, inverted */
    a = frame(in, 0.25f);
    cr_expect_float_eq(a->look_y, -0.5f, 1e-6f);
    input_system_destroy(in);
}

Test(input_actions, keys_bound_to_look_turn_like_a_full_stick) {
    const char text[] = "look_right = key:l\nlook_up = key:i\n";
    input_bindings *b = input_bindings_parse(text, sizeof text - 1, "keys", NULL);
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .bindings = b }, NULL);
    input_bindings_destroy(b);
    key_tap(in, GLFW_KEY_L, true);
    key_tap(in, GLFW_KEY_I, true);
    const input_actions *a = frame(in, 0.1f); /* 3 rad/s × 0.1 s */
    cr_expect_float_eq(a->look_x, 0.3f, 1e-6f);
    cr_expect_float_eq(a->look_y, 0.3f, 1e-6f);
    input_system_destroy(in);
}

/* ---- mouse capture -------------------------------------------------------------------------- */

Test(input_actions, the_capturing_click_does_not_use_the_tool) {
    input_system *in = make();
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_1, true);
    const input_actions *a = step(in);
    cr_expect_eq(a->pressed, BIT(CAPTURE_MOUSE));
    cr_expect_eq(a->down, BIT(CAPTURE_MOUSE));
    cr_expect(input__mouse_captured(in));
    a = step(in); /* still held: still the capture click, the tool stays up */
    cr_expect_eq(a->down, BIT(CAPTURE_MOUSE));
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_1, false);
    a = step(in);
    cr_expect_eq(a->released, BIT(CAPTURE_MOUSE));
    cr_expect_eq(a->down, 0u);
    /* Captured now: button 1 is the tool, button 2 the second tool use. */
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_1, true);
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_2, true);
    a = step(in);
    cr_expect_eq(a->pressed, BIT(TOOL) | BIT(TOOL_ALT));
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_1, false);
    input_feed_mouse_button(in, GLFW_MOUSE_BUTTON_2, false);
    a = step(in);
    cr_expect_eq(a->released, BIT(TOOL) | BIT(TOOL_ALT));
    input_system_destroy(in);
}

Test(input_actions, escape_releases_capture_then_quits) {
    input_system *in = make();
    capture_by_click(in);
    key_tap(in, GLFW_KEY_ESCAPE, true);
    const input_actions *a = step(in);
    cr_expect_not(input__mouse_captured(in));
    cr_expect_eq(a->down | a->pressed | a->released, 0u, "the press that releases capture is hidden");
    a = step(in);
    cr_expect_eq(a->down, 0u);
    key_tap(in, GLFW_KEY_ESCAPE, false);
    a = step(in);
    cr_expect_eq(a->released, 0u);
    key_tap(in, GLFW_KEY_ESCAPE, true);
    a = step(in);
    cr_expect_eq(a->pressed, BIT(QUIT));
    cr_expect_eq(a->down, BIT(QUIT));
    input_system_destroy(in);
}

Test(input_actions, capture_mouse_call_applies_at_the_next_update) {
    const input_actions *a;
    input_system *in = make();
    input_capture_mouse(in, true);
    input_feed_mouse_motion(in, 4.0f, 0.0f);
    a = step(in);
    cr_expect_float_eq(a->look_x, 0.01f, 1e-7f);
    cr_expect(input__mouse_captured(in));
    input_capture_mouse(in, false);
    input_feed_mouse_motion(in, 4.0f, 0.0f);
    a = step(in);
    cr_expect_eq(a->look_x, 0.0f);
    cr_expect_not(input__mouse_captured(in));
    input_system_destroy(in);
}

/* ---- gamepad buttons ------------------------------------------------------------------------ */

Test(input_actions, gamepad_buttons_and_triggers) {
    input_system *in = make();
    const struct { input_gamepad_state pad; uint32_t bits; } cases[] = {
        { { .buttons = 1u << INPUT_BUTTON_SOUTH }, BIT(JUMP) },
        { { .buttons = 1u << INPUT_BUTTON_EAST }, BIT(CROUCH) },
        { { .buttons = 1u << INPUT_BUTTON_NORTH }, BIT(TOGGLE_FLY) },
        { { .buttons = 1u << INPUT_BUTTON_LS }, BIT(SPRINT) },
        { { .buttons = 1u << INPUT_BUTTON_LB }, BIT(SPRINT) },
        { { .buttons = 1u << INPUT_BUTTON_START }, BIT(QUIT) },
        { { .rt = 0.7f }, BIT(TOOL) },          /* past half way */
        { { .rt = 0.4f }, 0 },
        { { .lt = 1.0f }, BIT(TOOL_ALT) },
        { { .buttons = 1u << INPUT_BUTTON_WEST }, 0 }, /* unbound by default */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        input_feed_gamepad(in, 0, &cases[i].pad);
        const input_actions *a = step(in);
        cr_expect_eq(a->down, cases[i].bits, "case %zu", i);
        cr_expect_eq(a->pressed, cases[i].bits, "case %zu", i);
        input_feed_gamepad(in, 0, &(input_gamepad_state){ 0 });
        a = step(in);
        cr_expect_eq(a->released, cases[i].bits, "case %zu", i);
    }
    input_system_destroy(in);
}

Test(input_actions, unplugging_a_pad_releases_what_it_held) {
    input_system *in = make();
    input_feed_gamepad(in, 2, &(input_gamepad_state){ .buttons = 1u << INPUT_BUTTON_SOUTH, .lx = 1.0f });
    const input_actions *a = step(in);
    cr_expect_eq(a->down, BIT(JUMP));
    cr_expect_eq(a->move_x, 1.0f);
    cr_expect_eq(input_gamepad_count(in), 1);
    input_feed_gamepad(in, 2, NULL);
    a = step(in);
    cr_expect_eq(a->released, BIT(JUMP));
    cr_expect_eq(a->move_x, 0.0f);
    cr_expect_eq(input_gamepad_count(in), 0);
    input_system_destroy(in);
}

Test(input_actions, first_pad_after_dead_zone_and_count) {
    input_system *in = make();
    input_gamepad_state zero = input_gamepad(in);
    cr_expect_eq(zero.lx, 0.0f);
    cr_expect_eq(zero.buttons, 0u);
    input_feed_gamepad(in, 3, &(input_gamepad_state){ .lx = 1.0f });
    input_feed_gamepad(in, 1, &(input_gamepad_state){ .lx = 0.1f, .ly = 0.575f, .rt = 0.25f, .buttons = 5 });
    step(in);
    cr_expect_eq(input_gamepad_count(in), 2);
    input_gamepad_state pad = input_gamepad(in); /* slot 1 comes first */
    /* (0.1, 0.575): r = 0.58363… → (r − 0.15)/0.85 = 0.51015…; components scale by that / r. */
    float r = sqrtf(0.1f * 0.1f + 0.575f * 0.575f), k = (r - 0.15f) / 0.85f / r;
    cr_expect_float_eq(pad.lx, 0.1f * k, 1e-6f);
    cr_expect_float_eq(pad.ly, 0.575f * k, 1e-6f);
    cr_expect_eq(pad.rt, 0.25f);
    cr_expect_eq(pad.buttons, 5u);
    input_system_destroy(in);
}

Test(input_actions, two_pads_combine) {
    const input_actions *a;
    input_system *in = make();
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .buttons = 1u << INPUT_BUTTON_SOUTH });
    input_feed_gamepad(in, 1, &(input_gamepad_state){ .buttons = 1u << INPUT_BUTTON_SOUTH });
    a = step(in);
    cr_expect_eq(a->pressed, BIT(JUMP));
    input_feed_gamepad(in, 0, &(input_gamepad_state){ 0 });
    a = step(in);
    cr_expect_eq(a->released, 0u, "the other pad still holds jump");
    input_feed_gamepad(in, 1, &(input_gamepad_state){ 0 });
    a = step(in);
    cr_expect_eq(a->released, BIT(JUMP));
    input_system_destroy(in);
}

/* The slots the gamepad thread publishes into, without the thread: what input_update makes of them. */
Test(input_actions, published_pad_states_become_events) {
    input_system *in = make();
    input_pads_shared *pads = input__pads(in);
    input_gamepad_state south = { .buttons = 1u << INPUT_BUTTON_SOUTH };
    input__gamepad_publish(pads, 0, &(input_gamepad_state){ 0 });
    const input_actions *a = step(in);
    cr_expect_eq(input_gamepad_count(in), 1);
    cr_expect_eq(a->down, 0u);
    /* Pressed and released between two frames: still one press, one release. */
    input__gamepad_publish(pads, 0, &south);
    input__gamepad_publish(pads, 0, &(input_gamepad_state){ 0 });
    a = step(in);
    cr_expect_eq(a->pressed, BIT(JUMP));
    cr_expect_eq(a->released, BIT(JUMP));
    cr_expect_eq(a->down, 0u);
    /* Held across frames. */
    input__gamepad_publish(pads, 0, &south);
    a = step(in);
    cr_expect_eq(a->pressed, BIT(JUMP));
    a = step(in);
    cr_expect_eq(a->down, BIT(JUMP));
    cr_expect_eq(a->pressed, 0u);
    /* Unplugged while held. */
    input__gamepad_publish(pads, 0, NULL);
    a = step(in);
    cr_expect_eq(a->released, BIT(JUMP));
    cr_expect_eq(input_gamepad_count(in), 0);
    input_system_destroy(in);
}

/* ---- names ---------------------------------------------------------------------------------- */

Test(input_actions, action_names_round_trip) {
    for (int a = 0; a < INPUT_ACTION_COUNT; a++)
        cr_expect_eq(input_action_from_name(input_action_name((input_action)a)), (input_action)a);
    cr_expect_str_eq(input_action_name(INPUT_ACTION_TOOL_ALT), "tool_alt");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_CAPTURE_MOUSE), "capture_mouse");
    cr_expect_eq(input_action_from_name("move_up"), INPUT_ACTION_COUNT); /* an axis, not a button action */
    cr_expect_eq(input_action_from_name("JUMP"), INPUT_ACTION_COUNT);
    cr_expect_eq(input_action_from_name(NULL), INPUT_ACTION_COUNT);
}

Test(input_actions, bad_dt_counts_as_zero) {
    input_system *in = make();
    input_feed_gamepad(in, 0, &(input_gamepad_state){ .rx = 1.0f });
    const input_actions *a = frame(in, NAN);
    cr_expect_eq(a->look_x, 0.0f);
    cr_expect_eq(input_frame_dt(in), 0.0f);
    a = frame(in, 0.1f);
    cr_expect_float_eq(a->look_x, 0.3f, 1e-6f);
    cr_expect_eq(input_frame_dt(in), 0.1f);
    input_system_destroy(in);
}
