/* fuzz_bindings — libFuzzer target for the bindings parser (engine/input/input_bindings.c) and
 * the action code the parsed bindings drive (engine/input/input_actions.c).
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's sources, runs each 20 s)
 * Seeds: tests/fuzz/corpus/fuzz_bindings/ (the shipped file, one line of every error kind).
 *
 * The input is the text, not NUL-terminated. Besides "no crash, no leak, no read out of bounds"
 * it traps when a property fails: parsing always gives bindings (bad lines are skipped), those
 * bindings are valid (every source fits its action, settings in range), no more lines are bad
 * than there are lines, and whatever the bindings, an input system driven by them keeps move
 * within length 1.
 */
#include "core/core.h"
#include "input/input.h"
#include "input/input_internal.h"

#include <math.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

/* A few frames of events made from the input's bytes, through the bindings just parsed. */
static void fuzz_drive(const input_bindings *bindings, const unsigned char *bytes, size_t size) {
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .bindings = bindings }, NULL);
    if (!in) __builtin_trap();
    for (size_t i = 0; i + 1 < size && i < 64; i += 2) {
        input_feed_key(in, bytes[i] + 256 * (bytes[i + 1] & 1), bytes[i + 1] & 2);
        input_feed_mouse_button(in, bytes[i] & 7, bytes[i + 1] & 4);
        if (bytes[i + 1] & 8) input_feed_mouse_motion(in, (float)(int8_t)bytes[i], (float)(int8_t)bytes[i + 1]);
        if (bytes[i + 1] & 16)
            input_feed_gamepad(in, bytes[i] & 7,
                                  &(input_gamepad_state){ .lx = (float)(int8_t)bytes[i] / 127.0f,
                                                          .ry = (float)(int8_t)bytes[i + 1] / 127.0f,
                                                          .rt = (float)bytes[i] / 255.0f,
                                                          .buttons = (uint32_t)bytes[i + 1] << 8 | bytes[i] });
        if ((i & 15) == 14) {
            if (!input_update(in, 0.016f)) __builtin_trap();
            const input_actions *a = input_actions_get(in);
            if (!(sqrtf(a->move_x * a->move_x + a->move_y * a->move_y) <= 1.0f + 1e-5f)) __builtin_trap();
        }
    }
    input_system_destroy(in);
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    core_log_set_level(CORE_LOG_OFF); /* every bad line is a message otherwise */
    int bad = -1;
    input_bindings *b = input_bindings_parse((const char *)bytes, size, "fuzz", &bad);
    if (!b || bad < 0 || !input__bindings_valid(b)) __builtin_trap();
    size_t lines = size > 0;
    for (size_t i = 0; i + 1 < size; i++) lines += bytes[i] == '\n';
    if ((size_t)bad > lines) __builtin_trap();
    fuzz_drive(b, bytes, size);
    input_bindings_destroy(b);
    return 0;
}
