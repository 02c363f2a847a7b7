/* accel.c - two levels: a wide BVH per geometry (wbvh.h), stored once
 * however many instances place it, under a wide BVH over the instances'
 * world boxes; both traced by the kernels of the best instruction set
 * (kernels.h), single rays and packets alike. */
#include "accel.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "engine/accel/bvh.h"
#include "engine/accel/intersect.h"
#include "engine/accel/kernels.h"
#include "engine/base/parallel.h"
#include "scene.h"
#include "engine/accel/wbvh.h"

struct accel {
    wbvh *geoms;                 /* geom_count bottom levels; index = scene geometry index */
    uint32_t geom_count;
    wbvh_instance *instances;    /* instance_count; index = instance id (hit.geom_id) */
    aabb *instance_bounds;       /* world box of each instance (empty: nothing to hit) */
    accel_placement *placements; /* where each instance is (what shading reads); instances[i]
                                    caches its to_object for traversal */
    const scene *scene;          /* built from; outlives the accel (the scene's placements) */
    uint32_t instance_count;
    wbvh top;                    /* over the instances */
    const kernel_table *kernels; /* resolved once at build */
    /* instance_count flags, nonzero: hidden. Set in serial sections (accel.h);
     * relaxed loads in the traversal, one byte per instance visit */
    atomic_uchar *hidden;
    /* the top level's boxes leave out instances hidden when it was last
     * refitted (shown ones are always in: showing refits at once) */
    atomic_bool refit_pending; /* something was hidden since: accel_commit would shrink boxes */
    /* guards the top level's boxes between a refit (accel_set_hidden,
     * accel_commit, in a serial section) and accel_pick on another thread;
     * render threads never trace while a refit runs, so they do not take it */
    pthread_mutex_t refit_lock;
    bool lock_ready;
    aabb scene_box; /* union of the instances' world boxes as the scene placed them at build
                       (accel_scene_bounds); empty when nothing can be hit; never changes */
    bool single_rays; /* accel_set_single_rays: set before tracing, never during */
};

/* One geometry's wide BVH; primitives that can never be hit are left out. */
static bool build_geometry(wbvh *out, const scene_geometry *g, int threads, tess_error *err)
{
    if (g->ops->tree) { /* the kind keeps its tree: borrow it */
        const wbvh *kept = g->ops->tree(g->data, threads, err);
        if (!kept)
            return false;
        *out = *kept;
        out->borrowed = true;
        return true;
    }
    aabb *boxes;
    uint32_t *prim_ids, kept;
    if (!geometry_hit_boxes(g->ops, g->data, threads, &boxes, &prim_ids, &kept))
        return tess_error_set(err, "accel: out of memory for the bounds of geometry '%s'", g->name);
    bvh binary;
    bool ok = bvh_build(&binary, boxes, kept, threads, err);
    if (ok) {
        ok = wbvh_build(out, &binary, g->ops, g->data, prim_ids, err);
        bvh_finish(&binary);
    }
    free(boxes);
    free(prim_ids);
    return ok;
}

/* World box of an instance from its geometry's tree (the root's children). */
static aabb instance_box(const accel_placement *si, const wbvh *w)
{
    aabb b = aabb_empty();
    if (w->node_count == 0)
        return b;
    const wbvh_node *root = &w->nodes[0];
    for (int i = 0; i < WBVH_WIDTH; i++)
        if (root->child_mask >> i & 1u)
            b = aabb_grow(b, (aabb){v3(root->lo_x[i], root->lo_y[i], root->lo_z[i]),
                                    v3(root->hi_x[i], root->hi_y[i], root->hi_z[i])});
    return si->identity ? b : affine3_box(&si->to_world, b);
}

