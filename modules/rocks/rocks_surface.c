/* rocks_surface.c — the surface a rock's levels of detail are simplified from (001 §5).
 *
 * 001 meshes r = 2ρ − 1 by marching cubes on the voxel grid. That mesh has about 1 400 triangles
 * for a rock of the round n = 5 set, of which LOD 0 keeps about 75, and simplifying it was most
 * of the cost of building a tile set. So a rock is first contoured on a grid of twice the
 * spacing, with vertices fitted to the voxel grid's own crossings: dual contouring (Ju, Losasso,
 * Schaefer and Warren 2002) with one vertex per surface piece of a coarse cell (Schaefer, Ju
 * and Warren 2007's manifold rule), about 350 triangles, which the simplifier takes down the
 * rest of the way. Where the coarse grid cannot follow the rock, the rock is meshed by marching
 * cubes as before (rocks_mesh.c).
 *
 * The grids. The fine grid is ρ's voxel centres, sample (x, y, z) at position (x, y, z), in a
 * box whose border voxels are empty. Coarse sample i sits on fine sample 2i − 2 along each axis,
 * so the coarse grid starts and ends outside the box and every coarse sign change lies inside
 * it; coarse cell c spans fine samples 2c − 2 … 2c.
 *
 * A coarse cell whose corners differ in sign holds one vertex per surface piece: its crossed
 * edges joined where the surface joins them on each face (two crossed edges of a face belong
 * together; on a face whose corners alternate, the inside corners are kept apart, each cut off
 * with its own two edges: the rule the two cells sharing the face both read from its four signs,
 * so an edge of the dual mesh lies in exactly two triangles, save where one piece crosses a face
 * twice, below). A quad joins the four pieces around each crossed coarse edge.
 *
 * Each vertex is the point nearest, in the least-squares sense, to the tangent planes of the
 * fine crossings in its cell (the marching-cubes points on the fine edges, with normals from the
 * field's central differences, as terrain_mesh computes them), pulled a little towards their mean
 * (λ = 0.05, which also keeps the solve regular where the planes are parallel): the vertex lies
 * on the voxels' own surface, not at the middle of its cell, and a coarse cell's vertex follows
 * the fine surface as far as its planes agree. (Most of a rock's ρ is 0 or 1, and there the
 * differences tilt the normals at every step of the voxels, so edges and corners still come out
 * rounded by a few tenths of a voxel, as marching cubes rounds them.) In a cell with several
 * pieces, a crossing on a crossed coarse edge goes to that edge's piece, any other to the piece
 * whose crossed coarse edges' midpoints lie nearest.
 *
 * When not. The coarse grid cannot see what lies between its samples: a fin or slab under two
 * voxels thick, a bump that no coarse edge crosses. Three signs of that send the rock to
 * marching cubes:
 *   - a fine crossing that no cell with a vertex holds, more than 1.5 voxels from every vertex
 *     in the cells around it: detail the coarse surface passes by;
 *   - a vertex whose crossings' normals disagree (their sum shorter than 0.35 of their count):
 *     the two faces of a thin plate, or a sharp ridge, in one cell (at 0.5 twice the rocks went
 *     to marching cubes, and LOD 0 came out no nearer to the voxels);
 *   - a surface that is not closed with each edge in two triangles (a piece that crosses one
 *     face twice, beside another that does; rare).
 * Measured on the n = 5 sets (release, the first 2 000 rocks of each): the accepted surfaces lie
 * within 1.46 voxels of every marching-cubes point of the same ρ, 0.09–0.10 voxel on average;
 * 97 % of the round and mixed sets' rocks are accepted, 92 % of the slabs'. LOD 0 simplified from
 * them lies nearer the marching-cubes points than LOD 0 simplified from marching cubes itself
 * (over the first 300 round rocks 0.160 against 0.174 voxel on average, 15 against 19 rocks with
 * a point more than a voxel off, the worst 1.73 against 1.35), with as many triangles.
 */
#include "rocks_internal.h"

#include "core/core.h"
#include "core/core_lanes.h"

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <string.h>

#define PAD 1                         /* fine samples around the box, for central differences */
#define MAX_ROW 64                    /* a row of the box's samples is one word of signs */
#define PULL 0.05f                    /* λ: towards the crossings' mean */
#define FAR_VOXELS 1.5f               /* a missed crossing this far from every vertex shows */
#define AGREEMENT 0.35f               /* |Σ n| ≥ this × count, or the normals disagree */

