/* Rocks in a world (rocks.h, "placing rocks"): the lattice colouring, placement in a support,
 * edits, reloads, and a player standing on a pile. Expectations come from the definitions
 * (anchors in the support, checked here through terrain_world_material_at, a different path from
 * the placement's column table), from invariants (a partition of space places each rock once,
 * a replayed world is the same world) and from geometry worked out by hand (the pile's height). */
#include "../engine/test.h"
#include "rocks/rocks.h"

#include "core/core.h"
#include "game/player.h"
#include "rocks_test_cache.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PILE_X 16.0
#define PILE_Z 16.0
#define GROUND 8.0f
#define PILE_HEIGHT 3.0f

/* Flat bedrock at GROUND, and a cone of rocks PILE_HEIGHT high, 4 m in radius. */
static float pile_height(double x, double z) {
    return fmaxf(0.0f, PILE_HEIGHT - 0.75f * (float)hypot(x - PILE_X, z - PILE_Z));
}

static void pile_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    bool bare = user != NULL;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, GROUND - TERRAIN_FLOOR_Y);
    if (!bare) terrain_stacks_builder_push(builder, TERRAIN_ROCKS, pile_height((double)x + 0.5, (double)z + 0.5));
}

static terrain_stacks *pile_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, pile_column, user);
}

static terrain_world *pile_world(bool bare, terrain_edit_log *log) {
    return terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(3),
                                                       .generate = pile_chunk, .generate_user = bare ? (void *)1 : NULL,
                                                       .edits = log });
}

/* A small set, quick to build: what matters here is placement, not the rocks' finish. */
static rocks_tileset *small_set(void) {
    rocks_tileset_desc desc = { .cells = 4, .voxels_per_cell = 6, .shape = ROCKS_SHAPE_ROUND };
    desc.cache_path = rocks_test_cache(&desc);
    rocks_tileset *set = rocks_tileset_create(&desc);
    cr_assert_not_null(set);
    return set;
}

static const double PILE_MIN[3] = { 0, 0, 0 }, PILE_MAX[3] = { 32, 32, 32 };

static void place(const rocks_tileset *set, terrain_world *world, const double *min, const double *max,
                  rocks_placement *out) {
    cr_assert(rocks_place_box(&(rocks_place_desc){ .tiles = set, .world = world }, min, max, out));
}

/* ---- the colouring ---------------------------------------------------------------------------- */

Test(rocks_place, lattice_colouring_has_no_period) {
    /* A period p would make colour(x) = colour(x + p) everywhere; a fair hash agrees with its
     * shift about half the time. Every shift up to 12 along each axis of a 48³ block. */
    enum { S = 48, P = 12 };
    static uint8_t c[S][S][S];
    for (int k = 0; k < S; k++)
        for (int j = 0; j < S; j++)
            for (int i = 0; i < S; i++) c[k][j][i] = (uint8_t)rocks_lattice_colour(77, i, j, k);
    int ones = 0;
    for (int k = 0; k < S; k++)
        for (int j = 0; j < S; j++)
            for (int i = 0; i < S; i++) ones += c[k][j][i];
    cr_assert(ones > S * S * S * 45 / 100 && ones < S * S * S * 55 / 100, "colours balanced: %d of %d", ones, S * S * S);
    for (int dz = 0; dz <= P; dz++)
        for (int dy = 0; dy <= P; dy++)
            for (int dx = 0; dx <= P; dx++) {
                if (!dx && !dy && !dz) continue;
                int same = 0, total = 0;
                for (int k = 0; k + dz < S; k += 2)
                    for (int j = 0; j + dy < S; j += 2)
                        for (int i = 0; i + dx < S; i += 2) {
                            same += c[k][j][i] == c[k + dz][j + dy][i + dx];
                            total++;
                        }
                cr_assert(same < total * 6 / 10, "shift (%d,%d,%d) repeats %d of %d colours", dx, dy, dz, same, total);
            }
}

/* ---- placement -------------------------------------------------------------------------------- */

/* World metres of placed rock i's region origin (its vertices scale by 3 m from there). */
static void instance_origin(const rocks_placement *p, uint32_t i, double out[3]) {
    for (int a = 0; a < 3; a++) out[a] = p->origin[a] + p->instances[i].position[a];
}

