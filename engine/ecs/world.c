/* world.c — the world, components, entities and their archetype tables (see ecs.h and
 * ecs_internal.h for the layout). */
#include "ecs_internal.h"

#include <stdlib.h>
#include <string.h>

#include "trace/trace.h"

/* core_grow for the ECS's 32-bit counts (they keep tables and records small). */
void *ecs_grow(void *items, uint32_t *capacity, uint32_t needed, size_t item_size) {
    if (needed <= *capacity) return items;
    size_t grown = *capacity;
    items = core_grow(items, &grown, needed, item_size);
    *capacity = (uint32_t)grown;
    return items;
}

/* ---- tables ----------------------------------------------------------------------------- */

int ecs_table_column_of(const ecs_table *table, ecs_component component) {
    /* Component sets are small (a handful): a linear scan beats a binary search here. */
    for (uint32_t i = 0; i < table->component_count; i++)
        if (table->components[i] == component) return (int)i;
    return -1;
}

/* ---- element hooks: construct, destruct, move ------------------------------------------ */

static inline const ecs_hooks *column_hooks(const ecs_world *world, const ecs_table *table,
                                            uint32_t column) {
    return &world->components[table->components[column]].hooks;
}

static inline uint8_t *column_at(const ecs_column *column, uint32_t row) {
    return column->data + (size_t)row * column->size;
}

/* `count` fresh elements: the ctor, or zeros. */
static void elements_construct(const ecs_hooks *hooks, const ecs_column *column, uint32_t row,
                               uint32_t count) {
    if (!column->size || !count) return;
    if (hooks->ctor) hooks->ctor(column_at(column, row), (int)count, hooks->user);
    else memset(column_at(column, row), 0, (size_t)count * column->size);
}

static void elements_destruct(const ecs_hooks *hooks, const ecs_column *column, uint32_t row,
                              uint32_t count) {
    if (column->size && count && hooks->dtor)
        hooks->dtor(column_at(column, row), (int)count, hooks->user);
}

/* Moves `count` elements to memory that does not overlap them; the source is dead after. */
static void elements_move(const ecs_hooks *hooks, uint8_t *dst, uint8_t *src, uint32_t count,
                          uint32_t size) {
    if (!size || !count) return;
    if (hooks->move) hooks->move(dst, src, (int)count, hooks->user);
    else memcpy(dst, src, (size_t)count * size);
}

/* ---- table storage ---------------------------------------------------------------------- */

static void column_reserve(const ecs_hooks *hooks, ecs_column *column, uint32_t count,
                           uint32_t old_capacity, uint32_t capacity) {
    if (column->size == 0) return;
    uint8_t *data = core_alloc_aligned((size_t)capacity * column->size, ECS_COLUMN_ALIGN);
    if (column->data) elements_move(hooks, data, column->data, count, column->size);
    core_free(column->data, (size_t)old_capacity * column->size);
    column->data = data;
}

static void table_reserve(const ecs_world *world, ecs_table *table, uint32_t needed) {
    if (needed <= table->capacity) return;
    uint32_t capacity = CORE_MAX(CORE_MAX(needed, table->capacity * 2), 16u);
    table->entities = core_realloc(table->entities, table->capacity * sizeof(ecs_entity),
                                   capacity * sizeof(ecs_entity));
    for (uint32_t i = 0; i < table->component_count; i++)
        column_reserve(column_hooks(world, table, i), &table->columns[i], table->count,
                       table->capacity, capacity);
    table->capacity = capacity;
}

/* Appends a row for `entity`; its column values are left for the caller to fill. */
static uint32_t table_append(const ecs_world *world, ecs_table *table, ecs_entity entity) {
    table_reserve(world, table, table->count + 1);
    table->entities[table->count] = entity;
    return table->count++;
}

/* Removes a row whose elements were destructed or moved out already, by moving the last row
 * into its place, which keeps the columns dense. */
