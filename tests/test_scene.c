/* test_scene.c - the scene container, scene_load and JSON scene files.
 *
 * Every test writes its inputs into its own mkdtemp directory under /tmp and
 * removes it afterwards. The example scenes are read from ../configs/scenes
 * (the suite runs in tests/). */
#include <criterion/criterion.h>

#include <dirent.h>
#include <stdarg.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "engine/scene/part_tree.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"

#define EXAMPLE_SCENES_DIR "../configs/scenes"

/* ---- temporary directory ----------------------------------------------- */

static char tmp_dir[64]; /* per test (Criterion runs each test in its own process) */

static void make_tmp_dir(void)
{
    snprintf(tmp_dir, sizeof tmp_dir, "/tmp/tessera_test_scene_XXXXXX");
    cr_assert_not_null(mkdtemp(tmp_dir), "mkdtemp: %s", strerror(errno));
}

static void remove_tree(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return;
    if (S_ISDIR(st.st_mode)) {
        DIR *d = opendir(path);
        struct dirent *e;
        while (d && (e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            char child[512];
            snprintf(child, sizeof child, "%s/%s", path, e->d_name);
            remove_tree(child);
        }
        if (d)
            closedir(d);
        rmdir(path);
    } else {
        unlink(path);
    }
}

static void remove_tmp_dir(void)
{
    if (tmp_dir[0])
        remove_tree(tmp_dir);
}

TestSuite(scene, .init = make_tmp_dir, .fini = remove_tmp_dir);

/* tmp_dir/rel into buf */
static const char *tmp_path(char *buf, size_t size, const char *rel)
{
    snprintf(buf, size, "%s/%s", tmp_dir, rel);
    return buf;
}

/* Write `text` to tmp_dir/rel (its directory must exist). */
static void put_file(const char *rel, const char *text)
{
    char path[512];
    FILE *f = fopen(tmp_path(path, sizeof path, rel), "wb");
    cr_assert_not_null(f, "cannot write %s", path);
    fwrite(text, 1, strlen(text), f);
    fclose(f);
}

static void put_dir(const char *rel)
{
    char path[512];
    cr_assert_eq(mkdir(tmp_path(path, sizeof path, rel), 0700), 0);
}

/* ---- shared inputs ----------------------------------------------------- */

/* One triangle with per-vertex normals; vertices in this order. */
static const char tri_ply[] = "ply\n"
                              "format ascii 1.0\n"
                              "element vertex 3\n"
                              "property float x\nproperty float y\nproperty float z\n"
                              "property float nx\nproperty float ny\nproperty float nz\n"
                              "element face 1\n"
                              "property list uchar int vertex_indices\n"
                              "end_header\n"
                              "1 2 3 1 0 0\n"
                              "-1 0.5 2 0 0.6 0.8\n"
                              "0 0 -1 0 0 1\n"
                              "3 0 1 2\n";
static const float tri_pos[3][3] = {{1, 2, 3}, {-1, 0.5f, 2}, {0, 0, -1}};
static const float tri_nrm[3][3] = {{1, 0, 0}, {0, 0.6f, 0.8f}, {0, 0, 1}};

/* Two quads (four triangles) with MTL materials: "red" at x >= 2, "green" at x <= 1. */
static const char colored_obj[] = "mtllib colored.mtl\n"
                                  "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                  "v 2 0 0\nv 3 0 0\nv 3 1 0\nv 2 1 0\n"
                                  "usemtl green\n"
                                  "f 1 2 3\nf 1 3 4\n"
                                  "usemtl red\n"
                                  "f 5 6 7\nf 5 7 8\n";
static const char colored_mtl[] = "newmtl red\nKd 1 0 0\n\nnewmtl green\nKd 0 0.5 0\n";

/* Write scene.json with `text` and load it. */
static scene *load_text(const char *text, tess_error *err)
{
    char path[512];
    put_file("scene.json", text);
    return scene_load_json(tmp_path(path, sizeof path, "scene.json"), err);
}

/* `text` must fail to load with a message holding the scene path and every
 * NULL-terminated string after it. */
static void expect_failure(const char *text, ...)
{
    char path[512];
    tess_error err = {{0}};
    scene *s = load_text(text, &err);
    cr_assert_null(s, "loaded although it should fail:\n%s", text);
    tmp_path(path, sizeof path, "scene.json");
    cr_assert(strstr(err.msg, path) == err.msg, "message '%s' does not start with the path", err.msg);
    cr_assert(strchr(err.msg, '\n') == NULL, "message '%s' is not one line", err.msg);
    va_list ap;
    va_start(ap, text);
    for (const char *want = va_arg(ap, const char *); want; want = va_arg(ap, const char *))
        cr_assert(strstr(err.msg, want), "message '%s' lacks '%s'", err.msg, want);
    va_end(ap);
}

#define assert_vec3(v, X, Y, Z, eps)                                                                               \
    do {                                                                                                           \
        vec3 v_ = (v);                                                                                             \
        cr_assert(fabsf(v_.x - (X)) <= (eps) && fabsf(v_.y - (Y)) <= (eps) && fabsf(v_.z - (Z)) <= (eps),          \
                  "%s = (%.9g, %.9g, %.9g), expected (%.9g, %.9g, %.9g)", #v, (double)v_.x, (double)v_.y,         \
                  (double)v_.z, (double)(X), (double)(Y), (double)(Z));                                            \
    } while (0)

static vec3 vertex(const mesh *m, uint32_t i)
{
    return v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
}

static vec3 normal_of(const mesh *m, uint32_t i)
{
    return v3(m->normals[3 * i], m->normals[3 * i + 1], m->normals[3 * i + 2]);
}

/* ---- the container ----------------------------------------------------- */

Test(scene, defaults_have_documented_values)
{
    material m = material_default();
    cr_assert_str_eq(m.name, "default");
    cr_assert_eq(m.model, MATERIAL_LAMBERT);
    assert_vec3(m.diffuse, 0.7f, 0.7f, 0.7f, 0.f);
    assert_vec3(m.specular, 0.f, 0.f, 0.f, 0.f);
    cr_assert_eq(m.shininess, 0.f);
    cr_assert_eq(m.ambient, 1.f);

    light l = light_default_directional();
    float n = sqrtf(0.4f * 0.4f + 1.f + 0.3f * 0.3f);
    cr_assert_eq(l.kind, LIGHT_DIRECTIONAL);
    assert_vec3(l.direction, 0.4f / n, 1.f / n, 0.3f / n, 1e-6f);
    assert_vec3(l.color, 1.f, 1.f, 1.f, 0.f);
    cr_assert_eq(l.intensity, 1.f);
    cr_assert(l.casts_shadows);
}

Test(scene, create_destroy_and_growth)
{
    scene_destroy(NULL);
    scene *s = scene_create();
    cr_assert_not_null(s);
    cr_assert_not(s->has_camera);
    vec3 lo, hi;
    cr_assert_not(scene_bounds(s, &lo, &hi), "an empty scene has no bounds");
    cr_assert_eq(scene_triangle_count(s), 0);
    for (int i = 0; i < 1000; i++) {
        material m = material_default();
        light l = light_default_directional();
        cr_assert_eq(scene_add_material(s, &m), i);
        cr_assert_eq(scene_add_light(s, &l), i);
        cr_assert_eq(scene_add_sphere(s, v3((float)i, 0.f, 0.f), 0.5f, (uint32_t)i), i);
    }
    cr_assert_eq(s->material_count, 1000);
    cr_assert_eq(s->light_count, 1000);
    cr_assert_eq(s->spheres.count, 1000);
    cr_assert_eq(s->spheres.center_x[999], 999.f);
    cr_assert_eq(s->spheres.material_id[998], 998u);
    for (int i = 0; i < 20; i++) {
        mesh *m = mesh_create();
        mesh_add_vertex(m, 0, 0, 0);
        mesh_add_vertex(m, 1, 0, 0);
        mesh_add_vertex(m, 0, 1, 0);
        mesh_add_triangle(m, 0, 1, 2);
        cr_assert_eq(scene_add_mesh(s, m, 0, "tri"), i);
    }
    cr_assert_eq(scene_triangle_count(s), 20);
    cr_assert_eq(scene_add_mesh(s, NULL, 0, "none"), -1);
    cr_assert_eq(s->mesh_count, 20);
    cr_assert_str_eq(s->meshes[19]->name, "tri");
    cr_assert_null(s->meshes[19]->mesh_material_ids);
    scene_destroy(s);
}

Test(scene, bounds_include_sphere_radii_and_meshes)
{
    scene *s = scene_create();
    scene_add_sphere(s, v3(0.f, 0.f, 0.f), 2.f, 0);
    scene_add_sphere(s, v3(10.f, -1.f, 0.f), 0.5f, 0);
    vec3 lo, hi;
    cr_assert(scene_bounds(s, &lo, &hi));
    assert_vec3(lo, -2.f, -2.f, -2.f, 0.f);
    assert_vec3(hi, 10.5f, 2.f, 2.f, 0.f);
    mesh *m = mesh_create();
    mesh_add_vertex(m, -5, 0, 0);
    mesh_add_vertex(m, 0, 7, 0);
    mesh_add_vertex(m, 0, 0, 1);
    mesh_add_triangle(m, 0, 1, 2);
    scene_add_mesh(s, m, 0, NULL);
    cr_assert(scene_bounds(s, &lo, &hi));
    assert_vec3(lo, -5.f, -2.f, -2.f, 0.f);
    assert_vec3(hi, 10.5f, 7.f, 2.f, 0.f);
    scene_destroy(s);
}

Test(scene, add_mesh_with_own_materials_adds_scene_materials)
{
    scene *s = scene_create();
    material first = material_default();
    scene_add_material(s, &first);
    mesh *m = mesh_create();
    mesh_add_vertex(m, 0, 0, 0);
    mesh_add_vertex(m, 1, 0, 0);
    mesh_add_vertex(m, 0, 1, 0);
    mesh_add_triangle(m, 0, 1, 2);
    mesh_add_triangle(m, 0, 2, 1);
    cr_assert(mesh_enable_triangle_materials(m));
    m->materials = calloc(2, sizeof *m->materials);
    m->material_count = 2;
    snprintf(m->materials[0].name, sizeof m->materials[0].name, "brick");
    snprintf(m->materials[1].name, sizeof m->materials[1].name, "glass");
    m->materials[1].diffuse_rgb[0] = 0.25f;
    m->materials[1].diffuse_rgb[1] = 0.5f;
    m->materials[1].diffuse_rgb[2] = 0.75f;
    m->triangle_material[1] = 1;
    cr_assert_eq(scene_add_mesh(s, m, 0, "walls"), 0);
    cr_assert_eq(s->material_count, 3);
    const uint32_t *ids = s->meshes[0]->mesh_material_ids;
    cr_assert_not_null(ids);
    cr_assert_eq(ids[0], 1u);
    cr_assert_eq(ids[1], 2u);
    cr_assert_str_eq(s->materials[2].name, "glass");
    cr_assert_eq(s->materials[2].model, MATERIAL_LAMBERT);
    assert_vec3(s->materials[2].diffuse, 0.25f, 0.5f, 0.75f, 0.f);
    cr_assert_eq(s->materials[2].ambient, material_default().ambient);
    scene_destroy(s);
}

/* ---- scene_load on a mesh file ----------------------------------------- */

static void check_bare_mesh_scene(const char *rel, uint32_t triangles)
{
    char path[512];
    tess_error err = {{0}};
    scene *s = scene_load(tmp_path(path, sizeof path, rel), &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->mesh_count, 1);
    cr_assert_eq(s->meshes[0]->mesh->triangle_count, triangles);
    cr_assert_eq(s->spheres.count, 0);
    cr_assert_eq(s->light_count, 1);
    light def = light_default_directional();
    cr_assert_eq(s->lights[0].kind, LIGHT_DIRECTIONAL);
    assert_vec3(s->lights[0].direction, def.direction.x, def.direction.y, def.direction.z, 0.f);
    cr_assert_not(s->has_camera);
    assert_vec3(s->background, 0.02f, 0.02f, 0.03f, 0.f);
    assert_vec3(s->ambient, 0.1f, 0.1f, 0.1f, 0.f);
    uint32_t mid = s->meshes[0]->material_id;
    cr_assert_lt(mid, s->material_count);
    cr_assert_str_eq(s->materials[mid].name, "default");
    scene_destroy(s);
}

Test(scene, load_bare_ply_in_file_coordinates)
{
    put_file("tri.ply", tri_ply);
    check_bare_mesh_scene("tri.ply", 1);
    char path[512];
    tess_error err = {{0}};
    scene *s = scene_load(tmp_path(path, sizeof path, "tri.ply"), &err);
    cr_assert_eq(s->material_count, 1);
    for (uint32_t i = 0; i < 3; i++)
        assert_vec3(vertex(s->meshes[0]->mesh, i), tri_pos[i][0], tri_pos[i][1], tri_pos[i][2], 0.f);
    scene_destroy(s);
}

Test(scene, load_bare_obj)
{
    put_file("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
    check_bare_mesh_scene("quad.obj", 2);
}

Test(scene, load_bare_missing_mesh_fails)
{
    char path[512];
    tess_error err = {{0}};
    cr_assert_null(scene_load(tmp_path(path, sizeof path, "nothing.ply"), &err));
    cr_assert(strstr(err.msg, "nothing.ply"), "%s", err.msg);
}

/* ---- JSON: valid scenes ------------------------------------------------ */

Test(scene, full_scene_loads_exact_values)
{
    put_file("tri.ply", tri_ply);
    scene *s;
    tess_error err = {{0}};
    s = load_text("{\n"
                  "  \"camera\": {\"eye\": [0, 1, 5], \"look_at\": [0, 0.5, 0], \"up\": [0, 0, 1], \"fov_deg\": 35},\n"
                  "  \"background\": [0.25, 0.5, 0.125],\n"
                  "  \"ambient\": [0.0625, 0.03125, 0],\n"
                  "  \"materials\": {\n"
                  "    \"matte\": {\"model\": \"lambert\", \"diffuse\": [0.5, 0.25, 1]},\n"
                  "    \"shiny\": {\"model\": \"phong\", \"diffuse\": [0.1, 0.2, 0.3], \"specular\": [0.5, 0.5, 2],\n"
                  "              \"shininess\": 64, \"ambient\": 0.75}\n"
                  "  },\n"
                  "  \"lights\": [\n"
                  "    {\"type\": \"directional\", \"direction\": [0, 2, 0], \"color\": [1, 0.5, 0.25], \"intensity\": 3,\n"
                  "     \"shadows\": false},\n"
                  "    {\"type\": \"point\", \"position\": [1, 2, 3], \"color\": [0.5, 0.5, 0.5], \"intensity\": 40,\n"
                  "     \"shadows\": true}\n"
                  "  ],\n"
                  "  \"meshes\": [{\"file\": \"tri.ply\", \"material\": \"shiny\", \"transform\": {\"translate\": [1, 0, 0]},\n"
                  "              \"optional\": false}],\n"
                  "  \"spheres\": [{\"center\": [1, 2, 3], \"radius\": 0.5, \"material\": \"matte\"},\n"
                  "              {\"center\": [-1, -2, -3], \"radius\": 2}]\n"
                  "}\n",
                  &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert(s->has_camera);
    assert_vec3(s->camera.eye, 0.f, 1.f, 5.f, 0.f);
    assert_vec3(s->camera.look_at, 0.f, 0.5f, 0.f, 0.f);
    assert_vec3(s->camera.up, 0.f, 0.f, 1.f, 0.f);
    cr_assert_eq(s->camera.fov_deg, 35.f);
    assert_vec3(s->background, 0.25f, 0.5f, 0.125f, 0.f);
    assert_vec3(s->ambient, 0.0625f, 0.03125f, 0.f, 0.f);

    /* the two named materials in file order, then the default for the second sphere */
    cr_assert_eq(s->material_count, 3);
    const material *matte = &s->materials[0], *shiny = &s->materials[1];
    cr_assert_str_eq(matte->name, "matte");
    cr_assert_eq(matte->model, MATERIAL_LAMBERT);
    assert_vec3(matte->diffuse, 0.5f, 0.25f, 1.f, 0.f);
    assert_vec3(matte->specular, 0.f, 0.f, 0.f, 0.f);
    cr_assert_eq(matte->ambient, 1.f);
    cr_assert_str_eq(shiny->name, "shiny");
    cr_assert_eq(shiny->model, MATERIAL_PHONG);
    assert_vec3(shiny->diffuse, 0.1f, 0.2f, 0.3f, 0.f);
    assert_vec3(shiny->specular, 0.5f, 0.5f, 2.f, 0.f);
    cr_assert_eq(shiny->shininess, 64.f);
    cr_assert_eq(shiny->ambient, 0.75f);
    cr_assert_str_eq(s->materials[2].name, "default");

    cr_assert_eq(s->light_count, 2);
    cr_assert_eq(s->lights[0].kind, LIGHT_DIRECTIONAL);
    assert_vec3(s->lights[0].direction, 0.f, 1.f, 0.f, 0.f);
    assert_vec3(s->lights[0].color, 1.f, 0.5f, 0.25f, 0.f);
    cr_assert_eq(s->lights[0].intensity, 3.f);
    cr_assert_not(s->lights[0].casts_shadows);
    cr_assert_eq(s->lights[1].kind, LIGHT_POINT);
    assert_vec3(s->lights[1].position, 1.f, 2.f, 3.f, 0.f);
    assert_vec3(s->lights[1].color, 0.5f, 0.5f, 0.5f, 0.f);
    cr_assert_eq(s->lights[1].intensity, 40.f);
    cr_assert(s->lights[1].casts_shadows);

    cr_assert_eq(s->mesh_count, 1);
    cr_assert_eq(s->meshes[0]->material_id, 1u);
    cr_assert_null(s->meshes[0]->mesh_material_ids);
    cr_assert_str_eq(s->meshes[0]->name, "tri.ply");
    assert_vec3(vertex(s->meshes[0]->mesh, 0), 2.f, 2.f, 3.f, 0.f);

    cr_assert_eq(s->spheres.count, 2);
    cr_assert_eq(s->spheres.center_x[0], 1.f);
    cr_assert_eq(s->spheres.center_y[0], 2.f);
    cr_assert_eq(s->spheres.center_z[0], 3.f);
    cr_assert_eq(s->spheres.radius[0], 0.5f);
    cr_assert_eq(s->spheres.material_id[0], 0u);
    cr_assert_eq(s->spheres.radius[1], 2.f);
    cr_assert_eq(s->spheres.material_id[1], 2u);
    cr_assert_eq(scene_triangle_count(s), 1);
    scene_destroy(s);
}

Test(scene, camera_defaults_for_up_and_fov)
{
    tess_error err = {{0}};
    scene *s = load_text("{\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
                         " \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}",
                         &err);
    cr_assert_not_null(s, "%s", err.msg);
    assert_vec3(s->camera.up, 0.f, 1.f, 0.f, 0.f);
    cr_assert_eq(s->camera.fov_deg, CAMERA_DEFAULT_FOV_DEG);
    assert_vec3(s->background, 0.02f, 0.02f, 0.03f, 0.f);
    assert_vec3(s->ambient, 0.1f, 0.1f, 0.1f, 0.f);
    scene_destroy(s);
}

Test(scene, comments_are_accepted)
{
    tess_error err = {{0}};
    scene *s = load_text("// a scene with comments\n"
                         "/* block\n   comment */ {\n"
                         "  \"spheres\": [ // one sphere\n"
                         "    {\"center\": [0, /* x */ 0, 0], \"radius\": 1} /* after */\n"
                         "  ]\n"
                         "} // trailing comment, no newline at the end",
                         &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->spheres.count, 1);
    scene_destroy(s);
}

Test(scene, no_lights_gives_default_light_and_empty_list_gives_none)
{
    tess_error err = {{0}};
    scene *s = load_text("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}", &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->light_count, 1);
    light def = light_default_directional();
    cr_assert_eq(s->lights[0].kind, def.kind);
    assert_vec3(s->lights[0].direction, def.direction.x, def.direction.y, def.direction.z, 0.f);
    assert_vec3(s->lights[0].color, def.color.x, def.color.y, def.color.z, 0.f);
    cr_assert_eq(s->lights[0].intensity, def.intensity);
    cr_assert_eq(s->lights[0].casts_shadows, def.casts_shadows);
    cr_assert_not(s->has_camera);
    scene_destroy(s);

    s = load_text("{\"lights\": [], \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}", &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->light_count, 0);
    scene_destroy(s);
}

Test(scene, material_named_default_is_the_fallback)
{
    tess_error err = {{0}};
    scene *s = load_text("{\"materials\": {\"default\": {\"diffuse\": [1, 0, 0]}},"
                         " \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}",
                         &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->material_count, 1);
    cr_assert_eq(s->spheres.material_id[0], 0u);
    assert_vec3(s->materials[0].diffuse, 1.f, 0.f, 0.f, 0.f);
    scene_destroy(s);
}

Test(scene, relative_mesh_path_is_resolved_against_the_scene_directory)
{
    put_dir("scenes");
    put_dir("scenes/data");
    put_file("scenes/data/tri.ply", tri_ply);
    put_file("scenes/s.json", "{\"meshes\": [{\"file\": \"data/tri.ply\"}]}");
    char path[512];
    tess_error err = {{0}};
    /* the working directory (tests/) is not the scene's directory */
    scene *s = scene_load(tmp_path(path, sizeof path, "scenes/s.json"), &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->mesh_count, 1);
    cr_assert_eq(s->meshes[0]->mesh->vertex_count, 3);
    scene_destroy(s);

    /* an absolute path is used as it is */
    char text[1024];
    snprintf(text, sizeof text, "{\"meshes\": [{\"file\": \"%s/scenes/data/tri.ply\"}]}", tmp_dir);
    s = load_text(text, &err);
    cr_assert_not_null(s, "%s", err.msg);
    scene_destroy(s);

    /* a scene path without a directory resolves against the working directory */
    cr_assert_eq(chdir(tmp_dir), 0);
    s = scene_load("scenes/s.json", &err);
    cr_assert_not_null(s, "%s", err.msg);
    scene_destroy(s);
    put_file("top.json", "{\"meshes\": [{\"file\": \"scenes/data/tri.ply\"}]}");
    s = scene_load("top.json", &err);
    cr_assert_not_null(s, "%s", err.msg);
    scene_destroy(s);
}

/* Load tri.ply through a scene with `xform` (the JSON members of a mesh entry,
 * after "file") and return its mesh; the scene is left in *out for destroying. */
static const mesh *load_tri_with(const char *xform, scene **out)
{
    char text[1024];
    tess_error err = {{0}};
    put_file("tri.ply", tri_ply);
    snprintf(text, sizeof text, "{\"meshes\": [{\"file\": \"tri.ply\", %s}]}", xform);
    *out = load_text(text, &err);
    cr_assert_not_null(*out, "%s\n%s", text, err.msg);
    cr_assert_eq((*out)->meshes[0]->mesh->vertex_count, 3);
    return (*out)->meshes[0]->mesh;
}

/* Each vertex i of the transformed mesh equals f(tri_pos[i]); normals (if the
 * loader kept them) equal g(tri_nrm[i]). */
typedef vec3 (*point_map)(vec3);

static void check_tri(const mesh *m, point_map f, point_map g)
{
    for (uint32_t i = 0; i < 3; i++) {
        vec3 want = f(v3(tri_pos[i][0], tri_pos[i][1], tri_pos[i][2]));
        assert_vec3(vertex(m, i), want.x, want.y, want.z, 1e-5f);
        if (m->normals) {
            vec3 n = g(v3(tri_nrm[i][0], tri_nrm[i][1], tri_nrm[i][2]));
            assert_vec3(normal_of(m, i), n.x, n.y, n.z, 1e-5f);
        }
    }
}

static vec3 translated(vec3 p) { return v3(p.x + 10.f, p.y - 20.f, p.z + 0.5f); }
static vec3 same(vec3 n) { return n; }
static vec3 rot_x90(vec3 p) { return v3(p.x, -p.z, p.y); }
static vec3 rot_y90(vec3 p) { return v3(p.z, p.y, -p.x); }
static vec3 rot_z90(vec3 p) { return v3(-p.y, p.x, p.z); }
static vec3 rot_x90_then_y90(vec3 p) { return rot_y90(rot_x90(p)); }
static vec3 rot_x30(vec3 p)
{
    float c = cosf(30.f * 3.14159265f / 180.f), s = sinf(30.f * 3.14159265f / 180.f);
    return v3(p.x, c * p.y - s * p.z, s * p.y + c * p.z);
}
static vec3 scaled_2(vec3 p) { return v3_scale(p, 2.f); }
static vec3 scaled_234(vec3 p) { return v3(2.f * p.x, 3.f * p.y, 4.f * p.z); }
/* normals under scale (2, 3, 4): the inverse transpose, renormalised */
static vec3 normal_scaled_234(vec3 n) { return v3_normalize(v3(n.x / 2.f, n.y / 3.f, n.z / 4.f)); }
/* scale (2, 3, 4), then X 90, then Z 90, then translate (1, 2, 3) */
static vec3 combined(vec3 p) { return v3_add(rot_z90(rot_x90(scaled_234(p))), v3(1.f, 2.f, 3.f)); }
static vec3 normal_combined(vec3 n) { return rot_z90(rot_x90(normal_scaled_234(n))); }
/* matrix [0 -1 0 5; 2 0 0 6; 0 0 1 7] */
static vec3 matrix_map(vec3 p) { return v3(-p.y + 5.f, 2.f * p.x + 6.f, p.z + 7.f); }
static vec3 matrix_normal(vec3 n) { return v3_normalize(v3(-n.y, n.x / 2.f, n.z)); }

Test(scene, transforms_apply_to_positions_and_normals)
{
    scene *s;
    check_tri(load_tri_with("\"transform\": {\"translate\": [10, -20, 0.5]}", &s), translated, same);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"rotate_deg\": [90, 0, 0]}", &s), rot_x90, rot_x90);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"rotate_deg\": [0, 90, 0]}", &s), rot_y90, rot_y90);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"rotate_deg\": [0, 0, 90]}", &s), rot_z90, rot_z90);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"rotate_deg\": [90, 90, 0]}", &s), rot_x90_then_y90,
              rot_x90_then_y90);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"rotate_deg\": [30, 0, 0]}", &s), rot_x30, rot_x30);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"scale\": 2}", &s), scaled_2, same);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"scale\": [2, 3, 4]}", &s), scaled_234, normal_scaled_234);
    scene_destroy(s);
    check_tri(load_tri_with("\"transform\": {\"translate\": [1, 2, 3], \"rotate_deg\": [90, 0, 90],"
                            " \"scale\": [2, 3, 4]}",
                            &s),
              combined, normal_combined);
    scene_destroy(s);
    check_tri(load_tri_with("\"matrix\": [0, -1, 0, 5,  2, 0, 0, 6,  0, 0, 1, 7]", &s), matrix_map, matrix_normal);
    scene_destroy(s);
}

