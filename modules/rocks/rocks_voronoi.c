/* rocks_voronoi.c — one region instance: the discrete anisotropic Voronoi cells of its seeds,
 * their contacts and their erosion (001 §4–§5).
 *
 * Why a rock depends on its region alone. 001 §4 gives each voxel to the seed with the smallest
 * d_k = f_k/g_k, but "among which seeds" is left open, and with all seeds of a tiling a rock's
 * shape would depend on tiles far away (001 §2's straddling problem). We take the owner of voxel
 * v among the seeds of its dual block only: per axis, v's cell and the neighbour cell on v's side
 * of the cell's centre (2×2×2 cells). Then
 *   - a seed in cell c can own v only when c is in v's dual block, i.e. v lies within half a
 *     cell of c: every rock lies inside its cell grown by half a cell;
 *   - the owner of such a v is decided by seeds in cells c ± 1;
 *   - so a rock's voxel set depends only on the seeds of c ± 1, which (001 §3) lie in the closure
 *     of c's region and are fixed by that region's colours alone.
 * Contacts (001 §5) are decided the same way (below), and erosion reads only the rock's own
 * voxels and contacts, so the eroded rock and its mesh are one function of the region instance:
 * computed once, shared by every tile that holds a piece of the region. Ties in d go to the
 * smaller seed id, so the rule is total and the same in every frame.
 */
#include "rocks_internal.h"

#include "core/core.h"
#include "core/core_lanes.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>

#define BLOCK_SIDE 8    /* voxels along a cell octant's side at most: ⌈m/2⌉ ≤ 8 */

typedef struct region_build {
    const rocks__params *params;
    rocks__region region;
    int m, n;
    /* closure cells lo − 1 … hi + 1 */
    int clo[3], cdim[3];
    uint32_t *cell_first, *cell_count;
    rocks__seed *seeds;
    uint32_t seed_count;
    /* the voxels whose dual block holds a region cell */
    int vlo[3], vdim[3];
    int32_t *owner;
    /* per seed: the voxels it owns and their box (lo xyz, hi xyz), kept as ownership is decided */
    uint32_t *owned;
    int (*owned_box)[6];
} region_build;

static int region_colour(const void *user, int x, int y, int z) {
    const rocks__region *r = user;
    if (x < 0 || x > 1 || y < 0 || y > 1 || z < 0 || z > 1 || !r->known[z][y][x]) return 0;   /* never asked */
    return r->colour[z][y][x];
}

static size_t cell_slot(const region_build *b, const int c[3]) {
    return ((size_t)(c[2] - b->clo[2]) * b->cdim[1] + (c[1] - b->clo[1])) * b->cdim[0] + (c[0] - b->clo[0]);
}

static void make_seeds(region_build *b) {
    size_t cells = (size_t)b->cdim[0] * b->cdim[1] * b->cdim[2];
    b->cell_first = core_alloc(cells * sizeof *b->cell_first);
    b->cell_count = core_alloc(cells * sizeof *b->cell_count);
    b->seeds = core_alloc(cells * ROCKS__MAX_SEEDS_PER_CELL * sizeof *b->seeds);
    b->seed_count = 0;
    int c[3];
    for (c[2] = b->clo[2]; c[2] < b->clo[2] + b->cdim[2]; c[2]++)
        for (c[1] = b->clo[1]; c[1] < b->clo[1] + b->cdim[1]; c[1]++)
            for (c[0] = b->clo[0]; c[0] < b->clo[0] + b->cdim[0]; c[0]++) {
                size_t slot = cell_slot(b, c);
                b->cell_first[slot] = b->seed_count;
                int count = rocks__cell_seeds(b->params, c, region_colour, &b->region, b->seeds + b->seed_count);
                b->cell_count[slot] = (uint32_t)count;
                b->seed_count += (uint32_t)count;
            }
}

/* ---- ownership (001 §4, the dual-block rule above) --------------------------------------------- */

/* Voxels first … last of row (y, z) belong to seed `who`: its count and box. */
static void note_owned(region_build *b, int32_t who, int first, int last, int y, int z) {
    if (who < 0) return;
    int *box = b->owned_box[who];
    b->owned[who] += (uint32_t)(last - first + 1);
    if (first < box[0]) box[0] = first;
    if (y < box[1]) box[1] = y;
    if (z < box[2]) box[2] = z;
    if (last > box[3]) box[3] = last;
    if (y > box[4]) box[4] = y;
    if (z > box[5]) box[5] = z;
}

/* Drops the candidates that cannot own a voxel of the block, keeping the others' order. Over the
 * box of its voxel centres, a seed's d is at most its largest value at the box's 8 corners (d is
 * convex) and at least q_min times the squared distance from the seed to the box. A seed whose
 * least value exceeds some seed's largest is beaten at every voxel, so leaving it out changes no
 * owner. The margins cover float rounding of d (relative 1e-6) many times over. */
