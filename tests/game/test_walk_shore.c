/* Looks out over water from a shore (walk.h: game_find_shore_view, `shore R` lines,
 * game_walk_resolve_stops).
 *
 * The worlds are made by hand from bedrock columns and water layers. In the sea world, dry ground
 * at y = 11 covers x < 0 and the sea (a bed at 5, water to 10) covers x ≥ 0, across the whole
 * width. What the finder must give there follows from that geometry and walk.h's rules:
 *   - searching every 2 m from (−20.5, 0.5), the grid points on the row z = 0.5 are the nearest
 *     to the centre on each column; the dry point nearest the water is x = −0.5 (its neighbour at
 *     x = 1.5 is water), 20 m from the centre, and no shore lies nearer: the eye is (−0.5, 12.62,
 *     0.5);
 *   - every direction with a +x component sees water all the way out to 64 m (the 16 samples every
 *     4 m), so the most water is a tie broken towards the water beside the shore, +x: --look yaw
 *     270 (yaw 0 = +z, 90 = −x);
 *   - the eye is 2.62 m over the water: atan(2.62 / 25) = 6.0°, under the 8° floor, so pitch −8.
 * With no water, with only a pond of 4 × 4 m (less than 40 m of water along any view) or with a
 * shore 20 m above the water (over the 12 m limit), nothing is found. */
#include "../engine/test.h"
#include "walk_test.h"
#include "game/walk.h"

#include <math.h>
#include <string.h>

typedef enum shore_kind { SEA, DRY, POND, CLIFF } shore_kind;

static void shore_column(void *user, int64_t gx, int64_t gz, terrain_stacks_builder *b) {
    const shore_kind *kind = user;
    double bed = 11.0, surface = 0.0;
    switch (*kind) {
    case SEA: if (gx >= 0) bed = 5.0, surface = 10.0; break;
    case DRY: break;
    case POND: if (gx >= 0 && gx < 4 && gz >= 0 && gz < 4) bed = 8.0, surface = 10.0; break;
    case CLIFF: if (gx >= 0) bed = 5.0, surface = 10.0; else bed = 30.0; break;
    }
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(bed - TERRAIN_FLOOR_Y));
    if (surface > bed) terrain_stacks_builder_push(b, TERRAIN_WATER, (float)(surface - bed));
}

static terrain_stacks *shore_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, shore_column, user);
}

static terrain_world *shore_world_create(shore_kind *kind) {
    return terrain_world_create(&(terrain_world_desc){ .generate = shore_generate, .generate_user = kind });
}

Test(game_walk_shore, the_nearest_shore_looks_out_over_the_sea) {
    shore_kind kind = SEA;
    terrain_world *world = shore_world_create(&kind);
    game_shore_view v;
    cr_assert(game_find_shore_view(world, -20.5, 0.5, 60.0, &v), "the sea 20 m away was not found");
    cr_expect_float_eq(v.eye[0], -0.5, 1e-9, "eye x %.2f", v.eye[0]);
    cr_expect_float_eq(v.eye[2], 0.5, 1e-9, "eye z %.2f", v.eye[2]);
    cr_expect_float_eq(v.eye[1], 11.0 + 1.62, 1e-4, "eye height %.3f", v.eye[1]);
    cr_expect_not(terrain_world_water_at(world, v.eye[0], v.eye[2], NULL, NULL), "the eye stands over water");
    cr_expect(terrain_world_water_at(world, v.water[0], v.water[2], NULL, NULL), "no water beside the shore");
    cr_expect_float_eq(v.water[1], 10.0, 1e-6);
    cr_expect_lt(fabs(remainder(v.yaw - 270.0, 360.0)), 1e-3, "yaw %.2f, the sea lies along +x (270)", v.yaw);
    cr_expect_float_eq(v.pitch, -8.0, 1e-4, "pitch %.3f", v.pitch);
    cr_expect_float_eq(v.open, (float)GAME_SHORE_VIEW_DISTANCE, 1e-6, "open water %.0f m", v.open);
    /* from farther off, still the same stretch of shore, the nearest point of it */
    cr_assert(game_find_shore_view(world, -40.5, 10.5, 100.0, &v));
    cr_expect_float_eq(v.eye[0], -0.5, 1e-9);
    cr_expect_float_eq(v.eye[2], 10.5, 1e-9);
    /* out of reach: the sea is 20 m away, the search 15 m */
    cr_expect_not(game_find_shore_view(world, -20.5, 0.5, 15.0, &v));
    terrain_world_destroy(world);
}

