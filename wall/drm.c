/* drm.c - the DRM/KMS backend (see drm.h). */
#include "drm_card.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>
#include <sys/stat.h>
#include <drm_fourcc.h>
#include <libudev.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include "engine/base/log.h"
#include "engine/frame/pipeline.h"
#include "seat/session.h"
#include "xrgb.h"

#define DRM_MAX_CARDS 16
#define DRM_FLIP_TIMEOUT_MS 1000   /* a flip event later than this: probe the connectors (and see drm_flip_judge) */
#define DRM_HOTPLUG_PASSES 3       /* a monitor that moved connectors: gone, then back */
#define DRM_SEAT_WAIT_MS 200       /* while switched away: how often to look for a stop (and tell the pause hook) */
#define DRM_IDLE_WAIT_MS 100       /* every monitor unplugged: wait this long for a hotplug event per step */
#define DRM_IDLE_PROBE_MS 1000     /* ... and without udev, probe the connectors this often */
/* ---------------------------------------------------------------- properties */

static bool prop_value(int fd, uint32_t object, uint32_t type, const char *name, uint64_t *value)
{
    drmModeObjectProperties *props = drmModeObjectGetProperties(fd, object, type);
    bool found = false;
    for (uint32_t i = 0; props && i < props->count_props && !found; i++) {
        drmModePropertyRes *p = drmModeGetProperty(fd, props->props[i]);
        if (p && !strcmp(p->name, name)) {
            *value = props->prop_values[i];
            found = true;
        }
        drmModeFreeProperty(p);
    }
    drmModeFreeObjectProperties(props);
    return found;
}

/* ---------------------------------------------------------------- connectors */

static double mode_refresh_hz(const drmModeModeInfo *m)
{
    if (m->htotal == 0 || m->vtotal == 0)
        return (double)m->vrefresh;
    return (double)m->clock * 1000.0 / ((double)m->htotal * (double)m->vtotal);
}

static void read_edid(int fd, uint32_t connector_id, drm_connector_info *info)
{
    uint64_t blob_id = 0;
    if (!prop_value(fd, connector_id, DRM_MODE_OBJECT_CONNECTOR, "EDID", &blob_id) || !blob_id)
        return;
    drmModePropertyBlobRes *blob = drmModeGetPropertyBlob(fd, (uint32_t)blob_id);
    if (blob) {
        info->has_edid = edid_parse(blob->data, blob->length, &info->edid);
        if (!info->has_edid)
            log_warn("%s: EDID of %s is not valid; the monitor is known by its connector name only", "drm",
                     info->name);
    }
    drmModeFreePropertyBlob(blob);
}

/* The CRTC that drives connector `cn` now (through its encoder), or 0. */
static uint32_t current_crtc(int fd, const drmModeConnector *cn)
{
    if (!cn->encoder_id)
        return 0;
    drmModeEncoder *enc = drmModeGetEncoder(fd, cn->encoder_id);
    uint32_t crtc = enc ? enc->crtc_id : 0;
    drmModeFreeEncoder(enc);
    return crtc;
}

static void free_connectors(drm_connector_info *infos, wall_device_connector *conns, size_t n)
{
    for (size_t i = 0; infos && i < n; i++) {
        free(infos[i].modes);
        free(infos[i].mode_infos);
    }
    free(infos);
    free(conns);
}

/* The card's connectors now (a full probe) into c->infos / c->conns,
 * replacing the earlier lists; a connector seen before keeps the CRTC it had
 * when the card was opened (what close restores). */
static bool read_connectors(drm_card *c, tess_error *err)
{
    drmModeRes *res = drmModeGetResources(c->fd);
    if (!res)
        return tess_error_set(err, "%s: not a KMS device (no mode resources)", c->path);
    size_t n = (size_t)res->count_connectors, count = 0;
    drm_connector_info *infos = calloc(n ? n : 1, sizeof *infos);
    wall_device_connector *conns = calloc(n ? n : 1, sizeof *conns);
    bool first_read = c->infos == NULL;
    bool ok = infos && conns;
    if (!ok)
        tess_error_set(err, "%s: out of memory", c->path);
    for (size_t i = 0; ok && i < n; i++) {
        drmModeConnector *cn = drmModeGetConnector(c->fd, res->connectors[i]);
        if (!cn)
            continue;
        drm_connector_info *info = &infos[count];
        wall_device_connector *dc = &conns[count];
        const char *type = drmModeGetConnectorTypeName(cn->connector_type);
        info->id = cn->connector_id;
        snprintf(info->name, sizeof info->name, "%s-%u", type ? type : "Unknown", cn->connector_type_id);
        if (first_read)
            info->saved_crtc = current_crtc(c->fd, cn);
        for (size_t k = 0; !first_read && k < c->conn_count; k++)
            if (c->infos[k].id == info->id)
                info->saved_crtc = c->infos[k].saved_crtc;
        read_edid(c->fd, cn->connector_id, info);
        size_t modes = cn->count_modes > 0 ? (size_t)cn->count_modes : 0;
        info->modes = calloc(modes ? modes : 1, sizeof *info->modes);
        info->mode_infos = calloc(modes ? modes : 1, sizeof *info->mode_infos);
        count++; /* freed with the list from here on */
        if (!info->modes || !info->mode_infos) {
            drmModeFreeConnector(cn);
            ok = tess_error_set(err, "%s: out of memory", c->path);
            break;
        }
        int preferred = -1, user_defined = -1;
        for (size_t m = 0; m < modes; m++) {
            info->mode_infos[m] = cn->modes[m];
            info->modes[m] = (wall_device_mode){cn->modes[m].hdisplay, cn->modes[m].vdisplay,
                                                mode_refresh_hz(&cn->modes[m])};
            if (preferred < 0 && (cn->modes[m].type & DRM_MODE_TYPE_PREFERRED))
                preferred = (int)m;
            if (user_defined < 0 && (cn->modes[m].type & DRM_MODE_TYPE_USERDEF))
                user_defined = (int)m;
        }
        *dc = (wall_device_connector){info->name, cn->connection == DRM_MODE_CONNECTED && modes > 0,
                                      info->has_edid ? info->edid.manufacturer : NULL,
                                      info->has_edid ? info->edid.model : NULL,
                                      info->has_edid ? info->edid.serial : NULL,
                                      info->modes, modes, preferred, user_defined};
        drmModeFreeConnector(cn);
    }
    drmModeFreeResources(res);
    if (!ok) {
        free_connectors(infos, conns, count);
        return false;
    }
    free_connectors(c->infos, c->conns, c->conn_count);
    c->infos = infos;
    c->conns = conns;
    c->conn_count = count;
    return true;
}

