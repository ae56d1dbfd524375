/* Tests of ECS entities and components (engine/ecs): ids, add/set/remove/get, tags, bulk
 * creation. */
#include "core/core.h"
#include "ecs/ecs.h"

#include "test.h"
#include <string.h>

typedef struct Position { float x, y; } Position;
typedef struct Velocity { float x, y; } Velocity;
typedef struct Health { int points; } Health;

typedef struct fixture {
    ecs_world *world;
    ecs_component position, velocity, health, frozen;
} fixture;

static fixture fixture_make(void) {
    fixture f = { .world = ecs_world_create(NULL) };
    f.position = ECS_COMPONENT(f.world, Position);
    f.velocity = ECS_COMPONENT(f.world, Velocity);
    f.health = ECS_COMPONENT(f.world, Health);
    f.frozen = ECS_TAG(f.world, Frozen);
    return f;
}

static uint32_t index_of(ecs_entity e) { return (uint32_t)e; }
static uint32_t generation_of(ecs_entity e) { return (uint32_t)(e >> 32); }

Test(ecs_entities, null_is_never_alive) {
    fixture f = fixture_make();
    cr_expect_not(ecs_is_alive(f.world, 0));
    cr_expect_null(ecs_get(f.world, 0, f.position));
    cr_expect_eq(ecs_entity_count(f.world), 0);
    ecs_world_destroy(f.world);
}

Test(ecs_entities, created_ids_are_distinct_and_alive) {
    fixture f = fixture_make();
    ecs_entity ids[100];
    for (int i = 0; i < 100; i++) {
        ids[i] = ecs_entity_create(f.world);
        cr_assert_neq(ids[i], 0);
        cr_expect(ecs_is_alive(f.world, ids[i]));
        for (int j = 0; j < i; j++) cr_assert_neq(ids[i], ids[j]);
    }
    cr_expect_eq(ecs_entity_count(f.world), 100);
    ecs_world_destroy(f.world);
}

Test(ecs_entities, destroyed_index_is_reused_with_a_new_generation) {
    fixture f = fixture_make();
    ecs_entity old = ecs_entity_create(f.world);
    ecs_set(f.world, old, f.position, &(Position){ 1, 2 });
    ecs_entity_destroy(f.world, old);
    cr_expect_not(ecs_is_alive(f.world, old));
    cr_expect_eq(ecs_entity_count(f.world), 0);

    ecs_entity reborn = ecs_entity_create(f.world);
    ecs_set(f.world, reborn, f.position, &(Position){ 3, 4 });
    cr_expect_eq(index_of(reborn), index_of(old), "the only free index is reused");
    cr_expect_neq(generation_of(reborn), generation_of(old));
    cr_expect_neq(reborn, old);

    /* The old id must not reach the new entity through any call. */
    cr_expect_not(ecs_is_alive(f.world, old));
    cr_expect_null(ecs_get(f.world, old, f.position));
    cr_expect_not(ecs_has(f.world, old, f.position));
    ecs_entity_destroy(f.world, old); /* ignored: it is dead */
    ecs_remove(f.world, old, f.position);
    cr_expect(ecs_is_alive(f.world, reborn));
    Position *p = ecs_get(f.world, reborn, f.position);
    cr_assert_not_null(p);
    cr_expect(p->x == 3 && p->y == 4);
    ecs_world_destroy(f.world);
}

Test(ecs_entities, every_reuse_bumps_the_generation) {
    fixture f = fixture_make();
    ecs_entity seen[50];
    for (int round = 0; round < 50; round++) {
        seen[round] = ecs_entity_create(f.world);
        ecs_entity_destroy(f.world, seen[round]);
    }
    for (int i = 0; i < 50; i++) {
        cr_expect_not(ecs_is_alive(f.world, seen[i]));
        for (int j = 0; j < i; j++) cr_expect_neq(seen[i], seen[j]);
    }
    ecs_world_destroy(f.world);
}

