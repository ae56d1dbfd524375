/* The gfx layer through OSMesa: shader files with #include and errors at file:line, reloading,
 * framebuffers, instanced and indirect draws, GPU timings in the trace, the backend fallback. */
#include "../engine/test.h"
#include "render_util.h"

#include "trace/trace.h"

#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <time.h>

static const char *vertex_ok =
    "#version 450 core\n"
    "layout(location = 0) in vec2 a_position;\n"
    "layout(location = 1) in vec2 a_offset;\n"
    "void main() { gl_Position = vec4(a_position + a_offset, 0.0, 1.0); }\n";

static const char *fragment_with_include =
    "#version 450 core\n"                  /* 1 */
    "#include \"colour.glsl\"\n"            /* 2 */
    "out vec4 frag_color;\n"                /* 3 */
    "void main() {\n"                       /* 4 */
    "    frag_color = vec4(COLOUR, 1.0);\n" /* 5 */
    "}\n";

static const char *colour_red = "// colour.glsl\n#define COLOUR vec3(1.0, 0.0, 0.0)\n";

/* An offscreen context whose shader folder holds quad.vert (vertex_ok), quad.frag and
 * colour.glsl with the given texts; the folder's path goes to *folder when asked for. */
static gfx_context *quad_context(const char *fragment, const char *include, const char **folder) {
    const char *names[] = { "quad.vert", "quad.frag", "colour.glsl" };
    const char *texts[] = { vertex_ok, fragment, include };
    const char *made = render_shader_folder(names, texts, 3);
    if (folder) *folder = made;
    return gfx_context_create(&(gfx_context_desc){ .width = 32, .height = 32, .headless = true, .shader_dir = made });
}

Test(render_gfx, include_pastes_the_file) {
    gfx_context *gfx = quad_context(fragment_with_include, colour_red, NULL);
    gfx_program program = gfx_program_load(gfx, "quad.vert", "quad.frag");
    cr_assert(program.id, "the program builds");
    cr_assert_neq(gfx_program_gl(gfx, program), 0);
    gfx_context_destroy(gfx);
}

/* Runs gfx_program_load on a folder whose files hold an error, and returns the log. */
static char *load_errors(const char *fragment, const char *include, bool *built) {
    gfx_context *gfx = quad_context(fragment, include, NULL);
    render_capture_begin();
    gfx_program program = gfx_program_load(gfx, "quad.vert", "quad.frag");
    char *log = render_capture_end();
    *built = program.id != 0;
    gfx_context_destroy(gfx);
    return log;
}

Test(render_gfx, error_in_an_included_file_names_that_file_and_line) {
    bool built;
    char *log = load_errors(fragment_with_include, "// colour.glsl\n\n#define COLOUR vec3(1.0, 0.0, 0.0) +\n", &built);
    cr_assert_not(built);
    /* The bad expansion is reported where it is used (quad.frag:5) or defined (colour.glsl:3). */
    cr_assert(strstr(log, "quad.frag:5:") || strstr(log, "colour.glsl:3:"), "log: %s", log);
    free(log);
}

Test(render_gfx, error_after_an_include_keeps_the_line_numbers) {
    const char *fragment =
        "#version 450 core\n"
        "#include \"colour.glsl\"\n"
        "out vec4 frag_color;\n"
        "void main() {\n"
        "    frag_color = vec4(COLOUR, 1.0);\n"
        "    undeclared_thing = 1.0;\n"          /* line 6 */
        "}\n";
    bool built;
    char *log = load_errors(fragment, colour_red, &built);
    cr_assert_not(built);
    cr_assert(strstr(log, "quad.frag:6:"), "log: %s", log);
    free(log);
}

Test(render_gfx, error_inside_an_include_names_it) {
    bool built;
    char *log = load_errors(fragment_with_include, "// colour.glsl\n\nfloat broken( {\n#define COLOUR vec3(1)\n", &built);
    cr_assert_not(built);
    cr_assert(strstr(log, "colour.glsl:3:"), "log: %s", log);
    free(log);
}

Test(render_gfx, missing_include_is_reported) {
    bool built;
    const char *fragment = "#version 450 core\n#include \"nowhere.glsl\"\nvoid main() {}\n";
    char *log = load_errors(fragment, colour_red, &built);
    cr_assert_not(built);
    cr_assert(strstr(log, "nowhere.glsl"), "log: %s", log);
    free(log);
}

