/* iso_cell.h - where a ray meets an iso-surface of the trilinear field:
 * exactly inside one cell, and along a whole volume.
 *
 * THE CUBIC. Inside a cell, in cell-local coordinates p in [0,1]^3 with
 * corner values c[x + 2y + 4z], the field is
 *   rho(p) = sum over corners of c * (x ? p.x : 1-p.x)(y ? p.y : 1-p.y)(z ? p.z : 1-p.z),
 * and along a ray p(s) = org + s dir it is a cubic in s. iso_cell_cubic
 * forms f(s) = rho(p(s)) - iso = a s^3 + b s^2 + c s + d (Marmitt, Kleer,
 * Wald, Friedrich, Slusallek, "Fast and Accurate Ray-Voxel Intersection
 * Techniques for Iso-Surface Ray Tracing", VMV 2004; the expansion is
 * Parker et al.'s, "Interactive Ray Tracing for Isosurface Rendering",
 * 1998). iso is subtracted from every corner first (the weights sum to 1),
 * so d is small where the surface is near, not the difference of two large
 * numbers.
 *
 * WHY DOUBLE. The coefficients are sums of eight products whose terms cancel
 * (a is a third difference of the corners: zero for any field linear along
 * the ray), and corner values reach 65535 (uint16) or CT values with an iso
 * in the thousands; in float the cancellation leaves errors ~1e-7 of the
 * corner magnitude in a and b, which moves near-tangent roots by far more
 * than 1e-4 cell and can flip the sign of d near the surface. In double the
 * same errors are 1e-16 relative, and the root's tolerance (1e-8 cell) is
 * met with room. The cost is nil next to fetching the eight corners.
 *
 * THE EXACT ROOT (Marmitt et al.). f's extrema are the roots of f' = 3a s^2
 * + 2b s + c, solved stably (q = -(B + sign(B) sqrt(B^2 - 4AC)) / 2, roots
 * q/A and C/q); those inside (s0, s1) split the segment into at most three
 * pieces on which f is monotonic, so each holds at most one root, found by a
 * sign change of f at its ends. The first such piece is refined by the
 * Illinois variant of regula falsi (a bisection step whenever two steps
 * fail to halve the bracket) until the bracket is at most tol_s wide. A
 * root where f touches zero without crossing (a tangent, double root) is
 * found only when f is exactly 0 at the extremum, as floating point gives
 * for exact data; a grazing ray that misses it by rounding misses it.
 *
 * HALF-OPEN SEGMENTS. A segment reports roots in (s0, s1]: a root exactly
 * at s0 belongs to the segment before (the neighbour cell), so walking
 * cells reports it once; f_s0 = 0 says "s0 is a root already reported".
 * f_s0 is the value at s0 *as the caller knows it*: its sign must be the
 * one the previous cell saw at its s1. Carrying that sign across cells
 * (rather than trusting this cell's cubic at s0, which rounds differently
 * and may flip the sign of a value ~0) makes the signs seen along a ray one
 * sequence: whenever the ray's field changes sign some segment sees it
 * change, so no root falls between cells (iso_volume_first_hit does this).
 *
 * THE CHEAP METHODS (for the speed/accuracy report): iso_cell_root_linear
 * interpolates linearly between f(s0) and f(s1) and so sees only a sign
 * change between the segment's ends (misses two crossings in one cell);
 * iso_cell_root_regula_falsi does a fixed number of plain regula falsi
 * steps on that same bracket (Neubauer et al. 2002's repeated linear
 * interpolation), with no extrema isolation.
 *
 * The ray parameter s of a cell is the caller's; tolerances are in s. For a
 * cell-local direction dir, a tolerance of e cell widths is e / |dir|.
 * Everything here is pure: no state, any thread. */
#ifndef TESSERA_ISO_CELL_H
#define TESSERA_ISO_CELL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/volume/macrocell.h"
#include "engine/volume/volume.h"

/* the exact method's default tolerance, in cell widths along the ray: far
 * below anything a pixel shows, and a few Illinois steps away */
#define ISO_CELL_TOL 1e-8
/* regula falsi steps of the cheap method (b) unless told otherwise */
#define ISO_CELL_RF_STEPS 3

/* f(s) = a s^3 + b s^2 + c s + d: the trilinear field minus iso along a ray */
typedef struct iso_cubic {
    double a, b, c, d;
} iso_cubic;

static inline double iso_cubic_eval(const iso_cubic *f, double s) { return ((f->a * s + f->b) * s + f->c) * s + f->d; }

/* The cubic of the cell with corners c[x + 2y + 4z] along the cell-local ray
 * org + s dir (org need not lie in the cell). */
iso_cubic iso_cell_cubic(const float corner[8], double iso, const double org[3], const double dir[3]);

/* The trilinear field at cell-local p, and its gradient there (per cell
 * width; divide by the spacing for world units). */
double iso_cell_value(const float corner[8], const double p[3]);
void iso_cell_gradient(const float corner[8], const double p[3], double grad[3]);

/* The exact method: the first root of f in (s0, s1], within tol_s; f_s0 the
 * value at s0 as the caller knows it (see HALF-OPEN SEGMENTS; iso_cubic_eval
 * at s0 when there is no neighbour). False when there is none. */
bool iso_cell_root(const iso_cubic *f, double s0, double f_s0, double s1, double tol_s, double *s);

/* Every root in (s0, s1], in order, at most 3 (a cubic has no more); the
 * count. roots[i] is what iso_cell_root would give on (roots[i-1], s1]. */
int iso_cell_roots(const iso_cubic *f, double s0, double f_s0, double s1, double tol_s, double roots[3]);

/* The next root after a root already found at s_after (within tol_s of it:
 * the same root is not reported again), up to s1. For transparency: the
 * surfaces behind the first. */
bool iso_cell_next_root(const iso_cubic *f, double s_after, double s1, double tol_s, double *s);

/* Cheap method (a): linear interpolation between f(s0) and f(s1); a root only
 * when they differ in sign (or f(s1) is 0). */
bool iso_cell_root_linear(const iso_cubic *f, double s0, double f_s0, double s1, double *s);

/* Cheap method (b): `steps` regula falsi steps on [s0, s1] when f changes sign
 * across it (no extrema isolation). */
bool iso_cell_root_regula_falsi(const iso_cubic *f, double s0, double f_s0, double s1, int steps, double *s);

/* ---- along a whole volume -------------------------------------------------- */

typedef enum iso_method {
    ISO_METHOD_EXACT,        /* extrema isolation + Illinois (Marmitt et al.) */
    ISO_METHOD_LINEAR,       /* (a): one linear interpolation per cell */
    ISO_METHOD_REGULA_FALSI, /* (b): ISO_CELL_RF_STEPS regula falsi steps per cell */
} iso_method;

typedef struct iso_hit {
    double t;             /* the world ray's t */
    uint32_t cell[3];     /* the trilinear cell hit (its low corner sample) */
    double local[3];      /* the hit in the cell's [0,1]^3 */
    double gradient[3];   /* of the field at the hit, world units (per world unit of distance) */
} iso_hit;

/* The first crossing of the iso-surface `iso` by the world ray org + t dir,
 * t in [t_min, t_max]: macrocells that cannot reach iso are skipped, the
 * cells of the others walked in order (macrocell.h), the sign carried from
 * cell to cell. `grid` must be built over `v`. False when the ray meets no
 * surface. */
bool iso_volume_first_hit(const volume *v, const macrocell_grid *grid, const double org[3], const double dir[3],
                          double t_min, double t_max, float iso, iso_method method, iso_hit *hit);

#endif
