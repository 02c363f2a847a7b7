/* test_dvr.c - the volume integrator (engine/geometry/volume/dvr.h) against closed
 * forms and an independent fine quadrature: a constant field for every
 * step, jitter, spacing and both paths; a linear field's convergence with
 * the step, classic against pre-integrated; empty-space skipping against
 * no skipping; early termination; jitter averaging; a ray stopped short;
 * pre-integration converging on noise below a kink. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "engine/geometry/volume/dvr.h"
#include "engine/geometry/volume/macrocell.h"
#include "engine/geometry/volume/volume.h"

TestSuite(dvr);

/* ---- helpers ---------------------------------------------------------------- */

typedef float (*field_fn)(double x, double y, double z);

/* a float32 volume of n samples per axis holding f at the sample positions
 * (voxel coordinates), with the given spacing */
static volume *make_volume(uint32_t nx, uint32_t ny, uint32_t nz, const double spacing[3], field_fn f)
{
    tess_error err = {{0}};
    volume *v = volume_create(nx, ny, nz, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    float *s = volume_voxels(v);
    for (uint32_t k = 0; k < nz; k++)
        for (uint32_t j = 0; j < ny; j++)
            for (uint32_t i = 0; i < nx; i++)
                s[volume_index(v, i, j, k)] = f(i, j, k);
    if (spacing)
        for (int a = 0; a < 3; a++)
            v->spacing[a] = spacing[a];
    cr_assert(volume_update_range(v, "test", &err), "%s", err.msg);
    return v;
}

/* a transfer function of two colours and up to four opacity points over [lo, hi] */
static colormap make_tf(const float c0[3], const float c1[3], int n_opacity, const float (*opacity)[2], float lo,
                        float hi)
{
    colormap cm;
    memset(&cm, 0, sizeof cm);
    cm.color_count = 2;
    cm.colors[0].pos = 0.0f;
    cm.colors[1].pos = 1.0f;
    memcpy(cm.colors[0].rgb, c0, sizeof cm.colors[0].rgb);
    memcpy(cm.colors[1].rgb, c1, sizeof cm.colors[1].rgb);
    cm.opacity_count = (uint32_t)n_opacity;
    for (int i = 0; i < n_opacity; i++)
        cm.opacity[i] = (colormap_opacity_point){opacity[i][0], opacity[i][1]};
    cm.lo = lo;
    cm.hi = hi;
    cm.range_auto = false;
    tess_error err = {{0}};
    cr_assert(colormap_validate(&cm, &err), "%s", err.msg);
    return cm;
}

static dvr_volume *make_dvr(const volume *v, const colormap *tf, double step, bool pre, bool skip, float min_t)
{
    dvr_settings s = dvr_settings_default();
    s.step_vox = step;
    s.preintegrate = pre;
    s.skip_empty = skip;
    s.min_transmittance = min_t;
    tess_error err = {{0}};
    dvr_volume *d = dvr_create(v, NULL, tf, &s, &err);
    cr_assert_not_null(d, "%s", err.msg);
    return d;
}

/* The independent reference: the emission-absorption integral along a path
 * of `length` voxels on which the value is s0 + slope * x (x in voxels from
 * the start), by the midpoint rule over `n` equal pieces with the exact
 * colormap_eval; second order, so n = 2^16 over 64 voxels is good to ~1e-8. */
static void reference(const colormap *tf, double s0, double slope, double length, int n, double rgb[3], double *T)
{
    double h = length / n, t = 1.0;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int i = 0; i < n; i++) {
        colormap_rgba e = colormap_eval(tf, (float)(s0 + slope * (i + 0.5) * h));
        double alpha = 1.0 - pow(1.0 - e.a, h);
        rgb[0] += t * alpha * e.r;
        rgb[1] += t * alpha * e.g;
        rgb[2] += t * alpha * e.b;
        t *= 1.0 - alpha;
    }
    *T = t;
}

/* largest difference over the colour channels and T */
static double diff4(const float rgb[3], float T, const double ref_rgb[3], double ref_T)
{
    double e = fabs(T - ref_T);
    for (int c = 0; c < 3; c++)
        e = fmax(e, fabs(rgb[c] - ref_rgb[c]));
    return e;
}

static const float red[3] = {0.9f, 0.1f, 0.05f}, blue[3] = {0.05f, 0.2f, 0.8f};

/* ---- constant field ------------------------------------------------------------ */

