/* iso_kind.h - an iso-surface of a structured volume, ray traced directly
 * (no triangles), as a geometry kind (geometry.h): the surface where the
 * trilinear field (volume.h, iso_cell.h) equals the iso-value.
 *
 * PRIMITIVES. The whole volume is one primitive (prim 0) whose bounds are
 * the box of the macrocells that are not constant (a constant cell holds
 * no crossing of any value; the zero background around a scan is culled
 * by the BVH), rounded outwards to float, the same for every value; no
 * bounds (never hit) when the whole field is constant. Its `intersect`
 * walks the macrocells as iso_volume_first_hit does (HITS below): the walk
 * skips every block that cannot reach the iso-value, so
 * the empty-space skipping follows the value and changing the value needs
 * no rebuild of any accel (the BVH sees one box whatever the value). A
 * finer split (one primitive per block of macrocells) lets the BVH cull
 * blocks too, but each block's own walk then restarts its DDA and loses
 * the sign carried across block faces (iso_cell.h HALF-OPEN SEGMENTS) and
 * the boxes would have to follow the value to cull anything the macrocells
 * do not already skip, and a group of crossings (HITS) could straddle two
 * primitives; one primitive keeps all three (see iso_kind.c).
 *
 * SPACE. The kind's object space is the volume's world space (sample (i,
 * j, k) at origin + (i, j, k) spacing); an instance's transform places it.
 *
 * HITS. `intersect` gives the first float t in (t_near, t_far] where the
 * ray changes side of the surface. One walk through the macrocells and
 * their cells (iso_cell.h; every root of a cell, the sign carried from
 * cell to cell) runs from t_near (the cheap methods: from two cells
 * before it, as their roots move with where a segment starts) to the box's exit
 * whatever t_far is, and t_far only accepts what it found: a ray finds the
 * same t alone, in a packet and under any traversal order, bit for bit.
 * Crossings that round to one float t are one group: an odd number is one
 * hit, an even number (a sheet thinner than the float t can resolve)
 * cancels, so counting hits by next-hit queries (t_near raised to the
 * previous hit) keeps parity: what caps and transparency need.
 * Integer samples (uint8, int16, uint16) equal to an integer value would
 * make f exactly 0 on whole faces (a ray touching the value without
 * crossing it); such a value is traced as the next float above it, so
 * samples equal to the value count as below it (iso_kind_value still gives
 * the value set).
 * `describe`: the point org + t dir (computed in double, rounded once),
 * its error bound (iso_kind.c: the float t's rounding, the point's, and
 * the root's tolerance; for the cheap methods one cell), the unit analytic
 * gradient (towards higher values) as the geometric normal, the
 * central-difference gradients of the cell's samples interpolated at the
 * hit as the shading normal (continuous across cells: no facets), and the
 * kind's colour.
 *
 * CLOSED. The surface bounds a solid (parity works) exactly when it does
 * not meet the volume's boundary: the field on the six faces is continuous
 * on a connected set and bilinear on each face cell, so it takes exactly
 * the values between the boundary samples' min and max. The kind keeps
 * those (one pass over the faces when the shared volume is made) and says
 * closed when the iso-value is outside [boundary min, boundary max]: O(1),
 * exact for the field, and it changes with the value (set_value's caller
 * calls scene_forget_closed).
 *
 * OWNERSHIP. Several iso kinds (several values of one volume, each its own
 * geometry) share one iso_volume: the volume, its macrocell grid and the
 * boundary range, reference counted. iso_volume_create takes the volume
 * and grid and frees them when the last reference goes;
 * iso_volume_borrow shares a pair the caller keeps (alive until the last
 * kind made from it is destroyed). Each kind holds one reference; the
 * scene owns a kind once scene_add_geometry took it (iso_kind_ops.destroy
 * releases the reference). The creator's own reference is dropped with
 * iso_volume_release once the kinds are made.
 *
 * Threading: reference counts are atomic (kinds may be destroyed on any
 * thread); everything else is read-only while anything traces, and
 * iso_kind_set_value runs only where nothing traces (a serial section). */
#ifndef TESSERA_ISO_KIND_H
#define TESSERA_ISO_KIND_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/err.h"
#include "engine/accel/geometry.h"
#include "engine/base/vec3.h"
#include "iso_cell.h"
#include "macrocell.h"
#include "volume.h"

typedef struct iso_volume iso_volume;
typedef struct iso_kind iso_kind;

/* Share `v` with `grid` (built over v; NULL: one is built with
 * MACROCELL_DEFAULT_K). Takes ownership of both, also on failure. One
 * reference, the caller's. NULL (err set) when v is NULL or short of
 * memory. */
