/* terrain_render.c — drawing terrain meshes: triplanar materials (000 §6), height and slope tint
 * (002 §4.1), procedural material textures, camera-relative transforms. Main thread only. */
#include "terrain.h"
#include "terrain_internal.h"

#include "core/core.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <cglm/cglm.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#define TERRAIN_TEXTURE_SIZE 256
#define TERRAIN_TEXTURE_LAYERS 4          /* bedrock, sand, rocks, water bed */
#define TERRAIN_TEXTURE_METRES 8.0        /* one texture repeat covers this many metres */
#define TERRAIN_SHADOW_UNIT 3             /* the shadow map's texture unit (the clipmap uses 0 and 1) */

struct terrain_renderer {
    gfx_context *gfx;
    gfx_program terrain, sky, clipmap;
    gfx_texture materials;
    gfx_vertex_array empty;
    terrain_renderer_desc desc;
    terrain_clipmap *far_terrain;         /* not owned; NULL = none */
    terrain__shadows *shadows;            /* NULL with shadows off */
    bool shadows_drawn;                   /* terrain_renderer_draw_shadows ran for the next draw */
    float material_means[TERRAIN_TEXTURE_LAYERS][3];
};

/* ---- procedural material textures ---- */

/* Value noise on a lattice that wraps every `period` cells, so the texture tiles seamlessly. */
static float texture_lattice(uint64_t seed, int x, int y, int period) {
    x = ((x % period) + period) % period;
    y = ((y % period) + period) % period;
    uint64_t h = core_hash_combine(core_hash_u64(seed), core_hash_u64((uint64_t)(uint32_t)x << 32 | (uint32_t)y));
    return (float)(h >> 40) * (1.0f / 16777216.0f);
}

static float texture_value_noise(uint64_t seed, float x, float y, int period) {
    int xi = (int)floorf(x), yi = (int)floorf(y);
    float fx = x - (float)xi, fy = y - (float)yi;
    fx = fx * fx * (3 - 2 * fx);
    fy = fy * fy * (3 - 2 * fy);
    float a = texture_lattice(seed, xi, yi, period), b = texture_lattice(seed, xi + 1, yi, period);
    float c = texture_lattice(seed, xi, yi + 1, period), d = texture_lattice(seed, xi + 1, yi + 1, period);
    return (a + (b - a) * fx) + ((c + (d - c) * fx) - (a + (b - a) * fx)) * fy;
}

/* fBm of tiling value noise over the unit square (u, v ∈ [0, 1)), first octave `cells` across. */
static float texture_fbm(uint64_t seed, float u, float v, int cells, int octaves) {
    float sum = 0, amplitude = 0.5f, total = 0;
    for (int o = 0; o < octaves; o++, cells *= 2, amplitude *= 0.5f) {
        sum += amplitude * texture_value_noise(seed + (uint64_t)o, u * (float)cells, v * (float)cells, cells);
        total += amplitude;
    }
    return sum / total;
}

static void texture_material_texel(int layer, float u, float v, uint8_t *rgba) {
    float r, g, b;
    if (layer == 0) {        /* bedrock: grey-brown strata with cracks */
        float strata = texture_fbm(11, u * 0.25f, v, 8, 5);
        float grain = texture_fbm(12, u, v, 32, 3);
        float shade = 0.45f + 0.35f * strata + 0.2f * grain;
        r = 0.52f * shade; g = 0.48f * shade; b = 0.43f * shade;
    } else if (layer == 1) { /* sand: fine, warm, with ripples */
        float grain = texture_fbm(21, u, v, 64, 3);
        float ripple = 0.5f + 0.5f * sinf((u * 12.0f + texture_fbm(22, u, v, 4, 3) * 3.0f) * 6.2831853f);
        float shade = 0.8f + 0.12f * grain + 0.08f * ripple;
        r = 0.86f * shade; g = 0.76f * shade; b = 0.55f * shade;
    } else if (layer == 2) { /* rocks: pebbles as cells of high noise */
        float cells = texture_fbm(31, u, v, 16, 2);
        float detail = texture_fbm(32, u, v, 64, 2);
        float shade = 0.35f + 0.5f * cells * cells + 0.15f * detail;
        r = 0.48f * shade; g = 0.47f * shade; b = 0.46f * shade;
    } else {                 /* water bed: dark silt */
        float silt = texture_fbm(41, u, v, 16, 4);
        float shade = 0.5f + 0.3f * silt;
        r = 0.30f * shade; g = 0.33f * shade; b = 0.28f * shade;
    }
    rgba[0] = (uint8_t)fminf(255.0f, r * 255.0f);
    rgba[1] = (uint8_t)fminf(255.0f, g * 255.0f);
    rgba[2] = (uint8_t)fminf(255.0f, b * 255.0f);
    rgba[3] = 255;
}

