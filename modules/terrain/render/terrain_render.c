/* terrain_render.c — drawing terrain meshes: triplanar materials (000 §6) with normal maps, a
 * detail layer near the camera and macro variation (textures made in terrain_textures.c), height
 * and slope tint (002 §4.1), camera-relative transforms. Main thread only. */
#include "terrain/render/terrain_render.h"
#include "terrain/render/terrain_render_internal.h"

#include "core/core.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <cglm/cglm.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

/* Texture coordinates take mesh origins modulo the longest texture period (the macro layer's),
 * a multiple of all the others, so every layer lines up across meshes. */
#define TERRAIN_TEXTURE_PERIOD ((double)TERRAIN__MACRO_METRES)
#define TERRAIN_SHADOW_UNIT 3             /* the shadow map's texture unit (materials 0, clipmap 1, detail 2) */

struct terrain_renderer {
    gfx_context *gfx;
    gfx_program terrain, sky, clipmap;
    gfx_texture materials, detail;        /* terrain_textures.c */
    gfx_vertex_array empty;
    terrain_renderer_desc desc;
    terrain_clipmap *far_terrain;         /* not owned; NULL = none */
    float material_means[TERRAIN__MATERIAL_LAYERS][3];
    float material_tints[TERRAIN__MATERIAL_LAYERS][3];
    double texture_ms;                    /* how long the textures took to make */
    terrain__shadows *shadows;            /* NULL with shadows off */
    bool shadows_drawn;                   /* terrain_renderer_draw_shadows ran for the next draw */
    bool water_drawn;                     /* terrain_water draws the sea: the far terrain leaves
                                             its own tint of the sea out */
};

/* ---- procedural material textures ---- */

static void terrain_material_textures(terrain_renderer *r) {
    TRACE_ZONE("terrain_material_textures");
    uint64_t start = core_time_ns();
    terrain__material_texels texels;
    terrain__material_texels_make(&texels);
    r->materials = gfx_texture_create(&(gfx_texture_desc){
        .width = TERRAIN__BASE_SIZE, .height = TERRAIN__BASE_SIZE, .layers = TERRAIN__MATERIAL_LAYERS,
        .data = texels.base, .mipmaps = true });
    r->detail = gfx_texture_create(&(gfx_texture_desc){
        .width = TERRAIN__DETAIL_SIZE, .height = TERRAIN__DETAIL_SIZE, .layers = TERRAIN__DETAIL_LAYERS,
        .data = texels.detail, .mipmaps = true });
    /* The detail within one mip level (bilinear, not trilinear): half its fetches on llvmpipe,
     * and a step between levels is hidden where it shows at all, the detail fading out. */
    glTextureParameteri(gfx_texture_gl(r->detail), GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    memcpy(r->material_means, texels.means, sizeof r->material_means);
    memcpy(r->material_tints, texels.tints, sizeof r->material_tints);
    terrain__material_texels_free(&texels);
    r->texture_ms = (double)(core_time_ns() - start) * 1e-6;
}

/* The uniforms both terrain programs read for their materials. The detail array goes on unit 2:
 * the clipmap keeps its heights on unit 1 (terrain_clipmap.c). */
static void terrain_material_uniforms(terrain_renderer *r, gfx_program program) {
    static const char *const tints[TERRAIN__MATERIAL_LAYERS] = {
        "u_material_tints[0]", "u_material_tints[1]", "u_material_tints[2]", "u_material_tints[3]" };
    static const char *const mean_shades[TERRAIN__MATERIAL_LAYERS] = {
        "u_mean_shades[0]", "u_mean_shades[1]", "u_mean_shades[2]", "u_mean_shades[3]" };
    gfx_context *gfx = r->gfx;
    for (int layer = 0; layer < TERRAIN__MATERIAL_LAYERS; layer++) {
        gfx_uniform_vec3(gfx, program, tints[layer], r->material_tints[layer]);
        gfx_uniform_float(gfx, program, mean_shades[layer], r->material_means[layer][0] / r->material_tints[layer][0]);
    }
    gfx_uniform_float(gfx, program, "u_texture_scale", 1.0f / TERRAIN__BASE_METRES);
    gfx_uniform_float(gfx, program, "u_texture_scale2", 1.0f / TERRAIN__BASE2_METRES);
    gfx_uniform_float(gfx, program, "u_macro_scale", 1.0f / TERRAIN__MACRO_METRES);
    /* The low quality (no detail) drops the 25 m sample too: the two extra fetches that cost. */
    gfx_uniform_float(gfx, program, "u_scale_blend", r->desc.detail_distance > 0 ? 1.0f : 0.0f);
    gfx_uniform_int(gfx, program, "u_materials", 0);
    gfx_uniform_int(gfx, program, "u_detail", 2);
    gfx_texture_bind(r->materials, 0);
    gfx_texture_bind(r->detail, 2);
}

double terrain_renderer_texture_ms(const terrain_renderer *r) { return r->texture_ms; }

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
    if (r->desc.detail_distance == 0) r->desc.detail_distance = 16.0f;
    if (r->desc.detail_distance < 0) r->desc.detail_distance = 0;
    terrain_material_textures(r);
    if (!terrain_renderer_set_shadows(r, r->desc.shadows)) {
        terrain_renderer_destroy(r);
        return NULL;
    }
    r->empty = gfx_vertex_array_create(&(gfx_vertex_array_desc){ 0 });
    return r;
}

