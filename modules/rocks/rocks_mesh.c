/* rocks_mesh.c — an eroded rock's meshes, levels of detail, anchors and hull (001 §5–§6).
 *
 * The field r = 2ρ − 1 at voxel centres (001 §5), −1 outside the rock; the box carries a border
 * of empty voxels, so every surface closes. The surface is the dual contouring of r at two voxels
 * (rocks_surface.c: about a quarter of marching cubes' triangles, its vertices fitted to marching
 * cubes' points), or, where that cannot follow the rock, marching cubes of r itself
 * (terrain_mesh_build, f > 0 solid). LOD 0 is simplified from it (rocks_simplify.c, error ≤ 0.5
 * voxel from the dual surface, 0.6 from marching cubes: a voxel-grid surface has far more
 * triangles than its shape needs, and the set must stay small), LOD 1 and 2 aim at 1/4 and 1/12
 * of LOD 0's triangles, all in one run of the simplifier, which keeps closed meshes closed (each
 * edge in exactly two triangles). A level that still comes out not closed falls back to the
 * level above it, so every level is watertight.
 */
#include "rocks_internal.h"

#include "core/core.h"

#include <math.h>
#include <string.h>

/* The corner after corner k of triangle t: the end of its k-th directed edge. */
static inline uint32_t edge_end(const uint32_t *indices, uint32_t t, int k) { return indices[t + (k == 2 ? 0 : k + 1)]; }

/* Closed means each directed edge once and its reverse once. The vertices the triangles use are
 * numbered 0, 1, … in order of first use; up to 256 of them (a rock's levels of detail: ~40),
 * the directed edges are bits of a 256-column matrix, so each test is one bit. */
#define DENSE_VERTICES 256

static bool watertight_dense(const uint32_t *indices, uint32_t index_count, const uint16_t *number, uint32_t used) {
    uint64_t edges[DENSE_VERTICES][DENSE_VERTICES / 64];
    memset(edges, 0, used * sizeof edges[0]);
    for (uint32_t t = 0; t < index_count; t += 3)
        for (int k = 0; k < 3; k++) {
            uint32_t a = number[indices[t + k]], b = number[edge_end(indices, t, k)];
            uint64_t bit = 1ull << (b % 64);
            if (edges[a][b / 64] & bit) return false;   /* a directed edge twice */
            edges[a][b / 64] |= bit;
        }
    for (uint32_t t = 0; t < index_count; t += 3)
        for (int k = 0; k < 3; k++) {
            uint32_t a = number[indices[t + k]], b = number[edge_end(indices, t, k)];
            if (!(edges[b][a / 64] >> (a % 64) & 1)) return false;   /* no reverse */
        }
    return true;
}

/* More vertices: directed edges bucketed by their first vertex (a counting sort, O(n)). */
static bool watertight_buckets(const uint32_t *indices, uint32_t index_count, uint32_t vertex_count) {
    const size_t words = 2 * ((size_t)vertex_count + 1) + index_count;   /* first, fill, to: one block */
    uint32_t *first = core_alloc(words * sizeof *first), *fill = first + vertex_count + 1, *to = fill + vertex_count + 1;
    memset(first, 0, ((size_t)vertex_count + 1) * sizeof *first);
    for (uint32_t t = 0; t < index_count; t += 3)
        for (int k = 0; k < 3; k++) first[indices[t + k] + 1]++;
    for (uint32_t v = 0; v < vertex_count; v++) first[v + 1] += first[v];
    memcpy(fill, first, ((size_t)vertex_count + 1) * sizeof *fill);
    for (uint32_t t = 0; t < index_count; t += 3)
        for (int k = 0; k < 3; k++) to[fill[indices[t + k]]++] = edge_end(indices, t, k);
    bool ok = true;
    for (uint32_t a = 0; a < vertex_count && ok; a++)
        for (uint32_t e = first[a]; e < first[a + 1] && ok; e++) {
            uint32_t b = to[e];
            for (uint32_t f = e + 1; f < first[a + 1]; f++)
                if (to[f] == b) ok = false;   /* a directed edge twice */
            bool back = false;
            for (uint32_t f = first[b]; f < first[b + 1] && !back; f++) back = to[f] == a;
            ok &= back;
        }
    core_free(first, words * sizeof *first);
    return ok;
}

