/* isa/traverse.c - wide-BVH traversal kernels, compiled once per instruction
 * set (see isa/simd.h); engine/accel/kernels.c picks one table at run time.
 *
 * Single rays: one ray against the 8 child boxes of a node at once (Ize's
 * robust slab test), nearest child first, then 4 triangles at once with the
 * watertight test of Woop, Benthin and Wald (JCGT 2013), evaluated in exactly
 * the operation order of engine/accel/intersect.c so results are bit-identical.
 *
 * Packets: up to 64 rays walk the tree together carrying a 64-bit mask of the
 * rays that reach each node. For packets whose direction signs agree, a whole
 * node is first culled by interval arithmetic over the packet's origins and
 * inverse directions (Boulos et al., "Geometric and Arithmetic Culling Methods
 * for Entire Ray Packets", 2006), one test per child for all rays; surviving
 * children get exact per-ray masks, RAY_LANES rays per vector. Leaves test one
 * triangle against RAY_LANES rays. When a packet has thinned out to a few rays
 * (PACKET_SINGLE_RAY_MAX), those continue as single rays from that node.
 *
 * Ties: a hit replaces the current one when (t, geom_id, prim_id) is smaller in
 * lexicographic order, so the result never depends on the order in which
 * nodes and lanes are visited.
 *
 * Next-hit queries (ray_derived.after_*, PACKET_AFTER_HIT): a hit also has to
 * come after the query's bound in that order (ray_hit_after). The ray's t_near
 * is then the float below the bound's t, so a hit at exactly that t reaches
 * the offer, where the ids decide; primitives that can be met twice (spheres,
 * kinds' own tests) are asked from the bound's t itself when their ids do not
 * come after it, so their second crossing is found. Closest hit only. */
#include "simd.h"

#include <float.h>
#include <math.h>
#include <stdalign.h>
#include <string.h>

#include "engine/base/camera.h"
#include "engine/accel/intersect.h"
#include "engine/accel/kernels.h"
#include "engine/accel/wbvh.h"

/* A packet with at most this many rays left in a subtree continues as single
 * rays: below it, per-ray node tests in lanes cost more than they share (at
 * a triangle leaf the choice is priced per leaf: leaf_single_cheaper).
 * Any-hit queries (occlusion) leave packets earlier: their rays (ambient
 * occlusion's most of all) are incoherent and stop at their first hit, so
 * packets thin out fast. Measured (dragon, 1920x1080, AMD EPYC, 1 thread, 3
 * alternating runs, median frame): the ao renderer at 8 rays, closest-hit
 * threshold 2: 469 / 510 / 522 ms, any-hit 4: 451 / 471 / 487 ms. */
#define PACKET_SINGLE_RAY_MAX 2
#define PACKET_SINGLE_RAY_MAX_ANY 4

/* Stack references: inner node index, or leaf = LEAF bit | first << 4 | (count - 1),
 * where first and count are blocks, or for WBVH_POINTS points (count 1..16). */
#define REF_LEAF 0x80000000u
#define REF_BLOCKS_BITS 4u
_Static_assert(WBVH_MAX_LEAF_FIRST <= (REF_LEAF >> REF_BLOCKS_BITS), "a leaf's first block fits its reference");
_Static_assert(BVH_LEAF_MAX <= (1u << REF_BLOCKS_BITS), "a leaf's count - 1 fits its reference");

static inline uint32_t child_ref(const wbvh_node *n, int i)
{
    return n->leaf_blocks[i] ? REF_LEAF | (n->child[i] << REF_BLOCKS_BITS) | (n->leaf_blocks[i] - 1u) : n->child[i];
}

