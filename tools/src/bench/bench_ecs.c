/* bench_ecs.c — ECS rows: iterating a two-component query beside two bare arrays (the memory
 * bandwidth limit), and creating a million entities.
 *
 *   ecs.iterate.1m        ns per entity for position += velocity over 1M entities, via a query
 *   ecs.iterate.1m.raw    the same update over two plain arrays
 *   ecs.iterate.1m.ratio  ours / raw, run by run (target ≤ 1.2)
 *   ecs.create.1m         ms to create 1M entities with Position and Velocity (bulk path)
 *   ecs.create.1m.each    the same one entity at a time (ecs_entity_create + 2 × ecs_set)
 *   ecs.progress.100systems  µs per ecs_progress: 100 trivial systems over the 9 default
 *                         phases, half of them parallel, 1000 entities, a job system with
 *                         --threads threads (target ≤ 30: the scheduling a game pays a frame)
 *   ecs.hooks.add_remove  ns per ecs_add + ecs_remove of a component with ctor, dtor, on_add
 *                         and on_remove hooks (the entity's row moves twice)
 *   ecs.add_remove        the same without hooks, in the same run
 */
#include "bench.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"

typedef struct Position { float x, y; } Position;
typedef struct Velocity { float x, y; } Velocity;

enum { ENTITIES = 1000000, PASSES = 8, RUNS = 15 };

/* The update both rows run, so the rows differ only in where the arrays come from.
 * The loop is split at a multiple of 8 because GCC 12 at -O2 (its "very cheap" vectoriser
 * cost model) vectorises a loop only when its trip count is known to be a multiple of the
 * vector width; the bulk loop then compiles to packed SSE adds, the tail to at most 7 scalar
 * steps. A table's count is known only at run time, so an ECS loop needs this to vectorise. */
static inline void move(Position *restrict p, const Velocity *restrict v, int count) {
    int bulk = count & ~7;
    for (int i = 0; i < bulk; i++) {
        p[i].x += v[i].x;
        p[i].y += v[i].y;
    }
    for (int i = bulk; i < count; i++) {
        p[i].x += v[i].x;
        p[i].y += v[i].y;
    }
}

static void fill(Position *p, Velocity *v, int count) {
    for (int i = 0; i < count; i++) {
        p[i] = (Position){ (float)i, (float)-i };
        v[i] = (Velocity){ 0.5f, 0.25f };
    }
}

/* ---- iterate ---------------------------------------------------------------------------- */

typedef struct iterate_state {
    ecs_world *world;
    ecs_query *moving;
    Position *positions;   /* the bare arrays */
    Velocity *velocities;
} iterate_state;

static double sample_query(iterate_state *s) {
    uint64_t start = core_time_ns();
    for (int pass = 0; pass < PASSES; pass++) {
        ecs_iter it = ecs_query_iter(s->world, s->moving);
        while (ecs_query_next(&it)) move(ecs_field(&it, 0), ecs_field(&it, 1), it.count);
    }
    return (double)(core_time_ns() - start) / ((double)PASSES * ENTITIES);
}

static double sample_raw(iterate_state *s) {
    uint64_t start = core_time_ns();
    for (int pass = 0; pass < PASSES; pass++) move(s->positions, s->velocities, ENTITIES);
    return (double)(core_time_ns() - start) / ((double)PASSES * ENTITIES);
}

