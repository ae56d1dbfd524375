/* Tests of ECS component lifecycle hooks (engine/ecs): on_remove runs once, with the current
 * value, whatever takes a component away — ecs_remove, ecs_entity_destroy, a command buffer,
 * a system's commands during ecs_progress, ecs_world_destroy — and never for ecs_set. ctor,
 * dtor, move, on_add and on_set run once per event on every path (counts worked out by hand),
 * and a component owning heap memory neither leaks nor frees twice under ASan.
 * Also meant to run under ThreadSanitizer (one test uses a 2-thread job system). */
#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"

#include "test.h"
#include <signal.h>
#include <stdlib.h>
#include <string.h>

typedef struct Mesh { int buffer; } Mesh;    /* stands in for a component owning a GPU buffer */
typedef struct Position { float x, y; } Position;

enum { LOG_CAPACITY = 32 };

/* What a hook saw, call by call. */
typedef struct hook_log {
    ecs_component component;         /* the hooked component, for ecs_get inside the hook */
    int calls;
    ecs_entity entities[LOG_CAPACITY];
    int buffers[LOG_CAPACITY];       /* Mesh.buffer at the call; -1 when data was NULL */
    bool data_null[LOG_CAPACITY];
    bool consistent[LOG_CAPACITY];   /* alive, and ecs_get gave the same data */
    int thread[LOG_CAPACITY];        /* job_thread_index, when the world has a job system */
} hook_log;

static void log_call(ecs_world *world, ecs_entity entity, void *data, void *user) {
    hook_log *log = user;
    int i = log->calls++;
    if (i >= LOG_CAPACITY) return;
    log->entities[i] = entity;
    log->buffers[i] = data ? ((Mesh *)data)->buffer : -1;
    log->data_null[i] = data == NULL;
    log->consistent[i] = ecs_is_alive(world, entity) && ecs_has(world, entity, log->component) &&
                         ecs_get(world, entity, log->component) == data;
    job_system *jobs = ecs_world_jobs(world);
    log->thread[i] = jobs ? job_thread_index(jobs) : 0;
}

typedef struct fixture {
    job_system *jobs;
    ecs_world *world;
    ecs_component mesh, position, frozen;
    hook_log log;                    /* of the Mesh hook */
} fixture;

/* Heap-allocated, so the log outlives ecs_world_destroy and keeps its address. */
static fixture *fixture_make(int threads) {
    fixture *f = calloc(1, sizeof *f);
    if (threads) f->jobs = job_system_create(&(job_system_desc){ .threads = threads });
    f->world = ecs_world_create(&(ecs_world_desc){ .jobs = f->jobs });
    f->mesh = ECS_COMPONENT(f->world, Mesh);
    f->position = ECS_COMPONENT(f->world, Position);
    f->frozen = ECS_TAG(f->world, Frozen);
    f->log.component = f->mesh;
    ecs_component_on_remove(f->world, f->mesh, log_call, &f->log);
    return f;
}

static ecs_entity spawn_mesh(fixture *f, int buffer) {
    ecs_entity e = ecs_entity_create(f->world);
    ecs_set(f->world, e, f->mesh, &(Mesh){ buffer });
    return e;
}

/* Destroys the world (running its hooks) but keeps the log for the test to read. */
static void fixture_destroy_world(fixture *f) {
    ecs_world_destroy(f->world);
    f->world = NULL;
    if (f->jobs) job_system_destroy(f->jobs);
    f->jobs = NULL;
}

static void fixture_free(fixture *f) {
    fixture_destroy_world(f);
    free(f);
}

/* ---- ecs_remove, ecs_entity_destroy, ecs_set -------------------------------------------- */

Test(ecs_hooks, remove_calls_hook_once_with_current_value) {
    fixture *f = fixture_make(0);
    ecs_entity e = spawn_mesh(f, 7);
    ecs_set(f->world, e, f->position, &(Position){ 1, 2 });
    ecs_set(f->world, e, f->mesh, &(Mesh){ 9 });
    cr_expect_eq(f->log.calls, 0, "adding and overwriting remove nothing");

    ecs_remove(f->world, e, f->mesh);
    cr_assert_eq(f->log.calls, 1);
    cr_expect_eq(f->log.entities[0], e);
    cr_expect_eq(f->log.buffers[0], 9, "the value as last set, not the first one");
    cr_expect(f->log.consistent[0], "during the hook the entity still has the component");
    cr_expect_not(ecs_has(f->world, e, f->mesh));
    cr_expect(ecs_is_alive(f->world, e), "remove leaves the entity alive");

    ecs_remove(f->world, e, f->mesh);
    ecs_remove(f->world, e, f->position);
    cr_expect_eq(f->log.calls, 1, "a second remove, or removing another component, calls nothing");
    fixture_destroy_world(f);
    cr_expect_eq(f->log.calls, 1, "e no longer has Mesh when the world goes");
    free(f);
}

