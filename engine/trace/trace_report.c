/* trace_report.c — reads a Chrome trace back and summarises it: frame-time percentiles, per-zone
 * inclusive and self times, per-counter statistics, the slowest frames, the frames over a
 * budget and an SVG plot of frame times (trace.h, REPORT).
 *
 * Zones are B/E pairs, matched per (pid, tid) with a stack as Chrome does (an "E" closes the
 * innermost open "B" of its thread, whatever its name), or X events. Frames are zones named
 * "frame". Every zone is kept as an instance (thread, begin, end, args); a sweep over each
 * thread's instances in time order nests them and gives self times; sorting copies of them by
 * (zone, duration) then gives each zone's count, totals, p99 and max in one pass. Counter
 * samples are kept too, so the slowest frames can show the counters at their end.
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
#define REPORT_ARGS_MAX_CHARS 160  /* a zone's args as text, cut beyond this */

typedef struct report_instance {
    uint32_t zone;        /* name index while loading; index into report->zones after */
    uint32_t thread;
    size_t begin_event;   /* file index of its B or X: orders zones with equal spans */
    double begin_us, end_us, self_us;
    size_t args;          /* offset of its args text in detail->text; 0 = none */
} report_instance;

typedef struct report_counter_sample {
    uint32_t series;      /* series name index */
    size_t event;         /* file index: orders samples with equal ts */
    double ts_us, value;
} report_counter_sample;

struct trace_report_detail {
    report_instance *instances;
    size_t instance_count, instance_capacity;
    size_t *frames;                 /* instance index of each frame, as report->frame_ms */
    size_t frame_capacity;
    size_t *by_begin;               /* instance indices sorted by begin time */
    double *reach_us;               /* reach_us[k]: the latest end among by_begin[0..k] */
    report_counter_sample *samples; /* sorted by (series, ts, event) */
    size_t sample_count, sample_capacity;
    size_t *counter_first;          /* report->counters[i]'s first sample */
    char *text;                     /* args texts, NUL-terminated, from offset 1 */
    size_t text_size, text_capacity;
};

/* Names → small indices, with an open-addressing hash. Names point into the JSON arena until
 * the statistics copy them out. */
typedef struct report_names {
    const char **names;
    size_t count, capacity;
    uint32_t *slots;      /* name index + 1; 0 = empty */
    size_t slot_capacity;
} report_names;

typedef struct report_open_zone {
    const char *name;
    double ts_us;
    size_t event, args;
} report_open_zone;

/* The zones still open on one (pid, tid), innermost last. */
typedef struct report_thread {
    uint64_t pid, tid;
    report_open_zone *open;
    size_t open_count, open_capacity;
} report_thread;

typedef struct report_builder {
    trace_report *report;
    core_error *error;              /* may be NULL */
    trace_report_detail *detail;
    core_arena *arena;
    report_names zones, series;
    uint32_t frame_zone;            /* name index of "frame", UINT32_MAX until seen */
    report_thread *threads;
    size_t thread_count, thread_capacity, last_thread;
} report_builder;

/* ---- small helpers ---------------------------------------------------------------------- */


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

static uint32_t report_name_index(report_names *t, const char *name) {
    if (2 * (t->count + 1) > t->slot_capacity) {
        /* Rehash into a table twice the size. */
        size_t capacity = t->slot_capacity ? t->slot_capacity * 2 : 64;
        uint32_t *slots = core_calloc(capacity, sizeof *slots);
        for (size_t z = 0; z < t->count; z++) {
            size_t i = core_hash_bytes(t->names[z], strlen(t->names[z]), 0) & (capacity - 1);
            while (slots[i]) i = (i + 1) & (capacity - 1);
            slots[i] = (uint32_t)z + 1;
        }
        core_free(t->slots, t->slot_capacity * sizeof *slots);
        t->slots = slots;
        t->slot_capacity = capacity;
    }
    size_t mask = t->slot_capacity - 1;
    size_t i = core_hash_bytes(name, strlen(name), 0) & mask;
    for (; t->slots[i]; i = (i + 1) & mask)
        if (strcmp(t->names[t->slots[i] - 1], name) == 0) return t->slots[i] - 1;
    t->names = core_grow(t->names, &t->capacity, t->count + 1, sizeof *t->names);
    t->names[t->count] = name;
    t->slots[i] = (uint32_t)++t->count;
    return (uint32_t)(t->count - 1);
}

static void report_names_free(report_names *t) {
    core_free(t->names, t->capacity * sizeof *t->names);
    core_free(t->slots, t->slot_capacity * sizeof *t->slots);
}

/* ---- zone arguments --------------------------------------------------------------------- */

static void report_text_append(trace_report_detail *d, const char *chars, size_t length) {
    d->text = core_grow(d->text, &d->text_capacity, d->text_size + length + 1, 1);
    memcpy(d->text + d->text_size, chars, length);
    d->text_size += length;
    d->text[d->text_size] = '\0';
}

static void report_text_value(trace_report_detail *d, const core_json_value *value) {
    char number[32];
    switch (value->type) {
    case CORE_JSON_STRING:
        report_text_append(d, value->string.chars, strnlen(value->string.chars, value->string.length));
        break;
    case CORE_JSON_NUMBER:
        report_text_append(d, number, (size_t)snprintf(number, sizeof number, "%.10g", value->number));
        break;
    case CORE_JSON_BOOL: report_text_append(d, value->boolean ? "true" : "false", value->boolean ? 4 : 5); break;
    case CORE_JSON_NULL: report_text_append(d, "null", 4); break;
    case CORE_JSON_ARRAY: report_text_append(d, "[...]", 5); break;
    case CORE_JSON_OBJECT: report_text_append(d, "{...}", 5); break;
    }
}

/* A zone's "args" object as "key=value key=value" in the text pool; 0 when it has none. Only
 * the slowest frames show it, so nested values are not spelled out, and a long one is cut
 * (on a UTF-8 character boundary) with "...". */
