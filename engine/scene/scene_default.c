/* scene_default.c - the built-in scene: needs no data file, so `make run` and
 * the tests work anywhere. A grey ground quad, a tessellated torus (with vertex
 * normals, Phong), a ring of seven spheres, a directional and a point light. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene.h"

/* Torus tessellation: enough segments that the silhouette looks round at 1080p. */
#define TORUS_MAJOR_SEGMENTS 96
#define TORUS_MINOR_SEGMENTS 48
#define TORUS_MAJOR_RADIUS 1.0f
#define TORUS_MINOR_RADIUS 0.35f
#define RING_SPHERES 7
#define GROUND_HALF_EXTENT 8.f

static const float pi = 3.14159265358979323846f;

static mesh *make_ground(void)
{
    mesh *m = mesh_create();
    if (!m)
        return NULL;
    const float e = GROUND_HALF_EXTENT;
    bool ok = mesh_add_vertex(m, -e, 0.f, -e) && mesh_add_vertex(m, e, 0.f, -e) && mesh_add_vertex(m, e, 0.f, e) &&
              mesh_add_vertex(m, -e, 0.f, e) && mesh_add_triangle(m, 0, 2, 1) && mesh_add_triangle(m, 0, 3, 2);
    if (!ok) {
        mesh_destroy(m);
        return NULL;
    }
    return m;
}

/* A torus around the Y axis, centred at (0, height, 0), tilted by `tilt` radians about X. */
static mesh *make_torus(float height, float tilt)
{
    mesh *m = mesh_create();
    const uint32_t nu = TORUS_MAJOR_SEGMENTS, nv = TORUS_MINOR_SEGMENTS;
    if (!m || !mesh_reserve_vertices(m, nu * nv) || !mesh_reserve_triangles(m, 2 * nu * nv) ||
        !mesh_enable_normals(m)) {
        mesh_destroy(m);
        return NULL;
    }
    float ct = cosf(tilt), st = sinf(tilt);
    for (uint32_t i = 0; i < nu; i++) {
        float a = 2.f * pi * (float)i / (float)nu;
        for (uint32_t j = 0; j < nv; j++) {
            float b = 2.f * pi * (float)j / (float)nv;
            vec3 n = v3(cosf(a) * cosf(b), sinf(b), sinf(a) * cosf(b));
            vec3 p = v3(TORUS_MAJOR_RADIUS * cosf(a) + TORUS_MINOR_RADIUS * n.x, TORUS_MINOR_RADIUS * n.y,
                        TORUS_MAJOR_RADIUS * sinf(a) + TORUS_MINOR_RADIUS * n.z);
            /* tilt about X, then lift */
            vec3 pt = v3(p.x, ct * p.y - st * p.z + height, st * p.y + ct * p.z);
            vec3 nt = v3(n.x, ct * n.y - st * n.z, st * n.y + ct * n.z);
            uint32_t k = m->vertex_count;
            mesh_add_vertex(m, pt.x, pt.y, pt.z); /* cannot fail: reserved */
            m->normals[3 * k + 0] = nt.x;
            m->normals[3 * k + 1] = nt.y;
            m->normals[3 * k + 2] = nt.z;
        }
    }
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j;
            uint32_t c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
            mesh_add_triangle(m, a, d, c);
            mesh_add_triangle(m, a, c, b);
        }
    return m;
}

static material make_material(const char *name, material_model model, vec3 diffuse, vec3 specular, float shininess)
{
    material m = material_default();
    snprintf(m.name, sizeof m.name, "%s", name);
    m.model = model;
    m.diffuse = diffuse;
    m.specular = specular;
    m.shininess = shininess;
    return m;
}

scene *scene_create_default(tess_error *err)
{
    scene *s = scene_create();
    if (!s)
        goto oom;
    s->background = v3(0.05f, 0.06f, 0.09f);
    s->ambient = v3(0.08f, 0.08f, 0.1f);

    material ground = make_material("ground", MATERIAL_LAMBERT, v3(0.6f, 0.6f, 0.55f), v3(0.f, 0.f, 0.f), 0.f);
    material torus = make_material("torus", MATERIAL_PHONG, v3(0.7f, 0.12f, 0.08f), v3(0.5f, 0.5f, 0.5f), 48.f);
    int ground_id = scene_add_material(s, &ground), torus_id = scene_add_material(s, &torus);
    if (ground_id < 0 || torus_id < 0)
        goto oom;
    mesh *g = make_ground();
    if (!g || scene_add_mesh(s, g, (uint32_t)ground_id, "ground") < 0)
        goto oom;
    mesh *t = make_torus(0.9f, 0.5f);
    if (!t || scene_add_mesh(s, t, (uint32_t)torus_id, "torus") < 0)
        goto oom;

    for (int i = 0; i < RING_SPHERES; i++) {
        float a = 2.f * pi * (float)i / RING_SPHERES;
        float hue = (float)i / RING_SPHERES;
        vec3 colour = v3(0.5f + 0.45f * cosf(2.f * pi * hue), 0.5f + 0.45f * cosf(2.f * pi * (hue - 1.f / 3.f)),
                         0.5f + 0.45f * cosf(2.f * pi * (hue - 2.f / 3.f)));
        char name[SCENE_NAME_BYTES];
        snprintf(name, sizeof name, "sphere%d", i);
        material sm = make_material(name, MATERIAL_PHONG, colour, v3(0.6f, 0.6f, 0.6f), 64.f);
        int id = scene_add_material(s, &sm);
        float radius = 0.3f + 0.05f * (float)(i % 3);
        if (id < 0 || scene_add_sphere(s, v3(2.6f * cosf(a), radius, 2.6f * sinf(a)), radius, (uint32_t)id) < 0)
            goto oom;
    }

    light sun = light_default_directional();
    sun.intensity = 0.9f;
    light lamp = {.kind = LIGHT_POINT, .position = v3(-2.5f, 4.f, 3.f), .color = v3(1.f, 0.85f, 0.6f),
                  .intensity = 12.f, .casts_shadows = true};
    if (scene_add_light(s, &sun) < 0 || scene_add_light(s, &lamp) < 0)
        goto oom;

    s->has_camera = true;
    s->camera = (camera_desc){.eye = v3(4.5f, 3.2f, 6.5f), .look_at = v3(0.f, 0.6f, 0.f), .up = v3(0.f, 1.f, 0.f),
                              .fov_deg = 40.f};
    return s;
oom:
    scene_destroy(s);
    tess_error_set(err, "default scene: out of memory");
    return NULL;
}
