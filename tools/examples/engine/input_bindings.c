/* input_bindings — bindings and report decoders, with no device (engine/input/input.h):
 *
 *   1. bindings from a text (what data/input/bindings.txt holds and a player edits): a line
 *      that remaps jump, and a misspelt line that is reported with its name and line number,
 *      counted and skipped while the rest applies;
 *   2. an input system made with them and no devices (.no_gamepads, no window): what a frame's
 *      actions are when nothing is pressed;
 *   3. a report decoder fed a scripted sequence of DualShock 4 reports (the bytes hid_read gives),
 *      one of them a byte short: each decoded state printed, the bad one named and skipped;
 *   4. the last decoded state and a key fed to the input system (input_feed_gamepad,
 *      input_feed_key: what a test, a script or a network peer does): the actions they make
 *      through the bindings of 1.
 *
 *   input_bindings [--threads N] [--trace FILE]
 *
 * tools/hidreplay decodes a recorded file of reports the same way.
 */
#include "core/core.h"
#include "input/input.h"

#include <GLFW/glfw3.h>   /* key codes for input_feed_key */
#include "trace/trace.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* The pad's buttons by name ("south east"), or "-" when none is down. */
static const char *button_names(uint32_t buttons, char *text, size_t size) {
    text[0] = 0;
    for (int b = 0; b < INPUT_BUTTON_COUNT; b++)
        if (buttons & (1u << b))
            snprintf(text + strlen(text), size - strlen(text), "%s%s", text[0] ? " " : "", input_button_name(b));
    return text[0] ? text : "-";
}

static const char *action_names(uint32_t bits, char *text, size_t size) {
    text[0] = 0;
    for (int a = 0; a < INPUT_ACTION_COUNT; a++)
        if (bits & INPUT_ACTION_BIT(a))
            snprintf(text + strlen(text), size - strlen(text), "%s%s", text[0] ? " " : "", input_action_name(a));
    return text[0] ? text : "none";
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const core_option options[] = { CORE_COMMON_OPTIONS(common) };
    core_cli cli = { .program = "input_bindings", .summary = "bindings from a text and a decoder fed scripted reports",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* 1. Bindings: the defaults, with these lines over them. */
    const char text[] =
        "# my bindings\n"
        "jump       = key:space, pad:east      # jump on the right face button\n"
        "crouch     = key:c, pad:south\n"
        "sprintt    = pad:lb                   # misspelt: reported and skipped\n"
        "look_speed = 0.004\n";
    int bad_lines = 0;
    input_bindings *bindings = input_bindings_parse(text, sizeof text - 1, "my_bindings.txt", &bad_lines);
    printf("input_bindings: bindings read, %d bad line skipped\n", bad_lines);

    /* 2. An input system with them and no device: nothing is down. */
    input_system *input = input_system_create(&(input_system_desc){ .bindings = bindings, .no_gamepads = true }, NULL);
    input_bindings_destroy(bindings);              /* the system keeps a copy */
    if (!input) return 1;
    input_update(input, 1.0f / 60.0f);
    char names[256];
    const input_actions *actions = input_actions_get(input);
    printf("input_bindings: no device, actions down: %s, move (%.1f, %.1f)\n",
           action_names(actions->down, names, sizeof names), actions->move_x, actions->move_y);

    /* 3. A DualShock 4 (054c:09cc) over Bluetooth, reduced reports of 10 bytes: report id 1,
     * sticks lx ly rx ry (0 … 255, 128 centred), the face buttons over the d-pad (8 = released;
     * cross 0x20, circle 0x40), two more button bytes, then the triggers l2 r2. */
    input_decoder *pad = input_decoder_create(&(input_decoder_desc){ .vendor_id = 0x054c, .product_id = 0x09cc },
                                              NULL);
    if (!pad) return 1;
    static const struct { uint8_t bytes[10]; size_t size; } script[] = {
        { { 0x01, 0x80, 0x80, 0x80, 0x80, 0x08, 0x00, 0x00, 0x00, 0x00 }, 10 },   /* at rest */
        { { 0x01, 0x00, 0x80, 0x80, 0x80, 0x28, 0x00, 0x00, 0x00, 0x00 }, 10 },   /* left, cross */
        { { 0x01, 0x80, 0x00, 0x80, 0x80, 0x48, 0x00, 0x00, 0x00, 0xff }, 10 },   /* up, circle, r2 */
        { { 0x01, 0x80, 0x00, 0x80, 0x80, 0x48, 0x00, 0x00, 0x00 }, 9 },          /* a byte short */
    };
    input_gamepad_state state = { 0 };
    for (int i = 0; i < (int)CORE_COUNTOF(script); i++) {
        core_error why = { 0 };                    /* NULL instead: no text is formatted */
        input_decode_result result = input_decoder_decode(pad, script[i].bytes, script[i].size, &state, &why);
        if (result != INPUT_DECODE_OK) {           /* state is left as it was */
            printf("input_bindings: report %d: %s\n", i + 1, why.message);
            continue;
        }
        input_apply_dead_zone(&state, 0.15f);
        printf("input_bindings: report %d: stick (%.2f, %.2f), r2 %.1f, buttons %s\n", i + 1, state.lx, state.ly,
               state.rt, button_names(state.buttons, names, sizeof names));
    }
    input_decoder_stats_info stats = input_decoder_stats(pad);
    printf("input_bindings: %llu reports decoded, %llu too short\n", (unsigned long long)stats.decoded,
           (unsigned long long)stats.short_reports);
    input_decoder_destroy(pad);

    /* 4. The last good state (stick up, circle = east, r2) as pad 0, and the C key, fed to the
     *    input system: the next frame's actions come from them through the bindings of 1. */
    input_feed_gamepad(input, 0, &state);
    input_feed_key(input, GLFW_KEY_C, true);
    input_update(input, 1.0f / 60.0f);
    actions = input_actions_get(input);
    printf("input_bindings: fed pad and key, actions down: %s, move (%.1f, %.1f)\n",
           action_names(actions->down, names, sizeof names), actions->move_x, actions->move_y);
    input_system_destroy(input);
    trace_stop();
    return 0;
}

/* Expected output:
 * Run: --threads 1
 * ^input_bindings: bindings read, 1 bad line skipped$
 * ^input_bindings: no device, actions down: none, move \(0\.0, 0\.0\)$
 * ^input_bindings: report 1: stick \(0\.00, 0\.00\), r2 0\.0, buttons -$
 * ^input_bindings: report 2: stick \(-1\.00, 0\.00\), r2 0\.0, buttons south$
 * ^input_bindings: report 3: stick \(0\.00, -1\.00\), r2 1\.0, buttons east$
 * ^input_bindings: report 4: report too short: 9 bytes, need 10$
 * ^input_bindings: 3 reports decoded, 1 too short$
 * ^input_bindings: fed pad and key, actions down: jump crouch tool, move \(0\.0, 1\.0\)$
 */
