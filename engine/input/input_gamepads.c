/* input_gamepads.c — gamepads through hidapi, on a thread of their own.
 *
 * The thread enumerates HID devices about once a second (hot-plug), opens the gamepads among
 * them, reads their input reports with a short timeout and decodes each into the device's
 * input_gamepad_state, which it publishes into input_pads_shared under its mutex. The main
 * thread copies the slots in input_update and never waits on the OS.
 *
 * Which devices are gamepads: those input_gamepad_kind_from_ids knows, and any other whose
 * report descriptor has a top-level Generic Desktop Joystick (0x04) or Gamepad (0x05)
 * application collection. hidapi 0.13 has no hid_get_report_descriptor, so on Linux the
 * descriptor is read from sysfs: /dev/hidrawN → /sys/class/hidraw/hidrawN/device/report_descriptor.
 *
 * Every device path seen is remembered until it vanishes from the enumeration, with what became
 * of it (not a pad, failed, open), so a device is examined — and a failure logged — once per
 * plug-in, not every second. A pad whose read fails is closed and examined afresh at the next
 * scan: still listed after a passing error, it reopens; unplugged, it is gone.
 *
 * Stopping: input__gamepads_stop sets `stop` and signals `wake`. An idle thread waits on `wake`
 * and returns at once; one reading devices notices within one read timeout (≤ 8 ms).
 */
#include "input/input_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <hidapi/hidapi.h>

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <wchar.h>

enum {
    INPUT_ENUMERATE_NS = 1000 * 1000 * 1000,   /* hot-plug scan period */
    INPUT_READ_BUDGET_MS = 8,                  /* one read round over all devices, at most */
    INPUT_REPORT_MAX = 1024,
    INPUT_DESCRIPTOR_MAX = 4096,               /* HID_MAX_DESCRIPTOR_SIZE */
    INPUT_REPORTS_PER_ROUND = 64,              /* drained per device per round, at most */
};

typedef enum input_device_fate {
    INPUT_DEVICE_IGNORED,    /* not a gamepad, or failed (logged once) */
    INPUT_DEVICE_OPEN,
    INPUT_DEVICE_RETRY,      /* a read failed: closed, examined afresh at the next scan if still listed */
} input_device_fate;

typedef struct input_device {
    char *path;
    input_device_fate fate;
    bool seen;               /* in the latest enumeration */
    int slot;
    hid_device *handle;
    input_decoder *decoder;
    input_gamepad_state state;
    input_gamepad_kind kind;
    char name[96];
} input_device;

struct input_gamepads {
    input_pads_shared *shared;
    pthread_t thread;
    input_device *devices;
    size_t device_count, device_capacity;
    bool warned_full;
};

/* hidapi's init is process-wide and not counted; so count here, for several input systems. */
static pthread_mutex_t input_hid_lock = PTHREAD_MUTEX_INITIALIZER;
static int input_hid_users;

/* ---- shared slots --------------------------------------------------------------------------- */

void input__pads_shared_init(input_pads_shared *shared) {
    memset(shared, 0, sizeof *shared);
    pthread_mutex_init(&shared->lock, NULL);
    pthread_condattr_t attr;
    pthread_condattr_init(&attr);
    pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
    pthread_cond_init(&shared->wake, &attr);
    pthread_condattr_destroy(&attr);
}

void input__pads_shared_destroy(input_pads_shared *shared) {
    pthread_cond_destroy(&shared->wake);
    pthread_mutex_destroy(&shared->lock);
}

void input__gamepad_publish(input_pads_shared *shared, int slot, const input_gamepad_state *state) {
    if (slot < 0 || slot >= INPUT_MAX_GAMEPADS) return;
    pthread_mutex_lock(&shared->lock);
    input_pad_slot *s = &shared->slots[slot];
    if (state) {
        if (!s->connected) {
            s->connected = true;
            s->generation++;
            s->latched = 0;
        }
        s->latched |= state->buttons & ~s->state.buttons;
        s->state = *state;
    } else {
        s->connected = false;
        s->state = (input_gamepad_state){ 0 };
        s->latched = 0;
    }
    pthread_mutex_unlock(&shared->lock);
}

