/* test_pipeline_cli.c - the pipeline through the tessera binary: components by
 * name on the command line and in --config files, channels, camera paths with
 * --record and replay, `bench --path` and `bench --scaling` output, and clear
 * errors for bad options and configs. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/frame/camera_path.h"
#include "support.h"
#include "wall/dump.h"

#define TIMEOUT_S 120

static char tmp_dir[256];

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "pipecli"); }

TestSuite(pipeline_cli, .init = make_tmp_dir, .timeout = 300);

static int run(char *out, size_t out_bytes, const char *args_fmt)
{
    return support_tessera(tmp_dir, TIMEOUT_S, out, out_bytes, args_fmt);
}

static void write_file(const char *name, const char *text) { support_write_file(tmp_dir, name, text); }

static float *read_exr(const char *name, int *w, int *h) { return support_read_image(tmp_dir, name, w, h); }

static void expect_same_exr(const char *a, const char *b)
{
    int wa, ha, wb, hb;
    float *pa = read_exr(a, &wa, &ha), *pb = read_exr(b, &wb, &hb);
    cr_assert(wa == wb && ha == hb, "%s and %s differ in size", a, b);
    cr_expect(!memcmp(pa, pb, (size_t)wa * ha * 3 * sizeof(float)), "%s and %s differ", a, b);
    free(pa);
    free(pb);
}

static void expect_error(const char *args_fmt, const char *const *needles)
{
    support_expect_error(tmp_dir, TIMEOUT_S, args_fmt, needles);
}

#define EXPECT_ERROR(args, ...) expect_error(args, (const char *const[]){__VA_ARGS__, NULL})

Test(pipeline_cli, images_do_not_depend_on_threads_tile_order_or_tile_size)
{
    char out[8192];
    cr_assert_eq(run(out, sizeof out, "render --size 61x37 --threads 1 --out %s/a.exr"), 0, "%s", out);
    cr_assert_eq(run(out, sizeof out, "render --size 61x37 --threads 3 --tile-order hilbert --tile-size 7 "
                                      "--out %s/b.exr"),
                 0, "%s", out);
    cr_assert_eq(run(out, sizeof out, "render --size 61x37 --threads 2 --tile-order shuffle --out %s/c.exr"), 0,
                 "%s", out);
    expect_same_exr("a.exr", "b.exr");
    expect_same_exr("a.exr", "c.exr");
    /* jittered sampling too, and it differs from single sampling */
    cr_assert_eq(run(out, sizeof out, "render --size 61x37 --threads 1 --sampler jittered:2 --out %s/j1.exr"), 0,
                 "%s", out);
    cr_assert_eq(run(out, sizeof out, "render --size 61x37 --threads 3 --tile-order spiral --sampler jittered:2 "
                                      "--out %s/j3.exr"),
                 0, "%s", out);
    expect_same_exr("j1.exr", "j3.exr");
    int w, h;
    float *single = read_exr("a.exr", &w, &h), *jit = read_exr("j1.exr", &w, &h);
    cr_expect(memcmp(single, jit, (size_t)w * h * 3 * sizeof(float)) != 0, "jittered equals single sampling");
    free(single);
    free(jit);
}

