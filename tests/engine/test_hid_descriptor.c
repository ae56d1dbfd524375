/* test_hid_descriptor.c — the HID report-descriptor parser and the generic decoder
 * (engine/input/input_hid_descriptor.c).
 *
 * The descriptors are written out item by item with their meaning beside each (HID 1.11 §6.2.2:
 * prefix = tag << 4 | type << 2 | size code), and the reports are laid out by hand from them: a
 * comment under each descriptor gives the bit positions its fields get. Hostile and truncated
 * descriptors must be refused with a reason, never crash or read outside (ASan watches).
 */
#include "input_decode_test.h"

#include "input/input.h"
#include "input/input_decode_internal.h"

#include <stdlib.h>
#include <string.h>


/* A typical cheap USB pad: no report IDs, X Y Z Rz 8-bit, a 4-bit hat, 12 buttons.
 * Body bits: X 0-7, Y 8-15, Z 16-23, Rz 24-31, hat 32-35, buttons 1-12 at 36-47 → 6 bytes. */
static const uint8_t pad_plain[] = {
    0x05, 0x01,             /* Usage Page (Generic Desktop) */
    0x09, 0x05,             /* Usage (Game Pad) */
    0xa1, 0x01,             /* Collection (Application) */
    0x09, 0x30, 0x09, 0x31, /*   Usage (X), Usage (Y) */
    0x09, 0x32, 0x09, 0x35, /*   Usage (Z), Usage (Rz) */
    0x15, 0x00,             /*   Logical Minimum (0) */
    0x26, 0xff, 0x00,       /*   Logical Maximum (255) */
    0x75, 0x08, 0x95, 0x04, /*   Report Size (8), Report Count (4) */
    0x81, 0x02,             /*   Input (Data, Var, Abs) */
    0x09, 0x39,             /*   Usage (Hat switch) */
    0x15, 0x00, 0x25, 0x07, /*   Logical 0 … 7 */
    0x35, 0x00,             /*   Physical Minimum (0) */
    0x46, 0x3b, 0x01,       /*   Physical Maximum (315) */
    0x65, 0x14,             /*   Unit (degrees) */
    0x75, 0x04, 0x95, 0x01, /*   Report Size (4), Report Count (1) */
    0x81, 0x42,             /*   Input (Data, Var, Abs, Null state) */
    0x65, 0x00,             /*   Unit (none) */
    0x05, 0x09,             /*   Usage Page (Button) */
    0x19, 0x01, 0x29, 0x0c, /*   Usage Minimum (1), Usage Maximum (12) */
    0x15, 0x00, 0x25, 0x01, /*   Logical 0 … 1 */
    0x75, 0x01, 0x95, 0x0c, /*   Report Size (1), Report Count (12) */
    0x81, 0x02,             /*   Input (Data, Var, Abs) */
    0xc0,                   /* End Collection */
};

/* The same pad behind Report ID 1, plus a vendor input report 2 (8 bytes) that carries nothing
 * we read. Report 1: ID, then the 6 body bytes above; the longest report is 2: 1 + 8 bytes. */
static const uint8_t pad_with_ids[] = {
    0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
    0x85, 0x01,             /*   Report ID (1) */
    0x09, 0x30, 0x09, 0x31, 0x09, 0x32, 0x09, 0x35,
    0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x04, 0x81, 0x02,
    0x09, 0x39, 0x15, 0x00, 0x25, 0x07, 0x75, 0x04, 0x95, 0x01, 0x81, 0x42,
    0x05, 0x09, 0x19, 0x01, 0x29, 0x0c, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x0c, 0x81, 0x02,
    0x85, 0x02,             /*   Report ID (2) */
    0x06, 0x00, 0xff,       /*   Usage Page (Vendor 0xff00) */
    0x09, 0x01,             /*   Usage (1) */
    0x75, 0x08, 0x95, 0x08, /*   Report Size (8), Report Count (8) */
    0x81, 0x02,             /*   Input */
    0xc0,
};

