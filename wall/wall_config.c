/* wall_config.c (wall) - reading and checking wall files, and resolving each
 * output's pixel size against a DRM card's connectors or for headless runs.
 * The format, the coordinates and the checks are documented in wall_config.h
 * (and docs/wall-format.md). */
#include "wall_config.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/json_read.h"

/* A wall file is a few dozen lines; a larger file is most likely a mistake. */
#define WALL_FILE_MAX_BYTES (1u << 20)
#define MODE_MAX_PX 32767   /* DRM keeps mode sizes in 16 bits */
#define REFRESH_MAX_HZ 1000.0
#define GRID_MAX_CELL 255
/* Lengths and placed corners stay within 1 km of the wall's origin and an active
 * area is at least 0.1 mm: the fit and overlap checks (1e-6 relative, 0.5 mm)
 * mean something only while positions are not many orders above the sizes.
 * (A position_px of 5e18 once made a 339 mm tall output 0 mm tall.) */
#define WALL_MAX_LENGTH_MM 1e6
#define WALL_MIN_SIZE_MM 0.1
#define MODE_TEXT_BYTES 48  /* "32767x32767@1000.00" with room to spare */
#define LIST_TEXT_BYTES 320 /* the "(the card has: ...)" part of a message */

static const char format_name[] = "tessera-wall";
static const int format_version = 1;

/* How the file placed an output: the kind and its two numbers as written
 * (grid cell, mm or px), before they become the active area's top-left. */
typedef enum placement_kind { PLACE_GRID, PLACE_MM, PLACE_PX } placement_kind;

typedef struct placement {
    placement_kind kind;
    double a, b; /* column, row / x, y */
} placement;

/* ---- small helpers --------------------------------------------------------- */

/* The field path of outputs[i]; returns the length for jr_field_leave. */
static size_t enter_output(jr_ctx *c, size_t i)
{
    size_t saved = jr_field_key(c, "outputs");
    jr_field_index(c, i);
    return saved;
}

