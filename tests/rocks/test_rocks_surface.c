/* The dual surface a rock's levels of detail are simplified from (rocks_surface.c): closed
 * 2-manifolds whatever the field, a ball on its sphere, a box's sharp corners kept where marching
 * cubes cuts them, a slab thinner than the coarse grid refused, and on real rocks the surface
 * within reach of every marching-cubes vertex. Expectations come from the shapes' geometry
 * (a sphere's radius, a box's corners, the grid edges marching cubes puts its points on) and
 * from invariants (every edge in two triangles, one fan round every vertex, V − E + F = 2). */
#include "../engine/test.h"
#include "core/core.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct box_field {
    int size[3];
    float *rho;
} box_field;

static box_field box_field_make(int sx, int sy, int sz) {
    box_field f = { { sx, sy, sz }, calloc((size_t)sx * sy * sz, sizeof(float)) };
    return f;
}

static float *rho_at(box_field *f, int x, int y, int z) {
    return &f->rho[((size_t)z * f->size[1] + y) * f->size[0] + x];
}

/* Each directed edge once and its reverse once; one fan of triangles round every vertex used;
 * V − E + F = 2 (a sphere). */
static void expect_closed_sphere(const rocks__surface *s) {
    cr_assert(rocks__watertight(s->indices, s->index_count, s->vertex_count), "the surface has an open or doubled edge");
    uint32_t *uses = calloc(s->vertex_count, sizeof *uses), used = 0;
    for (uint32_t i = 0; i < s->index_count; i++) used += uses[s->indices[i]]++ == 0;
    /* a vertex's fan: walk from one of its triangles to the next across the edge after it */
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        if (!uses[v]) continue;
        uint32_t start = UINT32_MAX;
        for (uint32_t t = 0; t < s->index_count / 3 && start == UINT32_MAX; t++)
            for (int k = 0; k < 3; k++)
                if (s->indices[3 * t + k] == v) start = 3 * t + (uint32_t)k;
        uint32_t corner = start, steps = 0;
        do {
            uint32_t t = corner / 3, k = corner % 3, b = s->indices[3 * t + (k + 2) % 3];   /* v's triangle v a b */
            uint32_t next = UINT32_MAX;   /* the triangle holding v → b */
            for (uint32_t u = 0; u < s->index_count / 3 && next == UINT32_MAX; u++)
                for (int j = 0; j < 3; j++)
                    if (s->indices[3 * u + j] == v && s->indices[3 * u + (j + 1) % 3] == b) next = 3 * u + (uint32_t)j;
            cr_assert_neq(next, UINT32_MAX);
            corner = next, steps++;
        } while (corner != start && steps <= uses[v]);
        cr_expect_eq(steps, uses[v], "vertex %u: %u triangles, but one fan holds %u", v, uses[v], steps);
    }
    long euler = (long)used - (long)(s->index_count / 2) + (long)(s->index_count / 3);   /* E = 3F/2 */
    cr_expect_eq(euler, 2, "V − E + F = %ld", euler);
    free(uses);
}

/* A ball of radius R about the box's centre, ρ falling from 1 to 0 over two voxels across the
 * sphere (so r = 2ρ − 1 crosses zero on it, and its differences point along the radius). A vertex
 * fitted to the tangent planes of a convex surface sits outside it: for crossings within a
 * coarse cell, at most √3 voxels of arc from the vertex's own direction, by at most
 * R (1 / cos(√3 / R) − 1) ≈ 0.25 voxel at R = 6.3. Normals point out. */
/* ---- the closed-mesh check (rocks__watertight) on meshes built by hand ---------------------- */

/* A torus of rings × segments vertices, quads split in two, all turned the same way: every
 * directed edge once and its reverse once (worked out per quad edge: the next quad holds it
 * reversed). Returns the index count. */
static uint32_t torus(uint32_t rings, uint32_t segments, uint32_t first_vertex, uint32_t *out) {
    uint32_t n = 0;
    for (uint32_t i = 0; i < rings; i++)
        for (uint32_t j = 0; j < segments; j++) {
            uint32_t a = first_vertex + i * segments + j, b = first_vertex + (i + 1) % rings * segments + j;
            uint32_t c = first_vertex + (i + 1) % rings * segments + (j + 1) % segments;
            uint32_t d = first_vertex + i * segments + (j + 1) % segments;
            out[n++] = a, out[n++] = b, out[n++] = c;
            out[n++] = a, out[n++] = c, out[n++] = d;
        }
    return n;
}

