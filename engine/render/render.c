#include "render.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/accel/intersect.h"
#include "engine/base/log.h"
#include "engine/scene/frame_state.h"
#include "engine/scene/scene.h"
#include "engine/accel/clip.h"
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

static vec3 render_shade_layers(const render_view *v, const ray *r, uint64_t *shadow_rays);

vec3 render_shade(const render_view *v, const ray *r, uint64_t *shadow_rays)
{
    const scene *s = v->scene;
    if (v->state && (frame_state_transparent(v->state) || clip_planes_on(frame_state_clip_planes(v->state))))
        return render_shade_layers(v, r, shadow_rays);
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

/* What a frame asks beyond opaque surfaces seen whole: transparency and
 * cutting planes (frame_state.h), with the settings that bound them. Made
 * once per tile or block from the view; the frame state does not change
 * while a frame renders, so every tile of a frame makes the same one. */
typedef struct view_extras {
    render_settings set; /* the view's settings, or the defaults */
    bool transparent;    /* some surface has opacity < 1 */
    clip_set clip;       /* the cutting planes that are on (count 0: none) */
} view_extras;

static void view_extras_make(const render_view *v, view_extras *x)
{
    x->set = v->settings ? *v->settings : render_settings_default();
    x->transparent = v->state && frame_state_transparent(v->state);
    x->clip.count = 0;
    if (v->state)
        clip_set_make(&x->clip, frame_state_clip_planes(v->state));
}

/* Whether rays walk their surfaces layer by layer (render_layers) rather
 * than stop at the first: transparency, or planes (caps and clipped intervals). */
static bool needs_layers(const view_extras *x) { return x->transparent || x->clip.count > 0; }

static float opacity_of(const render_view *v, uint32_t geom_id)
{
    return v->state ? frame_state_opacity(v->state, geom_id) : 1.f;
}

/* Light that reaches the origins of the shadow rays of `mask` (rays[i]):
 * transmit[i] = 1 unoccluded, 0 blocked, in between through transparent
 * surfaces (the product of 1 - opacity over every surface crossed, when the
 * frame is transparent and transparent_shadows is set; the walk stops as
 * render_layers does: below min_transmittance, or after max_layers surfaces,
 * as blocked). Rays are cut by the cutting planes first (a ray with nothing
 * left reaches the light). */
static void trace_shadows(const render_view *v, const view_extras *x, ray_packet *shadows, uint32_t count,
                          uint64_t mask, uint32_t facts, const ray *rays, render_counts *counts,
                          float transmit[PACKET_MAX_RAYS])
{
    ray cut_rays[PACKET_MAX_RAYS];
    const ray *cut = rays; /* without planes the rays as they are: no copy on the opaque path */
    uint64_t traced = mask;
    for (uint64_t m = mask; m; m &= m - 1)
        transmit[__builtin_ctzll(m)] = 1.f;
    if (x->clip.count > 0) {
        traced = 0;
        for (uint64_t m = mask; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            cut_rays[i] = rays[i];
            if (clip_ray(&x->clip, &cut_rays[i], NULL))
                traced |= 1ull << i;
        }
        cut = cut_rays;
    }
    if (!traced)
        return;
    if (!x->transparent || !x->set.transparent_shadows) { /* any surface blocks: one any-hit query */
        packet_reset(shadows, count, facts);
        shadows->active = traced;
        for (uint64_t m = traced; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            packet_set_ray(shadows, i, &cut[i]);
        }
        counts->shadow_rays += (uint64_t)__builtin_popcountll(traced);
        for (uint64_t m = accel_occluded_packet(v->accel, packet_whole(shadows)); m; m &= m - 1)
            transmit[__builtin_ctzll(m)] = 0.f;
        return;
    }
    hit last[PACKET_MAX_RAYS];
    uint64_t walking = traced;
    for (int layer = 0; walking && layer < x->set.max_layers; layer++) {
        packet_reset(shadows, count, facts);
        shadows->active = walking;
        for (uint64_t m = walking; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            packet_set_ray(shadows, i, &cut[i]);
            if (layer > 0)
                packet_set_after(shadows, i, &last[i]);
        }
        counts->shadow_rays += (uint64_t)__builtin_popcountll(walking);
        accel_intersect_packet(v->accel, packet_whole(shadows));
        for (uint64_t m = walking; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            if (shadows->hit_t[i] == INFINITY) {
                walking &= ~(1ull << i);
                continue;
            }
            last[i] = packet_get_hit(shadows, i);
            transmit[i] *= 1.f - opacity_of(v, last[i].geom_id);
            if (transmit[i] < x->set.min_transmittance) {
                transmit[i] = 0.f;
                walking &= ~(1ull << i);
            }
        }
    }
    for (uint64_t m = walking; m; m &= m - 1) /* more surfaces than max_layers: blocked */
        transmit[__builtin_ctzll(m)] = 0.f;
}

/* Colours of the hits of ps->hits in p, whose surfaces are derived (and
 * possibly replaced by caps): ambient and lights with shadows, or eyelight,
 * into ps->colour. */
static void shade_hits(const render_view *v, const view_extras *x, ray_packet *p, ray_packet *shadows,
                       packet_shading *ps, render_counts *counts)
{
    const scene *s = v->scene;
    ray shadow_rays[PACKET_MAX_RAYS];
    float transmit[PACKET_MAX_RAYS];
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
        trace_shadows(v, x, shadows, p->count, ps->hits, facts, shadow_rays, counts, transmit);
        for (uint64_t m = ps->hits; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            if (transmit[i] < 1.f) /* 0: the harness's factor; between: blended towards it */
                ps->colour[i] = v3_scale(ps->colour[i],
                                         EYELIGHT_SHADOW_FACTOR + (1.f - EYELIGHT_SHADOW_FACTOR) * transmit[i]);
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
            transmit[i] = 1.f;
            if (ps->ls[i].needs_shadow_ray) {
                need_ray |= 1ull << i;
                shadow_rays[i] = shadow_ray(&sf, &ps->ls[i]);
            }
        }
        if (need_ray) {
            uint32_t facts = lt->kind == LIGHT_DIRECTIONAL ? PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED : 0;
            trace_shadows(v, x, shadows, p->count, need_ray, facts, shadow_rays, counts, transmit);
        }
        for (uint64_t m = lit; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            if (transmit[i] == 0.f)
                continue;
            surface sf = lane_surface(p, ps, i);
            vec3 c = light_contribution(&sf, lt, &ps->ls[i], ps->to_viewer[i]);
            if (transmit[i] < 1.f)
                c = v3_scale(c, transmit[i]);
            ps->colour[i] = v3_add(ps->colour[i], c);
        }
    }
}

