/* dvr_medium.h - a volume rendered directly (dvr.h) as a participating
 * medium of a scene (scene.h, PARTICIPATING MEDIA): integrated along each
 * primary ray up to its first surface and composited in front of it.
 *
 * Ownership: the medium holds a reference to the shared volume (iso_kind.h,
 * iso_volume: the volume and its macrocell grid, which the volume's
 * iso-surfaces share) and owns its dvr_volume; the scene owns the medium
 * once scene_add_medium took it. TIME STEPS are the shared volume's
 * (iso_kind.h): the medium's step ops step it, and the medium renders
 * whatever step the shared volume shows (it watches the swap; the transfer
 * function keeps step 0's range). Threading: integrate from any thread;
 * step_ready from any thread; set_colormap and set_step only where
 * nothing traces. */
#ifndef TESSERA_DVR_MEDIUM_H
#define TESSERA_DVR_MEDIUM_H

#include "engine/base/colormap.h"
#include "engine/base/err.h"
#include "engine/scene/scene.h"
#include "engine/geometry/volume/dvr.h"
#include "engine/geometry/volume/iso_kind.h"

typedef struct dvr_medium dvr_medium;

/* A medium over `shared` (a reference of its own is taken) through transfer
 * function `tf` with `settings` (NULL: dvr_settings_default()). NULL, err
 * set, on no memory or bad settings. */
dvr_medium *dvr_medium_create(iso_volume *shared, const colormap *tf, const dvr_settings *settings,
                              tess_error *err);
void dvr_medium_destroy(dvr_medium *m); /* NULL is fine; what ops.destroy calls */
const dvr_volume *dvr_medium_volume(const dvr_medium *m);

/* data: a dvr_medium. */
extern const medium_ops dvr_medium_ops;

#endif
