/* gfx_resources.c — buffers, vertex arrays, textures, framebuffers, passes and draws: a thin
 * layer over OpenGL 4.5's direct state access, so creating a thing never disturbs bindings.
 * Objects live in the current context's pools (gfx_pool.c) behind generation-checked handles. */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

/* ---- the current context's pools ---- */

gfx_context *gfx__current;

void gfx__resources_init(gfx_context *gfx) {
    /* Each context's slots start at another generation, so a handle kept from an earlier
     * context is unlikely to match an object of this one (an odd stride visits all 65 536). */
    static uint16_t contexts;
    uint16_t first = (uint16_t)(1u + (uint32_t)++contexts * 0x9e37u);
    gfx__pool_init(&gfx->buffers, "buffer", sizeof(gfx__buffer_entry), first);
    gfx__pool_init(&gfx->vertex_arrays, "vertex array", sizeof(gfx__vertex_array_entry), first);
    gfx__pool_init(&gfx->textures, "texture", sizeof(gfx__texture_entry), first);
    gfx__pool_init(&gfx->framebuffers, "framebuffer", sizeof(gfx__framebuffer_entry), first);
    gfx__current = gfx;
}

void gfx__resources_destroy(gfx_context *gfx) {
    /* What is still live dies with the GL context. */
    gfx__pool_destroy(&gfx->buffers);
    gfx__pool_destroy(&gfx->vertex_arrays);
    gfx__pool_destroy(&gfx->textures);
    gfx__pool_destroy(&gfx->framebuffers);
    if (gfx__current == gfx) gfx__current = NULL;
}

#define GFX_POOL(field) (gfx__current ? &gfx__current->field : NULL)

/* The entry a handle names, or NULL after reporting it (debug builds stop there). */
static void *gfx_use(gfx_pool *pool, uint32_t id, const char *call) {
    void *entry = pool ? gfx__pool_lookup(pool, id) : NULL;
    if (!entry) gfx__pool_report(pool, id, call);
    return entry;
}

/* For _destroy: a zero handle is nothing to do, and without a context the object is gone with
 * it; otherwise the live entry, or NULL after reporting a stale handle. */
static void *gfx_use_to_destroy(gfx_pool *pool, uint32_t id, const char *call) {
    if (!id || !pool) return NULL;
    return gfx_use(pool, id, call);
}

static bool gfx_valid(gfx_pool *pool, uint32_t id) { return pool && gfx__pool_lookup(pool, id); }

static gfx__buffer_entry *gfx_buffer_use(gfx_buffer buffer, const char *call) {
    return gfx_use(GFX_POOL(buffers), buffer.id, call);
}
static gfx__texture_entry *gfx_texture_use(gfx_texture texture, const char *call) {
    return gfx_use(GFX_POOL(textures), texture.id, call);
}
static gfx__vertex_array_entry *gfx_vertex_array_use(gfx_vertex_array array, const char *call) {
    return gfx_use(GFX_POOL(vertex_arrays), array.id, call);
}
static gfx__framebuffer_entry *gfx_framebuffer_use(gfx_framebuffer framebuffer, const char *call) {
    return gfx_use(GFX_POOL(framebuffers), framebuffer.id, call);
}

/* A new entry of the current context's pool `field`; NULL (logged) without a context. */
static uint32_t gfx_make(gfx_pool *pool, void **entry, const char *call) {
    if (!pool) {
        core_log_error("gfx", "%s without a context (before gfx_context_create or after gfx_context_destroy)", call);
        return 0;
    }
    return gfx__pool_alloc(pool, entry);
}

/* ---- passes ---- */

