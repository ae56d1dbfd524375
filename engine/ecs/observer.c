/* observer.c — observers: callbacks when an entity starts or stops matching a query.
 *
 * Each table keeps the list of observers whose query it matches, filled when the table or the
 * observer is created. A move between two tables then only compares their two lists, and a
 * move between tables that no observer cares about (both lists empty) costs one test.
 */
#include "ecs_internal.h"

#include <string.h>

static bool table_has_observer(const ecs_table *table, const ecs_observer_info *observer) {
    for (uint32_t i = 0; i < table->observer_count; i++)
        if (table->observers[i] == observer) return true;
    return false;
}

static void table_observer_append(ecs_table *table, ecs_observer_info *observer) {
    table->observers = ecs_grow(table->observers, &table->observer_capacity,
                                table->observer_count + 1, sizeof *table->observers);
    table->observers[table->observer_count++] = observer;
}

static void table_observer_drop(ecs_table *table, const ecs_observer_info *observer) {
    for (uint32_t i = 0; i < table->observer_count; i++) {
        if (table->observers[i] != observer) continue;
        /* memmove, not swap: the list stays in registration order, which is call order. */
        memmove(&table->observers[i], &table->observers[i + 1],
                (table->observer_count - i - 1) * sizeof *table->observers);
        table->observer_count--;
        return;
    }
}

void ecs_observers_table_created(ecs_world *world, ecs_table *table) {
    for (uint32_t i = 0; i < world->observer_count; i++) {
        ecs_observer_info *observer = world->observers[i];
        if (observer && ecs_query_matches_table(&observer->terms, table))
            table_observer_append(table, observer);
    }
}

ecs_observer ecs_observer_add(ecs_world *world, const ecs_observer_desc *desc) {
    ECS_ASSERT_STRUCTURAL(world);
    assert(desc && desc->fn && "an observer needs a function");
    assert(desc->query.with[0] && "an observer's query needs a `with` term");
    ecs_observer_info *observer = core_calloc(1, sizeof *observer);
    observer->name = core_strdup(desc->name ? desc->name : "observer");
    ecs_query_terms_init(&observer->terms, world, &desc->query);
    observer->events = desc->events ? desc->events : (ECS_ON_ADD | ECS_ON_REMOVE);
    observer->fn = desc->fn;
    observer->user = desc->user;

    world->observers = ecs_grow(world->observers, &world->observer_capacity,
                                world->observer_count + 1, sizeof *world->observers);
    world->observers[world->observer_count++] = observer;
    for (uint32_t i = 0; i < world->table_count; i++)
        if (ecs_query_matches_table(&observer->terms, world->tables[i]))
            table_observer_append(world->tables[i], observer);
    return world->observer_count;
}

static void observer_free(ecs_observer_info *observer) {
    core_free(observer->name, strlen(observer->name) + 1);
    core_free(observer, sizeof *observer);
}

void ecs_observer_remove(ecs_world *world, ecs_observer id) {
    ECS_ASSERT_STRUCTURAL(world);
    if (!id) return;
    assert(id <= world->observer_count && world->observers[id - 1] && "not a live observer");
    /* Release builds: an id removed already, or never made, is ignored (ids are not reused, so
     * it cannot name another observer). */
    if (id > world->observer_count || !world->observers[id - 1]) return;
    ecs_observer_info *observer = world->observers[id - 1];
    for (uint32_t i = 0; i < world->table_count; i++)
        table_observer_drop(world->tables[i], observer);
    world->observers[id - 1] = NULL; /* ids are indices: the slot is not reused */
    observer_free(observer);
}

void ecs_observers_fire(ecs_world *world, ecs_entity entity, const ecs_table *from,
                        const ecs_table *to, ecs_event event) {
    /* The table whose observers may fire, and the one where they would go on matching. */
    const ecs_table *matching = event == ECS_ON_ADD ? to : from;
    const ecs_table *other = event == ECS_ON_ADD ? from : to;
    if (!matching) return;
    bool was_in_hook = world->in_hook;
    world->in_hook = true;
    for (uint32_t i = 0; i < matching->observer_count; i++) {
        ecs_observer_info *observer = matching->observers[i];
        if (!(observer->events & (uint32_t)event)) continue;
        if (other && table_has_observer(other, observer)) continue;
        observer->fn(world, entity, event, observer->user);
    }
    world->in_hook = was_in_hook;
}

void ecs_observers_free(ecs_world *world) {
    for (uint32_t i = 0; i < world->observer_count; i++)
        if (world->observers[i]) observer_free(world->observers[i]);
    core_free(world->observers, world->observer_capacity * sizeof *world->observers);
}
