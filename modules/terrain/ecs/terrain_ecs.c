/* terrain_ecs.c — the terrain as entities: column chunks generated in the generate phase, mesh
 * chunks meshed in the mesh phase (both in parallel on the job system), uploaded in draw. */
#include "terrain/ecs/terrain_ecs_internal.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "trace/trace.h"

#include <math.h>
#include <stdlib.h>

_Static_assert(TERRAIN_CHUNK_COLUMNS == TERRAIN_MESH_CELLS, "a level-0 mesh chunk is one column chunk wide");


static void terrain_generate_system(ecs_iter *it) {
    terrain_ecs *te = it->user;
    while (ecs_query_next(it)) {
        TerrainChunk *chunks = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) {
            if (chunks[i].stacks) continue;
            /* Retained: the cache never evicts a chunk an entity holds. */
            terrain_world_retain(te->terrain, chunks[i].coord);
            chunks[i].stacks = terrain_world_stacks(te->terrain, chunks[i].coord);
            ecs_defer_add(it->commands, it->entities[i], te->chunk_ready);
        }
    }
}

/* One mesh chunk at its level: terrain_mesh_chunk samples the cells plus a one-sample apron for
 * gradients (normals agree with the neighbours' along shared borders) and, next to finer
 * neighbours, the transition samples that close the seam. */
static void terrain_mesh_chunk_build(terrain_ecs *te, TerrainMeshChunk *chunk) {
    TRACE_ZONE("terrain_mesh_chunk");
    trace_zone_arg_int("x", chunk->x);
    trace_zone_arg_int("y", chunk->y);
    trace_zone_arg_int("z", chunk->z);
    trace_zone_arg_int("level", chunk->lod.level);
    if (!terrain_mesh_chunk(te->terrain, chunk->x, chunk->y, chunk->z, &chunk->lod, &chunk->mesh))
        chunk->mesh = (terrain_mesh){ 0 };      /* nothing to show; the reason is logged */
    /* Its water surfaces, read from the same stacks (002 §3.4): handed to WaterPlane at upload. */
    terrain__water_free(&chunk->water);
    chunk->water = terrain__water_find(te->terrain, chunk->x, chunk->y, chunk->z, chunk->lod.level);
    chunk->state = TERRAIN_MESH_MESHED;
}

static void terrain_mesh_system(ecs_iter *it) {
    terrain_ecs *te = it->user;
    while (ecs_query_next(it)) {
        TerrainMeshChunk *chunks = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) {
            if (chunks[i].state != TERRAIN_MESH_WAITING) continue;
            terrain_mesh_chunk_build(te, &chunks[i]);
            ecs_defer_add(it->commands, it->entities[i], te->mesh_ready);
        }
    }
}

static void terrain_cull_system(ecs_iter *it) {
    terrain_ecs *te = it->user;
    while (ecs_query_next(it)) {
        TerrainMeshChunk *chunks = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) {
            TerrainMeshChunk *c = &chunks[i];
            bool on_gpu = c->gpu.vertex_array.id != 0;
            const double *origin = on_gpu ? c->gpu.origin : c->mesh.origin;
            const float *lo = on_gpu ? c->gpu.bounds_min : c->mesh.bounds_min;
            const float *hi = on_gpu ? c->gpu.bounds_max : c->mesh.bounds_max;
            c->visible = !c->hidden && (!te->culling || terrain_frustum_sees(&te->frustum, origin, lo, hi));
        }
    }
}

size_t terrain__mesh_bytes(uint32_t vertex_count, uint32_t index_count) {
    return (size_t)vertex_count * sizeof(terrain_vertex) + (size_t)index_count * sizeof(uint32_t);
}

/* The chunk's water surfaces go onto its entity with its mesh, replacing what an older mesh
 * had; a chunk that holds water no more loses the component. */
static void terrain_upload_water(terrain_ecs *te, ecs_commands *commands, ecs_entity entity, TerrainMeshChunk *c) {
    if (c->water) ecs_defer_set(commands, entity, te->water_plane, c->water);
    else if (ecs_has(te->ecs, entity, te->water_plane)) ecs_defer_remove(commands, entity, te->water_plane);
    terrain__water_free(&c->water);
}

/* Uploads meshed chunks (the CPU copy is freed), replacing what the chunk drew before; when
 * streaming, only as many as the frame's budget allows, then queued frees. */
