/* input_bindings.c — the bindings file: defaults, parser, loader (input.h, "bindings").
 *
 * The format is in README.md. The parser reads text[0, size) line by line and never past it;
 * a line is copied into a bounded buffer before it is looked at, so NUL bytes, overlong lines and
 * any other bytes are a reported bad line, never a read out of bounds. A bad line changes nothing:
 * either the whole line applies or none of it does.
 */
#include "input/input_internal.h"

#include "core/core.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(INPUT_KEY_COUNT == GLFW_KEY_LAST + 1, "INPUT_KEY_COUNT follows GLFW");
_Static_assert(INPUT_MOUSE_BUTTON_COUNT == GLFW_MOUSE_BUTTON_LAST + 1, "INPUT_MOUSE_BUTTON_COUNT follows GLFW");
_Static_assert(INPUT_TARGET_COUNT <= 32, "button actions are bits of a uint32_t");

enum { INPUT_BINDINGS_MAX_FILE = 1 << 20 };

/* ---- names ---------------------------------------------------------------------------------- */

typedef struct input_name_code {
    const char *name;
    int code;
} input_name_code;

/* GLFW's key names in lower case (GLFW_KEY_LEFT_SHIFT → left_shift); letters, digits, f1–f25 and
 * kp_0–kp_9 are handled by rule in input_key_from_name. */
static const input_name_code input_key_names[] = {
    { "space", GLFW_KEY_SPACE },
    { "apostrophe", GLFW_KEY_APOSTROPHE },
    { "comma", GLFW_KEY_COMMA },
    { "minus", GLFW_KEY_MINUS },
    { "period", GLFW_KEY_PERIOD },
    { "slash", GLFW_KEY_SLASH },
    { "semicolon", GLFW_KEY_SEMICOLON },
    { "equal", GLFW_KEY_EQUAL },
    { "left_bracket", GLFW_KEY_LEFT_BRACKET },
    { "backslash", GLFW_KEY_BACKSLASH },
    { "right_bracket", GLFW_KEY_RIGHT_BRACKET },
    { "grave_accent", GLFW_KEY_GRAVE_ACCENT },
    { "world_1", GLFW_KEY_WORLD_1 },
    { "world_2", GLFW_KEY_WORLD_2 },
    { "escape", GLFW_KEY_ESCAPE },
    { "enter", GLFW_KEY_ENTER },
    { "tab", GLFW_KEY_TAB },
    { "backspace", GLFW_KEY_BACKSPACE },
    { "insert", GLFW_KEY_INSERT },
    { "delete", GLFW_KEY_DELETE },
    { "right", GLFW_KEY_RIGHT },
    { "left", GLFW_KEY_LEFT },
    { "down", GLFW_KEY_DOWN },
    { "up", GLFW_KEY_UP },
    { "page_up", GLFW_KEY_PAGE_UP },
    { "page_down", GLFW_KEY_PAGE_DOWN },
    { "home", GLFW_KEY_HOME },
    { "end", GLFW_KEY_END },
    { "caps_lock", GLFW_KEY_CAPS_LOCK },
    { "scroll_lock", GLFW_KEY_SCROLL_LOCK },
    { "num_lock", GLFW_KEY_NUM_LOCK },
    { "print_screen", GLFW_KEY_PRINT_SCREEN },
    { "pause", GLFW_KEY_PAUSE },
    { "kp_decimal", GLFW_KEY_KP_DECIMAL },
    { "kp_divide", GLFW_KEY_KP_DIVIDE },
    { "kp_multiply", GLFW_KEY_KP_MULTIPLY },
    { "kp_subtract", GLFW_KEY_KP_SUBTRACT },
    { "kp_add", GLFW_KEY_KP_ADD },
    { "kp_enter", GLFW_KEY_KP_ENTER },
    { "kp_equal", GLFW_KEY_KP_EQUAL },
    { "left_shift", GLFW_KEY_LEFT_SHIFT },
    { "left_ctrl", GLFW_KEY_LEFT_CONTROL },
    { "left_control", GLFW_KEY_LEFT_CONTROL },
    { "left_alt", GLFW_KEY_LEFT_ALT },
    { "left_super", GLFW_KEY_LEFT_SUPER },
    { "right_shift", GLFW_KEY_RIGHT_SHIFT },
    { "right_ctrl", GLFW_KEY_RIGHT_CONTROL },
    { "right_control", GLFW_KEY_RIGHT_CONTROL },
    { "right_alt", GLFW_KEY_RIGHT_ALT },
    { "right_super", GLFW_KEY_RIGHT_SUPER },
    { "menu", GLFW_KEY_MENU },
};

