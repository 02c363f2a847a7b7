/* bvh_spatial.c - the SBVH builder (bvh_spatial.h).
 *
 * Shape of the build: depth first, left child first, on the calling thread;
 * each node's children are allocated as a pair when the node is split, so
 * the nodes come out in bvh.h's canonical layout without a copy. A node owns
 * an array of references (a box and an input triangle number); splitting it
 * writes two new arrays (a chopped triangle has a reference in both) and
 * frees its own, so at any time the arrays alive are the current node's and
 * the pending right siblings': disjoint parts of the final references.
 *
 * CONSERVATIVE CLIPPING. A chopped reference's box is the bounds of the
 * triangle clipped to the side's slab, computed in double, rounded outward
 * to float and widened by one more float step, then intersected with the
 * reference's box and the slab (exact min / max). So it always contains the
 * triangle's part in the slab and the box it came from: a leaf box is never
 * smaller than what its references stand for; at worst an ulp bigger.
 *
 * The choice at a node is a function of its references alone, and nodes are
 * split in one fixed order, so the output (including which splits the
 * reference budget still allowed) depends on the input alone. */
#include "bvh_spatial.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/progress.h"

/* Bins per axis of the object split: bvh.c's BVH_BINS. */
#define OBJECT_BINS 16

typedef struct sbox {
    float lo[3], hi[3]; /* empty: lo = +inf, hi = -inf */
} sbox;

/* One reference: the part of triangle `prim` (an input number) inside box. */
typedef struct sref {
    sbox box;
    uint32_t prim;
} sref;

static sbox sbox_empty(void) { return (sbox){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}}; }
static bool sbox_is_empty(const sbox *b) { return !(b->lo[0] <= b->hi[0] && b->lo[1] <= b->hi[1] && b->lo[2] <= b->hi[2]); }

static void sbox_grow(sbox *b, const sbox *o)
{
    for (int a = 0; a < 3; a++) {
        b->lo[a] = o->lo[a] < b->lo[a] ? o->lo[a] : b->lo[a];
        b->hi[a] = o->hi[a] > b->hi[a] ? o->hi[a] : b->hi[a];
    }
}

static sbox sbox_and(const sbox *a, const sbox *b)
{
    sbox r;
    for (int k = 0; k < 3; k++) {
        r.lo[k] = a->lo[k] > b->lo[k] ? a->lo[k] : b->lo[k];
        r.hi[k] = a->hi[k] < b->hi[k] ? a->hi[k] : b->hi[k];
    }
    return r;
}

static aabb sbox_to_aabb(const sbox *b) { return (aabb){v3(b->lo[0], b->lo[1], b->lo[2]), v3(b->hi[0], b->hi[1], b->hi[2])}; }

/* Half the surface area; 0 when empty (as aabb_half_area). */
static float sbox_half_area(const sbox *b)
{
    if (sbox_is_empty(b))
        return 0.f;
    float ex = b->hi[0] - b->lo[0], ey = b->hi[1] - b->lo[1], ez = b->hi[2] - b->lo[2];
    return ex * ey + ey * ez + ez * ex;
}

/* --- clipping (see CONSERVATIVE CLIPPING above) --- */

/* The next float toward -inf / +inf of a finite f (bit steps: no libm call). */
static float step_down(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    if (f == 0.f)
        u = 0x80000001u; /* -0 and +0: the smallest negative */
    else
        u = f > 0.f ? u - 1 : u + 1;
    memcpy(&f, &u, sizeof f);
    return f;
}
static float step_up(float f) { return -step_down(-f); }

/* The largest float <= x, one float step lower again (the slack covers the
 * double rounding of a clipped corner); and the mirror. Infinite x stays. */
static float float_below(double x)
{
    float f = (float)x;
    if (!isfinite(f))
        return f;
    if ((double)f > x)
        f = step_down(f);
    return step_down(f);
}
static float float_above(double x)
{
    float f = (float)x;
    if (!isfinite(f))
        return f;
    if ((double)f < x)
        f = step_up(f);
    return step_up(f);
}