static void table_remove_row(ecs_world *world, ecs_table *table, uint32_t row) {
    uint32_t last = --table->count;
    if (row == last) return;
    ecs_entity moved = table->entities[last];
    table->entities[row] = moved;
    if (table->hooked) {
        for (uint32_t i = 0; i < table->component_count; i++)
            elements_move(column_hooks(world, table, i), column_at(&table->columns[i], row),
                          column_at(&table->columns[i], last), 1, table->columns[i].size);
    } else {
        for (uint32_t i = 0; i < table->component_count; i++) {
            ecs_column *column = &table->columns[i];
            if (column->size)
                memcpy(column_at(column, row), column_at(column, last), column->size);
        }
    }
    world->records[ecs_id_index(moved)].row = row;
}

static bool hooks_any(const ecs_hooks *h) {
    return h->ctor || h->dtor || h->move || h->on_add || h->on_set || h->on_remove;
}

static void table_update_hooked(const ecs_world *world, ecs_table *table) {
    table->hooked = false;
    for (uint32_t i = 0; i < table->component_count; i++)
        table->hooked = table->hooked || hooks_any(column_hooks(world, table, i));
}

static uint64_t components_hash(const ecs_component *sorted, uint32_t count) {
    return core_hash_bytes(sorted, count * sizeof *sorted, 0x65637374u);
}

static ecs_table *table_create(ecs_world *world, const ecs_component *sorted, uint32_t count,
                               uint64_t hash) {
    ecs_table *table = core_calloc(1, sizeof *table);
    table->index = world->table_count;
    table->hash = hash;
    table->component_count = count;
    if (count) {
        table->components = core_alloc(count * sizeof *sorted);
        memcpy(table->components, sorted, count * sizeof *sorted);
        table->columns = core_calloc(count, sizeof *table->columns);
    }
    for (uint32_t i = 0; i < count; i++)
        table->columns[i].size = world->components[sorted[i]].size;
    table_update_hooked(world, table);

    world->tables = ecs_grow(world->tables, &world->table_capacity, world->table_count + 1,
                             sizeof *world->tables);
    world->tables[world->table_count++] = table;
    for (uint32_t i = 0; i < world->query_count; i++)
        ecs_query_consider_table(world->queries[i], table);
    ecs_observers_table_created(world, table);
    return table;
}

static void table_free(ecs_table *table) {
    for (uint32_t i = 0; i < table->component_count; i++)
        core_free(table->columns[i].data, (size_t)table->capacity * table->columns[i].size);
    core_free(table->columns, table->component_count * sizeof *table->columns);
    core_free(table->components, table->component_count * sizeof *table->components);
    core_free(table->entities, table->capacity * sizeof *table->entities);
    core_free(table->edges, table->edge_capacity * sizeof *table->edges);
    core_free(table->observers, table->observer_capacity * sizeof *table->observers);
    core_free(table, sizeof *table);
}

ecs_table *ecs_table_for(ecs_world *world, const ecs_component *sorted, uint32_t count) {
    /* A linear search: edges cache every transition after its first use, so this runs once
     * per (table, component) pair, and a world has tens to hundreds of tables. */
    uint64_t hash = components_hash(sorted, count);
    for (uint32_t i = 0; i < world->table_count; i++) {
        ecs_table *table = world->tables[i];
        /* The empty table has no component array: memcmp may not be given its NULL. */
        if (table->hash == hash && table->component_count == count &&
            (count == 0 || memcmp(table->components, sorted, count * sizeof *sorted) == 0))
            return table;
    }
    return table_create(world, sorted, count, hash);
}

static ecs_edge *table_edge(ecs_table *table, ecs_component component) {
    if (component >= table->edge_capacity) {
        uint32_t old = table->edge_capacity;
        table->edges = ecs_grow(table->edges, &table->edge_capacity, component + 1,
                                sizeof *table->edges);
        memset(table->edges + old, 0, (table->edge_capacity - old) * sizeof *table->edges);
    }
    return &table->edges[component];
}

/* The table of `table`'s components plus `component` (which it lacks). */
static ecs_table *table_with(ecs_world *world, ecs_table *table, ecs_component component) {
    ecs_edge *edge = table_edge(table, component);
    if (edge->add) return edge->add;
    ecs_component set[table->component_count + 1];
    uint32_t set_count = 0, i = 0;
    while (i < table->component_count && table->components[i] < component)
        set[set_count++] = table->components[i++];
    set[set_count++] = component;
    while (i < table->component_count) set[set_count++] = table->components[i++];
    ecs_table *target = ecs_table_for(world, set, set_count);
    table_edge(table, component)->add = target;     /* the lookup may have grown edges */
    table_edge(target, component)->remove = table;
    return target;
}

