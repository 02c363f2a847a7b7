/* report_img.c - the image chores of `make report` (tools/report/report.sh)
 * that no tessera command does: averaging renders into a reference, finding
 * where two images differ most, and cutting one region out of several images
 * into a side-by-side picture. Images go through wall/dump.h (OpenImageIO):
 * EXR and other float formats are linear as stored, 8-bit formats sRGB.
 *
 * usage:
 *   report_img mean OUT IN...
 *       OUT = the per-pixel mean of the IN images (linear RGB, summed in
 *       double in the order given); every IN the same size.
 *   report_img region SIZE REF TEST
 *       prints "X Y": the top-left corner of the SIZE x SIZE window (on a
 *       grid of SIZE / 8 pixels) where TEST differs most from REF (sum of
 *       squared differences of the values clamped to [0, 1], as a display
 *       shows them; the first such window in row order on ties).
 *   report_img montage OUT X Y SIZE ZOOM COLS IN...
 *       the SIZE x SIZE region at (X, Y) of each IN, enlarged ZOOM times
 *       (nearest pixel), in rows of COLS cells GAP_PX apart on grey; an IN
 *       of "-" leaves its cell empty. The region must lie inside every IN.
 *   report_img jpeg IMAGE RUNS QUALITY...
 *       the remote view's JPEG frames (remote/jpeg.h) of IMAGE: the picture
 *       as the page would get it without loss (8-bit sRGB, engine/base/srgb8.h) is
 *       compressed at each QUALITY with each chroma subsampling (4:4:4,
 *       4:2:2, 4:2:0), RUNS times; prints one tab-separated line each:
 *       subsampling, quality, JPEG bytes, the median encode time in ms and
 *       the mean LDR-FLIP of the decoded picture against the lossless one
 *       (metrics/flip.h, FLIP's default viewer: 67 pixels per degree) and
 *       its PSNR in dB over the 8-bit codes (peak 255), after
 *       a "# convert_ms M" line: the median time of the float-to-8-bit
 *       conversion a frame needs first (remote display's show()).
 * Exit status 0, 1 for a failure (said on stderr, naming the file), 2 for a
 * bad command line. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/clock.h"
#include "engine/base/sample_ring.h"
#include "engine/base/srgb.h"
#include "metrics/flip.h"
#include "remote/jpeg.h"
#include "wall/dump.h"
#include "engine/base/srgb8.h"

#define GAP_PX 4            /* between montage cells */
#define GAP_LINEAR 0.2f     /* grey of the gaps and empty cells (linear) */
#define REGION_GRID_DIV 8   /* window positions every SIZE / 8 pixels */
#define MAX_INPUTS 64

typedef struct image {
    int w, h;
    float *rgb; /* linear, 3 per pixel, top row first; owned */
} image;

static bool image_read(const char *path, image *img)
{
    tess_error err = {{0}};
    if (!dump_read_linear_rgb(path, &img->w, &img->h, &img->rgb, &err)) {
        fprintf(stderr, "report_img: %s\n", err.msg);
        return false;
    }
    return true;
}

static bool image_write(const char *path, const image *img)
{
    tess_error err = {{0}};
    if (!dump_write_rgb(path, img->w, img->h, img->rgb, &err)) {
        fprintf(stderr, "report_img: %s\n", err.msg);
        return false;
    }
    return true;
}

/* A whole decimal number in [lo, hi]; false (said) otherwise. */
static bool parse_int(const char *text, const char *what, int lo, int hi, int *out)
{
    char *end;
    long v = strtol(text, &end, 10);
    if (end == text || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "report_img: %s '%s': expected a whole number in %d..%d\n", what, text, lo, hi);
        return false;
    }
    *out = (int)v;
    return true;
}