accel *accel_build(const scene *s, int threads, tess_error *err)
{
    accel *a = calloc(1, sizeof *a);
    if (!a)
        goto oom;
    uint32_t n = s->instance_count;
    a->geom_count = s->geometry_count;
    a->instance_count = n;
    if (!(a->geoms = calloc((size_t)a->geom_count + 1, sizeof *a->geoms)) ||
        !(a->instances = calloc((size_t)n + 1, sizeof *a->instances)) ||
        !(a->instance_bounds = calloc((size_t)n + 1, sizeof *a->instance_bounds)) ||
        !(a->placements = calloc((size_t)n + 1, sizeof *a->placements)) ||
        !(a->hidden = calloc((size_t)n + 1, sizeof *a->hidden)))
        goto oom;
    if (pthread_mutex_init(&a->refit_lock, NULL) != 0)
        goto oom;
    a->lock_ready = true;
    atomic_init(&a->refit_pending, false);
    a->kernels = kernels_select();
    a->scene = s;
    for (uint32_t g = 0; g < a->geom_count; g++)
        if (!build_geometry(&a->geoms[g], &s->geometries[g], threads, err))
            goto fail;
    /* the instance level: empty instances keep a point box at the origin,
     * so the tree stays finite (they hold nothing to hit) */
    aabb *build_boxes = malloc(((size_t)n + 1) * sizeof *build_boxes);
    if (!build_boxes)
        goto oom;
    a->scene_box = aabb_empty();
    for (uint32_t i = 0; i < n; i++) {
        const scene_instance *si = &s->instances[i];
        a->instances[i] = (wbvh_instance){.geometry = &a->geoms[si->geometry], .to_object = si->to_object,
                                          .identity = si->identity};
        a->placements[i] = (accel_placement){si->to_world, si->to_object, si->identity};
        a->instance_bounds[i] = instance_box(&a->placements[i], &a->geoms[si->geometry]);
        build_boxes[i] = aabb_is_empty(a->instance_bounds[i]) ? (aabb){v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 0.f)}
                                                              : a->instance_bounds[i];
        if (!aabb_is_empty(a->instance_bounds[i]))
            a->scene_box = aabb_grow(a->scene_box, a->instance_bounds[i]);
    }
    /* one instance per leaf: entering one costs a packet setup below, so the
     * wide nodes' exact per-ray masks should decide it, not a shared leaf */
    bvh binary;
    bool ok = bvh_build_leaves(&binary, build_boxes, n, 1, 1, err);
    free(build_boxes);
    if (!ok)
        goto fail;
    ok = wbvh_build_instances(&a->top, &binary, a->instances, a->hidden, err);
    bvh_finish(&binary);
    if (!ok)
        goto fail;
    /* boxes from the instances' own bounds (empty ones masked off) */
    wbvh_refit_instances(&a->top, a->instance_bounds);
    return a;
oom:
    tess_error_set(err, "accel: out of memory");
fail:
    accel_destroy(a);
    return NULL;
}

void accel_destroy(accel *a)
{
    if (!a)
        return;
    if (a->geoms)
        for (uint32_t i = 0; i < a->geom_count; i++)
            wbvh_finish(&a->geoms[i]);
    free(a->geoms);
    wbvh_finish(&a->top);
    free(a->instances);
    free(a->instance_bounds);
    free(a->placements);
    free(a->hidden);
    if (a->lock_ready)
        pthread_mutex_destroy(&a->refit_lock);
    free(a);
}

void accel_set_crop(const accel *a, uint32_t geom_id, geometry_crop crop)
{
    if (geom_id >= a->instance_count)
        return;
    const scene_geometry *g = scene_instance_geometry(a->scene, geom_id);
    const geometry_controls *c = geometry_controls_of(g->ops);
    if (c->set_crop)
        c->set_crop(g->data, crop);
}

void accel_set_value(const accel *a, uint32_t geom_id, float value)
{
    if (geom_id >= a->instance_count)
        return;
    const scene_geometry *g = scene_instance_geometry(a->scene, geom_id);
    /* the kind's `closed` answer may follow its value: drop the cached one (a serial section's
     * change, like the value itself) */
    const geometry_controls *c = geometry_controls_of(g->ops);
    if (c->set_value && c->set_value(g->data, value))
        scene_forget_closed((scene *)(uintptr_t)a->scene, a->scene->instances[geom_id].geometry);
}

