/* drm.h - DRM/KMS scan-out for a display wall: one process drives every
 * output of a card straight through KMS, no compositor.
 *
 * Life of a card: drm_card_open (becomes DRM master, saves every CRTC's state)
 * -> drm_card_connectors -> wall_config_match_device -> drm_wall_start (a CRTC
 * and its primary plane per output, four XRGB8888 dumb buffers and a black one
 * each, the mode set with one atomic commit tested first with TEST_ONLY, or the
 * legacy API where atomic is missing or TESSERA_DRM_NO_ATOMIC=1: the two paths
 * are drm_atomic.c and drm_legacy.c behind drm_card.h's drm_kms_ops) ->
 * drm_wall_attach (the pipeline whose
 * channels the outputs are) -> frames through the displays it returns ->
 * drm_card_close (restores the saved CRTCs, frees the buffers). The commands
 * reach this life only through the display-backend table: drm_backend.c is
 * drm's display_lifecycle (display_backend.h) over these calls.
 *
 * Frames: each output is a pipeline channel. Its display's write_tile hook
 * (engine/render/display.h) has the render threads convert each finished tile into
 * the scan-out buffer of that frame (frame f -> buffer f % 4; 8-bit sRGB,
 * rotated to the panel's scan-out orientation), each pixel written once and
 * never read back (scan-out memory may be write-combined). At the end of each
 * display stage the card waits for the previous flip events (so the pipeline
 * runs at the display's pace) and flips every live output in one atomic commit
 * (non-blocking, with flip events).
 *
 * Hotplug: udev's HOTPLUG=1 events for the card (and any flip that never
 * completes) make it read the connectors again at the next display stage and
 * apply wall_hotplug_plan: an output whose monitor is gone is switched off
 * (its CRTC released) and its channel switched off in the pipeline (a
 * transaction); one whose monitor is back in a mode of the same size is
 * brought up again and its channel switched on. The other outputs go on. */
#ifndef TESSERA_DRM_H
#define TESSERA_DRM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "engine/render/display.h"
#include "engine/base/err.h"
#include "wall_config.h"

typedef struct drm_card drm_card;
typedef struct session session;

/* Open a card through the session (seat/session.h: libseat, or direct as
 * root): `path`, or NULL for the first /dev/dri/cardN that has a connected
 * connector. NULL with err (no card, not permitted, not master). The session
 * must outlive the card; VT switches it reports pause the wall (the display
 * stage waits, so the frame loop does) and restore it on return. */
drm_card *drm_card_open(const char *path, session *sn, tess_error *err);

/* Restore the CRTC configuration found at open (unless switched away to
 * another VT: then the console's owner has them), free everything. NULL is fine. */
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

/* The pipeline whose channels first_channel .. + w->count are this card's
 * outputs, so hotplug can switch them off and on. Before pipeline_run. */
struct pipeline;
void drm_wall_attach(drm_card *c, struct pipeline *p, int first_channel);

/* Told on the display thread while the wall is paused because the seat took
 * the card away (a VT switch): paused true when the pause starts and then at
 * least every 200 ms while it lasts, false when the wall goes on. The frame
 * loop waits meanwhile, healthy: a service watchdog is fed from here
 * (wall/service.h). NULL fn: nobody is told. Before pipeline_run. */
typedef void (*drm_pause_fn)(void *ctx, bool paused);
void drm_card_set_pause_hook(drm_card *c, drm_pause_fn fn, void *ctx);

/* Told on the display thread of each output's completed page flip: the
 * frame now on screen, the output's name, the CRTC's vblank counter and the
 * vblank's time (CLOCK_MONOTONIC us, as the kernel stamps it). The same is
 * logged at debug level: "CARD: OUTPUT: flipped to frame F at vblank S (T s)" (not "frame F on screen": that line,
 * once per commit, says every output shows F). */
typedef void (*drm_flip_fn)(void *ctx, uint64_t frame, const char *output, unsigned vblank_sequence,
                            int64_t vblank_monotonic_us);
void drm_card_set_flip_hook(drm_card *c, drm_flip_fn fn, void *ctx);

/* CRTCs for outputs: masks[o] has bit k set when output o's encoders can
 * drive CRTC k (of `crtcs`, at most 32). Fills crtc_of_output[o] with distinct
 * CRTC indices by a maximum bipartite matching (augmenting paths: an earlier
 * output moves to another CRTC of its own when a later one needs its first
 * choice). Returns -1 when every output got one, else the first output that
 * cannot. Pure; drm_wall_start uses it with the card's masks. */
int drm_match_crtcs(const uint32_t *masks, int outputs, int crtcs, int *crtc_of_output);

/* ---- page flips that fail (pure: drm_end_stage applies it; tested without a card) ----
 *
 * What became of one output's page flip in a display stage: its event came
 * (DONE), the commit or its legacy page flip was refused (REFUSED: an atomic
 * commit is refused for every output in it), or no event came within the
 * flip time-out (TIMED_OUT: the monitor may have gone mid-frame); NONE when it
 * was not flipped (no new frame, dark). */
typedef enum drm_flip_outcome {
    DRM_FLIP_NONE,
    DRM_FLIP_DONE,
    DRM_FLIP_REFUSED,
    DRM_FLIP_TIMED_OUT,
} drm_flip_outcome;

#define DRM_FLIP_FAILS_LIMIT 5 /* stages in a row an output's flips may fail before it is given up */

/* Per output: display stages in a row whose flip of it failed. Zeroed at
 * start and after a hotplug change (the failures had a cause). */
typedef struct drm_flip_health {
    int failed[WALL_MAX_OUTPUTS];
    unsigned kinds[WALL_MAX_OUTPUTS]; /* bit 1 << outcome of each failure counted in failed[] */
} drm_flip_health;

typedef struct drm_flip_verdict {
    bool probe;                        /* a flip failed: read the connectors (an output may be gone) */
    bool give_up[WALL_MAX_OUTPUTS];    /* failed DRM_FLIP_FAILS_LIMIT stages in a row while another
                                          output's flips completed: switch it off, the rest goes on */
    bool fatal;                        /* the limit reached and no output's flip completed: the card
                                          shows nothing (unless the probe finds an output gone) */
    tess_error why;                    /* with give_up or fatal: one line naming the outputs given up
                                          and what failed, or why the card is given up */
} drm_flip_verdict;

/* Note one stage's outcomes (outcome[o] for outputs 0 .. count-1; names[o]
 * their connectors for messages, or NULL) in *h and say what to do. An
 * output given up has its count cleared (if it is lit again, it starts
 * afresh). */
drm_flip_verdict drm_flip_judge(drm_flip_health *h, const drm_flip_outcome *outcome, const char *const *names,
                                int count);

/* Whether the card took the atomic path (else legacy). */
bool drm_card_atomic(const drm_card *c);

/* `tessera outputs`: every card, its connectors, EDID identities and modes. */
int drm_print_outputs(FILE *f);

#endif
