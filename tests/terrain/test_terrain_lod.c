/* Level of detail: coarser chunks beside finer ones must close the seams. The checks are on the
 * union of the chunk meshes of an octree-like arrangement — a level-L region split into its 8
 * level-(L−1) chunks, surrounded by its 26 level-L neighbours, each told which of its neighbours
 * is finer — with vertices merged by exact world position: a closed shape's union has every
 * edge once in each direction and the Euler characteristic of its topology; generated terrain's
 * union is open only on the block's outer box. Crack-free seams are exactly what makes these
 * hold: a crossing placed differently on the two sides, or a segment drawn on one side only,
 * leaves an edge without its reverse on the seam. The same checks hold for chunks simplified
 * by terrain_lod_desc.max_error (their border kept), with a plane worked out by hand and the
 * simplified surface's distance to the marching-cubes vertices. */
#include "../engine/test.h"
#include "core/core.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"
#include "distance_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- analytic fields: f at grid points, whatever the request ------------------------------ */

typedef struct analytic {
    int kind;                 /* 0 sphere, 1 noise blob, 2 plane */
    double centre[3], radius;
    uint64_t seed;
    int scale;                /* noise lattice, grid points */
} analytic;

static double lattice_value(uint64_t seed, int64_t x, int64_t y, int64_t z) {
    uint64_t h = core_hash_combine(core_hash_combine(core_hash_combine(seed, (uint64_t)x), (uint64_t)y), (uint64_t)z);
    return (double)(h % 2001) / 1000.0 - 1.0 + 0.0123457;   /* never exactly 0 */
}

static double noise_value(const analytic *an, const double p[3]) {
    double cell[3], frac[3];
    for (int a = 0; a < 3; a++) {
        cell[a] = floor(p[a] / an->scale);
        frac[a] = p[a] / an->scale - cell[a];
    }
    double sum = 0.0;
    for (int c = 0; c < 8; c++) {
        double weight = 1.0;
        for (int a = 0; a < 3; a++) weight *= (c >> a) & 1 ? frac[a] : 1.0 - frac[a];
        sum += weight * lattice_value(an->seed, (int64_t)cell[0] + (c & 1), (int64_t)cell[1] + ((c >> 1) & 1),
                                      (int64_t)cell[2] + ((c >> 2) & 1));
    }
    return sum;
}

static float analytic_at(const analytic *an, const double p[3]) {
    double dx = p[0] - an->centre[0], dy = p[1] - an->centre[1], dz = p[2] - an->centre[2];
    double ball = an->radius - sqrt(dx * dx + dy * dy + dz * dz);
    if (an->kind == 0) return (float)ball;
    if (an->kind == 2) return (float)(an->centre[1] - p[1] - an->centre[0] * p[0] - an->centre[2] * p[2]);   /* solid below */
    return (float)fmin(noise_value(an, p) + 0.2, ball);   /* noise, cut off by a ball: closed */
}

static bool analytic_sample(void *user, const terrain_field_desc *desc, terrain_field *out) {
    const analytic *an = user;
    int step = desc->step ? desc->step : 1;
    *out = (terrain_field){ .nx = desc->size[0], .ny = desc->size[1], .nz = desc->size[2], .spacing = (float)step };
    for (int a = 0; a < 3; a++) out->origin[a] = (double)desc->first[a];
    out->values = core_alloc((size_t)out->nx * out->ny * out->nz * sizeof *out->values);
    for (int z = 0; z < out->nz; z++)
        for (int y = 0; y < out->ny; y++)
            for (int x = 0; x < out->nx; x++) {
                double p[3] = { (double)(desc->first[0] + (int64_t)x * step), (double)(desc->first[1] + (int64_t)y * step),
                                (double)(desc->first[2] + (int64_t)z * step) };
                out->values[((size_t)z * out->ny + y) * out->nx + x] = analytic_at(an, p);
            }
    return true;
}

/* ---- the arrangement: region R of level L as 8 chunks of L − 1, its 26 neighbours at L ------- */

#define BLOCK_MESHES 34

typedef struct block {
    terrain_mesh meshes[BLOCK_MESHES];
    int count;
    int64_t triangles[2];     /* of the finer chunks, of the coarser ones */
    double box_min[3], box_max[3];
} block;

typedef bool (*chunk_mesher)(void *user, int64_t x, int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out);