/* "FILE: field 'outputs[j].KEY' (or 'outputs[j]' for a NULL key): REASON"; false. */
static bool output_fail(jr_ctx *c, int j, const char *key, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static bool output_fail(jr_ctx *c, int j, const char *key, const char *fmt, ...)
{
    char reason[TESS_ERROR_MSG_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    size_t saved = enter_output(c, (size_t)j);
    if (key)
        jr_field_key(c, key);
    jr_field_fail(c, "%s", reason);
    jr_field_leave(c, saved);
    return false;
}

/* The pixels the output shows as mounted: 90 and 270 swap the mode's sides. */
static void mounted_px(const wall_output *o, int mode_w, int mode_h, int *w, int *h)
{
    bool turned = o->rotation_deg == 90 || o->rotation_deg == 270;
    *w = turned ? mode_h : mode_w;
    *h = turned ? mode_w : mode_h;
}

/* "WxH" or "WxH@HZ" with HZ to 2 decimals, trailing zeros dropped (hz 0: any). */
static const char *format_mode(char *buf, size_t size, int w, int h, double hz)
{
    if (hz <= 0.0) {
        snprintf(buf, size, "%dx%d", w, h);
        return buf;
    }
    int n = snprintf(buf, size, "%dx%d@%.2f", w, h, hz);
    while (n > 0 && (size_t)n < size && buf[n - 1] == '0')
        buf[--n] = '\0';
    if (n > 0 && (size_t)n < size && buf[n - 1] == '.')
        buf[--n] = '\0';
    return buf;
}

/* Whether the physical aspect of the active area agrees with its pixels
 * (square pixels within WALL_ASPECT_TOLERANCE); both aspects (w / h) out. */
static bool aspect_agrees(const wall_output *o, int w_px, int h_px, double *mm_aspect, double *px_aspect)
{
    *mm_aspect = o->width_mm / o->height_mm;
    *px_aspect = (double)w_px / (double)h_px;
    return fabs(*mm_aspect / *px_aspect - 1.0) <= WALL_ASPECT_TOLERANCE;
}

/* ---- a comma-separated list inside a message, cut with "..." when long --- */

typedef struct text_list {
    char text[LIST_TEXT_BYTES];
    size_t used; /* strlen(text) */
    bool cut;    /* "..." was appended; later items are dropped */
} text_list;

static void list_add(text_list *l, const char *item)
{
    static const char more[] = ", ...";
    if (l->cut)
        return;
    size_t sep = l->used ? 2 : 0, len = strlen(item);
    if (l->used + sep + len + sizeof more > sizeof l->text) {
        snprintf(l->text + l->used, sizeof l->text - l->used, "%s", l->used ? more : "...");
        l->used = strlen(l->text);
        l->cut = true;
        return;
    }
    snprintf(l->text + l->used, sizeof l->text - l->used, "%s%s", sep ? ", " : "", item);
    l->used += sep + len;
}

/* ---- the top level ---------------------------------------------------------- */


/* "units" is required so that every file says what its numbers are. */
static bool read_units(jr_ctx *c, json_object *root)
{
    const char *units = NULL;
    if (!jr_require_member(c, root, "units") || !jr_opt_string(c, root, "units", &units))
        return false;
    if (strcmp(units, "mm") == 0)
        return true;
    size_t saved = jr_field_key(c, "units");
    jr_field_fail(c, "expected \"mm\" (sizes and positions are millimetres), got \"%.32s\"", units);
    jr_field_leave(c, saved);
    return false;
}

/* ---- one output: names ------------------------------------------------------ */

static bool is_alpha(char ch) { return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z'); }
static bool is_digit(char ch) { return ch >= '0' && ch <= '9'; }

/* TYPE-INDEX as DRM names connectors ("HDMI-A-1", "DP-2", "eDP-1", "Virtual-1"):
 * a letter first, then letters, digits and '-', ending in '-' and digits. */
static bool is_connector_name(const char *s)
{
    if (!is_alpha(s[0]))
        return false;
    const char *dash = strrchr(s, '-');
    if (!dash || !dash[1])
        return false;
    for (const char *p = s; *p; p++)
        if (!(is_alpha(*p) || is_digit(*p) || *p == '-') || (p > dash && !is_digit(*p)))
            return false;
    return true;
}

static bool read_connector(jr_ctx *c, json_object *obj, wall_output *o)
{
    const char *name = NULL;
    if (!jr_require_member(c, obj, "connector") || !jr_opt_string(c, obj, "connector", &name))
        return false;
    size_t saved = jr_field_key(c, "connector");
    bool ok = strlen(name) < sizeof o->connector
                  ? is_connector_name(name) ||
                        jr_field_fail(c, "expected a DRM connector name TYPE-INDEX such as HDMI-A-1 or DP-2, "
                                         "got '%.40s'", name)
                  : jr_field_fail(c, "at most %zu characters, got %zu", sizeof o->connector - 1, strlen(name));
    jr_field_leave(c, saved);
    if (ok)
        snprintf(o->connector, sizeof o->connector, "%s", name);
    return ok;
}

/* An EDID text field: printable ASCII (as EDID descriptors hold), up to
 * size - 1 characters; absent leaves out as "". */
static bool read_edid_text(jr_ctx *c, json_object *edid, const char *key, char *out, size_t size)
{
    const char *s = NULL;
    if (!jr_opt_string(c, edid, key, &s))
        return false;
    if (!s)
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = strlen(s) < size || jr_field_fail(c, "at most %zu characters, got %zu", size - 1, strlen(s));
    for (const char *p = s; ok && *p; p++)
        if (*p < 0x20 || *p > 0x7e)
            ok = jr_field_fail(c, "expected printable ASCII text");
    jr_field_leave(c, saved);
    if (ok)
        snprintf(out, size, "%s", s);
    return ok;
}

/* The manufacturer is the EDID's PNP id: three capital letters. */
static bool check_manufacturer(jr_ctx *c, const char *m)
{
    if (!m[0] || (strlen(m) == 3 && m[0] >= 'A' && m[0] <= 'Z' && m[1] >= 'A' && m[1] <= 'Z' && m[2] >= 'A' &&
                  m[2] <= 'Z'))
        return true;
    size_t saved = jr_field_key(c, "manufacturer");
    jr_field_fail(c, "expected the 3-letter EDID manufacturer id in capitals such as \"DEL\", got \"%s\"", m);
    jr_field_leave(c, saved);
    return false;
}

static bool read_edid(jr_ctx *c, json_object *obj, wall_edid *e)
{
    static const char *const fields[] = {"manufacturer", "model", "serial", NULL};
    json_object *v;
    if (!jr_get_member(obj, "edid", &v))
        return true;
    char manufacturer[WALL_EDID_TEXT_BYTES] = ""; /* longer than 3 until checked */
    size_t saved = jr_field_key(c, "edid");
    bool ok = jr_expect_object(c, v) && jr_check_fields(c, v, fields) &&
              read_edid_text(c, v, "manufacturer", manufacturer, sizeof manufacturer) &&
              check_manufacturer(c, manufacturer) &&
              read_edid_text(c, v, "model", e->model, sizeof e->model) &&
              read_edid_text(c, v, "serial", e->serial, sizeof e->serial);
    if (ok)
        memcpy(e->manufacturer, manufacturer, sizeof e->manufacturer); /* "" or 3 letters and the NUL */
    if (ok && !e->manufacturer[0] && !e->model[0] && !e->serial[0])
        ok = jr_field_fail(c, "give at least one of manufacturer, model and serial");
    jr_field_leave(c, saved);
    e->given = ok;
    return ok;
}

/* ---- one output: mode and rotation -------------------------------------- */

/* A decimal integer of 1..5 digits at *p, advanced past it; 0 if none. */
static int scan_int(const char **p)
{
    int value = 0, digits = 0;
    while (is_digit(**p) && digits < 6) {
        value = value * 10 + (**p - '0');
        (*p)++;
        digits++;
    }
    return digits >= 1 && digits <= 5 ? value : 0;
}

/* A refresh rate "60" or "59.94": digits, optionally '.' and digits, to the end. */
static bool scan_refresh(const char *p, double *hz)
{
    const char *start = p;
    while (is_digit(*p))
        p++;
    if (p == start)
        return false;
    if (*p == '.') {
        const char *frac = ++p;
        while (is_digit(*p))
            p++;
        if (p == frac)
            return false;
    }
    if (*p || p - start > 12)
        return false;
    *hz = strtod(start, NULL);
    return *hz > 0.0 && *hz <= REFRESH_MAX_HZ;
}

/* "preferred", "WxH" or "WxH@HZ" into o's mode fields. */
static bool parse_mode(const char *s, wall_output *o)
{
    if (strcmp(s, "preferred") == 0) {
        o->mode_preferred = true;
        return true;
    }
    const char *p = s;
    int w = scan_int(&p);
    if (!w || *p++ != 'x')
        return false;
    int h = scan_int(&p);
    if (!h || w > MODE_MAX_PX || h > MODE_MAX_PX)
        return false;
    double hz = 0.0;
    if (*p && (*p != '@' || !scan_refresh(p + 1, &hz)))
        return false;
    o->mode_w_px = w;
    o->mode_h_px = h;
    o->mode_hz = hz;
    return true;
}

static bool read_mode(jr_ctx *c, json_object *obj, wall_output *o)
{
    const char *s = NULL;
    if (!jr_opt_string(c, obj, "mode", &s))
        return false;
    if (!s || parse_mode(s, o)) {
        o->mode_preferred = !s || o->mode_preferred;
        return true;
    }
    size_t saved = jr_field_key(c, "mode");
    jr_field_fail(c, "expected \"WIDTHxHEIGHT\", \"WIDTHxHEIGHT@HZ\" (1..%d pixels, refresh in (0, %g] Hz) or "
                     "\"preferred\", got \"%.40s\"", MODE_MAX_PX, REFRESH_MAX_HZ, s);
    jr_field_leave(c, saved);
    return false;
}

static bool read_rotation(jr_ctx *c, json_object *obj, wall_output *o)
{
    double deg = 0.0;
    if (!jr_opt_double(c, obj, "rotation", jr_range_float, &deg))
        return false;
    if (deg == 0.0 || deg == 90.0 || deg == 180.0 || deg == 270.0) {
        o->rotation_deg = (int)deg;
        return true;
    }
    size_t saved = jr_field_key(c, "rotation");
    jr_field_fail(c, "must be 0, 90, 180 or 270 (degrees clockwise), got %g", deg);
    jr_field_leave(c, saved);
    return false;
}

/* ---- one output: geometry ---------------------------------------------- */

static const jr_range size_range = {WALL_MIN_SIZE_MM, WALL_MAX_LENGTH_MM, false, false};
static const jr_range bezel_range = {0.0, WALL_MAX_LENGTH_MM, false, false};
static const jr_range position_range = {-WALL_MAX_LENGTH_MM, WALL_MAX_LENGTH_MM, false, false};

/* The current field as an array of exactly 2 numbers in r. */
static bool read_pair(jr_ctx *c, json_object *v, jr_range r, double out[2])
{
    if (!json_object_is_type(v, json_type_array))
        return jr_field_fail(c, "expected an array of 2 numbers, got %s", jr_kind(v));
    size_t got = json_object_array_length(v);
    if (got != 2)
        return jr_field_fail(c, "expected an array of 2 numbers, got %zu element%s", got, got == 1 ? "" : "s");
    for (size_t i = 0; i < 2; i++) {
        size_t saved = jr_field_index(c, i);
        bool ok = jr_double(c, json_object_array_get_idx(v, i), r, &out[i]);
        jr_field_leave(c, saved);
        if (!ok)
            return false;
    }
    return true;
}

static bool read_size(jr_ctx *c, json_object *obj, wall_output *o)
{
    json_object *v;
    double wh[2];
    if (!jr_require_member(c, obj, "size_mm") || !jr_get_member(obj, "size_mm", &v))
        return false;
    size_t saved = jr_field_key(c, "size_mm");
    bool ok = read_pair(c, v, size_range, wh);
    jr_field_leave(c, saved);
    o->width_mm = wh[0];
    o->height_mm = ok ? wh[1] : 0.0;
    return ok;
}

static bool read_bezel(jr_ctx *c, json_object *obj, wall_output *o)
{
    static const char *const fields[] = {"left", "top", "right", "bottom", NULL};
    json_object *v;
    if (!jr_get_member(obj, "bezel_mm", &v))
        return true;
    size_t saved = jr_field_key(c, "bezel_mm");
    bool ok = jr_expect_object(c, v) && jr_check_fields(c, v, fields) &&
              jr_opt_double(c, v, "left", bezel_range, &o->bezel_left_mm) &&
              jr_opt_double(c, v, "top", bezel_range, &o->bezel_top_mm) &&
              jr_opt_double(c, v, "right", bezel_range, &o->bezel_right_mm) &&
              jr_opt_double(c, v, "bottom", bezel_range, &o->bezel_bottom_mm);
    jr_field_leave(c, saved);
    return ok;
}

/* A grid cell: whole numbers 0..GRID_MAX_CELL (the pair is already read). */
static bool check_grid_cell(jr_ctx *c, const double cell[2])
{
    for (size_t i = 0; i < 2; i++) {
        if (cell[i] == floor(cell[i]) && cell[i] <= GRID_MAX_CELL)
            continue;
        size_t saved = jr_field_index(c, i);
        jr_field_fail(c, "must be a whole number from 0 to %d, got %g", GRID_MAX_CELL, cell[i]);
        jr_field_leave(c, saved);
        return false;
    }
    return true;
}

/* position_px [x, y] (read, the current field) in wall mm lies within
 * WALL_MAX_LENGTH_MM of the origin at this output's pixel pitch. */
static bool check_px_position(jr_ctx *c, const wall_output *o, const double xy[2])
{
    int w_px, h_px;
    mounted_px(o, o->mode_w_px, o->mode_h_px, &w_px, &h_px);
    const double pitch_mm[2] = {o->width_mm / w_px, o->height_mm / h_px};
    for (size_t i = 0; i < 2; i++) {
        if (fabs(xy[i] * pitch_mm[i]) <= WALL_MAX_LENGTH_MM)
            continue;
        size_t saved = jr_field_index(c, i);
        jr_field_fail(c, "%g px at this output's %g mm pixels is %g mm from the origin; a wall spans at most "
                         "%g mm", xy[i], pitch_mm[i], xy[i] * pitch_mm[i], WALL_MAX_LENGTH_MM);
        jr_field_leave(c, saved);
        return false;
    }
    return true;
}

/* Exactly one of grid, position_mm, position_px; *p as written. */
static bool read_placement(jr_ctx *c, json_object *obj, const wall_output *o, placement *p)
{
    static const char *const keys[] = {"grid", "position_mm", "position_px"};
    static const placement_kind kinds[] = {PLACE_GRID, PLACE_MM, PLACE_PX};
    json_object *v = NULL, *found = NULL;
    int count = 0, which = 0;
    char given[64] = "";
    for (int k = 0; k < 3; k++) {
        if (!jr_get_member(obj, keys[k], &v))
            continue;
        size_t used = strlen(given);
        snprintf(given + used, sizeof given - used, "%s%s", count ? " and " : "", keys[k]);
        found = v;
        which = k;
        count++;
    }
    if (count == 0)
        return jr_field_fail(c, "needs one of grid, position_mm or position_px (where the output sits)");
    if (count > 1)
        return jr_field_fail(c, "give only one of grid, position_mm and position_px, got %s", given);
    size_t saved = jr_field_key(c, keys[which]);
    double ab[2];
    /* position_px is checked in mm once read (check_px_position) */
    jr_range r = kinds[which] == PLACE_GRID ? jr_range_nonneg
                 : kinds[which] == PLACE_MM ? position_range
                                            : jr_range_float;
    bool ok = read_pair(c, found, r, ab) && (kinds[which] != PLACE_GRID || check_grid_cell(c, ab));
    if (ok && kinds[which] == PLACE_PX && o->mode_preferred)
        ok = jr_field_fail(c, "needs an explicit mode such as \"1920x1080\" (a wall pixel is this output's "
                              "pixel), got mode 'preferred'");
    if (ok && kinds[which] == PLACE_PX)
        ok = check_px_position(c, o, ab);
    jr_field_leave(c, saved);
    *p = (placement){kinds[which], ab[0], ab[1]};
    return ok;
}

/* With an explicit mode the active area's aspect must match its mounted pixels. */
static bool check_aspect(jr_ctx *c, const wall_output *o)
{
    if (o->mode_preferred)
        return true;
    int w, h;
    double mm_aspect, px_aspect;
    char mode[MODE_TEXT_BYTES];
    mounted_px(o, o->mode_w_px, o->mode_h_px, &w, &h);
    if (aspect_agrees(o, w, h, &mm_aspect, &px_aspect))
        return true;
    return jr_field_fail(c, "size_mm %g x %g has aspect %.4f but mode %s rotated %d gives %d x %d px, aspect "
                            "%.4f; they must agree within %g%% (square pixels)",
                         o->width_mm, o->height_mm, mm_aspect,
                         format_mode(mode, sizeof mode, o->mode_w_px, o->mode_h_px, o->mode_hz), o->rotation_deg,
                         w, h, px_aspect, WALL_ASPECT_TOLERANCE * 100.0);
}

/* outputs[i] (the current field) into *o and *p. */
static bool read_output(jr_ctx *c, json_object *v, wall_output *o, placement *p)
{
    static const char *const fields[] = {"connector", "edid", "mode", "rotation", "grid", "position_mm",
                                         "position_px", "size_mm", "bezel_mm", NULL};
    *o = (wall_output){.device_connector = -1, .device_mode = -1};
    return jr_expect_object(c, v) && jr_check_fields(c, v, fields) && read_connector(c, v, o) &&
           read_edid(c, v, &o->edid) && read_mode(c, v, o) && read_rotation(c, v, o) && read_size(c, v, o) &&
           read_bezel(c, v, o) && read_placement(c, v, o, p) && check_aspect(c, o);
}

static bool read_outputs(jr_ctx *c, json_object *root, wall_config *w, placement *places)
{
    json_object *all;
    if (!jr_require_member(c, root, "outputs") || !jr_get_member(root, "outputs", &all))
        return false;
    size_t outer = jr_field_key(c, "outputs");
    bool ok = jr_expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    if (ok && n == 0)
        ok = jr_field_fail(c, "needs at least 1 output");
    if (ok && n > WALL_MAX_OUTPUTS)
        ok = jr_field_fail(c, "has %zu outputs, at most %d are supported (WALL_MAX_OUTPUTS)", n, WALL_MAX_OUTPUTS);
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = jr_field_index(c, i);
        ok = read_output(c, json_object_array_get_idx(all, i), &w->outputs[i], &places[i]);
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    w->count = ok ? (int)n : 0;
    return ok;
}

/* ---- the wall: placing, normalising, checking ---------------------------------- */

static bool same_tile(const wall_output *a, const wall_output *b)
{
    return a->width_mm == b->width_mm && a->height_mm == b->height_mm && a->bezel_left_mm == b->bezel_left_mm &&
           a->bezel_top_mm == b->bezel_top_mm && a->bezel_right_mm == b->bezel_right_mm &&
           a->bezel_bottom_mm == b->bezel_bottom_mm;
}

/* Every grid output has the tile of the first grid output. */
static bool check_grid(jr_ctx *c, const wall_config *w, const placement *places)
{
    int first = -1;
    for (int i = 0; i < w->count; i++) {
        if (places[i].kind != PLACE_GRID)
            continue;
        if (first < 0) {
            first = i;
            continue;
        }
        if (same_tile(&w->outputs[first], &w->outputs[i]))
            continue;
        return output_fail(c, i, NULL, "grid placement needs every grid output to have the same size_mm and "
                           "bezel_mm as outputs[%d]; use position_mm", first);
    }
    return true;
}

/* The active area's top-left from the placement as written (before normalisation). */
static void place_output(wall_output *o, const placement *p)
{
    int w_px, h_px;
    switch (p->kind) {
    case PLACE_GRID: {
        double tile_w = o->bezel_left_mm + o->width_mm + o->bezel_right_mm;
        double tile_h = o->bezel_top_mm + o->height_mm + o->bezel_bottom_mm;
        o->x_mm = p->a * tile_w + o->bezel_left_mm;
        o->y_mm = p->b * tile_h + o->bezel_top_mm;
        return;
    }
    case PLACE_MM:
        o->x_mm = p->a;
        o->y_mm = p->b;
        return;
    case PLACE_PX: /* read_placement made sure the mode is explicit */
        mounted_px(o, o->mode_w_px, o->mode_h_px, &w_px, &h_px);
        o->x_mm = p->a * o->width_mm / w_px;
        o->y_mm = p->b * o->height_mm / h_px;
        return;
    }
}

/* An output's tile, active area plus bezels: [x0, x1) x [y0, y1) in wall mm. */
typedef struct tile_rect {
    double x0, y0, x1, y1;
} tile_rect;

static tile_rect tile_of(const wall_output *o)
{
    return (tile_rect){o->x_mm - o->bezel_left_mm, o->y_mm - o->bezel_top_mm,
                       o->x_mm + o->width_mm + o->bezel_right_mm, o->y_mm + o->height_mm + o->bezel_bottom_mm};
}

/* Shift everything so the bounding box of the tiles starts at (0, 0). */
static void normalise(wall_config *w)
{
    tile_rect box = tile_of(&w->outputs[0]);
    for (int i = 1; i < w->count; i++) {
        tile_rect t = tile_of(&w->outputs[i]);
        box = (tile_rect){fmin(box.x0, t.x0), fmin(box.y0, t.y0), fmax(box.x1, t.x1), fmax(box.y1, t.y1)};
    }
    for (int i = 0; i < w->count; i++) {
        w->outputs[i].x_mm -= box.x0;
        w->outputs[i].y_mm -= box.y0;
    }
    w->width_mm = box.x1 - box.x0;
    w->height_mm = box.y1 - box.y0;
}

static bool check_overlap_pair(jr_ctx *c, const wall_config *w, int i, int j)
{
    tile_rect a = tile_of(&w->outputs[i]), b = tile_of(&w->outputs[j]);
    double ox = fmin(a.x1, b.x1) - fmax(a.x0, b.x0), oy = fmin(a.y1, b.y1) - fmax(a.y0, b.y0);
    if (ox <= WALL_OVERLAP_TOLERANCE_MM || oy <= WALL_OVERLAP_TOLERANCE_MM)
        return true;
    return output_fail(c, j, NULL, "its tile (active area + bezels, x %g..%g, y %g..%g mm) overlaps that of "
                       "outputs[%d] (x %g..%g, y %g..%g mm) by %g x %g mm",
                       b.x0, b.x1, b.y0, b.y1, i, a.x0, a.x1, a.y0, a.y1, ox, oy);
}

static bool check_overlaps(jr_ctx *c, const wall_config *w)
{
    for (int j = 1; j < w->count; j++)
        for (int i = 0; i < j; i++)
            if (!check_overlap_pair(c, w, i, j))
                return false;
    return true;
}

static bool same_edid(const wall_edid *a, const wall_edid *b)
{
    return a->given && b->given && strcmp(a->manufacturer, b->manufacturer) == 0 &&
           strcmp(a->model, b->model) == 0 && strcmp(a->serial, b->serial) == 0;
}

/* "manufacturer DEL, model U2415, serial ABC123" with only the given fields. */
static const char *describe_edid(char *buf, size_t size, const char *manufacturer, const char *model,
                                 const char *serial)
{
    const char *names[] = {"manufacturer", "model", "serial"}, *values[] = {manufacturer, model, serial};
    size_t used = 0;
    buf[0] = '\0';
    for (int k = 0; k < 3 && used < size; k++)
        if (values[k] && values[k][0])
            used += (size_t)snprintf(buf + used, size - used, "%s%s %s", used ? ", " : "", names[k], values[k]);
    if (!buf[0])
        snprintf(buf, size, "no EDID");
    return buf;
}

/* One monitor, one output: EDID identities are unique, and so are connector
 * names on one machine. With `per_node` (the file has "nodes": each machine
 * has its own DP-1) read_nodes checks the names node by node instead. */
static bool check_duplicates(jr_ctx *c, const wall_config *w, bool per_node)
{
    char who[3 * WALL_EDID_TEXT_BYTES + 40];
    for (int j = 1; j < w->count; j++) {
        const wall_output *b = &w->outputs[j];
        for (int i = 0; i < j; i++) {
            const wall_output *a = &w->outputs[i];
            if (!per_node && strcmp(a->connector, b->connector) == 0)
                return output_fail(c, j, "connector", "'%s' is also the connector of outputs[%d]", b->connector, i);
            if (same_edid(&a->edid, &b->edid))
                return output_fail(c, j, "edid", "the same monitor identity as outputs[%d] (%s); one monitor "
                                   "cannot be two outputs", i,
                                   describe_edid(who, sizeof who, b->edid.manufacturer, b->edid.model,
                                                 b->edid.serial));
        }
    }
    return true;
}

/* The output a node's list names (the current field): a connector name that
 * only one output has, or an index into "outputs". -1 with the error. */
static int find_node_output(jr_ctx *c, const wall_config *w, json_object *entry)
{
    if (json_object_is_type(entry, json_type_int)) {
        int64_t k = json_object_get_int64(entry);
        if (k < 0 || k >= w->count)
            return jr_field_fail(c, "output index %lld: the wall's outputs are 0..%d", (long long)k, w->count - 1),
                   -1;
        return (int)k;
    }
    if (!json_object_is_type(entry, json_type_string))
        return jr_field_fail(c, "expected a connector name or an output index, got %s", jr_kind(entry)), -1;
    const char *name = json_object_get_string(entry);
    int found = -1;
    for (int k = 0; k < w->count; k++) {
        if (strcmp(w->outputs[k].connector, name) != 0)
            continue;
        if (found >= 0)
            return jr_field_fail(c, "'%s' is the connector of outputs[%d] and outputs[%d]: name each by its index",
                                 name, found, k),
                   -1;
        found = k;
    }
    if (found < 0)
        jr_field_fail(c, "'%s' is not one of the wall's outputs", name);
    return found;
}

/* nodes[i] (the current field). */
static bool read_node(jr_ctx *c, json_object *v, wall_config *w, wall_node *n, bool *taken)
{
    static const char *const fields[] = {"rank", "host", "outputs", NULL};
    *n = (wall_node){.rank = -1};
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields))
        return false;
    double rank = -1.0;
    const char *host = NULL;
    if (!jr_opt_double(c, v, "rank", (jr_range){0.0, WALL_MAX_OUTPUTS - 1, false, false}, &rank) ||
        !jr_opt_string(c, v, "host", &host))
        return false;
    bool has_rank = jr_get_member(v, "rank", NULL);
    if (has_rank == (host != NULL))
        return jr_field_fail(c, "give exactly one of rank and host");
    if (has_rank && rank != floor(rank))
        return jr_member_fail(c, "rank", "must be a whole number");
    if (host && strlen(host) >= WALL_HOST_BYTES)
        return jr_member_fail(c, "host", "longer than 63 characters");
    n->rank = has_rank ? (int)rank : -1;
    if (host)
        snprintf(n->host, sizeof n->host, "%s", host);
    json_object *list;
    if (!jr_require_member(c, v, "outputs") || !jr_get_member(v, "outputs", &list))
        return false;
    size_t saved = jr_field_key(c, "outputs");
    bool ok = jr_expect_array(c, list);
    size_t count = ok ? json_object_array_length(list) : 0;
    if (ok && count == 0)
        ok = jr_field_fail(c, "a node drives at least 1 output");
    for (size_t i = 0; ok && i < count; i++) {
        size_t inner = jr_field_index(c, i);
        int found = find_node_output(c, w, json_object_array_get_idx(list, i));
        ok = found >= 0;
        if (ok && taken[found])
            ok = jr_field_fail(c, "output %d (%s) is driven by another node already", found,
                               w->outputs[found].connector);
        for (int k = 0; ok && k < w->count; k++) /* one machine has one connector of a name */
            if (n->outputs[k] && !strcmp(w->outputs[k].connector, w->outputs[found].connector))
                ok = jr_field_fail(c, "outputs[%d] and outputs[%d] are both connector '%s' of this node", k, found,
                                   w->outputs[k].connector);
        if (ok)
            taken[found] = n->outputs[found] = true;
        jr_field_leave(c, inner);
    }
    jr_field_leave(c, saved);
    return ok;
}

static bool read_nodes(jr_ctx *c, json_object *root, wall_config *w)
{
    json_object *all;
    if (!jr_get_member(root, "nodes", &all))
        return true;
    size_t outer = jr_field_key(c, "nodes");
    bool ok = jr_expect_array(c, all), taken[WALL_MAX_OUTPUTS] = {false};
    size_t n = ok ? json_object_array_length(all) : 0;
    if (ok && (n == 0 || n > (size_t)w->count))
        ok = jr_field_fail(c, "has %zu nodes: 1..%d (a node drives at least one output)", n, w->count);
    bool by_rank = false, by_host = false;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = jr_field_index(c, i);
        ok = read_node(c, json_object_array_get_idx(all, i), w, &w->nodes[i], taken);
        if (ok) {
            by_rank = by_rank || w->nodes[i].rank >= 0;
            by_host = by_host || w->nodes[i].rank < 0;
        }
        for (size_t k = 0; ok && k < i; k++)
            if (w->nodes[i].rank >= 0 && w->nodes[k].rank == w->nodes[i].rank)
                ok = jr_field_fail(c, "rank %d is nodes[%zu]'s already", w->nodes[i].rank, k);
        if (ok && w->nodes[i].rank >= (int)n)
            ok = jr_field_fail(c, "rank %d: with %zu nodes the ranks are 0..%zu", w->nodes[i].rank, n, n - 1);
        jr_field_leave(c, saved);
    }
    if (ok && by_rank && by_host)
        ok = jr_field_fail(c, "name every node by rank or every node by host, not some of each");
    for (int k = 0; ok && k < w->count; k++)
        if (!taken[k])
            ok = jr_field_fail(c, "output '%s' (outputs[%d]) is in no node", w->outputs[k].connector, k);
    jr_field_leave(c, outer);
    w->node_count = ok ? (int)n : 0;
    return ok;
}