/* ---- a coarse cell's pieces -------------------------------------------------------------------- */

/* Corners: bit 0 x, bit 1 y, bit 2 z. Edge 4·axis + b_u + 2·b_w runs along `axis` through the
 * corners whose bits on the two other axes (u = axis + 1, w = axis + 2, mod 3) are b_u, b_w. */
static int edge_along(int axis, int corner) {
    int u = (axis + 1) % 3, w = (axis + 2) % 3;
    return 4 * axis + ((corner >> u) & 1) + 2 * ((corner >> w) & 1);
}

static int edge_first_corner(int edge) {
    int axis = edge >> 2, u = (axis + 1) % 3, w = (axis + 2) % 3;
    return (edge & 1) << u | ((edge >> 1) & 1) << w;
}

static int union_find(int *parent, int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
}

static int8_t piece_of_edge[256][12];   /* per case (corner signs), each edge's piece or −1 */
static uint8_t piece_count[256];
static uint8_t faces_met_twice[256];    /* bit 2·axis + side: the face's corners alternate and one
                                           piece holds both its curves */
static pthread_once_t pieces_once = PTHREAD_ONCE_INIT;

/* The crossed edges of one face joined as the surface joins them (see the top). */
static void join_on_face(int signs, int axis, int side, int *parent) {
    int u = (axis + 1) % 3, w = (axis + 2) % 3, s = side << axis;
    const int corner[4] = { s, s | 1 << u, s | 1 << u | 1 << w, s | 1 << w };   /* round the face */
    int edge[4];   /* edge k joins corner k and corner k + 1 */
    for (int k = 0; k < 4; k++) edge[k] = edge_along(k & 1 ? w : u, corner[k == 2 ? 3 : k]);
    int crossed[4], n = 0;
    for (int k = 0; k < 4; k++)
        if (((signs >> corner[k]) & 1) != ((signs >> corner[(k + 1) & 3]) & 1)) crossed[n++] = k;
    if (n == 2) parent[union_find(parent, edge[crossed[0]])] = union_find(parent, edge[crossed[1]]);
    if (n == 4)
        for (int k = 0; k < 4; k++)
            if ((signs >> corner[k]) & 1) parent[union_find(parent, edge[k])] = union_find(parent, edge[(k + 3) & 3]);
}

/* faces_met_twice for one case, once its pieces are known. */
static uint8_t met_twice(int signs) {
    uint8_t faces = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int u = (axis + 1) % 3, w = (axis + 2) % 3, s = side << axis;
            int a = (signs >> s) & 1, b = (signs >> (s | 1 << u)) & 1, c = (signs >> (s | 1 << u | 1 << w)) & 1,
                d = (signs >> (s | 1 << w)) & 1;
            if (a == b || b == c || c == d || d == a) continue;   /* not alternating */
            /* its two curves: the edges along u through corner s and through s + w lie on different ones */
            if (piece_of_edge[signs][edge_along(u, s)] == piece_of_edge[signs][edge_along(u, s | 1 << w)])
                faces |= (uint8_t)(1 << (2 * axis + side));
        }
    return faces;
}

static void make_pieces(void) {
    for (int signs = 0; signs < 256; signs++) {
        int parent[12], label[12], count = 0;
        for (int e = 0; e < 12; e++) parent[e] = e, label[e] = -1;
        for (int axis = 0; axis < 3; axis++)
            for (int side = 0; side < 2; side++) join_on_face(signs, axis, side, parent);
        for (int e = 0; e < 12; e++) {
            int c0 = edge_first_corner(e), c1 = c0 | 1 << (e >> 2);
            if (((signs >> c0) & 1) == ((signs >> c1) & 1)) {
                piece_of_edge[signs][e] = -1;
                continue;
            }
            int root = union_find(parent, e);
            if (label[root] < 0) label[root] = count++;
            piece_of_edge[signs][e] = (int8_t)label[root];
        }
        piece_count[signs] = (uint8_t)count;
        faces_met_twice[signs] = met_twice(signs);
    }
}

/* ---- the grids --------------------------------------------------------------------------------- */

/* The tangent planes and points of a vertex's crossings, in fine units: sixteen floats, added
 * four at a time. */