void gfx_pass_begin(gfx_context *gfx, const gfx_pass_desc *desc) {
    if (gfx->open_pass >= 0) {
        core_warn("gfx", "pass '%s' begun inside another; ending that one first",
                  desc->name ? desc->name : "pass");
        gfx_pass_end(gfx);
    }
    trace_zone_begin(desc->name ? desc->name : "pass");
    gfx__timer_pass_begin(gfx, desc->name);
    int width = gfx->width, height = gfx->height;
    GLuint target = 0;
    if (desc->target.id) {
        /* A stale target draws into the default framebuffer, never into another object. */
        const gfx__framebuffer_entry *fb = gfx_framebuffer_use(desc->target, "gfx_pass_begin");
        if (fb) {
            target = fb->name;
            width = fb->width;
            height = fb->height;
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glViewport(0, 0, width, height);
    /* The default framebuffer's depth may have been cleared already, by gfx_frame_end; this
     * pass may draw into it, so that holds for one pass only. */
    bool cleared_ahead = target == 0 && gfx->depth_cleared_ahead;
    if (target == 0) gfx->depth_cleared_ahead = false;
    GLbitfield clear = 0;
    if (desc->clear_color) {
        glClearColor(desc->color[0], desc->color[1], desc->color[2], desc->color[3]);
        clear |= GL_COLOR_BUFFER_BIT;
    }
    if (desc->clear_depth) {
        glDepthMask(GL_TRUE);
        glClearDepth(1.0);
        if (!cleared_ahead) clear |= GL_DEPTH_BUFFER_BIT;
    }
    if (clear) glClear(clear);
}

void gfx_pass_end(gfx_context *gfx) {
    gfx__timer_pass_end(gfx);
    trace_zone_end();
}

/* ---- buffers ---- */

gfx_buffer gfx_buffer_create(const gfx_buffer_desc *desc) {
    gfx__buffer_entry *entry;
    gfx_buffer buffer = { gfx_make(GFX_POOL(buffers), (void **)&entry, "gfx_buffer_create") };
    if (!buffer.id) return buffer;
    entry->size = desc->size;
    glCreateBuffers(1, &entry->name);
    GLenum usage = desc->usage == GFX_BUFFER_DYNAMIC ? GL_DYNAMIC_DRAW : GL_STATIC_DRAW;
    glNamedBufferData(entry->name, (GLsizeiptr)desc->size, desc->data, usage);
    return buffer;
}

void gfx_buffer_update(gfx_buffer buffer, size_t offset, const void *data, size_t size) {
    const gfx__buffer_entry *entry = gfx_buffer_use(buffer, "gfx_buffer_update");
    if (!entry) return;
    if (offset + size > entry->size) {
        core_log_error("gfx", "buffer update of %zu bytes at %zu overruns a %zu-byte buffer", size,
                   offset, entry->size);
        return;
    }
    glNamedBufferSubData(entry->name, (GLintptr)offset, (GLsizeiptr)size, data);
}

void gfx_buffer_destroy(gfx_buffer *buffer) {
    gfx_pool *pool = GFX_POOL(buffers);
    gfx__buffer_entry *entry = gfx_use_to_destroy(pool, buffer->id, "gfx_buffer_destroy");
    if (entry) {
        glDeleteBuffers(1, &entry->name);
        gfx__pool_free(pool, buffer->id);
    }
    *buffer = (gfx_buffer){ 0 };
}

bool gfx_buffer_valid(gfx_buffer buffer) { return gfx_valid(GFX_POOL(buffers), buffer.id); }

size_t gfx_buffer_size(gfx_buffer buffer) {
    const gfx__buffer_entry *entry = gfx_buffer_use(buffer, "gfx_buffer_size");
    return entry ? entry->size : 0;
}

GLuint gfx_buffer_gl(gfx_buffer buffer) {
    const gfx__buffer_entry *entry = gfx_buffer_use(buffer, "gfx_buffer_gl");
    return entry ? entry->name : 0;
}

/* ---- vertex arrays ---- */

static bool gfx_type_is_integer_attribute(GLenum type, bool normalized) {
    if (normalized || type == GL_FLOAT || type == GL_HALF_FLOAT || type == GL_DOUBLE) return false;
    return true;
}

static GLuint gfx_buffer_name(gfx_buffer buffer, const char *call) {
    const gfx__buffer_entry *entry = gfx_buffer_use(buffer, call);
    return entry ? entry->name : 0;
}

/* The GL name of an optional buffer: 0 for none; a stale one is reported and left out. */
static GLuint gfx_optional_buffer(gfx_buffer buffer, const char *call) {
    return buffer.id ? gfx_buffer_name(buffer, call) : 0;
}

gfx_vertex_array gfx_vertex_array_create(const gfx_vertex_array_desc *desc) {
    GLuint vertices = gfx_optional_buffer(desc->vertices, "gfx_vertex_array_create");
    GLuint instances = gfx_optional_buffer(desc->instances, "gfx_vertex_array_create");
    GLuint indices = gfx_optional_buffer(desc->indices, "gfx_vertex_array_create");
    gfx__vertex_array_entry *entry;
    gfx_vertex_array array = { gfx_make(GFX_POOL(vertex_arrays), (void **)&entry, "gfx_vertex_array_create") };
    if (!array.id) return array;
    GLuint name;
    glCreateVertexArrays(1, &name);
    entry->name = name;
    if (vertices) glVertexArrayVertexBuffer(name, 0, vertices, 0, (GLsizei)desc->vertex_stride);
    if (instances) {
        glVertexArrayVertexBuffer(name, 1, instances, 0, (GLsizei)desc->instance_stride);
        glVertexArrayBindingDivisor(name, 1, 1);
    }
    for (GLuint location = 0; location < GFX_MAX_ATTRIBUTES; location++) {
        const gfx_attribute *a = &desc->attributes[location];
        if (a->components == 0) break;
        GLenum type = a->type ? a->type : GL_FLOAT;
        glEnableVertexArrayAttrib(name, location);
        if (gfx_type_is_integer_attribute(type, a->normalized))
            glVertexArrayAttribIFormat(name, location, a->components, type, a->offset);
        else
            glVertexArrayAttribFormat(name, location, a->components, type,
                                      a->normalized ? GL_TRUE : GL_FALSE, a->offset);
        glVertexArrayAttribBinding(name, location, a->buffer == 1 ? 1 : 0);
    }
    if (indices) glVertexArrayElementBuffer(name, indices);
    return array;
}

void gfx_vertex_array_destroy(gfx_vertex_array *vertex_array) {
    gfx_pool *pool = GFX_POOL(vertex_arrays);
    gfx__vertex_array_entry *entry = gfx_use_to_destroy(pool, vertex_array->id, "gfx_vertex_array_destroy");
    if (entry) {
        glDeleteVertexArrays(1, &entry->name);
        gfx__pool_free(pool, vertex_array->id);
    }
    *vertex_array = (gfx_vertex_array){ 0 };
}

bool gfx_vertex_array_valid(gfx_vertex_array vertex_array) {
    return gfx_valid(GFX_POOL(vertex_arrays), vertex_array.id);
}

GLuint gfx_vertex_array_gl(gfx_vertex_array vertex_array) {
    const gfx__vertex_array_entry *entry = gfx_vertex_array_use(vertex_array, "gfx_vertex_array_gl");
    return entry ? entry->name : 0;
}

/* ---- textures ---- */

typedef struct gfx_format_info { GLenum internal, format, type; int bytes; } gfx_format_info;

static gfx_format_info gfx_format_get(gfx_format format) {
    switch (format) {
    case GFX_FORMAT_R8:       return (gfx_format_info){ GL_R8, GL_RED, GL_UNSIGNED_BYTE, 1 };
    case GFX_FORMAT_R32F:     return (gfx_format_info){ GL_R32F, GL_RED, GL_FLOAT, 4 };
    case GFX_FORMAT_RG32F:    return (gfx_format_info){ GL_RG32F, GL_RG, GL_FLOAT, 8 };
    case GFX_FORMAT_RGBA16F:  return (gfx_format_info){ GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT, 8 };
    case GFX_FORMAT_RGBA32F:  return (gfx_format_info){ GL_RGBA32F, GL_RGBA, GL_FLOAT, 16 };
    case GFX_FORMAT_DEPTH32F: return (gfx_format_info){ GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT, 4 };
    case GFX_FORMAT_DEPTH24:  return (gfx_format_info){ GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, 4 };
    case GFX_FORMAT_DEFAULT:
    case GFX_FORMAT_RGBA8:
    default:                  return (gfx_format_info){ GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4 };
    }
}

static int gfx_mip_levels(int width, int height) {
    int levels = 1;
    while ((width | height) >> levels) levels++;
    return levels;
}

static void gfx_texture_write(const gfx__texture_entry *entry, int layer, int x, int y, int width,
                              int height, const void *data) {
    gfx_format_info info = gfx_format_get(entry->format);
    if (entry->target == GL_TEXTURE_2D_ARRAY)
        glTextureSubImage3D(entry->name, 0, x, y, layer, width, height, 1, info.format, info.type, data);
    else
        glTextureSubImage2D(entry->name, 0, x, y, width, height, info.format, info.type, data);
}

gfx_texture gfx_texture_create(const gfx_texture_desc *desc) {
    gfx__texture_entry *entry;
    gfx_texture texture = { gfx_make(GFX_POOL(textures), (void **)&entry, "gfx_texture_create") };
    if (!texture.id) return texture;
    gfx_format_info info = gfx_format_get(desc->format);
    int layers = desc->layers > 1 ? desc->layers : 1;
    *entry = (gfx__texture_entry){ .target = layers > 1 || desc->array ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D,
                                   .width = desc->width, .height = desc->height, .layers = layers,
                                   .format = desc->format ? desc->format : GFX_FORMAT_RGBA8 };
    int levels = desc->mipmaps ? gfx_mip_levels(desc->width, desc->height) : 1;
    GLuint name;
    glCreateTextures(entry->target, 1, &name);
    entry->name = name;
    if (entry->target == GL_TEXTURE_2D_ARRAY) glTextureStorage3D(name, levels, info.internal, desc->width, desc->height, layers);
    else glTextureStorage2D(name, levels, info.internal, desc->width, desc->height);
    GLint wrap = desc->clamp ? GL_CLAMP_TO_EDGE : GL_REPEAT;
    glTextureParameteri(name, GL_TEXTURE_WRAP_S, wrap);
    glTextureParameteri(name, GL_TEXTURE_WRAP_T, wrap);
    GLint magnify = desc->nearest ? GL_NEAREST : GL_LINEAR;
    GLint minify = desc->mipmaps ? (desc->nearest ? GL_NEAREST_MIPMAP_NEAREST : GL_LINEAR_MIPMAP_LINEAR)
                                 : magnify;
    glTextureParameteri(name, GL_TEXTURE_MAG_FILTER, magnify);
    glTextureParameteri(name, GL_TEXTURE_MIN_FILTER, minify);
    if (desc->compare) {
        glTextureParameteri(name, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
        glTextureParameteri(name, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    }
    if (desc->data) {
        size_t layer_bytes = (size_t)desc->width * (size_t)desc->height * (size_t)info.bytes;
        for (int layer = 0; layer < layers; layer++)
            gfx_texture_write(entry, layer, 0, 0, desc->width, desc->height,
                              (const uint8_t *)desc->data + layer_bytes * (size_t)layer);
        if (desc->mipmaps) glGenerateTextureMipmap(name);
    }
    return texture;
}

void gfx_texture_update(gfx_texture texture, int layer, int x, int y, int width, int height,
                        const void *data) {
    const gfx__texture_entry *entry = gfx_texture_use(texture, "gfx_texture_update");
    if (entry) gfx_texture_write(entry, layer, x, y, width, height, data);
}

void gfx_texture_bind(gfx_texture texture, int unit) {
    const gfx__texture_entry *entry = gfx_texture_use(texture, "gfx_texture_bind");
    if (entry) glBindTextureUnit((GLuint)unit, entry->name);
}

void gfx_texture_destroy(gfx_texture *texture) {
    gfx_pool *pool = GFX_POOL(textures);
    gfx__texture_entry *entry = gfx_use_to_destroy(pool, texture->id, "gfx_texture_destroy");
    if (entry) {
        glDeleteTextures(1, &entry->name);
        gfx__pool_free(pool, texture->id);
    }
    *texture = (gfx_texture){ 0 };
}

bool gfx_texture_valid(gfx_texture texture) { return gfx_valid(GFX_POOL(textures), texture.id); }

GLuint gfx_texture_gl(gfx_texture texture) {
    const gfx__texture_entry *entry = gfx_texture_use(texture, "gfx_texture_gl");
    return entry ? entry->name : 0;
}

/* ---- framebuffers ---- */

static void gfx_framebuffer_attach(GLuint framebuffer, GLenum attachment, gfx_texture texture, int layer) {
    const gfx__texture_entry *entry = gfx_texture_use(texture, "gfx_framebuffer_create");
    if (!entry) return;
    if (entry->target == GL_TEXTURE_2D_ARRAY)
        glNamedFramebufferTextureLayer(framebuffer, attachment, entry->name, 0, layer);
    else
        glNamedFramebufferTexture(framebuffer, attachment, entry->name, 0);
}

gfx_framebuffer gfx_framebuffer_create(const gfx_framebuffer_desc *desc) {
    gfx__framebuffer_entry *entry;
    gfx_framebuffer framebuffer = { gfx_make(GFX_POOL(framebuffers), (void **)&entry, "gfx_framebuffer_create") };
    if (!framebuffer.id) return framebuffer;
    GLuint name;
    glCreateFramebuffers(1, &name);
    *entry = (gfx__framebuffer_entry){ .name = name, .width = desc->width, .height = desc->height };
    if (desc->depth_only) {
        glNamedFramebufferDrawBuffer(name, GL_NONE);
        glNamedFramebufferReadBuffer(name, GL_NONE);
    } else {
        gfx_texture color = gfx_texture_create(&(gfx_texture_desc){
            .width = desc->width, .height = desc->height, .format = desc->color_format, .clamp = true });
        gfx_framebuffer_attach(name, GL_COLOR_ATTACHMENT0, color, 0);
        entry->color = color;
    }
    if (desc->depth_texture.id) {
        gfx_framebuffer_attach(name, GL_DEPTH_ATTACHMENT, desc->depth_texture, desc->depth_layer);
        entry->depth_borrowed = desc->depth_texture;
    } else if (desc->depth) {
        gfx_texture depth = gfx_texture_create(&(gfx_texture_desc){
            .width = desc->width, .height = desc->height, .format = GFX_FORMAT_DEPTH32F, .clamp = true,
            .nearest = true });
        gfx_framebuffer_attach(name, GL_DEPTH_ATTACHMENT, depth, 0);
        entry->depth = depth;
    }
    GLenum status = glCheckNamedFramebufferStatus(name, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        core_log_error("gfx", "framebuffer %dx%d is incomplete (status 0x%x)", desc->width, desc->height,
                   status);
        gfx_framebuffer_destroy(&framebuffer);
    }
    return framebuffer;
}

void gfx_framebuffer_destroy(gfx_framebuffer *framebuffer) {
    gfx_pool *pool = GFX_POOL(framebuffers);
    gfx__framebuffer_entry *entry = gfx_use_to_destroy(pool, framebuffer->id, "gfx_framebuffer_destroy");
    if (entry) {
        glDeleteFramebuffers(1, &entry->name);
        gfx_texture_destroy(&entry->color);
        gfx_texture_destroy(&entry->depth);
        gfx__pool_free(pool, framebuffer->id);
    }
    *framebuffer = (gfx_framebuffer){ 0 };
}

bool gfx_framebuffer_valid(gfx_framebuffer framebuffer) {
    return gfx_valid(GFX_POOL(framebuffers), framebuffer.id);
}

GLuint gfx_framebuffer_gl(gfx_framebuffer framebuffer) {
    const gfx__framebuffer_entry *entry = gfx_framebuffer_use(framebuffer, "gfx_framebuffer_gl");
    return entry ? entry->name : 0;
}

gfx_texture gfx_framebuffer_color(gfx_framebuffer framebuffer) {
    const gfx__framebuffer_entry *entry = gfx_framebuffer_use(framebuffer, "gfx_framebuffer_color");
    return entry ? entry->color : (gfx_texture){ 0 };
}

gfx_texture gfx_framebuffer_depth(gfx_framebuffer framebuffer) {
    const gfx__framebuffer_entry *entry = gfx_framebuffer_use(framebuffer, "gfx_framebuffer_depth");
    if (!entry) return (gfx_texture){ 0 };
    return entry->depth.id ? entry->depth : entry->depth_borrowed;
}

void gfx_framebuffer_size(gfx_framebuffer framebuffer, int *width, int *height) {
    const gfx__framebuffer_entry *entry = gfx_framebuffer_use(framebuffer, "gfx_framebuffer_size");
    *width = entry ? entry->width : 0;
    *height = entry ? entry->height : 0;
}

/* ---- draws ---- */

gfx_context_stats_info gfx__frame_counts;

void gfx_draw(const gfx_draw_desc *desc) {
    const gfx__vertex_array_entry *array = gfx_vertex_array_use(desc->vertex_array, "gfx_draw");
    if (!array) return;
    GLuint indirect = 0;
    if (desc->indirect.id) {
        const gfx__buffer_entry *buffer = gfx_buffer_use(desc->indirect, "gfx_draw");
        if (!buffer) return;
        indirect = buffer->name;
    }
    GLenum primitive = desc->primitive ? desc->primitive : GL_TRIANGLES;
    GLsizei instances = desc->instances ? (GLsizei)desc->instances : 1;
    gfx__frame_counts.draw_calls++;
    if (indirect) gfx__frame_counts.indirect_draws++;
    else if (primitive == GL_TRIANGLES) gfx__frame_counts.triangles += (uint64_t)(desc->count / 3) * (uint64_t)instances;
    glBindVertexArray(array->name);
    bool indexed = desc->index_type == GFX_INDEX_U16 || desc->index_type == GFX_INDEX_U32;  /* DEFAULT = NONE */
    GLenum index_type = desc->index_type == GFX_INDEX_U16 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
    size_t index_size = desc->index_type == GFX_INDEX_U16 ? 2 : 4;
    if (indirect) {
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect);
        const void *offset = (const void *)(uintptr_t)desc->indirect_offset;
        if (!indexed) glDrawArraysIndirect(primitive, offset);
        else glDrawElementsIndirect(primitive, index_type, offset);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    } else if (!indexed) {
        glDrawArraysInstanced(primitive, (GLint)desc->first, (GLsizei)desc->count, instances);
    } else {
        const void *offset = (const void *)(uintptr_t)(desc->first * index_size);
        glDrawElementsInstancedBaseVertex(primitive, (GLsizei)desc->count, index_type, offset,
                                          instances, desc->base_vertex);
    }
}
