/* The far terrain's geometry clipmap through OSMesa: ground under the horizon and sky above it,
 * no sky through the ground (cracks between levels), nothing of the clipmap inside the hole,
 * the same picture 100 km out, no gap where the volumetric chunks meet it, and far lakes drawn
 * as water at their level. */
#include "../engine/test.h"
#include "render_util.h"

#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define W 96
#define H 64

typedef struct far_scene {
    gfx_context *gfx;
    terrain_renderer *renderer;
    terrain_clipmap *clipmap;
} far_scene;

static far_scene far_scene_open(terrain_generation_desc generation, terrain_renderer_desc renderer_desc) {
    far_scene s = { .gfx = render_offscreen(W, H) };
    s.renderer = terrain_renderer_create(s.gfx, &renderer_desc);
    cr_assert(s.renderer, "the renderer's shaders (clipmap.vert, clipmap.frag included) build");
    s.clipmap = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = generation });
    terrain_renderer_set_clipmap(s.renderer, s.clipmap);
    return s;
}

static void far_scene_close(far_scene *s) {
    terrain_clipmap_destroy(s->clipmap);
    terrain_renderer_destroy(s->renderer);
    gfx_context_destroy(s->gfx);
}

/* Distance along the view axis of every pixel (top row first), from the depth buffer. */
static void read_view_depths(float *depths) {
    float *raw = malloc(W * H * sizeof *raw);
    glReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, raw);
    const double n = 0.1, f = 4000.0;                     /* terrain_view's defaults */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double z = 2.0 * raw[(H - 1 - y) * W + x] - 1.0;
            depths[y * W + x] = (float)(2.0 * n * f / (f + n - z * (f - n)));
        }
    free(raw);
}

/* One frame as a game would draw it: update, cull, upload, draw (optionally with meshes); with
 * `depths`, the view-axis distance of every pixel too. */
static render_image far_draw_with(far_scene *s, const terrain_view *view, const terrain_gpu_mesh *meshes, int mesh_count,
                                  bool upload, float *depths) {
    terrain_clipmap_update(s->clipmap, view->camera);
    terrain_frustum frustum = terrain_frustum_from_view(view);
    terrain_clipmap_cull(s->clipmap, &frustum);
    gfx_frame_begin(s->gfx);
    if (upload) terrain_clipmap_upload(s->clipmap);
    terrain_renderer_draw(s->renderer, view, meshes, mesh_count);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(s->gfx, image.rgba);
    if (depths) read_view_depths(depths);
    gfx_frame_end(s->gfx);
    return image;
}

static render_image far_draw(far_scene *s, const terrain_view *view, const terrain_gpu_mesh *meshes, int mesh_count) {
    return far_draw_with(s, view, meshes, mesh_count, true, NULL);
}

/* The same view with nothing but the sky. */
static render_image sky_draw(far_scene *s, const terrain_view *view) {
    terrain_renderer_set_clipmap(s->renderer, NULL);
    gfx_frame_begin(s->gfx);
    terrain_renderer_draw(s->renderer, view, NULL, 0);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(s->gfx, image.rgba);
    gfx_frame_end(s->gfx);
    terrain_renderer_set_clipmap(s->renderer, s->clipmap);
    return image;
}

static bool same_pixel(const render_image *a, const render_image *b, int x, int y, int tolerance) {
    const uint8_t *p = render_pixel(a, x, y), *q = render_pixel(b, x, y);
    for (int c = 0; c < 3; c++)
        if (abs((int)p[c] - (int)q[c]) > tolerance) return false;
    return true;
}

/* Pixels of rows [first_row, H) where the picture is the bare sky. */
static int sky_pixels_below(const render_image *image, const render_image *sky, int first_row) {
    int count = 0;
    for (int y = first_row; y < H; y++)
        for (int x = 0; x < W; x++) count += same_pixel(image, sky, x, y, 2);
    return count;
}

/* Primitives the GL was given while `draw` ran (GL_PRIMITIVES_GENERATED). */
static GLuint primitives_of(far_scene *s, const terrain_view *view, bool with_clipmap) {
    GLuint query, count = 0;
    glGenQueries(1, &query);
    glBeginQuery(GL_PRIMITIVES_GENERATED, query);
    render_image image = with_clipmap ? far_draw(s, view, NULL, 0) : sky_draw(s, view);
    glEndQuery(GL_PRIMITIVES_GENERATED);
    glGetQueryObjectuiv(query, GL_QUERY_RESULT, &count);
    glDeleteQueries(1, &query);
    free(image.rgba);
    return count;
}

