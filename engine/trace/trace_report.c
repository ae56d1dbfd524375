/* trace_report.c — reads a Chrome trace back and summarises it: frame-time percentiles, per-zone
 * statistics and an SVG plot of frame times (trace.h, REPORT).
 *
 * Zones are B/E pairs, matched per (pid, tid) with a stack as Chrome does (an "E" closes the
 * innermost open "B" of its thread, whatever its name), or X events. Frames are zones named
 * "frame". Every zone's duration is kept as a sample; sorting the samples by (zone, duration)
 * then gives each zone's count, total, p99 and max in one pass.
 */
#include "trace/trace.h"

#include "core/core.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#define REPORT_FRAME_BUDGET_60HZ_MS 16.7
#define REPORT_FRAME_BUDGET_30HZ_MS 33.3

typedef struct report_sample {
    uint32_t zone; /* index into report_builder.zone_names */
    double ms;
} report_sample;

typedef struct report_open_zone {
    const char *name;
    double ts_us;
} report_open_zone;

/* The zones still open on one (pid, tid), innermost last. */
typedef struct report_thread {
    uint64_t pid, tid;
    report_open_zone *open;
    size_t open_count, open_capacity;
} report_thread;

typedef struct report_builder {
    trace_report *report;
    const char **zone_names;   /* point into the JSON arena until copied out */
    size_t zone_count, zone_capacity;
    uint32_t *zone_slots;      /* hash of name → zone index + 1; 0 = empty */
    size_t slot_capacity;
    report_sample *samples;
    size_t sample_count, sample_capacity;
    double *frames;
    size_t frame_count, frame_capacity;
    report_thread *threads;
    size_t thread_count, thread_capacity, last_thread;
} report_builder;

/* ---- small helpers ---------------------------------------------------------------------- */

CORE_PRINTF(2, 3)
static bool report_fail(trace_report *report, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    vsnprintf(report->error, sizeof report->error, fmt, args);
    va_end(args);
    return false;
}

static int report_compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double trace_percentile(const double *sorted, size_t n, double p) {
    if (n == 0) return 0.0;
    /* p·n/100 rather than p/100·n: with whole p and n the product is exact, so a rank that
     * is a whole number (p95 of 20 values = 19) does not become 19.000000000000004 → 20. */
    double rank = ceil(p * (double)n / 100.0);
    if (!(rank >= 1.0)) rank = 1.0; /* also catches NaN */
    if (rank > (double)n) rank = (double)n;
    return sorted[(size_t)rank - 1];
}

/* ---- zones and threads ------------------------------------------------------------------ */

static uint32_t report_zone_index(report_builder *b, const char *name) {
    if (2 * (b->zone_count + 1) > b->slot_capacity) {
        /* Rehash into a table twice the size. */
        size_t capacity = b->slot_capacity ? b->slot_capacity * 2 : 64;
        uint32_t *slots = core_calloc(capacity, sizeof *slots);
        for (size_t z = 0; z < b->zone_count; z++) {
            size_t i = core_hash_bytes(b->zone_names[z], strlen(b->zone_names[z]), 0) & (capacity - 1);
            while (slots[i]) i = (i + 1) & (capacity - 1);
            slots[i] = (uint32_t)z + 1;
        }
        core_free(b->zone_slots, b->slot_capacity * sizeof *slots);
        b->zone_slots = slots;
        b->slot_capacity = capacity;
    }
    size_t mask = b->slot_capacity - 1;
    size_t i = core_hash_bytes(name, strlen(name), 0) & mask;
    for (; b->zone_slots[i]; i = (i + 1) & mask)
        if (strcmp(b->zone_names[b->zone_slots[i] - 1], name) == 0) return b->zone_slots[i] - 1;
    b->zone_names = core_grow(b->zone_names, &b->zone_capacity, b->zone_count + 1, sizeof *b->zone_names);
    b->zone_names[b->zone_count] = name;
    b->zone_slots[i] = (uint32_t)++b->zone_count;
    return (uint32_t)(b->zone_count - 1);
}

