/* cmd_robust.c - `tessera robust`: the kernels on the hard cases of
 * tools/robust/hard_cases.h (the generators tests/test_robust.c uses),
 * counting wrong answers and measuring the speed over the same rays. It is
 * what the report's robustness knob runs against both builds: this one and
 * build-unrobust/tessera (engine/accel/intersect.h, TESSERA_UNROBUST).
 *
 * One line per case on stdout:
 *   case=NAME rays=N wrong_hits=W leaks=L per_million=X mrays_s=M checked=C build=B isa=I threads=T
 *   mrays_s_min=A mrays_s_max=B mrays_cpu_s=P mrays_cpu_s_min=Q mrays_cpu_s_max=R
 * (mrays_cpu_s: millions of rays per CPU second of this process, median)
 * rays: traced and timed; checked: those compared with the right answer (all
 * but the primary case's, which checks a subsample against a brute-force
 * reference in double); per_million = (W + L) * 1e6 / checked; mrays_s: rays /
 * wall time of tracing them all, median of --repeat runs, each run tracing the
 * case as many times over as takes ROBUST_MIN_RUN_S (the set-up, scene building
 * and checking are not timed). Every ray goes through the packet
 * entry points (accel_intersect_packet, or accel_occluded_packet for shadow
 * rays), 64 at a time, as the renderer's. */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "engine/scene/accel.h"
#include "engine/base/camera.h"
#include "engine/accel/intersect.h"
#include "engine/accel/packet.h"
#include "engine/scene/scene.h"
#include "tools/robust/hard_cases.h"

#define ROBUST_MAX_THREADS 256
#define ROBUST_MAX_REPEAT 1000
/* A timed run traces its case as many times as takes at least this long (by
 * the untimed first pass), at most ROBUST_MAX_PASSES times: short cases
 * (--small) would otherwise be timed over a few milliseconds. */
#define ROBUST_MIN_RUN_S 0.25
#define ROBUST_MAX_PASSES 10000
/* The primary case checks every ROBUST_PRIMARY_STRIDE-th ray against brute
 * force in double (every ROBUST_PRIMARY_STRIDE_SMALL-th with --small). */
#define ROBUST_PRIMARY_STRIDE 64
#define ROBUST_PRIMARY_STRIDE_SMALL 16
/* Primary case: hit/miss or primitive differences closer than this to being
 * right are not counted (barycentrics of a triangle, relative distance of the
 * ray from a sphere's silhouette, relative t of two crossings: a near tie). A
 * float kernel is ~1e-7 relative; 1e-5 leaves room for the grazing rays at
 * silhouettes. */
#define ROBUST_PRIMARY_BAND 1e-5

#ifdef TESSERA_UNROBUST
#define ROBUST_BUILD "fast"
#else
#define ROBUST_BUILD "robust"
#endif

typedef enum robust_query { QUERY_CLOSEST, QUERY_ANY } robust_query;

/* Rays traced against one accel with one query; results by ray index. */
typedef struct robust_batch {
    accel *accel;
    size_t scene;        /* index in the case's scenes of the scene of accel */
    size_t first, count; /* rays [first, first + count) of the case */
    robust_query query;
} robust_batch;

/* A scene of a case and its accel (both owned by the case). */
typedef struct robust_scene {
    scene *scene;
    accel *accel;
} robust_scene;

/* A case made ready to trace: its scenes, rays and results. */
typedef struct robust_case {
    robust_scene *scenes;
    size_t scene_count, scene_capacity;
    robust_batch *batches;
    size_t batch_count, batch_capacity;
    ray *rays;
    size_t ray_count, ray_capacity;
    size_t check_stride;       /* primary: check every check_stride-th ray */
    hit *hits;                 /* QUERY_CLOSEST results */
    unsigned char *occluded;   /* QUERY_ANY results */
} robust_case;

typedef struct robust_options {
    const char *cases[8];
    int case_count;
    int threads, repeat;
    bool small;
} robust_options;

typedef struct robust_counts {
    uint64_t wrong_hits, leaks, checked;
} robust_counts;