Test(ecs_entities, add_returns_zeroed_data) {
    fixture f = fixture_make();
    /* Dirty the memory the column will reuse: fill a row, destroy it, add again. */
    ecs_entity first = ecs_entity_create(f.world);
    ecs_set(f.world, first, f.position, &(Position){ 7, 7 });
    ecs_entity_destroy(f.world, first);
    ecs_entity e = ecs_entity_create(f.world);
    Position *p = ecs_add(f.world, e, f.position);
    cr_assert_not_null(p);
    cr_expect(p->x == 0 && p->y == 0);
    cr_expect(ecs_has(f.world, e, f.position));
    cr_expect_not(ecs_has(f.world, e, f.velocity));
    cr_expect_null(ecs_get(f.world, e, f.velocity));
    ecs_world_destroy(f.world);
}

Test(ecs_entities, values_survive_moves_between_tables) {
    fixture f = fixture_make();
    ecs_entity e = ecs_entity_create(f.world);
    ecs_set(f.world, e, f.health, &(Health){ 42 });
    ecs_set(f.world, e, f.position, &(Position){ 1, 2 });
    ecs_add(f.world, e, f.frozen);
    ecs_set(f.world, e, f.velocity, &(Velocity){ 5, 6 });
    ecs_remove(f.world, e, f.position);
    ecs_remove(f.world, e, f.frozen);

    cr_expect_eq(((Health *)ecs_get(f.world, e, f.health))->points, 42);
    Velocity *v = ecs_get(f.world, e, f.velocity);
    cr_assert_not_null(v);
    cr_expect(v->x == 5 && v->y == 6);
    cr_expect_not(ecs_has(f.world, e, f.position));
    cr_expect_not(ecs_has(f.world, e, f.frozen));
    ecs_world_destroy(f.world);
}

Test(ecs_entities, removing_a_row_keeps_the_others) {
    fixture f = fixture_make();
    ecs_entity e[4];
    for (int i = 0; i < 4; i++) {
        e[i] = ecs_entity_create(f.world);
        ecs_set(f.world, e[i], f.health, &(Health){ 100 + i });
    }
    ecs_entity_destroy(f.world, e[0]);    /* the last row moves into row 0 */
    ecs_remove(f.world, e[2], f.health);  /* and another row leaves the table */
    cr_expect_eq(((Health *)ecs_get(f.world, e[1], f.health))->points, 101);
    cr_expect_eq(((Health *)ecs_get(f.world, e[3], f.health))->points, 103);
    cr_expect(ecs_is_alive(f.world, e[2]));
    cr_expect_null(ecs_get(f.world, e[2], f.health));
    ecs_world_destroy(f.world);
}

Test(ecs_entities, tags_have_presence_but_no_data) {
    fixture f = fixture_make();
    ecs_entity e = ecs_entity_create(f.world);
    cr_expect_null(ecs_add(f.world, e, f.frozen));
    cr_expect(ecs_has(f.world, e, f.frozen));
    cr_expect_null(ecs_get(f.world, e, f.frozen));
    cr_expect_eq(ecs_component_size(f.world, f.frozen), 0);
    ecs_remove(f.world, e, f.frozen);
    cr_expect_not(ecs_has(f.world, e, f.frozen));
    ecs_world_destroy(f.world);
}

/* {Position, Health} → {Health} → {}: {Health} is first reached by a removal, so no edge leads
 * from it to the empty table yet; that lookup once handed memcmp the empty table's NULL array. */
Test(ecs_entities, removing_every_component_returns_to_the_empty_table) {
    fixture f = fixture_make();
    ecs_entity e = ecs_entity_create(f.world);
    ecs_set(f.world, e, f.position, &(Position){ 1, 2 });
    ecs_set(f.world, e, f.health, &(Health){ 3 });
    ecs_remove(f.world, e, f.position);
    ecs_remove(f.world, e, f.health);
    cr_expect(ecs_is_alive(f.world, e));
    cr_expect_not(ecs_has(f.world, e, f.position));
    cr_expect_not(ecs_has(f.world, e, f.health));
    ecs_query *all = ecs_query_create(f.world, &(ecs_query_desc){ 0 });
    cr_expect_eq(ecs_query_count(f.world, all), 1, "e is back among the component-less");
    ecs_world_destroy(f.world);
}

