/* test_navigate.c - camera motions (input/navigate.h): orbit (distances kept,
 * pivot fixed in the image, inverse yaw, conventions, elevation clamp), pan
 * (grab: the dragged point follows the cursor), dolly (composition, point
 * fixed in the image, scale invariance), flight, fly-to, blend and ease, the
 * refusal of invalid motions, and the plane ray against the renderer's basis
 * (engine/base/camera.h). Plane positions are measured through camera_basis_window,
 * independently of navigate.c's own frame. Random cases come from a fixed
 * seed per test, so every run checks the same cameras. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "engine/base/camera.h"
#include "input/navigate.h"

static const double pi = 3.14159265358979323846;
/* Largest relative rounding error of one float rounding (half an ulp). */
static const double float_half_ulp = 1.0 / 16777216.0; /* 2^-24 */

/* ---- double vectors and a deterministic generator ------------------------ */

typedef struct d3 {
    double x, y, z;
} d3;

static d3 d(vec3 a) { return (d3){a.x, a.y, a.z}; }
static vec3 to_f(d3 a) { return v3((float)a.x, (float)a.y, (float)a.z); }
static d3 add(d3 a, d3 b) { return (d3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static d3 sub(d3 a, d3 b) { return (d3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static d3 scale(d3 a, double s) { return (d3){a.x * s, a.y * s, a.z * s}; }
static double dot(d3 a, d3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static d3 cross(d3 a, d3 b) { return (d3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
static double len(d3 a) { return sqrt(dot(a, a)); }
static d3 unit(d3 a) { return scale(a, 1.0 / len(a)); }
static double dist(vec3 a, vec3 b) { return len(sub(d(a), d(b))); }

static uint64_t rng_state;

static void rng_seed(uint64_t seed) { rng_state = seed * 2654435761u + 1u; }

/* Uniform in [lo, hi): a 64-bit LCG, top 53 bits. */
static double rnd(double lo, double hi)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * ((double)(rng_state >> 11) / 9007199254740992.0);
}

static d3 rnd_unit(void)
{
    for (;;) {
        d3 v = {rnd(-1, 1), rnd(-1, 1), rnd(-1, 1)};
        double l = len(v);
        if (l > 0.1 && l <= 1.0)
            return scale(v, 1.0 / l);
    }
}

/* ---- cameras ------------------------------------------------------------- */

static camera_desc cam(vec3 eye, vec3 look_at, vec3 up, float fov_deg)
{
    return (camera_desc){.eye = eye, .look_at = look_at, .up = up, .fov_deg = fov_deg};
}

static bool same_bits(camera_desc a, camera_desc b) { return memcmp(&a, &b, sizeof a) == 0; }

static bool valid(const camera_desc *c) { return camera_validate(c, NULL); }

/* Elevation of the view above the plane normal to the up hint, degrees. */
static double elevation_deg(const camera_desc *c)
{
    double s = dot(unit(sub(d(c->look_at), d(c->eye))), unit(d(c->up)));
    return asin(fmax(-1.0, fmin(1.0, s))) * 180.0 / pi;
}

/* A random valid camera: eye in [-5, 5]^3, view distance in [2, 15], the view
 * within 80 degrees of level, an up hint that is not always unit nor
 * orthogonal to the view, fov in [30, 100]. Coordinates stay within a few view
 * distances, so rounding them to float moves the image by well under 1e-5
 * plane units (the fixed tolerances below rely on that). */
static camera_desc rnd_camera(void)
{
    static const vec3 ups[] = {{0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}, {0.1f, 2.f, -0.3f}, {-0.5f, 0.2f, 3.f}};
    for (;;) {
        vec3 up = ups[(int)rnd(0, 4)];
        d3 view = rnd_unit();
        double s = dot(view, unit(d(up)));
        if (fabs(s) > sin(80.0 * pi / 180.0))
            continue;
        d3 eye = {rnd(-5, 5), rnd(-5, 5), rnd(-5, 5)};
        camera_desc c = cam(to_f(eye), to_f(add(eye, scale(view, rnd(2, 15)))), up, (float)rnd(30, 100));
        if (valid(&c))
            return c;
    }
}

/* The renderer's basis for the whole plane (directions only: the image size
 * does not enter them). */
static camera_basis plane_basis(const camera_desc *c, float aspect)
{
    return camera_basis_window(c, aspect, CAMERA_WINDOW_FULL, 16, 16);
}

/* World point at plane point (sx, sy) and depth `depth` along the renderer's forward. */
static d3 unproject(const camera_desc *c, float aspect, double sx, double sy, double depth)
{
    camera_basis b = plane_basis(c, aspect);
    d3 dir = add(d(b.forward), add(scale(d(b.right), sx), scale(d(b.up), sy)));
    return add(d(c->eye), scale(dir, depth));
}

/* Plane point (and depth) of world point p: p - eye = depth * (forward + sx
 * right + sy up) in the renderer's basis, whose three vectors are orthogonal. */
static void project(const camera_desc *c, float aspect, d3 p, double *sx, double *sy, double *depth)
{
    camera_basis b = plane_basis(c, aspect);
    d3 q = sub(p, d(c->eye)), right = d(b.right), up = d(b.up);
    double z = dot(q, d(b.forward));
    *sx = dot(q, right) / (z * dot(right, right));
    *sy = dot(q, up) / (z * dot(up, up));
    if (depth)
        *depth = z;
}

/* Bound on how far rounding c's eye and look_at to float moves the image of
 * a point at depth `depth` near plane point (sx, sy), in plane units. Each
 * rounding moves a point by at most 2^-24 times its length. The eye's shift
 * moves the image by shift / depth; the view direction turns by up to (eye's
 * + look_at's shift) / view distance, which moves the image of a direction at
 * tangent t by (1 + t^2) times the turn, and rolls the frame by up to the turn
 * over sin(view, up), which moves it by |t| times the roll. Plane units are
 * tangents over tan(fov/2) (times the aspect for sx). */
static double image_rounding_bound(const camera_desc *c, float aspect, double depth, double sx, double sy)
{
    double eye_shift = float_half_ulp * len(d(c->eye)), at_shift = float_half_ulp * len(d(c->look_at));
    d3 f = unit(sub(d(c->look_at), d(c->eye)));
    double sin_view_up = len(cross(f, unit(d(c->up))));
    double tan_half = tan(0.5 * c->fov_deg * pi / 180.0);
    double tx = sx * tan_half * aspect, ty = sy * tan_half, t2 = tx * tx + ty * ty;
    double turn = (eye_shift + at_shift) / dist(c->eye, c->look_at);
    double move = eye_shift / depth + turn * (1.0 + t2) + turn / sin_view_up * sqrt(t2);
    return move / (tan_half * fmin((double)aspect, 1.0));
}

/* A point in front of c, at plane point within [-0.8, 0.8]^2 and depth in [lo, hi]. */
static d3 rnd_point_in_view(const camera_desc *c, float aspect, double lo, double hi)
{
    return unproject(c, aspect, rnd(-0.8, 0.8), rnd(-0.8, 0.8), rnd(lo, hi));
}

/* ---- orbit --------------------------------------------------------------- */

/* One orbit moves a point by a rotation about the pivot, so its distance from
 * the pivot changes only by the final rounding of its coordinates: at most
 * 2^-24 * |x| for the rounded point x (a little more for slack). */
static double rounding_bound(vec3 x) { return 1.01 * float_half_ulp * len(d(x)) + 1e-30; }

Test(navigate, orbit_keeps_distances_over_composed_orbits)
{
    /* Each rounding moves the distance by a random amount, so 1000 composed
     * orbits drift as a random walk: per camera the drift is ~sqrt(1000) roundings,
     * a few 1e-7 relative here. Each step must stay within its rounding bound,
     * each final drift within 1000 such bounds, and the root mean square of the
     * final drifts (64 of them) under 1e-6: a systematic error (a rotation that
     * is not orthonormal, a pivot that drifts) fails them. */
    rng_seed(11);
    double sum_sq = 0.0, largest = 0.0;
    int samples = 0;
    for (int run = 0; run < 32; run++) {
        d3 pivot = {rnd(-1, 1), rnd(-1, 1), rnd(-1, 1)};
        d3 up = unit(add((d3){0, 1, 0}, scale(rnd_unit(), 0.3)));
        d3 eye, at;
        do {
            eye = add(pivot, scale(rnd_unit(), rnd(2, 10)));
            at = add(pivot, scale(rnd_unit(), rnd(1, 4)));
        } while (fabs(dot(unit(sub(at, eye)), up)) > 0.95);
        camera_desc c = cam(to_f(eye), to_f(at), to_f(up), 50.f), start = c;
        cr_assert(valid(&c));
        vec3 p = to_f(pivot);
        double eye_r0 = dist(c.eye, p), at_r0 = dist(c.look_at, p);
        for (int i = 0; i < 1000; i++) {
            double eye_r = dist(c.eye, p), at_r = dist(c.look_at, p);
            c = navigate_orbit(&c, p, rnd(-0.7, 0.7), rnd(-0.4, 0.4));
            cr_assert(valid(&c), "run %d step %d", run, i);
            cr_assert_leq(fabs(dist(c.eye, p) - eye_r), rounding_bound(c.eye), "run %d step %d", run, i);
            cr_assert_leq(fabs(dist(c.look_at, p) - at_r), rounding_bound(c.look_at), "run %d step %d", run, i);
        }
        double eye_rel = dist(c.eye, p) / eye_r0 - 1.0, at_rel = dist(c.look_at, p) / at_r0 - 1.0;
        cr_assert_leq(fabs(eye_rel), 1000.0 * rounding_bound(c.eye) / eye_r0);
        cr_assert_leq(fabs(at_rel), 1000.0 * rounding_bound(c.look_at) / at_r0);
        sum_sq += eye_rel * eye_rel + at_rel * at_rel;
        largest = fmax(largest, fmax(fabs(eye_rel), fabs(at_rel)));
        samples += 2;
        cr_assert_gt(dist(c.eye, start.eye), 1e-3, "run %d: the orbits did not move the camera", run);
    }
    double rms = sqrt(sum_sq / samples);
    cr_log_info("orbit distance drift after 1000 orbits: rms %.3g, largest %.3g", rms, largest);
    cr_assert_lt(rms, 1e-6, "rms relative drift %g (largest %g)", rms, largest);
}

Test(navigate, orbit_keeps_the_pivot_in_place_in_the_image)
{
    rng_seed(12);
    for (int i = 0; i < 500; i++) {
        camera_desc c = rnd_camera();
        float aspect = (float)rnd(0.5, 2.5);
        d3 pivot = rnd_point_in_view(&c, aspect, 1, 8);
        /* every fourth pitch is large enough to hit the elevation clamp */
        double pitch_rad = i % 4 == 0 ? rnd(-5, 5) : rnd(-0.5, 0.5);
        camera_desc o = navigate_orbit(&c, to_f(pivot), rnd(-3, 3), pitch_rad);
        cr_assert(valid(&o), "case %d", i);
        double sx0, sy0, sx1, sy1;
        d3 pf = d(to_f(pivot)); /* the pivot the orbit was given */
        project(&c, aspect, pf, &sx0, &sy0, NULL);
        project(&o, aspect, pf, &sx1, &sy1, NULL);
        cr_assert_lt(fabs(sx1 - sx0), 1e-5, "case %d: sx %.9g -> %.9g", i, sx0, sx1);
        cr_assert_lt(fabs(sy1 - sy0), 1e-5, "case %d: sy %.9g -> %.9g", i, sy0, sy1);
    }
}

Test(navigate, orbit_yaw_then_minus_yaw_returns)
{
    rng_seed(13);
    for (int i = 0; i < 300; i++) {
        camera_desc c = rnd_camera();
        vec3 pivot = to_f(rnd_point_in_view(&c, 1.5f, 1, 12));
        double yaw_rad = rnd(-3, 3);
        camera_desc there = navigate_orbit(&c, pivot, yaw_rad, 0.0);
        camera_desc back = navigate_orbit(&there, pivot, -yaw_rad, 0.0);
        double scale_len = fmax(dist(c.eye, pivot), dist(c.look_at, pivot)) + len(d(pivot));
        /* the eye turns on a circle about the up axis through the pivot: its chord */
        d3 u = unit(d(c.up)), r = sub(d(c.eye), d(pivot));
        double radius = len(sub(r, scale(u, dot(r, u))));
        double chord = 2.0 * radius * fabs(sin(0.5 * yaw_rad));
        cr_assert_lt(fabs(dist(there.eye, c.eye) - chord), 1e-5 * scale_len, "case %d", i);
        cr_assert_lt(dist(back.eye, c.eye), 1e-5 * scale_len, "case %d", i);
        cr_assert_lt(dist(back.look_at, c.look_at), 1e-5 * scale_len, "case %d", i);
        cr_assert(memcmp(&back.up, &c.up, sizeof c.up) == 0 && back.fov_deg == c.fov_deg);
    }
}

Test(navigate, orbit_conventions)
{
    /* looking down -z from +z at the origin: right is +x, up +y */
    camera_desc c = cam(v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 2.f, 0.f), 45.f);
    vec3 origin = v3(0.f, 0.f, 0.f);

    camera_desc yawed = navigate_orbit(&c, origin, pi / 2, 0.0); /* the camera moves to its right */
    cr_assert_lt(dist(yawed.eye, v3(5.f, 0.f, 0.f)), 1e-6, "eye (%g %g %g)", yawed.eye.x, yawed.eye.y, yawed.eye.z);
    cr_assert(memcmp(&yawed.look_at, &origin, sizeof origin) == 0, "orbiting about look_at keeps it, bit for bit");

    camera_desc pitched = navigate_orbit(&c, origin, 0.0, pi / 6); /* the camera moves up */
    cr_assert_lt(dist(pitched.eye, v3(0.f, 2.5f, (float)(5.0 * cos(pi / 6)))), 1e-6);
    cr_assert_lt(fabs(elevation_deg(&pitched) + 30.0), 1e-5, "looks down 30 degrees: %g", elevation_deg(&pitched));

    /* a pivot off the look_at: look_at turns about it too */
    vec3 pivot = v3(0.f, 0.f, -5.f);
    camera_desc about = navigate_orbit(&c, pivot, pi, 0.0);
    cr_assert_lt(dist(about.eye, v3(0.f, 0.f, -15.f)), 1e-5);
    cr_assert_lt(dist(about.look_at, v3(0.f, 0.f, -10.f)), 1e-5);

    /* up and fov are kept bit for bit (the horizon stays level) */
    cr_assert(memcmp(&about.up, &c.up, sizeof c.up) == 0 && about.fov_deg == c.fov_deg);
    cr_assert(memcmp(&pitched.up, &c.up, sizeof c.up) == 0 && pitched.fov_deg == c.fov_deg);
    cr_assert(same_bits(navigate_orbit(&c, pivot, 0.0, 0.0), c), "a zero orbit is the identity");
}

Test(navigate, orbit_elevation_is_clamped)
{
    const double min_angle_to_up_deg = 90.0 - NAVIGATE_MAX_ELEVATION_DEG; /* 5 */
    rng_seed(14);
    for (int i = 0; i < 300; i++) {
        camera_desc c = rnd_camera();
        vec3 pivot = to_f(rnd_point_in_view(&c, 1.f, 1, 12));
        double pitch_rad = (i % 2 ? 1.0 : -1.0) * (i % 3 == 0 ? 1e3 : rnd(3, 50));
        camera_desc o = navigate_orbit(&c, pivot, rnd(-1, 1), pitch_rad);
        cr_assert(valid(&o), "case %d", i);
        double view_to_up_deg = acos(dot(unit(sub(d(o.look_at), d(o.eye))), unit(d(o.up)))) * 180.0 / pi;
        cr_assert_geq(view_to_up_deg, min_angle_to_up_deg - 1e-3, "case %d: %g degrees from up", i, view_to_up_deg);
        cr_assert_leq(view_to_up_deg, 180.0 - min_angle_to_up_deg + 1e-3, "case %d: %g from up", i, view_to_up_deg);
        /* a huge pitch ends exactly on the clamp: up (pitch > 0) looks down.
         * (Rounding eye and look_at turns the view by up to ~2e-4 degrees here.) */
        double want_deg = pitch_rad > 0 ? -NAVIGATE_MAX_ELEVATION_DEG : NAVIGATE_MAX_ELEVATION_DEG;
        cr_assert_lt(fabs(elevation_deg(&o) - want_deg), 1e-3, "case %d: elevation %g", i, elevation_deg(&o));
    }
}

Test(navigate, orbit_beyond_the_clamp_only_comes_back)
{
    /* looking 88 degrees up (valid: more than 0.8 degrees from up) */
    double e_rad = 88.0 * pi / 180.0;
    camera_desc c = cam(v3(1.f, 2.f, 3.f), v3(1.f + 5.f * (float)cos(e_rad), 2.f + 5.f * (float)sin(e_rad), 3.f),
                        v3(0.f, 1.f, 0.f), 60.f);
    cr_assert(valid(&c));
    double start_deg = elevation_deg(&c);
    cr_assert_gt(start_deg, NAVIGATE_MAX_ELEVATION_DEG);
    /* pitch < 0: the camera moves down, the view would tilt further up: refused */
    camera_desc further = navigate_orbit(&c, c.look_at, 0.0, -0.2);
    cr_assert_lt(fabs(elevation_deg(&further) - start_deg), 1e-5, "elevation %g", elevation_deg(&further));
    /* pitch > 0 tilts it down by the full amount */
    camera_desc back = navigate_orbit(&c, c.look_at, 0.0, 0.1);
    cr_assert_lt(fabs(elevation_deg(&back) - (start_deg - 0.1 * 180.0 / pi)), 1e-4, "%g", elevation_deg(&back));
    /* and a huge one stops at the lower clamp */
    camera_desc down = navigate_orbit(&c, c.look_at, 0.0, 100.0);
    cr_assert_lt(fabs(elevation_deg(&down) + NAVIGATE_MAX_ELEVATION_DEG), 1e-4, "%g", elevation_deg(&down));
}

/* ---- pan ----------------------------------------------------------------- */

Test(navigate, pan_grabbed_point_follows_the_cursor)
{
    static const double depths[] = {0.3, 2.0, 15.0, 60.0};
    static const float aspects[] = {1.f, 16.f / 9.f, 0.6f, 5.333f};
    rng_seed(21);
    for (int i = 0; i < 400; i++) {
        camera_desc c = rnd_camera();
        double depth = depths[i % 4] * rnd(0.8, 1.25);
        float aspect = aspects[(i / 4) % 4];
        double sx = rnd(-1, 1), sy = rnd(-1, 1), dsx = rnd(-0.5, 0.5), dsy = rnd(-0.5, 0.5);
        d3 point = unproject(&c, aspect, sx, sy, depth);
        camera_desc p = navigate_pan(&c, aspect, depth, dsx, dsy);
        cr_assert(valid(&p), "case %d", i);
        double sx1, sy1;
        project(&p, aspect, point, &sx1, &sy1, NULL);
        /* both cameras' roundings, and the float bases of the projection */
        double tol = 5e-6 + 2.0 * (image_rounding_bound(&c, aspect, depth, sx, sy) +
                                   image_rounding_bound(&p, aspect, depth, sx + dsx, sy + dsy));
        cr_assert_lt(fabs(sx1 - (sx + dsx)), tol, "case %d: sx %.9g want %.9g", i, sx1, sx + dsx);
        cr_assert_lt(fabs(sy1 - (sy + dsy)), tol, "case %d: sy %.9g want %.9g", i, sy1, sy + dsy);
        /* a translation parallel to the image plane: eye and look_at move alike,
         * across the view, to their roundings */
        double eye_round = float_half_ulp * (len(d(c.eye)) + len(d(p.eye)));
        double at_round = float_half_ulp * (len(d(c.look_at)) + len(d(p.look_at)));
        d3 move_eye = sub(d(p.eye), d(c.eye)), move_at = sub(d(p.look_at), d(c.look_at));
        d3 f = unit(sub(d(c.look_at), d(c.eye)));
        cr_assert_gt(len(move_eye), 0.0, "case %d: the camera moved", i);
        cr_assert_leq(len(sub(move_eye, move_at)), 1.01 * (eye_round + at_round), "case %d", i);
        cr_assert_leq(fabs(dot(move_eye, f)), 1.01 * eye_round + 1e-30, "case %d", i);
        cr_assert(memcmp(&p.up, &c.up, sizeof c.up) == 0 && p.fov_deg == c.fov_deg);
    }
}

Test(navigate, pan_direction)
{
    /* dragging to the right (dsx > 0) moves the camera to its left (-x here) */
    camera_desc c = cam(v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 90.f);
    camera_desc p = navigate_pan(&c, 2.f, 5.0, 0.25, 0.0);
    /* |right| = tan(45) * 2 = 2 at unit depth: 0.25 * 2 * 5 = 2.5 */
    cr_assert_lt(dist(p.eye, v3(-2.5f, 0.f, 5.f)), 1e-6, "eye (%g %g %g)", p.eye.x, p.eye.y, p.eye.z);
    cr_assert_lt(dist(p.look_at, v3(-2.5f, 0.f, 0.f)), 1e-6);
    camera_desc q = navigate_pan(&c, 2.f, 5.0, 0.0, -0.5); /* drag down: the camera goes up */
    cr_assert_lt(dist(q.eye, v3(0.f, 2.5f, 5.f)), 1e-6, "eye (%g %g %g)", q.eye.x, q.eye.y, q.eye.z);
}

/* ---- dolly --------------------------------------------------------------- */

Test(navigate, dolly_composes_and_keeps_the_point_in_the_image)
{
    rng_seed(31);
    for (int i = 0; i < 300; i++) {
        camera_desc c = rnd_camera();
        float aspect = (float)rnd(0.5, 3.0);
        vec3 point = to_f(rnd_point_in_view(&c, aspect, 1, 12));
        double a = exp(rnd(-2, 2)), b = exp(rnd(-2, 2));
        camera_desc twice = navigate_dolly(&c, point, a);
        twice = navigate_dolly(&twice, point, b);
        camera_desc once = navigate_dolly(&c, point, a * b);
        cr_assert(valid(&once) && valid(&twice), "case %d", i);
        double scale_len = len(d(c.eye)) + len(d(c.look_at)) + len(d(point)) + dist(c.eye, point) * fmax(1.0, a * b);
        cr_assert_lt(dist(twice.eye, once.eye), 1e-6 * scale_len, "case %d", i);
        cr_assert_lt(dist(twice.look_at, once.look_at), 1e-6 * scale_len, "case %d", i);
        /* eye and look_at both scale about the point */
        d3 want_eye = add(d(point), scale(sub(d(c.eye), d(point)), a * b));
        d3 want_at = add(d(point), scale(sub(d(c.look_at), d(point)), a * b));
        cr_assert_lt(len(sub(d(once.eye), want_eye)), 1e-6 * scale_len, "case %d", i);
        cr_assert_lt(len(sub(d(once.look_at), want_at)), 1e-6 * scale_len, "case %d", i);
        /* the point stays put in the image, to the roundings: a camera moved close
         * to it has coordinates large against its view distance */
        double sx0, sy0, sx1, sy1, depth0, depth1;
        project(&c, aspect, d(point), &sx0, &sy0, &depth0);
        project(&once, aspect, d(point), &sx1, &sy1, &depth1);
        double tol = 5e-6 + 2.0 * (image_rounding_bound(&c, aspect, depth0, sx0, sy0) +
                                   image_rounding_bound(&once, aspect, depth1, sx1, sy1));
        cr_assert_lt(fabs(sx1 - sx0), tol, "case %d", i);
        cr_assert_lt(fabs(sy1 - sy0), tol, "case %d", i);
        cr_assert(memcmp(&once.up, &c.up, sizeof c.up) == 0 && once.fov_deg == c.fov_deg);
    }
}

Test(navigate, dolly_is_scale_invariant)
{
    static const double scales[] = {1e-3, 0.37, 3.7, 250.0};
    rng_seed(32);
    for (int i = 0; i < 200; i++) {
        camera_desc c = rnd_camera();
        d3 point = rnd_point_in_view(&c, 1.f, 1, 12);
        double s = scales[i % 4], factor = exp(rnd(-2, 2));
        camera_desc big = cam(to_f(scale(d(c.eye), s)), to_f(scale(d(c.look_at), s)), c.up, c.fov_deg);
        camera_desc small = navigate_dolly(&c, to_f(point), factor);
        camera_desc scaled = navigate_dolly(&big, to_f(scale(point, s)), factor);
        double tol = 1e-6 * s * (len(d(c.eye)) + len(point) + dist(c.eye, to_f(point)) * fmax(1.0, factor));
        cr_assert_lt(len(sub(d(scaled.eye), scale(d(small.eye), s))), tol, "case %d", i);
        cr_assert_lt(len(sub(d(scaled.look_at), scale(d(small.look_at), s))), tol, "case %d", i);
    }
}

/* ---- flight and fly-to --------------------------------------------------- */

Test(navigate, fly_moves_by_the_requested_distance)
{
    rng_seed(41);
    for (int i = 0; i < 300; i++) {
        camera_desc c = rnd_camera();
        double forward = rnd(-5, 5), right = rnd(-5, 5), up = rnd(-5, 5);
        d3 f = unit(sub(d(c.look_at), d(c.eye))), u = unit(d(c.up)), r = unit(cross(f, d(c.up)));
        double tol = 4.0 * float_half_ulp * (len(d(c.eye)) + len(d(c.look_at)) + 15.0);
        /* one axis at a time: exactly that distance, along that axis */
        camera_desc a = navigate_fly(&c, forward, 0.0, 0.0);
        cr_assert_lt(fabs(dist(a.eye, c.eye) - fabs(forward)), tol, "case %d", i);
        cr_assert_lt(len(sub(sub(d(a.eye), d(c.eye)), scale(f, forward))), tol, "case %d", i);
        camera_desc b = navigate_fly(&c, 0.0, right, 0.0);
        cr_assert_lt(len(sub(sub(d(b.eye), d(c.eye)), scale(r, right))), tol, "case %d", i);
        camera_desc e = navigate_fly(&c, 0.0, 0.0, up);
        cr_assert_lt(fabs(dist(e.eye, c.eye) - fabs(up)), tol, "case %d: the up hint is normalized", i);
        cr_assert_lt(len(sub(sub(d(e.eye), d(c.eye)), scale(u, up))), tol, "case %d", i);
        /* all three: the sum, eye and look_at alike */
        camera_desc all = navigate_fly(&c, forward, right, up);
        d3 want = add(scale(f, forward), add(scale(r, right), scale(u, up)));
        cr_assert_lt(len(sub(sub(d(all.eye), d(c.eye)), want)), tol, "case %d", i);
        cr_assert_lt(len(sub(sub(d(all.look_at), d(c.look_at)), want)), tol, "case %d", i);
        cr_assert(memcmp(&all.up, &c.up, sizeof c.up) == 0 && all.fov_deg == c.fov_deg);
    }
}

Test(navigate, look_at_point_centres_the_point)
{
    rng_seed(42);
    for (int i = 0; i < 300; i++) {
        camera_desc c = rnd_camera();
        vec3 point = to_f((d3){rnd(-20, 20), rnd(-20, 20), rnd(-20, 20)});
        double distance = exp(rnd(-3, 4));
        camera_desc t = navigate_look_at_point(&c, point, distance);
        cr_assert(valid(&t), "case %d", i);
        cr_assert(memcmp(&t.look_at, &point, sizeof point) == 0, "look_at is the point");
        double tol = 4.0 * float_half_ulp * (len(d(point)) + distance);
        cr_assert_lt(fabs(dist(t.eye, point) - distance), tol, "case %d", i);
        /* the ray through the plane centre hits the point */
        vec3 origin, dir;
        navigate_plane_ray(&t, 1.7f, 0.0, 0.0, &origin, &dir);
        d3 to_point = sub(d(point), d(origin));
        cr_assert_gt(dot(to_point, d(dir)), 0.0, "case %d: the point is in front", i);
        cr_assert_lt(len(cross(to_point, d(dir))), 1e-6 * distance + 2.0 * tol, "case %d: ray misses", i);
        /* seen from the same direction as before */
        d3 v0 = unit(sub(d(c.look_at), d(c.eye))), v1 = unit(sub(d(t.look_at), d(t.eye)));
        cr_assert_lt(len(sub(v0, v1)), 1e-6 + 2.0 * tol / distance, "case %d", i);
        cr_assert(memcmp(&t.up, &c.up, sizeof c.up) == 0 && t.fov_deg == c.fov_deg);
    }
}

/* ---- blend and ease ------------------------------------------------------ */

Test(navigate, blend_endpoints_are_exact)
{
    camera_desc a = cam(v3(0.1f, 0.7f, 3.3f), v3(-1.9f, 0.3f, 0.01f), v3(0.f, 1.f, 0.2f), 33.3f);
    camera_desc b = cam(v3(7.7f, -2.1f, 0.3f), v3(1.1f, 1e-3f, -4.f), v3(0.1f, 0.9f, 0.f), 71.1f);
    cr_assert(same_bits(navigate_blend(&a, &b, 0.0), a));
    cr_assert(same_bits(navigate_blend(&a, &b, -0.5), a));
    cr_assert(same_bits(navigate_blend(&a, &b, -INFINITY), a));
    cr_assert(same_bits(navigate_blend(&a, &b, NAN), a), "NaN counts as 0");
    cr_assert(same_bits(navigate_blend(&a, &b, 1.0), b));
    cr_assert(same_bits(navigate_blend(&a, &b, 3.0), b));
    cr_assert(same_bits(navigate_blend(&a, &b, INFINITY), b));
    /* s = 1 is b even where a + (b - a) * 1 is not: 3e15 - (3e15 - 1e-3) loses the 1e-3 */
    camera_desc far = cam(v3(3e15f, 0.f, 0.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f);
    camera_desc close = cam(v3(1e-3f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f);
    cr_assert(valid(&far) && valid(&close));
    cr_assert(same_bits(navigate_blend(&far, &close, 1.0), close));
    cr_assert(same_bits(navigate_blend(&close, &far, 0.0), close));
    /* in between: linear in every field */
    camera_desc m = navigate_blend(&a, &b, 0.25);
    cr_assert_lt(len(sub(d(m.eye), add(scale(d(a.eye), 0.75), scale(d(b.eye), 0.25)))), 1e-6);
    cr_assert_lt(len(sub(d(m.look_at), add(scale(d(a.look_at), 0.75), scale(d(b.look_at), 0.25)))), 1e-6);
    cr_assert_lt(len(sub(d(m.up), add(scale(d(a.up), 0.75), scale(d(b.up), 0.25)))), 1e-6);
    cr_assert_lt(fabs(m.fov_deg - (0.75 * a.fov_deg + 0.25 * b.fov_deg)), 1e-5);
    /* just inside the ends: close to, but not, the end */
    camera_desc near_b = navigate_blend(&a, &b, 1.0 - 1e-9);
    cr_assert_lt(dist(near_b.eye, b.eye), 1e-6);
}

Test(navigate, blend_that_is_invalid_gives_the_nearer_camera)
{
    /* up passes through zero at s = 1 / 4 and s = 3 / 4 */
    camera_desc a = cam(v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f);
    camera_desc b = cam(v3(1.f, 0.f, 5.f), v3(1.f, 0.f, 0.f), v3(0.f, -3.f, 0.f), 50.f);
    cr_assert(same_bits(navigate_blend(&a, &b, 0.25), a));
    camera_desc c = cam(v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 3.f, 0.f), 40.f);
    camera_desc e = cam(v3(1.f, 0.f, 5.f), v3(1.f, 0.f, 0.f), v3(0.f, -1.f, 0.f), 50.f);
    cr_assert(same_bits(navigate_blend(&c, &e, 0.75), e));
    /* eye and look_at swap places: they meet at s = 1 / 2, which goes to b */
    camera_desc f = cam(v3(0.f, 0.f, 1.f), v3(0.f, 0.f, -1.f), v3(0.f, 1.f, 0.f), 40.f);
    camera_desc g = cam(v3(0.f, 0.f, -1.f), v3(0.f, 0.f, 1.f), v3(0.f, 1.f, 0.f), 40.f);
    cr_assert(same_bits(navigate_blend(&f, &g, 0.5), g));
    camera_desc ok = navigate_blend(&f, &g, 0.4); /* valid there: a real blend */
    cr_assert(valid(&ok));
    cr_assert_lt(dist(ok.eye, v3(0.f, 0.f, 0.2f)), 1e-7);
}

Test(navigate, ease_is_a_clamped_smoothstep)
{
    cr_assert_eq(navigate_ease(0.0), 0.0);
    cr_assert_eq(navigate_ease(1.0), 1.0);
    cr_assert_eq(navigate_ease(0.5), 0.5);
    cr_assert_eq(navigate_ease(-3.0), 0.0);
    cr_assert_eq(navigate_ease(7.0), 1.0);
    cr_assert_eq(navigate_ease(NAN), 0.0);
    cr_assert_lt(fabs(navigate_ease(0.25) - 0.15625), 1e-15);
    cr_assert_lt(navigate_ease(1e-4), 1e-7, "flat at the start");
    cr_assert_gt(navigate_ease(1.0 - 1e-4), 1.0 - 1e-7, "flat at the end");
    double prev = 0.0;
    for (int k = 1; k <= 1000; k++) {
        double s = k / 1000.0, e = navigate_ease(s);
        cr_assert_gt(e, prev, "increasing at %g", s);
        cr_assert_lt(fabs(e + navigate_ease(1.0 - s) - 1.0), 1e-15, "symmetric at %g", s);
        prev = e;
    }
}

/* ---- refusals ------------------------------------------------------------ */

Test(navigate, invalid_motions_return_the_input)
{
    camera_desc c = cam(v3(1.f, 2.f, 3.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f);
    vec3 p = v3(0.5f, 0.5f, 0.5f), nan_point = v3(NAN, 0.f, 0.f);
    /* bad arguments */
    cr_assert(same_bits(navigate_dolly(&c, p, NAN), c));
    cr_assert(same_bits(navigate_dolly(&c, p, 0.0), c));
    cr_assert(same_bits(navigate_dolly(&c, p, -2.0), c));
    cr_assert(same_bits(navigate_dolly(&c, p, INFINITY), c));
    cr_assert(same_bits(navigate_dolly(&c, nan_point, 2.0), c));
    cr_assert(same_bits(navigate_look_at_point(&c, p, 0.0), c));
    cr_assert(same_bits(navigate_look_at_point(&c, p, -1.0), c));
    cr_assert(same_bits(navigate_look_at_point(&c, p, NAN), c));
    cr_assert(same_bits(navigate_look_at_point(&c, nan_point, 1.0), c));
    cr_assert(same_bits(navigate_orbit(&c, p, NAN, 0.0), c));
    cr_assert(same_bits(navigate_orbit(&c, p, 0.1, INFINITY), c));
    cr_assert(same_bits(navigate_orbit(&c, nan_point, 0.1, 0.1), c));
    cr_assert(same_bits(navigate_pan(&c, 1.f, 0.0, 0.1, 0.1), c));
    cr_assert(same_bits(navigate_pan(&c, 1.f, -1.0, 0.1, 0.1), c));
    cr_assert(same_bits(navigate_pan(&c, 1.f, 2.0, NAN, 0.1), c));
    cr_assert(same_bits(navigate_pan(&c, 0.f, 2.0, 0.1, 0.1), c));
    cr_assert(same_bits(navigate_pan(&c, NAN, 2.0, 0.1, 0.1), c));
    cr_assert(same_bits(navigate_fly(&c, NAN, 0.0, 0.0), c));
    cr_assert(same_bits(navigate_fly(&c, 0.0, 0.0, -INFINITY), c));
    /* motions whose rounded result would not be a camera */
    cr_assert(same_bits(navigate_dolly(&c, c.eye, 1e-30), c), "look_at would land on the eye");
    cr_assert(same_bits(navigate_look_at_point(&c, p, 1e-30), c), "eye would land on the point");
    cr_assert(same_bits(navigate_pan(&c, 1.f, 1e300, 0.5, 0.5), c), "non-finite eye");
    cr_assert(same_bits(navigate_fly(&c, 1e300, 0.0, 0.0), c), "non-finite eye");
    cr_assert(same_bits(navigate_dolly(&c, p, 1e300), c), "non-finite eye");
    /* an invalid camera is left alone */
    camera_desc bad = cam(v3(1.f, 1.f, 1.f), v3(1.f, 1.f, 1.f), v3(0.f, 1.f, 0.f), 40.f);
    cr_assert(same_bits(navigate_orbit(&bad, p, 0.3, 0.2), bad));
    cr_assert(same_bits(navigate_fly(&bad, 1.0, 1.0, 1.0), bad));
    cr_assert(same_bits(navigate_dolly(&bad, p, 2.0), bad));
    camera_desc along_up = cam(v3(0.f, 0.f, 0.f), v3(0.f, 3.f, 0.f), v3(0.f, 1.f, 0.f), 40.f);
    cr_assert(same_bits(navigate_pan(&along_up, 1.f, 1.0, 0.2, 0.0), along_up));
    cr_assert(same_bits(navigate_look_at_point(&along_up, p, 2.0), along_up));
    vec3 origin, dir;
    navigate_plane_ray(&bad, 1.f, 0.0, 0.0, &origin, &dir);
    cr_assert(memcmp(&origin, &bad.eye, sizeof origin) == 0 && dir.x == 0.f && dir.y == 0.f && dir.z == 0.f,
              "no ray for an invalid camera: a zero direction");
}

/* ---- the plane ray and the renderer -------------------------------------- */

/* The renderer's pixel (x, y) of a W x H image of `window` lies at plane point
 * (cx + hw * px, cy + hh * py), with (px, py) its screen coordinates in the
 * image (camera.h); the plane ray there must be the renderer's pixel ray. */
static void check_window(const camera_desc *c, float plane_aspect, camera_window w, int width, int height)
{
    camera_basis b = camera_basis_window(c, plane_aspect, w, width, height);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            double px = 2.0 * (x + 0.5) / width - 1.0, py = 1.0 - 2.0 * (y + 0.5) / height;
            vec3 origin, dir;
            navigate_plane_ray(c, plane_aspect, w.center_x + w.half_width * px, w.center_y + w.half_height * py,
                               &origin, &dir);
            d3 want = unit(d(camera_pixel_direction(&b, x, y)));
            cr_assert(memcmp(&origin, &b.eye, sizeof origin) == 0, "origin is the eye");
            cr_assert_lt(fabs(len(d(dir)) - 1.0), 1e-6, "unit direction");
            cr_assert_gt(dot(d(dir), want), 0.0);
            cr_assert_lt(len(cross(d(dir), want)), 2e-6, "pixel (%d, %d) of a %dx%d window: %g rad apart", x, y,
                         width, height, len(cross(d(dir), want)));
        }
}

Test(navigate, plane_ray_matches_the_renderer)
{
    rng_seed(51);
    for (int i = 0; i < 40; i++) {
        camera_desc c = rnd_camera();
        float plane_aspect = (float)rnd(0.5, 6.0);
        check_window(&c, plane_aspect, CAMERA_WINDOW_FULL, 9, 7);
        /* one output of a 3 x 2 wall, and an arbitrary off-centre window */
        check_window(&c, plane_aspect, (camera_window){2.f / 3.f, 0.5f, 1.f / 3.f, 0.5f}, 8, 6);
        check_window(&c, plane_aspect, (camera_window){-0.31f, 0.17f, 0.22f, 0.4f}, 5, 11);
    }
    /* and camera_basis_make for a plain W x H image */
    camera_desc c = cam(v3(1.f, 2.f, 3.f), v3(-2.f, 0.5f, 0.f), v3(0.f, 1.f, 0.f), 65.f);
    camera_basis b = camera_basis_make(&c, 64, 48);
    vec3 origin, dir;
    navigate_plane_ray(&c, 64.f / 48.f, 2.0 * 10.5 / 64 - 1.0, 1.0 - 2.0 * 40.5 / 48, &origin, &dir);
    cr_assert_lt(len(cross(d(dir), unit(d(camera_pixel_direction(&b, 10, 40))))), 2e-6);
}
