/* display.h - the image display component: where the pipeline hands a
 * finished frame. Implementations live outside the engine (wall/: null, dump;
 * DRM/KMS comes with the wall issue; tests have their own); the engine knows
 * only this interface.
 *
 * Threading: show() is called by the pipeline's display thread only, one call
 * at a time per display, during the display stage of the frame after the one
 * that rendered the image. The image is read-only and stays unchanged until
 * show() returns; a display that needs the pixels later copies them. */
#ifndef TESSERA_DISPLAY_H
#define TESSERA_DISPLAY_H

#include <stdbool.h>
#include <stdint.h>

#include "camera.h"
#include "err.h"

/* One finished frame of one channel. */
typedef struct frame_image {
    const float *rgb;        /* linear RGB, 3 floats per pixel, row-major, top row first */
    int width_px, height_px;
    uint64_t frame;          /* pipeline frame number, from 0 */
    double time_s;           /* the frame's time (pipeline time mode) */
    int channel;             /* index of the channel that rendered it */
    camera_desc camera;      /* the camera it was rendered with */
    uint64_t camera_serial;  /* changes of this channel's camera before this frame (0: the initial one) */
} frame_image;

typedef struct image_display image_display;

typedef struct image_display_ops {
    const char *name; /* component name, as in configs: "null", "dump", ... */
    /* Present one frame. False with err set stops the pipeline with that error. */
    bool (*show)(image_display *d, const frame_image *img, tess_error *err);
    void (*destroy)(image_display *d); /* frees d */
} image_display_ops;

/* Implementations embed this as their first member. */
struct image_display {
    const image_display_ops *ops;
};

static inline void image_display_destroy(image_display *d)
{
    if (d)
        d->ops->destroy(d);
}

#endif