static inline float lane_float(uint32_t bits)
{
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* ------------------------------------------------------------------------
 * Single ray
 * ------------------------------------------------------------------------ */

/* Child boxes of n the ray enters before t_far (conservatively scaled); their
 * entry distances go to dist[]. An axis the ray is parallel to (zero
 * direction component) constrains by containment, boundary included. */
static inline unsigned node_hit1(const wbvh_node *n, const ray *r, const ray_derived *d, float dist[WBVH_WIDTH])
{
    const float *lo[3] = {n->lo_x, n->lo_y, n->lo_z}, *hi[3] = {n->hi_x, n->hi_y, n->hi_z};
    const float org[3] = {r->org.x, r->org.y, r->org.z}, inv[3] = {d->inv_dir.x, d->inv_dir.y, d->inv_dir.z};
    const vn scale = vn_set1(INTERSECT_FAR_SCALE);
    unsigned bits = 0;
    if (d->zero_axes == 0) { /* the common case: three slabs */
        const bool neg_x = inv[0] < 0.f, neg_y = inv[1] < 0.f, neg_z = inv[2] < 0.f;
        const float *near_x = neg_x ? n->hi_x : n->lo_x, *far_x = neg_x ? n->lo_x : n->hi_x;
        const float *near_y = neg_y ? n->hi_y : n->lo_y, *far_y = neg_y ? n->lo_y : n->hi_y;
        const float *near_z = neg_z ? n->hi_z : n->lo_z, *far_z = neg_z ? n->lo_z : n->hi_z;
        const vn ox = vn_set1(org[0]), oy = vn_set1(org[1]), oz = vn_set1(org[2]);
        const vn ix = vn_set1(inv[0]), iy = vn_set1(inv[1]), iz = vn_set1(inv[2]);
        const vn t_near = vn_set1(r->t_near), t_far = vn_set1(r->t_far * INTERSECT_CULL_SCALE + d->cull_slack);
        for (int h = 0; h < WBVH_WIDTH; h += NODE_LANES) {
            vn enter = vn_max(vn_max(vn_mul(vn_sub(vn_load(near_x + h), ox), ix),
                                     vn_mul(vn_sub(vn_load(near_y + h), oy), iy)),
                              vn_max(vn_mul(vn_sub(vn_load(near_z + h), oz), iz), t_near));
            vn leave = vn_min(vn_mul(vn_min(vn_min(vn_mul(vn_sub(vn_load(far_x + h), ox), ix),
                                                   vn_mul(vn_sub(vn_load(far_y + h), oy), iy)),
                                            vn_mul(vn_sub(vn_load(far_z + h), oz), iz)),
                                     scale),
                              t_far);
            bits |= vn_le_bits(enter, leave) << h;
            vn_store(dist + h, enter);
        }
        return bits & n->child_mask;
    }
    for (int h = 0; h < WBVH_WIDTH; h += NODE_LANES) {
        vn enter = vn_set1(r->t_near), leave = vn_set1(INFINITY);
        unsigned inside = (1u << NODE_LANES) - 1u;
        for (int a = 0; a < 3; a++) {
            vn o = vn_set1(org[a]);
            vn l = vn_load(lo[a] + h), u = vn_load(hi[a] + h);
            if (d->zero_axes >> a & 1u) {
                inside &= vn_le_bits(l, o) & vn_le_bits(o, u);
                continue;
            }
            vn i = vn_set1(inv[a]);
            vn t0 = vn_mul(vn_sub(l, o), i), t1 = vn_mul(vn_sub(u, o), i);
            enter = vn_max(enter, vn_min(t0, t1));
            leave = vn_min(leave, vn_max(t0, t1));
        }
        leave = vn_min(vn_mul(leave, scale), vn_set1(r->t_far * INTERSECT_CULL_SCALE + d->cull_slack));
        bits |= (vn_le_bits(enter, leave) & inside) << h;
        vn_store(dist + h, enter);
    }
    return bits & n->child_mask;
}

/* Absolute cull margin of ray r for the geometry of w (intersect.h). */
static inline float max3_abs(vec3 a)
{
    float x = fabsf(a.x), y = fabsf(a.y), z = fabsf(a.z);
    float m = x > y ? x : y;
    return m > z ? m : z;
}

static inline float ray_cull_slack(const ray *r, const wbvh *w)
{
    return intersect_cull_slack(max3_abs(r->org), max3_abs(r->dir), w->coord_abs_max);
}

/* Record a hit if it beats the current one. */
static inline bool offer1(ray *r, const ray_derived *d, hit *h, float t, float u, float v, uint32_t geom_id,
                          uint32_t prim)
{
    if (!hit_comes_first(t, geom_id, prim, h->t, h->geom_id, h->prim_id) || !ray_hit_after(d, t, geom_id, prim))
        return false;
    *h = (hit){.t = t, .u = u, .v = v, .prim_id = prim, .geom_id = geom_id};
    r->t_far = t;
    return true;
}

/* A stand-in vertex for the unused lanes of a 4-triangle test (their ids are
 * invalid: they never report a hit). */
static const float zero_vertex[3];

/* Coordinate `axis` of the four vertices p[0..3], one per lane. Loaded into
 * the register lane by lane: a block written to memory and read back as
 * vectors stalled on store forwarding (9 vectors a block). */
static inline v4 lanes_of(const float *const p[WBVH_BLOCK], int axis)
{
    return _mm_setr_ps(p[0][axis], p[1][axis], p[2][axis], p[3][axis]);
}

/* One ray against 4 triangles of a mesh leaf, corners p0[i], p1[i], p2[i] of
 * lane i (zero_vertex in unused lanes), id ids[i], for the lanes of
 * `valid`. Returns whether a hit was recorded (any: found). */
static bool triangles4_1(const float *const p0[WBVH_BLOCK], const float *const p1[WBVH_BLOCK],
                         const float *const p2[WBVH_BLOCK], const uint32_t ids[WBVH_BLOCK], unsigned valid,
                         uint32_t geom_id, ray *r,
                         const ray_derived *d, hit *h, bool any)
{
    const float org[3] = {r->org.x, r->org.y, r->org.z};
    const int kx = d->kx, ky = d->ky, kz = d->kz;
    const v4 okx = v4_set1(org[kx]), oky = v4_set1(org[ky]), okz = v4_set1(org[kz]);
    const v4 sx = v4_set1(d->shear_x), sy = v4_set1(d->shear_y), sz = v4_set1(d->shear_z);
    const v4 az = v4_sub(lanes_of(p0, kz), okz), bz = v4_sub(lanes_of(p1, kz), okz), cz = v4_sub(lanes_of(p2, kz), okz);
    const v4 akx = v4_sub(lanes_of(p0, kx), okx), aky = v4_sub(lanes_of(p0, ky), oky);
    const v4 bkx = v4_sub(lanes_of(p1, kx), okx), bky = v4_sub(lanes_of(p1, ky), oky);
    const v4 ckx = v4_sub(lanes_of(p2, kx), okx), cky = v4_sub(lanes_of(p2, ky), oky);
    const v4 ax = v4_sub(akx, v4_mul(sx, az)), ay = v4_sub(aky, v4_mul(sy, az));
    const v4 bx = v4_sub(bkx, v4_mul(sx, bz)), by = v4_sub(bky, v4_mul(sy, bz));
    const v4 cx = v4_sub(ckx, v4_mul(sx, cz)), cy = v4_sub(cky, v4_mul(sy, cz));
    const v4 u = v4_sub(v4_mul(cx, by), v4_mul(cy, bx));
    const v4 v = v4_sub(v4_mul(ax, cy), v4_mul(ay, cx));
    const v4 w = v4_sub(v4_mul(bx, ay), v4_mul(by, ax));
#ifndef TESSERA_UNROBUST
    const v4 zero = v4_set1(0.f), tol = v4_set1(INTERSECT_EDGE_TOL);
    const v4 ma = v4_add(v4_add(v4_abs(akx), v4_abs(aky)), v4_abs(az));
    const v4 mb = v4_add(v4_add(v4_abs(bkx), v4_abs(bky)), v4_abs(bz));
    const v4 mc = v4_add(v4_add(v4_abs(ckx), v4_abs(cky)), v4_abs(cz));
    /* an edge sign float cannot vouch for: those lanes are decided by the scalar test, in double */
    const v4 pa = v4_add(v4_abs(ax), v4_abs(ay)), pb = v4_add(v4_abs(bx), v4_abs(by));
    const v4 pc = v4_add(v4_abs(cx), v4_abs(cy));
    const unsigned on_edge =
        v4_bits(v4_or(v4_or(v4_le(v4_abs(u), v4_mul(tol, v4_add(v4_mul(mc, pb), v4_mul(mb, pc)))),
                            v4_le(v4_abs(v), v4_mul(tol, v4_add(v4_mul(ma, pc), v4_mul(mc, pa))))),
                      v4_le(v4_abs(w), v4_mul(tol, v4_add(v4_mul(mb, pa), v4_mul(ma, pb)))))) &
        valid;
#else
    const v4 zero = v4_set1(0.f);
    const unsigned on_edge = 0u; /* fast build (intersect.h): float decides every edge */
#endif
    const v4 any_neg = v4_or(v4_or(v4_lt(u, zero), v4_lt(v, zero)), v4_lt(w, zero));
    const v4 any_pos = v4_or(v4_or(v4_gt(u, zero), v4_gt(v, zero)), v4_gt(w, zero));
    const v4 det = v4_add(v4_add(u, v), w);
    const v4 tz = v4_add(v4_add(v4_mul(u, v4_mul(sz, az)), v4_mul(v, v4_mul(sz, bz))), v4_mul(w, v4_mul(sz, cz)));
    const v4 t_near = v4_set1(r->t_near), t_far = v4_set1(r->t_far);
    const v4 inv_det = v4_div(v4_set1(1.f), det);
    const v4 t = v4_mul(tz, inv_det);
    v4 ok = v4_andnot(v4_and(v4_gt(t, t_near), v4_le(t, t_far)), v4_and(any_neg, any_pos));
    ok = v4_andnot(ok, v4_eq(det, zero));
    unsigned hits = v4_bits(ok) & valid & ~on_edge;
    if (!hits && !on_edge)
        return false;
    if (any && hits)
        return true;
    alignas(16) float t_lane[4], u_lane[4], v_lane[4];
    _mm_store_ps(t_lane, t);
    _mm_store_ps(u_lane, v4_mul(v, inv_det));
    _mm_store_ps(v_lane, v4_mul(w, inv_det));
    bool found = false;
    for (int i = 0; i < WBVH_BLOCK; i++) {
        if (hits >> i & 1u)
            found |= offer1(r, d, h, t_lane[i], u_lane[i], v_lane[i], geom_id, ids[i]);
        else if (on_edge >> i & 1u) {
            float te, ue, ve;
            if (intersect_triangle(r, d, v3(p0[i][0], p0[i][1], p0[i][2]), v3(p1[i][0], p1[i][1], p1[i][2]),
                                   v3(p2[i][0], p2[i][1], p2[i][2]), &te, &ue, &ve)) {
                if (any)
                    return true;
                found |= offer1(r, d, h, te, ue, ve, geom_id, ids[i]);
            }
        }
    }
    return found;
}

/* The ray a primitive that may be met twice is tested with: under a
 * next-hit bound its ids do not pass at the bound's t, so only crossings
 * beyond that t count (t_near = after_t, exclusive). */
static inline const ray *prim_query_ray(const ray *r, const ray_derived *d, uint32_t geom_id, uint32_t prim, ray *scratch)
{
    if (d->after_t == -INFINITY || ray_hit_after(d, d->after_t, geom_id, prim) || !(r->t_near < d->after_t))
        return r;
    *scratch = *r;
    scratch->t_near = d->after_t;
    return scratch;
}

/* One ray against up to 4 spheres (scalar: spheres are not the hot path yet). */
static bool sphere_block1(const wbvh_sphere_block *b, uint32_t geom_id, ray *r, const ray_derived *d, hit *h, bool any)
{
    bool found = false;
    for (int i = 0; i < WBVH_BLOCK; i++) {
        if (b->prim_id[i] == RAY_INVALID_ID)
            continue;
        float t;
        ray scratch;
        const ray *q = prim_query_ray(r, d, geom_id, b->prim_id[i], &scratch);
        if (q->t_near < r->t_far && intersect_sphere(q, v3(b->cx[i], b->cy[i], b->cz[i]), b->r[i], &t)) {
            if (any)
                return true;
            found |= offer1(r, d, h, t, 0.f, 0.f, geom_id, b->prim_id[i]);
        }
    }
    return found;
}

/* One ray against up to 4 primitives of a kind without a SIMD layout: its
 * scalar `intersect`. */
static bool prim_block1(const wbvh *w, const wbvh_prim_block *b, uint32_t geom_id, ray *r, const ray_derived *d, hit *h,
                        bool any)
{
    bool found = false;
    for (int i = 0; i < WBVH_BLOCK; i++) {
        if (b->prim_id[i] == RAY_INVALID_ID)
            continue;
        float t, u, v;
        ray scratch;
        const ray *q = prim_query_ray(r, d, geom_id, b->prim_id[i], &scratch);
        if (q->t_near < r->t_far && w->ops->intersect(w->data, b->prim_id[i], q, &t, &u, &v)) {
            if (any)
                return true;
            found |= offer1(r, d, h, t, u, v, geom_id, b->prim_id[i]);
        }
    }
    return found;
}

/* The children of a WBVH_POINTS node that hold a point inside the crop
 * range (all of them without a crop). */
static inline unsigned crop_children(const wbvh *w, uint32_t node)
{
    const geometry_crop *crop = w->points.crop;
    if (!crop->active)
        return 0xFFu;
    const float *lo = w->crop_lo + (size_t)node * WBVH_WIDTH, *hi = w->crop_hi + (size_t)node * WBVH_WIDTH;
    unsigned bits = 0;
    for (int i = 0; i < WBVH_WIDTH; i++)
        bits |= (unsigned)(lo[i] <= crop->hi && hi[i] >= crop->lo) << i;
    return bits;
}

/* Whether point p is seen under the crop. */
static inline bool point_seen(const geometry_points *pt, uint32_t p)
{
    return !pt->crop_value || !pt->crop->active || (pt->crop->lo <= pt->crop_value[p] && pt->crop_value[p] <= pt->crop->hi);
}

/* One ray against points [first, first + count) under a next-hit bound: one
 * at a time, each from the bound's t when its ids do not come after it. */
static bool points_leaf1_after(const wbvh *w, uint32_t first, uint32_t count, uint32_t geom_id, ray *r,
                               const ray_derived *d, hit *h)
{
    const geometry_points *pt = &w->points;
    bool found = false;
    for (uint32_t p = first; p < first + count; p++) {
        if (!point_seen(pt, p))
            continue;
        float t;
        ray scratch;
        const ray *q = prim_query_ray(r, d, geom_id, p, &scratch);
        float radius = pt->radius ? pt->radius[p] : pt->radius_all;
        if (q->t_near < r->t_far && intersect_sphere(q, v3(pt->x[p], pt->y[p], pt->z[p]), radius, &t))
            found |= offer1(r, d, h, t, 0.f, 0.f, geom_id, p);
    }
    return found;
}

/* One ray against the points [first, first + count) of a WBVH_POINTS tree,
 * RAY_LANES spheres per instruction, read in place (the arrays are padded:
 * lanes past the range load defined values and are masked off). The
 * arithmetic is intersect_sphere's, operation for operation and in the same
 * order, so hits equal the scalar test's bit for bit. */
static bool points_leaf1(const wbvh *w, uint32_t first, uint32_t count, uint32_t geom_id, ray *r,
                         const ray_derived *d, hit *h, bool any)
{
    if (d->after_t != -INFINITY && !any)
        return points_leaf1_after(w, first, count, geom_id, r, d, h);
    const geometry_points *pt = &w->points;
    const float a_s = v3_dot(r->dir, r->dir);
    const vr a = vr_set1(a_s), dx = vr_set1(r->dir.x), dy = vr_set1(r->dir.y), dz = vr_set1(r->dir.z);
    const vr ox = vr_set1(r->org.x), oy = vr_set1(r->org.y), oz = vr_set1(r->org.z), zero = vr_set1(0.f);
    const bool cropping = pt->crop_value && pt->crop->active;
    bool found = false;
    for (uint32_t base = first; base < first + count; base += RAY_LANES) {
        const uint32_t n = first + count - base < RAY_LANES ? first + count - base : RAY_LANES;
        unsigned valid = n >= 32 ? ~0u : (1u << n) - 1u;
        if (cropping) {
            const vr v = vr_loadu(pt->crop_value + base);
            valid &= vm_bits(vm_and(vr_le(vr_set1(pt->crop->lo), v), vr_le(v, vr_set1(pt->crop->hi))));
            if (!valid)
                continue;
        }
        const vr rad = pt->radius ? vr_loadu(pt->radius + base) : vr_set1(pt->radius_all);
        const vr fx = vr_sub(ox, vr_loadu(pt->x + base)), fy = vr_sub(oy, vr_loadu(pt->y + base)),
                 fz = vr_sub(oz, vr_loadu(pt->z + base));
        const vr b_half = vr_add(vr_add(vr_mul(fx, dx), vr_mul(fy, dy)), vr_mul(fz, dz));
        const vr s = vr_div(b_half, a);
        const vr lx = vr_sub(fx, vr_mul(dx, s)), ly = vr_sub(fy, vr_mul(dy, s)), lz = vr_sub(fz, vr_mul(dz, s));
        const vr rr = vr_mul(rad, rad);
        const vr disc = vr_mul(a, vr_sub(rr, vr_add(vr_add(vr_mul(lx, lx), vr_mul(ly, ly)), vr_mul(lz, lz))));
        valid &= ~vm_bits(vr_lt(disc, zero));
        if (!valid)
            continue;
        const vr c = vr_sub(vr_add(vr_add(vr_mul(fx, fx), vr_mul(fy, fy)), vr_mul(fz, fz)), rr);
        const vr q = vr_neg(vr_add(b_half, vr_copysign(vr_sqrt(disc), b_half)));
        const vm q_zero = vr_eq(q, zero);
        const vr t0 = vr_select(q_zero, zero, vr_div(c, q)), t1 = vr_select(q_zero, zero, vr_div(q, a));
        const vm swap = vr_gt(t0, t1);
        const vr lo = vr_select(swap, t1, t0), hi = vr_select(swap, t0, t1);
        const vr tn = vr_set1(r->t_near), tf = vr_set1(r->t_far);
        const vm in_lo = vm_and(vr_gt(lo, tn), vr_le(lo, tf)), in_hi = vm_and(vr_gt(hi, tn), vr_le(hi, tf));
        unsigned hits = valid & vm_bits(vm_or(in_lo, in_hi));
        if (!hits)
            continue;
        if (any)
            return true;
        alignas(64) float t[RAY_LANES];
        vr_store(t, vr_select(in_lo, lo, hi));
        for (; hits; hits &= hits - 1u) {
            int lane = __builtin_ctz(hits);
            found |= offer1(r, d, h, t[lane], 0.f, 0.f, geom_id, base + (uint32_t)lane);
        }
    }
    return found;
}

static bool traverse1(const wbvh *w, uint32_t ref, uint32_t geom_id, ray *r, const ray_derived *d_in, hit *h, bool any);

/* One ray against a WBVH_MESH leaf: its triangles tested 4 at a time
 * (triangles4_1), in intersect_triangle's operations (the same bits as the
 * packet path and the scalar reference). */
static bool mesh_leaf1(const wbvh *w, uint32_t first, uint32_t count, uint32_t geom_id, ray *r, const ray_derived *d,
                       hit *h, bool any)
{
    const float *pos = w->mesh.positions;
    const uint32_t *canon = w->mesh.canon; /* NULL: a triangle's id is its place */
    bool found = false;
    for (uint32_t k = first; k < first + count; k += WBVH_BLOCK) {
        const float *p0[WBVH_BLOCK], *p1[WBVH_BLOCK], *p2[WBVH_BLOCK];
        uint32_t ids[WBVH_BLOCK] = {RAY_INVALID_ID, RAY_INVALID_ID, RAY_INVALID_ID, RAY_INVALID_ID};
        const uint32_t lanes = first + count - k < WBVH_BLOCK ? first + count - k : WBVH_BLOCK;
        for (uint32_t lane = 0; lane < WBVH_BLOCK; lane++) {
            if (lane >= lanes) {
                p0[lane] = p1[lane] = p2[lane] = zero_vertex;
                continue;
            }
            const uint32_t prim = k + lane, *idx = w->mesh.indices + 3 * (size_t)prim;
            p0[lane] = pos + 3 * (size_t)idx[0];
            p1[lane] = pos + 3 * (size_t)idx[1];
            p2[lane] = pos + 3 * (size_t)idx[2];
            ids[lane] = canon ? canon[prim] : prim;
        }
        if (triangles4_1(p0, p1, p2, ids, (1u << lanes) - 1u, geom_id, r, d, h, any)) {
            if (any)
                return true;
            found = true;
        }
    }
    return found;
}

static inline bool instance_hidden(const wbvh *w, uint32_t id)
{
    return atomic_load_explicit(&w->hidden[id], memory_order_relaxed) != 0;
}

/* One ray against up to 4 instances: down into each geometry's tree. */
static bool instance_block1(const wbvh *w, const wbvh_prim_block *b, ray *r, const ray_derived *d, hit *h, bool any)
{
    bool found = false;
    for (int i = 0; i < WBVH_BLOCK; i++) {
        uint32_t id = b->prim_id[i];
        if (id == RAY_INVALID_ID || instance_hidden(w, id))
            continue;
        const wbvh_instance *inst = &w->instances[id];
        if (inst->geometry->node_count == 0)
            continue;
        bool hit_here;
        if (inst->identity) {
            hit_here = traverse1(inst->geometry, 0, id, r, d, h, any);
        } else {
            ray local = affine3_ray(&inst->to_object, r);
            if (ray_is_degenerate(&local))
                continue;
            ray_derived ld = ray_derive(&local);
            ld.after_t = d->after_t, ld.after_geom = d->after_geom, ld.after_prim = d->after_prim;
            hit_here = traverse1(inst->geometry, 0, id, &local, &ld, h, any);
            if (hit_here && !any)
                r->t_far = local.t_far;
        }
        if (hit_here && any)
            return true;
        found |= hit_here;
    }
    return found;
}

/* The one switch on the kind of leaf in the single-ray loop. */
static bool leaf1(const wbvh *w, uint32_t ref, uint32_t geom_id, ray *r, const ray_derived *d, hit *h, bool any)
{
    uint32_t first = (ref & ~REF_LEAF) >> REF_BLOCKS_BITS, count = (ref & ((1u << REF_BLOCKS_BITS) - 1u)) + 1u;
    if (w->kind == WBVH_POINTS)
        return points_leaf1(w, first, count, geom_id, r, d, h, any);
    if (w->kind == WBVH_MESH)
        return mesh_leaf1(w, first, count, geom_id, r, d, h, any);
    bool found = false;
    for (uint32_t k = first; k < first + count; k++) {
        bool hit_here;
        switch (w->kind) {
        case WBVH_SPHERES:
            hit_here = sphere_block1((const wbvh_sphere_block *)w->blocks + k, geom_id, r, d, h, any);
            break;
        case WBVH_PRIMS: hit_here = prim_block1(w, (const wbvh_prim_block *)w->blocks + k, geom_id, r, d, h, any); break;
        case WBVH_INSTANCES:
        default: hit_here = instance_block1(w, (const wbvh_prim_block *)w->blocks + k, r, d, h, any); break;
        }
        if (hit_here && any)
            return true;
        found |= hit_here;
    }
    return found;
}

typedef struct stack_entry1 {
    uint32_t ref;
    float dist; /* entry distance of the box when pushed */
} stack_entry1;

/* Traverse the subtree at `ref` with one ray. */
static bool traverse1(const wbvh *w, uint32_t ref, uint32_t geom_id, ray *r, const ray_derived *d_in, hit *h, bool any)
{
    ray_derived d_local = *d_in;
    const ray_derived *d = &d_local;
    d_local.cull_slack = ray_cull_slack(r, w);
    stack_entry1 stack[WBVH_STACK_SIZE];
    int top = 0;
    bool found = false;
    for (;;) {
        if (ref & REF_LEAF) {
            if (leaf1(w, ref, geom_id, r, d, h, any)) {
                if (any)
                    return true;
                found = true;
            }
        } else {
            const wbvh_node *n = &w->nodes[ref];
            alignas(32) float dist[WBVH_WIDTH];
            unsigned bits = node_hit1(n, r, d, dist);
            if (w->crop_lo)
                bits &= crop_children(w, ref);
            if (bits) {
                int i = __builtin_ctz(bits);
                bits &= bits - 1u;
                if (!bits) { /* one child: no ordering needed */
                    ref = child_ref(n, i);
                    continue;
                }
                /* several: push all, sorted so the nearest ends on top, then pop it */
                int base = top;
                stack[top++] = (stack_entry1){child_ref(n, i), dist[i]};
                while (bits) {
                    i = __builtin_ctz(bits);
                    bits &= bits - 1u;
                    stack_entry1 e = {child_ref(n, i), dist[i]};
                    int j = top++;
                    while (j > base && stack[j - 1].dist < e.dist) {
                        stack[j] = stack[j - 1];
                        j--;
                    }
                    stack[j] = e;
                }
            }
        }
        const float cull = r->t_far * INTERSECT_CULL_SCALE + d->cull_slack;
        do {
            if (top == 0)
                return found;
            top--;
        } while (stack[top].dist > cull);
        ref = stack[top].ref;
    }
}

static bool ISA_SUFFIX(intersect1)(const wbvh *w, uint32_t geom_id, ray *r, const ray_derived *d, hit *h, bool any)
{
    if (w->node_count == 0)
        return false;
    return traverse1(w, 0, geom_id, r, d, h, any);
}

/* ------------------------------------------------------------------------
 * Packets
 * ------------------------------------------------------------------------ */

/* The 6 axis orders of the watertight test (kz, and kx/ky swapped by sign). */
#define AXIS_ORDERS 6

typedef struct packet_ctx {
    ray_packet *p;
    const wbvh *w;
    uint32_t geom_id;
    bool any;
    uint64_t done;     /* any-hit: rays found occluded (no longer traced) */
    uint64_t improved; /* closest-hit: rays whose hit changed */
    /* watertight test setup, per ray (lanes beyond the packet's rays are 0) */
    alignas(64) float shear_x[PACKET_MAX_RAYS];
    alignas(64) float shear_y[PACKET_MAX_RAYS];
    alignas(64) float shear_z[PACKET_MAX_RAYS];
    ray_derived derived[PACKET_MAX_RAYS]; /* ray_derive of each ray, for single-ray continuation */
    uint64_t order_mask[AXIS_ORDERS]; /* rays using axis order k */
    int order_axes[AXIS_ORDERS][3];   /* kx, ky, kz of order k */
    int order_count;
    bool shear_ready;   /* the fields above are set up (lazily, at the first packet leaf) */
    uint64_t shear_rays; /* the rays they were set up for */
    alignas(64) float slack[PACKET_MAX_RAYS]; /* per-ray cull slack for this geometry */
    float slack_hi;                           /* the largest of them */
    /* axes along which some ray of the packet has a zero direction component */
    unsigned zero_axes;
    /* interval culling: valid when every direction component has one sign */
    bool interval;
    float org_lo[3], org_hi[3];
    float inv_lo[3], inv_hi[3];
    float t_near_lo;
} packet_ctx;

static void setup_shear(packet_ctx *c, uint64_t mask)
{
    ray_packet *p = c->p;
    memset(c->shear_x, 0, sizeof c->shear_x);
    memset(c->shear_y, 0, sizeof c->shear_y);
    memset(c->shear_z, 0, sizeof c->shear_z);
    c->order_count = 0;
    for (uint64_t m = mask; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        ray one = packet_get_ray(p, i);
        ray_derived d = ray_derive(&one);
        if (p->flags & PACKET_AFTER_HIT)
            d.after_t = p->after_t[i], d.after_geom = p->after_geom[i], d.after_prim = p->after_prim[i];
        c->derived[i] = d;
        c->shear_x[i] = d.shear_x;
        c->shear_y[i] = d.shear_y;
        c->shear_z[i] = d.shear_z;
        int k = 0;
        while (k < c->order_count &&
               !(c->order_axes[k][0] == d.kx && c->order_axes[k][1] == d.ky && c->order_axes[k][2] == d.kz))
            k++;
        if (k == c->order_count) {
            c->order_axes[k][0] = d.kx, c->order_axes[k][1] = d.ky, c->order_axes[k][2] = d.kz;
            c->order_mask[k] = 0;
            c->order_count++;
        }
        c->order_mask[k] |= 1ull << i;
    }
}

/* Smallest / largest of the lanes of `mask` in array v (plain compares: the
 * libm fminf/fmaxf are calls, and no NaN reaches here). */
static void lanes_range(const float *v, uint64_t mask, float *lo, float *hi)
{
    vr vlo = vr_set1(INFINITY), vhi = vr_set1(-INFINITY);
    for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
        unsigned lanes = (unsigned)(mask >> g) & ((1u << RAY_LANES) - 1u);
        if (!lanes)
            continue;
        vm m = vm_from_bits(lanes);
        vr x = vr_load(v + g);
        vlo = vr_min(vlo, vr_select(m, x, vr_set1(INFINITY)));
        vhi = vr_max(vhi, vr_select(m, x, vr_set1(-INFINITY)));
    }
    alignas(64) float l[RAY_LANES], h[RAY_LANES];
    vr_store(l, vlo);
    vr_store(h, vhi);
    *lo = l[0];
    *hi = h[0];
    for (int i = 1; i < RAY_LANES; i++) {
        *lo = l[i] < *lo ? l[i] : *lo;
        *hi = h[i] > *hi ? h[i] : *hi;
    }
}

