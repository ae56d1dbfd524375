/* Tests of record and replay (engine/input/input_record.c, input_system.c): a scripted session
 * recorded and replayed gives the same actions bit for bit; the file follows the documented
 * layout (engine/input/README.md, "Record file"), read here independently of the reader; cut,
 * corrupted, wrong-magic and missing files are clear errors, never crashes (ASan watches). */
#include "core/core.h"
#include "input/input.h"
#include "input/input_internal.h"
#include "test.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- files ---------------------------------------------------------------------------------- */

typedef struct bytes {
    uint8_t *data;
    size_t size;
} bytes;

static bytes read_all(const char *path) {
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "%s", path);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    rewind(f);
    bytes b = { malloc((size_t)size + 1), (size_t)size };
    cr_assert_eq(fread(b.data, 1, b.size, f), b.size);
    fclose(f);
    return b;
}

static void write_all(const char *path, const uint8_t *data, size_t size) {
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "%s", path);
    cr_assert_eq(fwrite(data, 1, size, f), size);
    fclose(f);
}

static bool exists(const char *path) { return access(path, F_OK) == 0; }

static void temp_path(char *out, size_t size, const char *name) {
    snprintf(out, size, "/tmp/test_input_record_%d_%s", (int)getpid(), name);
}

static uint32_t le32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Record boundaries, from the layout in README.md. */
typedef struct layout {
    size_t header_end;
    size_t start[1024], end[1024];
    int records;
} layout;

static void read_layout(const bytes *b, layout *out) {
    cr_assert_geq(b->size, 20u);
    out->header_end = 16 + le32(b->data + 12) + 4;
    out->records = 0;
    for (size_t at = out->header_end; at < b->size && out->records < 1024;) {
        out->start[out->records] = at;
        at += 8 + le32(b->data + at + 4) + 4;
        out->end[out->records++] = at;
    }
}

/* ---- a scripted session --------------------------------------------------------------------- */

static uint64_t next(uint64_t *s) {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static float unit(uint64_t *s) { return (float)((int)(next(s) % 4001) - 2000) / 2000.0f; } /* [-1, 1] */

typedef struct script {
    uint64_t rng;
    bool keys[INPUT_KEY_COUNT];
    bool buttons[3];
} script;

/* One frame of made-up play: keys, clicks, motion, scroll, two pads coming and going, capture. */
static float script_frame(script *s, input_system *in) {
    static const int keys[] = { GLFW_KEY_W, GLFW_KEY_A, GLFW_KEY_S, GLFW_KEY_D, GLFW_KEY_SPACE,
                                GLFW_KEY_LEFT_SHIFT, GLFW_KEY_C, GLFW_KEY_F, GLFW_KEY_ESCAPE, GLFW_KEY_J };
    int events = (int)(next(&s->rng) % 5);
    for (int e = 0; e < events; e++) {
        uint64_t r = next(&s->rng);
        switch (r % 10) {
        case 0: case 1: case 2: case 3: {
            int key = keys[(r >> 8) % (sizeof keys / sizeof keys[0])];
            s->keys[key] = !s->keys[key];
            input_feed_key(in, key, s->keys[key]);
            break;
        }
        case 4: {
            int button = (int)((r >> 8) % 3);
            s->buttons[button] = !s->buttons[button];
            input_feed_mouse_button(in, button, s->buttons[button]);
            break;
        }
        case 5: input_feed_mouse_motion(in, 20.0f * unit(&s->rng), 20.0f * unit(&s->rng)); break;
        case 6: {
            input_gamepad_state pad = { .lx = unit(&s->rng), .ly = unit(&s->rng), .rx = unit(&s->rng),
                                        .ry = unit(&s->rng), .lt = 0.5f + 0.5f * unit(&s->rng),
                                        .rt = 0.5f + 0.5f * unit(&s->rng),
                                        .buttons = (uint32_t)(next(&s->rng) & 0x1ffff) };
            input_feed_gamepad(in, (int)((r >> 8) % 2), &pad);
            break;
        }
        case 7: input_feed_gamepad(in, (int)((r >> 8) % 2), NULL); break;
        case 8: input_feed_scroll(in, unit(&s->rng), unit(&s->rng)); break;
        default: input_capture_mouse(in, (r >> 8) & 1); break;
        }
    }
    return 0.005f + (float)(next(&s->rng) % 1000) * 1e-5f;
}

static input_bindings *session_bindings(void) {
    const char text[] = "jump = key:j, pad:south\nlook_speed = 0.003\ninvert_y = true\nstick_look_speed = 2\n";
    return input_bindings_parse(text, sizeof text - 1, "session", NULL);
}

/* Records `frames` frames to `path`; returns the actions and dts computed live (caller frees). */
static input_actions *record_session(const char *path, int frames, float **dts) {
    input_bindings *b = session_bindings();
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .bindings = b, .record_path = path }, NULL);
    input_bindings_destroy(b);
    cr_assert_not_null(in);
    input_actions *actions = malloc((size_t)frames * sizeof *actions);
    *dts = malloc((size_t)frames * sizeof **dts);
    script s = { .rng = 0x243f6a8885a308d3ull };
    for (int f = 0; f < frames; f++) {
        float dt = script_frame(&s, in);
        cr_assert(input_update(in, dt));
        actions[f] = *input_actions_get(in);
        (*dts)[f] = dt;
    }
    input_system_destroy(in);
    return actions;
}