static size_t report_args_text(report_builder *b, const core_json_value *event) {
    const core_json_value *args = core_json_get(event, "args");
    if (!args || args->type != CORE_JSON_OBJECT || args->object.count == 0) return 0;
    trace_report_detail *d = b->detail;
    if (d->text_size == 0) report_text_append(d, "", 1); /* offset 0 stays "none" */
    size_t start = d->text_size, i = 0;
    for (; i < args->object.count && d->text_size - start < REPORT_ARGS_MAX_CHARS; i++) {
        if (i) report_text_append(d, " ", 1);
        const core_json_string *key = &args->object.keys[i];
        report_text_append(d, key->chars, strnlen(key->chars, key->length));
        report_text_append(d, "=", 1);
        report_text_value(d, &args->object.values[i]);
    }
    if (d->text_size - start > REPORT_ARGS_MAX_CHARS || i < args->object.count) {
        size_t end = start + CORE_MIN(d->text_size - start, (size_t)REPORT_ARGS_MAX_CHARS - 3);
        while (end > start && ((unsigned char)d->text[end] & 0xc0) == 0x80) end--;
        d->text_size = end;
        report_text_append(d, "...", 3);
    }
    d->text_size++; /* keep the NUL */
    return start;
}

/* ---- zones and threads ------------------------------------------------------------------ */

