/* screenshot.c — dated, never-overwriting picture names (screenshot.h). */
#include "game/screenshot.h"

#include "core/core.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { GAME_SCREENSHOT_MAX_SUFFIX = 999 };

static bool game_screenshot_folder(const char *folder) {
    if (mkdir(folder, 0755) == 0 || errno == EEXIST) {
        struct stat st;
        if (stat(folder, &st) == 0 && S_ISDIR(st.st_mode)) return true;
        core_log_error("game", "cannot keep screenshots in %s: it is not a folder", folder);
        return false;
    }
    core_log_error("game", "cannot make the screenshots folder %s: %s", folder, strerror(errno));
    return false;
}

bool game_screenshot_reserve(const char *folder, const char *prefix, const struct tm *when, char *path,
                             size_t path_size) {
    if (!game_screenshot_folder(folder)) return false;
    char stamp[32];
    strftime(stamp, sizeof stamp, "%Y-%m-%d-%H-%M-%S", when);
    for (int n = 1; n <= GAME_SCREENSHOT_MAX_SUFFIX; n++) {
        char suffix[8] = "";
        if (n > 1) snprintf(suffix, sizeof suffix, "-%d", n);
        if (snprintf(path, path_size, "%s/%s-%s%s.png", folder, prefix, stamp, suffix) >= (int)path_size) {
            core_log_error("game", "the screenshot path in %s is too long", folder);
            return false;
        }
        int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        if (fd >= 0) {
            close(fd);
            return true;
        }
        if (errno != EEXIST) {
            core_log_error("game", "cannot create the screenshot %s: %s", path, strerror(errno));
            return false;
        }
    }
    core_log_error("game", "no free screenshot name in %s for %s-%s (up to -%d)", folder, prefix, stamp,
               GAME_SCREENSHOT_MAX_SUFFIX);
    return false;
}