static float constant_5(double x, double y, double z)
{
    (void)x, (void)y, (void)z;
    return 5.0f;
}

/* T = (1 - a)^(length / voxel), colour = c (1 - T), for any step, jitter,
 * path and spacing, classic and pre-integrated */
Test(dvr, constant_field_matches_closed_form)
{
    const double spacings[][3] = {{1, 1, 1}, {2.0, 1.0, 0.5}};
    const float opacity[][2] = {{0.0f, 0.08f}, {1.0f, 0.08f}};
    colormap tf = make_tf(red, red, 2, opacity, 0.0f, 10.0f);
    const double steps[] = {1.0, 0.5, 0.3, 0.137, 2.5};
    const double jitters[] = {0.0, 0.37, 0.9};
    for (size_t sp = 0; sp < 2; sp++) {
        volume *v = make_volume(17, 9, 12, spacings[sp], constant_5);
        double voxel = fmin(spacings[sp][0], fmin(spacings[sp][1], spacings[sp][2]));
        /* world box: [0, 16 sx] x [0, 8 sy] x [0, 11 sz] */
        const double rays[][6] = {
            {-3.0, 3.3, 2.1, 1.0, 0.0, 0.0},     /* along x */
            {-1.0, -2.0, -0.5, 0.9, 0.45, 0.3},  /* oblique */
            {40.0, 9.5, 6.0, -3.0, -0.2, -0.1},  /* oblique, long dir */
        };
        for (size_t ri = 0; ri < 3; ri++)
            for (int pre = 0; pre < 2; pre++)
                for (size_t si = 0; si < 5; si++)
                    for (size_t ji = 0; ji < 3; ji++) {
                        dvr_volume *d = make_dvr(v, &tf, steps[si], pre, true, 0.0f);
                        const double *org = rays[ri], *dir = rays[ri] + 3;
                        float rgb[3], T;
                        cr_assert(dvr_integrate(d, org, dir, 0.0, 1e9, jitters[ji], rgb, &T));
                        /* the closed form from the world length inside the box */
                        double ov[3], dv[3], t0 = 0.0, t1 = 1e9;
                        volume_ray_to_voxel(v->origin, v->spacing, org, dir, ov, dv);
                        const double lo[3] = {0, 0, 0}, hi[3] = {16, 8, 11};
                        cr_assert(volume_clip_box(ov, dv, lo, hi, &t0, &t1));
                        double len = (t1 - t0) * sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
                        double want_T = pow(1.0 - 0.08, len / voxel);
                        colormap_rgba c = colormap_eval(&tf, 5.0f);
                        const double want_rgb[3] = {c.r * (1.0 - want_T), c.g * (1.0 - want_T),
                                                    c.b * (1.0 - want_T)};
                        double e = diff4(rgb, T, want_rgb, want_T);
                        cr_assert(e < 2e-6, "spacing %zu ray %zu pre %d step %g jitter %g: T %.8f want %.8f (error %g)",
                                  sp, ri, pre, steps[si], jitters[ji], (double)T, want_T, e);
                        dvr_destroy(d);
                    }
        volume_destroy(v);
    }
}

/* ---- noise at a kink ------------------------------------------------------------- */

/* values 366 .. 389 (a hash of the sample), as scanner noise in air is:
 * just below the kink where the opacity ramp below starts (389.1) */
static float noise_field(double x, double y, double z)
{
    uint32_t h = (uint32_t)x * 73856093u ^ (uint32_t)y * 19349663u ^ (uint32_t)z * 83492791u;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return (float)(366 + h % 24);
}

/* Pre-integration converges to the classic integral as the step shrinks
 * on noise just below a kink of the transfer function, as the CT bunny's
 * air sits at the foot of ct-bone's opacity ramp: both paths at step 1/16
 * against classic at 1/64, over 64 rays 60 voxels long. The noise is
 * transparent (T stays 1); a pre-integration table coarser than the
 * classic one (256 entries, 4 units each here) blurred the kink onto it
 * and made it a haze (T 0.96 on the CT's air, a FLIP of 0.045). */
static const float kink_opacity[][2] = {{0.0f, 0.0f}, {0.38f, 0.0f}, {0.62f, 0.5f}, {1.0f, 0.5f}};

