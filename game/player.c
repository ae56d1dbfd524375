/* The player controller (player.h): a capsule of sphere probes against the trilinear
 * interpolation of the terrain field sampled around it. game/README.md explains the model. */
#include "player.h"

#include "trace/trace.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#define PROBE_COUNT 5            /* spheres along the capsule's axis, bottom to top */
#define RESOLVE_ITERATIONS 4
#define SKIN 1e-4f               /* penetration below this is contact, not overlap (no jitter) */
#define SNAP_EPSILON 1e-3f       /* a gap to walkable ground below this needs no snapping */
#define GROUND_EPSILON 0.02f     /* airborne with walkable ground this close below = landed */
#define MAX_SUBSTEPS 512
#define SPAWN_FRAMES 1200
#define SPAWN_SEARCH_RADIUS 64   /* columns */

/* ---- the field around the player ------------------------------------------------------------ */

/* Samples of f on integer grid points; `lo` is the local coordinate of sample (0, 0, 0). */
typedef struct local_field {
    terrain_field field;
    float lo[3];
    double origin[3];                /* world position of local (0, 0, 0) */
    const game_player_desc *params;   /* its obstacle hooks */
} local_field;

/* f and its gradient at local point p by trilinear interpolation of the cell around p (outside
 * the grid the border cells are extended, which the margins keep from mattering). */
static float field_eval(const local_field *lf, const float p[3], float grad[3]) {
    const int n[3] = { lf->field.nx, lf->field.ny, lf->field.nz };
    int cell[3];
    float t[3];
    for (int a = 0; a < 3; a++) {
        float g = p[a] - lf->lo[a];
        float c = floorf(g);
        if (c < 0.0f) c = 0.0f;
        if (c > (float)(n[a] - 2)) c = (float)(n[a] - 2);
        cell[a] = (int)c;
        t[a] = fminf(fmaxf(g - c, 0.0f), 1.0f);
    }
    const float *v = lf->field.values;
    size_t row = (size_t)n[0], slab = (size_t)n[0] * (size_t)n[1];
    size_t base = (size_t)cell[2] * slab + (size_t)cell[1] * row + (size_t)cell[0];
    float c000 = v[base], c100 = v[base + 1];
    float c010 = v[base + row], c110 = v[base + row + 1];
    float c001 = v[base + slab], c101 = v[base + slab + 1];
    float c011 = v[base + slab + row], c111 = v[base + slab + row + 1];
    float tx = t[0], ty = t[1], tz = t[2];
    /* along x first */
    float c00 = c000 + (c100 - c000) * tx, c10 = c010 + (c110 - c010) * tx;
    float c01 = c001 + (c101 - c001) * tx, c11 = c011 + (c111 - c011) * tx;
    float c0 = c00 + (c10 - c00) * ty, c1 = c01 + (c11 - c01) * ty;
    float dx00 = c100 - c000, dx10 = c110 - c010, dx01 = c101 - c001, dx11 = c111 - c011;
    float dx0 = dx00 + (dx10 - dx00) * ty, dx1 = dx01 + (dx11 - dx01) * ty;
    grad[0] = dx0 + (dx1 - dx0) * tz;
    float dy0 = c10 - c00, dy1 = c11 - c01;
    grad[1] = dy0 + (dy1 - dy0) * tz;
    grad[2] = c1 - c0;
    return c0 + (c1 - c0) * tz;
}

typedef struct contact {
    float distance;              /* estimated distance from the point to the surface; < 0 inside */
    float normal[3];             /* unit, pointing into the air */
} contact;

/* The nearer of the terrain's contact and the obstacles' (rocks), when there are obstacles. */
static contact obstacle_contact(const local_field *lf, const float c[3], contact terrain) {
    const game_player_desc *p = lf->params;
    if (!p || !p->obstacle_distance) return terrain;
    double point[3] = { lf->origin[0] + c[0], lf->origin[1] + c[1], lf->origin[2] + c[2] };
    float normal[3];
    float d = p->obstacle_distance(p->obstacle_user, point, fminf(terrain.distance, 2.0f), normal);
    if (!(d < terrain.distance)) return terrain;
    contact out = { .distance = d, .normal = { normal[0], normal[1], normal[2] } };
    return out;
}

/* −f/|∇f|: exact where f is a clamped distance (flat ground, planar walls within 1 m of them).
 * |∇f| is bounded below so that f's saturated plateaus (f = ±1 more than σ from any surface)
 * read as far away rather than as a division by zero. */