static void terrain_upload_system(ecs_iter *it) {
    terrain_ecs *te = it->user;
    uint64_t budget = terrain__stream_upload_budget(te);
    uint64_t start = core_time_ns(), deadline = budget == UINT64_MAX ? UINT64_MAX : start + budget;
    while (ecs_query_next(it)) {
        TerrainMeshChunk *chunks = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) {
            TerrainMeshChunk *c = &chunks[i];
            if (c->state != TERRAIN_MESH_MESHED) continue;
            /* Edited chunks go up whatever the budget: a stroke shows the frame it lands. */
            if (!c->edited && deadline != UINT64_MAX && core_time_ns() >= deadline) continue;
            size_t old_bytes = c->gpu_bytes, cpu_bytes = terrain__mesh_bytes(c->mesh.vertex_count, c->mesh.index_count);
            terrain_gpu_mesh_destroy(&c->gpu);
            c->gpu = terrain_gpu_mesh_upload(&c->mesh);
            c->gpu_bytes = c->gpu.vertex_array.id ? cpu_bytes : 0;
            terrain_mesh_free(&c->mesh);
            terrain_upload_water(te, it->commands, it->entities[i], c);
            c->state = TERRAIN_MESH_UPLOADED;
            c->edited = false;
            if (te->stream) terrain__stream_uploaded(te, cpu_bytes, c->gpu_bytes, old_bytes);
            ecs_defer_add(it->commands, it->entities[i], te->mesh_uploaded);
        }
    }
    if (te->stream) terrain__stream_free_pending(te, deadline);
}

/* TerrainMeshChunk's on_remove hook: the one place its meshes and GPU buffers are freed,
 * whatever removes it (streaming's eviction, terrain_ecs_destroy, a game's own destroy). When
 * streaming, the GPU mesh joins the queue of frees spread over frames; the streamer counted
 * the bytes out when it chose to evict. */
static void terrain_mesh_chunk_removed(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)world, (void)entity;
    terrain_ecs *te = user;
    TerrainMeshChunk *c = data;
    terrain_mesh_free(&c->mesh);
    terrain__water_free(&c->water);
    if (te->stream && c->gpu.vertex_array.id) terrain__stream_free_later(te, c->gpu);
    else terrain_gpu_mesh_destroy(&c->gpu);
    c->gpu = (terrain_gpu_mesh){ 0 };
}

terrain_ecs *terrain_ecs_create(const terrain_ecs_desc *desc) {
    if (!desc || !desc->ecs || !desc->terrain) {
        core_log_error("terrain", "terrain_ecs_create needs .ecs and .terrain");
        return NULL;
    }
    ecs_world *ecs = desc->ecs;
    terrain_world *terrain = desc->terrain;
    terrain_ecs *te = core_calloc(1, sizeof *te);
    te->ecs = ecs;
    te->terrain = terrain;
    te->chunk = ECS_COMPONENT(ecs, TerrainChunk);
    te->mesh_chunk = ECS_COMPONENT(ecs, TerrainMeshChunk);
    ecs_component_on_remove(ecs, te->mesh_chunk, terrain_mesh_chunk_removed, te);
    te->chunk_ready = ECS_TAG(ecs, TerrainChunkReady);
    te->mesh_ready = ECS_TAG(ecs, TerrainMeshReady);
    te->mesh_uploaded = ECS_TAG(ecs, TerrainMeshUploaded);
    te->streamed = ECS_TAG(ecs, TerrainMeshStreamed);
    te->water_plane = ECS_COMPONENT(ecs, WaterPlane);
    te->self_resource = ecs_resource_register(ecs, &(ecs_resource_desc){ .name = "terrain_ecs", .object = te });
    te->clipmap_resource = ecs_resource_register(ecs, &(ecs_resource_desc){ .name = "terrain_clipmap" });
    te->chunks = ecs_query_create(ecs, &(ecs_query_desc){ .with = { te->chunk } });
    te->mesh_chunks = ecs_query_create(ecs, &(ecs_query_desc){ .with = { te->mesh_chunk } });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "terrain_generate", .phase = "generate",
        .query = { .with = { te->chunk }, .without = { te->chunk_ready } }, .writes = { te->chunk },
        .fn = terrain_generate_system,
        .user = te, .parallel = true, .batch_size = 1 });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "terrain_mesh", .phase = "mesh",
        .query = { .with = { te->mesh_chunk }, .without = { te->mesh_ready, te->streamed } },
        .writes = { te->mesh_chunk }, .fn = terrain_mesh_system,
        .user = te, .parallel = true, .batch_size = 1 });
    /* Meshed chunks (uploaded or not) have bounds: the cull phase runs before the upload. */
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "terrain_cull", .phase = "cull",
        .query = { .with = { te->mesh_chunk, te->mesh_ready } }, .writes = { te->mesh_chunk },
        .fn = terrain_cull_system, .user = te, .parallel = true, .batch_size = 256 });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "terrain_upload", .phase = "draw",
        .query = { .with = { te->mesh_chunk, te->mesh_ready }, .without = { te->mesh_uploaded } },
        .writes = { te->mesh_chunk, te->water_plane, te->self_resource }, .fn = terrain_upload_system,
        .user = te, .main_thread = true });
    terrain__editor_register(te);
    return te;
}

