#include "kernels.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "log.h"

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

static const kernel_table *const tables[KERNEL_ISA_COUNT] = {&kernel_table_sse2, &kernel_table_avx2,
                                                              &kernel_table_avx512};

const kernel_table *kernels_for(kernel_isa isa)
{
    if (isa < 0 || isa >= KERNEL_ISA_COUNT || !cpu_runs(isa))
        return NULL;
    return tables[isa];
}

const kernel_table *kernels_select(void)
{
    const char *forced = getenv("TESSERA_ISA");
    if (forced && *forced) {
        for (int i = 0; i < KERNEL_ISA_COUNT; i++)
            if (strcmp(forced, tables[i]->isa_name) == 0) {
                if (cpu_runs((kernel_isa)i))
                    return tables[i];
                log_warn("TESSERA_ISA=%s: this CPU cannot run it; using the best it can", forced);
            }
    }
    for (int i = KERNEL_ISA_COUNT - 1; i >= 0; i--)
        if (cpu_runs((kernel_isa)i))
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
