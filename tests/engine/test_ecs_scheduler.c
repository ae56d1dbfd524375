/* Tests of the ECS scheduler (engine/ecs): phases, conflicts, main-thread and parallel
 * systems on a 2-thread job system. Also meant to run under ThreadSanitizer. */
#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include "test.h"
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct Position { float x, y; } Position;
typedef struct Velocity { float x, y; } Velocity;
typedef struct Counter { int visits; } Counter;

typedef struct fixture {
    job_system *jobs;
    ecs_world *world;
    ecs_component position, velocity, counter;
} fixture;

static fixture fixture_make(int threads) {
    fixture f = { .jobs = threads ? job_system_create(&(job_system_desc){ .threads = threads }) : NULL };
    f.world = ecs_world_create(&(ecs_world_desc){ .jobs = f.jobs });
    f.position = ECS_COMPONENT(f.world, Position);
    f.velocity = ECS_COMPONENT(f.world, Velocity);
    f.counter = ECS_COMPONENT(f.world, Counter);
    return f;
}

static void fixture_free(fixture *f) {
    ecs_world_destroy(f->world);
    if (f->jobs) job_system_destroy(f->jobs);
}

static void spin_ns(uint64_t ns) {
    uint64_t start = core_time_ns();
    while (core_time_ns() - start < ns) {}
}

/* ---- conflicts -------------------------------------------------------------------------- */

enum { FRAMES = 8 };

typedef struct timed_system {
    uint64_t begin[FRAMES], end[FRAMES];
    int calls;
    _Atomic int *started;          /* set on entry, for a partner to see */
    _Atomic int *partner_started;  /* NULL: just spin 2 ms */
} timed_system;

/* Spins at least 2 ms; with a partner, also until the partner has started (at most 500 ms),
 * so two systems that may overlap do overlap even on a busy machine. */
static void timed(ecs_iter *it) {
    timed_system *t = it->user;
    uint64_t begin = core_time_ns();
    atomic_store(t->started, 1);
    spin_ns(2000000);
    if (t->partner_started)
        while (!atomic_load(t->partner_started) && core_time_ns() - begin < 500000000ull) {}
    if (t->calls < FRAMES) {
        t->begin[t->calls] = begin;
        t->end[t->calls] = core_time_ns();
    }
    t->calls++;
}

Test(ecs_scheduler, conflicting_systems_run_in_registration_order) {
    fixture f = fixture_make(2);
    _Atomic int started_a = 0, started_b = 0;
    timed_system a = { .started = &started_a }, b = { .started = &started_b };
    /* a writes Position, b reads it: they conflict. */
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "a", .phase = "game", .fn = timed,
        .user = &a, .query = { .with = { f.position } }, .writes = { f.position } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "b", .phase = "game", .fn = timed,
        .user = &b, .query = { .with = { f.position, f.velocity } } });
    for (int frame = 0; frame < FRAMES; frame++) ecs_progress(f.world, 0.016f);
    cr_assert_eq(a.calls, FRAMES);
    cr_assert_eq(b.calls, FRAMES);
    for (int i = 0; i < FRAMES; i++) {
        cr_expect_leq(a.end[i], b.begin[i], "frame %d: b started before a ended", i);
        if (i + 1 < FRAMES) cr_expect_leq(b.end[i], a.begin[i + 1], "frames do not overlap");
    }
    fixture_free(&f);
}

Test(ecs_scheduler, a_write_write_pair_conflicts_too) {
    fixture f = fixture_make(2);
    _Atomic int started_a = 0, started_b = 0;
    timed_system a = { .started = &started_a }, b = { .started = &started_b };
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "a", .phase = "stream", .fn = timed,
        .user = &a, .writes = { f.counter } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "b", .phase = "stream", .fn = timed,
        .user = &b, .reads = { f.position }, .writes = { f.counter } });
    for (int frame = 0; frame < FRAMES; frame++) ecs_progress(f.world, 0.016f);
    for (int i = 0; i < FRAMES; i++) cr_expect_leq(a.end[i], b.begin[i], "frame %d", i);
    fixture_free(&f);
}

Test(ecs_scheduler, independent_systems_overlap) {
    fixture f = fixture_make(2);
    _Atomic int started_a = 0, started_b = 0;
    timed_system a = { .started = &started_a, .partner_started = &started_b };
    timed_system b = { .started = &started_b, .partner_started = &started_a };
    /* Both read Position; each writes a component of its own: no conflict. */
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "a", .phase = "game", .fn = timed,
        .user = &a, .query = { .with = { f.position } }, .writes = { f.velocity } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "b", .phase = "game", .fn = timed,
        .user = &b, .query = { .with = { f.position } }, .writes = { f.counter } });
    ecs_progress(f.world, 0.016f);
    cr_assert_eq(a.calls, 1);
    cr_assert_eq(b.calls, 1);
    bool overlap = a.begin[0] < b.end[0] && b.begin[0] < a.end[0];
    cr_expect(overlap, "a [%llu, %llu] b [%llu, %llu]", (unsigned long long)a.begin[0],
              (unsigned long long)a.end[0], (unsigned long long)b.begin[0],
              (unsigned long long)b.end[0]);
    fixture_free(&f);
}