static const char *const input_pad_axis_names[INPUT_PAD_AXIS_COUNT] = {
    "lt", "rt",
    "left_stick_up", "left_stick_down", "left_stick_left", "left_stick_right",
    "right_stick_up", "right_stick_down", "right_stick_left", "right_stick_right",
};

static const char *const input_mouse_axis_names[INPUT_MOUSE_AXIS_COUNT] = { "left", "right", "up", "down" };

/* A whole number in [lo, hi] spelt with digits only ("12"), or -1. */
static int input_small_number(const char *s, int lo, int hi) {
    if (!*s || strlen(s) > 3) return -1;
    int value = 0;
    for (; *s; s++) {
        if (*s < '0' || *s > '9') return -1;
        value = value * 10 + (*s - '0');
    }
    return value >= lo && value <= hi ? value : -1;
}

/* GLFW key code, or -1. `name` is lower case. */
static int input_key_from_name(const char *name) {
    if (name[0] && !name[1]) {
        if (name[0] >= 'a' && name[0] <= 'z') return GLFW_KEY_A + (name[0] - 'a');
        if (name[0] >= '0' && name[0] <= '9') return GLFW_KEY_0 + (name[0] - '0');
    }
    if (name[0] == 'f') {
        int n = input_small_number(name + 1, 1, 25);
        if (n > 0) return GLFW_KEY_F1 + n - 1;
    }
    if (strncmp(name, "kp_", 3) == 0) {
        int n = input_small_number(name + 3, 0, 9);
        if (n >= 0 && name[4] == '\0') return GLFW_KEY_KP_0 + n;
    }
    for (size_t i = 0; i < CORE_COUNTOF(input_key_names); i++)
        if (strcmp(name, input_key_names[i].name) == 0) return input_key_names[i].code;
    return -1;
}

/* ---- validity ------------------------------------------------------------------------------- */

static bool input_target_is_look(int target) {
    return target >= INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_UP) && target <= INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_RIGHT);
}

const char *input__source_misfit(int target, input_source source) {
    if (target < 0 || target >= INPUT_TARGET_COUNT) return "no such action";
    switch (source.kind) {
    case INPUT_SOURCE_KEY: return source.code < INPUT_KEY_COUNT ? NULL : "no such key";
    case INPUT_SOURCE_MOUSE_BUTTON: return source.code < INPUT_MOUSE_BUTTON_COUNT ? NULL : "no such mouse button";
    case INPUT_SOURCE_PAD_BUTTON: return source.code < INPUT_BUTTON_COUNT ? NULL : "no such gamepad button";
    case INPUT_SOURCE_PAD_AXIS: return source.code < INPUT_PAD_AXIS_COUNT ? NULL : "no such gamepad axis";
    case INPUT_SOURCE_MOUSE_AXIS:
        if (source.code >= INPUT_MOUSE_AXIS_COUNT) return "no such mouse axis";
        return input_target_is_look(target)
                   ? NULL
                   : "mouse motion only turns the view: bind it to look_up, look_down, look_left or look_right";
    default: return "no such kind of source";
    }
}

static bool input_settings_valid(const input_bindings *b) {
    return b->look_speed >= 0.0f && b->look_speed <= INPUT_LOOK_SPEED_MAX && b->stick_look_speed >= 0.0f &&
           b->stick_look_speed <= INPUT_STICK_LOOK_SPEED_MAX && b->dead_zone >= 0.0f &&
           b->dead_zone <= INPUT_DEAD_ZONE_MAX;
}

bool input__bindings_valid(const input_bindings *b) {
    for (int t = 0; t < INPUT_TARGET_COUNT; t++) {
        if (b->source_count[t] > INPUT_MAX_SOURCES) return false;
        for (int i = 0; i < b->source_count[t]; i++)
            if (input__source_misfit(t, b->sources[t][i])) return false;
    }
    return input_settings_valid(b);
}

