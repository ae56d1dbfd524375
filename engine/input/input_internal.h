/* input_internal.h — what the input system's files share, and the seams tests use. Only
 * engine/input/ and the input tests include this.
 *
 * The input system is built around one device-independent seam: everything a device does becomes
 * an input_event in a per-frame list (GLFW callbacks, the gamepad thread, the replay reader and the
 * tests' input_feed_* all append to it), and input__state_* turn that list plus the held state
 * into the frame's input_actions. Recording writes the list; replaying reads it back and runs the
 * same code, so a replay is bit for bit the recorded run.
 */
#ifndef INPUT_INTERNAL_H
#define INPUT_INTERNAL_H

#include "input/input.h"

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum {
    INPUT_KEY_COUNT = 349,          /* GLFW_KEY_LAST + 1 (checked where GLFW is included) */
    INPUT_MOUSE_BUTTON_COUNT = 8,   /* GLFW_MOUSE_BUTTON_LAST + 1 */
    INPUT_MAX_GAMEPADS = 8,         /* slots; a ninth pad is logged and ignored */
    INPUT_MAX_SOURCES = 8,          /* sources per action in a binding */
    INPUT_MAX_EVENTS = 4096,        /* events per frame; more are dropped (warned once) */
    INPUT_BINDINGS_MAX_LINE = 1024, /* bytes per bindings line, comment included */
};

/* ---- binding targets and sources ------------------------------------------------------------ */

/* The half-axes the analog actions are built from: move_x = right − left, etc. */
typedef enum input_axis {
    INPUT_AXIS_MOVE_UP,
    INPUT_AXIS_MOVE_DOWN,
    INPUT_AXIS_MOVE_LEFT,
    INPUT_AXIS_MOVE_RIGHT,
    INPUT_AXIS_LOOK_UP,
    INPUT_AXIS_LOOK_DOWN,
    INPUT_AXIS_LOOK_LEFT,
    INPUT_AXIS_LOOK_RIGHT,
    INPUT_AXIS_COUNT
} input_axis;

/* A binding target is a button action (0 … INPUT_ACTION_COUNT − 1) or a half-axis
 * (INPUT_ACTION_COUNT + input_axis). */
enum { INPUT_TARGET_COUNT = INPUT_ACTION_COUNT + INPUT_AXIS_COUNT };
#define INPUT_TARGET_AXIS(axis) (INPUT_ACTION_COUNT + (int)(axis))

typedef enum input_source_kind {
    INPUT_SOURCE_KEY = 1,           /* code: GLFW key */
    INPUT_SOURCE_MOUSE_BUTTON,      /* code: GLFW mouse button, 0 = button1 (left) */
    INPUT_SOURCE_MOUSE_AXIS,        /* code: input_mouse_axis; look half-axes only */
    INPUT_SOURCE_PAD_BUTTON,        /* code: input_button */
    INPUT_SOURCE_PAD_AXIS,          /* code: input_pad_axis */
} input_source_kind;

typedef enum input_mouse_axis {
    INPUT_MOUSE_LEFT,
    INPUT_MOUSE_RIGHT,
    INPUT_MOUSE_UP,
    INPUT_MOUSE_DOWN,
    INPUT_MOUSE_AXIS_COUNT
} input_mouse_axis;

typedef enum input_pad_axis {
    INPUT_PAD_LT,
    INPUT_PAD_RT,
    INPUT_PAD_LEFT_STICK_UP,
    INPUT_PAD_LEFT_STICK_DOWN,
    INPUT_PAD_LEFT_STICK_LEFT,
    INPUT_PAD_LEFT_STICK_RIGHT,
    INPUT_PAD_RIGHT_STICK_UP,
    INPUT_PAD_RIGHT_STICK_DOWN,
    INPUT_PAD_RIGHT_STICK_LEFT,
    INPUT_PAD_RIGHT_STICK_RIGHT,
    INPUT_PAD_AXIS_COUNT
} input_pad_axis;

typedef struct input_source {
    uint8_t kind;    /* input_source_kind */
    uint16_t code;
} input_source;

struct input_bindings {
    input_source sources[INPUT_TARGET_COUNT][INPUT_MAX_SOURCES];
    uint8_t source_count[INPUT_TARGET_COUNT];
    float look_speed;        /* radians per mouse count */
    float stick_look_speed;  /* radians per second at full stick deflection (and for keys) */
    float dead_zone;         /* radial stick dead zone */
    bool invert_y;           /* look_y sign flipped (mouse, stick and keys alike) */
};

