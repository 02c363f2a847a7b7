/* drm.c - the DRM/KMS backend (see drm.h). */
#include "drm.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>
#include <drm_fourcc.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include "dump.h"
#include "edid.h"
#include "engine/log.h"

#define DRM_MAX_CARDS 16
#define DRM_FLIP_TIMEOUT_MS 1000 /* a flip event later than this means the output is gone */

typedef struct drm_buffer {
    uint32_t handle, fb_id, pitch_bytes;
    uint64_t size_bytes;
    uint8_t *map; /* write-only: scan-out memory may be write-combined */
} drm_buffer;

typedef struct drm_output {
    uint32_t connector_id, crtc_id, plane_id;
    uint32_t mode_blob;          /* atomic: MODE_ID blob */
    drmModeModeInfo mode;
    int rotation_deg;            /* as mounted, clockwise (wall_config.h) */
    int width_px, height_px;     /* mounted image size (the channel's) */
    drm_buffer buffers[2];
    int back;                    /* the buffer the next frame is written into; display thread only */
} drm_output;

/* One connector as the card reports it, with storage for wall_device_connector's strings. */
typedef struct drm_connector_info {
    uint32_t id;
    char name[WALL_CONNECTOR_BYTES];
    edid_identity edid;
    bool has_edid;
    wall_device_mode *modes;
    drmModeModeInfo *mode_infos; /* the same modes, as KMS wants them */
    uint32_t saved_crtc;         /* the CRTC driving it when the card was opened, 0 if none */
} drm_connector_info;

struct drm_card {
    int fd;
    char path[64];
    bool atomic;
    drm_connector_info *infos;
    wall_device_connector *conns; /* parallel to infos */
    size_t conn_count;
    drmModeCrtc **saved_crtcs;    /* the CRTC states found at open */
    int saved_count;
    drm_output outputs[WALL_MAX_OUTPUTS];
    int output_count;
    int pending_flips;            /* flip events still to come; display thread only */
};

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

