/* pipeline_state.c - the frame state (what transactions change): records
 * applied to it, here alone, with what follows from them (the drawn
 * overlay, the accel's hidden flags); the setters that apply a record at
 * once; and what may be read of the pipeline's state and counters. */
#include "pipeline_private.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/base/log.h"

/* ---------------------------------------------------------------- state */

/* State may change here: in the serial section, or while no loop runs. */
bool pipeline_may_change_state(const pipeline *p, const char *what)
{
    if (pipeline_in_serial_section(p) || !atomic_load(&p->running))
        return true;
    log_error("pipeline: %s outside a transaction or serial callback: refused (state changes only at the "
              "frame barrier)",
              what);
    return false;
}

_Static_assert(OVERLAY_POINTERS == TXN_POINTERS, "a pointer record's slot is an overlay pointer");

/* Apply a record to the state (serial section, or no loop running) and carry
 * out what follows from it: the drawn overlay, the accel's hidden flags. */
bool pipeline_apply_record(pipeline *p, const txn_record *r)
{
    tess_error err = {{0}};
    if (!txn_apply(r, &p->state, &err)) {
        log_error("pipeline: transaction refused: %s", err.msg);
        return false;
    }
    if (p->record_observer)
        p->record_observer(p->record_observer_ctx, r);
    switch (r->kind) {
    case TXN_STATUS:
    case TXN_GOVERNOR_STATUS:
        pipeline_compose_status(p);
        break;
    case TXN_CURSOR:
        p->overlay.cursor_visible = p->state.cursor_visible;
        p->overlay.cursor_sx = p->state.cursor_sx;
        p->overlay.cursor_sy = p->state.cursor_sy;
        break;
    case TXN_POINTER:
        for (int i = 0; i < OVERLAY_POINTERS; i++) {
            p->overlay.pointer_visible[i] = p->state.pointer_visible[i];
            p->overlay.pointer_sx[i] = p->state.pointer_sx[i];
            p->overlay.pointer_sy[i] = p->state.pointer_sy[i];
        }
        break;
    case TXN_HIDE:
    case TXN_SHOW:
    case TXN_ISOLATE:
    case TXN_SHOW_ALL:
        /* the accel's flags follow at the end of the serial section (once for all of its
         * records: only the flags that differ); outside a loop at once */
        if (!pipeline_in_serial_section(p))
            frame_state_sync_accel(&p->state, p->cfg.accel);
        break;
    default:
        break;
    }
    return true;
}

/* overlay.status from the status text asked for and, when shown, the
 * governor's line for the frame being planned; bumps the state's
 * overlay_serial when the drawn text changes. */
void pipeline_compose_status(pipeline *p)
{
    const frame_state *st = &p->state;
    char text[PIPELINE_STATUS_BYTES];
    if (!st->governor_status_shown)
        snprintf(text, sizeof text, "%s", st->status);
    else {
        char line[PIPELINE_STATUS_BYTES];
        if (p->governed)
            governor_describe(&p->gov, &p->frame_plan, line, sizeof line);
        else
            snprintf(line, sizeof line, "governor: off (no frame budget)");
        /* the asked-for text first, the governor's line after it, cut at the end */
        size_t used = strlen(st->status);
        memcpy(text, st->status, used + 1);
        if (used && used + 3 < sizeof text) {
            memcpy(text + used, " | ", 4);
            used += 3;
        }
        size_t room = sizeof text - 1 - used, n = strnlen(line, room);
        memcpy(text + used, line, n);
        text[used + n] = '\0';
    }
    char before[PIPELINE_STATUS_BYTES];
    memcpy(before, p->overlay.status, sizeof before);
    overlay_set_status(&p->overlay, text);
    if (strcmp(before, p->overlay.status) != 0)
        frame_state_bump_overlay(&p->state);
}

/* The setters: records applied at once (serial section, or no loop running). */

bool pipeline_set_camera(pipeline *p, int channel, const camera_desc *camera)
{
    if (!pipeline_may_change_state(p, "camera change"))
        return false;
    if (channel < 0 || channel >= p->channel_count) {
        log_error("pipeline: camera change for channel %d: there are %d channels", channel, p->channel_count);
        return false;
    }
    txn_record r = txn_camera(channel, camera);
    return pipeline_apply_record(p, &r);
}

