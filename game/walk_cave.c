/* walk_cave.c — finding a look into a cave mouth or under an arch (walk.h: game_find_cave_view),
 * and turning a walk's `cave R` waypoints into flights to such a view (game_walk_resolve_caves).
 *
 * The stacks say where the terrain has a roof: a column whose layers hold an air gap with solid
 * ground below it and solid above it is sheltered at the gap's floor (000 §3.1: overhangs, arches
 * and caves are air layers between material layers). A sheltered column is a place to look into
 * when a walkable path leads out from it at the floor's height: stepping along one of eight
 * directions, every column stays sheltered at that floor until one is open (its ground within a
 * few metres of the floor, nothing above it). The view then stands farther out along the same
 * direction, on open ground, far enough back that the roof's top stays inside the picture (so sky
 * shows over it, with 60° of vertical field), and with nothing solid on the
 * line of sight to the mouth (the field is negative all along it). Of all candidates the deepest
 * shelter wins (a cave over a ledge), then the nearest to the centre of the search. */
#include "game/walk.h"

#include "core/core.h"
#include "terrain/terrain.h"

#include <math.h>
#include <string.h>

#define CAVE_GRID 2.0                 /* metres between the columns searched */
#define CAVE_MIN_GAP 3.0f             /* a gap a player stands in, clear of the kernel's rounding */
#define CAVE_MIN_ROOF 3.0f            /* solid metres over the gap: thinner slabs the field (σ = 1 m)
                                         rounds away (a 1 m slab fills half the kernel: f = 0) */
#define CAVE_MIN_DEPTH 6.0            /* sheltered metres before the open ground: a cave, not a ledge */
#define CAVE_MAX_ROOF 40.0f           /* roof top above the floor, at most: sky must stay in view */
#define CAVE_MAX_DEPTH 24.0           /* metres searched from the sheltered column to open ground */
#define CAVE_FLOOR_TOLERANCE 2.5f     /* open ground outside within this of the floor */
#define CAVE_MIN_BACK 6.0             /* the view stands at least this far out of the mouth */
#define CAVE_MAX_BACK 40.0
#define CAVE_TOP_ANGLE 0.45          /* radians over the view's centre the roof may reach: 25.8°,
                                         inside a 60° field's top edge, so sky shows over it */
#define CAVE_EYE_HEIGHT 1.62          /* game_player's default eye height */
#define CAVE_PI 3.14159265358979323846

/* A column's gap: the lowest air layer with solid ground under it and solid over it, above the sea. */
typedef struct cave_gap { float floor, ceiling, roof_top; } cave_gap;

static bool cave_solid(terrain_material m) { return m == TERRAIN_BEDROCK || m == TERRAIN_SAND || m == TERRAIN_ROCKS; }

static int64_t cave_floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

/* The layers of the column holding world point (x, z); returns how many (0 on failure). */
static int cave_column(terrain_world *world, double x, double z, terrain_layer *layers, int capacity) {
    int64_t gx = (int64_t)floor(x / TERRAIN_COLUMN_SIZE), gz = (int64_t)floor(z / TERRAIN_COLUMN_SIZE);
    terrain_chunk_coord chunk = { cave_floor_div(gx, TERRAIN_CHUNK_COLUMNS), cave_floor_div(gz, TERRAIN_CHUNK_COLUMNS) };
    const terrain_stacks *stacks = terrain_world_stacks(world, chunk);
    if (!stacks) return 0;
    return terrain_stacks_column(stacks, (int)(gx - chunk.x * TERRAIN_CHUNK_COLUMNS),
                                 (int)(gz - chunk.z * TERRAIN_CHUNK_COLUMNS), layers, capacity);
}

/* The gap whose floor lies within `tolerance` of `near` (any gap above the sea when near is NaN). */
static bool cave_find_gap(const terrain_layer *layers, int count, float sea_level, float near, float tolerance,
                          cave_gap *out) {
    float y = TERRAIN_FLOOR_Y;
    for (int i = 0; i < count; i++) {
        float bottom = y, top = y + layers[i].thickness;
        y = top;
        if (layers[i].material != TERRAIN_AIR || i == 0 || i + 1 >= count) continue;
        if (!cave_solid(layers[i - 1].material) || !cave_solid(layers[i + 1].material)) continue;
        if (top - bottom < CAVE_MIN_GAP || bottom < sea_level + 0.5f) continue;
        if (!isnan(near) && fabsf(bottom - near) > tolerance) continue;
        float roof = top;
        int k = i + 1;
        while (k < count && layers[k].material != TERRAIN_AIR) roof += layers[k++].thickness;
        if (roof - top < CAVE_MIN_ROOF) continue;
        *out = (cave_gap){ bottom, top, roof };
        return true;
    }
    return false;
}

/* Open ground at about the floor's height: the column's top solid layer within the tolerance of
 * `floor`, nothing above it. Its top is *ground. */
static bool cave_open(terrain_world *world, double x, double z, float floor, float *ground) {
    float top = terrain_world_top(world, x, z);
    if (fabsf(top - floor) > CAVE_FLOOR_TOLERANCE) return false;
    terrain_layer layers[64];
    int count = cave_column(world, x, z, layers, 64);
    float y = TERRAIN_FLOOR_Y, solid_top = TERRAIN_FLOOR_Y;
    for (int i = 0; i < count; i++) {
        y += layers[i].thickness;
        if (cave_solid(layers[i].material)) solid_top = y;
    }
    *ground = top;
    return solid_top <= top + 0.01f;
}

