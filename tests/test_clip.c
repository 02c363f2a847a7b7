/* test_clip.c - cutting planes (engine/accel/clip.h) and closed parts.
 *
 * Clipping: analytic cases against the EXACTNESS rule of clip.h (t_far is the
 * largest float not above the crossing, t_near the largest float below it),
 * checked where the answer is decidable exactly: axis-aligned planes with
 * float data small enough that t * dir and the plane offset are exact in
 * double, so the kept side of every float t is known without rounding. On
 * such data the double crossing tc cannot round onto the wrong side of a
 * float (|t - num / denom| is at least 2^-44 |t| unless zero, far above
 * double's 2^-53), so the check is equality, no tolerance. Random general
 * planes are checked in long double with a tolerance of a few double ulps of
 * the magnitudes (the one rounding clip.h allows).
 *
 * Closed parts: the edge-parity rule of geometry_triangles_ops' `closed` on
 * cubes whole, split, open and doubled, the spheres' and a kind without the
 * operation, the scene's cache, and the parts of tests/data/assembly-small.glb
 * (tools/gen_assembly: every mesh a closed solid). Runs from tests/. */
#include <criterion/criterion.h>

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/accel/clip.h"
#include "engine/accel/geometry.h"
#include "engine/accel/intersect.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"

TestSuite(clip);

/* ---- helpers -------------------------------------------------------------- */

static uint64_t rng_state = 0x9e3779b97f4a7c15u;

/* splitmix64: a fixed sequence, so every run checks the same cases */
static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}

/* uniform in [lo, hi) */
static double rng_range(double lo, double hi) { return lo + (hi - lo) * (double)(rng_next() >> 11) * 0x1p-53; }

/* an integer in [-limit, limit] divided by 1024: exact in float and double */
static float rng_grid(int32_t limit)
{
    int32_t k = (int32_t)(rng_next() % (uint64_t)(2 * limit + 1)) - limit;
    return (float)k / 1024.f;
}

static clip_set one_plane(vec3 point, vec3 normal)
{
    clip_plane planes[CLIP_MAX_PLANES] = {{.point = point, .normal = normal, .on = true}};
    clip_set c;
    clip_set_make(&c, planes);
    cr_assert_eq(c.count, 1u);
    return c;
}

static ray make_ray(vec3 org, vec3 dir) { return (ray){org, dir, 0.f, INFINITY}; }

/* Exact side of org + t dir against plane z = pz removing z > pz (normal +z)
 * or z < pz (normal -z): with grid data t * dir.z and pz - org.z are exact in
 * double, so this is no approximation. */
static bool kept_z(float org_z, float dir_z, float pz, double sign, float t)
{
    return sign * ((double)t * dir_z) <= sign * ((double)pz - org_z);
}

/* ---- clip_ray: analytic ---------------------------------------------------- */

Test(clip, a_ray_along_an_axis_is_cut_where_it_crosses_the_plane)
{
    ray r = make_ray(v3(0.f, 0.f, -5.f), v3(0.f, 0.f, 1.f));
    int entry = 42;
    clip_set up = one_plane(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f)); /* removes z > 0 */
    cr_assert(clip_ray(&up, &r, &entry));
    cr_expect_eq(r.t_near, 0.f);
    cr_expect_eq(r.t_far, 5.f, "t_far %a", (double)r.t_far);
    cr_expect_eq(entry, -1, "t_near is the ray's own");

    r = make_ray(v3(0.f, 0.f, -5.f), v3(0.f, 0.f, 1.f));
    clip_set down = one_plane(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, -1.f)); /* removes z < 0 */
    cr_assert(clip_ray(&down, &r, &entry));
    cr_expect_eq(r.t_near, nextafterf(5.f, 0.f), "t_near %a: the float just below 5 (exclusive)", (double)r.t_near);
    cr_expect_eq(r.t_far, INFINITY);
    cr_expect_eq(entry, 0);
}

Test(clip, a_crossing_that_is_a_float_is_the_last_kept_t)
{
    const float crossings[] = {1.f, 0.75f, 3.0e-3f, 1.0e6f, 0x1.fffffep+10f, FLT_MIN, 0x1p-140f, 12345.678f};
    for (size_t i = 0; i < sizeof crossings / sizeof crossings[0]; i++) {
        float f = crossings[i];
        clip_set up = one_plane(v3(0.f, 0.f, f), v3(0.f, 0.f, 1.f));
        ray r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
        r.t_near = -1.f;
        cr_assert(clip_ray(&up, &r, NULL));
        cr_expect_eq(r.t_far, f, "tc = %a: t_far %a", (double)f, (double)r.t_far);
        clip_set down = one_plane(v3(0.f, 0.f, f), v3(0.f, 0.f, -1.f));
        r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
        r.t_near = -1.f;
        int entry = -1;
        cr_assert(clip_ray(&down, &r, &entry));
        cr_expect_eq(r.t_near, nextafterf(f, -INFINITY), "tc = %a: t_near %a", (double)f, (double)r.t_near);
        cr_expect_eq(entry, 0);
    }
    /* tc = 0: t_near is the largest float below zero, so t = 0 (and -0) are in */
    clip_set down = one_plane(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, -1.f));
    ray r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
    r.t_near = -1.f;
    cr_assert(clip_ray(&down, &r, NULL));
    cr_expect_eq(r.t_near, -0x1p-149f);
}

