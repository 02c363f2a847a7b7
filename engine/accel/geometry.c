/* geometry.c - the affine helpers of geometry.h and the primitive boxes every
 * kind's tree is built from (the kinds themselves: engine/geometry/). */
#include "geometry.h"

#include <math.h>
#include <stdlib.h>

#include "intersect.h"
#include "engine/base/parallel.h"
#include "wbvh.h"

bool affine3_invert(const affine3 *a, affine3 *inverse)
{
    const float *m = a->m;
    for (int i = 0; i < 12; i++)
        if (!isfinite(m[i]))
            return false;
    double l[3][3] = {{m[0], m[1], m[2]}, {m[4], m[5], m[6]}, {m[8], m[9], m[10]}};
    double t[3] = {m[3], m[7], m[11]};
    double c00 = l[1][1] * l[2][2] - l[1][2] * l[2][1], c01 = l[1][2] * l[2][0] - l[1][0] * l[2][2],
           c02 = l[1][0] * l[2][1] - l[1][1] * l[2][0];
    double det = l[0][0] * c00 + l[0][1] * c01 + l[0][2] * c02;
    if (!(fabs(det) > 0.0) || !isfinite(det))
        return false;
    double inv[3][3] = {
        {c00 / det, (l[0][2] * l[2][1] - l[0][1] * l[2][2]) / det, (l[0][1] * l[1][2] - l[0][2] * l[1][1]) / det},
        {c01 / det, (l[0][0] * l[2][2] - l[0][2] * l[2][0]) / det, (l[0][2] * l[1][0] - l[0][0] * l[1][2]) / det},
        {c02 / det, (l[0][1] * l[2][0] - l[0][0] * l[2][1]) / det, (l[0][0] * l[1][1] - l[0][1] * l[1][0]) / det},
    };
    for (int r = 0; r < 3; r++) {
        double shift = -(inv[r][0] * t[0] + inv[r][1] * t[1] + inv[r][2] * t[2]);
        for (int c = 0; c < 3; c++)
            inverse->m[4 * r + c] = (float)inv[r][c];
        inverse->m[4 * r + 3] = (float)shift;
    }
    for (int i = 0; i < 12; i++)
        if (!isfinite(inverse->m[i]))
            return false;
    return true;
}

aabb affine3_box(const affine3 *a, aabb b)
{
    if (aabb_is_empty(b))
        return b;
    aabb out = aabb_empty();
    for (int k = 0; k < 8; k++) {
        vec3 corner = v3(k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z);
        out = aabb_grow_point(out, affine3_point(a, corner));
    }
    /* the corners' rounding: widen by a few ulps of the magnitudes so no
     * transformed point of the box falls outside */
    float mag = fmaxf(fmaxf(fmaxf(fabsf(out.lo.x), fabsf(out.hi.x)), fmaxf(fabsf(out.lo.y), fabsf(out.hi.y))),
                      fmaxf(fabsf(out.lo.z), fabsf(out.hi.z)));
    float pad = mag * 0x1p-20f;
    out.lo = v3_sub(out.lo, v3(pad, pad, pad));
    out.hi = v3_add(out.hi, v3(pad, pad, pad));
    return out;
}

/* Shared by the threads computing primitive boxes. */
typedef struct box_job {
    const geometry_ops *ops;
    const void *data;
    aabb *boxes; /* per primitive; empty for one that can never be hit */
} box_job;

static void prim_boxes(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    box_job *job = ctx;
    for (size_t i = begin; i < end; i++)
        if (!job->ops->prim_bounds(job->data, (uint32_t)i, &job->boxes[i]))
            job->boxes[i] = aabb_empty();
}

/* Primitives per parallel chunk of box computation. */
#define GEOMETRY_BOX_GRAIN 16384

bool geometry_hit_boxes(const geometry_ops *ops, const void *data, int threads, aabb **boxes_out, uint32_t **ids_out,
                        uint32_t *kept_out)
{
    uint32_t count = ops->prim_count(data);
    aabb *boxes = malloc(((size_t)count + 1) * sizeof *boxes);
    uint32_t *ids = malloc(((size_t)count + 1) * sizeof *ids);
    if (!boxes || !ids) {
        free(boxes);
        free(ids);
        return false;
    }
    box_job job = {ops, data, boxes};
    parallel_for(threads, count, GEOMETRY_BOX_GRAIN, prim_boxes, &job);
    /* compact (in order, so the result does not depend on the thread count) */
    uint32_t kept = 0;
    for (uint32_t i = 0; i < count; i++) {
        if (aabb_is_empty(boxes[i]))
            continue;
        boxes[kept] = boxes[i];
        ids[kept++] = i;
    }
    *boxes_out = boxes;
    *ids_out = ids;
    *kept_out = kept;
    return true;
}

const geometry_controls geometry_controls_none = {0};