int wall_config_node_of(const wall_config *w, int rank, int size, const char *const *hosts, tess_error *err)
{
    if (w->node_count != size) {
        tess_error_set(err, "the wall has %d nodes and %d processes were started (mpirun -np %d)", w->node_count,
                       size, w->node_count);
        return -1;
    }
    for (int i = 0; i < w->node_count; i++)
        if (w->nodes[i].rank == rank)
            return i;
    int before = 0; /* lower ranks on this host */
    for (int r = 0; r < rank; r++)
        before += strcmp(hosts[r], hosts[rank]) == 0;
    for (int i = 0; i < w->node_count; i++)
        if (w->nodes[i].rank < 0 && !strcmp(w->nodes[i].host, hosts[rank]) && before-- == 0)
            return i;
    tess_error_set(err, "no node of the wall is rank %d or (the next one) on host '%s'", rank, hosts[rank]);
    return -1;
}

static bool read_wall(jr_ctx *c, json_object *root, wall_config *w)
{
    static const char *const fields[] = {"format", "version", "units", "outputs", "nodes", NULL};
    placement places[WALL_MAX_OUTPUTS];
    if (!json_object_is_type(root, json_type_object))
        return tess_error_set(c->err, "%s: expected a JSON object at the top level, got %s", c->path,
                              jr_kind(root));
    if (!jr_check_format(c, root, format_name, "a wall file") || !jr_check_fields(c, root, fields) ||
        !jr_check_version(c, root, format_version) ||
        !read_units(c, root) || !read_outputs(c, root, w, places) || !check_grid(c, w, places))
        return false;
    for (int i = 0; i < w->count; i++)
        place_output(&w->outputs[i], &places[i]);
    normalise(w);
    return check_duplicates(c, w, jr_get_member(root, "nodes", NULL)) && check_overlaps(c, w) &&
           read_nodes(c, root, w);
}

