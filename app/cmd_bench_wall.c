/* cmd_bench_wall.c - `tessera bench --wall FILE`: frame time of a display
 * wall, rendered headless in fixed-rate time with a moving camera, two ways:
 *   whole: every output a channel of one pipeline (one set of render threads,
 *          one tile counter over all outputs), as `tessera run --wall` runs it;
 *   alone: each output by itself, a one-channel pipeline with that output's
 *          window of the wall camera, its size and its display;
 * for every display kind asked for (the headless display backends), so the lines show
 * what sharing one pipeline across outputs buys or costs, and what handing
 * frames to the outputs costs. Rounds alternate over all the runs, as
 * `bench --scaling` does, so a noisy machine hits them alike; a run during
 * which other programs were busy is repeated. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "option_check.h"
#include "pipeline_cli.h"
#include "wall/display_backend.h"
#include "wall/wall_config.h"
#include "wall/wall_headless.h"

#define WALL_DEFAULT_FRAMES 24
#define WALL_MIN_FRAMES 3     /* frame times are loop steps 0..frames-2: at least two */
#define WALL_DEFAULT_ROUNDS 3
#define WALL_WARMUP_FRAMES 3  /* the untimed run first (page faults, caches, the dump directory) */
#define WALL_MAX_SIZE_SCALE 4.0
#define WALL_DEFAULT_DISPLAYS "null,convert"

/* As bench --scaling: a run during which other programs took more than this
 * fraction of its wall time in CPU (and more than the floor: /proc/stat
 * counts 10 ms ticks) is repeated, up to WALL_MAX_ATTEMPTS runs in all. */
#define WALL_NOISE_FRACTION 0.02
#define WALL_NOISE_FLOOR_S 0.03
#define WALL_MAX_ATTEMPTS 4

/* Before each run, wait (--quiet-wait: at most that long in all) for a
 * moment in which other programs used under WALL_QUIET_CPU CPUs over
 * WALL_QUIET_SAMPLE_S. */
#define WALL_QUIET_SAMPLE_S 0.25
#define WALL_QUIET_CPU 0.1
#define WALL_DEFAULT_QUIET_WAIT_S 300.0

/* ---------------------------------------------------------------- display kinds */

/* The kinds are the headless display backends (wall/display_backend.h: those
 * with a `create`): a new one there is measurable here. A kind that writes
 * files gets OUT_DIR/bench-RUN-CONNECTOR.png, one file rewritten every frame. */
static image_display *kind_display(const display_backend *kind, const char *out_dir, const char *run,
                                   const wall_output *o, tess_error *err)
{
    char pattern[CLI_PATTERN_BYTES] = "";
    if (kind->options & DISPLAY_OPTION_OUT) {
        int n = snprintf(pattern, sizeof pattern, "%s/bench-%s-%s.png", out_dir, run, o->connector);
        if (n < 0 || (size_t)n >= sizeof pattern) {
            tess_error_set(err, "--out %s: path too long", out_dir);
            return NULL;
        }
    }
    display_backend_args args = {pattern, false, NULL};
    return kind->create(&args, err);
}

static const display_backend *kind_by_name(const char *name, size_t len)
{
    for (size_t k = 0; k < display_backend_count; k++)
        if (display_backends[k].create && strlen(display_backends[k].name) == len &&
            !strncmp(display_backends[k].name, name, len))
            return &display_backends[k];
    return NULL;
}

/* ---------------------------------------------------------------- the benchmark's state */

typedef struct wall_sample {
    double frame_ms;   /* median loop step of the run (display of frame f-1 + render of frame f) */
    double display_ms; /* thread 0's display stage per displayed frame (all the run's outputs) */
    double cpu_other;  /* CPU seconds other programs took during the run */
    double run_s;      /* wall time of pipeline_run */
} wall_sample;

typedef struct wall_variant {
    const display_backend *kind;
    int output;           /* the output rendered alone, or -1: the whole wall */
    wall_sample *samples; /* one per round */
    int repeated;         /* noisy runs thrown away and run again */
    int noisy_kept;       /* rounds noisy in every attempt (WALL_MAX_ATTEMPTS, or 1 with --keep-noisy) */
} wall_variant;

typedef struct bench_wall {
    cli_pipeline_spec spec;   /* threads, rate, frames, traverser, sampler, renderer */
    const cli_scene *cs;
    wall_config wall;         /* pixel sizes resolved and scaled */
    int stitched_w, stitched_h; /* the stitched wall at the config's sizes (unscaled) */
    long long wall_pixels;
    camera_desc camera;       /* the wall's one camera (its start: it moves) */
    bool have_path;
    camera_path path;
    const char *path_file;
    const char *out_dir;
    double size_scale;
    const display_backend *kinds[DISPLAY_BACKENDS_MAX];
    int kind_count;
    int rounds;
    bool reject_noisy;
    double quiet_wait_s;      /* waiting budget left; < 0 until given */
    double waited_s;          /* spent waiting */
    wall_variant *variants;   /* kind k: variants[k * (outputs + 1)] the wall, then the outputs */
    int variant_count;
    double *scratch;          /* frames doubles */
} bench_wall;

