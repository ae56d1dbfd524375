/* bench_input.c — input rows: what decoding one gamepad HID report costs, per pad.
 *
 *   input.decode.dualshock4            USB report 0x01 (64 bytes)
 *   input.decode.dualsense             USB report 0x01 (64 bytes)
 *   input.decode.switch_pro            report 0x30 (64 bytes, USB)
 *   input.decode.generic               a typical cheap pad through its report descriptor: 4 × 8-bit
 *                                      axes, a hat, 12 buttons (6-byte reports, no report ID)
 *   input.decode.dualshock4.bluetooth  report 0x11 (78 bytes), CRC-32 checked
 *   input.decode.dualsense.bluetooth   report 0x31 (78 bytes), CRC-32 checked
 *
 * A sample decodes BENCH_PASSES passes over BENCH_REPORTS different reports (sticks, triggers,
 * buttons and hat from a hash of the index, so no two neighbours are alike) and returns ns per
 * report. The target (issue) is ≤ 1 µs; the decoders aim at tens of nanoseconds.
 */
#include "bench.h"

#include "core/core.h"
#include "input/input.h"

#include <string.h>

enum { BENCH_REPORTS = 1024, BENCH_PASSES = 256, BENCH_RUNS = 9, BENCH_MAX_REPORT = 80 };

typedef struct input_bench {
    input_decoder *decoder;
    size_t report_size;
    uint8_t reports[BENCH_REPORTS][BENCH_MAX_REPORT];
} input_bench;

/* A typical generic pad (the one tests/engine/test_hid_descriptor.c spells out item by item). */
static const uint8_t bench_generic_descriptor[] = {
    0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
    0x09, 0x30, 0x09, 0x31, 0x09, 0x32, 0x09, 0x35, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x04, 0x81, 0x02,
    0x09, 0x39, 0x15, 0x00, 0x25, 0x07, 0x35, 0x00, 0x46, 0x3b, 0x01, 0x65, 0x14, 0x75, 0x04, 0x95, 0x01, 0x81, 0x42,
    0x65, 0x00, 0x05, 0x09, 0x19, 0x01, 0x29, 0x0c, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x0c, 0x81, 0x02,
    0xc0,
};

static uint32_t bench_crc32(uint32_t crc, const uint8_t *bytes, size_t size) {
    crc = ~crc;
    for (size_t i = 0; i < size; i++) {
        crc ^= bytes[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1)));
    }
    return ~crc;
}

/* The Sony Bluetooth CRC: over 0xa1 then bytes 0-73, little-endian at 74. */
static void bench_seal(uint8_t *report) {
    uint8_t seed = 0xa1;
    uint32_t crc = bench_crc32(bench_crc32(0, &seed, 1), report, 74);
    for (int i = 0; i < 4; i++) report[74 + i] = (uint8_t)(crc >> (8 * i));
}

typedef enum bench_layout {
    BENCH_DS4_USB, BENCH_DS4_BT, BENCH_DS_USB, BENCH_DS_BT, BENCH_SWITCH, BENCH_GENERIC,
} bench_layout;

