/* walk_cliff.c — finding a look at a cliff (walk.h: game_find_cliff_view), for a walk's `cliff R`
 * waypoints: the tour's stop that shows the fractured blocks on steep bedrock walls (paper 003,
 * rocks_cliffs).
 *
 * A cliff here is what the blocks' presence asks for, seen from the columns' tops: a foot column
 * on dry ground from which the ground rises steeply (CLIFF_RISE over the next 2 m, steeper than
 * 63°) and at least CLIFF_MIN_HEIGHT over the next 6 m, the same along CLIFF_HALF_WIDTH metres to
 * either side (a wall, not a spike), with bedrock behind its middle. The face must be lit: it is
 * looked at along one of 8 directions whose dot with the sunlight's horizontal (0.55, 0.35) is
 * positive (the terrain renderer's sun is towards (−0.55, 0.55, −0.35)), the most lit first. The
 * eye stands back from the foot, over the ground, and far enough that the wall's top stays
 * CLIFF_SKY_ROOM degrees under the picture's top edge: a cliff against the sky, never a picture
 * of a wall (issue 12). The search walks square rings of columns outwards, as the others do, and
 * the nearest cliff with a view wins. */
#include "game/walk.h"
#include "game/walk_view.h"

#include "terrain/terrain.h"

#include <math.h>

#define CLIFF_STEP 2.0                /* metres between the columns searched */
#define CLIFF_RISE 6.0                /* metres the ground rises over the 2 m past the foot */
#define CLIFF_MIN_HEIGHT 10.0         /* metres it rises over the 6 m past the foot */
#define CLIFF_HALF_WIDTH 4.0          /* the rise holds 2 and 4 m to either side too */
#define CLIFF_FACE_STEP 2.0           /* the face is looked at every 2 m up, */
#define CLIFF_FACE_TOP 8.0            /* to this over the foot, */
#define CLIFF_FACE_REACH 8.0          /* found within this past the foot, */
#define CLIFF_FACE_STEEPNESS 0.5      /* and steep there: |∇f·ŷ| < this |∇f| */
#define CLIFF_DIRECTIONS 8
#define CLIFF_EYE_HEIGHT 1.62         /* game_player's default eye height */
#define CLIFF_FEET_CLEARANCE 0.5      /* the feet over the ground under the eye by this */
#define CLIFF_LOOK_HEIGHT 6.0         /* the point looked at: up to this over the foot */
#define CLIFF_TOP_REACH 16.0          /* the wall's top: the highest ground this far past the foot */
#define CLIFF_HALF_FOV 30.0           /* degrees: the world program's 60° vertical field */
#define CLIFF_SKY_ROOM 6.0            /* degrees of sky at least over the wall's top */
#define CLIFF_SIGHT_STEP 0.5
#define CLIFF_SIGHT_MARGIN 0.25       /* the ground under the line of sight by this */
#define CLIFF_PI 3.14159265358979323846

static const double cliff_backs[] = { 16.0, 20.0, 24.0, 28.0, 34.0 };   /* eye from the foot, tried in order */

/* Steep from (x, z) along (dx, dz): the rise over 2 m and over 6 m. */
static bool cliff_rises(terrain_world *world, double x, double z, double dx, double dz, float foot) {
    return (double)terrain_world_top(world, x + 2.0 * dx, z + 2.0 * dz) - foot >= CLIFF_RISE &&
           (double)terrain_world_top(world, x + 6.0 * dx, z + 6.0 * dz) - foot >= CLIFF_MIN_HEIGHT;
}

/* The face itself steep where blocks go (rocks_cliffs' presence: the field's gradient within 30°
 * of level) at every CLIFF_FACE_STEP metres up to CLIFF_FACE_TOP over the foot: the columns' tops
 * rise as steeply over a stair of ledges or under an overhang, which carry no blocks. */
