/* test_input_decode.c — the known pads' report decoders, the gamepad-state helpers and the dead
 * zone (engine/input/input_decode.c).
 *
 * Every report here is built byte by byte from the published layouts (Linux hid-playstation.c and
 * hid-nintendo.c structs, SDL's HIDAPI drivers; the offsets are restated next to each builder),
 * and every expected value is worked out by hand: 8-bit axes (2v − 255)/255, triggers v/255,
 * Switch sticks (raw − 2048)/1433 with y negated. The Bluetooth CRC comes from a bitwise CRC-32
 * written here, checked against the standard check value first.
 */
#include "input_decode_test.h"

#include "input/input.h"

#include <math.h>
#include <string.h>


static input_decoder *decoder_for(uint16_t vendor_id, uint16_t product_id) {
    core_error error = { 0 };
    input_decoder *d = input_decoder_create(&(input_decoder_desc){ .vendor_id = vendor_id, .product_id = product_id },
                                            &error);
    cr_assert_not_null(d, "%04x:%04x: %s", vendor_id, product_id, error.message);
    return d;
}

/* ---- a reference CRC-32 (bit by bit) for the Sony Bluetooth reports ------------------------- */

static uint32_t crc32_bitwise(uint32_t crc, const uint8_t *bytes, size_t size) {
    crc = ~crc;
    for (size_t i = 0; i < size; i++) {
        crc ^= bytes[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1)));
    }
    return ~crc;
}

/* hid-playstation: CRC-32 over the byte 0xa1 then the report's first 74 bytes, stored LE at 74. */
static void sony_bt_seal(uint8_t report[78]) {
    uint8_t seed = 0xa1;
    uint32_t crc = crc32_bitwise(crc32_bitwise(0, &seed, 1), report, 74);
    report[74] = (uint8_t)crc;
    report[75] = (uint8_t)(crc >> 8);
    report[76] = (uint8_t)(crc >> 16);
    report[77] = (uint8_t)(crc >> 24);
}

Test(input_decode, reference_crc_is_crc32) {
    cr_assert_eq(crc32_bitwise(0, (const uint8_t *)"123456789", 9), 0xcbf43926u);
}

/* ---- report builders, straight from the layouts ---------------------------------------------- */

/* DualShock 4 USB report 0x01 (64 bytes): 1 lx, 2 ly, 3 rx, 4 ry, 5 hat | square<<4 cross<<5
 * circle<<6 triangle<<7, 6 L1 R1 L2 R2 share options L3 R3, 7 PS | touchpad<<1 | counter<<2,
 * 8 L2, 9 R2. */
typedef struct sony_input {
    uint8_t lx, ly, rx, ry, b0, b1, b2, l2, r2;
} sony_input;

static const sony_input sony_idle = { 0x80, 0x80, 0x80, 0x80, 0x08, 0, 0, 0, 0 };

static void ds4_usb(uint8_t r[64], sony_input in) {
    memset(r, 0, 64);
    r[0] = 0x01;
    r[1] = in.lx, r[2] = in.ly, r[3] = in.rx, r[4] = in.ry;
    r[5] = in.b0, r[6] = in.b1, r[7] = in.b2, r[8] = in.l2, r[9] = in.r2;
    r[30] = 0x1b; /* status byte 1: a battery level, cable; byte 31 (adapter flag) left 0 */
}

/* DualShock 4 Bluetooth report 0x11 (78 bytes): 1 flags (0xc0: HID + CRC), 2 reserved, then the
 * USB bytes 1-9 at 3-11; CRC at 74. */
static void ds4_bt(uint8_t r[78], sony_input in) {
    memset(r, 0, 78);
    r[0] = 0x11;
    r[1] = 0xc0;
    r[3] = in.lx, r[4] = in.ly, r[5] = in.rx, r[6] = in.ry;
    r[7] = in.b0, r[8] = in.b1, r[9] = in.b2, r[10] = in.l2, r[11] = in.r2;
    r[12] = 0xff; /* the sensor timestamp, not a trigger */
    sony_bt_seal(r);
}

/* The reduced Bluetooth report 0x01: 10 bytes, USB bytes 0-9. */
static void sony_short(uint8_t r[10], sony_input in) {
    const uint8_t bytes[10] = { 0x01, in.lx, in.ly, in.rx, in.ry, in.b0, in.b1, in.b2, in.l2, in.r2 };
    memcpy(r, bytes, 10);
}

/* DualSense USB report 0x01 (64 bytes): 1 lx, 2 ly, 3 rx, 4 ry, 5 L2, 6 R2, 7 counter,
 * 8 hat + face, 9 L1 R1 L2 R2 create options L3 R3, 10 PS | touchpad<<1 | mute<<2. */
static void ds_usb(uint8_t r[64], sony_input in) {
    memset(r, 0, 64);
    r[0] = 0x01;
    r[1] = in.lx, r[2] = in.ly, r[3] = in.rx, r[4] = in.ry;
    r[5] = in.l2, r[6] = in.r2, r[7] = 0x5a; /* a counter value */
    r[8] = in.b0, r[9] = in.b1, r[10] = in.b2;
}

