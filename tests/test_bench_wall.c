/* test_bench_wall.c - `tessera bench --wall` end to end: one BENCH_WALL line
 * per output and display kind plus the whole wall's, sizes and pixel counts
 * as the wall config gives them, numbers that parse and are positive, the
 * dump display's files, and clear errors for bad options and files. Speeds
 * are never compared (the suite runs on shared, noisy machines); runs use
 * --keep-noisy so that a busy machine does not repeat them.
 * Runs ../tessera (or $TESSERA_BIN) from the tests/ directory. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "support.h"

#define TIMEOUT_S 120
#define OUTPUT_BYTES 32768

static char tmp_dir[256];

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "benchwall"); }

static void remove_tmp_dir(void) { support_remove_tmp_dir(tmp_dir); }

TestSuite(bench_wall, .init = make_tmp_dir, .fini = remove_tmp_dir, .timeout = 300);

/* Run `tessera bench ARGS` (every %s is the temp dir) with stdout and stderr
 * apart; the exit status. */
static int run_bench(char *out, char *err, const char *args_fmt)
{
    return support_tessera_bench(tmp_dir, TIMEOUT_S, out, err, OUTPUT_BYTES, args_fmt);
}

/* Three outputs of different sizes placed by position_mm, 1 mm a pixel. */
static const char three_outputs[] =
    "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": [\n"
    " {\"connector\": \"DP-1\", \"mode\": \"64x36\", \"position_mm\": [0, 0], \"size_mm\": [64, 36]},\n"
    " {\"connector\": \"HDMI-A-1\", \"mode\": \"40x30\", \"position_mm\": [70, 0], \"size_mm\": [40, 30]},\n"
    " {\"connector\": \"Virtual-3\", \"mode\": \"24x32\", \"position_mm\": [0, 40], \"size_mm\": [24, 32]}]}\n";

/* The line starting with `prefix` (at the start of a line), copied into buf; NULL if none. */
static const char *find_line(const char *text, const char *prefix, char *buf, size_t buf_bytes)
{
    size_t n = strlen(prefix);
    for (const char *p = text; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL) {
        if (!strncmp(p, prefix, n)) {
            size_t len = strcspn(p, "\n");
            if (len >= buf_bytes)
                len = buf_bytes - 1;
            memcpy(buf, p, len);
            buf[len] = '\0';
            return buf;
        }
    }
    return NULL;
}

static int count_prefix(const char *text, const char *prefix)
{
    int count = 0;
    size_t n = strlen(prefix);
    for (const char *p = text; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL)
        count += !strncmp(p, prefix, n);
    return count;
}

/* The number after " key=" in a line; fails the test when absent or unparsable. */
static double field(const char *line, const char *key)
{
    char needle[64];
    snprintf(needle, sizeof needle, " %s=", key);
    const char *p = strstr(line, needle);
    cr_assert(p, "no field %s in: %s", key, line);
    char *end;
    double v = strtod(p + strlen(needle), &end);
    cr_assert(end != p + strlen(needle) && (*end == ' ' || *end == '\0' || *end == 'x'), "field %s unparsable: %s",
              key, line);
    cr_assert(isfinite(v), "field %s not finite: %s", key, line);
    return v;
}

static void expect_positive(const char *line, const char *const *keys)
{
    for (const char *const *k = keys; *k; k++)
        cr_expect(field(line, *k) > 0.0, "%s should be positive: %s", *k, line);
}

static const char *const timed_keys[] = {"median_ms", "min_ms", "max_ms", "fps", "mpix_s", NULL};

/* The output line of `connector` with `display`: checked and returned in buf. */
static const char *expect_output_line(const char *out, const char *connector, const char *display, int w, int h,
                                      char *buf, size_t buf_bytes)
{
    char prefix[128], size[64];
    snprintf(prefix, sizeof prefix, "BENCH_WALL output=%s display=%s ", connector, display);
    const char *line = find_line(out, prefix, buf, buf_bytes);
    cr_assert(line, "no line '%s': %s", prefix, out);
    snprintf(size, sizeof size, " size=%dx%d ", w, h);
    cr_expect(strstr(line, size), "expected%s: %s", size, line);
    cr_expect_eq(field(line, "pixels"), (double)w * h, "%s", line);
    expect_positive(line, timed_keys);
    cr_expect(field(line, "min_ms") <= field(line, "median_ms") && field(line, "median_ms") <= field(line, "max_ms"),
              "%s", line);
    cr_expect(field(line, "display_ms") >= 0.0, "%s", line);
    return line;
}

Test(bench_wall, one_line_per_output_and_display_plus_the_wall)
{
    static char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    char line[2048];
    support_write_file(tmp_dir, "three.json", three_outputs);
    int code = run_bench(out, err, "--wall %s/three.json --frames 3 --rounds 2 --threads 2 --keep-noisy");
    cr_assert_eq(code, 0, "exit %d: %s%s", code, out, err);
    /* default displays: null, then convert; 3 outputs + the wall each */
    cr_expect_eq(count_prefix(out, "BENCH_WALL output="), 6, "%s", out);
    cr_expect_eq(count_prefix(out, "BENCH_WALL wall="), 2, "%s", out);
    cr_expect_eq(count_prefix(out, "BENCH_WALL_DISPLAY "), 2, "%s", out);
    const char *displays[] = {"null", "convert"};
    for (int k = 0; k < 2; k++) {
        expect_output_line(out, "DP-1", displays[k], 64, 36, line, sizeof line);
        expect_output_line(out, "HDMI-A-1", displays[k], 40, 30, line, sizeof line);
        expect_output_line(out, "Virtual-3", displays[k], 24, 32, line, sizeof line);
        cr_expect(field(line, "frames") == 3 && field(line, "rounds") == 2 && field(line, "threads") == 2, "%s",
                  line);
        char prefix[512], needle[64];
        snprintf(prefix, sizeof prefix, "BENCH_WALL wall=%s/three.json display=%s ", tmp_dir, displays[k]);
        cr_assert(find_line(out, prefix, line, sizeof line), "no line '%s': %s", prefix, out);
        cr_expect_eq(field(line, "outputs"), 3, "%s", line);
        cr_expect_eq(field(line, "pixels"), 64 * 36 + 40 * 30 + 24 * 32, "%s", line);
        expect_positive(line, timed_keys);
        expect_positive(line, (const char *const[]){"outputs_sum_ms", "sum_over_wall", NULL});
        cr_expect(field(line, "display_ms") >= 0.0 && field(line, "display_ms_per_output") >= 0.0, "%s", line);
        snprintf(needle, sizeof needle, "BENCH_WALL_DISPLAY display=%s baseline=null ", displays[k]);
        cr_assert(find_line(out, needle, line, sizeof line), "no line '%s': %s", needle, out);
        expect_positive(line, (const char *const[]){"wall_ms", "baseline_ms", "cost_ratio", NULL});
        field(line, "cost_ms"); /* may be negative: only that it parses */
        cr_expect(field(line, "display_ms_per_output") >= 0.0 && field(line, "alone_display_ms_per_output") >= 0.0,
                  "%s", line);
    }
    /* the baseline against itself */
    cr_assert(find_line(out, "BENCH_WALL_DISPLAY display=null ", line, sizeof line), "%s", out);
    cr_expect_eq(field(line, "cost_ms"), 0.0, "%s", line);
    cr_expect_eq(field(line, "cost_ratio"), 1.0, "%s", line);
    /* 2 rounds of 2 x (3 outputs + the wall); --keep-noisy: nothing repeated, no waiting */
    cr_assert(find_line(out, "BENCH_WALL_NOISE ", line, sizeof line), "%s", out);
    cr_expect_eq(field(line, "runs"), 16, "%s", line);
    cr_expect(field(line, "repeated") == 0 && field(line, "waited_s") == 0, "%s", line);
    cr_expect(field(line, "noisy") >= 0, "%s", line);
    /* the summary for people, after the lines */
    cr_expect(strstr(out, "\n# ") && strstr(out, "outputs alone, summed"), "%s", out);
    cr_expect(strstr(out, "handing frames to the outputs"), "%s", out);
}

Test(bench_wall, pixel_counts_follow_the_config_and_size_scale)
{
    static char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    char line[2048];
    int code = run_bench(out, err,
                         "--wall ../configs/walls/vm_2x2.json --size-scale 0.125 --display convert --frames 3 "
                         "--rounds 1 --threads 2 --keep-noisy");
    cr_assert_eq(code, 0, "exit %d: %s%s", code, out, err);
    cr_expect_eq(count_prefix(out, "BENCH_WALL output="), 4, "%s", out);
    for (int i = 1; i <= 4; i++) {
        char name[32];
        snprintf(name, sizeof name, "Virtual-%d", i);
        expect_output_line(out, name, "convert", 80, 60, line, sizeof line);
    }
    cr_assert(find_line(out, "BENCH_WALL wall=../configs/walls/vm_2x2.json display=convert ", line, sizeof line),
              "%s", out);
    cr_expect_eq(field(line, "pixels"), 4 * 80 * 60, "%s", line);
    cr_expect(field(line, "display_ms") > 0.0, "convert has a display stage: %s", line);
    /* the rotated outputs of portrait_3x1 are 1080x1920 as mounted */
    code = run_bench(out, err,
                     "--wall ../configs/walls/portrait_3x1.json --size-scale 0.05 --display null --frames 3 "
                     "--rounds 1 --keep-noisy");
    cr_assert_eq(code, 0, "exit %d: %s%s", code, out, err);
    for (int i = 1; i <= 3; i++) {
        char name[32];
        snprintf(name, sizeof name, "Virtual-%d", i);
        expect_output_line(out, name, "null", 54, 96, line, sizeof line);
    }
}

Test(bench_wall, dump_writes_each_outputs_image_into_out)
{
    static char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    char line[2048];
    support_write_file(tmp_dir, "three.json", three_outputs);
    support_write_file(tmp_dir, "path.json",
                       "{\"format\": \"tessera-camera-path\", \"version\": 1, \"keyframes\": ["
                       "{\"time\": 1, \"eye\": [4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]},"
                       "{\"time\": 2, \"eye\": [-4.5, 3.2, 6.5], \"look_at\": [0, 0.6, 0]}]}");
    int code = run_bench(out, err,
                         "--wall %s/three.json --display null,dump --out %s --camera-path %s/path.json --frames 3 "
                         "--rounds 1 --threads 2 --keep-noisy");
    cr_assert_eq(code, 0, "exit %d: %s%s", code, out, err);
    cr_assert(find_line(out, "BENCH_WALL_DISPLAY display=dump baseline=null ", line, sizeof line), "%s", out);
    cr_expect(field(line, "display_ms_per_output") > 0.0, "%s", line);
    const char *names[] = {"DP-1", "HDMI-A-1", "Virtual-3"};
    const int sizes[][2] = {{64, 36}, {40, 30}, {24, 32}};
    for (int i = 0; i < 3; i++)
        for (int run = 0; run < 2; run++) {
            char file[128];
            int w, h;
            snprintf(file, sizeof file, "bench-%s-%s.png", run ? "alone" : "wall", names[i]);
            float *px = support_read_image(tmp_dir, file, &w, &h);
            cr_expect(w == sizes[i][0] && h == sizes[i][1], "%s is %dx%d", file, w, h);
            free(px);
        }
    cr_expect(strstr(out, "camera path"), "the summary names the camera path: %s", out);
}

Test(bench_wall, help_documents_every_option)
{
    static char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    cr_assert_eq(run_bench(out, err, "--wall --help"), 0, "%s%s", out, err);
    const char *options[] = {"--wall FILE", "--display LIST", "null", "convert", "dump", "--out DIR",
                             "--frames N", "--rounds R", "--rate HZ", "--camera-path FILE", "--camera ",
                             "--size-scale S", "--scene FILE", "--threads N", "--keep-noisy", "--config FILE",
                             "--tile-size", "--no-shadows", "BENCH_WALL output=", "BENCH_WALL wall=",
                             "--quiet-wait S", "BENCH_WALL_DISPLAY", "BENCH_WALL_NOISE", "sum_over_wall",
                             "cost_ms"};
    for (size_t i = 0; i < sizeof options / sizeof options[0]; i++)
        cr_expect(strstr(out, options[i]), "help lacks '%s': %s", options[i], out);
    /* and 'tessera bench --help' points to it */
    cr_assert_eq(run_bench(out, err, "--help"), 0, "%s%s", out, err);
    cr_expect(strstr(out, "--wall FILE"), "%s", out);
}

static void expect_error(const char *args_fmt, const char *const *needles)
{
    char args[2048];
    snprintf(args, sizeof args, "bench %s", args_fmt);
    support_expect_error(tmp_dir, TIMEOUT_S, args, needles);
    char log_path[512], out[OUTPUT_BYTES];
    snprintf(log_path, sizeof log_path, "%s/cli.log", tmp_dir);
    support_read_text(log_path, out, sizeof out);
    cr_expect(!strstr(out, "BENCH_WALL"), "'%s' printed results: %s", args_fmt, out);
}

#define EXPECT_ERROR(args, ...) expect_error(args, (const char *const[]){__VA_ARGS__, NULL})

Test(bench_wall, bad_options_and_files_get_clear_errors)
{
    support_write_file(tmp_dir, "three.json", three_outputs);
    support_write_file(tmp_dir, "preferred.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"Virtual-1\", \"grid\": [0, 0], \"size_mm\": [40, 30]}]}");
    support_write_file(tmp_dir, "broken.json", "{\"format\": \"tessera-wall\", \"version\": 1,,}");
    EXPECT_ERROR("--wall", "--wall");
    EXPECT_ERROR("--wall %s/missing.json", "missing.json");
    EXPECT_ERROR("--wall %s/broken.json", "broken.json");
    EXPECT_ERROR("--wall %s/preferred.json", "preferred.json", "preferred");
    EXPECT_ERROR("--wall %s/three.json --display hdmi", "--display", "hdmi", "null, convert, convert-tiles, dump");
    EXPECT_ERROR("--wall %s/three.json --display null,,convert", "--display");
    EXPECT_ERROR("--wall %s/three.json --display convert,convert", "--display", "twice");
    EXPECT_ERROR("--wall %s/three.json --display drm", "--display", "drm");
    EXPECT_ERROR("--wall %s/three.json --display dump", "dump", "--out");
    EXPECT_ERROR("--wall %s/three.json --display null --out %s", "--out", "dump");
    EXPECT_ERROR("--wall %s/three.json --display dump --out %s/no/such/dir", "--out", "no/such/dir",
                 "not an existing directory");
    EXPECT_ERROR("--wall %s/three.json --frames 2", "--frames", "at least 3");
    EXPECT_ERROR("--wall %s/three.json --frames many", "--frames", "many");
    EXPECT_ERROR("--wall %s/three.json --rounds 0", "--rounds");
    EXPECT_ERROR("--wall %s/three.json --quiet-wait -1", "--quiet-wait");
    EXPECT_ERROR("--wall %s/three.json --size-scale 0", "--size-scale", "'0'");
    EXPECT_ERROR("--wall %s/three.json --size-scale big", "--size-scale", "big");
    EXPECT_ERROR("--wall %s/three.json --size 64x36", "--size", "--size-scale");
    EXPECT_ERROR("--wall %s/three.json --time real", "--time", "fixed-rate");
    EXPECT_ERROR("--wall %s/three.json --threads 0", "--threads");
    EXPECT_ERROR("--wall %s/three.json --bogus", "--bogus");
    EXPECT_ERROR("--wall %s/three.json --camera-path %s/nope.json", "nope.json");
    EXPECT_ERROR("--wall %s/three.json --scene %s/nope.ply", "nope.ply");
}
