/* render_util.h — helpers the render tests share: offscreen contexts, images, captured logs. */
#ifndef RENDER_UTIL_H
#define RENDER_UTIL_H

#include "gfx/gfx.h"
#include "terrain/terrain.h"

#include <stdbool.h>
#include <stdint.h>

typedef struct render_image { int width, height; uint8_t *rgba; } render_image;

gfx_context *render_offscreen(int width, int height);
/* Draws `frames` frames of the reference scene with its default camera and reads the result. */
render_image render_scene(gfx_context *gfx, int frames);
void render_image_free(render_image *image);
const uint8_t *render_pixel(const render_image *image, int x, int y);
float render_luminance(const uint8_t *rgba);

/* Everything written to stderr between begin and end (log lines), NUL-terminated; free(). */
void render_capture_begin(void);
char *render_capture_end(void);

/* A fresh folder under /tmp with the given files written into it; returns its path (static). */
const char *render_shader_folder(const char *const *names, const char *const *texts, int count);
void render_write_file(const char *folder, const char *name, const char *text);

/* A hand-made world for terrain_world_desc.generate: bedrock rolling between −6 and +6 m,
 * periodic (40 m along x, 50 m along z; both divide 100 800 m, so the ground there is the
 * ground at the origin). */
terrain_stacks *render_rolling_chunk(void *user, terrain_chunk_coord coord);

#endif
