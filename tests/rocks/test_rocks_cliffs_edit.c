/* Cliff blocks after an edit (rocks_cliffs.c, issue 18): an edit that changes which blocks stand
 * changes the world's field only within rocks_cliffs_reach of the columns it changed (so the
 * chunks the ECS meshes again, terrain_world_desc.amplify_reach, are enough), and the presence
 * the cliffs keep for tile cells is never stale: the edited world gives the same field as a world
 * generated that way from the start, with cliffs that never saw the old stacks.
 *
 * The wall: bedrock up to 20 m for x < 0, a floor at 0 for x ≥ 0 (a face x = 0 across z). The
 * edit cuts a notch 3 m wide and 12 m deep into its top, at the border of column chunks z = 0
 * and z = 1 (z = 32), so cells on either side read it. */
#include "../engine/test.h"
#include "rocks/rocks.h"
#include "rocks_test_wall.h"

#include <math.h>

static rocks_cliffs *columnar_cliffs(void) {
    rocks_cliffs *c = columnar_cliffs_in("cliffs-edit");
    cr_assert_not_null(c);
    return c;
}

/* Samples 1 m apart over the wall around the notch. */
static const terrain_field_desc around = { .first = { -10, 0, 14 }, .size = { 18, 26, 36 } };

static terrain_field sample(terrain_world *world) {
    terrain_field f;
    cr_assert(terrain_field_sample(world, &around, &f));
    return f;
}

/* Whether (x, y, z) lies farther than `reach` along some axis from the changed columns' box
 * (columns [NOTCH_X0, 0) × [NOTCH_Z0, NOTCH_Z1), their changed heights 8 … 20 m). */
static bool beyond_reach(double x, double y, double z, const float reach[3]) {
    double dx = fmax(fmax(NOTCH_X0 - x, x - 0.0), 0.0);
    double dy = fmax(fmax(NOTCH_TOP - y, y - 20.0), 0.0);
    double dz = fmax(fmax(NOTCH_Z0 - z, z - NOTCH_Z1), 0.0);
    return dx > reach[0] || dy > reach[1] || dz > reach[2];
}

Test(rocks_cliffs_edit, an_edit_changes_blocks_within_the_reach_and_the_kept_presence_follows_it) {
    rocks_cliffs *seen = columnar_cliffs(), *fresh = columnar_cliffs();
    float reach[3], none[3] = { 1, 1, 1 };
    rocks_cliffs_reach(seen, reach);
    for (int a = 0; a < 3; a++) {
        cr_assert_gt(reach[a], 2.0f, "at least what presence reads past a block");
        cr_assert_lt(reach[a], 30.0f, "a block's size, not a tile's: %g m", (double)reach[a]);
    }
    rocks_cliffs_reach(NULL, none);
    cr_assert(none[0] == 0 && none[1] == 0 && none[2] == 0);

    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generate = wall_chunk, .generate_user = (void *)&plain, .amplify = rocks_cliffs_amplify, .amplify_user = seen,
        .amplify_reach = { reach[0], reach[1], reach[2] } });
    terrain_field before = sample(world);
    /* the edit: a commit of the notched chunks, as the tools make */
    for (int64_t cz = 0; cz <= 1; cz++) {
        terrain_chunk_coord coord = { -1, cz };
        terrain_world_commit(world, coord, terrain_stacks_from_columns(coord, wall_column, (void *)&notched),
                             TERRAIN_EDIT_SET);
    }
    terrain_field after = sample(world);

    terrain_world *from_start = terrain_world_create(&(terrain_world_desc){
        .generate = wall_chunk, .generate_user = (void *)&notched, .amplify = rocks_cliffs_amplify, .amplify_user = fresh });
    terrain_field expected = sample(from_start);

    size_t changed = 0, stale = 0, beyond = 0;
    for (int k = 0; k < around.size[2]; k++)
        for (int j = 0; j < around.size[1]; j++)
            for (int i = 0; i < around.size[0]; i++) {
                size_t at = ((size_t)k * around.size[1] + j) * around.size[0] + i;
                stale += after.values[at] != expected.values[at];
                if (after.values[at] == before.values[at]) continue;
                changed++;
                beyond += beyond_reach((double)(around.first[0] + i), (double)(around.first[1] + j),
                                       (double)(around.first[2] + k), reach);
            }
    cr_expect_gt(changed, 0, "the notch changes the field");
    cr_expect_eq(stale, 0, "%zu samples differ from the world made notched (kept presence is stale)", stale);
    cr_expect_eq(beyond, 0, "%zu changed samples farther than the reach (%g, %g, %g) m", beyond, (double)reach[0],
                 (double)reach[1], (double)reach[2]);
    terrain_field_free(&before);
    terrain_field_free(&after);
    terrain_field_free(&expected);
    terrain_world_destroy(world);
    terrain_world_destroy(from_start);
    rocks_cliffs_destroy(seen);
    rocks_cliffs_destroy(fresh);
}