/* Nothing solid between the eye and the target (the field negative at every half metre). */
static bool cave_clear_sight(terrain_world *world, const double eye[3], const double target[3]) {
    double d[3] = { target[0] - eye[0], target[1] - eye[1], target[2] - eye[2] };
    double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    int steps = (int)ceil(length / 0.5);
    for (int s = 0; s <= steps; s++) {
        double t = (double)s / steps;
        if (terrain_field_at(world, eye[0] + d[0] * t, eye[1] + d[1] * t, eye[2] + d[2] * t, 0) >= 0.0f) return false;
    }
    return true;
}

/* From sheltered column (x, z) with gap g, along direction (dx, dz): the view, if one exists.
 * *depth receives the sheltered metres walked before the open ground. */
static bool cave_view_along(terrain_world *world, double x, double z, const cave_gap *g, double dx, double dz,
                            game_cave_view *out, double *depth) {
    terrain_layer layers[64];
    double d = CAVE_GRID;
    float ground = 0.0f;
    for (;; d += CAVE_GRID) {
        if (d > CAVE_MAX_DEPTH) return false;
        double px = x + dx * d, pz = z + dz * d;
        if (cave_open(world, px, pz, g->floor, &ground)) break;
        cave_gap next;
        int count = cave_column(world, px, pz, layers, 64);
        if (!cave_find_gap(layers, count, -1e30f, g->floor, CAVE_FLOOR_TOLERANCE, &next)) return false;
    }
    if (d < CAVE_MIN_DEPTH) return false;
    const double target[3] = { x, g->floor + 0.5 * (g->ceiling - g->floor), z };
    for (double back = CAVE_MIN_BACK; back <= CAVE_MAX_BACK; back += CAVE_GRID) {
        double ex = x + dx * (d + back), ez = z + dz * (d + back);
        float outside;
        if (!cave_open(world, ex, ez, g->floor, &outside) && fabsf(terrain_world_top(world, ex, ez) - g->floor) > 4.0f)
            continue;
        outside = terrain_world_top(world, ex, ez);
        double eye[3] = { ex, outside + CAVE_EYE_HEIGHT, ez };
        double horizontal = d + back;
        double pitch = atan2(target[1] - eye[1], horizontal);
        /* the roof ends between the last sheltered sample and the open one: at least `back` away */
        double roof_angle = atan2(g->roof_top - eye[1], back);
        if (roof_angle - pitch > CAVE_TOP_ANGLE) continue;             /* the roof would hide the sky */
        if (!cave_clear_sight(world, eye, target)) continue;
        memcpy(out->eye, eye, sizeof eye);
        memcpy(out->mouth, target, sizeof target);
        /* looking back along −(dx, dz); --look degrees: 0 = +z, 90 = −x, so (−sin, cos) is the view */
        out->yaw = (float)atan2(dx, -dz) * (float)(180.0 / CAVE_PI);
        if (out->yaw < 0.0f) out->yaw += 360.0f;
        out->pitch = (float)(pitch * (180.0 / CAVE_PI));
        out->depth = (float)d;
        *depth = d;
        return true;
    }
    return false;
}

bool game_find_cave_view(terrain_world *world, double centre_x, double centre_z, double radius, game_cave_view *out) {
    const terrain_generation_desc *params = terrain_world_generation(world);
    float sea_level = params ? params->sea_level : 0.0f;
    static const int directions[8][2] = { { 1, 0 }, { 1, 1 }, { 0, 1 }, { -1, 1 }, { -1, 0 }, { -1, -1 }, { 0, -1 }, { 1, -1 } };
    bool found = false;
    double best_reach = INFINITY, best_depth = 0.0, best_distance = INFINITY;
    int cells = (int)ceil(radius / CAVE_GRID);
    terrain_layer layers[64];
    for (int k = -cells; k <= cells; k++)
        for (int i = -cells; i <= cells; i++) {
            double distance = hypot(i * CAVE_GRID, k * CAVE_GRID);
            if (distance > radius) continue;
            double x = centre_x + i * CAVE_GRID, z = centre_z + k * CAVE_GRID;
            cave_gap gap;
            int count = cave_column(world, x, z, layers, 64);
            if (!cave_find_gap(layers, count, sea_level, NAN, 0.0f, &gap) || gap.roof_top - gap.floor > CAVE_MAX_ROOF)
                continue;
            for (int d = 0; d < 8; d++) {
                double dx = directions[d][0], dz = directions[d][1], norm = hypot(dx, dz);
                game_cave_view view;
                double depth;
                if (!cave_view_along(world, x, z, &gap, dx / norm, dz / norm, &view, &depth)) continue;
                /* the view nearest its mouth wins (the cave fills more of the picture, the
                 * ground before it less); within a grid step of that, the deeper, then the
                 * nearer to the search's centre */
                double reach = hypot(view.eye[0] - view.mouth[0], view.eye[2] - view.mouth[2]) - depth;
                bool better = !found || reach < best_reach - CAVE_GRID ||
                              (reach < best_reach + CAVE_GRID &&
                               (depth > best_depth + CAVE_GRID ||
                                (depth > best_depth - CAVE_GRID && distance < best_distance)));
                if (better)
                    *out = view, best_reach = reach, best_depth = depth, best_distance = distance, found = true;
            }
        }
    return found;
}
