/* test_dump.c - the OpenImageIO dump backend (wall/dump.h): round trips,
 * the exactness of the sRGB encoder, and every error a user can cause.
 * Each test writes into its own fresh mkdtemp directory under /tmp. */
#include <criterion/criterion.h>

#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "wall/dump.h"

static char tmp_dir[64]; /* this test's scratch directory; Criterion runs each test in its own process */

static void make_tmp_dir(void)
{
    strcpy(tmp_dir, "/tmp/tessera_dump_XXXXXX");
    cr_assert_not_null(mkdtemp(tmp_dir), "mkdtemp failed");
}

/* The directory is flat: the tests create no subdirectories in it. */
static void remove_tmp_dir(void)
{
    DIR *dir = opendir(tmp_dir);
    if (!dir)
        return;
    for (struct dirent *e; (e = readdir(dir));) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "%s/%s", tmp_dir, e->d_name);
        unlink(path);
    }
    closedir(dir);
    rmdir(tmp_dir);
}

TestSuite(dump, .init = make_tmp_dir, .fini = remove_tmp_dir);

/* `name` inside the scratch directory, in a caller buffer of 512 bytes. */
static const char *in_tmp(char *buf, const char *name)
{
    snprintf(buf, 512, "%s/%s", tmp_dir, name);
    return buf;
}

static void write_bytes(const char *path, const void *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "cannot create %s", path);
    cr_assert_eq(fwrite(bytes, 1, n, f), n);
    cr_assert_eq(fclose(f), 0);
}

static bool file_exists(const char *path) { return access(path, F_OK) == 0; }

/* The specification: the sRGB curve in double, clamped to [0, 1], NaN -> 0,
 * rounded to nearest. Written independently of the implementation. */
static int srgb_reference(float linear)
{
    if (isnan(linear) || linear <= 0.0f)
        return 0;
    if (linear >= 1.0f)
        return 255;
    double x = linear;
    double v = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    return (int)floor(v * 255.0 + 0.5);
}

/* ---- the sRGB encoder ---- */

Test(dump, srgb_known_values)
{
    /* expectations from the formula, worked by hand in double */
    cr_assert_eq(dump_srgb_encode_u8(0.0f), 0);
    cr_assert_eq(dump_srgb_encode_u8(1.0f), 255);
    cr_assert_eq(dump_srgb_encode_u8(0.5f), 188);       /* 0.7354 * 255 = 187.5x */
    cr_assert_eq(dump_srgb_encode_u8(0.214f), 127);     /* 0.49994 * 255 = 127.48 */
    cr_assert_eq(dump_srgb_encode_u8(0.2158605f), 128); /* the linear value of sRGB 128/255 */
    cr_assert_eq(dump_srgb_encode_u8(0.18f), 118);      /* mid grey */
    cr_assert_eq(dump_srgb_encode_u8(0.001f), 3);       /* linear toe: 12.92e-3 * 255 = 3.29 */
    cr_assert_eq(dump_srgb_encode_u8(0.0031308f), 10);  /* the toe's end */
    cr_assert_eq(dump_srgb_encode_u8(0.75f), 225);
}

Test(dump, srgb_clamps_nan_negative_and_over_one)
{
    const float zero[] = {NAN, -NAN, -0.0f, -1e-30f, -1.0f, -INFINITY, FLT_TRUE_MIN, 1e-10f};
    for (size_t i = 0; i < sizeof zero / sizeof zero[0]; i++)
        cr_assert_eq(dump_srgb_encode_u8(zero[i]), 0, "input %g", (double)zero[i]);
    const float full[] = {1.0f, 1.0000001f, 1.5f, 1e30f, FLT_MAX, INFINITY, 0.99999994f};
    for (size_t i = 0; i < sizeof full / sizeof full[0]; i++)
        cr_assert_eq(dump_srgb_encode_u8(full[i]), 255, "input %.9g", (double)full[i]);
}

/* A dense sweep of [0, 1] (and a little outside it) against the reference. */
Test(dump, srgb_matches_formula_dense_sweep)
{
    const int steps = 1000000;
    for (int i = -1000; i <= steps + 1000; i++) {
        float x = (float)i / (float)steps;
        cr_assert_eq(dump_srgb_encode_u8(x), srgb_reference(x), "x = %.9g", (double)x);
    }
}

