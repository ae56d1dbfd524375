/* rocks_blocks.c — block tiles for cliffs (paper 003 §4): periodic Poisson points, fracture discs
 * by block type, clusters of mutually visible points, convex hulls as smoothly intersected
 * planes, gradient-based warping; and the replication of the tile over space (003 §5).
 *
 * Periodic throughout. Points, discs and neighbour edges live on the 3-torus of side s, so the
 * tile's blocks meet across its border exactly as they meet inside it. A cluster is grown in its
 * own unwrapped frame (each new point placed at the minimal-image offset from the point that
 * reached it), so a block that straddles the border is one convex set; it is then moved by a
 * whole tile so that its anchor lies in [0, s)³.
 *
 * A change to what a build makes (any array of the tile) must bump ROCKS__BLOCK_CACHE_VERSION
 * (rocks_internal.h): cache files hold a build's output under its desc.
 */
#include "rocks_internal.h"
#include "rocks_world_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_HULL_POINTS 400           /* a cluster's points that enter its hull (more are subsampled) */
#define MERGE_COS 0.95f               /* hull faces within ~18° share one plane */
#define BOUNDS_MARGIN 1.0f            /* bounds hold the field's values above −1 m */

/* ---- small helpers -------------------------------------------------------------------------- */

typedef struct rng { uint64_t state; } rng;

static uint64_t rng_next(rng *r) { return core_hash_u64(r->state += 0x9e3779b97f4a7c15ull); }
static float rng_unit(rng *r) { return (float)(rng_next(r) >> 40) * (1.0f / 16777216.0f); }
static float rng_range(rng *r, float lo, float hi) { return lo + (hi - lo) * rng_unit(r); }

static void rng_direction(rng *r, float out[3]) {
    for (;;) {
        float v[3] = { rng_range(r, -1, 1), rng_range(r, -1, 1), rng_range(r, -1, 1) };
        float l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (l2 > 1e-4f && l2 <= 1.0f) {
            float inv = 1.0f / sqrtf(l2);
            for (int a = 0; a < 3; a++) out[a] = v[a] * inv;
            return;
        }
    }
}

static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void normalize3(float v[3]) {
    float l = sqrtf(dot3(v, v));
    if (l > 0) v[0] /= l, v[1] /= l, v[2] /= l;
}

static float wrap(float x, float s) {
    x = fmodf(x, s);
    if (x < 0) x += s;
    return x >= s ? 0.0f : x;
}

/* b − a on the torus: the shortest of the lattice images. */
static void min_image(const float a[3], const float b[3], float s, float d[3]) {
    for (int k = 0; k < 3; k++) {
        d[k] = b[k] - a[k];
        d[k] -= s * roundf(d[k] / s);
    }
}

const char *rocks_block_type_name(rocks_block_type type) {
    static const char *names[ROCKS_BLOCK_TYPE_END] = {
        [ROCKS_BLOCK_EQUIDIMENSIONAL] = "equidimensional", [ROCKS_BLOCK_RHOMBOHEDRAL] = "rhombohedral",
        [ROCKS_BLOCK_POLYHEDRAL] = "polyhedral", [ROCKS_BLOCK_TABULAR] = "tabular", [ROCKS_BLOCK_COLUMNAR] = "columnar",
    };
    return (unsigned)type < ROCKS_BLOCK_TYPE_END ? names[type] : NULL;
}

bool rocks_parse_block_type(const char *text, rocks_block_type *out) {
    for (int t = ROCKS_BLOCK_EQUIDIMENSIONAL; text && t < ROCKS_BLOCK_TYPE_END; t++)
        if (strcmp(text, rocks_block_type_name((rocks_block_type)t)) == 0) {
            *out = (rocks_block_type)t;
            return true;
        }
    return false;
}

float rocks_smooth_intersection(float a, float b, float rounding) {
    float k = fmaxf(1.0f - fabsf(a - b) / rounding, 0.0f);   /* 003 §4.2 */
    return fminf(a, b) - rounding * k * k * k / 6.0f;
}

/* ---- Poisson-disc points on the torus (Bridson's dart growth) -------------------------------- */

typedef struct point_grid {
    int g;                            /* cells a side */
    float cell;                       /* s / g ≤ r / √3: one point a cell at most */
    int32_t *slot;                    /* g³ point indices, −1 empty */
} point_grid;

static int grid_index(const point_grid *grid, const float p[3]) {
    int c[3];
    for (int a = 0; a < 3; a++) {
        c[a] = (int)(p[a] / grid->cell);
        if (c[a] >= grid->g) c[a] = grid->g - 1;
    }
    return (c[2] * grid->g + c[1]) * grid->g + c[0];
}

/* Calls visit(user, j) for the points in cells within `reach` cells of p (with repeats when the
 * grid is smaller than the neighbourhood); stops when it returns false. */
static bool grid_visit(const point_grid *grid, const float p[3], int reach, bool (*visit)(void *, int32_t), void *user) {
    int wrapped[3][17], span = 2 * reach + 1;   /* reach ≤ 8: the cells' indices on each axis */
    for (int a = 0; a < 3; a++) {
        int c = (int)(p[a] / grid->cell);
        for (int d = 0; d < span; d++) wrapped[a][d] = ((c + d - reach) % grid->g + grid->g) % grid->g;
    }
    for (int z = 0; z < span; z++)
        for (int y = 0; y < span; y++) {
            const int32_t *row = grid->slot + ((size_t)wrapped[2][z] * grid->g + wrapped[1][y]) * grid->g;
            for (int x = 0; x < span; x++) {
                int32_t j = row[wrapped[0][x]];
                if (j >= 0 && !visit(user, j)) return false;
            }
        }
    return true;
}

typedef struct far_check { const float (*points)[3]; const float *p; float s, r2; } far_check;

static bool far_enough(void *user, int32_t j) {
    far_check *f = user;
    float d[3];
    min_image(f->p, f->points[j], f->s, d);
    return dot3(d, d) >= f->r2;
}

/* Fills a torus of side s with points at least r apart (003 §4.1: Poisson, not a grid, which
 * aliases into axis-aligned fractures). Returns the count; *out and *grid_out are the caller's. */
static uint32_t poisson_points(rng *r, float s, float radius, float (**out)[3], point_grid *grid_out) {
    point_grid grid = { .g = (int)ceilf(s * sqrtf(3.0f) / radius) };
    grid.cell = s / (float)grid.g;
    size_t cells = (size_t)grid.g * grid.g * grid.g;
    grid.slot = core_alloc(cells * sizeof *grid.slot);
    for (size_t i = 0; i < cells; i++) grid.slot[i] = -1;
    size_t cap = cells, count = 0, active_count = 0;
    float (*points)[3] = core_alloc(cap * sizeof *points);
    uint32_t *active = core_alloc(cap * sizeof *active);
    int reach = (int)ceilf(radius / grid.cell);
    for (int a = 0; a < 3; a++) points[0][a] = rng_range(r, 0, s);
    grid.slot[grid_index(&grid, points[0])] = 0;
    active[active_count++] = 0;
    count = 1;
    while (active_count) {
        uint32_t pick = (uint32_t)(rng_next(r) % active_count);
        const float *base = points[active[pick]];
        bool placed = false;
        for (int attempt = 0; attempt < 24 && !placed; attempt++) {
            float dir[3], c[3];
            rng_direction(r, dir);
            float len = radius * rng_range(r, 1.0f, 2.0f);
            for (int a = 0; a < 3; a++) c[a] = wrap(base[a] + dir[a] * len, s);
            int cell = grid_index(&grid, c);
            if (grid.slot[cell] >= 0) continue;
            far_check check = { points, c, s, radius * radius };
            if (!grid_visit(&grid, c, reach, far_enough, &check)) continue;
            memcpy(points[count], c, sizeof c);
            grid.slot[cell] = (int32_t)count;
            active[active_count++] = (uint32_t)count++;
            placed = true;
        }
        if (!placed) active[pick] = active[--active_count];
    }
    core_free(active, cap * sizeof *active);
    *out = points;
    *grid_out = grid;
    return (uint32_t)count;
}

/* ---- fracture discs by block type (003 §4.1) ------------------------------------------------ */

typedef struct disc_list { rocks_block_disc *items; size_t count, cap; } disc_list;

