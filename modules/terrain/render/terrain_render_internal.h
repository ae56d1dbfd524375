/* terrain_render_internal.h — the private declarations of the terrain's drawing area
 * (modules/terrain/render/): the clipmap's levels and blocks, the sun's shadow map, the
 * renderer's scene for water's passes, the material textures. The public API is
 * render/terrain_render.h.
 *
 * Sections are owned by whoever wrote them; add new declarations in a section of your own.
 */
#ifndef TERRAIN_RENDER_INTERNAL_H
#define TERRAIN_RENDER_INTERNAL_H

#include "terrain/render/terrain_render.h"
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdint.h>

/* ==== far terrain: geometry clipmaps (terrain_clipmap.c) =================================== */

/* Level L's vertex (i, k), 0 ≤ i, k ≤ cells, is the world point ((first[0] + i)·s, (first[1] +
 * k)·s) with s = finest_spacing·2^L; first[] is even, so the level's border lies on level L + 1's
 * vertex lines. Each level is cut along the cell cuts 0, n/4, n/4 + 1, n/2, 3n/4, 3n/4 + 1, n,
 * and each of the four long segments again into TERRAIN__CLIPMAP_SPLIT equal parts (culling
 * then drops more of a level's triangles outside the view): the finer level always covers
 * exactly the cells [h, h + n/2) on each axis, h = n/4 or n/4 + 1, which are whole segments,
 * so a block is either all covered or not at all. */
#define TERRAIN__CLIPMAP_SPLIT 2
#define TERRAIN__CLIPMAP_SEGMENTS (2 + 4 * TERRAIN__CLIPMAP_SPLIT)
#define TERRAIN__CLIPMAP_BLOCKS (TERRAIN__CLIPMAP_SEGMENTS * TERRAIN__CLIPMAP_SEGMENTS)

typedef struct terrain__clipmap_level_info {
    int64_t first[2];                 /* grid index of vertex (0, 0), in units of `spacing` */
    double spacing;
    int cells;
    float octaves;                    /* of the multifractal (004 §4.1) */
    float morph_start, morph_width;   /* metres (see terrain__clipmap_morph) */
} terrain__clipmap_level_info;

terrain__clipmap_level_info terrain__clipmap_level(const terrain_clipmap *clipmap, int level);
/* The stored height of grid point (i, k) of a level (world (i·s, k·s)); NAN when the level's
 * window (its vertices and one more on every side) does not hold it. */
float terrain__clipmap_texel(const terrain_clipmap *clipmap, int level, int64_t i, int64_t k);

/* Geomorphing (Losasso & Hoppe's transition regions): a vertex at (dx, dz) from the camera of
 * the clipmap's last update (the one its levels were placed for, not the one drawing them, so
 * the guarantees below hold however far the view moved since) blends towards the coarser
 * level's surface by
 *     α = clamp((max(|dx|, |dz|) − start) / width, 0, 1),  and α = 1 on the level's border,
 *     h = (1 − α)·h_fine + α·h_coarse,
 * where h_coarse is the coarser level's triangle surface under the vertex: its vertex, the
 * midpoint of its edge, or the midpoint of its cell's diagonal (from (i, k) to (i + 1, k + 1),
 * the diagonal the triangles use), i.e. ½(H(c) + H(c + odd)) with c = the coarse vertex at or
 * before the fine one and odd = the fine index's parity. start = half the footprint − the most
 * the level's centre can be off the camera − width, so α reaches 1 before the border (the
 * border term makes that exact against rounding), and the coarser level's own transition
 * starts far outside the finer level, so the coarser vertices under the finer border are its
 * unmorphed heights, the very ones the finer level reads. shaders/clipmap.vert
 * computes the same expressions (`precise`), so the finer border's vertices lie exactly on the
 * coarser level's edges (T-junctions without gaps; zero-area triangles along every level's
 * border cover what rounding leaves). */
static inline float terrain__clipmap_morph(float dx, float dz, float start, float inverse_width, bool border) {
    float a = (fmaxf(fabsf(dx), fabsf(dz)) - start) * inverse_width;
    a = a < 0.0f ? 0.0f : a > 1.0f ? 1.0f : a;
    return border ? 1.0f : a;
}

