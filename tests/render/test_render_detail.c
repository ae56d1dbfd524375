/* The terrain's detail layer, normal maps and macro variation (issue 12): the detail averages to
 * 1 so far colours stay the material means the clipmap uses; from a metre above bare bedrock the
 * ground shows more local contrast with the detail than without; from far away it does not
 * change a region's colour. */
#include "../engine/test.h"
#include "render_util.h"

#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 160
#define H 120

/* ---- the texels ---- */

static double channel_mean(const uint8_t *rgba, size_t texels, int channel) {
    double sum = 0;
    for (size_t i = 0; i < texels; i++) sum += rgba[i * 4 + (size_t)channel];
    return sum / (double)texels;
}

Test(render_detail, every_detail_and_macro_multiplier_has_a_mean_of_one) {
    terrain__material_texels texels;
    terrain__material_texels_make(&texels);
    const size_t count = (size_t)TERRAIN__DETAIL_SIZE * TERRAIN__DETAIL_SIZE;
    for (int layer = 0; layer < TERRAIN__DETAIL_LAYERS; layer++) {
        const uint8_t *rgba = texels.detail + count * 4 * (size_t)layer;
        /* Decoded as the shader does: 2·R/255 (and 2·G/255 for the macro layer's hue). */
        double mean = 2.0 * channel_mean(rgba, count, 0) / 255.0;
        cr_assert_lt(fabs(mean - 1.0), 0.01, "layer %d: the multiplier's mean is %.4f", layer, mean);
        if (layer == TERRAIN__MATERIAL_LAYERS) {
            double hue = 2.0 * channel_mean(rgba, count, 1) / 255.0;
            cr_assert_lt(fabs(hue - 1.0), 0.01, "macro hue mean %.4f", hue);
        }
        /* A multiplier that varies: a constant 1 would pass the mean and add nothing. */
        int lowest = 255, highest = 0;
        for (size_t i = 0; i < count; i++) {
            if (rgba[i * 4] < lowest) lowest = rgba[i * 4];
            if (rgba[i * 4] > highest) highest = rgba[i * 4];
        }
        cr_assert_gt(highest - lowest, 20, "layer %d varies only %d .. %d", layer, lowest, highest);
    }
    terrain__material_texels_free(&texels);
}

/* A tiling height field's slopes sum to zero around each row and column (central differences
 * telescope), so the normal maps lean no way on average: lit from any side, a far region is
 * as bright as flat ground. The stored x, y are of unit normals, so not exactly zero-sum: within
 * two steps of 255. */
Test(render_detail, normal_maps_lean_no_way_on_average) {
    terrain__material_texels texels;
    terrain__material_texels_make(&texels);
    const size_t base = (size_t)TERRAIN__BASE_SIZE * TERRAIN__BASE_SIZE, detail = (size_t)TERRAIN__DETAIL_SIZE * TERRAIN__DETAIL_SIZE;
    for (int layer = 0; layer < TERRAIN__MATERIAL_LAYERS; layer++)
        for (int channel = 1; channel <= 2; channel++) {
            double b = channel_mean(texels.base + base * 4 * (size_t)layer, base, channel);
            double d = channel_mean(texels.detail + detail * 4 * (size_t)layer, detail, channel);
            cr_assert_lt(fabs(b - 127.5), 2.0, "base layer %d channel %d mean %.2f", layer, channel, b);
            cr_assert_lt(fabs(d - 127.5), 2.0, "detail layer %d channel %d mean %.2f", layer, channel, d);
        }
    terrain__material_texels_free(&texels);
}

Test(render_detail, the_far_colours_are_the_tints_times_the_mean_shades) {
    terrain__material_texels texels;
    terrain__material_texels_make(&texels);
    const size_t count = (size_t)TERRAIN__BASE_SIZE * TERRAIN__BASE_SIZE;
    for (int layer = 0; layer < TERRAIN__MATERIAL_LAYERS; layer++) {
        double shade = channel_mean(texels.base + count * 4 * (size_t)layer, count, 0) / 255.0;
        for (int c = 0; c < 3; c++)
            cr_assert_float_eq(texels.means[layer][c], shade * texels.tints[layer][c], 1e-4);
    }
    /* Sand is warm, the rocks grey (the old textures' look, kept). */
    cr_assert_gt(texels.means[1][0], texels.means[1][2] + 0.15f);
    cr_assert_lt(fabsf(texels.means[2][0] - texels.means[2][2]), 0.05f);
    terrain__material_texels_free(&texels);
}

/* ---- the pictures ---- */

/* Flat ground of 2·size metres around the origin, at height 0, facing up, with the material
 * weights `weights` (bedrock, sand, rocks, water; unorm8) at every vertex. */
