/* test_progress.c - the progress reporter (engine/base/progress.h): the exact
 * text of lines, bar and summary; the rate, time-left and percentage
 * arithmetic; silence for short tasks, when quiet and under TESSERA_LOG=warn;
 * an unknown (0) total; percentages that never go back while several threads
 * add at once; and the hooks: a BVH is the same bytes whether the reporter
 * counts or is silenced, and the PLY reader reports the bytes it read. Every
 * test drives a fake clock, so none depends on the speed of the machine, and
 * none sleeps. */
#include <criterion/criterion.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/accel/bvh.h"
#include "engine/load/ply_read.h"
#include "engine/base/progress.h"

/* A clock the test sets by hand. */
typedef struct fake_clock {
    double now_s;
} fake_clock;

static double read_fake_clock(void *ctx) { return ((fake_clock *)ctx)->now_s; }

/* A reporter's output captured in memory. */
typedef struct capture {
    FILE *stream;
    char *text; /* valid after capture_text */
    size_t length;
} capture;

static void capture_open(capture *c)
{
    *c = (capture){0};
    c->stream = open_memstream(&c->text, &c->length);
    cr_assert(c->stream);
    unsetenv("TESSERA_LOG"); /* this test's own process: progress is info, shown by default */
}

static const char *capture_text(capture *c)
{
    fflush(c->stream);
    return c->text ? c->text : "";
}

static void capture_close(capture *c)
{
    fclose(c->stream);
    free(c->text);
}

static void begin_fake(progress *p, capture *c, fake_clock *clock, enum progress_style style, const char *what,
                       uint64_t total, const char *unit)
{
    progress_set_quiet(false); /* a process starts quiet (tessera's main speaks) */
    progress_output out = {.stream = c->stream, .style = style, .clock = read_fake_clock, .clock_ctx = clock};
    progress_begin_output(p, what, total, unit, &out);
}

Test(progress, lines_at_ten_percent_steps_then_a_summary)
{
    capture c;
    capture_open(&c);
    fake_clock clock = {0.0};
    progress p;
    begin_fake(&p, &c, &clock, PROGRESS_STYLE_LINES, "loading dragon.ply", 870000000u, "B");
    progress_set(&p, 0u); /* the first update: the rate counts from here */
    clock.now_s = 0.5;
    progress_set(&p, 100000000u); /* inside the silent second */
    cr_expect_str_eq(capture_text(&c), "");
    clock.now_s = 1.0;
    progress_set(&p, 348000000u);
    cr_expect_str_eq(capture_text(&c), "tessera: loading dragon.ply: 40% (348 MB of 870 MB, 348 MB/s, 1.5 s left)\n");
    clock.now_s = 2.5;
    progress_set(&p, 400000000u); /* still the 40 % step: no line */
    progress_set(&p, 435000000u); /* 50 % */
    clock.now_s = 3.0;
    progress_set(&p, 870000000u); /* 100 %: the summary says it */
    progress_end(&p);
    cr_expect_str_eq(capture_text(&c),
                     "tessera: loading dragon.ply: 40% (348 MB of 870 MB, 348 MB/s, 1.5 s left)\n"
                     "tessera: loading dragon.ply: 50% (435 MB of 870 MB, 174 MB/s, 2.5 s left)\n"
                     "tessera: loading dragon.ply: 870 MB in 3.0 s (290 MB/s)\n");
    capture_close(&c);
}

Test(progress, lines_keep_a_gap_and_speak_when_stalled)
{
    capture c;
    capture_open(&c);
    fake_clock clock = {0.0};
    progress p;
    begin_fake(&p, &c, &clock, PROGRESS_STYLE_LINES, "building BVH", 1000000u, "prim");
    progress_add(&p, 0u);
    clock.now_s = 1.0;
    progress_add(&p, 100000u); /* 10 %: the first line */
    clock.now_s = 1.5;
    progress_add(&p, 100000u); /* 20 %, but only 0.5 s after the last line */
    clock.now_s = 11.0;
    progress_add(&p, 1000u); /* 20.1 %: a new step since the last line, 10 s later */
    clock.now_s = 21.5;
    progress_add(&p, 1000u); /* the same step, but 10.5 s without a line */
    cr_expect_str_eq(capture_text(&c),
                     "tessera: building BVH: 10% (100 k prim of 1.0 M prim, 100 k prim/s, 9.0 s left)\n"
                     "tessera: building BVH: 20% (201 k prim of 1.0 M prim, 18.3 k prim/s, 44 s left)\n"
                     "tessera: building BVH: 20% (202 k prim of 1.0 M prim, 9.4 k prim/s, 1 min 25 s left)\n");
    clock.now_s = 22.0;
    progress_end(&p); /* given up short of the total */
    cr_expect(strstr(capture_text(&c), "tessera: building BVH: stopped at 20% (202 k prim of 1.0 M prim) after 22 s\n"),
              "%s", capture_text(&c));
    capture_close(&c);
}

