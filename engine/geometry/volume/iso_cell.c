/* iso_cell.c - ray / trilinear-cell intersection (iso_cell.h). */
#include "iso_cell.h"

#include <float.h>
#include <math.h>

/* the Illinois refinement's cap: with a bisection at least every other step
 * the bracket halves every two steps, so 2 * 64 steps take any double
 * bracket below any tolerance; the cap only guards against a NaN */
#define REFINE_MAX_STEPS 160

iso_cubic iso_cell_cubic(const float corner[8], double iso, const double org[3], const double dir[3])
{
    /* along axis a the two corner weights are linear in s:
     *   w0(s) = (1 - org) - dir s,  w1(s) = org + dir s  -> alpha[a][x] + beta[a][x] s */
    double alpha[3][2], beta[3][2];
    for (int a = 0; a < 3; a++) {
        alpha[a][0] = 1.0 - org[a];
        beta[a][0] = -dir[a];
        alpha[a][1] = org[a];
        beta[a][1] = dir[a];
    }
    iso_cubic f = {0.0, 0.0, 0.0, 0.0};
    for (int c = 0; c < 8; c++) {
        int x = c & 1, y = (c >> 1) & 1, z = (c >> 2) & 1;
        double rho = (double)corner[c] - iso; /* in double: see WHY DOUBLE */
        double ax = alpha[0][x], bx = beta[0][x], ay = alpha[1][y], by = beta[1][y], az = alpha[2][z],
               bz = beta[2][z];
        /* (ax + bx s)(ay + by s)(az + bz s), expanded */
        f.d += rho * (ax * ay * az);
        f.c += rho * (bx * ay * az + ax * by * az + ax * ay * bz);
        f.b += rho * (bx * by * az + bx * ay * bz + ax * by * bz);
        f.a += rho * (bx * by * bz);
    }
    return f;
}

double iso_cell_value(const float corner[8], const double p[3])
{
    double v = 0.0;
    for (int c = 0; c < 8; c++) {
        double wx = c & 1 ? p[0] : 1.0 - p[0], wy = c & 2 ? p[1] : 1.0 - p[1], wz = c & 4 ? p[2] : 1.0 - p[2];
        v += (double)corner[c] * wx * wy * wz;
    }
    return v;
}

void iso_cell_gradient(const float corner[8], const double p[3], double grad[3])
{
    double x = p[0], y = p[1], z = p[2];
    const float *c = corner;
    grad[0] = (1 - y) * (1 - z) * ((double)c[1] - c[0]) + y * (1 - z) * ((double)c[3] - c[2]) +
              (1 - y) * z * ((double)c[5] - c[4]) + y * z * ((double)c[7] - c[6]);
    grad[1] = (1 - x) * (1 - z) * ((double)c[2] - c[0]) + x * (1 - z) * ((double)c[3] - c[1]) +
              (1 - x) * z * ((double)c[6] - c[4]) + x * z * ((double)c[7] - c[5]);
    grad[2] = (1 - x) * (1 - y) * ((double)c[4] - c[0]) + x * (1 - y) * ((double)c[5] - c[1]) +
              (1 - x) * y * ((double)c[6] - c[2]) + x * y * ((double)c[7] - c[3]);
}

/* The roots of f' = 3a s^2 + 2b s + c strictly inside (s0, s1), ascending, in
 * out[0..]; the count (0..2). The quadratic is solved without cancellation:
 * q = -(B + sign(B) sqrt(D)) / 2 never subtracts nearly equal numbers, and
 * C / q gives the small root accurately when A is tiny (where -B/2A +- ...
 * would lose it). */
static int extrema(const iso_cubic *f, double s0, double s1, double out[2])
{
    double A = 3.0 * f->a, B = 2.0 * f->b, C = f->c;
    double r[2];
    int n = 0;
    if (A == 0.0) {
        if (B != 0.0)
            r[n++] = -C / B;
    } else {
        double disc = B * B - 4.0 * A * C;
        if (disc >= 0.0) {
            double q = -0.5 * (B + copysign(sqrt(disc), B));
            if (q != 0.0) {
                r[n++] = q / A;
                r[n++] = C / q;
            } else
                r[n++] = 0.0; /* B = 0 and D = 0, so C = 0: a double root at 0 */
        }
    }
    int m = 0;
    for (int i = 0; i < n; i++)
        if (r[i] > s0 && r[i] < s1)
            out[m++] = r[i];
    if (m == 2 && out[0] > out[1]) {
        double t = out[0];
        out[0] = out[1];
        out[1] = t;
    }
    if (m == 2 && out[0] == out[1])
        m = 1;
    return m;
}

/* The root in [lo, hi] where flo and fhi differ in sign (both non-zero):
 * Illinois regula falsi (the retained end's value halved when it is kept
 * twice), with a bisection step whenever the bracket has not halved over
 * the last two steps; ends when the bracket is at most tol wide. The root is
 * then within tol of the returned value. */
static double refine(const iso_cubic *f, double lo, double flo, double hi, double fhi, double tol)
{
    int kept = 0; /* -1: lo was kept last step, +1: hi was, 0: neither yet */
    double width_before[2] = {INFINITY, INFINITY}; /* the bracket's width one and two steps ago */
    for (int step = 0; step < REFINE_MAX_STEPS && hi - lo > tol; step++) {
        double width = hi - lo, x;
        if (width > 0.5 * width_before[1])
            x = lo + 0.5 * width;
        else
            x = lo + width * (flo / (flo - fhi));
        if (!(x > lo && x < hi))
            x = lo + 0.5 * width;
        width_before[1] = width_before[0];
        width_before[0] = width;
        double fx = iso_cubic_eval(f, x);
        if (fx == 0.0)
            return x;
        if ((fx < 0.0) == (flo < 0.0)) {
            lo = x;
            flo = fx;
            if (kept == 1)
                fhi *= 0.5;
            kept = 1;
        } else {
            hi = x;
            fhi = fx;
            if (kept == -1)
                flo *= 0.5;
            kept = -1;
        }
    }
    double x = lo + (hi - lo) * (flo / (flo - fhi));
    return x > lo && x < hi ? x : 0.5 * (lo + hi);
}