bool rocks__watertight(const uint32_t *indices, uint32_t index_count, uint32_t vertex_count) {
    if (index_count == 0 || index_count % 3) return false;
    for (uint32_t t = 0; t < index_count; t += 3)
        for (int k = 0; k < 3; k++) {
            uint32_t a = indices[t + k], b = edge_end(indices, t, k);
            if (a == b || a >= vertex_count) return false;   /* a degenerate triangle, or no such vertex */
        }
    uint16_t small[1024], *number = vertex_count <= 1024 ? small : core_alloc(vertex_count * sizeof *number);
    memset(number, 0xff, vertex_count * sizeof *number);
    uint32_t used = 0;
    for (uint32_t i = 0; i < index_count && used <= DENSE_VERTICES; i++)
        if (number[indices[i]] == UINT16_MAX) number[indices[i]] = (uint16_t)used++;
    bool ok = used <= DENSE_VERTICES ? watertight_dense(indices, index_count, number, used)
                                     : watertight_buckets(indices, index_count, vertex_count);
    if (number != small) core_free(number, vertex_count * sizeof *number);
    return ok;
}

/* Simplification, in voxels of error and shares of LOD 0's triangles. LOD 0 at 0.6 voxel keeps
 * about 75 triangles a rock of the round set (the marching-cubes mesh has ~1 350; at 0.25 voxel
 * meshoptimizer kept 294, and the default set held 89 MB): a rock's facets stay under 4 cm at
 * the game's 3 m tiles. LOD 2 is what most rocks in view draw (past 35 m), so it goes as far as
 * 8 voxels. */
#define DUAL_LOD0_ERROR 0.5f    /* from the dual surface, which already strays a little from the
                                   voxels' crossings: at 0.5 LOD 0 keeps as many triangles as from
                                   marching cubes at 0.6, and lies nearer to them (rocks_surface.c) */
#define LOD1_ERROR 2.0f
#define LOD1_SHARE 4
#define LOD2_ERROR 8.0f
#define LOD2_SHARE 12

/* One round of farthest-point sampling over the centres (padded to groups of eight): each
 * centre's squared distance to the anchors so far, lowered by the last one (bx, by, bz), and the
 * first centre at the largest. Eight lanes of fixed length, which the compiler vectorises: each
 * lane keeps its first centre at its maximum, then the least index among the lanes at the
 * maximum, as one scan in order would. Compiled twice (below); the lanes do the scalar
 * operations in the same order, with no FMA, so both give the same bits. Returns the centre, or
 * −1 when none is farther than 0. */
static inline __attribute__((always_inline)) ptrdiff_t farthest_centre(const float *restrict cx, const float *restrict cy,
                                                                      const float *restrict cz, float *restrict nearest,
                                                                      size_t padded, float bx, float by, float bz) {
    float far[8];
    int32_t at[8];
    for (int j = 0; j < 8; j++) far[j] = -1.0f, at[j] = j;
    for (size_t i = 0; i < padded; i += 8) {
        float near[8];
        for (int j = 0; j < 8; j++) {   /* branch-free, so it vectorises */
            float d2 = 0.0f;
            d2 += (cx[i + j] - bx) * (cx[i + j] - bx);
            d2 += (cy[i + j] - by) * (cy[i + j] - by);
            d2 += (cz[i + j] - bz) * (cz[i + j] - bz);
            near[j] = d2 < nearest[i + j] ? d2 : nearest[i + j];
        }
        for (int j = 0; j < 8; j++) {
            nearest[i + j] = near[j];
            int32_t further = -(int32_t)(near[j] > far[j]);
            far[j] = near[j] > far[j] ? near[j] : far[j];
            at[j] = (at[j] & ~further) | ((int32_t)(i + (size_t)j) & further);
        }
    }
    int lane = 0;
    for (int j = 1; j < 8; j++)
        if (far[j] > far[lane] || (far[j] == far[lane] && at[j] < at[lane])) lane = j;
    return far[lane] > 0.0f ? (ptrdiff_t)at[lane] : -1;
}