/* ---------------------------------------------------------------- one run */

typedef struct step_clock {
    double *ms;
    int count, capacity;
} step_clock;

static void step_tick(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    step_clock *c = ctx;
    if (fi->frame > 0 && c->count < c->capacity)
        c->ms[c->count++] = 1e3 * fi->last_frame_s;
}

/* The pipeline of a run: every output as a channel (output -1), or that one
 * output alone; each its window of the wall camera's image plane, with
 * `kind`'s display. */
static pipeline *make_pipeline(const bench_wall *b, const display_backend *kind, int output, int frames,
                               tess_error *err)
{
    pipeline_config cfg = cli_pipeline_config(&b->spec, b->cs);
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE; /* the same frames for every run */
    cfg.max_frames = (uint64_t)frames;
    pipeline *p = pipeline_create(&cfg, err);
    if (!p)
        return NULL;
    int first = output < 0 ? 0 : output, last = output < 0 ? b->wall.count : output + 1;
    for (int i = first; i < last; i++) {
        const wall_output *o = &b->wall.outputs[i];
        image_display *d = kind_display(kind, b->out_dir, output < 0 ? "wall" : "alone", o, err);
        /* the pipeline owns d from pipeline_add_channel_window on, also on failure */
        if (!d || pipeline_add_channel_window(p, &b->camera, wall_plane_aspect(&b->wall),
                                              wall_output_window(&b->wall, i), o->width_px, o->height_px, d,
                                              err) < 0) {
            tess_error_prefix(err, "output %s: ", o->connector);
            pipeline_destroy(p);
            return NULL;
        }
    }
    return p;
}

/* Run `v` once for `frames` frames; *out gets its figures. */
static bool run_once(bench_wall *b, const wall_variant *v, int frames, wall_sample *out)
{
    tess_error err = {{0}};
    pipeline *p = make_pipeline(b, v->kind, v->output, frames, &err);
    if (!p) {
        cli_error("%s: %s", b->spec.wall_file, err.msg);
        return false;
    }
    step_clock clock = {b->scratch, 0, frames};
    cli_path_player player = {.all_channels = true};
    cli_orbit orbit = {.all_channels = true};
    bool ok;
    if (b->have_path) {
        player.path = b->path; /* borrowed */
        player.time_offset_s = b->path.keys[0].time_s;
        ok = cli_path_player_start(p, &player);
    } else {
        ok = cli_orbit_start(p, &orbit, CLI_ORBIT_PERIOD_S);
    }
    ok = ok && pipeline_add_serial_animation(p, "frame clock", step_tick, &clock);
    if (!ok) {
        cli_error("cannot register the animation callbacks");
        pipeline_destroy(p);
        return false;
    }
    double busy0 = cli_machine_busy_s(), own0 = cli_own_cpu_s();
    ok = pipeline_run(p, &err);
    double busy1 = cli_machine_busy_s(), own1 = cli_own_cpu_s();
    if (!ok)
        cli_error("%s", err.msg);
    pipeline_stats st = pipeline_get_stats(p);
    out->frame_ms = cli_median(clock.ms, (size_t)clock.count);
    out->display_ms = st.frames_displayed ? 1e3 * st.display_s / (double)st.frames_displayed : 0.0;
    out->cpu_other = busy0 < 0.0 || busy1 < 0.0 ? 0.0 : fmax(0.0, (busy1 - busy0) - (own1 - own0));
    out->run_s = st.run_s;
    pipeline_destroy(p);
    return ok;
}

static bool sample_noisy(const wall_sample *s)
{
    return s->cpu_other > fmax(WALL_NOISE_FRACTION * s->run_s, WALL_NOISE_FLOOR_S);
}

/* Wait for a quiet moment, within what is left of the budget. */
static void wait_for_quiet(bench_wall *b)
{
    while (b->quiet_wait_s > 0.0) {
        double busy0 = cli_machine_busy_s(), own0 = cli_own_cpu_s(), t0 = cli_now_s();
        if (busy0 < 0.0)
            return; /* /proc/stat unreadable: nothing to wait for */
        struct timespec ts = {0, (long)(WALL_QUIET_SAMPLE_S * 1e9)};
        nanosleep(&ts, NULL);
        double dt = cli_now_s() - t0, other = (cli_machine_busy_s() - busy0) - (cli_own_cpu_s() - own0);
        b->waited_s += dt;
        b->quiet_wait_s -= dt;
        if (other < WALL_QUIET_CPU * dt)
            return;
    }
}

