/* terrain_water.c — drawing water surfaces: the sea out to the horizon and the lakes of the
 * WaterPlane components, over the opaque frame (002 §3.4, 004 §4.3). terrain.h's "drawing
 * water" says what each quality does; water.frag holds the optics. Main thread only. */
#include "terrain/ecs/terrain_ecs.h"
#include "terrain/ecs/terrain_ecs_internal.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <cglm/cglm.h>
#include <math.h>
#include <string.h>

#define WATER_MAP_SIZE 128                /* texels along each side of the dudv and normal maps */
/* The camera's x, z reach the shader modulo this: a multiple of every repeat water.frag uses
 * (normals 8 m and 20 m, dudv 12 m and 10 m), so the maps line up however far the camera goes. */
#define WATER_MAP_PERIOD 120.0
#define WATER_WAVES 12                    /* sines summed into each map */
#define WATER_UNDER_DENSITY 0.12f         /* per metre: the fog seen under water */
#define WATER_CLIP_MARGIN 0.05f           /* metres the passes' clip planes reach past the surface */
#define WATER_LAKE_ABOVE_SEA 0.05f        /* a WaterPlane this far above the sea is a lake */

/* Texture units of the surface program. */
enum { UNIT_SCENE_COLOR, UNIT_SCENE_DEPTH, UNIT_REFLECTION, UNIT_DUDV, UNIT_NORMALS, UNIT_GROUND };

struct terrain_water {
    terrain_water_desc desc;
    gfx_program surface, under, probe;
    gfx_texture dudv, normals;
    gfx_vertex_array empty;
    gfx_texture color_copy, depth_copy;   /* the opaque frame, copied each draw */
    int copy_width, copy_height;
    gfx_framebuffer reflection, refraction;   /* high: half the frame's size */
    ecs_component plane_component;
    ecs_query *planes;                    /* entities with a WaterPlane */
    terrain_gpu_mesh *meshes;             /* gathered for the high quality's passes */
    size_t mesh_capacity;
    /* Whether any water was seen: an occlusion query a frame, two in turn, read a frame later.
     * A frame after one whose water was all hidden (behind hills) only probes again, with a
     * depth-tested quad and no shading, and skips the copy of the frame, whose wait for the
     * frame's drawing (llvmpipe draws the frame when it is read) would cost the most. */
    GLuint queries[2];
    bool query_issued[2];
    int query_next;
    terrain_water_stats_info stats;
};

bool terrain_water_parse_quality(const char *text, terrain_water_quality *out) {
    static const char *const names[] = { "off", "low", "medium", "high" };
    for (int q = 0; q < 4; q++)
        if (text && strcmp(text, names[q]) == 0) {
            *out = (terrain_water_quality)(TERRAIN_WATER_OFF + q);
            return true;
        }
    return false;
}

const char *terrain_water_quality_name(terrain_water_quality quality) {
    switch (quality) {
    case TERRAIN_WATER_OFF: return "off";
    case TERRAIN_WATER_MEDIUM: return "medium";
    case TERRAIN_WATER_HIGH: return "high";
    default: return "low";
    }
}

/* ---- procedural maps ---------------------------------------------------------------------- */

/* A sum of sines whose wave vectors are whole numbers of cycles across the map, so it tiles;
 * hashed directions and phases, amplitudes falling as 1/frequency (a gentle chop). Returns the
 * height and its gradient in map units (one map = 1). */
static float water_waves(uint64_t seed, double u, double v, float gradient[2]) {
    float height = 0;
    gradient[0] = gradient[1] = 0;
    for (int j = 0; j < WATER_WAVES; j++) {
        uint64_t h = core_hash_u64(seed * 131 + (uint64_t)j);
        int frequency = 2 + j / 2;                               /* cycles across the map */
        double angle = (double)(h & 0xffff) / 65536.0 * 2.0 * M_PI;
        int kx = (int)lround(cos(angle) * frequency), kz = (int)lround(sin(angle) * frequency);
        if (kx == 0 && kz == 0) kx = 1;
        double phase = (double)((h >> 16) & 0xffff) / 65536.0 * 2.0 * M_PI;
        double amplitude = 1.0 / frequency;
        double argument = 2.0 * M_PI * (kx * u + kz * v) + phase;
        height += (float)(amplitude * sin(argument));
        gradient[0] += (float)(amplitude * 2.0 * M_PI * kx * cos(argument));
        gradient[1] += (float)(amplitude * 2.0 * M_PI * kz * cos(argument));
    }
    return height;
}

