/* input_record.c — the record file: writer (--record) and reader (--replay).
 *
 * Layout (README.md, "Record file"; all numbers little-endian, floats as their IEEE-754 bits):
 *
 *   header   "INPUTREC"  u32 version (1)  u32 length L  payload[L]  u32 checksum
 *   record   tag[4] ("FRAM" or "END!")  u32 length L  payload[L]  u32 checksum
 *
 * A checksum is the low 32 bits of core_hash_bytes(seed 0) over everything of its header or
 * record before it (tag and length included), so a flipped bit, a torn write or a length that
 * points elsewhere is caught, not misread. The file ends with one END! record holding the frame
 * count; a file without it was cut short (a crash) and the replay says so when it gets there.
 *
 * The writer streams to PATH.part beside PATH, flushing each frame, and renames it over PATH in
 * input__recorder_close: an interrupted run never replaces a good recording, and what it leaves
 * in PATH.part replays up to the last whole frame.
 */
#include "input/input_internal.h"

#include "core/core.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

enum {
    INPUT_RECORD_VERSION = 1,
    INPUT_RECORD_MAX_HEADER = 64 * 1024,
    /* One frame: 12 + 30 per event (the largest) + 28; a length above this is corrupt. */
    INPUT_RECORD_MAX_FRAME = 12 + 30 * INPUT_MAX_EVENTS + 28,
};

static const char input_record_magic[8] = { 'I', 'N', 'P', 'U', 'T', 'R', 'E', 'C' };
static const char input_tag_frame[4] = { 'F', 'R', 'A', 'M' };
static const char input_tag_end[4] = { 'E', 'N', 'D', '!' };

/* ---- bytes ---------------------------------------------------------------------------------- */

typedef struct input_bytes {
    uint8_t *data;
    size_t size, capacity;
} input_bytes;

static void input_put(input_bytes *b, const void *data, size_t size) {
    b->data = core_grow(b->data, &b->capacity, b->size + size, 1);
    memcpy(b->data + b->size, data, size);
    b->size += size;
}
static void input_put_u8(input_bytes *b, uint32_t v) {
    uint8_t byte = (uint8_t)v;
    input_put(b, &byte, 1);
}
static void input_put_u16(input_bytes *b, uint32_t v) {
    uint8_t bytes[2] = { (uint8_t)v, (uint8_t)(v >> 8) };
    input_put(b, bytes, 2);
}
static void input_put_u32(input_bytes *b, uint32_t v) {
    uint8_t bytes[4] = { (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24) };
    input_put(b, bytes, 4);
}
static void input_put_f32(input_bytes *b, float f) {
    uint32_t bits;
    memcpy(&bits, &f, 4);
    input_put_u32(b, bits);
}
static void input_patch_u32(input_bytes *b, size_t at, uint32_t v) {
    for (int i = 0; i < 4; i++) b->data[at + (size_t)i] = (uint8_t)(v >> (8 * i));
}
static void input_bytes_free(input_bytes *b) {
    if (b->data) core_free(b->data, b->capacity);
    *b = (input_bytes){ 0 };
}

static uint32_t input_read_u32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint32_t input_checksum(const uint8_t *data, size_t size) { return (uint32_t)core_hash_bytes(data, size, 0); }

/* A bounded reader: once it runs past the end every read gives 0 and `ok` stays false. */
typedef struct input_cursor {
    const uint8_t *at, *end;
    bool ok;
} input_cursor;

static uint32_t input_get(input_cursor *c, int bytes) {
    if (!c->ok || c->end - c->at < bytes) {
        c->ok = false;
        return 0;
    }
    uint32_t v = 0;
    for (int i = 0; i < bytes; i++) v |= (uint32_t)c->at[i] << (8 * i);
    c->at += bytes;
    return v;
}
static float input_get_f32(input_cursor *c) {
    uint32_t bits = input_get(c, 4);
    float f;
    memcpy(&f, &bits, 4);
    return f;
}