/* The table of `table`'s components minus `component` (which it has). */
static ecs_table *table_without(ecs_world *world, ecs_table *table, ecs_component component) {
    ecs_edge *edge = table_edge(table, component);
    if (edge->remove) return edge->remove;
    ecs_component set[table->component_count];
    uint32_t set_count = 0;
    for (uint32_t i = 0; i < table->component_count; i++)
        if (table->components[i] != component) set[set_count++] = table->components[i];
    ecs_table *target = ecs_table_for(world, set, set_count);
    table_edge(table, component)->remove = target;
    table_edge(target, component)->add = table;
    return target;
}

/* ---- entity hooks: on_add, on_set, on_remove -------------------------------------------- */

/* Calls `fn` (one of the component's entity hooks, or NULL) with the data of the component in
 * `column` of the entity at `row`. The row is in place, so ecs_get works on the entity. */
static void hook_call(ecs_world *world, ecs_hook_fn fn, const ecs_table *table, uint32_t row,
                      uint32_t column) {
    if (!fn) return;
    const ecs_column *data = &table->columns[column];
    void *value = data->size ? column_at(data, row) : NULL;
    /* Inside a phase (on_set from a system's ecs_set) structure is frozen anyway, and workers
     * must not write the flag. */
    bool guard = !world->in_phase;
    if (guard) world->in_hook = true;
    fn(world, table->entities[row], value, column_hooks(world, table, column)->user);
    if (guard) world->in_hook = false;
}

static void hook_on_remove(ecs_world *world, const ecs_table *table, uint32_t row,
                           uint32_t column) {
    hook_call(world, column_hooks(world, table, column)->on_remove, table, row, column);
}

/* The entity at `row` is about to lose every component: its observers, then its on_remove
 * hooks. */
static void entity_leaving(ecs_world *world, const ecs_table *table, uint32_t row) {
    if (table->observer_count)
        ecs_observers_fire(world, table->entities[row], table, NULL, ECS_ON_REMOVE);
    for (uint32_t i = 0; i < table->component_count; i++) hook_on_remove(world, table, row, i);
}

/* ---- world ------------------------------------------------------------------------------ */

ecs_world *ecs_world_create(const ecs_world_desc *desc) {
    ecs_world *world = core_calloc(1, sizeof *world);
    world->jobs = desc ? desc->jobs : NULL;
    /* Index 0 of components and records is never used, so that id 0 can mean "none". */
    world->components = ecs_grow(NULL, &world->component_capacity, 16, sizeof *world->components);
    memset(world->components, 0, world->component_capacity * sizeof *world->components);
    world->component_count = 1;
    world->records = ecs_grow(NULL, &world->record_capacity, 1024, sizeof *world->records);
    memset(&world->records[0], 0, sizeof world->records[0]);
    world->record_count = 1;
    ecs_table_for(world, NULL, 0); /* tables[0]: entities without components */
    ecs_pipeline_init(world);
    return world;
}

void ecs_world_destroy(ecs_world *world) {
    if (!world) return;
    /* Every entity still alive loses its components here, so owners of resources get to free
     * them; first every observer and on_remove hook, while every table and record is whole,
     * then the destructors, a column at a time. */
    for (uint32_t t = 0; t < world->table_count; t++) {
        ecs_table *table = world->tables[t];
        if (!table->hooked && !table->observer_count) continue;
        for (uint32_t row = 0; row < table->count; row++) entity_leaving(world, table, row);
    }
    for (uint32_t t = 0; t < world->table_count; t++) {
        ecs_table *table = world->tables[t];
        if (!table->hooked) continue;
        for (uint32_t i = 0; i < table->component_count; i++)
            elements_destruct(column_hooks(world, table, i), &table->columns[i], 0, table->count);
    }
    ecs_scheduler_free(world);
    ecs_resources_free(world);
    ecs_observers_free(world);
    for (uint32_t i = 0; i < world->query_count; i++) ecs_query_free(world->queries[i]);
    core_free(world->queries, world->query_capacity * sizeof *world->queries);
    for (uint32_t i = 0; i < world->table_count; i++) table_free(world->tables[i]);
    core_free(world->tables, world->table_capacity * sizeof *world->tables);
    for (uint32_t i = 1; i < world->component_count; i++)
        core_free(world->components[i].name, strlen(world->components[i].name) + 1);
    core_free(world->components, world->component_capacity * sizeof *world->components);
    core_free(world->records, world->record_capacity * sizeof *world->records);
    core_arena_release(&world->frame);
    core_free(world, sizeof *world);
}