void accel_set_colormap(const accel *a, uint32_t geom_id, const char *name)
{
    if (geom_id >= a->instance_count)
        return;
    const scene_geometry *g = scene_instance_geometry(a->scene, geom_id);
    const geometry_controls *c = geometry_controls_of(g->ops);
    if (c->set_colormap)
        c->set_colormap(g->data, name);
}

void accel_set_transfer(const accel *a, const char *name)
{
    const scene *s = a->scene;
    for (uint32_t m = 0; m < s->medium_count; m++) {
        const geometry_controls *c = medium_controls_of(s->media[m].ops);
        if (c->set_colormap)
            c->set_colormap(s->media[m].data, name);
    }
}

size_t accel_bytes(const accel *a)
{
    size_t bytes = sizeof *a + wbvh_bytes(&a->top) + a->geom_count * sizeof *a->geoms +
                   a->instance_count * (sizeof *a->instances + sizeof *a->instance_bounds + sizeof *a->hidden);
    for (uint32_t i = 0; i < a->geom_count; i++)
        bytes += wbvh_bytes(&a->geoms[i]);
    return bytes;
}

uint32_t accel_geometry_count(const accel *a) { return a->instance_count; }

bool accel_scene_bounds(const accel *a, vec3 *lo, vec3 *hi)
{
    if (aabb_is_empty(a->scene_box))
        return false;
    *lo = a->scene_box.lo;
    *hi = a->scene_box.hi;
    return true;
}

/* Refit the instance level's stale nodes under the lock accel_pick takes. */
static void refit(accel *a)
{
    pthread_mutex_lock(&a->refit_lock);
    wbvh_refit_stale(&a->top, a->instance_bounds);
    pthread_mutex_unlock(&a->refit_lock);
    atomic_store_explicit(&a->refit_pending, false, memory_order_relaxed);
}

/* The accel is logically const for tracing; hiding changes its mutable part. */
static accel *mutable_accel(const accel *a) { return (accel *)(uintptr_t)a; }

void accel_set_hidden_range(const accel *ca, uint32_t first, uint32_t count, bool hidden)
{
    accel *a = mutable_accel(ca);
    if (first >= a->instance_count)
        return;
    uint32_t end = count > a->instance_count - first ? a->instance_count : first + count;
    bool showed = false, hid = false;
    pthread_mutex_lock(&a->refit_lock); /* the stale marks are the refit's */
    for (uint32_t i = first; i < end; i++) {
        unsigned char old = atomic_exchange_explicit(&a->hidden[i], hidden ? 1u : 0u, memory_order_relaxed);
        if (!old != !hidden)
            wbvh_mark_instances(&a->top, i, 1);
        showed |= old && !hidden;
        hid |= !old && hidden;
    }
    pthread_mutex_unlock(&a->refit_lock);
    if (showed) /* a shown instance must be inside the boxes before anything traces again */
        refit(a);
    else if (hid)
        atomic_store_explicit(&a->refit_pending, true, memory_order_relaxed);
}

void accel_set_hidden(const accel *a, uint32_t geom_id, bool hidden) { accel_set_hidden_range(a, geom_id, 1, hidden); }

void accel_unhide_all(const accel *a) { accel_set_hidden_range(a, 0, a->instance_count, false); }

bool accel_hidden(const accel *a, uint32_t geom_id)
{
    return geom_id < a->instance_count && atomic_load_explicit(&a->hidden[geom_id], memory_order_relaxed) != 0;
}

const accel_placement *accel_placement_of(const accel *a, uint32_t geom_id) { return &a->placements[geom_id]; }

