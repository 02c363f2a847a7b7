/* pipeline_serial.c - the serial section: what the last thread to arrive at
 * the frame barrier runs while the others wait. The previous step is folded
 * in (rays, stats, buffer rotation), queued transactions, due one-shots and
 * serial animation run, the thread count changes, the governor (or a fixed
 * render scale) plans the frame, and the frame is frozen for the render
 * threads. Its log lines are kept for thread 0 (pipeline_stages.c writes
 * them after the barrier). */
#include "pipeline_private.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/base/log.h"
#include "engine/scene/scene.h"

/* ---------------------------------------------------------------- serial section */

/* The pipeline whose serial section this thread is running, if any. */
static _Thread_local const pipeline *tls_serial_owner;

bool pipeline_in_serial_section(const pipeline *p) { return tls_serial_owner == p; }

/* log_divert_thread's target in the serial section: the line is kept for thread 0. */
static void keep_barrier_log(void *ctx, const char *line)
{
    pipeline *p = ctx;
    size_t n = strlen(line);
    if (p->barrier_log_bytes + n + 1 > sizeof p->barrier_log) {
        p->barrier_log_dropped++;
        return;
    }
    memcpy(p->barrier_log + p->barrier_log_bytes, line, n);
    p->barrier_log[p->barrier_log_bytes + n] = '\n';
    p->barrier_log_bytes += n + 1;
}

/* Time one serial callback against the budget. */
static void note_duration(pipeline *p, const char *kind, const char *name, double t0)
{
    double took = pipeline_now_s() - t0;
    if (took <= PIPELINE_CALLBACK_BUDGET_S)
        return;
    log_warn("pipeline: %s '%s' took %.1f ms at the frame barrier (budget %.1f ms): every render thread waited",
             kind, name, 1e3 * took, 1e3 * PIPELINE_CALLBACK_BUDGET_S);
    pthread_mutex_lock(&p->stats_lock);
    p->stats.slow_callbacks++;
    pthread_mutex_unlock(&p->stats_lock);
}

/* Run the transactions queued before this point, in FIFO order. They run
 * outside queue_lock (they may queue more); the slots stay counted in the
 * queue until they are done, so producers cannot reuse them. */
static void run_transactions(pipeline *p)
{
    pthread_mutex_lock(&p->queue_lock);
    size_t head = p->queue_head, count = p->queue_count;
    pthread_mutex_unlock(&p->queue_lock);
    for (size_t i = 0; i < count; i++) {
        queued_call *c = &p->queue[(head + i) % PIPELINE_QUEUE_MAX];
        double t0 = pipeline_now_s();
        if (c->fn)
            c->fn(p, c->args.bytes);
        else
            pipeline_apply_record(p, (const txn_record *)(const void *)c->args.bytes);
        note_duration(p, "transaction", c->name, t0);
    }
    pthread_mutex_lock(&p->queue_lock);
    p->queue_head = (head + count) % PIPELINE_QUEUE_MAX;
    p->queue_count -= count;
    pthread_mutex_unlock(&p->queue_lock);
    pthread_mutex_lock(&p->stats_lock);
    p->stats.transactions_applied += count;
    pthread_mutex_unlock(&p->stats_lock);
}

/* Run the one-shots due at `frame` (or earlier), in the order they were queued. */
static void run_oneshots(pipeline *p, uint64_t frame)
{
    size_t due = 0;
    pthread_mutex_lock(&p->queue_lock);
    size_t kept = 0;
    for (size_t i = 0; i < p->oneshot_count; i++) {
        if (p->oneshots[i].due_frame <= frame)
            p->oneshot_scratch[due++] = p->oneshots[i];
        else
            p->oneshots[kept++] = p->oneshots[i];
    }
    p->oneshot_count = kept;
    pthread_mutex_unlock(&p->queue_lock);
    for (size_t i = 0; i < due; i++) {
        queued_call *c = &p->oneshot_scratch[i];
        double t0 = pipeline_now_s();
        c->fn(p, c->args.bytes);
        note_duration(p, "one-shot callback", c->name, t0);
    }
}

