/* The seam between the volumetric chunks and the far clipmap (002 §3.5), looked along from low
 * angles: with the clipmap's heights from the stacks no sky shows through the seam and no ledge
 * does — no part of the clipmap inside the hole (its pit's wall) is seen off the chunks' surface.
 * The same views with the clipmap on G alone show ledges: the check can tell. */
#include "../engine/test.h"
#include "render_util.h"

#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 96
#define H 64
#define NEAR_PLANE 0.1
#define FAR_PLANE 4000.0                     /* terrain_view's defaults */

/* View-axis distance of every pixel (top row first), from the depth buffer. */
static void read_view_depths(float *depths) {
    float *raw = malloc(W * H * sizeof *raw);
    glReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, raw);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double z = 2.0 * raw[(H - 1 - y) * W + x] - 1.0;
            depths[y * W + x] = (float)(2.0 * NEAR_PLANE * FAR_PLANE / (FAR_PLANE + NEAR_PLANE - z * (FAR_PLANE - NEAR_PLANE)));
        }
    free(raw);
}

/* One frame: the clipmap (or none) updated, culled, uploaded and drawn with the meshes; the
 * picture and every pixel's view-axis distance. */
static render_image draw_view(gfx_context *gfx, terrain_renderer *renderer, terrain_clipmap *clipmap, const terrain_view *view,
                              const terrain_gpu_mesh *meshes, int count, float *depths) {
    terrain_renderer_set_clipmap(renderer, clipmap);
    if (clipmap) {
        terrain_clipmap_update(clipmap, view->camera);
        terrain_frustum frustum = terrain_frustum_from_view(view);
        terrain_clipmap_cull(clipmap, &frustum);
    }
    gfx_frame_begin(gfx);
    if (clipmap) terrain_clipmap_upload(clipmap);
    terrain_renderer_draw(renderer, view, meshes, count);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(gfx, image.rgba);
    read_view_depths(depths);
    gfx_frame_end(gfx);
    return image;
}

/* The world point a pixel shows at view-axis distance `depth` (yaw 0 looks along −z, positive
 * turns right; the vertical field of view is 60°). */
static void pixel_point(const terrain_view *view, int x, int y, double depth, double out[3]) {
    double t = tan(M_PI / 6.0), ndc_x = (x + 0.5) / W * 2.0 - 1.0, ndc_y = 1.0 - (y + 0.5) / H * 2.0;
    double sy = sin(view->yaw), cy = cos(view->yaw), sp = sin(view->pitch), cp = cos(view->pitch);
    const double forward[3] = { sy * cp, sp, -cy * cp }, right[3] = { cy, 0, sy }, up[3] = { -sy * sp, cp, cy * sp };
    for (int a = 0; a < 3; a++)
        out[a] = view->camera[a] + depth * (forward[a] + ndc_x * t * view->aspect * right[a] + ndc_y * t * up[a]);
}

static bool same_pixel(const render_image *a, const render_image *b, int x, int y, int tolerance) {
    const uint8_t *p = render_pixel(a, x, y), *q = render_pixel(b, x, y);
    for (int c = 0; c < 3; c++)
        if (abs((int)p[c] - (int)q[c]) > tolerance) return false;
    return true;
}

typedef struct seam_counts { int sky, ledge, seam; } seam_counts;

/* Draws the view with the clipmap and with the meshes alone (and the sky alone) and counts, below
 * the middle row: sky pixels; pixels near the border (within the hole's band) whose point lies
 * inside the hole yet off the meshes (the clipmap's pit seen: nearer than the meshes there by
 * more than 0.3 m, or where they show nothing) — a ledge. */
static seam_counts count_seam(gfx_context *gfx, terrain_renderer *renderer, terrain_clipmap *clipmap, const terrain_view *view,
                              const terrain_gpu_mesh *meshes, int count, const double hole_min[2], const double hole_max[2]) {
    float *with = malloc(W * H * sizeof *with), *alone = malloc(W * H * sizeof *alone), *bare = malloc(W * H * sizeof *bare);
    render_image image = draw_view(gfx, renderer, clipmap, view, meshes, count, with);
    render_image meshes_only = draw_view(gfx, renderer, NULL, view, meshes, count, alone);
    render_image sky = draw_view(gfx, renderer, NULL, view, NULL, 0, bare);
    seam_counts counts = { 0 };
    for (int y = H / 2; y < H; y++)
        for (int x = 0; x < W; x++) {
            counts.sky += same_pixel(&image, &sky, x, y, 2);
            double p[3];
            pixel_point(view, x, y, with[y * W + x], p);
            double inside = fmin(fmin(p[0] - hole_min[0], hole_max[0] - p[0]), fmin(p[2] - hole_min[1], hole_max[1] - p[2]));
            if (inside < 0.25 || inside > 8.0) continue;        /* the band where the pit's wall is */
            counts.seam++;
            bool no_mesh = alone[y * W + x] > 0.99 * FAR_PLANE;
            counts.ledge += no_mesh || alone[y * W + x] - with[y * W + x] > 0.3f;
        }
    render_image_free(&image);
    render_image_free(&meshes_only);
    render_image_free(&sky);
    free(with);
    free(alone);
    free(bare);
    return counts;
}