/* The triangle's corners, from the input arrays. */
static void triangle_corners(const bvh_triangles *t, uint32_t prim, const float *c[3])
{
    const uint32_t *idx = t->indices + 3 * (size_t)t->ids[prim];
    for (int k = 0; k < 3; k++)
        c[k] = t->positions + 3 * (size_t)idx[k];
}

/* Bounds in double; empty: lo = +inf, hi = -inf. */
typedef struct dbox {
    double lo[3], hi[3];
} dbox;

static dbox dbox_empty(void) { return (dbox){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}}; }

static void dbox_add(dbox *b, const double p[3])
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = p[k] < b->lo[k] ? p[k] : b->lo[k];
        b->hi[k] = p[k] > b->hi[k] ? p[k] : b->hi[k];
    }
}

static void dbox_merge(dbox *b, const dbox *o)
{
    for (int k = 0; k < 3; k++) {
        b->lo[k] = o->lo[k] < b->lo[k] ? o->lo[k] : b->lo[k];
        b->hi[k] = o->hi[k] > b->hi[k] ? o->hi[k] : b->hi[k];
    }
}

/* Bounds of where the triangle v meets the plane x[axis] = at: its corners
 * on the plane and its edges' crossings (each crossing on the plane exactly). */
static dbox plane_section(const double v[3][3], int axis, double at)
{
    dbox s = dbox_empty();
    for (int e = 0; e < 3; e++) {
        const double *a = v[e], *b = v[(e + 1) % 3];
        if (a[axis] == at)
            dbox_add(&s, a);
        if ((a[axis] < at && b[axis] > at) || (a[axis] > at && b[axis] < at)) {
            double t = (at - a[axis]) / (b[axis] - a[axis]), q[3];
            for (int k = 0; k < 3; k++)
                q[k] = a[k] + t * (b[k] - a[k]);
            q[axis] = at;
            dbox_add(&s, q);
        }
    }
    return s;
}

/* Boxes of reference r's parts in the slabs between consecutive cuts
 * cuts[0] < ... < cuts[slabs] on `axis` (cuts[0] and cuts[slabs] r's box
 * ends): out[k] for [cuts[k], cuts[k + 1]], empty where the triangle has no
 * part inside r's box. The part of a triangle in a slab is a convex polygon
 * whose corners are the triangle's corners inside the slab and its sections
 * with the two planes, so its bounds are theirs. */
static void slab_boxes(const bvh_triangles *t, const sref *r, int axis, const float *cuts, int slabs, sbox *out)
{
    const float *c[3];
    triangle_corners(t, r->prim, c);
    double v[3][3];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            v[i][k] = c[i][k];
    dbox below = plane_section(v, axis, cuts[0]);
    for (int k = 0; k < slabs; k++) {
        dbox above = plane_section(v, axis, cuts[k + 1]), part = below;
        dbox_merge(&part, &above);
        for (int i = 0; i < 3; i++)
            if (v[i][axis] > cuts[k] && v[i][axis] < cuts[k + 1])
                dbox_add(&part, v[i]);
        if (!(part.lo[0] <= part.hi[0])) {
            out[k] = sbox_empty();
        } else {
            sbox b;
            for (int a = 0; a < 3; a++) {
                b.lo[a] = float_below(part.lo[a]);
                b.hi[a] = float_above(part.hi[a]);
            }
            b.lo[axis] = b.lo[axis] > cuts[k] ? b.lo[axis] : cuts[k];
            b.hi[axis] = b.hi[axis] < cuts[k + 1] ? b.hi[axis] : cuts[k + 1];
            out[k] = sbox_and(&b, &r->box);
        }
        below = above;
    }
}

/* --- object split: binned SAH over reference centroids (Wald 2007) --- */