/* error_scale > 0: every chunk simplified by that many times its level's error. */
static void block_build(block *b, chunk_mesher mesh, void *user, const int64_t region[3], int level, float error_scale) {
    b->count = 0;
    b->triangles[0] = b->triangles[1] = 0;
    double size = (double)TERRAIN_MESH_CELLS * (double)(1 << level);
    for (int a = 0; a < 3; a++) b->box_min[a] = (double)(region[a] - 1) * size, b->box_max[a] = (double)(region[a] + 2) * size;
    for (int k = 0; k < 8; k++) {
        terrain_mesh *m = &b->meshes[b->count++];
        cr_assert(mesh(user, 2 * region[0] + (k & 1), 2 * region[1] + ((k >> 1) & 1), 2 * region[2] + (k >> 2),
                       &(terrain_lod_desc){ .level = level - 1,
                                            .max_error = error_scale * (float)terrain_chunk_level_error(level - 1) }, m));
        b->triangles[0] += m->index_count / 3;
    }
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                if (!dx && !dy && !dz) continue;
                terrain_mesh *m = &b->meshes[b->count++];
                /* From the neighbour, R lies at the opposite offset. */
                terrain_lod_desc lod = { .level = level, .finer_neighbours = terrain_lod_neighbour_bit(-dx, -dy, -dz),
                                         .max_error = error_scale * (float)terrain_chunk_level_error(level) };
                cr_assert(mesh(user, region[0] + dx, region[1] + dy, region[2] + dz, &lod, m));
                b->triangles[1] += m->index_count / 3;
            }
}

static void block_free(block *b) {
    for (int i = 0; i < b->count; i++) terrain_mesh_free(&b->meshes[i]);
}

static bool analytic_mesher(void *user, int64_t x, int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out) {
    return terrain__mesh_chunk_with(analytic_sample, user, NULL, x, y, z, lod, out);
}

static bool world_mesher(void *user, int64_t x, int64_t y, int64_t z, const terrain_lod_desc *lod, terrain_mesh *out) {
    return terrain_mesh_chunk(user, x, y, z, lod, out);
}

/* ---- the union, merged by world position ----------------------------------------------------- */

typedef struct keyed { double p[3]; uint32_t original; } keyed;

static int compare_keyed(const void *a, const void *b) {
    const keyed *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->p[i] != y->p[i]) return x->p[i] < y->p[i] ? -1 : 1;
    return 0;
}