/* ---------------------------------------------------------------- open / close */

static bool any_connected(int fd)
{
    drmModeRes *res = drmModeGetResources(fd);
    bool found = false;
    for (int i = 0; res && i < res->count_connectors && !found; i++) {
        drmModeConnector *cn = drmModeGetConnector(fd, res->connectors[i]);
        found = cn && cn->connection == DRM_MODE_CONNECTED && cn->count_modes > 0;
        drmModeFreeConnector(cn);
    }
    drmModeFreeResources(res);
    return found;
}

static int open_first_card(session *sn, char *path, size_t path_bytes, tess_error *err)
{
    bool any = false;
    for (int i = 0; i < DRM_MAX_CARDS; i++) {
        snprintf(path, path_bytes, "/dev/dri/card%d", i);
        if (access(path, F_OK) != 0)
            continue;
        tess_error why = {{0}};
        int fd = session_open_device(sn, path, &why);
        if (fd < 0)
            continue;
        any = true;
        if (any_connected(fd))
            return fd;
        session_close_device(sn, fd);
    }
    tess_error_set(err, any ? "drm: no card has a connected monitor" : "drm: no DRM card (/dev/dri/card*) can be opened");
    return -1;
}

drm_card *drm_card_open(const char *path, session *sn, tess_error *err)
{
    drm_card *c = calloc(1, sizeof *c);
    if (!c) {
        tess_error_set(err, "drm: out of memory");
        return NULL;
    }
    c->session = sn;
    c->fd = -1;
    if (path) {
        snprintf(c->path, sizeof c->path, "%s", path);
        c->fd = session_open_device(sn, path, err);
    } else {
        c->fd = open_first_card(sn, c->path, sizeof c->path, err);
    }
    if (c->fd < 0) {
        free(c);
        return NULL;
    }
    /* a seat made us master already; without one we must be root */
    if (!drmIsMaster(c->fd) && drmSetMaster(c->fd) != 0) {
        tess_error_set(err, "%s: cannot become DRM master (another program, e.g. a compositor, drives the "
                       "outputs; or run as root / through a seat): %s", c->path, strerror(errno));
        session_close_device(sn, c->fd);
        free(c);
        return NULL;
    }
    drmSetClientCap(c->fd, DRM_CLIENT_CAP_UNIVERSAL_PLANES, 1);
    /* TESSERA_DRM_NO_ATOMIC=1 (as wlroots' WLR_DRM_NO_ATOMIC): the legacy path on a card that has atomic,
     * for a driver whose atomic support misbehaves, and for tests/vm_wall.sh to drive both paths */
    const char *no_atomic = getenv("TESSERA_DRM_NO_ATOMIC");
    bool atomic = !(no_atomic && !strcmp(no_atomic, "1")) && drmSetClientCap(c->fd, DRM_CLIENT_CAP_ATOMIC, 1) == 0;
    c->kms = atomic ? &drm_kms_atomic : &drm_kms_legacy;
    struct stat st;
    if (fstat(c->fd, &st) == 0)
        c->devnum = st.st_rdev;
    drmModeRes *res = drmModeGetResources(c->fd);
    if (!res) {
        tess_error_set(err, "%s: not a KMS device (no mode resources)", c->path);
        drm_card_close(c);
        return NULL;
    }
    bool ok = read_connectors(c, err);
    c->saved_crtcs = calloc((size_t)res->count_crtcs + 1, sizeof *c->saved_crtcs);
    for (int i = 0; ok && c->saved_crtcs && i < res->count_crtcs; i++)
        c->saved_crtcs[c->saved_count++] = drmModeGetCrtc(c->fd, res->crtcs[i]);
    drmModeFreeResources(res);
    if (!ok) {
        drm_card_close(c);
        return NULL;
    }
    return c;
}

const char *drm_card_path(const drm_card *c) { return c->path; }
bool drm_card_atomic(const drm_card *c) { return c->kms == &drm_kms_atomic; }

size_t drm_card_connectors(const drm_card *c, const wall_device_connector **out)
{
    *out = c->conns;
    return c->conn_count;
}

static void free_buffer(int fd, drm_buffer *b)
{
    if (b->map)
        munmap(b->map, b->size_bytes);
    if (b->fb_id)
        drmModeRmFB(fd, b->fb_id);
    if (b->handle) {
        struct drm_mode_destroy_dumb d = {.handle = b->handle};
        drmIoctl(fd, DRM_IOCTL_MODE_DESTROY_DUMB, &d);
    }
    memset(b, 0, sizeof *b);
}

static void wait_flips(drm_card *c);

