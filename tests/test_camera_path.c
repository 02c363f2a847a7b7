/* test_camera_path.c - camera path files (engine/frame/camera_path.h): parse errors,
 * evaluation (exact keys, continuity, Catmull-Rom C1 and straight lines,
 * clamping and looping), recording, save/load round trips, and the example
 * paths in ../configs/paths (the suite runs in tests/) against the built-in
 * default scene. Files are written to a mkdtemp directory per test. */
#include <criterion/criterion.h>

#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/frame/camera_path.h"
#include "engine/scene/scene.h"
#include "support.h"

#define EXAMPLE_PATHS_DIR "../configs/paths"

/* ---- temporary files ----------------------------------------------------- */

static char tmp_dir[64]; /* per test (Criterion runs each test in its own process) */

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "camera-path"); }

/* The tests only create flat files in tmp_dir. */
static void remove_tmp_dir(void)
{
    DIR *d = opendir(tmp_dir);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL) {
        char path[sizeof tmp_dir + sizeof e->d_name + 1];
        snprintf(path, sizeof path, "%s/%s", tmp_dir, e->d_name);
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0)
            unlink(path);
    }
    if (d)
        closedir(d);
    rmdir(tmp_dir);
}

TestSuite(camera_path, .init = make_tmp_dir, .fini = remove_tmp_dir);

static const char *tmp_file(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/%s", tmp_dir, name);
    return buf;
}

static void put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "cannot write %s", path);
    fputs(text, f);
    fclose(f);
}

/* ---- helpers ------------------------------------------------------------- */

#define HEADER "\"format\": \"tessera-camera-path\", \"version\": 1, "

/* A valid key with eye (x, 1, 5), looking at the origin. */
#define KEY(t, x) "{\"time\": " #t ", \"eye\": [" #x ", 1, 5], \"look_at\": [0, 0, 0]}"

static bool parse(const char *text, camera_path *out, tess_error *err)
{
    return camera_path_parse("path.json", text, strlen(text), out, err);
}

/* Parsing `text` must fail with a message containing `want`. */
static void expect_failure(const char *text, const char *want)
{
    camera_path p;
    tess_error err = {{0}};
    cr_assert_not(parse(text, &p, &err), "accepted: %s", text);
    cr_assert(strstr(err.msg, want), "for %s\n  got:  %s\n  want: %s", text, err.msg, want);
    cr_assert_null(p.keys, "a failed parse leaves an empty path");
    cr_assert_eq(p.count, 0);
}

static camera_path parse_ok(const char *text)
{
    camera_path p;
    tess_error err = {{0}};
    cr_assert(parse(text, &p, &err), "%s\n  for: %s", err.msg, text);
    return p;
}

static camera_desc cam(vec3 eye, vec3 look_at, vec3 up, float fov_deg)
{
    return (camera_desc){.eye = eye, .look_at = look_at, .up = up, .fov_deg = fov_deg};
}

static void append_ok(camera_path *p, double t, camera_desc c)
{
    tess_error err = {{0}};
    cr_assert(camera_path_append(p, t, &c, &err), "append at %g: %s", t, err.msg);
}

static bool same_bits(camera_desc a, camera_desc b) { return memcmp(&a, &b, sizeof a) == 0; }

static double dist(vec3 a, vec3 b) { return v3_length(v3_sub(a, b)); }

/* Non-uniform times, a curved path of eye and look_at, varied up and fov. */
static camera_path curved_path(camera_path_interp interp, bool loop)
{
    static const double times[] = {0.0, 0.7, 1.5, 3.0, 3.4, 5.0};
    camera_path p = {.interp = interp, .loop = loop};
    for (int i = 0; i < 6; i++) {
        double a = 0.9 * i;
        camera_desc c = cam(v3(6.f * (float)cos(a), 1.f + 0.4f * (float)i, 6.f * (float)sin(a)),
                            v3(0.1f * (float)i, 0.5f, -0.2f * (float)i), v3(0.1f * (float)i, 1.f, 0.f),
                            35.f + 3.f * (float)i);
        if (loop && i == 5)
            c = p.keys[0].camera; /* a loop closes on its first camera */
        append_ok(&p, times[i], c);
    }
    return p;
}

/* ---- parse errors ---------------------------------------------------------- */

Test(camera_path, minimal_file_gets_the_defaults)
{
    camera_path p = parse_ok("{" HEADER "\"keyframes\": [" KEY(0.5, 2) "]}");
    cr_assert_eq(p.count, 1);
    cr_assert_eq(p.interp, CAMERA_PATH_CATMULL_ROM);
    cr_assert_not(p.loop);
    cr_assert_eq(p.keys[0].time_s, 0.5);
    camera_desc want = cam(v3(2.f, 1.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), CAMERA_DEFAULT_FOV_DEG);
    cr_assert(same_bits(p.keys[0].camera, want));
    cr_assert_eq(camera_path_duration(&p), 0.0);
    cr_assert(same_bits(camera_path_eval(&p, -3.0), want), "one key is a still camera");
    cr_assert(same_bits(camera_path_eval(&p, 100.0), want));
    camera_path_free(&p);
    cr_assert_null(p.keys);
    cr_assert_eq(p.count, 0);
}

