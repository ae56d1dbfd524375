/* input.h — gamepads (hidapi), keyboard and mouse (GLFW), actions, bindings, record and replay.
 *
 * Three layers, each usable on its own:
 *
 *   1. Report decoders turn the raw HID input reports of a gamepad into one plain state:
 *          input_decoder *d = input_decoder_create(&(input_decoder_desc){
 *              .vendor_id = 0x054c, .product_id = 0x09cc }, NULL);    // a DualShock 4
 *          input_gamepad_state pad;
 *          core_error why = {0};                                      // or NULL: no text formatted
 *          if (input_decoder_decode(d, report, size, &pad, &why) == INPUT_DECODE_OK) use(pad.lx);
 *          else log("%s", why.message);      // "report too short: 9 bytes, need 10"
 *      Known pads (DualShock 4, DualSense, Switch Pro) are picked by vendor and product id; any
 *      other pad is decoded from its HID report descriptor (.descriptor). Reports that are too
 *      short, too long, of an unknown report ID or malformed are counted (input_decoder_stats_info)
 *      and ignored — a decoder never reads outside the bytes it is given.
 *      Axes follow SDL's convention: x positive right, y positive down, full deflection ±1;
 *      triggers 0…1. input_apply_dead_zone applies the radial dead zone to a state.
 *
 *   2. The input system owns the devices: it enumerates hidapi gamepads on a background thread
 *      (about once a second; a frame never waits on the OS), reads their reports there, and
 *      takes keyboard and mouse events from a GLFW window (raw mouse motion where offered). Pads
 *      hidapi cannot read (the xpad driver's, or a hidraw node this user may not open: the log
 *      names the node and data/input/70-gamepads.rules) are read through GLFW's gamepad API while a
 *      window exists, with SDL's mappings and the lines of input_system_desc.gamepad_mappings_path:
 *          core_error error = { 0 };
 *          input_system *input = input_system_create(&(input_system_desc){ .glfw_window = window,
 *                                      .gamepad_mappings_path = "gamecontrollerdb.txt" }, &error);
 *          if (!input) fprintf(stderr, "%s\n", error.message);   // names the file that failed
 *
 *   3. Actions (move, look, jump, sprint, crouch, tool, toggle fly) are what a game reads. They
 *      are fed by both devices through bindings loaded from a small text file the user can edit
 *      (see input_bindings_load). Every frame:
 *          input_update(input, dt);                   // once per frame, main thread
 *          dt = input_frame_dt(input);                // the recorded dt when replaying
 *          const input_actions *a = input_actions_get(input);
 *          if (a->pressed & INPUT_ACTION_BIT(INPUT_ACTION_JUMP)) jump();
 *      `--record FILE` stores every frame's raw events and actions; `--replay FILE` feeds them
 *      back instead of the devices, so a run is reproducible frame for frame.
 *
 * Threads: everything but the decoders is main-thread only. Decoders are plain data: one per
 * device, used from one thread at a time.
 */
#ifndef INPUT_H
#define INPUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/core.h"   /* core_error */

/* ---- gamepad state ------------------------------------------------------------------------ */

/* Buttons by position (SDL's naming): south is the bottom face button whatever its label. */
typedef enum input_button {
    INPUT_BUTTON_SOUTH,      /* Cross, B (Nintendo), A (Xbox) */
    INPUT_BUTTON_EAST,
    INPUT_BUTTON_WEST,
    INPUT_BUTTON_NORTH,
    INPUT_BUTTON_LB,
    INPUT_BUTTON_RB,
    INPUT_BUTTON_LS,         /* left stick click */
    INPUT_BUTTON_RS,
    INPUT_BUTTON_BACK,       /* Share / Create / Minus */
    INPUT_BUTTON_START,      /* Options / Plus */
    INPUT_BUTTON_GUIDE,      /* PS / Home */
    INPUT_BUTTON_DPAD_UP,
    INPUT_BUTTON_DPAD_DOWN,
    INPUT_BUTTON_DPAD_LEFT,
    INPUT_BUTTON_DPAD_RIGHT,
    INPUT_BUTTON_TOUCHPAD,
    INPUT_BUTTON_MISC,       /* DualSense mute, Switch capture */
    INPUT_BUTTON_COUNT
} input_button;

/* "south", "east", … "misc": the names tools/hidreplay prints and bindings files use. */
const char *input_button_name(input_button button);
/* The button of that name, or INPUT_BUTTON_COUNT when there is none. */
input_button input_button_from_name(const char *name);

typedef struct input_gamepad_state {
    float lx, ly, rx, ry;    /* sticks, [-1, 1]; x positive right, y positive down */
    float lt, rt;            /* triggers, [0, 1] (digital triggers give 0 or 1) */
    uint32_t buttons;        /* bit (1u << input_button) per pressed button */
} input_gamepad_state;

