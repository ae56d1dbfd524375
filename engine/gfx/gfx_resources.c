/* gfx_resources.c — buffers, vertex arrays, textures, framebuffers, passes and draws: a thin
 * layer over OpenGL 4.5's direct state access, so creating a thing never disturbs bindings. */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

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
    if (desc->target) {
        target = desc->target->id;
        width = desc->target->width;
        height = desc->target->height;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glViewport(0, 0, width, height);
    GLbitfield clear = 0;
    if (desc->clear_color) {
        glClearColor(desc->color[0], desc->color[1], desc->color[2], desc->color[3]);
        clear |= GL_COLOR_BUFFER_BIT;
    }
    if (desc->clear_depth) {
        glDepthMask(GL_TRUE);
        glClearDepth(1.0);
        clear |= GL_DEPTH_BUFFER_BIT;
    }
    if (clear) glClear(clear);
}

void gfx_pass_end(gfx_context *gfx) {
    gfx__timer_pass_end(gfx);
    trace_zone_end();
}

/* ---- buffers ---- */

gfx_buffer gfx_buffer_create(const gfx_buffer_desc *desc) {
    gfx_buffer buffer = { 0, desc->size };
    glCreateBuffers(1, &buffer.id);
    GLenum usage = desc->usage == GFX_BUFFER_DYNAMIC ? GL_DYNAMIC_DRAW : GL_STATIC_DRAW;
    glNamedBufferData(buffer.id, (GLsizeiptr)desc->size, desc->data, usage);
    return buffer;
}

void gfx_buffer_update(gfx_buffer buffer, size_t offset, const void *data, size_t size) {
    if (offset + size > buffer.size) {
        core_log_error("gfx", "buffer update of %zu bytes at %zu overruns a %zu-byte buffer", size,
                   offset, buffer.size);
        return;
    }
    glNamedBufferSubData(buffer.id, (GLintptr)offset, (GLsizeiptr)size, data);
}

void gfx_buffer_destroy(gfx_buffer *buffer) {
    if (buffer->id) glDeleteBuffers(1, &buffer->id);
    *buffer = (gfx_buffer){ 0 };
}

/* ---- vertex arrays ---- */

static bool gfx_type_is_integer_attribute(GLenum type, bool normalized) {
    if (normalized || type == GL_FLOAT || type == GL_HALF_FLOAT || type == GL_DOUBLE) return false;
    return true;
}

gfx_vertex_array gfx_vertex_array_create(const gfx_vertex_array_desc *desc) {
    gfx_vertex_array array = { 0 };
    glCreateVertexArrays(1, &array.id);
    glVertexArrayVertexBuffer(array.id, 0, desc->vertices.id, 0, (GLsizei)desc->vertex_stride);
    if (desc->instances.id) {
        glVertexArrayVertexBuffer(array.id, 1, desc->instances.id, 0, (GLsizei)desc->instance_stride);
        glVertexArrayBindingDivisor(array.id, 1, 1);
    }
    for (GLuint location = 0; location < GFX_MAX_ATTRIBUTES; location++) {
        const gfx_attribute *a = &desc->attributes[location];
        if (a->components == 0) break;
        GLenum type = a->type ? a->type : GL_FLOAT;
        glEnableVertexArrayAttrib(array.id, location);
        if (gfx_type_is_integer_attribute(type, a->normalized))
            glVertexArrayAttribIFormat(array.id, location, a->components, type, a->offset);
        else
            glVertexArrayAttribFormat(array.id, location, a->components, type,
                                      a->normalized ? GL_TRUE : GL_FALSE, a->offset);
        glVertexArrayAttribBinding(array.id, location, a->buffer == 1 ? 1 : 0);
    }
    if (desc->indices.id) glVertexArrayElementBuffer(array.id, desc->indices.id);
    return array;
}

void gfx_vertex_array_destroy(gfx_vertex_array *vertex_array) {
    if (vertex_array->id) glDeleteVertexArrays(1, &vertex_array->id);
    vertex_array->id = 0;
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
    case GFX_FORMAT_RGBA8:
    default:                  return (gfx_format_info){ GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4 };
    }
}

static int gfx_mip_levels(int width, int height) {
    int levels = 1;
    while ((width | height) >> levels) levels++;
    return levels;
}