Test(ecs_hooks, entity_destroy_calls_hook_once) {
    fixture *f = fixture_make(0);
    ecs_entity a = spawn_mesh(f, 1), b = spawn_mesh(f, 2);
    ecs_entity_destroy(f->world, a);
    cr_assert_eq(f->log.calls, 1);
    cr_expect_eq(f->log.entities[0], a);
    cr_expect_eq(f->log.buffers[0], 1);
    cr_expect(f->log.consistent[0], "a is still whole during its hook");
    cr_expect_not(ecs_is_alive(f->world, a));

    ecs_entity_destroy(f->world, a);
    cr_expect_eq(f->log.calls, 1, "destroying a dead id calls nothing");
    /* b took a's row when a went; its value must have come along. */
    cr_expect_eq(((Mesh *)ecs_get(f->world, b, f->mesh))->buffer, 2);
    ecs_entity_destroy(f->world, b);
    cr_assert_eq(f->log.calls, 2);
    cr_expect_eq(f->log.entities[1], b);
    cr_expect_eq(f->log.buffers[1], 2);
    fixture_destroy_world(f);
    cr_expect_eq(f->log.calls, 2, "nothing left for the world to release");
    free(f);
}

Test(ecs_hooks, set_overwrite_does_not_call_hook) {
    fixture *f = fixture_make(0);
    ecs_entity e = spawn_mesh(f, 1);
    for (int i = 2; i <= 5; i++) ecs_set(f->world, e, f->mesh, &(Mesh){ i });
    ecs_add(f->world, e, f->mesh);
    cr_expect_eq(f->log.calls, 0, "overwriting and re-adding keep the component");
    cr_expect_eq(((Mesh *)ecs_get(f->world, e, f->mesh))->buffer, 5);
    fixture_destroy_world(f);
    cr_assert_eq(f->log.calls, 1, "released once, when the world goes");
    cr_expect_eq(f->log.buffers[0], 5);
    free(f);
}

Test(ecs_hooks, not_called_for_entities_without_the_component) {
    fixture *f = fixture_make(0);
    ecs_entity plain = ecs_entity_create(f->world);
    ecs_entity placed = ecs_entity_create(f->world);
    ecs_set(f->world, placed, f->position, &(Position){ 3, 4 });
    ecs_add(f->world, placed, f->frozen);
    ecs_remove(f->world, placed, f->mesh);
    ecs_remove(f->world, placed, f->position);
    ecs_entity_destroy(f->world, plain);
    ecs_entity_destroy(f->world, placed);
    ecs_remove(f->world, placed, f->mesh);
    cr_expect_eq(f->log.calls, 0);
    ecs_entity_create(f->world); /* left for the world to destroy */
    fixture_destroy_world(f);
    cr_expect_eq(f->log.calls, 0);
    free(f);
}

/* ---- command buffers -------------------------------------------------------------------- */

Test(ecs_hooks, deferred_destroy_and_remove_call_hook_at_apply) {
    fixture *f = fixture_make(0);
    ecs_entity a = spawn_mesh(f, 10), b = spawn_mesh(f, 20), c = spawn_mesh(f, 30);
    ecs_commands *commands = ecs_commands_create(f->world);
    ecs_defer_entity_destroy(commands, b);
    ecs_defer_remove(commands, a, f->mesh);
    ecs_defer_entity_destroy(commands, b);          /* b is dead by then: skipped */
    ecs_defer_set(commands, c, f->mesh, &(Mesh){ 31 });
    cr_expect_eq(f->log.calls, 0, "nothing happens before apply");

    ecs_commands_apply(commands);
    cr_assert_eq(f->log.calls, 2, "b destroyed once, a's Mesh removed, c's only overwritten");
    cr_expect_eq(f->log.entities[0], b, "in recording order");
    cr_expect_eq(f->log.buffers[0], 20);
    cr_expect_eq(f->log.entities[1], a);
    cr_expect_eq(f->log.buffers[1], 10);
    cr_expect(f->log.consistent[0] && f->log.consistent[1]);
    ecs_commands_destroy(commands);
    fixture_destroy_world(f);
    cr_assert_eq(f->log.calls, 3);
    cr_expect_eq(f->log.entities[2], c);
    cr_expect_eq(f->log.buffers[2], 31);
    free(f);
}

