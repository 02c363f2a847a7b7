/* pipeline_stages.c - what runs between frame barriers, on every render
 * thread: parallel animation, the display stage (thread 0: the queued
 * buffers shown, the display hooks), the render stage (the traverser hands
 * out the frame's work; a reduced frame is upscaled), then the next barrier.
 * A thread the serial section starts enters here. */
#include "pipeline_private.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>

#include "engine/base/log.h"
#include "engine/base/thread_name.h"

/* ---------------------------------------------------------------- the stages */

/* Thread 0, after a barrier: write what the serial section logged (one write). */
static void flush_barrier_log(pipeline *p)
{
    if (p->barrier_log_bytes) {
        fwrite(p->barrier_log, 1, p->barrier_log_bytes, stderr);
        p->barrier_log_bytes = 0;
    }
    if (p->barrier_log_dropped) {
        log_warn("pipeline: %llu more log lines of one frame barrier dropped (over %d bytes)",
                 (unsigned long long)p->barrier_log_dropped, PIPELINE_BARRIER_LOG_BYTES);
        p->barrier_log_dropped = 0;
    }
}

/* A display's show or end_stage failed: the run stops with its error. */
static void display_failed(pipeline *p, const image_display *d, tess_error *err)
{
    if (!tess_error_is_set(err))
        tess_error_set(err, "display '%s' failed without a reason", d->ops->name);
    p->display_error = *err;
    p->display_failed = true;
}

static void display_stage(pipeline *p)
{
    double t0 = pipeline_now_s();
    for (int i = 0; i < p->channel_count && !p->display_failed; i++) {
        pipe_channel *c = &p->channels[i];
        if (!c->queued_valid)
            continue;
        tess_error err = {{0}};
        if (!c->display->ops->show(c->display, &c->buffers[c->queued].meta, &err))
            display_failed(p, c->display, &err);
    }
    for (int i = 0; i < p->channel_count && !p->display_failed; i++) {
        image_display *d = p->channels[i].display;
        tess_error err = {{0}};
        if (d->ops->settle_stage && !d->ops->settle_stage(d, &err))
            display_failed(p, d, &err);
    }
    /* the frame lock: every process here before a flip, also one whose display failed (it
     * shows nothing more, but the others wait at this barrier; its stop reaches them through
     * the next frame sync, so that all stop at the same step) */
    if (p->display_sync) {
        uint64_t shown = UINT64_MAX;
        for (int i = 0; i < p->channel_count && shown == UINT64_MAX && !p->display_failed; i++)
            if (p->channels[i].queued_valid)
                shown = p->channels[i].buffers[p->channels[i].queued].meta.frame;
        tess_error err = {{0}};
        if (!p->display_sync(p->display_sync_ctx, shown, &err) && !p->display_failed) { /* the first error stays */
            if (!tess_error_is_set(&err))
                tess_error_set(&err, "the display sync failed without a reason");
            p->display_error = err;
            p->display_failed = true;
        }
    }
    for (int i = 0; i < p->channel_count && !p->display_failed; i++) {
        image_display *d = p->channels[i].display;
        tess_error err = {{0}};
        if (d->ops->end_stage && !d->ops->end_stage(d, &err))
            display_failed(p, d, &err);
    }
    p->display_stage_s = pipeline_now_s() - t0;
}

/* The dynamically balanced stage: the traverser hands out the frame's work. */
/* A reduced frame's second half: bands of tile_px output rows, upscaled from
 * the channel's low-res frame, then the overlay and write_tile per tile. */
static void upscale_stage(pipeline *p, render_thread *t)
{
    const int tile_px = p->cfg.tile_px, rung = p->frame_plan.rung;
    for (;;) {
        uint32_t item = atomic_fetch_add_explicit(&p->upscale_next, 1, memory_order_relaxed);
        if (item >= p->upscale_items)
            return;
        int ci = 0; /* first_band ascends; a channel switched off has no bands (its first equals the next's) */
        while (ci + 1 < p->channel_count && item >= p->channels[ci + 1].first_band)
            ci++;
        pipe_channel *c = &p->channels[ci];
        frame_buffer *b = &c->buffers[c->pending];
        int y0 = (int)(item - c->first_band) * tile_px;
        int y1 = y0 + tile_px < c->height_px ? y0 + tile_px : c->height_px;
        upscale_plan_rows(c->plans[rung], c->lowres, b->rgb, y0, y1, t->upscale_scratch);
        image_display *sink = c->display->ops->write_tile ? c->display : NULL;
        for (int x0 = 0; x0 < c->width_px; x0 += tile_px) {
            int x1 = x0 + tile_px < c->width_px ? x0 + tile_px : c->width_px;
            if (c->overlay_on)
                overlay_draw(&c->overlay, c->width_px, x0, y0, x1, y1, b->rgb);
            if (sink)
                sink->ops->write_tile(sink, &b->meta, x0, y0, x1, y1);
        }
    }
}

/* The dynamically balanced stage: the traverser hands out the frame's work
 * (a reduced frame: its rung's traverser, the upscale barrier, upscaling). */
static void render_stage(pipeline *p, render_thread *t)
{
    render_counts counts = {0}; /* on this thread's stack: no shared cache line per packet */
    double t0 = pipeline_now_s();
    if (p->reduced) {
        image_traverser *lowres = p->rung_traversers[p->frame_plan.rung];
        lowres->ops->render(lowres, p->frame_renderer, &p->frame_sampler, &counts);
        pipeline_barrier_wait(&p->upscale_barrier, p, NULL);
        double t1 = pipeline_now_s();
        upscale_stage(p, t);
        t->upscale_stage_s = pipeline_now_s() - t1;
    } else
        p->traverser->ops->render(p->traverser, p->frame_renderer, &p->frame_sampler, &counts);
    t->render_stage_s = pipeline_now_s() - t0;
    t->counts = counts;
}

/* Steps 2-4 of the current loop step, then the next frame barrier. Returns
 * when this thread leaves the loop. */
void pipeline_frame_loop(render_thread *t)
{
    pipeline *p = t->p;
    for (;;) {
        const loop_step *s = &p->step;
        if (t->id == 0) /* the last barrier's log lines: written here, while nobody waits */
            flush_barrier_log(p);
        if (s->exit || t->id >= s->info.threads)
            return;
        if (s->animate_parallel) {
            for (int i = 0; i < p->parallel_anim_count; i++)
                p->parallel_anim[i].fn(p, p->parallel_anim[i].ctx, &s->info, t->id, s->info.threads);
            pipeline_barrier_wait(&p->anim_barrier, p, NULL);
        }
        if (t->id == 0 && s->display)
            display_stage(p);
        if (s->render)
            render_stage(p, t);
        double arrived = pipeline_now_s();
        pipeline_barrier_wait(&p->frame_barrier, p, pipeline_serial_section);
        t->left_barrier_s = pipeline_now_s();
        t->barrier_s += t->left_barrier_s - arrived;
    }
}

/* A thread started in a serial section: it joins the step that section prepares. */
void *pipeline_thread_main(void *arg)
{
    render_thread *t = arg;
    thread_name_set("tess-render-%d", t->id);
    barrier *b = &t->p->frame_barrier;
    pthread_mutex_lock(&b->lock);
    while (atomic_load(&b->generation) == t->start_generation)
        pthread_cond_wait(&b->released, &b->lock);
    pthread_mutex_unlock(&b->lock);
    pipeline_frame_loop(t);
    return NULL;
}
