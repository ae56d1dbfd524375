/* query.c — queries: which tables match, iteration over them, and batches for jobs. */
#include "ecs_internal.h"

#include <string.h>

/* Copies a 0-terminated term list and returns its length. */
static int copy_terms(ecs_component *to, const ecs_component *from, const ecs_world *world) {
    (void)world; /* only the assert reads it */
    int count = 0;
    for (; count < ECS_MAX_TERMS && from[count]; count++) {
        assert(from[count] < world->component_count && "unknown component in a query");
        to[count] = from[count];
    }
    return count;
}

void ecs_query_terms_init(ecs_query *query, const ecs_world *world, const ecs_query_desc *desc) {
    query->with_count = copy_terms(query->with, desc->with, world);
    query->without_count = copy_terms(query->without, desc->without, world);
    query->optional_count = copy_terms(query->optional, desc->optional, world);
}

ecs_query *ecs_query_create(ecs_world *world, const ecs_query_desc *desc) {
    ECS_ASSERT_STRUCTURAL(world);
    ecs_query *query = core_calloc(1, sizeof *query);
    if (desc) ecs_query_terms_init(query, world, desc);
    for (uint32_t i = 0; i < world->table_count; i++)
        ecs_query_consider_table(query, world->tables[i]);
    world->queries = ecs_grow(world->queries, &world->query_capacity, world->query_count + 1,
                              sizeof *world->queries);
    world->queries[world->query_count++] = query;
    return query;
}

void ecs_query_free(ecs_query *query) {
    core_free(query->matches, query->match_capacity * sizeof *query->matches);
    core_free(query, sizeof *query);
}

void ecs_query_destroy(ecs_world *world, ecs_query *query) {
    ECS_ASSERT_STRUCTURAL(world);
    for (uint32_t i = 0; i < world->query_count; i++) {
        if (world->queries[i] != query) continue;
        memmove(&world->queries[i], &world->queries[i + 1],
                (world->query_count - i - 1) * sizeof *world->queries);
        world->query_count--;
        ecs_query_free(query);
        return;
    }
    assert(!"ecs_query_destroy: not a query of this world");
}

bool ecs_query_matches_table(const ecs_query *query, const ecs_table *table) {
    for (int i = 0; i < query->with_count; i++)
        if (ecs_table_column_of(table, query->with[i]) < 0) return false;
    for (int i = 0; i < query->without_count; i++)
        if (ecs_table_column_of(table, query->without[i]) >= 0) return false;
    return true;
}

void ecs_query_consider_table(ecs_query *query, ecs_table *table) {
    if (!ecs_query_matches_table(query, table)) return;

    ecs_query_match match = { .table = table };
    for (int i = 0; i < query->with_count; i++)
        match.columns[i] = (int16_t)ecs_table_column_of(table, query->with[i]);
    for (int i = 0; i < query->optional_count; i++)
        match.columns[query->with_count + i] =
            (int16_t)ecs_table_column_of(table, query->optional[i]);
    query->matches = ecs_grow(query->matches, &query->match_capacity, query->match_count + 1,
                              sizeof *query->matches);
    query->matches[query->match_count++] = match;
}

int ecs_query_count(const ecs_world *world, const ecs_query *query) {
    (void)world;
    size_t total = 0;
    for (uint32_t i = 0; i < query->match_count; i++) total += query->matches[i].table->count;
    return (int)total;
}

/* ---- iteration -------------------------------------------------------------------------- */

static ecs_iter iter_range(ecs_world *world, const ecs_query *query, uint32_t match,
                           uint32_t row, uint32_t count) {
    return (ecs_iter){ .world = world,
                       .internal = { .query = query, .match = match, .row = row,
                                     .remaining = count } };
}

ecs_iter ecs_query_iter(ecs_world *world, const ecs_query *query) {
    ecs_access_check_query(world, query);
    return iter_range(world, query, 0, 0, UINT32_MAX);
}

ecs_iter ecs_batch_iter(ecs_world *world, const ecs_query *query, ecs_batch batch) {
    return iter_range(world, query, batch.match, batch.row, batch.count);
}

/* Points the iterator's fields at `row` of the matched table. */
static void iter_point_fields(ecs_iter *it, const ecs_query_match *match, uint32_t row) {
    const ecs_query *query = it->internal.query;
    int field_count = query->with_count + query->optional_count;
    uint32_t present = 0;
    for (int f = 0; f < field_count; f++) {
        int column_index = match->columns[f];
        it->fields[f] = NULL;
        if (column_index < 0) continue;
        present |= 1u << f;
        const ecs_column *column = &match->table->columns[column_index];
        if (column->size) it->fields[f] = column->data + (size_t)row * column->size;
    }
    it->internal.present = present;
}

bool ecs_query_next(ecs_iter *it) {
    const ecs_query *query = it->internal.query;
    while (query && it->internal.remaining && it->internal.match < query->match_count) {
        const ecs_query_match *match = &query->matches[it->internal.match++];
        uint32_t row = it->internal.row;
        it->internal.row = 0;
        uint32_t rows = match->table->count;
        if (row >= rows) continue;   /* empty tables are part of the cache; skip them */
        uint32_t count = CORE_MIN(rows - row, it->internal.remaining);
        it->internal.remaining -= count;
        iter_point_fields(it, match, row);
        it->entities = match->table->entities + row;
        it->count = (int)count;
        return true;
    }
    it->entities = NULL;
    it->count = 0;
    return false;
}

/* ---- batches ---------------------------------------------------------------------------- */

int ecs_query_batches(const ecs_world *world, const ecs_query *query, int batch_size,
                      ecs_batch *batches, int capacity) {
    (void)world;
    assert(batch_size > 0);
    int batch_count = 0;
    uint32_t size = (uint32_t)batch_size, filled = size; /* filled == size: start a new one */
    for (uint32_t match = 0; match < query->match_count; match++) {
        uint32_t rows = query->matches[match].table->count;
        for (uint32_t row = 0; row < rows;) {
            if (filled == size) {
                if (batch_count < capacity)
                    batches[batch_count] = (ecs_batch){ .match = match, .row = row };
                batch_count++;
                filled = 0;
            }
            /* A batch runs on across tables until it holds batch_size entities. */
            uint32_t take = CORE_MIN(rows - row, size - filled);
            if (batch_count <= capacity) batches[batch_count - 1].count += take;
            filled += take;
            row += take;
        }
    }
    return batch_count;
}
