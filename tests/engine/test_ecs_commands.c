/* Tests of ECS command buffers (engine/ecs): deferred create/destroy/add/set/remove, and a
 * deterministic apply order whatever the thread count. */
#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"

#include "test.h"
#include <stdlib.h>
#include <string.h>

typedef struct Position { float x, y; } Position;
typedef struct Health { int points; } Health;

typedef struct fixture {
    ecs_world *world;
    ecs_component position, health, frozen;
    ecs_commands *commands;
} fixture;

static fixture fixture_make(void) {
    fixture f = { .world = ecs_world_create(NULL) };
    f.position = ECS_COMPONENT(f.world, Position);
    f.health = ECS_COMPONENT(f.world, Health);
    f.frozen = ECS_TAG(f.world, Frozen);
    f.commands = ecs_commands_create(f.world);
    return f;
}

static void fixture_free(fixture *f) {
    ecs_commands_destroy(f->commands);
    ecs_world_destroy(f->world);
}

/* The one entity a query over `component` finds, or 0 when it finds none or several. */
static ecs_entity only_entity_with(ecs_world *world, ecs_component component) {
    ecs_query *q = ecs_query_create(world, &(ecs_query_desc){ .with = { component } });
    ecs_entity found = 0;
    int n = 0;
    ecs_iter it = ecs_query_iter(world, q);
    while (ecs_query_next(&it))
        for (int i = 0; i < it.count; i++, n++) found = it.entities[i];
    ecs_query_destroy(world, q);
    return n == 1 ? found : 0;
}

Test(ecs_commands, deferred_create_and_set_appear_after_apply) {
    fixture f = fixture_make();
    ecs_entity placeholder = ecs_defer_entity_create(f.commands);
    ecs_defer_set(f.commands, placeholder, f.position, &(Position){ 5, 6 });
    ecs_defer_add(f.commands, placeholder, f.frozen);
    cr_expect_neq(placeholder, 0);
    cr_expect_not(ecs_is_alive(f.world, placeholder), "a placeholder is not an entity");
    cr_expect_null(ecs_get(f.world, placeholder, f.position));
    cr_expect_eq(ecs_entity_count(f.world), 0, "nothing happens before apply");
    cr_expect_eq(ecs_commands_count(f.commands), 3);

    ecs_commands_apply(f.commands);
    cr_expect_eq(ecs_commands_count(f.commands), 0, "apply empties the buffer");
    cr_expect_eq(ecs_entity_count(f.world), 1);
    ecs_entity e = only_entity_with(f.world, f.position);
    cr_assert_neq(e, 0);
    Position *p = ecs_get(f.world, e, f.position);
    cr_expect(p->x == 5 && p->y == 6);
    cr_expect(ecs_has(f.world, e, f.frozen));
    fixture_free(&f);
}

Test(ecs_commands, placeholders_of_one_buffer_stay_apart) {
    fixture f = fixture_make();
    ecs_entity a = ecs_defer_entity_create(f.commands);
    ecs_entity b = ecs_defer_entity_create(f.commands);
    cr_expect_neq(a, b);
    ecs_defer_set(f.commands, b, f.health, &(Health){ 2 });
    ecs_defer_set(f.commands, a, f.health, &(Health){ 1 });
    ecs_defer_add(f.commands, b, f.frozen);
    ecs_commands_apply(f.commands);
    ecs_entity frozen = only_entity_with(f.world, f.frozen);
    cr_assert_neq(frozen, 0);
    cr_expect_eq(((Health *)ecs_get(f.world, frozen, f.health))->points, 2);
    cr_expect_eq(ecs_entity_count(f.world), 2);
    fixture_free(&f);
}

Test(ecs_commands, deferred_destroy_happens_at_apply) {
    fixture f = fixture_make();
    ecs_entity e = ecs_entity_create(f.world);
    ecs_set(f.world, e, f.health, &(Health){ 3 });
    ecs_defer_entity_destroy(f.commands, e);
    cr_expect(ecs_is_alive(f.world, e));
    cr_expect_eq(((Health *)ecs_get(f.world, e, f.health))->points, 3);
    ecs_commands_apply(f.commands);
    cr_expect_not(ecs_is_alive(f.world, e));
    cr_expect_eq(ecs_entity_count(f.world), 0);
    fixture_free(&f);
}