typedef struct choice {
    int kind;     /* 0: none, 1: object, 2: spatial */
    int axis;
    int bin;      /* object: bins [0, bin] go left; spatial: the plane between bins bin - 1 and bin */
    float cost;
    sbox left, right;
    uint32_t left_count, right_count; /* spatial: as binned (before unsplitting) */
} choice;

typedef struct object_map {
    float lo[3], scale[3]; /* centroid (lo + hi) box min; bins / extent, 0 without extent */
} object_map;

static int object_bin(const object_map *m, const sref *r, int axis)
{
    float c = r->box.lo[axis] + r->box.hi[axis];
    float f = (c - m->lo[axis]) * m->scale[axis];
    f = f > 0.f ? f : 0.f; /* NaN -> 0 */
    f = f < (float)(OBJECT_BINS - 1) ? f : (float)(OBJECT_BINS - 1);
    return (int)f;
}

static float split_cost(float left_area, uint32_t left_n, float right_area, uint32_t right_n, float parent_area)
{
    float sides = left_area * bvh_leaf_blocks(left_n) + right_area * bvh_leaf_blocks(right_n);
    return BVH_COST_TRAVERSAL + BVH_COST_INTERSECT * sides / parent_area;
}

/* The SAH sweep over one axis's bins: every plane p (bins [0, p) left, the
 * rest right), sides counted by left_n_of (the bins' references entering)
 * and right_n_of (leaving); *best takes a strictly cheaper split (so ties
 * go to the lower axis, then plane). Object splits record bin p - 1 (the
 * last left bin), spatial ones the plane p. */
#define SWEEP_BINS_MAX (BVH_SPATIAL_BINS > OBJECT_BINS ? BVH_SPATIAL_BINS : OBJECT_BINS)
static void sweep(const sbox *box, const uint32_t *left_n_of, const uint32_t *right_n_of, int bins, int kind, int axis,
                  float parent_area, choice *best)
{
    sbox right_box[SWEEP_BINS_MAX];
    uint32_t right_n[SWEEP_BINS_MAX];
    sbox acc = sbox_empty();
    uint32_t acc_n = 0;
    for (int b = bins - 1; b > 0; b--) {
        sbox_grow(&acc, &box[b]);
        acc_n += right_n_of[b];
        right_box[b] = acc;
        right_n[b] = acc_n;
    }
    acc = sbox_empty();
    acc_n = 0;
    for (int p = 1; p < bins; p++) {
        sbox_grow(&acc, &box[p - 1]);
        acc_n += left_n_of[p - 1];
        if (acc_n == 0 || right_n[p] == 0)
            continue;
        float cost = split_cost(sbox_half_area(&acc), acc_n, sbox_half_area(&right_box[p]), right_n[p], parent_area);
        if (cost < best->cost)
            *best = (choice){kind, axis, kind == 1 ? p - 1 : p, cost, acc, right_box[p], acc_n, right_n[p]};
    }
}

static choice best_object_split(const sref *refs, uint32_t n, float parent_area, object_map *map)
{
    sbox cent = sbox_empty();
    for (uint32_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            float c = refs[i].box.lo[a] + refs[i].box.hi[a];
            cent.lo[a] = c < cent.lo[a] ? c : cent.lo[a];
            cent.hi[a] = c > cent.hi[a] ? c : cent.hi[a];
        }
    for (int a = 0; a < 3; a++) {
        map->lo[a] = cent.lo[a];
        map->scale[a] = cent.hi[a] > cent.lo[a] ? (float)OBJECT_BINS * (1.f - 1e-6f) / (cent.hi[a] - cent.lo[a]) : 0.f;
    }
    choice best = {.kind = 0, .cost = INFINITY};
    for (int axis = 0; axis < 3; axis++) {
        if (map->scale[axis] == 0.f)
            continue;
        sbox box[OBJECT_BINS];
        uint32_t count[OBJECT_BINS] = {0};
        for (int b = 0; b < OBJECT_BINS; b++)
            box[b] = sbox_empty();
        for (uint32_t i = 0; i < n; i++) {
            int b = object_bin(map, &refs[i], axis);
            sbox_grow(&box[b], &refs[i].box);
            count[b]++;
        }
        sweep(box, count, count, OBJECT_BINS, 1, axis, parent_area, &best);
    }
    return best;
}