static void setup_interval(packet_ctx *c, uint64_t mask)
{
    const ray_packet *p = c->p;
    const float *src[7] = {p->t_near, p->org_x, p->org_y, p->org_z, p->inv_dir_x, p->inv_dir_y, p->inv_dir_z};
    /* one pass over the rays for all seven ranges */
    vr lo[7], hi[7];
    for (int k = 0; k < 7; k++) {
        lo[k] = vr_set1(INFINITY);
        hi[k] = vr_set1(-INFINITY);
    }
    for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
        unsigned lanes = (unsigned)(mask >> g) & ((1u << RAY_LANES) - 1u);
        if (!lanes)
            continue;
        vm m = vm_from_bits(lanes);
        for (int k = 0; k < 7; k++) {
            vr x = vr_load(src[k] + g);
            lo[k] = vr_min(lo[k], vr_select(m, x, vr_set1(INFINITY)));
            hi[k] = vr_max(hi[k], vr_select(m, x, vr_set1(-INFINITY)));
        }
    }
    float range_lo[7], range_hi[7];
    for (int k = 0; k < 7; k++) {
        alignas(64) float l[RAY_LANES], h[RAY_LANES];
        vr_store(l, lo[k]);
        vr_store(h, hi[k]);
        range_lo[k] = l[0];
        range_hi[k] = h[0];
        for (int i = 1; i < RAY_LANES; i++) {
            range_lo[k] = l[i] < range_lo[k] ? l[i] : range_lo[k];
            range_hi[k] = h[i] > range_hi[k] ? h[i] : range_hi[k];
        }
    }
    c->t_near_lo = range_lo[0];
    c->interval = true;
    c->zero_axes = 0;
    for (int a = 0; a < 3; a++) {
        c->org_lo[a] = range_lo[1 + a], c->org_hi[a] = range_hi[1 + a];
        c->inv_lo[a] = range_lo[4 + a], c->inv_hi[a] = range_hi[4 + a];
        if ((c->inv_lo[a] < 0.f) != (c->inv_hi[a] < 0.f))
            c->interval = false; /* the inverse directions straddle 0: the interval is everything */
        /* +-FLT_MAX stands for a zero component: that axis is tested by containment */
        if (c->inv_lo[a] == -FLT_MAX || c->inv_hi[a] == FLT_MAX)
            c->zero_axes |= 1u << a;
    }
}