/* A joystick with 16-bit signed sticks (X Y Rx Ry), 10-bit triggers (Z Rz), a 1 … 8 hat and 4
 * buttons, in report 3. Body bits: X 0-15, Y 16-31, Rx 32-47, Ry 48-63, Z 64-73, Rz 74-83,
 * padding 84-87, hat 88-91, buttons 1-4 at 92-95 → 12 bytes (13 with the ID). */
static const uint8_t joystick_16bit[] = {
    0x05, 0x01, 0x09, 0x04, /* Usage Page (Generic Desktop), Usage (Joystick) */
    0xa1, 0x01,             /* Collection (Application) */
    0x85, 0x03,             /*   Report ID (3) */
    0xa1, 0x00,             /*   Collection (Physical) */
    0x09, 0x30, 0x09, 0x31, 0x09, 0x33, 0x09, 0x34,  /* X Y Rx Ry */
    0x16, 0x00, 0x80,       /*     Logical Minimum (−32768) */
    0x26, 0xff, 0x7f,       /*     Logical Maximum (32767) */
    0x75, 0x10, 0x95, 0x04, 0x81, 0x02,
    0xc0,                   /*   End Collection */
    0x09, 0x32, 0x09, 0x35, /*   Z, Rz */
    0x15, 0x00, 0x26, 0xff, 0x03,   /* Logical 0 … 1023 */
    0x75, 0x0a, 0x95, 0x02, 0x81, 0x02,
    0x75, 0x04, 0x95, 0x01, 0x81, 0x03,   /* 4 bits of padding: Input (Constant) */
    0x09, 0x39, 0x15, 0x01, 0x25, 0x08,   /* Hat, logical 1 … 8 (0 = centred) */
    0x75, 0x04, 0x95, 0x01, 0x81, 0x42,
    0x05, 0x09, 0x19, 0x01, 0x29, 0x04, 0x15, 0x00, 0x25, 0x01,
    0x75, 0x01, 0x95, 0x04, 0x81, 0x02,
    0xc0,
};

static input_decoder *generic_decoder(const uint8_t *descriptor, size_t size) {
    core_error error = { 0 };
    input_decoder *d = input_decoder_create(&(input_decoder_desc){ .vendor_id = 0x0079, .product_id = 0x0006,
                                                                   .descriptor = descriptor,
                                                                   .descriptor_size = size },
                                            &error);
    cr_assert_not_null(d, "%s", error.message);
    cr_assert_eq(input_decoder_kind(d), INPUT_GAMEPAD_GENERIC);
    return d;
}

/* Whether parsing fails with `code` (CORE_ERROR_NONE: any code) and a reason: CORE_ERROR_CORRUPT
 * for items that run past the end, CORE_ERROR_RANGE past the parser's limits, CORE_ERROR_FORMAT
 * for what HID does not allow or a pad does not have. */
static void expect_refused(const uint8_t *descriptor, size_t size, core_error_code code) {
    input_hid_layout layout;
    core_error error = { 0 };
    cr_expect_not(input__hid_layout_parse(descriptor, size, &layout, &error), "parsed, expected %s",
                  core_error_code_name(code));
    cr_expect_neq(error.message[0], '\0');
    if (code) cr_expect_eq(error.code, code, "code %s, expected %s (%s)", core_error_code_name(error.code),
                           core_error_code_name(code), error.message);
    else cr_expect_neq(error.code, CORE_ERROR_NONE, "%s", error.message);
}

/* ---- the typical pad ------------------------------------------------------------------------- */

Test(input_hid, plain_pad_axes) {
    input_decoder *d = generic_decoder(pad_plain, sizeof pad_plain);
    const uint8_t centred[6] = { 0x80, 0x80, 0x80, 0x80, 0x08, 0x00 };
    input_gamepad_state s = decode_ok(d, centred, sizeof centred);
    cr_expect_float_eq(s.lx, 1.0f / 255, EPS);
    cr_expect_float_eq(s.ly, 1.0f / 255, EPS);
    cr_expect_float_eq(s.rx, 1.0f / 255, EPS, "no Rx/Ry: Z is the right stick's x");
    cr_expect_float_eq(s.ry, 1.0f / 255, EPS);
    cr_expect_eq(s.lt, 0.0f);
    cr_expect_eq(s.rt, 0.0f);
    cr_expect_eq(s.buttons, 0u, "hat 8 is outside 0 … 7: centred");
    const uint8_t deflected[6] = { 0x00, 0xff, 0xff, 0x00, 0x0f, 0x00 };
    s = decode_ok(d, deflected, sizeof deflected);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, 1.0f);
    cr_expect_eq(s.rx, 1.0f);
    cr_expect_eq(s.ry, -1.0f);
    cr_expect_eq(s.buttons, 0u);
    input_decoder_destroy(d);
}