Test(rocks_surface, the_closed_mesh_check_knows_a_tetrahedron) {
    uint32_t tetra[12] = { 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2 };   /* outward, each edge both ways */
    cr_expect(rocks__watertight(tetra, 12, 4));
    cr_expect(rocks__watertight(tetra, 12, 1000), "unused vertices do not open a mesh");
    cr_expect_not(rocks__watertight(tetra, 9, 4), "one face missing: three open edges");
    uint32_t flipped[12];
    memcpy(flipped, tetra, sizeof tetra);
    flipped[1] = 1, flipped[2] = 2;
    cr_expect_not(rocks__watertight(flipped, 12, 4), "a face turned over: its edges run twice one way");
    uint32_t doubled[15];
    memcpy(doubled, tetra, sizeof tetra);
    memcpy(doubled + 12, tetra, 3 * sizeof *tetra);
    cr_expect_not(rocks__watertight(doubled, 15, 4), "a face twice");
    uint32_t degenerate[15];
    memcpy(degenerate, tetra, sizeof tetra);
    degenerate[12] = 0, degenerate[13] = 0, degenerate[14] = 1;
    cr_expect_not(rocks__watertight(degenerate, 15, 4), "a triangle with a vertex twice");
    cr_expect_not(rocks__watertight(tetra, 12, 3), "an index past the vertices");
    cr_expect_not(rocks__watertight(tetra, 11, 4), "a count that is not whole triangles");
    cr_expect_not(rocks__watertight(tetra, 0, 4), "nothing");
}

/* Both ways of checking: up to 256 vertices used (a bit matrix) and more (edges in buckets). */
Test(rocks_surface, the_closed_mesh_check_knows_small_and_large_tori) {
    const uint32_t sizes[2][2] = { { 6, 9 }, { 20, 17 } };   /* 54 and 340 vertices */
    for (int t = 0; t < 2; t++) {
        uint32_t rings = sizes[t][0], segments = sizes[t][1], vertices = rings * segments + 7;
        uint32_t *indices = malloc(6 * rings * segments * sizeof *indices);
        uint32_t n = torus(rings, segments, 7, indices);
        cr_expect(rocks__watertight(indices, n, vertices), "torus %u × %u", rings, segments);
        cr_expect_not(rocks__watertight(indices, n - 3, vertices), "torus %u × %u less a triangle", rings, segments);
        uint32_t keep = indices[n / 2 + 1];
        indices[n / 2 + 1] = indices[n / 2 + 2], indices[n / 2 + 2] = keep;   /* one triangle turned over */
        cr_expect_not(rocks__watertight(indices, n, vertices), "torus %u × %u with a triangle turned", rings, segments);
        free(indices);
    }
}

