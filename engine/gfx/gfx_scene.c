/* gfx_scene.c — the reference scene: a lit sphere on a ground grid under a sky.
 *
 * It exists to check a platform end to end (context, shaders, buffers, depth, timing): the render
 * tests look at its pixels, the benchmark times its frames, and tools/play shows it until the world
 * exists. Sizes and colours are chosen so a test can reason about the image: the sphere (radius 1,
 * centre (0, 1, 0)) fills the middle, the sun comes from the left, the sky fills the top. */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <cglm/cglm.h>
#include <math.h>

#define SCENE_SPHERE_RINGS 24
#define SCENE_SPHERE_SEGMENTS 48
#define SCENE_GROUND_HALF_SIZE 400.0f

typedef struct scene_vertex { float position[3], normal[3]; } scene_vertex;

typedef struct scene_mesh {
    gfx_buffer vertices, indices;
    gfx_vertex_array array;
    uint32_t index_count;
} scene_mesh;

struct gfx_scene {
    gfx_context *gfx;
    gfx_program lit, sky;
    scene_mesh sphere, ground;
    gfx_vertex_array empty;        /* the sky's triangle needs no vertex data */
};

static scene_mesh scene_mesh_upload(const scene_vertex *vertices, uint32_t vertex_count,
                                    const uint32_t *indices, uint32_t index_count) {
    scene_mesh mesh = { .index_count = index_count };
    mesh.vertices = gfx_buffer_create(&(gfx_buffer_desc){ .size = vertex_count * sizeof *vertices,
                                                          .data = vertices });
    mesh.indices = gfx_buffer_create(&(gfx_buffer_desc){ .size = index_count * sizeof *indices,
                                                         .data = indices });
    mesh.array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = mesh.vertices, .vertex_stride = sizeof(scene_vertex), .indices = mesh.indices,
        .attributes = { { .components = 3, .offset = 0 },
                        { .components = 3, .offset = offsetof(scene_vertex, normal) } } });
    return mesh;
}

static void scene_mesh_destroy(scene_mesh *mesh) {
    gfx_vertex_array_destroy(&mesh->array);
    gfx_buffer_destroy(&mesh->vertices);
    gfx_buffer_destroy(&mesh->indices);
}

/* A unit sphere of latitude rings; counter-clockwise seen from outside. */
static scene_mesh scene_sphere(void) {
    enum { VERTICES = (SCENE_SPHERE_RINGS + 1) * (SCENE_SPHERE_SEGMENTS + 1),
           INDICES = SCENE_SPHERE_RINGS * SCENE_SPHERE_SEGMENTS * 6 };
    scene_vertex *vertices = core_alloc(VERTICES * sizeof *vertices);
    uint32_t *indices = core_alloc(INDICES * sizeof *indices);
    uint32_t v = 0, i = 0;
    for (int ring = 0; ring <= SCENE_SPHERE_RINGS; ring++) {
        float polar = (float)M_PI * (float)ring / SCENE_SPHERE_RINGS;
        for (int segment = 0; segment <= SCENE_SPHERE_SEGMENTS; segment++) {
            float azimuth = 2.0f * (float)M_PI * (float)segment / SCENE_SPHERE_SEGMENTS;
            float n[3] = { sinf(polar) * cosf(azimuth), cosf(polar), -sinf(polar) * sinf(azimuth) };
            vertices[v++] = (scene_vertex){ { n[0], n[1], n[2] }, { n[0], n[1], n[2] } };
        }
    }
    const uint32_t row = SCENE_SPHERE_SEGMENTS + 1;
    for (uint32_t ring = 0; ring < SCENE_SPHERE_RINGS; ring++) {
        for (uint32_t segment = 0; segment < SCENE_SPHERE_SEGMENTS; segment++) {
            uint32_t a = ring * row + segment, b = a + row;
            uint32_t quad[6] = { a, b, a + 1, a + 1, b, b + 1 };
            for (int k = 0; k < 6; k++) indices[i++] = quad[k];
        }
    }
    scene_mesh mesh = scene_mesh_upload(vertices, v, indices, i);
    core_free(vertices, VERTICES * sizeof *vertices);
    core_free(indices, INDICES * sizeof *indices);
    return mesh;
}

static scene_mesh scene_ground(void) {
    const float s = SCENE_GROUND_HALF_SIZE;
    const scene_vertex vertices[4] = {
        { { -s, 0, -s }, { 0, 1, 0 } }, { { -s, 0, s }, { 0, 1, 0 } },
        { { s, 0, s }, { 0, 1, 0 } },   { { s, 0, -s }, { 0, 1, 0 } },
    };
    const uint32_t indices[6] = { 0, 1, 2, 0, 2, 3 };
    return scene_mesh_upload(vertices, 4, indices, 6);
}

