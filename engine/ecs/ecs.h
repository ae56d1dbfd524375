/* ecs.h — entities, components, queries, command buffers, systems and phases.
 *
 * WORLD
 *     ecs_world *world = ecs_world_create(&(ecs_world_desc){ .jobs = jobs }); // NULL jobs: run
 *     ...                                                                     // on this thread
 *     ecs_world_destroy(world);
 *
 * COMPONENTS are plain structs registered at run time; a tag is a component of size 0.
 *     typedef struct Position { float x, y; } Position;
 *     ecs_component position = ECS_COMPONENT(world, Position);
 *     ecs_component frozen = ECS_TAG(world, Frozen);
 *   HOOKS. A component may have lifecycle hooks, all set at once (any may be NULL):
 *     ecs_component_set_hooks(world, mesh, &(ecs_hooks){
 *         .ctor = mesh_init,          // (data, count, user): new elements; NULL = zeroed
 *         .dtor = mesh_fini,          // (data, count, user): elements that go; NULL = nothing
 *         .move = mesh_move,          // (dst, src, count, user): NULL = memcpy; src is dead after
 *         .on_add = mesh_added,       // (world, entity, data, user): after it was added
 *         .on_set = mesh_changed,     // after ecs_set / ecs_defer_set copied a value in
 *         .on_remove = mesh_release,  // before it leaves the entity, before the dtor
 *         .user = renderer });
 *   ctor runs for every add (ecs_add, ecs_set of a missing component, ecs_entity_create_many,
 *   the same from a command buffer), dtor for every removal (ecs_remove, ecs_entity_destroy,
 *   ecs_world_destroy), move wherever a row's bytes move (to another table on add or remove,
 *   into a removed row's place, into a grown column). Each element is constructed, moved and
 *   destructed once per event; create_many, column growth and ecs_world_destroy pass whole
 *   runs of elements in one call. A value ecs_set copies in replaces the constructed bytes as
 *   they are (nothing is freed), so a component whose ctor allocates is filled through ecs_add
 *   and its fields, or takes its value over in on_set. A component that owns something (a GPU
 *   buffer, a mesh) releases it in on_remove or dtor: one place, whatever takes it away.
 *   ecs_component_on_remove(world, mesh, mesh_release, user) sets on_remove alone.
 *   Hooks run on the thread making the structural change (the ecs_progress thread, when
 *   command buffers are applied; on_set also in a system calling ecs_set), and may not change
 *   structure themselves (that asserts).
 *
 * ENTITIES are 64-bit ids: a 32-bit index and a 32-bit generation (0 is the null entity). A
 * destroyed entity's index is reused with a new generation, so an old id never reaches the
 * new entity: ecs_is_alive says false and ecs_get returns NULL.
 *     ecs_entity e = ecs_entity_create(world);
 *     ecs_set(world, e, position, &(Position){ 1, 2 });   // adds the component if missing
 *     Position *p = ecs_get(world, e, position);          // NULL if e lacks it or is dead
 *     ecs_remove(world, e, position);
 *     ecs_entity_destroy(world, e);
 *
 * QUERIES match every entity that has all `with` components and none of the `without` ones.
 * Fields are numbered: the `with` terms first, then the `optional` ones. An optional field is
 * NULL in tables that lack it (and a tag's field is always NULL: use ecs_field_is_set).
 *     ecs_query *moving = ecs_query_create(world, &(ecs_query_desc){
 *         .with = { position, velocity }, .without = { frozen }, .optional = { color } });
 *     ecs_iter it = ecs_query_iter(world, moving);
 *     while (ecs_query_next(&it)) {
 *         Position *p = ecs_field(&it, 0);
 *         Velocity *v = ecs_field(&it, 1);
 *         Color *c = ecs_field(&it, 2);                     // may be NULL
 *         for (int i = 0; i < it.count; i++) { p[i].x += v[i].x; p[i].y += v[i].y; }
 *     }
 *   Each step of the loop is one table: `it.count` entities whose fields are plain arrays.
 *   Do not add, remove, create or destroy while iterating; record commands instead.
 *
 * COMMANDS defer structural changes (create, destroy, add, set, remove). A system gets its own
 * buffer in it->commands; the scheduler applies all buffers at the end of the phase, in system
 * registration order and then batch order, so the result never depends on thread timing.
 *     ecs_entity chunk = ecs_defer_entity_create(it->commands);  // a placeholder id, see below
 *     ecs_defer_set(it->commands, chunk, position, &(Position){ 0, 0 });
 *     ecs_defer_entity_destroy(it->commands, it->entities[i]);
 *   Outside systems, a buffer of your own: ecs_commands_create, ecs_commands_apply, _destroy.
 *
 * SYSTEMS AND PHASES. A frame runs the phases in order; the default pipeline is
 *     input, game, stream, generate, stabilize, mesh, lod, cull, draw, background
 *   ("background" hands work to the job system once the frame is drawn, so that it runs while
 *   the main thread waits on the GPU instead of beside the frame's own work; on a CPU renderer
 *   such as llvmpipe, while the frame is rasterised.)
 *     static void move(ecs_iter *it) {
 *         while (ecs_query_next(it)) { ... }               // it->dt, it->user, it->commands
 *     }
 *     ecs_phase_add(world, "physics", "game");             // a new phase right after "game"
 *     ecs_system_add(world, &(ecs_system_desc){ .name = "move", .phase = "physics",
 *         .query = { .with = { position, velocity } }, .writes = { position }, .fn = move });
 *     ecs_progress(world, dt);                             // one frame, every phase in order
 *   A system reads its query's components unless it lists them in `writes`; components and
 *   resources it touches otherwise go in `reads` or `writes` too (see ACCESS). Within a phase,
 *   two systems conflict when one writes what the other reads or writes: conflicting systems
 *   run one after the other in registration order, the others run at the same time on the job
 *   system.
 *   `.main_thread` pins a system to the main thread (OpenGL); `.parallel` splits its query
 *   into batches of about `.batch_size` entities that run as parallel jobs, each batch with
 *   its own command buffer. Every phase and every system is a trace zone named after it.
 *   A phase whose systems took under 20 us in all last frame (and that has no system of
 *   several batches now) runs on the calling thread: waking workers would cost more.
 *
 * PLACEHOLDER IDS. ecs_defer_entity_create returns a placeholder that only the buffer it came from
 * understands: use it in later commands of that buffer; the real entity exists once the buffer
 * is applied. Real ids are handed out at apply time, in apply order, which is what keeps them
 * identical for any thread count. Do not store a placeholder in component data.
 *
 * OBSERVERS are called when an entity starts or stops matching a query because a component
 * was added or removed, or the entity was created (create_many) or destroyed (ecs_world_destroy
 * included):
 *     static void on_body(ecs_world *w, ecs_entity e, ecs_event event, void *user) { ... }
 *     ecs_observer body = ecs_observer_add(world, &(ecs_observer_desc){
 *         .query = { .with = { position, velocity }, .without = { frozen } },
 *         .events = ECS_ON_ADD | ECS_ON_REMOVE, .fn = on_body });
 *   ON_ADD comes after the entity moved into the matching table (ecs_get works, on_add hooks
 *   have run), ON_REMOVE before it leaves the last one (before on_remove hooks). A move
 *   between two matching tables calls nothing. Each table keeps the observers that match it,
 *   so moves between tables no observer cares about cost nothing more. Like hooks, observers
 *   run on the thread making the change and may not change structure.
 *
 * STATS. ecs_world_stats(world) counts entities, tables, queries, systems, observers and the rows
 * moved between tables since the world began (every add or remove that changes an entity's
 * component set); ecs_progress emits each frame's moves as the trace counter ecs.table_moves.
 *
 * RESOURCES are the world's singletons (the terrain world, the renderer, the input system, the
 * clock): one value per world, not per entity. A resource is registered like a component and
 * declared like one in a system's `reads` and `writes`, so two systems writing the same resource
 * never overlap while readers of it do.
 *     typedef struct Clock { double seconds; } Clock;
 *     ecs_component clock = ECS_RESOURCE(world, Clock);              // a zeroed value the world keeps
 *     ecs_component terrain = ecs_resource_register(world, &(ecs_resource_desc){
 *         .name = "terrain_world", .object = my_terrain });          // an object you own
 *     Clock *c = ecs_resource_get(world, clock);                     // in a system that declared it
 *     terrain_world *t = ecs_resource_get(world, terrain);           // the object itself
 *
 * ACCESS. A system reads its query's components and writes what it lists in `writes`; anything
 * else it touches (components through ecs_get or ecs_set, another query, a resource) goes in
 * `reads` or `writes`. Debug builds check it: ecs_get, ecs_set, ecs_query_iter and
 * ecs_resource_get on a component or resource the running system did not declare stop the
 * program with a message naming the system and the component. A system that declares nothing
 * at all (no query, no reads, no writes) is exclusive: it runs alone in its phase, after the
 * systems added before it and before those added after it, and may touch anything.
 *
 * THREADS. All calls that change the world's structure (and registering components, resources,
 * queries, phases and systems) belong to the thread that runs ecs_progress, outside a running
 * phase: while a phase runs, such a call is a programmer error and asserts. Inside a phase, a
 * system reads what it declares and writes only what it lists in `writes`.
 */
