/* The player in water (game/player.h: wading, swimming, diving, climbing out; issue 15), in
 * hand-built worlds of bedrock columns with water layers on them.
 *
 * Water is not in the field (terrain_material_in_field), so the collision sees only the bedrock:
 * with σ = 1 a flat bed at height g has its surface exactly at y = g (test_player.c works that
 * out), whatever water lies over it. What the player must do follows from player.h's rules and the
 * default parameters, not from the code:
 *   - wading with the feet d under the surface, the gait is the walk speed (4.5 m/s; the sprint does
 *     not apply) times 1 − 0.5·min(d / 1.2, 1): at d = 0.5 that is 1 − 0.5·0.5/1.2 = 0.791667,
 *     so a steady 2 s covers 9.0 m on dry ground and 7.125 m in the water;
 *   - afloat, the eye rests 0.1 m over the surface: the feet 1.62 − 0.1 = 1.52 m under it;
 *   - diving (crouch) sinks at up to 2.5 m/s, eased at 10 m/s²: 2 s from rest go 2.5·2 − 2.5²/20
 *     = 4.6875 m down; let go, it floats back up and settles at rest without overshoot;
 *   - a shore up to 1 m over the surface is climbed onto; a 3 m cliff is not.
 * Layer heights are stored in quanta of 1/32 m, so the worlds use heights that are whole quanta.
 */
#include "../engine/test.h"
#include "game/walk.h"

#include <math.h>
#include <string.h>

#define SURFACE 10.0
#define EYE_AFLOAT (SURFACE + 0.1)
#define BIT(a) INPUT_ACTION_BIT(INPUT_ACTION_##a)
#define YAW_PLUS_X 1.57079632679f      /* yaw 0 looks along −z; a quarter turn right looks along +x */

/* ---- worlds -------------------------------------------------------------------------------- */

typedef enum water_kind {
    BEACH,          /* bed 11 − 0.25·x (a 14° slope), down to 4; water to 10 where it is lower */
    SHALLOWS,       /* flat ground at 10 under `depth` metres of water (none: dry) */
    DEEP,           /* a bed at 0 under 10 m of water everywhere */
    LEDGE,          /* x < 0: a bed at 5 under water to 10; x ≥ 0: dry land `rise` over the water */
    LAKE,           /* flat ground at 10 with a lake for x ∈ [0, 20): a bed at 5, water to 10 */
} water_kind;

typedef struct water_world {
    water_kind kind;
    double depth, rise;
} water_world;

/* Bedrock up to `bed`, then water up to `surface` if that is higher. */
static void push_column(terrain_stacks_builder *b, double bed, double surface) {
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(bed - TERRAIN_FLOOR_Y));
    if (surface > bed) terrain_stacks_builder_push(b, TERRAIN_WATER, (float)(surface - bed));
}

static void water_column(void *user, int64_t gx, int64_t gz, terrain_stacks_builder *b) {
    const water_world *w = user;
    double x = (double)gx;
    (void)gz;
    switch (w->kind) {
    case BEACH: push_column(b, fmax(11.0 - 0.25 * x, 4.0), SURFACE); break;
    case SHALLOWS: push_column(b, 10.0, 10.0 + w->depth); break;
    case DEEP: push_column(b, 0.0, SURFACE); break;
    case LEDGE: push_column(b, x < 0 ? 5.0 : SURFACE + w->rise, SURFACE); break;
    case LAKE: push_column(b, x >= 0 && x < 20 ? 5.0 : 10.0, SURFACE); break;
    }
}

static terrain_stacks *water_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, water_column, user);
}

static terrain_world *water_world_create(water_world *w) {
    return terrain_world_create(&(terrain_world_desc){ .generate = water_generate, .generate_user = w });
}

/* Stands (or floats) the player at (x, y, z), looking along +x. */
static void place(game_player *pl, double x, double y, double z) {
    game_player_init(pl, NULL);
    pl->position[0] = x, pl->position[1] = y, pl->position[2] = z;
    pl->yaw = YAW_PLUS_X;
    pl->on_ground = true;
}

static double eye_y(const game_player *pl) {
    double eye[3];
    game_player_eye(pl, eye);
    return eye[1];
}

