/* colormap.c - built-in colour maps and transfer functions, evaluation,
 * baking and the JSON form (colormap.h). */
#include "colormap.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "json_read.h"
#include "srgb.h"

/* ---- built-in tables ------------------------------------------------------ */

/* Colours are sRGB code values written 0xRRGGBB, for readability; they are
 * decoded to linear RGB once, when a map is made (make_preset). */

/* viridis and magma: Stefan van der Walt and Nathaniel Smith (viridis with
 * Eric Firing), the matplotlib colour maps released under CC0
 * (https://github.com/BIDS/colormap, colormaps.py). Each published table
 * has 256 entries; these are that table linearly interpolated at t = i / 32
 * (33 points, evenly spaced) and rounded to 8 bits. Against all 256
 * published entries the 33-point map is within 0.004 in linear RGB. */
static const uint32_t viridis_srgb[] = {
    0x440154, 0x470d60, 0x48186a, 0x482374, 0x472d7b, 0x453681, 0x424086, 0x3f4989, 0x3b528b,
    0x375a8d, 0x33638d, 0x2f6a8e, 0x2c728e, 0x297a8e, 0x26818e, 0x23898e, 0x21908c, 0x1f988b,
    0x1f9f88, 0x21a685, 0x28ae80, 0x31b57b, 0x3ebc74, 0x4cc26c, 0x5dc963, 0x6ece58, 0x82d34c,
    0x96d83f, 0xabdc32, 0xc0df24, 0xd5e21a, 0xeae51a, 0xfde725,
};

static const uint32_t magma_srgb[] = {
    0x000004, 0x030311, 0x0a0822, 0x130d33, 0x1d1146, 0x28115a, 0x36106a, 0x430f76, 0x50127c,
    0x5d177f, 0x691c81, 0x762181, 0x822681, 0x8f2a81, 0x9c2e7f, 0xa9327d, 0xb63779, 0xc33b75,
    0xcf4170, 0xdb486a, 0xe65163, 0xee5c5e, 0xf5695c, 0xf9785d, 0xfb8761, 0xfd9668, 0xfea571,
    0xfeb47b, 0xfec387, 0xfed194, 0xfde0a2, 0xfceeb0, 0xfcfdbf,
};

/* cool-warm: Kenneth Moreland, "Diverging Color Maps for Scientific
 * Visualization", ISVC 2009; his 33-point table (CoolWarmFloat33.csv, sRGB,
 * evenly spaced) rounded to 8 bits. Blue #3b4cc0 to red #b40426 through the
 * grey #dddddd at t = 0.5. */
static const uint32_t cool_warm_srgb[] = {
    0x3b4cc0, 0x445acc, 0x4d68d7, 0x5775e1, 0x6282ea, 0x6c8ef1, 0x779af7, 0x82a5fb, 0x8db0fe,
    0x98b9ff, 0xa3c2ff, 0xaec9fd, 0xb8d0f9, 0xc2d5f4, 0xccd9ee, 0xd5dbe6, 0xdddddd, 0xe5d8d1,
    0xecd3c5, 0xf1ccb9, 0xf5c4ad, 0xf7bba0, 0xf7b194, 0xf7a687, 0xf49a7b, 0xf18d6f, 0xec7f63,
    0xe57058, 0xde604d, 0xd55042, 0xcb3e38, 0xc0282f, 0xb40426,
};

/* greyscale: black to white in 17 steps even in sRGB code value (0x00, 0x10,
 * ..., 0xf0, 0xff), so that, interpolated in linear light between them, the
 * ramp still looks even rather than too bright in the dark half. */
static const uint32_t greyscale_srgb[] = {
    0x000000, 0x101010, 0x202020, 0x303030, 0x404040, 0x505050, 0x606060, 0x707070, 0x808080,
    0x909090, 0xa0a0a0, 0xb0b0b0, 0xc0c0c0, 0xd0d0d0, 0xe0e0e0, 0xf0f0f0, 0xffffff,
};

/* ct-bone: CT bone, laid out for a range of [-1000, 2000] Hounsfield units
 * (t = (HU + 1000) / 3000): air (t 0) to soft tissue and water (t 0.33 to
 * 0.35) stay transparent; opacity rises from t 0.40 (200 HU, where
 * cancellous bone starts) through 0.3 at t 0.50 (500 HU) to 0.8 at t 0.70
 * (1100 HU, cortical bone); the colour goes from dark red through beige to
 * ivory and white. Our own simple design, not a published one; no segment
 * is steeper than COLORMAP_TABLE_TOLERANCE allows. */