static void disc_add(disc_list *l, const float centre[3], const float normal[3], float radius, float s) {
    l->items = core_grow(l->items, &l->cap, l->count + 1, sizeof *l->items);
    rocks_block_disc *d = &l->items[l->count++];
    for (int a = 0; a < 3; a++) d->centre[a] = wrap(centre[a], s), d->normal[a] = normal[a];
    normalize3(d->normal);
    d->radius = radius;
}

/* Discs whose centres are a Poisson set of spacing `spacing`, normals from `normal_fn`. */
static void scattered_discs(rng *r, disc_list *l, float s, float spacing, float radius_lo, float radius_hi,
                            void (*normal_fn)(rng *, const float frame[3][3], float[3]), const float frame[3][3]) {
    float (*centres)[3];
    point_grid grid;
    uint32_t n = poisson_points(r, s, spacing, &centres, &grid);
    for (uint32_t i = 0; i < n; i++) {
        float normal[3];
        normal_fn(r, frame, normal);
        disc_add(l, centres[i], normal, rng_range(r, radius_lo, radius_hi), s);
    }
    core_free(centres, (size_t)grid.g * grid.g * grid.g * sizeof *centres);
    core_free(grid.slot, (size_t)grid.g * grid.g * grid.g * sizeof *grid.slot);
}

/* Equidimensional and rhombohedral: one of the frame's three axes; one in ten irregular. */
static void frame_normal(rng *r, const float frame[3][3], float out[3]) {
    if (rng_unit(r) < 0.1f) { rng_direction(r, out); return; }
    memcpy(out, frame[rng_next(r) % 3], 3 * sizeof(float));
}

static void random_normal(rng *r, const float frame[3][3], float out[3]) {
    (void)frame;
    rng_direction(r, out);
}

/* Cross joints: horizontal normals along x or z (tabular), or vertical (columnar). */
static void horizontal_axis_normal(rng *r, const float frame[3][3], float out[3]) {
    (void)frame;
    bool x = rng_next(r) & 1;
    out[0] = x, out[1] = 0, out[2] = !x;
}

static void vertical_normal(rng *r, const float frame[3][3], float out[3]) {
    (void)r, (void)frame;
    out[0] = 0, out[1] = 1, out[2] = 0;
}

/* A set of parallel discs of `radius` across the tile, normal (i, j, k) with integer entries
 * (so the set's images on the torus are the set itself: the planes continue across borders),
 * spaced `spacing` × [0.7, 1.3] along the normal over its period s / |(i, j, k)|. */
static void parallel_set(rng *r, disc_list *l, float s, const int ijk[3], float spacing, float radius) {
    float n[3] = { (float)ijk[0], (float)ijk[1], (float)ijk[2] };
    float len = sqrtf(dot3(n, n));
    normalize3(n);
    float period = s / len, t = rng_range(r, 0, spacing);
    while (t < period - 0.5f * spacing) {
        /* a random point of the plane n·p = t (wrapping moves it to another plane of the set) */
        float v[3] = { rng_range(r, 0, s), rng_range(r, 0, s), rng_range(r, 0, s) }, c[3];
        float along = dot3(v, n);
        for (int a = 0; a < 3; a++) c[a] = v[a] + (t - along) * n[a];
        disc_add(l, c, n, radius, s);
        t += spacing * rng_range(r, 0.7f, 1.3f);
    }
}

/* The type's defaults (metres), for a desc left at zero. */
void rocks__block_type_defaults(rocks_block_type type, float *spacing, float *radius) {
    static const float table[ROCKS_BLOCK_TYPE_END][2] = {
        [ROCKS_BLOCK_EQUIDIMENSIONAL] = { 4.5f, 5.0f },   /* 003 §4.1: radii ≈ 5 m */
        [ROCKS_BLOCK_RHOMBOHEDRAL] = { 4.5f, 5.0f },      /* the same, in an oblique frame */
        [ROCKS_BLOCK_POLYHEDRAL] = { 3.0f, 3.0f },        /* closer centres, more discs */
        [ROCKS_BLOCK_TABULAR] = { 1.6f, 0.0f },           /* bed thickness; beds span the tile */
        [ROCKS_BLOCK_COLUMNAR] = { 2.4f, 0.0f },          /* column width; sets span the tile */
    };
    *spacing = table[type][0];
    *radius = table[type][1];
}

static void make_discs(const rocks_block_tile_desc *d, rng *r, disc_list *l) {
    const float s = d->size;
    float frame[3][3] = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } };
    switch (d->type) {
    case ROCKS_BLOCK_RHOMBOHEDRAL:
        /* each axis tilted 20–35° towards a random direction across it: mutually oblique sets */
        for (int a = 0; a < 3; a++) {
            float tilt[3];
            rng_direction(r, tilt);
            float along = dot3(tilt, frame[a]);
            for (int k = 0; k < 3; k++) tilt[k] -= along * frame[a][k];
            normalize3(tilt);
            float angle = rng_range(r, 0.35f, 0.61f);
            for (int k = 0; k < 3; k++) frame[a][k] = cosf(angle) * frame[a][k] + sinf(angle) * tilt[k];
        }
        /* fall through */
    case ROCKS_BLOCK_EQUIDIMENSIONAL:
        scattered_discs(r, l, s, d->fracture_spacing, 0.8f * d->fracture_radius, 1.2f * d->fracture_radius,
                        frame_normal, (const float(*)[3])frame);
        break;
    case ROCKS_BLOCK_POLYHEDRAL:
        scattered_discs(r, l, s, d->fracture_spacing, 0.6f * d->fracture_radius, 1.4f * d->fracture_radius,
                        random_normal, (const float(*)[3])frame);
        break;
    case ROCKS_BLOCK_TABULAR:
        /* bedding planes as wide as the tile (003 §4.1), cross joints of radius s / 10 */
        parallel_set(r, l, s, (const int[3]){ 0, 1, 0 }, d->fracture_spacing, s);
        scattered_discs(r, l, s, 1.8f * d->fracture_spacing, 0.08f * s, 0.12f * s, horizontal_axis_normal,
                        (const float(*)[3])frame);
        break;
    case ROCKS_BLOCK_COLUMNAR:
        /* three continuous vertical sets about 60° apart ((1,0,0), (1,0,2), (−1,0,2) in x, z)
         * make prisms; rare horizontal cross joints cut them into long columns */
        parallel_set(r, l, s, (const int[3]){ 1, 0, 0 }, d->fracture_spacing, s);
        parallel_set(r, l, s, (const int[3]){ 1, 0, 2 }, d->fracture_spacing, s);
        parallel_set(r, l, s, (const int[3]){ -1, 0, 2 }, d->fracture_spacing, s);
        scattered_discs(r, l, s, 3.0f * d->fracture_spacing, 0.15f * s, 0.25f * s, vertical_normal,
                        (const float(*)[3])frame);
        break;
    default: break;
    }
}

/* ---- visibility: does a fracture cut the segment a–b? ---------------------------------------- */

/* A disc image: a disc moved by whole tiles into some cluster's frame. */
typedef struct disc_image { float centre[3], normal[3], radius2; } disc_image;

static bool disc_cuts(const disc_image *d, const float a[3], const float b[3]) {
    float da = (a[0] - d->centre[0]) * d->normal[0] + (a[1] - d->centre[1]) * d->normal[1] +
               (a[2] - d->centre[2]) * d->normal[2];
    float db = (b[0] - d->centre[0]) * d->normal[0] + (b[1] - d->centre[1]) * d->normal[1] +
               (b[2] - d->centre[2]) * d->normal[2];
    if ((da > 0) == (db > 0) || da == db) return false;
    float t = da / (da - db), r2 = 0;
    for (int k = 0; k < 3; k++) {
        float x = a[k] + t * (b[k] - a[k]) - d->centre[k];
        r2 += x * x;
    }
    return r2 <= d->radius2;
}

/* The disc images that can cut a segment inside the ball (centre, reach). */
static size_t near_discs(const rocks_block_tile *tile, const float centre[3], float reach, disc_image **out,
                         size_t *cap) {
    const float s = tile->desc.size;
    size_t n = 0;
    for (uint32_t i = 0; i < tile->disc_count; i++) {
        const rocks_block_disc *d = &tile->discs[i];
        float base[3];
        min_image(centre, d->centre, s, base);   /* the nearest image, relative to centre */
        for (int o = 0; o < 27; o++) {
            float c[3] = { base[0] + s * (float)(o % 3 - 1), base[1] + s * (float)(o / 3 % 3 - 1),
                           base[2] + s * (float)(o / 9 - 1) };
            float along = dot3(c, d->normal), dist2 = dot3(c, c);
            /* the plane must pass within reach, and the disc's rim must reach the ball */
            if (fabsf(along) > reach) continue;
            float across = sqrtf(fmaxf(dist2 - along * along, 0.0f));
            if (across > d->radius + reach) continue;
            *out = core_grow(*out, cap, n + 1, sizeof **out);
            disc_image *img = &(*out)[n++];
            for (int k = 0; k < 3; k++) img->centre[k] = centre[k] + c[k], img->normal[k] = d->normal[k];
            img->radius2 = d->radius * d->radius;
        }
    }
    return n;
}

