/* particle_kind.c - particles as a geometry kind (particle_kind.h). */
#include "particle_kind.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/bvh.h"
#include "engine/intersect.h"
#include "engine/parallel.h"
#include "engine/srgb.h"
#include "engine/wbvh.h"

/* Particles a leaf of the tree holds at most: one 16-lane AVX-512 test
 * (the SAH decides below that), and how many one leaf test takes in the
 * SAH's cost of a leaf (2^this). */
#define PARTICLE_LEAF_MAX WBVH_POINTS_LEAF_MAX
#define PARTICLE_LEAF_BLOCK_LOG2 4u
/* Particles per parallel chunk of box computation. */
#define PARTICLE_BOX_GRAIN 16384

struct particle_kind {
    particle_set *set;     /* owned; capacity >= count + GEOMETRY_POINTS_PAD (kernels read past) */
    int radius_attribute;  /* index in set, or -1: radius_all */
    float radius_all;
    int crop_attribute;    /* index in set, or -1 */
    geometry_crop crop;    /* written only in serial sections (particle_kind_set_crop) */
    uint32_t material_id;
    /* COLOUR: what describe reports (particle_colouring) */
    particle_colouring colouring;
    int colour_attribute;  /* PARTICLE_COLOUR_MAP: index in set */
    int rgb_attribute[3];  /* PARTICLE_COLOUR_RGB: red, green, blue */
    colormap map;          /* PARTICLE_COLOUR_MAP, range fitted */
    colormap_table *table; /* PARTICLE_COLOUR_MAP: map baked for the per-hit lookup; else NULL */
    float srgb_decode[256]; /* PARTICLE_COLOUR_RGB: linear value of each code */
    /* THE TREE, built once by the first kind_tree call. tree_lock guards
     * the build; tree_ready (release after the build, acquire before use)
     * lets later calls skip the lock. */
    pthread_mutex_t tree_lock;
    atomic_bool tree_ready;
    wbvh tree;
};

static inline float radius_of(const particle_kind *k, uint32_t p)
{
    return k->radius_attribute >= 0 ? k->set->attributes[k->radius_attribute].values[p] : k->radius_all;
}

static inline bool seen(const particle_kind *k, uint32_t p)
{
    if (k->crop_attribute < 0 || !k->crop.active)
        return true;
    float v = k->set->attributes[k->crop_attribute].values[p];
    return k->crop.lo <= v && v <= k->crop.hi;
}

/* the default radius as a fraction of the centres' box diagonal */
#define DEFAULT_RADIUS_OF_DIAGONAL 0.001f

float particle_kind_default_radius(const particle_set *set)
{
    float lo[3], hi[3];
    if (!particle_set_bounds(set, lo, hi))
        return 1.f;
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    float diag = sqrtf(dx * dx + dy * dy + dz * dz);
    return diag > 0.f ? DEFAULT_RADIUS_OF_DIAGONAL * diag : 1.f;
}

static bool set_colouring(particle_kind *k, const particle_kind_options *opt, const char *source, tess_error *err)
{
    k->colouring = opt->colouring;
    if (opt->colouring == PARTICLE_COLOUR_RGB) {
        static const char *const names[3] = {"red", "green", "blue"};
        for (int c = 0; c < 3; c++)
            if ((k->rgb_attribute[c] = particle_set_find_attribute(k->set, names[c])) < 0)
                return tess_error_set(err, "%s: colour by rgb needs the attributes red, green and blue (no '%s')",
                                      source, names[c]);
        for (int v = 0; v < 256; v++)
            k->srgb_decode[v] = (float)srgb_curve_decode(v / 255.0);
        return true;
    }
    if (opt->colouring != PARTICLE_COLOUR_MAP)
        return true;
    if (!opt->colour_attribute || (k->colour_attribute = particle_set_find_attribute(k->set, opt->colour_attribute)) < 0)
        return tess_error_set(err, "%s: no attribute '%s' to colour by", source,
                              opt->colour_attribute ? opt->colour_attribute : "");
    if (opt->map)
        k->map = *opt->map;
    else
        colormap_preset("viridis", &k->map);
    const particle_attribute *a = &k->set->attributes[k->colour_attribute];
    colormap_fit_range(&k->map, a->min, a->max);
    if (!(k->table = malloc(sizeof *k->table)))
        return tess_error_set(err, "%s: out of memory for the colour map", source);
    colormap_bake(&k->map, k->table);
    return true;
}