job_system *ecs_world_jobs(const ecs_world *world) { return world->jobs; }

/* ---- components ------------------------------------------------------------------------- */

ecs_component ecs_component_lookup(const ecs_world *world, const char *name) {
    for (uint32_t i = 1; i < world->component_count; i++)
        if (strcmp(world->components[i].name, name) == 0) return i;
    return 0;
}

ecs_component ecs_component_register(ecs_world *world, const ecs_component_desc *desc) {
    ECS_ASSERT_STRUCTURAL(world);
    assert(desc && desc->name && "a component needs a name");
    size_t align = desc->align ? desc->align : alignof(max_align_t);
    assert((align & (align - 1)) == 0 && align <= ECS_COLUMN_ALIGN);
    assert(desc->size % align == 0 && "size must be a multiple of the alignment");
    assert(desc->size <= UINT32_MAX);

    ecs_component existing = ecs_component_lookup(world, desc->name);
    if (existing) {
        assert(world->components[existing].size == desc->size && "registered with another size");
        return existing;
    }
    world->components = ecs_grow(world->components, &world->component_capacity,
                                 world->component_count + 1, sizeof *world->components);
    ecs_component id = world->component_count++;
    world->components[id] = (ecs_component_info){
        .name = core_strdup(desc->name), .size = (uint32_t)desc->size, .align = (uint32_t)align };
    return id;
}

size_t ecs_component_size(const ecs_world *world, ecs_component component) {
    ECS_ASSERT_COMPONENT(world, component);
    return world->components[component].size;
}

void ecs_component_set_hooks(ecs_world *world, ecs_component component, const ecs_hooks *hooks) {
    /* Set up like a registration: outside phases, and not from a hook (swapping hooks while an
     * entity's hooks run would make which of them ran hard to tell). */
    ECS_ASSERT_STRUCTURAL(world);
    ECS_ASSERT_COMPONENT(world, component);
    world->components[component].hooks = hooks ? *hooks : (ecs_hooks){ 0 };
    for (uint32_t i = 0; i < world->table_count; i++) table_update_hooked(world, world->tables[i]);
}

ecs_hooks ecs_component_hooks(const ecs_world *world, ecs_component component) {
    ECS_ASSERT_COMPONENT(world, component);
    return world->components[component].hooks;
}

void ecs_component_on_remove(ecs_world *world, ecs_component component, ecs_remove_fn fn,
                             void *user) {
    ECS_ASSERT_COMPONENT(world, component);
    ecs_hooks hooks = world->components[component].hooks;
    hooks.on_remove = fn;
    if (fn) hooks.user = user;
    ecs_component_set_hooks(world, component, &hooks);
}

/* ---- entities --------------------------------------------------------------------------- */

/* The record of a live entity, or NULL. */
static ecs_record *alive_record(const ecs_world *world, ecs_entity entity) {
    uint32_t index = ecs_id_index(entity);
    if (entity == 0 || ecs_id_is_placeholder(entity) || index >= world->record_count) return NULL;
    ecs_record *record = &world->records[index];
    if (!record->table || record->generation != ecs_id_generation(entity)) return NULL;
    return record;
}

bool ecs_is_alive(const ecs_world *world, ecs_entity entity) {
    return alive_record(world, entity) != NULL;
}

int ecs_entity_count(const ecs_world *world) { return world->alive_count; }

/* Takes a free index (the most recently freed first) or a new one. */
static ecs_entity id_take(ecs_world *world) {
    uint32_t index = world->free_head;
    if (index) {
        world->free_head = world->records[index].row;
    } else {
        assert(world->record_count < UINT32_MAX && "out of entity indices");
        world->records = ecs_grow(world->records, &world->record_capacity,
                                  world->record_count + 1, sizeof *world->records);
        index = world->record_count++;
        world->records[index].generation = 0;
    }
    world->alive_count++;
    return ecs_id_make(index, world->records[index].generation);
}