static ptrdiff_t farthest_baseline(const float *cx, const float *cy, const float *cz, float *nearest, size_t padded,
                                   float bx, float by, float bz) {
    return farthest_centre(cx, cy, cz, nearest, padded, bx, by, bz);
}

#if ROCKS__HAS_AVX2
__attribute__((target("avx2"))) static ptrdiff_t farthest_avx2(const float *cx, const float *cy, const float *cz,
                                                               float *nearest, size_t padded, float bx, float by,
                                                               float bz) {
    return farthest_centre(cx, cy, cz, nearest, padded, bx, by, bz);
}
#else
#define farthest_avx2 farthest_baseline
#endif

/* Anchors (001 §6): the seed, then voxel centres with ρ ≥ ½ spread by farthest-point sampling.
 * 001 uses every voxel centre; 15 spread ones bound the cost of testing a rock against the
 * support (placement stays under 0.5 ms a chunk) and still see where it lies. The centres are
 * kept as three arrays padded to groups of eight (a pad's distance is −1, never the farthest).
 * Returns the count written. */
static uint32_t spread_anchors(const float *rho, const int box_lo[3], const int size[3], const float seed_pos[3],
                               float tile_scale, float (*anchors)[3]) {
    const size_t total = (size_t)size[0] * size[1] * size[2], room = (total + 7) & ~(size_t)7;
    float *centres = core_alloc(4 * room * sizeof *centres);
    float *restrict cx = centres, *restrict cy = cx + room, *restrict cz = cy + room, *restrict nearest = cz + room;
    size_t c = 0;
    for (int z = 0; z < size[2]; z++)
        for (int y = 0; y < size[1]; y++)
            for (int x = 0; x < size[0]; x++) {
                if (rho[((size_t)z * size[1] + y) * size[0] + x] < 0.5f) continue;
                cx[c] = ((float)(box_lo[0] + x) + 0.5f) * tile_scale;
                cy[c] = ((float)(box_lo[1] + y) + 0.5f) * tile_scale;
                cz[c] = ((float)(box_lo[2] + z) + 0.5f) * tile_scale;
                nearest[c++] = INFINITY;   /* the first round measures from the seed */
            }
    const size_t padded = (c + 7) & ~(size_t)7;
    for (; c < padded; c++) cx[c] = cy[c] = cz[c] = 0.0f, nearest[c] = -1.0f;
    memcpy(anchors[0], seed_pos, 3 * sizeof *seed_pos);
    const bool wide = rocks__lanes_wide();
    uint32_t count = 1;
    float bx = seed_pos[0], by = seed_pos[1], bz = seed_pos[2];
    while (count < ROCKS__ANCHORS) {
        ptrdiff_t best = wide ? farthest_avx2(cx, cy, cz, nearest, padded, bx, by, bz)
                              : farthest_baseline(cx, cy, cz, nearest, padded, bx, by, bz);
        if (best < 0) break;
        bx = cx[best], by = cy[best], bz = cz[best];
        anchors[count][0] = bx, anchors[count][1] = by, anchors[count][2] = bz;
        count++;
    }
    core_free(centres, 4 * room * sizeof *centres);
    return count;
}

/* The levels in one run of the simplifier (rocks_simplify.c). A level that is not closed (the
 * simplifier keeps closed meshes closed, so only a marching-cubes mesh that is not would) is the
 * level above it, or the input for LOD 0. */
