/* Tests of the bindings file (engine/input/input_bindings.c): the shipped file equals the
 * built-in defaults, every kind of bad line is reported with its file name and line number and
 * skipped while the good lines apply, and a binding replaces the defaults of its action. */
#include "input/input.h"
#include "input/input_internal.h"
#include "test.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- helpers -------------------------------------------------------------------------------- */

/* Parses `size` bytes of `text` with stderr sent to a file, whose text lands in `log`. */
static input_bindings *parse_logged(const char *text, size_t size, int *bad, char *log, size_t log_size) {
    fflush(stderr);
    FILE *sink = tmpfile();
    cr_assert_not_null(sink);
    int saved = dup(2);
    dup2(fileno(sink), 2);
    input_bindings *b = input_bindings_parse(text, size, "test.txt", bad);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(sink);
    size_t n = fread(log, 1, log_size - 1, sink);
    log[n] = '\0';
    fclose(sink);
    return b;
}

#define PARSE_LOGGED(literal, bad, log) parse_logged(literal, sizeof(literal) - 1, bad, log, sizeof(log))

static bool has_source(const input_bindings *b, int target, input_source_kind kind, int code) {
    for (int i = 0; i < b->source_count[target]; i++)
        if (b->sources[target][i].kind == kind && b->sources[target][i].code == code) return true;
    return false;
}

static int lines_in(const char *log) {
    int n = 0;
    for (; *log; log++) n += *log == '\n';
    return n;
}

/* ---- the shipped file ----------------------------------------------------------------------- */

Test(input_bindings, shipped_file_equals_the_defaults) {
    int bad = -1;
    input_bindings *file = input_bindings_load("data/input/bindings.txt", &bad, NULL);
    cr_assert_not_null(file, "run the tests from the repository root");
    cr_expect_eq(bad, 0);
    input_bindings *defaults = input_bindings_default();
    cr_expect(input__bindings_equal(file, defaults));
    cr_expect(input__bindings_valid(defaults));
    input_bindings_destroy(file);
    input_bindings_destroy(defaults);
}

Test(input_bindings, defaults_as_the_brief_lists_them) {
    input_bindings *b = input_bindings_default();
    cr_expect(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_KEY, GLFW_KEY_SPACE));
    cr_expect(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_SOUTH));
    cr_expect(has_source(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_KEY, GLFW_KEY_LEFT_SHIFT));
    cr_expect(has_source(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_LEFT_CONTROL));
    cr_expect(has_source(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_C));
    cr_expect(has_source(b, INPUT_ACTION_TOOL, INPUT_SOURCE_MOUSE_BUTTON, GLFW_MOUSE_BUTTON_1));
    cr_expect(has_source(b, INPUT_ACTION_TOOL, INPUT_SOURCE_PAD_AXIS, INPUT_PAD_RT));
    cr_expect(has_source(b, INPUT_ACTION_TOOL_ALT, INPUT_SOURCE_MOUSE_BUTTON, GLFW_MOUSE_BUTTON_2));
    cr_expect(has_source(b, INPUT_ACTION_TOGGLE_FLY, INPUT_SOURCE_KEY, GLFW_KEY_F));
    cr_expect(has_source(b, INPUT_ACTION_SCREENSHOT, INPUT_SOURCE_KEY, GLFW_KEY_F12));
    cr_expect(has_source(b, INPUT_ACTION_FULLSCREEN, INPUT_SOURCE_KEY, GLFW_KEY_F11));
    cr_expect(has_source(b, INPUT_ACTION_QUIT, INPUT_SOURCE_KEY, GLFW_KEY_ESCAPE));
    cr_expect(has_source(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_UP), INPUT_SOURCE_KEY, GLFW_KEY_W));
    cr_expect(has_source(b, INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_LEFT), INPUT_SOURCE_KEY, GLFW_KEY_LEFT));
    cr_expect(has_source(b, INPUT_TARGET_AXIS(INPUT_AXIS_LOOK_RIGHT), INPUT_SOURCE_MOUSE_AXIS, INPUT_MOUSE_RIGHT));
    cr_expect_eq(b->look_speed, 0.0025f);
    cr_expect_eq(b->stick_look_speed, 3.0f);
    cr_expect_eq(b->dead_zone, 0.15f);
    cr_expect_not(b->invert_y);
    input_bindings_destroy(b);
}

/* ---- good lines ----------------------------------------------------------------------------- */