/* "jump" … "quit", then "move_up" … "look_right". */
const char *input__target_name(int target);
/* NULL when the source fits the target; otherwise why not ("mouse:left only turns the view"). */
const char *input__source_misfit(int target, input_source source);
/* Every source valid for its target, counts in range, settings in range. */
bool input__bindings_valid(const input_bindings *bindings);
/* Same sources per target (as sets) and the same settings. */
bool input__bindings_equal(const input_bindings *a, const input_bindings *b);
void input__bindings_set_default(input_bindings *bindings);

/* Setting ranges (inclusive). */
#define INPUT_LOOK_SPEED_MAX 1.0f
#define INPUT_STICK_LOOK_SPEED_MAX 100.0f
#define INPUT_DEAD_ZONE_MAX 0.95f
#define INPUT_DEAD_ZONE_DEFAULT 0.15f

/* ---- raw events ----------------------------------------------------------------------------- */

typedef enum input_event_kind {
    INPUT_EVENT_KEY = 1,            /* code: GLFW key; down */
    INPUT_EVENT_MOUSE_BUTTON,       /* code: GLFW mouse button; down */
    INPUT_EVENT_MOUSE_MOTION,       /* x, y: cursor counts, y down positive */
    INPUT_EVENT_SCROLL,             /* x, y: wheel offsets */
    INPUT_EVENT_GAMEPAD,            /* code: slot; pad: the state before the dead zone */
    INPUT_EVENT_GAMEPAD_GONE,       /* code: slot */
    INPUT_EVENT_CAPTURE,            /* down: captured (input_capture_mouse) */
    INPUT_EVENT_KIND_END
} input_event_kind;

typedef struct input_event {
    uint8_t kind;
    uint8_t down;
    uint16_t code;
    float x, y;
    input_gamepad_state pad;
} input_event;

/* Whether an event's fields are in range (a replayed file is checked with this). */
bool input__event_valid(const input_event *event);

/* ---- held state and action computation (input_actions.c) ----------------------------------- */

typedef struct input_pad_view {
    bool connected;
    input_gamepad_state state;      /* after the dead zone */
} input_pad_view;

typedef struct input_state {
    input_bindings bindings;
    float dead_zone;
    bool keys[INPUT_KEY_COUNT];
    uint8_t mouse_down;             /* bit per mouse button held */
    uint8_t mouse_down_captured;    /* … pressed while the mouse was captured */
    bool captured;                  /* logical mouse capture: motion turns the view */
    input_pad_view pads[INPUT_MAX_GAMEPADS];
    uint32_t raw_down;              /* button actions whose sources are down */
    uint32_t swallowed;             /* held actions hidden from the game (quit that released capture) */
    float mouse_dx, mouse_dy;       /* this frame's captured motion */
    float scroll_x, scroll_y;       /* this frame's wheel */
    input_actions actions;
} input_state;

void input__state_init(input_state *state, const input_bindings *bindings, float dead_zone);
void input__state_begin_frame(input_state *state);
void input__state_apply(input_state *state, const input_event *event);
void input__state_end_frame(input_state *state, float dt);

/* ---- gamepads: the thread and what it publishes (input_gamepads.c) -------------------------- */

typedef struct input_pad_slot {
    bool connected;
    uint32_t generation;            /* bumped on every connect, so a quick re-plug is seen */
    input_gamepad_state state;      /* latest decoded, before the dead zone */
    uint32_t latched;               /* buttons that went down since the main thread last looked */
    /* who reads the pad in this slot: the hidraw thread or GLFW on the main thread */
    bool claimed, hidraw;
    uint16_t vendor_id, product_id; /* 0 when unknown */
    char name[64];
} input_pad_slot;

/* Shared between the gamepad thread (writes) and the main thread (reads in input_update; writes
 * for the pads it reads through GLFW). */
typedef struct input_pads_shared {
    pthread_mutex_t lock;
    pthread_cond_t wake;            /* CLOCK_MONOTONIC; signalled to stop the thread */
    bool stop;
    bool hid_scanned;               /* the hidraw thread has enumerated once (GLFW waits for it) */
    input_pad_slot slots[INPUT_MAX_GAMEPADS];
} input_pads_shared;

