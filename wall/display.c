/* display.c (wall) - the null and dump image displays. */
#include "display.h"

#include <stdlib.h>
#include <string.h>

#include "dump.h"

static bool null_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)d;
    (void)img;
    (void)err;
    return true;
}

static void plain_destroy(image_display *d) { free(d); }

static const image_display_ops null_ops = {"null", null_show, plain_destroy};

image_display *display_null_create(void)
{
    image_display *d = calloc(1, sizeof *d);
    if (d)
        d->ops = &null_ops;
    return d;
}

typedef struct dump_display {
    image_display base;
    char pattern[4096];
    bool sequence;
} dump_display;

static bool dump_show(image_display *d, const frame_image *img, tess_error *err)
{
    dump_display *dd = (dump_display *)d;
    char path[4096];
    if (img->frame > (uint64_t)INT32_MAX)
        return tess_error_set(err, "%s: frame number %llu too large for a file name", dd->pattern,
                              (unsigned long long)img->frame);
    if (!dump_frame_path(dd->pattern, (int)img->frame, dd->sequence, path, sizeof path, err) ||
        !dump_write_rgb(path, img->width_px, img->height_px, img->rgb, err))
        return false;
    return true;
}

static const image_display_ops dump_ops = {"dump", dump_show, plain_destroy};

image_display *display_dump_create(const char *pattern, bool sequence, tess_error *err)
{
    char probe[4096];
    if (!pattern || !*pattern) {
        tess_error_set(err, "dump display: no output file pattern");
        return NULL;
    }
    if (strlen(pattern) >= sizeof ((dump_display *)0)->pattern) {
        tess_error_set(err, "dump display: output pattern longer than %zu bytes",
                       sizeof ((dump_display *)0)->pattern - 1);
        return NULL;
    }
    if (!dump_frame_path(pattern, 0, sequence, probe, sizeof probe, err))
        return NULL;
    dump_display *d = calloc(1, sizeof *d);
    if (!d) {
        tess_error_set(err, "dump display: out of memory");
        return NULL;
    }
    d->base.ops = &dump_ops;
    strcpy(d->pattern, pattern);
    d->sequence = sequence;
    return &d->base;
}

/* What a scan-out display does with a frame, without the device: encode to
 * 8-bit sRGB XRGB8888 (one 32-bit word per pixel) in its own buffer. For
 * benchmarks of the display stage. */
typedef struct convert_display {
    image_display base;
    uint32_t *xrgb;      /* capacity_px words */
    size_t capacity_px;
} convert_display;

static bool convert_show(image_display *d, const frame_image *img, tess_error *err)
{
    convert_display *cd = (convert_display *)d;
    size_t pixels = (size_t)img->width_px * (size_t)img->height_px;
    if (pixels > cd->capacity_px) {
        uint32_t *grown = realloc(cd->xrgb, pixels * sizeof *grown);
        if (!grown)
            return tess_error_set(err, "convert display: out of memory for %dx%d", img->width_px, img->height_px);
        cd->xrgb = grown;
        cd->capacity_px = pixels;
    }
    for (size_t i = 0; i < pixels; i++) {
        const float *c = img->rgb + 3 * i;
        cd->xrgb[i] = (uint32_t)dump_srgb_encode_u8(c[0]) << 16 | (uint32_t)dump_srgb_encode_u8(c[1]) << 8 |
                      (uint32_t)dump_srgb_encode_u8(c[2]);
    }
    return true;
}

static void convert_destroy(image_display *d)
{
    free(((convert_display *)d)->xrgb);
    free(d);
}

static const image_display_ops convert_ops = {"convert", convert_show, convert_destroy};

image_display *display_convert_create(void)
{
    convert_display *d = calloc(1, sizeof *d);
    if (d)
        d->base.ops = &convert_ops;
    return d ? &d->base : NULL;
}

image_display *display_create(const char *name, const char *dump_pattern, bool sequence, tess_error *err)
{
    if (!strcmp(name, "convert")) {
        image_display *d = display_convert_create();
        if (!d)
            tess_error_set(err, "convert display: out of memory");
        return d;
    }
    if (!strcmp(name, "null")) {
        image_display *d = display_null_create();
        if (!d)
            tess_error_set(err, "null display: out of memory");
        return d;
    }
    if (!strcmp(name, "dump"))
        return display_dump_create(dump_pattern, sequence, err);
    tess_error_set(err, "unknown display '%s' (known: %s)", name, DISPLAY_NAMES);
    return NULL;
}