/* Visible blocks next to each other in the index buffer are drawn in one call: fewer calls than
 * blocks, and the GL is given exactly the visible blocks' triangles, no more, no fewer. */
Test(render_clipmap, neighbouring_blocks_are_one_draw_of_exactly_their_triangles) {
    far_scene s = far_scene_open(terrain_generation_defaults(42), (terrain_renderer_desc){ .cloud_cover = -1 });
    terrain_view view = { .camera = { 100, 0, 200 }, .pitch = -0.3f, .aspect = (float)W / H };
    terrain_clipmap_update(s.clipmap, view.camera);
    view.camera[1] = terrain_clipmap_height(s.clipmap, 100, 200) + 60.0;
    GLuint with = primitives_of(&s, &view, true);
    terrain_clipmap_stats_info stats = terrain_clipmap_stats(s.clipmap);
    GLuint without = primitives_of(&s, &view, false);
    cr_assert_gt(stats.blocks_drawn, 0);
    cr_assert_lt(stats.draws, stats.blocks_drawn, "%d draws for %d blocks", stats.draws, stats.blocks_drawn);
    cr_assert_eq((uint64_t)(with - without), stats.triangles, "%u primitives for %llu triangles in the visible blocks",
                 with - without, (unsigned long long)stats.triangles);
    far_scene_close(&s);
}

Test(render_clipmap, ground_below_the_horizon_sky_above) {
    far_scene s = far_scene_open(terrain_generation_defaults(42), (terrain_renderer_desc){ .cloud_cover = -1 });
    terrain_view view = { .camera = { 100, 0, 200 }, .pitch = -0.05f, .aspect = (float)W / H };
    terrain_clipmap_update(s.clipmap, view.camera);
    view.camera[1] = terrain_clipmap_height(s.clipmap, 100, 200) + 60.0;
    render_image image = far_draw(&s, &view, NULL, 0), sky = sky_draw(&s, &view);
    terrain_clipmap_stats_info stats = terrain_clipmap_stats(s.clipmap);
    cr_assert_gt(stats.blocks_drawn, 0);
    cr_assert_gt(stats.triangles, 10000u, "%llu triangles", (unsigned long long)stats.triangles);
    cr_assert_geq(stats.reach, 4000.0, "the defaults reach past 4 km: %.0f m", stats.reach);
    int top_sky = 0, bottom_ground = 0;
    for (int x = 0; x < W; x++) {
        top_sky += same_pixel(&image, &sky, x, 0, 2);
        bottom_ground += !same_pixel(&image, &sky, x, H - 1, 2);
    }
    cr_assert_eq(top_sky, W, "the top row is sky");
    cr_assert_eq(bottom_ground, W, "the bottom row is ground");
    /* Not one colour: the ground is lit, shaded and banded. */
    float lo = 255, hi = 0;
    for (int y = H / 2; y < H; y++)
        for (int x = 0; x < W; x++) {
            float l = render_luminance(render_pixel(&image, x, y));
            lo = fminf(lo, l);
            hi = fmaxf(hi, l);
        }
    cr_assert_gt(hi - lo, 20.0f, "luminance %.0f … %.0f", lo, hi);
    /* 700 m on, drawn without an explicit upload (the draw uploads what the update left) and
     * again after one: the same picture. */
    view.camera[0] += 700.0;
    render_image lazy = far_draw_with(&s, &view, NULL, 0, false, NULL), eager = far_draw(&s, &view, NULL, 0);
    cr_assert(memcmp(lazy.rgba, eager.rgba, W * H * 4) == 0);
    render_image_free(&lazy);
    render_image_free(&eager);
    render_image_free(&image);
    render_image_free(&sky);
    far_scene_close(&s);
}

/* Looking down from above the ground, in eight directions and at three places (one 100 km out):
 * the lower part of the picture is all ground; a crack between levels, or a missing block,
 * would let the sky through. Thin fog, so that ground never fades into the sky's colour. */