void accel_set_placement(const accel *ca, uint32_t first, uint32_t count, const affine3 *moves)
{
    accel *a = mutable_accel(ca);
    if (first >= a->instance_count)
        return;
    uint32_t end = count > a->instance_count - first ? a->instance_count : first + count;
    pthread_mutex_lock(&a->refit_lock);
    for (uint32_t i = first; i < end; i++) {
        const scene_instance *si = &a->scene->instances[i];
        accel_placement pl = {si->to_world, si->to_object, si->identity};
        if (!affine3_is_identity(&moves[i - first])) {
            pl.to_world = affine3_compose(&moves[i - first], &si->to_world);
            pl.identity = affine3_is_identity(&pl.to_world);
            if (!affine3_invert(&pl.to_world, &pl.to_object))
                continue; /* not invertible after all (rounding): stays where it was */
        }
        a->placements[i] = pl;
        a->instances[i].to_object = pl.to_object;
        a->instances[i].identity = pl.identity;
        a->instance_bounds[i] = instance_box(&pl, a->instances[i].geometry);
    }
    wbvh_mark_instances(&a->top, first, end - first);
    wbvh_refit_stale(&a->top, a->instance_bounds);
    pthread_mutex_unlock(&a->refit_lock);
    atomic_store_explicit(&a->refit_pending, false, memory_order_relaxed);
}

bool accel_commit(const accel *ca)
{
    accel *a = mutable_accel(ca);
    if (!atomic_load_explicit(&a->refit_pending, memory_order_relaxed))
        return false;
    refit(a);
    return true;
}

const char *accel_isa_name(const accel *a) { return a->kernels->isa_name; }

bool accel_use_isa(accel *a, const char *isa_name)
{
    for (int i = 0; i < KERNEL_ISA_COUNT; i++) {
        const kernel_table *t = kernels_for((kernel_isa)i);
        if (t && strcmp(t->isa_name, isa_name) == 0) {
            a->kernels = t;
            return true;
        }
    }
    return false;
}

/* A scene of one untransformed instance (a mesh file) skips the instance
 * level: its geometry's tree, or NULL. The level would cost a second packet
 * setup per packet for nothing (measured: 5-8 % of primary rays on a small
 * mesh). */
static const wbvh *sole_geometry(const accel *a)
{
    if (a->instance_count != 1 || !a->placements[0].identity ||
        atomic_load_explicit(&a->hidden[0], memory_order_relaxed))
        return NULL;
    return a->instances[0].geometry;
}

/* One ray from the root of the instance level. */
static bool trace(const accel *a, ray *r, hit *h, bool any)
{
    if (a->top.node_count == 0 || ray_is_degenerate(r))
        return false;
    ray_derived d = ray_derive(r);
    const wbvh *sole = sole_geometry(a);
    if (sole)
        return a->kernels->intersect1(sole, 0, r, &d, h, any);
    return a->kernels->intersect1(&a->top, 0, r, &d, h, any);
}

bool accel_intersect(const accel *a, const ray *r, hit *h)
{
    *h = hit_none();
    ray local = *r;
    return trace(a, &local, h, false);
}

/* A ray's bound for a next-hit query (ray.h NEXT-HIT QUERIES): t_near raised
 * to the float below after->t. */
static void bound_after(ray *r, ray_derived *d, const hit *after)
{
    d->after_t = after->t;
    d->after_geom = after->geom_id;
    d->after_prim = after->prim_id;
    float below = nextafterf(after->t, -INFINITY);
    if (r->t_near < below)
        r->t_near = below;
}

bool accel_intersect_after(const accel *a, const ray *r, const hit *after, hit *h)
{
    *h = hit_none();
    ray local = *r;
    if (a->top.node_count == 0 || ray_is_degenerate(&local))
        return false;
    ray_derived d = ray_derive(&local);
    bound_after(&local, &d, after);
    if (!(local.t_near < local.t_far))
        return false;
    const wbvh *sole = sole_geometry(a);
    return a->kernels->intersect1(sole ? sole : &a->top, 0, &local, &d, h, false);
}

bool accel_intersect_instance(const accel *a, uint32_t geom_id, const ray *r, const hit *after, hit *h)
{
    *h = hit_none();
    if (geom_id >= a->instance_count || a->instances[geom_id].geometry->node_count == 0)
        return false;
    const wbvh_instance *inst = &a->instances[geom_id];
    ray local = inst->identity ? *r : affine3_ray(&inst->to_object, r);
    if (ray_is_degenerate(&local))
        return false;
    ray_derived d = ray_derive(&local);
    if (after) {
        bound_after(&local, &d, after);
        if (!(local.t_near < local.t_far))
            return false;
    }
    return a->kernels->intersect1(inst->geometry, geom_id, &local, &d, h, false);
}

