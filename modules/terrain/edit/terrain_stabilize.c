/* terrain_stabilize.c — stabilization by the angle of repose (000 §3.4).
 *
 * The paper, per material layer (sand first, then rocks on top): h is the height of the
 * column's layer, h_i those of its eight neighbours, Δh_i = h − h_i (we write the drop from the
 * centre; the paper's figure measures it the other way round), s the distance between the
 * columns and α the material's angle of repose. The excess is Δh̃_i = Δh_i − s·tan α where that
 * is positive, else 0, and the column gives its neighbours
 *     Δz_i = a · Δh̃_i / Σ_j Δh̃_j
 * a "small constant amount a so as to avoid oscillations", repeated until nothing moves.
 * Readings we take:
 *   - s is the distance between column centres: 1 m to the four sides, √2 m to the corners
 *     (the slope is measured along the line the material slides on).
 *   - Sand moves on the sand surface (top of sand over the column's base), then rocks on the
 *     ground (top of rocks), each with its own angle: "a stabilization simulation step for every
 *     material, starting from bottom layers to top layers". A sand slope under rocks thus keeps
 *     the sand's angle, as Figure 7 shows.
 *   - A column gives a = min(step, what it holds, ⌈Σ_j Δh̃_j / (k + 1)⌉), k the neighbours with
 *     an excess: never more than it has, and no more than brings it level with them — giving
 *     Σ Δh̃ / (k + 1) to k neighbours with equal excesses leaves exactly the angle of repose
 *     (the centre drops by a, each neighbour rises by a / k). At least one quantum.
 *   - Thicknesses are integer quanta (1/32 m); the excess is fixed point (1/256 quantum), and
 *     Δz_i is rounded down with the remainder handed out one quantum at a time to the largest
 *     fractional parts (ties to the lower direction index): the mass of each material is
 *     conserved exactly and the rounding is the same everywhere.
 *   - A column moves only when some excess exceeds the tolerance; the distribution then uses
 *     all positive excesses.
 *
 * Order: colour-partitioned Gauss–Seidel. A column reads and writes only its 3 × 3
 * neighbourhood, so columns three apart in x and in z (one of nine colours, by world column
 * index mod 3) never touch the same column. A pass moves the material of every column of one
 * colour from the current heights, at once and in any order; nine passes in a fixed order (an
 * iteration) look at every column once. The outcome depends on nothing but the input: not on the
 * thread count (rows of one colour three apart are disjoint jobs), not on how the rows are split
 * into jobs, and not on how the world is split into regions (regions side by side copy a
 * one-column halo of their neighbours' heights before a pass and hand back what their border
 * columns gave into it after it; colours come from world coordinates), so a split region
 * stabilizes to the same bytes as one big region. Moving one column at a time is also what lets
 * the step be large: Σ h² over a surface is an integer that every move lowers (a move of a from
 * a drop of at least s·tan α, capped as above, changes it by −2·Σ Δz_i·Δh_i + a² + Σ Δz_i² < 0),
 * so the iteration always ends, whatever the step. (An earlier version updated all columns at
 * once from the old heights, Jacobi style; several columns then pile into one pit in the same
 * step, and it oscillated for steps over about two quanta.)
 *
 * Activity. A column's flows are a function of its 3 × 3 neighbourhood, so a pass looks only at
 * columns of its colour with a change in that neighbourhood during the last nine passes (since
 * the column's last look); an edit counts as a change. Stamps (the pass number) say what
 * changed, so nothing is cleared between passes, and a per-row span bounds the scan. Skipping
 * changes no result: a skipped column would have computed nothing.
 */
#include "terrain/edit/terrain_edit_internal.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include <limits.h>
#include <math.h>
#include <string.h>

#define FIXED 256                             /* excess in 1/256 quanta */
#define PARALLEL_MIN_COLUMNS 1024             /* a pass with fewer candidates runs on one thread */

typedef struct material_rule {
    int64_t slope[8];                         /* s·tan α in 1/256 quanta, per direction */
    int32_t quick[8];                         /* a drop of at most this many quanta moves nothing */
} material_rule;

typedef struct stabilize_rules {
    material_rule material[2];                /* sand, rocks */
    int64_t tolerance;                        /* 1/256 quanta */
    int32_t step;                             /* quanta */
    int max_iterations;
    uint64_t budget_ns;
    bool wake;
} stabilize_rules;

static bool diagonal(int d) { return terrain__dir[d][0] != 0 && terrain__dir[d][1] != 0; }

static int64_t floor_mod(int64_t a, int64_t b) {
    int64_t m = a % b;
    return m < 0 ? m + b : m;
}

static int64_t floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

/* ---- parameters ----------------------------------------------------------------------------- */

static bool angle_rule(const char *name, float degrees, float fallback, int64_t tolerance, material_rule *rule) {
    if (degrees == 0.0f) degrees = fallback;
    if (!(degrees > 0.0f && degrees < 90.0f)) {
        core_log_error("terrain", "stabilize: %s %g degrees (0 < angle < 90)", name, (double)degrees);
        return false;
    }
    double t = tan((double)degrees * (M_PI / 180.0)) * TERRAIN__QUANTA_PER_METRE * FIXED;
    for (int d = 0; d < 8; d++) {
        double slope = diagonal(d) ? t * M_SQRT2 : t;
        rule->slope[d] = slope > 1e15 ? (int64_t)1e15 : llround(slope);
        int64_t quick = (rule->slope[d] + tolerance) / FIXED;
        rule->quick[d] = quick > INT32_MAX ? INT32_MAX : (int32_t)quick;
    }
    return true;
}

