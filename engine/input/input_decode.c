/* input_decode.c — the gamepad state helpers, the decoder object and the decoders of the known
 * pads (DualShock 4, DualSense, Switch Pro). Generic pads go through input_hid_descriptor.c.
 *
 * Layouts, byte offsets from the start of the report as hid_read returns it (report ID at 0).
 * Sources: Linux drivers/hid/hid-playstation.c (struct dualshock4_input_report_usb/_bt,
 * dualsense_input_report, DS_BUTTONS*_* masks, DS4_INPUT_REPORT_BT_MINIMAL), hid-nintendo.c
 * (struct joycon_input_report, JC_BTN_*, stick unpacking), SDL's HIDAPI drivers
 * (SDL_hidapi_ps4.c / _ps5.c / _switch.c: packet checks, axis scaling), dekuNukem's
 * Nintendo_Switch_Reverse_Engineering notes and the psdevwiki DS4-USB / DS4-BT pages.
 *
 *   DualShock 4 (054c:05c4, 054c:09cc, wireless adapter 054c:0ba0)
 *     0x01 USB, 64 bytes: 1 lx, 2 ly, 3 rx, 4 ry, 5 hat (low nibble) + square cross circle triangle
 *          (bits 4-7), 6 L1 R1 L2 R2 share options L3 R3 (bits 0-7), 7 PS (bit 0) touchpad click
 *          (bit 1) + counter, 8 L2 analog, 9 R2 analog; 31 bit 2: the adapter has no controller.
 *     0x01 reduced Bluetooth report, 10 bytes: bytes 1-9 as above.
 *     0x11 Bluetooth, 78 bytes: 1 flags (bit 7: HID data present), 2 reserved, the USB bytes 1-9
 *          at 3-11; 74-77 CRC-32 (little-endian) of the byte 0xa1 followed by bytes 0-73.
 *   DualSense (054c:0ce6, Edge 054c:0df2)
 *     0x01 USB, 64 bytes: 1 lx, 2 ly, 3 rx, 4 ry, 5 L2, 6 R2, 7 counter, 8 hat + face buttons as
 *          on the DS4, 9 L1 R1 L2 R2 create options L3 R3, 10 PS (bit 0) touchpad (1) mute (2).
 *     0x01 simple Bluetooth report, 10 bytes: the DS4 layout (no mute button in it).
 *     0x31 Bluetooth, 78 bytes: 1 sequence/tag, the USB bytes 1-10 at 2-11; CRC as on the DS4.
 *   Switch Pro (057e:2009)
 *     0x30 standard full report (0x31 the same with NFC/IR data after it), USB 64 bytes, at least
 *          12: 3 right buttons Y X B A SR SL R ZR (bits 0-7), 4 shared minus plus rstick lstick
 *          home capture (bits 0-5), 5 left buttons down up right left SR SL L ZL, 6-8 left stick
 *          and 9-11 right stick as two 12-bit values: x = b0 | (b1 & 0xf) << 8, y = b1 >> 4 | b2 << 4,
 *          y up-positive.
 *     Other IDs (0x21 subcommand replies, 0x3f simple HID mode, 0x81 USB acks) are not read.
 *
 * Axes: an 8-bit value v becomes (2v − 255) / 255, so 0x00 → −1, 0xff → +1 and the centre 0x80 →
 * +1/255 ≈ 0.0039 (SDL's v·257 − 32768 over 32767 gives the same 0.0039); triggers v / 255.
 * Switch sticks have no factory calibration here: centre 2048 and a half-range of 1433 counts
 * (SDL's fallback for an unprogrammed calibration: 0.7 × 2048), clamped to ±1, y negated.
 */
#include "input/input_decode_internal.h"

#include "core/core.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ---- gamepad state -------------------------------------------------------------------------- */