ecs_component terrain_ecs_resource(const terrain_ecs *te) { return te->self_resource; }

void terrain_ecs_destroy(terrain_ecs *te) {
    if (!te) return;
    terrain__stream_destroy(te);           /* waits for its background jobs */
    terrain__editor_destroy(te);
    /* The mesh chunks are the terrain's entities: they go with it, their hook freeing what
     * they hold (the streamer is gone, so GPU meshes go at once, on this thread). The hook's
     * user is te, so it is cleared before te is freed. */
    int mesh_count = ecs_query_count(te->ecs, te->mesh_chunks);
    ecs_entity *doomed = core_alloc((size_t)(mesh_count + 1) * sizeof *doomed);
    int doomed_count = 0;
    ecs_iter it = ecs_query_iter(te->ecs, te->mesh_chunks);
    while (ecs_query_next(&it))
        for (int i = 0; i < it.count; i++) doomed[doomed_count++] = it.entities[i];
    for (int i = 0; i < doomed_count; i++) ecs_entity_destroy(te->ecs, doomed[i]);
    core_free(doomed, (size_t)(mesh_count + 1) * sizeof *doomed);
    ecs_component_on_remove(te->ecs, te->mesh_chunk, NULL, NULL);
    it = ecs_query_iter(te->ecs, te->chunks);
    while (ecs_query_next(&it)) {
        TerrainChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++)
            if (chunks[i].stacks) terrain_world_release(te->terrain, chunks[i].coord);
    }
    if (te->draw_list) core_free(te->draw_list, te->draw_capacity * sizeof *te->draw_list);
    if (te->caster_list) core_free(te->caster_list, te->caster_capacity * sizeof *te->caster_list);
    core_free(te, sizeof *te);
}

void terrain_ecs_spawn_area(terrain_ecs *te, int64_t cx, int64_t cz, int radius, int64_t y_first, int64_t y_last) {
    for (int64_t z = cz - radius; z <= cz + radius; z++)
        for (int64_t x = cx - radius; x <= cx + radius; x++) {
            ecs_entity e = ecs_entity_create(te->ecs);
            ecs_set(te->ecs, e, te->chunk, &(TerrainChunk){ .coord = { x, z } });
            for (int64_t y = y_first; y <= y_last; y++) {
                ecs_entity m = ecs_entity_create(te->ecs);
                ecs_set(te->ecs, m, te->mesh_chunk, &(TerrainMeshChunk){ .x = x, .y = y, .z = z });
            }
        }
}

/* Whether level-L chunk (x, z) lies inside the finer level's area (L > 0). */
static bool terrain_ring_inner(int half_width, int level, int64_t x, int64_t z) {
    int64_t inner = half_width / 2;
    return level > 0 && x >= -inner && x < inner && z >= -inner && z < inner;
}

static uint32_t terrain_ring_mask(int half_width, int level, int64_t x, int64_t y, int64_t z,
                                  int64_t y_first, int64_t y_last) {
    uint32_t mask = 0;
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                if (y + dy < y_first || y + dy > y_last) continue;   /* nothing meshed there */
                if (terrain_ring_inner(half_width, level, x + dx, z + dz))
                    mask |= terrain_lod_neighbour_bit(dx, dy, dz);
            }
    return mask;
}