static int compare_u64(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

typedef struct union_topology {
    bool watertight;          /* every directed edge once and its reverse once */
    int64_t euler;            /* V − E + F of the merged mesh */
    int degenerate;           /* triangles that merging collapsed */
    int open;                 /* directed edges whose reverse occurs fewer times */
    int open_inside;          /* of those, not on the block's outer box */
    size_t triangles;
} union_topology;

static union_topology union_check(const block *b) {
    union_topology t = { .watertight = true };
    size_t vertices = 0, indices = 0;
    for (int m = 0; m < b->count; m++) vertices += b->meshes[m].vertex_count, indices += b->meshes[m].index_count;
    keyed *keys = malloc((vertices + 1) * sizeof *keys);
    double *world = malloc((vertices + 1) * 3 * sizeof *world);
    uint32_t *merged = malloc((vertices + 1) * sizeof *merged);
    size_t v = 0;
    for (int m = 0; m < b->count; m++)
        for (uint32_t i = 0; i < b->meshes[m].vertex_count; i++, v++) {
            for (int a = 0; a < 3; a++) keys[v].p[a] = b->meshes[m].origin[a] + b->meshes[m].vertices[i].position[a];
            keys[v].original = (uint32_t)v;
        }
    qsort(keys, vertices, sizeof *keys, compare_keyed);
    uint32_t distinct = 0;
    for (size_t i = 0; i < vertices; i++) {
        if (i > 0 && compare_keyed(&keys[i], &keys[i - 1]) != 0) distinct++;
        merged[keys[i].original] = distinct;
        memcpy(world + 3 * (size_t)distinct, keys[i].p, sizeof keys[i].p);
    }
    uint32_t merged_count = vertices ? distinct + 1 : 0;
    uint64_t *directed = malloc((indices + 1) * sizeof *directed);
    bool *used = calloc(merged_count + 1, 1);
    size_t count = 0, base = 0;
    for (int m = 0; m < b->count; m++) {
        const terrain_mesh *mesh = &b->meshes[m];
        for (uint32_t i = 0; i < mesh->index_count; i += 3) {
            uint32_t tri[3];
            for (int k = 0; k < 3; k++) tri[k] = merged[base + mesh->indices[i + k]];
            if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
                t.degenerate++;
                continue;
            }
            t.triangles++;
            for (int k = 0; k < 3; k++) {
                directed[count++] = (uint64_t)tri[k] << 32 | tri[(k + 1) % 3];
                used[tri[k]] = true;
            }
        }
        base += mesh->vertex_count;
    }
    qsort(directed, count, sizeof *directed, compare_u64);
    /* Runs of equal directed edges against runs of their reverse. */
    for (size_t i = 0; i < count;) {
        size_t j = i;
        while (j < count && directed[j] == directed[i]) j++;
        size_t forward = j - i;
        uint64_t reverse = (directed[i] & 0xffffffffu) << 32 | directed[i] >> 32;
        size_t backward = 0;
        uint64_t *hit = bsearch(&reverse, directed, count, sizeof *directed, compare_u64);
        if (hit) {
            size_t h = (size_t)(hit - directed);
            while (h > 0 && directed[h - 1] == reverse) h--;
            while (h + backward < count && directed[h + backward] == reverse) backward++;
        }
        if (forward != 1 || backward != 1) t.watertight = false;
        if (forward > backward) {
            t.open += (int)(forward - backward);
            const double *p = world + 3 * (size_t)(directed[i] >> 32), *q = world + 3 * (size_t)(directed[i] & 0xffffffffu);
            bool on_box = false;
            for (int a = 0; a < 3; a++)
                on_box |= (p[a] == b->box_min[a] && q[a] == b->box_min[a]) || (p[a] == b->box_max[a] && q[a] == b->box_max[a]);
            if (!on_box) t.open_inside += (int)(forward - backward);
        }
        i = j;
    }
    int64_t used_count = 0;
    for (uint32_t i = 0; i < merged_count; i++) used_count += used[i];
    t.euler = used_count - (int64_t)(count / 2) + (int64_t)(count / 3);
    free(keys);
    free(world);
    free(merged);
    free(directed);
    free(used);
    return t;
}

/* ---- closed shapes across levels ------------------------------------------------------------- */

Test(terrain_lod, spheres_across_levels_are_closed) {
    /* Spheres over R = [0, 64)³ (level 1, as 8 level-0 chunks) and its level-1 neighbours: across
     * R's corner (face, edge and corner neighbours), across one face seam, along the edge line
     * x = y = 64 (a coarse face beside a finer edge neighbour), and over all of R. */
    const analytic spheres[] = {
        { .centre = { 61.3, 66.7, 63.1 }, .radius = 21.7 },
        { .centre = { 50.2, 30.6, 70.3 }, .radius = 17.1 },
        { .centre = { 64.4, 63.6, 20.2 }, .radius = 14.3 },
        { .centre = { 33.1, 30.7, 31.9 }, .radius = 45.2 },
        { .centre = { 64.3, 62.9, 65.6 }, .radius = 5.3 },
    };
    const int64_t region[3] = { 0, 0, 0 };
    for (size_t s = 0; s < CORE_COUNTOF(spheres); s++) {
        analytic an = spheres[s];
        block b;
        block_build(&b, analytic_mesher, &an, region, 1, 0.0f);
        union_topology t = union_check(&b);
        cr_expect(t.watertight, "sphere %zu: %d open edges", s, t.open);
        cr_expect_eq(t.euler, 2, "sphere %zu: V − E + F = %lld", s, (long long)t.euler);
        cr_expect_eq(t.degenerate, 0, "sphere %zu", s);
        cr_expect_gt(b.triangles[1], 0, "sphere %zu reaches the coarser chunks", s);
        block_free(&b);
    }
}