Test(scene, axis_rotations_are_exact)
{
    scene *s;
    const mesh *m = load_tri_with("\"transform\": {\"rotate_deg\": [90, 180, -90]}", &s);
    /* X 90: (x, -z, y); Y 180: (-x, y, -z); Z -90: (y, -x, z) => (-z, x, -y) overall */
    for (uint32_t i = 0; i < 3; i++)
        assert_vec3(vertex(m, i), -tri_pos[i][2], tri_pos[i][0], -tri_pos[i][1], 0.f);
    scene_destroy(s);
}

static void put_colored_obj(void)
{
    put_file("colored.obj", colored_obj);
    put_file("colored.mtl", colored_mtl);
}

Test(scene, mesh_with_mtl_materials_gets_scene_materials)
{
    put_colored_obj();
    tess_error err = {{0}};
    scene *s = load_text("{\"materials\": {\"unused\": {}}, \"meshes\": [{\"file\": \"colored.obj\"}]}", &err);
    cr_assert_not_null(s, "%s", err.msg);
    const scene_mesh *sm = s->meshes[0];
    const mesh *m = sm->mesh;
    cr_assert_gt(m->material_count, 0, "the loader kept no MTL materials");
    cr_assert_not_null(sm->mesh_material_ids);
    cr_assert_lt(sm->material_id, s->material_count);
    for (uint32_t i = 0; i < m->material_count; i++) {
        uint32_t id = sm->mesh_material_ids[i];
        cr_assert_lt(id, s->material_count);
        cr_assert_geq(id, 1u, "mesh materials come after the file's named ones");
        cr_assert_str_eq(s->materials[id].name, m->materials[i].name);
        cr_assert_eq(s->materials[id].model, MATERIAL_LAMBERT);
        cr_assert_eq(s->materials[id].ambient, 1.f);
    }
    /* each triangle's material is the one its usemtl named */
    cr_assert_eq(m->triangle_count, 4);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        bool right = vertex(m, m->indices[3 * t]).x >= 2.f;
        const material *mat = &s->materials[sm->mesh_material_ids[m->triangle_material[t]]];
        cr_assert_str_eq(mat->name, right ? "red" : "green");
        if (right)
            assert_vec3(mat->diffuse, 1.f, 0.f, 0.f, 0.f);
        else
            assert_vec3(mat->diffuse, 0.f, 0.5f, 0.f, 0.f);
    }
    scene_destroy(s);
}

