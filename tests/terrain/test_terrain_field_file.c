/* Field files (PREFIX.raw + PREFIX.json) and PLY meshes: round trips, and every kind of bad
 * file refused with the error code of its kind and a message that names the file. */
#include "../engine/test.h"
#include "core/core.h"
#include "terrain/terrain.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char *temp_dir(void) {
    static char path[64];
    snprintf(path, sizeof path, "/tmp/terrain_field_file_XXXXXX");
    cr_assert_not_null(mkdtemp(path));
    return path;
}

static void remove_dir(const char *dir) {
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char path[512];
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        remove(path);
    }
    closedir(d);
    rmdir(dir);
}

static int count_files(const char *dir) {
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f);
    fputs(text, f);
    fclose(f);
}

static terrain_field small_field(void) {
    terrain_field f = { .nx = 3, .ny = 4, .nz = 5, .origin = { -1.5, 1e9 + 0.25, -7 }, .spacing = 0.5f };
    f.values = core_alloc(60 * sizeof(float));
    for (int i = 0; i < 60; i++) f.values[i] = (float)i * 0.125f - 3.0f;
    return f;
}

Test(terrain_field_file, round_trip) {
    char *dir = temp_dir(), prefix[128], path[160];
    snprintf(prefix, sizeof prefix, "%s/field", dir);
    terrain_field f = small_field();
    core_error error = { 0 };
    cr_assert(terrain_field_write(&f, prefix, &error), "%s", error.message);
    cr_expect_eq(count_files(dir), 2, "just .raw and .json: no temporaries left");
    /* The raw file is the values, little-endian, x fastest. */
    snprintf(path, sizeof path, "%s.raw", prefix);
    FILE *raw = fopen(path, "rb");
    unsigned char bytes[8];
    cr_assert_eq(fread(bytes, 1, 8, raw), 8);
    fclose(raw);
    cr_expect(bytes[0] == 0 && bytes[1] == 0 && bytes[2] == 0x40 && bytes[3] == 0xc0, "-3.0f little-endian");
    /* Read back through each spelling of the path. */
    const char *suffixes[] = { "", ".json", ".raw" };
    for (size_t s = 0; s < 3; s++) {
        snprintf(path, sizeof path, "%s%s", prefix, suffixes[s]);
        terrain_field g;
        cr_assert(terrain_field_read(path, &g, &error), "%s", error.message);
        cr_expect_eq(g.nx, 3);
        cr_expect_eq(g.ny, 4);
        cr_expect_eq(g.nz, 5);
        cr_expect_eq(g.spacing, 0.5f);
        for (int a = 0; a < 3; a++) cr_expect_eq(g.origin[a], f.origin[a], "origin exact");
        cr_expect_eq(memcmp(g.values, f.values, 60 * sizeof(float)), 0);
        terrain_field_free(&g);
    }
    terrain_field_free(&f);
    remove_dir(dir);
}

/* Reading `json` (and a raw of `raw_bytes` bytes, NULL = none) fails with `code`, and the message
 * names the file that is wrong (`file`: "f.json" or "f.raw"). */
static void expect_read_error(const char *json, const void *raw_bytes, size_t raw_size, core_error_code code,
                              const char *file) {
    char *dir = temp_dir(), path[160];
    snprintf(path, sizeof path, "%s/f.json", dir);
    if (json) write_text(path, json);
    if (raw_bytes) {
        char raw_path[160];
        snprintf(raw_path, sizeof raw_path, "%s/f.raw", dir);
        FILE *f = fopen(raw_path, "wb");
        fwrite(raw_bytes, 1, raw_size, f);
        fclose(f);
    }
    terrain_field g;
    core_error error = { 0 };
    cr_expect_not(terrain_field_read(path, &g, &error), "should refuse %s", json ? json : "(no header)");
    cr_expect_null(g.values);
    cr_expect_eq(error.code, code, "%s: code %s, expected %s (%s)", json ? json : "(no header)",
                 core_error_code_name(error.code), core_error_code_name(code), error.message);
    char named[192];
    snprintf(named, sizeof named, "%s/%s", dir, file);
    cr_expect_not_null(strstr(error.message, named), "message '%s' should name %s", error.message, named);
    remove_dir(dir);
}