Test(terrain_lod, noise_blobs_across_levels_are_closed) {
    /* Blobs with features at and below the coarse spacing (lattice 2–7 grid points), levels 1 and
     * 2: every kind of transition face, including split edges whose midpoint sample differs in
     * sign from both ends. Merging by position can join two vertices at one sample (t rounded to
     * 0 or 1), so the check is the balanced one: each edge as often in both directions. */
    const int scales[] = { 2, 3, 5, 7 };
    int closed = 0, with_both = 0;
    for (uint64_t seed = 1; seed <= 24; seed++) {
        int level = seed % 3 == 0 ? 2 : 1;
        double size = 32.0 * (1 << level);
        analytic an = { .kind = 1, .seed = seed, .scale = scales[seed % 4] * (level == 2 ? 2 : 1),
                        .centre = { size * (1.0 + 0.1 * (double)(seed % 5)), size * (0.9 + 0.05 * (double)(seed % 7)),
                                    size * (1.05 - 0.08 * (double)(seed % 4)) },
                        .radius = size * 0.45 };
        block b;
        block_build(&b, analytic_mesher, &an, (const int64_t[3]){ 0, 0, 0 }, level, 0.0f);
        union_topology t = union_check(&b);
        cr_expect_eq(t.open, 0, "seed %llu (level %d): %d open edges", (unsigned long long)seed, level, t.open);
        cr_expect_eq(t.euler % 2, 0, "seed %llu", (unsigned long long)seed);
        closed += t.open == 0;
        with_both += b.triangles[0] > 0 && b.triangles[1] > 0;
        block_free(&b);
    }
    cr_expect_eq(closed, 24);
    cr_expect_gt(with_both, 20, "the blobs cross the seams");
}

/* ---- generated terrain ------------------------------------------------------------------------- */

static int64_t ground_region(terrain_world *world, int level) {
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    double size = 32.0 * (1 << level);
    return (int64_t)floor(terrain_stacks_top(stacks, 31, 31) / size);
}

Test(terrain_lod, generated_terrain_seams_have_no_open_edges) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5) });
    for (int level = 1; level <= 2; level++) {
        int64_t region[3] = { 0, ground_region(world, level), 0 };
        block b;
        block_build(&b, world_mesher, world, region, level, 0.0f);
        union_topology t = union_check(&b);
        cr_expect_gt(t.open, 0, "level %d: the terrain leaves the block", level);
        cr_expect_eq(t.open_inside, 0, "level %d: %d of %d open edges inside the block (on a seam)", level,
                     t.open_inside, t.open);
        cr_expect_gt(b.triangles[0], 0);
        cr_expect_gt(b.triangles[1], 0);
        for (int m = 0; m < b.count; m++)
            for (uint32_t v = 0; v < b.meshes[m].vertex_count; v++) {
                const terrain_vertex *vx = &b.meshes[m].vertices[v];
                const float *n = vx->normal;
                cr_expect_float_eq(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-4f);
                cr_expect_eq(vx->weights[0] + vx->weights[1] + vx->weights[2] + vx->weights[3], 255);
            }
        block_free(&b);
    }
    terrain_world_destroy(world);
}

Test(terrain_lod, coarse_chunks_have_far_fewer_triangles) {
    /* The same 128 m block of ground at level 0 (64 chunks), level 1 (8) and level 2 (1). */
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(9) });
    int64_t region = ground_region(world, 2);
    int64_t triangles[3] = { 0, 0, 0 };
    for (int level = 0; level <= 2; level++) {
        int per = 1 << (2 - level);
        for (int z = 0; z < per; z++)
            for (int y = 0; y < per; y++)
                for (int x = 0; x < per; x++) {
                    terrain_mesh mesh;
                    cr_assert(terrain_mesh_chunk(world, x, region * per + y, z, &(terrain_lod_desc){ .level = level }, &mesh));
                    triangles[level] += mesh.index_count / 3;
                    terrain_mesh_free(&mesh);
                }
    }
    cr_log_info("triangles over 128 m: level 0 %lld, level 1 %lld (%.2f×), level 2 %lld (%.2f×)",
                (long long)triangles[0], (long long)triangles[1], (double)triangles[0] / (double)triangles[1],
                (long long)triangles[2], (double)triangles[0] / (double)triangles[2]);
    cr_expect_gt(triangles[2], 0);
    cr_expect_gt(triangles[0], 3 * triangles[1], "a level-1 surface has about a quarter of the triangles");
    cr_expect_gt(triangles[1], 3 * triangles[2]);
    terrain_world_destroy(world);
}

/* ---- simplified chunks (terrain_lod_desc.max_error) -------------------------------------------- */

