/* Cliffs whose block type follows the stacks' materials (paper 003 §5: a copy is kept where "the
 * material γ(a_k) corresponds to the material of the underlying block"; rocks_cliffs_desc.
 * material_blocks). The world is a wall made by hand: its face is the plane x = 0, rock behind it
 * (x < 0) up to 28 m, a floor in front at y = 0; the rock behind the face is one material below
 * STRATA_H and another above it. Which copies are present is read per tile cell
 * (rocks__cliffs_present, the amplify hook's own path), and what each must be is worked out from
 * the layout alone:
 *   - the type is read from the material three quarters of a metre behind the face along the
 *     field's gradient, and a wall is steep: |g_y| < 0.5 |g|, so that point lies less than
 *     0.375 m above or below the anchor. A copy of the lower rock's type has its anchor below
 *     STRATA_H + 0.375, one of the upper rock's above STRATA_H − 0.375;
 *   - bedrock with no entry follows the strata by the anchor's height, as before;
 *   - a game's material with no entry, like sand, gets no blocks.
 * Tiles are 12 m so the suite stays short under the sanitizers. */
#include "../engine/test.h"
#include "core/core.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define STRATA_H 10.0f                /* the lower rock gives way to the upper one here */
#define WALL_TOP 28.0f
#define TILE 12.0f
#define STEEP_REACH 0.375             /* 0.75 m · ε (0.5): how far up or down the material is read */

/* a game's two rocks */
#define ROCK_A ((terrain_material)TERRAIN_MATERIAL_BUILTIN_COUNT)
#define ROCK_B ((terrain_material)(TERRAIN_MATERIAL_BUILTIN_COUNT + 1))

/* The tiles are most of a test's time (seconds under ASan): under tools/test, which sets
 * ROCKS_TEST_CACHE_DIR to a folder fresh each run (rocks_test_cache.h), the cliffs keep them in a
 * folder of this file's own there, so each tile is built once a run. Their seed is this file's
 * too. */
#define STRATA_SEED 18

static rocks_cliffs_desc strata_desc(void) {
    static char dir[512];
    const char *root = getenv("ROCKS_TEST_CACHE_DIR");
    if (root && *root) snprintf(dir, sizeof dir, "%s/strata", root);
    return (rocks_cliffs_desc){ .seed = STRATA_SEED, .tile_size = TILE, .cache_dir = root && *root ? dir : NULL };
}

typedef struct two_rocks { terrain_material lower, upper; } two_rocks;

static void two_rocks_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const two_rocks *w = user;
    (void)z;
    if (x < 0) {
        terrain_stacks_builder_push(b, w->lower, STRATA_H - TERRAIN_FLOOR_Y);
        terrain_stacks_builder_push(b, w->upper, WALL_TOP - STRATA_H);
    } else {
        terrain_stacks_builder_push(b, w->lower, 0.0f - TERRAIN_FLOOR_Y);   /* the floor */
    }
}

static terrain_stacks *two_rocks_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, two_rocks_column, user);
}

static terrain_world *wall_world(two_rocks *rocks, rocks_cliffs *cliffs) {
    return terrain_world_create(&(terrain_world_desc){ .generate = two_rocks_chunk, .generate_user = rocks,
                                                       .amplify = cliffs ? rocks_cliffs_amplify : NULL,
                                                       .amplify_user = cliffs });
}

/* The present copies of `type` in the tile cells along the face (x cells −1 and 0, heights up to
 * 36 m, z from 0 to 36 m): each one's anchor height into heights (up to capacity); returns how
 * many. */
static int present_anchor_heights(rocks_cliffs *cliffs, terrain_world *world, rocks_block_type type, double *heights,
                                  int capacity) {
    const rocks_block_tile *tile = rocks__cliffs_tile(cliffs, type);
    if (!tile) return 0;
    uint64_t bits[64];
    cr_assert_leq((tile->block_count + 63) / 64, CORE_COUNTOF(bits));
    int count = 0;
    for (int64_t z = 0; z < 3; z++)
        for (int64_t y = 0; y < 3; y++)
            for (int64_t x = -1; x <= 0; x++) {
                const int64_t cell[3] = { x, y, z };
                rocks__cliffs_present(cliffs, world, type, cell, bits);
                for (uint32_t b = 0; b < tile->block_count; b++)
                    if (bits[b / 64] >> (b % 64) & 1) {
                        if (count < capacity) heights[count] = (double)y * TILE + tile->blocks[b].anchor[1];
                        count++;
                    }
            }
    return count;
}

