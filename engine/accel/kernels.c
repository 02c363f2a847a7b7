#include "kernels.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/log.h"

static const kernel_table *const tables[KERNEL_ISA_COUNT] = {&kernel_table_sse2, &kernel_table_avx2,
                                                              &kernel_table_avx512};

static bool cpu_runs(kernel_isa isa)
{
    __builtin_cpu_init();
    switch (isa) {
    case KERNEL_ISA_SSE2:
        return true; /* the x86-64 baseline */
    case KERNEL_ISA_AVX2:
        return __builtin_cpu_supports("avx2");
    case KERNEL_ISA_AVX512:
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
               __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
    default:
        return false;
    }
}

kernel_isa kernels_isa_by_name(const char *name)
{
    for (int i = 0; name && i < KERNEL_ISA_COUNT; i++)
        if (strcmp(name, tables[i]->isa_name) == 0)
            return (kernel_isa)i;
    return KERNEL_ISA_COUNT;
}

const char *kernels_isa_name(kernel_isa isa)
{
    return isa >= 0 && isa < KERNEL_ISA_COUNT ? tables[isa]->isa_name : "?";
}

/* The highest ISA TESSERA_ISA_MAX allows: the last one when it is unset or
 * empty, or names no ISA (kernels_check_env refuses that; the library only
 * ignores it). Read on every call: the environment is the one truth, and the
 * tests set it per process. */
static kernel_isa isa_cap(void)
{
    const char *cap = getenv("TESSERA_ISA_MAX");
    if (!cap || !*cap)
        return KERNEL_ISA_COUNT - 1;
    kernel_isa isa = kernels_isa_by_name(cap);
    return isa == KERNEL_ISA_COUNT ? KERNEL_ISA_COUNT - 1 : isa;
}

bool kernels_usable(kernel_isa isa, char *why, size_t why_bytes)
{
    if (why && why_bytes)
        why[0] = '\0';
    if (isa < 0 || isa >= KERNEL_ISA_COUNT) {
        if (why && why_bytes)
            snprintf(why, why_bytes, "no such instruction set");
        return false;
    }
    if (!cpu_runs(isa)) {
        if (why && why_bytes)
            snprintf(why, why_bytes, "this CPU lacks %s", tables[isa]->isa_name);
        return false;
    }
    if (isa > isa_cap()) {
        if (why && why_bytes)
            snprintf(why, why_bytes, "TESSERA_ISA_MAX=%s caps it", getenv("TESSERA_ISA_MAX"));
        return false;
    }
    return true;
}

const kernel_table *kernels_for(kernel_isa isa)
{
    return kernels_usable(isa, NULL, 0) ? tables[isa] : NULL;
}

/* "sse2, avx2, avx512" */
static void isa_list(char *out, size_t out_bytes)
{
    size_t used = 0;
    out[0] = '\0';
    for (int i = 0; i < KERNEL_ISA_COUNT && used < out_bytes; i++)
        used += (size_t)snprintf(out + used, out_bytes - used, "%s%s", i ? ", " : "", tables[i]->isa_name);
}

bool kernels_check_env(tess_error *err)
{
    static const char *const vars[] = {"TESSERA_ISA_MAX", "TESSERA_ISA"};
    for (size_t v = 0; v < sizeof vars / sizeof vars[0]; v++) {
        const char *value = getenv(vars[v]);
        if (value && *value && kernels_isa_by_name(value) == KERNEL_ISA_COUNT) {
            char names[64];
            isa_list(names, sizeof names);
            return tess_error_set(err, "environment: %s=%s: not an instruction set (expected one of: %s)", vars[v],
                                  value, names);
        }
    }
    return true;
}

const kernel_table *kernels_select(void)
{
    const char *forced = getenv("TESSERA_ISA");
    if (forced && *forced) {
        kernel_isa isa = kernels_isa_by_name(forced);
        char why[96];
        if (isa == KERNEL_ISA_COUNT)
            log_warn("TESSERA_ISA=%s: not an instruction set; using the best this CPU can run", forced);
        else if (kernels_usable(isa, why, sizeof why))
            return tables[isa];
        else
            log_warn("TESSERA_ISA=%s: %s; using the best it can", forced, why);
    }
    for (int i = KERNEL_ISA_COUNT - 1; i >= 0; i--)
        if (kernels_usable((kernel_isa)i, NULL, 0))
            return tables[i];
    return tables[KERNEL_ISA_SSE2];
}

static const kernel_table *default_table; /* written once under default_once */
static pthread_once_t default_once = PTHREAD_ONCE_INIT;

static void resolve_default(void) { default_table = kernels_select(); }

const kernel_table *kernels_default(void)
{
    pthread_once(&default_once, resolve_default);
    return default_table;
}