/* DualSense Bluetooth report 0x31 (78 bytes): 1 sequence/tag, then USB bytes 1-10 at 2-11. */
static void ds_bt(uint8_t r[78], sony_input in) {
    memset(r, 0, 78);
    r[0] = 0x31;
    r[1] = 0x10;
    r[2] = in.lx, r[3] = in.ly, r[4] = in.rx, r[5] = in.ry;
    r[6] = in.l2, r[7] = in.r2, r[8] = 0x77;
    r[9] = in.b0, r[10] = in.b1, r[11] = in.b2;
    sony_bt_seal(r);
}

/* ---- names and ids ---------------------------------------------------------------------------- */

Test(input_decode, button_names_round_trip) {
    const char *expected[INPUT_BUTTON_COUNT] = {
        "south", "east", "west", "north", "lb", "rb", "ls", "rs", "back", "start", "guide",
        "dpad_up", "dpad_down", "dpad_left", "dpad_right", "touchpad", "misc",
    };
    for (int b = 0; b < INPUT_BUTTON_COUNT; b++) {
        cr_expect_str_eq(input_button_name((input_button)b), expected[b]);
        cr_expect_eq(input_button_from_name(expected[b]), (input_button)b);
    }
    cr_expect_eq(input_button_from_name("cross"), INPUT_BUTTON_COUNT);
    cr_expect_eq(input_button_from_name(""), INPUT_BUTTON_COUNT);
    cr_expect_eq(input_button_from_name(NULL), INPUT_BUTTON_COUNT);
    cr_expect_not_null(input_button_name(INPUT_BUTTON_COUNT));
}

Test(input_decode, kinds_from_ids) {
    struct { uint16_t vid, pid; input_gamepad_kind kind; } known[] = {
        { 0x054c, 0x05c4, INPUT_GAMEPAD_DUALSHOCK4 }, { 0x054c, 0x09cc, INPUT_GAMEPAD_DUALSHOCK4 },
        { 0x054c, 0x0ba0, INPUT_GAMEPAD_DUALSHOCK4 }, { 0x054c, 0x0ce6, INPUT_GAMEPAD_DUALSENSE },
        { 0x054c, 0x0df2, INPUT_GAMEPAD_DUALSENSE },  { 0x057e, 0x2009, INPUT_GAMEPAD_SWITCH_PRO },
    };
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++) {
        input_gamepad_kind kind = INPUT_GAMEPAD_GENERIC;
        cr_expect(input_gamepad_kind_from_ids(known[i].vid, known[i].pid, &kind));
        cr_expect_eq(kind, known[i].kind);
        input_decoder *d = decoder_for(known[i].vid, known[i].pid);
        cr_expect_eq(input_decoder_kind(d), known[i].kind);
        input_decoder_destroy(d);
    }
    input_gamepad_kind kind = INPUT_GAMEPAD_DUALSENSE;
    cr_expect_not(input_gamepad_kind_from_ids(0x054c, 0x0268, &kind)); /* DualShock 3: not ours */
    cr_expect_not(input_gamepad_kind_from_ids(0x045e, 0x028e, &kind));
    cr_expect_str_eq(input_gamepad_kind_name(INPUT_GAMEPAD_GENERIC), "generic");
    cr_expect_str_eq(input_gamepad_kind_name(INPUT_GAMEPAD_DUALSHOCK4), "dualshock4");
    cr_expect_str_eq(input_gamepad_kind_name(INPUT_GAMEPAD_DUALSENSE), "dualsense");
    cr_expect_str_eq(input_gamepad_kind_name(INPUT_GAMEPAD_SWITCH_PRO), "switch_pro");
}

Test(input_decode, unknown_pad_needs_a_descriptor) {
    core_error error = { 0 };
    input_decoder *d = input_decoder_create(&(input_decoder_desc){ .vendor_id = 0x1234, .product_id = 0xabcd },
                                            &error);
    cr_expect_null(d);
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s: %s", core_error_code_name(error.code), error.message);
    cr_expect(strstr(error.message, "1234:abcd") != NULL, "names the pad: %s", error.message);
    cr_expect_null(input_decoder_create(&(input_decoder_desc){ .vendor_id = 0x1234 }, NULL));
    error = (core_error){ 0 };
    cr_expect_null(input_decoder_create(NULL, &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT);
    /* A known pad ignores a descriptor, even a useless one. */
    const uint8_t junk[] = { 0xff };
    d = input_decoder_create(&(input_decoder_desc){ .vendor_id = 0x054c, .product_id = 0x09cc, .descriptor = junk,
                                                    .descriptor_size = 1 },
                             &error);
    cr_expect_not_null(d);
    input_decoder_destroy(d);
    input_decoder_destroy(NULL);
}

/* ---- DualShock 4 -------------------------------------------------------------------------------- */

Test(input_decode, ds4_centred_sticks_read_zero) {
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    uint8_t r[64];
    ds4_usb(r, sony_idle);
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    /* 0x80 is one count above the exact middle 127.5: (256 − 255)/255 = 1/255. */
    cr_expect_float_eq(s.lx, 1.0f / 255, EPS);
    cr_expect_float_eq(s.ly, 1.0f / 255, EPS);
    cr_expect_float_eq(s.rx, 1.0f / 255, EPS);
    cr_expect_float_eq(s.ry, 1.0f / 255, EPS);
    cr_expect_eq(s.lt, 0.0f);
    cr_expect_eq(s.rt, 0.0f);
    cr_expect_eq(s.buttons, 0u);
    input_decoder_destroy(d);
}

Test(input_decode, ds4_full_deflection_signs) {
    input_decoder *d = decoder_for(0x054c, 0x05c4);
    uint8_t r[64];
    /* left stick up-left, right stick down-right */
    ds4_usb(r, (sony_input){ .lx = 0x00, .ly = 0x00, .rx = 0xff, .ry = 0xff, .b0 = 0x08 });
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, -1.0f, "up is negative y");
    cr_expect_eq(s.rx, 1.0f);
    cr_expect_eq(s.ry, 1.0f, "down is positive y");
    /* a quarter: 0x40 = 64 → (128 − 255)/255 */
    ds4_usb(r, (sony_input){ .lx = 0x40, .ly = 0xc0, .rx = 0x80, .ry = 0x80, .b0 = 0x08 });
    s = decode_ok(d, r, sizeof r);
    cr_expect_float_eq(s.lx, -127.0f / 255, EPS);
    cr_expect_float_eq(s.ly, 129.0f / 255, EPS);
    input_decoder_destroy(d);
}

