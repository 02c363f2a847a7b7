/* surface.c - a hit described for shading (surface.h). */
#include "surface.h"

#include <math.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/accel/geometry.h"


/* A world position's rounding bound after the instance's transform: the
 * object-space bound carried through |L|, plus the transform's own rounding
 * (a few ulps of each term, gamma(4) of |L| |p| + |t|). */
static vec3 transformed_error(const affine3 *m, vec3 p, vec3 error)
{
    const float *a = m->m;
    const float g = 4.f * 0x1p-24f / (1.f - 4.f * 0x1p-24f);
    float out[3];
    for (int r = 0; r < 3; r++) {
        float l0 = fabsf(a[4 * r]), l1 = fabsf(a[4 * r + 1]), l2 = fabsf(a[4 * r + 2]);
        float carried = l0 * error.x + l1 * error.y + l2 * error.z;
        float magnitude = l0 * fabsf(p.x) + l1 * fabsf(p.y) + l2 * fabsf(p.z) + fabsf(a[4 * r + 3]);
        out[r] = (carried + g * magnitude) * (1.f + 2.f * g);
    }
    return v3(out[0], out[1], out[2]);
}

/* Highlighted parts are drawn in their colour mixed this far towards
 * RENDER_HIGHLIGHT_RGB (lit and shadowed like the rest). */
#define RENDER_HIGHLIGHT_MIX 0.6f
static const vec3 render_highlight_rgb = {1.0f, 0.55f, 0.05f};

/* Describe the hit surface in the world: its instance's geometry describes it
 * in object space (the ray mapped there as traversal mapped it), then the
 * instance's transform places it. The position (and its error bound) only
 * when `need_position`, i.e. when shading will cast a shadow ray or light a
 * point. */
surface surface_describe(const render_view *v, const ray *r, const hit *h, bool need_position)
{
    const scene *s = v->scene;
    const scene_instance *inst = &s->instances[h->geom_id];
    const scene_geometry *g = &s->geometries[inst->geometry];
    /* where the instance is now (a move transaction may have placed it anew) */
    const accel_placement *pl = accel_placement_of(v->accel, h->geom_id);
    geometry_surface gs;
    surface sf;
    if (pl->identity) {
        g->ops->describe(g->data, h->prim_id, r, h, need_position, &gs);
        sf.position = gs.position;
        sf.position_error = gs.position_error;
        sf.geometric_n = gs.geometric_n;
        sf.shading_n = gs.shading_n;
    } else {
        ray local = affine3_ray(&pl->to_object, r);
        g->ops->describe(g->data, h->prim_id, &local, h, need_position, &gs);
        if (need_position) {
            sf.position = affine3_point(&pl->to_world, gs.position);
            sf.position_error = transformed_error(&pl->to_world, gs.position, gs.position_error);
        }
        /* normals by the inverse transpose: the transpose of world -> object */
        sf.geometric_n = v3_normalize(affine3_vector_transposed(&pl->to_object, gs.geometric_n));
        sf.shading_n = v3_normalize(affine3_vector_transposed(&pl->to_object, gs.shading_n));
    }
    const frame_state *st = v->state;
    sf.mat = &s->materials[inst->material != SCENE_NO_MATERIAL ? inst->material : gs.material_id];
    sf.kd = gs.has_colour ? gs.colour : sf.mat->diffuse;
    if (st) { /* the frame state's colour and highlight of the instance (absent: two NULL tests) */
        vec3 rgb;
        if (frame_state_colour(st, h->geom_id, &rgb))
            sf.kd = rgb;
        if (frame_state_highlighted(st, h->geom_id))
            sf.kd = v3_add(v3_scale(sf.kd, 1.f - RENDER_HIGHLIGHT_MIX), v3_scale(render_highlight_rgb, RENDER_HIGHLIGHT_MIX));
    }
    /* two-sided: face the viewer */
    if (v3_dot(sf.geometric_n, r->dir) > 0.f)
        sf.geometric_n = v3_scale(sf.geometric_n, -1.f);
    if (v3_dot(sf.shading_n, sf.geometric_n) < 0.f)
        sf.shading_n = v3_scale(sf.shading_n, -1.f);
    return sf;
}