typedef union qef {
    core_floats4 v[4];
    struct {
        float a[6];                   /* Σ n nᵀ: xx yy zz xy xz yz */
        float b[3];                   /* Σ n (n·p) */
        float mass[3], normal[3];     /* Σ p, Σ n */
        float count;                  /* exact: far fewer than 2²⁴ crossings */
    };
} qef;
_Static_assert(sizeof(qef) == 4 * sizeof(core_floats4), "a qef is four vectors of four floats");

typedef struct dual_grid {
    int size[3];
    ptrdiff_t fine_stride[3];
    float *fine;                      /* r at the padded fine samples, −1 outside the box */
    size_t fine_total;
    uint64_t *solid_rows;             /* per box row (y, z): bit x set where solid (r ≥ 0) */
    int samples[3], cells[3];         /* coarse */
    ptrdiff_t cell_stride[3];
    uint64_t *sample_rows;            /* per coarse row (y, z): bit x set where sample x is solid */
    uint8_t *cell_case;               /* corner signs; 0 for a cell all inside or all outside */
    int32_t *cell_first;              /* its first vertex, −1 when it has none */
    uint32_t *crossed_cells;          /* the cells with vertices, in order */
    size_t cell_total, crossed_count;
    qef *qefs;                        /* one a vertex */
    uint32_t vertex_count;
    float (*missed)[3];               /* crossings in cells without vertices */
    size_t missed_count, missed_cap;
    core_arena arena;                 /* every array above but missed */
} dual_grid;

static float *fine_sample(const dual_grid *g, int x, int y, int z) {
    return g->fine + (z + PAD) * g->fine_stride[2] + (y + PAD) * g->fine_stride[1] + (x + PAD);
}

/* One row of r = 2ρ − 1 (ρ = ½ counts as solid, as in marching cubes' field: r = 0 becomes 10⁻⁶),
 * four samples at a time; returns its signs, bit x set where solid. */
static uint64_t fine_row(const float *in, float *out, int length) {
    const core_floats4 two = core_floats4_splat(2.0f), one = core_floats4_splat(1.0f), zero = core_floats4_splat(0.0f);
    const core_ints4 bit = { 1, 2, 4, 8 };
    uint64_t solid = 0;
    int x = 0;
    for (; x + 4 <= length; x += 4) {
        core_floats4 r = two * core_floats4_load(in + x) - one;
        core_ints4 bits = (r >= zero) & bit;
        core_floats4_store(out + x, core_floats4_select(r == zero, core_floats4_splat(1e-6f), r));
        solid |= (uint64_t)(bits[0] | bits[1] | bits[2] | bits[3]) << x;
    }
    for (; x < length; x++) {
        float r = 2.0f * in[x] - 1.0f;
        out[x] = r == 0.0f ? 1e-6f : r;
        solid |= (uint64_t)(r >= 0.0f) << x;
    }
    return solid;
}

static void make_fine(dual_grid *g, const float *rho) {
    const int sx = g->size[0], sy = g->size[1], sz = g->size[2];
    g->fine_stride[0] = 1, g->fine_stride[1] = sx + 2 * PAD, g->fine_stride[2] = (ptrdiff_t)(sx + 2 * PAD) * (sy + 2 * PAD);
    g->fine_total = (size_t)g->fine_stride[2] * (sz + 2 * PAD);
    g->solid_rows = core_arena_alloc(&g->arena, (size_t)sy * sz * sizeof *g->solid_rows, 16);
    g->fine = core_arena_alloc(&g->arena, g->fine_total * sizeof *g->fine, 16);
    /* −1 around the box: the first and last planes and rows whole, each row's ends */
    const size_t plane = (size_t)g->fine_stride[2], row_length = (size_t)g->fine_stride[1];
    for (size_t i = 0; i < plane * PAD; i++) g->fine[i] = g->fine[g->fine_total - 1 - i] = -1.0f;
    for (int z = 0; z < sz; z++) {
        float *first_rows = fine_sample(g, -PAD, -PAD, z), *last_rows = fine_sample(g, -PAD, sy, z);
        for (size_t i = 0; i < row_length * PAD; i++) first_rows[i] = last_rows[i] = -1.0f;
    }
    for (int z = 0; z < sz; z++)
        for (int y = 0; y < sy; y++) {
            const float *in = rho + ((size_t)z * sy + y) * sx;
            float *out = fine_sample(g, 0, y, z);
            for (int p = 1; p <= PAD; p++) out[-p] = out[sx - 1 + p] = -1.0f;
            g->solid_rows[(size_t)z * sy + y] = fine_row(in, out, sx);
        }
}

