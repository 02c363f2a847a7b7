/* mesh.c - the growing triangle mesh (mesh.h). */
#include "mesh.h"

#include <stdlib.h>
#include <string.h>

void ga_mesh_init(struct ga_mesh *mesh) { memset(mesh, 0, sizeof *mesh); }

void ga_mesh_finish(struct ga_mesh *mesh)
{
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->indices);
    memset(mesh, 0, sizeof *mesh);
}

/* Grow *array (elem_bytes each, *cap of them) to hold at least `need`. */
static bool grow(void **array, size_t *cap, size_t need, size_t elem_bytes)
{
    if (need <= *cap)
        return true;
    size_t cap_new = *cap ? *cap : 256;
    while (cap_new < need)
        cap_new *= 2;
    void *p = realloc(*array, cap_new * elem_bytes);
    if (!p)
        return false;
    *array = p;
    *cap = cap_new;
    return true;
}

uint32_t ga_mesh_vertex(struct ga_mesh *mesh, struct ga_v3 position, struct ga_v3 normal)
{
    if (mesh->failed)
        return 0;
    if (mesh->vertex_count >= UINT32_MAX) {
        mesh->failed = true;
        return 0;
    }
    size_t cap = mesh->vertex_cap;
    if (!grow((void **)&mesh->positions, &cap, mesh->vertex_count + 1, 3 * sizeof(float))) {
        mesh->failed = true;
        return 0;
    }
    cap = mesh->vertex_cap;
    if (!grow((void **)&mesh->normals, &cap, mesh->vertex_count + 1, 3 * sizeof(float))) {
        mesh->failed = true;
        return 0;
    }
    mesh->vertex_cap = cap;
    struct ga_v3 n = ga_v3_normalize(normal);
    float *p = mesh->positions + 3 * mesh->vertex_count;
    float *q = mesh->normals + 3 * mesh->vertex_count;
    p[0] = (float)position.x;
    p[1] = (float)position.y;
    p[2] = (float)position.z;
    q[0] = (float)n.x;
    q[1] = (float)n.y;
    q[2] = (float)n.z;
    return (uint32_t)mesh->vertex_count++;
}

void ga_mesh_triangle(struct ga_mesh *mesh, uint32_t a, uint32_t b, uint32_t c)
{
    if (mesh->failed)
        return;
    if (!grow((void **)&mesh->indices, &mesh->index_cap, mesh->index_count + 3, sizeof(uint32_t))) {
        mesh->failed = true;
        return;
    }
    uint32_t *t = mesh->indices + mesh->index_count;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    mesh->index_count += 3;
}

static struct ga_v3 stored_position(const struct ga_mesh *mesh, uint32_t i)
{
    const float *p = mesh->positions + 3 * (size_t)i;
    return ga_v3_make(p[0], p[1], p[2]);
}

void ga_mesh_triangle_facing(struct ga_mesh *mesh, uint32_t a, uint32_t b, uint32_t c, struct ga_v3 want)
{
    if (mesh->failed)
        return;
    struct ga_v3 pa = stored_position(mesh, a);
    struct ga_v3 n = ga_v3_cross(ga_v3_sub(stored_position(mesh, b), pa), ga_v3_sub(stored_position(mesh, c), pa));
    if (ga_v3_dot(n, want) >= 0.0)
        ga_mesh_triangle(mesh, a, b, c);
    else
        ga_mesh_triangle(mesh, a, c, b);
}
