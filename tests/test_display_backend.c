/* test_display_backend.c - the table of display backends (wall/display_backend.h):
 * every headless backend is made by its name and its display carries that
 * name; the device backends are refused one channel at a time; an unknown name's
 * error lists every name of the table; every device backend's lifecycle has what
 * the commands call.
 *
 * And a backend on a device defined here, in tests/ alone (a new backend in wall/
 * is its file and one row of display_backends[]): the commands' own path
 * (cli_pipeline_create on a --wall, the hooks as cmd_render.c and cluster_cli.c
 * set them, pipeline_run, cli_pipeline_release_outputs) starts it, attaches the
 * pipeline, calls its hooks, and destroys it after its displays, in that order;
 * on a wall of several machines it is started on this process's outputs only;
 * a start that fails leaves nothing to destroy. */
#include <criterion/criterion.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/frame/pipeline.h"
#include "support.h"
#include "app/cli.h"
#include "app/pipeline_cli.h"
#include "wall/display_backend.h"

Test(display_backend, every_headless_backend_made_by_name)
{
    char dir[] = "/tmp/tessera-backend-XXXXXX", pattern[128];
    cr_assert_not_null(mkdtemp(dir));
    snprintf(pattern, sizeof pattern, "%s/f_####.png", dir);
    int headless = 0;
    for (size_t i = 0; i < display_backend_count; i++) {
        const display_backend *b = &display_backends[i];
        cr_assert_eq(display_backend_by_name(b->name), b, "%s", b->name);
        tess_error err = {{0}};
        image_display *d = display_create(b->name, pattern, true, &err);
        if (b->needs & DISPLAY_NEEDS_DEVICE) {
            cr_assert_null(b->create, "%s", b->name);
            cr_assert_not_null(b->lifecycle, "%s", b->name);
            cr_assert_null(d, "%s", b->name);
            cr_assert(strstr(err.msg, "--wall"), "%s: %s", b->name, err.msg);
            continue;
        }
        cr_assert_not_null(d, "%s: %s", b->name, err.msg);
        cr_assert_str_eq(d->ops->name, b->name);
        image_display_destroy(d);
        headless++;
    }
    cr_assert_geq(headless, 4); /* null, convert, convert-tiles, dump */
    rmdir(dir);
}

Test(display_backend, options_and_needs)
{
    /* the backends that take --out are the ones that refuse to be made without it */
    for (size_t i = 0; i < display_backend_count; i++) {
        const display_backend *b = &display_backends[i];
        if (!b->create)
            continue;
        tess_error err = {{0}};
        image_display *d = display_create(b->name, NULL, false, &err);
        cr_assert_eq(d == NULL, (b->options & DISPLAY_OPTION_OUT) != 0, "%s: %s", b->name, err.msg);
        image_display_destroy(d);
    }
    cr_assert(display_backend_by_name("drm")->options & DISPLAY_OPTION_CARD);
    cr_assert(display_backend_by_name("dump")->needs & DISPLAY_NEEDS_OIIO);
    cr_assert_null(display_backend_by_name("drmm"));
}

Test(display_backend, unknown_name_lists_the_table)
{
    tess_error err = {{0}};
    cr_assert_null(display_create("bogus", NULL, false, &err));
    cr_assert(strstr(err.msg, "'bogus'"), "%s", err.msg);
    for (size_t i = 0; i < display_backend_count; i++)
        cr_assert(strstr(err.msg, display_backends[i].name), "%s lacks %s", err.msg, display_backends[i].name);
    char names[256];
    display_backend_names(DISPLAY_OPTION_OUT, " or ", names, sizeof names);
    cr_assert_str_eq(names, "dump");
    display_backend_names(0, ", ", names, sizeof names);
    cr_assert_str_eq(names, "null, convert, convert-tiles, dump, drm");
}

