/* terrain_clipmap.c — geometry clipmaps for the far terrain (002 §3.2, §3.5; Losasso & Hoppe,
 * "Geometry clipmaps", SIGGRAPH 2004).
 *
 * Levels. Level L is a square grid of n × n cells of s_L = finest·2^L metres; its vertex (i, k)
 * is the world point ((first_x + i)·s_L, (first_z + k)·s_L). Level 0 is centred on the camera,
 * snapped to desc.centre_snap (2·s_0 by default; the streamed rings' coarsest chunk in the game,
 * so that level 0 lies on their hole), and every coarser level is placed from the finer one
 * inside it:
 *     first_L = 2·⌊(first_{L−1}/2 − n/4) / 2⌋
 * so first_L is even (its border lies on level L + 1's vertex lines), the finer level starts
 * h = first_{L−1}/2 − first_L ∈ {n/4, n/4 + 1} cells in (only two cases per axis, see the
 * blocks below), and a level's centre is at most s_L behind the finer one's: the camera is
 * within snap/2 + s_0·(2^{L+1} − 2) of level L's centre (s_0·(2^{L+1} − 1) with the default).
 *
 * Heights. Each level keeps the heights of its vertices plus one ring (for normals) in a
 * toroidal array of (n + 4)² floats: grid point (i, k) lives at (i mod T, k mod T), so when the
 * level moves only the rows and columns that came in are computed (terrain__ground_row_spaced:
 * G with the octaves the spacing carries, 004 §4.1; with desc.world, the chunks' surface where
 * they are cached, below) and uploaded, at the same toroidal place in
 * one RGBA32F texture layer per level (the height, its normal's x and z, and the level of a lake
 * whose water holds the point, terrain__lake_row_spaced, packed at upload: one read per
 * vertex). A height depends only on its grid point and the chunks cached, so an incremental
 * update gives exactly the array a fresh build at the new place would (tested); when chunks are
 * generated, committed or evicted (the world's surface watch) a second pass recomputes the
 * texels whose columns they hold, in every level's window, and uploads their rows.
 *
 * Stacks. 002 §3.5 builds the clipmap's height map from the stacks. Where the four columns
 * around a grid point are cached, its height is the one the chunks' meshes draw there: the
 * topmost crossing of the mesher's field on the point's vertical line, sampled at the outermost
 * ring's vertical step (desc.mesh_step) and interpolated as the mesher does (corner_surface).
 * So edits show from afar, and along the hole's border the clipmap meets the meshes.
 *
 * Far lakes. The vertex shader stands a lake's vertices at its level (the drawn surface is
 * max(ground, lake), morphed as a whole) and clipmap.frag shades them as water; block bounds
 * take the lakes' levels in. Levels coarser than 8 m have no basins and so no lakes.
 *
 * Blocks. The vertex and index data are one static grid of (n + 1)² vertices shared by every
 * level (the vertex shader places and displaces them). Its cells are cut at 0, n/4, n/4 + 1,
 * n/2, 3n/4, 3n/4 + 1, n along each axis, and the four long segments again in halves
 * (TERRAIN__CLIPMAP_SPLIT), into 10 × 10 blocks, each a contiguous range of the index buffer.
 * The finer level covers exactly the cells [h, h + n/2) of each axis (h above), whole segments,
 * so a block is wholly covered or not at all: level L draws the blocks the finer level leaves,
 * those the frustum may see (bounds from the heights, the coarser level's under the morph and
 * the pit's depth where any hole reaches), neighbours in the buffer in one call.
 *
 * Seams. Each level's vertices geomorph to the coarser level's triangles near its border
 * (terrain__clipmap_morph, mirrored in shaders/clipmap.vert), reaching them exactly on it: every
 * finer border vertex lies on a coarser edge. Zero-area triangles along every level's border
 * (Losasso & Hoppe §3.2) cover the last rounding slivers of those T-junctions.
 *
 * The hole. The volumetric chunks replace the clipmap's centre (002 §3.5). The paper bends the
 * meso mesh's border to the clipmap's height; our chunks are meshed by another system, with open
 * borders. On G alone the chunks' surface lies above or below the clipmap along the border
 * (typically by a metre, up to 19 m: world.seam.max_gap.g_only); with the stacks' heights it
 * meets it at every border sample of the meshes (the seam, below). Either way the clipmap goes
 * under them inside the border, so no remaining gap shows sky: inside the hole it sinks, over hole_band metres
 * from the border, to hole_depth below the ground and stays there, a pit whose walls are a
 * skirt for the chunks' open border and whose floor lies deeper than the generator's caves.
 * A ray heading down through a gap at the border therefore meets the wall or, having passed
 * under the chunks' edge, the floor or the far wall: ground, never sky, whether it comes from
 * inside the hole or from outside. Cutting the centre out instead (discarding it) lets rays that
 * pass under the chunks' edge from outside reach the sky (render-tested: a few pixels per
 * view), and would show sky through an unmeshed chunk; the pit costs only hidden fragments,
 * which the depth test drops early (the shader never discards). Its one condition: the hole's
 * border lies on the finest level's vertex lines inside it (chunk borders do, at 4 m), else a
 * triangle straddling the border starts sinking outside it. A level wholly inside a hole (level
 * 0 of the rings' own spacing, snapped as they are, once their layout is in) is all pit: the
 * coarser level draws it instead (level_buried, below). The game starts at twice their spacing
 * instead (game/app.c), so none is.
 *
 * The seam. With the stacks' heights, a vertex on a hole's border keeps its own texel (α = 0)
 * whatever its level's morph (on_hole_border, clipmap.vert's `seam`): a level 0 of the rings'
 * spacing lies on their hole (centre_snap), so its border is the hole's, where the morph would
 * otherwise put its odd vertices on the next level's edges. Where a level's border runs along the hole's,
 * that opens a T-junction crack against the coarser level in the border's vertical plane; a ray
 * through it from outside runs under the chunks' edge into the pit (ground), and one from inside
 * has gone under the chunks' surface first. The pit's band starts at the border vertex, at the
 * meshes' height, so its wall stays hidden under the chunks.
 *
 * Several holes. Every viewer's rings replace the clipmap where they are, so there is one hole
 * per viewer (up to TERRAIN_CLIPMAP_MAX_HOLES), and the pit is their union's: a point sinks by
 * the deepest of the pits of the holes that hold it, max_h depth·clamp(inside_h / band, 0, 1).
 * Where two holes overlap by 2·band or more, every point of the overlap is a band inside one of
 * them, so the floor runs on without a wall; holes that only touch leave a ridge up to the ground
 * along the shared edge (each is 0 deep there). The exact distance to the union's border would
 * close that too, at the cost of a loop over every pair in the vertex shader.
 */
#include "terrain/render/terrain_render_internal.h"

#include "core/core.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SEGMENTS TERRAIN__CLIPMAP_SEGMENTS
#define BLOCKS TERRAIN__CLIPMAP_BLOCKS
#define EDGE_FADE 0.15f            /* the last 15 % of the outermost level fades into the sky */
#define CHANGE_BATCH 256           /* surface changes taken from the world at once */
#define SURFACE_RUNS 32            /* a column's topmost solid runs read for its surface */

typedef struct clipmap_level {
    int64_t first[2];               /* grid index of vertex (0, 0) (x, z), in spacings; even */
    double spacing;
    float octaves;
    bool valid;                     /* heights hold the window around `first` */
    float *heights;                 /* size × size, toroidal */
    float *lakes;                   /* the same: a lake's level, or TERRAIN__NO_LAKE */
    uint8_t *dirty_columns, *dirty_rows;  /* toroidal columns / rows to upload */
    uint8_t *stale, *stale_rows;    /* size² / size: toroidal texels whose chunks changed */
    bool stale_any;
    bool bounds_dirty;
    float block_min[BLOCKS], block_max[BLOCKS];
    bool in_frustum[BLOCKS];
    bool culled;                    /* in_frustum is for the current placement */
} clipmap_level;

/* One run of new heights: grid row k, grid columns i0 … i0 + count − 1 of a level. */
typedef struct row_task {
    int level, count;
    int64_t k, i0;
} row_task;