static bool input_source_in(const input_source *list, int count, input_source source) {
    for (int i = 0; i < count; i++)
        if (list[i].kind == source.kind && list[i].code == source.code) return true;
    return false;
}

bool input__bindings_equal(const input_bindings *a, const input_bindings *b) {
    for (int t = 0; t < INPUT_TARGET_COUNT; t++) {
        /* Lists hold no duplicates, so equal counts and a ⊆ b mean equal sets. */
        if (a->source_count[t] != b->source_count[t]) return false;
        for (int i = 0; i < a->source_count[t]; i++)
            if (!input_source_in(b->sources[t], b->source_count[t], a->sources[t][i])) return false;
    }
    return a->look_speed == b->look_speed && a->stick_look_speed == b->stick_look_speed &&
           a->dead_zone == b->dead_zone && a->invert_y == b->invert_y;
}

/* ---- defaults ------------------------------------------------------------------------------- */

static void input_bind(input_bindings *b, int target, input_source_kind kind, int code) {
    b->sources[target][b->source_count[target]++] = (input_source){ .kind = (uint8_t)kind, .code = (uint16_t)code };
}

/* data/input/bindings.txt says the same in the file format; a test holds them equal. */
void input__bindings_set_default(input_bindings *b) {
    *b = (input_bindings){ .look_speed = 0.0025f, .stick_look_speed = 3.0f, .dead_zone = INPUT_DEAD_ZONE_DEFAULT };
    input_bind(b, INPUT_ACTION_JUMP, INPUT_SOURCE_KEY, GLFW_KEY_SPACE);
    input_bind(b, INPUT_ACTION_JUMP, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_SOUTH);
    input_bind(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_KEY, GLFW_KEY_LEFT_SHIFT);
    input_bind(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_LS);
    input_bind(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_LB);
    input_bind(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_LEFT_CONTROL);
    input_bind(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_C);
    input_bind(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_EAST);
    input_bind(b, INPUT_ACTION_TOOL, INPUT_SOURCE_MOUSE_BUTTON, GLFW_MOUSE_BUTTON_1);
    input_bind(b, INPUT_ACTION_TOOL, INPUT_SOURCE_PAD_AXIS, INPUT_PAD_RT);
    input_bind(b, INPUT_ACTION_TOOL_ALT, INPUT_SOURCE_MOUSE_BUTTON, GLFW_MOUSE_BUTTON_2);
    input_bind(b, INPUT_ACTION_TOOL_ALT, INPUT_SOURCE_PAD_AXIS, INPUT_PAD_LT);
    input_bind(b, INPUT_ACTION_TOGGLE_FLY, INPUT_SOURCE_KEY, GLFW_KEY_F);
    input_bind(b, INPUT_ACTION_TOGGLE_FLY, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_NORTH);
    input_bind(b, INPUT_ACTION_SCREENSHOT, INPUT_SOURCE_KEY, GLFW_KEY_F12);
    input_bind(b, INPUT_ACTION_FULLSCREEN, INPUT_SOURCE_KEY, GLFW_KEY_F11);
    input_bind(b, INPUT_ACTION_CAPTURE_MOUSE, INPUT_SOURCE_MOUSE_BUTTON, GLFW_MOUSE_BUTTON_1);
    input_bind(b, INPUT_ACTION_QUIT, INPUT_SOURCE_KEY, GLFW_KEY_ESCAPE);
    input_bind(b, INPUT_ACTION_QUIT, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_START);
    input_bind(b, INPUT_ACTION_NEXT_TOOL, INPUT_SOURCE_KEY, GLFW_KEY_TAB);
    input_bind(b, INPUT_ACTION_NEXT_TOOL, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_RB);
    input_bind(b, INPUT_ACTION_TOGGLE_HUD, INPUT_SOURCE_KEY, GLFW_KEY_F1);

    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_UP), INPUT_SOURCE_KEY, GLFW_KEY_W);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_UP), INPUT_SOURCE_KEY, GLFW_KEY_UP);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_UP), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_LEFT_STICK_UP);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_DOWN), INPUT_SOURCE_KEY, GLFW_KEY_S);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_DOWN), INPUT_SOURCE_KEY, GLFW_KEY_DOWN);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_DOWN), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_LEFT_STICK_DOWN);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_LEFT), INPUT_SOURCE_KEY, GLFW_KEY_A);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_LEFT), INPUT_SOURCE_KEY, GLFW_KEY_LEFT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_LEFT), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_LEFT_STICK_LEFT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_RIGHT), INPUT_SOURCE_KEY, GLFW_KEY_D);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_RIGHT), INPUT_SOURCE_KEY, GLFW_KEY_RIGHT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_RIGHT), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_LEFT_STICK_RIGHT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_UP), INPUT_SOURCE_MOUSE_AXIS, INPUT_MOUSE_UP);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_UP), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_RIGHT_STICK_UP);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_DOWN), INPUT_SOURCE_MOUSE_AXIS, INPUT_MOUSE_DOWN);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_DOWN), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_RIGHT_STICK_DOWN);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_LEFT), INPUT_SOURCE_MOUSE_AXIS, INPUT_MOUSE_LEFT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_LEFT), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_RIGHT_STICK_LEFT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_RIGHT), INPUT_SOURCE_MOUSE_AXIS, INPUT_MOUSE_RIGHT);
    input_bind(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_RIGHT), INPUT_SOURCE_PAD_AXIS, INPUT_PAD_RIGHT_STICK_RIGHT);
}