/* Round r of variant v, repeated while the machine was busy with other work;
 * when every attempt was noisy, the least disturbed one (the smallest share
 * of its run time other programs took) is kept. */
static bool run_variant(bench_wall *b, wall_variant *v, int r)
{
    int attempts = b->reject_noisy ? WALL_MAX_ATTEMPTS : 1;
    wall_sample best = {0.0, 0.0, INFINITY, 1.0};
    for (int a = 0; a < attempts; a++) {
        wall_sample s;
        wait_for_quiet(b);
        if (!run_once(b, v, b->spec.frames, &s))
            return false;
        if (!sample_noisy(&s)) {
            v->samples[r] = s;
            return true;
        }
        if (s.cpu_other / fmax(s.run_s, 1e-9) < best.cpu_other / fmax(best.run_s, 1e-9))
            best = s;
        if (a + 1 < attempts)
            v->repeated++;
    }
    v->samples[r] = best;
    v->noisy_kept++;
    return true;
}

/* ---------------------------------------------------------------- the report */

typedef struct variant_summary {
    double frame_ms, min_ms, max_ms, display_ms, cpu_other;
} variant_summary;

static variant_summary summarize(const bench_wall *b, const wall_variant *v, double *tmp)
{
    variant_summary s = {0.0, INFINITY, 0.0, 0.0, 0.0};
    int n = b->rounds;
    for (int r = 0; r < n; r++) {
        tmp[r] = v->samples[r].frame_ms;
        s.min_ms = fmin(s.min_ms, tmp[r]);
        s.max_ms = fmax(s.max_ms, tmp[r]);
    }
    s.frame_ms = cli_median(tmp, (size_t)n);
    for (int r = 0; r < n; r++)
        tmp[r] = v->samples[r].display_ms;
    s.display_ms = cli_median(tmp, (size_t)n);
    for (int r = 0; r < n; r++)
        tmp[r] = v->samples[r].cpu_other;
    s.cpu_other = cli_median(tmp, (size_t)n);
    return s;
}

static wall_variant *variant_of(const bench_wall *b, int kind, int output)
{
    return &b->variants[kind * (b->wall.count + 1) + 1 + output]; /* output -1: the wall */
}

/* Median over the rounds of (sum of the outputs alone) / (the wall), round by round. */
static double sum_over_wall(const bench_wall *b, int kind, double *tmp)
{
    for (int r = 0; r < b->rounds; r++) {
        double sum = 0.0;
        for (int i = 0; i < b->wall.count; i++)
            sum += variant_of(b, kind, i)->samples[r].frame_ms;
        double whole = variant_of(b, kind, -1)->samples[r].frame_ms;
        tmp[r] = whole > 0.0 ? sum / whole : 0.0;
    }
    return cli_median(tmp, (size_t)b->rounds);
}

/* The wall's frame time with `kind` against the baseline kind 0, round by
 * round: medians of the difference (ms) and of the ratio. */
static void cost_against_baseline(const bench_wall *b, int kind, double *tmp, double *cost_ms, double *ratio)
{
    const wall_variant *v = variant_of(b, kind, -1), *base = variant_of(b, 0, -1);
    for (int r = 0; r < b->rounds; r++)
        tmp[r] = v->samples[r].frame_ms - base->samples[r].frame_ms;
    *cost_ms = cli_median(tmp, (size_t)b->rounds);
    for (int r = 0; r < b->rounds; r++)
        tmp[r] = base->samples[r].frame_ms > 0.0 ? v->samples[r].frame_ms / base->samples[r].frame_ms : 0.0;
    *ratio = cli_median(tmp, (size_t)b->rounds);
}

/* A path as one space-free field: whitespace and '%' as %XX. */
static void print_field(const char *text)
{
    for (const unsigned char *p = (const unsigned char *)text; *p; p++) {
        if (*p <= ' ' || *p == '%' || *p == 0x7f)
            printf("%%%02X", *p);
        else
            putchar(*p);
    }
}

static double per_s(double ms) { return ms > 0.0 ? 1e3 / ms : 0.0; }