Test(progress, bar_redrawn_in_place_then_replaced_by_the_summary)
{
    capture c;
    capture_open(&c);
    fake_clock clock = {0.0};
    progress p;
    begin_fake(&p, &c, &clock, PROGRESS_STYLE_BAR, "loading dragon.ply", 870000000u, "B");
    progress_set(&p, 0u);
    clock.now_s = 1.0;
    progress_set(&p, 348000000u);
    const char *first = "\rtessera: loading dragon.ply  40% [########------------] 348 MB/s, 1.5 s left\033[K";
    cr_expect_str_eq(capture_text(&c), first);
    clock.now_s = 1.05;
    progress_set(&p, 400000000u); /* within 0.1 s of the last draw */
    cr_expect_str_eq(capture_text(&c), first);
    clock.now_s = 3.0;
    progress_set(&p, 870000000u);
    progress_end(&p);
    char expected[512];
    snprintf(expected, sizeof expected,
             "%s\rtessera: loading dragon.ply 100%% [####################] 290 MB/s, 0.0 s left\033[K"
             "\rtessera: loading dragon.ply: 870 MB in 3.0 s (290 MB/s)\033[K\n",
             first);
    cr_expect_str_eq(capture_text(&c), expected);
    capture_close(&c);
}

Test(progress, bar_fits_the_line_with_a_long_name)
{
    capture c;
    capture_open(&c);
    fake_clock clock = {0.0};
    progress p;
    char what[PROGRESS_WHAT_BYTES];
    memset(what, 'x', sizeof what - 1);
    what[sizeof what - 1] = '\0';
    begin_fake(&p, &c, &clock, PROGRESS_STYLE_BAR, what, 1000u, "B");
    progress_set(&p, 0u);
    clock.now_s = 2.0;
    progress_set(&p, 500u);
    const char *text = capture_text(&c);
    cr_assert(text[0] == '\r');
    const char *escape = strstr(text, "\033[K");
    cr_assert(escape);
    /* a stream that is no terminal counts as 80 columns: at most 79 shown */
    cr_expect_leq(escape - (text + 1), 79, "%s", text + 1);
    cr_expect(strstr(text, "...  50% ["), "%s", text + 1);
    capture_close(&c);
}

Test(progress, short_task_prints_nothing)
{
    for (int style = PROGRESS_STYLE_BAR; style <= PROGRESS_STYLE_LINES; style++) {
        capture c;
        capture_open(&c);
        fake_clock clock = {0.0};
        progress p;
        begin_fake(&p, &c, &clock, (enum progress_style)style, "loading cube.ply", 1000u, "B");
        for (int i = 1; i <= 10; i++) {
            clock.now_s = 0.09 * i; /* the whole task within 0.9 s */
            progress_add(&p, 100u);
        }
        progress_end(&p);
        cr_expect_str_eq(capture_text(&c), "", "style %d", style);
        capture_close(&c);
    }
}

/* A long task that would report on every update, with `out` quiet or not. */
static const char *long_task(capture *c, bool quiet)
{
    fake_clock clock = {0.0};
    progress p;
    progress_output out = {.stream = c->stream, .style = PROGRESS_STYLE_LINES, .clock = read_fake_clock,
                           .clock_ctx = &clock, .quiet = quiet};
    progress_begin_output(&p, "loading lucy.ply", 100u, "B", &out);
    for (int i = 1; i <= 100; i++) {
        clock.now_s = 2.0 * i;
        progress_add(&p, 1u);
    }
    progress_end(&p);
    return capture_text(c);
}

