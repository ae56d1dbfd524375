/* Block tiles for cliffs (paper 003 §4–§5): the smooth intersection against hand-worked values,
 * a block made by hand (a cube corner), the replication's continuity across tile borders (value
 * and gradient), the clusters' defining property (no fracture between two points of a block),
 * every point inside its block's planes, block shapes by type, presence, determinism, bad input;
 * the tiles' cache file (round trip, cuts, flipped bytes, old versions, other parameters, files
 * whose checksum matches but whose indices do not) and the cliffs' cache folder and jobs.
 * Tiles are small (12 m, or 8 m) so the suite runs in seconds under the sanitizers. */
#include "../engine/test.h"
#include "core/core.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"
#include "rocks/rocks_world_internal.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static rocks_block_tile *small_tile(rocks_block_type type, uint64_t seed, float relief) {
    rocks_block_tile *t = rocks_block_tile_create(&(rocks_block_tile_desc){
        .type = type, .seed = seed, .size = 8.0f, .point_spacing = 0.6f, .fracture_spacing = 2.5f,
        .fracture_radius = 3.0f, .relief = relief });
    cr_assert_not_null(t);
    return t;
}

/* ---- 003 §4.2 by hand ----------------------------------------------------------------------- */

Test(rocks_blocks, smooth_intersection_hand_cases) {
    const float R = 0.25f;
    /* k = 1 − 0.1/0.25 = 0.6; 0.1 − 0.25 · 0.216 / 6 = 0.091 */
    cr_assert_float_eq(rocks_smooth_intersection(0.1f, 0.2f, R), 0.091f, 1e-6f);
    cr_assert_float_eq(rocks_smooth_intersection(0.2f, 0.1f, R), 0.091f, 1e-6f);   /* symmetric */
    /* equal arguments: k = 1, the edge cut back by R/6 */
    cr_assert_float_eq(rocks_smooth_intersection(0.3f, 0.3f, R), 0.3f - 0.25f / 6.0f, 1e-6f);
    /* |a − b| ≥ R: k = 0, the plain min */
    cr_assert_float_eq(rocks_smooth_intersection(0.1f, 0.5f, R), 0.1f, 1e-7f);
    cr_assert_float_eq(rocks_smooth_intersection(-2.0f, 0.3f, R), -2.0f, 1e-7f);
    /* two planes x < 1 and y < 1 (inside positive): on the bisector of the edge, 0.1 m in from
     * each plane, 0.1 − R/6; the surface crosses the bisector at h = R/6 from each plane */
    cr_assert_float_eq(rocks_smooth_intersection(1.0f - 0.9f, 1.0f - 0.9f, R), 0.1f - R / 6.0f, 1e-6f);
    cr_assert_float_eq(rocks_smooth_intersection(R / 6.0f, R / 6.0f, R), 0.0f, 1e-6f);
}

/* A block prescribed by hand (003 §4: user control): the cube [0, 1]³'s corner at (1, 1, 1)
 * as three planes, no relief. On the diagonal 0.1 m in from each face: fold
 *   smin(0.1, 0.1) = 0.1 − R/6 = 0.0583333;
 *   then with 0.1: |Δ| = R/6, k = 5/6, 0.0583333 − R (5/6)³ / 6 = 0.0583333 − 0.0241127.
 * The gradient by the chain rule (the operator is not symmetric in three arguments: 003 §4.2
 * notes the order matters): the first fold weighs −x̂ and −ŷ by ½ each; the second weighs that
 * by 1 − k²/2 = 47/72 and −ẑ by k²/2 = 25/72: (−47/144, −47/144, −25/72), normalised
 * (−0.565078, −0.565078, −0.601146). Central differences agree. */
Test(rocks_blocks, hand_made_cube_corner) {
    float planes[3][4] = { { 1, 0, 0, 1 }, { 0, 1, 0, 1 }, { 0, 0, 1, 1 } };
    rocks_block block = { .plane_first = 0, .plane_count = 3 };
    rocks_block_tile tile = { .desc = { .rounding = 0.25f, .relief = -1.0f }, .blocks = &block, .block_count = 1,
                              .planes = planes, .plane_count = 3 };
    float g[3];
    float v = rocks_block_field(&tile, 0, (const float[3]){ 0.9f, 0.9f, 0.9f }, g);
    cr_assert_float_eq(v, 0.0342207f, 2e-6f);
    const float expected[3] = { -0.565078f, -0.565078f, -0.601146f };
    for (int a = 0; a < 3; a++) {
        cr_assert_float_eq(g[a], expected[a], 1e-5f);
        float lo[3] = { 0.9f, 0.9f, 0.9f }, hi[3] = { 0.9f, 0.9f, 0.9f };
        lo[a] -= 1e-3f, hi[a] += 1e-3f;
        float slope = (rocks_block_field(&tile, 0, hi, NULL) - rocks_block_field(&tile, 0, lo, NULL)) / 2e-3f;
        cr_assert_float_eq(slope / 0.577600f, expected[a], 2e-3f);   /* |∇| = 0.5776 before normalising */
    }
    /* deep inside, far from the edges (all |Δ| ≥ R): the nearest face's distance */
    cr_assert_float_eq(rocks_block_field(&tile, 0, (const float[3]){ 0.5f, 0.2f, 0.1f }, NULL), 0.5f, 1e-6f);
    /* outside past a face: minus the distance to it */
    cr_assert_float_eq(rocks_block_field(&tile, 0, (const float[3]){ 1.5f, 0.2f, 0.1f }, NULL), -0.5f, 1e-6f);
}

/* ---- replication (003 §5) ------------------------------------------------------------------ */