static int cmd_mean(int argc, char **argv)
{
    if (argc < 4 || argc - 3 > MAX_INPUTS) {
        fprintf(stderr, "usage: report_img mean OUT IN... (1..%d inputs)\n", MAX_INPUTS);
        return 2;
    }
    int code = 1, n = argc - 3;
    image first = {0}, next = {0}, out = {0};
    double *sum = NULL;
    if (!image_read(argv[3], &first))
        goto done;
    size_t values = (size_t)first.w * (size_t)first.h * 3;
    sum = calloc(values, sizeof *sum);
    out = (image){first.w, first.h, malloc(values * sizeof *out.rgb)};
    if (!sum || !out.rgb) {
        fprintf(stderr, "report_img: out of memory for %dx%d\n", first.w, first.h);
        goto done;
    }
    for (size_t i = 0; i < values; i++)
        sum[i] = first.rgb[i];
    for (int k = 1; k < n; k++) {
        if (!image_read(argv[3 + k], &next))
            goto done;
        if (next.w != first.w || next.h != first.h) {
            fprintf(stderr, "report_img: %s is %dx%d, %s is %dx%d: mean needs one size\n", argv[3 + k], next.w,
                    next.h, argv[3], first.w, first.h);
            goto done;
        }
        for (size_t i = 0; i < values; i++)
            sum[i] += next.rgb[i];
        free(next.rgb);
        next.rgb = NULL;
    }
    for (size_t i = 0; i < values; i++)
        out.rgb[i] = (float)(sum[i] / n);
    code = image_write(argv[2], &out) ? 0 : 1;
done:
    free(first.rgb);
    free(next.rgb);
    free(out.rgb);
    free(sum);
    return code;
}

static float clamp01(float v) { return v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v; }

static int cmd_region(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: report_img region SIZE REF TEST\n");
        return 2;
    }
    int size, code = 1;
    if (!parse_int(argv[2], "SIZE", 1, 1 << 14, &size))
        return 2;
    image ref = {0}, test = {0};
    double *sat = NULL; /* summed-area table, (w + 1) x (h + 1), row 0 and column 0 zero */
    if (!image_read(argv[3], &ref) || !image_read(argv[4], &test))
        goto done;
    if (ref.w != test.w || ref.h != test.h) {
        fprintf(stderr, "report_img: %s is %dx%d, %s is %dx%d: region needs one size\n", argv[3], ref.w, ref.h,
                argv[4], test.w, test.h);
        goto done;
    }
    if (size > ref.w || size > ref.h) {
        fprintf(stderr, "report_img: a %d px region does not fit in %dx%d (%s)\n", size, ref.w, ref.h, argv[3]);
        goto done;
    }
    size_t stride = (size_t)ref.w + 1;
    sat = calloc(stride * ((size_t)ref.h + 1), sizeof *sat);
    if (!sat) {
        fprintf(stderr, "report_img: out of memory for %dx%d\n", ref.w, ref.h);
        goto done;
    }
    for (int y = 0; y < ref.h; y++) {
        double row = 0.0;
        for (int x = 0; x < ref.w; x++) {
            size_t p = ((size_t)y * (size_t)ref.w + (size_t)x) * 3;
            for (int c = 0; c < 3; c++) {
                double d = (double)clamp01(ref.rgb[p + c]) - (double)clamp01(test.rgb[p + c]);
                row += d * d;
            }
            sat[(size_t)(y + 1) * stride + (size_t)(x + 1)] = sat[(size_t)y * stride + (size_t)(x + 1)] + row;
        }
    }
    int step = size / REGION_GRID_DIV > 0 ? size / REGION_GRID_DIV : 1;
    int best_x = 0, best_y = 0;
    double best = -1.0;
    for (int y = 0; y + size <= ref.h; y += step)
        for (int x = 0; x + size <= ref.w; x += step) {
            size_t y0 = (size_t)y * stride, y1 = (size_t)(y + size) * stride;
            double s = sat[y1 + (size_t)(x + size)] - sat[y1 + (size_t)x] - sat[y0 + (size_t)(x + size)] +
                       sat[y0 + (size_t)x];
            if (s > best) {
                best = s;
                best_x = x;
                best_y = y;
            }
        }
    printf("%d %d\n", best_x, best_y);
    code = 0;
done:
    free(ref.rgb);
    free(test.rgb);
    free(sat);
    return code;
}