Test(dvr, preintegration_converges_below_a_kink)
{
    volume *v = make_volume(64, 12, 12, NULL, noise_field);
    const colormap tf = make_tf(blue, red, 4, kink_opacity, 0.0f, 1024.0f);
    dvr_volume *ref = make_dvr(v, &tf, 1.0 / 64, false, false, 0.0f);
    dvr_volume *paths[2] = {make_dvr(v, &tf, 1.0 / 16, false, false, 0.0f),
                            make_dvr(v, &tf, 1.0 / 16, true, false, 0.0f)};
    double worst[2] = {0.0, 0.0};
    for (int r = 0; r < 64; r++) {
        const double org[3] = {-1.0, 2.0 + 1.0 * (r % 8), 2.0 + 1.0 * (r / 8)};
        const double dir[3] = {1.0, 0.01 * (r % 5), 0.01 * (r % 7)};
        float ref_rgb[3], ref_T;
        cr_assert(dvr_integrate(ref, org, dir, 0.0, INFINITY, 0.0, ref_rgb, &ref_T));
        const double want[3] = {ref_rgb[0], ref_rgb[1], ref_rgb[2]};
        for (int p = 0; p < 2; p++) {
            float rgb[3], T;
            cr_assert(dvr_integrate(paths[p], org, dir, 0.0, INFINITY, 0.0, rgb, &T));
            worst[p] = fmax(worst[p], diff4(rgb, T, want, ref_T));
        }
    }
    printf("dvr noise below a kink, step 1/16 against classic 1/64, worst of 64 rays: classic %.2e, "
           "pre-integrated %.2e\n",
           worst[0], worst[1]);
    cr_assert(worst[0] < 1e-3, "classic %g", worst[0]);
    cr_assert(worst[1] < 1e-3, "pre-integrated %g", worst[1]);
    for (int p = 0; p < 2; p++)
        dvr_destroy(paths[p]);
    dvr_destroy(ref);
    volume_destroy(v);
}

/* ---- linear field --------------------------------------------------------------- */

/* 16 value units per voxel along x: 0 .. 1024 over the 65 samples */
static float ramp_x(double x, double y, double z)
{
    (void)y, (void)z;
    return (float)(16.0 * x);
}

/* the error of one integration along x through ramp_x, against the
 * reference on the same path */
static double ramp_error(const volume *v, const colormap *tf, double step, bool pre, double jitter, double t1,
                         float out_rgb[3], float *out_T)
{
    dvr_volume *d = make_dvr(v, tf, step, pre, false, 0.0f);
    const double org[3] = {-2.0, 1.5, 1.5}, dir[3] = {1.0, 0.0, 0.0};
    float rgb[3], T;
    cr_assert(dvr_integrate(d, org, dir, 0.0, t1, jitter, rgb, &T));
    dvr_destroy(d);
    double ref_rgb[3], ref_T;
    double end = fmin(t1 - 2.0, 64.0);
    reference(tf, 0.0, 16.0, end, 1 << 16, ref_rgb, &ref_T);
    if (out_rgb) {
        memcpy(out_rgb, rgb, sizeof rgb);
        *out_T = T;
    }
    return diff4(rgb, T, ref_rgb, ref_T);
}

/* a gentle ramp over the whole range, and a steep one (0 to 0.4 over 2
 * voxels of the field, then constant) that a step of one voxel undersamples */
static const float gentle_opacity[][2] = {{0.0f, 0.0f}, {1.0f, 0.15f}};
static const float steep_opacity[][2] = {{0.0f, 0.0f}, {0.5f, 0.0f}, {0.53f, 0.4f}, {1.0f, 0.4f}};
/* a thin sheet: up and down again within 0.02 of the range (1.3 voxels of
 * the field), which a step of one voxel samples at one or two points */
static const float tent_opacity[][2] = {{0.0f, 0.0f}, {0.5f, 0.0f}, {0.51f, 0.15f}, {0.52f, 0.0f}};