static void setup_slack(packet_ctx *c, uint64_t mask)
{
    const ray_packet *p = c->p;
    c->slack_hi = 0.f;
    memset(c->slack, 0, sizeof c->slack);
    for (uint64_t rest = mask; rest; rest &= rest - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(rest);
        ray one = {v3(p->org_x[i], p->org_y[i], p->org_z[i]), v3(p->dir_x[i], p->dir_y[i], p->dir_z[i]), 0.f, 0.f};
        c->slack[i] = ray_cull_slack(&one, c->w);
        c->slack_hi = c->slack[i] > c->slack_hi ? c->slack[i] : c->slack_hi;
    }
}

/* Range of (plane - org) * inv over the packet's origin and inverse-direction intervals. */
static inline void interval_product(vn plane, float org_lo, float org_hi, float inv_lo, float inv_hi, vn *lo, vn *hi)
{
    vn d_lo = vn_sub(plane, vn_set1(org_hi)), d_hi = vn_sub(plane, vn_set1(org_lo));
    vn i_lo = vn_set1(inv_lo), i_hi = vn_set1(inv_hi);
    vn p0 = vn_mul(d_lo, i_lo), p1 = vn_mul(d_lo, i_hi), p2 = vn_mul(d_hi, i_lo), p3 = vn_mul(d_hi, i_hi);
    *lo = vn_min(vn_min(p0, p1), vn_min(p2, p3));
    *hi = vn_max(vn_max(p0, p1), vn_max(p2, p3));
}