static void free_outputs(drm_card *c)
{
    for (int o = 0; o < c->output_count; o++) {
        drm_output *out = &c->outputs[o];
        for (int b = 0; b < DRM_FRAME_BUFFERS; b++)
            free_buffer(c->fd, &out->buffers[b]);
        free_buffer(c->fd, &out->blank);
        if (out->mode_blob)
            drmModeDestroyPropertyBlob(c->fd, out->mode_blob);
        out->mode_blob = 0;
    }
    c->output_count = 0;
}

/* Put back what was there at open: each saved CRTC with its connectors, or off. */
static void restore_crtcs(drm_card *c)
{
    for (int i = 0; i < c->saved_count; i++) {
        drmModeCrtc *s = c->saved_crtcs[i];
        if (!s)
            continue;
        uint32_t conns[64];
        int n = 0;
        for (size_t k = 0; k < c->conn_count && n < 64; k++)
            if (c->infos[k].saved_crtc == s->crtc_id)
                conns[n++] = c->infos[k].id;
        int rc = s->mode_valid && n > 0
                     ? drmModeSetCrtc(c->fd, s->crtc_id, s->buffer_id, s->x, s->y, conns, n, &s->mode)
                     : drmModeSetCrtc(c->fd, s->crtc_id, 0, 0, 0, NULL, 0, NULL);
        if (rc != 0)
            log_warn("%s: could not restore CRTC %u: %s", c->path, s->crtc_id, strerror(errno));
    }
}

void drm_card_close(drm_card *c)
{
    if (!c)
        return;
    bool ours = session_active(c->session); /* switched away: the console's owner has the CRTCs */
    if (c->fd >= 0 && c->output_count > 0 && ours) {
        wait_flips(c); /* a buffer still queued for scan-out must not be freed under it */
        restore_crtcs(c);
    }
    free_outputs(c);
    for (int i = 0; i < c->saved_count; i++)
        drmModeFreeCrtc(c->saved_crtcs[i]);
    free(c->saved_crtcs);
    free_connectors(c->infos, c->conns, c->conn_count);
    if (c->monitor)
        udev_monitor_unref(c->monitor);
    if (c->udev)
        udev_unref(c->udev);
    if (c->fd >= 0) {
        if (!session_has_seat(c->session) && ours)
            drmDropMaster(c->fd);
        session_close_device(c->session, c->fd);
    }
    free(c);
}

/* ---------------------------------------------------------------- bringing up the outputs */

static bool create_buffer(drm_card *c, int width, int height, drm_buffer *b, tess_error *err)
{
    struct drm_mode_create_dumb create = {.width = (uint32_t)width, .height = (uint32_t)height, .bpp = 32};
    if (drmIoctl(c->fd, DRM_IOCTL_MODE_CREATE_DUMB, &create) != 0)
        return tess_error_set(err, "%s: cannot create a %dx%d dumb buffer: %s", c->path, width, height,
                              strerror(errno));
    b->handle = create.handle;
    b->pitch_bytes = create.pitch;
    b->size_bytes = create.size;
    uint32_t handles[4] = {create.handle}, pitches[4] = {create.pitch}, offsets[4] = {0};
    if (drmModeAddFB2(c->fd, (uint32_t)width, (uint32_t)height, DRM_FORMAT_XRGB8888, handles, pitches, offsets,
                      &b->fb_id, 0) != 0)
        return tess_error_set(err, "%s: cannot add a framebuffer: %s", c->path, strerror(errno));
    struct drm_mode_map_dumb map = {.handle = create.handle};
    if (drmIoctl(c->fd, DRM_IOCTL_MODE_MAP_DUMB, &map) != 0)
        return tess_error_set(err, "%s: cannot map a dumb buffer: %s", c->path, strerror(errno));
    void *p = mmap(NULL, create.size, PROT_READ | PROT_WRITE, MAP_SHARED, c->fd, (off_t)map.offset);
    if (p == MAP_FAILED)
        return tess_error_set(err, "%s: cannot map a dumb buffer: %s", c->path, strerror(errno));
    b->map = p;
    memset(b->map, 0, create.size); /* black until the first frame */
    return true;
}

/* Try to give output o a CRTC from its mask, moving earlier outputs to other
 * CRTCs of theirs when needed (one augmenting path). */
static bool match_crtc(int o, const uint32_t *masks, int crtcs, int *owner, uint32_t *visited)
{
    for (int k = 0; k < crtcs; k++) {
        if (!(masks[o] & (1u << k)) || (*visited & (1u << k)))
            continue;
        *visited |= 1u << k;
        if (owner[k] < 0 || match_crtc(owner[k], masks, crtcs, owner, visited)) {
            owner[k] = o;
            return true;
        }
    }
    return false;
}

int drm_match_crtcs(const uint32_t *masks, int outputs, int crtcs, int *crtc_of_output)
{
    int owner[32];
    crtcs = crtcs < 32 ? crtcs : 32;
    for (int k = 0; k < 32; k++)
        owner[k] = -1;
    for (int o = 0; o < outputs; o++) {
        uint32_t visited = 0;
        crtc_of_output[o] = -1;
        if (!match_crtc(o, masks, crtcs, owner, &visited))
            return o;
    }
    for (int k = 0; k < crtcs; k++)
        if (owner[k] >= 0)
            crtc_of_output[owner[k]] = k;
    return -1;
}