#ifndef ECS_H
#define ECS_H

#include <assert.h>
#include <stdalign.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "jobs/jobs.h"

enum {
    ECS_MAX_TERMS = 8,                       /* per list in a query: with, without, optional */
    ECS_MAX_FIELDS = 2 * ECS_MAX_TERMS,      /* with + optional */
    ECS_MAX_ACCESS = 16,                     /* per list in a system: reads, writes */
    ECS_DEFAULT_BATCH_SIZE = 4096,           /* entities per batch of a parallel system */
};

typedef uint64_t ecs_entity;                 /* 0 = none */
typedef uint32_t ecs_component;              /* 0 = none; also ends the term lists below */
typedef uint32_t ecs_system;                 /* 0 = none */

typedef struct ecs_world ecs_world;
typedef struct ecs_query ecs_query;
typedef struct ecs_commands ecs_commands;

/* ---- world ------------------------------------------------------------------------------ */

typedef struct ecs_world_desc {
    job_system *jobs;                        /* NULL = run every system on the calling thread */
} ecs_world_desc;

ecs_world *ecs_world_create(const ecs_world_desc *desc);   /* desc may be NULL */
void ecs_world_destroy(ecs_world *world);
job_system *ecs_world_jobs(const ecs_world *world);        /* for systems that spawn jobs */

