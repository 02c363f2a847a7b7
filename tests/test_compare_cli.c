/* test_compare_cli.c - `tessera compare` (app/cmd_compare.c) end to
 * end: its one line of numbers, the map file, the viewing distance from a
 * wall config, and every bad input with a message naming the file. Runs
 * ../tessera (or $TESSERA_BIN) from the tests/ directory on images written
 * here (tests/flip_pair.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flip_pair.h"
#include "metrics/error_map.h"
#include "support.h"

/* Hang guards, not speed limits: a run that takes this long is stuck. Generous, because under
 * ASan on a loaded 2-core machine one `compare` (OpenImageIO's start-up) took over 60 s. */
#define RUN_TIMEOUT_S 300
#define OUT_BYTES 8192

static char dir[256];

/* dir/NAME.png from sRGB codes (W x H). */
static void write_codes(const char *name, const uint8_t *codes, int w, int h)
{
    float *lin = malloc((size_t)w * h * 3 * sizeof *lin);
    cr_assert(lin);
    for (int i = 0; i < w * h * 3; i++)
        lin[i] = flip_pair_linear(codes[i]);
    char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    tess_error err = {{0}};
    cr_assert(dump_write_rgb(path, w, h, lin, &err), "%s", err.msg);
    free(lin);
}

static void setup(void)
{
    support_make_tmp_dir(dir, sizeof dir, "compare");
    static uint8_t ref[FLIP_PAIR_W * FLIP_PAIR_H * 3], test[FLIP_PAIR_W * FLIP_PAIR_H * 3];
    flip_pair_codes(ref, test);
    write_codes("ref.png", ref, FLIP_PAIR_W, FLIP_PAIR_H);
    write_codes("test.png", test, FLIP_PAIR_W, FLIP_PAIR_H);
    write_codes("small.png", ref, FLIP_PAIR_W / 2, FLIP_PAIR_H / 2);
    support_write_file(dir, "text.png", "this is not an image\n");
}

static void teardown(void) { support_remove_tmp_dir(dir); }

TestSuite(compare_cli, .init = setup, .fini = teardown, .timeout = 1500); /* a hang guard for all the runs of one test */

/* Run `tessera compare ARGS` (every %s is dir); stdout to out, stderr to err. The exit status. */
static int compare(char *out, char *err, const char *args_fmt)
{
    return support_tessera_split(dir, RUN_TIMEOUT_S, out, err, OUT_BYTES, "compare", args_fmt);
}

/* `tessera compare ARGS` fails with `code`, prints nothing on stdout and
 * says every NULL-terminated needle in one error line. */
static void expect_failure(int code, const char *args_fmt, const char *const *needles)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    int got = compare(out, err, args_fmt);
    cr_expect_eq(got, code, "'%s': exit %d, expected %d: %s", args_fmt, got, code, err);
    cr_expect_eq(out[0], '\0', "'%s' printed a result: %s", args_fmt, out);
    cr_expect(strstr(err, "tessera: error: "), "'%s': no error line: %s", args_fmt, err);
    for (const char *const *n = needles; *n; n++)
        cr_expect(strstr(err, *n), "'%s': message lacks '%s': %s", args_fmt, *n, err);
}
#define EXPECT_FAILURE(code, args, ...) expect_failure(code, args, (const char *const[]){__VA_ARGS__, NULL})

Test(compare_cli, identical_images_print_zeros)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    cr_assert_eq(compare(out, err, "%s/ref.png %s/ref.png"), 0, "%s", err);
    cr_expect_str_eq(out, "flip_mean=0.000000 flip_median=0.000000 flip_q3=0.000000 rmse=0 psnr=inf "
                          "differing_pixels=0\n");
}

