/* terrain_mesh.c — marching cubes over a terrain_field (000 §6: "standard polygonization
 * techniques"), with shared vertices, gradient normals and material weights.
 *
 * One vertex per crossed grid edge, shared by the cells around it. The cells are found and
 * numbered by edge-based passes over rows of samples in the style of Flying Edges (Schroeder et
 * al. 2015; "the cells" below): rows whose samples all agree with their neighbours' cost a word
 * test, the others are visited only at the cells their signs say are crossed, and a prefix sum
 * gives each row its place in the output, so big fields split over the job system's threads
 * without locks and with the same result. The cell's triangles come from the case table of
 * terrain_mesh_tables.c, whose ambiguous faces are resolved from the face's signs alone (inside
 * corners kept apart), so neighbouring cells agree and closed surfaces come out watertight.
 *
 * Positions: along an edge from sample s₀ to s₁ (always from the lower index, so every mesh
 * that has the edge computes the same number) t = f₀ / (f₀ − f₁), rounded to 1/8192. With the
 * sample index below 2048 the coordinate (index + t)·spacing is then exact in a float, so two
 * chunks whose grids share a face place their border vertices at bit-identical world positions
 * (origin + position, in double) even though their origins differ.
 *
 * Normals: −∇f (f > 0 inside, so −∇f points into the air) from central differences on the grid
 * (one-sided on the field's outermost samples), interpolated along the edge with the same t.
 * The apron samples are read for these differences but their cells are not meshed.
 *
 * Material weights (000 §6: textures blended "according to the ratio of neighboring
 * materials"): we read "neighbouring materials" as what a one-metre vertical segment centred half
 * a column inside the surface (along −n) holds: the exact length of each material's layers in it
 * (the stacks are run-length layers), in the four columns around it with bilinear weights, scaled
 * to 255 (all bedrock when only air is found, or without a world). Continuous in the vertex's
 * position: no bands (the 8 point samples this replaced gave 9 levels).
 *
 * Occlusion (terrain_vertex.occlusion, "openness" = 1 − occlusion/255): how much of the sky the
 * vertex sees within 8 m, from rays through the stacks' solid slabs (below, "openness"). Like the
 * weights, a function of the vertex's world position and normal only, so chunks agree on their
 * shared vertices; computed once here, so the renderer pays nothing a frame for it.
 *
 * Then the triangles are reordered for the GPU's vertex cache with meshoptimizer (unless
 * desc.no_optimize). The arrays have their exact sizes (terrain_mesh_free needs them). A field
 * whose meshed samples all have one sign costs one pass over them and no output.
 */
#define _DEFAULT_SOURCE   /* madvise's MADV_HUGEPAGE */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include "jobs/jobs.h"

#include <inttypes.h>
#include <math.h>
#include <meshoptimizer.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

typedef terrain__mesh_builder mesh_builder;   /* terrain_internal.h (terrain_lod.c builds one too) */

/* ---- vertices ------------------------------------------------------------------------------ */

/* ∂f along each axis at sample (x, y, z), up to the common factor 1/spacing. */
static void mesh_gradient(const mesh_builder *b, int x, int y, int z, float g[3]) {
    const float *v = b->field->values;
    const int at[3] = { x, y, z };
    const size_t stride[3] = { 1, (size_t)b->n[0], b->slice };
    size_t here = (size_t)z * b->slice + (size_t)y * b->n[0] + (size_t)x;
    for (int a = 0; a < 3; a++) {
        if (at[a] > 0 && at[a] < b->n[a] - 1) g[a] = 0.5f * (v[here + stride[a]] - v[here - stride[a]]);
        else if (at[a] > 0) g[a] = v[here] - v[here - stride[a]];
        else if (at[a] < b->n[a] - 1) g[a] = v[here + stride[a]] - v[here];
        else g[a] = 0.0f;
    }
}

/* The gradient at an interior sample: the central differences of mesh_gradient, no branches. */
static inline void mesh_gradient_inside(const mesh_builder *b, const float *at, float g[3]) {
    const size_t row = (size_t)b->n[0];
    g[0] = 0.5f * (at[1] - at[-1]);
    g[1] = 0.5f * (at[row] - at[-(ptrdiff_t)row]);
    g[2] = 0.5f * (at[b->slice] - at[-(ptrdiff_t)b->slice]);
}

/* Fills *v with the vertex on the edge from sample (x, y, z) one step along `axis`; its two
 * samples have values f0 (at the lower index) and f1 of different signs. */
static void mesh_make_vertex(const mesh_builder *b, terrain_vertex *v, int x, int y, int z, int axis, float f0, float f1) {
    float t = terrain__mesh_edge_t(f0, f1);
    const float spacing = b->field->spacing;
    v->position[0] = (float)x * spacing;
    v->position[1] = (float)y * spacing;
    v->position[2] = (float)z * spacing;
    v->position[axis] = ((float)(axis == 0 ? x : axis == 1 ? y : z) + t) * spacing;
    const int x1 = x + (axis == 0), y1 = y + (axis == 1), z1 = z + (axis == 2);
    float g0[3], g1[3];
    if (x > 0 && y > 0 && z > 0 && x1 < b->n[0] - 1 && y1 < b->n[1] - 1 && z1 < b->n[2] - 1) {
        const float *at = b->field->values + (size_t)z * b->slice + (size_t)y * (size_t)b->n[0] + (size_t)x;
        const size_t step = axis == 0 ? 1 : axis == 1 ? (size_t)b->n[0] : b->slice;
        mesh_gradient_inside(b, at, g0);
        mesh_gradient_inside(b, at + step, g1);
    } else {
        mesh_gradient(b, x, y, z, g0);
        mesh_gradient(b, x1, y1, z1, g1);
    }
    float g[3], length2 = 0.0f;
    for (int a = 0; a < 3; a++) {
        g[a] = g0[a] + t * (g1[a] - g0[a]);
        length2 += g[a] * g[a];
    }
    if (length2 > 0.0f) {
        float inverse = -1.0f / sqrtf(length2);
        for (int a = 0; a < 3; a++) v->normal[a] = g[a] * inverse;
    } else {
        /* A flat field between the two samples: the edge itself is the best guess, pointing
         * from the inside sample to the outside one. */
        v->normal[0] = v->normal[1] = v->normal[2] = 0.0f;
        v->normal[axis] = f0 > 0.0f ? 1.0f : -1.0f;
    }
    v->weights[0] = 255, v->weights[1] = v->weights[2] = v->weights[3] = 0;
}

/* The same, appended to the builder's array (terrain_lod.c builds vertex by vertex). */
static uint32_t mesh_add_vertex(mesh_builder *b, int x, int y, int z, int axis, float f0, float f1) {
    b->vertices = core_grow(b->vertices, &b->vertex_capacity, b->vertex_count + 1, sizeof *b->vertices);
    mesh_make_vertex(b, &b->vertices[b->vertex_count], x, y, z, axis, f0, f1);
    return (uint32_t)b->vertex_count++;
}

/* ---- material weights (000 §6) ----------------------------------------------------------- */

static int64_t mesh_floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

static int64_t mesh_floor(double v) {
    int64_t i = (int64_t)v;
    return i - ((double)i > v);
}

typedef struct mesh_material_probe {
    terrain_world *world;
    terrain_chunk_coord chunk;
    const terrain_stacks *stacks;
} mesh_material_probe;

/* A cursor at the bottom of global column (gx, gz), the probe keeping the last chunk's stacks
 * (neighbouring vertices and columns mostly share one). */
static terrain__column_cursor mesh_probe_cursor(mesh_material_probe *probe, int64_t gx, int64_t gz) {
    terrain_chunk_coord chunk = { mesh_floor_div(gx, TERRAIN_CHUNK_COLUMNS), mesh_floor_div(gz, TERRAIN_CHUNK_COLUMNS) };
    if (!probe->stacks || chunk.x != probe->chunk.x || chunk.z != probe->chunk.z) {
        probe->stacks = terrain_world_stacks(probe->world, chunk);
        probe->chunk = chunk;
    }
    return terrain__stacks_cursor(probe->stacks, (int)(gx - chunk.x * TERRAIN_CHUNK_COLUMNS),
                                  (int)(gz - chunk.z * TERRAIN_CHUNK_COLUMNS));
}

/* The columns of a window [x0, x0 + width) × [z0, z0 + depth), their layers decoded once: the
 * weights read each column for several vertices (about four lookups a column in a chunk), and
 * walking the packed words each time cost more than the weights' arithmetic. */
typedef struct mesh_columns {
    int64_t x0, z0;
    int width, depth;
    uint32_t *first;               /* width·depth + 1: column c's layers are first[c] … first[c + 1] − 1 */
    uint32_t *base;                /* width·depth: the bottom of column c's first kept layer */
    uint32_t *top;                 /* each layer's top, quanta above the floor */
    uint8_t *slot;                 /* each layer's material: 0 … 3 for bedrock … water, 4 invisible */
    size_t capacity;               /* of top and slot */
} mesh_columns;

/* Keeps only the layers that reach into the heights [lo, hi] metres (what the callers will read):
 * a column's layers start at the floor, 256 m below sea level, and stepping over the ones under
 * the surface cost the weights more than their arithmetic. */
