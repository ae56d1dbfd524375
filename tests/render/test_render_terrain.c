/* The terrain renderer through OSMesa: materials from the vertex weights, camera-relative drawing
 * far from the origin, and a generated, meshed region that looks like ground under a sky. */
#include "../engine/test.h"
#include "render_util.h"

#include "terrain/terrain.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 96
#define H 64

/* A flat square of `size` metres at height 0, facing up, every vertex with the given weights. */
static terrain_mesh flat_square(double origin_x, double origin_z, float size, const uint8_t weights[4]) {
    terrain_mesh mesh = { .origin = { origin_x, 0, origin_z }, .vertex_count = 4, .index_count = 6 };
    mesh.vertices = calloc(4, sizeof *mesh.vertices);
    mesh.indices = malloc(6 * sizeof *mesh.indices);
    const float corners[4][2] = { { -size, -size }, { -size, size }, { size, size }, { size, -size } };
    for (int i = 0; i < 4; i++) {
        mesh.vertices[i] = (terrain_vertex){ .position = { corners[i][0], 0, corners[i][1] }, .normal = { 0, 1, 0 } };
        memcpy(mesh.vertices[i].weights, weights, 4);
    }
    const uint32_t indices[6] = { 0, 1, 2, 0, 2, 3 };   /* counter-clockwise seen from above */
    memcpy(mesh.indices, indices, sizeof indices);
    mesh.bounds_min[0] = mesh.bounds_min[2] = -size;
    mesh.bounds_max[0] = mesh.bounds_max[2] = size;
    return mesh;
}

static void free_square(terrain_mesh *mesh) { free(mesh->vertices); free(mesh->indices); }

/* Renders one mesh seen from `height` metres above its origin, looking straight down. */
static render_image render_mesh(gfx_context *gfx, terrain_renderer *renderer, const terrain_mesh *mesh,
                                double camera_x, double camera_z, double height) {
    terrain_gpu_mesh gpu = terrain_gpu_mesh_upload(mesh);
    terrain_view view = { .camera = { camera_x, height, camera_z }, .pitch = -1.5707f, .aspect = (float)W / H,
                          .sun_direction = { 0, 1, 0 } };
    gfx_frame_begin(gfx);
    terrain_renderer_draw(renderer, &view, &gpu, 1);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(gfx, image.rgba);
    gfx_frame_end(gfx);
    terrain_gpu_mesh_destroy(&gpu);
    return image;
}

static void mean_color(const render_image *image, double mean[3]) {
    mean[0] = mean[1] = mean[2] = 0;
    for (int i = 0; i < W * H; i++)
        for (int c = 0; c < 3; c++) mean[c] += image->rgba[i * 4 + c] / (double)(W * H);
}

Test(render_terrain, vertex_weights_pick_the_material) {
    gfx_context *gfx = render_offscreen(W, H);
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -50 });
    cr_assert(renderer);
    terrain_mesh sand = flat_square(0, 0, 50, (const uint8_t[4]){ 0, 255, 0, 0 });
    terrain_mesh rock = flat_square(0, 0, 50, (const uint8_t[4]){ 0, 0, 255, 0 });
    render_image a = render_mesh(gfx, renderer, &sand, 0, 0, 10), b = render_mesh(gfx, renderer, &rock, 0, 0, 10);
    double sand_mean[3], rock_mean[3];
    mean_color(&a, sand_mean);
    mean_color(&b, rock_mean);
    /* Sand is warm (red well above blue); the rocks texture is a neutral grey and darker. */
    cr_assert_gt(sand_mean[0], sand_mean[2] + 40, "sand %.0f %.0f %.0f", sand_mean[0], sand_mean[1], sand_mean[2]);
    cr_assert_lt(fabs(rock_mean[0] - rock_mean[2]), 15, "rocks %.0f %.0f %.0f", rock_mean[0], rock_mean[1], rock_mean[2]);
    cr_assert_gt(sand_mean[1], rock_mean[1] + 30);
    free_square(&sand);
    free_square(&rock);
    render_image_free(&a);
    render_image_free(&b);
    terrain_renderer_destroy(renderer);
    gfx_context_destroy(gfx);
}

