/* remote.c (remote) - the remote view's server: libwebsockets on its own
 * thread, the page, viewers, frames out, messages in (remote.h). */
#define _DEFAULT_SOURCE /* getifaddrs */
#include "remote.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <libwebsockets.h>
#include <net/if.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

#include "engine/base/clock.h"
#include "engine/base/log.h"
#include "engine/render/overlay.h"
#include "engine/frame/pipeline.h"
#include "engine/base/thread_name.h"
#include "encoder.h"
#include "page.h"
#include "source.h"

#define PROTOCOL_NAME "tessera-remote-1"
#define TEXT_MAX 512 /* a server->page text message */
#define POLICY_TEXT                                                                                               \
    "One person steers the camera at a time: whoever starts a drag, touch or wheel first holds it until the "     \
    "gesture ends; other gestures meanwhile only move their pointer. A private view has a camera of its own "   \
    "that only its viewer steers."

/* One connected viewer: the server thread's alone. */
typedef struct viewer {
    bool used;
    struct lws *wsi;
    remote_viewer_input input;
    remote_rate rate;
    char rx[REMOTE_MESSAGE_MAX_BYTES]; /* the message being received */
    size_t rx_bytes;
    bool rx_too_long, rx_binary;
    char text[2][TEXT_MAX];            /* text messages waiting to go out, oldest first */
    int text_count;
    int in_flight;                     /* frames sent, not acknowledged */
    uint64_t last_sent;                /* frame number; UINT64_MAX: none yet */
    int view;                          /* the encoder channel it is sent: 0 the follow channel, 1 + k
                                          private channel k */
    int private_k;                     /* its private channel, -1: it follows the wall */
    uint64_t since_us;                 /* frames shown before this (its last switch) are not sent */
    uint64_t first_frame;              /* its view's newest frame when it came to it (UINT64_MAX: none) */
    uint64_t first_sent;               /* the first frame of its view sent to it (UINT64_MAX: none yet) */
    uint64_t sent_here;                /* frames of its view sent to it */
    uint64_t sent;                     /* frames sent to it */
} viewer;

/* What lws keeps per connection (zeroed by lws when it starts): which viewer
 * it is, as slot + 1 (0: none, also for a connection refused before it
 * became a viewer), why a WebSocket is refused (0: it is not; else its close
 * code, REMOTE_CLOSE_*: the handshake completes and the socket is closed
 * with that code and a reason, because a browser's WebSocket cannot see a
 * refused handshake's status), and for the page, how far it is written. */
typedef struct session {
    int slot_plus_1;
    int refuse;
    size_t page_written;
} session;

struct remote_view {
    remote_config cfg;
    char token[REMOTE_TOKEN_BYTES];
    remote_encoder *encoder;
    remote_source *source;
    bool source_taken, display_taken;
    image_display *display; /* until taken */
    int private_count;      /* private channels made for (encoder channels 1..private_count) */
    image_display *private_displays[INPUT_MAX_VIEWERS]; /* until taken */
    struct pipeline *p;
    remote_channels channels;
    int width_px, height_px;
    camera_window area;
    pthread_mutex_t context_lock; /* guards `context` against the encoder thread's wake-ups while it goes */
    struct lws_context *context;  /* context_lock for the encoder thread; the server thread's while it runs */
    struct lws_vhost *vhost;
    pthread_t thread;
    bool started;
    atomic_bool stop;
    atomic_bool server_done;           /* the server thread has said goodbye to its viewers */
    bool stopping;                     /* the connections are being closed (by the server thread,
                                          then remote_view_stop): the run is over, nothing more
                                          goes to input (so a recording ends with what the wall
                                          showed) or to the pipeline */
    viewer viewers[INPUT_MAX_VIEWERS]; /* server thread */
    int viewer_count;                  /* server thread */
    int following;                     /* server thread: viewers following the wall */
    bool private_lent[INPUT_MAX_VIEWERS]; /* server thread: private channel k is some viewer's */
    uint8_t *send_buf;                 /* server thread: LWS_PRE + header + JPEG */
    size_t send_capacity;
    remote_stats stats;                /* server thread; read after stop (or racily, for a glance) */
};

static const struct lws_protocols protocols[];

void remote_config_default(remote_config *c)
{
    memset(c, 0, sizeof *c);
    c->port = -1;
    snprintf(c->bind, sizeof c->bind, "127.0.0.1");
    c->max_viewers = REMOTE_DEFAULT_VIEWERS;
    c->private_views = -1;
    c->width_px = REMOTE_DEFAULT_WIDTH;
    c->height_px = REMOTE_DEFAULT_HEIGHT;
    c->quality = REMOTE_DEFAULT_QUALITY;
    c->subsampling = REMOTE_SUBSAMPLING_420;
}

