/* macrocell.c - the min/max grid and the 3D-DDA (macrocell.h). The walk is
 * Amanatides and Woo's ("A Fast Voxel Traversal Algorithm for Ray
 * Tracing", Eurographics 1987), with each crossing t recomputed from its
 * plane rather than accumulated, so spans stay exact neighbours. */
#include "macrocell.h"

#include <math.h>
#include <stdlib.h>

macrocell_grid *macrocell_grid_create(const volume *v, uint32_t k, tess_error *err)
{
    if (k == 0 || k > MACROCELL_MAX_K) {
        tess_error_set(err, "macrocell grid: block edge %u is not in 1..%u", k, MACROCELL_MAX_K);
        return NULL;
    }
    const uint32_t n[3] = {v->nx, v->ny, v->nz};
    for (int a = 0; a < 3; a++)
        if (n[a] < 2) {
            tess_error_set(err, "macrocell grid: the volume has %u sample(s) along %c: no trilinear cell", n[a],
                           "xyz"[a]);
            return NULL;
        }
    macrocell_grid *g = calloc(1, sizeof *g);
    if (!g) {
        tess_error_set(err, "macrocell grid: out of memory");
        return NULL;
    }
    g->k = k;
    for (int a = 0; a < 3; a++) {
        g->cells[a] = n[a] - 1;
        g->m[a] = (g->cells[a] + k - 1) / k;
        g->spacing[a] = v->spacing[a];
        g->origin[a] = v->origin[a];
    }
    size_t count = macrocell_count(g);
    g->min = malloc(count * sizeof *g->min);
    g->max = malloc(count * sizeof *g->max);
    if (!g->min || !g->max) {
        macrocell_grid_destroy(g);
        tess_error_set(err, "macrocell grid: out of memory for %zu macrocells", count);
        return NULL;
    }
    for (size_t m = 0; m < count; m++) {
        g->min[m] = INFINITY;
        g->max[m] = -INFINITY;
    }
    /* Row by row in memory order. Along an axis, macrocell a spans samples
     * a k .. min((a + 1) k, n - 1): the sample on a block boundary belongs to
     * both blocks (the shared face). A row's block ranges are reduced first
     * (each sample read once, the boundary ones twice), then merged into the
     * macrocells the row's (y, z) lies in: one, or two on a boundary, per axis. */
    float *row_lo = malloc(g->m[0] * sizeof *row_lo), *row_hi = malloc(g->m[0] * sizeof *row_hi);
    if (!row_lo || !row_hi) {
        free(row_lo);
        free(row_hi);
        macrocell_grid_destroy(g);
        tess_error_set(err, "macrocell grid: out of memory");
        return NULL;
    }
    for (uint32_t z = 0; z < n[2]; z++) {
        uint32_t cz1 = z / k < g->m[2] ? z / k : g->m[2] - 1, cz0 = z % k == 0 && z > 0 ? z / k - 1 : cz1;
        for (uint32_t y = 0; y < n[1]; y++) {
            uint32_t cy1 = y / k < g->m[1] ? y / k : g->m[1] - 1, cy0 = y % k == 0 && y > 0 ? y / k - 1 : cy1;
            size_t row = volume_index(v, 0, y, z);
            for (uint32_t a = 0; a < g->m[0]; a++) {
                uint32_t x0 = a * k, x1 = x0 + k < n[0] - 1 ? x0 + k : n[0] - 1;
                float lo = volume_sample_at(v, row + x0), hi = lo;
                for (uint32_t x = x0 + 1; x <= x1; x++) {
                    float smp = volume_sample_at(v, row + x);
                    lo = smp < lo ? smp : lo;
                    hi = smp > hi ? smp : hi;
                }
                row_lo[a] = lo;
                row_hi[a] = hi;
            }
            for (uint32_t c = cz0; c <= cz1; c++)
                for (uint32_t b = cy0; b <= cy1; b++) {
                    size_t m0 = macrocell_index(g, 0, b, c);
                    for (uint32_t a = 0; a < g->m[0]; a++) {
                        g->min[m0 + a] = row_lo[a] < g->min[m0 + a] ? row_lo[a] : g->min[m0 + a];
                        g->max[m0 + a] = row_hi[a] > g->max[m0 + a] ? row_hi[a] : g->max[m0 + a];
                    }
                }
        }
    }
    free(row_lo);
    free(row_hi);
    return g;
}

