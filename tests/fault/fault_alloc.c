/* fault_alloc.c - the --wrap shims behind fault.h, and the sweep.
 *
 * Each __wrap_X counts the call while armed and makes the armed one fail the
 * way X fails (NULL / ENOMEM, -1 / ENOMEM for getline, ENOMEM returned by
 * posix_memalign); everything else goes to __real_X (the C library's, or the
 * sanitizer's interceptor in the ASan build). */
#define _GNU_SOURCE /* strndup, getline, open_memstream */
#include "fault.h"

#include <criterion/criterion.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#define FAULT_HAVE_LSAN 1
#endif

static atomic_bool armed;
static atomic_long countdown; /* the armed failure is the call that takes it from 1 to 0 */
static atomic_long counted;
static atomic_bool fired;

void fault_arm(long n)
{
    atomic_store(&counted, 0);
    atomic_store(&fired, false);
    atomic_store(&countdown, n);
    atomic_store(&armed, true);
}

long fault_disarm(void)
{
    atomic_store(&armed, false);
    return atomic_load(&counted);
}

bool fault_fired(void) { return atomic_load(&fired); }

/* Count one allocation; true when it is the one to fail. */
static bool should_fail(void)
{
    if (!atomic_load_explicit(&armed, memory_order_relaxed))
        return false;
    atomic_fetch_add(&counted, 1);
    if (atomic_fetch_sub(&countdown, 1) != 1)
        return false;
    atomic_store(&fired, true);
    errno = ENOMEM;
    return true;
}

/* The shims: declared here (nothing else calls them by these names). */
void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);
void *__real_aligned_alloc(size_t align, size_t size);
int __real_posix_memalign(void **out, size_t align, size_t size);
char *__real_strdup(const char *s);
char *__real_strndup(const char *s, size_t n);
ssize_t __real_getline(char **line, size_t *capacity, FILE *f);
FILE *__real_open_memstream(char **buf, size_t *size);
FILE *__real_fopen(const char *path, const char *mode);
void *__wrap_malloc(size_t size);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t size);
void *__wrap_aligned_alloc(size_t align, size_t size);
int __wrap_posix_memalign(void **out, size_t align, size_t size);
char *__wrap_strdup(const char *s);
char *__wrap_strndup(const char *s, size_t n);
ssize_t __wrap_getline(char **line, size_t *capacity, FILE *f);
FILE *__wrap_open_memstream(char **buf, size_t *size);
FILE *__wrap_fopen(const char *path, const char *mode);

void *__wrap_malloc(size_t size) { return should_fail() ? NULL : __real_malloc(size); }
void *__wrap_calloc(size_t n, size_t size) { return should_fail() ? NULL : __real_calloc(n, size); }
void *__wrap_realloc(void *p, size_t size) { return should_fail() ? NULL : __real_realloc(p, size); }
void *__wrap_aligned_alloc(size_t align, size_t size)
{
    return should_fail() ? NULL : __real_aligned_alloc(align, size);
}
int __wrap_posix_memalign(void **out, size_t align, size_t size)
{
    return should_fail() ? ENOMEM : __real_posix_memalign(out, align, size);
}
char *__wrap_strdup(const char *s) { return should_fail() ? NULL : __real_strdup(s); }
char *__wrap_strndup(const char *s, size_t n) { return should_fail() ? NULL : __real_strndup(s, n); }
/* getline fails as glibc's does when growing the line fails: -1, ENOMEM */
ssize_t __wrap_getline(char **line, size_t *capacity, FILE *f)
{
    return should_fail() ? -1 : __real_getline(line, capacity, f);
}
FILE *__wrap_open_memstream(char **buf, size_t *size)
{
    return should_fail() ? NULL : __real_open_memstream(buf, size);
}
/* fopen allocates its FILE: it fails with ENOMEM like the others */
FILE *__wrap_fopen(const char *path, const char *mode) { return should_fail() ? NULL : __real_fopen(path, mode); }

bool fault_no_leaks(void)
{
#ifdef FAULT_HAVE_LSAN
    return __lsan_do_recoverable_leak_check() == 0;
#else
    return true;
#endif
}

static bool names_out_of_memory(const char *msg)
{
    return strstr(msg, "out of memory") || strstr(msg, strerror(ENOMEM));
}

fault_sweep_stats fault_sweep(const char *name, fault_op_fn op, void *ctx, const char *const *needles)
{
    fault_sweep_stats st = {0, 0, 0};
    char msg[1024];
    bool same = false;

    /* fault-free, counting: the sweep's size; twice, to know the count is stable */
    for (int run = 0; run < 2; run++) {
        msg[0] = '\0';
        fault_arm(0);
        bool ok = op(ctx, msg, sizeof msg, &same);
        long n = fault_disarm();
        cr_assert(ok, "%s: fails without an injected failure: %s", name, msg);
        cr_assert(same, "%s: the fault-free result differs from the reference", name);
        cr_assert(run == 0 || n == st.allocations, "%s: %ld allocations, then %ld: the sweep would not be exact",
                  name, st.allocations, n);
        st.allocations = n;
    }

    for (long n = 1; n <= st.allocations; n++) {
        msg[0] = '\0';
        same = false;
        fault_arm(n);
        bool ok = op(ctx, msg, sizeof msg, &same);
        fault_disarm();
        cr_assert(fault_fired(), "%s: allocation %ld of %ld never came", name, n, st.allocations);
        if (ok) {
            cr_assert(same, "%s: allocation %ld of %ld failed, yet it succeeded with a different result", name, n,
                      st.allocations);
            st.recovered++;
            continue;
        }
        st.failed++;
        cr_assert(msg[0] != '\0', "%s: allocation %ld of %ld failed: no message", name, n, st.allocations);
        cr_assert(strchr(msg, '\n') == NULL, "%s: allocation %ld: message of more than one line: %s", name, n, msg);
        cr_assert(names_out_of_memory(msg), "%s: allocation %ld of %ld failed: the message does not say so: %s", name,
                  n, st.allocations, msg);
        for (const char *const *s = needles; s && *s; s++)
            cr_assert(strstr(msg, *s), "%s: allocation %ld of %ld: the message does not name '%s': %s", name, n,
                      st.allocations, *s, msg);
    }
    cr_assert(fault_no_leaks(), "%s: LeakSanitizer found leaks in the sweep (report above)", name);
    cr_log_info("%s: %ld allocations swept: %ld failed cleanly, %ld recovered", name, st.allocations, st.failed,
                st.recovered);
    return st;
}