/* The first surfaces of the hits of ps->hits (derived, shaded; the lanes of
 * `capped` show a cap) into *first for the AO term (render_first_surfaces),
 * each with the weight alpha[i] it has in the blend (alpha NULL: opaque, 1). */
static void note_first_surfaces(const render_view *v, const ray_packet *p, const packet_shading *ps,
                                const float *alpha, uint64_t capped, render_first_surfaces *first)
{
    first->hits = ps->hits;
    for (uint64_t m = ps->hits; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        surface sf = lane_surface(p, ps, i);
        first->geom_id[i] = p->geom_id[i];
        first->t[i] = p->hit_t[i];
        if (capped >> i & 1u) { /* on the plane, short of the hit */
            vec3 dir = v3(p->dir_x[i], p->dir_y[i], p->dir_z[i]);
            first->t[i] = v3_dot(v3_sub(sf.position, v3(p->org_x[i], p->org_y[i], p->org_z[i])), dir) / v3_dot(dir, dir);
        }
        first->position[i] = sf.position;
        first->position_error[i] = sf.position_error;
        first->normal[i] = sf.geometric_n;
        first->ambient[i] = v->shading == RENDER_SHADE_EYELIGHT ? v3(0.f, 0.f, 0.f) : ambient_term(v->scene, &sf);
        if (alpha)
            first->ambient[i] = v3_scale(first->ambient[i], alpha[i]);
    }
}

/* Trace and shade the primary packet p (rays [0, p->count)) when every
 * surface is opaque and nothing is clipped: the same results as
 * render_shade on each ray, with every ray cast in packets. */