Test(render_terrain, a_view_100_km_away_renders_exactly_as_at_the_origin) {
    gfx_context *gfx = render_offscreen(W, H);
    terrain_renderer *renderer = terrain_renderer_create(gfx, NULL);
    const uint8_t mixed[4] = { 128, 64, 63, 0 };
    /* The same square and camera, shifted by 100 km (a multiple of the textures' 200 m period). */
    terrain_mesh near = flat_square(3.25, -7.5, 30, mixed), far = flat_square(100003.25, 99992.5, 30, mixed);
    render_image a = render_mesh(gfx, renderer, &near, 1.0, -6.0, 12), b = render_mesh(gfx, renderer, &far, 100001.0, 99994.0, 12);
    int worst = 0;
    for (int i = 0; i < W * H * 4; i++) {
        int d = abs((int)a.rgba[i] - (int)b.rgba[i]);
        if (d > worst) worst = d;
    }
    cr_assert_leq(worst, 1, "largest channel difference %d", worst);
    free_square(&near);
    free_square(&far);
    render_image_free(&a);
    render_image_free(&b);
    terrain_renderer_destroy(renderer);
    gfx_context_destroy(gfx);
}

#include "ecs/ecs.h"
#include "jobs/jobs.h"

/* Everything a generated area needs, made and unmade in one place. */
typedef struct area {
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_renderer *renderer;
    terrain_ecs *te;
} area;

static area area_open(int threads, uint64_t seed, int width, int height, terrain_renderer_desc renderer_desc) {
    area a = { .gfx = render_offscreen(width, height) };
    a.jobs = job_system_create(&(job_system_desc){ .threads = threads });
    a.ecs = ecs_world_create(&(ecs_world_desc){ .jobs = a.jobs });
    a.world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(seed) });
    a.renderer = terrain_renderer_create(a.gfx, &renderer_desc);
    a.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = a.ecs, .terrain = a.world });
    return a;
}

static void area_close(area *a) {
    terrain_ecs_destroy(a->te);
    terrain_renderer_destroy(a->renderer);
    ecs_world_destroy(a->ecs);
    terrain_world_destroy(a->world);
    job_system_destroy(a->jobs);
    gfx_context_destroy(a->gfx);
}

/* Draws the area's uploaded chunks from `view` and reads the frame back. */
static render_image area_draw(area *a, const terrain_view *view) {
    gfx_frame_begin(a->gfx);
    terrain_ecs_draw(a->te, a->renderer, view);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(a->gfx, image.rgba);
    gfx_frame_end(a->gfx);
    return image;
}

/* Height of the ground in the middle of chunk (0, 0). */
static float area_ground(area *a) {
    return terrain_stacks_surface(terrain_world_stacks(a->world, (terrain_chunk_coord){ 0, 0 }), 16, 16);
}

/* Generates, meshes and draws a 3 × 3-chunk area through the ECS on `threads` threads. */
static terrain_ecs_stats_info render_generated(int threads, render_image *image) {
    area a = area_open(threads, 7, W, H, (terrain_renderer_desc){ .sea_level = terrain_generation_defaults(7).sea_level });
    terrain_ecs_spawn_area(a.te, 0, 0, 1, -4, 8);
    ecs_progress(a.ecs, 1.0f / 60.0f);
    /* From 60 m above the middle of chunk (0, 0), looking north and down a little. */
    terrain_view view = { .camera = { 16, area_ground(&a) + 60, 40 }, .pitch = -0.3f, .aspect = (float)W / H };
    *image = area_draw(&a, &view);
    terrain_ecs_stats_info stats = terrain_ecs_stats(a.te);
    area_close(&a);
    return stats;
}