Test(camera_path, all_fields_and_comments_are_read)
{
    camera_path p = parse_ok("// a path\n{" HEADER "/* block */ \"interpolation\": \"linear\", \"loop\": true,\n"
                             "\"keyframes\": [\n"
                             "  {\"time\": 1, \"eye\": [1, 2, 3], \"look_at\": [0, 0.5, 0], \"up\": [0, 0, 1],"
                             "   \"fov_deg\": 60},\n"
                             "  {\"time\": 2.25, \"eye\": [3, 2, 1], \"look_at\": [0, 0, 0]},\n"
                             "  {\"time\": 4, \"eye\": [1, 2, 3], \"look_at\": [0, 0.5, 0], \"up\": [0, 0, 1],"
                             "   \"fov_deg\": 60}\n"
                             "]} // end");
    cr_assert_eq(p.count, 3);
    cr_assert_eq(p.interp, CAMERA_PATH_LINEAR);
    cr_assert(p.loop);
    cr_assert_eq(p.keys[1].time_s, 2.25);
    cr_assert(same_bits(p.keys[0].camera, cam(v3(1.f, 2.f, 3.f), v3(0.f, 0.5f, 0.f), v3(0.f, 0.f, 1.f), 60.f)));
    cr_assert_eq(camera_path_duration(&p), 3.0);
    camera_path_free(&p);
}

Test(camera_path, syntax_errors_report_line_and_column)
{
    expect_failure("{" HEADER "\n  \"keyframes\": [\n    " KEY(0, 1) ",\n    {\"time\" 1}\n  ]\n}",
                   "path.json:4:13: JSON syntax error: object property name separator ':' expected");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, 1) "]", "path.json:1:");
    expect_failure("", "path.json:1:1: JSON syntax error");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, 1) "]} x", "path.json:1:");
}

Test(camera_path, top_level_must_be_an_object)
{
    expect_failure("[1, 2]", "path.json: expected a JSON object at the top level, got array");
}

Test(camera_path, format_and_version_are_required_and_checked)
{
    expect_failure("{\"version\": 1, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'format': required field is missing");
    expect_failure("{\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]}}",
                   "path.json: field 'format': required field is missing");
    expect_failure("{\"format\": \"tessera-scene\", \"version\": 1, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'format': expected \"tessera-camera-path\", got \"tessera-scene\"");
    expect_failure("{\"format\": \"tessera-camera-path\", \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'version': required field is missing");
    expect_failure("{\"format\": \"tessera-camera-path\", \"version\": 2, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'version': unsupported version 2 (this build reads version 1)");
}

Test(camera_path, unknown_fields_are_errors)
{
    expect_failure("{" HEADER "\"speed\": 2, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'speed': unknown field (expected one of: format, version, interpolation, "
                   "loop, keyframes)");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, 1) ", {\"time\": 1, \"eye\": [1, 1, 1], "
                   "\"look_at\": [0, 0, 0], \"zoom\": 2}]}",
                   "path.json: field 'keyframes[1].zoom': unknown field (expected one of: time, eye, look_at, up, "
                   "fov_deg)");
}

Test(camera_path, missing_or_empty_keyframes_are_errors)
{
    expect_failure("{" HEADER "\"loop\": false}", "path.json: field 'keyframes': required field is missing");
    expect_failure("{" HEADER "\"keyframes\": []}", "path.json: field 'keyframes': needs at least 1 keyframe");
    expect_failure("{" HEADER "\"keyframes\": [{\"eye\": [1, 1, 1], \"look_at\": [0, 0, 0]}]}",
                   "path.json: field 'keyframes[0].time': required field is missing");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"look_at\": [0, 0, 0]}]}",
                   "path.json: field 'keyframes[0].eye': required field is missing");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [0, 0, 0]}]}",
                   "path.json: field 'keyframes[0].look_at': required field is missing");
}

Test(camera_path, times_must_increase_strictly)
{
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, 1) ", " KEY(1, 2) ", " KEY(1.5, 3) ", " KEY(1.5, 4) "]}",
                   "path.json: field 'keyframes[3].time': must be greater than keyframes[2].time (1.5), got 1.5");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(2, 1) ", " KEY(1, 2) "]}",
                   "path.json: field 'keyframes[1].time': must be greater than keyframes[0].time (2), got 1");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(-1, 1) "]}",
                   "path.json: field 'keyframes[0].time': must be >= 0, got -1");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0.1, 1) ", " KEY(0.10000000000000001, 2) "]}",
                   "must be greater than keyframes[0].time (0.1), got 0.1");
}

Test(camera_path, invalid_cameras_are_errors)
{
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, 1) ", {\"time\": 1, \"eye\": [1, 2, 3], "
                   "\"look_at\": [1, 2, 3]}]}",
                   "path.json: field 'keyframes[1]': camera: eye and look_at are the same point");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [0, 5, 0], \"look_at\": [0, 0, 0]}]}",
                   "path.json: field 'keyframes[0]': camera: up is parallel to the view direction");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], "
                   "\"up\": [0, 0, 0]}]}",
                   "path.json: field 'keyframes[0]': camera: up is the zero vector");
}