/* Destroys, through its commands, every entity whose buffer is odd. */
static void destroy_odd(ecs_iter *it) {
    while (ecs_query_next(it)) {
        const Mesh *m = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++)
            if (m[i].buffer % 2) ecs_defer_entity_destroy(it->commands, it->entities[i]);
    }
}

static void check_progress_destroys(int threads) {
    fixture *f = fixture_make(threads);
    ecs_entity e[6];
    for (int i = 0; i < 6; i++) e[i] = spawn_mesh(f, i + 1);
    /* Batches of one: on two threads the system's jobs run on the worker too. */
    ecs_system_add(f->world, &(ecs_system_desc){ .name = "destroy_odd", .phase = "game",
        .fn = destroy_odd, .query = { .with = { f->mesh } }, .parallel = true, .batch_size = 1 });
    ecs_progress(f->world, 0.016f);

    /* Buffers 1, 3, 5 are odd: e[0], e[2], e[4], applied in batch order (row order). */
    cr_assert_eq(f->log.calls, 3, "threads %d", threads);
    for (int k = 0; k < 3; k++) {
        cr_expect_eq(f->log.entities[k], e[2 * k], "threads %d: call %d", threads, k);
        cr_expect_eq(f->log.buffers[k], 2 * k + 1, "threads %d: call %d", threads, k);
        cr_expect(f->log.consistent[k], "threads %d: call %d", threads, k);
        cr_expect_eq(f->log.thread[k], 0, "threads %d: hooks run on the ecs_progress thread",
                     threads);
    }
    ecs_progress(f->world, 0.016f);
    cr_expect_eq(f->log.calls, 3, "threads %d: nothing odd is left", threads);
    fixture_destroy_world(f);
    cr_expect_eq(f->log.calls, 6, "threads %d: the three even ones go with the world", threads);
    free(f);
}

Test(ecs_hooks, system_commands_call_hook_on_the_progress_thread) {
    check_progress_destroys(0);
    check_progress_destroys(2);
}

/* ---- ecs_world_destroy ------------------------------------------------------------------ */

Test(ecs_hooks, world_destroy_calls_hook_for_every_remaining_entity) {
    fixture *f = fixture_make(0);
    /* Buffers 1..12 in three tables: Mesh; Mesh + Position; Mesh + Frozen (4 each). */
    ecs_entity e[12];
    for (int i = 0; i < 12; i++) {
        e[i] = spawn_mesh(f, i + 1);
        if (i % 3 == 1) ecs_set(f->world, e[i], f->position, &(Position){ 0, 0 });
        if (i % 3 == 2) ecs_add(f->world, e[i], f->frozen);
    }
    /* Four made in bulk, buffers 13..16, and five that never had a Mesh. */
    Mesh bulk_values[4] = { { 13 }, { 14 }, { 15 }, { 16 } };
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 4,
        .components = { f->position, f->mesh }, .values = { NULL, bulk_values } });
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 5, .components = { f->position } });
    ecs_entity_destroy(f->world, e[0]);      /* buffer 1 */
    ecs_entity_destroy(f->world, e[4]);      /* buffer 5 */
    ecs_remove(f->world, e[8], f->mesh);     /* buffer 9 */
    cr_assert_eq(f->log.calls, 3);

    fixture_destroy_world(f);
    /* 16 Meshes in all, 3 already gone: 13 left; their buffers sum to 136 - (1 + 5 + 9). */
    cr_assert_eq(f->log.calls, 3 + 13);
    int sum = 0;
    bool seen[17] = { false }, once = true, consistent = true;
    for (int i = 3; i < f->log.calls; i++) {
        int buffer = f->log.buffers[i];
        cr_assert(buffer >= 1 && buffer <= 16, "call %d: buffer %d", i, buffer);
        once = once && !seen[buffer];
        seen[buffer] = true;
        sum += buffer;
        consistent = consistent && f->log.consistent[i];
    }
    cr_expect_eq(sum, 136 - 15);
    cr_expect(once, "every remaining entity is released exactly once");
    cr_expect(!seen[1] && !seen[5] && !seen[9], "nor again for those already released");
    cr_expect(consistent, "ecs_get works in hooks while the world is destroyed");
    free(f);
}

