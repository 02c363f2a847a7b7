/* colormap.h - colour maps (a scalar to a colour, for particles) and transfer
 * functions (a scalar to a colour and an opacity, for volumes): one value
 * type, built-in maps by name, exact evaluation, a baked table for the
 * per-hit lookup, and the JSON form of scene files.
 *
 * MAPPING. A data value v becomes t = (v - lo) / (hi - lo), clamped to
 * [0, 1]; t then interpolates piecewise-linearly between the control points
 * (colour and opacity separately). Before the first point and after the last
 * the end points' values hold. lo == hi maps every value to t = 0 (the first
 * point); a NaN value also gives t = 0, +inf gives 1, -inf gives 0.
 *
 * COLOUR SPACE. Colours are stored and interpolated as linear RGB in [0, 1]
 * (the engine renders in linear RGB). Tables and JSON give colours as sRGB
 * code values, decoded once when the map is made (engine/base/srgb.h).
 *
 * OPACITY. A map without opacity points is opaque (opacity 1 everywhere). The
 * opacity is a number in [0, 1] interpolated like a colour channel; how it
 * turns into absorption along a ray (per unit length, per step) is the volume
 * renderer's business, not this module's.
 *
 * RANGE. [lo, hi] is in data units. With range_auto the caller takes it from
 * the data (colormap_fit_range with the data's min and max) before baking;
 * until then lo = 0, hi = 1.
 *
 * Ownership: a colormap and a colormap_table are plain values (no pointers);
 * copy them freely. Threading: none inside; a baked table is read-only and
 * may be shared by every render thread. */
#ifndef TESSERA_COLORMAP_H
#define TESSERA_COLORMAP_H

#include <stdbool.h>
#include <stdint.h>

#include "err.h"

struct json_object; /* json-c */
struct jr_ctx;      /* engine/base/json_read.h */

/* more control points than a published map needs (they sample at 33 or fewer) */
#define COLORMAP_MAX_POINTS 64
/* the longest built-in name plus room; custom maps have name "" */
#define COLORMAP_NAME_BYTES 32
/* entries of a baked table (16 KiB): nearest-entry lookup is then off by at
 * most half an entry, 1/2046 of the range, times the steepest segment's
 * slope (colormap_table_error) */
#define COLORMAP_TABLE_SIZE 1024
/* largest difference, in linear RGB and in opacity, between colormap_lookup
 * and colormap_eval for every built-in map (tests/test_colormap.c checks it):
 * viridis' red rises 5.1 per unit of t at its top end, so half an entry is
 * 0.0025 there. That is under one 8-bit sRGB code value where the linear
 * value is above 0.2; in darker colours the same linear error is up to a few
 * code values. */
#define COLORMAP_TABLE_TOLERANCE 0.003f

typedef struct colormap_color_point {
    float pos;    /* in [0, 1], strictly increasing along the map */
    float rgb[3]; /* linear RGB, each in [0, 1] */
} colormap_color_point;

typedef struct colormap_opacity_point {
    float pos;     /* in [0, 1], strictly increasing along the map */
    float opacity; /* in [0, 1] */
} colormap_opacity_point;

/* Invariants (colormap_validate checks them; every maker here keeps them):
 * 2 <= color_count <= COLORMAP_MAX_POINTS; opacity_count is 0 or in
 * [2, COLORMAP_MAX_POINTS]; positions and values as their comments say;
 * lo and hi finite with lo <= hi. */
typedef struct colormap {
    char name[COLORMAP_NAME_BYTES]; /* the built-in it came from, "" when custom */
    colormap_color_point colors[COLORMAP_MAX_POINTS];
    uint32_t color_count;
    colormap_opacity_point opacity[COLORMAP_MAX_POINTS];
    uint32_t opacity_count;         /* 0: opaque */
    float lo, hi;                   /* data range mapped to [0, 1] */
    bool range_auto;                /* lo and hi come from the data (colormap_fit_range) */
} colormap;

/* One looked-up value: linear RGB and opacity (1 for an opaque map). */
typedef struct colormap_rgba {
    float r, g, b, a;
} colormap_rgba;