static bool make_rules(const terrain_stabilize_desc *p, stabilize_rules *r) {
    if (!p) {
        core_log_error("terrain", "stabilize: no parameters");
        return false;
    }
    *r = (stabilize_rules){ .max_iterations = p->max_iterations, .budget_ns = p->budget_ns,
                            .wake = p->edge == TERRAIN_EDGE_WAKE };
    if (!(p->tolerance >= 0.0f) || p->tolerance > 1e6f) {
        core_log_error("terrain", "stabilize: tolerance %g m (0 ... 1e6)", (double)p->tolerance);
        return false;
    }
    r->tolerance = llround((double)p->tolerance * TERRAIN__QUANTA_PER_METRE * FIXED);
    if (!angle_rule("sand_angle", p->sand_angle, 33.0f, r->tolerance, &r->material[0]) ||
        !angle_rule("rocks_angle", p->rocks_angle, 42.0f, r->tolerance, &r->material[1]))
        return false;
    float step = p->step == 0.0f ? 1.0f : p->step;
    if (!(step > 0.0f) || step > (float)TERRAIN__FLOW_MAX / TERRAIN__QUANTA_PER_METRE) {
        core_log_error("terrain", "stabilize: step %g m (0 < step <= %g)", (double)step,
                   (double)TERRAIN__FLOW_MAX / TERRAIN__QUANTA_PER_METRE);
        return false;
    }
    r->step = (int32_t)CORE_MAX(1, llround((double)step * TERRAIN__QUANTA_PER_METRE));
    if (p->max_iterations < 0) {
        core_log_error("terrain", "stabilize: max_iterations %d (0 = no limit)", p->max_iterations);
        return false;
    }
    if (p->edge != TERRAIN_EDGE_WALL && p->edge != TERRAIN_EDGE_WAKE) {
        core_log_error("terrain", "stabilize: unknown edge mode %d", (int)p->edge);
        return false;
    }
    return true;
}

/* ---- one column (000 §3.4) ------------------------------------------------------------------ */

/* Outflows of one material from `cell`, whose surface is h[cell] and which holds `available`
 * quanta of it, into out[8]; returns their total (0: out untouched). */
static int32_t material_flow(const int32_t *h, size_t cell, const ptrdiff_t offset[8], int32_t available,
                             const material_rule *rule, const stabilize_rules *rules, int32_t out[8]) {
    int32_t centre = h[cell], drop[8];
    bool steep = false;
    for (int d = 0; d < 8; d++) {
        drop[d] = centre - h[(ptrdiff_t)cell + offset[d]];
        steep |= drop[d] > rule->quick[d];
    }
    if (!steep) return 0;
    int64_t excess[8], sum = 0;
    int receivers = 0;
    for (int d = 0; d < 8; d++) {
        int64_t e = (int64_t)drop[d] * FIXED - rule->slope[d];
        excess[d] = e > 0 ? e : 0;
        sum += excess[d];
        receivers += e > 0;
    }
    int64_t level = (sum + (int64_t)FIXED * (receivers + 1) - 1) / ((int64_t)FIXED * (receivers + 1));
    int64_t amount = CORE_MIN(CORE_MIN(level, (int64_t)rules->step), (int64_t)available);
    /* ⌊amount·e/Σe⌋ and its remainder, exactly: a quotient from the reciprocal is off by at
     * most one (products stay below 2^51, exact in a double), and the integer check fixes it —
     * a 64-bit division per neighbour cost a tenth of the whole loop. */
    double inverse = 1.0 / (double)sum;
    int64_t remainder[8], given = 0;
    for (int d = 0; d < 8; d++) {
        out[d] = 0;
        remainder[d] = -1;
        if (!excess[d]) continue;
        int64_t share = amount * excess[d];
        int64_t q = (int64_t)((double)share * inverse), r = share - q * sum;
        if (r < 0) q--, r += sum;
        else if (r >= sum) q++, r -= sum;
        out[d] = (int32_t)q;
        remainder[d] = r;
        given += q;
    }
    for (int64_t left = amount - given; left > 0; left--) {
        int best = 0;
        for (int d = 1; d < 8; d++)
            if (remainder[d] > remainder[best]) best = d;
        out[best]++;
        remainder[best] = -1;
    }
    return (int32_t)amount;
}

/* Records that cell (i, k) changed in pass `pass` (i, k may be in the halo: then what it
 * received is also kept to hand to the neighbouring region). */
static void mark(terrain_columns *c, int i, int k, size_t cell, uint32_t pass) {
    c->changed[cell] = pass;
    terrain__span_extend(&c->changed_span[k + 1], i, pass);
    if (i >= 0 && k >= 0 && i < c->width && k < c->depth)
        c->flags[(size_t)k * (size_t)c->width + (size_t)i] |= TERRAIN__COLUMN_EDITED;
}

static bool in_halo(const terrain_columns *c, int i, int k) { return i < 0 || k < 0 || i >= c->width || k >= c->depth; }

/* Moves one column's sand, then its rocks (bottom layer first, 000 §3.4); returns the quanta
 * moved. */