/* ---- setting and clearing --------------------------------------------------------------- */

Test(ecs_hooks, clearing_with_null_stops_calls) {
    fixture *f = fixture_make(0);
    ecs_entity a = spawn_mesh(f, 1), b = spawn_mesh(f, 2), c = spawn_mesh(f, 3);
    spawn_mesh(f, 4);
    ecs_remove(f->world, a, f->mesh);
    cr_assert_eq(f->log.calls, 1);

    ecs_component_on_remove(f->world, f->mesh, NULL, &f->log);
    ecs_remove(f->world, b, f->mesh);
    ecs_entity_destroy(f->world, c);
    ecs_commands *commands = ecs_commands_create(f->world);
    ecs_defer_entity_destroy(commands, a);
    ecs_commands_apply(commands);
    ecs_commands_destroy(commands);
    fixture_destroy_world(f);
    cr_expect_eq(f->log.calls, 1, "no calls after clearing, not even from the world's end");
    free(f);
}

Test(ecs_hooks, setting_again_replaces_hook_and_user) {
    fixture *f = fixture_make(0);
    hook_log other = { .component = f->mesh };
    ecs_entity a = spawn_mesh(f, 1), b = spawn_mesh(f, 2);
    ecs_component_on_remove(f->world, f->mesh, log_call, &other);
    ecs_entity_destroy(f->world, a);
    ecs_remove(f->world, b, f->mesh);
    cr_expect_eq(f->log.calls, 0);
    cr_assert_eq(other.calls, 2);
    cr_expect_eq(other.buffers[0], 1);
    cr_expect_eq(other.buffers[1], 2);
    fixture_free(f);
}

/* ---- tags and several hooked components ------------------------------------------------- */

Test(ecs_hooks, tag_hook_gets_null_data) {
    fixture *f = fixture_make(0);
    hook_log tags = { .component = f->frozen };
    ecs_component_on_remove(f->world, f->frozen, log_call, &tags);
    ecs_entity a = ecs_entity_create(f->world), b = spawn_mesh(f, 5);
    ecs_entity c = ecs_entity_create(f->world);
    ecs_add(f->world, a, f->frozen);
    ecs_add(f->world, b, f->frozen);
    ecs_add(f->world, c, f->frozen);

    ecs_remove(f->world, a, f->frozen);
    ecs_entity_destroy(f->world, b);
    cr_assert_eq(tags.calls, 2);
    cr_expect_eq(tags.entities[0], a);
    cr_expect_eq(tags.entities[1], b);
    cr_expect(tags.data_null[0] && tags.data_null[1], "a tag has no data");
    cr_expect(tags.consistent[0] && tags.consistent[1], "ecs_get of a tag is NULL too");
    cr_assert_eq(f->log.calls, 1, "destroying b also released its Mesh");
    cr_expect_eq(f->log.entities[0], b);
    cr_expect_eq(f->log.buffers[0], 5);

    ecs_world_destroy(f->world);
    f->world = NULL;
    cr_assert_eq(tags.calls, 3);
    cr_expect_eq(tags.entities[2], c);
    cr_expect(tags.data_null[2]);
    fixture_free(f);
}

/* ---- ctor, dtor, move, on_add, on_set ------------------------------------------------------ */

/* A component that owns heap memory and points at itself: under ASan a missed dtor leaks, a
 * second one frees twice, and a row moved without the move hook keeps a stale `self`. */
typedef struct Tracked {
    int *heap;
    struct Tracked *self;
} Tracked;
typedef struct Counter { int value; } Counter;   /* no memory of its own; ctor sets 100 */

typedef struct life {
    int ctor, dtor, move, on_add, on_set, on_remove;   /* calls */
    int constructed, destructed, moved;                /* elements */
    int live;                                          /* constructed - destructed */
    bool self_ok;                                      /* every element seen was in place */
    int thread_max;                                    /* highest job_thread_index in a hook */
} life;