/* ---- payloads ------------------------------------------------------------------------------- */

static void input_encode_header(input_bytes *b, const input_bindings *bindings, float dead_zone) {
    input_put_u32(b, INPUT_TARGET_COUNT);
    for (int t = 0; t < INPUT_TARGET_COUNT; t++) {
        input_put_u8(b, bindings->source_count[t]);
        for (int i = 0; i < bindings->source_count[t]; i++) {
            input_put_u8(b, bindings->sources[t][i].kind);
            input_put_u16(b, bindings->sources[t][i].code);
        }
    }
    input_put_f32(b, bindings->look_speed);
    input_put_f32(b, bindings->stick_look_speed);
    input_put_f32(b, bindings->dead_zone);
    input_put_u8(b, bindings->invert_y);
    input_put_f32(b, dead_zone);
}

bool input__record_decode_header(const uint8_t *payload, size_t size, input_bindings *bindings, float *dead_zone,
                                 core_error *error) {
    input_cursor c = { payload, payload + size, true };
    input_bindings b = { 0 };
    uint32_t targets = input_get(&c, 4);
    if (c.ok && targets != INPUT_TARGET_COUNT)
        return core_error_set(error, CORE_ERROR_FORMAT, "%u actions, this build has %d", targets, INPUT_TARGET_COUNT);
    for (int t = 0; t < INPUT_TARGET_COUNT && c.ok; t++) {
        uint32_t count = input_get(&c, 1);
        if (count > INPUT_MAX_SOURCES)
            return core_error_set(error, CORE_ERROR_RANGE, "%s has %u sources (at most %d)", input__target_name(t), count,
                              INPUT_MAX_SOURCES);
        for (uint32_t i = 0; i < count && c.ok; i++) {
            input_source source = { .kind = (uint8_t)input_get(&c, 1), .code = (uint16_t)input_get(&c, 2) };
            if (c.ok && input__source_misfit(t, source))
                return core_error_set(error, CORE_ERROR_FORMAT, "bad source %u:%u for %s", source.kind, source.code,
                                  input__target_name(t));
            b.sources[t][i] = source;
        }
        b.source_count[t] = (uint8_t)count;
    }
    b.look_speed = input_get_f32(&c);
    b.stick_look_speed = input_get_f32(&c);
    b.dead_zone = input_get_f32(&c);
    uint32_t invert = input_get(&c, 1);
    float zone = input_get_f32(&c);
    if (!c.ok) return core_error_set(error, CORE_ERROR_CORRUPT, "header payload too short");
    if (c.at != c.end) return core_error_set(error, CORE_ERROR_CORRUPT, "%zu stray bytes in the header", (size_t)(c.end - c.at));
    b.invert_y = invert != 0;
    if (invert > 1 || !input__bindings_valid(&b) || !(zone >= 0.0f && zone <= INPUT_DEAD_ZONE_MAX))
        return core_error_set(error, CORE_ERROR_RANGE, "settings out of range");
    *bindings = b;
    *dead_zone = zone;
    return true;
}

bool input__event_valid(const input_event *e) {
    switch (e->kind) {
    case INPUT_EVENT_KEY: return e->code < INPUT_KEY_COUNT && e->down <= 1;
    case INPUT_EVENT_MOUSE_BUTTON: return e->code < INPUT_MOUSE_BUTTON_COUNT && e->down <= 1;
    case INPUT_EVENT_MOUSE_MOTION:
    case INPUT_EVENT_SCROLL: return isfinite(e->x) && isfinite(e->y);
    case INPUT_EVENT_GAMEPAD:
        return e->code < INPUT_MAX_GAMEPADS && isfinite(e->pad.lx) && isfinite(e->pad.ly) && isfinite(e->pad.rx) &&
               isfinite(e->pad.ry) && isfinite(e->pad.lt) && isfinite(e->pad.rt);
    case INPUT_EVENT_GAMEPAD_GONE: return e->code < INPUT_MAX_GAMEPADS;
    case INPUT_EVENT_CAPTURE: return e->down <= 1;
    default: return false;
    }
}

