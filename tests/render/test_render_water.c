/* Water surfaces (terrain_water.c): what the sea shows at a grazing angle and straight down,
 * that nothing above the water leaks into the refraction, that off draws nothing, that the
 * shore has no hard line, and the fog under water. Worlds are made by hand (sand under a sea at
 * 0 m), so what each pixel must show follows from the geometry: the sky mirrored in the sea
 * near the horizon, where Schlick's Fresnel term is near 1; the bottom through a metre of clear
 * water; the water's colour from below. The sky is clear and shadows and occlusion are off, so
 * that frames differ only by the water. */
#include "render_util.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DT (1.0f / 60.0f)
#define WIDTH 160
#define HEIGHT 90

typedef enum sea_kind {
    SEA_DEEP,        /* sand 30 m under the sea */
    SEA_SHALLOW,     /* sand 1 m under it */
    SEA_BLOCK,       /* deep, and a tall block of bedrock over x, z ∈ [14, 18) from 1 m to 19 m
                        above the water (nothing of it under the surface) */
    SEA_BEACH,       /* a 5 % beach rising along +x through the waterline at x = 40 */
    SEA_DRY,         /* the shallow sea's bed with no water on it: no WaterPlane of its own */
} sea_kind;

static float quantized(float metres) { return roundf(metres / TERRAIN_HEIGHT_QUANTUM) * TERRAIN_HEIGHT_QUANTUM; }

static void sea_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    sea_kind kind = *(const sea_kind *)user;
    float ground = kind == SEA_SHALLOW || kind == SEA_DRY ? -1.0f : kind == SEA_BEACH ? quantized(-2.0f + 0.05f * (float)x) : -30.0f;
    terrain_stacks_builder_push(b, TERRAIN_SAND, ground - TERRAIN_FLOOR_Y);
    if (ground < 0 && kind != SEA_DRY) terrain_stacks_builder_push(b, TERRAIN_WATER, -ground);
    if (kind == SEA_BLOCK && x >= 14 && x < 18 && z >= 14 && z < 18) {
        terrain_stacks_builder_push(b, TERRAIN_AIR, 1);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 18);
    }
}

static terrain_stacks *sea_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, sea_column, user);
}

typedef struct sea {
    sea_kind kind;
    int width, height;
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
    terrain_renderer *renderer;
    terrain_clipmap *far;            /* NULL: no far terrain (sea_add_far_terrain) */
    terrain_view view;
} sea;

/* 3 × 3 chunks around chunk (0, 0), mesh layers from −32 m to +32 m, the sea at 0 m (drawn when
 * has_sea: terrain_world_desc.sea); a frame of `scale` times WIDTH × HEIGHT. */
static void sea_open_scaled(sea *s, sea_kind kind, terrain_view view, int scale, bool has_sea) {
    memset(s, 0, sizeof *s);
    s->kind = kind;
    s->width = WIDTH * scale, s->height = HEIGHT * scale;
    s->gfx = render_offscreen(s->width, s->height);
    cr_assert_not_null(s->gfx);
    s->jobs = job_system_create(&(job_system_desc){ .threads = 2 });
    s->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = s->jobs });
    terrain_generation_desc generation = terrain_generation_defaults(5);
    generation.sea_level = 0;
    s->world = terrain_world_create(&(terrain_world_desc){ .generation = generation, .generate = sea_chunk,
                                                           .generate_user = &s->kind, .sea = has_sea });
    s->te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = s->ecs, .terrain = s->world });
    s->renderer = terrain_renderer_create(s->gfx, &(terrain_renderer_desc){
        .sea_level = 0, .cloud_cover = -1, .shadows = TERRAIN_SHADOWS_OFF, .no_occlusion = true });
    cr_assert_not_null(s->renderer);
    terrain_ecs_spawn_area(s->te, 0, 0, 1, -1, 0);
    view.aspect = (float)WIDTH / HEIGHT;
    s->view = view;
}

static void sea_open(sea *s, sea_kind kind, terrain_view view) { sea_open_scaled(s, kind, view, 1, true); }