Test(rocks_surface, a_ball_comes_out_closed_and_on_its_sphere) {
    const float radius = 6.3f, centre = 9.2f;
    box_field f = box_field_make(20, 20, 20);
    for (int z = 1; z < 19; z++)
        for (int y = 1; y < 19; y++)
            for (int x = 1; x < 19; x++) {
                float d = sqrtf((x - centre) * (x - centre) + (y - centre) * (y - centre) + (z - centre) * (z - centre));
                *rho_at(&f, x, y, z) = fminf(1.0f, fmaxf(0.0f, 0.5f * (radius - d) + 0.5f));
            }
    rocks__surface s;
    cr_assert(rocks__dual_surface(f.rho, f.size, &s), "a ball is what the coarse grid follows");
    expect_closed_sphere(&s);
    const float bound = radius * (1.0f / cosf(sqrtf(3.0f) / radius) - 1.0f);
    float worst = 0.0f, least_dot = 1.0f;
    for (uint32_t v = 0; v < s.vertex_count; v++) {
        const float *p = s.positions + 3 * v, *n = s.normals + 3 * v;
        float d[3] = { p[0] - centre, p[1] - centre, p[2] - centre }, length = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        worst = fmaxf(worst, fabsf(length - radius));
        least_dot = fminf(least_dot, (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / length);
    }
    cr_expect_lt(worst, bound, "a vertex %.3f voxel off the sphere (bound %.3f)", (double)worst, (double)bound);
    cr_expect_gt(least_dot, 0.95f, "a normal %.3f from the outward radius", (double)least_dot);
    rocks__surface_free(&s);
    free(f.rho);
}

/* Solid voxels 4 … 11 on each axis (ρ 1 or 0, as most of a rock is): the faces lie half a voxel
 * out, at 3.5 and 11.5. Marching cubes lies on them except where it cuts the edges (by up to
 * √2/4 ≈ 0.35 voxel) and the corners (by 1/√3 ≈ 0.58: its corner triangle passes through the
 * three edge midpoints a voxel from it). The dual surface, closed, keeps its vertices within half
 * a voxel of the faces and inside the box grown by that. */
Test(rocks_surface, a_box_of_whole_voxels_stays_on_its_faces) {
    box_field f = box_field_make(16, 16, 16);
    for (int z = 4; z <= 11; z++)
        for (int y = 4; y <= 11; y++)
            for (int x = 4; x <= 11; x++) *rho_at(&f, x, y, z) = 1.0f;
    rocks__surface s;
    cr_assert(rocks__dual_surface(f.rho, f.size, &s));
    expect_closed_sphere(&s);
    for (uint32_t v = 0; v < s.vertex_count; v++) {
        const float *p = s.positions + 3 * v;
        float to_face = INFINITY, outside = 0.0f;
        for (int a = 0; a < 3; a++) {
            to_face = fminf(to_face, fminf(fabsf(p[a] - 3.5f), fabsf(p[a] - 11.5f)));
            outside = fmaxf(outside, fmaxf(3.5f - p[a], p[a] - 11.5f));
        }
        cr_expect_lt(to_face, 0.5f, "vertex %u is %.3f voxel from every face", v, (double)to_face);
        cr_expect_lt(outside, 0.5f);
    }
    rocks__surface_free(&s);
    free(f.rho);
}

/* A plate one voxel thick between two planes of coarse samples: no coarse edge crosses it, so
 * the coarse grid sees nothing, and the rock is meshed voxel by voxel instead. */
Test(rocks_surface, a_slab_between_the_coarse_samples_is_refused) {
    box_field f = box_field_make(16, 16, 16);
    for (int z = 3; z <= 12; z++)
        for (int x = 3; x <= 12; x++) *rho_at(&f, x, 7, z) = 1.0f;   /* coarse samples lie on even y */
    rocks__surface s;
    cr_expect_not(rocks__dual_surface(f.rho, f.size, &s));
    cr_expect_eq(s.vertex_count, 0u);
    cr_expect_null(s.indices);
    free(f.rho);
}

/* A plate one voxel thick with its voxels on a plane of coarse samples but whose upper face
 * carries a ridge a voxel wide between them: the ridge's crossings lie in cells with no vertex,
 * more than 1.5 voxels from any, and the surface is refused. */
Test(rocks_surface, a_ridge_the_coarse_grid_misses_is_refused) {
    box_field f = box_field_make(16, 16, 16);
    for (int z = 3; z <= 12; z++)
        for (int x = 3; x <= 12; x++)
            for (int y = 6; y <= 8; y++) *rho_at(&f, x, y, z) = 1.0f;   /* a slab on y = 6 … 8 */
    for (int z = 3; z <= 12; z++)
        for (int y = 9; y <= 12; y++) *rho_at(&f, 7, y, z) = 1.0f;      /* a fin on odd x, 4 voxels tall */
    rocks__surface s;
    cr_expect_not(rocks__dual_surface(f.rho, f.size, &s));
    free(f.rho);
    /* the same fin two voxels thick (x = 7, 8) holds a coarse sample: followed */
    f = box_field_make(16, 16, 16);
    for (int z = 3; z <= 12; z++)
        for (int x = 3; x <= 12; x++)
            for (int y = 6; y <= 8; y++) *rho_at(&f, x, y, z) = 1.0f;
    for (int z = 3; z <= 12; z++)
        for (int y = 9; y <= 12; y++) *rho_at(&f, 7, y, z) = *rho_at(&f, 8, y, z) = 1.0f;
    cr_expect(rocks__dual_surface(f.rho, f.size, &s));
    rocks__surface_free(&s);
    free(f.rho);
}

/* A plate 1.2 voxels thick, tilted 45° about z: its two faces cross the same coarse cells, and
 * a vertex fitted to both would lie between them (marching cubes' points up to 1.3 voxels from
 * such a surface). Their normals, opposite, sum to far less than 0.35 of their count: refused. */
Test(rocks_surface, the_two_faces_of_a_thin_plate_in_one_cell_are_refused) {
    box_field f = box_field_make(18, 18, 18);
    for (int z = 3; z < 15; z++)
        for (int y = 4; y < 15; y++)
            for (int x = 4; x < 15; x++)
                if (fabsf(((float)x - 8.5f + (float)y - 9.0f) * 0.70710678f) <= 0.6f) *rho_at(&f, x, y, z) = 1.0f;
    rocks__surface s;
    cr_expect_not(rocks__dual_surface(f.rho, f.size, &s));
    free(f.rho);
}

/* Whatever the field: a refusal, or a closed 2-manifold. Blobs of random noise (ρ from a few
 * random bumps, some crossing each other, some thin), 300 boxes. */
Test(rocks_surface, any_field_gives_a_closed_manifold_or_a_refusal) {
    int accepted = 0;
    for (uint64_t seed = 1; seed <= 300; seed++) {
        box_field f = box_field_make(14, 13, 15);
        float bumps[6][4];
        for (int b = 0; b < 6; b++)
            for (int k = 0; k < 4; k++) {
                uint64_t h = core_hash_combine(seed, (uint64_t)(b * 4 + k));
                float u = (float)(h >> 40) / (float)(1 << 24);
                bumps[b][k] = k < 3 ? 2.0f + u * 10.0f : 1.0f + u * 3.5f;   /* centre, radius */
            }
        for (int z = 1; z < 14; z++)
            for (int y = 1; y < 12; y++)
                for (int x = 1; x < 13; x++) {
                    float value = 0.0f;
                    for (int b = 0; b < 6; b++) {
                        float dx = x - bumps[b][0], dy = y - bumps[b][1], dz = z - bumps[b][2];
                        value = fmaxf(value, bumps[b][3] - sqrtf(dx * dx + dy * dy + dz * dz) + 0.5f);
                    }
                    *rho_at(&f, x, y, z) = fminf(1.0f, fmaxf(0.0f, value));
                }
        rocks__surface s;
        if (rocks__dual_surface(f.rho, f.size, &s)) {
            accepted++;
            cr_assert(rocks__watertight(s.indices, s.index_count, s.vertex_count), "seed %llu: an open or doubled edge",
                      (unsigned long long)seed);
            rocks__surface_free(&s);
        }
        free(f.rho);
    }
    cr_expect_gt(accepted, 100, "%d of 300 accepted", accepted);   /* the test must see surfaces */
}

/* ---- real rocks ---------------------------------------------------------------------------------- */

static float point_triangle_distance(const float *p, const float *a, const float *b, const float *c) {
    /* the nearest point on the triangle (Ericson's regions) */
    float ab[3], ac[3], ap[3], q[3];
    for (int i = 0; i < 3; i++) ab[i] = b[i] - a[i], ac[i] = c[i] - a[i], ap[i] = p[i] - a[i];
#define DOT(u, v) ((u)[0] * (v)[0] + (u)[1] * (v)[1] + (u)[2] * (v)[2])
    float d1 = DOT(ab, ap), d2 = DOT(ac, ap), bp[3], cp[3];
    for (int i = 0; i < 3; i++) bp[i] = p[i] - b[i], cp[i] = p[i] - c[i];
    float d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
    float vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
#undef DOT
    if (d1 <= 0 && d2 <= 0) memcpy(q, a, sizeof q);
    else if (d3 >= 0 && d4 <= d3) memcpy(q, b, sizeof q);
    else if (d6 >= 0 && d5 <= d6) memcpy(q, c, sizeof q);
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        for (int i = 0; i < 3; i++) q[i] = a[i] + d1 / (d1 - d3) * ab[i];
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        for (int i = 0; i < 3; i++) q[i] = a[i] + d2 / (d2 - d6) * ac[i];
    else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        for (int i = 0; i < 3; i++) q[i] = b[i] + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c[i] - b[i]);
    else
        for (int i = 0; i < 3; i++) q[i] = a[i] + ab[i] * (vb / (va + vb + vc)) + ac[i] * (vc / (va + vb + vc));
    float d = 0.0f;
    for (int i = 0; i < 3; i++) d += (p[i] - q[i]) * (p[i] - q[i]);
    return sqrtf(d);
}

