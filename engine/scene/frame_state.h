/* frame_state.h - what transactions may change between frames, in one
 * versioned object owned by the pipeline (pipeline.h, TRANSACTIONS).
 *
 * CONTENTS. Per channel its camera (with a change serial) and whether it is
 * active; the render thread count; the overlay's inputs (status text, cursor,
 * whether the governor's line is shown); render options (renderer,
 * shadows); per geometry (ids 0..geometry_count-1, what hits report as
 * geom_id) visibility, a highlight flag, a colour override (linear RGB) and
 * an opacity and a crop (particles seen by an attribute's range, given by
 * crop records; the scene's own until then); a global opacity; the cutting
 * planes (clip.h, CLIP_MAX_PLANES, all off initially).
 * Room for more: what the next issues add (accumulation) goes here, with a
 * record kind in txn.h that edits it.
 *
 * OPACITY. What a surface of geometry id lets through is 1 - opacity, with
 * opacity = global opacity x its part opacity (frame_state_opacity), both in
 * [0, 1]: 1 opaque (the default for both), 0 see-through (the surface is
 * still hit, its contribution weighted 0: a renderer may skip it). The
 * global opacity scales every part, so "opacity all 0.5" then a part at 0.5
 * shows that part at 0.25. frame_state_transparent says in O(1) whether any
 * surface may be less than opaque (global < 1, or translucent_count > 0):
 * renderers take their opaque fast path when it is false.
 *
 * WHO CHANGES IT. Only txn_apply (txn.h) and the setters below, and in a
 * pipeline only in the serial section of the frame barrier (transactions,
 * serial callbacks) or while no loop runs: pipeline_state.c enforces it. So
 * while a frame renders the state does not change: the state at the barrier
 * IS the frame's snapshot, and render threads read it through a const pointer
 * (render_view.state) without locks; the barrier orders their reads after
 * the serial section's writes.
 *
 * VERSION AND SERIALS. `version` is bumped by every applied change (a
 * setter or record that succeeds, even one that sets what is already
 * there). The governor needs to know what kind of change it was:
 *   picture_serial  bumped when what the picture shows changes: a camera
 *                   different from the one it replaces, a channel switched,
 *                   a geometry's visibility changed, show-all (always),
 *                   highlight or colour changed, shadows or renderer changed,
 *                   the global or a part's opacity changed, a cutting plane
 *                   switched on or off, or one that is on moved or turned
 *                   (a plane that stays off may change unseen: no bump),
 *                   a crop, value or colour map given or changed, a
 *                   different time step;
 *   overlay_serial  bumped when the overlay changes: the cursor or a remote
 *                   viewer's pointer moved, shown or hidden (their setters),
 *                   and by the pipeline when
 *                   the status line as drawn changes (frame_state_bump_overlay);
 *   camera_serial[c] bumped by every camera set on channel c, the same or not.
 *
 * PRIVATE CHANNELS. A channel made private before the run (a remote viewer's
 * own camera: remote/) is not the wall's: a camera record for all channels
 * leaves it, and it draws neither the cursor nor viewers' pointers (plane
 * points of the wall's view). Everything else (visibility, planes, ...) it
 * shares.
 *
 * MEMORY. Nothing per geometry is allocated until a scene uses the feature:
 * the hidden, highlight and colour arrays are each NULL until the first
 * record that needs one (a hide, a highlight on, a colour override, a part
 * opacity below 1: part_opacity stays NULL while every part is opaque, and
 * setting parts to 1 before that allocates nothing). The global opacity and
 * the planes are fixed-size members.
 *
 * VISIBILITY AND THE ACCEL. The accel keeps its own hidden flags (accel.h;
 * traversal reads them). The state says what should be hidden and marks
 * which ids may differ from the accel; frame_state_sync_accel (serial
 * section) brings the accel in line calling accel_set_hidden only for ids
 * whose flag differs, and accel_unhide_all after a show-all. */
#ifndef TESSERA_FRAME_STATE_H
#define TESSERA_FRAME_STATE_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/accel/clip.h"
#include "engine/accel/geometry.h"
#include "engine/base/err.h"
#include "engine/base/vec3.h"

struct accel;
struct renderer;

/* The state's sizes; the records that edit it (txn.h) have the same ones
 * (checked at compile time in txn.c). */
#define FRAME_STATE_MAX_CHANNELS 16 /* = TXN_MAX_CHANNELS */
#define FRAME_STATE_MAX_THREADS 256 /* = TXN_MAX_THREADS */
#define FRAME_STATE_TEXT_BYTES 128  /* = TXN_TEXT_BYTES: status text with its NUL */
#define FRAME_STATE_NAME_BYTES 32   /* = TXN_NAME_BYTES: a colour map's or transfer function's name */
#define FRAME_STATE_POINTERS 8      /* = TXN_POINTERS: remote viewers' pointers */

