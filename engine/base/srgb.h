/* srgb.h - the sRGB transfer curve (IEC 61966-2-1) in double, both ways:
 * code values in [0, 1] <-> linear values in [0, 1]. The 8-bit encoder of
 * scan-out and image files (engine/base/srgb8.h) is exact to this curve; the image
 * reader, the FLIP error map's colours and the FLIP check's pairs use it too. */
#ifndef TESSERA_SRGB_H
#define TESSERA_SRGB_H

#include <math.h>

/* Linear value of an sRGB code value (both in [0, 1]). */
static inline double srgb_curve_decode(double code)
{
    return code <= 0.04045 ? code / 12.92 : pow((code + 0.055) / 1.055, 2.4);
}

/* sRGB code value of a linear value (both in [0, 1]), not rounded. */
static inline double srgb_curve_encode(double linear)
{
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
}

#endif
