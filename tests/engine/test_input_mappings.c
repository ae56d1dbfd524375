/* Tests of the SDL game controller mappings (engine/input/input_mappings.c): a hand-built mapping
 * line turns a hand-built raw joystick into the pad state and the actions worked out by hand from
 * the format's rules; bad lines are reported with their file name and line number and skipped;
 * GUIDs give their vendor and product ids. Default bindings (dead zone 0.15, stick_look_speed 3). */
#include "input/input.h"
#include "input/input_internal.h"
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#define BIT(action) INPUT_ACTION_BIT(INPUT_ACTION_##action)
#define PAD(button) (1u << INPUT_BUTTON_##button)

/* An Xbox 360 pad's GUID as Linux gives it (bus 3, vendor 045e, product 028e, version 0114), with
 * elements in unusual places so that only the mapping can put them right: south on button 3, the
 * left stick's y inverted, the right trigger on the upper half of axis 5, the right stick's x
 * driven by two buttons, the d-pad on hat 0. */
static const char hand_line[] = "030000005e0400008e02000014010000,Hand Pad,a:b3,b:b1,x:b2,y:b0,"
                                "leftx:a0,lefty:a1~,righttrigger:+a5,-rightx:b7,+rightx:b6,"
                                "dpup:h0.1,dpright:h0.2,dpdown:h0.4,dpleft:h0.8,platform:Linux,";

static input_sdl_mapping parse_ok(const char *line) {
    input_sdl_mapping m;
    core_error error = { 0 };
    cr_assert(input__sdl_mapping_parse(line, strlen(line), &m, &error), "%s: %s", line, error.message);
    return m;
}

Test(input_mappings, hand_built_line_maps_a_raw_joystick_to_the_pad) {
    input_sdl_mapping m = parse_ok(hand_line);
    cr_expect_str_eq(m.guid, "030000005e0400008e02000014010000");
    cr_expect_str_eq(m.name, "Hand Pad");
    cr_expect(!m.other_platform);

    /* Raw: button 3 (a → south) and 6 (+rightx) down, axis 1 at +0.8 (inverted: up), axis 5 at
     * 0.6 (upper half: t = 0.6), hat 0 = 4 (down). */
    float axes[6] = { 0.0f, 0.8f, 0.0f, 0.0f, 0.0f, 0.6f };
    uint8_t buttons[8] = { 0, 0, 0, 1, 0, 0, 1, 0 }, hats[1] = { 4 };
    input_sdl_pad pad;
    input__sdl_mapping_apply(&m, &(input_sdl_joystick){ .axes = axes, .axis_count = 6, .buttons = buttons,
                                                        .button_count = 8, .hats = hats, .hat_count = 1 },
                             &pad);
    input_gamepad_state s;
    input__sdl_pad_to_state(&pad, &s);
    cr_expect_eq(s.buttons, PAD(SOUTH) | PAD(DPAD_DOWN));
    cr_expect_float_eq(s.lx, 0.0f, 1e-6f);
    cr_expect_float_eq(s.ly, -0.8f, 1e-6f);        /* ~: −0.8, y down positive: pushed up */
    cr_expect_float_eq(s.rx, 1.0f, 1e-6f);         /* +rightx from button 6 alone */
    cr_expect_float_eq(s.rt, 0.6f, 1e-6f);         /* righttrigger 2·0.6 − 1 = 0.2 → (0.2 + 1)/2 */
    cr_expect_float_eq(s.lt, 0.0f, 1e-6f);         /* unmapped: released */

    /* Through the default bindings, dt 0.1: south is jump; rt 0.6 is past half way, so tool is
     * down; the left stick at 0.8 up gives move_y (0.8 − 0.15)/(1 − 0.15) = 0.764706; the right
     * stick fully right turns 3 rad/s · 0.1 s = 0.3 rad. */
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true }, NULL);
    cr_assert_not_null(in);
    input_feed_gamepad(in, 0, &s);
    cr_assert(input_update(in, 0.1f));
    const input_actions *a = input_actions_get(in);
    cr_expect_eq(a->down, BIT(JUMP) | BIT(TOOL));
    cr_expect_float_eq(a->move_x, 0.0f, 1e-6f);
    cr_expect_float_eq(a->move_y, 0.65f / 0.85f, 1e-5f);
    cr_expect_float_eq(a->look_x, 0.3f, 1e-5f);
    cr_expect_float_eq(a->look_y, 0.0f, 1e-6f);
    input_system_destroy(in);
}