static void bench_iterate(bench_context *ctx) {
    if (!bench_wants(ctx, "ecs.iterate.1m")) return;
    iterate_state s = { .world = ecs_world_create(NULL) };
    ecs_component position = ECS_COMPONENT(s.world, Position);
    ecs_component velocity = ECS_COMPONENT(s.world, Velocity);
    s.positions = core_alloc(ENTITIES * sizeof *s.positions);
    s.velocities = core_alloc(ENTITIES * sizeof *s.velocities);
    fill(s.positions, s.velocities, ENTITIES);
    ecs_entity_create_many(s.world, &(ecs_bulk_desc){ .count = ENTITIES,
        .components = { position, velocity }, .values = { s.positions, s.velocities } });
    s.moving = ecs_query_create(s.world, &(ecs_query_desc){ .with = { position, velocity } });

    /* Interleaved runs: both rows see the same machine state, and each ratio compares two
     * samples taken a moment apart. */
    double ours[RUNS], raw[RUNS], ratio[RUNS];
    bench_consume(sample_query(&s) + sample_raw(&s)); /* warm-up */
    for (int r = 0; r < RUNS; r++) {
        ours[r] = sample_query(&s);
        raw[r] = sample_raw(&s);
        ratio[r] = ours[r] / raw[r];
    }
    bench_consume(s.positions[ENTITIES / 2].x);
    bench_record(ctx, "ecs.iterate.1m", "ns", ours, RUNS);
    bench_record(ctx, "ecs.iterate.1m.raw", "ns", raw, RUNS);
    bench_record(ctx, "ecs.iterate.1m.ratio", "x", ratio, RUNS);

    core_free(s.positions, ENTITIES * sizeof *s.positions);
    core_free(s.velocities, ENTITIES * sizeof *s.velocities);
    ecs_world_destroy(s.world);
}

/* ---- create ----------------------------------------------------------------------------- */

typedef struct create_state {
    Position *positions;
    Velocity *velocities;
} create_state;

static double sample_create_bulk(void *user) {
    create_state *s = user;
    ecs_world *world = ecs_world_create(NULL);
    ecs_component position = ECS_COMPONENT(world, Position);
    ecs_component velocity = ECS_COMPONENT(world, Velocity);
    uint64_t start = core_time_ns();
    ecs_entity_create_many(world, &(ecs_bulk_desc){ .count = ENTITIES,
        .components = { position, velocity }, .values = { s->positions, s->velocities } });
    double ms = core_ns_to_ms(core_time_ns() - start);
    ecs_world_destroy(world);
    return ms;
}

static double sample_create_each(void *user) {
    create_state *s = user;
    ecs_world *world = ecs_world_create(NULL);
    ecs_component position = ECS_COMPONENT(world, Position);
    ecs_component velocity = ECS_COMPONENT(world, Velocity);
    uint64_t start = core_time_ns();
    for (int i = 0; i < ENTITIES; i++) {
        ecs_entity e = ecs_entity_create(world);
        ecs_set(world, e, position, &s->positions[i]);
        ecs_set(world, e, velocity, &s->velocities[i]);
    }
    double ms = core_ns_to_ms(core_time_ns() - start);
    ecs_world_destroy(world);
    return ms;
}

static void bench_create(bench_context *ctx) {
    if (!bench_wants(ctx, "ecs.create.1m") && !bench_wants(ctx, "ecs.create.1m.each")) return;
    create_state s = { .positions = core_alloc(ENTITIES * sizeof *s.positions),
                       .velocities = core_alloc(ENTITIES * sizeof *s.velocities) };
    fill(s.positions, s.velocities, ENTITIES);
    bench_run(ctx, "ecs.create.1m", "ms", 9, sample_create_bulk, &s);
    bench_run(ctx, "ecs.create.1m.each", "ms", 5, sample_create_each, &s);
    core_free(s.positions, ENTITIES * sizeof *s.positions);
    core_free(s.velocities, ENTITIES * sizeof *s.velocities);
}

/* ---- progress: the cost of scheduling ------------------------------------------------- */

enum { PROGRESS_SYSTEMS = 100, PROGRESS_ENTITIES = 1000, PROGRESS_FRAMES = 200 };

typedef struct progress_state {
    ecs_world *world;
} progress_state;

/* A trivial system: reads its query's one field. What is measured is everything around it. */
static void touch_positions(ecs_iter *it) {
    float sum = 0;
    while (ecs_query_next(it)) {
        const Position *p = ecs_field(it, 0);
        sum += p[0].x;
    }
    bench_consume(sum);
}

static double sample_progress(void *user) {
    progress_state *s = user;
    uint64_t start = core_time_ns();
    for (int frame = 0; frame < PROGRESS_FRAMES; frame++) ecs_progress(s->world, 0.016f);
    return (double)(core_time_ns() - start) / 1e3 / PROGRESS_FRAMES;
}