/* A free slot, marked as read by hidraw or GLFW, with the pad's ids and name; −1 when all 8 are
 * taken. Either thread may claim; each releases only what it claimed. */
int input__pad_slot_claim(input_pads_shared *shared, bool hidraw, uint16_t vendor_id, uint16_t product_id,
                          const char *name);
void input__pad_slot_release(input_pads_shared *shared, int slot);

typedef struct input_gamepads input_gamepads;

void input__pads_shared_init(input_pads_shared *shared);
void input__pads_shared_destroy(input_pads_shared *shared);
/* What the reading thread calls for each decoded report (state NULL: the pad is gone). Tests
 * call it from threads of their own. */
void input__gamepad_publish(input_pads_shared *shared, int slot, const input_gamepad_state *state);

/* NULL when hid_init fails (logged); starts the thread. */
input_gamepads *input__gamepads_start(input_pads_shared *shared);
/* Stops and joins the thread (within a few milliseconds), closes the devices. */
void input__gamepads_stop(input_gamepads *gamepads);

/* Top-level usages of a HID report descriptor: true when one of its top-level application
 * collections is Generic Desktop Joystick (0x04) or Gamepad (0x05). Safe on any bytes. */
bool input__descriptor_is_gamepad(const uint8_t *descriptor, size_t size);

/* ---- SDL game controller mappings (input_mappings.c) ------------------------------------------ */

/* A pad's outputs in SDL's terms: GLFW's 15 gamepad buttons in GLFW's order (GLFW_GAMEPAD_BUTTON_A
 * … _DPAD_LEFT), then the ones GLFW lacks; GLFW's 6 gamepad axes in its order (sticks −1…1, y down
 * positive; triggers −1 at rest … 1 pulled). */
typedef enum input_sdl_output {
    INPUT_SDL_A, INPUT_SDL_B, INPUT_SDL_X, INPUT_SDL_Y,
    INPUT_SDL_LEFTSHOULDER, INPUT_SDL_RIGHTSHOULDER, INPUT_SDL_BACK, INPUT_SDL_START, INPUT_SDL_GUIDE,
    INPUT_SDL_LEFTSTICK, INPUT_SDL_RIGHTSTICK,
    INPUT_SDL_DPUP, INPUT_SDL_DPRIGHT, INPUT_SDL_DPDOWN, INPUT_SDL_DPLEFT,
    INPUT_SDL_MISC1, INPUT_SDL_TOUCHPAD,
    INPUT_SDL_PADDLE1, INPUT_SDL_PADDLE2, INPUT_SDL_PADDLE3, INPUT_SDL_PADDLE4,
    INPUT_SDL_BUTTON_COUNT,
    INPUT_SDL_LEFTX = INPUT_SDL_BUTTON_COUNT, INPUT_SDL_LEFTY, INPUT_SDL_RIGHTX, INPUT_SDL_RIGHTY,
    INPUT_SDL_LEFTTRIGGER, INPUT_SDL_RIGHTTRIGGER,
    INPUT_SDL_OUTPUT_COUNT
} input_sdl_output;
enum {
    INPUT_SDL_AXIS_COUNT = INPUT_SDL_OUTPUT_COUNT - INPUT_SDL_BUTTON_COUNT,
    INPUT_SDL_GLFW_BUTTONS = INPUT_SDL_MISC1,  /* the first 15 are GLFW's */
    INPUT_SDL_MAX_BINDINGS = 48,               /* elements per mapping line */
    INPUT_SDL_MAX_LINE = 1024,                 /* bytes per mappings line */
    INPUT_SDL_MAX_FILE = 4 << 20,
};

/* The pad as SDL/GLFW's gamepad layer sees it: what glfwGetGamepadState gives, and what
 * input__sdl_mapping_apply makes from a raw joystick. */
typedef struct input_sdl_pad {
    bool buttons[INPUT_SDL_BUTTON_COUNT];
    float axes[INPUT_SDL_AXIS_COUNT];
} input_sdl_pad;

