/* Tests of ECS resources and access (engine/ecs, ecs.h RESOURCES and ACCESS): value and object
 * resources; resources in the conflict graph (two writers never overlap, readers do); a system
 * that declares nothing runs alone in its phase; in debug builds an access the running system
 * did not declare stops the program. Also meant to run under ThreadSanitizer. */
#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"

#include "test.h"
#include <signal.h>
#include <stdatomic.h>
#include <string.h>

typedef struct Clock { double seconds; int ticks; } Clock;
typedef struct Position { float x, y; } Position;
typedef struct Velocity { float x, y; } Velocity;

typedef struct fixture {
    job_system *jobs;
    ecs_world *world;
    ecs_component position, velocity, clock;
} fixture;

static fixture fixture_make(int threads) {
    fixture f = { .jobs = threads ? job_system_create(&(job_system_desc){ .threads = threads }) : NULL };
    f.world = ecs_world_create(&(ecs_world_desc){ .jobs = f.jobs });
    f.position = ECS_COMPONENT(f.world, Position);
    f.velocity = ECS_COMPONENT(f.world, Velocity);
    f.clock = ECS_RESOURCE(f.world, Clock);
    ecs_entity e = ecs_entity_create(f.world);
    ecs_set(f.world, e, f.position, &(Position){ 1, 2 });
    ecs_set(f.world, e, f.velocity, &(Velocity){ 3, 4 });
    return f;
}

static void fixture_free(fixture *f) {
    ecs_world_destroy(f->world);
    if (f->jobs) job_system_destroy(f->jobs);
}

/* ---- values and objects ----------------------------------------------------------------- */

Test(ecs_resources, a_value_resource_starts_zeroed_and_keeps_what_is_set) {
    fixture f = fixture_make(0);
    Clock *clock = ecs_resource_get(f.world, f.clock);
    cr_assert_not_null(clock);
    cr_expect_eq(clock->ticks, 0);
    cr_expect(clock->seconds == 0.0);
    ecs_resource_set(f.world, f.clock, &(Clock){ .seconds = 2.5, .ticks = 7 });
    cr_expect_eq(((Clock *)ecs_resource_get(f.world, f.clock))->ticks, 7);
    cr_expect(((Clock *)ecs_resource_get(f.world, f.clock))->seconds == 2.5);
    cr_expect_eq(ECS_RESOURCE(f.world, Clock), f.clock, "registering again: the same resource");
    cr_expect(ecs_is_resource(f.world, f.clock));
    cr_expect(!ecs_is_resource(f.world, f.position));
    fixture_free(&f);
}

Test(ecs_resources, an_object_resource_is_the_callers_object) {
    fixture f = fixture_make(0);
    int first = 1, second = 2;
    ecs_component r = ecs_resource_register(f.world, &(ecs_resource_desc){ .name = "thing", .object = &first });
    cr_expect_eq(ecs_resource_get(f.world, r), &first);
    cr_expect_eq(ecs_resource_register(f.world, &(ecs_resource_desc){ .name = "thing", .object = &second }), r);
    cr_expect_eq(ecs_resource_get(f.world, r), &second, "registering again points it at the new object");
    fixture_free(&f);
}

/* ---- the conflict graph ----------------------------------------------------------------- */

typedef struct probe {
    _Atomic int *inside;             /* systems of the test inside their function now */
    _Atomic int *most;               /* the most seen inside at once */
    _Atomic int *entered;            /* systems that have started this frame */
    int partners;                    /* wait (≤ 300 ms) until this many have started */
    ecs_component resource;          /* touched through ecs_resource_get */
} probe;

/* Enters, waits for its partners (systems that may overlap then do, even on a busy machine), or
 * 3 ms when it has none, and notes how many were inside at once. */
