/* Ambient occlusion through OSMesa: the mesher's per-vertex occlusion (terrain_vertex.occlusion)
 * darkens the floor of a cave closed on every side, seen from inside, by a clear margin against
 * the same meshes drawn with terrain_renderer_desc.no_occlusion; open flat ground in the sun is
 * drawn the same either way (its openness is 1, which the shader leaves unchanged). */
#include "../engine/test.h"
#include "render_util.h"

#include "terrain/terrain.h"

#include <math.h>
#include <stdlib.h>

#define W 96
#define H 64

/* A plain at 10 m; under columns −8 … 7 × −8 … 7 a cave: bedrock to 2 m, air to 6 m, then a
 * 4 m roof up to the plain. */
static void cave_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    if (x >= -8 && x <= 7 && z >= -8 && z <= 7) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 2.0f - TERRAIN_FLOOR_Y);
        terrain_stacks_builder_push(b, TERRAIN_AIR, 4.0f);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 4.0f);
    } else {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.0f - TERRAIN_FLOOR_Y);
    }
}

static terrain_stacks *cave_chunk(void *user, terrain_chunk_coord c) { return terrain_stacks_from_columns(c, cave_column, user); }

/* Straight down from `eye`, the default sun (from the side: it lights the cave's floor too, as
 * nothing casts shadows). */
static render_image draw_down(gfx_context *gfx, terrain_renderer *renderer, const terrain_gpu_mesh *meshes, int count,
                              const double eye[3]) {
    terrain_view view = { .camera = { eye[0], eye[1], eye[2] }, .pitch = -1.5707f, .aspect = (float)W / H };
    gfx_frame_begin(gfx);
    terrain_renderer_draw(renderer, &view, meshes, count);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(gfx, image.rgba);
    gfx_frame_end(gfx);
    return image;
}

static double mean_luminance(const render_image *image) {
    double sum = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) sum += render_luminance(render_pixel(image, x, y));
    return sum / (W * H);
}

Test(render_ao, a_cave_floor_darkens_and_open_ground_does_not_change) {
    gfx_context *gfx = render_offscreen(W, H);
    /* occlusion alone: the sun shines into the cave without a shadow map */
    terrain_renderer *lit = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -50, .shadows = TERRAIN_SHADOWS_OFF });
    terrain_renderer *flat = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -50, .no_occlusion = true,
                                                                                   .shadows = TERRAIN_SHADOWS_OFF });
    cr_assert(lit && flat);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = cave_chunk });
    /* The four chunks around the cave, and one of open plain from 32 to 64 m in x and z. */
    const int64_t chunks[5][3] = { { -1, 0, -1 }, { 0, 0, -1 }, { -1, 0, 0 }, { 0, 0, 0 }, { 1, 0, 1 } };
    terrain_gpu_mesh gpu[5];
    int occluded = 0;
    for (int c = 0; c < 5; c++) {
        terrain_mesh mesh;
        cr_assert(terrain_mesh_chunk(world, chunks[c][0], chunks[c][1], chunks[c][2], NULL, &mesh));
        for (uint32_t v = 0; v < mesh.vertex_count; v++) occluded += mesh.vertices[v].occlusion > 128;
        gpu[c] = terrain_gpu_mesh_upload(&mesh);
        terrain_mesh_free(&mesh);
    }
    cr_assert_gt(occluded, 0, "the cave's vertices are mostly closed in");

    /* From the middle of the cave, 2.5 m above its floor: the view holds only floor. */
    const double in_cave[3] = { 0.0, 4.5, 0.0 };
    render_image cave_ao = draw_down(gfx, lit, gpu, 5, in_cave), cave_plain = draw_down(gfx, flat, gpu, 5, in_cave);
    double with = mean_luminance(&cave_ao), without = mean_luminance(&cave_plain);
    /* The floor's openness is small (the roof 4 m up closes every ray): the sky ambient goes
     * nearly to 0 and the sun to ~0.45 of itself, so the floor keeps well under ¾ of its light. */
    cr_expect_lt(with, 0.75 * without, "the cave floor: %.1f with occlusion, %.1f without", with, without);
    cr_expect_gt(without, 20.0, "the floor is lit at all without occlusion (%.1f)", without);

    /* Open plain, 10 m up, far (> 20 m) from the cave: the same picture within rounding. */
    const double over_plain[3] = { 48.0, 20.0, 48.0 };
    render_image open_ao = draw_down(gfx, lit, gpu, 5, over_plain), open_plain = draw_down(gfx, flat, gpu, 5, over_plain);
    int largest = 0;
    for (int i = 0; i < W * H * 4; i++) {
        int d = abs((int)open_ao.rgba[i] - (int)open_plain.rgba[i]);
        largest = d > largest ? d : largest;
    }
    cr_expect_leq(largest, 1, "open ground differs by %d levels", largest);
    cr_expect_gt(mean_luminance(&open_ao), 40.0, "the plain is in the sun");

    render_image_free(&cave_ao);
    render_image_free(&cave_plain);
    render_image_free(&open_ao);
    render_image_free(&open_plain);
    for (int c = 0; c < 5; c++) terrain_gpu_mesh_destroy(&gpu[c]);
    terrain_world_destroy(world);
    terrain_renderer_destroy(lit);
    terrain_renderer_destroy(flat);
    gfx_context_destroy(gfx);
}
