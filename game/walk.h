/* walk.h — scripted walks: `--walk SCRIPT` turned into the player's input, frame by frame, so a
 * headless run (an end-to-end test, a benchmark, a screenshot) walks the world like a player.
 *
 *     game_walk walk;
 *     core_error error = {0};
 *     if (!game_walk_parse(spec, &walk, &error)) {                 // "straight:2000" or a file
 *         fprintf(stderr, "demo: bad value for '--walk': %s\n", error.message);
 *         return 2;
 *     }
 *     game_walker walker;
 *     game_walker_start(&walker, &walk, &player);                  // after game_player_spawn
 *     while (!game_walker_done(&walker)) {                          // each frame
 *         input_actions actions = game_walker_step(&walker, &player, dt);
 *         game_player_update(&player, world, &actions, dt);
 *         ...                                                       // draw, trace, HUD
 *     }
 *     printf("walked %.1f m, %s\n", walker.walked, walker.stuck ? "stuck" : "arrived");
 *     game_walk_free(&walk);
 *
 * Scripts. `straight:METRES` (0 < METRES ≤ 100000) walks straight ahead from wherever the player
 * starts, in the direction it faces. Anything else is the path of a waypoint file:
 *
 *     # a lap round a square, 40 m a side, starting where the player stands
 *     relative            # waypoints are offsets from the start (world axes), not coordinates
 *     radius 2            # a waypoint is reached within 2 m (the default)
 *     40 0                # X Z, metres; sprinting is the default gait
 *     40 40   walk        # at walking speed
 *     0 40    jump        # hopping all the way
 *     0 0     fly y=30    # flying, climbing to 30 m above the start's feet
 *
 * - A waypoint line is `X Z` (decimal numbers, world metres, |X|, |Z| ≤ 1e9) followed by words:
 *   `sprint` (the default) or `walk`; `jump` (jump whenever on the ground); `fly` (fly mode for
 *   this leg: toggled on before it, off again before a leg without `fly`); `y=H` with `fly`, the
 *   height to fly at (without it a flying leg keeps the height it starts at).
 * - `shot`: once the waypoint is reached the walker holds still (shot_due) until
 *   game_walker_resume, so a program can take a picture there (world --walk: FILE-N.png beside
 *   --screenshot FILE, turned to the most open view, or with `look=YAW,PITCH` that way: degrees
 *   as --look takes them, yaw 0 = +z and 90 = −x, pitch up within ±89).
 * - `cave R [shot]` instead of X Z: a look into the nearest cave mouth or under the nearest arch
 *   within R metres (1 ≤ R ≤ 1000) of the previous waypoint. The program resolves it when the walk
 *   starts (game_walk_resolve_caves: the world program does) into a flight to a view of it that
 *   faces the mouth; a walker given an unresolved one skips it.
 * - `shore R [shot]` instead of X Z: a look out over water from the nearest shore within R metres
 *   (1 ≤ R ≤ 1000) of the previous waypoint, resolved as `cave` lines are (game_walk_resolve_stops,
 *   game_find_shore_view) into a flight to dry ground at the water's edge, facing the water.
 * - `rocks R [shot]` instead of X Z: a look down at the nearest pile of rocks within R metres
 *   (1 ≤ R ≤ 1000) of the previous waypoint, resolved likewise (game_find_rocks_view) into a flight
 *   to a point in the air on the pile's sunlit side; the picture is turned to the pile from
 *   wherever the eye got to (look_at), so it stays in the middle.
 * - `cliff R [shot]` instead of X Z: a look at the nearest cliff within R metres (1 ≤ R ≤ 1000) of
 *   the previous waypoint, resolved likewise (game_find_cliff_view) into a flight to a point
 *   before its sunlit face, the face kept in the middle of the picture (look_at).
 * - Directives, each at most once and before the first waypoint: `relative` (X Z and y= are
 *   offsets from the walker's start), `ahead` (offsets in the start's own frame: X metres to the
 *   right, Z metres ahead, as straight:M is `ahead` + `0 M`), `radius R` (0.1 ≤ R ≤ 1000 m),
 *   `fly-over` (a walking leg whose sidesteps to one side have failed flies the rest of the leg,
 *   climbing over what blocks it, and lands for the next: such a walk never ends stuck at a
 *   wall it could fly over).
 *   Without `relative` or `ahead` the coordinates are absolute (world metres, at any distance).
 * - `#` starts a comment; blank lines are skipped; LF or CRLF line ends; a UTF-8 byte order mark
 *   is skipped. Lines are at most 1024 bytes; at most 100000 waypoints; at least one.
 * Errors name the place and the problem, "path.walk:7: z: 'abc' is not a number", and the parse
 * fails as a whole (a half-read path would walk somewhere else than intended).
 *
 * The walker turns towards the next waypoint (look_x, at most GAME_WALKER_TURN_RATE), runs at it
 * (move_y, slower while it faces away, turning on the spot when it faces more than 90° away), and
 * keeps the pitch a little below level (GAME_WALKER_PITCH) so pictures show both the terrain and
 * the sky. When the last half second covered less than half of what its gait would, it is
 * stalled: it jumps and sidesteps (moves at 45° to the right of the waypoint, then after four
 * stalls to the left, …) for a second, which clears low walls and slides round short tall ones.
 * Flying (toggle_fly pressed once to switch, pitch level) it holds jump or crouch to reach the
 * leg's height, and climbs instead of jumping when stalled. A waypoint is reached within the
 * radius, horizontally (and in 3D for `fly y=H`, which is the feet's height). Each leg has a time
 * limit of twice its length at the gait's speed plus 5 s; running out of it ends the walk with
 * `stuck` set, so an unreachable waypoint ends the walk rather than looping forever.
 *
 * Deterministic: the walker reads only the player and the dt it is given (no clocks, no
 * generator), so a walk replays bit for bit. Its rules are in seconds, so it behaves the same at
 * 30 and at 144 frames a second. Frames in which the player waited for terrain (player.waiting)
 * do not count against the time limit: a walk whose terrain never becomes ready waits as long as
 * the player does, and the program's own frame limit is what ends that.
 * Coordinates are doubles and every difference is taken in double before anything is rounded to
 * float, so a walk 100 km out steers as it does at the origin (tests/game/test_walk.c walks the
 * same relative path at both and compares the displacements).
 */
