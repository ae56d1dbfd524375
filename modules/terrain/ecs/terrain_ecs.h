/* terrain_ecs.h — the terrain in a running world (modules/terrain/ecs/): column chunks and mesh
 * chunks as entities, generated, meshed, culled and uploaded by systems (on the job system);
 * streaming that follows viewers, with the far clipmap; edits queued and stabilized a budget a
 * frame; water drawn over the frame. Built on data/, edit/ and render/; terrain/terrain.h
 * includes it.
 *
 *     terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
 *     terrain_ecs_stream(te, &(terrain_stream_desc){ .levels = 3 });
 *     each frame:
 *         terrain_ecs_set_viewers(te, &eye, 1);
 *         terrain_ecs_set_view(te, &view);
 *         ecs_progress(ecs, dt);
 *         terrain_ecs_draw(te, renderer, &view);
 *     terrain_ecs_destroy(te);                     // main thread, with the gfx context
 *
 * Drawing water (terrain_water, at the end) lives here, not in render/: it draws the lakes of the
 * WaterPlane components and the mesh chunks of a terrain_ecs, so it reads the ECS.
 */
#ifndef TERRAIN_ECS_H
#define TERRAIN_ECS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "terrain/data/terrain_data.h"
#include "terrain/edit/terrain_edit.h"
#include "terrain/render/terrain_render.h"

/* ---- in the ECS --------------------------------------------------------------------------- */

/* Column chunks and mesh chunks are entities. Systems (registered by terrain_ecs_create):
 *   generate  "terrain_generate"  TerrainChunk without stacks → stacks (parallel)
 *   mesh      "terrain_mesh"      TerrainMeshChunk waiting → field + marching cubes (parallel)
 *   cull      "terrain_cull"      meshed TerrainMeshChunk → visible in the view? (parallel)
 *   draw      "terrain_upload"    meshed TerrainMeshChunk → GPU (main thread)
 * terrain_ecs_draw then draws every uploaded mesh chunk and trims the world's cache (call it
 * outside ecs_progress, on the main thread). */
typedef struct ecs_world ecs_world;
typedef uint32_t ecs_component;                /* as ecs.h's (C11 allows the same typedef twice) */

typedef struct TerrainChunk {
    terrain_chunk_coord coord;
    const terrain_stacks *stacks;        /* NULL until the generate phase has run; after an edit
                                            the stabilize phase points it at the new stacks */
} TerrainChunk;

typedef enum terrain_mesh_state {
    TERRAIN_MESH_WAITING,               /* to be meshed */
    TERRAIN_MESH_MESHED,                /* CPU mesh ready, not uploaded */
    TERRAIN_MESH_UPLOADED,              /* on the GPU (the CPU copy is freed) */
} terrain_mesh_state;

typedef struct TerrainMeshChunk {
    int64_t x, y, z;                    /* in chunks of its level */
    terrain_lod_desc lod;               /* level and finer neighbours (terrain_mesh_chunk) */
    terrain_mesh_state state;
    bool visible;                       /* in the view's frustum (cull phase) */
    bool hidden;                        /* streaming: out of range and replaced, not drawn */
    terrain_mesh mesh;                  /* the newest mesh until uploaded */
    terrain_gpu_mesh gpu;               /* drawn; an older one stays until its successor is up */
    size_t gpu_bytes;
    bool edited;                        /* meshed again after an edit: uploaded this frame,
                                           whatever the upload budget */
    WaterPlane *water;                  /* the water surfaces found with the newest mesh (NULL =
                                           none; owned): the upload copies them into the
                                           entity's WaterPlane component */
} TerrainMeshChunk;

typedef struct terrain_ecs terrain_ecs;
typedef struct terrain_ecs_stats_info {
    int chunks, chunks_generated;
    int mesh_chunks, mesh_chunks_waiting, mesh_chunks_uploaded;
    uint64_t triangles;
} terrain_ecs_stats_info;

typedef struct terrain_ecs_desc {
    ecs_world *ecs;                   /* required: the world the components and systems go on */
    terrain_world *terrain;           /* required: the stacks they read and write (not owned) */
} terrain_ecs_desc;
/* Registers the components and systems on desc->ecs; NULL (message logged) without .ecs or
 * .terrain. */
