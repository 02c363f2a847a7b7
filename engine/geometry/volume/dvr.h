/* dvr.h - direct volume rendering: the emission-absorption integral of a
 * structured volume (volume.h) through a transfer function (colormap.h)
 * along one ray, front to back, with empty-space skipping over the
 * macrocell grid (macrocell.h), early ray termination and optional
 * pre-integration. A pure module: it renders no image and knows no camera.
 *
 * OPACITY. A transfer function's opacity a(v) is the opacity accumulated
 * over ONE VOXEL of path: a length of the volume's smallest spacing, in
 * world units (docs/scene-format.md says the same). A path of length L
 * through a constant value v has transmittance (1 - a(v))^(L / voxel), so
 * the extinction is sigma(v) = -ln(1 - a(v)) per voxel; a(v) = 1 is opaque
 * at any length. The result does not depend on the step size for a constant
 * field, and is the same in world space for any ray direction, also in a
 * volume with unequal spacing.
 *
 * MODEL. Colours are emitted in proportion to the absorption (associated
 * colours): a slab of opacity alpha and colour c in front of transmittance T
 * adds T alpha c, then T becomes T (1 - alpha). Over a path the colour is
 * then sum_i T_i alpha_i c_i and for constant c and alpha it is c (1 - T).
 *
 * SLABS. The clipped ray [ta, tb] (the caller's [t0, t1] inside the field's
 * box [origin, origin + (n - 1) spacing]) is cut at ta + (k + jitter) *
 * step, k = 0, 1, ... (step in the ray's t: the step in voxels times the
 * voxel length over |dir|): a first slab of jitter * step (none for jitter
 * 0), full slabs of one step, and a last slab cut at tb. Each slab counts
 * with its true length, so [ta, tb] is covered exactly, with no gap and no
 * overlap: a constant field's result is the closed form for any step and
 * jitter (with the opacity its value has in the tables).
 *   Classic (pre-integration off): one sample per slab, at its midpoint
 *   (trilinear), through the baked table (colormap_table, nearest of
 *   COLORMAP_TABLE_SIZE entries), with the opacity corrected to the slab's
 *   length: alpha = 1 - (1 - a)^(length / voxel) (precomputed per entry for
 *   a full step). The midpoint rule makes the optical depth second order in
 *   the step for a smooth field and transfer function.
 *   Pre-integrated (on): one sample per slab boundary; the slab's colour
 *   and opacity come from a DVR_PREINT_SIZE^2 table read bilinearly at its
 *   front and back values, assuming the value varies linearly between them
 *   (dvr.c, PRE-INTEGRATION, has the model and its error).
 *
 * EMPTY SPACE. Per macrocell, the largest transfer-function opacity over the
 * table entries its [min, max] can reach (in both the classic and the
 * pre-integration binning). Runs of macrocells whose largest opacity is 0
 * are skipped: the slabs inside them are never sampled. The slab grid is
 * global along the ray, so skipping changes which slabs are visited, never
 * where they are: the result equals the unskipped one (bitwise, unless a
 * sample rounds across a macrocell face into a neighbour's values).
 *
 * EARLY TERMINATION. Integration stops after the first slab that leaves
 * T < min_transmittance; *transmittance_out is then that small T, not 0 (a
 * caller compositing a background over it is off by at most that much).
 *
 * Ownership: a dvr_volume keeps pointers to the volume and to a grid it was
 * given (the caller keeps both alive and unchanged); a grid it built itself
 * it owns. Threading: dvr_integrate reads only, from any number of threads;
 * dvr_set_transfer and dvr_set_settings must not run during an integration. */
#ifndef TESSERA_DVR_H
#define TESSERA_DVR_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/colormap.h"
#include "engine/base/err.h"
#include "macrocell.h"
#include "volume.h"

/* entries per axis of the pre-integration table (4 floats each: 16 MiB,
 * allocated only while pre-integration is on), over the transfer function's
 * range: the classic table's resolution (a coarser table blurs the transfer
 * function and biases the picture); read bilinearly, built from running
 * integrals in O(SIZE^2), 9 ms (dvr.c, PRE-INTEGRATION, has its error) */
#define DVR_PREINT_SIZE COLORMAP_TABLE_SIZE
/* the step accepted, in voxels: finer gains nothing at float precision, and
 * coarser than a few voxels misses whole cells */
#define DVR_STEP_MIN_VOX (1.0 / 1024.0)
#define DVR_STEP_MAX_VOX 16.0

typedef struct dvr_settings {
    double step_vox;          /* sample spacing along the ray, in voxels (smallest spacing); default 0.5 */
    float min_transmittance;  /* stop once T falls below this, in [0, 1); default 1/255 */
    bool preintegrate;        /* pre-integrated slabs (DVR_PREINT_SIZE^2 table); default off */
    bool skip_empty;          /* skip macrocells of opacity 0; default on (off: for tests and timing) */
} dvr_settings;