Test(camera_path, fov_must_be_inside_0_180)
{
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], "
                   "\"fov_deg\": 180}]}",
                   "path.json: field 'keyframes[0].fov_deg': must be in (0, 180), got 180");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], "
                   "\"fov_deg\": 0}]}",
                   "path.json: field 'keyframes[0].fov_deg': must be in (0, 180), got 0");
}

Test(camera_path, non_finite_numbers_are_errors)
{
    expect_failure("{" HEADER "\"keyframes\": [" KEY(NaN, 1) "]}",
                   "path.json: field 'keyframes[0].time': expected a finite number, got nan");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(Infinity, 1) "]}",
                   "path.json: field 'keyframes[0].time': expected a finite number, got inf");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(1e999, 1) "]}",
                   "path.json: field 'keyframes[0].time': expected a finite number");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, NaN) "]}",
                   "path.json: field 'keyframes[0].eye[0]': expected a finite number, got nan");
    expect_failure("{" HEADER "\"keyframes\": [" KEY(0, 1e39) "]}",
                   "path.json: field 'keyframes[0].eye[0]': 1e+39 is out of range for a float");
}

Test(camera_path, wrong_types_are_errors)
{
    expect_failure("{" HEADER "\"keyframes\": {}}", "path.json: field 'keyframes': expected an array, got object");
    expect_failure("{" HEADER "\"keyframes\": [3]}", "path.json: field 'keyframes[0]': expected an object, got number");
    expect_failure("{" HEADER "\"keyframes\": [" KEY("0", 1) "]}",
                   "path.json: field 'keyframes[0].time': expected a number, got string");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [1, 2], \"look_at\": [0, 0, 0]}]}",
                   "path.json: field 'keyframes[0].eye': expected an array of 3 numbers, got 2 elements");
    expect_failure("{" HEADER "\"keyframes\": [{\"time\": 0, \"eye\": [1, 2, 3], \"look_at\": null}]}",
                   "path.json: field 'keyframes[0].look_at': expected an array of 3 numbers, got null");
    expect_failure("{" HEADER "\"loop\": 1, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'loop': expected a boolean, got number");
    expect_failure("{" HEADER "\"interpolation\": \"cubic\", \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'interpolation': unknown value 'cubic' (expected one of: catmull-rom, linear)");
    expect_failure("{\"format\": 7, \"version\": 1, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'format': expected a string, got number");
    expect_failure("{\"format\": \"tessera-camera-path\", \"version\": \"1\", \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'version': expected a number, got string");
}

Test(camera_path, duplicate_keys_are_errors)
{
    expect_failure("{" HEADER "\n\"keyframes\": [{\"time\": 0, \"eye\": [1, 1, 1], \"time\": 1, "
                   "\"look_at\": [0, 0, 0]}]}",
                   "path.json:2:45: duplicate key 'time' in a JSON object");
    expect_failure("{" HEADER "\"loop\": false, \"loop\": true, \"keyframes\": [" KEY(0, 1) "]}",
                   "duplicate key 'loop'");
}

Test(camera_path, loop_needs_two_keys_and_a_closing_key)
{
    expect_failure("{" HEADER "\"loop\": true, \"keyframes\": [" KEY(0, 1) "]}",
                   "path.json: field 'loop': needs at least 2 keyframes");
    expect_failure("{" HEADER "\"loop\": true, \"keyframes\": [" KEY(0, 1) ", " KEY(1, 2) ", " KEY(2, 3) "]}",
                   "path.json: field 'keyframes[2]': with \"loop\": true the last keyframe must repeat the camera "
                   "of keyframes[0]");
    expect_failure("{" HEADER "\"loop\": true, \"keyframes\": [" KEY(0, 1) ", " KEY(1, 2) ", "
                   "{\"time\": 2, \"eye\": [1, 1, 5], \"look_at\": [0, 0, 0], \"fov_deg\": 41}]}",
                   "must repeat the camera of keyframes[0]");
    camera_path p = parse_ok("{" HEADER "\"loop\": true, \"keyframes\": [" KEY(0, 1) ", " KEY(1, 2) ", " KEY(2, 1)
                             "]}");
    cr_assert(p.loop);
    camera_path_free(&p);
}

Test(camera_path, missing_file_and_directory_are_errors)
{
    char path[256];
    camera_path p;
    tess_error err = {{0}};
    cr_assert_not(camera_path_load(tmp_file(path, sizeof path, "absent.json"), &p, &err));
    cr_assert(strstr(err.msg, path) && strstr(err.msg, "cannot open: No such file"), "%s", err.msg);
    cr_assert_eq(p.count, 0);
    tess_error err2 = {{0}};
    cr_assert_not(camera_path_load(tmp_dir, &p, &err2));
    cr_assert(strstr(err2.msg, "cannot open: not a regular file"), "%s", err2.msg);
}