Test(render_gfx, include_cycle_is_harmless) {
    gfx_context *gfx = quad_context(fragment_with_include, "#include \"colour.glsl\"\n#define COLOUR vec3(1.0)\n", NULL);
    cr_assert(gfx_program_load(gfx, "quad.vert", "quad.frag").id);
    gfx_context_destroy(gfx);
}

/* Draws instanced quads (one per offset) in the program's colour and counts coloured pixels. */
static int draw_quads(gfx_context *gfx, gfx_program program, bool indirect, int instances) {
    const float corners[] = { -0.25f, -0.25f, 0.25f, -0.25f, 0.25f, 0.25f, -0.25f, 0.25f };
    const uint16_t indices[] = { 0, 1, 2, 0, 2, 3 };
    const float offsets[] = { -0.5f, -0.5f, 0.5f, 0.5f, -0.5f, 0.5f, 0.5f, -0.5f };
    gfx_buffer vertices = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof corners, .data = corners });
    gfx_buffer index_buffer = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof indices, .data = indices });
    gfx_buffer instance_buffer = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof offsets, .data = offsets });
    gfx_vertex_array array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = vertices, .vertex_stride = 8, .indices = index_buffer,
        .instances = instance_buffer, .instance_stride = 8,
        .attributes = { { .components = 2 }, { .components = 2, .buffer = 1 } } });
    /* DrawElementsIndirectCommand: count, instanceCount, firstIndex, baseVertex, baseInstance. */
    const uint32_t command[5] = { 6, (uint32_t)instances, 0, 0, 0 };
    gfx_buffer indirect_buffer = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof command, .data = command });
    gfx_framebuffer target = gfx_framebuffer_create(&(gfx_framebuffer_desc){ .width = 64, .height = 64, .depth = true });
    cr_assert(target.id);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "quads", .target = target, .clear_color = true,
                                          .clear_depth = true });
    gfx_program_use(gfx, program);
    glDisable(GL_CULL_FACE);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = array, .index_type = GFX_INDEX_U16, .count = 6,
                               .instances = (uint32_t)instances,
                               .indirect = indirect ? indirect_buffer : (gfx_buffer){ 0 } });
    gfx_pass_end(gfx);
    uint8_t *pixels = malloc(64 * 64 * 4);
    glGetTextureImage(gfx_texture_gl(gfx_framebuffer_color(target)), 0, GL_RGBA, GL_UNSIGNED_BYTE, 64 * 64 * 4, pixels);
    int red = 0;
    for (int i = 0; i < 64 * 64; i++) red += pixels[i * 4] > 200 && pixels[i * 4 + 1] < 50;
    free(pixels);
    gfx_framebuffer_destroy(&target);
    gfx_vertex_array_destroy(&array);
    gfx_buffer_destroy(&vertices);
    gfx_buffer_destroy(&index_buffer);
    gfx_buffer_destroy(&instance_buffer);
    gfx_buffer_destroy(&indirect_buffer);
    return red;
}

static gfx_program red_program(gfx_context *gfx) {
    return gfx_program_from_source(gfx, "red", vertex_ok,
                                   "#version 450 core\nout vec4 c;\nvoid main() { c = vec4(1, 0, 0, 1); }\n");
}

Test(render_gfx, instanced_draw_covers_each_instance) {
    gfx_context *gfx = render_offscreen(32, 32);
    gfx_program program = red_program(gfx);
    cr_assert(program.id);
    /* Each quad is 0.5 × 0.5 of the 2 × 2 clip square: 1/16 of 64 × 64 = 256 pixels. */
    cr_assert_eq(draw_quads(gfx, program, false, 1), 256);
    cr_assert_eq(draw_quads(gfx, program, false, 4), 4 * 256);
    gfx_context_destroy(gfx);
}

Test(render_gfx, indirect_draw_takes_its_counts_from_the_buffer) {
    gfx_context *gfx = render_offscreen(32, 32);
    gfx_program program = red_program(gfx);
    cr_assert_eq(draw_quads(gfx, program, true, 3), 3 * 256);
    gfx_context_destroy(gfx);
}

/* A full-screen quad at clip depth z (window depth (z + 1) / 2) in `colour`, into the bound
 * framebuffer with the context's depth test (LEQUAL); returns the centre pixel's RGBA. */