static bool report_add_zone(report_builder *b, size_t index, const char *name, double ms) {
    /* Finite timestamps far apart can still overflow their difference. */
    if (!isfinite(ms)) return report_fail(b->report, "event %zu: zone duration out of range", index);
    b->samples = core_grow(b->samples, &b->sample_capacity, b->sample_count + 1, sizeof *b->samples);
    b->samples[b->sample_count++] = (report_sample){ .zone = report_zone_index(b, name), .ms = ms };
    if (strcmp(name, "frame") == 0) {
        b->frames = core_grow(b->frames, &b->frame_capacity, b->frame_count + 1, sizeof *b->frames);
        b->frames[b->frame_count++] = ms;
    }
    return true;
}

/* pid and tid are numbers in Chrome traces, strings in a few other tools' output. */
static uint64_t report_id(const core_json_value *value) {
    if (value && value->type == CORE_JSON_NUMBER) {
        double number = value->number == 0 ? 0.0 : value->number; /* -0 is 0 */
        uint64_t bits;
        memcpy(&bits, &number, sizeof bits);
        return bits;
    }
    if (value && value->type == CORE_JSON_STRING) return core_hash_bytes(value->string.chars, value->string.length, 1);
    return 0;
}

static report_thread *report_thread_of(report_builder *b, const core_json_value *event) {
    uint64_t pid = report_id(core_json_get(event, "pid")), tid = report_id(core_json_get(event, "tid"));
    /* Consecutive events are usually from the same thread: try the last one first. */
    if (b->thread_count && b->threads[b->last_thread].pid == pid && b->threads[b->last_thread].tid == tid)
        return &b->threads[b->last_thread];
    for (size_t i = 0; i < b->thread_count; i++) {
        if (b->threads[i].pid == pid && b->threads[i].tid == tid) {
            b->last_thread = i;
            return &b->threads[i];
        }
    }
    b->threads = core_grow(b->threads, &b->thread_capacity, b->thread_count + 1, sizeof *b->threads);
    b->threads[b->thread_count] = (report_thread){ .pid = pid, .tid = tid };
    b->last_thread = b->thread_count++;
    return &b->threads[b->last_thread];
}

/* ---- events ----------------------------------------------------------------------------- */

static const char *report_event_name(const core_json_value *event) {
    return core_json_string_or(core_json_get(event, "name"), "(unnamed)");
}

static bool report_event_time(report_builder *b, const core_json_value *event, size_t index,
                              const char *key, char ph, double *out) {
    const core_json_value *value = core_json_get(event, key);
    if (!value || value->type != CORE_JSON_NUMBER)
        return report_fail(b->report, "event %zu (\"%c\") has no numeric \"%s\"", index, ph, key);
    *out = value->number;
    return true;
}

static bool report_begin(report_builder *b, const core_json_value *event, size_t index) {
    double ts = 0;
    if (!report_event_time(b, event, index, "ts", 'B', &ts)) return false;
    report_thread *thread = report_thread_of(b, event);
    thread->open = core_grow(thread->open, &thread->open_capacity, thread->open_count + 1, sizeof *thread->open);
    thread->open[thread->open_count++] = (report_open_zone){ .name = report_event_name(event), .ts_us = ts };
    return true;
}

static bool report_end(report_builder *b, const core_json_value *event, size_t index) {
    double ts = 0;
    if (!report_event_time(b, event, index, "ts", 'E', &ts)) return false;
    report_thread *thread = report_thread_of(b, event);
    if (thread->open_count == 0)
        return report_fail(b->report, "event %zu: \"E\" without a matching \"B\" on its thread (pid %g, tid %g)",
                           index, core_json_number_or(core_json_get(event, "pid"), 0),
                           core_json_number_or(core_json_get(event, "tid"), 0));
    report_open_zone zone = thread->open[--thread->open_count];
    if (ts < zone.ts_us)
        return report_fail(b->report, "event %zu: zone \"%.64s\" ends (ts %g) before it begins (ts %g)", index,
                           zone.name, ts, zone.ts_us);
    return report_add_zone(b, index, zone.name, (ts - zone.ts_us) / 1000.0);
}

static bool report_complete(report_builder *b, const core_json_value *event, size_t index) {
    double ts = 0, dur = 0;
    if (!report_event_time(b, event, index, "ts", 'X', &ts)) return false;
    if (!report_event_time(b, event, index, "dur", 'X', &dur)) return false;
    if (dur < 0) return report_fail(b->report, "event %zu: \"X\" with a negative \"dur\" (%g)", index, dur);
    return report_add_zone(b, index, report_event_name(event), dur / 1000.0);
}

