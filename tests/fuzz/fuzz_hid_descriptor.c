/* fuzz_hid_descriptor — libFuzzer target for the HID report-descriptor parser and the generic
 * gamepad decoder (engine/input/input_hid_descriptor.c).
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's sources, runs each 20 s)
 * Seeds: tests/fuzz/corpus/fuzz_hid_descriptor/ (typical pads' descriptors with a few reports).
 *
 * Input: 2 bytes little-endian = the descriptor's length (clamped to what is left), the
 * descriptor, then reports, each preceded by 1 byte of length (clamped likewise).
 *
 * Besides "no crash, no leak, no read out of bounds" it traps when one of these fails:
 *   - a refused descriptor says why; an accepted one's layout stays inside its own reports
 *     (every field ends within its report's needed bytes, which fit the longest report);
 *   - a decode that succeeds gives axes in [-1, 1], triggers in [0, 1], no stray button bits;
 *     one that fails leaves the state exactly as it was and has a reason;
 *   - the statistics count every decode once.
 */
#include "core/core.h"
#include "input/input.h"
#include "input/input_decode_internal.h"
#include "fuzz_gamepad.h"

#include <stdlib.h>
#include <string.h>

static void fuzz_check_layout(const input_hid_layout *layout) {
    if (layout->field_count == 0 || layout->field_count > INPUT_HID_MAX_FIELDS) __builtin_trap();
    if (layout->report_count == 0 || layout->max_report_bytes > INPUT_HID_MAX_REPORT_BYTES + 1) __builtin_trap();
    size_t id_bytes = layout->uses_report_ids ? 1 : 0;
    for (int r = 0; r < layout->report_count; r++) {
        const input_hid_report *report = &layout->reports[r];
        if (layout->report_of_id[report->id] != r + 1) __builtin_trap();
        if (report->needed_bytes + id_bytes > layout->max_report_bytes) __builtin_trap();
        for (int f = report->first_field; f < report->first_field + report->field_count; f++) {
            const input_hid_field *field = &layout->fields[f];
            if (field->bit_size == 0 || field->bit_size > 32) __builtin_trap();
            if ((uint64_t)field->bit_offset + field->bit_size > (uint64_t)report->needed_bytes * 8) __builtin_trap();
        }
    }
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    if (size < 2) return 0;
    size_t descriptor_size = (size_t)bytes[0] | (size_t)bytes[1] << 8;
    bytes += 2, size -= 2;
    if (descriptor_size > size) descriptor_size = size;
    /* Descriptor and reports are copied to heap blocks of exactly their size, so ASan sees any
     * read past them. */
    uint8_t *descriptor = malloc(descriptor_size ? descriptor_size : 1);
    memcpy(descriptor, bytes, descriptor_size);
    bytes += descriptor_size, size -= descriptor_size;

    input_hid_layout layout;
    core_error error = { 0 };
    bool parsed = input__hid_layout_parse(descriptor, descriptor_size, &layout, &error);
    if (!parsed && (error.code == CORE_ERROR_NONE || error.message[0] == '\0')) __builtin_trap();
    if (parsed) fuzz_check_layout(&layout);

    /* The same bytes through the public door, with an id no known pad has. */
    input_decoder *decoder = input_decoder_create(&(input_decoder_desc){ .vendor_id = 0xf00d, .product_id = 0x0001,
                                                                         .descriptor = descriptor,
                                                                         .descriptor_size = descriptor_size },
                                                  &error);
    free(descriptor);
    if ((decoder != NULL) != parsed) __builtin_trap();
    if (!decoder) return 0;
    input_gamepad_state state = { .lx = 0.5f, .buttons = 1u << INPUT_BUTTON_MISC };
    uint64_t calls = 0;
    while (size > 0) {
        size_t length = bytes[0];
        bytes++, size--;
        if (length > size) length = size;
        uint8_t *report = malloc(length ? length : 1);
        memcpy(report, bytes, length);
        fuzz_decode_checked(decoder, report, length, &state);
        free(report);
        calls++;
        bytes += length, size -= length;
    }
    fuzz_check_stats(decoder, calls);
    input_decoder_destroy(decoder);
    return 0;
}
