/* txn_text.c - the text form of records (txn.h: txn_encode_text,
 * txn_decode_text): what recordings and the control channels carry. */
#include "txn.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct out_buf {
    char *p;
    size_t size, len;
    bool overflow;
} out_buf;

static void put(out_buf *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(out_buf *o, const char *fmt, ...)
{
    if (o->overflow)
        return;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(o->p + o->len, o->size - o->len, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= o->size - o->len)
        o->overflow = true;
    else
        o->len += (size_t)n;
}

static void put_quoted(out_buf *o, const char *text)
{
    put(o, " \"");
    for (const unsigned char *s = (const unsigned char *)text; *s; s++) {
        if (*s == '"' || *s == '\\')
            put(o, "\\%c", *s);
        else if (*s < 32 || *s > 126)
            put(o, "\\x%02x", *s);
        else
            put(o, "%c", *s);
    }
    put(o, "\"");
}

static void put_geoms(out_buf *o, const txn_geoms *g) { put(o, " %u %u", g->first, g->count); }

size_t txn_encode_text(const txn_record *r, char *buf, size_t size)
{
    if (size == 0)
        return 0;
    buf[0] = '\0';
    tess_error err = {{0}};
    if (!txn_validate(r, &err))
        return 0;
    out_buf o = {buf, size, 0, false};
    put(&o, "%s", txn_kind_name(r->kind));
    switch (r->kind) {
    case TXN_CAMERA: {
        const camera_desc *c = &r->args.camera.camera;
        if (r->args.camera.channel == TXN_ALL_CHANNELS)
            put(&o, " all");
        else
            put(&o, " %d", (int)r->args.camera.channel);
        put(&o, " %a %a %a %a %a %a %a %a %a %a", (double)c->eye.x, (double)c->eye.y, (double)c->eye.z,
            (double)c->look_at.x, (double)c->look_at.y, (double)c->look_at.z, (double)c->up.x, (double)c->up.y,
            (double)c->up.z, (double)c->fov_deg);
        break;
    }
    case TXN_CURSOR:
        put(&o, " %d %a %a", r->args.cursor.on ? 1 : 0, (double)r->args.cursor.sx, (double)r->args.cursor.sy);
        break;
    case TXN_POINTER:
        put(&o, " %d %d %a %a", (int)r->args.pointer.slot, r->args.pointer.on ? 1 : 0, (double)r->args.pointer.sx,
            (double)r->args.pointer.sy);
        break;
    case TXN_STATUS:
        put_quoted(&o, r->args.status.text);
        break;
    case TXN_GOVERNOR_STATUS:
    case TXN_SHADOWS:
    case TXN_TOUR:
        put(&o, " %d", r->args.flag.on ? 1 : 0);
        break;
    case TXN_HIDE:
    case TXN_SHOW:
    case TXN_ISOLATE:
        put_geoms(&o, &r->args.geoms);
        break;
    case TXN_HIGHLIGHT:
        put_geoms(&o, &r->args.highlight.geoms);
        put(&o, " %d", r->args.highlight.on ? 1 : 0);
        break;
    case TXN_COLOUR:
        put_geoms(&o, &r->args.colour.geoms);
        if (r->args.colour.reset)
            put(&o, " reset");
        else
            put(&o, " %a %a %a", (double)r->args.colour.rgb[0], (double)r->args.colour.rgb[1],
                (double)r->args.colour.rgb[2]);
        break;
    case TXN_RENDERER:
        put(&o, " %s", r->args.renderer.name);
        break;
    case TXN_THREADS:
        put(&o, " %d", (int)r->args.threads.count);
        break;
    case TXN_CHANNEL_ACTIVE:
        put(&o, " %d %d", (int)r->args.channel.channel, r->args.channel.on ? 1 : 0);
        break;
    case TXN_MOVE:
        put_geoms(&o, &r->args.move.geoms);
        for (int i = 0; i < 12; i++)
            put(&o, " %a", (double)r->args.move.m[i]);
        break;
    case TXN_OPACITY:
        if (r->args.opacity.all)
            put(&o, " all");
        else
            put_geoms(&o, &r->args.opacity.geoms);
        put(&o, " %a", (double)r->args.opacity.a);
        break;
    case TXN_CLIP_PLANE: {
        const float *p = r->args.clip_plane.point, *n = r->args.clip_plane.normal;
        put(&o, " %d %d %a %a %a %a %a %a", (int)r->args.clip_plane.index, r->args.clip_plane.on ? 1 : 0,
            (double)p[0], (double)p[1], (double)p[2], (double)n[0], (double)n[1], (double)n[2]);
        break;
    }
    case TXN_CROP:
        put_geoms(&o, &r->args.crop.geoms);
        put(&o, " %d %a %a", r->args.crop.on ? 1 : 0, (double)r->args.crop.lo, (double)r->args.crop.hi);
        break;
    case TXN_TIME_STEP:
        put(&o, " %u", (unsigned)r->args.time_step.step);
        break;
    case TXN_VALUE:
        put_geoms(&o, &r->args.value.geoms);
        put(&o, " %a", (double)r->args.value.v);
        break;
    case TXN_COLORMAP:
        put_geoms(&o, &r->args.colormap.geoms);
        put(&o, " %s", r->args.colormap.name);
        break;
    case TXN_TRANSFER:
        put(&o, " %s", r->args.renderer.name);
        break;
    case TXN_SHOW_ALL:
    case TXN_QUIT:
    case TXN_KIND_COUNT:
        break;
    }
    if (o.overflow) {
        buf[0] = '\0';
        return 0;
    }
    return o.len;
}

typedef struct reader {
    const char *p, *end;
    tess_error *err;
} reader;

static void skip_spaces(reader *r)
{
    while (r->p < r->end && (*r->p == ' ' || *r->p == '\t'))
        r->p++;
}

/* A word for an error message: control characters as '?', so it stays one line. */
static void printable(char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s < 32 || (unsigned char)*s == 127)
            *s = '?';
}

