/* terrain_brush.c — editing brushes on a terrain_columns region (000 §4.3, §4.4).
 *
 * Deposit (§4.3): "a brush characterized by a depositing region R and the distribution of material
 * within this region". The region is a disc of radius R around (x, z); the distribution is
 * §4.1's g(r) = (1 − r²/R²)² (or flat) at each column's centre, scaled so that the volume asked
 * for is dropped exactly: each column gets ⌊Q·w/Σw⌋ quanta and the Q − Σ⌊…⌋ left over go one
 * each to the columns with the largest remainders (ties to the lower index), Q the volume in
 * quanta·column. The material lands on the pile (sand under rocks, both under water: §3.4's
 * order) and stays where it lands until stabilization moves it. Water on the pile is displaced
 * (it flows off, as the sculpt brush's added material displaces it): as much of it goes as the
 * pile rises, so a water surface never rises with a deposit into it.
 *
 * Erosion (§4.4): bedrock turns into rocks and sand, a share ρ of rocks ("the relative volume of
 * rocks and sand produced by erosion"), per column rocks = round(ρ·e) and sand = e − rocks of the
 * e bedrock quanta eroded, so the mass is exact column by column. Surface erosion lowers the
 * top of each column's highest bedrock layer by depth·g(r) (the paper turns "only the bedrock
 * material layers at the surface" into sediment); the granular material takes the bedrock's
 * place under the pile, so the ground does not move until stabilization does. A layer eroded
 * through opens what lies below, and the material falls there when stabilization sorts the
 * column. Collapse erosion ("rocks detaching from the bedrock and falling apart") turns all
 * bedrock inside the ball of radius R around (x, y, z) into granular material; sorting then
 * drops it, and what lay on it, to the next stable layer below.
 */
#include "terrain/edit/terrain_edit_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdlib.h>

#define WEIGHT_ONE (1 << 24)                   /* brush weights in fixed point */
#define MAX_RADIUS 1e5f
#define MAX_VOLUME 1e9                         /* m³: 3.2·10^10 quanta, products stay in 64 bits */

/* The columns whose centres a disc of radius r around (x, z) may cover, clipped to the region;
 * false when it misses the region. */
static bool disc_bounds(const terrain_columns *c, double x, double z, double r, int *i0, int *k0, int *i1, int *k1) {
    double u = x - (double)c->x0 - 0.5, v = z - (double)c->z0 - 0.5;   /* centre in column indices */
    double lo_i = floor(u - r), hi_i = ceil(u + r), lo_k = floor(v - r), hi_k = ceil(v + r);
    if (hi_i < 0 || hi_k < 0 || lo_i > c->width - 1 || lo_k > c->depth - 1) return false;
    *i0 = (int)fmax(lo_i, 0);
    *k0 = (int)fmax(lo_k, 0);
    *i1 = (int)fmin(hi_i, c->width - 1);
    *k1 = (int)fmin(hi_k, c->depth - 1);
    return true;
}

/* g at column (i, k)'s centre, 0 outside the disc. */
static double brush_weight(const terrain_columns *c, double x, double z, double r, terrain_falloff falloff, int i,
                           int k) {
    double dx = (double)c->x0 + i + 0.5 - x, dz = (double)c->z0 + k + 0.5 - z;
    double t = (dx * dx + dz * dz) / (r * r);
    if (t >= 1.0) return 0.0;
    return falloff == TERRAIN_FALLOFF_FLAT ? 1.0 : (1.0 - t) * (1.0 - t);   /* 000 §4.1's g(r) */
}

