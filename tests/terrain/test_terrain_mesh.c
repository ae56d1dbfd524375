/* Marching cubes: invariants of the mesh rather than examples. Closed shapes must come out
 * watertight (every edge shared by exactly two triangles, in opposite directions) with the
 * Euler characteristic of their topology (sphere 2, torus 0), the analytic area within a few
 * per cent, and normals and winding facing the air; every cell configuration and every pair of
 * neighbouring configurations must close; adjacent chunks must agree on their shared border. */
#include "../engine/test.h"
#include "core/core.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"
#include "jobs/jobs.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- fields made by the test -------------------------------------------------------------- */

typedef float (*field_fn)(const double p[3], const void *user);

static terrain_field field_make(int nx, int ny, int nz, field_fn fn, const void *user) {
    terrain_field f = { .nx = nx, .ny = ny, .nz = nz, .spacing = 1.0f };
    f.values = core_alloc((size_t)nx * ny * nz * sizeof *f.values);
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++)
            for (int x = 0; x < nx; x++) {
                double p[3] = { x, y, z };
                f.values[((size_t)z * ny + y) * nx + x] = fn(p, user);
            }
    return f;
}

typedef struct sphere { double centre[3], radius; } sphere;
static float sphere_fn(const double p[3], const void *user) {
    const sphere *s = user;
    double dx = p[0] - s->centre[0], dy = p[1] - s->centre[1], dz = p[2] - s->centre[2];
    return (float)(s->radius - sqrt(dx * dx + dy * dy + dz * dz));   /* > 0 inside */
}

typedef struct torus { double centre[3], major, minor; } torus;   /* around the y axis */
static float torus_fn(const double p[3], const void *user) {
    const torus *t = user;
    double dx = p[0] - t->centre[0], dy = p[1] - t->centre[1], dz = p[2] - t->centre[2];
    double ring = sqrt(dx * dx + dz * dz) - t->major;
    return (float)(t->minor - sqrt(ring * ring + dy * dy));
}

/* ---- mesh invariants ------------------------------------------------------------------------ */

