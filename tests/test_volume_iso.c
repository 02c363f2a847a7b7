/* test_volume_iso.c - ray / trilinear-cell intersection
 * (engine/geometry/volume/iso_cell.h) on analytic fields: single cells with known
 * roots (two crossings between ends of one sign, a tangent double root,
 * three crossings), random cells against a dense brute-force search of the
 * trilinear field itself (not the cubic), and a sphere's distance field
 * sampled on a grid, traced through the whole volume: accuracy against the
 * trilinear root and no ray lost between cells.
 *
 * Errors are in cell widths along the ray. The measured errors of the three
 * methods are printed (stderr) for the speed/accuracy report. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "engine/geometry/volume/iso_cell.h"
#include "engine/geometry/volume/macrocell.h"
#include "engine/geometry/volume/volume.h"

static uint64_t rng_state;

static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double rng_unit(void) { return (double)(rng_next() >> 11) * 0x1.0p-53; }

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* ---- single cells with known roots -------------------------------------------- */

/* Corners constant along z with c000 = c110 = 1, c100 = c010 = -1: along the
 * ray x = y = s (any fixed z) the field is (2s - 1)^2, a parabola with its
 * minimum 0 at s = 1/2. */
static const float saddle[8] = {1, -1, -1, 1, 1, -1, -1, 1};

Test(volume_iso, two_crossings_inside_ends_of_one_sign)
{
    const double org[3] = {0.0, 0.0, 0.5}, dir[3] = {1.0, 1.0, 0.0};
    /* iso 1/4: (2s - 1)^2 = 1/4 at s = 1/4 and 3/4; f(0) = f(1) = 3/4 > 0 */
    iso_cubic f = iso_cell_cubic(saddle, 0.25, org, dir);
    double s;
    cr_assert(iso_cell_root(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 1e-12, &s));
    cr_assert(fabs(s - 0.25) <= 1e-12, "first root %.17g, expected 0.25", s);
    double next;
    cr_assert(iso_cell_next_root(&f, s, 1.0, 1e-12, &next));
    cr_assert(fabs(next - 0.75) <= 1e-12, "second root %.17g", next);
    cr_assert_not(iso_cell_next_root(&f, next, 1.0, 1e-12, &s), "no third");
    double roots[3];
    cr_assert_eq(iso_cell_roots(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 1e-12, roots), 2);
    /* the cheap methods see no sign change between the ends: they miss both */
    cr_assert_not(iso_cell_root_linear(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, &s));
    cr_assert_not(iso_cell_root_regula_falsi(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 8, &s));
    /* the segment's half-open end: a segment starting on the first root reports the second */
    cr_assert(iso_cell_root(&f, 0.25, 0.0, 1.0, 1e-12, &s));
    cr_assert(fabs(s - 0.75) <= 1e-12);
}

Test(volume_iso, tangent_double_root)
{
    const double org[3] = {0.0, 0.0, 0.5}, dir[3] = {1.0, 1.0, 0.0};
    /* iso 0: (2s - 1)^2 touches 0 at s = 1/2 without crossing */
    iso_cubic f = iso_cell_cubic(saddle, 0.0, org, dir);
    double s;
    cr_assert(iso_cell_root(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 1e-12, &s));
    cr_assert_eq(s, 0.5, "the extremum is the root: %.17g", s);
    cr_assert_not(iso_cell_next_root(&f, s, 1.0, 1e-12, &s), "a double root is reported once");
    cr_assert_not(iso_cell_root_linear(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, &s));
    cr_assert_not(iso_cell_root_regula_falsi(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 8, &s));
    /* the gradient vanishes there along the ray: (d/dx + d/dy) of the field is 0 */
    double g[3], p[3] = {0.5, 0.5, 0.5};
    iso_cell_gradient(saddle, p, g);
    cr_assert(fabs(g[0] + g[1]) < 1e-15);
}

