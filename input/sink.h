/* sink.h - input transactions (controller.h's input_txn: txn.h records)
 * into a running pipeline: each record is submitted to the pipeline as it is
 * (pipeline_submit), recorded to a file when asked (record.h); recorded ones
 * play back through the same path; the input-level kinds (tour, quit) are
 * carried out here: the attract tour runs as a serial animation, quit stops
 * the pipeline.
 *
 * COALESCING. Camera and cursor changes go through a one-slot mailbox: the
 * first change queues one transaction and later ones only overwrite the slot
 * until that transaction runs at the barrier and empties it. So however fast
 * input arrives, at most one camera transaction waits at a time, and the one
 * that runs applies the newest camera (a camera record for all channels:
 * one for a single channel, replayed, is submitted as it is). Everything else
 * (status, hide, show-all, ..., tour, quit) is queued in order as its own
 * transaction.
 *
 * THE TOUR. TOUR on: from the next frame the wall's camera follows the tour
 * path (looping, from its first key), eased in from the camera shown when it
 * starts over tour_ease_s of pipeline time; TOUR off: the camera stays where
 * the tour left it. input_sink_current_camera tells the input thread which
 * camera the wall shows, for the hand-over.
 *
 * RECORDING. Every record emitted goes to the record file but those that
 * name a private channel (engine/scene/frame_state.h: a remote viewer's own view's
 * camera and its switching on and off): a recording holds what the wall
 * showed, and plays back without a remote view.
 *
 * Threading: input_sink_emit from one thread at a time besides the pipeline
 * (the input thread, or the replay thread); `lock` guards the mailbox and
 * the shown camera and is never held across anything that blocks; the
 * record file has its own lock. Tour state is touched only in the serial
 * section. */
#ifndef TESSERA_INPUT_SINK_H
#define TESSERA_INPUT_SINK_H

#include <stdbool.h>

#include "engine/frame/camera_path.h"
#include "engine/base/err.h"
#include "engine/frame/pipeline.h"
#include "controller.h"
#include "record.h"

typedef struct input_sink_config {
    const camera_path *tour;  /* NULL: no tour; kept by the caller while the sink lives */
    double tour_ease_s;       /* easing into the tour; 0: 2 s */
    const char *record_file;  /* NULL or "": no recording */
    bool print_status;        /* status texts also to stdout */
} input_sink_config;

typedef struct input_sink input_sink;

/* Before pipeline_run (registers the tour animation). NULL with err. */
input_sink *input_sink_create(pipeline *p, const input_sink_config *cfg, tess_error *err);

/* After pipeline_run has returned (joins a replay thread). */
void input_sink_destroy(input_sink *s);

/* Queue (and record) one transaction. */
void input_sink_emit(input_sink *s, const input_txn *t);

/* The camera the wall shows (the last set by the sink or the tour; before
 * any, the pipeline's channel 0 camera at creation). */
camera_desc input_sink_current_camera(input_sink *s);

typedef enum input_replay_speed {
    INPUT_REPLAY_RECORDED, /* at the recorded times, from the call (a thread) */
    INPUT_REPLAY_FRAMES,   /* one transaction per frame, from the next frame */
    INPUT_REPLAY_ALL,      /* all queued now: they apply before the next frame */
} input_replay_speed;

#define INPUT_REPLAY_SPEED_NAMES "recorded, frames, all"
bool input_replay_speed_from_name(const char *name, input_replay_speed *out);

/* Play a record back through the sink (the record is copied). Before
 * pipeline_run, or while running for RECORDED. False with err. */
bool input_sink_replay(input_sink *s, const input_record *rec, input_replay_speed speed, tess_error *err);

/* Transactions emitted, those the pipeline refused (queue full, stopped);
 * camera changes put into the mailbox, and mailbox transactions that applied
 * one (the rest were overwritten by newer ones before a barrier: coalesced);
 * transactions played back from a record (counted apart from emitted); and
 * pipeline transactions queued (accepted): a camera or cursor change that
 * rides on a waiting mailbox transaction queues none, so emitted + replayed
 * = queued + refused + changes coalesced into a waiting mailbox. The tour's
 * starts and stops as they happened at a barrier (with a tour). */
typedef struct input_sink_stats {
    uint64_t emitted, refused;
    uint64_t camera_changes, camera_applied;
    uint64_t replayed, queued;
    uint64_t tour_starts, tour_stops;
} input_sink_stats;
input_sink_stats input_sink_get_stats(input_sink *s);

#endif