/* Bits 0, 2, 4, … of v packed into bits 0, 1, 2, … */
static uint64_t even_bits(uint64_t v) {
    v &= 0x5555555555555555ull;
    v = (v | v >> 1) & 0x3333333333333333ull;
    v = (v | v >> 2) & 0x0f0f0f0f0f0f0f0full;
    v = (v | v >> 4) & 0x00ff00ff00ff00ffull;
    v = (v | v >> 8) & 0x0000ffff0000ffffull;
    return (v | v >> 16) & 0x00000000ffffffffull;
}

static uint64_t sample_row(const dual_grid *g, int y, int z) { return g->sample_rows[(size_t)z * g->samples[1] + y]; }

/* Coarse signs, each cell's case, and a vertex (qef) for each piece of each cell that has one.
 * Coarse sample (x, y, z) is fine sample (2x − 2, 2y − 2, 2z − 2), so a coarse row of signs is
 * the even bits of a fine row moved up one (x = 0 lies outside the box). A cell is crossed where
 * its four rows' bits x and x + 1 are neither all clear nor all set; only those are visited. */
static void make_cells(dual_grid *g) {
    for (int a = 0; a < 3; a++) g->samples[a] = g->size[a] / 2 + 3, g->cells[a] = g->samples[a] - 1;
    g->cell_stride[0] = 1, g->cell_stride[1] = g->cells[0], g->cell_stride[2] = (ptrdiff_t)g->cells[0] * g->cells[1];
    g->cell_total = (size_t)g->cell_stride[2] * g->cells[2];
    g->sample_rows = core_arena_alloc(&g->arena, (size_t)g->samples[1] * g->samples[2] * sizeof *g->sample_rows, 16);
    g->cell_first = core_arena_alloc(&g->arena, g->cell_total * sizeof *g->cell_first, 16);
    g->crossed_cells = core_arena_alloc(&g->arena, g->cell_total * sizeof *g->crossed_cells, 16);
    g->cell_case = core_arena_alloc(&g->arena, g->cell_total, 16);
    for (int z = 0; z < g->samples[2]; z++)
        for (int y = 0; y < g->samples[1]; y++) {
            const int fy = 2 * y - 2, fz = 2 * z - 2;
            const bool inside = fy >= 0 && fz >= 0 && fy < g->size[1] && fz < g->size[2];
            g->sample_rows[(size_t)z * g->samples[1] + y] = inside ? even_bits(g->solid_rows[(size_t)fz * g->size[1] + fy]) << 1 : 0;
        }
    memset(g->cell_case, 0, g->cell_total);
    memset(g->cell_first, 0xff, g->cell_total * sizeof *g->cell_first);   /* −1 */
    g->vertex_count = 0;
    g->crossed_count = 0;
    const uint64_t in_row = (1ull << g->cells[0]) - 1;
    for (int z = 0; z < g->cells[2]; z++)
        for (int y = 0; y < g->cells[1]; y++) {
            const uint64_t a = sample_row(g, y, z), b = sample_row(g, y + 1, z), c = sample_row(g, y, z + 1),
                           d = sample_row(g, y + 1, z + 1);
            const uint64_t some = a | b | c | d, all = a & b & c & d;
            for (uint64_t crossed = (some | some >> 1) & ~(all & all >> 1) & in_row; crossed; crossed &= crossed - 1) {
                const int x = __builtin_ctzll(crossed);
                const int signs = (int)((a >> x & 3) | (b >> x & 3) << 2 | (c >> x & 3) << 4 | (d >> x & 3) << 6);
                const size_t cell = (size_t)(z * g->cell_stride[2] + y * g->cell_stride[1] + x);
                g->cell_case[cell] = (uint8_t)signs;
                g->cell_first[cell] = (int32_t)g->vertex_count;
                g->vertex_count += piece_count[signs];
                g->crossed_cells[g->crossed_count++] = (uint32_t)cell;
            }
        }
    g->qefs = core_arena_alloc(&g->arena, (g->vertex_count ? g->vertex_count : 1) * sizeof *g->qefs, 16);
    memset(g->qefs, 0, g->vertex_count * sizeof *g->qefs);
}

/* The coarse coordinates of a cell. */
static void cell_coordinates(const dual_grid *g, size_t cell, int out[3]) {
    out[0] = (int)(cell % (size_t)g->cells[0]);
    out[1] = (int)(cell / (size_t)g->cells[0] % (size_t)g->cells[1]);
    out[2] = (int)(cell / (size_t)g->cell_stride[2]);
}

