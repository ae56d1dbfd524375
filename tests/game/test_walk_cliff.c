/* Looks at a cliff (walk.h: game_find_cliff_view, `cliff R` lines, game_walk_resolve_stops).
 *
 * The worlds are made by hand: a bedrock floor at y = 10 and, in the wall world, bedrock up to
 * y = 30 for every column x ≥ 20: a vertical face at x = 20, turned to −x. What the finder must
 * give, searching from (0.5, 0.5), follows from walk.h's rules:
 *   - the columns searched have centres at odd x and z; of the lit directions, the most lit is
 *     45° (dot 0.64 with (0.55, 0.35)), but along it the columns 4 m to one side of any foot do
 *     not rise; the next, 0° (+x, dot 0.55), rises 20 m from the foot column x = 19 (centre 19)
 *     at 2 m and at 6 m past it, and so do the columns 2 and 4 m to either side; the nearest such
 *     foot is (19, 1), 18.5 m away;
 *   - the face: at 2, 4, 6 and 8 m over the foot (y = 10), the field is first ≥ 0 about a metre
 *     along +x, where its gradient is level: steep; bedrock 6 m past the foot, 10 m up;
 *   - the point looked at is a metre past the foot, min(20 / 2, 6) = 6 m over it: (20, 16, 1);
 *   - the eye, 2.12 m over the floor (12.12), b metres back: the wall's top (30, from 2 m past
 *     the foot) is atan(17.88 / (b + 2)) up and the face atan(3.88 / (b + 1)) up; their difference
 *     must stay within 30° − 6° = 24°: b = 16 gives 31.9°, 20 gives 28.6°, 24 gives 25.7°, 28
 *     gives 23.2°. So the eye is at (−9, 12.12, 1), yaw 270 (looking +x), pitch atan(3.88 / 29).
 * With no wall, with the wall of sand, with a 50° ramp instead or with the floor under water,
 * nothing is found. */
#include "../engine/test.h"
#include "walk_test.h"
#include "game/walk.h"

#include <math.h>
#include <string.h>

typedef enum cliff_kind { WALL, FLAT, SAND_WALL, RAMP, DROWNED } cliff_kind;

static void cliff_column(void *user, int64_t gx, int64_t gz, terrain_stacks_builder *b) {
    (void)gz;
    const cliff_kind *kind = user;
    double floor_top = 10.0, extra = 0.0;
    terrain_material extra_material = TERRAIN_BEDROCK;
    switch (*kind) {
    case WALL: case DROWNED: extra = gx >= 20 ? 20.0 : 0.0; break;
    case FLAT: break;
    case SAND_WALL: extra = gx >= 20 ? 20.0 : 0.0, extra_material = TERRAIN_SAND; break;
    case RAMP: extra = gx >= 20 ? fmin(1.2 * (double)(gx - 19), 20.0) : 0.0; break;
    }
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(floor_top - TERRAIN_FLOOR_Y));
    if (extra > 0.0) terrain_stacks_builder_push(b, extra_material, (float)extra);
    if (*kind == DROWNED && gx < 20) terrain_stacks_builder_push(b, TERRAIN_WATER, 5.0f);
}

static terrain_stacks *cliff_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, cliff_column, user);
}

static terrain_world *cliff_world_create(cliff_kind *kind) {
    return terrain_world_create(&(terrain_world_desc){ .generate = cliff_generate, .generate_user = kind });
}

Test(game_walk_cliff, a_wall_is_seen_from_where_its_top_leaves_sky_above_it) {
    cliff_kind kind = WALL;
    terrain_world *world = cliff_world_create(&kind);
    game_cliff_view v;
    cr_assert(game_find_cliff_view(world, 0.5, 0.5, 60.0, &v), "the wall 18.5 m away was not found");
    cr_expect_float_eq(v.face[0], 20.0, 1e-9, "face x %.3f", v.face[0]);
    cr_expect_float_eq(v.face[1], 16.0, 1e-4, "face y %.3f", v.face[1]);
    cr_expect_float_eq(v.face[2], 1.0, 1e-9, "face z %.3f", v.face[2]);
    cr_expect_float_eq(v.height, 20.0f, 1e-4, "height %.3f", v.height);
    cr_expect_float_eq(v.eye[0], -9.0, 1e-9, "eye x %.3f", v.eye[0]);
    cr_expect_float_eq(v.eye[1], 12.12, 1e-4, "eye y %.3f", v.eye[1]);
    cr_expect_float_eq(v.eye[2], 1.0, 1e-9, "eye z %.3f", v.eye[2]);
    cr_expect_float_eq(v.yaw, 270.0f, 1e-3, "yaw %.3f", v.yaw);
    cr_expect_float_eq(v.pitch, atan2(3.88, 29.0) * 180.0 / M_PI, 1e-3, "pitch %.3f", v.pitch);
    /* out of reach: every foot column is 18.5 m away at least */
    cr_expect_not(game_find_cliff_view(world, 0.5, 0.5, 15.0, &v));
    terrain_world_destroy(world);
}