/* The CRTCs each output's encoders can drive (possible_crtcs masks, bit k = res->crtcs[k]). */
static uint32_t possible_crtcs(drm_card *c, uint32_t connector_id)
{
    drmModeConnector *cn = drmModeGetConnector(c->fd, connector_id);
    uint32_t mask = 0;
    for (int e = 0; cn && e < cn->count_encoders; e++) {
        drmModeEncoder *enc = drmModeGetEncoder(c->fd, cn->encoders[e]);
        mask |= enc ? enc->possible_crtcs : 0;
        drmModeFreeEncoder(enc);
    }
    drmModeFreeConnector(cn);
    return mask;
}

/* A CRTC for each output from its encoders' possible-CRTC masks (a maximum
 * bipartite matching, so a first choice never blocks a later output that
 * could only use it), and that CRTC's primary plane. */
static bool assign_crtcs(drm_card *c, drmModeRes *res, tess_error *err)
{
    uint32_t masks[WALL_MAX_OUTPUTS];
    int crtc_index_of[WALL_MAX_OUTPUTS];
    for (int o = 0; o < c->output_count; o++)
        masks[o] = possible_crtcs(c, c->outputs[o].connector_id);
    int unmatched = drm_match_crtcs(masks, c->output_count, res->count_crtcs, crtc_index_of);
    if (unmatched >= 0)
        return tess_error_set(err, "%s: no CRTC is left for outputs[%d] (%s): the card cannot drive all these "
                                   "outputs at once (its possible-CRTC mask 0x%x of %d CRTCs)",
                              c->path, unmatched, c->wall.outputs[unmatched].connector, masks[unmatched],
                              res->count_crtcs);
    drmModePlaneRes *planes = drmModeGetPlaneResources(c->fd);
    bool ok = true;
    for (int o = 0; o < c->output_count && ok; o++) {
        drm_output *out = &c->outputs[o];
        int crtc_index = crtc_index_of[o];
        out->crtc_id = res->crtcs[crtc_index];
        for (uint32_t p = 0; planes && p < planes->count_planes && !out->plane_id; p++) {
            drmModePlane *pl = drmModeGetPlane(c->fd, planes->planes[p]);
            uint64_t type = 0;
            if (pl && (pl->possible_crtcs & (1u << crtc_index)) &&
                prop_value(c->fd, pl->plane_id, DRM_MODE_OBJECT_PLANE, "type", &type) &&
                type == DRM_PLANE_TYPE_PRIMARY) {
                bool taken = false;
                for (int q = 0; q < o; q++)
                    taken = taken || c->outputs[q].plane_id == pl->plane_id;
                if (!taken)
                    out->plane_id = pl->plane_id;
            }
            drmModeFreePlane(pl);
        }
        if (!out->plane_id && c->kms->needs_primary_plane)
            ok = tess_error_set(err, "%s: no primary plane for CRTC %u", c->path, out->crtc_id);
    }
    drmModeFreePlaneResources(planes);
    return ok;
}

/* Switch output o off (a monitor gone, or given up on); a failure is only logged. */
static void disable_output(drm_card *c, int o)
{
    tess_error err = {{0}};
    if (!c->kms->disable(c, o, &err))
        log_warn("%s", err.msg);
}

/* ---------------------------------------------------------------- frames */

static const char *output_name(const drm_card *c, int o);

/* tv_sec, tv_usec: the vblank's time on CLOCK_MONOTONIC (DRM_CAP_TIMESTAMP_MONOTONIC,
 * every kernel since 3.x) */
static void flip_done(int fd, unsigned sequence, unsigned tv_sec, unsigned tv_usec, unsigned crtc_id, void *data)
{
    (void)fd;
    drm_card *c = data;
    if (c->pending_flips > 0)
        c->pending_flips--;
    for (int o = 0; o < c->output_count; o++)
        if (c->outputs[o].flip_pending && c->outputs[o].crtc_id == crtc_id) {
            c->outputs[o].flip_pending = false;
            c->outputs[o].flip = DRM_FLIP_DONE;
            log_debug("%s: %s: flipped to frame %llu at vblank %u (%u.%06u s)", c->path, output_name(c, o),
                      (unsigned long long)c->flipping_frame, sequence, tv_sec, tv_usec);
            if (c->flip_fn)
                c->flip_fn(c->flip_ctx, c->flipping_frame, output_name(c, o), sequence,
                           (int64_t)tv_sec * 1000000 + tv_usec);
        }
}

/* Wait for the flip events of the last commit. An output whose event never
 * comes (unplugged under it) is marked TIMED_OUT and the connectors are
 * probed; drm_end_stage judges the outcomes (drm_flip_judge). */
static void wait_flips(drm_card *c)
{
    drmEventContext ev = {.version = 3, .page_flip_handler2 = flip_done};
    if (c->pending_flips == 0)
        return;
    while (c->pending_flips > 0) {
        struct pollfd pfd = {c->fd, POLLIN, 0};
        int n = poll(&pfd, 1, DRM_FLIP_TIMEOUT_MS);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            log_warn("%s: no page-flip event within %d ms; probing the connectors", c->path, DRM_FLIP_TIMEOUT_MS);
            c->pending_flips = 0;
            for (int o = 0; o < c->output_count; o++)
                if (c->outputs[o].flip_pending) {
                    c->outputs[o].flip_pending = false;
                    c->outputs[o].flip = DRM_FLIP_TIMED_OUT;
                }
            c->probe_needed = true;
            return;
        }
        drmHandleEvent(c->fd, &ev);
    }
    /* what the end-to-end tests (tests/vm_*.sh) wait for: from now on every output shows
     * this frame or a later one */
    log_debug("%s: frame %llu on screen", c->path, (unsigned long long)c->flipping_frame);
}

/* Flip every live output that has a new frame (c->kms: in one atomic commit, or one page flip
 * per CRTC). A refused flip makes the connectors be probed: an output may have gone between
 * the last probe and now. */
