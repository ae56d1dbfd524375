/* The reference scene through OSMesa, checked by what a viewer would see: sky at the top, the
 * sphere where projection puts it and of the size it should have, lit from the sun's side, in
 * front of the ground (depth), a grid on the ground; and against a reviewed golden image. */
#include "../engine/test.h"
#include "render_util.h"

#include <math.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
#include <stdlib.h>

#define W 160
#define H 90
#define FOV_Y (60.0 * M_PI / 180.0)
#define NEAR 0.1
#define FAR 2000.0

/* Only the sphere is redder than it is green or blue (ground, grid and sky lean blue). */
static bool is_sphere(const uint8_t *p) { return p[0] > p[1] + 6 && p[0] > p[2] + 6; }

Test(render_scene, sky_fills_the_top_rows) {
    gfx_context *gfx = render_offscreen(W, H);
    cr_assert(gfx);
    render_image image = render_scene(gfx, 2);
    int blue = 0, total = 0;
    for (int y = 0; y < H / 8; y++)
        for (int x = 0; x < W; x++, total++) {
            const uint8_t *p = render_pixel(&image, x, y);
            blue += p[2] > p[0] + 40 && p[2] > p[1] && p[2] > 150;
        }
    cr_assert_geq(blue, total * 98 / 100, "only %d of %d top pixels are sky blue", blue, total);
    render_image_free(&image);
    gfx_context_destroy(gfx);
}

Test(render_scene, sphere_sits_where_projection_puts_it) {
    gfx_context *gfx = render_offscreen(W, H);
    render_image image = render_scene(gfx, 2);
    /* The camera looks at the sphere's centre from D away: the disc is centred, and its radius
     * is tan(asin(1/D)) / tan(fov/2) of half the height. */
    double distance = sqrt(0.6 * 0.6 + 5.0 * 5.0);
    double radius = tan(asin(1.0 / distance)) / tan(FOV_Y / 2) * (H / 2.0);
    int covered = 0, outside = 0;
    double sum_x = 0, sum_y = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (!is_sphere(render_pixel(&image, x, y))) continue;
            covered++;
            sum_x += x + 0.5;
            sum_y += y + 0.5;
            double dx = x + 0.5 - W / 2.0, dy = y + 0.5 - H / 2.0;
            outside += sqrt(dx * dx + dy * dy) > radius + 1.5;
        }
    double expected = M_PI * radius * radius;
    cr_assert(covered > expected * 0.9 && covered < expected * 1.1,
              "sphere covers %d pixels, expected about %.0f", covered, expected);
    cr_assert_eq(outside, 0, "%d sphere-coloured pixels outside the disc of radius %.1f", outside, radius);
    cr_assert(fabs(sum_x / covered - W / 2.0) < 1.0 && fabs(sum_y / covered - H / 2.0) < 1.0,
              "disc centred at (%.1f, %.1f)", sum_x / covered, sum_y / covered);
    render_image_free(&image);
    gfx_context_destroy(gfx);
}

Test(render_scene, sphere_is_lit_from_the_suns_side) {
    gfx_context *gfx = render_offscreen(W, H);
    render_image image = render_scene(gfx, 2);
    /* At time 0 the sun is at x = cos(2.4) < 0: the left half of the disc faces it. */
    double left = 0, right = 0;
    int left_count = 0, right_count = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const uint8_t *p = render_pixel(&image, x, y);
            if (!is_sphere(p)) continue;
            if (x < W / 2) { left += render_luminance(p); left_count++; }
            else { right += render_luminance(p); right_count++; }
        }
    cr_assert(left_count > 0 && right_count > 0);
    cr_assert_gt(left / left_count, 1.5 * right / right_count, "left %.1f, right %.1f",
                 left / left_count, right / right_count);
    render_image_free(&image);
    gfx_context_destroy(gfx);
}

Test(render_scene, ground_shows_grid_lines) {
    gfx_context *gfx = render_offscreen(W, H);
    render_image image = render_scene(gfx, 2);
    int dark = 0, total = 0;
    for (int y = H - H / 5; y < H; y++)
        for (int x = 0; x < W; x++, total++) dark += render_luminance(render_pixel(&image, x, y)) < 70;
    cr_assert(dark > total / 50 && dark < total * 2 / 5, "%d of %d ground pixels on lines", dark, total);
    render_image_free(&image);
    gfx_context_destroy(gfx);
}