/* The next space-separated word into buf. */
static bool word(reader *r, char *buf, size_t size, const char *what)
{
    skip_spaces(r);
    size_t n = 0;
    while (r->p < r->end && *r->p != ' ' && *r->p != '\t') {
        if (n + 1 >= size)
            return tess_error_set(r->err, "%s is too long", what);
        buf[n++] = *r->p++;
    }
    buf[n] = '\0';
    if (n == 0)
        return tess_error_set(r->err, "%s is missing", what);
    return true;
}

static bool number(reader *r, double *out, const char *what)
{
    char buf[64];
    if (!word(r, buf, sizeof buf, what))
        return false;
    char *endp;
    errno = 0;
    double v = strtod(buf, &endp);
    if (*endp != '\0' || !isfinite(v) || errno == ERANGE) {
        printable(buf);
        return tess_error_set(r->err, "%s: expected a finite number, got '%s'", what, buf);
    }
    *out = v;
    return true;
}

static bool float_value(reader *r, float *out, const char *what)
{
    double v;
    if (!number(r, &v, what))
        return false;
    if ((double)(float)v != v)
        return tess_error_set(r->err, "%s: %.17g is not exactly a float (the file is written with %%a)", what, v);
    *out = (float)v;
    return true;
}

/* A whole number in [lo, hi]; `range_msg` says what is wanted. */
static bool whole(reader *r, double lo, double hi, double *out, const char *what, const char *range_msg)
{
    if (!number(r, out, what))
        return false;
    if (*out < lo || *out > hi || *out != floor(*out))
        return tess_error_set(r->err, "%s", range_msg);
    return true;
}

static bool flag(reader *r, bool *out, const char *what)
{
    char buf[8];
    if (!word(r, buf, sizeof buf, what))
        return false;
    if (strcmp(buf, "0") && strcmp(buf, "1")) {
        printable(buf);
        return tess_error_set(r->err, "%s: expected 0 or 1, got '%s'", what, buf);
    }
    *out = buf[0] == '1';
    return true;
}

static bool quoted(reader *r, char *out, size_t size)
{
    skip_spaces(r);
    if (r->p >= r->end || *r->p != '"')
        return tess_error_set(r->err, "status: expected a quoted text");
    r->p++;
    size_t n = 0;
    for (;;) {
        if (r->p >= r->end)
            return tess_error_set(r->err, "status: the text has no closing quote");
        unsigned char ch = (unsigned char)*r->p++;
        if (ch == '"')
            break;
        if (ch == '\\') {
            if (r->p >= r->end)
                return tess_error_set(r->err, "status: the text ends inside an escape");
            char e = *r->p++;
            if (e == 'x') {
                if (r->end - r->p < 2 || !isxdigit((unsigned char)r->p[0]) || !isxdigit((unsigned char)r->p[1]))
                    return tess_error_set(r->err, "status: \\x needs two hex digits");
                char hex[3] = {r->p[0], r->p[1], 0};
                ch = (unsigned char)strtol(hex, NULL, 16);
                r->p += 2;
            } else if (e == '"' || e == '\\') {
                ch = (unsigned char)e;
            } else {
                return tess_error_set(r->err, "status: unknown escape (expected \\\", \\\\ or \\xHH)");
            }
        }
        /* a NUL (raw or \x00) would end the text early: what follows could
         * never be written back, so a replay would not be the recording */
        if (ch == '\0')
            return tess_error_set(r->err, "status: the text holds a NUL byte");
        if (n + 1 >= size)
            return tess_error_set(r->err, "status: the text is longer than %zu bytes", size - 1);
        out[n++] = (char)ch;
    }
    out[n] = '\0';
    return true;
}

