/* Looks at a pile of rocks (walk.h: game_find_rocks_view, `rocks R` lines, game_walk_resolve_stops,
 * the tour's rocks stop).
 *
 * The worlds are made by hand: a flat bedrock floor at y = 10 and, in the cone world, a rock cone
 * on it centred on column (20, 20) (its centre (20.5, 20.5)): a column whose centre lies r metres
 * from the cone's has a rock layer 4 − 0.8·r thick (none from r = 5 on). What the finder must give
 * follows from that geometry and walk.h's rules:
 *   - searching from the cone's centre, the centre column is rocky (4 m) and so are all 25 of the
 *     5 × 5 around it (r ≤ 2.83, at least 1.74 m): the pile is there, its centre the centroid of
 *     those 25 columns, (20.5, 20.5), at their mean top 14 − 0.8·(mean r) with mean r = (4·1 +
 *     4·√2 + 4·2 + 8·√5 + 4·√8) / 25, and its top 14;
 *   - the most lit view direction of the 8 is 45° ((0.707, 0.707): dot 0.63 with (0.55, 0.35)), the
 *     first eye 8 m back along it and 3.5 m over the top, (20.5 − 5.657, 17.5, 20.5 − 5.657): over
 *     the floor, the line of sight over the cone's flank (at 6 m along it the line is at 13.75, the
 *     flank under it at most 14 − 0.8·1.3), and the floor behind it 7.5 m under the eye, which
 *     48 m out is 8.9° down, under the picture's top edge (32° − 30° down) less 2°: open; --look
 *     yaw 315, pitch −atan(5 / 8);
 *   - with a 30 m wall over x < 16, every eye on the 45° and 0° lines stands in the wall; the next
 *     lit direction, 90° (+z, dot 0.35), has its first eye at (20.5, 17.5, 12.5): yaw 0. The wall
 *     rises into the picture's top on the view's two rays to its −x side, but not on the other
 *     three: open.
 * With no rocks, with a rock sheet 0.5 m thick everywhere, with a single rocky column or with the
 * cone under water, nothing is found. */
#include "../engine/test.h"
#include "walk_test.h"
#include "game/walk.h"

#include <math.h>
#include <string.h>

typedef enum rocks_kind { CONE, CONE_WALL, FLAT, THIN, ONE_COLUMN, DROWNED } rocks_kind;

#define CONE_X 20.5
#define CONE_Z 20.5

static void rocks_column(void *user, int64_t gx, int64_t gz, terrain_stacks_builder *b) {
    const rocks_kind *kind = user;
    double r = hypot(gx + 0.5 - CONE_X, gz + 0.5 - CONE_Z), rock = 0.0, bed = 10.0;
    switch (*kind) {
    case CONE: case DROWNED: rock = fmax(4.0 - 0.8 * r, 0.0); break;
    case CONE_WALL: rock = fmax(4.0 - 0.8 * r, 0.0); if (gx < 16) bed = 40.0, rock = 0.0; break;
    case FLAT: break;
    case THIN: rock = 0.5; break;
    case ONE_COLUMN: rock = gx == 20 && gz == 20 ? 3.0 : 0.0; break;
    }
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(bed - TERRAIN_FLOOR_Y));
    if (rock > 0.0) terrain_stacks_builder_push(b, TERRAIN_ROCKS, (float)rock);
    if (*kind == DROWNED) terrain_stacks_builder_push(b, TERRAIN_WATER, (float)(20.0 - bed - rock));
}

static terrain_stacks *rocks_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, rocks_column, user);
}

static terrain_world *rocks_world_create(rocks_kind *kind) {
    return terrain_world_create(&(terrain_world_desc){ .generate = rocks_generate, .generate_user = kind });
}

/* The pile's mean top, from the cone's formula (the layer thicknesses are multiples of 1/32 m). */
static double cone_mean_top(void) {
    double sum = 0.0;
    for (int k = -2; k <= 2; k++)
        for (int i = -2; i <= 2; i++) sum += 10.0 + round((4.0 - 0.8 * hypot(i, k)) * 32.0) / 32.0;
    return sum / 25.0;
}