static void note_thread(life *l, ecs_world *world) {
    job_system *jobs = world ? ecs_world_jobs(world) : NULL;
    int thread = jobs ? job_thread_index(jobs) : 0;
    if (thread > l->thread_max) l->thread_max = thread;
}

static void tracked_ctor(void *data, int count, void *user) {
    life *l = user;
    Tracked *t = data;
    for (int i = 0; i < count; i++) {
        t[i].heap = malloc(sizeof *t[i].heap);
        *t[i].heap = 1;
        t[i].self = &t[i];
    }
    l->ctor++, l->constructed += count, l->live += count;
}

static void tracked_dtor(void *data, int count, void *user) {
    life *l = user;
    Tracked *t = data;
    for (int i = 0; i < count; i++) {
        l->self_ok = l->self_ok && t[i].self == &t[i];
        free(t[i].heap);
        t[i].heap = NULL;
    }
    l->dtor++, l->destructed += count, l->live -= count;
}

static void tracked_move(void *dst, void *src, int count, void *user) {
    life *l = user;
    Tracked *to = dst, *from = src;
    for (int i = 0; i < count; i++) {
        l->self_ok = l->self_ok && from[i].self == &from[i];
        to[i] = (Tracked){ .heap = from[i].heap, .self = &to[i] };
        from[i] = (Tracked){ 0 }; /* dead: a dtor on it would be caught by self_ok */
    }
    l->move++, l->moved += count;
}

static void life_on_add(ecs_world *world, ecs_entity entity, void *data, void *user) {
    life *l = user;
    (void)entity;
    Tracked *t = data;
    l->self_ok = l->self_ok && t && t->self == t && t->heap;
    l->on_add++;
    note_thread(l, world);
}

static void life_on_set(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)entity, (void)data;
    ((life *)user)->on_set++;
    note_thread(user, world);
}

static void life_on_remove(ecs_world *world, ecs_entity entity, void *data, void *user) {
    life *l = user;
    (void)entity;
    Tracked *t = data;
    l->self_ok = l->self_ok && t && t->self == t && t->heap;
    l->on_remove++;
    note_thread(l, world);
}

static void counter_ctor(void *data, int count, void *user) {
    for (int i = 0; i < count; i++) ((Counter *)data)[i].value = 100;
    life *l = user;
    l->ctor++, l->constructed += count, l->live += count;
}

static void counter_dtor(void *data, int count, void *user) {
    (void)data;
    life *l = user;
    l->dtor++, l->destructed += count, l->live -= count;
}

static void counter_on_add(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)entity, (void)data;
    ((life *)user)->on_add++;
    note_thread(user, world);
}

static void counter_on_remove(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)entity, (void)data;
    ((life *)user)->on_remove++;
    note_thread(user, world);
}

typedef struct life_fixture {
    job_system *jobs;
    ecs_world *world;
    ecs_component tracked, counter, position;
    life t, c;                       /* of Tracked and of Counter */
} life_fixture;

static life_fixture *life_make(int threads) {
    life_fixture *f = calloc(1, sizeof *f);
    f->t.self_ok = f->c.self_ok = true;
    if (threads) f->jobs = job_system_create(&(job_system_desc){ .threads = threads });
    f->world = ecs_world_create(&(ecs_world_desc){ .jobs = f->jobs });
    f->tracked = ECS_COMPONENT(f->world, Tracked);
    f->counter = ECS_COMPONENT(f->world, Counter);
    f->position = ECS_COMPONENT(f->world, Position);
    ecs_component_set_hooks(f->world, f->tracked, &(ecs_hooks){
        .ctor = tracked_ctor, .dtor = tracked_dtor, .move = tracked_move,
        .on_add = life_on_add, .on_set = life_on_set, .on_remove = life_on_remove,
        .user = &f->t });
    ecs_component_set_hooks(f->world, f->counter, &(ecs_hooks){
        .ctor = counter_ctor, .dtor = counter_dtor, .on_add = counter_on_add,
        .on_set = life_on_set, .on_remove = counter_on_remove, .user = &f->c });
    return f;
}

