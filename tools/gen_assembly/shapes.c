/* shapes.c - tessellating the parts (shapes.h).
 *
 * Two general builders do most of the work: a sweep (a closed polygon moved
 * along a path of frames, open with flat caps or closed into a loop) and a
 * lathe (a profile from pole to pole turned about z). The bolt, whose hex head
 * meets a round shank, has its own. Each builder computes every point once and
 * reuses it, so faces meeting at a point store bit-identical positions. */
#include "shapes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"

#define PI 3.14159265358979323846

struct ga_shape ga_shape_make(enum ga_shape_kind kind)
{
    struct ga_shape shape;
    memset(&shape, 0, sizeof shape);
    shape.kind = kind;
    return shape;
}

const char *ga_shape_kind_name(enum ga_shape_kind kind)
{
    static const char *const names[GA_SHAPE_KIND_COUNT] = {
        [GA_SHAPE_FRAME] = "frame",   [GA_SHAPE_STRINGER_BOX] = "stringer", [GA_SHAPE_STRINGER_Z] = "stringer",
        [GA_SHAPE_SKIN] = "skin",     [GA_SHAPE_PIPE] = "pipe",             [GA_SHAPE_BRACKET] = "bracket",
        [GA_SHAPE_BOLT] = "bolt",     [GA_SHAPE_RIVET] = "rivet",
    };
    return (unsigned)kind < GA_SHAPE_KIND_COUNT ? names[kind] : "part";
}

/* ---- sweep ---------------------------------------------------------------- */

/* A cross-section: a simple polygon, counter-clockwise in (u, v). An edge i
 * (point i to i + 1) is smooth (normals interpolate the points' normals, for
 * arcs) or flat (its own normal). `caps` triangulate it, counter-clockwise. */
struct profile {
    int count;         /* points */
    double *u, *v;     /* point coordinates */
    double *nu, *nv;   /* point normals for smooth edges (unit, outward) */
    bool *smooth;      /* per edge */
    int cap_count;     /* triangles in caps */
    int *caps;         /* 3 point indices a triangle */
};

/* One station of a path: origin and axes, with t = u x v the direction of travel. */
struct station {
    struct ga_v3 o, u, v, t;
};

static bool profile_alloc(struct profile *p, int count, int cap_count)
{
    memset(p, 0, sizeof *p);
    p->count = count;
    p->cap_count = cap_count;
    p->u = calloc((size_t)count * 4, sizeof(double));
    p->smooth = calloc((size_t)count, sizeof(bool));
    p->caps = calloc((size_t)(cap_count > 0 ? cap_count : 1) * 3, sizeof(int));
    if (!p->u || !p->smooth || !p->caps)
        return false;
    p->v = p->u + count;
    p->nu = p->v + count;
    p->nv = p->nu + count;
    return true;
}

static void profile_free(struct profile *p)
{
    free(p->u);
    free(p->smooth);
    free(p->caps);
}

static void profile_cap(struct profile *p, int at, int a, int b, int c)
{
    p->caps[3 * at] = a;
    p->caps[3 * at + 1] = b;
    p->caps[3 * at + 2] = c;
}

/* Triangles a sweep of `p` over `stations` stations makes. */
static uint64_t sweep_triangles(int count, int cap_count, int stations, bool closed)
{
    uint64_t sides = 2ull * (uint64_t)count * (uint64_t)(closed ? stations : stations - 1);
    return sides + (closed ? 0 : 2ull * (uint64_t)cap_count);
}

/* The normal at point `end` (0: start, 1: end) of edge e, in (u, v). */
static void edge_normal(const struct profile *p, int e, int end, double *nu, double *nv)
{
    int a = e, b = (e + 1) % p->count;
    if (p->smooth[e]) {
        int at = end ? b : a;
        *nu = p->nu[at];
        *nv = p->nv[at];
        return;
    }
    *nu = p->v[b] - p->v[a];
    *nv = -(p->u[b] - p->u[a]);
}

