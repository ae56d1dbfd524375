/* rocks_render.c — the rocks in view as one batch of vertices a frame, drawn with one call.
 *
 * Every level of detail of every rock keeps its own compact vertices (tile units from the rock's
 * seed, and normals) and indices on the CPU, made once from the tile set. A frame picks the rocks
 * in view and their levels and writes each one's vertices, placed (seed less the camera, plus the
 * vertex times the scale) and tinted, into one vertex buffer with its indices, then draws them
 * all with one glDrawElements. The CPU work is a few operations per vertex in view: ~7 k
 * vertices for the ~1 200 rocks a walk's start view holds, most of them at LOD 2 (4.3 vertices).
 *
 * Why not instances: an instanced draw (the first version: one glMultiDrawElementsIndirect, a
 * command per rock mesh and level) costs llvmpipe about a microsecond per instance whatever the
 * mesh, 1.2 ms a frame for 1 200 rocks whose 4-triangle LOD 2 is almost all of them; drawing
 * every rock at LOD 2 saved 0.1 of it. Rocks this small are also what a GPU packs poorly into
 * instances. The per-frame upload is ~32 bytes a vertex (~0.2 MB).
 *
 * Levels of detail: a rock switches at lod_distance × s, s ∈ [0.75, 1.25] from a hash of its
 * key, so switches are spread over a band instead of a ring moving with the player. Past
 * 0.8 × range (times s again) a rock shrinks into its seed point, gone at range.
 */
#include "rocks_world_internal.h"

#include <math.h>
#include <string.h>

#include "core/core.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

/* A vertex of a rock's level, as kept: tile units from the rock's seed. */
typedef struct rock_mesh_vertex {
    float local[3];
    int8_t normal[4];
} rock_mesh_vertex;

/* Where one rock level's compact vertices and its indices (into them) start. */
typedef struct rock_level {
    uint32_t vertex_first, index_first;
    uint16_t vertex_count;            /* a rock's vertices fit 16-bit indices in the tile set */
    uint32_t index_count;
} rock_level;

/* A rock in view: its level (an index into levels), where and how it is drawn. */
typedef struct rock_pick {
    uint32_t level;
    float seed[3];                    /* metres from the camera */
    float scale;                      /* metres a tile unit: tile size × the fade past range */
    uint8_t tint[4];
} rock_pick;

/* A vertex as drawn (32 bytes). */
typedef struct rock_gpu_vertex {
    float relative[3];                /* metres from the camera */
    float local[3];                   /* tile units from the seed: the grain's frame */
    int8_t normal[4];
    uint8_t tint[4];                  /* albedo, unorm */
} rock_gpu_vertex;

struct rocks_renderer {
    gfx_context *gfx;
    const rocks_tileset *set;
    gfx_program program;
    rock_level *levels;               /* rock_count × ROCKS_LODS */
    rock_mesh_vertex *mesh_vertices;
    uint16_t *mesh_indices;
    size_t mesh_vertex_count, mesh_index_count;
    /* The frame's batch: the rocks picked, CPU staging, and the GPU buffers (grown by doubling). */
    rock_pick *picks;
    size_t pick_capacity;
    rock_gpu_vertex *staged_vertices;
    uint32_t *staged_indices;
    size_t staged_vertex_capacity, staged_index_capacity;
    gfx_buffer vertices, indices;
    gfx_vertex_array vertex_array;
    size_t vertex_capacity, index_capacity;   /* in items, GPU side */
};

static void make_buffers(rocks_renderer *r) {
    r->vertices = gfx_buffer_create(&(gfx_buffer_desc){ .size = r->vertex_capacity * sizeof(rock_gpu_vertex),
                                                        .usage = GFX_BUFFER_DYNAMIC });
    r->indices = gfx_buffer_create(&(gfx_buffer_desc){ .size = r->index_capacity * sizeof(uint32_t),
                                                       .usage = GFX_BUFFER_DYNAMIC });
    r->vertex_array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = r->vertices, .vertex_stride = sizeof(rock_gpu_vertex), .indices = r->indices,
        .attributes = {
            { .components = 3, .type = GL_FLOAT, .offset = offsetof(rock_gpu_vertex, relative) },
            { .components = 3, .type = GL_FLOAT, .offset = offsetof(rock_gpu_vertex, local) },
            { .components = 3, .type = GL_BYTE, .normalized = true, .offset = offsetof(rock_gpu_vertex, normal) },
            { .components = 3, .type = GL_UNSIGNED_BYTE, .normalized = true, .offset = offsetof(rock_gpu_vertex, tint) },
        } });
}