int input__pad_slot_claim(input_pads_shared *shared, bool hidraw, uint16_t vendor_id, uint16_t product_id,
                          const char *name) {
    int slot = -1;
    pthread_mutex_lock(&shared->lock);
    for (int i = 0; i < INPUT_MAX_GAMEPADS && slot < 0; i++) {
        input_pad_slot *s = &shared->slots[i];
        if (s->claimed) continue;
        slot = i;
        s->claimed = true;
        s->hidraw = hidraw;
        s->vendor_id = vendor_id;
        s->product_id = product_id;
        snprintf(s->name, sizeof s->name, "%s", name ? name : "");
    }
    pthread_mutex_unlock(&shared->lock);
    return slot;
}

void input__pad_slot_release(input_pads_shared *shared, int slot) {
    if (slot < 0 || slot >= INPUT_MAX_GAMEPADS) return;
    pthread_mutex_lock(&shared->lock);
    input_pad_slot *s = &shared->slots[slot];
    s->claimed = s->hidraw = false;
    s->vendor_id = s->product_id = 0;
    s->name[0] = '\0';
    pthread_mutex_unlock(&shared->lock);
}

/* ---- descriptors ---------------------------------------------------------------------------- */

/* Walks the short items of a report descriptor (HID 1.11 §6.2.2.2) and checks the usage of each
 * top-level collection. Only Usage Page (global), Usage (local), Collection and End Collection
 * matter here; long items (§6.2.2.3) are skipped by their size byte. */
bool input__descriptor_is_gamepad(const uint8_t *d, size_t size) {
    uint32_t usage_page = 0, usage = 0;
    bool have_usage = false;
    int depth = 0;
    size_t at = 0;
    while (at < size) {
        uint8_t prefix = d[at];
        if (prefix == 0xfe) { /* long item: 0xfe, data size, tag, data */
            if (at + 1 >= size) return false;
            at += 3 + (size_t)d[at + 1];
            continue;
        }
        size_t length = (prefix & 3) == 3 ? 4 : (prefix & 3);
        if (at + 1 + length > size) return false;
        uint32_t value = 0;
        for (size_t i = 0; i < length; i++) value |= (uint32_t)d[at + 1 + i] << (8 * i);
        switch (prefix & 0xfc) {
        case 0x04: usage_page = value; break;                     /* Usage Page */
        case 0x08:                                                /* Usage */
            if (!have_usage) usage = length == 4 ? value : (usage_page << 16) | value;
            have_usage = true;
            break;
        case 0xa0:                                                /* Collection */
            if (depth == 0 && have_usage && (usage == 0x00010004u || usage == 0x00010005u)) return true;
            depth++;
            break;
        case 0xc0:                                                /* End Collection */
            if (depth > 0) depth--;
            break;
        default: break;
        }
        /* Local items (Usage among them) last until the next main item (§6.2.2.8). */
        if ((prefix & 0x0c) == 0x00) have_usage = false;
        at += 1 + length;
    }
    return false;
}

/* Reads /sys/class/hidraw/hidrawN/device/report_descriptor for a /dev/hidrawN path; returns the
 * size, or 0 when there is none to read. */
static size_t input_read_descriptor(const char *device_path, uint8_t *out, size_t capacity) {
    const char *name = strrchr(device_path, '/');
    name = name ? name + 1 : device_path;
    if (strncmp(name, "hidraw", 6) != 0) return 0;
    char path[256];
    if (snprintf(path, sizeof path, "/sys/class/hidraw/%s/device/report_descriptor", name) >= (int)sizeof path) return 0;
    FILE *file = fopen(path, "rb");
    if (!file) return 0;
    size_t size = fread(out, 1, capacity, file);
    fclose(file);
    return size;
}

/* UTF-8 from hidapi's wide strings (UTF-32 on Linux); the C locale's wcstombs would refuse
 * anything outside ASCII. */
