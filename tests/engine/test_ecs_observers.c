/* Tests of ECS observers (engine/ecs): an observer is called once each time an entity starts
 * (ECS_ON_ADD) or stops (ECS_ON_REMOVE) matching its query, whatever made it so — add, remove,
 * destroy, create_many, a command buffer, a system's commands, ecs_world_destroy — and never
 * for a move between two tables that both match or both do not. Also the world's table-move
 * count (ecs_world_stats_info, and the ecs.table_moves trace counter).
 * Also meant to run under ThreadSanitizer (one test uses a 2-thread job system). */
#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include "test.h"
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct A { int value; } A;
typedef struct B { int value; } B;
typedef struct C { int value; } C;
typedef struct D { int value; } D;

enum { SEEN_CAPACITY = 64 };

/* What an observer saw, call by call. */
typedef struct seen {
    ecs_component a, b;              /* components it checks are readable in the call */
    int adds, removes;
    ecs_entity entities[SEEN_CAPACITY];
    ecs_event events[SEEN_CAPACITY];
    bool readable[SEEN_CAPACITY];    /* alive, and ecs_get gave A and B */
    int thread_max;
} seen;

static void observe(ecs_world *world, ecs_entity entity, ecs_event event, void *user) {
    seen *s = user;
    int i = s->adds + s->removes;
    if (event == ECS_ON_ADD) s->adds++;
    else s->removes++;
    if (i >= SEEN_CAPACITY) return;
    s->entities[i] = entity;
    s->events[i] = event;
    s->readable[i] = ecs_is_alive(world, entity) && ecs_get(world, entity, s->a) &&
                     ecs_get(world, entity, s->b);
    job_system *jobs = ecs_world_jobs(world);
    int thread = jobs ? job_thread_index(jobs) : 0;
    if (thread > s->thread_max) s->thread_max = thread;
}

typedef struct fixture {
    job_system *jobs;
    ecs_world *world;
    ecs_component a, b, c, d;
    seen seen;                       /* of the {A, B} without {C} observer */
    ecs_observer observer;
} fixture;

static fixture *fixture_make(int threads) {
    fixture *f = calloc(1, sizeof *f);
    if (threads) f->jobs = job_system_create(&(job_system_desc){ .threads = threads });
    f->world = ecs_world_create(&(ecs_world_desc){ .jobs = f->jobs });
    f->a = ECS_COMPONENT(f->world, A);
    f->b = ECS_COMPONENT(f->world, B);
    f->c = ECS_COMPONENT(f->world, C);
    f->d = ECS_COMPONENT(f->world, D);
    f->seen = (seen){ .a = f->a, .b = f->b };
    f->observer = ecs_observer_add(f->world, &(ecs_observer_desc){ .name = "ab_not_c",
        .query = { .with = { f->a, f->b }, .without = { f->c } }, .fn = observe,
        .user = &f->seen });
    return f;
}

static void fixture_destroy_world(fixture *f) {
    ecs_world_destroy(f->world);
    f->world = NULL;
    if (f->jobs) job_system_destroy(f->jobs);
    f->jobs = NULL;
}

/* ---- direct calls ----------------------------------------------------------------------- */

Test(ecs_observers, start_and_stop_matching) {
    fixture *f = fixture_make(0);
    ecs_entity e = ecs_entity_create(f->world);
    ecs_add(f->world, e, f->a);
    cr_expect_eq(f->seen.adds + f->seen.removes, 0, "A alone does not match");
    ecs_add(f->world, e, f->b);
    cr_expect_eq(f->seen.adds, 1, "A and B match");
    ecs_add(f->world, e, f->c);
    cr_expect_eq(f->seen.removes, 1, "C excludes it");
    ecs_remove(f->world, e, f->c);
    cr_expect_eq(f->seen.adds, 2, "without C it matches again");
    ecs_entity_destroy(f->world, e);
    cr_expect_eq(f->seen.removes, 2, "destroyed");
    cr_assert_eq(f->seen.adds + f->seen.removes, 4);
    ecs_event expected[4] = { ECS_ON_ADD, ECS_ON_REMOVE, ECS_ON_ADD, ECS_ON_REMOVE };
    for (int i = 0; i < 4; i++) {
        cr_expect_eq(f->seen.events[i], expected[i], "call %d", i);
        cr_expect_eq(f->seen.entities[i], e, "call %d", i);
        cr_expect(f->seen.readable[i], "call %d: the entity has A and B during the call", i);
    }
    fixture_destroy_world(f);
    cr_expect_eq(f->seen.adds + f->seen.removes, 4, "nothing left for the world's end");
    free(f);
}

