#include "intersect.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>


static float component(vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }

/* 1/x, but +-FLT_MAX for a zero x (signed like the zero), so no product is NaN;
 * box tests treat zero components by containment (ray_derived.zero_axes). */
#ifndef TESSERA_UNROBUST
static float safe_reciprocal(float x) { return x != 0.f ? 1.f / x : copysignf(FLT_MAX, x); }
#else
static float safe_reciprocal(float x) { return 1.f / x; } /* fast build: +-inf for a zero x */
#endif

ray_derived ray_derive(const ray *r)
{
    ray_derived d;
    d.inv_dir = v3(safe_reciprocal(r->dir.x), safe_reciprocal(r->dir.y), safe_reciprocal(r->dir.z));
#ifndef TESSERA_UNROBUST
    d.zero_axes = (r->dir.x == 0.f ? 1u : 0u) | (r->dir.y == 0.f ? 2u : 0u) | (r->dir.z == 0.f ? 4u : 0u);
#else
    d.zero_axes = 0u; /* fast build: no containment rule, every axis a plain slab */
#endif
    d.cull_slack = 0.f;
    d.after_t = -INFINITY;
    d.after_geom = d.after_prim = RAY_INVALID_ID;
    float ax = fabsf(r->dir.x), ay = fabsf(r->dir.y), az = fabsf(r->dir.z);
    d.kz = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    d.kx = (d.kz + 1) % 3;
    d.ky = (d.kx + 1) % 3;
    float dz = component(r->dir, d.kz);
    if (dz < 0.f) { /* keep the winding so U, V, W signs mean the same for every ray */
        int t = d.kx;
        d.kx = d.ky;
        d.ky = t;
    }
    d.shear_x = component(r->dir, d.kx) / dz;
    d.shear_y = component(r->dir, d.ky) / dz;
    d.shear_z = 1.f / dz;
    return d;
}

/* gamma(n) = n u / (1 - n u), u = 2^-24 */
static float gamma_n(int n) { return (float)n * 0x1p-24f / (1.f - (float)n * 0x1p-24f); }

#ifdef TESSERA_UNROBUST
vec3 ray_offset_origin(surface_point sp, vec3 n)
{
    return v3_add(sp.p, v3_scale(n, INTERSECT_UNROBUST_SHADOW_OFFSET)); /* fast build: a fixed epsilon */
}
#else
static int32_t float_bits(float f)
{
    int32_t i;
    memcpy(&i, &f, sizeof i);
    return i;
}

static float bits_float(int32_t i)
{
    float f;
    memcpy(&f, &i, sizeof f);
    return f;
}

/* The next float after x in the direction of `towards`' sign (x unchanged for
 * towards == 0); nextafterf without the library call, for finite x. */
static float step_away(float x, float towards)
{
    if (towards == 0.f)
        return x;
    if (x == 0.f)
        return towards > 0.f ? 0x1p-149f : -0x1p-149f;
    int32_t bits = float_bits(x);
    bool up_in_magnitude = (x > 0.f) == (towards > 0.f);
    return bits_float(up_in_magnitude ? bits + 1 : bits - 1);
}

vec3 ray_offset_origin(surface_point sp, vec3 n)
{
    float d = fabsf(n.x) * sp.error.x + fabsf(n.y) * sp.error.y + fabsf(n.z) * sp.error.z;
    vec3 offset = v3_scale(n, d);
    vec3 po = v3_add(sp.p, offset);
    /* the addition rounds too: step one more float away along the offset */
    po.x = step_away(po.x, offset.x);
    po.y = step_away(po.y, offset.y);
    po.z = step_away(po.z, offset.z);
    return po;
}
#endif

static float max3f(float a, float b, float c)
{
    float m = a > b ? a : b;
    return m > c ? m : c;
}

static float max_abs3(vec3 a) { return max3f(fabsf(a.x), fabsf(a.y), fabsf(a.z)); }

/* The allowance is the same in every component: the intersection test mixes
 * coordinates (through the shear), so a point exact in one coordinate (on an
 * axis-aligned plane) still needs the allowance of the others. */
surface_point surface_point_triangle(vec3 v0, vec3 v1, vec3 v2, float u, float v)
{
    float b0 = 1.f - u - v;
    surface_point sp;
    sp.p = v3_add(v3_scale(v0, b0), v3_add(v3_scale(v1, u), v3_scale(v2, v)));
    float e = gamma_n(SURFACE_ERROR_ULPS) * (max3f(max_abs3(v0), max_abs3(v1), max_abs3(v2)) + max_abs3(sp.p));
    sp.error = v3(e, e, e);
    return sp;
}

surface_point surface_point_sphere(vec3 org, vec3 dir, float t, vec3 centre, float radius, vec3 *normal)
{
    vec3 rel = v3_sub(v3_add(org, v3_scale(dir, t)), centre);
    float len = v3_length(rel);
    vec3 n = len > 0.f ? v3_scale(rel, 1.f / len) : v3(0.f, 1.f, 0.f);
    surface_point sp;
    sp.p = v3_add(centre, v3_scale(n, radius));
    float e = gamma_n(SURFACE_ERROR_ULPS) * (max_abs3(centre) + radius);
    sp.error = v3(e, e, e);
    *normal = n;
    return sp;
}