Test(progress, quiet_prints_nothing)
{
    capture c;
    capture_open(&c);
    cr_expect_str_eq(long_task(&c, false), "", "a process starts quiet");
    capture_close(&c);

    progress_set_quiet(false);
    capture_open(&c);
    cr_expect_str_neq(long_task(&c, false), ""); /* the task does speak when not quiet */
    capture_close(&c);

    capture_open(&c);
    cr_expect_str_eq(long_task(&c, true), "", "quiet for this task");
    capture_close(&c);

    capture_open(&c);
    progress_set_quiet(true);
    cr_expect_str_eq(long_task(&c, false), "", "quiet for the process");
    progress_set_quiet(false);
    capture_close(&c);

    capture_open(&c);
    setenv("TESSERA_LOG", "warn", 1);
    cr_expect_str_eq(long_task(&c, false), "", "TESSERA_LOG=warn");
    capture_close(&c);
}

Test(progress, null_and_never_begun_do_nothing)
{
    progress_begin(NULL, "x", 10, "B");
    progress_add(NULL, 1);
    progress_set(NULL, 1);
    progress_end(NULL);
    progress p = {0};
    progress_add(&p, 5);
    progress_set(&p, 7);
    progress_end(&p);
    cr_expect_eq(atomic_load(&p.done), 0);
}

Test(progress, zero_total_reports_amount_and_rate_only)
{
    cr_expect_eq(progress_percent(5, 0), 0);
    cr_expect_lt(progress_seconds_left(5, 0, 1.0), 0.0);
    for (int style = PROGRESS_STYLE_BAR; style <= PROGRESS_STYLE_LINES; style++) {
        capture c;
        capture_open(&c);
        fake_clock clock = {0.0};
        progress p;
        begin_fake(&p, &c, &clock, (enum progress_style)style, "reading stream", 0u, "B");
        progress_add(&p, 0u); /* nothing done at time 0 */
        clock.now_s = 10.0;
        progress_add(&p, 5000000u);
        clock.now_s = 20.0;
        progress_add(&p, 5000000u);
        progress_end(&p);
        const char *expected = style == PROGRESS_STYLE_LINES
                                   ? "tessera: reading stream: 5.0 MB (500 kB/s)\n"
                                     "tessera: reading stream: 10.0 MB (500 kB/s)\n"
                                     "tessera: reading stream: 10.0 MB in 20 s (500 kB/s)\n"
                                   : "\rtessera: reading stream 5.0 MB, 500 kB/s\033[K"
                                     "\rtessera: reading stream 10.0 MB, 500 kB/s\033[K"
                                     "\rtessera: reading stream: 10.0 MB in 20 s (500 kB/s)\033[K\n";
        cr_expect_str_eq(capture_text(&c), expected, "style %d", style);
        capture_close(&c);
    }
}

Test(progress, rate_time_left_and_percent)
{
    cr_expect_float_eq(progress_rate(100, 2.0), 50.0, 1e-12);
    cr_expect_eq(progress_rate(100, 0.0), 0.0);
    cr_expect_eq(progress_rate(100, -1.0), 0.0);
    /* 250 of 1000 done: 750 more at 250 a second */
    cr_expect_float_eq(progress_seconds_left(250, 1000, 250.0), 3.0, 1e-12);
    cr_expect_lt(progress_seconds_left(250, 1000, 0.0), 0.0); /* no rate yet */
    cr_expect_lt(progress_seconds_left(250, 0, 100.0), 0.0);  /* no total */
    cr_expect_eq(progress_seconds_left(1000, 1000, 0.0), 0.0);
    cr_expect_eq(progress_seconds_left(2000, 1000, 4.0), 0.0); /* more than announced */
    cr_expect_eq(progress_percent(0, 1000), 0);
    cr_expect_eq(progress_percent(999, 1000), 99);
    cr_expect_eq(progress_percent(1000, 1000), 100);
    cr_expect_eq(progress_percent(5000, 1000), 100);
    cr_expect_eq(progress_percent(UINT64_MAX - 1, UINT64_MAX), 99); /* never 100 early, no overflow */
    cr_expect_eq(progress_percent(UINT64_MAX / 100 * 49, UINT64_MAX), 49); /* in doubles there */
    cr_expect_eq(progress_percent(UINT64_MAX / 100 * 51, UINT64_MAX), 51);
}

