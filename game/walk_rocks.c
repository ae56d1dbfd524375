/* walk_rocks.c — finding a look at a pile of rocks (walk.h: game_find_rocks_view), for a walk's
 * `rocks R` waypoints (issue 12's tour: "once they exist, rocks, grass and water").
 *
 * Rock piles are layers of the stacks (000 §5: talus at cliff feet, scree on steep slopes, stones
 * at lakes' waterlines), which the rocks module fills with rocks. A column is rocky when its top
 * solid layer is rocks, at least ROCKS_MIN_THICKNESS thick, with no water over it (a drowned
 * pile shows as water); a pile is a rocky column with enough rocky columns around it that one
 * column's sliver does not count. The view stands on the side the default sun lights (the
 * terrain renderer's sun is towards (−0.55, 0.55, −0.35), so faces turned to −x/−z are lit: the
 * camera looks towards +x/+z), above the pile, looking down at it; the eye must be in the air and
 * the ground between it and the pile under the line of sight. A view is better when the ground
 * behind the pile stays out of the picture's top (a talus pile photographed against its cliff is
 * a wall with rocks at its foot): the nearest pile with such a view wins, else the nearest with
 * any. The search walks square rings outwards from the centre, as the shore finder does, and
 * stops once a ring lies wholly farther than the nearest pile with an open view. */
#include "game/walk.h"
#include "game/walk_view.h"

#include "terrain/terrain.h"

#include <math.h>

#define ROCKS_MIN_THICKNESS 1.0f      /* metres of rock layer: a pile, not a scatter of stones */
#define ROCKS_PILE_HALF 2             /* the pile test looks at the 5 × 5 columns around */
#define ROCKS_PILE_MIN_COLUMNS 12     /* ... of which this many are rocky */
#define ROCKS_DIRECTIONS 8
#define ROCKS_EYE_HEIGHT 1.62         /* game_player's default eye height: its feet fly under the eye */
#define ROCKS_FEET_CLEARANCE 0.5      /* the feet at least this far over the ground under the eye */
#define ROCKS_SIGHT_STEP 0.5          /* metres between samples of the line of sight */
#define ROCKS_SIGHT_END 1.5           /* the line's last metres lie over the pile itself */
#define ROCKS_SIGHT_MARGIN 0.25       /* the ground under the line by at least this */
#define ROCKS_BEHIND_DISTANCE 48.0    /* the ground behind the pile, sampled out to this: nearer
                                         than that, ground in the picture's top is a wall */
#define ROCKS_BEHIND_STEP 2.0
#define ROCKS_HALF_FOV 30.0           /* degrees: the world program's 60° vertical field */
#define ROCKS_BEHIND_ROOM 2.0         /* degrees under the picture's top edge the ground stays */
#define ROCKS_BEHIND_RAYS 5           /* the ground behind is looked at along this many rays, */
#define ROCKS_BEHIND_RAY_ANGLE 18.0   /* degrees apart (the picture is 92° wide at 16:9) */
#define ROCKS_PI 3.14159265358979323846

/* Distances and heights of the eye tried, in order: 6–9 m from the pile's centre, 3–5 m over its
 * top (a pitch of 18° to 40° down). */
static const double rocks_backs[] = { 8.0, 6.5, 9.0 };
static const double rocks_heights[] = { 3.5, 4.5, 3.0, 5.0 };

static int64_t rocks_floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