Test(scene, named_material_overrides_mtl_materials)
{
    put_colored_obj();
    tess_error err = {{0}};
    scene *s = load_text("{\"materials\": {\"blue\": {\"diffuse\": [0, 0, 1]}},"
                         " \"meshes\": [{\"file\": \"colored.obj\", \"material\": \"blue\"}]}",
                         &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->material_count, 1);
    cr_assert_eq(s->meshes[0]->material_id, 0u);
    cr_assert_null(s->meshes[0]->mesh_material_ids);
    cr_assert_eq(s->meshes[0]->mesh->material_count, 0);
    scene_destroy(s);
}

Test(scene, missing_optional_mesh_is_skipped)
{
    put_file("tri.ply", tri_ply);
    tess_error err = {{0}};
    scene *s = load_text("{\"meshes\": [{\"file\": \"absent/nothing.ply\", \"optional\": true},"
                         " {\"file\": \"tri.ply\"}]}",
                         &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_eq(s->mesh_count, 1);
    cr_assert_eq(s->meshes[0]->mesh->vertex_count, 3);
    scene_destroy(s);
}

/* ---- JSON: errors ------------------------------------------------------ */

Test(scene, missing_scene_file)
{
    char path[512];
    tess_error err = {{0}};
    cr_assert_null(scene_load_json(tmp_path(path, sizeof path, "none.json"), &err));
    cr_assert(strstr(err.msg, path) && strstr(err.msg, "cannot open"), "%s", err.msg);
    /* scene_load dispatches on the extension, also in capitals */
    cr_assert_null(scene_load(tmp_path(path, sizeof path, "none.JSON"), &(tess_error){{0}}));
}

Test(scene, scene_path_that_is_a_directory)
{
    char path[512];
    put_dir("dir.json");
    tess_error err = {{0}};
    cr_assert_null(scene_load_json(tmp_path(path, sizeof path, "dir.json"), &err));
    cr_assert(strstr(err.msg, "cannot open: not a regular file"), "%s", err.msg);
}

Test(scene, syntax_errors_report_line_and_column)
{
    expect_failure("{\n"
                   "  \"background\": [0, 0, 0],\n"
                   "  \"ambient\": [0.1, 0.1 0.1]\n"
                   "}\n",
                   ":3:24: JSON syntax error: ", NULL);
    expect_failure("{\n  \"spheres\": [\n", ":3:1: JSON syntax error: ", NULL);        /* truncated */
    expect_failure("", ":1:1: JSON syntax error", NULL);                                  /* empty */
    expect_failure("{\"spheres\": []}\nxx\n", ":2:1: JSON syntax error", NULL);           /* trailing */
    expect_failure("{\"spheres\": []} /* unterminated", ":1:", "JSON syntax error", NULL); /* comment */
    expect_failure("{\"a\" 1}", ":1:6: JSON syntax error", NULL);
    expect_failure("{\"s\": \"\xff\"}", ":1:", "JSON syntax error", NULL); /* invalid UTF-8 */
}

Test(scene, duplicate_keys_are_errors)
{
    expect_failure("{\n  \"ambient\": [0, 0, 0],\n  \"ambient\": [1, 1, 1]\n}", ":3:3: duplicate key 'ambient'", NULL);
    expect_failure("{\"materials\": {\"a\": {},\n \"b\": {\"diffuse\": [0, 0, 0], \"diffuse\": [1, 1, 1]}}}",
                   ":2:30: duplicate key 'diffuse'", NULL);
    /* the same key spelled with an escape */
    expect_failure("{\"materials\": {\"ab\": {}, \"a\\u0062\": {}}}", ":1:26: duplicate key 'a", NULL);
    /* equal keys in different objects are fine */
    tess_error err = {{0}};
    scene *s = load_text("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}, {\"center\": [1, 0, 0], \"radius\": 1}]}",
                         &err);
    cr_assert_not_null(s, "%s", err.msg);
    scene_destroy(s);
}

#define SPHERE "\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]"

Test(scene, unknown_fields_are_errors)
{
    expect_failure("{\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0]},\n"
                   "  {\"type\": \"directional\", \"direction\": [0, 1, 0], \"colour\": [1, 1, 1]}], " SPHERE "}",
                   ": field 'lights[1].colour': unknown field (expected one of: type, direction, position, color, "
                   "intensity, shadows)",
                   NULL);
    expect_failure("{\"sphere\": []}", ": field 'sphere': unknown field (expected one of: camera,", NULL);
    expect_failure("{\"materials\": {\"red\": {\"difuse\": [1, 0, 0]}}, " SPHERE "}",
                   "field 'materials.red.difuse': unknown field", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"x.ply\", \"transform\": {\"rotate\": [0, 0, 0]}}]}",
                   "field 'meshes[0].transform.rotate': unknown field", NULL);
    expect_failure("{\"camera\": {\"eye\": [0, 0, 1], \"look_at\": [0, 0, 0], \"fov\": 30}, " SPHERE "}",
                   "field 'camera.fov': unknown field", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"colour\": 1}]}",
                   "field 'spheres[0].colour': unknown field (expected one of: center, radius, material)", NULL);
}

Test(scene, wrong_types_are_errors)
{
    expect_failure("{\"camera\": {\"eye\": [0, 0, 1], \"look_at\": [0, 0, 0], \"fov_deg\": \"40\"}, " SPHERE "}",
                   ": field 'camera.fov_deg': expected a number, got string", NULL);
    expect_failure("[1, 2]", "expected a JSON object at the top level, got array", NULL);
    expect_failure("null", "expected a JSON object at the top level, got null", NULL);
    /* a control character in a key must not break the one-line message */
    expect_failure("{\"sph\\neres\": []}", "field 'sph?eres': unknown field", NULL);
    expect_failure("{\"lights\": {}, " SPHERE "}", "field 'lights': expected an array, got object", NULL);
    expect_failure("{\"materials\": [], " SPHERE "}", "field 'materials': expected an object, got array", NULL);
    expect_failure("{\"background\": \"black\", " SPHERE "}", "field 'background': expected an array of 3 numbers, got string",
                   NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, null, 0], \"radius\": 1}]}",
                   "field 'spheres[0].center[1]': expected a number, got null", NULL);
    expect_failure("{\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"shadows\": 1}], " SPHERE "}",
                   "field 'lights[0].shadows': expected a boolean, got number", NULL);
    expect_failure("{\"meshes\": [{\"file\": 3}]}", "field 'meshes[0].file': expected a string, got number", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"\"}]}", "field 'meshes[0].file': must not be empty", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"a.ply\", \"transform\": {\"scale\": \"big\"}}]}",
                   "field 'meshes[0].transform.scale': expected a number or an array of 3 numbers, got string", NULL);
    expect_failure("{\"spheres\": [7]}", "field 'spheres[0]': expected an object, got number", NULL);
}