static bool sweep(struct ga_mesh *mesh, const struct profile *p, const struct station *st, int stations, bool closed)
{
    int n = p->count;
    uint32_t *idx = malloc(sizeof(uint32_t) * 7 * (size_t)n);
    struct ga_v3 *pts = malloc(sizeof(struct ga_v3) * (size_t)n);
    if (!idx || !pts) {
        free(idx);
        free(pts);
        return false;
    }
    /* per edge: start and end vertex of the first, previous and current station */
    uint32_t *first_s = idx, *first_e = idx + n, *prev_s = idx + 2 * n, *prev_e = idx + 3 * n;
    uint32_t *cur_s = idx + 4 * n, *cur_e = idx + 5 * n, *shared = idx + 6 * n;
    for (int r = 0; r < stations; r++) {
        const struct station *s = &st[r];
        for (int i = 0; i < n; i++)
            pts[i] = ga_v3_add(s->o, ga_v3_comb(s->u, p->u[i], s->v, p->v[i]));
        /* a point between two smooth edges has one vertex for both */
        for (int i = 0; i < n; i++)
            if (p->smooth[(i + n - 1) % n] && p->smooth[i])
                shared[i] = ga_mesh_vertex(mesh, pts[i], ga_v3_comb(s->u, p->nu[i], s->v, p->nv[i]));
        for (int e = 0; e < n; e++) {
            int b = (e + 1) % n;
            double nu, nv;
            if (p->smooth[(e + n - 1) % n] && p->smooth[e]) {
                cur_s[e] = shared[e];
            } else {
                edge_normal(p, e, 0, &nu, &nv);
                cur_s[e] = ga_mesh_vertex(mesh, pts[e], ga_v3_comb(s->u, nu, s->v, nv));
            }
            if (p->smooth[e] && p->smooth[b]) {
                cur_e[e] = shared[b];
            } else {
                edge_normal(p, e, 1, &nu, &nv);
                cur_e[e] = ga_mesh_vertex(mesh, pts[b], ga_v3_comb(s->u, nu, s->v, nv));
            }
        }
        if (r > 0) {
            for (int e = 0; e < n; e++) {
                ga_mesh_triangle(mesh, prev_s[e], prev_e[e], cur_e[e]);
                ga_mesh_triangle(mesh, prev_s[e], cur_e[e], cur_s[e]);
            }
        } else {
            memcpy(first_s, cur_s, sizeof(uint32_t) * (size_t)n);
            memcpy(first_e, cur_e, sizeof(uint32_t) * (size_t)n);
        }
        bool start_cap = r == 0, end_cap = r == stations - 1;
        if (!closed && (start_cap || end_cap)) {
            struct ga_v3 cap_n = start_cap ? ga_v3_scale(s->t, -1.0) : s->t;
            uint32_t base = (uint32_t)mesh->vertex_count;
            for (int i = 0; i < n; i++)
                ga_mesh_vertex(mesh, pts[i], cap_n);
            for (int c = 0; c < p->cap_count; c++) {
                const int *t = p->caps + 3 * c;
                if (start_cap)
                    ga_mesh_triangle(mesh, base + (uint32_t)t[0], base + (uint32_t)t[2], base + (uint32_t)t[1]);
                else
                    ga_mesh_triangle(mesh, base + (uint32_t)t[0], base + (uint32_t)t[1], base + (uint32_t)t[2]);
            }
        }
        memcpy(prev_s, cur_s, sizeof(uint32_t) * (size_t)n);
        memcpy(prev_e, cur_e, sizeof(uint32_t) * (size_t)n);
    }
    if (closed)
        for (int e = 0; e < n; e++) {
            ga_mesh_triangle(mesh, prev_s[e], prev_e[e], first_e[e]);
            ga_mesh_triangle(mesh, prev_s[e], first_e[e], first_s[e]);
        }
    free(idx);
    free(pts);
    return !mesh->failed;
}