Test(compare_cli, known_pair_gives_the_reference_implementations_mean)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    cr_assert_eq(compare(out, err, "%s/ref.png %s/test.png --threads 1"), 0, "%s", err);
    double mean, median, q3, rmse, psnr;
    unsigned long differing;
    cr_assert_eq(sscanf(out, "flip_mean=%lf flip_median=%lf flip_q3=%lf rmse=%lf psnr=%lf differing_pixels=%lu", &mean,
                        &median, &q3, &rmse, &psnr, &differing),
                 6, "not the one result line: %s", out);
    cr_expect(fabs(mean - FLIP_PAIR_NVLABS_MEAN) <= FLIP_PAIR_TOLERANCE, "flip_mean %.6f, NVlabs %.6f", mean,
              FLIP_PAIR_NVLABS_MEAN);
    cr_expect(median > 0.0 && median <= q3 && q3 <= 1.0, "%s", out);
    cr_expect(rmse > 0.0 && fabs(psnr + 20.0 * log10(rmse)) < 0.01, "%s", out);
    /* the right third (blue + 30) and most of the other two differ; the shifted third's
     * columns that the shift leaves equal (ramps aside) do not */
    cr_expect(differing > 0 && differing <= (unsigned long)FLIP_PAIR_W * FLIP_PAIR_H, "%s", out);
    /* the same numbers with more threads */
    char out2[OUT_BYTES];
    cr_assert_eq(compare(out2, err, "%s/ref.png %s/test.png --threads 3"), 0, "%s", err);
    cr_expect_str_eq(out2, out);
}

Test(compare_cli, map_has_the_image_size_plus_the_legend)
{
    char out[OUT_BYTES], err[OUT_BYTES];
    cr_assert_eq(compare(out, err, "%s/ref.png %s/test.png --map %s/map.png"), 0, "%s", err);
    cr_expect(strncmp(out, "flip_mean=", 10) == 0, "%s", out);
    int w, h;
    float *rgb = support_read_image(dir, "map.png", &w, &h);
    cr_expect_eq(w, FLIP_PAIR_W);
    cr_expect_eq(h, FLIP_PAIR_H + error_map_legend_height_px(FLIP_PAIR_W), "map height %d", h);
    free(rgb);
    EXPECT_FAILURE(1, "%s/ref.png %s/test.png --map %s/no/such/dir/map.png", "map.png", "cannot open for writing");
}

Test(compare_cli, exr_is_linear_and_png_is_srgb)
{
    /* the PNG's decoded values stored in an EXR are the same image */
    char png[512], exr[512];
    snprintf(png, sizeof png, "%s/ref.png", dir);
    snprintf(exr, sizeof exr, "%s/ref.exr", dir);
    int w, h;
    float *lin = NULL;
    tess_error e = {{0}};
    cr_assert(dump_read_linear_rgb(png, &w, &h, &lin, &e), "%s", e.msg);
    cr_expect(fabs(lin[0] - flip_pair_linear(0)) < 1e-9 && fabs(lin[3 * (w - 1)] - 1.0f) < 1e-9,
              "the red ramp decodes to %g .. %g", lin[0], lin[3 * (w - 1)]);
    cr_assert(dump_write_rgb(exr, w, h, lin, &e), "%s", e.msg);
    free(lin);
    char out[OUT_BYTES], err[OUT_BYTES];
    cr_assert_eq(compare(out, err, "%s/ref.png %s/ref.exr"), 0, "%s", err);
    cr_expect(strstr(out, "flip_mean=0.000000 ") && strstr(out, "differing_pixels=0\n"), "%s", out);
}

Test(compare_cli, bad_images_are_named)
{
    EXPECT_FAILURE(1, "%s/ref.png %s/small.png", "ref.png is 96x64 but", "small.png is 48x32",
                   "must be the same size");
    EXPECT_FAILURE(1, "%s/ref.png %s/missing.png", "missing.png: cannot read");
    EXPECT_FAILURE(1, "%s/missing.png %s/ref.png", "missing.png: cannot read");
    EXPECT_FAILURE(1, "%s/ref.png %s/text.png", "text.png: cannot read");
    EXPECT_FAILURE(1, "%s/ref.png %s", "cannot read: it is a directory, not an image file");
}