void terrain_renderer_set_clipmap(terrain_renderer *r, terrain_clipmap *clipmap) { r->far_terrain = clipmap; }

bool terrain__renderer_has_ground(const terrain_renderer *r) {
    return r->far_terrain && terrain__clipmap_ground_levels(r->far_terrain) > 0;
}

int terrain__renderer_bind_ground(terrain_renderer *r, uint32_t program, const double camera[3], int unit) {
    if (r->far_terrain) return terrain__clipmap_bind_ground(r->far_terrain, r->gfx, program, camera, unit);
    gfx_uniform_int(r->gfx, (gfx_program){ program }, "u_ground_levels", 0);
    gfx_uniform_int(r->gfx, (gfx_program){ program }, "u_ground_heights", unit);
    return 0;
}

void terrain_renderer_set_occlusion(terrain_renderer *r, bool on) { r->desc.no_occlusion = !on; }

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
    gfx_texture_destroy(&r->detail);
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
    gpu.part_count = mesh->part_count;
    memcpy(gpu.parts, mesh->parts, mesh->part_count * sizeof *mesh->parts);
    if (mesh->index_count == 0) return gpu;
    gpu.vertex_buffer = gfx_buffer_create(&(gfx_buffer_desc){
        .size = mesh->vertex_count * sizeof(terrain_vertex), .data = mesh->vertices });
    gpu.index_buffer = gfx_buffer_create(&(gfx_buffer_desc){
        .size = mesh->index_count * sizeof(uint32_t), .data = mesh->indices });
    gpu.vertex_array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = gpu.vertex_buffer, .vertex_stride = sizeof(terrain_vertex), .indices = gpu.index_buffer,
        .attributes = { { .components = 3, .offset = offsetof(terrain_vertex, position) },
                        { .components = 3, .offset = offsetof(terrain_vertex, normal) },
                        { .components = 4, .type = GL_UNSIGNED_BYTE, .normalized = true,
                          .offset = offsetof(terrain_vertex, weights) },
                        { .components = 1, .type = GL_UNSIGNED_BYTE, .normalized = true,
                          .offset = offsetof(terrain_vertex, occlusion) } } });
    return gpu;
}

