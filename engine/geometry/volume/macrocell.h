/* macrocell.h - a min/max grid over blocks of the trilinear field's cells,
 * and the 3D-DDA that walks a ray through it (or through the cells
 * themselves), in order, with the ray's t at each entry and exit.
 *
 * CELLS. The trilinear field of a volume (volume.h) has (nx-1)(ny-1)(nz-1)
 * cells; cell (i, j, k) spans samples i..i+1, j..j+1, k..k+1, so two
 * neighbouring cells share a face of four samples.
 *
 * MACROCELLS. Macrocell (a, b, c) is the block of k^3 cells starting at cell
 * (a k, b k, c k), cut short at the volume's far faces; it holds the min and
 * max of the samples i = a k .. min((a+1) k, nx-1) (and so on for y and z):
 * the shared boundary samples included. Inside a cell the trilinear field is
 * a convex combination of the cell's 8 samples, so it takes exactly the
 * values between the min and max of those samples it reaches; hence
 * "min <= iso <= max" is a conservative (never false-negative) test that the
 * field in the macrocell can reach iso, and "max < lo or min > hi" proves a
 * value range absent (empty-space skipping).
 *
 * WALKS. volume_dda walks any regular grid of cells `cell_size` voxels wide,
 * in voxel coordinates (sample (i, j, k) at (i, j, k)); the macrocell walk is
 * one over the macrocells, clipped to the field's box [0, n-1]^3, and the
 * cell walk inside one macrocell span is one over its cells with the span's
 * [t_enter, t_exit]. Every boundary t is computed afresh from its plane,
 * (plane - org) / dir in double precision, never accumulated, and the exit t
 * of one span *is* the entry t of the next: spans tile the clipped ray
 * without gaps or overlaps, so nothing falls between cells. A ray through an
 * edge or corner would give zero-length spans; they are skipped. The ray
 * parameter t is the caller's: world rays are mapped to voxel coordinates
 * with the same t (volume_ray_to_voxel).
 *
 * LEAPS. Stepping the DDA one macrocell at a time through a region where
 * nothing changes was the walk's cost (the MRI under mri-soft: ~18
 * non-empty and as many empty macrocells a ray). A leap field
 * (macrocell_leap_build) marks each macrocell with one of two classes
 * (empty or not: the caller's) and holds the Chebyshev distance, in
 * macrocells, to the nearest macrocell of the other class: from macrocell
 * m with distance d every macrocell within d - 1 of m on each axis is of
 * m's class, so macrocell_walk_leap moves the walk to where the ray leaves
 * that cube: one exit t (its far planes' t, the formula the DDA steps by)
 * and the cell there, instead of up to 3 (d - 1) steps. The field is the
 * caller's: what "empty" means (a transfer function's zero opacity, an
 * iso-value out of range) changes with its settings, and rebuilding it is
 * O(macrocells), two chamfer passes. A leap changes no span the walk gives
 * afterwards: the cell it lands in is the one the full walk is in at that
 * t (per axis, the cell whose planes' t bracket it), entered at the same
 * t; every span it jumps over lies in the cube.
 *
 * Ownership: the grid owns its arrays and copies what it needs of the
 * volume (it keeps no pointer to it). Threading: a built grid is read-only;
 * walks are values on the caller's stack. */
#ifndef TESSERA_MACROCELL_H
#define TESSERA_MACROCELL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"
#include "volume.h"

/* the usual block edge: 8^3 cells a macrocell, so the grid is 1/512 of the
 * sample count (8 bytes each) and a build reads (9/8)^3 ~ 1.4 samples per sample */
#define MACROCELL_DEFAULT_K 8u
/* the largest block edge accepted (a block of 256^3 cells would skip nothing) */
#define MACROCELL_MAX_K 256u

typedef struct macrocell_grid {
    uint32_t k;               /* cells per macrocell edge, 1..MACROCELL_MAX_K */
    uint32_t cells[3];        /* cells of the trilinear field per axis: n - 1 (>= 1) */
    uint32_t m[3];            /* macrocells per axis: ceil(cells / k) */
    float *min, *max;         /* per macrocell, index a + m[0] * (b + m[1] * c); min <= max */
    double spacing[3], origin[3]; /* the volume's, for world rays */
} macrocell_grid;

/* Build the grid over `v` with k cells per macrocell edge. NULL (err set)
 * when a dimension has fewer than 2 samples (no cell), k is 0 or above
 * MACROCELL_MAX_K, or memory is short. */
macrocell_grid *macrocell_grid_create(const volume *v, uint32_t k, tess_error *err);
void macrocell_grid_destroy(macrocell_grid *g); /* NULL is fine */

static inline size_t macrocell_count(const macrocell_grid *g) { return (size_t)g->m[0] * g->m[1] * g->m[2]; }

static inline size_t macrocell_index(const macrocell_grid *g, uint32_t a, uint32_t b, uint32_t c)
{
    return (size_t)a + (size_t)g->m[0] * ((size_t)b + (size_t)g->m[1] * c);
}

/* Can the trilinear field in macrocell `index` take the value iso? (exact for
 * the samples' range; see MACROCELLS) */
static inline bool macrocell_may_reach(const macrocell_grid *g, size_t index, float iso)
{
    return g->min[index] <= iso && iso <= g->max[index];
}

