/* cmd_bench_path.c - `tessera bench --path` (camera transactions sent from a
 * path at a fixed rate, like a user steering, with the frame rate each one
 * saw) and `tessera bench --scaling` (the same animation at 1..N threads and
 * the fraction of linear speed-up at each). */
#include <math.h>
#include <stddef.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/base/srgb.h"
#include "metrics/flip.h"
#include "option_check.h"
#include "pipeline_cli.h"

#define BENCH_PATH_MAX_TRANSACTIONS 1000000
#define BENCH_PATH_DEFAULT_FLIP_SAMPLES 16 /* with --budget-ms: transactions whose frame gets flip_vs_full */
#define BENCH_PATH_MAX_FLIP_SAMPLES 1000
#define SCALING_DEFAULT_ROUNDS 3
#define SCALING_DEFAULT_FRAMES 48
#define SCALING_MAX_COUNTS 32 /* --thread-counts entries */

/* Per-frame durations, kept by a serial callback (serial section only). */
typedef struct frame_clock {
    double *frame_s;  /* frame_s[f]: wall time of the loop step that rendered frame f (display f-1 + render f) */
    size_t count, capacity;
    bool last_idle;   /* the previous step rendered nothing (a governor's idle step): it is not a frame */
} frame_clock;

static void clock_tick(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    frame_clock *fc = ctx;
    bool previous_was_frame = fi->frame > 0 && !fc->last_idle && fc->count == fi->frame - 1;
    fc->last_idle = fi->idle;
    if (!previous_was_frame)
        return;
    if (fc->count == fc->capacity) {
        size_t cap = fc->capacity ? 2 * fc->capacity : 1024;
        double *grown = realloc(fc->frame_s, cap * sizeof *grown);
        if (!grown)
            return; /* the report will have fewer frames; it says how many */
        fc->frame_s = grown;
        fc->capacity = cap;
    }
    fc->frame_s[fc->count++] = fi->last_frame_s;
}

/* ---------------------------------------------------------------- --path */

typedef struct path_sender {
    pipeline *p;
    bool all_channels;    /* a wall: the camera of every output */
    const camera_path *path;
    double rate_hz;
    size_t transactions;  /* to send: floor(duration * rate) + 1 */
    uint64_t *applied_at; /* applied_at[k]: frame transaction k was applied before (serial section) */
    atomic_size_t refused;
} path_sender;

typedef struct camera_txn {
    path_sender *sender;
    size_t seq;
    camera_desc camera;
} camera_txn;

static void apply_path_camera(pipeline *p, void *args)
{
    camera_txn *t = args;
    int channels = t->sender->all_channels ? pipeline_channel_count(p) : 1;
    for (int i = 0; i < channels; i++)
        pipeline_set_camera(p, i, &t->camera);
    t->sender->applied_at[t->seq] = pipeline_frame(p);
}

static void stop_now(pipeline *p, void *args)
{
    (void)args;
    pipeline_stop(p);
}

/* The last transaction: stop after the frame that shows the last camera. */
static void end_of_path(pipeline *p, void *args)
{
    (void)args;
    pipeline_at_frame(p, pipeline_frame(p) + 1, "stop", stop_now, NULL, 0);
}

/* ---- what channel 0's display was given: each frame's scale, and 8-bit
 * copies of the frames that first showed the sampled transactions ---- */

typedef struct flip_sample {
    size_t txn;         /* the transaction it measures */
    bool captured;
    camera_desc camera; /* of the frame */
    double scale;       /* its render scale. The frame is a pure function of camera and scale
                           (pipeline.h, DETERMINISM), so it is made again after the run instead of
                           kept: keeping 16 frames of 1080p (copying them out on the display thread)
                           slowed the frame after each by 50-100 ms on this VM (cold pages) */
    double flip;        /* mean FLIP against the full-size frame of the camera; NAN: not measured */
} flip_sample;

typedef struct frame_tap {
    image_display base;
    image_display_ops ops;   /* the inner display's hooks, forwarded */
    image_display *inner;
    const path_sender *sender;
    flip_sample *samples;    /* sorted by txn */
    size_t sample_count;
    double *frame_scale;     /* frame_scale[f]: render scale of frame f (display thread while running) */
    size_t frame_count, frame_capacity;
    int width_px, height_px; /* channel 0's size */
} frame_tap;