static int compare_u64(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

typedef struct mesh_topology {
    bool watertight;          /* every directed edge once, its reverse once */
    int64_t euler;            /* V − E + F */
    int degenerate;           /* triangles repeating an index */
    int unused_vertices;
} mesh_topology;

static mesh_topology mesh_check(const terrain_mesh *mesh) {
    mesh_topology t = { .watertight = true };
    size_t count = mesh->index_count;
    uint64_t *directed = malloc((count ? count : 1) * sizeof *directed);
    for (size_t i = 0; i < count; i += 3) {
        for (int k = 0; k < 3; k++) {
            uint64_t a = mesh->indices[i + k], b = mesh->indices[i + (k + 1) % 3];
            directed[i + k] = a << 32 | b;
        }
        if (mesh->indices[i] == mesh->indices[i + 1] || mesh->indices[i + 1] == mesh->indices[i + 2] ||
            mesh->indices[i] == mesh->indices[i + 2])
            t.degenerate++;
    }
    qsort(directed, count, sizeof *directed, compare_u64);
    for (size_t i = 0; i < count; i++) {
        if (i > 0 && directed[i] == directed[i - 1]) t.watertight = false;   /* same direction twice */
        uint64_t reverse = (directed[i] & 0xffffffffu) << 32 | directed[i] >> 32;
        if (!bsearch(&reverse, directed, count, sizeof *directed, compare_u64)) t.watertight = false;
    }
    bool *used = calloc(mesh->vertex_count ? mesh->vertex_count : 1, 1);
    for (size_t i = 0; i < count; i++) used[mesh->indices[i]] = true;
    for (uint32_t v = 0; v < mesh->vertex_count; v++) t.unused_vertices += !used[v];
    t.euler = (int64_t)mesh->vertex_count - (int64_t)(count / 2) + (int64_t)(count / 3);
    free(used);
    free(directed);
    return t;
}

static void triangle_normal(const terrain_mesh *mesh, size_t i, double n[3], double centroid[3]) {
    const float *p[3];
    for (int k = 0; k < 3; k++) p[k] = mesh->vertices[mesh->indices[i + k]].position;
    double u[3], v[3];
    for (int a = 0; a < 3; a++) {
        u[a] = (double)p[1][a] - p[0][a], v[a] = (double)p[2][a] - p[0][a];
        centroid[a] = ((double)p[0][a] + p[1][a] + p[2][a]) / 3.0;
    }
    n[0] = u[1] * v[2] - u[2] * v[1], n[1] = u[2] * v[0] - u[0] * v[2], n[2] = u[0] * v[1] - u[1] * v[0];
}

static terrain_mesh mesh_of(const terrain_field *f, int apron) {
    terrain_mesh mesh;
    cr_assert(terrain_mesh_build(f, &(terrain_mesh_desc){ .apron = apron }, &mesh));
    return mesh;
}

/* ---- closed shapes ----------------------------------------------------------------------------- */

Test(terrain_mesh, sphere_is_watertight_with_euler_2_and_its_area) {
    const double radii[] = { 3.3, 7.0, 12.4 };
    for (size_t r = 0; r < CORE_COUNTOF(radii); r++) {
        sphere s = { { 15.3, 16.1, 14.7 }, radii[r] };
        terrain_field f = field_make(32, 33, 31, sphere_fn, &s);
        terrain_mesh mesh = mesh_of(&f, 0);
        mesh_topology t = mesh_check(&mesh);
        cr_expect(t.watertight, "radius %g", s.radius);
        cr_expect_eq(t.euler, 2, "radius %g: V − E + F = %lld", s.radius, (long long)t.euler);
        cr_expect_eq(t.degenerate, 0);
        cr_expect_eq(t.unused_vertices, 0);
        double area = terrain_mesh_area(&mesh), analytic = 4.0 * M_PI * s.radius * s.radius;
        cr_expect_lt(fabs(area - analytic) / analytic, 0.03, "radius %g: area %g against %g", s.radius, area, analytic);
        /* Vertices on the sphere, normals radial and outward, triangles counter-clockwise from outside. */
        for (uint32_t v = 0; v < mesh.vertex_count; v++) {
            const terrain_vertex *vx = &mesh.vertices[v];
            double d[3], length = 0.0, dot = 0.0;
            for (int a = 0; a < 3; a++) d[a] = vx->position[a] - s.centre[a], length += d[a] * d[a];
            length = sqrt(length);
            for (int a = 0; a < 3; a++) dot += d[a] / length * vx->normal[a];
            cr_expect_lt(fabs(length - s.radius), 0.05, "vertex %u at distance %g", v, length);
            cr_expect_gt(dot, 0.97, "vertex %u normal against the radius: %g", v, dot);
            cr_expect_eq(vx->weights[0], 255, "no world: all bedrock");
        }
        int inward = 0;
        for (size_t i = 0; i < mesh.index_count; i += 3) {
            double n[3], c[3];
            triangle_normal(&mesh, i, n, c);
            inward += n[0] * (c[0] - s.centre[0]) + n[1] * (c[1] - s.centre[1]) + n[2] * (c[2] - s.centre[2]) < 0;
        }
        cr_expect_eq(inward, 0, "radius %g: %d triangles wound inward", s.radius, inward);
        /* Bounds hold every vertex and touch the sphere's extent. */
        for (int a = 0; a < 3; a++) {
            cr_expect_float_eq(mesh.bounds_min[a], s.centre[a] - s.radius, 0.05);
            cr_expect_float_eq(mesh.bounds_max[a], s.centre[a] + s.radius, 0.05);
        }
        terrain_mesh_free(&mesh);
        terrain_field_free(&f);
    }
}

Test(terrain_mesh, torus_is_watertight_with_euler_0_and_its_area) {
    torus tor = { { 17.2, 16.6, 16.9 }, 10.0, 4.0 };
    terrain_field f = field_make(35, 34, 35, torus_fn, &tor);
    terrain_mesh mesh = mesh_of(&f, 0);
    mesh_topology t = mesh_check(&mesh);
    cr_expect(t.watertight);
    cr_expect_eq(t.euler, 0, "V − E + F = %lld", (long long)t.euler);
    double area = terrain_mesh_area(&mesh), analytic = 4.0 * M_PI * M_PI * tor.major * tor.minor;
    cr_expect_lt(fabs(area - analytic) / analytic, 0.03, "area %g against %g", area, analytic);
    for (uint32_t v = 0; v < mesh.vertex_count; v++) {
        /* Outward from the tube's core circle. */
        const float *p = mesh.vertices[v].position, *n = mesh.vertices[v].normal;
        double dx = p[0] - tor.centre[0], dz = p[2] - tor.centre[2], r = sqrt(dx * dx + dz * dz);
        double core[3] = { tor.centre[0] + dx / r * tor.major, tor.centre[1], tor.centre[2] + dz / r * tor.major };
        double out[3] = { p[0] - core[0], p[1] - core[1], p[2] - core[2] };
        double length = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
        cr_expect_gt((out[0] * n[0] + out[1] * n[1] + out[2] * n[2]) / length, 0.95, "vertex %u", v);
    }
    terrain_mesh_free(&mesh);
    terrain_field_free(&f);
}

/* Hollow: a solid block with a spherical air bubble; its walls face into the bubble. */
Test(terrain_mesh, air_bubble_in_solid_faces_inward) {
    sphere s = { { 10.4, 9.8, 10.1 }, 5.5 };
    terrain_field f = field_make(21, 21, 21, sphere_fn, &s);
    for (size_t i = 0; i < (size_t)21 * 21 * 21; i++) f.values[i] = -f.values[i];
    terrain_mesh mesh = mesh_of(&f, 0);
    mesh_topology t = mesh_check(&mesh);
    cr_expect(t.watertight);
    cr_expect_eq(t.euler, 2);
    for (uint32_t v = 0; v < mesh.vertex_count; v++) {
        const float *p = mesh.vertices[v].position, *n = mesh.vertices[v].normal;
        double dot = (p[0] - s.centre[0]) * n[0] + (p[1] - s.centre[1]) * n[1] + (p[2] - s.centre[2]) * n[2];
        cr_expect_lt(dot, 0.0, "vertex %u: normal points to the bubble's centre (the air)", v);
    }
    terrain_mesh_free(&mesh);
    terrain_field_free(&f);
}

/* ---- every configuration -------------------------------------------------------------------- */

Test(terrain_mesh, case_table_is_complete) {
    const terrain__mc_case *table = terrain__mc_table();
    for (int config = 0; config < 256; config++) {
        cr_expect_neq(table[config].triangle_count, 0xff, "config %d", config);
        /* Triangles are exactly the crossed edges, and only those. */
        uint16_t used = 0;
        for (int t = 0; t < table[config].triangle_count; t++)
            for (int k = 0; k < 3; k++) used |= (uint16_t)(1u << table[config].edges[t][k]);
        uint16_t crossed = 0;
        for (int e = 0; e < 12; e++) {
            int a = terrain__mc_edge_corners[e][0], b = terrain__mc_edge_corners[e][1];
            if (((config >> a) & 1) != ((config >> b) & 1)) crossed |= (uint16_t)(1u << e);
        }
        cr_expect_eq(used, crossed, "config %d", config);
        cr_expect_eq(table[config].edge_mask, crossed, "config %d", config);
        cr_expect_eq(table[config].triangle_count == 0, config == 0 || config == 255);
    }
}

/* A small grid with a block of cells in the middle whose corners take the bits of `config`;
 * every other sample is `outside` (so the surface closes inside the grid). */
static terrain_field block_field(int cells[3], uint32_t config, float outside, uint64_t seed) {
    terrain_field f = { .nx = cells[0] + 3, .ny = cells[1] + 3, .nz = cells[2] + 3, .spacing = 1.0f };
    size_t count = (size_t)f.nx * f.ny * f.nz;
    f.values = core_alloc(count * sizeof *f.values);
    for (size_t i = 0; i < count; i++) f.values[i] = outside;
    int bit = 0;
    for (int z = 1; z <= cells[2] + 1; z++)
        for (int y = 1; y <= cells[1] + 1; y++)
            for (int x = 1; x <= cells[0] + 1; x++, bit++) {
                /* Magnitudes vary so vertices do not all sit at edge midpoints. */
                float magnitude = 0.1f + (float)(core_hash_u64(seed * 131 + (uint64_t)bit) % 1000) / 1000.0f;
                f.values[((size_t)z * f.ny + y) * f.nx + x] = ((config >> bit) & 1) ? magnitude : -magnitude;
            }
    return f;
}

Test(terrain_mesh, every_cell_configuration_closes) {
    int cells[3] = { 1, 1, 1 };
    for (uint32_t config = 0; config < 256; config++) {
        for (int polarity = 0; polarity < 2; polarity++) {
            terrain_field f = block_field(cells, config, polarity ? 1.0f : -1.0f, config);
            terrain_mesh mesh = mesh_of(&f, 0);
            mesh_topology t = mesh_check(&mesh);
            cr_expect(t.watertight, "config %u, outside %s", config, polarity ? "solid" : "air");
            cr_expect_eq(t.euler % 2, 0, "config %u", config);
            terrain_mesh_free(&mesh);
            terrain_field_free(&f);
        }
    }
}

/* Two cells side by side along each axis, all 2^12 sign patterns of their 12 corners: every
 * pair of face configurations two neighbouring cells can see. */
Test(terrain_mesh, every_pair_of_neighbouring_cells_closes) {
    int failures = 0;
    for (int axis = 0; axis < 3; axis++) {
        int cells[3] = { 1, 1, 1 };
        cells[axis] = 2;
        for (uint32_t config = 0; config < 4096; config++) {
            for (int polarity = 0; polarity < 2; polarity++) {
                terrain_field f = block_field(cells, config, polarity ? 1.0f : -1.0f, config + 7u * (uint32_t)axis);
                terrain_mesh mesh;
                terrain_mesh_build(&f, &(terrain_mesh_desc){ .no_optimize = true }, &mesh);
                mesh_topology t = mesh_check(&mesh);
                if (!t.watertight || t.degenerate) {
                    if (failures++ < 10) cr_expect(t.watertight, "axis %d config %u polarity %d", axis, config, polarity);
                }
                terrain_mesh_free(&mesh);
                terrain_field_free(&f);
            }
        }
    }
    cr_expect_eq(failures, 0);
}

/* Random fields: smooth value noise at several scales and raw white noise (every ambiguous
 * case), forced to air on the border so every surface is closed. */
static float noise_field_value(uint64_t seed, int x, int y, int z, int scale) {
    /* Trilinear value noise on a lattice of `scale` samples. */
    int cx = x / scale, cy = y / scale, cz = z / scale;
    float fx = (float)(x % scale) / scale, fy = (float)(y % scale) / scale, fz = (float)(z % scale) / scale;
    float corner[8];
    for (int c = 0; c < 8; c++) {
        uint64_t h = core_hash_combine(core_hash_combine(core_hash_combine(seed, (uint64_t)(cx + (c & 1))),
                                                         (uint64_t)(cy + ((c >> 1) & 1))),
                                       (uint64_t)(cz + ((c >> 2) & 1)));
        corner[c] = (float)(h % 2001) / 1000.0f - 1.0f;
    }
    float x0 = corner[0] + fx * (corner[1] - corner[0]), x1 = corner[2] + fx * (corner[3] - corner[2]);
    float x2 = corner[4] + fx * (corner[5] - corner[4]), x3 = corner[6] + fx * (corner[7] - corner[6]);
    float y0 = x0 + fy * (x1 - x0), y1 = x2 + fy * (x3 - x2);
    return y0 + fz * (y1 - y0);
}

Test(terrain_mesh, random_noise_fields_are_watertight) {
    const int scales[] = { 1, 2, 3, 5 };
    int meshes_with_triangles = 0;
    for (uint64_t seed = 1; seed <= 60; seed++) {
        int scale = scales[seed % CORE_COUNTOF(scales)];
        int n = 14 + (int)(seed % 7);
        terrain_field f = { .nx = n, .ny = n + 1, .nz = n - 1, .spacing = 1.0f };
        f.values = core_alloc((size_t)f.nx * f.ny * f.nz * sizeof *f.values);
        for (int z = 0; z < f.nz; z++)
            for (int y = 0; y < f.ny; y++)
                for (int x = 0; x < f.nx; x++) {
                    bool border = x == 0 || y == 0 || z == 0 || x == f.nx - 1 || y == f.ny - 1 || z == f.nz - 1;
                    float value = border ? -1.0f : noise_field_value(seed, x, y, z, scale);
                    /* Every fifth seed: values on a coarse lattice, many exactly 0 (on the surface). */
                    if (seed % 5 == 0) value = roundf(value * 4.0f) / 4.0f;
                    f.values[((size_t)z * f.ny + y) * f.nx + x] = value;
                }
        terrain_mesh mesh;
        cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .no_optimize = seed % 2 == 0 }, &mesh));
        mesh_topology t = mesh_check(&mesh);
        cr_expect(t.watertight, "seed %llu (scale %d)", (unsigned long long)seed, scale);
        cr_expect_eq(t.euler % 2, 0, "seed %llu", (unsigned long long)seed);
        cr_expect_eq(t.unused_vertices, 0, "seed %llu", (unsigned long long)seed);
        for (uint32_t v = 0; v < mesh.vertex_count; v++) {
            const float *nrm = mesh.vertices[v].normal;
            cr_expect_float_eq(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2], 1.0f, 1e-4f);
        }
        meshes_with_triangles += mesh.index_count > 0;
        terrain_mesh_free(&mesh);
        terrain_field_free(&f);
    }
    cr_expect_eq(meshes_with_triangles, 60);
}