Test(input_decode, ds4_each_button_by_position) {
    struct { int byte; uint8_t bit; uint32_t want; } cases[] = {
        { 5, 0x10, BIT(INPUT_BUTTON_WEST) },    /* square */
        { 5, 0x20, BIT(INPUT_BUTTON_SOUTH) },   /* cross */
        { 5, 0x40, BIT(INPUT_BUTTON_EAST) },    /* circle */
        { 5, 0x80, BIT(INPUT_BUTTON_NORTH) },   /* triangle */
        { 6, 0x01, BIT(INPUT_BUTTON_LB) },      /* L1 */
        { 6, 0x02, BIT(INPUT_BUTTON_RB) },      /* R1 */
        { 6, 0x10, BIT(INPUT_BUTTON_BACK) },    /* share */
        { 6, 0x20, BIT(INPUT_BUTTON_START) },   /* options */
        { 6, 0x40, BIT(INPUT_BUTTON_LS) },      /* L3 */
        { 6, 0x80, BIT(INPUT_BUTTON_RS) },      /* R3 */
        { 7, 0x01, BIT(INPUT_BUTTON_GUIDE) },   /* PS */
        { 7, 0x02, BIT(INPUT_BUTTON_TOUCHPAD) },
        { 7, 0xfc, 0 },                          /* the frame counter is not a button */
    };
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        uint8_t r[64];
        ds4_usb(r, sony_idle);
        r[cases[i].byte] |= cases[i].bit;
        input_gamepad_state s = decode_ok(d, r, sizeof r);
        cr_expect_eq(s.buttons, cases[i].want, "byte %d bit 0x%02x: buttons 0x%x", cases[i].byte, cases[i].bit,
                     s.buttons);
    }
    input_decoder_destroy(d);
}


Test(input_decode, ds4_hat_values) {
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    for (uint8_t hat = 0; hat < 16; hat++) {
        uint8_t r[64];
        sony_input in = sony_idle;
        in.b0 = hat | 0x20; /* with cross held, so the nibble is read alone */
        ds4_usb(r, in);
        input_gamepad_state s = decode_ok(d, r, sizeof r);
        cr_expect_eq(s.buttons, hat_dpad[hat] | BIT(INPUT_BUTTON_SOUTH), "hat %u: 0x%x", hat, s.buttons);
    }
    input_decoder_destroy(d);
}

Test(input_decode, ds4_triggers) {
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    uint8_t r[64];
    sony_input in = sony_idle;
    in.l2 = 0xff, in.r2 = 0x80, in.b1 = 0x0c;
    ds4_usb(r, in);
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lt, 1.0f);
    cr_expect_float_eq(s.rt, 128.0f / 255, EPS);
    cr_expect_eq(s.buttons, 0u, "the triggers' digital bits are not buttons");
    in.l2 = 0, in.r2 = 0, in.b1 = 0;
    ds4_usb(r, in);
    s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lt, 0.0f);
    cr_expect_eq(s.rt, 0.0f);
    /* A fight stick that sets only the digital bits reads as fully pressed. */
    in.b1 = 0x04;
    ds4_usb(r, in);
    s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lt, 1.0f);
    cr_expect_eq(s.rt, 0.0f);
    input_decoder_destroy(d);
}

Test(input_decode, ds4_bluetooth_offsets) {
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    uint8_t r[78];
    ds4_bt(r, (sony_input){ .lx = 0x00, .ly = 0xff, .rx = 0x40, .ry = 0x80, .b0 = 0x26, .b1 = 0x21, .b2 = 0x02,
                            .l2 = 0x33, .r2 = 0xff });
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_eq(s.ly, 1.0f);
    cr_expect_float_eq(s.rx, -127.0f / 255, EPS);
    cr_expect_float_eq(s.ry, 1.0f / 255, EPS);
    cr_expect_float_eq(s.lt, 51.0f / 255, EPS);
    cr_expect_eq(s.rt, 1.0f);
    /* b0 0x26: hat 6 (left) + cross; b1 0x21: L1 + options; b2 0x02: touchpad */
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_DPAD_LEFT) | BIT(INPUT_BUTTON_SOUTH) | BIT(INPUT_BUTTON_LB) |
                                BIT(INPUT_BUTTON_START) | BIT(INPUT_BUTTON_TOUCHPAD));
    input_decoder_destroy(d);
}