Test(render_terrain, generated_area_shows_ground_under_sky_the_same_on_any_thread_count) {
    render_image one, two;
    terrain_ecs_stats_info a = render_generated(1, &one), b = render_generated(2, &two);
    cr_assert_eq(a.chunks, 9);
    cr_assert_eq(a.chunks_generated, 9, "the generate phase made every chunk's stacks");
    cr_assert_eq(a.mesh_chunks_uploaded, a.mesh_chunks, "the mesh and draw phases finished in one frame");
    cr_assert_gt(a.triangles, 1000u);
    cr_assert_eq(a.triangles, b.triangles, "the same meshes on 1 and 2 threads");
    cr_assert(memcmp(one.rgba, two.rgba, W * H * 4) == 0, "the same image on 1 and 2 threads");
    int sky = 0, ground = 0;
    for (int x = 0; x < W; x++) {
        const uint8_t *top = render_pixel(&one, x, 0), *bottom = render_pixel(&one, x, H - 1);
        sky += top[2] > top[0] + 30;
        ground += !(bottom[2] > bottom[0] + 30);
    }
    cr_assert_gt(sky, W * 9 / 10, "sky along the top row");
    cr_assert_gt(ground, W * 9 / 10, "ground along the bottom row");
    render_image_free(&one);
    render_image_free(&two);
}

/* ---- rings of detail through the ECS: the meshes on the GPU close every seam ---- */

typedef struct ring_point { double p[3]; } ring_point;

static int ring_point_compare(const void *a, const void *b) {
    const double *x = ((const ring_point *)a)->p, *y = ((const ring_point *)b)->p;
    for (int i = 0; i < 3; i++)
        if (x[i] != y[i]) return x[i] < y[i] ? -1 : 1;
    return 0;
}

