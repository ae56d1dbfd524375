/* fuzz_replay — libFuzzer target for the record-file reader (engine/input/input_record.c) and the
 * replay path of the input system (engine/input/input_system.c).
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's sources, runs each 20 s)
 * Seeds: tests/fuzz/corpus/fuzz_replay/ (a short recorded session; one frame's payload; one
 * header's payload).
 *
 * Each input is tried three ways (four, counting the report-descriptor check below): as a whole file given to input_system_create(.replay_path) and played
 * to its end; and, since a fuzzer rarely gets a checksum right, as a header payload and as a
 * frame payload fed straight to the decoders behind the reader. Besides "no crash, no leak, no
 * read out of bounds" it traps when a property fails: a decoder that refuses says why, what it
 * accepts is valid (events in range, bindings valid), and move never exceeds length 1.
 */
#include "core/core.h"
#include "input/input.h"
#include "input/input_internal.h"

#include <math.h>
#include <stdio.h>
#include <sys/mman.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

static void fuzz_check_move(const input_actions *a) {
    if (!(sqrtf(a->move_x * a->move_x + a->move_y * a->move_y) <= 1.0f + 1e-5f)) __builtin_trap();
}

/* The whole file, through a memory file the reader opens by path. */
static void fuzz_file(const unsigned char *bytes, size_t size) {
    static int fd = -1;
    static char path[64];
    if (fd < 0) {
        fd = memfd_create("fuzz_replay", 0);
        if (fd < 0) __builtin_trap();
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    if (ftruncate(fd, 0) != 0 || (size && pwrite(fd, bytes, size, 0) != (ssize_t)size)) __builtin_trap();
    input_system *in = input_system_create(&(input_system_desc){ .replay_path = path }, NULL);
    if (!in) return;
    for (int frame = 0; frame < 100000 && input_update(in, 0.016f); frame++) {
        fuzz_check_move(input_actions_get(in));
        if (!(input_frame_dt(in) >= 0.0f)) __builtin_trap();
    }
    input_system_destroy(in);
}

static void fuzz_payloads(const unsigned char *bytes, size_t size) {
    core_error error = { 0 };
    input_bindings bindings;
    float dead_zone;
    if (input__record_decode_header(bytes, size, &bindings, &dead_zone, &error)) {
        if (!input__bindings_valid(&bindings) || !(dead_zone >= 0.0f && dead_zone <= 1.0f)) __builtin_trap();
    } else if (error.code == CORE_ERROR_NONE || !error.message[0]) {
        __builtin_trap();
    }

    static input_event events[INPUT_MAX_EVENTS];
    input_frame frame;
    error = (core_error){ 0 };
    if (!input__record_decode_frame(bytes, size, &frame, events, INPUT_MAX_EVENTS, &error)) {
        if (error.code == CORE_ERROR_NONE || !error.message[0]) __builtin_trap();
        return;
    }
    static input_state state;
    input_bindings defaults;
    input__bindings_set_default(&defaults);
    input__state_init(&state, &defaults, 0.15f);
    input__state_begin_frame(&state);
    for (uint32_t i = 0; i < frame.event_count; i++) {
        if (!input__event_valid(&frame.events[i])) __builtin_trap();
        input__state_apply(&state, &frame.events[i]);
    }
    input__state_end_frame(&state, frame.dt);
    fuzz_check_move(&state.actions);
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    core_log_set_level(CORE_LOG_OFF); /* a bad file is a message otherwise */
    fuzz_file(bytes, size);
    fuzz_payloads(bytes, size);
    /* The other bytes the input system reads from outside: a report descriptor from sysfs, of
     * which the gamepad thread checks the top-level usage. Only "stays in bounds" to check. */
    (void)input__descriptor_is_gamepad(bytes, size);
    return 0;
}
