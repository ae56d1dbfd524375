/* Tests of ECS queries (engine/ecs): with/without/optional terms, tables created after the
 * query, batches, and long random programs checked against a plain reference model. */
#include "core/core.h"
#include "ecs/ecs.h"

#include "test.h"
#include <string.h>

typedef struct Position { float x, y; } Position;
typedef struct Velocity { float x, y; } Velocity;
typedef struct Color { unsigned char r, g, b; } Color;

/* ---- hand-made cases -------------------------------------------------------------------- */

typedef struct scene {
    ecs_world *world;
    ecs_component position, velocity, color, frozen;
    ecs_entity still, moving, frozen_moving, colored_moving;
} scene;

static scene scene_make(void) {
    scene s = { .world = ecs_world_create(NULL) };
    s.position = ECS_COMPONENT(s.world, Position);
    s.velocity = ECS_COMPONENT(s.world, Velocity);
    s.color = ECS_COMPONENT(s.world, Color);
    s.frozen = ECS_TAG(s.world, Frozen);
    s.still = ecs_entity_create(s.world);
    ecs_set(s.world, s.still, s.position, &(Position){ 1, 1 });
    s.moving = ecs_entity_create(s.world);
    ecs_set(s.world, s.moving, s.position, &(Position){ 2, 2 });
    ecs_set(s.world, s.moving, s.velocity, &(Velocity){ 1, 0 });
    s.frozen_moving = ecs_entity_create(s.world);
    ecs_set(s.world, s.frozen_moving, s.position, &(Position){ 3, 3 });
    ecs_set(s.world, s.frozen_moving, s.velocity, &(Velocity){ 1, 0 });
    ecs_add(s.world, s.frozen_moving, s.frozen);
    s.colored_moving = ecs_entity_create(s.world);
    ecs_set(s.world, s.colored_moving, s.position, &(Position){ 4, 4 });
    ecs_set(s.world, s.colored_moving, s.velocity, &(Velocity){ 0, 1 });
    ecs_set(s.world, s.colored_moving, s.color, &(Color){ 9, 8, 7 });
    return s;
}

/* Runs the query once and returns how many entities it visited. */
static int visit_count(ecs_world *world, const ecs_query *query) {
    int n = 0;
    ecs_iter it = ecs_query_iter(world, query);
    while (ecs_query_next(&it)) n += it.count;
    return n;
}

Test(ecs_queries, with_terms_give_fields_in_order) {
    scene s = scene_make();
    ecs_query *q = ecs_query_create(s.world, &(ecs_query_desc){ .with = { s.velocity, s.position } });
    ecs_iter it = ecs_query_iter(s.world, q);
    int visited = 0;
    while (ecs_query_next(&it)) {
        Velocity *v = ecs_field(&it, 0);
        Position *p = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++) {
            Position *expected = ecs_get(s.world, it.entities[i], s.position);
            cr_expect_eq(&p[i], expected, "field 1 is the Position column");
            cr_expect_eq(&v[i], ecs_get(s.world, it.entities[i], s.velocity));
            visited++;
        }
    }
    cr_expect_eq(visited, 3, "moving, frozen_moving, colored_moving");
    cr_expect_eq(ecs_query_count(s.world, q), 3);
    ecs_world_destroy(s.world);
}

Test(ecs_queries, without_terms_exclude) {
    scene s = scene_make();
    ecs_query *q = ecs_query_create(s.world, &(ecs_query_desc){
        .with = { s.position, s.velocity }, .without = { s.frozen } });
    ecs_iter it = ecs_query_iter(s.world, q);
    int visited = 0;
    while (ecs_query_next(&it))
        for (int i = 0; i < it.count; i++) {
            cr_expect(it.entities[i] == s.moving || it.entities[i] == s.colored_moving);
            visited++;
        }
    cr_expect_eq(visited, 2);
    ecs_world_destroy(s.world);
}

Test(ecs_queries, optional_fields_are_null_where_missing) {
    scene s = scene_make();
    ecs_query *q = ecs_query_create(s.world, &(ecs_query_desc){
        .with = { s.velocity }, .optional = { s.color, s.frozen } });
    ecs_iter it = ecs_query_iter(s.world, q);
    int visited = 0;
    while (ecs_query_next(&it)) {
        Color *c = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++, visited++) {
            ecs_entity e = it.entities[i];
            if (e == s.colored_moving) {
                cr_assert_not_null(c);
                cr_expect(c[i].r == 9 && c[i].g == 8 && c[i].b == 7);
            } else {
                cr_expect_null(c);
            }
            cr_expect_eq(ecs_field_is_set(&it, 2), e == s.frozen_moving, "the Frozen tag");
            cr_expect_null(ecs_field(&it, 2), "a tag has no data");
        }
    }
    cr_expect_eq(visited, 3);
    ecs_world_destroy(s.world);
}

