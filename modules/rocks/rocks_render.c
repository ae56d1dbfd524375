/* rocks_render.c — the tile set's rock meshes on the GPU, drawn instanced.
 *
 * Every rock mesh of every level of detail lives in one vertex and one index buffer, uploaded
 * once. A frame buckets the rocks in view by (rock, LOD) — counting, a prefix sum, a scatter: no
 * sort — writes their instances into one buffer in bucket order, and issues one
 * glMultiDrawElementsIndirect whose commands are the buckets (baseInstance points each at its
 * run of instances). The CPU work is a few operations per rock in view, whatever their meshes.
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

typedef struct rock_gpu_vertex {
    float position[3];                /* tile units from the rock's seed */
    int8_t normal[4];
} rock_gpu_vertex;

typedef struct rock_gpu_instance {
    float seed[4];                    /* seed − camera (metres), scale */
    float tint[4];
} rock_gpu_instance;

typedef struct draw_command {
    uint32_t count, instance_count, first_index;
    int32_t base_vertex;
    uint32_t base_instance;
} draw_command;

struct rocks_renderer {
    gfx_context *gfx;
    const rocks_tileset *set;
    gfx_program program;
    gfx_buffer vertices, indices, instances, commands;
    gfx_vertex_array vertex_array;
    size_t instance_capacity, command_capacity;   /* in items, GPU side */
    /* Per-frame CPU scratch. */
    uint32_t *bucket_count;           /* rock_count × ROCKS_LODS, zero between frames */
    uint32_t *touched;                /* bucket ids with a count */
    size_t touched_capacity;
    rock_gpu_instance *staged;
    size_t staged_capacity;
    rock_gpu_instance *ordered;
    size_t ordered_capacity;
    draw_command *command_list;
    size_t command_list_capacity;
};

/* Instances in buffer 1, advanced once per instance (baseInstance offsets them per command). */
static void make_vertex_array(rocks_renderer *r) {
    r->vertex_array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = r->vertices, .vertex_stride = sizeof(rock_gpu_vertex),
        .instances = r->instances, .instance_stride = sizeof(rock_gpu_instance),
        .indices = r->indices,
        .attributes = {
            { .components = 3, .type = GL_FLOAT, .offset = 0 },
            { .components = 3, .type = GL_BYTE, .normalized = true, .offset = offsetof(rock_gpu_vertex, normal) },
            { .components = 4, .type = GL_FLOAT, .offset = 0, .buffer = 1 },
            { .components = 4, .type = GL_FLOAT, .offset = offsetof(rock_gpu_instance, tint), .buffer = 1 },
        } });
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
    /* Vertices relative to their rock's seed: the instance then places the seed. */
    rock_gpu_vertex *vertices = core_alloc((set->vertex_count ? set->vertex_count : 1) * sizeof *vertices);
    for (uint32_t k = 0; k < set->rock_count; k++) {
        const rocks_rock *rock = &set->rocks[k];
        for (uint32_t v = rock->vertex_first; v < rock->vertex_first + rock->vertex_count; v++) {
            const rocks_vertex *in = &set->vertices[v];
            rock_gpu_vertex *out = &vertices[v];
            for (int a = 0; a < 3; a++) {
                out->position[a] = in->position[a] - rock->seed[a];
                out->normal[a] = in->normal[a];
            }
            out->normal[3] = 0;
        }
    }
    r->vertices = gfx_buffer_create(&(gfx_buffer_desc){ .size = (size_t)set->vertex_count * sizeof *vertices,
                                                        .data = vertices });
    core_free(vertices, (set->vertex_count ? set->vertex_count : 1) * sizeof *vertices);
    r->indices = gfx_buffer_create(&(gfx_buffer_desc){ .size = (size_t)set->index_count * sizeof(uint16_t),
                                                       .data = set->indices });
    r->instance_capacity = 4096;
    r->instances = gfx_buffer_create(&(gfx_buffer_desc){ .size = r->instance_capacity * sizeof(rock_gpu_instance),
                                                         .usage = GFX_BUFFER_DYNAMIC });
    r->command_capacity = 1024;
    r->commands = gfx_buffer_create(&(gfx_buffer_desc){ .size = r->command_capacity * sizeof(draw_command),
                                                        .usage = GFX_BUFFER_DYNAMIC });
    make_vertex_array(r);
    r->bucket_count = core_calloc((size_t)set->rock_count * ROCKS_LODS + 1, sizeof *r->bucket_count);
    return r;
}

void rocks__renderer_destroy(rocks_renderer *r) {
    if (!r) return;
    gfx_vertex_array_destroy(&r->vertex_array);
    gfx_buffer_destroy(&r->vertices);
    gfx_buffer_destroy(&r->indices);
    gfx_buffer_destroy(&r->instances);
    gfx_buffer_destroy(&r->commands);
    core_free(r->bucket_count, ((size_t)r->set->rock_count * ROCKS_LODS + 1) * sizeof *r->bucket_count);
    core_free(r->touched, r->touched_capacity * sizeof *r->touched);
    core_free(r->staged, r->staged_capacity * sizeof *r->staged);
    core_free(r->ordered, r->ordered_capacity * sizeof *r->ordered);
    core_free(r->command_list, r->command_list_capacity * sizeof *r->command_list);
    core_free(r, sizeof *r);
}