static uint8_t water_unorm(float value) {        /* [−1, 1] → 0.5 + 0.5·value in bytes */
    float v = 0.5f + 0.5f * fmaxf(-1.0f, fminf(1.0f, value));
    return (uint8_t)lroundf(v * 255.0f);
}

/* The normal map (RG: the normal's x and z of the waves' surface) and the dudv map (RG: two
 * independent wave fields, each scaled into [−1, 1]), both tileable, made once at start-up as
 * terrain_textures.c makes the materials'. */
static void water_maps(terrain_water *w) {
    size_t bytes = (size_t)WATER_MAP_SIZE * WATER_MAP_SIZE * 4;
    uint8_t *normals = core_alloc(bytes), *dudv = core_alloc(bytes);
    /* Σ 1/f over the waves bounds each field. The slopes: a gentle chop, typically a tenth (6°)
     * and at the steepest about a quarter; the shader scales them again by depth and distance. */
    float bound = 0;
    for (int j = 0; j < WATER_WAVES; j++) bound += 1.0f / (float)(2 + j / 2);
    float slope_scale = 0.25f / (bound * 2.0f * (float)M_PI * 2.0f);
    for (int y = 0; y < WATER_MAP_SIZE; y++)
        for (int x = 0; x < WATER_MAP_SIZE; x++) {
            double u = (double)x / WATER_MAP_SIZE, v = (double)y / WATER_MAP_SIZE;
            float g[2], unused[2];
            water_waves(1, u, v, g);
            float nx = -g[0] * slope_scale, nz = -g[1] * slope_scale, ny = 1.0f;
            float length = sqrtf(nx * nx + ny * ny + nz * nz);
            uint8_t *n = normals + ((size_t)y * WATER_MAP_SIZE + (size_t)x) * 4;
            n[0] = water_unorm(nx / length), n[1] = water_unorm(nz / length);
            n[2] = water_unorm(ny / length), n[3] = 255;
            uint8_t *d = dudv + ((size_t)y * WATER_MAP_SIZE + (size_t)x) * 4;
            d[0] = water_unorm(water_waves(2, u, v, unused) / bound);
            d[1] = water_unorm(water_waves(3, u, v, unused) / bound);
            d[2] = 128, d[3] = 255;
        }
    w->normals = gfx_texture_create(&(gfx_texture_desc){ .width = WATER_MAP_SIZE, .height = WATER_MAP_SIZE,
                                                        .data = normals, .mipmaps = true });
    w->dudv = gfx_texture_create(&(gfx_texture_desc){ .width = WATER_MAP_SIZE, .height = WATER_MAP_SIZE,
                                                     .data = dudv, .mipmaps = true });
    core_free(normals, bytes);
    core_free(dudv, bytes);
}

/* ---- life ---------------------------------------------------------------------------------- */

static bool water_quality_valid(terrain_water_quality quality) { return (unsigned)quality <= TERRAIN_WATER_HIGH; }

