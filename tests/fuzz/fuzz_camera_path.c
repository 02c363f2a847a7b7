/* fuzz_camera_path.c - camera path files (engine/frame/camera_path.c) through
 * camera_path_parse. A path that parses must keep the header's promises:
 * strictly increasing times, valid key cameras, camera_path_eval valid at any
 * time (between keys, outside them, NaN, infinite), and save-then-load giving
 * the keys back bit for bit. */
#include "fuzz.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/frame/camera_path.h"

static void check_eval(const camera_path *p, double t, const char *name)
{
    camera_desc c = camera_path_eval(p, t);
    tess_error err = {{0}};
    if (!camera_validate(&c, &err))
        fuzz_fail("%s: camera_path_eval at t = %a gives an invalid camera: %s", name, t, err.msg);
}

static void check_path(const camera_path *p, const char *name)
{
    if (p->count < 1 || p->count > p->capacity)
        fuzz_fail("%s: %zu keys (capacity %zu)", name, p->count, p->capacity);
    for (size_t k = 0; k < p->count; k++) {
        tess_error err = {{0}};
        if (!camera_validate(&p->keys[k].camera, &err))
            fuzz_fail("%s: key %zu: invalid camera accepted: %s", name, k, err.msg);
        if (!(p->keys[k].time_s >= 0.0) || !isfinite(p->keys[k].time_s) ||
            (k > 0 && !(p->keys[k].time_s > p->keys[k - 1].time_s)))
            fuzz_fail("%s: key %zu: time %a out of order", name, k, p->keys[k].time_s);
    }
    static const double fractions[] = {0.0, 1e-300, 1e-9, 0.25, 0.5, 0.999999, 1.0 - 0x1p-52};
    for (size_t k = 0; k < p->count; k++) {
        double t0 = p->keys[k].time_s;
        double h = k + 1 < p->count ? p->keys[k + 1].time_s - t0 : 1.0;
        for (size_t f = 0; f < sizeof fractions / sizeof fractions[0]; f++)
            check_eval(p, t0 + fractions[f] * h, name);
    }
    double d = camera_path_duration(p);
    const double odd[] = {-1.0, -1e300, 1e300, p->keys[0].time_s + 3.5 * d, NAN, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof odd / sizeof odd[0]; i++)
        check_eval(p, odd[i], name);
}

static void check_round_trip(const camera_path *p, const char *name)
{
    static char file[512];
    if (!file[0])
        snprintf(file, sizeof file, "%s/saved.json", fuzz_scratch_dir());
    tess_error err = {{0}};
    if (!camera_path_save(p, file, &err))
        fuzz_fail("%s: a parsed path does not save: %s", name, err.msg);
    camera_path back = {0};
    if (!camera_path_load(file, &back, &err))
        fuzz_fail("%s: the saved path does not load: %s", name, err.msg);
    if (back.count != p->count || back.interp != p->interp || back.loop != p->loop)
        fuzz_fail("%s: save/load changed the path's shape", name);
    for (size_t k = 0; k < p->count; k++)
        if (back.keys[k].time_s != p->keys[k].time_s ||
            memcmp(&back.keys[k].camera, &p->keys[k].camera, sizeof back.keys[k].camera) != 0)
            fuzz_fail("%s: save/load changed key %zu", name, k);
    camera_path_free(&back);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = "path.json";
    camera_path p;
    tess_error err = {{0}};
    if (camera_path_parse(name, (const char *)data, size, &p, &err)) {
        check_path(&p, name);
        check_round_trip(&p, name);
    } else {
        fuzz_check_error(&err, name);
        if (p.count != 0 || p.keys != NULL)
            fuzz_fail("%s: a failed parse left %zu keys", name, p.count);
    }
    camera_path_free(&p);
    return 0;
}