bool accel_occluded(const accel *a, const ray *r)
{
    ray local = *r;
    hit unused = hit_none();
    return trace(a, &local, &unused, true);
}

bool accel_pick(const accel *ca, const ray *r, hit *h)
{
    accel *a = mutable_accel(ca);
    pthread_mutex_lock(&a->refit_lock);
    bool found = accel_intersect(a, r, h);
    pthread_mutex_unlock(&a->refit_lock);
    return found;
}

void accel_set_single_rays(accel *a, bool single_rays)
{
    a->single_rays = single_rays;
}

/* accel_set_single_rays: the packet's rays of `mask` traced one by one
 * through the single-ray queries; closest hits (with the packet's next-hit
 * bounds) written back as the packet kernels write them. Returns the rays
 * that hit (any: occluded). */
static uint64_t packet_one_by_one(const accel *a, ray_packet *p, uint64_t mask, bool any)
{
    uint64_t found = 0;
    for (uint64_t m = mask; m; m &= m - 1) {
        const uint32_t i = (uint32_t)__builtin_ctzll(m);
        ray one = packet_get_ray(p, i);
        if (any) {
            if (accel_occluded(a, &one))
                found |= 1ull << i;
            continue;
        }
        const hit before = packet_get_hit(p, i);
        hit h;
        bool hit_here;
        if (p->flags & PACKET_AFTER_HIT) {
            const hit after = {.t = p->after_t[i], .geom_id = p->after_geom[i], .prim_id = p->after_prim[i]};
            hit_here = accel_intersect_after(a, &one, &after, &h);
        } else {
            hit_here = accel_intersect(a, &one, &h);
        }
        /* the packet's own hit stands unless this one comes first (as the kernels' offer) */
        if (!hit_here || !hit_comes_first(h.t, h.geom_id, h.prim_id, before.t, before.geom_id, before.prim_id))
            continue;
        packet_set_hit(p, i, &h);
        found |= 1ull << i;
    }
    return found;
}

void accel_intersect_packet(const accel *a, packet_range r)
{
    /* hits change: what was derived from them is stale */
    r.packet->flags &= ~(uint32_t)(PACKET_HAVE_HIT_POSITION | PACKET_HAVE_GEOMETRIC_NORMAL | PACKET_HAVE_SHADING_NORMAL);
    uint64_t mask = a->kernels->traceable(r.packet, packet_range_mask(r));
    if (!mask || a->top.node_count == 0)
        return;
    if (a->single_rays) {
        packet_one_by_one(a, r.packet, mask, false);
        return;
    }
    packet_derive_inv_dir(r.packet);
    const wbvh *sole = sole_geometry(a);
    a->kernels->intersect_packet(sole ? sole : &a->top, 0, r.packet, mask, false);
}

uint64_t accel_occluded_packet(const accel *a, packet_range r)
{
    uint64_t mask = a->kernels->traceable(r.packet, packet_range_mask(r));
    if (!mask || a->top.node_count == 0)
        return 0;
    if (a->single_rays)
        return packet_one_by_one(a, r.packet, mask, true);
    packet_derive_inv_dir(r.packet);
    const wbvh *sole = sole_geometry(a);
    return a->kernels->intersect_packet(sole ? sole : &a->top, 0, r.packet, mask, true);
}

