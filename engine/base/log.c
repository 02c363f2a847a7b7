#include "log.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const level_names[] = {"debug", "info", "warn", "error"};

/* log_divert_thread: this thread's lines go here instead of stderr */
static _Thread_local log_divert_fn divert_fn;
static _Thread_local void *divert_ctx;

void log_divert_thread(log_divert_fn fn, void *ctx)
{
    divert_fn = fn;
    divert_ctx = fn ? ctx : NULL;
}

static enum log_level threshold(void)
{
    const char *env = getenv("TESSERA_LOG");
    if (env)
        for (int i = LOG_DEBUG; i <= LOG_ERROR; i++)
            if (strcmp(env, level_names[i]) == 0)
                return (enum log_level)i;
    return LOG_INFO;
}

bool log_enabled(enum log_level level) { return level >= threshold(); }

static void emit(enum log_level level, const char *file, int line, const char *suffix, const char *fmt,
                 va_list ap)
{
    if (level < threshold())
        return;
    char body[1024];
    vsnprintf(body, sizeof body, fmt, ap);
    if (divert_fn) {
        char whole[1400];
        if (level == LOG_DEBUG)
            snprintf(whole, sizeof whole, "tessera: %s: %s%s (%s:%d)", level_names[level], body, suffix, file, line);
        else
            snprintf(whole, sizeof whole, "tessera: %s: %s%s", level_names[level], body, suffix);
        divert_fn(divert_ctx, whole);
        return;
    }
    /* one fprintf per message so lines from several threads do not interleave */
    if (level == LOG_DEBUG)
        fprintf(stderr, "tessera: %s: %s%s (%s:%d)\n", level_names[level], body, suffix, file, line);
    else
        fprintf(stderr, "tessera: %s: %s%s\n", level_names[level], body, suffix);
}

void log_write(enum log_level level, const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    emit(level, file, line, "", fmt, ap);
    va_end(ap);
}

void log_write_errno(enum log_level level, const char *file, int line, const char *fmt, ...)
{
    int saved = errno;
    char suffix[256];
    snprintf(suffix, sizeof suffix, ": %s", strerror(saved));
    va_list ap;
    va_start(ap, fmt);
    emit(level, file, line, suffix, fmt, ap);
    va_end(ap);
}
