/* progress.h - progress of one long task with a known total (bytes of a file
 * read, primitives placed into BVH leaves), reported on stderr.
 *
 * WHAT IT PRINTS. On a terminal (isatty(stderr), TERM not "dumb"), one line
 * redrawn in place with '\r' at most every PROGRESS_BAR_PERIOD_S:
 *   tessera: loading dragon.ply  40% [########------------] 410 MB/s, 1.3 s left
 * and, when the task ends, that line replaced by its summary:
 *   tessera: loading dragon.ply: 870 MB in 2.1 s (410 MB/s)
 * Anywhere else (a log file, a pipe), whole lines: one each time the task
 * passes a new multiple of 10 % (at most one every PROGRESS_LINE_GAP_S, and one
 * every PROGRESS_LINE_STALL_S without a new step), then the same summary:
 *   tessera: loading dragon.ply: 40% (348 MB of 870 MB, 410 MB/s, 1.3 s left)
 * The rate is the average since the task's first update (so time before
 * anything could be counted, such as the top levels of a BVH build, does not
 * dilute it); the time left assumes it holds. The summary's rate is the
 * whole task's: amount / time since progress_begin.
 * A total of 0 means "unknown": amounts and rate, no percentage or time left.
 *
 * WHEN IT IS SILENT. A process is quiet until it calls progress_set_quiet(false):
 * tessera's main does; the engine used as a library (the test suite, the soak
 * driver, the fuzzers) prints no progress unless it asks. A task that ends
 * within PROGRESS_SILENT_S prints nothing at all (so small scenes stay quiet).
 * Nothing is printed either under TESSERA_LOG=warn or error (progress is info,
 * engine/base/log.h), or with progress_output.quiet for one task.
 * Output goes to stderr only (the benchmarks' parsers read stdout). A failed
 * write is ignored, never reported.
 *
 * COST AND THREADS. progress_add / progress_set may be called often and from
 * several threads at once: each is one relaxed atomic add (or max) on `done`;
 * only when `done` reaches `check_at` (every ~0.1 % of the total) does the
 * caller read the clock, and then only the thread that wins the `busy` flag
 * formats and writes; the others go on at once. Nothing a caller computes
 * depends on the reporter, so a build stays bit-identical with or without it.
 * progress_begin and progress_end must not run concurrently with updates of
 * the same reporter (begin before the workers start, end after they finish).
 * Every function accepts NULL and then does nothing; a zeroed reporter that
 * was never begun is silent, and progress_end on it does nothing. */
#ifndef TESSERA_PROGRESS_H
#define TESSERA_PROGRESS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* a task that ends sooner prints nothing; a longer one shows from then on */
#define PROGRESS_SILENT_S 1.0
/* ... once its rate has been measured over this long */
#define PROGRESS_RATE_MIN_S 0.5
/* a terminal's bar is redrawn at most this often */
#define PROGRESS_BAR_PERIOD_S 0.1
/* plain lines: at most one per this many seconds, each at a new 10 % step ... */
#define PROGRESS_LINE_GAP_S 1.0
/* ... and one after this long without a new step (a slow task still speaks) */
#define PROGRESS_LINE_STALL_S 10.0
/* `what` is cut to this many bytes (with its NUL) */
#define PROGRESS_WHAT_BYTES 80
/* `unit` is cut to this many bytes (with its NUL): "B", "tri", "prim" */
#define PROGRESS_UNIT_BYTES 16

/* How a reporter shows itself. */
enum progress_style {
    PROGRESS_STYLE_AUTO,  /* a bar when the stream is a terminal (TERM not "dumb"), else lines */
    PROGRESS_STYLE_BAR,   /* a bar redrawn with '\r' */
    PROGRESS_STYLE_LINES, /* whole lines */
};

/* Monotonic seconds; ctx is progress_output.clock_ctx. */
typedef double (*progress_clock_fn)(void *ctx);