static uint8_t srgb_byte(float linear)
{
    double v = linear > 0.f ? (linear < 1.f ? (double)linear : 1.0) : 0.0;
    return (uint8_t)(srgb_curve_encode(v) * 255.0 + 0.5);
}

static void to_srgb8(const float *rgb, size_t floats, uint8_t *out)
{
    for (size_t i = 0; i < floats; i++)
        out[i] = srgb_byte(rgb[i]);
}

static bool tap_show(image_display *d, const frame_image *img, tess_error *err)
{
    frame_tap *t = (frame_tap *)d;
    if (img->frame >= t->frame_capacity) {
        size_t cap = t->frame_capacity ? 2 * t->frame_capacity : 1024;
        while (cap <= img->frame)
            cap *= 2;
        double *grown = realloc(t->frame_scale, cap * sizeof *grown);
        if (grown) {
            t->frame_scale = grown;
            t->frame_capacity = cap;
        }
    }
    if (img->frame < t->frame_capacity) {
        for (size_t f = t->frame_count; f < img->frame; f++)
            t->frame_scale[f] = NAN; /* frames never shown (none, unless a channel was off) */
        t->frame_scale[img->frame] = img->render_scale;
        if (img->frame >= t->frame_count)
            t->frame_count = img->frame + 1;
    }
    /* the serial section that applied a transaction came before this frame's display stage */
    for (size_t i = 0; i < t->sample_count; i++) {
        flip_sample *s = &t->samples[i];
        if (s->captured || t->sender->applied_at[s->txn] != img->frame)
            continue;
        s->camera = img->camera;
        s->scale = img->render_scale;
        s->captured = true;
    }
    return t->inner->ops->show(t->inner, img, err);
}

static void tap_write_tile(image_display *d, const frame_image *img, int x0, int y0, int x1, int y1)
{
    frame_tap *t = (frame_tap *)d;
    t->inner->ops->write_tile(t->inner, img, x0, y0, x1, y1);
}

static bool tap_end_stage(image_display *d, tess_error *err)
{
    frame_tap *t = (frame_tap *)d;
    return t->inner->ops->end_stage(t->inner, err);
}

static bool tap_settle_stage(image_display *d, tess_error *err)
{
    frame_tap *t = (frame_tap *)d;
    return t->inner->ops->settle_stage(t->inner, err);
}

static void tap_destroy(image_display *d)
{
    frame_tap *t = (frame_tap *)d;
    image_display_destroy(t->inner);
    t->inner = NULL; /* the samples and scales outlive the pipeline: freed by bench_path */
}

/* cli_pipeline_spec.wrap_display: channel 0 gets the tap (made by bench_path). */
static image_display *wrap_with_tap(void *ctx, int channel, image_display *inner, tess_error *err)
{
    (void)err;
    frame_tap *t = ctx;
    if (channel != 0)
        return inner;
    t->inner = inner;
    t->ops = (image_display_ops){"tap", tap_show, tap_destroy, inner->ops->write_tile ? tap_write_tile : NULL,
                                 inner->ops->end_stage ? tap_end_stage : NULL,
                                 inner->ops->settle_stage ? tap_settle_stage : NULL};
    t->base.ops = &t->ops;
    return &t->base;
}

/* After the run: each captured frame against the full-size, one-ray-per-pixel
 * frame of its camera (what the governor would show with time to spare),
 * both as 8-bit sRGB, FLIP at its default viewer. */