static int prune_candidates(const region_build *b, const int v0[3], const int size[3], uint32_t *cand, int count) {
    float lo[8 * ROCKS__MAX_SEEDS_PER_CELL][3], hi[8 * ROCKS__MAX_SEEDS_PER_CELL][3];
    float bound = INFINITY;   /* the smallest of the seeds' largest d */
    for (int k = 0; k < count; k++) {
        const rocks__seed *s = &b->seeds[cand[k]];
        float most = 0.0f;
        for (int a = 0; a < 3; a++) {
            lo[k][a] = (float)(v0[a] - s->cell[a] * b->m) + 0.5f - s->u[a];
            hi[k][a] = lo[k][a] + (float)(size[a] - 1);
        }
        for (int corner = 0; corner < 8; corner++) {
            float d = rocks__distance(s->q, corner & 1 ? hi[k][0] : lo[k][0], corner & 2 ? hi[k][1] : lo[k][1],
                                      corner & 4 ? hi[k][2] : lo[k][2]);
            most = d > most ? d : most;
        }
        bound = most < bound ? most : bound;
    }
    bound = bound * 1.01f + 1e-3f;
    int kept = 0;
    for (int k = 0; k < count; k++) {
        float gap2 = 0.0f;   /* squared distance from the seed to the box */
        for (int a = 0; a < 3; a++) {
            float g = lo[k][a] > 0.0f ? lo[k][a] : hi[k][a] < 0.0f ? -hi[k][a] : 0.0f;
            gap2 += g * g;
        }
        if (0.99f * b->seeds[cand[k]].q_min * gap2 <= bound) cand[kept++] = cand[k];
    }
    return kept;
}

/* The owner of each voxel of a block among its candidates (count ≥ 1), into rows of BLOCK_SIDE:
 * a loop of fixed length, which the compiler vectorises; the padding lanes compute with dx = 0
 * and are never read. The first candidate finds the distances unset (as if infinite) and takes
 * every voxel. Compiled twice (below): each lane does the scalar operations in the same order,
 * with no FMA, so both give the same bits. */
static inline __attribute__((always_inline)) void owners_in_rows(const region_build *b, const int v0[3], const int size[3],
                                                                const uint32_t *cand, int count, int32_t *who) {
    float best[BLOCK_SIDE * BLOCK_SIDE * BLOCK_SIDE];
    const int nx = size[0], ny = size[1], nz = size[2], m = b->m;
    for (int k = 0; k < count; k++) {
        const rocks__seed *s = &b->seeds[cand[k]];
        const float *q = s->q, q0 = q[0];   /* q0 a local: the x loop below loads nothing else */
        float dxs[BLOCK_SIDE] = { 0 };
        for (int x = 0; x < nx; x++) dxs[x] = (float)(v0[0] + x - s->cell[0] * m) + 0.5f - s->u[0];
        int32_t id = (int32_t)cand[k];
        for (int z = 0; z < nz; z++) {
            float dz = (float)(v0[2] + z - s->cell[2] * m) + 0.5f - s->u[2];
            for (int y = 0; y < ny; y++) {
                float dy = (float)(v0[1] + y - s->cell[1] * m) + 0.5f - s->u[1];
                float bq = q[3] * dy + q[4] * dz;                     /* rocks__distance, split */
                float aq = (q[1] * dy + q[5] * dz) * dy + q[2] * dz * dz;
                float *row = best + (z * ny + y) * BLOCK_SIDE;
                int32_t *row_who = who + (z * ny + y) * BLOCK_SIDE;
                for (int x = 0; x < BLOCK_SIDE; x++) {   /* branch-free, so it vectorises */
                    float d = (q0 * dxs[x] + bq) * dxs[x] + aq, r = row[x];
                    r = k ? r : INFINITY;   /* loaded either way: a select, not a branch */
                    int32_t better = -(int32_t)(d < r);
                    row[x] = d < r ? d : r;
                    row_who[x] = (row_who[x] & ~better) | (id & better);
                }
            }
        }
    }
}

/* SSE2 (x86-64's baseline: a row in two halves), and AVX2 where the CPU has it (a row of
 * BLOCK_SIDE = 8 in one): 4 % of the whole tile-set build on this project's machine. "fma" is
 * never a target, and -std=c11 keeps GCC from contracting, so the lanes round as the scalar code. */
static void owners_baseline(const region_build *b, const int v0[3], const int size[3], const uint32_t *cand, int count,
                            int32_t *who) {
    owners_in_rows(b, v0, size, cand, count, who);
}

#if ROCKS__HAS_AVX2
__attribute__((target("avx2"))) static void owners_avx2(const region_build *b, const int v0[3], const int size[3],
                                                        const uint32_t *cand, int count, int32_t *who) {
    owners_in_rows(b, v0, size, cand, count, who);
}
#else
#define owners_avx2 owners_baseline
#endif

static _Atomic int lanes_path = ROCKS__LANES_AUTO;

bool rocks__lanes_wide(void) {
    int path = atomic_load_explicit(&lanes_path, memory_order_relaxed);
    if (path == ROCKS__LANES_AUTO) {
        path = rocks__lanes_supported(ROCKS__LANES_AVX2) ? ROCKS__LANES_AVX2 : ROCKS__LANES_BASELINE;
        atomic_store_explicit(&lanes_path, path, memory_order_relaxed);
    }
    return path == ROCKS__LANES_AVX2;
}

bool rocks__lanes_supported(rocks__lanes path) {
    switch (path) {
    case ROCKS__LANES_AUTO:
    case ROCKS__LANES_BASELINE: return true;
#if ROCKS__HAS_AVX2
    case ROCKS__LANES_AVX2: __builtin_cpu_init(); return __builtin_cpu_supports("avx2");
#endif
    default: return false;
    }
}

bool rocks__lanes_set(rocks__lanes path) {
    if (!rocks__lanes_supported(path)) return false;
    atomic_store_explicit(&lanes_path, (int)path, memory_order_relaxed);
    return true;
}

/* One octant of one cell: all its voxels share a dual block, so the candidates are fixed and the
 * loop runs candidate by candidate over rows of voxels (structure of arrays: the x offsets of a
 * row precomputed, then two multiplies and two adds a voxel, vectorisable). */
