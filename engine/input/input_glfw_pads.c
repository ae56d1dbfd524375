/* input_glfw_pads.c — gamepads hidapi cannot read, read through GLFW's gamepad API instead.
 *
 * The kernel's xpad driver (wired Xbox pads and their clones) makes no hidraw node, and a stock
 * desktop does not let a user open /dev/hidraw* without a udev rule; GLFW reads the same pads
 * through evdev (/dev/input/event*, which logind opens to the user at the seat) and knows SDL's
 * mapping database. So every frame, on the main thread (GLFW's joystick calls are main-thread
 * only), each GLFW joystick that is a gamepad — one GLFW has a mapping for, built in or from
 * `--gamepad-mappings FILE` — and that the hidraw thread does not already read is read here and
 * published into a slot like a hidraw pad: the rest of the input system cannot tell them apart.
 *
 * A pad whose GUID has a line in the mappings file is mapped by input__sdl_mapping_apply from
 * the raw joystick (the code the tests check); any other through glfwGetGamepadState with GLFW's
 * built-in mappings. The file's lines also go to glfwUpdateGamepadMappings, so GLFW agrees on
 * which joysticks are gamepads.
 *
 * Duplicates (input__glfw_pad_is_duplicate): a pad the hidraw thread has open is left to it,
 * matched by the vendor and product ids in GLFW's GUID. Until the hidraw thread has enumerated
 * once, GLFW reads nothing, so a pad both can read does not start on GLFW and then move.
 */
#include "input/input_internal.h"

#include "core/core.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <string.h>

_Static_assert(INPUT_GLFW_JOYSTICKS == GLFW_JOYSTICK_LAST + 1, "joystick count");
_Static_assert(INPUT_SDL_GLFW_BUTTONS == GLFW_GAMEPAD_BUTTON_LAST + 1, "GLFW's gamepad buttons come first");
_Static_assert(INPUT_SDL_DPLEFT == GLFW_GAMEPAD_BUTTON_DPAD_LEFT && INPUT_SDL_GUIDE == GLFW_GAMEPAD_BUTTON_GUIDE &&
                   INPUT_SDL_LEFTSHOULDER == GLFW_GAMEPAD_BUTTON_LEFT_BUMPER,
               "the SDL outputs follow GLFW's button order");
_Static_assert(INPUT_SDL_AXIS_COUNT == GLFW_GAMEPAD_AXIS_LAST + 1 &&
                   INPUT_SDL_RIGHTTRIGGER - INPUT_SDL_BUTTON_COUNT == GLFW_GAMEPAD_AXIS_RIGHT_TRIGGER,
               "the SDL axes follow GLFW's axis order");

bool input__glfw_pad_is_duplicate(const input_pad_slot slots[INPUT_MAX_GAMEPADS], const char *guid, const char *name,
                                  int same_ids_before) {
    uint16_t vendor = 0, product = 0;
    bool ids = input__guid_ids(guid, &vendor, &product);
    int hidraw_with_ids = 0;
    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++) {
        const input_pad_slot *s = &slots[i];
        if (!s->claimed || !s->hidraw) continue;
        if (ids && s->vendor_id == vendor && s->product_id == product) hidraw_with_ids++;
        if (!ids && name && s->name[0] && strstr(name, s->name)) return true;
    }
    return ids && same_ids_before < hidraw_with_ids;
}

bool input__glfw_pads_init(input_glfw_pads *g, const char *mappings_path, bool active, core_error *error) {
    *g = (input_glfw_pads){ .active = active };
    for (int i = 0; i < INPUT_GLFW_JOYSTICKS; i++) g->slot[i] = -1;
    if (mappings_path) {
        int bad = 0;
        if (!input__sdl_mappings_load(&g->mappings, mappings_path, &bad, error)) return false;
        core_info("input", "gamepad mappings %s: %zu for this platform, %d bad line%s skipped", mappings_path,
                  g->mappings.count, bad, bad == 1 ? "" : "s");
    }
    /* Every line was checked above (GLFW would skip or half-read a bad one without naming it). */
    if (active && g->mappings.text_size && glfwUpdateGamepadMappings(g->mappings.text) != GLFW_TRUE)
        core_warn("input", "GLFW refused the gamepad mappings from %s", mappings_path);
    return true;
}

static void input_glfw_pad_drop(input_glfw_pads *g, input_pads_shared *shared, int jid, const char *why) {
    if (g->slot[jid] < 0) return;
    core_info("input", "gamepad disconnected: joystick %d (GLFW; %s)", jid, why);
    input__gamepad_publish(shared, g->slot[jid], NULL);
    input__pad_slot_release(shared, g->slot[jid]);
    g->slot[jid] = -1;
}

