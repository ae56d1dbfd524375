/* input_mappings.c — SDL game controller mappings: the line parser, the mapping of a raw joystick
 * through one, and the mappings file.
 *
 * GLFW reads pads it has no hidraw decoder for through these mappings (its own built-in copy of
 * SDL's database, plus the lines of `--gamepad-mappings FILE`). GLFW's glfwUpdateGamepadMappings
 * never says which line is wrong: GLFW 3.3.8 (tried under Xvfb) skips a line with a bad GUID with
 * a bare "Invalid value for parameter" and still returns GLFW_TRUE, and quietly drops or misreads
 * an element it cannot parse (leftshoulderr:b4, a:x0, dpup:h0.3, a:b300), so a typo silently
 * unmaps a button. So every line is checked here first: a bad one is reported with its file and
 * line number and left out, and GLFW gets only lines that mean what they say.
 *
 * Format (SDL's gamecontrollerdb.txt): GUID,name,output:input,...  where
 *   output  a b x y back guide start leftstick rightstick leftshoulder rightshoulder dpup dpdown
 *           dpleft dpright misc1 touchpad paddle1-4 (buttons), leftx lefty rightx righty
 *           lefttrigger righttrigger (axes); an axis may take a half: "+leftx", "-leftx"
 *   input   bN (button), hN.M (hat N, bit M: 1 up 2 right 4 down 8 left), aN (axis), with an
 *           optional half "+aN"/"-aN" and an optional "~" after it (inverted)
 * and the keys platform (which OS the line is for), crc, hint, sdk>=, sdk<= and face, which
 * choose lines rather than map elements.
 *
 * Values, as SDL and GLFW read them: an input becomes t in [0, 1] (a whole axis (v + 1)/2, "+aN"
 * v, "-aN" −v, clamped; a button or hat bit 0 or 1; "~" flips v first). A button output is pressed
 * past t > 0.5. An axis output is 2t − 1 for the whole axis, t for "+leftx" and −t for "-leftx";
 * halves of one axis add up.
 */
#include "input/input_internal.h"

#include "core/core.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

static const char *const input_sdl_output_names[INPUT_SDL_OUTPUT_COUNT] = {
    "a", "b", "x", "y", "leftshoulder", "rightshoulder", "back", "start", "guide", "leftstick", "rightstick",
    "dpup", "dpright", "dpdown", "dpleft", "misc1", "touchpad", "paddle1", "paddle2", "paddle3", "paddle4",
    "leftx", "lefty", "rightx", "righty", "lefttrigger", "righttrigger",
};

/* Keys that select lines (which OS, SDK, …) rather than map an element. */
static const char *const input_sdl_selectors[] = { "platform", "crc", "hint", "sdk>=", "sdk<=", "face" };

enum { INPUT_SDL_MAX_BUTTON = 255, INPUT_SDL_MAX_AXIS = 63, INPUT_SDL_MAX_HAT = 15 };

/* ---- one line --------------------------------------------------------------------------------- */

/* [at, end) of a field, shown in a message: at most 40 bytes, control bytes as '?'. */
static const char *input_sdl_shown(const char *at, size_t length, char *out, size_t capacity) {
    size_t n = 0;
    for (; n < length && n < 40 && n + 1 < capacity; n++) out[n] = (at[n] >= 0x20 && at[n] < 0x7f) ? at[n] : '?';
    out[n] = '\0';
    return out;
}

static int input_sdl_output_from(const char *name, size_t length) {
    for (int i = 0; i < INPUT_SDL_OUTPUT_COUNT; i++)
        if (strlen(input_sdl_output_names[i]) == length && memcmp(input_sdl_output_names[i], name, length) == 0) return i;
    return -1;
}

/* A decimal number of 1 to 3 digits in [at, end), at most `max`; -1 when it is not one. */
static int input_sdl_number(const char *at, const char *end, int max) {
    if (at >= end || end - at > 3) return -1;
    int value = 0;
    for (; at < end; at++) {
        if (*at < '0' || *at > '9') return -1;
        value = value * 10 + (*at - '0');
    }
    return value <= max ? value : -1;
}