static int32_t settle(terrain_columns *c, const stabilize_rules *rules, int i, int k, const ptrdiff_t offset[8],
                      uint32_t pass, bool *gifts) {
    size_t cell = terrain__cell(c, i, k);
    bool border = i == 0 || k == 0 || i == c->width - 1 || k == c->depth - 1;
    int32_t moved = 0, out[8];
    for (int m = 0; m < 2; m++) {
        int32_t *surface = m == 0 ? c->sand_top : c->ground;
        int32_t available = m == 0 ? c->sand_top[cell] - c->base[cell] : c->ground[cell] - c->sand_top[cell];
        if (available <= 0) continue;
        int32_t total = material_flow(surface, cell, offset, available, &rules->material[m], rules, out);
        if (!total) continue;
        /* Sand leaving lowers the ground too; rocks only the ground. */
        if (m == 0) c->sand_top[cell] -= total;
        c->ground[cell] -= total;
        for (int d = 0; d < 8; d++) {
            if (!out[d]) continue;
            int ni = i + terrain__dir[d][0], nk = k + terrain__dir[d][1];
            size_t n = (size_t)((ptrdiff_t)cell + offset[d]);
            if (m == 0) c->sand_top[n] += out[d];
            c->ground[n] += out[d];
            mark(c, ni, nk, n, pass);
            if (border && in_halo(c, ni, nk)) {
                *(m == 0 ? &c->gift_sand[n] : &c->gift_rocks[n]) += out[d];
                *gifts = true;
            }
        }
        moved += total;
    }
    if (moved) mark(c, i, k, cell, pass);
    return moved;
}

/* ---- one pass ------------------------------------------------------------------------------- */

/* A row of a region that a pass works on. */
typedef struct row_item {
    terrain_columns *region;
    int row;
} row_item;

typedef struct pass_work {
    const stabilize_rules *rules;
    const row_item *items;
    uint32_t pass;
    int colour_x, colour_z;                   /* world column index mod 3 of this pass's columns */
} pass_work;

static void neighbour_offsets(const terrain_columns *c, ptrdiff_t offset[8]) {
    for (int d = 0; d < 8; d++) offset[d] = (ptrdiff_t)terrain__dir[d][1] * c->pitch + terrain__dir[d][0];
}

/* The columns [lo, hi] of row k near a change that still matters to `pass` (rows k − 1 … k + 1,
 * one column wider); false when none is. */
static bool row_range(const terrain_columns *c, int k, uint32_t pass, int *lo, int *hi) {
    int a = INT_MAX, b = INT_MIN;
    for (int r = k - 1; r <= k + 1; r++) {
        const terrain__span *s = &c->changed_span[r + 1];
        if (!terrain__recent(s->clock, pass)) continue;
        a = CORE_MIN(a, s->lo);
        b = CORE_MAX(b, s->hi);
    }
    if (a > b) return false;
    *lo = CORE_MAX(a - 1, 0);
    *hi = CORE_MIN(b + 1, c->width - 1);
    return *lo <= *hi;
}

/* Whether column `cell`'s neighbourhood changed since its colour's last pass. */
static bool active(const terrain_columns *c, size_t cell, const ptrdiff_t offset[8], uint32_t pass) {
    if (terrain__recent(c->changed[cell], pass)) return true;
    for (int d = 0; d < 8; d++)
        if (terrain__recent(c->changed[(ptrdiff_t)cell + offset[d]], pass)) return true;
    return false;
}

static void pass_row(const pass_work *w, terrain_columns *c, int k) {
    ptrdiff_t offset[8];
    neighbour_offsets(c, offset);
    int64_t moved = 0;
    bool gifts = false;
    int lo, hi;
    if (row_range(c, k, w->pass, &lo, &hi)) {
        int first = lo + (int)floor_mod(w->colour_x - (c->x0 + lo), 3);
        for (int i = first; i <= hi; i += 3)
            if (active(c, terrain__cell(c, i, k), offset, w->pass))
                moved += settle(c, w->rules, i, k, offset, w->pass, &gifts);
    }
    c->row_moved[k + 1] = moved;
    c->row_gifts[k + 1] = gifts;
}

static void pass_range(void *user, size_t begin, size_t end) {
    const pass_work *w = user;
    for (size_t n = begin; n < end; n++) pass_row(w, w->items[n].region, w->items[n].row);
}

/* pass_range as a job: its zone carries how many columns of the pass's colour its rows span, the
 * measure of its work (rows differ in length), so a slow batch in a trace explains itself. */
static void pass_batch(void *user, size_t begin, size_t end) {
    const pass_work *w = user;
    if (trace_active()) {
        int64_t columns = 0;
        for (size_t n = begin; n < end; n++) {
            const terrain_columns *c = w->items[n].region;
            int lo, hi;
            if (!row_range(c, w->items[n].row, w->pass, &lo, &hi)) continue;
            int first = lo + (int)floor_mod(w->colour_x - (c->x0 + lo), 3); /* as pass_row walks */
            if (first <= hi) columns += (hi - first) / 3 + 1;
        }
        trace_zone_arg_int("columns", columns);
        trace_zone_arg_int("rows", (int64_t)(end - begin));
    }
    pass_range(user, begin, end);
}

/* ---- regions side by side ------------------------------------------------------------------- */

/* Copies region `from`'s columns along its side d into the halo of the neighbour there: all of
 * them, or (only ≠ 0) those changed in pass `only`, the rest being there already. */