static const float ct_bone_pos[] = {0.f, 0.40f, 0.50f, 0.70f, 1.f};
static const uint32_t ct_bone_srgb[] = {0x000000, 0x8c3a26, 0xe0bc8c, 0xfff2d8, 0xffffff};
static const colormap_opacity_point ct_bone_opacity[] = {
    {0.f, 0.f}, {0.40f, 0.f}, {0.50f, 0.3f}, {0.70f, 0.8f}, {1.f, 0.95f},
};

/* mri-soft: soft tissue in a T1-weighted MRI volume with the automatic range:
 * the dark background (t < 0.1) transparent, then a gentle opacity ramp to
 * 0.6 at the brightest value so that inner structures show through; warm
 * flesh tones from black to off-white. Our own simple design. */
static const float mri_soft_pos[] = {0.f, 0.25f, 0.60f, 1.f};
static const uint32_t mri_soft_srgb[] = {0x000000, 0x5a3a32, 0xd8b4a0, 0xfff6ee};
static const colormap_opacity_point mri_soft_opacity[] = {
    {0.f, 0.f}, {0.10f, 0.f}, {0.30f, 0.05f}, {0.70f, 0.3f}, {1.f, 0.6f},
};

#define COUNT(a) (sizeof(a) / sizeof(a)[0])

/* A built-in: colours with their positions (NULL: evenly spaced from 0 to
 * 1), and opacity points (none: opaque). */
typedef struct preset {
    const char *name;
    const uint32_t *srgb;
    const float *pos;
    uint32_t color_count;
    const colormap_opacity_point *opacity;
    uint32_t opacity_count;
} preset;

static const preset presets[] = {
    {"viridis", viridis_srgb, NULL, COUNT(viridis_srgb), NULL, 0},
    {"magma", magma_srgb, NULL, COUNT(magma_srgb), NULL, 0},
    {"cool-warm", cool_warm_srgb, NULL, COUNT(cool_warm_srgb), NULL, 0},
    {"greyscale", greyscale_srgb, NULL, COUNT(greyscale_srgb), NULL, 0},
    {"ct-bone", ct_bone_srgb, ct_bone_pos, COUNT(ct_bone_srgb), ct_bone_opacity, COUNT(ct_bone_opacity)},
    {"mri-soft", mri_soft_srgb, mri_soft_pos, COUNT(mri_soft_srgb), mri_soft_opacity, COUNT(mri_soft_opacity)},
};

/* in the order of presets[] */
static const char *const preset_names[] = {"viridis", "magma", "cool-warm", "greyscale", "ct-bone", "mri-soft", NULL};

_Static_assert(COUNT(preset_names) == COUNT(presets) + 1, "one name per preset, then NULL");

const char *const *colormap_names(void) { return preset_names; }

/* The empty map every maker starts from: no points, range automatic [0, 1]. */
static void init_empty(colormap *cm)
{
    memset(cm, 0, sizeof *cm);
    cm->lo = 0.f;
    cm->hi = 1.f;
    cm->range_auto = true;
}

static float decode_channel(uint32_t srgb, int shift)
{
    return (float)srgb_curve_decode((double)((srgb >> shift) & 0xffu) / 255.0);
}

static void make_preset(const preset *p, colormap *out)
{
    init_empty(out);
    snprintf(out->name, sizeof out->name, "%s", p->name);
    out->color_count = p->color_count;
    for (uint32_t i = 0; i < p->color_count; i++) {
        colormap_color_point *c = &out->colors[i];
        c->pos = p->pos ? p->pos[i] : (float)i / (float)(p->color_count - 1);
        c->rgb[0] = decode_channel(p->srgb[i], 16);
        c->rgb[1] = decode_channel(p->srgb[i], 8);
        c->rgb[2] = decode_channel(p->srgb[i], 0);
    }
    out->opacity_count = p->opacity_count;
    for (uint32_t i = 0; i < p->opacity_count; i++)
        out->opacity[i] = p->opacity[i];
}

static const preset *find_preset(const char *name)
{
    for (size_t i = 0; i < COUNT(presets); i++)
        if (strcmp(presets[i].name, name) == 0)
            return &presets[i];
    return NULL;
}

