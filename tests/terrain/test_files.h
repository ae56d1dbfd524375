/* test_files.h — files and folders for the terrain tests that save (the edit log, the world
 * database): temporary folders, reading and writing whole files, removing what a test made. */
#ifndef TEST_FILES_H
#define TEST_FILES_H

#include "../engine/test.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static inline void make_temp_dir(char *path, size_t size) {
    snprintf(path, size, "/tmp/terrain_test_XXXXXX");
    cr_assert_not_null(mkdtemp(path));
}

/* rm -r of what the tests make. */
static inline void remove_tree(const char *path) {
    DIR *dir = opendir(path);
    if (!dir) {
        unlink(path);
        return;
    }
    for (struct dirent *e; (e = readdir(dir));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        size_t size = strlen(path) + strlen(e->d_name) + 2;
        char *child = malloc(size);
        snprintf(child, size, "%s/%s", path, e->d_name);
        remove_tree(child);
        free(child);
    }
    closedir(dir);
    rmdir(path);
}

/* Bytes of the plain files directly in `path` (a world folder: world.db and its journal). */
static inline long long folder_bytes(const char *path) {
    DIR *dir = opendir(path);
    cr_assert_not_null(dir, "%s", path);
    long long total = 0;
    for (struct dirent *e; (e = readdir(dir));) {
        char child[4096];
        struct stat info;
        snprintf(child, sizeof child, "%s/%s", path, e->d_name);
        if (stat(child, &info) == 0 && S_ISREG(info.st_mode)) total += info.st_size;
    }
    closedir(dir);
    return total;
}

static inline bool exists(const char *path) {
    struct stat info;
    return stat(path, &info) == 0;
}

/* The whole file (malloc'd, one byte more than *size); the test fails when it cannot be read. */
static inline uint8_t *read_all(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "%s", path);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *bytes = malloc(*size + 1);
    cr_assert_eq(fread(bytes, 1, *size, f), *size);
    fclose(f);
    return bytes;
}

static inline void write_all(const char *path, const void *bytes, size_t size) {
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "%s", path);
    cr_assert_eq(fwrite(bytes, 1, size, f), size);
    fclose(f);
}

#endif