static contact probe(const local_field *lf, const float c[3]) {
    float g[3];
    float f = field_eval(lf, c, g);
    float len = sqrtf(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    contact out;
    if (len < 1e-6f) {
        out.distance = f < 0.0f ? 2.0f : -2.0f;
        out.normal[0] = 0.0f, out.normal[1] = 1.0f, out.normal[2] = 0.0f;
        return obstacle_contact(lf, c, out);
    }
    out.distance = -f / fmaxf(len, 0.5f);
    for (int a = 0; a < 3; a++) out.normal[a] = -g[a] / len;
    return obstacle_contact(lf, c, out);
}

/* ---- the capsule ---------------------------------------------------------------------------- */

typedef struct mover {
    const game_player_desc *params;
    const local_field *lf;
    float height;                /* of the capsule now */
    float cos_max_slope;
} mover;

static float probe_y(const mover *m, float height, int i) {
    float r = m->params->radius;
    return r + (height - 2.0f * r) * (float)i / (float)(PROBE_COUNT - 1);
}

/* Whether a capsule of `height` with its feet at p overlaps nothing. */
static bool capsule_clear(const mover *m, const float p[3], float height) {
    for (int i = 0; i < PROBE_COUNT; i++) {
        float c[3] = { p[0], p[1] + probe_y(m, height, i), p[2] };
        if (probe(m->lf, c).distance < m->params->radius - SKIN) return false;
    }
    return true;
}

typedef struct resolve_result {
    bool ground, wall, ceiling;
} resolve_result;

/* Pushes every overlapping probe out (each push at most r/2, so no probe is carried through a
 * thin layer) and removes the velocity that goes into the surfaces. Walking: walkable contacts
 * lift the player vertically (no sliding down slopes), steeper upward-facing ones push it
 * horizontally only (running into a steep slope never lifts it). Flying: along the normal. */
static resolve_result resolve(const mover *m, float p[3], float v[3], bool walking) {
    resolve_result result = { 0 };
    float r = m->params->radius, max_push = 0.5f * r;
    float last_wall[2] = { 0.0f, 0.0f };       /* horizontal direction of the last steep push */
    for (int iteration = 0; iteration < RESOLVE_ITERATIONS; iteration++) {
        bool pushed = false;
        for (int i = 0; i < PROBE_COUNT; i++) {
            float c[3] = { p[0], p[1] + probe_y(m, m->height, i), p[2] };
            contact ct = probe(m->lf, c);
            float depth = r - ct.distance;
            if (depth <= SKIN) continue;
            pushed = true;
            const float *n = ct.normal;
            float h = sqrtf(n[0] * n[0] + n[2] * n[2]);
            float hx = h > 0.0f ? n[0] / h : 0.0f, hz = h > 0.0f ? n[2] / h : 0.0f;
            /* Wedged: two steep faces pushing against each other (a crevice between rocks)
             * hold the capsule up as ground does; pushed only sideways it would sink between
             * them until the pushes cancel. */
            bool wedged = walking && n[1] > 0.0f && hx * last_wall[0] + hz * last_wall[1] < -0.3f;
            if (walking && (n[1] >= m->cos_max_slope || wedged)) {
                p[1] += fminf(depth / n[1], max_push);
                if (v[1] < 0.0f) v[1] = 0.0f;
                result.ground = true;
            } else if (walking && n[1] >= 0.0f) {
                last_wall[0] = hx, last_wall[1] = hz;
                float push = fminf(depth / h, max_push);
                p[0] += hx * push, p[2] += hz * push;
                float into = v[0] * hx + v[2] * hz;
                if (into < 0.0f) v[0] -= into * hx, v[2] -= into * hz;
                result.wall = true;
            } else {
                float push = fminf(depth, max_push);
                for (int a = 0; a < 3; a++) p[a] += n[a] * push;
                float into = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
                if (into < 0.0f)
                    for (int a = 0; a < 3; a++) v[a] -= into * n[a];
                if (n[1] < 0.0f) result.ceiling = true;
                else if (n[1] >= m->cos_max_slope) result.ground = true;
                else result.wall = true;
            }
        }
        if (!pushed) break;
    }
    return result;
}

/* Vertical gap from the bottom probe down to walkable ground, or +inf when what is below (within
 * the field's reach) is not walkable. */
static float ground_gap(const mover *m, const float p[3]) {
    float c[3] = { p[0], p[1] + m->params->radius, p[2] };
    contact ct = probe(m->lf, c);
    if (ct.normal[1] < m->cos_max_slope) return INFINITY;
    return (ct.distance - m->params->radius) / ct.normal[1];
}

/* Moves p down onto walkable ground at most max_drop below, in steps of at most r/2; false (p
 * unchanged) when there is none. */
static bool snap_down(const mover *m, float p[3], float max_drop) {
    float q[3] = { p[0], p[1], p[2] }, dropped = 0.0f;
    for (int i = 0; i < 64; i++) {
        float gap = ground_gap(m, q);
        if (gap <= SNAP_EPSILON) {
            p[1] = q[1];
            return true;
        }
        if (dropped + gap > max_drop) return false;
        float step = fminf(gap, 0.5f * m->params->radius);
        q[1] -= step, dropped += step;
    }
    return false;
}

/* Raises p by `amount` in steps of at most r/2 if the capsule stays clear all the way. */
static bool lift_clear(const mover *m, float p[3], float amount) {
    float q[3] = { p[0], p[1], p[2] }, lifted = 0.0f, step = 0.5f * m->params->radius;
    while (lifted < amount) {
        float s = fminf(step, amount - lifted);
        q[1] += s, lifted += s;
        if (!capsule_clear(m, q, m->height)) return false;
    }
    p[1] = q[1];
    return true;
}

/* Whether something holds the capsule up where it stands though no walkable ground lies under
 * it: lowered by GROUND_EPSILON it is pushed back up (wedged between two steep faces, resolve's
 * `wedged`). */
static bool held_below(const mover *m, const float p[3]) {
    float q[3] = { p[0], p[1] - GROUND_EPSILON, p[2] }, v[3] = { 0.0f, 0.0f, 0.0f };
    resolve_result hit = resolve(m, q, v, true);
    return hit.ground && q[1] >= p[1] - SNAP_EPSILON;
}

/* One walking substep of `h` seconds (the move is at most r/2 long). */
static void walk_substep(const mover *m, float p[3], float v[3], bool *on_ground, float h) {
    const game_player_desc *pr = m->params;
    if (*on_ground && v[1] <= 0.0f) {
        v[1] = 0.0f;
        float start[3] = { p[0], p[1], p[2] };
        float moved[3] = { p[0] + v[0] * h, p[1], p[2] + v[2] * h };
        float vm[3] = { v[0], v[1], v[2] };
        resolve_result hit = resolve(m, moved, vm, true);
        if (hit.wall && pr->step_height > 0.0f) {
            /* step up: lift, move, come down on walkable ground; keep it if it got further */
            float q[3] = { start[0], start[1], start[2] }, vq[3] = { v[0], v[1], v[2] };
            if (lift_clear(m, q, pr->step_height)) {
                q[0] += v[0] * h, q[2] += v[2] * h;
                resolve(m, q, vq, true);
                if (snap_down(m, q, pr->step_height + 0.05f) && capsule_clear(m, q, m->height)) {
                    float speed2 = v[0] * v[0] + v[2] * v[2];
                    float along_q = ((q[0] - start[0]) * v[0] + (q[2] - start[2]) * v[2]);
                    float along_m = ((moved[0] - start[0]) * v[0] + (moved[2] - start[2]) * v[2]);
                    if (speed2 > 0.0f && along_q > along_m + 1e-4f * sqrtf(speed2)) {
                        memcpy(moved, q, sizeof q);
                        vm[0] = v[0], vm[2] = v[2];
                    }
                }
            }
        }
        memcpy(p, moved, sizeof moved);
        memcpy(v, vm, sizeof vm);
        *on_ground = snap_down(m, p, pr->step_height) || held_below(m, p);
        if (*on_ground) {
            v[1] = 0.0f;
            resolve(m, p, v, true);
        }
        return;
    }
    v[1] = fmaxf(v[1] - pr->gravity * h, -pr->terminal_speed);
    for (int a = 0; a < 3; a++) p[a] += v[a] * h;
    resolve_result hit = resolve(m, p, v, true);
    *on_ground = v[1] <= 0.0f && (hit.ground || ground_gap(m, p) <= GROUND_EPSILON);
    if (*on_ground) v[1] = 0.0f;
}

/* Moves v[0 … n) towards target by at most step (a negative step: all the way). */
static void approach(float *v, const float *target, int n, float step) {
    float d2 = 0.0f;
    for (int i = 0; i < n; i++) d2 += (target[i] - v[i]) * (target[i] - v[i]);
    float scale = step < 0.0f || d2 <= step * step ? 1.0f : step / sqrtf(d2);
    for (int i = 0; i < n; i++) v[i] += (target[i] - v[i]) * scale;
}

/* ---- water (player.h: the model; issue 15) ---------------------------------------------------- */

/* What a frame in water asks of its substeps, in the frame's local coordinates. */
typedef struct swim_plan {
    float float_eye;             /* the height the eye floats at: the surface + swim_eye_above */
    float eye_height;            /* the eye over the feet */
    int vertical;                /* −1 dive (crouch held), +1 rise (jump held), 0 float */
    float climb_to;              /* the feet's height over a shore being climbed; NaN: none */
    float wish[2];               /* the horizontal velocity asked for (x, z) */
} swim_plan;

/* The vertical motion of a floating player over h seconds, from its eye's offset x0 above the
 * float height and velocity v[1]. Within speed/ω of the height it is the critically damped spring
 * x'' = −2ωx' − ω²x, solved exactly: x(h) = (x0 + (v0 + ωx0)h)·e^(−ωh), so it settles without
 * overshoot or jitter however long the step (a player arriving at the zone's edge at `speed` has
 * v0 + ωx0 = 0 and decays as a pure exponential). Farther away the velocity eases towards `speed`
 * in the height's direction. Returns the rise of the feet. */
static float swim_float(const game_player_desc *pr, float x0, float speed, float v[3], float h) {
    float w = pr->buoyancy_rate;
    if (fabsf(x0) * w <= speed) {
        float decay = expf(-w * h), c = v[1] + w * x0;
        v[1] = (v[1] - w * c * h) * decay;
        return (x0 + c * h) * decay - x0;
    }
    float target = x0 < 0.0f ? speed : -speed;
    approach(&v[1], &target, 1, pr->swim_accel * h);
    return v[1] * h;
}

/* One substep in water (at most r/2 long, as walking's). Returns whether the feet stand on the bed
 * (a walkable contact under them). Collision is walking's: the bed lifts, walls push sideways. */
static bool swim_substep(const mover *m, const swim_plan *s, float p[3], float v[3], float h) {
    const game_player_desc *pr = m->params;
    float rise;
    if (!isnan(s->climb_to)) {
        /* climbing out: up the shore while pressing on, then level until over its top */
        v[0] = s->wish[0], v[2] = s->wish[1];
        v[1] = p[1] < s->climb_to ? pr->dive_speed : 0.0f;
        rise = v[1] * h;
    } else if (s->vertical < 0) {
        float target = -pr->dive_speed;
        approach(&v[1], &target, 1, pr->swim_accel * h);
        rise = v[1] * h;
    } else {
        float speed = s->vertical > 0 ? pr->dive_speed : pr->float_speed;
        rise = swim_float(pr, p[1] + s->eye_height - s->float_eye, speed, v, h);
    }
    p[0] += v[0] * h, p[1] += rise, p[2] += v[2] * h;
    return resolve(m, p, v, true).ground;
}

/* ---- the frame ------------------------------------------------------------------------------ */

static float or_default(float value, float fallback) { return value > 0.0f ? value : fallback; }

void game_player_init(game_player *player, const game_player_desc *params) {
    memset(player, 0, sizeof *player);
    game_player_desc p = params ? *params : (game_player_desc){ 0 };
    p.radius = or_default(p.radius, 0.35f);
    p.height = or_default(p.height, 1.8f);
    p.crouch_height = or_default(p.crouch_height, 1.2f);
    p.eye_height = or_default(p.eye_height, 1.62f);
    p.crouch_eye_height = or_default(p.crouch_eye_height, 1.05f);
    p.walk_speed = or_default(p.walk_speed, 4.5f);
    p.sprint_speed = or_default(p.sprint_speed, 8.0f);
    p.crouch_speed = or_default(p.crouch_speed, 2.0f);
    p.gravity = or_default(p.gravity, 20.0f);
    p.jump_speed = or_default(p.jump_speed, sqrtf(2.0f * p.gravity * 1.1f));
    p.terminal_speed = or_default(p.terminal_speed, 50.0f);
    p.step_height = or_default(p.step_height, 0.5f);
    p.max_slope_deg = or_default(p.max_slope_deg, 50.0f);
    p.fly_speed = or_default(p.fly_speed, 12.0f);
    p.fly_sprint_speed = or_default(p.fly_sprint_speed, 48.0f);
    p.pitch_limit = or_default(p.pitch_limit, 1.55f);
    p.ground_accel = or_default(p.ground_accel, 60.0f);
    p.air_accel = or_default(p.air_accel, 12.0f);
    p.fly_accel = or_default(p.fly_accel, 120.0f);
    p.bob_amplitude = or_default(p.bob_amplitude, 0.05f);
    p.max_dt = or_default(p.max_dt, 0.1f);
    p.swim_depth = or_default(p.swim_depth, 1.2f);
    p.wade_slowdown = or_default(p.wade_slowdown, 0.5f);
    p.swim_eye_above = or_default(p.swim_eye_above, 0.1f);
    p.swim_speed = or_default(p.swim_speed, 3.0f);
    p.swim_sprint_speed = or_default(p.swim_sprint_speed, 5.0f);
    p.dive_speed = or_default(p.dive_speed, 2.5f);
    p.float_speed = or_default(p.float_speed, 1.5f);
    p.buoyancy_rate = or_default(p.buoyancy_rate, 4.0f);
    p.swim_accel = or_default(p.swim_accel, 10.0f);
    p.climb_out_height = or_default(p.climb_out_height, 1.0f);
    if (p.wade_slowdown > 1.0f) p.wade_slowdown = 1.0f;
    /* a floating player must stay deeper than swim_depth, or it would stop swimming at once */
    p.swim_depth = fminf(p.swim_depth, fmaxf(p.eye_height - p.swim_eye_above - 0.1f, 0.1f));
    if (p.crouch_height > p.height) p.crouch_height = p.height;
    if (p.crouch_height < 2.0f * p.radius) p.crouch_height = 2.0f * p.radius;
    player->params = p;
}

float game_player_height(const game_player *player) {
    return player->crouching ? player->params.crouch_height : player->params.height;
}

void game_player_eye(const game_player *player, double eye[3]) {
    const game_player_desc *p = &player->params;
    eye[0] = player->position[0];
    eye[1] = player->position[1] + (double)(player->crouching ? p->crouch_eye_height : p->eye_height);
    eye[2] = player->position[2];
}

float game_player_wade_share(const game_player_desc *params, float depth) {
    if (!(depth > 0.0f)) return 1.0f;
    return 1.0f - params->wade_slowdown * fminf(depth / params->swim_depth, 1.0f);
}

#define BOB_STRIDE 1.2f                /* metres a half cycle: a dip per step */

float game_player_bob(const game_player *player) {
    const game_player_desc *p = &player->params;
    if (player->flying || player->swimming || !player->on_ground || p->bob_amplitude <= 0.0f) return 0.0f;
    float speed = hypotf(player->velocity[0], player->velocity[2]);
    float share = fminf(speed / p->sprint_speed, 1.0f);
    return p->bob_amplitude * share * fabsf(sinf(player->bob_phase * 3.14159265f));
}

static bool down(const input_actions *a, input_action action) { return (a->down & INPUT_ACTION_BIT(action)) != 0; }
static bool pressed(const input_actions *a, input_action action) {
    return (a->pressed & INPUT_ACTION_BIT(action)) != 0;
}

/* The velocity the input asks for this frame. */
static void wish_velocity(const game_player *pl, const input_actions *a, float out[3]) {
    const game_player_desc *p = &pl->params;
    float mx = a->move_x, my = a->move_y, len = sqrtf(mx * mx + my * my);
    if (len > 1.0f) mx /= len, my /= len;
    float sy = sinf(pl->yaw), cy = cosf(pl->yaw);
    if (pl->flying) {
        float sp = sinf(pl->pitch), cp = cosf(pl->pitch);
        float speed = down(a, INPUT_ACTION_SPRINT) ? p->fly_sprint_speed : p->fly_speed;
        float up = (down(a, INPUT_ACTION_JUMP) ? 1.0f : 0.0f) - (down(a, INPUT_ACTION_CROUCH) ? 1.0f : 0.0f);
        out[0] = (sy * cp * my + cy * mx) * speed;
        out[1] = (sp * my + up) * speed;
        out[2] = (-cy * cp * my + sy * mx) * speed;
        return;
    }
    bool sprint = down(a, INPUT_ACTION_SPRINT);
    float speed = pl->crouching ? p->crouch_speed : sprint ? p->sprint_speed : p->walk_speed;
    if (pl->swimming) speed = sprint ? p->swim_sprint_speed : p->swim_speed;   /* the view's yaw only */
    else if (pl->in_water)             /* wading: no sprint, slower the deeper */
        speed = (pl->crouching ? p->crouch_speed : p->walk_speed) * game_player_wade_share(p, pl->water_depth);
    out[0] = (sy * my + cy * mx) * speed;
    out[1] = 0.0f;
    out[2] = (-cy * my + sy * mx) * speed;
}

/* Feet this far under the ground top of a column with water on it are in a cave below the water,
 * not in it (the field's rounding puts feet on a sloping bed up to ~0.5 m under its column's top). */
#define WATER_CAVE_MARGIN 1.0

/* The water state at the player's position now: in_water, water_surface, water_depth and
 * eye_under_water, then whether the next frame swims. A swimmer goes on swimming until its feet
 * stand on the bed less than swim_depth under the surface or leave the water; a walker starts
 * once deeper than swim_depth. Both rules at swim_depth, but a floating swimmer's feet are
 * eye_height − swim_eye_above deep, deeper than swim_depth, so only the bed ends a swim. */
static void water_refresh(game_player *pl, terrain_world *world) {
    const game_player_desc *p = &pl->params;
    float surface = 0.0f, ground = 0.0f;
    double feet = pl->position[1];
    bool wet = terrain_world_water_at(world, pl->position[0], pl->position[2], &surface, &ground) &&
               feet < (double)surface && feet >= (double)ground - WATER_CAVE_MARGIN;
    double eye[3];
    game_player_eye(pl, eye);
    pl->in_water = wet;
    pl->water_surface = wet ? surface : 0.0f;
    pl->water_depth = wet ? (float)((double)surface - feet) : 0.0f;
    pl->eye_under_water = wet && eye[1] < (double)surface;
    if (pl->flying || !wet) pl->swimming = false;
    else if (pl->swimming) pl->swimming = !(pl->on_ground && pl->water_depth < p->swim_depth);
    else pl->swimming = pl->water_depth > p->swim_depth;
}

/* A shore a swimmer climbs out onto: along the horizontal wish, the first of the columns at
 * r + 0.25, r + 0.75 and r + 1.25 m from the axis whose ground rises more than a step above the
 * feet. Its top, when at most climb_out_height above the surface, in world metres; NaN otherwise
 * (open water, or a cliff: the swimmer stays in the water below it). */
static float swim_climb_top(const game_player *pl, terrain_world *world, const float wish[3]) {
    const game_player_desc *p = &pl->params;
    float speed = hypotf(wish[0], wish[2]);
    if (!(speed > 0.0f)) return NAN;
    for (int k = 0; k < 3; k++) {
        double d = (double)p->radius + 0.25 + 0.5 * k;
        float top = terrain_world_top(world, pl->position[0] + (double)(wish[0] / speed) * d,
                                      pl->position[2] + (double)(wish[2] / speed) * d);
        if ((double)top <= pl->position[1] + (double)p->step_height) continue;
        return top <= pl->water_surface + p->climb_out_height ? top : NAN;
    }
    return NAN;
}

/* Margin a climbing swimmer rises above the shore's column top before moving over it, so that it
 * lands on the top rather than on its rounded edge. */
#define CLIMB_CLEARANCE 0.25f
#define CLIMB_SPARE_SECONDS 1.5f   /* a climb may take this longer than its rise at dive_speed */

/* Whether this frame climbs: a swimmer heading into a shore it can climb starts (player.h); a
 * climb goes on while the move input holds, within its time, until the feet are over the shore's
 * top (checked after the move, climb_done). */
static bool climb_begin(game_player *pl, terrain_world *world, const input_actions *a, const float wish[3]) {
    const game_player_desc *p = &pl->params;
    bool moving = wish[0] != 0.0f || wish[2] != 0.0f;
    if (pl->climbing && (!moving || pl->climb_time <= 0.0f)) pl->climbing = false;
    if (pl->climbing || !pl->swimming || down(a, INPUT_ACTION_CROUCH)) return pl->climbing;
    float top = swim_climb_top(pl, world, wish);
    if (isnan(top)) return false;
    pl->climbing = true;
    pl->climb_top = top;
    pl->climb_time = (float)((double)top + CLIMB_CLEARANCE - pl->position[1]) / p->dive_speed + CLIMB_SPARE_SECONDS;
    return true;
}

/* After a climbing frame: over the shore (the column under the feet reaches its top, and the feet
 * are above it), the climb is done and the player lands (walking, or wading on a shelf). */
static void climb_done(game_player *pl, terrain_world *world, float dt) {
    pl->climb_time -= dt;
    float under = terrain_world_top(world, pl->position[0], pl->position[2]);
    if (under >= pl->climb_top - 0.5f && pl->position[1] >= (double)under) pl->climbing = false;
}

static void update(game_player *pl, terrain_world *world, const input_actions *a, float dt, bool ask_region) {
    const game_player_desc *p = &pl->params;
    if (!(dt > 0.0f)) dt = 0.0f;
    if (dt > p->max_dt) dt = p->max_dt;

    pl->yaw = remainderf(pl->yaw + a->look_x, 6.28318530718f);
    pl->pitch = fminf(fmaxf(pl->pitch + a->look_y, -p->pitch_limit), p->pitch_limit);
    if (pressed(a, INPUT_ACTION_TOGGLE_FLY)) {
        pl->flying = !pl->flying;
        pl->velocity[0] = pl->velocity[1] = pl->velocity[2] = 0.0f;
        pl->on_ground = false;
        if (pl->flying) pl->swimming = pl->climbing = false;
    }
    if (dt == 0.0f) return;

    float wish[3];
    bool swimming = pl->swimming;      /* as the last update left the water state */
    bool want_crouch = !pl->flying && !swimming && down(a, INPUT_ACTION_CROUCH);   /* swimming: dive */
    if (want_crouch) pl->crouching = true;   /* shrinking always fits */
    wish_velocity(pl, a, wish);
    float v[3] = { pl->velocity[0], pl->velocity[1], pl->velocity[2] };
    if (pl->flying) approach(v, wish, 3, p->fly_accel < 0.0f ? -1.0f : p->fly_accel * dt);
    else {
        float horizontal[2] = { v[0], v[2] }, target[2] = { wish[0], wish[2] };
        float accel = swimming ? p->swim_accel : pl->on_ground ? p->ground_accel : p->air_accel;
        approach(horizontal, target, 2, accel < 0.0f ? -1.0f : accel * dt);
        v[0] = horizontal[0], v[2] = horizontal[1];
    }
    if (!pl->flying && !swimming && pl->on_ground && pressed(a, INPUT_ACTION_JUMP)) {
        v[1] = p->jump_speed;
        pl->on_ground = false;
    }
    /* water takes most of a fall's speed at once: a dive from a cliff goes a metre or so under */
    if (swimming) v[1] = fmaxf(v[1], -2.0f * p->dive_speed);

    /* the box this frame can reach: the capsule, the move, a step, pushes, and the cell around */
    float speed_bound = sqrtf(v[0] * v[0] + v[2] * v[2]) + fabsf(v[1]) + (pl->flying ? 0.0f : p->gravity * dt) +
                        (swimming || pl->climbing ? p->dive_speed + p->swim_sprint_speed : 0.0f);
    float reach = speed_bound * dt + p->step_height + p->radius + 1.0f;
    int64_t origin[3];
    float feet[3];
    for (int i = 0; i < 3; i++) {
        origin[i] = (int64_t)floor(pl->position[i]);
        feet[i] = (float)(pl->position[i] - (double)origin[i]);
    }
    int lo[3], size[3];
    float box_lo[3] = { feet[0] - reach, feet[1] - reach, feet[2] - reach };
    float box_hi[3] = { feet[0] + reach, feet[1] + p->height + reach, feet[2] + reach };
    double region_min[3], region_max[3];
    for (int i = 0; i < 3; i++) {
        lo[i] = (int)floorf(box_lo[i]);
        size[i] = (int)ceilf(box_hi[i]) - lo[i] + 1;
        region_min[i] = (double)(origin[i] + lo[i]);
        region_max[i] = (double)(origin[i] + lo[i] + size[i] - 1);
    }
    if (ask_region && p->region_ready && !p->region_ready(p->region_user, region_min, region_max)) {
        pl->waiting = true;            /* hold still: no walking into it, no falling */
        pl->velocity[0] = pl->velocity[1] = pl->velocity[2] = 0.0f;
        return;
    }
    pl->waiting = false;

    local_field lf = { .lo = { (float)lo[0], (float)lo[1], (float)lo[2] },
                       .origin = { (double)origin[0], (double)origin[1], (double)origin[2] }, .params = p };
    if (p->obstacles_near) p->obstacles_near(p->obstacle_user, region_min, region_max);
    if (!terrain_field_sample(world, &(terrain_field_desc){
            .first = { origin[0] + lo[0], origin[1] + lo[1], origin[2] + lo[2] },
            .size = { size[0], size[1], size[2] } }, &lf.field))
        return;                        /* only for absurd positions (beyond ±2^52 m) */

    mover m = { .params = p, .lf = &lf, .height = game_player_height(pl),
                .cos_max_slope = cosf(p->max_slope_deg * 0.0174532925f) };
    if (pl->crouching && !want_crouch && capsule_clear(&m, feet, p->height)) {
        pl->crouching = false;
        m.height = p->height;
    }
    bool climbing = !pl->flying && climb_begin(pl, world, a, wish);
    swim_plan plan = { .climb_to = NAN };
    if (swimming || climbing) {
        double eye[3];
        game_player_eye(pl, eye);
        plan.eye_height = (float)(eye[1] - pl->position[1]);
        plan.float_eye = (float)((double)pl->water_surface + (double)p->swim_eye_above - (double)origin[1]);
        plan.vertical = down(a, INPUT_ACTION_CROUCH) ? -1 : down(a, INPUT_ACTION_JUMP) ? 1 : 0;
        plan.wish[0] = wish[0], plan.wish[1] = wish[2];
        if (climbing) plan.climb_to = (float)((double)pl->climb_top - (double)origin[1]) + CLIMB_CLEARANCE;
    }

    int substeps = (int)ceilf(speed_bound * dt / (0.5f * p->radius));
    if (substeps < 1) substeps = 1;
    if (substeps > MAX_SUBSTEPS) substeps = MAX_SUBSTEPS;
    float h = dt / (float)substeps;
    bool on_ground = pl->on_ground;
    for (int s = 0; s < substeps; s++) {
        if (pl->flying) {
            for (int i = 0; i < 3; i++) feet[i] += v[i] * h;
            resolve(&m, feet, v, false);
        } else if (swimming || climbing) {
            on_ground = swim_substep(&m, &plan, feet, v, h);
        } else {
            walk_substep(&m, feet, v, &on_ground, h);
        }
    }
    terrain_field_free(&lf.field);

    pl->on_ground = !pl->flying && on_ground;
    memcpy(pl->velocity, v, sizeof v);
    if (pl->on_ground && !swimming) pl->bob_phase = fmodf(pl->bob_phase + hypotf(v[0], v[2]) * dt / BOB_STRIDE, 2.0f);
    for (int i = 0; i < 3; i++) pl->position[i] = (double)origin[i] + (double)feet[i];
    if (climbing) climb_done(pl, world, dt);
    water_refresh(pl, world);
}

void game_player_update(game_player *player, terrain_world *world, const input_actions *actions, float dt) {
    TRACE_ZONE("game_player_update");
    update(player, world, actions, dt, true);
}

/* ---- spawn ---------------------------------------------------------------------------------- */

static int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

static void column_heights(terrain_world *world, int64_t gx, int64_t gz, float *top, float *surface) {
    terrain_chunk_coord coord = { floor_div(gx, TERRAIN_CHUNK_COLUMNS), floor_div(gz, TERRAIN_CHUNK_COLUMNS) };
    const terrain_stacks *stacks = terrain_world_stacks(world, coord);
    int i = (int)(gx - coord.x * TERRAIN_CHUNK_COLUMNS), k = (int)(gz - coord.z * TERRAIN_CHUNK_COLUMNS);
    *top = terrain_stacks_top(stacks, i, k);
    if (surface) *surface = terrain_stacks_surface(stacks, i, k);
}

static bool column_dry(terrain_world *world, int64_t gx, int64_t gz) {
    float top, surface;
    column_heights(world, gx, gz, &top, &surface);
    return surface <= top;
}

/* Swimming at rest at the float height (within a millimetre). */
static bool spawn_afloat(const game_player *pl) {
    double eye[3];
    game_player_eye(pl, eye);
    double rest = (double)pl->water_surface + (double)pl->params.swim_eye_above;
    return pl->swimming && fabs(eye[1] - rest) < 1e-3 && fabsf(pl->velocity[1]) < 1e-2f;
}

void game_player_spawn(game_player *player, terrain_world *world, double x, double z) {
    int64_t gx = (int64_t)floor(x), gz = (int64_t)floor(z);
    double cx = x, cz = z;
    if (!column_dry(world, gx, gz)) {
        /* square rings outwards, in a fixed order; the first dry column wins */
        bool found = false;
        for (int64_t ring = 1; ring <= SPAWN_SEARCH_RADIUS && !found; ring++)
            for (int64_t dz = -ring; dz <= ring && !found; dz++)
                for (int64_t dx = -ring; dx <= ring && !found; dx++) {
                    if (dx != -ring && dx != ring && dz != -ring && dz != ring) continue;
                    if (column_dry(world, gx + dx, gz + dz)) {
                        found = true;
                        gx += dx, gz += dz;
                        cx = (double)gx + 0.5, cz = (double)gz + 0.5;
                    }
                }
    }
    /* above every solid top within the field's reach of the capsule's axis: f < 0 there */
    float highest = TERRAIN_FLOOR_Y;
    for (int64_t dz = -2; dz <= 2; dz++)
        for (int64_t dx = -2; dx <= 2; dx++) {
            float top;
            column_heights(world, gx + dx, gz + dz, &top, NULL);
            highest = fmaxf(highest, top);
        }
    game_player_desc params = player->params;
    memset(player, 0, sizeof *player);
    player->params = params;
    player->position[0] = cx;
    player->position[1] = (double)highest + 1.0;
    player->position[2] = cz;
    /* no dry land near: afloat where the water is deep enough, else on its bed as on land */
    float surface;
    if (terrain_world_water_at(world, cx, cz, &surface, NULL)) {
        double afloat = (double)surface + (double)params.swim_eye_above - (double)params.eye_height;
        player->position[1] = fmax(player->position[1], afloat);
    }
    water_refresh(player, world);
    /* fall onto it (or settle afloat) with the controller itself (the same collision as walking) */
    input_actions idle = { 0 };
    for (int frame = 0; frame < SPAWN_FRAMES && !player->on_ground && !spawn_afloat(player); frame++)
        update(player, world, &idle, 1.0f / 60.0f, false);
    player->velocity[0] = player->velocity[1] = player->velocity[2] = 0.0f;
}

/* ---- the most open view --------------------------------------------------------------------- */

#define OPEN_PI 3.14159265358979323846

/* The steepest angle from the eye up to the ground tops along yaw, out to the view distance. */
static double skyline_along(terrain_world *world, const double eye[3], double yaw) {
    double forward_x = sin(yaw), forward_z = -cos(yaw);   /* yaw 0 looks along −z */
    double steepest = -OPEN_PI / 2;
    for (double d = 8.0; d <= GAME_PLAYER_VIEW_DISTANCE; d += 8.0) {
        float top;
        int64_t x = (int64_t)floor(eye[0] + forward_x * d), z = (int64_t)floor(eye[2] + forward_z * d);
        column_heights(world, x, z, &top, NULL);
        steepest = fmax(steepest, atan2((double)top - eye[1], d));
    }
    return steepest;
}

float game_player_open_yaw(const game_player *player, terrain_world *world, float preferred, float *skyline) {
    double eye[3], angle[GAME_PLAYER_VIEW_DIRECTIONS], lowest = INFINITY;
    game_player_eye(player, eye);
    for (int k = 0; k < GAME_PLAYER_VIEW_DIRECTIONS; k++) {
        angle[k] = skyline_along(world, eye, (double)preferred + 2.0 * OPEN_PI * k / GAME_PLAYER_VIEW_DIRECTIONS);
        lowest = fmin(lowest, angle[k]);
    }
    /* Within a hundredth of a radian of the lowest counts as a tie: then the smallest turn. */
    int best = 0;
    double best_turn = INFINITY;
    for (int k = 0; k < GAME_PLAYER_VIEW_DIRECTIONS; k++) {
        double turn = fabs(remainder(2.0 * OPEN_PI * k / GAME_PLAYER_VIEW_DIRECTIONS, 2.0 * OPEN_PI));
        if (angle[k] <= lowest + 0.01 && turn < best_turn) best = k, best_turn = turn;
    }
    if (skyline) *skyline = (float)angle[best];
    return (float)remainder((double)preferred + 2.0 * OPEN_PI * best / GAME_PLAYER_VIEW_DIRECTIONS, 2.0 * OPEN_PI);
}