Test(ecs_commands, commands_apply_in_recording_order) {
    fixture f = fixture_make();
    ecs_entity kept = ecs_entity_create(f.world), dropped = ecs_entity_create(f.world);
    ecs_defer_remove(f.commands, kept, f.health);        /* nothing to remove yet */
    ecs_defer_set(f.commands, kept, f.health, &(Health){ 1 });
    ecs_defer_set(f.commands, kept, f.health, &(Health){ 2 });  /* the later value wins */
    ecs_defer_set(f.commands, dropped, f.health, &(Health){ 1 });
    ecs_defer_remove(f.commands, dropped, f.health);
    ecs_commands_apply(f.commands);
    cr_expect_eq(((Health *)ecs_get(f.world, kept, f.health))->points, 2);
    cr_expect_not(ecs_has(f.world, dropped, f.health));
    fixture_free(&f);
}

Test(ecs_commands, commands_on_dead_entities_are_skipped) {
    fixture f = fixture_make();
    ecs_entity e = ecs_entity_create(f.world);
    ecs_commands *later = ecs_commands_create(f.world);
    ecs_defer_entity_destroy(f.commands, e);
    ecs_defer_entity_destroy(later, e);                     /* two systems destroy the same entity */
    ecs_defer_set(later, e, f.health, &(Health){ 1 });
    ecs_defer_add(later, e, f.frozen);
    ecs_commands_apply(f.commands);
    ecs_entity reborn = ecs_entity_create(f.world);  /* takes e's index */
    ecs_commands_apply(later);
    cr_expect_not(ecs_is_alive(f.world, e));
    cr_expect(ecs_is_alive(f.world, reborn), "the stale id must not reach the new entity");
    cr_expect_not(ecs_has(f.world, reborn, f.health));
    cr_expect_not(ecs_has(f.world, reborn, f.frozen));
    ecs_commands_destroy(later);
    fixture_free(&f);
}

Test(ecs_commands, a_created_entity_can_be_destroyed_in_the_same_buffer) {
    fixture f = fixture_make();
    ecs_entity e = ecs_defer_entity_create(f.commands);
    ecs_defer_add(f.commands, e, f.frozen);
    ecs_defer_entity_destroy(f.commands, e);
    ecs_commands_apply(f.commands);
    cr_expect_eq(ecs_entity_count(f.world), 0);
    fixture_free(&f);
}

/* ---- the same program on any number of threads ------------------------------------------ */

typedef struct Value { uint64_t v; } Value;
typedef struct Counter { int n; } Counter;

typedef struct program {
    ecs_component value, counter, marked;
    int frame;
} program;

static uint64_t decide(ecs_entity e, int frame, uint64_t salt) {
    return core_hash_combine(core_hash_combine(e, (uint64_t)frame), salt);
}

/* game, parallel: some entities spawn a child with a Value and a Counter. */
static void spawn(ecs_iter *it) {
    program *p = it->user;
    while (ecs_query_next(it))
        for (int i = 0; i < it->count; i++) {
            uint64_t h = decide(it->entities[i], p->frame, 1);
            if (h % 9 != 0) continue;
            ecs_entity child = ecs_defer_entity_create(it->commands);
            ecs_defer_set(it->commands, child, p->value, &(Value){ h });
            ecs_defer_add(it->commands, child, p->counter);
        }
}

/* game, parallel, beside spawn: destroys some, marks others (often the same ones). */
static void thin(ecs_iter *it) {
    program *p = it->user;
    while (ecs_query_next(it))
        for (int i = 0; i < it->count; i++) {
            uint64_t h = decide(it->entities[i], p->frame, 2);
            if (h % 11 == 0) ecs_defer_entity_destroy(it->commands, it->entities[i]);
            if (h % 5 == 0) ecs_defer_add(it->commands, it->entities[i], p->marked);
            if (h % 7 == 0) ecs_defer_set(it->commands, it->entities[i], p->value, &(Value){ h });
        }
}

/* stream: counts up, retires counters past 3 and re-values their entity. */
static void count_up(ecs_iter *it) {
    program *p = it->user;
    while (ecs_query_next(it)) {
        Counter *c = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++)
            if (++c[i].n > 3) {
                ecs_defer_remove(it->commands, it->entities[i], p->counter);
                ecs_defer_set(it->commands, it->entities[i], p->value, &(Value){ (uint64_t)c[i].n });
            }
    }
}