static void input_encode_event(input_bytes *b, const input_event *e) {
    input_put_u8(b, e->kind);
    switch (e->kind) {
    case INPUT_EVENT_KEY:
        input_put_u16(b, e->code);
        input_put_u8(b, e->down);
        break;
    case INPUT_EVENT_MOUSE_BUTTON:
        input_put_u8(b, e->code);
        input_put_u8(b, e->down);
        break;
    case INPUT_EVENT_MOUSE_MOTION:
    case INPUT_EVENT_SCROLL:
        input_put_f32(b, e->x);
        input_put_f32(b, e->y);
        break;
    case INPUT_EVENT_GAMEPAD:
        input_put_u8(b, e->code);
        input_put_f32(b, e->pad.lx);
        input_put_f32(b, e->pad.ly);
        input_put_f32(b, e->pad.rx);
        input_put_f32(b, e->pad.ry);
        input_put_f32(b, e->pad.lt);
        input_put_f32(b, e->pad.rt);
        input_put_u32(b, e->pad.buttons);
        break;
    case INPUT_EVENT_GAMEPAD_GONE: input_put_u8(b, e->code); break;
    case INPUT_EVENT_CAPTURE: input_put_u8(b, e->down); break;
    default: break;
    }
}

static input_event input_decode_event(input_cursor *c) {
    input_event e = { .kind = (uint8_t)input_get(c, 1) };
    switch (e.kind) {
    case INPUT_EVENT_KEY:
        e.code = (uint16_t)input_get(c, 2);
        e.down = (uint8_t)input_get(c, 1);
        break;
    case INPUT_EVENT_MOUSE_BUTTON:
        e.code = (uint16_t)input_get(c, 1);
        e.down = (uint8_t)input_get(c, 1);
        break;
    case INPUT_EVENT_MOUSE_MOTION:
    case INPUT_EVENT_SCROLL:
        e.x = input_get_f32(c);
        e.y = input_get_f32(c);
        break;
    case INPUT_EVENT_GAMEPAD:
        e.code = (uint16_t)input_get(c, 1);
        e.pad.lx = input_get_f32(c);
        e.pad.ly = input_get_f32(c);
        e.pad.rx = input_get_f32(c);
        e.pad.ry = input_get_f32(c);
        e.pad.lt = input_get_f32(c);
        e.pad.rt = input_get_f32(c);
        e.pad.buttons = input_get(c, 4);
        break;
    case INPUT_EVENT_GAMEPAD_GONE: e.code = (uint16_t)input_get(c, 1); break;
    case INPUT_EVENT_CAPTURE: e.down = (uint8_t)input_get(c, 1); break;
    default: break;
    }
    return e;
}

static void input_encode_actions(input_bytes *b, const input_actions *a) {
    input_put_f32(b, a->move_x);
    input_put_f32(b, a->move_y);
    input_put_f32(b, a->look_x);
    input_put_f32(b, a->look_y);
    input_put_u32(b, a->down);
    input_put_u32(b, a->pressed);
    input_put_u32(b, a->released);
}

