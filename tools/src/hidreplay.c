/* hidreplay — decodes recorded gamepad HID reports and prints one JSON line per report.
 *
 *     hidreplay 054c:09cc pad.bin                          # a DualShock 4 (known by its ids)
 *     hidreplay 0079:0006 pad.bin --descriptor desc.bin    # any pad, through its descriptor
 *     hidreplay 054c:0ce6 pad.bin --dead-zone 0.15         # sticks after the radial dead zone
 *
 * FILE holds the reports one after another, each preceded by its length as 2 bytes little-endian;
 * a report starts with its report ID where the device uses IDs (as hid_read returns it). Output:
 *     {"lx":0,"ly":-1,"rx":0.003921569,"ry":0,"lt":0,"rt":1,"buttons":["south","dpad_up"]}
 * with the axes in SDL's convention (y down) and the buttons in input_button order. A report that
 * does not decode prints {"error":"report too short: 9 bytes, need 10"} and the next one is read;
 * a record cut short at the end of the file prints an error line too.
 *
 * Exit status: 0 the file was read to its end; 1 it could not be read, was cut short, or the pad
 * cannot be decoded (unknown ids without --descriptor, an unusable descriptor); 2 bad arguments
 * or an unwritable --trace.
 */
#include "core/core.h"
#include "input/input.h"
#include "trace/trace.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Reads a whole file; NULL (after a message naming it) when it cannot. Free with core_free. */
static uint8_t *hidreplay_read_file(const char *path, size_t *size) {
    FILE *file = fopen(path, "rb");
    if (!file) {
        fprintf(stderr, "hidreplay: cannot open %s: %s\n", path, strerror(errno));
        return NULL;
    }
    size_t capacity = 0, used = 0;
    uint8_t *bytes = NULL;
    for (;;) {
        bytes = core_grow(bytes, &capacity, used + 65536, 1);
        size_t got = fread(bytes + used, 1, capacity - used, file);
        used += got;
        if (got == 0) break;
    }
    bool failed = ferror(file);
    int saved = errno;
    fclose(file);
    if (failed) {
        fprintf(stderr, "hidreplay: cannot read %s: %s\n", path, strerror(saved));
        core_free(bytes, capacity);
        return NULL;
    }
    /* Shrink to the exact size so the caller frees with the size it knows. */
    uint8_t *exact = core_alloc(used ? used : 1);
    memcpy(exact, bytes, used);
    core_free(bytes, capacity);
    *size = used;
    return exact;
}

/* "054c:09cc" → ids; false when it is not two hex numbers of at most 4 digits. */
static bool hidreplay_parse_ids(const char *text, uint16_t *vendor_id, uint16_t *product_id) {
    unsigned value[2];
    const char *at = text;
    for (int part = 0; part < 2; part++) {
        int digits = 0;
        value[part] = 0;
        for (; *at && *at != ':'; at++, digits++) {
            char c = *at;
            int nibble = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10
                       : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
            if (nibble < 0 || digits == 4) return false;
            value[part] = value[part] << 4 | (unsigned)nibble;
        }
        if (digits == 0) return false;
        if (part == 0) {
            if (*at != ':') return false;
            at++;
        }
    }
    if (*at) return false;
    *vendor_id = (uint16_t)value[0];
    *product_id = (uint16_t)value[1];
    return true;
}

/* The shortest decimal that reads back as the same float (so 0.5 prints as 0.5, 1/255 as
 * 0.003921569); -0 prints as 0. */
static void hidreplay_print_number(FILE *out, float value) {
    if (value == 0.0f) value = 0.0f;
    char text[32];
    for (int digits = 1; digits <= 9; digits++) {
        snprintf(text, sizeof text, "%.*g", digits, (double)value);
        if (strtof(text, NULL) == value) break;
    }
    fputs(text, out);
}

static void hidreplay_print_state(FILE *out, const input_gamepad_state *state) {
    const char *names[] = { "lx", "ly", "rx", "ry", "lt", "rt" };
    const float values[] = { state->lx, state->ly, state->rx, state->ry, state->lt, state->rt };
    fputc('{', out);
    for (int i = 0; i < 6; i++) {
        fprintf(out, "%s\"%s\":", i ? "," : "", names[i]);
        hidreplay_print_number(out, values[i]);
    }
    fputs(",\"buttons\":[", out);
    bool first = true;
    for (int b = 0; b < INPUT_BUTTON_COUNT; b++) {
        if (!(state->buttons & 1u << b)) continue;
        fprintf(out, "%s\"%s\"", first ? "" : ",", input_button_name((input_button)b));
        first = false;
    }
    fputs("]}\n", out);
}