struct terrain_clipmap {
    terrain_clipmap_desc desc;      /* with the defaults filled in */
    terrain_clipmap_desc asked;     /* as given (terrain_clipmap_set_screen derives again) */
    int level_count, cells, size;   /* size = T = cells + 4 */
    clipmap_level levels[TERRAIN_CLIPMAP_MAX_LEVELS];
    bool has_camera;
    double camera[3];               /* of the last update */
    bool upload_pending;            /* heights changed since the last upload */
    uint8_t *upload_flags;          /* scratch of terrain_clipmap_upload: size */
    float (*upload_texels)[4];      /* scratch: size² packed texels */
    int hole_count;                 /* the non-empty holes, 0 … TERRAIN_CLIPMAP_MAX_HOLES */
    double hole_min[TERRAIN_CLIPMAP_MAX_HOLES][2], hole_max[TERRAIN_CLIPMAP_MAX_HOLES][2];
    int cuts[SEGMENTS + 1];         /* cell cuts of the blocks */
    uint32_t block_first[BLOCKS], block_count[BLOCKS];   /* index ranges */
    uint32_t *indices;              /* CPU copy until the first upload */
    size_t index_count;
    row_task *tasks;
    size_t task_count, task_capacity;
    terrain_chunk_coord *changes;   /* scratch of the update: the world's surface changes */
    terrain_clipmap_stats_info stats;
    gfx_texture texture;            /* one layer per level; { 0 } until the first upload */
    gfx_buffer index_buffer;
    gfx_vertex_array vertex_array;
};

/* ---- integer helpers ---- */

static int64_t floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

static int floor_mod(int64_t a, int m) {
    int64_t r = a % m;
    return (int)(r < 0 ? r + m : r);
}

/* ---- creation: defaults, block cuts, the shared index buffer ---- */

/* Detail from a screen-space error (terrain.h; terrain_screen_error.c): the fields left 0 among
 * cells, finest_spacing and levels, from K. Level L (spacing s_L) is drawn from n·s_L/4 out,
 * where the finer level ends, and the camera may be up to s_0·(2^{L+1} − 1) < 2·s_L from its
 * centre: it needs n·s_L/4 − 2·s_L ≥ ε(s_L)·K, so n ≥ 4·(K·ε(s)/s + 2) — the same for every
 * level, since ε is proportional to s; the finest spacing only has to hold from where the
 * volumetric rings end. */
static void clipmap_derive(terrain_clipmap_desc *d) {
    double scale = terrain_screen_error_scale(d->viewport_height, d->fov_y, d->pixel_error);
    if (scale <= 0.0) return;
    if (d->cells == 0) {
        double cells = 4.0 * (scale * terrain_clipmap_spacing_error(1.0) + 2.0);
        d->cells = cells >= 1024.0 ? 1024 : CORE_MAX(16, 16 * (int)ceil(cells / 16.0));
    }
    if (!(d->finest_spacing > 0.0f)) {
        float spacing = 1.0f;
        while (spacing < 32.0f && terrain_clipmap_spacing_error(2.0 * spacing) * scale <= (double)d->inner_distance)
            spacing *= 2.0f;
        d->finest_spacing = spacing;
    }
    if (d->levels == 0) {
        int cells = CORE_MAX(16, CORE_MIN(d->cells, 1024));
        d->levels = 1;
        while (d->levels < TERRAIN_CLIPMAP_MAX_LEVELS && 0.5 * cells * ldexp((double)d->finest_spacing, d->levels - 1) < 8192.0)
            d->levels++;
    }
}

static terrain_clipmap_desc clipmap_defaults(const terrain_clipmap_desc *in) {
    terrain_clipmap_desc d = *in;
    if (!(d.pixel_error > 0.0f)) d.pixel_error = 0.0f;
    clipmap_derive(&d);
    if (d.levels == 0) d.levels = 6;
    if (d.levels < 1 || d.levels > TERRAIN_CLIPMAP_MAX_LEVELS) {
        core_warn("terrain", "clipmap: %d levels is out of range 1…%d; clamped", d.levels, TERRAIN_CLIPMAP_MAX_LEVELS);
        d.levels = CORE_MAX(1, CORE_MIN(d.levels, TERRAIN_CLIPMAP_MAX_LEVELS));
    }
    if (d.cells == 0) d.cells = 128;
    if (d.cells < 16 || d.cells > 1024 || d.cells % 16) {
        int cells = CORE_MAX(16, CORE_MIN(d.cells, 1024)) / 16 * 16;
        core_warn("terrain", "clipmap: %d cells is not a multiple of 16 in 16…1024; using %d", d.cells, cells);
        d.cells = cells;
    }
    if (!(d.finest_spacing > 0.0f)) d.finest_spacing = 4.0f;
    if (!(d.hole_band > 0.0f)) d.hole_band = 2.0f * d.finest_spacing;
    if (!(d.mesh_step > 0.0f)) d.mesh_step = TERRAIN_COLUMN_SIZE;
    /* Level 0's centre on a grid of an even number of its spacings, no coarser than keeps each
     * coarser level's morph outside the finer level: the finer border lies up to half_L + b_L
     * from the camera (b_L = centre_offset_bound), the coarser morph starts at 2·half_L − b_L −
     * 2·s_L − w_{L+1}, so 2·b_L ≤ s_L·(n/2 − 2 − 2⌊n/10⌋); level 0 (b_0 = snap/2) is the tightest
     * for every n ≥ 16. */
    double unit = 2.0 * d.finest_spacing, widest = d.finest_spacing * (0.5 * d.cells - 2.0 - 2.0 * (d.cells / 10));
    double snap = d.centre_snap > 0.0f ? unit * floor(d.centre_snap / unit + 0.5) : unit;
    if (snap > widest) {
        core_warn("terrain", "clipmap: centre_snap %g m is over %g m for %d cells of %g m; clamped", d.centre_snap, widest,
                  d.cells, d.finest_spacing);
        snap = unit * floor(widest / unit);
    }
    d.centre_snap = (float)fmax(snap, unit);
    /* The pit's floor below every cave the generator carves (they end cave_fade_height + 1.5
     * cave wavelengths below G, 108 m by default), with room to spare. */
    if (!(d.hole_depth > 0.0f))
        d.hole_depth = CORE_MAX(d.generation.cave_fade_height + 1.5f * d.generation.cave_wavelength, 0.0f) + 48.0f;
    return d;
}

static uint32_t grid_vertex(const terrain_clipmap *c, int i, int k) { return (uint32_t)(k * (c->cells + 1) + i); }

static void push_triangle(terrain_clipmap *c, size_t *capacity, uint32_t a, uint32_t b, uint32_t d) {
    c->indices = core_grow(c->indices, capacity, c->index_count + 3, sizeof *c->indices);
    c->indices[c->index_count++] = a;
    c->indices[c->index_count++] = b;
    c->indices[c->index_count++] = d;
}

/* Zero-area triangles over each pair of border edges of the block's border cells, both ways
 * round so that whichever way rounding opens a sliver, one of them faces the camera. */
static void push_border_slivers(terrain_clipmap *c, size_t *capacity, int x0, int x1, int z0, int z1) {
    int n = c->cells;
    for (int side = 0; side < 4; side++) {
        bool along_x = side < 2;
        int line = side % 2 ? n : 0;
        if (along_x ? (line == 0 ? z0 != 0 : z1 != n) : (line == 0 ? x0 != 0 : x1 != n)) continue;
        int from = along_x ? x0 : z0, to = along_x ? x1 : z1;
        for (int a = from + (from & 1); a < to && a + 2 <= n; a += 2) {
            uint32_t v[3];
            for (int t = 0; t < 3; t++) v[t] = along_x ? grid_vertex(c, a + t, line) : grid_vertex(c, line, a + t);
            push_triangle(c, capacity, v[0], v[1], v[2]);
            push_triangle(c, capacity, v[2], v[1], v[0]);
        }
    }
}

static void build_blocks(terrain_clipmap *c) {
    int n = c->cells;
    const int base[7] = { 0, n / 4, n / 4 + 1, n / 2, 3 * n / 4, 3 * n / 4 + 1, n };
    int cuts[SEGMENTS + 1], count = 0;
    cuts[count++] = 0;
    for (int s = 0; s < 6; s++) {
        int parts = base[s + 1] - base[s] > 1 ? TERRAIN__CLIPMAP_SPLIT : 1;
        for (int k = 1; k <= parts; k++) cuts[count++] = base[s] + (base[s + 1] - base[s]) * k / parts;
    }
    memcpy(c->cuts, cuts, sizeof cuts);
    size_t capacity = 0;
    for (int b = 0; b < BLOCKS; b++) {
        int x0 = cuts[b % SEGMENTS], x1 = cuts[b % SEGMENTS + 1];
        int z0 = cuts[b / SEGMENTS], z1 = cuts[b / SEGMENTS + 1];
        c->block_first[b] = (uint32_t)c->index_count;
        /* Counter-clockwise seen from above (+y), split along (i, k)–(i + 1, k + 1): the
         * diagonal terrain__clipmap_morph's coarse surface assumes. */
        for (int k = z0; k < z1; k++) {
            for (int i = x0; i < x1; i++) {
                push_triangle(c, &capacity, grid_vertex(c, i, k), grid_vertex(c, i, k + 1), grid_vertex(c, i + 1, k + 1));
                push_triangle(c, &capacity, grid_vertex(c, i, k), grid_vertex(c, i + 1, k + 1), grid_vertex(c, i + 1, k));
            }
        }
        push_border_slivers(c, &capacity, x0, x1, z0, z1);
        c->block_count[b] = (uint32_t)c->index_count - c->block_first[b];
    }
    c->indices = core_realloc(c->indices, capacity * sizeof *c->indices, c->index_count * sizeof *c->indices);
}

