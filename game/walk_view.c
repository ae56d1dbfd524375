/* walk_view.c — what the walk's view finders share (walk_view.h). */
#include "game/walk_view.h"

#include "terrain/terrain.h"

#include <math.h>

int game__sunlit_directions(int count, int *order) {
    const double light_x = 0.55, light_z = 0.35;
    double dots[64];
    int lit = 0;
    if (count > 64) count = 64;
    for (int d = 0; d < count; d++) {
        double angle = 2.0 * GAME__VIEW_PI * d / count;
        dots[d] = cos(angle) * light_x + sin(angle) * light_z;
        if (dots[d] <= 0.0) continue;
        int at = lit++;
        while (at > 0 && dots[order[at - 1]] < dots[d]) order[at] = order[at - 1], at--;
        order[at] = d;
    }
    return lit;
}

bool game__eye_clear(terrain_world *world, const double eye[3], double feet_below) {
    double feet = eye[1] - feet_below;
    for (int k = -1; k <= 1; k++)
        for (int i = -1; i <= 1; i++)
            if ((double)terrain_world_top(world, eye[0] + i, eye[2] + k) > feet) return false;
    return true;
}

bool game__clear_sight(terrain_world *world, const double eye[3], const double target[3], double until, double step,
                       double margin) {
    double dx = target[0] - eye[0], dy = target[1] - eye[1], dz = target[2] - eye[2];
    double horizontal = hypot(dx, dz);
    for (double d = step; d < until; d += step) {
        double t = d / horizontal;
        if ((double)terrain_world_top(world, eye[0] + dx * t, eye[2] + dz * t) > eye[1] + dy * t - margin) return false;
    }
    return true;
}

float game__look_yaw(double dx, double dz) {
    float yaw = (float)(atan2(-dx, dz) * (180.0 / GAME__VIEW_PI));
    return yaw < 0.0f ? yaw + 360.0f : yaw;
}
