/* The player controller (game/player.h) in hand-built worlds whose field is known by hand.
 *
 * With σ = 1 column the field is f = 2·V/(8σ³) − 1 (000 §3.3). Over flat ground of height g
 * (whole columns of bedrock up to g) the kernel cube [y−1, y+1] holds 4·clamp(g − y + 1, 0, 2) of
 * solid, so f(y) = clamp(g − y, −1, 1): the surface is at y = g and f is the signed vertical
 * distance within a metre of it. Likewise a wall of columns x ≥ w rising far above the ground has
 * f = clamp(x − w, −1, 1) more than a metre above the ground, and a gap between a floor at g and
 * a ceiling at g + H (H ≥ 1) has its surfaces exactly at g and g + H. A step of height D between
 * columns x < s and x ≥ s is smoothed over x ∈ [s − 1, s + 1]: where a fraction t of the kernel
 * lies over the high side, f(y) = (1 − t)·clamp(g − y) + t·clamp(g + D − y); for D = 0.3 that is a
 * ramp of slope 0.15 (walked up like any slope), for D = 2 its steepest part is steeper than
 * 63° from y ≈ g + 0.54 to g + 1.46 (slope above the 50° limit: y = g + t/(1 − t) below, with
 * dy/dx = 1/(2(1 − t)²) > tan 50° once t > 0.352), so it cannot be walked but a 1.1 m jump from its
 * foot clears the steep band. */
#include "../engine/test.h"
#include "game/player.h"

#include <math.h>
#include <string.h>

/* ---- worlds -------------------------------------------------------------------------------- */

typedef enum world_kind { FLAT, WALL, STEP, TUNNEL } world_kind;

typedef struct hand_world {
    world_kind kind;
    int64_t shift_chunks;              /* the whole world moved by this many chunks in x and z */
    double ground;                     /* floor height (integer metres) */
    double edge;                       /* x where the wall / step / tunnel roof begins */
    double rise;                       /* step height, or the tunnel's clear height */
} hand_world;

static void hand_column(const hand_world *w, int64_t gx, terrain_stacks_builder *b) {
    double x = (double)gx, floor_height = w->ground - TERRAIN_FLOOR_Y;
    bool beyond = x >= w->edge;
    switch (w->kind) {
    case FLAT: terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)floor_height); break;
    case WALL: terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(floor_height + (beyond ? 20.0 : 0.0))); break;
    case STEP: terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(floor_height + (beyond ? w->rise : 0.0))); break;
    case TUNNEL:
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)floor_height);
        if (beyond) {
            terrain_stacks_builder_push(b, TERRAIN_AIR, (float)w->rise);
            terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 5.0f);
        }
        break;
    }
}

/* Global column x of the shifted world is column x − shift of the hand-made one. */
static void hand_shifted_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const hand_world *hand = user;
    (void)z;
    hand_column(hand, x - hand->shift_chunks * TERRAIN_CHUNK_COLUMNS, b);
}

static terrain_stacks *hand_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, hand_shifted_column, user);
}

static terrain_world *hand_world_create(hand_world *hand) {
    return terrain_world_create(&(terrain_world_desc){ .generate = hand_generate, .generate_user = hand });
}

#define walk(x, y) ((input_actions){ .move_x = (x), .move_y = (y) })

#define BIT(a) INPUT_ACTION_BIT(INPUT_ACTION_##a)
#define YAW_PLUS_X 1.57079632679f      /* yaw 0 looks along −z; a quarter turn right looks along +x */

/* Stands the player at (x, y, z), on the ground, looking along +x. */
static void place(game_player *pl, double x, double y, double z) {
    game_player_init(pl, &(game_player_desc){ 0 });
    pl->position[0] = x, pl->position[1] = y, pl->position[2] = z;
    pl->yaw = YAW_PLUS_X;
    pl->on_ground = true;
}

/* ---- flat ground ------------------------------------------------------------------------------ */