static void clipmap_init(terrain_clipmap *c, const terrain_clipmap_desc *desc) {
    c->asked = *desc;
    c->desc = clipmap_defaults(desc);
    c->level_count = c->desc.levels;
    c->cells = c->desc.cells;
    c->size = c->cells + 4;
    size_t texels = (size_t)c->size * (size_t)c->size;
    for (int l = 0; l < c->level_count; l++) {
        clipmap_level *lv = &c->levels[l];
        lv->spacing = ldexp((double)c->desc.finest_spacing, l);
        lv->octaves = terrain__ground_octaves(&c->desc.generation, (float)lv->spacing);
        lv->heights = core_calloc(texels, sizeof(float));
        lv->lakes = core_calloc(texels, sizeof(float));
        lv->dirty_columns = core_calloc((size_t)c->size, 1);
        lv->dirty_rows = core_calloc((size_t)c->size, 1);
        lv->stale = core_calloc(texels, 1);
        lv->stale_rows = core_calloc((size_t)c->size, 1);
    }
    if (c->desc.world) terrain__world_watch_surface(c->desc.world, true);
    build_blocks(c);
    c->stats = (terrain_clipmap_stats_info){ .levels = c->level_count, .cells = c->cells,
                                        .finest_spacing = c->desc.finest_spacing };
}

terrain_clipmap *terrain_clipmap_create(const terrain_clipmap_desc *desc) {
    terrain_clipmap *c = core_calloc(1, sizeof *c);
    clipmap_init(c, desc ? desc : &(terrain_clipmap_desc){ 0 });
    return c;
}

/* Everything clipmap_init made and what the updates and uploads added, GL objects included. */
static void clipmap_fini(terrain_clipmap *c) {
    gfx_vertex_array_destroy(&c->vertex_array);
    gfx_buffer_destroy(&c->index_buffer);
    gfx_texture_destroy(&c->texture);
    size_t texels = (size_t)c->size * (size_t)c->size;
    for (int l = 0; l < c->level_count; l++) {
        core_free(c->levels[l].heights, texels * sizeof(float));
        core_free(c->levels[l].lakes, texels * sizeof(float));
        core_free(c->levels[l].dirty_columns, (size_t)c->size);
        core_free(c->levels[l].dirty_rows, (size_t)c->size);
        core_free(c->levels[l].stale, texels);
        core_free(c->levels[l].stale_rows, (size_t)c->size);
    }
    if (c->desc.world) terrain__world_watch_surface(c->desc.world, false);
    if (c->changes) core_free(c->changes, CHANGE_BATCH * sizeof *c->changes);
    if (c->indices) core_free(c->indices, c->index_count * sizeof *c->indices);
    if (c->upload_flags) core_free(c->upload_flags, (size_t)c->size);
    if (c->upload_texels) core_free(c->upload_texels, texels * sizeof *c->upload_texels);
    if (c->tasks) core_free(c->tasks, c->task_capacity * sizeof *c->tasks);
}

void terrain_clipmap_destroy(terrain_clipmap *c) {
    if (!c) return;
    clipmap_fini(c);
    core_free(c, sizeof *c);
}

bool terrain_clipmap_set_screen(terrain_clipmap *c, int viewport_height, float fov_y, float inner_distance) {
    if (!(c->asked.pixel_error > 0.0f)) return false;
    terrain_clipmap_desc asked = c->asked;
    asked.viewport_height = viewport_height;
    asked.fov_y = fov_y;
    asked.inner_distance = inner_distance;
    terrain_clipmap_desc d = clipmap_defaults(&asked);
    c->asked = asked;
    if (d.cells == c->desc.cells && d.finest_spacing == c->desc.finest_spacing && d.levels == c->desc.levels &&
        d.hole_band == c->desc.hole_band) {
        c->desc = d;
        return false;
    }
    /* Made anew: the holes stay, the heights come with the next update, GL with the next upload. */
    int hole_count = c->hole_count;
    double hole_min[TERRAIN_CLIPMAP_MAX_HOLES][2], hole_max[TERRAIN_CLIPMAP_MAX_HOLES][2];
    memcpy(hole_min, c->hole_min, sizeof hole_min);
    memcpy(hole_max, c->hole_max, sizeof hole_max);
    clipmap_fini(c);
    memset(c, 0, sizeof *c);
    clipmap_init(c, &asked);
    c->hole_count = hole_count;
    memcpy(c->hole_min, hole_min, sizeof hole_min);
    memcpy(c->hole_max, hole_max, sizeof hole_max);
    return true;
}

/* ---- placement ---- */

/* Where every level goes for a camera (see the file comment): level 0's centre is the camera
 * snapped to desc.centre_snap (2·s_0 by default). */
static void clipmap_place(const terrain_clipmap *c, const double camera[3], int64_t first[][2]) {
    int n = c->cells;
    int64_t snap = (int64_t)llround(c->desc.centre_snap / c->levels[0].spacing);   /* even, in s_0 */
    for (int axis = 0; axis < 2; axis++) {
        double s0 = c->levels[0].spacing, p = camera[axis ? 2 : 0];
        first[0][axis] = snap * (int64_t)floor(p / (snap * s0) + 0.5) - n / 2;
        for (int l = 1; l < c->level_count; l++) first[l][axis] = 2 * floor_div(first[l - 1][axis] / 2 - n / 4, 2);
    }
}

/* How far level L's centre can be from the camera of the update that placed it: half the snap
 * for level 0, and each coarser level's centre at most s_L behind the finer one's. */
static double centre_offset_bound(const terrain_clipmap *c, int level) {
    return 0.5 * c->desc.centre_snap + c->levels[0].spacing * (ldexp(1.0, level + 1) - 2.0);
}

/* Where the finer level starts inside level L, in L's cells (n/4 or n/4 + 1). */
static int finer_offset(const terrain_clipmap *c, int level, int axis) {
    return (int)(c->levels[level - 1].first[axis] / 2 - c->levels[level].first[axis]);
}

static terrain__clipmap_level_info level_info(const terrain_clipmap *c, int level) {
    const clipmap_level *lv = &c->levels[level];
    double half = 0.5 * c->cells * lv->spacing;
    double width = (double)(c->cells / 10) * lv->spacing;
    return (terrain__clipmap_level_info){
        .first = { lv->first[0], lv->first[1] }, .spacing = lv->spacing, .cells = c->cells, .octaves = lv->octaves,
        .morph_start = (float)(half - centre_offset_bound(c, level) - width), .morph_width = (float)width };
}

terrain__clipmap_level_info terrain__clipmap_level(const terrain_clipmap *c, int level) { return level_info(c, level); }

/* ---- heights: planning the new rows and columns, computing them ---- */

static void add_task(terrain_clipmap *c, int level, int64_t k, int64_t i0, int count) {
    if (count <= 0) return;
    c->tasks = core_grow(c->tasks, &c->task_capacity, c->task_count + 1, sizeof *c->tasks);
    c->tasks[c->task_count++] = (row_task){ .level = level, .count = count, .k = k, .i0 = i0 };
}

static void mark_range(uint8_t *flags, int size, int64_t from, int count) {
    for (int j = 0; j < count && j < size; j++) flags[floor_mod(from + j, size)] = 1;
}

/* The rows and columns of level L's window [first − 1, first + n + 2) that the move from its
 * current place to `next` brings in. */
static bool plan_level(terrain_clipmap *c, int level, const int64_t next[2]) {
    clipmap_level *lv = &c->levels[level];
    const int width = c->cells + 3;
    int64_t old_lo[2] = { lv->first[0] - 1, lv->first[1] - 1 }, new_lo[2] = { next[0] - 1, next[1] - 1 };
    bool moved = !lv->valid || next[0] != lv->first[0] || next[1] != lv->first[1];
    bool full = !lv->valid || llabs(next[0] - lv->first[0]) >= width || llabs(next[1] - lv->first[1]) >= width;
    for (int64_t k = new_lo[1]; k < new_lo[1] + width; k++) {
        bool old_row = !full && k >= old_lo[1] && k < old_lo[1] + width;
        if (!old_row) {
            add_task(c, level, k, new_lo[0], width);
            lv->dirty_rows[floor_mod(k, c->size)] = 1;
        } else if (next[0] > lv->first[0]) {
            add_task(c, level, k, old_lo[0] + width, (int)(next[0] - lv->first[0]));
        } else if (next[0] < lv->first[0]) {
            add_task(c, level, k, new_lo[0], (int)(lv->first[0] - next[0]));
        }
    }
    if (!full && next[0] > lv->first[0]) mark_range(lv->dirty_columns, c->size, old_lo[0] + width, (int)(next[0] - lv->first[0]));
    if (!full && next[0] < lv->first[0]) mark_range(lv->dirty_columns, c->size, new_lo[0], (int)(lv->first[0] - next[0]));
    if (full) memset(lv->dirty_columns, 1, (size_t)c->size);
    if (moved) {
        lv->bounds_dirty = true;
        lv->culled = false;
        if (level > 0) c->levels[level - 1].bounds_dirty = true;   /* its morph target moved */
    }
    lv->first[0] = next[0];
    lv->first[1] = next[1];
    lv->valid = true;
    return full;
}