/* ---- the edge-based passes against a cell-by-cell walk ------------------------------------ */

/* The mesher works row by row on sign bits (Flying Edges). The reference here walks every cell,
 * takes its triangles from the case table and places each vertex on its grid edge by the
 * documented rule ((index + t)·spacing, t = terrain__mesh_edge_t), with nothing shared with the
 * mesher's passes. The two meshes must hold the same triangles (as position triples, each turned
 * to start at its smallest corner so the winding counts) and one vertex per crossed edge. */
typedef struct ref_triangle { float p[9]; } ref_triangle;

static int compare_triangles(const void *a, const void *b) { return memcmp(a, b, sizeof(ref_triangle)); }

static void canonical_triangle(const float *p0, const float *p1, const float *p2, ref_triangle *out) {
    const float *p[3] = { p0, p1, p2 };
    int first = 0;
    for (int k = 1; k < 3; k++)
        if (memcmp(p[k], p[first], 3 * sizeof(float)) < 0) first = k;
    for (int k = 0; k < 3; k++) memcpy(out->p + 3 * k, p[(first + k) % 3], 3 * sizeof(float));
}

/* The reference's triangles (sorted) and crossed-edge count, for the box apron … n − 1 − apron. */
static ref_triangle *reference_triangles(const terrain_field *f, int apron, size_t *triangle_count, size_t *edges) {
    const int n[3] = { f->nx, f->ny, f->nz };
    const terrain__mc_case *table = terrain__mc_table();
    size_t capacity = 1024, count = 0;
    ref_triangle *out = malloc(capacity * sizeof *out);
    #define REF_VALUE(x, y, z) f->values[((size_t)(z) * n[1] + (y)) * n[0] + (x)]
    for (int z = apron; z < n[2] - 1 - apron; z++)
        for (int y = apron; y < n[1] - 1 - apron; y++)
            for (int x = apron; x < n[0] - 1 - apron; x++) {
                unsigned config = 0;
                for (int c = 0; c < 8; c++) config |= (unsigned)(REF_VALUE(x + (c & 1), y + (c >> 1 & 1), z + (c >> 2)) > 0.0f) << c;
                const terrain__mc_case *cell = &table[config];
                for (int t = 0; t < cell->triangle_count; t++) {
                    float p[3][3];
                    for (int k = 0; k < 3; k++) {
                        int e = cell->edges[t][k], c0 = terrain__mc_edge_corners[e][0], axis = e / 4;
                        int at[3] = { x + (c0 & 1), y + (c0 >> 1 & 1), z + (c0 >> 2) };
                        float f0 = REF_VALUE(at[0], at[1], at[2]);
                        float f1 = REF_VALUE(at[0] + (axis == 0), at[1] + (axis == 1), at[2] + (axis == 2));
                        for (int a = 0; a < 3; a++) p[k][a] = (float)at[a] * f->spacing;
                        p[k][axis] = ((float)at[axis] + terrain__mesh_edge_t(f0, f1)) * f->spacing;
                    }
                    if (count == capacity) out = realloc(out, (capacity *= 2) * sizeof *out);
                    canonical_triangle(p[0], p[1], p[2], &out[count++]);
                }
            }
    /* Crossed edges inside the box: lo … hi samples, edges lo … hi − 1 along theirs (none when
     * an axis has no cell: such a field meshes to nothing). */
    *edges = 0;
    bool cells = n[0] - 1 - 2 * apron > 0 && n[1] - 1 - 2 * apron > 0 && n[2] - 1 - 2 * apron > 0;
    for (int z = apron; cells && z <= n[2] - 1 - apron; z++)
        for (int y = apron; y <= n[1] - 1 - apron; y++)
            for (int x = apron; x <= n[0] - 1 - apron; x++) {
                bool inside = REF_VALUE(x, y, z) > 0.0f;
                if (x < n[0] - 1 - apron && (REF_VALUE(x + 1, y, z) > 0.0f) != inside) (*edges)++;
                if (y < n[1] - 1 - apron && (REF_VALUE(x, y + 1, z) > 0.0f) != inside) (*edges)++;
                if (z < n[2] - 1 - apron && (REF_VALUE(x, y, z + 1) > 0.0f) != inside) (*edges)++;
            }
    #undef REF_VALUE
    qsort(out, count, sizeof *out, compare_triangles);
    *triangle_count = count;
    return out;
}