static bool same_bits(const input_actions *a, const input_actions *b) { return memcmp(a, b, sizeof *a) == 0; }

/* Replays `path` to its end; returns the frames delivered. */
static int replay_count(const char *path, bool *failed) {
    input_system *in = input_system_create(&(input_system_desc){ .replay_path = path }, NULL);
    if (!in) return -1;
    int frames = 0;
    while (input_update(in, 0.0f) && frames < 100000) frames++;
    *failed = input__replay_failed(in);
    input_system_destroy(in);
    return frames;
}

/* ---- round trip ----------------------------------------------------------------------------- */

Test(input_record, replay_reproduces_every_frame_bit_for_bit) {
    char path[256], part[300];
    temp_path(path, sizeof path, "session.rec");
    snprintf(part, sizeof part, "%s.part", path);
    enum { FRAMES = 600 };
    float *dts;
    input_actions *recorded = record_session(path, FRAMES, &dts);
    cr_expect(exists(path));
    cr_expect_not(exists(part), "the temporary is renamed over the target");

    /* The session exercised what it should have. */
    uint32_t any_pressed = 0;
    bool any_look = false, any_move = false;
    for (int f = 0; f < FRAMES; f++) {
        any_pressed |= recorded[f].pressed;
        any_look |= recorded[f].look_x != 0.0f;
        any_move |= recorded[f].move_x != 0.0f;
    }
    cr_expect_neq(any_pressed & INPUT_ACTION_BIT(INPUT_ACTION_JUMP), 0u);
    cr_expect(any_look);
    cr_expect(any_move);

    /* Replay with the default bindings and no-pads left out: the file's bindings apply, no device opens. */
    input_system *in = input_system_create(&(input_system_desc){ .replay_path = path }, NULL);
    cr_assert_not_null(in);
    cr_expect_not(input__gamepad_thread_running(in));
    for (int f = 0; f < FRAMES; f++) {
        input_feed_key(in, GLFW_KEY_W, true); /* ignored while replaying */
        cr_assert(input_update(in, 123.0f), "frame %d", f);
        cr_expect(same_bits(input_actions_get(in), &recorded[f]), "frame %d differs", f);
        float dt = input_frame_dt(in);
        cr_expect_eq(memcmp(&dt, &dts[f], sizeof dt), 0, "frame %d: recorded dt", f);
    }
    cr_expect_not(input_update(in, 0.016f), "the replay has ended");
    cr_expect_not(input_update(in, 0.016f));
    cr_expect_eq(input_actions_get(in)->down, 0u);
    cr_expect_eq(input__replay_mismatches(in), 0u);
    cr_expect_not(input__replay_failed(in));
    input_system_destroy(in);
    free(recorded);
    free(dts);
    unlink(path);
}