particle_kind *particle_kind_create(particle_set *set, const particle_kind_options *opt, const char *source,
                                    tess_error *err)
{
    particle_kind *k = calloc(1, sizeof *k);
    if (!k || pthread_mutex_init(&k->tree_lock, NULL) != 0) {
        free(k);
        particle_set_destroy(set);
        tess_error_set(err, "%s: out of memory", source);
        return NULL;
    }
    k->set = set;
    k->radius_attribute = -1;
    k->crop_attribute = -1;
    k->material_id = opt->material_id;
    k->radius_all = opt->radius;
    atomic_init(&k->tree_ready, false);
    if (opt->radius_attribute) {
        k->radius_attribute = particle_set_find_attribute(set, opt->radius_attribute);
        if (k->radius_attribute < 0) {
            tess_error_set(err, "%s: no attribute '%s' for the radius", source, opt->radius_attribute);
            goto fail;
        }
        const float *r = set->attributes[k->radius_attribute].values;
        for (uint32_t i = 0; i < set->count; i++)
            if (!(r[i] > 0.f)) {
                tess_error_set(err, "%s: particle %u: radius attribute '%s' is %g (must be > 0)", source, i,
                               opt->radius_attribute, (double)r[i]);
                goto fail;
            }
    } else if (!(opt->radius > 0.f) || !isfinite(opt->radius)) {
        tess_error_set(err, "%s: the radius must be a finite number > 0", source);
        goto fail;
    }
    if (!set_colouring(k, opt, source, err))
        goto fail;
    if (opt->crop_attribute) {
        k->crop_attribute = particle_set_find_attribute(set, opt->crop_attribute);
        if (k->crop_attribute < 0) {
            tess_error_set(err, "%s: no attribute '%s' to crop by", source, opt->crop_attribute);
            goto fail;
        }
        k->crop = opt->crop;
    }
    /* the kernels read GEOMETRY_POINTS_PAD floats past the last particle */
    if (!particle_set_fit(set, GEOMETRY_POINTS_PAD)) {
        tess_error_set(err, "%s: out of memory for %u particles", source, set->count);
        goto fail;
    }
    return k;
fail:
    particle_kind_destroy(k);
    return NULL;
}

void particle_kind_destroy(particle_kind *k)
{
    if (!k)
        return;
    wbvh_finish(&k->tree);
    free(k->table);
    pthread_mutex_destroy(&k->tree_lock);
    particle_set_destroy(k->set);
    free(k);
}

const particle_set *particle_kind_set(const particle_kind *k) { return k->set; }
const colormap *particle_kind_colormap(const particle_kind *k)
{
    return k->colouring == PARTICLE_COLOUR_MAP ? &k->map : NULL;
}
geometry_crop particle_kind_crop(const particle_kind *k) { return k->crop; }
int particle_kind_crop_attribute(const particle_kind *k) { return k->crop_attribute; }

void particle_kind_set_crop(particle_kind *k, geometry_crop crop)
{
    if (k->crop_attribute >= 0)
        k->crop = crop;
}

/* ---- geometry ops ------------------------------------------------------ */

static uint32_t kind_count(const void *data) { return ((const particle_kind *)data)->set->count; }

static bool kind_prim_bounds(const void *data, uint32_t prim, aabb *out)
{
    const particle_kind *k = data;
    const particle_set *s = k->set;
    float r = radius_of(k, prim);
    vec3 c = v3(s->x[prim], s->y[prim], s->z[prim]);
    *out = (aabb){v3_sub(c, v3(r, r, r)), v3_add(c, v3(r, r, r))};
    return true;
}

static bool kind_intersect(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v)
{
    const particle_kind *k = data;
    const particle_set *s = k->set;
    *u = *v = 0.f;
    return seen(k, prim) && intersect_sphere(r, v3(s->x[prim], s->y[prim], s->z[prim]), radius_of(k, prim), t);
}