static void sea_close(sea *s) {
    terrain_clipmap_destroy(s->far);
    terrain_ecs_destroy(s->te);
    terrain_renderer_destroy(s->renderer);
    ecs_world_destroy(s->ecs);
    terrain_world_destroy(s->world);
    job_system_destroy(s->jobs);
    gfx_context_destroy(s->gfx);
}

/* Far terrain under the sea: a generated world made flat at `ground` (the height of the hand-made
 * sea bed), so its heights, which low water takes its depth from, are the bed's. */
static void sea_add_far_terrain(sea *s, float ground) {
    terrain_generation_desc flat = terrain_generation_defaults(5);
    flat.sea_level = 0;
    flat.relief_height = 0;
    flat.base_height = ground;
    flat.vertical_perturbation = flat.horizontal_perturbation = 0;
    flat.cave_threshold = 0;
    flat.lake_spacing = 0;
    s->far = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = flat, .levels = 3, .cells = 32 });
    terrain_renderer_set_clipmap(s->renderer, s->far);
}

static terrain_water *sea_water(sea *s, terrain_water_quality quality) {
    terrain_water *water = terrain_water_create(&(terrain_water_desc){
        .gfx = s->gfx, .ecs = s->ecs, .world = s->world, .quality = quality });
    cr_assert_not_null(water);
    return water;
}

/* A frame as the game draws it (water NULL: none); the image read back. The first call lets
 * the chunks mesh and upload. */
static render_image sea_frame(sea *s, terrain_water *water) {
    for (int frame = 0; frame < 3; frame++) {
        gfx_frame_begin(s->gfx);
        if (s->far) terrain_clipmap_update(s->far, s->view.camera);
        terrain_ecs_set_view(s->te, &s->view);
        ecs_progress(s->ecs, DT);
        terrain_ecs_draw(s->te, s->renderer, &s->view);
        if (water) terrain_water_draw(water, s->te, s->renderer, &s->view);
        render_image image = { s->width, s->height, NULL };
        if (frame == 2) {
            image.rgba = malloc((size_t)s->width * (size_t)s->height * 4);
            glFinish();
            gfx_read_pixels(s->gfx, image.rgba);
        }
        gfx_frame_end(s->gfx);
        if (image.rgba) return image;
    }
    return (render_image){ 0 };
}

/* Mean colour (0…1) of the rectangle [x0, x1) × [y0, y1). */
static void mean_color(const render_image *image, int x0, int y0, int x1, int y1, float out[3]) {
    double sum[3] = { 0, 0, 0 };
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++)
            for (int c = 0; c < 3; c++) sum[c] += render_pixel(image, x, y)[c];
    for (int c = 0; c < 3; c++) out[c] = (float)(sum[c] / ((double)(x1 - x0) * (y1 - y0) * 255.0));
}

static int pixel_difference(const uint8_t *a, const uint8_t *b) {
    int most = 0;
    for (int c = 0; c < 3; c++) most = abs(a[c] - b[c]) > most ? abs(a[c] - b[c]) : most;
    return most;
}

/* Looking level over a deep sea from 2 m up, the rows just under the horizon (rays 0.3° to 2.3°
 * down) see the sea far out: Schlick's term for a flat surface there is above 0.75 (cos θ ≤
 * sin 2.7° = 0.047, F = 0.02 + 0.98·(1 − 0.047)^5 ≈ 0.78), and the mirror of such a ray is the
 * sky just as high above the horizon. So each of those rows matches, within a fifth of the
 * way to black, the row the same distance above the horizon in the frame without water; and it
 * is far from what that frame shows there without water (the sky below the horizon is the
 * horizon's colour, the sea bed nearer in is sand). Both qualities. */