static void input_utf8(const wchar_t *w, char *out, size_t capacity) {
    size_t n = 0;
    for (; w && *w && n + 5 < capacity; w++) {
        uint32_t c = (uint32_t)*w;
        if (c > 0x10ffff || (c >= 0xd800 && c <= 0xdfff)) c = 0xfffd;
        if (c < 0x80) {
            out[n++] = (char)c;
        } else if (c < 0x800) {
            out[n++] = (char)(0xc0 | (c >> 6));
            out[n++] = (char)(0x80 | (c & 0x3f));
        } else if (c < 0x10000) {
            out[n++] = (char)(0xe0 | (c >> 12));
            out[n++] = (char)(0x80 | ((c >> 6) & 0x3f));
            out[n++] = (char)(0x80 | (c & 0x3f));
        } else {
            out[n++] = (char)(0xf0 | (c >> 18));
            out[n++] = (char)(0x80 | ((c >> 12) & 0x3f));
            out[n++] = (char)(0x80 | ((c >> 6) & 0x3f));
            out[n++] = (char)(0x80 | (c & 0x3f));
        }
    }
    out[n] = '\0';
}

static void input_device_name(const struct hid_device_info *info, char *out, size_t capacity) {
    char product[64];
    input_utf8(info->product_string, product, sizeof product);
    if (product[0]) snprintf(out, capacity, "%s", product);
    else snprintf(out, capacity, "HID %04x:%04x", info->vendor_id, info->product_id);
}

/* Names the node and, when it is a permission problem, the udev rule that fixes it. The pad may
 * still work: the GLFW fallback reads it through evdev when a window exists. */
static void input_log_open_failure(const char *name, const struct hid_device_info *info, int error) {
    if (error == EACCES || error == EPERM) {
        core_warn("input",
                  "cannot open gamepad %s (%04x:%04x): %s is not readable by this user (%s). The udev rule "
                  "data/input/70-gamepads.rules fixes it: install it with `sudo tools/setup --udev` (or add "
                  "KERNEL==\"hidraw*\", ATTRS{idVendor}==\"%04x\", TAG+=\"uaccess\" to "
                  "/etc/udev/rules.d/70-gamepads.rules), then replug the pad",
                  name, info->vendor_id, info->product_id, info->path, strerror(error), info->vendor_id);
        return;
    }
    core_warn("input", "cannot open gamepad %s (%04x:%04x, %s): %s", name, info->vendor_id, info->product_id,
              info->path, error ? strerror(error) : "hid_open_path failed");
}

/* ---- devices -------------------------------------------------------------------------------- */

static input_device *input_device_find(input_gamepads *g, const char *path) {
    for (size_t i = 0; i < g->device_count; i++)
        if (strcmp(g->devices[i].path, path) == 0) return &g->devices[i];
    return NULL;
}

/* Decides what a newly seen device is and opens it when it is a gamepad. Failures are logged
 * here, once: the device stays IGNORED until it is unplugged. */