static int anchors_in_rocks(terrain_world *world, const rocks_tileset *set, const rocks_rock *rock,
                            const double origin[3], double tile) {
    int inside = 0;
    for (uint32_t a = 0; a < rock->anchor_count; a++) {
        const float *q = set->anchors[rock->anchor_first + a];
        inside += terrain_world_material_at(world, origin[0] + q[0] * tile, origin[1] + q[1] * tile,
                                            origin[2] + q[2] * tile) == TERRAIN_ROCKS;
    }
    return inside;
}

/* The small set placed over the pile's box (or over bare ground); pile_free releases it all. */
typedef struct pile_placed {
    rocks_tileset *set;
    terrain_world *world;
    rocks_placement p;
} pile_placed;

static pile_placed pile_place(bool bare) {
    pile_placed c = { .set = small_set(), .world = pile_world(bare, NULL) };
    place(c.set, c.world, PILE_MIN, PILE_MAX, &c.p);
    return c;
}

static void pile_free(pile_placed *c) {
    rocks_placement_free(&c->p);
    terrain_world_destroy(c->world);
    rocks_tileset_destroy(c->set);
}

Test(rocks_place, every_rock_placed_has_most_anchors_in_the_rock_layer) {
    pile_placed c = pile_place(false);
    const rocks_tileset *set = c.set;
    terrain_world *world = c.world;
    const rocks_placement p = c.p;
    cr_assert_gt(p.count, 20, "a 3 m pile of 4 m radius holds rocks: %u", p.count);
    for (uint32_t i = 0; i < p.count; i++) {
        const rocks_rock *rock = &set->rocks[p.instances[i].rock];
        double origin[3];
        instance_origin(&p, i, origin);
        int inside = anchors_in_rocks(world, set, rock, origin, 3.0);
        cr_assert_geq(inside * 10, (int)rock->anchor_count * 6, "rock %u: %d of %u anchors in the layer", i, inside,
                      rock->anchor_count);
        /* and it stands in the pile's footprint */
        double seed_r = hypot(origin[0] + rock->seed[0] * 3.0 - PILE_X, origin[2] + rock->seed[2] * 3.0 - PILE_Z);
        cr_assert_lt(seed_r, 4.0 + 3.0 * set->max_radius, "rock %u's seed %.2f m from the pile's axis", i, seed_r);
    }
    pile_free(&c);
}

Test(rocks_place, bare_ground_has_no_rocks) {
    pile_placed c = pile_place(true);
    cr_assert_eq(c.p.count, 0);
    pile_free(&c);
}

typedef struct placed_rock { int64_t mm[3]; uint32_t rock; } placed_rock;

static int placed_compare(const void *a, const void *b) { return memcmp(a, b, sizeof(placed_rock)); }

static size_t collect(const rocks_placement *p, placed_rock *out, size_t at) {
    for (uint32_t i = 0; i < p->count; i++) {
        placed_rock r = { .rock = p->instances[i].rock };
        for (int a = 0; a < 3; a++) r.mm[a] = llround((p->origin[a] + p->instances[i].position[a]) * 1000.0);
        out[at++] = r;
    }
    return at;
}

Test(rocks_place, boxes_that_partition_space_place_each_rock_once) {
    rocks_tileset *set = small_set();
    terrain_world *world = pile_world(false, NULL);
    rocks_placement whole = { 0 }, part = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &whole);
    placed_rock *a = calloc(whole.count + 1, sizeof *a), *b = calloc(whole.count * 2 + 64, sizeof *b);
    size_t na = collect(&whole, a, 0), nb = 0;
    /* 8 boxes of 16 m, at odd offsets from the tile lattice (3 m) */
    for (int c = 0; c < 8; c++) {
        double lo[3] = { (c & 1) * 16.0 + 0, ((c >> 1) & 1) * 16.0, ((c >> 2) & 1) * 16.0 };
        double hi[3] = { lo[0] + 16, lo[1] + 16, lo[2] + 16 };
        place(set, world, lo, hi, &part);
        cr_assert_leq(nb + part.count, whole.count * 2 + 64);
        nb = collect(&part, b, nb);
    }
    cr_assert_eq(nb, na, "the parts place %zu rocks, the whole %zu", nb, na);
    qsort(a, na, sizeof *a, placed_compare);
    qsort(b, nb, sizeof *b, placed_compare);
    cr_assert(memcmp(a, b, na * sizeof *a) == 0, "the same rocks at the same places");
    for (size_t i = 1; i < na; i++) cr_assert(placed_compare(&a[i - 1], &a[i]) != 0, "rock placed twice");
    free(a), free(b);
    rocks_placement_free(&whole);
    rocks_placement_free(&part);
    terrain_world_destroy(world);
    rocks_tileset_destroy(set);
}

