/* player.h — the first-person player controller of the walkable world: walking with gravity,
 * jump, sprint and crouch, a capsule colliding with the terrain's implicit field, wading and
 * swimming in water, and a fly mode for inspection.
 *
 *     terrain_world *world = terrain_world_create(&(terrain_world_desc){
 *         .generation = terrain_generation_defaults(42) });
 *     game_player player;
 *     game_player_init(&player, &(game_player_desc){ 0 });      // zero = every default
 *     game_player_spawn(&player, world, 0.0, 0.0);                 // on solid ground near (0, 0)
 *     for (;;) {                                                    // each frame
 *         input_update(input, dt);                                  // devices or a replay
 *         const input_actions *actions = input_actions_get(input);
 *         game_player_update(&player, world, actions, input_frame_dt(input));
 *         double eye[3];
 *         game_player_eye(&player, eye);
 *         terrain_view view = { .camera = { eye[0], eye[1], eye[2] },
 *                               .yaw = player.yaw, .pitch = player.pitch };
 *         ...
 *     }
 *
 * Model. The player is a capsule (radius r, height h, feet at `position`) made of sphere probes
 * along its axis. The terrain is the field f of terrain_field_sample (f > 0 solid, f = 0 the
 * surface); each update samples f on the integer grid points around the capsule's swept box and
 * reads it between them by trilinear interpolation. A probe's distance to the surface is
 * estimated as −f/|∇f| (exact on flat ground and planar walls, where f is a clamped distance).
 * Motion is cut into substeps of at most r/2, and after each one every probe that is closer than
 * r to the surface is pushed out: so a probe's centre never reaches the solid side and the
 * player cannot tunnel, whatever the speed (game/README.md has the argument).
 * Surfaces are walkable up to max_slope_deg: on those the player stands (no sliding, no
 * gravity, snapped down slopes and small ledges up to step_height); steeper ones are walls
 * (pushed out horizontally only, so running into them never lifts the player); downward-facing
 * ones are ceilings.
 *
 * Motion eases: the horizontal velocity moves towards what the input asks by at most
 * ground_accel·dt a frame on the ground (air_accel in the air, so a jump keeps most of its
 * momentum and can be steered a little), the whole velocity by fly_accel·dt when flying.
 *
 * Water (issue 15). Water is a material layer of the stacks (000 §3.1) that the field, and so the
 * collision, does not see; terrain_world_water_at says where a surface lies over the column under
 * the feet. With the feet under it by d (the immersion), and d below swim_depth (the water under
 * the chest), the player wades: it walks, jumps and crouches as on land, but its gait is the walk
 * speed (the sprint does not apply in water) times game_player_wade_share(d) = 1 −
 * wade_slowdown·min(d / swim_depth, 1): 1 on dry land, 0.79 at 0.5 m, 0.5 at the chest. Deeper
 * it swims: no gravity; it moves in the horizontal plane of the look direction at swim_speed
 * (sprint: swim_sprint_speed), easing at swim_accel; it floats with its eye swim_eye_above the
 * surface. The float is a critically damped spring within speed/ω of that height (ω =
 * buoyancy_rate; solved exactly each substep, so it settles without overshoot or jitter at any
 * frame rate), and farther away a steady rise at float_speed. Crouch (C, Ctrl) dives at
 * dive_speed; jump (Space) rises at dive_speed; letting go floats back up. So it touches the sea
 * bed only where the water is shallower than its floating depth (eye_height − swim_eye_above) or
 * when it dives on purpose. It stops swimming where its feet stand on the bed less than
 * swim_depth under the surface (a beach: wading), or once its feet are out of the water. Heading
 * into a shore whose ground, within 1.6 m ahead, rises more than step_height above its feet but
 * at most climb_out_height above the surface, a swimmer climbs out (`climbing`: rises at
 * dive_speed while pressing on, to a little over the top, moves over it and lands; letting go of
 * the move input ends the climb); a higher shore is a cliff it stays under.
 * Flying ignores water. The state says in_water, swimming and eye_under_water (for the renderer's
 * tint) after each update.
 *
 * Streaming: before a frame's motion, params.region_ready (when set) is asked whether the box the
 * frame will read is available; if not, the player does not move at all that frame (no walking,
 * no falling) and the field is not sampled, so unready chunks are never generated on the main
 * thread. The player waits where it is until the region is ready.
 *
 * Coordinates: `position` is double precision (world metres); each update works in floats
 * relative to an integer local origin near the player, so the controller behaves the same at
 * 100 km from the world's origin as at the origin. Deterministic: the same state, inputs and dt
 * give the same result bit for bit (no clocks, no globals). Not thread-safe per player.
 * Yaw 0 looks along −z, positive turns right; pitch positive looks up (terrain_view's convention).
 */
