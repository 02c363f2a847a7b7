/* fuzz_particles.c - particle files (engine/load/particle_load.c): PLY
 * point sets and LAMMPS text dumps. The input is the file, handed over as a
 * memfd (the readers want a regular file); its path has no extension, so
 * particles_load chooses by the first line, and each loader is also run on
 * the input directly (a PLY header that is no dump and a dump that is no PLY
 * are both worth reaching). */
#include "fuzz.h"

#include <math.h>
#include <string.h>

#include "engine/geometry/particles/particles.h"
#include "engine/load/particle_load.h"

/* What a loaded set promises (particles.h): counts within capacity, finite
 * positions and values, each attribute's min and max bounding its values,
 * names terminated and distinct. Every array element is read, so the
 * sanitizer sees an array shorter than its count. */
static void check_set(const particle_set *p, const char *name)
{
    if (p->count > p->capacity || p->attribute_count > PARTICLE_MAX_ATTRIBUTES)
        fuzz_fail("%s: count %u, capacity %u, %u attributes", name, p->count, p->capacity, p->attribute_count);
    if (p->timestep < -1)
        fuzz_fail("%s: time step %lld", name, (long long)p->timestep);
    for (uint32_t i = 0; i < p->count; i++)
        if (!isfinite(p->x[i]) || !isfinite(p->y[i]) || !isfinite(p->z[i]))
            fuzz_fail("%s: particle %u: position not finite", name, i);
    for (uint32_t a = 0; a < p->attribute_count; a++) {
        const particle_attribute *at = &p->attributes[a];
        if (!memchr(at->name, '\0', sizeof at->name) || at->name[0] == '\0')
            fuzz_fail("%s: attribute %u: name empty or not terminated", name, a);
        if (particle_set_find_attribute(p, at->name) != (int)a)
            fuzz_fail("%s: attribute '%s' named twice", name, at->name);
        for (uint32_t i = 0; i < p->count; i++)
            if (!(at->values[i] >= at->min && at->values[i] <= at->max))
                fuzz_fail("%s: particle %u: %s = %g outside [%g, %g]", name, i, at->name, (double)at->values[i],
                          (double)at->min, (double)at->max);
    }
}

static void run(particle_set *(*load)(const char *, tess_error *), const char *path)
{
    tess_error err = {{0}};
    particle_set *p = load(path, &err);
    if (p)
        check_set(p, path);
    else
        fuzz_check_error(&err, path);
    particle_set_destroy(p);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_memfd(data, size);
    run(particles_load, path);
    run(particles_load_ply, path);
    run(particles_load_lammps, path);
    return 0;
}