bool wall_config_parse(const char *name, const char *text, size_t len, wall_config *out, tess_error *err)
{
    *out = (wall_config){0};
    json_object *root = NULL;
    jr_ctx ctx = {.path = name, .err = err};
    bool ok = jr_parse(name, text, len, &root, err) && read_wall(&ctx, root, out);
    json_object_put(root);
    if (!ok)
        *out = (wall_config){0};
    return ok;
}

bool wall_config_load(const char *file, wall_config *out, tess_error *err)
{
    *out = (wall_config){0};
    size_t len = 0;
    char *text = jr_read_file(file, WALL_FILE_MAX_BYTES, "a wall file", &len, err);
    if (!text)
        return false;
    bool ok = wall_config_parse(file, text, len, out, err);
    free(text);
    return ok;
}

/* ---- resolving pixel sizes against a device ---------------------------------- */

/* A field the file gave must equal the monitor's; an absent one matches anything. */
static bool edid_field_matches(const char *want, const char *have)
{
    return !want[0] || (have && strcmp(want, have) == 0);
}

static bool edid_matches(const wall_edid *e, const wall_device_connector *d)
{
    return d->connected && edid_field_matches(e->manufacturer, d->edid_manufacturer) &&
           edid_field_matches(e->model, d->edid_model) && edid_field_matches(e->serial, d->edid_serial);
}