static void expect_mesh_matches_reference(const terrain_field *f, int apron, const char *what) {
    size_t count, edges;
    ref_triangle *expected = reference_triangles(f, apron, &count, &edges);
    terrain_mesh mesh;
    cr_assert(terrain_mesh_build(f, &(terrain_mesh_desc){ .apron = apron, .no_optimize = true }, &mesh));
    cr_expect_eq(mesh.index_count, count * 3, "%s apron %d: %u indices, the walk %zu", what, apron, mesh.index_count, count * 3);
    cr_expect_eq(mesh.vertex_count, edges, "%s apron %d: %u vertices, %zu crossed edges", what, apron, mesh.vertex_count, edges);
    if (mesh.index_count == count * 3) {
        ref_triangle *got = malloc((count ? count : 1) * sizeof *got);
        for (size_t t = 0; t < count; t++)
            canonical_triangle(mesh.vertices[mesh.indices[3 * t]].position, mesh.vertices[mesh.indices[3 * t + 1]].position,
                               mesh.vertices[mesh.indices[3 * t + 2]].position, &got[t]);
        qsort(got, count, sizeof *got, compare_triangles);
        size_t differ = 0;
        for (size_t t = 0; t < count; t++) differ += memcmp(&got[t], &expected[t], sizeof *got) != 0;
        cr_expect_eq(differ, 0, "%s apron %d: %zu of %zu triangles differ from the cell-by-cell walk", what, apron, differ, count);
        free(got);
    }
    terrain_mesh_free(&mesh);
    free(expected);
}