/* The largest distance from a vertex of `full` to the surface of `simple` (the same origin). */
static double largest_distance(const terrain_mesh *full, const terrain_mesh *simple) {
    double largest = 0.0;
    for (uint32_t v = 0; v < full->vertex_count; v++) {
        double p[3], nearest = INFINITY;
        for (int k = 0; k < 3; k++) p[k] = full->vertices[v].position[k];
        for (uint32_t i = 0; i < simple->index_count && nearest > 0.0; i += 3) {
            double corners[3][3];
            const double *corner[3] = { corners[0], corners[1], corners[2] };
            bool near = true;
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 3; k++) corners[c][k] = simple->vertices[simple->indices[i + c]].position[k];
            for (int k = 0; k < 3 && near; k++)   /* no triangle farther than the nearest so far */
                near = fmin(corners[0][k], fmin(corners[1][k], corners[2][k])) - nearest <= p[k] &&
                       fmax(corners[0][k], fmax(corners[1][k], corners[2][k])) + nearest >= p[k];
            if (near) nearest = fmin(nearest, point_triangle_distance(p, corner));
        }
        largest = fmax(largest, nearest);
    }
    return largest;
}

typedef struct border_points { double (*p)[3]; size_t count; } border_points;

static int compare_point(const void *a, const void *b) {
    const double *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* The vertices on the sides x or z = lo or hi (mesh coordinates), sorted. */
static border_points border_of(const terrain_mesh *m, float lo, float hi) {
    border_points b = { .p = malloc((m->vertex_count + 1) * sizeof *b.p) };
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const float *q = m->vertices[v].position;
        if (q[0] != lo && q[0] != hi && q[2] != lo && q[2] != hi) continue;
        for (int k = 0; k < 3; k++) b.p[b.count][k] = q[k];
        b.count++;
    }
    qsort(b.p, b.count, sizeof *b.p, compare_point);
    return b;
}

Test(terrain_lod, simplifying_a_plane_keeps_its_border_and_its_area) {
    /* f = 20.5 − y − 0.31 x − 0.17 z over chunk (0, 0, 0). f is linear, so marching cubes puts
     * every vertex on the plane and no collapse moves the surface: the simplifier may take every
     * vertex that is not on the chunk's sides or next to them. What is left tiles the same polygon, whose area is
     * that of the 32 × 32 m square tilted, 1024·sqrt(1 + 0.31² + 0.17²) = 1086.12 m², with the
     * same border vertices. */
    analytic an = { .kind = 2, .centre = { 0.31, 20.5, 0.17 } };
    terrain_mesh full, simple;
    cr_assert(analytic_mesher(&an, 0, 0, 0, &(terrain_lod_desc){ 0 }, &full));
    cr_assert(analytic_mesher(&an, 0, 0, 0, &(terrain_lod_desc){ .max_error = 0.02f }, &simple));
    const double area = 1024.0 * sqrt(1.0 + 0.31 * 0.31 + 0.17 * 0.17);
    cr_expect(fabs(terrain_mesh_area(&full) - area) < 1e-3 * area, "full %.3f m²", terrain_mesh_area(&full));
    cr_expect(fabs(terrain_mesh_area(&simple) - area) < 1e-3 * area, "simplified %.3f m²", terrain_mesh_area(&simple));
    /* The chunk's cells span mesh coordinates 1 … 33 (the apron's first sample is the origin). */
    border_points a = border_of(&full, 1.0f, 33.0f), b = border_of(&simple, 1.0f, 33.0f);
    cr_assert_gt(a.count, 2 * 32);
    cr_expect_eq(a.count, b.count);
    for (size_t i = 0; i < a.count && i < b.count; i++) cr_expect_eq(compare_point(a.p[i], b.p[i]), 0, "border vertex %zu", i);
    /* The vertices next to the border (sharing a triangle with one, not on it) are kept too. */
    uint8_t *on_border = calloc(full.vertex_count, 1), *next = calloc(full.vertex_count, 1);
    for (uint32_t v = 0; v < full.vertex_count; v++) {
        const float *q = full.vertices[v].position;
        on_border[v] = q[0] == 1.0f || q[0] == 33.0f || q[2] == 1.0f || q[2] == 33.0f;
    }
    for (uint32_t i = 0; i < full.index_count; i += 3) {
        const uint32_t *t = full.indices + i;
        if (on_border[t[0]] || on_border[t[1]] || on_border[t[2]])
            for (int k = 0; k < 3; k++) next[t[k]] = !on_border[t[k]];
    }
    size_t ring = 0;
    for (uint32_t v = 0; v < full.vertex_count; v++) ring += next[v];
    /* A disc of B border and I inner vertices has B + 2I − 2 triangles: with only the ring left
     * inside, B + 2·ring − 2; a fifth more allows for collapses the simplifier leaves undone (it
     * left 10 % on this plane). */
    uint32_t triangles = simple.index_count / 3;
    size_t least = b.count + 2 * ring - 2;
    cr_expect_geq(triangles, least);
    cr_expect_leq(triangles, least + least / 5, "%u triangles for %zu border and %zu ring vertices", triangles, b.count, ring);
    cr_expect_gt(full.index_count / 3, 3 * triangles, "marching cubes: %u", full.index_count / 3);
    free(on_border), free(next);
    for (uint32_t v = 0; v < simple.vertex_count; v++) {
        double p[3];
        for (int k = 0; k < 3; k++) p[k] = simple.origin[k] + simple.vertices[v].position[k];
        cr_expect(fabs(analytic_at(&an, p)) < 1e-3f, "vertex %u off the plane", v);
    }
    free(a.p), free(b.p);
    terrain_mesh_free(&full), terrain_mesh_free(&simple);
}