static const char *connector_name(const wall_device_connector *d) { return d->name ? d->name : "?"; }

/* "HDMI-A-1 (manufacturer DEL, model U2415)" or "DP-1 (not connected)" per connector. */
static void list_monitors(text_list *l, const wall_device_connector *conns, size_t n)
{
    char edid[3 * WALL_EDID_TEXT_BYTES + 40], item[sizeof edid + WALL_CONNECTOR_BYTES + 8];
    for (size_t k = 0; k < n; k++) {
        const wall_device_connector *d = &conns[k];
        if (d->connected)
            describe_edid(edid, sizeof edid, d->edid_manufacturer, d->edid_model, d->edid_serial);
        snprintf(item, sizeof item, "%.31s (%s)", connector_name(d), d->connected ? edid : "not connected");
        list_add(l, item);
    }
}

/* The connected connector whose EDID has every field the file gave; -1 with err. */
static int find_by_edid(const wall_output *o, int i, const wall_device_connector *conns, size_t n, tess_error *err)
{
    char want[3 * WALL_EDID_TEXT_BYTES + 40];
    text_list matches = {0}, card = {0};
    int found = -1, count = 0;
    for (size_t k = 0; k < n; k++)
        if (edid_matches(&o->edid, &conns[k])) {
            found = count++ ? found : (int)k;
            list_add(&matches, connector_name(&conns[k]));
        }
    describe_edid(want, sizeof want, o->edid.manufacturer, o->edid.model, o->edid.serial);
    if (count == 1)
        return found;
    if (count > 1) {
        tess_error_set(err, "outputs[%d]: EDID %s matches %d connected monitors (%s); give more of "
                            "manufacturer, model and serial", i, want, count, matches.text);
        return -1;
    }
    list_monitors(&card, conns, n);
    tess_error_set(err, "outputs[%d]: no connected monitor has EDID %s (the card has: %s)", i, want,
                   n ? card.text : "no connectors");
    return -1;
}

