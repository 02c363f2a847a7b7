/* upscale.c - bilinear and clamped Catmull-Rom upscaling (upscale.h). */
#include "upscale.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The taps of one output coordinate along one axis. */
typedef struct axis_tap {
    int index[4];   /* source texels i-1, i, i+1, i+2, each clamped into [0, n_src - 1] */
    float t;        /* u - i in [0, 1): bilinear's weight of texel i + 1 */
    float weight[4]; /* Catmull-Rom weights of index[0..3] (clamped-cubic only) */
} axis_tap;

struct upscale_plan {
    int src_w, src_h, dst_w, dst_h;
    upscale_filter filter;
    axis_tap *column_taps; /* dst_w of them */
    axis_tap *row_taps;    /* dst_h of them */
};

bool upscale_filter_from_name(const char *name, upscale_filter *out, tess_error *err)
{
    if (name && !strcmp(name, "bilinear")) {
        *out = UPSCALE_BILINEAR;
        return true;
    }
    if (name && !strcmp(name, "clamped-cubic")) {
        *out = UPSCALE_CLAMPED_CUBIC;
        return true;
    }
    return tess_error_set(err, "unknown upscaling filter '%s' (expected one of: %s)", name ? name : "(null)",
                          UPSCALE_FILTER_NAMES);
}

const char *upscale_filter_name(upscale_filter f)
{
    switch (f) {
    case UPSCALE_BILINEAR:
        return "bilinear";
    case UPSCALE_CLAMPED_CUBIC:
        return "clamped-cubic";
    }
    return "?";
}

bool upscale_scale_validate(double scale, tess_error *err)
{
    if (!isfinite(scale) || !(scale > 0.0) || scale > 1.0)
        return tess_error_set(err, "render scale %g is not in (0, 1]", scale);
    return true;
}

int upscale_low_res_px(int size_px, double scale)
{
    double n = round((double)size_px * scale);
    return n < 1.0 ? 1 : (int)n;
}

static int clamp_index(int i, int n) { return i < 0 ? 0 : i >= n ? n - 1 : i; }

/* The taps of every output coordinate of an axis of n_dst pixels from n_src
 * texels (upscale.h, ALIGNMENT and FILTERS). */
static void fill_axis(axis_tap *taps, int n_src, int n_dst)
{
    for (int x = 0; x < n_dst; x++) {
        double u = ((double)x + 0.5) * (double)n_src / (double)n_dst - 0.5;
        if (u < 0.0)
            u = 0.0;
        if (u > (double)(n_src - 1))
            u = (double)(n_src - 1);
        double fi = floor(u);
        int i = (int)fi;
        double t = u - fi;
        axis_tap *tap = &taps[x];
        for (int k = 0; k < 4; k++)
            tap->index[k] = clamp_index(i - 1 + k, n_src);
        tap->t = (float)t;
        double t2 = t * t, t3 = t2 * t;
        tap->weight[0] = (float)(0.5 * (-t3 + 2.0 * t2 - t));
        tap->weight[1] = (float)(0.5 * (3.0 * t3 - 5.0 * t2 + 2.0));
        tap->weight[2] = (float)(0.5 * (-3.0 * t3 + 4.0 * t2 + t));
        tap->weight[3] = (float)(0.5 * (t3 - t2));
    }
}

upscale_plan *upscale_plan_create(int src_w, int src_h, int dst_w, int dst_h, upscale_filter filter,
                                  tess_error *err)
{
    if (src_w < 1 || src_h < 1 || dst_w < 1 || dst_h < 1) {
        tess_error_set(err, "upscale: sizes must be at least 1x1 (source %dx%d, destination %dx%d)", src_w, src_h,
                       dst_w, dst_h);
        return NULL;
    }
    if (src_w > dst_w || src_h > dst_h) {
        tess_error_set(err, "upscale: source %dx%d is larger than the destination %dx%d on an axis (only enlarges)",
                       src_w, src_h, dst_w, dst_h);
        return NULL;
    }
    if (filter != UPSCALE_BILINEAR && filter != UPSCALE_CLAMPED_CUBIC) {
        tess_error_set(err, "upscale: unknown filter %d (expected one of: %s)", (int)filter, UPSCALE_FILTER_NAMES);
        return NULL;
    }
    upscale_plan *p = calloc(1, sizeof *p);
    if (!p)
        goto no_memory;
    p->src_w = src_w;
    p->src_h = src_h;
    p->dst_w = dst_w;
    p->dst_h = dst_h;
    p->filter = filter;
    p->column_taps = malloc((size_t)dst_w * sizeof *p->column_taps);
    p->row_taps = malloc((size_t)dst_h * sizeof *p->row_taps);
    if (!p->column_taps || !p->row_taps)
        goto no_memory;
    fill_axis(p->column_taps, src_w, dst_w);
    fill_axis(p->row_taps, src_h, dst_h);
    return p;
no_memory:
    upscale_plan_destroy(p);
    tess_error_set(err, "upscale: out of memory for a %dx%d plan", dst_w, dst_h);
    return NULL;
}