input_bindings *input_bindings_default(void) {
    input_bindings *b = core_alloc(sizeof *b);
    input__bindings_set_default(b);
    return b;
}

void input_bindings_destroy(input_bindings *bindings) {
    if (bindings) core_free(bindings, sizeof *bindings);
}

/* ---- parser --------------------------------------------------------------------------------- */

typedef struct input_parser {
    const char *name;
    int line;
    int bad_lines;
    input_bindings *bindings;
} input_parser;

static void input_parser_bad(input_parser *p, const char *fmt, ...) CORE_PRINTF(2, 3);
static void input_parser_bad(input_parser *p, const char *fmt, ...) {
    char reason[256];
    va_list args;
    va_start(args, fmt);
    vsnprintf(reason, sizeof reason, fmt, args);
    va_end(args);
    core_warn("input", "%s:%d: %s (line skipped)", p->name, p->line, reason);
    p->bad_lines++;
}

/* `s` as it may be printed: at most 40 bytes, bytes outside printable ASCII as \xNN. */
static const char *input_shown(const char *s, char out[200]) {
    size_t n = 0;
    for (size_t i = 0; s[i] && n < 190; i++) {
        if (i == 40) {
            memcpy(out + n, "...", 3);
            n += 3;
            break;
        }
        unsigned char c = (unsigned char)s[i];
        if (c >= 0x20 && c < 0x7f) out[n++] = (char)c;
        else n += (size_t)snprintf(out + n, 5, "\\x%02x", c);
    }
    out[n] = '\0';
    return out;
}

static bool input_is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Trims s in place and returns its first non-blank character. */
static char *input_trim(char *s) {
    while (input_is_space(*s)) s++;
    size_t n = strlen(s);
    while (n > 0 && input_is_space(s[n - 1])) s[--n] = '\0';
    return s;
}

static void input_lower(char *s) {
    for (; *s; s++) *s = (char)tolower((unsigned char)*s);
}

