#include "mesh_cache.h"

#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "engine/accel/bvh.h"
#include "engine/accel/bvh_spatial.h"
#include "engine/base/clock.h"
#include "engine/base/log.h"
#include "engine/accel/wbvh.h"

/* What the sections hold and how: bump on any change of the mesh or node
 * layout, of the tree builder's result or of the ordering (mesh_tree.c). */
#define MESH_CACHE_CONTENT_VERSION 2u /* 2: spatial splits' repeated triangles and "canon" */

#define MESH_CACHE_MIN_BYTES_DEFAULT (16ull << 20)

/* The "meta" section: the counts and what the arrays hold. */
typedef struct mesh_cache_meta {
    uint32_t vertex_count, triangle_count, material_count, node_count;
    uint32_t has_normals, has_colors, has_triangle_material;
    uint32_t duplicate_count; /* mesh.h: nonzero iff a "canon" section holds triangle_count ids */
    float coord_abs_max;
    uint32_t reserved2[7];
} mesh_cache_meta;

/* The key's build parameters beyond the caller's: what the tree depends on. */
typedef struct key_params {
    mesh_cache_params caller;
    uint32_t leaf_max, width, node_bytes, max_depth;
    uint32_t spatial_bins, spatial_growth_percent; /* 0 without spatial splits */
} key_params;

uint64_t mesh_cache_min_bytes(void)
{
    const char *v = getenv("TESSERA_CACHE_MIN_BYTES");
    if (v && *v) {
        char *end;
        errno = 0;
        unsigned long long n = strtoull(v, &end, 10);
        if (!errno && !*end)
            return n;
        log_warn("TESSERA_CACHE_MIN_BYTES=%s is not a byte count; using %llu", v, MESH_CACHE_MIN_BYTES_DEFAULT);
    }
    return MESH_CACHE_MIN_BYTES_DEFAULT;
}

static bool key_of(const char *path, const mesh_cache_params *params, cache_key *key, tess_error *err)
{
    key_params kp;
    memset(&kp, 0, sizeof kp);
    kp.caller = *params;
    kp.leaf_max = BVH_LEAF_DEFAULT;
    kp.width = WBVH_WIDTH;
    kp.node_bytes = (uint32_t)sizeof(wbvh_node);
    kp.max_depth = BVH_MAX_DEPTH;
    if (params->spatial_splits) /* the builder's own limits decide the references */
        kp.spatial_bins = BVH_SPATIAL_BINS, kp.spatial_growth_percent = (uint32_t)(BVH_SPATIAL_GROWTH * 100.0 + 0.5);
    return cache_hash_file(path, &kp, sizeof kp, key, err);
}

static void release_mapping(void *owner) { cache_close(owner); }

/* The section `tag` of exactly `count` elements; NULL (err set) otherwise. */
static const void *section(const cache_file *c, const char *tag, size_t element_bytes, size_t count, tess_error *err)
{
    size_t got;
    const void *p = cache_section(c, tag, element_bytes, &got, err);
    if (p && got != count) {
        tess_error_set(err, "section '%s' holds %zu elements, its meta says %zu", tag, got, count);
        return NULL;
    }
    return p;
}

/* The mesh and tree of an opened cache, in place; NULL (err set) when its
 * sections do not fit together (a writer's bug: the checksums held). */
static mesh *mesh_from_cache(cache_file *c, wbvh **tree_out, tess_error *err)
{
    size_t n;
    const mesh_cache_meta *meta = cache_section(c, "meta", sizeof *meta, &n, err);
    if (!meta || n != 1) {
        if (meta)
            tess_error_set(err, "section 'meta' holds %zu elements", n);
        return NULL;
    }
    mesh *m = calloc(1, sizeof *m);
    wbvh *tree = calloc(1, sizeof *tree);
    if (!m || !tree) {
        free(m);
        free(tree);
        tess_error_set(err, "out of memory");
        return NULL;
    }
    m->vertex_count = m->vertex_capacity = meta->vertex_count;
    m->triangle_count = m->triangle_capacity = meta->triangle_count;
    m->material_count = meta->material_count;
    size_t nv3 = 3 * (size_t)meta->vertex_count, nt3 = 3 * (size_t)meta->triangle_count;
    bool ok = (m->positions = (float *)section(c, "positions", sizeof(float), nv3, err)) &&
              (m->indices = (uint32_t *)section(c, "indices", sizeof(uint32_t), nt3, err)) &&
              (!meta->has_normals || (m->normals = (float *)section(c, "normals", sizeof(float), nv3, err))) &&
              (!meta->has_colors || (m->colors = (float *)section(c, "colors", sizeof(float), nv3, err))) &&
              (!meta->has_triangle_material ||
               (m->triangle_material = (uint32_t *)section(c, "tri_material", sizeof(uint32_t),
                                                           meta->triangle_count, err))) &&
              (!meta->material_count ||
               (m->materials = (mesh_material *)section(c, "materials", sizeof(mesh_material),
                                                        meta->material_count, err))) &&
              (!meta->duplicate_count ||
               (m->canon = (uint32_t *)section(c, "canon", sizeof(uint32_t), meta->triangle_count, err))) &&
              (tree->nodes = (wbvh_node *)section(c, "nodes", sizeof(wbvh_node), meta->node_count, err));
    if (!ok) {
        free(m);
        free(tree);
        return NULL;
    }
    tree->kind = WBVH_MESH;
    tree->node_count = meta->node_count;
    tree->coord_abs_max = meta->coord_abs_max;
    m->duplicate_count = meta->duplicate_count;
    tree->mesh = (geometry_mesh_arrays){m->positions, m->indices, m->canon};
    tree->ops = &geometry_triangles_ops;
    tree->borrowed = true; /* the nodes are the mapping's */
    m->owner = c;
    m->release = release_mapping;
    *tree_out = tree;
    return m;
}