Test(render_water, grazing_sea_mirrors_the_sky) {
    terrain_water_quality qualities[2] = { TERRAIN_WATER_LOW, TERRAIN_WATER_HIGH };
    for (int q = 0; q < 2; q++) {
        sea s;
        sea_open(&s, SEA_DEEP, (terrain_view){ .camera = { 16, 2, 16 } });
        render_image dry = sea_frame(&s, NULL);
        terrain_water *water = sea_water(&s, qualities[q]);
        render_image wet = sea_frame(&s, water);
        for (int d = 0; d < 4; d++) {
            float sky[3], sea_row[3];
            mean_color(&dry, 10, HEIGHT / 2 - 1 - d, WIDTH - 10, HEIGHT / 2 - d, sky);
            mean_color(&wet, 10, HEIGHT / 2 + d, WIDTH - 10, HEIGHT / 2 + d + 1, sea_row);
            for (int c = 0; c < 3; c++)
                cr_expect_leq(fabsf(sea_row[c] - sky[c]), 0.2f * sky[c] + 0.02f,
                              "%s: row %d below the horizon, channel %d: %.3f against the sky's %.3f",
                              terrain_water_quality_name(qualities[q]), d, c, sea_row[c], sky[c]);
        }
        cr_expect_eq(terrain_water_stats(water).planes_drawn, 1);
        terrain_water_destroy(water);
        render_image_free(&dry);
        render_image_free(&wet);
        sea_close(&s);
    }
}

/* Looking nearly straight down (86°) from 6 m into a metre of clear water, the middle of the
 * frame is the sand bottom seen through it: 1 m of water keeps at least e^(−0.28) ≈ 0.76 of any
 * channel (the extinction terrain.h's water model allows: red goes first, at most 0.28 a metre)
 * and the surface reflects about 2 % straight down. Through 30 m, the same view is darker and
 * greener (green's share of the colour larger) than through 1 m. */
Test(render_water, shallow_water_shows_the_bottom_deep_water_is_dark_and_green) {
    terrain_view down = { .camera = { 16, 6, 16 }, .pitch = -1.5f };
    float bottom[3], shallow[3], deep[3];
    sea s;
    sea_open(&s, SEA_SHALLOW, down);
    render_image dry = sea_frame(&s, NULL);
    terrain_water *water = sea_water(&s, TERRAIN_WATER_LOW);
    render_image wet = sea_frame(&s, water);
    mean_color(&dry, 60, 30, 100, 60, bottom);
    mean_color(&wet, 60, 30, 100, 60, shallow);
    for (int c = 0; c < 3; c++) {
        cr_expect_geq(shallow[c], 0.72f * bottom[c], "channel %d: %.3f through 1 m, bottom %.3f", c, shallow[c], bottom[c]);
        cr_expect_leq(shallow[c], bottom[c] + 0.06f, "channel %d: %.3f through 1 m, bottom %.3f", c, shallow[c], bottom[c]);
    }
    terrain_water_destroy(water);
    render_image_free(&dry);
    render_image_free(&wet);
    sea_close(&s);

    sea_open(&s, SEA_DEEP, down);
    water = sea_water(&s, TERRAIN_WATER_LOW);
    wet = sea_frame(&s, water);
    mean_color(&wet, 60, 30, 100, 60, deep);
    float shallow_sum = shallow[0] + shallow[1] + shallow[2], deep_sum = deep[0] + deep[1] + deep[2];
    cr_expect_lt(deep_sum, 0.6f * shallow_sum, "deep %.3f, shallow %.3f", deep_sum, shallow_sum);
    cr_expect_gt(deep[1] / deep_sum, shallow[1] / shallow_sum, "green share: deep %.3f, shallow %.3f",
                 deep[1] / deep_sum, shallow[1] / shallow_sum);
    cr_expect_gt(deep[1], deep[0], "deep water is greener than red: %.3f %.3f", deep[1], deep[0]);
    terrain_water_destroy(water);
    render_image_free(&wet);
    sea_close(&s);
}

/* Low blends the water over the frame and reads none of it; medium copies the frame and
 * refracts the copy. Over a flat bed the two compute the same light (the same transmittance
 * through the same thickness: the depth under the surface over the view ray's slope equals the
 * scene's distance behind the surface), so their mean colours over the sea agree; what differs
 * is medium's distortion of the bed by the waves, which averages out. Through 1 m at 25° below
 * the horizon (a factor 0.8 off in low's blending fails it), and 30 m looking down. Without far terrain, low has no depth to go by and
 * reads the frame as medium does. */