static void push_side(terrain_columns *from, int d, uint32_t only) {
    terrain_columns *to = from->neighbour[d];
    int dx = terrain__dir[d][0], dz = terrain__dir[d][1];
    /* The side is a row, a column or a corner: its first cell, its length and its stride. */
    int i = dx > 0 ? from->width - 1 : 0, k = dz > 0 ? from->depth - 1 : 0;
    int length = dx == 0 ? from->width : dz == 0 ? from->depth : 1;
    int ti = i - dx * from->width, tk = k - dz * from->depth;
    size_t src = terrain__cell(from, i, k), dst = terrain__cell(to, ti, tk);
    size_t stride = dx == 0 ? 1 : (size_t)from->pitch;
    for (int n = 0; n < length; n++, src += stride, dst += stride) {
        uint32_t stamp = from->changed[src];
        if (only && stamp != only) continue;
        to->sand_top[dst] = from->sand_top[src];
        to->ground[dst] = from->ground[src];
        to->changed[dst] = stamp;
        if (!terrain__recent(stamp, from->clock)) continue;
        terrain__span_extend(&to->changed_span[tk + (dx == 0 ? 0 : n) + 1], ti + (dx == 0 ? n : 0), stamp);
        to->last_change = CORE_MAX(to->last_change, stamp);
    }
}

static void push_sides(terrain_columns *from, uint32_t only) {
    for (int d = 0; d < 8; d++)
        if (from->neighbour[d]) push_side(from, d, only);
}

/* After pass `pass`: pushes the sides that the pass's changes reach (the rows' spans bound
 * them; a span may hold older changes too, which only makes a side pushed for nothing). */
static void push_changes(terrain_columns *from, uint32_t pass) {
    int i0 = INT_MAX, i1 = INT_MIN, k0 = INT_MAX, k1 = INT_MIN;
    for (int k = 0; k < from->depth; k++) {
        const terrain__span *span = &from->changed_span[k + 1];
        if (span->clock != pass) continue;
        i0 = CORE_MIN(i0, span->lo);
        i1 = CORE_MAX(i1, span->hi);
        k0 = CORE_MIN(k0, k);
        k1 = k;
    }
    for (int d = 0; d < 8; d++) {
        int dx = terrain__dir[d][0], dz = terrain__dir[d][1];
        bool reaches = (dx < 0 ? i0 <= 0 : dx > 0 ? i1 >= from->width - 1 : true) &&
                       (dz < 0 ? k0 <= 0 : dz > 0 ? k1 >= from->depth - 1 : true);
        if (from->neighbour[d] && reaches && k0 <= k1) push_side(from, d, pass);
    }
}

/* Hands what region c's border columns gave into its halo on side d to the neighbour there. */
static bool deliver_side(terrain_columns *c, int d, uint32_t pass) {
    terrain_columns *to = c->neighbour[d];
    int dx = terrain__dir[d][0], dz = terrain__dir[d][1];
    int i0 = dx < 0 ? -1 : dx > 0 ? c->width : 0, i1 = dx < 0 ? -1 : dx > 0 ? c->width : c->width - 1;
    int k0 = dz < 0 ? -1 : dz > 0 ? c->depth : 0, k1 = dz < 0 ? -1 : dz > 0 ? c->depth : c->depth - 1;
    bool any = false;
    for (int k = k0; k <= k1; k++) {
        for (int i = i0; i <= i1; i++) {
            size_t cell = terrain__cell(c, i, k);
            int32_t sand = c->gift_sand[cell], rocks = c->gift_rocks[cell];
            if (!sand && !rocks) continue;
            c->gift_sand[cell] = c->gift_rocks[cell] = 0;
            int ti = i - dx * c->width, tk = k - dz * c->depth;
            size_t dst = terrain__cell(to, ti, tk);
            to->sand_top[dst] += sand;
            to->ground[dst] += sand + rocks;
            mark(to, ti, tk, dst, pass);
            to->last_change = pass;
            any = true;
        }
    }
    return any;
}

/* The halo on sides without a neighbour: walls that nothing flows into or out of. */
static void wall_halo(terrain_columns *c) {
    for (int k = -1; k <= c->depth; k++) {
        for (int i = -1; i <= c->width; i++) {
            if (!in_halo(c, i, k)) continue;
            int rx = i < 0 ? -1 : i >= c->width, rz = k < 0 ? -1 : k >= c->depth;
            int index = (rz + 1) * 3 + (rx + 1);
            if (!(c->edge_sides & (1u << (index < 4 ? index : index - 1)))) continue;
            size_t cell = terrain__cell(c, i, k);
            c->base[cell] = c->sand_top[cell] = c->ground[cell] = TERRAIN__WALL_HEIGHT;
            c->changed[cell] = 0;
        }
    }
}

/* Finds each region's neighbours; false for sizes that differ, regions off the grid of the first
 * one, or two at one place. */
