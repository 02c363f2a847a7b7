/* pipeline.c - the life of a pipeline: created from a config, run (its
 * traversers made once the channels are known, with the governor's or a
 * render scale's buffers; the loop itself is pipeline_stages.c's and
 * pipeline_serial.c's), destroyed. See pipeline.h for the model and
 * pipeline_private.h for the files and which lock or stage guards each field. */
#include "pipeline_private.h"

#include <assert.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "engine/scene/accel.h"
#include "engine/base/log.h"
#include "engine/scene/scene.h"

/* The part opacities the scene starts with (scene_instance.opacity); false
 * on no memory. */
static bool start_opacities(frame_state *st, const scene *s)
{
    for (uint32_t i = 0; s && i < s->instance_count; i++)
        if (s->instances[i].opacity != 1.f && !frame_state_set_opacity(st, i, 1, s->instances[i].opacity))
            return false;
    return true;
}

pipeline *pipeline_create(const pipeline_config *cfg, tess_error *err)
{
    if (!pipeline_config_validate(cfg, err))
        return NULL;
    pipeline *p = calloc(1, sizeof *p);
    queued_call *queue = malloc(PIPELINE_QUEUE_MAX * sizeof *queue);
    queued_call *oneshots = malloc(PIPELINE_QUEUE_MAX * sizeof *oneshots);
    queued_call *scratch = malloc(PIPELINE_QUEUE_MAX * sizeof *scratch);
    if (!p || !queue || !oneshots || !scratch) {
        free(p);
        free(queue);
        free(oneshots);
        free(scratch);
        tess_error_set(err, "pipeline: out of memory");
        return NULL;
    }
    p->cfg = *cfg;
    p->queue = queue;
    p->oneshots = oneshots;
    p->oneshot_scratch = scratch;
    frame_state_init(&p->state, cfg->renderer, cfg->shadows, cfg->threads, accel_geometry_count(cfg->accel));
    p->frame_renderer = cfg->renderer;
    /* an earlier user's hidden flags, and the part opacities the scene starts with */
    if (!frame_state_adopt_hidden(&p->state, cfg->accel) || !start_opacities(&p->state, cfg->scene)) {
        frame_state_finish(&p->state);
        free(p);
        free(queue);
        free(oneshots);
        free(scratch);
        tess_error_set(err, "pipeline: out of memory");
        return NULL;
    }
    /* where inspection starts: as records, so the planes are normalised as input's are (validated above) */
    if (cfg->opacity != 1.f)
        frame_state_set_global_opacity(&p->state, cfg->opacity);
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        if (!pipeline_plane_unused(&cfg->clip[i])) {
            txn_record r = pipeline_plane_record(i, &cfg->clip[i]);
            tess_error unused = {{0}};
            bool applied = txn_apply(&r, &p->state, &unused);
            assert(applied); /* pipeline_config_validate checked it; a plane allocates nothing */
            (void)applied;
        }
    pthread_mutex_init(&p->queue_lock, NULL);
    pthread_cond_init(&p->queue_changed, NULL);
    pthread_mutex_init(&p->stats_lock, NULL);
    pipeline_barrier_init(&p->frame_barrier);
    pipeline_barrier_init(&p->anim_barrier);
    pipeline_barrier_init(&p->upscale_barrier);
    p->frame_plan = (governor_frame){GOVERNOR_FRAME_SCALED, 0, 0, 1};
    p->frame_sampler = cfg->sampler;
    atomic_init(&p->upscale_next, 0);
    atomic_init(&p->stop_requested, false);
    atomic_init(&p->running, false);
    p->thread_count = 1;
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++) {
        p->threads[i].p = p;
        p->threads[i].id = i;
    }
    return p;
}

/* Reduced frames (a governor, or a fixed render scale): per rung above 0 a
 * tiled traverser of the low-res sizes and each channel's upscale plan, the
 * low-res buffers (rung 1 is the largest) and, with a governor, the
 * accumulation buffers. pipeline_run, before the loop; per-thread scratch
 * comes later (have_upscale_scratch). */
