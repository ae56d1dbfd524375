/* gfx_timer.c — GPU time of every pass, read back without stalling.
 *
 * Each pass writes a timestamp query at its start and end. Results are read GFX_TIMER_FRAMES − 1
 * frames later, and only once the GPU says they are available: asking earlier would make the CPU
 * wait for the GPU, which is the stall this exists to show, not cause. Finished passes go to the
 * trace as zones named "gpu PASS" on the "GPU" lane, in trace time (GL timestamps are offset by a calibration taken
 * at start-up and every 256 frames). */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

static void gfx_timer_calibrate(gfx_context *gfx) {
    GLint64 gpu_now = 0;
    glGetInteger64v(GL_TIMESTAMP, &gpu_now);
    gfx->gpu_to_trace_ns = (int64_t)trace_now() - (int64_t)gpu_now;
}

void gfx__timers_init(gfx_context *gfx) {
    for (int f = 0; f < GFX_TIMER_FRAMES; f++)
        glGenQueries(GFX_MAX_PASSES * 2, gfx->timer_frames[f].queries);
    gfx_timer_calibrate(gfx);
}

void gfx__timers_destroy(gfx_context *gfx) {
    for (int f = 0; f < GFX_TIMER_FRAMES; f++)
        glDeleteQueries(GFX_MAX_PASSES * 2, gfx->timer_frames[f].queries);
}

/* Reads a finished frame's timestamps; false while the GPU has not got that far. */
static bool gfx_timer_frame_read(gfx_context *gfx, gfx_timer_frame *frame) {
    if (frame->pass_count == 0) return true;
    GLuint available = 0;
    glGetQueryObjectuiv(frame->queries[frame->pass_count * 2 - 1], GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available) return false;
    for (int p = 0; p < frame->pass_count; p++) {
        GLuint64 begin = 0, end = 0;
        glGetQueryObjectui64v(frame->queries[p * 2], GL_QUERY_RESULT, &begin);
        glGetQueryObjectui64v(frame->queries[p * 2 + 1], GL_QUERY_RESULT, &end);
        if (end < begin) end = begin;
        gfx->last_timings[p] = (gfx_pass_timing){ frame->names[p], (double)(end - begin) * 1e-6 };
        if (trace_active()) {
            /* "gpu scene" beside the CPU's "scene" zone, so the report tells them apart. */
            char name[96];
            snprintf(name, sizeof name, "gpu %s", frame->names[p]);
            trace_complete("GPU", trace_intern(name), (uint64_t)((int64_t)begin + gfx->gpu_to_trace_ns),
                           (uint64_t)((int64_t)end + gfx->gpu_to_trace_ns));
        }
    }
    gfx->last_timing_count = frame->pass_count;
    return true;
}

void gfx__timers_collect(gfx_context *gfx) {
    if (gfx->frame_index % 256 == 0) gfx_timer_calibrate(gfx);
    /* Oldest first, so the trace's GPU lane stays in order. */
    for (uint64_t age = GFX_TIMER_FRAMES - 1; age >= 1; age--) {
        if (gfx->frame_index < age) continue;
        gfx_timer_frame *frame = &gfx->timer_frames[(gfx->frame_index - age) % GFX_TIMER_FRAMES];
        if (frame->pending && gfx_timer_frame_read(gfx, frame)) frame->pending = false;
    }
    gfx_timer_frame *current = &gfx->timer_frames[gfx->frame_index % GFX_TIMER_FRAMES];
    /* Still not in after GFX_TIMER_FRAMES frames: drop it rather than wait. */
    current->pending = false;
    current->pass_count = 0;
}

void gfx__timer_pass_begin(gfx_context *gfx, const char *name) {
    gfx_timer_frame *frame = &gfx->timer_frames[gfx->frame_index % GFX_TIMER_FRAMES];
    if (frame->pass_count >= GFX_MAX_PASSES) { gfx->open_pass = -1; return; }
    int pass = frame->pass_count++;
    frame->names[pass] = name ? name : "pass";
    frame->pending = true;
    glQueryCounter(frame->queries[pass * 2], GL_TIMESTAMP);
    gfx->open_pass = pass;
}

void gfx__timer_pass_end(gfx_context *gfx) {
    if (gfx->open_pass < 0) return;
    gfx_timer_frame *frame = &gfx->timer_frames[gfx->frame_index % GFX_TIMER_FRAMES];
    glQueryCounter(frame->queries[gfx->open_pass * 2 + 1], GL_TIMESTAMP);
    gfx->open_pass = -1;
}

int gfx_pass_timings(const gfx_context *gfx, gfx_pass_timing *timings, int capacity) {
    int count = gfx->last_timing_count < capacity ? gfx->last_timing_count : capacity;
    for (int i = 0; i < count; i++) timings[i] = gfx->last_timings[i];
    return count;
}