/* `count` stations along +x from x0 to x1, axes u = y, v = z. */
static struct station *stations_along_x(double x0, double x1, int count)
{
    struct station *st = malloc(sizeof *st * (size_t)count);
    if (!st)
        return NULL;
    for (int i = 0; i < count; i++) {
        double x = i == count - 1 ? x1 : x0 + (x1 - x0) * i / (count - 1);
        st[i] = (struct station){ga_v3_make(x, 0, 0), ga_v3_make(0, 1, 0), ga_v3_make(0, 0, 1), ga_v3_make(1, 0, 0)};
    }
    return st;
}

static bool extrude_x(struct ga_mesh *mesh, const struct profile *p, double x0, double x1, int stations)
{
    struct station *st = stations_along_x(x0, x1, stations);
    bool ok = st && sweep(mesh, p, st, stations, false);
    free(st);
    return ok;
}

/* Quad a, b, c, d (counter-clockwise) as two cap triangles from index `at`. */
static void profile_cap_quad(struct profile *p, int at, int a, int b, int c, int d)
{
    profile_cap(p, at, a, b, c);
    profile_cap(p, at + 1, a, c, d);
}

static void profile_point(struct profile *p, int i, double u, double v)
{
    p->u[i] = u;
    p->v[i] = v;
}

/* ---- the parts ------------------------------------------------------------ */

static bool build_frame(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double ri = s->size[0], ro = s->size[1], w = s->size[2];
    int n = s->segments[0];
    struct profile p;
    struct station *st = malloc(sizeof *st * (size_t)n);
    bool ok = profile_alloc(&p, 4, 0) && st;
    if (ok) {
        /* u along x, v radial: u x v is the direction of increasing angle */
        profile_point(&p, 0, -w / 2, ri);
        profile_point(&p, 1, w / 2, ri);
        profile_point(&p, 2, w / 2, ro);
        profile_point(&p, 3, -w / 2, ro);
        for (int j = 0; j < n; j++) {
            double a = 2.0 * PI * j / n, c = cos(a), sn = sin(a);
            st[j] = (struct station){ga_v3_make(0, 0, 0), ga_v3_make(1, 0, 0), ga_v3_make(0, c, sn),
                                     ga_v3_make(0, -sn, c)};
        }
        ok = sweep(mesh, &p, st, n, true);
    }
    free(st);
    profile_free(&p);
    return ok;
}

static bool build_stringer_box(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double len = s->size[0], top = s->size[1], w = s->size[2], h = s->size[3];
    struct profile p;
    bool ok = profile_alloc(&p, 4, 2);
    if (ok) {
        profile_point(&p, 0, -w / 2, top - h);
        profile_point(&p, 1, w / 2, top - h);
        profile_point(&p, 2, w / 2, top);
        profile_point(&p, 3, -w / 2, top);
        profile_cap_quad(&p, 0, 0, 1, 2, 3);
        ok = extrude_x(mesh, &p, 0.0, len, 2);
    }
    profile_free(&p);
    return ok;
}

static bool build_stringer_z(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double len = s->size[0], top = s->size[1], f = s->size[2], h = s->size[3], t = s->size[4];
    double u0 = -t / 2, v0 = top - h;
    struct profile p;
    bool ok = profile_alloc(&p, 8, 6);
    if (ok) {
        /* bottom flange towards +y, web, top flange (against the skin) towards -y */
        static const double pu[8] = {0, 1, 1, 2, 2, 3, 3, 0}, pv[8] = {0, 0, 2, 2, 1, 1, 4, 4};
        for (int i = 0; i < 8; i++) {
            double uu = pu[i] == 0 ? 0 : pu[i] == 1 ? f : pu[i] == 2 ? t : t - f;
            double vv = pv[i] == 0 ? 0 : pv[i] == 1 ? h : pv[i] == 2 ? t : h - t;
            profile_point(&p, i, u0 + uu, v0 + vv);
        }
        profile_cap_quad(&p, 0, 0, 1, 2, 3);
        profile_cap_quad(&p, 2, 0, 3, 4, 7);
        profile_cap_quad(&p, 4, 7, 4, 5, 6);
        ok = extrude_x(mesh, &p, 0.0, len, 2);
    }
    profile_free(&p);
    return ok;
}

