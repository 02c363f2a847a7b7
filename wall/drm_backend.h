/* drm_backend.h (wall) - the drm row of the display-backend table
 * (display_backend.h): its lifecycle over drm.h. start opens the seat
 * (seat/session.h) and the card through it (--card, else the first with a
 * connected monitor), matches the wall's outputs to the card's connectors
 * and brings them up (drm_wall_start); the instance owns the seat and the
 * card, and destroy restores the CRTCs found at start and closes both. */
#ifndef TESSERA_WALL_DRM_BACKEND_H
#define TESSERA_WALL_DRM_BACKEND_H

#include "display_backend.h"

extern const display_lifecycle drm_display_lifecycle;

#endif
