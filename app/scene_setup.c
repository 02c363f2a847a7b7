/* scene_setup.c - what every command does first: load the scene (or make the
 * built-in one), build its acceleration structure, report both, and choose
 * the camera. */
#include <stdio.h>

#include "cli.h"
#include "engine/scene/accel.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"

bool cli_scene_prepare(const char *scene_path, int threads, cli_scene *out)
{
    return cli_scene_prepare_with(scene_path, NULL, threads, out);
}

bool cli_scene_prepare_with(const char *scene_path, const struct scene_load_options *opts, int threads,
                            cli_scene *out)
{
    *out = (cli_scene){.name = scene_path ? scene_path : "(built-in default)"};
    tess_error err = {{0}};
    double t0 = cli_now_s();
    out->scene = scene_path ? scene_load_with(scene_path, opts, &err) : scene_create_default(&err);
    if (!out->scene) {
        cli_error("%s", err.msg);
        return false;
    }
    double t1 = cli_now_s();
    out->accel = accel_build(out->scene, threads, &err);
    if (!out->accel) {
        cli_error("%s", err.msg);
        return false;
    }
    out->load_s = t1 - t0;
    out->build_s = cli_now_s() - t1;
    const scene *s = out->scene;
    char volumes[96] = ""; /* only a scene with volumes says so */
    if (s->volume_count)
        snprintf(volumes, sizeof volumes, ", %u volume%s (%.3g M voxels)", s->volume_count,
                 s->volume_count == 1 ? "" : "s", (double)s->volume_voxels * 1e-6);
    fprintf(stderr,
            "tessera: scene %s: %zu triangles, %u spheres, %zu particles%s, %u light%s; loaded in %.3f s, BVH built in "
            "%.3f s (%s kernels)\n",
            out->name, scene_triangle_count(s), s->spheres.count, scene_point_count(s), volumes, s->light_count,
            s->light_count == 1 ? "" : "s", out->load_s, out->build_s, accel_isa_name(out->accel));
    return true;
}

bool cli_scene_camera(const cli_scene *cs, const camera_desc *given, int width_px, int height_px, camera_desc *out)
{
    const scene *s = cs->scene;
    vec3 lo, hi;
    if (given)
        *out = *given;
    else if (s->has_camera)
        *out = s->camera;
    else if (scene_bounds(s, &lo, &hi))
        *out = camera_frame_bounds(lo, hi, CAMERA_DEFAULT_VIEW_DIR, CAMERA_DEFAULT_FOV_DEG, width_px, height_px);
    else {
        cli_error("%s: the scene has no geometry to look at", cs->name);
        return false;
    }
    tess_error err = {{0}};
    if (!camera_validate(out, &err)) {
        cli_error("%s: %s", cs->name, err.msg);
        return false;
    }
    return true;
}

void cli_scene_finish(cli_scene *cs)
{
    accel_destroy(cs->accel);
    scene_destroy(cs->scene);
    cs->accel = NULL;
    cs->scene = NULL;
}