void macrocell_grid_destroy(macrocell_grid *g)
{
    if (!g)
        return;
    free(g->min);
    free(g->max);
    free(g);
}

/* Two chamfer passes with the 26 neighbours at distance 1, forward over
 * the 13 neighbours before a macrocell in memory order, then backward over
 * the 13 after it: exact for the chessboard (L-infinity) distance, as
 * Rosenfeld and Pfaltz's two-pass transform is in 2D ("Sequential
 * Operations in Digital Picture Processing", JACM 1966). A neighbour of
 * the other class is at distance 1; one of the same class passes its own
 * distance on, plus 1 (the transform towards the other class's macrocells,
 * for both classes at once). */
void macrocell_leap_build(const macrocell_grid *g, uint8_t *leap)
{
    const int32_t m[3] = {(int32_t)g->m[0], (int32_t)g->m[1], (int32_t)g->m[2]};
    size_t count = macrocell_count(g);
    for (size_t i = 0; i < count; i++)
        leap[i] = (uint8_t)((leap[i] & MACROCELL_LEAP_MARK) | MACROCELL_LEAP_MAX);
    for (int pass = 0; pass < 2; pass++) {
        int32_t s = pass == 0 ? -1 : 1; /* the neighbours already final lie on side s */
        for (int32_t n = 0; n < m[2]; n++)
            for (int32_t nb = 0; nb < m[1]; nb++)
                for (int32_t na = 0; na < m[0]; na++) {
                    int32_t c = pass == 0 ? n : m[2] - 1 - n, b = pass == 0 ? nb : m[1] - 1 - nb,
                            a = pass == 0 ? na : m[0] - 1 - na;
                    uint8_t *here = &leap[macrocell_index(g, (uint32_t)a, (uint32_t)b, (uint32_t)c)];
                    unsigned mark = *here & MACROCELL_LEAP_MARK, best = *here & MACROCELL_LEAP_MAX;
                    /* (dz, dy, dx) lexicographically on side s of (0, 0, 0) */
                    for (int32_t dz = 0; dz <= 1 && best > 1; dz++)
                        for (int32_t dy = dz ? -1 : 0; dy <= 1; dy++)
                            for (int32_t dx = dz || dy ? -1 : 1; dx <= 1; dx++) {
                                int32_t x = a + s * dx, y = b + s * dy, z = c + s * dz;
                                if (x < 0 || y < 0 || z < 0 || x >= m[0] || y >= m[1] || z >= m[2])
                                    continue;
                                uint8_t there = leap[macrocell_index(g, (uint32_t)x, (uint32_t)y, (uint32_t)z)];
                                unsigned d = (there & MACROCELL_LEAP_MARK) != mark ? 1u
                                                                                   : (there & MACROCELL_LEAP_MAX) + 1u;
                                best = d < best ? d : best;
                            }
                    *here = (uint8_t)(mark | best);
                }
    }
}

void volume_ray_to_voxel(const double origin[3], const double spacing[3], const double org[3], const double dir[3],
                         double org_vox[3], double dir_vox[3])
{
    for (int a = 0; a < 3; a++) {
        org_vox[a] = (org[a] - origin[a]) / spacing[a];
        dir_vox[a] = dir[a] / spacing[a];
    }
}

bool volume_clip_box(const double org[3], const double dir[3], const double lo[3], const double hi[3], double *t0,
                     double *t1)
{
    double near = *t0, far = *t1;
    for (int a = 0; a < 3; a++) {
        if (dir[a] == 0.0) {
            if (org[a] < lo[a] || org[a] > hi[a])
                return false;
            continue;
        }
        double ta = (lo[a] - org[a]) / dir[a], tb = (hi[a] - org[a]) / dir[a];
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        near = ta > near ? ta : near;
        far = tb < far ? tb : far;
    }
    if (!(near <= far))
        return false;
    *t0 = near;
    *t1 = far;
    return true;
}

