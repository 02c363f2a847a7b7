/* governor.c - the frame-budget governor's state machine and cost model (see
 * governor.h). */
#include "governor.h"

#include <math.h>
#include <stdio.h>

#include "engine/render/sampler.h"
#include "engine/render/upscale.h"

const double GOVERNOR_SCALES[GOVERNOR_RUNGS] = {1.0, 0.875, 0.75, 0.625, 0.5, 0.375, 0.25};

bool governor_config_validate(const governor_config *cfg, tess_error *err)
{
    if (!(cfg->budget_s > 0.0) || !isfinite(cfg->budget_s))
        return tess_error_set(err, "governor: budget: %g ms is not a positive time", 1e3 * cfg->budget_s);
    if (!(cfg->still_s >= 0.0) || !isfinite(cfg->still_s))
        return tess_error_set(err, "governor: still time: %g s is not a time >= 0", cfg->still_s);
    if (cfg->refine_k < 1 || cfg->refine_k > PIXEL_SAMPLER_MAX_K)
        return tess_error_set(err, "governor: refine k: %d is not in 1..%d", cfg->refine_k, PIXEL_SAMPLER_MAX_K);
    return true;
}

void governor_init(governor *g, const governor_config *cfg, double output_pixels)
{
    *g = (governor){0};
    g->cfg = *cfg;
    g->output_pixels = output_pixels;
    g->mode = GOVERNOR_MOVING;
    g->rung = 0;
    g->changed_at_s = 0.0;
}

double governor_rung_pixels(int rung, const int *widths_px, const int *heights_px, int channels)
{
    double scale = GOVERNOR_SCALES[rung < 0 ? 0 : rung >= GOVERNOR_RUNGS ? GOVERNOR_RUNGS - 1 : rung];
    double pixels = 0.0;
    for (int i = 0; i < channels; i++)
        pixels += (double)upscale_low_res_px(widths_px[i], scale) * (double)upscale_low_res_px(heights_px[i], scale);
    return pixels;
}

static double ema(double old, bool have_old, double sample)
{
    return have_old ? old + GOVERNOR_EMA_WEIGHT * (sample - old) : sample;
}

double governor_predict_s(const governor *g, int rung, const double *rung_pixels)
{
    double s = g->overhead_s + g->pixel_s * rung_pixels[rung];
    if (rung > 0)
        s += g->upscale_s;
    return s;
}

/* The moving frames' rung for the next frame (see governor.h, THE SCALE LADDER). */
static int choose_rung(const governor *g, const double *rung_pixels)
{
    if (!g->have_pixel_s)
        return g->rung; /* nothing measured yet: the first frame shows what full size costs */
    const double budget = g->cfg.budget_s;
    int r = g->rung;
    if (governor_predict_s(g, r, rung_pixels) > GOVERNOR_HIGH_FRACTION * budget) {
        int down = r;
        while (down + 1 < GOVERNOR_RUNGS && governor_predict_s(g, down, rung_pixels) > GOVERNOR_TARGET_FRACTION * budget)
            down++;
        return down;
    }
    if (r > 0 && governor_predict_s(g, r - 1, rung_pixels) <= GOVERNOR_TARGET_FRACTION * budget)
        return r - 1;
    return r;
}

governor_frame governor_plan(governor *g, double time_s, bool picture_changed, bool overlay_changed,
                             const double *rung_pixels)
{
    if (picture_changed) {
        g->mode = GOVERNOR_MOVING;
        g->changed_at_s = time_s;
        g->resolve_pending = false;
    }
    if (g->mode == GOVERNOR_MOVING && !picture_changed && time_s - g->changed_at_s >= g->cfg.still_s) {
        g->mode = GOVERNOR_REFINING;
        g->stratum_next = 0;
    }
    const int total = g->cfg.refine_k * g->cfg.refine_k;
    switch (g->mode) {
    case GOVERNOR_MOVING:
        g->rung = choose_rung(g, rung_pixels);
        return (governor_frame){GOVERNOR_FRAME_SCALED, g->rung, 0, 1};
    case GOVERNOR_REFINING: {
        int stratum = g->stratum_next++;
        if (g->stratum_next == total)
            g->mode = GOVERNOR_CONVERGED;
        return (governor_frame){GOVERNOR_FRAME_ACCUMULATE, 0, stratum, stratum + 1};
    }
    case GOVERNOR_CONVERGED:
    default:
        if (overlay_changed || g->resolve_pending) {
            g->resolve_pending = false;
            return (governor_frame){GOVERNOR_FRAME_RESOLVE, 0, 0, total};
        }
        return (governor_frame){GOVERNOR_FRAME_IDLE, 0, 0, total};
    }
}

void governor_observe(governor *g, const governor_frame *f, const governor_cost *c)
{
    if (f->kind == GOVERNOR_FRAME_IDLE || f->kind == GOVERNOR_FRAME_RESOLVE)
        return; /* no rays: says nothing about their cost */
    double outside = c->step_s - c->render_s;
    if (outside < 0.0)
        outside = 0.0;
    g->overhead_s = ema(g->overhead_s, g->have_overhead_s, outside);
    g->have_overhead_s = true;
    double tracing_s = c->render_s - c->upscale_s;
    if (c->pixels > 0.0 && tracing_s > 0.0) {
        g->pixel_s = ema(g->pixel_s, g->have_pixel_s, tracing_s / c->pixels);
        g->have_pixel_s = true;
    }
    if (f->kind == GOVERNOR_FRAME_SCALED && f->rung > 0) {
        g->upscale_s = ema(g->upscale_s, g->have_upscale_s, c->upscale_s);
        g->have_upscale_s = true;
    }
    if (f->kind == GOVERNOR_FRAME_SCALED && c->step_s > g->cfg.budget_s)
        g->frames_over_budget++;
}

void governor_describe(const governor *g, const governor_frame *f, char *buf, unsigned size)
{
    const int total = g->cfg.refine_k * g->cfg.refine_k;
    switch (f->kind) {
    case GOVERNOR_FRAME_SCALED:
        snprintf(buf, size, "governor: moving, scale %.3g (budget %.0f ms)", GOVERNOR_SCALES[f->rung],
                 1e3 * g->cfg.budget_s);
        break;
    case GOVERNOR_FRAME_ACCUMULATE:
        if (f->samples < total)
            snprintf(buf, size, "governor: refining, %d/%d samples", f->samples, total);
        else /* the last sample converges */
            snprintf(buf, size, "governor: converged, %d samples", total);
        break;
    case GOVERNOR_FRAME_RESOLVE:
    case GOVERNOR_FRAME_IDLE:
    default:
        snprintf(buf, size, "governor: converged, %d samples", total);
        break;
    }
}