/* Radial dead zone: a stick whose deflection r is under `radius` reads 0; beyond it the length
 * is rescaled to (r − radius)/(1 − radius), so output still reaches 1 and keeps its direction. */
void input_apply_dead_zone(input_gamepad_state *state, float radius);

/* ---- report decoders ---------------------------------------------------------------------- */

typedef enum input_gamepad_kind {
    INPUT_GAMEPAD_GENERIC,       /* decoded through its report descriptor */
    INPUT_GAMEPAD_DUALSHOCK4,
    INPUT_GAMEPAD_DUALSENSE,
    INPUT_GAMEPAD_SWITCH_PRO,
} input_gamepad_kind;

const char *input_gamepad_kind_name(input_gamepad_kind kind);
/* The known pad of that USB vendor/product id; false when it is not one (then use a descriptor). */
bool input_gamepad_kind_from_ids(uint16_t vendor_id, uint16_t product_id, input_gamepad_kind *kind);

typedef struct input_decoder_desc {
    uint16_t vendor_id, product_id;
    /* Required for pads that are not known by id; ignored for known ones. */
    const uint8_t *descriptor;
    size_t descriptor_size;
} input_decoder_desc;

typedef struct input_decoder input_decoder;

/* NULL when the pad is unknown and its descriptor missing (CORE_ERROR_ARGUMENT) or unusable
 * (CORE_ERROR_FORMAT: malformed, or no stick or buttons; CORE_ERROR_RANGE: past the parser's
 * limits); then `error` (may be NULL) says why in one line. */
input_decoder *input_decoder_create(const input_decoder_desc *desc, core_error *error);
void input_decoder_destroy(input_decoder *decoder);
input_gamepad_kind input_decoder_kind(const input_decoder *decoder);

typedef enum input_decode_result {
    INPUT_DECODE_OK,             /* *state updated */
    INPUT_DECODE_SHORT,          /* fewer bytes than the layout needs */
    INPUT_DECODE_OVERSIZED,      /* more bytes than any report of this device */
    INPUT_DECODE_UNKNOWN_ID,     /* a report ID this decoder does not read (e.g. an ack) */
    INPUT_DECODE_MALFORMED,      /* right size and ID, impossible content */
} input_decode_result;

/* `report` starts with the report ID byte where the device uses report IDs (as hid_read gives
 * it). On anything but INPUT_DECODE_OK, *state is left as it was and `error` (may be NULL; text
 * is formatted only when given) says why with its numbers ("report too short: 9 bytes, need
 * 10"): SHORT is CORE_ERROR_CORRUPT (truncated), OVERSIZED CORE_ERROR_RANGE, UNKNOWN_ID and
 * MALFORMED CORE_ERROR_FORMAT. On INPUT_DECODE_OK `error` is left as it was. */
input_decode_result input_decoder_decode(input_decoder *decoder, const uint8_t *report, size_t size,
                                         input_gamepad_state *state, core_error *error);
/* The result in a few words ("report too short"). */
const char *input_decode_result_name(input_decode_result result);

typedef struct input_decoder_stats_info {
    uint64_t decoded, short_reports, oversized, unknown_id, malformed;
} input_decoder_stats_info;
input_decoder_stats_info input_decoder_stats(const input_decoder *decoder);

/* ---- actions ------------------------------------------------------------------------------ */

typedef enum input_action {
    INPUT_ACTION_JUMP,
    INPUT_ACTION_SPRINT,
    INPUT_ACTION_CROUCH,
    INPUT_ACTION_TOOL,           /* use the current tool (primary) */
    INPUT_ACTION_TOOL_ALT,       /* the tool's second use (e.g. carve instead of add) */
    INPUT_ACTION_TOGGLE_FLY,
    INPUT_ACTION_SCREENSHOT,     /* F12 by default; the program calls gfx_screenshot */
    INPUT_ACTION_FULLSCREEN,     /* F11 by default; the program calls gfx_window_toggle_fullscreen */
    INPUT_ACTION_CAPTURE_MOUSE,  /* click to capture, Escape to release (by default) */
    INPUT_ACTION_QUIT,
    INPUT_ACTION_NEXT_TOOL,      /* the tool selector: Tab / right shoulder by default (after quit,
                                    so recordings made before it keep their bits) */
    INPUT_ACTION_TOGGLE_HUD,     /* F1 by default: the program shows or hides its HUD */
    INPUT_ACTION_COUNT
} input_action;
#define INPUT_ACTION_BIT(action) (1u << (action))

