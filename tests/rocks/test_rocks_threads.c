/* Cliff blocks sampled from several threads while the main thread edits the wall (rocks_cliffs.c
 * under ThreadSanitizer, in test_threads): the shared cache of presence behind its lock, each
 * thread's memo of its last answers, and the world's commit count read without a lock. Readers
 * sample single points (a picking ray's samples) and small boxes (a collision query's) over the
 * wall; the main thread cuts and fills a notch across a chunk border, and samples too, so its
 * own memo holds answers from before each commit. Afterwards every sample, taken on the main
 * thread and through a small box, must equal a world generated in the final state, with cliffs
 * that never saw an edit: no answer kept from before a commit survives it.
 *
 * The wall: bedrock up to 20 m for x < 0, a floor at 0 for x ≥ 0; the notch lowers columns
 * [−3, 0) × [29, 35) to 8 m (the column chunks z = 0 and z = 1 meet at z = 32). */
#include "../engine/test.h"
#include "rocks/rocks.h"
#include "rocks_test_wall.h"

#include <pthread.h>
#include <stdatomic.h>

static rocks_cliffs *columnar_cliffs(void) {
    rocks_cliffs *c = columnar_cliffs_in("cliffs-threads");
    cr_assert_not_null(c);
    return c;
}

static terrain_world *wall_world(const bool *state, rocks_cliffs *cliffs) {
    return terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk, .generate_user = (void *)state,
                                                       .amplify = rocks_cliffs_amplify, .amplify_user = cliffs });
}

/* The i-th of the points sampled around the notch: 1 m apart in x and z, 0.5 m in y. */
#define POINTS (8 * 34 * 12)
static void point(int i, double p[3]) {
    p[0] = -6.0 + i % 8, p[1] = 4.0 + 0.5 * (i / 8 % 34), p[2] = 26.0 + i / (8 * 34);
}

typedef struct share {
    terrain_world *world;
    atomic_bool stop;
    atomic_long samples;
} share;

static void *reader(void *user) {
    share *s = user;
    for (long round = 0; !atomic_load(&s->stop); round++) {
        double p[3];
        point((int)(round % POINTS), p);
        (void)terrain_field_at(s->world, p[0], p[1], p[2], 0);
        if (round % 16 == 0) {
            terrain_field f;
            if (terrain_field_sample(s->world, &(terrain_field_desc){ .first = { -4, 6, 28 + round % 6 },
                                                                      .size = { 4, 6, 4 } }, &f))
                terrain_field_free(&f);
        }
        atomic_fetch_add(&s->samples, 1);
    }
    return NULL;
}

static void commit_notch(terrain_world *world, const bool *state) {
    for (int64_t cz = 0; cz <= 1; cz++) {
        terrain_chunk_coord coord = { -1, cz };
        terrain_world_commit(world, coord, terrain_stacks_from_columns(coord, wall_column, (void *)state),
                             TERRAIN_EDIT_SET);
    }
}

Test(rocks_threads, blocks_sampled_while_the_wall_is_edited_match_a_fresh_world) {
    enum { ROUNDS = 12 };
    rocks_cliffs *seen = columnar_cliffs(), *fresh = columnar_cliffs();
    share s = { .world = wall_world(&plain, seen) };
    pthread_t readers[3];
    for (int t = 0; t < 3; t++) pthread_create(&readers[t], NULL, reader, &s);
    double p[3];
    for (int round = 0; round < ROUNDS; round++) {
        for (int i = 0; i < POINTS; i += 7) point(i, p), (void)terrain_field_at(s.world, p[0], p[1], p[2], 0);
        commit_notch(s.world, round % 2 ? &plain : &notched);
    }
    atomic_store(&s.stop, true);
    for (int t = 0; t < 3; t++) pthread_join(readers[t], NULL);
    cr_expect_gt(atomic_load(&s.samples), 0);
    const bool *last = (ROUNDS - 1) % 2 ? &plain : &notched;
    terrain_world *expected = wall_world(last, fresh);
    rocks_cliffs *other_cliffs = columnar_cliffs();
    terrain_world *other = wall_world(last == &plain ? &notched : &plain, other_cliffs);
    /* all of the edited world's samples first: each thread's memo holds one world's answers */
    static float got[POINTS];
    for (int i = 0; i < POINTS; i++) point(i, p), got[i] = terrain_field_at(s.world, p[0], p[1], p[2], 0);
    int differ = 0, raised = 0, blocks_differ = 0;
    for (int i = 0; i < POINTS; i++) {
        point(i, p);
        float want = terrain_field_at(expected, p[0], p[1], p[2], 0);
        differ += got[i] != want;
        const float base = terrain_field_base_at(expected, p[0], p[1], p[2], 0);
        raised += want > base;
        /* where the other state's blocks differ on the same ground: a stale answer would show */
        blocks_differ += base == terrain_field_base_at(other, p[0], p[1], p[2], 0) &&
                         want != terrain_field_at(other, p[0], p[1], p[2], 0);
    }
    cr_expect_gt(raised, 0, "blocks raise some of the samples");
    cr_expect_gt(blocks_differ, 0, "the notch changes blocks where it leaves the ground as it was");
    cr_expect_eq(differ, 0, "%d of %d samples differ from the fresh world's (an answer kept from before a commit)",
                 differ, POINTS);
    terrain_world_destroy(expected);
    terrain_world_destroy(other);
    rocks_cliffs_destroy(other_cliffs);
    terrain_world_destroy(s.world);
    rocks_cliffs_destroy(seen);
    rocks_cliffs_destroy(fresh);
}
