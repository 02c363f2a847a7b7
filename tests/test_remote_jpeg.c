/* test_remote_jpeg.c - the remote view's JPEG frames (remote/jpeg.h):
 * encode/decode round trips keep the size and come close to the frame
 * (closer and bigger at higher quality, smaller with chroma subsampling),
 * colour channels stay in place, and bad arguments or a broken file give
 * an error instead of a crash. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "remote/jpeg.h"

#define W 96
#define H 64

/* A frame with smooth gradients, a hard edge and saturated colour blocks. */
static void test_frame(uint32_t *xrgb, int stride_px)
{
    for (int y = 0; y < H; y++)
        for (int x = 0; x < stride_px; x++) {
            uint32_t r = (uint32_t)(x * 255 / (W - 1)), g = (uint32_t)(y * 255 / (H - 1)), b = x < W / 2 ? 40u : 200u;
            if (x >= 8 && x < 24 && y >= 8 && y < 24) /* pure red */
                r = 255, g = 0, b = 0;
            if (x >= 72 && x < 88 && y >= 40 && y < 56) /* pure blue */
                r = 0, g = 0, b = 255;
            xrgb[(size_t)y * (size_t)stride_px + (size_t)x] = x < W ? (r << 16) | (g << 8) | b : 0xdeadbeefu;
        }
}

/* Mean absolute code difference over R, G, B. */
static double mean_abs_error(const uint32_t *a, int stride_a, const uint32_t *b)
{
    double sum = 0.0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int s = 0; s < 24; s += 8)
                sum += abs((int)((a[y * stride_a + x] >> s) & 0xff) - (int)((b[y * W + x] >> s) & 0xff));
    return sum / (3.0 * W * H);
}

static size_t round_trip(remote_jpeg *j, const uint32_t *frame, int stride_px, int quality, remote_subsampling sub,
                         double *error)
{
    tess_error err = {{0}};
    const uint8_t *file = NULL;
    size_t bytes = 0;
    cr_assert(remote_jpeg_encode(j, frame, W, H, stride_px, quality, sub, &file, &bytes, &err), "%s", err.msg);
    cr_assert_gt(bytes, 100);
    cr_assert(file[0] == 0xff && file[1] == 0xd8, "a JPEG starts with SOI");
    uint32_t *decoded = NULL;
    int w = 0, h = 0;
    cr_assert(remote_jpeg_decode(file, bytes, &decoded, &w, &h, &err), "%s", err.msg);
    cr_assert_eq(w, W);
    cr_assert_eq(h, H);
    *error = mean_abs_error(frame, stride_px, decoded);
    free(decoded);
    return bytes;
}

Test(remote_jpeg, round_trip_is_close_and_quality_trades_bytes_for_error)
{
    uint32_t frame[W * H];
    test_frame(frame, W);
    tess_error err = {{0}};
    remote_jpeg *j = remote_jpeg_create(&err);
    cr_assert(j, "%s", err.msg);
    double e95, e30, e420;
    size_t b95 = round_trip(j, frame, W, 95, REMOTE_SUBSAMPLING_444, &e95);
    size_t b30 = round_trip(j, frame, W, 30, REMOTE_SUBSAMPLING_444, &e30);
    size_t b420 = round_trip(j, frame, W, 95, REMOTE_SUBSAMPLING_420, &e420);
    cr_assert_lt(e95, 2.0, "quality 95, 4:4:4: mean error %.3f codes", e95);
    cr_assert_gt(e30, e95, "quality 30 errs more (%.3f) than 95 (%.3f)", e30, e95);
    cr_assert_lt(b30, b95, "quality 30 is smaller (%zu) than 95 (%zu)", b30, b95);
    cr_assert_lt(b420, b95, "4:2:0 is smaller (%zu) than 4:4:4 (%zu)", b420, b95);
    cr_assert_gt(e420, e95, "4:2:0 loses colour detail: %.3f against %.3f", e420, e95);
    remote_jpeg_destroy(j);
}