static bool report_event(report_builder *b, const core_json_value *event, size_t index) {
    if (event->type != CORE_JSON_OBJECT) return report_fail(b->report, "event %zu is not an object", index);
    const core_json_value *ph = core_json_get(event, "ph");
    if (!ph || ph->type != CORE_JSON_STRING)
        return report_fail(b->report, "event %zu has no \"ph\" (phase) string", index);
    if (ph->string.length != 1) return true; /* not a phase this report knows */
    switch (ph->string.chars[0]) {
    case 'B': return report_begin(b, event, index);
    case 'E': return report_end(b, event, index);
    case 'X': return report_complete(b, event, index);
    case 'C': b->report->counter_count++; return true;
    default: return true; /* metadata, instants, flows, …: not part of the summary */
    }
}

/* ---- statistics ------------------------------------------------------------------------- */

static int report_compare_samples(const void *a, const void *b) {
    const report_sample *x = a, *y = b;
    if (x->zone != y->zone) return x->zone < y->zone ? -1 : 1;
    return (x->ms > y->ms) - (x->ms < y->ms);
}

static int report_compare_zones(const void *a, const void *b) {
    const trace_zone_stats *x = a, *y = b;
    if (x->total_ms != y->total_ms) return x->total_ms > y->total_ms ? -1 : 1;
    return strcmp(x->name, y->name); /* a stable order for equal totals */
}

/* One pass over the samples sorted by (zone, duration); each zone's run is its sorted durations. */
static void report_zone_stats(report_builder *b) {
    trace_report *report = b->report;
    if (b->sample_count == 0) return;
    qsort(b->samples, b->sample_count, sizeof *b->samples, report_compare_samples);
    double *run = core_alloc(b->sample_count * sizeof *run);
    report->zones = core_calloc(b->zone_count, sizeof *report->zones);
    for (size_t i = 0; i < b->sample_count;) {
        uint32_t zone = b->samples[i].zone;
        size_t n = 0;
        double total = 0;
        for (; i < b->sample_count && b->samples[i].zone == zone; i++) {
            run[n++] = b->samples[i].ms;
            total += b->samples[i].ms;
        }
        report->zones[report->zone_count++] = (trace_zone_stats){
            .name = core_strdup(b->zone_names[zone]),
            .count = n,
            .total_ms = total,
            .p99_ms = trace_percentile(run, n, 99),
            .max_ms = run[n - 1],
        };
    }
    core_free(run, b->sample_count * sizeof *run);
    qsort(report->zones, report->zone_count, sizeof *report->zones, report_compare_zones);
}

static void report_frame_stats(report_builder *b) {
    trace_report *report = b->report;
    size_t n = b->frame_count;
    report->frame_count = n;
    if (n == 0) return;
    report->frame_ms = core_alloc(n * sizeof *report->frame_ms);
    memcpy(report->frame_ms, b->frames, n * sizeof *report->frame_ms);
    qsort(b->frames, n, sizeof *b->frames, report_compare_doubles); /* file order is kept above */
    report->frame_p50_ms = trace_percentile(b->frames, n, 50);
    report->frame_p95_ms = trace_percentile(b->frames, n, 95);
    report->frame_p99_ms = trace_percentile(b->frames, n, 99);
    report->frame_max_ms = b->frames[n - 1];
    for (size_t i = 0; i < n; i++) {
        report->frames_over_16ms += b->frames[i] > REPORT_FRAME_BUDGET_60HZ_MS;
        report->frames_over_33ms += b->frames[i] > REPORT_FRAME_BUDGET_30HZ_MS;
    }
}

static void report_builder_free(report_builder *b) {
    for (size_t i = 0; i < b->thread_count; i++)
        core_free(b->threads[i].open, b->threads[i].open_capacity * sizeof *b->threads[i].open);
    core_free(b->threads, b->thread_capacity * sizeof *b->threads);
    core_free(b->zone_names, b->zone_capacity * sizeof *b->zone_names);
    core_free(b->zone_slots, b->slot_capacity * sizeof *b->zone_slots);
    core_free(b->samples, b->sample_capacity * sizeof *b->samples);
    core_free(b->frames, b->frame_capacity * sizeof *b->frames);
}