/* ---- clusters (003 §4.1) -------------------------------------------------------------------- */

typedef struct cluster_state {
    const rocks_block_tile *tile;
    const float (*points)[3];
    point_grid grid;
    int reach;                        /* grid cells within the neighbour distance */
    float neighbour2;
    int32_t *owner;                   /* cluster of each point, −1 free */
    /* the cluster being grown */
    float (*members)[3];              /* unwrapped positions */
    uint32_t *member_index;
    size_t member_count, member_cap, index_cap;
    uint32_t *queue;
    size_t queue_cap;
    disc_image *discs;
    size_t disc_count, disc_cap;
    int8_t *side;                     /* disc × member: which side of its plane */
    size_t side_cap;
    int32_t *side_count;              /* disc: members on the positive side */
    size_t side_count_cap;
    float seed[3], extent;
    /* neighbour search scratch */
    const float *from;
    uint32_t *found;
    size_t found_count, found_cap;
} cluster_state;

static float side_of(const disc_image *d, const float p[3]) {
    return (p[0] - d->centre[0]) * d->normal[0] + (p[1] - d->centre[1]) * d->normal[1] +
           (p[2] - d->centre[2]) * d->normal[2];
}

/* 003 §4.1: every point of a cluster sees every other (no disc cuts the segment). Only discs
 * whose plane has members on q's other side can cut, and only segments to those members. */
static bool visible_from_all(cluster_state *c, const float q[3]) {
    size_t m = c->member_count;
    for (size_t k = 0; k < c->disc_count; k++) {
        bool positive = side_of(&c->discs[k], q) > 0;
        size_t other = positive ? m - (size_t)c->side_count[k] : (size_t)c->side_count[k];
        if (other == 0) continue;
        const int8_t *sides = c->side + k * c->member_cap;
        for (size_t j = 0; j < m; j++)
            if ((sides[j] > 0) != positive && disc_cuts(&c->discs[k], q, c->members[j])) return false;
    }
    return true;
}

static void grow_side_table(cluster_state *c, size_t members) {
    if (members <= c->member_cap) return;
    size_t old_cap = c->member_cap, cap = old_cap ? old_cap : 64;
    while (cap < members) cap *= 2;
    int8_t *side = core_alloc(c->disc_count * cap + 1);
    if (c->side)
        for (size_t k = 0; k < c->disc_count; k++) memcpy(side + k * cap, c->side + k * old_cap, c->member_count);
    if (c->side) core_free(c->side, c->side_cap);
    c->side = side;
    c->side_cap = c->disc_count * cap + 1;
    c->members = core_realloc(c->members, old_cap * sizeof *c->members, cap * sizeof *c->members);
    c->member_cap = cap;
}

static void add_member(cluster_state *c, uint32_t index, const float p[3], int32_t cluster) {
    grow_side_table(c, c->member_count + 1);
    c->member_index = core_grow(c->member_index, &c->index_cap, c->member_count + 1, sizeof *c->member_index);
    memcpy(c->members[c->member_count], p, 3 * sizeof(float));
    c->member_index[c->member_count] = index;
    for (size_t k = 0; k < c->disc_count; k++) {
        bool positive = side_of(&c->discs[k], p) > 0;
        c->side[k * c->member_cap + c->member_count] = positive ? 1 : -1;
        c->side_count[k] += positive;
    }
    c->member_count++;
    c->owner[index] = cluster;
}

static bool collect_neighbour(void *user, int32_t j) {
    cluster_state *c = user;
    float d[3];
    min_image(c->from, c->points[j], c->tile->desc.size, d);
    if (dot3(d, d) < c->neighbour2 && c->owner[j] < 0) {
        c->found = core_grow(c->found, &c->found_cap, c->found_count + 1, sizeof *c->found);
        c->found[c->found_count++] = (uint32_t)j;
    }
    return true;
}

/* Grows cluster `id` from point `start` breadth-first over the neighbour graph (edges shorter
 * than twice the Poisson radius), taking a neighbour when every member sees it. */
static void grow_cluster(cluster_state *c, uint32_t start, int32_t id) {
    const float s = c->tile->desc.size;
    memcpy(c->seed, c->points[start], sizeof c->seed);
    c->member_count = 0;
    c->disc_count = near_discs(c->tile, c->seed, c->extent + 2.0f * sqrtf(c->neighbour2), &c->discs, &c->disc_cap);
    c->side_count = core_grow(c->side_count, &c->side_count_cap, c->disc_count + 1, sizeof *c->side_count);
    memset(c->side_count, 0, (c->disc_count + 1) * sizeof *c->side_count);
    if (c->side) core_free(c->side, c->side_cap);
    c->side = NULL, c->side_cap = 0;
    if (c->members) core_free(c->members, c->member_cap * sizeof *c->members);
    c->members = NULL, c->member_cap = 0;
    add_member(c, start, c->seed, id);
    for (size_t head = 0; head < c->member_count; head++) {
        float from_unwrapped[3];   /* a copy: adding members may move the array */
        memcpy(from_unwrapped, c->members[head], sizeof from_unwrapped);
        c->from = c->points[c->member_index[head]];
        c->found_count = 0;
        grid_visit(&c->grid, c->from, c->reach, collect_neighbour, c);
        for (size_t f = 0; f < c->found_count; f++) {
            uint32_t j = c->found[f];
            if (c->owner[j] >= 0) continue;   /* taken since (or listed twice) */
            float d[3], q[3], e[3];
            min_image(c->from, c->points[j], s, d);
            for (int a = 0; a < 3; a++) q[a] = from_unwrapped[a] + d[a], e[a] = q[a] - c->seed[a];
            if (dot3(e, e) > c->extent * c->extent) continue;   /* bounded: see extent */
            if (visible_from_all(c, q)) add_member(c, j, q, id);
        }
    }
}

/* ---- convex hull and planes (003 §4.2) ------------------------------------------------------ */

typedef struct hull_face { int v[3]; float n[3], d, area; bool live; } hull_face;

static bool make_face(const float (*p)[3], int a, int b, int c, hull_face *f) {
    float u[3], w[3];
    for (int k = 0; k < 3; k++) u[k] = p[b][k] - p[a][k], w[k] = p[c][k] - p[a][k];
    float n[3] = { u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0] };
    float l = sqrtf(dot3(n, n));
    if (!(l > 1e-9f)) return false;
    *f = (hull_face){ .v = { a, b, c }, .n = { n[0] / l, n[1] / l, n[2] / l }, .area = 0.5f * l, .live = true };
    f->d = dot3(f->n, p[a]);
    return true;
}

/* Incremental 3D hull of n points (n ≤ MAX_HULL_POINTS): the faces, outward. 0 when the points
 * are (nearly) coplanar. Each point removes the faces it sees and joins their horizon. */