static void flip_ready(drm_card *c)
{
    int refused = 0, refused_errno = 0;
    c->pending_flips = c->kms->flip(c, &refused, &refused_errno);
    if (c->pending_flips > 0)
        c->flipping_frame = c->ready_frame;
    if (refused > 0) {
        log_warn("%s: page flip refused (%d output%s): %s; probing the connectors", c->path, refused,
                 refused == 1 ? "" : "s", strerror(refused_errno));
        c->probe_needed = true;
    }
    for (int o = 0; o < c->output_count; o++)
        c->outputs[o].ready = -1;
}

/* "were refused", "never completed" or both, for the failures in `kinds` */
static const char *failure_text(unsigned kinds)
{
    bool refused = kinds & (1u << DRM_FLIP_REFUSED), timed_out = kinds & (1u << DRM_FLIP_TIMED_OUT);
    return refused && timed_out ? "were refused or never completed" : refused ? "were refused" : "never completed";
}

drm_flip_verdict drm_flip_judge(drm_flip_health *h, const drm_flip_outcome *outcome, const char *const *names,
                                int count)
{
    drm_flip_verdict v = {0};
    bool any_done = false;
    int limit_reached = -1; /* an output whose failures reached the limit */
    if (count > WALL_MAX_OUTPUTS)
        count = WALL_MAX_OUTPUTS;
    for (int o = 0; o < count; o++) {
        if (outcome[o] == DRM_FLIP_DONE) {
            h->failed[o] = 0;
            h->kinds[o] = 0;
            any_done = true;
        } else if (outcome[o] == DRM_FLIP_REFUSED || outcome[o] == DRM_FLIP_TIMED_OUT) {
            h->failed[o]++;
            h->kinds[o] |= 1u << outcome[o];
            v.probe = true;
            if (h->failed[o] >= DRM_FLIP_FAILS_LIMIT && limit_reached < 0)
                limit_reached = o;
        }
    }
    if (limit_reached >= 0 && !any_done) {
        v.fatal = true;
        tess_error_set(&v.why, "%d page flips in a row %s and no output's completed", DRM_FLIP_FAILS_LIMIT,
                       failure_text(h->kinds[limit_reached]));
        return v;
    }
    char list[TESS_ERROR_MSG_BYTES] = "";
    size_t used = 0;
    unsigned kinds = 0;
    for (int o = 0; o < count && any_done; o++) {
        if (h->failed[o] < DRM_FLIP_FAILS_LIMIT)
            continue;
        v.give_up[o] = true;
        kinds |= h->kinds[o];
        int n = snprintf(list + used, sizeof list - used, "%soutputs[%d]%s%s%s", used ? ", " : "", o,
                         names && names[o] ? " (" : "", names && names[o] ? names[o] : "",
                         names && names[o] ? ")" : "");
        used = n > 0 && (size_t)n < sizeof list - used ? used + (size_t)n : sizeof list - 1;
        h->failed[o] = 0;
        h->kinds[o] = 0;
    }
    if (used > 0)
        tess_error_set(&v.why, "%s: %d page flips in a row %s while the other outputs' completed; switched off, the "
                               "rest of the wall goes on", list, DRM_FLIP_FAILS_LIMIT, failure_text(kinds));
    return v;
}

/* ---------------------------------------------------------------- hotplug */

/* Listen for udev's connector-change events of this card; without udev (or
 * its daemon) only flip time-outs make us probe. */
static void watch_hotplug(drm_card *c)
{
    c->udev = udev_new();
    /* udevd re-broadcasts the kernel's events once its rules ran; without the daemon, the kernel's own */
    const char *source = access("/run/udev/control", F_OK) == 0 ? "udev" : "kernel";
    c->monitor = c->udev ? udev_monitor_new_from_netlink(c->udev, source) : NULL;
    if (c->monitor && (udev_monitor_filter_add_match_subsystem_devtype(c->monitor, "drm", NULL) < 0 ||
                       udev_monitor_enable_receiving(c->monitor) < 0)) {
        udev_monitor_unref(c->monitor);
        c->monitor = NULL;
    }
    if (!c->monitor)
        log_warn("%s: cannot listen for hotplug events (udev); unplugged monitors are noticed only when their "
                 "page flips stop", c->path);
}

/* Drain the monitor; true if one of the events was a HOTPLUG=1 of this card. */
static bool hotplug_event(drm_card *c)
{
    bool ours = false;
    for (;;) {
        struct pollfd pfd = {udev_monitor_get_fd(c->monitor), POLLIN, 0};
        if (poll(&pfd, 1, 0) <= 0)
            return ours;
        struct udev_device *dev = udev_monitor_receive_device(c->monitor);
        if (!dev)
            return ours;
        const char *hotplug = udev_device_get_property_value(dev, "HOTPLUG");
        if (hotplug && !strcmp(hotplug, "1") && udev_device_get_devnum(dev) == c->devnum)
            ours = true;
        udev_device_unref(dev);
    }
}

static const char *output_name(const drm_card *c, int o) { return c->wall.outputs[o].connector; }

static void announce(drm_card *c, int o, bool live)
{
    if (c->pipeline && !pipeline_queue_channel_active(c->pipeline, c->first_channel + o, live))
        log_warn("%s: could not switch channel %d %s", c->path, c->first_channel + o, live ? "on" : "off");
}