Test(dvr, linear_field_converges_and_preintegration_helps)
{
    volume *v = make_volume(65, 4, 4, NULL, ramp_x);
    const colormap tfs[3] = {make_tf(blue, red, 2, gentle_opacity, 0.0f, 1024.0f),
                             make_tf(blue, red, 4, steep_opacity, 0.0f, 1024.0f),
                             make_tf(blue, red, 4, tent_opacity, 0.0f, 1024.0f)};
    const char *names[3] = {"gentle ramp", "steep ramp", "thin sheet"};
    const double steps[] = {2.0, 1.0, 0.5, 0.25, 1.0 / 16, 1.0 / 64};
    double err[3][2][6];
    for (int f = 0; f < 3; f++)
        for (int pre = 0; pre < 2; pre++) {
            printf("dvr linear field, %s, %s:", names[f], pre ? "pre-integrated" : "classic");
            for (int s = 0; s < 6; s++) {
                err[f][pre][s] = ramp_error(v, &tfs[f], steps[s], pre, 0.0, 1e9, NULL, NULL);
                printf("  %g: %.2e", steps[s], err[f][pre][s]);
            }
            printf("\n");
        }
    for (int f = 0; f < 3; f++)
        for (int pre = 0; pre < 2; pre++)
            cr_assert(err[f][pre][5] < 5e-4, "%s, pre %d: error at step 1/64 is %g", names[f], pre, err[f][pre][5]);
    /* the gentle ramp is nearly linear in the extinction, which the midpoint
     * rule integrates exactly: its error is the tables' floor at any step.
     * The steep ramp's and the sheet's classic errors fall with the step
     * down to that floor */
    for (int f = 1; f < 3; f++) {
        cr_assert(err[f][0][3] < err[f][0][1] / 4.0, "%s: classic error at 1/4 %g vs 1 %g", names[f], err[f][0][3],
                  err[f][0][1]);
        cr_assert(err[f][0][5] < err[f][0][0] / 10.0, "%s: classic error at 1/64 %g vs 2 %g", names[f],
                  err[f][0][5], err[f][0][0]);
    }
    /* the sheet at one voxel: pre-integration far better */
    cr_assert(err[2][1][1] < err[2][0][1] / 10.0, "sheet at step 1: pre-integrated %g, classic %g", err[2][1][1],
              err[2][0][1]);
    volume_destroy(v);
}

/* ---- empty-space skipping --------------------------------------------------------- */

/* a ball of high values (up to 100 at the centre) in empty space, with a
 * second small one off to the side */
static float balls(double x, double y, double z)
{
    double r1 = sqrt((x - 20) * (x - 20) + (y - 24) * (y - 24) + (z - 30) * (z - 30));
    double r2 = sqrt((x - 48) * (x - 48) + (y - 40) * (y - 40) + (z - 12) * (z - 12));
    return (float)fmax(0.0, fmax(100.0 - 6.0 * r1, 60.0 - 12.0 * r2));
}

/* a 2-sphere direction and an origin outside the 64^3 box, from a counter */
static void test_ray(int i, double org[3], double dir[3])
{
    double u = fmod(i * 0.6180339887, 1.0), w = fmod(i * 0.7548776662 + 0.3, 1.0);
    double phi = 6.283185307179586 * u, ct = 2.0 * w - 1.0, st = sqrt(1.0 - ct * ct);
    double dd[3] = {st * cos(phi), st * sin(phi), ct};
    /* aim at a point of the box, start 100 back */
    double target[3] = {8.0 + fmod(i * 13.7, 48.0), 8.0 + fmod(i * 29.3, 48.0), 8.0 + fmod(i * 7.1, 48.0)};
    for (int a = 0; a < 3; a++) {
        dir[a] = dd[a] * (1.0 + (i % 3)); /* any length */
        org[a] = target[a] - 100.0 * dd[a];
    }
}

