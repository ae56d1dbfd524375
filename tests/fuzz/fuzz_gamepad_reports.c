/* fuzz_gamepad_reports — libFuzzer target for the known pads' report decoders (DualShock 4,
 * DualSense, Switch Pro: engine/input/input_decode.c) and the radial dead zone.
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's sources, runs each 20 s)
 * Seeds: tests/fuzz/corpus/fuzz_gamepad_reports/ (USB and Bluetooth reports of each pad).
 *
 * Input: byte 0 picks the pad (its low bits) and whether 78-byte Sony Bluetooth reports get a
 * correct CRC written into them (bit 7), so the fuzzer reaches both sides of the CRC rule; byte 1
 * is a dead-zone radius (byte / 255); then reports as hidreplay reads them: 2 bytes little-endian
 * length (clamped to what is left), the report.
 *
 * Traps when: a decode succeeds with axes outside [-1, 1], triggers outside [0, 1] or stray
 * button bits; a failed decode changes the state or has no reason; a dead zone of radius > 0
 * gives a stick longer than 1 (plus rounding), a NaN, or flips a component's sign, or radius 0
 * changes anything; the statistics miscount.
 */
#include "core/core.h"
#include "input/input.h"
#include "fuzz_gamepad.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const struct { uint16_t vendor_id, product_id; } fuzz_pads[] = {
    { 0x054c, 0x05c4 }, { 0x054c, 0x09cc }, { 0x054c, 0x0ba0 }, /* DualShock 4 */
    { 0x054c, 0x0ce6 }, { 0x054c, 0x0df2 },                     /* DualSense */
    { 0x057e, 0x2009 },                                         /* Switch Pro */
};

static uint32_t fuzz_crc32(uint32_t crc, const uint8_t *bytes, size_t size) {
    crc = ~crc;
    for (size_t i = 0; i < size; i++) {
        crc ^= bytes[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1)));
    }
    return ~crc;
}

static void fuzz_seal(uint8_t report[78]) {
    uint8_t seed = 0xa1;
    uint32_t crc = fuzz_crc32(fuzz_crc32(0, &seed, 1), report, 74);
    for (int i = 0; i < 4; i++) report[74 + i] = (uint8_t)(crc >> (8 * i));
}

static void fuzz_check_dead_zone(const input_gamepad_state *raw, float radius) {
    input_gamepad_state s = *raw;
    input_apply_dead_zone(&s, radius);
    if (radius == 0.0f) { /* no dead zone: raw values, corners (length √2) included */
        if (memcmp(&s, raw, sizeof s) != 0) __builtin_trap();
        return;
    }
    const float in[4] = { raw->lx, raw->ly, raw->rx, raw->ry }, out[4] = { s.lx, s.ly, s.rx, s.ry };
    for (int stick = 0; stick < 2; stick++) {
        float x = out[2 * stick], y = out[2 * stick + 1];
        if (isnan(x) || isnan(y) || x * x + y * y > 1.0f + 1e-5f) __builtin_trap();
        for (int k = 0; k < 2; k++)
            if (out[2 * stick + k] * in[2 * stick + k] < 0) __builtin_trap(); /* direction kept */
    }
    if (s.lt != raw->lt || s.rt != raw->rt || s.buttons != raw->buttons) __builtin_trap();
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    if (size < 2) return 0;
    uint8_t pick = bytes[0];
    float radius = (float)bytes[1] / 255.0f;
    bytes += 2, size -= 2;
    const size_t pad = (pick & 0x7f) % (sizeof fuzz_pads / sizeof fuzz_pads[0]);
    bool seal = pick & 0x80;
    input_decoder *decoder = input_decoder_create(&(input_decoder_desc){ .vendor_id = fuzz_pads[pad].vendor_id,
                                                                         .product_id = fuzz_pads[pad].product_id },
                                                  NULL);
    if (!decoder) __builtin_trap();
    input_gamepad_state state = { .ry = -0.25f, .buttons = 1u << INPUT_BUTTON_TOUCHPAD };
    uint64_t calls = 0;
    while (size >= 2) {
        size_t length = (size_t)bytes[0] | (size_t)bytes[1] << 8;
        bytes += 2, size -= 2;
        if (length > size) length = size;
        /* Each report in a heap block of exactly its size, so ASan sees any read past it (a
         * slice of the fuzzer's buffer would have the next report's bytes behind it). */
        uint8_t *report = malloc(length ? length : 1);
        memcpy(report, bytes, length);
        if (seal && length == 78) fuzz_seal(report);
        input_decode_result result = fuzz_decode_checked(decoder, report, length, &state);
        free(report);
        calls++;
        if (result == INPUT_DECODE_OK) fuzz_check_dead_zone(&state, radius);
        bytes += length, size -= length;
    }
    fuzz_check_stats(decoder, calls);
    input_decoder_destroy(decoder);
    return 0;
}