bool colormap_preset(const char *name, colormap *out)
{
    const preset *p = name ? find_preset(name) : NULL;
    if (!p)
        return false;
    make_preset(p, out);
    return true;
}

/* room for every name in names_text */
#define NAMES_TEXT_BYTES 128

/* "viridis, magma, ..." into buf, for messages. */
static const char *names_text(char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t i = 0; preset_names[i] && used < size; i++)
        used += (size_t)snprintf(buf + used, size - used, "%s%s", i ? ", " : "", preset_names[i]);
    return buf;
}

/* ---- checks ------------------------------------------------------------------ */

static bool unit(float x) { return x >= 0.f && x <= 1.f; } /* false for NaN */

bool colormap_validate(const colormap *cm, tess_error *err)
{
    if (cm->color_count < 2 || cm->color_count > COLORMAP_MAX_POINTS)
        return tess_error_set(err, "colour map: %u colour points (expected 2 to %d)", cm->color_count,
                              COLORMAP_MAX_POINTS);
    if (cm->opacity_count == 1 || cm->opacity_count > COLORMAP_MAX_POINTS)
        return tess_error_set(err, "colour map: %u opacity points (expected none or 2 to %d)", cm->opacity_count,
                              COLORMAP_MAX_POINTS);
    for (uint32_t i = 0; i < cm->color_count; i++) {
        const colormap_color_point *c = &cm->colors[i];
        if (!unit(c->pos) || !unit(c->rgb[0]) || !unit(c->rgb[1]) || !unit(c->rgb[2]))
            return tess_error_set(err, "colour map: colour point %u: position and channels must be in [0, 1]", i);
        if (i > 0 && !(c->pos > cm->colors[i - 1].pos))
            return tess_error_set(err,
                                  "colour map: colour point %u: position %g is not greater than the previous point's (%g)",
                                  i, c->pos, cm->colors[i - 1].pos);
    }
    for (uint32_t i = 0; i < cm->opacity_count; i++) {
        const colormap_opacity_point *o = &cm->opacity[i];
        if (!unit(o->pos) || !unit(o->opacity))
            return tess_error_set(err, "colour map: opacity point %u: position and opacity must be in [0, 1]", i);
        if (i > 0 && !(o->pos > cm->opacity[i - 1].pos))
            return tess_error_set(err,
                                  "colour map: opacity point %u: position %g is not greater than the previous point's (%g)",
                                  i, o->pos, cm->opacity[i - 1].pos);
    }
    if (!isfinite(cm->lo) || !isfinite(cm->hi) || !(cm->lo <= cm->hi))
        return tess_error_set(err, "colour map: range [%g, %g] must be finite with lo <= hi", cm->lo, cm->hi);
    return true;
}

void colormap_fit_range(colormap *cm, float data_min, float data_max)
{
    if (!cm->range_auto || !isfinite(data_min) || !isfinite(data_max) || !(data_min <= data_max))
        return;
    cm->lo = data_min;
    cm->hi = data_max;
}

/* ---- evaluation ------------------------------------------------------------- */

/* Index i of the segment [pos(i), pos(i+1)] holding t, and the fraction along
 * it, for `count` >= 2 strictly increasing positions: the float at `first`
 * and every `stride` bytes after it (the pos of each colour or opacity
 * point). Before the first point the fraction is 0 of segment 0, after the
 * last 1 of the last segment. */
static uint32_t find_segment(const float *first, size_t stride, uint32_t count, double t, double *frac)
{
    const char *base = (const char *)first;
#define POS(k) ((double)*(const float *)(base + (size_t)(k) * stride))
    if (t <= POS(0)) {
        *frac = 0.0;
        return 0;
    }
    if (t >= POS(count - 1)) {
        *frac = 1.0;
        return count - 2;
    }
    uint32_t i = 0;
    while (i + 2 < count && t >= POS(i + 1)) /* a scan: at most 64 points, and not the per-hit path */
        i++;
    *frac = (t - POS(i)) / (POS(i + 1) - POS(i)); /* positions strictly increase: no division by 0 */
#undef POS
    return i;
}

static double lerp(double a, double b, double f) { return a + (b - a) * f; }