bool remote_config_validate(const remote_config *c, tess_error *err)
{
    if (c->port < -1 || c->port > 65535)
        return tess_error_set(err, "remote.port: %d is not a port (0..65535; 0: a free one)", c->port);
    struct in_addr a;
    if (inet_pton(AF_INET, c->bind, &a) != 1)
        return tess_error_set(err, "remote.bind: '%s' is not an IPv4 address (127.0.0.1, 0.0.0.0 for every network)",
                              c->bind);
    size_t n = strlen(c->token);
    if (n) {
        if (n < REMOTE_TOKEN_MIN || n >= REMOTE_TOKEN_BYTES)
            return tess_error_set(err, "remote.token: %zu characters (%d..%d)", n, REMOTE_TOKEN_MIN,
                                  REMOTE_TOKEN_BYTES - 1);
        for (size_t i = 0; i < n; i++) {
            char ch = c->token[i];
            bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '-' ||
                      ch == '_';
            if (!ok)
                return tess_error_set(err, "remote.token: character %zu '%c' (only A-Z a-z 0-9 - _)", i + 1, ch);
        }
    }
    if (c->max_viewers < 1 || c->max_viewers > INPUT_MAX_VIEWERS)
        return tess_error_set(err, "remote.max_viewers: %d (1..%d)", c->max_viewers, INPUT_MAX_VIEWERS);
    if (c->private_views < -1 || c->private_views > c->max_viewers)
        return tess_error_set(err, "remote.private_views: %d (0..max_viewers = %d)", c->private_views, c->max_viewers);
    if (c->width_px < 16 || c->width_px > 4096 || c->height_px < 16 || c->height_px > 4096)
        return tess_error_set(err, "remote.width/height: %dx%d (16..4096 each)", c->width_px, c->height_px);
    if (c->quality < REMOTE_JPEG_QUALITY_MIN || c->quality > REMOTE_JPEG_QUALITY_MAX)
        return tess_error_set(err, "remote.quality: %d (%d..%d)", c->quality, REMOTE_JPEG_QUALITY_MIN,
                              REMOTE_JPEG_QUALITY_MAX);
    return true;
}

/* ---- helpers ------------------------------------------------------------------- */

/* Equal without an early exit, so the time taken does not tell how much of a guess was right. */
static bool token_equal(const char *a, const char *b)
{
    size_t na = strlen(a), nb = strlen(b);
    unsigned diff = (unsigned)(na != nb);
    for (size_t i = 0; i < na && i < REMOTE_TOKEN_BYTES; i++)
        diff |= (unsigned)(unsigned char)a[i] ^ (unsigned)(unsigned char)(i < nb ? b[i] : 0);
    return diff == 0;
}

static bool request_token_ok(remote_view *v, struct lws *wsi)
{
    char buf[REMOTE_TOKEN_BYTES + 16];
    const char *t = lws_get_urlarg_by_name(wsi, "token=", buf, (int)sizeof buf);
    return t && token_equal(t, v->token);
}

static void queue_text(viewer *vw, const char *text)
{
    if (vw->text_count == 2) { /* the older one goes: only errors can pile up */
        memmove(vw->text[0], vw->text[1], TEXT_MAX);
        vw->text_count = 1;
    }
    snprintf(vw->text[vw->text_count++], TEXT_MAX, "%s", text);
    lws_callback_on_writable(vw->wsi);
}

static void push_events(remote_view *v, const input_event *events, int count)
{
    if (count > 0 && !remote_source_push(v->source, events, count))
        v->stats.input_overflow++;
}

/* The follow channel on while anybody follows the wall, off when nobody does. */
static void following_changed(remote_view *v, int delta)
{
    int before = v->following;
    v->following += delta;
    if ((before == 0) == (v->following == 0) || v->stopping) /* stopping: the pipeline has stopped */
        return;
    bool needed = v->following > 0;
    if (!pipeline_queue_channel_active(v->p, v->channels.follow, needed))
        log_warn("remote view: switching the view's channel %s was refused", needed ? "on" : "off");
}

/* The viewer starts watching encoder channel `view` now: nothing shown before goes to it. */
static void viewer_watch(remote_view *v, viewer *vw, int view)
{
    vw->view = view;
    vw->since_us = clock_monotonic_us();
    vw->last_sent = vw->first_sent = UINT64_MAX;
    vw->sent_here = 0;
    vw->first_frame = remote_encoder_newest_frame(v->encoder, view);
}