/* ---- building a case ---- */

static bool grow(void **array, size_t *capacity, size_t need, size_t element_bytes)
{
    if (need <= *capacity)
        return true;
    size_t cap = *capacity ? *capacity * 2 : 64;
    while (cap < need)
        cap *= 2;
    void *p = realloc(*array, cap * element_bytes);
    if (!p)
        return false;
    *array = p;
    *capacity = cap;
    return true;
}

/* Give the case scene s and accel a (destroyed here on failure). */
static bool case_keep_scene(robust_case *c, scene *s, accel *a)
{
    if (!grow((void **)&c->scenes, &c->scene_capacity, c->scene_count + 1, sizeof *c->scenes)) {
        accel_destroy(a);
        scene_destroy(s);
        return false;
    }
    c->scenes[c->scene_count++] = (robust_scene){s, a};
    return true;
}

/* A scene of the one mesh m (owned from here on, also on failure) and its accel. */
static accel *case_add_mesh_scene(robust_case *c, mesh *m)
{
    if (!m)
        return NULL;
    scene *s = scene_create();
    material mat = material_default();
    if (!s || scene_add_material(s, &mat) != 0) {
        mesh_destroy(m);
        scene_destroy(s);
        return NULL;
    }
    if (scene_add_mesh(s, m, 0, "hard case") < 0) { /* it took m */
        scene_destroy(s);
        return NULL;
    }
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    if (!a) {
        scene_destroy(s);
        return NULL;
    }
    return case_keep_scene(c, s, a) ? a : NULL;
}

static bool case_add_ray(robust_case *c, ray r)
{
    if (!grow((void **)&c->rays, &c->ray_capacity, c->ray_count + 1, sizeof *c->rays))
        return false;
    c->rays[c->ray_count++] = r;
    return true;
}

/* The rays added since `first` become one batch against a, the accel of the
 * case's latest scene. */
static bool case_add_batch(robust_case *c, accel *a, size_t first, robust_query q)
{
    if (c->ray_count == first)
        return true;
    if (!grow((void **)&c->batches, &c->batch_capacity, c->batch_count + 1, sizeof *c->batches))
        return false;
    c->batches[c->batch_count++] = (robust_batch){a, c->scene_count - 1, first, c->ray_count - first, q};
    return true;
}

static bool case_alloc_results(robust_case *c)
{
    size_t n = c->ray_count ? c->ray_count : 1;
    c->hits = malloc(n * sizeof *c->hits);
    c->occluded = malloc(n);
    return c->hits && c->occluded;
}

static void case_free(robust_case *c)
{
    for (size_t i = 0; i < c->scene_count; i++) {
        accel_destroy(c->scenes[i].accel);
        scene_destroy(c->scenes[i].scene);
    }
    free(c->scenes);
    free(c->batches);
    free(c->rays);
    free(c->hits);
    free(c->occluded);
    memset(c, 0, sizeof *c);
}

/* ---- tracing: packets of 64 claimed from one counter by every thread ---- */

typedef struct robust_item {
    uint32_t batch;
    size_t first; /* ray index */
    uint32_t count;
} robust_item;

typedef struct robust_work {
    robust_case *c;
    const robust_item *items;
    size_t item_count;
    size_t passes;      /* claims run over item_count * passes: the case traced `passes` times */
    atomic_size_t next;
    atomic_bool failed;
} robust_work;

/* Trace one packet; its results are stored when `store` (the first pass over
 * the items: one thread per item, so no two threads write one result). */
static void trace_item(robust_case *c, const robust_item *it, ray_packet *p, bool store)
{
    const robust_batch *b = &c->batches[it->batch];
    packet_reset(p, it->count, 0);
    for (uint32_t i = 0; i < it->count; i++)
        packet_set_ray(p, i, &c->rays[it->first + i]);
    packet_detect_facts(p);
    if (b->query == QUERY_ANY) {
        uint64_t mask = accel_occluded_packet(b->accel, packet_whole(p));
        for (uint32_t i = 0; i < it->count && store; i++)
            c->occluded[it->first + i] = (unsigned char)(mask >> i & 1u);
        return;
    }
    accel_intersect_packet(b->accel, packet_whole(p));
    for (uint32_t i = 0; i < it->count && store; i++)
        c->hits[it->first + i] = packet_get_hit(p, i);
}