static uint32_t depth_quad(gfx_context *gfx, gfx_program program, float z, const float colour[3]) {
    const float corners[] = { -1, -1, 1, -1, 1, 1, -1, -1, 1, 1, -1, 1 };
    gfx_buffer vertices = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof corners, .data = corners });
    gfx_vertex_array array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = vertices, .vertex_stride = 8, .attributes = { { .components = 2 } } });
    gfx_program_use(gfx, program);
    gfx_uniform_float(gfx, program, "u_z", z);
    gfx_uniform_vec3(gfx, program, "u_colour", colour);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = array, .count = 6 });
    uint8_t pixels[32 * 32 * 4];
    gfx_read_pixels(gfx, pixels);
    const uint8_t *centre = pixels + (16 * 32 + 16) * 4;
    gfx_vertex_array_destroy(&array);
    gfx_buffer_destroy(&vertices);
    return (uint32_t)centre[0] | (uint32_t)centre[1] << 8 | (uint32_t)centre[2] << 16;
}

/* gfx_frame_end clears the default framebuffer's depth for the next frame, and the first pass
 * into it that asks for a depth clear skips its own: the depth must still be clear there, and
 * only there (a later pass's clear is done, a pass without one keeps the depth drawn). */
Test(render_gfx, depth_cleared_ahead_at_frame_end_serves_one_pass) {
    gfx_context *gfx = render_offscreen(32, 32);
    gfx_program program = gfx_program_from_source(gfx, "depth",
        "#version 450 core\nlayout(location = 0) in vec2 a_position;\nuniform float u_z;\n"
        "void main() { gl_Position = vec4(a_position, u_z, 1.0); }\n",
        "#version 450 core\nuniform vec3 u_colour;\nout vec4 c;\nvoid main() { c = vec4(u_colour, 1); }\n");
    cr_assert(program.id);
    const float red[3] = { 1, 0, 0 }, green[3] = { 0, 1, 0 }, blue[3] = { 0, 0, 1 };
    const uint32_t RED = 0xff, GREEN = 0xff00, BLUE = 0xff0000;
    gfx_frame_begin(gfx);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "near", .clear_color = true, .clear_depth = true });
    cr_assert_eq(depth_quad(gfx, program, -0.5f, red), RED, "depth 0.25 drawn");
    gfx_pass_end(gfx);
    gfx_frame_end(gfx);
    gfx_frame_begin(gfx);
    /* Depth 0.75 behind last frame's 0.25: drawn only if the depth was cleared. */
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "far", .clear_color = true, .clear_depth = true });
    cr_assert_eq(depth_quad(gfx, program, 0.5f, green), GREEN, "the new frame's depth is clear");
    gfx_pass_end(gfx);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "kept" });
    cr_assert_eq(depth_quad(gfx, program, 0.8f, red), GREEN, "no clear asked: 0.9 stays behind 0.75");
    gfx_pass_end(gfx);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "again", .clear_depth = true });
    cr_assert_eq(depth_quad(gfx, program, 0.8f, blue), BLUE, "a second clear in the frame is done");
    gfx_pass_end(gfx);
    gfx_frame_end(gfx);
    gfx_context_destroy(gfx);
}

Test(render_gfx, frame_stats_count_the_draws_and_their_triangles) {
    /* A quad is 2 triangles: 1 + 4 instances drawn directly make 10, and the indirect draw's
     * triangles are on the GPU, so it counts as an indirect draw only. */
    gfx_context *gfx = render_offscreen(32, 32);
    gfx_program program = red_program(gfx);
    gfx_frame_begin(gfx);
    draw_quads(gfx, program, false, 1);
    draw_quads(gfx, program, false, 4);
    draw_quads(gfx, program, true, 3);
    gfx_frame_end(gfx);
    gfx_context_stats_info s = gfx_context_stats(gfx);
    cr_expect_eq(s.draw_calls, 3);
    cr_expect_eq(s.triangles, 10);
    cr_expect_eq(s.indirect_draws, 1);
    gfx_frame_begin(gfx);   /* an empty frame resets them */
    gfx_frame_end(gfx);
    s = gfx_context_stats(gfx);
    cr_expect_eq(s.draw_calls + s.triangles + s.indirect_draws, 0);
    gfx_context_destroy(gfx);
}