Test(terrain_lod, simplified_spheres_across_levels_stay_closed) {
    /* Four times the level's error, to make the simplifier work hard near the seams: the union
     * must stay one closed surface (V − E + F = 2) with fewer triangles. */
    const analytic spheres[] = {
        { .centre = { 61.3, 66.7, 63.1 }, .radius = 21.7 },
        { .centre = { 50.2, 30.6, 70.3 }, .radius = 17.1 },
        { .centre = { 33.1, 30.7, 31.9 }, .radius = 45.2 },
    };
    for (size_t s = 0; s < CORE_COUNTOF(spheres); s++) {
        analytic an = spheres[s];
        block full, simple;
        block_build(&full, analytic_mesher, &an, (const int64_t[3]){ 0, 0, 0 }, 1, 0.0f);
        block_build(&simple, analytic_mesher, &an, (const int64_t[3]){ 0, 0, 0 }, 1, 4.0f);
        union_topology t = union_check(&simple);
        cr_expect(t.watertight, "sphere %zu: %d open edges", s, t.open);
        cr_expect_eq(t.euler, 2, "sphere %zu: V − E + F = %lld", s, (long long)t.euler);
        cr_expect_eq(t.degenerate, 0, "sphere %zu", s);
        cr_expect_lt(simple.triangles[0] + simple.triangles[1], full.triangles[0] + full.triangles[1], "sphere %zu", s);
        block_free(&full), block_free(&simple);
    }
}

Test(terrain_lod, simplified_generated_terrain_meets_at_every_seam) {
    /* The streamer's simplification (each chunk by its level's own error) on generated ground
     * across levels 0–1 and 1–2: no open edge inside the block, fewer triangles, every vertex
     * kept with its own normal and weights, and the full surface near the simplified one. */
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5) });
    for (int level = 1; level <= 2; level++) {
        int64_t region[3] = { 0, ground_region(world, level), 0 };
        block full, simple;
        block_build(&full, world_mesher, world, region, level, 0.0f);
        block_build(&simple, world_mesher, world, region, level, 1.0f);
        union_topology t = union_check(&simple);
        cr_expect_eq(t.open_inside, 0, "level %d: %d of %d open edges inside the block", level, t.open_inside, t.open);
        int64_t before = full.triangles[0] + full.triangles[1], after = simple.triangles[0] + simple.triangles[1];
        cr_log_info("level %d block: %lld triangles simplified to %lld (%.0f %%)", level, (long long)before,
                    (long long)after, 100.0 * (double)after / (double)before);
        cr_expect_lt(after, before);
        for (int m = 0; m < simple.count; m++) {
            const terrain_mesh *mesh = &simple.meshes[m];
            for (uint32_t v = 0; v < mesh->vertex_count; v++) {
                const float *n = mesh->vertices[v].normal;
                const uint8_t *w = mesh->vertices[v].weights;
                cr_expect_float_eq(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-4f);
                cr_expect_eq(w[0] + w[1] + w[2] + w[3], 255);
            }
        }
        /* The finer chunks (m < 8, level − 1) and the coarser ones: how far the simplified
         * surface strays from the marching-cubes vertices. */
        for (int m = 0; m < simple.count; m += 7) {
            int at = m < 8 ? level - 1 : level;
            double error = terrain_chunk_level_error(at), distance = largest_distance(&full.meshes[m], &simple.meshes[m]);
            cr_log_info("level %d chunk %d: %.3f m at most from the full surface (max_error %.3f m)", at, m, distance, error);
            cr_expect_leq(distance, 2.0 * error, "level %d chunk %d: %.3f m", at, m, distance);
        }
        block_free(&full), block_free(&simple);
    }
    terrain_world_destroy(world);
}

