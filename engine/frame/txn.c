/* txn.c - transaction records (txn.h). */
#include "txn.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "engine/scene/frame_state.h"
#include "engine/accel/geometry.h"
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

/* |n| in double: exact squares of floats (no overflow or underflow to 0 for any finite nonzero n). */
static double normal_length(const float n[3])
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
        if (normal_length(r->args.clip_plane.normal) == 0.0)
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

static bool geoms_in(const frame_state *st, const char *kind, const txn_geoms *g, tess_error *err)
{
    if ((uint64_t)g->first + g->count > st->geometry_count)
        return txn_range_error(kind, g, st->geometry_count, err);
    return true;
}

static bool channel_in(const frame_state *st, const char *kind, int channel, tess_error *err)
{
    if (channel >= st->channel_count)
        return tess_error_set(err, "%s: channel %d: there are %d channels", kind, channel, st->channel_count);
    return true;
}

static bool out_of_memory(const char *kind, tess_error *err)
{
    return tess_error_set(err, "%s: out of memory for the per-instance flags", kind);
}

bool txn_apply(const txn_record *r, frame_state *st, tess_error *err)
{
    if (!txn_validate(r, err))
        return false;
    const char *name = txn_kind_name(r->kind);
    switch (r->kind) {
    case TXN_CAMERA: {
        int ch = r->args.camera.channel;
        if (ch == TXN_ALL_CHANNELS) { /* the wall's camera: every channel but the private ones */
            for (int i = 0; i < st->channel_count; i++)
                if (!st->private_view[i])
                    frame_state_set_camera(st, i, &r->args.camera.camera);
            return true;
        }
        if (!channel_in(st, name, ch, err))
            return false;
        frame_state_set_camera(st, ch, &r->args.camera.camera);
        return true;
    }
    case TXN_CURSOR:
        frame_state_set_cursor(st, r->args.cursor.on, r->args.cursor.sx, r->args.cursor.sy);
        return true;
    case TXN_POINTER:
        frame_state_set_pointer(st, r->args.pointer.slot, r->args.pointer.on, r->args.pointer.sx,
                                r->args.pointer.sy);
        return true;
    case TXN_STATUS:
        frame_state_set_status(st, r->args.status.text);
        return true;
    case TXN_GOVERNOR_STATUS:
        frame_state_set_governor_status(st, r->args.flag.on);
        return true;
    case TXN_HIDE:
    case TXN_SHOW:
        if (!geoms_in(st, name, &r->args.geoms, err))
            return false;
        if (!frame_state_set_hidden(st, r->args.geoms.first, r->args.geoms.count, r->kind == TXN_HIDE))
            return out_of_memory(name, err);
        return true;
    case TXN_ISOLATE:
        if (!geoms_in(st, name, &r->args.geoms, err))
            return false;
        if (!frame_state_isolate(st, r->args.geoms.first, r->args.geoms.count))
            return out_of_memory(name, err);
        return true;
    case TXN_SHOW_ALL:
        frame_state_show_all(st);
        return true;
    case TXN_HIGHLIGHT:
        if (!geoms_in(st, name, &r->args.highlight.geoms, err))
            return false;
        if (!frame_state_set_highlight(st, r->args.highlight.geoms.first, r->args.highlight.geoms.count,
                                       r->args.highlight.on))
            return out_of_memory(name, err);
        return true;
    case TXN_COLOUR:
        if (!geoms_in(st, name, &r->args.colour.geoms, err))
            return false;
        if (!frame_state_set_colour(st, r->args.colour.geoms.first, r->args.colour.geoms.count,
                                    r->args.colour.reset ? NULL : r->args.colour.rgb))
            return out_of_memory(name, err);
        return true;
    case TXN_SHADOWS:
        frame_state_set_shadows(st, r->args.flag.on);
        return true;
    case TXN_RENDERER:
        frame_state_set_renderer(st, renderer_by_name(r->args.renderer.name));
        return true;
    case TXN_THREADS:
        frame_state_set_threads(st, r->args.threads.count);
        return true;
    case TXN_CHANNEL_ACTIVE:
        if (!channel_in(st, name, r->args.channel.channel, err))
            return false;
        frame_state_set_active(st, r->args.channel.channel, r->args.channel.on);
        return true;
    case TXN_MOVE: {
        if (!geoms_in(st, name, &r->args.move.geoms, err))
            return false;
        affine3 a;
        memcpy(a.m, r->args.move.m, sizeof a.m);
        if (!frame_state_set_move(st, r->args.move.geoms.first, r->args.move.geoms.count, &a))
            return out_of_memory(name, err);
        return true;
    }
    case TXN_OPACITY:
        if (r->args.opacity.all) {
            frame_state_set_global_opacity(st, r->args.opacity.a);
            return true;
        }
        if (!geoms_in(st, name, &r->args.opacity.geoms, err))
            return false;
        if (!frame_state_set_opacity(st, r->args.opacity.geoms.first, r->args.opacity.geoms.count,
                                     r->args.opacity.a))
            return tess_error_set(err, "opacity: out of memory for the per-instance opacities");
        return true;
    case TXN_CLIP_PLANE: {
        const float *p = r->args.clip_plane.point, *n = r->args.clip_plane.normal;
        double len = normal_length(n);
        clip_plane plane = {.point = v3(p[0], p[1], p[2]),
                            .normal = v3((float)(n[0] / len), (float)(n[1] / len), (float)(n[2] / len)),
                            .on = r->args.clip_plane.on};
        frame_state_set_clip_plane(st, r->args.clip_plane.index, &plane);
        return true;
    }
    case TXN_CROP:
        if (!geoms_in(st, name, &r->args.crop.geoms, err))
            return false;
        if (!frame_state_set_crop(st, r->args.crop.geoms.first, r->args.crop.geoms.count,
                                  (geometry_crop){r->args.crop.on, r->args.crop.lo, r->args.crop.hi}))
            return out_of_memory(name, err);
        return true;
    case TXN_TIME_STEP:
        frame_state_set_time_step(st, r->args.time_step.step);
        return true;
    case TXN_VALUE:
        if (!geoms_in(st, name, &r->args.value.geoms, err))
            return false;
        if (!frame_state_set_value(st, r->args.value.geoms.first, r->args.value.geoms.count, r->args.value.v))
            return out_of_memory(name, err);
        return true;
    case TXN_TRANSFER:
        frame_state_set_transfer(st, r->args.renderer.name);
        return true;
    case TXN_COLORMAP:
        if (!geoms_in(st, name, &r->args.colormap.geoms, err))
            return false;
        if (!frame_state_set_colormap(st, r->args.colormap.geoms.first, r->args.colormap.geoms.count,
                                      r->args.colormap.name))
            return out_of_memory(name, err);
        return true;
    case TXN_TOUR:
    case TXN_QUIT:
    case TXN_KIND_COUNT:
        break;
    }
    return tess_error_set(err, "%s: an input-level transaction (the input sink carries it out), not frame state",
                          name);
}