static void own_block(region_build *b, const int v0[3], const int size[3], const int first_cell[3]) {
    uint32_t cand[8 * ROCKS__MAX_SEEDS_PER_CELL];
    int count = 0;
    for (int dz = 0; dz < 2; dz++)
        for (int dy = 0; dy < 2; dy++)
            for (int dx = 0; dx < 2; dx++) {
                int c[3] = { first_cell[0] + dx, first_cell[1] + dy, first_cell[2] + dz };
                size_t slot = cell_slot(b, c);
                for (uint32_t i = 0; i < b->cell_count[slot]; i++) cand[count++] = b->cell_first[slot] + i;
            }
    for (int i = 1; i < count; i++) {   /* by id: with strict < below, ties go to the smaller id */
        uint32_t x = cand[i];
        int j = i - 1;
        while (j >= 0 && b->seeds[cand[j]].id > b->seeds[x].id) cand[j + 1] = cand[j], j--;
        cand[j + 1] = x;
    }
    count = prune_candidates(b, v0, size, cand, count);
    int32_t who[BLOCK_SIDE * BLOCK_SIDE * BLOCK_SIDE];
    const int nx = size[0], ny = size[1], nz = size[2];
    if (count == 0)
        for (int i = 0; i < BLOCK_SIDE * ny * nz; i++) who[i] = -1;
    else if (rocks__lanes_wide())
        owners_avx2(b, v0, size, cand, count, who);
    else
        owners_baseline(b, v0, size, cand, count, who);
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++) {
            const int32_t *row = who + (z * ny + y) * BLOCK_SIDE;
            int32_t *dst = b->owner + ((size_t)(v0[2] + z - b->vlo[2]) * b->vdim[1] + (v0[1] + y - b->vlo[1])) * b->vdim[0] +
                           (v0[0] - b->vlo[0]);
            memcpy(dst, row, (size_t)nx * sizeof *dst);
            for (int x = 0, end; x < nx; x = end) {   /* the row's runs of one owner */
                for (end = x + 1; end < nx && row[end] == row[x];) end++;
                note_owned(b, row[x], v0[0] + x, v0[0] + end - 1, v0[1] + y, v0[2] + z);
            }
        }
}

static void own_voxels(region_build *b) {
    const int m = b->m, half = m / 2;   /* voxels s < half are on the lower side (2s + 1 < m) */
    size_t total = (size_t)b->vdim[0] * b->vdim[1] * b->vdim[2];
    b->owner = core_alloc(total * sizeof *b->owner);
    b->owned = core_calloc(b->seed_count ? b->seed_count : 1, sizeof *b->owned);
    b->owned_box = core_alloc((b->seed_count ? b->seed_count : 1) * sizeof *b->owned_box);
    for (uint32_t i = 0; i < b->seed_count; i++)
        for (int a = 0; a < 3; a++) b->owned_box[i][a] = 1 << 30, b->owned_box[i][3 + a] = -(1 << 30);
    int c[3];
    for (c[2] = b->clo[2]; c[2] < b->clo[2] + b->cdim[2]; c[2]++)
        for (c[1] = b->clo[1]; c[1] < b->clo[1] + b->cdim[1]; c[1]++)
            for (c[0] = b->clo[0]; c[0] < b->clo[0] + b->cdim[0]; c[0]++)
                for (int octant = 0; octant < 8; octant++) {
                    int v0[3], size[3], first_cell[3];
                    bool empty = false;
                    for (int a = 0; a < 3; a++) {
                        int upper = (octant >> a) & 1;
                        int lo = c[a] * m + (upper ? half : 0), hi = c[a] * m + (upper ? m : half);
                        if (lo < b->vlo[a]) lo = b->vlo[a];
                        if (hi > b->vlo[a] + b->vdim[a]) hi = b->vlo[a] + b->vdim[a];
                        v0[a] = lo, size[a] = hi - lo;
                        first_cell[a] = upper ? c[a] : c[a] - 1;
                        empty |= size[a] <= 0;
                    }
                    if (!empty) own_block(b, v0, size, first_cell);
                }
}

static int32_t owner_at(const region_build *b, const int v[3]) {
    for (int a = 0; a < 3; a++)
        if (v[a] < b->vlo[a] || v[a] >= b->vlo[a] + b->vdim[a]) return -2;
    return b->owner[((size_t)(v[2] - b->vlo[2]) * b->vdim[1] + (v[1] - b->vlo[1])) * b->vdim[0] + (v[0] - b->vlo[0])];
}

/* Whether voxel v's dual block holds both cells. */
static bool dual_holds(int m, const int v[3], const int a[3], const int c[3]) {
    for (int axis = 0; axis < 3; axis++) {
        int first;
        rocks__dual_axis(v[axis], m, &first);
        if (a[axis] != first && a[axis] != first + 1) return false;
        if (c[axis] != first && c[axis] != first + 1) return false;
    }
    return true;
}

/* ---- contacts (001 §5) ------------------------------------------------------------------------ */

/* Whether the point t of the way from sa to sb is nearer sa (d_a < d_b): the bisection's test. */
static inline bool nearer_first(const rocks__seed *sa, const rocks__seed *sb, const float dvec[3], double t) {
    float x = (float)(t * dvec[0]), y = (float)(t * dvec[1]), z = (float)(t * dvec[2]);
    return rocks__distance(sa->q, x, y, z) < rocks__distance(sb->q, x - dvec[0], y - dvec[1], z - dvec[2]);
}

/* Once both ends round to the same float point, every t between them does too (t·d and its
 * rounding are monotone in t), so every later step compares the same distances: the halvings go
 * on (the same bits) without evaluating them. */
