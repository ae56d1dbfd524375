/* terrain_mesh_tables.c — the marching-cubes case table, derived from one rule instead of typed
 * in (a typo in a 256-row table is a hole in the terrain).
 *
 * Numbering. Corner v = x | y << 1 | z << 2 of the cell. Edge 4·a + m runs along axis a from
 * the corner with bit a clear to the one with it set; m packs the other two axes' bits, lower
 * axis first (x-edges: m = y + 2z; y-edges: m = x + 2z; z-edges: m = x + 2y). A corner is
 * "inside" when f > 0.
 *
 * The rule. On each face of the cell the iso-line is drawn from the face's four signs alone:
 * one segment across the face when 1, 2 adjacent or 3 corners are inside; on an ambiguous face
 * (two diagonal corners inside, two outside) two segments, each cutting off one inside corner:
 * inside corners are always kept apart, outside ones joined across the face. Two cells that share
 * a face see the same four signs, so they draw the same segments on it and the surface has no
 * cracks. Each segment is oriented so that, seen from outside the cell, the inside lies on its
 * right; each crossed edge then starts one segment and ends one, the segments chain into closed
 * loops, and every loop, triangulated, is a disk whose triangles run counter-clockwise seen from
 * the outside (f ≤ 0, the air).
 *
 * Triangulating a loop: any triangulation is a disk, but a diagonal between two vertices on the
 * same cell face could also be drawn by the cell across that face (four triangles on one edge,
 * and a flat triangle inside the face). So the diagonals must join vertices that share no face;
 * a diagonal then belongs to this cell alone and every mesh edge has exactly two triangles: a
 * face segment one in each of the two cells beside the face, a diagonal two in its own cell.
 * Among the triangulations that obey this we take the one whose triangles' edge-midpoint
 * geometry is least skinny (the largest smallest angle, on the edges' midpoints), which is the
 * fan the hand-written tables use for the simple cases.
 */
#include "terrain/data/terrain_data_internal.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

static terrain__mc_case mc_table[256];
static pthread_once_t mc_once = PTHREAD_ONCE_INIT;

const uint8_t terrain__mc_edge_corners[12][2] = {
    { 0, 1 }, { 2, 3 }, { 4, 5 }, { 6, 7 },      /* x */
    { 0, 2 }, { 1, 3 }, { 4, 6 }, { 5, 7 },      /* y */
    { 0, 4 }, { 1, 5 }, { 2, 6 }, { 3, 7 },      /* z */
};

static int mc_edge_of(int a, int b) {
    for (int e = 0; e < 12; e++) {
        if ((terrain__mc_edge_corners[e][0] == a && terrain__mc_edge_corners[e][1] == b) ||
            (terrain__mc_edge_corners[e][0] == b && terrain__mc_edge_corners[e][1] == a))
            return e;
    }
    return -1;
}

static void mc_corner_position(int v, double p[3]) {
    p[0] = v & 1, p[1] = (v >> 1) & 1, p[2] = (v >> 2) & 1;
}

static void mc_edge_midpoint(int e, double p[3]) {
    double a[3], b[3];
    mc_corner_position(terrain__mc_edge_corners[e][0], a);
    mc_corner_position(terrain__mc_edge_corners[e][1], b);
    for (int i = 0; i < 3; i++) p[i] = 0.5 * (a[i] + b[i]);
}

/* Faces as bit masks over the 6 faces (axis·2 + side) an edge lies on. */
static unsigned mc_edge_faces(int e) {
    int axis = e / 4, m = e % 4;
    int u = axis == 0 ? 1 : 0, w = axis == 2 ? 1 : 2;   /* the other two axes, lower first */
    return (1u << (u * 2 + (m & 1))) | (1u << (w * 2 + (m >> 1)));
}

/* Appends the oriented segment a → b (edges) whose inside side holds the point `inside`, on
 * the face with outward normal `normal`. The inside is on the segment's right seen from the
 * outside: normal · ((b − a) × (inside − a)) < 0. */
static void mc_add_segment(int next[12], int a, int b, const double inside[3], const double normal[3]) {
    double pa[3], pb[3], d[3], s[3];
    mc_edge_midpoint(a, pa);
    mc_edge_midpoint(b, pb);
    for (int i = 0; i < 3; i++) d[i] = pb[i] - pa[i], s[i] = inside[i] - pa[i];
    double cross[3] = { d[1] * s[2] - d[2] * s[1], d[2] * s[0] - d[0] * s[2], d[0] * s[1] - d[1] * s[0] };
    double side = normal[0] * cross[0] + normal[1] * cross[1] + normal[2] * cross[2];
    if (side > 0) {
        int t = a;
        a = b, b = t;
    }
    next[a] = b;
}

static void mc_face_segments(int config, int axis, int side, int next[12]) {
    int u = axis == 0 ? 1 : 0, w = axis == 2 ? 1 : 2;
    int corners[4];
    static const int cycle[4][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 1 } };
    for (int q = 0; q < 4; q++) corners[q] = (side << axis) | (cycle[q][0] << u) | (cycle[q][1] << w);
    double normal[3] = { 0, 0, 0 };
    normal[axis] = side ? 1.0 : -1.0;
    int inside[4], count = 0;
    for (int q = 0; q < 4; q++) count += inside[q] = (config >> corners[q]) & 1;
    if (count == 0 || count == 4) return;
    if (count == 2 && inside[0] == inside[2]) {
        /* Ambiguous: cut off each inside corner on its own. */
        for (int q = 0; q < 4; q++) {
            if (!inside[q]) continue;
            double p[3];
            mc_corner_position(corners[q], p);
            mc_add_segment(next, mc_edge_of(corners[q], corners[(q + 3) % 4]),
                           mc_edge_of(corners[q], corners[(q + 1) % 4]), p, normal);
        }
        return;
    }
    int crossed[2], n = 0;
    double centroid[3] = { 0, 0, 0 };
    for (int q = 0; q < 4; q++) {
        int r = (q + 1) % 4;
        if (inside[q] != inside[r]) crossed[n++] = mc_edge_of(corners[q], corners[r]);
        if (inside[q]) {
            double p[3];
            mc_corner_position(corners[q], p);
            for (int i = 0; i < 3; i++) centroid[i] += p[i] / count;
        }
    }
    mc_add_segment(next, crossed[0], crossed[1], centroid, normal);
}