/* Children that some ray of the packet may enter before t_far_hi (one test
 * for all rays); lower bounds of their entry distances go to dist[]. */
static unsigned node_interval(const packet_ctx *c, const wbvh_node *n, float t_far_hi, float dist[WBVH_WIDTH])
{
    const float *lo[3] = {n->lo_x, n->lo_y, n->lo_z}, *hi[3] = {n->hi_x, n->hi_y, n->hi_z};
    unsigned bits = 0;
    for (int h = 0; h < WBVH_WIDTH; h += NODE_LANES) {
        vn enter = vn_set1(c->t_near_lo), leave = vn_set1(INFINITY);
        for (int a = 0; a < 3; a++) {
            if (c->zero_axes >> a & 1u)
                continue; /* no bound from an axis some ray runs parallel to */
            bool neg = c->inv_lo[a] < 0.f;
            vn near = vn_load((neg ? hi[a] : lo[a]) + h), far = vn_load((neg ? lo[a] : hi[a]) + h);
            vn near_lo, near_hi, far_lo, far_hi;
            interval_product(near, c->org_lo[a], c->org_hi[a], c->inv_lo[a], c->inv_hi[a], &near_lo, &near_hi);
            interval_product(far, c->org_lo[a], c->org_hi[a], c->inv_lo[a], c->inv_hi[a], &far_lo, &far_hi);
            enter = vn_max(enter, near_lo);
            leave = vn_min(leave, far_hi);
        }
        leave = vn_min(vn_mul(leave, vn_set1(INTERSECT_FAR_SCALE)), vn_set1(t_far_hi * INTERSECT_CULL_SCALE + c->slack_hi));
        bits |= vn_le_bits(enter, leave) << h;
        vn_store(dist + h, enter);
    }
    return bits & n->child_mask;
}

/* Exact per-ray masks of the rays in `mask` that enter each child in `children`. */
static void node_rays(const packet_ctx *c, const wbvh_node *n, unsigned children, uint64_t mask,
                      uint64_t child_mask[WBVH_WIDTH])
{
    const ray_packet *p = c->p;
    const vr scale = vr_set1(INTERSECT_FAR_SCALE);
    const float *org[3] = {p->org_x, p->org_y, p->org_z}, *inv[3] = {p->inv_dir_x, p->inv_dir_y, p->inv_dir_z};
    const float *dir[3] = {p->dir_x, p->dir_y, p->dir_z};
    const float *lo[3] = {n->lo_x, n->lo_y, n->lo_z}, *hi[3] = {n->hi_x, n->hi_y, n->hi_z};
    for (int i = 0; i < WBVH_WIDTH; i++)
        child_mask[i] = 0;
    for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
        unsigned lanes = (unsigned)(mask >> g) & ((1u << RAY_LANES) - 1u);
        if (!lanes)
            continue;
        vr o[3], iv[3];
        vm parallel[3]; /* lanes whose direction is zero on the axis: containment instead */
        for (int a = 0; a < 3; a++) {
            o[a] = vr_load(org[a] + g);
            iv[a] = vr_load(inv[a] + g);
            if (c->zero_axes >> a & 1u)
                parallel[a] = vr_eq(vr_load(dir[a] + g), vr_set1(0.f));
        }
        const vr t_near = vr_load(p->t_near + g);
        const vr t_far = vr_add(vr_mul(vr_load(p->t_far + g), vr_set1(INTERSECT_CULL_SCALE)), vr_load(c->slack + g));
        for (unsigned cm = children; cm; cm &= cm - 1u) {
            int i = __builtin_ctz(cm);
            vr enter = t_near, leave = vr_set1(INFINITY);
            unsigned inside = lanes;
            for (int a = 0; a < 3; a++) {
                vr l = vr_set1(lo[a][i]), u = vr_set1(hi[a][i]);
                vr t0 = vr_mul(vr_sub(l, o[a]), iv[a]), t1 = vr_mul(vr_sub(u, o[a]), iv[a]);
                vr t_min = vr_min(t0, t1), t_max = vr_max(t0, t1);
                if (c->zero_axes >> a & 1u) {
                    vm contained = vm_and(vr_le(l, o[a]), vr_le(o[a], u));
                    inside &= ~(vm_bits(parallel[a]) & ~vm_bits(contained));
                    t_min = vr_select(parallel[a], vr_set1(-INFINITY), t_min);
                    t_max = vr_select(parallel[a], vr_set1(INFINITY), t_max);
                }
                enter = vr_max(enter, t_min);
                leave = vr_min(leave, t_max);
            }
            leave = vr_min(vr_mul(leave, scale), t_far);
            child_mask[i] |= (uint64_t)(vm_bits(vr_le(enter, leave)) & inside) << g;
        }
    }
}

/* Write a hit into the packet if it beats the ray's current one. */
static inline void offer_packet(packet_ctx *c, uint32_t i, float t, float u, float v, uint32_t prim)
{
    ray_packet *p = c->p;
    if (!hit_comes_first(t, c->geom_id, prim, p->hit_t[i], p->geom_id[i], p->prim_id[i]))
        return;
    if ((p->flags & PACKET_AFTER_HIT) && t == p->after_t[i] &&
        !(c->geom_id > p->after_geom[i] || (c->geom_id == p->after_geom[i] && prim > p->after_prim[i])))
        return;
    p->hit_t[i] = t;
    p->hit_u[i] = u;
    p->hit_v[i] = v;
    p->prim_id[i] = prim;
    p->geom_id[i] = c->geom_id;
    p->t_far[i] = t;
    c->improved |= 1ull << i;
}