/* A map sampled for the per-hit lookup: entry i is the exact value at
 * t = i / (COLORMAP_TABLE_SIZE - 1). */
typedef struct colormap_table {
    double lo;    /* data value of entry 0 */
    double scale; /* entries per data unit: (SIZE - 1) / (hi - lo); 0 when lo == hi */
    colormap_rgba entry[COLORMAP_TABLE_SIZE];
} colormap_table;

/* ---- built-in maps ------------------------------------------------------- */

/* Every built-in name, NULL-terminated: the colour maps "viridis", "magma",
 * "cool-warm", "greyscale" (opaque) and the transfer functions "ct-bone",
 * "mri-soft" (with opacity ramps). colormap.c documents each and its source. */
const char *const *colormap_names(void);

/* The built-in called `name` into *out, range automatic (lo 0, hi 1). False,
 * *out untouched, when no built-in has that name. */
bool colormap_preset(const char *name, colormap *out);

/* ---- checks and ranges --------------------------------------------------- */

/* Whether *cm keeps the invariants above; else false with a message such as
 * "colour map: colour point 3: position 0.2 is not greater than the previous
 * point's (0.4)". For maps built by hand; the makers here always pass. */
bool colormap_validate(const colormap *cm, tess_error *err);

/* With range_auto, take [lo, hi] from the data's minimum and maximum (both
 * finite, min <= max; otherwise nothing changes). A fixed range stays. */
void colormap_fit_range(colormap *cm, float data_min, float data_max);

/* ---- evaluation ----------------------------------------------------------- */

/* Exact value at normalised position t (clamped to [0, 1]; NaN reads as 0),
 * interpolated in double. */
colormap_rgba colormap_eval_unit(const colormap *cm, double t);

/* Exact value for data value `value` (see MAPPING above). */
colormap_rgba colormap_eval(const colormap *cm, float value);

/* Sample *cm into *out for colormap_lookup (COLORMAP_TABLE_SIZE exact
 * evaluations; call once per map and range, not per frame). */
void colormap_bake(const colormap *cm, colormap_table *out);

/* An upper bound of |colormap_lookup - colormap_eval| in any channel for a
 * table baked from *cm: its steepest slope (per unit of t, over colour and
 * opacity segments) times half an entry. A hand-made map with two points
 * very close together has a large bound: bake is then no substitute for eval. */
float colormap_table_error(const colormap *cm);

/* The table entry nearest to `value`: what a renderer calls per hit. Agrees
 * with colormap_eval on NaN, infinities, clamping and lo == hi; between
 * entries it is within COLORMAP_TABLE_TOLERANCE for the built-ins. */
static inline colormap_rgba colormap_lookup(const colormap_table *table, float value)
{
    /* in double so that no float range overflows; NaN for NaN input or inf * 0 */
    double u = ((double)value - table->lo) * table->scale;
    if (!(u > 0.0)) /* also catches NaN */
        u = 0.0;
    if (u > (double)(COLORMAP_TABLE_SIZE - 1))
        u = (double)(COLORMAP_TABLE_SIZE - 1);
    return table->entry[(int)(u + 0.5)];
}

/* ---- JSON ------------------------------------------------------------------ */

/* Read a colour map from `obj`, the value of the current field of `ctx`:
 *   "viridis"                                      a built-in, range "auto"
 *   {"map": "viridis", "range": [lo, hi]}          a built-in, fixed range
 *   {"colors": [[pos, r, g, b], ...],              custom; r, g, b are sRGB
 *    "opacity": [[pos, a], ...], "range": "auto"}  code values in [0, 1]
 * "map" or "colors" is required (not both); "opacity" is optional (with
 * "map" it replaces the built-in's opacity); "range" defaults to "auto".
 * docs/scene-format.md ("Colour maps and transfer functions") has the rules
 * and messages. False with a jr_ctx message naming the field; *out is
 * written only on success. */
bool colormap_from_json(struct json_object *obj, struct jr_ctx *ctx, colormap *out);

#endif