static void hidreplay_print_error(FILE *out, const char *fmt, ...) CORE_PRINTF(2, 3);
static void hidreplay_print_error(FILE *out, const char *fmt, ...) {
    char message[256];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    fputs("{\"error\":", out);
    core_json_write_string(out, message);
    fputs("}\n", out);
}

/* Decodes every record of the file; false when the last one was cut short. */
static bool hidreplay_run(input_decoder *decoder, const uint8_t *bytes, size_t size, float dead_zone, FILE *out) {
    input_gamepad_state state = { 0 };
    size_t at = 0;
    while (at < size) {
        if (size - at < 2) {
            hidreplay_print_error(out, "truncated record at byte %zu: 1 byte left, a length takes 2", at);
            return false;
        }
        size_t length = (size_t)bytes[at] | (size_t)bytes[at + 1] << 8;
        if (size - at - 2 < length) {
            hidreplay_print_error(out, "truncated record at byte %zu: length %zu, %zu bytes left", at, length,
                                  size - at - 2);
            return false;
        }
        const uint8_t *report = bytes + at + 2;
        at += 2 + length;
        core_error why = { 0 };
        input_decode_result result = input_decoder_decode(decoder, report, length, &state, &why);
        if (result != INPUT_DECODE_OK) {
            hidreplay_print_error(out, "%s", why.message);
            continue;
        }
        input_gamepad_state shown = state;
        if (dead_zone > 0) input_apply_dead_zone(&shown, dead_zone);
        hidreplay_print_state(out, &shown);
    }
    return true;
}

int main(int argc, char **argv) {
    const char *descriptor_path = NULL;
    double dead_zone = 0.0;
    const char *positional[2] = { 0 };
    int positional_count = 0;
    core_common_args common = { 0 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(common), /* every program takes them; --threads changes nothing here */
        { .name = "descriptor", .kind = CORE_OPTION_STRING, .value = &descriptor_path, .metavar = "DESCFILE",
          .help = "the pad's HID report descriptor (raw bytes), for pads not known by their ids" },
        { .name = "dead-zone", .kind = CORE_OPTION_DOUBLE, .value = &dead_zone, .metavar = "R",
          .min_double = 0.0, .max_double = 1.0, .help = "radial stick dead zone, 0 … 1 (default 0: raw values)" },
    };
    core_cli cli = {
        .program = "hidreplay",
        .summary = "Decode recorded gamepad HID reports (2-byte little-endian length, then the report) "
                   "to one JSON line each.",
        .options = options,
        .option_count = (int)CORE_COUNTOF(options),
        .positional_name = "VID:PID FILE",
        .positional = positional,
        .positional_min = 2,
        .positional_max = 2,
        .positional_count = &positional_count,
    };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    uint16_t vendor_id, product_id;
    if (!hidreplay_parse_ids(positional[0], &vendor_id, &product_id)) {
        fprintf(stderr, "hidreplay: bad VID:PID '%s': want two hex numbers like 054c:09cc\n", positional[0]);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    int status = 1;
    size_t descriptor_size = 0, report_bytes_size = 0;
    uint8_t *descriptor = NULL, *report_bytes = NULL;
    input_decoder *decoder = NULL;
    input_gamepad_kind kind;
    bool known = input_gamepad_kind_from_ids(vendor_id, product_id, &kind);
    if (descriptor_path && !(descriptor = hidreplay_read_file(descriptor_path, &descriptor_size)))
        goto done;
    if (!(report_bytes = hidreplay_read_file(positional[1], &report_bytes_size))) goto done;
    core_error error = { 0 };
    decoder = input_decoder_create(&(input_decoder_desc){ .vendor_id = vendor_id, .product_id = product_id,
                                                          .descriptor = descriptor,
                                                          .descriptor_size = descriptor_size },
                                   &error);
    if (!decoder) {
        fprintf(stderr, "hidreplay: %s%s\n", error.message,
                descriptor || known ? "" : " (pass its report descriptor with --descriptor DESCFILE)");
        goto done;
    }
    trace_zone_begin("decode");
    bool complete = hidreplay_run(decoder, report_bytes, report_bytes_size, (float)dead_zone, stdout);
    trace_zone_end();
    status = complete ? 0 : 1;
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "hidreplay: cannot write the output: %s\n", strerror(errno));
        status = 1;
    }
done:
    input_decoder_destroy(decoder);
    if (descriptor) core_free(descriptor, descriptor_size ? descriptor_size : 1);
    if (report_bytes) core_free(report_bytes, report_bytes_size ? report_bytes_size : 1);
    trace_stop();
    return status;
}