terrain_water *terrain_water_create(const terrain_water_desc *desc) {
    if (!desc || !desc->gfx || !desc->world) {
        core_log_error("terrain", "terrain_water_create: gfx and world are required");
        return NULL;
    }
    if (!water_quality_valid(desc->quality)) {
        core_log_error("terrain", "terrain_water_create: unknown quality %d", (int)desc->quality);
        return NULL;
    }
    gfx_program surface = gfx_program_load(desc->gfx, "water.vert", "water.frag");
    gfx_program under = gfx_program_load(desc->gfx, "sky.vert", "water_under.frag");
    gfx_program probe = gfx_program_load(desc->gfx, "water.vert", "water_probe.frag");
    if (!surface.id || !under.id || !probe.id) return NULL;
    terrain_water *w = core_calloc(1, sizeof *w);
    *w = (terrain_water){ .desc = *desc, .surface = surface, .under = under, .probe = probe };
    glCreateQueries(GL_ANY_SAMPLES_PASSED, 2, w->queries);
    if (w->desc.quality == TERRAIN_WATER_DEFAULT) w->desc.quality = TERRAIN_WATER_LOW;
    water_maps(w);
    w->empty = gfx_vertex_array_create(&(gfx_vertex_array_desc){ 0 });
    if (desc->ecs) {
        /* Registering by the same name again returns the same component: whichever of this and
         * the mesh phase comes first makes it. */
        w->plane_component = ECS_COMPONENT(desc->ecs, WaterPlane);
        w->planes = ecs_query_create(desc->ecs, &(ecs_query_desc){ .with = { w->plane_component } });
    }
    return w;
}

static void water_free_copies(terrain_water *w) {
    gfx_texture_destroy(&w->color_copy);
    gfx_texture_destroy(&w->depth_copy);
    w->copy_width = w->copy_height = 0;
}

static void water_free_passes(terrain_water *w) {
    gfx_framebuffer_destroy(&w->reflection);
    gfx_framebuffer_destroy(&w->refraction);
}

void terrain_water_destroy(terrain_water *w) {
    if (!w) return;
    water_free_copies(w);
    water_free_passes(w);
    gfx_texture_destroy(&w->dudv);
    gfx_texture_destroy(&w->normals);
    gfx_vertex_array_destroy(&w->empty);
    glDeleteQueries(2, w->queries);
    if (w->planes) ecs_query_destroy(w->desc.ecs, w->planes);
    core_free(w->meshes, w->mesh_capacity * sizeof *w->meshes);
    core_free(w, sizeof *w);
}

bool terrain_water_set_quality(terrain_water *w, terrain_water_quality quality) {
    if (!water_quality_valid(quality)) {
        core_log_error("terrain", "terrain_water_set_quality: unknown quality %d", (int)quality);
        return false;
    }
    if (quality == TERRAIN_WATER_DEFAULT) quality = TERRAIN_WATER_LOW;
    if (quality != TERRAIN_WATER_HIGH) water_free_passes(w);
    if (quality == TERRAIN_WATER_OFF) water_free_copies(w);
    w->desc.quality = quality;
    return true;
}

terrain_water_stats_info terrain_water_stats(const terrain_water *w) { return w->stats; }

/* ---- targets ------------------------------------------------------------------------------- */

static gfx_texture water_copy_texture(gfx_format format, int width, int height, bool nearest) {
    return gfx_texture_create(&(gfx_texture_desc){ .width = width, .height = height, .format = format,
                                                   .nearest = nearest, .clamp = true });
}

/* The copies of the opaque frame, (re)made at its size. The depth copy is 24-bit like the
 * default framebuffer's depth (glCopyTexSubImage2D reads it into any depth format; the same
 * bits keep it exact). */
static void water_copy_frame(terrain_water *w, int width, int height) {
    if (w->copy_width != width || w->copy_height != height) {
        water_free_copies(w);
        w->color_copy = water_copy_texture(GFX_FORMAT_RGBA8, width, height, false);
        w->depth_copy = water_copy_texture(GFX_FORMAT_DEPTH24, width, height, true);
        w->copy_width = width, w->copy_height = height;
    }
    glCopyTextureSubImage2D(gfx_texture_gl(w->color_copy), 0, 0, 0, 0, 0, width, height);
    glCopyTextureSubImage2D(gfx_texture_gl(w->depth_copy), 0, 0, 0, 0, 0, width, height);
}

/* High: the reflection and refraction targets at half the frame's size; false (logged) when
 * the driver refuses them. */
