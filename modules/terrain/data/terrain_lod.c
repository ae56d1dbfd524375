/* terrain_lod.c — meshes of coarser levels whose seams with finer neighbours are closed by
 * "subdivided transition faces" (README, Level of detail).
 *
 * A chunk at level L samples f every s = 2^L grid points (h = s/2 is the finer level's spacing).
 * A cell edge on a boundary shared with a finer neighbour is split at its midpoint (one more
 * sample, on the fine grid); a cell face on a face shared with a finer face neighbour also gets
 * its centre sample (3 × 3 samples: four fine faces). Such "transition" cells are contoured face
 * by face with the rule of terrain_mesh_tables.c, generalised to a convex polygon of samples:
 * walk the face's boundary counter-clockwise seen from outside the cell; each run of inside
 * (f > 0) samples is cut off by one segment from the crossing where the walk enters it to the
 * one where it leaves it (inside on the segment's right). On a square this is exactly the table's
 * rule (ambiguous faces keep the inside corners apart), so:
 *   - a subdivided face's four sub-squares are contoured exactly as the finer chunk contours its
 *     cell faces there (same four samples, same rule, crossings interpolated from the lower
 *     index with the same rounding: same positions to the bit);
 *   - a face with split edges but no centre (between two coarse cells, beside a seam) depends on
 *     its own samples only, and the coarse cell across it splits the same edges (the split rule
 *     is a function of where the edge lies and which regions around it are finer), so it draws
 *     the same segments;
 *   - a face without split edges is a square: the table rule, as the regular cell across it.
 * Every crossing on a cell edge then starts one of the cell's segments and ends one (the two
 * faces beside the edge walk it in opposite directions), so they chain into closed loops;
 * a loop of 3 is one triangle, a longer one a fan around an added centroid vertex (its spokes
 * belong to this cell alone), and a loop of 2 — two segments along one split edge, from two
 * faces of the cell, around a midpoint sample whose sign differs from both ends — is dropped:
 * the cells across those two faces carry the edge, once in each direction. So every mesh edge
 * has two triangles, in opposite directions. Cells without split edges keep the case table.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LOD_CELLS TERRAIN_MESH_CELLS
#define LOD_SAMPLES (LOD_CELLS + 3)          /* a one-sample apron on each side */
#define LOD_FINE (2 * LOD_CELLS + 1)         /* fine samples along a face side */
#define LOD_NO_VERTEX UINT32_MAX
#define LOD_MAX_LEVEL 16
#define LOD_MAX_SEGMENTS 64

uint32_t terrain_lod_neighbour_bit(int dx, int dy, int dz) {
    if (dx < -1 || dx > 1 || dy < -1 || dy > 1 || dz < -1 || dz > 1 || (dx == 0 && dy == 0 && dz == 0)) return 0;
    int index = (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1);
    return 1u << (index < 13 ? index : index - 1);
}

/* A chunk face (axis a, side 0 = low, 1 = high) sampled on the fine grid, and the vertices of
 * its fine segments: values[w·65 + u], u along the lower other axis, w the higher. */
typedef struct lod_face {
    bool sampled;
    terrain_field field;
    uint32_t *vertex[2];                 /* segment from (u, w) one step along u [0] or w [1] */
} lod_face;

typedef struct lod_chunk {
    terrain__mesh_builder b;
    const float *values;                 /* the coarse samples */
    bool split[3][3][3];                 /* [axis][side_u + 1][side_w + 1]: edges there split */
    bool subdivided[3][2];               /* chunk faces shared with a finer face neighbour */
    lod_face faces[6];                   /* index axis·2 + side */
    uint32_t *edges[3];                  /* vertex of the unsplit coarse edge from a sample, per axis */
    float fine_spacing;
} lod_chunk;

static void other_axes(int a, int *u, int *w) {
    *u = a == 0 ? 1 : 0;
    *w = a == 2 ? 1 : 2;
}

/* -1, 0, 1: where a coarse sample index lies across the meshed box along one axis. */
static int lod_side(int q) { return q == 1 ? -1 : q == LOD_CELLS + 1 ? 1 : 0; }

static size_t lod_index(const int p[3]) {
    return ((size_t)p[2] * LOD_SAMPLES + (size_t)p[1]) * LOD_SAMPLES + (size_t)p[0];
}