bool accel_set_time_step(const accel *ca, uint32_t step, tess_error *err)
{
    accel *a = mutable_accel(ca);
    scene *s = (scene *)(uintptr_t)a->scene; /* its closed cache follows the step (a serial section) */
    bool ok = true;
    pthread_mutex_lock(&a->refit_lock);
    for (uint32_t g = 0; g < a->geom_count; g++) {
        const scene_geometry *sg = &s->geometries[g];
        const geometry_controls *c = geometry_controls_of(sg->ops);
        /* one state only: nothing changes (no tree to take or rebuild) */
        if (!c->set_step || (c->step_count && c->step_count(sg->data) <= 1))
            continue;
        if (!c->set_step(sg->data, step, ok ? err : NULL)) {
            ok = false;
            continue;
        }
        scene_forget_closed(s, g); /* whether it bounds a solid may differ from step to step */
        if (sg->ops->leaf == GEOMETRY_LEAF_POINTS) { /* its tree changed with its points */
            const wbvh *t = sg->ops->tree(sg->data, 1, ok ? err : NULL);
            if (!t) {
                ok = false;
                continue;
            }
            a->geoms[g] = *t;
            a->geoms[g].borrowed = true;
        } else {
            /* its primitives' boxes may have moved with the step (an
             * iso-surface's active box): its bottom level again, from
             * prim_bounds (kinds with time steps keep few primitives) */
            wbvh fresh;
            if (!build_geometry(&fresh, sg, 1, ok ? err : NULL)) {
                ok = false;
                continue;
            }
            wbvh_finish(&a->geoms[g]);
            a->geoms[g] = fresh;
        }
        for (uint32_t i = 0; i < a->instance_count; i++)
            if (s->instances[i].geometry == g) {
                a->instance_bounds[i] = instance_box(&a->placements[i], &a->geoms[g]);
                wbvh_mark_instances(&a->top, i, 1);
            }
    }
    /* media (a volume rendered directly): their boxes stay; a medium sharing
     * a series with a geometry above finds the step shown already */
    for (uint32_t m = 0; m < s->medium_count; m++) {
        const scene_medium *sm = &s->media[m];
        const geometry_controls *c = medium_controls_of(sm->ops);
        if (c->set_step && !c->set_step(sm->data, step, ok ? err : NULL))
            ok = false;
    }
    wbvh_refit_stale(&a->top, a->instance_bounds);
    pthread_mutex_unlock(&a->refit_lock);
    return ok;
}

/* Each node's boxes, children and slots as built (not child_mask, which hiding
 * changes, nor padding). */
static void hash_tree(XXH3_state_t *st, const wbvh *w)
{
    XXH3_64bits_update(st, &w->node_count, sizeof w->node_count);
    XXH3_64bits_update(st, &w->block_count, sizeof w->block_count);
    for (uint32_t i = 0; i < w->node_count; i++) {
        const wbvh_node *n = &w->nodes[i];
        XXH3_64bits_update(st, n->lo_x, sizeof n->lo_x);
        XXH3_64bits_update(st, n->hi_x, sizeof n->hi_x);
        XXH3_64bits_update(st, n->lo_y, sizeof n->lo_y);
        XXH3_64bits_update(st, n->hi_y, sizeof n->hi_y);
        XXH3_64bits_update(st, n->lo_z, sizeof n->lo_z);
        XXH3_64bits_update(st, n->hi_z, sizeof n->hi_z);
        XXH3_64bits_update(st, n->child, sizeof n->child);
        XXH3_64bits_update(st, n->leaf_blocks, sizeof n->leaf_blocks);
        XXH3_64bits_update(st, &n->slot_mask, sizeof n->slot_mask);
    }
}

uint64_t accel_checksum(const accel *a)
{
    XXH3_state_t *st = XXH3_createState();
    if (!st)
        return 0;
    XXH3_64bits_reset(st);
    XXH3_64bits_update(st, &a->geom_count, sizeof a->geom_count);
    XXH3_64bits_update(st, &a->instance_count, sizeof a->instance_count);
    for (uint32_t g = 0; g < a->geom_count; g++)
        hash_tree(st, &a->geoms[g]);
    for (uint32_t i = 0; i < a->instance_count; i++) {
        const aabb *b = &a->instance_bounds[i];
        XXH3_64bits_update(st, b, sizeof *b);
    }
    uint64_t h = XXH3_64bits_digest(st);
    XXH3_freeState(st);
    return h;
}