static void *trace_worker(void *arg)
{
    robust_work *w = arg;
    ray_packet *p = aligned_alloc(64, sizeof *p);
    if (!p) {
        atomic_store(&w->failed, true);
        return NULL;
    }
    for (;;) {
        size_t k = atomic_fetch_add_explicit(&w->next, 1, memory_order_relaxed);
        if (k >= w->item_count * w->passes)
            break;
        trace_item(w->c, &w->items[k % w->item_count], p, k < w->item_count);
    }
    free(p);
    return NULL;
}

/* Trace the case `passes` times on `threads` threads (the caller's
 * included); its wall time in seconds (and this process's CPU seconds in
 * *cpu_s), or -1 without memory. */
static double trace_passes(robust_case *c, const robust_item *items, size_t item_count, size_t passes, int threads,
                           double *cpu_s)
{
    robust_work w = {.c = c, .items = items, .item_count = item_count, .passes = passes};
    atomic_init(&w.next, 0);
    atomic_init(&w.failed, false);
    pthread_t ids[ROBUST_MAX_THREADS];
    int started = 0;
    double t0 = cli_now_s(), cpu0 = cli_own_cpu_s();
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&ids[started], NULL, trace_worker, &w) != 0)
            break; /* the threads that started trace every packet */
        started++;
    }
    trace_worker(&w);
    for (int i = 0; i < started; i++)
        pthread_join(ids[i], NULL);
    double seconds = cli_now_s() - t0;
    *cpu_s = cli_own_cpu_s() - cpu0;
    return atomic_load(&w.failed) ? -1.0 : seconds;
}

/* Trace every ray of c once untimed (the results), then `repeat` timed runs,
 * each tracing the case as many times as takes ROBUST_MIN_RUN_S by the first
 * pass, on `threads` threads. The median speed in Mrays/s goes to speed[1],
 * the slowest and fastest run's to speed[0] and speed[2], the median of
 * millions of rays per CPU second of this process (all threads) to speed[4]
 * (slowest and fastest run: speed[3], speed[5]): on a busy machine that one
 * does not count the time others took the CPU. False without memory. */
static bool trace_case(robust_case *c, int threads, int repeat, double speed[6])
{
    size_t items_n = 0;
    for (size_t b = 0; b < c->batch_count; b++)
        items_n += (c->batches[b].count + PACKET_MAX_RAYS - 1) / PACKET_MAX_RAYS;
    robust_item *items = malloc((items_n ? items_n : 1) * sizeof *items);
    double *speeds = malloc(2 * (size_t)repeat * sizeof *speeds), *cpu_speeds = speeds + repeat;
    if (!items || !speeds) {
        free(items);
        free(speeds);
        return false;
    }
    size_t k = 0;
    for (size_t b = 0; b < c->batch_count; b++)
        for (size_t off = 0; off < c->batches[b].count; off += PACKET_MAX_RAYS) {
            size_t left = c->batches[b].count - off;
            items[k++] = (robust_item){(uint32_t)b, c->batches[b].first + off,
                                       left < PACKET_MAX_RAYS ? (uint32_t)left : PACKET_MAX_RAYS};
        }
    double cpu_s;
    double first_s = trace_passes(c, items, items_n, 1, threads, &cpu_s);
    bool ok = first_s >= 0.0;
    size_t passes = 1;
    if (ok && first_s < ROBUST_MIN_RUN_S)
        passes = first_s > ROBUST_MIN_RUN_S / ROBUST_MAX_PASSES ? (size_t)ceil(ROBUST_MIN_RUN_S / first_s)
                                                                 : ROBUST_MAX_PASSES;
    for (int r = 0; r < repeat && ok; r++) {
        double seconds = trace_passes(c, items, items_n, passes, threads, &cpu_s);
        ok = seconds >= 0.0;
        speeds[r] = seconds > 0.0 ? (double)c->ray_count * (double)passes / seconds * 1e-6 : 0.0;
        cpu_speeds[r] = cpu_s > 0.0 ? (double)c->ray_count * (double)passes / cpu_s * 1e-6 : 0.0;
    }
    for (int which = 0; which < 2; which++) { /* wall, then CPU */
        const double *v = which ? cpu_speeds : speeds;
        double *out = speed + 3 * which;
        out[0] = out[2] = v[0];
        for (int r = 1; r < repeat; r++) {
            out[0] = v[r] < out[0] ? v[r] : out[0];
            out[2] = v[r] > out[2] ? v[r] : out[2];
        }
    }
    speed[1] = cli_median(speeds, (size_t)repeat);
    speed[4] = cli_median(cpu_speeds, (size_t)repeat);
    free(items);
    free(speeds);
    return ok;
}