/* Bring a dark output back on connector `conn` in `mode` (same size as before). */
static void bring_back(drm_card *c, int o, int conn, int mode)
{
    drm_output *out = &c->outputs[o];
    uint32_t old_connector = out->connector_id;
    drmModeModeInfo old_mode = out->mode;
    out->connector_id = c->infos[conn].id;
    out->mode = c->infos[conn].mode_infos[mode];
    tess_error err = {{0}};
    if (!c->kms->modeset(c, o, o, "bringing an output back", &err)) {
        log_warn("outputs[%d] (%s) stays dark: %s", o, output_name(c, o), err.msg);
        out->connector_id = old_connector;
        out->mode = old_mode;
        return;
    }
    out->live = true;
    out->ready = -1;
    log_info("%s: outputs[%d] (%s) is back on %s, %dx%d", c->path, o, output_name(c, o), c->infos[conn].name,
             out->mode.hdisplay, out->mode.vdisplay);
    announce(c, o, true);
}

/* Read the connectors again and apply what the plan says; true when an
 * output went dark or was lit again. */
static bool handle_hotplug(drm_card *c)
{
    tess_error err = {{0}};
    bool any_change = false;
    if (!read_connectors(c, &err)) {
        log_warn("%s: reading the connectors after a hotplug event: %s", c->path, err.msg);
        return false;
    }
    for (int o = 0; o < c->output_count; o++) /* a given-up output's monitor unplugged: a new chance */
        for (size_t k = 0; c->outputs[o].given_up && k < c->conn_count; k++)
            if (c->infos[k].id == c->outputs[o].connector_id && !c->conns[k].connected)
                c->outputs[o].given_up = false;
    for (int pass = 0; pass < DRM_HOTPLUG_PASSES; pass++) {
        bool live[WALL_MAX_OUTPUTS];
        int driving[WALL_MAX_OUTPUTS];
        wall_hotplug_step steps[WALL_MAX_OUTPUTS];
        for (int o = 0; o < c->output_count; o++) {
            live[o] = c->outputs[o].live;
            driving[o] = -1;
            for (size_t k = 0; live[o] && k < c->conn_count; k++)
                if (c->infos[k].id == c->outputs[o].connector_id)
                    driving[o] = (int)k;
        }
        wall_hotplug_plan(&c->wall, live, driving, c->conns, c->conn_count, steps);
        bool changed = false;
        for (int o = 0; o < c->output_count; o++) {
            if (steps[o].action == WALL_HOTPLUG_GONE) {
                log_warn("%s: outputs[%d] (%s) is gone (%s); the rest of the wall goes on", c->path, o,
                         output_name(c, o), steps[o].reason.msg);
                disable_output(c, o);
                c->outputs[o].live = false;
                c->outputs[o].ready = -1;
                announce(c, o, false);
                changed = true;
            } else if (steps[o].action == WALL_HOTPLUG_BACK && !c->outputs[o].given_up) {
                bring_back(c, o, steps[o].connector, steps[o].mode);
                changed = changed || c->outputs[o].live;
            } else if (pass == 0 && !live[o] && tess_error_is_set(&steps[o].reason)) {
                log_info("%s: outputs[%d] (%s) stays dark: %s", c->path, o, output_name(c, o), steps[o].reason.msg);
            }
        }
        if (!changed)
            break;
        any_change = true;
        c->flip_health = (drm_flip_health){{0}, {0}}; /* the failures had a cause: an output came or went */
    }
    return any_change;
}

/* ---------------------------------------------------------------- VT switches */

/* Light every live output again (after a VT switch the console had the CRTCs). */
static void restore_wall(drm_card *c)
{
    for (int o = 0; o < c->output_count; o++) {
        tess_error err = {{0}};
        if (c->outputs[o].live && !c->kms->modeset(c, o, o, "restoring an output after a VT switch", &err))
            log_warn("outputs[%d] (%s): %s", o, output_name(c, o), err.msg);
    }
}

/* The seat wants the card back (a VT switch away): finish the flips in
 * flight, let go, and wait (the frame loop waits with us: nothing renders)
 * until the seat is ours again or the pipeline is asked to stop. */
static void follow_seat(drm_card *c)
{
    session_dispatch(c->session, 0);
    if (!session_disable_pending(c->session))
        return;
    wait_flips(c);
    session_ack_disable(c->session);
    log_info("%s: switched away from our VT: the wall pauses", c->path);
    while (!session_active(c->session) && !(c->pipeline && pipeline_stop_requested(c->pipeline))) {
        if (c->pause_fn)
            c->pause_fn(c->pause_ctx, true);
        session_dispatch(c->session, DRM_SEAT_WAIT_MS);
    }
    if (!session_active(c->session))
        return;
    if (c->pause_fn)
        c->pause_fn(c->pause_ctx, false);
    log_info("%s: back on our VT: the wall goes on", c->path);
    restore_wall(c);
    c->probe_needed = true; /* monitors may have come and gone meanwhile */
    c->flip_health = (drm_flip_health){{0}, {0}}; /* flips before the switch say nothing about now */
    for (int o = 0; o < c->output_count; o++) {
        c->outputs[o].ready = -1; /* their buffers may have been written while we waited: show the next frame */
        c->outputs[o].flip = DRM_FLIP_NONE;
    }
}

/* ---------------------------------------------------------------- the displays */

typedef struct drm_display {
    image_display base;
    drm_card *card;
    int output; /* index into card->outputs */
} drm_display;

/* Render threads: a finished tile straight into the frame's scan-out buffer. */
static void drm_write_tile(image_display *d, const frame_image *img, int x0, int y0, int x1, int y1)
{
    drm_display *dd = (drm_display *)d;
    const drm_output *out = &dd->card->outputs[dd->output];
    const drm_buffer *b = &out->buffers[img->frame % DRM_FRAME_BUFFERS];
    xrgb_target t = {b->map, b->pitch_bytes, out->mode.hdisplay, out->mode.vdisplay};
    xrgb_write_rect(img->rgb, img->width_px, img->height_px, x0, y0, x1, y1, out->rotation_deg, &t);
}