Test(clip, a_crossing_between_floats_keeps_exactly_the_floats_on_its_side)
{
    /* 1/3: no float; the bounds are the floats either side of it */
    clip_set up = one_plane(v3(0.f, 0.f, 1.f), v3(0.f, 0.f, 1.f));
    ray r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 3.f));
    cr_assert(clip_ray(&up, &r, NULL));
    cr_expect((double)r.t_far * 3.0 <= 1.0 && (double)nextafterf(r.t_far, INFINITY) * 3.0 > 1.0, "t_far %a",
              (double)r.t_far);
    clip_set down = one_plane(v3(0.f, 0.f, 1.f), v3(0.f, 0.f, -1.f));
    r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 3.f));
    cr_assert(clip_ray(&down, &r, NULL));
    cr_expect((double)r.t_near * 3.0 < 1.0 && (double)nextafterf(r.t_near, INFINITY) * 3.0 >= 1.0, "t_near %a",
              (double)r.t_near);

    /* many grid cases, either normal, either direction: exact agreement at
     * both bounds and one float beyond each */
    for (int i = 0; i < 20000; i++) {
        float org_z = rng_grid(1 << 16), pz = rng_grid(1 << 16), dir_z = rng_grid(1 << 14);
        if (dir_z == 0.f)
            continue;
        double sign = (rng_next() & 1) ? 1.0 : -1.0;
        clip_set c = one_plane(v3(0.f, 0.f, pz), v3(0.f, 0.f, (float)sign));
        ray r0 = make_ray(v3(rng_grid(64), rng_grid(64), org_z), v3(rng_grid(512), rng_grid(512), dir_z));
        r0.t_near = -INFINITY;
        ray r1 = r0;
        bool left = clip_ray(&c, &r1, NULL);
        cr_assert(left, "a plane not parallel to the ray leaves half of an unbounded interval");
        if (r1.t_far < INFINITY) {
            cr_assert(kept_z(org_z, dir_z, pz, sign, r1.t_far), "case %d: t_far %a removed", i, (double)r1.t_far);
            cr_assert(!kept_z(org_z, dir_z, pz, sign, nextafterf(r1.t_far, INFINITY)), "case %d: past t_far kept", i);
        }
        if (r1.t_near > -INFINITY) {
            cr_assert(!kept_z(org_z, dir_z, pz, sign, r1.t_near), "case %d: t_near %a kept", i, (double)r1.t_near);
            cr_assert(kept_z(org_z, dir_z, pz, sign, nextafterf(r1.t_near, INFINITY)), "case %d: past t_near removed",
                      i);
        }
        cr_assert((r1.t_far < INFINITY) != (r1.t_near > -INFINITY), "exactly one bound moves");
    }
}

Test(clip, crossings_beyond_float_range)
{
    /* tc = 1e60: every finite float is below it */
    clip_set up = one_plane(v3(0.f, 0.f, 1e30f), v3(0.f, 0.f, 1.f));
    ray r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1e-30f));
    int entry = 7;
    cr_assert(clip_ray(&up, &r, &entry));
    cr_expect_eq(r.t_far, FLT_MAX, "only +inf is past the crossing");
    cr_expect_eq(r.t_near, 0.f);
    cr_expect_eq(entry, -1);
    /* kept only at t >= 1e60: no finite float, so nothing is left */
    clip_set down = one_plane(v3(0.f, 0.f, 1e30f), v3(0.f, 0.f, -1.f));
    r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1e-30f));
    ray before = r;
    cr_expect(!clip_ray(&down, &r, &entry));
    cr_expect(memcmp(&r, &before, sizeof r) == 0, "r unchanged when nothing is left");
    /* going down from below the plane removing z > 1e30: kept for t >= -1e60,
     * so the lower bound is -inf and t_near stays the ray's */
    r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, -1e-30f));
    cr_assert(clip_ray(&up, &r, &entry));
    cr_expect_eq(r.t_near, 0.f);
    cr_expect_eq(r.t_far, INFINITY);
    cr_expect_eq(entry, -1);
    r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, -1e-30f));
    r.t_near = -INFINITY;
    cr_assert(clip_ray(&up, &r, &entry));
    cr_expect_eq(r.t_near, -INFINITY);
    cr_expect_eq(entry, -1);
}

Test(clip, a_ray_starting_on_the_removed_side)
{
    clip_set c = one_plane(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f)); /* removes z > 0 */
    ray r = make_ray(v3(1.f, 2.f, 5.f), v3(0.f, 0.f, 1.f));
    ray before = r;
    int entry = 3;
    cr_expect(!clip_ray(&c, &r, &entry), "leaving the kept side: nothing left");
    cr_expect(memcmp(&r, &before, sizeof r) == 0);
    cr_expect_eq(entry, 3, "entry untouched when nothing is left");
    r = make_ray(v3(1.f, 2.f, 5.f), v3(0.f, 0.f, -2.f));
    cr_assert(clip_ray(&c, &r, &entry));
    cr_expect_eq(r.t_near, nextafterf(2.5f, 0.f));
    cr_expect_eq(r.t_far, INFINITY);
    cr_expect_eq(entry, 0, "enters through the plane");
    /* a shadow ray's interval ending before the plane: nothing left */
    r = make_ray(v3(1.f, 2.f, 5.f), v3(0.f, 0.f, -2.f));
    r.t_far = 2.f;
    cr_expect(!clip_ray(&c, &r, NULL));
    r.t_far = 2.5f;
    cr_assert(clip_ray(&c, &r, NULL), "t = 2.5 is on the plane: kept");
    cr_expect_eq(r.t_far, 2.5f);
}