/* Whether the coarse edge from sample p along axis a is split. */
static bool lod_edge_split(const lod_chunk *c, int a, const int p[3]) {
    int u, w;
    other_axes(a, &u, &w);
    return c->split[a][lod_side(p[u]) + 1][lod_side(p[w]) + 1];
}

/* ---- fine points: coordinates F = 2·(coarse sample index) (+1 at midpoints and centres) ---- */

/* The first sampled chunk face whose plane holds every point of `count` (fine coordinates). */
static int lod_face_of(const lod_chunk *c, const int (*points)[3], int count) {
    for (int f = 0; f < 6; f++) {
        int a = f / 2, plane = f % 2 ? 2 * (LOD_CELLS + 1) : 2;
        if (!c->faces[f].sampled) continue;
        bool all = true;
        for (int k = 0; k < count; k++) all &= points[k][a] == plane;
        if (all) return f;
    }
    return -1;
}

static void lod_face_uw(int f, const int F[3], int *u_out, int *w_out) {
    int u, w;
    other_axes(f / 2, &u, &w);
    *u_out = F[u] - 2, *w_out = F[w] - 2;
}

static float lod_value(const lod_chunk *c, const int F[3]) {
    if (!(F[0] & 1) && !(F[1] & 1) && !(F[2] & 1)) {
        int p[3] = { F[0] / 2, F[1] / 2, F[2] / 2 };
        return c->values[lod_index(p)];
    }
    int f = lod_face_of(c, (const int(*)[3])F, 1), u, w;
    lod_face_uw(f, F, &u, &w);
    return c->faces[f].field.values[w * LOD_FINE + u];
}

/* Gradient at a fine point: the coarse one, averaged over the coarse samples around it. */
static void lod_gradient(const lod_chunk *c, const int F[3], float g[3]) {
    g[0] = g[1] = g[2] = 0.0f;
    int count = 0;
    for (int corner = 0; corner < 8; corner++) {
        int p[3];
        bool skip = false;
        for (int a = 0; a < 3; a++) {
            int bit = (corner >> a) & 1;
            if (!(F[a] & 1) && bit) skip = true;
            p[a] = (F[a] >> 1) + bit;
        }
        if (skip) continue;
        float gc[3];
        terrain__mesh_gradient(&c->b, p[0], p[1], p[2], gc);
        for (int a = 0; a < 3; a++) g[a] += gc[a];
        count++;
    }
    for (int a = 0; a < 3; a++) g[a] /= (float)count;
}

/* The vertex on the fine segment from F0 one fine step along axis a (F0 the lower end). */
static uint32_t lod_fine_vertex(lod_chunk *c, const int F0[3], int a) {
    int F1[3] = { F0[0], F0[1], F0[2] };
    F1[a]++;
    const int ends[2][3] = { { F0[0], F0[1], F0[2] }, { F1[0], F1[1], F1[2] } };
    int f = lod_face_of(c, ends, 2), u, w, fu, fw;
    other_axes(f / 2, &fu, &fw);
    lod_face_uw(f, F0, &u, &w);
    uint32_t *slot = &c->faces[f].vertex[a == fu ? 0 : 1][w * LOD_FINE + u];
    if (*slot != LOD_NO_VERTEX) return *slot;
    float f0 = lod_value(c, F0), f1 = lod_value(c, F1);
    float t = terrain__mesh_edge_t(f0, f1);
    terrain__mesh_builder *b = &c->b;
    b->vertices = core_grow(b->vertices, &b->vertex_capacity, b->vertex_count + 1, sizeof *b->vertices);
    terrain_vertex *v = &b->vertices[b->vertex_count];
    /* (F + t)·h is exact in a float, as the finer chunk's (index + t)·h for the same point. */
    for (int k = 0; k < 3; k++) v->position[k] = (float)F0[k] * c->fine_spacing;
    v->position[a] = ((float)F0[a] + t) * c->fine_spacing;
    float g0[3], g1[3], g[3], length2 = 0.0f;
    lod_gradient(c, F0, g0);
    lod_gradient(c, F1, g1);
    for (int k = 0; k < 3; k++) {
        g[k] = g0[k] + t * (g1[k] - g0[k]);
        length2 += g[k] * g[k];
    }
    if (length2 > 0.0f) {
        float inverse = -1.0f / sqrtf(length2);
        for (int k = 0; k < 3; k++) v->normal[k] = g[k] * inverse;
    } else {
        v->normal[0] = v->normal[1] = v->normal[2] = 0.0f;
        v->normal[a] = f0 > 0.0f ? 1.0f : -1.0f;
    }
    v->weights[0] = 255, v->weights[1] = v->weights[2] = v->weights[3] = 0;
    *slot = (uint32_t)b->vertex_count++;
    return *slot;
}