typedef struct frame_state {
    uint64_t version;        /* every applied change */
    uint64_t picture_serial; /* changes of what the picture shows (above) */
    uint64_t overlay_serial; /* changes of the overlay (above) */

    /* channels */
    int channel_count;
    camera_desc cameras[FRAME_STATE_MAX_CHANNELS];
    uint64_t camera_serials[FRAME_STATE_MAX_CHANNELS]; /* cameras set so far */
    bool active[FRAME_STATE_MAX_CHANNELS];             /* rendered and displayed */
    bool private_view[FRAME_STATE_MAX_CHANNELS];       /* fixed before the run: a camera "all" record
                                                          (the wall's camera) passes it by; only
                                                          records naming it set its camera */

    int threads;             /* render threads wanted, 1..FRAME_STATE_MAX_THREADS */

    /* the overlay's inputs (the pipeline composes the drawn line) */
    char status[FRAME_STATE_TEXT_BYTES]; /* the status text asked for */
    bool cursor_visible;
    float cursor_sx, cursor_sy;
    bool pointer_visible[FRAME_STATE_POINTERS]; /* remote viewers' pointers, by viewer slot */
    float pointer_sx[FRAME_STATE_POINTERS], pointer_sy[FRAME_STATE_POINTERS];
    bool governor_status_shown;

    /* render options */
    const struct renderer *renderer; /* never NULL once initialised */
    bool shadows;
    float opacity;           /* global, [0, 1] (OPACITY above); 1 after init */
    clip_plane clip[CLIP_MAX_PLANES]; /* cutting planes (normals unit); all off after init */

    /* per geometry: bitsets of (geometry_count + 63) / 64 words, NULL until used */
    uint32_t geometry_count;
    uint64_t *hidden;        /* bit set: hidden */
    uint32_t hidden_count;   /* bits set in `hidden` */
    uint64_t *highlight;     /* bit set: highlighted */
    uint64_t *coloured;      /* bit set: colour[id] overrides the material */
    vec3 *colour;            /* geometry_count entries, with `coloured` */
    affine3 *moved;          /* geometry_count placements applied after the scene's (identity:
                                not moved), NULL until the first move */
    float *part_opacity;     /* geometry_count opacities in [0, 1] (1: opaque), NULL until the first
                                part set below 1 */
    uint32_t translucent_count; /* entries of part_opacity below 1 (0 while it is NULL) */
    geometry_crop *crop;     /* geometry_count crops given by records (particles: geometry.h), with
                                `cropped`; NULL until the first crop record */
    uint64_t *cropped;       /* bit set: crop[id] was given (the scene's own crop holds until then) */

    /* what frame_state_sync_accel still has to do */
    bool accel_unhide_all;   /* a show-all since the last sync */
    uint32_t dirty_first, dirty_end; /* ids [first, end) may differ from the accel's flags */
    uint32_t moved_first, moved_end; /* ids [first, end) moved since the last sync */
    uint32_t crop_first, crop_end;   /* ids [first, end) whose crop may differ from their kind's */
    float *value;            /* geometry_count scalar parameters (iso-values) given by records, with
                                `valued`; NULL until the first value record */
    uint64_t *valued;        /* bit set: value[id] was given */
    uint32_t value_first, value_end; /* ids [first, end) whose value may differ from their kind's */
    char (*colormap)[FRAME_STATE_NAME_BYTES]; /* geometry_count map names given by records, with `mapped`;
                                NULL until the first colormap record */
    uint64_t *mapped;        /* bit set: colormap[id] was given */
    uint32_t map_first, map_end; /* ids [first, end) whose map may differ from their kind's */
    char transfer[FRAME_STATE_NAME_BYTES]; /* the transfer function every medium should use; "" until a record */
    bool transfer_dirty;     /* `transfer` may differ from what the media use */
    uint32_t time_step;      /* the step every time series shows (0 at start) */
    bool time_step_dirty;    /* time_step may differ from what the geometries show */
} frame_state;

/* A state for geometry_count geometries with no channels, nothing hidden,
 * no overlay, the given render options, opaque (opacity 1), no cutting
 * plane on. Allocates nothing. */
void frame_state_init(frame_state *st, const struct renderer *r, bool shadows, int threads, uint32_t geometry_count);
/* Free the per-geometry arrays. */
void frame_state_finish(frame_state *st);

/* Add a channel with its camera (active, serial 0); its index, or -1 when
 * FRAME_STATE_MAX_CHANNELS exist. Before the pipeline runs. */
int frame_state_add_channel(frame_state *st, const camera_desc *c);
/* Make channel `channel` private (private_view). Before the pipeline runs. */
void frame_state_set_private(frame_state *st, int channel);

/* Take over the accel's hidden flags (a pipeline made over an accel whose
 * geometries an earlier user hid): allocates `hidden` only if some are. */
bool frame_state_adopt_hidden(frame_state *st, const struct accel *a);