/* ---- heights from the stacks where chunks are cached (002 §3.5) ----
 *
 * 002 §3.5 makes the clipmap's height map from the stacks ("sum the heights of all our
 * layers"). Ours is the height the chunks' meshes draw at the grid point, so that near and far
 * meet along the hole's border: the mesher's field f (000 §3.3, σ one column) at the point is a
 * column corner's, whose kernel covers exactly the four columns around it, f(y) = L(y)/4 − 1
 * with L the solid length of the four columns within [y − 1, y + 1]; a mesh of vertical step s
 * finds the topmost sign change of f between samples at multiples of s and places its vertex
 * at the linear crossing (terrain__mesh_edge_t, from the lower sample). On level ground this is
 * the columns' top exactly; on a slope, for step 1, the mean of the four tops. At coarser
 * spacings the value is the same point sample at the grid point (no average over the cell): the
 * grid points are the meshes' own samples when the spacings agree, and the level's morph does
 * the filtering between levels. Amplification (terrain_world_desc.amplify) is not seen. */

typedef struct chunk_memo {
    terrain_chunk_coord coord[4];
    const terrain_stacks *stacks[4];
    int count, next;
} chunk_memo;

static const terrain_stacks *memo_stacks(terrain_world *world, chunk_memo *memo, terrain_chunk_coord coord) {
    for (int m = 0; m < memo->count; m++)
        if (memo->coord[m].x == coord.x && memo->coord[m].z == coord.z) return memo->stacks[m];
    const terrain_stacks *stacks = terrain__world_surface_stacks(world, coord);
    int slot = memo->count < 4 ? memo->count++ : (memo->next++ & 3);
    memo->coord[slot] = coord;
    memo->stacks[slot] = stacks;
    return stacks;
}

/* A column's topmost solid runs (metres); below the lowest kept run it counts as solid. */
typedef struct column_runs {
    int count;
    double bottom[SURFACE_RUNS], top[SURFACE_RUNS];
    double lake;                    /* its water's top when a lake lies on it, else −∞ */
} column_runs;

/* Appends a solid run, keeping the topmost SURFACE_RUNS: the lowest merges into the one above. */
static void push_run(column_runs *out, double bottom, double top) {
    if (out->count == SURFACE_RUNS) {
        memmove(out->bottom, out->bottom + 1, (SURFACE_RUNS - 1) * sizeof *out->bottom);
        memmove(out->top, out->top + 1, (SURFACE_RUNS - 1) * sizeof *out->top);
        out->bottom[0] = -INFINITY;
        out->count--;
    }
    out->bottom[out->count] = bottom;
    out->top[out->count++] = top;
}

static void read_column(const terrain_stacks *stacks, int i, int k, float sea_level, column_runs *out) {
    out->count = 0;
    out->lake = -INFINITY;
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
    terrain__qlayer layer;
    int64_t height = 0;
    bool solid = true;              /* below the floor: bedrock */
    double bottom = -INFINITY;
    while (terrain__cursor_next(&cursor, &layer)) {
        bool in_field = terrain_material_in_field((terrain_material)layer.material);
        if (in_field != solid && layer.quanta > 0) {
            double y = TERRAIN_FLOOR_Y + (double)height * TERRAIN_HEIGHT_QUANTUM;
            if (solid) push_run(out, bottom, y);
            else bottom = y;
            solid = in_field;
        }
        height += layer.quanta;
    }
    if (solid) push_run(out, bottom, TERRAIN_FLOOR_Y + (double)height * TERRAIN_HEIGHT_QUANTUM);   /* air above */
    int64_t surface, ground;
    if (terrain__stacks_water(stacks, i, k, &surface, &ground)) {
        double top = TERRAIN_FLOOR_Y + (double)surface * TERRAIN_HEIGHT_QUANTUM;
        /* The sea is drawn as ground under sea level (clipmap.frag), a lake as water. */
        if (top > (double)sea_level + 0.5 * TERRAIN_HEIGHT_QUANTUM) out->lake = top;
    }
}

/* f at height y of the corner whose kernel covers the four columns. */
static float corner_field(const column_runs columns[4], double y) {
    double solid = 0.0;
    for (int c = 0; c < 4; c++)
        for (int r = columns[c].count - 1; r >= 0; r--) {
            if (columns[c].top[r] <= y - 1.0) break;          /* runs below lie lower still */
            double lo = fmax(columns[c].bottom[r], y - 1.0), hi = fmin(columns[c].top[r], y + 1.0);
            solid += hi > lo ? hi - lo : 0.0;
        }
    return (float)(solid / 4.0 - 1.0);
}

/* The surface a mesh of vertical step `step` draws at the corner of columns x − 1, x and
 * z − 1, z (above), and the lake on them; false when any of the four is not cached. */
static bool corner_surface(const terrain_clipmap *c, chunk_memo *memo, int64_t x, int64_t z, float *height, float *lake) {
    column_runs columns[4];
    double highest = TERRAIN_FLOOR_Y, water = -INFINITY;
    for (int n = 0; n < 4; n++) {
        int64_t column_x = x - 1 + (n & 1), column_z = z - 1 + (n >> 1);
        terrain_chunk_coord coord = { floor_div(column_x, TERRAIN_CHUNK_COLUMNS), floor_div(column_z, TERRAIN_CHUNK_COLUMNS) };
        const terrain_stacks *stacks = memo_stacks(c->desc.world, memo, coord);
        if (!stacks) return false;
        read_column(stacks, (int)(column_x - coord.x * TERRAIN_CHUNK_COLUMNS), (int)(column_z - coord.z * TERRAIN_CHUNK_COLUMNS),
                    c->desc.generation.sea_level, &columns[n]);
        const column_runs *runs = &columns[n];
        if (runs->count > 0) highest = fmax(highest, runs->top[runs->count - 1]);
        water = fmax(water, runs->lake);
    }
    /* From the first sample above every solid (f = −1) down to the first one not in air. A sample
     * with f = 0 exactly lies on the surface itself: where two of the four columns are solid and
     * two are air over a stretch (a wall through the corner), f is 0 all along it, and the mesh
     * draws that vertical face up to its topmost such sample; the height is that sample's. */
    double step = c->desc.mesh_step;
    double y = step * ceil((highest + 1.0) / step);
    float above = corner_field(columns, y);
    *height = TERRAIN_FLOOR_Y;
    for (int guard = 0; guard < 4096 && y > TERRAIN_FLOOR_Y - step; guard++) {
        float below = corner_field(columns, y - step);
        if (below >= 0.0f) {
            *height = (float)(y - step + (double)terrain__mesh_edge_t(below, above) * step);
            break;
        }
        above = below;
        y -= step;
    }
    *lake = isfinite(water) ? (float)water : TERRAIN__NO_LAKE;
    return true;
}

/* Overwrites the grid points of a run whose columns are cached with the chunks' surface. */
static void surface_run(const terrain_clipmap *c, const clipmap_level *lv, int64_t i0, int64_t k, int count, float *heights,
                        float *lakes) {
    if (!c->desc.world) return;
    chunk_memo memo = { .count = 0 };
    int64_t z = (int64_t)floor((double)k * lv->spacing / TERRAIN_COLUMN_SIZE);
    for (int j = 0; j < count; j++) {
        int64_t x = (int64_t)floor((double)(i0 + j) * lv->spacing / TERRAIN_COLUMN_SIZE);
        float height, lake;
        if (!corner_surface(c, &memo, x, z, &height, &lake)) continue;
        heights[j] = height;
        lakes[j] = lake;
    }
}

static void run_task(terrain_clipmap *c, const row_task *t) {
    clipmap_level *lv = &c->levels[t->level];
    size_t row_start = (size_t)floor_mod(t->k, c->size) * (size_t)c->size;
    float *row = lv->heights + row_start, *lakes = lv->lakes + row_start;
    int64_t i = t->i0;
    for (int left = t->count; left > 0;) {
        int start = floor_mod(i, c->size), run = CORE_MIN(left, c->size - start);   /* split at the wrap */
        double x0 = (double)i * lv->spacing, z = (double)t->k * lv->spacing;
        terrain__ground_row_spaced(&c->desc.generation, x0, lv->spacing, z, run, (float)lv->spacing, row + start,
                                   lakes + start);
        surface_run(c, lv, i, t->k, run, row + start, lakes + start);
        i += run;
        left -= run;
    }
}

