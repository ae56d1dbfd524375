/* rocks_simplify.c — a rock's levels of detail by quadric edge collapse (the meshes of 001 §5,
 * made small enough to keep 256 tiles of them).
 *
 * Garland and Heckbert's quadrics, weighed as meshoptimizer's simplifier (which this replaces)
 * weighs them: each vertex sums the planes of its triangles weighted by area, and moving vertex
 * u onto a neighbour v costs u's area-weighted mean squared distance from v to those planes
 * (voxels²). Collapses only move a vertex onto an existing neighbour, so every level uses a
 * subset of the marching-cubes vertices. As meshoptimizer, the work goes in passes: a pass ranks
 * the collapses (a counting sort on the top bits of the error), takes them in that order and
 * ends when the errors climb well past those of the cheapest third; a collapse that would turn a
 * triangle over (normals' dot product ≤ 0) is refused. Differences, all for rocks:
 *   - Closed meshes stay closed: a collapse u → v is refused unless u and v have exactly two
 *     common neighbours (the apexes of their two triangles) and the apexes do not make a
 *     triangle with each of them: the link condition of a closed 2-manifold. meshoptimizer 0.18
 *     does not check it, and about one rock in nine came out open and fell back to the whole
 *     marching-cubes mesh.
 *   - Within a pass a vertex may take several others, but once it has taken one it does not
 *     move (meshoptimizer locks both ends of each collapse): the ranked cost of moving u onto v
 *     reads u's quadric and v's position only, so it stays exact while v takes others. The
 *     checks read the mesh as it is, from the pass's adjacency and the collapses written into
 *     the triangles at once (a vertex's triangles are its own and those of the vertices it took).
 *   - Both directions of every edge are ranked (no branch on which is cheaper).
 *   - One run makes all levels: it stops at each level's error bound or triangle target, writes
 *     the level, then goes on. Coarser levels so keep the quadrics of the full mesh (their error
 *     is measured from the marching-cubes surface, not from LOD 0), and the full mesh is set up
 *     once, not three times.
 * Measured on 2 000 rocks of the round set: LOD 0 keeps 72.5 triangles (meshoptimizer 73.6, of
 * which 11.6 % open), the marching-cubes vertices lie 0.18 voxel from it on average (the same).
 */
#include "rocks_internal.h"

#include "core/core.h"

#include <math.h>
#include <string.h>

#define NONE UINT32_MAX
#define SORT_BINS 257                 /* 16 an octave over the 16 octaves under the limit */

typedef struct collapse {
    uint32_t from, to;
    float error;
    uint32_t key;                     /* its bin in the ranking's counting sort */
} collapse;

/* The plane quadric of a vertex, Σ w (n·p + d)² = pᵀAp + 2bᵀp + c, as a00 a11 a22 2a01 2a02 2a12
 * 2b0 2b1 2b2 c, then Σ w and a zero (twelve: sums of them vectorise), and the weight's inverse
 * apart. Positions are taken from the centre of the mesh's box (floats then keep the
 * cancellation against c small). */
#define QUADRIC_FLOATS 12
#define WEIGHT 10
typedef struct quadric {
    float a[QUADRIC_FLOATS];
} quadric;

static void quadric_add(quadric *q, const quadric *r) {
    for (int i = 0; i < QUADRIC_FLOATS; i++) q->a[i] += r->a[i];
}

struct rocks__simplifier {
    float *positions;                 /* relative to the centre of their box */
    quadric *quadrics;
    float *inverse;                   /* 1 / Σ w of each quadric */
    uint32_t vertex_count, live_vertices;
    uint32_t *indices;                /* the mesh so far */
    size_t index_count, capacity;
    uint32_t *first, *triangles;      /* the pass's adjacency: vertex v's triangles are
                                         triangles[first[v] … first[v + 1]) */
    uint32_t pass_id;
    uint32_t *took;                   /* the last pass in which a vertex took another */
    uint32_t *taken_first, *taken_next;   /* the vertices it took then, as a list */
    uint8_t *gone;                    /* moved onto another */
    uint32_t *stamp, stamp_value;
    collapse *collapses, *sorted;     /* ranked; then in order of error (counting sort) */
    float worst;                      /* the largest error taken so far */
    core_arena arena;                 /* holds this struct and every array above */
};