Test(camera_path, file_errors_name_the_file)
{
    char path[256];
    put_file(tmp_file(path, sizeof path, "bad.json"), "{" HEADER "\"keyframes\": [" KEY(1, 1) ", " KEY(1, 2) "]}");
    camera_path p;
    tess_error err = {{0}};
    cr_assert_not(camera_path_load(path, &p, &err));
    char want[512];
    snprintf(want, sizeof want, "%s: field 'keyframes[1].time': must be greater than keyframes[0].time (1), got 1",
             path);
    cr_assert_str_eq(err.msg, want);
}

Test(camera_path, text_need_not_be_nul_terminated)
{
    const char text[] = "{" HEADER "\"keyframes\": [" KEY(0, 1) "]}garbage";
    camera_path p;
    tess_error err = {{0}};
    cr_assert(camera_path_parse("mem", text, strlen(text) - strlen("garbage"), &p, &err), "%s", err.msg);
    camera_path_free(&p);
}

Test(camera_path, null_error_pointer_is_fine)
{
    camera_path p;
    cr_assert_not(camera_path_parse("x", "{}", 2, &p, NULL));
    cr_assert_not(camera_path_load("/nonexistent/path.json", &p, NULL));
    camera_desc c = cam(v3(0.f, 0.f, 1.f), v3(0.f, 0.f, 1.f), v3(0.f, 1.f, 0.f), 40.f);
    cr_assert_not(camera_path_append(&p, 0.0, &c, NULL));
}

/* ---- evaluation ------------------------------------------------------------ */

Test(camera_path, eval_at_key_times_is_exact)
{
    for (int mode = 0; mode < 4; mode++) {
        camera_path p = curved_path(mode & 1 ? CAMERA_PATH_LINEAR : CAMERA_PATH_CATMULL_ROM, mode & 2);
        for (size_t k = 0; k < p.count; k++) {
            camera_desc got = camera_path_eval(&p, p.keys[k].time_s);
            cr_assert(same_bits(got, p.keys[k].camera), "mode %d key %zu", mode, k);
        }
        camera_path_free(&p);
    }
}

Test(camera_path, linear_midpoint_is_exact)
{
    camera_path p = {.interp = CAMERA_PATH_LINEAR};
    camera_desc a = cam(v3(1.f, 2.f, 3.f), v3(0.1f, 0.2f, 0.3f), v3(0.f, 1.f, 0.f), 30.f);
    camera_desc b = cam(v3(-3.f, 4.5f, 7.25f), v3(0.7f, -0.3f, 0.9f), v3(0.2f, 1.f, 0.f), 50.f);
    append_ok(&p, 1.0, a);
    append_ok(&p, 3.0, b);
    camera_desc m = camera_path_eval(&p, 2.0);
    cr_assert_eq(m.eye.x, (float)((1.0 + -3.0) / 2));
    cr_assert_eq(m.eye.y, (float)((2.0 + 4.5) / 2));
    cr_assert_eq(m.eye.z, (float)((3.0 + 7.25) / 2));
    cr_assert_eq(m.look_at.x, (float)(((double)0.1f + (double)0.7f) / 2));
    cr_assert_eq(m.look_at.y, (float)(((double)0.2f + (double)-0.3f) / 2));
    cr_assert_eq(m.look_at.z, (float)(((double)0.3f + (double)0.9f) / 2));
    cr_assert_eq(m.up.x, 0.1f);
    cr_assert_eq(m.up.y, 1.f);
    cr_assert_eq(m.fov_deg, 40.f);
    /* a quarter of the way */
    camera_desc q = camera_path_eval(&p, 1.5);
    cr_assert_eq(q.eye.x, 0.f);
    cr_assert_eq(q.fov_deg, 35.f);
    camera_path_free(&p);
}

Test(camera_path, eval_is_continuous_between_keys)
{
    for (int mode = 0; mode < 4; mode++) {
        camera_path p = curved_path(mode & 1 ? CAMERA_PATH_LINEAR : CAMERA_PATH_CATMULL_ROM, mode & 2);
        const double step = 1e-4;
        camera_desc prev = camera_path_eval(&p, 0.0);
        for (double t = step; t <= 5.0; t += step) {
            camera_desc c = camera_path_eval(&p, t);
            /* speeds stay below ~40 units/s on this path */
            cr_assert_lt(dist(c.eye, prev.eye), 40.0 * step + 1e-5, "mode %d eye jumps at t=%g", mode, t);
            cr_assert_lt(dist(c.look_at, prev.look_at), 40.0 * step + 1e-5, "mode %d look_at jumps at %g", mode, t);
            cr_assert_lt(fabs(c.fov_deg - prev.fov_deg), 40.0 * step + 1e-4, "mode %d fov jumps at %g", mode, t);
            prev = c;
        }
        camera_path_free(&p);
    }
}

