/* pipeline_config.c - what a pipeline is given: the config (defaults and
 * checks), its channels and their buffers, the cluster hooks, private
 * channels and the status line's corner (all before the run), and the
 * animation and termination callbacks (before the run or in the serial
 * section). */
#include "pipeline_private.h"

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/log.h"

/* ---------------------------------------------------------------- config */

pipeline_config pipeline_config_default(const struct scene *s, const struct accel *a)
{
    pipeline_config c;
    memset(&c, 0, sizeof c);
    c.scene = s;
    c.accel = a;
    c.threads = 1;
    c.time_mode = PIPELINE_TIME_REAL;
    c.rate_hz = 30.0;
    c.max_frames = 0;
    c.tile_px = RENDER_TILE_PX;
    c.order = TILE_ORDER_ROWS;
    c.order_seed = 1;
    c.sampler = pixel_sampler_single();
    c.renderer = renderer_by_name("raytracer");
    c.shadows = true;
    c.budget_ms = 0.0;
    c.still_s = GOVERNOR_DEFAULT_STILL_S;
    c.refine_k = GOVERNOR_DEFAULT_REFINE_K;
    c.upscale = UPSCALE_BILINEAR;
    c.render_scale = 1.0;
    c.settings = render_settings_default();
    c.opacity = 1.f; /* the planes: all unused (zeroed) */
    return c;
}

static bool settings_validate(const render_settings *s, tess_error *err)
{
    if (!(s->min_transmittance > 0.f && s->min_transmittance < 1.f))
        return tess_error_set(err, "pipeline: settings.min_transmittance: %g is not in (0, 1)",
                              (double)s->min_transmittance);
    if (s->max_layers < 1 || s->max_layers > PIPELINE_MAX_LAYERS_MAX)
        return tess_error_set(err, "pipeline: settings.max_layers: %d is not in 1..%d", s->max_layers,
                              PIPELINE_MAX_LAYERS_MAX);
    if (s->cap_style != RENDER_CAP_TINT && s->cap_style != RENDER_CAP_HATCH)
        return tess_error_set(err, "pipeline: settings.cap_style: unknown style %d", (int)s->cap_style);
    if (s->ao_rays < 1 || s->ao_rays > PIPELINE_AO_RAYS_MAX)
        return tess_error_set(err, "pipeline: settings.ao_rays: %d is not in 1..%d", s->ao_rays,
                              PIPELINE_AO_RAYS_MAX);
    if (!isfinite(s->ao_distance) || s->ao_distance < 0.f)
        return tess_error_set(err, "pipeline: settings.ao_distance: %g is not a distance >= 0 (0: from the scene)",
                              (double)s->ao_distance);
    if (s->ao_interleave < 1 || s->ao_interleave > PIPELINE_AO_INTERLEAVE_MAX)
        return tess_error_set(err, "pipeline: settings.ao_interleave: %d is not in 1..%d", s->ao_interleave,
                              PIPELINE_AO_INTERLEAVE_MAX);
    if (s->ao_filter_px < 1 || s->ao_filter_px > PIPELINE_AO_FILTER_PX_MAX || s->ao_filter_px % 2 == 0)
        return tess_error_set(err, "pipeline: settings.ao_filter_px: %d is not odd in 1..%d", s->ao_filter_px,
                              PIPELINE_AO_FILTER_PX_MAX);
    if (s->ao_frames < 1 || s->ao_frames > PIPELINE_AO_FRAMES_MAX)
        return tess_error_set(err, "pipeline: settings.ao_frames: %d is not in 1..%d", s->ao_frames,
                              PIPELINE_AO_FRAMES_MAX);
    if (!(s->ao_exponent >= 1.f && s->ao_exponent <= RENDER_AO_EXPONENT_MAX))
        return tess_error_set(err, "pipeline: settings.ao_exponent: %g is not in [1, %g]", (double)s->ao_exponent,
                              (double)RENDER_AO_EXPONENT_MAX);
    return true;
}

/* An initial plane the config leaves unused: off, zero normal (a zeroed entry). */
bool pipeline_plane_unused(const clip_plane *c)
{
    return !c->on && c->normal.x == 0.f && c->normal.y == 0.f && c->normal.z == 0.f;
}