void terrain_gpu_mesh_destroy(terrain_gpu_mesh *mesh) {
    gfx_vertex_array_destroy(&mesh->vertex_array);
    gfx_buffer_destroy(&mesh->vertex_buffer);
    gfx_buffer_destroy(&mesh->index_buffer);
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
static void terrain_draw_clipmap(terrain_renderer *r, const terrain_view *view, mat4 view_projection,
                                 const terrain__shadows *shadows) {
    gfx_context *gfx = r->gfx;
    float texture_offset[3];
    for (int a = 0; a < 3; a++) texture_offset[a] = (float)terrain_wrap(view->camera[a], TERRAIN_TEXTURE_PERIOD);
    gfx_program_use(gfx, r->clipmap);
    gfx_uniform_mat4(gfx, r->clipmap, "u_view_projection", (const float *)view_projection);
    terrain_material_uniforms(r, r->clipmap);
    gfx_uniform_vec3(gfx, r->clipmap, "u_texture_offset", texture_offset);
    gfx_uniform_float(gfx, r->clipmap, "u_sea_level", r->desc.sea_level);
    gfx_uniform_float(gfx, r->clipmap, "u_snow_height", r->desc.snow_height);
    gfx_uniform_vec3(gfx, r->clipmap, "u_bedrock_mean", r->material_means[0]);
    gfx_uniform_vec3(gfx, r->clipmap, "u_sand_mean", r->material_means[1]);
    gfx_uniform_float(gfx, r->clipmap, "u_water_drawn", r->water_drawn ? 1.0f : 0.0f);
    terrain__shadows_bind(shadows, gfx, r->clipmap.id, TERRAIN_SHADOW_UNIT);
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

/* What the terrain's, the clipmap's and the sky's programs share. */
static void terrain_scene_uniforms(terrain_renderer *r, gfx_program program, const vec3 sun, const float clip_plane[4]) {
    const float zero[3] = { 0, 0, 0 };
    gfx_uniform_vec3(r->gfx, program, "u_sun_direction", sun);
    gfx_uniform_vec3(r->gfx, program, "u_camera_position", zero);
    gfx_uniform_float(r->gfx, program, "u_fog_density", r->desc.fog_density);
    gfx_uniform_vec4(r->gfx, program, "u_clip_plane", clip_plane);
}

static void terrain_draw_sky(terrain_renderer *r, const terrain_view *view, mat4 inverse);

/* Indices first … first + count of the mesh, if any; returns their triangles. */
static uint64_t terrain_draw_run(const terrain_gpu_mesh *m, uint32_t first, uint32_t count) {
    if (count == 0) return 0;
    gfx_draw(&(gfx_draw_desc){ .vertex_array = m->vertex_array, .first = first, .count = count,
                               .index_type = GFX_INDEX_U32 });
    return count / 3;
}

uint64_t terrain__draw_parts(const terrain_gpu_mesh *m, terrain__box_test test, const void *user) {
    if (m->part_count == 0) return terrain_draw_run(m, 0, m->index_count);
    uint32_t first = 0, count = 0;   /* the run of parts in view so far */
    uint64_t drawn = 0;
    for (uint32_t p = 0; p < m->part_count; p++) {
        const terrain_mesh_part *part = &m->parts[p];
        if (!test(user, m->origin, part->bounds_min, part->bounds_max)) {
            drawn += terrain_draw_run(m, first, count);
            count = 0;
            continue;
        }
        if (count == 0) first = part->first_index;
        count += part->index_count;
    }
    return drawn + terrain_draw_run(m, first, count);
}

static bool terrain_frustum_test(const void *frustum, const double origin[3], const float lo[3], const float hi[3]) {
    return terrain_frustum_sees(frustum, origin, lo, hi);
}

/* The meshes, the far terrain and (`with_sky`) the sky into the bound framebuffer with `view`,
 * shadows from `shadows` (NULL: none), keeping only what lies on the positive side of the
 * camera-relative `clip_plane` (all zero: everything; the sky is never clipped). Returns the
 * meshes' triangles drawn. */
static uint64_t terrain_draw_scene(terrain_renderer *r, const terrain_view *view, const terrain_gpu_mesh *meshes,
                               int mesh_count, const float clip_plane[4], const terrain__shadows *shadows,
                               bool with_sky) {
    gfx_context *gfx = r->gfx;
    mat4 view_projection, inverse;
    terrain_view_projection(view, view_projection);
    glm_mat4_inv(view_projection, inverse);
    vec3 sun;
    terrain_view_sun(view, sun);
    bool clipped = clip_plane[0] != 0 || clip_plane[1] != 0 || clip_plane[2] != 0 || clip_plane[3] != 0;
    if (clipped) glEnable(GL_CLIP_DISTANCE0);
    gfx_program programs[3] = { r->terrain, r->sky, r->clipmap };
    for (int p = 0; p < 3; p++) terrain_scene_uniforms(r, programs[p], sun, clip_plane);
    terrain_frustum frustum = terrain_frustum_from_view(view);
    uint64_t triangles = 0;
    gfx_program_use(gfx, r->terrain);
    gfx_uniform_mat4(gfx, r->terrain, "u_view_projection", (const float *)view_projection);
    gfx_uniform_float(gfx, r->terrain, "u_sea_level", r->desc.sea_level);
    gfx_uniform_float(gfx, r->terrain, "u_snow_height", r->desc.snow_height);
    gfx_uniform_float(gfx, r->terrain, "u_detail_scale", 1.0f / TERRAIN__DETAIL_METRES);
    gfx_uniform_float(gfx, r->terrain, "u_detail_distance", r->desc.detail_distance);
    terrain_material_uniforms(r, r->terrain);
    gfx_uniform_float(gfx, r->terrain, "u_occlusion", r->desc.no_occlusion ? 0.0f : 1.0f);
    terrain__shadows_bind(shadows, gfx, r->terrain.id, TERRAIN_SHADOW_UNIT);
    for (int i = 0; i < mesh_count; i++) {
        const terrain_gpu_mesh *m = &meshes[i];
        if (m->index_count == 0) continue;
        /* Both subtractions in double: small floats reach the GPU wherever the camera is. */
        float offset[3], texture_offset[3];
        for (int a = 0; a < 3; a++) {
            offset[a] = (float)(m->origin[a] - view->camera[a]);
            texture_offset[a] = (float)terrain_wrap(m->origin[a], TERRAIN_TEXTURE_PERIOD);
        }
        gfx_uniform_vec3(gfx, r->terrain, "u_offset", offset);
        gfx_uniform_vec3(gfx, r->terrain, "u_texture_offset", texture_offset);
        gfx_uniform_float(gfx, r->terrain, "u_mesh_y", (float)m->origin[1]);
        triangles += terrain__draw_parts(m, terrain_frustum_test, &frustum);
    }
    if (r->far_terrain) terrain_draw_clipmap(r, view, view_projection, shadows);
    if (clipped) glDisable(GL_CLIP_DISTANCE0);     /* sky.vert writes no clip distance */
    if (with_sky) terrain_draw_sky(r, view, inverse);
    return triangles;
}

/* The sky behind what is drawn: a full-screen triangle at the far plane (the scene's uniforms
 * already set on its program). */
static void terrain_draw_sky(terrain_renderer *r, const terrain_view *view, mat4 inverse) {
    gfx_context *gfx = r->gfx;
    gfx_program_use(gfx, r->sky);
    gfx_uniform_mat4(gfx, r->sky, "u_inverse_view_projection", (const float *)inverse);
    gfx_uniform_float(gfx, r->sky, "u_cloud_cover", r->desc.cloud_cover);
    gfx_uniform_float(gfx, r->sky, "u_time", view->time);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = r->empty, .count = 3 });
}