colormap_rgba colormap_eval_unit(const colormap *cm, double t)
{
    if (!(t > 0.0)) /* also NaN */
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    double f;
    uint32_t i = find_segment(&cm->colors[0].pos, sizeof cm->colors[0], cm->color_count, t, &f);
    const float *a = cm->colors[i].rgb, *b = cm->colors[i + 1].rgb;
    colormap_rgba out = {(float)lerp(a[0], b[0], f), (float)lerp(a[1], b[1], f), (float)lerp(a[2], b[2], f), 1.f};
    if (cm->opacity_count >= 2) {
        i = find_segment(&cm->opacity[0].pos, sizeof cm->opacity[0], cm->opacity_count, t, &f);
        out.a = (float)lerp(cm->opacity[i].opacity, cm->opacity[i + 1].opacity, f);
    }
    return out;
}

colormap_rgba colormap_eval(const colormap *cm, float value)
{
    double span = (double)cm->hi - (double)cm->lo;
    double t = span > 0.0 ? ((double)value - cm->lo) / span : 0.0; /* lo == hi: the first point */
    return colormap_eval_unit(cm, t);
}

void colormap_bake(const colormap *cm, colormap_table *out)
{
    double span = (double)cm->hi - (double)cm->lo;
    out->lo = cm->lo;
    out->scale = span > 0.0 ? (double)(COLORMAP_TABLE_SIZE - 1) / span : 0.0;
    for (int i = 0; i < COLORMAP_TABLE_SIZE; i++)
        out->entry[i] = colormap_eval_unit(cm, (double)i / (double)(COLORMAP_TABLE_SIZE - 1));
}

float colormap_table_error(const colormap *cm)
{
    double steepest = 0.0;
    for (uint32_t i = 0; i + 1 < cm->color_count; i++) {
        double dt = (double)cm->colors[i + 1].pos - cm->colors[i].pos;
        for (int k = 0; k < 3; k++)
            steepest = fmax(steepest, fabs((double)cm->colors[i + 1].rgb[k] - cm->colors[i].rgb[k]) / dt);
    }
    for (uint32_t i = 0; i + 1 < cm->opacity_count; i++) {
        double dt = (double)cm->opacity[i + 1].pos - cm->opacity[i].pos;
        steepest = fmax(steepest, fabs((double)cm->opacity[i + 1].opacity - cm->opacity[i].opacity) / dt);
    }
    /* plus the float rounding of the entries and of the index */
    return (float)(steepest * 0.5 / (COLORMAP_TABLE_SIZE - 1) + 1e-6);
}

/* ---- JSON ---------------------------------------------------------------------- */

/* The built-in `name` at the current field, or "unknown colour map". */
static bool read_name(jr_ctx *c, const char *name, colormap *out)
{
    const preset *p = find_preset(name);
    char known[NAMES_TEXT_BYTES];
    if (!p)
        return jr_field_fail(c, "unknown colour map '%.64s' (known: %s)", name, names_text(known, sizeof known));
    make_preset(p, out);
    return true;
}

/* Member `key` of `obj`: an array of 2 to COLORMAP_MAX_POINTS points, each an
 * array of `width` numbers in [0, 1] whose first, the position, increases
 * strictly from point to point. Row i goes to rows[i * width ...]. `shape`
 * names the form of a point in messages ("[position, r, g, b]"). */
static bool read_points(jr_ctx *c, json_object *obj, const char *key, size_t width, const char *shape,
                        float *rows, uint32_t *count)
{
    json_object *v = NULL;
    jr_get_member(obj, key, &v);
    size_t saved = jr_field_key(c, key);
    bool ok = jr_expect_array(c, v);
    size_t n = ok ? json_object_array_length(v) : 0;
    if (ok && (n < 2 || n > COLORMAP_MAX_POINTS))
        ok = jr_field_fail(c, "expected 2 to %d points, got %zu", COLORMAP_MAX_POINTS, n);
    for (size_t i = 0; ok && i < n; i++) {
        size_t at_point = jr_field_index(c, i);
        json_object *point = json_object_array_get_idx(v, i);
        if (!json_object_is_type(point, json_type_array) || json_object_array_length(point) != width) {
            if (json_object_is_type(point, json_type_array))
                ok = jr_field_fail(c, "expected %s, got %zu numbers", shape, json_object_array_length(point));
            else
                ok = jr_field_fail(c, "expected %s, got %s", shape, jr_kind(point));
        }
        float *row = rows + i * width;
        ok = ok && jr_numbers(c, point, width, jr_range_unit, row);
        if (ok && i > 0 && !(row[0] > row[-(ptrdiff_t)width])) {
            size_t at_pos = jr_field_index(c, 0);
            ok = jr_field_fail(c, "position %g is not greater than the previous point's (%g)", row[0],
                               row[-(ptrdiff_t)width]);
            jr_field_leave(c, at_pos);
        }
        jr_field_leave(c, at_point);
    }
    jr_field_leave(c, saved);
    if (ok)
        *count = (uint32_t)n;
    return ok;
}