/* Parses "kind:name" (already trimmed) into *out; false after reporting why. */
static bool input_parse_source(input_parser *p, int target, char *text, input_source *out) {
    char shown[200];
    char *colon = strchr(text, ':');
    if (!colon) {
        input_parser_bad(p, "source '%s' needs a kind: key:NAME, mouse:NAME or pad:NAME", input_shown(text, shown));
        return false;
    }
    *colon = '\0';
    char *kind = input_trim(text), *name = input_trim(colon + 1);
    input_lower(kind);
    input_lower(name);
    int code = -1;
    input_source_kind source_kind = 0;
    if (strcmp(kind, "key") == 0) {
        source_kind = INPUT_SOURCE_KEY;
        code = input_key_from_name(name);
    } else if (strcmp(kind, "mouse") == 0) {
        if (strncmp(name, "button", 6) == 0) {
            source_kind = INPUT_SOURCE_MOUSE_BUTTON;
            int n = input_small_number(name + 6, 1, INPUT_MOUSE_BUTTON_COUNT);
            code = n > 0 ? n - 1 : -1;
        } else {
            source_kind = INPUT_SOURCE_MOUSE_AXIS;
            for (int i = 0; i < INPUT_MOUSE_AXIS_COUNT; i++)
                if (strcmp(name, input_mouse_axis_names[i]) == 0) code = i;
        }
    } else if (strcmp(kind, "pad") == 0) {
        source_kind = INPUT_SOURCE_PAD_AXIS;
        for (int i = 0; i < INPUT_PAD_AXIS_COUNT; i++)
            if (strcmp(name, input_pad_axis_names[i]) == 0) code = i;
        if (code < 0) {
            input_button button = input_button_from_name(name);
            if ((int)button >= 0 && button < INPUT_BUTTON_COUNT) {
                source_kind = INPUT_SOURCE_PAD_BUTTON;
                code = (int)button;
            }
        }
    } else {
        input_parser_bad(p, "unknown source kind '%s' (expected key, mouse or pad)", input_shown(kind, shown));
        return false;
    }
    if (code < 0) {
        input_parser_bad(p, "unknown source '%s:%s'", kind, input_shown(name, shown));
        return false;
    }
    *out = (input_source){ .kind = (uint8_t)source_kind, .code = (uint16_t)code };
    const char *misfit = input__source_misfit(target, *out);
    if (misfit) {
        input_parser_bad(p, "%s:%s cannot drive %s: %s", kind, name, input__target_name(target), misfit);
        return false;
    }
    return true;
}

/* "action = source, source…": all sources good, or the line is skipped. */
static void input_parse_binding(input_parser *p, int target, char *value) {
    input_source sources[INPUT_MAX_SOURCES];
    int count = 0;
    if (*value) {
        for (char *item = value;;) {
            char *comma = strchr(item, ',');
            if (comma) *comma = '\0';
            char *text = input_trim(item);
            if (!*text) {
                input_parser_bad(p, "empty source in the list of %s", input__target_name(target));
                return;
            }
            input_source source;
            if (!input_parse_source(p, target, text, &source)) return;
            if (!input_source_in(sources, count, source)) {
                if (count == INPUT_MAX_SOURCES) {
                    input_parser_bad(p, "more than %d sources for %s", INPUT_MAX_SOURCES, input__target_name(target));
                    return;
                }
                sources[count++] = source;
            }
            if (!comma) break;
            item = comma + 1;
        }
    }
    memcpy(p->bindings->sources[target], sources, (size_t)count * sizeof sources[0]);
    p->bindings->source_count[target] = (uint8_t)count;
}

static bool input_parse_float(input_parser *p, const char *key, const char *value, float lo, float hi, float *out) {
    char shown[200];
    char *end = NULL;
    errno = 0;
    float f = strtof(value, &end);
    if (!*value || end == value || *end != '\0' || !isfinite(f) || errno == ERANGE) {
        input_parser_bad(p, "%s: '%s' is not a number", key, input_shown(value, shown));
        return false;
    }
    if (f < lo || f > hi) {
        input_parser_bad(p, "%s must be between %g and %g, not %g", key, (double)lo, (double)hi, (double)f);
        return false;
    }
    *out = f;
    return true;
}

/* A setting line; false when `key` names no setting. */
static bool input_parse_setting(input_parser *p, const char *key, char *value) {
    input_bindings *b = p->bindings;
    if (strcmp(key, "look_speed") == 0) {
        input_parse_float(p, key, value, 0.0f, INPUT_LOOK_SPEED_MAX, &b->look_speed);
    } else if (strcmp(key, "stick_look_speed") == 0) {
        input_parse_float(p, key, value, 0.0f, INPUT_STICK_LOOK_SPEED_MAX, &b->stick_look_speed);
    } else if (strcmp(key, "dead_zone") == 0) {
        input_parse_float(p, key, value, 0.0f, INPUT_DEAD_ZONE_MAX, &b->dead_zone);
    } else if (strcmp(key, "invert_y") == 0) {
        char shown[200];
        input_lower(value);
        if (strcmp(value, "true") == 0) b->invert_y = true;
        else if (strcmp(value, "false") == 0) b->invert_y = false;
        else input_parser_bad(p, "invert_y: expected true or false, not '%s'", input_shown(value, shown));
    } else {
        return false;
    }
    return true;
}

