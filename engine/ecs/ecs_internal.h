/* ecs_internal.h — the ECS's private structures, shared by the files of engine/ecs/.
 *
 * Storage is by archetype: one table per distinct set of components. A table holds its
 * entities in one array and each component in one contiguous column, row i of every column
 * belonging to entities[i]. An entity's record says which table and row hold it. Adding or
 * removing a component moves the entity to the table of the new set; each table caches, per
 * component, the table that adding or removing it leads to (its edges).
 */
#ifndef ECS_INTERNAL_H
#define ECS_INTERNAL_H

#include "ecs.h"

#include "core/core.h"

/* ---- ids -------------------------------------------------------------------------------- */

/* The generation's top bit marks a placeholder from ecs_defer_entity_create; real generations use
 * the low 31 bits and wrap, so a real id never looks like a placeholder. */
#define ECS_PLACEHOLDER_BIT (1ull << 63)
#define ECS_GENERATION_MASK 0x7fffffffu

static inline uint32_t ecs_id_index(ecs_entity e) { return (uint32_t)e; }
static inline uint32_t ecs_id_generation(ecs_entity e) { return (uint32_t)(e >> 32); }
static inline ecs_entity ecs_id_make(uint32_t index, uint32_t generation) {
    return (ecs_entity)generation << 32 | index;
}
static inline bool ecs_id_is_placeholder(ecs_entity e) { return (e & ECS_PLACEHOLDER_BIT) != 0; }

/* ---- components ------------------------------------------------------------------------- */

typedef struct ecs_component_info {
    char *name;
    uint32_t size, align;
    ecs_hooks hooks;                 /* all NULL = plain bytes, nothing to call */
} ecs_component_info;

/* ---- tables ----------------------------------------------------------------------------- */

/* Columns start on a cache line: a fresh line for every column keeps vector loads aligned and
 * keeps two columns from sharing a line that two threads write. */
enum { ECS_COLUMN_ALIGN = 64 };

typedef struct ecs_column {
    uint8_t *data;          /* table->capacity elements, ECS_COLUMN_ALIGN-ed; NULL for tags */
    uint32_t size;          /* bytes per element; 0 for tags */
} ecs_column;

typedef struct ecs_table ecs_table;

typedef struct ecs_edge {
    ecs_table *add, *remove; /* NULL = not looked up yet */
} ecs_edge;

struct ecs_table {
    uint32_t index;                  /* position in world->tables */
    uint64_t hash;                   /* of the component set, for lookup */
    ecs_component *components;       /* sorted ascending */
    uint32_t component_count;
    ecs_column *columns;             /* columns[i] holds components[i] */
    ecs_entity *entities;
    uint32_t count, capacity;
    bool hooked;                     /* some component has hooks: moves take the slow path */
    ecs_edge *edges;                 /* indexed by component id */
    uint32_t edge_capacity;
    struct ecs_observer_info **observers; /* those whose query matches, in registration order:
                                             none (the usual case) costs a move nothing */
    uint32_t observer_count, observer_capacity;
};

/* Index of `component` among the table's columns, or -1. */
int ecs_table_column_of(const ecs_table *table, ecs_component component);

/* ---- entities --------------------------------------------------------------------------- */

typedef struct ecs_record {
    ecs_table *table;       /* NULL = free slot */
    uint32_t row;           /* in a free slot: the next free index (0 = end of the list) */
    uint32_t generation;
} ecs_record;

/* ---- queries ---------------------------------------------------------------------------- */

typedef struct ecs_query_match {
    ecs_table *table;
    int16_t columns[ECS_MAX_FIELDS]; /* column of each field in the table, -1 = absent */
} ecs_query_match;

struct ecs_query {
    ecs_component with[ECS_MAX_TERMS], without[ECS_MAX_TERMS], optional[ECS_MAX_TERMS];
    int with_count, without_count, optional_count;
    ecs_query_match *matches;        /* in table creation order */
    uint32_t match_count, match_capacity;
};

/* Adds `table` to the query's matches if it matches. */
void ecs_query_consider_table(ecs_query *query, ecs_table *table);
/* Whether the table has every `with` term and no `without` term. */
bool ecs_query_matches_table(const ecs_query *query, const ecs_table *table);
/* Fills a query's terms from a desc, without registering it with the world (no matches). */
void ecs_query_terms_init(ecs_query *query, const ecs_world *world, const ecs_query_desc *desc);
void ecs_query_free(ecs_query *query);

/* ---- observers -------------------------------------------------------------------------- */

typedef struct ecs_observer_info {
    char *name;
    ecs_query terms;                 /* with and without only; its matches stay empty */
    uint32_t events;
    ecs_observer_fn fn;
    void *user;
} ecs_observer_info;

/* Offers a new table to every observer. */
void ecs_observers_table_created(ecs_world *world, ecs_table *table);
/* Calls, for `entity` going from table `from` to table `to` (either may be NULL: created,
 * destroyed), the observers of `event` that match the table it leaves (ON_REMOVE) or enters
 * (ON_ADD) but not the other one. */
void ecs_observers_fire(ecs_world *world, ecs_entity entity, const ecs_table *from,
                        const ecs_table *to, ecs_event event);
void ecs_observers_free(ecs_world *world);

/* ---- commands --------------------------------------------------------------------------- */

