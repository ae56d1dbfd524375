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
    rocks_tiles_desc desc = { .cells = 4, .voxels_per_cell = 6, .shape = ROCKS_SHAPE_ROUND };
    desc.cache_path = rocks_test_cache(&desc);
    rocks_tileset *set = rocks_tiles_create(&desc);
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

Test(rocks_place, every_rock_placed_has_most_anchors_in_the_rock_layer) {
    rocks_tileset *set = small_set();
    terrain_world *world = pile_world(false, NULL);
    rocks_placement p = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &p);
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
    rocks_placement_free(&p);
    terrain_world_destroy(world);
    rocks_tiles_destroy(set);
}

Test(rocks_place, bare_ground_has_no_rocks) {
    rocks_tileset *set = small_set();
    terrain_world *world = pile_world(true, NULL);
    rocks_placement p = { 0 };
    place(set, world, PILE_MIN, PILE_MAX, &p);
    cr_assert_eq(p.count, 0);
    rocks_placement_free(&p);
    terrain_world_destroy(world);
    rocks_tiles_destroy(set);
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
    rocks_tiles_destroy(set);
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
    rocks_tiles_destroy(set);
}

Test(rocks_place, a_reloaded_world_gives_the_same_rocks_byte_for_byte) {
    rocks_tileset *set = small_set();
    terrain_edit_log *log = terrain_edit_log_create(1234);
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
    rocks_tiles_destroy(set);
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
    game_player_init(&player, &(game_player_params){ .obstacle_distance = pile_distance, .obstacle_user = &obstacles });
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
    rocks_tiles_destroy(set);
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
    char error[256] = "";
    cr_expect_not(rocks_tile_write_ply(set, 0, "/tmp/never.ply", error, sizeof error));
    cr_expect(strstr(error, "released") != NULL, "%s", error);
    rocks_placement_free(&with);
    rocks_placement_free(&without);
    terrain_world_destroy(world);
    rocks_tiles_destroy(set);
}