static void mesh_columns_make(mesh_columns *c, terrain_world *world, int64_t x0, int64_t z0, int width, int depth,
                              double lo, double hi) {
    *c = (mesh_columns){ .x0 = x0, .z0 = z0, .width = width, .depth = depth, .capacity = 256 };
    size_t columns = (size_t)width * (size_t)depth;
    c->first = core_alloc((columns + 1) * sizeof *c->first);
    c->base = core_alloc(columns * sizeof *c->base);
    c->top = core_alloc(c->capacity * sizeof *c->top);
    c->slot = core_alloc(c->capacity);
    const double q_lo = (lo - TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE, q_hi = (hi - TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE;
    mesh_material_probe probe = { .world = world };
    uint32_t count = 0;
    for (int k = 0; k < depth; k++)
        for (int i = 0; i < width; i++) {
            size_t column = (size_t)k * (size_t)width + (size_t)i;
            c->first[column] = count;
            c->base[column] = 0;
            terrain__column_cursor cursor = mesh_probe_cursor(&probe, x0 + i, z0 + k);
            terrain__qlayer layer;
            uint32_t height = 0;
            while ((double)height < q_hi && terrain__cursor_next(&cursor, &layer)) {
                height += layer.quanta;
                if ((double)height <= q_lo) {   /* wholly under the heights read */
                    c->base[column] = height;
                    continue;
                }
                if (count == c->capacity) {
                    c->top = core_realloc(c->top, c->capacity * sizeof *c->top, 2 * c->capacity * sizeof *c->top);
                    c->slot = core_realloc(c->slot, c->capacity, 2 * c->capacity);
                    c->capacity *= 2;
                }
                unsigned material = layer.material;
                c->top[count] = height;
                c->slot[count++] = (uint8_t)(material >= TERRAIN_BEDROCK && material <= TERRAIN_WATER ? material - TERRAIN_BEDROCK : 4);
            }
        }
    c->first[columns] = count;
}

static void mesh_columns_free(mesh_columns *c) {
    size_t columns = (size_t)c->width * (size_t)c->depth;
    core_free(c->first, (columns + 1) * sizeof *c->first);
    core_free(c->base, columns * sizeof *c->base);
    core_free(c->top, c->capacity * sizeof *c->top);
    core_free(c->slot, c->capacity);
}

/* Adds w × the length (in quanta) of each visible material's layers inside [y0, y1] metres in
 * global column (gx, gz) of the window to sums[bedrock … water] (below the floor is bedrock,
 * above the last layer air, as terrain_stacks_material_at reads a column). The stacks are
 * run-length layers, so the overlap of the segment with each layer is exact. Layers wholly
 * under y0 add nothing and are stepped over. */
static void mesh_column_overlaps(const mesh_columns *c, int64_t gx, int64_t gz, double y0, double y1, double w,
                                 double sums[5]) {
    const double q0 = (y0 - TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE, q1 = (y1 - TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE;
    if (q0 < 0.0) sums[0] += w * ((q1 < 0.0 ? q1 : 0.0) - q0);
    int64_t i = gx - c->x0, k = gz - c->z0;
    if (i < 0 || i >= c->width || k < 0 || k >= c->depth) return;   /* never for a unit normal: read as air */
    size_t column = (size_t)k * (size_t)c->width + (size_t)i;
    uint32_t layer = c->first[column], end = c->first[column + 1];
    while (layer < end && (double)c->top[layer] <= q0) layer++;
    double bottom = layer > c->first[column] ? (double)c->top[layer - 1] : (double)c->base[column];
    /* Without a branch on the overlap or the material (which are not predictable): a layer
     * outside the segment adds +0, an invisible material goes to slot 4. */
    for (; layer < end && bottom < q1; layer++) {
        double top = (double)c->top[layer], lo = q0 > bottom ? q0 : bottom, hi = q1 < top ? q1 : top;
        double length = hi - lo;
        sums[c->slot[layer]] += w * (length > 0.0 ? length : 0.0);
        bottom = top;
    }
}

/* The segment's centre for a vertex at p with normal n (below), and the first of the four columns
 * around it with its tent weights. */
static void mesh_weights_segment(const double p[3], const float n[3], double centre[3], int64_t *gx0, int64_t *gz0,
                                 double *fx, double *fz) {
    const double half = 0.5 * TERRAIN_COLUMN_SIZE;
    for (int a = 0; a < 3; a++) centre[a] = p[a] - half * n[a];
    /* Column centres sit at (g + ½)·c: the four around the centre and the tent's weights. */
    double u = centre[0] / TERRAIN_COLUMN_SIZE - 0.5, v = centre[2] / TERRAIN_COLUMN_SIZE - 0.5;
    *gx0 = mesh_floor(u), *gz0 = mesh_floor(v);
    *fx = u - (double)*gx0, *fz = v - (double)*gz0;
}

/* The weights of one vertex at world position p with normal n (000 §6, "according to the ratio
 * of neighboring materials"). We read "neighbouring materials" as what a one-metre segment just
 * under the surface holds: centred half a column inside along −n, vertical, ±½ column, and
 * integrated over x and z with a tent (bilinear) kernel one column wide, i.e. over the four
 * columns whose centres surround the segment's centre. Each material weighs the exact length of
 * its layers inside the segment, so the weights move continuously with the vertex (8 point
 * samples gave 9 levels, which banded), and only from world position and normal: shared border
 * vertices get the same bytes in every chunk. The window c holds the four columns. */
static void mesh_vertex_weights(const mesh_columns *c, const double p[3], const float n[3], uint8_t out[4]) {
    const double half = 0.5 * TERRAIN_COLUMN_SIZE;
    double centre[3], fx, fz;
    int64_t gx0, gz0;
    mesh_weights_segment(p, n, centre, &gx0, &gz0, &fx, &fz);
    double sums[5] = { 0, 0, 0, 0, 0 };   /* bedrock … water, and the invisible ones */
    for (int column = 0; column < 4; column++) {
        double w = ((column & 1) ? fx : 1.0 - fx) * ((column >> 1) ? fz : 1.0 - fz);
        if (w > 0.0)
            mesh_column_overlaps(c, gx0 + (column & 1), gz0 + (column >> 1), centre[1] - half, centre[1] + half, w, sums);
    }
    double total = sums[0] + sums[1] + sums[2] + sums[3];
    out[0] = 255, out[1] = out[2] = out[3] = 0;
    if (!(total > 0.0)) return;   /* only air around (a sliver): keep bedrock */
    int sum = 0, largest = 0;
    for (int m = 0; m < 4; m++) {
        out[m] = (uint8_t)floor(255.0 * sums[m] / total + 0.5);
        sum += out[m];
        if (sums[m] > sums[largest]) largest = m;
    }
    out[largest] = (uint8_t)(out[largest] + 255 - sum);   /* they sum to 255 */
}

void terrain__mesh_vertex_weights(terrain_world *world, const double p[3], const float n[3], uint8_t out[4]) {
    double centre[3], fx, fz;
    int64_t gx0, gz0;
    mesh_weights_segment(p, n, centre, &gx0, &gz0, &fx, &fz);
    mesh_columns columns;
    const double half = 0.5 * TERRAIN_COLUMN_SIZE;
    mesh_columns_make(&columns, world, gx0, gz0, 2, 2, centre[1] - half, centre[1] + half);
    mesh_vertex_weights(&columns, p, n, out);
    mesh_columns_free(&columns);
}

/* The box around a mesh's vertices, relative to its origin (all 0 for no vertex). */
static void mesh_vertex_bounds(const mesh_builder *b, float lo[3], float hi[3]) {
    for (int a = 0; a < 3; a++) lo[a] = b->vertex_count ? INFINITY : 0.0f, hi[a] = b->vertex_count ? -INFINITY : 0.0f;
    for (size_t i = 0; i < b->vertex_count; i++)
        for (int a = 0; a < 3; a++) {
            float p = b->vertices[i].position[a];
            lo[a] = p < lo[a] ? p : lo[a], hi[a] = p > hi[a] ? p : hi[a];
        }
}

/* Every vertex's weights, from one window of decoded columns over the vertices' world box lo …
 * hi: a segment's centre lies within half a column of its vertex, its four columns within one
 * more, and its ends within a column of the vertex's height. */
static void mesh_weights(const mesh_builder *b, terrain_world *world, const double origin[3], const double lo[3],
                         const double hi[3]) {
    if (b->vertex_count == 0) return;
    int64_t x0 = mesh_floor(lo[0] / TERRAIN_COLUMN_SIZE) - 2, z0 = mesh_floor(lo[2] / TERRAIN_COLUMN_SIZE) - 2;
    int64_t x1 = mesh_floor(hi[0] / TERRAIN_COLUMN_SIZE) + 2, z1 = mesh_floor(hi[2] / TERRAIN_COLUMN_SIZE) + 2;
    mesh_columns columns;
    mesh_columns_make(&columns, world, x0, z0, (int)(x1 - x0 + 1), (int)(z1 - z0 + 1), lo[1] - 2.0 * TERRAIN_COLUMN_SIZE,
                      hi[1] + 2.0 * TERRAIN_COLUMN_SIZE);
    for (size_t i = 0; i < b->vertex_count; i++) {
        terrain_vertex *v = &b->vertices[i];
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = origin[a] + v->position[a];
        mesh_vertex_weights(&columns, p, v->normal, v->weights);
    }
    mesh_columns_free(&columns);
}

/* ---- openness: ambient occlusion from the stacks -------------------------------------------- */

/* How much sky a vertex sees, from the terrain itself, once when the mesh is made (no cost a
 * frame; the shader scales its sky light by it). Rays leave the vertex, lifted MESH_AO_LIFT along
 * its normal, in MESH_AO_DIRECTIONS fixed directions of the hemisphere around the normal; each
 * ray reads the solid fraction s of a one-metre box at MESH_AO_STEPS distances (1, 3 and 7 m)
 * and lets through ∏(1 − strength·s), nearer solid counting more; openness is the mean over the
 * rays. The directions are spread cosine-weighted (a golden-angle spiral), so the mean
 * estimates the cosine-weighted visibility of the usual ambient-occlusion integral, and they stop
 * 60° from the normal: the stacks are 1 m stairs under a smooth surface, and grazing rays would
 * find the stair beside them on any slope. With that, a plane reads exactly 1 (measured on
 * stepped planes of 11° to 45°: the stairs stay below the lifted rays), so open ground is
 * unchanged and meets the far clipmap, which has no occlusion, without a seam.
 *
 * s is the field's own reading of the stacks (000 §3.3: solid = sand and bedrock): the exact
 * solid length of each column in each 1 m slab [J, J + 1), read trilinearly between the slabs'
 * centres, so openness changes continuously with the vertex (no bands) and depends only on its
 * world position and normal (shared border vertices agree). A mesh reads each column of a window
 * over its bounds once, into bytes of slabs. */
#define MESH_AO_DIRECTIONS 8
#define MESH_AO_STEPS 3
#define MESH_AO_LIFT 1.0
#define MESH_AO_CAP_SIN 0.8660254037844386   /* sin 60° */
#define MESH_AO_MARGIN TERRAIN__MESH_OCCLUSION_REACH   /* lift + 7 m + the tent + a slab, and 1 */
static const double mesh_ao_distance[MESH_AO_STEPS] = { 1.0, 3.0, 7.0 };
static const double mesh_ao_strength[MESH_AO_STEPS] = { 1.0, 1.0, 0.85 };

typedef struct mesh_ao {
    mesh_material_probe stacks;
    int64_t x0, z0, y0;            /* the window's first column and slab */
    int width, depth, height;      /* columns along x and z, slabs along y */
    double u_end, v_end, w_end;    /* width − 1, depth − 1, height − 1: where reads end */
    uint8_t *slabs;                /* the solid quanta in slab [J, J + 1) of each column, y fastest */
    int32_t *tops;                 /* per 2 × 2 block of columns from (i, k): no solid from this
                                      slab up in any of them */
} mesh_ao;

#define MESH_AO_MAX_SLABS (1u << 24)   /* 16 MB; a larger window (chunks of level ≥ 3) gets none */

/* Column (gx, gz)'s slabs: one walk up its layers, each slab the exact solid length inside it in
 * quanta (layers are whole quanta, so a slab holds 0 … 32 of them: a byte, exact). Below the
 * floor is bedrock. Returns the slab above its highest solid quantum. */
static int32_t mesh_ao_fill_column(mesh_ao *ao, int64_t gx, int64_t gz, uint8_t *slabs) {
    mesh_material_probe *probe = &ao->stacks;
    terrain__column_cursor cursor = mesh_probe_cursor(probe, gx, gz);
    memset(slabs, 0, (size_t)ao->height);
    /* Heights in quanta above the window's first slab; a solid run [bottom, top) fills the slabs
     * it covers and adds its ends' parts to the slabs they fall in. */
    const int64_t Q = TERRAIN__QUANTA_PER_METRE, last = (int64_t)ao->height * Q;
    int64_t height = ((int64_t)TERRAIN_FLOOR_Y - ao->y0) * Q, bottom = INT64_MIN / 2, top = 0;
    bool solid = true;
    terrain__qlayer layer;
    for (;;) {
        bool more = terrain__cursor_next(&cursor, &layer);
        bool next_solid = more && terrain_material_in_field((terrain_material)layer.material);
        bool run_ends = solid && (!more || !next_solid || height >= last);
        if (run_ends && height > 0 && bottom < last) {
            int64_t lo = bottom > 0 ? bottom : 0, hi = height < last ? height : last;
            int64_t first_full = (lo + Q - 1) / Q, end_full = hi / Q;
            if (first_full > end_full) {                       /* inside one slab */
                slabs[lo / Q] = (uint8_t)(slabs[lo / Q] + (hi - lo));
            } else {
                if (lo < first_full * Q) slabs[lo / Q] = (uint8_t)(slabs[lo / Q] + (first_full * Q - lo));
                if (end_full > first_full) memset(slabs + first_full, (int)Q, (size_t)(end_full - first_full));
                if (hi > end_full * Q) slabs[end_full] = (uint8_t)(slabs[end_full] + (hi - end_full * Q));
            }
            top = hi;
        }
        if (!more || height >= last) break;
        if (next_solid && !solid) bottom = height;
        solid = next_solid;
        height += layer.quanta;
    }
    return (int32_t)((top + Q - 1) / Q);
}

/* Every column of the window, and per 2 × 2 block of columns from (i, k) the highest of their
 * tops (a point above it reads no solid: most rays in the open stop there). */
static void mesh_ao_fill(mesh_ao *ao) {
    for (int k = 0; k < ao->depth; k++)
        for (int i = 0; i < ao->width; i++) {
            size_t column = (size_t)k * (size_t)ao->width + (size_t)i;
            ao->tops[column] = mesh_ao_fill_column(ao, ao->x0 + i, ao->z0 + k, ao->slabs + column * (size_t)ao->height);
        }
    for (int k = 0; k + 1 < ao->depth; k++)   /* in place: each block reads only later entries */
        for (int i = 0; i + 1 < ao->width; i++) {
            int32_t *t = &ao->tops[k * ao->width + i];
            int32_t a = t[0] > t[1] ? t[0] : t[1], b = t[ao->width] > t[ao->width + 1] ? t[ao->width] : t[ao->width + 1];
            t[0] = a > b ? a : b;
        }
}

/* The solid fraction around a point: the slabs' values sit at the centres of 1 m boxes (column
 * centres in x and z, slab centres in y), read trilinearly — a tent kernel one column wide in
 * each axis, so the value moves continuously with the point. The point comes in the window's
 * own units: u = x / column − ½ less the window's first column (and so for z, and y in slabs),
 * an exact shift by a whole number, so floor and fraction are those of the world's own
 * reading, and a point inside the window is ≥ 0 there, its floor a truncation. */
static double mesh_ao_solid(const mesh_ao *ao, double u, double v, double w) {
    /* The window's margin keeps every ray inside; a point outside would be a bug, read as air. */
    if (!(u >= 0.0 && u < ao->u_end && v >= 0.0 && v < ao->v_end && w >= 0.0 && w < ao->w_end)) return 0.0;
    int i = (int)u, k = (int)v, j = (int)w;
    size_t column = (size_t)k * (size_t)ao->width + (size_t)i;
    if (j >= ao->tops[column]) return 0.0;
    double fx = u - (double)i, fz = v - (double)k, fy = w - (double)j;
    const size_t row = (size_t)ao->width * (size_t)ao->height, h = (size_t)ao->height;
    const uint8_t *s00 = ao->slabs + column * h + (size_t)j, *s10 = s00 + h, *s01 = s00 + row, *s11 = s01 + h;
    double a00 = s00[0] + fy * (s00[1] - s00[0]), a10 = s10[0] + fy * (s10[1] - s10[0]);
    double a01 = s01[0] + fy * (s01[1] - s01[0]), a11 = s11[0] + fy * (s11[1] - s11[0]);
    double near = a00 + fx * (a10 - a00), far = a01 + fx * (a11 - a01);
    return (near + fz * (far - near)) * (1.0 / TERRAIN__QUANTA_PER_METRE);
}

/* Openness of one vertex (world position p, unit normal n) in [0, 1]. */
static double mesh_ao_openness(const mesh_ao *ao, const double directions[MESH_AO_DIRECTIONS][3], const double p[3],
                               const float nf[3]) {
    double n[3] = { nf[0], nf[1], nf[2] };
    /* A tangent frame continuous in n but at n = −y (Duff et al. 2017's basis, built around +y):
     * a flip of the frame would turn the rays between neighbouring vertices. */
    double t[3], b[3];
    if (n[1] > -0.9999) {
        double a = 1.0 / (1.0 + n[1]), c = -n[0] * n[2] * a;
        t[0] = 1.0 - n[0] * n[0] * a, t[1] = -n[0], t[2] = c;
        b[0] = c, b[1] = -n[2], b[2] = 1.0 - n[2] * n[2] * a;
    } else {
        t[0] = 1, t[1] = 0, t[2] = 0;
        b[0] = 0, b[1] = 0, b[2] = 1;
    }
    double start[3];
    for (int a = 0; a < 3; a++) start[a] = p[a] + MESH_AO_LIFT * n[a];
    /* Every read point first (arithmetic the compiler can do two at a time), then the reads,
     * then the rays: one loop over all three kept more values live than there are registers. */
    enum { READS = MESH_AO_DIRECTIONS * MESH_AO_STEPS };
    double u[READS], v[READS], w[READS], solid[READS];
    for (int k = 0; k < MESH_AO_DIRECTIONS; k++) {
        const double *d = directions[k];
        double ray[3];
        for (int a = 0; a < 3; a++) ray[a] = d[0] * t[a] + d[1] * b[a] + d[2] * n[a];
        for (int s = 0; s < MESH_AO_STEPS; s++) {
            double r = mesh_ao_distance[s];
            double x = start[0] + r * ray[0], y = start[1] + r * ray[1], z = start[2] + r * ray[2];
            u[k * MESH_AO_STEPS + s] = (x / TERRAIN_COLUMN_SIZE - 0.5) - (double)ao->x0;
            v[k * MESH_AO_STEPS + s] = (z / TERRAIN_COLUMN_SIZE - 0.5) - (double)ao->z0;
            w[k * MESH_AO_STEPS + s] = (y - 0.5) - (double)ao->y0;
        }
    }
    for (int q = 0; q < READS; q++) solid[q] = mesh_ao_solid(ao, u[q], v[q], w[q]);
    double open = 0.0;
    for (int k = 0; k < MESH_AO_DIRECTIONS; k++) {
        double through = 1.0;
        for (int s = 0; s < MESH_AO_STEPS; s++) through *= 1.0 - mesh_ao_strength[s] * solid[k * MESH_AO_STEPS + s];
        open += through;
    }
    return open / MESH_AO_DIRECTIONS;
}

/* lo … hi: the vertices' world box. */
static void mesh_openness(const mesh_builder *b, terrain_world *world, const double origin[3], const double lo[3],
                          const double hi[3]) {
    if (b->vertex_count == 0) return;
    /* The directions in the frame (t, b, n): cosine-weighted over the 60° cap, sin θ ∝ √u. */
    double directions[MESH_AO_DIRECTIONS][3];
    for (int k = 0; k < MESH_AO_DIRECTIONS; k++) {
        double sin_theta = MESH_AO_CAP_SIN * sqrt((k + 0.5) / MESH_AO_DIRECTIONS);
        double phi = 2.399963229728653 * k;   /* the golden angle */
        directions[k][0] = sin_theta * cos(phi);
        directions[k][1] = sin_theta * sin(phi);
        directions[k][2] = sqrt(1.0 - sin_theta * sin_theta);
    }
    mesh_ao ao = { .stacks = { .world = world } };
    ao.x0 = mesh_floor(lo[0] / TERRAIN_COLUMN_SIZE) - MESH_AO_MARGIN;
    ao.y0 = mesh_floor(lo[1]) - MESH_AO_MARGIN;
    ao.z0 = mesh_floor(lo[2] / TERRAIN_COLUMN_SIZE) - MESH_AO_MARGIN;
    ao.width = (int)(mesh_floor(hi[0] / TERRAIN_COLUMN_SIZE) + MESH_AO_MARGIN - ao.x0 + 1);
    ao.height = (int)(mesh_floor(hi[1]) + MESH_AO_MARGIN - ao.y0 + 1);
    ao.depth = (int)(mesh_floor(hi[2] / TERRAIN_COLUMN_SIZE) + MESH_AO_MARGIN - ao.z0 + 1);
    ao.u_end = ao.width - 1, ao.v_end = ao.depth - 1, ao.w_end = ao.height - 1;
    size_t column_count = (size_t)ao.width * (size_t)ao.depth, slab_count = column_count * (size_t)ao.height;
    if (slab_count > MESH_AO_MAX_SLABS) return;
    ao.slabs = core_alloc(slab_count * sizeof *ao.slabs);
    ao.tops = core_alloc(column_count * sizeof *ao.tops);
    mesh_ao_fill(&ao);
    for (size_t i = 0; i < b->vertex_count; i++) {
        terrain_vertex *v = &b->vertices[i];
        double p[3];
        for (int a = 0; a < 3; a++) p[a] = origin[a] + v->position[a];
        double open = mesh_ao_openness(&ao, (const double (*)[3])directions, p, v->normal);
        v->occlusion = (uint8_t)(255 - (int)floor(fmin(fmax(open, 0.0), 1.0) * 255.0 + 0.5));
    }
    core_free(ao.slabs, slab_count * sizeof *ao.slabs);
    core_free(ao.tops, column_count * sizeof *ao.tops);
}

/* ---- the cells: edge-based passes in the style of Flying Edges ----------------------------- */

/* Schroeder, Maynard and Geveci, "Flying Edges" (2015): rather than visiting every cell, the
 * mesher works on rows of samples along x. Each row (y, z) owns the crossed edges that start on
 * it: its x-edges, its y-edges to row (y + 1, z) and its z-edges to row (y, z + 1).
 *   1. classify: the row's signs as bits (1 = inside), its crossed x-edges counted;
 *   2. count: its crossed y- and z-edges, and the triangles of the cells between it and the rows
 *      above it (+y, +z, +y+z). A cell is visited only where its 8 corners differ, found 64 cells
 *      at a time from the four rows' bits; rows whose signs agree end to end cost one word test;
 *   3. a prefix sum over the rows gives each its first vertex and first index;
 *   4. generate: each row writes its vertices and its cells' triangles at those offsets.
 * Passes 1, 2 and 4 touch only their own rows' outputs, so with a job system they run over slabs
 * of z in parallel without locks, and the output is the same whatever the thread count. The
 * vertex ids a cell needs come from eight running counters (the x-edges of its four rows, the
 * y-edges of two, the z-edges of two), advanced at each visited cell: a skipped cell's corners all
 * agree, so no edge it owns is crossed and no counter moves past it.
 * Same case table, same edges, same vertex values as a cell-by-cell walk; only the numbering of
 * the vertices is by row. */

enum { FE_OUTSIDE, FE_INSIDE, FE_MIXED };

typedef struct fe_row {
    uint32_t x_count, y_count, z_count;   /* crossed edges the row owns along x, y and z */
    uint32_t index_count;                 /* indices of the cells between it and the rows above */
    uint32_t first_vertex, first_index;   /* its place in the output (the prefix sum) */
    uint8_t kind;                         /* FE_OUTSIDE, FE_INSIDE or FE_MIXED over lo … hi */
} fe_row;

typedef struct fe_mesher {
    mesh_builder *b;
    const terrain__mc_case *table;
    int data_words, words;       /* 64-bit words of signs per row: the data, and one spare (0) */
    int rows_y, rows_z;          /* rows of the meshed box */
    uint64_t *signs;             /* bit x of row (y, z): sample inside */
    uint64_t *edge_mask;         /* bits lo … hi along x (edge starts along y and z, samples) */
    uint64_t *cell_mask;         /* bits lo … hi − 1 (cells, x-edges) */
    fe_row *rows;
} fe_mesher;

static inline int fe_count_bits(uint64_t w) {
    /* Baseline x86-64 has no popcnt instruction (GCC calls a library routine); most words are 0. */
    if (!w) return 0;
    w = w - ((w >> 1) & 0x5555555555555555ull);
    w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
    w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return (int)((w * 0x0101010101010101ull) >> 56);
}

static inline size_t fe_row_index(const fe_mesher *m, int y, int z) {
    return (size_t)(z - m->b->lo[2]) * (size_t)m->rows_y + (size_t)(y - m->b->lo[1]);
}

static inline const uint64_t *fe_signs(const fe_mesher *m, size_t row) { return m->signs + row * (size_t)m->words; }

/* Bit x of the result is bit x + 1 of the row. */
static inline uint64_t fe_next(const uint64_t *row, int w) { return (row[w] >> 1) | (row[w + 1] << 63); }

/* Word w of the crossed edges row a owns: its x-edges (other NULL; cells lo … hi − 1), or its
 * edges to row `other` (samples lo … hi). */
static inline uint64_t fe_crossed(const fe_mesher *m, const uint64_t *a, const uint64_t *other, int w) {
    return other ? (a[w] ^ other[w]) & m->edge_mask[w] : (a[w] ^ fe_next(a, w)) & m->cell_mask[w];
}

static uint32_t fe_count_crossed(const fe_mesher *m, const uint64_t *a, const uint64_t *other) {
    int crossed = 0;
    for (int w = 0; w < m->data_words; w++) crossed += fe_count_bits(fe_crossed(m, a, other, w));
    return (uint32_t)crossed;
}

/* Pass 1 for row (y, z). */
static void fe_classify_row(fe_mesher *m, int y, int z) {
    const mesh_builder *b = m->b;
    const int n = b->n[0];
    const float *v = b->field->values + (size_t)z * b->slice + (size_t)y * (size_t)n;
    const size_t r = fe_row_index(m, y, z);
    uint64_t *s = m->signs + r * (size_t)m->words;
    /* Each word built in a register, four samples at a time where SSE2 is (every x86-64). */
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps();
#endif
    for (int w = 0; w < m->data_words; w++) {
        const float *p = v + w * 64;
        const int count = n - w * 64 < 64 ? n - w * 64 : 64;
        uint64_t bits = 0;
        int k = 0;
#if defined(__SSE2__)
        for (; k + 4 <= count; k += 4) bits |= (uint64_t)_mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(p + k), zero)) << k;
#endif
        for (; k < count; k++) bits |= (uint64_t)(p[k] > 0.0f) << k;
        s[w] = bits;
    }
    s[m->data_words] = 0;
    bool some_inside = false, some_outside = false;
    for (int w = 0; w < m->data_words; w++) {
        uint64_t inside = s[w] & m->edge_mask[w];
        some_inside |= inside != 0;
        some_outside |= inside != m->edge_mask[w];
    }
    m->rows[r].x_count = fe_count_crossed(m, s, NULL);
    m->rows[r].kind = some_inside && some_outside ? FE_MIXED : some_inside ? FE_INSIDE : FE_OUTSIDE;
}

/* Crossed edges between two rows (their samples lo … hi differ); none when both are uniform alike. */
static uint32_t fe_count_between(const fe_mesher *m, const fe_row *ra, const uint64_t *a, const fe_row *rb,
                                 const uint64_t *b) {
    return ra->kind == rb->kind && ra->kind != FE_MIXED ? 0 : fe_count_crossed(m, a, b);
}

/* The cells between rows a = (y, z), b = (y + 1, z), c = (y, z + 1), d = (y + 1, z + 1): with
 * out NULL, the number of indices they make; otherwise writes them, the vertex ids from the
 * running counters (see the top of this part). Corner bits as in the case table: the cell's
 * x = 0 side y0z0 → bit 0, y1z0 → 2, y0z1 → 4, y1z1 → 6, the x = 1 side one bit up. */
static uint32_t fe_cells(const fe_mesher *m, const uint64_t *a, const uint64_t *b, const uint64_t *c,
                         const uint64_t *d, uint32_t counter[8], uint32_t *out) {
    uint32_t written = 0;
    for (int w = 0; w < m->data_words; w++) {
        const uint64_t A = a[w], A1 = fe_next(a, w), B = b[w], B1 = fe_next(b, w);
        const uint64_t C = c[w], C1 = fe_next(c, w), D = d[w], D1 = fe_next(d, w);
        uint64_t any = A | A1 | B | B1 | C | C1 | D | D1, all = A & A1 & B & B1 & C & C1 & D & D1;
        uint64_t active = any & ~all & m->cell_mask[w];
        while (active) {
            const int x = __builtin_ctzll(active);
            active &= active - 1;
            const unsigned config = (unsigned)((A >> x & 1) | (A1 >> x & 1) << 1 | (B >> x & 1) << 2 |
                                               (B1 >> x & 1) << 3 | (C >> x & 1) << 4 | (C1 >> x & 1) << 5 |
                                               (D >> x & 1) << 6 | (D1 >> x & 1) << 7);
            const terrain__mc_case *cell = &m->table[config];
            const uint32_t count = (uint32_t)cell->triangle_count * 3;
            if (out) {
                /* Crossings at this x of the y-edges of rows a and c, the z-edges of rows a and b. */
                const uint32_t ya = (config ^ config >> 2) & 1, yc = (config >> 4 ^ config >> 6) & 1;
                const uint32_t za = (config ^ config >> 4) & 1, zb = (config >> 2 ^ config >> 6) & 1;
                /* Edge numbering of terrain_mesh_tables.c: 0–3 x-edges of rows a, b, c, d; 4, 5 the
                 * y-edges of row a at x, x + 1; 6, 7 those of row c; 8, 9 the z-edges of row a at
                 * x, x + 1; 10, 11 those of row b. */
                const uint32_t id[12] = { counter[0], counter[1], counter[2], counter[3],
                                          counter[4], counter[4] + ya, counter[5], counter[5] + yc,
                                          counter[6], counter[6] + za, counter[7], counter[7] + zb };
                const uint8_t *edges = &cell->edges[0][0];
                for (uint32_t k = 0; k < count; k++) out[written + k] = id[edges[k]];
                counter[0] += (config ^ config >> 1) & 1;
                counter[1] += (config >> 2 ^ config >> 3) & 1;
                counter[2] += (config >> 4 ^ config >> 5) & 1;
                counter[3] += (config >> 6 ^ config >> 7) & 1;
                counter[4] += ya, counter[5] += yc, counter[6] += za, counter[7] += zb;
            }
            written += count;
        }
    }
    return written;
}

static bool fe_is_cell_row(const fe_mesher *m, int y, int z) { return y < m->b->hi[1] && z < m->b->hi[2]; }

/* Pass 2 for row (y, z). */
static void fe_count_row(fe_mesher *m, int y, int z) {
    const mesh_builder *b = m->b;
    const size_t r = fe_row_index(m, y, z), up = r + 1, back = r + (size_t)m->rows_y;
    fe_row *row = &m->rows[r];
    const uint64_t *a = fe_signs(m, r);
    row->y_count = y < b->hi[1] ? fe_count_between(m, row, a, &m->rows[up], fe_signs(m, up)) : 0;
    row->z_count = z < b->hi[2] ? fe_count_between(m, row, a, &m->rows[back], fe_signs(m, back)) : 0;
    row->index_count = 0;
    if (!fe_is_cell_row(m, y, z)) return;
    const fe_row *rb = &m->rows[up], *rc = &m->rows[back], *rd = &m->rows[back + 1];
    if (row->kind != FE_MIXED && rb->kind == row->kind && rc->kind == row->kind && rd->kind == row->kind) return;
    row->index_count = fe_cells(m, a, fe_signs(m, up), fe_signs(m, back), fe_signs(m, back + 1), NULL, NULL);
}

/* Pass 4 for row (y, z): its vertices, then its cells' triangles. */
static void fe_generate_row(fe_mesher *m, int y, int z) {
    mesh_builder *b = m->b;
    const size_t r = fe_row_index(m, y, z), up = r + 1, back = r + (size_t)m->rows_y;
    const fe_row *row = &m->rows[r];
    const uint64_t *a = fe_signs(m, r);
    const int n = b->n[0];
    const float *v = b->field->values + (size_t)z * b->slice + (size_t)y * (size_t)n;
    terrain_vertex *out = b->vertices + row->first_vertex;
    const size_t axis_step[3] = { 1, (size_t)n, b->slice };
    const uint32_t count[3] = { row->x_count, row->y_count, row->z_count };
    for (int axis = 0; axis < 3; axis++) {   /* x-, then y-, then z-edges, as first_vertex counts them */
        if (!count[axis]) continue;
        const uint64_t *other = axis == 0 ? NULL : fe_signs(m, axis == 1 ? up : back);
        for (int w = 0; w < m->data_words; w++)
            for (uint64_t bits = fe_crossed(m, a, other, w); bits; bits &= bits - 1) {
                int x = w * 64 + __builtin_ctzll(bits);
                mesh_make_vertex(b, out++, x, y, z, axis, v[x], v[x + axis_step[axis]]);
            }
    }
    if (!row->index_count) return;
    const fe_row *rb = &m->rows[up], *rc = &m->rows[back], *rd = &m->rows[back + 1];
    uint32_t counter[8] = { row->first_vertex, rb->first_vertex, rc->first_vertex, rd->first_vertex,
                            row->first_vertex + row->x_count, rc->first_vertex + rc->x_count,
                            row->first_vertex + row->x_count + row->y_count,
                            rb->first_vertex + rb->x_count + rb->y_count };
    fe_cells(m, a, fe_signs(m, up), fe_signs(m, back), fe_signs(m, back + 1), counter, b->indices + row->first_index);
}

typedef enum { FE_CLASSIFY, FE_COUNT, FE_GENERATE } fe_pass;

typedef struct fe_slabs {
    fe_mesher *m;
    fe_pass pass;
} fe_slabs;

/* Slices z = lo + begin … lo + end − 1, every row of each. */
static void fe_run_slabs(void *user, size_t begin, size_t end) {
    fe_slabs *job = user;
    fe_mesher *m = job->m;
    const mesh_builder *b = m->b;
    for (size_t k = begin; k < end; k++) {
        int z = b->lo[2] + (int)k;
        for (int y = b->lo[1]; y <= b->hi[1]; y++) {
            if (job->pass == FE_CLASSIFY) fe_classify_row(m, y, z);
            else if (job->pass == FE_COUNT) fe_count_row(m, y, z);
            else fe_generate_row(m, y, z);
        }
    }
}

/* A field this large (cells) is split over the job system's threads, when the desc gives one. */
#define FE_PARALLEL_CELLS (64 * 64 * 64)

static void fe_pass_run(fe_mesher *m, fe_pass pass, job_system *jobs) {
    fe_slabs job = { .m = m, .pass = pass };
    static const char *const names[] = { "terrain.mesh.classify", "terrain.mesh.count", "terrain.mesh.generate" };
    if (jobs) job_parallel_for(jobs, (size_t)m->rows_z, 0, fe_run_slabs, &job, names[pass]);
    else fe_run_slabs(&job, 0, (size_t)m->rows_z);
}

/* A mask along x: bits [from, to] set. */
static void fe_mask(uint64_t *mask, int words, int from, int to) {
    for (int w = 0; w < words; w++) {
        int lo = from - w * 64, hi = to - w * 64;   /* in this word's bits */
        if (hi < 0 || lo > 63) { mask[w] = 0; continue; }
        uint64_t upper = hi >= 63 ? ~0ull : (2ull << hi) - 1;
        uint64_t lower = lo <= 0 ? ~0ull : ~((1ull << lo) - 1);
        mask[w] = upper & lower;
    }
}

/* The output of a big field. With 4 KB pages, first writing a 10 MB array costs 2 500 page
 * faults, which on the machines here took as long as meshing it (8 MB: 5–9 ms, against 0.4 ms in
 * huge pages). Where the kernel gives transparent huge pages on request (Linux's default
 * "madvise" mode), such an array is placed on 2 MB boundaries and asked for in huge pages. */
#define FE_HUGE_PAGE ((size_t)2 << 20)
static void *fe_alloc_output(size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes >= 2 * FE_HUGE_PAGE) {
        void *p = core_alloc_aligned(bytes, FE_HUGE_PAGE);   /* a multiple of 2 MB underneath */
        size_t whole = (bytes + FE_HUGE_PAGE - 1) & ~(FE_HUGE_PAGE - 1);
        (void)madvise(p, whole, MADV_HUGEPAGE);   /* a hint: if refused, 4 KB pages as before */
        return p;
    }
#endif
    return core_alloc(bytes);
}

/* Runs the four passes; false when the box has no surface (nothing allocated in b), or past
 * 32-bit indices (logged). */
static bool fe_mesh(mesh_builder *b, job_system *jobs, bool *too_big) {
    fe_mesher m = { .b = b, .table = terrain__mc_table() };
    m.data_words = (b->n[0] + 63) / 64;
    m.words = m.data_words + 1;
    m.rows_y = b->hi[1] - b->lo[1] + 1;
    m.rows_z = b->hi[2] - b->lo[2] + 1;
    const size_t row_count = (size_t)m.rows_y * (size_t)m.rows_z;
    const size_t sign_bytes = row_count * (size_t)m.words * sizeof *m.signs;
    m.signs = core_alloc(sign_bytes);
    m.edge_mask = core_alloc(2 * (size_t)m.words * sizeof *m.edge_mask);
    m.cell_mask = m.edge_mask + m.words;
    fe_mask(m.edge_mask, m.words, b->lo[0], b->hi[0]);
    fe_mask(m.cell_mask, m.words, b->lo[0], b->hi[0] - 1);
    m.rows = core_alloc(row_count * sizeof *m.rows);
    double cells = (double)(b->hi[0] - b->lo[0]) * (m.rows_y - 1) * (m.rows_z - 1);
    if (cells < FE_PARALLEL_CELLS) jobs = NULL;

    fe_pass_run(&m, FE_CLASSIFY, jobs);
    bool surface = false;
    for (size_t r = 0; r < row_count && !surface; r++)
        surface = m.rows[r].kind == FE_MIXED || m.rows[r].kind != m.rows[0].kind;
    if (surface) {
        fe_pass_run(&m, FE_COUNT, jobs);
        uint64_t vertices = 0, indices = 0;
        for (size_t r = 0; r < row_count; r++) {
            fe_row *row = &m.rows[r];
            row->first_vertex = (uint32_t)vertices, row->first_index = (uint32_t)indices;
            vertices += (uint64_t)row->x_count + row->y_count + row->z_count;
            indices += row->index_count;
            if (vertices > UINT32_MAX - 1 || indices > UINT32_MAX) break;
        }
        if (vertices > UINT32_MAX - 1 || indices > UINT32_MAX) {
            core_log_error("terrain", "mesh: over 32-bit indices (%" PRIu64 "+ vertices, %" PRIu64 "+ indices)", vertices,
                       indices);
            *too_big = true;
            surface = false;
        } else {
            b->vertex_count = b->vertex_capacity = (size_t)vertices;
            b->index_count = b->index_capacity = (size_t)indices;
            b->vertices = fe_alloc_output(b->vertex_capacity * sizeof *b->vertices);
            b->indices = fe_alloc_output(b->index_capacity * sizeof *b->indices);
            fe_pass_run(&m, FE_GENERATE, jobs);
        }
    }
    core_free(m.signs, sign_bytes);
    core_free(m.edge_mask, 2 * (size_t)m.words * sizeof *m.edge_mask);
    core_free(m.rows, row_count * sizeof *m.rows);
    return surface;
}

/* ---- the mesh ------------------------------------------------------------------------------ */

/* Which cell of the part grid triangle tri's centroid falls in, over the box lo … hi in x and z. */
static unsigned mesh_part_of(const mesh_builder *b, const uint32_t tri[3], const float lo[2], const float scale[2]) {
    int cell[2];
    for (int c = 0; c < 2; c++) {
        int a = c ? 2 : 0;
        float centroid = (b->vertices[tri[0]].position[a] + b->vertices[tri[1]].position[a] +
                          b->vertices[tri[2]].position[a]) * (1.0f / 3.0f);
        int i = (int)((centroid - lo[c]) * scale[c]);
        cell[c] = i < 0 ? 0 : i >= TERRAIN_MESH_PART_GRID ? TERRAIN_MESH_PART_GRID - 1 : i;
    }
    return (unsigned)(cell[1] * TERRAIN_MESH_PART_GRID + cell[0]);
}

/* The box of a part's vertices (a loop per component took 0.04 ms of a chunk's 0.75). */
static void mesh_part_box(const mesh_builder *b, terrain_mesh_part *part) {
    const uint32_t *index = b->indices + part->first_index, *end = index + part->index_count;
#if defined(__SSE2__)
    /* Four lanes a vertex: the position and the normal's x, which the box leaves out. */
    __m128 lo = _mm_set1_ps(INFINITY), hi = _mm_set1_ps(-INFINITY);
    for (; index < end; index++) {
        __m128 v = _mm_loadu_ps(b->vertices[*index].position);
        lo = _mm_min_ps(lo, v), hi = _mm_max_ps(hi, v);
    }
    float lanes_lo[4], lanes_hi[4];
    _mm_storeu_ps(lanes_lo, lo), _mm_storeu_ps(lanes_hi, hi);
    memcpy(part->bounds_min, lanes_lo, sizeof part->bounds_min);
    memcpy(part->bounds_max, lanes_hi, sizeof part->bounds_max);
#else
    for (int a = 0; a < 3; a++) part->bounds_min[a] = INFINITY, part->bounds_max[a] = -INFINITY;
    for (; index < end; index++)
        for (int a = 0; a < 3; a++) {
            float v = b->vertices[*index].position[a];
            part->bounds_min[a] = v < part->bounds_min[a] ? v : part->bounds_min[a];
            part->bounds_max[a] = v > part->bounds_max[a] ? v : part->bounds_max[a];
        }
#endif
}

/* The triangles in vertex-cache order, then sorted into the parts (terrain_data.h), and the
 * parts' boxes. meshoptimizer's FIFO variant: on our chunks (bench rows' 8 surface chunks, ~3 100
 * triangles each) it reaches an ACMR of 0.690 at a 16-entry cache against 0.683 for
 * meshopt_optimizeVertexCache, in 0.10 ms instead of 0.71 ms (Debian's 0.18); the slice order we
 * emit is already at 1.00. The sort is stable, so each part keeps that order but for its border:
 * ACMR 0.81 on 62 generated chunks (11.5 parts each) against 0.70 whole. Ordering each part on its
 * own reached only 0.78, parts being small, for 0.1 ms more a chunk. */
static void mesh_parts(mesh_builder *b, terrain_mesh *out) {
    size_t triangles = b->index_count / 3;
    uint32_t *ordered = core_alloc(b->index_count * sizeof *ordered);
    meshopt_optimizeVertexCacheFifo(ordered, b->indices, b->index_count, b->vertex_count, 16);
    /* The grid over the mesh's box (out->bounds, already made) in x and z. */
    const float lo[2] = { out->bounds_min[0], out->bounds_min[2] }, hi[2] = { out->bounds_max[0], out->bounds_max[2] };
    float scale[2];
    for (int c = 0; c < 2; c++) scale[c] = hi[c] > lo[c] ? TERRAIN_MESH_PART_GRID / (hi[c] - lo[c]) : 0.0f;
    uint8_t *part_of = core_alloc(triangles);
    uint32_t first[TERRAIN_MESH_PARTS + 1] = { 0 };
    for (size_t t = 0; t < triangles; t++) {
        part_of[t] = (uint8_t)mesh_part_of(b, ordered + 3 * t, lo, scale);
        first[part_of[t] + 1] += 3;
    }
    for (int p = 0; p < TERRAIN_MESH_PARTS; p++) first[p + 1] += first[p];
    uint32_t next[TERRAIN_MESH_PARTS];
    memcpy(next, first, sizeof next);
    for (size_t t = 0; t < triangles; t++) {
        memcpy(b->indices + next[part_of[t]], ordered + 3 * t, 3 * sizeof *ordered);
        next[part_of[t]] += 3;
    }
    out->part_count = 0;
    for (int p = 0; p < TERRAIN_MESH_PARTS; p++) {
        if (first[p + 1] == first[p]) continue;
        terrain_mesh_part *part = &out->parts[out->part_count++];
        *part = (terrain_mesh_part){ .first_index = first[p], .index_count = first[p + 1] - first[p] };
        mesh_part_box(b, part);
    }
    core_free(ordered, b->index_count * sizeof *ordered);
    core_free(part_of, triangles);
}

static float segment_distance(const float p[3], const float a[3], const float b[3]) {
    float ab[3], ap[3], along = 0.0f, length = 0.0f, d = 0.0f;
    for (int k = 0; k < 3; k++) ab[k] = b[k] - a[k], ap[k] = p[k] - a[k], along += ab[k] * ap[k], length += ab[k] * ab[k];
    float t = length > 0.0f ? fminf(fmaxf(along / length, 0.0f), 1.0f) : 0.0f;
    for (int k = 0; k < 3; k++) d += (ap[k] - t * ab[k]) * (ap[k] - t * ab[k]);
    return sqrtf(d);
}

/* Distance from p to triangle abc: to its plane where p projects inside the triangle, else to
 * its nearest edge. */
static float triangle_distance(const float p[3], const float *corner[3]) {
    float e0[3], e1[3], n[3], ap[3];
    for (int k = 0; k < 3; k++) e0[k] = corner[1][k] - corner[0][k], e1[k] = corner[2][k] - corner[0][k], ap[k] = p[k] - corner[0][k];
    n[0] = e0[1] * e1[2] - e0[2] * e1[1], n[1] = e0[2] * e1[0] - e0[0] * e1[2], n[2] = e0[0] * e1[1] - e0[1] * e1[0];
    float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    bool inside = nn > 0.0f;
    for (int k = 0; k < 3 && inside; k++) {
        const float *a = corner[k], *b = corner[(k + 1) % 3];
        float e[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, t[3] = { p[0] - a[0], p[1] - a[1], p[2] - a[2] };
        float c[3] = { e[1] * t[2] - e[2] * t[1], e[2] * t[0] - e[0] * t[2], e[0] * t[1] - e[1] * t[0] };
        inside = c[0] * n[0] + c[1] * n[1] + c[2] * n[2] >= 0.0f;
    }
    if (inside) return fabsf(ap[0] * n[0] + ap[1] * n[1] + ap[2] * n[2]) / sqrtf(nn);
    return fminf(segment_distance(p, corner[0], corner[1]),
                 fminf(segment_distance(p, corner[1], corner[2]), segment_distance(p, corner[2], corner[0])));
}

#define SIMPLIFY_GRID 16   /* cells along each axis of the check's grid over the mesh's box */

/* The grid cell along one axis that coordinate `at` falls in, clamped to the grid. */
static int simplify_grid_cell(float at, float lo, float scale) {
    int i = (int)((at - lo) * scale);
    return i < 0 ? 0 : i > SIMPLIFY_GRID - 1 ? SIMPLIFY_GRID - 1 : i;
}

/* Whether every vertex the simplified triangles (b->indices, index_count of them) left out lies
 * within `tolerance` of them. Quadrics measure a collapse by the planes of the triangles around
 * it, so a thin fin or spike can fold onto its own side planes at no cost and vanish (seen: an
 * 8 m fin of a level-2 chunk under a 0.32 m error); this catches it. The triangles go into a
 * SIMPLIFY_GRID³ grid, each into the cells its box grown by the tolerance touches, so a vertex
 * need only look at its own cell. */
static bool mesh_simplified_near(const mesh_builder *b, size_t index_count, float tolerance) {
    float lo[3], hi[3], scale[3];
    mesh_vertex_bounds(b, lo, hi);
    for (int k = 0; k < 3; k++) scale[k] = hi[k] > lo[k] ? SIMPLIFY_GRID / (hi[k] - lo[k]) : 0.0f;
    const size_t cells = SIMPLIFY_GRID * SIMPLIFY_GRID * SIMPLIFY_GRID;
    uint32_t *first = core_calloc(cells + 1, sizeof *first);
    uint8_t *kept = core_calloc(b->vertex_count, 1);
    int range[2][3];
    /* Two passes over the triangles: count each cell's, then place them (CSR). */
    uint32_t *entries = NULL;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < index_count; i += 3) {
            for (int k = 0; k < 3; k++) {
                float a = b->vertices[b->indices[i]].position[k], c = b->vertices[b->indices[i + 1]].position[k],
                      d = b->vertices[b->indices[i + 2]].position[k];
                range[0][k] = simplify_grid_cell(fminf(a, fminf(c, d)) - tolerance, lo[k], scale[k]);
                range[1][k] = simplify_grid_cell(fmaxf(a, fmaxf(c, d)) + tolerance, lo[k], scale[k]);
            }
            for (int z = range[0][2]; z <= range[1][2]; z++)
                for (int y = range[0][1]; y <= range[1][1]; y++)
                    for (int x = range[0][0]; x <= range[1][0]; x++) {
                        size_t cell = ((size_t)z * SIMPLIFY_GRID + y) * SIMPLIFY_GRID + x;
                        if (pass == 0) first[cell + 1]++;
                        else entries[first[cell]++] = (uint32_t)i;
                    }
            if (pass == 0) kept[b->indices[i]] = kept[b->indices[i + 1]] = kept[b->indices[i + 2]] = 1;
        }
        if (pass == 0) {
            for (size_t c = 0; c < cells; c++) first[c + 1] += first[c];
            entries = core_alloc(((size_t)first[cells] + 1) * sizeof *entries);
        }
    }
    /* first[c] now ends cell c's run; the run starts where cell c − 1's ends. */
    bool near = true;
    for (size_t v = 0; v < b->vertex_count && near; v++) {
        if (kept[v]) continue;
        const float *p = b->vertices[v].position;
        size_t cell = 0;
        for (int k = 2; k >= 0; k--) cell = cell * SIMPLIFY_GRID + (size_t)simplify_grid_cell(p[k], lo[k], scale[k]);
        near = false;
        for (uint32_t e = cell ? first[cell - 1] : 0; e < first[cell] && !near; e++) {
            const uint32_t *tri = b->indices + entries[e];
            const float *corner[3] = { b->vertices[tri[0]].position, b->vertices[tri[1]].position, b->vertices[tri[2]].position };
            near = triangle_distance(p, corner) <= tolerance;
        }
    }
    core_free(entries, ((size_t)first[cells] + 1) * sizeof *entries);
    core_free(first, (cells + 1) * sizeof *first);
    core_free(kept, b->vertex_count);
    return near;
}