/* A world height as quanta above the floor, clamped to the columns' range. */
static int64_t height_quanta(double y) {
    double q = (y - (double)TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE;
    return llround(fmin(fmax(q, -1.0), (double)TERRAIN__COLUMN_MAX_QUANTA));
}

static bool valid_falloff(terrain_falloff f) {
    return f == TERRAIN_FALLOFF_DEFAULT || f == TERRAIN_FALLOFF_SMOOTH || f == TERRAIN_FALLOFF_FLAT;
}

/* ---- deposit (000 §4.3) --------------------------------------------------------------------- */

typedef struct share {
    int i, k;
    int64_t weight, quanta, remainder;
} share;

static int by_remainder(const void *a, const void *b) {
    const share *x = a, *y = b;
    if (x->remainder != y->remainder) return x->remainder > y->remainder ? -1 : 1;
    if (x->k != y->k) return x->k < y->k ? -1 : 1;
    return (x->i > y->i) - (x->i < y->i);
}

static bool valid_deposit(const terrain_deposit_desc *d, terrain_material material) {
    if (material != TERRAIN_SAND && material != TERRAIN_ROCKS) {
        core_log_error("terrain", "deposit: brush material %d (%s) is not sand or rocks", (int)d->material,
                   terrain_material_name(material));
        return false;
    }
    if (!isfinite(d->x) || !isfinite(d->z) || (d->at_height && !isfinite(d->y)) || !(d->radius > 0.0f) ||
        d->radius > MAX_RADIUS) {
        core_log_error("terrain", "deposit: centre (%g, %g), height %g, radius %g m (finite, 0 < radius <= %g)",
                   d->x, d->z, d->y, (double)d->radius, (double)MAX_RADIUS);
        return false;
    }
    if (!(d->volume >= 0.0) || d->volume > MAX_VOLUME) {
        core_log_error("terrain", "deposit: volume %g m3 (0 ... %g)", d->volume, MAX_VOLUME);
        return false;
    }
    if (!valid_falloff(d->falloff)) {
        core_log_error("terrain", "deposit: unknown falloff %d", (int)d->falloff);
        return false;
    }
    return true;
}

/* The columns under the brush with their integer weights; returns how many (shares allocated
 * with room for the disc's bounding box). */
static int deposit_shares(const terrain_columns *c, const terrain_deposit_desc *d, share **out, size_t *capacity,
                          int64_t *weight_sum) {
    int i0, k0, i1, k1;
    *out = NULL;
    *capacity = 0;
    *weight_sum = 0;
    if (!disc_bounds(c, d->x, d->z, d->radius, &i0, &k0, &i1, &k1)) return 0;
    *capacity = (size_t)(i1 - i0 + 1) * (size_t)(k1 - k0 + 1);
    share *s = core_alloc(*capacity * sizeof *s);
    int n = 0;
    for (int k = k0; k <= k1; k++) {
        for (int i = i0; i <= i1; i++) {
            double w = brush_weight(c, d->x, d->z, d->radius, d->falloff, i, k);
            int64_t weight = llround(w * WEIGHT_ONE);
            if (weight <= 0) continue;
            s[n++] = (share){ .i = i, .k = k, .weight = weight };
            *weight_sum += weight;
        }
    }
    *out = s;
    return n;
}

bool terrain_deposit(terrain_columns *c, const terrain_deposit_desc *desc, int64_t *quanta) {
    if (quanta) *quanta = 0;
    if (!c || !desc) {
        core_log_error("terrain", "deposit: no region or no description");
        return false;
    }
    terrain_material material = terrain__brush_material(desc->material, TERRAIN_SAND);
    if (!valid_deposit(desc, material)) return false;
    int64_t total = llround(desc->volume * TERRAIN__QUANTA_PER_METRE);
    if (total == 0) return true;

    share *shares;
    size_t capacity;
    int64_t weight_sum;
    int count = deposit_shares(c, desc, &shares, &capacity, &weight_sum);
    if (count == 0) {
        core_log_error("terrain", "deposit: the brush at (%g, %g), radius %g m, covers no column centre of the region",
                   desc->x, desc->z, (double)desc->radius);
        core_free(shares, capacity * sizeof *shares);
        return false;
    }
    /* Largest remainders: the total is exact and the rounding depends on nothing but the input. */
    int64_t given = 0;
    for (int n = 0; n < count; n++) {
        shares[n].quanta = total * shares[n].weight / weight_sum;
        shares[n].remainder = total * shares[n].weight % weight_sum;
        given += shares[n].quanta;
    }
    qsort(shares, (size_t)count, sizeof *shares, by_remainder);
    for (int64_t n = 0; n < total - given; n++) shares[n].quanta++;

    if (desc->at_height) {
        /* Each column's share goes into its space nearest y (terrain__columns_insert). */
        int64_t placed = 0, height = height_quanta(desc->y);
        for (int n = 0; n < count; n++)
            placed += terrain__columns_insert(c, shares[n].i, shares[n].k, height, (uint32_t)material,
                                              (int32_t)CORE_MIN(shares[n].quanta, (int64_t)INT32_MAX));
        if (quanta) *quanta = placed;
        core_free(shares, capacity * sizeof *shares);
        return true;
    }
    bool fits = true;
    for (int n = 0; n < count && fits; n++)
        fits = c->ground[terrain__cell(c, shares[n].i, shares[n].k)] + shares[n].quanta < TERRAIN__COLUMN_MAX_QUANTA;
    if (!fits) {
        core_log_error("terrain", "deposit: %g m3 on a radius of %g m would pile a column over %d m", desc->volume,
                   (double)desc->radius, TERRAIN__COLUMN_MAX_QUANTA / 32);
    } else {
        for (int n = 0; n < count; n++) {
            if (shares[n].quanta == 0) continue;
            size_t cell = terrain__cell(c, shares[n].i, shares[n].k);
            int32_t q = (int32_t)shares[n].quanta;
            if (material == TERRAIN_SAND) c->sand_top[cell] += q;
            c->ground[cell] += q;
            /* The water standing on the pile is displaced, not lifted: its surface stays. */
            int32_t *water = &c->water[(size_t)shares[n].k * (size_t)c->width + (size_t)shares[n].i];
            *water = CORE_MAX(*water - q, 0);
            terrain__columns_touch(c, shares[n].i, shares[n].k);
        }
        if (quanta) *quanta = total;
    }
    core_free(shares, capacity * sizeof *shares);
    return fits;
}

/* ---- erosion (000 §4.4) --------------------------------------------------------------------- */

static bool valid_erode(const terrain_erode_desc *d) {
    if (d->mode != TERRAIN_ERODE_DEFAULT && d->mode != TERRAIN_ERODE_SURFACE && d->mode != TERRAIN_ERODE_COLLAPSE) {
        core_log_error("terrain", "erode: unknown mode %d", (int)d->mode);
        return false;
    }
    bool collapse = d->mode == TERRAIN_ERODE_COLLAPSE;
    if (!isfinite(d->x) || !isfinite(d->z) || ((collapse || d->at_height) && !isfinite(d->y)) || !(d->radius > 0.0f) ||
        d->radius > MAX_RADIUS) {
        core_log_error("terrain", "erode: centre (%g, %g, %g), radius %g m (finite, 0 < radius <= %g)", d->x, d->y, d->z,
                   (double)d->radius, (double)MAX_RADIUS);
        return false;
    }
    if (!(d->depth >= 0.0f) || d->depth > MAX_RADIUS) {
        core_log_error("terrain", "erode: depth %g m (0 ... %g)", (double)d->depth, (double)MAX_RADIUS);
        return false;
    }
    if (!(d->rocks_ratio >= 0.0f && d->rocks_ratio <= 1.0f)) {
        core_log_error("terrain", "erode: rocks_ratio %g (0 ... 1)", (double)d->rocks_ratio);
        return false;
    }
    if (!valid_falloff(d->falloff)) {
        core_log_error("terrain", "erode: unknown falloff %d", (int)d->falloff);
        return false;
    }
    return true;
}

typedef struct eroder {
    terrain_columns *c;
    const terrain_erode_desc *desc;
    terrain__clayer *scratch;
    size_t capacity;
    terrain__gap *gaps;
    size_t gap_capacity;
    int64_t eroded;
} eroder;

/* The column's layers with out[0..count) rebuilt in scratch after the input (room for count + 4
 * more per bedrock layer: a layer cut in two with sand and rocks between). */
static terrain__clayer *output_room(eroder *e, int count) {
    e->scratch = core_grow(e->scratch, &e->capacity, (size_t)count * 5 + 8, sizeof *e->scratch);
    return e->scratch + count;
}

static int push(terrain__clayer *out, int n, uint32_t material, int64_t quanta) {
    if (quanta <= 0) return n;
    out[n++] = (terrain__clayer){ material, (int32_t)quanta };
    return n;
}

/* Sand and rocks for `bedrock` eroded quanta, per 000 §4.4's ρ. */
static int push_granular(eroder *e, terrain__clayer *out, int n, int64_t bedrock) {
    int64_t rocks = llround((double)bedrock * (double)e->desc->rocks_ratio);
    n = push(out, n, TERRAIN_SAND, bedrock - rocks);
    n = push(out, n, TERRAIN_ROCKS, rocks);
    e->eroded += bedrock;
    return n;
}

/* Surface: the stable layer under a space of the column — the open top space (the highest
 * stable layer), or with a height the space nearest it (a cave's floor) — loses `depth` quanta
 * from its top if it is bedrock, turned into granular material at the bottom of that space
 * (sorted into it: sand, rocks, water, air). Layers above the space stay as they were. */
static void erode_surface(eroder *e, int i, int k, int64_t depth, bool at_height, int64_t height) {
    terrain_columns *c = e->c;
    if (c->flags[(size_t)k * (size_t)c->width + (size_t)i] & TERRAIN__COLUMN_UNSORTED)
        terrain__columns_sort(c, i, k, &e->scratch, &e->capacity);
    int count = terrain__columns_layers(c, i, k, &e->scratch, &e->capacity);
    e->gaps = core_grow(e->gaps, &e->gap_capacity, (size_t)count + 1, sizeof *e->gaps);
    int gap_count = terrain__column_gaps(e->scratch, count, e->gaps, count + 1);
    const terrain__gap *g = &e->gaps[at_height ? terrain__gap_nearest(e->gaps, gap_count, height) : gap_count - 1];
    int under = g->first - 1;
    if (under < 0 || e->scratch[under].material != TERRAIN_BEDROCK || depth <= 0) return;
    terrain__clayer *out = output_room(e, count), *in = e->scratch;
    int64_t eroded = CORE_MIN(depth, (int64_t)in[under].quanta);
    int n = 0;
    for (int l = 0; l < under; l++) out[n++] = in[l];
    n = push(out, n, TERRAIN_BEDROCK, in[under].quanta - eroded);
    int64_t rocks = llround((double)eroded * (double)e->desc->rocks_ratio);
    n = push(out, n, TERRAIN_SAND, g->amount[0] + eroded - rocks);
    n = push(out, n, TERRAIN_ROCKS, g->amount[1] + rocks);
    n = push(out, n, TERRAIN_WATER, g->amount[2]);
    n = push(out, n, TERRAIN_AIR, g->amount[3]);
    for (int l = g->end; l < count; l++) out[n++] = in[l];
    e->eroded += eroded;
    terrain__columns_store(c, i, k, out, n);
    terrain__columns_touch(c, i, k);
}

/* Collapse: bedrock in [lo, hi) (quanta above the floor) turns granular where it is. */
static void erode_span(eroder *e, int i, int k, int64_t lo, int64_t hi) {
    int count = terrain__columns_layers(e->c, i, k, &e->scratch, &e->capacity);
    terrain__clayer *out = output_room(e, count), *in = e->scratch;
    int64_t bottom = 0, before = e->eroded;
    int n = 0;
    for (int l = 0; l < count; l++) {
        int64_t top = bottom + in[l].quanta;
        int64_t a = CORE_MAX(bottom, lo), b = CORE_MIN(top, hi);
        if (in[l].material != TERRAIN_BEDROCK || a >= b) {
            out[n++] = in[l];
        } else {
            n = push(out, n, TERRAIN_BEDROCK, a - bottom);
            n = push_granular(e, out, n, b - a);
            n = push(out, n, TERRAIN_BEDROCK, top - b);
        }
        bottom = top;
    }
    if (e->eroded == before) return;
    terrain__columns_store(e->c, i, k, out, n);
    terrain__columns_touch(e->c, i, k);
}

bool terrain_erode(terrain_columns *c, const terrain_erode_desc *desc, int64_t *quanta) {
    if (quanta) *quanta = 0;
    if (!c || !desc) {
        core_log_error("terrain", "erode: no region or no description");
        return false;
    }
    if (!valid_erode(desc)) return false;
    eroder e = { .c = c, .desc = desc };
    int i0, k0, i1, k1;
    double r = desc->radius;
    if (disc_bounds(c, desc->x, desc->z, r, &i0, &k0, &i1, &k1)) {
        for (int k = k0; k <= k1; k++) {
            for (int i = i0; i <= i1; i++) {
                double w = brush_weight(c, desc->x, desc->z, r, desc->falloff, i, k);
                if (w <= 0.0) continue;
                if (desc->mode != TERRAIN_ERODE_COLLAPSE) {   /* surface, the default */
                    erode_surface(&e, i, k, llround((double)desc->depth * w * TERRAIN__QUANTA_PER_METRE),
                                  desc->at_height, desc->at_height ? height_quanta(desc->y) : 0);
                    continue;
                }
                /* The ball's chord along the column's axis. */
                double dx = (double)c->x0 + i + 0.5 - desc->x, dz = (double)c->z0 + k + 0.5 - desc->z;
                double half = sqrt(fmax(r * r - dx * dx - dz * dz, 0.0));
                double floor_y = TERRAIN_FLOOR_Y;
                int64_t lo = llround(fmax(desc->y - half - floor_y, 0.0) * TERRAIN__QUANTA_PER_METRE);
                int64_t hi = llround(fmin(fmax(desc->y + half - floor_y, 0.0), (double)TERRAIN__COLUMN_MAX_QUANTA / 32) *
                                     TERRAIN__QUANTA_PER_METRE);
                if (lo < hi) erode_span(&e, i, k, lo, hi);
            }
        }
    }
    core_free(e.scratch, e.capacity * sizeof *e.scratch);
    core_free(e.gaps, e.gap_capacity * sizeof *e.gaps);
    if (quanta) *quanta = e.eroded;
    return true;
}
