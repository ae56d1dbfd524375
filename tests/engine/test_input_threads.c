/* Tests of the gamepad thread and the slots it publishes into (engine/input/input_gamepads.c,
 * input_system.c). Only the macros test.h provides, so that test_threads can run them under
 * ThreadSanitizer too. */
#include "core/core.h"
#include "input/input.h"
#include "input/input_internal.h"
#include "test.h"

#include <pthread.h>
#include <sched.h>
#include <time.h>

static double ms_since(uint64_t t0) { return (double)(core_time_ns() - t0) * 1e-6; }

/* With gamepads enabled and none plugged in (or no hidraw at all), the thread starts, scans,
 * sleeps, and input_system_destroy wakes and joins it at once — not after its one-second period. */
Test(input_threads, gamepad_thread_starts_and_stops_quickly) {
    uint64_t t0 = core_time_ns();
    input_system *in = input_system_create(&(input_system_desc){ 0 }, NULL);
    cr_assert_not_null(in);
    cr_expect(input__gamepad_thread_running(in), "hid_init succeeds on Linux's hidraw backend");
    for (int i = 0; i < 3; i++) cr_assert(input_update(in, 0.016f));
    input_system_destroy(in);
    double whole = ms_since(t0);
    cr_expect_lt(whole, 100.0, "create, 3 frames, destroy took %.1f ms", whole);

    /* Once the thread sleeps between scans, stopping still takes no more than a moment. */
    in = input_system_create(&(input_system_desc){ 0 }, NULL);
    cr_assert_not_null(in);
    nanosleep(&(struct timespec){ .tv_nsec = 30 * 1000 * 1000 }, NULL);
    t0 = core_time_ns();
    input_system_destroy(in);
    double stop = ms_since(t0);
    cr_expect_lt(stop, 100.0, "destroy took %.1f ms", stop);
}

Test(input_threads, no_thread_without_gamepads) {
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true }, NULL);
    cr_assert_not_null(in);
    cr_expect_not(input__gamepad_thread_running(in));
    input_system_destroy(in);
}

enum { PUBLISHED = 20000 };

static void *publisher(void *arg) {
    input_pads_shared *pads = arg;
    for (int i = 1; i <= PUBLISHED; i++) {
        input_gamepad_state state = { .lx = (float)i / PUBLISHED,
                                      .buttons = (i & 1) ? 1u << INPUT_BUTTON_SOUTH : 0u };
        input__gamepad_publish(pads, 0, &state);
    }
    return NULL;
}

/* A thread publishing as the reader thread does, while the main thread updates: every frame sees
 * a state the publisher wrote (never a torn one), in order, and the last one in the end. */
Test(input_threads, published_states_arrive_whole_and_in_order) {
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .dead_zone = 0.01f }, NULL);
    cr_assert_not_null(in);
    pthread_t thread;
    cr_assert_eq(pthread_create(&thread, NULL, publisher, input__pads(in)), 0);
    float last = 0.0f;
    int presses = 0;
    for (int frame = 0; frame < 2000; frame++) {
        cr_assert(input_update(in, 0.001f));
        float lx = input_gamepad(in).lx;
        cr_expect_geq(lx, last, "frame %d went back: %f after %f", frame, (double)lx, (double)last);
        last = lx;
        presses += (input_actions_get(in)->pressed & INPUT_ACTION_BIT(INPUT_ACTION_JUMP)) != 0;
    }
    pthread_join(thread, NULL);
    cr_assert(input_update(in, 0.001f));
    cr_expect_eq(input_gamepad(in).lx, 1.0f);
    cr_expect_eq(input_gamepad_count(in), 1);
    cr_expect_leq(presses, PUBLISHED / 2 + 1);
    input_system_destroy(in);
}

/* Two readers (as the hidraw thread and the GLFW reader on the main thread) claiming and releasing
 * slots at once: a slot is never held by both; each checks that the slot it got still carries its
 * own mark while it holds it. */
enum { CLAIMS = 5000 };

typedef struct claimer { input_pads_shared *pads; bool hidraw; int clashes, claimed; } claimer;