static double unit(uint64_t *state) {
    *state = core_hash_u64(*state + 0x9e3779b97f4a7c15ull);
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* Across a border the same block copies are evaluated at the same point: the value is
 * continuous. A point ε either side of x = k·s differs by at most 2ε times the field's slope
 * (1 for planes; the smooth intersection's weights sum to 1), plus float rounding. */
Test(rocks_blocks, continuous_across_tile_borders) {
    rocks_block_tile *t = small_tile(ROCKS_BLOCK_TABULAR, 3, -1.0f);
    const double s = t->desc.size, eps = 1e-4;
    uint64_t state = 11;
    int finite = 0;
    for (int i = 0; i < 3000; i++) {
        int axis = i % 3;
        double p[3], lo[3], hi[3];
        for (int a = 0; a < 3; a++) p[a] = (unit(&state) - 0.5) * 6.0 * s;
        p[axis] = s * floor(p[axis] / s);   /* on a border */
        memcpy(lo, p, sizeof p), memcpy(hi, p, sizeof p);
        lo[axis] -= eps, hi[axis] += eps;
        float a = rocks_block_tile_field(t, lo, NULL, NULL, NULL), b = rocks_block_tile_field(t, hi, NULL, NULL, NULL);
        if (isinf(a) || isinf(b)) {
            cr_assert(isinf(a) && isinf(b), "border at %g %g %g: one side −∞ (%g), the other %g", p[0], p[1], p[2], a, b);
            continue;
        }
        finite++;
        cr_assert_leq(fabsf(a - b), 2 * eps + 1e-4, "border at %g %g %g: %g vs %g", p[0], p[1], p[2], a, b);
    }
    cr_assert_gt(finite, 1000, "most border points are near some block");
    rocks_block_tile_destroy(t);
}

/* The gradient too: central differences (h) either side of a border, δ away. The smooth
 * intersection's second derivative is at most 1/R per fold along a direction, and two normals
 * differ by at most 2, so the gradient moves by at most 4·(2δ)/R across; the differences' own
 * error is O(h/R). */
Test(rocks_blocks, gradient_continuous_across_tile_borders) {
    rocks_block_tile *t = small_tile(ROCKS_BLOCK_EQUIDIMENSIONAL, 5, -1.0f);
    const double s = t->desc.size, delta = 1e-3, h = 1e-3;
    const float R = t->desc.rounding;
    const float tolerance = 4.0f * (float)(2 * delta) / R + 8.0f * (float)h / R + 0.02f;
    uint64_t state = 12;
    int checked = 0;
    for (int i = 0; i < 1500; i++) {
        int axis = i % 3;
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = (unit(&state) - 0.5) * 4.0 * s;
        p[axis] = s * floor(p[axis] / s);
        float g[2][3];
        bool ok = true;
        uint32_t first = UINT32_MAX;
        for (int side = 0; side < 2; side++) {
            double c[3];
            memcpy(c, p, sizeof c);
            c[axis] += side ? delta : -delta;
            for (int a = 0; a < 3; a++) {
                double q0[3], q1[3];
                memcpy(q0, c, sizeof c), memcpy(q1, c, sizeof c);
                q0[a] -= h, q1[a] += h;
                uint32_t b0, b1;
                float f0 = rocks_block_tile_field(t, q0, NULL, NULL, &b0), f1 = rocks_block_tile_field(t, q1, NULL, NULL, &b1);
                if (first == UINT32_MAX) first = b0;
                /* t = maxᵢ bᵢ has a kink where two blocks tie, border or not: keep to one block */
                if (isinf(f0) || isinf(f1) || b0 != first || b1 != first) ok = false;
                g[side][a] = (f1 - f0) / (float)(2 * h);
            }
        }
        if (!ok) continue;
        checked++;
        for (int a = 0; a < 3; a++)
            cr_assert_leq(fabsf(g[0][a] - g[1][a]), tolerance, "at %g %g %g axis %d: %g vs %g", p[0], p[1], p[2], a,
                          g[0][a], g[1][a]);
    }
    cr_assert_gt(checked, 500);
    rocks_block_tile_destroy(t);
}

static bool refuse_all(void *user, uint32_t block, const double anchor[3]) {
    (void)user, (void)block, (void)anchor;
    return false;
}

typedef struct anchor_check { double p[3]; float reach; bool far; } anchor_check;

/* Presence is asked at the copy's anchor in world metres: within a block's size of the point. */
static bool near_anchor(void *user, uint32_t block, const double anchor[3]) {
    (void)block;
    anchor_check *c = user;
    double d2 = 0;
    for (int a = 0; a < 3; a++) d2 += (anchor[a] - c->p[a]) * (anchor[a] - c->p[a]);
    if (sqrt(d2) > c->reach) c->far = true;
    return true;
}

Test(rocks_blocks, presence_decides_which_copies_count) {
    rocks_block_tile *t = small_tile(ROCKS_BLOCK_COLUMNAR, 2, 0.0f);
    uint64_t state = 13;
    for (int i = 0; i < 500; i++) {
        double p[3] = { (unit(&state) - 0.5) * 100, (unit(&state) - 0.5) * 100, (unit(&state) - 0.5) * 100 };
        cr_assert(isinf(rocks_block_tile_field(t, p, refuse_all, NULL, NULL)), "no block accepted: −∞");
        anchor_check c = { .p = { p[0], p[1], p[2] }, .reach = t->desc.size };
        uint32_t block;
        float all = rocks_block_tile_field(t, p, NULL, NULL, &block);
        float asked = rocks_block_tile_field(t, p, near_anchor, &c, NULL);
        cr_assert_eq(all, asked);
        cr_assert_not(c.far, "an anchor passed to presence is more than a tile from the point");
        if (!isinf(all)) cr_assert_lt(block, t->block_count);
    }
    rocks_block_tile_destroy(t);
}

/* ---- the blocks themselves (003 §4.1–§4.2) ------------------------------------------------- */

/* Does disc d (or one of its copies a tile away) cut the segment a–b? Brute force over the 125
 * copies within two tiles, independently of the builder's near-disc lists. */
static bool any_copy_cuts(const rocks_block_tile *t, const rocks_block_disc *d, const float a[3], const float b[3]) {
    const float s = t->desc.size;
    for (int o = 0; o < 125; o++) {
        float c[3] = { d->centre[0] + s * (float)(o % 5 - 2), d->centre[1] + s * (float)(o / 5 % 5 - 2),
                       d->centre[2] + s * (float)(o / 25 - 2) };
        float da = 0, db = 0;
        for (int k = 0; k < 3; k++) da += (a[k] - c[k]) * d->normal[k], db += (b[k] - c[k]) * d->normal[k];
        if ((da > 0) == (db > 0) || da == db) continue;
        float u = da / (da - db), r2 = 0;
        for (int k = 0; k < 3; k++) {
            float x = a[k] + u * (b[k] - a[k]) - c[k];
            r2 += x * x;
        }
        if (r2 <= d->radius * d->radius) return true;
    }
    return false;
}

/* 003 §4.1: "all the points in a given cluster are visible to each other". */
Test(rocks_blocks, no_fracture_inside_a_block) {
    for (int type = ROCKS_BLOCK_EQUIDIMENSIONAL; type < ROCKS_BLOCK_TYPE_END; type++) {
        rocks_block_tile *t = small_tile((rocks_block_type)type, 9, 0.0f);
        uint64_t state = 14;
        for (int pair = 0; pair < 400; pair++) {
            const rocks_block *b = &t->blocks[(uint32_t)(unit(&state) * t->block_count)];
            if (b->point_count < 2) continue;
            const float *p = t->points[b->point_first + (uint32_t)(unit(&state) * b->point_count)];
            const float *q = t->points[b->point_first + (uint32_t)(unit(&state) * b->point_count)];
            for (uint32_t d = 0; d < t->disc_count; d++)
                cr_assert_not(any_copy_cuts(t, &t->discs[d], p, q), "%s: disc %u cuts a block", rocks_block_type_name(type), d);
        }
        rocks_block_tile_destroy(t);
    }
}

/* Every plane of a block supports its cluster (a hull face pushed out, or a fracture past the
 * cluster's last point): each point is inside every plane. And the anchor is in the tile. */
Test(rocks_blocks, every_point_inside_its_block) {
    for (int type = ROCKS_BLOCK_EQUIDIMENSIONAL; type < ROCKS_BLOCK_TYPE_END; type++) {
        rocks_block_tile *t = small_tile((rocks_block_type)type, 4, 0.0f);
        cr_assert_gt(t->block_count, 5);
        for (uint32_t i = 0; i < t->block_count; i++) {
            const rocks_block *b = &t->blocks[i];
            cr_assert_geq(b->plane_count, 4, "a closed convex block needs 4 planes");
            for (int a = 0; a < 3; a++) cr_assert(b->anchor[a] >= 0 && b->anchor[a] < t->desc.size);
            for (uint32_t j = 0; j < b->point_count; j++) {
                const float *p = t->points[b->point_first + j];
                for (uint32_t k = 0; k < b->plane_count; k++) {
                    const float *pl = t->planes[b->plane_first + k];
                    cr_assert_geq(pl[3] - (pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2]), -1e-4f);
                }
                for (int a = 0; a < 3; a++) cr_assert(p[a] >= b->bounds_min[a] && p[a] <= b->bounds_max[a]);
            }
        }
        rocks_block_tile_destroy(t);
    }
}

/* Mean extent of the blocks' points along each axis. */
static void mean_extent(const rocks_block_tile *t, double out[3]) {
    out[0] = out[1] = out[2] = 0;
    for (uint32_t i = 0; i < t->block_count; i++) {
        const rocks_block *b = &t->blocks[i];
        for (int a = 0; a < 3; a++) {
            float lo = INFINITY, hi = -INFINITY;
            for (uint32_t j = 0; j < b->point_count; j++) {
                lo = fminf(lo, t->points[b->point_first + j][a]);
                hi = fmaxf(hi, t->points[b->point_first + j][a]);
            }
            out[a] += (hi - lo) / t->block_count;
        }
    }
}

/* 003 §4.1's types by shape (y is up): tabular blocks are flat (beds across the tile), columnar
 * ones tall (continuous vertical sets, rare cross joints), equidimensional ones about as deep
 * as wide and tall (three orthogonal sets). The types' own defaults, on a 12 m tile. */
Test(rocks_blocks, shapes_follow_the_type) {
    double e[ROCKS_BLOCK_TYPE_END][3] = { { 0 } };
    for (int type = ROCKS_BLOCK_EQUIDIMENSIONAL; type < ROCKS_BLOCK_TYPE_END; type++) {
        /* a 12 m tile holds a dozen of the equidimensional type's discs: average a few tiles,
         * so one tile's chance layout does not decide */
        int seeds = type == ROCKS_BLOCK_EQUIDIMENSIONAL ? 4 : 1;
        for (int seed = 1; seed <= seeds; seed++) {
            rocks_block_tile *t = rocks_block_tile_create(&(rocks_block_tile_desc){
                .type = (rocks_block_type)type, .seed = (uint64_t)seed, .size = 12, .point_spacing = 0.7f });
            cr_assert_not_null(t);
            double one[3];
            mean_extent(t, one);
            for (int a = 0; a < 3; a++) e[type][a] += one[a] / seeds;
            rocks_block_tile_destroy(t);
        }
    }
    const double *tab = e[ROCKS_BLOCK_TABULAR], *col = e[ROCKS_BLOCK_COLUMNAR], *eq = e[ROCKS_BLOCK_EQUIDIMENSIONAL];
    cr_assert_lt(tab[1], 0.6 * fmin(tab[0], tab[2]), "tabular: %g %g %g", tab[0], tab[1], tab[2]);
    cr_assert_gt(col[1], 1.5 * fmax(col[0], col[2]), "columnar: %g %g %g", col[0], col[1], col[2]);
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) cr_assert_lt(eq[a], 1.6 * eq[b], "equidimensional: %g %g %g", eq[0], eq[1], eq[2]);
}

Test(rocks_blocks, deterministic_and_seeded) {
    rocks_block_tile *a = small_tile(ROCKS_BLOCK_POLYHEDRAL, 21, 0.0f), *b = small_tile(ROCKS_BLOCK_POLYHEDRAL, 21, 0.0f);
    cr_assert_eq(a->block_count, b->block_count);
    cr_assert_eq(a->plane_count, b->plane_count);
    cr_assert_eq(memcmp(a->planes, b->planes, a->plane_count * sizeof *a->planes), 0);
    cr_assert_eq(memcmp(a->blocks, b->blocks, a->block_count * sizeof *a->blocks), 0);
    rocks_block_tile *c = small_tile(ROCKS_BLOCK_POLYHEDRAL, 22, 0.0f);
    cr_assert(c->plane_count != a->plane_count || memcmp(a->planes, c->planes, a->plane_count * sizeof *a->planes) != 0);
    rocks_block_tile_destroy(a);
    rocks_block_tile_destroy(b);
    rocks_block_tile_destroy(c);
}