/* "jump", "sprint", … as bindings files name them; INPUT_ACTION_COUNT when unknown. */
const char *input_action_name(input_action action);
input_action input_action_from_name(const char *name);

typedef struct input_actions {
    float move_x, move_y;        /* walk: x right, y forward; length ≤ 1 */
    float look_x, look_y;        /* radians to turn this frame: x right (yaw), y up (pitch) */
    uint32_t down;               /* INPUT_ACTION_BIT per action held now */
    uint32_t pressed;            /* … went down this frame */
    uint32_t released;           /* … went up this frame */
} input_actions;

/* ---- bindings ----------------------------------------------------------------------------- */

/* A bindings file: one binding per line, '#' starts a comment, e.g.
 *     jump        = key:space, pad:south
 *     move_up     = key:w, pad:left_stick_up
 *     look_right  = mouse:right, pad:right_stick_right
 *     tool        = mouse:button1, pad:rt
 *     look_speed  = 0.0025          # radians per mouse count
 * input_bindings_load reports each bad line with its file name and line number (through
 * core_warn, and counted in *bad_lines) and skips it; the rest of the file still applies. */
typedef struct input_bindings input_bindings;
input_bindings *input_bindings_default(void);
/* NULL only when the file cannot be read: CORE_ERROR_IO (missing, unreadable) or CORE_ERROR_RANGE
 * (larger than 1 MiB), with a message naming the file; not logged. Bad lines
 * are warnings that skip the line, not a failure. */
input_bindings *input_bindings_load(const char *path, int *bad_lines, core_error *error);
input_bindings *input_bindings_parse(const char *text, size_t size, const char *name, int *bad_lines);
void input_bindings_destroy(input_bindings *bindings);

/* ---- the input system --------------------------------------------------------------------- */

typedef struct input_system_desc {
    const input_bindings *bindings;  /* NULL = defaults; copied */
    void *glfw_window;               /* a GLFWwindow *, or NULL (no keyboard or mouse) */
    bool no_gamepads;                /* don't open hidapi (tests, replays) */
    float dead_zone;                 /* radial stick dead zone; 0 = default 0.15 */
    const char *record_path;         /* --record FILE: write frames here */
    const char *replay_path;         /* --replay FILE: read frames from here instead of devices */
    /* --gamepad-mappings FILE: lines in SDL's game controller database format for the pads read
     * through GLFW (bad lines are reported with FILE:LINE and skipped; an unreadable file fails
     * input_system_create) */
    const char *gamepad_mappings_path;
} input_system_desc;

typedef struct input_system input_system;

/* NULL on failure, with the error naming the file (not logged): CORE_ERROR_IO for a replay or
 * --gamepad-mappings file that cannot be read or a record file that cannot be written;
 * CORE_ERROR_FORMAT (bad magic, a bad source in the header), _RANGE (settings out of range),
 * _VERSION (another recording version) or _CORRUPT (a short or damaged header) for a bad replay;
 * CORE_ERROR_RANGE for a mappings file over 4 MiB. */
input_system *input_system_create(const input_system_desc *desc, core_error *error);
void input_system_destroy(input_system *input);

/* Once per frame on the main thread: polls GLFW events (glfwPollEvents; the input system owns
 * the window's key, mouse-button, cursor and scroll callbacks), gathers gamepad states, computes the
 * actions; records or replays the frame. Returns false when a replay has run out of frames. */
bool input_update(input_system *input, float dt);
const input_actions *input_actions_get(const input_system *input);
/* The dt this frame's actions were computed with: input_update's argument, or while replaying the
 * recorded one, which a replayed run should step its simulation with (stick look scales by it). */
float input_frame_dt(const input_system *input);

/* The first connected gamepad's state after the dead zone (zeros when none). */
input_gamepad_state input_gamepad(const input_system *input);
int input_gamepad_count(const input_system *input);

/* Mouse capture for looking around (hides the cursor; raw motion where the platform has it). */
void input_capture_mouse(input_system *input, bool captured);

/* Events from a source of your own (a test, a script, a network peer, an on-screen pad): queued
 * for the next input_update exactly as a device's would be, then bound to actions, recorded and
 * replayed like them; ignored while a replay runs. Keys are GLFW key codes (GLFW_KEY_SPACE …),
 * buttons GLFW mouse buttons; out-of-range codes and non-finite motion are dropped. A gamepad
 * state is taken before the dead zone, as a decoder gives it; NULL unplugs that slot. */
void input_feed_key(input_system *input, int key, bool down);
void input_feed_mouse_button(input_system *input, int button, bool down);
void input_feed_mouse_motion(input_system *input, float dx, float dy);
void input_feed_scroll(input_system *input, float dx, float dy);
void input_feed_gamepad(input_system *input, int slot, const input_gamepad_state *state);

#endif