Test(scene, wrong_array_lengths_are_errors)
{
    expect_failure("{\"camera\": {\"eye\": [0, 1], \"look_at\": [0, 0, 0]}, " SPHERE "}",
                   "field 'camera.eye': expected an array of 3 numbers, got 2 elements", NULL);
    expect_failure("{\"ambient\": [0, 0, 0, 0], " SPHERE "}", "field 'ambient': expected an array of 3 numbers, got 4",
                   NULL);
    expect_failure("{\"meshes\": [{\"file\": \"a.ply\", \"matrix\": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]}",
                   "field 'meshes[0].matrix': expected an array of 12 numbers, got 11 elements", NULL);
}

Test(scene, non_finite_and_huge_numbers_are_errors)
{
    expect_failure("{\"spheres\": [{\"center\": [NaN, 0, 0], \"radius\": 1}]}",
                   "field 'spheres[0].center[0]': expected a finite number", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": Infinity}]}",
                   "field 'spheres[0].radius': expected a finite number", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, -Infinity, 0], \"radius\": 1}]}",
                   "field 'spheres[0].center[1]': expected a finite number", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 1e999], \"radius\": 1}]}",
                   "field 'spheres[0].center[2]': expected a finite number", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 1e39], \"radius\": 1}]}",
                   "field 'spheres[0].center[2]': 1e+39 is out of range for a float", NULL);
    expect_failure("{\"spheres\": [{\"center\": [99999999999999999999, 0, 0], \"radius\": 1}]}",
                   "field 'spheres[0].center[0]': integer out of range", NULL);
    expect_failure("{\"spheres\": [{\"center\": [-99999999999999999999, 0, 0], \"radius\": 1}]}",
                   "field 'spheres[0].center[0]': integer out of range", NULL);
}

