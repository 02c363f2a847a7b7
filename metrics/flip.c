/* flip.c (metrics) - LDR-FLIP (flip.h; Andersson et al., HPG 2020).
 *
 * Work is split into bands of rows; each band is computed on its own from
 * the inputs. A band streams its rows through two ring buffers of
 * horizontally filtered rows (one for the colour filters, one for the
 * feature filters), each holding the 2r + 1 source rows the vertical filter
 * of the current output row reads, so memory is O(width * radius) per
 * thread whatever the image height. */
#include "flip.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/parallel.h"

#define FLIP_PI 3.14159265358979323846

/* The paper's constants (section 3). */
#define FLIP_QC 0.7   /* exponent of the HyAB colour distance */
#define FLIP_PC 0.4   /* breakpoint, as a fraction of the largest distance ... */
#define FLIP_PT 0.95  /* ... which maps to this error */
#define FLIP_GW 0.082 /* feature filter width in degrees (standard deviation = GW / 2) */
#define FLIP_QF 0.5   /* exponent of the feature difference */

/* Contrast sensitivity filters: a * sqrt(pi / b) * exp(-pi^2 x^2 / b), x in
 * degrees, one term for Y and Cx, a sum of two for Cz (the paper's table 1). */
#define FLIP_Y_B 0.0047 /* (a = 1 for Y and Cx: it cancels in the normalisation) */
#define FLIP_CX_B 0.0053
#define FLIP_CZ_A1 34.1
#define FLIP_CZ_B1 0.04
#define FLIP_CZ_A2 13.5
#define FLIP_CZ_B2 0.025
#define FLIP_WIDEST_B FLIP_CZ_B1 /* the largest b: it sets the colour filter's radius */

/* Taps of the widest filter at FLIP_MAX_PPD: the colour radius is
 * ceil(3 * sqrt(0.04 / (2 pi^2)) * 1000) = 136, the feature radius
 * ceil(1.5 * 0.082 * 1000) = 123; 2 * 136 + 1 = 273, rounded up. */
#define FLIP_MAX_TAPS 280

/* Rows per band: the unit of work a thread takes. A band recomputes the 2r
 * rows around it that its neighbours also filter, 20 % extra at 67 ppd. */
#define FLIP_BAND_ROWS 96

/* linear RGB (sRGB primaries) -> XYZ, D65: the rational form the FLIP
 * reference uses (image-engineering.de's derivation from the primaries). */
static const double rgb_to_xyz[3][3] = {
    {10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0},
    {2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0},
    {1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0},
};

typedef struct flip_constants {
    double xyz_to_rgb[3][3];  /* inverse of rgb_to_xyz */
    double white[3];          /* XYZ of linear RGB (1, 1, 1): the D65 reference white, Yn = 1 */
    double cmax;              /* largest colour distance (green vs blue), already ^ FLIP_QC */
    double pccmax;            /* FLIP_PC * cmax */
    int color_r, feature_r;   /* filter radii in pixels */
    /* Colour filters, 2 color_r + 1 taps each, offset k - color_r pixels.
     * Y and Cx sum to 1; the two Cz terms are each scaled by
     * 1 / sqrt(S1^2 + S2^2) so that the 2-D filter g1 g1' + g2 g2' sums to 1. */
    double y[FLIP_MAX_TAPS], cx[FLIP_MAX_TAPS], cz1[FLIP_MAX_TAPS], cz2[FLIP_MAX_TAPS];
    /* Feature filters, 2 feature_r + 1 taps: the Gaussian (sums to 1), its
     * first and second derivatives (positive taps sum to 1, negative to -1). */
    double g[FLIP_MAX_TAPS], dg[FLIP_MAX_TAPS], ddg[FLIP_MAX_TAPS];
} flip_constants;

static double clamp01(double v) { return v > 0.0 ? (v < 1.0 ? v : 1.0) : 0.0; } /* NaN -> 0 */

static void mat3_apply(const double m[3][3], const double in[3], double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = m[i][0] * in[0] + m[i][1] * in[1] + m[i][2] * in[2];
}