Test(terrain_mesh, row_passes_equal_a_cell_by_cell_walk) {
    /* Rows narrower and wider than a 64-bit word and straddling one (63 … 130 samples), noise
     * with exact zeros, and whole rows of one sign beside rows of the other (the passes skip
     * rows whose signs agree with their neighbours': planes test that shortcut's edges). */
    const int sizes[][3] = { { 2, 2, 2 }, { 5, 4, 3 }, { 35, 35, 35 }, { 63, 6, 5 }, { 64, 5, 6 },
                             { 65, 7, 4 }, { 66, 5, 5 }, { 128, 4, 4 }, { 130, 6, 5 } };
    uint32_t state = 12345;
    for (size_t s = 0; s < CORE_COUNTOF(sizes); s++)
        for (int kind = 0; kind < 3; kind++) {
            terrain_field f = { .nx = sizes[s][0], .ny = sizes[s][1], .nz = sizes[s][2], .spacing = 0.5f };
            f.values = core_alloc((size_t)f.nx * f.ny * f.nz * sizeof *f.values);
            for (int z = 0; z < f.nz; z++)
                for (int y = 0; y < f.ny; y++)
                    for (int x = 0; x < f.nx; x++) {
                        state = state * 1664525u + 1013904223u;
                        float noise = (float)(state >> 8) / 16777216.0f - 0.5f;
                        float value = kind == 0 ? noise
                                    : kind == 1 ? roundf(noise * 2.0f) / 2.0f                /* many zeros */
                                                : (float)(y % 3 == 1) - 0.5f + (x == 40 && z == 2 ? 1.0f : 0.0f);
                        f.values[((size_t)z * f.ny + y) * f.nx + x] = value;
                    }
            char what[64];
            snprintf(what, sizeof what, "%d × %d × %d kind %d", f.nx, f.ny, f.nz, kind);
            for (int apron = 0; apron <= 1; apron++) expect_mesh_matches_reference(&f, apron, what);
            terrain_field_free(&f);
        }
}

Test(terrain_mesh, big_fields_mesh_the_same_on_every_thread_count) {
    /* 71³ samples: past the size the mesher splits over threads. Same bytes with 1, 2 and 3
     * threads and without a job system. */
    sphere s = { { 35.2, 33.7, 36.1 }, 30.3 };
    terrain_field f = field_make(71, 71, 71, sphere_fn, &s);
    terrain_mesh alone;
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .apron = 1, .no_optimize = true }, &alone));
    cr_assert_gt(alone.index_count, 0);
    for (int threads = 1; threads <= 3; threads++) {
        job_system *jobs = job_system_create(&(job_system_desc){ .threads = threads });
        terrain_mesh mesh;
        cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .apron = 1, .no_optimize = true, .jobs = jobs }, &mesh));
        cr_expect_eq(mesh.vertex_count, alone.vertex_count, "%d threads", threads);
        cr_expect_eq(mesh.index_count, alone.index_count, "%d threads", threads);
        if (mesh.vertex_count == alone.vertex_count && mesh.index_count == alone.index_count) {
            cr_expect(!memcmp(mesh.vertices, alone.vertices, mesh.vertex_count * sizeof *mesh.vertices), "%d threads", threads);
            cr_expect(!memcmp(mesh.indices, alone.indices, mesh.index_count * sizeof *mesh.indices), "%d threads", threads);
        }
        terrain_mesh_free(&mesh);
        job_system_destroy(jobs);
    }
    mesh_topology t = mesh_check(&alone);
    cr_expect(t.watertight);
    cr_expect_eq(t.euler, 2);
    terrain_mesh_free(&alone);
    terrain_field_free(&f);
}

/* ---- empty, full, apron --------------------------------------------------------------------- */

static float constant_fn(const double p[3], const void *user) {
    (void)p;
    return *(const float *)user;
}

Test(terrain_mesh, empty_and_full_fields_give_no_triangles) {
    const float values[] = { -1.0f, 1.0f, 0.0f, -0.25f };
    for (size_t i = 0; i < CORE_COUNTOF(values); i++) {
        terrain_field f = field_make(20, 20, 20, constant_fn, &values[i]);
        terrain_mesh mesh = mesh_of(&f, 1);
        cr_expect_eq(mesh.vertex_count, 0);
        cr_expect_eq(mesh.index_count, 0);
        cr_expect_null(mesh.vertices);
        terrain_mesh_free(&mesh);
        terrain_field_free(&f);
    }
    /* A field whose only surface lies in the apron: nothing is meshed. */
    float inside = 1.0f;
    terrain_field f = field_make(10, 10, 10, constant_fn, &inside);
    f.values[0] = -1.0f;   /* corner sample, in the apron */
    terrain_mesh mesh = mesh_of(&f, 1);
    cr_expect_eq(mesh.index_count, 0);
    terrain_mesh_free(&mesh);
    terrain_field_free(&f);
}