Test(scene, out_of_range_values_are_errors)
{
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": -1}]}",
                   "field 'spheres[0].radius': must be > 0, got -1", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 0}]}", "field 'spheres[0].radius': must be > 0",
                   NULL);
    expect_failure("{\"camera\": {\"eye\": [0, 0, 1], \"look_at\": [0, 0, 0], \"fov_deg\": 180}, " SPHERE "}",
                   "field 'camera.fov_deg': must be in (0, 180), got 180", NULL);
    expect_failure("{\"camera\": {\"eye\": [0, 0, 1], \"look_at\": [0, 0, 0], \"fov_deg\": 0}, " SPHERE "}",
                   "field 'camera.fov_deg': must be in (0, 180)", NULL);
    expect_failure("{\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"color\": [1, -0.5, 1]}], " SPHERE "}",
                   "field 'lights[0].color[1]': must be >= 0, got -0.5", NULL);
    expect_failure("{\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": -2}], " SPHERE "}",
                   "field 'lights[0].intensity': must be >= 0", NULL);
    expect_failure("{\"background\": [-1, 0, 0], " SPHERE "}", "field 'background[0]': must be >= 0", NULL);
    expect_failure("{\"materials\": {\"m\": {\"diffuse\": [0.5, 1.5, 0]}}, " SPHERE "}",
                   "field 'materials.m.diffuse[1]': must be in [0, 1], got 1.5", NULL);
    expect_failure("{\"materials\": {\"m\": {\"shininess\": -1}}, " SPHERE "}",
                   "field 'materials.m.shininess': must be >= 0", NULL);
    expect_failure("{\"materials\": {\"m\": {\"specular\": [0, -1, 0]}}, " SPHERE "}",
                   "field 'materials.m.specular[1]': must be >= 0", NULL);
    expect_failure("{\"materials\": {\"m\": {\"ambient\": 2}}, " SPHERE "}", "field 'materials.m.ambient': must be in [0, 1]",
                   NULL);
    expect_failure("{\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0]}], " SPHERE "}",
                   "field 'lights[0].type': unknown value 'spot' (expected one of: directional, point)", NULL);
    expect_failure("{\"materials\": {\"m\": {\"model\": \"blinn\"}}, " SPHERE "}",
                   "field 'materials.m.model': unknown value 'blinn' (expected one of: lambert, phong)", NULL);
    expect_failure("{\"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 0]}], " SPHERE "}",
                   "field 'lights[0].direction': must not be the zero vector", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"a.ply\", \"transform\": {\"scale\": [1, 0, 1]}}]}",
                   "field 'meshes[0].transform.scale': must not be zero", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"a.ply\", \"matrix\": [1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 1, 0]}]}",
                   "field 'meshes[0].matrix': the 3x3 part is singular", NULL);
}

