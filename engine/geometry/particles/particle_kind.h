/* particle_kind.h - particles as a geometry kind (geometry.h): a particle
 * set drawn as spheres, read in place by the kernels (GEOMETRY_LEAF_POINTS),
 * with a radius, a crop by an attribute's value and its own wide BVH.
 *
 * MEMORY. The kind keeps the set's arrays (12 bytes a particle, plus its
 * attributes) and one wide BVH whose leaves are ranges of them: no centre
 * is copied. Building the tree reorders the set (particles.h ORDER), once.
 *
 * CROP. With a crop attribute, only particles whose value lies in the crop
 * range are seen (by every ray: primary, shadow, AO). The tree keeps each
 * child's range of that attribute, so a crop skips whole subtrees; the range
 * changes (particle_kind_set_crop) without a rebuild, in a serial section
 * (nothing traces meanwhile), like hiding a part.
 *
 * Registration: scene_add_geometry(s, &particle_kind_ops, kind, name). */
#ifndef TESSERA_PARTICLE_KIND_H
#define TESSERA_PARTICLE_KIND_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/colormap.h"
#include "engine/base/err.h"
#include "engine/accel/geometry.h"
#include "particles.h"

typedef struct particle_kind particle_kind;

/* How particles are coloured. */
typedef enum particle_colouring {
    PARTICLE_COLOUR_MATERIAL, /* the material's diffuse colour */
    PARTICLE_COLOUR_MAP,      /* an attribute through a colour map */
    PARTICLE_COLOUR_RGB,      /* the attributes red, green, blue: sRGB code values 0..255 (a scanner's) */
} particle_colouring;

typedef struct particle_kind_options {
    float radius;                  /* every particle's radius (> 0), when radius_attribute is NULL */
    const char *radius_attribute;  /* per-particle radius from this attribute (values > 0), or NULL */
    const char *crop_attribute;    /* the attribute a crop range applies to, or NULL: no crop */
    geometry_crop crop;            /* the range at start (active or not) */
    uint32_t material_id;          /* scene material of every particle */
    particle_colouring colouring;
    const char *colour_attribute;  /* PARTICLE_COLOUR_MAP: the attribute coloured */
    const colormap *map;           /* PARTICLE_COLOUR_MAP: the map (an automatic range is fitted to the
                                      attribute's values); NULL: viridis */
} particle_kind_options;

/* The radius a set gets when nothing says: 0.001 x the diagonal of its
 * centres' box (what the Embree peer gives a point set), 1 for a set
 * without extent. */
float particle_kind_default_radius(const particle_set *set);

/* A kind over `set` (taken: owned from now on, also on failure). `source`
 * names the set in messages ("particles[0]: radius attribute 'r' ..."). */
particle_kind *particle_kind_create(particle_set *set, const particle_kind_options *opt, const char *source,
                                    tess_error *err);
void particle_kind_destroy(particle_kind *k); /* NULL is fine; what ops.destroy calls */

const particle_set *particle_kind_set(const particle_kind *k);
/* The crop now (the attribute's min and max bound any range worth giving). */
geometry_crop particle_kind_crop(const particle_kind *k);
/* The crop attribute's index in the set, or -1 without one. */
int particle_kind_crop_attribute(const particle_kind *k);
/* Change the crop range: only while nothing traces (a serial section). A
 * kind without a crop attribute ignores it. */
void particle_kind_set_crop(particle_kind *k, geometry_crop crop);

/* Colour by the built-in map `name` (colormap.h) over the same range: only
 * where nothing traces. False when the kind does not colour by a map or no
 * built-in has that name. */
bool particle_kind_set_colormap(particle_kind *k, const char *name);

/* The colour map in use (PARTICLE_COLOUR_MAP), its range fitted; NULL otherwise. */
const colormap *particle_kind_colormap(const particle_kind *k);

/* TIME STEPS. A kind may show a series of particle files, one step at a
 * time: it shows step 0 (the set it was made with, loaded from paths[0])
 * until particle_kind_set_step swaps another in. A loader thread loads the
 * step asked for next and builds its tree while frames render, so at most
 * two steps are in memory; setting a step that is ready swaps at once,
 * one that is not waits for its load. Every step must have the attributes
 * the kind reads (radius, crop, colour); a colour map keeps step 0's range.
 * attach: paths copied, each step read by `read` (the kind does not know
 * file formats: engine/load/particle_load.h's particles_load is one); false
 * on no memory. */
typedef particle_set *particle_file_reader(const char *path, tess_error *err);
bool particle_kind_attach_series(particle_kind *k, const char *const *paths, uint32_t count, particle_file_reader *read,
                                 tess_error *err);
uint32_t particle_kind_step_count(const particle_kind *k); /* 1 without a series */
uint32_t particle_kind_step(const particle_kind *k);       /* the step shown */
/* Whether `step` (mod the count) can be shown without waiting: it is shown
 * or loaded. When not, the loader is asked for it (prefetch). Any thread. */
bool particle_kind_step_ready(particle_kind *k, uint32_t step);
/* Show `step` (mod the count): only where nothing traces (a serial section;
 * an accel's copy of the tree must follow: accel_set_time_step). False,
 * with the file's error, when its file cannot be loaded (the step shown
 * stays). */
bool particle_kind_set_step(particle_kind *k, uint32_t step, tess_error *err);

/* The kind's ops; data is a particle_kind. */
extern const geometry_ops particle_kind_ops;

#endif
