/* drm_backend.c (wall) - the drm backend's lifecycle (drm_backend.h). */
#include "drm_backend.h"

#include <stdlib.h>
#include <unistd.h>

#include "drm.h"
#include "seat/session.h"

/* A started drm backend: the seat and the card opened through it. */
typedef struct drm_instance {
    display_instance base; /* first: display_instance_* reach the backend through it */
    session *seat;         /* owned; outlives the card (drm_card_open's rule) */
    drm_card *card;        /* owned; its outputs are up from start to destroy */
} drm_instance;

static drm_instance *drm_of(const display_instance *d)
{
    return (drm_instance *)d;
}

static void drm_destroy(display_instance *d)
{
    drm_instance *di = drm_of(d);
    drm_card_close(di->card); /* the CRTCs as they were */
    session_close(di->seat);
    free(di);
}

static display_instance *drm_start(const display_backend *b, const display_start_args *a, wall_config *w,
                                   image_display **displays, tess_error *err)
{
    (void)b; /* one drm row: nothing of its own beside it */
    drm_instance *di = calloc(1, sizeof *di);
    if (!di) {
        tess_error_set(err, "drm: out of memory");
        return NULL;
    }
    di->seat = session_open();
    if (!di->seat) {
        tess_error_set(err, "seat: out of memory");
        goto fail;
    }
    di->card = drm_card_open(a->card_path && a->card_path[0] ? a->card_path : NULL, di->seat, err);
    if (!di->card)
        goto fail;
    const wall_device_connector *conns;
    size_t n = drm_card_connectors(di->card, &conns);
    if (!wall_config_match_device(w, conns, n, err)) {
        tess_error_prefix(err, "%s: ", drm_card_path(di->card));
        goto fail;
    }
    if (!drm_wall_start(di->card, w, displays, err))
        goto fail;
    fprintf(stderr, "tessera: %s: %d outputs up (%s modesetting)\n", drm_card_path(di->card), w->count,
            drm_card_atomic(di->card) ? "atomic" : "legacy");
    return &di->base;
fail:
    drm_destroy(&di->base);
    return NULL;
}

static void drm_attach(display_instance *d, struct pipeline *p, int first_channel)
{
    drm_wall_attach(drm_of(d)->card, p, first_channel);
}

static void drm_set_pause_hook(display_instance *d, display_pause_fn fn, void *ctx)
{
    drm_card_set_pause_hook(drm_of(d)->card, fn, ctx);
}

static void drm_set_flip_hook(display_instance *d, display_flip_fn fn, void *ctx)
{
    drm_card_set_flip_hook(drm_of(d)->card, fn, ctx);
}

static struct session *drm_seat(const display_instance *d)
{
    return drm_of(d)->seat;
}

/* The kiosk's card: the one `tessera run --wall` looks for when no display is given. */
static bool drm_device_present(void)
{
    return access("/dev/dri/card0", F_OK) == 0;
}

const display_lifecycle drm_display_lifecycle = {
    .start = drm_start,
    .attach = drm_attach,
    .set_pause_hook = drm_set_pause_hook,
    .set_flip_hook = drm_set_flip_hook,
    .seat = drm_seat,
    .destroy = drm_destroy,
    .device_present = drm_device_present,
    .print_outputs = drm_print_outputs,
    .outputs_what = "DRM cards, connectors, monitors (EDID) and modes",
    .outputs_help = "List every DRM card, its connectors (names as wall configs use them), the EDID identity\n"
                    "of each connected monitor and its modes.\n",
    .device_label = "DRM",
    .card_help = "DRM card for --display drm (default: the first with a connected monitor)",
    .kiosk_help = "With --wall FILE and a DRM card (/dev/dri/card0) it is the kiosk: every\n"
                  "output of the wall is driven through DRM/KMS (--display drm), in real time, until\n"
                  "SIGINT/SIGTERM, following hotplug and VT switches (see docs/walls.md).\n",
};
