/* encoder.c (remote) - the remote channels' displays and the JPEG encoder
 * thread (encoder.h). */
#include "encoder.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/clock.h"
#include "engine/base/log.h"
#include "engine/base/sample_ring.h"
#include "engine/base/thread_name.h"
#include "engine/base/srgb8.h"


/* One 8-bit frame and what the page is told about it. */
typedef struct frame8 {
    uint32_t *xrgb; /* width_px * height_px words; grown as needed */
    size_t capacity_px;
    int width_px, height_px;
    uint64_t frame, camera_serial;
    uint64_t shown_us; /* when the display was shown it (clock_monotonic_us) */
} frame8;

/* A channel: the display thread fills `back`, swaps it with `mailbox` under
 * the lock; the encoder swaps `mailbox` with `work` under the lock and
 * encodes `work` without it, then copies the JPEG to `published` under it. */
typedef struct channel {
    frame8 back;           /* display thread only */
    frame8 mailbox;        /* lock */
    bool mailbox_full;     /* lock: mailbox holds a frame the encoder has not taken */
    frame8 work;           /* encoder thread only */
    uint8_t *published;    /* lock: the newest JPEG */
    size_t published_capacity;
    remote_encoded_info published_info; /* lock */
    bool have_published;   /* lock */
} channel;


struct remote_encoder {
    int channel_count;
    int quality;
    remote_subsampling sub;
    void (*ready)(void *ctx);
    void *ready_ctx;
    remote_jpeg *jpeg; /* encoder thread */
    pthread_mutex_t lock;
    pthread_cond_t wake; /* lock: a mailbox filled, or stop */
    bool stop;           /* lock */
    channel channels[REMOTE_CHANNELS_MAX];
    remote_encoder_stats stats; /* lock (medians computed when asked) */
    sample_ring show_times, encode_times; /* lock: ms */
    int next_channel; /* encoder thread: where its search for a full mailbox starts (round robin) */
    pthread_t thread;
    bool started;
};

typedef struct remote_display {
    image_display base;
    remote_encoder *e;
    int index;
} remote_display;

static bool frame8_fit(frame8 *f, int w, int h)
{
    size_t px = (size_t)w * (size_t)h;
    if (px > f->capacity_px) {
        uint32_t *grown = realloc(f->xrgb, px * sizeof *grown);
        if (!grown)
            return false;
        f->xrgb = grown;
        f->capacity_px = px;
    }
    f->width_px = w;
    f->height_px = h;
    return true;
}

static bool display_show(image_display *d, const frame_image *img, tess_error *err)
{
    remote_display *rd = (remote_display *)d;
    remote_encoder *e = rd->e;
    channel *c = &e->channels[rd->index];
    double t0 = clock_monotonic_s();
    c->back.shown_us = clock_monotonic_us();
    if (!frame8_fit(&c->back, img->width_px, img->height_px))
        return tess_error_set(err, "remote view: out of memory for a %dx%d frame", img->width_px, img->height_px);
    for (int y = 0; y < img->height_px; y++)
        srgb8_encode_xrgb(img->rgb + (size_t)y * (size_t)img->width_px * 3, 1, img->width_px,
                          c->back.xrgb + (size_t)y * (size_t)img->width_px);
    c->back.frame = img->frame;
    c->back.camera_serial = img->camera_serial;
    double ms = (clock_monotonic_s() - t0) * 1e3;
    pthread_mutex_lock(&e->lock);
    frame8 swap = c->mailbox;
    c->mailbox = c->back;
    c->back = swap;
    if (c->mailbox_full)
        e->stats.frames_skipped++;
    c->mailbox_full = true;
    e->stats.frames_shown++;
    sample_ring_add(&e->show_times, ms);
    pthread_cond_signal(&e->wake);
    pthread_mutex_unlock(&e->lock);
    return true;
}

static void display_destroy(image_display *d) { free(d); }

static const image_display_ops remote_display_ops = {
    .name = "remote",
    .show = display_show,
    .destroy = display_destroy,
};

image_display *remote_encoder_display(remote_encoder *e, int index)
{
    if (index < 0 || index >= e->channel_count)
        return NULL;
    remote_display *d = calloc(1, sizeof *d);
    if (!d)
        return NULL;
    d->base.ops = &remote_display_ops;
    d->e = e;
    d->index = index;
    return &d->base;
}

/* Encode channel i's work frame and publish it (encoder thread). */
static void encode_one(remote_encoder *e, int i)
{
    channel *c = &e->channels[i];
    const uint8_t *jpeg;
    size_t bytes;
    tess_error err = {{0}};
    double t0 = clock_monotonic_s();
    bool ok = remote_jpeg_encode(e->jpeg, c->work.xrgb, c->work.width_px, c->work.height_px, c->work.width_px,
                                 e->quality, e->sub, &jpeg, &bytes, &err);
    double ms = (clock_monotonic_s() - t0) * 1e3;
    pthread_mutex_lock(&e->lock);
    if (ok && bytes > c->published_capacity) {
        uint8_t *grown = realloc(c->published, bytes);
        if (grown) {
            c->published = grown;
            c->published_capacity = bytes;
        } else {
            ok = false;
            tess_error_set(&err, "out of memory for %zu bytes", bytes);
        }
    }
    if (ok) {
        memcpy(c->published, jpeg, bytes);
        c->published_info = (remote_encoded_info){.frame = c->work.frame,
                                                  .camera_serial = c->work.camera_serial,
                                                  .width_px = c->work.width_px,
                                                  .height_px = c->work.height_px,
                                                  .jpeg_bytes = bytes,
                                                  .shown_us = c->work.shown_us};
        c->have_published = true;
        e->stats.frames_encoded++;
        e->stats.jpeg_bytes += bytes;
        sample_ring_add(&e->encode_times, ms);
    } else {
        e->stats.encode_failures++;
    }
    pthread_mutex_unlock(&e->lock);
    if (!ok)
        log_error("remote view: frame %llu not sent: %s", (unsigned long long)c->work.frame, err.msg);
}