Test(ecs_queries, picks_up_tables_created_later) {
    scene s = scene_make();
    ecs_query *q = ecs_query_create(s.world, &(ecs_query_desc){ .with = { s.color } });
    cr_expect_eq(visit_count(s.world, q), 1);
    ecs_entity e = ecs_entity_create(s.world);
    ecs_add(s.world, e, s.color);           /* a table that did not exist: {Color} */
    ecs_add(s.world, e, s.frozen);          /* and another: {Color, Frozen} */
    cr_expect_eq(visit_count(s.world, q), 2);
    ecs_remove(s.world, s.colored_moving, s.color);
    cr_expect_eq(visit_count(s.world, q), 1);
    ecs_world_destroy(s.world);
}

Test(ecs_queries, empty_query_matches_every_entity) {
    scene s = scene_make();
    ecs_entity bare = ecs_entity_create(s.world);
    ecs_query *all = ecs_query_create(s.world, &(ecs_query_desc){ 0 });
    cr_expect_eq(visit_count(s.world, all), 5);
    ecs_entity_destroy(s.world, bare);
    cr_expect_eq(visit_count(s.world, all), 4);
    ecs_query_destroy(s.world, all);
    ecs_world_destroy(s.world);
}

Test(ecs_queries, batches_cover_each_entity_once) {
    ecs_world *world = ecs_world_create(NULL);
    ecs_component position = ECS_COMPONENT(world, Position);
    ecs_component velocity = ECS_COMPONENT(world, Velocity);
    ecs_component frozen = ECS_TAG(world, Frozen);
    /* Three tables of 70, 5 and 33 entities: 108 in all. */
    static ecs_entity ids[108];
    ecs_entity_create_many(world, &(ecs_bulk_desc){ .count = 70, .components = { position },
                                                    .ids = ids });
    ecs_entity_create_many(world, &(ecs_bulk_desc){ .count = 5, .components = { position, frozen },
                                                    .ids = ids + 70 });
    ecs_entity_create_many(world, &(ecs_bulk_desc){ .count = 33, .components = { position, velocity },
                                                    .ids = ids + 75 });
    ecs_query *q = ecs_query_create(world, &(ecs_query_desc){ .with = { position } });

    ecs_batch batches[16];
    int n = ecs_query_batches(world, q, 25, batches, 2);
    cr_assert_eq(n, 5, "ceil(108 / 25) batches");
    cr_assert_eq(ecs_query_batches(world, q, 25, batches, 16), 5);
    int seen_total = 0;
    static int seen[108];
    memset(seen, 0, sizeof seen);
    for (int b = 0; b < n; b++) {
        int in_batch = 0;
        ecs_iter it = ecs_batch_iter(world, q, batches[b]);
        while (ecs_query_next(&it)) {
            cr_assert_not_null(ecs_field(&it, 0));
            for (int i = 0; i < it.count; i++)
                for (int k = 0; k < 108; k++) seen[k] += ids[k] == it.entities[i];
            in_batch += it.count;
        }
        cr_expect_eq(in_batch, b < 4 ? 25 : 8, "batch %d", b);
        seen_total += in_batch;
    }
    cr_expect_eq(seen_total, 108);
    for (int k = 0; k < 108; k++) cr_expect_eq(seen[k], 1, "entity %d", k);
    ecs_world_destroy(world);
}

/* ---- random programs against a reference model ------------------------------------------ */

enum { KINDS = 6, MAX_ENTITIES = 300, CHECK_EVERY = 97, QUERIES = 12 };

/* Components of assorted sizes and alignments; the last two are tags. */
typedef struct Small { unsigned char bytes[3]; } Small;
typedef struct Word { uint32_t value; } Word;
typedef struct Wide { double d; uint64_t u; } Wide;
typedef struct Odd { uint16_t a[5]; } Odd;

typedef struct model_entity {
    ecs_entity id;
    unsigned mask;                 /* bit k: has component k */
    uint32_t stamp[KINDS];         /* what the component's bytes were made from; 0 = zeroed */
} model_entity;

typedef struct model {
    model_entity entities[MAX_ENTITIES];
    int count;
    ecs_entity dead[4096];         /* ids destroyed so far (the first 4096) */
    int dead_count;
} model;