/* One-sided difference quotients of the eye at t, from the left and the right. */
static void eye_slopes(const camera_path *p, double t, double h, vec3 *left, vec3 *right)
{
    vec3 at = camera_path_eval(p, t).eye;
    *left = v3_scale(v3_sub(at, camera_path_eval(p, t - h).eye), (float)(1.0 / h));
    *right = v3_scale(v3_sub(camera_path_eval(p, t + h).eye, at), (float)(1.0 / h));
}

Test(camera_path, catmull_rom_is_c1_at_keys)
{
    const double h = 1e-4;
    camera_path p = curved_path(CAMERA_PATH_CATMULL_ROM, false);
    for (size_t k = 1; k + 1 < p.count; k++) {
        vec3 left, right;
        eye_slopes(&p, p.keys[k].time_s, h, &left, &right);
        cr_assert_gt(v3_length(left), 1.0, "key %zu: the path moves", k);
        cr_assert_lt(dist(left, right), 0.03, "key %zu: slope jumps by %g", k, dist(left, right));
    }
    camera_path_free(&p);
    /* the same measure sees the kinks of linear interpolation */
    camera_path lin = curved_path(CAMERA_PATH_LINEAR, false);
    vec3 left, right;
    eye_slopes(&lin, lin.keys[2].time_s, h, &left, &right);
    cr_assert_gt(dist(left, right), 1.0);
    camera_path_free(&lin);
}

Test(camera_path, catmull_rom_tangent_matches_the_documented_formula)
{
    camera_path p = curved_path(CAMERA_PATH_CATMULL_ROM, false);
    size_t k = 2;
    double t0 = p.keys[k - 1].time_s, t1 = p.keys[k].time_s, t2 = p.keys[k + 1].time_s;
    vec3 p0 = p.keys[k - 1].camera.eye, p1 = p.keys[k].camera.eye, p2 = p.keys[k + 1].camera.eye;
    vec3 left, right;
    eye_slopes(&p, t1, 1e-5, &left, &right);
    float want[3], got[3] = {0.5f * (left.x + right.x), 0.5f * (left.y + right.y), 0.5f * (left.z + right.z)};
    for (int a = 0; a < 3; a++) {
        double q0 = v3_get(p0, a), q1 = v3_get(p1, a), q2 = v3_get(p2, a);
        want[a] = (float)(((q2 - q1) / (t2 - t1) * (t1 - t0) + (q1 - q0) / (t1 - t0) * (t2 - t1)) / (t2 - t0));
        cr_assert_lt(fabsf(got[a] - want[a]), 0.02f, "axis %d: slope %g, formula %g", a, got[a], want[a]);
    }
    camera_path_free(&p);
}

Test(camera_path, collinear_keys_at_constant_speed_give_a_straight_line)
{
    const vec3 start = v3(-4.f, 1.f, 2.f), velocity = v3(1.5f, 0.25f, -0.5f);
    const vec3 target = v3(0.f, 0.5f, -3.f), target_velocity = v3(-0.5f, 0.f, 0.25f);
    camera_path p = {0};
    for (int k = 0; k < 6; k++) {
        float t = 0.5f * (float)k;
        append_ok(&p, t, cam(v3_add(start, v3_scale(velocity, t)), v3_add(target, v3_scale(target_velocity, t)),
                             v3(0.f, 1.f, 0.f), 40.f));
    }
    for (double t = 0.0; t <= 2.5; t += 0.01) {
        camera_desc c = camera_path_eval(&p, t);
        vec3 eye = v3_add(start, v3_scale(velocity, (float)t));
        vec3 look = v3_add(target, v3_scale(target_velocity, (float)t));
        cr_assert_lt(dist(c.eye, eye), 2e-6, "t=%g: eye off the line by %g", t, dist(c.eye, eye));
        cr_assert_lt(dist(c.look_at, look), 2e-6, "t=%g: look_at off the line by %g", t, dist(c.look_at, look));
    }
    camera_path_free(&p);
}