void terrain_ecs_spawn_rings(terrain_ecs *te, int half_width, int levels, double y_min, double y_max) {
    if (levels < 1) levels = 1;
    if (levels > 1 && half_width % 2) half_width++;     /* rings must align with coarser chunks */
    double top_height = (double)TERRAIN_MESH_CELLS * (double)(1 << (levels - 1));
    y_min = floor(y_min / top_height) * top_height;
    y_max = ceil(y_max / top_height) * top_height;
    for (int level = 0; level < levels; level++) {
        double height = (double)TERRAIN_MESH_CELLS * (double)(1 << level);
        int64_t y_first = (int64_t)floor(y_min / height), y_last = (int64_t)ceil(y_max / height) - 1;
        for (int64_t z = -half_width; z < half_width; z++)
            for (int64_t x = -half_width; x < half_width; x++) {
                if (terrain_ring_inner(half_width, level, x, z)) continue;
                if (level == 0) {     /* a level-0 mesh chunk is one column chunk wide */
                    ecs_entity e = ecs_entity_create(te->ecs);
                    ecs_set(te->ecs, e, te->chunk, &(TerrainChunk){ .coord = { x, z } });
                }
                for (int64_t y = y_first; y <= y_last; y++) {
                    ecs_entity m = ecs_entity_create(te->ecs);
                    ecs_set(te->ecs, m, te->mesh_chunk, &(TerrainMeshChunk){
                        .x = x, .y = y, .z = z,
                        .lod = { .level = level,
                                 .finer_neighbours = terrain_ring_mask(half_width, level, x, y, z, y_first, y_last) } });
                }
            }
    }
}

void terrain_ecs_set_view(terrain_ecs *te, const terrain_view *view) {
    te->culling = view != NULL;
    if (view) te->frustum = terrain_frustum_from_view(view);
}

/* Squared distance from the camera to the mesh's box. */
static double terrain_mesh_distance2(const terrain_gpu_mesh *m, const double camera[3]) {
    double sum = 0;
    for (int a = 0; a < 3; a++) {
        double lo = m->origin[a] + m->bounds_min[a], hi = m->origin[a] + m->bounds_max[a];
        double d = camera[a] < lo ? lo - camera[a] : camera[a] > hi ? camera[a] - hi : 0.0;
        sum += d * d;
    }
    return sum;
}

static int terrain_compare_nearer(const void *a, const void *b, void *camera) {
    double x = terrain_mesh_distance2(a, camera), y = terrain_mesh_distance2(b, camera);
    return (x > y) - (x < y);
}

void terrain_ecs_draw(terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view) {
    size_t count = 0, casters = 0;
    ecs_iter it = ecs_query_iter(te->ecs, te->mesh_chunks);
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            /* The newest mesh on the GPU, or the one it replaces until it is up. Out of view it
             * may still shade what is in view: the shadow pass culls those by its own boxes. */
            if (chunks[i].gpu.index_count == 0) continue;
            te->caster_list = core_grow(te->caster_list, &te->caster_capacity, casters + 1, sizeof *te->caster_list);
            te->caster_list[casters++] = chunks[i].gpu;
            if (!chunks[i].visible) continue;
            te->draw_list = core_grow(te->draw_list, &te->draw_capacity, count + 1, sizeof *te->draw_list);
            te->draw_list[count++] = chunks[i].gpu;
        }
    }
    /* Nearest first: the depth test then rejects what nearer ground hides before it is shaded
     * (triplanar shading is most of a frame on llvmpipe), whatever order the ECS's tables hold
     * the chunks in (a component added to some chunks, as grass does, reorders them). */
    double camera[3] = { view->camera[0], view->camera[1], view->camera[2] };
    if (count > 1) qsort_r(te->draw_list, count, sizeof *te->draw_list, terrain_compare_nearer, camera);
    terrain_renderer_draw_shadows(renderer, view, te->caster_list, (int)casters);
    terrain_renderer_draw(renderer, view, te->draw_list, (int)count);
    trace_counter("terrain.mesh_chunks_drawn", (double)count);
    trace_counter("terrain.chunks_cached", (double)terrain_world_chunk_count(te->terrain));
    /* Outside ecs_progress no frame job holds stacks (background jobs bracket their reads with
     * terrain_world_read_begin/end): the moment to drop cached chunks no entity keeps. */
    terrain_world_trim(te->terrain);
}

terrain_ecs_stats_info terrain_ecs_stats(const terrain_ecs *te) {
    terrain_ecs_stats_info stats = { 0 };
    ecs_iter it = ecs_query_iter(te->ecs, te->chunks);
    while (ecs_query_next(&it)) {
        TerrainChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++, stats.chunks++) stats.chunks_generated += chunks[i].stacks != NULL;
    }
    it = ecs_query_iter(te->ecs, te->mesh_chunks);
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++, stats.mesh_chunks++) {
            stats.mesh_chunks_waiting += chunks[i].state == TERRAIN_MESH_WAITING;
            stats.mesh_chunks_uploaded += chunks[i].state == TERRAIN_MESH_UPLOADED;
            stats.triangles += chunks[i].state == TERRAIN_MESH_UPLOADED ? chunks[i].gpu.index_count / 3
                                                                         : chunks[i].mesh.index_count / 3;
        }
    }
    return stats;
}