static void *encoder_main(void *arg)
{
    remote_encoder *e = arg;
    thread_name_set("tess-remote-enc");
    pthread_mutex_lock(&e->lock);
    for (;;) {
        int full = -1; /* the next full mailbox after the last one encoded: every channel gets its turn */
        for (int j = 0; j < e->channel_count && full < 0; j++) {
            int i = (e->next_channel + j) % e->channel_count;
            if (e->channels[i].mailbox_full)
                full = i;
        }
        if (e->stop)
            break;
        if (full < 0) {
            pthread_cond_wait(&e->wake, &e->lock);
            continue;
        }
        channel *c = &e->channels[full];
        frame8 swap = c->work;
        c->work = c->mailbox;
        c->mailbox = swap;
        c->mailbox_full = false;
        e->next_channel = (full + 1) % e->channel_count;
        pthread_mutex_unlock(&e->lock);
        encode_one(e, full);
        if (e->ready)
            e->ready(e->ready_ctx);
        pthread_mutex_lock(&e->lock);
    }
    pthread_mutex_unlock(&e->lock);
    return NULL;
}

remote_encoder *remote_encoder_create(int channels, int quality, remote_subsampling sub, void (*ready)(void *ctx),
                                      void *ctx, tess_error *err)
{
    if (channels < 1 || channels > REMOTE_CHANNELS_MAX) {
        tess_error_set(err, "remote view: %d channels (1..%d)", channels, REMOTE_CHANNELS_MAX);
        return NULL;
    }
    remote_encoder *e = calloc(1, sizeof *e);
    if (!e) {
        tess_error_set(err, "remote view: out of memory");
        return NULL;
    }
    e->channel_count = channels;
    e->quality = quality;
    e->sub = sub;
    e->ready = ready;
    e->ready_ctx = ctx;
    pthread_mutex_init(&e->lock, NULL);
    pthread_cond_init(&e->wake, NULL);
    if (!(e->jpeg = remote_jpeg_create(err))) {
        remote_encoder_destroy(e);
        return NULL;
    }
    if (pthread_create(&e->thread, NULL, encoder_main, e) != 0) {
        tess_error_set(err, "remote view: cannot start the encoder thread");
        remote_encoder_destroy(e);
        return NULL;
    }
    e->started = true;
    return e;
}

void remote_encoder_destroy(remote_encoder *e)
{
    if (!e)
        return;
    if (e->started) {
        pthread_mutex_lock(&e->lock);
        e->stop = true;
        pthread_cond_signal(&e->wake);
        pthread_mutex_unlock(&e->lock);
        pthread_join(e->thread, NULL);
    }
    for (int i = 0; i < REMOTE_CHANNELS_MAX; i++) {
        channel *c = &e->channels[i];
        free(c->back.xrgb);
        free(c->mailbox.xrgb);
        free(c->work.xrgb);
        free(c->published);
    }
    remote_jpeg_destroy(e->jpeg);
    pthread_cond_destroy(&e->wake);
    pthread_mutex_destroy(&e->lock);
    free(e);
}

bool remote_encoder_copy_newest(remote_encoder *e, int index, uint64_t after_frame, uint64_t shown_after_us,
                                uint8_t **out, size_t *out_capacity, size_t out_offset, remote_encoded_info *info)
{
    if (index < 0 || index >= e->channel_count)
        return false;
    channel *c = &e->channels[index];
    bool copied = false;
    pthread_mutex_lock(&e->lock);
    if (c->have_published && (after_frame == UINT64_MAX || c->published_info.frame > after_frame) &&
        c->published_info.shown_us >= shown_after_us) {
        size_t need = out_offset + c->published_info.jpeg_bytes;
        if (need > *out_capacity) {
            uint8_t *grown = realloc(*out, need);
            if (grown) {
                *out = grown;
                *out_capacity = need;
            }
        }
        if (need <= *out_capacity) {
            memcpy(*out + out_offset, c->published, c->published_info.jpeg_bytes);
            *info = c->published_info;
            copied = true;
        }
    }
    pthread_mutex_unlock(&e->lock);
    return copied;
}

uint64_t remote_encoder_newest_frame(remote_encoder *e, int index)
{
    if (index < 0 || index >= e->channel_count)
        return UINT64_MAX;
    pthread_mutex_lock(&e->lock);
    const channel *c = &e->channels[index];
    uint64_t frame = c->have_published ? c->published_info.frame : UINT64_MAX;
    pthread_mutex_unlock(&e->lock);
    return frame;
}

remote_encoder_stats remote_encoder_get_stats(remote_encoder *e)
{
    pthread_mutex_lock(&e->lock);
    remote_encoder_stats s = e->stats;
    s.show_ms_median = sample_ring_median(&e->show_times);
    s.encode_ms_median = sample_ring_median(&e->encode_times);
    pthread_mutex_unlock(&e->lock);
    return s;
}