static void probed(ecs_iter *it) {
    probe *p = it->user;
    if (p->resource) ecs_resource_get(it->world, p->resource);
    int now = atomic_fetch_add(p->inside, 1) + 1;
    atomic_fetch_add(p->entered, 1);
    uint64_t begin = core_time_ns();
    while (core_time_ns() - begin < (p->partners ? 300000000ull : 3000000ull)) {
        int seen = atomic_load(p->inside);
        if (seen > now) now = seen;
        if (p->partners && atomic_load(p->entered) >= p->partners) break;
    }
    int most = atomic_load(p->most);
    while (now > most && !atomic_compare_exchange_weak(p->most, &most, now)) {}
    atomic_fetch_sub(p->inside, 1);
}

static int most_inside_over_frames(fixture *f, _Atomic int *inside, _Atomic int *most, _Atomic int *entered) {
    for (int frame = 0; frame < 6; frame++) {
        atomic_store(entered, 0);
        ecs_progress(f->world, 0.016f);
    }
    (void)inside;
    return atomic_load(most);
}

Test(ecs_resources, two_writers_of_a_resource_never_overlap) {
    fixture f = fixture_make(2);
    _Atomic int inside = 0, most = 0, entered = 0;
    probe p = { &inside, &most, &entered, .resource = f.clock };
    for (int i = 0; i < 2; i++)
        ecs_system_add(f.world, &(ecs_system_desc){ .name = i ? "b" : "a", .phase = "game", .fn = probed,
                                                     .user = &p, .writes = { f.clock } });
    cr_expect_eq(most_inside_over_frames(&f, &inside, &most, &entered), 1);
    fixture_free(&f);
}

Test(ecs_resources, readers_of_a_resource_overlap) {
    fixture f = fixture_make(2);
    _Atomic int inside = 0, most = 0, entered = 0;
    probe p = { &inside, &most, &entered, .partners = 2, .resource = f.clock };
    for (int i = 0; i < 2; i++)
        ecs_system_add(f.world, &(ecs_system_desc){ .name = i ? "b" : "a", .phase = "game", .fn = probed,
                                                     .user = &p, .reads = { f.clock } });
    cr_expect_eq(most_inside_over_frames(&f, &inside, &most, &entered), 2);
    fixture_free(&f);
}

/* The control for the exclusive test below: the same two systems overlap once the first
 * declares what it touches. */
Test(ecs_resources, a_system_that_declares_what_it_touches_runs_beside_others) {
    fixture f = fixture_make(2);
    _Atomic int inside = 0, most = 0, entered = 0;
    probe p = { &inside, &most, &entered, .partners = 2 };
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "declares", .phase = "game", .fn = probed,
                                                 .user = &p, .reads = { f.clock } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "mover", .phase = "game", .fn = probed,
                                                 .user = &p, .query = { .with = { f.position } },
                                                 .writes = { f.position } });
    cr_expect_eq(most_inside_over_frames(&f, &inside, &most, &entered), 2);
    fixture_free(&f);
}

Test(ecs_resources, a_system_that_declares_nothing_runs_alone_in_its_phase) {
    fixture f = fixture_make(2);
    _Atomic int inside = 0, most = 0, entered = 0;
    probe p = { &inside, &most, &entered, .partners = 2 };
    /* Neither earlier nor later systems of the phase share its time. */
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "before", .phase = "game", .fn = probed,
                                                 .user = &p, .reads = { f.clock } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "undeclared", .phase = "game", .fn = probed, .user = &p });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "after", .phase = "game", .fn = probed,
                                                 .user = &p, .query = { .with = { f.position } },
                                                 .writes = { f.position } });
    cr_expect_eq(most_inside_over_frames(&f, &inside, &most, &entered), 1);
    fixture_free(&f);
}

/* ---- access checks (debug builds) ------------------------------------------------------- */

typedef struct access_probe {
    fixture *f;
    ecs_entity entity;
    int calls;
} access_probe;

