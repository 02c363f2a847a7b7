/* session.h (seat) - the seat: who may open the DRM card (and, for input, the event
 * devices) and when, through libseat. libseat reaches seatd or logind, so the
 * kiosk runs without root; as root with neither, its builtin backend (an
 * embedded seatd) does the same job, including VT switching. When no seat can
 * be opened at all (no VT, e.g. a container) devices are opened directly
 * (root), with no VT handling.
 *
 * VT switches: when the user switches away, the seat asks us to release the
 * devices (session_disable_pending); the owner stops touching them (no ioctl,
 * no commit) and acknowledges with session_ack_disable; the seat manager then
 * revokes DRM master. When the user comes back, session_active turns true
 * again and the owner restores its state (the console changed the CRTCs).
 *
 * Threading: one thread at a time (the pipeline's display thread while
 * running, the main thread before and after); libseat calls the listener
 * inside session_dispatch on that thread, so the flags need no lock. */
#ifndef TESSERA_SEAT_SESSION_H
#define TESSERA_SEAT_SESSION_H

#include <stdbool.h>

#include "engine/base/err.h"

typedef struct session session;

/* Open the seat and wait (up to a few seconds) until it is enabled. Never
 * NULL except out of memory: without a seat the session opens devices
 * directly (logged once, with libseat's reason). */
session *session_open(void);
void session_close(session *s); /* closes devices still open; NULL is fine */

/* Whether a seat manages the devices (else: direct, root). */
bool session_has_seat(const session *s);

/* Open a device node (e.g. /dev/dri/card0) through the seat, else with
 * open(2) read-write. The fd, or -1 with err naming the path and why. */
int session_open_device(session *s, const char *path, tess_error *err);
void session_close_device(session *s, int fd);

/* Handle the seat's events, waiting up to timeout_ms (0: only what is there). */
void session_dispatch(session *s, int timeout_ms);

/* The seat is ours: devices may be used. */
bool session_active(const session *s);

/* The seat asked us to let go (a VT switch away): stop touching the devices,
 * then session_ack_disable. */
bool session_disable_pending(const session *s);
void session_ack_disable(session *s);

#endif
