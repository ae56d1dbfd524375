/* gfx.h — OpenGL 4.5 core rendering on a GLFW window or an OSMesa offscreen framebuffer.
 *
 * One renderer, two context backends. The same drawing code runs on both:
 *
 *     gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 640, .height = 360, .title = "demo" });
 *     if (!gfx) return 1;                          // the reason has been logged
 *     gfx_program lit = gfx_program_load(gfx, "scene.vert", "scene.frag");
 *     if (!lit.id) return 1;                       // file:line of the GLSL error printed
 *     while (!gfx_window_should_close(gfx)) {
 *         gfx_frame_begin(gfx);
 *         gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "scene", .clear_color = {0.5f,0.7f,1,1},
 *                                               .clear_depth = true });
 *         gfx_program_use(gfx, lit);
 *         gfx_uniform_mat4(gfx, lit, "u_view_projection", view_projection);
 *         gfx_draw(&(gfx_draw_desc){ .vertex_array = mesh, .count = index_count,
 *                                     .index_type = GFX_INDEX_U32 });
 *         gfx_pass_end(gfx);
 *         gfx_frame_end(gfx);                      // swap, or finish the offscreen frame
 *     }
 *     gfx_context_destroy(gfx);
 *
 * Backends. A window is made when a display exists (DISPLAY or WAYLAND_DISPLAY set) and GLFW can
 * open one; otherwise, or with .headless, the context is OSMesa's (llvmpipe) and one line says
 * so. OpenGL functions come from a loader glad generates at build time (<glad/gl.h>); include
 * gfx.h and call gl* directly where the thin layer below does not reach.
 *
 * Shaders live in shaders/ as GLSL 450 files. `#include "file.glsl"` pastes a file from the same
 * folder (once per program; nested up to 16 deep). A compile or link error is printed as
 * "shaders/file.glsl:LINE: message" and gfx_program_load returns { 0 }; programs exit 1 then.
 * In debug builds (ENGINE_DEBUG) gfx_frame_begin notices changed shader files about twice a
 * second and rebuilds the programs that use them; a broken edit keeps the old program.
 *
 * Passes are the unit of GPU timing: each gfx_pass_begin/end pair is measured with timestamp
 * queries and, when tracing is on, shows as a zone on the "GPU" lane of the trace a few frames
 * later (when the results are ready, never stalling).
 *
 * Handles. Buffers, vertex arrays, textures and framebuffers are handles: a 32-bit id whose low
 * 16 bits name a slot in the context's pool of that kind and whose high 16 bits are the slot's
 * generation (sokol_gfx's pools). Destroying bumps the slot's generation, so a copy of the handle
 * kept elsewhere goes stale and never names the object made later in the same slot. A zero
 * handle is none. Every call looks the handle up; a stale or zero handle passed to a call that
 * uses it is a programmer error: debug builds stop on an assert, release builds log it once per
 * kind and do nothing (never touch another object). `_destroy` of a zero handle does nothing.
 * `gfx_X_valid` says whether a handle names a live object; `gfx_X_gl` gives its GL name, for the
 * GL calls this layer does not wrap (0 for a stale handle, which is reported as above).
 * The pools belong to the context made last by gfx_context_create (the one OpenGL draws with); objects
 * die with it, and destroying them after gfx_context_destroy does nothing.
 *
 *     gfx_buffer b = gfx_buffer_create(&(gfx_buffer_desc){ .size = 64 });
 *     gfx_buffer copy = b;
 *     gfx_buffer_destroy(&b);                      // b = { 0 }; copy is stale now
 *     gfx_buffer_valid(copy);                      // false
 *
 * Threads: OpenGL is called from the main thread only; everything here is main-thread only.
 */
#ifndef GFX_H
#define GFX_H

#include <glad/gl.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* ---- context ------------------------------------------------------------------------------ */

typedef enum gfx_backend { GFX_BACKEND_WINDOW, GFX_BACKEND_OFFSCREEN } gfx_backend;