Test(input_hid, plain_pad_hat_and_buttons) {
    input_decoder *d = generic_decoder(pad_plain, sizeof pad_plain);
    for (uint8_t hat = 0; hat < 8; hat++) {
        const uint8_t r[6] = { 0x80, 0x80, 0x80, 0x80, hat, 0x00 };
        cr_expect_eq(decode_ok(d, r, sizeof r).buttons, hat_dpad[hat], "hat %u", hat);
    }
    /* Buttons 1 … 12 are bits 36 … 47: byte 4 bits 4-7, then byte 5. */
    const uint32_t order[12] = {
        BIT(INPUT_BUTTON_SOUTH), BIT(INPUT_BUTTON_EAST), BIT(INPUT_BUTTON_WEST), BIT(INPUT_BUTTON_NORTH),
        BIT(INPUT_BUTTON_LB),    BIT(INPUT_BUTTON_RB),   BIT(INPUT_BUTTON_BACK), BIT(INPUT_BUTTON_START),
        BIT(INPUT_BUTTON_LS),    BIT(INPUT_BUTTON_RS),   BIT(INPUT_BUTTON_GUIDE), 0, /* 12: unmapped */
    };
    for (int b = 0; b < 12; b++) {
        uint8_t r[6] = { 0x80, 0x80, 0x80, 0x80, 0x08, 0x00 };
        int bit = 36 + b;
        r[bit / 8] |= (uint8_t)(1u << (bit % 8));
        cr_expect_eq(decode_ok(d, r, sizeof r).buttons, order[b], "button %d", b + 1);
    }
    input_decoder_destroy(d);
}

Test(input_hid, plain_pad_bad_reports) {
    input_decoder *d = generic_decoder(pad_plain, sizeof pad_plain);
    const uint8_t r[8] = { 0x80, 0x80, 0x80, 0x80, 0x08, 0x00, 0x00, 0x00 };
    expect_rejected(d, r, 5, INPUT_DECODE_SHORT);
    cr_expect_str_eq(last_rejection.message, "report too short: 5 bytes, need 6");
    expect_rejected(d, r, 0, INPUT_DECODE_SHORT);
    expect_rejected(d, r, 7, INPUT_DECODE_OVERSIZED);
    cr_expect_str_eq(last_rejection.message, "report too long: 7 bytes, at most 6");
    input_decoder_stats_info stats = input_decoder_stats(d);
    cr_expect_eq(stats.short_reports, 2u);
    cr_expect_eq(stats.oversized, 1u);
    cr_expect_eq(stats.decoded, 0u);
    input_decoder_destroy(d);
}

Test(input_hid, pad_with_report_ids) {
    input_decoder *d = generic_decoder(pad_with_ids, sizeof pad_with_ids);
    const uint8_t r[7] = { 0x01, 0x00, 0xff, 0x80, 0x80, 0x02 | 0x10, 0x01 };
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, 1.0f);
    /* hat 2 (right), button 1 (bit 36 = byte 4 bit 4), button 5 (bit 40 = byte 5 bit 0) */
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_DPAD_RIGHT) | BIT(INPUT_BUTTON_SOUTH) | BIT(INPUT_BUTTON_LB));
    const uint8_t vendor[9] = { 0x02, 1, 2, 3, 4, 5, 6, 7, 8 };
    expect_rejected(d, vendor, sizeof vendor, INPUT_DECODE_UNKNOWN_ID);
    const uint8_t other[7] = { 0x07, 0, 0, 0, 0, 0, 0 };
    expect_rejected(d, other, sizeof other, INPUT_DECODE_UNKNOWN_ID);
    cr_expect_str_eq(last_rejection.message, "unknown report ID 0x07 (7 bytes)");
    expect_rejected(d, r, 6, INPUT_DECODE_SHORT);
    cr_expect_str_eq(last_rejection.message, "report too short: 6 bytes, need 7");
    uint8_t longer[12] = { 0x01, 0x80, 0x80, 0x80, 0x80, 0x08, 0x00 };
    decode_ok(d, longer, 9);  /* not longer than the device's longest report (2: 9 bytes) */
    expect_rejected(d, longer, 10, INPUT_DECODE_OVERSIZED);
    expect_rejected(d, r, 0, INPUT_DECODE_SHORT);
    input_decoder_destroy(d);
}

