/* wall_headless.c - per-output images and the stitched wall image. */
#include "wall_headless.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "display.h"
#include "dump.h"

float wall_plane_aspect(const wall_config *w) { return (float)(w->width_mm / w->height_mm); }

camera_window wall_output_window(const wall_config *w, int i)
{
    const wall_output *o = &w->outputs[i];
    /* wall mm (x right, y down, origin top-left) to plane screen coordinates (sx right, sy up, [-1, 1]) */
    double cx = 2.0 * (o->x_mm + 0.5 * o->width_mm) / w->width_mm - 1.0;
    double cy = 1.0 - 2.0 * (o->y_mm + 0.5 * o->height_mm) / w->height_mm;
    return (camera_window){(float)cx, (float)cy, (float)(o->width_mm / w->width_mm),
                           (float)(o->height_mm / w->height_mm)};
}

/* Pixels per mm of the finest output. */
static double finest_density(const wall_config *w)
{
    double density = 0.0;
    for (int i = 0; i < w->count; i++) {
        const wall_output *o = &w->outputs[i];
        density = fmax(density, fmax(o->width_px / o->width_mm, o->height_px / o->height_mm));
    }
    return density;
}

void wall_stitched_size(const wall_config *w, int *width_px, int *height_px)
{
    double density = finest_density(w);
    *width_px = (int)lround(w->width_mm * density);
    *height_px = (int)lround(w->height_mm * density);
    if (*width_px < 1)
        *width_px = 1;
    if (*height_px < 1)
        *height_px = 1;
}

bool wall_output_pattern(const char *pattern, const char *name, char *out, size_t out_bytes)
{
    const char *slash = strrchr(pattern, '/');
    const char *dot = strrchr(pattern, '.');
    size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - pattern) : strlen(pattern);
    int n = snprintf(out, out_bytes, "%.*s-%s%s", (int)stem, pattern, name, pattern + stem);
    return n >= 0 && (size_t)n < out_bytes;
}

/* Shared by the displays of one wall; used by the display thread only. */
typedef struct wall_state {
    int outputs;
    int width_px, height_px;  /* stitched image */
    /* per output k: the stitched pixels it shows (dest[k][i]) and their pixels in its image (source[k][i]);
     * pixels behind bezels and in gaps are in no list and stay black */
    uint32_t *dest[WALL_MAX_OUTPUTS], *source[WALL_MAX_OUTPUTS];
    size_t count[WALL_MAX_OUTPUTS];
    float *rgb;               /* the stitched frame being assembled */
    char pattern[4096];
    bool sequence;
    int alive;                /* displays not yet destroyed */
    int last;                 /* the output whose show completes a stitched frame; -1: none is written */
} wall_state;

typedef struct wall_display {
    image_display base;
    wall_state *wall;
    int index;           /* output index = channel index */
    image_display *dump; /* this output's own files */
} wall_display;

static void wall_state_free(wall_state *ws)
{
    for (int k = 0; k < WALL_MAX_OUTPUTS; k++) {
        free(ws->dest[k]);
        free(ws->source[k]);
    }
    free(ws->rgb);
    free(ws);
}

static bool wall_show(image_display *d, const frame_image *img, tess_error *err)
{
    wall_display *wd = (wall_display *)d;
    wall_state *ws = wd->wall;
    if (!wd->dump->ops->show(wd->dump, img, err))
        return false;
    if (ws->last < 0) /* part of a wall: no stitched image */
        return true;
    const uint32_t *dest = ws->dest[wd->index], *source = ws->source[wd->index];
    for (size_t i = 0; i < ws->count[wd->index]; i++)
        memcpy(ws->rgb + 3 * (size_t)dest[i], img->rgb + 3 * (size_t)source[i], 3 * sizeof(float));
    if (wd->index != ws->last) /* the last output completes the frame */
        return true;
    char path[4096];
    if (img->frame > (uint64_t)INT32_MAX)
        return tess_error_set(err, "%s: frame number too large", ws->pattern);
    return dump_frame_path(ws->pattern, (int)img->frame, ws->sequence, path, sizeof path, err) &&
           dump_write_rgb(path, ws->width_px, ws->height_px, ws->rgb, err);
}

static void wall_destroy(image_display *d)
{
    wall_display *wd = (wall_display *)d;
    image_display_destroy(wd->dump);
    if (--wd->wall->alive == 0)
        wall_state_free(wd->wall);
    free(wd);
}

static const image_display_ops wall_ops = {.name = "wall", .show = wall_show, .destroy = wall_destroy};