#ifndef GAME_PLAYER_H
#define GAME_PLAYER_H

#include <stdbool.h>

#include "input/input.h"
#include "terrain/terrain.h"

/* Zero means the default for every field. */
typedef struct game_player_desc {
    float radius;                     /* capsule radius; 0 = 0.35 m */
    float height;                     /* standing capsule height; 0 = 1.8 m */
    float crouch_height;              /* 0 = 1.2 m */
    float eye_height;                 /* above the feet, standing; 0 = 1.62 m */
    float crouch_eye_height;          /* 0 = 1.05 m */
    float walk_speed;                 /* 0 = 4.5 m/s */
    float sprint_speed;               /* 0 = 8 m/s */
    float crouch_speed;               /* 0 = 2 m/s */
    float jump_speed;                 /* 0 = sqrt(2·gravity·1.1 m), a 1.1 m jump */
    float gravity;                    /* 0 = 20 m/s² */
    float terminal_speed;             /* fastest fall; 0 = 50 m/s */
    float step_height;                /* ledges climbed without a jump; 0 = 0.5 m */
    float max_slope_deg;              /* steepest walkable slope; 0 = 50° */
    float fly_speed;                  /* 0 = 12 m/s */
    float fly_sprint_speed;           /* 0 = 48 m/s */
    float pitch_limit;                /* radians; 0 = 1.55 (just under straight up/down) */
    /* How fast the velocity reaches what the input asks (m/s²), so starts and stops ease in
     * and out: on the ground 0 = 60 (a sprint reached in 0.13 s), in the air (air control)
     * 0 = 12, flying 0 = 120. Negative: at once (the velocity is the input's). */
    float ground_accel, air_accel, fly_accel;
    float bob_amplitude;              /* head bob on the ground at a sprint, metres; 0 = 0.05,
                                         negative = none (game_player_bob) */
    float max_dt;                     /* longer frames are clamped to this; 0 = 0.1 s */
    /* Water (see the model above). */
    float swim_depth;                 /* immersion from which the player swims; 0 = 1.2 m (the
                                         chest); at most eye_height − swim_eye_above − 0.1 */
    float wade_slowdown;              /* share of the walk speed lost at swim_depth; 0 = 0.5 */
    float swim_eye_above;             /* the floating eye over the surface; 0 = 0.1 m */
    float swim_speed;                 /* 0 = 3 m/s */
    float swim_sprint_speed;          /* 0 = 5 m/s */
    float dive_speed;                 /* down with crouch, up with jump, climbing out; 0 = 2.5 m/s */
    float float_speed;                /* rising with nothing held; 0 = 1.5 m/s */
    float buoyancy_rate;              /* ω of the float at the surface; 0 = 4 /s (settles in ~1.5 s) */
    float swim_accel;                 /* easing in water; 0 = 10 m/s² */
    float climb_out_height;           /* a shore this far above the surface is climbed onto;
                                         0 = 1 m */
    /* Whether the terrain inside [min, max] (world metres) may be read now. NULL = always
     * (terrain_world generates what it lacks synchronously). */
    bool (*region_ready)(void *user, const double min[3], const double max[3]);
    void *region_user;
    /* Solid things besides the terrain (the rocks of rocks.h). obstacles_near is told, once an
     * update, the box the capsule can reach; obstacle_distance then gives the signed distance
     * from a world point to the nearest obstacle (< 0 inside; max_distance when none is nearer)
     * and its unit normal, and the capsule collides with whichever is nearer, the terrain or
     * it. NULL = none. */
    void (*obstacles_near)(void *user, const double min[3], const double max[3]);
    float (*obstacle_distance)(void *user, const double point[3], float max_distance, float normal[3]);
    void *obstacle_user;
} game_player_desc;