Test(terrain_mesh, bad_fields_are_refused) {
    terrain_field f = { .nx = 4, .ny = 4, .nz = 4, .spacing = 1.0f };   /* no values */
    terrain_mesh mesh;
    cr_expect_not(terrain_mesh_build(&f, &(terrain_mesh_desc){ 0 }, &mesh));
    float v = 1.0f;
    f = field_make(4, 4, 4, constant_fn, &v);
    cr_expect_not(terrain_mesh_build(&f, &(terrain_mesh_desc){ .apron = -1 }, &mesh));
    cr_expect(terrain_mesh_build(&f, &(terrain_mesh_desc){ .apron = 2 }, &mesh), "too small to mesh is empty, not wrong");
    cr_expect_eq(mesh.index_count, 0);
    terrain_field_free(&f);
}

/* ---- adjacent chunks -------------------------------------------------------------------------- */

typedef struct border_vertex { double p[3]; float n[3]; } border_vertex;

static int compare_border(const void *a, const void *b) {
    const border_vertex *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->p[i] != y->p[i]) return x->p[i] < y->p[i] ? -1 : 1;
    return 0;
}

/* World positions (and normals) of the vertices on the plane world[axis] = plane, but for those
 * sitting exactly on a grid sample: a sample with f = 0 is reached by edges from both sides of
 * the plane (t = 0 or 1), which each chunk meshes only on its own side. */
static border_vertex *border_vertices(const terrain_mesh *mesh, int axis, double plane, size_t *count) {
    border_vertex *out = malloc((mesh->vertex_count + 1) * sizeof *out);
    *count = 0;
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        border_vertex b;
        for (int a = 0; a < 3; a++) b.p[a] = mesh->origin[a] + mesh->vertices[v].position[a], b.n[a] = mesh->vertices[v].normal[a];
        bool on_sample = b.p[0] == floor(b.p[0]) && b.p[1] == floor(b.p[1]) && b.p[2] == floor(b.p[2]);
        if (b.p[axis] == plane && !on_sample) out[(*count)++] = b;
    }
    qsort(out, *count, sizeof *out, compare_border);
    return out;
}

static void expect_same_border(const terrain_mesh *a, const terrain_mesh *b, int axis, double plane) {
    size_t na, nb;
    border_vertex *va = border_vertices(a, axis, plane, &na), *vb = border_vertices(b, axis, plane, &nb);
    cr_expect_gt(na, 0, "the surface crosses the border");
    cr_expect_eq(na, nb, "border vertex counts %zu and %zu", na, nb);
    int differ = 0;
    for (size_t i = 0; i < na && i < nb; i++)
        differ += memcmp(va[i].p, vb[i].p, sizeof va[i].p) != 0 || memcmp(va[i].n, vb[i].n, sizeof va[i].n) != 0;
    cr_expect_eq(differ, 0, "%d of %zu border vertices differ", differ, na);
    free(va);
    free(vb);
}

Test(terrain_mesh, adjacent_analytic_chunks_share_border_vertices) {
    /* One sphere across two 24³-cell chunks along x, with a one-sample apron; the second field's
     * samples are the first's shifted by 24 (same function, other origin). */
    sphere s = { { 24.0 + 0.37, 12.2, 11.9 }, 9.3 };
    terrain_field a = { .nx = 27, .ny = 27, .nz = 27, .spacing = 1.0f, .origin = { -1, -1, -1 } };
    terrain_field b = a;
    b.origin[0] = 23.0;
    a.values = core_alloc(27 * 27 * 27 * sizeof(float));
    b.values = core_alloc(27 * 27 * 27 * sizeof(float));
    for (int z = 0; z < 27; z++)
        for (int y = 0; y < 27; y++)
            for (int x = 0; x < 27; x++) {
                double pa[3] = { a.origin[0] + x, a.origin[1] + y, a.origin[2] + z };
                double pb[3] = { b.origin[0] + x, pa[1], pa[2] };
                a.values[(z * 27 + y) * 27 + x] = sphere_fn(pa, &s);
                b.values[(z * 27 + y) * 27 + x] = sphere_fn(pb, &s);
            }
    terrain_mesh ma = mesh_of(&a, 1), mb = mesh_of(&b, 1);
    expect_same_border(&ma, &mb, 0, 24.0);
    /* Together they are the closed sphere: merge the border vertices and check the union. */
    cr_expect_float_eq(terrain_mesh_area(&ma) + terrain_mesh_area(&mb), 4.0 * M_PI * s.radius * s.radius,
                       0.03 * 4.0 * M_PI * s.radius * s.radius);
    terrain_mesh_free(&ma);
    terrain_mesh_free(&mb);
    terrain_field_free(&a);
    terrain_field_free(&b);
}

static terrain_mesh chunk_mesh(terrain_world *world, int64_t cx, int64_t cy, int64_t cz) {
    const int cells = 32, apron = 1;
    terrain_field field;
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){
        .first = { cx * cells - apron, cy * cells - apron, cz * cells - apron },
        .size = { cells + 1 + 2 * apron, cells + 1 + 2 * apron, cells + 1 + 2 * apron } }, &field));
    terrain_mesh mesh;
    cr_assert(terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = world, .apron = apron }, &mesh));
    terrain_field_free(&field);
    return mesh;
}

/* Generated terrain leaves the chunk, so its mesh is open — but only on the meshed box's faces:
 * an edge without its reverse must lie in one face plane (local coordinates lo … hi). */