static void run_task_range(void *user, size_t begin, size_t end) {
    terrain_clipmap *c = user;
    for (size_t t = begin; t < end; t++) run_task(c, &c->tasks[t]);
}

/* ---- the dirty rectangles: texels whose chunks came, changed or went ---- */

/* Marks the grid points of every level whose four columns include one of the chunk's, within
 * the level's window, for recomputing (and their rows for upload). */
static void mark_chunk(terrain_clipmap *c, terrain_chunk_coord coord, const bool *full) {
    const int width = c->cells + 3;
    double lo[2] = { (double)coord.x * TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE,
                     (double)coord.z * TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE };
    for (int l = 0; l < c->level_count; l++) {
        clipmap_level *lv = &c->levels[l];
        if (full[l]) continue;                         /* every texel is new anyway */
        int64_t from[2], to[2];
        bool empty = false;
        for (int a = 0; a < 2; a++) {
            /* Point x reads columns x − 1 and x: those in [lo, lo + N) for x in [lo, lo + N]. */
            from[a] = CORE_MAX((int64_t)ceil(lo[a] / lv->spacing), lv->first[a] - 1);
            to[a] = CORE_MIN((int64_t)floor((lo[a] + TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE) / lv->spacing),
                             lv->first[a] - 1 + width - 1);
            empty |= from[a] > to[a];
        }
        if (empty) continue;
        for (int64_t k = from[1]; k <= to[1]; k++) {
            int row = floor_mod(k, c->size);
            uint8_t *stale = lv->stale + (size_t)row * (size_t)c->size;
            for (int64_t i = from[0]; i <= to[0]; i++) stale[floor_mod(i, c->size)] = 1;
            lv->stale_rows[row] = 1;
            lv->dirty_rows[row] = 1;
        }
        lv->stale_any = true;
        lv->bounds_dirty = true;
        if (l > 0) c->levels[l - 1].bounds_dirty = true;   /* its morph target changed */
    }
}

/* Row tasks for the marked texels, in grid order, each texel once; clears the marks. */
static void plan_stale(terrain_clipmap *c, int level) {
    clipmap_level *lv = &c->levels[level];
    const int width = c->cells + 3;
    if (!lv->stale_any) return;
    for (int64_t k = lv->first[1] - 1; k < lv->first[1] - 1 + width; k++) {
        int row = floor_mod(k, c->size);
        if (!lv->stale_rows[row]) continue;
        uint8_t *stale = lv->stale + (size_t)row * (size_t)c->size;
        for (int64_t i = lv->first[0] - 1, end = i + width; i < end;) {
            if (!stale[floor_mod(i, c->size)]) { i++; continue; }
            int64_t run = i;
            while (run < end && stale[floor_mod(run, c->size)]) run++;
            add_task(c, level, k, i, (int)(run - i));
            i = run;
        }
        memset(stale, 0, (size_t)c->size);
        lv->stale_rows[row] = 0;
    }
    lv->stale_any = false;
}

/* Takes the world's surface changes and marks what they touch; returns whether any came. */
static bool take_surface_changes(terrain_clipmap *c, const bool *full) {
    if (!c->desc.world) return false;
    if (!c->changes) c->changes = core_alloc(CHANGE_BATCH * sizeof *c->changes);
    bool any = false;
    for (int count; (count = terrain__world_take_surface_changes(c->desc.world, c->changes, CHANGE_BATCH)) > 0;) {
        for (int n = 0; n < count; n++) mark_chunk(c, c->changes[n], full);
        any = true;
    }
    return any;
}

/* ---- block bounds ---- */

static void texel_range(const terrain_clipmap *c, const float *texels, int64_t i0, int64_t i1, int64_t k0, int64_t k1,
                        float *lo, float *hi) {
    int first_column = floor_mod(i0, c->size), columns = (int)(i1 - i0 + 1);
    float low = *lo, high = *hi;                  /* locals: the loop then vectorises */
    for (int64_t k = k0; k <= k1; k++) {
        const float *row = texels + (size_t)floor_mod(k, c->size) * (size_t)c->size;
        /* The row's texels are one or two runs of the toroidal array. */
        for (int column = first_column, left = columns; left > 0;) {
            int run = CORE_MIN(left, c->size - column);
            for (int j = column; j < column + run; j++) {
                low = row[j] < low ? row[j] : low;
                high = row[j] > high ? row[j] : high;
            }
            left -= run;
            column = 0;
        }
    }
    *lo = low;
    *hi = high;
}

/* The heights and lake levels texels [i0, i1] × [k0, k1] of a level reach: the lakes raise the
 * top only (their sentinel lies far below any ground). */
static void level_range(const terrain_clipmap *c, int level, int64_t i0, int64_t i1, int64_t k0, int64_t k1, float *lo,
                        float *hi) {
    float unused = INFINITY;
    texel_range(c, c->levels[level].heights, i0, i1, k0, k1, lo, hi);
    texel_range(c, c->levels[level].lakes, i0, i1, k0, k1, &unused, hi);
}

/* Heights a block can be drawn at: its own vertices (and one more cell around, for the border
 * slivers) and, because it may morph, the coarser level's vertices under it. */
static void level_bounds(terrain_clipmap *c, int level) {
    clipmap_level *lv = &c->levels[level];
    for (int b = 0; b < BLOCKS; b++) {
        int x0 = CORE_MAX(c->cuts[b % SEGMENTS] - 1, 0), x1 = CORE_MIN(c->cuts[b % SEGMENTS + 1] + 1, c->cells);
        int z0 = CORE_MAX(c->cuts[b / SEGMENTS] - 1, 0), z1 = CORE_MIN(c->cuts[b / SEGMENTS + 1] + 1, c->cells);
        float lo = INFINITY, hi = -INFINITY;
        level_range(c, level, lv->first[0] + x0, lv->first[0] + x1, lv->first[1] + z0, lv->first[1] + z1, &lo, &hi);
        if (level + 1 < c->level_count)
            level_range(c, level + 1, floor_div(lv->first[0] + x0, 2), floor_div(lv->first[0] + x1 + 1, 2),
                        floor_div(lv->first[1] + z0, 2), floor_div(lv->first[1] + z1 + 1, 2), &lo, &hi);
        lv->block_min[b] = lo;
        lv->block_max[b] = hi;
    }
    lv->bounds_dirty = false;
}

/* ---- update ---- */

/* Runs the planned tasks; returns how many texels they computed. */
static uint64_t run_tasks(terrain_clipmap *c, uint64_t parallel_from) {
    uint64_t texels = 0;
    for (size_t t = 0; t < c->task_count; t++) texels += (uint64_t)c->tasks[t].count;
    if (c->desc.jobs && texels > parallel_from)
        job_parallel_for(c->desc.jobs, c->task_count, 0, run_task_range, c, "terrain.clipmap.heights");
    else
        run_task_range(c, 0, c->task_count);
    return texels;
}

uint64_t terrain_clipmap_update(terrain_clipmap *c, const double camera[3]) {
    TRACE_ZONE("terrain_clipmap_update");
    if (!isfinite(camera[0]) || !isfinite(camera[2]) || fabs(camera[0]) > 1e15 || fabs(camera[2]) > 1e15) {
        core_warn("terrain", "clipmap: camera (%g, %g, %g) ignored", camera[0], camera[1], camera[2]);
        return 0;
    }
    int64_t next[TERRAIN_CLIPMAP_MAX_LEVELS][2];
    clipmap_place(c, camera, next);
    c->task_count = 0;
    bool full[TERRAIN_CLIPMAP_MAX_LEVELS];
    for (int l = 0; l < c->level_count; l++) full[l] = plan_level(c, l, next[l]);
    /* Two passes, each computing any texel once: what the move brought in, then what changed
     * in the world (002 §3.5), which may overlap it. */
    /* A walk's step (a band two texels wide: about a microsecond a row) is not worth waking the
     * workers for; a jump or the first build is. A texel of the stacks costs about 0.6 µs
     * (release, against 0.15 for G's): new chunks' texels fan out from 1024. */
    uint64_t texels = run_tasks(c, 4096);
    if (take_surface_changes(c, full)) {
        c->task_count = 0;
        for (int l = 0; l < c->level_count; l++) plan_stale(c, l);
        texels += run_tasks(c, 1024);
    }
    for (int l = 0; l < c->level_count; l++)
        if (c->levels[l].bounds_dirty) level_bounds(c, l);
    memcpy(c->camera, camera, sizeof c->camera);
    c->has_camera = true;
    c->upload_pending |= texels > 0;
    c->stats.texels_updated = texels;
    c->stats.reach = 0.5 * c->cells * c->levels[c->level_count - 1].spacing - centre_offset_bound(c, c->level_count - 1);
    return texels;
}

