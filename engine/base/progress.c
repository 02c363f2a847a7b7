/* progress.c - the progress reporter (progress.h): counting, deciding when a
 * report is due, and formatting the bar, the lines and the summary. */
#include "progress.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include "clock.h"
#include "log.h"

/* cells of the terminal bar between its brackets */
#define BAR_CELLS 20
/* columns assumed when the terminal does not say */
#define DEFAULT_COLUMNS 80
/* `what` is never cut shorter than this to fit the bar on the line */
#define WHAT_MIN_CHARS 12
/* one report, escapes included */
#define REPORT_BYTES 320
/* "1.3 s", "870 MB", "12.3 M prim" with room to spare */
#define FIELD_BYTES 48

/* progress_set_quiet: read by every progress_begin; a process starts quiet */
static atomic_bool all_quiet = true;

void progress_set_quiet(bool quiet) { atomic_store_explicit(&all_quiet, quiet, memory_order_relaxed); }

/* ---- arithmetic ------------------------------------------------------------ */

double progress_rate(uint64_t done, double elapsed_s)
{
    return elapsed_s > 0.0 ? (double)done / elapsed_s : 0.0;
}

double progress_seconds_left(uint64_t done, uint64_t total, double rate)
{
    if (total == 0)
        return -1.0;
    if (done >= total)
        return 0.0;
    return rate > 0.0 && isfinite(rate) ? (double)(total - done) / rate : -1.0;
}

int progress_percent(uint64_t done, uint64_t total)
{
    if (total == 0)
        return 0;
    if (done >= total)
        return 100;
    /* exact in integers while done * 100 fits; 99 at most until done reaches total */
    uint64_t pct = done <= UINT64_MAX / 100 ? done * 100 / total : (uint64_t)((double)done / (double)total * 100.0);
    return pct > 99 ? 99 : (int)pct;
}

char *progress_format_amount(char *buf, size_t size, double value, const char *unit)
{
    static const char *const byte_units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
    static const char *const prefixes[] = {"", "k", "M", "G", "T", "P", "E"};
    const int last = (int)(sizeof prefixes / sizeof prefixes[0]) - 1;
    if (!unit)
        unit = "";
    if (!isfinite(value) || value < 0.0) {
        snprintf(buf, size, "? %s", unit);
        return buf;
    }
    bool bytes = strcmp(unit, "B") == 0;
    int k = 0;
    double v = value;
    /* 999.5 would print as "1000": it is 1.00 of the next prefix */
    while (v >= 999.5 && k < last) {
        v /= 1000.0;
        k++;
    }
    /* whole units unscaled print as integers ("512 B", "37 tri"); otherwise
     * three significant figures, give or take: "1.3", "12.3", "870" */
    int decimals = (k == 0 && v == floor(v)) || v >= 99.95 ? 0 : 1;
    if (bytes)
        snprintf(buf, size, "%.*f %s", decimals, v, byte_units[k]);
    else if (unit[0])
        snprintf(buf, size, "%.*f %s%s%s", decimals, v, prefixes[k], k ? " " : "", unit);
    else
        snprintf(buf, size, "%.*f%s%s", decimals, v, k ? " " : "", prefixes[k]);
    return buf;
}

char *progress_format_seconds(char *buf, size_t size, double seconds)
{
    if (!isfinite(seconds) || seconds < 0.0)
        snprintf(buf, size, "?");
    else if (seconds < 9.95)
        snprintf(buf, size, "%.1f s", seconds);
    else if (seconds < 59.5)
        snprintf(buf, size, "%.0f s", seconds);
    else if (seconds < 3599.5) {
        long s = lround(seconds);
        snprintf(buf, size, "%ld min %02ld s", s / 60, s % 60);
    } else {
        long min = lround(seconds / 60.0);
        snprintf(buf, size, "%ld h %02ld min", min / 60, min % 60);
    }
    return buf;
}

/* ---- begin and end ------------------------------------------------------------ */

static double monotonic_clock(void *ctx)
{
    (void)ctx;
    return clock_monotonic_s();
}

/* A terminal that understands '\r' and "erase to the end of the line". */
static bool is_terminal(FILE *stream)
{
    int fd = fileno(stream);
    if (fd < 0 || !isatty(fd))
        return false;
    const char *term = getenv("TERM");
    return !(term && strcmp(term, "dumb") == 0);
}