Test(rocks_blocks, bad_input_is_refused) {
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .type = ROCKS_BLOCK_TYPE_END }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .size = 2 }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .size = 1e6f }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .size = NAN }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .point_spacing = 0.01f }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .joint = 5 }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .rounding = -1 }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .relief_scale = -1 }));
    rocks_block_type type;
    for (int t = ROCKS_BLOCK_EQUIDIMENSIONAL; t < ROCKS_BLOCK_TYPE_END; t++) {
        cr_assert(rocks_parse_block_type(rocks_block_type_name((rocks_block_type)t), &type));
        cr_assert_eq((int)type, t);
    }
    cr_assert_not(rocks_parse_block_type("granite", &type));
    cr_assert_not(rocks_parse_block_type(NULL, &type));
    cr_assert_null(rocks_block_type_name(ROCKS_BLOCK_TYPE_END));
    cr_assert_null(rocks_block_type_name(ROCKS_BLOCK_DEFAULT), "DEFAULT is not a type of its own");
    cr_assert_not(rocks_parse_block_type("default", &type));
}

/* ---- a block placed by hand (003 §4, user control) ------------------------------------------- */

typedef struct sphere { float centre[3], radius; } sphere;

static float sphere_field(void *user, const float p[3]) {
    const sphere *s = user;
    float d2 = 0;
    for (int a = 0; a < 3; a++) d2 += (p[a] - s->centre[a]) * (p[a] - s->centre[a]);
    return s->radius - sqrtf(d2);
}

/* A sphere placed across the tile's x border: it is block 0, its field is its own (the radius
 * at its centre, in every copy of the tile), it owns the sample points within a joint of it on
 * both sides of the border, and no generated block holds a point there. */
Test(rocks_blocks, custom_block_takes_its_place) {
    sphere ball = { .centre = { 0.4f, 4.0f, 4.0f }, .radius = 1.5f };
    rocks_block_custom custom = { .field = sphere_field, .user = &ball, .bounds_min = { -1.1f, 2.5f, 2.5f },
                                  .bounds_max = { 1.9f, 5.5f, 5.5f } };
    rocks_block_tile *t = rocks_block_tile_create(&(rocks_block_tile_desc){
        .type = ROCKS_BLOCK_POLYHEDRAL, .seed = 3, .size = 8.0f, .point_spacing = 0.45f, .fracture_spacing = 2.5f,
        .fracture_radius = 3.0f, .custom = &custom, .custom_count = 1 });
    cr_assert_not_null(t);
    cr_assert_eq(t->blocks[0].custom, 1u);   /* desc.custom[0] */
    cr_assert_gt(t->blocks[0].point_count, 10);
    const float joint = t->desc.joint, s = t->desc.size;
    for (int k = -2; k <= 2; k++) {
        double p[3] = { 0.4 + k * s, 4.0 + 3 * k * s, 4.0 - k * s };
        uint32_t block;
        cr_assert_float_eq(rocks_block_tile_field(t, p, NULL, NULL, &block), 1.5f, 1e-5f);
        cr_assert_eq(block, 0u);
    }
    for (uint32_t i = 0; i < t->block_count; i++)
        for (uint32_t j = 0; j < t->blocks[i].point_count; j++) {
            const float *p = t->points[t->blocks[i].point_first + j];
            float d2 = 0;   /* to the nearest copy of the centre */
            for (int a = 0; a < 3; a++) {
                float d = p[a] - ball.centre[a];
                d -= s * roundf(d / s);
                d2 += d * d;
            }
            if (i == 0) cr_assert_lt(sqrtf(d2), ball.radius + joint + 1e-4f);
            else cr_assert_geq(sqrtf(d2), ball.radius + joint - 1e-4f, "block %u holds a point inside the sphere", i);
        }
    /* points on the far side of the border were taken too */
    bool far_side = false;
    for (uint32_t j = 0; j < t->blocks[0].point_count; j++) far_side |= t->points[t->blocks[0].point_first + j][0] < 0;
    cr_assert(far_side);
    rocks_block_tile_destroy(t);
    /* bad hand-made blocks */
    rocks_block_custom outside = custom;
    outside.bounds_min[0] += 9, outside.bounds_max[0] += 9;   /* centred outside the tile */
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .size = 8, .custom = &outside, .custom_count = 1 }));
    rocks_block_custom no_field = custom;
    no_field.field = NULL;
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .size = 8, .custom = &no_field, .custom_count = 1 }));
    cr_assert_null(rocks_block_tile_create(&(rocks_block_tile_desc){ .size = 8, .custom = NULL, .custom_count = 2 }));
}

/* ---- blocks in a terrain field --------------------------------------------------------------- */

/* Presence by a hash of the copy (a block's copies in different tiles differ). */
static bool every_other_copy(void *user, uint32_t block, const double anchor[3]) {
    (void)user;
    uint64_t h = core_hash_combine(block, (uint64_t)(int64_t)floor(anchor[0] * 4));
    h = core_hash_combine(h, (uint64_t)(int64_t)floor(anchor[1] * 4));
    h = core_hash_combine(h, (uint64_t)(int64_t)floor(anchor[2] * 4));
    return h & 1;
}

/* rocks_block_tile_amplify raises each sample to the replication at that point, as
 * rocks_block_tile_field gives it point by point with the same presence (clamped to [−1, 1]). */
Test(rocks_blocks, amplify_equals_the_field_point_by_point) {
    rocks_block_tile *t = small_tile(ROCKS_BLOCK_EQUIDIMENSIONAL, 8, 0.0f);
    terrain_field field = { .nx = 21, .ny = 13, .nz = 17, .origin = { -6.5, 3.0, 11.0 }, .spacing = 0.5f };
    size_t n = (size_t)field.nx * field.ny * field.nz;
    field.values = core_alloc(n * sizeof *field.values);
    for (size_t i = 0; i < n; i++) field.values[i] = i % 5 == 0 ? 0.3f : -1.0f;   /* some already raised */
    rocks_block_tile_amplify(t, &field, every_other_copy, NULL);
    int raised = 0;
    for (int z = 0; z < field.nz; z++)
        for (int y = 0; y < field.ny; y++)
            for (int x = 0; x < field.nx; x++) {
                size_t i = ((size_t)z * field.ny + y) * field.nx + x;
                double p[3] = { field.origin[0] + x * 0.5, field.origin[1] + y * 0.5, field.origin[2] + z * 0.5 };
                float before = i % 5 == 0 ? 0.3f : -1.0f;
                float t_value = rocks_block_tile_field(t, p, every_other_copy, NULL, NULL);
                float expected = fmaxf(before, fminf(1.0f, t_value));
                cr_assert_float_eq(field.values[i], expected, 1e-4f, "at %g %g %g", p[0], p[1], p[2]);
                raised += field.values[i] > before;
            }
    cr_assert_gt(raised, 100);
    core_free(field.values, n * sizeof *field.values);
    rocks_block_tile_destroy(t);
}

static void wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user, (void)z;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (x < 0 ? 20.0f : 0.0f) - TERRAIN_FLOOR_Y);
}

static terrain_stacks *wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, wall_column, user);
}

/* 003 §5's presence on a wall x = 0 (bedrock behind, up to 20 m) over a floor y = 0: the field
 * there is the signed distance in metres within a metre of a flat face (000 §3.3 with σ = 1). */
Test(rocks_blocks, presence_on_steep_walls_only) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk });
    rocks_wall_presence walls = { .world = world };
    const double on_face[][3] = { { -0.3, 10, 5 }, { 0.4, 6, -3 }, { -0.8, 15, 40 } };
    const double not_on_face[][3] = { { 5, 0.3, 5 },     /* the floor: flat */
                                      { -3, 10, 5 },     /* deep in the wall: f = 1 */
                                      { 3, 10, 5 },      /* in the air: f = −1 */
                                      { -5, 19.8, 5 } }; /* the wall's flat top */
    for (size_t i = 0; i < CORE_COUNTOF(on_face); i++)
        cr_assert(rocks_block_on_walls(&walls, 0, on_face[i]), "on the face: %g %g %g", on_face[i][0], on_face[i][1], on_face[i][2]);
    for (size_t i = 0; i < CORE_COUNTOF(not_on_face); i++)
        cr_assert_not(rocks_block_on_walls(&walls, 0, not_on_face[i]), "not a wall: %g %g %g", not_on_face[i][0],
                      not_on_face[i][1], not_on_face[i][2]);
    terrain_world_destroy(world);
}

typedef struct wall_blocks { rocks_block_tile *tile; rocks_wall_presence walls; } wall_blocks;

static void amplify_wall(void *user, terrain_world *world, terrain_field *field) {
    wall_blocks *w = user;
    w->walls.world = world;
    rocks_block_tile_amplify(w->tile, field, rocks_block_on_walls, &w->walls);
}

/* Through the world's hook: the blocks rise out of the wall's face, and two neighbouring
 * chunks' fields agree bit for bit on the samples they share (so their meshes meet), whichever
 * is sampled first: the amplification is a function of the position alone. */
