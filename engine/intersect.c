#include "intersect.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>


static float component(vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }

/* 1/x, but +-FLT_MAX for a zero x (signed like the zero): then (plane - org) * inv
 * is 0, not NaN, for an origin on a slab plane, and a huge finite number otherwise. */
static float safe_reciprocal(float x) { return x != 0.f ? 1.f / x : copysignf(FLT_MAX, x); }

ray_derived ray_derive(const ray *r)
{
    ray_derived d;
    d.inv_dir = v3(safe_reciprocal(r->dir.x), safe_reciprocal(r->dir.y), safe_reciprocal(r->dir.z));
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

/* Constants of Waechter & Binder's method: near the origin (|p| < 1/32) a fixed
 * offset of 1/65536 along n; elsewhere n scaled by 256 ulps, added in the
 * integer representation so the step grows with |p|. */
#define OFFSET_ORIGIN_BAND (1.f / 32.f)
#define OFFSET_FLOAT_SCALE (1.f / 65536.f)
#define OFFSET_INT_SCALE 256.f

static float offset_component(float p, float n)
{
    int32_t step = (int32_t)(OFFSET_INT_SCALE * n);
    float stepped = bits_float(float_bits(p) + (p < 0.f ? -step : step));
    return fabsf(p) < OFFSET_ORIGIN_BAND ? p + OFFSET_FLOAT_SCALE * n : stepped;
}

vec3 ray_offset_origin(vec3 p, vec3 n)
{
    n = v3_normalize(n);
    return v3(offset_component(p.x, n.x), offset_component(p.y, n.y), offset_component(p.z, n.z));
}

bool intersect_triangle(const ray *r, const ray_derived *d, vec3 v0, vec3 v1, vec3 v2, float *t_out, float *u_out,
                        float *v_out)
{
    vec3 a = v3_sub(v0, r->org), b = v3_sub(v1, r->org), c = v3_sub(v2, r->org);
    float az = component(a, d->kz), bz = component(b, d->kz), cz = component(c, d->kz);
    float ax = component(a, d->kx) - d->shear_x * az, ay = component(a, d->ky) - d->shear_y * az;
    float bx = component(b, d->kx) - d->shear_x * bz, by = component(b, d->ky) - d->shear_y * bz;
    float cx = component(c, d->kx) - d->shear_x * cz, cy = component(c, d->ky) - d->shear_y * cz;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if (u == 0.f || v == 0.f || w == 0.f) {
        /* on an edge in float: decide in double, which is exact for these
         * products of floats, so both triangles sharing the edge agree */
        u = (float)((double)cx * by - (double)cy * bx);
        v = (float)((double)ax * cy - (double)ay * cx);
        w = (float)((double)bx * ay - (double)by * ax);
    }
    if ((u < 0.f || v < 0.f || w < 0.f) && (u > 0.f || v > 0.f || w > 0.f))
        return false;
    float det = u + v + w;
    if (det == 0.f)
        return false; /* ray in the triangle's plane, or a degenerate triangle */
    float tz = u * (d->shear_z * az) + v * (d->shear_z * bz) + w * (d->shear_z * cz);
    float sign = det < 0.f ? -1.f : 1.f;
    float t_scaled = tz * sign, det_abs = det * sign;
    if (!(t_scaled > r->t_near * det_abs) || t_scaled > r->t_far * det_abs)
        return false;
    float inv_det = 1.f / det;
    float t = tz * inv_det;
    /* the scaled comparison can round differently from the division: the
     * interval contract is on t itself */
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

bool intersect_box(const ray *r, const ray_derived *d, const aabb *b, float *t_entry)
{
    float tx0 = (b->lo.x - r->org.x) * d->inv_dir.x, tx1 = (b->hi.x - r->org.x) * d->inv_dir.x;
    float ty0 = (b->lo.y - r->org.y) * d->inv_dir.y, ty1 = (b->hi.y - r->org.y) * d->inv_dir.y;
    float tz0 = (b->lo.z - r->org.z) * d->inv_dir.z, tz1 = (b->hi.z - r->org.z) * d->inv_dir.z;
    float t_in = fmaxf(fmaxf(fminf(tx0, tx1), fminf(ty0, ty1)), fmaxf(fminf(tz0, tz1), r->t_near));
    float t_out = fminf(fminf(fmaxf(tx0, tx1), fmaxf(ty0, ty1)), fmaxf(tz0, tz1)) * INTERSECT_FAR_SCALE;
    t_out = fminf(t_out, r->t_far * INTERSECT_FAR_SCALE);
    *t_entry = t_in;
    return t_in <= t_out;
}
