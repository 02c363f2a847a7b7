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

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "macrocell.h"
#include "volume.h"

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

/* THE WALK both the first-hit query below and the iso-surface kind
 * (iso_kind.c) take: the cells along the world ray org + t dir, t in
 * [t_min, t_max], that can hold the iso-value (macrocells that cannot reach
 * it skipped whole, then cells whose 8 samples all lie on one side), in
 * order, each with its cubic along the ray and the field's value at its
 * entry, whose sign is carried from where the walk left the cell before
 * (rounding at a shared face cannot flip it: no root is lost or found
 * twice between cells). Given a leap field (iso_cell_walk.leap), runs of
 * macrocells that cannot reach iso are passed in one leap each (macrocell.h
 * LEAPS); the cells given, their t's and carried signs are the same. */

typedef struct iso_cell_candidate {
    int32_t cell[3];  /* its low corner sample */
    double te, tx;    /* the world ray's t at its entry and exit */
    float corner[8];  /* its samples (volume_cell_corners) */
    double org[3];    /* the ray's entry point in the cell's [0,1]^3: cell-local s = t - te */
    iso_cubic f;      /* field - iso along the ray, in s */
    double f0;        /* field - iso at s = 0 with the carried sign: f.d, or +-DBL_MIN where rounding
                         flipped it (the true value is ~0), or 0 where the walk left the cell before
                         exactly on the surface (that root was the cell before's) */
} iso_cell_candidate;

typedef struct iso_cell_walk {
    const volume *v;
    float iso;
    macrocell_walk walk;
    volume_dda cells;     /* the cells of the current span */
    bool in_span;         /* cells is walking a span */
    bool carried;         /* f_carry holds the field's sign (and a value) where the walk left */
    double f_carry;
    bool have_last;       /* last_f and last_s1: the candidate returned last, whose exit value is
                             carried when the walk goes on */
    iso_cubic last_f;
    double last_s1;
    double dir_len;       /* |dir| in voxel units: tolerances in cells become tolerances in t */
    /* the caller's, or NULL (begin sets it so): a leap field over the grid
     * whose MACROCELL_LEAP_MARK is set exactly where the macrocell cannot
     * reach iso (macrocell.h LEAPS); the walk then leaps from such spans
     * over the cube around them, all of one sign (below) */
    const uint8_t *leap;
    /* the caller's: stop (next returns false, stopped set) after skipping a
     * span or cell whose entry's float t is above stop_beyond (INFINITY:
     * never), so a caller waiting for the walk to pass a t does not walk on
     * through skipped space to the next candidate; next may be called
     * again to go on */
    float stop_beyond;
    bool stopped;
} iso_cell_walk;

/* A value of the sign the field has everywhere in a block whose samples
 * lie in [lo, hi] with iso outside it: what is carried past a skipped block.
 * Also past a leap: the macrocells of a leap's cube cannot reach iso and
 * neighbours share their face samples, so a macrocell below iso has no
 * neighbour above it; the cube is connected through faces, hence all of
 * it lies on the side of the macrocell leapt from. */
static inline double iso_sign_value(float lo, float hi, float iso)
{
    return lo > iso ? (double)lo - iso : (double)hi - iso;
}

/* iso_cell_walk_begin: start; false when the ray misses the volume (nothing
 * to walk). iso_cell_walk_next: the next cell that can hold the iso-value;
 * false when the walk is over (or stopped: stop_beyond). Inline: the walk
 * is the iso-surface kind's hot loop. */
static inline bool iso_cell_walk_begin(iso_cell_walk *w, const volume *v, const macrocell_grid *grid, const double org[3],
                         const double dir[3], double t_min, double t_max, float iso)
{
    w->v = v;
    w->iso = iso;
    w->in_span = false;
    w->carried = false;
    w->f_carry = 0.0;
    w->have_last = false;
    w->stop_beyond = INFINITY;
    w->stopped = false;
    w->leap = NULL;
    if (!macrocell_walk_begin(&w->walk, grid, org, dir, t_min, t_max))
        return false;
    const double *d = w->walk.dir;
    w->dir_len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    return true;
}