Test(clip, parallel_rays_are_kept_whole_or_removed_whole)
{
    clip_set c = one_plane(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
    const float heights[] = {-1.f, -0x1p-149f, 0.f, -0.f};
    for (size_t i = 0; i < sizeof heights / sizeof heights[0]; i++) {
        ray r = make_ray(v3(0.f, 0.f, heights[i]), v3(1.f, -3.f, 0.f));
        int entry = 5;
        cr_assert(clip_ray(&c, &r, &entry), "z = %a is kept", (double)heights[i]);
        cr_expect(r.t_near == 0.f && r.t_far == INFINITY && entry == -1);
    }
    ray r = make_ray(v3(0.f, 0.f, 0x1p-149f), v3(1.f, -3.f, 0.f));
    cr_expect(!clip_ray(&c, &r, NULL), "the smallest height above the plane is removed");
    r = make_ray(v3(0.f, 0.f, 1.f), v3(1.f, 0.f, 0.f));
    cr_expect(!clip_ray(&c, &r, NULL));
}

Test(clip, rays_that_are_not_finite_never_get_nan_bounds)
{
    clip_set c = one_plane(v3(0.f, 0.f, 0.f), v3(0.6f, 0.f, 0.8f));
    const ray rays[] = {
        make_ray(v3(NAN, 0.f, 0.f), v3(0.f, 0.f, 1.f)),
        make_ray(v3(0.f, 0.f, 0.f), v3(INFINITY, 0.f, 1.f)),
        make_ray(v3(-INFINITY, 0.f, 0.f), v3(1.f, 0.f, 0.f)),
        make_ray(v3(INFINITY, 0.f, -INFINITY), v3(1.f, 0.f, 1.f)),
        {v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f), NAN, INFINITY},
    };
    for (size_t i = 0; i < sizeof rays / sizeof rays[0]; i++) {
        ray r = rays[i];
        if (clip_ray(&c, &r, NULL))
            cr_expect(!isnan(r.t_near) && !isnan(r.t_far) && r.t_near < r.t_far, "ray %zu", i);
        else
            cr_expect(memcmp(&r, &rays[i], sizeof r) == 0, "ray %zu unchanged", i);
    }
}

Test(clip, several_planes_give_one_interval)
{
    clip_plane planes[CLIP_MAX_PLANES] = {0};
    planes[1] = (clip_plane){v3(0.f, 0.f, 2.f), v3(0.f, 0.f, 1.f), true};    /* removes z > 2 */
    planes[3] = (clip_plane){v3(0.f, 0.f, -1.f), v3(0.f, 0.f, -1.f), true};  /* removes z < -1 */
    planes[4] = (clip_plane){v3(0.f, 0.f, 100.f), v3(0.f, 0.f, 1.f), false}; /* off */
    planes[6] = (clip_plane){v3(0.5f, 0.f, 0.f), v3(-1.f, 0.f, 0.f), true};  /* removes x < 0.5 */
    clip_set c;
    clip_set_make(&c, planes);
    cr_assert_eq(c.count, 3u);
    cr_expect(c.index[0] == 1 && c.index[1] == 3 && c.index[2] == 6);

    /* along z from below: enters through plane 3 at t = 9 (z = -1), leaves at t = 12 (z = 2) */
    ray r = make_ray(v3(1.f, 0.f, -10.f), v3(0.f, 0.f, 1.f));
    int entry = -1;
    cr_assert(clip_ray(&c, &r, &entry));
    cr_expect_eq(r.t_near, nextafterf(9.f, 0.f));
    cr_expect_eq(r.t_far, 12.f);
    cr_expect_eq(entry, 3);

    /* diagonal in xz: x = -10 + t reaches 0.5 at t = 10.5, z = -10 + t reaches -1 at 9: plane 6 bounds */
    r = make_ray(v3(-10.f, 0.f, -10.f), v3(1.f, 0.f, 1.f));
    cr_assert(clip_ray(&c, &r, &entry));
    cr_expect_eq(r.t_near, nextafterf(10.5f, 0.f));
    cr_expect_eq(r.t_far, 12.f);
    cr_expect_eq(entry, 6);

    /* the two z planes swapped: kept z > 2 and z < -1 at once, empty everywhere */
    planes[1].normal = v3(0.f, 0.f, -1.f);
    planes[3].normal = v3(0.f, 0.f, 1.f);
    clip_set_make(&c, planes);
    r = make_ray(v3(1.f, 0.f, -10.f), v3(0.f, 0.f, 1.f));
    ray before = r;
    cr_expect(!clip_ray(&c, &r, &entry));
    cr_expect(memcmp(&r, &before, sizeof r) == 0);
    cr_expect(!clip_keeps_point(&c, v3(1.f, 0.f, 0.f)));

    /* equal planes at 2 and 5: the lower index names the entry */
    clip_plane same[CLIP_MAX_PLANES] = {0};
    same[2] = same[5] = (clip_plane){v3(0.f, 0.f, 1.f), v3(0.f, 0.f, -1.f), true};
    clip_set_make(&c, same);
    r = make_ray(v3(0.f, 0.f, -1.f), v3(0.f, 0.f, 1.f));
    cr_assert(clip_ray(&c, &r, &entry));
    cr_expect_eq(entry, 2);
    /* a tie with the ray's own t_near keeps the ray's */
    r = make_ray(v3(0.f, 0.f, -1.f), v3(0.f, 0.f, 1.f));
    r.t_near = nextafterf(2.f, 0.f);
    cr_assert(clip_ray(&c, &r, &entry));
    cr_expect_eq(entry, -1);
}