/* The rays of `mask` (all with axis order `axes`) against the triangle
 * v0 v1 v2 (id prim), RAY_LANES rays at a time, in the operation order of
 * intersect_triangle. */
static void triangle_rays(packet_ctx *c, const float *v0_in, const float *v1_in, const float *v2_in, uint32_t prim,
                          const int axes[3], uint64_t mask)
{
    ray_packet *p = c->p;
    /* copies: the stores to the packet below may alias the inputs, which would reload them */
    const float v0[3] = {v0_in[0], v0_in[1], v0_in[2]}, v1[3] = {v1_in[0], v1_in[1], v1_in[2]},
                v2[3] = {v2_in[0], v2_in[1], v2_in[2]};
    const float *org[3] = {p->org_x, p->org_y, p->org_z};
    const int kx = axes[0], ky = axes[1], kz = axes[2];
    const vr zero = vr_set1(0.f);
    for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
        unsigned lanes = (unsigned)(mask >> g) & ((1u << RAY_LANES) - 1u);
        if (!lanes)
            continue;
        const vr okx = vr_load(org[kx] + g), oky = vr_load(org[ky] + g), okz = vr_load(org[kz] + g);
        const vr sx = vr_load(c->shear_x + g), sy = vr_load(c->shear_y + g), sz = vr_load(c->shear_z + g);
        const vr az = vr_sub(vr_set1(v0[kz]), okz), bz = vr_sub(vr_set1(v1[kz]), okz),
                 cz = vr_sub(vr_set1(v2[kz]), okz);
        const vr akx = vr_sub(vr_set1(v0[kx]), okx), aky = vr_sub(vr_set1(v0[ky]), oky);
        const vr bkx = vr_sub(vr_set1(v1[kx]), okx), bky = vr_sub(vr_set1(v1[ky]), oky);
        const vr ckx = vr_sub(vr_set1(v2[kx]), okx), cky = vr_sub(vr_set1(v2[ky]), oky);
        const vr ax = vr_sub(akx, vr_mul(sx, az)), ay = vr_sub(aky, vr_mul(sy, az));
        const vr bx = vr_sub(bkx, vr_mul(sx, bz)), by = vr_sub(bky, vr_mul(sy, bz));
        const vr cx = vr_sub(ckx, vr_mul(sx, cz)), cy = vr_sub(cky, vr_mul(sy, cz));
        const vr u = vr_sub(vr_mul(cx, by), vr_mul(cy, bx));
        const vr v = vr_sub(vr_mul(ax, cy), vr_mul(ay, cx));
        const vr w = vr_sub(vr_mul(bx, ay), vr_mul(by, ax));
#ifndef TESSERA_UNROBUST
        const vr tol = vr_set1(INTERSECT_EDGE_TOL);
        const vr ma = vr_add(vr_add(vr_abs(akx), vr_abs(aky)), vr_abs(az));
        const vr mb = vr_add(vr_add(vr_abs(bkx), vr_abs(bky)), vr_abs(bz));
        const vr mc = vr_add(vr_add(vr_abs(ckx), vr_abs(cky)), vr_abs(cz));
        const vr pa = vr_add(vr_abs(ax), vr_abs(ay)), pb = vr_add(vr_abs(bx), vr_abs(by));
        const vr pc = vr_add(vr_abs(cx), vr_abs(cy));
        const unsigned on_edge =
            vm_bits(vm_or(vm_or(vr_le(vr_abs(u), vr_mul(tol, vr_add(vr_mul(mc, pb), vr_mul(mb, pc)))),
                                vr_le(vr_abs(v), vr_mul(tol, vr_add(vr_mul(ma, pc), vr_mul(mc, pa))))),
                          vr_le(vr_abs(w), vr_mul(tol, vr_add(vr_mul(mb, pa), vr_mul(ma, pb)))))) &
            lanes;
#else
        const unsigned on_edge = 0u; /* fast build (intersect.h): float decides every edge */
#endif
        const vm any_neg = vm_or(vm_or(vr_lt(u, zero), vr_lt(v, zero)), vr_lt(w, zero));
        const vm any_pos = vm_or(vm_or(vr_gt(u, zero), vr_gt(v, zero)), vr_gt(w, zero));
        const vr det = vr_add(vr_add(u, v), w);
        const vr tz = vr_add(vr_add(vr_mul(u, vr_mul(sz, az)), vr_mul(v, vr_mul(sz, bz))), vr_mul(w, vr_mul(sz, cz)));
        const vr t_near = vr_load(p->t_near + g), t_far = vr_load(p->t_far + g);
        const vr inv_det = vr_div(vr_set1(1.f), det);
        const vr t = vr_mul(tz, inv_det);
        vm ok = vm_andnot(vm_and(vr_gt(t, t_near), vr_le(t, t_far)), vm_and(any_neg, any_pos));
        ok = vm_andnot(ok, vr_eq(det, zero));
        unsigned hits = vm_bits(ok) & lanes & ~on_edge;
        unsigned at_bound = 0; /* next-hit queries: hits at a bound's t, settled by ids in offer_packet */
        if (p->flags & PACKET_AFTER_HIT) {
            at_bound = vm_bits(vr_eq(t, vr_load(p->after_t + g))) & hits;
            hits &= ~at_bound;
        }
        if (at_bound) {
            alignas(64) float t_lane[RAY_LANES], u_lane[RAY_LANES], v_lane[RAY_LANES];
            vr_store(t_lane, t);
            vr_store(u_lane, vr_mul(v, inv_det));
            vr_store(v_lane, vr_mul(w, inv_det));
            for (unsigned m = at_bound; m; m &= m - 1u) {
                int l = __builtin_ctz(m);
                offer_packet(c, g + (uint32_t)l, t_lane[l], u_lane[l], v_lane[l], prim);
            }
        }
        if (c->any) {
            c->done |= (uint64_t)hits << g;
        } else if (hits) {
            const vr u_out = vr_mul(v, inv_det), v_out = vr_mul(w, inv_det);
            const vr best_t = vr_load(p->hit_t + g);
            /* strictly closer lanes in vector form; equal t (a tie) is settled per ray below */
            const unsigned better = vm_bits(vr_lt(t, best_t)) & hits;
            const unsigned ties = vm_bits(vr_eq(t, best_t)) & hits;
            if (better) {
                const vm upd = vm_from_bits(better);
                vr_store(p->hit_t + g, vr_select(upd, t, best_t));
                vr_store(p->t_far + g, vr_select(upd, t, vr_load(p->t_far + g)));
                vr_store(p->hit_u + g, vr_select(upd, u_out, vr_load(p->hit_u + g)));
                vr_store(p->hit_v + g, vr_select(upd, v_out, vr_load(p->hit_v + g)));
                vr_store_ps_as_u32(p->prim_id + g,
                                   vr_select(upd, vr_set1(lane_float(prim)), vr_load_u32_as_ps(p->prim_id + g)));
                vr_store_ps_as_u32(p->geom_id + g, vr_select(upd, vr_set1(lane_float(c->geom_id)),
                                                            vr_load_u32_as_ps(p->geom_id + g)));
                c->improved |= (uint64_t)better << g;
            }
            if (ties) {
                alignas(64) float t_lane[RAY_LANES], u_lane[RAY_LANES], v_lane[RAY_LANES];
                vr_store(t_lane, t);
                vr_store(u_lane, u_out);
                vr_store(v_lane, v_out);
                for (unsigned m = ties; m; m &= m - 1u) {
                    int l = __builtin_ctz(m);
                    offer_packet(c, g + (uint32_t)l, t_lane[l], u_lane[l], v_lane[l], prim);
                }
            }
        }
        /* rays that meet an edge exactly in float: the scalar test, in double */
        for (unsigned m = on_edge; m; m &= m - 1u) {
            uint32_t i = g + (uint32_t)__builtin_ctz(m);
            ray one = packet_get_ray(p, i);
            ray_derived d = ray_derive(&one);
            float te, ue, ve;
            if (intersect_triangle(&one, &d, v3(v0[0], v0[1], v0[2]), v3(v1[0], v1[1], v1[2]),
                                   v3(v2[0], v2[1], v2[2]), &te, &ue, &ve)) {
                if (c->any)
                    c->done |= 1ull << i;
                else
                    offer_packet(c, i, te, ue, ve, prim);
            }
        }
    }
}

/* Per-ray watertight setup, made on first use: most packets never reach a
 * leaf or a single-ray continuation. */
static inline void ensure_shear(packet_ctx *c)
{
    if (!c->shear_ready) {
        setup_shear(c, c->shear_rays);
        c->shear_ready = true;
    }
}