/* ---- a brute-force reference ------------------------------------------------------------------ */

/* Layers that vary from column to column: rock on bedrock, on some columns a cave (air) and a
 * second rock layer over it, sand, a third rock layer, and on every fifth row of columns 3 m of
 * sand that buries the rock under it. Columns hold one to three rock intervals, so a rock's
 * footprint meets columns that differ. */
static void strata_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    double u = (double)x, v = (double)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, GROUND - TERRAIN_FLOOR_Y);
    terrain_stacks_builder_push(builder, TERRAIN_ROCKS, 0.5f + 1.5f * (float)(0.5 + 0.5 * sin(u * 0.7) * cos(v * 0.5)));
    if ((x + z) % 3 == 0) {
        terrain_stacks_builder_push(builder, TERRAIN_AIR, 0.75f);
        terrain_stacks_builder_push(builder, TERRAIN_ROCKS, 0.5f);
    }
    terrain_stacks_builder_push(builder, TERRAIN_SAND, 0.25f + 0.5f * (float)((x * 7 + z * 3) % 4) / 4.0f);
    if (x % 4 != 0) terrain_stacks_builder_push(builder, TERRAIN_ROCKS, 1.0f);
    if (z % 5 == 0) terrain_stacks_builder_push(builder, TERRAIN_SAND, 3.0f);
}

static terrain_stacks *strata_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, strata_column, user);
}

/* The layers of the column under world (x, z). */
static int column_layers(terrain_world *world, double x, double z, terrain_layer layers[64]) {
    int64_t i = (int64_t)floor(x), k = (int64_t)floor(z);
    int64_t cx = (i >= 0 ? i : i - 31) / 32, cz = (k >= 0 ? k : k - 31) / 32;
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    int n = terrain_stacks_column(stacks, (int)(i - cx * 32), (int)(k - cz * 32), layers, 64);
    return n < 64 ? n : 64;
}

/* A point is in the support when its height lies in a rock layer of its column, bottom included,
 * top not: [lo, hi) read from the layers (sums of multiples of 1/32 m from the floor, exact). Not
 * terrain_world_material_at, which rounds the height to a float first: the small set's voxel
 * centres lie on the 1/32 m grid of the layers' bounds, so that rounding decides ties there. */
static bool reference_in_rocks(terrain_world *world, double x, double y, double z) {
    terrain_layer layers[64];
    int n = column_layers(world, x, z, layers);
    double lo = TERRAIN_FLOOR_Y;
    for (int l = 0; l < n; l++) {
        double hi = lo + layers[l].thickness;
        if (layers[l].material == TERRAIN_ROCKS && y >= lo && y < hi) return true;
        lo = hi;
    }
    return false;
}

/* The definition, read from the world's own layers: the seed's column, its rock layers bottom-up
 * (adjacent ones one layer); the first within `depth` of the seed buries it when the solid run it
 * lies in rises more than `depth` above the seed. */
static bool reference_buried(terrain_world *world, const double seed[3], double depth) {
    terrain_layer layers[64];
    int n = column_layers(world, seed[0], seed[2], layers);
    double y = TERRAIN_FLOOR_Y;
    for (int l = 0; l < n; l++) {
        double lo = y, hi = y + layers[l].thickness;
        y = hi;
        if (layers[l].material != TERRAIN_ROCKS) continue;
        while (l + 1 < n && layers[l + 1].material == TERRAIN_ROCKS) hi = y = y + layers[++l].thickness;
        if (!(seed[1] >= lo - depth && seed[1] < hi + depth)) continue;
        double run_top = hi;
        for (int m = l + 1; m < n && layers[m].material != TERRAIN_AIR && layers[m].material != TERRAIN_WATER; m++)
            run_top += layers[m].thickness;
        return run_top - seed[1] > depth;
    }
    return false;
}

typedef struct reference_counts { int buried, too_few; } reference_counts;