static void make_lods(const uint32_t *indices, size_t index_count, const float *positions, size_t vertex_count,
                      float lod0_error, uint32_t *lod[ROCKS_LODS], size_t lod_count[ROCKS_LODS]) {
    const float error[ROCKS_LODS] = { lod0_error, LOD1_ERROR, LOD2_ERROR };
    static const size_t share[ROCKS_LODS] = { 0, LOD1_SHARE, LOD2_SHARE };
    rocks__simplifier *simplifier = rocks__simplify_begin(indices, index_count, positions, vertex_count);
    for (int l = 0; l < ROCKS_LODS; l++) {
        size_t target = l == 0 ? 0 : (lod_count[0] / (3 * share[l])) * 3;
        lod_count[l] = rocks__simplify_run(simplifier, error[l], target, lod[l]);
        if (lod_count[l] == 0 || !rocks__watertight(lod[l], (uint32_t)lod_count[l], (uint32_t)vertex_count)) {
            const uint32_t *above = l == 0 ? indices : lod[l - 1];
            lod_count[l] = l == 0 ? index_count : lod_count[l - 1];
            memcpy(lod[l], above, lod_count[l] * sizeof *lod[l]);
        }
    }
    rocks__simplify_end(simplifier);
}

/* The rock's surface in voxels: the dual contouring at two voxels (rocks_surface.c) where it
 * follows the voxels, else marching cubes of r on the voxel grid (001 §5). False when nothing
 * of the rock is left. */
static bool rock_surface(const float *rho, const int size[3], rocks__surface *out, bool *dual) {
    *dual = rocks__dual_surface(rho, size, out);
    if (*dual) return true;
    const size_t total = (size_t)size[0] * size[1] * size[2];
    terrain_field field = { .nx = size[0], .ny = size[1], .nz = size[2], .spacing = 1.0f };
    field.values = core_alloc(total * sizeof *field.values);
    for (size_t i = 0; i < total; i++) {
        float r = 2.0f * rho[i] - 1.0f;
        field.values[i] = r == 0.0f ? 1e-6f : r;   /* ρ = ½ counts as solid, like the anchors */
    }
    terrain_mesh mesh;
    bool built = terrain_mesh_build(&field, &(terrain_mesh_desc){ .no_occlusion = true, .no_optimize = true }, &mesh);
    core_free(field.values, total * sizeof *field.values);
    if (!built) return false;
    if (mesh.index_count == 0) {
        terrain_mesh_free(&mesh);
        return false;
    }
    memset(out, 0, sizeof *out);
    out->vertex_count = mesh.vertex_count, out->index_count = mesh.index_count, out->index_cap = mesh.index_count;
    out->positions = core_alloc(3 * ((size_t)mesh.vertex_count + 1) * sizeof *out->positions);
    out->normals = core_alloc(3 * ((size_t)mesh.vertex_count + 1) * sizeof *out->normals);
    for (uint32_t v = 0; v < mesh.vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            out->positions[3 * v + a] = mesh.vertices[v].position[a];
            out->normals[3 * v + a] = mesh.vertices[v].normal[a];
        }
    out->indices = core_alloc(mesh.index_count * sizeof *out->indices);
    memcpy(out->indices, mesh.indices, mesh.index_count * sizeof *out->indices);
    terrain_mesh_free(&mesh);
    return true;
}

#define GROW(res, field, cap, needed) ((res)->field = core_grow((res)->field, &(res)->cap, (needed), sizeof *(res)->field))