Test(rocks_blocks, chunks_with_blocks_meet_exactly) {
    wall_blocks w = { .tile = small_tile(ROCKS_BLOCK_COLUMNAR, 6, 0.08f) };
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk, .amplify = amplify_wall,
                                                                     .amplify_user = &w });
    terrain_field a, b, c;
    /* a and b split x at 0 (the face), b and c split z at 16 */
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -16, 0, 0 }, .size = { 17, 20, 17 } }, &a));
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { 0, 0, 0 }, .size = { 17, 20, 17 } }, &b));
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { 0, 0, 16 }, .size = { 17, 20, 17 } }, &c));
    int out_of_face = 0;
    for (int z = 0; z < 17; z++)
        for (int y = 0; y < 20; y++) {
            cr_assert_eq(a.values[((size_t)z * 20 + y) * 17 + 16], b.values[((size_t)z * 20 + y) * 17 + 0]);
            for (int x = 0; x < 17; x++) {
                cr_assert_eq(b.values[((size_t)16 * 20 + y) * 17 + x], c.values[((size_t)0 * 20 + y) * 17 + x]);
                /* in front of the face (x ≥ 1 m, above the floor) only blocks can be solid */
                if (x >= 1 && y >= 2 && b.values[((size_t)z * 20 + y) * 17 + x] > 0) out_of_face++;
            }
        }
    cr_assert_gt(out_of_face, 10, "blocks stand out of the wall");
    terrain_field_free(&a);
    terrain_field_free(&b);
    terrain_field_free(&c);
    terrain_world_destroy(world);
    rocks_block_tile_destroy(w.tile);
}

/* ---- coarse fields: what a level of detail shows of a block ---------------------------------- */

/* A block's smallest width by hand: a 3 × 1.5 × 5 box is 1.5 wide; the cube [0, 3]³ with its
 * corner cut by x + y + z ≤ 4.5 is 4.5/√3 = 2.598 wide along (1, 1, 1) (corners (0, 0, 0) and the
 * cut's plane) and 3 along each axis; an equilateral triangle of side 2 drawn out 5 m along y
 * is a prism √3 = 1.732 wide (a side to the opposite corner). */
Test(rocks_blocks, block_width_by_hand) {
    const float r3 = 0.57735027f;   /* 1/√3 */
    float box[6][4] = { { 1, 0, 0, 3 }, { -1, 0, 0, 0 }, { 0, 1, 0, 1.5f }, { 0, -1, 0, 0 }, { 0, 0, 1, 5 }, { 0, 0, -1, 0 } };
    float cut[7][4] = { { 1, 0, 0, 3 }, { -1, 0, 0, 0 }, { 0, 1, 0, 3 }, { 0, -1, 0, 0 }, { 0, 0, 1, 3 }, { 0, 0, -1, 0 },
                        { r3, r3, r3, 4.5f * r3 } };
    /* sides through (0, 0), (2, 0), (1, √3) in x, z, normals pointing out */
    const float h = 1.7320508f;
    float prism[5][4] = { { 0, 0, -1, 0 }, { h / 2, 0, 0.5f, h }, { -h / 2, 0, 0.5f, 0 }, { 0, 1, 0, 5 }, { 0, -1, 0, 0 } };
    const struct { float (*planes)[4]; uint32_t count; float width; } cases[] = {
        { box, 6, 1.5f }, { cut, 7, 4.5f * r3 }, { prism, 5, h } };
    for (size_t i = 0; i < CORE_COUNTOF(cases); i++) {
        rocks_block block = { .plane_first = 0, .plane_count = cases[i].count };
        rocks_block_tile tile = { .desc = { .rounding = 0.25f, .relief = -1.0f }, .blocks = &block, .block_count = 1,
                                  .planes = cases[i].planes, .plane_count = cases[i].count };
        cr_assert_float_eq(rocks__block_width(&tile, 0), cases[i].width, 1e-4f, "case %zu", i);
    }
    /* the rule itself: level 0 keeps all; at h = 2 a block 3 m wide or less is gone, 3.5 m is
     * thinned by 2 − 1.75 = 0.25 (to 2(3.5 − 2) = 3 m), 4 m and more kept as it is */
    cr_assert_eq(rocks__coarse_erosion(0.5f, 1.0f), 0.0f);
    cr_assert_eq(rocks__coarse_erosion(3.0f, 2.0f), INFINITY);
    cr_assert_float_eq(rocks__coarse_erosion(3.5f, 2.0f), 0.25f, 1e-6f);
    cr_assert_eq(rocks__coarse_erosion(4.0f, 2.0f), 0.0f);
    cr_assert_eq(rocks__coarse_erosion(5.9f, 4.0f), INFINITY);
    cr_assert_eq(rocks__coarse_erosion(9.0f, 4.0f), 0.0f);
}

/* Boxes given by hand: > 0 inside, the distance to the nearest face inside. */
typedef struct hand_box { float lo[3], hi[3]; } hand_box;

static float hand_box_field(void *user, const float p[3]) {
    const hand_box *b = user;
    float v = INFINITY;
    for (int a = 0; a < 3; a++) v = fminf(v, fminf(p[a] - b->lo[a], b->hi[a] - p[a]));
    return v;
}

/* Only the hand-made blocks (the first `custom_count`) of the tile copy at the origin. */
static bool hand_blocks_at_origin(void *user, uint32_t block, const double anchor[3]) {
    const rocks_block_tile *t = user;
    bool origin = true;
    for (int a = 0; a < 3; a++) origin &= anchor[a] >= 0 && anchor[a] < t->desc.size;
    return origin && block < (uint32_t)t->desc.custom_count;
}

static void amplify_hand_blocks(void *user, terrain_world *world, terrain_field *field) {
    (void)world;
    rocks_block_tile_amplify(user, field, hand_blocks_at_origin, user);
}

/* The coarse fields' rule on the wall x = 0, with three boxes standing out of it, 2.5, 3.5 and
 * 6.5 m at their thinnest: at 1 m every box raises the field (level 0 unchanged); at 2 m the
 * 2.5 m box (under 1.5 h = 3 m) leaves the base field as it was, though the row of samples at
 * y = 2 runs through it (the box filter alone would leave a 1 m sliver), the 3.5 m one is thinned by
 * 0.25 m (h − w/2), the 6.5 m one is as at 1 m; at 4 m the 3.5 m box is gone too (under 6 m) and
 * the 6.5 m one thinned by 0.75 m. Values worked out from the boxes' own fields, not read from
 * the code. */