static size_t convex_hull(const float (*p)[3], int n, float eps, hull_face **faces_out, size_t *cap) {
    if (n < 4) return 0;
    /* a first tetrahedron: two far points, the farthest from their line, the farthest from that plane */
    int i0 = 0, i1 = 0, i2 = -1, i3 = -1;
    for (int i = 1; i < n; i++)
        if (p[i][0] < p[i0][0]) i0 = i;
    float best = -1;
    for (int i = 0; i < n; i++) {
        float d[3] = { p[i][0] - p[i0][0], p[i][1] - p[i0][1], p[i][2] - p[i0][2] };
        if (dot3(d, d) > best) best = dot3(d, d), i1 = i;
    }
    best = eps * eps;
    for (int i = 0; i < n; i++) {
        hull_face f;
        if (make_face(p, i0, i1, i, &f) && 2.0f * f.area > best) best = 2.0f * f.area, i2 = i;
    }
    if (i2 < 0) return 0;
    hull_face base;
    make_face(p, i0, i1, i2, &base);
    best = eps;
    for (int i = 0; i < n; i++) {
        float h = fabsf(dot3(base.n, p[i]) - base.d);
        if (h > best) best = h, i3 = i;
    }
    if (i3 < 0) return 0;
    if (dot3(base.n, p[i3]) - base.d > 0) { int t = i1; i1 = i2; i2 = t; }   /* i3 behind the base */
    size_t count = 0;
    hull_face *faces = *faces_out;
    const int tet[4][3] = { { i0, i1, i2 }, { i0, i3, i1 }, { i1, i3, i2 }, { i2, i3, i0 } };
    for (int f = 0; f < 4; f++) {
        faces = core_grow(faces, cap, count + 1, sizeof *faces);
        make_face(p, tet[f][0], tet[f][1], tet[f][2], &faces[count++]);
    }
    int horizon[2 * 3 * 4 * MAX_HULL_POINTS];
    for (int i = 0; i < n; i++) {
        if (i == i0 || i == i1 || i == i2 || i == i3) continue;
        int edges = 0;
        bool seen = false;
        for (size_t f = 0; f < count; f++) {
            if (!faces[f].live || dot3(faces[f].n, p[i]) - faces[f].d <= eps) continue;
            seen = true;
            faces[f].live = false;
            for (int e = 0; e < 3 && edges < (int)(sizeof horizon / sizeof *horizon) / 2; e++) {
                int a = faces[f].v[e], b = faces[f].v[(e + 1) % 3];
                int k;   /* an edge seen from both sides is inside the visible region: drop it */
                for (k = 0; k < edges; k++)
                    if (horizon[2 * k] == b && horizon[2 * k + 1] == a) break;
                if (k < edges) horizon[2 * k] = horizon[2 * (edges - 1)], horizon[2 * k + 1] = horizon[2 * (edges - 1) + 1], edges--;
                else horizon[2 * edges] = a, horizon[2 * edges + 1] = b, edges++;
            }
        }
        if (!seen) continue;
        for (int e = 0; e < edges; e++) {
            faces = core_grow(faces, cap, count + 1, sizeof *faces);
            if (make_face(p, horizon[2 * e], horizon[2 * e + 1], i, &faces[count])) count++;
        }
        /* compact now and then so the dead faces do not pile up */
        if (count > 8 * (size_t)n) {
            size_t w = 0;
            for (size_t f = 0; f < count; f++)
                if (faces[f].live) faces[w++] = faces[f];
            count = w;
        }
    }
    size_t w = 0;
    for (size_t f = 0; f < count; f++)
        if (faces[f].live) faces[w++] = faces[f];
    *faces_out = faces;
    return w;
}

static int by_area_desc(const void *a, const void *b) {
    float x = ((const hull_face *)a)->area, y = ((const hull_face *)b)->area;
    return (x < y) - (x > y);
}

/* The hull's faces merged into planes: faces within ~18° share one plane whose normal is their
 * area-weighted mean and whose offset supports every point, pushed out by `push` (the points
 * stop about a Poisson radius short of a fracture; the push closes that to the joint). */
static size_t hull_planes(const float (*p)[3], int n, hull_face *faces, size_t face_count, float push,
                          float (*planes)[4], size_t max_planes) {
    qsort(faces, face_count, sizeof *faces, by_area_desc);
    size_t count = 0;
    float sum[64][3];
    if (max_planes > 64) max_planes = 64;
    for (size_t f = 0; f < face_count; f++) {
        size_t k;
        for (k = 0; k < count; k++) {
            float m[3] = { sum[k][0], sum[k][1], sum[k][2] };
            normalize3(m);
            if (dot3(m, faces[f].n) > MERGE_COS) break;
        }
        if (k == count) {
            if (count == max_planes) continue;
            sum[count][0] = sum[count][1] = sum[count][2] = 0;
            count++;
        }
        for (int a = 0; a < 3; a++) sum[k][a] += faces[f].area * faces[f].n[a];
    }
    for (size_t k = 0; k < count; k++) {
        normalize3(sum[k]);
        float d = -INFINITY;
        for (int i = 0; i < n; i++) d = fmaxf(d, dot3(sum[k], p[i]));
        planes[k][0] = sum[k][0], planes[k][1] = sum[k][1], planes[k][2] = sum[k][2], planes[k][3] = d + push;
    }
    return count;
}

/* A hull plane that lies along a fracture the cluster stops at becomes that fracture's plane,
 * set back half a joint: the face is then as flat as the fracture, and the block across it
 * stops half a joint on its side (the hull of Poisson points alone leaves faces tilted by up to
 * a point spacing over a block's width). `shift` moves the cluster's frame to the block's. */
static void snap_to_fractures(float (*planes)[4], size_t count, const float (*p)[3], int n, const disc_image *discs,
                              size_t disc_count, const float shift[3], float spacing, float joint) {
    for (size_t k = 0; k < count; k++) {
        float best = 0.9f, snapped[4];   /* within ~25° */
        for (size_t j = 0; j < disc_count; j++) {
            float along = dot3(planes[k], discs[j].normal);
            if (fabsf(along) <= best) continue;
            float nd[3], sign = along > 0 ? 1.0f : -1.0f, support = -INFINITY;
            for (int a = 0; a < 3; a++) nd[a] = sign * discs[j].normal[a];
            float offset = dot3(nd, discs[j].centre) + dot3(nd, shift);
            for (int i = 0; i < n; i++) support = fmaxf(support, dot3(nd, p[i]));
            /* a fracture just past the cluster's outermost points (so the plane, half a joint
             * short of it, still holds every point of the cluster) */
            if (!(offset - 0.5f * joint >= support && offset <= support + 1.5f * spacing)) continue;
            best = fabsf(along);
            snapped[0] = nd[0], snapped[1] = nd[1], snapped[2] = nd[2], snapped[3] = offset - 0.5f * joint;
        }
        if (best > 0.9f) memcpy(planes[k], snapped, sizeof snapped);
    }
}

/* Merging can leave a thin cluster's planes open in some direction (their normals no longer
 * surround it). Where one of 14 directions (axes, diagonals) has no plane facing it, the
 * cluster's box planes are added: every block is then bounded. */
static size_t close_block(float (*planes)[4], size_t count, const float (*p)[3], int n, float push) {
    bool open = count < 4;
    for (int v = 0; v < 14 && !open; v++) {
        float dir[3] = { 0, 0, 0 };
        if (v < 6) dir[v / 2] = v % 2 ? -1.0f : 1.0f;
        else for (int a = 0; a < 3; a++) dir[a] = ((v - 6) >> a & 1) ? -0.57735f : 0.57735f;
        float best = -1.0f;
        for (size_t k = 0; k < count; k++) best = fmaxf(best, dot3(planes[k], dir));
        open = best < 0.3f;
    }
    if (!open || count + 6 > 64) return count;
    for (int a = 0; a < 3; a++)
        for (int sign = -1; sign <= 1; sign += 2) {
            float *pl = planes[count++], d = -INFINITY;
            pl[0] = pl[1] = pl[2] = 0;
            pl[a] = (float)sign;
            for (int i = 0; i < n; i++) d = fmaxf(d, (float)sign * p[i][a]);
            pl[3] = d + push;
        }
    return count;
}

/* ---- the block field ------------------------------------------------------------------------ */

/* The convex base c(p): the planes' smooth intersection, folded in order, with its gradient
 * (∂/∂a of min(a, b) − R k³/6 is 1 − k²/2 for the smaller argument, k²/2 for the other). */
static float base_field(const float (*planes)[4], uint32_t count, float rounding, const float p[3], float g[3]) {
    float value = planes[0][3] - dot3(planes[0], p);
    float grad[3] = { -planes[0][0], -planes[0][1], -planes[0][2] };
    for (uint32_t k = 1; k < count; k++) {
        float h = planes[k][3] - dot3(planes[k], p);
        float kk = fmaxf(1.0f - fabsf(value - h) / rounding, 0.0f);
        float w_small = 1.0f - 0.5f * kk * kk, w_large = 0.5f * kk * kk;
        float w_value = value <= h ? w_small : w_large, w_h = value <= h ? w_large : w_small;
        for (int a = 0; a < 3; a++) grad[a] = w_value * grad[a] - w_h * planes[k][a];
        value = fminf(value, h) - rounding * kk * kk * kk / 6.0f;
    }
    if (g) memcpy(g, grad, sizeof grad);
    return value;
}