/* One region instance of a round set at the game's resolution (10 voxels a cell), its rocks'
 * eroded ρ rebuilt from the voxels the build keeps (the box round a rock's voxels, grown by one:
 * what rocks__rock_mesh is given). Each rock the dual surface accepts: every marching-cubes point
 * of the same ρ lies within 1.5 voxels of it (the refusal's bound: a crossing no vertex's cell
 * holds may lie 1.5 voxels from the vertices about it); and most rocks are accepted (the
 * point of the dual surface: measured 97 % of the n = 5 round set; a regression guard). */
Test(rocks_surface, real_rocks_stay_within_reach_of_their_marching_cubes) {
    rocks__params params;
    cr_assert(rocks__params_make(&(rocks_tileset_desc){ .seed = 3, .shape = ROCKS_SHAPE_ROUND, .cells = 5 }, &params));
    rocks__region_result region;
    rocks__region_build(&params, &(rocks__build_options){ .keep_voxels = true }, ROCKS__REGION_COUNT - 1, &region);
    cr_assert_gt(region.rock_count, 20u);
    uint32_t accepted = 0;
    float worst = 0.0f;
    for (uint32_t r = 0; r < region.rock_count; r++) {
        int lo[3] = { INT32_MAX, INT32_MAX, INT32_MAX }, hi[3] = { INT32_MIN, INT32_MIN, INT32_MIN };
        for (uint32_t i = region.voxel_first[r]; i < region.voxel_first[r] + region.voxel_count[r]; i++)
            for (int a = 0; a < 3; a++) lo[a] = region.voxels[i][a] < lo[a] ? region.voxels[i][a] : lo[a],
                                       hi[a] = region.voxels[i][a] > hi[a] ? region.voxels[i][a] : hi[a];
        box_field f = box_field_make(hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, hi[2] - lo[2] + 3);
        for (uint32_t i = region.voxel_first[r]; i < region.voxel_first[r] + region.voxel_count[r]; i++)
            *rho_at(&f, region.voxels[i][0] - lo[0] + 1, region.voxels[i][1] - lo[1] + 1, region.voxels[i][2] - lo[2] + 1) =
                region.voxel_rho[i];
        rocks__surface s;
        if (rocks__dual_surface(f.rho, f.size, &s)) {
            accepted++;
            expect_closed_sphere(&s);
            size_t total = (size_t)f.size[0] * f.size[1] * f.size[2];
            terrain_field field = { .nx = f.size[0], .ny = f.size[1], .nz = f.size[2], .spacing = 1.0f,
                                    .values = malloc(total * sizeof(float)) };
            for (size_t i = 0; i < total; i++) field.values[i] = f.rho[i] == 0.5f ? 1e-6f : 2.0f * f.rho[i] - 1.0f;
            terrain_mesh mesh;
            cr_assert(terrain_mesh_build(&field, &(terrain_mesh_desc){ .no_occlusion = true, .no_optimize = true }, &mesh));
            for (uint32_t v = 0; v < mesh.vertex_count; v++) {
                float nearest = INFINITY;
                for (uint32_t t = 0; t < s.index_count; t += 3)
                    nearest = fminf(nearest, point_triangle_distance(mesh.vertices[v].position, s.positions + 3 * s.indices[t],
                                                                     s.positions + 3 * s.indices[t + 1],
                                                                     s.positions + 3 * s.indices[t + 2]));
                worst = fmaxf(worst, nearest);
            }
            terrain_mesh_free(&mesh);
            free(field.values);
            rocks__surface_free(&s);
        }
        free(f.rho);
    }
    cr_expect_leq(worst, 1.5f, "a marching-cubes point %.3f voxel from the dual surface", (double)worst);
    cr_expect_geq(accepted, region.rock_count * 8 / 10, "%u of %u rocks accepted", accepted, region.rock_count);
    rocks__region_result_free(&region);
}