Test(volume_iso, three_crossings)
{
    /* along the diagonal x = y = z = s the field is the cubic with Bernstein
     * coefficients c0, (c1 + c2 + c4)/3, (c3 + c5 + c6)/3, c7; these make it
     * 100 (s - 0.2)(s - 0.5)(s - 0.8) */
    const float corner[8] = {-8, 14, 14, -14, 14, -14, -14, 8};
    const double org[3] = {0, 0, 0}, dir[3] = {1, 1, 1};
    iso_cubic f = iso_cell_cubic(corner, 0.0, org, dir);
    cr_assert(fabs(f.a - 100.0) < 1e-12 && fabs(f.b + 150.0) < 1e-12 && fabs(f.c - 66.0) < 1e-12 &&
                  fabs(f.d + 8.0) < 1e-12,
              "cubic %g %g %g %g", f.a, f.b, f.c, f.d);
    double roots[3];
    int n = iso_cell_roots(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 1e-12, roots);
    cr_assert_eq(n, 3);
    const double expect[3] = {0.2, 0.5, 0.8};
    for (int i = 0; i < 3; i++)
        cr_assert(fabs(roots[i] - expect[i]) < 1e-11, "root %d: %.17g", i, roots[i]);
    double s;
    cr_assert(iso_cell_root(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, 1e-12, &s));
    cr_assert(fabs(s - 0.2) < 1e-11);
    /* linear interpolation sees one sign change and puts it at the middle root */
    cr_assert(iso_cell_root_linear(&f, 0.0, iso_cubic_eval(&f, 0.0), 1.0, &s));
    cr_assert(fabs(s - 0.5) < 1e-12, "linear: %.17g", s);
    /* the cubic is the trilinear field */
    for (double t = 0.0; t <= 1.0; t += 0.125) {
        double p[3] = {t, t, t};
        cr_assert(fabs(iso_cubic_eval(&f, t) - iso_cell_value(corner, p)) < 1e-12);
    }
}

Test(volume_iso, cubic_and_gradient_are_the_trilinear_field)
{
    rng_state = 3;
    for (int trial = 0; trial < 1000; trial++) {
        float corner[8];
        for (int i = 0; i < 8; i++)
            corner[i] = (float)(rng_unit() * 4000.0 - 1000.0);
        double org[3], dir[3], iso = rng_unit() * 3000.0 - 1000.0;
        for (int a = 0; a < 3; a++) {
            org[a] = rng_unit() * 1.4 - 0.2;
            dir[a] = rng_unit() * 2.0 - 1.0;
        }
        iso_cubic f = iso_cell_cubic(corner, iso, org, dir);
        for (int k = 0; k <= 4; k++) {
            double s = k * 0.25, p[3];
            for (int a = 0; a < 3; a++)
                p[a] = org[a] + s * dir[a];
            double want = iso_cell_value(corner, p) - iso;
            cr_assert(fabs(iso_cubic_eval(&f, s) - want) <= 1e-9 * 4000.0);
            /* the analytic gradient against central differences (the field is a
             * cubic along each axis-parallel line: the difference is exact to rounding) */
            double g[3];
            iso_cell_gradient(corner, p, g);
            for (int a = 0; a < 3; a++) {
                double h = 1e-4, pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]};
                pp[a] += h;
                pm[a] -= h;
                double fd = (iso_cell_value(corner, pp) - iso_cell_value(corner, pm)) / (2 * h);
                cr_assert(fabs(fd - g[a]) <= 1e-6 * 4000.0, "gradient %d: %g against %g", a, g[a], fd);
            }
        }
    }
}

/* ---- random cells against brute force ------------------------------------------- */

/* the trilinear field minus iso at org + s dir: the independent reference */
static double field_at(const float corner[8], double iso, const double org[3], const double dir[3], double s)
{
    double p[3] = {org[0] + s * dir[0], org[1] + s * dir[1], org[2] + s * dir[2]};
    return iso_cell_value(corner, p) - iso;
}

/* The first root in (0, 1] by brute force: `steps` equal steps of the field
 * until its sign changes (or it is 0), then bisection of that step to
 * 1e-15. False when no step changes sign. */
static bool brute_force_root(const float corner[8], double iso, const double org[3], const double dir[3],
                             int steps, double *root)
{
    double prev = field_at(corner, iso, org, dir, 0.0);
    for (int i = 1; i <= steps; i++) {
        double s = (double)i / steps, fs = field_at(corner, iso, org, dir, s);
        if (fs == 0.0 && prev != 0.0) {
            *root = s;
            return true;
        }
        if (prev != 0.0 && (prev < 0.0) != (fs < 0.0)) {
            double lo = (double)(i - 1) / steps, hi = s, flo = prev;
            while (hi - lo > 1e-15) {
                double mid = 0.5 * (lo + hi), fm = field_at(corner, iso, org, dir, mid);
                if (fm == 0.0)
                    break;
                if ((fm < 0.0) == (flo < 0.0)) {
                    lo = mid;
                    flo = fm;
                } else
                    hi = mid;
            }
            *root = 0.5 * (lo + hi);
            return true;
        }
        prev = fs;
    }
    return false;
}