Test(display_backend, device_backends_have_a_whole_lifecycle)
{
    int devices = 0;
    for (size_t i = 0; i < display_backend_count; i++) {
        const display_backend *b = &display_backends[i];
        const display_lifecycle *l = b->lifecycle;
        cr_assert_eq(l != NULL, (b->needs & DISPLAY_NEEDS_DEVICE) != 0, "%s", b->name);
        cr_assert_eq(l != NULL, b->create == NULL, "%s: a device backend has no one-channel display", b->name);
        if (!l) {
            cr_assert(!(b->options & DISPLAY_OPTION_CARD), "%s: --card without a device", b->name);
            continue;
        }
        devices++;
        cr_assert(l->start && l->destroy, "%s", b->name);
        cr_assert(l->device_label && l->device_label[0], "%s", b->name);
        cr_assert(!l->print_outputs || (l->outputs_what && l->outputs_help), "%s", b->name);
        cr_assert(!l->device_present || l->kiosk_help, "%s", b->name);
        cr_assert(!(b->options & DISPLAY_OPTION_CARD) || l->card_help, "%s", b->name);
    }
    cr_assert_geq(devices, 1); /* drm */
    cr_assert_eq(display_backend_kiosk_kind(), display_backend_by_name("drm"));
    /* the generic calls take a NULL instance (no device) and do nothing */
    cr_assert_not(display_instance_set_pause_hook(NULL, NULL, NULL));
    cr_assert_not(display_instance_set_flip_hook(NULL, NULL, NULL));
    cr_assert_null(display_instance_seat(NULL));
    display_instance_attach(NULL, NULL, 0);
    display_instance_destroy(NULL);
    /* a headless backend is not started */
    wall_config w = {.count = 0};
    image_display *displays[WALL_MAX_OUTPUTS] = {NULL};
    tess_error err = {{0}};
    display_start_args a = {NULL};
    cr_assert_null(display_backend_start(display_backend_by_name("null"), &a, NULL, &w, displays, &err));
    cr_assert(strstr(err.msg, "headless"), "%s", err.msg);
}

/* ---------------------------------------------------------------- a backend of the tests' own */

#define EVENTS_MAX 64
#define EVENT_BYTES 96

/* What the test backend was asked to do, in order. Written on the main thread and, while
 * pipeline_run runs, only by its display thread (the hooks, show): read after it returns. */
typedef struct event_log {
    char events[EVENTS_MAX][EVENT_BYTES];
    int count;
    int overflowed;
} event_log;