/* "b3", "h0.4", "a2", "+a2", "-a2", "a2~" into *b; false when it is none of them. */
static bool input_sdl_parse_input(const char *at, const char *end, input_sdl_binding *b) {
    if (at < end && (*at == '+' || *at == '-')) b->input_half = *at++ == '+' ? 1 : -1;
    if (end > at && end[-1] == '~') {
        b->invert = true;
        end--;
    }
    if (at >= end) return false;
    b->kind = (uint8_t)*at++;
    if (b->kind == 'b' || b->kind == 'a') {
        if ((b->kind == 'b') && (b->input_half || b->invert)) return false; /* halves are for axes */
        int index = input_sdl_number(at, end, b->kind == 'b' ? INPUT_SDL_MAX_BUTTON : INPUT_SDL_MAX_AXIS);
        b->index = (uint8_t)index;
        return index >= 0;
    }
    if (b->kind != 'h' || b->input_half || b->invert) return false;
    const char *dot = memchr(at, '.', (size_t)(end - at));
    if (!dot) return false;
    int hat = input_sdl_number(at, dot, INPUT_SDL_MAX_HAT), mask = input_sdl_number(dot + 1, end, 8);
    if (hat < 0 || (mask != 1 && mask != 2 && mask != 4 && mask != 8)) return false;
    b->index = (uint8_t)hat;
    b->hat_mask = (uint8_t)mask;
    return true;
}

/* One "key:value" field; false with the reason in `error`. */
static bool input_sdl_parse_field(input_sdl_mapping *m, const char *at, const char *end, core_error *error) {
    char shown[48];
    const char *colon = memchr(at, ':', (size_t)(end - at));
    if (!colon) {
        core_error_set(error, CORE_ERROR_FORMAT, "'%s' is not output:input", input_sdl_shown(at, (size_t)(end - at), shown, sizeof shown));
        return false;
    }
    size_t key_length = (size_t)(colon - at);
    for (size_t i = 0; i < sizeof input_sdl_selectors / sizeof *input_sdl_selectors; i++)
        if (strlen(input_sdl_selectors[i]) == key_length && memcmp(input_sdl_selectors[i], at, key_length) == 0) {
            if (i == 0) m->other_platform = !((size_t)(end - colon - 1) == 5 && memcmp(colon + 1, "Linux", 5) == 0);
            return true;
        }
    input_sdl_binding b = { 0 };
    if (at < colon && (*at == '+' || *at == '-')) b.output_half = *at++ == '+' ? 1 : -1;
    int output = input_sdl_output_from(at, (size_t)(colon - at));
    if (output < 0 || (b.output_half && output < INPUT_SDL_BUTTON_COUNT)) {
        core_error_set(error, CORE_ERROR_FORMAT, "unknown output '%s'", input_sdl_shown(at - (b.output_half != 0), key_length, shown, sizeof shown));
        return false;
    }
    b.output = (uint8_t)output;
    if (!input_sdl_parse_input(colon + 1, end, &b)) {
        core_error_set(error, CORE_ERROR_FORMAT, "%s: bad input '%s' (expected bN, hN.M or aN)", input_sdl_output_names[output],
                 input_sdl_shown(colon + 1, (size_t)(end - colon - 1), shown, sizeof shown));
        return false;
    }
    for (int i = 0; i < m->binding_count; i++)
        if (m->bindings[i].output == b.output && (m->bindings[i].output_half == b.output_half || !b.output_half ||
                                                  !m->bindings[i].output_half)) {
            core_error_set(error, CORE_ERROR_FORMAT, "%s mapped twice", input_sdl_output_names[output]);
            return false;
        }
    if (m->binding_count == INPUT_SDL_MAX_BINDINGS) {
        core_error_set(error, CORE_ERROR_RANGE, "more than %d elements", INPUT_SDL_MAX_BINDINGS);
        return false;
    }
    m->bindings[m->binding_count++] = b;
    return true;
}

