/* input_pick.c - the input controller's pick hook over a scene (input_pick.h). */
#include "input_pick.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/scene/part_tree.h"
#include "engine/geometry/particles/particle_kind.h"
#include "engine/scene/scene.h"

/* A path is at most this long before its label is cut (deeper paths than
 * this are not worth showing whole on a status line anyway). */
#define PATH_BYTES 4096

/* Part id's path as a label: whole when it fits, else "..." and its tail. */
static void part_label(const part_tree *t, int32_t id, char *out, size_t size)
{
    char path[PATH_BYTES];
    size_t n = part_tree_path(t, id, path, sizeof path);
    if (n >= sizeof path)
        n = sizeof path - 1; /* cut at the end by part_tree_path: show its head */
    if (n == 0) {
        snprintf(out, size, "(the whole assembly)");
    } else if (n < size) {
        memcpy(out, path, n + 1);
    } else {
        size_t keep = size - 4; /* "..." + tail + NUL */
        memcpy(out, "...", 3);
        memcpy(out + 3, path + n - keep, keep);
        out[size - 1] = '\0';
    }
}

/* Part id's subtree as an input_part; false when it holds no instance. */
static bool part_range(const scene *s, int32_t id, input_part *out)
{
    uint32_t first = 0, end = 0;
    scene_part_instances(s, (uint32_t)id, &first, &end);
    if (end <= first)
        return false;
    out->first = first;
    out->count = end - first;
    part_label(s->parts, id, out->label, sizeof out->label);
    return true;
}

/* Fill the part, its ancestors and `what` for a hit on a part; false when the
 * hit instance has none. */
static bool hit_part(const scene *s, const hit *h, input_hit *out)
{
    if (!s->parts || h->geom_id >= s->instance_count)
        return false;
    uint32_t part = s->instances[h->geom_id].part;
    if (part == SCENE_NO_PART || part >= (uint32_t)part_tree_count(s->parts))
        return false;
    if (!part_range(s, (int32_t)part, &out->part))
        return false;
    const scene_geometry *g = scene_instance_geometry(s, h->geom_id);
    const char *prim = g->ops == &geometry_triangles_ops ? "triangle" : "primitive";
    char tail[40];
    size_t tail_len = (size_t)snprintf(tail, sizeof tail, " %s %u", prim, h->prim_id);
    size_t label_len = strlen(out->part.label), room = sizeof out->what - 5 - tail_len - 1;
    /* "part PATH triangle N"; a path too long keeps its tail after "...", as the label does */
    const char *path = out->part.label;
    size_t path_len = label_len;
    char *w = out->what;
    memcpy(w, "part ", 5);
    w += 5;
    if (label_len > room) {
        memcpy(w, "...", 3);
        w += 3;
        path_len = room - 3;
        path += label_len - path_len;
    }
    memcpy(w, path, path_len);
    memcpy(w + path_len, tail, tail_len + 1);
    out->ancestor_count = 0;
    for (int32_t p = part_tree_parent(s->parts, (int32_t)part);
         p != PART_NONE && p != PART_ROOT && out->ancestor_count < INPUT_HIT_ANCESTORS;
         p = part_tree_parent(s->parts, p))
        if (part_range(s, p, &out->ancestors[out->ancestor_count]))
            out->ancestor_count++;
    return true;
}

void cli_input_pick(const scene *s, const accel *a, vec3 origin, vec3 dir, input_hit *out)
{
    ray r = {.org = origin, .dir = dir, .t_near = 0.f, .t_far = INFINITY};
    hit h;
    memset(out, 0, sizeof *out);
    if (!accel_pick(a, &r, &h))
        return;
    out->hit = true;
    out->point = v3_add(origin, v3_scale(dir, h.t));
    out->geom_id = h.geom_id;
    out->prim_id = h.prim_id;
    if (hit_part(s, &h, out))
        return;
    out->part.first = h.geom_id;
    out->part.count = 1;
    const scene_geometry *g = scene_instance_geometry(s, h.geom_id);
    if (g->ops == &geometry_triangles_ops) {
        snprintf(out->what, sizeof out->what, "mesh %u '%s' triangle %u", h.geom_id, g->name, h.prim_id);
        snprintf(out->part.label, sizeof out->part.label, "mesh %u '%s'", h.geom_id, g->name);
    } else if (g->ops == &geometry_spheres_ops) {
        /* spheres are one geometry: hiding one hides the set (per-sphere hiding is not there yet) */
        snprintf(out->what, sizeof out->what, "sphere %u", h.prim_id);
        snprintf(out->part.label, sizeof out->part.label, "the sphere set (%u spheres)", s->spheres.count);
    } else if (g->ops == &particle_kind_ops) {
        /* a particle's attributes are what people pick it for: "particle 12 of 'melt.dump': id 4512,
         * c_ke 3.21, ..." (as many as fit the status line) */
        const particle_set *set = particle_kind_set(g->data);
        int used = snprintf(out->what, sizeof out->what, "particle %u of '%s'", h.prim_id, g->name);
        for (uint32_t k = 0; k < set->attribute_count && used > 0; k++) {
            char one[64];
            int n = snprintf(one, sizeof one, "%s %s %.4g", k ? "," : ":", set->attributes[k].name,
                             (double)set->attributes[k].values[h.prim_id]);
            if (n < 0 || (size_t)n >= sizeof one || (size_t)(used + n) >= sizeof out->what)
                break; /* whole attributes only */
            memcpy(out->what + used, one, (size_t)n + 1);
            used += n;
        }
        snprintf(out->part.label, sizeof out->part.label, "the particles '%s' (%u)", g->name, set->count);
    } else {
        snprintf(out->what, sizeof out->what, "%s %u '%s' primitive %u", g->ops->name, h.geom_id, g->name, h.prim_id);
        snprintf(out->part.label, sizeof out->part.label, "%s %u '%s'", g->ops->name, h.geom_id, g->name);
    }
}