/* ---- setters (txn_apply calls these after validating; the same rules) ---- */
void frame_state_set_camera(frame_state *st, int channel, const camera_desc *c);
void frame_state_set_active(frame_state *st, int channel, bool on);
void frame_state_set_threads(frame_state *st, int threads);
void frame_state_set_status(frame_state *st, const char *text);
void frame_state_set_cursor(frame_state *st, bool on, float sx, float sy);
void frame_state_set_pointer(frame_state *st, int slot, bool on, float sx, float sy); /* slot 0..FRAME_STATE_POINTERS-1 */
void frame_state_set_governor_status(frame_state *st, bool shown);
void frame_state_set_shadows(frame_state *st, bool on);
void frame_state_set_renderer(frame_state *st, const struct renderer *r);
/* Visibility of [first, first + count) (in range); isolate hides the rest. False, st unchanged, out of memory. */
bool frame_state_set_hidden(frame_state *st, uint32_t first, uint32_t count, bool hidden);
bool frame_state_isolate(frame_state *st, uint32_t first, uint32_t count);
void frame_state_show_all(frame_state *st);
bool frame_state_set_highlight(frame_state *st, uint32_t first, uint32_t count, bool on);
/* rgb NULL: remove the override */
bool frame_state_set_colour(frame_state *st, uint32_t first, uint32_t count, const float *rgb);
/* Place [first, first + count) by m after the scene's placement (the identity: back where the
 * scene put them). m must be invertible (txn_validate checks). False, st unchanged, out of memory. */
bool frame_state_set_move(frame_state *st, uint32_t first, uint32_t count, const affine3 *m);
/* Global opacity, in [0, 1] (txn_validate checks). */
void frame_state_set_global_opacity(frame_state *st, float opacity);
/* Opacity of parts [first, first + count) (in range), in [0, 1]. False, st unchanged, out of memory. */
bool frame_state_set_opacity(frame_state *st, uint32_t first, uint32_t count, float opacity);
/* Cutting plane `index` (0..CLIP_MAX_PLANES-1) becomes *p, whose normal must
 * be unit: txn_apply normalises a record's normal before calling this. */
/* The crop of geometries [first, first + count) (their particle kinds'
 * range, frame_state_sync_accel passes it on); false on no memory. */
bool frame_state_set_crop(frame_state *st, uint32_t first, uint32_t count, geometry_crop crop);
/* The scalar parameter (iso-value) / colour map of geometries
 * [first, first + count) (frame_state_sync_accel passes them on); false on
 * no memory. */
bool frame_state_set_value(frame_state *st, uint32_t first, uint32_t count, float v);
bool frame_state_set_colormap(frame_state *st, uint32_t first, uint32_t count, const char *name);
/* What a record gave geometry id; false when none did. */
bool frame_state_value(const frame_state *st, uint32_t id, float *v);
bool frame_state_colormap(const frame_state *st, uint32_t id, const char **name);
/* Every medium's transfer function (frame_state_sync_accel passes it on). */
void frame_state_set_transfer(frame_state *st, const char *name);
/* Every time series to step `step` (frame_state_sync_accel passes it on). */
void frame_state_set_time_step(frame_state *st, uint32_t step);
/* The crop a record gave geometry id; false when none did. */
bool frame_state_crop(const frame_state *st, uint32_t id, geometry_crop *out);
void frame_state_set_clip_plane(frame_state *st, int index, const clip_plane *p);
/* The pipeline: the drawn status line changed. */
void frame_state_bump_overlay(frame_state *st);

/* ---- readers (any thread that may read the state: see WHO CHANGES IT) ---- */
bool frame_state_hidden(const frame_state *st, uint32_t id);      /* false out of range */
bool frame_state_highlighted(const frame_state *st, uint32_t id); /* false out of range */
/* Whether id has a colour override; then *rgb is it (rgb may be NULL). */
bool frame_state_colour(const frame_state *st, uint32_t id, vec3 *rgb);
/* The opacity of id's surfaces: global x part (the part's is 1 when never set or id is out of range). */
float frame_state_opacity(const frame_state *st, uint32_t id);
/* Whether any surface may be less than opaque: global < 1 or a part below 1. O(1). */
bool frame_state_transparent(const frame_state *st);
/* The CLIP_MAX_PLANES cutting planes (those with on == false clip nothing). */
const clip_plane *frame_state_clip_planes(const frame_state *st);

/* Bring the accel's hidden flags in line (serial section; see above).
 * Changes go as runs of consecutive ids (accel_set_hidden_range: a subtree
 * shown is one refit of the instance level), then accel_commit shrinks the
 * instance level around what was hidden. Moved instances get their new
 * placement (accel_set_placement: one refit for the range). Returns the
 * accel calls made (one per run + unhide-all + one per moved range). */
uint32_t frame_state_sync_accel(frame_state *st, const struct accel *a);

#endif