/* What clipmap.vert computes for vertex (i, k) of a level with the camera at `camera`: its
 * camera-relative x and z (floats, from one anchor shared by every level, so vertices that two
 * levels share come out bit-identical) and its drawn height (morphed; hole sinking excluded). */
void terrain__clipmap_vertex(const terrain_clipmap *clipmap, int level, int i, int k, const double camera[3],
                             float position[2], float *height);

/* The holes as clipmap.vert receives them (u_holes, u_hole_count) for the camera: min x, min z,
 * max x, max z, camera-relative; returns how many (the empty ones are never kept). */
int terrain__clipmap_holes(const terrain_clipmap *clipmap, const double camera[3], float holes[][4]);

/* What clipmap.vert sinks a camera-relative position (terrain__clipmap_vertex's) by: the
 * deepest of the holes' pits there, 0 outside every hole (the drawn height is height − sink). */
float terrain__clipmap_sink(const terrain_clipmap *clipmap, const double camera[3], const float position[2]);

typedef struct terrain__clipmap_block_info {
    int cells_min[2], cells_max[2];   /* cells [min, max) of the level's grid along x and z */
    double box_min[3], box_max[3];    /* world bounds the cull tests (heights conservative) */
    bool covered;                     /* by the finer level, or its level lies wholly in a hole (a pit
                                         the coarser level draws): never drawn */
    bool visible;                     /* drawn (not covered and, if culled, in the frustum) */
} terrain__clipmap_block_info;

terrain__clipmap_block_info terrain__clipmap_block(const terrain_clipmap *clipmap, int level, int block);

/* Draws the visible blocks with `program` (shaders/clipmap.*), which terrain_renderer_draw has
 * made current with the shared uniforms set; sets the draw counters and stats. Main thread. */
void terrain__clipmap_draw(terrain_clipmap *clipmap, gfx_context *gfx, uint32_t program, const terrain_view *view);
/* Sets water_ground.glsl's uniforms on `program` (in use) and binds the heights to texture
 * `unit`: the levels bound, 0 (u_ground_levels = 0) before the first upload. Main thread. */
int terrain__clipmap_bind_ground(terrain_clipmap *clipmap, gfx_context *gfx, uint32_t program, const double camera[3],
                                 int unit);
/* The levels terrain__clipmap_bind_ground would bind now (0 before the first upload). */
int terrain__clipmap_ground_levels(const terrain_clipmap *clipmap);

/* ==== end of the clipmap section ========================================================== */

/* ==== meshes by parts (terrain_render.c) ================================================== */

/* Whether a box (origin + lo … hi, world metres) is to be drawn. */
typedef bool (*terrain__box_test)(const void *user, const double origin[3], const float lo[3], const float hi[3]);
/* Draws the parts of `mesh` whose boxes pass `test` (program and uniforms already set), runs of
 * consecutive parts in one draw call: they tile the indices in order. A mesh without parts is
 * drawn whole. Returns the triangles drawn. */
uint64_t terrain__draw_parts(const terrain_gpu_mesh *mesh, terrain__box_test test, const void *user);

/* ==== sun shadows (terrain_shadow.c) ====================================================== */

typedef struct terrain__shadows terrain__shadows;

/* NULL with quality off, or when the shaders or the depth target cannot be made (logged). */
terrain__shadows *terrain__shadows_create(gfx_context *gfx, terrain_shadow_quality quality);
void terrain__shadows_destroy(terrain__shadows *shadows);
/* Fits the cascades to `view` and renders `casters` into them: one pass named "shadows". */
void terrain__shadows_render(terrain__shadows *shadows, const terrain_view *view, const float sun[3],
                             const terrain_gpu_mesh *casters, int caster_count);
/* Sets shadow.glsl's uniforms on `program` (in use) and binds the map to texture `unit`;
 * shadows NULL sets u_shadow_cascades = 0 (the sampler still gets a unit of its own: GL refuses
 * a draw whose samplers of two types share one). */
