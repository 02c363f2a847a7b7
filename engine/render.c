#include "render.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"
#include "log.h"
#include "frame_state.h"
#include "scene.h"
#include "surface.h"

/* Eyelight without shadow rays looks at normals only. */
static bool needs_position(const render_view *v)
{
    return v->shading != RENDER_SHADE_EYELIGHT || (v->shadows && v->scene->light_count > 0);
}

/* What one light does at one surface point, before its shadow ray is traced. */
typedef struct light_sample {
    vec3 to_light;        /* unit, towards the light */
    float n_dot_l;        /* > 0 when the light can reach the point */
    float falloff;        /* 1 for a directional light, 1/d^2 for a point light */
    float shadow_t_far;   /* shadow ray length (unit direction) */
    bool needs_shadow_ray;
} light_sample;

/* False when the light cannot reach the point at all (behind the surface, or
 * a point light sitting on it). */
static bool sample_light(const render_view *v, const surface *sf, const light *l, light_sample *ls)
{
    ls->falloff = 1.f;
    if (l->kind == LIGHT_DIRECTIONAL) {
        ls->to_light = l->direction;
        ls->shadow_t_far = FLT_MAX;
    } else {
        vec3 d = v3_sub(l->position, sf->position);
        float dist2 = v3_dot(d, d);
        if (!(dist2 > 0.f))
            return false;
        ls->falloff = 1.f / dist2;
        ls->to_light = v3_scale(d, 1.f / sqrtf(dist2));
        ls->shadow_t_far = sqrtf(dist2);
    }
    ls->n_dot_l = v3_dot(sf->shading_n, ls->to_light);
    /* a light below the geometric surface cannot reach it, whatever the shading normal says */
    if (ls->n_dot_l <= 0.f || v3_dot(sf->geometric_n, ls->to_light) <= 0.f)
        return false;
    ls->needs_shadow_ray = v->shadows && l->casts_shadows;
    return true;
}

static ray shadow_ray(const surface *sf, const light_sample *ls)
{
    return (ray){ray_offset_origin((surface_point){sf->position, sf->position_error}, sf->geometric_n), ls->to_light,
                 0.f, ls->shadow_t_far};
}

/* Reflected light from an unshadowed light sample. */
static vec3 light_contribution(const surface *sf, const light *l, const light_sample *ls, vec3 to_viewer)
{
    vec3 reflected = v3_scale(sf->kd, ls->n_dot_l);
    if (sf->mat->model == MATERIAL_PHONG) {
        vec3 mirror = v3_sub(v3_scale(sf->shading_n, 2.f * ls->n_dot_l), ls->to_light);
        float r_dot_v = v3_dot(mirror, to_viewer);
        if (r_dot_v > 0.f)
            reflected = v3_add(reflected, v3_scale(sf->mat->specular, powf(r_dot_v, sf->mat->shininess)));
    }
    return v3_mul(reflected, v3_scale(l->color, l->intensity * ls->falloff));
}

/* Ambient term of the Phong model. */
static vec3 ambient_term(const scene *s, const surface *sf)
{
    return v3_mul(v3_scale(s->ambient, sf->mat->ambient), sf->kd);
}

/* Eyelight (the peer harness's shade): |cos| between the geometric normal and the ray. */
static float eyelight_grey(const surface *sf, const ray *r)
{
    return fabsf(v3_dot(sf->geometric_n, v3_normalize(r->dir)));
}

/* The eyelight shadow ray towards the first light (point lights: t_far 1 with
 * the unnormalised direction to the light). */
static ray eyelight_shadow_ray(const scene *s, const surface *sf)
{
    const light *l = &s->lights[0];
    vec3 to_light = l->kind == LIGHT_DIRECTIONAL ? l->direction : v3_sub(l->position, sf->position);
    float t_far = l->kind == LIGHT_DIRECTIONAL ? FLT_MAX : 1.f;
    return (ray){ray_offset_origin((surface_point){sf->position, sf->position_error}, sf->geometric_n), to_light, 0.f,
                 t_far};
}

/* Eyelight darkens to this fraction in shadow, as the peer harness's lit image. */
#define EYELIGHT_SHADOW_FACTOR 0.2f