/* Two rocks, two block types: below the change every present copy is the lower rock's type,
 * above it the upper rock's, and both show. Then the field the world meshes: against cliffs
 * that map rock A alone, the samples well below the change (further than a slab reaches down
 * from its anchor) are the same bits, and well above it (further than a column reaches up) only
 * the cliffs that map rock B raise any: a game's material with no entry gets no blocks. Were
 * the materials ignored, bedrock's strata (columnar) would decide, and no wall here is bedrock. */
Test(rocks_strata, block_type_follows_the_material) {
    two_rocks rocks = { ROCK_A, ROCK_B };
    rocks_cliffs_desc both = strata_desc();
    both.strata_count = 1, both.strata[0] = ROCKS_BLOCK_COLUMNAR;
    both.material_blocks[ROCK_A] = ROCKS_BLOCK_COLUMNAR;
    both.material_blocks[ROCK_B] = ROCKS_BLOCK_TABULAR;
    rocks_cliffs *a = rocks_cliffs_create(&both);
    cr_assert_not_null(a);
    terrain_world *world_a = wall_world(&rocks, a);
    double heights[4096];
    int columnar = present_anchor_heights(a, world_a, ROCKS_BLOCK_COLUMNAR, heights, 4096);
    cr_assert_leq(columnar, 4096);
    for (int i = 0; i < columnar; i++)
        cr_expect_lt(heights[i], STRATA_H + STEEP_REACH, "a columnar copy (rock A's) at %.2f m, over rock B", heights[i]);
    int tabular = present_anchor_heights(a, world_a, ROCKS_BLOCK_TABULAR, heights, 4096);
    cr_assert_leq(tabular, 4096);
    for (int i = 0; i < tabular; i++)
        cr_expect_gt(heights[i], STRATA_H - STEEP_REACH, "a tabular copy (rock B's) at %.2f m, over rock A", heights[i]);
    cr_expect_gt(columnar, 0, "rock A's wall breaks into columns");
    cr_expect_gt(tabular, 0, "rock B's wall breaks into slabs");
    cr_expect_null(rocks__cliffs_tile(a, ROCKS_BLOCK_EQUIDIMENSIONAL), "a tile per type used, no more");

    rocks_cliffs_desc lower_only = both;
    lower_only.material_blocks[ROCK_B] = ROCKS_BLOCK_DEFAULT;
    rocks_cliffs *b = rocks_cliffs_create(&lower_only);
    cr_assert_not_null(b);
    terrain_world *world_b = wall_world(&rocks, b), *plain = wall_world(&rocks, NULL);
    const terrain_field_desc box = { .first = { -4, 0, 0 }, .size = { 8, 28, 24 } };
    terrain_field fa, fb, f0;
    cr_assert(terrain_field_sample(world_a, &box, &fa));
    cr_assert(terrain_field_sample(world_b, &box, &fb));
    cr_assert(terrain_field_sample(plain, &box, &f0));
    int raised_above = 0, raised_below = 0;
    for (int z = 0; z < 24; z++)
        for (int y = 0; y < 28; y++)
            for (int x = 0; x < 8; x++) {
                size_t i = ((size_t)z * 28 + (size_t)y) * 8 + (size_t)x;
                if (y <= STRATA_H - 4) {
                    cr_assert_eq(fa.values[i], fb.values[i], "below the change, at (%d, %d, %d)", x - 4, y, z);
                    raised_below += fa.values[i] > f0.values[i];
                }
                if (y >= STRATA_H + 7) {
                    cr_assert_eq(fb.values[i], f0.values[i], "rock B unmapped raises nothing, at (%d, %d, %d)", x - 4, y, z);
                    raised_above += fa.values[i] > f0.values[i];
                }
            }
    cr_expect_gt(raised_below, 20, "rock A's columns stand out of the lower wall");
    cr_expect_gt(raised_above, 20, "rock B's slabs stand out of the upper wall");
    terrain_field_free(&fa);
    terrain_field_free(&fb);
    terrain_field_free(&f0);
    terrain_world_destroy(world_a);
    terrain_world_destroy(world_b);
    terrain_world_destroy(plain);
    rocks_cliffs_destroy(a);
    rocks_cliffs_destroy(b);
}

/* With no entry in the table the strata decide, as they always did: on a bedrock wall every
 * present copy's type is its anchor's band's (tabular in [0, 10) and [20, 30), columnar in
 * [10, 20)), and a table that maps only a material the world lacks (which takes the materials'
 * shortcut instead of the bands') finds the very same copies. (A game's material with no entry
 * gets none: block_type_follows_the_material.) */