Test(rocks_blocks, coarse_fields_drop_thin_blocks) {
    hand_box boxes[3] = { { { -1, 1, 2 }, { 2, 3.5f, 8 } },             /* 2.5 m (y) */
                          { { -1, 6, 2 }, { 2.5f, 10, 8 } },            /* 3.5 m (x) */
                          { { -3, 12.5f, 1 }, { 3.5f, 19, 8 } } };      /* 6.5 m (x, y) */
    rocks_block_custom custom[3];
    for (int i = 0; i < 3; i++) {
        custom[i] = (rocks_block_custom){ .field = hand_box_field, .user = &boxes[i] };
        memcpy(custom[i].bounds_min, boxes[i].lo, sizeof boxes[i].lo);
        memcpy(custom[i].bounds_max, boxes[i].hi, sizeof boxes[i].hi);
    }
    rocks_block_tile *t = rocks_block_tile_create(&(rocks_block_tile_desc){
        .type = ROCKS_BLOCK_EQUIDIMENSIONAL, .size = 24, .point_spacing = 2, .fracture_spacing = 6, .fracture_radius = 6,
        .custom = custom, .custom_count = 3 });
    cr_assert_not_null(t);
    for (uint32_t i = 0; i < 3; i++) cr_assert_eq(t->blocks[i].custom, i + 1);
    cr_assert_float_eq(t->widths[0], 2.5f, 1e-6f);
    cr_assert_float_eq(t->widths[1], 3.5f, 1e-6f);
    cr_assert_float_eq(t->widths[2], 6.5f, 1e-6f);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk, .amplify = amplify_hand_blocks,
                                                                     .amplify_user = t });
    terrain_world *plain = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk });
    terrain_field fine, coarse, coarsest, base;
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -4, 0, 0 }, .size = { 9, 21, 11 } }, &fine));
    cr_assert(terrain_field_sample(plain, &(terrain_field_desc){ .first = { -4, 0, 0 }, .size = { 9, 21, 11 } }, &base));
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -4, 0, 0 }, .size = { 5, 11, 6 }, .step = 2 },
                                   &coarse));
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -4, 0, 0 }, .size = { 3, 6, 3 }, .step = 4 },
                                   &coarsest));
    int raised_fine[3] = { 0 }, raised_coarse[3] = { 0 };
    for (int z = 0; z < 11; z++)
        for (int y = 0; y < 21; y++)
            for (int x = 0; x < 9; x++) {
                const float p[3] = { (float)(x - 4), (float)y, (float)z };
                const size_t i = ((size_t)z * 21 + y) * 9 + x;
                int which = y < 5 ? 0 : y < 12 ? 1 : 2;   /* the box whose bounds (±1 m) reach it */
                float expected = fmaxf(base.values[i], fminf(1.0f, hand_box_field(&boxes[which], p)));
                cr_assert_float_eq(fine.values[i], expected, 1e-6f, "level 0 at %g %g %g", p[0], p[1], p[2]);
                raised_fine[which] += fine.values[i] > base.values[i];
                if (x % 2 || y % 2 || z % 2) continue;   /* the coarse field's samples */
                const float erosion[3] = { INFINITY, 0.25f, 0.0f };
                float coarse_expected = fmaxf(base.values[i], fminf(1.0f, hand_box_field(&boxes[which], p) - erosion[which]));
                float v = coarse.values[((size_t)(z / 2) * 11 + y / 2) * 5 + x / 2];
                cr_assert_float_eq(v, coarse_expected, 1e-6f, "2 m at %g %g %g", p[0], p[1], p[2]);
                raised_coarse[which] += v > base.values[i];
                if (which == 2) cr_assert_eq(v, fine.values[i], "the 6.5 m box as at 1 m");
                if (x % 4 || y % 4 || z % 4) continue;   /* the coarsest field's */
                const float erosion4[3] = { INFINITY, INFINITY, 0.75f };
                float coarsest_expected = fmaxf(base.values[i], fminf(1.0f, hand_box_field(&boxes[which], p) - erosion4[which]));
                cr_assert_float_eq(coarsest.values[((size_t)(z / 4) * 6 + y / 4) * 3 + x / 4], coarsest_expected, 1e-6f,
                                   "4 m at %g %g %g", p[0], p[1], p[2]);
            }
    for (int b = 0; b < 3; b++) cr_assert_gt(raised_fine[b], 10, "box %d stands out at 1 m", b);
    cr_assert_eq(raised_coarse[0], 0, "the 2.5 m box leaves the 2 m field as it was");
    cr_assert_gt(raised_coarse[1], 3, "the 3.5 m box, thinned, still shows at 2 m");
    cr_assert_gt(raised_coarse[2], 3);
    /* by hand: (0, 8, 4) on the face (base 0) is 1 m inside the 3.5 m box, 0.75 after thinning;
     * (2, 8, 4) in the air (base −1) 0.5 inside it, 0.25 after; (0, 16, 4) is 3 m inside the
     * 6.5 m box: 1 (clamped) at 2 m, and 3 − 0.75, clamped to 1, at 4 m; (0, 12, 4) at 4 m is
     * 0.5 under the box: −0.5 − 0.75 < 0, the face's 0 stays */
    cr_assert_float_eq(coarse.values[((size_t)2 * 11 + 1) * 5 + 2], 0.0f, 1e-6f);   /* (0, 2, 4): the face */
    cr_assert_float_eq(coarse.values[((size_t)2 * 11 + 4) * 5 + 2], 0.75f, 1e-6f);
    cr_assert_float_eq(coarse.values[((size_t)2 * 11 + 4) * 5 + 3], 0.25f, 1e-6f);
    cr_assert_float_eq(coarse.values[((size_t)2 * 11 + 8) * 5 + 2], 1.0f, 1e-6f);
    cr_assert_float_eq(coarsest.values[((size_t)1 * 6 + 4) * 3 + 1], 1.0f, 1e-6f);
    cr_assert_float_eq(coarsest.values[((size_t)1 * 6 + 3) * 3 + 1], 0.0f, 1e-6f);
    terrain_field_free(&fine);
    terrain_field_free(&coarse);
    terrain_field_free(&coarsest);
    terrain_field_free(&base);
    terrain_world_destroy(world);
    terrain_world_destroy(plain);
    rocks_block_tile_destroy(t);
}

/* ---- cliffs in a world (rocks_cliffs) -------------------------------------------------------- */

/* The same wall in sand, on sand: bedrock only 5 m under the floor. */
static void sand_wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user, (void)z;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, -5.0f - TERRAIN_FLOOR_Y);
    terrain_stacks_builder_push(b, TERRAIN_SAND, x < 0 ? 25.0f : 5.0f);
}

static terrain_stacks *sand_wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, sand_wall_column, user);
}

/* Samples a field of the world with and without the cliffs; returns how many the cliffs raised
 * (none is ever lowered). A rocks_cliffs serves one world: its cache is keyed by chunk versions. */
static int raised_samples(terrain_stacks *(*generate)(void *, terrain_chunk_coord), terrain_world *world, int step) {
    terrain_world *plain = terrain_world_create(&(terrain_world_desc){ .generate = generate });
    terrain_field_desc desc = { .first = { -8, 0, 0 }, .size = { 16, 24, 20 }, .step = step };
    terrain_field a, b;
    cr_assert(terrain_field_sample(world, &desc, &a));
    cr_assert(terrain_field_sample(plain, &desc, &b));
    int raised = 0;
    for (size_t i = 0; i < (size_t)16 * 24 * 20; i++) {
        cr_assert_geq(a.values[i], b.values[i]);
        raised += a.values[i] > b.values[i];
    }
    terrain_field_free(&a);
    terrain_field_free(&b);
    terrain_world_destroy(plain);
    return raised;
}

static terrain_world *cliff_world(terrain_stacks *(*generate)(void *, terrain_chunk_coord), rocks_cliffs *cliffs) {
    return terrain_world_create(&(terrain_world_desc){ .generate = generate, .amplify = rocks_cliffs_amplify,
                                                       .amplify_user = cliffs });
}

/* Blocks stand on a bedrock wall, not on a sand one; not in fields coarser than max_spacing;
 * and the presence worked out for a tile cell is reused by the next field that meets it. */
Test(rocks_blocks, cliffs_on_bedrock_walls) {
    const rocks_cliffs_desc desc = { .strata_count = 1, .strata = { ROCKS_BLOCK_COLUMNAR }, .tile_size = 12 };
    rocks_cliffs *cliffs = rocks_cliffs_create(&desc);
    cr_assert_not_null(cliffs);
    terrain_world *world = cliff_world(wall_chunk, cliffs);
    cr_assert_gt(raised_samples(wall_chunk, world, 1), 20);
    rocks_cliffs_stats_info first = rocks_cliffs_stats(cliffs);
    cr_assert_gt(first.cells_computed, 0);
    cr_assert_gt(raised_samples(wall_chunk, world, 1), 20);
    rocks_cliffs_stats_info second = rocks_cliffs_stats(cliffs);
    cr_assert_eq(second.cells_computed, first.cells_computed, "the second field computes no cell again");
    cr_assert_gt(second.cells_reused, first.cells_reused);
    cr_assert_eq(raised_samples(wall_chunk, world, 8), 0, "none past max_spacing (4 m)");
    terrain_world_destroy(world);
    rocks_cliffs_destroy(cliffs);
    rocks_cliffs_desc fine_only = desc;
    fine_only.max_spacing = 1;
    rocks_cliffs *level0 = rocks_cliffs_create(&fine_only);
    terrain_world *level0_world = cliff_world(wall_chunk, level0);
    cr_assert_gt(raised_samples(wall_chunk, level0_world, 1), 20);
    cr_assert_eq(raised_samples(wall_chunk, level0_world, 2), 0, "max_spacing 1: level 0 only");
    terrain_world_destroy(level0_world);
    rocks_cliffs_destroy(level0);

    rocks_cliffs *sand = rocks_cliffs_create(&desc);
    terrain_world *sand_world = cliff_world(sand_wall_chunk, sand);
    cr_assert_eq(raised_samples(sand_wall_chunk, sand_world, 1), 0, "no blocks on sand");
    terrain_world_destroy(sand_world);
    rocks_cliffs_destroy(sand);

    cr_assert_null(rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 9 }));
    cr_assert_null(rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 1, .strata = { (rocks_block_type)7 } }));
    cr_assert_null(rocks_cliffs_create(&(rocks_cliffs_desc){ .stratum_height = -1 }));
}

/* The world's cliffs at 2 m (level 1): some blocks show, and a coarse sample is never above the
 * 1 m field's at the same point nor below the base field (a coarse field shows a subset of the
 * blocks, each thinned or as it is: f̃ = max(f, t − e) with e ≥ 0). */
Test(rocks_blocks, cliffs_in_coarse_fields) {
    rocks_cliffs *cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 1, .strata = { ROCKS_BLOCK_COLUMNAR },
                                                                     .tile_size = 12 });
    terrain_world *world = cliff_world(wall_chunk, cliffs);
    terrain_world *plain = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk });
    terrain_field fine, coarse, base;
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -8, 0, 0 }, .size = { 17, 21, 25 } }, &fine));
    cr_assert(terrain_field_sample(plain, &(terrain_field_desc){ .first = { -8, 0, 0 }, .size = { 17, 21, 25 } }, &base));
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -8, 0, 0 }, .size = { 9, 11, 13 }, .step = 2 },
                                   &coarse));
    int raised = 0;
    for (int z = 0; z < 13; z++)
        for (int y = 0; y < 11; y++)
            for (int x = 0; x < 9; x++) {
                float v = coarse.values[((size_t)z * 11 + y) * 9 + x];
                size_t i = ((size_t)(2 * z) * 21 + 2 * y) * 17 + 2 * x;
                cr_assert_leq(v, fine.values[i]);
                cr_assert_geq(v, base.values[i]);
                raised += v > base.values[i];
            }
    cr_assert_gt(raised, 0, "blocks in the 2 m field");
    terrain_field_free(&fine);
    terrain_field_free(&coarse);
    terrain_field_free(&base);
    terrain_world_destroy(world);
    terrain_world_destroy(plain);
    rocks_cliffs_destroy(cliffs);
}

/* Strata: with tabular blocks in the bands [0, 10) and [20, 30) and columnar ones between, the
 * blocks raised in a band are that band's type's (tiles of one seed differ by type). */