static inline bool iso_cell_walk_next(iso_cell_walk *w, iso_cell_candidate *out)
{
    const macrocell_grid *grid = w->walk.grid;
    const float iso = w->iso;
    w->stopped = false;
    if (w->have_last) { /* the candidate before was passed: carry its exit */
        w->f_carry = iso_cubic_eval(&w->last_f, w->last_s1);
        w->carried = true;
        w->have_last = false;
    }
    for (;;) {
        if (!w->in_span) {
            macrocell_span span;
            if (!macrocell_walk_next(&w->walk, &span))
                return false;
            if (!macrocell_may_reach(grid, span.index, iso)) {
                w->f_carry = iso_sign_value(grid->min[span.index], grid->max[span.index], iso);
                w->carried = true;
                if ((float)span.t_enter > w->stop_beyond) {
                    w->stopped = true;
                    return false;
                }
                uint32_t dist = w->leap ? macrocell_leap_dist(w->leap[span.index]) : 0;
                if (dist >= MACROCELL_LEAP_MIN) {
                    macrocell_walk_leap(&w->walk, &span, dist);
                    /* past stop_beyond in skipped space: no crossing lies between */
                    if ((float)w->walk.dda.t > w->stop_beyond) {
                        w->stopped = true;
                        return false;
                    }
                }
                continue;
            }
            macrocell_walk_cells(&w->walk, &span, &w->cells);
            w->in_span = true;
        }
        int32_t *c = out->cell;
        if (!volume_dda_next(&w->cells, c, &out->te, &out->tx)) {
            w->in_span = false;
            continue;
        }
        volume_cell_corners(w->v, (uint32_t)c[0], (uint32_t)c[1], (uint32_t)c[2], out->corner);
        float lo = out->corner[0], hi = out->corner[0];
        for (int i = 1; i < 8; i++) {
            lo = out->corner[i] < lo ? out->corner[i] : lo;
            hi = out->corner[i] > hi ? out->corner[i] : hi;
        }
        if (iso < lo || iso > hi) {
            w->f_carry = iso_sign_value(lo, hi, iso);
            w->carried = true;
            if ((float)out->te > w->stop_beyond) {
                w->stopped = true;
                return false;
            }
            continue;
        }
        for (int a = 0; a < 3; a++)
            out->org[a] = w->walk.org[a] + out->te * w->walk.dir[a] - c[a];
        out->f = iso_cell_cubic(out->corner, iso, out->org, w->walk.dir);
        /* the value at the entry: this cell's own f(0) (its magnitude matters to the
         * cheap methods' interpolation), but with the sign carried from the cell
         * before, which rounding at the shared face may have flipped */
        out->f0 = out->f.d;
        if (w->carried) {
            if (w->f_carry == 0.0)
                out->f0 = 0.0; /* the cell before's exit was a root, found there */
            else if (out->f0 == 0.0 || (out->f0 < 0.0) != (w->f_carry < 0.0))
                out->f0 = copysign(DBL_MIN, w->f_carry);
        }
        w->last_f = out->f;
        w->last_s1 = out->tx - out->te;
        w->have_last = true;
        return true;
    }
}


/* The first crossing of the iso-surface `iso` by the world ray org + t dir,
 * t in [t_min, t_max]: macrocells that cannot reach iso are skipped, the
 * cells of the others walked in order (macrocell.h), the sign carried from
 * cell to cell. `grid` must be built over `v`. False when the ray meets no
 * surface. */
bool iso_volume_first_hit(const volume *v, const macrocell_grid *grid, const double org[3], const double dir[3],
                          double t_min, double t_max, float iso, iso_method method, iso_hit *hit);

#endif
