/* render_util.c — see render_util.h. */
#include "render_util.h"

#include <math.h>

#include "core/core.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

gfx_context *render_offscreen(int width, int height) {
    return gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .headless = true });
}

render_image render_scene(gfx_context *gfx, int frames) {
    gfx_scene *scene = gfx_scene_create(gfx);
    render_image image = { 0 };
    if (!scene) return image;
    gfx_camera camera = gfx_scene_default_camera();
    for (int i = 0; i < frames; i++) {
        gfx_frame_begin(gfx);
        gfx_scene_draw(scene, &camera, 0.0);
        if (i + 1 < frames) gfx_frame_end(gfx);
    }
    gfx_size(gfx, &image.width, &image.height);
    image.rgba = malloc((size_t)image.width * (size_t)image.height * 4);
    glFinish();
    gfx_read_pixels(gfx, image.rgba);
    gfx_frame_end(gfx);
    gfx_scene_destroy(scene);
    return image;
}

void render_image_free(render_image *image) {
    free(image->rgba);
    image->rgba = NULL;
}

const uint8_t *render_pixel(const render_image *image, int x, int y) {
    return image->rgba + ((size_t)y * (size_t)image->width + (size_t)x) * 4;
}

float render_luminance(const uint8_t *rgba) {
    return 0.2126f * rgba[0] + 0.7152f * rgba[1] + 0.0722f * rgba[2];
}

static int render_saved_stderr = -1;
static FILE *render_capture_file;

void render_capture_begin(void) {
    fflush(stderr);
    render_capture_file = tmpfile();
    render_saved_stderr = dup(2);
    dup2(fileno(render_capture_file), 2);
}

char *render_capture_end(void) {
    fflush(stderr);
    dup2(render_saved_stderr, 2);
    close(render_saved_stderr);
    long size = ftell(render_capture_file);
    char *text = calloc(1, (size_t)(size > 0 ? size : 0) + 1);
    rewind(render_capture_file);
    if (size > 0 && fread(text, 1, (size_t)size, render_capture_file) != (size_t)size) text[0] = 0;
    fclose(render_capture_file);
    fprintf(stderr, "%s", text);   /* still shown in the test's output */
    return text;
}

void render_write_file(const char *folder, const char *name, const char *text) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s", folder, name);
    FILE *file = fopen(path, "wb");
    if (!file) return;
    fputs(text, file);
    fclose(file);
}

const char *render_shader_folder(const char *const *names, const char *const *texts, int count) {
    static char folder[64];
    snprintf(folder, sizeof folder, "/tmp/render_test_XXXXXX");
    if (!mkdtemp(folder)) return NULL;
    for (int i = 0; i < count; i++) render_write_file(folder, names[i], texts[i]);
    return folder;
}

static void rolling_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    double h = 4.0 * sin((double)x * (2.0 * M_PI / 40.0)) + 2.0 * cos((double)z * (2.0 * M_PI / 50.0));
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(h - TERRAIN_FLOOR_Y));
}

terrain_stacks *render_rolling_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, rolling_column, user);
}