mesh *mesh_cache_load_file(const char *path, const mesh_cache_params *params, mesh_file_reader *read,
                           mesh_cache_load *out, tess_error *err)
{
    memset(out, 0, sizeof *out);
    struct stat st;
    if (!cache_enabled() || stat(path, &st) != 0 || (uint64_t)st.st_size < mesh_cache_min_bytes())
        return read(path, err);
    tess_error why = {{0}};
    char cache_path[CACHE_PATH_BYTES];
    if (!key_of(path, params, &out->key, &why) || !cache_path_for_key(out->key, cache_path, sizeof cache_path, &why)) {
        log_warn("%s: no structure cache: %s", path, why.msg);
        return read(path, err);
    }
    cache_file *c = NULL;
    cache_status status = cache_open(cache_path, out->key, MESH_CACHE_CONTENT_VERSION, &c, &why);
    if (status == CACHE_OK) {
        mesh *m = mesh_from_cache(c, &out->tree, &why);
        if (m) {
            out->state = MESH_CACHE_HIT;
            log_info("%s: mesh and tree mapped from the cache %s (%u triangles)", path, cache_path,
                     m->triangle_count);
            return m;
        }
        cache_close(c);
        log_warn("cache %s: unusable (%s) - rebuilding", cache_path, why.msg);
    } else if (status != CACHE_MISSING) {
        log_warn("%s - rebuilding", why.msg);
    }
    mesh *m = read(path, err);
    if (m)
        out->state = MESH_CACHE_PENDING;
    return m;
}

void mesh_cache_adopt(scene_mesh *sm, mesh_cache_load *load)
{
    sm->cache_state = (int)load->state;
    sm->cache_key[0] = load->key.lo;
    sm->cache_key[1] = load->key.hi;
    if (load->state == MESH_CACHE_HIT) {
        load->tree->data = sm;
        atomic_store_explicit(&sm->tree, load->tree, memory_order_release);
    }
    load->tree = NULL;
}

void mesh_cache_abandon(mesh_cache_load *load)
{
    free(load->tree); /* borrowed nodes: the mesh's mapping holds them */
    load->tree = NULL;
}

void mesh_cache_store(scene_mesh *sm, const wbvh *tree)
{
    if (sm->cache_state != MESH_CACHE_PENDING)
        return;
    const mesh *m = sm->mesh;
    cache_key key = {sm->cache_key[0], sm->cache_key[1]};
    char path[CACHE_PATH_BYTES];
    tess_error why = {{0}};
    mesh_cache_meta meta;
    memset(&meta, 0, sizeof meta);
    meta.vertex_count = m->vertex_count;
    meta.triangle_count = m->triangle_count;
    meta.material_count = m->materials ? m->material_count : 0;
    meta.node_count = tree->node_count;
    meta.has_normals = m->normals != NULL;
    meta.has_colors = m->colors != NULL;
    meta.has_triangle_material = m->triangle_material != NULL;
    meta.duplicate_count = m->canon ? m->duplicate_count : 0;
    meta.coord_abs_max = tree->coord_abs_max;
    size_t nv3 = 3 * (size_t)m->vertex_count, nt3 = 3 * (size_t)m->triangle_count;
    cache_section_source secs[9];
    size_t n = 0;
    secs[n++] = (cache_section_source){"meta", &meta, sizeof meta, 1};
    secs[n++] = (cache_section_source){"positions", m->positions, sizeof(float), nv3};
    secs[n++] = (cache_section_source){"indices", m->indices, sizeof(uint32_t), nt3};
    if (m->normals)
        secs[n++] = (cache_section_source){"normals", m->normals, sizeof(float), nv3};
    if (m->colors)
        secs[n++] = (cache_section_source){"colors", m->colors, sizeof(float), nv3};
    if (m->triangle_material)
        secs[n++] = (cache_section_source){"tri_material", m->triangle_material, sizeof(uint32_t), m->triangle_count};
    if (meta.material_count)
        secs[n++] = (cache_section_source){"materials", m->materials, sizeof(mesh_material), meta.material_count};
    if (meta.duplicate_count)
        secs[n++] = (cache_section_source){"canon", m->canon, sizeof(uint32_t), m->triangle_count};
    secs[n++] = (cache_section_source){"nodes", tree->nodes, sizeof(wbvh_node), tree->node_count};
    double start = clock_monotonic_s();
    if (cache_path_for_key(key, path, sizeof path, &why) &&
        cache_write(path, key, MESH_CACHE_CONTENT_VERSION, secs, n, &why)) {
        sm->cache_state = MESH_CACHE_WRITTEN;
        log_info("mesh '%s': structure cache written to %s in %.2f s", sm->name, path, clock_monotonic_s() - start);
    } else {
        sm->cache_state = MESH_CACHE_FAILED;
        log_warn("mesh '%s': %s (the next start builds again)", sm->name, why.msg);
    }
}