static void print_machine_lines(const bench_wall *b, double *tmp)
{
    const cli_pipeline_spec *s = &b->spec;
    int n_out = b->wall.count;
    for (int k = 0; k < b->kind_count; k++) {
        const char *kn = b->kinds[k]->name;
        double sum_ms = 0.0;
        for (int i = 0; i < n_out; i++) {
            const wall_output *o = &b->wall.outputs[i];
            const wall_variant *v = variant_of(b, k, i);
            variant_summary m = summarize(b, v, tmp);
            long long px = (long long)o->width_px * o->height_px;
            sum_ms += m.frame_ms;
            printf("BENCH_WALL output=%s display=%s size=%dx%d pixels=%lld frames=%d rounds=%d threads=%d "
                   "median_ms=%.3f min_ms=%.3f max_ms=%.3f fps=%.3f mpix_s=%.3f display_ms=%.3f cpu_other_s=%.3f "
                   "repeated=%d noisy=%d\n",
                   o->connector, kn, o->width_px, o->height_px, px, s->frames, b->rounds, s->threads, m.frame_ms,
                   m.min_ms, m.max_ms, per_s(m.frame_ms), 1e-3 * (double)px * per_s(m.frame_ms) * 1e-3,
                   m.display_ms, m.cpu_other, v->repeated, v->noisy_kept);
        }
        const wall_variant *w = variant_of(b, k, -1);
        variant_summary m = summarize(b, w, tmp);
        printf("BENCH_WALL wall=");
        print_field(s->wall_file);
        printf(" display=%s outputs=%d pixels=%lld frames=%d rounds=%d threads=%d median_ms=%.3f min_ms=%.3f "
               "max_ms=%.3f fps=%.3f mpix_s=%.3f display_ms=%.3f display_ms_per_output=%.3f outputs_sum_ms=%.3f "
               "sum_over_wall=%.4f cpu_other_s=%.3f repeated=%d noisy=%d\n",
               kn, n_out, b->wall_pixels, s->frames, b->rounds, s->threads, m.frame_ms, m.min_ms, m.max_ms,
               per_s(m.frame_ms), 1e-6 * (double)b->wall_pixels * per_s(m.frame_ms), m.display_ms,
               m.display_ms / n_out, sum_ms, sum_over_wall(b, k, tmp), m.cpu_other, w->repeated, w->noisy_kept);
    }
    for (int k = 0; k < b->kind_count; k++) {
        double cost_ms, ratio, alone_display = 0.0;
        cost_against_baseline(b, k, tmp, &cost_ms, &ratio);
        variant_summary m = summarize(b, variant_of(b, k, -1), tmp), base = summarize(b, variant_of(b, 0, -1), tmp);
        for (int i = 0; i < n_out; i++)
            alone_display += summarize(b, variant_of(b, k, i), tmp).display_ms / n_out;
        printf("BENCH_WALL_DISPLAY display=%s baseline=%s wall_ms=%.3f baseline_ms=%.3f cost_ms=%.3f cost_ratio=%.4f "
               "display_ms_per_output=%.3f alone_display_ms_per_output=%.3f\n",
               b->kinds[k]->name, b->kinds[0]->name, m.frame_ms, base.frame_ms, cost_ms, ratio, m.display_ms / n_out,
               alone_display);
    }
    int repeated = 0, noisy = 0;
    for (int v = 0; v < b->variant_count; v++) {
        repeated += b->variants[v].repeated;
        noisy += b->variants[v].noisy_kept;
    }
    printf("BENCH_WALL_NOISE runs=%d repeated=%d noisy=%d waited_s=%.1f\n", b->variant_count * b->rounds, repeated,
           noisy, b->waited_s);
}