static void shade_packet(const render_view *v, const view_extras *x, ray_packet *p, ray_packet *shadows,
                         packet_shading *ps, render_first_surfaces *first, render_counts *counts)
{
    const scene *s = v->scene;
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
    shade_hits(v, x, p, shadows, ps, counts);
    if (first)
        note_first_surfaces(v, p, ps, NULL, 0, first);
}

/* Cap hatching: stripes this many pixels apart, half of them darkened by
 * RENDER_CAP_HATCH_DARK. */
#define RENDER_CAP_HATCH_PX 8.f
#define RENDER_CAP_HATCH_DARK 0.45f
/* Caps are drawn in their part's colour times this. */
#define RENDER_CAP_TINT_FACTOR 0.8f
/* Most crossings a parity count follows along one ray (a part's surface
 * crossed more often is taken as not containing the point). */
#define RENDER_PARITY_MAX_CROSSINGS 1024

/* Whether the point where ray r (already cut: its t_near is just below the
 * plane crossing) enters the kept region lies inside the closed part of its
 * first hit `first`: the crossings of that part's surface from there on,
 * counted one by one, are odd. */
static bool inside_by_parity(const render_view *v, const ray *r, const hit *first, render_counts *counts)
{
    ray whole = *r;
    whole.t_far = FLT_MAX; /* the part's surface beyond any other plane counts too */
    hit prev = *first, h;
    uint32_t crossings = 1;
    while (crossings < RENDER_PARITY_MAX_CROSSINGS &&
           accel_intersect_instance(v->accel, first->geom_id, &whole, &prev, &h)) {
        crossings++;
        prev = h;
    }
    counts->secondary_rays += crossings;
    return crossings < RENDER_PARITY_MAX_CROSSINGS && (crossings & 1u);
}

/* Most surfaces the search for a closed part walks past (open parts in
 * front of it), per ray. */
#define RENDER_CAP_SEARCH_MAX 64

/* The first surface of a closed part along ray r (cut by the planes) at or
 * after its first hit `first`: where a cap may be. Open parts are walked past:
 * if the plane point lies inside a closed part, everything met before that
 * part's surface lies inside it too and is covered by the cap (solids do not
 * overlap); if it does not, the parity says so. False when there is none. */
static bool first_closed_hit(const render_view *v, const ray *r, hit first, hit *out, render_counts *counts)
{
    const scene *s = v->scene;
    hit h = first;
    for (int step = 0; step < RENDER_CAP_SEARCH_MAX; step++) {
        if (scene_geometry_closed(s, s->instances[h.geom_id].geometry)) {
            *out = h;
            return true;
        }
        hit next;
        counts->secondary_rays++;
        if (!accel_intersect_after(v->accel, r, &h, &next))
            return false;
        h = next;
    }
    return false;
}

/* Turn lane i's derived surface into the cap of plane `plane` where ray r
 * crosses it: on the plane, facing the ray, in the colour of the closed part
 * whose surface `part` is (tinted or hatched). False (surface untouched) if
 * the crossing cannot be placed. */