/* What every view must be, whatever the world: the eye in the air over its ground, the pile in the
 * middle of the view, the view from the lit side, looking down. */
static void expect_a_view_of_the_pile(terrain_world *world, const game_rocks_view *v) {
    cr_expect_gt(v->eye[1] - 1.62, (double)terrain_world_top(world, v->eye[0], v->eye[2]) + 0.4,
                 "the feet under the eye (%.1f, %.1f, %.1f) are in the ground", v->eye[0], v->eye[1], v->eye[2]);
    double dx = v->pile[0] - v->eye[0], dy = v->pile[1] - v->eye[1], dz = v->pile[2] - v->eye[2];
    double horizontal = hypot(dx, dz);
    cr_expect(horizontal >= 6.0 - 1e-9 && horizontal <= 9.0 + 1e-9, "%.2f m from the pile", horizontal);
    cr_expect(v->eye[1] - v->top >= 3.0 - 1e-9 && v->eye[1] - v->top <= 5.0 + 1e-9, "%.2f m over the pile's top",
              v->eye[1] - v->top);
    double yaw = v->yaw * (M_PI / 180.0), pitch = v->pitch * (M_PI / 180.0);
    double look[3] = { -sin(yaw) * cos(pitch), sin(pitch), cos(yaw) * cos(pitch) };   /* --look's axes */
    double length = sqrt(dx * dx + dy * dy + dz * dz);
    double cosine = (look[0] * dx + look[1] * dy + look[2] * dz) / length;
    cr_expect_gt(cosine, cos(0.5 * M_PI / 180.0), "the view misses the pile by %.2f°", acos(fmin(cosine, 1.0)) * 180.0 / M_PI);
    cr_expect_gt(look[0] * 0.55 + look[2] * 0.35, 0.0, "the view (%.2f, %.2f) looks at the pile's dark side", look[0], look[2]);
    cr_expect_lt(v->pitch, 0.0f);
}

Test(game_walk_rocks, the_view_looks_down_at_the_cone_from_the_lit_side) {
    rocks_kind kind = CONE;
    terrain_world *world = rocks_world_create(&kind);
    game_rocks_view v;
    cr_assert(game_find_rocks_view(world, CONE_X, CONE_Z, 10.0, &v), "no pile at the cone");
    expect_a_view_of_the_pile(world, &v);
    double top = cone_mean_top(), back = 8.0 * M_SQRT1_2;
    cr_expect_float_eq(v.pile[0], CONE_X, 1e-9, "pile x %.3f", v.pile[0]);
    cr_expect_float_eq(v.pile[2], CONE_Z, 1e-9, "pile z %.3f", v.pile[2]);
    cr_expect_float_eq(v.pile[1], top, 1e-4, "pile y %.3f, the 5 x 5's mean top %.3f", v.pile[1], top);
    cr_expect_float_eq(v.top, 14.0, 1e-6, "top %.3f", v.top);
    cr_expect_float_eq(v.eye[0], CONE_X - back, 1e-6, "eye x %.3f", v.eye[0]);
    cr_expect_float_eq(v.eye[2], CONE_Z - back, 1e-6, "eye z %.3f", v.eye[2]);
    cr_expect_float_eq(v.eye[1], 17.5, 1e-6, "eye y %.3f", v.eye[1]);
    cr_expect_lt(fabs(remainder(v.yaw - 315.0, 360.0)), 1e-3, "yaw %.2f", v.yaw);
    cr_expect_float_eq(v.pitch, -atan2(17.5 - top, 8.0) * 180.0 / M_PI, 1e-3, "pitch %.3f", v.pitch);
    cr_expect(v.open, "nothing behind the cone");
    /* from 28 m off, the nearest pile is on the cone's near flank, and the view still sees the cone */
    cr_assert(game_find_rocks_view(world, 0.5, 0.5, 60.0, &v), "the cone 28 m away was not found");
    expect_a_view_of_the_pile(world, &v);
    cr_expect_lt(hypot(v.pile[0] - CONE_X, v.pile[2] - CONE_Z), 3.0, "pile (%.1f, %.1f)", v.pile[0], v.pile[2]);
    /* out of reach: no column 1 m deep in rock lies within 20 m (r ≤ 3.75: 24.5 m away at least) */
    cr_expect_not(game_find_rocks_view(world, 0.5, 0.5, 20.0, &v));
    terrain_world_destroy(world);
}