/* ---- text form ----------------------------------------------------------------------- */

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
        if (!whole(r, 0.0, CLIP_MAX_PLANES - 1, &v, "clip-plane index",
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
    txn_record t = blank(TXN_QUIT);
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

/* ---- binary form ---------------------------------------------------------------------- */

static void put_u32(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)v;
    b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16);
    b[3] = (unsigned char)(v >> 24);
}

static uint32_t get_u32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static void put_f32(unsigned char *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    put_u32(b, u);
}

static float get_f32(const unsigned char *b)
{
    uint32_t u = get_u32(b);
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* The binary layout of one record's arguments (encode: write t into b; decode: read b into
 * t), one description for both so they never disagree. */
static void layout(txn_record *t, unsigned char *b, bool write)
{
#define U32(off, lv)                                                                                                   \
    do {                                                                                                               \
        if (write)                                                                                                     \
            put_u32(b + (off), (uint32_t)(lv));                                                                        \
        else                                                                                                           \
            (lv) = get_u32(b + (off));                                                                                 \
    } while (0)
#define I32(off, lv)                                                                                                   \
    do {                                                                                                               \
        if (write)                                                                                                     \
            put_u32(b + (off), (uint32_t)(lv));                                                                        \
        else                                                                                                           \
            (lv) = (int32_t)get_u32(b + (off));                                                                        \
    } while (0)
#define F32(off, lv)                                                                                                   \
    do {                                                                                                               \
        if (write)                                                                                                     \
            put_f32(b + (off), (lv));                                                                                  \
        else                                                                                                           \
            (lv) = get_f32(b + (off));                                                                                 \
    } while (0)
#define U8(off, lv)                                                                                                    \
    do {                                                                                                               \
        if (write)                                                                                                     \
            b[off] = (unsigned char)((lv) ? 1 : 0);                                                                    \
        else                                                                                                           \
            (lv) = b[off] != 0;                                                                                        \
    } while (0)
    switch (t->kind) {
    case TXN_CAMERA: {
        camera_desc *c = &t->args.camera.camera;
        float *v[10] = {&c->eye.x, &c->eye.y, &c->eye.z, &c->look_at.x, &c->look_at.y, &c->look_at.z,
                        &c->up.x,  &c->up.y,  &c->up.z,  &c->fov_deg};
        I32(4, t->args.camera.channel);
        for (int i = 0; i < 10; i++)
            F32(8 + 4 * i, *v[i]);
        break;
    }
    case TXN_CURSOR:
        U8(4, t->args.cursor.on);
        F32(8, t->args.cursor.sx);
        F32(12, t->args.cursor.sy);
        break;
    case TXN_POINTER:
        I32(4, t->args.pointer.slot);
        U8(8, t->args.pointer.on);
        F32(12, t->args.pointer.sx);
        F32(16, t->args.pointer.sy);
        break;
    case TXN_STATUS:
        if (write)
            memcpy(b + 4, t->args.status.text, strnlen(t->args.status.text, TXN_TEXT_BYTES));
        else
            memcpy(t->args.status.text, b + 4, TXN_TEXT_BYTES);
        break;
    case TXN_RENDERER:
    case TXN_TRANSFER:
        if (write)
            memcpy(b + 4, t->args.renderer.name, strnlen(t->args.renderer.name, TXN_NAME_BYTES));
        else
            memcpy(t->args.renderer.name, b + 4, TXN_NAME_BYTES);
        break;
    case TXN_GOVERNOR_STATUS:
    case TXN_SHADOWS:
    case TXN_TOUR:
        U8(4, t->args.flag.on);
        break;
    case TXN_HIDE:
    case TXN_SHOW:
    case TXN_ISOLATE:
        U32(4, t->args.geoms.first);
        U32(8, t->args.geoms.count);
        break;
    case TXN_HIGHLIGHT:
        U32(4, t->args.highlight.geoms.first);
        U32(8, t->args.highlight.geoms.count);
        U8(12, t->args.highlight.on);
        break;
    case TXN_COLOUR:
        U32(4, t->args.colour.geoms.first);
        U32(8, t->args.colour.geoms.count);
        U8(12, t->args.colour.reset);
        for (int i = 0; i < 3; i++)
            F32(16 + 4 * i, t->args.colour.rgb[i]);
        break;
    case TXN_THREADS:
        I32(4, t->args.threads.count);
        break;
    case TXN_CHANNEL_ACTIVE:
        I32(4, t->args.channel.channel);
        U8(8, t->args.channel.on);
        break;
    case TXN_MOVE:
        U32(4, t->args.move.geoms.first);
        U32(8, t->args.move.geoms.count);
        for (int i = 0; i < 12; i++)
            F32(12 + 4 * i, t->args.move.m[i]);
        break;
    case TXN_OPACITY:
        U8(4, t->args.opacity.all);
        U32(8, t->args.opacity.geoms.first);
        U32(12, t->args.opacity.geoms.count);
        F32(16, t->args.opacity.a);
        break;
    case TXN_CLIP_PLANE:
        I32(4, t->args.clip_plane.index);
        U8(8, t->args.clip_plane.on);
        for (int i = 0; i < 3; i++)
            F32(12 + 4 * i, t->args.clip_plane.point[i]);
        for (int i = 0; i < 3; i++)
            F32(24 + 4 * i, t->args.clip_plane.normal[i]);
        break;
    case TXN_CROP:
        U32(4, t->args.crop.geoms.first);
        U32(8, t->args.crop.geoms.count);
        U8(12, t->args.crop.on);
        F32(16, t->args.crop.lo);
        F32(20, t->args.crop.hi);
        break;
    case TXN_TIME_STEP:
        U32(4, t->args.time_step.step);
        break;
    case TXN_VALUE:
        U32(4, t->args.value.geoms.first);
        U32(8, t->args.value.geoms.count);
        F32(12, t->args.value.v);
        break;
    case TXN_COLORMAP:
        U32(4, t->args.colormap.geoms.first);
        U32(8, t->args.colormap.geoms.count);
        if (write)
            memcpy(b + 12, t->args.colormap.name, strnlen(t->args.colormap.name, TXN_NAME_BYTES));
        else
            memcpy(t->args.colormap.name, b + 12, TXN_NAME_BYTES);
        break;
    case TXN_SHOW_ALL:
    case TXN_QUIT:
    case TXN_KIND_COUNT:
        break;
    }
#undef U32
#undef I32
#undef F32
#undef U8
}