static bool build_skin(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double len = s->size[0], ri = s->size[1], ro = ri + s->size[2], span = s->size[3];
    int m = s->segments[0], k = s->segments[1];
    struct profile p;
    bool ok = profile_alloc(&p, 2 * (m + 1), 2 * m);
    if (ok) {
        /* outer arc o_0..o_m with falling angle (counter-clockwise in (y, z)), then
         * the inner arc back: i_j = point m + 1 + j sits at the angle of o_(m-j) */
        for (int j = 0; j <= m; j++) {
            double a = span / 2 - span * j / m, sa = sin(a), ca = cos(a);
            profile_point(&p, j, ro * sa, ro * ca);
            p.nu[j] = sa;
            p.nv[j] = ca;
            p.smooth[j] = j < m;
            double b = -span / 2 + span * j / m, sb = sin(b), cb = cos(b);
            profile_point(&p, m + 1 + j, ri * sb, ri * cb);
            p.nu[m + 1 + j] = -sb;
            p.nv[m + 1 + j] = -cb;
            p.smooth[m + 1 + j] = j < m;
        }
        for (int j = 0; j < m; j++)
            profile_cap_quad(&p, 2 * j, j, j + 1, m + 1 + (m - j - 1), m + 1 + (m - j));
        ok = extrude_x(mesh, &p, 0.0, len, k + 1);
    }
    profile_free(&p);
    return ok;
}

/* Stations of a pipe's centre line: straight a, bend 1, straight b and, when
 * bend 2 is not 0, bend 2 and straight c; `bend_steps` stations a bend. */
static int pipe_stations(const struct ga_shape *s)
{
    int per_bend = s->segments[1];
    return s->size[6] != 0.0 ? 4 + 2 * per_bend : 3 + per_bend;
}

static void pipe_station(struct station *st, double x, double y, double heading)
{
    double c = cos(heading), sn = sin(heading);
    *st = (struct station){ga_v3_make(x, y, 0), ga_v3_make(-sn, c, 0), ga_v3_make(0, 0, 1), ga_v3_make(c, sn, 0)};
}

static bool build_pipe(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double radius = s->size[0], bend_r = s->size[1];
    const double straight[3] = {s->size[2], s->size[3], s->size[4]}, bend[2] = {s->size[5], s->size[6]};
    int c = s->segments[0], per_bend = s->segments[1], count = pipe_stations(s);
    struct profile p;
    struct station *st = malloc(sizeof *st * (size_t)count);
    bool ok = profile_alloc(&p, c, c - 2) && st;
    if (!ok)
        goto out;
    for (int i = 0; i < c; i++) {
        double a = 2.0 * PI * i / c;
        profile_point(&p, i, radius * cos(a), radius * sin(a));
        p.nu[i] = cos(a);
        p.nv[i] = sin(a);
        p.smooth[i] = true;
    }
    for (int i = 1; i + 1 < c; i++)
        profile_cap(&p, i - 1, 0, i, i + 1);
    double x = 0, y = 0, h = 0;
    int at = 0;
    pipe_station(&st[at++], x, y, h);
    int bends = bend[1] != 0.0 ? 2 : 1;
    for (int b = 0; b < bends; b++) {
        x += straight[b] * cos(h);
        y += straight[b] * sin(h);
        pipe_station(&st[at++], x, y, h);
        /* turn by bend[b] about a centre bend_r to the side it turns to */
        double side = bend[b] > 0 ? 1.0 : -1.0, h0 = h;
        double cx = x - side * bend_r * sin(h0), cy = y + side * bend_r * cos(h0);
        for (int j = 1; j <= per_bend; j++) {
            h = h0 + bend[b] * j / per_bend;
            x = cx + side * bend_r * sin(h);
            y = cy - side * bend_r * cos(h);
            pipe_station(&st[at++], x, y, h);
        }
    }
    x += straight[bends] * cos(h);
    y += straight[bends] * sin(h);
    pipe_station(&st[at++], x, y, h);
    ok = sweep(mesh, &p, st, at, false);
out:
    free(st);
    profile_free(&p);
    return ok;
}