void terrain__shadows_bind(const terrain__shadows *shadows, gfx_context *gfx, uint32_t program, int unit);
/* Cascades drawn since creation (0 for NULL): a cascade is drawn again only when its box moved
 * with something casting into it, or what casts into it changed. */
uint64_t terrain__shadows_cascades_drawn(const terrain__shadows *shadows);
/* The renderer's shadows (NULL with shadows off). */
terrain__shadows *terrain__renderer_shadows(const terrain_renderer *renderer);

/* ==== end of the shadows section ========================================================== */

/* ==== the renderer's scene for water's passes (terrain_render.c, terrain_water.c) ========== */

/* Draws the meshes, the far terrain and the sky as terrain_renderer_draw does, but into the
 * framebuffer and pass the caller opened, without shadows, and keeping only what lies where
 * dot((p − camera, 1), clip_plane) ≥ 0 (camera-relative; all zero keeps everything; the sky is
 * never clipped): water's reflection and refraction passes. Main thread. */
void terrain__renderer_draw_clipped(terrain_renderer *renderer, const terrain_view *view,
                                    const terrain_gpu_mesh *meshes, int mesh_count, const float clip_plane[4]);
/* Whether terrain_water draws the sea over the frame: the far terrain then leaves out its own
 * tint of the ground under the sea (clipmap.frag), which would show through the shore's fade.
 * Takes effect from the next frame drawn; terrain_water_draw sets it every call (off clears
 * it), and it outlives the water object. */
void terrain__renderer_set_water_drawn(terrain_renderer *renderer, bool drawn);
float terrain__renderer_fog_density(const terrain_renderer *renderer);
float terrain__renderer_cloud_cover(const terrain_renderer *renderer);   /* 0 = a clear sky */
/* The far terrain's heights for water_ground.glsl (terrain__clipmap_bind_ground); without far
 * terrain u_ground_levels = 0. Returns the levels bound. */
int terrain__renderer_bind_ground(terrain_renderer *renderer, uint32_t program, const double camera[3], int unit);
/* Whether the renderer has far terrain whose heights terrain__renderer_bind_ground can bind. */
bool terrain__renderer_has_ground(const terrain_renderer *renderer);

/* ==== end of the water section ============================================================ */

/* ---- material textures (terrain_textures.c) ---- */

/* Base layers: TERRAIN__BASE_SIZE² RGBA8 per material, one repeat per TERRAIN__BASE_METRES:
 * R the shade (albedo = tint · R), GB the tangent-space normal's x, y (0.5 + 0.5·n).
 * Detail layers: TERRAIN__DETAIL_SIZE² RGBA8 per material, one repeat per
 * TERRAIN__DETAIL_METRES: R an albedo multiplier as 2·R with a mean of 1, GB the normal as above;
 * then one macro layer of the same size, one repeat per TERRAIN__MACRO_METRES: R brightness and
 * G hue (2·texel, mean 1), B the share of the coarser base sample (TERRAIN__BASE2_METRES). */
#define TERRAIN__MATERIAL_LAYERS 4          /* bedrock, sand, rocks, water bed */
#define TERRAIN__DETAIL_LAYERS (TERRAIN__MATERIAL_LAYERS + 1)
#define TERRAIN__BASE_SIZE 256
#define TERRAIN__DETAIL_SIZE 256
#define TERRAIN__BASE_METRES 8.0f
#define TERRAIN__BASE2_METRES 25.0f         /* the base again, coarser, against repeats */
#define TERRAIN__DETAIL_METRES 1.0f
#define TERRAIN__MACRO_METRES 200.0f        /* a multiple of every period above: texture
                                               coordinates wrap the origin modulo this */

typedef struct terrain__material_texels {
    uint8_t *base, *detail;                 /* layouts above; core_alloc'd */
    size_t base_bytes, detail_bytes;
    float tints[TERRAIN__MATERIAL_LAYERS][3];
    float means[TERRAIN__MATERIAL_LAYERS][3];  /* tint · mean shade: the far colour */
} terrain__material_texels;

/* Fills `out`; free with terrain__material_texels_free. Deterministic. */
void terrain__material_texels_make(terrain__material_texels *out);
void terrain__material_texels_free(terrain__material_texels *texels);

#endif