Test(ecs_observers, moves_between_matching_tables_are_silent) {
    fixture *f = fixture_make(0);
    ecs_entity e = ecs_entity_create(f->world);
    ecs_add(f->world, e, f->a);
    ecs_add(f->world, e, f->b);
    ecs_set(f->world, e, f->d, &(D){ 1 });   /* {A, B} → {A, B, D}: both match */
    ecs_remove(f->world, e, f->d);
    ecs_set(f->world, e, f->a, &(A){ 2 });   /* a write, no move */
    cr_expect_eq(f->seen.adds, 1);
    cr_expect_eq(f->seen.removes, 0);
    ecs_entity other = ecs_entity_create(f->world);
    ecs_add(f->world, other, f->c);
    ecs_add(f->world, other, f->a);
    ecs_add(f->world, other, f->b);          /* has C: never matches */
    ecs_remove(f->world, other, f->a);
    cr_expect_eq(f->seen.adds, 1);
    cr_expect_eq(f->seen.removes, 0);
    fixture_destroy_world(f);
    cr_expect_eq(f->seen.removes, 1, "e goes with the world");
    cr_expect_eq(f->seen.entities[1], e);
    cr_expect(f->seen.readable[1], "the world is whole while its observers run");
    free(f);
}

Test(ecs_observers, event_filter) {
    fixture *f = fixture_make(0);
    seen adds = { .a = f->a, .b = f->a }, removes = { .a = f->a, .b = f->a };
    ecs_observer_add(f->world, &(ecs_observer_desc){ .query = { .with = { f->a } },
        .events = ECS_ON_ADD, .fn = observe, .user = &adds });
    ecs_observer_add(f->world, &(ecs_observer_desc){ .query = { .with = { f->a } },
        .events = ECS_ON_REMOVE, .fn = observe, .user = &removes });
    ecs_entity e = ecs_entity_create(f->world);
    for (int i = 0; i < 3; i++) {
        ecs_add(f->world, e, f->a);
        ecs_remove(f->world, e, f->a);
    }
    cr_expect_eq(adds.adds, 3);
    cr_expect_eq(adds.removes, 0);
    cr_expect_eq(removes.adds, 0);
    cr_expect_eq(removes.removes, 3);
    fixture_destroy_world(f);
    free(f);
}

Test(ecs_observers, added_after_the_tables_and_removed) {
    fixture *f = fixture_make(0);
    ecs_entity e = ecs_entity_create(f->world);
    ecs_add(f->world, e, f->a);
    ecs_add(f->world, e, f->d);              /* table {A, D} exists before the observer */
    seen late = { .a = f->a, .b = f->d };
    ecs_observer late_id = ecs_observer_add(f->world, &(ecs_observer_desc){
        .query = { .with = { f->a, f->d } }, .fn = observe, .user = &late });
    cr_expect_eq(late.adds, 0, "adding an observer reports nothing for entities already there");
    ecs_remove(f->world, e, f->d);
    ecs_add(f->world, e, f->d);
    cr_expect_eq(late.removes, 1);
    cr_expect_eq(late.adds, 1);
    cr_expect_eq(ecs_world_stats(f->world).observers, 2);
    ecs_observer_remove(f->world, late_id);
    cr_expect_eq(ecs_world_stats(f->world).observers, 1);
    ecs_remove(f->world, e, f->d);
    ecs_entity_destroy(f->world, e);
    cr_expect_eq(late.removes + late.adds, 2, "no calls once removed");
    ecs_observer_remove(f->world, f->observer);
    ecs_entity g = ecs_entity_create(f->world);
    ecs_add(f->world, g, f->a);
    ecs_add(f->world, g, f->b);
    cr_expect_eq(f->seen.adds, 0);
    fixture_destroy_world(f);
    cr_expect_eq(f->seen.removes, 0);
    free(f);
}

/* ---- the order of hooks and observers --------------------------------------------------- */

typedef struct order_log {
    char steps[16][12];
    int count;
} order_log;

static order_log *order;

static void order_note(const char *step) {
    if (order->count < 16) snprintf(order->steps[order->count++], 12, "%s", step);
}
static void order_observer(ecs_world *w, ecs_entity e, ecs_event event, void *user) {
    (void)w, (void)e, (void)user;
    order_note(event == ECS_ON_ADD ? "obs_add" : "obs_remove");
}
static void order_on_add(ecs_world *w, ecs_entity e, void *d, void *u) {
    (void)w, (void)e, (void)d, (void)u;
    order_note("on_add");
}
static void order_on_remove(ecs_world *w, ecs_entity e, void *d, void *u) {
    (void)w, (void)e, (void)d, (void)u;
    order_note("on_remove");
}
static void order_ctor(void *d, int n, void *u) {
    (void)u;
    memset(d, 0, (size_t)n * sizeof(B));
    order_note("ctor");
}
static void order_dtor(void *d, int n, void *u) {
    (void)d, (void)n, (void)u;
    order_note("dtor");
}

