/* screenshot.h — where F12's pictures go: a new dated file in a folder, never over another.
 *
 *     char path[256];
 *     struct tm now;  time_t t = time(NULL);  localtime_r(&t, &now);
 *     if (game_screenshot_reserve("screenshots", "world", &now, path, sizeof path))
 *         gfx_screenshot(gfx, path);    // path: screenshots/world-2026-11-26-21-04-05.png
 *
 * The folder is made when missing. The name is PREFIX-YYYY-MM-DD-HH-MM-SS.png, or with -2, -3, …
 * before ".png" when that one exists (two pictures in one second). The file is created empty with
 * O_EXCL, which fails on any existing file, so the name is claimed even against another program
 * choosing at the same moment; the caller then writes the picture over its own empty file.
 */
#ifndef GAME_SCREENSHOT_H
#define GAME_SCREENSHOT_H

#include <stdbool.h>
#include <stddef.h>
#include <time.h>

/* False, with a message naming the folder or file, when the folder cannot be made or no name is
 * free (after -999). */
bool game_screenshot_reserve(const char *folder, const char *prefix, const struct tm *when, char *path,
                             size_t path_size);

#endif