/* What one integration did; the caller sums them across rays if it likes. */
typedef struct dvr_stats {
    uint64_t samples;         /* trilinear field samples taken */
    uint64_t slabs;           /* slabs composited */
    uint64_t spans_skipped;   /* empty macrocell spans the walk stopped at (a leap passes more) */
    uint64_t terminated;      /* 1 when the ray stopped on min_transmittance */
} dvr_stats;

/* One step's worth of a transfer-function entry: colour (not associated,
 * linear RGB) and the opacity of one full step. */
typedef struct dvr_rgba {
    float r, g, b, a;
} dvr_rgba;

/* Invariants: vol and grid describe the same field; step_t_world > 0;
 * every table matches `tf` and `settings` (dvr_set_transfer,
 * dvr_set_settings keep them so). */
typedef struct dvr_volume {
    const volume *vol;            /* not owned */
    const macrocell_grid *grid;   /* owned when own_grid */
    bool own_grid;
    dvr_settings settings;
    double voxel_world;           /* world length of "one voxel": the smallest spacing */
    colormap tf;                  /* the transfer function, range fitted to the volume when automatic */
    colormap_table table;         /* tf baked: the classic path's lookup (its index, not its values) */
    dvr_rgba step_rgba[COLORMAP_TABLE_SIZE]; /* per table entry: colour, and opacity over one step */
    dvr_rgba *preint;             /* DVR_PREINT_SIZE^2, [front * SIZE + back]; NULL until first needed */
    double preint_lo, preint_scale; /* value to preint entry: (v - lo) * scale, rounded; scale 0 when lo == hi */
    float *cell_opacity;          /* per macrocell: largest opacity its values reach (both binnings) */
    uint8_t *cell_leap;           /* per macrocell: leap field (macrocell.h LEAPS), marked where cell_opacity is 0 */
    float *range_scratch;         /* dvr_set_transfer's range-maximum tables (dvr.c) */
    struct dvr_preint_sums *sums; /* dvr_set_transfer's running integrals of the transfer function (dvr.c) */
} dvr_volume;

/* The defaults above. */
dvr_settings dvr_settings_default(void);

/* A renderer for `vol` (kept by pointer) with transfer function `tf`
 * (copied; an automatic range is fitted to the volume's min and max) and
 * `settings` (NULL: the defaults). `grid` is vol's macrocell grid, kept by
 * pointer, or NULL to build one (MACROCELL_DEFAULT_K). NULL (err set) on a
 * volume without cells, a grid of another shape, spacing or origin,
 * settings out of range, or no memory. */
dvr_volume *dvr_create(const volume *vol, const macrocell_grid *grid, const colormap *tf,
                       const dvr_settings *settings, tess_error *err);
void dvr_destroy(dvr_volume *d); /* NULL is fine */

/* A new transfer function (copied, range fitted as in dvr_create): rebakes
 * the tables (1024 entries, the pre-integration table when it is on) and
 * the macrocells' opacities in O(macrocells) through a range-maximum table. */
void dvr_set_transfer(dvr_volume *d, const colormap *tf);

/* New settings; false (nothing changed, err set) when out of range or out
 * of memory. Rebuilds what the step size or pre-integration needs. */
bool dvr_set_settings(dvr_volume *d, const dvr_settings *settings, tess_error *err);

/* Render `vol` with its macrocell grid `grid` from now on (both kept by
 * pointer, as dvr_create's; a grid d built itself is freed): a time step
 * of the same layout (the same dimensions, spacing and origin, a grid of
 * the same block edge). The transfer function keeps its range (fitted to
 * the first volume when automatic: a value keeps its colour from step to
 * step) and its tables; the macrocells' opacities are recomputed,
 * O(macrocells). False (nothing changed, err set) for another layout. Not
 * during an integration. */
bool dvr_set_volume(dvr_volume *d, const volume *vol, const macrocell_grid *grid, tess_error *err);

/* Integrate the ray org + t dir (world space, dir of any nonzero length)
 * over t in [t0, t1] (either may be infinite) clipped to the volume's box; t1 is where the caller's
 * ray stops (an opaque surface in front of the volume's back). jitter in
 * [0, 1) offsets the slab grid by that fraction of a step (out of range or
 * NaN reads as 0). Writes the associated colour (linear RGB, premultiplied:
 * composite as rgb + T * background) and the transmittance T. False, with
 * rgb 0 and T 1, when the ray misses the box or the segment is empty. */
bool dvr_integrate(const dvr_volume *d, const double org[3], const double dir[3], double t0, double t1,
                   double jitter, float rgb_out[3], float *transmittance_out);

/* The same, adding what it did to *stats (NULL is fine). */
bool dvr_integrate_stats(const dvr_volume *d, const double org[3], const double dir[3], double t0, double t1,
                         double jitter, float rgb_out[3], float *transmittance_out, dvr_stats *stats);

#endif
