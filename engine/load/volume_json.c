/* volume_json.c - a "volumes" entry of a scene file (volume_json.h). */
#include "volume_json.h"

#include <stdio.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "engine/scene/scene.h"
#include "engine/render/dvr_medium.h"
#include "engine/geometry/volume/iso_kind.h"
#include "engine/geometry/volume/macrocell.h"
#include "volume_read.h"

/* most iso-surfaces one entry may show (each is a geometry of its own) */
#define VOLUME_JSON_MAX_ISO 16

const char *const volume_json_fields[] = {"file", "files", "transform", "matrix", "optional", "macrocell", "iso", "dvr",
                                          NULL};

/* One "iso" element: {"value": V, "color": [r, g, b], "opacity": A, "material": NAME, "method": M}. */
static bool add_iso(jr_ctx *c, json_object *e, iso_volume *shared, const affine3 *placement, scene *s,
                    uint32_t default_material, volume_json_material_fn find_material, void *material_ctx)
{
    static const char *const fields[] = {"value", "color", "opacity", "material", "method", NULL};
    static const char *const methods[] = {"exact", "linear", "regula-falsi", NULL};
    const iso_method by_index[] = {ISO_METHOD_EXACT, ISO_METHOD_LINEAR, ISO_METHOD_REGULA_FALSI};
    float value = 0.f;
    vec3 colour = v3(0.8f, 0.8f, 0.8f);
    float opacity = 1.f;
    const char *material_name = NULL;
    int method = 0;
    if (!jr_expect_object(c, e) || !jr_check_fields(c, e, fields) || !jr_require_member(c, e, "value") ||
        !jr_opt_number(c, e, "value", jr_range_float, &value) || !jr_opt_vec3(c, e, "color", jr_range_unit, &colour) ||
        !jr_opt_number(c, e, "opacity", jr_range_unit, &opacity) ||
        !jr_opt_string(c, e, "material", &material_name) || !jr_opt_choice(c, e, "method", methods, &method))
        return false;
    uint32_t material_id = default_material;
    if (material_name) {
        int id = find_material ? find_material(material_ctx, material_name) : -1;
        if (id < 0)
            return jr_member_fail(c, "material", "no material of that name in \"materials\"");
        material_id = (uint32_t)id;
    }
    tess_error why = {{0}};
    iso_kind *k = iso_kind_create_shared(shared, value, colour, material_id, by_index[method], &why);
    if (!k)
        return jr_field_fail(c, "%s", why.msg);
    char name[SCENE_NAME_BYTES];
    snprintf(name, sizeof name, "iso %g", (double)value);
    int g = scene_add_geometry(s, &iso_kind_ops, k, name);
    int inst = g < 0 ? -1 : scene_add_instance(s, (uint32_t)g, placement, SCENE_NO_PART);
    if (inst < 0)
        return jr_field_fail(c, "out of memory adding the iso-surface");
    s->instances[inst].opacity = opacity;
    return true;
}

/* "dvr": {"transfer": COLOUR MAP, "step": VOXELS, "preintegrated": BOOL}. */
static bool add_dvr(jr_ctx *c, json_object *d, iso_volume *shared, const affine3 *placement, scene *s)
{
    static const char *const fields[] = {"transfer", "step", "preintegrated", NULL};
    json_object *tf_json;
    if (!jr_expect_object(c, d) || !jr_check_fields(c, d, fields) || !jr_require_member(c, d, "transfer"))
        return false;
    dvr_settings settings = dvr_settings_default();
    float step = (float)settings.step_vox;
    const jr_range step_range = {DVR_STEP_MIN_VOX, DVR_STEP_MAX_VOX, false, false};
    if (!jr_opt_number(c, d, "step", step_range, &step) || !jr_opt_bool(c, d, "preintegrated", &settings.preintegrate))
        return false;
    settings.step_vox = step;
    colormap tf;
    jr_get_member(d, "transfer", &tf_json);
    size_t saved = jr_field_key(c, "transfer");
    bool ok = colormap_from_json(tf_json, c, &tf) &&
              (tf.opacity_count > 0 ||
               jr_field_fail(c, "a transfer function needs opacity points (\"opacity\"; or a preset such as "
                                "\"ct-bone\" or \"mri-soft\")"));
    jr_field_leave(c, saved);
    if (!ok)
        return false;
    tess_error why = {{0}};
    dvr_medium *m = dvr_medium_create(shared, &tf, &settings, &why);
    if (!m)
        return jr_field_fail(c, "%s", why.msg);
    if (scene_add_medium(s, &dvr_medium_ops, m, placement, "dvr") < 0)
        return jr_field_fail(c, "out of memory adding the volume rendering");
    return true;
}

bool volume_json_add(jr_ctx *c, json_object *obj, volume *v, const char *const *steps, uint32_t step_count,
                     const affine3 *placement, scene *s, uint32_t default_material,
                     volume_json_material_fn find_material, void *material_ctx)
{
    json_object *iso = NULL, *dvr = NULL;
    bool has_iso = jr_get_member(obj, "iso", &iso), has_dvr = jr_get_member(obj, "dvr", &dvr);
    float k = (float)MACROCELL_DEFAULT_K;
    const jr_range k_range = {1.0, 64.0, false, false};
    if (!has_iso && !has_dvr) {
        volume_destroy(v);
        return jr_field_fail(c, "give 'iso' (iso-surfaces), 'dvr' (volume rendering) or both");
    }
    if (!jr_opt_number(c, obj, "macrocell", k_range, &k) ||
        ((float)(uint32_t)k != k && !jr_member_fail(c, "macrocell", "must be a whole number of cells"))) {
        volume_destroy(v);
        return false;
    }
    tess_error why = {{0}};
    uint64_t voxels = (uint64_t)v->nx * v->ny * v->nz;
    macrocell_grid *grid = macrocell_grid_create(v, (uint32_t)k, &why);
    if (!grid) {
        volume_destroy(v);
        return jr_field_fail(c, "%s", why.msg);
    }
    iso_volume *shared = iso_volume_create(v, grid, &why); /* takes both */
    if (!shared)
        return jr_field_fail(c, "%s", why.msg);
    bool ok = !steps || iso_volume_attach_series(shared, steps, step_count, volume_load, &why) ||
              jr_member_fail(c, "files", why.msg);
    if (ok && has_iso) {
        size_t outer = jr_field_key(c, "iso");
        ok = jr_expect_array(c, iso);
        size_t n = ok ? json_object_array_length(iso) : 0;
        if (ok && (n == 0 || n > VOLUME_JSON_MAX_ISO))
            ok = jr_field_fail(c, "%zu iso-surfaces (1 to %d)", n, VOLUME_JSON_MAX_ISO);
        for (size_t i = 0; ok && i < n; i++) {
            size_t saved = jr_field_index(c, i);
            ok = add_iso(c, json_object_array_get_idx(iso, i), shared, placement, s, default_material, find_material,
                         material_ctx);
            jr_field_leave(c, saved);
        }
        jr_field_leave(c, outer);
    }
    if (ok && has_dvr) {
        size_t outer = jr_field_key(c, "dvr");
        ok = add_dvr(c, dvr, shared, placement, s);
        jr_field_leave(c, outer);
    }
    iso_volume_release(shared); /* the kinds and the medium hold their own */
    if (ok) {
        s->volume_count++;
        s->volume_voxels += voxels;
    }
    return ok;
}