Test(clip, the_set_skips_bad_normals_and_normalises_in_double)
{
    clip_plane planes[CLIP_MAX_PLANES] = {0};
    planes[0] = (clip_plane){v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 0.f), true};
    planes[1] = (clip_plane){v3(0.f, 0.f, 0.f), v3(NAN, 0.f, 1.f), true};
    planes[2] = (clip_plane){v3(0.f, 0.f, 0.f), v3(INFINITY, 0.f, 0.f), true};
    planes[3] = (clip_plane){v3(NAN, 0.f, 0.f), v3(1.f, 0.f, 0.f), true};
    planes[7] = (clip_plane){v3(0.f, 0.f, 3.f), v3(0.f, 0.f, 2.f), true};
    clip_set c;
    clip_set_make(&c, planes);
    cr_assert_eq(c.count, 1u);
    cr_expect_eq(c.index[0], 7);
    cr_expect(c.n[0][0] == 0.0 && c.n[0][1] == 0.0 && c.n[0][2] == 1.0);
    cr_expect_eq(c.d[0], 3.0);
    clip_plane none[CLIP_MAX_PLANES] = {0};
    clip_set_make(&c, none);
    cr_expect_eq(c.count, 0u);
    ray r = make_ray(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
    int entry = 9;
    cr_expect(clip_ray(&c, &r, &entry) && r.t_near == 0.f && r.t_far == INFINITY && entry == -1,
              "no planes: nothing clipped");
    cr_expect(clip_keeps_point(&c, v3(1e30f, 0.f, 0.f)));
}

Test(clip, keeps_point_and_crossing)
{
    clip_set c = one_plane(v3(1.f, 1.f, 1.f), v3(0.f, 0.6f, 0.8f));
    cr_expect(clip_keeps_point(&c, v3(1.f, 1.f, 1.f)), "on the plane: kept");
    cr_expect(clip_keeps_point(&c, v3(1.f, 0.f, 1.f)));
    cr_expect(!clip_keeps_point(&c, v3(1.f, 2.f, 1.f)));
    ray r = make_ray(v3(0.f, -5.f, -5.f), v3(0.f, 1.f, 1.f));
    vec3 p;
    cr_assert(clip_crossing(&c, 0, &r, &p));
    double off = c.n[0][0] * p.x + c.n[0][1] * p.y + c.n[0][2] * p.z - c.d[0];
    cr_expect(fabs(off) < 4e-7, "on the plane within float rounding: %g", off);
    cr_expect(fabsf(p.y - p.z) < 1e-6f && p.x == 0.f, "on the ray: (%g %g %g)", p.x, p.y, p.z);
    cr_expect(!clip_crossing(&c, 1, &r, &p), "plane 1 is not in the set");
    r = make_ray(v3(0.f, 0.f, 0.f), v3(1.f, 0.f, 0.f));
    cr_expect(!clip_crossing(&c, 0, &r, &p), "parallel");
}

/* ---- clip_ray: general planes ---------------------------------------------- */

/* Signed distance of org + t dir to plane k of c in long double, and the size
 * of the magnitudes it is made of (for the tolerance). */
static long double side(const clip_set *c, uint32_t k, const ray *r, float t, long double *magnitude)
{
    long double s = -(long double)c->d[k], mag = fabsl((long double)c->d[k]);
    const float o[3] = {r->org.x, r->org.y, r->org.z}, d[3] = {r->dir.x, r->dir.y, r->dir.z};
    for (int a = 0; a < 3; a++) {
        long double x = (long double)o[a] + (long double)t * d[a];
        s += (long double)c->n[k][a] * x;
        mag += fabsl((long double)c->n[k][a]) * (fabsl((long double)o[a]) + fabsl((long double)t * d[a]));
    }
    *magnitude = mag;
    return s;
}

/* Whether t is kept by every plane: 1 kept, 0 removed, -1 undecided (within
 * the double rounding clip.h allows of one plane's distance). */
static int kept_general(const clip_set *c, const ray *r, float t)
{
    int verdict = 1;
    for (uint32_t k = 0; k < c->count; k++) {
        long double mag, s = side(c, k, r, t, &mag);
        long double tol = mag * 0x1p-48L;
        if (s > tol)
            return 0;
        if (s > -tol)
            verdict = -1;
    }
    return verdict;
}