/* The joystick's state in SDL's layout: through the file's mapping when it has one, else GLFW's. */
static bool input_glfw_pad_read(int jid, const input_sdl_mapping *user, input_sdl_pad *pad) {
    if (user) {
        input_sdl_joystick j = { 0 };
        j.axes = glfwGetJoystickAxes(jid, &j.axis_count);
        j.buttons = glfwGetJoystickButtons(jid, &j.button_count);
        j.hats = glfwGetJoystickHats(jid, &j.hat_count);
        input__sdl_mapping_apply(user, &j, pad);
        return true;
    }
    GLFWgamepadstate state;
    if (!glfwGetGamepadState(jid, &state)) return false;
    *pad = (input_sdl_pad){ 0 };
    for (int i = 0; i < INPUT_SDL_GLFW_BUTTONS; i++) pad->buttons[i] = state.buttons[i] == GLFW_PRESS;
    memcpy(pad->axes, state.axes, sizeof pad->axes);
    return true;
}

/* Claims a slot for a joystick newly read through GLFW; false when all are taken. */
static bool input_glfw_pad_connect(input_glfw_pads *g, input_pads_shared *shared, int jid, const char *guid,
                                   bool user) {
    uint16_t vendor = 0, product = 0;
    input__guid_ids(guid, &vendor, &product);
    const char *name = glfwGetGamepadName(jid);
    if (!name) name = glfwGetJoystickName(jid);
    int slot = input__pad_slot_claim(shared, false, vendor, product, name);
    if (slot < 0) {
        if (!g->warned_full) core_warn("input", "more than %d gamepads: %s ignored", INPUT_MAX_GAMEPADS, name ? name : "?");
        g->warned_full = true;
        return false;
    }
    g->slot[jid] = slot;
    core_info("input", "gamepad connected: %s (GLFW joystick %d, %s mapping, %04x:%04x, GUID %s)", name ? name : "?",
              jid, user ? "--gamepad-mappings" : "GLFW's", vendor, product, guid ? guid : "?");
    return true;
}

void input__glfw_pads_poll(input_glfw_pads *g, input_pads_shared *shared, bool wait_for_hid) {
    if (!g->active) return;
    input_pad_slot slots[INPUT_MAX_GAMEPADS];
    pthread_mutex_lock(&shared->lock);
    memcpy(slots, shared->slots, sizeof slots);
    bool hid_ready = !wait_for_hid || shared->hid_scanned;
    pthread_mutex_unlock(&shared->lock);
    if (!hid_ready) return;

    uint32_t ids[INPUT_GLFW_JOYSTICKS] = { 0 };    /* vendor << 16 | product of each gamepad, 0 none */
    for (int jid = 0; jid < INPUT_GLFW_JOYSTICKS; jid++) {
        if (!glfwJoystickPresent(jid)) {
            g->noted[jid] = false;
            input_glfw_pad_drop(g, shared, jid, "unplugged");
            continue;
        }
        const char *guid = glfwGetJoystickGUID(jid);
        const input_sdl_mapping *user = input__sdl_mappings_find(&g->mappings, guid);
        if (!user && !glfwJoystickIsGamepad(jid)) {
            if (!g->noted[jid])
                core_info("input", "joystick %s (GUID %s) has no gamepad mapping: add its line with --gamepad-mappings",
                          glfwGetJoystickName(jid) ? glfwGetJoystickName(jid) : "?", guid ? guid : "?");
            g->noted[jid] = true;
            continue;
        }
        uint16_t vendor, product;
        int same_before = 0;
        if (input__guid_ids(guid, &vendor, &product)) {
            ids[jid] = (uint32_t)vendor << 16 | product;
            for (int k = 0; k < jid; k++) same_before += ids[k] == ids[jid];
        }
        if (input__glfw_pad_is_duplicate(slots, guid, glfwGetJoystickName(jid), same_before)) {
            input_glfw_pad_drop(g, shared, jid, "read through hidraw now");
            continue;
        }
        if (g->slot[jid] < 0 && !input_glfw_pad_connect(g, shared, jid, guid, user != NULL)) continue;
        input_sdl_pad pad;
        input_gamepad_state state;
        if (!input_glfw_pad_read(jid, user, &pad)) continue;
        input__sdl_pad_to_state(&pad, &state);
        input__gamepad_publish(shared, g->slot[jid], &state);
    }
}

void input__glfw_pads_close(input_glfw_pads *g, input_pads_shared *shared) {
    for (int jid = 0; jid < INPUT_GLFW_JOYSTICKS; jid++)
        if (g->slot[jid] >= 0) {
            input__gamepad_publish(shared, g->slot[jid], NULL);
            input__pad_slot_release(shared, g->slot[jid]);
            g->slot[jid] = -1;
        }
    input__sdl_mappings_free(&g->mappings);
}