static void destroy_buffers(rocks_renderer *r) {
    gfx_vertex_array_destroy(&r->vertex_array);
    gfx_buffer_destroy(&r->vertices);
    gfx_buffer_destroy(&r->indices);
}

/* Rock level `lod`'s vertices, only those its triangles use, numbered in order of first use,
 * into out (tile units from the seed) with its indices into `indices`; both NULL: only counted.
 * Returns the vertices. `stamp` (one entry a vertex of the rock, UINT16_MAX between calls) says
 * where each vertex went. */
static uint16_t compact_level(const rocks_tileset *set, const rocks_rock *rock, int lod, uint16_t *stamp,
                              rock_mesh_vertex *out, uint16_t *indices) {
    uint16_t used = 0;
    for (uint32_t i = 0; i < rock->index_count[lod]; i++) {
        uint16_t v = set->indices[rock->index_first[lod] + i];
        if (stamp[v] == UINT16_MAX) {
            if (out) {
                const rocks_vertex *in = &set->vertices[rock->vertex_first + v];
                for (int a = 0; a < 3; a++) {
                    out[used].local[a] = in->position[a] - rock->seed[a];
                    out[used].normal[a] = in->normal[a];
                }
                out[used].normal[3] = 0;
            }
            stamp[v] = used++;
        }
        if (indices) indices[i] = stamp[v];
    }
    for (uint32_t i = 0; i < rock->index_count[lod]; i++) stamp[set->indices[rock->index_first[lod] + i]] = UINT16_MAX;
    return used;
}

rocks_renderer *rocks__renderer_create(gfx_context *gfx, const rocks_tileset *set) {
    if (!set->vertices || !set->indices) {
        core_log_error("rocks", "the tile set's meshes were released (rocks_tiles_release_meshes): nothing to draw");
        return NULL;
    }
    gfx_program program = gfx_program_load(gfx, "rocks.vert", "rocks.frag");
    if (!program.id) return NULL;
    rocks_renderer *r = core_calloc(1, sizeof *r);
    r->gfx = gfx;
    r->set = set;
    r->program = program;
    /* Counted first and allocated exactly: the set's own meshes are still in memory here, and
     * the game's peak memory is taken while they are. */
    uint16_t *stamp = core_alloc(65536 * sizeof *stamp);
    memset(stamp, 0xff, 65536 * sizeof *stamp);
    size_t vertex_total = 0, index_total = 0;
    for (uint32_t k = 0; k < set->rock_count; k++)
        for (int lod = 0; lod < ROCKS_LODS; lod++) {
            vertex_total += compact_level(set, &set->rocks[k], lod, stamp, NULL, NULL);
            index_total += set->rocks[k].index_count[lod];
        }
    r->levels = core_calloc((size_t)set->rock_count * ROCKS_LODS, sizeof *r->levels);
    r->mesh_vertices = core_alloc((vertex_total ? vertex_total : 1) * sizeof *r->mesh_vertices);
    r->mesh_indices = core_alloc((index_total ? index_total : 1) * sizeof *r->mesh_indices);
    for (uint32_t k = 0; k < set->rock_count; k++)
        for (int lod = 0; lod < ROCKS_LODS; lod++) {
            const rocks_rock *rock = &set->rocks[k];
            rock_level *level = &r->levels[(size_t)k * ROCKS_LODS + (size_t)lod];
            *level = (rock_level){ .vertex_first = (uint32_t)r->mesh_vertex_count, .index_first = (uint32_t)r->mesh_index_count,
                                   .index_count = rock->index_count[lod] };
            level->vertex_count = compact_level(set, rock, lod, stamp, r->mesh_vertices + r->mesh_vertex_count,
                                                r->mesh_indices + r->mesh_index_count);
            r->mesh_vertex_count += level->vertex_count;
            r->mesh_index_count += level->index_count;
        }
    core_free(stamp, 65536 * sizeof *stamp);
    r->vertex_capacity = 16384;
    r->index_capacity = 32768;
    make_buffers(r);
    return r;
}

void rocks__renderer_destroy(rocks_renderer *r) {
    if (!r) return;
    destroy_buffers(r);
    core_free(r->levels, (size_t)r->set->rock_count * ROCKS_LODS * sizeof *r->levels);
    core_free(r->mesh_vertices, (r->mesh_vertex_count ? r->mesh_vertex_count : 1) * sizeof *r->mesh_vertices);
    core_free(r->mesh_indices, (r->mesh_index_count ? r->mesh_index_count : 1) * sizeof *r->mesh_indices);
    core_free(r->picks, r->pick_capacity * sizeof *r->picks);
    core_free(r->staged_vertices, r->staged_vertex_capacity * sizeof *r->staged_vertices);
    core_free(r->staged_indices, r->staged_index_capacity * sizeof *r->staged_indices);
    core_free(r, sizeof *r);
}