/* A block placed by hand: its own field; the gradient by central differences. */
static float custom_field(const rocks_block_custom *c, const float p[3], float gradient[3]) {
    float v = c->field(c->user, p);
    if (gradient) {
        const float h = 1e-3f;
        for (int a = 0; a < 3; a++) {
            float lo[3] = { p[0], p[1], p[2] }, hi[3] = { p[0], p[1], p[2] };
            lo[a] -= h, hi[a] += h;
            gradient[a] = (c->field(c->user, hi) - c->field(c->user, lo)) / (2 * h);
        }
        normalize3(gradient);
    }
    return v;
}

float rocks_block_field(const rocks_block_tile *tile, uint32_t block, const float p[3], float gradient[3]) {
    const rocks_block *b = &tile->blocks[block];
    if (b->custom) return custom_field(&tile->desc.custom[b->custom - 1], p, gradient);
    const float (*planes)[4] = (const float(*)[4])tile->planes + b->plane_first;
    float g[3];
    float c = base_field(planes, b->plane_count, tile->desc.rounding, p, g);
    normalize3(g);
    if (gradient) memcpy(gradient, g, sizeof g);
    if (tile->desc.relief <= 0.0f) return c;
    /* 003 §4.2: ω⁻¹(p) = p + δ(p), δ = g Σᵢ |g·uᵢ| d(γᵢ(p)), the relief d seen on the three axis
     * planes (tri-planar), each weighted by how much the surface faces that axis */
    const float inv = 1.0f / tile->desc.relief_scale;
    uint64_t seed = core_hash_combine(tile->desc.seed, block);
    float d = fabsf(g[2]) * terrain_noise3(seed, p[0] * inv, p[1] * inv, 0.0f) +
              fabsf(g[1]) * terrain_noise3(seed, p[0] * inv, p[2] * inv, 17.0f) +
              fabsf(g[0]) * terrain_noise3(seed, p[1] * inv, p[2] * inv, 34.0f);
    float q[3];
    for (int a = 0; a < 3; a++) q[a] = p[a] + g[a] * d * tile->desc.relief;
    return base_field(planes, b->plane_count, tile->desc.rounding, q, NULL);
}

/* ---- building a tile ------------------------------------------------------------------------ */

static bool desc_make(const rocks_block_tile_desc *in, rocks_block_tile_desc *d) {
    *d = in ? *in : (rocks_block_tile_desc){ 0 };
    if (d->type == ROCKS_BLOCK_DEFAULT) d->type = ROCKS_BLOCK_EQUIDIMENSIONAL;
    if ((unsigned)d->type >= ROCKS_BLOCK_TYPE_END) {
        core_log_error("rocks", "block tile: type %d is not a block type (0 … %d)", (int)d->type, ROCKS_BLOCK_TYPE_END - 1);
        return false;
    }
    float spacing, radius;
    rocks__block_type_defaults(d->type, &spacing, &radius);
    if (!d->seed) d->seed = 1;
    if (d->size == 0) d->size = 16.0f;
    if (d->point_spacing == 0) d->point_spacing = d->size / 24.0f;
    if (d->fracture_spacing == 0) d->fracture_spacing = spacing;
    if (d->fracture_radius == 0) d->fracture_radius = radius;
    if (d->rounding == 0) d->rounding = 0.25f;
    if (d->joint == 0) d->joint = 0.15f;
    if (d->relief == 0) d->relief = 0.08f;
    if (d->relief_scale == 0) d->relief_scale = 0.8f;
    const char *bad = NULL;
    if (!(d->size >= 4.0f && d->size <= 64.0f)) bad = "size (4 … 64 m)";
    else if (!(d->point_spacing >= d->size / 48.0f && d->point_spacing <= d->size / 4.0f)) bad = "point_spacing (s/48 … s/4)";
    else if (!(d->fracture_spacing >= 2.0f * d->point_spacing && d->fracture_spacing <= d->size)) bad = "fracture_spacing (2 point spacings … s)";
    else if (!(d->fracture_radius >= 0.0f && d->fracture_radius <= 4.0f * d->size)) bad = "fracture_radius (0 … 4 s)";
    else if (!(d->rounding > 0.0f && d->rounding <= 4.0f)) bad = "rounding (0 … 4 m)";
    else if (!(d->joint >= 0.0f && d->joint <= d->point_spacing)) bad = "joint (0 … point_spacing)";
    else if (!(d->relief <= 1.0f)) bad = "relief (≤ 1 m)";
    else if (!(d->relief_scale > 0.05f && d->relief_scale <= d->size)) bad = "relief_scale (0.05 m … s)";
    else if (d->custom_count < 0 || d->custom_count > ROCKS_BLOCK_MAX_CUSTOM || (d->custom_count && !d->custom))
        bad = "custom blocks (0 … 64, with their array)";
    for (int k = 0; !bad && k < d->custom_count; k++) {
        const rocks_block_custom *c = &d->custom[k];
        bool box = c->field != NULL;
        for (int a = 0; a < 3; a++) {
            float centre = 0.5f * (c->bounds_min[a] + c->bounds_max[a]);
            box &= c->bounds_min[a] <= c->bounds_max[a] && c->bounds_max[a] - c->bounds_min[a] < d->size &&
                   centre >= 0.0f && centre < d->size;
        }
        if (!box) bad = "custom block (a field, and bounds smaller than the tile centred inside it)";
    }
    if (bad) {
        core_log_error("rocks", "block tile: bad %s", bad);
        return false;
    }
    return true;
}

/* The lookup grid: for each of grid³ cells of the tile, the blocks (and which of their 27
 * copies, this tile's or a neighbour's) whose bounds reach it. */
int rocks__block_grid_cells(float size) { return (int)fmaxf(1.0f, floorf(size / 2.0f)); }

static void build_grid(rocks_block_tile *t) {
    const float s = t->desc.size;
    int g = t->grid = rocks__block_grid_cells(s);
    size_t cells = (size_t)g * g * g;
    uint32_t *count = core_calloc(cells + 1, sizeof *count);
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t b = 0; b < t->block_count; b++)
            for (int o = 0; o < 27; o++) {
                int lo[3], hi[3];
                bool empty = false;
                for (int a = 0; a < 3; a++) {
                    float off = s * (float)((a == 0 ? o % 3 : a == 1 ? o / 3 % 3 : o / 9) - 1);
                    lo[a] = (int)floorf((t->blocks[b].bounds_min[a] + off) / s * (float)g);
                    hi[a] = (int)floorf((t->blocks[b].bounds_max[a] + off) / s * (float)g);
                    if (lo[a] < 0) lo[a] = 0;
                    if (hi[a] > g - 1) hi[a] = g - 1;
                    empty |= lo[a] > hi[a];
                }
                if (empty) continue;
                for (int z = lo[2]; z <= hi[2]; z++)
                    for (int y = lo[1]; y <= hi[1]; y++)
                        for (int x = lo[0]; x <= hi[0]; x++) {
                            size_t cell = ((size_t)z * g + y) * g + x;
                            if (pass == 0) count[cell + 1]++;
                            else t->grid_entries[count[cell]++] = b << 5 | (uint32_t)o;
                        }
            }
        if (pass == 0) {
            for (size_t c = 0; c < cells; c++) count[c + 1] += count[c];
            t->grid_entry_count = count[cells];
            t->grid_entries = core_alloc((t->grid_entry_count + 1) * sizeof *t->grid_entries);
            t->grid_first = core_alloc((cells + 1) * sizeof *t->grid_first);
            memcpy(t->grid_first, count, (cells + 1) * sizeof *count);
        }
    }
    core_free(count, (cells + 1) * sizeof *count);
}

/* Turns cluster `members` into block number t->block_count: its points (moved so the anchor is
 * in the tile), its hull's planes and bounds. False when the cluster has no volume. */
