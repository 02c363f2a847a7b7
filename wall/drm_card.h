/* drm_card.h (wall) - the DRM card's state, private to the DRM backend:
 * drm.c (cards, connectors, CRTC choice, buffers, hotplug, the display) and
 * its two modesetting paths behind one table, drm_kms_ops: drm_atomic.c
 * (one atomic commit for every output, tested with TEST_ONLY first) and
 * drm_legacy.c (drmModeSetCrtc and one page flip per CRTC), as wlroots'
 * backend/drm splits atomic.c and legacy.c. drm_card_open picks one when the
 * card takes (or refuses) the atomic client cap; nothing else asks which.
 *
 * Threading: as drm.h; every entry of drm_kms_ops runs on the display thread
 * (or in drm_wall_start before the pipeline runs). */
#ifndef TESSERA_WALL_DRM_CARD_H
#define TESSERA_WALL_DRM_CARD_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>
#include <xf86drmMode.h>

#include "drm.h"
#include "edid.h"
#include "engine/base/err.h"
#include "wall_config.h"

struct udev;
struct udev_monitor;
typedef struct pipeline pipeline;

typedef struct drm_kms_ops drm_kms_ops;

/* Frame f is written into buffer f % DRM_FRAME_BUFFERS by the render threads
 * while f-1 waits for its flip and f-2 is on screen; until the flip to f-2
 * has completed (waited for at the end of the display stage of frame f-1,
 * before frame f starts) f-3 is on screen. So four never collide. */
#define DRM_FRAME_BUFFERS 4
#define DRM_PROP_CACHE 512 /* (object, property) pairs: outputs x (connector 1 + CRTC 2 + plane 10), spare for replugs */

typedef struct drm_buffer {
    uint32_t handle, fb_id, pitch_bytes;
    uint64_t size_bytes;
    uint8_t *map; /* write-only: scan-out memory may be write-combined */
} drm_buffer;

/* One output of the wall. Fixed after drm_wall_start: rotation, sizes,
 * buffers (render threads write them through write_tile). The rest belongs to
 * the display thread (show, end_stage) and drm_card_close. */
typedef struct drm_output {
    uint32_t connector_id, crtc_id, plane_id;
    uint32_t mode_blob;          /* atomic: MODE_ID blob */
    drmModeModeInfo mode;
    int rotation_deg;            /* as mounted, clockwise (wall_config.h) */
    drm_buffer buffers[DRM_FRAME_BUFFERS];
    drm_buffer blank;            /* black: what a modeset shows before the first frame */
    bool live;                   /* being driven (false once its monitor is unplugged) */
    int ready;                   /* buffer of a finished frame to flip to at end_stage, -1 if none */
    bool flip_pending;           /* its flip was queued and its event has not come yet */
    drm_flip_outcome flip;       /* what became of its last flip, until judged at the next end_stage */
    bool given_up;               /* switched off for failing flips: stays dark until its monitor is seen
                                    unplugged (then it may come back like any unplugged one) */
} drm_output;

/* A property id of one KMS object, by name (a string literal). */
typedef struct drm_prop_entry {
    uint32_t object;
    const char *name;
    uint32_t id;
} drm_prop_entry;

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
    session *session;             /* opened fd through it; VT switches come from it */
    char path[64];
    const drm_kms_ops *kms;       /* the atomic or the legacy path, chosen once at open */
    drm_connector_info *infos;
    wall_device_connector *conns; /* parallel to infos */
    size_t conn_count;
    drmModeCrtc **saved_crtcs;    /* the CRTC states found at open */
    int saved_count;
    drm_output outputs[WALL_MAX_OUTPUTS];
    int output_count;
    wall_config wall;             /* as matched at drm_wall_start: hotplug plans against it */
    int pending_flips;            /* flip events still to come; display thread only */
    uint64_t ready_frame;         /* the newest frame show() handed us (display thread) */
    uint64_t flipping_frame;      /* the frame the last commit flips to (display thread) */
    bool settled;                 /* settle() ran this display stage; end_stage clears it (display thread) */
    bool commit_due;              /* settle() found the stage's frame to flip (display thread) */
    drm_flip_health flip_health;  /* per output: stages in a row whose flips failed (display thread) */
    /* hotplug (display thread): udev's connector-change events for this card */
    struct udev *udev;
    struct udev_monitor *monitor; /* NULL: no udev; only flip timeouts make us probe */
    dev_t devnum;
    bool probe_needed;            /* read the connectors again at the next end_stage */
    pipeline *pipeline;           /* whose channels first_channel.. are the outputs (drm_wall_attach) */
    int first_channel;
    drm_pause_fn pause_fn;        /* told while a VT switch pauses the wall (display thread) */
    void *pause_ctx;
    drm_flip_fn flip_fn;          /* told of each completed flip (display thread) */
    void *flip_ctx;
    /* property ids by (object, name), looked up once: a flip then costs no property ioctls
     * (display thread, and drm_wall_start before it) */
    drm_prop_entry prop_cache[DRM_PROP_CACHE];
    int prop_cached;
};

/* A modesetting path. */
struct drm_kms_ops {
    const char *name;         /* "atomic" or "legacy" */
    bool needs_primary_plane; /* an output without a primary plane cannot be driven */
    /* light outputs [first, last] in their modes, showing their blank buffers; false with err
     * (`what` names the change in it) */
    bool (*modeset)(drm_card *c, int first, int last, const char *what, tess_error *err);
    /* switch output o off (connector, CRTC and plane released); false with err */
    bool (*disable)(drm_card *c, int o, tess_error *err);
    /* queue a flip with a page-flip event (data: c) for every live output with a ready buffer:
     * each queued one gets flip_pending, each refused one flip = DRM_FLIP_REFUSED; returns
     * how many were queued, *refused how many refused and *refused_errno why */
    int (*flip)(drm_card *c, int *refused, int *refused_errno);
};

extern const drm_kms_ops drm_kms_atomic;
extern const drm_kms_ops drm_kms_legacy;

#endif