/* ---- 16-bit signed axes, triggers, a 1 … 8 hat --------------------------------------------------- */

static void put16(uint8_t *at, int value) {
    at[0] = (uint8_t)(value & 0xff);
    at[1] = (uint8_t)((value >> 8) & 0xff);
}

Test(input_hid, signed_16bit_axes_and_triggers) {
    input_decoder *d = generic_decoder(joystick_16bit, sizeof joystick_16bit);
    uint8_t r[13] = { 0x03 };
    put16(r + 1, -32768);   /* X */
    put16(r + 3, 32767);    /* Y */
    put16(r + 5, 0);        /* Rx */
    put16(r + 7, -16384);   /* Ry */
    /* Z = 1023 at body bits 64-73, Rz = 512 at 74-83: body byte 8 = 0xff, byte 9 = 0x03 (Z's top
     * two bits) | (512 & 0x3f) << 2 = 0x03, byte 10 = 512 >> 6 = 0x08, padding nibble 0. */
    r[1 + 8] = 0xff, r[1 + 9] = 0x03, r[1 + 10] = 0x08;
    r[1 + 11] = 0x01 | 0x20;  /* hat 1 (= up, the first value) ; button 2 (bit 93 = byte 11 bit 5) */
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, 1.0f);
    cr_expect_float_eq(s.rx, 1.0f / 65535, 1e-6f, "0 is half a count above the middle");
    cr_expect_float_eq(s.ry, -1.0f + 2.0f * 16384 / 65535, EPS);
    cr_expect_eq(s.lt, 1.0f, "Rx/Ry present: Z is the left trigger");
    cr_expect_float_eq(s.rt, 512.0f / 1023, EPS);
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_DPAD_UP) | BIT(INPUT_BUTTON_EAST));
    r[1 + 11] = 0x00; /* hat 0: outside 1 … 8, the null state */
    cr_expect_eq(decode_ok(d, r, sizeof r).buttons, 0u);
    r[1 + 11] = 0x08; /* hat 8: up-left */
    cr_expect_eq(decode_ok(d, r, sizeof r).buttons, BIT(INPUT_BUTTON_DPAD_UP) | BIT(INPUT_BUTTON_DPAD_LEFT));
    expect_rejected(d, r, 12, INPUT_DECODE_SHORT);
    input_decoder_destroy(d);
}

/* ---- parser details ------------------------------------------------------------------------- */

Test(input_hid, logical_maximum_ff_with_zero_minimum_is_255) {
    /* 0x25 0xff read signed would be −1; with a minimum of 0 it means 255 (as Linux reads it). */
    const uint8_t desc[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
        0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x25, 0xff, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,
        0xc0,
    };
    input_decoder *d = generic_decoder(desc, sizeof desc);
    const uint8_t r[2] = { 0xff, 0x00 };
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, -1.0f);
    input_decoder_destroy(d);
}