/* One "output:input" pair of a mapping line, e.g. "-leftx:h0.8" or "lefttrigger:a2~". */
typedef struct input_sdl_binding {
    uint8_t output;          /* input_sdl_output */
    int8_t output_half;      /* 0 the whole axis, +1 "+leftx", −1 "-leftx" */
    uint8_t kind;            /* 'b' button, 'a' axis, 'h' hat */
    uint8_t index;           /* button, axis or hat number */
    uint8_t hat_mask;        /* 1 up, 2 right, 4 down, 8 left */
    int8_t input_half;       /* 0 the whole axis, +1 "+a2", −1 "-a2" */
    bool invert;             /* "a2~" */
} input_sdl_binding;

typedef struct input_sdl_mapping {
    char guid[33];           /* 32 lower-case hex digits */
    char name[128];
    bool other_platform;     /* "platform:" names another OS: valid, but not for this machine */
    uint8_t binding_count;
    input_sdl_binding bindings[INPUT_SDL_MAX_BINDINGS];
} input_sdl_mapping;

/* One line of the SDL game controller database format (no newline):
 *     GUID,name,output:input,...,platform:Linux,
 * false with a one-line reason in `error` when it is not one; safe on any bytes. */
bool input__sdl_mapping_parse(const char *line, size_t length, input_sdl_mapping *mapping, core_error *error);

/* A raw joystick as glfwGetJoystickAxes/Buttons/Hats give it (hats as GLFW_HAT_* bits, which are
 * SDL's: 1 up, 2 right, 4 down, 8 left). Elements the mapping names beyond the counts read as
 * released / at rest. */
typedef struct input_sdl_joystick {
    const float *axes;
    const uint8_t *buttons;
    const uint8_t *hats;
    int axis_count, button_count, hat_count;
} input_sdl_joystick;
void input__sdl_mapping_apply(const input_sdl_mapping *mapping, const input_sdl_joystick *joystick, input_sdl_pad *pad);
/* SDL's layout to ours: buttons by the same positions, triggers from −1…1 to 0…1. */
void input__sdl_pad_to_state(const input_sdl_pad *pad, input_gamepad_state *state);

/* A mappings file's good lines: parsed, and as text for glfwUpdateGamepadMappings. */
typedef struct input_sdl_mappings {
    input_sdl_mapping *items;
    size_t count, capacity;
    char *text;              /* the good lines for this platform, each ending in '\n'; NUL-terminated */
    size_t text_size, text_capacity;
} input_sdl_mappings;

/* Reads text[0, size): each bad line is reported as "NAME:LINE: reason (line skipped)" through
 * core_warn and counted in *bad_lines; blank lines and '#' comments are skipped. Lines for
 * another platform are kept out of `text` and `items` without complaint. Never fails. */
void input__sdl_mappings_parse(input_sdl_mappings *mappings, const char *text, size_t size, const char *name,
                               int *bad_lines);
/* false (CORE_ERROR_IO, or _RANGE when larger than INPUT_SDL_MAX_FILE) when the file cannot be
 * read; bad lines are not a failure. */
bool input__sdl_mappings_load(input_sdl_mappings *mappings, const char *path, int *bad_lines, core_error *error);
/* A whole text file of at most max_bytes (the bindings, the gamepad mappings), for a parser;
 * free it with core_free(text, *capacity). NULL when it cannot be opened or read
 * (CORE_ERROR_IO) or is larger (CORE_ERROR_RANGE), with a message naming `what` and the path. */
char *input__file_read(const char *path, const char *what, size_t max_bytes, size_t *size, size_t *capacity,
                       core_error *error);
void input__sdl_mappings_free(input_sdl_mappings *mappings);
/* The mapping for a GUID (32 hex digits, any case), or NULL. */
const input_sdl_mapping *input__sdl_mappings_find(const input_sdl_mappings *mappings, const char *guid);

/* The USB vendor and product ids inside a Linux joystick GUID (SDL's and GLFW's layout: bus,
 * 0000, vendor, 0000, product, 0000, version, 0000, each 16-bit little-endian); false when the
 * GUID is the other form (bus and the device's name), which carries none. */
bool input__guid_ids(const char *guid, uint16_t *vendor_id, uint16_t *product_id);

/* ---- gamepads through GLFW, on the main thread (input_glfw_pads.c) ---------------------------- */

enum { INPUT_GLFW_JOYSTICKS = 16 };     /* GLFW_JOYSTICK_LAST + 1 */

/* Pads hidapi cannot read (xpad exposes no hidraw node; a node this user cannot open) are read
 * through GLFW's gamepad API, which knows SDL's mappings; `--gamepad-mappings FILE` adds lines. */