static void run_serial_animation(pipeline *p)
{
    /* a callback may register another (it runs from the next frame): iterate over a copy */
    serial_callback cbs[PIPELINE_MAX_CALLBACKS];
    int n = p->serial_anim_count;
    memcpy(cbs, p->serial_anim, (size_t)n * sizeof cbs[0]);
    for (int i = 0; i < n; i++) {
        double t0 = pipeline_now_s();
        cbs[i].fn(p, cbs[i].ctx, &p->step.info);
        note_duration(p, "serial animation", cbs[i].name, t0);
    }
}

/* Join threads that left the loop at an earlier barrier. */
void pipeline_join_departed(pipeline *p, int keep_below)
{
    for (int i = (keep_below > 1 ? keep_below : 1); i < PIPELINE_MAX_THREADS; i++)
        if (p->threads[i].joinable) {
            pthread_join(p->threads[i].handle, NULL);
            p->threads[i].joinable = false;
        }
}

/* Apply threads_wanted: start threads that join this step, or let the
 * highest-numbered ones leave after the barrier. Returns the new count. */
static int change_thread_count(pipeline *p)
{
    int want = p->state.threads, have = p->thread_count;
    if (want == have)
        return have;
    if (want > have) {
        for (int id = have; id < want; id++) {
            render_thread *t = &p->threads[id];
            if (t->joinable) { /* left at an earlier barrier: finish that first */
                pthread_join(t->handle, NULL);
                t->joinable = false;
            }
            memset(&t->counts, 0, sizeof t->counts);
            /* it must not arrive at the frame barrier before the barrier that started it releases */
            t->start_generation = atomic_load(&p->frame_barrier.generation);
            int rc = pthread_create(&t->handle, NULL, pipeline_thread_main, t);
            if (rc != 0) {
                log_warn("pipeline: could start only %d of %d render threads: %s", id, want, strerror(rc));
                want = id;
                p->state.threads = id; /* serial section: what the state can have */
                break;
            }
            t->joinable = true;
        }
    }
    if (want != have) {
        pthread_mutex_lock(&p->stats_lock);
        p->stats.thread_changes++;
        pthread_mutex_unlock(&p->stats_lock);
        log_debug("pipeline: %d -> %d render threads from frame %llu", have, want,
                  (unsigned long long)p->step.info.frame);
    }
    p->thread_count = want;
    return want;
}

/* Fold in what the previous step did: rays, frames, buffer rotation. */
static void finish_previous_step(pipeline *p)
{
    const loop_step *prev = &p->step;
    render_counts sum = {0};
    double longest_render_s = 0.0, longest_upscale_s = 0.0;
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++) {
        if (p->threads[i].upscale_stage_s > longest_upscale_s)
            longest_upscale_s = p->threads[i].upscale_stage_s;
        p->threads[i].upscale_stage_s = 0.0;
        render_counts *c = &p->threads[i].counts;
        sum.primary_rays += c->primary_rays;
        sum.primary_hits += c->primary_hits;
        sum.shadow_rays += c->shadow_rays;
        sum.secondary_rays += c->secondary_rays;
        sum.ao_rays += c->ao_rays;
        memset(c, 0, sizeof *c);
        if (p->threads[i].render_stage_s > longest_render_s)
            longest_render_s = p->threads[i].render_stage_s;
        p->threads[i].render_stage_s = 0.0;
    }
    p->last_render_s = longest_render_s;
    p->last_upscale_s = longest_upscale_s;
    pthread_mutex_lock(&p->stats_lock);
    p->stats.rays.primary_rays += sum.primary_rays;
    p->stats.rays.primary_hits += sum.primary_hits;
    p->stats.rays.shadow_rays += sum.shadow_rays;
    p->stats.rays.secondary_rays += sum.secondary_rays;
    p->stats.rays.ao_rays += sum.ao_rays;
    if (prev->render)
        p->stats.frames_rendered++;
    if (prev->render && p->reduced) {
        p->stats.upscale_s += longest_upscale_s;
        p->stats.frames_reduced++;
    }
    if (prev->render && p->governed) {
        const governor_frame *f = &p->frame_plan;
        p->stats.frames_scaled += f->kind == GOVERNOR_FRAME_SCALED;
        p->stats.frames_accumulated += f->kind == GOVERNOR_FRAME_ACCUMULATE;
        p->stats.frames_resolved += f->kind == GOVERNOR_FRAME_RESOLVE;
    }
    if (prev->info.idle)
        p->stats.idle_steps++;
    if (prev->display && prev->frames_queued && !p->display_failed)
        p->stats.frames_displayed++;
    if (prev->display)
        p->stats.display_s += p->display_stage_s;
    pthread_mutex_unlock(&p->stats_lock);
    for (int i = 0; i < p->channel_count; i++) {
        pipe_channel *c = &p->channels[i];
        if (prev->display)
            c->queued_valid = false;
        if (prev->render) { /* on screen <- queued, queued <- pending, pending <- old on screen */
            int old_on_screen = c->on_screen;
            c->on_screen = c->queued;
            c->queued = c->pending;
            c->pending = old_on_screen;
            c->queued_valid = c->buffers[c->queued].rendered;
        }
    }
}