Test(pipeline_cli, recorded_path_replays_the_same_frames)
{
    char out[8192];
    write_file("p.json", "{\"format\": \"tessera-camera-path\", \"version\": 1, \"keyframes\": ["
                         "{\"time\": 0, \"eye\": [4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]},"
                         "{\"time\": 0.5, \"eye\": [0, 4, 7], \"look_at\": [0, 0.5, 0], \"fov_deg\": 50},"
                         "{\"time\": 1, \"eye\": [-5, 2, 5], \"look_at\": [0.5, 0.6, 0]}]}");
    cr_assert_eq(run(out, sizeof out, "run --size 40x30 --threads 2 --time fixed --rate 10 --frames 11 "
                                      "--path %s/p.json --record %s/rec.json --out %s/a_####.exr"),
                 0, "%s", out);
    cr_expect(strstr(out, "recorded 11 camera keys"), "%s", out);
    /* the recording holds exactly the cameras the path gave at each frame's time */
    char path[512];
    tess_error err = {{0}};
    camera_path orig = {0}, rec = {0};
    snprintf(path, sizeof path, "%s/p.json", tmp_dir);
    cr_assert(camera_path_load(path, &orig, &err), "%s", err.msg);
    snprintf(path, sizeof path, "%s/rec.json", tmp_dir);
    cr_assert(camera_path_load(path, &rec, &err), "%s", err.msg);
    cr_assert_eq(rec.count, 11);
    for (size_t k = 0; k < rec.count; k++) {
        camera_desc want = camera_path_eval(&orig, (double)k / 10.0);
        cr_expect_eq(rec.keys[k].time_s, (double)k / 10.0);
        cr_expect(!memcmp(&rec.keys[k].camera, &want, sizeof want), "key %zu differs from the path", k);
    }
    camera_path_free(&orig);
    camera_path_free(&rec);
    /* replaying the recording renders the same frames, bit for bit */
    cr_assert_eq(run(out, sizeof out, "run --size 40x30 --threads 3 --time fixed --rate 10 --frames 11 "
                                      "--path %s/rec.json --out %s/b_####.exr"),
                 0, "%s", out);
    for (int f = 0; f < 11; f++) {
        char a[64], b[64];
        snprintf(a, sizeof a, "a_%04d.exr", f);
        snprintf(b, sizeof b, "b_%04d.exr", f);
        expect_same_exr(a, b);
    }
}

Test(pipeline_cli, config_file_sets_components_and_channels)
{
    char out[8192];
    char cfg[2048];
    /* display outputs are relative to the working directory (as --out): absolute here */
    snprintf(cfg, sizeof cfg,
             "// two viewpoints\n"
             "{\"threads\": 2, \"frames\": 2, \"time\": {\"mode\": \"fixed\", \"rate_hz\": 5},\n"
             " \"traverser\": {\"name\": \"tiled\", \"tile_px\": 8, \"order\": \"morton\"},\n"
             " \"sampler\": {\"name\": \"single\"}, \"renderer\": {\"name\": \"raytracer\"},\n"
             " \"size\": [48, 32], \"display\": {\"name\": \"dump\", \"out\": \"%s/main_####.exr\"},\n"
             " \"channels\": [{\"size\": [20, 24],\n"
             "   \"camera\": {\"eye\": [0, 8, 3], \"look_at\": [0, 0, 0], \"fov_deg\": 60},\n"
             "   \"display\": {\"name\": \"dump\", \"out\": \"%s/top_####.exr\"}}]}\n",
             tmp_dir, tmp_dir);
    write_file("cfg.json", cfg);
    cr_assert_eq(run(out, sizeof out, "render --config %s/cfg.json"), 0, "%s", out);
    int w, h;
    float *px = read_exr("main_0001.exr", &w, &h);
    cr_expect(w == 48 && h == 32, "main channel %dx%d", w, h);
    free(px);
    px = read_exr("top_0001.exr", &w, &h);
    cr_expect(w == 20 && h == 24, "second channel %dx%d", w, h);
    free(px);
    /* the second channel equals a plain render of its camera */
    cr_assert_eq(run(out, sizeof out, "render --size 20x24 --camera 0,8,3,0,0,0,0,1,0,60 --out %s/top_ref.exr"), 0,
                 "%s", out);
    expect_same_exr("top_0000.exr", "top_ref.exr");
    /* the command line overrides the file */
    cr_assert_eq(run(out, sizeof out, "render --config %s/cfg.json --frames 1 --size 16x16 --out %s/over.exr"), 0,
                 "%s", out);
    px = read_exr("over.exr", &w, &h);
    cr_expect(w == 16 && h == 16);
    free(px);
}