Test(clip, random_rays_and_planes_agree_with_the_kept_side_near_both_bounds)
{
    int undecided = 0, checked = 0, empty = 0;
    for (int i = 0; i < 4000; i++) {
        clip_plane planes[CLIP_MAX_PLANES] = {0};
        int n = 1 + (int)(rng_next() % 4);
        for (int k = 0; k < n; k++) {
            vec3 normal = v3_normalize(v3((float)rng_range(-1, 1), (float)rng_range(-1, 1), (float)rng_range(-1, 1)));
            planes[rng_next() % CLIP_MAX_PLANES] =
                (clip_plane){v3((float)rng_range(-10, 10), (float)rng_range(-10, 10), (float)rng_range(-10, 10)),
                             normal, true};
        }
        clip_set c;
        clip_set_make(&c, planes);
        ray r = make_ray(v3((float)rng_range(-20, 20), (float)rng_range(-20, 20), (float)rng_range(-20, 20)),
                         v3((float)rng_range(-3, 3), (float)rng_range(-3, 3), (float)rng_range(-3, 3)));
        r.t_near = -INFINITY;
        ray clipped = r;
        int entry;
        if (!clip_ray(&c, &clipped, &entry)) {
            empty++;
            /* empty: a sample of the line is removed (where decidable) */
            for (float t = -64.f; t <= 64.f; t += 0.25f)
                cr_assert_neq(kept_general(&c, &r, t), 1, "case %d: nothing left but t = %g is kept", i, t);
            continue;
        }
        /* floats at and next to each bound, a few steps in and out */
        const float bounds[2] = {clipped.t_near, clipped.t_far};
        for (int b = 0; b < 2; b++) {
            if (!isfinite(bounds[b]))
                continue;
            float t = bounds[b];
            for (int step = 0; step < 3; step++)
                t = nextafterf(t, b == 0 ? -INFINITY : INFINITY); /* outside */
            for (int step = 0; step < 7; step++, t = nextafterf(t, b == 0 ? INFINITY : -INFINITY)) {
                bool inside = t > clipped.t_near && t <= clipped.t_far;
                int verdict = kept_general(&c, &r, t);
                checked++;
                if (verdict < 0) {
                    undecided++;
                    continue;
                }
                cr_assert_eq(inside, verdict == 1, "case %d: t = %a inside %d but kept %d (interval (%a, %a])", i,
                             (double)t, inside, verdict, (double)clipped.t_near, (double)clipped.t_far);
            }
        }
        if (entry >= 0) {
            cr_assert(planes[entry].on);
            vec3 p;
            cr_assert(clip_crossing(&c, entry, &r, &p), "the entry plane is crossed");
        }
    }
    cr_expect(undecided * 100 < checked, "undecided %d of %d: the tolerance is too wide to test", undecided, checked);
    cr_expect(empty > 0 && empty < 4000, "both outcomes exercised (%d empty)", empty);
}

/* ---- a plane through the shared edge of two triangles ----------------------- */

Test(clip, triangles_either_side_of_a_plane_through_their_edge_are_cut_consistently)
{
    /* two triangles in z = 0 sharing the edge x = 0, y in [-1, 1]; the plane
     * x = 0 removes x > 0 (the right triangle) and keeps the edge itself */
    const vec3 left[3] = {v3(-1.f, -1.f, 0.f), v3(0.f, -1.f, 0.f), v3(0.f, 1.f, 0.f)};
    const vec3 right[3] = {v3(0.f, -1.f, 0.f), v3(1.f, -1.f, 0.f), v3(0.f, 1.f, 0.f)};
    clip_set c = one_plane(v3(0.f, 0.f, 0.f), v3(1.f, 0.f, 0.f));
    int hits_left = 0, hits_right = 0, hits_removed = 0, hits_on_edge = 0;
    for (int i = 0; i < 20000; i++) {
        /* aim at a point within a few ulps (or a few 1e-6) of the edge, slanted across it */
        float ulps = (float)((int)(rng_next() % 41) - 20);
        float aim_x = (rng_next() & 1) ? ulps * 0x1p-149f : ulps * 1e-7f;
        vec3 aim = v3(aim_x, rng_grid(900), 0.f);
        vec3 org = v3(rng_grid(2048), rng_grid(2048), 1.f + (float)(rng_next() % 8));
        ray r = make_ray(org, v3_sub(aim, org));
        if (!v3_is_finite(r.dir) || (r.dir.x == 0.f && r.dir.y == 0.f && r.dir.z == 0.f))
            continue;
        /* the hit without planes, and whether its point (in double from the
         * float t) is kept */
        ray_derived rd = ray_derive(&r);
        float t = INFINITY, u, v, tt;
        bool hit_l = intersect_triangle(&r, &rd, left[0], left[1], left[2], &tt, &u, &v);
        if (hit_l)
            t = tt;
        bool hit_r = intersect_triangle(&r, &rd, right[0], right[1], right[2], &tt, &u, &v);
        if (hit_r && tt < t)
            t = tt;
        if (!hit_l && !hit_r)
            continue;
        double hit_x = (double)org.x + (double)t * r.dir.x; /* exact sign: a sum of two exact terms, rounded once */
        bool point_kept = hit_x <= 0.0;
        cr_assert_eq(point_kept, clip_keeps_point(&c, v3((float)hit_x, 0.f, 0.f)), "float point agrees");
        /* the clipped ray finds that hit exactly when the point is kept */
        ray clipped = r;
        bool left_over = clip_ray(&c, &clipped, NULL);
        bool found = left_over && t > clipped.t_near && t <= clipped.t_far;
        cr_assert_eq(found, point_kept, "case %d: hit at t = %a, x = %a: kept %d, in the interval %d", i, (double)t,
                     hit_x, point_kept, found);
        if (found) {
            rd = ray_derive(&clipped);
            bool again = intersect_triangle(&clipped, &rd, left[0], left[1], left[2], &tt, &u, &v) ||
                         intersect_triangle(&clipped, &rd, right[0], right[1], right[2], &tt, &u, &v);
            cr_assert(again, "case %d: the kept hit is found by the clipped ray", i);
        }
        hits_left += hit_l;
        hits_right += hit_r;
        hits_removed += !point_kept;
        hits_on_edge += hit_x == 0.0;
    }
    cr_expect(hits_left > 1000 && hits_right > 1000 && hits_removed > 1000, "%d %d %d", hits_left, hits_right,
              hits_removed);
    cr_expect(hits_on_edge > 0, "some hits exactly on the edge (x = 0)");
}