/* a random point on the surface of the unit cube */
static void random_face_point(double p[3])
{
    int face = (int)(rng_next() % 6);
    for (int a = 0; a < 3; a++)
        p[a] = rng_unit();
    p[face / 2] = (double)(face % 2);
}

Test(volume_iso, random_cells_against_brute_force)
{
    rng_state = 11;
    const int cells = 120, steps = 1000000;
    int with_root = 0, linear_found = 0, rf_found = 0, linear_missed = 0, rf_missed = 0;
    double exact_max = 0.0, linear_max = 0.0, rf_max = 0.0;
    for (int trial = 0; trial < cells; trial++) {
        float corner[8];
        for (int i = 0; i < 8; i++)
            corner[i] = (float)(rng_unit() * 2.0 - 1.0);
        double p0[3], p1[3], dir[3];
        do {
            random_face_point(p0);
            random_face_point(p1);
            for (int a = 0; a < 3; a++)
                dir[a] = p1[a] - p0[a];
        } while (norm3(dir) < 0.2);
        const double iso = 0.0, len = norm3(dir);
        iso_cubic f = iso_cell_cubic(corner, iso, p0, dir);
        double f0 = iso_cubic_eval(&f, 0.0), s_ref = 0.0, s = 0.0;
        bool ref = brute_force_root(corner, iso, p0, dir, steps, &s_ref);
        bool exact = iso_cell_root(&f, 0.0, f0, 1.0, ISO_CELL_TOL / len, &s);
        cr_assert_eq(exact, ref, "cell %d: exact %s a root, brute force %s", trial, exact ? "finds" : "misses",
                     ref ? "finds one" : "does not");
        if (!ref)
            continue;
        with_root++;
        double err = fabs(s - s_ref) * len;
        cr_assert(err <= 1e-4, "cell %d: exact root %.17g, brute force %.17g: %g cell", trial, s, s_ref, err);
        exact_max = fmax(exact_max, err);
        if (iso_cell_root_linear(&f, 0.0, f0, 1.0, &s)) {
            linear_found++;
            linear_max = fmax(linear_max, fabs(s - s_ref) * len);
        } else
            linear_missed++;
        if (iso_cell_root_regula_falsi(&f, 0.0, f0, 1.0, ISO_CELL_RF_STEPS, &s)) {
            rf_found++;
            rf_max = fmax(rf_max, fabs(s - s_ref) * len);
        } else
            rf_missed++;
    }
    cr_assert_gt(with_root, cells / 4, "enough cells hold a root: %d", with_root);
    fprintf(stderr,
            "volume_iso random cells (%d with a root, brute force %d steps): exact max error %.3g cell; "
            "linear max %.3g cell (%d missed); regula falsi x%d max %.3g cell (%d missed)\n",
            with_root, steps, exact_max, linear_max, linear_missed, ISO_CELL_RF_STEPS, rf_max, rf_missed);
}

/* ---- a sphere through a whole volume ---------------------------------------- */

#define SPHERE_N 32
static const double sphere_c[3] = {15.3, 16.1, 15.7}; /* centre, voxel coordinates */
static const double sphere_r = 10.2;                  /* radius, voxels */

/* the distance field |p - c| - r sampled at the grid points, in a world frame
 * that is not the voxel frame */