static bool make_cap(const render_view *v, const view_extras *x, int plane, const ray *r, const hit *part,
                     ray_packet *p, packet_shading *ps, uint32_t i)
{
    vec3 at;
    if (!clip_crossing(&x->clip, plane, r, &at))
        return false;
    if (part->geom_id != p->geom_id[i] || part->prim_id != p->prim_id[i]) {
        /* the cap is the closed part's, found behind the first surface: its colour and material */
        surface sf = surface_describe(v, r, part, false);
        ps->kd[i] = sf.kd;
        ps->mat[i] = sf.mat;
        p->material_id[i] = (uint32_t)(sf.mat - v->scene->materials);
        p->geom_id[i] = part->geom_id; /* the cap's opacity is its part's */
        p->prim_id[i] = part->prim_id;
    }
    const clip_plane *pl = &frame_state_clip_planes(v->state)[plane];
    vec3 n = v3_dot(pl->normal, r->dir) > 0.f ? v3_scale(pl->normal, -1.f) : pl->normal;
    p->pos_x[i] = at.x, p->pos_y[i] = at.y, p->pos_z[i] = at.z;
    /* rounded once from double: half an ulp of each coordinate, and as much again for the plane's own rounding */
    ps->position_error[i] = v3(fabsf(at.x) * 0x1p-23f, fabsf(at.y) * 0x1p-23f, fabsf(at.z) * 0x1p-23f);
    p->ng_x[i] = p->ns_x[i] = n.x;
    p->ng_y[i] = p->ns_y[i] = n.y;
    p->ng_z[i] = p->ns_z[i] = n.z;
    vec3 kd = v3_scale(ps->kd[i], RENDER_CAP_TINT_FACTOR);
    if (x->set.cap_style == RENDER_CAP_HATCH) {
        /* stripes across the plane, RENDER_CAP_HATCH_PX pixels apart where the plane is
         * nearest the eye: spaced by the eye's distance from the plane (one value per
         * plane and frame, so the stripes are straight) */
        vec3 helper = fabsf(n.x) < 0.9f ? v3(1.f, 0.f, 0.f) : v3(0.f, 1.f, 0.f);
        vec3 across = v3_normalize(v3_cross(n, helper));
        const camera_basis *cam = &v->camera;
        float eye_distance = fabsf(v3_dot(v3_sub(cam->eye, pl->point), pl->normal));
        float pixel = 2.f * v3_length(cam->up) / (float)cam->height_px;
        float spacing = eye_distance * pixel * RENDER_CAP_HATCH_PX;
        if (!(spacing > 0.f))
            spacing = 1.f;
        float phase = v3_dot(at, across) / spacing;
        if (phase - floorf(phase) < 0.5f)
            kd = v3_scale(kd, RENDER_CAP_HATCH_DARK);
    }
    ps->kd[i] = kd;
    return true;
}

/* Per-ray state of a layer walk (render_layers), beside the packets. */
typedef struct layer_walk {
    ray base[PACKET_MAX_RAYS];       /* each ray cut by the planes */
    int8_t entry[PACKET_MAX_RAYS];   /* plane bounding base[i].t_near, or -1 */
    bool cap_checked[PACKET_MAX_RAYS];
    hit last[PACKET_MAX_RAYS];       /* the surface shaded last (the next is after it) */
    bool has_last[PACKET_MAX_RAYS];
    float transmit[PACKET_MAX_RAYS]; /* light still passing: product of 1 - opacity so far */
    vec3 sum[PACKET_MAX_RAYS];
    float media_from[PACKET_MAX_RAYS]; /* where the media not yet composited start (with media) */
} layer_walk;

/* A number in [0, 1) from a ray's direction bits: where a medium's first
 * sample lies within its step (render is a pure function of the pixel, so
 * no frame counter: the same pixel always jitters the same). */
static float ray_jitter(const ray *r)
{
    uint32_t bits[3];
    memcpy(&bits[0], &r->dir.x, 4);
    memcpy(&bits[1], &r->dir.y, 4);
    memcpy(&bits[2], &r->dir.z, 4);
    uint32_t h = bits[0] * 0x9E3779B1u ^ bits[1] * 0x85EBCA77u ^ bits[2] * 0xC2B2AE3Du;
    h ^= h >> 15, h *= 0x2C1B3C6Du, h ^= h >> 12;
    return (float)(h >> 8) * (1.f / 16777216.f);
}

/* The scene's participating media (scene.h, PARTICIPATING MEDIA) along r
 * over [r->t_near, r->t_far] (world space, already cut by the planes):
 * their colour (associated) and the transmittance left, nearest medium
 * first; false (nothing written) when no medium meets the segment. */
uint32_t render_media_spans(const scene *s, const ray *r, render_media_span spans[RENDER_MEDIA_SPANS_MAX])
{
    /* few media: insertion order */
    uint32_t n = 0;
    for (uint32_t m = 0; m < s->medium_count && n < RENDER_MEDIA_SPANS_MAX; m++) {
        const scene_medium *md = &s->media[m];
        aabb box;
        if (!md->ops->bounds(md->data, &box))
            continue;
        ray local = md->identity ? *r : affine3_ray(&md->to_object, r);
        ray_derived d = ray_derive(&local);
        float t0, t1;
        if (!intersect_box_span(&local, &d, &box, &t0, &t1))
            continue;
        uint32_t k = n++;
        while (k > 0 && spans[k - 1].enter > t0) {
            spans[k] = spans[k - 1];
            k--;
        }
        spans[k] = (render_media_span){t0, t1, m};
    }
    return n;
}

