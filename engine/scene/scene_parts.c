/* scene_parts.c - the queries on a scene's parts (scene.h): a part's
 * instance range, colours by path pattern. The parts themselves come from an
 * assembly (engine/load/scene_assembly.c). */
#include <stdint.h>

#include "part_tree.h"
#include "scene.h"

static uint32_t parted_below(const scene *s, uint32_t part)
{
    uint32_t lo = 0, hi = s->parted_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->instances[s->parted[mid]].part < part)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

void scene_part_instances(const scene *s, uint32_t part, uint32_t *first, uint32_t *end)
{
    *first = *end = 0;
    if (!s->parts || part >= (uint32_t)part_tree_count(s->parts))
        return;
    uint32_t subtree_end = (uint32_t)part_tree_subtree_end(s->parts, (int32_t)part);
    uint32_t lo = parted_below(s, part), hi = parted_below(s, subtree_end);
    if (lo < hi) { /* one id range: an assembly's instances are added together */
        *first = s->parted[lo];
        *end = s->parted[hi - 1] + 1;
    }
}

typedef struct colour_job {
    scene *s;
    uint32_t material_id;
} colour_job;

static bool colour_part(void *ctx, int32_t id, const char *path)
{
    (void)path;
    colour_job *job = ctx;
    uint32_t first, end;
    scene_part_instances(job->s, (uint32_t)id, &first, &end);
    for (uint32_t i = first; i < end; i++)
        job->s->instances[i].material = job->material_id;
    return true;
}

long scene_colour_parts(scene *s, const char *pattern, uint32_t material_id)
{
    if (!s->parts || material_id >= s->material_count)
        return 0;
    colour_job job = {s, material_id};
    return part_tree_match(s->parts, pattern, colour_part, &job);
}