Test(render_clipmap, no_sky_shows_through_the_ground) {
    far_scene s = far_scene_open(terrain_generation_defaults(9), (terrain_renderer_desc){ .cloud_cover = -1, .fog_density = 1e-5f });
    const double places[][2] = { { 0, 0 }, { 1523.5, -812.25 }, { -100047.0, 99911.0 } };
    for (size_t p = 0; p < sizeof places / sizeof places[0]; p++) {
        for (int direction = 0; direction < 8; direction++) {
            terrain_view view = { .camera = { places[p][0], 0, places[p][1] }, .yaw = (float)direction * 0.785f + 0.1f,
                                  .pitch = -0.35f, .aspect = (float)W / H };
            terrain_clipmap_update(s.clipmap, view.camera);
            view.camera[1] = terrain_clipmap_height(s.clipmap, view.camera[0], view.camera[2]) + 150.0;
            render_image image = far_draw(&s, &view, NULL, 0), sky = sky_draw(&s, &view);
            int holes = sky_pixels_below(&image, &sky, H * 2 / 5);
            cr_assert_eq(holes, 0, "place %zu direction %d: %d sky pixels below the horizon", p, direction, holes);
            render_image_free(&image);
            render_image_free(&sky);
        }
    }
    far_scene_close(&s);
}

/* A flat world at 10 m, seen straight down from 100 m above it: the vertical half-field of 30°
 * covers ±57.7 m along z and ±86.6 m along x (aspect 1.5) at the ground's depth. */
static terrain_generation_desc flat_world(float height) {
    terrain_generation_desc p = terrain_generation_defaults(1);
    p.relief_height = 0.0f;
    p.base_height = height;
    p.vertical_perturbation = 0.0f;
    p.horizontal_perturbation = 0.0f;
    p.cave_threshold = 0.0f;
    p.lake_spacing = 0.0f;                 /* no lakes: their basins would break the flatness */
    return p;
}

static void ground_under_pixel(int x, int y, double height, double ground[2]) {
    double ndc_x = (x + 0.5) / W * 2.0 - 1.0, ndc_y = 1.0 - (y + 0.5) / H * 2.0;
    double t = tan(M_PI / 6.0) * height;
    ground[0] = ndc_x * t * ((double)W / H);   /* screen right is +x */
    ground[1] = -ndc_y * t;                    /* screen up is −z (yaw 0) */
}

/* The hole: ±40 m around the camera, over flat ground at 10 m seen straight down from 110 m.
 * Inside it, nothing of the clipmap is at ground level: it has sunk to the pit's floor 156 m
 * below (hole_depth by default), over the hole's 8 m band; around it is the ground. */
Test(render_clipmap, the_hole_leaves_nothing_at_ground_level) {
    far_scene s = far_scene_open(flat_world(10.0f), (terrain_renderer_desc){ .cloud_cover = -1 });
    const double camera[2] = { 1000.0, -2000.0 };
    terrain_view view = { .camera = { camera[0], 110.0, camera[1] }, .pitch = -1.5707f, .aspect = (float)W / H };
    terrain_clipmap_set_hole(s.clipmap, (double[2]){ camera[0] - 40, camera[1] - 40 }, (double[2]){ camera[0] + 40, camera[1] + 40 });
    float *depths = malloc(W * H * sizeof *depths);
    render_image image = far_draw_with(&s, &view, NULL, 0, true, depths);
    render_image sky = sky_draw(&s, &view);
    /* The floor, 256 m down, shows its edge (32 m out) at 32·100/256 = 12.5 m at the ground's
     * depth; the ground starts 40 m out. */
    int inside = 0, outside = 0, inside_floor = 0, outside_ground = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double g[2];
            ground_under_pixel(x, y, 100.0, g);
            double d = fmax(fabs(g[0]), fabs(g[1]));
            float depth = depths[y * W + x];
            cr_assert_not(same_pixel(&image, &sky, x, y, 2), "pixel (%d, %d) shows the sky", x, y);
            if (d < 12.5 - 1.5) inside++, inside_floor += fabsf(depth - 256.0f) < 2.0f;
            if (d > 40.0 + 1.5) outside++, outside_ground += fabsf(depth - 100.0f) < 0.5f;
        }
    cr_assert_gt(inside, 50);
    cr_assert_gt(outside, 1000);
    cr_assert_eq(inside_floor, inside, "%d of %d pixels inside the hole are not on the pit's floor", inside - inside_floor, inside);
    cr_assert_eq(outside_ground, outside, "%d of %d pixels around the hole are not on the ground", outside - outside_ground, outside);
    free(depths);
    render_image_free(&image);
    render_image_free(&sky);
    far_scene_close(&s);
}