Test(game_walk_rocks, a_wall_on_the_lit_side_moves_the_eye_to_the_next_lit_direction) {
    rocks_kind kind = CONE_WALL;
    terrain_world *world = rocks_world_create(&kind);
    game_rocks_view v;
    cr_assert(game_find_rocks_view(world, CONE_X, CONE_Z, 10.0, &v), "no pile at the cone");
    expect_a_view_of_the_pile(world, &v);
    cr_expect_float_eq(v.eye[0], CONE_X, 1e-6, "eye x %.3f", v.eye[0]);
    cr_expect_float_eq(v.eye[2], CONE_Z - 8.0, 1e-6, "eye z %.3f", v.eye[2]);
    cr_expect_float_eq(v.eye[1], 17.5, 1e-6, "eye y %.3f", v.eye[1]);
    cr_expect_lt(fabs(remainder(v.yaw, 360.0)), 1e-3, "yaw %.2f, the view along +z (0)", v.yaw);
    cr_expect(v.open, "three of the five rays clear the wall");
    terrain_world_destroy(world);
}

Test(game_walk_rocks, no_rocks_a_thin_sheet_one_column_or_drowned_rocks_are_no_pile) {
    rocks_kind kinds[] = { FLAT, THIN, ONE_COLUMN, DROWNED };
    for (int k = 0; k < 4; k++) {
        terrain_world *world = rocks_world_create(&kinds[k]);
        game_rocks_view v;
        cr_expect_not(game_find_rocks_view(world, CONE_X, CONE_Z, 30.0, &v), "world %d: a pile at (%.1f, %.1f)", k,
                      v.pile[0], v.pile[2]);
        terrain_world_destroy(world);
    }
}

