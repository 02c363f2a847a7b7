/* service.h - telling the service manager (systemd, sd_notify(3)) how the
 * kiosk is doing, so that a wall that stops moving is restarted without
 * anybody there (configs/systemd/tessera-kiosk.service, docs/kiosk.md: installing a
 * kiosk). A platform service like the seat (seat/session.h): the engine knows
 * nothing of it; the run command attaches it to the pipeline.
 *
 * What is sent, on the socket NOTIFY_SOCKET names:
 *   READY=1     once the outputs are up and the first frame has been shown
 *               (the first serial section after frame 0's display stage);
 *   WATCHDOG=1  from the frame loop (a serial animation callback, so only a
 *               loop that completes frames sends it), at most every
 *               WATCHDOG_USEC / SERVICE_PINGS_PER_INTERVAL: a loop step may
 *               take up to 3/4 of WatchdogSec before systemd sees silence.
 *               A loop stuck for longer stops the pings and systemd restarts
 *               the process. A legitimate pause (the wall switched away from
 *               its VT and waiting for the seat: the display stage blocks)
 *               feeds it through service_notifier_paused;
 *   STATUS=     "running: 23.9 frames/s, 4 of 4 outputs up", "paused: ...",
 *               "stopping after N frames": with READY, on a change of the
 *               outputs up or of the pause, else at most every
 *               SERVICE_STATUS_PERIOD_S (systemctl status shows the last);
 *   STOPPING=1  when the frame loop ends.
 *
 * Without NOTIFY_SOCKET (not started by systemd) service_notifier_create
 * returns NULL, nothing is attached, and every function takes NULL and does
 * nothing: it costs nothing.
 *
 * Threading: the frame loop only decides what to say and posts it to a
 * small sender thread (a mailbox: flags and the newest status line, under a
 * mutex), which makes the sd_notify calls: no I/O at the frame barrier. The
 * loop's side is used by the pipeline's serial section and by its display
 * thread (service_notifier_paused, from a display's end_stage); those never
 * run at once (the display stage ends before thread 0 reaches the frame
 * barrier, which orders them), so that side has no lock. Create, attach and
 * destroy on the thread that runs the pipeline, outside the run; destroy
 * sends what is still posted (STOPPING=1) before it returns. */
#ifndef TESSERA_SERVICE_H
#define TESSERA_SERVICE_H

#include <stdbool.h>

struct pipeline;

/* WATCHDOG=1 this many times per watchdog interval (systemd's documentation
 * asks for at least 2): pings go at most interval / 4 apart, so a frame may
 * take 3/4 of the interval without the watchdog firing. */
#define SERVICE_PINGS_PER_INTERVAL 4
/* STATUS= at most this often while nothing changes: fresh enough for
 * `systemctl status`, one datagram a second at most. */
#define SERVICE_STATUS_PERIOD_S 1.0

typedef struct service_notifier service_notifier;

/* A notifier when NOTIFY_SOCKET is set (the watchdog armed when systemd asks
 * for one: WATCHDOG_USEC, WATCHDOG_PID), else NULL. Also NULL (logged) out of
 * memory: a kiosk runs on without telling. */
service_notifier *service_notifier_create(void);
void service_notifier_destroy(service_notifier *sn); /* NULL is fine */

/* The watchdog interval systemd asked for, in seconds; 0 when none. */
double service_notifier_watchdog_s(const service_notifier *sn);

/* Report on the pipeline's frames (a serial animation and a termination
 * callback); its channels 0 .. outputs-1 are the outputs STATUS counts (the
 * rest, e.g. a remote view's, are not; -1: every channel). After the
 * channels are added, before pipeline_run. sn NULL: does nothing, returns
 * true. */
bool service_notifier_attach(service_notifier *sn, struct pipeline *p, int outputs);

/* The frame loop is paused for a healthy reason and waits (why, e.g.
 * "switched away from our VT"): call at least every interval / 4 while it
 * lasts: feeds the watchdog (rate-limited) and says so in STATUS. why NULL:
 * the pause is over (the next frame says "running"). */
void service_notifier_paused(service_notifier *sn, const char *why);

/* Whether a watchdog ping is due at now_s when the last went at last_s (a
 * negative last_s: never), for an interval of interval_s (> 0). Pure. */
bool service_watchdog_due(double now_s, double last_s, double interval_s);

#endif