static int cmd_montage(int argc, char **argv)
{
    if (argc < 9 || argc - 8 > MAX_INPUTS) {
        fprintf(stderr, "usage: report_img montage OUT X Y SIZE ZOOM COLS IN... (1..%d inputs, - for none)\n",
                MAX_INPUTS);
        return 2;
    }
    int x0, y0, size, zoom, cols;
    if (!parse_int(argv[3], "X", 0, 1 << 14, &x0) || !parse_int(argv[4], "Y", 0, 1 << 14, &y0) ||
        !parse_int(argv[5], "SIZE", 1, 1 << 14, &size) || !parse_int(argv[6], "ZOOM", 1, 16, &zoom) ||
        !parse_int(argv[7], "COLS", 1, MAX_INPUTS, &cols))
        return 2;
    int n = argc - 8, rows = (n + cols - 1) / cols, cell = size * zoom;
    image out = {cols * cell + (cols - 1) * GAP_PX, rows * cell + (rows - 1) * GAP_PX, NULL};
    size_t values = (size_t)out.w * (size_t)out.h * 3;
    out.rgb = malloc(values * sizeof *out.rgb);
    if (!out.rgb) {
        fprintf(stderr, "report_img: out of memory for %dx%d\n", out.w, out.h);
        return 1;
    }
    for (size_t i = 0; i < values; i++)
        out.rgb[i] = GAP_LINEAR;
    int code = 1;
    image in = {0};
    for (int k = 0; k < n; k++) {
        const char *path = argv[8 + k];
        if (!strcmp(path, "-"))
            continue;
        if (!image_read(path, &in))
            goto done;
        if (x0 + size > in.w || y0 + size > in.h) {
            fprintf(stderr, "report_img: region %dx%d at (%d, %d) is not inside %s (%dx%d)\n", size, size, x0, y0,
                    path, in.w, in.h);
            goto done;
        }
        int ox = (k % cols) * (cell + GAP_PX), oy = (k / cols) * (cell + GAP_PX);
        for (int y = 0; y < cell; y++)
            for (int x = 0; x < cell; x++) {
                const float *src = in.rgb + ((size_t)(y0 + y / zoom) * (size_t)in.w + (size_t)(x0 + x / zoom)) * 3;
                float *dst = out.rgb + ((size_t)(oy + y) * (size_t)out.w + (size_t)(ox + x)) * 3;
                memcpy(dst, src, 3 * sizeof *dst);
            }
        free(in.rgb);
        in.rgb = NULL;
    }
    code = image_write(argv[2], &out) ? 0 : 1;
done:
    free(in.rgb);
    free(out.rgb);
    return code;
}


/* XRGB8888 words -> linear RGB through the sRGB curve (what a display shows). */
static void xrgb_to_linear(const uint32_t *xrgb, size_t pixels, float *rgb)
{
    static float linear_of_code[256];
    if (linear_of_code[255] == 0.0f)
        for (int c = 0; c < 256; c++)
            linear_of_code[c] = (float)srgb_curve_decode(c / 255.0);
    for (size_t i = 0; i < pixels; i++) {
        rgb[3 * i + 0] = linear_of_code[(xrgb[i] >> 16) & 0xff];
        rgb[3 * i + 1] = linear_of_code[(xrgb[i] >> 8) & 0xff];
        rgb[3 * i + 2] = linear_of_code[xrgb[i] & 0xff];
    }
}