Test(input_hid, usage_page_applies_at_the_main_item) {
    /* Usages listed while the page was Button, the page switched to Generic Desktop before the
     * Input item: HID 1.11 §6.2.2.8 combines them with the page in force at the main item. A
     * 4-byte usage carries its own page whatever the current one is. */
    const uint8_t desc[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
        0x05, 0x09,                         /* Usage Page (Button) */
        0x09, 0x30, 0x09, 0x31,             /* Usage 0x30, 0x31 … */
        0x05, 0x01,                         /* … then Usage Page (Generic Desktop) */
        0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,
        0x05, 0x09,                         /* Usage Page (Button) */
        0x0b, 0x32, 0x00, 0x01, 0x00,       /* Usage (Generic Desktop: Z), 4 bytes */
        0x0b, 0x35, 0x00, 0x01, 0x00,       /* Usage (Generic Desktop: Rz) */
        0x95, 0x02, 0x81, 0x02,
        0xc0,
    };
    input_decoder *d = generic_decoder(desc, sizeof desc);
    const uint8_t r[4] = { 0x00, 0xff, 0xff, 0x00 };
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, 1.0f);
    cr_expect_eq(s.rx, 1.0f);
    cr_expect_eq(s.ry, -1.0f);
    input_decoder_destroy(d);
}

Test(input_hid, push_pop_restore_globals) {
    /* Push saves the 8-bit range and size; a 16-bit section; Pop brings the 8-bit one back for Y. */
    const uint8_t desc[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
        0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x01,
        0xa4,                               /* Push */
        0x27, 0xff, 0xff, 0x00, 0x00,       /*   Logical Maximum (65535) */
        0x75, 0x10,                         /*   Report Size (16) */
        0x09, 0x30, 0x81, 0x02,             /*   X: 16 bits at 0 */
        0xb4,                               /* Pop */
        0x09, 0x31, 0x81, 0x02,             /* Y: 8 bits at 16 */
        0xc0,
    };
    input_decoder *d = generic_decoder(desc, sizeof desc);
    const uint8_t r[3] = { 0xff, 0xff, 0x00 };
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, -1.0f);
    expect_rejected(d, r, 4, INPUT_DECODE_OVERSIZED);
    input_decoder_destroy(d);
}

Test(input_hid, gamepad_collection_preferred_over_a_mouse) {
    /* A combo receiver: a mouse (report 1, relative X/Y, 3 buttons) and a pad (report 2). */
    const uint8_t desc[] = {
        0x05, 0x01, 0x09, 0x02, 0xa1, 0x01,       /* Mouse application */
        0x85, 0x01,
        0x05, 0x09, 0x19, 0x01, 0x29, 0x03, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x81, 0x02,
        0x95, 0x05, 0x81, 0x03,
        0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x81, 0x25, 0x7f, 0x75, 0x08, 0x95, 0x02,
        0x81, 0x06,                               /* Input (Data, Var, Rel) */
        0xc0,
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,       /* Game Pad application */
        0x85, 0x02,
        0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,
        0x05, 0x09, 0x19, 0x01, 0x29, 0x08, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02,
        0xc0,
    };
    input_decoder *d = generic_decoder(desc, sizeof desc);
    const uint8_t mouse[4] = { 0x01, 0x07, 0x10, 0xf0 };
    expect_rejected(d, mouse, sizeof mouse, INPUT_DECODE_UNKNOWN_ID);
    const uint8_t pad[4] = { 0x02, 0xff, 0x00, 0x08 };
    input_gamepad_state s = decode_ok(d, pad, sizeof pad);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, -1.0f);
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_NORTH));
    input_decoder_destroy(d);
}

Test(input_hid, second_pad_of_an_adapter_is_not_mixed_in) {
    /* Two joysticks (reports 1 and 2); the second has Rx/Ry the first lacks. Only pad 1 is read. */
    const uint8_t desc[] = {
        0x05, 0x01, 0x09, 0x04, 0xa1, 0x01, 0x85, 0x01,
        0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,
        0xc0,
        0x05, 0x01, 0x09, 0x04, 0xa1, 0x01, 0x85, 0x02,
        0x09, 0x30, 0x09, 0x31, 0x09, 0x33, 0x09, 0x34, 0x95, 0x04, 0x81, 0x02,
        0xc0,
    };
    input_decoder *d = generic_decoder(desc, sizeof desc);
    const uint8_t second[5] = { 0x02, 0x00, 0x00, 0x00, 0x00 };
    expect_rejected(d, second, sizeof second, INPUT_DECODE_UNKNOWN_ID);
    const uint8_t first[3] = { 0x01, 0x00, 0xff };
    input_gamepad_state s = decode_ok(d, first, sizeof first);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, 1.0f);
    input_decoder_destroy(d);
}