static bool add_block(rocks_block_tile *t, const float (*members)[3], size_t n, const disc_image *discs,
                      size_t disc_count, size_t *plane_cap, size_t *point_cap, hull_face **faces, size_t *face_cap) {
    const float s = t->desc.size;
    float centroid[3] = { 0, 0, 0 }, shift[3];
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) centroid[a] += members[i][a] / (float)n;
    for (int a = 0; a < 3; a++) shift[a] = -s * floorf(centroid[a] / s);
    float (*p)[3] = core_alloc(n * sizeof *p);
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) p[i][a] = members[i][a] + shift[a];
    /* big clusters enter the hull through an even subsample: the hull changes by under a
     * Poisson radius, and the incremental hull stays quadratic in a bounded count */
    float (*h)[3] = p;
    int hn = (int)n;
    float sub[MAX_HULL_POINTS][3];
    if (n > MAX_HULL_POINTS) {
        for (int i = 0; i < MAX_HULL_POINTS; i++) memcpy(sub[i], p[(size_t)i * n / MAX_HULL_POINTS], sizeof sub[i]);
        h = sub, hn = MAX_HULL_POINTS;
    }
    size_t face_count = convex_hull((const float(*)[3])h, hn, 1e-3f, faces, face_cap);
    if (face_count < 4) {
        core_free(p, n * sizeof *p);
        return false;
    }
    float planes[64][4];
    float push = fmaxf(0.0f, 0.5f * (t->desc.point_spacing - t->desc.joint));
    size_t plane_count = hull_planes((const float(*)[3])p, (int)n, *faces, face_count, push, planes, 64);
    snap_to_fractures(planes, plane_count, (const float(*)[3])p, (int)n, discs, disc_count, shift,
                      t->desc.point_spacing, t->desc.joint);
    plane_count = close_block(planes, plane_count, (const float(*)[3])p, (int)n, push);
    rocks_block *b = &t->blocks[t->block_count];
    *b = (rocks_block){ .plane_first = t->plane_count, .plane_count = (uint32_t)plane_count,
                        .point_first = t->point_count, .point_count = (uint32_t)n };
    for (int a = 0; a < 3; a++) {
        b->anchor[a] = centroid[a] + shift[a];
        b->bounds_min[a] = INFINITY, b->bounds_max[a] = -INFINITY;
    }
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            b->bounds_min[a] = fminf(b->bounds_min[a], p[i][a]);
            b->bounds_max[a] = fmaxf(b->bounds_max[a], p[i][a]);
        }
    float grow = push + fmaxf(t->desc.relief, 0.0f) + BOUNDS_MARGIN;
    for (int a = 0; a < 3; a++) b->bounds_min[a] -= grow, b->bounds_max[a] += grow;
    t->planes = core_grow(t->planes, plane_cap, t->plane_count + plane_count, sizeof *t->planes);
    memcpy(t->planes + t->plane_count, planes, plane_count * sizeof *planes);
    t->plane_count += (uint32_t)plane_count;
    t->points = core_grow(t->points, point_cap, t->point_count + n, sizeof *t->points);
    memcpy(t->points + t->point_count, p, n * sizeof *p);
    t->point_count += (uint32_t)n;
    t->block_count++;
    core_free(p, n * sizeof *p);
    return true;
}

/* Block number t->block_count is the developer's block k: the sample points it holds (any of
 * their 27 copies, within a joint) are taken from the clusters and become its points. */
static void add_custom_block(rocks_block_tile *t, int k, const float (*points)[3], int32_t *owner, size_t *point_cap) {
    const rocks_block_custom *c = &t->desc.custom[k];
    const float s = t->desc.size, reach = t->desc.joint;
    rocks_block *b = &t->blocks[t->block_count];
    *b = (rocks_block){ .point_first = t->point_count, .custom = (uint32_t)k + 1 };
    for (int a = 0; a < 3; a++) {
        b->anchor[a] = 0.5f * (c->bounds_min[a] + c->bounds_max[a]);
        b->bounds_min[a] = c->bounds_min[a] - BOUNDS_MARGIN;
        b->bounds_max[a] = c->bounds_max[a] + BOUNDS_MARGIN;
    }
    for (uint32_t i = 0; i < t->sample_count; i++) {
        if (owner[i] >= 0) continue;
        for (int o = 0; o < 27; o++) {
            float q[3] = { points[i][0] + s * (float)(o % 3 - 1), points[i][1] + s * (float)(o / 3 % 3 - 1),
                           points[i][2] + s * (float)(o / 9 - 1) };
            bool near = true;
            for (int a = 0; a < 3; a++) near &= q[a] >= c->bounds_min[a] - reach && q[a] <= c->bounds_max[a] + reach;
            if (!near || c->field(c->user, q) <= -reach) continue;
            owner[i] = INT32_MAX;   /* taken: no cluster grows into the developer's block */
            t->points = core_grow(t->points, point_cap, t->point_count + 1, sizeof *t->points);
            memcpy(t->points[t->point_count++], q, sizeof q);
            b->point_count++;
            break;
        }
    }
    t->block_count++;
}

/* The tile of desc `d` (defaults filled, checked), built. */
static rocks_block_tile *build_tile(const rocks_block_tile_desc *desc) {
    const rocks_block_tile_desc d = *desc;
    uint64_t start = core_time_ns();
    rocks_block_tile *t = core_calloc(1, sizeof *t);
    t->desc = d;
    if (d.custom_count) {   /* the tile keeps its own copy */
        rocks_block_custom *copy = core_alloc((size_t)d.custom_count * sizeof *copy);
        memcpy(copy, d.custom, (size_t)d.custom_count * sizeof *copy);
        t->desc.custom = copy;
    }
    /* The type's number counted from equidimensional = 0, as before DEFAULT took the zero: the
     * same seed and type make the same blocks as they did. */
    rng r = { core_hash_combine(d.seed, (uint64_t)(d.type - ROCKS_BLOCK_EQUIDIMENSIONAL)) };

    disc_list discs = { 0 };
    make_discs(&d, &r, &discs);
    t->discs = discs.items, t->disc_count = (uint32_t)discs.count;

    cluster_state c = { .tile = t };
    float (*points)[3];
    t->sample_count = poisson_points(&r, d.size, d.point_spacing, &points, &c.grid);
    c.points = (const float(*)[3])points;
    c.neighbour2 = 4.0f * d.point_spacing * d.point_spacing;
    c.reach = (int)ceilf(2.0f * d.point_spacing / c.grid.cell);
    /* A cluster's reach from its first point: large enough for the type's blocks, small enough
     * that a cluster never meets its own copy across the torus (2 × extent < s). */
    c.extent = 0.45f * d.size;
    c.owner = core_alloc(t->sample_count * sizeof *c.owner);
    for (uint32_t i = 0; i < t->sample_count; i++) c.owner[i] = -1;
    /* 003 §4.1: clusters start from random points */
    uint32_t *order = core_alloc(t->sample_count * sizeof *order);
    for (uint32_t i = 0; i < t->sample_count; i++) order[i] = i;
    for (uint32_t i = t->sample_count; i > 1; i--) {
        uint32_t j = (uint32_t)(rng_next(&r) % i), tmp = order[i - 1];
        order[i - 1] = order[j], order[j] = tmp;
    }
    size_t block_cap = 0, plane_cap = 0, point_cap = 0, face_cap = 0;
    hull_face *faces = NULL;
    for (int k = 0; k < d.custom_count; k++) {
        t->blocks = core_grow(t->blocks, &block_cap, t->block_count + 1, sizeof *t->blocks);
        add_custom_block(t, k, (const float(*)[3])points, c.owner, &point_cap);
    }
    int32_t clusters = 0;
    for (uint32_t o = 0; o < t->sample_count; o++) {
        if (c.owner[order[o]] >= 0) continue;
        grow_cluster(&c, order[o], clusters++);
        t->blocks = core_grow(t->blocks, &block_cap, t->block_count + 1, sizeof *t->blocks);
        add_block(t, (const float(*)[3])c.members, c.member_count, c.discs, c.disc_count, &plane_cap, &point_cap,
                  &faces, &face_cap);
    }
    build_grid(t);
    t->build_seconds = (double)(core_time_ns() - start) * 1e-9;

    core_free(order, t->sample_count * sizeof *order);
    core_free(c.owner, t->sample_count * sizeof *c.owner);
    core_free(points, (size_t)c.grid.g * c.grid.g * c.grid.g * sizeof *points);
    core_free(c.grid.slot, (size_t)c.grid.g * c.grid.g * c.grid.g * sizeof *c.grid.slot);
    if (c.members) core_free(c.members, c.member_cap * sizeof *c.members);
    if (c.side) core_free(c.side, c.side_cap);
    core_free(c.member_index, c.index_cap * sizeof *c.member_index);
    core_free(c.side_count, c.side_count_cap * sizeof *c.side_count);
    core_free(c.discs, c.disc_cap * sizeof *c.discs);
    core_free(c.found, c.found_cap * sizeof *c.found);
    core_free(faces, face_cap * sizeof *faces);
    /* shrink-to-fit so destroy knows the sizes */
    t->blocks = core_realloc(t->blocks, block_cap * sizeof *t->blocks, (t->block_count + 1) * sizeof *t->blocks);
    t->planes = core_realloc(t->planes, plane_cap * sizeof *t->planes, (t->plane_count + 1) * sizeof *t->planes);
    t->points = core_realloc(t->points, point_cap * sizeof *t->points, (t->point_count + 1) * sizeof *t->points);
    t->discs = core_realloc(t->discs, discs.cap * sizeof *t->discs, (t->disc_count + 1) * sizeof *t->discs);
    return t;
}

