/* pipeline_queue.c - queueing: transactions and one-shots into the queue
 * (queue_lock), the stop; and the records: checked against this pipeline,
 * queued (pipeline_submit, the pipeline_queue_* calls that build them) or
 * applied at once (pipeline_apply). The serial section runs the queue
 * (pipeline_serial.c). */
#include "pipeline_private.h"

#include <pthread.h>
#include <stdatomic.h>
#include <string.h>

#include "engine/base/log.h"

/* ---------------------------------------------------------------- queueing */

static bool queue_call(pipeline *p, bool oneshot, uint64_t frame, const char *name, pipeline_fn fn,
                       const void *args, size_t args_bytes)
{
    if (args_bytes > PIPELINE_ARGS_MAX) {
        log_error("pipeline: transaction '%s': %zu bytes of arguments (at most %d are copied)", name, args_bytes,
                  PIPELINE_ARGS_MAX);
        pthread_mutex_lock(&p->stats_lock);
        p->stats.transactions_rejected++;
        pthread_mutex_unlock(&p->stats_lock);
        return false;
    }
    pthread_mutex_lock(&p->queue_lock);
    const char *refusal = NULL;
    queued_call *slot = NULL;
    /* once the stop is asked for no barrier runs transactions any more (pipeline_serial_section) */
    bool stopping = p->closed || atomic_load(&p->stop_requested);
    if (stopping)
        refusal = p->closed ? "the pipeline has stopped" : "the pipeline is stopping";
    else if (!oneshot && p->queue_count == PIPELINE_QUEUE_MAX)
        refusal = "the transaction queue is full";
    else if (oneshot && p->oneshot_count == PIPELINE_QUEUE_MAX)
        refusal = "too many one-shot callbacks are waiting";
    else if (oneshot)
        slot = &p->oneshots[p->oneshot_count++];
    else
        slot = &p->queue[(p->queue_head + p->queue_count++) % PIPELINE_QUEUE_MAX];
    if (slot) {
        pthread_cond_broadcast(&p->queue_changed); /* an idle step may be waiting for work */
        slot->fn = fn;
        slot->name = name ? name : "(unnamed)";
        slot->due_frame = frame;
        slot->args_bytes = args_bytes;
        if (args_bytes)
            memcpy(slot->args.bytes, args, args_bytes);
    }
    /* log the first refusal of a run of them, not every retry of a flooding producer */
    bool first_refusal = refusal && !p->refusing;
    p->refusing = refusal != NULL;
    pthread_mutex_unlock(&p->queue_lock);
    if (refusal) {
        if (first_refusal)
            log_warn("pipeline: transaction '%s' refused: %s (further refusals are only counted until one is "
                     "accepted)",
                     name ? name : "(unnamed)", refusal);
        pthread_mutex_lock(&p->stats_lock);
        p->stats.transactions_rejected++;
        if (stopping)
            p->stats.rejected_stopped++;
        else
            p->stats.rejected_queue_full++;
        pthread_mutex_unlock(&p->stats_lock);
        return false;
    }
    return true;
}

static bool has_fn(pipeline_fn fn, const char *name)
{
    if (!fn)
        log_error("pipeline: transaction '%s' has no function", name ? name : "?");
    return fn != NULL;
}

bool pipeline_transaction(pipeline *p, const char *name, pipeline_fn fn, const void *args, size_t args_bytes)
{
    return has_fn(fn, name) && queue_call(p, false, 0, name, fn, args, args_bytes);
}

bool pipeline_at_frame(pipeline *p, uint64_t frame, const char *name, pipeline_fn fn, const void *args,
                       size_t args_bytes)
{
    return has_fn(fn, name) && queue_call(p, true, frame, name, fn, args, args_bytes);
}

void pipeline_stop(pipeline *p)
{
    atomic_store(&p->stop_requested, true);
    pthread_mutex_lock(&p->queue_lock); /* wake an idle step (it checks the flag under this lock) */
    pthread_cond_broadcast(&p->queue_changed);
    pthread_mutex_unlock(&p->queue_lock);
}

bool pipeline_stop_requested(const pipeline *p) { return atomic_load(&p->stop_requested); }

/* ---------------------------------------------------------------- records */

