/* dvr_medium.c - a volume rendered directly as a scene medium (dvr_medium.h). */
#include "dvr_medium.h"

#include <assert.h>
#include <stdlib.h>

struct dvr_medium {
    iso_volume *shared; /* one reference: keeps the volume and grid the dvr_volume points to */
    dvr_volume *dvr;    /* owned */
    iso_volume_watcher watcher; /* on shared: a time step swapped in is rendered from then on */
};

/* The shared volume swapped in a time step (a serial section): render its
 * samples. Its layout is step 0's (iso_volume_set_step checked it). */
static void volume_swapped(void *ctx, const volume *v, const macrocell_grid *grid)
{
    dvr_medium *m = ctx;
    bool same = dvr_set_volume(m->dvr, v, grid, NULL);
    assert(same);
    (void)same;
}

dvr_medium *dvr_medium_create(iso_volume *shared, const colormap *tf, const dvr_settings *settings,
                              tess_error *err)
{
    dvr_medium *m = calloc(1, sizeof *m);
    if (!m) {
        tess_error_set(err, "volume: out of memory for its direct rendering");
        return NULL;
    }
    m->dvr = dvr_create(iso_volume_data(shared), iso_volume_grid(shared), tf, settings, err);
    if (!m->dvr) {
        free(m);
        return NULL;
    }
    iso_volume_retain(shared);
    m->shared = shared;
    m->watcher = (iso_volume_watcher){.swapped = volume_swapped, .ctx = m};
    iso_volume_watch(shared, &m->watcher);
    return m;
}

void dvr_medium_destroy(dvr_medium *m)
{
    if (!m)
        return;
    if (m->shared)
        iso_volume_unwatch(m->shared, &m->watcher);
    dvr_destroy(m->dvr);
    iso_volume_release(m->shared);
    free(m);
}

const dvr_volume *dvr_medium_volume(const dvr_medium *m) { return m->dvr; }

/* The field's box in object (the volume's world) space: samples from
 * origin to origin + (n - 1) spacing. */
static bool medium_bounds(const void *data, aabb *out)
{
    const volume *v = iso_volume_data(((const dvr_medium *)data)->shared);
    const uint32_t n[3] = {v->nx, v->ny, v->nz};
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        if (n[a] < 2)
            return false;
        lo[a] = (float)v->origin[a];
        hi[a] = (float)(v->origin[a] + (double)(n[a] - 1) * v->spacing[a]);
    }
    *out = (aabb){v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2])};
    return true;
}

static void medium_integrate(const void *data, const ray *r, float jitter, vec3 *rgb, float *transmittance)
{
    const dvr_medium *m = data;
    const double org[3] = {r->org.x, r->org.y, r->org.z}, dir[3] = {r->dir.x, r->dir.y, r->dir.z};
    float c[3];
    dvr_integrate(m->dvr, org, dir, r->t_near, r->t_far, jitter, c, transmittance);
    *rgb = v3(c[0], c[1], c[2]);
}

static void medium_destroy(void *data) { dvr_medium_destroy(data); }

/* A volume's time steps are the shared volume's: the iso-surfaces of the
 * same entry step with it, whichever is set first (the watcher above
 * follows the swap). */
static uint32_t medium_step_count(const void *data)
{
    return iso_volume_step_count(((const dvr_medium *)data)->shared);
}

static bool medium_step_ready(void *data, uint32_t step)
{
    return iso_volume_step_ready(((dvr_medium *)data)->shared, step);
}

static bool medium_set_step(void *data, uint32_t step, tess_error *err)
{
    return iso_volume_set_step(((dvr_medium *)data)->shared, step, err);
}

static bool medium_set_colormap(void *data, const char *name)
{
    dvr_medium *m = data;
    colormap tf;
    if (!colormap_preset(name, &tf))
        return false;
    if (iso_volume_step_count(m->shared) > 1) {
        /* a time series keeps the range it has (step 0's when automatic), so a value keeps its
         * colour from step to step; dvr_set_transfer would fit it to the step shown */
        tf.lo = m->dvr->tf.lo;
        tf.hi = m->dvr->tf.hi;
        tf.range_auto = false;
    }
    dvr_set_transfer(m->dvr, &tf);
    return true;
}

static const colormap *medium_colormap(const void *data)
{
    const dvr_medium *m = data;
    return &m->dvr->tf;
}

static const geometry_controls medium_controls = {
    .set_colormap = medium_set_colormap,
    .colormap = medium_colormap,
    .step_count = medium_step_count,
    .step_ready = medium_step_ready,
    .set_step = medium_set_step,
};

const medium_ops dvr_medium_ops = {
    .name = "dvr",
    .bounds = medium_bounds,
    .integrate = medium_integrate,
    .destroy = medium_destroy,
    .controls = &medium_controls,
};