static void print_summary(const bench_wall *b, double *tmp)
{
    const cli_pipeline_spec *s = &b->spec;
    int n_out = b->wall.count, repeated = 0, noisy = 0;
    for (int v = 0; v < b->variant_count; v++) {
        repeated += b->variants[v].repeated;
        noisy += b->variants[v].noisy_kept;
    }
    printf("#\n# %s: %d output%s, %lld pixels a frame%s; %d frames a run in fixed-rate time at %g Hz, camera %s%s;\n"
           "# %d threads, %d rounds alternating over %d runs, %d noisy run%s repeated, %d kept noisy,\n"
           "# %.0f s spent waiting for quiet moments.\n"
           "# frame ms: median over the rounds of each run's median loop step (min-max over the rounds);\n"
           "# display ms: the pipeline's display stage per frame (thread 0, all the run's outputs).\n#\n",
           s->wall_file, n_out, n_out == 1 ? "" : "s", b->wall_pixels,
           b->size_scale != 1.0 ? " (sizes scaled)" : "", s->frames, s->rate_hz,
           b->have_path ? "path " : "orbiting (2 s a turn)", b->have_path ? b->path_file : "", s->threads,
           b->rounds, b->variant_count, repeated, repeated == 1 ? "" : "s", noisy, b->waited_s);
    printf("# %-8s %-14s %-10s %9s %-19s %8s %8s %11s\n", "display", "target", "size", "frame ms", "(min-max)", "fps",
           "Mpx/s", "display ms");
    for (int k = 0; k < b->kind_count; k++) {
        const char *kn = b->kinds[k]->name;
        variant_summary m = summarize(b, variant_of(b, k, -1), tmp);
        char range[64], size[32];
        snprintf(range, sizeof range, "(%.1f-%.1f)", m.min_ms, m.max_ms);
        snprintf(size, sizeof size, "%d outputs", n_out);
        printf("# %-8s %-14s %-10s %9.1f %-19s %8.2f %8.2f %11.2f\n", kn, "whole wall", size, m.frame_ms, range,
               per_s(m.frame_ms), 1e-6 * (double)b->wall_pixels * per_s(m.frame_ms), m.display_ms);
        double sum_ms = 0.0;
        for (int i = 0; i < n_out; i++) {
            const wall_output *o = &b->wall.outputs[i];
            variant_summary a = summarize(b, variant_of(b, k, i), tmp);
            sum_ms += a.frame_ms;
            snprintf(range, sizeof range, "(%.1f-%.1f)", a.min_ms, a.max_ms);
            snprintf(size, sizeof size, "%dx%d", o->width_px, o->height_px);
            printf("# %-8s %-14s %-10s %9.1f %-19s %8.2f %8.2f %11.2f\n", kn, o->connector, size, a.frame_ms, range,
                   per_s(a.frame_ms), 1e-6 * (double)o->width_px * o->height_px * per_s(a.frame_ms), a.display_ms);
        }
        double ratio = sum_over_wall(b, k, tmp);
        printf("# %-8s outputs alone, summed: %.1f ms a wall frame = %.3f x the whole wall's (%s)\n", kn, sum_ms,
               ratio, ratio >= 1.0 ? "one pipeline for all outputs is faster" : "one pipeline for all outputs is slower");
    }
    printf("#\n# handing frames to the outputs, whole wall, against %s (round by round):\n", b->kinds[0]->name);
    for (int k = 0; k < b->kind_count; k++) {
        double cost_ms, ratio;
        cost_against_baseline(b, k, tmp, &cost_ms, &ratio);
        variant_summary m = summarize(b, variant_of(b, k, -1), tmp);
        printf("#   %-8s %+8.1f ms a frame (x %.3f); display stage %.2f ms per output per frame: %s\n",
               b->kinds[k]->name, cost_ms, ratio, m.display_ms / n_out, b->kinds[k]->what);
    }
}

/* ---------------------------------------------------------------- setup */

/* Read the wall, resolve its outputs' pixel sizes without a device and scale them. */
static bool load_wall(bench_wall *b)
{
    tess_error err = {{0}};
    const char *file = b->spec.wall_file;
    bool ok = wall_config_load(file, &b->wall, &err) && wall_config_headless_sizes(&b->wall, &err);
    if (!ok) { /* the headless check names the output, not the file */
        cli_error("%s%s%s", strstr(err.msg, file) ? "" : file, strstr(err.msg, file) ? "" : ": ", err.msg);
        return false;
    }
    /* the camera is chosen for the stitched wall at the config's own sizes, as 'run --wall' does */
    wall_stitched_size(&b->wall, &b->stitched_w, &b->stitched_h);
    b->wall_pixels = 0;
    for (int i = 0; i < b->wall.count; i++) {
        wall_output *o = &b->wall.outputs[i];
        long w = lround(o->width_px * b->size_scale), h = lround(o->height_px * b->size_scale);
        if (w > CLI_MAX_IMAGE_EDGE_PX || h > CLI_MAX_IMAGE_EDGE_PX) {
            cli_error("--size-scale %g: output %s of %s would be %ldx%ld; at most %d pixels an edge", b->size_scale,
                      o->connector, file, w, h, CLI_MAX_IMAGE_EDGE_PX);
            return false;
        }
        o->width_px = w < 1 ? 1 : (int)w;
        o->height_px = h < 1 ? 1 : (int)h;
        b->wall_pixels += (long long)o->width_px * o->height_px;
    }
    return true;
}

/* --display LIST: comma-separated kind names. */
static bool parse_displays(const char *list, bench_wall *b)
{
    b->kind_count = 0;
    const char *p = list;
    for (;;) {
        size_t len = strcspn(p, ",");
        const display_backend *k = kind_by_name(p, len);
        if (len == 0) {
            cli_error("--display: empty name in '%s' (expected names separated by single commas)", list);
            return false;
        }
        if (!k) {
            char names[256] = "";
            for (size_t i = 0; i < display_backend_count; i++)
                if (display_backends[i].create)
                    snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", names[0] ? ", " : "",
                             display_backends[i].name);
            cli_error("--display: unknown display '%.*s' for bench --wall (expected a comma-separated list of: %s)",
                      (int)len, p, names);
            return false;
        }
        for (int i = 0; i < b->kind_count; i++)
            if (b->kinds[i] == k) {
                cli_error("--display: '%s' is listed twice in '%s'", k->name, list);
                return false;
            }
        b->kinds[b->kind_count++] = k;
        if (!p[len])
            return true;
        p += len + 1;
    }
}