static void expect_open_only_on_the_box(const terrain_mesh *mesh, float lo, float hi) {
    size_t count = mesh->index_count;
    uint64_t *directed = malloc(count * sizeof *directed);
    for (size_t i = 0; i < count; i += 3)
        for (int k = 0; k < 3; k++)
            directed[i + k] = (uint64_t)mesh->indices[i + k] << 32 | mesh->indices[i + (k + 1) % 3];
    qsort(directed, count, sizeof *directed, compare_u64);
    int open = 0, inside = 0, twice = 0;
    for (size_t i = 0; i < count; i++) {
        twice += i > 0 && directed[i] == directed[i - 1];
        uint64_t reverse = (directed[i] & 0xffffffffu) << 32 | directed[i] >> 32;
        if (bsearch(&reverse, directed, count, sizeof *directed, compare_u64)) continue;
        open++;
        const float *a = mesh->vertices[directed[i] >> 32].position, *b = mesh->vertices[directed[i] & 0xffffffffu].position;
        bool on_face = false;
        for (int axis = 0; axis < 3; axis++)
            on_face |= (a[axis] == lo && b[axis] == lo) || (a[axis] == hi && b[axis] == hi);
        inside += !on_face;
    }
    cr_expect_eq(twice, 0, "no directed edge twice");
    cr_expect_gt(open, 0, "the surface leaves the chunk");
    cr_expect_eq(inside, 0, "%d of %d open edges inside the chunk", inside, open);
    free(directed);
}

Test(terrain_mesh, adjacent_world_chunks_share_border_vertices) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5) });
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    int64_t cy = (int64_t)floor(terrain_stacks_top(stacks, 31, 16) / 32.0);
    terrain_mesh here = chunk_mesh(world, 0, cy, 0), east = chunk_mesh(world, 1, cy, 0), south = chunk_mesh(world, 0, cy, 1);
    cr_assert_gt(here.index_count, 0, "the chunk holds the surface");
    expect_open_only_on_the_box(&here, 1.0f, 33.0f);   /* the apron: local 0 is sample −1 */
    expect_same_border(&here, &east, 0, 32.0);
    expect_same_border(&here, &south, 2, 32.0);
    /* Weights: a distribution over the four visible materials. */
    for (uint32_t v = 0; v < here.vertex_count; v++) {
        const uint8_t *w = here.vertices[v].weights;
        cr_expect_eq(w[0] + w[1] + w[2] + w[3], 255, "vertex %u", v);
    }
    terrain_mesh_free(&here);
    terrain_mesh_free(&east);
    terrain_mesh_free(&south);
    terrain_world_destroy(world);
}

/* ---- material weights (000 §6) ---------------------------------------------------------------- */

/* Flat ground at 10 m: sand for x < 0, bedrock for x ≥ 0, a sand strip 4 m deep over bedrock. */
static void two_material_column(int64_t gx, terrain_stacks_builder *b) {
    if (gx < 0) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.0f - 4.0f - TERRAIN_FLOOR_Y);
        terrain_stacks_builder_push(b, TERRAIN_SAND, 4.0f);
    } else {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.0f - TERRAIN_FLOOR_Y);
    }
}

static terrain_stacks *two_material_generate(void *user, terrain_chunk_coord coord) {
    (void)user;
    terrain_stacks_builder *b = terrain_stacks_builder_create();
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            two_material_column(coord.x * TERRAIN_CHUNK_COLUMNS + i, b);
            terrain_stacks_builder_end_column(b);
        }
    terrain_stacks *stacks = terrain_stacks_builder_finish(b);
    terrain_stacks_builder_destroy(b);
    return stacks;
}

Test(terrain_mesh, weights_follow_the_visible_material) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = two_material_generate });
    terrain_field field;
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -9, 4, -3 }, .size = { 19, 12, 7 } }, &field));
    terrain_mesh mesh;
    cr_assert(terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = world, .apron = 1 }, &mesh));
    cr_assert_gt(mesh.vertex_count, 0);
    int sand = 0, bedrock = 0;
    for (uint32_t v = 0; v < mesh.vertex_count; v++) {
        const terrain_vertex *vx = &mesh.vertices[v];
        double x = mesh.origin[0] + vx->position[0], y = mesh.origin[1] + vx->position[1];
        cr_expect_float_eq(y, 10.0, 1e-4, "flat ground at 10 m");
        cr_expect_float_eq(vx->normal[1], 1.0f, 1e-4f, "facing up");
        if (x <= -1.0) {
            cr_expect_eq(vx->weights[1], 255, "sand at x = %g", x);
            sand++;
        }
        if (x >= 1.0) {
            cr_expect_eq(vx->weights[0], 255, "bedrock at x = %g", x);
            bedrock++;
        }
        if (x == 0.0) cr_expect(vx->weights[0] > 0 && vx->weights[1] > 0, "a blend at the border");
    }
    cr_expect_gt(sand, 0);
    cr_expect_gt(bedrock, 0);
    terrain_mesh_free(&mesh);
    terrain_field_free(&field);
    terrain_world_destroy(world);
}

Test(terrain_mesh, vertex_cache_optimisation_keeps_the_triangles) {
    sphere s = { { 8.5, 8.2, 8.9 }, 6.1 };
    terrain_field f = field_make(18, 18, 18, sphere_fn, &s);
    terrain_mesh plain, optimized;
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .no_optimize = true }, &plain));
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ 0 }, &optimized));
    cr_assert_eq(plain.index_count, optimized.index_count);
    cr_assert_eq(plain.vertex_count, optimized.vertex_count);
    /* The same set of triangles (each rotated to start at its smallest index), maybe reordered. */
    size_t triangles = plain.index_count / 3;
    uint64_t *ta = malloc(triangles * 2 * sizeof *ta), *tb = ta + triangles;
    const terrain_mesh *meshes[2] = { &plain, &optimized };
    for (int m = 0; m < 2; m++)
        for (size_t t = 0; t < triangles; t++) {
            const uint32_t *i = meshes[m]->indices + 3 * t;
            int r = i[0] < i[1] ? (i[0] < i[2] ? 0 : 2) : (i[1] < i[2] ? 1 : 2);
            uint64_t key = (uint64_t)i[r] << 42 | (uint64_t)i[(r + 1) % 3] << 21 | i[(r + 2) % 3];
            (m ? tb : ta)[t] = key;
        }
    qsort(ta, triangles, sizeof *ta, compare_u64);
    qsort(tb, triangles, sizeof *tb, compare_u64);
    cr_expect_eq(memcmp(ta, tb, triangles * sizeof *ta), 0);
    free(ta);
    terrain_mesh_free(&plain);
    terrain_mesh_free(&optimized);
    terrain_field_free(&f);
}