bool intersect_triangle_degenerate(vec3 v0, vec3 v1, vec3 v2)
{
    /* edge vectors and their cross product in double: exact for the usual
     * float inputs (differences of floats and products of such differences
     * fit in 53 bits unless the coordinates span very different exponents) */
    double e1x = (double)v1.x - v0.x, e1y = (double)v1.y - v0.y, e1z = (double)v1.z - v0.z;
    double e2x = (double)v2.x - v0.x, e2y = (double)v2.y - v0.y, e2z = (double)v2.z - v0.z;
    return e1y * e2z - e1z * e2y == 0.0 && e1z * e2x - e1x * e2z == 0.0 && e1x * e2y - e1y * e2x == 0.0;
}

#ifndef TESSERA_UNROBUST
/* Whether a ray that meets the edge from P to Q exactly (its edge function
 * Qx Py - Qy Px is 0, in the sheared 2D space the test works in) belongs to
 * this triangle, whose interior is where the edge function has the sign of
 * det: it does when a step from the ray in the fixed direction (1, 0), or
 * (0, 1) along an edge parallel to it, enters the interior. The triangle on
 * the edge's other side computes the same two points (the same ray, the same
 * vertices) and so the edge function's gradient negated, whatever its
 * winding: exactly one of two triangles sharing an edge has the ray, and
 * exactly one of a fan around a vertex (the step direction breaks every tie
 * the same way, as rasterisers' top-left rule). So a surface is crossed once
 * where its triangles meet: what transparency and parity counts need. */
static bool edge_owned(double px, double py, double qx, double qy, double det)
{
    double step_x = qy - py; /* d(edge function) / d(ray position x) */
    if (step_x != 0.0)
        return (step_x > 0.0) == (det > 0.0);
    double step_y = px - qx;
    return step_y != 0.0 && (step_y > 0.0) == (det > 0.0);
}

/* The watertight test in double, from the original float coordinates: for
 * the rays and triangles float cannot decide. Same conventions as below. */
static bool triangle_in_double(const ray *r, const ray_derived *d, vec3 v0, vec3 v1, vec3 v2, float *t_out,
                               float *u_out, float *v_out)
{
    const double org[3] = {r->org.x, r->org.y, r->org.z}, dir[3] = {r->dir.x, r->dir.y, r->dir.z};
    const double p0[3] = {v0.x, v0.y, v0.z}, p1[3] = {v1.x, v1.y, v1.z}, p2[3] = {v2.x, v2.y, v2.z};
    const int kx = d->kx, ky = d->ky, kz = d->kz;
    const double sx = dir[kx] / dir[kz], sy = dir[ky] / dir[kz], sz = 1.0 / dir[kz];
    const double az = p0[kz] - org[kz], bz = p1[kz] - org[kz], cz = p2[kz] - org[kz];
    const double ax = (p0[kx] - org[kx]) - sx * az, ay = (p0[ky] - org[ky]) - sy * az;
    const double bx = (p1[kx] - org[kx]) - sx * bz, by = (p1[ky] - org[ky]) - sy * bz;
    const double cx = (p2[kx] - org[kx]) - sx * cz, cy = (p2[ky] - org[ky]) - sy * cz;
    const double u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0))
        return false;
    const double det = u + v + w;
    if (det == 0.0)
        return false;
    /* exactly on an edge (or a vertex): the point belongs to one triangle only */
    if ((u == 0.0 && !edge_owned(bx, by, cx, cy, det)) || (v == 0.0 && !edge_owned(cx, cy, ax, ay, det)) ||
        (w == 0.0 && !edge_owned(ax, ay, bx, by, det)))
        return false;
    const double t = sz * (u * az + v * bz + w * cz) / det;
    const float tf = (float)t;
    if (!(tf > r->t_near) || !(tf <= r->t_far))
        return false;
    *t_out = tf;
    *u_out = (float)(v / det);
    *v_out = (float)(w / det);
    return true;
}
#endif