/* ---- the cases ---- */

/* closed_sphere: a closed 64 x 40 jittered UV sphere (test a) centred at
 * (1e5, 1e5, 1e5), rays from its centre and from a point near it at every
 * vertex and 22 points on every edge. Every ray must hit: a miss is a leak. */
static bool make_closed_sphere(robust_case *c, bool small)
{
    const int slices = small ? 16 : 64, stacks = small ? 10 : 40, points_per_edge = small ? 4 : 22;
    const double offset = 1e5;
    rng g = {20261122};
    dvec centre = dv(offset, offset, offset);
    accel *a = case_add_mesh_scene(c, jittered_sphere(slices, stacks, 0.05, centre, &g));
    if (!a)
        return false;
    const mesh *m = c->scenes[c->scene_count - 1].scene->meshes[0]->mesh;
    vec3 *targets;
    size_t edges;
    size_t n = closed_mesh_targets(m, points_per_edge, &targets, &edges);
    if (n == 0)
        return false;
    vec3 origins[2] = {dv_round(centre), dv_round(dv_add(centre, dv(0.0731, -0.0412, 0.0253)))};
    bool ok = true;
    for (int o = 0; o < 2 && ok; o++)
        for (size_t i = 0; i < n && ok; i++)
            ok = case_add_ray(c, (ray){origins[o], v3_sub(targets[i], origins[o]), 0.f, FLT_MAX});
    free(targets);
    return ok && case_add_batch(c, a, 0, QUERY_CLOSEST);
}

static robust_counts check_closed_sphere(const robust_case *c)
{
    robust_counts k = {0, 0, c->ray_count};
    for (size_t i = 0; i < c->ray_count; i++)
        k.leaks += c->hits[i].prim_id == RAY_INVALID_ID;
    return k;
}

/* slivers: triangles of aspect ratio 1e6 at 17 scales (longest edge 1e-8 ..
 * 1e8), needles and caps in random orientations, each alone in a scene (test
 * b); rays aimed inside them (every barycentric >= 0.2). The reference in
 * double confirms each hits; a miss is a wrong hit. */
static bool make_slivers(robust_case *c, bool small)
{
    const int orientations = small ? 4 : 40, rays_per_triangle = small ? 30 : 150;
    rng g = {0x51713};
    for (int e = -8; e <= 8; e++) {
        double len = pow(10.0, e);
        for (int o = 0; o < orientations; o++)
            for (int shape = 0; shape < 2; shape++) {
                vec3 v[3];
                random_sliver(&g, len, shape == 0, v);
                mesh *m = mesh_create();
                if (m && !(mesh_add_vertex(m, v[0].x, v[0].y, v[0].z) && mesh_add_vertex(m, v[1].x, v[1].y, v[1].z) &&
                           mesh_add_vertex(m, v[2].x, v[2].y, v[2].z) && mesh_add_triangle(m, 0, 1, 2))) {
                    mesh_destroy(m);
                    m = NULL;
                }
                accel *a = case_add_mesh_scene(c, m);
                if (!a)
                    return false;
                size_t first = c->ray_count;
                for (int k = 0; k < rays_per_triangle; k++) {
                    double b1, b2;
                    if (!case_add_ray(c, sliver_ray(&g, v, len, &b1, &b2)))
                        return false;
                }
                if (!case_add_batch(c, a, first, QUERY_CLOSEST))
                    return false;
            }
    }
    return true;
}