/* ---- far lakes ---- */

/* The centre of seed 1's first lake east of the origin and its level, from the far terrain's own
 * lake rows (whose agreement with the chunks' water test_terrain_water checks): the mean of the
 * 4 m texels at that level. */
static void find_far_lake(const terrain_generation_desc *p, double centre[2], float *level) {
    float row[160];
    *level = TERRAIN__NO_LAKE;
    for (int k = -50; k < 50 && *level == TERRAIN__NO_LAKE; k++) {
        terrain__lake_row_spaced(p, 0.0, 8.0, k * 8.0, 160, 8.0f, row);
        for (int j = 0; j < 160 && *level == TERRAIN__NO_LAKE; j++)
            if (row[j] != TERRAIN__NO_LAKE) *level = row[j], centre[0] = j * 8.0, centre[1] = k * 8.0;
    }
    cr_assert_neq(*level, TERRAIN__NO_LAKE, "seed 1 has a lake within 1.3 km");
    double sum[2] = { 0, 0 };
    int count = 0;
    const double x0 = centre[0] - 160.0, z0 = centre[1] - 160.0;
    for (int k = 0; k < 80; k++) {
        terrain__lake_row_spaced(p, x0, 4.0, z0 + k * 4.0, 80, 4.0f, row);
        for (int j = 0; j < 80; j++)
            if (row[j] == *level) sum[0] += x0 + j * 4.0, sum[1] += z0 + k * 4.0, count++;
    }
    centre[0] = sum[0] / count;
    centre[1] = sum[1] / count;
}

/* Whether the finest level's cell under world (x, z) lies wholly in the lake at `level` with its
 * ground at least `depth` metres under it (all four corners). */
static bool deep_lake_cell(const terrain_generation_desc *p, double x, double z, float level, float depth) {
    double x0 = floor(x / 4.0) * 4.0, z0 = floor(z / 4.0) * 4.0;
    for (int k = 0; k < 2; k++) {
        float lakes[2], ground[2];
        terrain__lake_row_spaced(p, x0, 4.0, z0 + 4.0 * k, 2, 4.0f, lakes);
        terrain__ground_row_spaced(p, x0, 4.0, z0 + 4.0 * k, 2, 4.0f, ground, NULL);
        for (int j = 0; j < 2; j++)
            if (lakes[j] != level || ground[j] > level - depth) return false;
    }
    return true;
}

/* A far lake seen straight down from 150 m above its level, with the clipmap alone (as beyond the
 * volumetric rings): every pixel over a cell whose ground lies 2 m or more under the lake is
 * drawn at the lake's level, 150 m away (not on its bed), in the water's colour: blue-green
 * over a bed of sand and grass, whose red the water takes first (water_optics.glsl). */
Test(render_clipmap, a_far_lake_is_drawn_as_water_at_its_level) {
    terrain_generation_desc p = terrain_generation_defaults(1);
    double centre[2] = { 0, 0 };
    float level;
    find_far_lake(&p, centre, &level);
    far_scene s = far_scene_open(p, (terrain_renderer_desc){ .cloud_cover = -1 });
    terrain_view view = { .camera = { centre[0], level + 150.0, centre[1] }, .pitch = -1.5707f, .aspect = (float)W / H };
    float *depths = malloc(W * H * sizeof *depths);
    render_image image = far_draw_with(&s, &view, NULL, 0, true, depths);
    int deep = 0, at_level = 0, water_coloured = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double g[2];
            ground_under_pixel(x, y, 150.0, g);
            if (!deep_lake_cell(&p, centre[0] + g[0], centre[1] + g[1], level, 2.0f)) continue;
            deep++;
            const uint8_t *c = render_pixel(&image, x, y);
            at_level += fabsf(depths[y * W + x] - 150.0f) < 0.2f;
            water_coloured += c[1] > c[0] + 15 && c[2] > c[0] + 15;
        }
    cr_assert_gt(deep, 50, "%d pixels over deep water (lake at %.2f m, centre %.0f, %.0f)", deep, (double)level,
                 centre[0], centre[1]);
    cr_expect_eq(at_level, deep, "%d of %d pixels over deep water are not at the lake's level", deep - at_level, deep);
    cr_expect_eq(water_coloured, deep, "%d of %d pixels over deep water are not blue-green", deep - water_coloured, deep);
    free(depths);
    render_image_free(&image);
    far_scene_close(&s);
}

