/* vegetation.h — grass patches grown on the GPU over the terrain's mesh chunks (002 §3.3).
 *
 *     grass_system *grass = grass_system_create(&(grass_system_desc){ .gfx = gfx, .ecs = ecs, .world = world,
 *                                                       .quality = GRASS_HIGH });
 *     each frame:
 *         grass_set_view(grass, &view, player_feet);   // before ecs_progress
 *         ecs_progress(ecs, dt);                        // "grass_place" runs in the draw phase
 *         terrain_ecs_draw(terrain, renderer, &view);   // the ground first: grass is depth-tested
 *         grass_draw(grass, &view);
 *     grass_system_destroy(grass);                             // before ecs_world_destroy and gfx_context_destroy
 *
 * Call grass_system_create after terrain_ecs_create(it reads the TerrainMeshChunk component). Every
 * mesh chunk of levels 0 and 1 that is uploaded, shown and within reach of the viewer gets a
 * GrassPatch component. Its tufts are placed by compute shaders from the chunk's GPU triangles
 * (no CPU work per tuft): each triangle takes the points of a hashed world lattice (one jittered
 * point per cell, DENSITY cells a square metre) that fall inside it seen from above, at their
 * barycentric position on the triangle. A point is grass when:
 *   - the slope α = (1 − n_y)·90° (002 §3.3) is under slope_limit;
 *   - the ground is soil (bedrock's weight, below the snow line) or, more thinly, sand: never
 *     rocks, cliffs or water beds;
 *   - it is above sea level;
 *   - it has sky above: no solid layer more than 1.5 m over it (not in caves, under arches or
 *     overhangs).
 * Because the lattice belongs to the world, not to the mesh, a tuft stands at the same (x, z)
 * whatever the chunk's level of detail or how an edit re-triangulated it: rings of detail that
 * move with the player, and remeshing after an edit, leave the grass where it was (and place it
 * again in the frame the chunk is re-uploaded). The same seed gives the same tufts, bit for bit,
 * in every run.
 *
 * Each tuft is two crossed billboards around an up halfway between the ground's normal and the
 * vertical, alpha-tested against a blade texture generated at start-up, with per-tuft height,
 * turn and colour, swaying in the wind and bending away from the player's feet. Density falls
 * with distance continuously: at distance d a share 1 − (d − 0.4·range)/(0.6·range) of the tufts
 * stands (each tuft shrinks out as its share passes), so no ring of grass appears or vanishes;
 * beyond range the terrain's own grass tint, which the blades' colours match, carries on.
 *
 * Each frame a compute pass keeps the tufts in view and not yet faded out, from every patch near
 * enough, in one buffer, and one indirect draw shows them: the CPU's work is a few uniforms a
 * patch, whatever the number of tufts.
 *
 * Threads: main thread only (OpenGL). The GPU passes are "grass.place" (placement),
 * "grass.cull" and "grass" (drawing) on the trace's GPU lane.
 */
#ifndef VEGETATION_H
#define VEGETATION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "terrain/terrain.h"

typedef struct ecs_world ecs_world;

typedef enum grass_quality {
    GRASS_DEFAULT = 0,                /* low */
    GRASS_OFF,                        /* no patches, nothing drawn */
    GRASS_LOW,                        /* 4 tufts a square metre out to 35 m */
    GRASS_HIGH,                       /* 9 tufts a square metre out to 70 m */
} grass_quality;

/* Parses "off", "low" or "high" (--grass); false for anything else. */
bool grass_parse_quality(const char *text, grass_quality *out);
const char *grass_quality_name(grass_quality quality);

/* Zero means the default for every field. */
typedef struct grass_system_desc {
    gfx_context *gfx;                 /* required */
    ecs_world *ecs;                   /* required: the world terrain_ecs_create registered on */
    terrain_world *world;             /* required: for the sky test and the sea level */
    grass_quality quality;
    int density;                      /* lattice cells per metre along each axis (density² tufts
                                         per m² at most); 0 = the quality's (2 low, 3 high); ≤ 8 */
    float range;                      /* metres where the last tuft goes; 0 = the quality's */
    float slope_limit;                /* degrees of α = (1 − n_y)·90; 0 = 35 */
    float height;                     /* metres of an average tuft; 0 = 0.5 */
    float snow_height;                /* as terrain_renderer_desc's; 0 = 120 m */
    float fog_density;                /* as terrain_renderer_desc's; 0 = 0.0025 */
    int max_placements;               /* new patches placed per frame ahead of need; 0 = 4
                                         (chunks within range, and chunks remeshed, are always
                                         placed in the frame they are uploaded) */
} grass_system_desc;

typedef struct grass_system grass_system;

/* NULL (the reason logged) when a required field is missing or the shaders do not build. */
grass_system *grass_system_create(const grass_system_desc *desc);
/* Releases every patch (the components stay, empty) and disables the system; the ECS world
 * runs on without grass, and a new grass_system_create may follow. */
void grass_system_destroy(grass_system *grass);

/* The view the next frame is drawn from, and the player's feet (world metres) that the grass
 * bends away from (NULL = nothing bends). Patches follow the view's camera. */
void grass_set_view(grass_system *grass, const terrain_view *view, const double player_feet[3]);
/* Draws the patches of the chunks the cull phase found visible (after the terrain: it needs the
 * depth buffer), in one pass named "grass". */
void grass_draw(grass_system *grass, const terrain_view *view);

/* The GrassPatch component of a mesh chunk entity (one per TerrainMeshChunk of levels 0 and 1
 * within reach). Its GPU buffers are released when the component leaves the entity. */
typedef struct GrassPatch {
    gfx_buffer tuft_buffer;           /* 2 vec4 per tuft (position, seed; normal, grow); { 0 }
                                         when no tuft */
    uint32_t tufts;
    uint64_t source;                  /* the mesh upload the tufts were placed from
                                         (terrain_gpu_mesh.serial) */
    double origin[3];                 /* of the mesh: tuft positions are relative to it */
    float bounds_min[3], bounds_max[3];
    /* The tufts lie in the mesh's triangle order, so each of its parts (terrain_mesh_part) holds
     * a run of them: part p's are [part_first_tuft[p], part_first_tuft[p + 1]). The culling pass
     * looks only at the runs of the parts in view. 0 parts: one run, the whole patch. */
    uint32_t part_count;
    uint32_t part_first_tuft[TERRAIN_MESH_PARTS + 1];
} GrassPatch;

typedef struct grass_system_stats_info {
    int patches;                      /* GrassPatch components now */
    uint64_t tufts;                   /* placed over all patches now (two billboards each) */
    uint64_t tufts_drawn;             /* those the last culling pass looked at: the tufts of the
                                         mesh parts in view and range of the patches drawn (the
                                         pass keeps those in view and not faded out) */
    int patches_drawn;
    uint64_t placements;              /* patches placed since creation (re-placements too) */
    double cpu_ms;                    /* CPU ms of the last frame: placing and drawing */
    size_t bytes;                     /* GPU memory of the patches' tufts (32 bytes a tuft) */
} grass_system_stats_info;

grass_system_stats_info grass_system_stats(const grass_system *grass);
/* The tufts the last grass_draw drew: those its culling pass kept (reads the GPU back, a wait:
 * tests, benchmarks). Two billboards each. */
uint64_t grass_visible_tufts(grass_system *grass);
/* A hash of every patch's tufts, in order of their chunks' coordinates (reads the GPU back:
 * tests and tools only). */
uint64_t grass_tufts_digest(grass_system *grass);

#endif