/* An error's rank bin: its float bits >> 19 (errors ≥ 0 order like their bits), 16 bins an
 * octave, counted down from the limit's; errors under 2⁻¹⁶ of the limit share the first bin. */
static uint32_t float_bits(float value) {
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    return bits;
}

static uint32_t sort_key(float error, uint32_t top) {
    uint32_t bits = float_bits(error) >> 19;
    return bits + (SORT_BINS - 1) <= top ? 0 : bits + (SORT_BINS - 1) - top;
}

static void quadric_add_triangle(quadric *q, const float *p0, const float *p1, const float *p2) {
    float e1[3], e2[3];
    for (int a = 0; a < 3; a++) e1[a] = p1[a] - p0[a], e2[a] = p2[a] - p0[a];
    float n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
    float length = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 0.0f)) return;     /* a degenerate triangle has no plane and no area */
    float inverse = 1.0f / length, w = length;   /* twice the area */
    for (int a = 0; a < 3; a++) n[a] *= inverse;
    float d = -(n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2]), nw[3] = { n[0] * w, n[1] * w, n[2] * w };
    q->a[0] += n[0] * nw[0], q->a[1] += n[1] * nw[1], q->a[2] += n[2] * nw[2];
    q->a[3] += 2.0f * n[0] * nw[1], q->a[4] += 2.0f * n[0] * nw[2], q->a[5] += 2.0f * n[1] * nw[2];
    q->a[6] += 2.0f * nw[0] * d, q->a[7] += 2.0f * nw[1] * d, q->a[8] += 2.0f * nw[2] * d;
    q->a[9] += d * d * w;
    q->a[WEIGHT] += w;
}

/* The mean squared distance from p (box-centred) to the planes q holds, given 1 / Σ w. */
static inline float quadric_error(const quadric *q, float inverse, const float *p) {
    const float *a = q->a, x = p[0], y = p[1], z = p[2];
    float r = x * (a[0] * x + a[3] * y + a[4] * z + a[6]) + y * (a[1] * y + a[5] * z + a[7]) + z * (a[2] * z + a[8]) + a[9];
    return fabsf(r) * inverse;
}

static float inverse_weight(const quadric *q) { return q->a[WEIGHT] > 0.0f ? 1.0f / q->a[WEIGHT] : 0.0f; }

/* ---- a pass ------------------------------------------------------------------------------------ */

static void build_adjacency(rocks__simplifier *s) {
    const uint32_t n = s->vertex_count;
    memset(s->first, 0, (n + 1) * sizeof *s->first);
    for (size_t i = 0; i < s->index_count; i++) s->first[s->indices[i]]++;
    for (uint32_t v = 0; v < n; v++) s->first[v + 1] += s->first[v];   /* ends */
    for (size_t t = s->index_count / 3; t-- > 0;)                      /* fill back to starts */
        for (int k = 0; k < 3; k++) s->triangles[--s->first[s->indices[3 * t + k]]] = (uint32_t)t;
}

/* Every half-edge a → b as the collapse of a onto b (so both directions of each edge), when it
 * costs at most `limit`; copied into s->sorted in order of error (the pass then reads them one
 * after the other). Returns the count. Branch-free: the candidate is written and kept by
 * advancing the count. */