Test(rocks_blocks, strata_choose_the_type) {
    rocks_cliffs *both = rocks_cliffs_create(&(rocks_cliffs_desc){
        .strata_count = 2, .strata = { ROCKS_BLOCK_TABULAR, ROCKS_BLOCK_COLUMNAR }, .stratum_height = 10, .tile_size = 12 });
    rocks_cliffs *tabular = rocks_cliffs_create(&(rocks_cliffs_desc){
        .strata_count = 1, .strata = { ROCKS_BLOCK_TABULAR }, .stratum_height = 10, .tile_size = 12 });
    terrain_world *a = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk, .amplify = rocks_cliffs_amplify,
                                                                 .amplify_user = both });
    terrain_world *b = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk, .amplify = rocks_cliffs_amplify,
                                                                 .amplify_user = tabular });
    /* a sample deep in a tabular band, away from the band's borders by more than a block */
    int same = 0, differ = 0;
    for (int z = 0; z < 24; z += 2)
        for (int y = 1; y < 20; y++) {
            float fa = terrain_field_at(a, 0.5, y, z, 0), fb = terrain_field_at(b, 0.5, y, z, 0);
            bool tabular_band = y >= 3 && y <= 7;     /* tabular anchors in [0, 10) reach here */
            bool columnar_band = y >= 13 && y <= 17;  /* only columnar ones here for `both` */
            if (tabular_band) same += fa == fb;
            if (columnar_band) differ += fa != fb;
        }
    cr_assert_gt(same, 0);
    cr_assert_gt(differ, 0, "the middle band holds the other type's blocks");
    terrain_world_destroy(a);
    terrain_world_destroy(b);
    rocks_cliffs_destroy(both);
    rocks_cliffs_destroy(tabular);
}

/* ---- the cache file (rocks_blocks_cache.c) -------------------------------------------------- */

/* The layout's header, worked out from the file's comment: magic, version, marker, seed, type,
 * 8 floats of the desc, 6 counts, the grid. Then the arrays and a u64 checksum. */
enum { CACHE_HEADER = 8 + 4 + 4 + 8 + 4 + 8 * 4 + 6 * 4 + 4 };

static rocks_block_tile_desc cache_tile_desc(const char *path) {
    return (rocks_block_tile_desc){ .type = ROCKS_BLOCK_TABULAR, .seed = 17, .size = 8.0f, .point_spacing = 0.6f,
                                    .fracture_spacing = 2.5f, .fracture_radius = 3.0f, .cache_path = path };
}

static size_t grid_cells(const rocks_block_tile *t) { return (size_t)t->grid * t->grid * t->grid; }

/* Every array, count and parameter of two tiles the same. */
static bool same_tile(const rocks_block_tile *a, const rocks_block_tile *b) {
    const rocks_block_tile_desc *p = &a->desc, *q = &b->desc;
    if (p->type != q->type || p->seed != q->seed || p->size != q->size || p->point_spacing != q->point_spacing ||
        p->fracture_spacing != q->fracture_spacing || p->fracture_radius != q->fracture_radius ||
        p->rounding != q->rounding || p->joint != q->joint || p->relief != q->relief ||
        p->relief_scale != q->relief_scale || p->custom_count != q->custom_count)
        return false;
    if (a->block_count != b->block_count || a->plane_count != b->plane_count || a->point_count != b->point_count ||
        a->disc_count != b->disc_count || a->sample_count != b->sample_count || a->grid != b->grid ||
        a->grid_entry_count != b->grid_entry_count)
        return false;
    return memcmp(a->blocks, b->blocks, a->block_count * sizeof *a->blocks) == 0 &&
           memcmp(a->planes, b->planes, a->plane_count * sizeof *a->planes) == 0 &&
           memcmp(a->points, b->points, a->point_count * sizeof *a->points) == 0 &&
           memcmp(a->discs, b->discs, a->disc_count * sizeof *a->discs) == 0 &&
           memcmp(a->grid_first, b->grid_first, (grid_cells(a) + 1) * sizeof *a->grid_first) == 0 &&
           memcmp(a->grid_entries, b->grid_entries, a->grid_entry_count * sizeof *a->grid_entries) == 0;
}

static unsigned char *read_all(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "%s", path);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *data = malloc(*size ? *size : 1);
    cr_assert_eq(fread(data, 1, *size, f), *size);
    fclose(f);
    return data;
}

static void write_all(const char *path, const unsigned char *data, size_t size) {
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f);
    if (size) fwrite(data, 1, size, f);
    fclose(f);
}

static bool file_exists(const char *path) {
    struct stat info;
    return stat(path, &info) == 0;
}

/* Files in a folder (the temporaries of a write must all be gone). */
static int files_in(const char *dir) {
    DIR *d = opendir(dir);
    cr_assert_not_null(d);
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d))) count += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return count;
}

/* Removes a folder made by the test and everything under it. */
static void remove_tree(const char *path) {
    DIR *d = opendir(path);
    if (!d) {
        remove(path);
        return;
    }
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char child[1024];
        snprintf(child, sizeof child, "%s/%s", path, e->d_name);
        remove_tree(child);
    }
    closedir(d);
    rmdir(path);
}

/* Runs `create(user)` with stderr in a file; returns what it made and the lines logged. */
static void *counting_notices(void *(*create)(const void *), const void *user, int *lines) {
    fflush(stderr);
    int saved = dup(2);
    FILE *log = tmpfile();
    dup2(fileno(log), 2);
    void *made = create(user);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(log);
    *lines = 0;
    int c;
    while ((c = fgetc(log)) != EOF) *lines += c == '\n';
    fclose(log);
    return made;
}

static void *create_tile(const void *desc) { return rocks_block_tile_create(desc); }
static void *create_cliffs(const void *desc) { return rocks_cliffs_create(desc); }

static rocks_block_tile *tile_counting_notices(const rocks_block_tile_desc *desc, int *lines) {
    return counting_notices(create_tile, desc, lines);
}

/* Recomputes a file's checksum after the test changed it on purpose (core_hash_bytes of every
 * byte before the last 8, with the seed the layout names). */
static void reseal(unsigned char *data, size_t size) {
    uint64_t sum = core_hash_bytes(data, size - 8, ROCKS__BLOCK_CACHE_CHECKSUM_SEED);
    memcpy(data + size - 8, &sum, 8);
}

/* Parses bytes; a tile accepted is freed. Returns whether it was accepted, its reason in *why. */
static bool parses(const unsigned char *data, size_t size, const rocks_block_tile_desc *desc, const char **why) {
    rocks_block_tile t;
    *why = NULL;
    bool ok = rocks__block_cache_parse(data, size, desc, &t, why);
    if (ok) rocks__block_tile_free_arrays(&t);
    else {
        cr_assert_not_null(*why, "a refusal says why");
        cr_assert(t.blocks == NULL && t.block_count == 0 && t.grid_first == NULL, "a refusal keeps nothing");
    }
    return ok;
}

/* The desc as the tile keeps it: defaults filled, no path (what the parser is given). */
static rocks_block_tile_desc filled(const rocks_block_tile *t) { return t->desc; }

/* A tile read back is the built one: the same arrays, and the same field (value and block) at
 * points all over, with and without presence; the file's size is the layout's; no temporary is
 * left; the folder is made when missing. */
Test(rocks_blocks, cache_round_trip) {
    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/sub/deeper/tile.bin", dir);
    rocks_block_tile_desc desc = cache_tile_desc(path);
    int lines;
    rocks_block_tile *built = tile_counting_notices(&desc, &lines);
    cr_assert_not_null(built);
    cr_expect_not(built->from_cache);
    cr_expect_gt(built->build_seconds, 0.0);
    cr_expect_eq(lines, 1, "a missing cache: one notice, %d lines", lines);
    cr_assert(file_exists(path), "the folder is made and the file written");
    cr_assert_null(built->desc.cache_path, "the tile does not keep the caller's path");
    snprintf(path, sizeof path, "%s/sub/deeper", dir);
    cr_expect_eq(files_in(path), 1, "no temporary left beside the file");
    snprintf(path, sizeof path, "%s/sub/deeper/tile.bin", dir);

    rocks_block_tile *loaded = tile_counting_notices(&desc, &lines);
    cr_assert_not_null(loaded);
    cr_expect(loaded->from_cache);
    cr_expect_eq(loaded->build_seconds, 0.0);
    cr_expect_eq(lines, 0, "read without a word");
    cr_assert(same_tile(built, loaded));
    uint64_t state = 31;
    for (int i = 0; i < 2000; i++) {
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = (unit(&state) - 0.5) * 5.0 * built->desc.size;
        uint32_t block_a, block_b;
        float a = rocks_block_tile_field(built, p, NULL, NULL, &block_a);
        float b = rocks_block_tile_field(loaded, p, NULL, NULL, &block_b);
        cr_assert(a == b || (isinf(a) && isinf(b)), "at %g %g %g: %g vs %g", p[0], p[1], p[2], a, b);
        cr_assert_eq(block_a, block_b);
        a = rocks_block_tile_field(built, p, every_other_copy, NULL, &block_a);
        b = rocks_block_tile_field(loaded, p, every_other_copy, NULL, &block_b);
        cr_assert(a == b || (isinf(a) && isinf(b)));
        cr_assert_eq(block_a, block_b);
    }
    size_t size;
    unsigned char *data = read_all(path, &size);
    size_t expected = CACHE_HEADER + built->block_count * (5 * 4 + 9 * 4) + built->plane_count * 16 +
                      built->point_count * 12 + built->disc_count * 7 * 4 + (grid_cells(built) + 1) * 4 +
                      built->grid_entry_count * 4 + 8;
    cr_expect_eq(size, expected, "%zu bytes, the layout gives %zu", size, expected);
    cr_expect_eq(memcmp(data, "ROCKBLCK", 8), 0);
    free(data);
    rocks_block_tile_destroy(built);
    rocks_block_tile_destroy(loaded);
    remove_tree(dir);
}