/* Where and how one task reports; progress_begin uses all defaults. */
typedef struct progress_output {
    FILE *stream;             /* NULL: stderr */
    enum progress_style style;
    progress_clock_fn clock;  /* NULL: CLOCK_MONOTONIC (tests inject a fake one) */
    void *clock_ctx;          /* passed to clock */
    bool quiet;               /* this task prints nothing */
} progress_output;

typedef struct progress {
    /* shared by the updating threads */
    _Atomic uint64_t done;     /* units done so far; only grows */
    _Atomic uint64_t check_at; /* an update that brings done to this reads the clock (0: the first does) */
    atomic_bool busy;          /* held by the one thread formatting and writing */
    /* set by progress_begin, read-only until progress_end */
    bool on;                   /* begun and not quiet: updates may print */
    bool bar;                  /* a '\r' bar, else whole lines */
    int columns;               /* the bar's terminal width */
    FILE *stream;
    progress_clock_fn clock;
    void *clock_ctx;
    uint64_t total;            /* 0: unknown */
    uint64_t step;             /* check_at advances by this: ~0.1 % of the total, at least 1 */
    double start_s;            /* clock at progress_begin */
    char what[PROGRESS_WHAT_BYTES];
    char unit[PROGRESS_UNIT_BYTES];
    /* written only by the thread holding busy */
    double shown_s;            /* clock when something was last written (start_s before) */
    uint64_t shown_done;       /* the largest done written: what is shown never goes back */
    int shown_decile;          /* lines: the last 10 % step written (-1: none) */
    bool have_base;            /* the first update has been seen: base_s and base_done hold */
    double base_s;             /* clock at the first update: the rate is measured from here */
    uint64_t base_done;        /* done at the first update */
    bool shown;                /* something was written: progress_end must close it */
} progress;

/* Start reporting `what` ("loading dragon.ply") of `total` units (0:
 * unknown) of `unit` ("B" is scaled as kB, MB, GB; any other unit gets k, M,
 * G prefixes: "12.3 M tri/s"). p may be reused after progress_end. */
void progress_begin(progress *p, const char *what, uint64_t total, const char *unit);
/* The same, with `out` (NULL: the defaults) choosing stream, style, clock, quiet. */
void progress_begin_output(progress *p, const char *what, uint64_t total, const char *unit,
                           const progress_output *out);
/* n more units done. */
void progress_add(progress *p, uint64_t n);
/* `done` units done in all (a smaller value than before is ignored). */
void progress_set(progress *p, uint64_t done);
/* The task is over (finished or given up): a task that has shown something
 * gets its summary line, or "stopped at 40% (...)" when done < total; a
 * short one stays silent. The reporter is silent afterwards. */
void progress_end(progress *p);

/* Silence every reporter of the process from their next progress_begin (true,
 * as a process starts), or let them speak (false). */
void progress_set_quiet(bool quiet);

/* ---- the arithmetic, exposed for tests ---------------------------------- */

/* done / elapsed_s units a second; 0 when elapsed_s is not positive. */
double progress_rate(uint64_t done, double elapsed_s);
/* Seconds left for total - done units at `rate` units a second; < 0 when
 * unknown (no total, no positive rate). 0 once done >= total. */
double progress_seconds_left(uint64_t done, uint64_t total, double rate);
/* Whole percent done, 0..100 (100 only when done >= total); 0 for total 0.
 * Exact while done * 100 fits in 64 bits, in doubles beyond. */
int progress_percent(uint64_t done, uint64_t total);
/* `value` units of `unit` in at most 3 significant figures with a prefix:
 * "870 MB", "12.3 M tri", "512 B". Returns buf. */
char *progress_format_amount(char *buf, size_t size, double value, const char *unit);
/* A duration: "1.3 s", "42 s", "2 min 05 s", "1 h 02 min". Returns buf. */
char *progress_format_seconds(char *buf, size_t size, double seconds);

#endif