/* The connector named as in the file, which must be connected; -1 with err. */
static int find_by_name(const wall_output *o, int i, const wall_device_connector *conns, size_t n, tess_error *err)
{
    text_list card = {0};
    for (size_t k = 0; k < n; k++) {
        if (!conns[k].name || strcmp(conns[k].name, o->connector) != 0)
            continue;
        if (conns[k].connected)
            return (int)k;
        tess_error_set(err, "outputs[%d]: connector '%s' has no monitor connected", i, o->connector);
        return -1;
    }
    for (size_t k = 0; k < n; k++)
        list_add(&card, connector_name(&conns[k]));
    tess_error_set(err, "outputs[%d]: connector '%s' not found (the card has: %s)", i, o->connector,
                   n ? card.text : "no connectors");
    return -1;
}

/* The largest mode (area, then refresh); -1 when there are none. */
static int largest_mode(const wall_device_connector *d)
{
    int best = -1;
    for (size_t k = 0; k < d->mode_count; k++) {
        const wall_device_mode *m = &d->modes[k], *b = best >= 0 ? &d->modes[best] : NULL;
        double area = (double)m->width_px * m->height_px, best_area = b ? (double)b->width_px * b->height_px : -1;
        if (area > best_area || (area == best_area && m->refresh_hz > b->refresh_hz))
            best = (int)k;
    }
    return best;
}

