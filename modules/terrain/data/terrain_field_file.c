/* terrain_field_file.c — fields on disk (PREFIX.raw + PREFIX.json) and meshes as PLY.
 *
 * Files come from outside, so reading checks everything and never trusts a size: the header's
 * keys and types, the dimensions' range, the .raw's size against the dimensions before anything
 * is allocated, and every value's finiteness. Errors name the file and what was wrong. Writing
 * goes to a temporary beside the target, renamed over it once complete.
 */
#include "terrain/data/terrain_data.h"

#include "core/core.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define FIELD_HEADER_MAX_BYTES (1u << 20)
/* A field file may hold up to 2^30 samples (4 GiB of floats). */
#define FIELD_FILE_MAX_SAMPLES ((uint64_t)1 << 30)


/* ---- little-endian floats ----------------------------------------------------------------- */

static void put_f32le(uint8_t *out, float value) {
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    for (int i = 0; i < 4; i++) out[i] = (uint8_t)(bits >> (8 * i));
}

static float get_f32le(const uint8_t *in) {
    uint32_t bits = (uint32_t)in[0] | (uint32_t)in[1] << 8 | (uint32_t)in[2] << 16 | (uint32_t)in[3] << 24;
    float value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

static void put_u32le(uint8_t *out, uint32_t value) {
    for (int i = 0; i < 4; i++) out[i] = (uint8_t)(value >> (8 * i));
}

/* ---- the header ------------------------------------------------------------------------------ */

static bool header_vector(const core_json_value *root, const char *key, double out[3], core_error *error) {
    const core_json_value *value = core_json_get(root, key);
    if (!value) return core_error_set(error, CORE_ERROR_FORMAT, "missing key \"%s\"", key);
    if (value->type != CORE_JSON_ARRAY || value->array.count != 3)
        return core_error_set(error, CORE_ERROR_FORMAT, "\"%s\" must be an array of 3 numbers", key);
    for (int a = 0; a < 3; a++) {
        const core_json_value *item = &value->array.items[a];
        if (item->type != CORE_JSON_NUMBER)
            return core_error_set(error, CORE_ERROR_FORMAT, "\"%s\"[%d] must be a number", key, a);
        if (!isfinite(item->number))
            return core_error_set(error, CORE_ERROR_RANGE, "\"%s\"[%d] = %g is not finite", key, a, item->number);
        out[a] = item->number;
    }
    return true;
}

bool terrain_field_header_parse(const char *text, size_t size, terrain_field_header *out, core_error *error) {
    memset(out, 0, sizeof *out);
    core_arena arena = { 0 };
    core_json_value *root;
    core_error json_error = { 0 };
    bool ok = false;
    double dims[3], origin[3];
    if (!core_json_parse(text, size, &arena, &root, &json_error)) {
        core_error_set(error, CORE_ERROR_FORMAT, "not JSON: %s", json_error.message);
    } else if (root->type != CORE_JSON_OBJECT) {
        core_error_set(error, CORE_ERROR_FORMAT, "the header must be a JSON object");
    } else if (header_vector(root, "dims", dims, error) &&
               header_vector(root, "origin", origin, error)) {
        const core_json_value *spacing = core_json_get(root, "spacing");
        ok = true;
        uint64_t samples = 1;
        for (int a = 0; a < 3 && ok; a++) {
            if (dims[a] != floor(dims[a]) || dims[a] < 1 || dims[a] > TERRAIN_FIELD_FILE_MAX_DIM)
                ok = core_error_set(error, CORE_ERROR_RANGE, "\"dims\"[%d] = %g is not a whole number in 1 … %d", a,
                                dims[a], TERRAIN_FIELD_FILE_MAX_DIM);
            else samples *= (uint64_t)dims[a];
        }
        if (ok && samples > FIELD_FILE_MAX_SAMPLES)
            ok = core_error_set(error, CORE_ERROR_RANGE, "\"dims\" give %llu samples, over the limit of %llu",
                            (unsigned long long)samples, (unsigned long long)FIELD_FILE_MAX_SAMPLES);
        if (ok && !spacing) ok = core_error_set(error, CORE_ERROR_FORMAT, "missing key \"spacing\"");
        if (ok && spacing->type != CORE_JSON_NUMBER) ok = core_error_set(error, CORE_ERROR_FORMAT, "\"spacing\" must be a number");
        /* A float must hold it, positive and finite. */
        if (ok && !(spacing->number > 0.0 && spacing->number <= 1e30 && (float)spacing->number > 0.0f))
            ok = core_error_set(error, CORE_ERROR_RANGE, "\"spacing\" = %g must be a positive finite number", spacing->number);
        if (ok) {
            for (int a = 0; a < 3; a++) out->dims[a] = (int)dims[a], out->origin[a] = origin[a];
            out->spacing = (float)spacing->number;
        }
    }
    core_arena_release(&arena);
    if (!ok) memset(out, 0, sizeof *out);
    return ok;
}

/* ---- paths and whole files ------------------------------------------------------------------- */

/* PREFIX from PREFIX, PREFIX.json or PREFIX.raw; caller frees with core_free(p, strlen(p) + 1). */
static char *field_prefix(const char *path) {
    size_t length = strlen(path);
    if (length > 5 && strcmp(path + length - 5, ".json") == 0) length -= 5;
    else if (length > 4 && strcmp(path + length - 4, ".raw") == 0) length -= 4;
    char *prefix = core_alloc(length + 1);
    memcpy(prefix, path, length);
    prefix[length] = '\0';
    return prefix;
}

static void path_free(char *path) { core_free(path, strlen(path) + 1); }

/* Writes `size` bytes to a temporary beside `path`, then renames it over `path`. */
static bool write_whole_file(const char *path, const void *data, size_t size, core_error *error) {
    char *temporary = core_alloc(strlen(path) + 32);
    sprintf(temporary, "%s.tmp%ld", path, (long)getpid());
    FILE *file = fopen(temporary, "wb");
    bool ok = file != NULL;
    if (!ok) core_error_set(error, CORE_ERROR_IO, "cannot write %s: %s", path, strerror(errno));
    if (ok && size && fwrite(data, 1, size, file) != size) ok = core_error_set(error, CORE_ERROR_IO, "cannot write %s: %s", path, strerror(errno));
    if (file && fclose(file) != 0 && ok) ok = core_error_set(error, CORE_ERROR_IO, "cannot write %s: %s", path, strerror(errno));
    if (ok && rename(temporary, path) != 0) ok = core_error_set(error, CORE_ERROR_IO, "cannot write %s: %s", path, strerror(errno));
    if (!ok && file) remove(temporary);
    core_free(temporary, strlen(path) + 32);
    return ok;
}

/* ---- fields ---------------------------------------------------------------------------------- */

bool terrain_field_write(const terrain_field *field, const char *prefix, core_error *error) {
    if (!field->values || field->nx <= 0 || field->ny <= 0 || field->nz <= 0)
        return core_error_set(error, CORE_ERROR_ARGUMENT, "cannot write %s: the field is empty", prefix);
    size_t count = (size_t)field->nx * field->ny * field->nz;
    uint8_t *bytes = core_alloc(count * 4);
    for (size_t i = 0; i < count; i++) put_f32le(bytes + 4 * i, field->values[i]);
    char *raw = core_strjoin(prefix, ".raw"), *json = core_strjoin(prefix, ".json");
    bool ok = write_whole_file(raw, bytes, count * 4, error);
    core_free(bytes, count * 4);
    if (ok) {
        char header[512];
        int length = snprintf(header, sizeof header, "{\"dims\":[%d,%d,%d],\"origin\":[%.17g,%.17g,%.17g],\"spacing\":%.9g}\n",
                              field->nx, field->ny, field->nz, field->origin[0], field->origin[1],
                              field->origin[2], (double)field->spacing);
        ok = write_whole_file(json, header, (size_t)length, error);
    }
    path_free(raw);
    path_free(json);
    return ok;
}

/* Reads at most `limit` bytes of `path`; false when it is larger or unreadable. */
static bool read_small_file(const char *path, size_t limit, char **out, size_t *size, core_error *error) {
    FILE *file = fopen(path, "rb");
    if (!file) return core_error_set(error, CORE_ERROR_IO, "cannot open %s: %s", path, strerror(errno));
    char *text = core_alloc(limit + 1);
    size_t got = fread(text, 1, limit + 1, file);
    bool failed = ferror(file);
    fclose(file);
    if (failed || got > limit) {
        core_free(text, limit + 1);
        return failed ? core_error_set(error, CORE_ERROR_IO, "cannot read %s", path)
                      : core_error_set(error, CORE_ERROR_RANGE, "%s: the header is over 1 MiB", path);
    }
    *out = text;
    *size = got;
    return true;
}

bool terrain_field_read(const char *path, terrain_field *out, core_error *error) {
    memset(out, 0, sizeof *out);
    char *prefix = field_prefix(path);
    char *json = core_strjoin(prefix, ".json"), *raw = core_strjoin(prefix, ".raw");
    path_free(prefix);
    bool ok = false;
    char *text = NULL;
    size_t text_size = 0;
    terrain_field_header header;
    core_error header_error = { 0 };
    FILE *file = NULL;
    if (!read_small_file(json, FIELD_HEADER_MAX_BYTES, &text, &text_size, error)) goto done;
    if (!terrain_field_header_parse(text, text_size, &header, &header_error)) {
        core_error_set(error, header_error.code, "%s: %s", json, header_error.message);
        goto done;
    }
    uint64_t count = (uint64_t)header.dims[0] * header.dims[1] * header.dims[2];
    file = fopen(raw, "rb");
    struct stat info;
    if (!file || fstat(fileno(file), &info) != 0) {
        core_error_set(error, CORE_ERROR_IO, "cannot open %s: %s", raw, strerror(errno));
        goto done;
    }
    if (!S_ISREG(info.st_mode) || (uint64_t)info.st_size != count * 4) {
        core_error_set(error, CORE_ERROR_CORRUPT, "%s holds %lld bytes, but dims %d × %d × %d in %s need %llu (float32 each)",
                   raw, (long long)info.st_size, header.dims[0], header.dims[1], header.dims[2], json,
                   (unsigned long long)(count * 4));
        goto done;
    }
    uint8_t *bytes = core_alloc((size_t)count * 4);
    size_t got = fread(bytes, 1, (size_t)count * 4, file);
    if (got != count * 4) {
        core_free(bytes, (size_t)count * 4);
        if (ferror(file)) core_error_set(error, CORE_ERROR_IO, "cannot read %s: %s", raw, strerror(errno));
        else core_error_set(error, CORE_ERROR_CORRUPT, "cannot read %s: shorter than it said", raw);
        goto done;
    }
    float *values = core_alloc((size_t)count * sizeof *values);
    ok = true;
    for (uint64_t i = 0; i < count; i++) {
        values[i] = get_f32le(bytes + 4 * i);
        if (!isfinite(values[i])) {
            int nx = header.dims[0], ny = header.dims[1];
            core_error_set(error, CORE_ERROR_RANGE, "%s: value %llu (x %d, y %d, z %d) is %s", raw, (unsigned long long)i,
                       (int)(i % (uint64_t)nx), (int)(i / (uint64_t)nx % (uint64_t)ny),
                       (int)(i / ((uint64_t)nx * ny)), isnan(values[i]) ? "NaN" : "infinite");
            ok = false;
            break;
        }
    }
    core_free(bytes, (size_t)count * 4);
    if (!ok) {
        core_free(values, (size_t)count * sizeof *values);
        goto done;
    }
    out->nx = header.dims[0], out->ny = header.dims[1], out->nz = header.dims[2];
    memcpy(out->origin, header.origin, sizeof out->origin);
    out->spacing = header.spacing;
    out->values = values;
done:
    if (file) fclose(file);
    if (text) core_free(text, FIELD_HEADER_MAX_BYTES + 1);
    path_free(json);
    path_free(raw);
    return ok;
}

/* ---- meshes as PLY ------------------------------------------------------------------------- */

bool terrain_mesh_write_ply(const terrain_mesh *mesh, const char *path, core_error *error) {
    char header[512];
    uint32_t triangles = mesh->index_count / 3;
    int header_size = snprintf(header, sizeof header,
                               "ply\nformat binary_little_endian 1.0\n"
                               "comment terrain mesh; positions relative to origin %.17g %.17g %.17g\n"
                               "element vertex %u\nproperty float x\nproperty float y\nproperty float z\n"
                               "property float nx\nproperty float ny\nproperty float nz\n"
                               "element face %u\nproperty list uchar uint vertex_indices\nend_header\n",
                               mesh->origin[0], mesh->origin[1], mesh->origin[2], mesh->vertex_count, triangles);
    size_t size = (size_t)header_size + (size_t)mesh->vertex_count * 24 + (size_t)triangles * 13;
    uint8_t *bytes = core_alloc(size), *at = bytes;
    memcpy(at, header, (size_t)header_size);
    at += header_size;
    for (uint32_t i = 0; i < mesh->vertex_count; i++) {
        const terrain_vertex *v = &mesh->vertices[i];
        for (int a = 0; a < 3; a++) put_f32le(at + 4 * a, v->position[a]), put_f32le(at + 12 + 4 * a, v->normal[a]);
        at += 24;
    }
    for (uint32_t t = 0; t < triangles; t++) {
        *at++ = 3;
        for (int k = 0; k < 3; k++, at += 4) put_u32le(at, mesh->indices[3 * t + k]);
    }
    bool ok = write_whole_file(path, bytes, size, error);
    core_free(bytes, size);
    return ok;
}