Test(render_gfx, texture_round_trip) {
    gfx_context *gfx = render_offscreen(32, 32);
    float texels[4 * 4];
    for (int i = 0; i < 16; i++) texels[i] = (float)i * 0.5f;
    gfx_texture texture = gfx_texture_create(&(gfx_texture_desc){ .width = 4, .height = 4,
                                                                   .format = GFX_FORMAT_R32F, .data = texels });
    float patch[4] = { -1, -2, -3, -4 };
    gfx_texture_update(texture, 0, 1, 1, 2, 2, patch);
    float back[16];
    glGetTextureImage(gfx_texture_gl(texture), 0, GL_RED, GL_FLOAT, sizeof back, back);
    cr_assert_float_eq(back[0], 0.0f, 0);
    cr_assert_float_eq(back[5], -1.0f, 0);
    cr_assert_float_eq(back[6], -2.0f, 0);
    cr_assert_float_eq(back[9], -3.0f, 0);
    cr_assert_float_eq(back[10], -4.0f, 0);
    cr_assert_float_eq(back[15], 7.5f, 0);
    gfx_texture_destroy(&texture);
    gfx_context_destroy(gfx);
}

Test(render_gfx, zeroed_desc_enums_give_the_documented_defaults) {
    gfx_context *gfx = render_offscreen(32, 32);
    /* gfx_buffer_usage: DEFAULT is STATIC (GL_STATIC_DRAW); DYNAMIC still asks for GL_DYNAMIC_DRAW. */
    const float corners[] = { -0.25f, -0.25f, 0.25f, -0.25f, 0.25f, 0.25f,
                              -0.25f, -0.25f, 0.25f, 0.25f, -0.25f, 0.25f };
    gfx_buffer plain = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof corners, .data = corners });
    gfx_buffer dynamic = gfx_buffer_create(&(gfx_buffer_desc){ .size = 16, .usage = GFX_BUFFER_DYNAMIC });
    GLint usage = 0;
    glGetNamedBufferParameteriv(gfx_buffer_gl(plain), GL_BUFFER_USAGE, &usage);
    cr_expect_eq(usage, GL_STATIC_DRAW);
    glGetNamedBufferParameteriv(gfx_buffer_gl(dynamic), GL_BUFFER_USAGE, &usage);
    cr_expect_eq(usage, GL_DYNAMIC_DRAW);

    /* gfx_format: DEFAULT is RGBA8, for a texture and for a framebuffer's colour attachment. */
    gfx_texture texture = gfx_texture_create(&(gfx_texture_desc){ .width = 4, .height = 4 });
    GLint internal = 0;
    glGetTextureLevelParameteriv(gfx_texture_gl(texture), 0, GL_TEXTURE_INTERNAL_FORMAT, &internal);
    cr_expect_eq(internal, GL_RGBA8);
    gfx_framebuffer target = gfx_framebuffer_create(&(gfx_framebuffer_desc){ .width = 64, .height = 64 });
    cr_assert(target.id);
    internal = 0;
    glGetTextureLevelParameteriv(gfx_texture_gl(gfx_framebuffer_color(target)), 0, GL_TEXTURE_INTERNAL_FORMAT,
                                 &internal);
    cr_expect_eq(internal, GL_RGBA8);

    /* gfx_index_type: DEFAULT is NONE, a glDrawArrays of .count vertices: two triangles, a quad
     * 0.5 × 0.5 of the 2 × 2 clip square, 1/16 of 64 × 64 = 256 pixels (an indexed draw with no
     * index buffer would draw nothing). */
    gfx_vertex_array array = gfx_vertex_array_create(&(gfx_vertex_array_desc){
        .vertices = plain, .vertex_stride = 8, .attributes = { { .components = 2 } } });
    gfx_program program = red_program(gfx);
    cr_assert(program.id);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "defaults", .target = target, .clear_color = true });
    gfx_program_use(gfx, program);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);
    gfx_draw(&(gfx_draw_desc){ .vertex_array = array, .count = 6 });
    gfx_pass_end(gfx);
    uint8_t *pixels = malloc(64 * 64 * 4);
    glGetTextureImage(gfx_texture_gl(gfx_framebuffer_color(target)), 0, GL_RGBA, GL_UNSIGNED_BYTE, 64 * 64 * 4, pixels);
    int red = 0;
    for (int i = 0; i < 64 * 64; i++) red += pixels[i * 4] > 200 && pixels[i * 4 + 1] < 50;
    free(pixels);
    cr_expect_eq(red, 256);

    gfx_vertex_array_destroy(&array);
    gfx_framebuffer_destroy(&target);
    gfx_texture_destroy(&texture);
    gfx_buffer_destroy(&plain);
    gfx_buffer_destroy(&dynamic);
    gfx_context_destroy(gfx);
}