static bool link_regions(terrain_columns *const *regions, int count) {
    const terrain_columns *first = regions[0];
    for (int r = 0; r < count; r++) {
        terrain_columns *c = regions[r];
        if (c->width != first->width || c->depth != first->depth) {
            core_log_error("terrain", "stabilize: region %d is %d x %d columns, region 0 %d x %d (one size for all)", r,
                       c->width, c->depth, first->width, first->depth);
            return false;
        }
        if ((c->x0 - first->x0) % first->width || (c->z0 - first->z0) % first->depth) {
            core_log_error("terrain", "stabilize: region %d at column (%lld, %lld) is off region 0's grid", r,
                       (long long)c->x0, (long long)c->z0);
            return false;
        }
    }
    for (int r = 0; r < count; r++) {
        terrain_columns *c = regions[r];
        memset(c->neighbour, 0, sizeof c->neighbour);
        for (int s = 0; s < count; s++) {
            const terrain_columns *o = regions[s];
            if (s != r && o->x0 == c->x0 && o->z0 == c->z0) {
                core_log_error("terrain", "stabilize: regions %d and %d are both at column (%lld, %lld)", r, s,
                           (long long)c->x0, (long long)c->z0);
                return false;
            }
            for (int d = 0; d < 8; d++)
                if (o->x0 == c->x0 + terrain__dir[d][0] * c->width && o->z0 == c->z0 + terrain__dir[d][1] * c->depth)
                    c->neighbour[d] = regions[s];
        }
        c->edge_sides = 0;
        for (int d = 0; d < 8; d++)
            if (!c->neighbour[d]) c->edge_sides |= (uint8_t)(1u << d);
    }
    return true;
}

/* ---- the edge ------------------------------------------------------------------------------- */

/* Directions of the regions that column (i, k)'s neighbours beyond the border lie in. */
static uint8_t outside_regions(const terrain_columns *c, int i, int k) {
    uint8_t regions = 0;
    for (int d = 0; d < 8; d++) {
        int x = i + terrain__dir[d][0], z = k + terrain__dir[d][1];
        int rx = x < 0 ? -1 : x >= c->width, rz = z < 0 ? -1 : z >= c->depth;
        if (rx == 0 && rz == 0) continue;
        int index = (rz + 1) * 3 + (rx + 1);      /* 0 … 8 without the centre, 4 */
        regions |= (uint8_t)(1u << (index < 4 ? index : index - 1));
    }
    return regions;
}

/* Regions beyond the edge that pass `pass` would need: next to a border column that changed
 * lately (their columns there may move now) or that may move now (it reads their heights).
 * Conservative: stopping earlier than needed only wakes a region sooner. */
static uint8_t edge_needs(const terrain_columns *c, uint32_t pass, const ptrdiff_t offset[8]) {
    uint8_t needs = 0;
    for (int k = 0; k < c->depth; k++) {
        int lo, hi;
        if (!row_range(c, k, pass, &lo, &hi)) continue;
        bool border_row = k == 0 || k == c->depth - 1;
        for (int i = lo; i <= hi; i++) {
            if (!border_row && i > 0 && i < c->width - 1) {
                i = CORE_MAX(i, c->width - 2);     /* inner rows: only their end columns */
                continue;
            }
            uint8_t beyond = outside_regions(c, i, k) & c->edge_sides;
            if (!beyond) continue;
            size_t cell = terrain__cell(c, i, k);
            bool holds = c->ground[cell] > c->base[cell];
            if (terrain__recent(c->changed[cell], pass) || (holds && active(c, cell, offset, pass))) needs |= beyond;
        }
    }
    return needs;
}

static void add_woken(terrain_stabilize_result *result, const terrain_columns *c, int d) {
    terrain_chunk_coord g = { floor_div(c->x0, c->width) + terrain__dir[d][0],
                              floor_div(c->z0, c->depth) + terrain__dir[d][1] };
    int known = CORE_MIN(result->woken_count, TERRAIN_STABILIZE_MAX_WOKEN);
    for (int n = 0; n < known; n++)
        if (result->woken[n].x == g.x && result->woken[n].z == g.z) return;
    if (result->woken_count < TERRAIN_STABILIZE_MAX_WOKEN) result->woken[result->woken_count] = g;
    result->woken_count++;
}

/* ---- the loop ------------------------------------------------------------------------------- */

typedef struct stabilizer {
    terrain_columns *const *regions;
    int count;
    const stabilize_rules *rules;
    job_system *jobs;
    row_item *items;
    size_t item_capacity;
    terrain_stabilize_result *result;
} stabilizer;

typedef enum pass_outcome {
    PASS_MOVED,                               /* material moved */
    PASS_QUIET,                               /* nothing moved */
    PASS_IDLE,                                /* no change anywhere still matters: stable */
    PASS_NEEDS_REGIONS,                       /* called off: columns beyond the edge needed */
} pass_outcome;

static bool region_awake(const terrain_columns *c, uint32_t pass) { return terrain__recent(c->last_change, pass); }

/* Rows of the pass's colour near a change that still matters, and how many columns they may
 * look at; notes which regions have such changes by their border. */
static size_t list_rows(stabilizer *s, const pass_work *w, size_t *columns) {
    size_t n = 0;
    *columns = 0;
    for (int r = 0; r < s->count; r++) {
        terrain_columns *c = s->regions[r];
        c->near_edge = false;
        if (!region_awake(c, w->pass)) continue;
        for (int k = 0; k < 2; k++)
            c->near_edge |= terrain__recent(c->changed_span[k + 1].clock, w->pass) ||
                            terrain__recent(c->changed_span[c->depth - k].clock, w->pass);
        for (int k = (int)floor_mod(w->colour_z - c->z0, 3); k < c->depth; k += 3) {
            int lo, hi;
            if (!row_range(c, k, w->pass, &lo, &hi)) continue;
            s->items = core_grow(s->items, &s->item_capacity, n + 1, sizeof *s->items);
            s->items[n++] = (row_item){ c, k };
            *columns += (size_t)(hi - lo + 1) / 3;
            c->near_edge |= lo == 0 || hi == c->width - 1 || k <= 1 || k >= c->depth - 2;
        }
    }
    return n;
}