Test(pipeline_cli, bad_configs_and_options_get_clear_errors)
{
    write_file("unknown.json", "{\"threads\": 2, \"tiles\": 3}");
    EXPECT_ERROR("render --config %s/unknown.json --out %s/a.png", "unknown.json", "tiles", "unknown field");
    write_file("order.json", "{\"traverser\": {\"order\": \"diagonal\"}}");
    EXPECT_ERROR("render --config %s/order.json --out %s/a.png", "order.json", "traverser.order", "diagonal");
    write_file("k.json", "{\"sampler\": {\"name\": \"jittered\", \"k\": 0}}");
    EXPECT_ERROR("render --config %s/k.json --out %s/a.png", "k.json", "sampler.k");
    write_file("syntax.json", "{\n  \"threads\": 2,,\n}");
    EXPECT_ERROR("render --config %s/syntax.json --out %s/a.png", "syntax.json:2");
    write_file("dump.json", "{\"display\": {\"name\": \"dump\"}}");
    EXPECT_ERROR("render --config %s/dump.json --out %s/a.png", "dump.json", "display.out");
    write_file("gov.json", "{\"governor\": {\"budget_ms\": -5}}");
    EXPECT_ERROR("render --config %s/gov.json --out %s/a.png", "gov.json", "governor.budget_ms");
    write_file("gov2.json", "{\"governor\": {\"budget_ms\": 30, \"upscale\": \"lanczos\"}}");
    EXPECT_ERROR("render --config %s/gov2.json --out %s/a.png", "gov2.json", "governor.upscale", "lanczos");
    write_file("gov3.json", "{\"governor\": {\"budget_ms\": 30, \"refine\": 4}}");
    EXPECT_ERROR("render --config %s/gov3.json --out %s/a.png", "gov3.json", "refine", "unknown field");
    write_file("tile.json", "{\"traverser\": {\"tile_px\": 1000}}");
    EXPECT_ERROR("render --config %s/tile.json --out %s/a.png", "tile.json", "tile_px");
    write_file("tr.json", "{\"renderer\": {\"transparency\": {\"min_transmittance\": 1}}}");
    EXPECT_ERROR("render --config %s/tr.json --out %s/a.png", "tr.json", "renderer.transparency.min_transmittance",
                 "(0, 1)");
    write_file("ao.json", "{\"renderer\": {\"ao\": {\"filter_px\": 4}}}");
    EXPECT_ERROR("render --config %s/ao.json --out %s/a.png", "ao.json", "renderer.ao.filter_px", "odd");
    write_file("caps.json", "{\"renderer\": {\"caps\": {\"style\": \"dots\"}}}");
    EXPECT_ERROR("render --config %s/caps.json --out %s/a.png", "caps.json", "renderer.caps.style", "tint, hatch");
    write_file("op.json", "{\"opacity\": 2}");
    EXPECT_ERROR("render --config %s/op.json --out %s/a.png", "op.json", "'opacity'", "[0, 1]");
    write_file("cut.json", "{\"cutting_planes\": [{\"point\": [0,0,0], \"normal\": [0,1,0]},"
                           " {\"point\": [0,0,0], \"normal\": [0,0,0]}]}");
    EXPECT_ERROR("render --config %s/cut.json --out %s/a.png", "cut.json", "cutting_planes[1].normal", "zero length");
    write_file("cut2.json", "{\"cutting_planes\": [{\"point\": [0,0,0], \"normal\": [0,1,0], \"enabled\": 1}]}");
    EXPECT_ERROR("render --config %s/cut2.json --out %s/a.png", "cut2.json", "cutting_planes[0].enabled",
                 "unknown field");
    EXPECT_ERROR("render --config %s/missing.json --out %s/a.png", "missing.json", "cannot open");
    EXPECT_ERROR("render --tile-order zigzag --out %s/a.png", "--tile-order", "zigzag", "hilbert");
    EXPECT_ERROR("render --tile-size 2 --out %s/a.png", "--tile-size");
    EXPECT_ERROR("render --sampler jittered:0 --out %s/a.png", "--sampler");
    EXPECT_ERROR("render --sampler fancy --out %s/a.png", "--sampler", "fancy");
    EXPECT_ERROR("render --display hdmi --out %s/a.png", "--display", "hdmi");
    EXPECT_ERROR("render --renderer pathtracer --out %s/a.png", "--renderer", "pathtracer");
    EXPECT_ERROR("run --time wallclock --out %s/a.png", "--time", "wallclock");
    EXPECT_ERROR("run --rate -3 --out %s/a.png", "--rate", "-3");
    write_file("badpath.json", "{\"format\": \"tessera-camera-path\", \"version\": 1, \"keyframes\": [{\"time\": 0, \"eye\": [0,0,0], \"look_at\": [0,0,0]}]}");
    EXPECT_ERROR("run --size 8x8 --path %s/badpath.json --out %s/f_####.png", "badpath.json", "keyframes[0]");
    EXPECT_ERROR("run --size 8x8 --record %s/no/dir/rec.json --out %s/f_####.png", "no/dir");
    EXPECT_ERROR("bench --path %s/nope.json", "nope.json");
    EXPECT_ERROR("bench --scaling --rounds 0", "--rounds");
}

