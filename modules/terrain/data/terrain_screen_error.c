/* terrain_screen_error.c — levels of detail chosen by a screen-space error (terrain.h, "detail
 * from a screen-space error"; README, same title).
 *
 * A displacement of ε metres across the view direction at distance d projects to ε/d radians,
 * and a radian at the centre of a perspective view is H / (2·tan(θ/2)) pixels: the pixel error
 * is ε·H / (2·d·tan(θ/2)). Setting it to the target τ gives the distance d = ε·K beyond which a
 * level whose geometric error is ε may be drawn, K = H / (2·τ·tan(θ/2)). (Off the centre the
 * projection's scale only grows by 1/cos² of the angle to the axis, ≤ 1.33 at the corners of a
 * 16:9 60° view: we take the centre's, as the usual screen-space-error metrics do.)
 *
 * The errors ε are the mean distance between a level's surface and the finest surface there is,
 * measured on generated terrain (seeds 1 and 7, 256 m squares; README):
 *   - a mesh-chunk level L samples f every h = 2^L m and marching cubes interpolates linearly
 *     across a cell. Mean distance of its vertices to f = 0 (the level-0 surface, itself within
 *     0.004 m): 0.08 m at h = 2, 0.40 at 4, 0.96 at 8. Below the scale where the kernel (a 2 m
 *     cube) smooths f, the surface is locally a curve of radius R and a chord of length h misses
 *     it by the sagitta h²/(8R): R ≈ 6.25 m fits (0.08 and 0.32 m); above it the field has detail
 *     at every scale and the error is a fixed share of the cell, h/8 (1.0 m at 8 m). The two
 *     meet at h = 6.25 m: ε = h/8 · min(1, h / 6.25 m).
 *   - a clipmap level of spacing s holds G with the octaves that s carries and draws it as
 *     triangles: mean vertical distance to G at 1 m was 1.0 m at s = 4, 1.8 at 8, 5.3 at 16, 8.2 at
 *     32, 14.9 at 64 (then less: the coarse levels have one octave left): ε = s/4. Vertical, not
 *     along the normal: a grazing view (the one that matters from the ground) sees it whole.
 * Means, not maxima: the maxima are single terrace risers and thin spurs (a 2 m feature a
 * 4 m cell cannot hold) that a maximum-based target would pay for everywhere.
 */
#include "terrain/data/terrain_data_internal.h"

#include <math.h>

double terrain_screen_error_scale(int viewport_height, float fov_y, float pixel_error) {
    if (!(pixel_error > 0.0f)) return 0.0;
    double height = viewport_height > 0 ? (double)viewport_height : (double)TERRAIN_SCREEN_DEFAULT_HEIGHT;
    double fov = fov_y > 0.0f ? (double)fov_y : 60.0 * 3.14159265358979323846 / 180.0;
    return height / (2.0 * (double)pixel_error * tan(0.5 * fov));
}

double terrain_chunk_level_error(int level) {
    double cell = ldexp((double)TERRAIN_COLUMN_SIZE, level);
    return cell / 8.0 * fmin(1.0, cell / 6.25);
}

double terrain_clipmap_spacing_error(double spacing) { return 0.25 * spacing; }

double terrain_rings_clearance(int half_width, int levels, int level) {
    double chunk = (double)TERRAIN_MESH_CELLS * (double)TERRAIN_COLUMN_SIZE;
    return (double)half_width * ldexp(chunk, level) - 0.5 * ldexp(chunk, levels - 1);
}

static bool rings_meet(int half_width, int levels, double scale) {
    for (int level = 0; level + 1 < levels; level++)
        if (terrain_rings_clearance(half_width, levels, level) < terrain_chunk_level_error(level + 1) * scale) return false;
    return terrain_rings_clearance(half_width, levels, levels - 1) >= (double)TERRAIN_GROUND_ERROR * scale;
}

int terrain_rings_half_width(int levels, double scale) {
    if (levels < 1) levels = 1;
    int step = levels > 1 ? 2 : 1;            /* rings align with coarser chunks (terrain_ecs_stream) */
    int half_width = step;
    while (half_width + step <= 64 && !rings_meet(half_width, levels, scale)) half_width += step;
    return half_width;
}