Test(render_water, low_reads_nothing_and_looks_as_medium_does) {
    const sea_kind kinds[2] = { SEA_SHALLOW, SEA_DEEP };
    const float grounds[2] = { -1.0f, -30.0f };
    const terrain_view views[2] = { { .camera = { 16, 6, 16 }, .pitch = -1.5f },
                                { .camera = { 16, 6, 0 }, .pitch = -0.44f } };
    for (int k = 0; k < 2; k++) {
        int v = 1 - k;                               /* 1 m at a slant, 30 m looking down */
        sea s;
        sea_open(&s, kinds[k], views[v]);
        sea_add_far_terrain(&s, grounds[k]);
        terrain_water *water = sea_water(&s, TERRAIN_WATER_MEDIUM);
        render_image medium = sea_frame(&s, water);
        cr_expect(terrain_water_stats(water).frame_read);
        cr_assert(terrain_water_set_quality(water, TERRAIN_WATER_LOW));
        render_image low = sea_frame(&s, water);
        cr_expect_not(terrain_water_stats(water).frame_read, "low read the frame");
        cr_expect_eq(terrain_water_stats(water).planes_drawn, 1);
        float a[3], b[3];
        mean_color(&medium, 20, 50, 140, 85, a);
        mean_color(&low, 20, 50, 140, 85, b);
        for (int c = 0; c < 3; c++)
            cr_expect_leq(fabsf(a[c] - b[c]), 0.04f, "kind %d view %d channel %d: medium %.3f, low %.3f", k, v, c, a[c], b[c]);
        terrain_water_destroy(water);
        render_image_free(&medium);
        render_image_free(&low);
        sea_close(&s);
    }
    sea s;
    sea_open(&s, SEA_SHALLOW, views[0]);
    terrain_water *water = sea_water(&s, TERRAIN_WATER_LOW);
    render_image image = sea_frame(&s, water);
    cr_expect(terrain_water_stats(water).frame_read, "low without far terrain did not read the frame");
    terrain_water_destroy(water);
    render_image_free(&image);
    sea_close(&s);
}

/* A tall block stands over the sea, all of it above the surface. Seen from 9 m away, a little
 * from above, the water around it must look as without the block wherever the water is seen
 * (outside the block's own silhouette): a refraction that took the block's colour at a
 * distorted position (a pixel or two from its edge) would differ there by far more than the
 * tolerance, which allows only for the depth mask picking the undistorted point of a deep,
 * dark sea bed. (Without the mask, this test fails: checked by hand.) */
Test(render_water, nothing_above_the_water_leaks_into_the_refraction) {
    terrain_view view = { .camera = { 16, 4, 7 }, .yaw = 3.14159265f, .pitch = -0.3f };
    render_image dry[2], wet[2];
    sea_kind kinds[2] = { SEA_DEEP, SEA_BLOCK };
    for (int k = 0; k < 2; k++) {
        sea s;
        sea_open_scaled(&s, kinds[k], view, 4, true);
        dry[k] = sea_frame(&s, NULL);
        terrain_water *water = sea_water(&s, TERRAIN_WATER_LOW);
        wet[k] = sea_frame(&s, water);
        terrain_water_destroy(water);
        sea_close(&s);
    }
    int compared = 0, leaks = 0, block = 0, worst = 0;
    for (int y = 0; y < 4 * HEIGHT; y++)
        for (int x = 0; x < 4 * WIDTH; x++) {
            bool near_block = pixel_difference(render_pixel(&dry[0], x, y), render_pixel(&dry[1], x, y)) > 2;
            block += near_block;
            bool water_here = pixel_difference(render_pixel(&dry[0], x, y), render_pixel(&wet[0], x, y)) > 2;
            if (near_block || !water_here) continue;
            compared++;
            int difference = pixel_difference(render_pixel(&wet[0], x, y), render_pixel(&wet[1], x, y));
            worst = difference > worst ? difference : worst;
            leaks += difference > 6;
        }
    cr_expect_gt(block, 1600, "the block covers %d pixels", block);
    cr_expect_gt(compared, 16 * WIDTH * HEIGHT / 4, "%d water pixels compared", compared);
    cr_expect_eq(leaks, 0, "%d water pixels show the block (worst difference %d)", leaks, worst);
    for (int k = 0; k < 2; k++) render_image_free(&dry[k]), render_image_free(&wet[k]);
}