static inline bool one_float_point(const float dvec[3], double lo, double hi) {
    return (float)(lo * dvec[0]) == (float)(hi * dvec[0]) && (float)(lo * dvec[1]) == (float)(hi * dvec[1]) &&
           (float)(lo * dvec[2]) == (float)(hi * dvec[2]);
}

/* c_pq is the point of [p_p, p_q] with d_p = d_q, found by bisection, always from the seed with
 * the smaller id (the same bits from either rock's region). The contact is kept when the voxel
 * v holding c_pq has both seeds' cells in its dual block and belongs to p or q, and its neighbour
 * across the face of v nearest to c_pq, with both cells in its dual block too, belongs to the
 * other: then the two rocks share that face, within half a voxel of c_pq, and both meshes pass
 * through its centre. The decision reads only owners computable from either region's closure,
 * so the two rocks agree on it. (001 §5 keeps every pair "into contact"; a pair whose bisector
 * point falls elsewhere touches, if at all, away from c_pq.) */
static bool contact_point(const region_build *b, const rocks__seed *p, const rocks__seed *q, double c[3]) {
    const rocks__seed *sa = p->id < q->id ? p : q, *sb = p->id < q->id ? q : p;
    const int m = b->m;
    float dvec[3];
    for (int a = 0; a < 3; a++) dvec[a] = (float)((sb->cell[a] - sa->cell[a]) * m) + (sb->u[a] - sa->u[a]);
    double lo = 0.0, hi = 1.0;
    bool nearer_a = false, settled = false;
    /* 40 halvings, two a round: a round tests its midpoint and both midpoints the next halving
     * can have, three independent chains the CPU runs side by side, then takes the one it needs
     * (0.5·(lo + t) or 0.5·(t + hi): the very doubles that halving computes). The state after
     * every halving is the one-at-a-time bisection's. The settled check from halving 20 on,
     * when the interval nears a float's precision. */
    for (int i = 0; i < 40; i += 2) {
        double t = 0.5 * (lo + hi), t_lo = 0.5 * (lo + t), t_hi = 0.5 * (t + hi);
        bool at_lo = false, at_hi = false;
        if (!settled) {
            nearer_a = nearer_first(sa, sb, dvec, t);
            at_lo = nearer_first(sa, sb, dvec, t_lo), at_hi = nearer_first(sa, sb, dvec, t_hi);
        }
        if (nearer_a) lo = t;
        else hi = t;
        if (!settled && i >= 20) settled = one_float_point(dvec, lo, hi);
        if (!settled) nearer_a = nearer_a ? at_hi : at_lo;   /* the midpoint below, tested above */
        t = 0.5 * (lo + hi);
        if (nearer_a) lo = t;
        else hi = t;
        if (!settled && i + 1 >= 20) settled = one_float_point(dvec, lo, hi);
    }
    double t = 0.5 * (lo + hi);
    int v[3];
    for (int a = 0; a < 3; a++) {
        double w = sa->u[a] + t * dvec[a];   /* voxels from sa's cell origin */
        int fl = (int)floor(w);
        v[a] = sa->cell[a] * m + fl;
        c[a] = (double)(sa->cell[a] * m) + w;
    }
    if (!dual_holds(m, v, p->cell, q->cell)) return false;
    int32_t pi = (int32_t)(p - b->seeds), qi = (int32_t)(q - b->seeds);
    int32_t o = owner_at(b, v);
    if (o != pi && o != qi) return false;
    int32_t other = o == pi ? qi : pi;
    /* the face of v nearest to c_pq: across it the other rock must own the neighbour */
    int axis = 0;
    double nearest = 1.0;
    int step = 1;
    for (int a = 0; a < 3; a++) {
        double f = c[a] - v[a];   /* 0 … 1 inside v */
        if (f < nearest) nearest = f, axis = a, step = -1;
        if (1.0 - f < nearest) nearest = 1.0 - f, axis = a, step = 1;
    }
    int w[3] = { v[0], v[1], v[2] };
    w[axis] += step;
    return dual_holds(m, w, p->cell, q->cell) && owner_at(b, w) == other;
}

/* contact_point for both rocks of a pair in the region, computed once: the answer (from the
 * seed with the smaller id) is the same whichever rock asks. Results are kept per region rock
 * and neighbour: the cell offset (27) and the seed's index in its cell. */
typedef struct contact_memo {
    uint8_t state;                    /* 0 not yet, 1 no contact, 2 contact at point */
    double point[3];
} contact_memo;

static size_t memo_slot(const region_build *b, int32_t rock, const rocks__seed *p, const rocks__seed *q) {
    int offset = (q->cell[2] - p->cell[2] + 1) * 9 + (q->cell[1] - p->cell[1] + 1) * 3 + (q->cell[0] - p->cell[0] + 1);
    return ((size_t)rock * 27 + (size_t)offset) * (size_t)b->params->seeds_max + (size_t)q->k;
}

static bool remembered_contact(const region_build *b, contact_memo *memo, const int32_t *slot, const rocks__seed *p,
                               const rocks__seed *q, double c[3]) {
    int32_t rp = slot[p - b->seeds], rq = slot[q - b->seeds];
    contact_memo *mine = rp >= 0 ? &memo[memo_slot(b, rp, p, q)] : NULL;
    if (mine && mine->state) {
        memcpy(c, mine->point, sizeof mine->point);
        return mine->state == 2;
    }
    bool kept = contact_point(b, p, q, c);
    if (rq >= 0) {   /* for q's turn */
        contact_memo *theirs = &memo[memo_slot(b, rq, q, p)];
        theirs->state = kept ? 2 : 1;
        memcpy(theirs->point, c, sizeof theirs->point);
    }
    return kept;
}

/* ---- erosion (001 §5) ------------------------------------------------------------------------- */