Test(input_bindings, a_line_replaces_the_defaults_of_its_action) {
    char log[4096];
    int bad = -1;
    input_bindings *b = PARSE_LOGGED("jump = key:j, pad:west\n", &bad, log);
    cr_expect_eq(bad, 0);
    cr_expect_str_eq(log, "");
    cr_expect_eq(b->source_count[INPUT_ACTION_JUMP], 2);
    cr_expect(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_KEY, GLFW_KEY_J));
    cr_expect(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_WEST));
    cr_expect_not(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_KEY, GLFW_KEY_SPACE));
    cr_expect(has_source(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_KEY, GLFW_KEY_LEFT_SHIFT), "other actions keep theirs");

    /* Through the input system: space no longer jumps, j does. */
    input_system *in = input_system_create(&(input_system_desc){ .no_gamepads = true, .bindings = b }, NULL);
    input_bindings_destroy(b);
    input_feed_key(in, GLFW_KEY_SPACE, true);
    cr_assert(input_update(in, 0.016f));
    cr_expect_eq(input_actions_get(in)->down, 0u);
    input_feed_key(in, GLFW_KEY_J, true);
    cr_assert(input_update(in, 0.016f));
    cr_expect_eq(input_actions_get(in)->pressed, INPUT_ACTION_BIT(INPUT_ACTION_JUMP));
    input_system_destroy(in);
}

Test(input_bindings, whitespace_comments_case_and_line_endings) {
    char log[4096];
    int bad = -1;
    input_bindings *b = PARSE_LOGGED("# a comment\r\n"
                                     "\r\n"
                                     "   \t  \n"
                                     "  Sprint\t=\tKEY : Right_Shift ,pad:RB   # trailing comment\r\n"
                                     "look_speed=0.004\n"
                                     "stick_look_speed = 1.5e0\n"
                                     "dead_zone = 0.2\n"
                                     "invert_y = TRUE\n"
                                     "crouch = key:kp_0, key:f25, key:9, mouse:button8\n"
                                     "fullscreen = key:left_control",   /* last line without newline */
                                     &bad, log);
    cr_expect_eq(bad, 0, "%s", log);
    cr_expect_eq(b->source_count[INPUT_ACTION_SPRINT], 2);
    cr_expect(has_source(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_KEY, GLFW_KEY_RIGHT_SHIFT));
    cr_expect(has_source(b, INPUT_ACTION_SPRINT, INPUT_SOURCE_PAD_BUTTON, INPUT_BUTTON_RB));
    cr_expect_eq(b->look_speed, 0.004f);
    cr_expect_eq(b->stick_look_speed, 1.5f);
    cr_expect_eq(b->dead_zone, 0.2f);
    cr_expect(b->invert_y);
    cr_expect(has_source(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_KP_0));
    cr_expect(has_source(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_F25));
    cr_expect(has_source(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_KEY, GLFW_KEY_9));
    cr_expect(has_source(b, INPUT_ACTION_CROUCH, INPUT_SOURCE_MOUSE_BUTTON, GLFW_MOUSE_BUTTON_8));
    cr_expect(has_source(b, INPUT_ACTION_FULLSCREEN, INPUT_SOURCE_KEY, GLFW_KEY_LEFT_CONTROL));
    input_bindings_destroy(b);
}

Test(input_bindings, empty_list_unbinds_and_duplicates_collapse) {
    char log[4096];
    int bad = -1;
    input_bindings *b = PARSE_LOGGED("screenshot =\ntool = pad:rt, pad:rt, mouse:button1\n", &bad, log);
    cr_expect_eq(bad, 0);
    cr_expect_eq(b->source_count[INPUT_ACTION_SCREENSHOT], 0);
    cr_expect_eq(b->source_count[INPUT_ACTION_TOOL], 2);
    input_bindings_destroy(b);
}

Test(input_bindings, a_later_line_wins) {
    int bad = -1;
    const char text[] = "jump = key:j\njump = key:k\n";
    input_bindings *b = input_bindings_parse(text, sizeof text - 1, "t", &bad);
    cr_expect_eq(bad, 0);
    cr_expect_eq(b->source_count[INPUT_ACTION_JUMP], 1);
    cr_expect(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_KEY, GLFW_KEY_K));
    input_bindings_destroy(b);
}