/* Off: the frame is the frame without a water object, bit for bit, and nothing is counted. */
Test(render_water, off_draws_nothing) {
    sea s;
    sea_open(&s, SEA_SHALLOW, (terrain_view){ .camera = { 16, 4, 16 }, .pitch = -0.4f });
    render_image without = sea_frame(&s, NULL);
    terrain_water *water = sea_water(&s, TERRAIN_WATER_OFF);
    render_image off = sea_frame(&s, water);
    cr_expect_eq(memcmp(without.rgba, off.rgba, WIDTH * HEIGHT * 4), 0, "water off changed the frame");
    cr_expect_eq(terrain_water_stats(water).planes_drawn, 0);
    /* And back on, it draws: the same call site is live. */
    cr_expect(terrain_water_set_quality(water, TERRAIN_WATER_LOW));
    render_image on = sea_frame(&s, water);
    cr_expect_neq(memcmp(without.rgba, on.rgba, WIDTH * HEIGHT * 4), 0, "water low drew nothing");
    terrain_water_destroy(water);
    render_image_free(&without);
    render_image_free(&off);
    render_image_free(&on);
    sea_close(&s);
}

/* Water out of sight: looking up into the sky from above the sea (every ray at least 39° up),
 * no water pixel passes the depth test, so from the frame after the first the water only probes
 * (an occlusion query, no colour written, no copy of the frame): nothing is counted as drawn and
 * the frame is the frame without water, bit for bit. */
Test(render_water, water_out_of_sight_is_only_probed) {
    sea s;
    sea_open(&s, SEA_DEEP, (terrain_view){ .camera = { 16, 4, 16 }, .pitch = 1.2f });
    render_image dry = sea_frame(&s, NULL);
    terrain_water *water = sea_water(&s, TERRAIN_WATER_HIGH);
    render_image wet = sea_frame(&s, water);
    cr_expect_eq(memcmp(dry.rgba, wet.rgba, WIDTH * HEIGHT * 4), 0, "hidden water changed the frame");
    cr_expect_eq(terrain_water_stats(water).planes_drawn, 0);
    terrain_water_destroy(water);
    render_image_free(&dry);
    render_image_free(&wet);
    sea_close(&s);
}

/* Along a 5 % beach seen from 3 m up, 18 m before the waterline, the water adds to the frame a
 * change (water frame − dry frame) that grows from nothing at the waterline. A hard edge would
 * add, in one pixel step, the reflection at that angle (Schlick at 9.5° down: F ≈ 0.42 of the
 * sky against sand, about 0.15 to 0.2 a channel); a soft shore changes by less than 0.06 a
 * channel between vertical neighbours across the waterline, in every column. */
Test(render_water, the_shore_fades_without_a_hard_line) {
    sea s;
    sea_open(&s, SEA_BEACH, (terrain_view){ .camera = { 22, 3, 16 }, .yaw = 1.5707963f, .pitch = -0.25f });
    render_image dry = sea_frame(&s, NULL);
    terrain_water *water = sea_water(&s, TERRAIN_WATER_LOW);
    render_image wet = sea_frame(&s, water);
    int columns = 0, worst = 0, worst_x = 0, worst_y = 0;
    for (int x = 8; x < WIDTH - 8; x++) {
        /* The waterline: going up from the bottom row (water), the first row the water left
         * alone is dry beach. (Beyond the beach, past the hand-made chunks, the sea shows
         * again: that edge of the world is no shore.) */
        int line = -1;
        for (int y = HEIGHT - 1; y > 0 && line < 0; y--)
            if (pixel_difference(render_pixel(&dry, x, y - 1), render_pixel(&wet, x, y - 1)) <= 2) line = y;
        if (line < 4 || line > HEIGHT - 12) continue;
        columns++;
        for (int y = line - 3; y < line + 8; y++) {
            int step = 0;
            for (int c = 0; c < 3; c++) {
                int above = render_pixel(&wet, x, y)[c] - render_pixel(&dry, x, y)[c];
                int below = render_pixel(&wet, x, y + 1)[c] - render_pixel(&dry, x, y + 1)[c];
                step = abs(below - above) > step ? abs(below - above) : step;
            }
            if (step > worst) worst = step, worst_x = x, worst_y = y;
        }
    }
    cr_expect_gt(columns, WIDTH / 2, "the waterline crosses %d columns", columns);
    cr_expect_leq(worst, 15, "a step of %d/255 at (%d, %d)", worst, worst_x, worst_y);
    terrain_water_destroy(water);
    render_image_free(&dry);
    render_image_free(&wet);
    sea_close(&s);
}