/* ---- the crossings ----------------------------------------------------------------------------- */

/* The piece of a cell of several that a crossing at p (fine units) belongs to: the one whose
 * crossed coarse edges' midpoints lie nearest. */
static int nearest_piece(const dual_grid *g, size_t cell, const int cell_xyz[3], const float p[3]) {
    const int8_t *piece = piece_of_edge[g->cell_case[cell]];
    float best = INFINITY;
    int which = 0;
    for (int e = 0; e < 12; e++) {
        if (piece[e] < 0) continue;
        int corner = edge_first_corner(e), axis = e >> 2;
        float d = 0.0f;
        for (int a = 0; a < 3; a++) {
            float mid = (float)(2 * cell_xyz[a] - 2) + (a == axis ? 1.0f : 2.0f * (float)((corner >> a) & 1));
            d += (p[a] - mid) * (p[a] - mid);
        }
        if (d < best) best = d, which = piece[e];
    }
    return which;
}

/* The piece of `cell` (coarse coordinates c) that the crossing on the fine edge from `at` along
 * `axis`, at p, belongs to: the piece of the crossed coarse edge it lies on, else the nearest. */
static int crossing_piece(const dual_grid *g, size_t cell, const int c[3], const int at[3], int axis, const float p[3]) {
    if (piece_count[g->cell_case[cell]] == 1) return 0;   /* most cells */
    const int u = (axis + 1) % 3, w = (axis + 2) % 3, ou = at[u] - (2 * c[u] - 2), ow = at[w] - (2 * c[w] - 2);
    if ((ou == 0 || ou == 2) && (ow == 0 || ow == 2)) {
        int piece = piece_of_edge[g->cell_case[cell]][edge_along(axis, (ou / 2) << u | (ow / 2) << w)];
        if (piece >= 0) return piece;
    }
    return nearest_piece(g, cell, c, p);
}

/* One crossing's terms: its point, and its tangent plane when it has a normal. */
static qef qef_of_crossing(const float p[3], const float n[3], bool has_normal) {
    qef q = { .v = { { 0 }, { 0 }, { 0, p[0], p[1], p[2] }, { 0, 0, 0, 1.0f } } };
    if (!has_normal) return q;
    float d = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
    q.v[0] = (core_floats4){ n[0] * n[0], n[1] * n[1], n[2] * n[2], n[0] * n[1] };
    q.v[1] = (core_floats4){ n[0] * n[2], n[1] * n[2], n[0] * d, n[1] * d };
    q.v[2] = (core_floats4){ n[2] * d, p[0], p[1], p[2] };
    q.v[3] = (core_floats4){ n[0], n[1], n[2], 1.0f };
    return q;
}

/* The crossing on the fine edge from sample (x, y, z) along `axis` given to every coarse cell
 * that holds the edge: one, or two or four when it lies on the cells' faces or edges (cell c
 * spans fine samples 2c − 2 … 2c, so an even coordinate off the axis lies on two cells). */
static void scatter_crossing(dual_grid *g, const int at[3], int axis, float t, const float n[3], bool has_normal) {
    const float p[3] = { (float)at[0] + (axis == 0 ? t : 0.0f), (float)at[1] + (axis == 1 ? t : 0.0f),
                         (float)at[2] + (axis == 2 ? t : 0.0f) };
    const qef terms = qef_of_crossing(p, n, has_normal);
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    int c[3] = { (at[0] + 2) >> 1, (at[1] + 2) >> 1, (at[2] + 2) >> 1 };   /* the highest cell */
    const int two_u = !(at[u] & 1), two_w = !(at[w] & 1);
    const int cu = c[u], cw = c[w];
    bool held = false;
    for (int i = 0; i <= two_w; i++)
        for (int j = 0; j <= two_u; j++) {
            c[u] = cu - j, c[w] = cw - i;
            size_t cell = (size_t)(c[2] * g->cell_stride[2] + c[1] * g->cell_stride[1] + c[0]);
            if (g->cell_first[cell] < 0) continue;
            qef *sum = &g->qefs[g->cell_first[cell] + crossing_piece(g, cell, c, at, axis, p)];
            for (int k = 0; k < 4; k++) sum->v[k] += terms.v[k];
            held = true;
        }
    if (!held) {   /* no vertex's cell holds it: checked against the vertices around, once placed */
        g->missed = core_grow(g->missed, &g->missed_cap, g->missed_count + 1, sizeof *g->missed);
        memcpy(g->missed[g->missed_count++], p, sizeof p);
    }
}