/* Per-region buffers for erode(), each sized for the largest rock box (no allocation per rock). */
typedef struct erosion_buffers {
    float *rho, *omega;
    uint8_t *empty, *sum_x, *sum_xy;  /* the emptiness indicator and its partial box sums */
    uint8_t *outside, *faces;         /* empty voxels among the 26 (6 face) neighbours */
    uint32_t *active, *emptied;       /* surface voxels that may still erode; those emptied in a step */
    size_t capacity;
} erosion_buffers;

/* Bytes after each byte array's box: its 16-byte loops may read and write up to SLACK − 1
 * past the last voxel they need (into this array's own tail, never the next array's). */
#define SLACK 32

static void erosion_buffers_make(erosion_buffers *e, size_t capacity) {
    e->capacity = capacity;
    e->rho = core_alloc(capacity * sizeof *e->rho);
    e->omega = core_alloc(capacity * sizeof *e->omega);
    const size_t stride = capacity + SLACK;
    e->empty = core_calloc(5, stride);
    e->sum_x = e->empty + stride, e->sum_xy = e->sum_x + stride;
    e->outside = e->sum_xy + stride, e->faces = e->outside + stride;
    e->active = core_alloc(2 * capacity * sizeof *e->active);
    e->emptied = e->active + capacity;
}

static void erosion_buffers_free(erosion_buffers *e) {
    core_free(e->rho, e->capacity * sizeof *e->rho);
    core_free(e->omega, e->capacity * sizeof *e->omega);
    core_free(e->empty, 5 * (e->capacity + SLACK));
    core_free(e->active, 2 * e->capacity * sizeof *e->active);
}

/* ω (001 §5): 0 within a of a contact, linear to 1 at b, the minimum over the contacts; 1 where
 * the box's voxels start. A contact at r ≥ b gives ω_c = 1 and cannot lower the minimum, so each
 * contact visits only the voxels of its ball: per row, the run of the chord (with a margin far
 * over the roundings), and not the rows whose y, z terms alone reach b² (d² only grows with the x
 * term). The run is taken whole, four voxels at a time and without branches: a voxel past b
 * gets ω_c = 1 ((float)√d² ≥ b there, b² being exact in double), and ω is read on the rock's
 * voxels only, so writing it on empty ones changes nothing. The same bits as evaluating every
 * contact at every voxel, whose order does not matter to a minimum. */
static void damping(float *omega, const int lo[3], const int size[3], const double (*contacts)[3],
                    int contact_count, float a, float b) {
    const double b2 = (double)b * (double)b;
    const core_floats4 va = core_floats4_splat(a), vb = core_floats4_splat(b);
    const core_doubles2 half_voxel = core_doubles2_splat(0.5);
    const core_ints4 lane = { 0, 1, 2, 3 };
    for (int c = 0; c < contact_count; c++) {
        const double *p = contacts[c];
        const core_doubles2 centre = core_doubles2_splat(p[0]);
        for (int z = 1; z < size[2] - 1; z++) {
            double dz = lo[2] + z + 0.5 - p[2];
            if (dz * dz >= b2) continue;
            for (int y = 1; y < size[1] - 1; y++) {
                double dy = lo[1] + y + 0.5 - p[1];
                double rest = b2 - (dy * dy + dz * dz);
                if (!(rest > 0.0)) continue;
                double half = sqrt(rest) + 1e-6;   /* the chord, and a margin far over the roundings */
                int from = (int)floor(p[0] - 0.5 - half) - lo[0], to = (int)ceil(p[0] - 0.5 + half) - lo[0];
                if (from < 1) from = 1;
                if (to > size[0] - 2) to = size[0] - 2;
                size_t row = ((size_t)z * size[1] + y) * size[0];
                float *out = omega + row;
                const double dy2 = dy * dy, dz2 = dz * dz;
                /* four at a time (core_lanes.h), no branches; the last group's lanes past `to` get
                 * ω_c = 1 and so write back what they read (at most three past the row's last
                 * interior voxel: its border voxel and the next row's first two, inside the box) */
                for (int x = from; x <= to; x += 4) {
                    core_doubles2 dx0 = (core_doubles2){ lo[0] + x, lo[0] + x + 1 } + half_voxel - centre;
                    core_doubles2 dx1 = (core_doubles2){ lo[0] + x + 2, lo[0] + x + 3 } + half_voxel - centre;
                    core_doubles2 d0 = dx0 * dx0 + core_doubles2_splat(dy2) + core_doubles2_splat(dz2);
                    core_doubles2 d1 = dx1 * dx1 + core_doubles2_splat(dy2) + core_doubles2_splat(dz2);
                    core_floats4 r = core_floats4_from_doubles(core_doubles2_sqrt(d0), core_doubles2_sqrt(d1));
                    core_floats4 old = core_floats4_load(out + x);
                    core_ints4 in_run = lane + (core_ints4){ x, x, x, x } <= (core_ints4){ to, to, to, to };
                    core_floats4 wc = core_floats4_select((r < vb) & in_run, (r - va) / (vb - va), core_floats4_splat(1.0f));
                    wc = core_floats4_select((r < va) & in_run, core_floats4_splat(0.0f), wc);
                    core_floats4_store(out + x, core_floats4_select(wc < old, wc, old));
                }
            }
        }
    }
}

/* How many of each voxel's 26 neighbours are empty, by three separable 3-sums of the emptiness
 * indicator, and of its 6 face neighbours. Each sum runs over the box as one flat array: a voxel
 * on the box's border gets a sum that wraps round a row or plane, but no rock voxel lies on the
 * border, and erosion reads the counts of rock voxels only. */