Test(compare_cli, option_errors)
{
    EXPECT_FAILURE(2, "%s/ref.png", "needs two images");
    EXPECT_FAILURE(2, "%s/ref.png %s/ref.png %s/test.png", "is a third");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --bogus", "unknown option '--bogus'");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --ppd 0", "--ppd: expected a number from 1 to 1000, got '0'");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --ppd x", "--ppd: expected a number");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --ppd", "--ppd needs a value");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --ppd 60 --wall w.json --distance-m 1", "--ppd: not an option with --wall");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --wall w.json", "--wall needs --distance-m");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --distance-m 1", "--distance-m: not an option without --wall");
    EXPECT_FAILURE(2, "%s/ref.png %s/test.png --threads 0", "--threads");
    char out[OUT_BYTES], err[OUT_BYTES];
    cr_expect_eq(compare(out, err, "--help"), 0);
    const char *options[] = {"--map", "--ppd", "--wall", "--distance-m", "--threads", "LINEAR RGB", "67.02"};
    for (size_t i = 0; i < sizeof options / sizeof options[0]; i++)
        cr_expect(strstr(out, options[i]), "compare --help lacks %s", options[i]);
}

Test(compare_cli, ppd_from_a_walls_pixel_pitch)
{
    /* 3840 pixels over 700 mm seen from 0.7 m: FLIP's default viewer */
    support_write_file(dir, "uhd.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"A-1\", \"mode\": \"3840x2160\", \"grid\": [0, 0], \"size_mm\": [700, 393.75]}]}");
    char out[OUT_BYTES], err[OUT_BYTES], default_out[OUT_BYTES];
    cr_assert_eq(compare(default_out, err, "%s/ref.png %s/test.png"), 0, "%s", err);
    cr_assert_eq(compare(out, err, "%s/ref.png %s/test.png --wall %s/uhd.json --distance-m 0.7"), 0, "%s", err);
    cr_expect_str_eq(out, default_out);
    cr_expect(strstr(err, "5.4857 px/mm, 67.02 pixels per degree"), "%s", err);
    cr_expect(!strstr(err, "warning"), "%s", err);

    /* farther away: more pixels per degree, the pair's noise less visible */
    cr_assert_eq(compare(out, err, "%s/ref.png %s/test.png --wall %s/uhd.json --distance-m 2"), 0, "%s", err);
    double near_mean, far_mean;
    cr_assert_eq(sscanf(default_out, "flip_mean=%lf", &near_mean), 1);
    cr_assert_eq(sscanf(out, "flip_mean=%lf", &far_mean), 1);
    cr_expect(far_mean < near_mean, "2 m: %g, 0.7 m: %g", far_mean, near_mean);

    /* two pitches: the finest is used, and said */
    support_write_file(dir, "mixed.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"A-1\", \"mode\": \"3840x2160\", \"position_mm\": [0, 0], \"size_mm\": [700, 393.75]},"
                       "{\"connector\": \"A-2\", \"mode\": \"1920x1080\", \"position_mm\": [700, 0], \"size_mm\": [700, 393.75]}]}");
    cr_assert_eq(compare(out, err, "%s/ref.png %s/test.png --wall %s/mixed.json --distance-m 0.7"), 0, "%s", err);
    cr_expect_str_eq(out, default_out);
    cr_expect(strstr(err, "tessera: warning: ") && strstr(err, "pixel pitches differ") &&
                  strstr(err, "using the finest, 5.4857 px/mm"),
              "%s", err);

    /* a wall the pitch cannot come from */
    support_write_file(dir, "preferred.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"A-1\", \"grid\": [0, 0], \"size_mm\": [700, 393.75]}]}");
    EXPECT_FAILURE(1, "%s/ref.png %s/test.png --wall %s/preferred.json --distance-m 1", "preferred.json",
                   "give an explicit mode");
    EXPECT_FAILURE(1, "%s/ref.png %s/test.png --wall %s/none.json --distance-m 1", "none.json");
    EXPECT_FAILURE(1, "%s/ref.png %s/test.png --wall %s/uhd.json --distance-m 500", "pixels per degree is outside");
}