static bool input_sdl_parse_guid(input_sdl_mapping *m, const char *at, const char *end, core_error *error) {
    char shown[48];
    bool ok = end - at == 32;
    for (int i = 0; ok && i < 32; i++) {
        char c = at[i];
        if (c >= 'A' && c <= 'F') c = (char)(c - 'A' + 'a');
        ok = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
        m->guid[i] = c;
    }
    m->guid[32] = '\0';
    if (!ok) core_error_set(error, CORE_ERROR_FORMAT, "GUID '%s' is not 32 hex digits", input_sdl_shown(at, (size_t)(end - at), shown, sizeof shown));
    return ok;
}

bool input__sdl_mapping_parse(const char *line, size_t length, input_sdl_mapping *m, core_error *error) {
    *m = (input_sdl_mapping){ 0 };
    const char *end = line + length, *comma = memchr(line, ',', length);
    if (!comma) {
        core_error_set(error, CORE_ERROR_FORMAT, "expected GUID,name,output:input,...");
        return false;
    }
    if (!input_sdl_parse_guid(m, line, comma, error)) return false;
    const char *name = comma + 1, *name_end = memchr(name, ',', (size_t)(end - name));
    if (!name_end) name_end = end;
    if (name_end == name || (size_t)(name_end - name) >= sizeof m->name) {
        core_error_set(error, name_end == name ? CORE_ERROR_FORMAT : CORE_ERROR_RANGE, "the name must be 1 to %zu bytes",
                       sizeof m->name - 1);
        return false;
    }
    for (const char *c = name; c < name_end; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f) {
            core_error_set(error, CORE_ERROR_FORMAT, "control byte in the name");
            return false;
        }
    memcpy(m->name, name, (size_t)(name_end - name));
    for (const char *at = name_end; at < end;) {
        at++; /* the comma */
        const char *field_end = memchr(at, ',', (size_t)(end - at));
        if (!field_end) field_end = end;
        /* SDL's lines end with a comma; an empty last field is fine, an empty one inside is not */
        if (field_end == at) {
            if (field_end == end) break;
            core_error_set(error, CORE_ERROR_FORMAT, "empty field");
            return false;
        }
        if (!input_sdl_parse_field(m, at, field_end, error)) return false;
        at = field_end;
    }
    if (m->binding_count == 0) {
        core_error_set(error, CORE_ERROR_FORMAT, "maps no button or axis");
        return false;
    }
    return true;
}

/* ---- a joystick through a mapping ------------------------------------------------------------- */

/* The input's value as t in [0, 1]. */
static float input_sdl_input(const input_sdl_binding *b, const input_sdl_joystick *j) {
    if (b->kind == 'b') return b->index < j->button_count && j->buttons && j->buttons[b->index] ? 1.0f : 0.0f;
    if (b->kind == 'h') return b->index < j->hat_count && j->hats && (j->hats[b->index] & b->hat_mask) ? 1.0f : 0.0f;
    float v = b->index < j->axis_count && j->axes && isfinite(j->axes[b->index]) ? j->axes[b->index] : 0.0f;
    if (b->invert) v = -v;
    float t = b->input_half > 0 ? v : b->input_half < 0 ? -v : 0.5f * (v + 1.0f);
    return fminf(fmaxf(t, 0.0f), 1.0f);
}

void input__sdl_mapping_apply(const input_sdl_mapping *m, const input_sdl_joystick *j, input_sdl_pad *pad) {
    *pad = (input_sdl_pad){ 0 };
    /* An unmapped trigger rests released (−1), like an unpressed one. */
    pad->axes[INPUT_SDL_LEFTTRIGGER - INPUT_SDL_BUTTON_COUNT] = -1.0f;
    pad->axes[INPUT_SDL_RIGHTTRIGGER - INPUT_SDL_BUTTON_COUNT] = -1.0f;
    for (int i = 0; i < m->binding_count; i++) {
        const input_sdl_binding *b = &m->bindings[i];
        float t = input_sdl_input(b, j);
        if (b->output < INPUT_SDL_BUTTON_COUNT) {
            pad->buttons[b->output] = pad->buttons[b->output] || t > 0.5f;
            continue;
        }
        float *axis = &pad->axes[b->output - INPUT_SDL_BUTTON_COUNT];
        /* A trigger has one direction: "+lefttrigger" is lefttrigger. */
        if (b->output_half == 0 || b->output >= INPUT_SDL_LEFTTRIGGER) *axis = 2.0f * t - 1.0f;
        else *axis = fminf(fmaxf(*axis + (float)b->output_half * t, -1.0f), 1.0f);
    }
}