static bool media_segment(const scene *s, const ray *r, vec3 *rgb_out, float *transmittance_out)
{
    render_media_span spans[RENDER_MEDIA_SPANS_MAX];
    uint32_t n = render_media_spans(s, r, spans);
    if (n == 0)
        return false;
    vec3 sum = v3(0.f, 0.f, 0.f);
    float through = 1.f; /* transmittance so far */
    float jitter = ray_jitter(r);
    for (uint32_t k = 0; k < n && through > 0.f; k++) {
        const scene_medium *md = &s->media[spans[k].medium];
        ray local = md->identity ? *r : affine3_ray(&md->to_object, r);
        local.t_near = spans[k].enter;
        local.t_far = spans[k].leave;
        vec3 rgb;
        float trans;
        md->ops->integrate(md->data, &local, jitter, &rgb, &trans);
        sum = v3_add(sum, v3_scale(rgb, through));
        through *= trans;
    }
    *rgb_out = sum;
    *transmittance_out = through;
    return true;
}

/* Media in front of each ray's first surface when rays stop at it (no layer
 * walk): colour = medium + transmittance x colour. */
static void composite_media(const render_view *v, const clip_set *clip, uint32_t count, uint64_t active,
                            const ray *rays, const render_first_surfaces *first, vec3 *colour)
{
    for (uint32_t i = 0; i < count; i++) {
        if (!(active >> i & 1u))
            continue;
        ray r = rays[i];
        if (first->hits >> i & 1u)
            r.t_far = first->t[i];
        /* the cutting planes cut media too: what is left of the ray is one
         * interval (the kept half-spaces are convex) */
        if (clip->count > 0 && !clip_ray(clip, &r, NULL))
            continue;
        vec3 rgb;
        float through;
        if (media_segment(v->scene, &r, &rgb, &through))
            colour[i] = v3_add(rgb, v3_scale(colour[i], through));
    }
}

/* In the layer walk: the media between the last surface (or the ray's start)
 * and t_end go into ray i's sum and transmittance before what lies at t_end. */
static void walk_media(const render_view *v, layer_walk *lw, uint32_t i, float t_end)
{
    ray r = lw->base[i];
    r.t_near = lw->media_from[i];
    r.t_far = t_end;
    lw->media_from[i] = t_end;
    vec3 rgb;
    float through;
    if (!(r.t_near < r.t_far) || !media_segment(v->scene, &r, &rgb, &through))
        return;
    lw->sum[i] = v3_add(lw->sum[i], v3_scale(rgb, lw->transmit[i]));
    lw->transmit[i] *= through;
}

/* Trace and shade the primary packet p surface after surface, front to back
 * in the next-hit order (accel_intersect_after: exact depth order, coplanar
 * faces by ids, the same for any thread or tile): each surface's colour
 * (lit and shadowed) adds transmit x opacity of it, transmit shrinks by
 * 1 - opacity; a ray stops at an opaque surface, when transmit falls below
 * min_transmittance (the rest is dropped), or at its max_layers-th surface,
 * which counts as opaque; a ray that leaves adds transmit x background.
 * Rays are cut by the cutting planes first; where a ray enters the kept
 * region through a plane inside a closed part, the part's cut face (a cap)
 * is its first surface. With all opacities 1 and no planes this gives
 * shade_packet's colours bit for bit. `first` (may be NULL) receives the
 * surfaces of layer 0. */
