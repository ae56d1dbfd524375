/* input_hid_descriptor.c — the HID report-descriptor parser and the generic gamepad decoder.
 *
 * The parser follows the Device Class Definition for HID 1.11, §6.2.2 (items), with the limits of
 * Linux's hid-core.c where the specification sets none (input_decode_internal.h lists them):
 *   - short items: a prefix byte (bSize in bits 0-1, where 3 means 4 bytes; bType in bits 2-3;
 *     bTag in bits 4-7) and 0, 1, 2 or 4 data bytes, little-endian. Long items (prefix 0xfe, a
 *     size byte, a tag byte, data) carry nothing a gamepad needs and are skipped.
 *   - global items (§6.2.2.7) set the usage page, logical range, report size/count/ID; Push and
 *     Pop save and restore them on a bounded stack.
 *   - local items (§6.2.2.8) list usages (Usage, Usage Minimum/Maximum) for the next main item
 *     and are cleared by every main item. A 1- or 2-byte usage is combined with the usage page in
 *     force at the main item ("when the parser encounters a main item it concatenates the last
 *     declared Usage Page with a Usage"); a 4-byte usage carries its own page.
 *   - main items: Input fields advance the bit position of their report (one per report ID;
 *     Output and Feature reports are separate and are not read); Collection / End Collection
 *     nest, bounded.
 *   - Logical Minimum is signed (§6.2.2.7). Logical Maximum is read signed when the minimum is
 *     negative and unsigned otherwise, as Linux does: many descriptors write 0 … 255 as 0x15 0x00
 *     0x25 0xff, which read strictly signed would be 0 … −1. A field whose minimum is negative
 *     holds two's-complement values.
 *
 * Which fields: Generic Desktop X (0x30), Y (0x31), Z (0x32), Rx (0x33), Ry (0x34), Rz (0x35),
 * Hat switch (0x39) and Button page (0x09) usages 1 … 11, from Input items that are data (not
 * constant) and variable (array items are skipped), absolute for axes, with fields of at most 32
 * bits. The first field of each usage wins. Fields inside an application collection that is a
 * Joystick (0x04), Game Pad (0x05) or Multi-axis Controller (0x08) are preferred, and only those
 * of one such collection are used (a two-player adapter's second pad is not mixed in); without
 * one, the fields of the first application collection that has any are used.
 *
 * Mapping into input_gamepad_state:
 *   X, Y → left stick. If both Rx and Ry exist: Rx, Ry → right stick, Z → lt, Rz → rt;
 *   otherwise Z, Rz → right stick (the DirectInput habit). Axes go from the logical range to
 *   [-1, 1] (triggers [0, 1]) linearly, clamped; HID's Y already grows downwards, like SDL's.
 *   Hat: (value − logical minimum) is the direction, 0 = up, clockwise; an 8-value range is in
 *   eighths, a 4-value range in quarters; values outside the logical range are the null state
 *   (centred, HID 1.11 §6.2.2.5 "Null State").
 *   Buttons 1 … 11, in that order: south, east, west, north, lb, rb, back, start, ls, rs, guide
 *   (the common DirectInput order; button 12 and above are not mapped).
 */
#include "input/input_decode_internal.h"

#include "core/core.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ---- what we look for --------------------------------------------------------------------------- */

enum {
    HID_SLOT_X, HID_SLOT_Y, HID_SLOT_Z, HID_SLOT_RX, HID_SLOT_RY, HID_SLOT_RZ, HID_SLOT_HAT,
    HID_SLOT_BUTTON1,
    HID_SLOT_COUNT = HID_SLOT_BUTTON1 + 11,
};

enum {
    HID_PAGE_GENERIC_DESKTOP = 0x01,
    HID_PAGE_BUTTON = 0x09,
    HID_USAGE_JOYSTICK = 0x04,
    HID_USAGE_GAMEPAD = 0x05,
    HID_USAGE_MULTI_AXIS = 0x08,
};

