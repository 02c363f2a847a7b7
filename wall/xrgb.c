/* xrgb.c - see xrgb.h. */
#include "xrgb.h"

#include "engine/base/srgb8.h"

/* Scan-out pixel (u, v) shows mounted pixel (x, y):
 *     0: x = u,          y = v
 *    90: x = mw - 1 - v, y = u
 *   180: x = mw - 1 - u, y = mh - 1 - v
 *   270: x = v,          y = mh - 1 - u
 * so the mounted index y * mw + x is affine in (u, v): base + du * u + dv * v. */
void xrgb_write_rect(const float *rgb, int mounted_w, int mounted_h, int x0, int y0, int x1, int y1,
                     int rotation_deg, const xrgb_target *dst)
{
    const long mw = mounted_w, mh = mounted_h;
    long base, du, dv;
    int u0, u1, v0, v1; /* the rectangle in scan-out pixels */
    switch (rotation_deg) {
    case 90:
        base = mw - 1, du = mw, dv = -1;
        u0 = y0, u1 = y1, v0 = mounted_w - x1, v1 = mounted_w - x0;
        break;
    case 180:
        base = (mh - 1) * mw + mw - 1, du = -1, dv = -mw;
        u0 = mounted_w - x1, u1 = mounted_w - x0, v0 = mounted_h - y1, v1 = mounted_h - y0;
        break;
    case 270:
        base = (mh - 1) * mw, du = -mw, dv = 1;
        u0 = mounted_h - y1, u1 = mounted_h - y0, v0 = x0, v1 = x1;
        break;
    default:
        base = 0, du = 1, dv = mw;
        u0 = x0, u1 = x1, v0 = y0, v1 = y1;
        break;
    }
    if (u1 > dst->width_px)
        u1 = dst->width_px;
    if (v1 > dst->height_px)
        v1 = dst->height_px;
    for (int v = v0; v < v1; v++) {
        uint32_t *row = (uint32_t *)(dst->pixels + (size_t)v * dst->pitch_bytes);
        if (u1 > u0)
            srgb8_encode_xrgb(rgb + 3 * (base + du * u0 + dv * v), du, u1 - u0, row + u0);
    }
}