/* Freeze each channel's camera and options for the frame about to render,
 * and give the traverser (a reduced frame: its rung's) the frame's targets. */
static void freeze_frame(pipeline *p)
{
    traverser_target targets[PIPELINE_MAX_CHANNELS];
    const governor_frame *plan = &p->frame_plan;
    const bool accumulate = plan->kind == GOVERNOR_FRAME_ACCUMULATE || plan->kind == GOVERNOR_FRAME_RESOLVE;
    const double scale = p->rung_scale[plan->rung];
    const frame_state *st = &p->state; /* the frame's snapshot: unchanged until the next barrier */
    p->frame_renderer = st->renderer;
    /* private channels: the status line alone (the cursor and pointers are the wall's plane
     * points); made only when some channel is private and on */
    overlay_state private_overlay;
    bool any_private = false;
    for (int i = 0; i < p->channel_count && !any_private; i++)
        any_private = st->private_view[i] && st->active[i];
    if (any_private) {
        private_overlay = p->overlay;
        private_overlay.cursor_visible = false;
        memset(private_overlay.pointer_visible, 0, sizeof private_overlay.pointer_visible);
    }
    uint32_t bands = 0;
    for (int i = 0; i < p->channel_count; i++) {
        pipe_channel *c = &p->channels[i];
        const camera_desc *camera = &st->cameras[i];
        const bool active = st->active[i];
        c->view = (render_view){.scene = p->cfg.scene,
                                .accel = p->cfg.accel,
                                .camera = camera_basis_window(camera, c->plane_aspect, c->window, c->width_px,
                                                              c->height_px),
                                .shadows = st->shadows,
                                .shading = st->renderer->shading,
                                .state = st,
                                .settings = &p->cfg.settings}; /* fixed: the pipeline's copy */
        frame_buffer *b = &c->buffers[c->pending];
        b->meta = (frame_image){b->rgb, c->width_px, c->height_px, p->step.info.frame, p->step.info.time_s, i,
                                *camera, st->camera_serials[i], p->reduced ? scale : 1.0,
                                p->governed ? plan->samples : p->cfg.sampler.kind == PIXEL_SAMPLER_SINGLE
                                                                  ? 1
                                                                  : p->cfg.sampler.k * p->cfg.sampler.k};
        b->rendered = active;
        image_display *sink = c->display->ops->write_tile ? c->display : NULL;
        c->overlay_on = overlay_plan_make(&c->overlay, any_private && st->private_view[i] ? &private_overlay : &p->overlay,
                                          c->window, c->width_px, c->height_px);
        if (p->reduced) {
            int w = upscale_low_res_px(c->width_px, scale), h = upscale_low_res_px(c->height_px, scale);
            c->lowres_view = c->view;
            c->lowres_view.camera = camera_basis_window(camera, c->plane_aspect, c->window, w, h);
            targets[i] = (traverser_target){.view = &c->lowres_view, .rgb = active ? c->lowres : NULL,
                                            .img = &b->meta};
            c->first_band = bands;
            if (active)
                bands += (uint32_t)((c->height_px + p->cfg.tile_px - 1) / p->cfg.tile_px);
            continue;
        }
        targets[i] = (traverser_target){.view = &c->view, .rgb = active ? b->rgb : NULL, .sink = sink,
                                        .img = &b->meta, .overlay = c->overlay_on ? &c->overlay : NULL};
        if (accumulate) {
            targets[i].accum = c->accum;
            targets[i].accum_samples = (float)plan->samples;
            targets[i].accum_reset = plan->kind == GOVERNOR_FRAME_ACCUMULATE && plan->stratum == 0;
            targets[i].resolve_only = plan->kind == GOVERNOR_FRAME_RESOLVE;
        }
    }
    if (p->reduced) {
        p->upscale_items = bands;
        atomic_store_explicit(&p->upscale_next, 0, memory_order_relaxed);
        p->rung_traversers[plan->rung]->ops->begin_frame(p->rung_traversers[plan->rung], targets);
    } else
        p->traverser->ops->begin_frame(p->traverser, targets);
}