/* ---- loading ---------------------------------------------------------------------------- */

static const core_json_value *report_find_events(const core_json_value *root, trace_report *report) {
    if (root->type == CORE_JSON_ARRAY) return root; /* the bare-array form of the format */
    const core_json_value *events = core_json_get(root, "traceEvents");
    if (!events || events->type != CORE_JSON_ARRAY) {
        report_fail(report, "no \"traceEvents\" array: not a Chrome trace");
        return NULL;
    }
    return events;
}

bool trace_report_parse(const char *json, size_t size, trace_report *report) {
    *report = (trace_report){ 0 };
    core_arena arena = { 0 };
    core_json_value *root;
    core_json_error error;
    bool ok = core_json_parse(json, size, &arena, &root, &error);
    if (!ok) report_fail(report, "not valid JSON: %s", error.message);
    const core_json_value *events = ok ? report_find_events(root, report) : NULL;
    ok = events != NULL;
    report_builder b = { .report = report };
    for (size_t i = 0; ok && i < events->array.count; i++) ok = report_event(&b, &events->array.items[i], i);
    if (ok) {
        report_zone_stats(&b);
        report_frame_stats(&b);
    }
    report_builder_free(&b);
    core_arena_release(&arena);
    return ok;
}

/* Reads a whole file; works for pipes too, which have no size to ask for. */
static char *report_read_file(const char *path, size_t *size, size_t *capacity) {
    FILE *file = fopen(path, "rb");
    if (!file) return NULL;
    char *data = NULL;
    *size = *capacity = 0;
    for (;;) {
        /* Read in pieces of at least 64 KiB. */
        if (*size == *capacity) data = core_grow(data, capacity, CORE_MAX(*size + 1, (size_t)1 << 16), 1);
        size_t n = fread(data + *size, 1, *capacity - *size, file);
        *size += n;
        if (n == 0) break;
    }
    bool failed = ferror(file) != 0;
    int error = errno;
    fclose(file);
    if (failed) {
        core_free(data, *capacity);
        errno = error;
        return NULL;
    }
    return data;
}

bool trace_report_load(const char *path, trace_report *report) {
    size_t size, capacity;
    char *data = report_read_file(path, &size, &capacity);
    if (!data) {
        int error = errno;
        *report = (trace_report){ 0 };
        return report_fail(report, "cannot read '%s': %s", path, strerror(error));
    }
    bool ok = trace_report_parse(data, size, report);
    core_free(data, capacity);
    if (!ok) {
        char reason[sizeof report->error];
        memcpy(reason, report->error, sizeof reason);
        report_fail(report, "%s: %s", path, reason);
    }
    return ok;
}

void trace_report_free(trace_report *report) {
    core_free(report->frame_ms, report->frame_count * sizeof *report->frame_ms);
    for (size_t i = 0; i < report->zone_count; i++)
        core_free((char *)report->zones[i].name, strlen(report->zones[i].name) + 1);
    core_free(report->zones, report->zone_count * sizeof *report->zones);
    *report = (trace_report){ 0 };
}

/* ---- printing --------------------------------------------------------------------------- */

/* A zone name padded to `width`; control characters would garble the terminal, so they show
 * as '?'. */
static void report_print_name(FILE *out, const char *name, int width) {
    int written = 0;
    for (const char *c = name; *c; c++) {
        fputc((unsigned char)*c < 0x20 ? '?' : *c, out);
        written += ((unsigned char)*c & 0xc0) != 0x80; /* characters, not UTF-8 bytes */
    }
    for (; written < width; written++) fputc(' ', out);
}

static double report_share(size_t part, size_t whole) { return whole ? 100.0 * (double)part / (double)whole : 0.0; }

