/* remote.h (remote) - the remote view: the kiosk serves a page and a
 * WebSocket endpoint (libwebsockets, on a thread of its own) so a tablet or
 * laptop browser shows the wall's picture and steers it
 * (docs/remote-protocol.md). Its parts:
 *   - one FOLLOW CHANNEL of the pipeline shows the wall's whole plane through
 *     the wall's camera at the view's size; it is rendered only while a
 *     viewer follows the wall (switched on and off by transactions); its
 *     display is remote_view_display (remote/encoder.h: JPEG off the render
 *     path);
 *   - PRIVATE VIEWS: up to private_views PRIVATE CHANNELS of the same size
 *     (engine/scene/frame_state.h: the wall's camera passes them by, they draw no
 *     cursor or pointers), each lent to one viewer that asked for a camera
 *     of its own ({"t":"view","private":true}). The viewer's held input is
 *     released in the wall's controller, then its device is given a private
 *     view's controller steering that channel (input/runner.h, PRIVATE
 *     VIEWS), which starts from the wall's camera and switches the channel
 *     on; following the wall again (or leaving) removes the device, which
 *     ends the view and switches the channel off. A private view's scene
 *     commands (hide, planes, ...) are not carried out: they are the shared
 *     view's (input/controller.h, PRIVATE VIEW). Frames shown before a
 *     switch are never sent after it;
 *   - the server sends each viewer the newest encoded frame when its
 *     connection can take it and fewer than REMOTE_IN_FLIGHT_MAX frames are
 *     unacknowledged, so a slow viewer gets fewer frames and never slows the
 *     wall;
 *   - viewers' messages become input events of an input source
 *     (remote/source.h) the input runner polls with libinput's devices: the
 *     same mapping layer, the same gestures;
 *   - access: bound to 127.0.0.1 unless configured, a token in the URL,
 *     at most max_viewers viewers, message size and rate limits; malformed
 *     messages are dropped and counted by reason.
 * Life: remote_view_create (before the pipeline's channels: its display),
 * remote_view_take_source (to the input runner), remote_view_start (after
 * the pipeline exists; prints the URL), the run, remote_view_stop (before
 * the input runner stops: the source is the runner's), pipeline_destroy,
 * remote_view_destroy.
 *
 * Threading: create/start/stop/destroy on one thread (the CLI's); the server
 * thread owns every viewer's state; the encoder thread and the display
 * thread work through remote/encoder.h. */
#ifndef TESSERA_REMOTE_REMOTE_H
#define TESSERA_REMOTE_REMOTE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "engine/render/display.h"
#include "engine/base/err.h"
#include "input/source.h"
#include "jpeg.h"
#include "protocol.h"

struct pipeline;

#define REMOTE_TOKEN_BYTES 65      /* a token's text with its NUL: at most 64 characters */
#define REMOTE_TOKEN_MIN 8
#define REMOTE_IN_FLIGHT_MAX 2     /* frames sent to a viewer and not yet acknowledged */
#define REMOTE_DEFAULT_VIEWERS 4
#define REMOTE_DEFAULT_WIDTH 1280
#define REMOTE_DEFAULT_HEIGHT 720
#define REMOTE_DEFAULT_QUALITY 80

typedef struct remote_config {
    int port;                      /* 0..65535 (0: a free port); -1: no remote view */
    char bind[64];                 /* the address to listen on: "127.0.0.1" unless configured */
    char token[REMOTE_TOKEN_BYTES]; /* "": a random one (32 hex digits) */
    int max_viewers;               /* 1..INPUT_MAX_VIEWERS */
    int private_views;             /* private channels, 0..max_viewers; -1 (default): max_viewers */
    int width_px, height_px;       /* the largest frame; the follow channel fits the plane's aspect in it */
    int quality;                   /* JPEG quality, REMOTE_JPEG_QUALITY_MIN..MAX */
    remote_subsampling subsampling;
} remote_config;

/* Off (port -1), 127.0.0.1, a random token, REMOTE_DEFAULT_* values, 4:2:0. */
void remote_config_default(remote_config *c);
/* False with err naming the field ("remote.port", ...) and the problem. */
bool remote_config_validate(const remote_config *c, tess_error *err);

typedef struct remote_view remote_view;

/* The encoder and the input source (the server starts later). NULL with err. */
remote_view *remote_view_create(const remote_config *c, tess_error *err);
/* The follow channel's display, to add to the pipeline (it owns it). Once. */
image_display *remote_view_display(remote_view *v);
/* Private channels the view was made for (private_views resolved). */
int remote_view_private_count(const remote_view *v);
/* Private channel k's display (0..remote_view_private_count-1), to add to the
 * pipeline as a private channel (it owns it). Once each; NULL after. */
image_display *remote_view_private_display(remote_view *v, int k);

/* The view's channels in the pipeline: the follow channel, and the private
 * channels first .. first + count - 1 (count: how many were added, maybe
 * fewer than remote_view_private_count when the pipeline had no room). */
typedef struct remote_channels {
    int follow;
    int private_first, private_count;
} remote_channels;
/* The input source, handed to the input runner (which destroys it). Once. */
input_source *remote_view_take_source(remote_view *v);

/* Start serving over the channels `ch` of p (each width_px x height_px;
 * switched off here, before the run: call while no loop runs); viewers'
 * input events carry plane points over `area` (the whole plane). Prints
 * "tessera: remote view: http://HOST:PORT/?token=TOKEN" on stderr. False
 * with err (a port in use names the port). */
bool remote_view_start(remote_view *v, struct pipeline *p, const remote_channels *ch, int width_px, int height_px,
                       camera_window area, tess_error *err);

/* Stop serving (viewers disconnected, the server thread joined).
 * Idempotent; NULL is fine. */
void remote_view_stop(remote_view *v);

/* Free everything; after remote_view_stop and after the pipeline (which owns
 * the display) is destroyed. NULL is fine. */
void remote_view_destroy(remote_view *v);

typedef struct remote_stats {
    uint64_t viewers_accepted;
    uint64_t refused_token, refused_full, refused_other; /* connections refused */
    uint64_t pages_served, http_refused;
    uint64_t frames_sent, bytes_sent;
    uint64_t frames_skipped;   /* frames encoded while a viewer was connected that it never got */
    uint64_t messages;         /* accepted */
    uint64_t dropped[REMOTE_DROP_REASONS];
    uint64_t input_overflow;   /* messages whose events did not fit the input queue */
    uint64_t private_views;    /* private views started */
    uint64_t private_refused;  /* asked for when every private channel was lent */
} remote_stats;

/* The counts so far (exact after remote_view_stop). */
remote_stats remote_view_stats(remote_view *v);
/* The counts and the encoder's times as a few lines. */
void remote_view_print_stats(remote_view *v, FILE *out);

#endif
