/* A real GLFW window (tools/test runs this binary under Xvfb when there is no display): open it,
 * draw ten frames of the reference scene, take a screenshot, and check it is not empty. */
#include "../engine/test.h"
#include "render_util.h"

#include <stb/stb_image.h>
#include <stdlib.h>
#include <unistd.h>

Test(render_window, ten_frames_and_a_screenshot) {
    if (!getenv("DISPLAY") && !getenv("WAYLAND_DISPLAY")) cr_skip_test("no display");
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 160, .height = 90, .title = "window test" });
    cr_assert(gfx);
    cr_assert_eq(gfx_backend_get(gfx), GFX_BACKEND_WINDOW, "a display exists, so a window opens");
    cr_assert_not_null(gfx_glfw_window(gfx));
    gfx_scene *scene = gfx_scene_create(gfx);
    cr_assert(scene);
    gfx_camera camera = gfx_scene_default_camera();
    for (int i = 0; i < 10; i++) {
        gfx_frame_begin(gfx);
        gfx_scene_draw(scene, &camera, i / 60.0);
        if (i < 9) gfx_frame_end(gfx);
    }
    cr_assert_not(gfx_window_should_close(gfx));
    char path[] = "/tmp/render_window_XXXXXX.png";
    close(mkstemps(path, 4));
    cr_assert(gfx_screenshot(gfx, path));
    gfx_frame_end(gfx);
    int width, height, channels;
    uint8_t *rgba = stbi_load(path, &width, &height, &channels, 4);
    unlink(path);
    cr_assert(rgba);
    /* Not one colour: the sky, the sphere and the ground all show. */
    int distinct_from_first = 0, reddish = 0, blue_top = 0;
    for (int i = 0; i < width * height; i++) {
        const uint8_t *p = rgba + i * 4;
        distinct_from_first += abs(p[0] - rgba[0]) + abs(p[1] - rgba[1]) + abs(p[2] - rgba[2]) > 30;
        reddish += p[0] > p[1] + 6 && p[0] > p[2] + 6;
        if (i < width * 5) blue_top += p[2] > p[0] + 40;
    }
    cr_assert_gt(distinct_from_first, width * height / 4);
    cr_assert_gt(reddish, 100);
    cr_assert_gt(blue_top, width * 5 * 9 / 10);
    stbi_image_free(rgba);
    gfx_scene_destroy(scene);
    gfx_context_destroy(gfx);
}