static void input_device_examine(input_gamepads *g, input_device *dev, const struct hid_device_info *info) {
    input_device_name(info, dev->name, sizeof dev->name);
    input_gamepad_kind kind = INPUT_GAMEPAD_GENERIC;
    bool known = input_gamepad_kind_from_ids(info->vendor_id, info->product_id, &kind);
    uint8_t descriptor[INPUT_DESCRIPTOR_MAX];
    size_t descriptor_size = input_read_descriptor(info->path, descriptor, sizeof descriptor);
    if (!known && !input__descriptor_is_gamepad(descriptor, descriptor_size)) return; /* a keyboard, … */

    core_error error = { 0 };
    input_decoder *decoder = input_decoder_create(
        &(input_decoder_desc){ .vendor_id = info->vendor_id, .product_id = info->product_id,
                               .descriptor = descriptor_size ? descriptor : NULL,
                               .descriptor_size = descriptor_size },
        &error);
    if (!decoder) {
        core_warn("input", "gamepad %s (%04x:%04x, %s) skipped: %s", dev->name, info->vendor_id, info->product_id,
                  info->path, error.code ? error.message : "its report descriptor cannot be decoded");
        return;
    }
    errno = 0;
    hid_device *handle = hid_open_path(info->path);
    if (!handle) {
        input_log_open_failure(dev->name, info, errno);
        input_decoder_destroy(decoder);
        return;
    }
    /* Claimed only once open: a slot marked hidraw tells the GLFW reader to leave this pad alone. */
    int slot = input__pad_slot_claim(g->shared, true, info->vendor_id, info->product_id, dev->name);
    if (slot < 0) {
        if (!g->warned_full) core_warn("input", "more than %d gamepads: %s ignored", INPUT_MAX_GAMEPADS, dev->name);
        g->warned_full = true;
        hid_close(handle);
        input_decoder_destroy(decoder);
        return;
    }
    dev->fate = INPUT_DEVICE_OPEN;
    dev->handle = handle;
    dev->decoder = decoder;
    dev->slot = slot;
    dev->state = (input_gamepad_state){ 0 };
    dev->kind = input_decoder_kind(decoder);
    input__gamepad_publish(g->shared, slot, &dev->state);
    core_info("input", "gamepad connected: %s (%s, %04x:%04x, %s)", dev->name, input_gamepad_kind_name(dev->kind),
              info->vendor_id, info->product_id, info->path);
}

static void input_device_close(input_gamepads *g, input_device *dev, input_device_fate fate, const char *why) {
    if (dev->fate != INPUT_DEVICE_OPEN) return;
    core_info("input", "gamepad disconnected: %s (%s; %s)", dev->name, input_gamepad_kind_name(dev->kind), why);
    input__gamepad_publish(g->shared, dev->slot, NULL);
    hid_close(dev->handle);
    input_decoder_destroy(dev->decoder);
    input__pad_slot_release(g->shared, dev->slot);
    dev->handle = NULL;
    dev->decoder = NULL;
    dev->fate = fate;
}

static void input_devices_enumerate(input_gamepads *g) {
    TRACE_ZONE("input_enumerate");
    for (size_t i = 0; i < g->device_count; i++) g->devices[i].seen = false;
    struct hid_device_info *list = hid_enumerate(0, 0);
    for (struct hid_device_info *info = list; info; info = info->next) {
        if (!info->path) continue;
        input_device *dev = input_device_find(g, info->path);
        if (dev) { /* hidapi lists a path once per top-level collection */
            dev->seen = true;
            if (dev->fate == INPUT_DEVICE_RETRY) {
                dev->fate = INPUT_DEVICE_IGNORED;
                input_device_examine(g, dev, info);
            }
            continue;
        }
        g->devices = core_grow(g->devices, &g->device_capacity, g->device_count + 1, sizeof *g->devices);
        dev = &g->devices[g->device_count++];
        *dev = (input_device){ .path = core_strdup(info->path), .fate = INPUT_DEVICE_IGNORED, .seen = true };
        input_device_examine(g, dev, info);
    }
    hid_free_enumeration(list);
    for (size_t i = 0; i < g->device_count;) {
        input_device *dev = &g->devices[i];
        if (dev->seen) {
            i++;
            continue;
        }
        input_device_close(g, dev, INPUT_DEVICE_IGNORED, "unplugged");
        core_free(dev->path, strlen(dev->path) + 1);
        g->devices[i] = g->devices[--g->device_count];
    }
}

/* Reads what each open device has; returns false when none is open. */
static bool input_devices_read(input_gamepads *g) {
    int open = 0;
    for (size_t i = 0; i < g->device_count; i++) open += g->devices[i].fate == INPUT_DEVICE_OPEN;
    if (open == 0) return false;
    int timeout_ms = CORE_MAX(1, INPUT_READ_BUDGET_MS / open);
    uint8_t report[INPUT_REPORT_MAX];
    for (size_t i = 0; i < g->device_count; i++) {
        input_device *dev = &g->devices[i];
        if (dev->fate != INPUT_DEVICE_OPEN) continue;
        /* Wait for the first report, then drain what is queued without waiting. */
        for (int n = 0; n < INPUT_REPORTS_PER_ROUND; n++) {
            int size = hid_read_timeout(dev->handle, report, sizeof report, n == 0 ? timeout_ms : 0);
            if (size < 0) {
                input_device_close(g, dev, INPUT_DEVICE_RETRY, "read failed");
                break;
            }
            if (size == 0) break;
            if (input_decoder_decode(dev->decoder, report, (size_t)size, &dev->state, NULL) == INPUT_DECODE_OK)
                input__gamepad_publish(g->shared, dev->slot, &dev->state);
        }
    }
    return true;
}