Test(dvr, empty_space_skipping_changes_nothing_but_the_work)
{
    volume *v = make_volume(64, 64, 64, NULL, balls);
    const float opacity_a[][2] = {{0.0f, 0.0f}, {0.3f, 0.0f}, {0.6f, 0.2f}, {1.0f, 0.5f}};
    const float opacity_b[][2] = {{0.0f, 0.0f}, {0.45f, 0.0f}, {0.55f, 0.9f}, {1.0f, 0.9f}};
    colormap tfs[2] = {make_tf(blue, red, 4, opacity_a, 0.0f, 100.0f), make_tf(red, blue, 4, opacity_b, 0.0f, 100.0f)};
    for (int pre = 0; pre < 2; pre++) {
        dvr_volume *skip = make_dvr(v, &tfs[0], 0.5, pre, true, 1.0f / 255.0f);
        dvr_volume *all = make_dvr(v, &tfs[0], 0.5, pre, false, 1.0f / 255.0f);
        for (int f = 0; f < 2; f++) {
            /* the same dvr_volume with a new transfer function: the
             * macrocells' opacities must follow */
            dvr_set_transfer(skip, &tfs[f]);
            dvr_set_transfer(all, &tfs[f]);
            dvr_stats st_skip = {0}, st_all = {0};
            double worst = 0.0;
            int hits = 0;
            for (int i = 0; i < 400; i++) {
                double org[3], dir[3];
                test_ray(i, org, dir);
                double jitter = fmod(i * 0.381966, 1.0);
                float a_rgb[3], a_T, b_rgb[3], b_T;
                bool ha = dvr_integrate_stats(skip, org, dir, 0.0, 1e9, jitter, a_rgb, &a_T, &st_skip);
                bool hb = dvr_integrate_stats(all, org, dir, 0.0, 1e9, jitter, b_rgb, &b_T, &st_all);
                cr_assert_eq(ha, hb);
                const double b_ref[3] = {b_rgb[0], b_rgb[1], b_rgb[2]};
                worst = fmax(worst, diff4(a_rgb, a_T, b_ref, b_T));
                hits += b_T < 0.999f;
            }
            printf("dvr skipping, tf %d, %s: %d of 400 rays see something; samples %llu skipping, %llu not "
                   "(%llu spans skipped); largest difference %.2e\n",
                   f, pre ? "pre-integrated" : "classic", hits, (unsigned long long)st_skip.samples,
                   (unsigned long long)st_all.samples, (unsigned long long)st_skip.spans_skipped, worst);
            cr_assert(hits > 20, "the test rays must see the balls");
            cr_assert(worst <= 1e-6, "skipping changed a result by %g", worst);
            cr_assert(st_skip.samples * 2 < st_all.samples, "skipping took %llu samples, no skipping %llu",
                      (unsigned long long)st_skip.samples, (unsigned long long)st_all.samples);
        }
        dvr_destroy(skip);
        dvr_destroy(all);
    }
    volume_destroy(v);
}

/* ---- early termination -------------------------------------------------------------- */

/* an opaque wall (value 100) for x in [20, 24], nothing (0) elsewhere */
static float wall(double x, double y, double z)
{
    (void)y, (void)z;
    return x >= 20.0 && x <= 24.0 ? 100.0f : 0.0f;
}

Test(dvr, early_termination_stops_at_an_opaque_slab)
{
    volume *v = make_volume(64, 8, 8, NULL, wall);
    const float opacity[][2] = {{0.0f, 0.0f}, {0.5f, 0.0f}, {1.0f, 1.0f}};
    colormap tf = make_tf(red, red, 3, opacity, 0.0f, 100.0f);
    const double org[3] = {-5.0, 3.5, 3.5}, dir[3] = {1.0, 0.0, 0.0};
    for (int pre = 0; pre < 2; pre++)
        for (int skip = 0; skip < 2; skip++) {
            dvr_volume *d = make_dvr(v, &tf, 0.25, pre, skip, 1.0f / 255.0f);
            dvr_stats st = {0};
            float rgb[3], T;
            cr_assert(dvr_integrate_stats(d, org, dir, 0.0, 1e9, 0.5, rgb, &T, &st));
            /* without termination: 63 / 0.25 = 252 slabs; the wall begins
             * about 19.5 voxels in (where the field rises), and is opaque
             * within a voxel */
            uint64_t bound = (uint64_t)(21.0 / 0.25) * (pre ? 2u : 1u);
            printf("dvr early termination, %s, skip %d: %llu samples, %llu slabs, T %.2e\n",
                   pre ? "pre-integrated" : "classic", skip, (unsigned long long)st.samples,
                   (unsigned long long)st.slabs, (double)T);
            cr_assert_eq(st.terminated, 1);
            cr_assert(T < 1.0f / 255.0f && T >= 0.0f);
            cr_assert(st.samples <= bound, "%llu samples", (unsigned long long)st.samples);
            /* an opaque wall stays the wall's colour */
            cr_assert(fabsf(rgb[0] - red[0] * (1.0f - T)) < 1e-5f);
            dvr_destroy(d);
        }
    volume_destroy(v);
}

/* ---- jitter ------------------------------------------------------------------------------ */

/* A thin sheet: the field crosses a narrow opacity peak (about 1.3 voxels
 * wide) once. A step of 2 voxels with one offset errs by where its samples
 * fall on the peak; the mean over many offsets approaches the reference (what
 * a renderer averaging jittered frames sees). Not exactly: the mean of the
 * transmittance exp(-tau) over offsets exceeds exp(-mean tau) (Jensen),
 * while the optical depth tau itself is unbiased; a thin sheet keeps that
 * bias small. */