size_t rocks__renderer_gpu_bytes(const rocks_renderer *r) {
    if (!r) return 0;
    return (size_t)r->set->vertex_count * sizeof(rock_gpu_vertex) + (size_t)r->set->index_count * sizeof(uint16_t) +
           r->instance_capacity * sizeof(rock_gpu_instance) + r->command_capacity * sizeof(draw_command);
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

uint64_t rocks__renderer_draw(rocks_renderer *r, const terrain_view *view, const rocks_draw_desc *params,
                              const rocks_placement *const *placements, int count, int *commands_out) {
    TRACE_ZONE("rocks_draw");
    const rocks_tileset *set = r->set;
    const float tile = params->tile_size;
    terrain_frustum frustum = terrain_frustum_from_view(view);
    size_t staged = 0, touched = 0;
    /* Pass 1: pick the rocks in view and their level; count per bucket. */
    for (int p = 0; p < count; p++) {
        const rocks_placement *pl = placements[p];
        float base[3] = { (float)(pl->origin[0] - view->camera[0]), (float)(pl->origin[1] - view->camera[1]),
                          (float)(pl->origin[2] - view->camera[2]) };
        for (uint32_t i = 0; i < pl->count; i++) {
            const rocks_instance *in = &pl->instances[i];
            const rocks_rock *rock = &set->rocks[in->rock];
            float seed[3];
            for (int a = 0; a < 3; a++) seed[a] = base[a] + in->position[a] + rock->seed[a] * tile;
            float radius = rock->radius * tile;
            if (!sphere_in_frustum(&frustum, seed, radius)) continue;
            float distance = sqrtf(seed[0] * seed[0] + seed[1] * seed[1] + seed[2] * seed[2]);
            float spread = 0.75f + 0.5f * key_unit(in->key, 0), scale;
            int lod = choose_lod(params, distance, spread, &scale);
            if (lod < 0 || rock->index_count[lod] == 0) continue;
            uint32_t bucket = in->rock * ROCKS_LODS + (uint32_t)lod;
            if (r->bucket_count[bucket]++ == 0) {
                r->touched = core_grow(r->touched, &r->touched_capacity, touched + 1, sizeof *r->touched);
                r->touched[touched++] = bucket;
            }
            r->staged = core_grow(r->staged, &r->staged_capacity, staged + 1, sizeof *r->staged);
            float shade = 0.85f + 0.3f * key_unit(in->key, 1), warm = key_unit(in->key, 2);
            r->staged[staged] = (rock_gpu_instance){
                .seed = { seed[0], seed[1], seed[2], tile * scale },
                .tint = { shade * (0.50f + 0.07f * warm), shade * (0.48f + 0.03f * warm), shade * (0.45f - 0.03f * warm), 0 },
            };
            r->staged[staged].tint[3] = (float)bucket;      /* its bucket (exact below 2^24) */
            staged++;
        }
    }
    *commands_out = (int)touched;
    if (staged == 0) return 0;
    /* Pass 2: commands in bucket order of first appearance; prefix sums become first instances. */
    r->command_list = core_grow(r->command_list, &r->command_list_capacity, touched, sizeof *r->command_list);
    uint32_t first = 0;
    for (size_t t = 0; t < touched; t++) {
        uint32_t bucket = r->touched[t];
        const rocks_rock *rock = &set->rocks[bucket / ROCKS_LODS];
        uint32_t lod = bucket % ROCKS_LODS, n = r->bucket_count[bucket];
        r->command_list[t] = (draw_command){ .count = rock->index_count[lod], .instance_count = n,
                                             .first_index = rock->index_first[lod],
                                             .base_vertex = (int32_t)rock->vertex_first, .base_instance = first };
        r->bucket_count[bucket] = first;           /* now the next free slot of the bucket */
        first += n;
    }
    /* Pass 3: scatter. */
    r->ordered = core_grow(r->ordered, &r->ordered_capacity, staged, sizeof *r->ordered);
    for (size_t s = 0; s < staged; s++) {
        uint32_t bucket = (uint32_t)r->staged[s].tint[3];
        r->ordered[r->bucket_count[bucket]++] = r->staged[s];
    }
    for (size_t t = 0; t < touched; t++) r->bucket_count[r->touched[t]] = 0;

    if (staged > r->instance_capacity || touched > r->command_capacity) {
        while (r->instance_capacity < staged) r->instance_capacity *= 2;
        while (r->command_capacity < touched) r->command_capacity *= 2;
        gfx_buffer_destroy(&r->instances);
        gfx_buffer_destroy(&r->commands);
        gfx_vertex_array_destroy(&r->vertex_array);
        r->instances = gfx_buffer_create(&(gfx_buffer_desc){ .size = r->instance_capacity * sizeof(rock_gpu_instance),
                                                             .usage = GFX_BUFFER_DYNAMIC });
        r->commands = gfx_buffer_create(&(gfx_buffer_desc){ .size = r->command_capacity * sizeof(draw_command),
                                                            .usage = GFX_BUFFER_DYNAMIC });
        make_vertex_array(r);
    }
    gfx_buffer_update(r->instances, 0, r->ordered, staged * sizeof *r->ordered);
    gfx_buffer_update(r->commands, 0, r->command_list, touched * sizeof *r->command_list);

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
    glBindVertexArray(gfx_vertex_array_gl(r->vertex_array));
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, gfx_buffer_gl(r->commands));
    glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_SHORT, NULL, (GLsizei)touched, 0);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    glBindVertexArray(0);
    gfx_pass_end(r->gfx);
    trace_counter("rocks.drawn", (double)staged);
    return staged;
}