static bool measure_flips(frame_tap *t, const cli_pipeline_spec *spec, const cli_scene *cs)
{
    int w = t->width_px, h = t->height_px;
    size_t pixels = (size_t)w * (size_t)h;
    float *full = malloc(pixels * 3 * sizeof *full), *a = malloc(pixels * 3 * sizeof *a);
    float *b = malloc(pixels * 3 * sizeof *b), *map = malloc(pixels * sizeof *map);
    float *low = malloc(pixels * 3 * sizeof *low), *shown = malloc(pixels * 3 * sizeof *shown);
    uint8_t *full8 = malloc(pixels * 3), *test8 = malloc(pixels * 3);
    bool ok = full && a && b && map && full8 && test8 && low && shown;
    if (!ok)
        cli_error("bench --path: out of memory for the FLIP measurement at %dx%d", w, h);
    float decode[256];
    for (int c = 0; c < 256; c++)
        decode[c] = (float)srgb_curve_decode(c / 255.0);
    for (size_t i = 0; ok && i < t->sample_count; i++) {
        flip_sample *s = &t->samples[i];
        if (!s->captured)
            continue;
        render_view v = {cs->scene, cs->accel, camera_basis_make(&s->camera, w, h), spec->shadows,
                         spec->renderer->shading, NULL, NULL};
        render_image(&v, spec->threads, full, NULL);
        if (s->scale >= 1.0) {
            s->flip = 0.0; /* the full-size frame itself */
            continue;
        }
        /* the shown frame again, as the pipeline made it: the low-res frame of the same view
         * (the output's plane aspect, the whole window), upscaled with the same filter */
        int low_w = upscale_low_res_px(w, s->scale), low_h = upscale_low_res_px(h, s->scale);
        render_view lv = v;
        lv.camera = camera_basis_window(&s->camera, (float)w / (float)h, CAMERA_WINDOW_FULL, low_w, low_h);
        render_image(&lv, spec->threads, low, NULL);
        tess_error uerr = {{0}};
        if (!upscale_image(low, low_w, low_h, shown, w, h, spec->upscale, &uerr)) {
            cli_error("bench --path: upscaling for FLIP: %s", uerr.msg);
            ok = false;
            break;
        }
        to_srgb8(full, pixels * 3, full8);
        to_srgb8(shown, pixels * 3, test8);
        for (size_t k = 0; k < pixels * 3; k++) {
            a[k] = decode[full8[k]];
            b[k] = decode[test8[k]];
        }
        tess_error err = {{0}};
        if (!flip_ldr_map(a, b, w, h, FLIP_DEFAULT_PPD, spec->threads, map, &err)) {
            cli_error("bench --path: FLIP: %s", err.msg);
            ok = false;
            break;
        }
        double sum = 0.0;
        for (size_t k = 0; k < pixels; k++)
            sum += map[k];
        s->flip = sum / (double)pixels;
    }
    free(full);
    free(a);
    free(b);
    free(map);
    free(full8);
    free(test8);
    free(low);
    free(shown);
    return ok;
}

static void sleep_until(double t)
{
    double now = cli_now_s();
    if (t <= now)
        return;
    double wait = t - now;
    struct timespec ts = {(time_t)wait, (long)((wait - floor(wait)) * 1e9)};
    nanosleep(&ts, NULL);
}

static void *send_path(void *arg)
{
    path_sender *s = arg;
    double start = cli_now_s();
    for (size_t k = 0; k < s->transactions; k++) {
        double t = (double)k / s->rate_hz;
        sleep_until(start + t);
        camera_txn txn = {s, k, camera_path_eval(s->path, s->path->keys[0].time_s + t)};
        while (!pipeline_transaction(s->p, "path camera", apply_path_camera, &txn, sizeof txn)) {
            atomic_fetch_add(&s->refused, 1);
            sleep_until(cli_now_s() + 1e-3); /* a full queue: as a user's input would, try again */
        }
    }
    while (!pipeline_transaction(s->p, "end of path", end_of_path, NULL, 0))
        sleep_until(cli_now_s() + 1e-3);
    return NULL;
}