Test(render_clipmap, a_view_100_km_away_renders_as_at_the_origin) {
    far_scene s = far_scene_open(flat_world(12.0f), (terrain_renderer_desc){ .cloud_cover = -1, .fog_density = 0.0008f });
    /* 102 400 m is a multiple of the outermost level's snapping (2 · 128 m) and of the textures'
     * period (200 m, the macro layer's), so every level lands on the same cells relative to the
     * camera and every texture on the same texels. */
    const double shift = 102400.0;
    terrain_view near = { .camera = { 3.3, 60.0, -7.1 }, .yaw = 0.7f, .pitch = -0.4f, .aspect = (float)W / H };
    terrain_view far = near;
    far.camera[0] += shift;
    far.camera[2] -= shift;
    render_image a = far_draw(&s, &near, NULL, 0), b = far_draw(&s, &far, NULL, 0);
    int worst = 0;
    for (int i = 0; i < W * H * 4; i++) worst = abs((int)a.rgba[i] - (int)b.rgba[i]) > worst ? abs((int)a.rgba[i] - (int)b.rgba[i]) : worst;
    cr_assert_leq(worst, 1, "largest channel difference %d", worst);
    render_image sky = sky_draw(&s, &near);
    cr_assert_gt(W * H - sky_pixels_below(&a, &sky, 0), W * H / 3, "the view shows the ground");
    render_image_free(&a);
    render_image_free(&b);
    render_image_free(&sky);
    far_scene_close(&s);
}

/* ---- the seam with the volumetric chunks (002 §3.5) ---- */

/* A 3 × 3-chunk area meshed through the ECS, the clipmap around it with the area as its hole:
 * from inside the area and from outside it, looking at its border in every direction, the
 * ground is never pierced by the sky. */
Test(render_clipmap, the_volumetric_area_and_the_clipmap_meet_without_holes) {
    const uint64_t seed = 7;
    terrain_generation_desc generation = terrain_generation_defaults(seed);
    far_scene s = far_scene_open(generation, (terrain_renderer_desc){ .cloud_cover = -1, .fog_density = 1e-5f,
                                                                     .sea_level = generation.sea_level });
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = generation });
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_spawn_area(te, 0, 0, 1, -4, 8);                /* columns and meshes over [−32, 64)² */
    ecs_progress(ecs, 1.0f / 60.0f);
    terrain_clipmap_set_hole(s.clipmap, (double[2]){ -32, -32 }, (double[2]){ 64, 64 });

    /* Gather the uploaded meshes and draw them with the clipmap ourselves (the ECS draw would
     * not let us read the sky-only picture of the same view). */
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
    const terrain_stacks *middle = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    double ground = terrain_stacks_top(middle, 16, 16);
    struct { double x, y, z; float pitch; } eyes[] = {
        { 16, ground + 25, 16, -0.3f },        /* inside, looking out at the border */
        { 16, ground + 6, 16, -0.12f },        /* inside, low, grazing */
        { 16, ground + 120, 160, -0.55f },     /* outside, above, looking back in */
    };
    for (size_t e = 0; e < sizeof eyes / sizeof eyes[0]; e++) {
        for (int direction = 0; direction < 8; direction++) {
            terrain_view view = { .camera = { eyes[e].x, eyes[e].y, eyes[e].z }, .yaw = (float)direction * 0.785f,
                                  .pitch = eyes[e].pitch, .aspect = (float)W / H };
            render_image image = far_draw(&s, &view, meshes, count), sky = sky_draw(&s, &view);
            int holes = sky_pixels_below(&image, &sky, H / 2);
            cr_expect_eq(holes, 0, "eye %zu direction %d: %d sky pixels below the middle row", e, direction, holes);
            render_image_free(&image);
            render_image_free(&sky);
        }
    }
    terrain_ecs_destroy(te);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    far_scene_close(&s);
}