/* Whether the next word is `kw` (then it is consumed). */
static bool keyword(reader *r, const char *kw)
{
    skip_spaces(r);
    size_t n = strlen(kw);
    if ((size_t)(r->end - r->p) >= n && memcmp(r->p, kw, n) == 0 &&
        ((size_t)(r->end - r->p) == n || r->p[n] == ' ' || r->p[n] == '\t')) {
        r->p += n;
        return true;
    }
    return false;
}

static bool geoms_text(reader *r, const char *kind, txn_geoms *g)
{
    char what[48], msg[96];
    double first, count;
    snprintf(what, sizeof what, "%s instance id", kind);
    snprintf(msg, sizeof msg, "%s: the instance id must be a whole number >= 0", kind);
    if (!whole(r, 0.0, 4294967294.0, &first, what, msg))
        return false;
    snprintf(what, sizeof what, "%s count", kind);
    snprintf(msg, sizeof msg, "%s: the count must be a whole number >= 1", kind);
    if (!whole(r, 1.0, 4294967295.0, &count, what, msg))
        return false;
    *g = (txn_geoms){(uint32_t)first, (uint32_t)count};
    return true;
}

static bool camera_text(reader *r, camera_desc *c)
{
    float *v[10] = {&c->eye.x, &c->eye.y, &c->eye.z, &c->look_at.x, &c->look_at.y, &c->look_at.z,
                    &c->up.x,  &c->up.y,  &c->up.z,  &c->fov_deg};
    static const char *const names[10] = {"camera eye.x",     "camera eye.y",     "camera eye.z", "camera look_at.x",
                                          "camera look_at.y", "camera look_at.z", "camera up.x",  "camera up.y",
                                          "camera up.z",      "camera fov_deg"};
    for (int i = 0; i < 10; i++)
        if (!float_value(r, v[i], names[i]))
            return false;
    return true;
}