iso_volume *iso_volume_create(volume *v, macrocell_grid *grid, tess_error *err);
/* The same over a volume and grid the caller owns and keeps alive until
 * the last reference goes; they are never freed here. */
iso_volume *iso_volume_borrow(const volume *v, const macrocell_grid *grid, tess_error *err);
void iso_volume_retain(iso_volume *shared);
void iso_volume_release(iso_volume *shared); /* NULL is fine; the last one frees */
const volume *iso_volume_data(const iso_volume *shared);
const macrocell_grid *iso_volume_grid(const iso_volume *shared);

/* TIME STEPS. A shared volume made by iso_volume_create may show a series
 * of volume files (series.h), one step at a time: step 0 is the volume it
 * was made with (loaded from paths[0]). A loader thread loads the step asked
 * for next and builds its macrocell grid, boundary range and active box
 * while frames render; at most two steps are in memory (the one shown and
 * one pending). Every step must have step 0's layout (volume_same_layout:
 * dimensions, type, spacing, origin), else its load fails with an error
 * naming the file and the field, and the step shown stays.
 * iso_volume_set_step swaps the step in for every kind sharing the volume
 * (they read it through the shared volume: the first call swaps, the others
 * find it shown) and tells the watchers (a dvr medium, whose dvr_volume
 * points at the samples): only where nothing traces. The active box (the
 * kinds' bounds) and the boundary range (`closed`) follow the step: an
 * accel rebuilds the kinds' one-primitive trees (accel_set_time_step).
 * attach: paths copied, each step read by `read` (the kind does not know
 * file formats: engine/load/volume_read.h's volume_load is one); false for a
 * borrowed volume or on no memory. */
typedef volume *volume_file_reader(const char *path, tess_error *err);
bool iso_volume_attach_series(iso_volume *shared, const char *const *paths, uint32_t count, volume_file_reader *read,
                              tess_error *err);
uint32_t iso_volume_step_count(const iso_volume *shared); /* 1 without a series */
uint32_t iso_volume_step(const iso_volume *shared);       /* the step shown */
/* Whether `step` (mod the count) can be shown without waiting; when not,
 * the loader is asked for it. Any thread. */
bool iso_volume_step_ready(iso_volume *shared, uint32_t step);
/* Show `step` (mod the count), waiting for its load if it is not loaded.
 * False with the file's error (the step shown stays). */
bool iso_volume_set_step(iso_volume *shared, uint32_t step, tess_error *err);

/* Something that keeps pointers to the shared volume's samples or grid
 * (a dvr_volume) and must follow a swap: `swapped` runs inside
 * iso_volume_set_step with the new step's, before the old step is freed.
 * The watcher struct lives in the watcher's own memory (no allocation);
 * watch and unwatch only where nothing traces. */
typedef struct iso_volume_watcher {
    void (*swapped)(void *ctx, const volume *v, const macrocell_grid *grid);
    void *ctx;
    struct iso_volume_watcher *next; /* the shared volume's list */
} iso_volume_watcher;
void iso_volume_watch(iso_volume *shared, iso_volume_watcher *w);
void iso_volume_unwatch(iso_volume *shared, iso_volume_watcher *w);

/* One iso-surface of a volume the caller keeps (borrowed: v and grid must
 * outlive the kind; the kind holds a borrowing iso_volume of its own).
 * colour: linear RGB in [0, 1], every hit's colour; material_id: the
 * scene material that lights it. NULL (err set) for a non-finite iso or no
 * memory. */
iso_kind *iso_kind_create(const volume *v, const macrocell_grid *grid, float iso_value, vec3 colour,
                          uint32_t material_id, iso_method method, tess_error *err);
/* The same over a shared volume (takes a reference of its own). */
iso_kind *iso_kind_create_shared(iso_volume *shared, float iso_value, vec3 colour, uint32_t material_id,
                                 iso_method method, tess_error *err);
/* Not needed once the scene owns the kind (its destroy op does this). */
void iso_kind_destroy(iso_kind *k); /* NULL is fine */

/* The iso-value. Set only where nothing traces; false (unchanged) when it
 * is not finite. No accel rebuild is needed; scene_forget_closed is. */
bool iso_kind_set_value(iso_kind *k, float iso_value);
float iso_kind_value(const iso_kind *k);
/* The volume's sample range: where stepping the value makes sense. */
void iso_kind_range(const iso_kind *k, float *lo, float *hi);

/* data: an iso_kind; .leaf = GEOMETRY_LEAF_PRIMS, one primitive. */
extern const geometry_ops iso_kind_ops;

#endif