#ifndef GAME_WALK_H
#define GAME_WALK_H

#include <stdbool.h>
#include <stddef.h>

#include "core/core.h"   /* core_error */

#include "player.h"

#define GAME_WALK_MAX_POINTS 100000
#define GAME_WALK_MAX_LINE 1024           /* bytes before the '\n' (a CRLF's CR counts) */
#define GAME_WALK_MAX_COORD 1e9           /* metres, for X, Z and y= */
#define GAME_WALK_MAX_STRAIGHT 100000.0   /* metres, for straight:M */
#define GAME_WALK_MAX_FILE (16 << 20)     /* bytes of a waypoint file */
#define GAME_WALK_MIN_RADIUS 0.1
#define GAME_WALK_MAX_RADIUS 1000.0
#define GAME_WALK_DEFAULT_RADIUS 2.0f

#define GAME_WALKER_TURN_RATE 6.0f        /* radians a second: 0.1 a frame at 60 Hz */
#define GAME_WALKER_PITCH (-0.1f)         /* the view's pitch while walking */

/* For a program's usage text. */
#define GAME_WALK_USAGE "straight:METRES (0 < METRES <= 100000) or a waypoint file (game/walk.h)"

/* What a waypoint's X Z (and y=) are measured from. */
typedef enum game_walk_frame {
    GAME_WALK_ABSOLUTE,               /* world metres */
    GAME_WALK_RELATIVE,               /* offsets from the walker's start, world axes */
    GAME_WALK_AHEAD,                  /* X to the right, Z ahead of the start's position and yaw */
} game_walk_frame;