/* Buttons 1 … 11 → input_button, in the order the file comment gives. */
static const uint8_t hid_button_map[11] = {
    INPUT_BUTTON_SOUTH, INPUT_BUTTON_EAST, INPUT_BUTTON_WEST, INPUT_BUTTON_NORTH,
    INPUT_BUTTON_LB, INPUT_BUTTON_RB, INPUT_BUTTON_BACK, INPUT_BUTTON_START,
    INPUT_BUTTON_LS, INPUT_BUTTON_RS, INPUT_BUTTON_GUIDE,
};

static uint32_t hid_slot_usage(int slot) {
    static const uint16_t desktop[HID_SLOT_BUTTON1] = { 0x30, 0x31, 0x32, 0x33, 0x34, 0x35, 0x39 };
    if (slot < HID_SLOT_BUTTON1) return (uint32_t)HID_PAGE_GENERIC_DESKTOP << 16 | desktop[slot];
    return (uint32_t)HID_PAGE_BUTTON << 16 | (uint32_t)(slot - HID_SLOT_BUTTON1 + 1);
}

/* ---- parser state ----------------------------------------------------------------------------- */

typedef struct hid_globals {
    uint32_t usage_page;
    uint32_t logical_min_raw, logical_max_raw;
    uint8_t logical_min_bytes, logical_max_bytes;
    uint32_t report_size, report_count, report_id;
} hid_globals;

/* A usage or a Usage Minimum … Maximum range. `extended`: 32-bit usages with their own page;
 * otherwise 16-bit ids to be combined with the page at the main item. */
typedef struct hid_usage_range {
    uint32_t min, max;
    bool extended;
} hid_usage_range;

typedef struct hid_candidate {
    bool found;
    uint8_t report_id;
    uint8_t bit_size;
    uint32_t bit_offset;
    int64_t logical_min, logical_max;
} hid_candidate;

/* The fields one application collection offers; `collection` = −1 until the first one. */
typedef struct hid_candidate_set {
    int collection;
    hid_candidate slots[HID_SLOT_COUNT];
} hid_candidate_set;

typedef struct hid_collection {
    int application;     /* ordinal of the enclosing application collection, from 1 */
    bool gamepad;        /* … and whether it is a joystick / gamepad / multi-axis controller */
} hid_collection;

typedef struct hid_parser {
    const uint8_t *data;
    size_t size, at;     /* `at`: the current item's first byte, for messages */
    hid_globals global;
    hid_globals stack[INPUT_HID_MAX_GLOBAL_STACK];
    int stack_depth;
    hid_usage_range usages[INPUT_HID_MAX_USAGES];
    int usage_count;
    bool have_min, have_max;
    uint32_t pending_min, pending_max;
    bool pending_min_extended, pending_max_extended;
    hid_collection collections[INPUT_HID_MAX_COLLECTION_DEPTH];
    int depth;
    int application_count;
    bool uses_report_ids;
    uint32_t input_bits[256];            /* per report ID, bits of input fields so far */
    hid_candidate_set gamepad_set, any_set;
    core_error *error;
} hid_parser;

static bool hid_fail(hid_parser *p, core_error_code code, const char *fmt, ...) CORE_PRINTF(3, 4);
static bool hid_fail(hid_parser *p, core_error_code code, const char *fmt, ...) {
    if (p->error) {
        p->error->code = code;
        va_list args;
        va_start(args, fmt);
        vsnprintf(p->error->message, sizeof p->error->message, fmt, args);
        va_end(args);
    }
    return false;
}

static int64_t hid_signed(uint32_t raw, uint8_t bytes) {
    switch (bytes) {
    case 1: return (int8_t)raw;
    case 2: return (int16_t)raw;
    case 4: return (int32_t)raw;
    default: return 0;
    }
}

static void hid_logical_range(const hid_globals *g, int64_t *min, int64_t *max) {
    *min = hid_signed(g->logical_min_raw, g->logical_min_bytes);
    *max = *min < 0 ? hid_signed(g->logical_max_raw, g->logical_max_bytes) : (int64_t)g->logical_max_raw;
}

/* ---- local items -------------------------------------------------------------------------------- */