/* ---- every viewer's rings are cut out (002 §3.5) ---- */

/* Streams the generator's world around `eyes` with the clipmap through the ECS (as the game
 * does: the lod phase re-centres it on eyes[0] and sets its holes), until every wanted chunk is
 * meshed and uploaded, then draws `view`. */
static render_image streamed_far_view(terrain_generation_desc generation, const double (*eyes)[3], int count,
                                      const terrain_view *view) {
    far_scene s = far_scene_open(generation, (terrain_renderer_desc){ .cloud_cover = -1, .sea_level = generation.sea_level });
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = generation });
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    terrain_ecs_stream(te, &(terrain_stream_desc){ .half_width = 2, .levels = 2 });
    terrain_ecs_set_clipmap(te, s.clipmap);
    int settled = -1;
    for (int frame = 0; frame < 20000 && settled < 0; frame++) {
        terrain_ecs_set_viewers(te, eyes, count);
        terrain_ecs_set_view(te, view);
        ecs_progress(ecs, 1.0f / 60.0f);
        terrain_world_trim(world);
        terrain_ecs_stream_stats_info st = terrain_ecs_stream_stats(te);
        terrain_ecs_stats_info es = terrain_ecs_stats(te);
        if (st.mesh_chunks_wanted > 0 && st.mesh_chunks_ready == st.mesh_chunks_wanted && st.jobs_in_flight == 0 &&
            es.mesh_chunks_uploaded == es.mesh_chunks)
            settled = frame;
        else
            nanosleep(&(struct timespec){ 0, 1000000 }, NULL);   /* let the workers get on */
    }
    cr_assert_geq(settled, 0, "streaming never settled");
    /* One more frame: the lod phase has seen the layout ready and set the holes. */
    terrain_ecs_set_viewers(te, eyes, count);
    terrain_ecs_set_view(te, view);
    ecs_progress(ecs, 1.0f / 60.0f);
    gfx_frame_begin(s.gfx);
    terrain_ecs_draw(te, s.renderer, view);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(s.gfx, image.rgba);
    gfx_frame_end(s.gfx);
    terrain_ecs_destroy(te);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    far_scene_close(&s);
    return image;
}

/* A second viewer 1.5 km from the first, looking down into its own rings (±128 m around it;
 * the view reaches about 75 m out): the clipmap must be sunk under them as it is when that
 * viewer is the only one. Else the clipmap's ground (coarse there, 1.5 km from its centre)
 * cuts through the chunks' surface, which it roughly coincides with. Both pictures draw the
 * same chunk meshes (the first viewer's rings are far away and do not touch the second's) over
 * a pit floor 156 m down: they should agree but for the odd pixel where a ray slips through
 * a seam between chunks onto the differently tessellated floor, hence 0.5 % of the pixels. */
Test(render_clipmap, a_second_viewers_rings_sink_the_clipmap_as_the_first_viewers_do) {
    terrain_generation_desc generation = terrain_generation_defaults(6);
    const double second[2] = { 1536.0, 512.0 };   /* on the 64 m grid the rings snap to */
    terrain_clipmap *probe = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = generation });
    terrain_clipmap_update(probe, (double[3]){ second[0], 0.0, second[1] });
    double ground = terrain_clipmap_height(probe, second[0], second[1]);
    terrain_clipmap_destroy(probe);
    cr_assert_gt(ground, generation.sea_level + 5.0, "land under the second viewer (%.1f m)", ground);
    terrain_view view = { .camera = { second[0], ground + 60.0, second[1] }, .yaw = 0.4f, .pitch = -1.2f,
                          .aspect = (float)W / H };
    const double both[2][3] = { { second[0] - 1536.0, ground, second[1] }, { view.camera[0], view.camera[1], view.camera[2] } };
    render_image two = streamed_far_view(generation, both, 2, &view);
    render_image one = streamed_far_view(generation, both + 1, 1, &view);
    int differing = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) differing += !same_pixel(&two, &one, x, y, 8);
    cr_expect_lt(differing, W * H / 200, "%d of %d pixels differ when the viewer is the second one", differing, W * H);
    render_image_free(&two);
    render_image_free(&one);
}