static void run(game_player *pl, terrain_world *world, input_actions a, double seconds, float dt) {
    int frames = (int)lround(seconds / dt);
    for (int i = 0; i < frames; i++) game_player_update(pl, world, &a, dt);
}

#define FORWARD ((input_actions){ .move_y = 1.0f })
#define IDLE ((input_actions){ 0 })

/* ---- wading ---------------------------------------------------------------------------------- */

/* Metres walked along +x between 1 s and 3 s (the ease to speed takes under 0.1 s). */
static double steady_distance(double depth, bool sprint) {
    water_world w = { .kind = SHALLOWS, .depth = depth };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    place(&pl, 0.5, 10.0, 0.5);
    input_actions a = FORWARD;
    if (sprint) a.down |= BIT(SPRINT);
    float dt = 1.0f / 60.0f;
    run(&pl, world, a, 1.0, dt);
    double start = pl.position[0];
    run(&pl, world, a, 2.0, dt);
    cr_expect(pl.on_ground, "depth %.1f: not on the ground", depth);
    cr_expect_float_eq(pl.position[1], 10.0, 1e-3, "depth %.1f: feet at %.4f", depth, pl.position[1]);
    cr_expect_eq(pl.in_water, depth > 0.0);
    cr_expect_not(pl.swimming, "depth %.1f: swimming", depth);
    double distance = pl.position[0] - start;
    terrain_world_destroy(world);
    return distance;
}

Test(game_player_water, wading_half_a_metre_deep_is_slower_by_the_stated_rule_and_never_a_sprint) {
    double dry = steady_distance(0.0, false), wet = steady_distance(0.5, false);
    cr_expect_float_eq(dry, 9.0, 0.01, "dry: %.4f m in 2 s", dry);
    cr_expect_float_eq(wet, 7.125, 0.01, "wading: %.4f m in 2 s", wet);
    cr_expect_float_eq(wet / dry, 1.0 - 0.5 * 0.5 / 1.2, 0.002, "ratio %.4f", wet / dry);
    double dry_sprint = steady_distance(0.0, true), wet_sprint = steady_distance(0.5, true);
    cr_expect_float_eq(dry_sprint, 16.0, 0.01, "a sprint on dry ground: %.4f m", dry_sprint);
    cr_expect_float_eq(wet_sprint, wet, 1e-3, "a sprint in the water: %.4f m, walking %.4f m", wet_sprint, wet);
    game_player_desc params;
    game_player pl;
    game_player_init(&pl, NULL);
    params = pl.params;
    cr_expect_float_eq(game_player_wade_share(&params, 0.5f), 1.0f - 0.5f * 0.5f / 1.2f, 1e-6);
    cr_expect_float_eq(game_player_wade_share(&params, 1.2f), 0.5f, 1e-6);
    cr_expect_float_eq(game_player_wade_share(&params, 3.0f), 0.5f, 1e-6);
    cr_expect_eq(game_player_wade_share(&params, 0.0f), 1.0f);
}

Test(game_player_water, a_wader_still_jumps) {
    water_world w = { .kind = SHALLOWS, .depth = 0.5 };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    place(&pl, 0.5, 10.0, 0.5);
    float dt = 1.0f / 60.0f;
    run(&pl, world, IDLE, 0.1, dt);                          /* the water state is known */
    cr_assert(pl.in_water && !pl.swimming && pl.on_ground);
    input_actions jump = { .down = BIT(JUMP), .pressed = BIT(JUMP) };
    game_player_update(&pl, world, &jump, dt);
    double highest = pl.position[1];
    for (int i = 0; i < 120; i++) {
        game_player_update(&pl, world, &(input_actions){ 0 }, dt);
        highest = fmax(highest, pl.position[1]);
    }
    /* a 1.1 m jump, less what the frames cut off its top */
    cr_expect_gt(highest, 10.0 + 1.0, "the jump rose to %.3f", highest);
    cr_expect(pl.on_ground && fabs(pl.position[1] - 10.0) < 1e-3, "landed at %.4f", pl.position[1]);
    terrain_world_destroy(world);
}

/* ---- swimming --------------------------------------------------------------------------------- */