static bool hid_add_usage(hid_parser *p, uint32_t min, uint32_t max, bool extended) {
    if (p->usage_count == INPUT_HID_MAX_USAGES)
        return hid_fail(p, CORE_ERROR_RANGE, "more than %d usages before one main item (byte %zu)", INPUT_HID_MAX_USAGES, p->at);
    p->usages[p->usage_count++] = (hid_usage_range){ .min = min, .max = max, .extended = extended };
    return true;
}

/* A Usage Minimum and Maximum make a range once both are seen. When one of them is 4 bytes,
 * its page applies to both. A range running backwards selects nothing. */
static bool hid_add_pending_range(hid_parser *p) {
    uint32_t min = p->pending_min, max = p->pending_max;
    bool extended = p->pending_min_extended || p->pending_max_extended;
    if (extended) {
        uint32_t page = (p->pending_min_extended ? min : max) & 0xffff0000u;
        if (!p->pending_min_extended) min = page | (min & 0xffff);
        if (!p->pending_max_extended) max = page | (max & 0xffff);
    }
    p->have_min = p->have_max = false;
    if (max < min) return true;
    return hid_add_usage(p, min, max, extended);
}

static void hid_clear_locals(hid_parser *p) {
    p->usage_count = 0;
    p->have_min = p->have_max = false;
}

static uint32_t hid_full_usage(const hid_parser *p, uint32_t usage, bool extended) {
    return extended ? usage : (p->global.usage_page & 0xffff) << 16 | (usage & 0xffff);
}

/* ---- main items ------------------------------------------------------------------------------- */

static void hid_offer_to(hid_candidate_set *set, int collection, int slot, const hid_candidate *field) {
    if (set->collection == -1) set->collection = collection;
    if (set->collection != collection || set->slots[slot].found) return;
    set->slots[slot] = *field;
}

static void hid_offer(hid_parser *p, int slot, uint32_t bit_offset, int64_t min, int64_t max, bool relative) {
    bool axis = slot <= HID_SLOT_RZ;
    if (axis && (relative || max <= min)) return;   /* a mouse's motion, or no range to scale */
    if (slot == HID_SLOT_HAT && max < min) return;
    hid_candidate field = {
        .found = true,
        .report_id = (uint8_t)p->global.report_id,
        .bit_size = (uint8_t)p->global.report_size,
        .bit_offset = bit_offset,
        .logical_min = min,
        .logical_max = max,
    };
    const hid_collection *c = p->depth ? &p->collections[p->depth - 1] : NULL;
    int collection = c ? c->application : 0;
    if (c && c->gamepad) hid_offer_to(&p->gamepad_set, collection, slot, &field);
    hid_offer_to(&p->any_set, collection, slot, &field);
}

static bool hid_input(hid_parser *p, uint32_t flags) {
    uint32_t id = p->global.report_id;
    uint64_t bits = (uint64_t)p->global.report_size * p->global.report_count;
    uint64_t start = p->input_bits[id];
    if (start + bits > (uint64_t)INPUT_HID_MAX_REPORT_BYTES * 8)
        return hid_fail(p, CORE_ERROR_RANGE, "input report %u longer than %d bytes (byte %zu)", (unsigned)id,
                        INPUT_HID_MAX_REPORT_BYTES, p->at);
    p->input_bits[id] = (uint32_t)(start + bits);
    bool constant = flags & 1, variable = flags & 2, relative = flags & 4;
    uint32_t size = p->global.report_size, count = p->global.report_count;
    if (constant || !variable || size == 0 || size > INPUT_HID_MAX_FIELD_BITS || count == 0) return true;
    int64_t min, max;
    hid_logical_range(&p->global, &min, &max);
    /* Field i takes the i-th usage of the list (ranges expanded). Later fields repeat the last
     * usage, which can only be a duplicate of one already offered, so they are not visited. */
    uint64_t index = 0;
    for (int u = 0; u < p->usage_count && index < count; u++) {
        const hid_usage_range *r = &p->usages[u];
        uint32_t lo = hid_full_usage(p, r->min, r->extended), hi = hid_full_usage(p, r->max, r->extended);
        if (hi < lo) hi = lo;
        for (int slot = 0; slot < HID_SLOT_COUNT; slot++) {
            uint32_t usage = hid_slot_usage(slot);
            if (usage < lo || usage > hi) continue;
            uint64_t field = index + (usage - lo);
            if (field < count) hid_offer(p, slot, (uint32_t)(start + field * size), min, max, relative);
        }
        index += (uint64_t)(hi - lo) + 1;
    }
    return true;
}