static int cmd_jpeg(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: report_img jpeg IMAGE RUNS QUALITY...\n");
        return 2;
    }
    int runs, qualities[32], quality_count = argc - 4;
    if (quality_count > 32 || !parse_int(argv[3], "RUNS", 1, 1000, &runs))
        return 2;
    for (int i = 0; i < quality_count; i++)
        if (!parse_int(argv[4 + i], "QUALITY", REMOTE_JPEG_QUALITY_MIN, REMOTE_JPEG_QUALITY_MAX, &qualities[i]))
            return 2;
    image img;
    if (!image_read(argv[2], &img))
        return 1;
    size_t pixels = (size_t)img.w * (size_t)img.h;
    uint32_t *lossless = malloc(pixels * sizeof *lossless);
    float *reference = malloc(pixels * 3 * sizeof *reference), *test = malloc(pixels * 3 * sizeof *test);
    float *error = malloc(pixels * sizeof *error);
    double *times_ms = malloc((size_t)runs * sizeof *times_ms);
    remote_jpeg *j = NULL;
    tess_error err = {{0}};
    int status = 1;
    if (!lossless || !reference || !test || !error || !times_ms) {
        fprintf(stderr, "report_img: out of memory for %dx%d\n", img.w, img.h);
        goto done;
    }
    for (int r = 0; r < runs; r++) {
        double t0 = clock_monotonic_s();
        for (int y = 0; y < img.h; y++)
            srgb8_encode_xrgb(img.rgb + (size_t)y * (size_t)img.w * 3, 1, img.w, lossless + (size_t)y * (size_t)img.w);
        times_ms[r] = (clock_monotonic_s() - t0) * 1e3;
    }
    printf("# convert_ms %.3f\n", median_sorting(times_ms, (size_t)runs));
    xrgb_to_linear(lossless, pixels, reference);
    if (!(j = remote_jpeg_create(&err)))
        goto fail;
    for (int sub = REMOTE_SUBSAMPLING_444; sub <= REMOTE_SUBSAMPLING_420; sub++) {
        for (int q = 0; q < quality_count; q++) {
            const uint8_t *file = NULL;
            size_t bytes = 0;
            for (int r = 0; r < runs; r++) {
                double t0 = clock_monotonic_s();
                if (!remote_jpeg_encode(j, lossless, img.w, img.h, img.w, qualities[q], (remote_subsampling)sub, &file,
                                        &bytes, &err))
                    goto fail;
                times_ms[r] = (clock_monotonic_s() - t0) * 1e3;
            }
            uint32_t *decoded = NULL;
            int dw = 0, dh = 0;
            if (!remote_jpeg_decode(file, bytes, &decoded, &dw, &dh, &err))
                goto fail;
            bool same_size = dw == img.w && dh == img.h;
            double squared = 0.0; /* sum of squared code differences over R, G, B */
            if (same_size) {
                xrgb_to_linear(decoded, pixels, test);
                for (size_t i = 0; i < pixels; i++)
                    for (int shift = 0; shift < 24; shift += 8) {
                        double d = (double)((lossless[i] >> shift) & 0xff) - (double)((decoded[i] >> shift) & 0xff);
                        squared += d * d;
                    }
            }
            free(decoded);
            if (!same_size) {
                fprintf(stderr, "report_img: the JPEG decoded to %dx%d, not %dx%d\n", dw, dh, img.w, img.h);
                goto done;
            }
            if (!flip_ldr_map(reference, test, img.w, img.h, FLIP_DEFAULT_PPD, 2, error, &err))
                goto fail;
            double sum = 0.0;
            for (size_t i = 0; i < pixels; i++)
                sum += error[i];
            double mse = squared / (3.0 * (double)pixels);
            printf("%s\t%d\t%zu\t%.3f\t%.6f\t%.2f\n", remote_subsampling_name((remote_subsampling)sub), qualities[q],
                   bytes, median_sorting(times_ms, (size_t)runs), sum / (double)pixels,
                   mse > 0.0 ? 10.0 * log10(255.0 * 255.0 / mse) : 99.0);
        }
    }
    status = 0;
    goto done;
fail:
    fprintf(stderr, "report_img: %s: %s\n", argv[2], err.msg);
done:
    remote_jpeg_destroy(j);
    free(lossless);
    free(reference);
    free(test);
    free(error);
    free(times_ms);
    free(img.rgb);
    return status;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "jpeg"))
        return cmd_jpeg(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "mean"))
        return cmd_mean(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "region"))
        return cmd_region(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "montage"))
        return cmd_montage(argc, argv);
    fprintf(stderr, "usage: report_img mean OUT IN... | region SIZE REF TEST | jpeg IMAGE RUNS QUALITY... |\n"
                    "       montage OUT X Y SIZE ZOOM COLS IN...\n");
    return 2;
}