Test(input_decode, ds4_reduced_bluetooth_report) {
    input_decoder *d = decoder_for(0x054c, 0x05c4);
    uint8_t r[10];
    sony_short(r, (sony_input){ .lx = 0xff, .ly = 0x00, .rx = 0x80, .ry = 0x80, .b0 = 0x80 | 0x02, .b1 = 0x80,
                                .b2 = 0x01, .l2 = 0x00, .r2 = 0x66 });
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, -1.0f);
    cr_expect_float_eq(s.rt, 102.0f / 255, EPS);
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_NORTH) | BIT(INPUT_BUTTON_DPAD_RIGHT) | BIT(INPUT_BUTTON_RS) |
                                BIT(INPUT_BUTTON_GUIDE));
    input_decoder_destroy(d);
}

Test(input_decode, ds4_bad_sizes_and_ids) {
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    uint8_t r[96];
    ds4_usb(r, sony_idle);
    memset(r + 64, 0, 32);
    expect_rejected(d, r, 9, INPUT_DECODE_SHORT);
    cr_expect_str_eq(last_rejection.message, "report too short: 9 bytes, need 10");
    expect_rejected(d, r, 0, INPUT_DECODE_SHORT);
    expect_rejected(d, NULL, 0, INPUT_DECODE_SHORT);
    expect_rejected(d, r, 65, INPUT_DECODE_OVERSIZED);
    cr_expect_str_eq(last_rejection.message, "report too long: 65 bytes, at most 64");
    uint8_t bt[96];
    ds4_bt(bt, sony_idle);
    memset(bt + 78, 0, 18);
    expect_rejected(d, bt, 77, INPUT_DECODE_SHORT);
    cr_expect_str_eq(last_rejection.message, "report too short: 77 bytes, need 78");
    expect_rejected(d, bt, 79, INPUT_DECODE_OVERSIZED);
    r[0] = 0x05; /* an output report's ID, never an input */
    expect_rejected(d, r, 32, INPUT_DECODE_UNKNOWN_ID);
    cr_expect(strstr(last_rejection.message, "0x05") != NULL, "names the ID: %s", last_rejection.message);
    input_decoder_stats_info stats = input_decoder_stats(d);
    cr_expect_eq(stats.decoded, 0u);
    cr_expect_eq(stats.short_reports, 4u);
    cr_expect_eq(stats.oversized, 2u);
    cr_expect_eq(stats.unknown_id, 1u);
    cr_expect_eq(stats.malformed, 0u);
    input_decoder_destroy(d);
}

Test(input_decode, ds4_malformed_reports) {
    input_decoder *d = decoder_for(0x054c, 0x0ba0);
    uint8_t r[64];
    ds4_usb(r, sony_idle);
    r[31] = 0x04; /* the wireless adapter: no controller paired */
    expect_rejected(d, r, sizeof r, INPUT_DECODE_MALFORMED);
    uint8_t bt[78];
    ds4_bt(bt, sony_idle);
    bt[1] = 0x40; /* no HID data in this report */
    sony_bt_seal(bt);
    expect_rejected(d, bt, sizeof bt, INPUT_DECODE_MALFORMED);
    cr_expect_eq(input_decoder_stats(d).malformed, 2u);
    input_decoder_destroy(d);
}

/* CRCs are enforced once the pad has shown it sends correct ones (3 reports); before that a wrong
 * CRC is let through, as SDL does for third-party pads. */
Test(input_decode, ds4_crc_enforced_once_trusted) {
    input_decoder *d = decoder_for(0x054c, 0x09cc);
    uint8_t bad[78];
    ds4_bt(bad, (sony_input){ .lx = 0xff, .ly = 0x80, .rx = 0x80, .ry = 0x80, .b0 = 0x08 });
    bad[74] ^= 0x01;
    input_gamepad_state s = decode_ok(d, bad, sizeof bad);
    cr_expect_eq(s.lx, 1.0f, "a clone's wrong CRC is accepted");
    uint8_t good[78];
    ds4_bt(good, sony_idle);
    for (int i = 0; i < 3; i++) decode_ok(d, good, sizeof good);
    expect_rejected(d, bad, sizeof bad, INPUT_DECODE_MALFORMED);
    cr_expect_str_eq(last_rejection.message, "malformed report: CRC mismatch");
    /* A corrupted byte anywhere in the covered range is caught too. */
    memcpy(bad, good, sizeof good);
    bad[40] ^= 0x80;
    expect_rejected(d, bad, sizeof bad, INPUT_DECODE_MALFORMED);
    decode_ok(d, good, sizeof good);
    input_decoder_stats_info stats = input_decoder_stats(d);
    cr_expect_eq(stats.decoded, 5u);
    cr_expect_eq(stats.malformed, 2u);
    input_decoder_destroy(d);
}