static terrain_mesh flat_ground(float size, const uint8_t weights[4]) {
    terrain_mesh mesh = { .vertex_count = 4, .index_count = 6 };
    mesh.vertices = calloc(4, sizeof *mesh.vertices);
    mesh.indices = malloc(6 * sizeof *mesh.indices);
    const float corners[4][2] = { { -size, -size }, { -size, size }, { size, size }, { size, -size } };
    for (int i = 0; i < 4; i++)
        mesh.vertices[i] = (terrain_vertex){ .position = { corners[i][0], 0, corners[i][1] }, .normal = { 0, 1, 0 },
                                             .weights = { weights[0], weights[1], weights[2], weights[3] } };
    const uint32_t indices[6] = { 0, 1, 2, 0, 2, 3 };
    memcpy(mesh.indices, indices, sizeof indices);
    mesh.bounds_min[0] = mesh.bounds_min[2] = -size;
    mesh.bounds_max[0] = mesh.bounds_max[2] = size;
    return mesh;
}

/* One picture of `mesh` (freed here) from `view`, by a renderer made from `desc`. */
static render_image render_mesh(terrain_mesh mesh, const terrain_view *view, const terrain_renderer_desc *desc) {
    gfx_context *gfx = render_offscreen(W, H);
    terrain_renderer *renderer = terrain_renderer_create(gfx, desc);
    cr_assert(renderer);
    terrain_gpu_mesh gpu = terrain_gpu_mesh_upload(&mesh);
    gfx_frame_begin(gfx);
    terrain_renderer_draw(renderer, view, &gpu, 1);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(gfx, image.rgba);
    gfx_frame_end(gfx);
    terrain_gpu_mesh_destroy(&gpu);
    free(mesh.vertices);
    free(mesh.indices);
    terrain_renderer_destroy(renderer);
    gfx_context_destroy(gfx);
    return image;
}

/* The ground from `height` metres above (3.3, ·, 5.6), looking straight down, under a low sun
 * (so that relief shows), with the detail layer reaching `detail_distance` (< 0: the low
 * quality, also without the 25 m scale blend; NO_DETAIL: no detail, all else as by default). */
#define NO_DETAIL 0.001f
static render_image render_ground_of(const uint8_t weights[4], float detail_distance, double height) {
    terrain_view view = { .camera = { 3.3, height, 5.6 }, .pitch = -1.5707f, .aspect = (float)W / H,
                          .sun_direction = { -0.6f, 0.5f, -0.3f } };
    return render_mesh(flat_ground(400, weights), &view, &(terrain_renderer_desc){
        .sea_level = -50, .fog_density = 1e-9f, .cloud_cover = -1, .detail_distance = detail_distance });
}

static render_image render_ground(float detail_distance, double height) {
    return render_ground_of((const uint8_t[4]){ 255, 0, 0, 0 }, detail_distance, height);
}

/* Mean absolute difference of two pictures' channels, 0 … 255. */
static double mean_difference(const render_image *a, const render_image *b) {
    double sum = 0;
    for (int i = 0; i < a->width * a->height * 4; i++)
        if (i % 4 != 3) sum += abs((int)a->rgba[i] - (int)b->rgba[i]);
    return sum / (3.0 * a->width * a->height);
}

/* terrain.frag reads each pixel's two largest materials, less the weight of the largest one it
 * leaves out. Where the second and the third are nearly equal, which of them is second must not
 * matter: bedrock ½ with sand and rocks a quarter each, the two quarters a step of 1/256 apart
 * one way and then the other, gives nearly the same picture (each then has a weight of 2/65 of
 * the blend). Dropping the third's weight without subtracting it would give a third of the
 * ground to sand in one picture and to rocks in the other: two thirds of the difference between
 * half sand and half rocks. */
Test(render_detail, materials_blend_without_a_step_where_the_second_and_third_swap) {
    render_image more_sand = render_ground_of((const uint8_t[4]){ 128, 65, 63, 0 }, NO_DETAIL, 3.0);
    render_image more_rocks = render_ground_of((const uint8_t[4]){ 128, 63, 65, 0 }, NO_DETAIL, 3.0);
    render_image sand = render_ground_of((const uint8_t[4]){ 128, 128, 0, 0 }, NO_DETAIL, 3.0);
    render_image rocks = render_ground_of((const uint8_t[4]){ 128, 0, 128, 0 }, NO_DETAIL, 3.0);
    double step = mean_difference(&more_sand, &more_rocks), materials = mean_difference(&sand, &rocks);
    cr_assert_gt(materials, 8.0, "half sand and half rocks look alike (%.2f of 255): the test sees nothing", materials);
    cr_assert_lt(step, 0.15 * materials, "a step of %.2f where sand and rocks swap places, against %.2f between them", step,
                 materials);
    render_image_free(&more_sand);
    render_image_free(&more_rocks);
    render_image_free(&sand);
    render_image_free(&rocks);
}