ecs_entity ecs_entity_create(ecs_world *world) {
    ECS_ASSERT_STRUCTURAL(world);
    ecs_entity entity = id_take(world);
    ecs_table *empty = world->tables[0];
    ecs_record *record = &world->records[ecs_id_index(entity)];
    record->table = empty;
    record->row = table_append(world, empty, entity);
    return entity;
}

void ecs_entity_destroy(ecs_world *world, ecs_entity entity) {
    ECS_ASSERT_STRUCTURAL(world);
    ecs_record *record = alive_record(world, entity);
    if (!record) return;
    ecs_table *table = record->table;
    if (table->hooked || table->observer_count) {
        entity_leaving(world, table, record->row);
        for (uint32_t i = 0; i < table->component_count; i++)
            elements_destruct(column_hooks(world, table, i), &table->columns[i], record->row, 1);
    }
    table_remove_row(world, table, record->row);
    /* A new generation makes every copy of the old id dead for good. */
    record->generation = (record->generation + 1) & ECS_GENERATION_MASK;
    record->table = NULL;
    record->row = world->free_head;
    world->free_head = ecs_id_index(entity);
    world->alive_count--;
}

/* Moves the row's elements to `to`: moved where both tables have the component, destructed
 * where only `from` has it, constructed where only `to` has it. Writes the columns of `to`
 * that were constructed into `added` and returns how many. */
static uint32_t row_transfer(ecs_world *world, ecs_table *from, uint32_t old_row, ecs_table *to,
                             uint32_t new_row, uint32_t *added) {
    uint32_t i = 0, j = 0, added_count = 0;
    while (i < from->component_count || j < to->component_count) {
        ecs_component a = i < from->component_count ? from->components[i] : UINT32_MAX;
        ecs_component b = j < to->component_count ? to->components[j] : UINT32_MAX;
        if (a == b) {
            ecs_column *dst = &to->columns[j];
            elements_move(column_hooks(world, to, j), column_at(dst, new_row),
                          column_at(&from->columns[i], old_row), 1, dst->size);
            i++, j++;
        } else if (a < b) {
            elements_destruct(column_hooks(world, from, i), &from->columns[i], old_row, 1);
            i++;
        } else {
            elements_construct(column_hooks(world, to, j), &to->columns[j], new_row, 1);
            added[added_count++] = j++;
        }
    }
    return added_count;
}

/* entity_move without hooks: copies what both tables have, zeroes what only `to` has. */
static void entity_move_plain(ecs_world *world, ecs_record *record, ecs_table *to) {
    ecs_table *from = record->table;
    uint32_t old_row = record->row;
    uint32_t new_row = table_append(world, to, from->entities[old_row]);
    uint32_t i = 0;
    for (uint32_t j = 0; j < to->component_count; j++) {
        while (i < from->component_count && from->components[i] < to->components[j]) i++;
        ecs_column *dst = &to->columns[j];
        if (!dst->size) continue;
        uint8_t *value = column_at(dst, new_row);
        if (i < from->component_count && from->components[i] == to->components[j])
            memcpy(value, column_at(&from->columns[i], old_row), dst->size);
        else
            memset(value, 0, dst->size);
    }
    table_remove_row(world, from, old_row);
    record->table = to;
    record->row = new_row;
    world->table_moves++;
}

/* entity_move with hooks or observers. In order: observers that stop matching, on_remove of
 * what `to` lacks, the row's move (with dtor and ctor), on_add of what `to` adds, observers
 * that start matching. Kept out of line: its stack frame (the VLA, the saved registers) would
 * otherwise slow the plain path that almost every move takes (ecs.create.1m.each). */
