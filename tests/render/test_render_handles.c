/* gfx's generation-checked handles (gfx.h, "Handles"): zero is none, a destroyed object's
 * handle goes stale, a reused slot gets a new generation, and a stale handle never reaches the
 * object made later in its slot (debug builds stop on it; release builds ignore it, logging
 * once). The slot is the handle's low 16 bits, as gfx.h documents. */
#include "../engine/test.h"
#include "render_util.h"

#include <signal.h>
#include <stdlib.h>
#include <string.h>

#define SLOT(id) ((id) & 0xffffu)

static gfx_buffer buffer_of(uint32_t value) {
    uint32_t words[4] = { value, value, value, value };
    return gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof words, .data = words });
}

Test(render_gfx_handles, zero_handles_are_none_and_destroying_them_does_nothing) {
    gfx_context *gfx = render_offscreen(16, 16);
    cr_assert_not(gfx_buffer_valid((gfx_buffer){ 0 }));
    cr_assert_not(gfx_texture_valid((gfx_texture){ 0 }));
    cr_assert_not(gfx_vertex_array_valid((gfx_vertex_array){ 0 }));
    cr_assert_not(gfx_framebuffer_valid((gfx_framebuffer){ 0 }));
    render_capture_begin();
    gfx_buffer buffer = { 0 };
    gfx_texture texture = { 0 };
    gfx_vertex_array array = { 0 };
    gfx_framebuffer framebuffer = { 0 };
    gfx_buffer_destroy(&buffer);
    gfx_texture_destroy(&texture);
    gfx_vertex_array_destroy(&array);
    gfx_framebuffer_destroy(&framebuffer);
    char *log = render_capture_end();
    cr_assert_str_eq(log, "", "destroying nothing is silent: %s", log);
    free(log);
    gfx_context_destroy(gfx);
}

Test(render_gfx_handles, destroying_makes_every_copy_stale) {
    gfx_context *gfx = render_offscreen(16, 16);
    gfx_buffer buffer = buffer_of(7);
    gfx_buffer copy = buffer;
    cr_assert_neq(buffer.id, 0);
    cr_assert(gfx_buffer_valid(copy));
    cr_assert_eq(gfx_buffer_size(copy), 16);
    gfx_buffer_destroy(&buffer);
    cr_assert_eq(buffer.id, 0, "destroy clears the handle it was given");
    cr_assert_not(gfx_buffer_valid(copy));

    gfx_texture texture = gfx_texture_create(&(gfx_texture_desc){ .width = 4, .height = 4 });
    gfx_texture texture_copy = texture;
    cr_assert(gfx_texture_valid(texture_copy));
    gfx_texture_destroy(&texture);
    cr_assert_not(gfx_texture_valid(texture_copy));

    gfx_vertex_array array = gfx_vertex_array_create(&(gfx_vertex_array_desc){ 0 });
    gfx_vertex_array array_copy = array;
    cr_assert(gfx_vertex_array_valid(array_copy));
    gfx_vertex_array_destroy(&array);
    cr_assert_not(gfx_vertex_array_valid(array_copy));
    gfx_context_destroy(gfx);
}

Test(render_gfx_handles, a_framebuffer_takes_the_attachments_it_made_with_it) {
    gfx_context *gfx = render_offscreen(16, 16);
    gfx_framebuffer framebuffer = gfx_framebuffer_create(&(gfx_framebuffer_desc){ .width = 8, .height = 4, .depth = true });
    cr_assert(gfx_framebuffer_valid(framebuffer));
    int width, height;
    gfx_framebuffer_size(framebuffer, &width, &height);
    cr_assert_eq(width, 8);
    cr_assert_eq(height, 4);
    gfx_texture color = gfx_framebuffer_color(framebuffer), depth = gfx_framebuffer_depth(framebuffer);
    cr_assert(gfx_texture_valid(color) && gfx_texture_valid(depth));
    gfx_framebuffer_destroy(&framebuffer);
    cr_assert_not(gfx_texture_valid(color));
    cr_assert_not(gfx_texture_valid(depth));

    /* A borrowed depth layer stays with its owner. */
    gfx_texture layers = gfx_texture_create(&(gfx_texture_desc){ .width = 8, .height = 8, .layers = 2,
                                                                  .format = GFX_FORMAT_DEPTH32F });
    framebuffer = gfx_framebuffer_create(&(gfx_framebuffer_desc){ .width = 8, .height = 8, .depth_only = true,
                                                                  .depth_texture = layers, .depth_layer = 1 });
    cr_assert(gfx_framebuffer_valid(framebuffer));
    cr_assert_eq(gfx_framebuffer_depth(framebuffer).id, layers.id);
    cr_assert_eq(gfx_framebuffer_color(framebuffer).id, 0);
    gfx_framebuffer_destroy(&framebuffer);
    cr_assert(gfx_texture_valid(layers));
    gfx_texture_destroy(&layers);
    gfx_context_destroy(gfx);
}