Test(pipeline_cli, bench_path_prints_every_transaction_and_frame_time_summary)
{
    char out[16384];
    write_file("short.json", "{\"format\": \"tessera-camera-path\", \"version\": 1, \"keyframes\": ["
                             "{\"time\": 0, \"eye\": [4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]},"
                             "{\"time\": 0.5, \"eye\": [-4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]}]}");
    cr_assert_eq(run(out, sizeof out, "bench --path %s/short.json --rate 20 --size 48x32 --threads 2"), 0, "%s", out);
    for (int k = 0; k <= 10; k++) {
        char needle[32];
        snprintf(needle, sizeof needle, "\ntxn %d ", k);
        cr_expect(strstr(out, needle), "no line for transaction %d: %s", k, out);
    }
    cr_expect(!strstr(out, "\ntxn 11 "), "more transactions than the path has: %s", out);
    const char *line = strstr(out, "BENCH_PATH ");
    cr_assert(line, "no BENCH_PATH line: %s", out);
    cr_expect(strstr(line, "transactions=11"), "%s", line);
    double median = -1, worst = -1;
    const char *m = strstr(line, "median_frame_ms="), *w = strstr(line, "worst_frame_ms=");
    cr_assert(m && w, "%s", line);
    sscanf(m, "median_frame_ms=%lf", &median);
    sscanf(w, "worst_frame_ms=%lf", &worst);
    cr_expect(median > 0 && worst >= median, "median %g worst %g", median, worst);
}

/* With a budget: every transaction's line has the frame's render scale, the
 * sampled ones a FLIP against the full-size frame; the summary has p50, p95
 * and the mean FLIP. A frame at full size scores exactly 0. */
Test(pipeline_cli, bench_path_with_a_budget_prints_scale_and_flip_per_transaction)
{
    char out[16384];
    write_file("short2.json", "{\"format\": \"tessera-camera-path\", \"version\": 1, \"keyframes\": ["
                              "{\"time\": 0, \"eye\": [4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]},"
                              "{\"time\": 0.5, \"eye\": [-4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]}]}");
    cr_assert_eq(run(out, sizeof out,
                     "bench --path %s/short2.json --rate 20 --size 64x40 --threads 2 --budget-ms 5 --flip-samples 3"),
                 0, "%s", out);
    int k, frame, sampled = 0;
    double t, ms, fps, scale;
    char flip[32];
    for (const char *l = strstr(out, "\ntxn "); l; l = strstr(l + 1, "\ntxn ")) {
        cr_assert_eq(sscanf(l, "\ntxn %d %lf %d %lf %lf %lf %31s", &k, &t, &frame, &ms, &fps, &scale, flip), 7,
                     "a transaction line without scale and FLIP: %.80s", l);
        cr_expect(scale > 0 && scale <= 1, "scale %g", scale);
        if (strcmp(flip, "-")) {
            double f = atof(flip);
            cr_expect(f >= 0 && f <= 1, "flip %g", f);
            /* a frame at full size is the full-size frame: exactly 0. (Which frame first shows
             * transaction 0 depends on timing: frame 0, at full size, or a later reduced one.) */
            if (scale == 1.0)
                cr_expect(f == 0.0, "transaction %d at full size: FLIP %g", k, f);
            sampled++;
        }
    }
    cr_expect_eq(sampled, 3, "3 transactions sampled: %s", out);
    const char *line = strstr(out, "BENCH_PATH ");
    cr_assert(line, "no BENCH_PATH line: %s", out);
    double p50 = -1, p95 = -1, mean = -1;
    const char *a = strstr(line, "p50_ms="), *b = strstr(line, "p95_ms="), *c = strstr(line, "flip_mean=");
    cr_assert(a && b && c, "%s", line);
    sscanf(a, "p50_ms=%lf", &p50);
    sscanf(b, "p95_ms=%lf", &p95);
    sscanf(c, "flip_mean=%lf", &mean);
    cr_expect(p50 > 0 && p95 >= p50 && mean >= 0 && mean <= 1, "p50 %g p95 %g flip_mean %g", p50, p95, mean);
    cr_expect(strstr(line, "flip_frames=3"), "%s", line);
}