__attribute__((noinline)) static void entity_move_hooked(ecs_world *world, ecs_record *record,
                                                         ecs_table *to) {
    ecs_table *from = record->table;
    ecs_entity entity = from->entities[record->row];
    if (from->observer_count) ecs_observers_fire(world, entity, from, to, ECS_ON_REMOVE);
    for (uint32_t i = 0; i < from->component_count; i++)
        if (ecs_table_column_of(to, from->components[i]) < 0)
            hook_on_remove(world, from, record->row, i);

    uint32_t old_row = record->row;
    uint32_t new_row = table_append(world, to, entity);
    uint32_t added[to->component_count + 1];
    uint32_t added_count = row_transfer(world, from, old_row, to, new_row, added);
    table_remove_row(world, from, old_row);
    record->table = to;
    record->row = new_row;
    world->table_moves++;

    for (uint32_t k = 0; k < added_count; k++)
        hook_call(world, column_hooks(world, to, added[k])->on_add, to, new_row, added[k]);
    if (to->observer_count) ecs_observers_fire(world, entity, from, to, ECS_ON_ADD);
}

static void entity_move(ecs_world *world, ecs_record *record, ecs_table *to) {
    const ecs_table *from = record->table;
    /* The usual case: nothing to call, and the add/remove cost stays that of two memcpys. */
    if (!from->hooked && !to->hooked && !from->observer_count && !to->observer_count)
        entity_move_plain(world, record, to);
    else
        entity_move_hooked(world, record, to);
}

static void *record_data(const ecs_record *record, int column_index) {
    if (column_index < 0) return NULL;
    const ecs_column *column = &record->table->columns[column_index];
    return column->size ? column->data + (size_t)record->row * column->size : NULL;
}

void *ecs_add(ecs_world *world, ecs_entity entity, ecs_component component) {
    ECS_ASSERT_STRUCTURAL(world);
    ECS_ASSERT_COMPONENT(world, component);
    assert(!ecs_is_resource(world, component) && "a resource belongs to the world, not to an entity");
    ecs_record *record = alive_record(world, entity);
    assert(record && "ecs_add on a dead entity");
    if (!record) return NULL;
    int column = ecs_table_column_of(record->table, component);
    if (column < 0) {
        entity_move(world, record, table_with(world, record->table, component));
        column = ecs_table_column_of(record->table, component);
    }
    return record_data(record, column);
}

void ecs_set(ecs_world *world, ecs_entity entity, ecs_component component, const void *value) {
    /* Writing a component the entity has is not a structural change (systems may do it for
     * components they declare); only the add is. */
    ecs_access_check(world, component, true, "ecs_set");
    bool had = ecs_has(world, entity, component);
    void *data = had ? ecs_get(world, entity, component) : ecs_add(world, entity, component);
    if (data) memcpy(data, value, world->components[component].size);
    ecs_hook_fn on_set = world->components[component].hooks.on_set;
    if (!on_set) return;
    ecs_record *record = alive_record(world, entity);
    if (record)
        hook_call(world, on_set, record->table, record->row,
                  (uint32_t)ecs_table_column_of(record->table, component));
}

void ecs_remove(ecs_world *world, ecs_entity entity, ecs_component component) {
    ECS_ASSERT_STRUCTURAL(world);
    ECS_ASSERT_COMPONENT(world, component);
    ecs_record *record = alive_record(world, entity);
    int column = record ? ecs_table_column_of(record->table, component) : -1;
    if (column < 0) return;
    entity_move(world, record, table_without(world, record->table, component));
}

bool ecs_has(const ecs_world *world, ecs_entity entity, ecs_component component) {
    const ecs_record *record = alive_record(world, entity);
    return record && ecs_table_column_of(record->table, component) >= 0;
}

void *ecs_get(const ecs_world *world, ecs_entity entity, ecs_component component) {
    ecs_access_check(world, component, false, "ecs_get");
    const ecs_record *record = alive_record(world, entity);
    return record ? record_data(record, ecs_table_column_of(record->table, component)) : NULL;
}

/* ---- bulk creation ---------------------------------------------------------------------- */

typedef struct bulk_term {
    ecs_component component;
    const void *values;
} bulk_term;

static int bulk_term_compare(const void *a, const void *b) {
    ecs_component x = ((const bulk_term *)a)->component, y = ((const bulk_term *)b)->component;
    return (x > y) - (x < y);
}