static bool report_add_zone(report_builder *b, size_t index, uint32_t thread, const report_open_zone *zone,
                            double end_us) {
    /* Finite timestamps far apart can still overflow their difference. */
    if (!isfinite(end_us - zone->ts_us)) return core_error_set(b->error, CORE_ERROR_RANGE, "event %zu: zone duration out of range", index);
    trace_report_detail *d = b->detail;
    uint32_t name = report_name_index(&b->zones, zone->name);
    d->instances = core_grow(d->instances, &d->instance_capacity, d->instance_count + 1, sizeof *d->instances);
    d->instances[d->instance_count] = (report_instance){
        .zone = name, .thread = thread, .begin_event = zone->event, .begin_us = zone->ts_us, .end_us = end_us,
        .self_us = end_us - zone->ts_us, .args = zone->args,
    };
    if (strcmp(zone->name, "frame") == 0) {
        trace_report *report = b->report;
        d->frames = core_grow(d->frames, &d->frame_capacity, report->frame_count + 1, sizeof *d->frames);
        d->frames[report->frame_count++] = d->instance_count;
    }
    d->instance_count++;
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

static uint32_t report_thread_of(report_builder *b, const core_json_value *event) {
    uint64_t pid = report_id(core_json_get(event, "pid")), tid = report_id(core_json_get(event, "tid"));
    /* Consecutive events are usually from the same thread: try the last one first. */
    if (b->thread_count && b->threads[b->last_thread].pid == pid && b->threads[b->last_thread].tid == tid)
        return (uint32_t)b->last_thread;
    for (size_t i = 0; i < b->thread_count; i++) {
        if (b->threads[i].pid == pid && b->threads[i].tid == tid) {
            b->last_thread = i;
            return (uint32_t)i;
        }
    }
    b->threads = core_grow(b->threads, &b->thread_capacity, b->thread_count + 1, sizeof *b->threads);
    b->threads[b->thread_count] = (report_thread){ .pid = pid, .tid = tid };
    b->last_thread = b->thread_count++;
    return (uint32_t)b->last_thread;
}

/* ---- events ----------------------------------------------------------------------------- */

static const char *report_event_name(const core_json_value *event) {
    return core_json_string_or(core_json_get(event, "name"), "(unnamed)");
}

static bool report_event_time(report_builder *b, const core_json_value *event, size_t index,
                              const char *key, char ph, double *out) {
    const core_json_value *value = core_json_get(event, key);
    if (!value || value->type != CORE_JSON_NUMBER)
        return core_error_set(b->error, CORE_ERROR_FORMAT, "event %zu (\"%c\") has no numeric \"%s\"", index, ph, key);
    *out = value->number;
    return true;
}

static bool report_begin(report_builder *b, const core_json_value *event, size_t index) {
    double ts = 0;
    if (!report_event_time(b, event, index, "ts", 'B', &ts)) return false;
    uint32_t thread_index = report_thread_of(b, event); /* may grow b->threads */
    report_thread *thread = &b->threads[thread_index];
    thread->open = core_grow(thread->open, &thread->open_capacity, thread->open_count + 1, sizeof *thread->open);
    thread->open[thread->open_count++] = (report_open_zone){
        .name = report_event_name(event), .ts_us = ts, .event = index, .args = report_args_text(b, event) };
    return true;
}

static bool report_end(report_builder *b, const core_json_value *event, size_t index) {
    double ts = 0;
    if (!report_event_time(b, event, index, "ts", 'E', &ts)) return false;
    uint32_t thread_index = report_thread_of(b, event);
    report_thread *thread = &b->threads[thread_index];
    if (thread->open_count == 0)
        return core_error_set(b->error, CORE_ERROR_FORMAT,
                           "event %zu: unbalanced \"E\": no matching \"B\" open on its thread (pid %g, tid %g)", index,
                           core_json_number_or(core_json_get(event, "pid"), 0),
                           core_json_number_or(core_json_get(event, "tid"), 0));
    report_open_zone zone = thread->open[--thread->open_count];
    if (ts < zone.ts_us)
        return core_error_set(b->error, CORE_ERROR_FORMAT, "event %zu: zone \"%.64s\" ends (ts %g) before it begins (ts %g)", index,
                           zone.name, ts, zone.ts_us);
    if (!zone.args) zone.args = report_args_text(b, event); /* Chrome merges an E's args into its zone */
    return report_add_zone(b, index, thread_index, &zone, ts);
}

static bool report_complete(report_builder *b, const core_json_value *event, size_t index) {
    double ts = 0, dur = 0;
    if (!report_event_time(b, event, index, "ts", 'X', &ts)) return false;
    if (!report_event_time(b, event, index, "dur", 'X', &dur)) return false;
    if (dur < 0) return core_error_set(b->error, CORE_ERROR_RANGE, "event %zu: \"X\" with a negative \"dur\" (%g)", index, dur);
    report_open_zone zone = { .name = report_event_name(event), .ts_us = ts, .event = index,
                              .args = report_args_text(b, event) };
    return report_add_zone(b, index, report_thread_of(b, event), &zone, ts + dur);
}

static void report_add_sample(report_builder *b, const char *series, size_t index, double ts, double value) {
    trace_report_detail *d = b->detail;
    d->samples = core_grow(d->samples, &d->sample_capacity, d->sample_count + 1, sizeof *d->samples);
    d->samples[d->sample_count++] = (report_counter_sample){
        .series = report_name_index(&b->series, series), .event = index, .ts_us = ts, .value = value };
}

/* A "C" event: {"value": v} alone is the series NAME; other keys are series NAME.KEY each. */
static bool report_counter(report_builder *b, const core_json_value *event, size_t index) {
    b->report->counter_count++;
    double ts = 0;
    if (!report_event_time(b, event, index, "ts", 'C', &ts)) return false;
    const char *name = report_event_name(event);
    const core_json_value *args = core_json_get(event, "args");
    if (!args || args->type != CORE_JSON_OBJECT) return true; /* a counter with no values */
    bool only_value = args->object.count == 1 && strcmp(args->object.keys[0].chars, "value") == 0;
    for (size_t i = 0; i < args->object.count; i++) {
        const core_json_value *value = &args->object.values[i];
        if (value->type != CORE_JSON_NUMBER) continue; /* Chrome plots numbers only */
        if (only_value) {
            report_add_sample(b, name, index, ts, value->number);
            continue;
        }
        const char *key = args->object.keys[i].chars;
        size_t name_length = strlen(name), key_length = strlen(key);
        char *series = core_arena_alloc(b->arena, name_length + key_length + 2, 1);
        memcpy(series, name, name_length);
        series[name_length] = '.';
        memcpy(series + name_length + 1, key, key_length + 1);
        report_add_sample(b, series, index, ts, value->number);
    }
    return true;
}

static bool report_event(report_builder *b, const core_json_value *event, size_t index) {
    if (event->type != CORE_JSON_OBJECT) return core_error_set(b->error, CORE_ERROR_FORMAT, "event %zu is not an object", index);
    const core_json_value *ph = core_json_get(event, "ph");
    if (!ph || ph->type != CORE_JSON_STRING)
        return core_error_set(b->error, CORE_ERROR_FORMAT, "event %zu has no \"ph\" (phase) string", index);
    if (ph->string.length != 1) return true; /* not a phase this report knows */
    switch (ph->string.chars[0]) {
    case 'B': return report_begin(b, event, index);
    case 'E': return report_end(b, event, index);
    case 'X': return report_complete(b, event, index);
    case 'C': return report_counter(b, event, index);
    default: return true; /* metadata, instants, flows, …: not part of the summary */
    }
}

/* ---- self times ------------------------------------------------------------------------- */

typedef struct report_span {
    uint32_t thread;
    size_t begin_event, instance;
    double begin_us, end_us;
} report_span;

/* Per thread, by begin; a zone that ends later encloses one that begins with it; equal spans
 * nest in the order their B events come (the outer B comes first). */
static int report_compare_spans(const void *a, const void *b) {
    const report_span *x = a, *y = b;
    if (x->thread != y->thread) return x->thread < y->thread ? -1 : 1;
    if (x->begin_us != y->begin_us) return x->begin_us < y->begin_us ? -1 : 1;
    if (x->end_us != y->end_us) return x->end_us > y->end_us ? -1 : 1;
    return (x->begin_event > y->begin_event) - (x->begin_event < y->begin_event);
}

/* Each zone's parent is the innermost zone of its thread that begins no later and ends no
 * earlier (a stack over the sorted spans); the parent's self time loses the child's duration.
 * X events that overlap without nesting (not valid in a trace) could take a parent below
 * zero: clamped. */
static void report_self_times(trace_report_detail *d) {
    size_t n = d->instance_count;
    if (n == 0) return;
    report_span *spans = core_alloc(n * sizeof *spans);
    for (size_t i = 0; i < n; i++) {
        const report_instance *z = &d->instances[i];
        spans[i] = (report_span){ .thread = z->thread, .begin_event = z->begin_event, .instance = i,
                                  .begin_us = z->begin_us, .end_us = z->end_us };
    }
    qsort(spans, n, sizeof *spans, report_compare_spans);
    size_t *stack = core_alloc(n * sizeof *stack), depth = 0;
    for (size_t i = 0; i < n; i++) {
        const report_span *s = &spans[i];
        while (depth && (spans[stack[depth - 1]].thread != s->thread || spans[stack[depth - 1]].end_us < s->end_us))
            depth--;
        if (depth) d->instances[spans[stack[depth - 1]].instance].self_us -= s->end_us - s->begin_us;
        stack[depth++] = i;
    }
    for (size_t i = 0; i < n; i++) d->instances[i].self_us = fmax(d->instances[i].self_us, 0.0);
    core_free(stack, n * sizeof *stack);
    core_free(spans, n * sizeof *spans);
}

/* ---- statistics ------------------------------------------------------------------------- */

typedef struct report_sample {
    uint32_t zone;
    double ms, self_ms;
} report_sample;

typedef struct report_zone_entry {
    trace_zone_stats stats;
    uint32_t zone; /* name index */
} report_zone_entry;

static int report_compare_samples(const void *a, const void *b) {
    const report_sample *x = a, *y = b;
    if (x->zone != y->zone) return x->zone < y->zone ? -1 : 1;
    return (x->ms > y->ms) - (x->ms < y->ms);
}

static int report_compare_zones(const void *a, const void *b) {
    const trace_zone_stats *x = &((const report_zone_entry *)a)->stats, *y = &((const report_zone_entry *)b)->stats;
    if (x->self_ms != y->self_ms) return x->self_ms > y->self_ms ? -1 : 1;
    if (x->total_ms != y->total_ms) return x->total_ms > y->total_ms ? -1 : 1;
    return strcmp(x->name, y->name); /* a stable order for equal times */
}

/* Statistics of one zone from its samples, sorted by duration. */
static trace_zone_stats report_one_zone(const char *name, const report_sample *run, size_t n, double *scratch) {
    trace_zone_stats stats = { .name = core_strdup(name), .count = n, .max_ms = run[n - 1].ms };
    for (size_t i = 0; i < n; i++) {
        scratch[i] = run[i].ms;
        stats.total_ms += run[i].ms;
        stats.self_ms += run[i].self_ms;
    }
    stats.p99_ms = trace_percentile(scratch, n, 99);
    return stats;
}

/* One pass over the zones sorted by (zone, duration); then zones are sorted by self time and
 * every instance learns its zone's place in report->zones. */
static void report_zone_stats(report_builder *b) {
    trace_report *report = b->report;
    trace_report_detail *d = b->detail;
    size_t n = d->instance_count;
    if (n == 0) return;
    report_sample *samples = core_alloc(n * sizeof *samples);
    for (size_t i = 0; i < n; i++)
        samples[i] = (report_sample){ .zone = d->instances[i].zone,
                                      .ms = (d->instances[i].end_us - d->instances[i].begin_us) / 1000.0,
                                      .self_ms = d->instances[i].self_us / 1000.0 };
    qsort(samples, n, sizeof *samples, report_compare_samples);
    double *scratch = core_alloc(n * sizeof *scratch);
    report_zone_entry *entries = core_calloc(b->zones.count, sizeof *entries);
    size_t count = 0;
    for (size_t i = 0, first = 0; i < n; first = i) {
        uint32_t zone = samples[i].zone;
        while (i < n && samples[i].zone == zone) i++;
        entries[count++] = (report_zone_entry){
            .stats = report_one_zone(b->zones.names[zone], samples + first, i - first, scratch), .zone = zone };
    }
    qsort(entries, count, sizeof *entries, report_compare_zones);
    uint32_t *place = core_alloc(b->zones.count * sizeof *place);
    report->zones = core_calloc(count, sizeof *report->zones);
    for (size_t i = 0; i < count; i++) {
        report->zones[i] = entries[i].stats;
        place[entries[i].zone] = (uint32_t)i;
    }
    report->zone_count = count;
    for (size_t i = 0; i < n; i++) d->instances[i].zone = place[d->instances[i].zone];
    core_free(place, b->zones.count * sizeof *place);
    core_free(entries, b->zones.count * sizeof *entries);
    core_free(scratch, n * sizeof *scratch);
    core_free(samples, n * sizeof *samples);
}

static int report_compare_counter_samples(const void *a, const void *b) {
    const report_counter_sample *x = a, *y = b;
    if (x->series != y->series) return x->series < y->series ? -1 : 1;
    if (x->ts_us != y->ts_us) return x->ts_us < y->ts_us ? -1 : 1;
    return (x->event > y->event) - (x->event < y->event);
}

typedef struct report_counter_entry {
    trace_counter_stats stats;
    size_t first; /* first sample */
} report_counter_entry;

static int report_compare_counters(const void *a, const void *b) {
    return strcmp(((const report_counter_entry *)a)->stats.name, ((const report_counter_entry *)b)->stats.name);
}

static trace_counter_stats report_one_counter(const char *name, const report_counter_sample *run, size_t n) {
    trace_counter_stats stats = { .name = core_strdup(name), .count = n, .min = run[0].value, .max = run[0].value,
                                  .last = run[n - 1].value };
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        stats.min = fmin(stats.min, run[i].value);
        stats.max = fmax(stats.max, run[i].value);
        sum += run[i].value;
    }
    stats.mean = sum / (double)n;
    return stats;
}