txn_record pipeline_plane_record(int index, const clip_plane *c)
{
    const float point[3] = {c->point.x, c->point.y, c->point.z}, normal[3] = {c->normal.x, c->normal.y, c->normal.z};
    return txn_clip_plane(index, c->on, point, normal);
}

bool pipeline_config_validate(const pipeline_config *cfg, tess_error *err)
{
    if (!cfg->scene || !cfg->accel)
        return tess_error_set(err, "pipeline: no scene or acceleration structure");
    if (cfg->threads < 1 || cfg->threads > PIPELINE_MAX_THREADS)
        return tess_error_set(err, "pipeline: threads: %d is not in 1..%d", cfg->threads, PIPELINE_MAX_THREADS);
    if (cfg->time_mode != PIPELINE_TIME_REAL && cfg->time_mode != PIPELINE_TIME_FIXED_RATE)
        return tess_error_set(err, "pipeline: unknown time mode %d", (int)cfg->time_mode);
    if (cfg->time_mode == PIPELINE_TIME_FIXED_RATE && !(cfg->rate_hz > 0.0 && isfinite(cfg->rate_hz)))
        return tess_error_set(err, "pipeline: rate_hz: %g is not a positive frame rate", cfg->rate_hz);
    if (cfg->tile_px < PIPELINE_TILE_PX_MIN || cfg->tile_px > PIPELINE_TILE_PX_MAX)
        return tess_error_set(err, "pipeline: tile_px: %d is not in %d..%d", cfg->tile_px, PIPELINE_TILE_PX_MIN,
                              PIPELINE_TILE_PX_MAX);
    if (!cfg->renderer)
        return tess_error_set(err, "pipeline: no renderer");
    if ((unsigned)cfg->order >= TILE_ORDER_COUNT)
        return tess_error_set(err, "pipeline: unknown tile order %d", (int)cfg->order);
    if (!pixel_sampler_validate(&cfg->sampler, err)) {
        tess_error_prefix(err, "pipeline: sampler: ");
        return false;
    }
    if (cfg->sampler.kind == PIXEL_SAMPLER_STRATUM)
        return tess_error_set(err, "pipeline: sampler: a stratum sampler is the governor's, not a config's");
    if (!(cfg->budget_ms >= 0.0) || !isfinite(cfg->budget_ms))
        return tess_error_set(err, "pipeline: budget_ms: %g is not a time >= 0 (0: no governor)", cfg->budget_ms);
    if (!upscale_scale_validate(cfg->render_scale, err)) {
        tess_error_prefix(err, "pipeline: render_scale: ");
        return false;
    }
    if (cfg->render_scale < 1.0 && cfg->budget_ms > 0.0)
        return tess_error_set(err, "pipeline: render_scale %g with budget_ms %g: the governor picks the scale",
                              cfg->render_scale, cfg->budget_ms);
    if ((unsigned)cfg->upscale > UPSCALE_CLAMPED_CUBIC)
        return tess_error_set(err, "pipeline: unknown upscale filter %d", (int)cfg->upscale);
    if (cfg->budget_ms > 0.0) {
        governor_config g = {cfg->budget_ms * 1e-3, cfg->still_s, cfg->refine_k};
        if (!governor_config_validate(&g, err)) {
            tess_error_prefix(err, "pipeline: ");
            return false;
        }
    }
    if (!settings_validate(&cfg->settings, err))
        return false;
    if (!isfinite(cfg->opacity) || cfg->opacity < 0.f || cfg->opacity > 1.f)
        return tess_error_set(err, "pipeline: opacity: %g is not in [0, 1]", (double)cfg->opacity);
    for (int i = 0; i < CLIP_MAX_PLANES; i++) {
        if (pipeline_plane_unused(&cfg->clip[i]))
            continue;
        txn_record r = pipeline_plane_record(i, &cfg->clip[i]);
        if (!txn_validate(&r, err)) {
            tess_error_prefix(err, "pipeline: clip[%d]: ", i);
            return false;
        }
    }
    return true;
}

/* ---------------------------------------------------------------- channels */