/* ---- main thread and phases ------------------------------------------------------------- */

typedef struct thread_probe {
    job_system *jobs;
    int calls, off_main;
} thread_probe;

static void record_thread(ecs_iter *it) {
    thread_probe *probe = it->user;
    probe->calls++;
    probe->off_main += job_thread_index(probe->jobs) != 0;
    spin_ns(200000);
}

static void busy(ecs_iter *it) {
    (void)it;
    spin_ns(200000);
}

Test(ecs_scheduler, main_thread_systems_run_on_the_main_thread) {
    fixture f = fixture_make(2);
    thread_probe probe = { .jobs = f.jobs };
    /* Busy neighbours keep the main thread occupied, so the worker is free to take the probe
     * if the scheduler let it. */
    for (int i = 0; i < 3; i++)
        ecs_system_add(f.world, &(ecs_system_desc){ .name = "busy", .phase = "draw", .fn = busy });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "upload", .phase = "draw",
        .fn = record_thread, .user = &probe, .main_thread = true });
    for (int frame = 0; frame < 20; frame++) ecs_progress(f.world, 0.016f);
    cr_expect_eq(probe.calls, 20);
    cr_expect_eq(probe.off_main, 0);
    fixture_free(&f);
}

typedef struct order_log {
    const char *names[16];
    int count;
} order_log;

typedef struct logged_system {
    order_log *log;
    const char *name;
} logged_system;

static void log_call(ecs_iter *it) {
    logged_system *s = it->user;
    s->log->names[s->log->count++] = s->name;
}

/* All loggers write Counter, so they also conflict: only phases can reorder them. */
static void add_logger(fixture *f, const char *phase, logged_system *s) {
    ecs_system_add(f->world, &(ecs_system_desc){ .name = s->name, .phase = phase, .fn = log_call,
                                                 .user = s, .writes = { f->counter } });
}

static void check_phase_order(int threads) {
    fixture f = fixture_make(threads);
    order_log log = { 0 };
    logged_system stream = { &log, "stream" }, game = { &log, "game" },
                  physics = { &log, "physics" }, input = { &log, "input" };
    /* Registered out of frame order on purpose; the phase decides when a system runs. */
    add_logger(&f, "stream", &stream);
    add_logger(&f, "game", &game);
    cr_assert(ecs_phase_add(f.world, "physics", "game"));
    add_logger(&f, "physics", &physics);
    add_logger(&f, "input", &input);
    ecs_progress(f.world, 0.016f);
    cr_assert_eq(log.count, 4, "threads %d", threads);
    const char *expected[] = { "input", "game", "physics", "stream" };
    for (int i = 0; i < 4; i++) cr_expect_str_eq(log.names[i], expected[i], "threads %d", threads);
    fixture_free(&f);
}

Test(ecs_scheduler, a_phase_added_after_game_runs_before_stream) {
    check_phase_order(0);
    check_phase_order(2);
}

Test(ecs_scheduler, bad_phase_names_are_refused) {
    fixture f = fixture_make(0);
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF); /* the errors are expected */
    cr_expect_not(ecs_phase_add(f.world, "physics", "no_such_phase"));
    cr_expect_not(ecs_phase_add(f.world, "stream", "game"), "stream exists already");
    cr_expect_eq(ecs_system_add(f.world, &(ecs_system_desc){ .name = "x", .phase = "nope", .fn = busy }), 0);
    core_log_set_level(level);
    fixture_free(&f);
}

/* ---- parallel systems and commands between phases ------------------------------------- */

typedef struct parallel_probe {
    ecs_component counter;
    _Atomic int calls;
    _Atomic int entities;
} parallel_probe;

static void visit(ecs_iter *it) {
    parallel_probe *probe = it->user;
    atomic_fetch_add(&probe->calls, 1);
    while (ecs_query_next(it)) {
        Counter *c = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) c[i].visits++;
        atomic_fetch_add(&probe->entities, it->count);
    }
}