static void print_path_report(const path_sender *s, frame_clock *fc, const frame_tap *tap,
                              const cli_pipeline_spec *spec)
{
    printf("# txn time_s frame frame_ms fps scale flip_vs_full (the frame that first showed the transaction; "
           "scale: its render scale, - on a wall; flip_vs_full: mean FLIP against the full-size frame of its "
           "camera, - where not sampled)\n");
    size_t next_sample = 0;
    double flip_sum = 0.0;
    size_t flips = 0;
    for (size_t k = 0; k < s->transactions; k++) {
        uint64_t f = s->applied_at[k];
        double frame_s = f < fc->count ? fc->frame_s[f] : NAN;
        char scale[16] = "-", flip[16] = "-";
        if (f < tap->frame_count && !isnan(tap->frame_scale[f]))
            snprintf(scale, sizeof scale, "%.4g", tap->frame_scale[f]);
        while (next_sample < tap->sample_count && tap->samples[next_sample].txn < k)
            next_sample++;
        if (next_sample < tap->sample_count && tap->samples[next_sample].txn == k &&
            !isnan(tap->samples[next_sample].flip)) {
            snprintf(flip, sizeof flip, "%.5f", tap->samples[next_sample].flip);
            flip_sum += tap->samples[next_sample].flip;
            flips++;
        }
        printf("txn %zu %.4f %llu %.2f %.1f %s %s\n", k, (double)k / s->rate_hz, (unsigned long long)f,
               1e3 * frame_s, 1.0 / frame_s, scale, flip);
    }
    size_t frames = fc->count;
    double worst = 0.0;
    for (size_t i = 0; i < frames; i++)
        worst = fc->frame_s[i] > worst ? fc->frame_s[i] : worst;
    double p95 = cli_quantile(fc->frame_s, frames, 0.95);
    double med = cli_median(fc->frame_s, frames);
    char flip_mean[32] = "-";
    if (flips)
        snprintf(flip_mean, sizeof flip_mean, "%.5f", flip_sum / (double)flips);
    printf("BENCH_PATH transactions=%zu frames=%zu rate_hz=%g threads=%d size=%dx%d median_frame_ms=%.3f "
           "worst_frame_ms=%.3f median_fps=%.2f refused=%zu p50_ms=%.3f p95_ms=%.3f budget_ms=%g flip_mean=%s "
           "flip_frames=%zu\n",
           s->transactions, frames, s->rate_hz, spec->threads, spec->channels[0].width_px,
           spec->channels[0].height_px, 1e3 * med, 1e3 * worst, med > 0.0 ? 1.0 / med : 0.0,
           atomic_load(&s->refused), 1e3 * med, 1e3 * p95, spec->budget_ms, flip_mean, flips);
}

static int bench_path(cli_pipeline_spec *spec, const cli_scene *cs, int flip_samples)
{
    tess_error err = {{0}};
    camera_path path = {0};
    if (!camera_path_load(spec->path_file, &path, &err)) {
        cli_error("%s", err.msg);
        return 1;
    }
    double duration = camera_path_duration(&path);
    double n = floor(duration * spec->rate_hz) + 1.0;
    if (n > BENCH_PATH_MAX_TRANSACTIONS) {
        cli_error("--path %s: %.0f transactions at %g Hz; at most %d", spec->path_file, n, spec->rate_hz,
                  BENCH_PATH_MAX_TRANSACTIONS);
        camera_path_free(&path);
        return 2;
    }
    path_sender s = {.path = &path, .rate_hz = spec->rate_hz, .transactions = (size_t)n,
                     .all_channels = spec->wall_file[0] != '\0'};
    atomic_init(&s.refused, 0);
    s.applied_at = calloc(s.transactions, sizeof *s.applied_at);
    for (size_t k = 0; s.applied_at && k < s.transactions; k++)
        s.applied_at[k] = UINT64_MAX; /* not applied yet */
    frame_clock fc = {NULL, 0, 0, false};
    /* the sampled transactions: evenly spread over the path, the first and the last included */
    frame_tap tap = {.sender = &s, .width_px = spec->channels[0].width_px, .height_px = spec->channels[0].height_px};
    size_t want = spec->wall_file[0] ? 0 : (size_t)flip_samples < s.transactions ? (size_t)flip_samples : s.transactions;
    tap.samples = want ? calloc(want, sizeof *tap.samples) : NULL;
    for (size_t i = 0; tap.samples && i < want; i++) {
        size_t txn = want == 1 ? 0 : (size_t)llround((double)i * (double)(s.transactions - 1) / (double)(want - 1));
        if (tap.sample_count && tap.samples[tap.sample_count - 1].txn == txn)
            continue;
        tap.samples[tap.sample_count++] = (flip_sample){.txn = txn, .flip = NAN};
    }

    if (!spec->wall_file[0]) {
        spec->wrap_display = wrap_with_tap;
        spec->wrap_ctx = &tap;
    }
    spec->channels[0].camera = camera_path_eval(&path, path.keys[0].time_s);
    spec->channels[0].have_camera = true;
    spec->frames = 0; /* until the path ends */
    display_instance *outputs = NULL; /* a wall on a device: the started backend */
    pipeline *p = s.applied_at ? cli_pipeline_create(spec, cs, &outputs) : NULL;
    int code = 1;
    if (p) {
        s.p = p;
        pipeline_add_serial_animation(p, "frame clock", clock_tick, &fc);
        pthread_t sender;
        if (pthread_create(&sender, NULL, send_path, &s) != 0) {
            cli_error("cannot start the transaction sender thread");
        } else {
            bool ok = pipeline_run(p, &err);
            pthread_join(sender, NULL);
            if (!ok)
                cli_error("%s", err.msg);
            else if (measure_flips(&tap, spec, cs)) {
                print_path_report(&s, &fc, &tap, spec);
                cli_pipeline_report(p, spec);
                code = 0;
            }
        }
    }
    pipeline_destroy(p);
    cli_pipeline_release_outputs(outputs);
    if (!p)
        image_display_destroy(tap.inner);
    free(tap.samples);
    free(tap.frame_scale);
    free(s.applied_at);
    free(fc.frame_s);
    camera_path_free(&path);
    spec->wrap_display = NULL;
    return code;
}