Test(game_player_water, walking_into_the_sea_from_a_beach_ends_up_swimming_at_the_surface) {
    water_world w = { .kind = BEACH };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    place(&pl, -3.5, 12.0, 0.5);            /* column −4: dry ground at 11 + 1 = 12 */
    float dt = 1.0f / 60.0f;
    bool waded = false;
    for (int i = 0; i < 10 * 60; i++) {     /* 10 s on: wading from x ≈ 4, swimming from x ≈ 8 */
        game_player_update(&pl, world, &FORWARD, dt);
        waded |= pl.in_water && !pl.swimming;
        if (pl.swimming) {
            /* afloat, never walking along the bed: the feet stay above the bed under them */
            double bed = fmax(11.0 - 0.25 * floor(pl.position[0]), 4.0);
            cr_assert_geq(pl.position[1], bed - 0.2, "frame %d: feet %.3f under the bed %.3f", i, pl.position[1], bed);
        }
    }
    cr_expect(waded, "never waded on the way in");
    cr_assert(pl.swimming, "not swimming at x = %.1f (feet %.3f)", pl.position[0], pl.position[1]);
    cr_expect_gt(pl.position[0], 20.0, "swam only to x = %.1f", pl.position[0]);
    run(&pl, world, IDLE, 4.0, dt);         /* let it settle */
    double bed = fmax(11.0 - 0.25 * floor(pl.position[0]), 4.0);
    cr_expect_float_eq(eye_y(&pl), EYE_AFLOAT, 0.01, "eye at %.4f, afloat is %.2f", eye_y(&pl), EYE_AFLOAT);
    cr_expect_gt(pl.position[1] - bed, 2.0, "feet %.2f, the bed %.2f", pl.position[1], bed);
    cr_expect(pl.in_water && !pl.eye_under_water && !pl.on_ground);
    cr_expect_float_eq(pl.water_surface, SURFACE, 1e-6);
    cr_expect_float_eq(pl.water_depth, 1.52, 0.01, "feet %.3f under the surface", pl.water_depth);
    /* at rest: no jitter */
    double last = eye_y(&pl), moved = 0.0;
    for (int i = 0; i < 60; i++) {
        game_player_update(&pl, world, &IDLE, dt);
        moved = fmax(moved, fabs(eye_y(&pl) - last));
        last = eye_y(&pl);
    }
    cr_expect_lt(moved, 1e-4, "the eye moved %.6f m in a frame at rest", moved);
    terrain_world_destroy(world);
}

Test(game_player_water, spawned_with_no_land_near_it_floats_at_the_surface) {
    water_world w = { .kind = DEEP };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    game_player_init(&pl, NULL);
    game_player_spawn(&pl, world, 3.5, -2.5);
    cr_expect(pl.swimming && pl.in_water && !pl.on_ground);
    cr_expect_float_eq(eye_y(&pl), EYE_AFLOAT, 2e-3, "eye at %.4f", eye_y(&pl));
    terrain_world_destroy(world);
}

/* Dives for 2 s, then holds `up` (or nothing) for `seconds`; returns the lowest eye height. */
static double dive_and_come_up(game_player *pl, terrain_world *world, input_actions up, double seconds,
                               double *highest_after) {
    float dt = 1.0f / 60.0f;
    input_actions dive = { .down = BIT(CROUCH) };
    run(pl, world, dive, 2.0, dt);
    double lowest = eye_y(pl);
    cr_expect(pl->eye_under_water && pl->swimming && !pl->crouching);
    *highest_after = -1e9;
    for (int i = 0; i < (int)lround(seconds / dt); i++) {
        game_player_update(pl, world, &up, dt);
        *highest_after = fmax(*highest_after, eye_y(pl));
    }
    return lowest;
}