/* Two metres under the sea, looking level: the middle of the frame is water seen over metres
 * (the bottom 28 m down, the surface above, both far along such rays), so the fog of water
 * covers it: blue-green (green and blue each well over twice red), dark, and unlike the frame
 * drawn without water. */
Test(render_water, under_water_the_frame_is_tinted) {
    sea s;
    sea_open(&s, SEA_DEEP, (terrain_view){ .camera = { 16, -2, 16 } });
    render_image dry = sea_frame(&s, NULL);
    terrain_water *water = sea_water(&s, TERRAIN_WATER_LOW);
    render_image wet = sea_frame(&s, water);
    cr_expect(terrain_water_stats(water).under_water);
    float tinted[3], plain[3];
    mean_color(&wet, 20, HEIGHT / 2 - 10, WIDTH - 20, HEIGHT / 2 + 10, tinted);
    mean_color(&dry, 20, HEIGHT / 2 - 10, WIDTH - 20, HEIGHT / 2 + 10, plain);
    cr_expect_gt(tinted[1], 2 * tinted[0], "green %.3f, red %.3f", tinted[1], tinted[0]);
    cr_expect_gt(tinted[2], 2 * tinted[0], "blue %.3f, red %.3f", tinted[2], tinted[0]);
    cr_expect_lt(tinted[0] + tinted[1] + tinted[2], 1.0f, "under water is dark: %.3f", tinted[0] + tinted[1] + tinted[2]);
    float change = fabsf(tinted[0] - plain[0]) + fabsf(tinted[1] - plain[1]) + fabsf(tinted[2] - plain[2]);
    cr_expect_gt(change, 0.3f, "the tint changed the frame by %.3f", change);
    terrain_water_destroy(water);
    render_image_free(&dry);
    render_image_free(&wet);
    sea_close(&s);
}

/* The surface seen from below: looking up from 2 m under it (86° up), every ray meets it within
 * 34° of the vertical, inside the critical angle (asin(1/1.33) ≈ 48.8°), so the sky shows
 * through, bright and blue; looking 11° up, the rays above the middle meet it 49° to 79° from
 * the vertical, past the critical angle: total internal reflection, the water's own dark colour.
 * The first is more than twice as bright as the second. */
Test(render_water, from_below_the_sky_shows_through_the_window_and_not_past_it) {
    float window[3], beyond[3];
    float pitches[2] = { 1.5f, 0.2f };
    for (int p = 0; p < 2; p++) {
        sea s;
        sea_open(&s, SEA_DEEP, (terrain_view){ .camera = { 16, -2, 16 }, .pitch = pitches[p] });
        terrain_water *water = sea_water(&s, TERRAIN_WATER_LOW);
        render_image wet = sea_frame(&s, water);
        if (p == 0) mean_color(&wet, 40, 20, WIDTH - 40, HEIGHT - 20, window);
        else mean_color(&wet, 20, 0, WIDTH - 20, HEIGHT / 2 - 5, beyond);
        terrain_water_destroy(water);
        render_image_free(&wet);
        sea_close(&s);
    }
    float window_sum = window[0] + window[1] + window[2], beyond_sum = beyond[0] + beyond[1] + beyond[2];
    cr_expect_gt(window_sum, 2 * beyond_sum, "through the window %.3f, past the critical angle %.3f", window_sum,
                 beyond_sum);
    cr_expect_gt(window[2], window[0], "the sky through the window is blue: %.3f %.3f %.3f", window[0], window[1],
                 window[2]);
}

