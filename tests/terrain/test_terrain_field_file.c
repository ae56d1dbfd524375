/* Field files (PREFIX.raw + PREFIX.json) and PLY meshes: round trips, and every kind of bad
 * file refused with a message that names the problem. */
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
    char error[256];
    cr_assert(terrain_field_write(&f, prefix, error, sizeof error), "%s", error);
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
        cr_assert(terrain_field_read(path, &g, error, sizeof error), "%s", error);
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

/* Reading `json` (and a raw of `raw_bytes` bytes, NULL = none) fails with a message containing
 * `expect`. */
static void expect_read_error(const char *json, const void *raw_bytes, size_t raw_size, const char *expect) {
    char *dir = temp_dir(), path[160], error[320];
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
    error[0] = '\0';
    cr_expect_not(terrain_field_read(path, &g, error, sizeof error), "should refuse (%s)", expect);
    cr_expect_null(g.values);
    cr_expect_not_null(strstr(error, expect), "message '%s' should mention '%s'", error, expect);
    remove_dir(dir);
}

Test(terrain_field_file, bad_headers_are_named) {
    float zeros[8] = { 0 };
    expect_read_error(NULL, NULL, 0, "cannot open");
    expect_read_error("not json", zeros, 32, "not JSON");
    expect_read_error("[1,2,3]", zeros, 32, "must be a JSON object");
    expect_read_error("{\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "missing key \"dims\"");
    expect_read_error("{\"dims\":[2,2,2],\"spacing\":1}", zeros, 32, "missing key \"origin\"");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0]}", zeros, 32, "missing key \"spacing\"");
    expect_read_error("{\"dims\":[2,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "\"dims\" must be an array of 3");
    expect_read_error("{\"dims\":[2,\"2\",2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "\"dims\"[1] must be a number");
    expect_read_error("{\"dims\":[2,2,0],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "\"dims\"[2] = 0");
    expect_read_error("{\"dims\":[2,-3,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "\"dims\"[1] = -3");
    expect_read_error("{\"dims\":[2.5,2,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "not a whole number");
    expect_read_error("{\"dims\":[5000,2,2],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "\"dims\"[0] = 5000");
    expect_read_error("{\"dims\":[4096,4096,4096],\"origin\":[0,0,0],\"spacing\":1}", zeros, 32, "over the limit");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,1e999,0],\"spacing\":1}", zeros, 32, "column 29: number out of range");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,null,0],\"spacing\":1}", zeros, 32, "\"origin\"[1] must be a number");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":0}", zeros, 32, "\"spacing\" = 0");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":\"1\"}", zeros, 32, "\"spacing\" must be a number");
    expect_read_error("{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":1e300}", zeros, 32, "\"spacing\"");
}

Test(terrain_field_file, bad_raw_files_are_named) {
    const char *header = "{\"dims\":[2,2,2],\"origin\":[0,0,0],\"spacing\":1}";
    float values[9] = { 0, 1, 2, 3, 4, 5, 6, 7, 8 };
    expect_read_error(header, NULL, 0, "f.raw");                          /* missing */
    expect_read_error(header, values, 28, "holds 28 bytes");              /* short */
    expect_read_error(header, values, 36, "need 32");                     /* long */
    values[5] = NAN;
    expect_read_error(header, values, 32, "value 5 (x 1, y 0, z 1) is NaN");
    values[5] = 5.0f, values[7] = -INFINITY;
    expect_read_error(header, values, 32, "is infinite");
}

Test(terrain_field_file, header_parser_alone) {
    terrain_field_header h;
    char error[256];
    const char *text = "{\"spacing\":2,\"origin\":[1,2,3],\"dims\":[7,8,9]}trailing";
    cr_expect_not(terrain_field_header_parse(text, strlen(text), &h, error, sizeof error), "trailing bytes");
    cr_expect(terrain_field_header_parse(text, strlen(text) - 8, &h, error, sizeof error), "%s", error);
    cr_expect_eq(h.dims[0], 7);
    cr_expect_eq(h.dims[2], 9);
    cr_expect_eq(h.origin[1], 2.0);
    cr_expect_eq(h.spacing, 2.0f);
    cr_expect_not(terrain_field_header_parse("", 0, &h, error, sizeof error));
    cr_expect_not(terrain_field_header_parse("{}", 2, &h, NULL, 0), "no error buffer is fine");
}

Test(terrain_field_file, unwritable_prefix) {
    terrain_field f = small_field();
    char error[256];
    cr_expect_not(terrain_field_write(&f, "/nonexistent-dir/field", error, sizeof error));
    cr_expect_not_null(strstr(error, "/nonexistent-dir/field.raw"), "%s", error);
    terrain_field_free(&f);
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
    char *dir = temp_dir(), path[160], error[256];
    snprintf(path, sizeof path, "%s/m.ply", dir);
    cr_assert(terrain_mesh_write_ply(&mesh, path, error, sizeof error), "%s", error);
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