static bool water_pass_targets(terrain_water *w, int width, int height) {
    int half_width = width / 2 > 1 ? width / 2 : 1, half_height = height / 2 > 1 ? height / 2 : 1;
    if (w->reflection.id) {
        int made_width, made_height;
        gfx_framebuffer_size(w->reflection, &made_width, &made_height);
        if (made_width == half_width && made_height == half_height) return true;
    }
    water_free_passes(w);
    gfx_framebuffer_desc fb = { .width = half_width, .height = half_height, .depth = true };
    w->reflection = gfx_framebuffer_create(&fb);
    w->refraction = gfx_framebuffer_create(&fb);
    if (w->reflection.id && w->refraction.id) return true;
    water_free_passes(w);
    return false;
}

/* ---- the high quality's passes -------------------------------------------------------------- */

/* The uploaded, shown mesh chunks `frustum` may see (NULL: those the cull phase found visible). */
static int water_gather_meshes(terrain_water *w, terrain_ecs *te, const terrain_frustum *frustum) {
    if (!te) return 0;
    int count = 0;
    ecs_iter it = ecs_query_iter(te->ecs, te->mesh_chunks);
    while (ecs_query_next(&it)) {
        const TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            const TerrainMeshChunk *c = &chunks[i];
            if (c->gpu.index_count == 0 || c->hidden) continue;
            bool seen = frustum ? terrain_frustum_sees(frustum, c->gpu.origin, c->gpu.bounds_min, c->gpu.bounds_max)
                                : c->visible;
            if (!seen) continue;
            w->meshes = core_grow(w->meshes, &w->mesh_capacity, (size_t)count + 1, sizeof *w->meshes);
            w->meshes[count++] = c->gpu;
        }
    }
    return count;
}

/* The sea's reflection (the camera mirrored about the sea; what lies under the sea clipped)
 * and refraction (the same view; what lies above it clipped), each into its half-size target. */
static void water_sea_passes(terrain_water *w, terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view,
                             float sea_level) {
    gfx_context *gfx = w->desc.gfx;
    terrain_view mirrored = *view;
    mirrored.camera[1] = 2.0 * sea_level - view->camera[1];
    mirrored.pitch = -view->pitch;
    terrain_frustum frustum = terrain_frustum_from_view(&mirrored);
    int count = water_gather_meshes(w, te, &frustum);
    const float clear[4] = { 0, 0, 0, 1 };
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "water.reflection", .target = w->reflection, .clear_color = true,
                                          .color = { clear[0], clear[1], clear[2], clear[3] }, .clear_depth = true });
    float above[4] = { 0, 1, 0, (float)(mirrored.camera[1] - sea_level) + WATER_CLIP_MARGIN };
    terrain__renderer_draw_clipped(renderer, &mirrored, w->meshes, count, above);
    gfx_pass_end(gfx);

    count = water_gather_meshes(w, te, NULL);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "water.refraction", .target = w->refraction, .clear_color = true,
                                          .color = { clear[0], clear[1], clear[2], clear[3] }, .clear_depth = true });
    float below[4] = { 0, -1, 0, (float)(sea_level - view->camera[1]) + WATER_CLIP_MARGIN };
    terrain__renderer_draw_clipped(renderer, view, w->meshes, count, below);
    gfx_pass_end(gfx);
}

/* ---- the surfaces ---------------------------------------------------------------------------- */

typedef struct water_frame {
    const terrain_view *view;
    mat4 view_projection, inverse;
    float sun[3];
    float under_surface;                  /* the surface the camera is under; NAN: none */
    bool high;                            /* the sea samples the passes */
    bool read_frame;                      /* the frame is copied (medium, high, under water);
                                             else low blends over it (water.frag's u_blend) */
} water_frame;

/* A camera coordinate modulo the maps' common period, in double: small floats for the shader. */
static float water_wrap(double value) { return (float)(value - floor(value / WATER_MAP_PERIOD) * WATER_MAP_PERIOD); }