Test(input_record, file_layout_as_documented) {
    char path[256];
    temp_path(path, sizeof path, "layout.rec");
    float *dts;
    input_actions *recorded = record_session(path, 40, &dts);
    bytes b = read_all(path);
    cr_assert_geq(b.size, 20u);
    cr_expect_eq(memcmp(b.data, "INPUTREC", 8), 0);
    cr_expect_eq(le32(b.data + 8), 1u);
    layout l;
    read_layout(&b, &l);
    cr_expect_eq(le32(b.data + l.header_end - 4), (uint32_t)core_hash_bytes(b.data, l.header_end - 4, 0));
    cr_assert_eq(l.records, 41, "40 frames and the end record");
    cr_expect_eq(l.end[40], b.size);
    for (int r = 0; r < l.records; r++) {
        const uint8_t *rec = b.data + l.start[r];
        size_t length = le32(rec + 4);
        cr_expect_eq(memcmp(rec, r < 40 ? "FRAM" : "END!", 4), 0, "record %d", r);
        cr_expect_eq(le32(rec + 8 + length), (uint32_t)core_hash_bytes(rec, 8 + length, 0), "record %d", r);
        if (r < 40) {
            cr_expect_eq(le32(rec + 8), (uint32_t)r, "frame index");
            uint32_t dt_bits;
            memcpy(&dt_bits, &dts[r], 4);
            cr_expect_eq(le32(rec + 12), dt_bits, "dt bits");
            /* The actions are the payload's last 28 bytes: move, look, down, pressed, released. */
            const uint8_t *a = rec + 8 + length - 28;
            float move_x;
            memcpy(&move_x, a, 4);
            cr_expect_eq(memcmp(&move_x, &recorded[r].move_x, 4), 0);
            cr_expect_eq(le32(a + 16), recorded[r].down);
            cr_expect_eq(le32(a + 20), recorded[r].pressed);
            cr_expect_eq(le32(a + 24), recorded[r].released);
        } else {
            cr_expect_eq(length, 4u);
            cr_expect_eq(le32(rec + 8), 40u, "the end record counts the frames");
        }
    }
    free(b.data);
    free(recorded);
    free(dts);
    unlink(path);
}

/* A replay recomputes; where the recorded actions disagree it warns (once) and keeps going. */
Test(input_record, a_changed_recorded_action_is_a_determinism_warning) {
    char path[256];
    temp_path(path, sizeof path, "drift.rec");
    float *dts;
    input_actions *recorded = record_session(path, 20, &dts);
    bytes b = read_all(path);
    layout l;
    read_layout(&b, &l);
    for (int r = 3; r <= 5; r++) { /* frames 3, 4, 5: move_x += 1 ulp-ish, checksum fixed up */
        uint8_t *rec = b.data + l.start[r];
        size_t length = le32(rec + 4);
        rec[8 + length - 28] ^= 1;
        uint32_t sum = (uint32_t)core_hash_bytes(rec, 8 + length, 0);
        for (int i = 0; i < 4; i++) rec[8 + length + (size_t)i] = (uint8_t)(sum >> (8 * i));
    }
    write_all(path, b.data, b.size);
    input_system *in = input_system_create(&(input_system_desc){ .replay_path = path }, NULL);
    cr_assert_not_null(in);
    for (int f = 0; f < 20; f++) {
        cr_assert(input_update(in, 0.0f));
        cr_expect(same_bits(input_actions_get(in), &recorded[f]), "recomputed, not read: frame %d", f);
    }
    cr_expect_not(input_update(in, 0.0f));
    cr_expect_eq(input__replay_mismatches(in), 3u);
    cr_expect_not(input__replay_failed(in));
    input_system_destroy(in);
    free(b.data);
    free(recorded);
    free(dts);
    unlink(path);
}