Test(render_clipmap_seam, looking_along_the_seam_from_low_angles_shows_no_sky_and_no_ledge) {
    const uint64_t seed = 1;
    terrain_generation_desc generation = terrain_generation_defaults(seed);
    gfx_context *gfx = render_offscreen(W, H);
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){
        .cloud_cover = -1, .fog_density = 1e-5f, .sea_level = generation.sea_level });
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = generation });
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(te, 0, 0, 1, -4, 8);                /* columns and meshes over [−32, 64)² */
    ecs_progress(ecs, 1.0f / 60.0f);
    const double hole_min[2] = { -32, -32 }, hole_max[2] = { 64, 64 };
    /* 1 m spacing: the level-0 meshes' every border sample is a clipmap vertex. */
    terrain_clipmap *stacks = terrain_clipmap_create(&(terrain_clipmap_desc){
        .generation = generation, .finest_spacing = 1.0f, .world = world, .mesh_step = 1.0f });
    terrain_clipmap *ground = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = generation, .finest_spacing = 1.0f });
    terrain_clipmap_set_hole(stacks, hole_min, hole_max);
    terrain_clipmap_set_hole(ground, hole_min, hole_max);

    terrain_gpu_mesh meshes[512];
    int count = 0;
    ecs_query *q = ecs_query_create(ecs, &(ecs_query_desc){ .with = { ecs_component_lookup(ecs, "TerrainMeshChunk") } });
    ecs_iter it = ecs_query_iter(ecs, q);
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++)
            if (chunks[i].gpu.index_count && count < 512) meshes[count++] = chunks[i].gpu;
    }
    cr_assert_gt(count, 4);
    /* Low eyes along each side of the square, looking along it, outside and inside. */
    struct { double x, z; float yaw; } eyes[] = {
        { -44, -30, 1.5708f },     /* west of the square, just inside z = −32, looking east along it */
        { -44, -34, 1.5708f },     /* just outside it */
        { 66, -44, 3.1416f },      /* south of x = 64's side, looking north (+z) along it */
        { 62, -44, 3.1416f },
        { 76, 62, -1.5708f },      /* east of z = 64's side, looking west along it */
        { -30, 76, 0.0f },         /* north of x = −32's side, looking south (−z) along it */
    };
    /* Measured: 6 322 pixels in the band, no ledge with the stacks' heights, 80 with G alone. */
    int sky = 0, ledges = 0, seam = 0, ledges_ground = 0;
    for (size_t e = 0; e < sizeof eyes / sizeof eyes[0]; e++) {
        float top = terrain_world_top(world, eyes[e].x, eyes[e].z);
        for (int height = 0; height < 2; height++) {
            terrain_view view = { .camera = { eyes[e].x, top + (height ? 8.0 : 2.5), eyes[e].z }, .yaw = eyes[e].yaw,
                                  .pitch = height ? -0.2f : -0.06f, .aspect = (float)W / H };
            seam_counts with = count_seam(gfx, renderer, stacks, &view, meshes, count, hole_min, hole_max);
            seam_counts old = count_seam(gfx, renderer, ground, &view, meshes, count, hole_min, hole_max);
            cr_expect_eq(with.sky, 0, "eye %zu/%d: %d sky pixels below the middle row", e, height, with.sky);
            sky += with.sky;
            ledges += with.ledge;
            seam += with.seam;
            ledges_ground += old.ledge;
        }
    }
    cr_assert_gt(seam, 200, "the views look at the seam: %d pixels in its band", seam);
    cr_expect_eq(ledges, 0, "%d of %d pixels in the seam's band show the clipmap's pit off the meshes", ledges, seam);
    cr_assert_gt(ledges_ground, 20, "with G alone the same views show %d ledge pixels: the check can tell", ledges_ground);
    terrain_clipmap_destroy(ground);
    terrain_clipmap_destroy(stacks);
    terrain_ecs_destroy(te);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    terrain_renderer_destroy(renderer);
    gfx_context_destroy(gfx);
}