static bool hid_collection_begin(hid_parser *p, uint32_t type) {
    if (p->depth == INPUT_HID_MAX_COLLECTION_DEPTH)
        return hid_fail(p, CORE_ERROR_RANGE, "collections nested deeper than %d (byte %zu)", INPUT_HID_MAX_COLLECTION_DEPTH, p->at);
    hid_collection c = p->depth ? p->collections[p->depth - 1] : (hid_collection){ 0 };
    if ((type & 0xff) == 1) { /* application */
        uint32_t usage = p->usage_count ? hid_full_usage(p, p->usages[0].min, p->usages[0].extended) : 0;
        c.application = ++p->application_count;
        c.gamepad = usage == ((uint32_t)HID_PAGE_GENERIC_DESKTOP << 16 | HID_USAGE_JOYSTICK) ||
                    usage == ((uint32_t)HID_PAGE_GENERIC_DESKTOP << 16 | HID_USAGE_GAMEPAD) ||
                    usage == ((uint32_t)HID_PAGE_GENERIC_DESKTOP << 16 | HID_USAGE_MULTI_AXIS);
    }
    p->collections[p->depth++] = c;
    return true;
}

static bool hid_main_item(hid_parser *p, unsigned tag, uint32_t value) {
    bool ok = true;
    switch (tag) {
    case 0x8: ok = hid_input(p, value); break;                  /* Input */
    case 0x9: case 0xb: break;                                  /* Output, Feature: not read */
    case 0xa: ok = hid_collection_begin(p, value); break;       /* Collection */
    case 0xc:                                                   /* End Collection */
        if (p->depth == 0) return hid_fail(p, CORE_ERROR_FORMAT, "End Collection without a Collection (byte %zu)", p->at);
        p->depth--;
        break;
    default: break;                                             /* reserved: ignored, as Linux does */
    }
    hid_clear_locals(p);
    return ok;
}

/* ---- global and local items ----------------------------------------------------------------- */

static bool hid_global_item(hid_parser *p, unsigned tag, uint32_t value, uint8_t bytes) {
    hid_globals *g = &p->global;
    switch (tag) {
    case 0x0: g->usage_page = value & 0xffff; break;
    case 0x1: g->logical_min_raw = value; g->logical_min_bytes = bytes; break;
    case 0x2: g->logical_max_raw = value; g->logical_max_bytes = bytes; break;
    case 0x7:
        if (value > INPUT_HID_MAX_REPORT_SIZE)
            return hid_fail(p, CORE_ERROR_RANGE, "report size %u bits exceeds %d (byte %zu)", (unsigned)value,
                            INPUT_HID_MAX_REPORT_SIZE, p->at);
        g->report_size = value;
        break;
    case 0x8:
        if (value == 0 || value > 255) return hid_fail(p, CORE_ERROR_FORMAT, "invalid report ID %u (byte %zu)", (unsigned)value, p->at);
        g->report_id = value;
        p->uses_report_ids = true;
        break;
    case 0x9:
        if (value > INPUT_HID_MAX_REPORT_COUNT)
            return hid_fail(p, CORE_ERROR_RANGE, "report count %u exceeds %d (byte %zu)", (unsigned)value,
                            INPUT_HID_MAX_REPORT_COUNT, p->at);
        g->report_count = value;
        break;
    case 0xa:
        if (p->stack_depth == INPUT_HID_MAX_GLOBAL_STACK)
            return hid_fail(p, CORE_ERROR_RANGE, "Push nested deeper than %d (byte %zu)", INPUT_HID_MAX_GLOBAL_STACK, p->at);
        p->stack[p->stack_depth++] = *g;
        break;
    case 0xb:
        if (p->stack_depth == 0) return hid_fail(p, CORE_ERROR_FORMAT, "Pop without a Push (byte %zu)", p->at);
        *g = p->stack[--p->stack_depth];
        break;
    default: break; /* physical range, unit, unit exponent, reserved */
    }
    return true;
}