Test(input_bindings, empty_text_is_the_defaults) {
    int bad = -1;
    input_bindings *b = input_bindings_parse("", 0, "empty", &bad);
    input_bindings *d = input_bindings_default();
    cr_expect_eq(bad, 0);
    cr_expect(input__bindings_equal(b, d));
    input_bindings_destroy(b);
    input_bindings_destroy(d);
}

/* ---- bad lines ------------------------------------------------------------------------------ */

/* Each bad line names the file and its line; good lines around them still apply. */
Test(input_bindings, each_error_kind_with_its_line_number) {
    char text[4096];
    size_t n = 0;
#define ADD(s) (memcpy(text + n, s, sizeof(s) - 1), n += sizeof(s) - 1)
    ADD("jump = key:j\n");                              /* 1 good */
    ADD("jumpp = key:k\n");                             /* 2 unknown action */
    ADD("crouch = key:nosuchkey\n");                    /* 3 unknown key */
    ADD("crouch = joystick:1\n");                       /* 4 unknown kind */
    ADD("sprint key:left_shift\n");                     /* 5 missing '=' */
    ADD("look_speed = fast\n");                         /* 6 garbage number */
    ADD("look_speed = 0.5x\n");                         /* 7 trailing junk */
    ADD("dead_zone = 2\n");                             /* 8 out of range */
    ADD("jump = mouse:left\n");                         /* 9 mouse motion on a button action */
    ADD("move_up = mouse:up\n");                        /* 10 … and on move */
    ADD("tool = pad:rt,, pad:lt\n");                    /* 11 empty source */
    ADD("tool = key\n");                                /* 12 no kind */
    ADD("toggle_fly = key:g\n");                        /* 13 good */
    ADD("quit = key:q\0key:w\n");                       /* 14 NUL byte */
    text[n++] = 'x';                                    /* 15 overlong */
    memset(text + n, 'a', INPUT_BINDINGS_MAX_LINE + 10);
    n += INPUT_BINDINGS_MAX_LINE + 10;
    text[n++] = '\n';
    ADD("invert_y = maybe\n");                          /* 16 not a bool */
    ADD("= key:a\n");                                   /* 17 no action */
    ADD("jump = pad:nosuchbutton\n");                   /* 18 unknown pad source */
    ADD("crouch = key:a,key:b,key:c,key:d,key:e,key:f,key:g,key:h,key:i\n"); /* 19 too many */
    ADD("look_speed = nan\n");                          /* 20 not finite */
    ADD("stick_look_speed = 2.5\n");                    /* 21 good */
    ADD("mouse:button1 = tool\n");                      /* 22 backwards */
    ADD("jump = mouse:button9\n");                      /* 23 no such button */
#undef ADD
    char log[16384];
    int bad = -1;
    input_bindings *b = parse_logged(text, n, &bad, log, sizeof log);
    const int bad_lines[] = { 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 15, 16, 17, 18, 19, 20, 22, 23 };
    const int bad_count = (int)(sizeof bad_lines / sizeof bad_lines[0]);
    cr_expect_eq(bad, bad_count);
    cr_expect_eq(lines_in(log), bad_count, "one line per bad line:\n%s", log);
    for (int i = 0; i < bad_count; i++) {
        char where[32];
        snprintf(where, sizeof where, "test.txt:%d: ", bad_lines[i]);
        cr_expect_not_null(strstr(log, where), "%s missing from:\n%s", where, log);
    }
    /* What each line was reported for. */
    cr_expect_not_null(strstr(log, "test.txt:2: unknown action 'jumpp'"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:3: unknown source 'key:nosuchkey'"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:5: missing '='"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:6: look_speed: 'fast' is not a number"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:8: dead_zone must be between"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:14: line contains a NUL byte"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:15: line longer than"), "%s", log);
    cr_expect_not_null(strstr(log, "test.txt:19: more than 8 sources"), "%s", log);

    /* The good lines applied … */
    cr_expect_eq(b->source_count[INPUT_ACTION_JUMP], 1);
    cr_expect(has_source(b, INPUT_ACTION_JUMP, INPUT_SOURCE_KEY, GLFW_KEY_J));
    cr_expect_eq(b->source_count[INPUT_ACTION_TOGGLE_FLY], 1);
    cr_expect(has_source(b, INPUT_ACTION_TOGGLE_FLY, INPUT_SOURCE_KEY, GLFW_KEY_G));
    cr_expect_eq(b->stick_look_speed, 2.5f);
    /* … and the bad ones changed nothing: those actions and settings keep their defaults. */
    input_bindings *d = input_bindings_default();
    const int untouched[] = { INPUT_ACTION_CROUCH, INPUT_ACTION_SPRINT, INPUT_ACTION_TOOL, INPUT_ACTION_QUIT,
                              INPUT_TARGET_AXIS(INPUT_AXIS_MOVE_UP) };
    for (size_t i = 0; i < sizeof untouched / sizeof untouched[0]; i++) {
        int t = untouched[i];
        cr_expect_eq(b->source_count[t], d->source_count[t], "%s", input__target_name(t));
        cr_expect_eq(memcmp(b->sources[t], d->sources[t], d->source_count[t] * sizeof d->sources[t][0]), 0);
    }
    cr_expect_eq(b->look_speed, d->look_speed);
    cr_expect_eq(b->dead_zone, d->dead_zone);
    cr_expect_eq(b->invert_y, d->invert_y);
    cr_expect(input__bindings_valid(b));
    input_bindings_destroy(d);
    input_bindings_destroy(b);
}