Test(game_walk_cliff, no_wall_a_sand_wall_a_ramp_or_a_drowned_foot_is_no_cliff) {
    cliff_kind kinds[] = { FLAT, SAND_WALL, RAMP, DROWNED };
    for (int k = 0; k < 4; k++) {
        terrain_world *world = cliff_world_create(&kinds[k]);
        game_cliff_view v;
        cr_expect_not(game_find_cliff_view(world, 0.5, 0.5, 40.0, &v), "world %d: a cliff at (%.1f, %.1f)", k,
                      v.face[0], v.face[2]);
        terrain_world_destroy(world);
    }
}

Test(game_walk_cliff, a_cliff_line_becomes_a_flight_facing_the_wall) {
    cliff_kind kind = WALL;
    terrain_world *world = cliff_world_create(&kind);
    game_walk walk = walk_test_parsed("relative\n0 -4\ncliff 60 shot\n0 -10\n");
    cr_expect_eq(walk.points[1].cliff_radius, 60.0f);
    game_player pl;
    walk_test_place(&pl, 0.5, 10.0, 4.5);
    game_walk_found found = game_walk_resolve_stops(&walk, world, &pl);
    cr_expect(found.cliffs == 1 && found.rocks == 0 && found.shores == 0 && found.caves == 0);
    cr_assert_eq(walk.count, 3);
    const game_walk_point *cliff = &walk.points[1];
    cr_expect(cliff->fly && cliff->has_y && cliff->has_look && cliff->has_look_at && cliff->shot);
    cr_expect_eq(cliff->cliff_radius, 0.0f);
    game_cliff_view v;
    cr_assert(game_find_cliff_view(world, 0.5, 0.5, 60.0, &v));   /* searched from the waypoint before */
    cr_expect_float_eq(cliff->x, v.eye[0] - 0.5, 1e-9);
    cr_expect_float_eq(cliff->z, v.eye[2] - 4.5, 1e-9);
    for (int a = 0; a < 3; a++) cr_expect_eq(cliff->look_at[a], v.face[a]);
    game_walk_free(&walk);
    /* nothing within reach: dropped with a notice */
    walk = walk_test_parsed("relative\n0 -4\ncliff 10 shot\n");
    cr_expect_eq(game_walk_resolve_stops(&walk, world, &pl).cliffs, 0);
    cr_expect_eq(walk.count, 1);
    game_walk_free(&walk);
    static const struct { const char *input; core_error_code code; const char *message; } cases[] = {
        { "cliff\n", CORE_ERROR_FORMAT, "t.walk:1: cliff needs a radius (metres)" },
        { "cliff 2000\n", CORE_ERROR_RANGE, "t.walk:1: cliff: '2000' is out of range (1 ... 1000 m)" },
        { "cliff 10 walk\n", CORE_ERROR_FORMAT, "t.walk:1: cliff: unknown word 'walk' (only shot; the flight and the view are found)" },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        core_error error = { 0 };
        cr_expect_not(game_walk_parse_text(cases[i].input, strlen(cases[i].input), "t.walk", &walk, &error),
                      "case %zu was taken", i);
        /* The kind of failure, and where: the message starts with the file and line. */
        cr_expect_eq(error.code, cases[i].code, "case %zu: code %s (%s)", i, core_error_code_name(error.code),
                     error.message);
        size_t where = strcspn(cases[i].message, " ");
        cr_expect(strncmp(error.message, cases[i].message, where) == 0, "case %zu: '%s' is not at '%.*s'", i,
                  error.message, (int)where, cases[i].message);
    }
    terrain_world_destroy(world);
}
