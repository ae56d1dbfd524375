/* walk_shore.c — finding a look out over water from its shore (walk.h: game_find_shore_view), for
 * a walk's `shore R` waypoints (issue 12's tour stop over water; issue 15).
 *
 * Water is a material layer of the stacks (000 §3.1), so the stacks say where it is:
 * terrain_world_water_at is true on a column whose highest non-air layer is water. A shore is a dry
 * column beside such a column. From it the view is worth a picture when it looks out over water,
 * not along a strip of it: of 16 directions, the one with the most water samples before any
 * ground rises above the eye, at least SHORE_MIN_OPEN metres of it. The search walks square rings
 * outwards from the centre and stops once a ring lies wholly farther than the best shore found,
 * so only the shores nearer than the answer are tried. */
#include "game/walk.h"
#include "game/walk_view.h"

#include "terrain/terrain.h"

#include <math.h>

#define SHORE_GRID 2.0                /* metres between the columns searched */
#define SHORE_DIRECTIONS 16
#define SHORE_STEP 4.0                /* metres between samples along a view */
#define SHORE_MIN_OPEN 40.0           /* metres of water a view must see: a lake, not a puddle */
#define SHORE_MAX_HEIGHT 12.0f        /* dry ground at most this far above the water: a shore, not
                                         a mountain with a lake in the distance */
#define SHORE_EYE_HEIGHT 1.62         /* game_player's default eye height */
#define SHORE_PITCH_DISTANCE 25.0     /* the view looks down at the water this far out ... */
#define SHORE_MIN_PITCH 8.0           /* ... but at least this many degrees down (the near water fills
                                         the lower part of the picture) */
#define SHORE_MAX_PITCH 25.0          /* and at most (sky stays in a 60° field: the horizon is 25° up) */
#define SHORE_PI 3.14159265358979323846

/* Metres of water along (dx, dz) from the eye, counted every SHORE_STEP out to the view distance,
 * up to the first ground that rises above the eye (the view ends there). */
static double shore_open_water(terrain_world *world, const double eye[3], double dx, double dz) {
    double open = 0.0;
    for (double d = SHORE_STEP; d <= GAME_SHORE_VIEW_DISTANCE; d += SHORE_STEP) {
        double x = eye[0] + dx * d, z = eye[2] + dz * d;
        if (terrain_world_water_at(world, x, z, NULL, NULL)) open += SHORE_STEP;
        else if ((double)terrain_world_top(world, x, z) > eye[1]) break;
    }
    return open;
}

/* The view from dry column (x, z) beside water whose surface is `surface`, whose direction from
 * it is (wx, wz): false when no direction sees SHORE_MIN_OPEN of water. */
static bool shore_view_from(terrain_world *world, double x, double z, float surface, double wx, double wz,
                            game_shore_view *out) {
    float ground = terrain_world_top(world, x, z);
    if (ground < surface || ground > surface + SHORE_MAX_HEIGHT) return false;
    double eye[3] = { x, (double)ground + SHORE_EYE_HEIGHT, z };
    double best_open = 0.0, best_turn = INFINITY, best_dx = 0.0, best_dz = 0.0;
    for (int k = 0; k < SHORE_DIRECTIONS; k++) {
        double angle = 2.0 * SHORE_PI * k / SHORE_DIRECTIONS, dx = cos(angle), dz = sin(angle);
        double open = shore_open_water(world, eye, dx, dz);
        double turn = acos(fmax(fmin(dx * wx + dz * wz, 1.0), -1.0));   /* from the water beside */
        if (open > best_open || (open == best_open && turn < best_turn))
            best_open = open, best_turn = turn, best_dx = dx, best_dz = dz;
    }
    if (best_open < SHORE_MIN_OPEN) return false;
    out->eye[0] = eye[0], out->eye[1] = eye[1], out->eye[2] = eye[2];
    out->water[0] = x + wx * SHORE_GRID, out->water[1] = surface, out->water[2] = z + wz * SHORE_GRID;
    out->yaw = game__look_yaw(best_dx, best_dz);
    double down = atan2(eye[1] - (double)surface, SHORE_PITCH_DISTANCE) * (180.0 / SHORE_PI);
    out->pitch = -(float)fmin(fmax(down, SHORE_MIN_PITCH), SHORE_MAX_PITCH);
    out->open = (float)best_open;
    return true;
}

/* Whether grid point (x, z) is a dry column with water beside it (at a grid step along an axis);
 * then the view from it. */
static bool shore_at(terrain_world *world, double x, double z, game_shore_view *out) {
    static const int beside[4][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 } };
    if (terrain_world_water_at(world, x, z, NULL, NULL)) return false;
    for (int n = 0; n < 4; n++) {
        float surface;
        double wx = beside[n][0], wz = beside[n][1];
        if (!terrain_world_water_at(world, x + wx * SHORE_GRID, z + wz * SHORE_GRID, &surface, NULL)) continue;
        if (shore_view_from(world, x, z, surface, wx, wz, out)) return true;
    }
    return false;
}

bool game_find_shore_view(terrain_world *world, double centre_x, double centre_z, double radius,
                          game_shore_view *out) {
    if (!(radius >= 0.0)) return false;
    int cells = (int)ceil(radius / SHORE_GRID);
    bool found = false;
    double best_distance = INFINITY;
    for (int ring = 0; ring <= cells; ring++) {
        if ((double)ring * SHORE_GRID > best_distance) break;   /* every point of it is farther */
        for (int k = -ring; k <= ring; k++)
            for (int i = -ring; i <= ring; i++) {
                if (i != -ring && i != ring && k != -ring && k != ring) continue;   /* the ring only */
                double distance = hypot(i * SHORE_GRID, k * SHORE_GRID);
                if (distance > radius || distance >= best_distance) continue;
                game_shore_view view;
                if (!shore_at(world, centre_x + i * SHORE_GRID, centre_z + k * SHORE_GRID, &view)) continue;
                *out = view, best_distance = distance, found = true;
            }
    }
    return found;
}