/* Whether a one-shot is due at `frame` (queue_lock held). One due at a later
 * frame is not work for an idle step: frames do not advance while idle, so
 * waking for it would spin. */
static bool oneshot_due(const pipeline *p, uint64_t frame)
{
    for (size_t i = 0; i < p->oneshot_count; i++)
        if (p->oneshots[i].due_frame <= frame)
            return true;
    return false;
}

/* Governor, real time: the previous step was idle; wait (in the serial
 * section, every render thread asleep at the barrier) until a transaction, a
 * one-shot or a stop arrives, or PIPELINE_IDLE_POLL_S passes (serial
 * animation, e.g. an idle clock, runs then). */
static void wait_while_idle(pipeline *p)
{
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until); /* pthread_cond_timedwait's default clock */
    long ns = until.tv_nsec + (long)(PIPELINE_IDLE_POLL_S * 1e9);
    until.tv_sec += ns / 1000000000L;
    until.tv_nsec = ns % 1000000000L;
    pthread_mutex_lock(&p->queue_lock);
    while (p->queue_count == 0 && !oneshot_due(p, p->next_frame) && !atomic_load(&p->stop_requested))
        if (pthread_cond_timedwait(&p->queue_changed, &p->queue_lock, &until) == ETIMEDOUT)
            break;
    pthread_mutex_unlock(&p->queue_lock);
}

/* A reduced frame needs every thread's upscale scratch (made once per thread,
 * here in the serial section); false, logged, when there is no memory for it
 * (the frame is then rendered at full size). */
static bool have_upscale_scratch(pipeline *p, int threads)
{
    for (int i = 0; i < threads; i++)
        if (!p->threads[i].upscale_scratch) {
            p->threads[i].upscale_scratch = malloc(p->upscale_scratch_floats * sizeof(float));
            if (!p->threads[i].upscale_scratch) {
                log_error("pipeline: no memory for upscaling on thread %d: this frame renders at full size", i);
                return false;
            }
        }
    return true;
}

/* A fixed render scale (no governor): every frame at rung 1, with the config's sampler. */
static void plan_fixed_scale_frame(pipeline *p, int threads)
{
    bool scratch = have_upscale_scratch(p, threads);
    p->frame_plan = (governor_frame){GOVERNOR_FRAME_SCALED, scratch ? 1 : 0, 0, 1};
    p->reduced = scratch;
    p->frame_sampler = p->cfg.sampler;
}

governor_cost pipeline_step_cost(const pipeline *p)
{
    const loop_step *s = &p->step;
    return (governor_cost){s->info.last_frame_s, s->info.last_render_s, p->last_upscale_s, p->last_step_pixels};
}

void pipeline_set_step_cost(pipeline *p, const governor_cost *cost)
{
    p->step_cost = *cost;
    p->step_cost_set = true;
}

/* Governor: feed it what the previous frame cost, plan this one, and make
 * sure the threads have upscale scratch for a reduced frame. Sets
 * frame_plan, frame_sampler and reduced. */
