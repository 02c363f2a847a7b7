/* srgb8.h (wall) - linear values to 8-bit sRGB codes: the encoding every
 * 8-bit pixel tessera shows or writes gets (scan-out words, wall/xrgb.h; 8-bit
 * image files, wall/dump.h). Exact: the code is the sRGB curve of
 * engine/base/srgb.h in double, clamped to [0, 1] and rounded to nearest, found by
 * a table and one comparison instead of a pow() a value. Plain C, so a DRM
 * kiosk encodes pixels without OpenImageIO.
 *
 * Threading: the table is built once, on the first call from any thread
 * (pthread_once); every function may be called from any thread after. */
#ifndef TESSERA_WALL_SRGB8_H
#define TESSERA_WALL_SRGB8_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" { /* wall/dump_oiio.cpp encodes 8-bit files with it */
#endif

/* The 8-bit sRGB code of one linear value: 0 for values <= 0 and NaN, 255 for >= 1. */
uint8_t srgb8_encode(float linear);

/* srgb8_encode of values[0 .. count) into codes[0 .. count). */
void srgb8_encode_values(const float *values, size_t count, uint8_t *codes);

/* `count` pixels of linear RGB (3 floats each), pixel i at rgb + 3 * i *
 * stride_px (stride_px may be negative), encoded into XRGB8888 words
 * out[0 .. count) (X = 0, R in bits 16-23): one scan-out row in one call. */
void srgb8_encode_xrgb(const float *rgb, long stride_px, int count, uint32_t *out);

#ifdef __cplusplus
}
#endif

#endif
