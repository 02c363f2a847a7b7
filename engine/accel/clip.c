/* clip.c - cutting planes (clip.h): the set of planes that are on, in
 * double, and the exact clipping of a ray's float interval against them. */
#include "clip.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

void clip_set_make(clip_set *out, const clip_plane planes[CLIP_MAX_PLANES])
{
    out->count = 0;
    for (int i = 0; i < CLIP_MAX_PLANES; i++) {
        const clip_plane *p = &planes[i];
        if (!p->on)
            continue;
        double n[3] = {p->normal.x, p->normal.y, p->normal.z};
        double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        /* the transaction layer only lets unit normals and finite points
         * through; a plane that slipped by is skipped rather than poisoning
         * every ray with NaN */
        if (!(length > 0.0) || !isfinite(length) || !v3_is_finite(p->point))
            continue;
        uint32_t k = out->count++;
        for (int a = 0; a < 3; a++)
            out->n[k][a] = n[a] / length;
        out->d[k] = out->n[k][0] * p->point.x + out->n[k][1] * p->point.y + out->n[k][2] * p->point.z;
        out->index[k] = (uint8_t)i;
    }
}

/* The largest float <= x (x not NaN): -inf below -FLT_MAX, FLT_MAX for
 * x in [FLT_MAX, +inf), +inf for +inf. */
static float float_at_most(double x)
{
    float f = (float)x; /* nearest, so at most one step off */
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

/* The largest float < x (x not NaN): -inf for x <= -FLT_MAX (no finite
 * float is below; as an exclusive bound -inf lets every finite t through). */
static float float_below(double x)
{
    float f = (float)x;
    return (double)f >= x ? nextafterf(f, -INFINITY) : f;
}

static double dot_float(const double n[3], vec3 v) { return n[0] * v.x + n[1] * v.y + n[2] * v.z; }

bool clip_ray(const clip_set *c, ray *r, int *entry_plane)
{
    /* Invariant through the loop: a float t satisfies t_near < t <= t_far
     * exactly when it is in r's interval and on the kept side of every plane
     * seen so far (sides judged against tc in double). */
    float t_near = r->t_near, t_far = r->t_far;
    int entry = -1;
    for (uint32_t k = 0; k < c->count; k++) {
        double denom = dot_float(c->n[k], r->dir);     /* kept: t * denom <= num */
        double num = c->d[k] - dot_float(c->n[k], r->org);
        if (isnan(denom) || isnan(num))
            return false; /* a non-finite ray: no side is kept */
        if (denom == 0.0) {
            if (!(num >= 0.0))
                return false; /* parallel, on the removed side */
            continue;         /* parallel, kept whole */
        }
        double tc = num / denom;
        if (isnan(tc))
            return false; /* inf / inf: the ray is nowhere on one side */
        if (denom > 0.0) {
            float bound = float_at_most(tc); /* t kept iff t <= tc iff t <= bound */
            if (bound < t_far)
                t_far = bound;
        } else {
            float bound = float_below(tc); /* t kept iff t >= tc iff t > bound */
            /* strictly greater: on a tie the ray's own bound, then the
             * lowest plane, keeps t_near (planes come in index order) */
            if (bound > t_near) {
                t_near = bound;
                entry = c->index[k];
            }
        }
    }
    /* Empty: no finite float in (t_near, t_far]. When t_near < t_far, t_far
     * itself is in; but (FLT_MAX, +inf] holds only +inf, which no hit has
     * (a plane crossing beyond float range leaves that), so it is empty too. */
    if (!(t_near < t_far) || !(t_near < FLT_MAX))
        return false;
    r->t_near = t_near;
    r->t_far = t_far;
    if (entry_plane)
        *entry_plane = entry;
    return true;
}

bool clip_keeps_point(const clip_set *c, vec3 x)
{
    for (uint32_t k = 0; k < c->count; k++)
        if (!(dot_float(c->n[k], x) <= c->d[k]))
            return false;
    return true;
}

bool clip_crossing(const clip_set *c, int plane, const ray *r, vec3 *point)
{
    for (uint32_t k = 0; k < c->count; k++) {
        if (c->index[k] != plane)
            continue;
        const double *n = c->n[k];
        double denom = dot_float(n, r->dir);
        if (!(denom != 0.0))
            return false; /* parallel (or NaN) */
        double tc = (c->d[k] - dot_float(n, r->org)) / denom;
        double x[3] = {r->org.x + tc * r->dir.x, r->org.y + tc * r->dir.y, r->org.z + tc * r->dir.z};
        /* onto the plane: remove the residual distance along the unit normal */
        double off = n[0] * x[0] + n[1] * x[1] + n[2] * x[2] - c->d[k];
        vec3 p = v3((float)(x[0] - off * n[0]), (float)(x[1] - off * n[1]), (float)(x[2] - off * n[2]));
        if (!v3_is_finite(p))
            return false;
        *point = p;
        return true;
    }
    return false; /* not a plane of c */
}