static bool read_connectors(drm_card *c, drmModeRes *res, tess_error *err)
{
    size_t n = (size_t)res->count_connectors;
    c->infos = calloc(n ? n : 1, sizeof *c->infos);
    c->conns = calloc(n ? n : 1, sizeof *c->conns);
    if (!c->infos || !c->conns)
        return tess_error_set(err, "%s: out of memory", c->path);
    for (size_t i = 0; i < n; i++) {
        drmModeConnector *cn = drmModeGetConnector(c->fd, res->connectors[i]);
        if (!cn)
            continue;
        drm_connector_info *info = &c->infos[c->conn_count];
        wall_device_connector *dc = &c->conns[c->conn_count];
        const char *type = drmModeGetConnectorTypeName(cn->connector_type);
        info->id = cn->connector_id;
        snprintf(info->name, sizeof info->name, "%s-%u", type ? type : "Unknown", cn->connector_type_id);
        info->saved_crtc = current_crtc(c->fd, cn);
        read_edid(c->fd, cn->connector_id, info);
        size_t modes = cn->count_modes > 0 ? (size_t)cn->count_modes : 0;
        info->modes = calloc(modes ? modes : 1, sizeof *info->modes);
        info->mode_infos = calloc(modes ? modes : 1, sizeof *info->mode_infos);
        if (!info->modes || !info->mode_infos) {
            drmModeFreeConnector(cn);
            return tess_error_set(err, "%s: out of memory", c->path);
        }
        int preferred = -1;
        for (size_t m = 0; m < modes; m++) {
            info->mode_infos[m] = cn->modes[m];
            info->modes[m] = (wall_device_mode){cn->modes[m].hdisplay, cn->modes[m].vdisplay,
                                                mode_refresh_hz(&cn->modes[m])};
            if (preferred < 0 && (cn->modes[m].type & DRM_MODE_TYPE_PREFERRED))
                preferred = (int)m;
        }
        *dc = (wall_device_connector){info->name, cn->connection == DRM_MODE_CONNECTED && modes > 0,
                                      info->has_edid ? info->edid.manufacturer : NULL,
                                      info->has_edid ? info->edid.model : NULL,
                                      info->has_edid ? info->edid.serial : NULL,
                                      info->modes, modes, preferred};
        c->conn_count++;
        drmModeFreeConnector(cn);
    }
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

static int open_first_card(char *path, size_t path_bytes, tess_error *err)
{
    bool any = false;
    for (int i = 0; i < DRM_MAX_CARDS; i++) {
        snprintf(path, path_bytes, "/dev/dri/card%d", i);
        int fd = open(path, O_RDWR | O_CLOEXEC);
        if (fd < 0)
            continue;
        any = true;
        if (any_connected(fd))
            return fd;
        close(fd);
    }
    tess_error_set(err, any ? "drm: no card has a connected monitor" : "drm: no DRM card (/dev/dri/card*) can be opened");
    return -1;
}

drm_card *drm_card_open(const char *path, tess_error *err)
{
    drm_card *c = calloc(1, sizeof *c);
    if (!c) {
        tess_error_set(err, "drm: out of memory");
        return NULL;
    }
    c->fd = -1;
    if (path) {
        snprintf(c->path, sizeof c->path, "%s", path);
        c->fd = open(path, O_RDWR | O_CLOEXEC);
        if (c->fd < 0)
            tess_error_set(err, "%s: cannot open: %s", path, strerror(errno));
    } else {
        c->fd = open_first_card(c->path, sizeof c->path, err);
    }
    if (c->fd < 0) {
        free(c);
        return NULL;
    }
    if (drmSetMaster(c->fd) != 0 && !drmIsMaster(c->fd)) {
        tess_error_set(err, "%s: cannot become DRM master (another program, e.g. a compositor, drives the "
                       "outputs; or run as root / through a seat): %s", c->path, strerror(errno));
        close(c->fd);
        free(c);
        return NULL;
    }
    drmSetClientCap(c->fd, DRM_CLIENT_CAP_UNIVERSAL_PLANES, 1);
    c->atomic = drmSetClientCap(c->fd, DRM_CLIENT_CAP_ATOMIC, 1) == 0;
    drmModeRes *res = drmModeGetResources(c->fd);
    if (!res) {
        tess_error_set(err, "%s: not a KMS device (no mode resources)", c->path);
        drm_card_close(c);
        return NULL;
    }
    bool ok = read_connectors(c, res, err);
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
bool drm_card_atomic(const drm_card *c) { return c->atomic; }

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

static void wait_flips(drm_card *c, tess_error *err);

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
    if (c->fd >= 0 && c->output_count > 0) {
        tess_error err = {{0}};
        wait_flips(c, &err); /* a buffer still queued for scan-out must not be freed under it */
        restore_crtcs(c);
    }
    for (int i = 0; i < c->output_count; i++) {
        for (int b = 0; b < 2; b++)
            free_buffer(c->fd, &c->outputs[i].buffers[b]);
        if (c->outputs[i].mode_blob)
            drmModeDestroyPropertyBlob(c->fd, c->outputs[i].mode_blob);
    }
    for (int i = 0; i < c->saved_count; i++)
        drmModeFreeCrtc(c->saved_crtcs[i]);
    free(c->saved_crtcs);
    for (size_t i = 0; i < c->conn_count; i++) {
        free(c->infos[i].modes);
        free(c->infos[i].mode_infos);
    }
    free(c->infos);
    free(c->conns);
    if (c->fd >= 0) {
        drmDropMaster(c->fd);
        close(c->fd);
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

/* A CRTC for each output from its encoders' possible-CRTC masks, and that
 * CRTC's primary plane; first fit in output order. */
static bool assign_crtcs(drm_card *c, drmModeRes *res, tess_error *err)
{
    uint32_t used_crtcs = 0;
    drmModePlaneRes *planes = drmModeGetPlaneResources(c->fd);
    bool ok = true;
    for (int o = 0; o < c->output_count && ok; o++) {
        drm_output *out = &c->outputs[o];
        drmModeConnector *cn = drmModeGetConnector(c->fd, out->connector_id);
        int crtc_index = -1;
        for (int e = 0; cn && e < cn->count_encoders && crtc_index < 0; e++) {
            drmModeEncoder *enc = drmModeGetEncoder(c->fd, cn->encoders[e]);
            for (int k = 0; enc && k < res->count_crtcs && crtc_index < 0; k++)
                if ((enc->possible_crtcs & (1u << k)) && !(used_crtcs & (1u << k)))
                    crtc_index = k;
            drmModeFreeEncoder(enc);
        }
        drmModeFreeConnector(cn);
        if (crtc_index < 0) {
            ok = tess_error_set(err, "%s: no free CRTC can drive output %d (connector %u)", c->path, o,
                                out->connector_id);
            break;
        }
        used_crtcs |= 1u << crtc_index;
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
        if (!out->plane_id && c->atomic)
            ok = tess_error_set(err, "%s: no primary plane for CRTC %u", c->path, out->crtc_id);
    }
    drmModeFreePlaneResources(planes);
    return ok;
}

/* Add the properties that show buffer `b` of every output (and, with
 * `modeset`, the connector routing and modes). */
static bool add_frame_props(drm_card *c, drmModeAtomicReq *req, int buffer_of[], bool modeset)
{
    bool ok = true;
    for (int o = 0; o < c->output_count; o++) {
        drm_output *out = &c->outputs[o];
        uint32_t w = out->mode.hdisplay, h = out->mode.vdisplay;
        if (modeset) {
            ok = ok &&
                 drmModeAtomicAddProperty(req, out->connector_id,
                                          prop_id(c->fd, out->connector_id, DRM_MODE_OBJECT_CONNECTOR, "CRTC_ID"),
                                          out->crtc_id) >= 0 &&
                 drmModeAtomicAddProperty(req, out->crtc_id,
                                          prop_id(c->fd, out->crtc_id, DRM_MODE_OBJECT_CRTC, "MODE_ID"),
                                          out->mode_blob) >= 0 &&
                 drmModeAtomicAddProperty(req, out->crtc_id,
                                          prop_id(c->fd, out->crtc_id, DRM_MODE_OBJECT_CRTC, "ACTIVE"), 1) >= 0;
            const char *names[] = {"CRTC_ID", "SRC_X", "SRC_Y", "SRC_W", "SRC_H", "CRTC_X", "CRTC_Y", "CRTC_W",
                                   "CRTC_H"};
            uint64_t values[] = {out->crtc_id, 0, 0, (uint64_t)w << 16, (uint64_t)h << 16, 0, 0, w, h};
            for (int k = 0; k < 9 && ok; k++)
                ok = drmModeAtomicAddProperty(req, out->plane_id,
                                              prop_id(c->fd, out->plane_id, DRM_MODE_OBJECT_PLANE, names[k]),
                                              values[k]) >= 0;
        }
        ok = ok && drmModeAtomicAddProperty(req, out->plane_id,
                                            prop_id(c->fd, out->plane_id, DRM_MODE_OBJECT_PLANE, "FB_ID"),
                                            out->buffers[buffer_of[o]].fb_id) >= 0;
    }
    return ok;
}

static bool modeset(drm_card *c, tess_error *err)
{
    int front[WALL_MAX_OUTPUTS] = {0};
    if (!c->atomic) {
        for (int o = 0; o < c->output_count; o++) {
            drm_output *out = &c->outputs[o];
            if (drmModeSetCrtc(c->fd, out->crtc_id, out->buffers[0].fb_id, 0, 0, &out->connector_id, 1, &out->mode))
                return tess_error_set(err, "%s: setting mode %s on CRTC %u failed: %s", c->path, out->mode.name,
                                      out->crtc_id, strerror(errno));
        }
        return true;
    }
    for (int o = 0; o < c->output_count; o++)
        if (drmModeCreatePropertyBlob(c->fd, &c->outputs[o].mode, sizeof c->outputs[o].mode,
                                      &c->outputs[o].mode_blob) != 0)
            return tess_error_set(err, "%s: cannot create a mode blob: %s", c->path, strerror(errno));
    drmModeAtomicReq *req = drmModeAtomicAlloc();
    bool ok = req && add_frame_props(c, req, front, true);
    /* the whole configuration is tested before anything changes */
    if (ok && drmModeAtomicCommit(c->fd, req, DRM_MODE_ATOMIC_TEST_ONLY | DRM_MODE_ATOMIC_ALLOW_MODESET, NULL) != 0)
        ok = tess_error_set(err, "%s: the wall's configuration was refused by the driver (TEST_ONLY): %s", c->path,
                            strerror(errno));
    else if (ok && drmModeAtomicCommit(c->fd, req, DRM_MODE_ATOMIC_ALLOW_MODESET, NULL) != 0)
        ok = tess_error_set(err, "%s: the modeset commit failed: %s", c->path, strerror(errno));
    else if (!req || !ok)
        ok = tess_error_set(err, "%s: cannot build the atomic request", c->path);
    drmModeAtomicFree(req);
    return ok;
}

/* ---------------------------------------------------------------- frames */

static void flip_done(int fd, unsigned sequence, unsigned tv_sec, unsigned tv_usec, unsigned crtc_id, void *data)
{
    (void)fd, (void)sequence, (void)tv_sec, (void)tv_usec, (void)crtc_id;
    drm_card *c = data;
    if (c->pending_flips > 0)
        c->pending_flips--;
}

static void wait_flips(drm_card *c, tess_error *err)
{
    drmEventContext ev = {.version = 3, .page_flip_handler2 = flip_done};
    while (c->pending_flips > 0) {
        struct pollfd pfd = {c->fd, POLLIN, 0};
        int n = poll(&pfd, 1, DRM_FLIP_TIMEOUT_MS);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            tess_error_set(err, "%s: no page-flip event within %d ms (an output was unplugged?)", c->path,
                           DRM_FLIP_TIMEOUT_MS);
            c->pending_flips = 0;
            return;
        }
        drmHandleEvent(c->fd, &ev);
    }
}

static bool flip_all(drm_card *c, tess_error *err)
{
    int back[WALL_MAX_OUTPUTS];
    for (int o = 0; o < c->output_count; o++)
        back[o] = c->outputs[o].back;
    if (c->atomic) {
        drmModeAtomicReq *req = drmModeAtomicAlloc();
        bool ok = req && add_frame_props(c, req, back, false) &&
                  drmModeAtomicCommit(c->fd, req, DRM_MODE_ATOMIC_NONBLOCK | DRM_MODE_PAGE_FLIP_EVENT, c) == 0;
        drmModeAtomicFree(req);
        if (!ok)
            return tess_error_set(err, "%s: page flip commit failed: %s", c->path, strerror(errno));
        c->pending_flips = c->output_count; /* one event per CRTC */
    } else {
        for (int o = 0; o < c->output_count; o++) {
            if (drmModePageFlip(c->fd, c->outputs[o].crtc_id, c->outputs[o].buffers[back[o]].fb_id,
                                DRM_MODE_PAGE_FLIP_EVENT, c) != 0)
                return tess_error_set(err, "%s: page flip failed: %s", c->path, strerror(errno));
            c->pending_flips++;
        }
    }
    for (int o = 0; o < c->output_count; o++)
        c->outputs[o].back ^= 1;
    return true;
}

/* The frame into the back buffer: 8-bit sRGB XRGB8888, each pixel written once,
 * rotated from the mounted image to the panel's scan-out orientation. */
static void convert_frame(const frame_image *img, drm_output *out)
{
    drm_buffer *b = &out->buffers[out->back];
    const int mw = img->width_px, mh = img->height_px; /* mounted */
    const int sw = out->mode.hdisplay, sh = out->mode.vdisplay;
    for (int v = 0; v < sh; v++) {
        uint32_t *row = (uint32_t *)(b->map + (size_t)v * b->pitch_bytes);
        for (int u = 0; u < sw; u++) {
            int x, y; /* the mounted pixel scan-out pixel (u, v) shows */
            switch (out->rotation_deg) {
            case 90: x = mw - 1 - v, y = u; break;
            case 180: x = mw - 1 - u, y = mh - 1 - v; break;
            case 270: x = v, y = mh - 1 - u; break;
            default: x = u, y = v; break;
            }
            uint32_t px = 0;
            if (x >= 0 && x < mw && y >= 0 && y < mh) {
                const float *c = img->rgb + 3 * ((size_t)y * (size_t)mw + (size_t)x);
                px = (uint32_t)dump_srgb_encode_u8(c[0]) << 16 | (uint32_t)dump_srgb_encode_u8(c[1]) << 8 |
                     (uint32_t)dump_srgb_encode_u8(c[2]);
            }
            row[u] = px;
        }
    }
}

typedef struct drm_display {
    image_display base;
    drm_card *card;
    int output; /* index into card->outputs = channel index */
} drm_display;

static bool drm_show(image_display *d, const frame_image *img, tess_error *err)
{
    drm_display *dd = (drm_display *)d;
    drm_card *c = dd->card;
    if (dd->output == 0) { /* a new frame: the previous flips must be done before their old fronts are reused */
        wait_flips(c, err);
        if (tess_error_is_set(err))
            return false;
    }
    convert_frame(img, &c->outputs[dd->output]);
    return dd->output == c->output_count - 1 ? flip_all(c, err) : true;
}

static void drm_display_destroy(image_display *d) { free(d); }

static const image_display_ops drm_display_ops = {"drm", drm_show, drm_display_destroy};

bool drm_wall_start(drm_card *c, const wall_config *w, image_display **displays, tess_error *err)
{
    drmModeRes *res = drmModeGetResources(c->fd);
    if (!res)
        return tess_error_set(err, "%s: no mode resources", c->path);
    c->output_count = w->count;
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
        out->width_px = wo->width_px;
        out->height_px = wo->height_px;
        out->back = 1; /* buffer 0 is shown (black) by the modeset */
    }
    ok = ok && assign_crtcs(c, res, err);
    for (int o = 0; o < c->output_count && ok; o++)
        for (int b = 0; b < 2 && ok; b++)
            ok = create_buffer(c, c->outputs[o].mode.hdisplay, c->outputs[o].mode.vdisplay, &c->outputs[o].buffers[b],
                               err);
    drmModeFreeResources(res);
    ok = ok && modeset(c, err);
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
        for (int o = 0; o < c->output_count; o++) {
            for (int b = 0; b < 2; b++)
                free_buffer(c->fd, &c->outputs[o].buffers[b]);
            if (c->outputs[o].mode_blob)
                drmModeDestroyPropertyBlob(c->fd, c->outputs[o].mode_blob);
        }
        c->output_count = 0;
    }
    return ok;
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
        fprintf(f, "%dx%d@%.2f fb %u at %u,%u ->", crtc->mode.hdisplay, crtc->mode.vdisplay,
                mode_refresh_hz(&crtc->mode), crtc->buffer_id, crtc->x, crtc->y);
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
                fprintf(f, "    %dx%d@%.2f%s\n", cn->modes[m].hdisplay, cn->modes[m].vdisplay,
                        mode_refresh_hz(&cn->modes[m]), cn->modes[m].type & DRM_MODE_TYPE_PREFERRED ? " preferred" : "");
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