/* Every tile of the lattice over the box, every rock it lists, tested by the definition alone
 * (rocks.h), with no culling: seed in the box, not buried, at least 60 % of its anchors in a rock
 * layer. In lattice order (k, j, i), then the tile's order. */

static uint32_t reference_place(const rocks_tileset *set, terrain_world *world, const double min[3],
                                const double max[3], rocks_instance *out, uint32_t capacity, reference_counts *why) {
    const double tile = 3.0;
    uint64_t seed = terrain_world_generation(world)->seed ^ 0x726f636b73ull;
    uint32_t count = 0;
    for (int64_t k = (int64_t)floor(min[2] / tile); k < (int64_t)ceil(max[2] / tile); k++)
        for (int64_t j = (int64_t)floor(min[1] / tile); j < (int64_t)ceil(max[1] / tile); j++)
            for (int64_t i = (int64_t)floor(min[0] / tile); i < (int64_t)ceil(max[0] / tile); i++) {
                uint8_t colour[8];
                for (int c = 0; c < 8; c++)
                    colour[c] = (uint8_t)rocks_lattice_colour(seed, i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                const rocks_tile *t = &set->tiles[rocks_tile_index(colour)];
                for (uint32_t e = t->first; e < t->first + t->count; e++) {
                    const rocks_rock *rock = &set->rocks[set->entries[e].rock];
                    double origin[3], at[3];
                    bool in_box = true;
                    for (int a = 0; a < 3; a++) {
                        origin[a] = ((double)(a == 0 ? i : a == 1 ? j : k) + set->entries[e].offset[a]) * tile;
                        at[a] = origin[a] + rock->seed[a] * tile;
                        in_box = in_box && at[a] >= min[a] && at[a] < max[a];
                    }
                    if (!in_box) continue;
                    if (reference_buried(world, at, 2.0 * set->max_radius * tile)) {
                        why->buried++;
                        continue;
                    }
                    int inside = 0;
                    for (uint32_t a = 0; a < rock->anchor_count; a++) {
                        const float *q = set->anchors[rock->anchor_first + a];
                        inside += reference_in_rocks(world, origin[0] + q[0] * tile, origin[1] + q[1] * tile,
                                                     origin[2] + q[2] * tile);
                    }
                    if (inside * 10 < (int)rock->anchor_count * 6) {
                        why->too_few += inside > 0;
                        continue;
                    }
                    cr_assert_lt(count, capacity);
                    out[count++] = (rocks_instance){ .position = { (float)(origin[0] - min[0]), (float)(origin[1] - min[1]),
                                                                   (float)(origin[2] - min[2]) },
                                                     .rock = set->entries[e].rock };
                }
            }
    return count;
}

static void expect_reference(const rocks_tileset *set, terrain_world *world, const double min[3], const double max[3],
                             reference_counts *why) {
    rocks_placement p = { 0 };
    place(set, world, min, max, &p);
    uint32_t capacity = p.count + 4096;
    rocks_instance *expected = calloc(capacity, sizeof *expected);
    uint32_t count = reference_place(set, world, min, max, expected, capacity, why);
    cr_assert_eq(p.count, count, "box (%g, %g, %g): %u rocks placed, the definition keeps %u", min[0], min[1], min[2],
                 p.count, count);
    for (uint32_t r = 0; r < count; r++) {
        cr_assert_eq(p.instances[r].rock, expected[r].rock, "instance %u: rock %u, the definition's %u", r,
                     p.instances[r].rock, expected[r].rock);
        for (int a = 0; a < 3; a++)
            cr_assert_float_eq(p.instances[r].position[a], expected[r].position[a], 1e-4f, "instance %u axis %d", r, a);
    }
    free(expected);
    rocks_placement_free(&p);
}

/* The placement's box holds every instance's rock, and is no looser than what its tiles list
 * can make it: per tile and offset, a rock's bounds (a few tile units) round the kept ones. */
Test(rocks_place, the_placement_box_holds_every_rock_placed) {
    pile_placed c = pile_place(false);
    const rocks_tileset *set = c.set;
    const rocks_placement p = c.p;
    cr_assert_gt(p.count, 20);
    float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    for (uint32_t i = 0; i < p.count; i++) {
        const rocks_rock *rock = &set->rocks[p.instances[i].rock];
        for (int a = 0; a < 3; a++) {
            float rock_lo = p.instances[i].position[a] + rock->bounds_min[a] * 3.0f;
            float rock_hi = p.instances[i].position[a] + rock->bounds_max[a] * 3.0f;
            cr_assert_geq(rock_lo, p.bounds_min[a] - 1e-4f, "rock %u below the box on axis %d", i, a);
            cr_assert_leq(rock_hi, p.bounds_max[a] + 1e-4f, "rock %u above the box on axis %d", i, a);
            lo[a] = fminf(lo[a], rock_lo), hi[a] = fmaxf(hi[a], rock_hi);
        }
    }
    for (int a = 0; a < 3; a++) {   /* a rock lies within its region, two tiles wide at most */
        cr_log_info("axis %d: the box %.2f m below the rocks, %.2f m above", a, lo[a] - p.bounds_min[a], p.bounds_max[a] - hi[a]);
        cr_expect_leq(lo[a] - p.bounds_min[a], 6.0f, "axis %d: the box reaches %.2f m below the rocks", a, lo[a] - p.bounds_min[a]);
        cr_expect_leq(p.bounds_max[a] - hi[a], 6.0f, "axis %d: the box reaches %.2f m above the rocks", a, p.bounds_max[a] - hi[a]);
    }
    pile_free(&c);
}

Test(rocks_place, placement_is_the_definition_applied_to_every_rock) {
    rocks_tileset *set = small_set();
    terrain_world *pile = pile_world(false, NULL);
    terrain_world *strata = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5),
                                                                        .generate = strata_chunk });
    reference_counts why = { 0 };
    expect_reference(set, pile, PILE_MIN, PILE_MAX, &why);
    /* boxes off the tile lattice and the chunk grid, across chunk borders and negative coordinates */
    const double boxes[][2][3] = { { { -7.5, 3.25, -12.0 }, { 21.0, 19.0, 9.5 } }, { { 20.2, 6.0, 27.7 }, { 45.1, 16.5, 41.0 } },
                                   { { 100000.5, 6.0, -70003.2 }, { 100013.0, 14.0, -69990.0 } } };   /* 100 km out */
    for (size_t b = 0; b < sizeof boxes / sizeof boxes[0]; b++) expect_reference(set, strata, boxes[b][0], boxes[b][1], &why);
    /* the strata hold rocks of every kind: kept, buried under the sand, dropped with some anchors in */
    rocks_placement p = { 0 };
    place(set, strata, boxes[0][0], boxes[0][1], &p);
    cr_assert_gt(p.count, 100, "%u rocks in the strata", p.count);
    cr_assert_gt(why.buried, 50, "%d buried", why.buried);
    cr_assert_gt(why.too_few, 50, "%d with too few anchors in", why.too_few);
    /* an index made once places the same bytes as the one a call makes for itself */
    rocks_place_index *index = rocks_place_index_create(set);
    rocks_placement with = { 0 };
    cr_assert(rocks_place_box(&(rocks_place_desc){ .tiles = set, .index = index, .world = strata }, boxes[0][0],
                              boxes[0][1], &with));
    cr_assert_eq(with.count, p.count);
    cr_assert(memcmp(with.instances, p.instances, p.count * sizeof *p.instances) == 0);
    rocks_place_index_destroy(index);
    rocks_placement_free(&with);
    rocks_placement_free(&p);
    terrain_world_destroy(strata);
    terrain_world_destroy(pile);
    rocks_tileset_destroy(set);
}