static int terminal_columns(FILE *stream)
{
    struct winsize ws;
    int fd = fileno(stream);
    if (fd >= 0 && ioctl(fd, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0)
        return ws.ws_col;
    return DEFAULT_COLUMNS;
}

void progress_begin(progress *p, const char *what, uint64_t total, const char *unit)
{
    progress_begin_output(p, what, total, unit, NULL);
}

void progress_begin_output(progress *p, const char *what, uint64_t total, const char *unit,
                           const progress_output *out)
{
    if (!p)
        return;
    progress_output o = out ? *out : (progress_output){0};
    p->on = !o.quiet && !atomic_load_explicit(&all_quiet, memory_order_relaxed) && log_enabled(LOG_INFO);
    p->stream = o.stream ? o.stream : stderr;
    p->bar = o.style == PROGRESS_STYLE_BAR || (o.style == PROGRESS_STYLE_AUTO && p->on && is_terminal(p->stream));
    p->columns = p->bar ? terminal_columns(p->stream) : DEFAULT_COLUMNS;
    p->clock = o.clock ? o.clock : monotonic_clock;
    p->clock_ctx = o.clock ? o.clock_ctx : NULL;
    p->total = total;
    p->step = total / 1000 > 0 ? total / 1000 : 1;
    snprintf(p->what, sizeof p->what, "%s", what ? what : "");
    snprintf(p->unit, sizeof p->unit, "%s", unit ? unit : "");
    atomic_store_explicit(&p->done, 0, memory_order_relaxed);
    atomic_store_explicit(&p->check_at, 0, memory_order_relaxed); /* the first update sets the base */
    atomic_store_explicit(&p->busy, false, memory_order_relaxed);
    p->start_s = p->shown_s = p->on ? p->clock(p->clock_ctx) : 0.0;
    p->shown_done = 0;
    p->shown_decile = -1;
    p->shown = false;
    p->have_base = false;
    p->base_s = p->start_s;
    p->base_done = 0;
}

/* ---- reports ------------------------------------------------------------------ */

/* Write one report; a failure is ignored (progress is never worth an error). */
static void emit(progress *p, const char *text, int length, size_t capacity)
{
    if (length <= 0)
        return;
    size_t n = (size_t)length < capacity ? (size_t)length : capacity - 1;
    fwrite(text, 1, n, p->stream);
    fflush(p->stream);
    p->shown = true;
}

/* ", 1.3 s left", or "" when unknown */
static void format_left(char *buf, size_t size, double left_s)
{
    char t[FIELD_BYTES];
    if (left_s < 0.0)
        buf[0] = '\0';
    else
        snprintf(buf, size, ", %s left", progress_format_seconds(t, sizeof t, left_s));
}

/* Units a second since the first update. */
static double current_rate(const progress *p, uint64_t done, double now)
{
    return progress_rate(done - p->base_done, now - p->base_s);
}

/* The bar: "\rtessera: WHAT  40% [########------------] 410 MB/s, 1.3 s left\033[K",
 * WHAT cut so the line fits the terminal. Without a total: amount and rate. */
static void show_bar(progress *p, uint64_t done, double now)
{
    char amount[FIELD_BYTES], rate[FIELD_BYTES], left[FIELD_BYTES], tail[160];
    double per_s = current_rate(p, done, now);
    progress_format_amount(rate, sizeof rate, per_s, p->unit);
    if (p->total > 0) {
        int pct = progress_percent(done, p->total);
        char cells[BAR_CELLS + 1];
        int full = pct * BAR_CELLS / 100;
        for (int i = 0; i < BAR_CELLS; i++)
            cells[i] = i < full ? '#' : '-';
        cells[BAR_CELLS] = '\0';
        format_left(left, sizeof left, progress_seconds_left(done, p->total, per_s));
        snprintf(tail, sizeof tail, " %3d%% [%s] %s/s%s", pct, cells, rate, left);
    } else {
        snprintf(tail, sizeof tail, " %s, %s/s", progress_format_amount(amount, sizeof amount, (double)done, p->unit),
                 rate);
    }
    /* the line must not wrap, or '\r' would not return to its start */
    int room = p->columns - 1 - (int)strlen("tessera: ") - (int)strlen(tail);
    int what_len = (int)strlen(p->what);
    if (room < WHAT_MIN_CHARS)
        room = WHAT_MIN_CHARS;
    char text[REPORT_BYTES];
    int n;
    if (what_len <= room)
        n = snprintf(text, sizeof text, "\rtessera: %s%s\033[K", p->what, tail);
    else
        n = snprintf(text, sizeof text, "\rtessera: %.*s...%s\033[K", room - 3, p->what, tail);
    emit(p, text, n, sizeof text);
}

/* A line: "tessera: WHAT: 40% (348 MB of 870 MB, 410 MB/s, 1.3 s left)". */
static void show_line(progress *p, uint64_t done, double now)
{
    char amount[FIELD_BYTES], total[FIELD_BYTES], rate[FIELD_BYTES], left[FIELD_BYTES], text[REPORT_BYTES];
    double per_s = current_rate(p, done, now);
    progress_format_amount(amount, sizeof amount, (double)done, p->unit);
    progress_format_amount(rate, sizeof rate, per_s, p->unit);
    int n;
    if (p->total > 0) {
        format_left(left, sizeof left, progress_seconds_left(done, p->total, per_s));
        n = snprintf(text, sizeof text, "tessera: %s: %d%% (%s of %s, %s/s%s)\n", p->what,
                     progress_percent(done, p->total), amount,
                     progress_format_amount(total, sizeof total, (double)p->total, p->unit), rate, left);
    } else {
        n = snprintf(text, sizeof text, "tessera: %s: %s (%s/s)\n", p->what, amount, rate);
    }
    emit(p, text, n, sizeof text);
}

/* Is a report due at `now`? Only after PROGRESS_SILENT_S, with a rate
 * measured over PROGRESS_RATE_MIN_S; a bar every
 * PROGRESS_BAR_PERIOD_S; a line at a new 10 % step (not 100 %: the summary
 * says that) after PROGRESS_LINE_GAP_S, or after PROGRESS_LINE_STALL_S anyway. */
static bool report_due(const progress *p, uint64_t done, double now)
{
    if (now - p->start_s < PROGRESS_SILENT_S || now - p->base_s < PROGRESS_RATE_MIN_S)
        return false;
    double since = now - p->shown_s;
    if (p->bar)
        return !p->shown || since >= PROGRESS_BAR_PERIOD_S;
    if (p->total > 0 && done >= p->total)
        return false;
    int decile = p->total > 0 ? progress_percent(done, p->total) / 10 : -1;
    return (decile > p->shown_decile && (!p->shown || since >= PROGRESS_LINE_GAP_S)) ||
           since >= PROGRESS_LINE_STALL_S;
}

/* Called by an update whose `done` reached check_at: the thread that takes
 * `busy` reads the clock and maybe reports; any other returns at once. */
static void poll(progress *p)
{
    if (atomic_exchange_explicit(&p->busy, true, memory_order_acquire))
        return;
    /* read under busy: at least what the previous holder read (one atomic's
     * values are seen in one order), so what is shown never goes back */
    uint64_t done = atomic_load_explicit(&p->done, memory_order_relaxed);
    if (done < p->shown_done)
        done = p->shown_done;
    uint64_t next = done > UINT64_MAX - p->step ? UINT64_MAX : done + p->step;
    atomic_store_explicit(&p->check_at, next, memory_order_relaxed);
    double now = p->clock(p->clock_ctx);
    if (!p->have_base) {
        p->have_base = true;
        p->base_s = now;
        p->base_done = done;
    }
    if (report_due(p, done, now)) {
        if (p->bar)
            show_bar(p, done, now);
        else
            show_line(p, done, now);
        p->shown_s = now;
        p->shown_done = done;
        if (p->total > 0)
            p->shown_decile = progress_percent(done, p->total) / 10;
    }
    atomic_store_explicit(&p->busy, false, memory_order_release);
}

void progress_add(progress *p, uint64_t n)
{
    if (!p || !p->on)
        return;
    uint64_t done = atomic_fetch_add_explicit(&p->done, n, memory_order_relaxed) + n;
    if (done >= atomic_load_explicit(&p->check_at, memory_order_relaxed))
        poll(p);
}

void progress_set(progress *p, uint64_t done)
{
    if (!p || !p->on)
        return;
    /* an atomic max: done only grows */
    uint64_t was = atomic_load_explicit(&p->done, memory_order_relaxed);
    while (was < done && !atomic_compare_exchange_weak_explicit(&p->done, &was, done, memory_order_relaxed,
                                                                memory_order_relaxed)) {
    }
    if (done >= atomic_load_explicit(&p->check_at, memory_order_relaxed))
        poll(p);
}

void progress_end(progress *p)
{
    if (!p || !p->on)
        return;
    /* by contract no update runs now; wait out one that broke it */
    while (atomic_exchange_explicit(&p->busy, true, memory_order_acquire)) {
    }
    uint64_t done = atomic_load_explicit(&p->done, memory_order_relaxed);
    double elapsed = p->clock(p->clock_ctx) - p->start_s;
    if (p->shown || elapsed >= PROGRESS_SILENT_S) {
        char amount[FIELD_BYTES], total[FIELD_BYTES], rate[FIELD_BYTES], time[FIELD_BYTES], text[REPORT_BYTES];
        progress_format_amount(amount, sizeof amount, (double)done, p->unit);
        progress_format_seconds(time, sizeof time, elapsed);
        const char *lead = p->bar ? "\r" : "", *trail = p->bar ? "\033[K\n" : "\n";
        int n;
        if (p->total == 0 || done >= p->total)
            n = snprintf(text, sizeof text, "%stessera: %s: %s in %s (%s/s)%s", lead, p->what, amount, time,
                         progress_format_amount(rate, sizeof rate, progress_rate(done, elapsed), p->unit), trail);
        else
            n = snprintf(text, sizeof text, "%stessera: %s: stopped at %d%% (%s of %s) after %s%s", lead, p->what,
                         progress_percent(done, p->total), amount,
                         progress_format_amount(total, sizeof total, (double)p->total, p->unit), time, trail);
        emit(p, text, n, sizeof text);
    }
    p->on = false;
    atomic_store_explicit(&p->busy, false, memory_order_release);
}