/* ---- components ------------------------------------------------------------------------- */

typedef struct ecs_component_desc {
    const char *name;                        /* required, unique; copied */
    size_t size;                             /* 0 = a tag */
    size_t align;                            /* 0 = alignof(max_align_t) */
} ecs_component_desc;

/* Registering a name again returns the same component (the size must match). */
ecs_component ecs_component_register(ecs_world *world, const ecs_component_desc *desc);
ecs_component ecs_component_lookup(const ecs_world *world, const char *name); /* 0 = unknown */
size_t ecs_component_size(const ecs_world *world, ecs_component component);

/* Lifecycle hooks of a component (see COMPONENTS above). Every field may be NULL. They run on
 * the thread making the structural change, once per event, and may read and write components
 * but not change structure (that asserts). `count` elements lie back to back at `data`. */
typedef void (*ecs_hook_fn)(ecs_world *world, ecs_entity entity, void *data, void *user);
typedef struct ecs_hooks {
    void (*ctor)(void *data, int count, void *user);           /* NULL = zero the memory */
    void (*dtor)(void *data, int count, void *user);           /* NULL = nothing */
    void (*move)(void *dst, void *src, int count, void *user); /* NULL = memcpy; src is dead
                                                                  after (no dtor for it) */
    ecs_hook_fn on_add;      /* after the component was added and constructed */
    ecs_hook_fn on_set;      /* after ecs_set / ecs_defer_set copied a value in */
    ecs_hook_fn on_remove;   /* just before it leaves the entity, before its dtor */
    void *user;              /* passed to every hook above */
} ecs_hooks;