/* The mode of d that fits the explicit mode of o, -1 if none (see the header). */
static int explicit_mode(const wall_output *o, const wall_device_connector *d)
{
    int best = -1;
    for (size_t k = 0; k < d->mode_count; k++) {
        const wall_device_mode *m = &d->modes[k];
        double off = fabs(m->refresh_hz - o->mode_hz);
        if (m->width_px != o->mode_w_px || m->height_px != o->mode_h_px ||
            (o->mode_hz > 0.0 && off > WALL_REFRESH_TOLERANCE_HZ))
            continue;
        if (best < 0 || (o->mode_hz > 0.0 && off < fabs(d->modes[best].refresh_hz - o->mode_hz)) ||
            (o->mode_hz <= 0.0 && best != d->preferred &&
             ((int)k == d->preferred || m->refresh_hz > d->modes[best].refresh_hz)))
            best = (int)k;
    }
    return best;
}

/* Each distinct mode of d once, as "WxH@HZ". */
static void list_modes(text_list *l, const wall_device_connector *d)
{
    char text[MODE_TEXT_BYTES], earlier[MODE_TEXT_BYTES];
    for (size_t k = 0; k < d->mode_count; k++) {
        const wall_device_mode *m = &d->modes[k];
        format_mode(text, sizeof text, m->width_px, m->height_px, m->refresh_hz);
        bool seen = false;
        for (size_t j = 0; j < k && !seen; j++)
            seen = strcmp(text, format_mode(earlier, sizeof earlier, d->modes[j].width_px, d->modes[j].height_px,
                                            d->modes[j].refresh_hz)) == 0;
        if (!seen)
            list_add(l, text);
    }
}

/* The mode index for output i on connector d; -1 with err. */
static int resolve_mode(const wall_output *o, int i, const wall_device_connector *d, tess_error *err)
{
    char want[MODE_TEXT_BYTES];
    text_list offered = {0};
    if (o->mode_preferred) {
        bool marked = d->preferred >= 0 && (size_t)d->preferred < d->mode_count;
        bool user = d->user_defined >= 0 && (size_t)d->user_defined < d->mode_count;
        int k = marked ? d->preferred : user ? d->user_defined : largest_mode(d);
        if (k < 0)
            tess_error_set(err, "outputs[%d]: %s offers no modes", i, connector_name(d));
        return k;
    }
    int k = explicit_mode(o, d);
    if (k >= 0)
        return k;
    list_modes(&offered, d);
    tess_error_set(err, "outputs[%d]: mode %s not offered by %s (it offers: %s)", i,
                   format_mode(want, sizeof want, o->mode_w_px, o->mode_h_px, o->mode_hz), connector_name(d),
                   d->mode_count ? offered.text : "no modes");
    return -1;
}

/* A mode the device chose ("preferred") must still fit the physical aspect. */
static bool check_device_aspect(const wall_output *o, int i, const wall_device_mode *m, const char *name,
                                tess_error *err)
{
    int w, h;
    double mm_aspect, px_aspect;
    char mode[MODE_TEXT_BYTES];
    mounted_px(o, m->width_px, m->height_px, &w, &h);
    if (!o->mode_preferred || aspect_agrees(o, w, h, &mm_aspect, &px_aspect))
        return true;
    return tess_error_set(err, "outputs[%d]: the preferred mode of %s, %s rotated %d (%d x %d px, aspect %.4f), "
                               "does not fit size_mm %g x %g (aspect %.4f) within %g%%; give an explicit mode",
                          i, name, format_mode(mode, sizeof mode, m->width_px, m->height_px, m->refresh_hz),
                          o->rotation_deg, w, h, px_aspect, o->width_mm, o->height_mm, mm_aspect,
                          WALL_ASPECT_TOLERANCE * 100.0);
}