size_t rocks__renderer_gpu_bytes(const rocks_renderer *r) {
    if (!r) return 0;
    return r->vertex_capacity * sizeof(rock_gpu_vertex) + r->index_capacity * sizeof(uint32_t);
}

size_t rocks__renderer_cpu_bytes(const rocks_renderer *r) {
    if (!r) return 0;
    return r->mesh_vertex_count * sizeof *r->mesh_vertices + r->mesh_index_count * sizeof *r->mesh_indices +
           (size_t)r->set->rock_count * ROCKS_LODS * sizeof *r->levels +
           r->pick_capacity * sizeof *r->picks + r->staged_vertex_capacity * sizeof *r->staged_vertices +
           r->staged_index_capacity * sizeof *r->staged_indices;
}

static float key_unit(uint32_t key, int which) {
    return (float)((core_hash_u64((uint64_t)key * 4 + (uint64_t)which) >> 40) & 0xffffff) / 16777216.0f;
}

/* Distance-based level, spread by the rock's own factor; -1 = past range. */
static int choose_lod(const rocks_draw_desc *params, float distance, float spread, float *scale) {
    float fade_start = 0.8f * params->range * spread, end = params->range * spread;
    if (distance >= end) return -1;
    *scale = distance <= fade_start ? 1.0f : (end - distance) / (end - fade_start);
    if (distance < params->lod_distance[0] * spread) return 0;
    if (distance < params->lod_distance[1] * spread) return 1;
    return 2;
}

static bool sphere_in_frustum(const terrain_frustum *f, const float c[3], float radius) {
    for (int p = 0; p < 6; p++)
        if (f->planes[p][0] * c[0] + f->planes[p][1] * c[1] + f->planes[p][2] * c[2] + f->planes[p][3] < -radius)
            return false;
    return true;
}

/* Writes a rock's level placed at seed (metres from the camera) with `scale` (metres a tile unit)
 * and `tint` into the batch at vertex `first_vertex`, index `first_index`. */
static void stage_rock(rocks_renderer *r, const rock_pick *pick, size_t first_vertex, size_t first_index) {
    const rock_level *level = &r->levels[pick->level];
    rock_gpu_vertex *out = r->staged_vertices + first_vertex;
    const rock_mesh_vertex *in = r->mesh_vertices + level->vertex_first;
    for (uint32_t v = 0; v < level->vertex_count; v++) {
        for (int a = 0; a < 3; a++) {
            out[v].relative[a] = pick->seed[a] + in[v].local[a] * pick->scale;
            out[v].local[a] = in[v].local[a];
        }
        memcpy(out[v].normal, in[v].normal, sizeof out[v].normal);
        memcpy(out[v].tint, pick->tint, sizeof out[v].tint);
    }
    const uint16_t *indices = r->mesh_indices + level->index_first;
    uint32_t *to = r->staged_indices + first_index, first = (uint32_t)first_vertex;
    for (uint32_t i = 0; i < level->index_count; i++) to[i] = first + indices[i];
}

static uint8_t unorm8(float x) { return (uint8_t)lrintf(fminf(fmaxf(x, 0.0f), 1.0f) * 255.0f); }

/* Grows the GPU buffers to hold the batch (doubling; the array is made again over them). */
static void fit_buffers(rocks_renderer *r, size_t vertex_count, size_t index_count) {
    if (vertex_count <= r->vertex_capacity && index_count <= r->index_capacity) return;
    while (r->vertex_capacity < vertex_count) r->vertex_capacity *= 2;
    while (r->index_capacity < index_count) r->index_capacity *= 2;
    destroy_buffers(r);
    make_buffers(r);
}