static void life_destroy_world(life_fixture *f) {
    ecs_world_destroy(f->world);
    f->world = NULL;
    if (f->jobs) job_system_destroy(f->jobs);
    f->jobs = NULL;
}

/* Every Tracked in the world is in place and owns its memory; returns how many there are. */
static int tracked_check(life_fixture *f) {
    ecs_query *q = ecs_query_create(f->world, &(ecs_query_desc){ .with = { f->tracked } });
    int count = 0;
    ecs_iter it = ecs_query_iter(f->world, q);
    while (ecs_query_next(&it)) {
        Tracked *t = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++, count++)
            f->t.self_ok = f->t.self_ok && t[i].self == &t[i] && t[i].heap && *t[i].heap == 1;
    }
    ecs_query_destroy(f->world, q);
    return count;
}

Test(ecs_hooks, lifecycle_counts_add_remove_destroy_world) {
    life_fixture *f = life_make(0);
    ecs_entity e[3];
    for (int i = 0; i < 3; i++) {
        e[i] = ecs_entity_create(f->world);
        ecs_add(f->world, e[i], f->tracked);
    }
    /* Rows a, b, c of table {Tracked}. Removing a moves c into row 0 (one move); b is then
     * the last row, so destroying it moves nothing. */
    ecs_remove(f->world, e[0], f->tracked);
    cr_expect_eq(f->t.move, 1, "c fills a's row");
    ecs_entity_destroy(f->world, e[1]);
    cr_expect_eq(tracked_check(f), 1);
    cr_expect_eq(f->t.live, 1);
    life_destroy_world(f);
    cr_expect_eq(f->t.ctor, 3);
    cr_expect_eq(f->t.on_add, 3);
    cr_expect_eq(f->t.on_remove, 3);
    cr_expect_eq(f->t.dtor, 3);
    cr_expect_eq(f->t.move, 1);
    cr_expect_eq(f->t.on_set, 0, "nothing was set");
    cr_expect_eq(f->t.live, 0);
    cr_expect(f->t.self_ok);
    free(f);
}

Test(ecs_hooks, move_runs_once_per_row_move) {
    life_fixture *f = life_make(0);
    ecs_entity a = ecs_entity_create(f->world), b = ecs_entity_create(f->world);
    ecs_add(f->world, a, f->tracked);
    ecs_add(f->world, b, f->tracked);
    cr_assert_eq(f->t.move, 0, "into fresh tables nothing moves");

    /* b is the last row of {Tracked}: it moves to {Tracked, Position}, nothing fills its row. */
    ecs_add(f->world, b, f->position);
    cr_expect_eq(f->t.move, 1);
    cr_expect_eq(f->t.moved, 1);
    /* a is row 0 of {Tracked, …} alone now: one move out. */
    ecs_add(f->world, a, f->position);
    cr_expect_eq(f->t.move, 2);
    /* a is row 1 of {Tracked, Position} (b, a): moving a back moves a only; then removing
     * Position from b (row 0, a gone) moves b. */
    ecs_remove(f->world, a, f->position);
    ecs_remove(f->world, b, f->position);
    cr_expect_eq(f->t.move, 4);
    cr_expect_eq(f->t.ctor, 2, "moving is not constructing");
    cr_expect_eq(f->t.dtor, 0, "nor destructing");
    cr_expect_eq(f->t.on_add, 2, "adding another component is not adding this one");
    cr_expect_eq(f->t.on_remove, 0);
    cr_expect_eq(tracked_check(f), 2);
    cr_expect(f->t.self_ok);
    life_destroy_world(f);
    cr_expect_eq(f->t.destructed, 2, "both in one table: one dtor call for its column");
    cr_expect_eq(f->t.dtor, 1);
    free(f);
}

Test(ecs_hooks, column_growth_moves_the_column_once) {
    life_fixture *f = life_make(0);
    /* A table's first capacity is 16 rows: the 17th entity grows it to 32, one move of the
     * 16 elements already there. */
    for (int i = 0; i < 17; i++) ecs_add(f->world, ecs_entity_create(f->world), f->tracked);
    cr_expect_eq(f->t.move, 1);
    cr_expect_eq(f->t.moved, 16);
    cr_expect_eq(tracked_check(f), 17);
    cr_expect(f->t.self_ok, "every element is where its self pointer says");
    life_destroy_world(f);
    cr_expect_eq(f->t.destructed, 17);
    cr_expect_eq(f->t.live, 0);
    free(f);
}