/* ---- piles on cave floors (000 §3.4) ---------------------------------------------------------- */

/* 000 §3.4 stabilizes "all material layers located between two stable bedrock layers", not only
 * the pile on top: sand and rocks lying on a cave's floor under its roof flow too. Such piles are
 * rare, so they are not in the padded height arrays: a column flagged TERRAIN__COLUMN_CAVE_PILE is
 * read as its list of spaces (terrain__gap), and each of its spaces under a roof is settled with
 * the same rule as the top pile (material_flow: sand on the sand surface, then rocks on the
 * ground). Readings we take:
 *   - The material that slides is the top quantum of the layer, at height `probe` = surface − 1.
 *     A neighbour receives into its space that holds that height — the same cave, a cave next to
 *     it, or the open pile outside a cave's mouth — and its surface there is that space's floor
 *     plus its sand (plus its rocks, for rocks). Where a stable layer fills the neighbour at that
 *     height it is a wall: nothing goes into rock.
 *   - A space under a roof takes no more than its air (its water keeps its thickness, as water on
 *     the top pile does while stabilization runs): what the flow rule gives beyond that stays
 *     with the giver, so a pile never grows into a roof and a full cave stops taking material.
 *   - The giver's own space gains the air it lost: the roof does not move.
 *   - The same nine colours as the top pile, in the same pass, after it: a column's 3 × 3 moves
 *     never meet another's of its colour, so the order within a pass does not matter and the
 *     result does not depend on the thread count. Beyond a region's border the pile reads and
 *     writes the neighbouring region's columns themselves (the halo holds only top piles); the
 *     pass runs on one thread over all regions, and colours come from world coordinates, so
 *     regions side by side give the bytes one big region gives. Where no region continues is a
 *     wall for these piles, in either edge mode (they wake no region). */

typedef struct cave_scratch {
    terrain__clayer *layers, *other, *rewritten;
    size_t layers_capacity, other_capacity, rewritten_capacity;
    terrain__gap *gaps, *other_gaps;
    size_t gaps_capacity, other_gaps_capacity;
} cave_scratch;

static void cave_scratch_free(cave_scratch *s) {
    core_free(s->layers, s->layers_capacity * sizeof *s->layers);
    core_free(s->other, s->other_capacity * sizeof *s->other);
    core_free(s->rewritten, s->rewritten_capacity * sizeof *s->rewritten);
    core_free(s->gaps, s->gaps_capacity * sizeof *s->gaps);
    core_free(s->other_gaps, s->other_gaps_capacity * sizeof *s->other_gaps);
}

/* Column (i, k)'s layers and spaces; returns the count of spaces. */
static int read_gaps(const terrain_columns *c, int i, int k, terrain__clayer **layers, size_t *layers_capacity,
                     terrain__gap **gaps, size_t *gaps_capacity, int *count) {
    *count = terrain__columns_layers(c, i, k, layers, layers_capacity);
    *gaps = core_grow(*gaps, gaps_capacity, (size_t)*count + 1, sizeof **gaps);
    return terrain__column_gaps(*layers, *count, *gaps, *count + 1);
}

/* Adds `delta` quanta (negative: takes) of sand (m = 0) or rocks (m = 1) to the space of column
 * (i, k) that holds `height`; under a roof the air gives or takes the room. */
static void gap_add(terrain_columns *c, int i, int k, int64_t height, int m, int32_t delta, cave_scratch *s) {
    int count;
    int gap_count = read_gaps(c, i, k, &s->other, &s->other_capacity, &s->other_gaps, &s->other_gaps_capacity, &count);
    int g = terrain__gap_holding(s->other_gaps, gap_count, height);
    if (g < 0) return;                        /* never: the caller found this space */
    const terrain__gap *gap = &s->other_gaps[g];
    int64_t amount[4] = { gap->amount[0], gap->amount[1], gap->amount[2], gap->amount[3] };
    amount[m] += delta;
    if (!terrain__gap_open(gap)) amount[3] -= delta;
    terrain__columns_rewrite_gap(c, i, k, s->other, count, gap, amount, &s->rewritten, &s->rewritten_capacity);
}

/* The region and column that column (i, k) of region c is — c's own, or beyond its border the
 * neighbouring region's (regions side by side have one size); NULL at the edge. */
static terrain_columns *locate(terrain_columns *c, int i, int k, int *ri, int *rk) {
    int rx = i < 0 ? -1 : i >= c->width, rz = k < 0 ? -1 : k >= c->depth;
    *ri = i - rx * c->width, *rk = k - rz * c->depth;
    if (!rx && !rz) return c;
    for (int d = 0; d < 8; d++)
        if (terrain__dir[d][0] == rx && terrain__dir[d][1] == rz) return c->neighbour[d];
    return NULL;
}

/* Surface of material m in the space of column (i, k) that holds `probe`, and the room the space
 * has; TERRAIN__WALL_HEIGHT where rock (or the edge) is at that height. */
