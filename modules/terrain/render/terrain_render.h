/* terrain_render.h — drawing the terrain (modules/terrain/render/; main thread, with a gfx
 * context): meshes on the GPU, the renderer (triplanar materials, sky, fog, the sun's cascaded
 * shadows), views and their frusta, and the far terrain's geometry clipmaps. Built on
 * data/terrain_data.h; terrain/terrain.h includes it.
 *
 *     terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){
 *         .shadows = TERRAIN_SHADOWS_LOW });
 *     terrain_gpu_mesh gpu = terrain_gpu_mesh_upload(&mesh);       // a terrain_mesh
 *     each frame:
 *         terrain_view view = { .camera = { x, y, z }, .yaw = yaw, .aspect = 16.0f / 9.0f };
 *         terrain_renderer_draw(renderer, &view, &gpu, 1);          // the meshes, then the sky
 *     terrain_gpu_mesh_destroy(&gpu);
 *     terrain_renderer_destroy(renderer);
 *
 * A running world draws with terrain_ecs_draw (ecs/terrain_ecs.h): it uploads, culls and casts
 * shadows for its chunks, and draws the clipmap given to terrain_renderer_set_clipmap.
 */
#ifndef TERRAIN_RENDER_H
#define TERRAIN_RENDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "terrain/data/terrain_data.h"

/* ---- rendering (main thread; needs a gfx context) ---------------------------------------- */

/* Triplanar texturing with blend exponent 8 (000 §6), materials mixed by the vertices' weights,
 * bedrock tinted by height band and slope (002 §4.1), sun, sky ambient and fog, and shadows of
 * the sun from a cascaded shadow map (desc.shadows: off, low by default, high). Material
 * textures are generated procedurally when the renderer is made. Meshes are drawn
 * camera-relative (origins subtracted in double precision), so a view 100 km from the world's
 * origin renders exactly as one near it. */
typedef struct gfx_context gfx_context;
typedef struct terrain_renderer terrain_renderer;

/* Sun shadows: a cascaded shadow map over the near terrain (terrain_shadow.c; the README's
 * "Sun shadows" says what each costs). The meshes cast; the meshes and the far terrain receive. */
typedef enum terrain_shadow_quality {
    TERRAIN_SHADOWS_DEFAULT = 0,      /* low */
    TERRAIN_SHADOWS_OFF,              /* no shadow pass, nothing sampled */
    TERRAIN_SHADOWS_LOW,              /* 2 cascades of 1024² out to 50 m, one bilinear tap */
    TERRAIN_SHADOWS_HIGH,             /* 3 cascades of 2048² out to 300 m, 3 × 3 bilinear taps */
} terrain_shadow_quality;

/* Parses "off", "low" or "high" (--shadows); false for anything else. */
bool terrain_parse_shadow_quality(const char *text, terrain_shadow_quality *out);
const char *terrain_shadow_quality_name(terrain_shadow_quality quality);

typedef struct terrain_renderer_desc {
    float sea_level;                  /* for the shore band; 0 = 0 m */
    float snow_height;                /* 0 = 120 m */
    float fog_density;                /* per metre; 0 = 0.0025 */
    float cloud_cover;                /* 0 = 0.45; negative = a clear sky */
    bool no_occlusion;                /* ignore the vertices' openness (ambient occlusion off) */
    float detail_distance;            /* metres to which the 1 m detail layer (grains, cracks,
                                         pebbles) reaches, fading out over the second half;
                                         0 = 16 m; negative = the low quality: no detail layer
                                         and no 25 m scale blend (their fetches skipped; normal
                                         maps and the macro variation stay) */
    terrain_shadow_quality shadows;   /* 0 = low */
    bool sky_apart;                   /* terrain_renderer_draw leaves the sky out: the caller
                                         draws it with terrain_renderer_draw_sky (a system of its
                                         own); reflections keep theirs */
} terrain_renderer_desc;

/* NULL when the shaders do not build (their errors printed at file:line). */
terrain_renderer *terrain_renderer_create(gfx_context *gfx, const terrain_renderer_desc *desc);
void terrain_renderer_destroy(terrain_renderer *renderer);
/* Milliseconds terrain_renderer_create spent making the material textures (CPU and upload). */
double terrain_renderer_texture_ms(const terrain_renderer *renderer);

/* A mesh on the GPU. */
typedef struct terrain_gpu_mesh {
    gfx_buffer vertex_buffer, index_buffer;
    gfx_vertex_array vertex_array;    /* { 0 } for an empty mesh (nothing to draw) */
    uint32_t index_count;
    uint64_t serial;                  /* unique per upload: what was derived from a mesh (grass)
                                         knows when it changed */
    double origin[3];
    float bounds_min[3], bounds_max[3];
    terrain_mesh_part parts[TERRAIN_MESH_PARTS];   /* the mesh's: the draw leaves out those out
                                                      of view */
    uint32_t part_count;              /* 0 = one part, the whole mesh */
} terrain_gpu_mesh;

