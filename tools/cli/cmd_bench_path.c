/* cmd_bench_path.c - `tessera bench --path` (camera transactions sent from a
 * path at a fixed rate, like a user steering, with the frame rate each one
 * saw) and `tessera bench --scaling` (the same animation at 1..N threads and
 * the fraction of linear speed-up at each). */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "engine/scene.h"
#include "option_check.h"
#include "pipeline_cli.h"

#define BENCH_PATH_MAX_TRANSACTIONS 1000000
#define SCALING_DEFAULT_ROUNDS 3
#define SCALING_DEFAULT_FRAMES 48

/* Per-frame durations, kept by a serial callback (serial section only). */
typedef struct frame_clock {
    double *frame_s;  /* frame_s[f]: wall time of loop step f (display f-1 + render f) */
    size_t count, capacity;
} frame_clock;

static void clock_tick(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    frame_clock *fc = ctx;
    if (fi->frame == 0)
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

static void print_path_report(const path_sender *s, frame_clock *fc, const cli_pipeline_spec *spec)
{
    printf("# txn time_s frame frame_ms fps (the frame that first showed the transaction)\n");
    for (size_t k = 0; k < s->transactions; k++) {
        uint64_t f = s->applied_at[k];
        double frame_s = f < fc->count ? fc->frame_s[f] : NAN;
        printf("txn %zu %.4f %llu %.2f %.1f\n", k, (double)k / s->rate_hz, (unsigned long long)f, 1e3 * frame_s,
               1.0 / frame_s);
    }
    size_t frames = fc->count;
    double worst = 0.0;
    for (size_t i = 0; i < frames; i++)
        worst = fc->frame_s[i] > worst ? fc->frame_s[i] : worst;
    double med = cli_median(fc->frame_s, frames);
    printf("BENCH_PATH transactions=%zu frames=%zu rate_hz=%g threads=%d size=%dx%d median_frame_ms=%.3f "
           "worst_frame_ms=%.3f median_fps=%.2f refused=%zu\n",
           s->transactions, frames, s->rate_hz, spec->threads, spec->channels[0].width_px,
           spec->channels[0].height_px, 1e3 * med, 1e3 * worst, med > 0.0 ? 1.0 / med : 0.0,
           atomic_load(&s->refused));
}

static int bench_path(cli_pipeline_spec *spec, const cli_scene *cs)
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
    frame_clock fc = {NULL, 0, 0};
    spec->channels[0].camera = camera_path_eval(&path, path.keys[0].time_s);
    spec->channels[0].have_camera = true;
    spec->frames = 0; /* until the path ends */
    pipeline *p = s.applied_at ? cli_pipeline_create(spec, cs) : NULL;
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
            else {
                print_path_report(&s, &fc, spec);
                cli_pipeline_report(p, spec);
                code = 0;
            }
        }
    }
    pipeline_destroy(p);
    free(s.applied_at);
    free(fc.frame_s);
    camera_path_free(&path);
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
} scaling_sample;

/* One timed run of the animation at `threads`. */
static bool scaling_run_once(cli_pipeline_spec *spec, const cli_scene *cs, const camera_path *path, int threads,
                             scaling_sample *out)
{
    tess_error err = {{0}};
    spec->threads = threads;
    pipeline *p = cli_pipeline_create(spec, cs);
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
    pipeline_destroy(p);
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

static int bench_scaling(cli_pipeline_spec *spec, const cli_scene *cs, int max_threads, int rounds,
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
    size_t n_samples = (size_t)max_threads * (size_t)rounds;
    scaling_sample *samples = calloc(n_samples, sizeof *samples);
    double *scratch = calloc((size_t)rounds, sizeof *scratch);
    int code = 1, rejected = 0;
    if (!samples || !scratch) {
        cli_error("out of memory");
        goto done;
    }
    /* rounds alternate over the thread counts, so slow drifts of the machine hit all alike */
    for (int r = 0; r < rounds; r++)
        for (int n = 1; n <= max_threads; n++)
            if (!scaling_run(spec, cs, have_path ? &path : NULL, n, reject_noisy, &samples[(n - 1) * rounds + r],
                             &rejected))
                goto done;
    printf("# %d frames %dx%d, display %s, %d rounds, %d noisy runs repeated; medians; fraction = speed-up / "
           "threads\n",
           spec->frames, spec->channels[0].width_px, spec->channels[0].height_px, spec->channels[0].display, rounds,
           rejected);
    double base = 0.0;
    for (int n = 1; n <= max_threads; n++) {
        const scaling_sample *row = &samples[(n - 1) * rounds];
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
        if (n == 1)
            base = t;
        double speedup = base / t;
        printf("SCALING threads=%d median_s=%.4f min_s=%.4f max_s=%.4f frames_per_s=%.2f speedup=%.3f "
               "fraction_of_linear=%.3f display_ms_per_frame=%.2f barrier_share=%.4f cpu_other_s=%.3f\n",
               n, t, lo, hi, spec->frames / t, speedup, speedup / n, d, wait, other);
    }
    code = 0;
done:
    free(samples);
    free(scratch);
    camera_path_free(&path);
    return code;
}

/* ---------------------------------------------------------------- the command */

static void usage(FILE *f)
{
    fputs("usage: tessera bench --path FILE [--rate HZ] [options]\n"
          "       tessera bench --scaling [--path FILE] [--threads N] [--rounds R] [options]\n"
          "--path: a sender thread queues one camera transaction per 1/HZ s of the camera path\n"
          "  (--rate, default 30), as a user steering would, while the pipeline renders as fast as it\n"
          "  can (real time). Prints per transaction 'txn K TIME FRAME FRAME_MS FPS' (the frame that\n"
          "  first showed it) and a BENCH_PATH line with the median and worst frame time.\n"
          "--scaling: renders the same animation (the path, or a 2 s orbit) in fixed-rate time at\n"
          "  1..N threads (--threads, default the number of CPUs), --rounds times each (default 3,\n"
          "  alternating), and prints per thread count a SCALING line: median wall time, speed-up\n"
          "  and the fraction of linear speed-up. Default display: convert (the work a scan-out\n"
          "  display does), so the display stage's overlap with rendering is measured too.\n"
          "  --scene FILE     JSON scene or mesh file (default: the built-in scene)\n"
          "  --size WxH       image size (default 1280x720)\n"
          "  --frames N       --scaling: frames per run (default: the path at --rate, or 48)\n"
          "  --keep-noisy     --scaling: keep runs during which other programs were busy (for a control\n"
          "                   that runs copies side by side); by default such runs are repeated\n",
          f);
    cli_pipeline_usage(f);
}

int cli_bench_path(int argc, char **argv)
{
    cli_pipeline_spec spec;
    cli_pipeline_spec_default(&spec, "null", NULL);
    const char *scene_path = NULL;
    bool scaling = false, reject_noisy = true;
    int rounds = SCALING_DEFAULT_ROUNDS;
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
    cli_scene cs;
    int max_threads = spec.threads;
    if (!cli_scene_prepare(scene_path, max_threads, &cs)) {
        cli_scene_finish(&cs);
        return 1;
    }
    int code = scaling ? bench_scaling(&spec, &cs, max_threads, rounds, reject_noisy) : bench_path(&spec, &cs);
    cli_scene_finish(&cs);
    return code;
}
