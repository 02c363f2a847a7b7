/* txn.c - transaction records (txn.h): kinds and their names, the
 * constructors, validation. Applying a record is txn_apply.c, its text form
 * txn_text.c, its binary form txn_binary.c. */
#include "txn.h"
#include "txn_private.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "engine/scene/frame_state.h"
#include "engine/render/render.h"

_Static_assert(sizeof(((txn_record *)0)->args.status.text) == TXN_TEXT_BYTES, "status text");
_Static_assert(TXN_MAX_CHANNELS == FRAME_STATE_MAX_CHANNELS && TXN_MAX_THREADS == FRAME_STATE_MAX_THREADS &&
                   TXN_TEXT_BYTES == FRAME_STATE_TEXT_BYTES && TXN_NAME_BYTES == FRAME_STATE_NAME_BYTES &&
                   TXN_POINTERS == FRAME_STATE_POINTERS,
               "a record's sizes are the frame state's");
_Static_assert(TXN_CLIP_PLANES == CLIP_MAX_PLANES, "a clip-plane record's index is a frame state's plane");

static const char *const kind_names[TXN_KIND_COUNT] = {
    [TXN_CAMERA] = "camera",         [TXN_CURSOR] = "cursor",
    [TXN_STATUS] = "status",         [TXN_HIDE] = "hide",
    [TXN_SHOW_ALL] = "show-all",     [TXN_TOUR] = "tour",
    [TXN_QUIT] = "quit",             [TXN_GOVERNOR_STATUS] = "governor-status",
    [TXN_SHOW] = "show",             [TXN_ISOLATE] = "isolate",
    [TXN_HIGHLIGHT] = "highlight",   [TXN_COLOUR] = "colour",
    [TXN_SHADOWS] = "shadows",       [TXN_RENDERER] = "renderer",
    [TXN_THREADS] = "threads",       [TXN_CHANNEL_ACTIVE] = "channel-active", [TXN_MOVE] = "move",
    [TXN_OPACITY] = "opacity",       [TXN_CLIP_PLANE] = "clip-plane",
    [TXN_CROP] = "crop",             [TXN_TIME_STEP] = "time-step",
    [TXN_VALUE] = "value",           [TXN_COLORMAP] = "colormap",
    [TXN_TRANSFER] = "transfer",     [TXN_POINTER] = "pointer",
};

const char *txn_kind_name(txn_kind k) { return (unsigned)k < TXN_KIND_COUNT ? kind_names[k] : "?"; }

bool txn_kind_from_name(const char *name, txn_text_version version, txn_kind *out)
{
    if (version == TXN_TEXT_V1) { /* the kinds of record format 1, by their names then */
        static const char *const v1[] = {"camera", "cursor", "status", "hide", "unhide-all", "tour", "quit",
                                          "governor-status"};
        for (int k = 0; k < 8; k++)
            if (strcmp(name, v1[k]) == 0) {
                *out = (txn_kind)k; /* the first eight kinds keep format 1's order */
                return true;
            }
        return false;
    }
    for (int k = 0; k < TXN_KIND_COUNT; k++)
        if (strcmp(name, kind_names[k]) == 0) {
            *out = (txn_kind)k;
            return true;
        }
    return false;
}

bool txn_kind_input_level(txn_kind k) { return k == TXN_TOUR || k == TXN_QUIT; }

/* ---- builders ---------------------------------------------------------------------- */

static txn_record blank(txn_kind kind)
{
    txn_record r;
    memset(&r, 0, sizeof r); /* padding too: records compare byte for byte */
    r.kind = kind;
    return r;
}

txn_record txn_camera(int channel, const camera_desc *c)
{
    txn_record r = blank(TXN_CAMERA);
    r.args.camera.channel = channel;
    r.args.camera.camera = *c;
    return r;
}

txn_record txn_pointer(int slot, bool on, float sx, float sy)
{
    txn_record r = blank(TXN_POINTER);
    r.args.pointer.slot = slot;
    r.args.pointer.on = on;
    r.args.pointer.sx = sx;
    r.args.pointer.sy = sy;
    return r;
}

txn_record txn_cursor(bool on, float sx, float sy)
{
    txn_record r = blank(TXN_CURSOR);
    r.args.cursor.on = on;
    r.args.cursor.sx = sx;
    r.args.cursor.sy = sy;
    return r;
}

txn_record txn_status(const char *text)
{
    txn_record r = blank(TXN_STATUS);
    if (text) {
        size_t n = strnlen(text, TXN_TEXT_BYTES - 1);
        memcpy(r.args.status.text, text, n);
    }
    return r;
}