Test(game_player, spawns_standing_on_flat_ground) {
    hand_world hand = { .kind = FLAT, .ground = 10 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    game_player_init(&pl, NULL);
    game_player_spawn(&pl, world, 5.3, -7.8);
    cr_expect(pl.on_ground);
    cr_expect_float_eq(pl.position[1], 10.0, 1e-3, "feet at %f, the surface is at 10", pl.position[1]);
    cr_expect_float_eq(pl.position[0], 5.3, 1e-6);
    cr_expect_float_eq(pl.position[2], -7.8, 1e-6);
    double eye[3];
    game_player_eye(&pl, eye);
    cr_expect_float_eq(eye[1], 10.0 + 1.62, 1e-3);
    terrain_world_destroy(world);
}

static void fall_and_rest(float dt) {
    hand_world hand = { .kind = FLAT, .ground = 10 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 3.25, 20.0, 4.5);
    pl.on_ground = false;
    input_actions idle = { 0 };
    int frames = (int)(2.0f / dt);
    double lowest = 1e9;
    for (int i = 0; i < frames; i++) {
        game_player_update(&pl, world, &idle, dt);
        lowest = fmin(lowest, pl.position[1]);
    }
    cr_expect(pl.on_ground, "dt %g: not landed", dt);
    cr_expect_geq(lowest, 10.0 - 1e-3, "dt %g: feet went down to %f", dt, lowest);
    cr_expect_float_eq(pl.position[1], 10.0, 1e-3, "dt %g: rests at %f", dt, pl.position[1]);
    double rest[3];
    memcpy(rest, pl.position, sizeof rest);
    for (int i = 0; i < 100; i++) {
        game_player_update(&pl, world, &idle, dt);
        cr_assert(memcmp(rest, pl.position, sizeof rest) == 0, "dt %g: moved at rest (frame %d)", dt, i);
    }
    terrain_world_destroy(world);
}

Test(game_player, falls_10m_and_lands_without_tunnelling_at_60hz) { fall_and_rest(1.0f / 60.0f); }
Test(game_player, falls_10m_and_lands_without_tunnelling_at_20hz) { fall_and_rest(1.0f / 20.0f); }
Test(game_player, falls_10m_and_lands_without_tunnelling_at_240hz) { fall_and_rest(1.0f / 240.0f); }

Test(game_player, falls_at_terminal_speed_onto_ground_without_tunnelling) {
    hand_world hand = { .kind = FLAT, .ground = 10 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 0.5, 500.0, 0.5);
    pl.on_ground = false;
    input_actions idle = { 0 };
    for (int i = 0; i < 300; i++) {
        game_player_update(&pl, world, &idle, 0.1f);          /* the longest frame: 5 m a frame */
        cr_assert_geq(pl.position[1], 10.0 - 1e-3);
    }
    cr_expect(pl.on_ground);
    terrain_world_destroy(world);
}

/* ---- walls ------------------------------------------------------------------------------------ */

Test(game_player, flying_into_a_wall_stops_at_radius_from_it) {
    hand_world hand = { .kind = WALL, .ground = 0, .edge = 10 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 5.5, 5.0, 0.5);                  /* more than a metre above the ground: f = x − 10 */
    pl.flying = true, pl.on_ground = false;
    for (int i = 0; i < 120; i++) game_player_update(&pl, world, &(input_actions){ .move_y = 1 }, 1.0f / 60.0f);
    cr_expect_float_eq(pl.position[0], 10.0 - 0.35, 0.01, "stopped at x = %f", pl.position[0]);
    cr_expect_float_eq(pl.position[1], 5.0, 1e-3);
    terrain_world_destroy(world);
}

Test(game_player, walking_into_a_wall_stops_at_radius_or_at_its_fillet) {
    hand_world hand = { .kind = WALL, .ground = 0, .edge = 10 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 5.5, 0.0, 0.5);
    for (int i = 0; i < 120; i++) {
        game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
        cr_assert_leq(pl.position[0], 10.0 - 0.35 + 0.01, "closer than r to the wall: x = %f", pl.position[0]);
    }
    /* The concave corner is rounded over σ = 1 m: u metres above the ground the fillet's surface is
     * at x = w − 1 + 2u/(1 + u) (f = (1 − t)(−u) + t with t the kernel's fraction over the wall), so
     * its slope reaches the 50° limit at u = √(2·tan 50°) − 1 ≈ 0.54, x ≈ w − 0.30. The bottom
     * sphere walks up the fillet to there and rests against it: centre r along the 50° normal,
     * x ≈ w − 0.30 − 0.35·sin 50° ≈ w − 0.56, feet ≈ 0.54 + 0.35·cos 50° − 0.35 ≈ 0.42 (the
     * distance estimate −f/|∇f| is not exact on the fillet, hence the tolerances). */
    cr_expect_float_eq(pl.position[0], 10.0 - 0.56, 0.1, "stopped at x = %f", pl.position[0]);
    cr_expect_float_eq(pl.position[1], 0.42, 0.1, "lifted to %f on the fillet", pl.position[1]);
    double x = pl.position[0];
    for (int i = 0; i < 60; i++) game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
    cr_expect_float_eq(pl.position[0], x, 1e-3, "kept pushing through: %f → %f", x, pl.position[0]);
    terrain_world_destroy(world);
}

Test(game_player, sliding_along_a_wall_keeps_the_tangential_speed) {
    hand_world hand = { .kind = WALL, .ground = 0, .edge = 10 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 9.0, 0.0, 0.5);
    pl.yaw = YAW_PLUS_X - 0.78539816f;          /* 45° between +x (into the wall) and −z */
    for (int i = 0; i < 60; i++) game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
    double z0 = pl.position[2];
    for (int i = 0; i < 60; i++) game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
    double tangential = z0 - pl.position[2];    /* metres along −z in one second */
    cr_expect_float_eq(tangential, 4.5 * 0.70710678, 0.02, "slid %f m/s", tangential);
    cr_expect_leq(pl.position[0], 10.0 - 0.35 + 0.01);
    terrain_world_destroy(world);
}

/* ---- steps ------------------------------------------------------------------------------------ */

/* 0.3125 m: layer thicknesses are multiples of 1/32 m, so "0.3 m" would be built as this anyway */
Test(game_player, climbs_a_0_3m_step) {
    hand_world hand = { .kind = STEP, .ground = 0, .edge = 10, .rise = 0.3125 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 5.5, 0.0, 0.5);
    for (int i = 0; i < 120; i++) game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
    cr_expect_gt(pl.position[0], 5.5 + 0.95 * 9.0, "only got to x = %f", pl.position[0]);
    cr_expect_float_eq(pl.position[1], 0.3125, 1e-3, "feet at %f on top of the step", pl.position[1]);
    cr_expect(pl.on_ground);
    terrain_world_destroy(world);
}

Test(game_player, a_2m_step_is_not_walked_up_but_a_jump_clears_it) {
    hand_world hand = { .kind = STEP, .ground = 0, .edge = 10, .rise = 2.0 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 5.5, 0.0, 0.5);
    for (int i = 0; i < 180; i++) {
        game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
        cr_assert_lt(pl.position[1], 0.6, "walked up to %f", pl.position[1]);
    }
    cr_expect_lt(pl.position[0], 10.0);
    input_actions jump = { .move_y = 1, .down = BIT(JUMP), .pressed = BIT(JUMP) };
    game_player_update(&pl, world, &jump, 1.0f / 60.0f);
    for (int i = 0; i < 120; i++) game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
    cr_expect_float_eq(pl.position[1], 2.0, 1e-3, "feet at %f after the jump", pl.position[1]);
    cr_expect_gt(pl.position[0], 11.0);
    terrain_world_destroy(world);
}

/* ---- tunnels and arches ----------------------------------------------------------------------- */

Test(game_player, walks_in_under_an_arch) {
    hand_world hand = { .kind = TUNNEL, .ground = 0, .edge = 10, .rise = 3.0 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 6.5, 0.0, 0.5);
    for (int i = 0; i < 120; i++) {
        game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
        cr_assert_float_eq(pl.position[1], 0.0, 1e-3);
    }
    cr_expect_gt(pl.position[0], 14.0);
    terrain_world_destroy(world);
}

Test(game_player, a_jump_under_a_low_ceiling_does_not_pass_through_it) {
    hand_world hand = { .kind = TUNNEL, .ground = 0, .edge = 0, .rise = 2.5 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 5.5, 0.0, 0.5);
    input_actions jump = { .down = BIT(JUMP), .pressed = BIT(JUMP) };
    game_player_update(&pl, world, &jump, 1.0f / 60.0f);
    double highest = 0.0;
    for (int i = 0; i < 120; i++) {
        game_player_update(&pl, world, &(input_actions){ 0 }, 1.0f / 60.0f);
        highest = fmax(highest, pl.position[1]);
        cr_assert_leq(pl.position[1] + 1.8, 2.5 + 0.01, "head at %f", pl.position[1] + 1.8);
    }
    cr_expect_gt(highest, 0.6, "did not jump (%f)", highest);
    cr_expect_float_eq(pl.position[1], 0.0, 1e-3);
    cr_expect(pl.on_ground);
    terrain_world_destroy(world);
}

/* The roof starts at x = 10; its underside is at 1.5 m for x ≥ 11 and curves up to 2.5 m at x = 10
 * (y = 0.5 + 1/t with t = (x − 9)/2 the kernel's fraction under the roof), so a standing player
 * gets a little way in (to where the underside is 1.8 m + r: x ≈ 10.3 … 10.6) but not under the
 * flat 1.5 m part. */
Test(game_player, crouches_through_a_1_5m_tunnel_and_stands_only_outside) {
    hand_world hand = { .kind = TUNNEL, .ground = 0, .edge = 10, .rise = 1.5 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 6.5, 0.0, 0.5);
    for (int i = 0; i < 120; i++) game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
    cr_expect_lt(pl.position[0], 10.7, "walked in standing: x = %f", pl.position[0]);
    /* pressed between the curved underside and the floor: held within the contact skin */
    cr_expect_float_eq(pl.position[1], 0.0, 5e-3, "feet at %f", pl.position[1]);
    input_actions crouch = { .move_y = 1, .down = BIT(CROUCH), .pressed = BIT(CROUCH) };
    for (int i = 0; i < 180; i++) game_player_update(&pl, world, &crouch, 1.0f / 60.0f);
    cr_expect(pl.crouching);
    cr_expect_gt(pl.position[0], 14.0, "crouched to x = %f", pl.position[0]);
    cr_expect_float_eq(pl.position[1], 0.0, 1e-3);
    for (int i = 0; i < 30; i++) game_player_update(&pl, world, &(input_actions){ 0 }, 1.0f / 60.0f);
    cr_expect(pl.crouching, "stood up into the ceiling");
    cr_expect_float_eq(game_player_height(&pl), 1.2f, 1e-6);
    for (int i = 0; i < 600 && pl.crouching; i++) {          /* back out, crouch released */
        game_player_update(&pl, world, &walk(0, -1), 1.0f / 60.0f);
        cr_assert(pl.crouching || pl.position[0] < 10.7, "stood at x = %f", pl.position[0]);
    }
    cr_expect_not(pl.crouching, "never stood up");
    /* where it stood, the standing capsule's top is in the air */
    cr_expect_lt(terrain_field_at(world, pl.position[0], pl.position[1] + 1.8, pl.position[2], 1.0f), 0.0f);
    terrain_world_destroy(world);
}

/* ---- fly mode --------------------------------------------------------------------------------- */

Test(game_player, fly_toggles_and_moves_along_the_view) {
    hand_world hand = { .kind = FLAT, .ground = 0 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 0.5, 0.0, 0.5);
    pl.yaw = 0.0f;
    input_actions toggle = { .look_x = 0.3f, .look_y = 0.4f, .pressed = BIT(TOGGLE_FLY) };
    game_player_update(&pl, world, &toggle, 1.0f / 60.0f);
    cr_assert(pl.flying);
    double start[3];
    memcpy(start, pl.position, sizeof start);
    for (int i = 0; i < 60; i++) game_player_update(&pl, world, &(input_actions){ .move_y = 1 }, 1.0f / 60.0f);
    /* Easing in at fly_accel 120 m/s²: 2, 4, … 12 m/s over the first six frames, then 12: in one
     * second (2 + 4 + 6 + 8 + 10 + 12 + 54·12) / 60 = 11.5 m along the view. */
    double expected[3] = { 11.5 * sin(0.3) * cos(0.4), 11.5 * sin(0.4), -11.5 * cos(0.3) * cos(0.4) };
    for (int a = 0; a < 3; a++)
        cr_expect_float_eq(pl.position[a] - start[a], expected[a], 1e-3, "axis %d: %f", a, pl.position[a] - start[a]);
    game_player_update(&pl, world, &(input_actions){ .pressed = BIT(TOGGLE_FLY) }, 1.0f / 60.0f);
    cr_assert_not(pl.flying);
    for (int i = 0; i < 120; i++) game_player_update(&pl, world, &(input_actions){ 0 }, 1.0f / 60.0f);
    cr_expect(pl.on_ground);
    cr_expect_float_eq(pl.position[1], 0.0, 1e-3);
    terrain_world_destroy(world);
}

/* ---- easing in and out ------------------------------------------------------------------------ */

/* Sprinting from rest on flat ground at 60 Hz: ground_accel 60 m/s² adds 1 m/s a frame, so
 * 1, 2, … 8 m/s over eight frames, then 8: in a second (1 + … + 8 + 52·8) / 60 = 452/60 m. Let go,
 * it slows by 1 m/s a frame: 7, 6, … 0, another 28/60 m. In the air the input steers at
 * air_accel 12 m/s²: pushing back for 0.2 s takes 2.4 m/s off the 8. */
Test(game_player, starts_and_stops_ease_and_the_air_steers_a_little) {
    hand_world hand = { .kind = FLAT, .ground = 0 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 0.5, 0.0, 0.5);
    input_actions run = { .move_y = 1, .down = BIT(SPRINT) };
    for (int i = 0; i < 60; i++) game_player_update(&pl, world, &run, 1.0f / 60.0f);
    cr_expect_float_eq(pl.position[0] - 0.5, 452.0 / 60.0, 1e-3, "ran %f m", pl.position[0] - 0.5);
    cr_expect_float_eq(pl.velocity[0], 8.0f, 1e-4);
    double before = pl.position[0];
    for (int i = 0; i < 30; i++) game_player_update(&pl, world, &(input_actions){ 0 }, 1.0f / 60.0f);
    cr_expect_float_eq(pl.position[0] - before, 28.0 / 60.0, 1e-3, "slid %f m", pl.position[0] - before);
    cr_expect_float_eq(pl.velocity[0], 0.0f, 1e-6);
    /* up to speed again, then a jump with the stick pulled back */
    for (int i = 0; i < 30; i++) game_player_update(&pl, world, &run, 1.0f / 60.0f);
    game_player_update(&pl, world, &(input_actions){ .move_y = -1, .down = BIT(SPRINT), .pressed = BIT(JUMP) },
                       1.0f / 60.0f);
    cr_assert_not(pl.on_ground);
    for (int i = 0; i < 11; i++)
        game_player_update(&pl, world, &(input_actions){ .move_y = -1, .down = BIT(SPRINT) }, 1.0f / 60.0f);
    cr_expect_not(pl.on_ground);
    /* the jump frame itself was on the ground (60 m/s², −1 m/s), then 11 frames in the air */
    cr_expect_float_eq(pl.velocity[0], 8.0f - 1.0f - 11.0f * 12.0f / 60.0f, 1e-3, "%f m/s", pl.velocity[0]);
    terrain_world_destroy(world);
}

/* ---- streaming -------------------------------------------------------------------------------- */

static bool ready_below_x(void *user, const double min[3], const double max[3]) {
    (void)min;
    return max[0] <= *(const double *)user;
}

Test(game_player, waits_at_the_edge_of_unready_terrain_and_never_falls) {
    hand_world hand = { .kind = FLAT, .ground = 0 };
    terrain_world *world = hand_world_create(&hand);
    double limit = 20.0;
    game_player pl;
    game_player_init(&pl, &(game_player_desc){ .region_ready = ready_below_x, .region_user = &limit });
    pl.position[0] = 5.5, pl.position[2] = 0.5, pl.yaw = YAW_PLUS_X, pl.on_ground = true;
    for (int i = 0; i < 300; i++) {
        game_player_update(&pl, world, &walk(0, 1), 1.0f / 60.0f);
        cr_assert_lt(pl.position[0], limit, "walked to x = %f", pl.position[0]);
        cr_assert_float_eq(pl.position[1], 0.0, 1e-3);
    }
    cr_expect(pl.waiting);
    cr_expect_gt(pl.position[0], limit - 4.0, "waits far from the edge: x = %f", pl.position[0]);
    /* in the air over terrain that is not ready: held, not falling */
    limit = -100.0;
    pl.position[1] = 5.0, pl.on_ground = false;
    for (int i = 0; i < 100; i++) game_player_update(&pl, world, &(input_actions){ 0 }, 1.0f / 60.0f);
    cr_expect_eq(pl.position[1], 5.0);
    limit = 1e9;                                  /* ready: falls and lands */
    for (int i = 0; i < 120; i++) game_player_update(&pl, world, &(input_actions){ 0 }, 1.0f / 60.0f);
    cr_expect_not(pl.waiting);
    cr_expect_float_eq(pl.position[1], 0.0, 1e-3);
    terrain_world_destroy(world);
}

/* ---- determinism and the far world ------------------------------------------------------------ */

/* A scripted frame: a few seconds of each thing, from a counter (no generator). */
static input_actions scripted(int frame) {
    input_actions a = { 0 };
    int phase = (frame / 40) % 8;
    a.move_y = phase == 5 ? -0.5f : 1.0f;
    a.move_x = phase == 2 ? 0.7f : phase == 6 ? -0.7f : 0.0f;
    a.look_x = 0.01f * (float)((frame % 7) - 3);
    a.look_y = 0.004f * (float)((frame % 5) - 2);
    if (phase == 3) a.down |= BIT(SPRINT);
    if (phase == 4) a.down |= BIT(CROUCH);
    if (frame % 50 == 10) a.down |= BIT(JUMP), a.pressed |= BIT(JUMP);
    if (frame == 450 || frame == 520) a.pressed |= BIT(TOGGLE_FLY);
    return a;
}

static void run_script(int64_t shift_chunks, double trajectory[600][3], game_player *out) {
    hand_world hand = { .kind = STEP, .ground = 0, .edge = 12, .rise = 2.0, .shift_chunks = shift_chunks };
    terrain_world *world = hand_world_create(&hand);
    double shift = (double)(shift_chunks * TERRAIN_CHUNK_COLUMNS);
    game_player pl;
    place(&pl, 3.5 + shift, 0.0, 0.5 + shift);
    pl.yaw = YAW_PLUS_X - 0.3f;
    for (int frame = 0; frame < 600; frame++) {
        input_actions a = scripted(frame);
        game_player_update(&pl, world, &a, 1.0f / 60.0f);
        trajectory[frame][0] = pl.position[0] - shift;
        trajectory[frame][1] = pl.position[1];
        trajectory[frame][2] = pl.position[2] - shift;
    }
    *out = pl;
    terrain_world_destroy(world);
}

static bool same_state(const game_player *a, const game_player *b) {
    return memcmp(a->position, b->position, sizeof a->position) == 0 &&
           memcmp(a->velocity, b->velocity, sizeof a->velocity) == 0 && memcmp(&a->yaw, &b->yaw, sizeof a->yaw) == 0 &&
           memcmp(&a->pitch, &b->pitch, sizeof a->pitch) == 0 && a->on_ground == b->on_ground &&
           a->crouching == b->crouching && a->flying == b->flying;
}

static double trajectory_a[600][3], trajectory_b[600][3], trajectory_far[600][3];

Test(game_player, deterministic_and_the_same_100km_out) {
    game_player a, b, far;
    run_script(0, trajectory_a, &a);
    run_script(0, trajectory_b, &b);
    cr_expect(same_state(&a, &b), "two runs differ");
    cr_expect(memcmp(trajectory_a, trajectory_b, sizeof trajectory_a) == 0);
    run_script(100000 / TERRAIN_CHUNK_COLUMNS, trajectory_far, &far);
    double worst = 0.0;
    for (int f = 0; f < 600; f++)
        for (int i = 0; i < 3; i++) worst = fmax(worst, fabs(trajectory_far[f][i] - trajectory_a[f][i]));
    cr_expect_leq(worst, 1e-6, "100 km out the trajectory differs by %g m", worst);
    /* the script must have done something: moved, climbed the step, flown */
    cr_expect_gt(fabs(trajectory_a[599][0] - 3.5) + fabs(trajectory_a[599][2] - 0.5), 5.0);
}

/* ---- generated terrain ------------------------------------------------------------------------ */

Test(game_player, walks_generated_terrain_with_eye_in_air_and_feet_on_the_surface) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    game_player pl;
    game_player_init(&pl, NULL);
    game_player_spawn(&pl, world, 0.0, 0.0);
    cr_assert(pl.on_ground, "spawned in the air at %f", pl.position[1]);
    /* on a slope of angle θ the bottom sphere touches the ground off its axis, so the feet point
     * (the axis's lowest point) lies r·(1/cos θ − 1) inside: 0.19 m at the 50° limit */
    double allowed = 0.35 * (1.0 / cos(50.0 * 3.14159265 / 180.0) - 1.0) + 0.03;
    double deepest = -1.0;
    for (int frame = 0; frame < 2000; frame++) {
        input_actions a = { .move_y = 1.0f, .look_x = frame % 400 == 0 ? 0.5f : 0.0f };
        if (frame % 60 == 30) a.down |= BIT(JUMP), a.pressed |= BIT(JUMP);
        game_player_update(&pl, world, &a, 1.0f / 60.0f);
        double eye[3];
        game_player_eye(&pl, eye);
        cr_assert_lt(terrain_field_at(world, eye[0], eye[1], eye[2], 1.0f), 0.0f, "eye in solid, frame %d", frame);
        float centre = terrain_field_at(world, pl.position[0], pl.position[1] + 0.35, pl.position[2], 1.0f);
        cr_assert_lt(centre, 0.0f, "bottom sphere's centre in solid, frame %d", frame);
        float feet = terrain_field_at(world, pl.position[0], pl.position[1], pl.position[2], 1.0f);
        deepest = fmax(deepest, feet);
    }
    cr_expect_leq(deepest, allowed, "feet %f inside", deepest);
    terrain_world_destroy(world);
}