void terrain_clipmap_set_holes(terrain_clipmap *c, const double (*min_xz)[2], const double (*max_xz)[2], int count) {
    if (count > TERRAIN_CLIPMAP_MAX_HOLES) {
        core_warn("terrain", "clipmap: %d holes, at most %d; the rest are left out", count, TERRAIN_CLIPMAP_MAX_HOLES);
        count = TERRAIN_CLIPMAP_MAX_HOLES;
    }
    if (!min_xz || !max_xz) count = 0;
    c->hole_count = 0;
    for (int h = 0; h < count; h++) {
        if (!(min_xz[h][0] < max_xz[h][0] && min_xz[h][1] < max_xz[h][1])) continue;   /* empty (or NaN) */
        memcpy(c->hole_min[c->hole_count], min_xz[h], sizeof min_xz[h]);
        memcpy(c->hole_max[c->hole_count], max_xz[h], sizeof max_xz[h]);
        c->hole_count++;
    }
}

void terrain_clipmap_set_hole(terrain_clipmap *c, const double min_xz[2], const double max_xz[2]) {
    if (!min_xz || !max_xz) {
        terrain_clipmap_set_holes(c, NULL, NULL, 0);
        return;
    }
    const double lo[1][2] = { { min_xz[0], min_xz[1] } }, hi[1][2] = { { max_xz[0], max_xz[1] } };
    terrain_clipmap_set_holes(c, lo, hi, 1);
}

int terrain__clipmap_holes(const terrain_clipmap *c, const double camera[3], float holes[][4]) {
    for (int h = 0; h < c->hole_count; h++) {
        holes[h][0] = (float)(c->hole_min[h][0] - camera[0]);
        holes[h][1] = (float)(c->hole_min[h][1] - camera[2]);
        holes[h][2] = (float)(c->hole_max[h][0] - camera[0]);
        holes[h][3] = (float)(c->hole_max[h][1] - camera[2]);
    }
    return c->hole_count;
}

/* clipmap.vert's hole_depth_inside and sink, step for step (the tests hold the two alike). */
float terrain__clipmap_sink(const terrain_clipmap *c, const double camera[3], const float position[2]) {
    float holes[TERRAIN_CLIPMAP_MAX_HOLES][4];
    int count = terrain__clipmap_holes(c, camera, holes);
    float band = c->desc.hole_band, depth = c->desc.hole_depth, sink = 0.0f;
    for (int h = 0; h < count; h++) {
        const float *u = holes[h];
        float inside = fminf(fminf(position[0] - u[0], u[2] - position[0]), fminf(position[1] - u[1], u[3] - position[1]));
        float ratio = inside / band;
        ratio = ratio < 0.0f ? 0.0f : ratio > 1.0f ? 1.0f : ratio;
        sink = fmaxf(sink, inside > 0.0f ? depth * ratio : 0.0f);
    }
    return sink;
}

/* ---- blocks and culling ---- */

/* The finer level covers cells [h, h + n/2) of level L along each axis. */
static bool segment_in_finer(const terrain_clipmap *c, int level, int axis, int segment) {
    int h = finer_offset(c, level, axis);
    return c->cuts[segment] >= h && c->cuts[segment + 1] <= h + c->cells / 2;
}

/* Whether the level lies wholly inside one hole: all of it would be pit under the chunks. A
 * level 0 of the rings' spacing and snap is the rings' hole itself once their layout is in:
 * a fifth of the clipmap's triangles, every one hidden. The coarser level draws the pit there
 * instead, at its own spacing: the pit's floor needs no detail, and its wall is the same (the
 * sink is linear across hole_band, one coarser cell at the default band), its border vertices
 * on the hole's border with their own heights as before. */
static bool level_buried(const terrain_clipmap *c, int level) {
    const clipmap_level *lv = &c->levels[level];
    if (!lv->valid) return false;
    for (int h = 0; h < c->hole_count; h++) {
        bool inside = true;
        for (int a = 0; a < 2; a++) {
            double lo = (double)lv->first[a] * lv->spacing, hi = (double)(lv->first[a] + c->cells) * lv->spacing;
            inside = inside && lo >= c->hole_min[h][a] && hi <= c->hole_max[h][a];
        }
        if (inside) return true;
    }
    return false;
}

terrain__clipmap_block_info terrain__clipmap_block(const terrain_clipmap *c, int level, int block) {
    const clipmap_level *lv = &c->levels[level];
    int sx = block % SEGMENTS, sz = block / SEGMENTS;
    terrain__clipmap_block_info info = { .cells_min = { c->cuts[sx], c->cuts[sz] },
                                         .cells_max = { c->cuts[sx + 1], c->cuts[sz + 1] } };
    /* One cell more around, for the border slivers; heights from level_bounds. */
    for (int a = 0; a < 2; a++) {
        info.box_min[a ? 2 : 0] = (double)(lv->first[a] + info.cells_min[a] - 1) * lv->spacing;
        info.box_max[a ? 2 : 0] = (double)(lv->first[a] + info.cells_max[a] + 1) * lv->spacing;
    }
    info.box_min[1] = lv->block_min[block];
    info.box_max[1] = lv->block_max[block];
    if (!lv->valid) return info;
    bool in_finer = level > 0 && !level_buried(c, level - 1) && segment_in_finer(c, level, 0, sx) &&
                    segment_in_finer(c, level, 1, sz);
    /* Blocks reaching into any hole are drawn sunk there (the pit). */
    for (int h = 0; h < c->hole_count; h++)
        if (info.box_max[0] > c->hole_min[h][0] && info.box_min[0] < c->hole_max[h][0] && info.box_max[2] > c->hole_min[h][1] &&
            info.box_min[2] < c->hole_max[h][1]) {
            info.box_min[1] -= c->desc.hole_depth;
            break;
        }
    info.covered = in_finer || level_buried(c, level);
    info.visible = !info.covered && (!lv->culled || lv->in_frustum[block]);
    return info;
}

int terrain_clipmap_cull(terrain_clipmap *c, const terrain_frustum *frustum) {
    TRACE_ZONE("terrain_clipmap_cull");
    int visible = 0;
    uint64_t triangles = 0;
    for (int l = 0; l < c->level_count; l++) {
        clipmap_level *lv = &c->levels[l];
        if (!lv->valid) continue;
        for (int b = 0; b < BLOCKS; b++) {
            terrain__clipmap_block_info info = terrain__clipmap_block(c, l, b);
            float size[3];
            for (int a = 0; a < 3; a++) size[a] = (float)(info.box_max[a] - info.box_min[a]);
            lv->in_frustum[b] = !info.covered && terrain_frustum_sees(frustum, info.box_min, (const float[3]){ 0, 0, 0 }, size);
            visible += lv->in_frustum[b];
            triangles += lv->in_frustum[b] ? c->block_count[b] / 3 : 0;
        }
        lv->culled = true;
    }
    c->stats.blocks_visible = visible;
    c->stats.triangles_visible = triangles;
    return visible;
}

/* ---- the CPU mirror of clipmap.vert ---- */

float terrain__clipmap_texel(const terrain_clipmap *c, int level, int64_t i, int64_t k) {
    const clipmap_level *lv = &c->levels[level];
    if (!lv->valid || i < lv->first[0] - 1 || i > lv->first[0] + c->cells + 1 || k < lv->first[1] - 1 ||
        k > lv->first[1] + c->cells + 1)
        return NAN;
    return lv->heights[(size_t)floor_mod(k, c->size) * (size_t)c->size + (size_t)floor_mod(i, c->size)];
}

/* The uniforms of one level, as the draw sets them: everything the GPU sees is small. */
typedef struct level_uniforms {
    float anchor[2];                /* the outermost level's vertex (0, 0) − camera (x, z) */
    int offset[2];                  /* this level's vertex (0, 0) from the anchor, in its spacings */
    float spacing, morph_start, morph_inverse_width;
    float morph_centre[2];          /* the camera of the last update − this camera (x, z) */
    int start[2], coarse_start[2];  /* toroidal texels of vertex (0, 0) here and in the coarser level */
} level_uniforms;