static void plan_governed_frame(pipeline *p, int threads)
{
    const loop_step *s = &p->step;
    if (p->last_step_pixels > 0.0) { /* the previous step rendered: what did it cost? */
        governor_cost cost = p->step_cost_set ? p->step_cost : pipeline_step_cost(p);
        uint64_t over = p->gov.frames_over_budget;
        governor_observe(&p->gov, &p->frame_plan, &cost);
        if (p->gov.frames_over_budget != over) {
            pthread_mutex_lock(&p->stats_lock);
            p->stats.frames_over_budget++;
            pthread_mutex_unlock(&p->stats_lock);
        }
    }
    bool picture_changed = p->state.picture_serial != p->planned_picture_serial || p->parallel_anim_count > 0;
    bool overlay_changed = p->state.overlay_serial != p->planned_overlay_serial;
    governor_mode before = p->gov.mode;
    int rung_before = p->frame_plan.rung;
    p->step_cost_set = false;
    governor_frame f = governor_plan(&p->gov, s->info.time_s, picture_changed, overlay_changed, p->rung_pixels);
    if (p->plan_sync) /* several processes: the leader's plan for all (cluster/) */
        p->plan_sync(p->plan_sync_ctx, s->info.frame, &f);
    if (f.kind == GOVERNOR_FRAME_SCALED && f.rung > 0 && !have_upscale_scratch(p, threads))
        f.rung = 0;
    p->frame_plan = f;
    p->planned_picture_serial = p->state.picture_serial;
    if (p->state.governor_status_shown)
        pipeline_compose_status(p); /* the line describes this frame's plan */
    /* the drawn text changed while idle: show it */
    if (p->state.overlay_serial != p->planned_overlay_serial && p->frame_plan.kind == GOVERNOR_FRAME_IDLE)
        p->frame_plan.kind = GOVERNOR_FRAME_RESOLVE;
    p->planned_overlay_serial = p->state.overlay_serial;
    f = p->frame_plan;
    p->reduced = f.kind == GOVERNOR_FRAME_SCALED && f.rung > 0;
    p->frame_sampler = f.kind == GOVERNOR_FRAME_ACCUMULATE
                           ? pixel_sampler_stratum(p->cfg.refine_k, p->cfg.sampler.seed, f.stratum)
                           : pixel_sampler_single();
    if (p->gov.mode != before) {
        char line[PIPELINE_STATUS_BYTES];
        governor_describe(&p->gov, &f, line, sizeof line);
        log_info("pipeline: frame %llu: %s", (unsigned long long)s->info.frame, line);
    } else if (f.kind == GOVERNOR_FRAME_SCALED && f.rung != rung_before)
        log_debug("pipeline: frame %llu: governor: scale %.3g -> %.3g (predicted %.1f ms, budget %.1f ms)",
                  (unsigned long long)s->info.frame, p->rung_scale[rung_before], p->rung_scale[f.rung],
                  1e3 * governor_predict_s(&p->gov, f.rung, p->rung_pixels), p->cfg.budget_ms);
    p->last_step_pixels = 0.0;
    if (f.kind == GOVERNOR_FRAME_SCALED || f.kind == GOVERNOR_FRAME_ACCUMULATE) {
        for (int i = 0; i < p->channel_count; i++)
            if (p->state.active[i]) {
                double w = p->channels[i].width_px, h = p->channels[i].height_px;
                if (p->reduced) {
                    w = upscale_low_res_px(p->channels[i].width_px, p->rung_scale[f.rung]);
                    h = upscale_low_res_px(p->channels[i].height_px, p->rung_scale[f.rung]);
                }
                p->last_step_pixels += w * h;
            }
    }
}