/* ---- DualSense ---------------------------------------------------------------------------------- */

Test(input_decode, dualsense_usb_layout) {
    input_decoder *d = decoder_for(0x054c, 0x0ce6);
    uint8_t r[64];
    ds_usb(r, sony_idle);
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_float_eq(s.lx, 1.0f / 255, EPS);
    cr_expect_float_eq(s.ry, 1.0f / 255, EPS);
    cr_expect_eq(s.buttons, 0u);
    ds_usb(r, (sony_input){ .lx = 0xff, .ly = 0x00, .rx = 0x00, .ry = 0xff, .b0 = 0x08, .l2 = 0xff, .r2 = 0x80 });
    s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, -1.0f);
    cr_expect_eq(s.rx, -1.0f);
    cr_expect_eq(s.ry, 1.0f);
    cr_expect_eq(s.lt, 1.0f);
    cr_expect_float_eq(s.rt, 128.0f / 255, EPS);
    input_decoder_destroy(d);
}

Test(input_decode, dualsense_buttons) {
    struct { int byte; uint8_t bit; uint32_t want; } cases[] = {
        { 8, 0x10, BIT(INPUT_BUTTON_WEST) },   { 8, 0x20, BIT(INPUT_BUTTON_SOUTH) },
        { 8, 0x40, BIT(INPUT_BUTTON_EAST) },   { 8, 0x80, BIT(INPUT_BUTTON_NORTH) },
        { 9, 0x01, BIT(INPUT_BUTTON_LB) },     { 9, 0x02, BIT(INPUT_BUTTON_RB) },
        { 9, 0x10, BIT(INPUT_BUTTON_BACK) },   /* create */
        { 9, 0x20, BIT(INPUT_BUTTON_START) },  /* options */
        { 9, 0x40, BIT(INPUT_BUTTON_LS) },     { 9, 0x80, BIT(INPUT_BUTTON_RS) },
        { 10, 0x01, BIT(INPUT_BUTTON_GUIDE) }, { 10, 0x02, BIT(INPUT_BUTTON_TOUCHPAD) },
        { 10, 0x04, BIT(INPUT_BUTTON_MISC) },  /* mute */
        { 7, 0xff, 0 },                         /* the counter */
    };
    input_decoder *d = decoder_for(0x054c, 0x0df2);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        uint8_t r[64];
        ds_usb(r, sony_idle);
        r[cases[i].byte] |= cases[i].bit;
        input_gamepad_state s = decode_ok(d, r, sizeof r);
        cr_expect_eq(s.buttons, cases[i].want, "byte %d bit 0x%02x: 0x%x", cases[i].byte, cases[i].bit, s.buttons);
    }
    for (uint8_t hat = 0; hat < 16; hat++) {
        uint8_t r[64];
        sony_input in = sony_idle;
        in.b0 = hat;
        ds_usb(r, in);
        cr_expect_eq(decode_ok(d, r, sizeof r).buttons, hat_dpad[hat], "hat %u", hat);
    }
    input_decoder_destroy(d);
}

Test(input_decode, dualsense_bluetooth_offsets) {
    input_decoder *d = decoder_for(0x054c, 0x0ce6);
    uint8_t r[78];
    ds_bt(r, (sony_input){ .lx = 0x00, .ly = 0x80, .rx = 0xff, .ry = 0x00, .b0 = 0x41, .b1 = 0x12, .b2 = 0x05,
                           .l2 = 0x10, .r2 = 0xff });
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, -1.0f);
    cr_expect_float_eq(s.ly, 1.0f / 255, EPS);
    cr_expect_eq(s.rx, 1.0f);
    cr_expect_eq(s.ry, -1.0f);
    cr_expect_float_eq(s.lt, 16.0f / 255, EPS);
    cr_expect_eq(s.rt, 1.0f);
    /* b0 0x41: hat 1 (up-right) + circle; b1 0x12: R1 + create; b2 0x05: PS + mute */
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_DPAD_UP) | BIT(INPUT_BUTTON_DPAD_RIGHT) | BIT(INPUT_BUTTON_EAST) |
                                BIT(INPUT_BUTTON_RB) | BIT(INPUT_BUTTON_BACK) | BIT(INPUT_BUTTON_GUIDE) |
                                BIT(INPUT_BUTTON_MISC));
    input_decoder_destroy(d);
}

Test(input_decode, dualsense_simple_bluetooth_report) {
    input_decoder *d = decoder_for(0x054c, 0x0ce6);
    uint8_t r[10];
    /* The simple report has the DS4 layout: triggers after the buttons, no counter, no mute. */
    sony_short(r, (sony_input){ .lx = 0x80, .ly = 0xff, .rx = 0x80, .ry = 0x80, .b0 = 0x14, .b1 = 0x01,
                                .b2 = 0x04, .l2 = 0xff, .r2 = 0x00 });
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.ly, 1.0f);
    cr_expect_eq(s.lt, 1.0f);
    cr_expect_eq(s.rt, 0.0f);
    cr_expect_eq(s.buttons, BIT(INPUT_BUTTON_DPAD_DOWN) | BIT(INPUT_BUTTON_WEST) | BIT(INPUT_BUTTON_LB));
    input_decoder_destroy(d);
}