void terrain_renderer_draw_sky(terrain_renderer *r, const terrain_view *view) {
    TRACE_ZONE("terrain_renderer_draw_sky");
    mat4 view_projection, inverse;
    terrain_view_projection(view, view_projection);
    glm_mat4_inv(view_projection, inverse);
    vec3 sun;
    terrain_view_sun(view, sun);
    gfx_pass_begin(r->gfx, &(gfx_pass_desc){ .name = "sky" });
    gfx_program_use(r->gfx, r->sky);
    terrain_scene_uniforms(r, r->sky, sun, (const float[4]){ 0, 0, 0, 0 });
    terrain_draw_sky(r, view, inverse);
    gfx_pass_end(r->gfx);
}

void terrain_renderer_draw(terrain_renderer *r, const terrain_view *view, const terrain_gpu_mesh *meshes,
                           int mesh_count) {
    TRACE_ZONE("terrain_renderer_draw");
    if (!r->shadows_drawn) terrain_renderer_draw_shadows(r, view, meshes, mesh_count);
    r->shadows_drawn = false;
    gfx_pass_begin(r->gfx, &(gfx_pass_desc){ .name = "terrain", .clear_depth = true });
    uint64_t triangles = terrain_draw_scene(r, view, meshes, mesh_count, (const float[4]){ 0, 0, 0, 0 }, r->shadows,
                                            !r->desc.sky_apart);
    gfx_pass_end(r->gfx);
    trace_counter("terrain.triangles_drawn", (double)triangles);
}

void terrain__renderer_draw_clipped(terrain_renderer *r, const terrain_view *view, const terrain_gpu_mesh *meshes,
                                    int mesh_count, const float clip_plane[4]) {
    TRACE_ZONE("terrain_renderer_draw_clipped");
    terrain_draw_scene(r, view, meshes, mesh_count, clip_plane, NULL, true);
}

void terrain__renderer_set_water_drawn(terrain_renderer *r, bool drawn) { r->water_drawn = drawn; }

float terrain__renderer_fog_density(const terrain_renderer *r) { return r->desc.fog_density; }
terrain__shadows *terrain__renderer_shadows(const terrain_renderer *r) { return r->shadows; }
float terrain__renderer_cloud_cover(const terrain_renderer *r) { return r->desc.cloud_cover; }