static bool build_bracket(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double a = s->size[0], b = s->size[1], t = s->size[2], w = s->size[3];
    struct profile p;
    bool ok = profile_alloc(&p, 6, 4);
    if (ok) {
        profile_point(&p, 0, 0, 0);
        profile_point(&p, 1, a, 0);
        profile_point(&p, 2, a, t);
        profile_point(&p, 3, t, t);
        profile_point(&p, 4, t, b);
        profile_point(&p, 5, 0, b);
        profile_cap_quad(&p, 0, 0, 1, 2, 3);
        profile_cap_quad(&p, 2, 0, 3, 4, 5);
        ok = extrude_x(mesh, &p, -w / 2, w / 2, 2);
    }
    profile_free(&p);
    return ok;
}

/* A profile (r, z) from a pole on the axis to a pole on the axis turned about
 * z in n steps. Segment s (point s to s + 1) is smooth (the points' normals
 * nr, nz) or flat. Going down the outside with growing angle, the outward
 * normal is d(profile) x d(angle), so quads are (s, j), (s+1, j), (s+1, j+1). */
static bool lathe(struct ga_mesh *mesh, const double *r, const double *z, const double *nr, const double *nz,
                  const bool *smooth, int points, int n)
{
    double *cs = malloc(sizeof(double) * 2 * (size_t)n);
    uint32_t *ring = malloc(sizeof(uint32_t) * 2 * (size_t)n);
    if (!cs || !ring) {
        free(cs);
        free(ring);
        return false;
    }
    double *sn = cs + n;
    for (int j = 0; j < n; j++) {
        cs[j] = cos(2.0 * PI * j / n);
        sn[j] = sin(2.0 * PI * j / n);
    }
    uint32_t *ra = ring, *rb = ring + n;
    for (int s = 0; s + 1 < points; s++) {
        int a = s, b = s + 1;
        double dr = r[b] - r[a], dz = z[b] - z[a];
        double fa_r = smooth[s] ? nr[a] : -dz, fa_z = smooth[s] ? nz[a] : dr;
        double fb_r = smooth[s] ? nr[b] : -dz, fb_z = smooth[s] ? nz[b] : dr;
        if (r[a] > 0)
            for (int j = 0; j < n; j++)
                ra[j] = ga_mesh_vertex(mesh, ga_v3_make(r[a] * cs[j], r[a] * sn[j], z[a]),
                                       ga_v3_make(fa_r * cs[j], fa_r * sn[j], fa_z));
        if (r[b] > 0)
            for (int j = 0; j < n; j++)
                rb[j] = ga_mesh_vertex(mesh, ga_v3_make(r[b] * cs[j], r[b] * sn[j], z[b]),
                                       ga_v3_make(fb_r * cs[j], fb_r * sn[j], fb_z));
        for (int j = 0; j < n; j++) {
            int k = (j + 1) % n;
            double mid = 2.0 * PI * (j + 0.5) / n;
            if (r[a] <= 0) {
                uint32_t pole = ga_mesh_vertex(mesh, ga_v3_make(0, 0, z[a]),
                                               ga_v3_make(fa_r * cos(mid), fa_r * sin(mid), fa_z));
                ga_mesh_triangle(mesh, pole, rb[j], rb[k]);
            } else if (r[b] <= 0) {
                uint32_t pole = ga_mesh_vertex(mesh, ga_v3_make(0, 0, z[b]),
                                               ga_v3_make(fb_r * cos(mid), fb_r * sin(mid), fb_z));
                ga_mesh_triangle(mesh, ra[j], pole, ra[k]);
            } else {
                ga_mesh_triangle(mesh, ra[j], rb[j], rb[k]);
                ga_mesh_triangle(mesh, ra[j], rb[k], ra[k]);
            }
        }
    }
    free(cs);
    free(ring);
    return !mesh->failed;
}

#define RIVET_MAX_DOME 256