/* ---- viewers ------------------------------------------------------------------- */

static int viewer_attach(remote_view *v, struct lws *wsi, session *ss)
{
    int slot = -1;
    for (int i = 0; i < v->cfg.max_viewers && slot < 0; i++)
        if (!v->viewers[i].used)
            slot = i;
    if (slot < 0) { /* filtered before, so two connections raced for the last place */
        v->stats.refused_full++;
        ss->refuse = REMOTE_CLOSE_FULL;
        lws_callback_on_writable(wsi);
        return 0;
    }
    viewer *vw = &v->viewers[slot];
    memset(vw, 0, sizeof *vw);
    vw->used = true;
    vw->wsi = wsi;
    vw->private_k = -1;
    uint64_t now = clock_monotonic_us();
    remote_viewer_input_init(&vw->input, slot);
    remote_rate_init(&vw->rate, now);
    viewer_watch(v, vw, 0);
    ss->slot_plus_1 = slot + 1;
    v->viewer_count++;
    following_changed(v, +1);
    v->stats.viewers_accepted++;
    input_event added = {.kind = INPUT_DEVICE_ADDED, .time_us = now, .device = vw->input.device};
    push_events(v, &added, 1);
    char colour[8], hello[TEXT_MAX];
    overlay_pointer_colour_hex(slot, colour);
    snprintf(hello, sizeof hello,
             "{\"type\":\"hello\",\"viewer\":%d,\"colour\":\"%s\",\"width\":%d,\"height\":%d,\"private_views\":%d,"
             "\"policy\":\"%s\"}",
             slot, colour, v->width_px, v->height_px, v->channels.private_count, POLICY_TEXT);
    queue_text(vw, hello);
    log_info("remote view: viewer %d connected", slot);
    return 0;
}

/* Frames of the channel this viewer could have had and did not get. */
static void count_skipped(remote_view *v, const viewer *vw)
{
    /* the first frame it could have had: the one after the newest when it came, else (the
     * channel was off until it came) the first one it was sent */
    uint64_t from = vw->first_frame != UINT64_MAX ? vw->first_frame + 1 : vw->first_sent;
    uint64_t newest = remote_encoder_newest_frame(v->encoder, vw->view);
    if (from == UINT64_MAX || newest == UINT64_MAX)
        return;
    uint64_t available = newest >= from ? newest - from + 1 : 0;
    if (available > vw->sent_here)
        v->stats.frames_skipped += available - vw->sent_here;
}

static void viewer_detach(remote_view *v, session *ss)
{
    if (ss->slot_plus_1 <= 0)
        return;
    int slot = ss->slot_plus_1 - 1;
    viewer *vw = &v->viewers[slot];
    input_event released[REMOTE_EVENTS_MAX];
    int n = remote_viewer_input_release(&vw->input, clock_monotonic_us(), released);
    if (!v->stopping)
        push_events(v, released, n);
    count_skipped(v, vw);
    log_info("remote view: viewer %d left (%llu frames sent)", slot, (unsigned long long)vw->sent);
    if (vw->private_k >= 0) /* its removal (above) ended the view in the input runner */
        v->private_lent[vw->private_k] = false;
    else
        following_changed(v, -1);
    vw->used = false;
    vw->wsi = NULL;
    ss->slot_plus_1 = 0;
    v->viewer_count--;
}