Test(render_gfx_handles, a_reused_slot_gets_a_new_generation) {
    gfx_context *gfx = render_offscreen(16, 16);
    /* One slot made and freed over and over: the only free slot, so each create reuses it, and
     * no two of its handles may be equal. */
    enum { ROUNDS = 1000 };
    uint32_t *ids = malloc(ROUNDS * sizeof *ids);
    for (int i = 0; i < ROUNDS; i++) {
        gfx_buffer buffer = buffer_of((uint32_t)i);
        ids[i] = buffer.id;
        gfx_buffer_destroy(&buffer);
    }
    for (int i = 1; i < ROUNDS; i++) cr_assert_eq(SLOT(ids[i]), SLOT(ids[0]), "round %d: the same slot", i);
    int repeats = 0;
    for (int i = 0; i < ROUNDS; i++)
        for (int j = i + 1; j < ROUNDS; j++) repeats += ids[i] == ids[j];
    cr_assert_eq(repeats, 0, "every reuse of the slot is a new handle");

    gfx_buffer old = buffer_of(1), kept = old;
    gfx_buffer_destroy(&old);
    gfx_buffer fresh = buffer_of(2);
    cr_assert_eq(SLOT(fresh.id), SLOT(kept.id));
    cr_assert_neq(fresh.id, kept.id);
    cr_assert(gfx_buffer_valid(fresh));
    cr_assert_not(gfx_buffer_valid(kept), "the old handle does not name the slot's new buffer");
    gfx_buffer_destroy(&fresh);
    free(ids);
    gfx_context_destroy(gfx);
}

Test(render_gfx_handles, a_handle_from_a_destroyed_context_names_nothing_in_the_next) {
    gfx_context *first = render_offscreen(16, 16);
    gfx_buffer left = buffer_of(1);         /* dies with its context */
    gfx_context_destroy(first);
    cr_assert_not(gfx_buffer_valid(left), "no context: nothing is valid");
    gfx_context *second = render_offscreen(16, 16);
    cr_assert_not(gfx_buffer_valid(left));
    gfx_buffer fresh = buffer_of(2);
    cr_assert_eq(SLOT(fresh.id), SLOT(left.id), "the same slot of the new context's pool");
    cr_assert_not(gfx_buffer_valid(left), "another context's handle stays stale");
    gfx_buffer_destroy(&fresh);
    gfx_context_destroy(second);
}

#ifdef NDEBUG
/* Release builds: a stale handle does nothing to the object now in its slot, and says so once. */
Test(render_gfx_handles, a_stale_handle_leaves_the_slots_new_object_alone) {
    gfx_context *gfx = render_offscreen(16, 16);
    gfx_buffer old = buffer_of(1), stale = old;
    gfx_buffer_destroy(&old);
    gfx_buffer fresh = buffer_of(2);
    cr_assert_eq(SLOT(fresh.id), SLOT(stale.id));
    render_capture_begin();
    uint32_t words[4] = { 9, 9, 9, 9 };
    gfx_buffer_update(stale, 0, words, sizeof words);
    gfx_buffer_update(stale, 0, words, sizeof words);
    cr_assert_eq(gfx_buffer_gl(stale), 0);
    char *log = render_capture_end();
    uint32_t back[4];
    glGetNamedBufferSubData(gfx_buffer_gl(fresh), 0, sizeof back, back);
    for (int i = 0; i < 4; i++) cr_assert_eq(back[i], 2, "word %d of the slot's new buffer is untouched", i);
    const char *first = strstr(log, "stale buffer handle");
    cr_assert(first, "log: %s", log);
    cr_assert_null(strstr(first + 1, "stale buffer handle"), "said once: %s", log);
    free(log);

    /* A stale texture binds nothing; a draw with a stale vertex array draws nothing. */
    gfx_texture texture = gfx_texture_create(&(gfx_texture_desc){ .width = 4, .height = 4 });
    gfx_texture stale_texture = texture;
    gfx_texture_destroy(&texture);
    gfx_texture other = gfx_texture_create(&(gfx_texture_desc){ .width = 4, .height = 4 });
    glBindTextureUnit(3, 0);
    gfx_texture_bind(stale_texture, 3);
    glActiveTexture(GL_TEXTURE3);
    GLint bound = -1;
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &bound);
    glActiveTexture(GL_TEXTURE0);
    cr_assert_eq(bound, 0, "unit 3 still holds nothing");
    gfx_vertex_array array = gfx_vertex_array_create(&(gfx_vertex_array_desc){ 0 }), stale_array = array;
    gfx_vertex_array_destroy(&array);
    gfx_frame_begin(gfx);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = stale_array, .count = 3 });
    gfx_frame_end(gfx);
    cr_assert_eq(gfx_context_stats(gfx).draw_calls, 0);
    gfx_texture_destroy(&other);
    gfx_buffer_destroy(&fresh);
    gfx_context_destroy(gfx);
}
#elif !defined(TEST_WITHOUT_CRITERION)
/* Debug builds stop where a stale or zero handle is used. */
Test(render_gfx_handles, a_stale_handle_stops_a_debug_build, .signal = SIGABRT) {
    render_offscreen(16, 16);
    gfx_buffer old = buffer_of(1), stale = old;
    gfx_buffer_destroy(&old);
    gfx_buffer fresh = buffer_of(2);
    (void)fresh;
    uint32_t words[4] = { 9, 9, 9, 9 };
    gfx_buffer_update(stale, 0, words, sizeof words);
}

Test(render_gfx_handles, a_zero_handle_stops_a_debug_build, .signal = SIGABRT) {
    render_offscreen(16, 16);
    gfx_texture_bind((gfx_texture){ 0 }, 0);
}
#endif