static void kind_describe(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                          geometry_surface *out)
{
    (void)need_position; /* the normal comes with the point */
    const particle_kind *k = data;
    const particle_set *s = k->set;
    vec3 c = v3(s->x[prim], s->y[prim], s->z[prim]);
    surface_point pt = surface_point_sphere(r->org, r->dir, h->t, c, radius_of(k, prim), &out->geometric_n);
    out->position = pt.p;
    out->position_error = pt.error;
    out->shading_n = out->geometric_n;
    out->material_id = k->material_id;
    out->has_colour = k->colouring != PARTICLE_COLOUR_MATERIAL;
    if (k->colouring == PARTICLE_COLOUR_MAP) {
        colormap_rgba mapped = colormap_lookup(k->table, s->attributes[k->colour_attribute].values[prim]);
        out->colour = v3(mapped.r, mapped.g, mapped.b);
    } else if (k->colouring == PARTICLE_COLOUR_RGB) {
        float rgb[3];
        for (int ch = 0; ch < 3; ch++) {
            float code = s->attributes[k->rgb_attribute[ch]].values[prim];
            /* code values 0..255 (rounded; outside clamped) */
            int i = code > 0.f ? (code < 255.f ? (int)(code + 0.5f) : 255) : 0;
            rgb[ch] = k->srgb_decode[i];
        }
        out->colour = v3(rgb[0], rgb[1], rgb[2]);
    }
}

static size_t kind_bytes(const void *data) { return particle_set_bytes(((const particle_kind *)data)->set); }

static void kind_destroy(void *data) { particle_kind_destroy(data); }

/* Each particle bounds a ball (as the spheres kind). */
static bool kind_closed(const void *data)
{
    (void)data;
    return true;
}

static void kind_points(const void *data, geometry_points *out)
{
    const particle_kind *k = data;
    const particle_set *s = k->set;
    *out = (geometry_points){
        .count = s->count,
        .x = s->x,
        .y = s->y,
        .z = s->z,
        .radius = k->radius_attribute >= 0 ? s->attributes[k->radius_attribute].values : NULL,
        .radius_all = k->radius_all,
        .crop_value = k->crop_attribute >= 0 ? s->attributes[k->crop_attribute].values : NULL,
        .crop = &k->crop,
    };
}

typedef struct box_job {
    const particle_kind *k;
    aabb *boxes;
} box_job;

static void particle_boxes(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    box_job *job = ctx;
    for (size_t i = begin; i < end; i++)
        kind_prim_bounds(job->k, (uint32_t)i, &job->boxes[i]);
}

/* The binary SAH tree over the particles' boxes, the set put in its order
 * (so leaf [first, first + count) of prim_order is particles first..), then
 * collapsed into the wide tree the kernels read in place. */
static bool build_tree(particle_kind *k, int threads, tess_error *err)
{
    uint32_t n = k->set->count;
    aabb *boxes = malloc(((size_t)n + 1) * sizeof *boxes);
    if (!boxes)
        return tess_error_set(err, "particles: out of memory for the boxes of %u particles", n);
    box_job job = {k, boxes};
    parallel_for(threads, n, PARTICLE_BOX_GRAIN, particle_boxes, &job);
    bvh binary;
    bool ok = bvh_build_blocks(&binary, boxes, n, threads, PARTICLE_LEAF_MAX, PARTICLE_LEAF_BLOCK_LOG2, err);
    free(boxes);
    if (!ok)
        return false;
    ok = particle_set_permute(k->set, binary.prim_order) ||
         tess_error_set(err, "particles: out of memory reordering %u particles", n);
    if (ok) {
        geometry_points points;
        kind_points(k, &points);
        ok = wbvh_build_points(&k->tree, &binary, &points, err);
    }
    bvh_finish(&binary);
    return ok;
}

static const wbvh *kind_tree(void *data, int threads, tess_error *err)
{
    particle_kind *k = data;
    if (atomic_load_explicit(&k->tree_ready, memory_order_acquire))
        return &k->tree;
    pthread_mutex_lock(&k->tree_lock);
    bool ok = atomic_load_explicit(&k->tree_ready, memory_order_relaxed) || build_tree(k, threads, err);
    if (ok)
        atomic_store_explicit(&k->tree_ready, true, memory_order_release);
    pthread_mutex_unlock(&k->tree_lock);
    return ok ? &k->tree : NULL;
}

static void kind_set_crop(void *data, geometry_crop crop) { particle_kind_set_crop(data, crop); }

const geometry_ops particle_kind_ops = {
    .name = "particles",
    .leaf = GEOMETRY_LEAF_POINTS,
    .prim_count = kind_count,
    .bounds = NULL,
    .prim_bounds = kind_prim_bounds,
    .fill_lane = NULL,
    .intersect = kind_intersect,
    .describe = kind_describe,
    .bytes = kind_bytes,
    .destroy = kind_destroy,
    .closed = kind_closed,
    .points = kind_points,
    .tree = kind_tree,
    .set_crop = kind_set_crop,
};