static volume *sphere_volume(void)
{
    tess_error err = {{0}};
    volume *v = volume_create(SPHERE_N, SPHERE_N, SPHERE_N, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    float *s = volume_voxels(v);
    for (uint32_t k = 0; k < SPHERE_N; k++)
        for (uint32_t j = 0; j < SPHERE_N; j++)
            for (uint32_t i = 0; i < SPHERE_N; i++) {
                double d[3] = {i - sphere_c[0], j - sphere_c[1], k - sphere_c[2]};
                s[volume_index(v, i, j, k)] = (float)(norm3(d) - sphere_r);
            }
    cr_assert(volume_update_range(v, "sphere", &err));
    v->spacing[0] = 0.5;
    v->spacing[1] = 0.75;
    v->spacing[2] = 1.0;
    v->origin[0] = -8.0;
    v->origin[1] = 2.0;
    v->origin[2] = 100.0;
    return v;
}

/* the trilinear field of v at voxel coordinates p (inside the volume) */
static double volume_field(const volume *v, const double p[3])
{
    uint32_t c[3];
    double local[3];
    const uint32_t n[3] = {v->nx, v->ny, v->nz};
    for (int a = 0; a < 3; a++) {
        double f = floor(p[a]);
        f = f < 0 ? 0 : f > n[a] - 2.0 ? n[a] - 2.0 : f;
        c[a] = (uint32_t)f;
        local[a] = p[a] - f;
    }
    float corner[8];
    volume_cell_corners(v, c[0], c[1], c[2], corner);
    return iso_cell_value(corner, local);
}

/* The first root of the trilinear field along the voxel ray over [t0, t1] by
 * brute force: steps of `h` voxel widths, then bisection. */
static bool volume_brute_root(const volume *v, const double o[3], const double d[3], double t0, double t1, double h,
                              double *root)
{
    double len = norm3(d), dt = h / len;
    double p[3];
    for (int a = 0; a < 3; a++)
        p[a] = o[a] + t0 * d[a];
    double prev = volume_field(v, p);
    for (double t = t0 + dt; t - dt < t1; t += dt) {
        double tt = fmin(t, t1);
        for (int a = 0; a < 3; a++)
            p[a] = o[a] + tt * d[a];
        double ft = volume_field(v, p);
        if ((prev < 0.0) != (ft < 0.0)) {
            double lo = tt - dt, hi = tt, flo = prev;
            while (hi - lo > 1e-14 * fmax(1.0, fabs(hi))) {
                double mid = 0.5 * (lo + hi);
                for (int a = 0; a < 3; a++)
                    p[a] = o[a] + mid * d[a];
                double fm = volume_field(v, p);
                if ((fm < 0.0) == (flo < 0.0)) {
                    lo = mid;
                    flo = fm;
                } else
                    hi = mid;
            }
            *root = 0.5 * (lo + hi);
            return true;
        }
        prev = ft;
    }
    return false;
}

static void voxel_to_world(const volume *v, const double o_vox[3], const double d_vox[3], double o[3], double d[3])
{
    for (int a = 0; a < 3; a++) {
        o[a] = v->origin[a] + o_vox[a] * v->spacing[a];
        d[a] = d_vox[a] * v->spacing[a];
    }
}

Test(volume_iso, sphere_accuracy_against_the_trilinear_root)
{
    rng_state = 5;
    volume *v = sphere_volume();
    tess_error err = {{0}};
    macrocell_grid *g4 = macrocell_grid_create(v, 4, &err), *g1 = macrocell_grid_create(v, 1, &err);
    cr_assert(g4 && g1, "%s", err.msg);
    const iso_method methods[3] = {ISO_METHOD_EXACT, ISO_METHOD_LINEAR, ISO_METHOD_REGULA_FALSI};
    double max_err[3] = {0, 0, 0};
    const int rays = 150;
    int hits = 0;
    for (int r = 0; r < rays; r++) {
        /* from outside the volume towards a point inside the sphere */
        double o_vox[3], target[3], d_vox[3], o[3], d[3];
        double u = rng_unit() * 6.283185307179586, w = rng_unit() * 2 - 1;
        double dirs[3] = {sqrt(1 - w * w) * cos(u), sqrt(1 - w * w) * sin(u), w};
        for (int a = 0; a < 3; a++) {
            o_vox[a] = sphere_c[a] + 30.0 * dirs[a];
            target[a] = sphere_c[a] + (rng_unit() * 2 - 1) * 7.0;
            d_vox[a] = (target[a] - o_vox[a]) / 30.0;
        }
        voxel_to_world(v, o_vox, d_vox, o, d);
        double t0 = 0.0, t1 = 1e30;
        const double lo[3] = {0, 0, 0}, hi[3] = {SPHERE_N - 1, SPHERE_N - 1, SPHERE_N - 1};
        cr_assert(volume_clip_box(o_vox, d_vox, lo, hi, &t0, &t1));
        double t_ref;
        cr_assert(volume_brute_root(v, o_vox, d_vox, t0, t1, 1e-3, &t_ref), "ray %d aims inside", r);
        hits++;
        for (int m = 0; m < 3; m++) {
            iso_hit hit;
            cr_assert(iso_volume_first_hit(v, g4, o, d, 0.0, INFINITY, 0.0f, methods[m], &hit), "ray %d method %d",
                      r, m);
            double e = fabs(hit.t - t_ref) * norm3(d_vox);
            max_err[m] = fmax(max_err[m], e);
            if (m == 0) {
                cr_assert(e <= 1e-4, "ray %d: exact hit %.17g, trilinear root %.17g: %g cell", r, hit.t, t_ref, e);
                /* skipping by macrocells changes nothing: the same cells are solved */
                iso_hit all;
                cr_assert(iso_volume_first_hit(v, g1, o, d, 0.0, INFINITY, 0.0f, methods[m], &all));
                cr_assert(fabs(all.t - hit.t) <= 1e-12 * fabs(hit.t) + 1e-12);
                /* the normal: the field's gradient, along the sphere's radius */
                double p[3], nrm[3], gl = norm3(hit.gradient), dot = 0.0;
                for (int a = 0; a < 3; a++) {
                    p[a] = o_vox[a] + hit.t * d_vox[a];
                    nrm[a] = p[a] - sphere_c[a];
                }
                double nl = norm3(nrm);
                /* world gradient back to voxel units: times the spacing */
                for (int a = 0; a < 3; a++)
                    dot += hit.gradient[a] * v->spacing[a] * nrm[a];
                double gv[3] = {hit.gradient[0] * v->spacing[0], hit.gradient[1] * v->spacing[1],
                                hit.gradient[2] * v->spacing[2]};
                cr_assert(gl > 0.0);
                cr_assert(dot / (norm3(gv) * nl) > 0.995, "normal off the radius: cos %g", dot / (norm3(gv) * nl));
                for (int a = 0; a < 3; a++)
                    cr_assert(hit.local[a] >= -1e-9 && hit.local[a] <= 1 + 1e-9);
            }
        }
    }
    fprintf(stderr,
            "volume_iso sphere (%d rays, trilinear root by 1e-3-voxel steps + bisection): exact max error %.3g cell; "
            "linear %.3g; regula falsi x%d %.3g\n",
            hits, max_err[0], max_err[1], ISO_CELL_RF_STEPS, max_err[2]);
    macrocell_grid_destroy(g4);
    macrocell_grid_destroy(g1);
    volume_destroy(v);
}

/* A dense grid of parallel rays, among them rays along cell faces and edges
 * (integer and half-integer coordinates): every ray that passes the centre
 * closer than r - 0.5 voxel hits, every one farther than r + 0.5 misses, for
 * every method and with and without macrocells, and each hit lies on the
 * surface (|field| tiny). A crack between cells would lose a ray. */
Test(volume_iso, sphere_no_cracks)
{
    volume *v = sphere_volume();
    tess_error err = {{0}};
    macrocell_grid *grids[2] = {macrocell_grid_create(v, 8, &err), macrocell_grid_create(v, 1, &err)};
    cr_assert(grids[0] && grids[1], "%s", err.msg);
    const double directions[][3] = {{1, 0, 0}, {0, 0, -1}, {1, 1, 0}, {1, 1, 1}, {0.3, -0.8, 0.52}, {-1, 0.25, 0}};
    const iso_method methods[3] = {ISO_METHOD_EXACT, ISO_METHOD_LINEAR, ISO_METHOD_REGULA_FALSI};
    long checked = 0;
    double worst_field = 0.0;
    for (size_t di = 0; di < sizeof directions / sizeof directions[0]; di++) {
        double d_vox[3], dl = norm3(directions[di]);
        for (int a = 0; a < 3; a++)
            d_vox[a] = directions[di][a] / dl;
        /* two axes spanning the plane perpendicular to the ray */
        double e1[3], e2[3], helper[3] = {0.6, 0.7, 0.38};
        e1[0] = d_vox[1] * helper[2] - d_vox[2] * helper[1];
        e1[1] = d_vox[2] * helper[0] - d_vox[0] * helper[2];
        e1[2] = d_vox[0] * helper[1] - d_vox[1] * helper[0];
        double l1 = norm3(e1);
        for (int a = 0; a < 3; a++)
            e1[a] /= l1;
        e2[0] = d_vox[1] * e1[2] - d_vox[2] * e1[1];
        e2[1] = d_vox[2] * e1[0] - d_vox[0] * e1[2];
        e2[2] = d_vox[0] * e1[1] - d_vox[1] * e1[0];
        bool axis = (directions[di][0] == 0) + (directions[di][1] == 0) + (directions[di][2] == 0) == 2;
        const int grid = 96;
        for (int iy = 0; iy < grid; iy++)
            for (int ix = 0; ix < grid; ix++) {
                double o_vox[3];
                if (axis) {
                    /* along an axis: the other two coordinates on a lattice of quarter voxels,
                     * so a quarter of the rays run along cell edges and half along faces */
                    int along = directions[di][0] != 0 ? 0 : directions[di][1] != 0 ? 1 : 2;
                    int u = (along + 1) % 3, w = (along + 2) % 3;
                    o_vox[along] = sphere_c[along] - 25.0 * d_vox[along];
                    o_vox[u] = 4.0 + ix * 0.25;
                    o_vox[w] = 4.0 + iy * 0.25;
                } else {
                    double a1 = (ix - grid / 2 + 0.5) * 0.25, a2 = (iy - grid / 2 + 0.5) * 0.25;
                    for (int a = 0; a < 3; a++)
                        o_vox[a] = sphere_c[a] - 25.0 * d_vox[a] + a1 * e1[a] + a2 * e2[a];
                }
                /* distance from the centre to the ray's line */
                double rel[3] = {sphere_c[0] - o_vox[0], sphere_c[1] - o_vox[1], sphere_c[2] - o_vox[2]};
                double along_t = rel[0] * d_vox[0] + rel[1] * d_vox[1] + rel[2] * d_vox[2];
                double perp[3] = {rel[0] - along_t * d_vox[0], rel[1] - along_t * d_vox[1],
                                  rel[2] - along_t * d_vox[2]};
                double dist = norm3(perp);
                bool must_hit = dist < sphere_r - 0.5, must_miss = dist > sphere_r + 0.5;
                if (!must_hit && !must_miss)
                    continue;
                double o[3], d[3];
                voxel_to_world(v, o_vox, d_vox, o, d);
                for (int gi = 0; gi < 2; gi++)
                    for (int m = 0; m < 3; m++) {
                        iso_hit hit;
                        bool got = iso_volume_first_hit(v, grids[gi], o, d, 0.0, INFINITY, 0.0f, methods[m], &hit);
                        cr_assert_eq(got, must_hit,
                                     "direction %zu ray (%d, %d) at distance %.3f (radius %.1f), method %d, k %u: %s",
                                     di, ix, iy, dist, sphere_r, m, grids[gi]->k, got ? "hit" : "missed");
                        if (got && m == ISO_METHOD_EXACT) {
                            double p[3];
                            for (int a = 0; a < 3; a++)
                                p[a] = o_vox[a] + hit.t * d_vox[a];
                            double fv = fabs(volume_field(v, p));
                            worst_field = fmax(worst_field, fv);
                            cr_assert(fv < 1e-6, "hit off the surface: field %g", fv);
                        }
                        checked++;
                    }
            }
    }
    fprintf(stderr, "volume_iso sphere: %ld ray traces without a crack; worst |field| at an exact hit %.3g\n", checked,
            worst_field);
    macrocell_grid_destroy(grids[0]);
    macrocell_grid_destroy(grids[1]);
    volume_destroy(v);
}

/* The walk with a leap field against the walk without: the same candidate
 * cells, with the same t's, cubics and carried entry values bit for bit,
 * on a field of a few blobs in a flat background (wide runs of macrocells
 * on both sides of the value, both below and above it) at several values. */
Test(volume_iso, leaping_walk_gives_the_same_candidates)
{
    enum { N = 61 };
    rng_state = 21;
    tess_error err = {{0}};
    volume *v = volume_create(N, N - 8, N + 5, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    double centre[5][3], radius[5], sign[5];
    for (int b = 0; b < 5; b++) {
        for (int a = 0; a < 3; a++)
            centre[b][a] = 8.0 + rng_unit() * (N - 16);
        radius[b] = 3.0 + rng_unit() * 8.0;
        sign[b] = b % 2 ? -1.0 : 1.0; /* bumps and dips */
    }
    float *s = volume_voxels(v);
    for (uint32_t k = 0; k < v->nz; k++)
        for (uint32_t j = 0; j < v->ny; j++)
            for (uint32_t i = 0; i < v->nx; i++) {
                double f = 0.0;
                for (int b = 0; b < 5; b++) {
                    double d[3] = {i - centre[b][0], j - centre[b][1], k - centre[b][2]};
                    double x = 1.0 - norm3(d) / radius[b];
                    f += x > 0.0 ? sign[b] * 100.0 * x : 0.0;
                }
                s[volume_index(v, i, j, k)] = (float)f;
            }
    cr_assert(volume_update_range(v, "blobs", &err), "%s", err.msg);
    v->spacing[1] = 0.5;
    v->origin[2] = -3.0;
    const uint32_t ks[] = {2, 4};
    const float isos[] = {-50.0f, -0.5f, 0.5f, 20.0f, 70.0f};
    size_t candidates = 0, leaps_used = 0;
    for (size_t ki = 0; ki < sizeof ks / sizeof ks[0]; ki++) {
        macrocell_grid *g = macrocell_grid_create(v, ks[ki], &err);
        cr_assert_not_null(g, "%s", err.msg);
        uint8_t *leap = malloc(macrocell_count(g));
        cr_assert_not_null(leap);
        for (size_t ii = 0; ii < sizeof isos / sizeof isos[0]; ii++) {
            float iso = isos[ii];
            for (size_t m = 0; m < macrocell_count(g); m++)
                leap[m] = macrocell_may_reach(g, m, iso) ? 0 : MACROCELL_LEAP_MARK;
            macrocell_leap_build(g, leap);
            for (int r = 0; r < 400; r++) {
                double o_vox[3], d_vox[3], o[3], d[3];
                for (int a = 0; a < 3; a++) {
                    o_vox[a] = rng_unit() * (N + 20) - 10.0;
                    d_vox[a] = rng_unit() * (N - 20) + 10.0 - o_vox[a];
                }
                if (r % 5 == 0) /* along an axis, on a macrocell plane */
                    for (int a = 1; a < 3; a++) {
                        d_vox[a] = 0.0;
                        o_vox[a] = floor(o_vox[a] / ks[ki]) * ks[ki];
                    }
                voxel_to_world(v, o_vox, d_vox, o, d);
                iso_cell_walk plain, leaping;
                bool any = iso_cell_walk_begin(&plain, v, g, o, d, 0.0, INFINITY, iso);
                cr_assert_eq(iso_cell_walk_begin(&leaping, v, g, o, d, 0.0, INFINITY, iso), any);
                if (!any)
                    continue;
                leaping.leap = leap;
                iso_cell_candidate a, b;
                for (;;) {
                    bool more = iso_cell_walk_next(&plain, &a);
                    cr_assert_eq(iso_cell_walk_next(&leaping, &b), more, "ray %d: one walk ended first", r);
                    if (!more)
                        break;
                    cr_assert(a.cell[0] == b.cell[0] && a.cell[1] == b.cell[1] && a.cell[2] == b.cell[2]);
                    cr_assert(a.te == b.te && a.tx == b.tx && a.f0 == b.f0, "ray %d cell (%d %d %d)", r, a.cell[0],
                              a.cell[1], a.cell[2]);
                    cr_assert(a.f.a == b.f.a && a.f.b == b.f.b && a.f.c == b.f.c && a.f.d == b.f.d);
                    candidates++;
                }
            }
            for (size_t m = 0; m < macrocell_count(g); m++)
                leaps_used += (leap[m] & MACROCELL_LEAP_MARK) && macrocell_leap_dist(leap[m]) >= MACROCELL_LEAP_MIN;
        }
        free(leap);
        macrocell_grid_destroy(g);
    }
    cr_assert_gt(candidates, 1000u);
    cr_assert_gt(leaps_used, 100u, "the field has room to leap");
    cr_log_info("volume_iso leaping walk: %zu candidates equal", candidates);
    volume_destroy(v);
}
