/* display_upscale.c - the upscaling display in front of another (display_upscale.h). */
#include "display_upscale.h"

#include <stdlib.h>
#include <string.h>

#include "engine/clock.h"

typedef struct upscale_display {
    image_display base;
    image_display *inner;     /* owned; gets dst_w x dst_h frames */
    upscale_plan *plan;       /* src -> dst taps, read-only */
    int src_w, src_h, dst_w, dst_h;
    float *out_rgb;           /* dst_w * dst_h * 3: the frame handed to inner; display thread only */
    float *scratch;           /* upscale_plan_scratch_floats(plan); display thread only */
    uint64_t frames;          /* upscaled so far; display thread only */
    double upscale_s;         /* time spent in the upscale of those; display thread only */
} upscale_display;

static bool upscale_show(image_display *d, const frame_image *img, tess_error *err)
{
    upscale_display *ud = (upscale_display *)d;
    if (img->width_px != ud->src_w || img->height_px != ud->src_h)
        return tess_error_set(err, "upscale display: got a %dx%d frame, made for %dx%d", img->width_px,
                              img->height_px, ud->src_w, ud->src_h);
    double start_s = clock_monotonic_s();
    upscale_plan_rows(ud->plan, img->rgb, ud->out_rgb, 0, ud->dst_h, ud->scratch);
    ud->upscale_s += clock_monotonic_s() - start_s;
    ud->frames++;
    frame_image out = *img;
    out.rgb = ud->out_rgb;
    out.width_px = ud->dst_w;
    out.height_px = ud->dst_h;
    if (ud->inner->ops->write_tile)
        ud->inner->ops->write_tile(ud->inner, &out, 0, 0, ud->dst_w, ud->dst_h);
    return ud->inner->ops->show(ud->inner, &out, err);
}

static void upscale_destroy(image_display *d)
{
    upscale_display *ud = (upscale_display *)d;
    image_display_destroy(ud->inner);
    upscale_plan_destroy(ud->plan);
    free(ud->out_rgb);
    free(ud->scratch);
    free(ud);
}

static const image_display_ops upscale_ops = {.name = "upscale", .show = upscale_show, .destroy = upscale_destroy};

image_display *display_upscale_create(image_display *inner, int src_w, int src_h, int dst_w, int dst_h,
                                      upscale_filter filter, tess_error *err)
{
    if (!inner) {
        tess_error_set(err, "upscale display: no display behind it");
        return NULL;
    }
    if (inner->ops->end_stage) {
        tess_error_set(err, "upscale display: cannot go in front of the %s display (it commits outputs together)",
                       inner->ops->name);
        image_display_destroy(inner);
        return NULL;
    }
    upscale_display *ud = calloc(1, sizeof *ud);
    if (!ud) {
        tess_error_set(err, "upscale display: out of memory");
        image_display_destroy(inner);
        return NULL;
    }
    ud->base.ops = &upscale_ops;
    ud->inner = inner;
    ud->src_w = src_w;
    ud->src_h = src_h;
    ud->dst_w = dst_w;
    ud->dst_h = dst_h;
    if (!(ud->plan = upscale_plan_create(src_w, src_h, dst_w, dst_h, filter, err)))
        goto fail;
    ud->out_rgb = malloc((size_t)dst_w * (size_t)dst_h * 3 * sizeof *ud->out_rgb);
    ud->scratch = malloc(upscale_plan_scratch_floats(ud->plan) * sizeof *ud->scratch);
    if (!ud->out_rgb || !ud->scratch) {
        tess_error_set(err, "upscale display: out of memory for a %dx%d frame", dst_w, dst_h);
        goto fail;
    }
    /* touch every page now: the first frame's upscale would otherwise pay the page faults of the
     * whole output buffer (700 ms for 1920x1080 on a loaded VM, 25x the upscale itself) */
    memset(ud->out_rgb, 0, (size_t)dst_w * (size_t)dst_h * 3 * sizeof *ud->out_rgb);
    return &ud->base;
fail:
    upscale_destroy(&ud->base);
    return NULL;
}

void display_upscale_time(const image_display *d, uint64_t *frames, double *upscale_s)
{
    const upscale_display *ud = (const upscale_display *)d;
    *frames = ud->frames;
    *upscale_s = ud->upscale_s;
}