/* Each layer's mean colour: what its mipmaps tend to far away (the clipmap uses it there). */
static void terrain_material_means(const uint8_t *texels, size_t layer_bytes, float means[][3]) {
    for (int layer = 0; layer < TERRAIN_TEXTURE_LAYERS; layer++) {
        double sum[3] = { 0, 0, 0 };
        for (size_t t = 0; t < layer_bytes; t += 4)
            for (int c = 0; c < 3; c++) sum[c] += texels[layer_bytes * (size_t)layer + t + (size_t)c];
        for (int c = 0; c < 3; c++) means[layer][c] = (float)(sum[c] / (double)(layer_bytes / 4) / 255.0);
    }
}

static gfx_texture terrain_material_textures(float means[][3]) {
    TRACE_ZONE("terrain_material_textures");
    const size_t layer_bytes = (size_t)TERRAIN_TEXTURE_SIZE * TERRAIN_TEXTURE_SIZE * 4;
    uint8_t *texels = core_alloc(layer_bytes * TERRAIN_TEXTURE_LAYERS);
    for (int layer = 0; layer < TERRAIN_TEXTURE_LAYERS; layer++)
        for (int y = 0; y < TERRAIN_TEXTURE_SIZE; y++)
            for (int x = 0; x < TERRAIN_TEXTURE_SIZE; x++)
                texture_material_texel(layer, (float)x / TERRAIN_TEXTURE_SIZE, (float)y / TERRAIN_TEXTURE_SIZE,
                                       texels + layer_bytes * (size_t)layer + ((size_t)y * TERRAIN_TEXTURE_SIZE + (size_t)x) * 4);
    gfx_texture texture = gfx_texture_create(&(gfx_texture_desc){
        .width = TERRAIN_TEXTURE_SIZE, .height = TERRAIN_TEXTURE_SIZE, .layers = TERRAIN_TEXTURE_LAYERS,
        .data = texels, .mipmaps = true });
    terrain_material_means(texels, layer_bytes, means);
    core_free(texels, layer_bytes * TERRAIN_TEXTURE_LAYERS);
    return texture;
}

/* ---- renderer ---- */

terrain_renderer *terrain_renderer_create(gfx_context *gfx, const terrain_renderer_desc *desc) {
    gfx_program terrain = gfx_program_load(gfx, "terrain.vert", "terrain.frag");
    gfx_program sky = gfx_program_load(gfx, "sky.vert", "sky.frag");
    gfx_program clipmap = gfx_program_load(gfx, "clipmap.vert", "clipmap.frag");
    if (!terrain.id || !sky.id || !clipmap.id) return NULL;
    terrain_renderer *r = core_calloc(1, sizeof *r);
    *r = (terrain_renderer){ .gfx = gfx, .terrain = terrain, .sky = sky, .clipmap = clipmap,
                             .desc = desc ? *desc : (terrain_renderer_desc){ 0 } };
    if (r->desc.snow_height == 0) r->desc.snow_height = 120.0f;
    if (r->desc.fog_density == 0) r->desc.fog_density = 0.0025f;
    if (r->desc.cloud_cover == 0) r->desc.cloud_cover = 0.45f;
    if (r->desc.cloud_cover < 0) r->desc.cloud_cover = 0;
    r->materials = terrain_material_textures(r->material_means);
    if (!terrain_renderer_set_shadows(r, r->desc.shadows)) {
        terrain_renderer_destroy(r);
        return NULL;
    }
    glCreateVertexArrays(1, &r->empty.id);
    return r;
}