Test(dvr, jitter_average_converges_to_the_reference)
{
    volume *v = make_volume(65, 4, 4, NULL, ramp_x);
    colormap tf = make_tf(blue, red, 4, tent_opacity, 0.0f, 1024.0f);
    const double org[3] = {-2.0, 1.5, 1.5}, dir[3] = {1.0, 0.0, 0.0};
    double ref_rgb[3], ref_T;
    reference(&tf, 0.0, 16.0, 64.0, 1 << 16, ref_rgb, &ref_T);
    const double steps[] = {2.0, 1.0};
    for (int si = 0; si < 2; si++) {
        dvr_volume *d = make_dvr(v, &tf, steps[si], false, true, 0.0f);
        const int n = 256;
        double mean_rgb[3] = {0, 0, 0}, mean_T = 0.0, worst_single = 0.0;
        for (int i = 0; i < n; i++) {
            float rgb[3], T;
            cr_assert(dvr_integrate(d, org, dir, 0.0, 1e9, (i + 0.5) / n, rgb, &T));
            worst_single = fmax(worst_single, diff4(rgb, T, ref_rgb, ref_T));
            for (int c = 0; c < 3; c++)
                mean_rgb[c] += rgb[c] / n;
            mean_T += T / n;
        }
        const float mean_f[3] = {(float)mean_rgb[0], (float)mean_rgb[1], (float)mean_rgb[2]};
        double mean_err = diff4(mean_f, (float)mean_T, ref_rgb, ref_T);
        printf("dvr jitter, thin sheet (reference T %.4f), step %g: worst single offset %.2e, mean of %d offsets "
               "%.2e\n",
               ref_T, steps[si], worst_single, n, mean_err);
        cr_assert(mean_err < worst_single / 10.0, "mean %g, worst single %g", mean_err, worst_single);
        cr_assert(mean_err < 1e-2, "mean %g", mean_err);
        dvr_destroy(d);
    }
    volume_destroy(v);
}

/* ---- stopping short ----------------------------------------------------------------------- */

/* t1 inside the volume (a surface in front of its back): the result is the
 * integral of the shorter path, and front + T_front * back = the whole. */
Test(dvr, t1_before_the_back_integrates_the_shorter_segment)
{
    volume *v = make_volume(65, 4, 4, NULL, ramp_x);
    colormap tf = make_tf(blue, red, 2, gentle_opacity, 0.0f, 1024.0f);
    const double org[3] = {-2.0, 1.5, 1.5}, dir[3] = {1.0, 0.0, 0.0};
    for (int pre = 0; pre < 2; pre++) {
        /* ray t = 2 is the box's front (x = 0); stop at x = 37.3 */
        double t1 = 2.0 + 37.3;
        float front_rgb[3], front_T;
        double e = ramp_error(v, &tf, 1.0 / 16, pre, 0.0, t1, front_rgb, &front_T);
        cr_assert(e < 1e-3, "%s: stopped ray off the short reference by %g", pre ? "pre" : "classic", e);
        dvr_volume *d = make_dvr(v, &tf, 1.0 / 16, pre, true, 0.0f);
        float back_rgb[3], back_T, all_rgb[3], all_T;
        cr_assert(dvr_integrate(d, org, dir, t1, 1e9, 0.0, back_rgb, &back_T));
        cr_assert(dvr_integrate(d, org, dir, 0.0, 1e9, 0.0, all_rgb, &all_T));
        const double joined[3] = {front_rgb[0] + front_T * back_rgb[0], front_rgb[1] + front_T * back_rgb[1],
                                  front_rgb[2] + front_T * back_rgb[2]};
        double j = diff4(all_rgb, all_T, joined, (double)front_T * back_T);
        cr_assert(j < 1e-3, "front + back differs from the whole by %g", j);
        /* a surface in front of the volume: nothing */
        float rgb[3], T;
        cr_assert_not(dvr_integrate(d, org, dir, 0.0, 1.5, 0.0, rgb, &T));
        cr_assert(T == 1.0f && rgb[0] == 0.0f);
        dvr_destroy(d);
    }
    /* the constant field: exact for the shorter length */
    volume *c = make_volume(17, 9, 12, NULL, constant_5);
    const float opacity[][2] = {{0.0f, 0.2f}, {1.0f, 0.2f}};
    colormap ctf = make_tf(red, red, 2, opacity, 0.0f, 10.0f);
    dvr_volume *d = make_dvr(c, &ctf, 0.5, true, true, 0.0f);
    float rgb[3], T;
    cr_assert(dvr_integrate(d, org, dir, 0.0, 2.0 + 7.77, 0.3, rgb, &T));
    cr_assert(fabs(T - pow(0.8, 7.77)) < 1e-6, "T %g want %g", (double)T, pow(0.8, 7.77));
    dvr_destroy(d);
    volume_destroy(c);
    volume_destroy(v);
}