static bool read_colors(jr_ctx *c, json_object *obj, colormap *cm)
{
    float rows[COLORMAP_MAX_POINTS][4];
    uint32_t n = 0;
    if (!read_points(c, obj, "colors", 4, "[position, r, g, b]", &rows[0][0], &n))
        return false;
    cm->color_count = n;
    for (uint32_t i = 0; i < n; i++) {
        cm->colors[i].pos = rows[i][0];
        for (int k = 0; k < 3; k++) /* sRGB code values in [0, 1] decode into [0, 1] */
            cm->colors[i].rgb[k] = (float)srgb_curve_decode(rows[i][1 + k]);
    }
    return true;
}

static bool read_opacity(jr_ctx *c, json_object *obj, colormap *cm)
{
    float rows[COLORMAP_MAX_POINTS][2];
    uint32_t n = 0;
    if (!read_points(c, obj, "opacity", 2, "[position, opacity]", &rows[0][0], &n))
        return false;
    cm->opacity_count = n;
    for (uint32_t i = 0; i < n; i++)
        cm->opacity[i] = (colormap_opacity_point){rows[i][0], rows[i][1]};
    return true;
}

/* "range": "auto" or [lo, hi], finite, lo <= hi. */
static bool read_range(jr_ctx *c, json_object *obj, colormap *cm)
{
    json_object *v = NULL;
    if (!jr_get_member(obj, "range", &v))
        return true; /* automatic, as init_empty left it */
    size_t saved = jr_field_key(c, "range");
    bool ok;
    if (json_object_is_type(v, json_type_string)) {
        ok = strcmp(json_object_get_string(v), "auto") == 0 ||
             jr_field_fail(c, "expected [lo, hi] or \"auto\", got \"%.64s\"", json_object_get_string(v));
    } else if (!json_object_is_type(v, json_type_array)) {
        ok = jr_field_fail(c, "expected [lo, hi] or \"auto\", got %s", jr_kind(v));
    } else {
        float lohi[2];
        ok = jr_numbers(c, v, 2, jr_range_float, lohi) &&
             (lohi[0] <= lohi[1] || jr_field_fail(c, "lo %g is greater than hi %g", lohi[0], lohi[1]));
        if (ok) {
            cm->lo = lohi[0];
            cm->hi = lohi[1];
            cm->range_auto = false;
        }
    }
    jr_field_leave(c, saved);
    return ok;
}

bool colormap_from_json(struct json_object *obj, struct jr_ctx *c, colormap *out)
{
    colormap cm;
    if (json_object_is_type(obj, json_type_string)) {
        if (!read_name(c, json_object_get_string(obj), &cm))
            return false;
        *out = cm;
        return true;
    }
    if (!json_object_is_type(obj, json_type_object))
        return jr_field_fail(c, "expected a colour map name or an object, got %s", jr_kind(obj));
    static const char *const fields[] = {"map", "colors", "opacity", "range", NULL};
    if (!jr_check_fields(c, obj, fields))
        return false;
    json_object *v;
    bool has_map = jr_get_member(obj, "map", &v), has_colors = jr_get_member(obj, "colors", &v);
    if (has_map && has_colors)
        return jr_field_fail(c, "give either 'map' (a built-in) or 'colors', not both");
    char known[NAMES_TEXT_BYTES];
    if (!has_map && !has_colors)
        return jr_field_fail(c, "give 'map' (a built-in: %s) or 'colors'", names_text(known, sizeof known));
    init_empty(&cm);
    if (has_map) {
        const char *name = NULL;
        if (!jr_opt_string(c, obj, "map", &name))
            return false;
        size_t saved = jr_field_key(c, "map");
        bool ok = read_name(c, name, &cm);
        jr_field_leave(c, saved);
        if (!ok)
            return false;
    } else if (!read_colors(c, obj, &cm)) {
        return false;
    }
    if (jr_get_member(obj, "opacity", &v) && !read_opacity(c, obj, &cm))
        return false;
    if (!read_range(c, obj, &cm))
        return false;
    *out = cm;
    return true;
}