static void mat3_inverse(const double m[3][3], double out[3][3])
{
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            /* cofactor of m[j][i] */
            int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            out[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
        }
}

/* YCxCz of a linear RGB pixel (clamped to [0, 1] first). */
static void rgb_to_ycxcz(const flip_constants *k, const float *rgb, double out[3])
{
    double lin[3] = {clamp01(rgb[0]), clamp01(rgb[1]), clamp01(rgb[2])}, xyz[3];
    mat3_apply(rgb_to_xyz, lin, xyz);
    double x = xyz[0] / k->white[0], y = xyz[1] / k->white[1], z = xyz[2] / k->white[2];
    out[0] = 116.0 * y - 16.0;
    out[1] = 500.0 * (x - y);
    out[2] = 200.0 * (y - z);
}

static double lab_f(double t)
{
    const double delta = 6.0 / 29.0;
    return t > delta * delta * delta ? cbrt(t) : t / (3.0 * delta * delta) + 4.0 / 29.0;
}

/* CIELab with the Hunt adjustment (a, b scaled by 0.01 L) of linear RGB in [0, 1]. */
static void rgb_to_hunt_lab(const flip_constants *k, const double rgb[3], double out[3])
{
    double xyz[3];
    mat3_apply(rgb_to_xyz, rgb, xyz);
    double fx = lab_f(xyz[0] / k->white[0]), fy = lab_f(xyz[1] / k->white[1]), fz = lab_f(xyz[2] / k->white[2]);
    double l = 116.0 * fy - 16.0;
    out[0] = l;
    out[1] = 0.01 * l * 500.0 * (fx - fy);
    out[2] = 0.01 * l * 200.0 * (fy - fz);
}

/* Filtered YCxCz -> linear RGB clamped to [0, 1] -> Hunt-adjusted Lab. */
static void filtered_ycxcz_to_hunt_lab(const flip_constants *k, double yy, double cx, double cz, double out[3])
{
    double y = (yy + 16.0) / 116.0;
    double xyz[3] = {(y + cx / 500.0) * k->white[0], y * k->white[1], (y - cz / 200.0) * k->white[2]}, rgb[3];
    mat3_apply(k->xyz_to_rgb, xyz, rgb);
    for (int i = 0; i < 3; i++)
        rgb[i] = clamp01(rgb[i]);
    rgb_to_hunt_lab(k, rgb, out);
}

static double hyab(const double a[3], const double b[3])
{
    return fabs(a[0] - b[0]) + hypot(a[1] - b[1], a[2] - b[2]);
}

double flip_ppd_of_viewer(double distance_m, double pixels_per_m) { return distance_m * pixels_per_m * FLIP_PI / 180.0; }

int flip_spatial_radius_px(double ppd)
{
    return (int)ceil(3.0 * sqrt(FLIP_WIDEST_B / (2.0 * FLIP_PI * FLIP_PI)) * ppd);
}

int flip_feature_radius_px(double ppd) { return (int)ceil(3.0 * 0.5 * FLIP_GW * ppd); }