vec3 render_shade(const render_view *v, const ray *r, uint64_t *shadow_rays)
{
    const scene *s = v->scene;
    hit h;
    if (!accel_intersect(v->accel, r, &h))
        return v->shading == RENDER_SHADE_EYELIGHT ? v3(0.f, 0.f, 0.f) : s->background;
    surface sf = surface_describe(v, r, &h, needs_position(v));
    if (v->shading == RENDER_SHADE_EYELIGHT) {
        float grey = eyelight_grey(&sf, r);
        if (v->shadows && s->light_count > 0) {
            ray shadow = eyelight_shadow_ray(s, &sf);
            ++*shadow_rays;
            if (accel_occluded(v->accel, &shadow))
                grey *= EYELIGHT_SHADOW_FACTOR;
        }
        return v3(grey, grey, grey);
    }
    vec3 to_viewer = v3_normalize(v3_scale(r->dir, -1.f));
    vec3 colour = ambient_term(s, &sf);
    for (uint32_t i = 0; i < s->light_count; i++) {
        light_sample ls;
        if (!sample_light(v, &sf, &s->lights[i], &ls))
            continue;
        if (ls.needs_shadow_ray) {
            ray shadow = shadow_ray(&sf, &ls);
            ++*shadow_rays;
            if (accel_occluded(v->accel, &shadow))
                continue;
        }
        colour = v3_add(colour, light_contribution(&sf, &s->lights[i], &ls, to_viewer));
    }
    return colour;
}

/* Per-ray shading state of one packet beyond what the packet itself holds
 * (hit positions and normals live in the packet's derived arrays). */
typedef struct packet_shading {
    vec3 kd[PACKET_MAX_RAYS];             /* diffuse reflectance at the hit */
    const material *mat[PACKET_MAX_RAYS]; /* material at the hit */
    vec3 position_error[PACKET_MAX_RAYS]; /* rounding allowance of pos_* (ray.h surface_point) */
    vec3 colour[PACKET_MAX_RAYS];
    vec3 to_viewer[PACKET_MAX_RAYS];
    light_sample ls[PACKET_MAX_RAYS];
    uint64_t hits; /* rays that hit something */
} packet_shading;

/* The packet's derived hit values for the rays in `hits`: geometric and
 * shading normals always, positions when `need_position`; each computed at
 * most once per traced packet (the PACKET_HAVE_ flags, which tracing clears). */
static void packet_derive_hit_surfaces(const render_view *v, ray_packet *p, packet_shading *ps, bool need_position)
{
    const uint32_t have = PACKET_HAVE_GEOMETRIC_NORMAL | PACKET_HAVE_SHADING_NORMAL |
                          (need_position ? PACKET_HAVE_HIT_POSITION : 0u);
    if ((p->flags & have) == have)
        return;
    const scene *s = v->scene;
    /* the hit triangles of a large mesh are cache misses: ask for all of them
     * (indices, then vertices) before reading any, so the waits overlap */
    for (uint64_t m = ps->hits; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        const scene_geometry *g = scene_instance_geometry(s, p->geom_id[i]);
        if (g->ops == &geometry_triangles_ops)
            __builtin_prefetch(((const scene_mesh *)g->data)->mesh->indices + 3 * (size_t)p->prim_id[i]);
    }
    for (uint64_t m = ps->hits; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        const scene_geometry *g = scene_instance_geometry(s, p->geom_id[i]);
        if (g->ops != &geometry_triangles_ops)
            continue;
        const mesh *mh = ((const scene_mesh *)g->data)->mesh;
        const uint32_t *idx = mh->indices + 3 * (size_t)p->prim_id[i];
        for (int k = 0; k < 3; k++)
            __builtin_prefetch(mh->positions + 3 * (size_t)idx[k]);
    }
    for (uint64_t m = ps->hits; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        ray r = packet_get_ray(p, i);
        hit h = packet_get_hit(p, i);
        surface sf = surface_describe(v, &r, &h, need_position);
        p->ng_x[i] = sf.geometric_n.x, p->ng_y[i] = sf.geometric_n.y, p->ng_z[i] = sf.geometric_n.z;
        p->ns_x[i] = sf.shading_n.x, p->ns_y[i] = sf.shading_n.y, p->ns_z[i] = sf.shading_n.z;
        if (need_position) {
            p->pos_x[i] = sf.position.x, p->pos_y[i] = sf.position.y, p->pos_z[i] = sf.position.z;
            ps->position_error[i] = sf.position_error;
        }
        p->material_id[i] = (uint32_t)(sf.mat - s->materials);
        ps->mat[i] = sf.mat;
        ps->kd[i] = sf.kd;
    }
    p->flags |= have;
}

/* Ray i's surface, gathered from the packet's derived arrays. */
static surface lane_surface(const ray_packet *p, const packet_shading *ps, uint32_t i)
{
    surface sf;
    sf.position = v3(p->pos_x[i], p->pos_y[i], p->pos_z[i]);
    sf.position_error = ps->position_error[i];
    sf.geometric_n = v3(p->ng_x[i], p->ng_y[i], p->ng_z[i]);
    sf.shading_n = v3(p->ns_x[i], p->ns_y[i], p->ns_z[i]);
    sf.kd = ps->kd[i];
    sf.mat = ps->mat[i];
    return sf;
}