/* Continue rays of `mask` one by one through the subtree at `ref`. */
static void finish_single(packet_ctx *c, uint32_t ref, uint64_t mask)
{
    ray_packet *p = c->p;
    ensure_shear(c);
    for (uint64_t m = mask; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        ray one = packet_get_ray(p, i);
        hit h = packet_get_hit(p, i);
        if (!traverse1(c->w, ref, c->geom_id, &one, &c->derived[i], &h, c->any))
            continue;
        if (c->any) {
            c->done |= 1ull << i;
            continue;
        }
        packet_set_hit(p, i, &h); /* one.t_far is h.t: a hit shrinks it to its t */
        c->improved |= 1ull << i;
    }
}

static uint64_t ISA_SUFFIX(intersect_packet)(const wbvh *w, uint32_t geom_id, ray_packet *p, uint64_t mask, bool any);

/* The rays of `mask` against one instance whose transform is not the
 * identity: mapped into its object space once per packet visit (the origin
 * once when the packet has a common origin), traced there, and the hits that
 * improved copied back. */
static uint64_t instance_packet(const wbvh_instance *inst, uint32_t id, ray_packet *p, uint64_t mask, bool any)
{
    ray_packet local;
    const affine3 *m = &inst->to_object;
    const bool common_origin = (p->flags & PACKET_COMMON_ORIGIN) != 0;
    vec3 shared_org = common_origin ? affine3_point(m, v3(p->org_x[0], p->org_y[0], p->org_z[0])) : v3(0.f, 0.f, 0.f);
    /* the kernels read whole groups of RAY_LANES lanes (and mask them), never
     * a group without a ray of the mask: only the lanes of touched groups
     * outside the mask need defined values */
    for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
        if (!((mask >> g) & ((1ull << RAY_LANES) - 1ull)))
            continue;
        for (uint32_t i = g; i < g + RAY_LANES; i++) {
            local.org_x[i] = local.org_y[i] = local.org_z[i] = 0.f;
            local.dir_x[i] = local.dir_y[i] = local.dir_z[i] = 0.f;
            local.inv_dir_x[i] = local.inv_dir_y[i] = local.inv_dir_z[i] = 0.f;
            local.t_near[i] = local.t_far[i] = 0.f;
            local.hit_t[i] = INFINITY;
            local.hit_u[i] = local.hit_v[i] = 0.f;
            local.prim_id[i] = local.geom_id[i] = RAY_INVALID_ID;
        }
    }
    uint64_t traceable = 0;
    for (uint64_t rest = mask; rest; rest &= rest - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(rest);
        vec3 o = common_origin ? shared_org : affine3_point(m, v3(p->org_x[i], p->org_y[i], p->org_z[i]));
        vec3 dv = affine3_vector(m, v3(p->dir_x[i], p->dir_y[i], p->dir_z[i]));
        ray one = {o, dv, p->t_near[i], p->t_far[i]};
        if (ray_is_degenerate(&one))
            continue;
        traceable |= 1ull << i;
        local.org_x[i] = o.x, local.org_y[i] = o.y, local.org_z[i] = o.z;
        local.dir_x[i] = dv.x, local.dir_y[i] = dv.y, local.dir_z[i] = dv.z;
        /* packet_derive_inv_dir's values, for these lanes only */
        local.inv_dir_x[i] = dv.x != 0.f ? 1.f / dv.x : copysignf(FLT_MAX, dv.x);
        local.inv_dir_y[i] = dv.y != 0.f ? 1.f / dv.y : copysignf(FLT_MAX, dv.y);
        local.inv_dir_z[i] = dv.z != 0.f ? 1.f / dv.z : copysignf(FLT_MAX, dv.z);
        local.t_near[i] = p->t_near[i];
        local.t_far[i] = p->t_far[i];
        local.hit_t[i] = p->hit_t[i];
        local.hit_u[i] = p->hit_u[i];
        local.hit_v[i] = p->hit_v[i];
        local.prim_id[i] = p->prim_id[i];
        local.geom_id[i] = p->geom_id[i];
    }
    const bool bounded = (p->flags & PACKET_AFTER_HIT) != 0;
    if (bounded) /* the bounds of every lane the kernels may read (groups of the mask) */
        for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
            if (!((mask >> g) & ((1ull << RAY_LANES) - 1ull)))
                continue;
            for (uint32_t i = g; i < g + RAY_LANES; i++) {
                local.after_t[i] = p->after_t[i];
                local.after_geom[i] = p->after_geom[i];
                local.after_prim[i] = p->after_prim[i];
            }
        }
    if (!traceable)
        return 0;
    local.count = p->count;
    local.active = traceable;
    local.flags = PACKET_HAVE_INV_DIR | (common_origin ? PACKET_COMMON_ORIGIN : 0u) | (bounded ? PACKET_AFTER_HIT : 0u);
    uint64_t result = ISA_SUFFIX(intersect_packet)(inst->geometry, id, &local, traceable, any);
    if (!any)
        for (uint64_t rest = result; rest; rest &= rest - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(rest);
            p->hit_t[i] = local.hit_t[i];
            p->hit_u[i] = local.hit_u[i];
            p->hit_v[i] = local.hit_v[i];
            p->prim_id[i] = local.prim_id[i];
            p->geom_id[i] = local.geom_id[i];
            p->t_far[i] = local.t_far[i];
        }
    return result;
}

/* The rays of `mask` against the instances of a leaf of the instance level. */
static void instances_leaf_packet(packet_ctx *c, uint32_t ref, uint64_t mask)
{
    const wbvh *w = c->w;
    uint32_t first = (ref & ~REF_LEAF) >> REF_BLOCKS_BITS, count = (ref & ((1u << REF_BLOCKS_BITS) - 1u)) + 1u;
    for (uint32_t k = first; k < first + count; k++) {
        const wbvh_prim_block *b = (const wbvh_prim_block *)w->blocks + k;
        for (int lane = 0; lane < WBVH_BLOCK; lane++) {
            uint32_t id = b->prim_id[lane];
            uint64_t m = mask & ~c->done;
            if (!m)
                return;
            if (id == RAY_INVALID_ID || instance_hidden(w, id))
                continue;
            const wbvh_instance *inst = &w->instances[id];
            uint64_t r = inst->identity ? ISA_SUFFIX(intersect_packet)(inst->geometry, id, c->p, m, c->any)
                                        : instance_packet(inst, id, c->p, m, c->any);
            if (c->any)
                c->done |= r;
            else
                c->improved |= r;
        }
    }
}

/* LEAF: are the rays of `mask` cheaper one by one against a leaf of `count`
 * triangles than in lanes? One by one, each ray runs ceil(count / 4) 4-wide
 * tests; in lanes, each triangle runs one RAY_LANES-wide test per started
 * vector of rays in each axis order (triangle_rays groups rays by it), so
 * rays of one direction (shadow rays toward a directional light, a camera's
 * rays) share every test and incoherent rays (ambient occlusion) share few.
 * A lane test is priced at half a 4-wide test: what was measured best
 * (AMD EPYC, AVX-512, 1 thread, 1920x1080, frame times of alternating runs
 * against the former fixed counts, RAY_LANES / 2 rays for closest hits and
 * 3 RAY_LANES / 4 for any-hit: dragon primary 77 / 84 ms, dragon + one
 * shadow ray a hit 117 / 134 ms, 4 M CT bunny ambient occlusion 870 / 904
 * ms; pricing it at a whole 4-wide test gave 77 / 120 / 897 ms, at a
 * quarter - / 120 / 887 ms, the bunny's primary rays 45 ms at all three). */
static inline bool leaf_single_cheaper(const packet_ctx *c, uint64_t mask, uint32_t count)
{
    unsigned lane_vectors = 0;
    for (int o = 0; o < c->order_count; o++)
        lane_vectors += ((unsigned)__builtin_popcountll(mask & c->order_mask[o]) + RAY_LANES - 1u) / RAY_LANES;
    const unsigned single_tests = (unsigned)__builtin_popcountll(mask) * ((count + WBVH_BLOCK - 1u) / WBVH_BLOCK);
    return 2u * single_tests <= lane_vectors * count;
}