/* Connector and mode for output i into *conn, *mode; false with err. */
static bool match_output(const wall_config *w, int i, const int *taken, const wall_device_connector *conns,
                         size_t n, int *conn, int *mode, tess_error *err)
{
    const wall_output *o = &w->outputs[i];
    *conn = o->edid.given ? find_by_edid(o, i, conns, n, err) : find_by_name(o, i, conns, n, err);
    if (*conn < 0)
        return false;
    for (int j = 0; j < i; j++)
        if (taken[j] == *conn)
            return tess_error_set(err, "outputs[%d] and outputs[%d] both resolve to connector %s", j, i,
                                  connector_name(&conns[*conn]));
    *mode = resolve_mode(o, i, &conns[*conn], err);
    return *mode >= 0 && check_device_aspect(o, i, &conns[*conn].modes[*mode], connector_name(&conns[*conn]), err);
}

bool wall_config_match_device(wall_config *w, const wall_device_connector *conns, size_t n, tess_error *err)
{
    int conn[WALL_MAX_OUTPUTS], mode[WALL_MAX_OUTPUTS];
    for (int i = 0; i < w->count; i++) {
        wall_output *o = &w->outputs[i];
        o->device_connector = o->device_mode = -1;
        o->width_px = o->height_px = 0;
    }
    for (int i = 0; i < w->count; i++)
        if (!match_output(w, i, conn, conns, n, &conn[i], &mode[i], err))
            return false;
    for (int i = 0; i < w->count; i++) {
        wall_output *o = &w->outputs[i];
        const wall_device_mode *m = &conns[conn[i]].modes[mode[i]];
        o->device_connector = conn[i];
        o->device_mode = mode[i];
        mounted_px(o, m->width_px, m->height_px, &o->width_px, &o->height_px);
    }
    return true;
}

/* ---- hotplug ------------------------------------------------------------------ */

static void plan_output(const wall_config *w, int i, const bool *live, const int *driving,
                        const wall_device_connector *conns, size_t n, const wall_hotplug_step *steps,
                        wall_hotplug_step *step)
{
    const wall_output *o = &w->outputs[i];
    int conn = -1, mode = -1;
    tess_error why = {{0}};
    int taken[WALL_MAX_OUTPUTS]; /* match_output's duplicate check is done here, against the live outputs */
    for (int j = 0; j < i; j++)
        taken[j] = -1;
    bool matched = match_output(w, i, taken, conns, n, &conn, &mode, &why);
    *step = (wall_hotplug_step){WALL_HOTPLUG_KEEP, -1, -1, {{0}}};
    if (live[i]) {
        if (!matched) {
            step->action = WALL_HOTPLUG_GONE;
            step->reason = why;
        } else if (conn != driving[i]) {
            step->action = WALL_HOTPLUG_GONE;
            tess_error_set(&step->reason, "outputs[%d]: its monitor is now on %s", i, connector_name(&conns[conn]));
        }
        return;
    }
    if (!matched) {
        step->reason = why;
        return;
    }
    for (int j = 0; j < w->count; j++) {
        bool keeps = j != i && live[j] && driving[j] == conn && steps[j].action != WALL_HOTPLUG_GONE;
        bool returns = j < i && steps[j].action == WALL_HOTPLUG_BACK && steps[j].connector == conn;
        if (keeps || returns) {
            tess_error_set(&step->reason, "outputs[%d]: connector %s is driven by outputs[%d]", i,
                           connector_name(&conns[conn]), j);
            return;
        }
    }
    int w_px, h_px;
    const wall_device_mode *m = &conns[conn].modes[mode];
    mounted_px(o, m->width_px, m->height_px, &w_px, &h_px);
    if (w_px != o->width_px || h_px != o->height_px) {
        char text[MODE_TEXT_BYTES];
        tess_error_set(&step->reason, "outputs[%d]: %s is back with mode %s (%d x %d px as mounted), but the wall "
                                      "started at %d x %d px; restart tessera to use it",
                       i, connector_name(&conns[conn]), format_mode(text, sizeof text, m->width_px, m->height_px,
                                                                   m->refresh_hz),
                       w_px, h_px, o->width_px, o->height_px);
        return;
    }
    step->action = WALL_HOTPLUG_BACK;
    step->connector = conn;
    step->mode = mode;
}

void wall_hotplug_plan(const wall_config *w, const bool *live, const int *driving, const wall_device_connector *conns,
                       size_t n, wall_hotplug_step *steps)
{
    /* live outputs first, so a dark one never takes a connector a live one keeps */
    for (int i = 0; i < w->count; i++)
        if (live[i])
            plan_output(w, i, live, driving, conns, n, steps, &steps[i]);
    for (int i = 0; i < w->count; i++)
        if (!live[i])
            plan_output(w, i, live, driving, conns, n, steps, &steps[i]);
}

/* ---- headless runs ---------------------------------------------------------- */

const char *wall_output_label(const wall_config *w, int i, char *buf, size_t bytes)
{
    const char *name = w->outputs[i].connector;
    bool shared = false;
    for (int k = 0; k < w->count && !shared; k++)
        shared = k != i && !strcmp(w->outputs[k].connector, name);
    int node = -1;
    for (int k = 0; shared && k < w->node_count && node < 0; k++)
        node = w->nodes[k].outputs[i] ? k : -1;
    if (node >= 0)
        snprintf(buf, bytes, "node%d-%s", node, name);
    else
        snprintf(buf, bytes, "%s", name);
    return buf;
}

int wall_config_subset(const wall_config *w, const bool *mask, wall_config *out, int *index_of)
{
    *out = *w;
    out->count = 0;
    out->node_count = 0;
    for (int i = 0; i < w->count; i++)
        if (mask[i]) {
            index_of[out->count] = i;
            out->outputs[out->count++] = w->outputs[i];
        }
    return out->count;
}

bool wall_config_headless_sizes(wall_config *w, tess_error *err)
{
    for (int i = 0; i < w->count; i++)
        if (w->outputs[i].mode_preferred)
            return tess_error_set(err, "outputs[%d] (%s): mode 'preferred' needs a device; give an explicit mode "
                                       "such as 1920x1080 for headless runs", i, w->outputs[i].connector);
    for (int i = 0; i < w->count; i++) {
        wall_output *o = &w->outputs[i];
        mounted_px(o, o->mode_w_px, o->mode_h_px, &o->width_px, &o->height_px);
    }
    return true;
}