/* Mean absolute luminance difference between horizontal and vertical neighbours. */
static double local_contrast(const render_image *image) {
    double sum = 0;
    int pairs = 0;
    for (int y = 0; y + 1 < image->height; y++)
        for (int x = 0; x + 1 < image->width; x++) {
            float here = render_luminance(render_pixel(image, x, y));
            sum += fabsf(render_luminance(render_pixel(image, x + 1, y)) - here);
            sum += fabsf(render_luminance(render_pixel(image, x, y + 1)) - here);
            pairs += 2;
        }
    return sum / pairs;
}

static void region_mean(const render_image *image, double mean[3]) {
    mean[0] = mean[1] = mean[2] = 0;
    for (int i = 0; i < image->width * image->height; i++)
        for (int c = 0; c < 3; c++) mean[c] += image->rgba[i * 4 + c] / (double)(image->width * image->height);
}

Test(render_detail, a_metre_above_bedrock_the_detail_sharpens_the_ground) {
    render_image on = render_ground(0, 1.0), off = render_ground(NO_DETAIL, 1.0);
    double contrast_on = local_contrast(&on), contrast_off = local_contrast(&off);
    /* From 1 m the 8 m base is magnified ~5× (32 texels a metre over ~170 pixels): nearly
     * smooth. The detail's 256 texels a metre put grains and cracks on every few pixels. */
    cr_assert_gt(contrast_on, 3.0 * contrast_off, "local contrast %.2f with the detail, %.2f without",
                 contrast_on, contrast_off);
    double mean_on[3], mean_off[3];
    region_mean(&on, mean_on);
    region_mean(&off, mean_off);
    /* Even here, over a 1.3 m square, the multiplier averages to about 1: within 10 %. */
    for (int c = 0; c < 3; c++)
        cr_assert_lt(fabs(mean_on[c] - mean_off[c]), 0.1 * mean_off[c], "channel %d: %.1f on, %.1f off", c,
                     mean_on[c], mean_off[c]);
    render_image_free(&on);
    render_image_free(&off);
}

Test(render_detail, from_afar_the_detail_averages_out) {
    /* The detail forced to reach 1 km, so that what is compared is its average through the
     * mipmaps (by default it has faded out long before 60 m). */
    render_image on = render_ground(1000, 60.0), off = render_ground(NO_DETAIL, 60.0);
    double mean_on[3], mean_off[3];
    region_mean(&on, mean_on);
    region_mean(&off, mean_off);
    for (int c = 0; c < 3; c++)
        cr_assert_lt(fabs(mean_on[c] - mean_off[c]), 0.03 * mean_off[c], "channel %d: %.2f on, %.2f off", c,
                     mean_on[c], mean_off[c]);
    /* And the default reach leaves the far picture exactly as it is without the detail. */
    render_image near_default = render_ground(0, 60.0);
    int worst = 0;
    for (int i = 0; i < W * H * 4; i++) {
        int d = abs((int)near_default.rgba[i] - (int)off.rgba[i]);
        if (d > worst) worst = d;
    }
    cr_assert_eq(worst, 0, "largest channel difference %d at 60 m", worst);
    /* The low quality differs there only by the 25 m scale blend, which keeps the mean. */
    render_image low = render_ground(-1, 60.0);
    double mean_low[3];
    region_mean(&low, mean_low);
    for (int c = 0; c < 3; c++)
        cr_assert_lt(fabs(mean_low[c] - mean_off[c]), 0.03 * mean_off[c], "channel %d: %.2f low, %.2f default", c,
                     mean_low[c], mean_off[c]);
    render_image_free(&low);
    render_image_free(&on);
    render_image_free(&off);
    render_image_free(&near_default);
}

/* A wall in the plane x = 0, both windings (culling keeps one), its vertices' normal `normal`. */
static terrain_mesh wall_with_normal(const float normal[3]) {
    terrain_mesh mesh = { .vertex_count = 4, .index_count = 12 };
    mesh.vertices = calloc(4, sizeof *mesh.vertices);
    mesh.indices = malloc(12 * sizeof *mesh.indices);
    const float corners[4][2] = { { -50, -50 }, { -50, 50 }, { 50, 50 }, { 50, -50 } };   /* y, z */
    for (int i = 0; i < 4; i++)
        mesh.vertices[i] = (terrain_vertex){ .position = { 0, corners[i][0], corners[i][1] },
                                             .normal = { normal[0], normal[1], normal[2] }, .weights = { 255, 0, 0, 0 } };
    const uint32_t indices[12] = { 0, 1, 2, 0, 2, 3, 0, 2, 1, 0, 3, 2 };
    memcpy(mesh.indices, indices, sizeof indices);
    mesh.bounds_min[1] = mesh.bounds_min[2] = -50;
    mesh.bounds_max[1] = mesh.bounds_max[2] = 50;
    return mesh;
}