Test(input_decode, dualsense_bad_reports) {
    input_decoder *d = decoder_for(0x054c, 0x0ce6);
    uint8_t r[80];
    ds_usb(r, sony_idle);
    memset(r + 64, 0, 16);
    expect_rejected(d, r, 9, INPUT_DECODE_SHORT);
    expect_rejected(d, r, 40, INPUT_DECODE_SHORT);
    cr_expect_str_eq(last_rejection.message, "report too short: 40 bytes, need 64");
    expect_rejected(d, r, 65, INPUT_DECODE_OVERSIZED);
    r[0] = 0x11; /* the DS4's Bluetooth ID */
    expect_rejected(d, r, 78, INPUT_DECODE_UNKNOWN_ID);
    uint8_t good[78], bad[78];
    ds_bt(good, sony_idle);
    expect_rejected(d, good, 77, INPUT_DECODE_SHORT);
    for (int i = 0; i < 3; i++) decode_ok(d, good, sizeof good);
    memcpy(bad, good, sizeof bad);
    bad[2] = 0x00; /* lx changed after the CRC was computed */
    expect_rejected(d, bad, sizeof bad, INPUT_DECODE_MALFORMED);
    input_decoder_stats_info stats = input_decoder_stats(d);
    cr_expect_eq(stats.decoded, 3u);
    cr_expect_eq(stats.short_reports, 3u);
    cr_expect_eq(stats.oversized, 1u);
    cr_expect_eq(stats.unknown_id, 1u);
    cr_expect_eq(stats.malformed, 1u);
    input_decoder_destroy(d);
}

/* ---- Switch Pro --------------------------------------------------------------------------------- */

/* Report 0x30: 1 timer, 2 battery/connection, 3 right buttons, 4 shared, 5 left, 6-8 left stick,
 * 9-11 right stick (12-bit x then 12-bit y: b0 = x low byte, b1 = x high nibble | y low nibble << 4,
 * b2 = y >> 4), 12 vibrator, then IMU data; 64 bytes over USB. */
static void switch_pack(uint8_t out[3], unsigned x, unsigned y) {
    out[0] = (uint8_t)(x & 0xff);
    out[1] = (uint8_t)((x >> 8) | (y & 0x0f) << 4);
    out[2] = (uint8_t)(y >> 4);
}

static void switch_report(uint8_t r[64], uint8_t right, uint8_t shared, uint8_t left, unsigned lx, unsigned ly,
                          unsigned rx, unsigned ry) {
    memset(r, 0, 64);
    r[0] = 0x30;
    r[1] = 0x42, r[2] = 0x91;
    r[3] = right, r[4] = shared, r[5] = left;
    switch_pack(r + 6, lx, ly);
    switch_pack(r + 9, rx, ry);
    r[12] = 0x0c;
}

Test(input_decode, switch_stick_packing_and_y_inversion) {
    input_decoder *d = decoder_for(0x057e, 0x2009);
    uint8_t r[64];
    switch_report(r, 0, 0, 0, 2048, 2048, 2048, 2048);
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, 0.0f);
    cr_expect_eq(s.ly, 0.0f);
    cr_expect_eq(s.rx, 0.0f);
    cr_expect_eq(s.ry, 0.0f);
    /* Bytes written out by hand: left x = 0x9c4 (2500), y = 0x5dc (1500) → c4 c9 5d. */
    const uint8_t left_stick[3] = { 0xc4, 0xc9, 0x5d };
    memcpy(r + 6, left_stick, 3);
    s = decode_ok(d, r, sizeof r);
    cr_expect_float_eq(s.lx, 452.0f / 1433, EPS);
    cr_expect_float_eq(s.ly, 548.0f / 1433, EPS, "raw y below centre is stick down: positive");
    /* Full deflections at the nominal range, and beyond it clamped. */
    switch_report(r, 0, 0, 0, 2048 + 1433, 2048 + 1433, 2048 - 1433, 0);
    s = decode_ok(d, r, sizeof r);
    cr_expect_float_eq(s.lx, 1.0f, EPS);
    cr_expect_float_eq(s.ly, -1.0f, EPS, "raw y up is screen up: negative");
    cr_expect_float_eq(s.rx, -1.0f, EPS);
    cr_expect_eq(s.ry, 1.0f);
    switch_report(r, 0, 0, 0, 4095, 0, 0, 4095);
    s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lx, 1.0f);
    cr_expect_eq(s.ly, 1.0f);
    cr_expect_eq(s.rx, -1.0f);
    cr_expect_eq(s.ry, -1.0f);
    input_decoder_destroy(d);
}