/* Replaces all of the component's hooks (hooks NULL clears them). Outside phases and hooks. */
void ecs_component_set_hooks(ecs_world *world, ecs_component component, const ecs_hooks *hooks);
ecs_hooks ecs_component_hooks(const ecs_world *world, ecs_component component);

typedef ecs_hook_fn ecs_remove_fn;
/* Sets only the on_remove hook (and the hooks' user when fn is not NULL); fn NULL clears it.
 * The hook gets the component's data just before the component leaves an entity:
 * ecs_remove, ecs_entity_destroy (directly or through a command buffer), and
 * ecs_world_destroy for every entity still holding it. Not called when ecs_set overwrites a
 * value. Tags (size 0) get data NULL. */
void ecs_component_on_remove(ecs_world *world, ecs_component component, ecs_remove_fn fn,
                             void *user);

#define ECS_COMPONENT(world, Type)                                                             \
    ecs_component_register((world), &(ecs_component_desc){                                    \
        .name = #Type, .size = sizeof(Type), .align = alignof(Type) })
#define ECS_TAG(world, Name) ecs_component_register((world), &(ecs_component_desc){ .name = #Name })

/* ---- resources -------------------------------------------------------------------------- */

typedef struct ecs_resource_desc {
    const char *name;                        /* required, unique among components and resources */
    size_t size;                             /* a value the world keeps, zeroed; or */
    size_t align;                            /* 0 = alignof(max_align_t) */
    void *object;                            /* an object the caller owns (size 0): the world
                                                keeps the pointer, never frees it */
} ecs_resource_desc;

/* Registering a name again returns the same resource; for an object resource it also points it
 * at the new object (a world that outlives what it names can be given the next one). */
ecs_component ecs_resource_register(ecs_world *world, const ecs_resource_desc *desc);
/* The world's copy of a value resource, or the object of an object resource. */
void *ecs_resource_get(const ecs_world *world, ecs_component resource);
/* Copies `value` into a value resource (declared in `writes` when called from a system). */
void ecs_resource_set(ecs_world *world, ecs_component resource, const void *value);
bool ecs_is_resource(const ecs_world *world, ecs_component id);

#define ECS_RESOURCE(world, Type)                                                              \
    ecs_resource_register((world), &(ecs_resource_desc){                                      \
        .name = #Type, .size = sizeof(Type), .align = alignof(Type) })

/* ---- entities --------------------------------------------------------------------------- */

ecs_entity ecs_entity_create(ecs_world *world);
void ecs_entity_destroy(ecs_world *world, ecs_entity entity);      /* dead ids are ignored */
bool ecs_is_alive(const ecs_world *world, ecs_entity entity);
int ecs_entity_count(const ecs_world *world);                      /* alive entities */

/* Returns the component's data, zeroed if it was just added (tags: NULL). */
void *ecs_add(ecs_world *world, ecs_entity entity, ecs_component component);
/* Copies `value` into the component, adding it first if missing. Inside a phase only the copy
 * is allowed (a component the entity has, declared in the system's writes). */
void ecs_set(ecs_world *world, ecs_entity entity, ecs_component component, const void *value);
void ecs_remove(ecs_world *world, ecs_entity entity, ecs_component component);
bool ecs_has(const ecs_world *world, ecs_entity entity, ecs_component component);
/* NULL when the entity is dead, lacks the component, or the component is a tag. */
void *ecs_get(const ecs_world *world, ecs_entity entity, ecs_component component);

/* Creates `count` entities straight into the table of `components`, without moving them
 * through the tables in between: the fast path for spawning many alike entities. */
typedef struct ecs_bulk_desc {
    int count;
    ecs_component components[ECS_MAX_TERMS]; /* ends at the first 0 */
    const void *values[ECS_MAX_TERMS];       /* per component `count` values; NULL = zeroed */
    ecs_entity *ids;                         /* optional: receives the `count` new ids */
} ecs_bulk_desc;
void ecs_entity_create_many(ecs_world *world, const ecs_bulk_desc *desc);

/* ---- queries ---------------------------------------------------------------------------- */

typedef struct ecs_query_desc {
    ecs_component with[ECS_MAX_TERMS];       /* each list ends at the first 0 */
    ecs_component without[ECS_MAX_TERMS];
    ecs_component optional[ECS_MAX_TERMS];
} ecs_query_desc;

/* The world owns queries (freed with it). A query remembers its matching tables and picks up
 * tables created later. An empty desc matches every entity. */
ecs_query *ecs_query_create(ecs_world *world, const ecs_query_desc *desc);
void ecs_query_destroy(ecs_world *world, ecs_query *query);
int ecs_query_count(const ecs_world *world, const ecs_query *query); /* matching entities */

typedef struct ecs_iter {
    ecs_world *world;
    const ecs_entity *entities;              /* `count` entities of the current table */
    int count;
    float dt;                                /* in systems: the frame's delta time, seconds */
    ecs_commands *commands;                  /* in systems: this invocation's own buffer */
    void *user;                              /* in systems: ecs_system_desc.user */
    void *fields[ECS_MAX_FIELDS];            /* read through ecs_field */
    struct {                                 /* private: where the iteration stands */
        const ecs_query *query;
        uint32_t match;                      /* next matched table */
        uint32_t row;                        /* first row to visit in it */
        uint32_t remaining;                  /* entities left in this iteration's range */
        uint32_t present;                    /* bit f: the current table has field f */
    } internal;
} ecs_iter;

ecs_iter ecs_query_iter(ecs_world *world, const ecs_query *query);
bool ecs_query_next(ecs_iter *it);

static inline void *ecs_field(const ecs_iter *it, int index) {
    assert(index >= 0 && index < ECS_MAX_FIELDS);
    return it->fields[index];
}
/* True when the current table has the field's component (for optional tags). */
static inline bool ecs_field_is_set(const ecs_iter *it, int index) {
    assert(index >= 0 && index < ECS_MAX_FIELDS);
    return (it->internal.present >> index) & 1u;
}

/* A range of a query's matches: `count` entities starting at `row` of matched table `match`,
 * running on into the following tables. Valid until the world's structure next changes. */
typedef struct ecs_batch {
    uint32_t match, row, count;
} ecs_batch;

/* Splits the matches into consecutive batches of `batch_size` entities (the last may be
 * smaller), writes up to `capacity` of them and returns how many there are in all. */
int ecs_query_batches(const ecs_world *world, const ecs_query *query, int batch_size,
                      ecs_batch *batches, int capacity);
ecs_iter ecs_batch_iter(ecs_world *world, const ecs_query *query, ecs_batch batch);

/* ---- observers ---------------------------------------------------------------------------- */

/* An observer is called when an entity starts matching its query (ECS_ON_ADD) or stops
 * matching it (ECS_ON_REMOVE) because a component was added or removed, the entity was created
 * with ecs_entity_create_many or destroyed, or the world is destroyed. ON_ADD runs after the
 * entity moved into the matching table and after its on_add hooks, ON_REMOVE before it leaves
 * the last matching table and before its on_remove hooks. The query needs a `with` term;
 * `optional` terms are ignored. Like hooks, observers run on the thread making the change and
 * may not change structure. */
typedef uint32_t ecs_observer;               /* 0 = none */
typedef enum ecs_event { ECS_ON_ADD = 1, ECS_ON_REMOVE = 2 } ecs_event; /* bit flags */
typedef void (*ecs_observer_fn)(ecs_world *world, ecs_entity entity, ecs_event event,
                                void *user);
typedef struct ecs_observer_desc {
    const char *name;                        /* for messages; copied; NULL = "observer" */
    ecs_query_desc query;
    uint32_t events;                         /* ECS_ON_ADD | ECS_ON_REMOVE; 0 = both */
    ecs_observer_fn fn;                      /* required */
    void *user;
} ecs_observer_desc;

ecs_observer ecs_observer_add(ecs_world *world, const ecs_observer_desc *desc);
void ecs_observer_remove(ecs_world *world, ecs_observer observer);   /* 0 is ignored */

/* ---- stats ------------------------------------------------------------------------------ */

typedef struct ecs_world_stats_info {
    uint64_t table_moves;                    /* rows moved between tables (archetype changes)
                                                since the world was created */
    int entities, tables, components, queries, systems, observers;
} ecs_world_stats_info;
/* ecs_progress also emits the moves of each frame as the trace counter "ecs.table_moves". */
ecs_world_stats_info ecs_world_stats(const ecs_world *world);

/* ---- commands --------------------------------------------------------------------------- */

ecs_commands *ecs_commands_create(ecs_world *world);
void ecs_commands_destroy(ecs_commands *commands);
/* Applies the commands in the order they were recorded, then empties the buffer. Commands on
 * entities that died meanwhile are skipped (two systems may both destroy the same entity). */
void ecs_commands_apply(ecs_commands *commands);
int ecs_commands_count(const ecs_commands *commands);

ecs_entity ecs_defer_entity_create(ecs_commands *commands);                 /* returns a placeholder */
void ecs_defer_entity_destroy(ecs_commands *commands, ecs_entity entity);
void ecs_defer_add(ecs_commands *commands, ecs_entity entity, ecs_component component);
void ecs_defer_set(ecs_commands *commands, ecs_entity entity, ecs_component component,
                   const void *value);
void ecs_defer_remove(ecs_commands *commands, ecs_entity entity, ecs_component component);

/* ---- phases and systems ----------------------------------------------------------------- */

typedef void (*ecs_system_fn)(ecs_iter *it);

typedef struct ecs_system_desc {
    const char *name;                        /* trace zone name; copied */
    const char *phase;                       /* required: an existing phase */
    ecs_query_desc query;                    /* empty: no query, fn is called once */
    ecs_component reads[ECS_MAX_ACCESS];     /* components and resources, besides the query's */
    ecs_component writes[ECS_MAX_ACCESS];    /* nothing at all declared: exclusive (see ACCESS) */
    ecs_system_fn fn;                        /* required */
    void *user;
    bool main_thread;                        /* always run on the main thread */
    bool parallel;                           /* split the query into batches run as jobs */
    int batch_size;                          /* 0 = ECS_DEFAULT_BATCH_SIZE */
} ecs_system_desc;

/* Inserts phase `name` right after phase `after`. False (and an error logged) when `after`
 * does not exist or `name` already does. */
bool ecs_phase_add(ecs_world *world, const char *name, const char *after);
/* Returns 0 (and logs an error) when the phase does not exist. */
ecs_system ecs_system_add(ecs_world *world, const ecs_system_desc *desc);

/* A disabled system is skipped by ecs_progress (its phase runs as if it had none) until enabled
 * again: for code that owns a system's `user` and goes away before the world does. */
void ecs_system_enable(ecs_world *world, ecs_system system, bool enabled);

/* Runs one frame: every phase in order, applying the phase's command buffers at its end.
 * Call from the thread that created the job system. */
void ecs_progress(ecs_world *world, float dt);

#endif /* ECS_H */
