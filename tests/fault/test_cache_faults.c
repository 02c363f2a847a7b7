/* test_cache_faults.c - the acceleration-structure cache (engine/base/cache_file.h) when the disk
 * fails under a write (a full disk: ENOSPC from pwrite, at the start and mid-file; a lost
 * write reported by close) and when memory runs out (every allocation of a write and of an
 * open, in turn). A failed write names the file and the problem, leaves no file and no
 * temporary, and leaves a cache already there untouched. */
#include <criterion/criterion.h>

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/base/cache_file.h"
#include "fault.h"

static char dir[64];
static char path[128];

static void dir_create(void)
{
    snprintf(dir, sizeof dir, "/tmp/tessera_fault_cache_XXXXXX");
    cr_assert_not_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/sub/model.tcache", dir);
}

static void dir_remove(void)
{
    fault_io_reset();
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
}

TestSuite(cache_faults, .init = dir_create, .fini = dir_remove);

static const cache_key KEY = {.lo = 42, .hi = 7};

/* three sections: four pwrite calls (header and table, then one per section) */
static uint32_t a[1000], b[3000];
static double c[77];
static const cache_section_source SECTIONS[3] = {
    {"a", a, sizeof a[0], 1000}, {"b", b, sizeof b[0], 3000}, {"c", c, sizeof c[0], 77}};

static void fill(uint32_t seed)
{
    for (int i = 0; i < 1000; i++)
        a[i] = (uint32_t)i * 2654435761u + seed;
    for (int i = 0; i < 3000; i++)
        b[i] = (uint32_t)i ^ seed;
    for (int i = 0; i < 77; i++)
        c[i] = i * 0.5 + seed;
}

/* Files in the cache's directory other than the cache itself (temporaries left behind). */
static int strays(void)
{
    char sub[128];
    snprintf(sub, sizeof sub, "%s/sub", dir);
    DIR *d = opendir(sub);
    if (!d)
        return 0;
    int n = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strcmp(e->d_name, "model.tcache"))
            n++;
    closedir(d);
    return n;
}

static void expect_failed_write(const char *problem, const char *what)
{
    tess_error err = {{0}};
    bool ok = cache_write(path, KEY, 1, SECTIONS, 3, &err);
    fault_io_reset();
    cr_assert_not(ok, "%s: written despite the injected failure", what);
    cr_assert(strstr(err.msg, path) && strstr(err.msg, "not written"), "%s: %s", what, err.msg);
    cr_assert(strstr(err.msg, problem), "%s: the message does not say '%s': %s", what, problem, err.msg);
    cr_assert_eq(strays(), 0, "%s: a temporary was left behind", what);
}

/* The cache at path opens and holds the arrays as filled with seed. */
static void expect_cache_of(uint32_t seed)
{
    fill(seed);
    tess_error err = {{0}};
    cache_file *f = NULL;
    cr_assert_eq(cache_open(path, KEY, 1, &f, &err), CACHE_OK, "%s", err.msg);
    size_t n = 0;
    const uint32_t *got = cache_section(f, "b", sizeof b[0], &n, &err);
    cr_assert(got && n == 3000 && memcmp(got, b, sizeof b) == 0);
    cache_close(f);
}

Test(cache_faults, a_full_disk_fails_the_write_and_leaves_nothing)
{
    fill(1);
    for (long skip = 0; skip < 4; skip++) { /* the header, then each section */
        char what[64];
        snprintf(what, sizeof what, "ENOSPC after %ld writes", skip);
        fault_io_fail_pwrite(ENOSPC, skip);
        expect_failed_write(strerror(ENOSPC), what);
        cr_assert_neq(access(path, F_OK), 0, "%s: a file appeared under the real name", what);
    }
}

Test(cache_faults, a_failed_rewrite_leaves_the_old_cache_whole)
{
    fill(1);
    tess_error err = {{0}};
    cr_assert(cache_write(path, KEY, 1, SECTIONS, 3, &err), "%s", err.msg);
    fill(2);
    fault_io_fail_pwrite(ENOSPC, 2);
    expect_failed_write(strerror(ENOSPC), "ENOSPC mid-rewrite");
    fault_io_fail_close(EIO);
    expect_failed_write("closing it", "EIO at close");
    expect_cache_of(1);
}

static void copy_msg(char *msg, size_t msg_bytes, const tess_error *err) { snprintf(msg, msg_bytes, "%s", err->msg); }

static bool op_write(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    (void)ctx;
    tess_error err = {{0}};
    bool ok = cache_write(path, KEY, 1, SECTIONS, 3, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = true;
    return true;
}

static bool op_open(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    (void)ctx;
    tess_error err = {{0}};
    cache_file *f = NULL;
    cache_status s = cache_open(path, KEY, 1, &f, &err);
    fault_disarm();
    if (s != CACHE_OK) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    size_t n = 0;
    const uint32_t *got = cache_section(f, "b", sizeof b[0], &n, &err);
    *same = got && n == 3000 && memcmp(got, b, sizeof b) == 0 && cache_section_count(f) == 3;
    cache_close(f);
    return true;
}

Test(cache_faults, every_allocation_of_a_write_and_an_open_may_fail)
{
    fill(3);
    const char *needles[] = {path, NULL};
    fault_sweep_stats w = fault_sweep("cache_write", op_write, NULL, needles);
    cr_assert_geq(w.allocations, 1);
    cr_assert_eq(strays(), 0);
    fault_sweep_stats o = fault_sweep("cache_open", op_open, NULL, needles);
    cr_assert_geq(o.allocations, 2);
    expect_cache_of(3);
}