Test(input_decode, switch_buttons_by_position) {
    struct { int byte; uint8_t bit; uint32_t want; } cases[] = {
        { 3, 0x01, BIT(INPUT_BUTTON_WEST) },       /* Y */
        { 3, 0x02, BIT(INPUT_BUTTON_NORTH) },      /* X */
        { 3, 0x04, BIT(INPUT_BUTTON_SOUTH) },      /* B */
        { 3, 0x08, BIT(INPUT_BUTTON_EAST) },       /* A */
        { 3, 0x30, 0 },                             /* SR, SL (Joy-Con only) */
        { 3, 0x40, BIT(INPUT_BUTTON_RB) },         /* R */
        { 4, 0x01, BIT(INPUT_BUTTON_BACK) },       /* minus */
        { 4, 0x02, BIT(INPUT_BUTTON_START) },      /* plus */
        { 4, 0x04, BIT(INPUT_BUTTON_RS) },
        { 4, 0x08, BIT(INPUT_BUTTON_LS) },
        { 4, 0x10, BIT(INPUT_BUTTON_GUIDE) },      /* home */
        { 4, 0x20, BIT(INPUT_BUTTON_MISC) },       /* capture */
        { 5, 0x01, BIT(INPUT_BUTTON_DPAD_DOWN) },
        { 5, 0x02, BIT(INPUT_BUTTON_DPAD_UP) },
        { 5, 0x04, BIT(INPUT_BUTTON_DPAD_RIGHT) },
        { 5, 0x08, BIT(INPUT_BUTTON_DPAD_LEFT) },
        { 5, 0x30, 0 },
        { 5, 0x40, BIT(INPUT_BUTTON_LB) },         /* L */
    };
    input_decoder *d = decoder_for(0x057e, 0x2009);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        uint8_t r[64];
        switch_report(r, 0, 0, 0, 2048, 2048, 2048, 2048);
        r[cases[i].byte] |= cases[i].bit;
        input_gamepad_state s = decode_ok(d, r, sizeof r);
        cr_expect_eq(s.buttons, cases[i].want, "byte %d bit 0x%02x: 0x%x", cases[i].byte, cases[i].bit, s.buttons);
        cr_expect_eq(s.lt, 0.0f);
        cr_expect_eq(s.rt, 0.0f);
    }
    /* ZL and ZR are digital triggers. */
    uint8_t r[64];
    switch_report(r, 0x80, 0, 0x80, 2048, 2048, 2048, 2048);
    input_gamepad_state s = decode_ok(d, r, sizeof r);
    cr_expect_eq(s.lt, 1.0f);
    cr_expect_eq(s.rt, 1.0f);
    cr_expect_eq(s.buttons, 0u);
    input_decoder_destroy(d);
}

Test(input_decode, switch_bad_reports) {
    input_decoder *d = decoder_for(0x057e, 0x2009);
    uint8_t r[400];
    memset(r, 0, sizeof r);
    switch_report(r, 0, 0, 0, 2048, 2048, 2048, 2048);
    expect_rejected(d, r, 11, INPUT_DECODE_SHORT);
    cr_expect_str_eq(last_rejection.message, "report too short: 11 bytes, need 12");
    decode_ok(d, r, 12);
    decode_ok(d, r, 49); /* the Bluetooth size of 0x30 */
    expect_rejected(d, r, 363, INPUT_DECODE_OVERSIZED);
    r[0] = 0x21; /* a subcommand reply */
    expect_rejected(d, r, 64, INPUT_DECODE_UNKNOWN_ID);
    r[0] = 0x81; /* a USB command ack */
    expect_rejected(d, r, 64, INPUT_DECODE_UNKNOWN_ID);
    input_decoder_stats_info stats = input_decoder_stats(d);
    cr_expect_eq(stats.decoded, 2u);
    cr_expect_eq(stats.short_reports, 1u);
    cr_expect_eq(stats.oversized, 1u);
    cr_expect_eq(stats.unknown_id, 2u);
    input_decoder_destroy(d);
}

/* ---- results ------------------------------------------------------------------------------------ */

Test(input_decode, result_names) {
    cr_expect_str_eq(input_decode_result_name(INPUT_DECODE_OK), "ok");
    cr_expect_str_eq(input_decode_result_name(INPUT_DECODE_SHORT), "report too short");
    cr_expect_str_eq(input_decode_result_name(INPUT_DECODE_OVERSIZED), "report too long");
    cr_expect_str_eq(input_decode_result_name(INPUT_DECODE_MALFORMED), "malformed report");
    /* The detail goes to the caller's error, one per call; a later success leaves it as it was;
     * NULL asks for none. */
    input_decoder *d = decoder_for(0x057e, 0x2009);
    input_decoder *other = decoder_for(0x054c, 0x09cc);
    input_gamepad_state s = { 0 };
    const uint8_t ack[2] = { 0x81, 0x01 };
    core_error error = { 0 }, other_error = { 0 };
    cr_assert_eq(input_decoder_decode(d, ack, sizeof ack, &s, &error), INPUT_DECODE_UNKNOWN_ID);
    cr_assert_eq(input_decoder_decode(other, ack, 1, &s, &other_error), INPUT_DECODE_UNKNOWN_ID);
    cr_assert_eq(input_decoder_decode(other, ack, 1, &s, NULL), INPUT_DECODE_UNKNOWN_ID);
    cr_expect_eq(error.code, CORE_ERROR_FORMAT);
    cr_expect_eq(other_error.code, CORE_ERROR_FORMAT);
    cr_expect_str_eq(error.message, "unknown report ID 0x81 (2 bytes)");
    cr_expect_str_eq(other_error.message, "unknown report ID 0x81 (1 bytes)");
    uint8_t r[64];
    memset(r, 0, sizeof r);
    switch_report(r, 0, 0, 0, 2048, 2048, 2048, 2048);
    cr_assert_eq(input_decoder_decode(d, r, 12, &s, &error), INPUT_DECODE_OK);
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "a success leaves the error as it was");
    input_decoder_destroy(d);
    input_decoder_destroy(other);
}