/* Which output pixel each stitched pixel shows (nearest, by the pixel
 * centre's wall position), as per-output lists. False when out of memory. */
static bool map_sources(const wall_config *w, wall_state *ws)
{
    size_t pixels = (size_t)ws->width_px * (size_t)ws->height_px;
    for (int k = 0; k < w->count; k++) { /* an output covers at most all of them */
        ws->dest[k] = malloc(pixels * sizeof *ws->dest[k]);
        ws->source[k] = malloc(pixels * sizeof *ws->source[k]);
        if (!ws->dest[k] || !ws->source[k])
            return false;
    }
    double mm_per_px_x = w->width_mm / ws->width_px, mm_per_px_y = w->height_mm / ws->height_px;
    for (int y = 0; y < ws->height_px; y++)
        for (int x = 0; x < ws->width_px; x++) {
            double wx = (x + 0.5) * mm_per_px_x, wy = (y + 0.5) * mm_per_px_y;
            for (int k = 0; k < w->count; k++) {
                const wall_output *o = &w->outputs[k];
                double u = (wx - o->x_mm) / o->width_mm, v = (wy - o->y_mm) / o->height_mm;
                if (u < 0.0 || u >= 1.0 || v < 0.0 || v >= 1.0)
                    continue;
                int ox = (int)(u * o->width_px), oy = (int)(v * o->height_px);
                ox = ox < o->width_px ? ox : o->width_px - 1;
                oy = oy < o->height_px ? oy : o->height_px - 1;
                ws->dest[k][ws->count[k]] = (uint32_t)y * (uint32_t)ws->width_px + (uint32_t)x;
                ws->source[k][ws->count[k]++] = (uint32_t)oy * (uint32_t)o->width_px + (uint32_t)ox;
                break;
            }
        }
    return true;
}

bool wall_headless_displays(const wall_config *w, const char *pattern, bool sequence, const bool *present,
                            image_display **displays, tess_error *err)
{
    wall_state *ws = calloc(1, sizeof *ws);
    if (!ws)
        return tess_error_set(err, "wall: out of memory");
    if (strlen(pattern) >= sizeof ws->pattern) {
        free(ws);
        return tess_error_set(err, "wall: output pattern too long");
    }
    snprintf(ws->pattern, sizeof ws->pattern, "%s", pattern);
    ws->sequence = sequence;
    ws->outputs = w->count;
    ws->last = w->count - 1;
    for (int i = 0; present && i < w->count; i++)
        if (!present[i])
            ws->last = -1; /* part of the wall: its outputs' own files only */
    wall_stitched_size(w, &ws->width_px, &ws->height_px);
    size_t pixels = (size_t)ws->width_px * (size_t)ws->height_px;
    /* the stitched image and its maps only when it is written (part of a wall pays nothing) */
    if (ws->last >= 0 && (!(ws->rgb = calloc(pixels * 3, sizeof *ws->rgb)) || !map_sources(w, ws))) { /* bezels black */
        tess_error_set(err, "wall: out of memory for a %dx%d stitched image", ws->width_px, ws->height_px);
        wall_state_free(ws);
        return false;
    }
    char probe[4096];
    if (!dump_frame_path(pattern, 0, sequence, probe, sizeof probe, err)) {
        wall_state_free(ws);
        return false;
    }
    int made = 0;
    for (int i = 0; i < w->count; i++) {
        displays[i] = NULL;
        if (present && !present[i])
            continue;
        char own[4096], label[WALL_LABEL_BYTES];
        wall_display *wd = calloc(1, sizeof *wd);
        bool ok = wd && wall_output_pattern(pattern, wall_output_label(w, i, label, sizeof label), own, sizeof own);
        if (ok)
            wd->dump = display_dump_create(own, sequence, err);
        if (!ok || !wd->dump) {
            free(wd);
            for (int k = 0; k < i; k++) { /* undo: the last destroy frees the shared state */
                image_display_destroy(displays[k]);
                displays[k] = NULL;
            }
            if (made == 0)
                wall_state_free(ws);
            if (!tess_error_is_set(err))
                tess_error_set(err, "wall: out of memory");
            return false;
        }
        wd->base.ops = &wall_ops;
        wd->wall = ws;
        wd->index = i;
        ws->alive++;
        made++;
        displays[i] = &wd->base;
    }
    if (made == 0) {
        wall_state_free(ws);
        return tess_error_set(err, "wall: no output of the wall is this process's");
    }
    return true;
}
