/* txn_apply.c - a record applied to the frame state (txn.h: txn_apply). */
#include "txn.h"
#include "txn_private.h"

#include <string.h>

#include "engine/base/colormap.h"
#include "engine/render/render.h"
#include "engine/scene/frame_state.h"

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
        double len = txn_normal_length(n);
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