/* --- spatial split: references binned into slabs, chopped at slab planes --- */

/* Plane k (0..BINS) of the node box on `axis`: monotone in k, exact at both ends. */
static float plane_at(const sbox *node, int axis, int k)
{
    if (k >= BVH_SPATIAL_BINS)
        return node->hi[axis];
    return node->lo[axis] + (node->hi[axis] - node->lo[axis]) * ((float)k / (float)BVH_SPATIAL_BINS);
}

/* The slabs a reference spans on `axis`: first = the last slab whose low plane
 * is <= box lo, last = the first slab whose high plane is >= box hi (at least
 * first). The partition uses the same function, so it agrees with the bins. */
static void slab_span(const sbox *node, const sbox *box, int axis, int *first, int *last)
{
    float extent = node->hi[axis] - node->lo[axis];
    float scale = (float)BVH_SPATIAL_BINS / extent;
    float f = (box->lo[axis] - node->lo[axis]) * scale;
    int b = f > 0.f ? (f < (float)(BVH_SPATIAL_BINS - 1) ? (int)f : BVH_SPATIAL_BINS - 1) : 0;
    while (b > 0 && plane_at(node, axis, b) > box->lo[axis])
        b--;
    while (b < BVH_SPATIAL_BINS - 1 && plane_at(node, axis, b + 1) <= box->lo[axis])
        b++;
    *first = b;
    f = (box->hi[axis] - node->lo[axis]) * scale;
    int e = f > 0.f ? (f < (float)(BVH_SPATIAL_BINS - 1) ? (int)f : BVH_SPATIAL_BINS - 1) : 0;
    while (e > 0 && plane_at(node, axis, e) >= box->hi[axis])
        e--;
    while (e < BVH_SPATIAL_BINS - 1 && plane_at(node, axis, e + 1) < box->hi[axis])
        e++;
    *last = e > b ? e : b;
}

static choice best_spatial_split(const bvh_triangles *t, const sref *refs, uint32_t n, const sbox *node,
                                 float parent_area)
{
    choice best = {.kind = 0, .cost = INFINITY};
    for (int axis = 0; axis < 3; axis++) {
        if (!(node->hi[axis] > node->lo[axis]))
            continue;
        sbox box[BVH_SPATIAL_BINS];
        uint32_t enter[BVH_SPATIAL_BINS] = {0}, leave[BVH_SPATIAL_BINS] = {0};
        for (int b = 0; b < BVH_SPATIAL_BINS; b++)
            box[b] = sbox_empty();
        for (uint32_t i = 0; i < n; i++) {
            int first, last;
            slab_span(node, &refs[i].box, axis, &first, &last);
            enter[first]++;
            leave[last]++;
            if (first == last) {
                sbox_grow(&box[first], &refs[i].box);
                continue;
            }
            const sref *r = &refs[i];
            float cuts[BVH_SPATIAL_BINS + 1];
            sbox parts[BVH_SPATIAL_BINS];
            int slabs = last - first + 1;
            cuts[0] = r->box.lo[axis];
            for (int b = 1; b < slabs; b++)
                cuts[b] = plane_at(node, axis, first + b);
            cuts[slabs] = r->box.hi[axis];
            slab_boxes(t, r, axis, cuts, slabs, parts);
            for (int b = 0; b < slabs; b++)
                sbox_grow(&box[first + b], &parts[b]);
        }
        sweep(box, enter, leave, BVH_SPATIAL_BINS, 2, axis, parent_area, &best);
    }
    return best;
}

/* --- the builder --- */

