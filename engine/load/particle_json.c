/* particle_json.c - a "particles" entry of a scene file (particle_json.h). */
#include "particle_json.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const particle_json_fields[] = {"file",     "files",  "material", "transform", "matrix",
                                            "optional", "radius", "crop",     "color_by",  "color_map", NULL};

/* "id, type, c_ke" (cut to fit) for messages about a name the set lacks. */
static void attribute_names(const particle_set *set, char *out, size_t size)
{
    size_t used = 0;
    out[0] = '\0';
    for (uint32_t a = 0; a < set->attribute_count && used + 1 < size; a++) {
        int n = snprintf(out + used, size - used, "%s%s", a ? ", " : "", set->attributes[a].name);
        if (n < 0)
            break;
        used += (size_t)n;
    }
    if (set->attribute_count == 0)
        snprintf(out, size, "no attributes");
}

/* Attribute `name` of the set, or a message at the current field. */
static bool find_attribute(jr_ctx *c, const particle_set *set, const char *name, int *index)
{
    *index = particle_set_find_attribute(set, name);
    if (*index >= 0)
        return true;
    char names[256];
    attribute_names(set, names, sizeof names);
    return jr_field_fail(c, "no attribute '%s' (the file has: %s)", name, names);
}

static bool read_radius(jr_ctx *c, json_object *v, const particle_set *set, particle_kind_options *opt)
{
    json_object *r;
    if (!jr_get_member(v, "radius", &r)) {
        opt->radius = particle_kind_default_radius(set);
        return true;
    }
    size_t saved = jr_field_key(c, "radius");
    bool ok;
    if (json_object_is_type(r, json_type_string)) {
        int index;
        ok = find_attribute(c, set, json_object_get_string(r), &index);
        if (ok) {
            opt->radius_attribute = set->attributes[index].name;
            const particle_attribute *a = &set->attributes[index];
            ok = set->count == 0 || a->min > 0.f ||
                 jr_field_fail(c, "attribute '%s' has values down to %g (a radius must be > 0)", a->name,
                               (double)a->min);
        }
    } else if (jr_is_number(r)) {
        ok = jr_number(c, r, jr_range_positive, &opt->radius);
    } else {
        ok = jr_field_fail(c, "expected a number > 0 or an attribute name, got %s", jr_kind(r));
    }
    jr_field_leave(c, saved);
    return ok;
}

static bool read_crop(jr_ctx *c, json_object *v, const particle_set *set, particle_kind_options *opt)
{
    static const char *const fields[] = {"attribute", "range", NULL};
    json_object *crop, *range;
    if (!jr_get_member(v, "crop", &crop))
        return true;
    size_t saved = jr_field_key(c, "crop");
    const char *name = NULL;
    int index = -1;
    bool ok = jr_expect_object(c, crop) && jr_check_fields(c, crop, fields) &&
              jr_require_member(c, crop, "attribute") && jr_opt_string(c, crop, "attribute", &name);
    if (ok) {
        size_t inner = jr_field_key(c, "attribute");
        ok = find_attribute(c, set, name, &index);
        jr_field_leave(c, inner);
    }
    if (ok) {
        opt->crop_attribute = set->attributes[index].name;
        opt->crop = (geometry_crop){false, set->attributes[index].min, set->attributes[index].max};
        if (jr_get_member(crop, "range", &range)) {
            float lohi[2];
            size_t inner = jr_field_key(c, "range");
            ok = jr_numbers(c, range, 2, jr_range_float, lohi) &&
                 (lohi[0] <= lohi[1] ||
                  jr_field_fail(c, "the low end %g is above the high end %g", (double)lohi[0], (double)lohi[1]));
            jr_field_leave(c, inner);
            if (ok)
                opt->crop = (geometry_crop){true, lohi[0], lohi[1]};
        }
    }
    jr_field_leave(c, saved);
    return ok;
}

/* "color_by": an attribute (through "color_map", default viridis over the
 * attribute's range) or "rgb" (the attributes red, green, blue); absent:
 * "rgb" when the set has those three, else the material's colour. */
static bool read_colour(jr_ctx *c, json_object *v, const particle_set *set, particle_kind_options *opt,
                        colormap *map)
{
    const char *by = NULL;
    json_object *m;
    bool has_map = jr_get_member(v, "color_map", &m);
    if (!jr_opt_string(c, v, "color_by", &by))
        return false;
    bool has_rgb = particle_set_find_attribute(set, "red") >= 0 && particle_set_find_attribute(set, "green") >= 0 &&
                   particle_set_find_attribute(set, "blue") >= 0;
    if (!by) {
        if (has_map)
            return jr_member_fail(c, "color_map", "needs 'color_by' (the attribute it colours)");
        opt->colouring = has_rgb ? PARTICLE_COLOUR_RGB : PARTICLE_COLOUR_MATERIAL;
        return true;
    }
    size_t saved = jr_field_key(c, "color_by");
    int index = -1;
    bool ok = true;
    if (strcmp(by, "rgb") == 0) {
        ok = has_rgb || jr_field_fail(c, "'rgb' needs the attributes red, green and blue");
        opt->colouring = PARTICLE_COLOUR_RGB;
    } else {
        ok = find_attribute(c, set, by, &index);
        opt->colouring = PARTICLE_COLOUR_MAP;
    }
    jr_field_leave(c, saved);
    if (!ok)
        return false;
    if (opt->colouring == PARTICLE_COLOUR_RGB) {
        return !has_map || jr_member_fail(c, "color_map", "a colour map needs an attribute in 'color_by', not 'rgb'");
    }
    opt->colour_attribute = set->attributes[index].name;
    if (!has_map)
        return true;
    saved = jr_field_key(c, "color_map");
    ok = colormap_from_json(m, c, map);
    jr_field_leave(c, saved);
    if (ok)
        opt->map = map;
    return ok;
}

particle_kind *particle_json_kind(jr_ctx *c, json_object *v, particle_set *set, uint32_t material_id)
{
    particle_kind_options opt = {.material_id = material_id};
    colormap map; /* read_colour fills it when given; the kind copies it */
    if (!read_radius(c, v, set, &opt) || !read_crop(c, v, set, &opt) || !read_colour(c, v, set, &opt, &map)) {
        particle_set_destroy(set);
        return NULL;
    }
    tess_error why = {{0}};
    particle_kind *k = particle_kind_create(set, &opt, "the particles", &why);
    if (!k)
        jr_field_fail(c, "%s", why.msg);
    return k;
}