static robust_counts check_slivers(const robust_case *c)
{
    robust_counts k = {0, 0, 0};
    for (size_t b = 0; b < c->batch_count; b++) {
        const mesh *m = c->scenes[c->batches[b].scene].scene->meshes[0]->mesh;
        const float *p = m->positions;
        vec3 v0 = v3(p[0], p[1], p[2]), v1 = v3(p[3], p[4], p[5]), v2 = v3(p[6], p[7], p[8]);
        for (size_t i = c->batches[b].first; i < c->batches[b].first + c->batches[b].count; i++) {
            ref_triangle_hit ref = reference_triangle(&c->rays[i], v0, v1, v2);
            if (!reference_hits(&ref, c->rays[i].t_near, c->rays[i].t_far))
                continue; /* not a hard case after rounding: not compared */
            k.checked++;
            k.wrong_hits += c->hits[i].prim_id != 0 || c->hits[i].geom_id != 0;
        }
    }
    return k;
}

/* lit_plane: a plane 200 across at 1 .. 1e6 from the origin, one big triangle
 * or an axis-aligned grid, lit at 1 .. 30 degrees (test g); primary rays hit
 * it (set-up, not timed), and each hit shoots render.c's shadow ray
 * (ray_offset_origin of the hit's surface point). A plane cannot shadow
 * itself: an occluded shadow ray is a wrong hit (a false shadow). */
static bool make_lit_plane(robust_case *c, bool small, uint64_t *primary_misses)
{
    const double offsets[] = {1, 10, 100, 1e3, 1e4, 1e5, 1e6};
    const double tilts_deg[] = {1, 2, 3, 5, 10, 20, 30};
    const double half = 100.0;
    const int samples = small ? 100 : 1500;
    rng g = {0x5AD0};
    *primary_misses = 0;
    for (size_t oi = 0; oi < sizeof offsets / sizeof offsets[0]; oi++)
        for (size_t ti = 0; ti < sizeof tilts_deg / sizeof tilts_deg[0]; ti++)
            for (int form = 0; form < 2; form++) {
                dvec shift, e0, e1, n;
                accel *a = case_add_mesh_scene(c, lit_plane_mesh(&g, offsets[oi], form, half, &shift, &e0, &e1, &n));
                if (!a)
                    return false;
                const mesh *m = c->scenes[c->scene_count - 1].scene->meshes[0]->mesh;
                vec3 to_light = lit_plane_light(&g, n, tilts_deg[ti]);
                size_t first = c->ray_count;
                for (int k = 0; k < samples; k++) {
                    ray primary = lit_plane_primary(&g, shift, e0, e1, n, half);
                    hit h;
                    if (!accel_intersect(a, &primary, &h)) {
                        (*primary_misses)++;
                        continue;
                    }
                    vec3 normal;
                    surface_point point = surface_at_hit(m, &h, primary.dir, &normal);
                    if (!(v3_dot(normal, to_light) > 0.f))
                        continue; /* unlit: render.c shoots no shadow ray */
                    if (!case_add_ray(c, (ray){ray_offset_origin(point, normal), to_light, 0.f, FLT_MAX}))
                        return false;
                }
                if (!case_add_batch(c, a, first, QUERY_ANY))
                    return false;
            }
    return true;
}

static robust_counts check_lit_plane(const robust_case *c)
{
    robust_counts k = {0, 0, c->ray_count};
    for (size_t i = 0; i < c->ray_count; i++)
        k.wrong_hits += c->occluded[i];
    return k;
}

