/* thread_name.h - names for tessera's threads, as top -H, gdb, perf and
 * /proc/PID/task/TID/comm show them: "tess-render-N" (the pipeline's render
 * threads other than the caller of pipeline_run), "tess-pool" (parallel.h's
 * workers: builds), "tess-input", "tess-replay", "tess-notify". The soak
 * test tells the pipeline's threads from the others by these names. The
 * thread that calls pipeline_run keeps its name (it is the process's:
 * renaming it would rename the process). */
#ifndef TESSERA_THREAD_NAME_H
#define TESSERA_THREAD_NAME_H

/* Name the calling thread (printf format; cut to the kernel's 15 bytes).
 * A failure is ignored: a name is a diagnostic, never needed to run. */
void thread_name_set(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

#endif