/* The vertex on the unsplit coarse edge from sample p along axis a. */
static uint32_t lod_edge_vertex(lod_chunk *c, const int p[3], int a) {
    size_t i = lod_index(p);
    if (c->edges[a][i] != LOD_NO_VERTEX) return c->edges[a][i];
    size_t stride = a == 0 ? 1 : a == 1 ? LOD_SAMPLES : (size_t)LOD_SAMPLES * LOD_SAMPLES;
    c->edges[a][i] = terrain__mesh_add_vertex(&c->b, p[0], p[1], p[2], a, c->values[i], c->values[i + stride]);
    return c->edges[a][i];
}

/* The vertex where the boundary piece between fine points A and B (one axis apart, 1 or 2 fine
 * steps) crosses the surface. */
static uint32_t lod_piece_vertex(lod_chunk *c, const int A[3], const int B[3]) {
    int a = A[0] != B[0] ? 0 : A[1] != B[1] ? 1 : 2;
    const int *low = A[a] < B[a] ? A : B;
    if (abs(A[a] - B[a]) == 2) {
        int p[3] = { low[0] / 2, low[1] / 2, low[2] / 2 };
        return lod_edge_vertex(c, p, a);
    }
    return lod_fine_vertex(c, low, a);
}

/* ---- transition cells ---------------------------------------------------------------------- */

typedef struct lod_segments {
    uint32_t from[LOD_MAX_SEGMENTS], to[LOD_MAX_SEGMENTS];
    int count;
} lod_segments;

/* The rule on a convex polygon given counter-clockwise seen from outside the cell: each run of
 * inside samples is cut off by a segment from the crossing entering it to the one leaving it. */
static void lod_contour_polygon(lod_chunk *c, const int (*points)[3], int n, lod_segments *out) {
    bool inside[12];
    for (int k = 0; k < n; k++) inside[k] = lod_value(c, points[k]) > 0.0f;
    for (int k = 0; k < n; k++) {
        int k1 = (k + 1) % n;
        if (inside[k] || !inside[k1]) continue;   /* not entering a run */
        int m = k1;
        while (inside[(m + 1) % n]) m = (m + 1) % n;
        int m1 = (m + 1) % n;
        out->from[out->count] = lod_piece_vertex(c, points[k], points[k1]);
        out->to[out->count] = lod_piece_vertex(c, points[m], points[m1]);
        out->count++;
    }
}

static void lod_reverse(int (*points)[3], int n) {
    for (int i = 0, j = n - 1; i < j; i++, j--)
        for (int a = 0; a < 3; a++) {
            int t = points[i][a];
            points[i][a] = points[j][a], points[j][a] = t;
        }
}