static int mesh_compare_edges(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* The open edges of triangles `indices` (count of them), sorted, into `edges` (room for count):
 * directed edges whose reverse no triangle has. Only edges between two vertices on the sides of
 * the meshed box can be open, so only those are looked at. False when a directed edge occurs
 * twice (two triangles on one side of an edge). */
static bool mesh_open_edges(const uint8_t *side, const uint32_t *indices, size_t count, uint64_t *edges, size_t *open) {
    size_t n = 0;
    for (size_t i = 0; i < count; i++) {
        uint32_t v = indices[i], w = indices[i % 3 == 2 ? i - 2 : i + 1];
        if (side[v] && side[w]) edges[n++] = (uint64_t)v << 32 | w;
    }
    qsort(edges, n, sizeof *edges, mesh_compare_edges);
    for (size_t i = 1; i < n; i++)
        if (edges[i] == edges[i - 1]) return false;
    *open = 0;
    for (size_t i = 0; i < n; i++) {
        uint64_t reverse = edges[i] << 32 | edges[i] >> 32;
        if (!bsearch(&reverse, edges, n, sizeof *edges, mesh_compare_edges)) edges[(*open)++] = edges[i];
    }
    return true;
}

/* Whether the simplified triangles (b->indices, count of them) have exactly the open edges of
 * the whole mesh (`whole`), each once: no crack opened along a chunk's side. */
static bool mesh_sides_kept(const mesh_builder *b, const uint8_t *side, const uint32_t *whole, size_t whole_count,
                            size_t count) {
    uint64_t *before = core_alloc((whole_count + 1) * sizeof *before), *after = core_alloc((count + 1) * sizeof *after);
    size_t open_before = 0, open_after = 0;
    bool kept = mesh_open_edges(side, whole, whole_count, before, &open_before) &&
                mesh_open_edges(side, b->indices, count, after, &open_after) && open_before == open_after &&
                memcmp(before, after, open_after * sizeof *after) == 0;
    core_free(before, (whole_count + 1) * sizeof *before);
    core_free(after, (count + 1) * sizeof *after);
    return kept;
}

/* Fewer triangles where fewer draw the same surface (desc.max_error; README, "Simplified
 * chunks"): meshoptimizer's edge collapses ranked by Garland and Heckbert's quadrics, none moving
 * the surface by more than about max_error by their measure, none flipping a triangle, and none
 * touching a vertex on the sides of the meshed box (where the neighbours' triangles start) or
 * next to one. Locking the border (meshopt_SimplifyLockBorder) is not enough in meshoptimizer
 * 0.18: an inner vertex may still collapse onto a border vertex and leave a sliver of the side's
 * plane uncovered, a crack against the neighbour (43 of 44 chunks of generated ground). So the
 * vertices next to the border are made border vertices too, each given a tiny triangle of its
 * own with two extra vertices (an open edge in, one out), which are dropped afterwards. Then two
 * checks, and the mesh stays whole if either fails: the open edges are those of the whole mesh
 * (mesh_sides_kept), and every vertex left out lies within 2·max_error of the triangles kept
 * (mesh_simplified_near: the quadrics' blind spot is a thin fin folding onto its own side
 * planes). Last, the vertices no triangle uses go, the rest in first-use order; this runs before
 * the weights and the occlusion, which are then made for the vertices kept only. */
static void mesh_simplify(mesh_builder *b, float max_error) {
    if (!(max_error > 0.0f) || b->index_count == 0) return;
    const size_t n = b->vertex_count, whole_count = b->index_count;
    const float spacing = b->field->spacing;
    uint8_t *side = core_calloc(n, 1), *ring = core_calloc(n, 1);
    for (size_t v = 0; v < n; v++)
        for (int a = 0; a < 3; a++) {
            float p = b->vertices[v].position[a];
            side[v] |= p == (float)b->lo[a] * spacing || p == (float)b->hi[a] * spacing;
        }
    size_t rings = 0;
    for (size_t i = 0; i < whole_count; i += 3) {
        const uint32_t *t = b->indices + i;
        if (!side[t[0]] && !side[t[1]] && !side[t[2]]) continue;
        for (int k = 0; k < 3; k++)
            if (!side[t[k]] && !ring[t[k]]) ring[t[k]] = 1, rings++;
    }
    /* Positions and triangles with the locking triangles after them: vertex v's are n + 2r and
     * n + 2r + 1, a thousandth of a cell off it along x and z (distinct positions, so that the
     * simplifier does not weld them to v). */
    float *positions = core_alloc((n + 2 * rings) * 3 * sizeof *positions);
    uint32_t *input = core_alloc((whole_count + 3 * rings) * sizeof *input);
    uint32_t *output = core_alloc((whole_count + 3 * rings) * sizeof *output);
    memcpy(input, b->indices, whole_count * sizeof *input);
    size_t extra = 0;
    for (size_t v = 0; v < n; v++) {
        memcpy(positions + 3 * v, b->vertices[v].position, 3 * sizeof *positions);
        if (!ring[v]) continue;
        uint32_t d = (uint32_t)(n + 2 * extra);
        float *pa = positions + 3 * (size_t)d, *pb = pa + 3;
        memcpy(pa, b->vertices[v].position, 3 * sizeof *pa);
        memcpy(pb, b->vertices[v].position, 3 * sizeof *pb);
        pa[0] += 1e-3f * spacing, pb[2] += 1e-3f * spacing;
        uint32_t *t = input + whole_count + 3 * extra++;
        t[0] = (uint32_t)v, t[1] = d, t[2] = d + 1;
    }
    const size_t all = n + 2 * rings, input_count = whole_count + 3 * rings;
    float extent = meshopt_simplifyScale(positions, all, 3 * sizeof *positions);
    size_t count = extent > 0.0f ? meshopt_simplify(output, input, input_count, positions, all, 3 * sizeof *positions, 0,
                                                    max_error / extent, meshopt_SimplifyLockBorder, NULL)
                                 : input_count;
    /* Without the locking triangles, into the builder (the whole mesh kept in `input`). */
    size_t kept = 0;
    for (size_t i = 0; i < count; i += 3)
        if (output[i] < n && output[i + 1] < n && output[i + 2] < n) {
            memcpy(b->indices + kept, output + i, 3 * sizeof *output);
            kept += 3;
        }
    if (!mesh_sides_kept(b, side, input, whole_count, kept) || !mesh_simplified_near(b, kept, 2.0f * max_error))
        memcpy(b->indices, input, whole_count * sizeof *input);
    else
        b->index_count = kept;
    core_free(positions, all * 3 * sizeof *positions);
    core_free(input, input_count * sizeof *input);
    core_free(output, input_count * sizeof *output);
    core_free(side, n);
    core_free(ring, n);
    if (b->index_count == whole_count) return;
    unsigned *remap = core_alloc(n * sizeof *remap);
    b->vertex_count = meshopt_optimizeVertexFetchRemap(remap, b->indices, b->index_count, n);
    meshopt_remapIndexBuffer(b->indices, b->indices, b->index_count, remap);
    meshopt_remapVertexBuffer(b->vertices, b->vertices, n, sizeof *b->vertices, remap);
    core_free(remap, n * sizeof *remap);
}

static void mesh_finish(mesh_builder *b, const terrain_mesh_desc *desc, const double origin[3], terrain_mesh *out) {
    out->part_count = 0;
    mesh_simplify(b, desc->max_error);
    for (size_t i = 0; i < b->vertex_count; i++) {
        b->vertices[i].occlusion = 0;
        memset(b->vertices[i].reserved, 0, sizeof b->vertices[i].reserved);
    }
    /* The box once: the weights' and occlusion's windows and the parts' grid are laid over it. */
    mesh_vertex_bounds(b, out->bounds_min, out->bounds_max);
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = origin[a] + out->bounds_min[a], hi[a] = origin[a] + out->bounds_max[a];
    if (desc->world) mesh_weights(b, desc->world, origin, lo, hi);
    if (desc->world && !desc->no_occlusion) mesh_openness(b, desc->world, origin, lo, hi);
    if (!desc->no_optimize && b->index_count) mesh_parts(b, out);
    /* Exact sizes, so that terrain_mesh_free knows them. */
    out->vertices = b->vertex_count ? core_realloc(b->vertices, b->vertex_capacity * sizeof *b->vertices,
                                                   b->vertex_count * sizeof *b->vertices) : NULL;
    if (!b->vertex_count && b->vertices) core_free(b->vertices, b->vertex_capacity * sizeof *b->vertices);
    out->indices = b->index_count ? core_realloc(b->indices, b->index_capacity * sizeof *b->indices,
                                                 b->index_count * sizeof *b->indices) : NULL;
    if (!b->index_count && b->indices) core_free(b->indices, b->index_capacity * sizeof *b->indices);
    out->vertex_count = (uint32_t)b->vertex_count;
    out->index_count = (uint32_t)b->index_count;
}

bool terrain_mesh_build(const terrain_field *field, const terrain_mesh_desc *desc_in, terrain_mesh *out) {
    const terrain_mesh_desc desc = desc_in ? *desc_in : (terrain_mesh_desc){ 0 };
    memset(out, 0, sizeof *out);
    for (int a = 0; a < 3; a++) out->origin[a] = field->origin[a];
    if (!field->values || field->nx <= 0 || field->ny <= 0 || field->nz <= 0 || desc.apron < 0 ||
        !(field->spacing > 0.0f)) {
        core_log_error("terrain", "mesh: bad field (%d × %d × %d samples, spacing %g, apron %d)", field->nx,
                   field->ny, field->nz, (double)field->spacing, desc.apron);
        return false;
    }
    mesh_builder b = { .field = field, .n = { field->nx, field->ny, field->nz },
                       .slice = (size_t)field->nx * field->ny };
    for (int a = 0; a < 3; a++) {
        b.lo[a] = desc.apron;
        b.hi[a] = b.n[a] - 1 - desc.apron;
        if (b.hi[a] <= b.lo[a]) return true;    /* no cell left to mesh */
    }
    bool too_big = false;
    if (!fe_mesh(&b, desc.jobs, &too_big)) return !too_big;
    mesh_finish(&b, &desc, field->origin, out);
    return true;
}

/* ---- for terrain_lod.c ---------------------------------------------------------------------- */

void terrain__mesh_gradient(const terrain__mesh_builder *b, int x, int y, int z, float g[3]) { mesh_gradient(b, x, y, z, g); }

uint32_t terrain__mesh_add_vertex(terrain__mesh_builder *b, int x, int y, int z, int axis, float f0, float f1) {
    return mesh_add_vertex(b, x, y, z, axis, f0, f1);
}

bool terrain__mesh_finish(terrain__mesh_builder *b, const terrain_mesh_desc *desc, const double origin[3], terrain_mesh *out) {
    if (b->vertex_count > UINT32_MAX - 1 || b->index_count > UINT32_MAX) {
        core_log_error("terrain", "mesh: %zu vertices, %zu indices: over 32-bit indices", b->vertex_count, b->index_count);
        core_free(b->vertices, b->vertex_capacity * sizeof *b->vertices);
        core_free(b->indices, b->index_capacity * sizeof *b->indices);
        return false;
    }
    mesh_finish(b, desc, origin, out);
    return true;
}

void terrain_mesh_free(terrain_mesh *mesh) {
    if (mesh->vertices) core_free(mesh->vertices, mesh->vertex_count * sizeof *mesh->vertices);
    if (mesh->indices) core_free(mesh->indices, mesh->index_count * sizeof *mesh->indices);
    memset(mesh, 0, sizeof *mesh);
}

double terrain_mesh_area(const terrain_mesh *mesh) {
    double area = 0.0;
    for (uint32_t i = 0; i + 2 < mesh->index_count; i += 3) {
        const float *p0 = mesh->vertices[mesh->indices[i]].position;
        const float *p1 = mesh->vertices[mesh->indices[i + 1]].position;
        const float *p2 = mesh->vertices[mesh->indices[i + 2]].position;
        double u[3], v[3];
        for (int a = 0; a < 3; a++) u[a] = (double)p1[a] - p0[a], v[a] = (double)p2[a] - p0[a];
        double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
        area += 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
    }
    return area;
}