Test(ecs_entities, components_are_found_by_name_and_registered_once) {
    fixture f = fixture_make();
    cr_expect_eq(ECS_COMPONENT(f.world, Position), f.position);
    cr_expect_eq(ecs_component_lookup(f.world, "Velocity"), f.velocity);
    cr_expect_eq(ecs_component_lookup(f.world, "Nothing"), 0);
    cr_expect_eq(ecs_component_size(f.world, f.health), sizeof(Health));
    cr_expect_neq(f.position, f.velocity);
    ecs_world_destroy(f.world);
}

Test(ecs_entities, create_many_fills_the_table_directly) {
    fixture f = fixture_make();
    ecs_entity single = ecs_entity_create(f.world);
    ecs_set(f.world, single, f.position, &(Position){ -1, -1 });
    ecs_add(f.world, single, f.velocity);

    enum { N = 1000 };
    static Position positions[N];
    static ecs_entity ids[N];
    for (int i = 0; i < N; i++) positions[i] = (Position){ (float)i, (float)(2 * i) };
    /* Components in a different order than their ids: the values must follow them. */
    ecs_entity_create_many(f.world, &(ecs_bulk_desc){
        .count = N, .components = { f.velocity, f.position },
        .values = { NULL, positions }, .ids = ids });

    cr_expect_eq(ecs_entity_count(f.world), N + 1);
    for (int i = 0; i < N; i++) {
        cr_assert(ecs_is_alive(f.world, ids[i]));
        Position *p = ecs_get(f.world, ids[i], f.position);
        Velocity *v = ecs_get(f.world, ids[i], f.velocity);
        cr_assert(p && v);
        cr_expect(p->x == (float)i && p->y == (float)(2 * i), "entity %d", i);
        cr_expect(v->x == 0 && v->y == 0);
    }
    Position *p = ecs_get(f.world, single, f.position);
    cr_expect(p->x == -1 && p->y == -1, "the entity already in the table is untouched");
    ecs_world_destroy(f.world);
}

Test(ecs_entities, create_many_reuses_free_indices) {
    fixture f = fixture_make();
    ecs_entity old[3];
    for (int i = 0; i < 3; i++) old[i] = ecs_entity_create(f.world);
    for (int i = 0; i < 3; i++) ecs_entity_destroy(f.world, old[i]);
    ecs_entity ids[5];
    ecs_entity_create_many(f.world, &(ecs_bulk_desc){ .count = 5, .components = { f.health },
                                                      .ids = ids });
    for (int i = 0; i < 5; i++) {
        cr_expect(ecs_is_alive(f.world, ids[i]));
        for (int j = 0; j < 3; j++) cr_expect_neq(ids[i], old[j]);
    }
    cr_expect_eq(ecs_entity_count(f.world), 5);
    ecs_world_destroy(f.world);
}

Test(ecs_entities, destroying_the_world_returns_every_byte) {
    ecs_world_destroy(ecs_world_create(NULL)); /* interns the phase names once, for good */
    size_t before = core_memory_in_use();
    fixture f = fixture_make();
    ecs_query *q = ecs_query_create(f.world, &(ecs_query_desc){ .with = { f.position } });
    ecs_commands *commands = ecs_commands_create(f.world);
    for (int i = 0; i < 5000; i++) {
        ecs_entity e = ecs_entity_create(f.world);
        ecs_set(f.world, e, f.position, &(Position){ (float)i, 0 });
        if (i % 3 == 0) ecs_add(f.world, e, f.frozen);
        if (i % 5 == 0) ecs_defer_set(commands, e, f.health, &(Health){ i });
        if (i % 7 == 0) ecs_entity_destroy(f.world, e);
    }
    ecs_commands_apply(commands);
    cr_expect_gt(ecs_query_count(f.world, q), 0);
    ecs_commands_destroy(commands);
    ecs_world_destroy(f.world);
    cr_expect_eq(core_memory_in_use(), before);
}