/* The red block stays red and the blue one blue: the pixel format's byte order is right. */
Test(remote_jpeg, colour_channels_stay_in_place)
{
    uint32_t frame[W * H];
    test_frame(frame, W);
    tess_error err = {{0}};
    remote_jpeg *j = remote_jpeg_create(&err);
    const uint8_t *file;
    size_t bytes;
    cr_assert(remote_jpeg_encode(j, frame, W, H, W, 90, REMOTE_SUBSAMPLING_444, &file, &bytes, &err), "%s", err.msg);
    uint32_t *d;
    int w, h;
    cr_assert(remote_jpeg_decode(file, bytes, &d, &w, &h, &err), "%s", err.msg);
    uint32_t red = d[16 * W + 16], blue = d[48 * W + 80];
    cr_assert_gt((red >> 16) & 0xff, 230, "red block: %06x", red & 0xffffff);
    cr_assert_lt(red & 0xff, 30, "red block: %06x", red & 0xffffff);
    cr_assert_gt(blue & 0xff, 230, "blue block: %06x", blue & 0xffffff);
    cr_assert_lt((blue >> 16) & 0xff, 30, "blue block: %06x", blue & 0xffffff);
    free(d);
    remote_jpeg_destroy(j);
}

/* A stride wider than the picture: the words past each row are not encoded. */
Test(remote_jpeg, stride_wider_than_the_picture)
{
    enum { STRIDE = W + 13 };
    static uint32_t padded[STRIDE * H];
    uint32_t tight[W * H];
    test_frame(padded, STRIDE);
    test_frame(tight, W);
    tess_error err = {{0}};
    remote_jpeg *j = remote_jpeg_create(&err);
    double e_padded, e_tight;
    size_t b_padded = round_trip(j, padded, STRIDE, 80, REMOTE_SUBSAMPLING_420, &e_padded);
    size_t b_tight = round_trip(j, tight, W, 80, REMOTE_SUBSAMPLING_420, &e_tight);
    cr_assert_eq(b_padded, b_tight);
    cr_assert_float_eq(e_padded, e_tight, 1e-12);
    remote_jpeg_destroy(j);
}

Test(remote_jpeg, bad_arguments_and_broken_files_are_errors)
{
    uint32_t frame[W * H];
    test_frame(frame, W);
    tess_error err = {{0}};
    remote_jpeg *j = remote_jpeg_create(&err);
    const uint8_t *file;
    size_t bytes;
    cr_assert_not(remote_jpeg_encode(j, frame, W, H, W, 0, REMOTE_SUBSAMPLING_420, &file, &bytes, &err));
    cr_assert(strstr(err.msg, "quality 0"), "%s", err.msg);
    cr_assert_not(remote_jpeg_encode(j, frame, W, H, W - 1, 80, REMOTE_SUBSAMPLING_420, &file, &bytes, &err));
    cr_assert_not(remote_jpeg_encode(j, frame, 0, H, W, 80, REMOTE_SUBSAMPLING_420, &file, &bytes, &err));
    cr_assert(remote_jpeg_encode(j, frame, W, H, W, 80, REMOTE_SUBSAMPLING_420, &file, &bytes, &err), "%s", err.msg);
    uint8_t *broken = malloc(bytes);
    memcpy(broken, file, bytes);
    uint32_t *d = (uint32_t *)1;
    int w, h;
    cr_assert_not(remote_jpeg_decode(broken, 40, &d, &w, &h, &err), "a truncated header");
    cr_assert_null(d);
    cr_assert(strstr(err.msg, "jpeg:"), "%s", err.msg);
    memset(broken, 0x5a, 64);
    cr_assert_not(remote_jpeg_decode(broken, bytes, &d, &w, &h, &err), "no SOI marker");
    free(broken);
    remote_jpeg_destroy(j);
}

Test(remote_jpeg, subsampling_names)
{
    remote_subsampling s;
    cr_assert(remote_subsampling_parse("444", &s) && s == REMOTE_SUBSAMPLING_444);
    cr_assert(remote_subsampling_parse("422", &s) && s == REMOTE_SUBSAMPLING_422);
    cr_assert(remote_subsampling_parse("420", &s) && s == REMOTE_SUBSAMPLING_420);
    cr_assert_not(remote_subsampling_parse("411", &s));
    cr_assert_not(remote_subsampling_parse(NULL, &s));
    cr_assert_str_eq(remote_subsampling_name(REMOTE_SUBSAMPLING_420), "420");
}