bool input__record_decode_frame(const uint8_t *payload, size_t size, input_frame *frame, input_event *events,
                                uint32_t event_capacity, core_error *error) {
    input_cursor c = { payload, payload + size, true };
    frame->index = input_get(&c, 4);
    frame->dt = input_get_f32(&c);
    uint32_t count = input_get(&c, 4);
    if (!c.ok) return core_error_set(error, CORE_ERROR_CORRUPT, "frame record too short");
    if (!(frame->dt >= 0.0f) || !isfinite(frame->dt)) return core_error_set(error, CORE_ERROR_RANGE, "bad dt");
    if (count > event_capacity) return core_error_set(error, CORE_ERROR_RANGE, "%u events (at most %u)", count, event_capacity);
    for (uint32_t i = 0; i < count; i++) {
        events[i] = input_decode_event(&c);
        if (!c.ok) return core_error_set(error, CORE_ERROR_CORRUPT, "event %u cut short", i);
        if (!input__event_valid(&events[i])) return core_error_set(error, CORE_ERROR_FORMAT, "event %u is not valid", i);
    }
    input_actions *a = &frame->actions;
    a->move_x = input_get_f32(&c);
    a->move_y = input_get_f32(&c);
    a->look_x = input_get_f32(&c);
    a->look_y = input_get_f32(&c);
    a->down = input_get(&c, 4);
    a->pressed = input_get(&c, 4);
    a->released = input_get(&c, 4);
    if (!c.ok) return core_error_set(error, CORE_ERROR_CORRUPT, "frame record too short for its actions");
    if (c.at != c.end) return core_error_set(error, CORE_ERROR_CORRUPT, "%zu stray bytes after the actions", (size_t)(c.end - c.at));
    frame->events = events;
    frame->event_count = count;
    return true;
}

/* ---- writer --------------------------------------------------------------------------------- */

struct input_recorder {
    FILE *file;
    char *path, *part_path;
    uint32_t frames;
    bool failed;
    input_bytes record;
};

static void input_recorder_fail(input_recorder *r, const char *what) {
    if (!r->failed)
        core_log_error("input", "cannot write the recording %s: %s: %s; recording stops (what was written stays in %s)",
                   r->part_path, what, strerror(errno), r->part_path);
    r->failed = true;
}

/* Writes tag, length, payload (already in r->record after 8 reserved bytes), checksum. */
static void input_recorder_emit(input_recorder *r, const char tag[4]) {
    input_bytes *b = &r->record;
    memcpy(b->data, tag, 4);
    input_patch_u32(b, 4, (uint32_t)(b->size - 8));
    input_put_u32(b, input_checksum(b->data, b->size));
    if (!r->failed && (fwrite(b->data, 1, b->size, r->file) != b->size || fflush(r->file) != 0))
        input_recorder_fail(r, "write failed");
}

static void input_record_begin(input_bytes *b) {
    b->size = 0;
    input_put(b, "\0\0\0\0\0\0\0\0", 8);
}

input_recorder *input__recorder_open(const char *path, const input_bindings *bindings, float dead_zone,
                                     core_error *error) {
    input_recorder *r = core_calloc(1, sizeof *r);
    r->path = core_strdup(path);
    size_t size = strlen(path) + sizeof ".part";
    r->part_path = core_alloc(size);
    snprintf(r->part_path, size, "%s.part", path);
    r->file = fopen(r->part_path, "wb");
    if (!r->file) {
        core_error_set(error, CORE_ERROR_IO, "cannot write the recording %s: %s", r->part_path, strerror(errno));
        core_free(r->part_path, size);
        core_free(r->path, strlen(r->path) + 1);
        core_free(r, sizeof *r);
        return NULL;
    }
    input_bytes *b = &r->record;
    input_put(b, input_record_magic, 8);
    input_put_u32(b, INPUT_RECORD_VERSION);
    input_put_u32(b, 0);
    input_encode_header(b, bindings, dead_zone);
    input_patch_u32(b, 12, (uint32_t)(b->size - 16));
    input_put_u32(b, input_checksum(b->data, b->size));
    if (fwrite(b->data, 1, b->size, r->file) != b->size || fflush(r->file) != 0) {
        core_error_set(error, CORE_ERROR_IO, "cannot write the recording %s: %s", r->part_path, strerror(errno));
        fclose(r->file);
        remove(r->part_path);
        input_bytes_free(b);
        core_free(r->part_path, size);
        core_free(r->path, strlen(r->path) + 1);
        core_free(r, sizeof *r);
        return NULL;
    }
    return r;
}