/* Samples sorted by (series, ts): each series' run gives its statistics, its last sample is the
 * latest, and trace_report_slowest can search it by time. */
static void report_counter_stats(report_builder *b) {
    trace_report *report = b->report;
    trace_report_detail *d = b->detail;
    size_t n = d->sample_count, series = b->series.count;
    if (n == 0) return;
    qsort(d->samples, n, sizeof *d->samples, report_compare_counter_samples);
    report_counter_entry *entries = core_calloc(series, sizeof *entries);
    size_t count = 0;
    for (size_t i = 0, first = 0; i < n; first = i) {
        uint32_t s = d->samples[i].series;
        while (i < n && d->samples[i].series == s) i++;
        entries[count++] = (report_counter_entry){
            .stats = report_one_counter(b->series.names[s], d->samples + first, i - first), .first = first };
    }
    qsort(entries, count, sizeof *entries, report_compare_counters);
    report->counters = core_calloc(count, sizeof *report->counters);
    d->counter_first = core_calloc(count, sizeof *d->counter_first);
    for (size_t i = 0; i < count; i++) {
        report->counters[i] = entries[i].stats;
        d->counter_first[i] = entries[i].first;
    }
    report->counter_series_count = count;
    core_free(entries, series * sizeof *entries);
}

typedef struct report_begin_key {
    double begin_us;
    size_t instance;
} report_begin_key;

static int report_compare_begin_keys(const void *a, const void *b) {
    const report_begin_key *x = a, *y = b;
    if (x->begin_us != y->begin_us) return x->begin_us < y->begin_us ? -1 : 1;
    return (x->instance > y->instance) - (x->instance < y->instance);
}

/* Zones by begin time, with the latest end reached so far: the zones that overlap a span
 * [begin, end) all lie between the first whose reach passes `begin` and the first that begins
 * at `end`, so a slow frame looks at the zones near it rather than at all of them. */
