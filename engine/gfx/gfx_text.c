/* gfx_text.c — HUD text: strings queued during a frame become quads (stb_easy_font builds each
 * glyph from little rectangles, so no font file or texture is needed) drawn in one pass over the
 * frame, with a one-pixel shadow so the text reads on sky and ground alike. */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* stb_easy_font.h is header-only with static functions; it shadows nothing of ours. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

#define GFX_TEXT_MAX_QUADS 16384

typedef struct gfx_text_vertex { float x, y, z; uint8_t color[4]; } gfx_text_vertex;   /* stb's layout */

struct gfx_text {
    gfx_context *gfx;
    gfx_program program;
    gfx_buffer vertices, indices;
    gfx_vertex_array array;
    gfx_text_vertex *queued;          /* 4 per quad */
    int quad_count;
};

gfx_text *gfx_text_create(gfx_context *gfx) {
    gfx_program program = gfx_program_load(gfx, "text.vert", "text.frag");
    if (!program.id) return NULL;
    gfx_text *t = core_calloc(1, sizeof *t);
    t->gfx = gfx;
    t->program = program;
    t->queued = core_alloc(GFX_TEXT_MAX_QUADS * 4 * sizeof *t->queued);
    /* Quads as two triangles each: one index buffer for all. */
    uint32_t *indices = core_alloc(GFX_TEXT_MAX_QUADS * 6 * sizeof *indices);
    for (uint32_t q = 0; q < GFX_TEXT_MAX_QUADS; q++) {
        const uint32_t base = q * 4, pattern[6] = { 0, 1, 2, 0, 2, 3 };
        for (int k = 0; k < 6; k++) indices[q * 6 + (uint32_t)k] = base + pattern[k];
    }
    t->indices = gfx_buffer_create(&(gfx_buffer_desc){ .size = GFX_TEXT_MAX_QUADS * 6 * sizeof *indices, .data = indices });
    core_free(indices, GFX_TEXT_MAX_QUADS * 6 * sizeof *indices);
    t->vertices = gfx_buffer_create(&(gfx_buffer_desc){ .size = GFX_TEXT_MAX_QUADS * 4 * sizeof *t->queued,
                                                        .usage = GFX_BUFFER_DYNAMIC });
    t->array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = t->vertices, .vertex_stride = sizeof(gfx_text_vertex), .indices = t->indices,
        .attributes = { { .components = 3 },
                        { .components = 4, .type = GL_UNSIGNED_BYTE, .normalized = true,
                          .offset = offsetof(gfx_text_vertex, color) } } });
    return t;
}

void gfx_text_destroy(gfx_text *t) {
    if (!t) return;
    gfx_vertex_array_destroy(&t->array);
    gfx_buffer_destroy(&t->vertices);
    gfx_buffer_destroy(&t->indices);
    core_free(t->queued, GFX_TEXT_MAX_QUADS * 4 * sizeof *t->queued);
    core_free(t, sizeof *t);
}

/* Appends the quads of one string at (x, y) in glyph units, scaled and moved into pixels. */
static void gfx_text_queue(gfx_text *t, float x, float y, float scale, const uint8_t color[4], char *text) {
    gfx_text_vertex *at = t->queued + t->quad_count * 4;
    int room = (GFX_TEXT_MAX_QUADS - t->quad_count) * 4 * (int)sizeof *at;
    int quads = stb_easy_font_print(0, 0, text, (unsigned char *)color, at, room);
    for (int v = 0; v < quads * 4; v++) {
        at[v].x = x + at[v].x * scale;
        at[v].y = y + at[v].y * scale;
    }
    t->quad_count += quads;
}

void gfx_text_print(gfx_text *t, float x, float y, float scale, const float color[4], const char *fmt, ...) {
    char text[1024];
    va_list args;
    va_start(args, fmt);
    vsnprintf(text, sizeof text, fmt, args);
    va_end(args);
    uint8_t rgba[4], shadow[4] = { 0, 0, 0, 0 };
    for (int c = 0; c < 4; c++) rgba[c] = (uint8_t)(color[c] < 0 ? 0 : color[c] > 1 ? 255 : color[c] * 255.0f + 0.5f);
    shadow[3] = rgba[3];
    gfx_text_queue(t, x + scale, y + scale, scale, shadow, text);
    gfx_text_queue(t, x, y, scale, rgba, text);
}

float gfx_text_width(const char *text, float scale) {
    return (float)stb_easy_font_width((char *)text) * scale;
}

void gfx_text_draw(gfx_text *t) {
    if (t->quad_count == 0) return;
    gfx_context *gfx = t->gfx;
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "hud" });
    gfx_buffer_update(t->vertices, 0, t->queued, (size_t)t->quad_count * 4 * sizeof *t->queued);
    float size[2] = { (float)gfx->width, (float)gfx->height };
    gfx_program_use(gfx, t->program);
    gfx_uniform_vec2(gfx, t->program, "u_screen_size", size);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = t->array, .count = (uint32_t)t->quad_count * 6,
                               .index_type = GFX_INDEX_U32 });
    glDisable(GL_BLEND);
    glEnable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    gfx_pass_end(gfx);
    t->quad_count = 0;
}