/* Sixteen voxels' p[−step] + p[0] + p[step] (core_lanes.h: SSE2 on any x86-64). */
static inline core_bytes16 sum3(const uint8_t *p, ptrdiff_t step) {
    return core_bytes16_load(p - step) + core_bytes16_load(p) + core_bytes16_load(p + step);
}

static void count_empty_neighbours(erosion_buffers *e, const int size[3]) {
    const ptrdiff_t sx = size[0], plane = sx * size[1], total = plane * size[2];
    const uint8_t *empty = e->empty;
    uint8_t *sum_x = e->sum_x, *sum_xy = e->sum_xy, *outside = e->outside, *faces = e->faces;
    for (ptrdiff_t i = 1; i < total - 1; i += 16) core_bytes16_store(sum_x + i, sum3(empty + i, 1));
    for (ptrdiff_t i = sx; i < total - sx; i += 16) core_bytes16_store(sum_xy + i, sum3(sum_x + i, sx));
    memset(outside, 0, (size_t)plane);
    memset(faces, 0, (size_t)plane);
    for (ptrdiff_t i = plane; i < total - plane; i += 16) {
        core_bytes16_store(outside + i, sum3(sum_xy + i, plane));
        core_bytes16_store(faces + i, core_bytes16_load(empty + i - 1) + core_bytes16_load(empty + i + 1) +
                                          core_bytes16_load(empty + i - sx) + core_bytes16_load(empty + i + sx) +
                                          core_bytes16_load(empty + i - plane) + core_bytes16_load(empty + i + plane));
    }
    memset(outside + total - plane, 0, (size_t)plane);
    memset(faces + total - plane, 0, (size_t)plane);
}

/* The rock's voxels in its box: emptiness 0, ρ = 1 and ω = 1 on them; emptiness 1 and ρ = 0
 * elsewhere (ω is read on the rock's voxels only). */
static void erosion_start(const region_build *b, int32_t self, const int lo[3], const int size[3], erosion_buffers *e) {
    const int sx = size[0], sy = size[1], sz = size[2];
    const size_t total = (size_t)sx * sy * sz;
    memset(e->empty, 1, total);
    memset(e->rho, 0, total * sizeof *e->rho);
    for (int z = 1; z < sz - 1; z++)
        for (int y = 1; y < sy - 1; y++) {
            /* the box less its border lies inside the owner array (it bounds the rock's voxels) */
            const int32_t *owner = b->owner + ((size_t)(lo[2] + z - b->vlo[2]) * b->vdim[1] + (lo[1] + y - b->vlo[1])) * b->vdim[0] +
                                   (lo[0] - b->vlo[0]);
            size_t row = ((size_t)z * sy + y) * sx;
            uint8_t *empty = e->empty + row;
            float *rho = e->rho + row, *omega = e->omega + row;
            int x = 1;
            for (; x + 4 <= sx - 1; x += 4) {   /* four at a time (core_lanes.h) */
                const core_floats4 one = core_floats4_splat(1.0f);
                const core_ints4 mine = core_ints4_load(owner + x) == (core_ints4){ self, self, self, self };   /* −1 or 0 */
                const uint8_t out[4] = { (uint8_t)(1 + mine[0]), (uint8_t)(1 + mine[1]), (uint8_t)(1 + mine[2]), (uint8_t)(1 + mine[3]) };
                core_floats4_store(rho + x, core_floats4_select(mine, one, core_floats4_splat(0.0f)));
                core_floats4_store(omega + x, one);
                memcpy(empty + x, out, sizeof out);
            }
            for (; x < sx - 1; x++) {
                int mine = owner[x] == self;
                empty[x] = (uint8_t)!mine, rho[x] = (float)mine, omega[x] = 1.0f;
            }
        }
}

/* The surface voxels that can erode, in order: in the rock, undamped, with a face neighbour
 * outside. Eight voxels at a time: one byte each of 1 − empty and of (faces > 0) (faces ≤ 6, so
 * its low three bits), and most groups of eight hold none. */
static size_t erosion_surface(size_t total, const uint8_t *empty, const float *omega, const uint8_t *faces, uint32_t *list) {
    const uint64_t ones = 0x0101010101010101ull;
    size_t count = 0;
    for (size_t i = 0; i < total; i += 8) {
        uint64_t e, f;
        memcpy(&e, empty + i, 8), memcpy(&f, faces + i, 8);
        uint64_t surface = ~e & (f | f >> 1 | f >> 2) & ones;
        if (total - i < 8) surface &= ~(~0ull << 8 * (total - i));   /* the bytes past the box */
        for (; surface; surface &= surface - 1) {
            size_t v = i + (size_t)__builtin_ctzll(surface) / 8;
            if (omega[v] > 0.0f) list[count++] = (uint32_t)v;
        }
    }
    return count;
}

/* ρ over the rock's box grown by one voxel (the border stays 0), after the erosion steps:
 * surface voxels (a face neighbour outside the rock or emptied) lose ε·k·ω a step, with k the
 * share of the 26 neighbours outside (spheroidal weathering, [BFO*07]: corners first) and ω the
 * damping of 001 §5 (0 within a of a contact, linear to 1 at b). Updates read the previous step's
 * state: a voxel's update reads only its own ρ and its neighbour counts, and the counts take the
 * voxels emptied in a step only after it, so the order of the voxels does not matter. Keeping
 * counts instead of reading 26 neighbours a surface voxel a step is what makes this cheap. */