Test(game_walk_rocks, a_rocks_line_becomes_a_flight_to_the_view_and_a_picture_of_the_pile) {
    rocks_kind kind = CONE;
    terrain_world *world = rocks_world_create(&kind);
    game_walk walk = walk_test_parsed("relative\n0 -4\nrocks 60 shot\n0 -10\n");
    cr_expect_eq(walk.points[1].rocks_radius, 60.0f);
    game_player pl;
    walk_test_place(&pl, 0.5, 10.0, 4.5);
    game_walk_found found = game_walk_resolve_stops(&walk, world, &pl);
    cr_expect(found.rocks == 1 && found.shores == 0 && found.caves == 0);
    cr_assert_eq(walk.count, 3);
    const game_walk_point *rocks = &walk.points[1];
    cr_expect(rocks->fly && rocks->has_y && rocks->has_look && rocks->has_look_at && rocks->shot);
    cr_expect_eq(rocks->rocks_radius, 0.0f);
    game_rocks_view v;
    cr_assert(game_find_rocks_view(world, 0.5, 0.5, 60.0, &v));   /* searched from the waypoint before */
    cr_expect_float_eq(rocks->x, v.eye[0] - 0.5, 1e-9);
    cr_expect_float_eq(rocks->z, v.eye[2] - 4.5, 1e-9);
    cr_expect_float_eq(rocks->y, v.eye[1] - pl.params.eye_height - 10.0, 1e-4, "feet %.3f", rocks->y);
    cr_expect(rocks->look_yaw == v.yaw && rocks->look_pitch == v.pitch);
    for (int a = 0; a < 3; a++) cr_expect_eq(rocks->look_at[a], v.pile[a]);
    game_walker w;
    game_walker_start(&w, &walk, &pl);
    float dt = 1.0f / 60.0f;
    int frame = 0;
    for (; frame < 3000 && !w.shot_due && !w.done; frame++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        game_player_update(&pl, world, &a, dt);
    }
    cr_assert(w.shot_due, "no picture after %d frames (%s)", frame, w.stuck ? "stuck" : "flying");
    cr_expect_eq(w.index, 2, "held at the pile's waypoint");
    double eye[3];
    game_player_eye(&pl, eye);
    cr_expect_leq(hypot(hypot(eye[0] - v.eye[0], eye[2] - v.eye[2]), eye[1] - v.eye[1]), GAME_WALK_DEFAULT_RADIUS + 0.5,
                  "eye (%.1f, %.1f, %.1f), view (%.1f, %.1f, %.1f)", eye[0], eye[1], eye[2], v.eye[0], v.eye[1], v.eye[2]);
    game_walk_free(&walk);
    /* nothing to find: dropped with a notice */
    walk = walk_test_parsed("relative\n0 -4\nrocks 10 shot\n0 -8\n");
    walk_test_place(&pl, 0.5, 10.0, 4.5);
    cr_expect_eq(game_walk_resolve_stops(&walk, world, &pl).rocks, 0);
    cr_expect_eq(walk.count, 2);
    cr_expect_not(walk.points[0].has_look_at || walk.points[1].has_look_at);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walk_rocks, rocks_lines_parse_and_their_errors_name_the_problem) {
    game_walk walk = walk_test_parsed("rocks 40\nrocks 12.5 shot\nshore 30\n");
    cr_expect(walk.points[0].rocks_radius == 40.0f && !walk.points[0].shot && walk.points[0].shore_radius == 0.0f);
    cr_expect(walk.points[1].rocks_radius == 12.5f && walk.points[1].shot && walk.points[1].cave_radius == 0.0f);
    cr_expect(walk.points[2].shore_radius == 30.0f && walk.points[2].rocks_radius == 0.0f);
    cr_expect_not(walk.points[0].has_look_at || walk.points[1].has_look_at);
    game_walk_free(&walk);
    static const struct { const char *input; core_error_code code; const char *message; } cases[] = {
        { "rocks\n", CORE_ERROR_FORMAT, "t.walk:1: rocks needs a radius (metres)" },
        { "rocks many\n", CORE_ERROR_FORMAT, "t.walk:1: rocks: 'many' is not a number" },
        { "rocks 0.5\n", CORE_ERROR_RANGE, "t.walk:1: rocks: '0.5' is out of range (1 ... 1000 m)" },
        { "rocks 10 fly\n", CORE_ERROR_FORMAT, "t.walk:1: rocks: unknown word 'fly' (only shot; the flight and the view are found)" },
        { "rocks 10 shot shot\n", CORE_ERROR_FORMAT, "t.walk:1: 'shot' given twice" },
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

/* The tour's stops in order: the spawn and 50 m on, a cave, a shore, a pile of rocks, the view
 * from 120 m up; six pictures, which fill the contact sheet's 3 × 2. */
Test(game_walk_rocks, the_tour_parses_with_its_rocks_stop) {
    game_walk walk = walk_test_parsed(game_walk_tour);
    cr_assert_eq(walk.count, 6);
    int shots = 0;
    for (int i = 0; i < walk.count; i++) shots += walk.points[i].shot;
    cr_expect_eq(shots, 6);
    cr_expect_eq(walk.points[2].cave_radius, 150.0f);
    cr_expect_eq(walk.points[3].shore_radius, 150.0f);
    cr_expect_eq(walk.points[4].rocks_radius, 150.0f);
    cr_expect(walk.points[5].fly && walk.points[5].has_y && walk.points[5].y == 120.0);
    cr_expect_eq(walk.frame, GAME_WALK_AHEAD);
    game_walk_free(&walk);
}