/* The frame is already in its buffer: flip to it at the end of the stage. */
static bool drm_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    drm_display *dd = (drm_display *)d;
    dd->card->outputs[dd->output].ready = (int)(img->frame % DRM_FRAME_BUFFERS);
    dd->card->ready_frame = img->frame;
    return true;
}

static bool settle(drm_card *c, tess_error *err);

/* Before the display sync (the barrier before the flip of a wall of several machines):
 * everything but the commit, so that after the barrier only the commit is left. */
static bool drm_settle_stage(image_display *d, tess_error *err)
{
    drm_display *dd = (drm_display *)d;
    return dd->output != 0 || settle(dd->card, err);
}

/* Once per display stage (output 0's display speaks for the card), after settle waited
 * for the previous flips (this paces the pipeline on the display) and followed hotplug:
 * flip every live output in one commit. */
static bool drm_end_stage(image_display *d, tess_error *err)
{
    drm_display *dd = (drm_display *)d;
    drm_card *c = dd->card;
    if (dd->output != 0)
        return true;
    if (!c->settled && !settle(c, err)) /* a caller that knows no settle_stage */
        return false;
    c->settled = false;
    if (c->commit_due) {
        c->commit_due = false;
        flip_ready(c);
    }
    return true;
}

/* drm_settle_stage's work: follow the seat, wait for the last commit's flips, judge them,
 * follow hotplug; c->commit_due when the stage's frame is to be flipped. */
static bool settle(drm_card *c, tess_error *err)
{
    c->settled = true;
    c->commit_due = false;
    follow_seat(c);
    if (!session_active(c->session))
        return true; /* stopping while switched away: touch nothing */
    wait_flips(c);
    drm_flip_outcome outcome[WALL_MAX_OUTPUTS];
    for (int o = 0; o < c->output_count; o++) {
        outcome[o] = c->outputs[o].flip;
        c->outputs[o].flip = DRM_FLIP_NONE;
    }
    const char *names[WALL_MAX_OUTPUTS];
    for (int o = 0; o < c->output_count; o++)
        names[o] = output_name(c, o);
    drm_flip_verdict verdict = drm_flip_judge(&c->flip_health, outcome, names, c->output_count);
    if (!verdict.fatal && tess_error_is_set(&verdict.why))
        log_warn("%s: %s (tried again once its monitor has been unplugged and plugged in)", c->path,
                 verdict.why.msg);
    for (int o = 0; o < c->output_count; o++)
        if (verdict.give_up[o] && c->outputs[o].live) {
            disable_output(c, o);
            c->outputs[o].live = false;
            c->outputs[o].given_up = true;
            c->outputs[o].ready = -1;
            announce(c, o, false);
        }
    if (c->monitor && hotplug_event(c))
        c->probe_needed = true;
    bool outputs_changed = false;
    if (c->probe_needed || verdict.probe) {
        c->probe_needed = false;
        outputs_changed = handle_hotplug(c);
    }
    bool any_live = false;
    for (int o = 0; o < c->output_count; o++)
        any_live = any_live || c->outputs[o].live;
    if (!any_live) { /* nothing to show: wait for a monitor to come back instead of spinning the loop */
        struct pollfd pfd = {c->monitor ? udev_monitor_get_fd(c->monitor) : -1, POLLIN, 0};
        if (c->monitor)
            poll(&pfd, 1, DRM_IDLE_WAIT_MS);
        else {
            poll(NULL, 0, DRM_IDLE_PROBE_MS); /* without udev: probe now and then */
            c->probe_needed = true;
        }
        return true;
    }
    if (verdict.fatal && !outputs_changed)
        return tess_error_set(err, "%s: %s, and no output was unplugged", c->path, verdict.why.msg);
    c->commit_due = true;
    return true;
}

static void drm_display_destroy(image_display *d) { free(d); }

static const image_display_ops drm_display_ops = {.name = "drm",
                                                  .show = drm_show,
                                                  .destroy = drm_display_destroy,
                                                  .write_tile = drm_write_tile,
                                                  .end_stage = drm_end_stage,
                                                  .settle_stage = drm_settle_stage};

bool drm_wall_start(drm_card *c, const wall_config *w, image_display **displays, tess_error *err)
{
    drmModeRes *res = drmModeGetResources(c->fd);
    if (!res)
        return tess_error_set(err, "%s: no mode resources", c->path);
    c->output_count = w->count;
    c->wall = *w;
    bool ok = true;
    for (int o = 0; o < w->count && ok; o++) {
        const wall_output *wo = &w->outputs[o];
        drm_output *out = &c->outputs[o];
        memset(out, 0, sizeof *out);
        if (wo->device_connector < 0 || (size_t)wo->device_connector >= c->conn_count || wo->device_mode < 0) {
            ok = tess_error_set(err, "outputs[%d] (%s): not matched to a connector of %s", o, wo->connector, c->path);
            break;
        }
        const drm_connector_info *info = &c->infos[wo->device_connector];
        out->connector_id = info->id;
        out->mode = info->mode_infos[wo->device_mode];
        out->rotation_deg = wo->rotation_deg;
        out->live = true;
        out->ready = -1;
    }
    ok = ok && assign_crtcs(c, res, err);
    for (int o = 0; o < c->output_count && ok; o++) {
        drm_output *out = &c->outputs[o];
        for (int b = 0; b < DRM_FRAME_BUFFERS && ok; b++)
            ok = create_buffer(c, out->mode.hdisplay, out->mode.vdisplay, &out->buffers[b], err);
        ok = ok && create_buffer(c, out->mode.hdisplay, out->mode.vdisplay, &out->blank, err);
    }
    drmModeFreeResources(res);
    ok = ok && c->kms->modeset(c, 0, c->output_count - 1, "the wall's configuration", err);
    for (int o = 0; o < c->output_count && ok; o++) {
        drm_display *dd = calloc(1, sizeof *dd);
        if (!dd) {
            for (int k = 0; k < o; k++)
                image_display_destroy(displays[k]);
            ok = tess_error_set(err, "drm: out of memory");
            break;
        }
        dd->base.ops = &drm_display_ops;
        dd->card = c;
        dd->output = o;
        displays[o] = &dd->base;
    }
    if (!ok) { /* leave the card as found */
        free_outputs(c);
        return false;
    }
    watch_hotplug(c);
    return true;
}