static int u64_compare(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

typedef struct ring_meshes { ring_point *points; uint32_t *triangles; size_t point_count, index_count; } ring_meshes;

/* Reads every uploaded mesh back from the GPU, in world positions (origin + vertex, in doubles). */
static void gather_gpu_meshes(const terrain_gpu_mesh *meshes, int count, ring_meshes *out) {
    *out = (ring_meshes){ 0 };
    for (int m = 0; m < count; m++) {
        GLint bytes = 0;
        glGetNamedBufferParameteriv(gfx_buffer_gl(meshes[m].vertex_buffer), GL_BUFFER_SIZE, &bytes);
        size_t vertex_count = (size_t)bytes / sizeof(terrain_vertex);
        terrain_vertex *vertices = malloc((size_t)bytes);
        uint32_t *indices = malloc(meshes[m].index_count * sizeof *indices);
        glGetNamedBufferSubData(gfx_buffer_gl(meshes[m].vertex_buffer), 0, bytes, vertices);
        glGetNamedBufferSubData(gfx_buffer_gl(meshes[m].index_buffer), 0, meshes[m].index_count * sizeof *indices, indices);
        out->points = realloc(out->points, (out->point_count + vertex_count) * sizeof *out->points);
        out->triangles = realloc(out->triangles, (out->index_count + meshes[m].index_count) * sizeof *out->triangles);
        for (size_t v = 0; v < vertex_count; v++)
            for (int a = 0; a < 3; a++)
                out->points[out->point_count + v].p[a] = meshes[m].origin[a] + (double)vertices[v].position[a];
        for (uint32_t i = 0; i < meshes[m].index_count; i++)
            out->triangles[out->index_count + i] = (uint32_t)out->point_count + indices[i];
        out->point_count += vertex_count;
        out->index_count += meshes[m].index_count;
        free(vertices);
        free(indices);
    }
}

Test(render_terrain, rings_of_detail_leave_no_open_edge_inside_the_area) {
    area a = area_open(2, 5, 32, 32, (terrain_renderer_desc){ 0 });
    const int half_width = 2, levels = 2;
    const double y_min = -64, y_max = 192;       /* multiples of the coarsest chunk height (64 m) */
    terrain_ecs_spawn_rings(a.te, half_width, levels, y_min, y_max);
    ecs_progress(a.ecs, 1.0f / 60.0f);           /* generate, mesh and upload */

    /* The GPU meshes, via the query the draw uses: gather them through a renderer-free path. */
    terrain_gpu_mesh meshes[1024];
    int count = 0;
    ecs_query *q = ecs_query_create(a.ecs, &(ecs_query_desc){ .with = { ecs_component_lookup(a.ecs, "TerrainMeshChunk") } });
    ecs_iter it = ecs_query_iter(a.ecs, q);
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            cr_assert_eq(chunks[i].state, TERRAIN_MESH_UPLOADED);
            if (chunks[i].gpu.index_count) meshes[count++] = chunks[i].gpu;
        }
    }
    ring_meshes all;
    gather_gpu_meshes(meshes, count, &all);
    cr_assert_gt(all.index_count, 3000u);

    /* Weld by exact world position, then every directed edge needs its reverse unless it lies
     * on the outer box of the area. */
    ring_point *unique = malloc(all.point_count * sizeof *unique);
    memcpy(unique, all.points, all.point_count * sizeof *unique);
    qsort(unique, all.point_count, sizeof *unique, ring_point_compare);
    size_t unique_count = 0;
    for (size_t i = 0; i < all.point_count; i++)
        if (i == 0 || ring_point_compare(&unique[i], &unique[unique_count - 1]) != 0) unique[unique_count++] = unique[i];
    uint32_t *weld = malloc(all.point_count * sizeof *weld);
    for (size_t i = 0; i < all.point_count; i++)
        weld[i] = (uint32_t)((ring_point *)bsearch(&all.points[i], unique, unique_count, sizeof *unique, ring_point_compare) - unique);
    uint64_t *edges = malloc(all.index_count * sizeof *edges);
    size_t edge_count = 0;
    for (size_t t = 0; t + 2 < all.index_count; t += 3)
        for (int k = 0; k < 3; k++) {
            uint64_t from = weld[all.triangles[t + k]], to = weld[all.triangles[t + (k + 1) % 3]];
            if (from != to) edges[edge_count++] = from << 32 | to;
        }
    qsort(edges, edge_count, sizeof *edges, u64_compare);
    const double outer = half_width * TERRAIN_MESH_CELLS * (double)(1 << (levels - 1));
    int open_inside = 0;
    for (size_t e = 0; e < edge_count; e++) {
        uint64_t reverse = (edges[e] << 32) | (edges[e] >> 32);
        if (bsearch(&reverse, edges, edge_count, sizeof *edges, u64_compare)) continue;
        const double *p = unique[edges[e] >> 32].p, *q2 = unique[edges[e] & 0xffffffffu].p;
        bool on_box = false;
        for (int axis = 0; axis < 3; axis++) {
            double lo = axis == 1 ? y_min : -outer, hi = axis == 1 ? y_max : outer;
            on_box |= (p[axis] == lo && q2[axis] == lo) || (p[axis] == hi && q2[axis] == hi);
        }
        open_inside += !on_box;
    }
    cr_assert_eq(open_inside, 0, "%d open edges inside the area (seams between levels or chunks)", open_inside);
    free(edges);
    free(weld);
    free(unique);
    free(all.points);
    free(all.triangles);
    area_close(&a);
}

/* Looks 50° up into an empty sky at time `t`. */
static render_image render_sky(gfx_context *gfx, terrain_renderer *renderer, float t) {
    terrain_view view = { .pitch = 0.87f, .aspect = (float)W / H, .time = t };
    gfx_frame_begin(gfx);
    terrain_renderer_draw(renderer, &view, NULL, 0);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(gfx, image.rgba);
    gfx_frame_end(gfx);
    return image;
}

static int pixels_that_differ(const render_image *a, const render_image *b) {
    int differ = 0;
    for (int i = 0; i < W * H; i++)
        for (int c = 0; c < 3; c++)
            if (abs((int)a->rgba[i * 4 + c] - (int)b->rgba[i * 4 + c]) > 8) { differ++; break; }
    return differ;
}