void terrain_renderer_set_clipmap(terrain_renderer *r, terrain_clipmap *clipmap) { r->far_terrain = clipmap; }

bool terrain_renderer_set_shadows(terrain_renderer *r, terrain_shadow_quality quality) {
    if (quality == TERRAIN_SHADOWS_DEFAULT) quality = TERRAIN_SHADOWS_LOW;
    terrain__shadows *shadows = terrain__shadows_create(r->gfx, quality);
    if (!shadows && quality != TERRAIN_SHADOWS_OFF) return false;
    terrain__shadows_destroy(r->shadows);
    r->shadows = shadows;
    r->desc.shadows = quality;
    r->shadows_drawn = false;
    return true;
}

void terrain_renderer_destroy(terrain_renderer *r) {
    if (!r) return;
    terrain__shadows_destroy(r->shadows);
    gfx_texture_destroy(&r->materials);
    gfx_vertex_array_destroy(&r->empty);
    core_free(r, sizeof *r);
}

terrain_gpu_mesh terrain_gpu_mesh_upload(const terrain_mesh *mesh) {
    TRACE_ZONE("terrain_gpu_mesh_upload");
    static uint64_t uploads;                  /* main thread only, as every GL call */
    terrain_gpu_mesh gpu = { .index_count = mesh->index_count, .serial = ++uploads };
    for (int a = 0; a < 3; a++) {
        gpu.origin[a] = mesh->origin[a];
        gpu.bounds_min[a] = mesh->bounds_min[a];
        gpu.bounds_max[a] = mesh->bounds_max[a];
    }
    if (mesh->index_count == 0) return gpu;
    gfx_buffer vertices = gfx_buffer_create(&(gfx_buffer_desc){
        .size = mesh->vertex_count * sizeof(terrain_vertex), .data = mesh->vertices });
    gfx_buffer indices = gfx_buffer_create(&(gfx_buffer_desc){
        .size = mesh->index_count * sizeof(uint32_t), .data = mesh->indices });
    gfx_vertex_array array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = vertices, .vertex_stride = sizeof(terrain_vertex), .indices = indices,
        .attributes = { { .components = 3, .offset = offsetof(terrain_vertex, position) },
                        { .components = 3, .offset = offsetof(terrain_vertex, normal) },
                        { .components = 4, .type = GL_UNSIGNED_BYTE, .normalized = true,
                          .offset = offsetof(terrain_vertex, weights) } } });
    gpu.vertex_buffer = vertices.id;
    gpu.index_buffer = indices.id;
    gpu.vertex_array = array.id;
    return gpu;
}

void terrain_gpu_mesh_destroy(terrain_gpu_mesh *mesh) {
    gfx_vertex_array_destroy(&(gfx_vertex_array){ mesh->vertex_array });
    gfx_buffer_destroy(&(gfx_buffer){ mesh->vertex_buffer, 0 });
    gfx_buffer_destroy(&(gfx_buffer){ mesh->index_buffer, 0 });
    *mesh = (terrain_gpu_mesh){ 0 };
}

/* View-projection with the eye at the origin: translation is applied per mesh, in doubles. */
static void terrain_view_projection(const terrain_view *view, mat4 out) {
    float cos_pitch = cosf(view->pitch);
    vec3 eye = { 0, 0, 0 }, up = { 0, 1, 0 };
    vec3 forward = { sinf(view->yaw) * cos_pitch, sinf(view->pitch), -cosf(view->yaw) * cos_pitch };
    mat4 look, projection;
    glm_lookat(eye, forward, up, look);
    float far_distance = view->far_distance > 0 ? view->far_distance : 4000.0f;
    glm_perspective(view->fov_y > 0 ? view->fov_y : glm_rad(60.0f), view->aspect > 0 ? view->aspect : 16.0f / 9.0f,
                    0.1f, far_distance, projection);
    glm_mat4_mul(projection, look, out);
}