/* generate, main thread: unmarks a third of the marked and spawns a bare entity for each. */
static void unmark(ecs_iter *it) {
    program *p = it->user;
    while (ecs_query_next(it))
        for (int i = 0; i < it->count; i++)
            if (decide(it->entities[i], p->frame, 3) % 3 == 0) {
                ecs_defer_remove(it->commands, it->entities[i], p->marked);
                ecs_defer_entity_create(it->commands);
            }
}

typedef struct snapshot_row {
    ecs_entity id;
    uint64_t value;
    int counter;
    bool has_value, has_counter, marked;
} snapshot_row;

static int row_compare(const void *a, const void *b) {
    ecs_entity x = ((const snapshot_row *)a)->id, y = ((const snapshot_row *)b)->id;
    return (x > y) - (x < y);
}

/* Every entity of the world with its components, sorted by id. */
static snapshot_row *snapshot(ecs_world *world, const program *p, int *count) {
    ecs_query *all = ecs_query_create(world, &(ecs_query_desc){ 0 });
    int n = ecs_query_count(world, all), k = 0;
    snapshot_row *rows = calloc((size_t)n + 1, sizeof *rows);
    ecs_iter it = ecs_query_iter(world, all);
    while (ecs_query_next(&it))
        for (int i = 0; i < it.count; i++, k++) {
            ecs_entity e = it.entities[i];
            Value *v = ecs_get(world, e, p->value);
            Counter *c = ecs_get(world, e, p->counter);
            rows[k] = (snapshot_row){ .id = e, .has_value = v != NULL, .value = v ? v->v : 0,
                                      .has_counter = c != NULL, .counter = c ? c->n : 0,
                                      .marked = ecs_has(world, e, p->marked) };
        }
    ecs_query_destroy(world, all);
    qsort(rows, (size_t)n, sizeof *rows, row_compare);
    *count = n;
    return rows;
}

/* threads = 0: a world without a job system. */
static snapshot_row *run_program(int threads, int *count) {
    job_system *jobs = threads ? job_system_create(&(job_system_desc){ .threads = threads }) : NULL;
    ecs_world *world = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    program p = { .value = ECS_COMPONENT(world, Value), .counter = ECS_COMPONENT(world, Counter),
                  .marked = ECS_TAG(world, Marked) };
    ecs_entity_create_many(world, &(ecs_bulk_desc){ .count = 400, .components = { p.value } });
    ecs_system_add(world, &(ecs_system_desc){ .name = "spawn", .phase = "game", .fn = spawn,
        .user = &p, .query = { .with = { p.value } }, .parallel = true, .batch_size = 37 });
    ecs_system_add(world, &(ecs_system_desc){ .name = "thin", .phase = "game", .fn = thin,
        .user = &p, .query = { .with = { p.value }, .without = { p.marked } }, .parallel = true,
        .batch_size = 23 });
    ecs_system_add(world, &(ecs_system_desc){ .name = "count", .phase = "stream", .fn = count_up,
        .user = &p, .query = { .with = { p.counter } }, .writes = { p.counter } });
    ecs_system_add(world, &(ecs_system_desc){ .name = "unmark", .phase = "generate",
        .fn = unmark, .user = &p, .query = { .with = { p.marked } }, .main_thread = true });
    for (p.frame = 0; p.frame < 25; p.frame++) ecs_progress(world, 1.0f / 60);
    snapshot_row *rows = snapshot(world, &p, count);
    ecs_world_destroy(world);
    if (jobs) job_system_destroy(jobs);
    return rows;
}

Test(ecs_commands, same_program_same_world_for_any_thread_count) {
    int reference_count;
    snapshot_row *reference = run_program(1, &reference_count);
    cr_assert_gt(reference_count, 400, "the program must create entities to be a test");
    const int thread_counts[] = { 0, 2, 3 };
    for (size_t t = 0; t < CORE_COUNTOF(thread_counts); t++) {
        int n;
        snapshot_row *rows = run_program(thread_counts[t], &n);
        cr_assert_eq(n, reference_count, "threads %d", thread_counts[t]);
        for (int i = 0; i < n; i++) {
            const snapshot_row *a = &rows[i], *b = &reference[i];
            cr_assert(a->id == b->id && a->has_value == b->has_value && a->value == b->value &&
                      a->has_counter == b->has_counter && a->counter == b->counter &&
                      a->marked == b->marked,
                      "threads %d: entity %d differs", thread_counts[t], i);
        }
        free(rows);
    }
    free(reference);
}