static void report_time_index(trace_report_detail *d) {
    size_t n = d->instance_count;
    if (n == 0) return;
    report_begin_key *keys = core_alloc(n * sizeof *keys);
    for (size_t i = 0; i < n; i++) keys[i] = (report_begin_key){ .begin_us = d->instances[i].begin_us, .instance = i };
    qsort(keys, n, sizeof *keys, report_compare_begin_keys);
    d->by_begin = core_alloc(n * sizeof *d->by_begin);
    d->reach_us = core_alloc(n * sizeof *d->reach_us);
    double reach = -INFINITY;
    for (size_t k = 0; k < n; k++) {
        d->by_begin[k] = keys[k].instance;
        reach = fmax(reach, d->instances[keys[k].instance].end_us);
        d->reach_us[k] = reach;
    }
    core_free(keys, n * sizeof *keys);
}

static void report_frame_stats(report_builder *b) {
    trace_report *report = b->report;
    size_t n = report->frame_count;
    if (n == 0) return;
    report->frame_ms = core_alloc(n * sizeof *report->frame_ms);
    for (size_t i = 0; i < n; i++) {
        const report_instance *frame = &b->detail->instances[b->detail->frames[i]];
        report->frame_ms[i] = (frame->end_us - frame->begin_us) / 1000.0;
    }
    double *sorted = core_alloc(n * sizeof *sorted);
    memcpy(sorted, report->frame_ms, n * sizeof *sorted);
    qsort(sorted, n, sizeof *sorted, report_compare_doubles); /* file order is kept above */
    report->frame_p50_ms = trace_percentile(sorted, n, 50);
    report->frame_p95_ms = trace_percentile(sorted, n, 95);
    report->frame_p99_ms = trace_percentile(sorted, n, 99);
    report->frame_max_ms = sorted[n - 1];
    for (size_t i = 0; i < n; i++) {
        report->frames_over_16ms += sorted[i] > REPORT_FRAME_BUDGET_60HZ_MS;
        report->frames_over_33ms += sorted[i] > REPORT_FRAME_BUDGET_30HZ_MS;
    }
    core_free(sorted, n * sizeof *sorted);
}

static void report_detail_free(trace_report_detail *d, size_t counter_count) {
    if (!d) return;
    core_free(d->instances, d->instance_capacity * sizeof *d->instances);
    core_free(d->frames, d->frame_capacity * sizeof *d->frames);
    core_free(d->samples, d->sample_capacity * sizeof *d->samples);
    core_free(d->counter_first, counter_count * sizeof *d->counter_first);
    core_free(d->by_begin, d->instance_count * sizeof *d->by_begin);
    core_free(d->reach_us, d->instance_count * sizeof *d->reach_us);
    core_free(d->text, d->text_capacity);
    core_free(d, sizeof *d);
}

static void report_builder_free(report_builder *b) {
    for (size_t i = 0; i < b->thread_count; i++)
        core_free(b->threads[i].open, b->threads[i].open_capacity * sizeof *b->threads[i].open);
    core_free(b->threads, b->thread_capacity * sizeof *b->threads);
    report_names_free(&b->zones);
    report_names_free(&b->series);
}

/* ---- loading ---------------------------------------------------------------------------- */

static const core_json_value *report_find_events(const core_json_value *root, core_error *error) {
    if (root->type == CORE_JSON_ARRAY) return root; /* the bare-array form of the format */
    const core_json_value *events = core_json_get(root, "traceEvents");
    if (!events || events->type != CORE_JSON_ARRAY) {
        core_error_set(error, CORE_ERROR_FORMAT, "no \"traceEvents\" array: not a Chrome trace");
        return NULL;
    }
    return events;
}