/* Does the macrocell's value range meet [lo, hi]? (a transfer function's
 * visible range: false means the macrocell is empty space) */
static inline bool macrocell_may_overlap(const macrocell_grid *g, size_t index, float lo, float hi)
{
    return g->min[index] <= hi && lo <= g->max[index];
}

/* A leap field entry is a macrocell's class (MACROCELL_LEAP_MARK: set or
 * not, the caller's meaning) and the Chebyshev distance, in macrocells, to
 * the nearest macrocell of the other class (bits MACROCELL_LEAP_MAX: 1 ..
 * MACROCELL_LEAP_MAX, which also stands for "none that near"). */
#define MACROCELL_LEAP_MARK 0x80u
#define MACROCELL_LEAP_MAX 0x7fu

/* the smallest distance worth a leap: a leap costs about as many divisions
 * as 6 DDA steps (3 far planes, a floor and plane checks per axis that
 * crosses one), and from distance 2 it saves 1 to 3 steps */
#define MACROCELL_LEAP_MIN 3u

static inline uint32_t macrocell_leap_dist(uint8_t leap) { return leap & MACROCELL_LEAP_MAX; }

/* Fill in the distances of `leap` (macrocell_count entries, indexed as min
 * and max) whose MACROCELL_LEAP_MARK bits hold the classes (other bits are
 * ignored). O(macrocells). */
void macrocell_leap_build(const macrocell_grid *g, uint8_t *leap);

/* A world ray as voxel coordinates with the same t: org_vox = (org - origin)
 * / spacing, dir_vox = dir / spacing, per axis. */
void volume_ray_to_voxel(const double origin[3], const double spacing[3], const double org[3], const double dir[3],
                         double org_vox[3], double dir_vox[3]);

/* Clip [*t0, *t1] to the box lo..hi (voxel coordinates) by slabs; false when
 * nothing is left (or the ray is parallel to a slab and outside it). */
bool volume_clip_box(const double org[3], const double dir[3], const double lo[3], const double hi[3], double *t0,
                     double *t1);

/* A walk through a grid of cells `cell_size` voxels wide: cell c spans
 * [c cell_size, (c + 1) cell_size] on each axis. */
typedef struct volume_dda {
    double org[3], dir[3];     /* the ray, voxel coordinates */
    double cell_size;          /* voxels per cell edge */
    int32_t cell[3];           /* the current cell */
    int32_t step[3];           /* +1, -1 or 0 (the ray is parallel to that axis' planes) */
    int32_t lo[3], hi[3];      /* the walk stays in cells lo..hi (inclusive) */
    double t, t_end;           /* the current cell's entry t; the walk's last t */
    double t_leave[3];         /* per axis, the t of the current cell's far plane ((plane - org) / dir;
                                * INFINITY for step 0): only the axis stepped across is recomputed */
    bool done;
} volume_dda;

/* Start a walk over [t0, t1] (already clipped to the grid's box: the start
 * cell is found from the point at t0 and clamped to lo..hi). */
void volume_dda_begin(volume_dda *w, const double org[3], const double dir[3], double t0, double t1,
                      uint32_t cell_size, const int32_t lo[3], const int32_t hi[3]);

/* The next cell along the ray with its [t_enter, t_exit] (t_enter < t_exit,
 * t_enter the previous span's t_exit); false when the walk is over. */
bool volume_dda_next(volume_dda *w, int32_t cell[3], double *t_enter, double *t_exit);

/* One macrocell on a ray. */
typedef struct macrocell_span {
    uint32_t m[3];            /* the macrocell */
    size_t index;             /* macrocell_index(m) */
    double t_enter, t_exit;   /* the ray's t inside it; t_enter < t_exit */
} macrocell_span;

/* A walk through the macrocells a world ray crosses, front to back. */
typedef struct macrocell_walk {
    const macrocell_grid *grid;
    double org[3], dir[3];    /* the ray in voxel coordinates (for cell walks inside a span) */
    volume_dda dda;           /* over macrocells, cell_size k */
} macrocell_walk;

/* Start the walk of the world ray org + t dir, t in [t_min, t_max], clipped
 * to the field's box; false when it misses the box, or dir is zero, or the
 * ray is not finite (nothing to walk; macrocell_walk_next then says so). */
bool macrocell_walk_begin(macrocell_walk *w, const macrocell_grid *g, const double org[3], const double dir[3],
                          double t_min, double t_max);
bool macrocell_walk_next(macrocell_walk *w, macrocell_span *span);

/* `span` was the last the walk gave and its macrocell has leap distance
 * `dist` (LEAPS): move the walk on to where the ray leaves the cube of
 * macrocells within dist - 1 of it (the walk may end there; its dda.t is
 * then that exit t). The next span is the first macrocell after that cube,
 * as the cell-by-cell walk would give it. No-op for dist < MACROCELL_LEAP_MIN. */
void macrocell_walk_leap(macrocell_walk *w, const macrocell_span *span, uint32_t dist);

/* Start the walk through the cells of the trilinear field inside `span`
 * (cell_size 1, cells of that macrocell only, over [t_enter, t_exit]). */
void macrocell_walk_cells(const macrocell_walk *w, const macrocell_span *span, volume_dda *cells);

#endif