static bool hid_local_item(hid_parser *p, unsigned tag, uint32_t value, uint8_t bytes) {
    bool extended = bytes == 4;
    switch (tag) {
    case 0x0: return hid_add_usage(p, value, value, extended);
    case 0x1:
        p->pending_min = value;
        p->pending_min_extended = extended;
        p->have_min = true;
        return p->have_max ? hid_add_pending_range(p) : true;
    case 0x2:
        p->pending_max = value;
        p->pending_max_extended = extended;
        p->have_max = true;
        return p->have_min ? hid_add_pending_range(p) : true;
    default: return true; /* designators, strings, delimiters */
    }
}

/* ---- the layout from what was found -------------------------------------------------------- */

static bool hid_set_usable(const hid_candidate_set *set) {
    if (set->slots[HID_SLOT_X].found && set->slots[HID_SLOT_Y].found) return true;
    for (int slot = HID_SLOT_HAT; slot < HID_SLOT_COUNT; slot++)
        if (set->slots[slot].found) return true;
    return false;
}

/* Buttons are mostly 1-bit fields side by side: one 64-bit load (from the byte holding the first
 * one, so up to 57 bits after it are in reach) serves them all. */
static void hid_plan_button_window(input_hid_layout *layout, input_hid_report *report) {
    uint32_t first = UINT32_MAX;
    for (int i = report->first_field; i < report->first_field + report->field_count; i++) {
        const input_hid_field *f = &layout->fields[i];
        if (f->target == INPUT_HID_BUTTON && f->bit_size == 1 && f->bit_offset < first) first = f->bit_offset;
    }
    if (first == UINT32_MAX) return;
    report->has_window = true;
    report->window_bit = first;
    for (int i = report->first_field; i < report->first_field + report->field_count; i++) {
        input_hid_field *f = &layout->fields[i];
        if (f->target != INPUT_HID_BUTTON || f->bit_size != 1 || f->bit_offset - first > 56) continue;
        f->in_window = true;
        f->window_shift = (uint8_t)(f->bit_offset - first);
    }
}