typedef struct game_walk_point {
    double x, z;
    double y;                         /* the height to fly at, when has_y */
    bool walk;                        /* walk instead of sprint */
    bool jump;                        /* jump whenever on the ground */
    bool fly;                         /* in fly mode */
    bool has_y;                       /* only with fly */
    bool shot;                        /* hold still for a picture once reached */
    bool has_look;                    /* at the shot, face look_yaw, look_pitch instead of the
                                         most open view */
    float look_yaw, look_pitch;       /* degrees as --look: yaw 0 = +z, 90 = −x; pitch up */
    float cave_radius;                /* > 0: a `cave R` line not yet resolved (the walker skips it) */
    float shore_radius;               /* > 0: a `shore R` line not yet resolved (skipped likewise) */
    float rocks_radius;               /* > 0: a `rocks R` line not yet resolved (skipped likewise) */
    float cliff_radius;               /* > 0: a `cliff R` line not yet resolved (skipped likewise) */
    bool has_look_at;                 /* at the shot, face look_at from wherever the eye got to (within
                                         the walk's radius of the waypoint): set by resolving a `rocks`
                                         or `cliff` line, never by a file, so the pile or the face
                                         stays in the middle */
    double look_at[3];                /* world metres (whatever the walk's frame) */
} game_walk_point;

typedef struct game_walk {
    game_walk_point *points;          /* count of them, owned (game_walk_free) */
    int count;                        /* ≥ 1 after a successful parse */
    game_walk_frame frame;
    float radius;                     /* reach radius, metres; 0 = GAME_WALK_DEFAULT_RADIUS */
    bool fly_over;                    /* a walking leg that sidesteps cannot pass flies over */
} game_walk;

/* The tour `world --tour` takes (and tools/play with no display): from the spawn into the most
 * open view on foot, flying over what it cannot walk round, a look into the nearest cave or under
 * the nearest arch, a look out over the nearest water from its shore (within 150 m of the cave's
 * view), a look down at the nearest pile of rocks (within 150 m of the shore's view), then up
 * 120 m for the view to the horizon; a picture at each of its six stops (fewer where no cave, no
 * shore or no pile is found). A waypoint file's text. */
extern const char game_walk_tour[];

/* Turns each `cave R` waypoint into a flight to a view into the nearest cave or arch within R
 * metres of the waypoint before it (of the player, for the first): game_find_cave_view, the view's
 * eye as a `fly y=H` point in the walk's own frame, facing the mouth (has_look); and each `shore R`
 * waypoint likewise into a flight to a view over water from the nearest shore
 * (game_find_shore_view), each `rocks R` waypoint into a flight to a view of the nearest pile
 * of rocks (game_find_rocks_view; look_at set to the pile), and each `cliff R` waypoint into a
 * flight to a view of the nearest cliff (game_find_cliff_view; look_at set to its face). A line
 * with nothing to find is
 * dropped, with a notice. Call it with the player where the walker will start (game_walker_start
 * measures relative and ahead walks from there). Returns how many of each were found. */
typedef struct game_walk_found { int caves, shores, rocks, cliffs; } game_walk_found;
game_walk_found game_walk_resolve_stops(game_walk *walk, terrain_world *world, const game_player *player);
/* game_walk_resolve_stops (shore and rocks lines too), returning the caves found. */
int game_walk_resolve_caves(game_walk *walk, terrain_world *world, const game_player *player);

/* `spec` is straight:METRES or the path of a waypoint file. On success *out holds the walk (free it
 * with game_walk_free); on failure *out is zeroed (freeing it is harmless), false is returned and
 * `error` (may be NULL) says why in one line naming the file and line ("walk.txt:3: …"):
 * CORE_ERROR_IO (cannot open or read the file), CORE_ERROR_FORMAT (a malformed line, an unknown
 * word, no waypoints, a bad straight: distance), CORE_ERROR_RANGE (a number out of its range,
 * too many waypoints or lines, a line or file too long), CORE_ERROR_ARGUMENT (no spec). */
bool game_walk_parse(const char *spec, game_walk *out, core_error *error);
/* A waypoint file's contents, text[0, size) (no NUL needed); `name` is what errors call it
 * ("walk.txt:3: …"). Same outcome as game_walk_parse. */