/* ---------------------------------------------------------------- --scaling */

/* A run during which other programs took more than this fraction of the
 * run's wall time in CPU (and more than SCALING_NOISE_FLOOR_S: /proc/stat
 * counts in 10 ms ticks) is repeated (up to SCALING_MAX_ATTEMPTS times). */
#define SCALING_NOISE_FRACTION 0.02
#define SCALING_NOISE_FLOOR_S 0.03
#define SCALING_MAX_ATTEMPTS 4

typedef struct scaling_sample {
    double run_s;      /* wall time of pipeline_run */
    double display_ms; /* thread 0's display stage per frame */
    double cpu_other;  /* CPU seconds other programs took during the run */
    double barrier_share; /* thread time spent at frame barriers / (threads x run time) */
    double serial_ms;  /* per frame barrier: the serial section */
    double release_ms; /* per frame barrier: serial section's end to the last thread leaving */
    double wait_ms;    /* per frame and thread: time at the frame barrier (idle + serial + release) */
    double cpu_ms;     /* per frame: this process's CPU time (all threads), which other programs
                          sharing the machine change much less than the wall time */
} scaling_sample;

/* One timed run of the animation at `threads`. */
static bool scaling_run_once(cli_pipeline_spec *spec, const cli_scene *cs, const camera_path *path, int threads,
                             scaling_sample *out)
{
    tess_error err = {{0}};
    spec->threads = threads;
    display_instance *outputs = NULL; /* a wall on a device: the started backend */
    pipeline *p = cli_pipeline_create(spec, cs, &outputs);
    if (!p)
        return false;
    bool wall = spec->wall_file[0] != '\0';
    cli_path_player player = {.time_offset_s = 0.0, .all_channels = wall};
    cli_orbit orbit = {.all_channels = wall};
    if (path) {
        player.path = *path; /* borrowed: not freed here */
        cli_path_player_start(p, &player);
    } else {
        cli_orbit_start(p, &orbit, CLI_ORBIT_PERIOD_S);
    }
    double busy0 = cli_machine_busy_s(), own0 = cli_own_cpu_s();
    bool ok = pipeline_run(p, &err);
    double busy1 = cli_machine_busy_s(), own1 = cli_own_cpu_s();
    if (!ok)
        cli_error("%s", err.msg);
    pipeline_stats st = pipeline_get_stats(p);
    out->run_s = st.run_s;
    out->display_ms = st.frames_displayed ? 1e3 * st.display_s / (double)st.frames_displayed : 0.0;
    out->cpu_other = busy0 < 0.0 ? 0.0 : (busy1 - busy0) - (own1 - own0);
    out->barrier_share = st.run_s > 0.0 ? st.barrier_s / ((double)threads * st.run_s) : 0.0;
    double barriers = st.serial_sections ? (double)st.serial_sections : 1.0;
    out->serial_ms = 1e3 * st.serial_s / barriers;
    out->release_ms = 1e3 * st.release_s / (st.serial_sections > 1 ? (double)(st.serial_sections - 1) : 1.0);
    out->wait_ms = 1e3 * st.barrier_s / ((double)threads * barriers);
    out->cpu_ms = st.frames_rendered ? 1e3 * (own1 - own0) / (double)st.frames_rendered : 0.0;
    pipeline_destroy(p);
    cli_pipeline_release_outputs(outputs);
    return ok;
}