/* ---- bad files ------------------------------------------------------------------------------ */

Test(input_record, missing_empty_wrong_magic_and_version_are_refused) {
    char path[256];
    temp_path(path, sizeof path, "bad.rec");
    core_error error = { 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .replay_path = "/nonexistent/replay.rec" }, &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "missing: %s", error.message);
    cr_expect_not_null(strstr(error.message, "/nonexistent/replay.rec"), "names the file: %s", error.message);
    write_all(path, (const uint8_t *)"", 0);
    error = (core_error){ 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .replay_path = path }, &error));
    cr_expect_eq(error.code, CORE_ERROR_CORRUPT, "empty: %s", error.message);

    float *dts;
    free(record_session(path, 3, &dts));
    free(dts);
    bytes b = read_all(path);
    b.data[0] = 'X';
    write_all(path, b.data, b.size);
    error = (core_error){ 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .replay_path = path }, &error), "wrong magic");
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "wrong magic: %s", error.message);
    b.data[0] = 'I';
    b.data[8] = 2;
    write_all(path, b.data, b.size);
    error = (core_error){ 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .replay_path = path }, &error), "unknown version");
    cr_expect_eq(error.code, CORE_ERROR_VERSION, "unknown version: %s", error.message);
    b.data[8] = 1;
    b.data[16] ^= 0x40;  /* a byte of the header's payload: its checksum no longer matches */
    write_all(path, b.data, b.size);
    error = (core_error){ 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .replay_path = path }, &error), "damaged header");
    cr_expect_eq(error.code, CORE_ERROR_CORRUPT, "damaged header: %s", error.message);
    b.data[16] ^= 0x40;
    write_all(path, b.data, b.size);
    error = (core_error){ 0 };
    input_system *in = input_system_create(&(input_system_desc){ .replay_path = path }, &error);
    cr_expect_not_null(in, "restored, it replays");
    cr_expect_eq(error.code, CORE_ERROR_NONE);
    input_system_destroy(in);
    free(b.data);
    unlink(path);
}

Test(input_record, every_truncation_is_caught) {
    char path[256], cut[256];
    temp_path(path, sizeof path, "whole.rec");
    temp_path(cut, sizeof cut, "cut.rec");
    float *dts;
    free(record_session(path, 8, &dts));
    free(dts);
    bytes b = read_all(path);
    layout l;
    read_layout(&b, &l);
    core_log_set_level(CORE_LOG_OFF); /* a message per cut otherwise */
    for (size_t size = 0; size < b.size; size++) {
        write_all(cut, b.data, size);
        bool failed = false;
        int frames = replay_count(cut, &failed);
        if (size < l.header_end) {
            cr_expect_eq(frames, -1, "cut at %zu (in the header): refused", size);
            continue;
        }
        int whole = 0; /* frame records wholly inside the cut */
        while (whole < 8 && l.end[whole] <= size) whole++;
        cr_expect_eq(frames, whole, "cut at %zu", size);
        cr_expect(failed, "cut at %zu: reported as cut short", size);
    }
    core_log_set_level(CORE_LOG_INFO);
    free(b.data);
    unlink(path);
    unlink(cut);
}