/* Float x in [0, 1] as an ordered integer: adjacent floats differ by 1. */
static uint32_t float_bits(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static float bits_float(uint32_t u)
{
    float x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* At each of the 255 rounding boundaries, found by bisection over the floats
 * with the reference, the floats on both sides (a few ulps each way). */
Test(dump, srgb_exact_at_every_boundary)
{
    for (int k = 0; k < 255; k++) {
        uint32_t lo = 0, hi = float_bits(1.0f); /* reference(lo) <= k < reference(hi) */
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (srgb_reference(bits_float(mid)) > k)
                hi = mid;
            else
                lo = mid;
        }
        cr_assert_eq(srgb_reference(bits_float(hi)), k + 1, "boundary %d skips a code", k);
        for (uint32_t u = hi - 4; u <= hi + 4; u++) {
            float x = bits_float(u);
            cr_assert_eq(dump_srgb_encode_u8(x), srgb_reference(x), "x = %.9g near boundary %d", (double)x, k);
        }
    }
}

/* Every float in [0, 1] (about 1.07e9 values, ~5 s at -O2): run with
 * TESSERA_EXHAUSTIVE=1 after changing the encoder. */
Test(dump, srgb_exhaustive_when_asked, .timeout = 3600)
{
    if (!getenv("TESSERA_EXHAUSTIVE")) {
        remove_tmp_dir(); /* a skipped test gets no .fini */
        cr_skip_test("set TESSERA_EXHAUSTIVE=1 to check every float");
    }
    for (uint32_t u = 0; u <= float_bits(1.0f); u++) {
        float x = bits_float(u);
        if (dump_srgb_encode_u8(x) != srgb_reference(x))
            cr_assert_fail("x = %.9g (bits 0x%08x): got %d, want %d", (double)x, (unsigned)u,
                           dump_srgb_encode_u8(x), srgb_reference(x));
    }
}

/* ---- round trips ---- */

enum { GRAD_W = 17, GRAD_H = 5 }; /* odd sizes catch stride mistakes */

/* A gradient across [0, 1] with out-of-range values mixed in: linear RGB. */
static void fill_gradient(float *rgb)
{
    for (int y = 0; y < GRAD_H; y++)
        for (int x = 0; x < GRAD_W; x++) {
            float *p = rgb + 3 * (y * GRAD_W + x);
            p[0] = (float)x / (GRAD_W - 1);
            p[1] = (float)y / (GRAD_H - 1);
            p[2] = (float)(x * GRAD_H + y) / (GRAD_W * GRAD_H) * 1.5f - 0.25f; /* [-0.25, 1.25) */
        }
    rgb[3 * 7 + 0] = NAN;
    rgb[3 * 8 + 1] = -INFINITY;
    rgb[3 * 9 + 2] = 1e30f;
}

/* Lossless 8-bit formats (PNG, and the others to cover each writer's path:
 * TIFF is written by OIIO itself, the rest through the checked file). */
Test(dump, eight_bit_round_trip_is_srgb_encoded)
{
    const char *names[] = {"grad.png", "grad.tif", "grad.bmp", "grad.tga", "grad.ppm", "grad.sgi"};
    float rgb[GRAD_W * GRAD_H * 3];
    fill_gradient(rgb);
    /* known values in the first pixels */
    rgb[0] = 0.0f, rgb[1] = 1.0f, rgb[2] = 0.5f, rgb[3] = 0.214f, rgb[4] = 0.18f, rgb[5] = 2.0f;

    for (size_t n = 0; n < sizeof names / sizeof names[0]; n++) {
        char path[512];
        in_tmp(path, names[n]);
        tess_error err = {""};
        cr_assert(dump_write_rgb(path, GRAD_W, GRAD_H, rgb, &err), "%s", err.msg);

        int w = 0, h = 0;
        uint8_t *got = NULL;
        cr_assert(dump_read_rgb8(path, &w, &h, &got, &err), "%s", err.msg);
        cr_assert_eq(w, GRAD_W);
        cr_assert_eq(h, GRAD_H);
        for (int i = 0; i < GRAD_W * GRAD_H * 3; i++)
            cr_assert_eq(got[i], dump_srgb_encode_u8(rgb[i]), "%s value %d: %g -> %d", names[n], i, (double)rgb[i],
                         got[i]);
        const uint8_t first[] = {0, 255, 188, 127, 118, 255};
        cr_assert_arr_eq(got, first, sizeof first, "%s", names[n]);
        cr_assert_eq(got[3 * 7 + 0], 0);   /* NaN */
        cr_assert_eq(got[3 * 8 + 1], 0);   /* -inf */
        cr_assert_eq(got[3 * 9 + 2], 255); /* 1e30 */
        free(got);

        /* the float reader returns the stored 8-bit codes scaled to [0, 1] */
        float *gotf = NULL;
        cr_assert(dump_read_rgbf(path, &w, &h, &gotf, &err), "%s", err.msg);
        for (int i = 0; i < GRAD_W * GRAD_H * 3; i++)
            cr_assert_float_eq(gotf[i], dump_srgb_encode_u8(rgb[i]) / 255.0f, 1e-6f, "%s value %d", names[n], i);
        free(gotf);
    }
}

/* Float formats keep every bit, values above 1 and below 0 included. */
Test(dump, float_formats_round_trip_bit_exact)
{
    const char *names[] = {"grad.exr", "GRAD_UPPER.EXR"};
    float rgb[GRAD_W * GRAD_H * 3];
    fill_gradient(rgb);
    rgb[3 * 7 + 0] = 65504.5f; /* beyond half float: proves FLOAT, not HALF */
    rgb[3 * 8 + 1] = -3.0f;
    rgb[3 * 9 + 2] = 1e-20f;
    rgb[10] = 3.14159265f;
    for (size_t n = 0; n < sizeof names / sizeof names[0]; n++) {
        char path[512];
        in_tmp(path, names[n]);
        tess_error err = {""};
        cr_assert(dump_write_rgb(path, GRAD_W, GRAD_H, rgb, &err), "%s", err.msg);
        int w = 0, h = 0;
        float *got = NULL;
        cr_assert(dump_read_rgbf(path, &w, &h, &got, &err), "%s", err.msg);
        cr_assert_eq(w, GRAD_W);
        cr_assert_eq(h, GRAD_H);
        for (int i = 0; i < GRAD_W * GRAD_H * 3; i++)
            cr_assert_eq(float_bits(got[i]), float_bits(rgb[i]), "%s value %d: wrote %.9g, read %.9g", names[n], i,
                         (double)rgb[i], (double)got[i]);
        free(got);
    }
}

/* A grey file is replicated to RGB (a hand-made binary PGM). */
Test(dump, read_grey_replicates)
{
    char path[512];
    in_tmp(path, "grey.pgm");
    const char pgm[] = "P5\n3 2\n255\n\x00\x40\x80\xc0\xfe\xff";
    write_bytes(path, pgm, sizeof pgm - 1);

    tess_error err = {""};
    int w = 0, h = 0;
    uint8_t *got = NULL;
    cr_assert(dump_read_rgb8(path, &w, &h, &got, &err), "%s", err.msg);
    cr_assert_eq(w, 3);
    cr_assert_eq(h, 2);
    const uint8_t want[] = {0, 0, 0, 0x40, 0x40, 0x40, 0x80, 0x80, 0x80, 0xc0, 0xc0, 0xc0, 0xfe, 0xfe, 0xfe, 0xff, 0xff, 0xff};
    cr_assert_arr_eq(got, want, sizeof want);
    free(got);
}

/* RGBA drops alpha and keeps the stored colour (not premultiplied): a
 * hand-made uncompressed 32-bit TGA, top-left origin, BGRA pixels. */
Test(dump, read_rgba_drops_alpha_unpremultiplied)
{
    char path[512];
    in_tmp(path, "rgba.tga");
    const uint8_t tga[18 + 2 * 4] = {
        0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, /* uncompressed true colour, no colour map, origin 0,0 */
        2, 0, 1, 0, 32, 0x28,               /* 2x1, 32 bpp, 8 alpha bits, top-left origin */
        50, 100, 200, 128,                  /* B G R A */
        7, 8, 9, 255,
    };
    write_bytes(path, tga, sizeof tga);

    tess_error err = {""};
    int w = 0, h = 0;
    uint8_t *got = NULL;
    cr_assert(dump_read_rgb8(path, &w, &h, &got, &err), "%s", err.msg);
    cr_assert_eq(w, 2);
    cr_assert_eq(h, 1);
    const uint8_t want[] = {200, 100, 50, 9, 8, 7};
    cr_assert_arr_eq(got, want, sizeof want, "got %d %d %d  %d %d %d", got[0], got[1], got[2], got[3], got[4], got[5]);
    free(got);
}

/* ---- write errors ---- */

static const float one_pixel[3] = {0.5f, 0.5f, 0.5f};

/* Writing `path` fails, names it in the message, and leaves no file. */
static void assert_write_fails(const char *path, int w, int h, const float *rgb, const char *also_in_msg)
{
    tess_error err = {""};
    cr_assert_not(dump_write_rgb(path, w, h, rgb, &err), "writing %s succeeded", path);
    cr_assert_not_null(strstr(err.msg, path), "message does not name %s: %s", path, err.msg);
    if (also_in_msg)
        cr_assert_not_null(strstr(err.msg, also_in_msg), "message lacks '%s': %s", also_in_msg, err.msg);
    cr_assert_not(file_exists(path), "%s left behind", path);
}

Test(dump, write_into_missing_directory_fails)
{
    char path[512];
    assert_write_fails(in_tmp(path, "no/such/dir/x.png"), 1, 1, one_pixel, NULL);
    assert_write_fails(in_tmp(path, "no/such/dir/x.exr"), 1, 1, one_pixel, NULL);
}

/* A regular file as parent directory: fails even as root, unlike chmod. */
Test(dump, write_below_regular_file_fails)
{
    char parent[512], path[512];
    write_bytes(in_tmp(parent, "plain_file"), "x", 1);
    assert_write_fails(in_tmp(path, "plain_file/x.png"), 1, 1, one_pixel, NULL);
    assert_write_fails(in_tmp(path, "plain_file/x.exr"), 1, 1, one_pixel, NULL);
}

Test(dump, write_unknown_extension_fails)
{
    char path[512];
    assert_write_fails(in_tmp(path, "frame.xyz123"), 1, 1, one_pixel, NULL);
    assert_write_fails(in_tmp(path, "no_extension"), 1, 1, one_pixel, NULL);
}

Test(dump, write_bad_size_or_data_fails)
{
    char path[512];
    in_tmp(path, "bad.png");
    assert_write_fails(path, 0, 0, one_pixel, "image size 0x0");
    assert_write_fails(path, -1, 5, one_pixel, "image size -1x5");
    assert_write_fails(path, 5, 0, one_pixel, "image size 5x0");
    assert_write_fails(path, 1, 1, NULL, "no pixel data");
}

/* Fault injection: the file opens but every write hits ENOSPC (/dev/full).
 * The write must fail and the partial file (here the symlink) be removed. */
Test(dump, write_to_full_device_fails)
{
    if (access("/dev/full", W_OK) != 0) {
        remove_tmp_dir(); /* a skipped test gets no .fini */
        cr_skip_test("no writable /dev/full");
    }
    const char *names[] = {"full.png", "full.exr", "full.jpg"};
    float rgb[64 * 64 * 3];
    for (int i = 0; i < 64 * 64 * 3; i++)
        rgb[i] = (float)((i * 7919) % 1000) / 1000.0f; /* poorly compressible */
    for (size_t n = 0; n < sizeof names / sizeof names[0]; n++) {
        char path[512];
        in_tmp(path, names[n]);
        cr_assert_eq(symlink("/dev/full", path), 0);
        assert_write_fails(path, 64, 64, rgb, NULL);
    }
}

/* ---- read errors ---- */

/* Reading `path` fails, names it, and leaves the outputs empty. */
static void assert_read_fails(const char *path)
{
    tess_error err = {""};
    int w = -1, h = -1;
    uint8_t *got8 = (uint8_t *)"sentinel";
    cr_assert_not(dump_read_rgb8(path, &w, &h, &got8, &err), "reading %s succeeded", path);
    cr_assert_not_null(strstr(err.msg, path), "message does not name %s: %s", path, err.msg);
    cr_assert_null(got8);
    cr_assert_eq(w, 0);
    cr_assert_eq(h, 0);

    tess_error errf = {""};
    float *gotf = NULL;
    cr_assert_not(dump_read_rgbf(path, &w, &h, &gotf, &errf), "reading %s succeeded", path);
    cr_assert_not_null(strstr(errf.msg, path), "message does not name %s: %s", path, errf.msg);
    cr_assert_null(gotf);
}

Test(dump, read_missing_file_fails)
{
    char path[512];
    assert_read_fails(in_tmp(path, "missing.png"));
    assert_read_fails(in_tmp(path, "missing.exr"));
}

Test(dump, read_garbage_png_fails)
{
    char path[512];
    in_tmp(path, "garbage.png");
    const char garbage[] = "this is not a PNG file at all, just some bytes\x01\x02\x03";
    write_bytes(path, garbage, sizeof garbage - 1);
    assert_read_fails(path);
}

/* A valid header followed by missing data: the failure comes from
 * read_image, after a successful open. */
Test(dump, read_truncated_png_fails)
{
    char path[512];
    in_tmp(path, "cut.png");
    enum { N = 64 };
    float rgb[N * N * 3];
    for (int i = 0; i < N * N * 3; i++)
        rgb[i] = (float)((i * 7919) % 1000) / 1000.0f; /* poorly compressible */
    tess_error err = {""};
    cr_assert(dump_write_rgb(path, N, N, rgb, &err), "%s", err.msg);
    cr_assert_eq(truncate(path, 200), 0);
    assert_read_fails(path);
}

Test(dump, null_arguments_fail)
{
    tess_error err = {""};
    cr_assert_not(dump_write_rgb(NULL, 1, 1, one_pixel, &err));
    cr_assert(tess_error_is_set(&err));
    cr_assert_not(dump_write_rgb("", 1, 1, one_pixel, NULL)); /* err may be NULL */

    int w, h;
    uint8_t *got = NULL;
    tess_error err2 = {""};
    cr_assert_not(dump_read_rgb8(NULL, &w, &h, &got, &err2));
    cr_assert(tess_error_is_set(&err2));

    char out[16];
    tess_error err3 = {""};
    cr_assert_not(dump_frame_path(NULL, 1, true, out, sizeof out, &err3));
    cr_assert(tess_error_is_set(&err3));
    tess_error err4 = {""};
    cr_assert_not(dump_frame_path("f.png", 1, true, out, 0, &err4));
    cr_assert(tess_error_is_set(&err4));
}

/* ---- frame paths ---- */

/* dump_frame_path(pattern, frame, sequence) into a roomy buffer must give `want`. */
static void assert_frame_path(const char *pattern, int frame, bool sequence, const char *want)
{
    char out[256];
    tess_error err = {""};
    cr_assert(dump_frame_path(pattern, frame, sequence, out, sizeof out, &err), "%s: %s", pattern, err.msg);
    cr_assert_str_eq(out, want, "pattern '%s' frame %d", pattern, frame);
}

static void assert_frame_path_fails(const char *pattern, int frame, size_t out_bytes, const char *also_in_msg)
{
    char out[256];
    tess_error err = {""};
    cr_assert_not(dump_frame_path(pattern, frame, true, out, out_bytes, &err), "'%s' gave '%s'", pattern, out);
    cr_assert_not_null(strstr(err.msg, pattern), "message does not name '%s': %s", pattern, err.msg);
    if (also_in_msg)
        cr_assert_not_null(strstr(err.msg, also_in_msg), "message lacks '%s': %s", also_in_msg, err.msg);
}

Test(dump, frame_path_fields)
{
    assert_frame_path("out/f_####.png", 7, true, "out/f_0007.png");
    assert_frame_path("#", 7, true, "7");
    assert_frame_path("f_%04d.png", 42, true, "f_0042.png");
    assert_frame_path("f_%d.png", 42, true, "f_42.png");
    assert_frame_path("f_%d.png", 0, true, "f_0.png");
    assert_frame_path("f_##.png", 12345, true, "f_12345.png"); /* '#'s are a minimum width */
    assert_frame_path("f_##.png", 3, false, "f_03.png");       /* a field is filled even for one frame */
    assert_frame_path("100%_##.png", 5, true, "100%_05.png");  /* a lone '%' is literal */
}

Test(dump, frame_path_auto_insert)
{
    assert_frame_path("out/f.png", 3, true, "out/f_0003.png");
    assert_frame_path("out/f", 3, true, "out/f_0003");
    assert_frame_path("out.v2/f", 3, true, "out.v2/f_0003"); /* a dot in a directory is no extension */
    assert_frame_path("a.tar.png", 3, true, "a.tar_0003.png");
    assert_frame_path(".hidden", 3, true, ".hidden_0003");
    assert_frame_path("f.png", 12345, true, "f_12345.png");
    assert_frame_path("out/f.png", 3, false, "out/f.png"); /* not a sequence: as is */
}

Test(dump, frame_path_errors)
{
    assert_frame_path_fails("f_##_##.png", 1, 256, "more than one");
    assert_frame_path_fails("f_%d_#.png", 1, 256, "more than one");
    assert_frame_path_fails("f_%04d%d.png", 1, 256, "more than one");
    assert_frame_path_fails("f_%4d.png", 1, 256, "%0Nd");
    assert_frame_path_fails("f_####.png", -1, 256, "negative");
    assert_frame_path_fails("f_####.png", 1, 10, "11 bytes"); /* needs 10 characters + NUL */
    assert_frame_path_fails("f_##.png", 12345, 11, NULL);
    assert_frame_path_fails("f.png", 1, 10, NULL); /* auto-insert overflows too */

    char out[11];
    tess_error err = {""};
    cr_assert(dump_frame_path("f_####.png", 1, true, out, sizeof out, &err), "%s", err.msg); /* exact fit */
    cr_assert_str_eq(out, "f_0001.png");
}