static void render_layers(const render_view *v, const view_extras *x, ray_packet *p, ray_packet *shadows,
                          packet_shading *ps, layer_walk *lw, render_first_surfaces *first, render_counts *counts)
{
    const scene *s = v->scene;
    const uint32_t count = p->count, facts = p->flags & (PACKET_COMMON_ORIGIN | PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED);
    const vec3 background = v->shading == RENDER_SHADE_EYELIGHT ? v3(0.f, 0.f, 0.f) : s->background;
    const bool caps = x->set.caps && x->clip.count > 0;
    const bool media = s->medium_count > 0; /* composited between the layers, front to back */
    uint64_t walking = 0;
    counts->primary_rays += count;
    for (uint32_t i = 0; i < count; i++) {
        lw->base[i] = packet_get_ray(p, i);
        int entry = -1;
        lw->sum[i] = v3(0.f, 0.f, 0.f);
        lw->transmit[i] = 1.f;
        lw->has_last[i] = lw->cap_checked[i] = false;
        if (x->clip.count > 0 && !clip_ray(&x->clip, &lw->base[i], &entry))
            lw->sum[i] = background; /* everything along it is cut away */
        else
            walking |= 1ull << i;
        lw->entry[i] = (int8_t)entry;
        lw->media_from[i] = lw->base[i].t_near;
    }
    for (int layer = 0; walking; layer++) {
        packet_reset(p, count, facts);
        p->active = walking;
        for (uint64_t m = walking; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            packet_set_ray(p, i, &lw->base[i]);
            if (lw->has_last[i])
                packet_set_after(p, i, &lw->last[i]);
        }
        if (layer > 0)
            counts->secondary_rays += (uint64_t)__builtin_popcountll(walking);
        accel_intersect_packet(v->accel, packet_whole(p));
        ps->hits = 0;
        for (uint64_t m = walking; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            if (p->hit_t[i] != INFINITY) {
                ps->hits |= 1ull << i;
                continue;
            }
            if (media)
                walk_media(v, lw, i, lw->base[i].t_far);
            lw->sum[i] = v3_add(lw->sum[i], v3_scale(background, lw->transmit[i]));
            walking &= ~(1ull << i);
        }
        if (!ps->hits)
            break;
        if (layer == 0)
            counts->primary_hits += (uint64_t)__builtin_popcountll(ps->hits);
        packet_derive_hit_surfaces(v, p, ps, needs_position(v));
        uint64_t capped = 0; /* lanes shading a cap this layer: their hit is still ahead */
        if (caps)
            for (uint64_t m = ps->hits; m; m &= m - 1) {
                uint32_t i = (uint32_t)__builtin_ctzll(m);
                if (lw->entry[i] < 0 || lw->cap_checked[i])
                    continue;
                lw->cap_checked[i] = true;
                hit part;
                if (first_closed_hit(v, &lw->base[i], packet_get_hit(p, i), &part, counts) &&
                    inside_by_parity(v, &lw->base[i], &part, counts) &&
                    make_cap(v, x, lw->entry[i], &lw->base[i], &part, p, ps, i))
                    capped |= 1ull << i;
            }
        shade_hits(v, x, p, shadows, ps, counts);
        const bool last_layer = layer + 1 >= x->set.max_layers;
        float alpha_of[PACKET_MAX_RAYS];
        for (uint64_t m = ps->hits; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            alpha_of[i] = last_layer ? 1.f : opacity_of(v, p->geom_id[i]);
        }
        if (layer == 0 && first)
            note_first_surfaces(v, p, ps, alpha_of, capped, first);
        for (uint64_t m = ps->hits; m; m &= m - 1) {
            uint32_t i = (uint32_t)__builtin_ctzll(m);
            float alpha = alpha_of[i];
            if (media)
                walk_media(v, lw, i, p->hit_t[i]);
            lw->sum[i] = v3_add(lw->sum[i], v3_scale(ps->colour[i], lw->transmit[i] * alpha));
            lw->transmit[i] *= 1.f - alpha;
            if (alpha >= 1.f || lw->transmit[i] < x->set.min_transmittance) {
                walking &= ~(1ull << i);
                continue;
            }
            if (!(capped >> i & 1u)) {
                lw->last[i] = packet_get_hit(p, i);
                lw->has_last[i] = true;
            }
        }
    }
    for (uint32_t i = 0; i < count; i++)
        ps->colour[i] = lw->sum[i];
}

/* Per thread, for the media of a packet when rays stop at their first
 * surface: those surfaces when the caller asked for none
 * (render_first_surfaces is 3.6 KB), and the rays as they were before
 * tracing. */
static _Thread_local render_first_surfaces media_first;
static _Thread_local ray media_rays[PACKET_MAX_RAYS];

/* Trace and shade primary packet p into ps->colour, by the walk the frame
 * needs; `first` (may be NULL) receives each ray's first surface. Media
 * (scene.h) go in front of the first surfaces, or between the layers when
 * rays walk them. */