bool rocks__rock_mesh(const rocks__params *params, const float *rho, const int box_lo[3], const int size[3],
                      const rocks__seed *seed, rocks__region_result *res, rocks_rock *rock) {
    const size_t total = (size_t)size[0] * size[1] * size[2];
    const int m = params->m;
    const float tile_scale = 1.0f / (float)(params->n * m);
    memset(rock, 0, sizeof *rock);
    bool any = false;
    for (size_t i = 0; i < total && !any; i++) any = rho[i] >= 0.5f;
    if (!any) return false;   /* eroded away: 001 §7's counts are below the seed counts */

    rocks__surface surface;
    bool dual;
    if (!rock_surface(rho, size, &surface, &dual)) return false;
    size_t vc = surface.vertex_count, ic = surface.index_count;
    const size_t words = ROCKS_LODS * ic + vc;   /* the levels' indices and the remap: one block */
    uint32_t *block = core_alloc(words * sizeof *block), *lod[ROCKS_LODS], *remap = block + ROCKS_LODS * ic;
    size_t lod_count[ROCKS_LODS];
    for (int l = 0; l < ROCKS_LODS; l++) lod[l] = block + l * ic;
    make_lods(surface.indices, ic, surface.positions, vc, dual ? DUAL_LOD0_ERROR : ROCKS__LOD0_ERROR, lod, lod_count);

    /* Keep LOD 0's vertices only, in order of first use (the others use a subset of them). */
    for (size_t v = 0; v < vc; v++) remap[v] = UINT32_MAX;
    uint32_t used = 0;
    for (size_t i = 0; i < lod_count[0]; i++)
        if (remap[lod[0][i]] == UINT32_MAX) remap[lod[0][i]] = used++;
    if (used > UINT16_MAX) core_fatal("rocks", "a rock with %u vertices (16-bit indices)", used);   /* ~10³ at most */

    rock->vertex_first = res->vertex_count;
    rock->vertex_count = used;
    GROW(res, vertices, vertex_cap, res->vertex_count + used);
    rocks_vertex *out = res->vertices + res->vertex_count;
    float seed_pos[3];
    for (int a = 0; a < 3; a++) seed_pos[a] = ((float)(seed->cell[a] * m) + seed->u[a]) * tile_scale;
    for (int a = 0; a < 3; a++) rock->bounds_min[a] = INFINITY, rock->bounds_max[a] = -INFINITY;
    for (int a = 0; a < ROCKS_HULL_AXES; a++) rock->hull[2 * a] = INFINITY, rock->hull[2 * a + 1] = -INFINITY;
    float radius2 = 0.0f;
    for (size_t v = 0; v < vc; v++) {
        if (remap[v] == UINT32_MAX) continue;
        rocks_vertex *o = &out[remap[v]];
        memset(o, 0, sizeof *o);
        float d2 = 0.0f;
        for (int a = 0; a < 3; a++) {
            float p = ((float)box_lo[a] + 0.5f + surface.positions[3 * v + a]) * tile_scale;
            o->position[a] = p;
            o->normal[a] = (int8_t)lrintf(fmaxf(-1.0f, fminf(1.0f, surface.normals[3 * v + a])) * 127.0f);
            if (p < rock->bounds_min[a]) rock->bounds_min[a] = p;
            if (p > rock->bounds_max[a]) rock->bounds_max[a] = p;
            d2 += (p - seed_pos[a]) * (p - seed_pos[a]);
        }
        if (d2 > radius2) radius2 = d2;
        for (int h = 0; h < ROCKS_HULL_AXES; h++) {
            const float *axis = rocks_hull_axes[h];
            float d = axis[0] * o->position[0] + axis[1] * o->position[1] + axis[2] * o->position[2];
            if (d < rock->hull[2 * h]) rock->hull[2 * h] = d;
            if (d > rock->hull[2 * h + 1]) rock->hull[2 * h + 1] = d;
        }
    }
    rock->radius = sqrtf(radius2);
    res->vertex_count += used;

    size_t all = lod_count[0] + lod_count[1] + lod_count[2];
    GROW(res, indices, index_cap, res->index_count + all);
    for (int l = 0; l < ROCKS_LODS; l++) {
        rock->index_first[l] = res->index_count;
        rock->index_count[l] = (uint32_t)lod_count[l];
        for (size_t i = 0; i < lod_count[l]; i++) res->indices[res->index_count++] = (uint16_t)remap[lod[l][i]];
    }
    core_free(block, words * sizeof *block);
    rocks__surface_free(&surface);

    rock->anchor_first = res->anchor_count;
    GROW(res, anchors, anchor_cap, res->anchor_count + ROCKS__ANCHORS);
    uint32_t anchor_count = spread_anchors(rho, box_lo, size, seed_pos, tile_scale, res->anchors + res->anchor_count);
    rock->anchor_count = anchor_count;
    res->anchor_count += anchor_count;
    return true;
}