/* {"t":"view"}: a camera of its own (a free private channel) or the wall's again. */
static void viewer_switch_view(remote_view *v, viewer *vw, bool want_private)
{
    char text[TEXT_MAX];
    if (want_private == (vw->private_k >= 0))
        goto tell;
    int k = -1;
    for (int i = 0; i < v->channels.private_count && k < 0 && want_private; i++)
        if (!v->private_lent[i])
            k = i;
    if (want_private && k < 0) {
        v->stats.private_refused++;
        snprintf(text, sizeof text,
                 "{\"type\":\"error\",\"text\":\"no private view is free (%d, all in use; remote.private_views): "
                 "this view follows the wall\"}",
                 v->channels.private_count);
        queue_text(vw, text);
        goto tell;
    }
    /* what it holds is let go where it was steering (the wall's controller, or its private
     * one, whose removal ends the view), then it comes back as a device of its new view */
    uint64_t now = clock_monotonic_us();
    input_event events[REMOTE_EVENTS_MAX + 2];
    int n = remote_viewer_input_release(&vw->input, now, events);
    events[n++] = (input_event){.kind = INPUT_DEVICE_ADDED, .time_us = now, .device = vw->input.device};
    if (want_private)
        events[n++] = (input_event){.kind = INPUT_PRIVATE_VIEW, .time_us = now, .device = vw->input.device,
                                    .code = v->channels.private_first + k};
    if (!remote_source_push(v->source, events, n)) { /* the input queue is full: no switch half made */
        v->stats.input_overflow++;
        queue_text(vw, "{\"type\":\"error\",\"text\":\"the kiosk is busy: the view was not switched, try again\"}");
        goto tell;
    }
    count_skipped(v, vw);
    if (want_private) {
        v->private_lent[k] = true;
        vw->private_k = k;
        v->stats.private_views++;
        following_changed(v, -1);
        viewer_watch(v, vw, 1 + k);
        log_info("remote view: viewer %d has a private view (channel %d)", vw->input.slot,
                 v->channels.private_first + k);
    } else {
        v->private_lent[vw->private_k] = false;
        vw->private_k = -1;
        following_changed(v, +1);
        viewer_watch(v, vw, 0);
        log_info("remote view: viewer %d follows the wall again", vw->input.slot);
    }
tell:
    snprintf(text, sizeof text, "{\"type\":\"view\",\"private\":%s}", vw->private_k >= 0 ? "true" : "false");
    queue_text(vw, text);
}

static void viewer_message(remote_view *v, viewer *vw)
{
    remote_drop_reason reason;
    remote_message m;
    uint64_t now = clock_monotonic_us();
    if (vw->rx_binary)
        reason = REMOTE_DROP_BINARY;
    else if (vw->rx_too_long)
        reason = REMOTE_DROP_TOO_LONG;
    else if (!remote_rate_take(&vw->rate, now))
        reason = REMOTE_DROP_RATE;
    else if (remote_message_parse(vw->rx, vw->rx_bytes, &m, &reason))
        goto parsed;
    v->stats.dropped[reason]++;
    return;
parsed:
    v->stats.messages++;
    if (m.kind == REMOTE_MSG_ACK) {
        if (vw->in_flight > 0)
            vw->in_flight--;
        lws_callback_on_writable(vw->wsi);
        return;
    }
    if (m.kind == REMOTE_MSG_VIEW) {
        viewer_switch_view(v, vw, m.private_view);
        return;
    }
    input_event events[REMOTE_EVENTS_MAX];
    push_events(v, events, remote_message_events(&vw->input, &m, &v->area, now, events));
}

static void viewer_receive(remote_view *v, struct lws *wsi, viewer *vw, const void *in, size_t len)
{
    if (lws_is_first_fragment(wsi)) {
        vw->rx_bytes = 0;
        vw->rx_too_long = false;
        vw->rx_binary = lws_frame_is_binary(wsi);
    }
    if (vw->rx_bytes + len > sizeof vw->rx)
        vw->rx_too_long = true;
    else {
        memcpy(vw->rx + vw->rx_bytes, in, len);
        vw->rx_bytes += len;
    }
    if (lws_is_final_fragment(wsi) && lws_remaining_packet_payload(wsi) == 0)
        viewer_message(v, vw);
}

/* One write per writeable callback (libwebsockets' rule): a waiting text
 * message first, else the newest frame if it may go. */
static int viewer_writeable(remote_view *v, viewer *vw)
{
    if (vw->text_count > 0) {
        size_t n = strlen(vw->text[0]);
        if (LWS_PRE + n > v->send_capacity) {
            uint8_t *grown = realloc(v->send_buf, LWS_PRE + TEXT_MAX);
            if (!grown)
                return -1;
            v->send_buf = grown;
            v->send_capacity = LWS_PRE + TEXT_MAX;
        }
        memcpy(v->send_buf + LWS_PRE, vw->text[0], n);
        memmove(vw->text[0], vw->text[1], TEXT_MAX);
        vw->text_count--;
        if (lws_write(vw->wsi, v->send_buf + LWS_PRE, n, LWS_WRITE_TEXT) < (int)n)
            return -1;
        lws_callback_on_writable(vw->wsi);
        return 0;
    }
    if (vw->in_flight >= REMOTE_IN_FLIGHT_MAX)
        return 0; /* its next ack asks again */
    remote_encoded_info info;
    if (!remote_encoder_copy_newest(v->encoder, vw->view, vw->last_sent, vw->since_us, &v->send_buf,
                                    &v->send_capacity, LWS_PRE + REMOTE_FRAME_HEADER_BYTES, &info))
        return 0; /* the encoder's next frame asks again */
    remote_frame_header(v->send_buf + LWS_PRE, info.frame, info.camera_serial, info.width_px, info.height_px,
                        (uint32_t)info.jpeg_bytes);
    size_t n = REMOTE_FRAME_HEADER_BYTES + info.jpeg_bytes;
    if (lws_write(vw->wsi, v->send_buf + LWS_PRE, n, LWS_WRITE_BINARY) < (int)n)
        return -1;
    vw->last_sent = info.frame;
    if (vw->first_sent == UINT64_MAX)
        vw->first_sent = info.frame;
    vw->in_flight++;
    vw->sent++;
    vw->sent_here++;
    v->stats.frames_sent++;
    v->stats.bytes_sent += n;
    return 0;
}