static void hid_build_layout(const hid_parser *p, const hid_candidate_set *set, input_hid_layout *layout) {
    memset(layout, 0, sizeof *layout);
    layout->uses_report_ids = p->uses_report_ids;
    uint32_t longest_bits = 0;
    for (int id = 0; id < 256; id++)
        if (p->input_bits[id] > longest_bits) longest_bits = p->input_bits[id];
    layout->max_report_bytes = (longest_bits + 7) / 8 + (p->uses_report_ids ? 1 : 0);

    /* Targets per slot (the file comment's mapping). */
    int target[HID_SLOT_COUNT];
    for (int slot = 0; slot < HID_SLOT_COUNT; slot++) target[slot] = -1;
    target[HID_SLOT_X] = INPUT_HID_LX;
    target[HID_SLOT_Y] = INPUT_HID_LY;
    if (set->slots[HID_SLOT_RX].found && set->slots[HID_SLOT_RY].found) {
        target[HID_SLOT_RX] = INPUT_HID_RX;
        target[HID_SLOT_RY] = INPUT_HID_RY;
        target[HID_SLOT_Z] = INPUT_HID_LT;
        target[HID_SLOT_RZ] = INPUT_HID_RT;
    } else {
        target[HID_SLOT_Z] = INPUT_HID_RX;
        target[HID_SLOT_RZ] = INPUT_HID_RY;
    }
    target[HID_SLOT_HAT] = INPUT_HID_HAT;
    for (int b = 0; b < 11; b++) target[HID_SLOT_BUTTON1 + b] = INPUT_HID_BUTTON;

    /* Fields grouped by report ID, reports in ID order. Report 0 cannot arrive once the device
     * uses IDs, so fields declared before the first Report ID item are dropped then. */
    for (int id = p->uses_report_ids ? 1 : 0; id < 256; id++) {
        input_hid_report report = { .id = (uint8_t)id, .first_field = layout->field_count };
        for (int slot = 0; slot < HID_SLOT_COUNT; slot++) {
            const hid_candidate *c = &set->slots[slot];
            if (!c->found || c->report_id != id || target[slot] < 0) continue;
            input_hid_field *f = &layout->fields[layout->field_count++];
            *f = (input_hid_field){
                .bit_offset = c->bit_offset,
                .bit_size = c->bit_size,
                .target = (uint8_t)target[slot],
                .button = slot >= HID_SLOT_BUTTON1 ? hid_button_map[slot - HID_SLOT_BUTTON1] : 0,
                .is_signed = c->logical_min < 0,
                .logical_min = c->logical_min,
                .logical_max = c->logical_max,
            };
            double range = (double)(c->logical_max - c->logical_min);
            if (f->target == INPUT_HID_LT || f->target == INPUT_HID_RT) {
                f->scale = 1.0 / range;
                f->offset = -(double)c->logical_min * f->scale;
            } else if (f->target <= INPUT_HID_RY) {
                f->scale = 2.0 / range;
                f->offset = -1.0 - (double)c->logical_min * f->scale;
            }
            if (f->target == INPUT_HID_BUTTON) report.button_mask |= 1u << f->button;
            if (f->target == INPUT_HID_HAT)
                report.button_mask |= 1u << INPUT_BUTTON_DPAD_UP | 1u << INPUT_BUTTON_DPAD_DOWN |
                                      1u << INPUT_BUTTON_DPAD_LEFT | 1u << INPUT_BUTTON_DPAD_RIGHT;
            uint32_t end_bytes = (uint32_t)(((uint64_t)f->bit_offset + f->bit_size + 7) / 8);
            if (end_bytes > report.needed_bytes) report.needed_bytes = end_bytes;
        }
        report.field_count = (uint8_t)(layout->field_count - report.first_field);
        if (report.field_count == 0) continue;
        hid_plan_button_window(layout, &report);
        layout->reports[layout->report_count] = report;
        layout->report_of_id[id] = ++layout->report_count;
    }
}

static bool hid_parse(hid_parser *p, const uint8_t *descriptor, size_t size, input_hid_layout *layout,
                      core_error *error);

bool input__hid_layout_parse(const uint8_t *descriptor, size_t size, input_hid_layout *layout,
                             core_error *error) {
    /* About 15 KiB of bounded workspace, once per device: zeroed, on the heap. */
    hid_parser *p = core_calloc(1, sizeof *p);
    bool ok = hid_parse(p, descriptor, size, layout, error);
    core_free(p, sizeof *p);
    return ok;
}