static void constants_init(flip_constants *k, double ppd)
{
    memset(k, 0, sizeof *k);
    mat3_inverse(rgb_to_xyz, k->xyz_to_rgb);
    const double ones[3] = {1.0, 1.0, 1.0};
    mat3_apply(rgb_to_xyz, ones, k->white);

    const double green[3] = {0.0, 1.0, 0.0}, blue[3] = {0.0, 0.0, 1.0};
    double green_lab[3], blue_lab[3];
    rgb_to_hunt_lab(k, green, green_lab);
    rgb_to_hunt_lab(k, blue, blue_lab);
    k->cmax = pow(hyab(green_lab, blue_lab), FLIP_QC);
    k->pccmax = FLIP_PC * k->cmax;

    /* Colour filters over offsets in degrees. The constant a * sqrt(pi / b)
     * of a single-term filter cancels in its normalisation; the Cz terms keep
     * theirs, split as sqrt(a sqrt(pi / b)) per direction. */
    k->color_r = flip_spatial_radius_px(ppd);
    const double pi2 = FLIP_PI * FLIP_PI;
    double sum_y = 0.0, sum_cx = 0.0, sum_cz1 = 0.0, sum_cz2 = 0.0;
    for (int t = 0; t <= 2 * k->color_r; t++) {
        double deg = (t - k->color_r) / ppd, deg2 = deg * deg;
        k->y[t] = exp(-pi2 * deg2 / FLIP_Y_B);
        k->cx[t] = exp(-pi2 * deg2 / FLIP_CX_B);
        k->cz1[t] = sqrt(FLIP_CZ_A1 * sqrt(FLIP_PI / FLIP_CZ_B1)) * exp(-pi2 * deg2 / FLIP_CZ_B1);
        k->cz2[t] = sqrt(FLIP_CZ_A2 * sqrt(FLIP_PI / FLIP_CZ_B2)) * exp(-pi2 * deg2 / FLIP_CZ_B2);
        sum_y += k->y[t];
        sum_cx += k->cx[t];
        sum_cz1 += k->cz1[t];
        sum_cz2 += k->cz2[t];
    }
    double cz_norm = 1.0 / sqrt(sum_cz1 * sum_cz1 + sum_cz2 * sum_cz2);
    for (int t = 0; t <= 2 * k->color_r; t++) {
        k->y[t] /= sum_y;
        k->cx[t] /= sum_cx;
        k->cz1[t] *= cz_norm;
        k->cz2[t] *= cz_norm;
    }

    /* Feature filters over offsets in pixels. */
    k->feature_r = flip_feature_radius_px(ppd);
    const double sigma = 0.5 * FLIP_GW * ppd;
    double sum_g = 0.0, dg_pos = 0.0, dg_neg = 0.0, ddg_pos = 0.0, ddg_neg = 0.0;
    for (int t = 0; t <= 2 * k->feature_r; t++) {
        double x = t - k->feature_r;
        double g = exp(-(x * x) / (2.0 * sigma * sigma));
        k->g[t] = g;
        k->dg[t] = -x * g;
        k->ddg[t] = (x * x / (sigma * sigma) - 1.0) * g;
        sum_g += g;
        if (k->dg[t] > 0.0)
            dg_pos += k->dg[t];
        else
            dg_neg -= k->dg[t];
        if (k->ddg[t] > 0.0)
            ddg_pos += k->ddg[t];
        else
            ddg_neg -= k->ddg[t];
    }
    for (int t = 0; t <= 2 * k->feature_r; t++) {
        k->g[t] /= sum_g;
        k->dg[t] /= k->dg[t] > 0.0 ? dg_pos : dg_neg;
        k->ddg[t] /= k->ddg[t] > 0.0 ? ddg_pos : ddg_neg;
    }
}

/* Channels of the horizontally filtered rows in the rings; each ring row
 * holds channel after channel, `width` doubles each. */
enum { C_Y, C_CX, C_CZ1, C_CZ2, C_CHANNELS };  /* colour, per image */
enum { F_DG, F_DDG, F_G, F_CHANNELS };         /* features, per image */

/* One worker's buffers (flip_work.scratch[worker]). */
typedef struct flip_scratch {
    double *pad;        /* one source row with `r` repeated edge pixels each side, 3 values per pixel */
    double *color_ring; /* (2 color_r + 1) rows x 2 images x C_CHANNELS x width */
    double *feature_ring; /* (2 feature_r + 1) rows x 2 images x F_CHANNELS x width */
    double *acc;        /* 2 x C_CHANNELS x width: one row filtered both ways */
    double *color_error; /* width: the colour error of one row */
    double *feature_acc; /* 2 images x 4 x width: dx, ddx, dy, ddy of one row */
} flip_scratch;

typedef struct flip_work {
    const flip_constants *k;
    const float *rgb[2]; /* reference, test */
    int w, h;
    float *error;
    flip_scratch *scratch; /* one per worker */
} flip_work;