/* Face (axis a, side sd) of the cell at coarse sample p. */
static void lod_cell_face(lod_chunk *c, const int p[3], int a, int sd, lod_segments *out) {
    int u, w;
    other_axes(a, &u, &w);
    /* (u, w) cycle (0,0) (1,0) (1,1) (0,1) is counter-clockwise seen from +a for a = x, z and
     * from −a for a = y (x × z = −y). */
    bool reverse = (sd == 1) == (a == 1);
    int base[3] = { 2 * p[0], 2 * p[1], 2 * p[2] };
    base[a] += 2 * sd;
    static const int cycle[4][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 1 } };
    int q = p[a] + sd;
    if ((q == 1 || q == LOD_CELLS + 1) && c->subdivided[a][q != 1]) {
        for (int sub = 0; sub < 4; sub++) {   /* four fine faces */
            int points[4][3];
            for (int k = 0; k < 4; k++) {
                memcpy(points[k], base, sizeof base);
                points[k][u] += (sub & 1) + cycle[k][0];
                points[k][w] += (sub >> 1) + cycle[k][1];
            }
            if (reverse) lod_reverse(points, 4);
            lod_contour_polygon(c, (const int(*)[3])points, 4, out);
        }
        return;
    }
    int points[8][3], n = 0;
    for (int k = 0; k < 4; k++) {
        int corner[3], next[3];
        memcpy(corner, base, sizeof base);
        corner[u] += 2 * cycle[k][0], corner[w] += 2 * cycle[k][1];
        memcpy(next, base, sizeof base);
        next[u] += 2 * cycle[(k + 1) % 4][0], next[w] += 2 * cycle[(k + 1) % 4][1];
        memcpy(points[n++], corner, sizeof corner);
        int axis = corner[u] != next[u] ? u : w;
        int low[3] = { corner[0] / 2, corner[1] / 2, corner[2] / 2 };
        if (next[axis] < corner[axis]) low[axis]--;
        if (lod_edge_split(c, axis, low)) {
            for (int k2 = 0; k2 < 3; k2++) points[n][k2] = (corner[k2] + next[k2]) / 2;
            n++;
        }
    }
    if (reverse) lod_reverse(points, n);
    lod_contour_polygon(c, (const int(*)[3])points, n, out);
}

static void lod_emit(terrain__mesh_builder *b, uint32_t i0, uint32_t i1, uint32_t i2) {
    b->indices = core_grow(b->indices, &b->index_capacity, b->index_count + 3, sizeof *b->indices);
    b->indices[b->index_count++] = i0;
    b->indices[b->index_count++] = i1;
    b->indices[b->index_count++] = i2;
}