Test(input_record, every_corrupted_byte_is_caught) {
    char path[256], bad[256];
    temp_path(path, sizeof path, "clean.rec");
    temp_path(bad, sizeof bad, "flipped.rec");
    float *dts;
    free(record_session(path, 6, &dts));
    free(dts);
    bytes b = read_all(path);
    layout l;
    read_layout(&b, &l);
    core_log_set_level(CORE_LOG_OFF);
    for (size_t at = 0; at < b.size; at++) {
        b.data[at] ^= 0x24;
        write_all(bad, b.data, b.size);
        b.data[at] ^= 0x24;
        bool failed = false;
        int frames = replay_count(bad, &failed);
        if (at < l.header_end) {
            cr_expect_eq(frames, -1, "byte %zu (header)", at);
            continue;
        }
        int record = 0;
        while (l.end[record] <= at) record++;
        cr_expect_eq(frames, record, "byte %zu: frames before the bad record", at);
        cr_expect(failed, "byte %zu", at);
    }
    core_log_set_level(CORE_LOG_INFO);
    free(b.data);
    unlink(path);
    unlink(bad);
}

Test(input_record, trailing_garbage_after_the_end_is_reported) {
    char path[256];
    temp_path(path, sizeof path, "trailing.rec");
    float *dts;
    free(record_session(path, 4, &dts));
    free(dts);
    FILE *f = fopen(path, "ab");
    fputs("junk", f);
    fclose(f);
    bool failed = false;
    cr_expect_eq(replay_count(path, &failed), 4);
    cr_expect(failed);
    unlink(path);
}

/* A crash leaves PATH.part: whole frames up to the crash, which replay, then "cut short". */
Test(input_record, an_interrupted_recording_replays_up_to_the_crash) {
    char path[256], part[300], copy[256];
    temp_path(path, sizeof path, "crash.rec");
    temp_path(copy, sizeof copy, "crash_copy.rec");
    snprintf(part, sizeof part, "%s.part", path);
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .record_path = path }, NULL);
    cr_assert_not_null(in);
    script s = { .rng = 77 };
    input_actions live[5];
    for (int f = 0; f < 5; f++) {
        cr_assert(input_update(in, script_frame(&s, in)));
        live[f] = *input_actions_get(in);
    }
    cr_expect(exists(part));
    cr_expect_not(exists(path), "the target appears only when the recording ends");
    bytes b = read_all(part); /* what a crash right now would leave */
    write_all(copy, b.data, b.size);
    input_system_destroy(in);
    cr_expect(exists(path));

    input_system *replay = input_system_create(&(input_system_desc){ .replay_path = copy }, NULL);
    cr_assert_not_null(replay);
    for (int f = 0; f < 5; f++) {
        cr_assert(input_update(replay, 0.0f));
        cr_expect(same_bits(input_actions_get(replay), &live[f]), "frame %d", f);
    }
    cr_expect_not(input_update(replay, 0.0f));
    cr_expect(input__replay_failed(replay));
    input_system_destroy(replay);
    free(b.data);
    unlink(path);
    unlink(copy);
}

Test(input_record, unwritable_record_path_fails_at_create) {
    core_error error = { 0 };
    cr_expect_null(input_system_create(&(input_system_desc){ .no_gamepads = true, .record_path = "/nonexistent/dir/x.rec" },
                                       &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s", error.message);
    cr_expect_not_null(strstr(error.message, "/nonexistent/dir/x.rec"), "names the file: %s", error.message);
}

Test(input_record, a_replay_can_be_recorded_again_identically) {
    char first[256], second[256];
    temp_path(first, sizeof first, "first.rec");
    temp_path(second, sizeof second, "second.rec");
    float *dts;
    free(record_session(first, 50, &dts));
    free(dts);
    input_system *in = input_system_create(&(input_system_desc){ .replay_path = first, .record_path = second }, NULL);
    cr_assert_not_null(in);
    while (input_update(in, 0.0f)) {}
    input_system_destroy(in);
    bytes a = read_all(first), b = read_all(second);
    cr_expect_eq(a.size, b.size);
    cr_expect(a.size == b.size && memcmp(a.data, b.data, a.size) == 0, "same bytes");
    free(a.data);
    free(b.data);
    unlink(first);
    unlink(second);
}
