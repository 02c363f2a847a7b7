/* isa_skip.h - what a test that loops over the instruction sets says of one
 * it may not use here: a CPU without AVX-512 (or AVX2), or TESSERA_ISA_MAX
 * capping it (make test-isa-caps). That is a check skipped, said the way the
 * suite says skipped checks (a SKIPPED line on stderr), never a Criterion
 * warning: Criterion 2.4 exits 1 when any test logged one, so the suite would
 * fail on such a CPU with every test green. Header-only (static). */
#ifndef TESSERA_TESTS_ISA_SKIP_H
#define TESSERA_TESTS_ISA_SKIP_H

#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <stdio.h>

#include "engine/accel/kernels.h"

/* When tessera may not use the ISA named isa_name here, say so for the
 * running test (suite::name) and return true: the caller skips that ISA. */
static inline bool isa_skip_note(const char *isa_name)
{
    char why[96];
    if (kernels_usable(kernels_isa_by_name(isa_name), why, sizeof why))
        return false;
    const char *suite = criterion_current_suite ? criterion_current_suite->name : "?";
    const char *test = criterion_current_test ? criterion_current_test->name : "?";
    fprintf(stderr, "SKIPPED: %s::%s: the %s kernels: %s\n", suite, test, isa_name, why);
    cr_log_info("%s::%s: %s kernels not tested here: %s", suite, test, isa_name, why);
    return true;
}

#endif