gfx_scene *gfx_scene_create(gfx_context *gfx) {
    gfx_program lit = gfx_program_load(gfx, "scene.vert", "scene.frag");
    gfx_program sky = gfx_program_load(gfx, "sky.vert", "sky.frag");
    if (!lit.id || !sky.id) return NULL;
    gfx_scene *scene = core_calloc(1, sizeof *scene);
    *scene = (gfx_scene){ .gfx = gfx, .lit = lit, .sky = sky, .sphere = scene_sphere(),
                          .ground = scene_ground() };
    scene->empty = gfx_vertex_array_create(&(gfx_vertex_array_desc){ 0 });
    return scene;
}

void gfx_scene_destroy(gfx_scene *scene) {
    if (!scene) return;
    scene_mesh_destroy(&scene->sphere);
    scene_mesh_destroy(&scene->ground);
    gfx_vertex_array_destroy(&scene->empty);
    core_free(scene, sizeof *scene);
}

gfx_camera gfx_scene_default_camera(void) {
    /* At eye height 5 m in front of the sphere, looking at its centre. */
    return (gfx_camera){ .position = { 0.0f, 1.6f, 5.0f }, .yaw = 0.0f, .pitch = atanf(-0.6f / 5.0f) };
}

static void scene_view_projection(const gfx_camera *camera, float aspect, mat4 view_projection) {
    float cos_pitch = cosf(camera->pitch);
    vec3 forward = { sinf(camera->yaw) * cos_pitch, sinf(camera->pitch), -cosf(camera->yaw) * cos_pitch };
    vec3 eye = { camera->position[0], camera->position[1], camera->position[2] };
    vec3 target, up = { 0, 1, 0 };
    glm_vec3_add(eye, forward, target);
    mat4 view, projection;
    glm_lookat(eye, target, up, view);
    float fov = camera->fov_y > 0 ? camera->fov_y : glm_rad(60.0f);
    glm_perspective(fov, aspect, 0.1f, 2000.0f, projection);
    glm_mat4_mul(projection, view, view_projection);
}

void gfx_scene_draw(gfx_scene *scene, const gfx_camera *camera, double seconds) {
    TRACE_ZONE("gfx_scene_draw");
    gfx_context *gfx = scene->gfx;
    int width, height;
    gfx_size(gfx, &width, &height);
    mat4 view_projection, inverse, model;
    scene_view_projection(camera, (float)width / (float)height, view_projection);
    glm_mat4_inv(view_projection, inverse);
    /* The sun circles slowly so a running demo shows the lighting is live. */
    float sun_angle = 2.4f + 0.05f * (float)seconds;
    vec3 sun = { cosf(sun_angle), 0.75f, 0.35f * sinf(sun_angle) };
    glm_vec3_normalize(sun);

    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "scene", .clear_depth = true });
    gfx_program programs[2] = { scene->lit, scene->sky };
    for (int p = 0; p < 2; p++) {
        gfx_uniform_vec3(gfx, programs[p], "u_sun_direction", sun);
        gfx_uniform_vec3(gfx, programs[p], "u_camera_position", camera->position);
        gfx_uniform_float(gfx, programs[p], "u_fog_density", 0.012f);
    }
    gfx_program_use(gfx, scene->lit);
    gfx_uniform_mat4(gfx, scene->lit, "u_view_projection", (const float *)view_projection);

    glm_mat4_identity(model);
    gfx_uniform_mat4(gfx, scene->lit, "u_model", (const float *)model);
    gfx_uniform_vec3(gfx, scene->lit, "u_albedo", (const float[3]){ 0.55f, 0.55f, 0.5f });
    gfx_uniform_int(gfx, scene->lit, "u_grid", 1);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = scene->ground.array, .count = scene->ground.index_count,
                               .index_type = GFX_INDEX_U32 });

    glm_translate_make(model, (vec3){ 0.0f, 1.0f, 0.0f });
    gfx_uniform_mat4(gfx, scene->lit, "u_model", (const float *)model);
    gfx_uniform_vec3(gfx, scene->lit, "u_albedo", (const float[3]){ 0.85f, 0.25f, 0.12f });
    gfx_uniform_int(gfx, scene->lit, "u_grid", 0);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = scene->sphere.array, .count = scene->sphere.index_count,
                               .index_type = GFX_INDEX_U32 });

    /* Sky last, at the far plane: only pixels nothing else covered run its shader. */
    gfx_program_use(gfx, scene->sky);
    gfx_uniform_mat4(gfx, scene->sky, "u_inverse_view_projection", (const float *)inverse);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = scene->empty, .count = 3 });
    gfx_pass_end(gfx);
}
