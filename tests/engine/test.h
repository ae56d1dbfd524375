/* test.h — what every test file includes instead of <criterion/criterion.h>.
 *
 * Normally this is Criterion. Criterion's runner cannot start under ThreadSanitizer (its shared
 * memory arena collides with TSan's address layout: Snaipe/Criterion#274, open since 2018), so
 * the `test_threads` program, built under TSan by tools/test, defines TEST_WITHOUT_CRITERION and
 * gets a small in-process runner with the same Test() and cr_* macros instead. Tests written
 * with the macros below run under both; test_shim.c is that runner.
 */
#ifndef TEST_H
#define TEST_H

#ifndef TEST_WITHOUT_CRITERION
#include <criterion/criterion.h>
#else

#include <setjmp.h>
#include <stdbool.h>
#include <string.h>

typedef struct test_case {
    const char *suite, *name;
    void (*fn)(void);
    struct test_case *next;
} test_case;

void test__register(test_case *test);
void test__check(bool ok, bool fatal, const char *file, int line, const char *expression, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));

#define Test(suite, name, ...)                                                                 \
    static void test_fn_##suite##_##name(void);                                                \
    static test_case test_case_##suite##_##name = { #suite, #name, test_fn_##suite##_##name, 0 }; \
    __attribute__((constructor)) static void test_register_##suite##_##name(void) {            \
        test__register(&test_case_##suite##_##name);                                           \
    }                                                                                          \
    static void test_fn_##suite##_##name(void)

/* `" " __VA_ARGS__` glues an optional message format onto a one-space literal (an empty one
 * would trip -Wformat-zero-length); test__check skips that space. */
#define TEST__CHECK(ok, fatal, expr, ...) test__check((ok), (fatal), __FILE__, __LINE__, expr, " " __VA_ARGS__)
#define cr_assert(c, ...) TEST__CHECK((c), true, #c, __VA_ARGS__)
#define cr_expect(c, ...) TEST__CHECK((c), false, #c, __VA_ARGS__)
#define cr_assert_not(c, ...) TEST__CHECK(!(c), true, "!(" #c ")", __VA_ARGS__)
#define cr_expect_not(c, ...) TEST__CHECK(!(c), false, "!(" #c ")", __VA_ARGS__)
#define TEST__CMP(a, op, b, fatal, ...) TEST__CHECK((a) op (b), fatal, #a " " #op " " #b, __VA_ARGS__)
#define cr_assert_eq(a, b, ...) TEST__CMP(a, ==, b, true, __VA_ARGS__)
#define cr_expect_eq(a, b, ...) TEST__CMP(a, ==, b, false, __VA_ARGS__)
#define cr_assert_neq(a, b, ...) TEST__CMP(a, !=, b, true, __VA_ARGS__)
#define cr_expect_neq(a, b, ...) TEST__CMP(a, !=, b, false, __VA_ARGS__)
#define cr_assert_lt(a, b, ...) TEST__CMP(a, <, b, true, __VA_ARGS__)
#define cr_expect_lt(a, b, ...) TEST__CMP(a, <, b, false, __VA_ARGS__)
#define cr_assert_leq(a, b, ...) TEST__CMP(a, <=, b, true, __VA_ARGS__)
#define cr_expect_leq(a, b, ...) TEST__CMP(a, <=, b, false, __VA_ARGS__)
#define cr_assert_gt(a, b, ...) TEST__CMP(a, >, b, true, __VA_ARGS__)
#define cr_expect_gt(a, b, ...) TEST__CMP(a, >, b, false, __VA_ARGS__)
#define cr_assert_geq(a, b, ...) TEST__CMP(a, >=, b, true, __VA_ARGS__)
#define cr_expect_geq(a, b, ...) TEST__CMP(a, >=, b, false, __VA_ARGS__)
#define cr_assert_null(p, ...) TEST__CHECK((p) == NULL, true, #p " == NULL", __VA_ARGS__)
#define cr_expect_null(p, ...) TEST__CHECK((p) == NULL, false, #p " == NULL", __VA_ARGS__)
#define cr_assert_not_null(p, ...) TEST__CHECK((p) != NULL, true, #p " != NULL", __VA_ARGS__)
#define cr_expect_not_null(p, ...) TEST__CHECK((p) != NULL, false, #p " != NULL", __VA_ARGS__)
#define cr_assert_str_eq(a, b, ...) TEST__CHECK(strcmp((a), (b)) == 0, true, #a " == " #b, __VA_ARGS__)
#define cr_expect_str_eq(a, b, ...) TEST__CHECK(strcmp((a), (b)) == 0, false, #a " == " #b, __VA_ARGS__)
#define TEST__NEAR(a, b, eps) ((a) - (b) <= (eps) && (b) - (a) <= (eps))
#define cr_assert_float_eq(a, b, eps, ...) TEST__CHECK(TEST__NEAR(a, b, eps), true, #a " ≈ " #b, __VA_ARGS__)
#define cr_expect_float_eq(a, b, eps, ...) TEST__CHECK(TEST__NEAR(a, b, eps), false, #a " ≈ " #b, __VA_ARGS__)
#define cr_log_info(...) ((void)0)
#define cr_skip_test(...) return

#endif /* TEST_WITHOUT_CRITERION */
#endif /* TEST_H */