Test(render_terrain, clouds_drift_with_time_and_a_clear_sky_has_none) {
    gfx_context *gfx = render_offscreen(W, H);
    terrain_renderer *cloudy = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .cloud_cover = 0.6f });
    terrain_renderer *clear = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .cloud_cover = -1 });
    render_image a = render_sky(gfx, cloudy, 0), b = render_sky(gfx, cloudy, 120);
    render_image c = render_sky(gfx, clear, 0), d = render_sky(gfx, clear, 120);
    cr_assert_gt(pixels_that_differ(&a, &b), W * H / 20, "two minutes later the clouds have moved");
    cr_assert_eq(pixels_that_differ(&c, &d), 0, "a clear sky does not change with time");
    cr_assert_gt(pixels_that_differ(&a, &c), W * H / 20, "cover 0.6 shows clouds");
    /* A clear sky is blue everywhere; clouds are near-white, so some cloudy pixels are grey. */
    int grey = 0;
    for (int i = 0; i < W * H; i++) {
        const uint8_t *p = a.rgba + i * 4;
        grey += abs(p[0] - p[2]) < 30 && p[0] > 150;
    }
    cr_assert_gt(grey, 0, "white clouds");
    render_image_free(&a);
    render_image_free(&b);
    render_image_free(&c);
    render_image_free(&d);
    terrain_renderer_destroy(cloudy);
    terrain_renderer_destroy(clear);
    gfx_context_destroy(gfx);
}

Test(render_terrain, frustum_keeps_what_is_seen_and_drops_what_is_behind) {
    terrain_view view = { .camera = { 1000, 50, -2000 }, .yaw = 0, .pitch = 0, .aspect = 1.5f };
    terrain_frustum f = terrain_frustum_from_view(&view);
    const float lo[3] = { 0, 0, 0 }, hi[3] = { 32, 32, 32 };
    /* Yaw 0 looks along −z: a box 100 m ahead is seen, one 100 m behind or 3 km above is not. */
    cr_assert(terrain_frustum_sees(&f, (double[3]){ 984, 34, -2132 }, lo, hi));
    cr_assert_not(terrain_frustum_sees(&f, (double[3]){ 984, 34, -1900 }, lo, hi));
    cr_assert_not(terrain_frustum_sees(&f, (double[3]){ 984, 3050, -2132 }, lo, hi));
    /* Beyond the far plane (4 km), and a box the camera stands in. */
    cr_assert_not(terrain_frustum_sees(&f, (double[3]){ 984, 34, -6500 }, lo, hi));
    cr_assert(terrain_frustum_sees(&f, (double[3]){ 990, 40, -2010 }, lo, hi));
    /* Half the horizontal field is atan(tan(30°)·1.5) = 40.9°: 45° to the right is outside, 36° inside. */
    double s_out = sin(45 * M_PI / 180), c_out = cos(45 * M_PI / 180), s_in = sin(36 * M_PI / 180), c_in = cos(36 * M_PI / 180);
    const float point_lo[3] = { -0.5f, -0.5f, -0.5f }, point_hi[3] = { 0.5f, 0.5f, 0.5f };
    cr_assert_not(terrain_frustum_sees(&f, (double[3]){ 1000 + 500 * s_out, 50, -2000 - 500 * c_out }, point_lo, point_hi));
    cr_assert(terrain_frustum_sees(&f, (double[3]){ 1000 + 500 * s_in, 50, -2000 - 500 * c_in }, point_lo, point_hi));
}