/* Lakes: a WaterPlane component (as the mesh phase attaches them) draws its plane over the cells
 * its row mask names, and at most one cell beyond (the mask is widened by a cell so that the
 * depth test and the shore draw the waterline, not the cells' square edges): a lake over the
 * west half of a chunk (x < 16) changes that half of the view from above, and beyond x = 17
 * the view stays as it was. */
Test(render_water, a_lake_plane_covers_its_cells_only) {
    sea s;
    /* A dry bed at −1 m, no sea (so the mesh phase attaches no WaterPlane): the only plane is
     * this test's, at 0.5 m over the west half of chunk (0, 0). */
    sea_open_scaled(&s, SEA_DRY, (terrain_view){ .camera = { 16, 30, 16 }, .pitch = -1.5f }, 1, false);
    render_image dry = sea_frame(&s, NULL);
    terrain_water *water = terrain_water_create(&(terrain_water_desc){
        .gfx = s.gfx, .ecs = s.ecs, .world = s.world });
    cr_assert_not_null(water);
    ecs_component plane_c = ecs_component_lookup(s.ecs, "WaterPlane");
    cr_assert_neq(plane_c, 0);
    WaterPlane plane = { .origin = { 0, 0, 0 }, .cell = 1, .count = 1 };
    plane.planes[0].height = 0.5f;
    plane.planes[0].deepest = -1;
    for (int k = 0; k < TERRAIN_MESH_CELLS; k++) plane.planes[0].rows[k] = 0xffffu;   /* cells x < 16 */
    ecs_set(s.ecs, ecs_entity_create(s.ecs), plane_c, &plane);
    render_image wet = sea_frame(&s, water);
    cr_expect_eq(terrain_water_stats(water).planes_drawn, 1);
    /* Camera 30 m over x = 16 looking down (86°): the frame's 80 half-columns span 30·tan 30°·16/9
     * ≈ 30 m each way, so columns 45…74 see x ≈ 3…14 m (lake) and 86…115 x ≈ 18…29 m (none);
     * the middle rows see z ≈ 12…20 m, inside the chunk. */
    int left_changed = 0, right_changed = 0, pixels = 0;
    for (int y = 35; y < 55; y++)
        for (int x = 0; x < 30; x++, pixels++) {
            left_changed += pixel_difference(render_pixel(&dry, 45 + x, y), render_pixel(&wet, 45 + x, y)) > 2;
            right_changed += pixel_difference(render_pixel(&dry, 86 + x, y), render_pixel(&wet, 86 + x, y)) > 2;
        }
    cr_expect_gt(left_changed, pixels * 9 / 10, "%d of %d pixels over the lake changed", left_changed, pixels);
    cr_expect_eq(right_changed, 0, "%d pixels beside the lake changed", right_changed);
    terrain_water_destroy(water);
    render_image_free(&dry);
    render_image_free(&wet);
    sea_close(&s);
}

Test(render_water, qualities_parse_and_bad_input_is_refused) {
    terrain_water_quality q = TERRAIN_WATER_DEFAULT;
    cr_expect(terrain_water_parse_quality("off", &q) && q == TERRAIN_WATER_OFF);
    cr_expect(terrain_water_parse_quality("low", &q) && q == TERRAIN_WATER_LOW);
    cr_expect(terrain_water_parse_quality("medium", &q) && q == TERRAIN_WATER_MEDIUM);
    cr_expect(terrain_water_parse_quality("high", &q) && q == TERRAIN_WATER_HIGH);
    cr_expect(!terrain_water_parse_quality("ultra", &q));
    cr_expect(!terrain_water_parse_quality(NULL, &q));
    cr_expect_str_eq(terrain_water_quality_name(TERRAIN_WATER_DEFAULT), "low");
    cr_expect_str_eq(terrain_water_quality_name(TERRAIN_WATER_MEDIUM), "medium");
    cr_expect_str_eq(terrain_water_quality_name(TERRAIN_WATER_HIGH), "high");
    render_capture_begin();
    cr_expect_null(terrain_water_create(&(terrain_water_desc){ 0 }));
    free(render_capture_end());
}