/* Every fine edge the surface crosses: its point (t = f₀ / (f₀ − f₁), as marching cubes puts it)
 * and normal (−∇r by central differences at both ends, interpolated). The box's border is empty,
 * so no crossing lies outside it. */
static void crossing(dual_grid *g, int x, int y, int z, int axis) {
    const ptrdiff_t *st = g->fine_stride;
    const float *p0 = fine_sample(g, x, y, z), *p1 = p0 + st[axis];
    float t = p0[0] / (p0[0] - p1[0]), n[3], length2 = 0.0f;
    for (int a = 0; a < 3; a++) {
        float g0 = p0[st[a]] - p0[-st[a]], g1 = p1[st[a]] - p1[-st[a]];
        n[a] = -(g0 + t * (g1 - g0));
        length2 += n[a] * n[a];
    }
    bool has_normal = length2 > 0.0f;
    if (has_normal) {
        float inverse = 1.0f / sqrtf(length2);
        for (int a = 0; a < 3; a++) n[a] *= inverse;
    }
    scatter_crossing(g, (const int[3]){ x, y, z }, axis, t, n, has_normal);
}

/* The crossed fine edges found a row of signs at a time: along x where a row's neighbouring bits
 * differ, along y and z where the row differs from the next one. */
static void gather_crossings(dual_grid *g) {
    const int sx = g->size[0], sy = g->size[1], sz = g->size[2];
    const uint64_t *rows = g->solid_rows;
    for (int z = 0; z < sz; z++)
        for (int y = 0; y < sy; y++) {
            const uint64_t row = rows[(size_t)z * sy + y];
            if (row == 0 && (y + 1 == sy || rows[(size_t)z * sy + y + 1] == 0) && (z + 1 == sz || rows[(size_t)(z + 1) * sy + y] == 0))
                continue;
            uint64_t across[3] = { (row ^ row >> 1) & ~(~(uint64_t)0 << (sx - 1)),
                                   y + 1 < sy ? row ^ rows[(size_t)z * sy + y + 1] : 0,
                                   z + 1 < sz ? row ^ rows[(size_t)(z + 1) * sy + y] : 0 };
            for (int axis = 0; axis < 3; axis++)
                for (uint64_t bits = across[axis]; bits; bits &= bits - 1) crossing(g, __builtin_ctzll(bits), y, z, axis);
        }
}

/* ---- vertices and quads ------------------------------------------------------------------------ */

/* The point minimising Σ (n·x − n·p)² + λ |x − mean|², as mean + δ with (A + λI) δ = b − A·mean;
 * kept inside the cell (fine coordinates lo … lo + 2). */
static void qef_point(const qef *q, const int lo[3], float out[3]) {
    double m[3], r[3];
    for (int a = 0; a < 3; a++) m[a] = q->count > 0.0f ? (double)q->mass[a] / q->count : lo[a] + 1.0;
    const double xx = q->a[0], yy = q->a[1], zz = q->a[2], xy = q->a[3], xz = q->a[4], yz = q->a[5];
    r[0] = q->b[0] - (xx * m[0] + xy * m[1] + xz * m[2]);
    r[1] = q->b[1] - (xy * m[0] + yy * m[1] + yz * m[2]);
    r[2] = q->b[2] - (xz * m[0] + yz * m[1] + zz * m[2]);
    const double a = xx + PULL, d = yy + PULL, f = zz + PULL;
    const double c00 = d * f - yz * yz, c01 = xz * yz - xy * f, c02 = xy * yz - xz * d;
    const double c11 = a * f - xz * xz, c12 = xy * xz - a * yz, c22 = a * d - xy * xy;
    const double inverse = 1.0 / (a * c00 + xy * c01 + xz * c02);   /* positive definite: λ > 0 */
    double x[3] = { m[0] + (c00 * r[0] + c01 * r[1] + c02 * r[2]) * inverse,
                    m[1] + (c01 * r[0] + c11 * r[1] + c12 * r[2]) * inverse,
                    m[2] + (c02 * r[0] + c12 * r[1] + c22 * r[2]) * inverse };
    for (int k = 0; k < 3; k++) out[k] = (float)(x[k] < lo[k] ? lo[k] : x[k] > lo[k] + 2 ? lo[k] + 2 : x[k]);
}

