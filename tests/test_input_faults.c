/* test_input_faults.c - input when things go wrong.
 *
 * Record files cut off mid-line (a kiosk killed or the power cut while it
 * recorded): the complete lines replay, the cut one is left out with a
 * warning naming the file and line (input/record.h, CUT OFF).
 *
 * The mapping layer (input/controller.h) fed what a broken or hostile device
 * can send: random events of every kind with
 * non-finite, huge, tiny and out-of-range values (coordinates, motions,
 * scales, wheel clicks, key codes, touch slots, device numbers, times going
 * backwards or leaping ahead), interleaved with ticks. It must never crash
 * (the ASan build checks every access) and never emit a camera, cursor or
 * status that is not finite and valid: a wall must never show a NaN camera. */
#define _GNU_SOURCE /* open_memstream, mkdtemp */
#include <criterion/criterion.h>
#include <fcntl.h>
#include <unistd.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/camera.h"
#include "input/controller.h"
#include "input/record.h"

typedef struct garbage_sink {
    long cameras, cursors, others;
    char problem[TESS_ERROR_MSG_BYTES + 128]; /* the first bad transaction, "" while all are fine */
    camera_desc shown;
} garbage_sink;

static void note_problem(garbage_sink *g, const char *what, const input_txn *t)
{
    if (g->problem[0])
        return;
    const camera_desc *c = &t->args.camera.camera;
    if (t->kind == TXN_CAMERA)
        snprintf(g->problem, sizeof g->problem, "%s: eye (%g, %g, %g) look_at (%g, %g, %g) up (%g, %g, %g) fov %g",
                 what, (double)c->eye.x, (double)c->eye.y, (double)c->eye.z, (double)c->look_at.x,
                 (double)c->look_at.y, (double)c->look_at.z, (double)c->up.x, (double)c->up.y, (double)c->up.z,
                 (double)c->fov_deg);
    else if (t->kind == TXN_CURSOR)
        snprintf(g->problem, sizeof g->problem, "%s: cursor (%g, %g)", what, (double)t->args.cursor.sx,
                 (double)t->args.cursor.sy);
    else
        snprintf(g->problem, sizeof g->problem, "%s: %s", what, txn_kind_name(t->kind));
}

static void emit(void *ctx, const input_txn *t)
{
    garbage_sink *g = ctx;
    tess_error err = {{0}};
    switch (t->kind) {
    case TXN_CAMERA:
        g->cameras++;
        if (!camera_validate(&t->args.camera.camera, &err))
            note_problem(g, err.msg, t);
        else
            g->shown = t->args.camera.camera;
        break;
    case TXN_CURSOR:
        g->cursors++;
        if (t->args.cursor.on && !(isfinite(t->args.cursor.sx) && isfinite(t->args.cursor.sy)))
            note_problem(g, "cursor not finite", t);
        break;
    case TXN_STATUS:
        g->others++;
        if (!memchr(t->args.status.text, '\0', sizeof t->args.status.text))
            note_problem(g, "status text not terminated", t);
        break;
    default:
        g->others++;
        break;
    }
}

/* Picks hit a plane y = 0 in front of the camera, or miss. */
static void pick(void *ctx, vec3 origin, vec3 dir, input_hit *out)
{
    (void)ctx;
    memset(out, 0, sizeof *out);
    if (!(dir.y < -1e-3f) || !isfinite(origin.y))
        return;
    float t = -origin.y / dir.y;
    out->hit = true;
    out->point = v3_add(origin, v3_scale(dir, t));
    out->geom_id = 0;
    snprintf(out->what, sizeof out->what, "mesh 0 'ground' triangle 1");
    snprintf(out->part.label, sizeof out->part.label, "mesh 0 'ground'");
}

static camera_desc current(void *ctx) { return ((garbage_sink *)ctx)->shown; }

/* xorshift64*: the same garbage on every run */
static uint64_t next(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 2685821657736338717ull;
}

static double garbage_number(uint64_t *s)
{
    static const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-310, -1e-310, 1e-30, 1e30, -1e30, 1e308,
                                     -1e308, DBL_MAX, INFINITY, -INFINITY, NAN, -NAN, 2.0, 1e6};
    uint64_t r = next(s);
    if (r % 3 == 0)
        return special[(r >> 8) % (sizeof special / sizeof special[0])];
    return ((double)(r >> 11) / 9007199254740992.0) * 4.0 - 2.0; /* uniform in [-2, 2): mostly on the plane */
}