terrain_ecs *terrain_ecs_create(const terrain_ecs_desc *desc);
/* Destroys the mesh-chunk entities; TerrainMeshChunk's on_remove hook frees their meshes (GPU
 * ones too: call on the main thread, with the context), as it does for any other removal. */
void terrain_ecs_destroy(terrain_ecs *te);
/* Spawns the column chunks within `radius` chunks of (cx, cz) and their mesh chunks for mesh
 * layers y_first … y_last (each TERRAIN_MESH_CELLS metres tall). */
void terrain_ecs_spawn_area(terrain_ecs *te, int64_t cx, int64_t cz, int radius, int64_t y_first, int64_t y_last);
/* Nested rings of detail around the origin: level 0 covers mesh chunks x, z ∈ [−w, w) (w =
 * half_width, even when levels > 1), and each coarser level L covers its own chunks in [−w, w)
 * but not the finer area inside, so level L reaches w·32·2^L metres out. Seams between levels
 * are closed (terrain_mesh_chunk). Every chunk is meshed whole, as streaming does by default
 * (terrain_simplify, below). All levels
 * cover [y_min, y_max] rounded out to the coarsest chunk height. Column-chunk entities are
 * spawned for the level-0 area. */
void terrain_ecs_spawn_rings(terrain_ecs *te, int half_width, int levels, double y_min, double y_max);

/* Which chunks streaming simplifies, each by its own level's error, terrain_chunk_level_error
 * (terrain_lod_desc.max_error): the surface moves by about what that level's sampling moves it
 * anyway (README, "Simplified chunks"). Fewer triangles to draw, more work to mesh. */
typedef enum terrain_simplify {
    TERRAIN_SIMPLIFY_NONE = 0,        /* none, marching cubes' triangles as they come (the
                                         default: the walk's frame times were best so, README) */
    TERRAIN_SIMPLIFY_ALL = 1,         /* every level (also what `.simplify = true` asks) */
    TERRAIN_SIMPLIFY_COARSE = 2,      /* levels 1 and up, level 0 whole: the coarse levels are
                                         most of what a view from a few tens of metres up draws,
                                         and a small share of the chunks streaming meshes */
} terrain_simplify;

/* The max_error streaming gives a chunk of `level` under `simplify` (0 = whole). */
float terrain_simplify_error(terrain_simplify simplify, int level);
/* "none", "coarse" or "all" into *out; false (out untouched) for anything else. */
bool terrain_parse_simplify(const char *text, terrain_simplify *out);

/* ---- streaming ----------------------------------------------------------------------------
 *
 * Instead of a fixed area, chunks follow viewers (the player, a second camera):
 *     terrain_ecs_stream(te, &(terrain_stream_desc){ .half_width = 2, .levels = 3,
 *                                                   .y_min = -200, .y_max = 240 });
 *     each frame:  terrain_ecs_set_viewers(te, &eye, 1);  ecs_progress(ecs, dt);  terrain_ecs_draw(...)
 *
 * Around each viewer the mesh chunks form nested rings as terrain_ecs_spawn_rings's, centred on
 * the viewer snapped to the coarsest level's chunk grid; the union over viewers is kept, each
 * place at the finest level any viewer wants there (levels of touching chunks then differ by at
 * most one, as the seams need). Systems, all on the main thread and cheap:
 *   stream    "terrain_stream"    re-centres the rings when a viewer crosses a chunk line:
 *                                 creates the chunks that came into range, cancels work for
 *                                 those that left, keeps their meshes while memory allows
 *   generate  "terrain_stream_generate"  column chunks around each viewer (collision_radius)
 *                                 generated by background jobs, then retained
 *   mesh      "terrain_stream_mesh"      mesh jobs in flight kept topped up, nearest and in-view
 *                                 first; finished ones collected
 *   draw      "terrain_upload"    at most upload_budget_ms of GPU uploads and frees a frame
 * Generation and meshing run as background jobs (jobs.h), so they span frames and a frame never
 * waits for them. A mesh chunk whose samples cannot reach any interface of its column chunks
 * (terrain_stacks_interface_range) is empty without being sampled. */