/* Source row `row` of image `img`, horizontally filtered with the colour filters, into `out`. */
static void color_row(const flip_work *wk, double *pad, int img, int row, double *out)
{
    const flip_constants *k = wk->k;
    const int w = wk->w, r = k->color_r;
    const float *src = wk->rgb[img] + (size_t)row * (size_t)w * 3;
    for (int x = 0; x < w; x++)
        rgb_to_ycxcz(k, src + 3 * (size_t)x, pad + 3 * ((size_t)x + (size_t)r));
    for (int p = 0; p < r; p++) {
        memcpy(pad + 3 * (size_t)p, pad + 3 * (size_t)r, 3 * sizeof *pad);
        memcpy(pad + 3 * ((size_t)w + (size_t)r + (size_t)p), pad + 3 * ((size_t)w + (size_t)r - 1), 3 * sizeof *pad);
    }
    double *oy = out + (size_t)C_Y * w, *ocx = out + (size_t)C_CX * w;
    double *oz1 = out + (size_t)C_CZ1 * w, *oz2 = out + (size_t)C_CZ2 * w;
    for (int x = 0; x < w; x++) {
        const double *in = pad + 3 * (size_t)x; /* pixel x - r */
        double sy = 0.0, scx = 0.0, sz1 = 0.0, sz2 = 0.0;
        for (int t = 0; t <= 2 * r; t++) {
            sy += k->y[t] * in[3 * t];
            scx += k->cx[t] * in[3 * t + 1];
            sz1 += k->cz1[t] * in[3 * t + 2];
            sz2 += k->cz2[t] * in[3 * t + 2];
        }
        oy[x] = sy;
        ocx[x] = scx;
        oz1[x] = sz1;
        oz2[x] = sz2;
    }
}

/* Source row `row` of image `img`: luminance Y / Yn filtered horizontally with dg, ddg and g. */
static void feature_row(const flip_work *wk, double *pad, int img, int row, double *out)
{
    const flip_constants *k = wk->k;
    const int w = wk->w, r = k->feature_r;
    const float *src = wk->rgb[img] + (size_t)row * (size_t)w * 3;
    for (int x = 0; x < w; x++) {
        const float *c = src + 3 * (size_t)x;
        double lin[3] = {clamp01(c[0]), clamp01(c[1]), clamp01(c[2])};
        pad[x + r] = (rgb_to_xyz[1][0] * lin[0] + rgb_to_xyz[1][1] * lin[1] + rgb_to_xyz[1][2] * lin[2]) / k->white[1];
    }
    for (int p = 0; p < r; p++) {
        pad[p] = pad[r];
        pad[w + r + p] = pad[w + r - 1];
    }
    double *odg = out + (size_t)F_DG * w, *oddg = out + (size_t)F_DDG * w, *og = out + (size_t)F_G * w;
    for (int x = 0; x < w; x++) {
        const double *in = pad + x;
        double sdg = 0.0, sddg = 0.0, sg = 0.0;
        for (int t = 0; t <= 2 * r; t++) {
            sdg += k->dg[t] * in[t];
            sddg += k->ddg[t] * in[t];
            sg += k->g[t] * in[t];
        }
        odg[x] = sdg;
        oddg[x] = sddg;
        og[x] = sg;
    }
}

/* acc[i] += weight * row[i] for i < n. */
static void add_scaled(double *acc, const double *row, double weight, int n)
{
    for (int i = 0; i < n; i++)
        acc[i] += weight * row[i];
}