void input__sdl_pad_to_state(const input_sdl_pad *pad, input_gamepad_state *state) {
    static const uint8_t button_of[INPUT_SDL_BUTTON_COUNT] = {
        [INPUT_SDL_A] = INPUT_BUTTON_SOUTH, [INPUT_SDL_B] = INPUT_BUTTON_EAST, [INPUT_SDL_X] = INPUT_BUTTON_WEST,
        [INPUT_SDL_Y] = INPUT_BUTTON_NORTH, [INPUT_SDL_LEFTSHOULDER] = INPUT_BUTTON_LB,
        [INPUT_SDL_RIGHTSHOULDER] = INPUT_BUTTON_RB, [INPUT_SDL_BACK] = INPUT_BUTTON_BACK,
        [INPUT_SDL_START] = INPUT_BUTTON_START, [INPUT_SDL_GUIDE] = INPUT_BUTTON_GUIDE,
        [INPUT_SDL_LEFTSTICK] = INPUT_BUTTON_LS, [INPUT_SDL_RIGHTSTICK] = INPUT_BUTTON_RS,
        [INPUT_SDL_DPUP] = INPUT_BUTTON_DPAD_UP, [INPUT_SDL_DPRIGHT] = INPUT_BUTTON_DPAD_RIGHT,
        [INPUT_SDL_DPDOWN] = INPUT_BUTTON_DPAD_DOWN, [INPUT_SDL_DPLEFT] = INPUT_BUTTON_DPAD_LEFT,
        [INPUT_SDL_MISC1] = INPUT_BUTTON_MISC, [INPUT_SDL_TOUCHPAD] = INPUT_BUTTON_TOUCHPAD,
        /* paddles: we have no button for them */
        [INPUT_SDL_PADDLE1] = INPUT_BUTTON_COUNT, [INPUT_SDL_PADDLE2] = INPUT_BUTTON_COUNT,
        [INPUT_SDL_PADDLE3] = INPUT_BUTTON_COUNT, [INPUT_SDL_PADDLE4] = INPUT_BUTTON_COUNT,
    };
    *state = (input_gamepad_state){ 0 };
    for (int i = 0; i < INPUT_SDL_BUTTON_COUNT; i++)
        if (pad->buttons[i] && button_of[i] < INPUT_BUTTON_COUNT) state->buttons |= 1u << button_of[i];
    float axis[INPUT_SDL_AXIS_COUNT];
    for (int i = 0; i < INPUT_SDL_AXIS_COUNT; i++)
        axis[i] = isfinite(pad->axes[i]) ? fminf(fmaxf(pad->axes[i], -1.0f), 1.0f) : 0.0f;
    state->lx = axis[0], state->ly = axis[1], state->rx = axis[2], state->ry = axis[3];
    state->lt = 0.5f * (axis[4] + 1.0f), state->rt = 0.5f * (axis[5] + 1.0f);
}

/* ---- GUIDs ------------------------------------------------------------------------------------ */

