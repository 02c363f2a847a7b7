/* drm_legacy.c (wall) - the legacy modesetting path (drm_card.h), for
 * drivers without atomic modesetting: drmModeSetCrtc per output, and one page
 * flip per CRTC, each on its own, so one refused CRTC does not hold back the
 * others. */
#include <errno.h>
#include <string.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include "drm_card.h"

static bool legacy_modeset(drm_card *c, int first, int last, const char *what, tess_error *err)
{
    (void)what; /* each CRTC is set by itself: the message names it */
    for (int o = first; o <= last; o++) {
        drm_output *out = &c->outputs[o];
        if (drmModeSetCrtc(c->fd, out->crtc_id, out->blank.fb_id, 0, 0, &out->connector_id, 1, &out->mode))
            return tess_error_set(err, "%s: setting mode %s on CRTC %u failed: %s", c->path, out->mode.name,
                                  out->crtc_id, strerror(errno));
    }
    return true;
}

static bool legacy_disable(drm_card *c, int o, tess_error *err)
{
    drm_output *out = &c->outputs[o];
    return drmModeSetCrtc(c->fd, out->crtc_id, 0, 0, 0, NULL, 0, NULL) == 0 ||
           tess_error_set(err, "%s: switching CRTC %u off: %s", c->path, out->crtc_id, strerror(errno));
}

static int legacy_flip(drm_card *c, int *refused, int *refused_errno)
{
    int count = 0;
    for (int o = 0; o < c->output_count; o++) {
        drm_output *out = &c->outputs[o];
        if (!out->live || out->ready < 0)
            continue;
        if (drmModePageFlip(c->fd, out->crtc_id, out->buffers[out->ready].fb_id, DRM_MODE_PAGE_FLIP_EVENT, c) == 0) {
            out->flip_pending = true;
            count++;
        } else {
            *refused_errno = errno;
            out->flip = DRM_FLIP_REFUSED;
            (*refused)++;
        }
    }
    return count;
}

const drm_kms_ops drm_kms_legacy = {
    .name = "legacy",
    .needs_primary_plane = false,
    .modeset = legacy_modeset,
    .disable = legacy_disable,
    .flip = legacy_flip,
};