static void erode(const region_build *b, int32_t self, const int lo[3], const int size[3], const double (*contacts)[3],
                  int contact_count, erosion_buffers *e) {
    const rocks__params *params = b->params;
    const int sx = size[0], sy = size[1], sz = size[2];
    erosion_start(b, self, lo, size, e);
    damping(e->omega, lo, size, contacts, contact_count, params->contact_voxels, params->blend_voxels);
    count_empty_neighbours(e, size);
    size_t active = erosion_surface((size_t)sx * sy * sz, e->empty, e->omega, e->faces, e->active);
    const float rate = params->desc.erosion_rate;
    float loss[27];   /* ε·k for k empty neighbours of 26, made once: no division a voxel a step */
    for (int k = 0; k <= 26; k++) loss[k] = rate * ((float)k / 26.0f);
    const ptrdiff_t plane = (ptrdiff_t)sx * sy, face[6] = { -1, 1, -sx, sx, -plane, plane };
    for (int step = 0; step < params->desc.erosion_steps; step++) {
        size_t kept = 0, emptied = 0;
        for (size_t k = 0; k < active; k++) {
            uint32_t i = e->active[k];
            float value = e->rho[i] - loss[e->outside[i]] * e->omega[i];
            if (value > 0.0f) e->rho[i] = value, e->active[kept++] = i;
            else e->rho[i] = 0.0f, e->emptied[emptied++] = i;
        }
        active = kept;
        for (size_t k = 0; k < emptied; k++) {
            uint8_t *outside = e->outside + e->emptied[k];
            for (ptrdiff_t dz = -plane; dz <= plane; dz += plane)
                for (ptrdiff_t dy = -sx; dy <= sx; dy += sx)
                    for (ptrdiff_t dx = -1; dx <= 1; dx++) outside[dz + dy + dx]++;
            outside[0]--;   /* itself */
            for (int f = 0; f < 6; f++) {   /* a voxel that reaches the surface joins the list */
                size_t j = (size_t)((ptrdiff_t)e->emptied[k] + face[f]);
                if (e->faces[j]++ == 0 && !e->empty[j] && e->omega[j] > 0.0f) e->active[active++] = (uint32_t)j;
            }
        }
    }
}

/* ---- the region ------------------------------------------------------------------------------- */

#define GROW(res, field, cap, needed) ((res)->field = core_grow((res)->field, &(res)->cap, (needed), sizeof *(res)->field))