Test(game_player_water, diving_goes_down_and_letting_go_comes_back_up) {
    water_world w = { .kind = DEEP };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    game_player_init(&pl, NULL);
    game_player_spawn(&pl, world, 0.5, 0.5);
    double highest;
    double lowest = dive_and_come_up(&pl, world, IDLE, 6.0, &highest);
    cr_expect_float_eq(EYE_AFLOAT - lowest, 4.6875, 0.05, "dived %.3f m in 2 s", EYE_AFLOAT - lowest);
    cr_expect_float_eq(eye_y(&pl), EYE_AFLOAT, 0.005, "back at %.4f", eye_y(&pl));
    cr_expect_leq(highest, EYE_AFLOAT + 0.005, "overshot to %.4f", highest);
    cr_expect(!pl.eye_under_water && pl.swimming);
    /* Jump rises faster than letting go: after 1.5 s it is higher. */
    game_player a, b;
    game_player_init(&a, NULL);
    game_player_spawn(&a, world, 0.5, 0.5);
    b = a;
    double ignored;
    dive_and_come_up(&a, world, IDLE, 1.5, &ignored);
    dive_and_come_up(&b, world, (input_actions){ .down = BIT(JUMP) }, 1.5, &ignored);
    cr_expect_gt(eye_y(&b), eye_y(&a) + 0.5, "jump: %.3f, letting go: %.3f", eye_y(&b), eye_y(&a));
    /* Down to the bed on purpose, and along it: 10 m down at 2.5 m/s */
    game_player c = a;
    run(&c, world, (input_actions){ .down = BIT(CROUCH), .move_y = 1.0f }, 6.0, 1.0f / 60.0f);
    cr_expect_float_eq(c.position[1], 0.0, 0.01, "a diver reaches the bed: feet at %.3f", c.position[1]);
    terrain_world_destroy(world);
}

/* Let go 3 m under the float height: back up, settled, and never above it, at any frame rate
 * (the spring is solved exactly over each step, not integrated). */
Test(game_player_water, the_float_settles_without_overshoot_at_20_60_and_144_hz) {
    water_world w = { .kind = DEEP };
    terrain_world *world = water_world_create(&w);
    const float rates[] = { 20.0f, 60.0f, 144.0f };
    for (int r = 0; r < 3; r++) {
        game_player pl;
        game_player_init(&pl, NULL);
        game_player_spawn(&pl, world, 0.5, 0.5);
        pl.position[1] -= 3.0;
        double highest = -1e9;
        float dt = 1.0f / rates[r];
        for (int i = 0; i < (int)lroundf(5.0f * rates[r]); i++) {
            game_player_update(&pl, world, &IDLE, dt);
            highest = fmax(highest, eye_y(&pl));
        }
        cr_expect_float_eq(eye_y(&pl), EYE_AFLOAT, 0.005, "%.0f Hz: eye at %.4f after 5 s", rates[r], eye_y(&pl));
        cr_expect_leq(highest, EYE_AFLOAT + 0.002, "%.0f Hz: overshot to %.4f", rates[r], highest);
    }
    terrain_world_destroy(world);
}

Test(game_player_water, flying_ignores_the_water) {
    water_world w = { .kind = DEEP };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    place(&pl, 0.5, 5.0, 0.5);
    pl.flying = true, pl.on_ground = false;
    run(&pl, world, FORWARD, 1.0, 1.0f / 60.0f);
    cr_expect(pl.flying && !pl.swimming && pl.in_water && pl.eye_under_water);
    cr_expect_float_eq(pl.velocity[0], 12.0, 1e-3, "flying at %.3f m/s", pl.velocity[0]);
    cr_expect_float_eq(pl.position[1], 5.0, 1e-3);
    terrain_world_destroy(world);
}

/* ---- leaving the water ------------------------------------------------------------------------- */

/* A swimmer 6.5 m out from a shore `rise` over the surface, swimming at it for `seconds`. */
static game_player swim_at_shore(double rise, double seconds) {
    water_world w = { .kind = LEDGE, .rise = rise };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    place(&pl, -6.5, EYE_AFLOAT - 1.62, 0.5);
    pl.on_ground = false;
    run(&pl, world, FORWARD, seconds, 1.0f / 60.0f);
    terrain_world_destroy(world);
    return pl;
}

