/* walk_view.h — what the walk's view finders share (walk_cliff.c, walk_rocks.c, walk_shore.c):
 * the directions the sun lights, an eye clear of the ground, a line of sight over the ground,
 * and --look's yaw of a direction. Private to game/.
 */
#ifndef GAME_WALK_VIEW_H
#define GAME_WALK_VIEW_H

#include <stdbool.h>

typedef struct terrain_world terrain_world;

#define GAME__VIEW_PI 3.14159265358979323846

/* Of `count` directions 2π·d/count (d = 0 … count − 1, as (cos, sin) in (x, z)), those whose dot
 * with the sunlight's horizontal (0.55, 0.35) is positive, the most lit first, into order (count
 * entries at most); returns how many. The terrain renderer's sun is towards (−0.55, 0.55, −0.35),
 * so a view along them looks at lit faces. */
int game__sunlit_directions(int count, int *order);

/* The eye is in the air: the feet `feet_below` metres under it are over the ground of the 3 × 3
 * columns around, so the player flies there without touching it. */
bool game__eye_clear(terrain_world *world, const double eye[3], double feet_below);

/* The ground stays `margin` metres under the line from the eye towards the target, sampled every
 * `step` metres of horizontal distance from the eye, short of `until`. */
bool game__clear_sight(terrain_world *world, const double eye[3], const double target[3], double until, double step,
                       double margin);

/* --look's yaw in degrees [0, 360) of a view along (dx, dz): yaw 0 = +z, 90 = −x, so the view is
 * (−sin yaw, cos yaw). */
float game__look_yaw(double dx, double dz);

#endif
