/* particle_kind.c - particles as a geometry kind (particle_kind.h). */
#include "particle_kind.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/accel/bvh.h"
#include "engine/accel/intersect.h"
#include "engine/base/parallel.h"
#include "engine/base/series.h"
#include "engine/base/srgb.h"
#include "engine/accel/wbvh.h"

/* Particles a leaf of the tree holds at most: one 16-lane AVX-512 test
 * (the SAH decides below that), and how many one leaf test takes in the
 * SAH's cost of a leaf (2^this). */
#define PARTICLE_LEAF_MAX WBVH_POINTS_LEAF_MAX
#define PARTICLE_LEAF_BLOCK_LOG2 4u
/* Particles per parallel chunk of box computation. */
#define PARTICLE_BOX_GRAIN 16384

/* Where a set keeps the attributes the kind reads (found by name in each
 * step's set: files of a series may order their columns differently). */
typedef struct step_layout {
    int radius, crop, colour, rgb[3]; /* indices in the set, -1 when unused */
} step_layout;

/* One time step as the series' loader makes it (series.h): the set, where
 * its attributes are, and its tree, built off the render threads. */
typedef struct particle_step {
    particle_set *set;
    step_layout lay;
    wbvh tree;
} particle_step;

struct particle_kind {
    particle_set *set;     /* owned; capacity >= count + GEOMETRY_POINTS_PAD (kernels read past) */
    /* the attributes by name (resolved in every step's set: step_layout) */
    char radius_name[PARTICLE_NAME_BYTES], crop_name[PARTICLE_NAME_BYTES], colour_name[PARTICLE_NAME_BYTES];
    particle_file_reader *read; /* TIME STEPS: how a step's file is read (set with series) */
    series *series;        /* TIME STEPS (series.h): NULL: one set. The shown step's set and tree are
                              set and tree below; they change only in particle_kind_set_step, which
                              runs where nothing traces (a serial section) */
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

/* The attributes the kind reads, found by name in `set`, checked: a per-
 * particle radius must be > 0 everywhere. */
static bool resolve_layout(const particle_kind *k, const particle_set *set, step_layout *lay, const char *source,
                           tess_error *err)
{
    *lay = (step_layout){-1, -1, -1, {-1, -1, -1}};
    if (k->radius_name[0]) {
        if ((lay->radius = particle_set_find_attribute(set, k->radius_name)) < 0)
            return tess_error_set(err, "%s: no attribute '%s' for the radius", source, k->radius_name);
        const float *r = set->attributes[lay->radius].values;
        for (uint32_t i = 0; i < set->count; i++)
            if (!(r[i] > 0.f))
                return tess_error_set(err, "%s: particle %u: radius attribute '%s' is %g (must be > 0)", source, i,
                                      k->radius_name, (double)r[i]);
    }
    if (k->crop_name[0] && (lay->crop = particle_set_find_attribute(set, k->crop_name)) < 0)
        return tess_error_set(err, "%s: no attribute '%s' to crop by", source, k->crop_name);
    if (k->colouring == PARTICLE_COLOUR_MAP && (lay->colour = particle_set_find_attribute(set, k->colour_name)) < 0)
        return tess_error_set(err, "%s: no attribute '%s' to colour by", source, k->colour_name);
    if (k->colouring == PARTICLE_COLOUR_RGB) {
        static const char *const names[3] = {"red", "green", "blue"};
        for (int c = 0; c < 3; c++)
            if ((lay->rgb[c] = particle_set_find_attribute(set, names[c])) < 0)
                return tess_error_set(err, "%s: colour by rgb needs the attributes red, green and blue (no '%s')",
                                      source, names[c]);
    }
    /* the kernels read GEOMETRY_POINTS_PAD floats past the last particle */
    return particle_set_fit((particle_set *)set, GEOMETRY_POINTS_PAD) ||
           tess_error_set(err, "%s: out of memory for %u particles", source, set->count);
}

static void apply_layout(particle_kind *k, const step_layout *lay)
{
    k->radius_attribute = lay->radius;
    k->crop_attribute = lay->crop;
    k->colour_attribute = lay->colour;
    memcpy(k->rgb_attribute, lay->rgb, sizeof k->rgb_attribute);
}

static bool copy_name(char *out, const char *name, const char *what, const char *source, tess_error *err)
{
    if (!name)
        return true;
    size_t len = strlen(name);
    if (len == 0 || len >= PARTICLE_NAME_BYTES)
        return tess_error_set(err, "%s: no attribute '%s' %s", source, name, what);
    memcpy(out, name, len + 1);
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
    k->material_id = opt->material_id;
    k->radius_all = opt->radius;
    k->colouring = opt->colouring;
    atomic_init(&k->tree_ready, false);
    step_layout lay;
    if (!copy_name(k->radius_name, opt->radius_attribute, "for the radius", source, err) ||
        !copy_name(k->crop_name, opt->crop_attribute, "to crop by", source, err) ||
        !copy_name(k->colour_name, opt->colouring != PARTICLE_COLOUR_MAP ? NULL
                                   : opt->colour_attribute              ? opt->colour_attribute
                                                                        : "",
                   "to colour by", source, err))
        goto fail;
    if (!opt->radius_attribute && (!(opt->radius > 0.f) || !isfinite(opt->radius))) {
        tess_error_set(err, "%s: the radius must be a finite number > 0", source);
        goto fail;
    }
    if (!resolve_layout(k, set, &lay, source, err))
        goto fail;
    apply_layout(k, &lay);
    if (k->crop_attribute >= 0)
        k->crop = opt->crop;
    if (k->colouring == PARTICLE_COLOUR_RGB)
        for (int v = 0; v < 256; v++)
            k->srgb_decode[v] = (float)srgb_curve_decode(v / 255.0);
    if (k->colouring == PARTICLE_COLOUR_MAP) {
        /* the range is fitted to this set (a series' first step: every step keeps its colours) */
        if (opt->map)
            k->map = *opt->map;
        else
            colormap_preset("viridis", &k->map);
        const particle_attribute *a = &set->attributes[k->colour_attribute];
        colormap_fit_range(&k->map, a->min, a->max);
        if (!(k->table = malloc(sizeof *k->table))) {
            tess_error_set(err, "%s: out of memory for the colour map", source);
            goto fail;
        }
        colormap_bake(&k->map, k->table);
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
    series_destroy(k->series); /* first: its loader reads k */
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

bool particle_kind_set_colormap(particle_kind *k, const char *name)
{
    colormap next;
    if (k->colouring != PARTICLE_COLOUR_MAP || !colormap_preset(name, &next))
        return false;
    /* the range stays (the scene's, or the fitted one) */
    next.lo = k->map.lo;
    next.hi = k->map.hi;
    next.range_auto = k->map.range_auto;
    k->map = next;
    colormap_bake(&k->map, k->table);
    return true;
}

void particle_kind_set_crop(particle_kind *k, geometry_crop crop)
{
    if (k->crop_attribute >= 0)
        k->crop = crop;
}

/* ---- time steps (series.h) --------------------------------------------- */

static bool build_tree(const particle_kind *k, particle_set *set, const step_layout *lay, wbvh *tree, int threads,
                       tess_error *err);

static void free_step(void *ctx, void *data)
{
    (void)ctx;
    particle_step *st = data;
    particle_set_destroy(st->set);
    wbvh_finish(&st->tree);
    free(st);
}

/* The loader thread's work: the step's set, checked, and its tree, built
 * on one thread while frames render. */
static void *load_step(void *ctx, const char *path, uint32_t step, tess_error *err)
{
    (void)step;
    const particle_kind *k = ctx;
    particle_step *st = calloc(1, sizeof *st);
    if (!st) {
        tess_error_set(err, "%s: out of memory", path);
        return NULL;
    }
    st->set = k->read(path, err);
    if (!st->set || !resolve_layout(k, st->set, &st->lay, path, err) ||
        !build_tree(k, st->set, &st->lay, &st->tree, 1, err)) {
        free_step(NULL, st);
        return NULL;
    }
    return st;
}

bool particle_kind_attach_series(particle_kind *k, const char *const *paths, uint32_t count, particle_file_reader *read,
                                 tess_error *err)
{
    k->read = read;
    k->series = series_create(paths, count, 0, load_step, free_step, k, err);
    if (!k->series)
        tess_error_prefix(err, "particles: ");
    return k->series != NULL;
}

uint32_t particle_kind_step_count(const particle_kind *k) { return k->series ? series_step_count(k->series) : 1; }
uint32_t particle_kind_step(const particle_kind *k) { return k->series ? series_step(k->series) : 0; }

bool particle_kind_step_ready(particle_kind *k, uint32_t step)
{
    return k->series ? series_ready(k->series, step) : step == 0;
}

bool particle_kind_set_step(particle_kind *k, uint32_t step, tess_error *err)
{
    if (!k->series)
        return true; /* one set: every step is it */
    void *taken;
    if (!series_take(k->series, step, &taken, err))
        return false;
    particle_step *st = taken;
    if (!st)
        return true; /* shown already */
    particle_set *old_set = k->set;
    wbvh old_tree = k->tree;
    k->set = st->set;
    k->tree = st->tree;
    apply_layout(k, &st->lay);
    atomic_store_explicit(&k->tree_ready, true, memory_order_release);
    free(st);
    particle_set_destroy(old_set);
    wbvh_finish(&old_tree);
    series_done(k->series); /* the old step is gone: the next one may load */
    return true;
}

/* ---- geometry ops ------------------------------------------------------ */

static uint32_t kind_count(const void *data) { return ((const particle_kind *)data)->set->count; }

/* The box of point i of a points view (its centre +- its radius). */
static aabb point_box(const geometry_points *p, uint32_t i)
{
    float r = p->radius ? p->radius[i] : p->radius_all;
    vec3 c = v3(p->x[i], p->y[i], p->z[i]);
    return (aabb){v3_sub(c, v3(r, r, r)), v3_add(c, v3(r, r, r))};
}

static void kind_points(const void *data, geometry_points *out);

static bool kind_prim_bounds(const void *data, uint32_t prim, aabb *out)
{
    geometry_points p;
    kind_points(data, &p);
    *out = point_box(&p, prim);
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

/* The arrays the kernels read for `set` under layout `lay`. */
static void points_of(const particle_kind *k, const particle_set *s, const step_layout *lay, geometry_points *out)
{
    *out = (geometry_points){
        .count = s->count,
        .x = s->x,
        .y = s->y,
        .z = s->z,
        .radius = lay->radius >= 0 ? s->attributes[lay->radius].values : NULL,
        .radius_all = k->radius_all,
        .crop_value = lay->crop >= 0 ? s->attributes[lay->crop].values : NULL,
        .crop = &k->crop,
    };
}

static step_layout current_layout(const particle_kind *k)
{
    return (step_layout){k->radius_attribute, k->crop_attribute, k->colour_attribute,
                         {k->rgb_attribute[0], k->rgb_attribute[1], k->rgb_attribute[2]}};
}

static void kind_points(const void *data, geometry_points *out)
{
    const particle_kind *k = data;
    step_layout lay = current_layout(k);
    points_of(k, k->set, &lay, out);
}

typedef struct box_job {
    geometry_points points;
    aabb *boxes;
} box_job;

static void particle_boxes(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    box_job *job = ctx;
    for (size_t i = begin; i < end; i++)
        job->boxes[i] = point_box(&job->points, (uint32_t)i);
}

/* The binary SAH tree over the boxes of `set`'s particles, the set put in
 * its order (so leaf [first, first + count) of prim_order is particles
 * first..), then collapsed into the wide tree the kernels read in place. */
static bool build_tree(const particle_kind *k, particle_set *set, const step_layout *lay, wbvh *tree, int threads,
                       tess_error *err)
{
    uint32_t n = set->count;
    aabb *boxes = malloc(((size_t)n + 1) * sizeof *boxes);
    if (!boxes)
        return tess_error_set(err, "particles: out of memory for the boxes of %u particles", n);
    box_job job = {.boxes = boxes};
    points_of(k, set, lay, &job.points);
    parallel_for(threads, n, PARTICLE_BOX_GRAIN, particle_boxes, &job);
    bvh binary;
    bool ok = bvh_build_blocks(&binary, boxes, n, threads, PARTICLE_LEAF_MAX, PARTICLE_LEAF_BLOCK_LOG2, err);
    free(boxes);
    if (!ok)
        return false;
    ok = particle_set_permute(set, binary.prim_order) ||
         tess_error_set(err, "particles: out of memory reordering %u particles", n);
    if (ok) {
        geometry_points points;
        points_of(k, set, lay, &points);
        ok = wbvh_build_points(tree, &binary, &points, err);
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
    step_layout lay = current_layout(k);
    bool ok = atomic_load_explicit(&k->tree_ready, memory_order_relaxed) ||
              build_tree(k, k->set, &lay, &k->tree, threads, err);
    if (ok)
        atomic_store_explicit(&k->tree_ready, true, memory_order_release);
    pthread_mutex_unlock(&k->tree_lock);
    return ok ? &k->tree : NULL;
}

static void kind_set_crop(void *data, geometry_crop crop) { particle_kind_set_crop(data, crop); }
static bool kind_set_colormap(void *data, const char *name) { return particle_kind_set_colormap(data, name); }
static const colormap *kind_colormap(const void *data) { return particle_kind_colormap(data); }

static bool kind_crop_attribute(const void *data, geometry_crop_attribute *out)
{
    const particle_kind *k = data;
    int attr = particle_kind_crop_attribute(k);
    if (attr < 0)
        return false;
    const particle_attribute *a = &particle_kind_set(k)->attributes[attr];
    *out = (geometry_crop_attribute){.min = a->min, .max = a->max, .crop = particle_kind_crop(k)};
    snprintf(out->name, sizeof out->name, "%s", a->name);
    return true;
}
static uint32_t kind_step_count(const void *data) { return particle_kind_step_count(data); }
static bool kind_step_ready(void *data, uint32_t step) { return particle_kind_step_ready(data, step); }
static bool kind_set_step(void *data, uint32_t step, tess_error *err)
{
    return particle_kind_set_step(data, step, err);
}

static const geometry_controls kind_controls = {
    .set_crop = kind_set_crop,
    .crop_attribute = kind_crop_attribute,
    .step_count = kind_step_count,
    .step_ready = kind_step_ready,
    .set_step = kind_set_step,
    .set_colormap = kind_set_colormap,
    .colormap = kind_colormap,
};

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
    .controls = &kind_controls,
};