/* ---- triangulating a loop ------------------------------------------------------------------ */

typedef struct mc_triangulation {
    int triangles[12][3];
    int count;
    double quality;           /* smallest angle, radians */
} mc_triangulation;

static bool mc_diagonal_allowed(int a, int b) { return (mc_edge_faces(a) & mc_edge_faces(b)) == 0; }

static double mc_smallest_angle(int a, int b, int c) {
    double p[3][3];
    mc_edge_midpoint(a, p[0]);
    mc_edge_midpoint(b, p[1]);
    mc_edge_midpoint(c, p[2]);
    double smallest = M_PI;
    for (int k = 0; k < 3; k++) {
        const double *o = p[k], *u = p[(k + 1) % 3], *v = p[(k + 2) % 3];
        double du[3], dv[3], dot = 0, lu = 0, lv = 0;
        for (int i = 0; i < 3; i++) {
            du[i] = u[i] - o[i], dv[i] = v[i] - o[i];
            dot += du[i] * dv[i], lu += du[i] * du[i], lv += dv[i] * dv[i];
        }
        double angle = acos(fmax(-1.0, fmin(1.0, dot / sqrt(lu * lv))));
        if (angle < smallest) smallest = angle;
    }
    return smallest;
}

/* Best triangulation of the polygon loop[first … last] (inclusive, in order) whose chord
 * (first, last) is already an edge; exhaustive (loops have at most 12 vertices, the cases are
 * computed once). */
static bool mc_triangulate(const int *loop, int first, int last, mc_triangulation *best) {
    best->count = 0;
    best->quality = M_PI;
    if (last - first < 2) return true;
    bool found = false;
    for (int apex = first + 1; apex < last; apex++) {
        /* Triangle (first, apex, last); its sides other than (first, last) are loop edges or
         * diagonals that must be allowed. */
        if (apex - first > 1 && !mc_diagonal_allowed(loop[first], loop[apex])) continue;
        if (last - apex > 1 && !mc_diagonal_allowed(loop[apex], loop[last])) continue;
        mc_triangulation left, right;
        if (!mc_triangulate(loop, first, apex, &left) || !mc_triangulate(loop, apex, last, &right)) continue;
        double quality = mc_smallest_angle(loop[first], loop[apex], loop[last]);
        if (left.count && left.quality < quality) quality = left.quality;
        if (right.count && right.quality < quality) quality = right.quality;
        if (found && quality <= best->quality + 1e-12) continue;
        found = true;
        best->count = 0;
        best->quality = quality;
        for (int t = 0; t < left.count; t++) memcpy(best->triangles[best->count++], left.triangles[t], sizeof left.triangles[t]);
        best->triangles[best->count][0] = loop[first];
        best->triangles[best->count][1] = loop[apex];
        best->triangles[best->count][2] = loop[last];
        best->count++;
        for (int t = 0; t < right.count; t++) memcpy(best->triangles[best->count++], right.triangles[t], sizeof right.triangles[t]);
    }
    return found;
}

/* Every triangulation of a polygon has exactly one triangle on its edge (loop[0], loop[n−1]),
 * so the recursion from that chord sees them all. */
static bool mc_triangulate_loop(const int *loop, int n, mc_triangulation *best) {
    return mc_triangulate(loop, 0, n - 1, best);
}

static void mc_build_case(int config, terrain__mc_case *out) {
    int next[12];
    for (int e = 0; e < 12; e++) next[e] = -1;
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) mc_face_segments(config, axis, side, next);
    out->triangle_count = 0;
    out->loop_count = 0;
    bool seen[12] = { false };
    for (int e = 0; e < 12; e++) {
        if (next[e] < 0 || seen[e]) continue;
        int loop[12], n = 0;
        for (int v = e; !seen[v]; v = next[v]) {
            seen[v] = true;
            loop[n++] = v;
        }
        mc_triangulation t;
        if (!mc_triangulate_loop(loop, n, &t)) {
            out->triangle_count = 0xff;   /* reported by terrain__mc_check; never expected */
            return;
        }
        out->loop_count++;
        for (int i = 0; i < t.count; i++) {
            for (int k = 0; k < 3; k++) out->edges[out->triangle_count][k] = (uint8_t)t.triangles[i][k];
            out->triangle_count++;
        }
    }
    uint16_t mask = 0;
    for (int e = 0; e < 12; e++)
        if (next[e] >= 0) mask |= (uint16_t)(1u << e);
    out->edge_mask = mask;
}

static void mc_build_table(void) {
    for (int config = 0; config < 256; config++) mc_build_case(config, &mc_table[config]);
}

const terrain__mc_case *terrain__mc_table(void) {
    pthread_once(&mc_once, mc_build_table);
    return mc_table;
}