/* The desc's components sorted by id (with their values alongside); returns how many. */
static uint32_t bulk_terms_sorted(const ecs_world *world, const ecs_bulk_desc *desc,
                                  bulk_term *terms) {
    (void)world; /* only the asserts read it */
    uint32_t count = 0;
    for (; count < ECS_MAX_TERMS && desc->components[count]; count++) {
        ECS_ASSERT_COMPONENT(world, desc->components[count]);
        terms[count] = (bulk_term){ desc->components[count], desc->values[count] };
    }
    qsort(terms, count, sizeof *terms, bulk_term_compare);
    for (uint32_t i = 1; i < count; i++)
        assert(terms[i].component != terms[i - 1].component && "component listed twice");
    return count;
}

/* Calls on_add of every column for rows first … first + count - 1; or, given the terms (in
 * column order), on_set of the columns that were given values. */
static void bulk_hooks(ecs_world *world, const ecs_table *table, uint32_t first, uint32_t count,
                       const bulk_term *terms) {
    for (uint32_t i = 0; i < table->component_count; i++) {
        const ecs_hooks *hooks = column_hooks(world, table, i);
        ecs_hook_fn fn = !terms ? hooks->on_add : terms[i].values ? hooks->on_set : NULL;
        if (!fn) continue;
        for (uint32_t k = 0; k < count; k++) hook_call(world, fn, table, first + k, i);
    }
}

void ecs_entity_create_many(ecs_world *world, const ecs_bulk_desc *desc) {
    ECS_ASSERT_STRUCTURAL(world);
    assert(desc && desc->count >= 0);
    bulk_term terms[ECS_MAX_TERMS];
    ecs_component set[ECS_MAX_TERMS];
    uint32_t term_count = bulk_terms_sorted(world, desc, terms);
    for (uint32_t i = 0; i < term_count; i++) set[i] = terms[i].component;

    ecs_table *table = ecs_table_for(world, set, term_count);
    uint32_t count = (uint32_t)desc->count, first = table->count;
    table_reserve(world, table, first + count);
    world->records = ecs_grow(world->records, &world->record_capacity,
                              world->record_count + count, sizeof *world->records);
    for (uint32_t k = 0; k < count; k++) {
        ecs_entity entity = id_take(world);
        world->records[ecs_id_index(entity)] = (ecs_record){
            .table = table, .row = first + k, .generation = ecs_id_generation(entity) };
        table->entities[first + k] = entity;
        if (desc->ids) desc->ids[k] = entity;
    }
    /* Whole columns at once: one ctor (or memset) and one memcpy per component instead of
     * one per entity. The same order as ecs_set on a missing component: construct, on_add,
     * observers, copy the value in, on_set. */
    for (uint32_t i = 0; i < term_count; i++) {
        const ecs_hooks *hooks = column_hooks(world, table, i);
        /* Zeroing what the values overwrite next would write the column twice; but on_add
         * and observers look at the entities before the values are in. */
        if (!terms[i].values || table->hooked || table->observer_count)
            elements_construct(hooks, &table->columns[i], first, count);
    }
    table->count = first + count;
    bulk_hooks(world, table, first, count, NULL);
    if (table->observer_count)
        for (uint32_t k = 0; k < count; k++)
            ecs_observers_fire(world, table->entities[first + k], NULL, table, ECS_ON_ADD);
    for (uint32_t i = 0; i < term_count; i++) {
        ecs_column *column = &table->columns[i];
        size_t bytes = (size_t)count * column->size;
        if (bytes && terms[i].values) memcpy(column_at(column, first), terms[i].values, bytes);
    }
    bulk_hooks(world, table, first, count, terms);
}

/* ---- stats ------------------------------------------------------------------------------ */

ecs_world_stats_info ecs_world_stats(const ecs_world *world) {
    ecs_world_stats_info stats = {
        .table_moves = world->table_moves,
        .entities = world->alive_count,
        .tables = (int)world->table_count,
        .components = (int)world->component_count - 1,
        .queries = (int)world->query_count,
        .systems = (int)world->system_count,
    };
    for (uint32_t i = 0; i < world->observer_count; i++) stats.observers += world->observers[i] != NULL;
    return stats;
}

void ecs_world_frame_end(ecs_world *world) {
    trace_counter("ecs.table_moves", (double)(world->table_moves - world->table_moves_reported));
    world->table_moves_reported = world->table_moves;
}