terrain_gpu_mesh terrain_gpu_mesh_upload(const terrain_mesh *mesh);
void terrain_gpu_mesh_destroy(terrain_gpu_mesh *mesh);

typedef struct terrain_view {
    double camera[3];                 /* world position of the eye */
    float yaw, pitch;                 /* radians; yaw 0 looks along −z, positive turns right */
    float fov_y;                      /* radians; 0 = 60° */
    float aspect;                     /* width / height */
    float far_distance;               /* 0 = 4000 m */
    float sun_direction[3];           /* towards the sun; 0 = a morning sun */
    float time;                       /* seconds; the clouds drift with it */
} terrain_view;

/* The view's projection × camera rotation (column-major, the camera at the origin: draw
 * camera-relative positions with it), and its unit sun direction (the default when unset): for
 * modules that draw into the terrain's frame (grass, water). */
void terrain_view_matrix(const terrain_view *view, float out[16]);
void terrain_view_sun(const terrain_view *view, float out[3]);

/* The view's frustum as six planes in camera-relative space, for culling mesh bounds. */
typedef struct terrain_frustum {
    float planes[6][4];               /* a·x + b·y + c·z + d ≥ 0 inside */
    double camera[3];
} terrain_frustum;

terrain_frustum terrain_frustum_from_view(const terrain_view *view);
/* Whether any part of the box origin + [bounds_min, bounds_max] may be inside (conservative:
 * boxes near a corner of the frustum may pass; a box that is seen never fails). */
bool terrain_frustum_sees(const terrain_frustum *frustum, const double origin[3], const float bounds_min[3],
                          const float bounds_max[3]);

/* Changes the shadows' quality (the map is made or freed now); false, shadows unchanged, when
 * the shadow map cannot be made (logged). */
bool terrain_renderer_set_shadows(terrain_renderer *renderer, terrain_shadow_quality quality);

/* Draws the meshes, then the sky behind them, inside one pass named "terrain". With shadows on,
 * a pass named "shadows" comes first: the sun's shadow map, cast by the meshes given to
 * terrain_renderer_draw_shadows since the last draw or else by these. Of each mesh only the parts
 * whose boxes the view's frustum may see are drawn (terrain_mesh_part); the trace counter
 * terrain.triangles_drawn says how many triangles that was. */
void terrain_renderer_draw(terrain_renderer *renderer, const terrain_view *view,
                           const terrain_gpu_mesh *meshes, int mesh_count);
/* The sky alone, in a pass named "sky", behind what the bound framebuffer holds (its depth at
 * the far plane): after terrain_renderer_draw with desc.sky_apart. */
void terrain_renderer_draw_sky(terrain_renderer *renderer, const terrain_view *view);
/* The shadow pass for the next terrain_renderer_draw, cast by `casters`: every mesh on the GPU
 * near the view, not only those in it (a hill behind the camera shades the ground in front). Each
 * cascade draws those whose bounds reach its footprint. Nothing happens with shadows off. */
void terrain_renderer_draw_shadows(terrain_renderer *renderer, const terrain_view *view,
                                   const terrain_gpu_mesh *casters, int caster_count);

/* ---- far terrain: geometry clipmaps (002 §3.2, §3.5) ---- */

