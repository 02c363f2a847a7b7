/* support.h - what the tests that run the tessera binary share: a temp
 * directory per test, the binary's path, running a command with its exit
 * status decoded, and reading a captured output file. Header-only (static). */
#ifndef TESSERA_TESTS_SUPPORT_H
#define TESSERA_TESTS_SUPPORT_H

#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>

/* A fresh mkdtemp directory /tmp/tessera-NAME-XXXXXX into dir. */
static inline void support_make_tmp_dir(char *dir, size_t size, const char *name)
{
    snprintf(dir, size, "/tmp/tessera-%s-XXXXXX", name);
    cr_assert(mkdtemp(dir), "mkdtemp %s", dir);
}

/* The binary under test: $TESSERA_BIN, else ../tessera (tests run from tests/). */
static inline const char *support_tessera_bin(void)
{
    const char *bin = getenv("TESSERA_BIN");
    return bin ? bin : "../tessera";
}

/* Run a shell command; its exit status, or 128 + the signal that killed it. */
static inline int support_run(const char *cmd)
{
    int status = system(cmd);
    if (WIFSIGNALED(status))
        return 128 + WTERMSIG(status);
    return WEXITSTATUS(status);
}

/* The start of a file as a string ("" when it cannot be read). */
static inline void support_read_text(const char *path, char *out, size_t out_bytes)
{
    FILE *f = fopen(path, "rb");
    size_t n = f ? fread(out, 1, out_bytes - 1, f) : 0;
    out[n] = '\0';
    if (f)
        fclose(f);
}

#endif
