/* The cliffs' shortcuts change no block (rocks_cliffs.c): before the field's wall test, an anchor
 * is passed over when the cube its test reads lies wholly in air or wholly in solid rock, judged
 * by the column chunks' bounds and then by each column's own spans, and, with materials mapped,
 * when no rock of its type lies near. Each answer must be the one the wall test would give.
 *
 * The world is a wall made by hand with what makes the column test hard: rock behind the face
 * (x < 0) up to 20 m, a cave into it from 5 to 14 m, 10 m deep and 22 m wide (columns whose
 * first solid run ends below their top: the cave's side walls are walls between runs), a floor at
 * 0 in front with water on part of it, and a step of sand on top of the wall in places. Every tile cell along the face is asked both ways:
 * rocks__cliffs_present (the hook's own path, shortcuts and cache) against
 * rocks__cliffs_present_unfiltered (every anchor through the wall test).
 *
 * The hook's point path is checked on the same wall: a one-sample field (a picking ray's sample,
 * answered from the blocks its thread kept for the sample's 2 m region) must equal the same point
 * taken as the centre of a 3³ field (the cells' path). */
#include "../engine/test.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#define TILE 12.0f

static void caved_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const terrain_material rock = *(const terrain_material *)user;
    if (x < 0) {
        const bool cave = z >= 8 && z < 30 && x > -10;
        terrain_stacks_builder_push(b, rock, (cave ? 5.0f : 20.0f) - TERRAIN_FLOOR_Y);
        if (cave) {
            terrain_stacks_builder_push(b, TERRAIN_AIR, 9.0f);
            terrain_stacks_builder_push(b, rock, 6.0f);
        }
        if (z % 12 < 4) terrain_stacks_builder_push(b, TERRAIN_SAND, 1.5f);
    } else {
        terrain_stacks_builder_push(b, rock, 0.0f - TERRAIN_FLOOR_Y);
        if (z > 20 && x < 6) terrain_stacks_builder_push(b, TERRAIN_WATER, 2.0f);
    }
}

static terrain_stacks *caved_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, caved_column, user);
}

/* Asks every cell along the face (x cells −2 … 0, heights to 36 m, z to 48 m) both ways; returns
 * the present blocks found, and fails on any cell where the two differ. */
static int present_both_ways(rocks_cliffs *cliffs, terrain_world *world, rocks_block_type type) {
    const rocks_block_tile *tile = rocks__cliffs_tile(cliffs, type);
    cr_assert_not_null(tile);
    uint64_t fast[64], slow[64];
    const uint32_t words = (tile->block_count + 63) / 64;
    cr_assert_leq(words, 64);
    int present = 0;
    for (int64_t z = 0; z < 4; z++)
        for (int64_t y = -1; y < 3; y++)
            for (int64_t x = -2; x <= 0; x++) {
                const int64_t cell[3] = { x, y, z };
                bool asked = rocks__cliffs_present(cliffs, world, type, cell, fast);
                cr_assert_eq(asked, rocks__cliffs_present_unfiltered(cliffs, world, type, cell, slow));
                for (uint32_t w = 0; w < words; w++) {
                    cr_expect_eq(fast[w], slow[w], "cell (%lld, %lld, %lld), blocks %u…: %016llx with the shortcuts, "
                                 "%016llx without", (long long)x, (long long)y, (long long)z, w * 64,
                                 (unsigned long long)fast[w], (unsigned long long)slow[w]);
                    present += __builtin_popcountll(slow[w]);
                }
            }
    return present;
}

/* The caved wall of `rock`, with cliffs of `desc` (a columnar stratum): every cell both ways. */
static void check_caved_wall(terrain_material rock, const rocks_cliffs_desc *desc) {
    rocks_cliffs *cliffs = rocks_cliffs_create(desc);
    cr_assert_not_null(cliffs);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generate = caved_chunk, .generate_user = &rock, .amplify = rocks_cliffs_amplify, .amplify_user = cliffs });
    int present = present_both_ways(cliffs, world, ROCKS_BLOCK_COLUMNAR);
    cr_expect_gt(present, 10, "the wall breaks into columns (%d blocks)", present);
    terrain_world_destroy(world);
    rocks_cliffs_destroy(cliffs);
}

/* Bedrock, its block type by the strata (the bounds' shortcut alone). */
Test(rocks_presence, the_shortcuts_over_bedrock_change_no_block) {
    check_caved_wall(TERRAIN_BEDROCK, &(rocks_cliffs_desc){ .strata_count = 1, .strata = { ROCKS_BLOCK_COLUMNAR },
                                                            .tile_size = TILE });
}

/* A game's rock mapped to a type (the materials' shortcuts too). */
Test(rocks_presence, the_shortcuts_over_a_mapped_rock_change_no_block) {
    const terrain_material rock = (terrain_material)TERRAIN_MATERIAL_BUILTIN_COUNT;
    rocks_cliffs_desc desc = { .strata_count = 1, .strata = { ROCKS_BLOCK_COLUMNAR }, .tile_size = TILE };
    desc.material_blocks[rock] = ROCKS_BLOCK_COLUMNAR;
    check_caved_wall(rock, &desc);
}

/* Every point of a 1 m lattice (offset a quarter metre, so points fall on every side of the 2 m
 * regions' borders) over the face, the cave and the floor: the point path and the field path give
 * the same value, to the bit. */
Test(rocks_presence, a_point_sample_equals_the_same_point_of_a_field) {
    const terrain_material rock = TERRAIN_BEDROCK;
    rocks_cliffs *cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 1,
                                                                     .strata = { ROCKS_BLOCK_COLUMNAR }, .tile_size = TILE });
    cr_assert_not_null(cliffs);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generate = caved_chunk, .generate_user = (void *)&rock, .amplify = rocks_cliffs_amplify, .amplify_user = cliffs });
    int points = 0, raised = 0, differ = 0;
    for (int k = 0; k <= 40; k++)
        for (int j = -1; j <= 24; j++)
            for (int i = -6; i <= 4; i++) {
                const double p[3] = { i + 0.25, j + 0.75, k + 0.25 };
                const float base = terrain_field_base_at(world, p[0], p[1], p[2], 0);
                float one = base, cube[27];
                for (int n = 0; n < 27; n++) cube[n] = base;
                terrain_field point = { .nx = 1, .ny = 1, .nz = 1, .origin = { p[0], p[1], p[2] },
                                        .spacing = TERRAIN_COLUMN_SIZE, .values = &one };
                terrain_field around = { .nx = 3, .ny = 3, .nz = 3, .spacing = TERRAIN_COLUMN_SIZE, .values = cube,
                                         .origin = { p[0] - TERRAIN_COLUMN_SIZE, p[1] - TERRAIN_COLUMN_SIZE,
                                                     p[2] - TERRAIN_COLUMN_SIZE } };
                rocks_cliffs_amplify(cliffs, world, &point);
                rocks_cliffs_amplify(cliffs, world, &around);
                points++;
                raised += one > base;
                if (one != cube[13] && differ++ < 5)
                    cr_expect_eq(one, cube[13], "at (%g, %g, %g): %.9g as a point, %.9g in a field", p[0], p[1], p[2],
                                 (double)one, (double)cube[13]);
            }
    cr_expect_eq(differ, 0, "%d of %d points differ", differ, points);
    cr_expect_gt(raised, 100, "blocks stand out of the wall at some points (%d)", raised);
    terrain_world_destroy(world);
    rocks_cliffs_destroy(cliffs);
}