typedef struct node_item {
    uint32_t node;  /* index in builder.nodes */
    uint32_t depth; /* root = 1 */
    sref *refs;     /* owned */
    uint32_t n;
    sbox bounds;    /* of refs' boxes */
} node_item;

typedef struct builder {
    const bvh_triangles *tris;
    bvh_node *nodes;
    uint32_t node_count, node_capacity;
    uint32_t *order; /* references' prims in leaf order */
    uint64_t order_count, order_capacity;
    uint64_t extra; /* references chopping may still add (the budget's rest), shared first come */
    float root_area;
    uint32_t depth;
    progress *report;   /* references placed in leaves, told up to the triangle count */
    uint64_t reported;
} builder;

static bool grow_nodes(builder *B)
{
    if (B->node_count + 2 <= B->node_capacity)
        return true;
    uint32_t cap = B->node_capacity ? 2 * B->node_capacity : 1024;
    bvh_node *n = realloc(B->nodes, (size_t)cap * sizeof *n);
    if (!n)
        return false;
    B->nodes = n;
    B->node_capacity = cap;
    return true;
}

static bool emit_leaf(builder *B, const node_item *it)
{
    if (B->order_count + it->n > B->order_capacity) {
        uint64_t cap = B->order_capacity * 2 > B->order_count + it->n ? B->order_capacity * 2 : B->order_count + it->n;
        uint32_t *o = realloc(B->order, (size_t)cap * sizeof *o);
        if (!o)
            return false;
        B->order = o;
        B->order_capacity = cap;
    }
    bvh_node *node = &B->nodes[it->node];
    node->first = (uint32_t)B->order_count;
    node->count = it->n;
    for (uint32_t i = 0; i < it->n; i++)
        B->order[B->order_count++] = it->refs[i].prim;
    return true;
}

/* The references of a split, partitioned into two new arrays with their bounds. */
typedef struct sides {
    sref *left, *right;
    uint32_t left_n, right_n;
    sbox left_box, right_box;
} sides;

static void put(sref *arr, uint32_t *count, sbox *bounds, const sref *r)
{
    arr[(*count)++] = *r;
    sbox_grow(bounds, &r->box);
}

static void partition_object(const node_item *it, const choice *c, const object_map *map, sides *s)
{
    for (uint32_t i = 0; i < it->n; i++) {
        const sref *r = &it->refs[i];
        if (object_bin(map, r, c->axis) <= c->bin)
            put(s->left, &s->left_n, &s->left_box, r);
        else
            put(s->right, &s->right_n, &s->right_box, r);
    }
}

static void partition_halves(const node_item *it, sides *s)
{
    for (uint32_t i = 0; i < it->n; i++) {
        if (i < it->n / 2)
            put(s->left, &s->left_n, &s->left_box, &it->refs[i]);
        else
            put(s->right, &s->right_n, &s->right_box, &it->refs[i]);
    }
}

/* Chop the references crossing the plane; one whose duplication the SAH does
 * not pay for goes whole to the cheaper side (the paper's unsplitting, with
 * the binned sides' areas and counts). */