void input__recorder_write(input_recorder *r, float dt, const input_event *events, uint32_t count,
                           const input_actions *actions) {
    if (r->failed) return;
    input_bytes *b = &r->record;
    input_record_begin(b);
    input_put_u32(b, r->frames);
    input_put_f32(b, dt);
    input_put_u32(b, count);
    for (uint32_t i = 0; i < count; i++) input_encode_event(b, &events[i]);
    input_encode_actions(b, actions);
    input_recorder_emit(r, input_tag_frame);
    r->frames++;
}

void input__recorder_close(input_recorder *r) {
    if (!r) return;
    input_record_begin(&r->record);
    input_put_u32(&r->record, r->frames);
    input_recorder_emit(r, input_tag_end);
    if (fclose(r->file) != 0) input_recorder_fail(r, "close failed");
    if (!r->failed) {
        if (rename(r->part_path, r->path) != 0)
            core_log_error("input", "cannot rename the recording %s to %s: %s", r->part_path, r->path, strerror(errno));
        else
            core_info("input", "recorded %u frames to %s", r->frames, r->path);
    }
    input_bytes_free(&r->record);
    core_free(r->part_path, strlen(r->part_path) + 1);
    core_free(r->path, strlen(r->path) + 1);
    core_free(r, sizeof *r);
}

/* ---- reader --------------------------------------------------------------------------------- */

struct input_replayer {
    FILE *file;
    char *path;
    uint64_t offset;           /* of the next record, for messages */
    uint32_t frames;           /* frames delivered */
    bool done, failed;
    input_bytes record;
    input_event *events;       /* INPUT_MAX_EVENTS */
};

static void input_replayer_stop(input_replayer *r, bool failed, const char *fmt, ...) CORE_PRINTF(3, 4);
static void input_replayer_stop(input_replayer *r, bool failed, const char *fmt, ...) {
    char reason[256];
    va_list args;
    va_start(args, fmt);
    vsnprintf(reason, sizeof reason, fmt, args);
    va_end(args);
    core_log_error("input", "replay %s: after frame %u (byte %llu): %s; the replay ends here", r->path, r->frames,
               (unsigned long long)r->offset, reason);
    r->done = true;
    r->failed = failed;
}

/* Reads `size` bytes; false at a short read. */
static bool input_read_exact(input_replayer *r, uint8_t *out, size_t size) { return fread(out, 1, size, r->file) == size; }

static void input_replayer_free(input_replayer *r) {
    if (r->file) fclose(r->file);
    input_bytes_free(&r->record);
    if (r->events) core_free(r->events, INPUT_MAX_EVENTS * sizeof *r->events);
    core_free(r->path, strlen(r->path) + 1);
    core_free(r, sizeof *r);
}