/* rays that miss, go nowhere or are NaN touch nothing */
Test(dvr, misses_and_bad_rays)
{
    volume *v = make_volume(9, 9, 9, NULL, constant_5);
    const float opacity[][2] = {{0.0f, 0.2f}, {1.0f, 0.2f}};
    colormap tf = make_tf(red, red, 2, opacity, 0.0f, 10.0f);
    dvr_volume *d = make_dvr(v, &tf, 0.5, false, true, 0.0f);
    float rgb[3], T;
    const double org[3] = {-1.0, 20.0, 4.0}, along[3] = {1.0, 0.0, 0.0}, zero[3] = {0, 0, 0},
                 nan_dir[3] = {NAN, 1.0, 0.0};
    cr_assert_not(dvr_integrate(d, org, along, 0.0, 1e9, 0.0, rgb, &T));
    cr_assert_not(dvr_integrate(d, org, zero, 0.0, 1e9, 0.0, rgb, &T));
    cr_assert_not(dvr_integrate(d, org, nan_dir, 0.0, 1e9, 0.0, rgb, &T));
    cr_assert(T == 1.0f && rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 0.0f);
    /* infinite ends are clipped to the box */
    const double inside[3] = {4.0, 4.0, 4.0};
    cr_assert(dvr_integrate(d, inside, along, -INFINITY, INFINITY, 0.0, rgb, &T));
    cr_assert(fabs(T - pow(0.8, 8.0)) < 1e-6, "T %g", (double)T);
    dvr_settings s = dvr_settings_default();
    tess_error err = {{0}};
    /* a grid of another volume is refused */
    volume *other = make_volume(9, 9, 10, NULL, constant_5);
    macrocell_grid *g = macrocell_grid_create(other, 4, &err);
    cr_assert_not_null(g, "%s", err.msg);
    cr_assert_null(dvr_create(v, g, &tf, NULL, &err));
    cr_assert(strstr(err.msg, "another volume") != NULL, "%s", err.msg);
    macrocell_grid_destroy(g);
    volume_destroy(other);
    err = (tess_error){{0}};
    s.step_vox = 0.0;
    cr_assert_not(dvr_set_settings(d, &s, &err));
    cr_assert(strstr(err.msg, "step") != NULL, "%s", err.msg);
    dvr_destroy(d);
    volume_destroy(v);
}

/* changing the settings or the transfer function afterwards gives what a
 * renderer made with them gives (the tables follow) */
Test(dvr, later_settings_and_transfer_match_fresh_ones)
{
    volume *v = make_volume(64, 64, 64, NULL, balls);
    const float opacity_a[][2] = {{0.0f, 0.0f}, {0.3f, 0.0f}, {0.6f, 0.2f}, {1.0f, 0.5f}};
    const float opacity_b[][2] = {{0.0f, 0.0f}, {0.45f, 0.0f}, {0.55f, 0.9f}, {1.0f, 0.9f}};
    colormap tf_a = make_tf(blue, red, 4, opacity_a, 0.0f, 100.0f);
    colormap tf_b = make_tf(red, blue, 4, opacity_b, 0.0f, 100.0f);
    dvr_volume *changed = make_dvr(v, &tf_a, 0.5, false, true, 1.0f / 255.0f);
    const struct {
        double step;
        bool pre;
        const colormap *tf;
    } cases[] = {
        {1.0, false, &tf_a}, {1.0, true, &tf_a}, {0.25, true, &tf_b}, {0.25, false, &tf_b}, {0.7, true, &tf_a},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        dvr_settings s = changed->settings;
        s.step_vox = cases[c].step;
        s.preintegrate = cases[c].pre;
        tess_error err = {{0}};
        cr_assert(dvr_set_settings(changed, &s, &err), "%s", err.msg);
        dvr_set_transfer(changed, cases[c].tf);
        dvr_volume *fresh = make_dvr(v, cases[c].tf, cases[c].step, cases[c].pre, true, 1.0f / 255.0f);
        for (int i = 0; i < 100; i++) {
            double org[3], dir[3];
            test_ray(i, org, dir);
            float a_rgb[3], a_T, b_rgb[3], b_T;
            dvr_integrate(changed, org, dir, 0.0, 1e9, 0.25, a_rgb, &a_T);
            dvr_integrate(fresh, org, dir, 0.0, 1e9, 0.25, b_rgb, &b_T);
            cr_assert(a_T == b_T && a_rgb[0] == b_rgb[0] && a_rgb[1] == b_rgb[1] && a_rgb[2] == b_rgb[2],
                      "case %zu ray %d: T %g vs %g", c, i, (double)a_T, (double)b_T);
        }
        dvr_destroy(fresh);
    }
    dvr_destroy(changed);
    volume_destroy(v);
}