static level_uniforms uniforms_for(const terrain_clipmap *c, int level, const double camera[3]) {
    const clipmap_level *lv = &c->levels[level], *top = &c->levels[c->level_count - 1];
    terrain__clipmap_level_info info = level_info(c, level);
    level_uniforms u = { .spacing = (float)lv->spacing, .morph_start = info.morph_start,
                         .morph_inverse_width = 1.0f / info.morph_width };
    int scale_shift = c->level_count - 1 - level;
    for (int a = 0; a < 2; a++) {
        /* In double: anchor and camera may be far from the origin, their difference is not. */
        u.anchor[a] = (float)((double)top->first[a] * top->spacing - camera[a ? 2 : 0]);
        u.morph_centre[a] = (float)(c->camera[a ? 2 : 0] - camera[a ? 2 : 0]);
        u.offset[a] = (int)(lv->first[a] - top->first[a] * ((int64_t)1 << scale_shift));
        u.start[a] = floor_mod(lv->first[a], c->size);
        u.coarse_start[a] = floor_mod(lv->first[a] / 2, c->size);
    }
    return u;
}

/* Whether a camera-relative vertex position lies on a hole's border (clipmap.vert's `seam`):
 * with the world's heights there, the vertex keeps its own (002 §3.5: where near and far meet the
 * clipmap takes the chunks' height), however the level morphs around it. */
static bool on_hole_border(const terrain_clipmap *c, const double camera[3], const float position[2], float spacing) {
    if (!c->desc.world) return false;
    float holes[TERRAIN_CLIPMAP_MAX_HOLES][4];
    int count = terrain__clipmap_holes(c, camera, holes);
    for (int h = 0; h < count; h++) {
        const float *u = holes[h];
        float inside = fminf(fminf(position[0] - u[0], u[2] - position[0]), fminf(position[1] - u[1], u[3] - position[1]));
        if (fabsf(inside) <= 1e-3f * spacing) return true;
    }
    return false;
}

static float level_vertex_height(const terrain_clipmap *c, int level, int i, int k, const level_uniforms *u,
                                 const float position[2], const double camera[3]) {
    const clipmap_level *lv = &c->levels[level];
    float fine = terrain__clipmap_texel(c, level, lv->first[0] + i, lv->first[1] + k);
    if (level + 1 >= c->level_count) return fine;
    int64_t ci = lv->first[0] / 2 + i / 2, ck = lv->first[1] / 2 + k / 2;
    float coarse = 0.5f * (terrain__clipmap_texel(c, level + 1, ci, ck) +
                           terrain__clipmap_texel(c, level + 1, ci + (i & 1), ck + (k & 1)));
    bool border = i == 0 || k == 0 || i == c->cells || k == c->cells;
    float alpha = terrain__clipmap_morph(position[0] - u->morph_centre[0], position[1] - u->morph_centre[1], u->morph_start,
                                         u->morph_inverse_width, border);
    if (on_hole_border(c, camera, position, u->spacing)) alpha = 0.0f;
    return (1.0f - alpha) * fine + alpha * coarse;
}

void terrain__clipmap_vertex(const terrain_clipmap *c, int level, int i, int k, const double camera[3], float position[2],
                             float *height) {
    level_uniforms u = uniforms_for(c, level, camera);
    position[0] = u.anchor[0] + (float)(u.offset[0] + i) * u.spacing;
    position[1] = u.anchor[1] + (float)(u.offset[1] + k) * u.spacing;
    *height = level_vertex_height(c, level, i, k, &u, position, camera);
}

float terrain_clipmap_height(const terrain_clipmap *c, double x, double z) {
    if (!c->has_camera) return NAN;
    for (int l = 0; l < c->level_count; l++) {
        const clipmap_level *lv = &c->levels[l];
        double gx = x / lv->spacing - (double)lv->first[0], gz = z / lv->spacing - (double)lv->first[1];
        if (!(gx >= 0 && gz >= 0 && gx <= c->cells && gz <= c->cells)) continue;
        int i = CORE_MIN((int)gx, c->cells - 1), k = CORE_MIN((int)gz, c->cells - 1);
        float fx = (float)(gx - i), fz = (float)(gz - k), h[2][2];
        for (int dz = 0; dz < 2; dz++)
            for (int dx = 0; dx < 2; dx++) {
                float position[2];
                terrain__clipmap_vertex(c, l, i + dx, k + dz, c->camera, position, &h[dz][dx]);
            }
        /* The triangle of the cell that holds the point (the diagonal runs (0, 0)–(1, 1)). */
        if (fz >= fx) return h[0][0] + (h[1][1] - h[1][0]) * fx + (h[1][0] - h[0][0]) * fz;
        return h[0][0] + (h[0][1] - h[0][0]) * fx + (h[1][1] - h[0][1]) * fz;
    }
    return NAN;
}

terrain_clipmap_stats_info terrain_clipmap_stats(const terrain_clipmap *c) { return c->stats; }

/* ---- GPU ---- */

/* Texel (i, k) of a level as the GPU keeps it: the height, the normal's x and z from central
 * differences over the level's own grid (its y, always positive on a height field, the shader
 * makes from them), and the lake level, so the vertex shader reads one texel where it read five
 * (on llvmpipe those reads were a third of the clipmap's draw). Neighbours wrap like the grid;
 * only the ring's own normals (which no vertex uses) see a stale neighbour. */
static void packed_texel(const clipmap_level *lv, int size, int i, int k, float out[4]) {
    const float *h = lv->heights;
    int left = (i + size - 1) % size, right = (i + 1) % size, back = (k + size - 1) % size, front = (k + 1) % size;
    float dx = h[(size_t)k * size + left] - h[(size_t)k * size + right];
    float dz = h[(size_t)back * size + i] - h[(size_t)front * size + i];
    float dy = 2.0f * (float)lv->spacing, length = sqrtf(dx * dx + dy * dy + dz * dz);
    out[0] = h[(size_t)k * size + i];
    out[1] = dx / length, out[2] = dz / length;
    out[3] = lv->lakes[(size_t)k * size + i];
}

/* Uploads the flagged rows (or columns) and their neighbours, whose normals the new heights
 * changed, and clears the flags. */
static void upload_runs(terrain_clipmap *c, int level, uint8_t *flags, bool rows) {
    const clipmap_level *lv = &c->levels[level];
    int size = c->size;
    if (size <= 0) return;
    uint8_t *wide = c->upload_flags;
    for (int a = 0; a < size; a++) wide[a] = flags[a] || flags[(a + 1) % size] || flags[(a + size - 1) % size];
    memset(flags, 0, (size_t)size);
    for (int a = 0; a < size;) {
        if (!wide[a]) { a++; continue; }
        int b = a;
        while (b < size && wide[b]) b++;
        int count = b - a;
        float (*texels)[4] = c->upload_texels;
        for (int n = 0; n < count; n++)
            for (int m = 0; m < size; m++)
                packed_texel(lv, size, rows ? m : a + n, rows ? a + n : m, texels[rows ? (size_t)n * size + m : (size_t)m * count + n]);
        if (rows) gfx_texture_update(c->texture, level, 0, a, size, count, texels);
        else gfx_texture_update(c->texture, level, a, 0, count, size, texels);
        a = b;
    }
}

static void create_gpu_objects(terrain_clipmap *c) {
    /* texelFetch only: the shader wraps the toroidal indices itself. */
    c->texture = gfx_texture_create(&(gfx_texture_desc){ .width = c->size, .height = c->size,
        .layers = c->level_count, .array = true, .format = GFX_FORMAT_RGBA32F, .nearest = true });
    c->upload_flags = core_calloc((size_t)c->size, 1);
    c->upload_texels = core_calloc((size_t)c->size * (size_t)c->size, sizeof *c->upload_texels);
    c->index_buffer = gfx_buffer_create(&(gfx_buffer_desc){
        .size = c->index_count * sizeof *c->indices, .data = c->indices });
    /* No vertex attributes: clipmap.vert makes (i, k) from gl_VertexID. */
    c->vertex_array = gfx_vertex_array_create(&(gfx_vertex_array_desc){ .indices = c->index_buffer });
    core_free(c->indices, c->index_count * sizeof *c->indices);
    c->indices = NULL;
    for (int l = 0; l < c->level_count; l++) memset(c->levels[l].dirty_columns, 1, (size_t)c->size);
}

void terrain_clipmap_upload(terrain_clipmap *c) {
    TRACE_ZONE("terrain_clipmap_upload");
    if (!c->texture.id) create_gpu_objects(c);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    for (int l = 0; l < c->level_count; l++) {
        if (!c->levels[l].valid) continue;
        upload_runs(c, l, c->levels[l].dirty_columns, false);
        upload_runs(c, l, c->levels[l].dirty_rows, true);
    }
    c->upload_pending = false;
}

static void uniform_ivec2(GLuint program, const char *name, const int *value) {
    GLint location = glGetUniformLocation(program, name);
    if (location >= 0) glUniform2i(location, value[0], value[1]);
}

