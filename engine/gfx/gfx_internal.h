/* gfx_internal.h — what the gfx module's files share. Not part of the public API. */
#ifndef GFX_INTERNAL_H
#define GFX_INTERNAL_H

#include "gfx/gfx.h"

#include <limits.h>
#include <stdio.h>

/* Passes timed per frame, and frames of queries in flight before results are read back. */
#define GFX_MAX_PASSES 32
#define GFX_TIMER_FRAMES 4

typedef struct gfx_timer_frame {
    GLuint queries[GFX_MAX_PASSES * 2];   /* begin/end timestamp per pass */
    const char *names[GFX_MAX_PASSES];
    int pass_count;
    bool pending;                          /* issued, results not read yet */
} gfx_timer_frame;

typedef struct gfx_program_entry gfx_program_entry;   /* gfx_shader.c */

/* What gfx_draw has drawn since the last gfx_frame_end (gfx_resources.c; OpenGL is used from
 * the main thread only, so plain counters). */
extern gfx_context_stats_info gfx__frame_counts;

struct gfx_context {
    gfx_backend backend;
    void *window;                  /* GLFWwindow * */
    void *osmesa;                  /* OSMesaContext */
    uint8_t *osmesa_pixels;
    int width, height;
    bool vsync;
    bool fullscreen;
    int windowed_x, windowed_y, windowed_width, windowed_height;
    uint64_t frame_index;
    gfx_context_stats_info last_frame;    /* counted by gfx_draw (gfx__frame_counts) */

    /* GPU timing (gfx_timer.c) */
    gfx_timer_frame timer_frames[GFX_TIMER_FRAMES];
    int open_pass;                 /* index in the current frame, −1 = none */
    int64_t gpu_to_trace_ns;       /* add to a GL timestamp to get trace time */
    gfx_pass_timing last_timings[GFX_MAX_PASSES];
    int last_timing_count;

    /* Programs (gfx_shader.c) */
    char shader_dir[PATH_MAX];
    gfx_program_entry *programs;
    uint32_t program_count;
    size_t program_capacity;
    uint64_t next_reload_check_ns;
    uint32_t program_in_use;
};

/* Backends (gfx_window.c, gfx_offscreen.c). The window says why it failed in `reason`; the
 * offscreen backend logs its own errors. */
bool gfx__window_open(gfx_context *gfx, const gfx_context_desc *desc, char *reason, size_t reason_size);
void gfx__window_close(gfx_context *gfx);
void gfx__window_swap(gfx_context *gfx);
bool gfx__offscreen_open(gfx_context *gfx, int width, int height);
void gfx__offscreen_close(gfx_context *gfx);

/* gfx_timer.c */
void gfx__timers_init(gfx_context *gfx);
void gfx__timers_collect(gfx_context *gfx);
void gfx__timers_destroy(gfx_context *gfx);
void gfx__timer_pass_begin(gfx_context *gfx, const char *name);
void gfx__timer_pass_end(gfx_context *gfx);

/* gfx_shader.c */
void gfx__programs_init(gfx_context *gfx, const char *shader_dir);
void gfx__programs_destroy(gfx_context *gfx);

#endif
