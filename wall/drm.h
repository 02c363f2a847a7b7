/* drm.h - DRM/KMS scan-out for a display wall: one process drives every
 * output of a card straight through KMS, no compositor.
 *
 * Life of a card: drm_card_open (becomes DRM master, saves every CRTC's state)
 * -> drm_card_connectors -> wall_config_match_device -> drm_wall_start (a CRTC
 * and its primary plane per output, two XRGB8888 dumb buffers each, the mode
 * set with one atomic commit tested first with TEST_ONLY, or the legacy API
 * where atomic is missing) -> frames through the displays it returns ->
 * drm_card_close (restores the saved CRTCs, frees the buffers).
 *
 * Frames: each output is a pipeline channel whose display converts the
 * finished float frame into the output's back buffer (8-bit sRGB, rotated to
 * the panel's scan-out orientation), written once and never read back (scan-out
 * memory may be write-combined); the last output of a frame flips every output
 * in one atomic commit (non-blocking, with flip events); the next frame waits
 * for those events before writing, so the pipeline runs at the display's pace. */
#ifndef TESSERA_DRM_H
#define TESSERA_DRM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "engine/display.h"
#include "engine/err.h"
#include "wall_config.h"

typedef struct drm_card drm_card;

/* Open a card: `path`, or NULL for the first /dev/dri/cardN that has a
 * connected connector. NULL with err (no card, not permitted, not master). */
drm_card *drm_card_open(const char *path, tess_error *err);

/* Restore the CRTC configuration found at open, free everything. NULL is fine. */
void drm_card_close(drm_card *c);

const char *drm_card_path(const drm_card *c);

/* The card's connectors, as wall_config_match_device reads them (valid until
 * drm_card_close). */
size_t drm_card_connectors(const drm_card *c, const wall_device_connector **out);

/* Bring up the outputs of `w` (matched to this card) and make one display per
 * output in displays[0 .. w->count): the pipeline channels' displays, in that
 * order. The displays refer to the card: destroy them (the pipeline) before
 * drm_card_close. False with err; nothing is left changed then. */
bool drm_wall_start(drm_card *c, const wall_config *w, image_display **displays, tess_error *err);

/* Whether the card took the atomic path (else legacy). */
bool drm_card_atomic(const drm_card *c);

/* `tessera outputs`: every card, its connectors, EDID identities and modes. */
int drm_print_outputs(FILE *f);

#endif