void rocks__region_build(const rocks__params *params, const rocks__build_options *options, int index,
                         rocks__region_result *out) {
    memset(out, 0, sizeof *out);
    region_build b = { .params = params, .m = params->m, .n = params->n };
    rocks__region_make(params, index, &b.region);
    const int m = b.m;
    for (int a = 0; a < 3; a++) {
        b.clo[a] = b.region.lo[a] - 1;
        b.cdim[a] = b.region.hi[a] - b.region.lo[a] + 3;
        b.vlo[a] = (b.region.lo[a] - 1) * m + m / 2;
        b.vdim[a] = (b.region.hi[a] - b.region.lo[a] + 2) * m;
    }
    make_seeds(&b);
    own_voxels(&b);

    /* The region's own seeds, each a rock (its voxel count and box are kept by own_voxels). */
    int32_t *slot = core_alloc(b.seed_count * sizeof *slot);
    uint32_t rocks = 0;
    for (uint32_t s = 0; s < b.seed_count; s++) {
        const int *c = b.seeds[s].cell;
        bool inside = true;
        for (int a = 0; a < 3; a++) inside &= c[a] >= b.region.lo[a] && c[a] <= b.region.hi[a];
        slot[s] = inside ? (int32_t)rocks++ : -1;
    }

    const size_t box_max = (size_t)(2 * m + 3) * (2 * m + 3) * (2 * m + 3);
    erosion_buffers erosion;
    erosion_buffers_make(&erosion, box_max);
    const float *rho = erosion.rho;
    double (*points)[3] = core_alloc(27 * ROCKS__MAX_SEEDS_PER_CELL * sizeof *points);
    const size_t memo_count = (size_t)(rocks ? rocks : 1) * 27 * (size_t)params->seeds_max;
    contact_memo *memo = core_calloc(memo_count, sizeof *memo);
    const float tile_scale = 1.0f / (float)(b.n * m);
    for (uint32_t s = 0; s < b.seed_count; s++) {
        if (slot[s] < 0) continue;
        const rocks__seed *p = &b.seeds[s];
        if (b.owned[s] == 0 && !options->keep_empty) continue;   /* owns no voxel centre */

        /* contacts with the seeds of the 26 cells around and its own cell */
        uint32_t contact_first = out->contact_count;
        int points_count = 0;
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int c[3] = { p->cell[0] + dx, p->cell[1] + dy, p->cell[2] + dz };
                    size_t cs = cell_slot(&b, c);
                    for (uint32_t i = 0; i < b.cell_count[cs]; i++) {
                        const rocks__seed *q = &b.seeds[b.cell_first[cs] + i];
                        if (q == p) continue;
                        double point[3];
                        if (!remembered_contact(&b, memo, slot, p, q, point)) continue;
                        memcpy(points[points_count++], point, sizeof point);
                        size_t old_cap = out->contact_cap;
                        GROW(out, contacts, contact_cap, out->contact_count + 1);
                        if (out->contact_cap != old_cap)
                            out->contact_other = core_realloc(out->contact_other, old_cap * sizeof *out->contact_other,
                                                              out->contact_cap * sizeof *out->contact_other);
                        rocks_contact *ct = &out->contacts[out->contact_count];
                        memset(ct, 0, sizeof *ct);
                        int origin[3];
                        int other = rocks__region_of_cell(params, q->cell, b.region.known, b.region.colour, origin);
                        for (int a = 0; a < 3; a++) {
                            ct->point[a] = (float)point[a] * tile_scale;
                            ct->other_offset[a] = (int8_t)(other >= 0 ? origin[a] : 0);
                        }
                        int *o = out->contact_other[out->contact_count];
                        o[0] = other;
                        for (int a = 0; a < 3; a++) o[1 + a] = q->cell[a] - (other >= 0 ? origin[a] : 0) * b.n;
                        o[4] = q->k;
                        out->contact_count++;
                    }
                }

        rocks_rock rock = { 0 };
        int lo[3], size[3];
        for (int a = 0; a < 3; a++) {
            int *box = b.owned_box[s];
            if (b.owned[s] == 0) box[a] = box[3 + a] = p->cell[a] * m + m / 2;
            lo[a] = box[a] - 1;
            size[a] = box[3 + a] - box[a] + 3;
        }
        erode(&b, (int32_t)s, lo, size, (const double (*)[3])points, points_count, &erosion);
        bool kept = rocks__rock_mesh(params, rho, lo, size, p, out, &rock);
        if (!kept && !options->keep_empty) {
            out->contact_count = contact_first;   /* a rock without contacts; drop it */
            continue;
        }
        rock.contact_first = contact_first;
        rock.contact_count = out->contact_count - contact_first;
        for (int a = 0; a < 3; a++) rock.seed[a] = ((float)(p->cell[a] * m) + p->u[a]) * tile_scale;
        rock.region = (uint8_t)b.region.kind;
        size_t old_cap = out->rock_cap;
        GROW(out, rocks, rock_cap, out->rock_count + 1);
        if (out->rock_cap != old_cap) {
            out->rock_cell = core_realloc(out->rock_cell, old_cap * sizeof *out->rock_cell, out->rock_cap * sizeof *out->rock_cell);
            out->rock_k = core_realloc(out->rock_k, old_cap * sizeof *out->rock_k, out->rock_cap * sizeof *out->rock_k);
            out->voxel_first = core_realloc(out->voxel_first, old_cap * sizeof *out->voxel_first, out->rock_cap * sizeof *out->voxel_first);
            out->voxel_count = core_realloc(out->voxel_count, old_cap * sizeof *out->voxel_count, out->rock_cap * sizeof *out->voxel_count);
        }
        uint32_t ri = out->rock_count++;
        out->rocks[ri] = rock;
        memcpy(out->rock_cell[ri], p->cell, sizeof p->cell);
        out->rock_k[ri] = p->k;
        out->voxel_first[ri] = out->voxel_total;
        out->voxel_count[ri] = 0;
        if (options->keep_voxels) {
            for (int z = 1; z < size[2] - 1; z++)
                for (int y = 1; y < size[1] - 1; y++)
                    for (int x = 1; x < size[0] - 1; x++) {
                        int v[3] = { lo[0] + x, lo[1] + y, lo[2] + z };
                        if (owner_at(&b, v) != (int32_t)s) continue;
                        size_t old = out->voxel_cap;
                        GROW(out, voxels, voxel_cap, out->voxel_total + 1);
                        if (out->voxel_cap != old)
                            out->voxel_rho = core_realloc(out->voxel_rho, old * sizeof *out->voxel_rho, out->voxel_cap * sizeof *out->voxel_rho);
                        for (int a = 0; a < 3; a++) out->voxels[out->voxel_total][a] = (int16_t)v[a];
                        out->voxel_rho[out->voxel_total] = rho[((size_t)z * size[1] + y) * size[0] + x];
                        out->voxel_total++;
                        out->voxel_count[ri]++;
                    }
        }
    }
    core_free(points, 27 * ROCKS__MAX_SEEDS_PER_CELL * sizeof *points);
    core_free(memo, memo_count * sizeof *memo);
    erosion_buffers_free(&erosion);
    core_free(b.owned, (b.seed_count ? b.seed_count : 1) * sizeof *b.owned);
    core_free(b.owned_box, (b.seed_count ? b.seed_count : 1) * sizeof *b.owned_box);
    core_free(slot, b.seed_count * sizeof *slot);
    size_t cells = (size_t)b.cdim[0] * b.cdim[1] * b.cdim[2];
    core_free(b.cell_first, cells * sizeof *b.cell_first);
    core_free(b.cell_count, cells * sizeof *b.cell_count);
    core_free(b.seeds, cells * ROCKS__MAX_SEEDS_PER_CELL * sizeof *b.seeds);
    core_free(b.owner, (size_t)b.vdim[0] * b.vdim[1] * b.vdim[2] * sizeof *b.owner);
}

void rocks__region_result_free(rocks__region_result *r) {
    core_free(r->rocks, r->rock_cap * sizeof *r->rocks);
    core_free(r->rock_cell, r->rock_cap * sizeof *r->rock_cell);
    core_free(r->rock_k, r->rock_cap * sizeof *r->rock_k);
    core_free(r->voxel_first, r->rock_cap * sizeof *r->voxel_first);
    core_free(r->voxel_count, r->rock_cap * sizeof *r->voxel_count);
    core_free(r->vertices, r->vertex_cap * sizeof *r->vertices);
    core_free(r->indices, r->index_cap * sizeof *r->indices);
    core_free(r->anchors, r->anchor_cap * sizeof *r->anchors);
    core_free(r->contacts, r->contact_cap * sizeof *r->contacts);
    core_free(r->contact_other, r->contact_cap * sizeof *r->contact_other);
    core_free(r->voxels, r->voxel_cap * sizeof *r->voxels);
    core_free(r->voxel_rho, r->voxel_cap * sizeof *r->voxel_rho);
    memset(r, 0, sizeof *r);
}