Test(input_hid, fields_split_over_reports_keep_the_others) {
    /* Sticks in report 1, buttons in report 2: each report updates only its own fields. */
    const uint8_t desc[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
        0x85, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02,
        0x85, 0x02, 0x05, 0x09, 0x19, 0x01, 0x29, 0x08, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02,
        0xc0,
    };
    input_decoder *d = generic_decoder(desc, sizeof desc);
    input_gamepad_state s = { .buttons = BIT(INPUT_BUTTON_DPAD_UP) }; /* not this pad's: must stay */
    const uint8_t sticks[3] = { 0x01, 0xff, 0x00 }, buttons[2] = { 0x02, 0x03 };
    cr_assert_eq(input_decoder_decode(d, sticks, sizeof sticks, &s, NULL), INPUT_DECODE_OK);
    cr_assert_eq(input_decoder_decode(d, buttons, sizeof buttons, &s, NULL), INPUT_DECODE_OK);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, -1.0f);
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_SOUTH) | BIT(INPUT_BUTTON_EAST) | BIT(INPUT_BUTTON_DPAD_UP));
    const uint8_t released[2] = { 0x02, 0x00 };
    cr_assert_eq(input_decoder_decode(d, released, sizeof released, &s, NULL), INPUT_DECODE_OK);
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_DPAD_UP));
    cr_expect_eq(s.lx, 1.0f);
    input_decoder_destroy(d);
}

Test(input_hid, long_items_are_skipped) {
    uint8_t desc[sizeof pad_plain + 6];
    const uint8_t long_item[6] = { 0xfe, 0x03, 0x42, 0x01, 0x02, 0x03 };
    memcpy(desc, long_item, sizeof long_item);
    memcpy(desc + sizeof long_item, pad_plain, sizeof pad_plain);
    input_decoder *d = generic_decoder(desc, sizeof desc);
    input_decoder_destroy(d);
    const uint8_t running_off[] = { 0xfe, 0x10, 0x00, 0x01, 0x02 };
    expect_refused(running_off, sizeof running_off, CORE_ERROR_CORRUPT);
    const uint8_t cut_header[] = { 0xfe, 0x10 };
    expect_refused(cut_header, sizeof cut_header, CORE_ERROR_CORRUPT);
}

Test(input_hid, extract_bits_is_bounded) {
    const uint8_t bytes[3] = { 0xa5, 0x3c, 0xff };
    cr_expect_eq(input__hid_extract_bits(bytes, 3, 0, 8), 0xa5u);
    cr_expect_eq(input__hid_extract_bits(bytes, 3, 4, 8), 0xcau);      /* 0x3ca5 >> 4, low byte */
    cr_expect_eq(input__hid_extract_bits(bytes, 3, 12, 12), 0xff3u);   /* 0xff3c >> 4 */
    cr_expect_eq(input__hid_extract_bits(bytes, 3, 20, 8), 0x0fu, "bits past the end read 0");
    cr_expect_eq(input__hid_extract_bits(bytes, 3, 1000, 32), 0u);
    cr_expect_eq(input__hid_extract_bits(bytes, 3, 7, 1), 1u);
    cr_expect_eq(input__hid_extract_bits(bytes, 0, 0, 32), 0u);
    const uint8_t five[5] = { 0xf0, 0xde, 0xbc, 0x9a, 0x78 };
    cr_expect_eq(input__hid_extract_bits(five, 5, 4, 32), 0x89abcdefu);
}

/* ---- truncated and hostile descriptors ------------------------------------------------------------- */