static void bench_progress(bench_context *ctx) {
    if (!bench_wants(ctx, "ecs.progress.100systems")) return;
    static const char *const phases[] = { "input", "game", "stream", "generate", "stabilize",
                                          "mesh", "lod", "cull", "draw" };
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    progress_state s = { .world = ecs_world_create(&(ecs_world_desc){ .jobs = jobs }) };
    ecs_component position = ECS_COMPONENT(s.world, Position);
    ecs_entity_create_many(s.world, &(ecs_bulk_desc){ .count = PROGRESS_ENTITIES,
                                                      .components = { position } });
    /* Readers only: no two conflict, so the scheduler may run every phase's systems at once. */
    for (int i = 0; i < PROGRESS_SYSTEMS; i++)
        ecs_system_add(s.world, &(ecs_system_desc){ .name = "touch",
            .phase = phases[i % CORE_COUNTOF(phases)], .query = { .with = { position } },
            .fn = touch_positions, .parallel = i % 2 == 1 });
    bench_run(ctx, "ecs.progress.100systems", "us", 15, sample_progress, &s);
    ecs_world_destroy(s.world);
    job_system_destroy(jobs);
}

/* ---- add and remove, with and without hooks --------------------------------------------- */

enum { TOGGLE_ENTITIES = 10000 };

typedef struct Hooked { int *owned; } Hooked;

typedef struct toggle_state {
    ecs_world *world;
    ecs_component toggled;
    ecs_entity *entities;
    int calls;                       /* hook calls, so none is optimised away */
} toggle_state;

static void hooked_ctor(void *data, int count, void *user) {
    Hooked *h = data;
    for (int i = 0; i < count; i++) h[i].owned = NULL;
    ((toggle_state *)user)->calls++;
}
static void hooked_dtor(void *data, int count, void *user) {
    (void)data, (void)count;
    ((toggle_state *)user)->calls++;
}
static void hooked_event(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)world, (void)entity, (void)data;
    ((toggle_state *)user)->calls++;
}

static double sample_toggle(void *user) {
    toggle_state *s = user;
    uint64_t start = core_time_ns();
    for (int i = 0; i < TOGGLE_ENTITIES; i++) {
        ecs_add(s->world, s->entities[i], s->toggled);
        ecs_remove(s->world, s->entities[i], s->toggled);
    }
    return (double)(core_time_ns() - start) / TOGGLE_ENTITIES;
}

static void bench_add_remove(bench_context *ctx) {
    if (!bench_wants(ctx, "ecs.hooks.add_remove") && !bench_wants(ctx, "ecs.add_remove")) return;
    ecs_world *world = ecs_world_create(NULL);
    ecs_component position = ECS_COMPONENT(world, Position);
    ecs_component velocity = ECS_COMPONENT(world, Velocity);
    ecs_component hooked = ECS_COMPONENT(world, Hooked);
    ecs_entity *entities = core_alloc(TOGGLE_ENTITIES * sizeof *entities);
    ecs_entity_create_many(world, &(ecs_bulk_desc){ .count = TOGGLE_ENTITIES,
                                                    .components = { position }, .ids = entities });
    /* Same world, same entities, same kind of move (one 8-byte component more, then less). */
    toggle_state plain = { .world = world, .toggled = velocity, .entities = entities };
    toggle_state with_hooks = { .world = world, .toggled = hooked, .entities = entities };
    ecs_component_set_hooks(world, hooked, &(ecs_hooks){ .ctor = hooked_ctor,
        .dtor = hooked_dtor, .on_add = hooked_event, .on_remove = hooked_event,
        .user = &with_hooks });
    bench_run(ctx, "ecs.add_remove", "ns", 15, sample_toggle, &plain);
    bench_run(ctx, "ecs.hooks.add_remove", "ns", 15, sample_toggle, &with_hooks);
    bench_consume(with_hooks.calls);
    ecs_world_destroy(world);
    core_free(entities, TOGGLE_ENTITIES * sizeof *entities);
}

void bench_group_ecs(bench_context *ctx) {
    bench_iterate(ctx);
    bench_create(ctx);
    bench_progress(ctx);
    bench_add_remove(ctx);
}