static void water_surface_uniforms(terrain_water *w, const water_frame *f, terrain_renderer *renderer) {
    gfx_context *gfx = w->desc.gfx;
    gfx_program p = w->surface;
    const float zero[3] = { 0, 0, 0 };
    int width, height;
    gfx_size(gfx, &width, &height);
    float fog = w->desc.fog_density > 0 ? w->desc.fog_density : terrain__renderer_fog_density(renderer);
    float clouds = w->desc.cloud_cover != 0 ? fmaxf(w->desc.cloud_cover, 0.0f) : terrain__renderer_cloud_cover(renderer);
    float texture_offset[2] = { water_wrap(f->view->camera[0]), water_wrap(f->view->camera[2]) };
    gfx_program_use(gfx, p);
    gfx_uniform_mat4(gfx, p, "u_view_projection", (const float *)f->view_projection);
    gfx_uniform_mat4(gfx, p, "u_inverse_view_projection", (const float *)f->inverse);
    gfx_uniform_vec2(gfx, p, "u_screen_size", (const float[2]){ (float)width, (float)height });
    gfx_uniform_vec2(gfx, p, "u_texture_offset", texture_offset);
    gfx_uniform_vec3(gfx, p, "u_sun_direction", f->sun);
    gfx_uniform_vec3(gfx, p, "u_camera_position", zero);
    gfx_uniform_float(gfx, p, "u_fog_density", fog);
    gfx_uniform_float(gfx, p, "u_cloud_cover", clouds);
    gfx_uniform_float(gfx, p, "u_time", f->view->time);
    gfx_uniform_int(gfx, p, "u_scene_color", UNIT_SCENE_COLOR);
    gfx_uniform_int(gfx, p, "u_scene_depth", UNIT_SCENE_DEPTH);
    gfx_uniform_int(gfx, p, "u_reflection", UNIT_REFLECTION);
    gfx_uniform_int(gfx, p, "u_dudv", UNIT_DUDV);
    gfx_uniform_int(gfx, p, "u_normals", UNIT_NORMALS);
    gfx_texture_bind(w->dudv, UNIT_DUDV);
    gfx_texture_bind(w->normals, UNIT_NORMALS);
    gfx_uniform_int(gfx, p, "u_blend", f->read_frame ? 0 : 1);
    gfx_uniform_float(gfx, p, "u_camera_y", (float)f->view->camera[1]);
    terrain__renderer_bind_ground(renderer, p.id, f->view->camera, UNIT_GROUND);
}

/* The frame under a surface: the copies, or the sea's refraction pass (and its reflection). */
static void water_sources(terrain_water *w, bool passes) {
    gfx_program p = w->surface;
    gfx_texture_bind(passes ? gfx_framebuffer_color(w->refraction) : w->color_copy, UNIT_SCENE_COLOR);
    gfx_texture_bind(passes ? gfx_framebuffer_depth(w->refraction) : w->depth_copy, UNIT_SCENE_DEPTH);
    gfx_texture_bind(passes ? gfx_framebuffer_color(w->reflection) : w->color_copy, UNIT_REFLECTION);
    gfx_uniform_int(w->desc.gfx, p, "u_use_reflection", passes ? 1 : 0);
}

/* One quad at world height `height` from world (x0, z0) over extent metres; `rows` NULL = all. */
static void water_draw_quad(terrain_water *w, gfx_program p, const water_frame *f, double x0, double z0,
                            double height, const float extent[2], float cell, const uint32_t *rows) {
    gfx_context *gfx = w->desc.gfx;
    const double *camera = f->view->camera;
    float corner[3] = { (float)(x0 - camera[0]), (float)(height - camera[1]), (float)(z0 - camera[2]) };
    gfx_uniform_vec3(gfx, p, "u_corner", corner);
    gfx_uniform_vec2(gfx, p, "u_extent", extent);
    gfx_uniform_float(gfx, p, "u_cell", cell > 0 ? cell : 1.0f);
    gfx_uniform_int(gfx, p, "u_use_rows", rows ? 1 : 0);
    if (rows) {
        GLuint program = gfx_program_gl(gfx, p);
        GLint location = glGetUniformLocation(program, "u_rows");
        if (location >= 0) glProgramUniform1uiv(program, location, TERRAIN_MESH_CELLS, rows);
    }
    bool under = !isnan(f->under_surface) && fabs((double)f->under_surface - height) < WATER_LAKE_ABOVE_SEA;
    gfx_uniform_int(gfx, p, "u_under", under ? 1 : 0);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = w->empty, .count = 6 });
    w->stats.planes_drawn++;
}