static bool decode_args(reader *r, txn_text_version version, txn_record *t)
{
    const char *name = txn_kind_name(t->kind);
    double v;
    switch (t->kind) {
    case TXN_CAMERA:
        t->args.camera.channel = TXN_ALL_CHANNELS;
        if (version != TXN_TEXT_V1) {
            char ch[16];
            if (!word(r, ch, sizeof ch, "camera channel"))
                return false;
            if (strcmp(ch, "all") != 0) {
                char *endp;
                long n = strtol(ch, &endp, 10);
                if (*endp || endp == ch || n < 0 || n >= TXN_MAX_CHANNELS) {
                    printable(ch);
                    return tess_error_set(r->err, "camera channel: expected all or 0..%d, got '%s'",
                                          TXN_MAX_CHANNELS - 1, ch);
                }
                t->args.camera.channel = (int32_t)n;
            }
        }
        return camera_text(r, &t->args.camera.camera);
    case TXN_CURSOR:
        return flag(r, &t->args.cursor.on, "cursor visibility") && float_value(r, &t->args.cursor.sx, "cursor x") &&
               float_value(r, &t->args.cursor.sy, "cursor y");
    case TXN_POINTER:
        if (!whole(r, 0.0, TXN_POINTERS - 1, &v, "pointer slot", "pointer: the slot must be a whole number in 0..7"))
            return false;
        t->args.pointer.slot = (int32_t)v;
        return flag(r, &t->args.pointer.on, "pointer visibility") && float_value(r, &t->args.pointer.sx, "pointer x") &&
               float_value(r, &t->args.pointer.sy, "pointer y");
    case TXN_STATUS:
        return quoted(r, t->args.status.text, sizeof t->args.status.text);
    case TXN_GOVERNOR_STATUS:
        return flag(r, &t->args.flag.on, "governor status on/off");
    case TXN_SHADOWS:
        return flag(r, &t->args.flag.on, "shadows on/off");
    case TXN_TOUR:
        return flag(r, &t->args.flag.on, "tour on/off");
    case TXN_HIDE:
        if (version == TXN_TEXT_V1) { /* one geometry */
            if (!whole(r, 0.0, 4294967294.0, &v, "hide instance id",
                       "hide: the instance id must be a whole number >= 0"))
                return false;
            t->args.geoms = (txn_geoms){(uint32_t)v, 1};
            return true;
        }
        return geoms_text(r, name, &t->args.geoms);
    case TXN_SHOW:
    case TXN_ISOLATE:
        return geoms_text(r, name, &t->args.geoms);
    case TXN_HIGHLIGHT:
        return geoms_text(r, name, &t->args.highlight.geoms) && flag(r, &t->args.highlight.on, "highlight on/off");
    case TXN_COLOUR: {
        if (!geoms_text(r, name, &t->args.colour.geoms))
            return false;
        if (keyword(r, "reset")) {
            t->args.colour.reset = true;
            return true;
        }
        return float_value(r, &t->args.colour.rgb[0], "colour r") &&
               float_value(r, &t->args.colour.rgb[1], "colour g") &&
               float_value(r, &t->args.colour.rgb[2], "colour b");
    }
    case TXN_RENDERER:
        return word(r, t->args.renderer.name, sizeof t->args.renderer.name, "renderer name");
    case TXN_THREADS:
        if (!whole(r, 1.0, TXN_MAX_THREADS, &v, "threads count", "threads: the count must be a whole number in 1..256"))
            return false;
        t->args.threads.count = (int32_t)v;
        return true;
    case TXN_CHANNEL_ACTIVE:
        if (!whole(r, 0.0, TXN_MAX_CHANNELS - 1, &v, "channel-active channel",
                   "channel-active: the channel must be a whole number in 0..15"))
            return false;
        t->args.channel.channel = (int32_t)v;
        return flag(r, &t->args.channel.on, "channel-active on/off");
    case TXN_MOVE:
        if (!geoms_text(r, name, &t->args.move.geoms))
            return false;
        for (int i = 0; i < 12; i++)
            if (!float_value(r, &t->args.move.m[i], "move matrix element"))
                return false;
        return true;
    case TXN_OPACITY:
        if (keyword(r, "all"))
            t->args.opacity.all = true;
        else if (!geoms_text(r, name, &t->args.opacity.geoms))
            return false;
        return float_value(r, &t->args.opacity.a, "opacity a");
    case TXN_CLIP_PLANE: {
        static const char *const point_names[3] = {"clip-plane point.x", "clip-plane point.y", "clip-plane point.z"},
                                 *const normal_names[3] = {"clip-plane normal.x", "clip-plane normal.y",
                                                           "clip-plane normal.z"};
        if (!whole(r, 0.0, TXN_CLIP_PLANES - 1, &v, "clip-plane index",
                   "clip-plane: the index must be a whole number in 0..7"))
            return false;
        t->args.clip_plane.index = (int32_t)v;
        if (!flag(r, &t->args.clip_plane.on, "clip-plane on/off"))
            return false;
        for (int i = 0; i < 3; i++)
            if (!float_value(r, &t->args.clip_plane.point[i], point_names[i]))
                return false;
        for (int i = 0; i < 3; i++)
            if (!float_value(r, &t->args.clip_plane.normal[i], normal_names[i]))
                return false;
        return true;
    }
    case TXN_CROP:
        return geoms_text(r, name, &t->args.crop.geoms) && flag(r, &t->args.crop.on, "crop on/off") &&
               float_value(r, &t->args.crop.lo, "crop lo") && float_value(r, &t->args.crop.hi, "crop hi");
    case TXN_TIME_STEP:
        if (!whole(r, 0.0, UINT32_MAX, &v, "time-step step", "time-step: the step must be a whole number in 0..4294967295"))
            return false;
        t->args.time_step.step = (uint32_t)v;
        return true;
    case TXN_VALUE:
        return geoms_text(r, name, &t->args.value.geoms) && float_value(r, &t->args.value.v, "value v");
    case TXN_COLORMAP:
        return geoms_text(r, name, &t->args.colormap.geoms) &&
               word(r, t->args.colormap.name, sizeof t->args.colormap.name, "colormap name");
    case TXN_TRANSFER:
        return word(r, t->args.renderer.name, sizeof t->args.renderer.name, "transfer name");
    case TXN_SHOW_ALL:
    case TXN_QUIT:
    case TXN_KIND_COUNT:
        break;
    }
    return true;
}

bool txn_decode_text(const char *text, size_t len, txn_text_version version, txn_record *out, tess_error *err)
{
    reader r = {text, text + len, err};
    char kind[24];
    if (!word(&r, kind, sizeof kind, "the transaction kind"))
        return false;
    txn_record t = txn_simple(TXN_QUIT);
    if (!txn_kind_from_name(kind, version, &t.kind)) {
        printable(kind);
        return tess_error_set(err, "unknown transaction kind '%s' (expected one of: %s)", kind,
                              version == TXN_TEXT_V1 ? "camera, cursor, status, hide, unhide-all, tour, quit, "
                                                       "governor-status"
                                                     : "camera, cursor, status, governor-status, hide, show, isolate, "
                                                       "show-all, highlight, colour, shadows, renderer, threads, "
                                                       "channel-active, move, opacity, clip-plane, tour, quit");
    }
    if (!decode_args(&r, version, &t))
        return false;
    skip_spaces(&r);
    if (r.p < r.end)
        return tess_error_set(err, "unexpected text after the transaction");
    if (!txn_validate(&t, err))
        return false;
    *out = t;
    return true;
}