bool intersect_triangle(const ray *r, const ray_derived *d, vec3 v0, vec3 v1, vec3 v2, float *t_out, float *u_out,
                        float *v_out)
{
    if (intersect_triangle_degenerate(v0, v1, v2))
        return false; /* zero area: never hit (the kernels leave such triangles out of the BVH) */
    vec3 a = v3_sub(v0, r->org), b = v3_sub(v1, r->org), c = v3_sub(v2, r->org);
    float akx = component(a, d->kx), aky = component(a, d->ky), az = component(a, d->kz);
    float bkx = component(b, d->kx), bky = component(b, d->ky), bz = component(b, d->kz);
    float ckx = component(c, d->kx), cky = component(c, d->ky), cz = component(c, d->kz);
    float ax = akx - d->shear_x * az, ay = aky - d->shear_y * az;
    float bx = bkx - d->shear_x * bz, by = bky - d->shear_y * bz;
    float cx = ckx - d->shear_x * cz, cy = cky - d->shear_y * cz;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    /* L1 sizes of the vertices relative to the origin (m, which bounds the
     * shear's rounding) and after the shear (p), in the kernels' order */
#ifndef TESSERA_UNROBUST
    float ma = (fabsf(akx) + fabsf(aky)) + fabsf(az), mb = (fabsf(bkx) + fabsf(bky)) + fabsf(bz),
          mc = (fabsf(ckx) + fabsf(cky)) + fabsf(cz);
    float pa = fabsf(ax) + fabsf(ay), pb = fabsf(bx) + fabsf(by), pc = fabsf(cx) + fabsf(cy);
    if (fabsf(u) <= INTERSECT_EDGE_TOL * (mc * pb + mb * pc) || fabsf(v) <= INTERSECT_EDGE_TOL * (ma * pc + mc * pa) ||
        fabsf(w) <= INTERSECT_EDGE_TOL * (mb * pa + ma * pb))
        return triangle_in_double(r, d, v0, v1, v2, t_out, u_out, v_out);
#endif
    if ((u < 0.f || v < 0.f || w < 0.f) && (u > 0.f || v > 0.f || w > 0.f))
        return false;
    float det = u + v + w; /* the signs agree and none is 0, so det is not 0 */
#ifdef TESSERA_UNROBUST
    if (det == 0.f) /* fast build: all three may be 0 */
        return false;
#endif
    float tz = u * (d->shear_z * az) + v * (d->shear_z * bz) + w * (d->shear_z * cz);
    float inv_det = 1.f / det;
    float t = tz * inv_det;
    /* the interval test is on the computed t itself, not on tz against
     * t_far * det as in the paper: that product rounds, and could reject a
     * primitive at exactly the current t_far, making ties depend on the order
     * in which primitives are tested */
    if (!(t > r->t_near) || !(t <= r->t_far))
        return false;
    *t_out = t;
    *u_out = v * inv_det;
    *v_out = w * inv_det;
    return true;
}

bool intersect_sphere(const ray *r, vec3 centre, float radius, float *t_out)
{
    vec3 f = v3_sub(r->org, centre);
    float a = v3_dot(r->dir, r->dir);
    float b_half = v3_dot(f, r->dir);
    /* distance of the centre from the ray's line, without the cancellation of b^2 - ac */
    vec3 l = v3_sub(f, v3_scale(r->dir, b_half / a));
    float disc = a * (radius * radius - v3_dot(l, l));
    if (disc < 0.f)
        return false;
    float c = v3_dot(f, f) - radius * radius;
    float q = -(b_half + copysignf(sqrtf(disc), b_half));
    float t0 = c / q, t1 = q / a;
    if (q == 0.f) /* ray starts at the centre of a zero-radius... or b and disc are 0 */
        t0 = t1 = 0.f;
    if (t0 > t1) {
        float t = t0;
        t0 = t1;
        t1 = t;
    }
    if (t0 > r->t_near && t0 <= r->t_far) {
        *t_out = t0;
        return true;
    }
    if (t1 > r->t_near && t1 <= r->t_far) {
        *t_out = t1;
        return true;
    }
    return false;
}

bool intersect_box_span(const ray *r, const ray_derived *d, const aabb *b, float *t_entry, float *t_exit)
{
    const float org[3] = {r->org.x, r->org.y, r->org.z}, inv[3] = {d->inv_dir.x, d->inv_dir.y, d->inv_dir.z};
    const float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
    float t_in = r->t_near, t_out = r->t_far;
    for (int a = 0; a < 3; a++) {
        if (d->zero_axes >> a & 1u) {
            if (!(lo[a] <= org[a] && org[a] <= hi[a]))
                return false;
            continue;
        }
        float t0 = (lo[a] - org[a]) * inv[a], t1 = (hi[a] - org[a]) * inv[a];
        t_in = fmaxf(t_in, fminf(t0, t1));
        t_out = fminf(t_out, fmaxf(t0, t1));
    }
    *t_entry = t_in;
    *t_exit = t_out;
    return t_in < t_out;
}

bool intersect_box(const ray *r, const ray_derived *d, const aabb *b, float *t_entry)
{
    const float org[3] = {r->org.x, r->org.y, r->org.z}, inv[3] = {d->inv_dir.x, d->inv_dir.y, d->inv_dir.z};
    const float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
    float t_in = r->t_near, t_out = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (d->zero_axes >> a & 1u) {
            /* parallel to the slab: inside it (boundary included) or never */
            if (!(lo[a] <= org[a] && org[a] <= hi[a]))
                return false;
            continue;
        }
        float t0 = (lo[a] - org[a]) * inv[a], t1 = (hi[a] - org[a]) * inv[a];
        t_in = fmaxf(t_in, fminf(t0, t1));
        t_out = fminf(t_out, fmaxf(t0, t1));
    }
    t_out = fminf(t_out * INTERSECT_FAR_SCALE, r->t_far * INTERSECT_CULL_SCALE + d->cull_slack);
    *t_entry = t_in;
    return t_in <= t_out;
}