static bool parse_scale(const char *option, const char *text, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end || errno == ERANGE || !(v > 0.0 && v <= WALL_MAX_SIZE_SCALE)) {
        cli_error("%s: expected a number in (0, %g], got '%s'", option, WALL_MAX_SIZE_SCALE, text);
        return false;
    }
    *out = v;
    return true;
}

static bool out_dir_ok(const char *dir)
{
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        cli_error("--out %s: not an existing directory", dir);
        return false;
    }
    if (access(dir, W_OK) != 0) {
        cli_error("--out %s: directory not writable: %s", dir, strerror(errno));
        return false;
    }
    return true;
}

static void usage(FILE *f)
{
    fputs("usage: tessera bench --wall FILE [--display LIST] [--frames N] [--rounds R] [options]\n"
          "Frame time of a display wall (configs/walls/*.json, docs/wall-format.md), rendered headless\n"
          "in fixed-rate time while the camera moves (an orbit, or --camera-path), two ways:\n"
          "  whole wall: every output a channel of one pipeline (one set of render threads, one tile\n"
          "              counter over all outputs), as 'tessera run --wall' renders it;\n"
          "  alone:      each output by itself, a one-channel pipeline with its window of the wall\n"
          "              camera, its size and its display;\n"
          "the same frames each time, for every display kind in LIST. One untimed warm-up run first;\n"
          "then each round runs all of these once, in alternating order (reversed every other round),\n"
          "so that a noisy machine hits them alike. Each run waits for a quiet moment first (see\n"
          "--quiet-wait); a run during which other programs took over 2 % of its time in CPU is\n"
          "repeated, up to 4 runs (if all 4 are noisy, the least disturbed one is kept).\n"
          "\n"
          "options:\n"
          "  --wall FILE       the wall (required); its modes must be explicit (no device is used)\n"
          "  --display LIST    comma-separated display kinds, each measured in the same run (default\n"
          "                    " WALL_DEFAULT_DISPLAYS "); the first is the baseline the others' cost is given\n"
          "                    against:\n",
          f);
    for (size_t k = 0; k < display_backend_count; k++)
        if (display_backends[k].create)
            fprintf(f, "                      %-13s %s\n", display_backends[k].name, display_backends[k].what);
    fputs("  --out DIR         where dump writes: DIR/bench-wall-CONNECTOR.png and\n"
          "                    DIR/bench-alone-CONNECTOR.png (required with dump, refused without)\n"
          "  --frames N        frames a run, at least 3 (default 24)\n"
          "  --rounds R        rounds, 1..1000 (default 3)\n"
          "  --rate HZ         frames per second of pipeline time (default 30): frame f shows the\n"
          "                    camera at time f / HZ\n"
          "  --camera-path FILE  the camera follows this path (configs/paths/*.json) from its first\n"
          "                    key (default: the wall camera orbits its look-at point, a turn in 2 s)\n"
          "  --camera ex,ey,ez,lx,ly,lz,ux,uy,uz,fov  the wall camera (default: the scene's, else\n"
          "                    the scene framed for the stitched wall, as 'tessera run --wall')\n"
          "  --size-scale S    every output's pixel size times S, in (0, 4] (default 1); the windows\n"
          "                    stay, so the picture is the same with fewer or more pixels\n"
          "  --scene FILE      JSON scene or mesh file (default: the built-in scene)\n"
          "  --threads N       render threads (default: the number of CPUs)\n"
          "  --keep-noisy      keep runs during which other programs were busy (not repeated), and do\n"
          "                    not wait for quiet moments unless --quiet-wait is given\n"
          "  --quiet-wait S    before each run, wait for a quarter second in which other programs used\n"
          "                    under 0.1 CPU, at most S seconds in all (default 300; 0: never wait)\n"
          "  --config FILE     pipeline config (docs/pipeline-config.md): threads, frames,\n"
          "                    time.rate_hz, traverser, sampler, renderer, camera, path (the camera\n"
          "                    path unless --camera-path); its size, display and channels are not used\n"
          "  --tile-size N, --tile-order O, --sampler S, --renderer R, --no-shadows\n"
          "                    as for 'tessera run' (see 'tessera run --help')\n"
          "  --time fixed      accepted: bench --wall always renders in fixed-rate time\n"
          "(bench --wall with --path or --scaling is the path or scaling benchmark on the wall:\n"
          "see 'tessera bench --scaling --help'.)\n"
          "\n"
          "output (stdout), fields key=value:\n"
          "  BENCH_WALL output=CONNECTOR display=D size=WxH pixels= frames= rounds= threads= median_ms=\n"
          "        min_ms= max_ms= fps= mpix_s= display_ms= cpu_other_s= repeated= noisy=\n"
          "      one per output and display kind: the output rendered alone\n"
          "  BENCH_WALL wall=FILE display=D outputs= pixels= frames= rounds= threads= median_ms= min_ms=\n"
          "        max_ms= fps= mpix_s= display_ms= display_ms_per_output= outputs_sum_ms=\n"
          "        sum_over_wall= cpu_other_s= repeated= noisy=\n"
          "      one per display kind: the whole wall\n"
          "  BENCH_WALL_DISPLAY display=D baseline=B wall_ms= baseline_ms= cost_ms= cost_ratio=\n"
          "        display_ms_per_output= alone_display_ms_per_output=\n"
          "      one per display kind: what handing the wall's frames to D costs against B\n"
          "  BENCH_WALL_NOISE runs= repeated= noisy= waited_s=\n"
          "      the measured runs (rounds x runs a round), noisy runs repeated, rounds kept noisy,\n"
          "      seconds spent waiting for quiet moments\n"
          "  then a summary for people, every line starting with '#'.\n"
          "  median_ms       median over the rounds of each run's median loop step (the display of\n"
          "                  frame f-1 on thread 0 overlapping the rendering of frame f); min_ms,\n"
          "                  max_ms: the fastest and slowest round; fps = 1000 / median_ms;\n"
          "                  mpix_s = pixels x fps / 1e6\n"
          "  display_ms      median over the rounds of the pipeline's display stage (thread 0) per\n"
          "                  frame, all the run's outputs; display_ms_per_output = that / outputs\n"
          "  outputs_sum_ms  the outputs' median_ms alone, summed: a wall frame output by output;\n"
          "                  sum_over_wall = median over the rounds of (that sum / the whole wall's\n"
          "                  frame time), > 1 when one pipeline for all outputs is faster\n"
          "  cost_ms         median over the rounds of the whole wall's frame time with D minus with\n"
          "                  B; cost_ratio likewise of D / B\n"
          "  alone_display_ms_per_output  the display stage per frame of the outputs alone, averaged\n"
          "  cpu_other_s     median CPU seconds other programs took during a run; repeated: noisy\n"
          "                  runs run again; noisy: rounds whose run stayed noisy\n"
          "Exit status: 0, 2 for a command-line error, 1 for any other error (one line on stderr).\n",
          f);
}