/* ---- the most open view ------------------------------------------------------------------- */

/* A 20 m wall beyond x = 10, flat ground elsewhere. Every direction with a +x component meets
 * the wall within the 96 m sampled, so its skyline rises above the horizon; every other one sees
 * flat ground, whose skyline is the eye's drop over the farthest sample, atan2(−eye, 96). Of
 * those ties the smallest turn from the preferred yaw (+x, into the wall) is a quarter turn, to
 * yaw 0 (−z) or π (+z, the first of the two in the search), rather than a half turn to −x. */
Test(game_player, the_most_open_view_turns_away_from_a_wall_by_the_smallest_turn) {
    hand_world hand = { .kind = WALL, .edge = 10.0 };
    terrain_world *world = hand_world_create(&hand);
    game_player pl;
    place(&pl, 0.5, 0.0, 0.5);
    double eye[3];
    game_player_eye(&pl, eye);
    float skyline;
    float yaw = game_player_open_yaw(&pl, world, YAW_PLUS_X, &skyline);
    cr_expect_leq(fabs(remainder((double)yaw, 3.14159265358979)), 1e-5, "yaw %f: along the wall", (double)yaw);
    cr_expect_float_eq(skyline, atan2(-eye[1], GAME_PLAYER_VIEW_DISTANCE), 1e-5, "skyline %f", (double)skyline);
    /* On flat ground every direction ties: the preferred one is kept. */
    hand_world flat = { .kind = FLAT };
    terrain_world *plain = hand_world_create(&flat);
    cr_expect_float_eq(game_player_open_yaw(&pl, plain, 1.0f, NULL), 1.0f, 1e-6);
    terrain_world_destroy(plain);
    terrain_world_destroy(world);
}