txn_record txn_flag(txn_kind kind, bool on)
{
    txn_record r = blank(kind);
    r.args.flag.on = on;
    return r;
}

txn_record txn_geoms_record(txn_kind kind, uint32_t first, uint32_t count)
{
    txn_record r = blank(kind);
    r.args.geoms = (txn_geoms){first, count};
    return r;
}

txn_record txn_highlight(uint32_t first, uint32_t count, bool on)
{
    txn_record r = blank(TXN_HIGHLIGHT);
    r.args.highlight.geoms = (txn_geoms){first, count};
    r.args.highlight.on = on;
    return r;
}

txn_record txn_colour(uint32_t first, uint32_t count, const float rgb[3])
{
    txn_record r = blank(TXN_COLOUR);
    r.args.colour.geoms = (txn_geoms){first, count};
    r.args.colour.reset = rgb == NULL;
    if (rgb)
        memcpy(r.args.colour.rgb, rgb, sizeof r.args.colour.rgb);
    return r;
}

txn_record txn_move(uint32_t first, uint32_t count, const float m[12])
{
    txn_record r = blank(TXN_MOVE);
    r.args.move.geoms = (txn_geoms){first, count};
    memcpy(r.args.move.m, m, sizeof r.args.move.m);
    return r;
}

txn_record txn_opacity_all(float a)
{
    txn_record r = blank(TXN_OPACITY);
    r.args.opacity.all = true;
    r.args.opacity.a = a;
    return r;
}

txn_record txn_opacity(uint32_t first, uint32_t count, float a)
{
    txn_record r = blank(TXN_OPACITY);
    r.args.opacity.geoms = (txn_geoms){first, count};
    r.args.opacity.a = a;
    return r;
}

txn_record txn_clip_plane(int index, bool on, const float point[3], const float normal[3])
{
    txn_record r = blank(TXN_CLIP_PLANE);
    r.args.clip_plane.index = index;
    r.args.clip_plane.on = on;
    memcpy(r.args.clip_plane.point, point, sizeof r.args.clip_plane.point);
    memcpy(r.args.clip_plane.normal, normal, sizeof r.args.clip_plane.normal);
    return r;
}

txn_record txn_crop(uint32_t first, uint32_t count, bool on, float lo, float hi)
{
    txn_record r = blank(TXN_CROP);
    r.args.crop.geoms = (txn_geoms){first, count};
    r.args.crop.on = on;
    r.args.crop.lo = lo;
    r.args.crop.hi = hi;
    return r;
}

txn_record txn_time_step(uint32_t step)
{
    txn_record r = blank(TXN_TIME_STEP);
    r.args.time_step.step = step;
    return r;
}

txn_record txn_value(uint32_t first, uint32_t count, float v)
{
    txn_record r = blank(TXN_VALUE);
    r.args.value.geoms = (txn_geoms){first, count};
    r.args.value.v = v;
    return r;
}

txn_record txn_colormap(uint32_t first, uint32_t count, const char *name)
{
    txn_record r = blank(TXN_COLORMAP);
    r.args.colormap.geoms = (txn_geoms){first, count};
    snprintf(r.args.colormap.name, sizeof r.args.colormap.name, "%s", name ? name : "");
    return r;
}

txn_record txn_transfer(const char *name)
{
    txn_record r = blank(TXN_TRANSFER);
    snprintf(r.args.renderer.name, sizeof r.args.renderer.name, "%s", name ? name : "");
    return r;
}

txn_record txn_renderer(const char *name)
{
    txn_record r = blank(TXN_RENDERER);
    if (name)
        memcpy(r.args.renderer.name, name, strnlen(name, TXN_NAME_BYTES - 1));
    return r;
}

txn_record txn_threads(int count)
{
    txn_record r = blank(TXN_THREADS);
    r.args.threads.count = count;
    return r;
}

txn_record txn_channel_active(int channel, bool on)
{
    txn_record r = blank(TXN_CHANNEL_ACTIVE);
    r.args.channel.channel = channel;
    r.args.channel.on = on;
    return r;
}

txn_record txn_simple(txn_kind kind) { return blank(kind); }

/* ---- validation and apply ------------------------------------------------------------ */

static bool geoms_valid(const char *kind, const txn_geoms *g, tess_error *err)
{
    if (g->count == 0)
        return tess_error_set(err, "%s: count: 0 instances (at least 1)", kind);
    if ((uint64_t)g->first + g->count > UINT32_MAX)
        return tess_error_set(err, "%s: first %u + count %u is past the largest instance id", kind, g->first,
                              g->count);
    return true;
}