typedef struct rng { uint64_t state; } rng;
static uint32_t rng_next(rng *r) { return (uint32_t)(core_hash_u64(++r->state) >> 32); }
static uint32_t rng_below(rng *r, uint32_t n) { return rng_next(r) % n; }

/* The bytes a component holds for `stamp`: all zero for 0, else a pattern of the stamp. */
static void stamp_bytes(uint32_t stamp, unsigned char *out, size_t size) {
    for (size_t i = 0; i < size; i++)
        out[i] = stamp ? (unsigned char)(core_hash_combine(stamp, i) & 0xff) : 0;
}

typedef struct world_under_test {
    ecs_world *world;
    ecs_component kinds[KINDS];
    size_t sizes[KINDS];
} world_under_test;

static world_under_test world_under_test_make(ecs_world *world) {
    world_under_test w = { .world = world };
    w.kinds[0] = ECS_COMPONENT(world, Small);
    w.kinds[1] = ECS_COMPONENT(world, Word);
    w.kinds[2] = ECS_COMPONENT(world, Wide);
    w.kinds[3] = ECS_COMPONENT(world, Odd);
    w.kinds[4] = ECS_TAG(world, TagA);
    w.kinds[5] = ECS_TAG(world, TagB);
    const size_t sizes[KINDS] = { sizeof(Small), sizeof(Word), sizeof(Wide), sizeof(Odd), 0, 0 };
    memcpy(w.sizes, sizes, sizeof sizes);
    return w;
}

static model_entity *model_find(model *m, ecs_entity id) {
    for (int i = 0; i < m->count; i++)
        if (m->entities[i].id == id) return &m->entities[i];
    return NULL;
}

static void step(world_under_test *w, model *m, rng *r) {
    uint32_t op = rng_below(r, 100);
    if (m->count == 0 || (op < 20 && m->count < MAX_ENTITIES)) {
        m->entities[m->count++] = (model_entity){ .id = ecs_entity_create(w->world) };
        return;
    }
    int which = (int)rng_below(r, (uint32_t)m->count);
    model_entity *e = &m->entities[which];
    int k = (int)rng_below(r, KINDS);
    if (op < 32) {                                  /* destroy */
        ecs_entity_destroy(w->world, e->id);
        if (m->dead_count < (int)CORE_COUNTOF(m->dead)) m->dead[m->dead_count++] = e->id;
        *e = m->entities[--m->count];
    } else if (op < 55) {                           /* add: zeroed if new, kept if not */
        ecs_add(w->world, e->id, w->kinds[k]);
        if (!(e->mask & 1u << k)) e->stamp[k] = 0;
        e->mask |= 1u << k;
    } else if (op < 80) {                           /* set */
        uint32_t stamp = rng_next(r) | 1;
        unsigned char bytes[64];
        stamp_bytes(stamp, bytes, w->sizes[k]);
        ecs_set(w->world, e->id, w->kinds[k], bytes);
        e->stamp[k] = stamp;
        e->mask |= 1u << k;
    } else {                                        /* remove */
        ecs_remove(w->world, e->id, w->kinds[k]);
        e->mask &= ~(1u << k);
    }
}

typedef struct query_case {
    unsigned with, without, optional;   /* masks of component kinds */
    ecs_query *query;
    int with_kinds[KINDS], optional_kinds[KINDS];
    int with_count, optional_count;
} query_case;

static query_case query_case_make(world_under_test *w, rng *r) {
    query_case c = { 0 };
    ecs_query_desc desc = { 0 };
    int nw = 0, nwo = 0, no = 0;
    for (int k = 0; k < KINDS; k++) {
        switch (rng_below(r, 4)) {           /* each kind: with, without, optional or nothing */
        case 0: c.with |= 1u << k; c.with_kinds[nw] = k; desc.with[nw++] = w->kinds[k]; break;
        case 1: c.without |= 1u << k; desc.without[nwo++] = w->kinds[k]; break;
        case 2: c.optional |= 1u << k; c.optional_kinds[no] = k; desc.optional[no++] = w->kinds[k]; break;
        default: break;
        }
    }
    c.with_count = nw;
    c.optional_count = no;
    c.query = ecs_query_create(w->world, &desc);
    return c;
}

static bool model_matches(const query_case *c, const model_entity *e) {
    return (e->mask & c->with) == c->with && (e->mask & c->without) == 0;
}