static void trace_packet(const render_view *v, const view_extras *x, ray_packet *p, ray_packet *shadows,
                         packet_shading *ps, layer_walk *lw, render_first_surfaces *first, render_counts *counts)
{
    const bool media = v->scene->medium_count > 0;
    const uint32_t count = p->count;
    const uint64_t active = p->active;
    if (media) {
        if (!first)
            first = &media_first;
        for (uint32_t i = 0; i < count; i++)
            media_rays[i] = packet_get_ray(p, i);
    }
    if (first)
        first->hits = 0;
    if (needs_layers(x)) { /* media between the layers (render_layers) */
        render_layers(v, x, p, shadows, ps, lw, first, counts);
        return;
    }
    shade_packet(v, x, p, shadows, ps, first, counts);
    if (media)
        composite_media(v, &x->clip, count, active, media_rays, first, ps->colour);
}

/* Per thread: two packets and the shading state, ~65 KB: too big for a
 * worker's stack. Used by one block (or one render_shade) at a time. */
static _Thread_local struct render_scratch {
    ray_packet primary, shadows;
    packet_shading ps;
    layer_walk walk;
} scratch;

/* render_shade when surfaces are walked layer by layer: the packet walk on a
 * packet of this one ray (the same kernels, single-ray path), in the
 * thread's scratch (render_shade is never called from inside a tile). */
static vec3 render_shade_layers(const render_view *v, const ray *r, uint64_t *shadow_rays)
{
    view_extras x;
    view_extras_make(v, &x);
    packet_reset(&scratch.primary, 1, 0);
    packet_set_ray(&scratch.primary, 0, r);
    packet_detect_facts(&scratch.primary);
    render_counts counts = {0};
    render_layers(v, &x, &scratch.primary, &scratch.shadows, &scratch.ps, &scratch.walk, NULL, &counts);
    *shadow_rays += counts.shadow_rays;
    return scratch.ps.colour[0];
}

void render_trace_primary(const render_view *v, ray_packet *p, vec3 colour[PACKET_MAX_RAYS],
                          render_first_surfaces *first, render_counts *counts)
{
    view_extras x;
    view_extras_make(v, &x);
    trace_packet(v, &x, p, &scratch.shadows, &scratch.ps, &scratch.walk, first, counts);
    memcpy(colour, scratch.ps.colour, p->count * sizeof colour[0]);
}

/* Primary rays per packet: 8 x 8 pixels, so a packet covers a compact patch. */
#define RENDER_PACKET_EDGE_PX 8

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
    view_extras x;
    view_extras_make(v, &x);
    for (int py = y0; py < y1; py += RENDER_PACKET_EDGE_PX)
        for (int px = x0; px < x1; px += RENDER_PACKET_EDGE_PX) {
            int w = x1 - px < RENDER_PACKET_EDGE_PX ? x1 - px : RENDER_PACKET_EDGE_PX;
            int h = y1 - py < RENDER_PACKET_EDGE_PX ? y1 - py : RENDER_PACKET_EDGE_PX;
            packet_primary(&scratch.primary, cam, px, py, w, h);
            trace_packet(v, &x, &scratch.primary, &scratch.shadows, &scratch.ps, &scratch.walk, NULL, counts);
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
    view_extras x;
    view_extras_make(v, &x);
    for (int r = 0; r < n; r++)
        sum[r] = v3(0.f, 0.f, 0.f);
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) {
            pixel_sampler_block_positions(s, x0, y0, w, h, i, j, sample_x, sample_y);
            packet_primary_at(&scratch.primary, &v->camera, sample_x, sample_y, (uint32_t)n);
            trace_packet(v, &x, &scratch.primary, &scratch.shadows, &scratch.ps, &scratch.walk, NULL, counts);
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
    view_extras x;
    view_extras_make(v, &x);
    pixel_sampler_block_positions(s, x0, y0, w, h, 0, 0, sample_x, sample_y);
    packet_primary_at(&scratch.primary, &v->camera, sample_x, sample_y, (uint32_t)n);
    trace_packet(v, &x, &scratch.primary, &scratch.shadows, &scratch.ps, &scratch.walk, NULL, counts);
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
    const renderer *renderer;
    const render_view *view;
    const pixel_sampler *sampler;
    float *rgb;
    int tile_px, tiles_x, tile_count;
    atomic_int next_tile; /* next tile index to hand out; tiles >= tile_count mean done */
    atomic_uint_fast64_t primary_rays, primary_hits, shadow_rays, secondary_rays, ao_rays; /* totals, added once per thread */
} tile_queue;