/* ---- a block's smallest width (what a coarse field can show of it) ------------------------- */

/* The extent of points `v` along unit normal n: max − min of n·v. */
static double extent_along(const float n[3], const double (*v)[3], size_t count) {
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < count; i++) {
        double d = (double)n[0] * v[i][0] + (double)n[1] * v[i][1] + (double)n[2] * v[i][2];
        lo = fmin(lo, d), hi = fmax(hi, d);
    }
    return hi - lo;
}

/* The corners of a convex block: the points where three of its planes meet inside all the others
 * (n·v ≤ d + 1 mm), into `out` (room for `capacity`); returns how many. */
static size_t block_corners(const float (*planes)[4], uint32_t count, double (*out)[3], size_t capacity) {
    size_t corners = 0;
    for (uint32_t i = 0; i < count; i++)
        for (uint32_t j = i + 1; j < count; j++)
            for (uint32_t k = j + 1; k < count && corners < capacity; k++) {
                const float *a = planes[i], *b = planes[j], *c = planes[k];
                double bc[3] = { (double)b[1] * c[2] - (double)b[2] * c[1], (double)b[2] * c[0] - (double)b[0] * c[2],
                                 (double)b[0] * c[1] - (double)b[1] * c[0] };
                double ca[3] = { (double)c[1] * a[2] - (double)c[2] * a[1], (double)c[2] * a[0] - (double)c[0] * a[2],
                                 (double)c[0] * a[1] - (double)c[1] * a[0] };
                double ab[3] = { (double)a[1] * b[2] - (double)a[2] * b[1], (double)a[2] * b[0] - (double)a[0] * b[2],
                                 (double)a[0] * b[1] - (double)a[1] * b[0] };
                double det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
                if (fabs(det) < 1e-6) continue;   /* two of them (nearly) parallel: no corner */
                double v[3];
                for (int e = 0; e < 3; e++) v[e] = ((double)a[3] * bc[e] + (double)b[3] * ca[e] + (double)c[3] * ab[e]) / det;
                bool inside = true;
                for (uint32_t m = 0; inside && m < count; m++)
                    inside = planes[m][0] * v[0] + planes[m][1] * v[1] + planes[m][2] * v[2] <= planes[m][3] + 1e-3;
                if (inside) memcpy(out[corners++], v, sizeof v);
            }
    return corners;
}

/* A block's smallest width: the least, over its planes' normals, of its extent along the normal
 * (between its corners). For a box or a prism that is its thickness; for other shapes the true
 * least width may lie between two edges and be smaller (a regular tetrahedron: 0.71 against 0.82
 * of its edge), so the coarse fields' rule errs towards keeping a block, by that much at most.
 * The smooth intersection (R/6 at an edge) and the relief (±8 cm) are left out: centimetres
 * against the metres the rule compares. A block without corners (never seen: every block is
 * closed by close_block) takes its points' extent instead. A block placed by hand: the smallest
 * side of its box (the developer's bounds, which hold its solid part). */
float rocks__block_width(const rocks_block_tile *t, uint32_t index) {
    const rocks_block *b = &t->blocks[index];
    if (b->custom) {
        const rocks_block_custom *c = &t->desc.custom[b->custom - 1];
        return fminf(fminf(c->bounds_max[0] - c->bounds_min[0], c->bounds_max[1] - c->bounds_min[1]),
                     c->bounds_max[2] - c->bounds_min[2]);
    }
    const float (*planes)[4] = (const float(*)[4])t->planes + b->plane_first;
    enum { MAX_CORNERS = 512 };
    double corners[MAX_CORNERS][3];
    size_t count = block_corners(planes, b->plane_count, corners, MAX_CORNERS);
    if (count < 4) {   /* not a solid: measure its points */
        count = b->point_count < MAX_CORNERS ? b->point_count : MAX_CORNERS;
        for (size_t i = 0; i < count; i++)
            for (int a = 0; a < 3; a++) corners[i][a] = t->points[b->point_first + i][a];
    }
    double width = INFINITY;
    for (uint32_t k = 0; k < b->plane_count; k++)
        width = fmin(width, extent_along(planes[k], (const double(*)[3])corners, count));
    return count ? (float)width : 0.0f;
}

float rocks__coarse_min_width(float spacing) {
    return spacing <= TERRAIN_COLUMN_SIZE ? -INFINITY : ROCKS__COARSE_MIN_WIDTH * spacing;
}

float rocks__coarse_erosion(float width, float spacing) {
    if (spacing <= TERRAIN_COLUMN_SIZE) return 0.0f;       /* level 0: every block as it is */
    if (!(width > rocks__coarse_min_width(spacing))) return INFINITY;
    return fmaxf(0.0f, spacing - 0.5f * width);            /* h − w/2: 2(w − h) of w left */
}

/* The tile copies a box can meet come from the union of the blocks' bounds (rocks__cell_range):
 * worked out once, not per field; so are the blocks' widths (derived, so not in the cache file). */
static rocks_block_tile *tile_finish(rocks_block_tile *t) {
    t->widths = core_alloc((t->block_count + 1) * sizeof *t->widths);
    for (uint32_t b = 0; b < t->block_count; b++) t->widths[b] = rocks__block_width(t, b);
    for (int a = 0; a < 3; a++) t->reach_min[a] = 0.0f, t->reach_max[a] = 0.0f;
    for (uint32_t b = 0; b < t->block_count; b++)
        for (int a = 0; a < 3; a++) {
            t->reach_min[a] = fminf(t->reach_min[a], t->blocks[b].bounds_min[a]);
            t->reach_max[a] = fmaxf(t->reach_max[a], t->blocks[b].bounds_max[a]);
        }
    return t;
}

rocks_block_tile *rocks_block_tile_create(const rocks_block_tile_desc *desc) {
    rocks_block_tile_desc d;
    if (!desc_make(desc, &d)) return NULL;
    /* a tile with custom blocks is never cached: their fields are function pointers */
    const char *path = d.custom_count ? NULL : d.cache_path;
    d.cache_path = NULL;   /* the tile's desc does not keep the caller's string */
    const char *why = NULL;
    if (path) {
        rocks_block_tile *t = core_calloc(1, sizeof *t);
        if (rocks__block_cache_read(path, &d, t, &why)) {
            t->from_cache = true;   /* build_seconds stays 0, as for a tile set read back */
            return tile_finish(t);
        }
        core_free(t, sizeof *t);
    }
    rocks_block_tile *t = tile_finish(build_tile(&d));
    if (path) {
        bool written = rocks__block_cache_write(path, t);
        core_warn("rocks", "block tile cache %s: %s; rebuilt in %.2f s%s", path, why ? why : "not read",
                  t->build_seconds, written ? " and rewrote it" : " (could not rewrite it)");
    }
    return t;
}

void rocks__block_tile_free_arrays(rocks_block_tile *t) {
    size_t cells = (size_t)t->grid * t->grid * t->grid;
    if (t->blocks) core_free(t->blocks, (t->block_count + 1) * sizeof *t->blocks);
    if (t->planes) core_free(t->planes, (t->plane_count + 1) * sizeof *t->planes);
    if (t->points) core_free(t->points, (t->point_count + 1) * sizeof *t->points);
    if (t->discs) core_free(t->discs, (t->disc_count + 1) * sizeof *t->discs);
    if (t->grid_first) core_free(t->grid_first, (cells + 1) * sizeof *t->grid_first);
    if (t->grid_entries) core_free(t->grid_entries, (t->grid_entry_count + 1) * sizeof *t->grid_entries);
    if (t->widths) core_free(t->widths, (t->block_count + 1) * sizeof *t->widths);
    t->blocks = NULL, t->planes = NULL, t->points = NULL, t->discs = NULL;
    t->grid_first = NULL, t->grid_entries = NULL, t->widths = NULL;
}

void rocks_block_tile_destroy(rocks_block_tile *t) {
    if (!t) return;
    rocks__block_tile_free_arrays(t);
    if (t->desc.custom_count) core_free((void *)t->desc.custom, (size_t)t->desc.custom_count * sizeof *t->desc.custom);
    core_free(t, sizeof *t);
}