/* The parser on bytes in memory: every truncation and a longer file refused (the size the
 * counts imply is checked before an array is read), flipped bits anywhere refused, another
 * version, byte order or parameters refused and named. */
Test(rocks_blocks, cache_parser_refuses_cuts_and_damage) {
    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/tile.bin", dir);
    rocks_block_tile_desc desc = cache_tile_desc(path);
    rocks_block_tile *built = rocks_block_tile_create(&desc);
    cr_assert_not_null(built);
    const rocks_block_tile_desc want = filled(built);
    size_t size;
    unsigned char *good = read_all(path, &size);
    const char *why;
    cr_assert(parses(good, size, &want, &why), "the good file: %s", why ? why : "");

    int accepted = 0;
    for (size_t cut = 0; cut < size; cut++) accepted += parses(good, cut, &want, &why);
    cr_expect_eq(accepted, 0, "%d truncated caches accepted", accepted);
    unsigned char *longer = malloc(size + 16);
    memcpy(longer, good, size);
    memset(longer + size, 0, 16);
    cr_expect_not(parses(longer, size + 16, &want, &why));
    cr_expect(why && strstr(why, "longer"), "%s", why ? why : "");
    free(longer);

    /* flipped bits: every byte of the header, then spread over every array and the checksum */
    unsigned char *bad = malloc(size);
    int flips = 0;
    for (size_t i = 0; i < CACHE_HEADER + 400; i++) {
        size_t at = i < CACHE_HEADER + 8 ? (i < CACHE_HEADER ? i : size - 8 + (i - CACHE_HEADER))
                                         : (size_t)(((uint64_t)i * 2654435761u) % size);
        memcpy(bad, good, size);
        bad[at] ^= (unsigned char)(1u << (i % 8));
        bool ok = parses(bad, size, &want, &why);
        cr_expect_not(ok, "a flipped bit at byte %zu of %zu was accepted", at, size);
        flips++;
    }
    cr_expect_gt(flips, 400);

    /* each header field named: version, byte order, parameters */
    uint32_t value = ROCKS__BLOCK_CACHE_VERSION + 1;
    memcpy(bad, good, size), memcpy(bad + 8, &value, 4), reseal(bad, size);
    cr_expect_not(parses(bad, size, &want, &why));
    cr_expect(why && strstr(why, "version"), "%s", why ? why : "");
    value = 0x04030201u;   /* the marker as the other byte order reads it */
    memcpy(bad, good, size), memcpy(bad + 12, &value, 4), reseal(bad, size);
    cr_expect_not(parses(bad, size, &want, &why));
    cr_expect(why && strstr(why, "byte order"), "%s", why ? why : "");
    rocks_block_tile_desc other = want;
    other.seed++;
    cr_expect_not(parses(good, size, &other, &why));
    cr_expect(why && strstr(why, "parameters"), "%s", why ? why : "");
    other = want;
    other.joint = 0.2f;
    cr_expect_not(parses(good, size, &other, &why));
    other = want;
    other.type = ROCKS_BLOCK_COLUMNAR;
    cr_expect_not(parses(good, size, &other, &why));
    memcpy(bad, good, size);
    bad[size - 1] ^= 1;
    cr_expect_not(parses(bad, size, &want, &why));
    cr_expect(why && strstr(why, "checksum"), "%s", why ? why : "");
    free(bad);
    free(good);
    rocks_block_tile_destroy(built);
    remove_tree(dir);
}

/* A file whose checksum matches (written again over changed bytes) but whose contents break an
 * invariant is refused as inconsistent, before anything indexes with it. */
Test(rocks_blocks, cache_parser_refuses_inconsistent_files) {
    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/tile.bin", dir);
    rocks_block_tile_desc desc = cache_tile_desc(path);
    rocks_block_tile *t = rocks_block_tile_create(&desc);
    cr_assert_not_null(t);
    const rocks_block_tile_desc want = filled(t);
    size_t size;
    unsigned char *good = read_all(path, &size);
    cr_assert_gt(t->block_count, 3);
    cr_assert_gt(t->grid_entry_count, 3);
    const size_t blocks = CACHE_HEADER, block_size = sizeof(rocks_block);
    const size_t planes = blocks + t->block_count * block_size;
    const size_t grid_first = planes + t->plane_count * 16 + t->point_count * 12 + t->disc_count * sizeof(rocks_block_disc);
    const size_t entries = grid_first + (grid_cells(t) + 1) * 4;
    const uint32_t last = t->block_count - 1;
    const float nan = NAN, huge = 1e30f;
    struct { size_t at; const void *value; size_t bytes; const char *what; } cases[] = {
        { blocks + last * block_size + offsetof(rocks_block, plane_first), &t->plane_count, 4, "a plane range past the end" },
        { blocks + offsetof(rocks_block, plane_count), &(uint32_t){ t->plane_count + 1 }, 4, "a plane count past the end" },
        { blocks + offsetof(rocks_block, point_first), &(uint32_t){ UINT32_MAX }, 4, "a point range past the end" },
        { blocks + offsetof(rocks_block, custom), &(uint32_t){ 1 }, 4, "a custom block" },
        { blocks + offsetof(rocks_block, bounds_min), &nan, 4, "a NaN bound" },
        { blocks + offsetof(rocks_block, anchor), &huge, 4, "an anchor far off" },
        { planes + 12, &nan, 4, "a NaN plane" },
        { entries, &(uint32_t){ t->block_count << 5 }, 4, "a grid entry's block past the count" },
        { entries, &(uint32_t){ 27 }, 4, "a grid entry's image past 26" },
        { grid_first, &(uint32_t){ 1 }, 4, "grid_first not starting at 0" },
        { grid_first + grid_cells(t) * 4, &(uint32_t){ t->grid_entry_count - 1 }, 4, "grid_first not ending at the count" },
        { grid_first + 4, &(uint32_t){ t->grid_entry_count + 5 }, 4, "grid_first decreasing" },
        { 8 + 4 + 4 + 8 + 4 + 8 * 4 + 6 * 4, &(int32_t){ t->grid + 1 }, 4, "another grid" },
        { 8 + 4 + 4 + 8 + 4 + 8 * 4 + 5 * 4, &(uint32_t){ t->point_count - 1 }, 4, "fewer samples than points" },
    };
    unsigned char *bad = malloc(size);
    for (size_t i = 0; i < CORE_COUNTOF(cases); i++) {
        memcpy(bad, good, size);
        memcpy(bad + cases[i].at, cases[i].value, cases[i].bytes);
        reseal(bad, size);
        const char *why;
        cr_expect_not(parses(bad, size, &want, &why), "%s was accepted", cases[i].what);
        cr_expect(why && strstr(why, "inconsistent"), "%s: %s", cases[i].what, why ? why : "");
    }
    free(bad);
    free(good);
    rocks_block_tile_destroy(t);
    remove_tree(dir);
}

/* Through rocks_block_tile_create: a cut file, a flipped byte, an old version number, an empty
 * file, another seed's file: each rebuilt with exactly one notice, the same tile as built, and
 * the file rewritten is read back next time without a word. */
Test(rocks_blocks, cache_damage_rebuilds_with_one_notice) {
    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/tile.bin", dir);
    rocks_block_tile_desc desc = cache_tile_desc(path);
    int lines;
    rocks_block_tile *built = tile_counting_notices(&desc, &lines);
    cr_assert_not_null(built);
    size_t size;
    unsigned char *good = read_all(path, &size);
    for (int kind = 0; kind < 4; kind++) {
        unsigned char *bad = malloc(size);
        memcpy(bad, good, size);
        size_t bad_size = size;
        if (kind == 0) bad_size = size / 2;
        if (kind == 1) bad[size / 3] ^= 0x10;
        if (kind == 2) {
            uint32_t old = ROCKS__BLOCK_CACHE_VERSION - 1;
            memcpy(bad + 8, &old, sizeof old);
        }
        if (kind == 3) bad_size = 0;
        write_all(path, bad, bad_size);
        free(bad);
        rocks_block_tile *again = tile_counting_notices(&desc, &lines);
        cr_assert_not_null(again);
        cr_expect_not(again->from_cache, "case %d", kind);
        cr_expect_eq(lines, 1, "case %d: %d lines", kind, lines);
        cr_expect(same_tile(built, again), "case %d", kind);
        rocks_block_tile_destroy(again);
        rocks_block_tile *reread = tile_counting_notices(&desc, &lines);
        cr_expect(reread->from_cache, "case %d: the rewritten cache", kind);
        cr_expect_eq(lines, 0, "case %d", kind);
        cr_expect(same_tile(built, reread), "case %d", kind);
        rocks_block_tile_destroy(reread);
    }
    /* other parameters: rebuilt (one notice), and a tile of those parameters, not the file's */
    rocks_block_tile_desc other = desc;
    other.seed = 18;
    rocks_block_tile *rebuilt = tile_counting_notices(&other, &lines);
    cr_expect_not(rebuilt->from_cache);
    cr_expect_eq(lines, 1);
    cr_expect_eq(rebuilt->desc.seed, 18u);
    cr_expect_not(same_tile(built, rebuilt));
    rocks_block_tile_destroy(rebuilt);
    other = desc;
    other.relief = -1.0f;
    rebuilt = tile_counting_notices(&other, &lines);
    cr_expect_not(rebuilt->from_cache);
    cr_expect_eq(lines, 1);
    rocks_block_tile_destroy(rebuilt);
    /* an unwritable path (under a file) is never fatal: the tile is built */
    char blocked[300];
    snprintf(blocked, sizeof blocked, "%s/tile.bin/inside.bin", dir);
    other = desc;
    other.cache_path = blocked;
    rebuilt = tile_counting_notices(&other, &lines);
    cr_assert_not_null(rebuilt);
    cr_expect_not(rebuilt->from_cache);
    cr_expect(same_tile(built, rebuilt));
    rocks_block_tile_destroy(rebuilt);
    free(good);
    rocks_block_tile_destroy(built);
    remove_tree(dir);
}