static void *render_worker(void *arg)
{
    tile_queue *q = arg;
    const camera_basis *cam = &q->view->camera;
    render_counts counts = {0}; /* this thread's, folded in once at the end */
    for (;;) {
        int tile = atomic_fetch_add_explicit(&q->next_tile, 1, memory_order_relaxed);
        if (tile >= q->tile_count) {
            atomic_fetch_add_explicit(&q->primary_rays, counts.primary_rays, memory_order_relaxed);
            atomic_fetch_add_explicit(&q->primary_hits, counts.primary_hits, memory_order_relaxed);
            atomic_fetch_add_explicit(&q->shadow_rays, counts.shadow_rays, memory_order_relaxed);
            atomic_fetch_add_explicit(&q->secondary_rays, counts.secondary_rays, memory_order_relaxed);
            atomic_fetch_add_explicit(&q->ao_rays, counts.ao_rays, memory_order_relaxed);
            return NULL;
        }
        int x0 = (tile % q->tiles_x) * q->tile_px, y0 = (tile / q->tiles_x) * q->tile_px;
        int x1 = x0 + q->tile_px < cam->width_px ? x0 + q->tile_px : cam->width_px;
        int y1 = y0 + q->tile_px < cam->height_px ? y0 + q->tile_px : cam->height_px;
        q->renderer->render_tile(q->view, q->sampler, x0, y0, x1, y1, q->rgb, &counts);
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
    static const renderer tiles_sampled = {"raytracer", RENDER_SHADE_PHONG, render_tile_sampled};
    render_image_tiles(&tiles_sampled, v, s, threads, RENDER_TILE_PX, rgb, counts);
}

void render_image_tiles(const renderer *r, const render_view *v, const pixel_sampler *s, int threads, int tile_px,
                        float *rgb, render_counts *counts)
{
    tile_queue q = {.renderer = r, .view = v, .sampler = s, .rgb = rgb, .tile_px = tile_px < 1 ? 1 : tile_px};
    q.tiles_x = (v->camera.width_px + q.tile_px - 1) / q.tile_px;
    q.tile_count = q.tiles_x * ((v->camera.height_px + q.tile_px - 1) / q.tile_px);
    atomic_init(&q.next_tile, 0);
    atomic_init(&q.primary_rays, 0);
    atomic_init(&q.primary_hits, 0);
    atomic_init(&q.shadow_rays, 0);
    atomic_init(&q.secondary_rays, 0);
    atomic_init(&q.ao_rays, 0);
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
        counts->secondary_rays = atomic_load(&q.secondary_rays);
        counts->ao_rays = atomic_load(&q.ao_rays);
    }
}

render_settings render_settings_default(void)
{
    render_settings s;
    memset(&s, 0, sizeof s); /* padding too: configs that hold settings are compared byte for byte */
    s.min_transmittance = RENDER_MIN_TRANSMITTANCE_DEFAULT;
    s.max_layers = RENDER_MAX_LAYERS_DEFAULT;
    s.transparent_shadows = true;
    s.caps = true;
    s.cap_style = RENDER_CAP_TINT;
    s.ao_rays = 16;
    s.ao_distance = 0.f;
    s.ao_interleave = 4;
    s.ao_filter_px = 5;
    s.ao_frames = 1;
    s.ao_exponent = RENDER_AO_EXPONENT_DEFAULT;
    s.ao_frame_base = 0;
    return s;
}

static const renderer renderers[] = {
    {"raytracer", RENDER_SHADE_PHONG, render_tile_sampled},
    {"eyelight", RENDER_SHADE_EYELIGHT, render_tile_sampled},
    {"ao", RENDER_SHADE_PHONG, render_ao_tile}, /* engine/render/render_ao.c; shading unused */
    {"raytracer-ao", RENDER_SHADE_PHONG, render_raytracer_ao_tile}, /* engine/render/render_ao.c */
};

const renderer *renderer_by_name(const char *name)
{
    for (size_t i = 0; i < sizeof renderers / sizeof renderers[0]; i++)
        if (!strcmp(renderers[i].name, name))
            return &renderers[i];
    return NULL;
}