static size_t rank_collapses(rocks__simplifier *s, float limit) {
    const uint32_t top = float_bits(limit) >> 19;
    size_t count = 0;
    for (size_t i = 0; i < s->index_count; i += 3)
        for (int k = 0; k < 3; k++) {
            uint32_t a = s->indices[i + k], b = s->indices[i + (k == 2 ? 0 : k + 1)];
            float error = quadric_error(&s->quadrics[a], s->inverse[a], s->positions + 3 * (size_t)b);
            s->collapses[count] = (collapse){ a, b, error, sort_key(error, top) };
            count += error <= limit;
        }
    uint32_t histogram[SORT_BINS];
    memset(histogram, 0, sizeof histogram);
    for (size_t i = 0; i < count; i++) histogram[s->collapses[i].key]++;
    uint32_t sum = 0;
    for (uint32_t k = 0; k < SORT_BINS; k++) {
        uint32_t here = histogram[k];
        histogram[k] = sum;
        sum += here;
    }
    for (size_t i = 0; i < count; i++) s->sorted[histogram[s->collapses[i].key]++] = s->collapses[i];
    return count;
}

static bool turns_over(const float *a, const float *b, const float *from, const float *to) {
    float eb[3], ef[3], et[3];
    for (int i = 0; i < 3; i++) eb[i] = b[i] - a[i], ef[i] = from[i] - a[i], et[i] = to[i] - a[i];
    float n0[3] = { eb[1] * ef[2] - eb[2] * ef[1], eb[2] * ef[0] - eb[0] * ef[2], eb[0] * ef[1] - eb[1] * ef[0] };
    float n1[3] = { eb[1] * et[2] - eb[2] * et[1], eb[2] * et[0] - eb[0] * et[2], eb[0] * et[1] - eb[1] * et[0] };
    return n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2] <= 0.0f;
}

/* Triangle t (the pass's collapses are written into it at once); false when it has collapsed. */
static inline bool current_triangle(const rocks__simplifier *s, uint32_t t, uint32_t out[3]) {
    memcpy(out, s->indices + 3 * (size_t)t, 3 * sizeof *out);
    return out[0] != out[1] && out[1] != out[2] && out[0] != out[2];
}

/* The next list of vertex v's triangles as they are in the middle of a pass: its own list from
 * the pass's start (x = v), then the lists of the vertices it took in this pass (their triangles
 * now hold v). Nothing else changes a vertex's triangles, and a vertex that took one does not
 * move again in the pass (so a vertex about to move has its own list only). NONE at the end. */
static inline uint32_t next_list(const rocks__simplifier *s, uint32_t v, uint32_t x) {
    if (x != v) return s->taken_next[x];
    return s->took[v] == s->pass_id ? s->taken_first[v] : NONE;
}

/* Whether v has a triangle on both b and c. */
static bool has_triangle_on(const rocks__simplifier *s, uint32_t v, uint32_t b, uint32_t c) {
    uint32_t tri[3];
    for (uint32_t x = v; x != NONE; x = next_list(s, v, x))
        for (uint32_t i = s->first[x]; i < s->first[x + 1]; i++)
            if (current_triangle(s, s->triangles[i], tri) && (tri[0] == b || tri[1] == b || tri[2] == b) &&
                (tri[0] == c || tri[1] == c || tri[2] == c))
                return true;
    return false;
}

/* The link condition of a closed 2-manifold: exactly two common neighbours (the apexes a, b of
 * the edge's triangles), and not both triangles u a b and v a b (collapsing would fold them onto
 * each other); and no turned triangle. u has taken none in this pass. */