Test(camera_path, constant_speed_survives_uneven_key_times)
{
    static const double times[] = {0.0, 0.1, 0.9, 1.0, 2.6};
    camera_path p = {0};
    for (int k = 0; k < 5; k++)
        append_ok(&p, times[k], cam(v3(2.f * (float)times[k], 1.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f));
    for (double t = 0.0; t <= 2.6; t += 0.013)
        cr_assert_lt(fabs(camera_path_eval(&p, t).eye.x - 2.0 * t), 2e-6, "t=%g", t);
    camera_path_free(&p);
}

Test(camera_path, times_outside_the_keys_are_clamped_without_loop)
{
    camera_path p = curved_path(CAMERA_PATH_CATMULL_ROM, false);
    cr_assert_eq(camera_path_duration(&p), 5.0);
    cr_assert(same_bits(camera_path_eval(&p, -1.0), p.keys[0].camera));
    cr_assert(same_bits(camera_path_eval(&p, -INFINITY), p.keys[0].camera));
    cr_assert(same_bits(camera_path_eval(&p, 5.5), p.keys[p.count - 1].camera));
    cr_assert(same_bits(camera_path_eval(&p, 1e300), p.keys[p.count - 1].camera));
    cr_assert(same_bits(camera_path_eval(&p, NAN), p.keys[0].camera));
    camera_path_free(&p);
}

Test(camera_path, looping_wraps_and_is_c1_at_the_seam)
{
    camera_path p = curved_path(CAMERA_PATH_CATMULL_ROM, true);
    double d = camera_path_duration(&p);
    cr_assert_eq(d, 5.0);
    for (double t = 0.05; t < 5.0; t += 0.37) {
        camera_desc c = camera_path_eval(&p, t);
        for (int wraps = -2; wraps <= 3; wraps++) {
            camera_desc w = camera_path_eval(&p, t + wraps * d);
            cr_assert_lt(dist(c.eye, w.eye), 1e-5, "t=%g + %d periods", t, wraps);
            cr_assert_lt(dist(c.look_at, w.look_at), 1e-5);
            cr_assert_lt(fabsf(c.fov_deg - w.fov_deg), 1e-4f);
        }
    }
    cr_assert(same_bits(camera_path_eval(&p, 10.0), p.keys[0].camera));
    cr_assert(same_bits(camera_path_eval(&p, -5.0), p.keys[0].camera));
    cr_assert(same_bits(camera_path_eval(&p, INFINITY), p.keys[0].camera));
    /* the seam: leaving key 0 and arriving at the closing key at the same velocity */
    const double h = 1e-4;
    vec3 at = p.keys[0].camera.eye;
    vec3 left = v3_scale(v3_sub(at, camera_path_eval(&p, d - h).eye), (float)(1.0 / h));
    vec3 right = v3_scale(v3_sub(camera_path_eval(&p, h).eye, at), (float)(1.0 / h));
    cr_assert_gt(v3_length(left), 1.0);
    cr_assert_lt(dist(left, right), 0.03, "slope jumps by %g at the seam", dist(left, right));
    camera_path_free(&p);
}

Test(camera_path, evaluated_cameras_are_always_valid)
{
    /* up turns over (passes through zero), and eye and look_at swap places */
    camera_path p = {.interp = CAMERA_PATH_LINEAR};
    camera_desc a = cam(v3(0.f, 0.f, 5.f), v3(0.f, 0.f, -5.f), v3(0.f, 1.f, 0.f), 40.f);
    camera_desc b = cam(v3(0.f, 0.f, -5.f), v3(0.f, 0.f, 5.f), v3(0.f, -1.f, 0.f), 60.f);
    append_ok(&p, 0.0, a);
    append_ok(&p, 2.0, b);
    for (int mode = 0; mode < 2; mode++) {
        p.interp = mode ? CAMERA_PATH_CATMULL_ROM : CAMERA_PATH_LINEAR;
        for (double t = 0.0; t <= 2.0; t += 1.0 / 64) {
            camera_desc c = camera_path_eval(&p, t);
            tess_error err = {{0}};
            cr_assert(camera_validate(&c, &err), "mode %d t=%g: %s", mode, t, err.msg);
        }
        /* at the midpoint eye == look_at and up == 0: the nearer key (s = 0.5 counts as the later key) */
        cr_assert(same_bits(camera_path_eval(&p, 1.0), b));
        cr_assert_gt(camera_path_eval(&p, 1.0 - 1.0 / 1024).eye.z, 0.f, "just before: interpolated");
    }
    camera_path_free(&p);
}

Test(camera_path, degenerate_up_falls_back_to_the_nearer_key)
{
    /* view along -Z throughout; up turns from +Y to -Y through 0 at t = 1 */
    camera_path p = {.interp = CAMERA_PATH_LINEAR};
    append_ok(&p, 0.0, cam(v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f));
    append_ok(&p, 2.0, cam(v3(0.f, 0.f, 6.f), v3(0.f, 0.f, 0.f), v3(0.f, -1.f, 0.f), 40.f));
    camera_desc before = camera_path_eval(&p, 0.5), mid = camera_path_eval(&p, 1.0);
    cr_assert_eq(before.up.y, 0.5f, "interpolated up is used as it is");
    cr_assert_eq(mid.up.y, -1.f, "zero up: the nearer key's (s = 0.5: the later key)");
    cr_assert_eq(mid.eye.z, 5.5f, "only up falls back");
    camera_path_free(&p);
}

Test(camera_path, empty_path_evaluates_to_a_valid_camera)
{
    camera_path p = {0};
    camera_desc c = camera_path_eval(&p, 1.0);
    cr_assert(camera_validate(&c, NULL));
    cr_assert_eq(camera_path_duration(&p), 0.0);
}

/* ---- recording and saving ---------------------------------------------------- */

Test(camera_path, append_rejects_bad_times_and_cameras)
{
    camera_path p = {0};
    camera_desc c = cam(v3(0.f, 1.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f);
    append_ok(&p, 1.0, c);
    append_ok(&p, 1.5, c);
    tess_error err = {{0}};
    cr_assert_not(camera_path_append(&p, 1.5, &c, &err));
    cr_assert_str_eq(err.msg, "camera path: time 1.5 s is not after the last keyframe's (1.5 s)");
    tess_error err2 = {{0}};
    cr_assert_not(camera_path_append(&p, 0.5, &c, &err2));
    cr_assert(strstr(err2.msg, "is not after"), "%s", err2.msg);
    tess_error err3 = {{0}};
    cr_assert_not(camera_path_append(&p, NAN, &c, &err3));
    cr_assert(strstr(err3.msg, "must be finite and >= 0"), "%s", err3.msg);
    camera_path q = {0};
    tess_error err4 = {{0}};
    cr_assert_not(camera_path_append(&q, -1.0, &c, &err4));
    cr_assert(strstr(err4.msg, "time -1 s must be finite and >= 0"), "%s", err4.msg);
    camera_desc bad = c;
    bad.look_at = bad.eye;
    tess_error err5 = {{0}};
    cr_assert_not(camera_path_append(&p, 2.0, &bad, &err5));
    cr_assert_str_eq(err5.msg, "camera path: keyframe at 2 s: camera: eye and look_at are the same point");
    cr_assert_eq(p.count, 2, "failed appends leave the path as it was");
    cr_assert_eq(q.count, 0);
    /* growth past the first allocation */
    for (int i = 0; i < 100; i++)
        append_ok(&p, 2.0 + i, c);
    cr_assert_eq(p.count, 102);
    cr_assert_eq(p.keys[101].time_s, 101.0);
    camera_path_free(&p);
}

/* Keys with values that print awkwardly: thirds, tiny, huge, negative zero. */
static camera_path awkward_path(void)
{
    camera_path p = {.interp = CAMERA_PATH_LINEAR};
    append_ok(&p, -0.0, cam(v3(1.f / 3.f, -0.f, 0.1f), v3(1e-7f, 2.5e-38f, -0.f), v3(0.f, 1.f, 1e-3f), 33.333332f));
    append_ok(&p, 0.1 + 0.2, cam(v3(3e7f, 16777217.f, -1.f / 7.f), v3(0.f, 0.f, 0.f), v3(0.1f, 0.9f, 0.f), 1e-3f));
    append_ok(&p, 1.0 / 3.0, cam(v3(123456.79f, 2.f, 3.f), v3(-1.f, -2.f, -3.f), v3(0.f, 1.f, 0.f), 179.99998f));
    append_ok(&p, 12345.678901234567, cam(v3(FLT_MIN, 1.f, 1.f), v3(1.f, 1e18f, 0.f), v3(1.f, 0.f, 0.f), 90.f));
    return p;
}

Test(camera_path, save_then_load_gives_bit_identical_keys)
{
    char path[256], again[256];
    camera_path p = awkward_path();
    tess_error err = {{0}};
    cr_assert(camera_path_save(&p, tmp_file(path, sizeof path, "saved.json"), &err), "%s", err.msg);
    camera_path q;
    cr_assert(camera_path_load(path, &q, &err), "%s", err.msg);
    cr_assert_eq(q.count, p.count);
    cr_assert_eq(q.interp, CAMERA_PATH_LINEAR);
    cr_assert_not(q.loop);
    cr_assert_eq(memcmp(q.keys, p.keys, p.count * sizeof *p.keys), 0, "keys differ after the round trip");
    cr_assert(signbit(q.keys[0].time_s), "negative zero survives");
    /* saving what was loaded gives the same file */
    cr_assert(camera_path_save(&q, tmp_file(again, sizeof again, "again.json"), &err), "%s", err.msg);
    char a[8192], b[8192];
    support_read_text(path, a, sizeof a);
    support_read_text(again, b, sizeof b);
    cr_assert_str_eq(a, b);
    cr_assert(strstr(a, "\"time\": 0.30000000000000004"), "shortest exact digits:\n%s", a);
    cr_assert(strstr(a, "\"eye\": [0.33333334, -0.0, 0.1]"), "shortest exact digits:\n%s", a);
    camera_path_free(&p);
    camera_path_free(&q);
}

Test(camera_path, save_round_trips_loops_and_catmull_rom)
{
    char path[256];
    camera_path p = curved_path(CAMERA_PATH_CATMULL_ROM, true);
    tess_error err = {{0}};
    cr_assert(camera_path_save(&p, tmp_file(path, sizeof path, "loop.json"), &err), "%s", err.msg);
    camera_path q;
    cr_assert(camera_path_load(path, &q, &err), "%s", err.msg);
    cr_assert(q.loop);
    cr_assert_eq(q.interp, CAMERA_PATH_CATMULL_ROM);
    cr_assert_eq(memcmp(q.keys, p.keys, p.count * sizeof *p.keys), 0);
    for (double t = -1.0; t < 7.0; t += 0.1)
        cr_assert(same_bits(camera_path_eval(&p, t), camera_path_eval(&q, t)), "t=%g", t);
    camera_path_free(&p);
    camera_path_free(&q);
}

Test(camera_path, save_refuses_paths_that_would_not_load)
{
    char path[256];
    tmp_file(path, sizeof path, "refused.json");
    camera_path empty = {0};
    tess_error err = {{0}};
    cr_assert_not(camera_path_save(&empty, path, &err));
    cr_assert(strstr(err.msg, "not saved: camera path: field 'keyframes': needs at least 1 keyframe"), "%s",
              err.msg);
    camera_path unclosed = curved_path(CAMERA_PATH_CATMULL_ROM, false);
    unclosed.loop = true; /* the last key does not repeat the first */
    tess_error err2 = {{0}};
    cr_assert_not(camera_path_save(&unclosed, path, &err2));
    cr_assert(strstr(err2.msg, "must repeat the camera of keyframes[0]"), "%s", err2.msg);
    cr_assert_neq(access(path, F_OK), 0, "nothing was written");
    tess_error err3 = {{0}};
    unclosed.loop = false;
    cr_assert_not(camera_path_save(&unclosed, "/nonexistent/dir/x.json", &err3));
    cr_assert(strstr(err3.msg, "/nonexistent/dir/x.json: cannot write: No such file"), "%s", err3.msg);
    camera_path_free(&unclosed);
}

/* ---- the example paths ------------------------------------------------------- */

/* Distance from p to the box [lo, hi] (0 inside). */
static double box_distance(vec3 p, vec3 lo, vec3 hi)
{
    double dx = fmax(fmax(lo.x - p.x, p.x - hi.x), 0.0), dy = fmax(fmax(lo.y - p.y, p.y - hi.y), 0.0);
    double dz = fmax(fmax(lo.z - p.z, p.z - hi.z), 0.0);
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static void mesh_box(const mesh *m, vec3 *lo, vec3 *hi)
{
    *lo = v3(INFINITY, INFINITY, INFINITY);
    *hi = v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        vec3 v = v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
        *lo = v3_min(*lo, v);
        *hi = v3_max(*hi, v);
    }
}

/* Every camera of the path is valid, above the ground, clear of the default
 * scene's spheres and of the torus's box, and looks at the scene. */
static void check_path_in_default_scene(const char *file, const camera_path *p, const scene *s)
{
    vec3 torus_lo, torus_hi;
    cr_assert_eq(s->mesh_count, 2, "default scene: ground and torus");
    mesh_box(s->meshes[1]->mesh, &torus_lo, &torus_hi);
    double end = p->keys[p->count - 1].time_s;
    for (double t = p->keys[0].time_s - 1.0; t <= end + 1.0; t += 0.01) {
        camera_desc c = camera_path_eval(p, t);
        tess_error err = {{0}};
        cr_assert(camera_validate(&c, &err), "%s t=%g: %s", file, t, err.msg);
        cr_assert_gt(c.eye.y, 0.5f, "%s t=%g: eye near or below the ground", file, t);
        cr_assert_gt(box_distance(c.eye, torus_lo, torus_hi), 0.3, "%s t=%g: eye in the torus", file, t);
        for (uint32_t i = 0; i < s->spheres.count; i++) {
            vec3 centre = v3(s->spheres.center_x[i], s->spheres.center_y[i], s->spheres.center_z[i]);
            cr_assert_gt(dist(c.eye, centre), s->spheres.radius[i] + 0.3, "%s t=%g: eye in sphere %u", file, t, i);
        }
        cr_assert_lt(v3_length(c.look_at), 2.f, "%s t=%g: looks away from the scene", file, t);
        cr_assert_lt(v3_length(c.eye), 20.f, "%s t=%g: too far away", file, t);
    }
}

Test(camera_path, example_paths_load_and_fly_clear_of_the_default_scene)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert_not_null(s, "%s", err.msg);
    DIR *d = opendir(EXAMPLE_PATHS_DIR);
    cr_assert_not_null(d, "cannot list %s (run from tests/)", EXAMPLE_PATHS_DIR);
    struct dirent *e;
    int loaded = 0;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 5, ".json") != 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "%s/%s", EXAMPLE_PATHS_DIR, e->d_name);
        camera_path p;
        cr_assert(camera_path_load(path, &p, &err), "%s", err.msg);
        cr_assert_gt(camera_path_duration(&p), 1.0, "%s", path);
        check_path_in_default_scene(path, &p, s);
        camera_path_free(&p);
        loaded++;
    }
    closedir(d);
    scene_destroy(s);
    cr_assert_geq(loaded, 3, "expected orbit, flythrough and tour");
}

Test(camera_path, example_paths_have_the_documented_shapes)
{
    static const struct {
        const char *name;
        double duration_s;
        bool loop;
    } want[] = {{"orbit.json", 8.0, true}, {"flythrough.json", 6.5, false}, {"tour.json", 20.0, true}};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        char path[256];
        snprintf(path, sizeof path, "%s/%s", EXAMPLE_PATHS_DIR, want[i].name);
        camera_path p;
        tess_error err = {{0}};
        cr_assert(camera_path_load(path, &p, &err), "%s", err.msg);
        cr_assert_eq(camera_path_duration(&p), want[i].duration_s, "%s", path);
        cr_assert_eq(p.loop, want[i].loop, "%s", path);
        camera_path_free(&p);
    }
}
