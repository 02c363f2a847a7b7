/* log.h - the one logger: severity, printf-checked format, source location.
 * Messages go to stderr; TESSERA_LOG=debug|info|warn|error sets the threshold. */
#ifndef TESSERA_LOG_H
#define TESSERA_LOG_H

#include <stdbool.h>

enum log_level { LOG_DEBUG, LOG_INFO, LOG_WARN, LOG_ERROR };

void log_write(enum log_level level, const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* As log_write, with ": strerror(errno)" appended (errno read on entry). */
void log_write_errno(enum log_level level, const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* Would a message of `level` be written (TESSERA_LOG's threshold)? Progress
 * reports (engine/base/progress.h) are info: TESSERA_LOG=warn silences them. */
bool log_enabled(enum log_level level);

/* Divert the calling thread's messages: each formatted line (no newline) goes
 * to fn(ctx, line) instead of stderr until log_divert_thread(NULL, NULL).
 * The pipeline's serial section collects its lines this way and writes them
 * after the frame barrier, so a slow stderr never stalls a frame. */
typedef void (*log_divert_fn)(void *ctx, const char *line);
void log_divert_thread(log_divert_fn fn, void *ctx);

#define log_debug(...) log_write(LOG_DEBUG, __FILE__, __LINE__, __VA_ARGS__)
#define log_info(...) log_write(LOG_INFO, __FILE__, __LINE__, __VA_ARGS__)
#define log_warn(...) log_write(LOG_WARN, __FILE__, __LINE__, __VA_ARGS__)
#define log_error(...) log_write(LOG_ERROR, __FILE__, __LINE__, __VA_ARGS__)
#define log_errno(level, ...) log_write_errno(level, __FILE__, __LINE__, __VA_ARGS__)

#endif