gfx_texture gfx_texture_create(const gfx_texture_desc *desc) {
    gfx_format_info info = gfx_format_get(desc->format);
    int layers = desc->layers > 1 ? desc->layers : 1;
    gfx_texture texture = { .target = layers > 1 ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D,
                            .width = desc->width, .height = desc->height, .layers = layers,
                            .format = desc->format };
    int levels = desc->mipmaps ? gfx_mip_levels(desc->width, desc->height) : 1;
    glCreateTextures(texture.target, 1, &texture.id);
    if (layers > 1) glTextureStorage3D(texture.id, levels, info.internal, desc->width, desc->height, layers);
    else glTextureStorage2D(texture.id, levels, info.internal, desc->width, desc->height);
    GLint wrap = desc->clamp ? GL_CLAMP_TO_EDGE : GL_REPEAT;
    glTextureParameteri(texture.id, GL_TEXTURE_WRAP_S, wrap);
    glTextureParameteri(texture.id, GL_TEXTURE_WRAP_T, wrap);
    GLint magnify = desc->nearest ? GL_NEAREST : GL_LINEAR;
    GLint minify = desc->mipmaps ? (desc->nearest ? GL_NEAREST_MIPMAP_NEAREST : GL_LINEAR_MIPMAP_LINEAR)
                                 : magnify;
    glTextureParameteri(texture.id, GL_TEXTURE_MAG_FILTER, magnify);
    glTextureParameteri(texture.id, GL_TEXTURE_MIN_FILTER, minify);
    if (desc->data) {
        size_t layer_bytes = (size_t)desc->width * (size_t)desc->height * (size_t)info.bytes;
        for (int layer = 0; layer < layers; layer++)
            gfx_texture_update(texture, layer, 0, 0, desc->width, desc->height,
                               (const uint8_t *)desc->data + layer_bytes * (size_t)layer);
        if (desc->mipmaps) glGenerateTextureMipmap(texture.id);
    }
    return texture;
}

void gfx_texture_update(gfx_texture texture, int layer, int x, int y, int width, int height,
                        const void *data) {
    gfx_format_info info = gfx_format_get(texture.format);
    if (texture.target == GL_TEXTURE_2D_ARRAY)
        glTextureSubImage3D(texture.id, 0, x, y, layer, width, height, 1, info.format, info.type, data);
    else
        glTextureSubImage2D(texture.id, 0, x, y, width, height, info.format, info.type, data);
}

void gfx_texture_bind(gfx_texture texture, int unit) { glBindTextureUnit((GLuint)unit, texture.id); }

void gfx_texture_destroy(gfx_texture *texture) {
    if (texture->id) glDeleteTextures(1, &texture->id);
    *texture = (gfx_texture){ 0 };
}

/* ---- framebuffers ---- */

bool gfx_framebuffer_create(gfx_framebuffer *framebuffer, const gfx_framebuffer_desc *desc) {
    *framebuffer = (gfx_framebuffer){ .width = desc->width, .height = desc->height };
    glCreateFramebuffers(1, &framebuffer->id);
    framebuffer->color = gfx_texture_create(&(gfx_texture_desc){
        .width = desc->width, .height = desc->height, .format = desc->color_format, .clamp = true });
    glNamedFramebufferTexture(framebuffer->id, GL_COLOR_ATTACHMENT0, framebuffer->color.id, 0);
    if (desc->depth) {
        framebuffer->depth = gfx_texture_create(&(gfx_texture_desc){
            .width = desc->width, .height = desc->height, .format = GFX_FORMAT_DEPTH32F, .clamp = true,
            .nearest = true });
        glNamedFramebufferTexture(framebuffer->id, GL_DEPTH_ATTACHMENT, framebuffer->depth.id, 0);
    }
    GLenum status = glCheckNamedFramebufferStatus(framebuffer->id, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        core_log_error("gfx", "framebuffer %dx%d is incomplete (status 0x%x)", desc->width, desc->height,
                   status);
        gfx_framebuffer_destroy(framebuffer);
        return false;
    }
    return true;
}

void gfx_framebuffer_destroy(gfx_framebuffer *framebuffer) {
    if (framebuffer->id) glDeleteFramebuffers(1, &framebuffer->id);
    gfx_texture_destroy(&framebuffer->color);
    gfx_texture_destroy(&framebuffer->depth);
    *framebuffer = (gfx_framebuffer){ 0 };
}

/* ---- draws ---- */

gfx_context_stats_info gfx__frame_counts;

void gfx_draw(const gfx_draw_desc *desc) {
    GLenum primitive = desc->primitive ? desc->primitive : GL_TRIANGLES;
    GLsizei instances = desc->instances ? (GLsizei)desc->instances : 1;
    gfx__frame_counts.draw_calls++;
    if (desc->indirect.id) gfx__frame_counts.indirect_draws++;
    else if (primitive == GL_TRIANGLES) gfx__frame_counts.triangles += (uint64_t)(desc->count / 3) * (uint64_t)instances;
    glBindVertexArray(desc->vertex_array.id);
    GLenum index_type = desc->index_type == GFX_INDEX_U16 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
    size_t index_size = desc->index_type == GFX_INDEX_U16 ? 2 : 4;
    if (desc->indirect.id) {
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, desc->indirect.id);
        const void *offset = (const void *)(uintptr_t)desc->indirect_offset;
        if (desc->index_type == GFX_INDEX_NONE) glDrawArraysIndirect(primitive, offset);
        else glDrawElementsIndirect(primitive, index_type, offset);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    } else if (desc->index_type == GFX_INDEX_NONE) {
        glDrawArraysInstanced(primitive, (GLint)desc->first, (GLsizei)desc->count, instances);
    } else {
        const void *offset = (const void *)(uintptr_t)(desc->first * index_size);
        glDrawElementsInstancedBaseVertex(primitive, (GLsizei)desc->count, index_type, offset,
                                          instances, desc->base_vertex);
    }
}
