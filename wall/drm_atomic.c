/* drm_atomic.c (wall) - the atomic modesetting path (drm_card.h): every
 * change one atomic request; a modeset is tested whole (TEST_ONLY) before
 * anything changes, and a frame's flips of every output are one commit. */
#include <errno.h>
#include <string.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include "drm_card.h"

/* ---------------------------------------------------------------- properties */

static uint32_t prop_id(int fd, uint32_t object, uint32_t type, const char *name)
{
    drmModeObjectProperties *props = drmModeObjectGetProperties(fd, object, type);
    uint32_t id = 0;
    for (uint32_t i = 0; props && i < props->count_props && !id; i++) {
        drmModePropertyRes *p = drmModeGetProperty(fd, props->props[i]);
        if (p && !strcmp(p->name, name))
            id = p->prop_id;
        drmModeFreeProperty(p);
    }
    drmModeFreeObjectProperties(props);
    return id;
}

static bool add_prop(drm_card *c, drmModeAtomicReq *req, uint32_t object, uint32_t type, const char *name,
                     uint64_t value)
{
    uint32_t id = 0;
    for (int k = 0; k < c->prop_cached && !id; k++)
        if (c->prop_cache[k].object == object && !strcmp(c->prop_cache[k].name, name))
            id = c->prop_cache[k].id;
    if (!id) {
        id = prop_id(c->fd, object, type, name);
        if (id && c->prop_cached < DRM_PROP_CACHE) /* names are string literals: kept, not copied */
            c->prop_cache[c->prop_cached++] = (drm_prop_entry){object, name, id};
    }
    return id && drmModeAtomicAddProperty(req, object, id, value) >= 0;
}

/* Output o shows framebuffer fb_id; with `modeset` also its routing and mode. */
static bool add_output_props(drm_card *c, drmModeAtomicReq *req, int o, uint32_t fb_id, bool modeset)
{
    drm_output *out = &c->outputs[o];
    uint32_t w = out->mode.hdisplay, h = out->mode.vdisplay;
    bool ok = true;
    if (modeset) {
        ok = add_prop(c, req, out->connector_id, DRM_MODE_OBJECT_CONNECTOR, "CRTC_ID", out->crtc_id) &&
             add_prop(c, req, out->crtc_id, DRM_MODE_OBJECT_CRTC, "MODE_ID", out->mode_blob) &&
             add_prop(c, req, out->crtc_id, DRM_MODE_OBJECT_CRTC, "ACTIVE", 1);
        const char *names[] = {"CRTC_ID", "SRC_X", "SRC_Y", "SRC_W", "SRC_H", "CRTC_X", "CRTC_Y", "CRTC_W", "CRTC_H"};
        uint64_t values[] = {out->crtc_id, 0, 0, (uint64_t)w << 16, (uint64_t)h << 16, 0, 0, w, h};
        for (int k = 0; k < 9 && ok; k++)
            ok = add_prop(c, req, out->plane_id, DRM_MODE_OBJECT_PLANE, names[k], values[k]);
    }
    return ok && add_prop(c, req, out->plane_id, DRM_MODE_OBJECT_PLANE, "FB_ID", fb_id);
}

/* Output o switched off: its connector, CRTC and plane released. */
static bool add_disable_props(drm_card *c, drmModeAtomicReq *req, int o)
{
    drm_output *out = &c->outputs[o];
    return add_prop(c, req, out->connector_id, DRM_MODE_OBJECT_CONNECTOR, "CRTC_ID", 0) &&
           add_prop(c, req, out->crtc_id, DRM_MODE_OBJECT_CRTC, "ACTIVE", 0) &&
           add_prop(c, req, out->crtc_id, DRM_MODE_OBJECT_CRTC, "MODE_ID", 0) &&
           add_prop(c, req, out->plane_id, DRM_MODE_OBJECT_PLANE, "FB_ID", 0) &&
           add_prop(c, req, out->plane_id, DRM_MODE_OBJECT_PLANE, "CRTC_ID", 0);
}