/* primary: the built-in default scene's primary rays (its camera), W x H in
 * 8 x 8 tiles, each tile one packet as the renderer makes them. Nothing here
 * is hard: it shows what the robust rules cost where they are not needed. */
static bool make_primary(robust_case *c, bool small, int threads)
{
    const int width = small ? 160 : 1280, height = small ? 96 : 720; /* multiples of 8 */
    c->check_stride = small ? ROBUST_PRIMARY_STRIDE_SMALL : ROBUST_PRIMARY_STRIDE;
    cli_scene cs;
    if (!cli_scene_prepare(NULL, threads, &cs)) {
        cli_scene_finish(&cs);
        return false;
    }
    camera_desc desc;
    if (!cli_scene_camera(&cs, NULL, width, height, &desc)) {
        cli_scene_finish(&cs);
        return false;
    }
    /* the case owns the scene and accel from here */
    if (!case_keep_scene(c, cs.scene, cs.accel))
        return false;
    bool ok = true;
    camera_basis cam = camera_basis_make(&desc, width, height);
    ray_packet *p = aligned_alloc(64, sizeof *p);
    if (!p)
        return false;
    for (int y = 0; y < height && ok; y += 8)
        for (int x = 0; x < width && ok; x += 8) {
            packet_primary(p, &cam, x, y, 8, 8);
            for (uint32_t i = 0; i < p->count && ok; i++)
                ok = case_add_ray(c, packet_get_ray(p, i));
        }
    free(p);
    return ok && case_add_batch(c, c->scenes[0].accel, 0, QUERY_CLOSEST);
}

/* The nearest crossing in double of ray r with any primitive of scene s: its
 * geometry, primitive, t and how far inside it is (smallest barycentric, or
 * (radius - line distance) / radius); *found false when none. The crossing
 * with primitive (want_geom, want_prim) goes to *want_t, *want_margin (margin
 * -inf when it has none). */
typedef struct ref_nearest {
    bool found;
    uint32_t geom, prim;
    double t, margin;
    double want_t, want_margin;
} ref_nearest;

static void ref_consider(ref_nearest *out, uint32_t geom, uint32_t prim, double t, double margin, uint32_t want_geom,
                         uint32_t want_prim)
{
    if (geom == want_geom && prim == want_prim) {
        out->want_t = t;
        out->want_margin = margin;
    }
    if (margin >= 0.0 && (!out->found || t < out->t)) {
        out->found = true;
        out->geom = geom, out->prim = prim, out->t = t, out->margin = margin;
    }
}

static ref_nearest reference_nearest(const scene *s, const ray *r, uint32_t want_geom, uint32_t want_prim)
{
    ref_nearest out = {.found = false, .want_t = INFINITY, .want_margin = -INFINITY};
    for (uint32_t gi = 0; gi < s->mesh_count; gi++) {
        const mesh *m = s->meshes[gi]->mesh;
        for (uint32_t t = 0; t < m->triangle_count; t++) {
            const uint32_t *idx = m->indices + 3 * (size_t)t;
            const float *a = m->positions + 3 * (size_t)idx[0], *b = m->positions + 3 * (size_t)idx[1],
                        *cc = m->positions + 3 * (size_t)idx[2];
            ref_triangle_hit h = reference_triangle(r, v3(a[0], a[1], a[2]), v3(b[0], b[1], b[2]), v3(cc[0], cc[1], cc[2]));
            if (!h.crosses || !(h.t > r->t_near) || !(h.t <= r->t_far))
                continue;
            ref_consider(&out, gi, t, h.t, fmin(h.b[0], fmin(h.b[1], h.b[2])), want_geom, want_prim);
        }
    }
    const sphere_set *sp = &s->spheres;
    dvec o = dv_of(r->org), d = dv_of(r->dir);
    for (uint32_t i = 0; i < sp->count; i++) {
        dvec f = dv_sub(o, dv(sp->center_x[i], sp->center_y[i], sp->center_z[i]));
        double radius = sp->radius[i];
        double along = -dv_dot(f, d) / dv_dot(d, d); /* t of the point nearest the centre */
        dvec l = dv_add(f, dv_scale(d, along));
        double dist = dv_len(l);
        double margin = (radius - dist) / radius;
        double half_chord = sqrt(fmax(radius * radius - dist * dist, 0.0)) / dv_len(d);
        double t = along - half_chord > r->t_near ? along - half_chord : along + half_chord;
        if (!(t > r->t_near) || !(t <= r->t_far))
            continue;
        ref_consider(&out, s->mesh_count, i, t, margin, want_geom, want_prim);
    }
    return out;
}