/* A vertical shaft swept through the pile's centre: everything within 1.5 m becomes air. */
static terrain_edit shaft(double points[2][3]) {
    points[0][0] = PILE_X, points[0][1] = GROUND + 6, points[0][2] = PILE_Z;
    points[1][0] = PILE_X, points[1][1] = GROUND - 1, points[1][2] = PILE_Z;
    return (terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
                           .sweep = { .points = (const double (*)[3])points, .point_count = 2, .radius = 1.5f } };
}

/* Whether a placed rock rests on something: some vertex of it has material (the layer, the
 * bedrock) within 2 cm under it. A rock on the rim of a hole may overhang it; one with nothing
 * under any of its points floats. */
static bool rock_rests(terrain_world *world, const rocks_tileset *set, const rocks_rock *rock, const double origin[3]) {
    for (uint32_t v = rock->vertex_first; v < rock->vertex_first + rock->vertex_count; v++) {
        const float *q = set->vertices[v].position;
        if (terrain_world_material_at(world, origin[0] + q[0] * 3.0, origin[1] + q[1] * 3.0 - 0.02,
                                      origin[2] + q[2] * 3.0) != TERRAIN_AIR)
            return true;
    }
    return false;
}

Test(rocks_place, after_a_carve_no_rock_floats_and_the_dug_rocks_are_gone) {
    rocks_tileset *set = small_set();
    terrain_world *world = pile_world(false, NULL);
    rocks_placement before = { 0 }, after = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &before);
    double points[2][3];
    terrain_edit edit = shaft(points);
    terrain_chunk_coord changed[8];
    cr_assert_gt(terrain_world_edit(world, &edit, changed, 8), 0);
    place(set, world, PILE_MIN, PILE_MAX, &after);
    cr_assert_lt(after.count, before.count, "the shaft took rocks: %u → %u", before.count, after.count);
    for (uint32_t i = 0; i < after.count; i++) {
        const rocks_rock *rock = &set->rocks[after.instances[i].rock];
        double origin[3];
        instance_origin(&after, i, origin);
        int inside = anchors_in_rocks(world, set, rock, origin, 3.0);
        cr_assert_geq(inside * 10, (int)rock->anchor_count * 6, "a rock left with %d of %u anchors", inside,
                      rock->anchor_count);
        cr_assert(rock_rests(world, set, rock, origin), "rock %u at (%.2f, %.2f, %.2f) floats: air 2 cm under all of it",
                  i, origin[0], origin[1], origin[2]);
    }
    /* Every rock that went had its anchors taken (fewer than 60 % left in the layer). */
    for (uint32_t i = 0; i < before.count; i++) {
        bool kept = false;
        for (uint32_t j = 0; j < after.count && !kept; j++)
            kept = after.instances[j].rock == before.instances[i].rock &&
                   memcmp(after.instances[j].position, before.instances[i].position, sizeof(float[3])) == 0;
        if (kept) continue;
        const rocks_rock *rock = &set->rocks[before.instances[i].rock];
        double origin[3];
        instance_origin(&before, i, origin);
        int inside = anchors_in_rocks(world, set, rock, origin, 3.0);
        cr_assert_lt(inside * 10, (int)rock->anchor_count * 6, "a rock went with %d of %u anchors still in", inside,
                     rock->anchor_count);
    }
    rocks_placement_free(&before);
    rocks_placement_free(&after);
    terrain_world_destroy(world);
    rocks_tileset_destroy(set);
}

