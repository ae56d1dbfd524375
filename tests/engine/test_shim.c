/* test_shim.c — the in-process test runner used where Criterion cannot run (ThreadSanitizer;
 * see test.h). Runs every registered test in this process, one after another, and ends with
 * the line "N passed, N failed". Usage: test_threads [--filter SUITE] */
#include "test.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

static test_case *first_test, **last_test = &first_test;
static bool current_failed;
static jmp_buf abort_current;

void test__register(test_case *test) {
    *last_test = test; /* in registration order, which is file order */
    last_test = &test->next;
}

void test__check(bool ok, bool fatal, const char *file, int line, const char *expression, const char *fmt, ...) {
    if (ok) return;
    current_failed = true;
    fprintf(stderr, "%s:%d: failed: %s", file, line, expression);
    if (fmt && *fmt == ' ') fmt++;
    if (fmt && *fmt) {
        va_list args;
        va_start(args, fmt);
        fprintf(stderr, ": ");
        vfprintf(stderr, fmt, args);
        va_end(args);
    }
    fprintf(stderr, "\n");
    if (fatal) longjmp(abort_current, 1);
}

/* setjmp lives in a function of its own so no local of the caller can be clobbered. */
static bool run_one(const test_case *test) {
    current_failed = false;
    if (setjmp(abort_current) == 0) test->fn();
    return !current_failed;
}

int main(int argc, char **argv) {
    const char *filter = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--filter") == 0 && i + 1 < argc) filter = argv[++i];
        else {
            fprintf(stderr, "usage: %s [--filter SUITE]\n", argv[0]);
            return 2;
        }
    }
    int passed = 0, failed = 0;
    for (test_case *test = first_test; test; test = test->next) {
        if (filter && strcmp(filter, test->suite) != 0) continue;
        bool ok = run_one(test);
        passed += ok;
        failed += !ok;
        printf("[%s] %s::%s\n", ok ? " ok " : "FAIL", test->suite, test->name);
        fflush(stdout);
    }
    printf("%s: %d passed, %d failed\n", argv[0], passed, failed);
    return failed ? 1 : 0;
}