/* ---- sample types ---------------------------------------------------------------- */

/* integer noise in [0, 200]: the same values fit every sample type exactly */
static float noise_200(double x, double y, double z)
{
    uint32_t h = (uint32_t)x * 73856093u ^ (uint32_t)y * 19349663u ^ (uint32_t)z * 83492791u;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return (float)(h % 201u);
}

/* The sampler is specialised per sample type (dvr.c): the same values as
 * uint8, int16, uint16 and float32 give bitwise the same integral, classic
 * and pre-integrated, through the interior and across the box's faces. */
Test(dvr, every_sample_type_integrates_alike)
{
    const float opacity[][2] = {{0.0f, 0.0f}, {0.3f, 0.02f}, {0.7f, 0.3f}, {1.0f, 0.05f}};
    colormap tf = make_tf(red, blue, 4, opacity, 0.0f, 200.0f);
    volume *ref = make_volume(23, 19, 17, NULL, noise_200);
    const volume_type types[] = {VOLUME_UINT8, VOLUME_INT16, VOLUME_UINT16};
    const double rays[][6] = {
        {-2.0, 3.3, 2.1, 1.0, 0.21, 0.13}, {11.2, -4.0, 30.0, -0.1, 0.3, -1.0}, {22.0, 18.0, 16.0, -1.0, -0.9, -0.8},
        {0.0, 0.0, 0.0, 1.0, 1.0, 1.0}, /* along the box's diagonal, starting on its corner */
    };
    for (int pre = 0; pre < 2; pre++) {
        dvr_volume *dref = make_dvr(ref, &tf, 0.37, pre, true, 0.0f);
        for (size_t t = 0; t < 3; t++) {
            tess_error err = {{0}};
            volume *v = volume_create(23, 19, 17, types[t], &err);
            cr_assert_not_null(v, "%s", err.msg);
            void *s = volume_voxels(v);
            const float *src = ref->data;
            for (size_t i = 0; i < volume_count(v); i++) {
                if (types[t] == VOLUME_UINT8)
                    ((uint8_t *)s)[i] = (uint8_t)src[i];
                else if (types[t] == VOLUME_INT16)
                    ((int16_t *)s)[i] = (int16_t)src[i];
                else
                    ((uint16_t *)s)[i] = (uint16_t)src[i];
            }
            cr_assert(volume_update_range(v, "test", &err), "%s", err.msg);
            dvr_volume *d = make_dvr(v, &tf, 0.37, pre, true, 0.0f);
            for (size_t r = 0; r < sizeof rays / sizeof rays[0]; r++) {
                float rgb0[3], rgb1[3], T0, T1;
                bool hit0 = dvr_integrate(dref, rays[r], rays[r] + 3, 0.0, INFINITY, 0.25, rgb0, &T0);
                bool hit1 = dvr_integrate(d, rays[r], rays[r] + 3, 0.0, INFINITY, 0.25, rgb1, &T1);
                cr_assert(hit0 && hit1, "ray %zu misses", r);
                cr_assert(T0 < 0.99f, "ray %zu sees nothing (T %g)", r, (double)T0);
                cr_assert(memcmp(rgb0, rgb1, sizeof rgb0) == 0 && T0 == T1,
                          "%s, %s, ray %zu: float32 %.9g %.9g %.9g T %.9g, other %.9g %.9g %.9g T %.9g",
                          volume_type_name(types[t]), pre ? "pre-integrated" : "classic", r, (double)rgb0[0],
                          (double)rgb0[1], (double)rgb0[2], (double)T0, (double)rgb1[0], (double)rgb1[1],
                          (double)rgb1[2], (double)T1);
            }
            dvr_destroy(d);
            volume_destroy(v);
        }
        dvr_destroy(dref);
    }
    volume_destroy(ref);
}