Test(rocks_place, a_reloaded_world_gives_the_same_rocks_byte_for_byte) {
    rocks_tileset *set = small_set();
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = 1234 });
    terrain_world *world = pile_world(false, log);
    double points[2][3];
    terrain_edit edit = shaft(points);
    terrain_chunk_coord changed[8];
    cr_assert_gt(terrain_world_edit(world, &edit, changed, 8), 0);
    rocks_placement first = { 0 }, second = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &first);
    terrain_world_destroy(world);
    world = pile_world(false, log);          /* a fresh world replays the log */
    place(set, world, PILE_MIN, PILE_MAX, &second);
    cr_assert_eq(first.count, second.count);
    cr_assert(memcmp(first.instances, second.instances, first.count * sizeof *first.instances) == 0);
    rocks_placement_free(&first);
    rocks_placement_free(&second);
    terrain_world_destroy(world);
    terrain_edit_log_destroy(log);
    rocks_tileset_destroy(set);
}

/* ---- the player on a pile ----------------------------------------------------------------------- */

typedef struct pile_obstacles {
    const rocks_tileset *set;
    const rocks_placement *placement;
} pile_obstacles;

static float pile_distance(void *user, const double point[3], float max_distance, float normal[3]) {
    const pile_obstacles *o = user;
    float best = max_distance;
    for (uint32_t i = 0; i < o->placement->count; i++) {
        const rocks_instance *in = &o->placement->instances[i];
        float local[3], n[3];
        for (int a = 0; a < 3; a++)
            local[a] = (float)((point[a] - o->placement->origin[a] - in->position[a]) / 3.0);
        float d = rocks_hull_distance(&o->set->rocks[in->rock], local, n) * 3.0f;
        if (d < best) {
            best = d;
            memcpy(normal, n, sizeof n);
        }
    }
    return best;
}

