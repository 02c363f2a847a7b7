/* dump.h - the dump-to-file backend: frames written through OpenImageIO.
 *
 * The format follows the file extension: .png (and other 8-bit formats such as
 * .jpg, .tif, .ppm) get 8-bit sRGB-encoded values; .exr gets linear float.
 * Implemented in dump.c (frame paths) and the image module dump_oiio.cpp, which
 * dump.c loads on the first image read or write (dump_module.h); every C++
 * exception is caught there and becomes a tess_error naming the path and
 * OpenImageIO's message. */
#ifndef TESSERA_DUMP_H
#define TESSERA_DUMP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"
#include "engine/base/srgb8.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Write a W x H image of linear RGB floats (3 per pixel, row-major, top row
 * first) to `path`. */
bool dump_write_rgb(const char *path, int width_px, int height_px, const float *rgb_linear, tess_error *err);

/* Read an image as 8-bit RGB (3 bytes per pixel, top row first), as stored in
 * the file (no colour conversion); for tests and reference images. The caller
 * frees *rgb_out with free(). */
bool dump_read_rgb8(const char *path, int *width_px, int *height_px, uint8_t **rgb_out, tess_error *err);

/* Read an image as float RGB (3 per pixel) with the file's values (EXR: linear). */
bool dump_read_rgbf(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err);

/* Read an image as linear RGB floats (3 per pixel, top row first), for
 * measuring: formats stored as floating point (EXR, HDR, float TIFF...) are
 * taken as linear and kept as stored; integer formats (8- and 16-bit PNG,
 * JPEG, TIFF...) are taken as sRGB-encoded and decoded with the sRGB curve
 * (IEC 61966-2-1) in double. Grey becomes RGB, alpha and further channels
 * are dropped. Errors name the file and OpenImageIO's reason. The caller
 * frees *rgb_out with free(). */
bool dump_read_linear_rgb(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err);

/* The file name of frame `frame` of a sequence written to `pattern`: a run of
 * '#' becomes the zero-padded frame number (at least as many digits as '#'s),
 * as does a printf-style "%d" or "%0Nd". A pattern without either gets
 * "_NNNN" before the extension when `sequence` is true, and is used as is
 * otherwise. False (with err) when the result does not fit in out_bytes or
 * the pattern has more than one frame-number field. */
bool dump_frame_path(const char *pattern, int frame, bool sequence, char *out, size_t out_bytes,
                     tess_error *err);

/* The code 8-bit files get for one linear value (clamped to [0, 1], rounded to nearest):
 * srgb8_encode (engine/base/srgb8.h), the encoder scan-out shares. */
static inline uint8_t dump_srgb_encode_u8(float linear) { return srgb8_encode(linear); }

#ifdef __cplusplus
}
#endif

#endif