static void partition_spatial(const builder *B, const node_item *it, const choice *c, sides *s)
{
    const int axis = c->axis;
    const float at = plane_at(&it->bounds, axis, c->bin);
    const float area_l = sbox_half_area(&c->left), area_r = sbox_half_area(&c->right);
    const float nl = (float)c->left_count, nr = (float)c->right_count;
    for (uint32_t i = 0; i < it->n; i++) {
        const sref *r = &it->refs[i];
        int first, last;
        slab_span(&it->bounds, &r->box, axis, &first, &last);
        if (last < c->bin) {
            put(s->left, &s->left_n, &s->left_box, r);
            continue;
        }
        if (first >= c->bin) {
            put(s->right, &s->right_n, &s->right_box, r);
            continue;
        }
        const float cuts[3] = {r->box.lo[axis], at, r->box.hi[axis]};
        sbox parts[2];
        slab_boxes(B->tris, r, axis, cuts, 2, parts);
        sref l = {parts[0], r->prim}, h = {parts[1], r->prim};
        bool has_l = !sbox_is_empty(&l.box), has_h = !sbox_is_empty(&h.box);
        if (has_l && has_h) {
            sbox whole_l = c->left, whole_r = c->right;
            sbox_grow(&whole_l, &r->box);
            sbox_grow(&whole_r, &r->box);
            float both = area_l * nl + area_r * nr;
            float to_left = sbox_half_area(&whole_l) * nl + area_r * (nr - 1.f);
            float to_right = area_l * (nl - 1.f) + sbox_half_area(&whole_r) * nr;
            if (to_left < both && to_left <= to_right)
                has_h = false, l.box = r->box;
            else if (to_right < both)
                has_l = false, h.box = r->box;
        } else if (!has_l && !has_h) {
            /* only for a triangle without area, whose clip can vanish: keep it whole on its lower side */
            has_l = true;
            l.box = r->box;
        }
        if (has_l)
            put(s->left, &s->left_n, &s->left_box, &l);
        if (has_h)
            put(s->right, &s->right_n, &s->right_box, &h);
    }
}

static bool sides_alloc(sides *s, uint32_t n)
{
    *s = (sides){NULL, NULL, 0, 0, sbox_empty(), sbox_empty()};
    s->left = malloc((size_t)n * sizeof *s->left);
    s->right = malloc((size_t)n * sizeof *s->right);
    return s->left && s->right;
}

static void sides_free(sides *s)
{
    free(s->left);
    free(s->right);
    s->left = s->right = NULL;
}

/* Split one node into *s (true) or make it a leaf (false, nothing allocated).
 * *ok is false when memory ran out. */
static bool split_node(builder *B, const node_item *it, sides *s, bool *ok)
{
    *ok = true;
    uint32_t n = it->n;
    float area = sbox_half_area(&it->bounds);
    float leaf_cost = BVH_COST_INTERSECT * bvh_leaf_blocks(n);
    bool leaf_wins = n <= (1u << BVH_SAH_BLOCK_LOG2) && n <= BVH_LEAF_DEFAULT && BVH_COST_TRAVERSAL >= BVH_COST_INTERSECT;
    if (n <= 1 || leaf_wins)
        return false;
    if (!sides_alloc(s, n)) {
        sides_free(s);
        return *ok = false;
    }
    if (it->depth < BVH_SAH_DEPTH_LIMIT && area > 0.f) {
        object_map map;
        choice obj = best_object_split(it->refs, n, area, &map);
        choice best = obj;
        sbox overlap = sbox_and(&obj.left, &obj.right);
        bool try_spatial = B->extra > 0 &&
                           (obj.kind == 0 || sbox_half_area(&overlap) > BVH_SPATIAL_ALPHA * B->root_area);
        if (try_spatial) {
            choice sp = best_spatial_split(B->tris, it->refs, n, &it->bounds, area);
            if (sp.kind && sp.cost < best.cost)
                best = sp;
        }
        if (best.kind && (n > BVH_LEAF_DEFAULT || best.cost < leaf_cost)) {
            if (best.kind == 2) {
                partition_spatial(B, it, &best, s);
                uint64_t added = (uint64_t)s->left_n + s->right_n - n;
                /* each side lost references or area (a side may keep all n, each chopped),
                 * so no node repeats its parent */
                bool progress_made = s->left_n > 0 && s->right_n > 0 &&
                                     (s->left_n < n || sbox_half_area(&s->left_box) < area) &&
                                     (s->right_n < n || sbox_half_area(&s->right_box) < area);
                if (progress_made && added <= B->extra) {
                    B->extra -= added;
                    return true;
                }
                /* over the budget, or a side held everything: the object split instead */
                s->left_n = s->right_n = 0;
                s->left_box = s->right_box = sbox_empty();
                best = obj;
            }
            if (best.kind == 1) {
                partition_object(it, &best, &map, s);
                return true;
            }
        }
    }
    if (n > BVH_LEAF_DEFAULT) { /* no useful SAH split (coincident centroids, or too deep): halves */
        partition_halves(it, s);
        return true;
    }
    sides_free(s);
    return false;
}