static robust_counts check_primary(const robust_case *c)
{
    robust_counts k = {0, 0, 0};
    const scene *s = c->scenes[0].scene;
    for (size_t i = 0; i < c->ray_count; i += c->check_stride) {
        const hit *h = &c->hits[i];
        ref_nearest ref = reference_nearest(s, &c->rays[i], h->geom_id, h->prim_id);
        k.checked++;
        bool ok;
        if (h->prim_id == RAY_INVALID_ID) /* a miss: right, or the reference hit is at an edge */
            ok = !ref.found || ref.margin <= ROBUST_PRIMARY_BAND;
        else if (ref.found && h->geom_id == ref.geom && h->prim_id == ref.prim)
            ok = true;
        else /* another primitive: it is (nearly) crossed, and a near tie or the right one is at an edge */
            ok = ref.want_margin >= -ROBUST_PRIMARY_BAND &&
                 (!ref.found || ref.margin <= ROBUST_PRIMARY_BAND ||
                  fabs(ref.want_t - ref.t) <= ROBUST_PRIMARY_BAND * ref.t);
        k.wrong_hits += !ok;
    }
    return k;
}

/* ---- the command ---- */

static const char *const case_names[] = {"primary", "closed_sphere", "slivers", "lit_plane"};
#define CASE_COUNT (sizeof case_names / sizeof case_names[0])

static void robust_usage(FILE *f)
{
    fputs("usage: tessera robust [--case NAME]... [--threads N] [--repeat N] [--small]\n"
          "Trace the hard cases of numerical robustness (tools/robust/hard_cases.h, the generators of\n"
          "tests/test_robust.c) and print per case one line:\n"
          "  case=NAME rays=N wrong_hits=W leaks=L per_million=X mrays_s=M checked=C build=B isa=I threads=T\n"
          "  mrays_s_min=A mrays_s_max=B mrays_cpu_s=P mrays_cpu_s_min=Q mrays_cpu_s_max=R (on the same line:\n"
          "  the slowest and fastest run; millions of rays per CPU second of this process, all threads:\n"
          "  median, slowest, fastest run)\n"
          "  --case NAME   one of: primary (the built-in scene's primary rays: nothing hard), closed_sphere\n"
          "                (rays from inside a closed jittered sphere at 1e5 through its vertices and edges:\n"
          "                a miss is a leak), slivers (triangles of aspect 1e6 at scales 1e-8..1e8: a miss is\n"
          "                a wrong hit), lit_plane (shadow rays from a lit plane at 1..1e6 from the origin:\n"
          "                an occluded one is a false shadow, a wrong hit); repeatable; default: all\n"
          "  --threads N   tracing threads (default 1)\n"
          "  --repeat N    timed runs over the same rays, the median speed is printed (3..1000, default 3)\n"
          "  --small       fewer rays per case (a quick check)\n"
          "wrong_hits: disagreements with the right answer (primary, 1280x720 or 160x96 with --small: with a\n"
          "brute-force reference in double on every 64th ray (16th), differences within 1e-5 of an edge,\n"
          "silhouette or tie not counted);\n"
          "per_million = (W + L) * 1e6 / C; mrays_s: rays / tracing wall time (set-up and checks not timed; a\n"
          "timed run traces the case as many times over as takes >= 0.25 s).\n"
          "build: robust, or fast for build-unrobust/tessera (make unrobust: engine/accel/intersect.h).\n",
          f);
}