static int input_target_from_name(const char *name) {
    for (int t = 0; t < INPUT_TARGET_COUNT; t++)
        if (strcmp(name, input__target_name(t)) == 0) return t;
    return -1;
}

/* One line without its newline, at most INPUT_BINDINGS_MAX_LINE bytes, no NUL. */
static void input_parse_line(input_parser *p, const char *bytes, size_t size) {
    char buffer[INPUT_BINDINGS_MAX_LINE + 1];
    memcpy(buffer, bytes, size);
    buffer[size] = '\0';
    char *hash = strchr(buffer, '#');
    if (hash) *hash = '\0';
    char *line = input_trim(buffer);
    if (!*line) return;
    char shown[200];
    char *equals = strchr(line, '=');
    if (!equals) {
        input_parser_bad(p, "missing '=' in '%s' (expected 'action = source, ...')", input_shown(line, shown));
        return;
    }
    *equals = '\0';
    char *key = input_trim(line), *value = input_trim(equals + 1);
    input_lower(key);
    if (!*key) {
        input_parser_bad(p, "missing action name before '='");
        return;
    }
    if (input_parse_setting(p, key, value)) return;
    int target = input_target_from_name(key);
    if (target < 0) {
        input_parser_bad(p, "unknown action '%s'", input_shown(key, shown));
        return;
    }
    input_parse_binding(p, target, value);
}

input_bindings *input_bindings_parse(const char *text, size_t size, const char *name, int *bad_lines) {
    input_parser p = { .name = name ? name : "<bindings>", .bindings = input_bindings_default() };
    size_t at = 0;
    while (at < size) {
        p.line++;
        const char *start = text + at;
        const char *newline = memchr(start, '\n', size - at);
        size_t length = newline ? (size_t)(newline - start) : size - at;
        at += length + (newline ? 1 : 0);
        if (length > INPUT_BINDINGS_MAX_LINE) {
            input_parser_bad(&p, "line longer than %d bytes", INPUT_BINDINGS_MAX_LINE);
        } else if (memchr(start, '\0', length)) {
            input_parser_bad(&p, "line contains a NUL byte");
        } else {
            input_parse_line(&p, start, length);
        }
    }
    if (bad_lines) *bad_lines = p.bad_lines;
    return p.bindings;
}

char *input__file_read(const char *path, const char *what, size_t max_bytes, size_t *size, size_t *capacity,
                       core_error *error) {
    *size = *capacity = 0;
    FILE *file = fopen(path, "rb");
    if (!file) {
        core_error_set(error, CORE_ERROR_IO, "cannot open %s %s: %s", what, path, strerror(errno));
        return NULL;
    }
    char *text = NULL;
    bool failed = false;
    for (;;) {
        text = core_grow(text, capacity, *size + 4096, 1);
        size_t got = fread(text + *size, 1, *capacity - *size, file);
        *size += got;
        if (*size > max_bytes) {
            core_error_set(error, CORE_ERROR_RANGE, "cannot load %s %s: larger than %zu bytes", what, path, max_bytes);
            failed = true;
            break;
        }
        if (got == 0) {
            if (ferror(file)) {
                core_error_set(error, CORE_ERROR_IO, "cannot read %s %s: %s", what, path, strerror(errno));
                failed = true;
            }
            break;
        }
    }
    fclose(file);
    if (failed) {
        core_free(text, *capacity);
        *size = *capacity = 0;
        return NULL;
    }
    return text;
}

input_bindings *input_bindings_load(const char *path, int *bad_lines, core_error *error) {
    if (bad_lines) *bad_lines = 0;
    size_t size, capacity;
    char *text = input__file_read(path, "bindings", INPUT_BINDINGS_MAX_FILE, &size, &capacity, error);
    if (!text) return NULL;
    input_bindings *bindings = input_bindings_parse(text, size, path, bad_lines);
    core_free(text, capacity);
    return bindings;
}