/* ---- closed parts ----------------------------------------------------------- */

/* The 8 corners of the cube [lo, lo + 1]^3, corner k at bits (x, y, z) of k. */
static vec3 cube_corner(vec3 lo, int k)
{
    return v3(lo.x + (float)(k & 1), lo.y + (float)(k >> 1 & 1), lo.z + (float)(k >> 2 & 1));
}

/* Its 6 faces as corner quads, counter-clockwise seen from outside. */
static const int cube_faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

/* Append the cube's faces (the first `faces` of them) to m: 8 shared
 * vertices, or 4 of its own per face when `split` (as for flat normals). */
static void add_cube(mesh *m, vec3 lo, int faces, bool split)
{
    uint32_t base = m->vertex_count;
    if (!split)
        for (int k = 0; k < 8; k++) {
            vec3 c = cube_corner(lo, k);
            cr_assert(mesh_add_vertex(m, c.x, c.y, c.z));
        }
    for (int f = 0; f < faces; f++) {
        uint32_t q[4];
        for (int i = 0; i < 4; i++) {
            if (split) {
                vec3 c = cube_corner(lo, cube_faces[f][i]);
                q[i] = m->vertex_count;
                cr_assert(mesh_add_vertex(m, c.x, c.y, c.z));
            } else {
                q[i] = base + (uint32_t)cube_faces[f][i];
            }
        }
        cr_assert(mesh_add_triangle(m, q[0], q[1], q[2]) && mesh_add_triangle(m, q[0], q[2], q[3]));
    }
}

/* The triangles kind's answer for m (m stays the caller's). */
static bool mesh_closed(mesh *m)
{
    scene_mesh sm = {.mesh = m};
    return geometry_triangles_ops.closed(&sm);
}

Test(clip, a_cube_is_closed_with_shared_or_split_vertices)
{
    mesh *m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 6, false);
    cr_expect_eq(m->triangle_count, 12u);
    cr_expect(mesh_closed(m), "12 triangles, 8 vertices");
    mesh_destroy(m);

    m = mesh_create();
    add_cube(m, v3(-0.5f, -0.5f, -0.5f), 6, true);
    cr_expect_eq(m->vertex_count, 24u);
    cr_expect(mesh_closed(m), "24 vertices (per-face normals) weld back to 8");
    mesh_destroy(m);

    /* a corner at the origin given as -0 in one face and +0 in the others:
     * the same position, welded */
    m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 6, true);
    for (uint32_t v = 0; v < 4; v++)
        for (int a = 0; a < 3; a++)
            if (m->positions[3 * v + a] == 0.f)
                m->positions[3 * v + a] = -0.f;
    cr_expect(mesh_closed(m), "-0 and +0 weld");
    mesh_destroy(m);
}

Test(clip, an_open_or_lone_surface_is_not_closed)
{
    mesh *m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 5, false);
    cr_expect(!mesh_closed(m), "a face missing: its rim is used once");
    mesh_destroy(m);

    m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 5, true);
    cr_expect(!mesh_closed(m), "split, a face missing");
    mesh_destroy(m);

    m = mesh_create();
    cr_assert(mesh_add_vertex(m, 0.f, 0.f, 0.f) && mesh_add_vertex(m, 1.f, 0.f, 0.f) &&
              mesh_add_vertex(m, 0.f, 1.f, 0.f) && mesh_add_triangle(m, 0, 1, 2));
    cr_expect(!mesh_closed(m), "a single triangle");
    cr_assert(mesh_add_triangle(m, 0, 2, 1));
    cr_expect(mesh_closed(m), "a triangle and its back face enclose nothing but are even at every edge: parity "
                              "never counts a point inside, so a cut of it has no cap either");
    mesh_destroy(m);

    m = mesh_create();
    cr_expect(!mesh_closed(m), "an empty mesh has nothing to cap");
    mesh_destroy(m);
}

