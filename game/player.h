/* player.h — the first-person player controller of the walkable world: walking with gravity,
 * jump, sprint and crouch, a capsule colliding with the terrain's implicit field, and a fly mode
 * for inspection.
 *
 *     terrain_world *world = terrain_world_create(&(terrain_world_desc){
 *         .generation = terrain_generation_defaults(42) });
 *     game_player player;
 *     game_player_init(&player, &(game_player_params){ 0 });      // zero = every default
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
typedef struct game_player_params {
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
    /* Whether the terrain inside [min, max] (world metres) may be read now. NULL = always
     * (terrain_world generates what it lacks synchronously). */
    bool (*region_ready)(void *user, const double min[3], const double max[3]);
    void *region_user;
} game_player_params;

typedef struct game_player {
    game_player_params params;        /* with the defaults filled in */
    double position[3];               /* the feet: bottom centre of the capsule, world metres */
    float velocity[3];                /* m/s */
    float yaw, pitch;                 /* radians, the view */
    bool on_ground, crouching, flying;
    bool waiting;                     /* the last update did not move: region not ready */
    float bob_phase;                  /* strides walked on the ground, for the head bob */
} game_player;

/* Fills in the defaults; the player stands at the origin, not spawned. */
void game_player_init(game_player *player, const game_player_params *params);
/* Puts the player on solid ground at or near column (x, z): on top of the highest solid layer of
 * the column (never in a cave), settled so that the capsule touches the surface f = 0 without
 * intersecting it. Columns under water are avoided: the nearest dry column within 64 m is taken
 * instead; with none, the player stands on the sea floor of (x, z) (water is air to the
 * collision; there is no swimming yet). Velocity zeroed, walking mode. Reads the world directly
 * (region_ready is not asked). */
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

#endif