double txn_normal_length(const float n[3])
{
    return sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
}

static bool text_terminated(const char *text, size_t size) { return memchr(text, '\0', size) != NULL; }

bool txn_validate(const txn_record *r, tess_error *err)
{
    const char *name = txn_kind_name(r->kind);
    switch (r->kind) {
    case TXN_CAMERA:
        if (r->args.camera.channel < TXN_ALL_CHANNELS || r->args.camera.channel >= TXN_MAX_CHANNELS)
            return tess_error_set(err, "camera: channel: %d is not a channel (0..%d, or all)",
                                  (int)r->args.camera.channel, TXN_MAX_CHANNELS - 1);
        if (!camera_validate(&r->args.camera.camera, err)) {
            tess_error_prefix(err, "camera: ");
            return false;
        }
        return true;
    case TXN_POINTER:
        if (r->args.pointer.slot < 0 || r->args.pointer.slot >= TXN_POINTERS)
            return tess_error_set(err, "pointer: slot: %d is not in 0..%d", (int)r->args.pointer.slot,
                                  TXN_POINTERS - 1);
        if (!isfinite(r->args.pointer.sx) || !isfinite(r->args.pointer.sy))
            return tess_error_set(err, "pointer: sx, sy: (%g, %g) is not finite", (double)r->args.pointer.sx,
                                  (double)r->args.pointer.sy);
        return true;
    case TXN_CURSOR:
        if (!isfinite(r->args.cursor.sx))
            return tess_error_set(err, "cursor: sx: %g is not finite", (double)r->args.cursor.sx);
        if (!isfinite(r->args.cursor.sy))
            return tess_error_set(err, "cursor: sy: %g is not finite", (double)r->args.cursor.sy);
        return true;
    case TXN_STATUS:
        if (!text_terminated(r->args.status.text, sizeof r->args.status.text))
            return tess_error_set(err, "status: text: not terminated within %d bytes", TXN_TEXT_BYTES);
        return true;
    case TXN_HIDE:
    case TXN_SHOW:
    case TXN_ISOLATE:
        return geoms_valid(name, &r->args.geoms, err);
    case TXN_HIGHLIGHT:
        return geoms_valid(name, &r->args.highlight.geoms, err);
    case TXN_COLOUR:
        if (!geoms_valid(name, &r->args.colour.geoms, err))
            return false;
        if (!r->args.colour.reset)
            for (int i = 0; i < 3; i++)
                if (!isfinite(r->args.colour.rgb[i]) || r->args.colour.rgb[i] < 0.f)
                    return tess_error_set(err, "colour: %c: %g is not a finite value >= 0", "rgb"[i],
                                          (double)r->args.colour.rgb[i]);
        return true;
    case TXN_RENDERER:
        if (!text_terminated(r->args.renderer.name, sizeof r->args.renderer.name))
            return tess_error_set(err, "renderer: name: not terminated within %d bytes", TXN_NAME_BYTES);
        if (!renderer_by_name(r->args.renderer.name))
            return tess_error_set(err, "renderer: name: no renderer '%s' (there are: " RENDERER_NAMES ")",
                                  r->args.renderer.name);
        return true;
    case TXN_THREADS:
        if (r->args.threads.count < 1 || r->args.threads.count > TXN_MAX_THREADS)
            return tess_error_set(err, "threads: count: %d is not in 1..%d", (int)r->args.threads.count,
                                  TXN_MAX_THREADS);
        return true;
    case TXN_CHANNEL_ACTIVE:
        if (r->args.channel.channel < 0 || r->args.channel.channel >= TXN_MAX_CHANNELS)
            return tess_error_set(err, "channel-active: channel: %d is not in 0..%d", (int)r->args.channel.channel,
                                  TXN_MAX_CHANNELS - 1);
        return true;
    case TXN_MOVE: {
        if (!geoms_valid(name, &r->args.move.geoms, err))
            return false;
        for (int i = 0; i < 12; i++)
            if (!isfinite(r->args.move.m[i]))
                return tess_error_set(err, "move: m[%d]: %g is not finite", i, (double)r->args.move.m[i]);
        affine3 a, inverse;
        memcpy(a.m, r->args.move.m, sizeof a.m);
        if (!affine3_invert(&a, &inverse))
            return tess_error_set(err, "move: m: the 3x3 part is singular");
        return true;
    }
    case TXN_OPACITY: {
        const txn_geoms *g = &r->args.opacity.geoms;
        if (r->args.opacity.all) {
            /* the text form "opacity all A" has no range: a record with one would not read back */
            if (g->first != 0 || g->count != 0)
                return tess_error_set(err, "opacity: first/count: %u %u with all (must be 0 0)", g->first, g->count);
        } else if (!geoms_valid(name, g, err)) {
            return false;
        }
        float a = r->args.opacity.a;
        if (!isfinite(a) || a < 0.f || a > 1.f)
            return tess_error_set(err, "opacity: a: %g is not a finite value in [0, 1]", (double)a);
        return true;
    }
    case TXN_CLIP_PLANE: {
        static const char *const axis[3] = {"x", "y", "z"};
        if (r->args.clip_plane.index < 0 || r->args.clip_plane.index >= CLIP_MAX_PLANES)
            return tess_error_set(err, "clip-plane: index: %d is not in 0..%d", (int)r->args.clip_plane.index,
                                  CLIP_MAX_PLANES - 1);
        for (int i = 0; i < 3; i++)
            if (!isfinite(r->args.clip_plane.point[i]))
                return tess_error_set(err, "clip-plane: point.%s: %g is not finite", axis[i],
                                      (double)r->args.clip_plane.point[i]);
        for (int i = 0; i < 3; i++)
            if (!isfinite(r->args.clip_plane.normal[i]))
                return tess_error_set(err, "clip-plane: normal.%s: %g is not finite", axis[i],
                                      (double)r->args.clip_plane.normal[i]);
        if (txn_normal_length(r->args.clip_plane.normal) == 0.0)
            return tess_error_set(err, "clip-plane: normal: zero length (a plane needs a direction)");
        return true;
    }
    case TXN_CROP: {
        if (!geoms_valid(name, &r->args.crop.geoms, err))
            return false;
        float lo = r->args.crop.lo, hi = r->args.crop.hi;
        if (!isfinite(lo))
            return tess_error_set(err, "crop: lo: %g is not finite", (double)lo);
        if (!isfinite(hi))
            return tess_error_set(err, "crop: hi: %g is not finite", (double)hi);
        if (lo > hi)
            return tess_error_set(err, "crop: lo %g is above hi %g", (double)lo, (double)hi);
        return true;
    }
    case TXN_TIME_STEP:
        return true;
    case TXN_VALUE:
        if (!geoms_valid(name, &r->args.value.geoms, err))
            return false;
        if (!isfinite(r->args.value.v))
            return tess_error_set(err, "value: v: %g is not finite", (double)r->args.value.v);
        return true;
    case TXN_COLORMAP: {
        if (!geoms_valid(name, &r->args.colormap.geoms, err))
            return false;
        if (strnlen(r->args.colormap.name, TXN_NAME_BYTES) == TXN_NAME_BYTES)
            return tess_error_set(err, "colormap: name: not terminated");
        colormap probe;
        if (!colormap_preset(r->args.colormap.name, &probe))
            return tess_error_set(err, "colormap: name: no built-in map '%s'", r->args.colormap.name);
        return true;
    }
    case TXN_TRANSFER: {
        if (strnlen(r->args.renderer.name, TXN_NAME_BYTES) == TXN_NAME_BYTES)
            return tess_error_set(err, "transfer: name: not terminated");
        colormap probe;
        if (!colormap_preset(r->args.renderer.name, &probe) || probe.opacity_count == 0)
            return tess_error_set(err, "transfer: name: no built-in transfer function '%s' (one with opacity)",
                                  r->args.renderer.name);
        return true;
    }
    case TXN_SHOW_ALL:
    case TXN_TOUR:
    case TXN_QUIT:
    case TXN_GOVERNOR_STATUS:
    case TXN_SHADOWS:
        return true;
    case TXN_KIND_COUNT:
        break;
    }
    return tess_error_set(err, "kind: %d is not a transaction kind", (int)r->kind);
}

bool txn_range_error(const char *kind, const txn_geoms *g, uint32_t count, tess_error *err)
{
    unsigned long long last = (unsigned long long)g->first + g->count - 1;
    char range[48];
    if (g->count == 1)
        snprintf(range, sizeof range, "instance %u", g->first);
    else
        snprintf(range, sizeof range, "instances %u..%llu", g->first, last);
    if (count == 0)
        return tess_error_set(err, "%s: %s: the scene has no instances", kind, range);
    if (count == 1)
        return tess_error_set(err, "%s: %s: the scene has 1 instance (id 0)", kind, range);
    return tess_error_set(err, "%s: %s: the scene has %u instances (ids 0..%u)", kind, range, count, count - 1);
}