Test(clip, edge_counts_decide_by_parity)
{
    /* a duplicated triangle: its edges are used 3 times, odd: open */
    mesh *m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 6, false);
    cr_assert(mesh_add_triangle(m, 0, 2, 3));
    cr_expect(!mesh_closed(m), "edge count 3");
    /* the same triangle once more: 4 uses, even again (the two extra copies
     * cancel under parity) */
    cr_assert(mesh_add_triangle(m, 0, 3, 2));
    cr_expect(mesh_closed(m), "edge count 4");
    mesh_destroy(m);

    /* two cubes sharing nothing, in one mesh */
    m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 6, false);
    add_cube(m, v3(3.f, 0.f, 0.f), 6, true);
    cr_expect(mesh_closed(m), "two disjoint cubes");
    mesh_destroy(m);

    /* two cubes touching along one edge (CAD parts do): that edge has 4 */
    m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 6, false);
    add_cube(m, v3(1.f, 1.f, 0.f), 6, false);
    cr_expect(mesh_closed(m), "non-manifold edge used 4 times");
    mesh_destroy(m);

    /* degenerate triangles (repeated vertex, collinear) are ignored */
    m = mesh_create();
    add_cube(m, v3(0.f, 0.f, 0.f), 6, false);
    cr_assert(mesh_add_vertex(m, 0.5f, 0.f, 0.f));
    cr_assert(mesh_add_triangle(m, 0, 0, 1) && mesh_add_triangle(m, 0, 1, 8) && mesh_add_triangle(m, 8, 8, 8));
    cr_expect(mesh_closed(m), "degenerate triangles do not count");
    mesh_destroy(m);
}

/* A UV sphere of `rings` x `segments` quads with the seam and pole vertices
 * split (their positions repeated bit for bit, -0 and +0 mixed at the poles;
 * the pole rows' triangles that collapse are degenerate). */
static mesh *uv_sphere(uint32_t rings, uint32_t segments)
{
    mesh *m = mesh_create();
    cr_assert(mesh_reserve_vertices(m, (rings + 1) * (segments + 1)) &&
              mesh_reserve_triangles(m, 2 * rings * segments));
    for (uint32_t i = 0; i <= rings; i++) {
        double theta = 3.14159265358979323846 * i / rings;
        for (uint32_t j = 0; j <= segments; j++) {
            double phi = 2.0 * 3.14159265358979323846 * (j % segments) / segments; /* the seam repeats j = 0 */
            double ring = i == 0 || i == rings ? 0.0 : sin(theta); /* sin(pi) is not 0 in double */
            cr_assert(mesh_add_vertex(m, (float)(ring * cos(phi)), (float)(ring * sin(phi)), (float)cos(theta)));
        }
    }
    for (uint32_t i = 0; i < rings; i++)
        for (uint32_t j = 0; j < segments; j++) {
            uint32_t a = i * (segments + 1) + j, b = a + 1, c = a + segments + 1, d = c + 1;
            cr_assert(mesh_add_triangle(m, a, c, d) && mesh_add_triangle(m, a, d, b));
        }
    return m;
}

/* The process's CPU seconds: what other processes on a loaded machine do not change. */
static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* mesh_closed's cost grows as n log n: 100 times the triangles may cost about
 * 100 x 1.6 (the log) x a few (caches) times as much, a quadratic pass 10,000
 * times. The verdict is a ratio of two costs measured in this process, so it
 * holds on any CPU at any speed (TCG, sanitizers); the small sphere's time is
 * the best of several runs, each long enough for the clock. */
Test(clip, a_large_split_sphere_is_closed_in_n_log_n)
{
    mesh *small = uv_sphere(30, 60); /* 3,600 triangles */
    mesh *m = uv_sphere(300, 600);   /* 360,000 triangles */
    double small_s = INFINITY;
    for (int run = 0; run < 7; run++) {
        double t0 = cpu_seconds();
        cr_expect(mesh_closed(small));
        double t = cpu_seconds() - t0;
        small_s = t < small_s ? t : small_s;
    }
    double t0 = cpu_seconds();
    cr_expect(mesh_closed(m));
    double large_s = cpu_seconds() - t0;
    double ratio = large_s / fmax(small_s, 1e-6);
    cr_log_info("mesh_closed: %.4f s for 3.6k triangles, %.3f s for 360k: ratio %.0f", small_s, large_s, ratio);
    cr_expect(ratio < 2000.0, "%.4f s for 3.6k triangles, %.3f s for 360k (ratio %.0f): not n log n?", small_s,
              large_s, ratio);
    /* a hole of one quad */
    m->triangle_count -= 2;
    cr_expect(!mesh_closed(m));
    mesh_destroy(small);
    mesh_destroy(m);
}