/* The terrain beyond the volumetric chunks, out to many kilometres: nested square grids of
 * cells×cells cells around the camera, level L's vertices finest_spacing·2^L apart, displaced by
 * heights kept in a toroidal array per level (GPU: one R32F texture layer per level) and
 * recomputed only where a level moved (Losasso & Hoppe's geometry clipmaps, 002 §3.2). The
 * heights are the generator's macro ground G (the stacks' top surface before the overhang shear
 * and the caves) with the octave count the level's spacing can carry (004 §4.1), so distant
 * levels do not alias — and, given the world (desc.world), the surface the chunks' meshes draw
 * wherever chunks are cached (002 §3.5), recomputed as chunks come, change and go: edits show
 * from afar. Each level's vertices morph towards the next coarser level's surface near its
 * border and meet it exactly there: no cracks between levels. Where the volumetric chunks are
 * drawn (terrain_clipmap_set_holes: one square per viewer's rings) the clipmap sinks into a pit
 * under them, deeper than any cave, whose walls skirt the chunks' open border: a gap shows
 * ground, never sky, from any side. With the world's heights the vertices on a hole's border
 * keep the chunks' height, so the clipmap meets the meshes there (002 §3.5 bends the meso mesh
 * to the clipmap instead; we bend the clipmap to the mesh). The outermost level and the
 * far plane fade into the sky (002 §4.4), so the world has no visible end.
 *
 *     terrain_clipmap *far = terrain_clipmap_create(&(terrain_clipmap_desc){
 *         .generation = terrain_generation_defaults(42), .jobs = jobs,
 *         .world = world, .mesh_step = 4, .centre_snap = 128 });   // rings of 3 levels
 *     terrain_renderer_set_clipmap(renderer, far);
 *     each frame:
 *         terrain_clipmap_update(far, camera);                 // CPU: recentre, new heights
 *         terrain_clipmap_set_holes(far, volume_min, volume_max, n);  // where chunks are (x, z)
 *         terrain_frustum frustum = terrain_frustum_from_view(&view);
 *         terrain_clipmap_cull(far, &frustum);                 // CPU: visible blocks
 *         terrain_clipmap_upload(far);                         // main thread: changed texels
 *         terrain_renderer_draw(renderer, &view, meshes, count);  // meshes, clipmap, sky
 *     terrain_clipmap_destroy(far);                            // main thread (GL objects)
 *
 * With the defaults (6 levels of 128² cells from 4 m) the finest level covers 512 m around the
 * camera and the outermost 16 km (8 km each way); the far plane (terrain_view.far_distance,
 * 4 km by default) ends the view first. Threads: update, set_holes and cull are CPU work for any
 * one thread at a time, not while the clipmap is uploaded or drawn (update may fan out on
 * desc.jobs); upload, the draw and destroy use OpenGL: main thread. */
#define TERRAIN_CLIPMAP_MAX_LEVELS 12
#define TERRAIN_CLIPMAP_MAX_HOLES 8       /* one per viewer: TERRAIN_MAX_VIEWERS */

typedef struct job_system job_system;
typedef struct terrain_clipmap terrain_clipmap;

typedef struct terrain_clipmap_desc {
    int levels;                       /* nested levels; 0 = 6, at most TERRAIN_CLIPMAP_MAX_LEVELS */
    int cells;                        /* cells along each side of a level, a multiple of 16 (16 …
                                         1024); 0 = 128 */
    float finest_spacing;             /* metres between level 0's vertices; 0 = 4 */
    float hole_band;                  /* metres inside the hole's border over which the clipmap
                                         sinks (the pit's wall); 0 = 2·finest_spacing */
    float hole_depth;                 /* how deep it sinks (the pit's floor below the ground);
                                         0 = below the generator's caves (156 m by default) */
    terrain_generation_desc generation;  /* copied; the world whose ground is drawn */
    job_system *jobs;                 /* computes new heights in parallel; NULL = the caller */
    /* The stacks where they exist (002 §3.5). With a world, a grid point whose four columns lie
     * in chunks the world has cached, or has edits of in its log, takes the
     * height the chunks' meshes draw there instead of G, and the texels of chunks that are
     * generated, committed or evicted are recomputed at the next update: edits show from afar
     * and the clipmap meets the chunks along the holes' border. Not owned: it must outlive the
     * clipmap; one clipmap per world; update where no trim runs meanwhile (as for the pointers
     * terrain_world_stacks returns). An unedited chunk is never generated for this, and falls
     * back to G once evicted; an edited one evicted is made again from the log (generated and
     * replayed, on the update's jobs), so edits show from afar however old. */
    terrain_world *world;             /* NULL = G everywhere */
    float mesh_step;                  /* metres between the vertical samples of the meshes along
                                         the holes' border: the streamed rings' outermost level,
                                         2^(levels − 1) (terrain_rings_clearance's level); the
                                         heights are those such a mesh draws; 0 = 1 */
    float centre_snap;                /* metres: level 0 is centred on the camera snapped to
                                         this grid (rounded to an even number of finest
                                         spacings; at most finest_spacing·(cells/2 − 2 −
                                         2·⌊cells/10⌋): 152 m for the defaults).
                                         The streamed rings' own snap (their coarsest chunk,
                                         32·2^(levels − 1)) puts level 0 on their hole, so the
                                         finest level draws the hole's border; 0 = 2·finest */
    /* Detail from a screen-space error (data/terrain_data.h): with pixel_error > 0 the fields
     * left 0 among cells, finest_spacing and levels are derived from K = terrain_screen_error_scale(
     * viewport_height, fov_y, pixel_error): cells ≥ 4·(ε(s)/s·K + 2) (level L is drawn from
     * cells·s_L/4 out, less the camera's 2·s_L offset, and needs ε(s_L)·K), finest_spacing the
     * largest power of two (1 … 32 m) with ε(s)·K ≤ inner_distance, levels the fewest whose
     * outermost reaches 8192 m from its centre (as far as the defaults). */
    float pixel_error;                /* pixels; 0 = the fixed defaults */
    int viewport_height;              /* pixels; 0 = 720 */
    float fov_y;                      /* radians; 0 = 60° */
    float inner_distance;             /* metres from the camera that the volumetric rings cover
                                         surely (terrain_rings_clearance of their outermost level);
                                         0 = none, the finest spacing is then 1 m */
} terrain_clipmap_desc;