/* The wall facing `facing` (+1 or −1). */
static terrain_mesh wall(float facing) { return wall_with_normal((const float[3]){ facing, 0, 0 }); }

/* The wall seen from 4 m in front of its +x face, its normal `normal`, the sun along `sun`. */
static render_image wall_picture(const float normal[3], const float sun[3]) {
    terrain_view view = { .camera = { 4.0, 1.3, 2.1 }, .yaw = -1.5707963f, .aspect = (float)W / H,
                          .sun_direction = { sun[0], sun[1], sun[2] } };
    return render_mesh(wall_with_normal(normal), &view, &(terrain_renderer_desc){
        .sea_level = -100, .fog_density = 1e-9f, .cloud_cover = -1, .detail_distance = NO_DETAIL });
}

/* The same for the projections: each pixel reads its two largest triplanar weights, less the
 * third's. A normal leaning equally towards +y and +z (x's weight 0.75 and 0.125 each for y and
 * z, with p = 8), tipped by 0.004 one way and then the other, must give nearly the same
 * picture; the sun, symmetric in y and z, lights both alike, and both faces are steep enough
 * (over 40°) to be bare rock. The scale: the same wall leaning clearly towards y, then towards
 * z (the second projection about a seventh of the blend, as it would be at the tie without the
 * subtraction). Measured: a step of 0.08 against 2.0; without the subtraction, 1.0. */
Test(render_detail, projections_blend_without_a_step_where_the_second_and_third_swap) {
    const float sun[3] = { 0.9f, 0.3f, 0.3f };
    render_image towards_y = wall_picture((const float[3]){ 0.70f, 0.562f, 0.558f }, sun);
    render_image towards_z = wall_picture((const float[3]){ 0.70f, 0.558f, 0.562f }, sun);
    render_image leaning_y = wall_picture((const float[3]){ 0.70f, 0.562f, 0.40f }, sun);
    render_image leaning_z = wall_picture((const float[3]){ 0.70f, 0.40f, 0.562f }, sun);
    double step = mean_difference(&towards_y, &towards_z), projections = mean_difference(&leaning_y, &leaning_z);
    cr_assert_gt(projections, 1.0, "the y and z projections look alike (%.2f of 255): the test sees nothing", projections);
    cr_assert_lt(step, 0.25 * projections, "a step of %.2f where the y and z projections swap, against %.2f between them",
                 step, projections);
    render_image_free(&towards_y);
    render_image_free(&towards_z);
    render_image_free(&leaning_y);
    render_image_free(&leaning_z);
}

/* Mean luminance of the wall facing `facing`, seen from 4 m in front of it, the sun along
 * `sun_x` (±1) and a little above. */
static double wall_luminance(float facing, float sun_x) {
    /* yaw 0 looks along −z and +90° along +x: −90° looks at the +x face from +x. */
    terrain_view view = { .camera = { 4.0 * facing, 1.3, 2.1 }, .yaw = -1.5707963f * facing, .aspect = (float)W / H,
                          .sun_direction = { sun_x, 0.3f, 0 } };
    render_image image = render_mesh(wall(facing), &view, &(terrain_renderer_desc){
        .sea_level = -100, .fog_density = 1e-9f, .cloud_cover = -1 });
    double sum = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) sum += render_luminance(render_pixel(&image, x, y));
    render_image_free(&image);
    return sum / (W * H);
}

/* Normal mapping keeps each projection's sign: a face looking down −x, lit from −x, is as bright
 * as the face looking up +x lit from +x (both sample the same texels, mirrored in the picture,
 * and a slope leans the same world way on both), and both are far brighter than a face lit from
 * behind (ambient only). A normal map that dropped the sign would light the −x face from +x. */
Test(render_detail, normal_mapping_lights_both_faces_of_an_axis_alike) {
    double plus = wall_luminance(1, 1), minus = wall_luminance(-1, -1), behind = wall_luminance(1, -1);
    cr_assert_lt(fabs(plus - minus), 0.03 * plus, "+x face %.1f, −x face %.1f", plus, minus);
    cr_assert_gt(plus, 1.5 * behind, "lit %.1f, lit from behind %.1f", plus, behind);
}