/* ---- the thread ----------------------------------------------------------------------------- */

static bool input_stopping(input_gamepads *g) {
    pthread_mutex_lock(&g->shared->lock);
    bool stop = g->shared->stop;
    pthread_mutex_unlock(&g->shared->lock);
    return stop;
}

/* Sleeps until `deadline_ns` (core_time_ns clock) or a stop request; true when stopping. */
static bool input_wait_until(input_gamepads *g, uint64_t deadline_ns) {
    struct timespec until = { .tv_sec = (time_t)(deadline_ns / 1000000000u), .tv_nsec = (long)(deadline_ns % 1000000000u) };
    pthread_mutex_lock(&g->shared->lock);
    while (!g->shared->stop && core_time_ns() < deadline_ns)
        if (pthread_cond_timedwait(&g->shared->wake, &g->shared->lock, &until) == ETIMEDOUT) break;
    bool stop = g->shared->stop;
    pthread_mutex_unlock(&g->shared->lock);
    return stop;
}

static void *input_gamepad_thread(void *arg) {
    input_gamepads *g = arg;
    trace_thread_name("input");
    uint64_t next_scan = 0;
    while (!input_stopping(g)) {
        uint64_t now = core_time_ns();
        if (now >= next_scan) {
            input_devices_enumerate(g);
            next_scan = now + INPUT_ENUMERATE_NS;
            pthread_mutex_lock(&g->shared->lock);
            g->shared->hid_scanned = true;
            pthread_mutex_unlock(&g->shared->lock);
        }
        if (!input_devices_read(g) && input_wait_until(g, next_scan)) break;
    }
    for (size_t i = 0; i < g->device_count; i++) {
        input_device_close(g, &g->devices[i], INPUT_DEVICE_IGNORED, "input system stopped");
        core_free(g->devices[i].path, strlen(g->devices[i].path) + 1);
    }
    g->device_count = 0;
    return NULL;
}

input_gamepads *input__gamepads_start(input_pads_shared *shared) {
    pthread_mutex_lock(&input_hid_lock);
    int rc = input_hid_users == 0 ? hid_init() : 0;
    if (rc == 0) input_hid_users++;
    pthread_mutex_unlock(&input_hid_lock);
    if (rc != 0) {
        core_warn("input", "hidapi cannot start (hid_init failed): no gamepads");
        return NULL;
    }
    input_gamepads *g = core_calloc(1, sizeof *g);
    g->shared = shared;
    int error = pthread_create(&g->thread, NULL, input_gamepad_thread, g);
    if (error) {
        core_warn("input", "cannot start the gamepad thread: %s; no gamepads", strerror(error));
        core_free(g, sizeof *g);
        g = NULL;
    }
    if (!g) {
        pthread_mutex_lock(&input_hid_lock);
        if (--input_hid_users == 0) hid_exit();
        pthread_mutex_unlock(&input_hid_lock);
    }
    return g;
}

void input__gamepads_stop(input_gamepads *g) {
    if (!g) return;
    pthread_mutex_lock(&g->shared->lock);
    g->shared->stop = true;
    pthread_cond_broadcast(&g->shared->wake);
    pthread_mutex_unlock(&g->shared->lock);
    pthread_join(g->thread, NULL);
    if (g->devices) core_free(g->devices, g->device_capacity * sizeof *g->devices);
    core_free(g, sizeof *g);
    pthread_mutex_lock(&input_hid_lock);
    if (--input_hid_users == 0) hid_exit();
    pthread_mutex_unlock(&input_hid_lock);
}