/* What every level shares: the heights, the holes and the fade into the sky. */
static void draw_shared_uniforms(terrain_clipmap *c, gfx_context *gfx, gfx_program program, const terrain_view *view) {
    const double *camera = view->camera;
    gfx_uniform_int(gfx, program, "u_heights", 1);
    gfx_uniform_int(gfx, program, "u_size", c->size);
    gfx_uniform_int(gfx, program, "u_cells", c->cells);
    gfx_uniform_float(gfx, program, "u_camera_y", (float)camera[1]);
    gfx_uniform_float(gfx, program, "u_hole_band", c->desc.hole_band);
    gfx_uniform_float(gfx, program, "u_hole_depth", c->desc.hole_depth);
    gfx_uniform_int(gfx, program, "u_seam_exact", c->desc.world != NULL);
    /* 002 §4.4: the outermost level's last 15 % and the last 15 % before the far plane fade into
     * the sky, so neither the clipmap's square edge nor the far plane's cut is ever seen. */
    float reach = (float)c->stats.reach, far_distance = view->far_distance > 0 ? view->far_distance : 4000.0f;
    gfx_uniform_vec2(gfx, program, "u_edge_fade", (const float[2]){ (1.0f - EDGE_FADE) * reach, reach });
    gfx_uniform_vec2(gfx, program, "u_far_fade", (const float[2]){ (1.0f - EDGE_FADE) * far_distance, 0.98f * far_distance });
    gfx_uniform_float(gfx, program, "u_water_level", c->desc.generation.sea_level);
    gfx_uniform_float(gfx, program, "u_sand_max_slope", c->desc.generation.sand_max_slope);
    gfx_uniform_float(gfx, program, "u_sand_depth", c->desc.generation.sand_depth);
}

/* The heights for water_ground.glsl (the ground under a point, for water's depth): each level's
 * vertex (0, 0) camera-relative (in double here, small there), its spacing and its toroidal
 * start texel, and the texture on `unit`. 0 levels until the first upload. */
int terrain__clipmap_ground_levels(const terrain_clipmap *c) {
    return c->has_camera && c->texture.id && !c->upload_pending ? c->level_count : 0;
}

int terrain__clipmap_bind_ground(terrain_clipmap *c, gfx_context *gfx, uint32_t program_handle, const double camera[3],
                                 int unit) {
    gfx_program program = { program_handle };
    GLuint gl_program = gfx_program_gl(gfx, program);
    int levels = terrain__clipmap_ground_levels(c);
    gfx_uniform_int(gfx, program, "u_ground_levels", levels);
    gfx_uniform_int(gfx, program, "u_ground_heights", unit);
    if (levels == 0) return 0;
    gfx_uniform_int(gfx, program, "u_ground_size", c->size);
    gfx_uniform_int(gfx, program, "u_ground_cells", c->cells);
    float origin[TERRAIN_CLIPMAP_MAX_LEVELS][2], spacing[TERRAIN_CLIPMAP_MAX_LEVELS];
    int start[TERRAIN_CLIPMAP_MAX_LEVELS][2];
    for (int l = 0; l < levels; l++) {
        const clipmap_level *lv = &c->levels[l];
        spacing[l] = (float)lv->spacing;
        for (int a = 0; a < 2; a++) {
            origin[l][a] = (float)((double)lv->first[a] * lv->spacing - camera[a ? 2 : 0]);
            start[l][a] = floor_mod(lv->first[a], c->size);
        }
    }
    GLint at = glGetUniformLocation(gl_program, "u_ground_origin");
    if (at >= 0) glProgramUniform2fv(gl_program, at, levels, &origin[0][0]);
    at = glGetUniformLocation(gl_program, "u_ground_spacing");
    if (at >= 0) glProgramUniform1fv(gl_program, at, levels, spacing);
    at = glGetUniformLocation(gl_program, "u_ground_start");
    if (at >= 0) glProgramUniform2iv(gl_program, at, levels, &start[0][0]);
    gfx_texture_bind(c->texture, unit);
    return levels;
}

/* The holes that reach block `info` (its box holds one cell more around than its vertices), as
 * a bit per hole: a hole that does not meet the box neither sinks nor seams any of its vertices. */
static unsigned block_holes(const terrain_clipmap *c, const terrain__clipmap_block_info *info) {
    unsigned near = 0;
    for (int h = 0; h < c->hole_count; h++)
        if (info->box_max[0] >= c->hole_min[h][0] && info->box_min[0] <= c->hole_max[h][0] &&
            info->box_max[2] >= c->hole_min[h][1] && info->box_min[2] <= c->hole_max[h][1])
            near |= 1u << h;
    return near;
}

/* clipmap.vert loops over u_holes for every vertex, and on llvmpipe that loop (an array read at
 * a varying index, once per hole and lane) was half the far terrain's vertex cost: each block
 * gets only the holes that reach it, which for all but the few blocks around the chunks is none. */
static void bind_block_holes(const terrain_clipmap *c, GLuint program, const float holes[][4], unsigned near) {
    float chosen[TERRAIN_CLIPMAP_MAX_HOLES][4];
    int count = 0;
    for (int h = 0; h < c->hole_count; h++)
        if (near & (1u << h)) memcpy(chosen[count++], holes[h], sizeof chosen[0]);
    GLint at = glGetUniformLocation(program, "u_hole_count");
    if (at >= 0) glUniform1i(at, count);
    at = glGetUniformLocation(program, "u_holes");
    if (at >= 0 && count > 0) glUniform4fv(at, count, &chosen[0][0]);
}

/* A range of the index buffer not drawn yet: neighbouring blocks drawn in one call. */
typedef struct clipmap_run {
    uint32_t first, count;
} clipmap_run;

static void clipmap_run_draw(terrain_clipmap *c, clipmap_run *run) {
    if (run->count == 0) return;
    gfx_draw(&(gfx_draw_desc){ .vertex_array = c->vertex_array, .first = run->first, .count = run->count,
                               .index_type = GFX_INDEX_U32 });
    c->stats.draws++;
    run->count = 0;
}

void terrain__clipmap_draw(terrain_clipmap *c, gfx_context *gfx, uint32_t program_handle, const terrain_view *view) {
    TRACE_ZONE("terrain_clipmap_draw");
    c->stats.blocks_drawn = 0;
    c->stats.draws = 0;
    c->stats.triangles = 0;
    if (!c->has_camera) return;
    /* Levels placed by an update whose heights are not on the GPU yet would draw stale ones. */
    if (!c->texture.id || c->upload_pending) terrain_clipmap_upload(c);
    gfx_program program = { program_handle };
    GLuint gl_program = gfx_program_gl(gfx, program);
    draw_shared_uniforms(c, gfx, program, view);
    gfx_texture_bind(c->texture, 1);
    float holes[TERRAIN_CLIPMAP_MAX_HOLES][4];
    terrain__clipmap_holes(c, view->camera, holes);
    unsigned bound = ~0u;                      /* the holes bound for the draws so far: none yet */
    for (int l = 0; l < c->level_count; l++) {
        level_uniforms u = uniforms_for(c, l, view->camera);
        gfx_uniform_int(gfx, program, "u_layer", l);
        gfx_uniform_int(gfx, program, "u_coarse_layer", l + 1 < c->level_count ? l + 1 : -1);
        gfx_uniform_vec2(gfx, program, "u_anchor", u.anchor);
        gfx_uniform_float(gfx, program, "u_spacing", u.spacing);
        gfx_uniform_vec2(gfx, program, "u_morph", (const float[2]){ u.morph_start, u.morph_inverse_width });
        gfx_uniform_vec2(gfx, program, "u_morph_centre", u.morph_centre);
        uniform_ivec2(gl_program, "u_offset", u.offset);
        uniform_ivec2(gl_program, "u_start", u.start);
        uniform_ivec2(gl_program, "u_coarse_start", u.coarse_start);
        /* Visible blocks next to each other in the index buffer (along a row, and from a row's
         * end to the next row's start) with the same holes are one draw. */
        clipmap_run run = { 0 };
        for (int b = 0; b < BLOCKS; b++) {
            terrain__clipmap_block_info info = terrain__clipmap_block(c, l, b);
            if (!info.visible) {
                clipmap_run_draw(c, &run);
                continue;
            }
            unsigned near = block_holes(c, &info);
            if (near != bound || c->block_first[b] != run.first + run.count) clipmap_run_draw(c, &run);
            if (near != bound) bind_block_holes(c, gl_program, holes, bound = near);   /* after the run it ends */
            if (run.count == 0) run.first = c->block_first[b];
            run.count += c->block_count[b];
            c->stats.blocks_drawn++;
            c->stats.triangles += c->block_count[b] / 3;
        }
        clipmap_run_draw(c, &run);
    }
    trace_counter("terrain.clipmap_blocks_drawn", c->stats.blocks_drawn);
    trace_counter("terrain.clipmap_triangles", (double)c->stats.triangles);
}
