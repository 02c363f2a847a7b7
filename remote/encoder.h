/* encoder.h (remote) - the remote view's channels' displays and their JPEG
 * encoder thread. A channel's display (remote_encoder_display) converts each
 * frame it is shown to 8-bit sRGB on the pipeline's display thread, into a
 * per-channel mailbox of one frame (the newest wins: a frame the encoder has
 * not taken yet is replaced and counted as skipped); the encoder thread
 * compresses the newest frame of each channel (remote/jpeg.h) and publishes
 * it as that channel's newest encoded frame, then calls `ready` (the server
 * wakes its loop). Readers copy the newest encoded frame out
 * (remote_encoder_copy_newest). Nothing waits on a reader: a slow viewer
 * only ever misses frames, and the wall never waits for the encoder.
 *
 * Threading: show() on the display thread; the encoder on its own thread;
 * copy_newest and stats from any thread. One mutex guards the mailboxes and
 * the published frames; nobody holds it while converting or encoding. */
#ifndef TESSERA_REMOTE_ENCODER_H
#define TESSERA_REMOTE_ENCODER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/render/display.h"
#include "engine/base/err.h"
#include "input/event.h"
#include "jpeg.h"

#define REMOTE_CHANNELS_MAX (1 + INPUT_MAX_VIEWERS) /* channels one encoder serves: the follow channel and
                                                      one private channel a viewer at most */

typedef struct remote_encoder remote_encoder;

/* `channels` channels (1..REMOTE_CHANNELS_MAX) at `quality` and `sub`;
 * ready(ctx) is called on the encoder thread after each published frame.
 * The thread starts here. NULL with err. */
remote_encoder *remote_encoder_create(int channels, int quality, remote_subsampling sub, void (*ready)(void *ctx),
                                      void *ctx, tess_error *err);

/* Stop and join the thread, free everything. Every display made by
 * remote_encoder_display must have been destroyed before (they are the
 * pipeline's: destroy the pipeline first). NULL is fine. */
void remote_encoder_destroy(remote_encoder *e);

/* The display of channel `index` (0..channels-1), owned by the caller (the
 * pipeline, once added as a channel's display). NULL when out of memory. */
image_display *remote_encoder_display(remote_encoder *e, int index);

/* The newest encoded frame of channel `index` newer than `after_frame`
 * (UINT64_MAX: any) and shown to the display at or after `shown_after_us`
 * (clock_monotonic_us; 0: any): its frame number, camera serial, size and
 * JPEG copied to out + out_offset (grown with realloc as needed: *out,
 * *out_capacity). False when there is no such frame. */
typedef struct remote_encoded_info {
    uint64_t frame, camera_serial;
    int width_px, height_px;
    size_t jpeg_bytes;
    uint64_t shown_us;
} remote_encoded_info;
bool remote_encoder_copy_newest(remote_encoder *e, int index, uint64_t after_frame, uint64_t shown_after_us,
                                uint8_t **out, size_t *out_capacity, size_t out_offset, remote_encoded_info *info);

/* The frame number of channel `index`'s newest encoded frame, or UINT64_MAX
 * when it has none (no copy). */
uint64_t remote_encoder_newest_frame(remote_encoder *e, int index);

typedef struct remote_encoder_stats {
    uint64_t frames_shown;    /* frames the displays were shown */
    uint64_t frames_encoded;
    uint64_t frames_skipped;  /* replaced in the mailbox before the encoder took them */
    uint64_t encode_failures;
    double show_ms_median;    /* show(): the conversion on the display thread (last 1024 frames) */
    double encode_ms_median;  /* one JPEG encode (last 1024 frames) */
    uint64_t jpeg_bytes;      /* all encoded frames' bytes */
} remote_encoder_stats;
remote_encoder_stats remote_encoder_get_stats(remote_encoder *e);

#endif