/* ---- HTTP ---------------------------------------------------------------------- */

static int http_refuse(remote_view *v, struct lws *wsi, unsigned status, const char *why)
{
    v->stats.http_refused++;
    char body[160];
    snprintf(body, sizeof body, "tessera remote view: %s", why);
    if (lws_return_http_status(wsi, status, body))
        return -1;
    return lws_http_transaction_completed(wsi) ? -1 : 0;
}

static int http_request(remote_view *v, struct lws *wsi, session *ss, const char *path)
{
    if (strcmp(path, "/") != 0)
        return http_refuse(v, wsi, HTTP_STATUS_NOT_FOUND, "no such page");
    if (!request_token_ok(v, wsi))
        return http_refuse(v, wsi, HTTP_STATUS_FORBIDDEN, "a wrong or missing token (use the URL tessera printed)");
    uint8_t headers[LWS_PRE + 1024];
    uint8_t *start = headers + LWS_PRE, *p = start, *end = headers + sizeof headers - 1;
    if (lws_add_http_common_headers(wsi, HTTP_STATUS_OK, "text/html; charset=utf-8", remote_page_html_bytes, &p, end) ||
        lws_add_http_header_by_name(wsi, (const unsigned char *)"cache-control:", (const unsigned char *)"no-store", 8,
                                    &p, end) ||
        lws_finalize_write_http_header(wsi, start, &p, end))
        return 1;
    ss->page_written = 0;
    v->stats.pages_served++;
    lws_callback_on_writable(wsi);
    return 0;
}

#define PAGE_CHUNK 4096

static int http_writeable(remote_view *v, struct lws *wsi, session *ss)
{
    size_t left = remote_page_html_bytes - ss->page_written;
    size_t n = left < PAGE_CHUNK ? left : PAGE_CHUNK;
    if (LWS_PRE + PAGE_CHUNK > v->send_capacity) {
        uint8_t *grown = realloc(v->send_buf, LWS_PRE + PAGE_CHUNK);
        if (!grown)
            return -1;
        v->send_buf = grown;
        v->send_capacity = LWS_PRE + PAGE_CHUNK;
    }
    memcpy(v->send_buf + LWS_PRE, remote_page_html + ss->page_written, n);
    bool last = n == left;
    if (lws_write(wsi, v->send_buf + LWS_PRE, n, last ? LWS_WRITE_HTTP_FINAL : LWS_WRITE_HTTP) != (int)n)
        return -1;
    ss->page_written += n;
    if (last)
        return lws_http_transaction_completed(wsi) ? -1 : 0;
    lws_callback_on_writable(wsi);
    return 0;
}

/* A WebSocket upgrade: the right path (else refused in the handshake), the
 * token and a free place (else let through, to be closed at once with a
 * code and a reason the page can show: refused_close). */
static int filter_viewer(remote_view *v, struct lws *wsi, session *ss)
{
    char uri[256];
    ss->refuse = 0;
    if (lws_hdr_copy(wsi, uri, (int)sizeof uri, WSI_TOKEN_GET_URI) <= 0 || strcmp(uri, "/ws") != 0) {
        v->stats.refused_other++;
        return 1;
    }
    if (!request_token_ok(v, wsi)) {
        v->stats.refused_token++;
        log_warn("remote view: a viewer with a wrong or missing token was refused");
        ss->refuse = REMOTE_CLOSE_TOKEN;
    } else if (v->viewer_count >= v->cfg.max_viewers) {
        v->stats.refused_full++;
        log_warn("remote view: a viewer was refused: %d viewers already (remote.max_viewers)", v->viewer_count);
        ss->refuse = REMOTE_CLOSE_FULL;
    }
    return 0;
}

/* A refused WebSocket's one write: the close frame with its code and reason
 * (docs/remote-protocol.md, "Refusals"); nothing else is ever sent to it. */