typedef struct gfx_context_desc {
    int width, height;         /* framebuffer size; 0 = 1280 × 720 */
    const char *title;         /* window title; NULL = "engine" */
    bool headless;             /* force the OSMesa backend (--headless) */
    bool no_vsync;             /* windows swap with vsync unless this is set */
    bool fullscreen;           /* start fullscreen on the primary monitor */
    bool hidden;               /* make the window but do not show it (tests) */
    const char *shader_dir;    /* NULL = $ENGINE_SHADERS, else the repository's shaders/ (found
                                  from the executable: bin/CONFIG/../../shaders) */
} gfx_context_desc;

typedef struct gfx_context gfx_context;

/* NULL when no context of either kind can be made (the reason is logged). */
gfx_context *gfx_context_create(const gfx_context_desc *desc);
void gfx_context_destroy(gfx_context *gfx);

gfx_backend gfx_backend_get(const gfx_context *gfx);
/* The GLFWwindow * of a window backend (for input_system_desc.glfw_window), NULL offscreen. */
void *gfx_glfw_window(const gfx_context *gfx);
/* Size of the default framebuffer in pixels (follows window resizes). */
void gfx_size(const gfx_context *gfx, int *width, int *height);

/* True once the user closed the window (never for offscreen contexts). */
bool gfx_window_should_close(const gfx_context *gfx);
void gfx_window_toggle_fullscreen(gfx_context *gfx);
void gfx_window_set_vsync(gfx_context *gfx, bool vsync);
void gfx_window_set_title(gfx_context *gfx, const char *title);

/* Parses "WxH" (--size), each from 16 to 16384; false for anything else. */
bool gfx_parse_size(const char *text, int *width, int *height);

/* Frame brackets: begin collects finished GPU timings (and reloads changed shaders in debug
 * builds); end swaps the window's buffers, or clears the offscreen depth for the next frame
 * and finishes the frame (README: "The next frame's depth clear"). */
void gfx_frame_begin(gfx_context *gfx);
void gfx_frame_end(gfx_context *gfx);
uint64_t gfx_frame_index(const gfx_context *gfx);

/* What the last finished frame drew, counted in gfx_draw; gfx_frame_end also records them as the
 * trace counters gfx.draw_calls, gfx.triangles and gfx.indirect_draws. Triangles are those of
 * GL_TRIANGLES draws times their instances; an indirect draw's count lives on the GPU, so it is
 * counted in indirect_draws and not in triangles (the grass's patches, for one). */
typedef struct gfx_context_stats_info {
    uint32_t draw_calls;
    uint64_t triangles;
    uint32_t indirect_draws;
} gfx_context_stats_info;
gfx_context_stats_info gfx_context_stats(const gfx_context *gfx);

/* Reads the default framebuffer into `rgba` (width × height × 4 bytes, top row first). */
void gfx_read_pixels(gfx_context *gfx, uint8_t *rgba);
/* Writes the default framebuffer as a PNG (stb_image_write). False, with a message, on failure. */
bool gfx_screenshot(gfx_context *gfx, const char *path);
/* Writes `rgba` (width × height × 4 bytes, top row first) as a PNG. False, with a message. */
bool gfx_write_png(const char *path, int width, int height, const uint8_t *rgba);

/* ---- passes and GPU timing ---------------------------------------------------------------- */

/* A handle (see "Handles" above); { 0 } = none. */
typedef struct gfx_framebuffer { uint32_t id; } gfx_framebuffer;

typedef struct gfx_pass_desc {
    const char *name;              /* trace zone name on the GPU lane; a string literal */
    gfx_framebuffer target;        /* { 0 } = the default framebuffer */
    bool clear_color;              /* clear with .color first */
    float color[4];
    bool clear_depth;              /* clear depth to 1 (offscreen, gfx_frame_end clears the
                                      default framebuffer's depth for the next frame: its first
                                      pass there finds it done; read depth before
                                      gfx_frame_end) */
} gfx_pass_desc;