/* Whether the column holding world (x, z) is rocky (above); *top is then its ground. */
static bool rocks_column(terrain_world *world, double x, double z, float *top) {
    int64_t gx = (int64_t)floor(x / TERRAIN_COLUMN_SIZE), gz = (int64_t)floor(z / TERRAIN_COLUMN_SIZE);
    terrain_chunk_coord chunk = { rocks_floor_div(gx, TERRAIN_CHUNK_COLUMNS), rocks_floor_div(gz, TERRAIN_CHUNK_COLUMNS) };
    const terrain_stacks *stacks = terrain_world_stacks(world, chunk);
    if (!stacks) return false;
    terrain_layer layers[128];
    int count = terrain_stacks_column(stacks, (int)(gx - chunk.x * TERRAIN_CHUNK_COLUMNS),
                                      (int)(gz - chunk.z * TERRAIN_CHUNK_COLUMNS), layers, 128);
    if (count <= 0 || count > 128) return false;
    int highest = count - 1;
    while (highest >= 0 && layers[highest].material == TERRAIN_AIR) highest--;
    if (highest < 0 || layers[highest].material != TERRAIN_ROCKS || layers[highest].thickness < ROCKS_MIN_THICKNESS)
        return false;
    float y = TERRAIN_FLOOR_Y;
    for (int i = 0; i <= highest; i++) y += layers[i].thickness;
    *top = y;
    return true;
}

typedef struct rocks_pile { double centre[3]; float top; } rocks_pile;

/* Column (x, z) is rocky and so are at least ROCKS_PILE_MIN_COLUMNS of the 5 × 5 around it
 * (itself included): the pile's centre is their centroid at their mean height, its top their
 * highest. */
static bool rocks_pile_at(terrain_world *world, double x, double z, rocks_pile *out) {
    float top;
    if (!rocks_column(world, x, z, &top)) return false;
    int rocky = 0;
    double sum_x = 0.0, sum_z = 0.0, sum_y = 0.0;
    float highest = -INFINITY;
    for (int k = -ROCKS_PILE_HALF; k <= ROCKS_PILE_HALF; k++)
        for (int i = -ROCKS_PILE_HALF; i <= ROCKS_PILE_HALF; i++) {
            double px = x + i * TERRAIN_COLUMN_SIZE, pz = z + k * TERRAIN_COLUMN_SIZE;
            if (!rocks_column(world, px, pz, &top)) continue;
            rocky++, sum_x += px, sum_z += pz, sum_y += top;
            highest = fmaxf(highest, top);
        }
    if (rocky < ROCKS_PILE_MIN_COLUMNS) return false;
    out->centre[0] = sum_x / rocky, out->centre[1] = sum_y / rocky, out->centre[2] = sum_z / rocky;
    out->top = highest;
    return true;
}

/* Whether ground along (dx, dz), from `from` metres out to ROCKS_BEHIND_DISTANCE, stays under the
 * line `limit` (rise over distance) from the eye. */
static bool rocks_ray_under(terrain_world *world, const double eye[3], double from, double dx, double dz, double limit) {
    for (double d = from; d <= ROCKS_BEHIND_DISTANCE; d += ROCKS_BEHIND_STEP) {
        double rise = (double)terrain_world_top(world, eye[0] + dx * d, eye[2] + dz * d) - eye[1];
        if (rise > d * limit) return false;
    }
    return true;
}

/* Open behind the pile: along the view (dx, dz) and rays to either side of it across the picture,
 * from the pile out to ROCKS_BEHIND_DISTANCE, no ground rises within ROCKS_BEHIND_ROOM degrees of
 * the picture's top edge (pitch_down degrees under the horizon plus half the field) on most of
 * them: a cliff may stand to one side (talus lies at cliff feet), not across the whole view. */
static bool rocks_open_behind(terrain_world *world, const double eye[3], double back, double dx, double dz,
                              double pitch_down) {
    double limit = tan((ROCKS_HALF_FOV - pitch_down - ROCKS_BEHIND_ROOM) * (ROCKS_PI / 180.0));
    int open = 0;
    for (int r = -ROCKS_BEHIND_RAYS / 2; r <= ROCKS_BEHIND_RAYS / 2; r++) {
        double turn = r * ROCKS_BEHIND_RAY_ANGLE * (ROCKS_PI / 180.0), c = cos(turn), s = sin(turn);
        open += rocks_ray_under(world, eye, back + ROCKS_BEHIND_STEP, dx * c - dz * s, dx * s + dz * c, limit);
    }
    return open > ROCKS_BEHIND_RAYS / 2;
}

