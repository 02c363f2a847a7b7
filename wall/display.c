/* display.c (wall) - the null, convert, convert-tiles and dump image displays. */
#include "display.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "dump.h"
#include "xrgb.h"

static bool null_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)d;
    (void)img;
    (void)err;
    return true;
}

static void plain_destroy(image_display *d) { free(d); }

static const image_display_ops null_ops = {.name = "null", .show = null_show, .destroy = plain_destroy};

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

static const image_display_ops dump_ops = {.name = "dump", .show = dump_show, .destroy = plain_destroy};

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

static bool convert_grow(uint32_t **xrgb, size_t *capacity_px, size_t pixels, const frame_image *img,
                         tess_error *err)
{
    if (pixels <= *capacity_px)
        return true;
    uint32_t *grown = realloc(*xrgb, pixels * sizeof *grown);
    if (!grown)
        return tess_error_set(err, "convert display: out of memory for %dx%d", img->width_px, img->height_px);
    *xrgb = grown;
    *capacity_px = pixels;
    return true;
}

static xrgb_target convert_target(uint32_t *xrgb, const frame_image *img)
{
    return (xrgb_target){(uint8_t *)xrgb, (size_t)img->width_px * sizeof *xrgb, img->width_px, img->height_px};
}

static bool convert_show(image_display *d, const frame_image *img, tess_error *err)
{
    convert_display *cd = (convert_display *)d;
    if (!convert_grow(&cd->xrgb, &cd->capacity_px, (size_t)img->width_px * (size_t)img->height_px, img, err))
        return false;
    xrgb_target t = convert_target(cd->xrgb, img);
    xrgb_write_rect(img->rgb, img->width_px, img->height_px, 0, 0, img->width_px, img->height_px, 0, &t);
    return true;
}

static void convert_destroy(image_display *d)
{
    free(((convert_display *)d)->xrgb);
    free(d);
}

static const image_display_ops convert_ops = {.name = "convert", .show = convert_show, .destroy = convert_destroy};

image_display *display_convert_create(void)
{
    convert_display *d = calloc(1, sizeof *d);
    if (d)
        d->base.ops = &convert_ops;
    return d ? &d->base : NULL;
}

/* The same encoding done by the render threads, tile by tile, into a ring of
 * CONVERT_TILES_BUFFERS buffers (frame f into f % CONVERT_TILES_BUFFERS), as
 * the DRM display writes its scan-out buffers. The ring is allocated by the
 * first tile (under `lock`, then published through the atomic pointer). */
#define CONVERT_TILES_BUFFERS 4
typedef struct convert_tiles_display {
    image_display base;
    pthread_mutex_t lock;              /* guards the allocation of ring */
    _Atomic(uint32_t *) ring;          /* CONVERT_TILES_BUFFERS * width * height words, or NULL */
    bool failed;                       /* out of memory; under lock */
} convert_tiles_display;

static uint32_t *convert_tiles_ring(convert_tiles_display *cd, const frame_image *img)
{
    uint32_t *ring = atomic_load_explicit(&cd->ring, memory_order_acquire);
    if (ring)
        return ring;
    pthread_mutex_lock(&cd->lock);
    ring = atomic_load_explicit(&cd->ring, memory_order_relaxed);
    if (!ring && !cd->failed) {
        /* cache-line aligned like the pipeline's frames (and scan-out memory): a 16-pixel tile row
         * is then whole lines, never a line shared with the neighbour tile another thread writes */
        size_t bytes = (size_t)CONVERT_TILES_BUFFERS * (size_t)img->width_px * (size_t)img->height_px * sizeof *ring;
        ring = aligned_alloc(64, (bytes + 63) & ~(size_t)63);
        cd->failed = ring == NULL;
        atomic_store_explicit(&cd->ring, ring, memory_order_release);
    }
    pthread_mutex_unlock(&cd->lock);
    return ring;
}

static void convert_tiles_write(image_display *d, const frame_image *img, int x0, int y0, int x1, int y1)
{
    convert_tiles_display *cd = (convert_tiles_display *)d;
    uint32_t *ring = convert_tiles_ring(cd, img);
    if (!ring) /* reported by show */
        return;
    uint32_t *frame = ring + (img->frame % CONVERT_TILES_BUFFERS) * (size_t)img->width_px * (size_t)img->height_px;
    xrgb_target t = convert_target(frame, img);
    xrgb_write_rect(img->rgb, img->width_px, img->height_px, x0, y0, x1, y1, 0, &t);
}

static bool convert_tiles_show(image_display *d, const frame_image *img, tess_error *err)
{
    convert_tiles_display *cd = (convert_tiles_display *)d;
    pthread_mutex_lock(&cd->lock);
    bool failed = cd->failed;
    pthread_mutex_unlock(&cd->lock);
    if (failed)
        return tess_error_set(err, "convert-tiles display: out of memory for %d buffers of %dx%d",
                              CONVERT_TILES_BUFFERS, img->width_px, img->height_px);
    return true; /* the render threads already wrote the frame */
}

static void convert_tiles_destroy(image_display *d)
{
    convert_tiles_display *cd = (convert_tiles_display *)d;
    free(atomic_load(&cd->ring));
    pthread_mutex_destroy(&cd->lock);
    free(cd);
}

static const image_display_ops convert_tiles_ops = {.name = "convert-tiles",
                                                    .show = convert_tiles_show,
                                                    .destroy = convert_tiles_destroy,
                                                    .write_tile = convert_tiles_write};

image_display *display_convert_tiles_create(void)
{
    convert_tiles_display *d = calloc(1, sizeof *d);
    if (!d)
        return NULL;
    d->base.ops = &convert_tiles_ops;
    pthread_mutex_init(&d->lock, NULL);
    atomic_init(&d->ring, NULL);
    return &d->base;
}