void pipeline_channel_free(pipe_channel *c)
{
    for (int b = 0; b < BUFFER_COUNT; b++)
        free(c->buffers[b].rgb_block);
    free(c->accum);
    free(c->lowres);
    for (int r = 0; r < GOVERNOR_RUNGS; r++)
        upscale_plan_destroy(c->plans[r]);
    image_display_destroy(c->display);
}

int pipeline_add_channel(pipeline *p, const camera_desc *camera, int width_px, int height_px, image_display *display,
                         tess_error *err)
{
    float aspect = height_px > 0 ? (float)width_px / (float)height_px : 1.f;
    return pipeline_add_channel_window(p, camera, aspect, CAMERA_WINDOW_FULL, width_px, height_px, display, err);
}

int pipeline_add_channel_window(pipeline *p, const camera_desc *camera, float plane_aspect, camera_window window,
                                int width_px, int height_px, image_display *display, tess_error *err)
{
    bool ok = true;
    if (p->ran || atomic_load(&p->running))
        ok = tess_error_set(err, "pipeline: channels can only be added before the pipeline runs");
    else if (p->channel_count == PIPELINE_MAX_CHANNELS)
        ok = tess_error_set(err, "pipeline: more than %d channels", PIPELINE_MAX_CHANNELS);
    else if (width_px < 1 || height_px < 1 || width_px > 65536 || height_px > 65536)
        ok = tess_error_set(err, "pipeline: channel %d: image size %dx%d is not in 1x1..65536x65536",
                            p->channel_count, width_px, height_px);
    else if (!display)
        ok = tess_error_set(err, "pipeline: channel %d has no display", p->channel_count);
    else if (!(plane_aspect > 0.f && isfinite(plane_aspect)) || !(window.half_width > 0.f) ||
             !(window.half_height > 0.f) || !isfinite(window.center_x) || !isfinite(window.center_y) ||
             !isfinite(window.half_width) || !isfinite(window.half_height))
        ok = tess_error_set(err, "pipeline: channel %d: degenerate window or plane aspect", p->channel_count);
    else if (!camera_validate(camera, err)) {
        tess_error_prefix(err, "pipeline: channel %d: ", p->channel_count);
        ok = false;
    }
    if (!ok) {
        image_display_destroy(display);
        return -1;
    }
    pipe_channel *c = &p->channels[p->channel_count];
    memset(c, 0, sizeof *c);
    c->width_px = width_px;
    c->height_px = height_px;
    c->plane_aspect = plane_aspect;
    c->window = window;
    c->display = display;
    /* the status line's corner: the bottom-left of every window so far */
    float left = window.center_x - window.half_width, bottom = window.center_y - window.half_height;
    if (p->channel_count == 0 || left < p->overlay.anchor_sx)
        p->overlay.anchor_sx = left;
    if (p->channel_count == 0 || bottom < p->overlay.anchor_sy)
        p->overlay.anchor_sy = bottom;
    size_t floats = (size_t)width_px * (size_t)height_px * 3;
    /* cache-line aligned, so a tile row shares lines with a neighbour tile only where the
     * image width makes it (16-pixel float RGB rows are whole lines) */
    size_t bytes = floats * sizeof(float) + 64;
    for (int b = 0; b < BUFFER_COUNT; b++)
        if ((c->buffers[b].rgb_block = calloc(1, bytes)))
            c->buffers[b].rgb = (float *)(((uintptr_t)c->buffers[b].rgb_block + 63) & ~(uintptr_t)63);
    bool have_memory = true;
    for (int b = 0; b < BUFFER_COUNT; b++)
        have_memory = have_memory && c->buffers[b].rgb != NULL;
    if (!have_memory) {
        pipeline_channel_free(c);
        memset(c, 0, sizeof *c);
        tess_error_set(err, "pipeline: channel %d: out of memory for its %dx%d frame buffers (%d of %.1f GiB each)",
                       p->channel_count, width_px, height_px, BUFFER_COUNT, (double)bytes / (1024.0 * 1024 * 1024));
        return -1;
    }
    c->pending = 0;
    c->queued = 1;
    c->on_screen = 2;
    frame_state_add_channel(&p->state, camera); /* its index is channel_count: both stop at the same maximum */
    return p->channel_count++;
}