/* The serial section of the frame barrier; returns the threads of the next step. */
static int serial_section_steps(pipeline *p)
{
    tls_serial_owner = p;
    pipeline_join_departed(p, p->thread_count);
    finish_previous_step(p);
    loop_step *s = &p->step;
    if (p->exit_after_step) {
        s->render = s->display = s->animate_parallel = false;
        s->exit = true;
        tls_serial_owner = NULL;
        return -1;
    }
    if (s->info.idle && p->cfg.time_mode == PIPELINE_TIME_REAL) {
        double w0 = pipeline_now_s();
        wait_while_idle(p);
        p->serial_s -= pipeline_now_s() - w0; /* waiting for work is not serial work */
    }
    double now = pipeline_now_s();
    uint64_t frame = p->next_frame, step = p->next_step;
    s->info.frame = frame;
    s->info.idle = false;
    s->info.last_frame_s = frame == 0 ? 0.0 : now - p->last_serial_s;
    s->info.last_render_s = frame == 0 ? 0.0 : p->last_render_s;
    p->last_serial_s = now;
    if (frame == 0)
        p->start_s = now;
    s->info.time_s = p->cfg.time_mode == PIPELINE_TIME_FIXED_RATE ? (double)step / p->cfg.rate_hz : now - p->start_s;
    s->info.threads = p->thread_count;
    /* a frame that will not render gets no callbacks (a stop asked for by one
     * of this barrier's transactions is seen after them) */
    bool stop = atomic_load(&p->stop_requested) || p->display_failed ||
                (p->cfg.max_frames > 0 && step >= p->cfg.max_frames);
    if (!stop) {
        run_transactions(p);
        run_oneshots(p, frame);
        run_serial_animation(p);
        stop = atomic_load(&p->stop_requested);
    }
    if (p->frame_sync) /* where processes meet: the leader's time, records and stop (cluster/) */
        p->frame_sync(p->frame_sync_ctx, p, &s->info, &stop);
    /* visibility changed by this barrier's records reaches the accel: one pass over the ids
     * they touched, accel_set_hidden only where a flag differs */
    frame_state_sync_accel(&p->state, p->cfg.accel);
    if (!p->closed_prepared && p->cfg.settings.caps && clip_planes_on(frame_state_clip_planes(&p->state))) {
        /* caps ask which parts are closed: answered here for all of them, not by a render thread mid-frame */
        scene_prepare_closed(p->cfg.scene, p->state.threads);
        p->closed_prepared = true;
    }
    bool any_queued = false;
    for (int i = 0; i < p->channel_count; i++)
        any_queued = any_queued || p->channels[i].queued_valid;
    /* displays with an end_stage hook are served every step, frames or not (a wall
     * whose monitors are all unplugged still has to notice one coming back) */
    s->frames_queued = any_queued;
    /* with a display sync (a wall of several machines) the display stage runs every step also
     * after a display failed: its barrier is one the other processes wait at */
    s->display = (any_queued || (!stop && p->displays_every_stage) || p->display_sync) &&
                 (!p->display_failed || p->display_sync);
    if (stop) {
        s->render = s->animate_parallel = false;
        p->exit_after_step = true;
        s->exit = !s->display; /* nothing left to show: leave now */
        tls_serial_owner = NULL;
        return -1;
    }
    int threads = change_thread_count(p);
    s->info.threads = threads;
    s->exit = false;
    p->next_step = step + 1;
    if (p->governed) {
        plan_governed_frame(p, threads);
        if (p->frame_plan.kind == GOVERNOR_FRAME_IDLE) {
            s->info.idle = true;
            s->render = s->animate_parallel = false;
            tls_serial_owner = NULL;
            return threads;
        }
    } else if (p->fixed_scale)
        plan_fixed_scale_frame(p, threads);
    if (p->reduced)
        pipeline_barrier_set_participants(&p->upscale_barrier, threads);
    s->render = true;
    s->animate_parallel = p->parallel_anim_count > 0;
    if (s->animate_parallel)
        pipeline_barrier_set_participants(&p->anim_barrier, threads);
    freeze_frame(p);
    p->next_frame = frame + 1;
    tls_serial_owner = NULL;
    return threads;
}

/* The serial section, its log lines kept for thread 0 (flush_barrier_log). */
int pipeline_serial_section(pipeline *p)
{
    double t0 = pipeline_now_s();
    /* the previous barrier's release: when its last thread left (threads that left the
     * loop there, or started then, have an older or no timestamp and do not count) */
    if (p->serial_end_s > 0.0) {
        double last = p->serial_end_s;
        for (int i = 0; i < p->released_threads; i++)
            if (p->threads[i].left_barrier_s > last)
                last = p->threads[i].left_barrier_s;
        p->release_s += last - p->serial_end_s;
    }
    log_divert_thread(keep_barrier_log, p);
    int threads = serial_section_steps(p);
    log_divert_thread(NULL, NULL);
    p->serial_end_s = pipeline_now_s();
    p->serial_s += p->serial_end_s - t0;
    p->serial_sections++;
    p->released_threads = threads > 0 ? threads : p->thread_count;
    return threads;
}
