/* fuzz_gamepad_mappings — libFuzzer target for the SDL game controller mapping parser
 * (engine/input/input_mappings.c) and the mapping of a raw joystick through what it parsed.
 *
 *   tests/fuzz/run.sh 20 fuzz_gamepad_mappings
 * Seeds: tests/fuzz/corpus/fuzz_gamepad_mappings/ (good lines of every element kind, bad ones).
 *
 * The input is a mappings file's text, not NUL-terminated. Besides "no crash, no leak, no read out
 * of bounds" it traps when a property fails: no more lines are bad than there are lines, every kept
 * mapping has a 32-hex-digit GUID, a name and elements in range, GLFW's text holds one line per
 * kept line, and a raw joystick made from the input's bytes (short arrays included) maps to sticks
 * in [−1, 1] and triggers in [0, 1].
 */
#include "core/core.h"
#include "input/input_internal.h"

#include <math.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

static bool fuzz_in_range(float v, float lo, float hi) { return v >= lo && v <= hi; }

static void fuzz_apply(const input_sdl_mapping *m, const unsigned char *bytes, size_t size) {
    float axes[8];
    uint8_t buttons[16], hats[2];
    for (int i = 0; i < 8; i++) axes[i] = size ? (float)(int8_t)bytes[(size_t)i % size] / 127.0f : 0.0f;
    for (int i = 0; i < 16; i++) buttons[i] = size ? bytes[(size_t)(i * 3) % size] & 1 : 0;
    for (int i = 0; i < 2; i++) hats[i] = size ? bytes[(size_t)(i * 5) % size] & 15 : 0;
    int counts = size ? bytes[0] : 0;
    input_sdl_joystick j = { .axes = axes, .axis_count = counts & 7, .buttons = buttons,
                             .button_count = (counts >> 3) & 15, .hats = hats, .hat_count = (counts >> 7) & 1 };
    input_sdl_pad pad;
    input__sdl_mapping_apply(m, &j, &pad);
    input_gamepad_state s;
    input__sdl_pad_to_state(&pad, &s);
    if (!fuzz_in_range(s.lx, -1, 1) || !fuzz_in_range(s.ly, -1, 1) || !fuzz_in_range(s.rx, -1, 1) ||
        !fuzz_in_range(s.ry, -1, 1) || !fuzz_in_range(s.lt, 0, 1) || !fuzz_in_range(s.rt, 0, 1))
        __builtin_trap();
    if (s.buttons >> INPUT_BUTTON_COUNT) __builtin_trap();
}

static void fuzz_check(const input_sdl_mapping *m) {
    if (strlen(m->guid) != 32 || !m->name[0] || m->binding_count == 0) __builtin_trap();
    for (int i = 0; i < m->binding_count; i++) {
        const input_sdl_binding *b = &m->bindings[i];
        if (b->output >= INPUT_SDL_OUTPUT_COUNT) __builtin_trap();
        if (b->kind != 'a' && b->kind != 'b' && b->kind != 'h') __builtin_trap();
        if (b->kind == 'h' && b->hat_mask != 1 && b->hat_mask != 2 && b->hat_mask != 4 && b->hat_mask != 8)
            __builtin_trap();
    }
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    core_log_set_level(CORE_LOG_OFF); /* every bad line is a message otherwise */
    input_sdl_mappings ms = { 0 };
    int bad = -1;
    input__sdl_mappings_parse(&ms, (const char *)bytes, size, "fuzz", &bad);
    size_t lines = size > 0;
    for (size_t i = 0; i + 1 < size; i++) lines += bytes[i] == '\n';
    if (bad < 0 || (size_t)bad > lines || ms.count > lines) __builtin_trap();
    size_t text_lines = 0;
    for (size_t i = 0; i < ms.text_size; i++) text_lines += ms.text[i] == '\n';
    if (ms.count > text_lines || (ms.text && strlen(ms.text) != ms.text_size)) __builtin_trap();
    for (size_t i = 0; i < ms.count; i++) {
        fuzz_check(&ms.items[i]);
        fuzz_apply(&ms.items[i], bytes, size);
    }
    /* One line straight to the line parser too, whatever bytes it holds. */
    input_sdl_mapping m;
    core_error error = { 0 };
    if (input__sdl_mapping_parse((const char *)bytes, size, &m, &error)) fuzz_check(&m);
    else if (error.code == CORE_ERROR_NONE || error.message[0] == '\0') __builtin_trap();
    input__sdl_mappings_free(&ms);
    return 0;
}