/* A point sampled just before an edit and again just after it (the tools' picking ray does this
 * every frame): the second answer is the edited world's, though the thread kept the first one's
 * tile cells (rocks_cliffs.c's memo of each thread's last answers). The points are those where
 * the notch changes the blocks but not the ground under them. */
Test(rocks_cliffs_edit, a_point_sampled_across_an_edit_follows_it) {
    rocks_cliffs *seen = columnar_cliffs(), *fresh_plain = columnar_cliffs(), *fresh_notched = columnar_cliffs();
    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generate = wall_chunk, .generate_user = (void *)&plain, .amplify = rocks_cliffs_amplify, .amplify_user = seen });
    terrain_world *want_plain = terrain_world_create(&(terrain_world_desc){
        .generate = wall_chunk, .generate_user = (void *)&plain, .amplify = rocks_cliffs_amplify,
        .amplify_user = fresh_plain });
    terrain_world *want_notched = terrain_world_create(&(terrain_world_desc){
        .generate = wall_chunk, .generate_user = (void *)&notched, .amplify = rocks_cliffs_amplify,
        .amplify_user = fresh_notched });
    int points = 0, wrong = 0;
    for (int k = 0; k < around.size[2] && points < 24; k++)
        for (int j = 0; j < around.size[1] && points < 24; j++)
            for (int i = 0; i < around.size[0] && points < 24; i++) {
                const double x = around.first[0] + i + 0.25, y = around.first[1] + j + 0.5, z = around.first[2] + k + 0.25;
                const float a = terrain_field_at(want_plain, x, y, z, 0), b = terrain_field_at(want_notched, x, y, z, 0);
                if (a == b || terrain_field_base_at(want_plain, x, y, z, 0) != terrain_field_base_at(want_notched, x, y, z, 0))
                    continue;
                points++;
                for (int round = 0; round < 2; round++) {   /* to the notch, and back */
                    (void)terrain_field_at(world, x, y, z, 0);
                    for (int64_t cz = 0; cz <= 1; cz++) {
                        terrain_chunk_coord coord = { -1, cz };
                        terrain_world_commit(world, coord,
                                             terrain_stacks_from_columns(coord, wall_column, (void *)(round ? &plain : &notched)),
                                             TERRAIN_EDIT_SET);
                    }
                    wrong += terrain_field_at(world, x, y, z, 0) != (round ? a : b);
                }
            }
    cr_expect_gt(points, 0, "the notch changes blocks over ground it leaves as it was");
    cr_expect_eq(wrong, 0, "%d of %d answers after an edit are the old world's", wrong, 2 * points);
    terrain_world_destroy(world);
    terrain_world_destroy(want_plain);
    terrain_world_destroy(want_notched);
    rocks_cliffs_destroy(seen);
    rocks_cliffs_destroy(fresh_plain);
    rocks_cliffs_destroy(fresh_notched);
}
