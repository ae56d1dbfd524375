/* distance_test.h — distances from a point to a segment and to a triangle, for the tests that
 * check how far a surface or a sweep strays (worked out here, apart from the code under test). */
#ifndef TERRAIN_DISTANCE_TEST_H
#define TERRAIN_DISTANCE_TEST_H

#include <math.h>
#include <stdbool.h>

static inline double point_segment_distance(const double p[3], const double a[3], const double b[3]) {
    double d[3], w[3], dd = 0.0, wd = 0.0;
    for (int e = 0; e < 3; e++) d[e] = b[e] - a[e], w[e] = p[e] - a[e], dd += d[e] * d[e], wd += w[e] * d[e];
    double t = dd > 0.0 ? fmin(fmax(wd / dd, 0.0), 1.0) : 0.0, e2 = 0.0;
    for (int e = 0; e < 3; e++) e2 += (w[e] - t * d[e]) * (w[e] - t * d[e]);
    return sqrt(e2);
}

/* To the triangle's plane where p projects inside the triangle (on the inner side of all three
 * edges, seen along the normal), else to the nearest edge. */
static inline double point_triangle_distance(const double p[3], const double *corner[3]) {
    double e0[3], e1[3], n[3], ap[3];
    for (int k = 0; k < 3; k++) e0[k] = corner[1][k] - corner[0][k], e1[k] = corner[2][k] - corner[0][k], ap[k] = p[k] - corner[0][k];
    n[0] = e0[1] * e1[2] - e0[2] * e1[1], n[1] = e0[2] * e1[0] - e0[0] * e1[2], n[2] = e0[0] * e1[1] - e0[1] * e1[0];
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    bool inside = nn > 0.0;
    for (int k = 0; k < 3 && inside; k++) {
        const double *a = corner[k], *b = corner[(k + 1) % 3];
        double edge[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, to[3] = { p[0] - a[0], p[1] - a[1], p[2] - a[2] };
        double side = (edge[1] * to[2] - edge[2] * to[1]) * n[0] + (edge[2] * to[0] - edge[0] * to[2]) * n[1] +
                      (edge[0] * to[1] - edge[1] * to[0]) * n[2];
        inside = side >= 0.0;
    }
    if (inside) return fabs(ap[0] * n[0] + ap[1] * n[1] + ap[2] * n[2]) / sqrt(nn);
    return fmin(point_segment_distance(p, corner[0], corner[1]),
                fmin(point_segment_distance(p, corner[1], corner[2]), point_segment_distance(p, corner[2], corner[0])));
}

#endif