/* Shadow rays for the rays of `mask`, one packet; returns the occluded ones. */
static uint64_t trace_shadows(const render_view *v, ray_packet *shadows, uint32_t count, uint64_t mask,
                              uint32_t facts, const ray *rays, render_counts *counts)
{
    packet_reset(shadows, count, facts);
    shadows->active = mask;
    for (uint64_t m = mask; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        packet_set_ray(shadows, i, &rays[i]);
    }
    counts->shadow_rays += (uint64_t)__builtin_popcountll(mask);
    return accel_occluded_packet(v->accel, packet_whole(shadows));
}

/* Trace and shade the primary packet p (rays [0, p->count)): the same
 * results as render_shade on each ray, with every ray cast in packets. */
static void shade_packet(const render_view *v, ray_packet *p, ray_packet *shadows, packet_shading *ps,
                         render_counts *counts)
{
    const scene *s = v->scene;
    ray shadow_rays[PACKET_MAX_RAYS];
    accel_intersect_packet(v->accel, packet_whole(p));
    counts->primary_rays += p->count;
    ps->hits = 0;
    for (uint32_t i = 0; i < p->count; i++)
        if (p->hit_t[i] != INFINITY)
            ps->hits |= 1ull << i;
        else
            ps->colour[i] = v->shading == RENDER_SHADE_EYELIGHT ? v3(0.f, 0.f, 0.f) : s->background;
    if (!ps->hits)
        return;
    counts->primary_hits += (uint64_t)__builtin_popcountll(ps->hits);
    packet_derive_hit_surfaces(v, p, ps, needs_position(v));
    for (uint64_t m = ps->hits; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        ray r = packet_get_ray(p, i);
        surface sf = lane_surface(p, ps, i);
        if (v->shading == RENDER_SHADE_EYELIGHT) {
            float grey = eyelight_grey(&sf, &r);
            ps->colour[i] = v3(grey, grey, grey);
        } else {
            ps->to_viewer[i] = v3_normalize(v3_scale(r.dir, -1.f));
            ps->colour[i] = ambient_term(s, &sf);
        }
    }
    if (v->shading == RENDER_SHADE_EYELIGHT) {
        if (!v->shadows || s->light_count == 0)
            return;
        for (uint64_t m = ps->hits; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            surface sf = lane_surface(p, ps, i);
            shadow_rays[i] = eyelight_shadow_ray(s, &sf);
        }
        uint32_t facts = s->lights[0].kind == LIGHT_DIRECTIONAL ? PACKET_CONSTANT_SIGNS : 0;
        uint64_t dark = trace_shadows(v, shadows, p->count, ps->hits, facts, shadow_rays, counts);
        for (uint64_t m = dark; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            ps->colour[i] = v3_scale(ps->colour[i], EYELIGHT_SHADOW_FACTOR);
        }
        return;
    }
    for (uint32_t l = 0; l < s->light_count; l++) {
        const light *lt = &s->lights[l];
        uint64_t lit = 0, need_ray = 0;
        for (uint64_t m = ps->hits; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            surface sf = lane_surface(p, ps, i);
            if (!sample_light(v, &sf, lt, &ps->ls[i]))
                continue;
            lit |= 1ull << i;
            if (ps->ls[i].needs_shadow_ray) {
                need_ray |= 1ull << i;
                shadow_rays[i] = shadow_ray(&sf, &ps->ls[i]);
            }
        }
        if (need_ray) {
            uint32_t facts = lt->kind == LIGHT_DIRECTIONAL ? PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED : 0;
            lit &= ~trace_shadows(v, shadows, p->count, need_ray, facts, shadow_rays, counts);
        }
        for (uint64_t m = lit; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            surface sf = lane_surface(p, ps, i);
            ps->colour[i] = v3_add(ps->colour[i], light_contribution(&sf, lt, &ps->ls[i], ps->to_viewer[i]));
        }
    }
}

/* Primary rays per packet: 8 x 8 pixels, so a packet covers a compact patch. */
#define RENDER_PACKET_EDGE_PX 8

/* Per thread: two packets and the shading state, ~60 KB: too big for a
 * worker's stack. Used by one block at a time. */
static _Thread_local struct render_scratch {
    ray_packet primary, shadows;
    packet_shading ps;
} scratch;