/* Returns -1 to go on, else the exit status. */
static int parse_options(int argc, char **argv, bench_wall *b, const char **scene_path)
{
    const char *displays = WALL_DEFAULT_DISPLAYS;
    for (int i = 1; i < argc; i++) /* first: 'bench --wall --help' has no FILE */
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        }
    const char *config = cli_pipeline_find_config(argc, argv);
    if (config && !cli_pipeline_config_load(config, &b->spec))
        return 2;
    bool frames_given = b->spec.frames_given && b->spec.frames > 0;
    cli_given given = {.count = 0};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        bool handled;
        cli_given_add(&given, a);
        if (!strcmp(a, "--display")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return 2;
            displays = val;
        } else if (!strcmp(a, "--out")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return 2;
            b->out_dir = val;
        } else if (!strcmp(a, "--rounds")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 1000, &b->rounds))
                return 2;
        } else if (!strcmp(a, "--size-scale")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !parse_scale(a, val, &b->size_scale))
                return 2;
        } else if (!strcmp(a, "--camera-path")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return 2;
            b->path_file = val;
        } else if (!strcmp(a, "--scene")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return 2;
            *scene_path = strcmp(val, "default") ? val : NULL;
        } else if (!strcmp(a, "--keep-noisy")) {
            b->reject_noisy = false;
        } else if (!strcmp(a, "--quiet-wait")) {
            int wait_s;
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 0, 86400, &wait_s))
                return 2;
            b->quiet_wait_s = wait_s;
        } else if (!strcmp(a, "--size") || !strcmp(a, "--record") || !strcmp(a, "--card") || !strcmp(a, "--path")) {
            cli_error("%s: not an option of bench --wall (%s; see 'tessera bench --wall --help')", a,
                      !strcmp(a, "--size")   ? "the sizes are the wall outputs'; --size-scale scales them"
                      : !strcmp(a, "--path") ? "the camera path is --camera-path"
                                             : "it renders headless");
            return 2;
        } else {
            if (!cli_pipeline_option(argc, argv, &i, &b->spec, &handled))
                return 2;
            if (!handled) {
                cli_error("unknown option '%s' (see 'tessera bench --wall --help')", a);
                return 2;
            }
            if (!strcmp(a, "--time") && b->spec.time_mode == PIPELINE_TIME_REAL) {
                cli_error("--time real: bench --wall renders in fixed-rate time (the same frames for every run)");
                return 2;
            }
            if (!strcmp(a, "--frames"))
                frames_given = true;
        }
    }
    if (!b->spec.wall_file[0]) {
        cli_error("bench --wall: FILE is required");
        return 2;
    }
    if (!cli_check_ignored_bench(&given, &b->spec, "--wall"))
        return 2;
    if (!frames_given)
        b->spec.frames = WALL_DEFAULT_FRAMES;
    if (b->spec.frames < WALL_MIN_FRAMES) {
        cli_error("--frames: bench --wall needs at least %d frames a run, got %d", WALL_MIN_FRAMES, b->spec.frames);
        return 2;
    }
    if (!parse_displays(displays, b))
        return 2;
    const display_backend *writer = NULL;
    for (int k = 0; k < b->kind_count; k++)
        writer = writer ? writer : b->kinds[k]->options & DISPLAY_OPTION_OUT ? b->kinds[k] : NULL;
    if (writer && !b->out_dir) {
        cli_error("--display %s: needs --out DIR (where each output's image is rewritten every frame)", writer->name);
        return 2;
    }
    if (!writer && b->out_dir) {
        char writers[128];
        display_backend_names(DISPLAY_OPTION_OUT, " or ", writers, sizeof writers);
        cli_error("--out %s: only the %s display writes files; --display is '%s'", b->out_dir, writers, displays);
        return 2;
    }
    if (b->out_dir && !out_dir_ok(b->out_dir))
        return 2;
    if (!b->path_file && b->spec.path_file[0])
        b->path_file = b->spec.path_file; /* from --config */
    if (b->quiet_wait_s < 0.0) /* not given */
        b->quiet_wait_s = b->reject_noisy ? WALL_DEFAULT_QUIET_WAIT_S : 0.0;
    return -1;
}