/* The surfaces with program `p`: the surface program (shaded), or the probe's. */
static void water_draw_sea(terrain_water *w, gfx_program p, const water_frame *f, float sea_level) {
    double reach = f->view->far_distance > 0 ? f->view->far_distance : 4000.0;
    if (p.id == w->surface.id && f->read_frame) water_sources(w, f->high);
    float extent[2] = { (float)(2 * reach), (float)(2 * reach) };
    water_draw_quad(w, p, f, f->view->camera[0] - reach, f->view->camera[2] - reach, sea_level, extent, 1, NULL);
}

static void water_draw_lakes(terrain_water *w, gfx_program p, const water_frame *f, float sea_level) {
    if (!w->planes) return;
    if (p.id == w->surface.id && f->read_frame) water_sources(w, false);
    terrain_frustum frustum = terrain_frustum_from_view(f->view);
    ecs_iter it = ecs_query_iter(w->desc.ecs, w->planes);
    while (ecs_query_next(&it)) {
        const WaterPlane *planes = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            const WaterPlane *wp = &planes[i];
            float side = wp->cell * TERRAIN_MESH_CELLS;
            for (int k = 0; k < wp->count && k < TERRAIN_WATER_PLANES_MAX; k++) {
                const terrain_water_plane *plane = &wp->planes[k];
                if (terrain_world_has_sea(w->desc.world) && plane->height <= sea_level + WATER_LAKE_ABOVE_SEA) continue;
                float y = (float)(plane->height - wp->origin[1]);
                if (!terrain_frustum_sees(&frustum, wp->origin, (const float[3]){ 0, y - 0.01f, 0 },
                                          (const float[3]){ side, y + 0.01f, side }))
                    continue;
                water_draw_quad(w, p, f, wp->origin[0], wp->origin[2], plane->height, (const float[2]){ side, side },
                                wp->cell, plane->rows);
            }
        }
    }
}

/* Under water: the water fog over everything drawn, cut by the surface above. */
static void water_draw_fog(terrain_water *w, const water_frame *f) {
    gfx_context *gfx = w->desc.gfx;
    gfx_program p = w->under;
    gfx_program_use(gfx, p);
    gfx_uniform_mat4(gfx, p, "u_inverse_view_projection", (const float *)f->inverse);
    gfx_uniform_vec3(gfx, p, "u_sun_direction", f->sun);
    gfx_uniform_float(gfx, p, "u_surface_above", (float)(f->under_surface - f->view->camera[1]));
    gfx_uniform_float(gfx, p, "u_water_density", WATER_UNDER_DENSITY);
    gfx_uniform_int(gfx, p, "u_scene_depth", UNIT_SCENE_DEPTH);
    gfx_texture_bind(w->depth_copy, UNIT_SCENE_DEPTH);
    glDisable(GL_DEPTH_TEST);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = w->empty, .count = 3 });
    glEnable(GL_DEPTH_TEST);
}

/* The surface the camera is under (its water column's top), NAN when it is in air. */
static float water_surface_over_camera(terrain_water *w, const terrain_view *view) {
    float surface, ground;
    if (!terrain_world_water_at(w->desc.world, view->camera[0], view->camera[2], &surface, &ground)) return NAN;
    return view->camera[1] < surface && view->camera[1] >= ground ? surface : NAN;
}

/* Whether the last frame's query saw water; true when it cannot tell yet (no query, or its
 * result not in: never a wait). */