void upscale_plan_destroy(upscale_plan *p)
{
    if (!p)
        return;
    free(p->column_taps);
    free(p->row_taps);
    free(p);
}

size_t upscale_plan_scratch_floats(const upscale_plan *p) { return (size_t)p->src_w * 3; }

/* Bilinear output row: rows blended into `line` (one source row), then columns. */
static void bilinear_row(const upscale_plan *p, const float *src, float *out, const axis_tap *row, float *line)
{
    size_t floats = (size_t)p->src_w * 3;
    const float *a = src + (size_t)row->index[1] * floats;
    const float *b = src + (size_t)row->index[2] * floats;
    float t = row->t;
    for (size_t k = 0; k < floats; k++)
        line[k] = a[k] + t * (b[k] - a[k]);
    for (int x = 0; x < p->dst_w; x++) {
        const axis_tap *col = &p->column_taps[x];
        const float *l = line + (size_t)col->index[1] * 3, *r = line + (size_t)col->index[2] * 3;
        for (int c = 0; c < 3; c++)
            out[3 * x + c] = l[c] + col->t * (r[c] - l[c]);
    }
}

static float min2(float a, float b) { return b < a ? b : a; }
static float max2(float a, float b) { return b > a ? b : a; }

/* Clamped Catmull-Rom output row: the 4 rows blended into `line`, then 4
 * columns of it, then the clamp to the 2 x 2 nearest source texels. */
static void cubic_row(const upscale_plan *p, const float *src, float *out, const axis_tap *row, float *line)
{
    size_t floats = (size_t)p->src_w * 3;
    const float *r0 = src + (size_t)row->index[0] * floats, *r1 = src + (size_t)row->index[1] * floats,
                *r2 = src + (size_t)row->index[2] * floats, *r3 = src + (size_t)row->index[3] * floats;
    const float *w = row->weight;
    for (size_t k = 0; k < floats; k++)
        line[k] = w[0] * r0[k] + w[1] * r1[k] + w[2] * r2[k] + w[3] * r3[k];
    for (int x = 0; x < p->dst_w; x++) {
        const axis_tap *col = &p->column_taps[x];
        const float *cw = col->weight;
        const float *q0 = line + (size_t)col->index[0] * 3, *q1 = line + (size_t)col->index[1] * 3,
                    *q2 = line + (size_t)col->index[2] * 3, *q3 = line + (size_t)col->index[3] * 3;
        /* the 2 x 2 nearest texels: rows index[1], index[2] x columns index[1], index[2] */
        const float *n00 = r1 + (size_t)col->index[1] * 3, *n01 = r1 + (size_t)col->index[2] * 3,
                    *n10 = r2 + (size_t)col->index[1] * 3, *n11 = r2 + (size_t)col->index[2] * 3;
        for (int c = 0; c < 3; c++) {
            float v = cw[0] * q0[c] + cw[1] * q1[c] + cw[2] * q2[c] + cw[3] * q3[c];
            float lo = min2(min2(n00[c], n01[c]), min2(n10[c], n11[c]));
            float hi = max2(max2(n00[c], n01[c]), max2(n10[c], n11[c]));
            out[3 * x + c] = v < lo ? lo : v > hi ? hi : v;
        }
    }
}

void upscale_plan_rows(const upscale_plan *p, const float *src, float *dst, int y0, int y1, float *scratch)
{
    size_t dst_floats = (size_t)p->dst_w * 3;
    if (p->src_w == p->dst_w && p->src_h == p->dst_h) { /* scale 1: a copy, bit for bit */
        if (y1 > y0)
            memcpy(dst + (size_t)y0 * dst_floats, src + (size_t)y0 * dst_floats,
                   (size_t)(y1 - y0) * dst_floats * sizeof *dst);
        return;
    }
    for (int y = y0; y < y1; y++) {
        float *out = dst + (size_t)y * dst_floats;
        switch (p->filter) {
        case UPSCALE_BILINEAR:
            bilinear_row(p, src, out, &p->row_taps[y], scratch);
            break;
        case UPSCALE_CLAMPED_CUBIC:
            cubic_row(p, src, out, &p->row_taps[y], scratch);
            break;
        }
    }
}

bool upscale_image(const float *src, int src_w, int src_h, float *dst, int dst_w, int dst_h, upscale_filter filter,
                   tess_error *err)
{
    upscale_plan *p = upscale_plan_create(src_w, src_h, dst_w, dst_h, filter, err);
    if (!p)
        return false;
    float *scratch = malloc(upscale_plan_scratch_floats(p) * sizeof *scratch);
    if (!scratch) {
        upscale_plan_destroy(p);
        return tess_error_set(err, "upscale: out of memory for a row of %d pixels", src_w);
    }
    upscale_plan_rows(p, src, dst, 0, dst_h, scratch);
    free(scratch);
    upscale_plan_destroy(p);
    return true;
}