/* the t where the ray leaves cell c of axis a through its far plane (step != 0) */
static inline double cell_far_t(const volume_dda *w, int a, int32_t c)
{
    double plane = (double)(w->step[a] > 0 ? c + 1 : c) * w->cell_size;
    return (plane - w->org[a]) / w->dir[a];
}

/* the t where the ray leaves the current cell through axis a's far plane */
static inline double dda_leave(const volume_dda *w, int a)
{
    if (w->step[a] == 0)
        return INFINITY;
    return cell_far_t(w, a, w->cell[a]);
}

void volume_dda_begin(volume_dda *w, const double org[3], const double dir[3], double t0, double t1,
                      uint32_t cell_size, const int32_t lo[3], const int32_t hi[3])
{
    w->cell_size = cell_size;
    w->t = t0;
    w->t_end = t1;
    w->done = !(t0 < t1);
    for (int a = 0; a < 3; a++) {
        w->org[a] = org[a];
        w->dir[a] = dir[a];
        w->lo[a] = lo[a];
        w->hi[a] = hi[a];
        w->step[a] = dir[a] > 0.0 ? 1 : dir[a] < 0.0 ? -1 : 0;
        /* the cell holding the point at t0; on a plane, the one the ray goes
         * into. Rounding may pick a neighbour: clamping keeps it in range and
         * a wrong pick only yields a zero-length span, which is skipped */
        double p = (w->step[a] == 0 ? org[a] : org[a] + t0 * dir[a]) / cell_size;
        double c = floor(p);
        if (w->step[a] < 0 && c == p)
            c -= 1.0;
        /* written so a NaN (a NaN ray) lands on lo, never in an int conversion */
        c = !(c >= lo[a]) ? lo[a] : c > hi[a] ? hi[a] : c;
        w->cell[a] = (int32_t)c;
        w->t_leave[a] = dda_leave(w, a);
    }
}

bool volume_dda_next(volume_dda *w, int32_t cell[3], double *t_enter, double *t_exit)
{
    while (!w->done) {
        /* the t where the ray leaves the current cell through each axis' far plane */
        int axis = -1;
        double t_leave = INFINITY;
        for (int a = 0; a < 3; a++)
            if (w->t_leave[a] < t_leave) {
                t_leave = w->t_leave[a];
                axis = a;
            }
        double t0 = w->t, t1 = t_leave < w->t_end ? t_leave : w->t_end;
        if (t1 < t0)
            t1 = t0;
        for (int a = 0; a < 3; a++)
            cell[a] = w->cell[a];
        if (t1 >= w->t_end || axis < 0)
            w->done = true;
        else {
            w->cell[axis] += w->step[axis];
            if (w->cell[axis] < w->lo[axis] || w->cell[axis] > w->hi[axis])
                w->done = true;
            w->t_leave[axis] = dda_leave(w, axis);
        }
        w->t = t1;
        if (t1 > t0) {
            *t_enter = t0;
            *t_exit = t1;
            return true;
        }
    }
    return false;
}

bool macrocell_walk_begin(macrocell_walk *w, const macrocell_grid *g, const double org[3], const double dir[3],
                          double t_min, double t_max)
{
    w->grid = g;
    volume_ray_to_voxel(g->origin, g->spacing, org, dir, w->org, w->dir);
    bool moves = false, finite = true;
    for (int a = 0; a < 3; a++) {
        moves |= w->dir[a] != 0.0;
        finite &= isfinite(w->org[a]) && isfinite(w->dir[a]);
    }
    if (!moves || !finite || isnan(t_min) || isnan(t_max)) {
        w->dda.done = true; /* a ray that goes nowhere (or a NaN) crosses nothing */
        return false;
    }
    const double lo[3] = {0.0, 0.0, 0.0};
    const double hi[3] = {g->cells[0], g->cells[1], g->cells[2]};
    double t0 = t_min, t1 = t_max;
    if (!volume_clip_box(w->org, w->dir, lo, hi, &t0, &t1)) {
        w->dda.done = true;
        return false;
    }
    const int32_t cell_lo[3] = {0, 0, 0};
    const int32_t cell_hi[3] = {(int32_t)g->m[0] - 1, (int32_t)g->m[1] - 1, (int32_t)g->m[2] - 1};
    volume_dda_begin(&w->dda, w->org, w->dir, t0, t1, g->k, cell_lo, cell_hi);
    return true;
}