static const char *const input_button_names[INPUT_BUTTON_COUNT] = {
    [INPUT_BUTTON_SOUTH] = "south",         [INPUT_BUTTON_EAST] = "east",
    [INPUT_BUTTON_WEST] = "west",           [INPUT_BUTTON_NORTH] = "north",
    [INPUT_BUTTON_LB] = "lb",               [INPUT_BUTTON_RB] = "rb",
    [INPUT_BUTTON_LS] = "ls",               [INPUT_BUTTON_RS] = "rs",
    [INPUT_BUTTON_BACK] = "back",           [INPUT_BUTTON_START] = "start",
    [INPUT_BUTTON_GUIDE] = "guide",         [INPUT_BUTTON_DPAD_UP] = "dpad_up",
    [INPUT_BUTTON_DPAD_DOWN] = "dpad_down", [INPUT_BUTTON_DPAD_LEFT] = "dpad_left",
    [INPUT_BUTTON_DPAD_RIGHT] = "dpad_right", [INPUT_BUTTON_TOUCHPAD] = "touchpad",
    [INPUT_BUTTON_MISC] = "misc",
};

const char *input_button_name(input_button button) {
    if ((unsigned)button >= INPUT_BUTTON_COUNT) return "unknown";
    return input_button_names[button];
}

input_button input_button_from_name(const char *name) {
    if (!name) return INPUT_BUTTON_COUNT;
    for (int i = 0; i < INPUT_BUTTON_COUNT; i++)
        if (strcmp(name, input_button_names[i]) == 0) return (input_button)i;
    return INPUT_BUTTON_COUNT;
}

/* The length is clamped to 1 as well: a square-gated stick's corner (r ≈ 1.41) would otherwise
 * come out longer than full deflection, and the state promises components in [-1, 1]. */
static void input_dead_zone_stick(float *x, float *y, float radius) {
    float r = sqrtf(*x * *x + *y * *y);
    if (!(r > radius)) { /* inside the zone, on its edge, or NaN */
        *x = 0.0f;
        *y = 0.0f;
        return;
    }
    float length = (r - radius) / (1.0f - radius);
    if (length > 1.0f) length = 1.0f;
    float k = length / r;
    *x *= k;
    *y *= k;
}

void input_apply_dead_zone(input_gamepad_state *state, float radius) {
    if (!(radius > 0.0f)) return; /* 0, negative or NaN: no dead zone */
    if (radius >= 1.0f) {
        state->lx = state->ly = state->rx = state->ry = 0.0f;
        return;
    }
    input_dead_zone_stick(&state->lx, &state->ly, radius);
    input_dead_zone_stick(&state->rx, &state->ry, radius);
}

/* ---- kinds -------------------------------------------------------------------------------- */

const char *input_gamepad_kind_name(input_gamepad_kind kind) {
    switch (kind) {
    case INPUT_GAMEPAD_GENERIC: return "generic";
    case INPUT_GAMEPAD_DUALSHOCK4: return "dualshock4";
    case INPUT_GAMEPAD_DUALSENSE: return "dualsense";
    case INPUT_GAMEPAD_SWITCH_PRO: return "switch_pro";
    }
    return "unknown";
}

bool input_gamepad_kind_from_ids(uint16_t vendor_id, uint16_t product_id, input_gamepad_kind *kind) {
    input_gamepad_kind found;
    if (vendor_id == 0x054c && (product_id == 0x05c4 || product_id == 0x09cc || product_id == 0x0ba0))
        found = INPUT_GAMEPAD_DUALSHOCK4;
    else if (vendor_id == 0x054c && (product_id == 0x0ce6 || product_id == 0x0df2))
        found = INPUT_GAMEPAD_DUALSENSE;
    else if (vendor_id == 0x057e && product_id == 0x2009)
        found = INPUT_GAMEPAD_SWITCH_PRO;
    else
        return false;
    if (kind) *kind = found;
    return true;
}

/* ---- the decoder object --------------------------------------------------------------------- */

/* Sony Bluetooth reports carry a CRC-32. Official pads always get it right; some third-party pads
 * that borrow Sony's ids do not, and SDL's HIDAPI driver accepts their reports rather than ignore
 * the pad. We do the same: CRCs are enforced (a mismatch is MALFORMED) once a pad has sent this
 * many reports with a correct one, and not before. */
enum { INPUT_CRC_TRUSTED_AFTER = 3 };

struct input_decoder {
    input_gamepad_kind kind;
    uint16_t vendor_id, product_id;
    uint8_t crc_good;                /* Bluetooth reports with a correct CRC, up to the threshold */
    input_decoder_stats_info stats;
    input_hid_layout layout;         /* INPUT_GAMEPAD_GENERIC only */
};

static void input_decode_crc_init(void);
static pthread_once_t input_decode_crc_once = PTHREAD_ONCE_INIT;


