/* fuzz_gamepad.h — the checks both gamepad fuzz targets make on every decode. Header-only: each
 * fuzz target is built alone from its one .c file (tests/fuzz/run.sh). */
#ifndef FUZZ_GAMEPAD_H
#define FUZZ_GAMEPAD_H

#include "input/input.h"

#include <stdbool.h>
#include <string.h>

static bool fuzz_in_range(float value, float lo, float hi) { return value >= lo && value <= hi; }

/* Axes in [-1, 1], triggers in [0, 1], no button bits past the last button. */
static void fuzz_check_state(const input_gamepad_state *s) {
    if (!fuzz_in_range(s->lx, -1, 1) || !fuzz_in_range(s->ly, -1, 1) || !fuzz_in_range(s->rx, -1, 1) ||
        !fuzz_in_range(s->ry, -1, 1) || !fuzz_in_range(s->lt, 0, 1) || !fuzz_in_range(s->rt, 0, 1))
        __builtin_trap();
    if (s->buttons >> INPUT_BUTTON_COUNT) __builtin_trap();
}

/* Decodes `report` (a heap block of exactly `length` bytes, so ASan sees any read past it): a
 * success gives a sane state, a failure leaves the state as it was and can say why. */
static input_decode_result fuzz_decode_checked(input_decoder *decoder, const uint8_t *report, size_t length,
                                               input_gamepad_state *state) {
    input_gamepad_state before = *state;
    core_error why = { 0 };
    input_decode_result result = input_decoder_decode(decoder, report, length, state, &why);
    if (result == INPUT_DECODE_OK) {
        fuzz_check_state(state);
        if (why.code != CORE_ERROR_NONE) __builtin_trap();
    } else {
        if (memcmp(&before, state, sizeof *state) != 0) __builtin_trap();
        if (why.code == CORE_ERROR_NONE || !why.message[0] || !input_decode_result_name(result)[0]) __builtin_trap();
    }
    return result;
}

/* Every decode counted exactly once. */
static void fuzz_check_stats(const input_decoder *decoder, uint64_t calls) {
    input_decoder_stats_info stats = input_decoder_stats(decoder);
    if (stats.decoded + stats.short_reports + stats.oversized + stats.unknown_id + stats.malformed != calls)
        __builtin_trap();
}

#endif