static void free_stack(node_item *stack, int top)
{
    for (int i = 0; i < top; i++)
        free(stack[i].refs);
}

uint64_t bvh_spatial_reference_budget(uint32_t count) { return count + (uint64_t)(BVH_SPATIAL_GROWTH * count); }

bool bvh_build_spatial(bvh *out, const bvh_triangles *tris, tess_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t count = tris->count;
    if (count == 0)
        return true;
    builder B = {.tris = tris};
    uint64_t budget = bvh_spatial_reference_budget(count);
    if (budget >= UINT32_MAX / 2)
        return tess_error_set(err, "bvh: too many triangles for spatial splits (%u)", count);
    progress report;
    progress_begin(&report, "building SBVH", count, "ref");
    B.report = &report;
    node_item stack[BVH_MAX_DEPTH + 1];
    int top = 0;
    B.extra = budget - count;
    node_item root = {0, 1, malloc((size_t)count * sizeof(sref)), count, sbox_empty()};
    bool ok = root.refs && grow_nodes(&B);
    if (ok) {
        for (uint32_t i = 0; i < count; i++) {
            const float *c[3];
            triangle_corners(tris, i, c);
            sbox b = sbox_empty();
            for (int k = 0; k < 3; k++) {
                sbox p = {{c[k][0], c[k][1], c[k][2]}, {c[k][0], c[k][1], c[k][2]}};
                sbox_grow(&b, &p);
            }
            root.refs[i] = (sref){b, i};
            sbox_grow(&root.bounds, &b);
        }
        B.root_area = sbox_half_area(&root.bounds);
        B.node_count = 1;
        stack[top++] = root;
    } else {
        free(root.refs);
    }
    while (ok && top > 0) {
        node_item it = stack[--top];
        bvh_node *node = &B.nodes[it.node];
        node->bounds = sbox_to_aabb(&it.bounds);
        if (it.depth > B.depth)
            B.depth = it.depth;
        sides s;
        bool split = split_node(&B, &it, &s, &ok);
        if (!ok || (split && !grow_nodes(&B))) {
            if (split)
                sides_free(&s);
            free(it.refs);
            ok = false;
            break;
        }
        if (!split) {
            ok = emit_leaf(&B, &it);
            /* references outnumber triangles: the report stops at the triangle count */
            uint64_t told = B.reported + it.n < count ? it.n : count - B.reported;
            progress_add(&report, told);
            B.reported += told;
            free(it.refs);
            continue;
        }
        uint32_t kids = B.node_count;
        B.node_count += 2;
        B.nodes[it.node].first = kids;
        B.nodes[it.node].count = 0;
        free(it.refs);
        if (top + 2 > BVH_MAX_DEPTH + 1) { /* cannot happen: depth stays below BVH_MAX_DEPTH */
            sides_free(&s);
            ok = false;
            break;
        }
        stack[top++] = (node_item){kids + 1, it.depth + 1, s.right, s.right_n, s.right_box};
        stack[top++] = (node_item){kids, it.depth + 1, s.left, s.left_n, s.left_box};
    }
    free_stack(stack, top);
    progress_end(&report);
    if (!ok) {
        free(B.nodes);
        free(B.order);
        return tess_error_set(err, "bvh: out of memory for the spatial splits of %u triangles", count);
    }
    bvh_node *shrunk = realloc(B.nodes, (size_t)B.node_count * sizeof *shrunk);
    out->nodes = shrunk ? shrunk : B.nodes;
    out->node_count = B.node_count;
    out->prim_order = B.order;
    out->prim_count = (uint32_t)B.order_count;
    out->depth = B.depth;
    return true;
}