static void note(event_log *log, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void note(event_log *log, const char *fmt, ...)
{
    if (log->count == EVENTS_MAX) {
        log->overflowed++;
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(log->events[log->count++], EVENT_BYTES, fmt, ap);
    va_end(ap);
}

/* The index of the first event starting with `prefix` at or after `from`, else -1. */
static int find_event(const event_log *log, const char *prefix, int from)
{
    for (int i = from < 0 ? 0 : from; i < log->count; i++)
        if (!strncmp(log->events[i], prefix, strlen(prefix)))
            return i;
    return -1;
}

static int count_events(const event_log *log, const char *prefix)
{
    int n = 0;
    for (int i = find_event(log, prefix, 0); i >= 0; i = find_event(log, prefix, i + 1))
        n++;
    return n;
}

/* The test backend's row, with the log beside it (the lifecycle's start gets the row). */
typedef struct test_backend {
    display_backend row; /* first: start's b is &row */
    event_log *log;
} test_backend;

typedef struct test_instance {
    display_instance base; /* first */
    event_log *log;
    int output_count;
    int live_displays;     /* made by start, not yet destroyed */
    display_pause_fn pause_fn;
    void *pause_ctx;
    display_flip_fn flip_fn;
    void *flip_ctx;
} test_instance;

typedef struct test_display {
    image_display base; /* first */
    test_instance *owner;
    int output;
    char name[WALL_LABEL_BYTES];
} test_display;

static bool test_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    test_display *td = (test_display *)d;
    test_instance *ti = td->owner;
    note(ti->log, "show %s frame %llu %dx%d", td->name, (unsigned long long)img->frame, img->width_px,
         img->height_px);
    if (ti->pause_fn && td->output == 0 && img->frame == 1) { /* the seat takes the device away, then back */
        ti->pause_fn(ti->pause_ctx, true);
        ti->pause_fn(ti->pause_ctx, false);
    }
    if (ti->flip_fn) /* on screen at once: vblank k at k ms */
        ti->flip_fn(ti->flip_ctx, img->frame, td->name, (unsigned)img->frame, (int64_t)img->frame * 1000);
    return true;
}

static void test_display_destroy(image_display *d)
{
    test_display *td = (test_display *)d;
    note(td->owner->log, "display destroyed %s", td->name);
    td->owner->live_displays--;
    free(td);
}

static const image_display_ops test_display_ops = {"test-device", test_show, test_display_destroy, NULL, NULL, NULL};

static void test_destroy(display_instance *d)
{
    test_instance *ti = (test_instance *)d;
    note(ti->log, "destroy (%d displays left)", ti->live_displays);
    free(ti);
}

static display_instance *test_start(const display_backend *b, const display_start_args *a, wall_config *w,
                                    image_display **displays, tess_error *err)
{
    const test_backend *tb = (const test_backend *)b;
    if (a->card_path && !strcmp(a->card_path, "refuse")) {
        note(tb->log, "start refused");
        tess_error_set(err, "test-device: %s: no such device", a->card_path);
        return NULL;
    }
    test_instance *ti = calloc(1, sizeof *ti);
    cr_assert_not_null(ti);
    ti->log = tb->log;
    ti->output_count = w->count;
    if (!wall_config_headless_sizes(w, err)) { /* the device's modes: the explicit ones */
        free(ti);
        return NULL;
    }
    note(tb->log, "start %d outputs card '%s'", w->count, a->card_path ? a->card_path : "(none)");
    for (int i = 0; i < w->count; i++) {
        test_display *td = calloc(1, sizeof *td);
        cr_assert_not_null(td);
        *td = (test_display){.base = {&test_display_ops}, .owner = ti, .output = i};
        wall_output_label(w, i, td->name, sizeof td->name);
        displays[i] = &td->base;
        ti->live_displays++;
    }
    return &ti->base;
}

static void test_attach(display_instance *d, struct pipeline *p, int first_channel)
{
    test_instance *ti = (test_instance *)d;
    note(ti->log, "attach channels %d..%d of %d", first_channel, first_channel + ti->output_count - 1,
         pipeline_channel_count(p));
}

static void test_set_pause_hook(display_instance *d, display_pause_fn fn, void *ctx)
{
    test_instance *ti = (test_instance *)d;
    note(ti->log, "pause hook set");
    ti->pause_fn = fn;
    ti->pause_ctx = ctx;
}

static void test_set_flip_hook(display_instance *d, display_flip_fn fn, void *ctx)
{
    test_instance *ti = (test_instance *)d;
    note(ti->log, "flip hook set");
    ti->flip_fn = fn;
    ti->flip_ctx = ctx;
}

static const display_lifecycle test_lifecycle = {
    .start = test_start,
    .attach = test_attach,
    .set_pause_hook = test_set_pause_hook,
    .set_flip_hook = test_set_flip_hook,
    .destroy = test_destroy,
    .device_label = "test",
    .card_help = "the test device (\"refuse\": start fails)",
};

static test_backend make_test_backend(event_log *log)
{
    return (test_backend){{"test-device", "a device of the tests' own", DISPLAY_OPTION_CARD, DISPLAY_NEEDS_DEVICE,
                           NULL, NULL, &test_lifecycle},
                          log};
}

/* What the hooks were told (as cmd_render.c's wall_paused and cluster_cli.c's note_flip are). */
static void on_pause(void *ctx, bool paused)
{
    note(ctx, "paused %s", paused ? "yes" : "no");
}

static void on_flip(void *ctx, uint64_t frame, const char *output, unsigned vblank_sequence,
                    int64_t vblank_monotonic_us)
{
    note(ctx, "flipped %s frame %llu vblank %u at %lld us", output, (unsigned long long)frame, vblank_sequence,
         (long long)vblank_monotonic_us);
}

/* A wall of two 64x48 outputs side by side (explicit modes), in dir; the second one's mode
 * is `second_mode`. */
static void write_wall(const char *dir, const char *second_mode, char *path, size_t path_bytes)
{
    snprintf(path, path_bytes, "%s/wall.json", dir);
    FILE *f = fopen(path, "w");
    cr_assert_not_null(f);
    fprintf(f, "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": [\n"
               " {\"connector\": \"Test-1\", \"mode\": \"64x48\", \"grid\": [0, 0], \"size_mm\": [160, 120],\n"
               "  \"bezel_mm\": {\"left\": 4, \"top\": 4, \"right\": 4, \"bottom\": 4}},\n"
               " {\"connector\": \"Test-2\", \"mode\": \"%s\", \"grid\": [1, 0], \"size_mm\": [160, 120],\n"
               "  \"bezel_mm\": {\"left\": 4, \"top\": 4, \"right\": 4, \"bottom\": 4}}]}\n",
            second_mode);
    cr_assert_eq(fclose(f), 0);
}

static void wall_spec(cli_pipeline_spec *s, const char *wall_file, const test_backend *tb, int frames)
{
    cli_pipeline_spec_default(s, "null", NULL);
    s->threads = 2;
    s->frames = frames;
    s->time_mode = PIPELINE_TIME_FIXED_RATE;
    snprintf(s->wall_file, sizeof s->wall_file, "%s", wall_file);
    s->wall_backend = &tb->row;
}

Test(display_backend, lifecycle_in_order_through_the_commands_path)
{
    char dir[128], wall_file[256];
    support_make_tmp_dir(dir, sizeof dir, "backend-life");
    write_wall(dir, "64x48", wall_file, sizeof wall_file);
    event_log log = {.count = 0};
    test_backend tb = make_test_backend(&log);
    cli_scene cs;
    cr_assert(cli_scene_prepare(NULL, 2, &cs));
    cli_pipeline_spec s;
    wall_spec(&s, wall_file, &tb, 3);
    snprintf(s.card_path, sizeof s.card_path, "/dev/test0");

    display_instance *outputs = NULL;
    pipeline *p = cli_pipeline_create(&s, &cs, &outputs);
    cr_assert_not_null(p);
    cr_assert_not_null(outputs, "a wall on a device: the started backend comes back");
    cr_assert_eq(outputs->backend, &tb.row);
    cr_assert_eq(pipeline_channel_count(p), 2);
    /* the hooks, as run_job (a service) and the cluster set them */
    cr_assert(display_instance_set_pause_hook(outputs, on_pause, &log));
    cr_assert(display_instance_set_flip_hook(outputs, on_flip, &log));
    cr_assert_null(display_instance_seat(outputs), "the test backend opens no seat");
    tess_error err = {{0}};
    cr_assert(pipeline_run(p, &err), "%s", err.msg);
    note(&log, "run returned");
    pipeline_destroy(p);
    cli_pipeline_release_outputs(outputs);
    cli_scene_finish(&cs);
    support_remove_tmp_dir(dir);

    for (int i = 0; i < log.count; i++)
        cr_log_info("event %d: %s", i, log.events[i]);
    cr_assert_eq(log.overflowed, 0);
    /* start (with --card, sizes resolved), attach, the hooks, frames, run over, displays, destroy */
    int start = find_event(&log, "start 2 outputs card '/dev/test0'", 0);
    int attach = find_event(&log, "attach channels 0..1 of 2", 0);
    int pause_set = find_event(&log, "pause hook set", 0);
    int flip_set = find_event(&log, "flip hook set", 0);
    int first_show = find_event(&log, "show ", 0);
    int ran = find_event(&log, "run returned", 0);
    int first_gone = find_event(&log, "display destroyed", 0);
    int destroy = find_event(&log, "destroy (0 displays left)", 0);
    cr_assert_eq(start, 0, "start first: %s", log.events[0]);
    cr_assert(start < attach && attach < pause_set && pause_set < flip_set && flip_set < first_show &&
                  first_show < ran && ran < first_gone && first_gone < destroy,
              "order: start %d attach %d pause %d flip %d show %d ran %d displays %d destroy %d", start, attach,
              pause_set, flip_set, first_show, ran, first_gone, destroy);
    cr_assert_eq(destroy, log.count - 1, "destroy last");
    cr_assert_eq(count_events(&log, "display destroyed"), 2);
    cr_assert_eq(count_events(&log, "destroy ("), 1);
    /* every frame on every output, at the resolved size, each flip told */
    for (int f = 0; f < 3; f++)
        for (int o = 1; o <= 2; o++) {
            char shown[EVENT_BYTES], flipped[EVENT_BYTES];
            snprintf(shown, sizeof shown, "show Test-%d frame %d 64x48", o, f);
            snprintf(flipped, sizeof flipped, "flipped Test-%d frame %d vblank %d at %d us", o, f, f, f * 1000);
            int at = find_event(&log, shown, 0);
            cr_assert_geq(at, 0, "no '%s'", shown);
            cr_assert_eq(find_event(&log, flipped, at), at + 1 + (o == 1 && f == 1 ? 2 : 0), "'%s' after '%s'",
                         flipped, shown);
        }
    cr_assert_eq(count_events(&log, "show "), 6);
    int paused = find_event(&log, "paused yes", 0);
    cr_assert_gt(paused, find_event(&log, "show Test-1 frame 1", 0));
    cr_assert_eq(find_event(&log, "paused no", 0), paused + 1);
}

Test(display_backend, several_machines_start_this_process_outputs)
{
    char dir[128], wall_file[256];
    support_make_tmp_dir(dir, sizeof dir, "backend-part");
    event_log log = {.count = 0};
    test_backend tb = make_test_backend(&log);
    display_start_args a = {"/dev/test0"};
    const bool mine[WALL_MAX_OUTPUTS] = {true, false};

    /* the other machine's output has its mode in the file: its size is known here too */
    write_wall(dir, "64x48", wall_file, sizeof wall_file);
    wall_config w;
    tess_error err = {{0}};
    cr_assert(wall_config_load(wall_file, &w, &err), "%s", err.msg);
    image_display *displays[WALL_MAX_OUTPUTS] = {NULL};
    display_instance *d = display_backend_start(&tb.row, &a, mine, &w, displays, &err);
    cr_assert_not_null(d, "%s", err.msg);
    cr_assert_str_eq(log.events[0], "start 1 outputs card '/dev/test0'");
    cr_assert_not_null(displays[0]);
    cr_assert_null(displays[1], "another machine's output has no display here");
    cr_assert(w.outputs[1].width_px == 64 && w.outputs[1].height_px == 48, "%dx%d", w.outputs[1].width_px,
              w.outputs[1].height_px);
    image_display_destroy(displays[0]);
    display_instance_destroy(d);
    cr_assert_str_eq(log.events[log.count - 1], "destroy (0 displays left)");

    /* ... without it, this machine cannot know the picture's size: refused before any start */
    log.count = 0;
    write_wall(dir, "preferred", wall_file, sizeof wall_file);
    cr_assert(wall_config_load(wall_file, &w, &err), "%s", err.msg);
    cr_assert_null(display_backend_start(&tb.row, &a, mine, &w, displays, &err));
    cr_assert(strstr(err.msg, "outputs[1]") && strstr(err.msg, "another machine's"), "%s", err.msg);
    cr_assert_eq(log.count, 0, "not started: %s", log.events[0]);
    support_remove_tmp_dir(dir);
}

Test(display_backend, failed_start_leaves_nothing_to_destroy)
{
    char dir[128], wall_file[256];
    support_make_tmp_dir(dir, sizeof dir, "backend-fail");
    write_wall(dir, "64x48", wall_file, sizeof wall_file);
    event_log log = {.count = 0};
    test_backend tb = make_test_backend(&log);
    cli_scene cs;
    cr_assert(cli_scene_prepare(NULL, 2, &cs));
    cli_pipeline_spec s;
    wall_spec(&s, wall_file, &tb, 1);
    snprintf(s.card_path, sizeof s.card_path, "refuse");
    display_instance *outputs = (display_instance *)&log; /* overwritten */
    cr_assert_null(cli_pipeline_create(&s, &cs, &outputs));
    cr_assert_null(outputs);
    cli_pipeline_release_outputs(outputs);
    cli_scene_finish(&cs);
    support_remove_tmp_dir(dir);
    cr_assert_eq(log.count, 1);
    cr_assert_str_eq(log.events[0], "start refused");
}