input_decoder *input_decoder_create(const input_decoder_desc *desc, core_error *error) {
    if (!desc) {
        core_error_set(error, CORE_ERROR_ARGUMENT, "no decoder description given");
        return NULL;
    }
    input_gamepad_kind kind = INPUT_GAMEPAD_GENERIC;
    bool known = input_gamepad_kind_from_ids(desc->vendor_id, desc->product_id, &kind);
    input_hid_layout layout;
    if (!known) {
        if (!desc->descriptor || desc->descriptor_size == 0) {
            core_error_set(error, CORE_ERROR_ARGUMENT,
                               "%04x:%04x is not a known pad and no report descriptor was given",
                               desc->vendor_id, desc->product_id);
            return NULL;
        }
        core_error reason = { 0 };
        if (!input__hid_layout_parse(desc->descriptor, desc->descriptor_size, &layout, &reason)) {
            core_error_set(error, reason.code, "%04x:%04x: unusable report descriptor: %s",
                               desc->vendor_id, desc->product_id, reason.message);
            return NULL;
        }
    }
    pthread_once(&input_decode_crc_once, input_decode_crc_init);
    input_decoder *decoder = core_calloc(1, sizeof *decoder);
    decoder->kind = kind;
    decoder->vendor_id = desc->vendor_id;
    decoder->product_id = desc->product_id;
    if (!known) decoder->layout = layout;
    return decoder;
}

void input_decoder_destroy(input_decoder *decoder) {
    if (decoder) core_free(decoder, sizeof *decoder);
}

input_gamepad_kind input_decoder_kind(const input_decoder *decoder) { return decoder->kind; }

input_decoder_stats_info input_decoder_stats(const input_decoder *decoder) { return decoder->stats; }

/* ---- CRC-32 (IEEE 802.3, reflected, as zlib), slicing by 8 ------------------------------------ */

static uint32_t input_crc_table[8][256];
static uint32_t input_crc_after_a1; /* the running value after the 0xa1 seed byte */

static void input_decode_crc_init(void) {
    for (uint32_t i = 0; i < 256; i++) {
        uint32_t c = i;
        for (int k = 0; k < 8; k++) c = c & 1 ? (c >> 1) ^ 0xedb88320u : c >> 1;
        input_crc_table[0][i] = c;
    }
    for (int t = 1; t < 8; t++)
        for (int i = 0; i < 256; i++) {
            uint32_t c = input_crc_table[t - 1][i];
            input_crc_table[t][i] = (c >> 8) ^ input_crc_table[0][c & 0xff];
        }
    uint32_t c = 0xffffffffu;
    input_crc_after_a1 = (c >> 8) ^ input_crc_table[0][(c ^ 0xa1u) & 0xff];
}