/* View-space distance along the camera's axis from a depth-buffer value. */
static double eye_depth(float stored) {
    double ndc = 2.0 * stored - 1.0;
    return 2.0 * NEAR * FAR / (FAR + NEAR - ndc * (FAR - NEAR));
}

Test(render_scene, depth_puts_the_sphere_in_front_of_the_ground) {
    gfx_context *gfx = render_offscreen(W, H);
    gfx_scene *scene = gfx_scene_create(gfx);
    cr_assert(scene);
    gfx_camera camera = gfx_scene_default_camera();
    gfx_frame_begin(gfx);
    gfx_scene_draw(scene, &camera, 0.0);
    float centre = 0, bottom = 0;
    /* Inside the frame: gfx_frame_end clears the depth for the next one. GL rows count from the
     * bottom: row H/2 is the centre; row 0 the bottom edge. */
    glReadPixels(W / 2, H / 2, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &centre);
    glReadPixels(W / 2, 0, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &bottom);
    gfx_frame_end(gfx);
    gfx_scene_destroy(scene);
    /* Centre: the sphere's near surface, D − 1 away along the view axis. */
    double distance = sqrt(0.6 * 0.6 + 5.0 * 5.0);
    cr_assert(fabs(eye_depth(centre) - (distance - 1.0)) < 0.05, "centre depth %.3f, expected %.3f",
              eye_depth(centre), distance - 1.0);
    /* Bottom row: the ray (0, ndc_y·tan(fov/2), −1) in view space meets the ground y = 0. */
    double pitch = atan(0.6 / 5.0), ndc_y = (0.5 / H) * 2.0 - 1.0, slope = ndc_y * tan(FOV_Y / 2);
    double drop_per_unit = -(slope * cos(pitch) - sin(pitch));   /* world y falls this much per unit */
    double expected = 1.6 / drop_per_unit;
    cr_assert(fabs(eye_depth(bottom) - expected) < 0.02, "bottom depth %.3f, expected %.3f",
              eye_depth(bottom), expected);
    cr_assert_lt(eye_depth(centre), 13.0, "the ground behind the sphere must not show through");
    gfx_context_destroy(gfx);
}

/* A reviewed image of the scene at 160×90 lives in tests/render/golden/. Renderers differ in
 * the last bits (rasterisation rules, precision), so the test allows a small mean difference and
 * a few stray pixels. RENDER_UPDATE_GOLDEN=1 rewrites it (then look at it before committing). */
Test(render_scene, matches_the_golden_image) {
    const char *path = "tests/render/golden/scene_160x90.png";
    gfx_context *gfx = render_offscreen(W, H);
    render_image image = render_scene(gfx, 2);
    if (getenv("RENDER_UPDATE_GOLDEN")) {
        for (int i = 3; i < W * H * 4; i += 4) image.rgba[i] = 255;
        cr_assert(stbi_write_png(path, W, H, 4, image.rgba, W * 4));
    }
    int width, height, channels;
    uint8_t *golden = stbi_load(path, &width, &height, &channels, 4);
    cr_assert(golden, "cannot read %s (run from the repository root)", path);
    cr_assert(width == W && height == H);
    double sum = 0;
    int far_off = 0;
    for (int i = 0; i < W * H; i++) {
        int worst = 0;
        for (int c = 0; c < 3; c++) {
            int d = abs((int)image.rgba[i * 4 + c] - (int)golden[i * 4 + c]);
            sum += d;
            if (d > worst) worst = d;
        }
        far_off += worst > 32;
    }
    double mean = sum / (W * H * 3);
    cr_assert_lt(mean, 2.0, "mean difference %.2f from the golden image", mean);
    cr_assert_leq(far_off, W * H / 100, "%d pixels differ by more than 32", far_off);
    stbi_image_free(golden);
    render_image_free(&image);
    gfx_context_destroy(gfx);
}