/* The roots in (s0, s1] in order, at most max_roots; see iso_cell.h. On each
 * monotonic piece [lo, hi]: a root at hi when f(hi) is exactly 0, else one
 * inside when f(lo) and f(hi) are non-zero and differ in sign. f(lo) = 0
 * means lo is a root already reported (by this segment or the one before):
 * a monotonic piece holds no other. */
static int find_roots(const iso_cubic *f, double s0, double f_s0, double s1, double tol, int max_roots,
                      double *roots)
{
    if (!(s1 > s0))
        return 0;
    double split[4];
    int pieces = extrema(f, s0, s1, split);
    split[pieces++] = s1;
    int count = 0;
    double lo = s0, flo = f_s0;
    for (int i = 0; i < pieces && count < max_roots; i++) {
        double hi = split[i], fhi = iso_cubic_eval(f, hi);
        if (fhi == 0.0)
            roots[count++] = hi;
        else if (flo != 0.0 && (flo < 0.0) != (fhi < 0.0))
            roots[count++] = refine(f, lo, flo, hi, fhi, tol);
        lo = hi;
        flo = fhi;
    }
    return count;
}

bool iso_cell_root(const iso_cubic *f, double s0, double f_s0, double s1, double tol_s, double *s)
{
    return find_roots(f, s0, f_s0, s1, tol_s, 1, s) == 1;
}

int iso_cell_roots(const iso_cubic *f, double s0, double f_s0, double s1, double tol_s, double roots[3])
{
    return find_roots(f, s0, f_s0, s1, tol_s, 3, roots);
}

bool iso_cell_next_root(const iso_cubic *f, double s_after, double s1, double tol_s, double *s)
{
    /* s_after is a root: its value is 0 by definition, so the monotonic piece
     * that holds it reports nothing more (find_roots), whatever rounding put
     * at s_after */
    return find_roots(f, s_after, 0.0, s1, tol_s, 1, s) == 1;
}

bool iso_cell_root_linear(const iso_cubic *f, double s0, double f_s0, double s1, double *s)
{
    double f1 = iso_cubic_eval(f, s1);
    if (f1 == 0.0) {
        *s = s1;
        return s1 > s0;
    }
    if (f_s0 == 0.0 || (f_s0 < 0.0) == (f1 < 0.0))
        return false;
    *s = s0 + (s1 - s0) * (f_s0 / (f_s0 - f1));
    return true;
}

bool iso_cell_root_regula_falsi(const iso_cubic *f, double s0, double f_s0, double s1, int steps, double *s)
{
    double lo = s0, flo = f_s0, hi = s1, fhi = iso_cubic_eval(f, s1);
    if (fhi == 0.0) {
        *s = s1;
        return s1 > s0;
    }
    if (flo == 0.0 || (flo < 0.0) == (fhi < 0.0))
        return false;
    double x = lo + (hi - lo) * (flo / (flo - fhi));
    for (int i = 1; i < steps; i++) {
        double fx = iso_cubic_eval(f, x);
        if (fx == 0.0)
            break;
        if ((fx < 0.0) == (flo < 0.0)) {
            lo = x;
            flo = fx;
        } else {
            hi = x;
            fhi = fx;
        }
        x = lo + (hi - lo) * (flo / (flo - fhi));
    }
    *s = x;
    return true;
}

/* ---- along a whole volume -------------------------------------------------- */

bool iso_volume_first_hit(const volume *v, const macrocell_grid *grid, const double org[3], const double dir[3],
                          double t_min, double t_max, float iso, iso_method method, iso_hit *hit)
{
    iso_cell_walk w;
    if (!iso_cell_walk_begin(&w, v, grid, org, dir, t_min, t_max, iso))
        return false;
    double tol_s = ISO_CELL_TOL / w.dir_len; /* ISO_CELL_TOL cell widths, in t */
    iso_cell_candidate cand;
    while (iso_cell_walk_next(&w, &cand)) {
        double s1 = cand.tx - cand.te, s = 0.0;
        bool found = false;
        switch (method) {
        case ISO_METHOD_EXACT: found = iso_cell_root(&cand.f, 0.0, cand.f0, s1, tol_s, &s); break;
        case ISO_METHOD_LINEAR: found = iso_cell_root_linear(&cand.f, 0.0, cand.f0, s1, &s); break;
        case ISO_METHOD_REGULA_FALSI:
            found = iso_cell_root_regula_falsi(&cand.f, 0.0, cand.f0, s1, ISO_CELL_RF_STEPS, &s);
            break;
        }
        if (found) {
            hit->t = cand.te + s;
            double g[3];
            for (int a = 0; a < 3; a++) {
                hit->cell[a] = (uint32_t)cand.cell[a];
                hit->local[a] = cand.org[a] + s * w.walk.dir[a];
            }
            iso_cell_gradient(cand.corner, hit->local, g);
            for (int a = 0; a < 3; a++)
                hit->gradient[a] = g[a] / grid->spacing[a];
            return true;
        }
    }
    return false;
}