Test(input_hid, truncated_descriptors_are_refused) {
    /* Every proper prefix of each descriptor, copied to a buffer of exactly that size so ASan
     * sees a read past it: refused (mid-item, or a collection left open), never a crash. */
    const struct { const uint8_t *bytes; size_t size; } all[] = {
        { pad_plain, sizeof pad_plain }, { pad_with_ids, sizeof pad_with_ids },
        { joystick_16bit, sizeof joystick_16bit },
    };
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) {
        for (size_t length = 0; length < all[k].size; length++) {
            uint8_t *copy = malloc(length ? length : 1);
            memcpy(copy, all[k].bytes, length);
            expect_refused(copy, length, CORE_ERROR_NONE);
            core_error error = { 0 };
            cr_expect_null(input_decoder_create(&(input_decoder_desc){ .vendor_id = 1, .product_id = 2,
                                                                       .descriptor = copy,
                                                                       .descriptor_size = length },
                                                &error));
            cr_expect_neq(error.code, CORE_ERROR_NONE);
            free(copy);
        }
    }
    const uint8_t mid_item[] = { 0x05, 0x01, 0x26, 0xff };
    expect_refused(mid_item, sizeof mid_item, CORE_ERROR_CORRUPT);
    expect_refused(NULL, 0, CORE_ERROR_FORMAT);
}

Test(input_hid, absurd_report_count_and_size) {
    const uint8_t count_65535[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x09, 0x30,
        0x75, 0x20,             /* Report Size (32) */
        0x96, 0xff, 0xff,       /* Report Count (65535) */
        0x81, 0x02, 0xc0,
    };
    expect_refused(count_65535, sizeof count_65535, CORE_ERROR_RANGE);
    const uint8_t too_long[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x09, 0x30,
        0x76, 0x00, 0x01,       /* Report Size (256) */
        0x96, 0x00, 0x30,       /* Report Count (12288): 384 KiB of report */
        0x81, 0x02, 0xc0,
    };
    expect_refused(too_long, sizeof too_long, CORE_ERROR_RANGE);
    const uint8_t accumulating[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01,
        0x76, 0x00, 0x01, 0x96, 0xf0, 0x01,   /* 256 bits × 496 = 15872 bytes: one item fits … */
        0x81, 0x03, 0x81, 0x03,               /* … two do not */
        0xc0,
    };
    expect_refused(accumulating, sizeof accumulating, CORE_ERROR_RANGE);
    const uint8_t size_300[] = { 0x05, 0x01, 0x76, 0x2c, 0x01 };
    expect_refused(size_300, sizeof size_300, CORE_ERROR_RANGE);
    const uint8_t id_0[] = { 0x05, 0x01, 0x85, 0x00 };
    expect_refused(id_0, sizeof id_0, CORE_ERROR_FORMAT);
    const uint8_t id_256[] = { 0x05, 0x01, 0x86, 0x00, 0x01 };
    expect_refused(id_256, sizeof id_256, CORE_ERROR_FORMAT);
}

Test(input_hid, deep_nesting_is_refused) {
    uint8_t desc[4000];
    size_t n = 0;
    for (int i = 0; i < 1000; i++) desc[n++] = 0xa1, desc[n++] = 0x00;
    for (int i = 0; i < 1000; i++) desc[n++] = 0xc0;
    expect_refused(desc, n, CORE_ERROR_RANGE);
    n = 0;
    for (int i = 0; i < 17; i++) desc[n++] = 0xa4;   /* Push × 17 */
    expect_refused(desc, n, CORE_ERROR_RANGE);
}

Test(input_hid, unbalanced_items_are_refused) {
    const uint8_t pop_first[] = { 0x05, 0x01, 0xb4 };
    expect_refused(pop_first, sizeof pop_first, CORE_ERROR_FORMAT);
    const uint8_t end_first[] = { 0x05, 0x01, 0xc0 };
    expect_refused(end_first, sizeof end_first, CORE_ERROR_FORMAT);
    const uint8_t left_open[] = { 0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0xa1, 0x00, 0xc0 };
    expect_refused(left_open, sizeof left_open, CORE_ERROR_FORMAT);
    /* A Push that is never popped is harmless: the pad still parses. */
    uint8_t pushed[sizeof pad_plain + 1] = { 0xa4 };
    memcpy(pushed + 1, pad_plain, sizeof pad_plain);
    input_decoder *d = generic_decoder(pushed, sizeof pushed);
    input_decoder_destroy(d);
}