static bool known_case(const char *name)
{
    for (size_t i = 0; i < CASE_COUNT; i++)
        if (!strcmp(name, case_names[i]))
            return true;
    return false;
}

static bool parse_options(int argc, char **argv, robust_options *o, int *exit_code)
{
    *exit_code = 2;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            robust_usage(stdout);
            *exit_code = 0;
            return false;
        } else if (!strcmp(a, "--case")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return false;
            if (!known_case(val)) {
                cli_error("--case '%s': unknown case (expected one of: primary, closed_sphere, slivers, lit_plane)",
                          val);
                return false;
            }
            if (o->case_count == (int)(sizeof o->cases / sizeof o->cases[0])) {
                cli_error("--case given too many times (at most %zu)", sizeof o->cases / sizeof o->cases[0]);
                return false;
            }
            o->cases[o->case_count++] = val;
        } else if (!strcmp(a, "--threads")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, ROBUST_MAX_THREADS, &o->threads))
                return false;
        } else if (!strcmp(a, "--repeat")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 3, ROBUST_MAX_REPEAT, &o->repeat))
                return false;
        } else if (!strcmp(a, "--small")) {
            o->small = true;
        } else {
            cli_error("unknown option '%s' (see 'tessera robust --help')", a);
            return false;
        }
    }
    if (o->case_count == 0)
        for (size_t i = 0; i < CASE_COUNT; i++)
            o->cases[o->case_count++] = case_names[i];
    return true;
}

/* Make, trace and check one case; prints its line. False on failure (said). */
static bool run_case(const char *name, const robust_options *o)
{
    robust_case c;
    memset(&c, 0, sizeof c);
    uint64_t primary_misses = 0;
    bool made = !strcmp(name, "primary")         ? make_primary(&c, o->small, o->threads)
                : !strcmp(name, "closed_sphere") ? make_closed_sphere(&c, o->small)
                : !strcmp(name, "slivers")       ? make_slivers(&c, o->small)
                                                 : make_lit_plane(&c, o->small, &primary_misses);
    double speed[6] = {0.0}; /* Mrays/s: slowest, median, fastest run; the same per CPU second */
    if (!made || !case_alloc_results(&c) || !trace_case(&c, o->threads, o->repeat, speed)) {
        cli_error("robust: case %s: could not make or trace it (out of memory, or the scene failed to load)", name);
        case_free(&c);
        return false;
    }
    robust_counts k = !strcmp(name, "primary")         ? check_primary(&c)
                      : !strcmp(name, "closed_sphere") ? check_closed_sphere(&c)
                      : !strcmp(name, "slivers")       ? check_slivers(&c)
                                                       : check_lit_plane(&c);
    if (primary_misses)
        fprintf(stderr, "tessera: robust: lit_plane: %llu primary rays aimed inside the plane missed it (no shadow ray)\n",
                (unsigned long long)primary_misses);
    double per_million = k.checked ? (double)(k.wrong_hits + k.leaks) * 1e6 / (double)k.checked : 0.0;
    printf("case=%s rays=%zu wrong_hits=%llu leaks=%llu per_million=%.2f mrays_s=%.3f checked=%llu build=%s isa=%s "
           "threads=%d mrays_s_min=%.3f mrays_s_max=%.3f mrays_cpu_s=%.3f mrays_cpu_s_min=%.3f mrays_cpu_s_max=%.3f\n",
           name, c.ray_count, (unsigned long long)k.wrong_hits, (unsigned long long)k.leaks, per_million, speed[1],
           (unsigned long long)k.checked, ROBUST_BUILD, accel_isa_name(c.scenes[0].accel), o->threads, speed[0],
           speed[2], speed[4], speed[3], speed[5]);
    fflush(stdout);
    case_free(&c);
    return true;
}

int cli_robust(int argc, char **argv)
{
    robust_options o = {.threads = 1, .repeat = 3};
    int code;
    if (!parse_options(argc, argv, &o, &code))
        return code;
    for (int i = 0; i < o.case_count; i++)
        if (!run_case(o.cases[i], &o))
            return 1;
    return 0;
}