void trace_report_print(const trace_report *report, FILE *out) {
    if (report->frame_count == 0) {
        fprintf(out, "frame time   0 frames (no zones named \"frame\")\n");
    } else {
        fprintf(out, "frame time   %zu frames   p50 %.3f ms   p95 %.3f ms   p99 %.3f ms   max %.3f ms\n",
                report->frame_count, report->frame_p50_ms, report->frame_p95_ms, report->frame_p99_ms,
                report->frame_max_ms);
        fprintf(out, "slow frames  %zu over 16.7 ms (%.1f%%), %zu over 33.3 ms (%.1f%%)\n",
                report->frames_over_16ms, report_share(report->frames_over_16ms, report->frame_count),
                report->frames_over_33ms, report_share(report->frames_over_33ms, report->frame_count));
    }
    fprintf(out, "counters     %zu events\n\n", report->counter_count);
    fprintf(out, "%-32s %10s %12s %10s %10s\n", "zone", "count", "total ms", "p99 ms", "max ms");
    for (size_t i = 0; i < report->zone_count; i++) {
        const trace_zone_stats *zone = &report->zones[i];
        report_print_name(out, zone->name, 32);
        fprintf(out, " %10zu %12.3f %10.3f %10.3f\n", zone->count, zone->total_ms, zone->p99_ms, zone->max_ms);
    }
}

/* ---- SVG plot --------------------------------------------------------------------------- */

enum { SVG_WIDTH = 960, SVG_HEIGHT = 400, SVG_LEFT = 72, SVG_RIGHT = 24, SVG_TOP = 48, SVG_BOTTOM = 56 };
#define SVG_PLOT_WIDTH ((double)(SVG_WIDTH - SVG_LEFT - SVG_RIGHT))
#define SVG_PLOT_HEIGHT ((double)(SVG_HEIGHT - SVG_TOP - SVG_BOTTOM))

/* A tick spacing of 1, 2 or 5 × 10^k that cuts `range` into about `ticks` steps. */
static double svg_nice_step(double range, int ticks) {
    double raw = range / ticks;
    double magnitude = pow(10.0, floor(log10(raw)));
    double normal = raw / magnitude;
    double step = normal <= 1 ? 1 : normal <= 2 ? 2 : normal <= 5 ? 5 : 10;
    return step * magnitude;
}

typedef struct svg_scale {
    size_t frames;
    double y_max_ms;
} svg_scale;

static double svg_x(const svg_scale *s, double frame) {
    double span = s->frames > 1 ? (double)(s->frames - 1) : 1.0;
    return SVG_LEFT + (s->frames > 1 ? frame / span : 0.5) * SVG_PLOT_WIDTH;
}

static double svg_y(const svg_scale *s, double ms) { return SVG_TOP + SVG_PLOT_HEIGHT * (1.0 - ms / s->y_max_ms); }

static void svg_y_axis(FILE *out, const svg_scale *s, double step) {
    for (double ms = 0; ms <= s->y_max_ms + step * 1e-9; ms += step) {
        double y = svg_y(s, ms);
        fprintf(out, "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"#e6e6e6\"/>\n", SVG_LEFT, y,
                SVG_WIDTH - SVG_RIGHT, y);
        fprintf(out, "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n", SVG_LEFT - 6, y + 4, ms);
    }
    fprintf(out, "<text transform=\"translate(18 %.1f) rotate(-90)\" text-anchor=\"middle\">frame time (ms)</text>\n",
            SVG_TOP + SVG_PLOT_HEIGHT / 2);
}

static void svg_x_axis(FILE *out, const svg_scale *s) {
    double last = s->frames > 1 ? (double)(s->frames - 1) : 0.0;
    double step = last > 0 ? svg_nice_step(last, 8) : 1.0;
    if (step < 1) step = 1; /* frames are whole */
    for (double frame = 0; frame <= last + step * 1e-9; frame += step) {
        double x = svg_x(s, frame);
        fprintf(out, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#333\"/>\n", x,
                SVG_HEIGHT - SVG_BOTTOM, x, SVG_HEIGHT - SVG_BOTTOM + 5);
        fprintf(out, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.0f</text>\n", x,
                SVG_HEIGHT - SVG_BOTTOM + 20, frame);
    }
    fprintf(out, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">frame</text>\n",
            SVG_LEFT + SVG_PLOT_WIDTH / 2, SVG_HEIGHT - 10);
}

static void svg_guide_line(FILE *out, const svg_scale *s, double ms, const char *color) {
    double y = svg_y(s, ms);
    fprintf(out, "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"%s\" stroke-dasharray=\"6 4\"/>\n",
            SVG_LEFT, y, SVG_WIDTH - SVG_RIGHT, y, color);
}