static int32_t cave_neighbour(terrain_columns *c, int i, int k, int64_t probe, int m, cave_scratch *s,
                              int64_t *room) {
    *room = 0;
    c = locate(c, i, k, &i, &k);
    if (!c) return TERRAIN__WALL_HEIGHT;
    int count;
    int gap_count = read_gaps(c, i, k, &s->other, &s->other_capacity, &s->other_gaps, &s->other_gaps_capacity, &count);
    int g = terrain__gap_holding(s->other_gaps, gap_count, probe);
    if (g < 0) return TERRAIN__WALL_HEIGHT;
    const terrain__gap *gap = &s->other_gaps[g];
    *room = terrain__gap_open(gap) ? INT64_MAX : gap->amount[3];
    return (int32_t)(gap->floor + gap->amount[0] + (m ? gap->amount[1] : 0));
}

/* Settles the piles in column (i, k)'s spaces under a roof, bottom space first, sand then rocks
 * in each; returns the quanta moved. */
static int32_t settle_caves(terrain_columns *c, const stabilize_rules *rules, int i, int k, uint32_t pass,
                            cave_scratch *s) {
    static const ptrdiff_t local[8] = { -4, -3, -2, -1, 1, 2, 3, 4 };   /* terrain__dir in a 3 × 3 array */
    int32_t moved = 0;
    for (int g = 0;; g++) {
        for (int m = 0; m < 2; m++) {
            int count;
            int gap_count = read_gaps(c, i, k, &s->layers, &s->layers_capacity, &s->gaps, &s->gaps_capacity, &count);
            if (g >= gap_count - 1) return moved;   /* the last space is the open top: not here */
            const terrain__gap *gap = &s->gaps[g];
            if (gap->amount[m] <= 0) continue;
            int64_t surface = gap->floor + gap->amount[0] + (m ? gap->amount[1] : 0), probe = surface - 1;
            int32_t h[9], out[8];
            int64_t room[8];
            h[4] = (int32_t)surface;
            for (int d = 0; d < 8; d++)
                h[4 + local[d]] = cave_neighbour(c, i + terrain__dir[d][0], k + terrain__dir[d][1], probe, m, s, &room[d]);
            int32_t available = (int32_t)CORE_MIN(gap->amount[m], (int64_t)INT32_MAX);
            if (!material_flow(h, 4, local, available, &rules->material[m], rules, out)) continue;
            int32_t given = 0;
            for (int d = 0; d < 8; d++) {
                out[d] = (int32_t)CORE_MIN((int64_t)out[d], room[d]);
                given += out[d];
            }
            if (!given) continue;
            gap_add(c, i, k, probe, m, -given, s);
            for (int d = 0; d < 8; d++) {
                if (!out[d]) continue;
                int ni, nk;
                terrain_columns *to = locate(c, i + terrain__dir[d][0], k + terrain__dir[d][1], &ni, &nk);
                gap_add(to, ni, nk, probe, m, out[d], s);
                mark(to, ni, nk, terrain__cell(to, ni, nk), pass);
                to->last_change = pass;   /* a neighbouring region's change: its halos follow */
            }
            mark(c, i, k, terrain__cell(c, i, k), pass);
            moved += given;
        }
    }
}

/* The cave piles of the pass's colour near a change, in every region (one thread: they are rare). */
static int64_t cave_pass(terrain_columns *const *regions, int count, const stabilize_rules *rules, uint32_t pass,
                         int colour_x, int colour_z) {
    int64_t moved = 0;
    cave_scratch scratch = { 0 };
    for (int r = 0; r < count; r++) {
        terrain_columns *c = regions[r];
        if (!c->cave_piles || !region_awake(c, pass)) continue;
        ptrdiff_t offset[8];
        neighbour_offsets(c, offset);
        for (int k = (int)floor_mod(colour_z - c->z0, 3); k < c->depth; k += 3) {
            int lo, hi;
            if (!row_range(c, k, pass, &lo, &hi)) continue;
            for (int i = lo + (int)floor_mod(colour_x - (c->x0 + lo), 3); i <= hi; i += 3) {
                if (!(c->flags[(size_t)k * (size_t)c->width + (size_t)i] & TERRAIN__COLUMN_CAVE_PILE) ||
                    !active(c, terrain__cell(c, i, k), offset, pass))
                    continue;
                int32_t m = settle_caves(c, rules, i, k, pass, &scratch);
                if (m) c->last_change = pass;
                moved += m;
            }
        }
    }
    cave_scratch_free(&scratch);
    return moved;
}