static bool reduced_setup(pipeline *p, const int *widths, const int *heights, tess_error *err)
{
    const char *who = p->governed ? "governor" : "render scale";
    for (int r = 1; r < p->rung_count; r++) {
        int low_w[PIPELINE_MAX_CHANNELS], low_h[PIPELINE_MAX_CHANNELS];
        for (int i = 0; i < p->channel_count; i++) {
            low_w[i] = upscale_low_res_px(widths[i], p->rung_scale[r]);
            low_h[i] = upscale_low_res_px(heights[i], p->rung_scale[r]);
        }
        p->rung_traversers[r] = traverser_tiled_create(p->cfg.tile_px, p->cfg.order, p->cfg.order_seed, low_w, low_h,
                                                       p->channel_count, err);
        if (!p->rung_traversers[r])
            return false;
        for (int i = 0; i < p->channel_count; i++) {
            pipe_channel *c = &p->channels[i];
            c->plans[r] = upscale_plan_create(low_w[i], low_h[i], widths[i], heights[i], p->cfg.upscale, err);
            if (!c->plans[r]) {
                tess_error_prefix(err, "pipeline: %s: channel %d: ", who, i);
                return false;
            }
            size_t need = upscale_plan_scratch_floats(c->plans[r]);
            if (need > p->upscale_scratch_floats)
                p->upscale_scratch_floats = need;
        }
    }
    for (int i = 0; i < p->channel_count; i++) {
        pipe_channel *c = &p->channels[i];
        size_t full = (size_t)widths[i] * (size_t)heights[i] * 3;
        size_t low = (size_t)upscale_low_res_px(widths[i], p->rung_scale[1]) *
                     (size_t)upscale_low_res_px(heights[i], p->rung_scale[1]) * 3;
        c->lowres = calloc(low, sizeof(float));
        if (p->governed)
            c->accum = calloc(full, sizeof(float));
        if (!c->lowres || (p->governed && !c->accum))
            return tess_error_set(err, "pipeline: %s: channel %d: out of memory for its %dx%d buffers", who, i,
                                  widths[i], heights[i]);
    }
    return true;
}

/* The governor (budget_ms > 0) or a fixed render scale (render_scale < 1):
 * the rungs in use, the governor's state, the buffers. */
static bool scale_setup(pipeline *p, const int *widths, const int *heights, tess_error *err)
{
    if (p->cfg.budget_ms > 0.0) {
        governor_config g = {p->cfg.budget_ms * 1e-3, p->cfg.still_s, p->cfg.refine_k};
        double output_pixels = 0.0;
        for (int i = 0; i < p->channel_count; i++)
            output_pixels += (double)widths[i] * (double)heights[i];
        governor_init(&p->gov, &g, output_pixels);
        for (int r = 0; r < GOVERNOR_RUNGS; r++) {
            p->rung_pixels[r] = governor_rung_pixels(r, widths, heights, p->channel_count);
            p->rung_scale[r] = GOVERNOR_SCALES[r];
        }
        p->rung_count = GOVERNOR_RUNGS;
        p->governed = true;
        p->frame_sampler = pixel_sampler_single();
    } else if (p->cfg.render_scale < 1.0) {
        p->rung_scale[0] = 1.0;
        p->rung_scale[1] = p->cfg.render_scale;
        p->rung_count = 2;
        p->fixed_scale = true;
    } else
        return true;
    if (!reduced_setup(p, widths, heights, err))
        return false;
    p->frame_plan = (governor_frame){GOVERNOR_FRAME_SCALED, 0, 0, 1};
    if (p->governed)
        log_info("pipeline: governor: budget %.1f ms, scales 1..%.3g (%s upscaling), refining to jittered:%d after "
                 "%.2f s still",
                 p->cfg.budget_ms, GOVERNOR_SCALES[GOVERNOR_RUNGS - 1], upscale_filter_name(p->cfg.upscale),
                 p->cfg.refine_k, p->cfg.still_s);
    return true;
}