static int input_hex(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* The little-endian 16-bit word at hex digits [4 * word, 4 * word + 4). */
static int input_guid_word(const char *guid, int word) {
    int d[4];
    for (int i = 0; i < 4; i++)
        if ((d[i] = input_hex(guid[4 * word + i])) < 0) return -1;
    return (d[2] << 12) | (d[3] << 8) | (d[0] << 4) | d[1];
}

bool input__guid_ids(const char *guid, uint16_t *vendor_id, uint16_t *product_id) {
    if (!guid || strlen(guid) != 32) return false;
    int words[8];
    for (int i = 0; i < 8; i++)
        if ((words[i] = input_guid_word(guid, i)) < 0) return false;
    /* Words 1, 3, 5 and 7 are zero in the id form; in the name form they hold the name's bytes. */
    if (words[1] || words[3] || words[5] || words[7] || !words[2] || !words[4]) return false;
    *vendor_id = (uint16_t)words[2];
    *product_id = (uint16_t)words[4];
    return true;
}

/* ---- a file of them --------------------------------------------------------------------------- */

static void input_sdl_keep(input_sdl_mappings *ms, const input_sdl_mapping *m, const char *line, size_t length) {
    /* A later line for the same GUID replaces an earlier one, as in GLFW. */
    input_sdl_mapping *slot = (input_sdl_mapping *)input__sdl_mappings_find(ms, m->guid);
    if (!slot) {
        ms->items = core_grow(ms->items, &ms->capacity, ms->count + 1, sizeof *ms->items);
        slot = &ms->items[ms->count++];
    }
    *slot = *m;
    ms->text = core_grow(ms->text, &ms->text_capacity, ms->text_size + length + 2, 1);
    memcpy(ms->text + ms->text_size, line, length);
    ms->text_size += length;
    ms->text[ms->text_size++] = '\n';
    ms->text[ms->text_size] = '\0';
}

void input__sdl_mappings_parse(input_sdl_mappings *ms, const char *text, size_t size, const char *name, int *bad_lines) {
    int bad = 0, line_number = 0;
    name = name ? name : "<mappings>";
    input_sdl_mapping *m = core_alloc(sizeof *m);
    for (size_t at = 0; at < size;) {
        line_number++;
        const char *line = text + at, *newline = memchr(line, '\n', size - at);
        size_t length = newline ? (size_t)(newline - line) : size - at;
        at += length + (newline != NULL);
        if (length && line[length - 1] == '\r') length--;
        while (length && (*line == ' ' || *line == '\t')) line++, length--;
        while (length && (line[length - 1] == ' ' || line[length - 1] == '\t')) length--;
        if (length == 0 || *line == '#') continue;
        core_error error = { 0 };
        if (length > INPUT_SDL_MAX_LINE) core_error_set(&error, CORE_ERROR_RANGE, "line longer than %d bytes", INPUT_SDL_MAX_LINE);
        else if (memchr(line, '\0', length)) core_error_set(&error, CORE_ERROR_FORMAT, "line contains a NUL byte");
        else if (input__sdl_mapping_parse(line, length, m, &error)) {
            if (!m->other_platform) input_sdl_keep(ms, m, line, length);
            continue;
        }
        core_warn("input", "%s:%d: %s (line skipped)", name, line_number, error.message);
        bad++;
    }
    core_free(m, sizeof *m);
    if (bad_lines) *bad_lines = bad;
}

bool input__sdl_mappings_load(input_sdl_mappings *ms, const char *path, int *bad_lines, core_error *error) {
    if (bad_lines) *bad_lines = 0;
    size_t size, capacity;
    char *text = input__file_read(path, "gamepad mappings", INPUT_SDL_MAX_FILE, &size, &capacity, error);
    if (!text) return false;
    input__sdl_mappings_parse(ms, text, size, path, bad_lines);
    core_free(text, capacity);
    return true;
}

void input__sdl_mappings_free(input_sdl_mappings *ms) {
    if (ms->items) core_free(ms->items, ms->capacity * sizeof *ms->items);
    if (ms->text) core_free(ms->text, ms->text_capacity);
    *ms = (input_sdl_mappings){ 0 };
}

const input_sdl_mapping *input__sdl_mappings_find(const input_sdl_mappings *ms, const char *guid) {
    if (!guid) return NULL;
    for (size_t i = 0; i < ms->count; i++)
        if (strcasecmp(ms->items[i].guid, guid) == 0) return &ms->items[i];
    return NULL;
}