/* What a record may name must exist in this pipeline: its geometries, its channels. */
static bool record_in_range(const pipeline *p, const txn_record *r, tess_error *err)
{
    const txn_geoms *g = r->kind == TXN_HIGHLIGHT ? &r->args.highlight.geoms
                         : r->kind == TXN_COLOUR  ? &r->args.colour.geoms
                         : r->kind == TXN_MOVE    ? &r->args.move.geoms
                         : r->kind == TXN_OPACITY && !r->args.opacity.all ? &r->args.opacity.geoms
                         : r->kind == TXN_HIDE || r->kind == TXN_SHOW || r->kind == TXN_ISOLATE ? &r->args.geoms
                                                                                                 : NULL;
    uint32_t count = p->state.geometry_count;
    if (g && (uint64_t)g->first + g->count > count)
        return txn_range_error(txn_kind_name(r->kind), g, count, err);
    int channel = r->kind == TXN_CAMERA ? r->args.camera.channel
                  : r->kind == TXN_CHANNEL_ACTIVE ? r->args.channel.channel
                                                  : TXN_ALL_CHANNELS;
    if (channel >= p->channel_count)
        return tess_error_set(err, "%s: no channel %d (there are %d)", txn_kind_name(r->kind), channel,
                              p->channel_count);
    return true;
}

/* Validate a record for queueing: its own checks, this pipeline's ranges, an engine kind. */
static bool record_ok(const pipeline *p, const txn_record *r, tess_error *err)
{
    if (!txn_validate(r, err) || !record_in_range(p, r, err))
        return false;
    if (txn_kind_input_level(r->kind))
        return tess_error_set(err, "%s: an input-level transaction (input/sink.h carries it out)",
                              txn_kind_name(r->kind));
    return true;
}

static bool submit(pipeline *p, const txn_record *r, tess_error *err)
{
    if (!record_ok(p, r, err))
        return false;
    if (!queue_call(p, false, 0, txn_kind_name(r->kind), NULL, r, sizeof *r))
        return tess_error_set(err, "pipeline: %s transaction refused (queue full or pipeline stopped)",
                              txn_kind_name(r->kind));
    return true;
}

bool pipeline_check(const pipeline *p, const txn_record *r, tess_error *err) { return record_ok(p, r, err); }

bool pipeline_submit_from(pipeline *p, const txn_record *r, const char *origin)
{
    tess_error err = {{0}};
    if (!record_ok(p, r, &err)) {
        log_error("pipeline: transaction refused: %s%s%s", origin ? origin : "", origin ? ": " : "", err.msg);
        pthread_mutex_lock(&p->stats_lock);
        p->stats.transactions_invalid++;
        pthread_mutex_unlock(&p->stats_lock);
        return false;
    }
    return submit(p, r, &err); /* a refusal by the queue is logged there */
}

bool pipeline_submit(pipeline *p, const txn_record *r) { return pipeline_submit_from(p, r, NULL); }

bool pipeline_apply(pipeline *p, const txn_record *r)
{
    if (!pipeline_may_change_state(p, txn_kind_name(r->kind)))
        return false;
    tess_error err = {{0}};
    if (!record_ok(p, r, &err)) {
        log_error("pipeline: transaction refused: %s", err.msg);
        return false;
    }
    return pipeline_apply_record(p, r);
}

/* ---- the setting-by-setting API: records built here ---- */

bool pipeline_queue_camera(pipeline *p, int channel, const camera_desc *camera, tess_error *err)
{
    if (channel < 0 || channel >= p->channel_count)
        return tess_error_set(err, "pipeline: no channel %d (there are %d)", channel, p->channel_count);
    if (!camera_validate(camera, err))
        return false;
    txn_record r = txn_camera(channel, camera);
    return submit(p, &r, err);
}

bool pipeline_queue_channel_active(pipeline *p, int channel, bool active)
{
    if (channel < 0 || channel >= p->channel_count) {
        log_error("pipeline: switching channel %d: there are %d channels", channel, p->channel_count);
        return false;
    }
    txn_record r = txn_channel_active(channel, active);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_threads(pipeline *p, int threads)
{
    txn_record r = txn_threads(threads);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_status(pipeline *p, const char *text)
{
    if (!text) {
        log_error("pipeline: status line: no text (\"\" hides the line)");
        return false;
    }
    txn_record r = txn_status(text);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_governor_status(pipeline *p, bool shown)
{
    txn_record r = txn_flag(TXN_GOVERNOR_STATUS, shown);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_cursor(pipeline *p, bool visible, float sx, float sy)
{
    txn_record r = txn_cursor(visible, sx, sy);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_hide(pipeline *p, uint32_t geom_id, bool hidden)
{
    txn_record r = txn_geoms_record(hidden ? TXN_HIDE : TXN_SHOW, geom_id, 1);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_unhide_all(pipeline *p)
{
    txn_record r = txn_simple(TXN_SHOW_ALL);
    return pipeline_submit(p, &r);
}