static bool hid_parse(hid_parser *p, const uint8_t *descriptor, size_t size, input_hid_layout *layout,
                      core_error *error) {
    p->data = descriptor;
    p->size = descriptor ? size : 0;
    p->error = error;
    p->gamepad_set.collection = p->any_set.collection = -1;
    if (p->size == 0) return hid_fail(p, CORE_ERROR_FORMAT, "empty report descriptor");

    size_t at = 0;
    while (at < p->size) {
        p->at = at;
        uint8_t prefix = p->data[at];
        if (prefix == 0xfe) { /* long item: 0xfe, bDataSize, bLongItemTag, data */
            if (p->size - at < 3) return hid_fail(p, CORE_ERROR_CORRUPT, "long item at byte %zu runs past the end", at);
            size_t length = p->data[at + 1];
            if (p->size - at - 3 < length)
                return hid_fail(p, CORE_ERROR_CORRUPT, "long item at byte %zu needs %zu data bytes, %zu left", at, length,
                                p->size - at - 3);
            at += 3 + length;
            continue;
        }
        uint8_t bytes = (prefix & 3) == 3 ? 4 : (prefix & 3);
        if (p->size - at - 1 < bytes)
            return hid_fail(p, CORE_ERROR_CORRUPT, "item 0x%02x at byte %zu needs %u data bytes, %zu left", prefix, at, bytes,
                            p->size - at - 1);
        uint32_t value = 0;
        for (unsigned i = 0; i < bytes; i++) value |= (uint32_t)p->data[at + 1 + i] << (8 * i);
        unsigned type = (prefix >> 2) & 3, tag = prefix >> 4;
        bool ok = true;
        if (type == 0) ok = hid_main_item(p, tag, value);
        else if (type == 1) ok = hid_global_item(p, tag, value, bytes);
        else if (type == 2) ok = hid_local_item(p, tag, value, bytes);
        /* type 3 (reserved, other than the long-item prefix): ignored, as Linux does */
        if (!ok) return false;
        at += 1u + bytes;
    }
    if (p->depth != 0)
        return hid_fail(p, CORE_ERROR_FORMAT, "%d collection%s not ended at the end of the descriptor", p->depth,
                        p->depth == 1 ? "" : "s");

    const hid_candidate_set *set = hid_set_usable(&p->gamepad_set) ? &p->gamepad_set
                                   : hid_set_usable(&p->any_set)   ? &p->any_set
                                                                   : NULL;
    if (!set) return hid_fail(p, CORE_ERROR_FORMAT, "no stick (X and Y), hat switch or buttons in the input reports");
    input_hid_layout built;
    hid_build_layout(p, set, &built);
    if (built.field_count == 0)
        return hid_fail(p, CORE_ERROR_FORMAT, "the stick and buttons are declared before the first Report ID, in no report");
    *layout = built;
    return true;
}

/* ---- decoding ------------------------------------------------------------------------------- */

/* Up to 8 bytes from bytes[at …], little-endian; bytes past byte_count read as 0. */
static inline uint64_t hid_load64(const uint8_t *bytes, size_t byte_count, size_t at) {
    uint64_t value = 0;
    if (at < byte_count && byte_count - at >= 8) {
        memcpy(&value, bytes + at, 8);
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
        value = __builtin_bswap64(value);
#endif
        return value;
    }
    for (size_t i = 0; at < byte_count && i < 8; i++, at++) value |= (uint64_t)bytes[at] << (8 * i);
    return value;
}

uint32_t input__hid_extract_bits(const uint8_t *bytes, size_t byte_count, uint32_t bit_offset, unsigned bit_size) {
    if (bit_size == 0) return 0;
    if (bit_size > 32) bit_size = 32;
    /* shift ≤ 7 and bit_size ≤ 32: the 64 loaded bits hold the whole field */
    uint64_t bits = hid_load64(bytes, byte_count, bit_offset >> 3) >> (bit_offset & 7);
    return (uint32_t)(bits & (((uint64_t)1 << bit_size) - 1));
}

/* A report body as the decoder reads it: in place when it has 8 bytes or more (each read is one
 * 8-byte load, moved back to end at the body's end when it would run past it), else gathered
 * into one register first. Every read stays inside the body whatever the offset; fields past
 * its end read 0 (the size checks keep them from happening). */
typedef struct hid_body {
    const uint8_t *bytes;
    size_t size;
    uint64_t small;          /* the whole body when size < 8 */
} hid_body;

static inline hid_body hid_body_of(const uint8_t *bytes, size_t size) {
    hid_body body = { .bytes = bytes, .size = size };
    if (size < 8)
        for (size_t i = 0; i < size; i++) body.small |= (uint64_t)bytes[i] << (8 * i);
    return body;
}

/* 64 − (bit_offset & 7) or more bits from bit_offset on, the rest zeros. */
static inline uint64_t hid_body_bits(const hid_body *body, uint32_t bit_offset) {
    if (body->size < 8) return bit_offset < 64 ? body->small >> bit_offset : 0;
    size_t at = bit_offset >> 3, base = at + 8 <= body->size ? at : body->size - 8;
    uint64_t word;
    memcpy(&word, body->bytes + base, 8);
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    word = __builtin_bswap64(word);
#endif
    size_t shift = (at - base) * 8 + (bit_offset & 7);
    return shift < 64 ? word >> shift : 0;
}