static bool water_seen_last_frame(terrain_water *w) {
    int last = w->query_next ^ 1;
    if (!w->query_issued[last]) return true;
    GLuint available = 0, seen = 1;
    glGetQueryObjectuiv(w->queries[last], GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available) return true;
    glGetQueryObjectuiv(w->queries[last], GL_QUERY_RESULT, &seen);
    return seen != 0;
}

/* The surfaces, counted by this frame's query: shaded, or only probed (no colour written). */
static void water_draw_surfaces(terrain_water *w, const water_frame *f, terrain_renderer *renderer, float sea_level,
                                bool shade) {
    gfx_context *gfx = w->desc.gfx;
    gfx_program p = shade ? w->surface : w->probe;
    if (shade) water_surface_uniforms(w, f, renderer);
    else {
        gfx_program_use(gfx, p);
        gfx_uniform_mat4(gfx, p, "u_view_projection", (const float *)f->view_projection);
        glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    }
    GLuint query = w->queries[w->query_next];
    glBeginQuery(GL_ANY_SAMPLES_PASSED, query);
    if (terrain_world_has_sea(w->desc.world)) water_draw_sea(w, p, f, sea_level);
    water_draw_lakes(w, p, f, sea_level);
    glEndQuery(GL_ANY_SAMPLES_PASSED);
    w->query_issued[w->query_next] = true;
    w->query_next ^= 1;
    if (!shade) {
        glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        w->stats.planes_drawn = 0;              /* probed, not drawn */
    }
}

void terrain_water_draw(terrain_water *w, terrain_ecs *te, terrain_renderer *renderer, const terrain_view *view) {
    w->stats = (terrain_water_stats_info){ 0 };
    terrain__renderer_set_water_drawn(renderer, w->desc.quality != TERRAIN_WATER_OFF && terrain_world_has_sea(w->desc.world));
    if (w->desc.quality == TERRAIN_WATER_OFF) return;
    TRACE_ZONE("terrain_water_draw");
    uint64_t start = core_time_ns();
    gfx_context *gfx = w->desc.gfx;
    float sea_level = terrain_world_generation(w->desc.world)->sea_level;
    water_frame f = { .view = view, .under_surface = water_surface_over_camera(w, view) };
    terrain_view_matrix(view, (float *)f.view_projection);
    glm_mat4_inv(f.view_projection, f.inverse);
    terrain_view_sun(view, f.sun);
    w->stats.under_water = !isnan(f.under_surface);
    int width, height;
    gfx_size(gfx, &width, &height);
    bool shade = w->stats.under_water || water_seen_last_frame(w);
    f.high = shade && terrain_world_has_sea(w->desc.world) && w->desc.quality == TERRAIN_WATER_HIGH && !w->stats.under_water &&
             view->camera[1] > sea_level && water_pass_targets(w, width, height);
    if (f.high) water_sea_passes(w, te, renderer, view, sea_level);
    /* Low reads nothing of the frame above water; under water (the fog needs the frame's depth)
     * or without far terrain (no heights for the depth) it reads it as medium does. */
    f.read_frame = shade && (w->desc.quality >= TERRAIN_WATER_MEDIUM || w->stats.under_water ||
                             !terrain__renderer_has_ground(renderer));
    w->stats.frame_read = f.read_frame;

    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "water" });
    if (f.read_frame) water_copy_frame(w, width, height);
    /* Blended over the frame; no depth written (nothing drawn later needs it, and the shader's
     * early depth test then skips the hidden sea at no cost); both faces (seen from below). */
    glEnable(GL_BLEND);
    if (f.read_frame) glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    else glBlendFunc(GL_ONE, GL_SRC1_COLOR);      /* low: water.frag's two outputs */
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    water_draw_surfaces(w, &f, renderer, sea_level, shade);
    if (w->stats.under_water) water_draw_fog(w, &f);
    glEnable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    gfx_pass_end(gfx);
    w->stats.cpu_ms = (double)(core_time_ns() - start) * 1e-6;
    trace_counter("water.planes_drawn", (double)w->stats.planes_drawn);
}