Test(input_hid, too_many_usages_are_refused) {
    uint8_t desc[2 + 2 * 1100 + 2];
    size_t n = 0;
    desc[n++] = 0x05, desc[n++] = 0x01;
    for (int i = 0; i < 1100; i++) desc[n++] = 0x09, desc[n++] = 0x30;
    expect_refused(desc, n, CORE_ERROR_RANGE);
}

Test(input_hid, nothing_to_read_is_refused) {
    /* A keyboard: modifier bits and an array of key codes; no stick, hat or buttons. */
    const uint8_t keyboard[] = {
        0x05, 0x01, 0x09, 0x06, 0xa1, 0x01,
        0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02,
        0x95, 0x06, 0x75, 0x08, 0x15, 0x00, 0x25, 0x65, 0x19, 0x00, 0x29, 0x65, 0x81, 0x00,
        0xc0,
    };
    expect_refused(keyboard, sizeof keyboard, CORE_ERROR_FORMAT);
    core_error error = { 0 };
    cr_expect_null(input_decoder_create(&(input_decoder_desc){ .vendor_id = 0x046d, .product_id = 0xc31c,
                                                               .descriptor = keyboard,
                                                               .descriptor_size = sizeof keyboard },
                                        &error));
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "%s", error.message);
    cr_expect(strstr(error.message, "046d:c31c") != NULL, "names the pad: %s", error.message);
    /* X alone is not a stick; a constant (padding) button is not a button. */
    const uint8_t x_only[] = {
        0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x09, 0x30, 0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x01,
        0x81, 0x02, 0x05, 0x09, 0x09, 0x01, 0x25, 0x01, 0x75, 0x01, 0x81, 0x03, 0xc0,
    };
    expect_refused(x_only, sizeof x_only, CORE_ERROR_FORMAT);
}

/* Random mutations of the good descriptors: whatever is accepted decodes random reports into
 * states within range; whatever is refused says why. A cheap in-test cousin of the fuzz target. */
Test(input_hid, mutated_descriptors_stay_in_bounds) {
    uint64_t seed = 0x9e3779b97f4a7c15ull;
    for (int round = 0; round < 3000; round++) {
        const uint8_t *base = round % 3 == 0 ? pad_plain : round % 3 == 1 ? pad_with_ids : joystick_16bit;
        size_t size = round % 3 == 0 ? sizeof pad_plain : round % 3 == 1 ? sizeof pad_with_ids : sizeof joystick_16bit;
        uint8_t *desc = malloc(size);
        memcpy(desc, base, size);
        for (int m = 0; m < 3; m++) {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            desc[(seed >> 33) % size] = (uint8_t)(seed >> 20);
        }
        input_hid_layout layout;
        core_error error = { 0 };
        if (input__hid_layout_parse(desc, size, &layout, &error)) {
            for (int k = 0; k < 20; k++) {
                uint8_t report[64];
                for (size_t i = 0; i < sizeof report; i++) {
                    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                    report[i] = (uint8_t)(seed >> 40);
                }
                if (layout.uses_report_ids && layout.report_count) report[0] = layout.reports[k % layout.report_count].id;
                input_gamepad_state s = { 0 };
                size_t length = (size_t)(seed >> 58) + 1;
                input_decode_failure failure;
                if (input__hid_decode(&layout, report, length, &s, &failure) == INPUT_DECODE_OK) {
                    cr_expect(s.lx >= -1 && s.lx <= 1 && s.ly >= -1 && s.ly <= 1);
                    cr_expect(s.rx >= -1 && s.rx <= 1 && s.ry >= -1 && s.ry <= 1);
                    cr_expect(s.lt >= 0 && s.lt <= 1 && s.rt >= 0 && s.rt <= 1);
                    cr_expect_eq(s.buttons >> INPUT_BUTTON_COUNT, 0u);
                }
            }
        } else {
            cr_expect_neq(error.code, CORE_ERROR_NONE);
            cr_expect_neq(error.message[0], '\0');
        }
        free(desc);
    }
}