Test(scene, structural_mistakes_are_errors)
{
    expect_failure("{\"lights\": [{\"direction\": [0, 1, 0]}], " SPHERE "}",
                   "field 'lights[0].type': required field is missing", NULL);
    expect_failure("{\"lights\": [{\"type\": \"directional\"}], " SPHERE "}",
                   "field 'lights[0].direction': required field is missing", NULL);
    expect_failure("{\"lights\": [{\"type\": \"directional\", \"direction\": [0, 1, 0], \"position\": [0, 0, 0]}], " SPHERE
                   "}",
                   "field 'lights[0].position': only point lights have a position", NULL);
    expect_failure("{\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"direction\": [0, 1, 0]}], " SPHERE "}",
                   "field 'lights[0].direction': only directional lights have a direction", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 0]}]}", "field 'spheres[0].radius': required field is missing",
                   NULL);
    expect_failure("{\"camera\": {\"eye\": [0, 0, 1]}, " SPHERE "}", "field 'camera.look_at': required field is missing",
                   NULL);
    expect_failure("{\"meshes\": [{\"material\": \"x\"}]}", "field 'meshes[0].file': required field is missing", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"a.ply\", \"transform\": {}, \"matrix\": []}]}",
                   "field 'meshes[0]': give either 'transform' or 'matrix', not both", NULL);
    expect_failure("{\"materials\": {\"\": {}}, " SPHERE "}", "field 'materials.': a material name must be 1 to 63 bytes",
                   NULL);
    expect_failure("{\"materials\": {\"a123456789b123456789c123456789d123456789e123456789f123456789g1234\": {}}, " SPHERE
                   "}",
                   "a material name must be 1 to 63 bytes", NULL);
}