/* A run, repeated while the machine was busy with other work. */
static bool scaling_run(cli_pipeline_spec *spec, const cli_scene *cs, const camera_path *path, int threads,
                        bool reject_noisy, scaling_sample *out, int *rejected)
{
    for (int attempt = 0; attempt < (reject_noisy ? SCALING_MAX_ATTEMPTS : 1); attempt++) {
        if (!scaling_run_once(spec, cs, path, threads, out))
            return false;
        if (out->cpu_other <= fmax(SCALING_NOISE_FRACTION * out->run_s, SCALING_NOISE_FLOOR_S))
            return true;
        ++*rejected;
    }
    return true; /* kept, and counted as noisy in the report */
}

/* The median of one field over a row's rounds. */
static double row_median(const scaling_sample *row, int rounds, size_t offset, double *scratch)
{
    for (int r = 0; r < rounds; r++)
        memcpy(&scratch[r], (const char *)&row[r] + offset, sizeof(double));
    return cli_median(scratch, (size_t)rounds);
}

/* The smallest value of one field over a row's rounds (the least disturbed). */
static double row_min(const scaling_sample *row, int rounds, size_t offset)
{
    double lo = INFINITY, v;
    for (int r = 0; r < rounds; r++) {
        memcpy(&v, (const char *)&row[r] + offset, sizeof(double));
        lo = fmin(lo, v);
    }
    return lo;
}

/* counts[0..n): the thread counts to run, in order; the speed-up is against the first. */
static int bench_scaling(cli_pipeline_spec *spec, const cli_scene *cs, const int *counts, int n_counts, int rounds,
                         bool reject_noisy)
{
    tess_error err = {{0}};
    camera_path path = {0};
    bool have_path = spec->path_file[0] != '\0';
    if (have_path && !camera_path_load(spec->path_file, &path, &err)) {
        cli_error("%s", err.msg);
        return 1;
    }
    spec->time_mode = PIPELINE_TIME_FIXED_RATE; /* the same frames at every thread count */
    if (spec->frames == 0)
        spec->frames = have_path ? (int)floor(camera_path_duration(&path) * spec->rate_hz) + 1
                                 : SCALING_DEFAULT_FRAMES;
    size_t n_samples = (size_t)n_counts * (size_t)rounds;
    scaling_sample *samples = calloc(n_samples, sizeof *samples);
    double *scratch = calloc((size_t)rounds, sizeof *scratch);
    int code = 1, rejected = 0;
    if (!samples || !scratch) {
        cli_error("out of memory");
        goto done;
    }
    /* rounds alternate over the thread counts, so slow drifts of the machine hit all alike */
    for (int r = 0; r < rounds; r++)
        for (int k = 0; k < n_counts; k++)
            if (!scaling_run(spec, cs, have_path ? &path : NULL, counts[k], reject_noisy, &samples[k * rounds + r],
                             &rejected))
                goto done;
    printf("# %d frames %dx%d, display %s, %d rounds, %d noisy runs repeated; medians; fraction = speed-up / "
           "threads\n",
           spec->frames, spec->channels[0].width_px, spec->channels[0].height_px, spec->channels[0].display, rounds,
           rejected);
    double base = 0.0;
    for (int k = 0; k < n_counts; k++) {
        const int n = counts[k];
        const scaling_sample *row = &samples[k * rounds];
        double t, d, other, wait, lo = INFINITY, hi = 0.0;
        for (int r = 0; r < rounds; r++) {
            scratch[r] = row[r].run_s;
            lo = fmin(lo, row[r].run_s);
            hi = fmax(hi, row[r].run_s);
        }
        t = cli_median(scratch, (size_t)rounds);
        for (int r = 0; r < rounds; r++)
            scratch[r] = row[r].display_ms;
        d = cli_median(scratch, (size_t)rounds);
        for (int r = 0; r < rounds; r++)
            scratch[r] = row[r].cpu_other;
        other = cli_median(scratch, (size_t)rounds);
        for (int r = 0; r < rounds; r++)
            scratch[r] = row[r].barrier_share;
        wait = cli_median(scratch, (size_t)rounds);
        if (k == 0)
            base = t * counts[0];
        double speedup = base / t;
        printf("SCALING threads=%d median_s=%.4f min_s=%.4f max_s=%.4f frames_per_s=%.2f speedup=%.3f "
               "fraction_of_linear=%.3f display_ms_per_frame=%.2f barrier_share=%.4f cpu_other_s=%.3f "
               "frames=%d serial_ms_per_frame=%.4f release_ms_per_frame=%.4f wait_ms_per_frame=%.4f "
               "cpu_ms_per_frame=%.3f cpu_ms_per_frame_min=%.3f display_ms_min=%.3f serial_ms_min=%.4f "
               "release_ms_min=%.4f\n",
               n, t, lo, hi, spec->frames / t, speedup, speedup / n, d, wait, other, spec->frames,
               row_median(row, rounds, offsetof(scaling_sample, serial_ms), scratch),
               row_median(row, rounds, offsetof(scaling_sample, release_ms), scratch),
               row_median(row, rounds, offsetof(scaling_sample, wait_ms), scratch),
               row_median(row, rounds, offsetof(scaling_sample, cpu_ms), scratch),
               row_min(row, rounds, offsetof(scaling_sample, cpu_ms)),
               row_min(row, rounds, offsetof(scaling_sample, display_ms)),
               row_min(row, rounds, offsetof(scaling_sample, serial_ms)),
               row_min(row, rounds, offsetof(scaling_sample, release_ms)));
    }
    code = 0;
done:
    free(samples);
    free(scratch);
    camera_path_free(&path);
    return code;
}