typedef struct input_glfw_pads {
    bool active;                                /* a window (so GLFW) and gamepads wanted */
    input_sdl_mappings mappings;                /* the file's good lines */
    int slot[INPUT_GLFW_JOYSTICKS];             /* the slot a joystick is read into, −1 none */
    bool noted[INPUT_GLFW_JOYSTICKS];           /* "no mapping for it" logged since it appeared */
    bool warned_full;
} input_glfw_pads;

/* Loads the mappings file (when given) and hands its good lines to GLFW (when `active`); false
 * (error filled, as input__sdl_mappings_load) only when the file cannot be read. */
bool input__glfw_pads_init(input_glfw_pads *pads, const char *mappings_path, bool active, core_error *error);
/* Once a frame, main thread, before the slots are gathered: joysticks that are gamepads and not
 * read by the hidraw thread are read and published into `shared`'s slots. */
void input__glfw_pads_poll(input_glfw_pads *pads, input_pads_shared *shared, bool wait_for_hid);
void input__glfw_pads_close(input_glfw_pads *pads, input_pads_shared *shared);

/* The duplicate rule: a GLFW joystick is a pad the hidraw thread already reads when its GUID
 * carries vendor and product ids and more hidraw slots have those ids than `same_ids_before`
 * (GLFW gamepads with the same ids at lower joystick numbers); when the GUID carries no ids, when
 * a hidraw pad's product name appears in the joystick's name. */
bool input__glfw_pad_is_duplicate(const input_pad_slot slots[INPUT_MAX_GAMEPADS], const char *guid, const char *name,
                                  int same_ids_before);

/* ---- record and replay (input_record.c) ----------------------------------------------------- */

typedef struct input_recorder input_recorder;
typedef struct input_replayer input_replayer;

/* The frame as stored: dt, raw events, resulting actions. */
typedef struct input_frame {
    uint32_t index;
    float dt;
    input_event *events;            /* owned by whoever decoded it */
    uint32_t event_count;
    input_actions actions;
} input_frame;

/* Opens PATH.part for writing and writes the header; NULL (CORE_ERROR_IO) when it cannot. */
input_recorder *input__recorder_open(const char *path, const input_bindings *bindings, float dead_zone,
                                     core_error *error);
void input__recorder_write(input_recorder *recorder, float dt, const input_event *events, uint32_t count,
                           const input_actions *actions);
/* Writes the end record, closes, renames PATH.part over PATH. */
void input__recorder_close(input_recorder *recorder);

/* Reads and checks the header; NULL when it is missing (CORE_ERROR_IO) or bad (CORE_ERROR_FORMAT
 * for a bad magic or header content, _VERSION for another recording version, _CORRUPT for a short,
 * truncated or damaged header), with a message naming the file. The bindings and dead zone the
 * recording was made with come back in *bindings and *dead_zone. */
input_replayer *input__replayer_open(const char *path, input_bindings *bindings, float *dead_zone,
                                     core_error *error);
/* The next frame (events valid until the next call), or false at the end or on a bad record
 * (logged with the file name and frame). */
bool input__replayer_next(input_replayer *replayer, input_frame *frame);
/* True once a bad or truncated record, not the end record, ended the replay. */
bool input__replayer_failed(const input_replayer *replayer);
void input__replayer_close(input_replayer *replayer);

/* The decoders behind the reader, exposed for the fuzz target: they check everything but the
 * checksum. `payload` is one record's payload. */
bool input__record_decode_header(const uint8_t *payload, size_t size, input_bindings *bindings, float *dead_zone,
                                 core_error *error);
bool input__record_decode_frame(const uint8_t *payload, size_t size, input_frame *frame, input_event *events,
                                uint32_t event_capacity, core_error *error);

/* ---- test seams (input_system.c) ------------------------------------------------------------ */

/* The shared slots the gamepad thread publishes into (exists with or without the thread). */
input_pads_shared *input__pads(input_system *input);
bool input__mouse_captured(const input_system *input);
bool input__gamepad_thread_running(const input_system *input);
/* Replayed frames whose recomputed actions differed from the recorded ones. */
uint64_t input__replay_mismatches(const input_system *input);
/* True when the replay ended on a bad record rather than its end record. */
bool input__replay_failed(const input_system *input);

#endif /* INPUT_INTERNAL_H */
