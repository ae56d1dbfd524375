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
 * The hook's path for points and small fields is checked on the same wall: a one-sample field (a
 * picking ray's sample, answered from the blocks its thread kept for the sample's 2 m region) and
 * a small box (the player's collision) must equal the same samples of a big field (the cells'
 * path). */
#include "../engine/test.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#include <stdlib.h>
#include <string.h>

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

/* A lattice 1 m apart (offset a quarter metre, so points fall on every side of the 2 m regions'
 * borders) over the face, the cave and the floor, amplified as one big field (the cells' path);
 * then each of its points alone, and boxes of 4 × 5 × 4 of its samples (the player's collision
 * asks such boxes), each asked twice (the second answer from what the thread kept): the same
 * values, to the bit. */
#define LATTICE_X 11
#define LATTICE_Y 26
#define LATTICE_Z 41

static float *base_values(terrain_world *world, const double origin[3], const int n[3]) {
    float *v = malloc(sizeof *v * (size_t)n[0] * n[1] * n[2]);
    cr_assert_not_null(v);
    for (int k = 0; k < n[2]; k++)
        for (int j = 0; j < n[1]; j++)
            for (int i = 0; i < n[0]; i++)
                v[((size_t)k * n[1] + j) * n[0] + i] =
                    terrain_field_base_at(world, origin[0] + i, origin[1] + j, origin[2] + k, 0);
    return v;
}

Test(rocks_presence, points_and_small_boxes_equal_the_same_samples_of_a_big_field) {
    const terrain_material rock = TERRAIN_BEDROCK;
    rocks_cliffs *cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 1,
                                                                     .strata = { ROCKS_BLOCK_COLUMNAR }, .tile_size = TILE });
    cr_assert_not_null(cliffs);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){
        .generate = caved_chunk, .generate_user = (void *)&rock, .amplify = rocks_cliffs_amplify, .amplify_user = cliffs });
    const int n[3] = { LATTICE_X, LATTICE_Y, LATTICE_Z };
    const double origin[3] = { -5.75, -0.25, 0.25 };
    float *base = base_values(world, origin, n);
    float *big = malloc(sizeof *big * (size_t)n[0] * n[1] * n[2]);
    cr_assert_not_null(big);
    memcpy(big, base, sizeof *big * (size_t)n[0] * n[1] * n[2]);
    terrain_field whole = { .nx = n[0], .ny = n[1], .nz = n[2], .origin = { origin[0], origin[1], origin[2] },
                            .spacing = TERRAIN_COLUMN_SIZE, .values = big };
    rocks_cliffs_amplify(cliffs, world, &whole);

    int raised = 0, points_differ = 0, boxes = 0, boxes_differ = 0;
    for (int k = 0; k < n[2]; k++)
        for (int j = 0; j < n[1]; j++)
            for (int i = 0; i < n[0]; i++) {
                const size_t at = ((size_t)k * n[1] + j) * n[0] + i;
                float one = base[at];
                terrain_field point = { .nx = 1, .ny = 1, .nz = 1, .origin = { origin[0] + i, origin[1] + j, origin[2] + k },
                                        .spacing = TERRAIN_COLUMN_SIZE, .values = &one };
                rocks_cliffs_amplify(cliffs, world, &point);
                raised += big[at] > base[at];
                if (one != big[at] && points_differ++ < 5)
                    cr_expect_eq(one, big[at], "at (%g, %g, %g): %.9g as a point, %.9g in the big field",
                                 point.origin[0], point.origin[1], point.origin[2], (double)one, (double)big[at]);
            }
    for (int k = 0; k + 4 <= n[2]; k += 3)
        for (int j = 0; j + 5 <= n[1]; j += 3)
            for (int i = 0; i + 4 <= n[0]; i += 3)
                for (int ask = 0; ask < 2; ask++) {
                    float v[4 * 5 * 4];
                    for (int z = 0; z < 4; z++)
                        for (int y = 0; y < 5; y++)
                            for (int x = 0; x < 4; x++)
                                v[(z * 5 + y) * 4 + x] = base[((size_t)(k + z) * n[1] + (j + y)) * n[0] + (i + x)];
                    terrain_field box = { .nx = 4, .ny = 5, .nz = 4, .spacing = TERRAIN_COLUMN_SIZE, .values = v,
                                          .origin = { origin[0] + i, origin[1] + j, origin[2] + k } };
                    rocks_cliffs_amplify(cliffs, world, &box);
                    bool same = true;
                    for (int z = 0; z < 4; z++)
                        for (int y = 0; y < 5; y++)
                            for (int x = 0; x < 4; x++)
                                same &= v[(z * 5 + y) * 4 + x] == big[((size_t)(k + z) * n[1] + (j + y)) * n[0] + (i + x)];
                    boxes++;
                    if (!same && boxes_differ++ < 5)
                        cr_expect(same, "the box at (%g, %g, %g), asked %s, differs from the big field", box.origin[0],
                                  box.origin[1], box.origin[2], ask ? "again" : "first");
                }
    cr_expect_eq(points_differ, 0, "%d of %d points differ", points_differ, n[0] * n[1] * n[2]);
    cr_expect_eq(boxes_differ, 0, "%d of %d boxes differ", boxes_differ, boxes);
    cr_expect_gt(raised, 100, "blocks stand out of the wall at some points (%d)", raised);
    free(base);
    free(big);
    terrain_world_destroy(world);
    rocks_cliffs_destroy(cliffs);
}