Test(pipeline_cli, bench_scaling_prints_a_fraction_of_linear_per_thread_count)
{
    char out[8192];
    cr_assert_eq(run(out, sizeof out, "bench --scaling --threads 3 --rounds 1 --frames 3 --size 32x24"), 0, "%s",
                 out);
    for (int n = 1; n <= 3; n++) {
        char needle[64];
        snprintf(needle, sizeof needle, "SCALING threads=%d ", n);
        const char *line = strstr(out, needle);
        cr_assert(line, "no line for %d threads: %s", n, out);
        double fraction = -1;
        const char *f = strstr(line, "fraction_of_linear=");
        cr_assert(f, "%s", line);
        sscanf(f, "fraction_of_linear=%lf", &fraction);
        cr_expect(fraction > 0.0, "%s", line);
        if (n == 1)
            cr_expect_eq(fraction, 1.0);
    }
}

/* --thread-counts: only those counts, in that order, more than the CPUs too; the
 * speed-up is against the first; each line has the frame barrier's aggregates. */
Test(pipeline_cli, bench_scaling_runs_the_thread_counts_asked_for)
{
    char out[8192];
    cr_assert_eq(run(out, sizeof out, "bench --scaling --thread-counts 2,5 --rounds 1 --frames 4 --size 32x24"), 0,
                 "%s", out);
    cr_expect_null(strstr(out, "SCALING threads=1 "), "%s", out);
    const char *two = strstr(out, "SCALING threads=2 "), *five = strstr(out, "SCALING threads=5 ");
    cr_assert(two && five && two < five, "%s", out);
    cr_expect(strstr(two, "speedup=2.000 fraction_of_linear=1.000"), "%s", two); /* linear up to the first */
    double serial = -1, release = -1, wait = -1;
    const char *a = strstr(five, "serial_ms_per_frame="), *b = strstr(five, "release_ms_per_frame="),
               *c = strstr(five, "wait_ms_per_frame=");
    cr_assert(a && b && c && strstr(five, "frames=4 "), "%s", five);
    sscanf(a, "serial_ms_per_frame=%lf", &serial);
    sscanf(b, "release_ms_per_frame=%lf", &release);
    sscanf(c, "wait_ms_per_frame=%lf", &wait);
    cr_expect(serial > 0 && release >= 0 && wait > 0, "%s", five);
    cr_expect_neq(run(out, sizeof out, "bench --scaling --thread-counts 0,2 --rounds 1 --frames 2 --size 8x8"), 0,
                  "%s", out);
    cr_expect_neq(run(out, sizeof out, "bench --path configs/paths/orbit.json --thread-counts 2"), 0, "%s", out);
}

/* Every example config renders (tiny, one frame), run from a scratch directory
 * so their relative out/ patterns land there. */
Test(pipeline_cli, example_configs_render)
{
    const char *examples[] = {"kiosk.json", "stills.json", "two_views.json"};
    char bin[4096], cfg_dir[4096], cmd[16384], out[8192];
    cr_assert(realpath(support_tessera_bin(), bin), "no binary at %s", support_tessera_bin());
    cr_assert(realpath("../configs/pipeline", cfg_dir));
    snprintf(cmd, sizeof cmd, "mkdir -p %s/out", tmp_dir);
    cr_assert_eq(support_run(cmd), 0);
    for (size_t i = 0; i < sizeof examples / sizeof examples[0]; i++) {
        snprintf(cmd, sizeof cmd,
                 "cd %s && timeout %d %s render --config %s/%s --size 24x16 --frames 1 --threads 2 > %s/log 2>&1",
                 tmp_dir, TIMEOUT_S, bin, cfg_dir, examples[i], tmp_dir);
        int code = support_run(cmd);
        char log[512];
        snprintf(log, sizeof log, "%s/log", tmp_dir);
        support_read_text(log, out, sizeof out);
        cr_expect_eq(code, 0, "%s: %s", examples[i], out);
        cr_expect(strstr(out, "1 frame"), "%s: %s", examples[i], out);
    }
    char top[512];
    snprintf(top, sizeof top, "%s/out/top_0000.png", tmp_dir);
    cr_expect(access(top, R_OK) == 0, "two_views.json wrote no second channel");
}