static inline uint32_t input_le32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* CRC-32 of 0xa1 followed by bytes[0, size): what the Sony pads put in a Bluetooth input report's
 * last four bytes (hid-playstation's PS_INPUT_CRC32_SEED). */
static uint32_t input_crc_sony_input(const uint8_t *bytes, size_t size) {
    uint32_t c = input_crc_after_a1;
    while (size >= 8) {
        uint32_t one = input_le32(bytes) ^ c, two = input_le32(bytes + 4);
        c = input_crc_table[7][one & 0xff] ^ input_crc_table[6][(one >> 8) & 0xff] ^
            input_crc_table[5][(one >> 16) & 0xff] ^ input_crc_table[4][one >> 24] ^
            input_crc_table[3][two & 0xff] ^ input_crc_table[2][(two >> 8) & 0xff] ^
            input_crc_table[1][(two >> 16) & 0xff] ^ input_crc_table[0][two >> 24];
        bytes += 8;
        size -= 8;
    }
    while (size--) c = (c >> 8) ^ input_crc_table[0][(c ^ *bytes++) & 0xff];
    return ~c;
}

enum { INPUT_SONY_BT_SIZE = 78, INPUT_SONY_CRC_AT = 74 };

/* Whether a 78-byte Sony Bluetooth report passes the CRC rule above. */
static bool input_sony_crc_accepts(input_decoder *decoder, const uint8_t *report) {
    if (input_crc_sony_input(report, INPUT_SONY_CRC_AT) == input_le32(report + INPUT_SONY_CRC_AT)) {
        if (decoder->crc_good < INPUT_CRC_TRUSTED_AFTER) decoder->crc_good++;
        return true;
    }
    return decoder->crc_good < INPUT_CRC_TRUSTED_AFTER;
}

/* ---- shared pieces of the known layouts ------------------------------------------------------ */

#define INPUT_BIT(button) (1u << (button))

/* Hat 0 = up, then clockwise in eighths; 8 … 15 centred (hid-playstation's ps_gamepad_hat_mapping). */
static const uint32_t input_hat_table[16] = {
    INPUT_BIT(INPUT_BUTTON_DPAD_UP),
    INPUT_BIT(INPUT_BUTTON_DPAD_UP) | INPUT_BIT(INPUT_BUTTON_DPAD_RIGHT),
    INPUT_BIT(INPUT_BUTTON_DPAD_RIGHT),
    INPUT_BIT(INPUT_BUTTON_DPAD_DOWN) | INPUT_BIT(INPUT_BUTTON_DPAD_RIGHT),
    INPUT_BIT(INPUT_BUTTON_DPAD_DOWN),
    INPUT_BIT(INPUT_BUTTON_DPAD_DOWN) | INPUT_BIT(INPUT_BUTTON_DPAD_LEFT),
    INPUT_BIT(INPUT_BUTTON_DPAD_LEFT),
    INPUT_BIT(INPUT_BUTTON_DPAD_UP) | INPUT_BIT(INPUT_BUTTON_DPAD_LEFT),
};

uint32_t input__hat_buttons(unsigned hat) { return input_hat_table[hat & 15]; }

static inline float input_axis8(uint8_t value) { return (float)(2 * (int)value - 255) / 255.0f; }
static inline float input_trigger8(uint8_t value) { return (float)value / 255.0f; }

/* The three Sony button bytes (same bits on the DS4 and the DualSense): b0 hat + face buttons,
 * b1 shoulders, triggers' digital bits, share/create, options, stick clicks; b2 PS, touchpad,
 * and on the DualSense mute. */
static inline uint32_t input_sony_buttons(uint8_t b0, uint8_t b1, uint8_t b2, bool has_mute) {
    uint32_t buttons = input_hat_table[b0 & 15];
    buttons |= (uint32_t)(b0 >> 4 & 1) << INPUT_BUTTON_WEST;   /* square */
    buttons |= (uint32_t)(b0 >> 5 & 1) << INPUT_BUTTON_SOUTH;  /* cross */
    buttons |= (uint32_t)(b0 >> 6 & 1) << INPUT_BUTTON_EAST;   /* circle */
    buttons |= (uint32_t)(b0 >> 7 & 1) << INPUT_BUTTON_NORTH;  /* triangle */
    buttons |= (uint32_t)(b1 & 1) << INPUT_BUTTON_LB;
    buttons |= (uint32_t)(b1 >> 1 & 1) << INPUT_BUTTON_RB;
    buttons |= (uint32_t)(b1 >> 4 & 1) << INPUT_BUTTON_BACK;
    buttons |= (uint32_t)(b1 >> 5 & 1) << INPUT_BUTTON_START;
    buttons |= (uint32_t)(b1 >> 6 & 1) << INPUT_BUTTON_LS;
    buttons |= (uint32_t)(b1 >> 7 & 1) << INPUT_BUTTON_RS;
    buttons |= (uint32_t)(b2 & 1) << INPUT_BUTTON_GUIDE;
    buttons |= (uint32_t)(b2 >> 1 & 1) << INPUT_BUTTON_TOUCHPAD;
    if (has_mute) buttons |= (uint32_t)(b2 >> 2 & 1) << INPUT_BUTTON_MISC;
    return buttons;
}

/* Some fight sticks set only the digital L2/R2 bits and leave the analog bytes 0 (SDL's
 * HIDAPI_DriverPS4_HandleStatePacket does the same). */
static inline float input_sony_trigger(uint8_t analog, uint8_t b1, unsigned digital_bit) {
    return analog == 0 && (b1 >> digital_bit & 1) ? 1.0f : input_trigger8(analog);
}

static inline void input_sony_sticks(const uint8_t *p, input_gamepad_state *state) {
    state->lx = input_axis8(p[0]);
    state->ly = input_axis8(p[1]);
    state->rx = input_axis8(p[2]);
    state->ry = input_axis8(p[3]);
}

/* The DS4 common block (also the DualSense's simple report): p[0] = lx … p[8] = R2. */
static inline void input_ds4_block(const uint8_t *p, input_gamepad_state *state, bool has_mute) {
    input_sony_sticks(p, state);
    state->lt = input_sony_trigger(p[7], p[5], 2);
    state->rt = input_sony_trigger(p[8], p[5], 3);
    state->buttons = input_sony_buttons(p[4], p[5], p[6], has_mute);
}

/* The DualSense block: p[0] = lx … p[4] L2, p[5] R2, p[6] counter, p[7 … 9] buttons. */
static inline void input_dualsense_block(const uint8_t *p, input_gamepad_state *state) {
    input_sony_sticks(p, state);
    state->lt = input_sony_trigger(p[4], p[8], 2);
    state->rt = input_sony_trigger(p[5], p[8], 3);
    state->buttons = input_sony_buttons(p[7], p[8], p[9], true);
}

static inline input_decode_result input_short(input_decode_failure *failure, size_t size, size_t need) {
    failure->size = size;
    failure->limit = need;
    return INPUT_DECODE_SHORT;
}

static inline input_decode_result input_long(input_decode_failure *failure, size_t size, size_t most) {
    failure->size = size;
    failure->limit = most;
    return INPUT_DECODE_OVERSIZED;
}

static inline input_decode_result input_unknown(input_decode_failure *failure, size_t size, int id) {
    failure->size = size;
    failure->report_id = id;
    return INPUT_DECODE_UNKNOWN_ID;
}

static inline input_decode_result input_malformed(input_decode_failure *failure, size_t size, const char *why) {
    failure->size = size;
    failure->reason = why;
    return INPUT_DECODE_MALFORMED;
}

/* ---- DualShock 4 ---------------------------------------------------------------------------- */

enum { INPUT_DS4_SHORT_SIZE = 10, INPUT_DS4_USB_SIZE = 64 };

static input_decode_result input_decode_ds4(input_decoder *decoder, const uint8_t *report, size_t size,
                                            input_gamepad_state *state, input_decode_failure *failure) {
    if (size == 0) return input_short(failure, size, INPUT_DS4_SHORT_SIZE);
    switch (report[0]) {
    case 0x01:
        /* 64 bytes: USB; 10: the reduced Bluetooth report. Both start with the same 10 bytes,
         * which are all we read, so a length in between is read the same way. */
        if (size < INPUT_DS4_SHORT_SIZE) return input_short(failure, size, INPUT_DS4_SHORT_SIZE);
        if (size > INPUT_DS4_USB_SIZE) return input_long(failure, size, INPUT_DS4_USB_SIZE);
        /* Status byte 2 (byte 31) bit 2: the wireless adapter has no controller paired right now;
         * always 0 on a pad (SDL's HIDAPI_DriverPS4_IsPacketValid, hid-playstation's dongle state). */
        if (size == INPUT_DS4_USB_SIZE && (report[31] & 0x04))
            return input_malformed(failure, size, "the wireless adapter reports no controller");
        input_ds4_block(report + 1, state, false);
        return INPUT_DECODE_OK;
    case 0x11:
        if (size < INPUT_SONY_BT_SIZE) return input_short(failure, size, INPUT_SONY_BT_SIZE);
        if (size > INPUT_SONY_BT_SIZE) return input_long(failure, size, INPUT_SONY_BT_SIZE);
        if (!(report[1] & 0x80)) return input_malformed(failure, size, "no input data (byte 1 bit 7 clear)");
        if (!input_sony_crc_accepts(decoder, report)) return input_malformed(failure, size, "CRC mismatch");
        input_ds4_block(report + 3, state, false);
        return INPUT_DECODE_OK;
    default:
        return input_unknown(failure, size, report[0]);
    }
}

/* ---- DualSense ------------------------------------------------------------------------------ */

enum { INPUT_DS_SIMPLE_SIZE = 10, INPUT_DS_USB_SIZE = 64 };

static input_decode_result input_decode_dualsense(input_decoder *decoder, const uint8_t *report, size_t size,
                                                  input_gamepad_state *state, input_decode_failure *failure) {
    if (size == 0) return input_short(failure, size, INPUT_DS_SIMPLE_SIZE);
    switch (report[0]) {
    case 0x01:
        /* Two layouts share the ID; the size tells them apart (hid-playstation and SDL do too). */
        if (size == INPUT_DS_SIMPLE_SIZE) {
            input_ds4_block(report + 1, state, false);
            return INPUT_DECODE_OK;
        }
        if (size < INPUT_DS_USB_SIZE)
            return input_short(failure, size, size < INPUT_DS_SIMPLE_SIZE ? INPUT_DS_SIMPLE_SIZE : INPUT_DS_USB_SIZE);
        if (size > INPUT_DS_USB_SIZE) return input_long(failure, size, INPUT_DS_USB_SIZE);
        input_dualsense_block(report + 1, state);
        return INPUT_DECODE_OK;
    case 0x31:
        if (size < INPUT_SONY_BT_SIZE) return input_short(failure, size, INPUT_SONY_BT_SIZE);
        if (size > INPUT_SONY_BT_SIZE) return input_long(failure, size, INPUT_SONY_BT_SIZE);
        if (!input_sony_crc_accepts(decoder, report)) return input_malformed(failure, size, "CRC mismatch");
        input_dualsense_block(report + 2, state);
        return INPUT_DECODE_OK;
    default:
        return input_unknown(failure, size, report[0]);
    }
}

/* ---- Switch Pro ----------------------------------------------------------------------------- */

/* 12 bytes reach the right stick; 362 is the longest input report the pad sends (0x31 with its
 * NFC/IR block, dekuNukem's bluetooth_hid_notes). */
enum { INPUT_SWITCH_MIN_SIZE = 12, INPUT_SWITCH_MAX_SIZE = 362 };

#define INPUT_SWITCH_CENTER 2048.0f
#define INPUT_SWITCH_HALF_RANGE 1433.0f

static inline float input_switch_axis(unsigned raw, float sign) {
    float value = sign * ((float)raw - INPUT_SWITCH_CENTER) / INPUT_SWITCH_HALF_RANGE;
    return value < -1.0f ? -1.0f : value > 1.0f ? 1.0f : value;
}

static input_decode_result input_decode_switch(const uint8_t *report, size_t size, input_gamepad_state *state,
                                               input_decode_failure *failure) {
    if (size == 0) return input_short(failure, size, INPUT_SWITCH_MIN_SIZE);
    if (report[0] != 0x30 && report[0] != 0x31) return input_unknown(failure, size, report[0]);
    if (size < INPUT_SWITCH_MIN_SIZE) return input_short(failure, size, INPUT_SWITCH_MIN_SIZE);
    if (size > INPUT_SWITCH_MAX_SIZE) return input_long(failure, size, INPUT_SWITCH_MAX_SIZE);
    uint8_t right = report[3], shared = report[4], left = report[5];
    /* Buttons by position: Nintendo's B is the bottom face button, A the right one, Y the left, X
     * the top (the labels are swapped relative to an Xbox pad, the places are not). */
    uint32_t buttons = 0;
    buttons |= (uint32_t)(right & 1) << INPUT_BUTTON_WEST;          /* Y */
    buttons |= (uint32_t)(right >> 1 & 1) << INPUT_BUTTON_NORTH;    /* X */
    buttons |= (uint32_t)(right >> 2 & 1) << INPUT_BUTTON_SOUTH;    /* B */
    buttons |= (uint32_t)(right >> 3 & 1) << INPUT_BUTTON_EAST;     /* A */
    buttons |= (uint32_t)(right >> 6 & 1) << INPUT_BUTTON_RB;       /* R */
    buttons |= (uint32_t)(shared & 1) << INPUT_BUTTON_BACK;         /* minus */
    buttons |= (uint32_t)(shared >> 1 & 1) << INPUT_BUTTON_START;   /* plus */
    buttons |= (uint32_t)(shared >> 2 & 1) << INPUT_BUTTON_RS;
    buttons |= (uint32_t)(shared >> 3 & 1) << INPUT_BUTTON_LS;
    buttons |= (uint32_t)(shared >> 4 & 1) << INPUT_BUTTON_GUIDE;   /* home */
    buttons |= (uint32_t)(shared >> 5 & 1) << INPUT_BUTTON_MISC;    /* capture */
    buttons |= (uint32_t)(left & 1) << INPUT_BUTTON_DPAD_DOWN;
    buttons |= (uint32_t)(left >> 1 & 1) << INPUT_BUTTON_DPAD_UP;
    buttons |= (uint32_t)(left >> 2 & 1) << INPUT_BUTTON_DPAD_RIGHT;
    buttons |= (uint32_t)(left >> 3 & 1) << INPUT_BUTTON_DPAD_LEFT;
    buttons |= (uint32_t)(left >> 6 & 1) << INPUT_BUTTON_LB;        /* L */
    const uint8_t *ls = report + 6, *rs = report + 9;
    state->lx = input_switch_axis((unsigned)ls[0] | (unsigned)(ls[1] & 0x0f) << 8, 1.0f);
    state->ly = input_switch_axis((unsigned)(ls[1] >> 4) | (unsigned)ls[2] << 4, -1.0f);
    state->rx = input_switch_axis((unsigned)rs[0] | (unsigned)(rs[1] & 0x0f) << 8, 1.0f);
    state->ry = input_switch_axis((unsigned)(rs[1] >> 4) | (unsigned)rs[2] << 4, -1.0f);
    state->lt = (float)(left >> 7 & 1);   /* ZL: digital */
    state->rt = (float)(right >> 7 & 1);  /* ZR */
    state->buttons = buttons;
    return INPUT_DECODE_OK;
}

/* ---- decode and its results ----------------------------------------------------------------- */

static void input_decode_explain(input_decode_result result, const input_decode_failure *f, core_error *error);

input_decode_result input_decoder_decode(input_decoder *decoder, const uint8_t *report, size_t size,
                                         input_gamepad_state *state, core_error *error) {
    assert(decoder && state);
    if (!report) size = 0;
    input_decode_failure failure = { 0 };
    input_decode_result result;
    switch (decoder->kind) {
    case INPUT_GAMEPAD_DUALSHOCK4: result = input_decode_ds4(decoder, report, size, state, &failure); break;
    case INPUT_GAMEPAD_DUALSENSE: result = input_decode_dualsense(decoder, report, size, state, &failure); break;
    case INPUT_GAMEPAD_SWITCH_PRO: result = input_decode_switch(report, size, state, &failure); break;
    default: result = input__hid_decode(&decoder->layout, report, size, state, &failure); break;
    }
    switch (result) {
    case INPUT_DECODE_OK: decoder->stats.decoded++; return result;
    case INPUT_DECODE_SHORT: decoder->stats.short_reports++; break;
    case INPUT_DECODE_OVERSIZED: decoder->stats.oversized++; break;
    case INPUT_DECODE_UNKNOWN_ID: decoder->stats.unknown_id++; break;
    case INPUT_DECODE_MALFORMED: decoder->stats.malformed++; break;
    }
    if (error) input_decode_explain(result, &failure, error);
    return result;
}

const char *input_decode_result_name(input_decode_result result) {
    switch (result) {
    case INPUT_DECODE_OK: return "ok";
    case INPUT_DECODE_SHORT: return "report too short";
    case INPUT_DECODE_OVERSIZED: return "report too long";
    case INPUT_DECODE_UNKNOWN_ID: return "unknown report ID";
    case INPUT_DECODE_MALFORMED: return "malformed report";
    }
    return "unknown result";
}

/* A failed decode's reason, with its numbers, into the caller's error: formatted only when the
 * caller asked for one, so the decode path itself formats no text. */
static void input_decode_explain(input_decode_result result, const input_decode_failure *f, core_error *error) {
    const char *plain = input_decode_result_name(result);
    switch (result) {
    case INPUT_DECODE_OK: break;
    case INPUT_DECODE_SHORT:
        core_error_set(error, CORE_ERROR_CORRUPT, "%s: %zu bytes, need %zu", plain, f->size, f->limit);
        break;
    case INPUT_DECODE_OVERSIZED:
        core_error_set(error, CORE_ERROR_RANGE, "%s: %zu bytes, at most %zu", plain, f->size, f->limit);
        break;
    case INPUT_DECODE_UNKNOWN_ID:
        core_error_set(error, CORE_ERROR_FORMAT, "%s 0x%02x (%zu bytes)", plain, (unsigned)f->report_id & 0xff, f->size);
        break;
    case INPUT_DECODE_MALFORMED:
        if (f->reason) core_error_set(error, CORE_ERROR_FORMAT, "%s: %s", plain, f->reason);
        else core_error_set(error, CORE_ERROR_FORMAT, "%s", plain);
        break;
    }
}