static pass_outcome run_pass(stabilizer *s) {
    uint32_t pass = s->regions[0]->clock + 1;
    int colour = (int)(pass % TERRAIN__COLOURS);
    pass_work w = { .rules = s->rules, .pass = pass, .colour_x = colour % 3, .colour_z = colour / 3 };

    bool awake = false, need = false;
    for (int r = 0; r < s->count; r++) awake |= region_awake(s->regions[r], pass);
    if (!awake) return PASS_IDLE;
    size_t columns;
    size_t rows = list_rows(s, &w, &columns);
    for (int r = 0; r < s->count; r++) {
        terrain_columns *c = s->regions[r];
        if (!c->edge_sides || !c->near_edge) continue;
        ptrdiff_t offset[8];
        neighbour_offsets(c, offset);
        uint8_t needs = edge_needs(c, pass, offset);
        for (int d = 0; d < 8; d++)
            if (needs & (1u << d)) add_woken(s->result, c, d);
        need |= needs != 0;
    }
    if (need && s->rules->wake) return PASS_NEEDS_REGIONS;

    w.items = s->items;
    if (s->jobs && job_thread_count(s->jobs) > 1 && columns >= PARALLEL_MIN_COLUMNS) {
        /* Rows of one colour are three apart, so their 3 × 3 writes never meet. */
        size_t batch = CORE_MAX((size_t)1, rows / ((size_t)job_thread_count(s->jobs) * 4));
        job_parallel_for(s->jobs, rows, batch, pass_batch, &w, "terrain.stabilize.pass");
    } else {
        pass_range(&w, 0, rows);
    }

    int64_t moved = 0;
    for (size_t n = 0; n < rows; n++) {
        terrain_columns *c = s->items[n].region;
        int64_t m = c->row_moved[s->items[n].row + 1];
        moved += m;
        if (m) c->last_change = pass;
        if (!c->row_gifts[s->items[n].row + 1] || s->count == 1) continue;
        /* Hand over what this row's border columns gave into the halo (each halo cell once: a
         * side's cells are zeroed as they go). */
        for (int d = 0; d < 8; d++)
            if (c->neighbour[d]) deliver_side(c, d, pass);
    }
    moved += cave_pass(s->regions, s->count, s->rules, pass, w.colour_x, w.colour_z);
    for (int r = 0; r < s->count; r++) s->regions[r]->clock = pass;
    if (moved && s->count > 1) {
        /* Refresh the halos next to every region that changed, with what changed. */
        for (int r = 0; r < s->count; r++)
            if (s->regions[r]->last_change == pass) push_changes(s->regions[r], pass);
    }
    s->result->moved += moved;
    return moved ? PASS_MOVED : PASS_QUIET;
}

/* Sorts the columns flagged out of order (000 §3.4's merge and order), before anything moves. */
static void sort_flagged(terrain_columns *c) {
    if (!c->unsorted) return;
    terrain__clayer *scratch = NULL;
    size_t capacity = 0;
    for (int k = 0; k < c->depth && c->unsorted; k++)
        for (int i = 0; i < c->width; i++)
            if (c->flags[(size_t)k * (size_t)c->width + (size_t)i] & TERRAIN__COLUMN_UNSORTED)
                terrain__columns_sort(c, i, k, &scratch, &capacity);
    core_free(scratch, capacity * sizeof *scratch);
}

static bool check_regions(terrain_columns *const *regions, int count) {
    if (count < 1 || !regions) {
        core_log_error("terrain", "stabilize: %d regions", count);
        return false;
    }
    for (int r = 0; r < count; r++)
        if (!regions[r]) {
            core_log_error("terrain", "stabilize: region %d is NULL", r);
            return false;
        }
    return link_regions(regions, count);
}

/* One clock for all (a region that joins carries its recent changes to the set's time), sorted
 * columns, walls on the edge and fresh halos elsewhere (neighbours may have been edited or
 * loaded since the last call). */
static void prepare_regions(terrain_columns *const *regions, int count) {
    uint32_t clock = 0;
    for (int r = 0; r < count; r++) clock = CORE_MAX(clock, regions[r]->clock);
    for (int r = 0; r < count; r++) {
        terrain__columns_set_clock(regions[r], clock);
        sort_flagged(regions[r]);
        wall_halo(regions[r]);
    }
    for (int r = 0; r < count; r++) push_sides(regions[r], 0);
}

bool terrain_stabilize_regions(terrain_columns *const *regions, int count, const terrain_stabilize_desc *params,
                               job_system *jobs, terrain_stabilize_result *result) {
    TRACE_ZONE("terrain.stabilize");
    terrain_stabilize_result local;
    if (!result) result = &local;
    *result = (terrain_stabilize_result){ 0 };
    stabilize_rules rules;
    if (!make_rules(params, &rules) || !check_regions(regions, count)) return false;
    prepare_regions(regions, count);

    stabilizer s = { .regions = regions, .count = count, .rules = &rules, .jobs = jobs, .result = result };
    uint64_t start = core_time_ns();
    int passes = 0, quiet = 0;
    for (;;) {
        if (rules.max_iterations && passes >= rules.max_iterations * TERRAIN__COLOURS) break;
        /* The first iteration always runs, so that a tight budget still makes progress. */
        if (rules.budget_ns && passes >= TERRAIN__COLOURS && core_time_ns() - start >= rules.budget_ns) break;
        pass_outcome outcome = run_pass(&s);
        if (outcome == PASS_NEEDS_REGIONS) break;
        if (outcome == PASS_IDLE) {
            result->converged = true;
            break;
        }
        passes++;
        quiet = outcome == PASS_QUIET ? quiet + 1 : 0;
        if (quiet >= TERRAIN__COLOURS) {          /* a whole iteration moved nothing */
            result->converged = true;
            break;
        }
    }
    result->iterations = (passes + TERRAIN__COLOURS - 1) / TERRAIN__COLOURS;
    trace_counter("terrain.stabilize.iterations", result->iterations);
    trace_counter("terrain.stabilize.moved_m3", (double)result->moved / TERRAIN__QUANTA_PER_METRE);
    core_free(s.items, s.item_capacity * sizeof *s.items);
    for (int r = 0; r < count; r++) memset(regions[r]->neighbour, 0, sizeof regions[r]->neighbour);
    return true;
}

bool terrain_stabilize_region(terrain_columns *columns, const terrain_stabilize_desc *params, job_system *jobs,
                              terrain_stabilize_result *result) {
    return terrain_stabilize_regions(&columns, 1, params, jobs, result);
}