bool pipeline_set_channel_active(pipeline *p, int channel, bool active)
{
    if (!pipeline_may_change_state(p, "channel switch"))
        return false;
    if (channel < 0 || channel >= p->channel_count) {
        log_error("pipeline: switching channel %d: there are %d channels", channel, p->channel_count);
        return false;
    }
    txn_record r = txn_channel_active(channel, active);
    return pipeline_apply_record(p, &r);
}

bool pipeline_channel_active(const pipeline *p, int channel)
{
    return channel >= 0 && channel < p->channel_count && p->state.active[channel];
}

bool pipeline_set_threads(pipeline *p, int threads)
{
    if (!pipeline_may_change_state(p, "thread-count change"))
        return false;
    txn_record r = txn_threads(threads);
    return pipeline_apply_record(p, &r);
}

bool pipeline_set_status(pipeline *p, const char *text)
{
    if (!pipeline_may_change_state(p, "status line change"))
        return false;
    if (!text) {
        log_error("pipeline: status line: no text (\"\" hides the line)");
        return false;
    }
    txn_record r = txn_status(text);
    return pipeline_apply_record(p, &r);
}

bool pipeline_set_governor_status(pipeline *p, bool shown)
{
    if (!pipeline_may_change_state(p, "governor status change"))
        return false;
    txn_record r = txn_flag(TXN_GOVERNOR_STATUS, shown);
    return pipeline_apply_record(p, &r);
}

governor_frame pipeline_governor_frame(const pipeline *p) { return p->frame_plan; }

const char *pipeline_status(const pipeline *p) { return p->overlay.status; }

bool pipeline_set_cursor(pipeline *p, bool visible, float sx, float sy)
{
    if (!pipeline_may_change_state(p, "cursor change"))
        return false;
    txn_record r = txn_cursor(visible, sx, sy);
    return pipeline_apply_record(p, &r);
}

bool pipeline_cursor(const pipeline *p, float *sx, float *sy)
{
    if (sx)
        *sx = p->state.cursor_sx;
    if (sy)
        *sy = p->state.cursor_sy;
    return p->state.cursor_visible;
}

bool pipeline_set_hidden(pipeline *p, uint32_t geom_id, bool hidden)
{
    if (!pipeline_may_change_state(p, hidden ? "hiding a geometry" : "showing a geometry"))
        return false;
    txn_record r = txn_geoms_record(hidden ? TXN_HIDE : TXN_SHOW, geom_id, 1);
    return pipeline_apply_record(p, &r);
}

bool pipeline_unhide_all(pipeline *p)
{
    if (!pipeline_may_change_state(p, "showing every geometry"))
        return false;
    txn_record r = txn_simple(TXN_SHOW_ALL);
    return pipeline_apply_record(p, &r);
}

bool pipeline_hidden(const pipeline *p, uint32_t geom_id)
{
    /* the state is what was asked for; the accel (what traversal sees) follows it at the end
     * of each serial section, and is what other threads may read while the loop runs */
    if (pipeline_in_serial_section(p) || !atomic_load(&p->running))
        return frame_state_hidden(&p->state, geom_id);
    return accel_hidden(p->cfg.accel, geom_id);
}

uint32_t pipeline_geometry_count(const pipeline *p) { return accel_geometry_count(p->cfg.accel); }

const frame_state *pipeline_frame_state(const pipeline *p) { return &p->state; }

camera_desc pipeline_camera(const pipeline *p, int channel)
{
    if (channel < 0 || channel >= p->channel_count)
        return p->state.cameras[0];
    return p->state.cameras[channel];
}

uint64_t pipeline_camera_serial(const pipeline *p, int channel)
{
    if (channel < 0 || channel >= p->channel_count)
        return 0;
    return p->state.camera_serials[channel];
}

int pipeline_channel_count(const pipeline *p) { return p->channel_count; }

camera_basis pipeline_channel_basis(const pipeline *p, int channel)
{
    int i = channel < 0 || channel >= p->channel_count ? 0 : channel;
    const pipe_channel *c = &p->channels[i];
    return camera_basis_window(&p->state.cameras[i], c->plane_aspect, c->window, c->width_px, c->height_px);
}
uint64_t pipeline_frame(const pipeline *p) { return p->step.info.frame; }

pipeline_stats pipeline_get_stats(pipeline *p)
{
    pthread_mutex_lock(&p->stats_lock);
    pipeline_stats s = p->stats;
    pthread_mutex_unlock(&p->stats_lock);
    return s;
}