static bool cliff_face_steep(terrain_world *world, double x, double z, double dx, double dz, float foot) {
    for (double h = CLIFF_FACE_STEP; h <= CLIFF_FACE_TOP; h += CLIFF_FACE_STEP) {
        double y = (double)foot + h, s = 0.0;
        while (s <= CLIFF_FACE_REACH && terrain_field_base_at(world, x + s * dx, y, z + s * dz, 0) < 0.0f) s += 0.25;
        if (s > CLIFF_FACE_REACH) return false;
        const double p[3] = { x + s * dx, y, z + s * dz };
        float g[3];
        for (int a = 0; a < 3; a++) {
            double lo[3] = { p[0], p[1], p[2] }, hi[3] = { p[0], p[1], p[2] };
            lo[a] -= 0.25, hi[a] += 0.25;
            g[a] = terrain_field_base_at(world, hi[0], hi[1], hi[2], 0) - terrain_field_base_at(world, lo[0], lo[1], lo[2], 0);
        }
        float length = sqrtf(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (!(length > 0.0f && fabsf(g[1]) < CLIFF_FACE_STEEPNESS * length)) return false;
    }
    return true;
}

/* A cliff at foot column (x, z) facing back along (dx, dz) (above); its height over 6 m in *height. */
static bool cliff_at(terrain_world *world, double x, double z, double dx, double dz, float *foot, double *height) {
    float surface, ground;
    if (terrain_world_water_at(world, x, z, &surface, &ground)) return false;
    *foot = terrain_world_top(world, x, z);
    if (!cliff_rises(world, x, z, dx, dz, *foot)) return false;
    for (double side = -CLIFF_HALF_WIDTH; side <= CLIFF_HALF_WIDTH; side += CLIFF_STEP) {
        if (side == 0.0) continue;
        double sx = x - dz * side, sz = z + dx * side;   /* (−dz, dx) runs along the wall */
        if (!cliff_rises(world, sx, sz, dx, dz, terrain_world_top(world, sx, sz))) return false;
    }
    if (!cliff_face_steep(world, x, z, dx, dz, *foot)) return false;
    *height = (double)terrain_world_top(world, x + 6.0 * dx, z + 6.0 * dz) - *foot;
    return terrain_world_material_at(world, x + 6.0 * dx, *foot + 0.5 * *height, z + 6.0 * dz) == TERRAIN_BEDROCK;
}

/* The wall's top, in degrees over the horizon from the eye `back` metres before the foot. */
static double cliff_top_angle(terrain_world *world, double x, double z, double dx, double dz, const double eye[3],
                              double back) {
    double best = -90.0;
    for (double s = CLIFF_STEP; s <= CLIFF_TOP_REACH; s += CLIFF_STEP) {
        double rise = (double)terrain_world_top(world, x + s * dx, z + s * dz) - eye[1];
        best = fmax(best, atan2(rise, back + s) * (180.0 / CLIFF_PI));
    }
    return best;
}

/* The view of the cliff at foot (x, z) along (dx, dz): the first eye distance whose eye is clear,
 * sees the face and keeps the wall's top under the picture's top edge. */
static bool cliff_view_at(terrain_world *world, double x, double z, double dx, double dz, game_cliff_view *out) {
    float foot;
    double height;
    if (!cliff_at(world, x, z, dx, dz, &foot, &height)) return false;
    const double target[3] = { x + dx, (double)foot + fmin(0.5 * height, CLIFF_LOOK_HEIGHT), z + dz };
    for (size_t b = 0; b < sizeof cliff_backs / sizeof cliff_backs[0]; b++) {
        double back = cliff_backs[b];
        double ex = x - dx * back, ez = z - dz * back;
        double ground = fmax((double)terrain_world_top(world, ex, ez), (double)foot);
        double eye[3] = { ex, ground + CLIFF_EYE_HEIGHT + CLIFF_FEET_CLEARANCE, ez };
        if (!game__eye_clear(world, eye, CLIFF_EYE_HEIGHT + CLIFF_FEET_CLEARANCE) ||
            !game__clear_sight(world, eye, target, back, CLIFF_SIGHT_STEP, CLIFF_SIGHT_MARGIN))
            continue;
        double horizontal = back + 1.0;   /* the target is 1 m past the foot */
        double pitch = atan2(target[1] - eye[1], horizontal) * (180.0 / CLIFF_PI);
        if (cliff_top_angle(world, x, z, dx, dz, eye, back) - pitch > CLIFF_HALF_FOV - CLIFF_SKY_ROOM) continue;
        for (int a = 0; a < 3; a++) out->eye[a] = eye[a], out->face[a] = target[a];
        out->height = (float)height;
        out->yaw = game__look_yaw(dx, dz);
        out->pitch = (float)pitch;
        return true;
    }
    return false;
}

bool game_find_cliff_view(terrain_world *world, double x, double z, double radius, game_cliff_view *out) {
    if (!(radius >= 0.0)) return false;
    int order[CLIFF_DIRECTIONS];
    int lit = game__sunlit_directions(CLIFF_DIRECTIONS, order);
    double centre_x = (floor(x / CLIFF_STEP) + 0.5) * CLIFF_STEP, centre_z = (floor(z / CLIFF_STEP) + 0.5) * CLIFF_STEP;
    int cells = (int)ceil(radius / CLIFF_STEP);
    double best = INFINITY;
    for (int ring = 0; ring <= cells; ring++) {
        if ((double)(ring - 1) * CLIFF_STEP > best) break;   /* every point of it is farther */
        for (int k = -ring; k <= ring; k++)
            for (int i = -ring; i <= ring; i++) {
                if (i != -ring && i != ring && k != -ring && k != ring) continue;   /* the ring only */
                double px = centre_x + i * CLIFF_STEP, pz = centre_z + k * CLIFF_STEP;
                double distance = hypot(px - x, pz - z);
                if (distance > radius || distance >= best) continue;
                for (int n = 0; n < lit; n++) {
                    double angle = 2.0 * CLIFF_PI * order[n] / CLIFF_DIRECTIONS;
                    game_cliff_view view;
                    if (!cliff_view_at(world, px, pz, cos(angle), sin(angle), &view)) continue;
                    *out = view, best = distance;
                    break;
                }
            }
    }
    return best < INFINITY;
}