static uint32_t lod_centroid(terrain__mesh_builder *b, const uint32_t *loop, int n) {
    b->vertices = core_grow(b->vertices, &b->vertex_capacity, b->vertex_count + 1, sizeof *b->vertices);
    terrain_vertex *v = &b->vertices[b->vertex_count];
    float p[3] = { 0, 0, 0 }, nrm[3] = { 0, 0, 0 };
    for (int k = 0; k < n; k++)
        for (int a = 0; a < 3; a++) p[a] += b->vertices[loop[k]].position[a], nrm[a] += b->vertices[loop[k]].normal[a];
    float length = sqrtf(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    for (int a = 0; a < 3; a++) {
        v->position[a] = p[a] / (float)n;
        v->normal[a] = length > 0.0f ? nrm[a] / length : (a == 1 ? 1.0f : 0.0f);
    }
    v->weights[0] = 255, v->weights[1] = v->weights[2] = v->weights[3] = 0;
    return (uint32_t)b->vertex_count++;
}

static void lod_transition_cell(lod_chunk *c, const int p[3]) {
    lod_segments s = { .count = 0 };
    for (int a = 0; a < 3; a++)
        for (int sd = 0; sd < 2; sd++) lod_cell_face(c, p, a, sd, &s);
    bool used[LOD_MAX_SEGMENTS] = { false };
    for (int first = 0; first < s.count; first++) {
        if (used[first]) continue;
        uint32_t loop[LOD_MAX_SEGMENTS];
        int n = 0;
        for (int at = first; at >= 0 && !used[at];) {
            used[at] = true;
            loop[n++] = s.from[at];
            int next = -1;
            for (int k = 0; k < s.count; k++)
                if (!used[k] && s.from[k] == s.to[at]) next = k;
            at = next;
        }
        if (n < 3) continue;   /* a loop of 2 along a split edge: the cells across carry it */
        if (n == 3) {
            lod_emit(&c->b, loop[0], loop[1], loop[2]);
            continue;
        }
        uint32_t centre = lod_centroid(&c->b, loop, n);
        for (int k = 0; k < n; k++) lod_emit(&c->b, centre, loop[k], loop[(k + 1) % n]);
    }
}

/* The corner configuration read corner by corner: the reference the sliding one is tested
 * against (terrain__mesh_chunk_reference). */
static unsigned lod_cell_config(const lod_chunk *c, const int p[3]) {
    unsigned config = 0;
    for (int v = 0; v < 8; v++) {
        int q[3] = { p[0] + (v & 1), p[1] + ((v >> 1) & 1), p[2] + ((v >> 2) & 1) };
        config |= (unsigned)(c->values[lod_index(q)] > 0.0f) << v;
    }
    return config;
}

/* A cell without split edges, of corner configuration `config` (not 0 or 0xff): the case
 * table, its edges' vertices made on first use (so in the order the cells reach them). */
static void lod_table_cell(lod_chunk *c, const int p[3], const terrain__mc_case *cell) {
    for (int t = 0; t < cell->triangle_count; t++) {
        uint32_t ids[3];
        for (int k = 0; k < 3; k++) {
            int e = cell->edges[t][k], corner = terrain__mc_edge_corners[e][0];
            int q[3] = { p[0] + (corner & 1), p[1] + ((corner >> 1) & 1), p[2] + ((corner >> 2) & 1) };
            ids[k] = lod_edge_vertex(c, q, e / 4);
        }
        lod_emit(&c->b, ids[0], ids[1], ids[2]);
    }
}

static bool lod_cell_is_transition(const lod_chunk *c, const int p[3]) {
    for (int a = 0; a < 3; a++) {
        int u, w;
        other_axes(a, &u, &w);
        for (int m = 0; m < 4; m++) {
            int q[3] = { p[0], p[1], p[2] };
            q[u] += m & 1, q[w] += m >> 1;
            if (lod_edge_split(c, a, q)) return true;
        }
    }
    return false;
}

/* Whether every sample a transition cell's faces could read has the same sign: the 8 coarse
 * corners and all 3 × 3 fine points of each sampled chunk face the cell touches (from every such
 * face, so a point on two faces is checked in both). Then every face's walk finds no run to cut
 * off, the cell draws nothing and creates no vertex, and skipping it changes no output. Most
 * border cells are all solid or all air; this is what keeps their cost near the table cells'. */
static bool lod_transition_cell_empty(const lod_chunk *c, const int p[3]) {
    const bool inside = c->values[lod_index(p)] > 0.0f;
    for (int v = 1; v < 8; v++) {
        int q[3] = { p[0] + (v & 1), p[1] + ((v >> 1) & 1), p[2] + ((v >> 2) & 1) };
        if ((c->values[lod_index(q)] > 0.0f) != inside) return false;
    }
    for (int f = 0; f < 6; f++) {
        int a = f / 2, u, w;
        if (!c->faces[f].sampled || p[a] != (f % 2 ? LOD_CELLS : 1)) continue;
        other_axes(a, &u, &w);
        const float *values = c->faces[f].field.values;
        for (int dw = 0; dw <= 2; dw++) {
            const float *row = values + (size_t)(2 * p[w] - 2 + dw) * LOD_FINE + (size_t)(2 * p[u] - 2);
            if ((row[0] > 0.0f) != inside || (row[1] > 0.0f) != inside || (row[2] > 0.0f) != inside) return false;
        }
    }
    return true;
}

/* ---- the chunk ----------------------------------------------------------------------------- */

static bool lod_fine(uint32_t mask, int dx, int dy, int dz) { return (mask & terrain_lod_neighbour_bit(dx, dy, dz)) != 0; }

static void lod_rules(lod_chunk *c, uint32_t mask) {
    for (int a = 0; a < 3; a++) {
        int u, w;
        other_axes(a, &u, &w);
        for (int su = -1; su <= 1; su++)
            for (int sw = -1; sw <= 1; sw++) {
                /* The regions sharing an edge at sides (su, sw): offsets 0 along a, 0 or the side
                 * along u and w, not the chunk itself. */
                bool split = false;
                for (int du = 0; du <= 1; du++)
                    for (int dw = 0; dw <= 1; dw++) {
                        int d[3] = { 0, 0, 0 };
                        d[u] = du * su, d[w] = dw * sw;
                        if (d[u] || d[w]) split |= lod_fine(mask, d[0], d[1], d[2]);
                    }
                c->split[a][su + 1][sw + 1] = split;
            }
        for (int sd = 0; sd < 2; sd++) {
            int d[3] = { 0, 0, 0 };
            d[a] = sd ? 1 : -1;
            c->subdivided[a][sd] = lod_fine(mask, d[0], d[1], d[2]);
        }
    }
}

static bool lod_mesh_transitions(terrain__field_sampler sample, void *user, terrain_world *weights_world,
                                 const int64_t first[3], int level, uint32_t mask, float max_error, bool reference,
                                 terrain_mesh *out) {
    const int64_t step = (int64_t)1 << level, half = step / 2;
    lod_chunk c = { .fine_spacing = (float)half * TERRAIN_COLUMN_SIZE };
    lod_rules(&c, mask);
    terrain_field field;
    terrain_field_desc desc = { .size = { LOD_SAMPLES, LOD_SAMPLES, LOD_SAMPLES }, .step = (int)step };
    for (int a = 0; a < 3; a++) desc.first[a] = first[a] - step;
    if (!sample(user, &desc, &field)) return false;
    bool ok = true;
    /* A chunk face's plane is sampled on the fine grid when some finer region touches it. */
    for (int f = 0; f < 6 && ok; f++) {
        int a = f / 2, sd = f % 2, u, w;
        other_axes(a, &u, &w);
        bool touched = false;
        for (int dz = -1; dz <= 1; dz++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int d[3] = { dx, dy, dz };
                    if (d[a] == (sd ? 1 : -1)) touched |= lod_fine(mask, dx, dy, dz);
                }
        if (!touched) continue;
        terrain_field_desc face = { .step = (int)half };
        face.size[a] = 1, face.size[u] = LOD_FINE, face.size[w] = LOD_FINE;
        face.first[a] = first[a] + sd * LOD_CELLS * step;
        face.first[u] = first[u], face.first[w] = first[w];
        lod_face *lf = &c.faces[f];
        ok = sample(user, &face, &lf->field);
        if (!ok) break;
        lf->sampled = true;
        for (int k = 0; k < 2; k++) {
            lf->vertex[k] = core_alloc((size_t)LOD_FINE * LOD_FINE * sizeof(uint32_t));
            memset(lf->vertex[k], 0xff, (size_t)LOD_FINE * LOD_FINE * sizeof(uint32_t));
        }
    }
    const size_t samples = (size_t)LOD_SAMPLES * LOD_SAMPLES * LOD_SAMPLES;
    if (ok) {
        c.values = field.values;
        c.b = (terrain__mesh_builder){ .field = &field, .n = { LOD_SAMPLES, LOD_SAMPLES, LOD_SAMPLES },
                                       .lo = { 1, 1, 1 }, .hi = { LOD_CELLS + 1, LOD_CELLS + 1, LOD_CELLS + 1 },
                                       .slice = (size_t)LOD_SAMPLES * LOD_SAMPLES };
        for (int a = 0; a < 3; a++) {
            c.edges[a] = core_alloc(samples * sizeof(uint32_t));
            memset(c.edges[a], 0xff, samples * sizeof(uint32_t));
        }
        const terrain__mc_case *table = terrain__mc_table();
        const size_t row = LOD_SAMPLES, slice = (size_t)LOD_SAMPLES * LOD_SAMPLES;
        for (int z = 1; z <= LOD_CELLS; z++)
            for (int y = 1; y <= LOD_CELLS; y++) {
                /* The corner signs slide along x as in terrain_mesh.c: bits of the cell's x = 0
                 * side y0z0 → 0, y1z0 → 2, y0z1 → 4, y1z1 → 6, the x = 1 side one bit up. */
                const float *v = c.values + lod_index((const int[3]){ 1, y, z });
                unsigned side = (v[0] > 0.0f) | (v[row] > 0.0f) << 2 | (v[slice] > 0.0f) << 4 | (v[row + slice] > 0.0f) << 6;
                for (int x = 1; x <= LOD_CELLS; x++) {
                    v++;
                    unsigned next = (v[0] > 0.0f) | (v[row] > 0.0f) << 2 | (v[slice] > 0.0f) << 4 | (v[row + slice] > 0.0f) << 6;
                    unsigned config = side | next << 1;
                    side = next;
                    int p[3] = { x, y, z };
                    bool border = x == 1 || y == 1 || z == 1 || x == LOD_CELLS || y == LOD_CELLS || z == LOD_CELLS;
                    if (reference) config = lod_cell_config(&c, p);
                    if (border && lod_cell_is_transition(&c, p)) {
                        if (reference || !lod_transition_cell_empty(&c, p)) lod_transition_cell(&c, p);
                    } else if (config != 0 && config != 0xff) {
                        lod_table_cell(&c, p, &table[config]);
                    }
                }
            }
        for (int a = 0; a < 3; a++) core_free(c.edges[a], samples * sizeof(uint32_t));
        ok = terrain__mesh_finish(&c.b, &(terrain_mesh_desc){ .world = weights_world, .max_error = max_error },
                                  field.origin, out);
        if (ok) memcpy(out->origin, field.origin, sizeof out->origin);
    }
    for (int f = 0; f < 6; f++) {
        if (!c.faces[f].sampled) continue;
        terrain_field_free(&c.faces[f].field);
        for (int k = 0; k < 2; k++) core_free(c.faces[f].vertex[k], (size_t)LOD_FINE * LOD_FINE * sizeof(uint32_t));
    }
    terrain_field_free(&field);
    return ok;
}

static bool lod_mesh_chunk(terrain__field_sampler sample, void *user, terrain_world *weights_world, int64_t x,
                           int64_t y, int64_t z, const terrain_lod_desc *lod_in, bool reference, terrain_mesh *out) {
    const terrain_lod_desc lod = lod_in ? *lod_in : (terrain_lod_desc){ 0 };
    memset(out, 0, sizeof *out);
    if (lod.level < 0 || lod.level > LOD_MAX_LEVEL || (lod.finer_neighbours >> 26) != 0 ||
        (lod.level == 0 && lod.finer_neighbours != 0)) {
        core_log_error("terrain", "mesh chunk: bad level %d or finer-neighbour mask 0x%x", lod.level,
                   (unsigned)lod.finer_neighbours);
        return false;
    }
    const int64_t step = (int64_t)1 << lod.level, coord[3] = { x, y, z };
    int64_t first[3];
    for (int a = 0; a < 3; a++) {
        if (coord[a] < -((int64_t)1 << 40) || coord[a] > ((int64_t)1 << 40)) {
            core_log_error("terrain", "mesh chunk: coordinate %lld is too far out", (long long)coord[a]);
            return false;
        }
        first[a] = coord[a] * LOD_CELLS * step;
    }
    /* Corner neighbours share a point only: they change nothing. */
    uint32_t mask = lod.finer_neighbours;
    for (int dz = -1; dz <= 1; dz += 2)
        for (int dy = -1; dy <= 1; dy += 2)
            for (int dx = -1; dx <= 1; dx += 2) mask &= ~terrain_lod_neighbour_bit(dx, dy, dz);
    if (mask) return lod_mesh_transitions(sample, user, weights_world, first, lod.level, mask, lod.max_error, reference, out);
    /* No seam to close: the plain pair (at level 0 exactly the example of terrain.h). */
    terrain_field field;
    terrain_field_desc desc = { .size = { LOD_SAMPLES, LOD_SAMPLES, LOD_SAMPLES }, .step = (int)step };
    for (int a = 0; a < 3; a++) desc.first[a] = first[a] - step;
    if (!sample(user, &desc, &field)) return false;
    bool ok = terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = weights_world, .apron = 1, .max_error = lod.max_error }, out);
    terrain_field_free(&field);
    return ok;
}

bool terrain__mesh_chunk_with(terrain__field_sampler sample, void *user, terrain_world *weights_world, int64_t x,
                              int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out) {
    return lod_mesh_chunk(sample, user, weights_world, x, y, z, lod, false, out);
}

bool terrain__mesh_chunk_reference(terrain__field_sampler sample, void *user, terrain_world *weights_world, int64_t x,
                                   int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out) {
    return lod_mesh_chunk(sample, user, weights_world, x, y, z, lod, true, out);
}

static bool lod_world_sample(void *user, const terrain_field_desc *desc, terrain_field *out) {
    return terrain_field_sample(user, desc, out);
}

bool terrain_mesh_chunk(terrain_world *world, int64_t x, int64_t y, int64_t z, const terrain_lod_desc *lod,
                        terrain_mesh *out) {
    return terrain__mesh_chunk_with(lod_world_sample, world, world, x, y, z, lod, out);
}
