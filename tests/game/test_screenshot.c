/* F12's picture names (game/screenshot.h): dated as worked out by hand from a fixed time, a new
 * name whenever one exists, and an existing file never touched. Each test works in a fresh folder
 * under /tmp. */
#include "../engine/test.h"
#include "game/screenshot.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* 2026-11-26 21:04:05 */
static const struct tm when = { .tm_year = 126, .tm_mon = 10, .tm_mday = 26, .tm_hour = 21, .tm_min = 4, .tm_sec = 5 };

static void make_dir(char *dir) {
    strcpy(dir, "/tmp/test_screenshot_XXXXXX");
    cr_assert_not_null(mkdtemp(dir));
}

static long file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

Test(game_screenshot, names_are_dated_and_made_in_a_new_folder) {
    char dir[64], folder[96], path[256], want[256];
    make_dir(dir);
    snprintf(folder, sizeof folder, "%s/screenshots", dir);   /* does not exist yet */
    cr_assert(game_screenshot_reserve(folder, "world", &when, path, sizeof path));
    snprintf(want, sizeof want, "%s/world-2026-11-26-21-04-05.png", folder);
    cr_expect_str_eq(path, want);
    cr_expect_eq(file_size(path), 0); /* claimed, empty until the picture is written */
    unlink(path);
    rmdir(folder);
    rmdir(dir);
}

Test(game_screenshot, a_screenshot_never_replaces_an_existing_file) {
    char dir[64], path[256], want[256], first[256];
    make_dir(dir);
    /* A picture already there under the first name: it must survive, byte for byte. */
    snprintf(first, sizeof first, "%s/world-2026-11-26-21-04-05.png", dir);
    FILE *f = fopen(first, "wb");
    cr_assert_not_null(f);
    fputs("an earlier picture", f);
    fclose(f);

    cr_assert(game_screenshot_reserve(dir, "world", &when, path, sizeof path));
    snprintf(want, sizeof want, "%s/world-2026-11-26-21-04-05-2.png", dir);
    cr_expect_str_eq(path, want);
    /* A third in the same second: -3, since -2 is now taken. */
    char third[256];
    cr_assert(game_screenshot_reserve(dir, "world", &when, third, sizeof third));
    snprintf(want, sizeof want, "%s/world-2026-11-26-21-04-05-3.png", dir);
    cr_expect_str_eq(third, want);
    cr_expect_eq(file_size(first), (long)strlen("an earlier picture"));
    unlink(first);
    unlink(path);
    unlink(third);
    rmdir(dir);
}

Test(game_screenshot, a_folder_that_is_a_file_is_an_error) {
    char dir[64], file[96], path[256];
    make_dir(dir);
    snprintf(file, sizeof file, "%s/screenshots", dir);
    FILE *f = fopen(file, "wb");
    cr_assert_not_null(f);
    fclose(f);
    cr_expect(!game_screenshot_reserve(file, "world", &when, path, sizeof path));
    cr_expect_eq(file_size(file), 0);
    unlink(file);
    rmdir(dir);
}
