/* support.h - what the tests that run the tessera binary share: a temp
 * directory per test, the binary's path, running a command with its exit
 * status decoded, and reading a captured output file. Header-only (static). */
#ifndef TESSERA_TESTS_SUPPORT_H
#define TESSERA_TESTS_SUPPORT_H

#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "wall/dump.h"

/* A fresh mkdtemp directory /tmp/tessera-NAME-XXXXXX into dir. */
static inline void support_make_tmp_dir(char *dir, size_t size, const char *name)
{
    snprintf(dir, size, "/tmp/tessera-%s-XXXXXX", name);
    cr_assert(mkdtemp(dir), "mkdtemp %s", dir);
}

/* Remove a directory made by support_make_tmp_dir, with what is in it. */
static inline void support_remove_tmp_dir(const char *dir)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
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

/* Run `tessera COMMAND ARGS` with a time limit, stdout and stderr kept apart
 * (dir/COMMAND.out, dir/COMMAND.err, copied to out and err, out_bytes each);
 * every %s in args_fmt (up to 4) is `dir`. The exit status (128+signal). */
static inline int support_tessera_split(const char *dir, int timeout_s, char *out, char *err, size_t out_bytes,
                                        const char *command, const char *args_fmt)
{
    char args[2048], cmd[4096], out_path[512], err_path[512];
    snprintf(args, sizeof args, args_fmt, dir, dir, dir, dir);
    snprintf(out_path, sizeof out_path, "%s/%s.out", dir, command);
    snprintf(err_path, sizeof err_path, "%s/%s.err", dir, command);
    snprintf(cmd, sizeof cmd, "timeout %d %s %s %s > '%s' 2> '%s'", timeout_s, support_tessera_bin(), command, args,
             out_path, err_path);
    int code = support_run(cmd);
    support_read_text(out_path, out, out_bytes);
    support_read_text(err_path, err, out_bytes);
    return code;
}

/* `tessera bench ARGS`, as support_tessera_split. */
static inline int support_tessera_bench(const char *dir, int timeout_s, char *out, char *err, size_t out_bytes,
                                        const char *args_fmt)
{
    return support_tessera_split(dir, timeout_s, out, err, out_bytes, "bench", args_fmt);
}

/* Run `tessera ARGS` with a time limit; every %s in args_fmt (up to 8) is
 * `dir`, where the combined output is captured (dir/cli.log) and copied to
 * `out`. Returns the exit status (124 from timeout: a hang; 128+signal). */
static inline int support_tessera(const char *dir, int timeout_s, char *out, size_t out_bytes, const char *args_fmt)
{
    char args[2048], cmd[4096], log_path[512];
    const char *d = dir;
    snprintf(args, sizeof args, args_fmt, d, d, d, d, d, d, d, d);
    snprintf(log_path, sizeof log_path, "%s/cli.log", dir);
    snprintf(cmd, sizeof cmd, "timeout %d %s %s > %s 2>&1", timeout_s, support_tessera_bin(), args, log_path);
    int code = support_run(cmd);
    support_read_text(log_path, out, out_bytes);
    return code;
}

/* Write `text` to dir/name. */
static inline void support_write_file(const char *dir, const char *name, const char *text)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    cr_assert(f, "cannot write %s", path);
    fputs(text, f);
    fclose(f);
}

/* Expect `tessera ARGS` (as for support_tessera) to fail cleanly: a non-zero
 * exit that is not a crash or a timeout, an error line, and every one of the
 * NULL-terminated needles in its output. */
static inline void support_expect_error(const char *dir, int timeout_s, const char *args_fmt,
                                        const char *const *needles)
{
    char out[8192];
    int code = support_tessera(dir, timeout_s, out, sizeof out, args_fmt);
    cr_expect(code != 0 && code < 124, "'%s' should fail cleanly, got exit %d: %s", args_fmt, code, out);
    cr_expect(strstr(out, "error") != NULL, "no error line for '%s': %s", args_fmt, out);
    for (const char *const *n = needles; *n; n++)
        cr_expect(strstr(out, *n) != NULL, "'%s': message lacks '%s': %s", args_fmt, *n, out);
}

/* Float pixels of the image dir/name (caller frees); fails the test if unreadable. */
static inline float *support_read_image(const char *dir, const char *name, int *w, int *h)
{
    char path[512];
    tess_error err = {{0}};
    float *rgb = NULL;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    cr_assert(dump_read_rgbf(path, w, h, &rgb, &err), "%s", err.msg);
    return rgb;
}

#endif