typedef struct terrain_stream_desc {
    int half_width;                   /* level-0 mesh chunks each way from the viewer; 0 = 2, or
                                         with pixel_error terrain_rings_half_width(levels, K) */
    int levels;                       /* rings of detail (level 0 included); 0 = 3 */
    float pixel_error;                /* screen-space error target τ in pixels ("detail from a
                                         screen-space error"); 0 = none: the fixed rings above.
                                         Only a half_width of 0 is derived; levels stay as given */
    int viewport_height;              /* pixels, for pixel_error; 0 = 720. The window's size
                                         changes: terrain_ecs_stream_set_screen */
    float fov_y;                      /* radians, for pixel_error; 0 = 60° */
    double y_min, y_max;              /* metres the mesh layers cover. Equal (the default):
                                         the generation parameters' base ± relief ± 48 m at
                                         first, then grown (never shrunk) to reach every
                                         interface of the column chunks generated or edited,
                                         so no peak or tower is cut off. Given: exactly that */
    int collision_radius;             /* column chunks each way kept generated; 0 = 2 */
    float upload_budget_ms;           /* main-thread GPU uploads and frees a frame; 0 = 2 ms */
    size_t memory_budget;             /* bytes of stacks and meshes kept (CPU + GPU); 0 = 384 MB */
    int max_jobs;                     /* background jobs in flight; 0 = as the work left needs:
                                         every worker busy while the world loads, then what
                                         finishes the backlog before the rings move again at
                                         the viewer's speed, at least 8 (README) */
    terrain_simplify simplify;        /* which levels' chunks are simplified by their level's
                                         own error; 0 = TERRAIN_SIMPLIFY_NONE (above) */
} terrain_stream_desc;

#define TERRAIN_MAX_VIEWERS 8

/* Turns streaming on (call once, before the first frame; spawned areas stay as they are). */
void terrain_ecs_stream(terrain_ecs *te, const terrain_stream_desc *desc);
/* A new viewport height and field of view (a resized window) for a desc with pixel_error: the
 * half width is derived again and, if it changed, the rings are laid out anew on the next frame
 * (what left them stays drawn until replaced, as when walking). No effect without pixel_error. */
void terrain_ecs_stream_set_screen(terrain_ecs *te, int viewport_height, float fov_y);
/* The desc streaming runs with: defaults filled in, half_width derived (terrain_ecs_stream). */
terrain_stream_desc terrain_ecs_stream_desc(terrain_ecs *te);
/* Where the viewers' eyes are (world metres; copied; at most TERRAIN_MAX_VIEWERS). */
void terrain_ecs_set_viewers(terrain_ecs *te, const double (*eyes)[3], int count);
/* Whether every column chunk the field reads inside [min, max] (plus the kernel) is generated:
 * the player's region_ready hook (game/player.h). Never generates anything. */
bool terrain_ecs_region_ready(terrain_ecs *te, const double min[3], const double max[3]);

/* The terrain's resource (ecs.h, RESOURCES): this terrain_ecs, whose state (streaming, editing,
 * the view) its systems declare through it. A system of yours that calls terrain_ecs functions
 * names it in its reads (stats, region checks) or writes (edits, viewers, the view). */
ecs_component terrain_ecs_resource(const terrain_ecs *te);

typedef struct terrain_ecs_stream_stats_info {
    int mesh_chunks_wanted;           /* in the viewers' rings */
    int mesh_chunks_ready;            /* of those, drawn or empty */
    int mesh_chunks_kept;             /* out of range, kept while memory allows */
    int jobs_in_flight;
    int jobs_limit;                   /* how many may be in flight now (terrain_stream_desc.max_jobs) */
    uint64_t chunks_meshed, chunks_skipped_empty, chunks_cancelled, chunks_evicted;
    size_t resident_bytes, peak_resident_bytes;   /* stacks cached + CPU and GPU meshes */
    size_t stacks_bytes;              /* of resident_bytes: the column chunks' stacks cached */
    size_t cpu_mesh_bytes;            /* meshes made and not uploaded yet */
    size_t gpu_mesh_bytes;            /* meshes uploaded (their vertex and index buffers) */
} terrain_ecs_stream_stats_info;
terrain_ecs_stream_stats_info terrain_ecs_stream_stats(const terrain_ecs *te);
/* Far terrain (after terrain_ecs_stream; the clipmap is not owned): the lod phase
 * ("terrain_clipmap") re-centres it on viewer 0 and sinks it under the squares every viewer's
 * rings cover (one hole each, duplicates dropped; terrain_clipmap_set_holes) once all their
 * chunks are in, keeping the previous squares until then; the cull phase
 * ("terrain_clipmap_cull") culls its blocks against the view. Give the renderer the same
 * clipmap (terrain_renderer_set_clipmap). */