input_replayer *input__replayer_open(const char *path, input_bindings *bindings, float *dead_zone,
                                     core_error *error) {
    input_replayer *r = core_calloc(1, sizeof *r);
    r->path = core_strdup(path);
    r->file = fopen(path, "rb");
    if (!r->file) {
        core_error_set(error, CORE_ERROR_IO, "cannot open the replay %s: %s", path, strerror(errno));
        input_replayer_free(r);
        return NULL;
    }
    uint8_t head[16];
    core_error why = { 0 };
    input_bytes *b = &r->record;
    if (!input_read_exact(r, head, sizeof head)) {
        core_error_set(&why, CORE_ERROR_CORRUPT, "too short for a header (truncated or empty)");
    } else if (memcmp(head, input_record_magic, 8) != 0) {
        core_error_set(&why, CORE_ERROR_FORMAT, "not an input recording (bad magic)");
    } else if (input_read_u32(head + 8) != INPUT_RECORD_VERSION) {
        core_error_set(&why, CORE_ERROR_VERSION, "recording version %u; this build reads version %d",
                       input_read_u32(head + 8), INPUT_RECORD_VERSION);
    } else if (input_read_u32(head + 12) > INPUT_RECORD_MAX_HEADER) {
        core_error_set(&why, CORE_ERROR_CORRUPT, "header length %u is corrupt", input_read_u32(head + 12));
    } else {
        size_t length = input_read_u32(head + 12);
        input_put(b, head, sizeof head);
        b->data = core_grow(b->data, &b->capacity, b->size + length + 4, 1);
        if (!input_read_exact(r, b->data + b->size, length + 4)) {
            core_error_set(&why, CORE_ERROR_CORRUPT, "header truncated");
        } else if (input_checksum(b->data, 16 + length) != input_read_u32(b->data + 16 + length)) {
            core_error_set(&why, CORE_ERROR_CORRUPT, "header checksum mismatch (corrupt)");
        } else {
            core_error bad = { 0 };
            if (!input__record_decode_header(b->data + 16, length, bindings, dead_zone, &bad))
                core_error_set(&why, bad.code ? bad.code : CORE_ERROR_FORMAT, "bad header: %s", bad.message);
            r->offset = 16 + length + 4;
        }
    }
    if (why.code) {
        core_error_set(error, why.code, "cannot replay %s: %s", path, why.message);
        input_replayer_free(r);
        return NULL;
    }
    r->events = core_alloc(INPUT_MAX_EVENTS * sizeof *r->events);
    return r;
}

bool input__replayer_next(input_replayer *r, input_frame *frame) {
    if (r->done) return false;
    uint8_t head[8];
    size_t got = fread(head, 1, sizeof head, r->file);
    if (got == 0 && feof(r->file)) {
        input_replayer_stop(r, true, "the file ends without its end record: the recording was cut short");
        return false;
    }
    if (got < sizeof head) {
        input_replayer_stop(r, true, "truncated record");
        return false;
    }
    bool is_end = memcmp(head, input_tag_end, 4) == 0;
    if (!is_end && memcmp(head, input_tag_frame, 4) != 0) {
        input_replayer_stop(r, true, "no record here (corrupt)");
        return false;
    }
    uint32_t length = input_read_u32(head + 4);
    if (length > (is_end ? 4u : (uint32_t)INPUT_RECORD_MAX_FRAME)) {
        input_replayer_stop(r, true, "record length %u is corrupt", length);
        return false;
    }
    input_bytes *b = &r->record;
    b->size = 0;
    input_put(b, head, sizeof head);
    b->data = core_grow(b->data, &b->capacity, 8 + (size_t)length + 4, 1);
    if (!input_read_exact(r, b->data + 8, (size_t)length + 4)) {
        input_replayer_stop(r, true, "truncated record");
        return false;
    }
    if (input_checksum(b->data, 8 + (size_t)length) != input_read_u32(b->data + 8 + length)) {
        input_replayer_stop(r, true, "checksum mismatch (corrupt)");
        return false;
    }
    if (is_end) {
        uint32_t count = length == 4 ? input_read_u32(b->data + 8) : UINT32_MAX;
        if (count != r->frames) input_replayer_stop(r, true, "end record counts %u frames (corrupt)", count);
        else if (fgetc(r->file) != EOF) input_replayer_stop(r, true, "bytes after the end record (corrupt)");
        r->done = true;
        return false;
    }
    core_error error = { 0 };
    if (!input__record_decode_frame(b->data + 8, length, frame, r->events, INPUT_MAX_EVENTS, &error)) {
        input_replayer_stop(r, true, "%s (corrupt)", error.message);
        return false;
    }
    if (frame->index != r->frames) {
        input_replayer_stop(r, true, "frame numbered %u (corrupt)", frame->index);
        return false;
    }
    r->offset += 8 + (uint64_t)length + 4;
    r->frames++;
    return true;
}

bool input__replayer_failed(const input_replayer *r) { return r->failed; }

void input__replayer_close(input_replayer *r) {
    if (r) input_replayer_free(r);
}