static void touch_later(const char *folder, const char *name, const char *text) {
    render_write_file(folder, name, text);
    /* Make sure the time differs from the first write, whatever the file system's resolution. */
    char path[512];
    snprintf(path, sizeof path, "%s/%s", folder, name);
    struct timespec times[2] = { { .tv_sec = time(NULL) + 10 }, { .tv_sec = time(NULL) + 10 } };
    utimensat(AT_FDCWD, path, times, 0);
}

Test(render_gfx, changed_include_rebuilds_the_program_and_a_broken_edit_keeps_the_old_one) {
    const char *folder;
    gfx_context *gfx = quad_context(fragment_with_include, colour_red, &folder);
    gfx_program program = gfx_program_load(gfx, "quad.vert", "quad.frag");
    GLuint first = gfx_program_gl(gfx, program);
    cr_assert_eq(gfx_programs_reload_changed(gfx), 0, "nothing changed yet");

    touch_later(folder, "colour.glsl", "#define COLOUR vec3(0.0, 1.0, 0.0)\n");
    cr_assert_eq(gfx_programs_reload_changed(gfx), 1);
    GLuint second = gfx_program_gl(gfx, program);
    cr_assert_neq(second, 0);
    cr_assert_neq(second, first);

    render_capture_begin();
    touch_later(folder, "quad.frag", "#version 450 core\nvoid main() { nonsense }\n");
    int rebuilt = gfx_programs_reload_changed(gfx);
    char *log = render_capture_end();
    cr_assert_eq(rebuilt, 0);
    cr_assert_eq(gfx_program_gl(gfx, program), second, "the working program stays");
    cr_assert(strstr(log, "quad.frag:2:"), "log: %s", log);
    free(log);
    gfx_context_destroy(gfx);
}

Test(render_gfx, pass_times_reach_the_trace_on_the_gpu_lane) {
    char path[] = "/tmp/render_trace_XXXXXX";
    int fd = mkstemp(path);
    cr_assert(fd >= 0);
    close(fd);
    cr_assert(trace_start(path));
    gfx_context *gfx = render_offscreen(64, 36);
    gfx_scene *scene = gfx_scene_create(gfx);
    gfx_camera camera = gfx_scene_default_camera();
    for (int i = 0; i < 8; i++) {
        trace_frame_begin();
        gfx_frame_begin(gfx);
        gfx_scene_draw(scene, &camera, 0.0);
        gfx_frame_end(gfx);
        trace_frame_end();
    }
    gfx_pass_timing timings[4];
    int count = gfx_pass_timings(gfx, timings, 4);
    cr_assert_eq(count, 1);
    cr_assert_str_eq(timings[0].name, "scene");
    cr_assert(timings[0].gpu_ms >= 0 && timings[0].gpu_ms < 1000);
    gfx_scene_destroy(scene);
    gfx_context_destroy(gfx);
    trace_stop();
    FILE *file = fopen(path, "rb");
    static char text[1 << 20];
    size_t size = fread(text, 1, sizeof text - 1, file);
    fclose(file);
    text[size] = 0;
    unlink(path);
    cr_assert(strstr(text, "\"GPU\""), "a GPU lane is named in the trace");
    /* Several frames' "scene" passes were read back: more than one X event named scene. */
    int events = 0;
    for (const char *p = text; (p = strstr(p, "\"ph\":\"X\"")); p++) events++;
    cr_assert_geq(events, 4, "%d GPU zones", events);
}

Test(render_gfx, no_display_falls_back_to_offscreen_and_says_so) {
    unsetenv("DISPLAY");
    unsetenv("WAYLAND_DISPLAY");
    render_capture_begin();
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 32, .height = 32 });
    char *log = render_capture_end();
    cr_assert(gfx);
    cr_assert_eq(gfx_backend_get(gfx), GFX_BACKEND_OFFSCREEN);
    cr_assert(strstr(log, "OSMesa"), "log: %s", log);
    cr_assert_null(gfx_glfw_window(gfx));
    free(log);
    gfx_context_destroy(gfx);
}