typedef struct terrain_clipmap terrain_clipmap;
void terrain_ecs_set_clipmap(terrain_ecs *te, terrain_clipmap *clipmap);

/* The view the cull phase tests against (copied); NULL = no culling, every chunk is drawn. */
void terrain_ecs_set_view(terrain_ecs *te, const terrain_view *view);
/* Draws the uploaded chunks the cull phase found visible. */
void terrain_ecs_draw(terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view);
terrain_ecs_stats_info terrain_ecs_stats(const terrain_ecs *te);

/* ---- editing in the ECS ----
 *
 * A running world (terrain_ecs) edits through a queue:
 *     terrain_ecs_edit(te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
 *                                           .deposit = { .x = x, .z = z, .radius = 4, .volume = 20 } });
 * In the next frame's stabilize phase ("terrain_stabilize", main thread) queued edits are
 * applied (terrain_world_edit) and the chunks they changed are stabilized (000 §3.4) as jobs,
 * a budget's worth a frame, continuing over the next frames until nothing moves; material that
 * reaches a chunk's border wakes the chunk beyond, so a slide crosses any number of chunks.
 * Whatever changed is committed to the world (and its log) each frame. In the mesh phase every
 * mesh chunk that reads a changed chunk is meshed again — streamed ones at once, as the frame's
 * own jobs, and uploaded whatever the upload budget — so a stroke is drawn in the frame its
 * edit is applied. Changes committed to the world by other code are remeshed the same way. */
typedef struct terrain_editing_desc {
    terrain_stabilize_desc stabilize;   /* angles, step, tolerance; budget_ns per frame (0 with
                                             max_iterations 0 = 2 ms); the edge is always WAKE */
    int max_regions;                      /* chunks stabilized at once; 0 = 256 (beyond, the
                                             border holds like a wall, with a warning) */
} terrain_editing_desc;

typedef struct terrain_ecs_edit_stats_info {
    int queued;                           /* edits waiting for the next stabilize phase */
    int stabilizing_chunks;               /* chunks not yet stable */
    uint64_t edits_applied, edits_refused;
    uint64_t iterations;                  /* of stabilization, in all */
    uint64_t chunks_committed;            /* by stabilization */
    double last_frame_ms;                 /* the stabilize phase's cost, the last frame it had work */
} terrain_ecs_edit_stats_info;

/* Queues the edit (copied, sweep arrays too); false (message logged) for a tool that is not a
 * brush or a sweep without points. */
bool terrain_ecs_edit(terrain_ecs *te, const terrain_edit *edit);
void terrain_ecs_set_editing(terrain_ecs *te, const terrain_editing_desc *settings);
terrain_ecs_edit_stats_info terrain_ecs_edit_stats(const terrain_ecs *te);