Test(game_walk_shore, no_water_a_pond_or_a_cliff_is_no_shore_view) {
    game_shore_view v;
    shore_kind kinds[] = { DRY, POND, CLIFF };
    for (int k = 0; k < 3; k++) {
        terrain_world *world = shore_world_create(&kinds[k]);
        cr_expect_not(game_find_shore_view(world, -10.5, 0.5, 40.0, &v), "world %d: a shore at (%.1f, %.1f)", k,
                      v.eye[0], v.eye[2]);
        terrain_world_destroy(world);
    }
}

Test(game_walk_shore, a_shore_line_becomes_a_flight_to_the_view_and_a_picture_over_the_water) {
    shore_kind kind = SEA;
    terrain_world *world = shore_world_create(&kind);
    game_walk walk = walk_test_parsed("relative\n0 -4\nshore 60 shot\n0 -10\n");
    cr_expect_eq(walk.points[1].shore_radius, 60.0f);
    game_player pl;
    walk_test_place(&pl, -20.5, 11.0, 4.5);
    game_walk_found found = game_walk_resolve_stops(&walk, world, &pl);
    cr_expect(found.shores == 1 && found.caves == 0);
    cr_assert_eq(walk.count, 3);
    const game_walk_point *shore = &walk.points[1];
    cr_expect(shore->fly && shore->has_y && shore->has_look && shore->shot && shore->shore_radius == 0.0f);
    game_shore_view v;
    cr_assert(game_find_shore_view(world, -20.5, 0.5, 60.0, &v));   /* searched from the waypoint before */
    cr_expect_float_eq(shore->x, v.eye[0] + 20.5, 1e-9);
    cr_expect_float_eq(shore->z, v.eye[2] - 4.5, 1e-9);
    cr_expect_float_eq(shore->y, v.eye[1] - pl.params.eye_height - 11.0, 1e-4, "feet %.3f", shore->y);
    cr_expect(shore->look_yaw == v.yaw && shore->look_pitch == v.pitch);
    game_walker w;
    game_walker_start(&w, &walk, &pl);
    float dt = 1.0f / 60.0f;
    int frame = 0;
    for (; frame < 3000 && !w.shot_due && !w.done; frame++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        game_player_update(&pl, world, &a, dt);
    }
    cr_assert(w.shot_due, "no picture after %d frames (%s)", frame, w.stuck ? "stuck" : "walking");
    cr_expect_eq(w.index, 2, "held at the shore's waypoint");
    double eye[3];
    game_player_eye(&pl, eye);
    cr_expect_leq(hypot(hypot(eye[0] - v.eye[0], eye[2] - v.eye[2]), eye[1] - v.eye[1]), GAME_WALK_DEFAULT_RADIUS + 0.5,
                  "eye (%.1f, %.1f, %.1f), view (%.1f, %.1f, %.1f)", eye[0], eye[1], eye[2], v.eye[0], v.eye[1], v.eye[2]);
    game_walk_free(&walk);
    /* nothing to find: dropped; never resolved: passed over without a picture */
    walk = walk_test_parsed("relative\n0 -4\nshore 10 shot\n0 -8\n");
    walk_test_place(&pl, -20.5, 11.0, 4.5);
    cr_expect_eq(game_walk_resolve_stops(&walk, world, &pl).shores, 0);
    cr_expect_eq(walk.count, 2);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walk_shore, shore_lines_parse_and_their_errors_name_the_problem) {
    game_walk walk = walk_test_parsed("shore 40\nshore 12.5 shot\ncave 30\n");
    cr_expect(walk.points[0].shore_radius == 40.0f && !walk.points[0].shot && walk.points[0].cave_radius == 0.0f);
    cr_expect(walk.points[1].shore_radius == 12.5f && walk.points[1].shot);
    cr_expect(walk.points[2].cave_radius == 30.0f && walk.points[2].shore_radius == 0.0f);
    game_walk_free(&walk);
    static const struct { const char *input; core_error_code code; const char *message; } cases[] = {
        { "shore\n", CORE_ERROR_FORMAT, "t.walk:1: shore needs a radius (metres)" },
        { "shore far\n", CORE_ERROR_FORMAT, "t.walk:1: shore: 'far' is not a number" },
        { "shore 1001\n", CORE_ERROR_RANGE, "t.walk:1: shore: '1001' is out of range (1 ... 1000 m)" },
        { "shore 10 walk\n", CORE_ERROR_FORMAT, "t.walk:1: shore: unknown word 'walk' (only shot; the flight and the view are found)" },
        { "shore 10 shot shot\n", CORE_ERROR_FORMAT, "t.walk:1: 'shot' given twice" },
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