/* Commit a modeset request: tested whole (TEST_ONLY) before anything changes. */
static bool commit_modeset(drm_card *c, drmModeAtomicReq *req, bool built, const char *what, tess_error *err)
{
    if (!req || !built)
        return tess_error_set(err, "%s: cannot build the atomic request for %s", c->path, what);
    if (drmModeAtomicCommit(c->fd, req, DRM_MODE_ATOMIC_TEST_ONLY | DRM_MODE_ATOMIC_ALLOW_MODESET, NULL) != 0)
        return tess_error_set(err, "%s: %s was refused by the driver (TEST_ONLY): %s", c->path, what,
                              strerror(errno));
    if (drmModeAtomicCommit(c->fd, req, DRM_MODE_ATOMIC_ALLOW_MODESET, NULL) != 0)
        return tess_error_set(err, "%s: the commit of %s failed: %s", c->path, what, strerror(errno));
    return true;
}

static bool make_mode_blob(drm_card *c, drm_output *out, tess_error *err)
{
    if (out->mode_blob)
        drmModeDestroyPropertyBlob(c->fd, out->mode_blob);
    out->mode_blob = 0;
    if (drmModeCreatePropertyBlob(c->fd, &out->mode, sizeof out->mode, &out->mode_blob) != 0)
        return tess_error_set(err, "%s: cannot create a mode blob: %s", c->path, strerror(errno));
    return true;
}

static bool atomic_modeset(drm_card *c, int first, int last, const char *what, tess_error *err)
{
    for (int o = first; o <= last; o++)
        if (!make_mode_blob(c, &c->outputs[o], err))
            return false;
    drmModeAtomicReq *req = drmModeAtomicAlloc();
    bool built = req != NULL;
    for (int o = first; o <= last && built; o++)
        built = add_output_props(c, req, o, c->outputs[o].blank.fb_id, true);
    bool ok = commit_modeset(c, req, built, what, err);
    drmModeAtomicFree(req);
    return ok;
}

static bool atomic_disable(drm_card *c, int o, tess_error *err)
{
    drmModeAtomicReq *req = drmModeAtomicAlloc();
    bool ok = commit_modeset(c, req, req && add_disable_props(c, req, o), "switching an output off", err);
    drmModeAtomicFree(req);
    return ok;
}

/* One commit for every output with a new frame. */
static int atomic_flip(drm_card *c, int *refused, int *refused_errno)
{
    int count = 0;
    drmModeAtomicReq *req = drmModeAtomicAlloc();
    bool ok = req != NULL;
    for (int o = 0; o < c->output_count && ok; o++) {
        drm_output *out = &c->outputs[o];
        if (out->live && out->ready >= 0) {
            ok = add_output_props(c, req, o, out->buffers[out->ready].fb_id, false);
            out->flip_pending = true;
            count++;
        }
    }
    if (ok && count > 0)
        ok = drmModeAtomicCommit(c->fd, req, DRM_MODE_ATOMIC_NONBLOCK | DRM_MODE_PAGE_FLIP_EVENT, c) == 0;
    *refused_errno = errno;
    drmModeAtomicFree(req);
    if (!ok) { /* a failed atomic commit changed nothing: no events come, for any output in it */
        for (int o = 0; o < c->output_count; o++)
            if (c->outputs[o].live && c->outputs[o].ready >= 0) {
                c->outputs[o].flip_pending = false;
                c->outputs[o].flip = DRM_FLIP_REFUSED;
                (*refused)++;
            }
        count = 0;
    }
    return count;
}

const drm_kms_ops drm_kms_atomic = {
    .name = "atomic",
    .needs_primary_plane = true,
    .modeset = atomic_modeset,
    .disable = atomic_disable,
    .flip = atomic_flip,
};