static void leaf_packet(packet_ctx *c, uint32_t ref, uint64_t mask)
{
    const wbvh *w = c->w;
    if (w->kind == WBVH_INSTANCES) {
        instances_leaf_packet(c, ref, mask);
        return;
    }
    if (w->kind != WBVH_MESH) { /* spheres, or a kind without a SIMD layout: one ray at a time */
        finish_single(c, ref, mask);
        return;
    }
    ensure_shear(c);
    uint32_t first = (ref & ~REF_LEAF) >> REF_BLOCKS_BITS, count = (ref & ((1u << REF_BLOCKS_BITS) - 1u)) + 1u;
    if (leaf_single_cheaper(c, mask, count)) {
        finish_single(c, ref, mask);
        return;
    }
    const float *pos = w->mesh.positions;
    /* the leaf's indices are one run; its vertices may be cache misses on a
     * large mesh: ask for all of them before testing any */
    for (uint32_t k = first; k < first + count; k++) {
        const uint32_t *idx = w->mesh.indices + 3 * (size_t)k;
        __builtin_prefetch(pos + 3 * (size_t)idx[0]);
        __builtin_prefetch(pos + 3 * (size_t)idx[1]);
        __builtin_prefetch(pos + 3 * (size_t)idx[2]);
    }
    const uint32_t *canon = w->mesh.canon; /* NULL: a triangle's id is its place */
    for (uint32_t prim = first; prim < first + count; prim++) {
        const uint32_t *idx = w->mesh.indices + 3 * (size_t)prim;
        const float *v0 = pos + 3 * (size_t)idx[0], *v1 = pos + 3 * (size_t)idx[1], *v2 = pos + 3 * (size_t)idx[2];
        const uint32_t id = canon ? canon[prim] : prim;
        for (int o = 0; o < c->order_count; o++) {
            uint64_t m = mask & c->order_mask[o] & ~c->done;
            if (m)
                triangle_rays(c, v0, v1, v2, id, c->order_axes[o], m);
        }
    }
}

typedef struct stack_entry_packet {
    uint32_t ref;
    float dist;    /* a lower bound of the rays' entry distances, for order only */
    uint64_t rays; /* rays that enter this child */
} stack_entry_packet;

static uint64_t ISA_SUFFIX(intersect_packet)(const wbvh *w, uint32_t geom_id, ray_packet *p, uint64_t mask, bool any)
{
    if (w->node_count == 0 || !mask)
        return 0;
    packet_ctx c;
    c.p = p;
    c.w = w;
    c.geom_id = geom_id;
    c.any = any;
    c.done = 0;
    c.improved = 0;
    c.shear_ready = false;
    c.shear_rays = mask;
    const int single_max = any ? PACKET_SINGLE_RAY_MAX_ANY : PACKET_SINGLE_RAY_MAX;
    if (__builtin_popcountll(mask) <= single_max) {
        finish_single(&c, 0, mask);
        return any ? c.done : c.improved;
    }
    c.shear_ready = false;
    c.shear_rays = mask;
    setup_interval(&c, mask);
    setup_slack(&c, mask);
    /* largest t_far of the packet, for interval culling; recomputed only after hits shrank some */
    float t_far_hi = INFINITY;
    uint64_t improved_seen = ~0ull;

    stack_entry_packet stack[WBVH_STACK_SIZE];
    int top = 0;
    uint32_t ref = 0;
    uint64_t rays = mask;
    for (;;) {
        rays &= ~c.done;
        if (rays) {
            if (__builtin_popcountll(rays) <= single_max) {
                finish_single(&c, ref, rays);
            } else if (ref & REF_LEAF) {
                leaf_packet(&c, ref, rays);
            } else {
                const wbvh_node *n = &w->nodes[ref];
                alignas(32) float dist[WBVH_WIDTH];
                unsigned children = n->child_mask;
                if (c.interval) {
                    if (improved_seen != c.improved) {
                        float t_far_lo;
                        lanes_range(p->t_far, mask, &t_far_lo, &t_far_hi);
                        improved_seen = c.improved;
                    }
                    children = node_interval(&c, n, t_far_hi, dist);
                } else {
                    for (int i = 0; i < WBVH_WIDTH; i++)
                        dist[i] = 0.f;
                }
                if (w->crop_lo)
                    children &= crop_children(w, ref);
                if (children) {
                    uint64_t child_rays[WBVH_WIDTH];
                    node_rays(&c, n, children, rays, child_rays);
                    /* push children that some ray enters, farthest first */
                    int base = top;
                    for (unsigned cm = children; cm; cm &= cm - 1u) {
                        int i = __builtin_ctz(cm);
                        if (!child_rays[i])
                            continue;
                        stack_entry_packet e = {child_ref(n, i), dist[i], child_rays[i]};
                        int j = top++;
                        while (j > base && stack[j - 1].dist < e.dist) {
                            stack[j] = stack[j - 1];
                            j--;
                        }
                        stack[j] = e;
                    }
                }
            }
        }
        if (top == 0)
            break;
        top--;
        ref = stack[top].ref;
        rays = stack[top].rays;
    }
    return any ? c.done : c.improved;
}

/* ------------------------------------------------------------------------
 * Packet setup
 * ------------------------------------------------------------------------ */

static uint64_t ISA_SUFFIX(traceable)(const ray_packet *p, uint64_t mask)
{
    const vr zero = vr_set1(0.f);
    uint64_t ok_bits = 0;
    for (uint32_t g = 0; g < PACKET_MAX_RAYS; g += RAY_LANES) {
        unsigned lanes = (unsigned)(mask >> g) & ((1u << RAY_LANES) - 1u);
        if (!lanes)
            continue;
        const vr ox = vr_load(p->org_x + g), oy = vr_load(p->org_y + g), oz = vr_load(p->org_z + g);
        const vr dx = vr_load(p->dir_x + g), dy = vr_load(p->dir_y + g), dz = vr_load(p->dir_z + g);
        /* x - x is 0 for finite x and NaN otherwise */
        vr finite = vr_add(vr_add(vr_add(vr_sub(ox, ox), vr_sub(oy, oy)), vr_add(vr_sub(oz, oz), vr_sub(dx, dx))),
                           vr_add(vr_sub(dy, dy), vr_sub(dz, dz)));
        vm zero_dir = vm_and(vm_and(vr_eq(dx, zero), vr_eq(dy, zero)), vr_eq(dz, zero));
        vm ok = vm_andnot(vm_and(vr_eq(finite, zero), vr_lt(vr_load(p->t_near + g), vr_load(p->t_far + g))), zero_dir);
        ok_bits |= (uint64_t)(vm_bits(ok) & lanes) << g;
    }
    return ok_bits;
}

static void ISA_SUFFIX(primary_directions)(ray_packet *p, const camera_basis *cam, int x0, int y0, int w, int h)
{
    alignas(64) float px[PACKET_MAX_RAYS], py[PACKET_MAX_RAYS];
    const int count = w * h;
    for (int i = 0; i < PACKET_MAX_RAYS; i++) {
        px[i] = (float)(x0 + (i < count ? i % w : 0));
        py[i] = (float)(y0 + (i < count ? i / w : 0));
    }
    const vr half = vr_set1(0.5f), two = vr_set1(2.f), one = vr_set1(1.f), zero = vr_set1(0.f);
    const vr width = vr_set1((float)cam->width_px), height = vr_set1((float)cam->height_px);
    for (int g = 0; g < count; g += RAY_LANES) {
        /* the operation order of camera_pixel_direction and v3_normalize */
        vr sx = vr_sub(vr_div(vr_mul(two, vr_add(vr_load(px + g), half)), width), one);
        vr sy = vr_sub(one, vr_div(vr_mul(two, vr_add(vr_load(py + g), half)), height));
        vr dx = vr_add(vr_set1(cam->forward.x), vr_add(vr_mul(vr_set1(cam->right.x), sx), vr_mul(vr_set1(cam->up.x), sy)));
        vr dy = vr_add(vr_set1(cam->forward.y), vr_add(vr_mul(vr_set1(cam->right.y), sx), vr_mul(vr_set1(cam->up.y), sy)));
        vr dz = vr_add(vr_set1(cam->forward.z), vr_add(vr_mul(vr_set1(cam->right.z), sx), vr_mul(vr_set1(cam->up.z), sy)));
        vr len = vr_sqrt(vr_add(vr_add(vr_mul(dx, dx), vr_mul(dy, dy)), vr_mul(dz, dz)));
        vm positive = vr_gt(len, zero);
        vr inv = vr_div(one, vr_select(positive, len, one));
        vr_store(p->dir_x + g, vr_select(positive, vr_mul(dx, inv), dx));
        vr_store(p->dir_y + g, vr_select(positive, vr_mul(dy, inv), dy));
        vr_store(p->dir_z + g, vr_select(positive, vr_mul(dz, inv), dz));
    }
}

const kernel_table ISA_SUFFIX(kernel_table) = {
    .isa_name = ISA_NAME,
    .intersect1 = ISA_SUFFIX(intersect1),
    .intersect_packet = ISA_SUFFIX(intersect_packet),
    .traceable = ISA_SUFFIX(traceable),
    .primary_directions = ISA_SUFFIX(primary_directions),
};