void terrain_view_matrix(const terrain_view *view, float out[16]) {
    mat4 m;
    terrain_view_projection(view, m);
    memcpy(out, m, sizeof m);
}

void terrain_view_sun(const terrain_view *view, float out[3]) {
    vec3 sun = { view->sun_direction[0], view->sun_direction[1], view->sun_direction[2] };
    if (glm_vec3_norm(sun) == 0) glm_vec3_copy((vec3){ -0.55f, 0.55f, -0.35f }, sun);
    glm_vec3_normalize(sun);
    memcpy(out, sun, sizeof sun);
}

/* Gribb and Hartmann: the planes are sums and differences of the clip matrix's rows. */
terrain_frustum terrain_frustum_from_view(const terrain_view *view) {
    mat4 m;
    terrain_view_projection(view, m);
    terrain_frustum f = { .camera = { view->camera[0], view->camera[1], view->camera[2] } };
    for (int p = 0; p < 6; p++) {
        int row = p / 2;
        float sign = (p % 2) ? -1.0f : 1.0f;
        float length = 0;
        for (int c = 0; c < 4; c++) f.planes[p][c] = m[c][3] + sign * m[c][row];   /* cglm: m[column][row] */
        for (int c = 0; c < 3; c++) length += f.planes[p][c] * f.planes[p][c];
        length = sqrtf(length);
        for (int c = 0; c < 4; c++) f.planes[p][c] /= length;
    }
    return f;
}

bool terrain_frustum_sees(const terrain_frustum *f, const double origin[3], const float bounds_min[3],
                          const float bounds_max[3]) {
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        float offset = (float)(origin[a] - f->camera[a]);
        lo[a] = offset + bounds_min[a];
        hi[a] = offset + bounds_max[a];
    }
    for (int p = 0; p < 6; p++) {
        const float *plane = f->planes[p];
        /* The box corner furthest along the plane's normal: if even it is outside, all are. */
        float x = plane[0] >= 0 ? hi[0] : lo[0], y = plane[1] >= 0 ? hi[1] : lo[1], z = plane[2] >= 0 ? hi[2] : lo[2];
        if (plane[0] * x + plane[1] * y + plane[2] * z + plane[3] < 0) return false;
    }
    return true;
}

static double terrain_wrap(double value, double period) { return value - floor(value / period) * period; }

/* The far terrain after the meshes, so that the depth test drops its pit under them early, and
 * before the sky, which fills only what nothing covered. */
static void terrain_draw_clipmap(terrain_renderer *r, const terrain_view *view, mat4 view_projection) {
    gfx_context *gfx = r->gfx;
    float texture_offset[3];
    for (int a = 0; a < 3; a++) texture_offset[a] = (float)terrain_wrap(view->camera[a], TERRAIN_TEXTURE_METRES);
    gfx_program_use(gfx, r->clipmap);
    gfx_uniform_mat4(gfx, r->clipmap, "u_view_projection", (const float *)view_projection);
    gfx_uniform_float(gfx, r->clipmap, "u_texture_scale", (float)(1.0 / TERRAIN_TEXTURE_METRES));
    gfx_uniform_vec3(gfx, r->clipmap, "u_texture_offset", texture_offset);
    gfx_uniform_float(gfx, r->clipmap, "u_sea_level", r->desc.sea_level);
    gfx_uniform_float(gfx, r->clipmap, "u_snow_height", r->desc.snow_height);
    gfx_uniform_int(gfx, r->clipmap, "u_materials", 0);
    gfx_uniform_vec3(gfx, r->clipmap, "u_bedrock_mean", r->material_means[0]);
    gfx_uniform_vec3(gfx, r->clipmap, "u_sand_mean", r->material_means[1]);
    gfx_texture_bind(r->materials, 0);
    terrain__shadows_bind(r->shadows, gfx, r->clipmap.id, TERRAIN_SHADOW_UNIT);
    terrain__clipmap_draw(r->far_terrain, gfx, r->clipmap.id, view);
}