Test(ecs_hooks, set_runs_on_set_and_adds_once) {
    life_fixture *f = life_make(0);
    ecs_entity e = ecs_entity_create(f->world);
    ecs_set(f->world, e, f->counter, &(Counter){ 5 });
    cr_expect_eq(f->c.ctor, 1);
    cr_expect_eq(f->c.on_add, 1);
    cr_expect_eq(f->c.on_set, 1);
    cr_expect_eq(((Counter *)ecs_get(f->world, e, f->counter))->value, 5, "the value wins");
    ecs_set(f->world, e, f->counter, &(Counter){ 6 });
    ecs_add(f->world, e, f->counter);
    cr_expect_eq(f->c.ctor, 1, "overwriting is not constructing");
    cr_expect_eq(f->c.on_add, 1);
    cr_expect_eq(f->c.on_set, 2, "ecs_add of a present component sets nothing");
    ecs_entity g = ecs_entity_create(f->world);
    ecs_add(f->world, g, f->counter);
    cr_expect_eq(((Counter *)ecs_get(f->world, g, f->counter))->value, 100, "the ctor's value");
    cr_expect_eq(f->c.on_set, 2);
    life_destroy_world(f);
    cr_expect_eq(f->c.destructed, 2);
    cr_expect_eq(f->c.on_remove, 2);
    free(f);
}

Test(ecs_hooks, lifecycle_through_a_command_buffer) {
    life_fixture *f = life_make(0);
    ecs_entity a = ecs_entity_create(f->world), b = ecs_entity_create(f->world);
    ecs_commands *commands = ecs_commands_create(f->world);
    ecs_entity p = ecs_defer_entity_create(commands);
    ecs_defer_add(commands, a, f->tracked);
    ecs_defer_add(commands, b, f->tracked);
    ecs_defer_add(commands, p, f->tracked);
    ecs_defer_set(commands, p, f->counter, &(Counter){ 7 });
    ecs_defer_remove(commands, a, f->tracked);
    ecs_defer_entity_destroy(commands, b);
    cr_expect_eq(f->t.ctor + f->c.ctor, 0, "nothing before apply");
    ecs_commands_apply(commands);
    cr_expect_eq(f->t.ctor, 3);
    cr_expect_eq(f->t.on_add, 3);
    cr_expect_eq(f->t.on_remove, 2, "a's removed, b destroyed");
    cr_expect_eq(f->t.dtor, 2);
    cr_expect_eq(f->c.ctor, 1);
    cr_expect_eq(f->c.on_add, 1);
    cr_expect_eq(f->c.on_set, 1);
    cr_expect_eq(tracked_check(f), 1);
    ecs_commands_destroy(commands);
    life_destroy_world(f);
    cr_expect_eq(f->t.dtor, 3);
    cr_expect_eq(f->t.on_remove, 3);
    cr_expect_eq(f->c.dtor, 1);
    cr_expect_eq(f->t.live, 0);
    cr_expect(f->t.self_ok);
    free(f);
}

Test(ecs_hooks, lifecycle_through_create_many) {
    life_fixture *f = life_make(0);
    Counter values[5] = { { 1 }, { 2 }, { 3 }, { 4 }, { 5 } };
    ecs_entity ids[5];
    ecs_entity_create_many(f->world, &(ecs_bulk_desc){ .count = 5, .ids = ids,
        .components = { f->counter, f->tracked }, .values = { values, NULL } });
    cr_expect_eq(f->t.ctor, 1, "one ctor call for the whole column");
    cr_expect_eq(f->t.constructed, 5);
    cr_expect_eq(f->t.on_add, 5);
    cr_expect_eq(f->t.on_set, 0, "Tracked got no values");
    cr_expect_eq(f->c.constructed, 5);
    cr_expect_eq(f->c.on_add, 5);
    cr_expect_eq(f->c.on_set, 5, "Counter got values");
    cr_expect_eq(((Counter *)ecs_get(f->world, ids[3], f->counter))->value, 4);
    cr_expect_eq(tracked_check(f), 5);
    life_destroy_world(f);
    cr_expect_eq(f->t.destructed, 5);
    cr_expect_eq(f->t.on_remove, 5);
    cr_expect_eq(f->c.destructed, 5);
    cr_expect_eq(f->c.on_remove, 5);
    cr_expect(f->t.self_ok);
    free(f);
}