typedef struct game_player {
    game_player_desc params;        /* with the defaults filled in */
    double position[3];               /* the feet: bottom centre of the capsule, world metres */
    float velocity[3];                /* m/s */
    float yaw, pitch;                 /* radians, the view */
    bool on_ground, crouching, flying;
    bool waiting;                     /* the last update did not move: region not ready */
    float bob_phase;                  /* strides walked on the ground, for the head bob */
    /* Water, as the last update left it (flying included). */
    bool in_water;                    /* the feet under a water surface (wading or swimming) */
    bool swimming;                    /* floating, diving or climbing out (never while flying) */
    bool eye_under_water;             /* game_player_eye lies under the surface */
    float water_surface;              /* that surface's height when in_water, world metres */
    float water_depth;                /* the feet's immersion under it; 0 out of water */
    bool climbing;                    /* climbing out of the water onto a shore */
    float climb_top;                  /* while climbing: that shore's ground top, world metres */
    float climb_time;                 /* while climbing: seconds it may still take */
} game_player;

/* Fills in the defaults; the player stands at the origin, not spawned. */
void game_player_init(game_player *player, const game_player_desc *params);
/* Puts the player on solid ground at or near column (x, z): on top of the highest solid layer of
 * the column (never in a cave), settled so that the capsule touches the surface f = 0 without
 * intersecting it. Columns under water are avoided: the nearest dry column within 64 m is taken
 * instead; with none, the player floats at the surface of (x, z) (or stands on its bed where the
 * water is shallow). Velocity zeroed, not flying. Reads the world directly (region_ready is not
 * asked). */
void game_player_spawn(game_player *player, terrain_world *world, double x, double z);
/* The most open view from where the player stands: of GAME_PLAYER_VIEW_DIRECTIONS yaws, the one
 * whose skyline (the steepest angle up to the ground top along the view, sampled every 8 m out
 * to GAME_PLAYER_VIEW_DISTANCE) is lowest; ties go to the direction nearest `preferred`. The
 * skyline's angle in radians goes to *skyline (may be NULL): below 0 the view looks down over
 * the land, above about 0.3 it faces a slope. Reads (generates) the columns it samples. */
#define GAME_PLAYER_VIEW_DIRECTIONS 16
#define GAME_PLAYER_VIEW_DISTANCE 96.0
float game_player_open_yaw(const game_player *player, terrain_world *world, float preferred, float *skyline);
/* One frame: look, then move (walk or fly) with collision. dt in seconds. */
void game_player_update(game_player *player, terrain_world *world, const input_actions *actions, float dt);
/* The eye, world metres. */
void game_player_eye(const game_player *player, double eye[3]);
/* How far the view dips below the eye for the head bob, metres (0 … bob_amplitude): twice a
 * stride (2.4 m), in proportion to the speed over the ground up to a sprint, none flying or in
 * the air. The view only: collision and tools use game_player_eye. */
float game_player_bob(const game_player *player);
/* The capsule's current height (crouched or standing). */
float game_player_height(const game_player *player);
/* The share of its gait a wading player keeps with its feet `depth` metres under the surface:
 * 1 − wade_slowdown·min(depth / swim_depth, 1); 1 for depth ≤ 0. */
float game_player_wade_share(const game_player_desc *params, float depth);

#endif