static inline int64_t hid_field_value(const input_hid_field *f, const hid_body *body) {
    uint32_t raw = (uint32_t)(hid_body_bits(body, f->bit_offset) & (((uint64_t)1 << f->bit_size) - 1));
    if (!f->is_signed) return raw;
    if (f->bit_size >= 32) return (int32_t)raw;
    uint32_t sign = 1u << (f->bit_size - 1);
    return (int64_t)(raw ^ sign) - (int64_t)sign;
}

static inline float hid_clamp(float value, float lo, float hi) {
    return value < lo ? lo : value > hi ? hi : value;
}

static uint32_t hid_hat_buttons(const input_hid_field *f, int64_t value) {
    if (value < f->logical_min || value > f->logical_max) return 0; /* null state: centred */
    int64_t index = value - f->logical_min, count = f->logical_max - f->logical_min + 1;
    int64_t eighth = count == 8 ? index : count == 4 ? index * 2 : index * 8 / count;
    return input__hat_buttons((unsigned)eighth);
}

input_decode_result input__hid_decode(const input_hid_layout *layout, const uint8_t *report, size_t size,
                                      input_gamepad_state *state, input_decode_failure *failure) {
    size_t id_bytes = layout->uses_report_ids ? 1 : 0;
    failure->size = size;
    if (size == 0) {
        size_t need = SIZE_MAX;
        for (int r = 0; r < layout->report_count; r++)
            if (layout->reports[r].needed_bytes + id_bytes < need) need = layout->reports[r].needed_bytes + id_bytes;
        failure->limit = need < 1 ? 1 : need;
        return INPUT_DECODE_SHORT;
    }
    unsigned id = id_bytes ? report[0] : 0;
    unsigned index = layout->report_of_id[id];
    if (index == 0) {
        failure->report_id = (int)id;
        return INPUT_DECODE_UNKNOWN_ID;
    }
    if (size > layout->max_report_bytes) {
        failure->limit = layout->max_report_bytes;
        return INPUT_DECODE_OVERSIZED;
    }
    const input_hid_report *r = &layout->reports[index - 1];
    const uint8_t *body = report + id_bytes;
    size_t body_size = size - id_bytes;
    if (body_size < r->needed_bytes) {
        failure->limit = r->needed_bytes + id_bytes;
        return INPUT_DECODE_SHORT;
    }
    /* Axes gathered in a local array and written back one by one: copying a whole struct that
     * was just written field by field stalls on store forwarding (it showed in the profile). */
    float axes[6] = { state->lx, state->ly, state->rx, state->ry, state->lt, state->rt };
    hid_body bits = hid_body_of(body, body_size);
    uint64_t window = r->has_window ? hid_body_bits(&bits, r->window_bit) : 0;
    uint32_t buttons = 0;
    const input_hid_field *f = &layout->fields[r->first_field], *end = f + r->field_count;
    for (; f < end; f++) {
        if (f->in_window) {
            buttons |= (uint32_t)(window >> f->window_shift & 1) << f->button;
            continue;
        }
        int64_t value = hid_field_value(f, &bits);
        if (f->target == INPUT_HID_BUTTON) {
            buttons |= (uint32_t)(value != 0) << f->button;
        } else if (f->target == INPUT_HID_HAT) {
            buttons |= hid_hat_buttons(f, value);
        } else {
            float scaled = (float)((double)value * f->scale + f->offset);
            bool trigger = f->target >= INPUT_HID_LT;
            axes[f->target] = hid_clamp(scaled, trigger ? 0.0f : -1.0f, 1.0f);
        }
    }
    state->lx = axes[0], state->ly = axes[1], state->rx = axes[2], state->ry = axes[3];
    state->lt = axes[4], state->rt = axes[5];
    state->buttons = (state->buttons & ~r->button_mask) | buttons;
    return INPUT_DECODE_OK;
}