Test(scene, unknown_material_names_are_errors)
{
    put_file("tri.ply", tri_ply);
    expect_failure("{\"materials\": {\"red\": {}}, \"meshes\": [{\"file\": \"tri.ply\", \"material\": \"blue\"}]}",
                   "field 'meshes[0].material': unknown material 'blue'", NULL);
    expect_failure("{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"material\": \"red\"}]}",
                   "field 'spheres[0].material': unknown material 'red'", NULL);
}

Test(scene, invalid_camera_is_an_error)
{
    expect_failure("{\"camera\": {\"eye\": [1, 2, 3], \"look_at\": [1, 2, 3]}, " SPHERE "}", "field 'camera': ", NULL);
    expect_failure("{\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [0, 1, 0]}, " SPHERE "}", "field 'camera': ", NULL);
}

Test(scene, mesh_errors_carry_the_field_and_the_loader_message)
{
    char want[600], mesh_path[512];
    put_file("tri.ply", tri_ply);
    tmp_path(mesh_path, sizeof mesh_path, "broken.ply");
    put_file("broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                           "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    snprintf(want, sizeof want, ": field 'meshes[1].file': %s", mesh_path);
    expect_failure("{\"meshes\": [{\"file\": \"tri.ply\"}, {\"file\": \"broken.ply\"}]}", want, NULL);
    /* a broken file is an error even when optional: only absence is forgiven */
    expect_failure("{\"meshes\": [{\"file\": \"broken.ply\", \"optional\": true}]}", want + strlen(": field 'meshes[1]"),
                   NULL);
    tmp_path(mesh_path, sizeof mesh_path, "missing.ply");
    snprintf(want, sizeof want, ": field 'meshes[2].file': %s", mesh_path);
    expect_failure("{\"meshes\": [{\"file\": \"tri.ply\"}, {\"file\": \"tri.ply\"}, {\"file\": \"missing.ply\"}]}", want,
                   NULL);
}

Test(scene, scene_without_geometry_is_an_error)
{
    expect_failure("{}", ": scene has no geometry", NULL);
    expect_failure("{\"meshes\": [], \"spheres\": []}", ": scene has no geometry", NULL);
    expect_failure("{\"meshes\": [{\"file\": \"gone.obj\", \"optional\": true}]}", ": scene has no geometry", NULL);
}

Test(scene, errors_with_null_error_pointer_do_not_crash)
{
    put_file("scene.json", "{\"spheres\": [{\"center\": [0, 0, 0], \"radius\": -1}]}");
    char path[512];
    cr_assert_null(scene_load_json(tmp_path(path, sizeof path, "scene.json"), NULL));
    cr_assert_null(scene_load(tmp_path(path, sizeof path, "none.json"), NULL));
}

/* ---- the example scenes ------------------------------------------------ */

/* True when the file names data outside the repository (../shared). */
static bool needs_shared_data(const char *path)
{
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "%s", path);
    char buf[65536];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return strstr(buf, "shared/data") != NULL;
}

Test(scene, example_scenes_load)
{
    DIR *d = opendir(EXAMPLE_SCENES_DIR);
    cr_assert_not_null(d, "cannot list %s (run from tests/)", EXAMPLE_SCENES_DIR);
    struct dirent *e;
    int loaded = 0;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 5, ".json") != 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "%s/%s", EXAMPLE_SCENES_DIR, e->d_name);
        if (needs_shared_data(path))
            continue;
        tess_error err = {{0}};
        scene *s = scene_load(path, &err);
        cr_assert_not_null(s, "%s: %s", path, err.msg);
        vec3 lo, hi;
        cr_assert(scene_bounds(s, &lo, &hi), "%s has no bounds", path);
        cr_assert_gt(s->light_count, 0, "%s has no lights", path);
        scene_destroy(s);
        loaded++;
    }
    closedir(d);
    cr_assert_geq(loaded, 2, "expected at least two self-contained example scenes");
}

/* ---- assemblies -------------------------------------------------------- */

/* The shipped assembly (tests/data/assembly-small.glb) by absolute path. */
static void small_assembly(char *out, size_t size)
{
    char cwd[400];
    cr_assert_not_null(getcwd(cwd, sizeof cwd));
    snprintf(out, size, "%s/data/assembly-small.glb", cwd);
    struct stat st;
    cr_assert_eq(stat(out, &st), 0, "%s is missing", out);
}