static bool build_rivet(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double rd = s->size[0], hd = s->size[1], rs = s->size[2], len = s->size[3];
    int n = s->segments[0], d = s->segments[1];
    if (d > RIVET_MAX_DOME)
        d = RIVET_MAX_DOME;
    enum { MAX_POINTS = RIVET_MAX_DOME + 4 };
    double r[MAX_POINTS], z[MAX_POINTS], nr[MAX_POINTS], nz[MAX_POINTS];
    bool smooth[MAX_POINTS];
    int k = 0;
    /* the dome from its pole to its rim: normals of the ellipse (r/rd^2, z/hd^2) */
    for (int i = 0; i <= d; i++, k++) {
        double g = 0.5 * PI * i / d;
        r[k] = i == 0 ? 0.0 : i == d ? rd : rd * sin(g);
        z[k] = i == d ? 0.0 : hd * cos(g);
        struct ga_v3 nrm = ga_v3_normalize(ga_v3_make(sin(g) / rd, 0, cos(g) / hd));
        nr[k] = i == d ? 1.0 : nrm.x;
        nz[k] = i == d ? 0.0 : nrm.z;
        smooth[k] = true;
    }
    smooth[k - 1] = false; /* rim to shank: the flat underside of the head */
    r[k] = rs, z[k] = 0, nr[k] = 1, nz[k] = 0, smooth[k] = false, k++;
    r[k] = rs, z[k] = -len, nr[k] = 1, nz[k] = 0, smooth[k] = false, k++;
    r[k] = 0, z[k] = -len, nr[k] = 0, nz[k] = -1, smooth[k] = false, k++;
    return lathe(mesh, r, z, nr, nz, smooth, k, n);
}

static bool build_bolt(const struct ga_shape *s, struct ga_mesh *mesh)
{
    double rh = s->size[0], hh = s->size[1], rs = s->size[2], len = s->size[3];
    int n = s->segments[0], k = n / 6;
    struct ga_v3 hex0[6], hex1[6], *top = malloc(sizeof *top * 2 * (size_t)n);
    uint32_t *ring = malloc(sizeof(uint32_t) * (size_t)n);
    if (!top || !ring) {
        free(top);
        free(ring);
        return false;
    }
    struct ga_v3 *bottom = top + n, up = ga_v3_make(0, 0, 1), down = ga_v3_make(0, 0, -1);
    for (int i = 0; i < 6; i++) {
        double a = PI * i / 3;
        hex0[i] = ga_v3_make(rh * cos(a), rh * sin(a), 0);
        hex1[i] = ga_v3_make(hex0[i].x, hex0[i].y, hh);
    }
    for (int j = 0; j < n; j++) {
        double a = 2.0 * PI * j / n;
        top[j] = ga_v3_make(rs * cos(a), rs * sin(a), 0);
        bottom[j] = ga_v3_make(top[j].x, top[j].y, -len);
    }
    /* the head's top face and its six sides */
    uint32_t base = (uint32_t)mesh->vertex_count;
    for (int i = 0; i < 6; i++)
        ga_mesh_vertex(mesh, hex1[i], up);
    for (int i = 1; i < 5; i++)
        ga_mesh_triangle_facing(mesh, base, base + (uint32_t)i, base + (uint32_t)i + 1, up);
    for (int i = 0; i < 6; i++) {
        int i1 = (i + 1) % 6;
        struct ga_v3 out = ga_v3_make(cos(PI * (i + 0.5) / 3), sin(PI * (i + 0.5) / 3), 0);
        uint32_t a = ga_mesh_vertex(mesh, hex0[i], out), b = ga_mesh_vertex(mesh, hex0[i1], out);
        uint32_t c = ga_mesh_vertex(mesh, hex1[i1], out), d = ga_mesh_vertex(mesh, hex1[i], out);
        ga_mesh_triangle_facing(mesh, a, b, c, out);
        ga_mesh_triangle_facing(mesh, a, c, d, out);
    }
    /* the head's underside: the hexagon around the shank's top circle. Each hex
     * edge covers k circle points; the first half fan from its start corner, the
     * second half from its end corner, so no triangle crosses the circle */
    uint32_t hb = (uint32_t)mesh->vertex_count;
    for (int i = 0; i < 6; i++)
        ga_mesh_vertex(mesh, hex0[i], down);
    uint32_t cb = (uint32_t)mesh->vertex_count;
    for (int j = 0; j < n; j++)
        ga_mesh_vertex(mesh, top[j], down);
    for (int i = 0; i < 6; i++) {
        uint32_t a = hb + (uint32_t)i, b = hb + (uint32_t)((i + 1) % 6);
        int j0 = k * i, mid = j0 + k / 2;
        for (int j = j0; j < mid; j++)
            ga_mesh_triangle_facing(mesh, a, cb + (uint32_t)j, cb + (uint32_t)(j + 1), down);
        for (int j = mid; j < j0 + k; j++)
            ga_mesh_triangle_facing(mesh, b, cb + (uint32_t)j, cb + (uint32_t)((j + 1) % n), down);
        ga_mesh_triangle_facing(mesh, a, b, cb + (uint32_t)mid, down);
    }
    /* the shank's side, top to bottom with growing angle, and its flat end */
    for (int j = 0; j < n; j++) {
        double a = 2.0 * PI * j / n;
        ring[j] = ga_mesh_vertex(mesh, top[j], ga_v3_make(cos(a), sin(a), 0));
        ga_mesh_vertex(mesh, bottom[j], ga_v3_make(cos(a), sin(a), 0));
    }
    for (int j = 0; j < n; j++) {
        uint32_t a = ring[j], b = ring[j] + 1, c = ring[(j + 1) % n] + 1, d = ring[(j + 1) % n];
        ga_mesh_triangle(mesh, a, b, c);
        ga_mesh_triangle(mesh, a, c, d);
    }
    uint32_t eb = (uint32_t)mesh->vertex_count;
    for (int j = 0; j < n; j++)
        ga_mesh_vertex(mesh, bottom[j], down);
    for (int j = 1; j + 1 < n; j++)
        ga_mesh_triangle_facing(mesh, eb, eb + (uint32_t)j, eb + (uint32_t)j + 1, down);
    free(top);
    free(ring);
    return !mesh->failed;
}

