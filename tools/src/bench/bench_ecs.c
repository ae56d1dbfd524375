/* bench_ecs.c — ECS rows: iterating a two-component query beside two bare arrays (the memory
 * bandwidth limit), and creating a million entities.
 *
 *   ecs.iterate.1m        ns per entity for position += velocity over 1M entities, via a query
 *   ecs.iterate.1m.raw    the same update over two plain arrays
 *   ecs.iterate.1m.ratio  ours / raw, run by run (target ≤ 1.2)
 *   ecs.create.1m         ms to create 1M entities with Position and Velocity (bulk path)
 *   ecs.create.1m.each    the same one entity at a time (ecs_entity_create + 2 × ecs_set)
 */
#include "bench.h"

#include "core/core.h"
#include "ecs/ecs.h"

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

void bench_group_ecs(bench_context *ctx) {
    bench_iterate(ctx);
    bench_create(ctx);
}