Test(input_bindings, garbage_bytes_are_bad_lines_not_crashes) {
    unsigned char bytes[2048];
    uint64_t x = 0x9e3779b97f4a7c15ull;
    for (size_t i = 0; i < sizeof bytes; i++) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        bytes[i] = (unsigned char)x;
    }
    char log[65536];
    int bad = -1;
    /* Not NUL-terminated: the parser must stay inside the size it is given (ASan watches). */
    char *copy = malloc(sizeof bytes);
    memcpy(copy, bytes, sizeof bytes);
    input_bindings *b = parse_logged(copy, sizeof bytes, &bad, log, sizeof log);
    cr_expect_geq(bad, 1);
    cr_expect(input__bindings_valid(b));
    input_bindings_destroy(b);
    free(copy);
}

Test(input_bindings, line_numbers_count_every_line) {
    char log[4096];
    int bad = -1;
    input_bindings *b = PARSE_LOGGED("\n\n# c\n\n\nwhat\n", &bad, log);
    cr_expect_eq(bad, 1);
    cr_expect_not_null(strstr(log, "test.txt:6: "), "%s", log);
    input_bindings_destroy(b);
}

Test(input_bindings, load_reports_missing_files) {
    int bad = -1;
    core_error error = { 0 };
    cr_expect_null(input_bindings_load("/nonexistent/bindings.txt", &bad, &error));
    cr_expect_eq(bad, 0);
    cr_expect_eq(error.code, CORE_ERROR_IO, "%s", error.message);
    cr_expect_not_null(strstr(error.message, "/nonexistent/bindings.txt"), "names the file: %s", error.message);
    cr_expect_null(input_bindings_load("/nonexistent/bindings.txt", NULL, NULL), "a NULL error is allowed");
}

Test(input_bindings, load_refuses_a_file_over_a_mebibyte) {
    char path[] = "/tmp/test_input_bindings_XXXXXX";
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    static char comment[(1 << 20) + 1];  /* one byte past the 1 MiB limit, all one comment line */
    memset(comment, ' ', sizeof comment);
    comment[0] = '#';
    cr_assert_eq(write(fd, comment, sizeof comment), (ssize_t)sizeof comment);
    close(fd);
    core_error error = { 0 };
    cr_expect_null(input_bindings_load(path, NULL, &error));
    cr_expect_eq(error.code, CORE_ERROR_RANGE, "%s", error.message);
    unlink(path);
}

Test(input_bindings, load_names_the_file_in_messages) {
    char path[] = "/tmp/test_input_bindings_XXXXXX";
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    const char text[] = "jump = key:space\nbogus\n";
    cr_assert_eq(write(fd, text, sizeof text - 1), (ssize_t)(sizeof text - 1));
    close(fd);
    fflush(stderr);
    FILE *sink = tmpfile();
    int saved = dup(2);
    dup2(fileno(sink), 2);
    int bad = -1;
    core_error error = { 0 };
    input_bindings *b = input_bindings_load(path, &bad, &error);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    char log[1024];
    rewind(sink);
    log[fread(log, 1, sizeof log - 1, sink)] = '\0';
    fclose(sink);
    unlink(path);
    cr_assert_not_null(b);
    cr_expect_eq(bad, 1);
    char where[64];
    snprintf(where, sizeof where, "%s:2: ", path);
    cr_expect_not_null(strstr(log, where), "%s", log);
    input_bindings_destroy(b);
}