Test(input_mappings, half_axes_hats_and_buttons_follow_the_format) {
    /* Both halves of leftx from the hat, lefty from the lower half of axis 2 ("-a2": t = −v),
     * the left trigger from a whole axis at rest (−1 → released), b from an axis past half. */
    input_sdl_mapping m = parse_ok("0300000000000000000000000000000a,Halves,-leftx:h0.8,+leftx:h0.2,"
                                   "lefty:-a2,lefttrigger:a3,b:a4,start:b0");
    float axes[5] = { 0.0f, 0.0f, -0.5f, -1.0f, 0.2f };
    uint8_t hats[1] = { 8 | 1 }; /* left and up */
    input_sdl_pad pad;
    input__sdl_mapping_apply(&m, &(input_sdl_joystick){ .axes = axes, .axis_count = 5, .hats = hats, .hat_count = 1 },
                             &pad);
    input_gamepad_state s;
    input__sdl_pad_to_state(&pad, &s);
    cr_expect_float_eq(s.lx, -1.0f, 1e-6f);        /* −t(left) + t(right) = −1 + 0 */
    cr_expect_float_eq(s.ly, 0.0f, 1e-6f);         /* t = 0.5 → 2·0.5 − 1 */
    cr_expect_float_eq(s.lt, 0.0f, 1e-6f);
    cr_expect_eq(s.buttons, PAD(EAST));            /* axis 4 at 0.2: t = 0.6 > 0.5; start: no buttons given */

    /* Elements past what the joystick has read as released or at rest, never out of bounds. */
    input__sdl_mapping_apply(&m, &(input_sdl_joystick){ 0 }, &pad);
    input__sdl_pad_to_state(&pad, &s);
    cr_expect_eq(s.buttons, 0u);
    cr_expect_float_eq(s.lx, 0.0f, 1e-6f);
}

Test(input_mappings, bad_lines_are_reported_with_their_line_number_and_skipped) {
    static const char text[] =
        "# a comment\n"                                                              /* 1 */
        "030000005e0400008e02000014010000,Good,a:b0,leftx:a0,platform:Linux,\n"      /* 2 */
        "030000005e0400008e02000014010001,Typo,a:b0,leftshoulderr:b4,\n"             /* 3: bad */
        "\n"                                                                         /* 4 */
        "03000000,Short GUID,a:b0,\n"                                                /* 5: bad */
        "030000005e0400008e02000014010002,Windows,a:b0,platform:Windows,\r\n"        /* 6: other OS */
        "030000005e0400008e02000014010003,Bad hat,dpup:h0.3,\n"                      /* 7: bad */
        "030000005e0400008e02000014010004,Twice,a:b0,a:b1\n"                         /* 8: bad */
        "030000005e0400008e02000014010005,Last,b:b1";                                /* 9 */
    fflush(stderr);
    FILE *sink = tmpfile();
    cr_assert_not_null(sink);
    int saved = dup(2);
    dup2(fileno(sink), 2);
    input_sdl_mappings ms = { 0 };
    int bad = -1;
    input__sdl_mappings_parse(&ms, text, sizeof text - 1, "pads.txt", &bad);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(sink);
    char log[2048];
    log[fread(log, 1, sizeof log - 1, sink)] = '\0';
    fclose(sink);

    cr_expect_eq(bad, 4);
    cr_expect(strstr(log, "pads.txt:3: unknown output 'leftshoulderr'"), "%s", log);
    cr_expect(strstr(log, "pads.txt:5: GUID"), "%s", log);
    cr_expect(strstr(log, "pads.txt:7: dpup: bad input 'h0.3'"), "%s", log);
    cr_expect(strstr(log, "pads.txt:8: a mapped twice"), "%s", log);
    cr_expect(!strstr(log, "pads.txt:6"), "%s", log);
    /* Kept: lines 2 and 9 (line 6 is for Windows), in GLFW's text too, each on a line. */
    cr_expect_eq(ms.count, 2u);
    cr_expect_not_null(input__sdl_mappings_find(&ms, "030000005E0400008E02000014010000"));
    cr_expect_not_null(input__sdl_mappings_find(&ms, "030000005e0400008e02000014010005"));
    cr_expect_str_eq(ms.text, "030000005e0400008e02000014010000,Good,a:b0,leftx:a0,platform:Linux,\n"
                              "030000005e0400008e02000014010005,Last,b:b1\n");
    input__sdl_mappings_free(&ms);
}

Test(input_mappings, an_unreadable_mappings_file_fails_create_with_an_io_error) {
    core_error error = { 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .no_gamepads = true,
                                                             .gamepad_mappings_path = "/nonexistent/pads.txt" },
                                       &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s", error.message);
    cr_expect_not_null(strstr(error.message, "/nonexistent/pads.txt"), "names the file: %s", error.message);
    input_sdl_mappings ms = { 0 };
    int bad = -1;
    error = (core_error){ 0 };
    cr_expect(!input__sdl_mappings_load(&ms, "/nonexistent/pads.txt", &bad, &error));
    cr_expect_eq(error.code, CORE_ERROR_IO);
    cr_expect_eq(bad, 0);
    input__sdl_mappings_free(&ms);
}