Test(rocks_place, the_player_stands_on_a_rock_pile) {
    rocks_tileset *set = small_set();
    terrain_world *world = pile_world(false, NULL);
    rocks_placement p = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &p);
    pile_obstacles obstacles = { set, &p };
    game_player player;
    game_player_init(&player, &(game_player_desc){ .obstacle_distance = pile_distance, .obstacle_user = &obstacles });
    player.position[0] = PILE_X, player.position[1] = GROUND + PILE_HEIGHT + 2.0, player.position[2] = PILE_Z;
    input_actions idle = { 0 };
    for (int f = 0; f < 180; f++) game_player_update(&player, world, &idle, 1.0f / 60.0f);
    /* Without the rocks the player would fall through the layer to the bedrock at GROUND. */
    cr_assert(player.on_ground, "standing after 3 s");
    cr_assert_gt(player.position[1], GROUND + 1.0, "feet at %.2f m: on the pile, not the bedrock under it (%.1f)",
                 player.position[1], (double)GROUND);
    cr_assert_lt(player.position[1], GROUND + PILE_HEIGHT + 0.6, "feet at %.2f m: no higher than the pile's top",
                 player.position[1]);
    /* The capsule's bottom sphere (radius 0.35) rests on the rocks' hulls, not in them. */
    double feet[3] = { player.position[0], player.position[1] + 0.35, player.position[2] };
    float n[3];
    float clear = pile_distance(&obstacles, feet, 2.0f, n);
    cr_assert_gt(clear, 0.34f, "the bottom sphere is %.3f m from the nearest rock (radius 0.35)", clear);
    /* Walking across the pile: never into a rock, and over it rather than stopped by it. */
    double start_z = player.position[2];
    input_actions forward = { .move_y = 1.0f };
    for (int f = 0; f < 150; f++) {
        game_player_update(&player, world, &forward, 1.0f / 60.0f);
        double probe[3] = { player.position[0], player.position[1] + 0.35, player.position[2] };
        clear = pile_distance(&obstacles, probe, 2.0f, n);
        cr_assert_gt(clear, 0.3f, "frame %d: the bottom sphere %.3f m from a rock", f, clear);
    }
    cr_assert_gt(fabs(player.position[2] - start_z), 4.0, "walked %.2f m in 2.5 s across the pile",
                 fabs(player.position[2] - start_z));
    rocks_placement_free(&p);
    terrain_world_destroy(world);
    rocks_tileset_destroy(set);
}

Test(rocks_place, an_index_of_another_tile_set_is_refused) {
    rocks_tileset *set = small_set(), *other = small_set();
    terrain_world *world = pile_world(false, NULL);
    rocks_place_index *index = rocks_place_index_create(other);
    rocks_placement p = { 0 };
    cr_assert_not(rocks_place_box(&(rocks_place_desc){ .tiles = set, .index = index, .world = world }, PILE_MIN,
                                  PILE_MAX, &p));
    cr_assert_null(rocks_place_index_create(NULL));
    rocks_place_index_destroy(index);
    rocks_placement_free(&p);
    terrain_world_destroy(world);
    rocks_tileset_destroy(other);
    rocks_tileset_destroy(set);
}

/* Releasing the CPU meshes (what the game does once they are on the GPU) leaves placement as it
 * was, and the PLY writer says why it cannot write. */
Test(rocks_place, placement_needs_no_meshes) {
    rocks_tileset *set = small_set();
    terrain_world *world = pile_world(false, NULL);
    rocks_placement with = { 0 }, without = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &with);
    size_t bytes = set->bytes;
    rocks_tiles_release_meshes(set);
    cr_expect_null(set->vertices);
    cr_expect_lt(set->bytes, bytes / 2, "%zu of %zu bytes left", set->bytes, bytes);
    place(set, world, PILE_MIN, PILE_MAX, &without);
    cr_assert_eq(with.count, without.count);
    cr_expect(memcmp(with.instances, without.instances, with.count * sizeof *with.instances) == 0);
    core_error error = { 0 };
    cr_expect_not(rocks_tile_write_ply(set, 0, "/tmp/never.ply", &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "the meshes were released: %s", error.message);
    rocks_placement_free(&with);
    rocks_placement_free(&without);
    terrain_world_destroy(world);
    rocks_tileset_destroy(set);
}
