/* input_decode_internal.h — what the report decoders' two files share (input_decode.c: the known
 * pads and the decoder object; input_hid_descriptor.c: the report-descriptor parser and the generic
 * decoder). Only engine/input/ and the decoder tests include this.
 *
 * A generic pad is read through an input_hid_layout: the parser walks the report descriptor once,
 * keeps the handful of fields a gamepad state needs (at most INPUT_HID_MAX_FIELDS) with their bit
 * positions and logical ranges, and the decoder then reads just those bits from each report. No
 * memory is allocated per descriptor beyond the fixed-size layout, whatever the descriptor says.
 */
#ifndef INPUT_DECODE_INTERNAL_H
#define INPUT_DECODE_INTERNAL_H

#include "input/input.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* ---- limits the parser enforces (a descriptor beyond them is rejected, with a reason) --------- */

enum {
    INPUT_HID_MAX_GLOBAL_STACK = 16,     /* Push depth (Linux allows 4) */
    INPUT_HID_MAX_COLLECTION_DEPTH = 32, /* nested Collection items */
    INPUT_HID_MAX_USAGES = 1024,         /* Usage items (a Usage Min/Max pair counts once) per main item */
    INPUT_HID_MAX_REPORT_COUNT = 12288,  /* Report Count (Linux's HID_MAX_USAGES) */
    INPUT_HID_MAX_REPORT_SIZE = 256,     /* Report Size in bits (Linux's limit) */
    INPUT_HID_MAX_REPORT_BYTES = 16383,  /* one report's body (Linux's HID_MAX_BUFFER_SIZE − 1) */
    INPUT_HID_MAX_FIELD_BITS = 32,       /* a field we read; wider ones are skipped, not read */
};

/* ---- the layout of a generic pad -------------------------------------------------------------- */

/* What a field feeds in input_gamepad_state. */
typedef enum input_hid_target {
    INPUT_HID_LX,
    INPUT_HID_LY,
    INPUT_HID_RX,
    INPUT_HID_RY,
    INPUT_HID_LT,
    INPUT_HID_RT,
    INPUT_HID_HAT,
    INPUT_HID_BUTTON,       /* `button` says which */
} input_hid_target;

typedef struct input_hid_field {
    uint32_t bit_offset;    /* from the start of the report body (after the ID byte, if any) */
    uint8_t bit_size;       /* 1 … 32 */
    uint8_t target;         /* input_hid_target */
    uint8_t button;         /* input_button, for INPUT_HID_BUTTON */
    bool is_signed;         /* logical minimum < 0: the bits are two's complement */
    bool in_window;         /* a 1-bit button read from its report's button window … */
    uint8_t window_shift;   /* … at this bit of it */
    int64_t logical_min, logical_max;
    double scale, offset;   /* axes: normalised = value · scale + offset (then clamped) */
} input_hid_field;

enum { INPUT_HID_MAX_FIELDS = 18 };      /* X Y Z Rx Ry Rz, hat, buttons 1 … 11 */

typedef struct input_hid_report {
    uint8_t id;             /* 0 when the device uses no report IDs */
    uint8_t first_field, field_count;
    uint32_t needed_bytes;  /* body bytes the fields reach into */
    uint32_t button_mask;   /* the state's button bits this report sets (buttons, dpad from a hat) */
    bool has_window;        /* 1-bit buttons within 57 bits of each other are read in one load */
    uint32_t window_bit;    /* the window's first bit in the body */
} input_hid_report;

typedef struct input_hid_layout {
    bool uses_report_ids;
    uint32_t max_report_bytes;           /* the longest input report, ID byte included */
    input_hid_field fields[INPUT_HID_MAX_FIELDS];   /* grouped by report, in report order */
    uint8_t field_count;
    input_hid_report reports[INPUT_HID_MAX_FIELDS];
    uint8_t report_count;
    uint8_t report_of_id[256];           /* report ID → index in reports[] + 1; 0 = none */
} input_hid_layout;

/* Parses a report descriptor into *layout. False, with a one-line reason in `error` (may be NULL),
 * when the descriptor is malformed, beyond the limits above, or has neither a stick (X and Y) nor
 * buttons nor a hat. Reads only descriptor[0, size). */
bool input__hid_layout_parse(const uint8_t *descriptor, size_t size, input_hid_layout *layout,
                             core_error *error);

/* What a failed decode says besides its result (for the caller's core_error). */
typedef struct input_decode_failure {
    size_t size;            /* the report's size */
    size_t limit;           /* SHORT: bytes needed; OVERSIZED: most bytes allowed */
    int report_id;          /* UNKNOWN_ID: the ID seen */
    const char *reason;     /* MALFORMED: what was impossible (a static string) */
} input_decode_failure;

/* Decodes one report of a generic pad. On anything but INPUT_DECODE_OK, *state is untouched and
 * *failure says why. Fields of other reports keep their values in *state. */
input_decode_result input__hid_decode(const input_hid_layout *layout, const uint8_t *report, size_t size,
                                      input_gamepad_state *state, input_decode_failure *failure);

/* Bits [bit_offset, bit_offset + bit_size) of bytes[0, byte_count), little-endian as HID lays
 * them out; bit_size ≤ 32. Bits past the end read as 0 (callers check sizes first; this is the
 * last line of defence, so nothing is ever read outside the buffer). */
uint32_t input__hid_extract_bits(const uint8_t *bytes, size_t byte_count, uint32_t bit_offset, unsigned bit_size);

/* ---- shared helpers --------------------------------------------------------------------------- */

/* Hat value 0 … 15 (0 = up, clockwise in eighths, 8 and above centred) → dpad button bits. */
uint32_t input__hat_buttons(unsigned hat);

#endif /* INPUT_DECODE_INTERNAL_H */