Test(input_mappings, every_kind_of_bad_line_is_refused) {
    static const char *const bad[] = {
        "",                                                     /* nothing */
        "030000005e0400008e02000014010000",                     /* no name */
        "030000005e0400008e0200001401000g,Pad,a:b0",            /* not hex */
        "030000005e0400008e02000014010000,,a:b0",               /* empty name */
        "030000005e0400008e02000014010000,Pad",                 /* maps nothing */
        "030000005e0400008e02000014010000,Pad,a",               /* no colon */
        "030000005e0400008e02000014010000,Pad,a:",              /* no input */
        "030000005e0400008e02000014010000,Pad,a:b",             /* no number */
        "030000005e0400008e02000014010000,Pad,a:b256",          /* button out of range */
        "030000005e0400008e02000014010000,Pad,a:x1",            /* unknown input kind */
        "030000005e0400008e02000014010000,Pad,+a:b1",           /* a button has no halves */
        "030000005e0400008e02000014010000,Pad,a:+b1",           /* nor has its input */
        "030000005e0400008e02000014010000,Pad,leftx:a64",       /* axis out of range */
        "030000005e0400008e02000014010000,Pad,dpup:h16.1",      /* hat out of range */
        "030000005e0400008e02000014010000,Pad,dpup:h0",         /* hat without a bit */
        "030000005e0400008e02000014010000,Pad,a:b0,,b:b1",      /* empty field inside */
        "030000005e0400008e02000014010000,Pad,leftx:a0,-leftx:h0.8", /* whole and half */
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        input_sdl_mapping m;
        core_error error = { 0 };
        cr_expect(!input__sdl_mapping_parse(bad[i], strlen(bad[i]), &m, &error), "accepted '%s'", bad[i]);
        /* Each is a malformed line (none is too long: that is the file reader's check). */
        cr_expect_eq(error.code, CORE_ERROR_FORMAT, "'%s': %s (%s)", bad[i], core_error_code_name(error.code),
                     error.message);
        cr_expect(error.message[0], "no reason for '%s'", bad[i]);
    }
}

Test(input_mappings, guid_gives_vendor_and_product) {
    uint16_t vendor = 0, product = 0;
    cr_expect(input__guid_ids("030000005e0400008e02000014010000", &vendor, &product));
    cr_expect_eq(vendor, 0x045e);
    cr_expect_eq(product, 0x028e);
    cr_expect(input__guid_ids("050000004c050000cc09000000810000", &vendor, &product)); /* DS4 over Bluetooth */
    cr_expect_eq(vendor, 0x054c);
    cr_expect_eq(product, 0x09cc);
    /* The name form: bus, then the name's bytes ("Xbox Gamepad") */
    cr_expect(!input__guid_ids("0300000058626f782047616d65706100", &vendor, &product));
    cr_expect(!input__guid_ids("not a guid", &vendor, &product));
}

/* The duplicate rule (input_internal.h): a GLFW joystick is left to hidraw when hidraw has a pad
 * of its ids open — as many joysticks of those ids as hidraw has pads of them. */
Test(input_mappings, a_pad_open_on_hidraw_is_not_read_through_glfw_again) {
    input_pad_slot slots[INPUT_MAX_GAMEPADS] = { 0 };
    slots[2] = (input_pad_slot){ .claimed = true, .hidraw = true, .vendor_id = 0x045e, .product_id = 0x028e,
                                 .name = "Controller" };
    slots[5] = (input_pad_slot){ .claimed = true, .hidraw = false, .vendor_id = 0x054c, .product_id = 0x09cc };
    const char *xbox = "030000005e0400008e02000014010000", *ds4 = "030000004c050000cc09000011010000";
    cr_expect(input__glfw_pad_is_duplicate(slots, xbox, "Microsoft X-Box 360 pad", 0));
    /* A second pad of the same kind: hidraw reads only one, so GLFW reads the other. */
    cr_expect(!input__glfw_pad_is_duplicate(slots, xbox, "Microsoft X-Box 360 pad", 1));
    /* Slot 5 is GLFW's own claim, not hidraw's. */
    cr_expect(!input__glfw_pad_is_duplicate(slots, ds4, "Sony Wireless Controller", 0));
    /* A GUID without ids: by name. */
    cr_expect(input__glfw_pad_is_duplicate(slots, "0300000058626f782047616d65706100", "Xbox Controller", 0));
    cr_expect(!input__glfw_pad_is_duplicate(slots, "0300000058626f782047616d65706100", "Other Pad", 0));
    /* Nothing on hidraw: nothing is a duplicate. */
    slots[2].claimed = false;
    cr_expect(!input__glfw_pad_is_duplicate(slots, xbox, "Microsoft X-Box 360 pad", 0));
}

Test(input_mappings, slots_are_claimed_once_and_released) {
    input_pads_shared shared;
    input__pads_shared_init(&shared);
    int taken[INPUT_MAX_GAMEPADS];
    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++) {
        taken[i] = input__pad_slot_claim(&shared, i & 1, 0x1234, (uint16_t)i, "pad");
        cr_expect_eq(taken[i], i);
    }
    cr_expect_eq(input__pad_slot_claim(&shared, true, 1, 2, "ninth"), -1);
    input__pad_slot_release(&shared, 3);
    cr_expect(!shared.slots[3].claimed);
    cr_expect_eq(input__pad_slot_claim(&shared, false, 1, 2, "again"), 3);
    cr_expect_str_eq(shared.slots[3].name, "again");
    cr_expect(!shared.slots[3].hidraw);
    input__pads_shared_destroy(&shared);
}