/* Binds the target, sets the viewport to its size, clears as asked, starts the pass's timer. */
void gfx_pass_begin(gfx_context *gfx, const gfx_pass_desc *desc);
void gfx_pass_end(gfx_context *gfx);

typedef struct gfx_pass_timing {
    const char *name;
    double gpu_ms;
} gfx_pass_timing;
/* GPU times of the passes of the newest frame whose results are in (count written). */
int gfx_pass_timings(const gfx_context *gfx, gfx_pass_timing *timings, int capacity);

/* ---- buffers ------------------------------------------------------------------------------ */

typedef enum gfx_buffer_usage {
    GFX_BUFFER_DEFAULT = 0,    /* = GFX_BUFFER_STATIC */
    GFX_BUFFER_STATIC,         /* written once (meshes) */
    GFX_BUFFER_DYNAMIC,        /* rewritten often (per-frame uniforms, instances) */
} gfx_buffer_usage;

/* A handle (see "Handles" above); { 0 } = none. */
typedef struct gfx_buffer { uint32_t id; } gfx_buffer;

typedef struct gfx_buffer_desc {
    size_t size;               /* bytes */
    const void *data;          /* NULL = uninitialised */
    gfx_buffer_usage usage;    /* DEFAULT = STATIC */
} gfx_buffer_desc;

/* { 0 } (logged) when no context is current or its pool is full. */
gfx_buffer gfx_buffer_create(const gfx_buffer_desc *desc);
void gfx_buffer_update(gfx_buffer buffer, size_t offset, const void *data, size_t size);
/* Destroys the buffer and sets *buffer to { 0 }. */
void gfx_buffer_destroy(gfx_buffer *buffer);
bool gfx_buffer_valid(gfx_buffer buffer);
size_t gfx_buffer_size(gfx_buffer buffer);   /* bytes; 0 for a stale handle */
GLuint gfx_buffer_gl(gfx_buffer buffer);

/* ---- vertex arrays ------------------------------------------------------------------------ */

#define GFX_MAX_ATTRIBUTES 8

typedef struct gfx_attribute {
    int components;            /* 1…4; 0 ends the list */
    GLenum type;               /* GL_FLOAT (0 = GL_FLOAT), GL_UNSIGNED_BYTE, … */
    bool normalized;           /* integer types read as [0, 1] / [-1, 1] */
    uint32_t offset;           /* bytes from the start of a vertex */
    int buffer;                /* 0 = .vertices, 1 = .instances */
} gfx_attribute;

typedef struct gfx_vertex_array_desc {
    gfx_buffer vertices;
    uint32_t vertex_stride;
    gfx_buffer instances;      /* optional, advanced once per instance */
    uint32_t instance_stride;
    gfx_buffer indices;        /* optional */
    gfx_attribute attributes[GFX_MAX_ATTRIBUTES];  /* location = index in this array */
} gfx_vertex_array_desc;

/* A handle (see "Handles" above); { 0 } = none. */
typedef struct gfx_vertex_array { uint32_t id; } gfx_vertex_array;

/* A zero desc makes an array with no attributes (draws whose vertices come from gl_VertexID).
 * The buffers must outlive the array. */
gfx_vertex_array gfx_vertex_array_create(const gfx_vertex_array_desc *desc);
void gfx_vertex_array_destroy(gfx_vertex_array *vertex_array);
bool gfx_vertex_array_valid(gfx_vertex_array vertex_array);
GLuint gfx_vertex_array_gl(gfx_vertex_array vertex_array);

/* ---- textures and framebuffers ------------------------------------------------------------ */

typedef enum gfx_format {
    GFX_FORMAT_DEFAULT = 0,    /* = GFX_FORMAT_RGBA8 */
    GFX_FORMAT_RGBA8,
    GFX_FORMAT_R8,
    GFX_FORMAT_R32F,
    GFX_FORMAT_RG32F,
    GFX_FORMAT_RGBA16F,
    GFX_FORMAT_RGBA32F,
    GFX_FORMAT_DEPTH32F,
    GFX_FORMAT_DEPTH24,        /* the default framebuffer's depth (copies of it keep its bits) */
} gfx_format;