/* ---- drawing water (terrain_water.c; 002 §3.4, 004 §4.3) ----------------------------------
 *
 * The sea (one plane at the generation's sea_level, out to the view's far distance, so it
 * reaches the horizon beyond the far terrain) and the lakes (the WaterPlane components whose
 * height is above the sea's), drawn over the opaque frame:
 *
 *     terrain_water *water = terrain_water_create(&(terrain_water_desc){
 *         .gfx = gfx, .ecs = ecs, .world = world, .quality = TERRAIN_WATER_LOW });
 *     each frame:
 *         terrain_ecs_draw(te, renderer, &view);       // ground, far terrain, sky
 *         grass_draw(grass, &view);                    // everything opaque first
 *         terrain_water_draw(water, te, renderer, &view);
 *     terrain_water_destroy(water);                    // main thread, before gfx_context_destroy
 *
 * Low (the default): nothing of the frame is read back, since on a software rasteriser
 * (llvmpipe) any read of the frame waits until all of it is drawn. Each surface is blended over
 * the frame: its opacity comes from the water's thickness along the view ray, the depth under
 * the surface taken from the far terrain's heights (terrain_renderer_set_clipmap), and the
 * reflection is the sky's, so the bottom shows through shallow water undistorted. Under water,
 * or with no far terrain to give the depth, it reads the frame as medium does.
 * Medium: the opaque frame's colour and depth are
 * copied to textures, and each surface samples them. Refraction is the copy at a position
 * distorted by a dudv map, masked by depth: where the scene at the distorted position lies in
 * front of the surface (something above the water), the undistorted position is used, so
 * nothing above the water leaks into it and the shore has no halo. Reflection is the sky along
 * the reflected ray (as sky.frag draws it) plus the sun's highlight on a scrolling normal map.
 * High: the sea's reflection comes from a pass of its own (the camera mirrored about the sea,
 * what lies under it clipped, half resolution; pass "water.reflection"), and its refraction
 * from another (what lies above it clipped, half resolution; "water.refraction"); lakes keep
 * the medium path. A Schlick Fresnel term blends the two; the thickness of water along the view
 * ray (from the scene's depth) darkens and greens deep water, keeps shallow water clear and
 * less reflective, and fades the surface out towards the shore (no hard line). Below the
 * surface (terrain_world_water_at at the camera) the surface is seen from underneath (total
 * internal reflection past the critical angle) and a water fog tints the frame. The surfaces
 * are drawn in a pass named "water". While no water shows (an occlusion query of the previous
 * frame: all of it behind hills or out of view), the surfaces are only probed, depth-tested
 * with no colour, and nothing is copied or shaded; water that comes into view appears a frame
 * later. Off: nothing drawn, no cost. A lake's plane covers the
 * cells of its row mask and one cell around them (the ground and the shore's fade draw the
 * waterline there, not the cells' square edges). Lakes beyond the volumetric rings are the far
 * terrain's own (its clipmap stands their surface at the lake's level and shades it with the
 * same optics, without maps), drawn whatever the quality, as its sea tint is. */
typedef enum terrain_water_quality {
    TERRAIN_WATER_DEFAULT = 0,        /* low */
    TERRAIN_WATER_OFF,                /* nothing drawn */
    TERRAIN_WATER_LOW,                /* blended over the frame, none of it read; the sky reflected */
    TERRAIN_WATER_MEDIUM,             /* the frame's copy refracted; the sky reflected */
    TERRAIN_WATER_HIGH,               /* the sea's reflection and refraction passes */
} terrain_water_quality;

/* Parses "off", "low", "medium" or "high" (--water); false for anything else. */
bool terrain_water_parse_quality(const char *text, terrain_water_quality *out);
const char *terrain_water_quality_name(terrain_water_quality quality);

/* Zero means the default for every field. */
typedef struct terrain_water_desc {
    gfx_context *gfx;                 /* required */
    terrain_world *world;             /* required: the sea level, and whether the camera is under
                                         water */
    ecs_world *ecs;                   /* the world terrain_ecs_create registered on; NULL = the
                                         sea alone, no lakes */
    terrain_water_quality quality;
    float fog_density;                /* as terrain_renderer_desc's; 0 = the renderer's */
    float cloud_cover;                /* as terrain_renderer_desc's; 0 = the renderer's */
} terrain_water_desc;

typedef struct terrain_water terrain_water;

/* NULL (the reason logged) when a required field is missing or the shaders do not build. */
terrain_water *terrain_water_create(const terrain_water_desc *desc);
void terrain_water_destroy(terrain_water *water);
/* Changes the quality (passes' targets made or freed now); false, unchanged, when they cannot be. */
bool terrain_water_set_quality(terrain_water *water, terrain_water_quality quality);
/* Draws the water over the frame drawn so far into the default framebuffer (after
 * terrain_ecs_draw and the grass), with the same view. `te` gives the lakes and the high
 * quality's meshes; NULL = the sea alone, its passes with the far terrain and sky only. */
void terrain_water_draw(terrain_water *water, terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view);

typedef struct terrain_water_stats_info {
    int planes_drawn;                 /* surfaces the last draw drew (the sea counts one) */
    bool under_water;                 /* the last draw's camera was below a surface */
    bool frame_read;                  /* the last draw copied the frame (medium, high, or under
                                         water): on llvmpipe, a wait for all of it */
    double cpu_ms;                    /* CPU ms of the last draw; on llvmpipe its GPU work too,
                                         and the frame's before it (the copy waits for it) */
} terrain_water_stats_info;
terrain_water_stats_info terrain_water_stats(const terrain_water *water);

#endif