Test(scene, an_assembly_loads_as_a_part_tree_with_instances)
{
    char glb[512];
    small_assembly(glb, sizeof glb);
    tess_error err = {{0}};
    scene *s = scene_load(glb, &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_assert_not_null(s->parts);
    cr_assert_gt(part_tree_count(s->parts), 200);
    cr_assert_lt(s->geometry_count, s->instance_count / 5, "fasteners are stored once: %u geometries, %u instances",
                 s->geometry_count, s->instance_count);
    cr_assert_gt(scene_instanced_triangle_count(s), 5 * scene_triangle_count(s));
    /* a subtree's instances are one range, and the parts of a section lie in it */
    int32_t section = part_tree_find(s->parts, "assembly/section-1");
    cr_assert_geq(section, 0, "assembly/section-1 is a part");
    uint32_t first, end, all_first, all_end;
    scene_part_instances(s, (uint32_t)section, &first, &end);
    scene_part_instances(s, PART_ROOT, &all_first, &all_end);
    cr_assert(first < end && all_first == 0 && all_end == s->instance_count, "section [%u, %u), all [%u, %u)", first,
              end, all_first, all_end);
    int32_t section_end = part_tree_subtree_end(s->parts, section);
    for (uint32_t i = 0; i < s->instance_count; i++) {
        bool inside = (int32_t)s->instances[i].part >= section && (int32_t)s->instances[i].part < section_end;
        cr_assert_eq(inside, i >= first && i < end, "instance %u (part %u)", i, s->instances[i].part);
    }
    scene_destroy(s);
}

static mesh *one_triangle(void)
{
    mesh *m = mesh_create();
    mesh_add_vertex(m, 0, 0, 0);
    mesh_add_vertex(m, 1, 0, 0);
    mesh_add_vertex(m, 0, 1, 0);
    mesh_add_triangle(m, 0, 1, 2);
    return m;
}

/* Meshes without parts before and after an assembly: every
 * part's range holds exactly its subtree's instances, never a part-less one,
 * and an instance out of preorder is refused. */
Test(scene, part_ranges_skip_instances_without_parts)
{
    char glb[512];
    small_assembly(glb, sizeof glb);
    tess_error err = {{0}};
    scene *s = scene_create();
    material mat = material_default();
    scene_add_material(s, &mat);
    cr_assert_geq(scene_add_mesh(s, one_triangle(), 0, "before"), 0);
    cr_assert(scene_load_assembly(s, glb, NULL, &err), "%s", err.msg);
    cr_assert_geq(scene_add_mesh(s, one_triangle(), 0, "after"), 0);
    int32_t count = part_tree_count(s->parts);
    for (int32_t part = 0; part < count; part++) { /* the root too: every instance with a part */
        uint32_t first, end;
        scene_part_instances(s, (uint32_t)part, &first, &end);
        int32_t part_end = part_tree_subtree_end(s->parts, part);
        uint32_t inside = 0;
        for (uint32_t i = 0; i < s->instance_count; i++) {
            uint32_t p = s->instances[i].part;
            bool in_subtree = p != SCENE_NO_PART && (int32_t)p >= part && (int32_t)p < part_end;
            inside += in_subtree;
            if (in_subtree)
                cr_assert(i >= first && i < end, "part %d: instance %u outside [%u, %u)", part, i, first, end);
        }
        cr_assert_eq(end - first, inside, "part %d: [%u, %u) for %u instances", part, first, end, inside);
    }
    cr_assert_eq(s->instances[0].part, SCENE_NO_PART);
    cr_assert_eq(s->instances[s->instance_count - 1].part, SCENE_NO_PART);
    /* preorder: an instance of an earlier part after a later one is refused */
    cr_assert_eq(scene_add_instance(s, 0, NULL, 1), -1);
    scene_destroy(s);
}

Test(scene, a_scene_file_places_an_assembly_and_colours_parts_by_pattern)
{
    char glb[512], text[2048];
    small_assembly(glb, sizeof glb);
    snprintf(text, sizeof text,
             "{\"materials\": {\"steel\": {\"diffuse\": [0.2, 0.2, 0.25]}},\n"
             " \"assemblies\": [{\"file\": \"%s\", \"transform\": {\"translate\": [0, 10, 0]},\n"
             "   \"colours\": [{\"parts\": \"**/bolt-*\", \"material\": \"steel\"},\n"
             "                 {\"parts\": \"assembly/section-2\", \"diffuse\": [1, 0, 0]},\n"
             "                 {\"parts\": \"**/no-such-part\", \"diffuse\": [0, 1, 0]}]}]}",
             glb);
    tess_error err = {{0}};
    scene *s = load_text(text, &err);
    cr_assert_not_null(s, "%s", err.msg);
    scene *plain = scene_load(glb, &err);
    cr_assert_not_null(plain, "%s", err.msg);
    vec3 lo, hi, plo, phi;
    cr_assert(scene_bounds(s, &lo, &hi) && scene_bounds(plain, &plo, &phi));
    cr_assert_float_eq(lo.y, plo.y + 10.f, 1e-3f, "placed 10 up: %g vs %g", (double)lo.y, (double)plo.y);
    int steel = -1;
    for (uint32_t m = 0; m < s->material_count && steel < 0; m++) /* the scene file's, before the assembly's own */
        if (strcmp(s->materials[m].name, "steel") == 0)
            steel = (int)m;
    char path[1024];
    int bolts = 0, red = 0;
    int32_t section2 = part_tree_find(s->parts, "assembly/section-2");
    cr_assert_geq(section2, 0);
    for (uint32_t i = 0; i < s->instance_count; i++) {
        uint32_t part = s->instances[i].part;
        part_tree_path(s->parts, (int32_t)part, path, sizeof path);
        bool in_section2 = (int32_t)part >= section2 && (int32_t)part < part_tree_subtree_end(s->parts, section2);
        if (in_section2) { /* the later colour wins */
            cr_assert_eq(s->materials[s->instances[i].material].diffuse.x, 1.f, "%s", path);
            red++;
        } else if (strstr(path, "/bolt-")) {
            cr_assert_eq(s->instances[i].material, (uint32_t)steel, "%s", path);
            bolts++;
        } else {
            cr_assert_eq(s->instances[i].material, SCENE_NO_MATERIAL, "%s", path);
        }
    }
    cr_assert(bolts > 0 && red > 0, "bolts %d, section-2 instances %d", bolts, red);
    scene_destroy(plain);
    scene_destroy(s);
}

Test(scene, assembly_entries_with_errors_name_the_field)
{
    char glb[512], text[2048];
    small_assembly(glb, sizeof glb);
    expect_failure("{\"assemblies\": [{\"file\": \"missing.glb\"}]}", "field 'assemblies[0].file': ", "missing.glb",
                   NULL);
    snprintf(text, sizeof text, "{\"assemblies\": [{\"file\": \"%s\", \"colours\": [{\"parts\": \"**\"}]}]}", glb);
    expect_failure(text, "field 'assemblies[0].colours[0]': give either 'material' or 'diffuse'", NULL);
    snprintf(text, sizeof text,
             "{\"assemblies\": [{\"file\": \"%s\", \"colours\": [{\"parts\": \"**\", \"material\": \"gold\"}]}]}", glb);
    expect_failure(text, "field 'assemblies[0].colours[0].material': unknown material 'gold'", NULL);
    snprintf(text, sizeof text, "{\"assemblies\": [{\"file\": \"%s\", \"scale\": 2}]}", glb);
    expect_failure(text, "field 'assemblies[0].scale': unknown field", NULL);
    snprintf(text, sizeof text,
             "{\"assemblies\": [{\"file\": \"%s\", \"colours\": [{\"parts\": \"**\", \"diffuse\": [2, 0, 0]}]}]}", glb);
    expect_failure(text, "field 'assemblies[0].colours[0].diffuse", NULL);
    put_file("broken.glb", "glTF but not really");
    expect_failure("{\"assemblies\": [{\"file\": \"broken.glb\"}]}", "field 'assemblies[0].file': ", "broken.glb",
                   NULL);
}