/* The same generated area drawn with and without culling: the same pixels, fewer chunks drawn. */
Test(render_terrain, culling_changes_no_pixel) {
    render_image images[2];
    uint64_t drawn[2];
    for (int pass = 0; pass < 2; pass++) {
        area a = area_open(2, 7, W, H, (terrain_renderer_desc){ .cloud_cover = -1 });
        terrain_ecs_spawn_area(a.te, 0, 0, 2, -2, 5);
        terrain_view view = { .camera = { 16, area_ground(&a) + 30, 16 }, .pitch = -0.2f, .aspect = (float)W / H };
        terrain_ecs_set_view(a.te, pass ? &view : NULL);
        ecs_progress(a.ecs, 1.0f / 60.0f);
        images[pass] = area_draw(&a, &view);
        ecs_query *q = ecs_query_create(a.ecs, &(ecs_query_desc){ .with = { ecs_component_lookup(a.ecs, "TerrainMeshChunk") } });
        drawn[pass] = 0;
        ecs_iter it = ecs_query_iter(a.ecs, q);
        while (ecs_query_next(&it)) {
            TerrainMeshChunk *chunks = ecs_field(&it, 0);
            for (int i = 0; i < it.count; i++) drawn[pass] += chunks[i].visible && chunks[i].gpu.index_count > 0;
        }
        area_close(&a);
    }
    cr_assert(memcmp(images[0].rgba, images[1].rgba, W * H * 4) == 0, "culling changed the image");
    cr_assert_lt(drawn[1], drawn[0], "culled %llu of %llu chunks", (unsigned long long)(drawn[0] - drawn[1]),
                 (unsigned long long)drawn[0]);
    render_image_free(&images[0]);
    render_image_free(&images[1]);
}

/* Meshes that the frustum's edges cross draw only their parts in view (terrain_data.h): the
 * same pixels as drawing them whole, and fewer triangles. */
Test(render_terrain, parts_out_of_view_are_left_out_and_change_no_pixel) {
    area a = area_open(2, 7, W, H, (terrain_renderer_desc){ .cloud_cover = -1, .shadows = TERRAIN_SHADOWS_OFF });
    terrain_ecs_spawn_area(a.te, 0, 0, 2, -2, 5);
    ecs_progress(a.ecs, 1.0f / 60.0f);
    ecs_query *q = ecs_query_create(a.ecs, &(ecs_query_desc){ .with = { ecs_component_lookup(a.ecs, "TerrainMeshChunk") } });
    terrain_gpu_mesh meshes[256];
    int count = 0;
    uint64_t whole = 0;
    ecs_iter it = ecs_query_iter(a.ecs, q);
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++)
            if (chunks[i].gpu.index_count > 0 && count < 256) {
                cr_expect_gt(chunks[i].gpu.part_count, 0, "a streamed chunk's mesh has parts");
                meshes[count++] = chunks[i].gpu;
                whole += chunks[i].gpu.index_count / 3;
            }
    }
    cr_assert_gt(count, 4);
    /* Low over the middle, looking along a diagonal: the edges cross many chunks. */
    terrain_view view = { .camera = { 16, area_ground(&a) + 20, 16 }, .yaw = 0.7f, .pitch = -0.3f, .aspect = (float)W / H };
    render_image images[2];
    uint64_t triangles[2];
    for (int pass = 0; pass < 2; pass++) {
        if (pass) for (int i = 0; i < count; i++) meshes[i].part_count = 0;   /* whole */
        gfx_frame_begin(a.gfx);
        terrain_renderer_draw(a.renderer, &view, meshes, count);
        images[pass] = (render_image){ W, H, malloc(W * H * 4) };
        gfx_read_pixels(a.gfx, images[pass].rgba);
        gfx_frame_end(a.gfx);
        triangles[pass] = gfx_context_stats(a.gfx).triangles;
    }
    cr_assert(memcmp(images[0].rgba, images[1].rgba, W * H * 4) == 0, "leaving parts out changed the image");
    cr_expect_eq(triangles[1], whole + 1, "drawn whole: every triangle and the sky's one (no shadows, no far terrain): %llu, %llu",
                 (unsigned long long)triangles[1], (unsigned long long)whole);
    cr_expect_lt(triangles[0], triangles[1] * 3 / 4, "parts in view: %llu of %llu triangles",
                 (unsigned long long)triangles[0], (unsigned long long)triangles[1]);
    cr_expect_gt(triangles[0], 0);
    render_image_free(&images[0]);
    render_image_free(&images[1]);
    area_close(&a);
}