typedef enum ecs_command_kind {
    ECS_COMMAND_CREATE,
    ECS_COMMAND_DESTROY,
    ECS_COMMAND_ADD,
    ECS_COMMAND_SET,
    ECS_COMMAND_REMOVE,
} ecs_command_kind;

typedef struct ecs_command {
    ecs_command_kind kind;
    ecs_component component;
    ecs_entity entity;               /* real id or placeholder of this buffer */
    size_t value_offset;             /* SET: where the value starts in commands->values */
} ecs_command;

struct ecs_commands {
    ecs_world *world;
    uint32_t serial;                 /* stamped into placeholders; changes on every reset */
    ecs_command *list;
    uint32_t count, capacity;
    uint8_t *values;                 /* SET values, back to back */
    size_t values_size, values_capacity;
    uint32_t placeholder_count;
    ecs_entity *resolved;            /* apply-time scratch: placeholder → real id */
    uint32_t resolved_capacity;
};

/* Empties the buffer and gives it a new serial (main thread, outside phases). */
void ecs_commands_reset(ecs_commands *commands);

/* ---- systems and phases ----------------------------------------------------------------- */

typedef struct ecs_system_info ecs_system_info;

typedef struct ecs_phase {
    char *name;
    const char *trace_name;          /* trace_intern'ed: outlives the world */
    ecs_system_info **systems;       /* in registration order */
    uint32_t system_count, system_capacity;
    uint64_t work_ns;                /* its systems' time in the last frame (UINT64_MAX: not
                                        run yet): light phases run on the calling thread */
} ecs_phase;

void ecs_scheduler_free(ecs_world *world);
void ecs_pipeline_init(ecs_world *world);

/* ---- resources and access --------------------------------------------------------------- */

/* A resource's storage. Its id comes from the component id space, so that systems list it in
 * their reads and writes and the conflict graph treats it like a component. */
typedef struct ecs_resource_slot {
    ecs_component id;
    void *data;                      /* the value the world keeps, or the caller's object */
    size_t size;                     /* 0 = an object the caller owns */
    size_t allocated;                /* bytes of `data` the world allocated (0 for objects) */
} ecs_resource_slot;

const ecs_resource_slot *ecs_resource_slot_of(const ecs_world *world, ecs_component id);
void ecs_resources_free(ecs_world *world);

/* Debug builds: stops with a message naming the running system and the component when the
 * system on this thread did not declare the access (reads or writes; `write`: writes). Nothing
 * outside systems, nor in systems that declared nothing (they run alone in their phase). */
#ifndef NDEBUG
void ecs_access_check(const ecs_world *world, ecs_component component, bool write, const char *call);
void ecs_access_check_query(const ecs_world *world, const ecs_query *query);
#else
#define ecs_access_check(world, component, write, call) ((void)0)
#define ecs_access_check_query(world, query) ((void)0)
#endif

/* ---- the world -------------------------------------------------------------------------- */

struct ecs_world {
    job_system *jobs;

    ecs_component_info *components;  /* indexed by id; [0] unused */
    uint32_t component_count, component_capacity;

    ecs_record *records;             /* indexed by entity index; [0] unused */
    uint32_t record_count, record_capacity;
    uint32_t free_head;              /* first free index, 0 = none */
    int alive_count;

    ecs_table **tables;              /* [0] is the empty table */
    uint32_t table_count, table_capacity;

    ecs_query **queries;
    uint32_t query_count, query_capacity;

    ecs_phase *phases;               /* in frame order */
    uint32_t phase_count, phase_capacity;
    ecs_system_info **systems;       /* in registration order; ecs_system is index + 1 */
    uint32_t system_count, system_capacity;

    ecs_observer_info **observers;   /* ecs_observer is index + 1; NULL = removed */
    uint32_t observer_count, observer_capacity;

    uint64_t table_moves;            /* rows moved between tables, ever (ecs_world_stats_info) */
    uint64_t table_moves_reported;   /* table_moves at the last ecs.table_moves counter */

    core_arena frame;                /* scheduler scratch, reset every phase */
    bool in_phase;                   /* a phase is running: structural calls assert */
    bool in_hook;                    /* a hook or observer runs: structural calls assert */
    uint32_t command_serial;

    ecs_resource_slot *resources;    /* in registration order (a handful: scanned) */
    uint32_t resource_count, resource_capacity;
};

/* Asserts that the world's structure may change now. A hook runs in the middle of a change
 * (the entity's row is about to move or go), so it may not start another. */
#define ECS_ASSERT_STRUCTURAL(world)                                                          \
    do {                                                                                      \
        assert(!(world)->in_phase && "structural change while a phase runs: use it->commands"); \
        assert(!(world)->in_hook && "structural change inside a hook or observer");            \
    } while (0)

#define ECS_ASSERT_COMPONENT(world, component)                                                \
    assert((component) > 0 && (component) < (world)->component_count && "unknown component")

ecs_table *ecs_table_for(ecs_world *world, const ecs_component *sorted, uint32_t count);
/* Emits this frame's table moves as the trace counter "ecs.table_moves" (ecs_progress). */
void ecs_world_frame_end(ecs_world *world);
/* Returns `items` (an array of `*capacity` elements) grown to hold at least `needed`. */
void *ecs_grow(void *items, uint32_t *capacity, uint32_t needed, size_t item_size);

#endif /* ECS_INTERNAL_H */