/* False when two cells across a face whose corners alternate each hold both of its curves in
 * one piece: the edge between their vertices would lie in four triangles (rare in rocks). Where
 * one of them holds the curves apart, its two vertices each meet the other's one along an edge
 * of two triangles. */
static bool two_sheets_everywhere(const dual_grid *g) {
    for (size_t i = 0; i < g->crossed_count; i++) {   /* a face met twice is a crossed cell's */
        const size_t cell = g->crossed_cells[i];
        uint8_t faces = faces_met_twice[g->cell_case[cell]];
        if (!faces) continue;
        int at[3];
        cell_coordinates(g, cell, at);
        for (int axis = 0; axis < 3; axis++)   /* the upper face: the lower is the neighbour's */
            if (faces >> (2 * axis + 1) & 1 && at[axis] + 1 < g->cells[axis] &&
                faces_met_twice[g->cell_case[cell + (size_t)g->cell_stride[axis]]] >> (2 * axis) & 1)
                return false;
    }
    return true;
}

/* Each vertex placed; false when its crossings' normals disagree (see the top). */
static bool place_vertices(const dual_grid *g, rocks__surface *out) {
    out->vertex_count = g->vertex_count;
    out->positions = core_alloc(3 * (size_t)(g->vertex_count + 1) * sizeof *out->positions);
    out->normals = core_alloc(3 * (size_t)(g->vertex_count + 1) * sizeof *out->normals);
    for (size_t i = 0; i < g->crossed_count; i++) {
        const size_t cell = g->crossed_cells[i];
        int at[3];
        cell_coordinates(g, cell, at);
        const int lo[3] = { 2 * at[0] - 2, 2 * at[1] - 2, 2 * at[2] - 2 };
        for (int k = 0; k < piece_count[g->cell_case[cell]]; k++) {
            uint32_t v = (uint32_t)(g->cell_first[cell] + k);
            const qef *q = &g->qefs[v];
            float length = sqrtf(q->normal[0] * q->normal[0] + q->normal[1] * q->normal[1] + q->normal[2] * q->normal[2]);
            if (q->count == 0.0f || !(length >= AGREEMENT * q->count)) return false;   /* none, or they disagree */
            qef_point(q, lo, out->positions + 3 * (size_t)v);
            for (int a = 0; a < 3; a++) out->normals[3 * (size_t)v + a] = q->normal[a] / length;
        }
    }
    return true;
}

/* False when a crossing that no vertex's cell holds lies far from every vertex around it. */
static bool missed_nothing(const dual_grid *g, const rocks__surface *s) {
    for (size_t i = 0; i < g->missed_count; i++) {
        const float *p = g->missed[i];
        float best = INFINITY;
        int c[3];
        for (int a = 0; a < 3; a++) c[a] = ((int)floorf(p[a]) + 2) >> 1;
        for (int z = c[2] - 1; z <= c[2] + 1; z++)
            for (int y = c[1] - 1; y <= c[1] + 1; y++)
                for (int x = c[0] - 1; x <= c[0] + 1; x++) {
                    if (x < 0 || y < 0 || z < 0 || x >= g->cells[0] || y >= g->cells[1] || z >= g->cells[2]) continue;
                    size_t cell = (size_t)(z * g->cell_stride[2] + y * g->cell_stride[1] + x);
                    for (int k = 0; g->cell_first[cell] >= 0 && k < piece_count[g->cell_case[cell]]; k++) {
                        const float *v = s->positions + 3 * (size_t)(g->cell_first[cell] + k);
                        float d = (v[0] - p[0]) * (v[0] - p[0]) + (v[1] - p[1]) * (v[1] - p[1]) + (v[2] - p[2]) * (v[2] - p[2]);
                        best = d < best ? d : best;
                    }
                }
        if (!(best <= FAR_VOXELS * FAR_VOXELS)) return false;
    }
    return true;
}

/* The coarse edges from samples 1 … samples − 2 of row (y, z) that the surface crosses, along
 * x, y and z: bit x set where sample x and its neighbour along the axis differ in sign. */
static void crossed_edges(const dual_grid *g, int y, int z, uint64_t across[3]) {
    const uint64_t row = sample_row(g, y, z), inner = ((1ull << (g->samples[0] - 1)) - 1) & ~1ull;
    across[0] = (row ^ row >> 1) & inner;
    across[1] = (row ^ sample_row(g, y + 1, z)) & inner;
    across[2] = (row ^ sample_row(g, y, z + 1)) & inner;
}