Test(render_gfx, size_flag_parsing) {
    int w = 0, h = 0;
    cr_assert(gfx_parse_size("640x360", &w, &h));
    cr_assert(w == 640 && h == 360);
    cr_assert(gfx_parse_size("16X16", &w, &h));
    const char *bad[] = { "", "640", "640x", "x360", "640x360x2", "15x100", "100x16385", "-640x360",
                          "640x-360", "640 x 360", "abc" };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
        cr_assert_not(gfx_parse_size(bad[i], &w, &h), "'%s' was accepted", bad[i]);
}

Test(render_gfx, screenshot_writes_a_png_and_reports_unwritable_paths) {
    gfx_context *gfx = render_offscreen(48, 27);
    render_image image = render_scene(gfx, 1);
    render_image_free(&image);
    char path[] = "/tmp/render_shot_XXXXXX.png";
    int fd = mkstemps(path, 4);
    close(fd);
    cr_assert(gfx_screenshot(gfx, path));
    FILE *file = fopen(path, "rb");
    unsigned char magic[8] = { 0 };
    cr_assert_eq(fread(magic, 1, 8, file), 8);
    fclose(file);
    unlink(path);
    cr_assert(memcmp(magic, "\x89PNG\r\n\x1a\n", 8) == 0);
    render_capture_begin();
    bool ok = gfx_screenshot(gfx, "/nonexistent-dir/shot.png");
    char *log = render_capture_end();
    cr_assert_not(ok);
    cr_assert(strstr(log, "/nonexistent-dir/shot.png"), "log: %s", log);
    free(log);
    gfx_context_destroy(gfx);
}

#ifdef ENGINE_DEBUG
Test(render_gfx, debug_builds_route_gl_errors_to_the_log) {
    gfx_context *gfx = render_offscreen(32, 32);
    render_capture_begin();
    glBindBuffer(GL_ARRAY_BUFFER, 123456);   /* never made by glGenBuffers: an error in core GL */
    char *log = render_capture_end();
    cr_assert_eq(glGetError(), GL_INVALID_OPERATION);
    cr_assert(strstr(log, "[error] gl:"), "log: %s", log);
    free(log);
    gfx_context_destroy(gfx);
}
#endif

Test(render_gfx, a_window_that_cannot_open_falls_back_in_one_line) {
    setenv("DISPLAY", ":97", 1);          /* a display no X server serves */
    unsetenv("WAYLAND_DISPLAY");
    render_capture_begin();
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 32, .height = 32 });
    char *log = render_capture_end();
    cr_assert(gfx);
    cr_assert_eq(gfx_backend_get(gfx), GFX_BACKEND_OFFSCREEN);
    int lines = 0;
    for (const char *p = log; *p; p++) lines += *p == '\n';
    cr_assert_eq(lines, 1, "log: %s", log);
    cr_assert(strstr(log, "no window (") && strstr(log, ":97") && strstr(log, "OSMesa"), "log: %s", log);
    free(log);
    gfx_context_destroy(gfx);
}

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

Test(render_gfx, hud_text_lands_where_it_was_printed) {
    gfx_context *gfx = render_offscreen(128, 64);
    gfx_text *hud = gfx_text_create(gfx);
    cr_assert(hud);
    gfx_frame_begin(gfx);
    gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "clear", .clear_color = true, .color = { 0, 0, 0, 1 } });
    gfx_pass_end(gfx);
    gfx_text_print(hud, 10, 20, 2, (const float[4]){ 1, 1, 1, 1 }, "HUD %d", 42);
    gfx_text_draw(hud);
    uint8_t *pixels = malloc(128 * 64 * 4);
    gfx_read_pixels(gfx, pixels);
    gfx_frame_end(gfx);
    /* The text's box from stb_easy_font's own metrics, times the scale, plus the shadow's unit. */
    char text[] = "HUD 42";
    int right = 10 + stb_easy_font_width(text) * 2 + 2, bottom = 20 + stb_easy_font_height(text) * 2 + 2;
    int white = 0, outside = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 128; x++) {
            const uint8_t *p = pixels + (y * 128 + x) * 4;
            if (p[0] < 128) continue;
            white++;
            outside += x < 10 || x >= right || y < 20 || y >= bottom;
        }
    cr_assert_gt(white, 60, "the text is drawn");
    cr_assert_eq(outside, 0, "%d text pixels outside its box (10, 20)–(%d, %d)", outside, right, bottom);
    free(pixels);
    gfx_text_destroy(hud);
    gfx_context_destroy(gfx);
}