/* Store the colours of a w x h block (row-major) at pixel (px, py) of the image. */
static void store_block(const camera_basis *cam, int px, int py, int w, int h, const vec3 *colour, float *rgb)
{
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            vec3 c = colour[j * w + i];
            float *out = rgb + 3 * ((size_t)(py + j) * (size_t)cam->width_px + (size_t)(px + i));
            out[0] = c.x;
            out[1] = c.y;
            out[2] = c.z;
        }
}

void render_tile(const render_view *v, int x0, int y0, int x1, int y1, float *rgb, render_counts *counts)
{
    const camera_basis *cam = &v->camera;
    for (int py = y0; py < y1; py += RENDER_PACKET_EDGE_PX)
        for (int px = x0; px < x1; px += RENDER_PACKET_EDGE_PX) {
            int w = x1 - px < RENDER_PACKET_EDGE_PX ? x1 - px : RENDER_PACKET_EDGE_PX;
            int h = y1 - py < RENDER_PACKET_EDGE_PX ? y1 - py : RENDER_PACKET_EDGE_PX;
            packet_primary(&scratch.primary, cam, px, py, w, h);
            shade_packet(v, &scratch.primary, &scratch.shadows, &scratch.ps, counts);
            store_block(cam, px, py, w, h, scratch.ps.colour, rgb);
        }
}

/* One w x h block at (x0, y0) (w, h <= 8) with a jittered sampler: one packet
 * per stratum (i, j) holding that stratum's sample of every pixel of the
 * block (neighbouring rays, so packets stay coherent), k^2 packets in all.
 * Colours are summed per pixel in stratum row-major order, then divided by
 * k^2: sampler.h's pixel value, independent of how the image is cut up. */
static void render_block_jittered(const render_view *v, const pixel_sampler *s, int x0, int y0, int w, int h,
                                  float *rgb, render_counts *counts)
{
    alignas(64) float sample_x[PACKET_MAX_RAYS], sample_y[PACKET_MAX_RAYS];
    vec3 sum[PACKET_MAX_RAYS];
    const int k = s->k, n = w * h;
    for (int r = 0; r < n; r++)
        sum[r] = v3(0.f, 0.f, 0.f);
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) {
            pixel_sampler_block_positions(s, x0, y0, w, h, i, j, sample_x, sample_y);
            packet_primary_at(&scratch.primary, &v->camera, sample_x, sample_y, (uint32_t)n);
            shade_packet(v, &scratch.primary, &scratch.shadows, &scratch.ps, counts);
            for (int r = 0; r < n; r++)
                sum[r] = v3_add(sum[r], scratch.ps.colour[r]);
        }
    const float samples = (float)(k * k);
    for (int r = 0; r < n; r++)
        sum[r] = v3(sum[r].x / samples, sum[r].y / samples, sum[r].z / samples);
    store_block(&v->camera, x0, y0, w, h, sum, rgb);
}

/* One w x h block with a stratum sampler: the packet render_block_jittered
 * traces for that stratum, its colours stored as they are (the governor's
 * accumulation adds them up in stratum order, as render_block_jittered does). */
static void render_block_stratum(const render_view *v, const pixel_sampler *s, int x0, int y0, int w, int h,
                                 float *rgb, render_counts *counts)
{
    alignas(64) float sample_x[PACKET_MAX_RAYS], sample_y[PACKET_MAX_RAYS];
    const int n = w * h;
    pixel_sampler_block_positions(s, x0, y0, w, h, 0, 0, sample_x, sample_y);
    packet_primary_at(&scratch.primary, &v->camera, sample_x, sample_y, (uint32_t)n);
    shade_packet(v, &scratch.primary, &scratch.shadows, &scratch.ps, counts);
    store_block(&v->camera, x0, y0, w, h, scratch.ps.colour, rgb);
}

void render_tile_sampled(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                         render_counts *counts)
{
    if (s->kind == PIXEL_SAMPLER_SINGLE) {
        render_tile(v, x0, y0, x1, y1, rgb, counts);
        return;
    }
    for (int py = y0; py < y1; py += RENDER_PACKET_EDGE_PX)
        for (int px = x0; px < x1; px += RENDER_PACKET_EDGE_PX) {
            int w = x1 - px < RENDER_PACKET_EDGE_PX ? x1 - px : RENDER_PACKET_EDGE_PX;
            int h = y1 - py < RENDER_PACKET_EDGE_PX ? y1 - py : RENDER_PACKET_EDGE_PX;
            if (s->kind == PIXEL_SAMPLER_STRATUM)
                render_block_stratum(v, s, px, py, w, h, rgb, counts);
            else
                render_block_jittered(v, s, px, py, w, h, rgb, counts);
        }
}