static int refused_close(remote_view *v, struct lws *wsi, int code)
{
    char reason[120];
    if (code == REMOTE_CLOSE_FULL)
        snprintf(reason, sizeof reason, "too many viewers (%d max)", v->cfg.max_viewers);
    else
        snprintf(reason, sizeof reason, "a wrong or missing token");
    lws_close_reason(wsi, (enum lws_close_status)code, (unsigned char *)reason, strlen(reason));
    return -1;
}

static int callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in, size_t len)
{
    struct lws_context *ctx = lws_get_context(wsi);
    remote_view *v = ctx ? lws_context_user(ctx) : NULL;
    session *ss = user;
    if (!v)
        return lws_callback_http_dummy(wsi, reason, user, in, len);
    switch (reason) {
    case LWS_CALLBACK_HTTP:
        return http_request(v, wsi, ss, in ? (const char *)in : "");
    case LWS_CALLBACK_HTTP_WRITEABLE:
        return http_writeable(v, wsi, ss);
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
        return filter_viewer(v, wsi, ss);
    case LWS_CALLBACK_ESTABLISHED:
        ss->slot_plus_1 = 0;
        if (ss->refuse) { /* closed in its first writeable callback, with the reason */
            lws_callback_on_writable(wsi);
            return 0;
        }
        return viewer_attach(v, wsi, ss);
    case LWS_CALLBACK_CLOSED:
        viewer_detach(v, ss);
        return 0;
    case LWS_CALLBACK_RECEIVE:
        if (ss->slot_plus_1 > 0)
            viewer_receive(v, wsi, &v->viewers[ss->slot_plus_1 - 1], in, len);
        return 0;
    case LWS_CALLBACK_SERVER_WRITEABLE:
        if (ss->refuse)
            return refused_close(v, wsi, ss->refuse);
        if (v->stopping) { /* say_goodbye */
            static const char bye[] = "the kiosk stopped";
            lws_close_reason(wsi, LWS_CLOSE_STATUS_GOINGAWAY, (unsigned char *)bye, sizeof bye - 1);
            return -1;
        }
        return ss->slot_plus_1 > 0 ? viewer_writeable(v, &v->viewers[ss->slot_plus_1 - 1]) : 0;
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED: /* a new frame was encoded (or stop) */
        if (v->viewer_count > 0)
            lws_callback_on_writable_all_protocol(ctx, &protocols[1]);
        return 0;
    default:
        break;
    }
    return lws_callback_http_dummy(wsi, reason, user, in, len);
}

static const struct lws_protocols protocols[] = {
    {"http", callback, sizeof(session), 0, 0, NULL, 0},
    {PROTOCOL_NAME, callback, sizeof(session), REMOTE_MESSAGE_MAX_BYTES, 0, NULL, 0},
    {NULL, NULL, 0, 0, 0, NULL, 0},
};

/* ---- the thread ---------------------------------------------------------------- */

static void encoded(void *ctx)
{
    remote_view *v = ctx;
    pthread_mutex_lock(&v->context_lock);
    if (v->context && !atomic_load(&v->stop))
        lws_cancel_service(v->context);
    pthread_mutex_unlock(&v->context_lock);
}

#define GOODBYE_US 2000000 /* how long the viewers have to take the close and answer it */

/* The run is over: every viewer is sent a close, 1001 "the kiosk stopped"
 * (docs/remote-protocol.md), so its page says the wall stopped rather than
 * that the connection was lost, and their answers are awaited for at most
 * GOODBYE_US (remote_view_stop wakes this loop meanwhile: lws_service would
 * otherwise sleep until a close's own 5 s time-out). One that cannot take the
 * close (it stopped reading) is cut after a second. */
static void say_goodbye(remote_view *v)
{
    v->stopping = true;
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++)
        if (v->viewers[i].used) {
            lws_set_timeout(v->viewers[i].wsi, PENDING_TIMEOUT_USER_OK, 1);
            lws_callback_on_writable(v->viewers[i].wsi);
        }
    uint64_t end = clock_monotonic_us() + GOODBYE_US;
    while (v->viewer_count > 0 && clock_monotonic_us() < end)
        if (lws_service(v->context, 0) < 0)
            break;
}

static void *server_main(void *arg)
{
    remote_view *v = arg;
    thread_name_set("tess-remote");
    bool ok = true;
    while (ok && !atomic_load(&v->stop))
        ok = lws_service(v->context, 0) >= 0;
    if (ok)
        say_goodbye(v);
    atomic_store(&v->server_done, true);
    return NULL;
}

