/* tests/tsan/criterion/criterion.h - a stand-in for Criterion's header, used
 * only by `make test-tsan`.
 *
 * Criterion cannot start under ThreadSanitizer (its inheritable arena fails:
 * "Could not initialize inheritable arena", Criterion issue #274, open), so
 * the TSan build compiles the threaded test files against this header
 * instead: the same Test() bodies and assertions, run one after another in
 * one process by main() below. A failed assertion prints file, line and
 * message and exits 1; a test's .timeout (default 600 s) is an alarm that
 * kills the run, so a deadlock fails instead of hanging.
 * Supports only what those files use: Test(suite, name[, .timeout = N]),
 * cr_assert, cr_assert_not, cr_assert_eq, cr_assert_null, cr_assert_not_null,
 * cr_assert_geq, cr_assert_gt, cr_assert_leq, cr_assert_float_eq,
 * cr_assert_str_eq, cr_expect*, cr_log_info. Several test files link into one binary: the registry and
 * main() are weak definitions, so each file's copy is the same one. */
#ifndef TESSERA_TSAN_CRITERION_SHIM_H
#define TESSERA_TSAN_CRITERION_SHIM_H

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct shim_test {
    const char *suite, *name;
    void (*fn)(void);
    unsigned timeout_s;
} shim_test;

typedef struct shim_options {
    int given;        /* a field to initialise when Test() has no options */
    unsigned timeout; /* seconds, 0: default */
} shim_options;

#define SHIM_MAX_TESTS 256
__attribute__((weak)) shim_test shim_tests[SHIM_MAX_TESTS];
__attribute__((weak)) int shim_test_count;

static inline void shim_register(const char *suite, const char *name, void (*fn)(void), shim_options o)
{
    if (shim_test_count == SHIM_MAX_TESTS) {
        fprintf(stderr, "tsan shim: more than %d tests\n", SHIM_MAX_TESTS);
        exit(2);
    }
    shim_tests[shim_test_count++] = (shim_test){suite, name, fn, o.timeout ? o.timeout : 600};
}

#define Test(suite, name, ...)                                                                 \
    static void suite##_##name(void);                                                          \
    __attribute__((constructor)) static void shim_register_##suite##_##name(void)              \
    {                                                                                          \
        shim_register(#suite, #name, suite##_##name, (shim_options){.given = 1, __VA_ARGS__});          \
    }                                                                                          \
    static void suite##_##name(void)

static inline void shim_check(bool ok, const char *file, int line, const char *expr, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static inline void shim_check(bool ok, const char *file, int line, const char *expr, const char *fmt, ...)
{
    if (ok)
        return;
    fprintf(stderr, "%s:%d: Assertion failed: %s\n  ", file, line, expr);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(1);
}

#define cr_assert(cond, ...) shim_check((cond) ? true : false, __FILE__, __LINE__, #cond, " " __VA_ARGS__)
#define cr_assert_not(cond, ...) shim_check((cond) ? false : true, __FILE__, __LINE__, "!(" #cond ")", " " __VA_ARGS__)
#define cr_assert_eq(a, b, ...) shim_check((a) == (b), __FILE__, __LINE__, #a " == " #b, " " __VA_ARGS__)
#define cr_assert_null(x, ...) shim_check((x) == NULL, __FILE__, __LINE__, #x " == NULL", " " __VA_ARGS__)
/* Criterion's expectations go on after a failure; here they stop the test like
 * an assertion (stricter, and the test fails either way). */
#define cr_expect(cond, ...) cr_assert(cond, __VA_ARGS__)
#define cr_expect_not(cond, ...) cr_assert_not(cond, __VA_ARGS__)
#define cr_expect_eq(a, b, ...) cr_assert_eq(a, b, __VA_ARGS__)
#define cr_expect_str_eq(a, b, ...) shim_check(strcmp((a), (b)) == 0, __FILE__, __LINE__, #a " == " #b, " " __VA_ARGS__)
#define cr_assert_geq(a, b, ...) shim_check((a) >= (b), __FILE__, __LINE__, #a " >= " #b, " " __VA_ARGS__)
#define cr_expect_geq(a, b, ...) cr_assert_geq(a, b, __VA_ARGS__)
#define cr_assert_gt(a, b, ...) shim_check((a) > (b), __FILE__, __LINE__, #a " > " #b, " " __VA_ARGS__)
#define cr_assert_leq(a, b, ...) shim_check((a) <= (b), __FILE__, __LINE__, #a " <= " #b, " " __VA_ARGS__)
#define cr_assert_lt(a, b, ...) shim_check((a) < (b), __FILE__, __LINE__, #a " < " #b, " " __VA_ARGS__)
#define cr_assert_not_null(x, ...) shim_check((x) != NULL, __FILE__, __LINE__, #x " != NULL", " " __VA_ARGS__)
#define cr_expect_null(x, ...) cr_assert_null(x, __VA_ARGS__)
#define cr_assert_str_eq(a, b, ...) cr_expect_str_eq(a, b, __VA_ARGS__)
/* |a - b| <= eps, as Criterion's (a, b and eps evaluated once each) */
#define cr_assert_float_eq(a, b, eps, ...)                                                                            \
    shim_check(fabs((double)(a) - (double)(b)) <= (double)(eps), __FILE__, __LINE__, "|" #a " - " #b "| <= " #eps,    \
               " " __VA_ARGS__)
#define cr_expect_float_eq(a, b, eps, ...) cr_assert_float_eq(a, b, eps, __VA_ARGS__)
/* Criterion's info log: printed to stderr here. */
#define cr_log_info(...) (fprintf(stderr, "  info: " __VA_ARGS__), fputc('\n', stderr))

/* Run every test whose "suite/name" starts with argv[1] (all without one). */
int main(int argc, char **argv);
__attribute__((weak)) int main(int argc, char **argv)
{
    const char *prefix = argc > 1 ? argv[1] : "";
    int ran = 0;
    for (int i = 0; i < shim_test_count; i++) {
        char full[256];
        snprintf(full, sizeof full, "%s/%s", shim_tests[i].suite, shim_tests[i].name);
        if (strncmp(full, prefix, strlen(prefix)) != 0)
            continue;
        fprintf(stderr, "[tsan] %s\n", full);
        alarm(shim_tests[i].timeout_s);
        shim_tests[i].fn();
        alarm(0);
        ran++;
    }
    fprintf(stderr, "[tsan] %d test%s passed\n", ran, ran == 1 ? "" : "s");
    return ran > 0 ? 0 : 1;
}

#endif