Test(progress, amounts_and_durations)
{
    char b[64];
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 870e6, "B"), "870 MB");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 512, "B"), "512 B");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 999.7e3, "B"), "1.0 MB");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 1.3e9, "B"), "1.3 GB");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 12.34e6, "tri"), "12.3 M tri");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 37, "tri"), "37 tri");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 2.5, "tri"), "2.5 tri");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, 4.2e3, ""), "4.2 k");
    cr_expect_str_eq(progress_format_amount(b, sizeof b, -1.0, "B"), "? B");
    cr_expect_str_eq(progress_format_seconds(b, sizeof b, 1.34), "1.3 s");
    cr_expect_str_eq(progress_format_seconds(b, sizeof b, 42.2), "42 s");
    cr_expect_str_eq(progress_format_seconds(b, sizeof b, 125.0), "2 min 05 s");
    cr_expect_str_eq(progress_format_seconds(b, sizeof b, 3720.0), "1 h 02 min");
    cr_expect_str_eq(progress_format_seconds(b, sizeof b, -1.0), "?");
}

/* ---- several threads ------------------------------------------------------ */

#define ADDERS 4
#define ADDS_EACH 100000

/* A clock that moves 50 ms every time it is read, from any thread. */
static atomic_uint clock_reads;
static double ticking_clock(void *ctx)
{
    (void)ctx;
    return 0.05 * (double)atomic_fetch_add(&clock_reads, 1u);
}

static void *add_ones(void *arg)
{
    progress *p = arg;
    for (int i = 0; i < ADDS_EACH; i++)
        progress_add(p, 1u);
    return NULL;
}

/* Run ADDERS threads of ADDS_EACH progress_add(1) with `style`, reporting into c. */
static void run_adders(enum progress_style style, capture *c)
{
    progress_set_quiet(false);
    atomic_store(&clock_reads, 0u);
    progress p;
    progress_output out = {.stream = c->stream, .style = style, .clock = ticking_clock};
    progress_begin_output(&p, "building BVH", (uint64_t)ADDERS * ADDS_EACH, "prim", &out);
    pthread_t threads[ADDERS];
    for (int t = 0; t < ADDERS; t++)
        cr_assert_eq(pthread_create(&threads[t], NULL, add_ones, &p), 0);
    for (int t = 0; t < ADDERS; t++)
        pthread_join(threads[t], NULL);
    cr_expect_eq(atomic_load(&p.done), (uint64_t)ADDERS * ADDS_EACH);
    progress_end(&p);
}

/* The percentages of every report in `text`, in order (reports start with
 * "tessera: building BVH" and give "NN%"); returns how many. */
static int percentages(const char *text, int *out, int max)
{
    int n = 0;
    for (const char *s = strstr(text, "tessera: building BVH"); s && n < max;
         s = strstr(s + 1, "tessera: building BVH")) {
        const char *pct = strchr(s, '%');
        const char *next = strstr(s + 1, "tessera: building BVH");
        if (!pct || (next && pct > next))
            continue; /* the summary has no percentage */
        const char *digits = pct;
        while (digits > s && digits[-1] >= '0' && digits[-1] <= '9')
            digits--;
        out[n++] = atoi(digits);
    }
    return n;
}

Test(progress, concurrent_adds_never_show_a_smaller_percentage)
{
    for (int style = PROGRESS_STYLE_BAR; style <= PROGRESS_STYLE_LINES; style++) {
        capture c;
        capture_open(&c);
        run_adders((enum progress_style)style, &c);
        const char *text = capture_text(&c);
        int pct[2000];
        int n = percentages(text, pct, 2000);
        cr_expect_gt(n, style == PROGRESS_STYLE_BAR ? 20 : 3, "style %d: only %d reports:\n%s", style, n, text);
        for (int i = 1; i < n; i++)
            cr_expect_geq(pct[i], pct[i - 1], "style %d: report %d shows %d%% after %d%%", style, i, pct[i],
                          pct[i - 1]);
        cr_expect(strstr(text, "tessera: building BVH: 400 k prim in "), "style %d: no summary:\n%s", style, text);
        capture_close(&c);
    }
}

/* ---- the BVH builder's hook ---------------------------------------------- */