bool pipeline_run(pipeline *p, tess_error *err)
{
    if (pipeline_in_serial_section(p)) {
        log_error("pipeline_run: called from inside the pipeline (a transaction or serial callback): refused");
        return tess_error_set(err, "pipeline_run: called from inside the pipeline");
    }
    if (p->ran)
        return tess_error_set(err, "pipeline_run: the pipeline has already run");
    if (p->channel_count == 0)
        return tess_error_set(err, "pipeline: no channels to render");
    int widths[PIPELINE_MAX_CHANNELS], heights[PIPELINE_MAX_CHANNELS];
    for (int i = 0; i < p->channel_count; i++) {
        widths[i] = p->channels[i].width_px;
        heights[i] = p->channels[i].height_px;
        p->displays_every_stage = p->displays_every_stage || p->channels[i].display->ops->end_stage != NULL;
    }
    p->traverser = traverser_tiled_create(p->cfg.tile_px, p->cfg.order, p->cfg.order_seed, widths, heights,
                                          p->channel_count, err);
    if (!p->traverser)
        return false;
    if (!scale_setup(p, widths, heights, err))
        return false;
    p->ran = true;
    atomic_store(&p->running, true);
    double t0 = pipeline_now_s();
    /* the first barrier has this thread alone: its serial section starts the others */
    p->thread_count = 1;
    pipeline_barrier_set_participants(&p->frame_barrier, 1);
    pipeline_barrier_wait(&p->frame_barrier, p, pipeline_serial_section);
    pipeline_frame_loop(&p->threads[0]);
    pipeline_join_departed(p, 1);
    double barrier_s = 0.0; /* every thread has been joined: their totals are final */
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++)
        barrier_s += p->threads[i].barrier_s;
    double run_s = pipeline_now_s() - t0;
    /* what is still queued will never run: count it (every accepted transaction is
     * applied or discarded), and empty the queue so the counts stay exact */
    pthread_mutex_lock(&p->queue_lock);
    p->closed = true;
    size_t discarded = p->queue_count;
    p->queue_head = (p->queue_head + p->queue_count) % PIPELINE_QUEUE_MAX;
    p->queue_count = 0;
    pthread_mutex_unlock(&p->queue_lock);
    if (discarded)
        log_info("pipeline: %zu transaction%s queued before the stop not applied (the loop had ended)", discarded,
                 discarded == 1 ? "" : "s");
    for (int i = 0; i < p->termination_count; i++)
        p->terminations[i].fn(p, p->terminations[i].ctx);
    atomic_store(&p->running, false);
    pthread_mutex_lock(&p->stats_lock);
    p->stats.run_s = run_s;
    p->stats.barrier_s = barrier_s;
    p->stats.serial_s = p->serial_s;
    p->stats.release_s = p->release_s;
    p->stats.serial_sections = p->serial_sections;
    p->stats.transactions_discarded += discarded;
    pthread_mutex_unlock(&p->stats_lock);
    if (p->display_failed)
        return tess_error_set(err, "%s", p->display_error.msg);
    return true;
}

void pipeline_destroy(pipeline *p)
{
    if (!p)
        return;
    if (pipeline_in_serial_section(p) || atomic_load(&p->running)) {
        log_error("pipeline_destroy: the pipeline is running; refused (stop it and let pipeline_run return)");
        return;
    }
    for (int i = 0; i < p->channel_count; i++)
        pipeline_channel_free(&p->channels[i]);
    image_traverser_destroy(p->traverser);
    pipeline_barrier_destroy(&p->frame_barrier);
    pipeline_barrier_destroy(&p->anim_barrier);
    pipeline_barrier_destroy(&p->upscale_barrier);
    for (int r = 0; r < GOVERNOR_RUNGS; r++)
        image_traverser_destroy(p->rung_traversers[r]);
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++)
        free(p->threads[i].upscale_scratch);
    pthread_cond_destroy(&p->queue_changed);
    pthread_mutex_destroy(&p->queue_lock);
    pthread_mutex_destroy(&p->stats_lock);
    free(p->queue);
    free(p->oneshots);
    free(p->oneshot_scratch);
    frame_state_finish(&p->state);
    free(p);
}