/* Observers nest around the hooks: ctor, on_add, ON_ADD; ON_REMOVE, on_remove, dtor. */
Test(ecs_observers, nest_around_hooks) {
    fixture *f = fixture_make(0);
    order_log log = { 0 };
    order = &log;
    ecs_component_set_hooks(f->world, f->b, &(ecs_hooks){ .ctor = order_ctor,
        .dtor = order_dtor, .on_add = order_on_add, .on_remove = order_on_remove });
    ecs_observer_add(f->world, &(ecs_observer_desc){ .query = { .with = { f->b } },
        .fn = order_observer });
    ecs_entity e = ecs_entity_create(f->world);
    ecs_add(f->world, e, f->b);
    ecs_remove(f->world, e, f->b);
    const char *expected[] = { "ctor", "on_add", "obs_add", "obs_remove", "on_remove", "dtor" };
    cr_assert_eq(log.count, 6);
    for (int i = 0; i < 6; i++) cr_expect_str_eq(log.steps[i], expected[i], "step %d", i);
    fixture_destroy_world(f);
    order = NULL;
    free(f);
}

/* ---- bulk, commands, systems, the world's end ------------------------------------------- */

Test(ecs_observers, create_many_and_world_destroy) {
    fixture *f = fixture_make(0);
    ecs_entity ids[6];
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 6, .ids = ids,
        .components = { f->b, f->a } });
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 4,
        .components = { f->b, f->a, f->c } });       /* excluded by C */
    cr_expect_eq(f->seen.adds, 6);
    bool readable = true;
    for (int i = 0; i < 6; i++) readable = readable && f->seen.readable[i];
    cr_expect(readable, "ON_ADD finds the new entities whole");
    cr_expect_eq(f->seen.entities[5], ids[5]);
    ecs_entity_destroy(f->world, ids[2]);
    fixture_destroy_world(f);
    cr_expect_eq(f->seen.removes, 6, "one destroyed, five with the world");
    free(f);
}

Test(ecs_observers, command_buffer) {
    fixture *f = fixture_make(0);
    ecs_entity e = ecs_entity_create(f->world);
    ecs_commands *commands = ecs_commands_create(f->world);
    ecs_entity p = ecs_defer_entity_create(commands);
    ecs_defer_set(commands, p, f->a, &(A){ 1 });
    ecs_defer_add(commands, p, f->b);        /* p matches */
    ecs_defer_add(commands, e, f->a);
    ecs_defer_add(commands, e, f->b);        /* e matches */
    ecs_defer_add(commands, e, f->c);        /* e stops */
    ecs_defer_entity_destroy(commands, p);          /* p stops */
    cr_expect_eq(f->seen.adds + f->seen.removes, 0, "nothing before apply");
    ecs_commands_apply(commands);
    cr_expect_eq(f->seen.adds, 2);
    cr_expect_eq(f->seen.removes, 2);
    ecs_commands_destroy(commands);
    fixture_destroy_world(f);
    cr_expect_eq(f->seen.removes, 2);
    free(f);
}

/* Adds B to entities with A that lack it, removes it from those that have it. */
static void toggle_b(ecs_iter *it) {
    const ecs_component *b = it->user;
    while (ecs_query_next(it))
        for (int i = 0; i < it->count; i++) {
            if (ecs_has(it->world, it->entities[i], *b))
                ecs_defer_remove(it->commands, it->entities[i], *b);
            else
                ecs_defer_add(it->commands, it->entities[i], *b);
        }
}

static void check_system_commands(int threads) {
    fixture *f = fixture_make(threads);
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 10, .components = { f->a } });
    ecs_system_add(f->world, &(ecs_system_desc){ .name = "toggle_b", .phase = "game",
        .query = { .with = { f->a } }, .fn = toggle_b, .user = &f->b, .parallel = true,
        .batch_size = 3 });
    ecs_progress(f->world, 0.016f);
    cr_expect_eq(f->seen.adds, 10, "threads %d", threads);
    ecs_progress(f->world, 0.016f);
    cr_expect_eq(f->seen.removes, 10, "threads %d", threads);
    ecs_progress(f->world, 0.016f);
    cr_expect_eq(f->seen.adds, 20, "threads %d", threads);
    cr_expect_eq(f->seen.thread_max, 0, "threads %d: observers run on the progress thread",
                 threads);
    /* 10 entities moved each frame, plus none at creation (bulk). */
    cr_expect_eq(ecs_world_stats(f->world).table_moves, 30u, "threads %d", threads);
    fixture_destroy_world(f);
    cr_expect_eq(f->seen.removes, 20, "threads %d", threads);
    free(f);
}