/* Rows [y0, y1) of the error map. */
static void flip_band(const flip_work *wk, flip_scratch *s, int y0, int y1)
{
    const flip_constants *k = wk->k;
    const int w = wk->w, h = wk->h;
    const int cr = k->color_r, fr = k->feature_r;
    const int c_slots = 2 * cr + 1, f_slots = 2 * fr + 1;
    const size_t c_row = 2 * (size_t)C_CHANNELS * (size_t)w; /* doubles per colour ring row */
    const size_t f_row = 2 * (size_t)F_CHANNELS * (size_t)w;
    int c_next = y0 - cr < 0 ? 0 : y0 - cr; /* next source row to filter into each ring */
    int f_next = y0 - fr < 0 ? 0 : y0 - fr;

    for (int y = y0; y < y1; y++) {
        /* The ring slot of source row j is j % slots: rows y - r .. y + r are
         * all there, as a new row only replaces one 2r + 1 rows older. */
        for (; c_next <= (y + cr < h ? y + cr : h - 1); c_next++)
            for (int img = 0; img < 2; img++)
                color_row(wk, s->pad, img, c_next,
                          s->color_ring + (size_t)(c_next % c_slots) * c_row + (size_t)img * C_CHANNELS * w);
        for (; f_next <= (y + fr < h ? y + fr : h - 1); f_next++)
            for (int img = 0; img < 2; img++)
                feature_row(wk, s->pad, img, f_next,
                            s->feature_ring + (size_t)(f_next % f_slots) * f_row + (size_t)img * F_CHANNELS * w);

        /* Colour: the vertical pass, then the colour error per pixel. */
        double *acc = s->acc;
        memset(acc, 0, c_row * sizeof *acc);
        for (int t = 0; t <= 2 * cr; t++) {
            int j = y + t - cr;
            j = j < 0 ? 0 : j >= h ? h - 1 : j;
            const double *src = s->color_ring + (size_t)(j % c_slots) * c_row;
            for (int img = 0; img < 2; img++) {
                size_t base = (size_t)img * C_CHANNELS * w;
                add_scaled(acc + base + (size_t)C_Y * w, src + base + (size_t)C_Y * w, k->y[t], w);
                add_scaled(acc + base + (size_t)C_CX * w, src + base + (size_t)C_CX * w, k->cx[t], w);
                add_scaled(acc + base + (size_t)C_CZ1 * w, src + base + (size_t)C_CZ1 * w, k->cz1[t], w);
                add_scaled(acc + base + (size_t)C_CZ2 * w, src + base + (size_t)C_CZ2 * w, k->cz2[t], w);
            }
        }
        float *err_row = wk->error + (size_t)y * (size_t)w;
        for (int x = 0; x < w; x++) {
            double lab[2][3];
            for (int img = 0; img < 2; img++) {
                const double *a = acc + (size_t)img * C_CHANNELS * w;
                filtered_ycxcz_to_hunt_lab(k, a[(size_t)C_Y * w + x], a[(size_t)C_CX * w + x],
                                           a[(size_t)C_CZ1 * w + x] + a[(size_t)C_CZ2 * w + x], lab[img]);
            }
            double c = pow(hyab(lab[0], lab[1]), FLIP_QC);
            c = c < k->pccmax ? c * (FLIP_PT / k->pccmax)
                              : FLIP_PT + (c - k->pccmax) / (k->cmax - k->pccmax) * (1.0 - FLIP_PT);
            s->color_error[x] = c;
        }
        /* Features: the vertical pass, then the final error per pixel. */
        const double *color_error = s->color_error;
        double *fa = s->feature_acc;
        memset(fa, 0, 8 * (size_t)w * sizeof *fa);
        for (int t = 0; t <= 2 * fr; t++) {
            int j = y + t - fr;
            j = j < 0 ? 0 : j >= h ? h - 1 : j;
            const double *src = s->feature_ring + (size_t)(j % f_slots) * f_row;
            for (int img = 0; img < 2; img++) {
                const double *in = src + (size_t)img * F_CHANNELS * w;
                double *out = fa + (size_t)img * 4 * w;
                add_scaled(out, in + (size_t)F_DG * w, k->g[t], w);          /* dx */
                add_scaled(out + w, in + (size_t)F_DDG * w, k->g[t], w);     /* ddx */
                add_scaled(out + 2 * w, in + (size_t)F_G * w, k->dg[t], w);  /* dy */
                add_scaled(out + 3 * w, in + (size_t)F_G * w, k->ddg[t], w); /* ddy */
            }
        }
        for (int x = 0; x < w; x++) {
            double edge[2], point[2];
            for (int img = 0; img < 2; img++) {
                const double *f = fa + (size_t)img * 4 * w;
                edge[img] = hypot(f[x], f[2 * (size_t)w + x]);
                point[img] = hypot(f[(size_t)w + x], f[3 * (size_t)w + x]);
            }
            double d = fmax(fabs(edge[0] - edge[1]), fabs(point[0] - point[1]));
            double feature = pow(d / sqrt(2.0), FLIP_QF);
            err_row[x] = (float)pow(color_error[x], 1.0 - feature);
        }
    }
}