typedef struct gfx_texture_desc {
    int width, height;
    int layers;                /* > 1 makes a 2D array texture (one layer per material, …) */
    bool array;                /* a 2D array texture even with one layer */
    gfx_format format;         /* DEFAULT = RGBA8 */
    const void *data;          /* NULL = uninitialised; all layers, tightly packed */
    bool mipmaps;              /* generate a full chain, trilinear filtering */
    bool nearest;              /* nearest filtering (default linear) */
    bool clamp;                /* clamp to edge (default repeat) */
    bool compare;              /* depth formats: sampled with comparison (sampler2DShadow, …):
                                  the reference ≤ the stored depth gives 1 */
} gfx_texture_desc;

/* A handle (see "Handles" above); { 0 } = none. */
typedef struct gfx_texture { uint32_t id; } gfx_texture;

/* { 0 } (logged) when no context is current or its pool is full. */
gfx_texture gfx_texture_create(const gfx_texture_desc *desc);
/* Rewrites a rectangle of one layer (data tightly packed in the texture's format). */
void gfx_texture_update(gfx_texture texture, int layer, int x, int y, int width, int height,
                        const void *data);
void gfx_texture_bind(gfx_texture texture, int unit);
void gfx_texture_destroy(gfx_texture *texture);
bool gfx_texture_valid(gfx_texture texture);
GLuint gfx_texture_gl(gfx_texture texture);

typedef struct gfx_framebuffer_desc {
    int width, height;
    gfx_format color_format;   /* one colour attachment; DEFAULT = RGBA8 */
    bool depth_only;           /* no colour attachment (shadow maps) */
    bool depth;                /* add a DEPTH32F attachment */
    gfx_texture depth_texture; /* instead: draw depth into this texture's layer .depth_layer; the
                                  texture is not the framebuffer's and outlives it */
    int depth_layer;
} gfx_framebuffer_desc;

/* { 0 } (message logged) when the driver refuses the combination. Destroying it destroys the
 * attachments it made. */
gfx_framebuffer gfx_framebuffer_create(const gfx_framebuffer_desc *desc);
void gfx_framebuffer_destroy(gfx_framebuffer *framebuffer);
bool gfx_framebuffer_valid(gfx_framebuffer framebuffer);
GLuint gfx_framebuffer_gl(gfx_framebuffer framebuffer);
/* Its attachments ({ 0 } where it has none) and size (0 × 0 for a stale handle). */
gfx_texture gfx_framebuffer_color(gfx_framebuffer framebuffer);
gfx_texture gfx_framebuffer_depth(gfx_framebuffer framebuffer);
void gfx_framebuffer_size(gfx_framebuffer framebuffer, int *width, int *height);

/* ---- programs ----------------------------------------------------------------------------- */

/* A handle that stays valid when the program is rebuilt from changed files. id 0 = none.
 * Programs live as long as their context (none is destroyed alone), so they need no
 * generation: an id is a slot number, checked against the context's count. */
typedef struct gfx_program { uint32_t id; } gfx_program;

/* Files are names inside the shader folder ("scene.vert"). A compute program passes
 * (NULL, NULL, "grass.comp") to gfx_program_load_compute. */
gfx_program gfx_program_load(gfx_context *gfx, const char *vertex_file, const char *fragment_file);
gfx_program gfx_program_load_compute(gfx_context *gfx, const char *compute_file);
/* Builds from source strings (named `name` in messages); not reloaded. */
gfx_program gfx_program_from_source(gfx_context *gfx, const char *name, const char *vertex_source,
                                    const char *fragment_source);
void gfx_program_use(gfx_context *gfx, gfx_program program);
/* The GL name of the program as it is now (changes on reload). */
GLuint gfx_program_gl(const gfx_context *gfx, gfx_program program);
/* Rebuilds every program whose files changed; returns how many were rebuilt. */
int gfx_programs_reload_changed(gfx_context *gfx);