/* Shared by the threads of one render_image call. */
typedef struct tile_queue {
    const render_view *view;
    const pixel_sampler *sampler;
    float *rgb;
    int tiles_x, tile_count;
    atomic_int next_tile; /* next tile index to hand out; tiles >= tile_count mean done */
    atomic_uint_fast64_t primary_rays, primary_hits, shadow_rays; /* totals, added once per thread */
} tile_queue;

static void *render_worker(void *arg)
{
    tile_queue *q = arg;
    const camera_basis *cam = &q->view->camera;
    render_counts counts = {0, 0, 0}; /* this thread's, folded in once at the end */
    for (;;) {
        int tile = atomic_fetch_add_explicit(&q->next_tile, 1, memory_order_relaxed);
        if (tile >= q->tile_count) {
            atomic_fetch_add_explicit(&q->primary_rays, counts.primary_rays, memory_order_relaxed);
            atomic_fetch_add_explicit(&q->primary_hits, counts.primary_hits, memory_order_relaxed);
            atomic_fetch_add_explicit(&q->shadow_rays, counts.shadow_rays, memory_order_relaxed);
            return NULL;
        }
        int x0 = (tile % q->tiles_x) * RENDER_TILE_PX, y0 = (tile / q->tiles_x) * RENDER_TILE_PX;
        int x1 = x0 + RENDER_TILE_PX < cam->width_px ? x0 + RENDER_TILE_PX : cam->width_px;
        int y1 = y0 + RENDER_TILE_PX < cam->height_px ? y0 + RENDER_TILE_PX : cam->height_px;
        render_tile_sampled(q->view, q->sampler, x0, y0, x1, y1, q->rgb, &counts);
    }
}

/* Most threads render_image starts: more than any machine we target has cores. */
#define RENDER_MAX_THREADS 256

void render_image(const render_view *v, int threads, float *rgb, render_counts *counts)
{
    const pixel_sampler single = pixel_sampler_single();
    render_image_sampled(v, &single, threads, rgb, counts);
}

void render_image_sampled(const render_view *v, const pixel_sampler *s, int threads, float *rgb,
                          render_counts *counts)
{
    tile_queue q = {.view = v, .sampler = s, .rgb = rgb};
    q.tiles_x = (v->camera.width_px + RENDER_TILE_PX - 1) / RENDER_TILE_PX;
    q.tile_count = q.tiles_x * ((v->camera.height_px + RENDER_TILE_PX - 1) / RENDER_TILE_PX);
    atomic_init(&q.next_tile, 0);
    atomic_init(&q.primary_rays, 0);
    atomic_init(&q.primary_hits, 0);
    atomic_init(&q.shadow_rays, 0);
    if (threads < 1)
        threads = 1;
    if (threads > RENDER_MAX_THREADS)
        threads = RENDER_MAX_THREADS;
    pthread_t ids[RENDER_MAX_THREADS];
    int started = 0;
    /* the calling thread is worker 0; if the system refuses more threads the
     * frame is still finished by those that run (a kiosk stays up) */
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&ids[started], NULL, render_worker, &q) != 0) {
            log_warn("render: could start only %d of %d render threads", started + 1, threads);
            break;
        }
        started++;
    }
    render_worker(&q);
    for (int i = 0; i < started; i++)
        pthread_join(ids[i], NULL);
    if (counts) {
        counts->primary_rays = atomic_load(&q.primary_rays);
        counts->primary_hits = atomic_load(&q.primary_hits);
        counts->shadow_rays = atomic_load(&q.shadow_rays);
    }
}

render_settings render_settings_default(void)
{
    return (render_settings){
        .min_transmittance = RENDER_MIN_TRANSMITTANCE_DEFAULT,
        .max_layers = RENDER_MAX_LAYERS_DEFAULT,
        .transparent_shadows = true,
        .caps = true,
        .cap_style = RENDER_CAP_TINT,
        .ao_rays = 8,
        .ao_distance = 0.f,
        .ao_interleave = 4,
        .ao_filter_px = 5,
        .ao_in_raytracer = false,
    };
}

static const renderer renderers[] = {
    {"raytracer", RENDER_SHADE_PHONG, render_tile_sampled},
    {"eyelight", RENDER_SHADE_EYELIGHT, render_tile_sampled},
    {"ao", RENDER_SHADE_PHONG, render_ao_tile}, /* engine/render_ao.c; shading unused */
};

const renderer *renderer_by_name(const char *name)
{
    for (size_t i = 0; i < sizeof renderers / sizeof renderers[0]; i++)
        if (!strcmp(renderers[i].name, name))
            return &renderers[i];
    return NULL;
}