void drm_wall_attach(drm_card *c, pipeline *p, int first_channel)
{
    c->pipeline = p;
    c->first_channel = first_channel;
}

void drm_card_set_pause_hook(drm_card *c, drm_pause_fn fn, void *ctx)
{
    c->pause_fn = fn;
    c->pause_ctx = ctx;
}

void drm_card_set_flip_hook(drm_card *c, drm_flip_fn fn, void *ctx)
{
    c->flip_fn = fn;
    c->flip_ctx = ctx;
}

/* ---------------------------------------------------------------- tessera outputs */

/* The scan-out state of every CRTC, one line each, e.g.
 *   "  CRTC 36: 640x480@60.00 fb 45 at 0,0 -> Virtual-1" or "  CRTC 37: off"
 * (what tests compare before and after a run: the state must come back). */
static void print_crtcs(FILE *f, int fd, const drmModeRes *res)
{
    for (int k = 0; k < res->count_crtcs; k++) {
        drmModeCrtc *crtc = drmModeGetCrtc(fd, res->crtcs[k]);
        if (!crtc)
            continue;
        fprintf(f, "  CRTC %u: ", crtc->crtc_id);
        if (!crtc->mode_valid) {
            fprintf(f, "off\n");
            drmModeFreeCrtc(crtc);
            continue;
        }
        fprintf(f, "%dx%d@%.2f fb %u%s at %u,%u ->", crtc->mode.hdisplay, crtc->mode.vdisplay,
                mode_refresh_hz(&crtc->mode), crtc->buffer_id, crtc->buffer_id ? "" : " (no framebuffer)", crtc->x,
                crtc->y);
        int driven = 0;
        for (int c = 0; c < res->count_connectors; c++) {
            drmModeConnector *cn = drmModeGetConnectorCurrent(fd, res->connectors[c]);
            if (cn && current_crtc(fd, cn) == crtc->crtc_id) {
                const char *type = drmModeGetConnectorTypeName(cn->connector_type);
                fprintf(f, " %s-%u", type ? type : "Unknown", cn->connector_type_id);
                driven++;
            }
            drmModeFreeConnector(cn);
        }
        fprintf(f, "%s\n", driven ? "" : " (no connector)");
        drmModeFreeCrtc(crtc);
    }
}

int drm_print_outputs(FILE *f)
{
    int cards = 0;
    for (int i = 0; i < DRM_MAX_CARDS; i++) {
        char path[64];
        snprintf(path, sizeof path, "/dev/dri/card%d", i);
        int fd = open(path, O_RDWR | O_CLOEXEC);
        if (fd < 0)
            continue;
        cards++;
        drmVersion *ver = drmGetVersion(fd);
        fprintf(f, "%s: %s\n", path, ver && ver->name ? ver->name : "(unknown driver)");
        drmFreeVersion(ver);
        drmModeRes *res = drmModeGetResources(fd);
        for (int k = 0; res && k < res->count_connectors; k++) {
            drmModeConnector *cn = drmModeGetConnector(fd, res->connectors[k]);
            if (!cn)
                continue;
            const char *type = drmModeGetConnectorTypeName(cn->connector_type);
            drm_connector_info info = {.id = cn->connector_id};
            snprintf(info.name, sizeof info.name, "%s-%u", type ? type : "Unknown", cn->connector_type_id);
            read_edid(fd, cn->connector_id, &info);
            fprintf(f, "  %s: %s", info.name, cn->connection == DRM_MODE_CONNECTED ? "connected" : "disconnected");
            if (info.has_edid)
                fprintf(f, ", edid {\"manufacturer\": \"%s\", \"model\": \"%s\", \"serial\": \"%s\"}",
                        info.edid.manufacturer, info.edid.model, info.edid.serial);
            if (cn->mmWidth && cn->mmHeight)
                fprintf(f, ", %ux%u mm", cn->mmWidth, cn->mmHeight);
            fputc('\n', f);
            for (int m = 0; m < cn->count_modes; m++)
                fprintf(f, "    %dx%d@%.2f%s%s\n", cn->modes[m].hdisplay, cn->modes[m].vdisplay,
                        mode_refresh_hz(&cn->modes[m]), cn->modes[m].type & DRM_MODE_TYPE_PREFERRED ? " preferred" : "",
                        cn->modes[m].type & DRM_MODE_TYPE_USERDEF ? " user-defined" : "");
            drmModeFreeConnector(cn);
        }
        print_crtcs(f, fd, res);
        drmModeFreeResources(res);
        close(fd);
    }
    if (!cards)
        fprintf(f, "no DRM card (/dev/dri/card*) can be opened\n");
    return cards;
}
