/* Looks into caves (walk.h: game_find_cave_view, game_walk_resolve_caves, `cave R` lines).
 *
 * The world is made by hand: flat bedrock ground at y = 10 m, and over it a tunnel through a block
 * of rock, columns x ∈ [−6, 6) × z ∈ [20, 36): ground to 10 m, air to 14 m, rock to 20 m. Each
 * open end of the tunnel is a mouth on level ground. What a good view of it must be follows from
 * that geometry, not from the finder's code:
 *   - the eye stands on open ground (1.62 m over y = 10), outside the block, and faces the
 *     point it looks at;
 *   - the point it looks at is inside the tunnel (under the roof, between 10 and 14 m), and the
 *     line of sight to it is air all the way;
 *   - the block's top (20 m high), even at its point nearest the eye, lies inside the picture, so
 *     sky shows over it: under 30° over the view's centre with a 60° field;
 *   - the deepest shelter is at least the tunnel's length: 16 m of roof from the far end's column
 *     to the open ground (more on a diagonal), less the 2 m search grid.
 * Without a roof (flat ground) nothing is found, and a tunnel whose floor lies under the sea is
 * water, not a cave. */
#include "../engine/test.h"
#include "walk_test.h"
#include "game/walk.h"

#include <math.h>
#include <string.h>

#define GROUND 10.0f
#define GAP_TOP 14.0f
#define ROOF_TOP 20.0f

typedef struct cave_world { bool tunnel; float sea_level; } cave_world;

static bool in_block(int64_t x, int64_t z) { return x >= -6 && x < 6 && z >= 20 && z < 36; }

static void cave_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const cave_world *cw = user;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, GROUND - TERRAIN_FLOOR_Y);
    if (cw->tunnel && in_block(x, z)) {
        terrain_stacks_builder_push(b, TERRAIN_AIR, GAP_TOP - GROUND);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, ROOF_TOP - GAP_TOP);
    }
}

static terrain_stacks *cave_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, cave_column, user);
}

static terrain_world *cave_world_create(cave_world *cw) {
    terrain_generation_desc generation = { .sea_level = cw->sea_level };
    return terrain_world_create(&(terrain_world_desc){ .generation = generation, .generate = cave_generate,
                                                       .generate_user = cw });
}

static const double PI = 3.14159265358979323846;

Test(game_walk_cave, a_tunnel_is_seen_from_open_ground_along_its_axis_with_sky_above_it) {
    cave_world cw = { .tunnel = true, .sea_level = 0.0f };
    terrain_world *world = cave_world_create(&cw);
    game_cave_view v;
    cr_assert(game_find_cave_view(world, 0.0, 0.0, 60.0, &v), "the tunnel 20 m away was not found");
    /* the eye: open ground, outside the block, facing the point it looks at */
    cr_expect(!in_block((int64_t)floor(v.eye[0]), (int64_t)floor(v.eye[2])), "eye at (%.1f, %.1f)", v.eye[0], v.eye[2]);
    cr_expect_float_eq(v.eye[1], GROUND + 1.62, 1e-3, "eye height %.3f", v.eye[1]);
    double dx = v.mouth[0] - v.eye[0], dz = v.mouth[2] - v.eye[2];
    double yaw = atan2(-dx, dz) * 180.0 / PI;             /* --look: (−sin, cos) is the view */
    cr_expect_lt(fabs(remainder(yaw - v.yaw, 360.0)), 1e-3, "yaw %.2f, the mouth is at %.2f", v.yaw, yaw);
    cr_expect_float_eq(v.pitch, atan2(v.mouth[1] - v.eye[1], hypot(dx, dz)) * 180.0 / PI, 1e-3);
    /* the point looked at: inside the tunnel, seen through air */
    cr_expect(in_block((int64_t)floor(v.mouth[0]), (int64_t)floor(v.mouth[2])), "mouth (%.1f, %.1f)", v.mouth[0],
              v.mouth[2]);
    cr_expect(v.mouth[1] > GROUND && v.mouth[1] < GAP_TOP, "mouth height %.2f", v.mouth[1]);
    for (int s = 0; s <= 100; s++) {
        double t = s / 100.0, p[3];
        for (int a = 0; a < 3; a++) p[a] = v.eye[a] + (v.mouth[a] - v.eye[a]) * t;
        cr_expect_lt(terrain_field_at(world, p[0], p[1], p[2], 0), 0.0f, "solid on the line of sight at %.2f", t);
    }
    /* the block's top (20 m) inside a 60° picture: its nearest point horizontally gives the
     * highest angle any of its top can reach */
    double nx = fmax(fmax(-6.0 - v.eye[0], v.eye[0] - 6.0), 0.0), nz = fmax(fmax(20.0 - v.eye[2], v.eye[2] - 36.0), 0.0);
    double over_centre = atan2(ROOF_TOP - v.eye[1], hypot(nx, nz)) - v.pitch * PI / 180.0;
    cr_expect_lt(over_centre, PI / 6.0, "the roof's edge %.1f° over the view's centre",
                 over_centre * 180.0 / PI);
    cr_expect_geq(v.depth, 16.0 - 2.0, "depth %.1f: the tunnel is 16 m long (2 m search grid)", v.depth);
    terrain_world_destroy(world);
}