static void lws_log(int level, const char *line)
{
    size_t n = strlen(line);
    while (n && (line[n - 1] == '\n' || line[n - 1] == '\r'))
        n--;
    if (level & LLL_ERR)
        log_error("remote view (libwebsockets): %.*s", (int)n, line);
    else
        log_warn("remote view (libwebsockets): %.*s", (int)n, line);
}

remote_view *remote_view_create(const remote_config *c, tess_error *err)
{
    if (!remote_config_validate(c, err))
        return NULL;
    remote_view *v = calloc(1, sizeof *v);
    if (!v) {
        tess_error_set(err, "remote view: out of memory");
        return NULL;
    }
    v->cfg = *c;
    atomic_init(&v->stop, false);
    atomic_init(&v->server_done, false);
    pthread_mutex_init(&v->context_lock, NULL);
    if (c->token[0]) {
        snprintf(v->token, sizeof v->token, "%s", c->token);
    } else {
        uint8_t random[16];
        if (getrandom(random, sizeof random, 0) != (ssize_t)sizeof random) {
            tess_error_set(err, "remote view: getrandom failed: no token could be made");
            free(v);
            return NULL;
        }
        for (int i = 0; i < 16; i++)
            snprintf(v->token + 2 * i, 3, "%02x", random[i]);
    }
    v->private_count = c->private_views < 0 ? c->max_viewers : c->private_views;
    bool ok = (v->encoder = remote_encoder_create(1 + v->private_count, c->quality, c->subsampling, encoded, v,
                                                  err)) &&
              (v->source = remote_source_create(err)) && (v->display = remote_encoder_display(v->encoder, 0));
    for (int k = 0; k < v->private_count && ok; k++)
        ok = (v->private_displays[k] = remote_encoder_display(v->encoder, 1 + k)) != NULL;
    if (!ok) {
        if (!err->msg[0])
            tess_error_set(err, "remote view: out of memory");
        remote_view_destroy(v);
        return NULL;
    }
    return v;
}

image_display *remote_view_display(remote_view *v)
{
    image_display *d = v->display_taken ? NULL : v->display;
    v->display_taken = true;
    return d;
}

int remote_view_private_count(const remote_view *v) { return v->private_count; }

image_display *remote_view_private_display(remote_view *v, int k)
{
    if (k < 0 || k >= v->private_count)
        return NULL;
    image_display *d = v->private_displays[k];
    v->private_displays[k] = NULL;
    return d;
}

input_source *remote_view_take_source(remote_view *v)
{
    input_source *s = v->source_taken ? NULL : remote_source_input(v->source);
    v->source_taken = true;
    return s;
}

/* The address a person on the network opens: the bind address, or for
 * 0.0.0.0 the first IPv4 address that is not loopback. */
static void url_host(const char *bind, char *out, size_t out_bytes)
{
    snprintf(out, out_bytes, "%s", bind);
    if (strcmp(bind, "0.0.0.0") != 0)
        return;
    struct ifaddrs *list;
    if (getifaddrs(&list) != 0)
        return;
    for (struct ifaddrs *i = list; i; i = i->ifa_next)
        if (i->ifa_addr && i->ifa_addr->sa_family == AF_INET && !(i->ifa_flags & IFF_LOOPBACK) &&
            (i->ifa_flags & IFF_UP)) {
            inet_ntop(AF_INET, &((struct sockaddr_in *)(void *)i->ifa_addr)->sin_addr, out, (socklen_t)out_bytes);
            break;
        }
    freeifaddrs(list);
}

bool remote_view_start(remote_view *v, struct pipeline *p, const remote_channels *ch, int width_px, int height_px,
                       camera_window area, tess_error *err)
{
    v->p = p;
    v->channels = *ch;
    if (v->channels.private_count > v->private_count)
        v->channels.private_count = v->private_count;
    v->width_px = width_px;
    v->height_px = height_px;
    v->area = area;
    for (int i = -1; i < v->channels.private_count; i++) {
        int channel = i < 0 ? ch->follow : ch->private_first + i;
        if (!pipeline_set_channel_active(p, channel, false))
            return tess_error_set(err, "remote view: its channel %d could not be switched off before the run",
                                  channel);
    }
    lws_set_log_level(LLL_ERR | LLL_WARN, lws_log);
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.options = LWS_SERVER_OPTION_EXPLICIT_VHOSTS | LWS_SERVER_OPTION_DISABLE_IPV6;
    info.user = v;
    info.gid = -1;
    info.uid = -1;
    info.port = CONTEXT_PORT_NO_LISTEN;
    if (!(v->context = lws_create_context(&info)))
        return tess_error_set(err, "remote view: libwebsockets could not start");
    info.port = v->cfg.port;
    info.iface = v->cfg.bind;
    info.protocols = protocols;
    info.vhost_name = "tessera";
    if (!(v->vhost = lws_create_vhost(v->context, &info))) {
        lws_context_destroy(v->context);
        v->context = NULL;
        return tess_error_set(err, "remote view: cannot listen on %s port %d (in use, or not ours to bind)",
                              v->cfg.bind, v->cfg.port);
    }
    int port = lws_get_vhost_listen_port(v->vhost);
    if (pthread_create(&v->thread, NULL, server_main, v) != 0) {
        lws_context_destroy(v->context);
        v->context = NULL;
        return tess_error_set(err, "remote view: cannot start the server thread");
    }
    v->started = true;
    char host[64];
    url_host(v->cfg.bind, host, sizeof host);
    fprintf(stderr, "tessera: remote view: http://%s:%d/?token=%s\n", host, port, v->token);
    fflush(stderr);
    return true;
}