bool game_walk_parse_text(const char *text, size_t size, const char *name, game_walk *out, core_error *error);
/* A copy whose points are its own (free it with game_walk_free too). */
void game_walk_copy(const game_walk *from, game_walk *to);
void game_walk_free(game_walk *walk);

/* A look into a cave mouth or under an arch: where to stand and which way to face. */
typedef struct game_cave_view {
    double eye[3];                    /* world metres, over open ground outside the mouth */
    double mouth[3];                  /* the sheltered point looked at, mid-height in the gap */
    float yaw, pitch;                 /* degrees as --look: yaw 0 = +z, 90 = −x; pitch up */
    float depth;                      /* metres of roof between that point and the open ground */
} game_cave_view;

/* Searches the columns within `radius` metres of (x, z) for a sheltered floor (an air gap above
 * the sea with ground under it and a roof over it: a cave, an arch, an overhang) that a level
 * path leads out of onto open ground, and a view from that ground into it with a clear line of
 * sight and the roof low enough in the picture to leave sky at its top. The view nearest its
 * mouth wins (the cave fills more of the picture), then the deepest shelter, then the nearest to
 * (x, z). False when there is none. Generates the chunks it reads (walk_cave.c). */
bool game_find_cave_view(terrain_world *world, double x, double z, double radius, game_cave_view *out);

/* A look out over water from its shore: where to stand and which way to face. */
typedef struct game_shore_view {
    double eye[3];                    /* world metres, over dry ground at the water's edge */
    double water[3];                  /* the water's surface next to it, where the shore is */
    float yaw, pitch;                 /* degrees as --look: yaw 0 = +z, 90 = −x; pitch up */
    float open;                       /* metres of water along the view (out to GAME_SHORE_VIEW_DISTANCE) */
} game_shore_view;

#define GAME_SHORE_VIEW_DISTANCE 64.0

/* Searches the columns within `radius` metres of (x, z) (every 2 m) for a shore: a dry column
 * (terrain_world_water_at false) beside one with water on it, its ground at most 12 m above that
 * water. From there it looks along the one of 16 directions with the most water (sampled every
 * 4 m out to GAME_SHORE_VIEW_DISTANCE, up to the first ground higher than the eye), which must be
 * at least 40 m of it (a sea or a lake, not a puddle); ties go to the direction nearest the water
 * beside it. It stands on the dry column, the eye 1.62 m up, looking down over the water by
 * atan(eye over the surface / 25 m), between 8° and 25°. The nearest shore wins. False when there
 * is none. Generates the chunks it reads (walk_shore.c). */
bool game_find_shore_view(terrain_world *world, double x, double z, double radius, game_shore_view *out);

/* A look at a pile of rocks: where to stand and which way to face. */
typedef struct game_rocks_view {
    double eye[3];                    /* world metres, in the air on the pile's lit side */
    double pile[3];                   /* the point looked at: the pile's centre at its mean height */
    float top;                        /* the pile's highest ground (the top of its rock layers) */
    float yaw, pitch;                 /* degrees as --look: yaw 0 = +z, 90 = −x; pitch up */
    bool open;                        /* no wall behind the pile (see game_find_rocks_view) */
} game_rocks_view;

/* Searches the columns within `radius` metres of (x, z) (every 1 m, square rings outwards) for a
 * pile of rocks: a column whose top solid layer is rocks (TERRAIN_ROCKS, no water over it) at least
 * 1 m thick, with at least 12 of the 5 × 5 columns around it (itself included) such columns. The
 * pile's centre is their centroid at their mean top, its top their highest. The view looks at it
 * from the side the default sun lights: of 8 directions, those whose view has a positive dot with
 * (0.55, 0, 0.35) (the light's way: the sun is towards (−0.55, 0.55, −0.35)), the most lit first;
 * the eye 6.5 to 9 m from the centre and 3 to 5 m over the top, the first of those places whose
 * feet (1.62 m under the eye) clear the ground by 0.5 m, with the ground under the line of sight
 * to the pile (to 1.5 m short of its centre, by 0.25 m). Pitch down at the centre. A view is
 * `open` when the ground behind the pile, out to 48 m, stays 2° under the picture's top edge (a
 * 60° field) along at least 3 of 5 rays 18° apart across the view: the pile is seen against the
 * land, not against a cliff. The first open view of a pile is its view, else its first view; the
 * nearest pile with an open view wins, else the nearest pile with a view. False when there is
 * none. Generates the chunks it reads (walk_rocks.c). */