/* Uniforms by name on the program in use (locations cached per program). A name the program
 * does not use (optimised away) is ignored. */
void gfx_uniform_float(gfx_context *gfx, gfx_program program, const char *name, float value);
void gfx_uniform_int(gfx_context *gfx, gfx_program program, const char *name, int value);
void gfx_uniform_vec2(gfx_context *gfx, gfx_program program, const char *name, const float *value);
void gfx_uniform_vec3(gfx_context *gfx, gfx_program program, const char *name, const float *value);
void gfx_uniform_vec4(gfx_context *gfx, gfx_program program, const char *name, const float *value);
void gfx_uniform_mat4(gfx_context *gfx, gfx_program program, const char *name, const float *value);

/* ---- draws -------------------------------------------------------------------------------- */

typedef enum gfx_index_type {
    GFX_INDEX_DEFAULT = 0,     /* = GFX_INDEX_NONE */
    GFX_INDEX_NONE,            /* no index buffer: glDrawArrays */
    GFX_INDEX_U16,
    GFX_INDEX_U32,
} gfx_index_type;

typedef struct gfx_draw_desc {
    gfx_vertex_array vertex_array;
    GLenum primitive;          /* 0 = GL_TRIANGLES */
    gfx_index_type index_type; /* DEFAULT = NONE = glDrawArrays */
    uint32_t first;            /* first vertex, or first index */
    uint32_t count;            /* vertices or indices */
    uint32_t instances;        /* 0 = 1, not instanced */
    int32_t base_vertex;
    /* vertex_array: required (a zero one is a programmer error, as a stale one).
     * Indirect: when .indirect.id is set, the draw parameters come from that buffer (a
     * DrawArraysIndirectCommand or DrawElementsIndirectCommand at .indirect_offset); for
     * GPU-generated draws such as grass. .count etc. are then ignored. */
    gfx_buffer indirect;
    size_t indirect_offset;
} gfx_draw_desc;

void gfx_draw(const gfx_draw_desc *desc);

/* ---- text --------------------------------------------------------------------------------- */

/* HUD text over the frame: queue strings during the frame, draw them once at its end.
 *     gfx_text *hud = gfx_text_create(gfx);
 *     gfx_text_print(hud, 8, 8, 2, (float[4]){ 1, 1, 1, 1 }, "%.1f ms", frame_ms);
 *     gfx_text_draw(hud);                          // one pass named "hud"
 * Positions in pixels from the top-left corner; glyphs are about 7 × 10 units (stb_easy_font) times
 * `scale`, with a shadow one unit down and right. */
typedef struct gfx_text gfx_text;
gfx_text *gfx_text_create(gfx_context *gfx);      /* NULL when its shaders fail */
void gfx_text_print(gfx_text *text, float x, float y, float scale, const float color[4], const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
void gfx_text_draw(gfx_text *text);
/* Pixels the text's widest line takes at `scale` (the shadow adds `scale` more). */
float gfx_text_width(const char *text, float scale);
void gfx_text_destroy(gfx_text *text);

/* ---- a reference scene -------------------------------------------------------------------- */

/* A lit sphere standing on a ground grid under a sky gradient: the scene the render tests, the
 * frame benchmark and `tools/play` (until the world exists) draw to check a platform. */
typedef struct gfx_scene gfx_scene;

typedef struct gfx_camera {
    float position[3];
    float yaw, pitch;          /* radians: yaw 0 looks along −z, positive turns right */
    float fov_y;               /* radians; 0 = 60° */
} gfx_camera;

gfx_scene *gfx_scene_create(gfx_context *gfx);   /* NULL when its shaders fail */
void gfx_scene_draw(gfx_scene *scene, const gfx_camera *camera, double seconds);
void gfx_scene_destroy(gfx_scene *scene);
/* The camera the tests and the benchmark use: eye at (0, 1.6, 5) looking at the sphere. */
gfx_camera gfx_scene_default_camera(void);

#endif