/* A kind without the operation (a point set, never hit). */
static uint32_t no_prims(const void *data)
{
    (void)data;
    return 0;
}
static bool no_bounds(const void *data, uint32_t prim, aabb *out)
{
    (void)data, (void)prim, (void)out;
    return false;
}
static bool no_hit(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v)
{
    (void)data, (void)prim, (void)r, (void)t, (void)u, (void)v;
    return false;
}
static void no_surface(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                       geometry_surface *out)
{
    (void)data, (void)prim, (void)r, (void)h, (void)need_position, (void)out;
}
static const geometry_ops open_kind_ops = {
    .name = "nothing",
    .leaf = GEOMETRY_LEAF_PRIMS,
    .prim_count = no_prims,
    .prim_bounds = no_bounds,
    .intersect = no_hit,
    .describe = no_surface,
};

/* A scene of: a closed cube (geometry 0), an open cube (1), spheres (2), the
 * kind without `closed` (3). */
static scene *closed_scene(void)
{
    scene *s = scene_create();
    cr_assert(s);
    material grey = material_default();
    cr_assert(scene_add_material(s, &grey) == 0);
    mesh *closed = mesh_create(), *open = mesh_create();
    add_cube(closed, v3(0.f, 0.f, 0.f), 6, true);
    add_cube(open, v3(2.f, 0.f, 0.f), 5, false);
    cr_assert(scene_add_mesh(s, closed, 0, "closed") == 0 && scene_add_mesh(s, open, 0, "open") == 1);
    cr_assert(scene_add_sphere(s, v3(0.f, 5.f, 0.f), 1.f, 0) == 0);
    cr_assert(scene_add_geometry(s, &open_kind_ops, NULL, "nothing") == 3);
    return s;
}

static void expect_closed_flags(const scene *s)
{
    cr_expect(scene_geometry_closed(s, 0), "closed cube");
    cr_expect(!scene_geometry_closed(s, 1), "open cube");
    cr_expect(scene_geometry_closed(s, 2), "spheres");
    cr_expect(!scene_geometry_closed(s, 3), "a kind without the operation");
    cr_expect(!scene_geometry_closed(s, 4), "no such geometry");
}

Test(clip, the_scene_answers_lazily_and_caches)
{
    scene *s = closed_scene();
    cr_expect_null(atomic_load(&s->closed), "nothing until the first question");
    cr_expect(!scene_geometry_closed(s, 3));
    cr_expect_null(atomic_load(&s->closed), "a kind without the operation needs no cache");
    expect_closed_flags(s);
    cr_expect_not_null(atomic_load(&s->closed));
    expect_closed_flags(s); /* from the cache */
    /* a geometry added later drops the cache; the next question makes a new one */
    mesh *m = mesh_create();
    add_cube(m, v3(5.f, 0.f, 0.f), 6, false);
    cr_assert(scene_add_mesh_geometry(s, m, 0, "late") == 4);
    cr_expect_null(atomic_load(&s->closed));
    cr_expect(scene_geometry_closed(s, 4));
    cr_expect(scene_geometry_closed(s, 0) && !scene_geometry_closed(s, 1));
    scene_destroy(s);

    s = closed_scene();
    scene_prepare_closed(s, 2);
    cr_expect_not_null(atomic_load(&s->closed));
    expect_closed_flags(s);
    scene_destroy(s);
}

static void *ask_every_geometry(void *arg)
{
    const scene *s = arg;
    uintptr_t answers = 0;
    for (uint32_t g = 0; g < s->geometry_count; g++)
        answers |= (uintptr_t)scene_geometry_closed(s, g) << g;
    return (void *)answers;
}

Test(clip, render_threads_may_ask_at_once)
{
    for (int round = 0; round < 20; round++) {
        scene *s = closed_scene();
        pthread_t threads[4];
        for (int i = 0; i < 4; i++)
            cr_assert_eq(pthread_create(&threads[i], NULL, ask_every_geometry, s), 0);
        for (int i = 0; i < 4; i++) {
            void *answers;
            cr_assert_eq(pthread_join(threads[i], &answers), 0);
            cr_expect_eq((uintptr_t)answers, 0x5u, "closed: geometries 0 and 2 (got %#lx)",
                         (unsigned long)(uintptr_t)answers);
        }
        scene_destroy(s);
    }
}

Test(clip, the_generated_assembly_parts_are_closed)
{
    /* tools/gen_assembly: frames, stringers, skins, pipes, brackets, bolts,
     * rivets, each made a closed solid (its README); loaded through assimp
     * with their per-face vertices split */
    scene *s = scene_create();
    tess_error err = {{0}};
    cr_assert(scene_load_assembly(s, "data/assembly-small.glb", NULL, &err), "%s", err.msg);
    cr_assert(s->geometry_count >= 7, "%u geometries: one mesh per kind at least", s->geometry_count);
    uint32_t split = 0;
    for (uint32_t g = 0; g < s->geometry_count; g++) {
        cr_expect(scene_geometry_closed(s, g), "geometry %u (%s) is not closed", g, s->geometries[g].name);
        const scene_mesh *sm = s->geometries[g].data;
        split += sm->mesh->vertex_count > sm->mesh->triangle_count / 2 + 2; /* more than a welded solid's V */
    }
    cr_expect(split > 0, "some parts have split vertices, so welding was needed");
    /* the instances are placed by rigid transforms, which keep a solid one */
    scene_destroy(s);
}