/* The rocks in view with their levels, into r->picks; returns how many. */
static size_t pick_rocks(rocks_renderer *r, const terrain_view *view, const rocks_draw_desc *params,
                         const rocks_placement *const *placements, int count) {
    const rocks_tileset *set = r->set;
    const float tile = params->tile_size;
    terrain_frustum frustum = terrain_frustum_from_view(view);
    size_t picked = 0;
    for (int p = 0; p < count; p++) {
        const rocks_placement *pl = placements[p];
        float base[3] = { (float)(pl->origin[0] - view->camera[0]), (float)(pl->origin[1] - view->camera[1]),
                          (float)(pl->origin[2] - view->camera[2]) };
        for (uint32_t i = 0; i < pl->count; i++) {
            const rocks_instance *in = &pl->instances[i];
            if (i + 8 < pl->count) __builtin_prefetch(&set->rocks[pl->instances[i + 8].rock]);
            const rocks_rock *rock = &set->rocks[in->rock];
            float seed[3];
            for (int a = 0; a < 3; a++) seed[a] = base[a] + in->position[a] + rock->seed[a] * tile;
            float radius = rock->radius * tile;
            if (!sphere_in_frustum(&frustum, seed, radius)) continue;
            float distance = sqrtf(seed[0] * seed[0] + seed[1] * seed[1] + seed[2] * seed[2]);
            float spread = 0.75f + 0.5f * key_unit(in->key, 0), scale;
            int lod = choose_lod(params, distance, spread, &scale);
            if (lod < 0 || rock->index_count[lod] == 0) continue;
            float shade = 0.85f + 0.3f * key_unit(in->key, 1), warm = key_unit(in->key, 2);
            r->picks = core_grow(r->picks, &r->pick_capacity, picked + 1, sizeof *r->picks);
            r->picks[picked] = (rock_pick){
                .level = in->rock * ROCKS_LODS + (uint32_t)lod, .seed = { seed[0], seed[1], seed[2] }, .scale = tile * scale,
                .tint = { unorm8(shade * (0.50f + 0.07f * warm)), unorm8(shade * (0.48f + 0.03f * warm)),
                          unorm8(shade * (0.45f - 0.03f * warm)), 255 } };
            __builtin_prefetch(&r->levels[r->picks[picked++].level]);
        }
    }
    return picked;
}

/* The picked rocks' vertices and indices into the staging arrays, and their counts. Two passes:
 * the levels, then their vertices, each scattered over megabytes and each read only after the
 * previous pass asked for it (prefetched), so the cache misses of one pass overlap. */
static void stage_batch(rocks_renderer *r, size_t picked, size_t *vertex_count, size_t *index_count) {
    size_t vertices = 0, indices = 0;
    for (size_t k = 0; k < picked; k++) {
        const rock_level *level = &r->levels[r->picks[k].level];
        __builtin_prefetch(r->mesh_vertices + level->vertex_first);
        __builtin_prefetch(r->mesh_indices + level->index_first);
        vertices += level->vertex_count;
        indices += level->index_count;
    }
    r->staged_vertices = core_grow(r->staged_vertices, &r->staged_vertex_capacity, vertices, sizeof *r->staged_vertices);
    r->staged_indices = core_grow(r->staged_indices, &r->staged_index_capacity, indices, sizeof *r->staged_indices);
    size_t first_vertex = 0, first_index = 0;
    for (size_t k = 0; k < picked; k++) {
        stage_rock(r, &r->picks[k], first_vertex, first_index);
        first_vertex += r->levels[r->picks[k].level].vertex_count;
        first_index += r->levels[r->picks[k].level].index_count;
    }
    *vertex_count = vertices, *index_count = indices;
}

uint64_t rocks__renderer_draw(rocks_renderer *r, const terrain_view *view, const rocks_draw_desc *params,
                              const rocks_placement *const *placements, int count, uint64_t *triangles_out) {
    TRACE_ZONE("rocks_draw");
    size_t picked = pick_rocks(r, view, params, placements, count), vertex_count = 0, index_count = 0;
    if (picked) stage_batch(r, picked, &vertex_count, &index_count);
    *triangles_out = index_count / 3;
    if (picked == 0) return 0;
    fit_buffers(r, vertex_count, index_count);
    gfx_buffer_update(r->vertices, 0, r->staged_vertices, vertex_count * sizeof *r->staged_vertices);
    gfx_buffer_update(r->indices, 0, r->staged_indices, index_count * sizeof *r->staged_indices);

    gfx_pass_begin(r->gfx, &(gfx_pass_desc){ .name = "rocks" });
    float matrix[16], sun[3], zero[3] = { 0, 0, 0 };
    terrain_view_matrix(view, matrix);
    terrain_view_sun(view, sun);
    gfx_program_use(r->gfx, r->program);
    gfx_uniform_mat4(r->gfx, r->program, "u_view_projection", matrix);
    gfx_uniform_vec3(r->gfx, r->program, "u_sun_direction", sun);
    gfx_uniform_vec3(r->gfx, r->program, "u_camera_position", zero);
    gfx_uniform_float(r->gfx, r->program, "u_fog_density", params->fog_density);
    /* the context's defaults (gfx_context.c): depth test LEQUAL, back faces culled; closed,
     * outward-wound rocks need nothing else, and nothing here is left changed */
    gfx_draw(&(gfx_draw_desc){ .vertex_array = r->vertex_array, .count = (uint32_t)index_count,
                               .index_type = GFX_INDEX_U32 });
    gfx_pass_end(r->gfx);
    trace_counter("rocks.drawn", (double)picked);
    trace_counter("rocks.triangles", (double)(index_count / 3));
    return picked;
}