bool txn_encode_binary(const txn_record *r, unsigned char out[TXN_BINARY_BYTES])
{
    tess_error err = {{0}};
    memset(out, 0, TXN_BINARY_BYTES);
    if (!txn_validate(r, &err))
        return false;
    txn_record copy = *r; /* layout takes a writable record (it reads it here) */
    put_u32(out, (uint32_t)r->kind);
    layout(&copy, out, true);
    return true;
}

bool txn_decode_binary(const unsigned char in[TXN_BINARY_BYTES], txn_record *out, tess_error *err)
{
    uint32_t kind = get_u32(in);
    if (kind >= TXN_KIND_COUNT)
        return tess_error_set(err, "kind: %u is not a transaction kind", kind);
    txn_record t = blank((txn_kind)kind);
    unsigned char bytes[TXN_BINARY_BYTES];
    memcpy(bytes, in, sizeof bytes);
    layout(&t, bytes, false);
    /* every byte the layout does not use must be zero; so must flag bytes other than 0/1 and the
     * padding inside the layout: re-encode and compare */
    unsigned char again[TXN_BINARY_BYTES];
    if (!txn_validate(&t, err))
        return false;
    txn_encode_binary(&t, again);
    if (memcmp(again, in, TXN_BINARY_BYTES) != 0)
        return tess_error_set(err, "%s: bytes that must be zero (or a flag that is not 0 or 1) are not",
                              txn_kind_name(t.kind));
    *out = t;
    return true;
}