Test(rocks_strata, no_entry_keeps_the_strata) {
    two_rocks bedrock = { TERRAIN_BEDROCK, TERRAIN_BEDROCK };
    rocks_cliffs_desc bands = strata_desc();
    bands.strata_count = 2, bands.strata[0] = ROCKS_BLOCK_TABULAR, bands.strata[1] = ROCKS_BLOCK_COLUMNAR;
    bands.stratum_height = 10;
    rocks_cliffs_desc absent = bands;
    absent.material_blocks[ROCK_A] = ROCKS_BLOCK_TABULAR;
    rocks_cliffs *p = rocks_cliffs_create(&bands), *q = rocks_cliffs_create(&absent);
    cr_assert_not_null(p);
    cr_assert_not_null(q);
    terrain_world *world_p = wall_world(&bedrock, p), *world_q = wall_world(&bedrock, q);
    double hp[4096], hq[4096];
    const rocks_block_type types[] = { ROCKS_BLOCK_TABULAR, ROCKS_BLOCK_COLUMNAR };
    for (int t = 0; t < 2; t++) {
        int np = present_anchor_heights(p, world_p, types[t], hp, 4096);
        int nq = present_anchor_heights(q, world_q, types[t], hq, 4096);
        cr_assert_leq(np, 4096);
        cr_expect_gt(np, 0, "%s blocks on the bedrock wall", rocks_block_type_name(types[t]));
        cr_assert_eq(np, nq, "%s: the same copies with a table that maps an absent rock", rocks_block_type_name(types[t]));
        for (int i = 0; i < np; i++) {
            cr_expect_eq(hp[i], hq[i]);
            int band = (int)floor(hp[i] / 10.0);
            cr_expect_eq(band & 1, t, "a %s copy at %.2f m lies in band %d", rocks_block_type_name(types[t]), hp[i], band);
        }
    }
    terrain_world_destroy(world_p);
    terrain_world_destroy(world_q);
    rocks_cliffs_destroy(p);
    rocks_cliffs_destroy(q);
}

/* Bedrock below follows its strata while a mapped rock above takes its own type: the bands
 * (columnar everywhere, 40 m each) meet the material's type (tabular) at the change. */
Test(rocks_strata, bedrock_strata_under_a_mapped_rock) {
    two_rocks rocks = { TERRAIN_BEDROCK, ROCK_B };
    rocks_cliffs_desc desc = strata_desc();
    desc.strata_count = 1, desc.strata[0] = ROCKS_BLOCK_COLUMNAR, desc.stratum_height = 40;
    desc.material_blocks[ROCK_B] = ROCKS_BLOCK_TABULAR;
    rocks_cliffs *cliffs = rocks_cliffs_create(&desc);
    cr_assert_not_null(cliffs);
    terrain_world *world = wall_world(&rocks, cliffs);
    double heights[4096];
    int columnar = present_anchor_heights(cliffs, world, ROCKS_BLOCK_COLUMNAR, heights, 4096);
    for (int i = 0; i < columnar && i < 4096; i++) cr_expect_lt(heights[i], STRATA_H + STEEP_REACH);
    int tabular = present_anchor_heights(cliffs, world, ROCKS_BLOCK_TABULAR, heights, 4096);
    for (int i = 0; i < tabular && i < 4096; i++) cr_expect_gt(heights[i], STRATA_H - STEEP_REACH);
    cr_expect_gt(columnar, 0);
    cr_expect_gt(tabular, 0);
    terrain_world_destroy(world);
    rocks_cliffs_destroy(cliffs);
}

/* Only rock breaks into blocks: an entry for air, sand, rocks or water, or an entry that is no
 * block type, is refused (NULL, with a message naming it). */
Test(rocks_strata, bad_tables_are_refused) {
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);
    const terrain_material not_rock[] = { TERRAIN_AIR, TERRAIN_SAND, TERRAIN_ROCKS, TERRAIN_WATER };
    for (size_t i = 0; i < CORE_COUNTOF(not_rock); i++) {
        rocks_cliffs_desc desc = { .tile_size = TILE };
        desc.material_blocks[not_rock[i]] = ROCKS_BLOCK_TABULAR;
        cr_expect_null(rocks_cliffs_create(&desc), "%s mapped", terrain_material_name(not_rock[i]));
    }
    rocks_cliffs_desc bad_type = { .tile_size = TILE };
    bad_type.material_blocks[ROCK_A] = ROCKS_BLOCK_TYPE_END;
    cr_expect_null(rocks_cliffs_create(&bad_type));
    bad_type.material_blocks[ROCK_A] = (rocks_block_type)-1;
    cr_expect_null(rocks_cliffs_create(&bad_type));
    core_log_set_level(level);
}