/* The view of `pile` from the lit side: of the directions whose view has a positive dot with the
 * sunlight's horizontal (0.55, 0.35), the most lit first, the first eye position that is clear
 * and sees the pile: the first such view open behind the pile (out->open), else the first. */
static bool rocks_view_of(terrain_world *world, const rocks_pile *pile, game_rocks_view *out) {
    int order[ROCKS_DIRECTIONS];
    const int lit = game__sunlit_directions(ROCKS_DIRECTIONS, order);
    const double target[3] = { pile->centre[0], pile->centre[1], pile->centre[2] };
    bool found = false;
    for (int n = 0; n < lit; n++) {
        double angle = 2.0 * ROCKS_PI * order[n] / ROCKS_DIRECTIONS, dx = cos(angle), dz = sin(angle);
        for (size_t b = 0; b < sizeof rocks_backs / sizeof rocks_backs[0]; b++)
            for (size_t h = 0; h < sizeof rocks_heights / sizeof rocks_heights[0]; h++) {
                double back = rocks_backs[b];
                double eye[3] = { target[0] - dx * back, (double)pile->top + rocks_heights[h], target[2] - dz * back };
                /* the line's last metres lie over the pile itself */
                double until = hypot(target[0] - eye[0], target[2] - eye[2]) - ROCKS_SIGHT_END;
                if (!game__eye_clear(world, eye, ROCKS_EYE_HEIGHT + ROCKS_FEET_CLEARANCE) ||
                    !game__clear_sight(world, eye, target, until, ROCKS_SIGHT_STEP, ROCKS_SIGHT_MARGIN))
                    continue;
                double down = atan2(eye[1] - target[1], back) * (180.0 / ROCKS_PI);
                bool open = rocks_open_behind(world, eye, back, dx, dz, down);
                if (found && !open) continue;
                for (int a = 0; a < 3; a++) out->eye[a] = eye[a], out->pile[a] = target[a];
                out->top = pile->top;
                out->yaw = game__look_yaw(dx, dz);
                out->pitch = -(float)down;
                out->open = open;
                found = true;
                if (open) return true;
            }
    }
    return found;
}

bool game_find_rocks_view(terrain_world *world, double x, double z, double radius, game_rocks_view *out) {
    if (!(radius >= 0.0)) return false;
    /* column centres, so each grid point reads one column */
    double centre_x = floor(x / TERRAIN_COLUMN_SIZE) * TERRAIN_COLUMN_SIZE + 0.5 * TERRAIN_COLUMN_SIZE;
    double centre_z = floor(z / TERRAIN_COLUMN_SIZE) * TERRAIN_COLUMN_SIZE + 0.5 * TERRAIN_COLUMN_SIZE;
    int cells = (int)ceil(radius / TERRAIN_COLUMN_SIZE);
    double best_open = INFINITY, best_any = INFINITY;   /* distances of the nearest views found */
    game_rocks_view any = { 0 };
    for (int ring = 0; ring <= cells; ring++) {
        /* every point of it is farther (the grid's centre is within 0.71 m of (x, z)) */
        if ((double)(ring - 1) * TERRAIN_COLUMN_SIZE > best_open) break;
        for (int k = -ring; k <= ring; k++)
            for (int i = -ring; i <= ring; i++) {
                if (i != -ring && i != ring && k != -ring && k != ring) continue;   /* the ring only */
                double px = centre_x + i * TERRAIN_COLUMN_SIZE, pz = centre_z + k * TERRAIN_COLUMN_SIZE;
                double distance = hypot(px - x, pz - z);
                if (distance > radius || distance >= best_open) continue;
                rocks_pile pile;
                game_rocks_view view;
                if (!rocks_pile_at(world, px, pz, &pile) || !rocks_view_of(world, &pile, &view)) continue;
                if (view.open) *out = view, best_open = distance;
                else if (distance < best_any) any = view, best_any = distance;
            }
    }
    if (best_open < INFINITY) return true;
    if (best_any < INFINITY) *out = any;
    return best_any < INFINITY;
}