/* ---- level 0 is the plain pair; steps sample the same points ----------------------------------- */

Test(terrain_lod, level_0_without_finer_neighbours_is_the_plain_pair) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5) });
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 1, 0 });
    int64_t cy = (int64_t)floor(terrain_stacks_top(stacks, 16, 16) / 32.0);
    terrain_field field;
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { 32 * 1 - 1, 32 * cy - 1, 32 * 0 - 1 },
                                                                .size = { 35, 35, 35 } }, &field));
    terrain_mesh pair, chunk;
    cr_assert(terrain_mesh_build(&field, &(terrain_mesh_desc){ .world = world, .apron = 1 }, &pair));
    cr_assert(terrain_mesh_chunk(world, 1, cy, 0, NULL, &chunk));
    cr_assert_gt(pair.index_count, 0);
    cr_assert_eq(pair.vertex_count, chunk.vertex_count);
    cr_assert_eq(pair.index_count, chunk.index_count);
    cr_expect_eq(memcmp(pair.vertices, chunk.vertices, pair.vertex_count * sizeof *pair.vertices), 0);
    cr_expect_eq(memcmp(pair.indices, chunk.indices, pair.index_count * sizeof *pair.indices), 0);
    cr_expect_eq(memcmp(pair.origin, chunk.origin, sizeof pair.origin), 0);
    terrain_mesh_free(&pair);
    terrain_mesh_free(&chunk);
    terrain_field_free(&field);
    terrain_world_destroy(world);
}

Test(terrain_lod, strided_samples_equal_unit_samples) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(11) });
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    int64_t ground = (int64_t)floor(terrain_stacks_top(stacks, 5, 5));
    const float sigmas[] = { 0.0f, 1.37f, 2.5f };
    const int steps[] = { 2, 3, 4, 8 };
    int compared = 0, differ = 0;
    for (size_t s = 0; s < CORE_COUNTOF(sigmas); s++) {
        terrain_field_desc unit = { .first = { -21, ground - 20, -13 }, .size = { 50, 41, 45 }, .sigma = sigmas[s] };
        terrain_field dense;
        cr_assert(terrain_field_sample(world, &unit, &dense));
        for (size_t k = 0; k < CORE_COUNTOF(steps); k++) {
            int step = steps[k];
            terrain_field_desc strided = { .first = { -19, ground - 17, -11 }, .size = { 40 / step + 1, 35 / step + 1, 3 },
                                           .sigma = sigmas[s], .step = step };
            terrain_field sparse;
            cr_assert(terrain_field_sample(world, &strided, &sparse));
            cr_expect_float_eq(sparse.spacing, (float)step, 0.0f);
            cr_expect_float_eq(sparse.origin[1], (double)(ground - 17), 0.0);
            for (int z = 0; z < sparse.nz; z++)
                for (int y = 0; y < sparse.ny; y++)
                    for (int x = 0; x < sparse.nx; x++) {
                        int64_t g[3] = { strided.first[0] + x * step, strided.first[1] + y * step, strided.first[2] + z * step };
                        float a = sparse.values[((size_t)z * sparse.ny + y) * sparse.nx + x];
                        float b = dense.values[((size_t)(g[2] - unit.first[2]) * dense.ny + (size_t)(g[1] - unit.first[1])) * dense.nx +
                                               (size_t)(g[0] - unit.first[0])];
                        differ += memcmp(&a, &b, sizeof a) != 0;
                        compared++;
                    }
            terrain_field_free(&sparse);
        }
        terrain_field_free(&dense);
    }
    cr_expect_eq(differ, 0, "%d of %d strided samples differ from the unit-step ones", differ, compared);
    cr_expect_gt(compared, 1000);
    terrain_field field;
    cr_expect_not(terrain_field_sample(world, &(terrain_field_desc){ .size = { 4, 4, 4 }, .step = -1 }, &field));
    terrain_world_destroy(world);
}