static void expect_field(world_under_test *w, const model_entity *e, int kind, const void *data,
                         int step_index) {
    if (w->sizes[kind] == 0) {
        cr_expect_null(data, "step %d: a tag's field is NULL", step_index);
        return;
    }
    unsigned char expected[64];
    stamp_bytes(e->stamp[kind], expected, w->sizes[kind]);
    cr_assert_not_null(data, "step %d: kind %d", step_index, kind);
    cr_expect(memcmp(data, expected, w->sizes[kind]) == 0, "step %d: kind %d value", step_index,
              kind);
}

static void check_query(world_under_test *w, model *m, const query_case *c, int step_index) {
    static unsigned char visited[MAX_ENTITIES];
    memset(visited, 0, sizeof visited);
    int total = 0;
    ecs_iter it = ecs_query_iter(w->world, c->query);
    while (ecs_query_next(&it)) {
        for (int i = 0; i < it.count; i++) {
            model_entity *e = model_find(m, it.entities[i]);
            cr_assert_not_null(e, "step %d: query returned an entity that is not alive", step_index);
            cr_assert(model_matches(c, e), "step %d: query returned a non-matching entity", step_index);
            int slot = (int)(e - m->entities);
            cr_assert_eq(visited[slot], 0, "step %d: entity visited twice", step_index);
            visited[slot] = 1;
            for (int f = 0; f < c->with_count; f++) {
                int kind = c->with_kinds[f];
                cr_expect(ecs_field_is_set(&it, f));
                unsigned char *column = ecs_field(&it, f);
                expect_field(w, e, kind, column ? column + (size_t)i * w->sizes[kind] : NULL, step_index);
            }
            for (int o = 0; o < c->optional_count; o++) {
                int kind = c->optional_kinds[o], f = c->with_count + o;
                bool has = e->mask & 1u << kind;
                cr_expect_eq(ecs_field_is_set(&it, f), has, "step %d: optional presence", step_index);
                unsigned char *column = ecs_field(&it, f);
                if (has) expect_field(w, e, kind, column ? column + (size_t)i * w->sizes[kind] : NULL, step_index);
                else cr_expect_null(column, "step %d: absent optional field", step_index);
            }
        }
        total += it.count;
    }
    int expected = 0;
    for (int i = 0; i < m->count; i++) expected += model_matches(c, &m->entities[i]);
    cr_assert_eq(total, expected, "step %d: matches", step_index);
    cr_assert_eq(ecs_query_count(w->world, c->query), expected);
}

static void check_entities(world_under_test *w, model *m, int step_index) {
    cr_assert_eq(ecs_entity_count(w->world), m->count, "step %d", step_index);
    for (int i = 0; i < m->count; i++) {
        const model_entity *e = &m->entities[i];
        cr_assert(ecs_is_alive(w->world, e->id));
        for (int k = 0; k < KINDS; k++) {
            bool has = e->mask & 1u << k;
            cr_assert_eq(ecs_has(w->world, e->id, w->kinds[k]), has, "step %d", step_index);
            void *data = ecs_get(w->world, e->id, w->kinds[k]);
            if (has && w->sizes[k]) expect_field(w, e, k, data, step_index);
            else cr_expect_null(data);
        }
    }
    for (int i = 0; i < m->dead_count; i++) {
        cr_assert_not(ecs_is_alive(w->world, m->dead[i]), "step %d: a destroyed id", step_index);
        cr_assert_null(ecs_get(w->world, m->dead[i], w->kinds[1]));
    }
}

static void run_random_program(uint64_t seed, int steps) {
    rng r = { seed };
    world_under_test w = world_under_test_make(ecs_world_create(NULL));
    static model m;
    memset(&m, 0, sizeof m);
    query_case cases[QUERIES];
    /* Half the queries exist before any table, half are made midway: both must be right. */
    for (int q = 0; q < QUERIES / 2; q++) cases[q] = query_case_make(&w, &r);
    for (int s = 0; s < steps; s++) {
        if (s == steps / 2)
            for (int q = QUERIES / 2; q < QUERIES; q++) cases[q] = query_case_make(&w, &r);
        step(&w, &m, &r);
        if (s % CHECK_EVERY == 0 || s == steps - 1) {
            int live_queries = s >= steps / 2 ? QUERIES : QUERIES / 2;
            for (int q = 0; q < live_queries; q++) check_query(&w, &m, &cases[q], s);
            check_entities(&w, &m, s);
        }
    }
    ecs_world_destroy(w.world);
}

Test(ecs_queries, random_programs_match_the_model) {
    for (uint64_t seed = 1; seed <= 6; seed++) run_random_program(seed * 7919, 6000);
}