uint64_t ga_shape_triangles(const struct ga_shape *s)
{
    uint64_t n = (uint64_t)s->segments[0], m = (uint64_t)s->segments[1];
    switch (s->kind) {
    case GA_SHAPE_FRAME: return sweep_triangles(4, 0, s->segments[0], true);
    case GA_SHAPE_STRINGER_BOX: return sweep_triangles(4, 2, 2, false);
    case GA_SHAPE_STRINGER_Z: return sweep_triangles(8, 6, 2, false);
    case GA_SHAPE_SKIN: return sweep_triangles(2 * (s->segments[0] + 1), 2 * s->segments[0], s->segments[1] + 1, false);
    case GA_SHAPE_PIPE: return sweep_triangles(s->segments[0], s->segments[0] - 2, pipe_stations(s), false);
    case GA_SHAPE_BRACKET: return sweep_triangles(6, 4, 2, false);
    case GA_SHAPE_BOLT: return 4 * n + 20;
    case GA_SHAPE_RIVET: return 2 * n * ((m > RIVET_MAX_DOME ? RIVET_MAX_DOME : m) + 2);
    case GA_SHAPE_KIND_COUNT: break;
    }
    return 0;
}

bool ga_shape_build(const struct ga_shape *shape, struct ga_mesh *mesh)
{
    switch (shape->kind) {
    case GA_SHAPE_FRAME: return build_frame(shape, mesh);
    case GA_SHAPE_STRINGER_BOX: return build_stringer_box(shape, mesh);
    case GA_SHAPE_STRINGER_Z: return build_stringer_z(shape, mesh);
    case GA_SHAPE_SKIN: return build_skin(shape, mesh);
    case GA_SHAPE_PIPE: return build_pipe(shape, mesh);
    case GA_SHAPE_BRACKET: return build_bracket(shape, mesh);
    case GA_SHAPE_BOLT: return build_bolt(shape, mesh);
    case GA_SHAPE_RIVET: return build_rivet(shape, mesh);
    case GA_SHAPE_KIND_COUNT: break;
    }
    return false;
}
