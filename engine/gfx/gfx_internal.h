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

/* A pool of one kind of object (gfx_pool.c): slots 1…count−1 with a generation each; freed
 * slots queue first in, first out, so a slot is reused as late as possible (a stale handle
 * would need 65 535 reuses of its one slot to alias). A handle's id is generation << 16 | slot;
 * slot 0 is never handed out, so the zero id is none. */
#define GFX_POOL_SLOT_BITS 16
#define GFX_POOL_MAX_SLOTS (1u << GFX_POOL_SLOT_BITS)

typedef struct gfx_pool {
    const char *kind;              /* "buffer", … for messages */
    size_t entry_size;
    uint8_t *entries;              /* capacity × entry_size */
    uint16_t *generations;
    uint32_t *next_free;           /* the free queue's links */
    bool *live;
    uint32_t count, capacity;      /* slots handed out at least once (slot 0 counted), allocated */
    uint32_t free_head, free_tail; /* 0 = empty */
    uint32_t live_count;
    uint16_t first_generation;     /* new slots start here: differs from context to context */
    bool stale_reported;           /* release builds log a stale handle once per pool */
} gfx_pool;

typedef struct gfx__buffer_entry { GLuint name; size_t size; } gfx__buffer_entry;
typedef struct gfx__vertex_array_entry { GLuint name; } gfx__vertex_array_entry;
typedef struct gfx__texture_entry {
    GLuint name;
    GLenum target;
    int width, height, layers;
    gfx_format format;
} gfx__texture_entry;
typedef struct gfx__framebuffer_entry {
    GLuint name;
    int width, height;
    gfx_texture color, depth;      /* attachments it made (and destroys) */
    gfx_texture depth_borrowed;    /* desc.depth_texture: attached, not destroyed */
} gfx__framebuffer_entry;

void gfx__pool_init(gfx_pool *pool, const char *kind, size_t entry_size, uint16_t first_generation);
void gfx__pool_destroy(gfx_pool *pool);
/* A fresh slot's id and its zeroed entry; 0 (logged) when the pool is full. */
uint32_t gfx__pool_alloc(gfx_pool *pool, void **entry);
/* The live entry `id` names, or NULL: reports nothing. */
void *gfx__pool_lookup(const gfx_pool *pool, uint32_t id);
/* Bumps the slot's generation and queues it for reuse; `id` must be live. */
void gfx__pool_free(gfx_pool *pool, uint32_t id);
/* A stale or zero handle reached `call`: debug builds stop, release builds log once. */
void gfx__pool_report(gfx_pool *pool, uint32_t id, const char *call);

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

    /* Offscreen, the default framebuffer's depth cleared by gfx_frame_end for the next frame,
     * and no pass into it since (gfx_pass_begin then skips its clear) */
    bool depth_cleared_ahead;

    /* Objects (gfx_resources.c), behind generation-checked handles */
    gfx_pool buffers, vertex_arrays, textures, framebuffers;
};

/* The context gfx_context_create made last (NULL after its gfx_context_destroy): whose pools handles name. */
extern gfx_context *gfx__current;
void gfx__resources_init(gfx_context *gfx);
void gfx__resources_destroy(gfx_context *gfx);

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