/* ---------------------------------------------------------------- the command */

/* --thread-counts LIST: comma-separated counts, each 1..PIPELINE_MAX_THREADS. */
static bool parse_counts(const char *option, const char *text, int *counts, int *n)
{
    char buf[512];
    if (strlen(text) >= sizeof buf) {
        cli_error("%s: list too long", option);
        return false;
    }
    snprintf(buf, sizeof buf, "%s", text);
    *n = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (*n == SCALING_MAX_COUNTS) {
            cli_error("%s: at most %d thread counts", option, SCALING_MAX_COUNTS);
            return false;
        }
        if (!cli_parse_int(option, tok, 1, PIPELINE_MAX_THREADS, &counts[*n]))
            return false;
        ++*n;
    }
    if (*n == 0) {
        cli_error("%s: no thread count in '%s'", option, text);
        return false;
    }
    return true;
}

static void usage(FILE *f)
{
    fputs("usage: tessera bench --path FILE [--rate HZ] [options]\n"
          "       tessera bench --scaling [--path FILE] [--threads N] [--rounds R] [options]\n"
          "--path: a sender thread queues one camera transaction per 1/HZ s of the camera path\n"
          "  (--rate, default 30), as a user steering would, while the pipeline renders as fast as it\n"
          "  can (real time). Prints per transaction 'txn K TIME FRAME FRAME_MS FPS SCALE FLIP' (the\n"
          "  frame that first showed it, its render scale, and for --flip-samples of them the mean\n"
          "  FLIP against the full-size frame of the same camera) and a BENCH_PATH line with the\n"
          "  median, p95 and worst frame time and the mean FLIP. With --budget-ms the governor\n"
          "  picks the scale.\n"
          "  --flip-samples N --path: transactions measured with FLIP, spread over the path (default\n"
          "                   16 with --budget-ms, else 0; the frames are made again after the run from\n"
          "                   their camera and scale, as the pipeline made them, not kept)\n"
          "--scaling: renders the same animation (the path, or a 2 s orbit) in fixed-rate time at\n"
          "  1..N threads (--threads, default the number of CPUs), --rounds times each (default 3,\n"
          "  alternating), and prints per thread count a SCALING line: median wall time, speed-up\n"
          "  and the fraction of linear speed-up. Default display: convert (the work a scan-out\n"
          "  display does), so the display stage's overlap with rendering is measured too.\n"
          "  Per frame barrier (medians over the rounds): serial_ms_per_frame (the serial section,\n"
          "  one thread working), release_ms_per_frame (its end to the last thread leaving the\n"
          "  barrier), wait_ms_per_frame (a thread's time at the barrier: idle at the frame's end,\n"
          "  serial section and release); cpu_ms_per_frame: the process's CPU time a frame (less\n"
          "  sensitive to other programs than wall time); *_min: the smallest over the rounds.\n"
          "  --scene FILE     JSON scene or mesh file (default: the built-in scene)\n"
          "  --size WxH       image size (default 1280x720)\n"
          "  --frames N       --scaling: frames per run (default: the path at --rate, or 48)\n"
          "  --thread-counts LIST  --scaling: run these thread counts (comma-separated, e.g.\n"
          "                   1,2,8,64; more threads than CPUs oversubscribe them) instead of 1..N;\n"
          "                   the speed-up is against the first, taken as linear up to it\n"
          "  --keep-noisy     --scaling: keep runs during which other programs were busy (for a control\n"
          "                   that runs copies side by side); by default such runs are repeated\n",
          f);
    cli_pipeline_usage(f, "bench sets it: real for --path, fixed for --scaling", "30");
}

