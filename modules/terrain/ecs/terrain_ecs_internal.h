/* terrain_ecs_internal.h — the private declarations of the terrain's ECS area
 * (modules/terrain/ecs/): the terrain_ecs object, the streamer's and the editor's hooks. The
 * public API is ecs/terrain_ecs.h.
 *
 * Sections are owned by whoever wrote them; add new declarations in a section of your own.
 */
#ifndef TERRAIN_ECS_INTERNAL_H
#define TERRAIN_ECS_INTERNAL_H

#include "terrain/ecs/terrain_ecs.h"
#include "terrain/data/terrain_data_internal.h"
#include "terrain/edit/terrain_edit_internal.h"
#include "terrain/render/terrain_render_internal.h"

#include "core/core.h"
#include "ecs/ecs.h"

#include <stdint.h>

/* ==== the terrain in the ECS, streaming (terrain_ecs.c, terrain_stream.c) ================= */

typedef struct terrain__streamer terrain__streamer;
typedef struct terrain__editor terrain__editor;

struct terrain_ecs {
    ecs_world *ecs;
    terrain_world *terrain;
    ecs_component chunk, mesh_chunk;
    /* Tags that move finished entities out of the systems' queries, so a frame with nothing to
     * generate or mesh schedules no jobs at all; `streamed` marks the streamer's mesh chunks,
     * which the synchronous systems leave alone. */
    ecs_component chunk_ready, mesh_ready, mesh_uploaded, streamed;
    ecs_component water_plane;           /* WaterPlane (terrain.h, "water planes") */
    /* Resources (ecs.h): this object (the streamer's and the editor's state, the view), and the
     * far terrain's clipmap, which systems declare instead of reaching them behind the
     * scheduler's back. */
    ecs_component self_resource, clipmap_resource;
    ecs_query *chunks, *mesh_chunks;
    terrain_frustum frustum;             /* of the view set for the cull phase */
    bool culling;
    terrain_gpu_mesh *draw_list;         /* gathered each draw */
    size_t draw_capacity;
    terrain_gpu_mesh *caster_list;       /* every mesh on the GPU: the shadows' casters */
    size_t caster_capacity;
    terrain__streamer *stream;           /* NULL unless terrain_ecs_stream was called */
    terrain__editor *editor;             /* created by the first edit call */
    terrain_world_change *changed;       /* column chunks committed before this frame's mesh phase */
    size_t changed_count, changed_capacity;
};

/* Bytes a mesh holds, on the CPU or (the same arrays) on the GPU. */
size_t terrain__mesh_bytes(uint32_t vertex_count, uint32_t index_count);
/* The upload system's budget: nanoseconds of uploads and frees this frame (UINT64_MAX when not
 * streaming: everything at once). */
uint64_t terrain__stream_upload_budget(const terrain_ecs *te);
/* Called by the upload system: a mesh went from the CPU to the GPU (replacing `old_gpu_bytes`). */
void terrain__stream_uploaded(terrain_ecs *te, size_t cpu_bytes, size_t gpu_bytes, size_t old_gpu_bytes);
/* Frees queued GPU meshes until the deadline (core_time_ns), at least a few a frame. */
void terrain__stream_free_pending(terrain_ecs *te, uint64_t deadline);
/* Queues a GPU mesh for terrain__stream_free_pending (from TerrainMeshChunk's on_remove hook). */
void terrain__stream_free_later(terrain_ecs *te, terrain_gpu_mesh gpu);
void terrain__stream_destroy(terrain_ecs *te);

/* Editing (terrain_ecs_edit.c): the stabilize phase's system, and the editor's memory. */
void terrain__editor_register(terrain_ecs *te);
void terrain__editor_destroy(terrain_ecs *te);
/* Whether mesh chunk (level, x, y, z) reads a column of the changed chunk at a changed height
 * (samples, apron, kernel and material weights, and `amplify_reach` metres further for what the
 * world's amplify hook adds): it must be meshed again. */
bool terrain__mesh_reads_change(int level, int64_t x, int64_t y, int64_t z, const terrain_world_change *change,
                                const float amplify_reach[3]);

/* ==== end of the ECS and streaming section ================================================ */

#endif