static void flip_band_task(void *ctx, size_t begin, size_t end, int worker)
{
    const flip_work *wk = ctx;
    for (size_t b = begin; b < end; b++) {
        int y0 = (int)b * FLIP_BAND_ROWS;
        int y1 = y0 + FLIP_BAND_ROWS < wk->h ? y0 + FLIP_BAND_ROWS : wk->h;
        flip_band(wk, &wk->scratch[worker], y0, y1);
    }
}

static void scratch_free(flip_scratch *s, int n)
{
    for (int i = 0; s && i < n; i++) {
        free(s[i].pad);
        free(s[i].color_ring);
        free(s[i].feature_ring);
        free(s[i].acc);
        free(s[i].color_error);
        free(s[i].feature_acc);
    }
    free(s);
}

bool flip_ldr_map(const float *reference_rgb, const float *test_rgb, int width_px, int height_px, double ppd,
                  int threads, float *error_out, tess_error *err)
{
    if (!reference_rgb || !test_rgb || !error_out)
        return tess_error_set(err, "flip: NULL image");
    if (width_px < 1 || height_px < 1)
        return tess_error_set(err, "flip: image size %dx%d: width and height must be positive", width_px, height_px);
    if (!(ppd >= FLIP_MIN_PPD && ppd <= FLIP_MAX_PPD))
        return tess_error_set(err, "flip: %g pixels per degree is outside %g..%g", ppd, FLIP_MIN_PPD, FLIP_MAX_PPD);
    if (threads < 1)
        threads = 1;
    size_t bands = ((size_t)height_px + FLIP_BAND_ROWS - 1) / FLIP_BAND_ROWS;
    if ((size_t)threads > bands)
        threads = (int)bands;

    flip_constants *k = malloc(sizeof *k);
    flip_scratch *scratch = calloc((size_t)threads, sizeof *scratch);
    bool ok = k && scratch;
    if (ok) {
        constants_init(k, ppd);
        const size_t w = (size_t)width_px;
        const int max_r = k->color_r > k->feature_r ? k->color_r : k->feature_r;
        for (int i = 0; ok && i < threads; i++) {
            scratch[i].pad = malloc((w + 2 * (size_t)max_r) * 3 * sizeof(double));
            scratch[i].color_ring = malloc((2 * (size_t)k->color_r + 1) * 2 * C_CHANNELS * w * sizeof(double));
            scratch[i].feature_ring = malloc((2 * (size_t)k->feature_r + 1) * 2 * F_CHANNELS * w * sizeof(double));
            scratch[i].acc = malloc(2 * C_CHANNELS * w * sizeof(double));
            scratch[i].color_error = malloc(w * sizeof(double));
            scratch[i].feature_acc = malloc(8 * w * sizeof(double));
            ok = scratch[i].pad && scratch[i].color_ring && scratch[i].feature_ring && scratch[i].acc &&
                 scratch[i].color_error && scratch[i].feature_acc;
        }
    }
    if (!ok) {
        scratch_free(scratch, threads);
        free(k);
        return tess_error_set(err, "flip: out of memory for a %dx%d image", width_px, height_px);
    }
    flip_work wk = {k, {reference_rgb, test_rgb}, width_px, height_px, error_out, scratch};
    parallel_for(threads, bands, 1, flip_band_task, &wk);
    scratch_free(scratch, threads);
    free(k);
    return true;
}