Test(ecs_observers, system_commands_on_the_progress_thread) {
    check_system_commands(0);
    check_system_commands(2);
}

/* ---- table moves and stats -------------------------------------------------------------- */

Test(ecs_world_stats_info, counts_table_moves_and_the_world) {
    fixture *f = fixture_make(0);
    ecs_world_stats_info st = ecs_world_stats(f->world);
    cr_expect_eq(st.table_moves, 0u);
    cr_expect_eq(st.entities, 0);
    cr_expect_eq(st.tables, 1, "the empty table");
    cr_expect_eq(st.components, 4);
    ecs_entity e = ecs_entity_create(f->world);  /* into the empty table: no move */
    ecs_add(f->world, e, f->a);                  /* 1 */
    ecs_set(f->world, e, f->b, &(B){ 2 });       /* 2 */
    ecs_set(f->world, e, f->b, &(B){ 3 });       /* a write */
    ecs_add(f->world, e, f->a);                  /* has it */
    ecs_remove(f->world, e, f->c);               /* lacks it */
    ecs_remove(f->world, e, f->a);               /* 3 */
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 5, .components = { f->d } });
    ecs_entity_destroy(f->world, e);             /* leaves, moves to no table */
    ecs_system_add(f->world, &(ecs_system_desc){ .name = "noop", .phase = "game",
        .fn = toggle_b, .query = { .with = { f->c } }, .user = &f->b });
    st = ecs_world_stats(f->world);
    cr_expect_eq(st.table_moves, 3u);
    cr_expect_eq(st.entities, 5);
    /* {}, {A}, {A, B}, {B}, {D} */
    cr_expect_eq(st.tables, 5);
    cr_expect_eq(st.systems, 1);
    cr_expect_eq(st.queries, 1, "the system's");
    cr_expect_eq(st.observers, 1);
    fixture_destroy_world(f);
    free(f);
}

Test(ecs_world_stats_info, table_moves_is_a_trace_counter_per_frame) {
    char path[] = "/tmp/test_ecs_moves_XXXXXX";
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    close(fd);
    cr_assert(trace_start(path));
    fixture *f = fixture_make(0);
    ecs_entity e[3];
    for (int i = 0; i < 3; i++) e[i] = ecs_entity_create(f->world);
    /* Frame 1: three moves before ecs_progress; frame 2: none; frame 3: one. */
    for (int i = 0; i < 3; i++) ecs_add(f->world, e[i], f->a);
    ecs_progress(f->world, 0.016f);
    ecs_progress(f->world, 0.016f);
    ecs_remove(f->world, e[0], f->a);
    ecs_progress(f->world, 0.016f);
    fixture_destroy_world(f);
    free(f);
    trace_stop();

    trace_report report = { 0 };
    core_error error = { 0 };
    cr_assert(trace_report_load(path, &report, &error), "%s", error.message);
    const trace_counter_stats *moves = NULL;
    for (size_t i = 0; i < report.counter_series_count; i++)
        if (strcmp(report.counters[i].name, "ecs.table_moves") == 0) moves = &report.counters[i];
    cr_assert_not_null(moves);
    cr_expect_eq(moves->count, 3u, "one sample a frame");
    cr_expect_float_eq(moves->max, 3.0, 1e-9);
    cr_expect_float_eq(moves->min, 0.0, 1e-9);
    cr_expect_float_eq(moves->last, 1.0, 1e-9);
    cr_expect_float_eq(moves->mean, 4.0 / 3.0, 1e-9);
    trace_report_free(&report);
    unlink(path);
}

/* ---- programmer errors ------------------------------------------------------------------ */

#if !defined(TEST_WITHOUT_CRITERION) && !defined(NDEBUG)
static void add_in_observer(ecs_world *world, ecs_entity entity, ecs_event event, void *user) {
    (void)event;
    ecs_add(world, entity, *(ecs_component *)user);
}

Test(ecs_observers, structural_change_inside_an_observer_asserts, .signal = SIGABRT) {
    fixture *f = fixture_make(0);
    ecs_observer_add(f->world, &(ecs_observer_desc){ .query = { .with = { f->a } },
        .fn = add_in_observer, .user = &f->d });
    ecs_add(f->world, ecs_entity_create(f->world), f->a);
}
#endif