/* A tile with custom blocks holds function pointers: never cached, cache_path ignored. */
Test(rocks_blocks, custom_tile_not_cached) {
    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/custom.bin", dir);
    sphere ball = { .centre = { 4.0f, 4.0f, 4.0f }, .radius = 1.0f };
    rocks_block_custom custom = { .field = sphere_field, .user = &ball, .bounds_min = { 3, 3, 3 }, .bounds_max = { 5, 5, 5 } };
    rocks_block_tile_desc desc = cache_tile_desc(path);
    desc.custom = &custom, desc.custom_count = 1;
    for (int run = 0; run < 2; run++) {
        int lines;
        rocks_block_tile *t = tile_counting_notices(&desc, &lines);
        cr_assert_not_null(t);
        cr_expect_not(t->from_cache);
        cr_expect_eq(lines, 0, "no cache, no notice");
        cr_expect_eq(t->blocks[0].custom, 1u);
        rocks_block_tile_destroy(t);
    }
    cr_expect_not(file_exists(path));
    cr_expect_eq(files_in(dir), 0);
    remove_tree(dir);
}

/* rocks_cliffs with cache_dir writes a file per type, named by type and seed (42 = 0x2a: a
 * world of another seed has files of its own); a second create reads them; with jobs the tiles
 * (their files, byte for byte) are those made without. The two cheapest types: four tile builds
 * are most of the suite's time under the sanitizers. */
Test(rocks_blocks, cliffs_cache_dir_and_jobs) {
    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char serial_dir[300], parallel_dir[300];
    snprintf(serial_dir, sizeof serial_dir, "%s/serial", dir);
    snprintf(parallel_dir, sizeof parallel_dir, "%s/parallel", dir);
    rocks_cliffs_desc desc = { .seed = 42, .strata_count = 3, .stratum_height = 10, .tile_size = 8,
                               .strata = { ROCKS_BLOCK_COLUMNAR, ROCKS_BLOCK_TABULAR, ROCKS_BLOCK_COLUMNAR },
                               .cache_dir = serial_dir };
    int lines;
    rocks_cliffs *first = counting_notices(create_cliffs, &desc, &lines);
    cr_assert_not_null(first);
    cr_expect_eq(lines, 2, "one notice per type's missing file: %d lines", lines);
    cr_expect_eq(rocks_cliffs_stats(first).tiles_from_cache, 0u);
    cr_expect_eq(files_in(serial_dir), 2, "a file per type the strata use");
    char columnar[400], tabular[400];
    snprintf(columnar, sizeof columnar, "%s/blocks-columnar-000000000000002a.bin", serial_dir);
    snprintf(tabular, sizeof tabular, "%s/blocks-tabular-000000000000002a.bin", serial_dir);
    cr_assert(file_exists(columnar) && file_exists(tabular));
    rocks_cliffs_destroy(first);

    rocks_cliffs *second = counting_notices(create_cliffs, &desc, &lines);
    cr_assert_not_null(second);
    cr_expect_eq(lines, 0);
    cr_expect_eq(rocks_cliffs_stats(second).tiles_from_cache, 2u, "both tiles read back");
    rocks_cliffs_destroy(second);

    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 3 });
    rocks_cliffs_desc parallel = desc;
    parallel.cache_dir = parallel_dir, parallel.jobs = jobs;
    rocks_cliffs *third = counting_notices(create_cliffs, &parallel, &lines);
    cr_assert_not_null(third);
    cr_expect_eq(lines, 2);
    cr_expect_eq(rocks_cliffs_stats(third).tiles_from_cache, 0u);
    rocks_cliffs_destroy(third);
    job_system_destroy(jobs);
    const char *types[] = { "columnar", "tabular" };
    for (int i = 0; i < 2; i++) {
        char a[400], b[400];
        snprintf(a, sizeof a, "%s/blocks-%s-000000000000002a.bin", serial_dir, types[i]);
        snprintf(b, sizeof b, "%s/blocks-%s-000000000000002a.bin", parallel_dir, types[i]);
        size_t size_a, size_b;
        unsigned char *da = read_all(a, &size_a), *db = read_all(b, &size_b);
        cr_expect(size_a == size_b && memcmp(da, db, size_a) == 0, "%s: the jobs' tile differs", types[i]);
        free(da);
        free(db);
    }
    remove_tree(dir);
}

/* ROCKS_BLOCK_DEFAULT, a zeroed desc's type, is equidimensional: the tile is the one asked for by
 * name, plane for plane, and its desc says so; a zeroed stratum (with strata_count set) makes an
 * equidimensional tile too, the file named after it. */
Test(rocks_blocks, a_zeroed_type_is_equidimensional) {
    rocks_block_tile *zero = small_tile(ROCKS_BLOCK_DEFAULT, 5, 0.0f);
    rocks_block_tile *named = small_tile(ROCKS_BLOCK_EQUIDIMENSIONAL, 5, 0.0f);
    cr_assert_eq(zero->desc.type, ROCKS_BLOCK_EQUIDIMENSIONAL);
    cr_assert_eq(zero->block_count, named->block_count);
    cr_assert_eq(zero->plane_count, named->plane_count);
    cr_assert_eq(memcmp(zero->planes, named->planes, zero->plane_count * sizeof *zero->planes), 0);
    rocks_block_tile_destroy(zero);
    rocks_block_tile_destroy(named);

    char dir[] = "/tmp/test_blocks_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    rocks_cliffs *cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){ .seed = 42, .strata_count = 1, .tile_size = 8,
                                                                      .cache_dir = dir });
    cr_assert_not_null(cliffs);
    char path[400];
    snprintf(path, sizeof path, "%s/blocks-equidimensional-000000000000002a.bin", dir);
    cr_expect(file_exists(path), "a zeroed stratum is equidimensional");
    cr_expect_eq(files_in(dir), 1);
    rocks_cliffs_destroy(cliffs);
    remove_tree(dir);
}

/* block_scale grows the blocks and keeps their shapes: scaled by 1.5, the tile's side and its
 * fractures' spacing grow alike, so a tile holds about as many blocks (each 3.4 times the
 * volume), and the 20 m wall still gets them. Scales outside 0.5 … 4, or a scaled side over
 * 64 m, are refused. */
Test(rocks_blocks, cliffs_block_scale_grows_the_blocks) {
    rocks_cliffs_desc desc = { .strata_count = 1, .strata = { ROCKS_BLOCK_COLUMNAR }, .tile_size = 12 };
    rocks_cliffs *plain = rocks_cliffs_create(&desc);
    desc.block_scale = 1.5f;
    rocks_cliffs *big = rocks_cliffs_create(&desc);
    cr_assert_not_null(plain);
    cr_assert_not_null(big);
    rocks_cliffs_stats_info a = rocks_cliffs_stats(plain), b = rocks_cliffs_stats(big);
    cr_expect_float_eq(a.tile_size, 12.0f, 1e-6f);
    cr_expect_float_eq(b.tile_size, 18.0f, 1e-6f);
    cr_expect_gt(a.blocks, 0);
    cr_expect(b.blocks * 10 >= a.blocks * 9 && b.blocks * 10 <= a.blocks * 11, "blocks a tile: %u at scale 1, %u at 1.5",
              a.blocks, b.blocks);
    terrain_world *world = cliff_world(wall_chunk, big);
    cr_expect_gt(raised_samples(wall_chunk, world, 1), 20);
    terrain_world_destroy(world);
    rocks_cliffs_destroy(plain);
    rocks_cliffs_destroy(big);
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);
    cr_expect_null(rocks_cliffs_create(&(rocks_cliffs_desc){ .block_scale = 0.25f }));
    cr_expect_null(rocks_cliffs_create(&(rocks_cliffs_desc){ .block_scale = 5 }));
    cr_expect_null(rocks_cliffs_create(&(rocks_cliffs_desc){ .tile_size = 32, .block_scale = 4 }));
    core_log_set_level(level);
}