void remote_view_stop(remote_view *v)
{
    if (!v || !v->started)
        return;
    pthread_mutex_lock(&v->context_lock);
    atomic_store(&v->stop, true); /* no wake-up from the encoder after this */
    pthread_mutex_unlock(&v->context_lock);
    /* wake the server thread until it is done: it says goodbye to the viewers, for a bounded time */
    while (!atomic_load(&v->server_done)) {
        lws_cancel_service(v->context);
        struct timespec tick = {0, 50 * 1000000L};
        nanosleep(&tick, NULL);
    }
    pthread_join(v->thread, NULL);
    v->started = false;
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++) /* still connected: what they missed */
        if (v->viewers[i].used)
            count_skipped(v, &v->viewers[i]);
    /* the context goes with its connections: CLOSED callbacks run here, on this thread (the
     * server thread is gone); the run is over, so they give input nothing more */
    v->stopping = true;
    pthread_mutex_lock(&v->context_lock);
    struct lws_context *ctx = v->context;
    v->context = NULL;
    pthread_mutex_unlock(&v->context_lock);
    lws_context_destroy(ctx);
}

void remote_view_destroy(remote_view *v)
{
    if (!v)
        return;
    remote_view_stop(v);
    if (!v->display_taken)
        image_display_destroy(v->display);
    for (int k = 0; k < v->private_count; k++)
        image_display_destroy(v->private_displays[k]);
    remote_encoder_destroy(v->encoder);
    if (!v->source_taken && v->source)
        input_source_destroy(remote_source_input(v->source));
    free(v->send_buf);
    pthread_mutex_destroy(&v->context_lock);
    free(v);
}

remote_stats remote_view_stats(remote_view *v) { return v->stats; }

void remote_view_print_stats(remote_view *v, FILE *out)
{
    remote_stats s = v->stats;
    remote_encoder_stats e = remote_encoder_get_stats(v->encoder);
    fprintf(out,
            "tessera: remote view: %llu viewers (refused: %llu token, %llu full, %llu other), %llu pages, "
            "%llu frames sent (%.1f KB/frame), %llu skipped for slow viewers; frames encoded %llu (%llu replaced "
            "before encoding), show %.2f ms, encode %.2f ms (medians)\n",
            (unsigned long long)s.viewers_accepted, (unsigned long long)s.refused_token,
            (unsigned long long)s.refused_full, (unsigned long long)s.refused_other,
            (unsigned long long)s.pages_served, (unsigned long long)s.frames_sent,
            s.frames_sent ? (double)s.bytes_sent / (double)s.frames_sent / 1024.0 : 0.0,
            (unsigned long long)s.frames_skipped, (unsigned long long)e.frames_encoded,
            (unsigned long long)e.frames_skipped, e.show_ms_median, e.encode_ms_median);
    uint64_t dropped = 0;
    for (int r = 0; r < REMOTE_DROP_REASONS; r++)
        dropped += s.dropped[r];
    fprintf(out, "tessera: remote view: %llu messages, %llu dropped", (unsigned long long)s.messages,
            (unsigned long long)dropped);
    for (int r = 0; r < REMOTE_DROP_REASONS; r++)
        if (s.dropped[r])
            fprintf(out, " (%s %llu)", remote_drop_reason_name((remote_drop_reason)r), (unsigned long long)s.dropped[r]);
    if (s.input_overflow)
        fprintf(out, ", %llu over the input queue", (unsigned long long)s.input_overflow);
    if (s.private_views || s.private_refused)
        fprintf(out, "; %llu private views (%llu refused: none free)", (unsigned long long)s.private_views,
                (unsigned long long)s.private_refused);
    fprintf(out, "\n");
}