static void *claim_loop(void *arg) {
    claimer *c = arg;
    uint16_t mark = c->hidraw ? 0xaaaa : 0x5555;
    for (int i = 0; i < CLAIMS; i++) {
        int slot = input__pad_slot_claim(c->pads, c->hidraw, mark, (uint16_t)i, "pad");
        if (slot < 0) continue;
        c->claimed++;
        sched_yield(); /* hold it a moment, so the other reader has a chance to claim meanwhile */
        pthread_mutex_lock(&c->pads->lock);
        c->clashes += c->pads->slots[slot].vendor_id != mark || c->pads->slots[slot].hidraw != c->hidraw;
        pthread_mutex_unlock(&c->pads->lock);
        input__pad_slot_release(c->pads, slot);
    }
    return NULL;
}

Test(input_threads, slots_are_never_claimed_twice) {
    input_pads_shared pads;
    input__pads_shared_init(&pads);
    claimer a = { .pads = &pads, .hidraw = true }, b = { .pads = &pads, .hidraw = false };
    pthread_t thread;
    cr_assert_eq(pthread_create(&thread, NULL, claim_loop, &a), 0);
    claim_loop(&b);
    pthread_join(thread, NULL);
    cr_expect_eq(a.clashes + b.clashes, 0);
    cr_expect_eq(a.claimed, CLAIMS); /* 8 slots, at most 2 held at once: every claim succeeds */
    cr_expect_eq(b.claimed, CLAIMS);
    for (int i = 0; i < INPUT_MAX_GAMEPADS; i++) cr_expect(!pads.slots[i].claimed);
    input__pads_shared_destroy(&pads);
}

/* ---- which HID devices are gamepads (the thread's check of a report descriptor) -------------- */

#define DESCRIPTOR(...) ((const uint8_t[]){ __VA_ARGS__ }), sizeof((const uint8_t[]){ __VA_ARGS__ })

Test(input_gamepads, top_level_usage_decides) {
    /* Usage Page (Generic Desktop), Usage (Game Pad), Collection (Application) … End Collection */
    cr_expect(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x09, 0x30, 0xc0)));
    /* … Usage (Joystick) */
    cr_expect(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x04, 0xa1, 0x01, 0xc0)));
    /* … Usage (Keyboard), (Mouse): not pads */
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0xc0)));
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x09, 0x01,
                                                          0xa1, 0x00, 0xc0, 0xc0)));
    /* Usage 0x05 on another page (Game Controls page 0x05, usage 5) is not Generic Desktop's. */
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x05, 0x09, 0x05, 0xa1, 0x01, 0xc0)));
    /* An extended (4-byte) usage carries its page: 0x0001_0005. */
    cr_expect(input__descriptor_is_gamepad(DESCRIPTOR(0x0b, 0x05, 0x00, 0x01, 0x00, 0xa1, 0x01, 0xc0)));
    /* A keyboard first, a gamepad second, both top level. */
    cr_expect(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0xc0,
                                                      0x09, 0x05, 0xa1, 0x01, 0xc0)));
    /* A gamepad usage nested inside a keyboard's collection is not top level. */
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x06, 0xa1, 0x01,
                                                          0x09, 0x05, 0xa1, 0x00, 0xc0, 0xc0)));
    /* The usage is consumed by the first main item: an Input between usage and collection clears it. */
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x09, 0x05, 0x81, 0x02, 0xa1, 0x01, 0xc0)));
}

Test(input_gamepads, broken_descriptors_are_not_pads) {
    cr_expect_not(input__descriptor_is_gamepad(NULL, 0));
    /* Cut inside the Usage item's data, before the collection. */
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0x05, 0x01, 0x0a, 0x05)));
    /* A long item whose size runs past the end. */
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0xfe, 0xff, 0x00)));
    cr_expect_not(input__descriptor_is_gamepad(DESCRIPTOR(0xfe)));
    /* A long item skipped whole, then a gamepad. */
    cr_expect(input__descriptor_is_gamepad(DESCRIPTOR(0xfe, 0x02, 0x10, 0xaa, 0xbb,
                                                      0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0xc0)));
    /* End Collection with nothing open does not go below the top level. */
    cr_expect(input__descriptor_is_gamepad(DESCRIPTOR(0xc0, 0xc0, 0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0xc0)));
}