typedef struct terrain_clipmap_stats_info {
    int levels, cells;
    float finest_spacing;
    double reach;                     /* metres the outermost level reaches at least from the
                                         camera of the last update, along x and z */
    uint64_t texels_updated;          /* heights computed by the last terrain_clipmap_update */
    int blocks_visible;               /* blocks the last terrain_clipmap_cull kept */
    uint64_t triangles_visible;       /* in those blocks */
    int blocks_drawn;                 /* by the last draw */
    int draws;                        /* draw calls it took (neighbouring blocks are one) */
    uint64_t triangles;               /* drawn by the last draw */
} terrain_clipmap_stats_info;

/* CPU only (no GL): the heights are computed on the first update. NULL never (bad fields are
 * clamped to their range, with a warning). */
terrain_clipmap *terrain_clipmap_create(const terrain_clipmap_desc *desc);
/* Frees the CPU data and, if terrain_clipmap_upload made any, the GL objects: main thread. */
void terrain_clipmap_destroy(terrain_clipmap *clipmap);
/* A new viewport height, field of view and inner distance for a desc with pixel_error (a resized
 * window, rings derived again): when the derived cells, finest spacing or levels change, the
 * levels are made anew (heights recomputed on the next update, GL objects remade on the next
 * upload: main thread, not while the clipmap is drawn); holes are kept. True when they changed. */
bool terrain_clipmap_set_screen(terrain_clipmap *clipmap, int viewport_height, float fov_y, float inner_distance);
/* Recentres the levels on the camera (world metres) and computes the heights that came into
 * them (all of them the first time or after a jump); returns how many. */
uint64_t terrain_clipmap_update(terrain_clipmap *clipmap, const double camera[3]);
/* The rectangles of the world (x, z in metres; hole h spans min_xz[h] … max_xz[h]) where the
 * volumetric chunks are drawn instead, typically one square per viewer's rings: inside a hole
 * the clipmap sinks, over desc.hole_band from its border, to desc.hole_depth below the ground
 * (hidden under the chunks). Where holes overlap, a point sinks by the deepest of their pits
 * there, so no wall rises inside the union where the overlap is at least 2·hole_band wide
 * (holes that only touch leave a ridge along the shared edge, rising to the ground). Put the
 * borders on level 0's vertex lines (multiples of finest_spacing: chunk borders are), else the
 * sinking starts up to a cell outside them. Replaces the previous holes; count is 0 …
 * TERRAIN_CLIPMAP_MAX_HOLES (more are clamped, with a warning); holes with min ≥ max on either
 * axis are left out. */
void terrain_clipmap_set_holes(terrain_clipmap *clipmap, const double (*min_xz)[2], const double (*max_xz)[2], int count);
/* One hole (terrain_clipmap_set_holes with count 1); min ≥ max on either axis (or NULL) = none. */
void terrain_clipmap_set_hole(terrain_clipmap *clipmap, const double min_xz[2], const double max_xz[2]);
/* Marks the blocks (each level is cut into 36) whose bounds the frustum may see, skipping those
 * a finer level covers; returns how many will be drawn. Without a cull since the last update
 * every uncovered block is drawn. */
int terrain_clipmap_cull(terrain_clipmap *clipmap, const terrain_frustum *frustum);
/* Main thread, with a GL context: makes the GL objects on the first call, then uploads the
 * heights that changed since the last call. The draw does it too when an update left heights
 * behind, so calling it is only a way to choose when the upload's time is spent. */
void terrain_clipmap_upload(terrain_clipmap *clipmap);
/* The ground height drawn at (x, z) by the finest level around it (its triangles, morphed as
 * for the camera of the last update, vertices on a hole's border kept as the draw keeps them;
 * the hole's sinking not included); NAN outside every level or before the first update. */
float terrain_clipmap_height(const terrain_clipmap *clipmap, double x, double z);
terrain_clipmap_stats_info terrain_clipmap_stats(const terrain_clipmap *clipmap);

/* terrain_renderer_draw draws the clipmap after the meshes and before the sky (NULL = none);
 * the clipmap is not owned and must outlive its use here. */
void terrain_renderer_set_clipmap(terrain_renderer *renderer, terrain_clipmap *clipmap);
/* Turns the vertices' ambient occlusion on or off from the next draw (as the desc's
 * no_occlusion; for comparisons and benchmarks). */
void terrain_renderer_set_occlusion(terrain_renderer *renderer, bool on);

#endif
