/* test_robust_cli.c - `tessera robust` (app/cmd_robust.c) end to end:
 * one line per case with every field, the default (robust) kernels giving 0
 * wrong hits and 0 leaks on the small cases, and bad options refused with a
 * message naming them. Runs ../tessera (or $TESSERA_BIN) from tests/. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

#define RUN_TIMEOUT_S 120
#define OUT_BYTES 8192

static char dir[256];

static void setup(void) { support_make_tmp_dir(dir, sizeof dir, "robust"); }
static void teardown(void) { support_remove_tmp_dir(dir); }

TestSuite(robust_cli, .init = setup, .fini = teardown, .timeout = 300);

/* The value of `key=` in line (up to the next space) as a number; -1 when absent. */
static double field(const char *line, const char *key)
{
    char needle[64];
    snprintf(needle, sizeof needle, " %s=", key);
    const char *p = strstr(line, needle);
    if (!p && !strncmp(line, needle + 1, strlen(needle + 1)))
        p = line - 1; /* the first field has no space before it */
    if (!p)
        return -1.0;
    return strtod(p + strlen(needle), NULL);
}

Test(robust_cli, prints_every_field_and_default_kernels_make_no_errors)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    int code = support_tessera_split(dir, RUN_TIMEOUT_S, out, err, OUT_BYTES, "robust", "--small --threads 2");
    cr_assert_eq(code, 0, "exit %d: %s", code, err);
    const char *cases[] = {"primary", "closed_sphere", "slivers", "lit_plane"};
    const char *keys[] = {"rays", "wrong_hits", "leaks", "per_million", "mrays_s", "checked", "threads", "mrays_s_min",
                          "mrays_s_max", "mrays_cpu_s", "mrays_cpu_s_min", "mrays_cpu_s_max"};
    char *save = NULL;
    int lines = 0;
    for (char *line = strtok_r(out, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        cr_assert(lines < 4, "more lines than cases: %s", line);
        char want[64];
        snprintf(want, sizeof want, "case=%s ", cases[lines]);
        cr_expect(!strncmp(line, want, strlen(want)), "line %d should start with '%s': %s", lines, want, line);
        for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
            cr_expect(field(line, keys[k]) >= 0.0, "no %s= in: %s", keys[k], line);
        cr_expect(strstr(line, " build=robust ") != NULL, "the default build says build=robust: %s", line);
        cr_expect(strstr(line, " isa=") != NULL, "no isa= in: %s", line);
        cr_expect_gt(field(line, "rays"), 1000.0, "too few rays: %s", line);
        cr_expect_gt(field(line, "checked"), 100.0, "too few checked: %s", line);
        cr_expect_gt(field(line, "mrays_s"), 0.0, "no speed: %s", line);
        cr_expect_eq(field(line, "threads"), 2.0, "%s", line);
        /* our kernels: no leak and no wrong hit on any hard case */
        cr_expect_eq(field(line, "wrong_hits"), 0.0, "%s", line);
        cr_expect_eq(field(line, "leaks"), 0.0, "%s", line);
        cr_expect_eq(field(line, "per_million"), 0.0, "%s", line);
        lines++;
    }
    cr_expect_eq(lines, 4, "one line per case: %d", lines);
}

Test(robust_cli, one_case_by_name)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    int code = support_tessera_split(dir, RUN_TIMEOUT_S, out, err, OUT_BYTES, "robust",
                                     "--small --case closed_sphere --repeat 4");
    cr_assert_eq(code, 0, "exit %d: %s", code, err);
    cr_expect(!strncmp(out, "case=closed_sphere ", 19), "%s", out);
    cr_expect_eq(strchr(out, '\n'), strrchr(out, '\n'), "one line only: %s", out);
    cr_expect_eq(field(out, "leaks"), 0.0, "%s", out);
    cr_expect_eq(field(out, "rays"), field(out, "checked"), "every closed-sphere ray is checked: %s", out);
}

Test(robust_cli, help_names_the_cases)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    int code = support_tessera_split(dir, RUN_TIMEOUT_S, out, err, OUT_BYTES, "robust", "--help");
    cr_assert_eq(code, 0);
    const char *needles[] = {"usage: tessera robust", "closed_sphere", "slivers", "lit_plane", "primary", "--repeat"};
    for (size_t i = 0; i < sizeof needles / sizeof needles[0]; i++)
        cr_expect(strstr(out, needles[i]) != NULL, "help lacks '%s': %s", needles[i], out);
}

Test(robust_cli, bad_options_are_refused_clearly)
{
    const char *const unknown_case[] = {"--case", "spheres", "closed_sphere", NULL};
    support_expect_error(dir, RUN_TIMEOUT_S, "robust --case spheres", unknown_case);
    const char *const missing[] = {"--case", NULL};
    support_expect_error(dir, RUN_TIMEOUT_S, "robust --case", missing);
    const char *const repeat[] = {"--repeat", "2", NULL};
    support_expect_error(dir, RUN_TIMEOUT_S, "robust --repeat 2", repeat);
    const char *const threads[] = {"--threads", "0", NULL};
    support_expect_error(dir, RUN_TIMEOUT_S, "robust --threads 0", threads);
    const char *const junk[] = {"--threads", "2x", NULL};
    support_expect_error(dir, RUN_TIMEOUT_S, "robust --threads 2x", junk);
    const char *const option[] = {"--fast", "tessera robust --help", NULL};
    support_expect_error(dir, RUN_TIMEOUT_S, "robust --fast", option);
}