/* n small boxes scattered by a fixed LCG (caller frees). */
static aabb *scattered_boxes(uint32_t n)
{
    aabb *boxes = malloc((size_t)n * sizeof *boxes);
    cr_assert(boxes);
    uint32_t state = 12345u;
    for (uint32_t i = 0; i < n; i++) {
        float c[3];
        for (int k = 0; k < 3; k++) {
            state = state * 1664525u + 1013904223u;
            c[k] = (float)(state >> 8) / (float)(1u << 24);
        }
        boxes[i] = (aabb){{c[0], c[1], c[2]}, {c[0] + 0.001f, c[1] + 0.002f, c[2] + 0.001f}};
    }
    return boxes;
}

/* The reporter counts what the build threads place, but the build never
 * reads it back: the tree is the same bytes with it counting or silenced. */
Test(progress, bvh_build_is_the_same_with_or_without_the_reporter)
{
    unsetenv("TESSERA_LOG");
    progress_set_quiet(false);
    const uint32_t n = 200000;
    aabb *boxes = scattered_boxes(n);
    bvh counted, silenced;
    tess_error err = {{0}};
    cr_assert(bvh_build(&counted, boxes, n, 2, &err), "%s", err.msg);
    progress_set_quiet(true);
    cr_assert(bvh_build(&silenced, boxes, n, 2, &err), "%s", err.msg);
    progress_set_quiet(false);
    cr_assert_eq(counted.node_count, silenced.node_count);
    cr_expect(!memcmp(counted.nodes, silenced.nodes, counted.node_count * sizeof *counted.nodes));
    cr_expect(!memcmp(counted.prim_order, silenced.prim_order, n * sizeof *counted.prim_order));
    bvh_finish(&counted);
    bvh_finish(&silenced);
    free(boxes);
}

/* ---- the PLY reader's hook ------------------------------------------------- */

/* The chunked reader tells its reporter the offset it has read up to: after
 * reading a whole file of several chunks, the file's size. */
Test(progress, ply_reader_reports_the_bytes_read)
{
    FILE *file = tmpfile();
    cr_assert(file);
    const size_t bytes = ((size_t)5 << 20) + 123; /* five 1 MiB chunks and a piece */
    for (size_t i = 0; i < bytes; i++)
        fputc((int)(i % 251), file);
    rewind(file);
    capture c;
    capture_open(&c);
    fake_clock clock = {0.0};
    progress p;
    begin_fake(&p, &c, &clock, PROGRESS_STYLE_LINES, "loading big.ply", bytes, "B");
    ply_reader r;
    cr_assert(ply_reader_init(&r, file, bytes));
    r.progress = &p;
    clock.now_s = 2.0;
    cr_expect_eq(ply_reader_skip(&r, bytes), bytes);
    cr_expect_eq(atomic_load(&p.done), bytes);
    clock.now_s = 4.0;
    progress_end(&p);
    cr_expect(strstr(capture_text(&c), "tessera: loading big.ply: 5.2 MB in 4.0 s (1.3 MB/s)\n"), "%s",
              capture_text(&c));
    ply_reader_finish(&r);
    fclose(file);
    capture_close(&c);
}

/* Time before the first update (the BVH build's top levels place no leaf)
 * does not count in the rate or the time left; the summary's rate is the
 * whole task's. Nothing is shown before the rate has 0.5 s behind it. */
Test(progress, rate_counts_from_the_first_update)
{
    capture c;
    capture_open(&c);
    fake_clock clock = {0.0};
    progress p;
    begin_fake(&p, &c, &clock, PROGRESS_STYLE_LINES, "building BVH", 1000000u, "prim");
    clock.now_s = 3.0; /* nothing counted for 3 s */
    progress_add(&p, 10000u);
    clock.now_s = 3.25;
    progress_add(&p, 90000u); /* 10 %, but the rate has only 0.25 s behind it */
    cr_expect_str_eq(capture_text(&c), "");
    clock.now_s = 4.0;
    progress_add(&p, 100000u); /* 20 %: 190 k in 1 s since the first update */
    cr_expect_str_eq(capture_text(&c),
                     "tessera: building BVH: 20% (200 k prim of 1.0 M prim, 190 k prim/s, 4.2 s left)\n");
    clock.now_s = 8.0;
    progress_add(&p, 800000u);
    progress_end(&p);
    cr_expect(strstr(capture_text(&c), "tessera: building BVH: 1.0 M prim in 8.0 s (125 k prim/s)\n"), "%s",
              capture_text(&c));
    capture_close(&c);
}