Test(terrain_field_file, bad_headers_are_named) {
    float zeros[8] = { 0 };
    /* No header file. */
    expect_read_error(NULL, NULL, 0, CORE_ERROR_IO, "f.json");
    /* Malformed: not JSON (a number too big for a double is a JSON error), not an object,
     * a key missing, a value of the wrong type. */
    expect_read_error("not json", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("[1,2,3]", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"spacing\":1}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0]}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,\"2\",2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,1e999,0],\"spacing\":1}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,null,0],\"spacing\":1}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":\"1\"}", zeros, 32, CORE_ERROR_FORMAT, "f.json");
    /* Numbers outside what a field may have: dims not whole in 1 … 4096, too many samples,
     * spacing not positive or too big for a float. */
    expect_read_error("{\"dims\":[2,2,0],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_RANGE, "f.json");
    expect_read_error("{\"dims\":[2,-3,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_RANGE, "f.json");
    expect_read_error("{\"dims\":[2.5,2,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_RANGE, "f.json");
    expect_read_error("{\"dims\":[5000,2,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_RANGE, "f.json");
    expect_read_error("{\"dims\":[4096,4096,4096],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, CORE_ERROR_RANGE,
                      "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":0}", zeros, 32, CORE_ERROR_RANGE, "f.json");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":1e300}", zeros, 32, CORE_ERROR_RANGE, "f.json");
}

Test(terrain_field_file, bad_raw_files_are_named) {
    const char *header = "{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":1}";
    float values[9] = { 0, 1, 2, 3, 4, 5, 6, 7, 8 };
    expect_read_error(header, NULL, 0, CORE_ERROR_IO, "f.raw");          /* missing */
    expect_read_error(header, values, 28, CORE_ERROR_CORRUPT, "f.raw");  /* short: 2 × 2 × 2 floats are 32 bytes */
    expect_read_error(header, values, 36, CORE_ERROR_CORRUPT, "f.raw");  /* long */
    values[5] = NAN;
    expect_read_error(header, values, 32, CORE_ERROR_RANGE, "f.raw");
    values[5] = 5.0f, values[7] = -INFINITY;
    expect_read_error(header, values, 32, CORE_ERROR_RANGE, "f.raw");
}

Test(terrain_field_file, header_parser_alone) {
    terrain_field_header h;
    core_error error = { 0 };
    const char *text = "{\"spacing\":2,\"origin\":[1,2,3],\"dims\":[7,8,9]}trailing";
    cr_expect_not(terrain_field_header_parse(text, strlen(text), &h, &error), "trailing bytes");
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "%s", error.message);
    error = (core_error){ 0 };
    cr_expect(terrain_field_header_parse(text, strlen(text) - 8, &h, &error), "%s", error.message);
    cr_expect_eq(error.code, CORE_ERROR_NONE, "a success leaves the error as it was");
    cr_expect_eq(h.dims[0], 7);
    cr_expect_eq(h.dims[2], 9);
    cr_expect_eq(h.origin[1], 2.0);
    cr_expect_eq(h.spacing, 2.0f);
    cr_expect_not(terrain_field_header_parse("", 0, &h, &error));
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "%s", error.message);
    cr_expect_not(terrain_field_header_parse("{}", 2, &h, NULL), "no error is fine");
}

Test(terrain_field_file, unwritable_prefix) {
    terrain_field f = small_field();
    core_error error = { 0 };
    cr_expect_not(terrain_field_write(&f, "/nonexistent-dir/field", &error));
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s", error.message);
    cr_expect_not_null(strstr(error.message, "/nonexistent-dir/field.raw"), "names the file: %s", error.message);
    terrain_field_free(&f);
    /* An empty field is the caller's mistake, not the disk's. */
    terrain_field empty = { 0 };
    cr_expect_not(terrain_field_write(&empty, "/tmp/never-written", &error));
    cr_expect_eq(error.code, CORE_ERROR_ARGUMENT, "%s", error.message);
}

Test(terrain_field_file, ply_layout) {
    terrain_vertex vertices[3] = {
        { .position = { 0, 0, 0 }, .normal = { 0, 0, 1 } },
        { .position = { 1, 0, 0 }, .normal = { 0, 0, 1 } },
        { .position = { 0, 2, 0 }, .normal = { 0, 0, 1 } },
    };
    uint32_t indices[3] = { 0, 1, 2 };
    terrain_mesh mesh = { .origin = { 10, 20, 30 }, .vertices = vertices, .indices = indices, .vertex_count = 3, .index_count = 3 };
    cr_expect_float_eq(terrain_mesh_area(&mesh), 1.0, 1e-12);
    char *dir = temp_dir(), path[160];
    core_error error = { 0 };
    snprintf(path, sizeof path, "%s/m.ply", dir);
    cr_assert(terrain_mesh_write_ply(&mesh, path, &error), "%s", error.message);
    FILE *f = fopen(path, "rb");
    char text[1024];
    size_t size = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[size] = '\0';
    char *end = strstr(text, "end_header\n");
    cr_assert_not_null(end);
    cr_expect_not_null(strstr(text, "format binary_little_endian 1.0\n"));
    cr_expect_not_null(strstr(text, "element vertex 3\n"));
    cr_expect_not_null(strstr(text, "element face 1\n"));
    cr_expect_not_null(strstr(text, "property list uchar uint vertex_indices\n"));
    size_t header = (size_t)(end - text) + strlen("end_header\n");
    cr_expect_eq(size, header + 3 * 24 + 13, "24 bytes a vertex, 13 a triangle");
    const unsigned char *body = (const unsigned char *)text + header;
    float y2;
    memcpy(&y2, body + 2 * 24 + 4, 4);
    cr_expect_eq(y2, 2.0f);
    cr_expect_eq(body[3 * 24], 3, "triangle count byte");
    cr_expect_eq(body[3 * 24 + 1 + 8], 2, "third index");
    remove_dir(dir);
}