/* Two triangles for each crossed coarse edge: the pieces of its four cells, counter-clockwise
 * seen from outside, split along the shorter diagonal. */
static void make_quads(const dual_grid *g, rocks__surface *out) {
    out->index_count = 0;
    const ptrdiff_t *cs = g->cell_stride;
    size_t quads = 0;   /* counted first: the indices in one allocation */
    for (int z = 1; z < g->samples[2] - 1; z++)
        for (int y = 1; y < g->samples[1] - 1; y++) {
            uint64_t across[3];
            crossed_edges(g, y, z, across);
            quads += (size_t)(__builtin_popcountll(across[0]) + __builtin_popcountll(across[1]) + __builtin_popcountll(across[2]));
        }
    out->index_cap = quads ? 6 * quads : 1;
    out->indices = core_alloc(out->index_cap * sizeof *out->indices);
    for (int z = 1; z < g->samples[2] - 1; z++)
        for (int y = 1; y < g->samples[1] - 1; y++) {
            const uint64_t row = sample_row(g, y, z);
            uint64_t across[3];
            crossed_edges(g, y, z, across);
            for (uint64_t edges = across[0] | across[1] | across[2]; edges; edges &= edges - 1) {
                const int x = __builtin_ctzll(edges);
                const bool solid = row >> x & 1;
                for (int axis = 0; axis < 3; axis++) {
                    if (!(across[axis] >> x & 1)) continue;
                    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
                    const ptrdiff_t here = z * cs[2] + y * cs[1] + x;
                    uint32_t v[4];
                    for (int k = 0; k < 4; k++) {   /* round the edge: (0, 0), (−1, 0), (−1, −1), (0, −1) on u, w */
                        int du = k == 1 || k == 2, dw = k >= 2;
                        size_t cell = (size_t)(here - du * cs[u] - dw * cs[w]);
                        int corner = du << u | dw << w;   /* the edge's low end, seen from that cell */
                        v[k] = (uint32_t)(g->cell_first[cell] + piece_of_edge[g->cell_case[cell]][edge_along(axis, corner)]);
                    }
                    if (!solid) {   /* solid towards +axis: the other way round */
                        uint32_t t = v[1];
                        v[1] = v[3], v[3] = t;
                    }
                    const float *p = out->positions;
                    float ac = 0.0f, bd = 0.0f;
                    for (int a = 0; a < 3; a++) {
                        float e0 = p[3 * v[0] + a] - p[3 * v[2] + a], e1 = p[3 * v[1] + a] - p[3 * v[3] + a];
                        ac += e0 * e0, bd += e1 * e1;
                    }
                    uint32_t *t = out->indices + out->index_count;
                    if (ac <= bd) t[0] = v[0], t[1] = v[1], t[2] = v[2], t[3] = v[0], t[4] = v[2], t[5] = v[3];
                    else t[0] = v[0], t[1] = v[1], t[2] = v[3], t[3] = v[1], t[4] = v[2], t[5] = v[3];
                    out->index_count += 6;
                }
            }
        }
}

static void dual_grid_free(dual_grid *g) {
    core_arena_release(&g->arena);
    core_free(g->missed, g->missed_cap * sizeof *g->missed);
}


bool rocks__dual_surface(const float *rho, const int size[3], rocks__surface *out) {
    pthread_once(&pieces_once, make_pieces);
    memset(out, 0, sizeof *out);
    if (size[0] > MAX_ROW) return false;
    dual_grid g = { .size = { size[0], size[1], size[2] } };
    make_fine(&g, rho);
    make_cells(&g);
    gather_crossings(&g);
    bool ok = g.vertex_count > 0 && two_sheets_everywhere(&g) && place_vertices(&g, out) && missed_nothing(&g, out);
    if (ok) make_quads(&g, out);

    dual_grid_free(&g);
    if (!ok) rocks__surface_free(out);
    return ok;
}

void rocks__surface_free(rocks__surface *s) {
    core_free(s->positions, 3 * (size_t)(s->vertex_count + 1) * sizeof *s->positions);
    core_free(s->normals, 3 * (size_t)(s->vertex_count + 1) * sizeof *s->normals);
    core_free(s->indices, s->index_cap * sizeof *s->indices);
    memset(s, 0, sizeof *s);
}