static int garbage_int(uint64_t *s, int usual_max)
{
    static const int special[] = {-1, INT32_MIN, INT32_MAX, 0x7fff, 0x10000, 767, 768, 10, 11};
    uint64_t r = next(s);
    if (r % 5 == 0)
        return special[(r >> 8) % (sizeof special / sizeof special[0])];
    return (int)((r >> 16) % (uint64_t)usual_max);
}

/* One run of `events` random events with the given tour setting. */
static void run_garbage(uint64_t seed, int events, bool tour)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.plane_aspect = 16.f / 9.f;
    cfg.home = (camera_desc){v3(0.f, 2.f, 8.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    cfg.scene_size = 10.0;
    cfg.idle_timeout_s = tour ? 2.0 : 0.0;
    cfg.have_tour = tour;
    garbage_sink g = {0};
    g.shown = cfg.home;
    input_controller_hooks hooks = {&g, pick, emit, current, NULL};
    input_controller *c = input_controller_create(&cfg, &hooks);
    cr_assert_not_null(c);

    uint64_t s = seed, now_us = 1000000;
    for (int i = 0; i < events && !g.problem[0]; i++) {
        uint64_t r = next(&s);
        /* time: mostly small steps, sometimes backwards, sometimes a leap */
        switch (r % 16) {
        case 0: now_us -= now_us > 50000 ? 50000 : 0; break;
        case 1: now_us += 3600ull * 1000000; break;
        default: now_us += (r >> 8) % 20000; break;
        }
        if ((r >> 4) % 7 == 0) {
            input_controller_tick(c, now_us);
            continue;
        }
        input_event e;
        memset(&e, 0, sizeof e);
        e.kind = (input_event_kind)((r >> 12) % (INPUT_DEVICE_REMOVED + 1));
        e.time_us = now_us;
        e.device = garbage_int(&s, 3);
        e.code = garbage_int(&s, 0x300); /* KEY_* and BTN_* codes, and beyond */
        e.pressed = next(&s) & 1;
        e.slot = garbage_int(&s, INPUT_MAX_TOUCHES + 2);
        e.fingers = garbage_int(&s, 5);
        e.cancelled = next(&s) & 1;
        e.x = garbage_number(&s);
        e.y = garbage_number(&s);
        e.dx = garbage_number(&s);
        e.dy = garbage_number(&s);
        e.scale = next(&s) % 4 ? 1.0 + 0.5 * garbage_number(&s) : garbage_number(&s);
        input_controller_event(c, &e);
        camera_desc cam = input_controller_camera(c);
        tess_error err = {{0}};
        if (!camera_validate(&cam, &err) && !g.problem[0])
            snprintf(g.problem, sizeof g.problem, "the steered camera after event %d (kind %d): %s", i, (int)e.kind,
                     err.msg);
        double speed = input_controller_fly_speed(c);
        if (!(isfinite(speed) && speed > 0.0) && !g.problem[0])
            snprintf(g.problem, sizeof g.problem, "fly speed %g after event %d (kind %d)", speed, i, (int)e.kind);
    }
    input_controller_destroy(c);
    cr_assert_str_empty(g.problem, "seed %llu (tour %d): %s", (unsigned long long)seed, tour, g.problem);
    cr_assert_gt(g.cameras, 0, "seed %llu: the garbage never moved the camera: the test tests nothing", (unsigned long long)seed);
}

Test(input_faults, random_events_never_give_a_bad_camera, .timeout = 60)
{
    for (uint64_t seed = 1; seed <= 40; seed++)
        run_garbage(seed * 0x9e3779b97f4a7c15ull, 4000, seed % 2 == 0);
}

/* ---- record files cut off ------------------------------------------------- */

/* A valid record of kind i % TXN_KIND_COUNT with arguments that depend on i. */
static input_txn sample_record(int i)
{
    camera_desc cam = {v3(1.f + (float)i, 2.5f, -3.f), v3(0.125f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 41.f};
    const float rgb[3] = {0.25f, 0.5f, (float)i};
    char text[64];
    snprintf(text, sizeof text, "picked mesh %d", i);
    switch ((txn_kind)(i % TXN_KIND_COUNT)) {
    case TXN_CAMERA: return txn_camera(i % 3 == 0 ? TXN_ALL_CHANNELS : i % 3, &cam);
    case TXN_CURSOR: return txn_cursor(true, 0.25f, -0.75f);
    case TXN_STATUS: return txn_status(text);
    case TXN_HIDE: return txn_geoms_record(TXN_HIDE, 123, 1 + (uint32_t)i);
    case TXN_SHOW_ALL: return txn_simple(TXN_SHOW_ALL);
    case TXN_TOUR: return txn_flag(TXN_TOUR, true);
    case TXN_QUIT: return txn_simple(TXN_QUIT);
    case TXN_GOVERNOR_STATUS: return txn_flag(TXN_GOVERNOR_STATUS, true);
    case TXN_SHOW: return txn_geoms_record(TXN_SHOW, 123, 1);
    case TXN_ISOLATE: return txn_geoms_record(TXN_ISOLATE, (uint32_t)i, 1000);
    case TXN_HIGHLIGHT: return txn_highlight(7, 2, i % 2 == 0);
    case TXN_COLOUR: return txn_colour(7, 2, rgb);
    case TXN_SHADOWS: return txn_flag(TXN_SHADOWS, false);
    case TXN_RENDERER: return txn_renderer("eyelight");
    case TXN_THREADS: return txn_threads(1 + i % 8);
    case TXN_CHANNEL_ACTIVE: return txn_channel_active(i % 4, true);
    case TXN_MOVE: {
        const float m[12] = {0.f, -1.f, 0.f, 0.5f * (float)i, 1.f, 0.f, 0.f, 0.f, 0.f, 0.f, 2.f, -0.25f};
        return txn_move(3, 4, m);
    }
    case TXN_OPACITY: return i % 2 ? txn_opacity_all(0.25f * (float)(i % 5)) : txn_opacity(5, 2, 0.5f);
    case TXN_CLIP_PLANE: {
        const float point[3] = {0.5f * (float)i, -1.f, 0.f}, normal[3] = {0.f, 0.f, 2.f};
        return txn_clip_plane(i % TXN_CLIP_PLANES, i % 2 == 0, point, normal);
    }
    case TXN_CROP: return txn_crop(2, 1, i % 2 == 0, -0.5f * (float)i, 1.f);
    case TXN_TIME_STEP: return txn_time_step((uint32_t)i % 9);
    case TXN_VALUE: return txn_value(2, 1, 0.5f * (float)i);
    case TXN_COLORMAP: return txn_colormap(2, 1, i % 2 ? "magma" : "viridis");
    case TXN_TRANSFER: return txn_transfer(i % 2 ? "ct-bone" : "mri-soft");
    case TXN_POINTER: return txn_pointer(i % TXN_POINTERS, i % 2 == 0, 0.25f * (float)(i % 5), -0.5f);
    case TXN_KIND_COUNT: break;
    }
    return txn_simple(TXN_QUIT);
}

/* A recording of `n` transactions of every kind, as the sink writes it. */
static char *recording(int n, size_t *len, size_t *last_line_start)
{
    char *text = NULL;
    FILE *f = open_memstream(&text, len);
    cr_assert_not_null(f);
    fprintf(f, "%s\n", INPUT_RECORD_HEADER);
    for (int i = 0; i < n; i++) {
        input_txn t = sample_record(i);
        fflush(f);
        if (i == n - 1)
            *last_line_start = *len;
        cr_assert(input_record_write(f, 0.5 * i, &t));
    }
    cr_assert_eq(fclose(f), 0);
    return text;
}

/* Cut at every byte of the last line: the lines before it replay, bit for
 * bit as in the whole file, and the warning names the file and line. */
Test(input_faults, a_record_cut_off_mid_line_replays_the_complete_lines)
{
    const int n = 2 * TXN_KIND_COUNT + 1; /* the last one a camera line, the longest kind */
    size_t len = 0, last = 0;
    char *text = recording(n, &len, &last);
    input_record whole = {0};
    tess_error err = {{0}};
    cr_assert(input_record_parse("rec.txt", text, len, &whole, &err), "%s", err.msg);
    cr_assert_eq(whole.count, (size_t)n);
    cr_assert_eq(whole.cut_line, 0);
    cr_assert_str_empty(whole.warning.msg);
    for (size_t cut = last + 1; cut < len; cut++) { /* the last line's first byte .. all but its newline */
        input_record r = {0};
        tess_error e = {{0}};
        cr_assert(input_record_parse("rec.txt", text, cut, &r, &e), "cut at %zu of %zu: %s", cut, len, e.msg);
        cr_assert_eq(r.count, (size_t)n - 1, "cut at %zu: %zu entries", cut, r.count);
        cr_assert_eq(memcmp(r.entries, whole.entries, r.count * sizeof *r.entries), 0, "cut at %zu", cut);
        cr_assert_eq(r.cut_line, (size_t)n + 1, "cut at %zu: line %zu", cut, r.cut_line);
        char want[256];
        snprintf(want, sizeof want,
                 "rec.txt:%d: the last line has no newline at its end (the recording was cut off?): left out; %d "
                 "transactions before it replay",
                 n + 1, n - 1);
        cr_assert_str_eq(r.warning.msg, want);
        input_record_free(&r);
    }
    /* cut right after a newline: nothing is missing, nothing to say */
    input_record r = {0};
    cr_assert(input_record_parse("rec.txt", text, last, &r, &err), "%s", err.msg);
    cr_assert_eq(r.count, (size_t)n - 1);
    cr_assert_eq(r.cut_line, 0);
    cr_assert_str_empty(r.warning.msg);
    input_record_free(&r);
    input_record_free(&whole);
    free(text);
}

/* A line that parses is left out too when it has no newline: it may be the
 * start of a longer one ("hide 12" of "hide 123"). One line cut: "1 transaction". */
Test(input_faults, a_cut_line_is_left_out_even_when_it_parses)
{
    const char text[] = INPUT_RECORD_HEADER_V1 "\n# a comment\n0.5 unhide-all\n0.75 hide 12";
    input_record r = {0};
    tess_error err = {{0}};
    cr_assert(input_record_parse("rec.txt", text, strlen(text), &r, &err), "%s", err.msg);
    cr_assert_eq(r.count, 1);
    cr_assert_eq(r.entries[0].txn.kind, TXN_SHOW_ALL);
    cr_assert_str_eq(r.warning.msg, "rec.txt:4: the last line has no newline at its end (the recording was cut off?): "
                                    "left out; 1 transaction before it replay");
    input_record_free(&r);
}

/* Cut inside the header there is nothing to replay: an error, as for any
 * file that is not a record; cut in a line before the last, the rest is
 * not a recording that stopped: an error naming the line. */
Test(input_faults, a_record_cut_in_the_header_or_mended_badly_is_an_error)
{
    const char header_cut[] = "tessera-input-rec";
    input_record r = {0};
    tess_error err = {{0}};
    cr_assert_not(input_record_parse("rec.txt", header_cut, strlen(header_cut), &r, &err));
    cr_assert(strstr(err.msg, "rec.txt:1: not an input record"), "%s", err.msg);
    const char middle_cut[] = INPUT_RECORD_HEADER "\n0.5 hide 1 1\n0.75 cam\n1.0 quit\n";
    tess_error err2 = {{0}};
    cr_assert_not(input_record_parse("rec.txt", middle_cut, strlen(middle_cut), &r, &err2));
    cr_assert(strstr(err2.msg, "rec.txt:3: unknown transaction kind 'cam'"), "%s", err2.msg);
}

/* input_record_load says so on stderr (the log), naming the file and line. */
Test(input_faults, loading_a_cut_record_warns)
{
    char dir[] = "/tmp/tessera_input_faults_XXXXXX";
    cr_assert_not_null(mkdtemp(dir));
    char path[128], log_path[128];
    snprintf(path, sizeof path, "%s/session.rec", dir);
    snprintf(log_path, sizeof log_path, "%s/stderr.txt", dir);
    FILE *f = fopen(path, "w");
    cr_assert_not_null(f);
    fprintf(f, "%s\n0.25 tour 1\n0.5 tour 0\n0.75 cursor 1 0x1p-1 0x1", INPUT_RECORD_HEADER);
    cr_assert_eq(fclose(f), 0);
    fflush(stderr);
    int saved = dup(2), fd = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    cr_assert(saved >= 0 && fd >= 0);
    dup2(fd, 2);
    close(fd);
    input_record r = {0};
    tess_error err = {{0}};
    bool ok = input_record_load(path, &r, &err);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    char logged[1024] = "";
    f = fopen(log_path, "r");
    cr_assert_not_null(f);
    size_t got = fread(logged, 1, sizeof logged - 1, f);
    logged[got] = '\0';
    fclose(f);
    unlink(log_path);
    unlink(path);
    rmdir(dir);
    cr_assert(ok, "%s", err.msg);
    cr_assert_eq(r.count, 2);
    char want[512];
    snprintf(want, sizeof want, "%s:4: the last line has no newline at its end", path);
    cr_assert(strstr(logged, want), "the log lacks '%s': %s", want, logged);
    cr_assert(strstr(logged, "warn"), "not a warning: %s", logged);
    input_record_free(&r);
}