/* ---------------------------------------------------------------- cluster hooks, private channels */

/* A cluster hook may be set once, before the run. */
static bool may_set_hook(const pipeline *p, bool already_set)
{
    if (p->ran || atomic_load(&p->running)) {
        log_error("pipeline: a cluster hook can be set only before the pipeline runs");
        return false;
    }
    return !already_set;
}

bool pipeline_set_record_observer(pipeline *p, pipeline_record_fn fn, void *ctx)
{
    if (!may_set_hook(p, p->record_observer != NULL))
        return false;
    p->record_observer = fn;
    p->record_observer_ctx = ctx;
    return true;
}

bool pipeline_set_frame_sync(pipeline *p, pipeline_sync_fn fn, void *ctx)
{
    if (!may_set_hook(p, p->frame_sync != NULL))
        return false;
    p->frame_sync = fn;
    p->frame_sync_ctx = ctx;
    return true;
}

bool pipeline_governed(const pipeline *p) { return p->cfg.budget_ms > 0.0; }

bool pipeline_set_plan_sync(pipeline *p, pipeline_plan_sync_fn fn, void *ctx)
{
    if (!pipeline_governed(p) || !may_set_hook(p, p->plan_sync != NULL))
        return false;
    p->plan_sync = fn;
    p->plan_sync_ctx = ctx;
    return true;
}

bool pipeline_set_display_sync(pipeline *p, pipeline_display_sync_fn fn, void *ctx)
{
    if (!may_set_hook(p, p->display_sync != NULL))
        return false;
    p->display_sync = fn;
    p->display_sync_ctx = ctx;
    return true;
}

bool pipeline_set_channel_private(pipeline *p, int channel, tess_error *err)
{
    if (p->ran || atomic_load(&p->running))
        return tess_error_set(err, "pipeline: a channel can be made private only before the pipeline runs");
    if (channel < 1 || channel >= p->channel_count)
        return tess_error_set(err, "pipeline: channel %d cannot be private (channels 1..%d may be; channel 0 is "
                                   "the wall's)",
                              channel, p->channel_count - 1);
    frame_state_set_private(&p->state, channel);
    return true;
}

bool pipeline_set_status_anchor(pipeline *p, float sx, float sy)
{
    if (p->ran || atomic_load(&p->running) || !isfinite(sx) || !isfinite(sy))
        return false;
    p->overlay.anchor_sx = sx;
    p->overlay.anchor_sy = sy;
    return true;
}

bool pipeline_channel_private(const pipeline *p, int channel)
{
    return channel >= 0 && channel < p->channel_count && p->state.private_view[channel];
}

/* ---------------------------------------------------------------- callbacks */

static bool may_register(const pipeline *p, const char *what, int count)
{
    if (!pipeline_may_change_state(p, what))
        return false;
    if (count >= PIPELINE_MAX_CALLBACKS) {
        log_error("pipeline: %s: more than %d registered", what, PIPELINE_MAX_CALLBACKS);
        return false;
    }
    return true;
}

bool pipeline_add_serial_animation(pipeline *p, const char *name, pipeline_serial_fn fn, void *ctx)
{
    if (!fn || !may_register(p, "serial animation callback", p->serial_anim_count))
        return false;
    p->serial_anim[p->serial_anim_count++] = (serial_callback){name ? name : "(unnamed)", fn, ctx};
    return true;
}

bool pipeline_add_parallel_animation(pipeline *p, const char *name, pipeline_parallel_fn fn, void *ctx)
{
    if (!fn || !may_register(p, "parallel animation callback", p->parallel_anim_count))
        return false;
    p->parallel_anim[p->parallel_anim_count++] = (parallel_callback){name ? name : "(unnamed)", fn, ctx};
    return true;
}

bool pipeline_add_termination(pipeline *p, const char *name, pipeline_termination_fn fn, void *ctx)
{
    if (!fn || !may_register(p, "termination callback", p->termination_count))
        return false;
    p->terminations[p->termination_count++] = (termination_callback){name ? name : "(unnamed)", fn, ctx};
    return true;
}