/* Every round runs every variant once; odd rounds in reverse order. */
static bool measure(bench_wall *b)
{
    wall_sample warmup;
    fprintf(stderr, "tessera: bench --wall: warm-up run (%d frames of the whole wall)\n", WALL_WARMUP_FRAMES);
    if (!run_once(b, &b->variants[0], WALL_WARMUP_FRAMES, &warmup))
        return false;
    for (int r = 0; r < b->rounds; r++) {
        fprintf(stderr, "tessera: bench --wall: round %d of %d (%d runs)\n", r + 1, b->rounds, b->variant_count);
        for (int j = 0; j < b->variant_count; j++) {
            int v = r % 2 ? b->variant_count - 1 - j : j;
            if (!run_variant(b, &b->variants[v], r))
                return false;
        }
    }
    return true;
}

int cli_bench_wall(int argc, char **argv)
{
    bench_wall b;
    memset(&b, 0, sizeof b);
    cli_pipeline_spec_default(&b.spec, "null", NULL);
    b.size_scale = 1.0;
    b.rounds = WALL_DEFAULT_ROUNDS;
    b.reject_noisy = true;
    b.quiet_wait_s = -1.0;
    const char *scene_path = NULL;
    int code = parse_options(argc, argv, &b, &scene_path);
    if (code >= 0)
        return code;
    tess_error err = {{0}};
    if (b.path_file) {
        if (!camera_path_load(b.path_file, &b.path, &err)) {
            cli_error("%s", err.msg);
            return 1;
        }
        if (b.path.count == 0) {
            cli_error("%s: the camera path has no keys", b.path_file);
            camera_path_free(&b.path);
            return 1;
        }
        b.have_path = true;
    }
    cli_scene cs = {0};
    code = 1;
    if (!load_wall(&b) || !cli_scene_prepare(scene_path, b.spec.threads, &cs))
        goto done;
    b.cs = &cs;
    const cli_channel_spec *main_ch = &b.spec.channels[0];
    if (!cli_scene_camera(&cs, main_ch->have_camera ? &main_ch->camera : NULL, b.stitched_w, b.stitched_h,
                          &b.camera))
        goto done;
    b.variant_count = b.kind_count * (b.wall.count + 1);
    b.variants = calloc((size_t)b.variant_count, sizeof *b.variants);
    b.scratch = calloc((size_t)(b.spec.frames > b.rounds ? b.spec.frames : b.rounds), sizeof *b.scratch);
    bool ok = b.variants && b.scratch;
    for (int v = 0; ok && v < b.variant_count; v++) {
        b.variants[v].kind = b.kinds[v / (b.wall.count + 1)];
        b.variants[v].output = v % (b.wall.count + 1) - 1;
        ok = (b.variants[v].samples = calloc((size_t)b.rounds, sizeof *b.variants[v].samples)) != NULL;
    }
    if (!ok) {
        cli_error("out of memory");
        goto done;
    }
    if (!measure(&b))
        goto done;
    print_machine_lines(&b, b.scratch);
    print_summary(&b, b.scratch);
    fflush(stdout);
    code = 0;
done:
    for (int v = 0; b.variants && v < b.variant_count; v++)
        free(b.variants[v].samples);
    free(b.variants);
    free(b.scratch);
    cli_scene_finish(&cs);
    camera_path_free(&b.path);
    return code;
}