Test(game_player_water, a_swimmer_climbs_out_onto_a_shore_a_metre_up_but_not_up_a_cliff) {
    /* Heights are whole 1/32 m quanta, and ground whose height has a fraction over 1 − r = 0.65
     * reads 0.08 m low (the probe's grid cell above it holds f's saturation at −1: a gradient of
     * 0.75), which this test does not measure. */
    static const double rises[] = { 0.25, 0.5, 1.0 };
    for (int k = 0; k < 3; k++) {
        double rise = rises[k];
        game_player pl = swim_at_shore(rise, 6.0);
        cr_expect(!pl.in_water && !pl.swimming && pl.on_ground, "rise %.1f: in water %d, swimming %d, on ground %d",
                  rise, pl.in_water, pl.swimming, pl.on_ground);
        cr_expect_float_eq(pl.position[1], SURFACE + rise, 0.01, "rise %.2f: feet at %.3f, x %.3f, climbing %d", rise,
                           pl.position[1], pl.position[0], pl.climbing);
        cr_expect_gt(pl.position[0], 1.0, "rise %.1f: only at x = %.2f", rise, pl.position[0]);
    }
    game_player pl = swim_at_shore(3.0, 6.0);
    cr_expect(pl.in_water && pl.swimming, "a 3 m cliff: in water %d, swimming %d", pl.in_water, pl.swimming);
    cr_expect_lt(pl.position[0], 0.0, "at x = %.2f", pl.position[0]);
    cr_expect_float_eq(eye_y(&pl), EYE_AFLOAT, 0.05, "eye at %.3f under the cliff", eye_y(&pl));
}

Test(game_player_water, walking_out_of_the_sea_up_a_beach_stops_swimming) {
    water_world w = { .kind = BEACH };
    terrain_world *world = water_world_create(&w);
    game_player pl;
    game_player_init(&pl, NULL);
    game_player_spawn(&pl, world, 24.5, 0.5);   /* the nearest dry column is 16 m to −x */
    cr_expect(!pl.in_water && pl.on_ground, "spawned on the beach");
    cr_expect_leq(pl.position[0], 5.0, "spawned at x = %.1f", pl.position[0]);
    /* out to sea and back */
    pl.position[0] = 24.5, pl.position[1] = EYE_AFLOAT - 1.62;
    pl.on_ground = false;
    pl.yaw = -YAW_PLUS_X;                       /* towards −x: the beach */
    run(&pl, world, FORWARD, 12.0, 1.0f / 60.0f);
    cr_expect(!pl.in_water && !pl.swimming && pl.on_ground, "x = %.1f: in water %d, swimming %d", pl.position[0],
              pl.in_water, pl.swimming);
    cr_expect_lt(pl.position[0], 4.0, "only reached x = %.1f", pl.position[0]);
    terrain_world_destroy(world);
}

/* ---- a scripted walk across a lake --------------------------------------------------------- */

Test(game_player_water, a_walk_across_a_lake_swims_it_and_is_not_stuck) {
    water_world w = { .kind = LAKE };
    terrain_world *world = water_world_create(&w);
    game_walk walk;
    core_error error = { 0 };
    const char text[] = "relative\n40 0\n";
    cr_assert(game_walk_parse_text(text, strlen(text), "lake.walk", &walk, &error), "%s", error.message);
    game_player pl;
    place(&pl, -10.5, 10.0, 0.5);
    game_walker walker;
    game_walker_start(&walker, &walk, &pl);
    float dt = 1.0f / 30.0f;
    int swimming_frames = 0, frame = 0;
    for (; frame < 3000 && !game_walker_done(&walker); frame++) {
        input_actions a = game_walker_step(&walker, &pl, dt);
        game_player_update(&pl, world, &a, dt);
        swimming_frames += pl.swimming;
        cr_assert_not(pl.flying, "frame %d: flying", frame);
    }
    cr_expect(game_walker_done(&walker) && !walker.stuck, "%s after %d frames at x = %.1f",
              walker.stuck ? "stuck" : "not done", frame, pl.position[0]);
    cr_expect_leq(fabs(pl.position[0] - 29.5), 2.0 + 1e-6, "ended at x = %.2f", pl.position[0]);
    cr_expect_float_eq(pl.position[1], 10.0, 0.05, "feet at %.3f", pl.position[1]);
    /* 20 m of lake at 5 m/s is 4 s: 120 frames, less what the edges take */
    cr_expect_gt(swimming_frames, 60, "swam %d frames", swimming_frames);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

