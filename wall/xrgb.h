/* xrgb.h - float frames to the 32-bit XRGB8888 words monitors scan out:
 * 8-bit sRGB (engine/base/srgb8.h, the same encoding as 8-bit files get),
 * rotated from the image as mounted to the panel's scan-out orientation.
 * Shared by the DRM display and the convert display that stands in for it. */
#ifndef TESSERA_XRGB_H
#define TESSERA_XRGB_H

#include <stddef.h>
#include <stdint.h>

/* A destination: scan-out pixels (before rotation) with a row pitch in bytes. */
typedef struct xrgb_target {
    uint8_t *pixels;
    size_t pitch_bytes;
    int width_px, height_px; /* scan-out size: the mounted size, swapped for 90 and 270 */
} xrgb_target;

/* Write the mounted-image rectangle [x0, x1) x [y0, y1) of `rgb` (linear RGB,
 * mounted_w x mounted_h, top row first) into `dst` rotated by rotation_deg
 * clockwise (0, 90, 180, 270: how the panel is mounted, wall_config.h). Each
 * destination word is written once, in address order within a row, and never
 * read: fit for write-combined scan-out memory. */
void xrgb_write_rect(const float *rgb, int mounted_w, int mounted_h, int x0, int y0, int x1, int y1,
                     int rotation_deg, const xrgb_target *dst);

#endif
