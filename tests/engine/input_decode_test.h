/* input_decode_test.h — what the decoder tests (test_input_decode.c, test_hid_descriptor.c) share:
 * decode and insist on success, or on a given failure that leaves the state untouched. */
#ifndef INPUT_DECODE_TEST_H
#define INPUT_DECODE_TEST_H

#include "test.h"

#include "input/input.h"

#include <string.h>

#define BIT(button) (1u << (button))
#define EPS 1e-5f

static input_gamepad_state decode_ok(input_decoder *d, const uint8_t *report, size_t size) {
    input_gamepad_state state = { 0 };
    core_error error = { 0 };
    input_decode_result result = input_decoder_decode(d, report, size, &state, &error);
    cr_assert_eq(result, INPUT_DECODE_OK, "decode: %s", error.message);
    cr_expect_eq(error.code, CORE_ERROR_NONE, "a decoded report set the error");
    return state;
}

/* The error code each rejection gives (input.h): a short report is truncated, a long one past
 * the device's largest, an unknown ID or impossible content malformed. */
static core_error_code decode_error_code(input_decode_result result) {
    switch (result) {
    case INPUT_DECODE_OK: return CORE_ERROR_NONE;
    case INPUT_DECODE_SHORT: return CORE_ERROR_CORRUPT;
    case INPUT_DECODE_OVERSIZED: return CORE_ERROR_RANGE;
    case INPUT_DECODE_UNKNOWN_ID: return CORE_ERROR_FORMAT;
    case INPUT_DECODE_MALFORMED: return CORE_ERROR_FORMAT;
    }
    return CORE_ERROR_CODE_COUNT;
}

/* The error of the last expect_rejected, for tests that check its numbers. */
static core_error last_rejection;

/* The hat's values and the d-pad buttons they mean: 0 up, clockwise in eighths, 8+ centred. */
static const uint32_t hat_dpad[16] = {
    BIT(INPUT_BUTTON_DPAD_UP),
    BIT(INPUT_BUTTON_DPAD_UP) | BIT(INPUT_BUTTON_DPAD_RIGHT),
    BIT(INPUT_BUTTON_DPAD_RIGHT),
    BIT(INPUT_BUTTON_DPAD_DOWN) | BIT(INPUT_BUTTON_DPAD_RIGHT),
    BIT(INPUT_BUTTON_DPAD_DOWN),
    BIT(INPUT_BUTTON_DPAD_DOWN) | BIT(INPUT_BUTTON_DPAD_LEFT),
    BIT(INPUT_BUTTON_DPAD_LEFT),
    BIT(INPUT_BUTTON_DPAD_UP) | BIT(INPUT_BUTTON_DPAD_LEFT),
    0, 0, 0, 0, 0, 0, 0, 0,
};

/* A state no decoder would produce, to see that a rejected report changes nothing. */
static const input_gamepad_state sentinel = { .lx = 0.25f, .ly = -0.5f, .rx = 0.125f, .ry = -0.75f,
                                              .lt = 0.5f, .rt = 0.0625f, .buttons = 0x15555u };

static void expect_rejected(input_decoder *d, const uint8_t *report, size_t size, input_decode_result want) {
    input_gamepad_state state = sentinel;
    core_error error = { 0 };
    input_decode_result got = input_decoder_decode(d, report, size, &state, &error);
    cr_expect_eq(got, want, "size %zu: got %s", size, input_decode_result_name(got));
    cr_expect_eq(error.code, decode_error_code(want), "size %zu: code %s (%s)", size, core_error_code_name(error.code),
                 error.message);
    last_rejection = error;
    cr_expect(memcmp(&state, &sentinel, sizeof state) == 0, "size %zu: state changed on a rejected report", size);
}

#endif