void terrain_renderer_draw_shadows(terrain_renderer *r, const terrain_view *view, const terrain_gpu_mesh *casters,
                                   int caster_count) {
    if (!r->shadows) return;
    vec3 sun;
    terrain_view_sun(view, sun);
    terrain__shadows_render(r->shadows, view, sun, casters, caster_count);
    r->shadows_drawn = true;
}

void terrain_renderer_draw(terrain_renderer *r, const terrain_view *view, const terrain_gpu_mesh *meshes,
                           int mesh_count) {
    TRACE_ZONE("terrain_renderer_draw");
    gfx_context *gfx = r->gfx;
    if (!r->shadows_drawn) terrain_renderer_draw_shadows(r, view, meshes, mesh_count);
    r->shadows_drawn = false;
    mat4 view_projection, inverse;
    terrain_view_projection(view, view_projection);
    glm_mat4_inv(view_projection, inverse);
    vec3 sun;
    terrain_view_sun(view, sun);
    const float zero[3] = { 0, 0, 0 };

    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "terrain", .clear_depth = true });
    gfx_program programs[3] = { r->terrain, r->sky, r->clipmap };
    for (int p = 0; p < 3; p++) {
        gfx_uniform_vec3(gfx, programs[p], "u_sun_direction", sun);
        gfx_uniform_vec3(gfx, programs[p], "u_camera_position", zero);
        gfx_uniform_float(gfx, programs[p], "u_fog_density", r->desc.fog_density);
    }
    gfx_program_use(gfx, r->terrain);
    gfx_uniform_mat4(gfx, r->terrain, "u_view_projection", (const float *)view_projection);
    gfx_uniform_float(gfx, r->terrain, "u_texture_scale", (float)(1.0 / TERRAIN_TEXTURE_METRES));
    gfx_uniform_float(gfx, r->terrain, "u_sea_level", r->desc.sea_level);
    gfx_uniform_float(gfx, r->terrain, "u_snow_height", r->desc.snow_height);
    gfx_uniform_int(gfx, r->terrain, "u_materials", 0);
    gfx_texture_bind(r->materials, 0);
    terrain__shadows_bind(r->shadows, gfx, r->terrain.id, TERRAIN_SHADOW_UNIT);
    for (int i = 0; i < mesh_count; i++) {
        const terrain_gpu_mesh *m = &meshes[i];
        if (m->index_count == 0) continue;
        /* Both subtractions in double: small floats reach the GPU wherever the camera is. */
        float offset[3], texture_offset[3];
        for (int a = 0; a < 3; a++) {
            offset[a] = (float)(m->origin[a] - view->camera[a]);
            texture_offset[a] = (float)terrain_wrap(m->origin[a], TERRAIN_TEXTURE_METRES);
        }
        gfx_uniform_vec3(gfx, r->terrain, "u_offset", offset);
        gfx_uniform_vec3(gfx, r->terrain, "u_texture_offset", texture_offset);
        gfx_uniform_float(gfx, r->terrain, "u_mesh_y", (float)m->origin[1]);
        gfx_draw(&(gfx_draw_desc){ .vertex_array = { m->vertex_array }, .count = m->index_count,
                                   .index_type = GFX_INDEX_U32 });
    }
    if (r->far_terrain) terrain_draw_clipmap(r, view, view_projection);
    gfx_program_use(gfx, r->sky);
    gfx_uniform_mat4(gfx, r->sky, "u_inverse_view_projection", (const float *)inverse);
    gfx_uniform_float(gfx, r->sky, "u_cloud_cover", r->desc.cloud_cover);
    gfx_uniform_float(gfx, r->sky, "u_time", view->time);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = r->empty, .count = 3 });
    gfx_pass_end(gfx);
}
