/* error_map.c (metrics) - the colour-mapped picture of an error map (error_map.h). */
#include "error_map.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/srgb.h"

/* matplotlib's magma at 0, 1/8, ..., 1 (sRGB-encoded). */
#define MAGMA_SAMPLES 9
static const double magma_srgb[MAGMA_SAMPLES][3] = {
    {0.001462, 0.000466, 0.013866}, {0.113094, 0.065492, 0.276784}, {0.316654, 0.071690, 0.485380},
    {0.512831, 0.148179, 0.507648}, {0.716387, 0.214982, 0.475290}, {0.904281, 0.319610, 0.388137},
    {0.986700, 0.535582, 0.382210}, {0.996898, 0.769591, 0.534892}, {0.987053, 0.991438, 0.749504},
};

/* Legend layout in units of `scale` pixels, top to bottom. */
#define LEGEND_GAP_TOP 2
#define LEGEND_BAR 8
#define LEGEND_TICK 2
#define LEGEND_GAP_TEXT 1
#define LEGEND_TEXT 5 /* glyph height */
#define LEGEND_UNITS 20 /* all of the above and a bottom gap of 2 */
/* Width per legend unit: the strip grows with the map so it stays readable. */
#define LEGEND_PX_PER_SCALE 320

/* 3 x 5 glyphs, a row per entry, bit 2 the left column. */
static const char glyph_chars[] = "0123456789.";
static const uint8_t glyphs[][5] = {
    {7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7},
    {7, 4, 7, 5, 7}, {7, 1, 1, 2, 2}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}, {0, 0, 0, 0, 2},
};

static int legend_scale(int width_px)
{
    int s = width_px / LEGEND_PX_PER_SCALE;
    return s < 1 ? 1 : s;
}

int error_map_legend_height_px(int width_px) { return LEGEND_UNITS * legend_scale(width_px); }

void error_map_color_srgb(double value, double srgb[3])
{
    double v = value > 0.0 ? (value < 1.0 ? value : 1.0) : 0.0;
    double at = v * (MAGMA_SAMPLES - 1);
    int i = (int)at;
    if (i >= MAGMA_SAMPLES - 1)
        i = MAGMA_SAMPLES - 2;
    double f = at - i;
    for (int c = 0; c < 3; c++)
        srgb[c] = magma_srgb[i][c] + f * (magma_srgb[i + 1][c] - magma_srgb[i][c]);
}

static void put_srgb(float *px, const double srgb[3])
{
    for (int c = 0; c < 3; c++)
        px[c] = (float)srgb_curve_decode(srgb[c]);
}

/* Fill the rectangle [x0, x1) x [y0, y1) of a W-wide picture, clipped to it. */
static void fill(float *rgb, int w, int h, int x0, int y0, int x1, int y1, float value)
{
    for (int y = y0 < 0 ? 0 : y0; y < y1 && y < h; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x1 && x < w; x++)
            for (int c = 0; c < 3; c++)
                rgb[3 * ((size_t)y * (size_t)w + (size_t)x) + c] = value;
}

static void draw_text(float *rgb, int w, int h, int x0, int y0, int scale, const char *text)
{
    for (int g = 0; text[g]; g++) {
        const char *at = strchr(glyph_chars, text[g]);
        if (!at)
            continue;
        const uint8_t *rows = glyphs[at - glyph_chars];
        for (int r = 0; r < 5; r++)
            for (int col = 0; col < 3; col++)
                if (rows[r] >> (2 - col) & 1)
                    fill(rgb, w, h, x0 + (4 * g + col) * scale, y0 + r * scale, x0 + (4 * g + col + 1) * scale,
                         y0 + (r + 1) * scale, 0.0f);
    }
}

/* The legend: rows [top, top + legend height) of the picture. */
static void draw_legend(float *rgb, int w, int h, int top)
{
    const int s = legend_scale(w);
    fill(rgb, w, h, 0, top, w, h, 1.0f); /* white ground: the ramp's black end stays visible */
    const int bar_y = top + LEGEND_GAP_TOP * s;
    for (int x = 0; x < w; x++) {
        double srgb[3];
        error_map_color_srgb(w > 1 ? (double)x / (w - 1) : 0.0, srgb);
        for (int y = bar_y; y < bar_y + LEGEND_BAR * s; y++)
            put_srgb(rgb + 3 * ((size_t)y * (size_t)w + (size_t)x), srgb);
    }
    static const double ticks[] = {0.0, 0.25, 0.5, 0.75, 1.0};
    static const char *const labels[] = {"0", "0.25", "0.5", "0.75", "1"};
    const int tick_y = bar_y + LEGEND_BAR * s, text_y = tick_y + (LEGEND_TICK + LEGEND_GAP_TEXT) * s;
    /* The ends first, then the middle, each label only where it overlaps none drawn. */
    static const int order[] = {0, 4, 2, 1, 3};
    int drawn_x0[5], drawn_x1[5], drawn = 0;
    for (int o = 0; o < 5; o++) {
        int t = order[o];
        int x = (int)lround(ticks[t] * (w - 1));
        fill(rgb, w, h, x - s / 2, tick_y, x - s / 2 + s, tick_y + LEGEND_TICK * s, 0.0f);
        int text_w = ((int)strlen(labels[t]) * 4 - 1) * s;
        int x0 = x - text_w / 2;
        x0 = x0 + text_w > w ? w - text_w : x0;
        x0 = x0 < 0 ? 0 : x0;
        bool fits = x0 + text_w <= w;
        for (int d = 0; fits && d < drawn; d++)
            fits = x0 + text_w + s <= drawn_x0[d] || x0 >= drawn_x1[d] + s;
        if (!fits)
            continue;
        draw_text(rgb, w, h, x0, text_y, s, labels[t]);
        drawn_x0[drawn] = x0;
        drawn_x1[drawn] = x0 + text_w;
        drawn++;
    }
}

bool error_map_render(const float *error, int width_px, int height_px, float **rgb_out, int *height_out,
                      tess_error *err)
{
    *rgb_out = NULL;
    *height_out = 0;
    if (!error || width_px < 1 || height_px < 1)
        return tess_error_set(err, "error map: image size %dx%d: width and height must be positive", width_px,
                              height_px);
    const int total_h = height_px + error_map_legend_height_px(width_px);
    float *rgb = malloc((size_t)width_px * (size_t)total_h * 3 * sizeof *rgb);
    if (!rgb)
        return tess_error_set(err, "error map: out of memory for %dx%d pixels", width_px, total_h);
    for (size_t i = 0; i < (size_t)width_px * (size_t)height_px; i++) {
        double srgb[3];
        error_map_color_srgb(error[i], srgb);
        put_srgb(rgb + 3 * i, srgb);
    }
    draw_legend(rgb, width_px, total_h, height_px);
    *rgb_out = rgb;
    *height_out = total_h;
    return true;
}