/* Drawn after the frame line, with a white halo, so the line never hides it. */
static void svg_guide_label(FILE *out, const svg_scale *s, double ms, const char *color, const char *label) {
    fprintf(out, "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\" fill=\"%s\" stroke=\"white\" "
                 "stroke-width=\"3\" paint-order=\"stroke\">%s</text>\n",
            SVG_WIDTH - SVG_RIGHT - 4, svg_y(s, ms) - 4, color, label);
}

/* The frame-time line. With more frames than pixels, each pixel column shows the largest and
 * smallest frame it covers, so no spike disappears. */
static void svg_frame_line(FILE *out, const svg_scale *s, const double *frame_ms) {
    fputs("<polyline fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.2\" stroke-linejoin=\"round\" points=\"", out);
    size_t columns = (size_t)SVG_PLOT_WIDTH;
    if (s->frames <= 2 * columns) {
        for (size_t i = 0; i < s->frames; i++) fprintf(out, "%.1f,%.1f ", svg_x(s, (double)i), svg_y(s, frame_ms[i]));
    } else {
        for (size_t c = 0; c < columns; c++) {
            size_t first = c * s->frames / columns, last = (c + 1) * s->frames / columns;
            double low = frame_ms[first], high = frame_ms[first];
            for (size_t i = first; i < last; i++) low = fmin(low, frame_ms[i]), high = fmax(high, frame_ms[i]);
            double x = svg_x(s, (double)first);
            fprintf(out, "%.1f,%.1f %.1f,%.1f ", x, svg_y(s, high), x, svg_y(s, low));
        }
    }
    fputs("\"/>\n", out);
}

static void svg_write(FILE *out, const trace_report *report) {
    svg_scale s = { .frames = report->frame_count };
    /* At least 40 ms so both guides show; a parsed report's times are always finite. */
    double top = isfinite(report->frame_max_ms) ? fmax(report->frame_max_ms, 40.0) : 40.0;
    double step = svg_nice_step(top, 6);
    s.y_max_ms = ceil(top / step) * step;
    fprintf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
                 "font-family=\"sans-serif\" font-size=\"12\">\n"
                 "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
            SVG_WIDTH, SVG_HEIGHT, SVG_WIDTH, SVG_HEIGHT);
    fprintf(out, "<text x=\"%d\" y=\"28\" font-size=\"16\">Frame times: %zu frames, p50 %.2f ms, p99 %.2f ms, "
                 "max %.2f ms</text>\n",
            SVG_LEFT, report->frame_count, report->frame_p50_ms, report->frame_p99_ms, report->frame_max_ms);
    svg_y_axis(out, &s, step);
    svg_guide_line(out, &s, REPORT_FRAME_BUDGET_60HZ_MS, "#2ca02c");
    svg_guide_line(out, &s, REPORT_FRAME_BUDGET_30HZ_MS, "#d62728");
    if (report->frame_count) {
        svg_x_axis(out, &s);
        svg_frame_line(out, &s, report->frame_ms);
    } else {
        fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">no frames in this trace</text>\n",
                SVG_LEFT + SVG_PLOT_WIDTH / 2, SVG_TOP + SVG_PLOT_HEIGHT / 2);
    }
    svg_guide_label(out, &s, REPORT_FRAME_BUDGET_60HZ_MS, "#2ca02c", "16.7 ms (60 fps)");
    svg_guide_label(out, &s, REPORT_FRAME_BUDGET_30HZ_MS, "#d62728", "33.3 ms (30 fps)");
    fprintf(out, "<polyline fill=\"none\" stroke=\"#333\" points=\"%d,%d %d,%d %d,%d\"/>\n", SVG_LEFT, SVG_TOP,
            SVG_LEFT, SVG_HEIGHT - SVG_BOTTOM, SVG_WIDTH - SVG_RIGHT, SVG_HEIGHT - SVG_BOTTOM);
    fputs("</svg>\n", out);
}

bool trace_report_write_svg(const trace_report *report, const char *svg_path) {
    FILE *out = fopen(svg_path, "w");
    if (!out) {
        core_error("trace", "cannot write '%s': %s", svg_path, strerror(errno));
        return false;
    }
    svg_write(out, report);
    bool failed = ferror(out) != 0;
    if (fclose(out) != 0) failed = true;
    if (failed) core_error("trace", "writing '%s' failed: %s", svg_path, strerror(errno));
    return !failed;
}