Test(game_walk_cave, no_roof_no_cave_and_under_the_sea_is_water) {
    cave_world flat = { .tunnel = false, .sea_level = 0.0f };
    terrain_world *world = cave_world_create(&flat);
    game_cave_view v;
    cr_expect_not(game_find_cave_view(world, 0.0, 0.0, 60.0, &v));
    terrain_world_destroy(world);
    cave_world drowned = { .tunnel = true, .sea_level = 30.0f };
    world = cave_world_create(&drowned);
    cr_expect_not(game_find_cave_view(world, 0.0, 0.0, 60.0, &v), "a tunnel 16 m under the sea was taken");
    terrain_world_destroy(world);
}

Test(game_walk_cave, a_cave_line_becomes_a_flight_to_the_view_and_a_picture_facing_the_mouth) {
    cave_world cw = { .tunnel = true, .sea_level = 0.0f };
    terrain_world *world = cave_world_create(&cw);
    game_walk walk = walk_test_parsed("relative\n0 -4\ncave 60 shot\n0 -10\n");
    cr_expect_eq(walk.points[1].cave_radius, 60.0f);
    game_player pl;
    walk_test_place(&pl, 0.5, GROUND, -10.5);
    cr_assert_eq(game_walk_resolve_caves(&walk, world, &pl), 1);
    cr_assert_eq(walk.count, 3);
    const game_walk_point *cave = &walk.points[1];
    cr_expect(cave->fly && cave->has_y && cave->has_look && cave->shot && cave->cave_radius == 0.0f);
    game_cave_view v;
    cr_assert(game_find_cave_view(world, 0.5, -14.5, 60.0, &v));   /* searched from the waypoint before */
    cr_expect_float_eq(cave->x, v.eye[0] - 0.5, 1e-9);
    cr_expect_float_eq(cave->z, v.eye[2] + 10.5, 1e-9);
    cr_expect_float_eq(cave->y, v.eye[1] - pl.params.eye_height - GROUND, 1e-4, "feet %.3f", cave->y);
    cr_expect(cave->look_yaw == v.yaw && cave->look_pitch == v.pitch);
    /* The walker flies there and holds for the picture. */
    game_walker w;
    game_walker_start(&w, &walk, &pl);
    float dt = 1.0f / 60.0f;
    int frame = 0;
    for (; frame < 3000 && !w.shot_due && !w.done; frame++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        game_player_update(&pl, world, &a, dt);
    }
    cr_assert(w.shot_due, "no picture after %d frames (%s)", frame, w.stuck ? "stuck" : "walking");
    cr_expect_eq(w.index, 2, "held at the cave's waypoint");
    double eye[3];
    game_player_eye(&pl, eye);
    cr_expect_leq(hypot(hypot(eye[0] - v.eye[0], eye[2] - v.eye[2]), eye[1] - v.eye[1]), GAME_WALK_DEFAULT_RADIUS + 0.5,
                  "eye (%.1f, %.1f, %.1f), view (%.1f, %.1f, %.1f)", eye[0], eye[1], eye[2], v.eye[0], v.eye[1], v.eye[2]);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walk_cave, a_cave_line_with_nothing_to_find_is_dropped_and_an_unresolved_one_is_skipped) {
    cave_world flat = { .tunnel = false, .sea_level = 0.0f };
    terrain_world *world = cave_world_create(&flat);
    game_walk walk = walk_test_parsed("relative\n0 -4\ncave 30 shot\n0 -8\n");
    game_player pl;
    walk_test_place(&pl, 0.5, GROUND, 0.5);
    cr_expect_eq(game_walk_resolve_caves(&walk, world, &pl), 0);
    cr_expect_eq(walk.count, 2);
    cr_expect(walk.points[1].z == -8.0 && walk.points[0].z == -4.0);
    game_walk_free(&walk);
    /* Never resolved: the walker passes over it, and takes no picture. */
    walk = walk_test_parsed("relative\ncave 30 shot\n0 -8\n");
    game_walker w;
    walk_test_place(&pl, 0.5, GROUND, 0.5);
    game_walker_start(&w, &walk, &pl);
    float dt = 1.0f / 60.0f;
    for (int frame = 0; frame < 2000 && !w.done; frame++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        cr_assert(!w.shot_due, "a picture at an unresolved cave");
        game_player_update(&pl, world, &a, dt);
    }
    cr_expect(w.done && !w.stuck && w.shots == 0);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walk_cave, look_and_cave_words_parse_and_their_errors_name_the_problem) {
    game_walk walk = walk_test_parsed("1 2 shot look=-90,12.5\ncave 40\n");
    cr_expect(walk.points[0].has_look && walk.points[0].look_yaw == 270.0f && walk.points[0].look_pitch == 12.5f);
    cr_expect(walk.points[1].cave_radius == 40.0f && !walk.points[1].shot);
    game_walk_free(&walk);
    static const struct { const char *input; core_error_code code; const char *message; } cases[] = {
        { "1 2 look=10,0\n", CORE_ERROR_FORMAT, "t.walk:1: look= needs shot (it is the picture's direction)" },
        { "1 2 shot look=10\n", CORE_ERROR_FORMAT, "t.walk:1: look=: '10' is not YAW,PITCH (degrees)" },
        { "1 2 shot look=a,0\n", CORE_ERROR_FORMAT, "t.walk:1: look=: yaw 'a' is not a number" },
        { "1 2 shot look=0,\n", CORE_ERROR_FORMAT, "t.walk:1: look=: pitch '' is not a number" },
        { "1 2 shot look=0,90\n", CORE_ERROR_RANGE, "t.walk:1: look=: pitch '90' is out of range (-89 ... 89)" },
        { "1 2 shot look=0,0 look=0,0\n", CORE_ERROR_FORMAT, "t.walk:1: 'look=' given twice" },
        { "cave\n", CORE_ERROR_FORMAT, "t.walk:1: cave needs a radius (metres)" },
        { "cave far\n", CORE_ERROR_FORMAT, "t.walk:1: cave: 'far' is not a number" },
        { "cave 0.5\n", CORE_ERROR_RANGE, "t.walk:1: cave: '0.5' is out of range (1 ... 1000 m)" },
        { "cave 10 fly\n", CORE_ERROR_FORMAT, "t.walk:1: cave: unknown word 'fly' (only shot; the flight and the view are found)" },
        { "cave 10 shot shot\n", CORE_ERROR_FORMAT, "t.walk:1: 'shot' given twice" },
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
}