bool game_find_rocks_view(terrain_world *world, double x, double z, double radius, game_rocks_view *out);

/* A look at a cliff: where to stand and which way to face. */
typedef struct game_cliff_view {
    double eye[3];                    /* world metres, in the air before the face */
    double face[3];                   /* the point looked at: a metre past the foot, up to 6 m over it */
    float height;                     /* metres the ground rises over the 4 m past the foot */
    float yaw, pitch;                 /* degrees as --look: yaw 0 = +z, 90 = −x; pitch up */
} game_cliff_view;

/* Searches the columns within `radius` metres of (x, z) (every 2 m, square rings outwards) for a
 * cliff: a dry foot column from which the ground rises at least 4 m over the next 2 m and 8 m
 * over the next 4 m, along one of the 8 directions whose dot with (0.55, 0.35) is positive (the
 * face lit by the default sun), the same 2 and 4 m to either side along the wall, with bedrock
 * behind the middle of that rise. The eye looks along that direction from 16, 20, 24, 28 or 34 m
 * before the foot (the first that works), 2.12 m over the ground there (or over the foot, if
 * higher): its feet clear of the ground around by 0.5 m, the ground under its line of sight to
 * the face, and the wall's top (the highest ground up to 16 m past the foot) at least 6° under
 * the top edge of a 60° picture aimed at the face. The nearest cliff with such a view wins. False
 * when there is none. Generates the chunks it reads (walk_cliff.c). */
bool game_find_cliff_view(terrain_world *world, double x, double z, double radius, game_cliff_view *out);

#define GAME_WALKER_HISTORY 64

/* Plain data; the fields above `private` are the progress a program may show. */
typedef struct game_walker {
    int index;                        /* the waypoint being walked to; count once all are reached */
    int frames;                       /* steps taken */
    double time;                      /* seconds walked (frames the player waited not counted) */
    double walked;                    /* path length covered, horizontally, metres */
    double from_start;                /* straight-line horizontal distance from the start, metres */
    bool done;                        /* arrived, or gave up (stuck) */
    bool stuck;                       /* gave up: a leg ran out of time */
    int stalls;                       /* times a stall was detected (jump and sidestep) */
    int shots;                        /* `shot` waypoints reached */
    bool shot_due;                    /* holding still at a `shot` waypoint: game_walker_resume */

    /* private */
    const game_walk *walk;            /* borrowed: must outlive the walker */
    double origin[3];                 /* the feet at the start */
    float origin_yaw;
    double last[2];                   /* position at the previous step */
    float last_dt;                    /* the dt the previous step was given */
    double leg_start, leg_limit;      /* seconds */
    double fly_height;                /* for a flying leg without y= */
    double detour_until;              /* sidestepping until then (seconds) */
    int leg_stalls;
    bool leg_flying_over;             /* this walking leg gave up sidestepping and flies */
    bool toggled;                     /* pressed toggle_fly on the previous step */
    struct { double time, x, y, z; } history[GAME_WALKER_HISTORY];
    int history_count, history_next;
} game_walker;

/* Starts the walk from where the player is now (position and yaw: relative and ahead walks are
 * measured from there). `walk` must stay alive and unchanged while the walker uses it. */
void game_walker_start(game_walker *walker, const game_walk *walk, const game_player *player);
/* This frame's actions for the player, who is about to be updated with the same dt. Updates the
 * progress first (waypoints reached, distance, the time limit); once done, returns no input. */
input_actions game_walker_step(game_walker *walker, const game_player *player, float dt);
bool game_walker_done(const game_walker *walker);
/* After a `shot` waypoint: the walker returns no input (shot_due) until this, so the program can
 * turn the view, let the world settle and take the picture; the hold counts against no leg. */
void game_walker_resume(game_walker *walker, const game_player *player);

#endif
