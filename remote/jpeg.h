/* jpeg.h (remote) - frames as JPEG for the remote view: 8-bit sRGB pixels
 * (XRGB8888 words as engine/base/srgb8.h encodes them, what the page shows) in,
 * a JPEG file in memory out, through libjpeg-turbo's TurboJPEG API (its SIMD
 * encoder; browsers decode JPEG natively). Quality and chroma subsampling are
 * the knobs (REPORT.md: bytes and encode time against FLIP).
 *
 * Threading: one remote_jpeg is used by one thread at a time (the encoder
 * thread); separate objects are independent. */
#ifndef TESSERA_REMOTE_JPEG_H
#define TESSERA_REMOTE_JPEG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

/* Chroma subsampling: 4:4:4 keeps every pixel's colour, 4:2:2 halves the
 * colour horizontally, 4:2:0 both ways (a quarter of the colour samples). */
typedef enum remote_subsampling {
    REMOTE_SUBSAMPLING_444,
    REMOTE_SUBSAMPLING_422,
    REMOTE_SUBSAMPLING_420,
} remote_subsampling;

#define REMOTE_SUBSAMPLING_NAMES "444, 422, 420"
#define REMOTE_JPEG_QUALITY_MIN 1
#define REMOTE_JPEG_QUALITY_MAX 100

/* "444", "422", "420" -> *out; false for anything else. */
bool remote_subsampling_parse(const char *name, remote_subsampling *out);
const char *remote_subsampling_name(remote_subsampling s);

typedef struct remote_jpeg remote_jpeg;

/* A compressor with its own output buffer. NULL with err. */
remote_jpeg *remote_jpeg_create(tess_error *err);
void remote_jpeg_destroy(remote_jpeg *j); /* NULL is fine */

/* Compress width_px x height_px XRGB8888 words (row-major, top row first,
 * stride_px words a row) at `quality` (REMOTE_JPEG_QUALITY_MIN..MAX) and
 * `sub`. *out points into j's buffer, valid until the next call on j or its
 * destruction; *out_bytes is the file's size. False with err (TurboJPEG's
 * message) on failure or invalid arguments. */
bool remote_jpeg_encode(remote_jpeg *j, const uint32_t *xrgb, int width_px, int height_px, int stride_px,
                        int quality, remote_subsampling sub, const uint8_t **out, size_t *out_bytes,
                        tess_error *err);

/* Decode a JPEG file into newly allocated XRGB8888 words (*xrgb, free()
 * it), with its size. False with err for a file TurboJPEG cannot read. For
 * tests and the report's error curve. */
bool remote_jpeg_decode(const uint8_t *data, size_t bytes, uint32_t **xrgb, int *width_px, int *height_px,
                        tess_error *err);

#endif
