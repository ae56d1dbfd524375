/* trace_file.h — reading a captured trace back in a test: the file's JSON (asserted valid) and its
 * traceEvents array, the file then removed. Shared by the trace, job and terrain-thread tests;
 * static, so each test program that includes it gets its own copy. Needs test.h first. */
#ifndef TESTS_TRACE_FILE_H
#define TESTS_TRACE_FILE_H

#include "core/core.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* The whole file, NUL-terminated (free it); the test fails when it cannot be read. */
static char *trace_file_read(const char *path, size_t *size) {
    FILE *file = fopen(path, "rb");
    cr_assert_not_null(file, "cannot open %s", path);
    fseek(file, 0, SEEK_END);
    long length = ftell(file);
    fseek(file, 0, SEEK_SET);
    char *data = malloc((size_t)length + 1);
    *size = fread(data, 1, (size_t)length, file);
    data[*size] = '\0';
    fclose(file);
    return data;
}

/* Parses the trace at `path` into `arena` (release it with core_arena_release), deletes the
 * file, and returns its traceEvents array; *root (may be NULL) gets the whole document. */
static const core_json_value *trace_file_load(const char *path, core_arena *arena, core_json_value **root) {
    size_t size;
    char *text = trace_file_read(path, &size);
    unlink(path);
    core_json_value *document;
    core_error error = { 0 };
    bool ok = core_json_parse(text, size, arena, &document, &error);
    free(text);
    cr_assert(ok, "%s is not valid JSON: %s", path, error.message);
    const core_json_value *events = core_json_get(document, "traceEvents");
    cr_assert_not_null(events, "%s has no traceEvents", path);
    cr_assert_eq(events->type, CORE_JSON_ARRAY);
    if (root) *root = document;
    return events;
}

#endif