static void get_velocity(ecs_iter *it) {
    access_probe *a = it->user;
    while (ecs_query_next(it)) {}
    cr_expect_not_null(ecs_get(it->world, a->entity, a->f->velocity));
    a->calls++;
}

static void set_velocity(ecs_iter *it) {
    access_probe *a = it->user;
    ecs_set(it->world, a->entity, a->f->velocity, &(Velocity){ 5, 6 });
    a->calls++;
}

static void get_clock(ecs_iter *it) {
    access_probe *a = it->user;
    cr_expect_not_null(ecs_resource_get(it->world, a->f->clock));
    a->calls++;
}

static access_probe access_fixture(fixture *f) {
    access_probe a = { .f = f };
    ecs_iter it = ecs_query_iter(f->world, ecs_query_create(f->world, &(ecs_query_desc){ .with = { f->position } }));
    while (ecs_query_next(&it)) a.entity = it.entities[0];
    return a;
}

/* What a system declares it may do: these run to the end. */
Test(ecs_resources, declared_accesses_pass_the_checks) {
    fixture f = fixture_make(0);
    access_probe a = access_fixture(&f);
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "reader", .phase = "game", .fn = get_velocity,
                                                 .user = &a, .query = { .with = { f.position } },
                                                 .reads = { f.velocity } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "writer", .phase = "game", .fn = set_velocity,
                                                 .user = &a, .writes = { f.velocity } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "clock", .phase = "game", .fn = get_clock,
                                                 .user = &a, .reads = { f.clock } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "anything", .phase = "game", .fn = get_clock,
                                                 .user = &a });   /* declares nothing: exclusive */
    ecs_progress(f.world, 0.016f);
    cr_expect_eq(a.calls, 4);
    cr_expect(((Velocity *)ecs_get(f.world, a.entity, f.velocity))->x == 5.0f);
    fixture_free(&f);
}

#if !defined(TEST_WITHOUT_CRITERION) && !defined(NDEBUG)
Test(ecs_resources, ecs_get_of_an_undeclared_component_stops, .signal = SIGABRT) {
    fixture f = fixture_make(0);
    access_probe a = access_fixture(&f);
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "sneaky", .phase = "game", .fn = get_velocity,
                                                 .user = &a, .query = { .with = { f.position } } });
    ecs_progress(f.world, 0.016f);
}

Test(ecs_resources, ecs_set_of_a_component_only_read_stops, .signal = SIGABRT) {
    fixture f = fixture_make(0);
    access_probe a = access_fixture(&f);
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "sneaky", .phase = "game", .fn = set_velocity,
                                                 .user = &a, .reads = { f.velocity } });
    ecs_progress(f.world, 0.016f);
}

Test(ecs_resources, an_undeclared_resource_stops, .signal = SIGABRT) {
    fixture f = fixture_make(2);
    access_probe a = access_fixture(&f);
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "sneaky", .phase = "game", .fn = get_clock,
                                                 .user = &a, .reads = { f.position } });
    ecs_progress(f.world, 0.016f);
}

static void iterate_other_query(ecs_iter *it) {
    ecs_query *velocities = it->user;
    ecs_iter other = ecs_query_iter(it->world, velocities);
    while (ecs_query_next(&other)) {}
}

Test(ecs_resources, iterating_an_undeclared_query_stops, .signal = SIGABRT) {
    fixture f = fixture_make(0);
    ecs_query *velocities = ecs_query_create(f.world, &(ecs_query_desc){ .with = { f.velocity } });
    ecs_system_add(f.world, &(ecs_system_desc){ .name = "sneaky", .phase = "game", .fn = iterate_other_query,
                                                 .user = velocities, .reads = { f.position } });
    ecs_progress(f.world, 0.016f);
}

Test(ecs_resources, a_resource_on_an_entity_asserts, .signal = SIGABRT) {
    fixture f = fixture_make(0);
    ecs_add(f.world, ecs_entity_create(f.world), f.clock);
}
#endif