/* The parts (terrain_data.h): they tile the indices in order, none empty; each holds the
 * triangles whose centroid lies in one cell of the TERRAIN_MESH_PART_GRID² grid over the mesh's
 * box in x and z, every cell that holds a centroid is a part, the cells come in order (z, then x),
 * and each part's box is exactly its triangles' box. */
static int grid_cell(double at, float lo, float hi) {
    int cell = (int)floor((at - lo) / (hi - lo) * TERRAIN_MESH_PART_GRID);
    return cell < 0 ? 0 : cell >= TERRAIN_MESH_PART_GRID ? TERRAIN_MESH_PART_GRID - 1 : cell;
}

Test(terrain_mesh, parts_hold_the_triangles_of_their_cell_in_order) {
    sphere s = { { 8.5, 8.2, 8.9 }, 6.1 };
    terrain_field f = field_make(18, 18, 18, sphere_fn, &s);
    terrain_mesh plain, mesh;
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ .no_optimize = true }, &plain));
    cr_assert(terrain_mesh_build(&f, &(terrain_mesh_desc){ 0 }, &mesh));
    cr_expect_eq(plain.part_count, 0, "the raw output has no parts");
    float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    for (uint32_t v = 0; v < mesh.vertex_count; v++)
        for (int a = 0; a < 3; a++) lo[a] = fminf(lo[a], mesh.vertices[v].position[a]), hi[a] = fmaxf(hi[a], mesh.vertices[v].position[a]);
    /* The cells the raw mesh's centroids fall in. */
    bool occupied[TERRAIN_MESH_PARTS] = { false };
    int cells = 0;
    for (uint32_t t = 0; t < plain.index_count; t += 3) {
        double centroid[3] = { 0, 0, 0 };
        for (int c = 0; c < 3; c++)
            for (int a = 0; a < 3; a++) centroid[a] += plain.vertices[plain.indices[t + c]].position[a] / 3.0;
        int cell = grid_cell(centroid[2], lo[2], hi[2]) * TERRAIN_MESH_PART_GRID + grid_cell(centroid[0], lo[0], hi[0]);
        cells += !occupied[cell];
        occupied[cell] = true;
    }
    cr_expect_gt(cells, 1);
    cr_assert_eq(mesh.part_count, (uint32_t)cells, "a part for each cell that holds triangles");
    const double cell_x = (hi[0] - lo[0]) / TERRAIN_MESH_PART_GRID, cell_z = (hi[2] - lo[2]) / TERRAIN_MESH_PART_GRID;
    uint32_t next = 0;
    int last_cell = -1;
    for (uint32_t p = 0; p < mesh.part_count; p++) {
        const terrain_mesh_part *part = &mesh.parts[p];
        cr_assert_eq(part->first_index, next, "part %u starts where the last ended", p);
        cr_assert_gt(part->index_count, 0, "part %u is empty", p);
        cr_assert_eq(part->index_count % 3, 0);
        next += part->index_count;
        int i = -1, k = -1;
        float box_lo[3] = { INFINITY, INFINITY, INFINITY }, box_hi[3] = { -INFINITY, -INFINITY, -INFINITY };
        for (uint32_t t = part->first_index; t < part->first_index + part->index_count; t += 3) {
            double centroid[3] = { 0, 0, 0 };
            for (int c = 0; c < 3; c++) {
                const float *q = mesh.vertices[mesh.indices[t + c]].position;
                for (int a = 0; a < 3; a++) {
                    centroid[a] += q[a] / 3.0;
                    box_lo[a] = fminf(box_lo[a], q[a]), box_hi[a] = fmaxf(box_hi[a], q[a]);
                }
            }
            if (i < 0) {   /* the part's cell, from its first triangle */
                i = grid_cell(centroid[0], lo[0], hi[0]), k = grid_cell(centroid[2], lo[2], hi[2]);
                cr_expect_gt(k * TERRAIN_MESH_PART_GRID + i, last_cell, "part %u's cell comes after the last's", p);
                last_cell = k * TERRAIN_MESH_PART_GRID + i;
            }
            cr_expect(centroid[0] >= lo[0] + i * cell_x - 1e-4 && centroid[0] <= lo[0] + (i + 1) * cell_x + 1e-4 &&
                          centroid[2] >= lo[2] + k * cell_z - 1e-4 && centroid[2] <= lo[2] + (k + 1) * cell_z + 1e-4,
                      "a triangle of part %u (cell %d, %d) has its centroid at x %g, z %g", p, i, k, centroid[0], centroid[2]);
        }
        for (int a = 0; a < 3; a++) {
            cr_expect_eq(part->bounds_min[a], box_lo[a], "part %u's box, axis %d", p, a);
            cr_expect_eq(part->bounds_max[a], box_hi[a], "part %u's box, axis %d", p, a);
        }
    }
    cr_expect_eq(next, mesh.index_count, "the parts hold every index");
    terrain_mesh_free(&plain);
    terrain_mesh_free(&mesh);
    terrain_field_free(&f);
}