bool trace_report_parse(const char *json, size_t size, trace_report *report, core_error *error) {
    *report = (trace_report){ 0 };
    core_arena arena = { 0 };
    core_json_value *root;
    core_error json_error = { 0 };
    bool ok = core_json_parse(json, size, &arena, &root, &json_error);
    if (!ok) core_error_set(error, CORE_ERROR_FORMAT, "not valid JSON: %s", json_error.message);
    const core_json_value *events = ok ? report_find_events(root, error) : NULL;
    ok = events != NULL;
    report_builder b = { .report = report, .error = error, .arena = &arena, .detail = core_calloc(1, sizeof(trace_report_detail)) };
    for (size_t i = 0; ok && i < events->array.count; i++) ok = report_event(&b, &events->array.items[i], i);
    if (ok) {
        report_self_times(b.detail);
        report_zone_stats(&b);
        report_counter_stats(&b);
        report_frame_stats(&b);
        report_time_index(b.detail);
        report->detail = b.detail;
    } else {
        report->frame_count = 0;
        report->counter_count = 0;
        report_detail_free(b.detail, 0);
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

bool trace_report_load(const char *path, trace_report *report, core_error *error) {
    size_t size, capacity;
    char *data = report_read_file(path, &size, &capacity);
    if (!data) {
        int read_errno = errno;
        *report = (trace_report){ 0 };
        return core_error_set(error, CORE_ERROR_IO, "cannot read '%s': %s", path, strerror(read_errno));
    }
    core_error reason = { 0 };
    bool ok = trace_report_parse(data, size, report, &reason);
    core_free(data, capacity);
    if (!ok) core_error_set(error, reason.code, "%s: %s", path, reason.message);
    return ok;
}

void trace_report_free(trace_report *report) {
    core_free(report->frame_ms, report->frame_count * sizeof *report->frame_ms);
    for (size_t i = 0; i < report->zone_count; i++)
        core_free((char *)report->zones[i].name, strlen(report->zones[i].name) + 1);
    core_free(report->zones, report->zone_count * sizeof *report->zones);
    for (size_t i = 0; i < report->counter_series_count; i++)
        core_free((char *)report->counters[i].name, strlen(report->counters[i].name) + 1);
    core_free(report->counters, report->counter_series_count * sizeof *report->counters);
    report_detail_free(report->detail, report->counter_series_count);
    *report = (trace_report){ 0 };
}

/* ---- printing --------------------------------------------------------------------------- */

/* A name padded to `width`; control characters would garble the terminal, so they show as '?'. */
static void report_print_name(FILE *out, const char *name, int width) {
    int written = 0;
    for (const char *c = name; *c; c++) {
        fputc((unsigned char)*c < 0x20 ? '?' : *c, out);
        written += ((unsigned char)*c & 0xc0) != 0x80; /* characters, not UTF-8 bytes */
    }
    for (; written < width; written++) fputc(' ', out);
}

static double report_share(size_t part, size_t whole) { return whole ? 100.0 * (double)part / (double)whole : 0.0; }

static void report_print_counters(const trace_report *report, FILE *out) {
    fprintf(out, "counters     %zu events, %zu series\n", report->counter_count, report->counter_series_count);
    if (report->counter_series_count == 0) return;
    fprintf(out, "\n%-32s %8s %14s %14s %14s %14s\n", "counter", "samples", "min", "max", "mean", "last");
    for (size_t i = 0; i < report->counter_series_count; i++) {
        const trace_counter_stats *c = &report->counters[i];
        report_print_name(out, c->name, 32);
        fprintf(out, " %8zu %14.10g %14.10g %14.10g %14.10g\n", c->count, c->min, c->max, c->mean, c->last);
    }
}

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
    report_print_counters(report, out);
    fprintf(out, "\n%-32s %10s %12s %12s %10s %10s\n", "zone (by self time)", "count", "self ms", "total ms",
            "p99 ms", "max ms");
    for (size_t i = 0; i < report->zone_count; i++) {
        const trace_zone_stats *zone = &report->zones[i];
        report_print_name(out, zone->name, 32);
        fprintf(out, " %10zu %12.3f %12.3f %10.3f %10.3f\n", zone->count, zone->self_ms, zone->total_ms,
                zone->p99_ms, zone->max_ms);
    }
}

/* ---- the slowest frames ----------------------------------------------------------------- */

typedef struct report_frame_key {
    double ms;
    size_t index;
} report_frame_key;

static int report_compare_frame_keys(const void *a, const void *b) {
    const report_frame_key *x = a, *y = b;
    if (x->ms != y->ms) return x->ms > y->ms ? -1 : 1;
    return (x->index > y->index) - (x->index < y->index);
}

static int report_compare_frame_zones(const void *a, const void *b) {
    const trace_frame_zone *x = a, *y = b;
    if (x->self_ms != y->self_ms) return x->self_ms > y->self_ms ? -1 : 1;
    return strcmp(x->name, y->name);
}

#define REPORT_ALL_THREADS UINT32_MAX

/* Every zone instance that overlaps [begin, end), on `thread` (or any: REPORT_ALL_THREADS), adds
 * its self time in the proportion of its duration that lies inside to all[its zone]
 * (report->zone_count entries): exact for zones inside the frame, a fair share for a job that
 * straddles its edge. Called for several spans on one array, it sums them. */
static void report_span_zones(const trace_report *report, double begin_us, double end_us, uint32_t thread,
                              trace_frame_zone *all) {
    const trace_report_detail *d = report->detail;
    size_t low = 0, high = d->instance_count; /* the first zone whose reach passes begin_us */
    while (low < high) {
        size_t mid = low + (high - low) / 2;
        if (d->reach_us[mid] > begin_us) high = mid; else low = mid + 1;
    }
    for (size_t k = low; k < d->instance_count && d->instances[d->by_begin[k]].begin_us < end_us; k++) {
        const report_instance *z = &d->instances[d->by_begin[k]];
        double overlap = fmin(z->end_us, end_us) - fmax(z->begin_us, begin_us);
        if (!(overlap > 0) || (thread != REPORT_ALL_THREADS && z->thread != thread)) continue;
        double duration = z->end_us - z->begin_us;
        trace_frame_zone *entry = &all[z->zone];
        entry->count++;
        entry->self_ms += z->self_us * (overlap / duration) / 1000.0;
        if (duration / 1000.0 > entry->slowest_ms) {
            entry->slowest_ms = duration / 1000.0;
            entry->args = z->args ? d->text + z->args : NULL;
        }
    }
}

static void report_frame_zones(const trace_report *report, double begin_us, double end_us, size_t top,
                               trace_slow_frame *frame) {
    trace_frame_zone *all = core_calloc(report->zone_count, sizeof *all);
    report_span_zones(report, begin_us, end_us, REPORT_ALL_THREADS, all);
    size_t used = 0;
    for (size_t z = 0; z < report->zone_count; z++) {
        if (all[z].count == 0) continue;
        all[used] = all[z];
        all[used++].name = report->zones[z].name;
    }
    qsort(all, used, sizeof *all, report_compare_frame_zones);
    frame->zone_count = CORE_MIN(used, top);
    if (frame->zone_count) {
        frame->zones = core_alloc(frame->zone_count * sizeof *frame->zones);
        memcpy(frame->zones, all, frame->zone_count * sizeof *frame->zones);
    }
    core_free(all, report->zone_count * sizeof *all);
}

/* Series c's last sample at or before end_us (its samples are sorted by time: bisection);
 * false when it has none yet. */
static bool report_series_at(const trace_report *report, size_t c, double end_us, double *value) {
    const trace_report_detail *d = report->detail;
    const report_counter_sample *run = d->samples + d->counter_first[c];
    size_t low = 0, high = report->counters[c].count; /* samples [0, low) are at or before end_us */
    while (low < high) {
        size_t mid = low + (high - low) / 2;
        if (run[mid].ts_us <= end_us) low = mid + 1; else high = mid;
    }
    if (low == 0) return false;
    *value = run[low - 1].value;
    return true;
}

/* Every series' last sample at or before `end_us`. */
static void report_frame_counters(const trace_report *report, double end_us, trace_slow_frame *frame) {
    if (report->counter_series_count == 0) return;
    frame->counters = core_alloc(report->counter_series_count * sizeof *frame->counters);
    for (size_t c = 0; c < report->counter_series_count; c++) {
        double value;
        if (report_series_at(report, c, end_us, &value))
            frame->counters[frame->counter_count++] = (trace_frame_counter){ .name = report->counters[c].name, .value = value };
    }
    /* Keep exactly counter_count, so the frame can be freed knowing only its own fields. */
    trace_frame_counter *all = frame->counters;
    frame->counters = NULL;
    if (frame->counter_count) {
        frame->counters = core_alloc(frame->counter_count * sizeof *frame->counters);
        memcpy(frame->counters, all, frame->counter_count * sizeof *frame->counters);
    }
    core_free(all, report->counter_series_count * sizeof *all);
}

void trace_report_slowest(const trace_report *report, size_t n, size_t top_zones, trace_slowest *out) {
    *out = (trace_slowest){ 0 };
    size_t frames = report->frame_count;
    if (!report->detail || frames == 0 || n == 0) return;
    report_frame_key *keys = core_alloc(frames * sizeof *keys);
    for (size_t i = 0; i < frames; i++) keys[i] = (report_frame_key){ .ms = report->frame_ms[i], .index = i };
    qsort(keys, frames, sizeof *keys, report_compare_frame_keys);
    out->frame_count = CORE_MIN(n, frames);
    out->frames = core_calloc(out->frame_count, sizeof *out->frames);
    for (size_t i = 0; i < out->frame_count; i++) {
        const report_instance *z = &report->detail->instances[report->detail->frames[keys[i].index]];
        trace_slow_frame *frame = &out->frames[i];
        frame->index = keys[i].index;
        frame->start_ms = z->begin_us / 1000.0;
        frame->duration_ms = (z->end_us - z->begin_us) / 1000.0;
        report_frame_zones(report, z->begin_us, z->end_us, top_zones, frame);
        report_frame_counters(report, z->end_us, frame);
    }
    core_free(keys, frames * sizeof *keys);
}

void trace_slowest_free(trace_slowest *slowest) {
    for (size_t i = 0; i < slowest->frame_count; i++) {
        trace_slow_frame *frame = &slowest->frames[i];
        core_free(frame->zones, frame->zone_count * sizeof *frame->zones);
        core_free(frame->counters, frame->counter_count * sizeof *frame->counters);
    }
    core_free(slowest->frames, slowest->frame_count * sizeof *slowest->frames);
    *slowest = (trace_slowest){ 0 };
}

/* Args are text from the file: control characters show as '?', like names. */
static void report_print_args(FILE *out, const char *args) {
    for (const char *c = args; *c; c++) fputc((unsigned char)*c < 0x20 ? '?' : *c, out);
}

static void report_print_slow_frame(FILE *out, const trace_slow_frame *frame) {
    fprintf(out, "\nframe %zu   at %.3f ms   %.3f ms\n", frame->index, frame->start_ms, frame->duration_ms);
    fprintf(out, "  %-30s %10s %8s %10s   %s\n", "zone (by self time)", "self ms", "count", "max ms",
            "args of the longest");
    for (size_t i = 0; i < frame->zone_count; i++) {
        const trace_frame_zone *zone = &frame->zones[i];
        fputs("  ", out);
        report_print_name(out, zone->name, 30);
        fprintf(out, " %10.3f %8zu %10.3f", zone->self_ms, zone->count, zone->slowest_ms);
        if (zone->args) {
            fputs("   ", out);
            report_print_args(out, zone->args);
        }
        fputc('\n', out);
    }
    if (frame->counter_count == 0) return;
    fputs("  counters at its end:", out);
    for (size_t i = 0; i < frame->counter_count; i++) {
        fputs(i ? ", " : " ", out);
        report_print_args(out, frame->counters[i].name);
        fprintf(out, " %.10g", frame->counters[i].value);
    }
    fputc('\n', out);
}

void trace_slowest_print(const trace_slowest *slowest, FILE *out) {
    fprintf(out, "slowest %zu frames (zones by self time inside the frame, all threads)\n", slowest->frame_count);
    for (size_t i = 0; i < slowest->frame_count; i++) report_print_slow_frame(out, &slowest->frames[i]);
}

/* ---- frames over a budget ------------------------------------------------------------------ */

#define REPORT_BUDGET_GAP 30
#define REPORT_BUDGET_TOP_ZONES 8
#define REPORT_BUDGET_PRINTED_RUNS 20

static int report_compare_budget_zones(const void *a, const void *b) {
    const trace_budget_zone *x = a, *y = b;
    double dx = x->over_ms - x->within_ms, dy = y->over_ms - y->within_ms;
    if (dx != dy) return dx > dy ? -1 : 1;
    return strcmp(x->name, y->name);
}

/* The frames' values: durations, or series c's sample at each frame's end (NaN: none yet). */
static double *report_budget_values(const trace_report *report, const char *series, core_error *error) {
    size_t c = 0;
    if (series) {
        while (c < report->counter_series_count && strcmp(report->counters[c].name, series) != 0) c++;
        if (c == report->counter_series_count) {
            core_error_set(error, CORE_ERROR_ARGUMENT, "no counter series \"%.64s\" in the trace (%zu series)", series,
                           report->counter_series_count);
            return NULL;
        }
    }
    double *values = core_alloc((report->frame_count ? report->frame_count : 1) * sizeof *values);
    for (size_t i = 0; i < report->frame_count; i++) {
        values[i] = report->frame_ms[i];
        if (!series) continue;
        const report_instance *z = report->detail ? &report->detail->instances[report->detail->frames[i]] : NULL;
        if (!z || !report_series_at(report, c, z->end_us, &values[i])) values[i] = NAN;
    }
    return values;
}

/* Over frames at most `gap` apart share a run. */
static void report_budget_runs(trace_over_budget *out, const double *values, size_t frames, size_t gap) {
    size_t capacity = 0;
    for (size_t i = 0; i < frames; i++) {
        if (!(values[i] > out->budget_ms)) continue;
        trace_budget_run *run = out->run_count ? &out->runs[out->run_count - 1] : NULL;
        if (!run || i - run->last > gap) {
            out->runs = core_grow(out->runs, &capacity, out->run_count + 1, sizeof *out->runs);
            run = &out->runs[out->run_count++];
            *run = (trace_budget_run){ .first = i, .worst_ms = values[i] };
        }
        run->last = i;
        run->over++;
        run->worst_ms = fmax(run->worst_ms, values[i]);
    }
    /* Exactly run_count, so that trace_over_budget_free knows the size. */
    if (out->run_count) out->runs = core_realloc(out->runs, capacity * sizeof *out->runs, out->run_count * sizeof *out->runs);
}

/* Each group's zone shares summed over its frames, then their means side by side. */
static void report_budget_zones(const trace_report *report, trace_over_budget *out, const double *values, size_t top) {
    size_t zones = report->zone_count;
    if (zones == 0) return;
    trace_frame_zone *over = core_calloc(zones, sizeof *over), *within = core_calloc(zones, sizeof *within);
    for (size_t i = 0; i < report->frame_count; i++) {
        if (isnan(values[i])) continue;
        const report_instance *z = &report->detail->instances[report->detail->frames[i]];
        report_span_zones(report, z->begin_us, z->end_us, z->thread, values[i] > out->budget_ms ? over : within);
    }
    size_t within_frames = out->frames - out->over;
    trace_budget_zone *all = core_alloc(zones * sizeof *all);
    size_t used = 0;
    for (size_t k = 0; k < zones; k++) {
        if (over[k].count == 0 && within[k].count == 0) continue;
        all[used++] = (trace_budget_zone){
            .name = report->zones[k].name,
            .over_ms = out->over ? over[k].self_ms / (double)out->over : 0.0,
            .within_ms = within_frames ? within[k].self_ms / (double)within_frames : 0.0,
        };
    }
    qsort(all, used, sizeof *all, report_compare_budget_zones);
    out->zone_count = CORE_MIN(used, top);
    if (out->zone_count) {
        out->zones = core_alloc(out->zone_count * sizeof *out->zones);
        memcpy(out->zones, all, out->zone_count * sizeof *out->zones);
    }
    core_free(all, zones * sizeof *all);
    core_free(over, zones * sizeof *over);
    core_free(within, zones * sizeof *within);
}

bool trace_report_over_budget(const trace_report *report, const trace_budget_desc *desc, trace_over_budget *out,
                              core_error *error) {
    *out = (trace_over_budget){ 0 };
    if (!desc || !(desc->budget_ms > 0) || !isfinite(desc->budget_ms))
        return core_error_set(error, CORE_ERROR_ARGUMENT, "the budget must be a number of milliseconds above 0");
    double *values = report_budget_values(report, desc->series, error);
    if (!values) return false;
    out->budget_ms = desc->budget_ms;
    out->series = desc->series;
    for (size_t i = 0; i < report->frame_count; i++) {
        out->frames += !isnan(values[i]);
        out->over += values[i] > desc->budget_ms;
    }
    report_budget_runs(out, values, report->frame_count, desc->gap ? desc->gap : REPORT_BUDGET_GAP);
    if (report->detail) report_budget_zones(report, out, values, desc->top_zones ? desc->top_zones : REPORT_BUDGET_TOP_ZONES);
    core_free(values, (report->frame_count ? report->frame_count : 1) * sizeof *values);
    return true;
}

void trace_over_budget_print(const trace_over_budget *over, FILE *out) {
    fprintf(out, "frames over %.3f ms (%s): %zu of %zu (%.2f%%) in %zu runs\n", over->budget_ms,
            over->series ? over->series : "frame duration", over->over, over->frames, report_share(over->over, over->frames),
            over->run_count);
    size_t shown = CORE_MIN(over->run_count, (size_t)REPORT_BUDGET_PRINTED_RUNS);
    for (size_t i = 0; i < shown; i++) {
        const trace_budget_run *run = &over->runs[i];
        fprintf(out, "  frames %7zu - %-7zu %6zu over   worst %.3f ms\n", run->first, run->last, run->over, run->worst_ms);
    }
    if (over->run_count > shown) fprintf(out, "  ... and %zu more runs\n", over->run_count - shown);
    if (over->zone_count == 0) return;
    fprintf(out, "\n  %-30s %12s %12s %10s\n", "zone (self ms a frame)", "over", "within", "more");
    for (size_t i = 0; i < over->zone_count; i++) {
        const trace_budget_zone *zone = &over->zones[i];
        fputs("  ", out);
        report_print_name(out, zone->name, 30);
        fprintf(out, " %12.3f %12.3f %+10.3f\n", zone->over_ms, zone->within_ms, zone->over_ms - zone->within_ms);
    }
}

void trace_over_budget_free(trace_over_budget *over) {
    core_free(over->runs, over->run_count * sizeof *over->runs);
    core_free(over->zones, over->zone_count * sizeof *over->zones);
    *over = (trace_over_budget){ 0 };
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

bool trace_report_write_svg(const trace_report *report, const char *svg_path, core_error *error) {
    FILE *out = fopen(svg_path, "w");
    if (!out) return core_error_set(error, CORE_ERROR_IO, "cannot write '%s': %s", svg_path, strerror(errno));
    svg_write(out, report);
    bool failed = ferror(out) != 0;
    if (fclose(out) != 0) failed = true;
    if (failed) core_error_set(error, CORE_ERROR_IO, "writing '%s' failed: %s", svg_path, strerror(errno));
    return !failed;
}
