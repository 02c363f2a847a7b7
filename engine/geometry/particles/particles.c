/* particles.c - the particle set's arrays (particles.h). */
#include "particles.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

particle_set *particle_set_create(void)
{
    particle_set *p = calloc(1, sizeof *p);
    if (p)
        p->timestep = -1;
    return p;
}

void particle_set_destroy(particle_set *p)
{
    if (!p)
        return;
    free(p->x);
    free(p->y);
    free(p->z);
    for (uint32_t a = 0; a < p->attribute_count; a++)
        free(p->attributes[a].values);
    free(p);
}

/* realloc *arr to n floats, zeroing the new tail beyond `keep` */
static bool grow_floats(float **arr, uint32_t keep, uint32_t n)
{
    float *grown = realloc(*arr, (size_t)n * sizeof *grown);
    if (!grown)
        return false;
    memset(grown + keep, 0, (size_t)(n - keep) * sizeof *grown);
    *arr = grown;
    return true;
}

bool particle_set_reserve(particle_set *p, uint32_t n)
{
    if (n > PARTICLE_MAX_COUNT)
        return false;
    if (n <= p->capacity)
        return true;
    if (!grow_floats(&p->x, p->count, n) || !grow_floats(&p->y, p->count, n) || !grow_floats(&p->z, p->count, n))
        return false;
    for (uint32_t a = 0; a < p->attribute_count; a++)
        if (!grow_floats(&p->attributes[a].values, p->count, n))
            return false;
    p->capacity = n;
    return true;
}

bool particle_set_fit(particle_set *p, uint32_t spare)
{
    if (spare > PARTICLE_MAX_COUNT - p->count)
        return false;
    uint32_t n = p->count + spare;
    if (n == p->capacity)
        return true;
    if (n > p->capacity)
        return particle_set_reserve(p, n);
    /* shrinking: realloc to fewer bytes keeps the data; a failure leaves the old block */
    float **arrays[3 + PARTICLE_MAX_ATTRIBUTES] = {&p->x, &p->y, &p->z};
    uint32_t count = 3;
    for (uint32_t a = 0; a < p->attribute_count; a++)
        arrays[count++] = &p->attributes[a].values;
    for (uint32_t i = 0; i < count; i++) {
        float *smaller = realloc(*arrays[i], (size_t)n * sizeof *smaller);
        if (smaller)
            *arrays[i] = smaller;
        memset(*arrays[i] + p->count, 0, (size_t)spare * sizeof **arrays[i]);
    }
    p->capacity = n;
    return true;
}

int particle_set_find_attribute(const particle_set *p, const char *name)
{
    for (uint32_t a = 0; a < p->attribute_count; a++)
        if (strcmp(p->attributes[a].name, name) == 0)
            return (int)a;
    return -1;
}

int particle_set_add_attribute(particle_set *p, const char *name)
{
    size_t len = strlen(name);
    if (len == 0 || len >= PARTICLE_NAME_BYTES || p->attribute_count >= PARTICLE_MAX_ATTRIBUTES ||
        particle_set_find_attribute(p, name) >= 0)
        return -1;
    particle_attribute *a = &p->attributes[p->attribute_count];
    memset(a, 0, sizeof *a);
    if (p->capacity > 0) {
        a->values = calloc(p->capacity, sizeof *a->values);
        if (!a->values)
            return -1;
    }
    memcpy(a->name, name, len + 1);
    return (int)p->attribute_count++;
}

bool particle_set_add(particle_set *p, float x, float y, float z, const float *attribute_values)
{
    if (p->count == p->capacity) {
        if (p->count >= PARTICLE_MAX_COUNT)
            return false;
        uint64_t want = p->capacity < 1024 ? 1024 : (uint64_t)p->capacity * 2;
        if (want > PARTICLE_MAX_COUNT)
            want = PARTICLE_MAX_COUNT;
        if (!particle_set_reserve(p, (uint32_t)want))
            return false;
    }
    uint32_t i = p->count++;
    p->x[i] = x, p->y[i] = y, p->z[i] = z;
    for (uint32_t a = 0; a < p->attribute_count; a++)
        p->attributes[a].values[i] = attribute_values ? attribute_values[a] : 0.f;
    return true;
}

bool particle_set_finish(particle_set *p, const char *source, tess_error *err)
{
    for (uint32_t i = 0; i < p->count; i++)
        if (!isfinite(p->x[i]) || !isfinite(p->y[i]) || !isfinite(p->z[i]))
            return tess_error_set(err, "%s: particle %u: position is not finite", source, i);
    for (uint32_t a = 0; a < p->attribute_count; a++) {
        particle_attribute *at = &p->attributes[a];
        float lo = INFINITY, hi = -INFINITY;
        for (uint32_t i = 0; i < p->count; i++) {
            float v = at->values[i];
            if (!isfinite(v))
                return tess_error_set(err, "%s: particle %u: attribute '%s' is not finite", source, i, at->name);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        at->min = p->count ? lo : 0.f;
        at->max = p->count ? hi : 0.f;
    }
    return true;
}

static bool permute_floats(float *arr, const uint32_t *order, uint32_t n, float *scratch)
{
    for (uint32_t i = 0; i < n; i++)
        scratch[i] = arr[order[i]];
    memcpy(arr, scratch, (size_t)n * sizeof *arr);
    return true;
}

bool particle_set_permute(particle_set *p, const uint32_t *order)
{
    if (p->count == 0)
        return true;
    float *scratch = malloc((size_t)p->count * sizeof *scratch);
    if (!scratch)
        return false;
    permute_floats(p->x, order, p->count, scratch);
    permute_floats(p->y, order, p->count, scratch);
    permute_floats(p->z, order, p->count, scratch);
    for (uint32_t a = 0; a < p->attribute_count; a++)
        permute_floats(p->attributes[a].values, order, p->count, scratch);
    free(scratch);
    return true;
}

size_t particle_set_bytes(const particle_set *p)
{
    return (size_t)p->count * sizeof(float) * (3u + p->attribute_count);
}

bool particle_set_bounds(const particle_set *p, float lo[3], float hi[3])
{
    if (p->count == 0)
        return false;
    lo[0] = hi[0] = p->x[0];
    lo[1] = hi[1] = p->y[0];
    lo[2] = hi[2] = p->z[0];
    for (uint32_t i = 1; i < p->count; i++) {
        lo[0] = fminf(lo[0], p->x[i]), hi[0] = fmaxf(hi[0], p->x[i]);
        lo[1] = fminf(lo[1], p->y[i]), hi[1] = fmaxf(hi[1], p->y[i]);
        lo[2] = fminf(lo[2], p->z[i]), hi[2] = fmaxf(hi[2], p->z[i]);
    }
    return true;
}