bool macrocell_walk_next(macrocell_walk *w, macrocell_span *span)
{
    int32_t c[3];
    if (!volume_dda_next(&w->dda, c, &span->t_enter, &span->t_exit))
        return false;
    for (int a = 0; a < 3; a++)
        span->m[a] = (uint32_t)c[a];
    span->index = macrocell_index(w->grid, span->m[0], span->m[1], span->m[2]);
    return true;
}

void macrocell_walk_leap(macrocell_walk *w, const macrocell_span *span, uint32_t dist)
{
    volume_dda *d = &w->dda;
    if (dist < MACROCELL_LEAP_MIN || d->done)
        return;
    int32_t r = (int32_t)dist - 1;
    /* where the ray leaves the cube: its first far plane; an axis where the
     * cube reaches past the grid leaves it at the walk's end */
    double t_exit = d->t_end;
    int exit_axis = -1;
    for (int a = 0; a < 3; a++) {
        if (d->step[a] == 0)
            continue;
        int32_t far = (int32_t)span->m[a] + d->step[a] * r;
        if (far < d->lo[a] || far > d->hi[a])
            continue;
        double t = cell_far_t(d, a, far);
        if (t < t_exit) {
            t_exit = t;
            exit_axis = a;
        }
    }
    if (!(t_exit > d->t))
        return; /* the walk is there already */
    if (t_exit >= d->t_end || exit_axis < 0) {
        d->t = d->t_end;
        d->done = true;
        return;
    }
    /* per axis the cell whose planes' t bracket t_exit (near <= t_exit <
     * far: a tie goes on, where the full walk gives a zero-length span).
     * The exit axis' is the cube's far cell's neighbour, entered at t_exit.
     * On another axis the walk stays where its current cell's far t is
     * beyond t_exit (no plane crossed: the usual case, no division); else
     * the point's floor, which rounding may put one off, corrected with the
     * plane t's the walk steps by (never behind the current cell, whose
     * near t is at most the walk's t) */
    for (int a = 0; a < 3; a++) {
        int32_t step = d->step[a], cell;
        if (step == 0 || (a != exit_axis && d->t_leave[a] > t_exit))
            continue;
        if (a == exit_axis)
            cell = (int32_t)span->m[a] + step * (r + 1);
        else {
            double c = floor((d->org[a] + t_exit * d->dir[a]) / d->cell_size);
            c = c < d->lo[a] ? d->lo[a] : c > d->hi[a] ? d->hi[a] : c;
            cell = (int32_t)c;
            if ((cell - d->cell[a]) * step <= 0)
                cell = d->cell[a] + step; /* the current cell's far t is not beyond t_exit */
            else
                while (cell - step != d->cell[a] && cell_far_t(d, a, cell - step) > t_exit)
                    cell -= step;
        }
        for (;;) {
            if (cell < d->lo[a] || cell > d->hi[a]) {
                d->t = t_exit;
                d->done = true; /* out of the grid: the full walk ends here too */
                return;
            }
            double t_far = cell_far_t(d, a, cell);
            if (t_far > t_exit) {
                d->cell[a] = cell;
                d->t_leave[a] = t_far;
                break;
            }
            cell += step;
        }
    }
    d->t = t_exit;
}

void macrocell_walk_cells(const macrocell_walk *w, const macrocell_span *span, volume_dda *cells)
{
    const macrocell_grid *g = w->grid;
    int32_t lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        uint32_t first = span->m[a] * g->k, end = first + g->k < g->cells[a] ? first + g->k : g->cells[a];
        lo[a] = (int32_t)first;
        hi[a] = (int32_t)end - 1;
    }
    volume_dda_begin(cells, w->org, w->dir, span->t_enter, span->t_exit, 1, lo, hi);
}