int cli_bench_path(int argc, char **argv)
{
    cli_pipeline_spec spec;
    cli_pipeline_spec_default(&spec, "null", NULL);
    const char *scene_path = NULL;
    bool scaling = false, reject_noisy = true;
    int rounds = SCALING_DEFAULT_ROUNDS, flip_samples = -1;
    int counts[SCALING_MAX_COUNTS], n_counts = 0; /* --thread-counts; 0: 1..--threads */
    const char *config = cli_pipeline_find_config(argc, argv);
    if (config && !cli_pipeline_config_load(config, &spec))
        return 2;
    bool display_given = false;
    cli_given given = {.count = 0};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        bool handled;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        }
        cli_given_add(&given, a);
        display_given = display_given || !strcmp(a, "--display");
        if (!cli_pipeline_option(argc, argv, &i, &spec, &handled))
            return 2;
        if (handled)
            continue;
        if (!strcmp(a, "--scaling")) {
            scaling = true;
        } else if (!strcmp(a, "--flip-samples")) {
            if (!(val = cli_option_value(argc, argv, &i)) ||
                !cli_parse_int(a, val, 0, BENCH_PATH_MAX_FLIP_SAMPLES, &flip_samples))
                return 2;
        } else if (!strcmp(a, "--thread-counts")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !parse_counts(a, val, counts, &n_counts))
                return 2;
        } else if (!strcmp(a, "--keep-noisy")) {
            reject_noisy = false;
        } else if (!strcmp(a, "--rounds")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 1000, &rounds))
                return 2;
        } else if (!strcmp(a, "--scene")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return 2;
            scene_path = strcmp(val, "default") ? val : NULL;
        } else {
            cli_error("unknown option '%s' (see 'tessera bench --help')", a);
            return 2;
        }
    }
    if (!scaling && !spec.path_file[0]) {
        cli_error("bench: --path FILE or --scaling is required here");
        return 2;
    }
    if (!cli_check_ignored_bench(&given, &spec, scaling ? "--scaling" : "--path"))
        return 2;
    if (scaling && !display_given && !config)
        snprintf(spec.channels[0].display, sizeof spec.channels[0].display, "convert");
    if (!scaling)
        spec.time_mode = PIPELINE_TIME_REAL;
    if (n_counts && !scaling) {
        cli_error("--thread-counts: an option of bench --scaling");
        return 2;
    }
    cli_scene cs;
    int max_threads = spec.threads;
    if (!n_counts)
        for (int n = 1; n <= max_threads && n_counts < SCALING_MAX_COUNTS; n++)
            counts[n_counts++] = n;
    if (!cli_scene_prepare(scene_path, max_threads, &cs)) {
        cli_scene_finish(&cs);
        return 1;
    }
    if (flip_samples < 0)
        flip_samples = spec.budget_ms > 0.0 ? BENCH_PATH_DEFAULT_FLIP_SAMPLES : 0;
    int code = scaling ? bench_scaling(&spec, &cs, counts, n_counts, rounds, reject_noisy)
                       : bench_path(&spec, &cs, flip_samples);
    cli_scene_finish(&cs);
    return code;
}