/* Fills report i of the given layout from a hash of i. */
static void bench_fill(uint8_t *r, bench_layout layout, uint32_t i) {
    uint64_t h = core_hash_u64(i + 1);
    uint8_t b[8];
    for (int k = 0; k < 8; k++) b[k] = (uint8_t)(h >> (8 * k));
    uint8_t hat = (uint8_t)(b[4] % 9);
    switch (layout) {
    case BENCH_DS4_USB: case BENCH_DS4_BT: {
        int at = layout == BENCH_DS4_USB ? 1 : 3;
        r[0] = layout == BENCH_DS4_USB ? 0x01 : 0x11;
        if (layout == BENCH_DS4_BT) r[1] = 0xc0;
        memcpy(r + at, b, 4);
        r[at + 4] = (uint8_t)(hat | (b[5] & 0xf0));
        r[at + 5] = b[6];
        r[at + 6] = (uint8_t)(b[7] & 0x03);
        r[at + 7] = b[5];
        r[at + 8] = b[7];
        if (layout == BENCH_DS4_BT) bench_seal(r);
        break;
    }
    case BENCH_DS_USB: case BENCH_DS_BT: {
        int at = layout == BENCH_DS_USB ? 1 : 2;
        r[0] = layout == BENCH_DS_USB ? 0x01 : 0x31;
        memcpy(r + at, b, 4);
        r[at + 4] = b[5], r[at + 5] = b[7], r[at + 6] = (uint8_t)i;
        r[at + 7] = (uint8_t)(hat | (b[5] & 0xf0));
        r[at + 8] = b[6];
        r[at + 9] = (uint8_t)(b[7] & 0x07);
        if (layout == BENCH_DS_BT) bench_seal(r);
        break;
    }
    case BENCH_SWITCH: {
        r[0] = 0x30;
        r[1] = (uint8_t)i;
        r[2] = 0x91;
        r[3] = b[4], r[4] = (uint8_t)(b[5] & 0x3f), r[5] = b[6];
        for (int k = 0; k < 6; k++) r[6 + k] = (uint8_t)(h >> (8 * k + 3));
        break;
    }
    case BENCH_GENERIC:
        memcpy(r, b, 4);
        r[4] = (uint8_t)(hat | (b[5] & 0xf0));
        r[5] = b[6];
        break;
    }
}

static double bench_sample(void *user) {
    input_bench *bench = user;
    input_gamepad_state state = { 0 };
    double sink = 0;
    uint64_t start = core_time_ns();
    for (int pass = 0; pass < BENCH_PASSES; pass++) {
        for (int i = 0; i < BENCH_REPORTS; i++) {
            input_decoder_decode(bench->decoder, bench->reports[i], bench->report_size, &state, NULL);
            sink += state.buttons;
        }
    }
    uint64_t elapsed = core_time_ns() - start;
    bench_consume(sink + state.lx);
    return (double)elapsed / ((double)BENCH_PASSES * BENCH_REPORTS);
}

static void input_bench_row(bench_context *ctx, const char *name, uint16_t vendor_id, uint16_t product_id,
                      bench_layout layout, size_t report_size) {
    if (!bench_wants(ctx, name)) return;
    input_bench *bench = core_calloc(1, sizeof *bench);
    core_error error = { 0 };
    bool generic = layout == BENCH_GENERIC;
    bench->decoder = input_decoder_create(
        &(input_decoder_desc){ .vendor_id = vendor_id, .product_id = product_id,
                               .descriptor = generic ? bench_generic_descriptor : NULL,
                               .descriptor_size = generic ? sizeof bench_generic_descriptor : 0 },
        &error);
    if (!bench->decoder) core_fatal("bench", "%s: %s", name, error.message);
    bench->report_size = report_size;
    for (uint32_t i = 0; i < BENCH_REPORTS; i++) bench_fill(bench->reports[i], layout, i);
    /* Every report must decode, or the row would time the rejection path. */
    input_gamepad_state state = { 0 };
    for (int i = 0; i < BENCH_REPORTS; i++)
        if (input_decoder_decode(bench->decoder, bench->reports[i], report_size, &state, NULL) != INPUT_DECODE_OK)
            core_fatal("bench", "%s: report %d does not decode", name, i);
    bench_run(ctx, name, "ns", BENCH_RUNS, bench_sample, bench);
    input_decoder_destroy(bench->decoder);
    core_free(bench, sizeof *bench);
}

void bench_group_input(bench_context *ctx) {
    if (!bench_wants(ctx, "input.decode")) return;
    input_bench_row(ctx, "input.decode.dualshock4", 0x054c, 0x09cc, BENCH_DS4_USB, 64);
    input_bench_row(ctx, "input.decode.dualsense", 0x054c, 0x0ce6, BENCH_DS_USB, 64);
    input_bench_row(ctx, "input.decode.switch_pro", 0x057e, 0x2009, BENCH_SWITCH, 64);
    input_bench_row(ctx, "input.decode.generic", 0x0079, 0x0006, BENCH_GENERIC, 6);
    input_bench_row(ctx, "input.decode.dualshock4.bluetooth", 0x054c, 0x09cc, BENCH_DS4_BT, 78);
    input_bench_row(ctx, "input.decode.dualsense.bluetooth", 0x054c, 0x0ce6, BENCH_DS_BT, 78);
}