/* ---- dead zone ---------------------------------------------------------------------------------- */

Test(input_decode, dead_zone_inside_is_zero) {
    input_gamepad_state s = { .lx = 0.1f, .ly = 0.1f, .rx = -0.14f, .ry = 0.0f, .lt = 0.05f, .rt = 0.5f,
                              .buttons = 3 };
    input_apply_dead_zone(&s, 0.2f); /* |(0.1, 0.1)| = 0.141 < 0.2 */
    cr_expect_eq(s.lx, 0.0f);
    cr_expect_eq(s.ly, 0.0f);
    cr_expect_eq(s.rx, 0.0f);
    cr_expect_eq(s.ry, 0.0f);
    cr_expect_eq(s.lt, 0.05f, "triggers have no dead zone");
    cr_expect_eq(s.rt, 0.5f);
    cr_expect_eq(s.buttons, 3u);
}

Test(input_decode, dead_zone_edge_and_rescale) {
    /* On the edge: r = radius → (r − radius)/(1 − radius) = 0. */
    input_gamepad_state s = { .lx = 0.0f, .ly = -0.25f, .rx = 0.15f, .ry = 0.2f };
    input_apply_dead_zone(&s, 0.25f);
    cr_expect_float_eq(s.lx, 0.0f, EPS);
    cr_expect_float_eq(s.ly, 0.0f, EPS);
    /* (0.15, 0.2): r = 0.25 exactly on the edge too */
    cr_expect_float_eq(s.rx, 0.0f, EPS);
    cr_expect_float_eq(s.ry, 0.0f, EPS);
    /* (0.3, −0.4): r = 0.5; with radius 0.2 the length becomes 0.3/0.8 = 0.375, direction (0.6, −0.8). */
    s = (input_gamepad_state){ .lx = 0.3f, .ly = -0.4f, .rx = -0.6f, .ry = 0.8f };
    input_apply_dead_zone(&s, 0.2f);
    cr_expect_float_eq(s.lx, 0.225f, EPS);
    cr_expect_float_eq(s.ly, -0.3f, EPS);
    /* (−0.6, 0.8): r = 1 → stays full deflection in the same direction. */
    cr_expect_float_eq(s.rx, -0.6f, EPS);
    cr_expect_float_eq(s.ry, 0.8f, EPS);
    /* A square-gated corner (1, 1): length clamped to 1, direction kept. */
    s = (input_gamepad_state){ .lx = 1.0f, .ly = 1.0f, .rx = -1.0f, .ry = 0.0f };
    input_apply_dead_zone(&s, 0.1f);
    cr_expect_float_eq(s.lx, 0.70710678f, EPS);
    cr_expect_float_eq(s.ly, 0.70710678f, EPS);
    cr_expect_float_eq(s.rx, -1.0f, EPS);
    cr_expect_float_eq(s.ry, 0.0f, EPS);
}

Test(input_decode, dead_zone_monotonic_and_bounded) {
    /* Invariants over a sweep: the output never exceeds 1, never points elsewhere, and grows
     * with the input. */
    for (int a = 0; a < 16; a++) {
        float angle = (float)a * 0.3927f, previous = 0.0f;
        for (int step = 0; step <= 40; step++) {
            float r = (float)step / 40.0f * 1.2f;
            input_gamepad_state s = { .lx = r * cosf(angle), .ly = r * sinf(angle) };
            input_apply_dead_zone(&s, 0.15f);
            float out = sqrtf(s.lx * s.lx + s.ly * s.ly);
            cr_expect_leq(out, 1.0f + EPS);
            cr_expect_geq(out, previous - EPS);
            if (out > 0) cr_expect_geq(s.lx * cosf(angle) + s.ly * sinf(angle), out - 1e-4f, "direction kept");
            previous = out;
        }
    }
}

Test(input_decode, dead_zone_degenerate_radii) {
    input_gamepad_state s = { .lx = 0.01f, .ly = 0.0f, .rx = 1.0f, .ry = 1.0f };
    input_gamepad_state before = s;
    input_apply_dead_zone(&s, 0.0f);
    cr_expect(memcmp(&s, &before, sizeof s) == 0, "radius 0 changes nothing");
    input_apply_dead_zone(&s, -1.0f);
    cr_expect(memcmp(&s, &before, sizeof s) == 0, "a negative radius changes nothing");
    input_apply_dead_zone(&s, NAN);
    cr_expect(memcmp(&s, &before, sizeof s) == 0, "NaN changes nothing");
    input_apply_dead_zone(&s, 1.0f);
    cr_expect_eq(s.lx, 0.0f);
    cr_expect_eq(s.rx, 0.0f);
    cr_expect_eq(s.ry, 0.0f);
}