Test(ecs_scheduler, a_parallel_system_visits_each_entity_once) {
    fixture f = fixture_make(2);
    enum { N = 10000, OTHERS = 1234, BATCH = 100 };
    static ecs_entity ids[N];
    /* Matching entities in two tables, and some that must not be visited. */
    ecs_entity_create_many(f.world, &(ecs_bulk_desc){ .count = N / 2, .components = { f.counter },
                                                      .ids = ids });
    ecs_entity_create_many(f.world, &(ecs_bulk_desc){ .count = N / 2,
                                                      .components = { f.counter, f.velocity },
                                                      .ids = ids + N / 2 });
    ecs_entity_create_many(f.world, &(ecs_bulk_desc){ .count = OTHERS, .components = { f.velocity } });
    parallel_probe probe = { .counter = f.counter };
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "visit", .phase = "lod", .fn = visit,
        .user = &probe, .query = { .with = { f.counter } }, .writes = { f.counter },
        .parallel = true, .batch_size = BATCH });
    ecs_progress(f.world, 0.016f);
    cr_expect_eq(atomic_load(&probe.calls), N / BATCH, "one call per batch");
    cr_expect_eq(atomic_load(&probe.entities), N);
    for (int i = 0; i < N; i++)
        cr_assert_eq(((Counter *)ecs_get(f.world, ids[i], f.counter))->visits, 1, "entity %d", i);
    fixture_free(&f);
}

typedef struct spawn_probe {
    ecs_component position;
    int seen_in_stream;
} spawn_probe;

static void spawn_one(ecs_iter *it) {
    spawn_probe *probe = it->user;
    ecs_entity e = ecs_defer_entity_create(it->commands);
    ecs_defer_set(it->commands, e, probe->position, &(Position){ 1, 2 });
}

static void see_spawned(ecs_iter *it) {
    spawn_probe *probe = it->user;
    while (ecs_query_next(it)) probe->seen_in_stream += it->count;
}

Test(ecs_scheduler, commands_apply_between_phases) {
    fixture f = fixture_make(2);
    spawn_probe probe = { .position = f.position };
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "spawn", .phase = "game", .fn = spawn_one, .user = &probe });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "see", .phase = "stream", .fn = see_spawned,
        .user = &probe, .query = { .with = { f.position } } });
    ecs_progress(f.world, 0.016f);
    cr_expect_eq(probe.seen_in_stream, 1, "game's entity exists by stream");
    ecs_progress(f.world, 0.016f);
    cr_expect_eq(probe.seen_in_stream, 1 + 2);
    cr_expect_eq(ecs_entity_count(f.world), 2);
    fixture_free(&f);
}

typedef struct dt_probe {
    float dt;
    void *user_seen;
} dt_probe;

static void read_dt(ecs_iter *it) {
    dt_probe *probe = it->user;
    probe->dt = it->dt;
    probe->user_seen = it->user;
    cr_expect_not_null(it->commands);
    cr_expect_eq(it->world != NULL, true);
}

Test(ecs_scheduler, systems_get_dt_user_and_commands) {
    fixture f = fixture_make(0);
    dt_probe probe = { 0 };
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "dt", .phase = "input", .fn = read_dt, .user = &probe });
    ecs_progress(f.world, 0.25f);
    cr_expect_float_eq(probe.dt, 0.25f, 0);
    cr_expect_eq(probe.user_seen, &probe);
    fixture_free(&f);
}

/* ---- traces ---------------------------------------------------------------------------- */

static size_t zone_count(const trace_report *report, const char *name) {
    for (size_t i = 0; i < report->zone_count; i++)
        if (strcmp(report->zones[i].name, name) == 0) return report->zones[i].count;
    return 0;
}

static void check_trace_zones(int threads) {
    char path[] = "/tmp/test_ecs_trace_XXXXXX";
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    close(fd);
    cr_assert(trace_start(path));
    fixture f = fixture_make(threads);
    ecs_entity_create_many(f.world, &(ecs_bulk_desc){ .count = 300, .components = { f.counter } });
    parallel_probe probe = { .counter = f.counter };
    ecs_phase_add(f.world, "physics", "game");
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "step_bodies", .phase = "physics", .fn = busy });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "visit_counters", .phase = "lod", .fn = visit,
        .user = &probe, .query = { .with = { f.counter } }, .writes = { f.counter },
        .parallel = true, .batch_size = 100 });
    for (int frame = 0; frame < 2; frame++) {
        trace_frame_begin();
        ecs_progress(f.world, 0.016f);
        trace_frame_end();
    }
    fixture_free(&f);
    trace_stop();

    trace_report report = { 0 };
    core_error error = { 0 };
    cr_assert(trace_report_load(path, &report, &error), "%s", error.message);
    const char *phases[] = { "input", "game", "physics", "stream", "generate", "stabilize", "mesh",
                             "lod", "cull", "draw", "background" };
    for (size_t i = 0; i < CORE_COUNTOF(phases); i++)
        cr_expect_eq(zone_count(&report, phases[i]), 2, "threads %d: phase %s", threads, phases[i]);
    cr_expect_eq(zone_count(&report, "step_bodies"), 2, "threads %d", threads);
    cr_expect_eq(zone_count(&report, "visit_counters"), 2 * 3, "threads %d: a zone per batch", threads);
    trace_report_free(&report);
    unlink(path);
}