/* ---- replication (003 §5) ------------------------------------------------------------------- */

float rocks_block_tile_field(const rocks_block_tile *tile, const double p[3], rocks_block_presence_fn present,
                             void *user, uint32_t *block_out) {
    const double s = tile->desc.size;
    double cell[3];
    float q[3];
    int g[3];
    for (int a = 0; a < 3; a++) {
        cell[a] = floor(p[a] / s);
        q[a] = (float)(p[a] - cell[a] * s);
        if (q[a] >= (float)s) q[a] = 0.0f, cell[a] += 1.0;   /* rounding up to s: the next tile */
        g[a] = (int)(q[a] / (float)s * (float)tile->grid);
        if (g[a] >= tile->grid) g[a] = tile->grid - 1;
    }
    size_t c = ((size_t)g[2] * tile->grid + g[1]) * tile->grid + g[0];
    float best = -INFINITY;
    uint32_t best_block = UINT32_MAX;
    for (uint32_t e = tile->grid_first[c]; e < tile->grid_first[c + 1]; e++) {
        uint32_t block = tile->grid_entries[e] >> 5, o = tile->grid_entries[e] & 31;
        int off[3] = { (int)(o % 3) - 1, (int)(o / 3 % 3) - 1, (int)(o / 9) - 1 };
        const rocks_block *b = &tile->blocks[block];
        float local[3];
        bool inside = true;
        for (int a = 0; a < 3; a++) {
            local[a] = q[a] - (float)s * (float)off[a];
            inside &= local[a] >= b->bounds_min[a] && local[a] <= b->bounds_max[a];
        }
        if (!inside) continue;
        if (present) {
            double anchor[3];
            for (int a = 0; a < 3; a++) anchor[a] = (cell[a] + off[a]) * s + b->anchor[a];
            if (!present(user, block, anchor)) continue;
        }
        float v = rocks_block_field(tile, block, local, NULL);
        if (v > best) best = v, best_block = block;
    }
    if (block_out) *block_out = best_block;
    return best;
}

/* ---- blocks in a terrain field (003 §5) ----------------------------------------------------- */

/* Samples of `field` inside [lo, hi] (world metres) along one axis: first and last index. */
static bool sample_range(const terrain_field *field, int axis, double lo, double hi, int *first, int *last) {
    int n = axis == 0 ? field->nx : axis == 1 ? field->ny : field->nz;
    double f = ceil((lo - field->origin[axis]) / field->spacing), l = floor((hi - field->origin[axis]) / field->spacing);
    if (f < 0) f = 0;
    if (l > n - 1) l = n - 1;
    *first = (int)f, *last = (int)l;
    return f <= l;
}

/* Whether block b's field at p can exceed `value`. The smooth intersection is at most the plain
 * min of the planes, and the warping moves p by at most √3 × the relief (δ = g Σ|gᵢ| d, |d| ≤ 1,
 * Σ|gᵢ| ≤ √3; planes are 1-Lipschitz), so b(p) ≤ minₖ hₖ(p) + √3·relief: a plane whose distance
 * is already below value − √3·relief decides. */
static bool may_exceed(const rocks_block_tile *tile, const rocks_block *b, const float p[3], float value) {
    float bound = value - 1.7321f * fmaxf(tile->desc.relief, 0.0f);
    const float (*planes)[4] = (const float(*)[4])tile->planes + b->plane_first;
    for (uint32_t k = 0; k < b->plane_count; k++)
        if (planes[k][3] - dot3(planes[k], p) <= bound) return false;
    return true;
}

/* One present copy (block `b` moved by `cell` tiles) raised into the samples its bounds cover. */
bool rocks__amplify_copy(const rocks_block_tile *tile, uint32_t b, const double cell[3], terrain_field *field) {
    /* a coarse field: the block thinned as a box filter of ±h thins it, or gone (rocks_blocks.h) */
    const float erosion = rocks__coarse_erosion(tile->widths[b], field->spacing);
    if (erosion == INFINITY) return false;
    const rocks_block *block = &tile->blocks[b];
    const double s = tile->desc.size;
    int first[3], last[3];
    for (int a = 0; a < 3; a++)
        if (!sample_range(field, a, cell[a] * s + block->bounds_min[a], cell[a] * s + block->bounds_max[a], &first[a],
                          &last[a]))
            return false;
    for (int z = first[2]; z <= last[2]; z++)
        for (int y = first[1]; y <= last[1]; y++)
            for (int x = first[0]; x <= last[0]; x++) {
                float *v = &field->values[((size_t)z * field->ny + y) * field->nx + x];
                if (*v >= 1.0f) continue;   /* already solid through: nothing to raise */
                int index[3] = { x, y, z };
                float local[3];
                for (int a = 0; a < 3; a++)
                    local[a] = (float)(field->origin[a] + index[a] * (double)field->spacing - cell[a] * s);
                if (!block->custom && !may_exceed(tile, block, local, *v + erosion)) continue;
                float t = fminf(1.0f, rocks_block_field(tile, b, local, NULL) - erosion);
                if (t > *v) *v = t;
            }
    return true;
}

void rocks__cell_range(const rocks_block_tile *tile, const double lo[3], const double hi[3], int64_t c0[3],
                       int64_t c1[3]) {
    const double s = tile->desc.size;
    for (int a = 0; a < 3; a++) {
        c0[a] = (int64_t)ceil((lo[a] - (double)tile->reach_max[a]) / s);
        c1[a] = (int64_t)floor((hi[a] - (double)tile->reach_min[a]) / s);
    }
}

void rocks_block_tile_amplify(const rocks_block_tile *tile, terrain_field *field, rocks_block_presence_fn present,
                              void *user) {
    const double s = tile->desc.size;
    double lo[3], hi[3];
    int n[3] = { field->nx, field->ny, field->nz };
    for (int a = 0; a < 3; a++) lo[a] = field->origin[a], hi[a] = field->origin[a] + (n[a] - 1) * (double)field->spacing;
    int64_t c0[3], c1[3];
    rocks__cell_range(tile, lo, hi, c0, c1);
    for (int64_t cz = c0[2]; cz <= c1[2]; cz++)
        for (int64_t cy = c0[1]; cy <= c1[1]; cy++)
            for (int64_t cx = c0[0]; cx <= c1[0]; cx++) {
                double cell[3] = { (double)cx, (double)cy, (double)cz };
                for (uint32_t b = 0; b < tile->block_count; b++) {
                    const rocks_block *block = &tile->blocks[b];
                    bool meets = true;
                    for (int a = 0; a < 3; a++)
                        meets &= cell[a] * s + block->bounds_max[a] >= lo[a] && cell[a] * s + block->bounds_min[a] <= hi[a];
                    if (!meets) continue;
                    double anchor[3];
                    for (int a = 0; a < 3; a++) anchor[a] = cell[a] * s + block->anchor[a];
                    if (present && !present(user, b, anchor)) continue;
                    rocks__amplify_copy(tile, b, cell, field);
                }
            }
}

bool rocks__wall_at(const rocks_wall_presence *w, const double anchor[3], float g[3]) {
    float depth_min = w->depth_min, depth_max = w->depth_max;
    if (depth_min == 0 && depth_max == 0) depth_min = -0.6f, depth_max = 0.9f;
    float steep = w->steepness > 0 ? w->steepness : 0.5f;
    float f = terrain_field_base_at(w->world, anchor[0], anchor[1], anchor[2], 0);
    if (!(f >= depth_min && f <= depth_max)) return false;
    /* the gradient by central differences half a metre apart (the field is linear over the
     * kernel's metre near a plane, so this is exact on a flat wall) */
    for (int a = 0; a < 3; a++) {
        double p[3] = { anchor[0], anchor[1], anchor[2] }, q[3] = { anchor[0], anchor[1], anchor[2] };
        p[a] -= 0.25, q[a] += 0.25;
        g[a] = terrain_field_base_at(w->world, q[0], q[1], q[2], 0) - terrain_field_base_at(w->world, p[0], p[1], p[2], 0);
    }
    float length = sqrtf(dot3(g, g));
    return length > 0 && fabsf(g[1]) < steep * length;
}

bool rocks_block_on_walls(void *wall_presence, uint32_t block, const double anchor[3]) {
    (void)block;
    float g[3];
    return rocks__wall_at(wall_presence, anchor, g);
}