static bool can_collapse(rocks__simplifier *s, uint32_t u, uint32_t v) {
    uint32_t near_v = ++s->stamp_value, counted = ++s->stamp_value, tri[3];
    /* v's neighbours. A collapsed triangle in v's lists needs no test: it holds v and vertices
     * still joined to v (the link condition keeps the edge from v to a collapsed triangle's
     * apex), so stamping it marks nothing new. */
    for (uint32_t x = v; x != NONE; x = next_list(s, v, x))
        for (uint32_t i = s->first[x]; i < s->first[x + 1]; i++) {
            const uint32_t *t = s->indices + 3 * (size_t)s->triangles[i];
            s->stamp[t[0]] = near_v, s->stamp[t[1]] = near_v, s->stamp[t[2]] = near_v;
        }
    int common = 0;
    uint32_t apexes[2] = { NONE, NONE };
    const float *pu = s->positions + 3 * (size_t)u, *pv = s->positions + 3 * (size_t)v;
    for (uint32_t i = s->first[u]; i < s->first[u + 1]; i++) {
        if (!current_triangle(s, s->triangles[i], tri)) continue;
        if (tri[0] == v || tri[1] == v || tri[2] == v) continue;   /* the two that vanish */
        int k = tri[0] == u ? 0 : tri[1] == u ? 1 : 2;
        uint32_t b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
        bool shared_b = s->stamp[b] == near_v || s->stamp[b] == counted;
        bool shared_c = s->stamp[c] == near_v || s->stamp[c] == counted;
        if (shared_b && shared_c) apexes[0] = b, apexes[1] = c;   /* u a b: is there a v a b? */
        common += (s->stamp[b] == near_v) + (s->stamp[c] == near_v);
        if (shared_b) s->stamp[b] = counted;
        if (shared_c) s->stamp[c] = counted;
        if (turns_over(s->positions + 3 * (size_t)b, s->positions + 3 * (size_t)c, pu, pv)) return false;
    }
    if (common != 2) return false;
    return apexes[0] == NONE || !has_triangle_on(s, v, apexes[0], apexes[1]);
}

/* Moves u onto v: u's triangles now hold v (those on both collapse), v takes u's planes. */
static void collapse_onto(rocks__simplifier *s, uint32_t u, uint32_t v) {
    for (uint32_t j = s->first[u]; j < s->first[u + 1]; j++) {
        uint32_t *tri = s->indices + 3 * (size_t)s->triangles[j];
        for (int k = 0; k < 3; k++) tri[k] = tri[k] == u ? v : tri[k];
    }
    s->taken_next[u] = s->took[v] == s->pass_id ? s->taken_first[v] : NONE;
    s->taken_first[v] = u;
    s->took[v] = s->pass_id;
    s->gone[u] = 1;
    quadric_add(&s->quadrics[v], &s->quadrics[u]);
    s->inverse[v] = inverse_weight(&s->quadrics[v]);
    s->live_vertices--;
}

/* One pass towards `limit` and `target_index_count`; returns the collapses made. A vertex that
 * has taken one in this pass does not move (its ranked costs are stale); one that has moved is
 * gone. */
static size_t pass(rocks__simplifier *s, float limit, size_t target_index_count) {
    build_adjacency(s);
    size_t count = rank_collapses(s, limit);
    if (count == 0) return 0;
    s->pass_id++;
    /* as meshoptimizer: the pass ends when the error passes 1.5× that of the edge_goal-th
     * cheapest, once a sixth of the goal is done, so cheap collapses go first across passes */
    size_t triangle_goal = (s->index_count - target_index_count) / 3, edge_goal = triangle_goal / 2;
    size_t removed = 0, made = 0;
    float error_goal = edge_goal < count ? 1.5f * s->sorted[edge_goal].error : INFINITY;
    for (size_t i = 0; i < count && removed < triangle_goal && s->live_vertices > 4; i++) {
        const collapse *c = &s->sorted[i];
        if (c->error > error_goal && c->error > s->worst && removed > triangle_goal / 6) break;
        if (s->gone[c->from] || s->gone[c->to] || s->took[c->from] == s->pass_id) continue;
        if (!can_collapse(s, c->from, c->to)) {
            edge_goal++;   /* a refused collapse does not count towards the goal's error */
            error_goal = edge_goal < count ? 1.5f * s->sorted[edge_goal].error : INFINITY;
            continue;
        }
        collapse_onto(s, c->from, c->to);
        if (c->error > s->worst) s->worst = c->error;
        removed += 2, made++;
    }
    size_t write = 0;   /* drop the collapsed triangles */
    for (size_t i = 0; i < s->index_count; i += 3) {
        const uint32_t *tri = s->indices + i;
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
        s->indices[write] = tri[0], s->indices[write + 1] = tri[1], s->indices[write + 2] = tri[2];
        write += 3;
    }
    s->index_count = write;
    return made;
}