Test(ecs_scheduler, phases_and_systems_are_trace_zones) {
    check_trace_zones(0);
    check_trace_zones(2);
}

/* ---- light phases on the calling thread ------------------------------------------------- */

static void note_thread(ecs_iter *it) {
    thread_probe *probe = it->user;
    probe->calls++;
    probe->off_main += job_thread_index(probe->jobs) != 0;
}

/* A phase whose systems took well under 20 us last frame runs on the calling thread (waking a
 * worker would cost more); a phase of heavy systems keeps running them at the same time, frame
 * after frame, not just in its first frame. */
Test(ecs_scheduler, light_phases_run_here_heavy_ones_on_jobs) {
    fixture f = fixture_make(2);
    thread_probe light[2] = { { .jobs = f.jobs }, { .jobs = f.jobs } };
    for (int i = 0; i < 2; i++)
        ecs_system_add(f.world, &(ecs_system_desc){ .name = "light", .phase = "input",
            .fn = note_thread, .user = &light[i], .query = { .with = { f.position } } });
    _Atomic int started_a = 0, started_b = 0;
    timed_system a = { .started = &started_a, .partner_started = &started_b };
    timed_system b = { .started = &started_b, .partner_started = &started_a };
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "a", .phase = "game", .fn = timed,
        .user = &a, .query = { .with = { f.position } }, .writes = { f.velocity } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "b", .phase = "game", .fn = timed,
        .user = &b, .query = { .with = { f.position } }, .writes = { f.counter } });
    int frames = 4;
    for (int frame = 0; frame < frames; frame++) {
        atomic_store(&started_a, 0);
        atomic_store(&started_b, 0);
        if (frame == 1) light[0].off_main = light[1].off_main = 0; /* the first frame may use jobs */
        ecs_progress(f.world, 0.016f);
    }
    cr_expect_eq(light[0].calls + light[1].calls, 2 * frames);
    cr_expect_eq(light[0].off_main + light[1].off_main, 0, "after the first frame, light systems run here");
    for (int frame = 0; frame < frames; frame++) {
        bool overlap = a.begin[frame] < b.end[frame] && b.begin[frame] < a.end[frame];
        cr_expect(overlap, "frame %d: heavy systems a and b ran one after the other", frame);
    }
    fixture_free(&f);
}

/* ---- programmer errors ------------------------------------------------------------------ */

#if !defined(TEST_WITHOUT_CRITERION) && !defined(NDEBUG)
static void create_directly(ecs_iter *it) { ecs_entity_create(it->world); }

Test(ecs_scheduler, structural_change_inside_a_phase_asserts, .signal = SIGABRT) {
    fixture f = fixture_make(0);
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "bad", .phase = "game", .fn = create_directly });
    ecs_progress(f.world, 0.016f);
}
#endif

/* ---- enabling and disabling ------------------------------------------------------------ */

static void count_calls(ecs_iter *it) { (*(int *)it->user)++; }

/* A disabled system is not called (parallel or not, with or without a query) until enabled
 * again; the systems beside it run as before. */
Test(ecs_scheduler, a_disabled_system_is_skipped_until_enabled) {
    fixture f = fixture_make(2);
    ecs_entity e = ecs_entity_create(f.world);
    ecs_set(f.world, e, f.position, &(Position){ 0, 0 });
    int a = 0, b = 0, c = 0;
    ecs_system sa = ecs_system_add(f.world, &(ecs_system_desc){ .name = "a", .phase = "game", .fn = count_calls,
                                                                 .user = &a, .query = { .with = { f.position } },
                                                                 .parallel = true });
    ecs_system sb = ecs_system_add(f.world, &(ecs_system_desc){ .name = "b", .phase = "game", .fn = count_calls,
                                                                 .user = &b });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "c", .phase = "game", .fn = count_calls, .user = &c,
                                                .writes = { f.position } });
    ecs_progress(f.world, 0.016f);
    ecs_system_enable(f.world, sa, false);
    ecs_system_enable(f.world, sb, false);
    ecs_progress(f.world, 0.016f);
    ecs_progress(f.world, 0.016f);
    ecs_system_enable(f.world, sa, true);
    ecs_progress(f.world, 0.016f);
    cr_expect_eq(a, 2, "a ran %d times", a);
    cr_expect_eq(b, 1, "b ran %d times", b);
    cr_expect_eq(c, 4, "c ran %d times", c);
    fixture_free(&f);
}