/* Adds Tracked to entities with Position and no Tracked, removes it from those with both. */
static void toggle_tracked(ecs_iter *it) {
    const ecs_component *ids = it->user;   /* [0] Tracked */
    while (ecs_query_next(it)) {
        for (int i = 0; i < it->count; i++) {
            if (ecs_has(it->world, it->entities[i], ids[0]))
                ecs_defer_remove(it->commands, it->entities[i], ids[0]);
            else
                ecs_defer_add(it->commands, it->entities[i], ids[0]);
        }
    }
}

static void check_progress_lifecycle(int threads) {
    life_fixture *f = life_make(threads);
    ecs_component ids[1] = { f->tracked };
    for (int i = 0; i < 8; i++) ecs_set(f->world, ecs_entity_create(f->world), f->position,
                                       &(Position){ (float)i, 0 });
    ecs_system_add(f->world, &(ecs_system_desc){ .name = "toggle", .phase = "game",
        .fn = toggle_tracked, .query = { .with = { f->position } }, .user = ids,
        .parallel = true, .batch_size = 2 });
    ecs_progress(f->world, 0.016f);           /* 8 adds */
    cr_expect_eq(f->t.ctor, 8, "threads %d", threads);
    cr_expect_eq(f->t.on_add, 8, "threads %d", threads);
    ecs_progress(f->world, 0.016f);           /* 8 removes */
    cr_expect_eq(f->t.on_remove, 8, "threads %d", threads);
    cr_expect_eq(f->t.dtor, 8, "threads %d", threads);
    ecs_progress(f->world, 0.016f);           /* 8 adds again, left for the world */
    cr_expect_eq(tracked_check(f), 8, "threads %d", threads);
    cr_expect_eq(f->t.thread_max, 0, "threads %d: hooks run on the ecs_progress thread",
                 threads);
    life_destroy_world(f);
    cr_expect_eq(f->t.ctor, 16, "threads %d", threads);
    cr_expect_eq(f->t.on_add, 16, "threads %d", threads);
    cr_expect_eq(f->t.on_remove, 16, "threads %d", threads);
    cr_expect_eq(f->t.destructed, 16, "threads %d", threads);
    cr_expect_eq(f->t.dtor, 8 + 1, "threads %d: 8 removes, then one column", threads);
    cr_expect_eq(f->t.live, 0, "threads %d", threads);
    cr_expect(f->t.self_ok, "threads %d", threads);
    free(f);
}

Test(ecs_hooks, lifecycle_through_system_commands) {
    check_progress_lifecycle(0);
    check_progress_lifecycle(2);
}

Test(ecs_hooks, on_remove_wrapper_keeps_the_other_hooks) {
    life_fixture *f = life_make(0);
    hook_log log = { .component = f->tracked };
    ecs_component_on_remove(f->world, f->tracked, log_call, &log);
    ecs_hooks hooks = ecs_component_hooks(f->world, f->tracked);
    cr_expect(hooks.ctor == tracked_ctor && hooks.dtor == tracked_dtor);
    /* The user is shared: ctor and dtor now get the log. Put the life back for them. */
    hooks.user = &f->t;
    hooks.on_remove = life_on_remove;
    ecs_component_set_hooks(f->world, f->tracked, &hooks);
    ecs_entity e = ecs_entity_create(f->world);
    ecs_add(f->world, e, f->tracked);
    ecs_entity_destroy(f->world, e);
    cr_expect_eq(f->t.on_remove, 1);
    cr_expect_eq(f->t.dtor, 1);
    life_destroy_world(f);
    free(f);
}

/* ---- programmer errors ------------------------------------------------------------------ */

#if !defined(TEST_WITHOUT_CRITERION) && !defined(NDEBUG)
static void create_in_hook(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)entity, (void)data, (void)user;
    ecs_entity_create(world);
}

Test(ecs_hooks, structural_change_inside_a_hook_asserts, .signal = SIGABRT) {
    fixture *f = fixture_make(0);
    ecs_component_on_remove(f->world, f->mesh, create_in_hook, NULL);
    ecs_entity_destroy(f->world, spawn_mesh(f, 1));
}
#endif