/* ---- the calls --------------------------------------------------------------------------------- */

/* The positions relative to the centre of their box. */
static void centre_positions(float *out, const float *positions, size_t vertex_count) {
    float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    for (size_t v = 0; v < vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            float p = positions[3 * v + a];
            lo[a] = p < lo[a] ? p : lo[a], hi[a] = p > hi[a] ? p : hi[a];
        }
    const float centre[3] = { 0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2]) };
    for (size_t v = 0; v < vertex_count; v++)
        for (int a = 0; a < 3; a++) out[3 * v + a] = positions[3 * v + a] - centre[a];
}

/* Each vertex's quadric from its triangles' planes, and the live vertices (a triangle uses them). */
static void make_quadrics(rocks__simplifier *s, const uint32_t *indices, size_t index_count) {
    for (size_t i = 0; i + 2 < index_count; i += 3) {
        quadric q = { { 0 } };
        const float *p = s->positions;
        quadric_add_triangle(&q, p + 3 * (size_t)indices[i], p + 3 * (size_t)indices[i + 1], p + 3 * (size_t)indices[i + 2]);
        for (int k = 0; k < 3; k++) quadric_add(&s->quadrics[indices[i + k]], &q);
    }
    for (size_t i = 0; i < index_count; i++) s->stamp[indices[i]] = 1;
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        s->inverse[v] = inverse_weight(&s->quadrics[v]);
        s->live_vertices += s->stamp[v];
    }
    s->stamp_value = 1;
}

/* An array of count items from the simplifier's arena. */
#define TAKE(arena, pointer, count) ((pointer) = core_arena_alloc((arena), (count) * sizeof *(pointer), 16))

rocks__simplifier *rocks__simplify_begin(const uint32_t *indices, size_t index_count, const float *positions,
                                         size_t vertex_count) {
    size_t n = vertex_count ? vertex_count : 1, capacity = index_count ? index_count : 3;
    /* the simplifier and all its arrays from one arena: a block or two a rock, not fourteen */
    core_arena arena = { 0 };
    rocks__simplifier *s = core_arena_alloc(&arena, sizeof *s, 16);
    memset(s, 0, sizeof *s);
    s->vertex_count = (uint32_t)vertex_count;
    s->capacity = capacity;
    s->index_count = index_count;
    TAKE(&arena, s->indices, capacity);
    TAKE(&arena, s->triangles, capacity);
    TAKE(&arena, s->collapses, capacity);
    TAKE(&arena, s->sorted, capacity);
    TAKE(&arena, s->positions, 3 * n);
    TAKE(&arena, s->quadrics, n);
    TAKE(&arena, s->inverse, n);
    TAKE(&arena, s->first, n + 1);
    TAKE(&arena, s->stamp, n);
    TAKE(&arena, s->took, n);
    TAKE(&arena, s->taken_first, n);
    TAKE(&arena, s->taken_next, n);
    TAKE(&arena, s->gone, n);
    s->arena = arena;   /* the arena's blocks, kept with what they hold */
    memset(s->quadrics, 0, n * sizeof *s->quadrics);   /* the sums, stamps and marks start at 0 */
    memset(s->stamp, 0, n * sizeof *s->stamp);
    memset(s->took, 0, n * sizeof *s->took);
    memset(s->gone, 0, n);
    memcpy(s->indices, indices, index_count * sizeof *indices);
    centre_positions(s->positions, positions, vertex_count);
    make_quadrics(s, indices, index_count);
    return s;
}

size_t rocks__simplify_run(rocks__simplifier *s, float error, size_t target_index_count, uint32_t *out) {
    const float limit = error * error;
    while (s->index_count > target_index_count && s->live_vertices > 4 && pass(s, limit, target_index_count) > 0) {
    }
    memcpy(out, s->indices, s->index_count * sizeof *out);
    return s->index_count;
}

void rocks__simplify_end(rocks__simplifier *s) {
    if (!s) return;
    core_arena arena = s->arena;   /* s lies in it */
    core_arena_release(&arena);
}