/* ---- the fast paths against the reference -------------------------------------------------- */

static bool world_sample(void *user, const terrain_field_desc *desc, terrain_field *out) {
    return terrain_field_sample(user, desc, out);
}

static bool meshes_equal(const terrain_mesh *a, const terrain_mesh *b) {
    return a->vertex_count == b->vertex_count && a->index_count == b->index_count &&
           memcmp(a->origin, b->origin, sizeof a->origin) == 0 &&
           memcmp(a->bounds_min, b->bounds_min, sizeof a->bounds_min) == 0 &&
           memcmp(a->bounds_max, b->bounds_max, sizeof a->bounds_max) == 0 &&
           (!a->vertex_count || memcmp(a->vertices, b->vertices, a->vertex_count * sizeof *a->vertices) == 0) &&
           (!a->index_count || memcmp(a->indices, b->indices, a->index_count * sizeof *a->indices) == 0);
}

/* The shortcuts (empty transition cells skipped, sliding corner signs) must change no byte of
 * the mesh, vertex order included: chunks at levels 1 and 2 with all neighbours finer, each face
 * neighbour alone, an edge neighbour alone and hashed masks, on noise blobs and on terrain. */
Test(terrain_lod, fast_paths_equal_the_reference) {
    analytic blob = { .kind = 1, .centre = { 40, 40, 40 }, .radius = 70, .seed = 11, .scale = 3 };
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5) });
    int compared = 0, with_triangles = 0;
    for (int level = 1; level <= 2; level++) {
        uint32_t masks[9] = { (1u << 26) - 1, terrain_lod_neighbour_bit(1, 0, 0), terrain_lod_neighbour_bit(0, -1, 0),
                              terrain_lod_neighbour_bit(0, 0, 1), terrain_lod_neighbour_bit(-1, 1, 0) };
        for (int m = 5; m < 9; m++) masks[m] = (uint32_t)core_hash_u64((uint64_t)(level * 10 + m)) & ((1u << 26) - 1);
        int64_t ground = ground_region(world, level);
        for (int m = 0; m < 9; m++)
            for (int source = 0; source < 2; source++) {
                terrain_lod_desc lod = { .level = level, .finer_neighbours = masks[m] };
                terrain_mesh fast, reference;
                terrain__field_sampler sample = source ? world_sample : analytic_sample;
                void *user = source ? (void *)world : (void *)&blob;
                int64_t y = source ? ground : 0;
                cr_assert(terrain__mesh_chunk_with(sample, user, source ? world : NULL, 0, y, 0, &lod, &fast));
                cr_assert(terrain__mesh_chunk_reference(sample, user, source ? world : NULL, 0, y, 0, &lod, &reference));
                cr_expect(meshes_equal(&fast, &reference), "level %d, mask 0x%x, %s", level, (unsigned)masks[m],
                          source ? "terrain" : "blob");
                compared++;
                with_triangles += fast.index_count > 0;
                terrain_mesh_free(&fast);
                terrain_mesh_free(&reference);
            }
    }
    cr_expect_eq(compared, 36);
    cr_expect_eq(with_triangles, 36);
    terrain_world_destroy(world);
}

Test(terrain_lod, bad_requests_are_refused) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(1) });
    terrain_mesh mesh;
    cr_expect_not(terrain_mesh_chunk(world, 0, 0, 0, &(terrain_lod_desc){ .level = -1 }, &mesh));
    cr_expect_not(terrain_mesh_chunk(world, 0, 0, 0, &(terrain_lod_desc){ .level = 17 }, &mesh));
    cr_expect_not(terrain_mesh_chunk(world, 0, 0, 0, &(terrain_lod_desc){ .level = 0, .finer_neighbours = 1 }, &mesh));
    cr_expect_not(terrain_mesh_chunk(world, 0, 0, 0, &(terrain_lod_desc){ .level = 1, .finer_neighbours = 1u << 26 }, &mesh));
    cr_expect_eq(terrain_lod_neighbour_bit(0, 0, 0), 0u);
    cr_expect_eq(terrain_lod_neighbour_bit(-1, -1, -1), 1u);
    cr_expect_eq(terrain_lod_neighbour_bit(1, 1, 1), 1u << 25);
    cr_expect_eq(terrain_lod_neighbour_bit(1, 0, 0), 1u << 13);   /* index 14, one above the centre */
    terrain_world_destroy(world);
}
