/* iso_kind.c - direct iso-surfaces as a geometry kind (iso_kind.h).
 *
 * Why one primitive rather than one per block of macrocells: the macrocell
 * walk already skips every block that cannot reach the value, a whole cube
 * of them a leap (the kind's leap field, rebuilt in O(macrocells) when the
 * value changes; macrocell.h LEAPS), and it carries the field's sign from block to
 * block (iso_cell.h HALF-OPEN SEGMENTS), so no crossing on a block face is
 * lost or found twice. Blocks as primitives would need boxes that follow
 * the value (a rebuild, or a refit, per value) to cull anything more, and
 * each block's walk would start afresh at its face, where the sign of a
 * value ~0 is whatever that block's cubic rounds it to. */
#include "iso_kind.h"

#include <float.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "engine/accel/ray.h"
#include "engine/base/series.h"

/* What one step of the field is: the samples, their grid and what the kind
 * derives from them once. */
typedef struct iso_field {
    const volume *v;             /* the samples (owned_v or the caller's) */
    const macrocell_grid *grid;  /* built over v (owned_grid or the caller's) */
    volume *owned_v;             /* freed with the field; NULL when borrowed */
    macrocell_grid *owned_grid;  /* likewise */
    float boundary_min, boundary_max; /* over the samples on the six faces of the box */
    /* ACTIVE BOX: the world box of the macrocells whose samples are not all
     * equal, rounded outwards to float. A cell whose 8 corners are equal
     * holds a constant field, so no crossing of any iso-value (no sign
     * change); every crossing lies in a non-constant macrocell. The box is
     * the primitive's bounds whatever the value: the BVH culls the rays that
     * miss it (the zero background around a scan) before any walk. */
    bool active;                      /* some macrocell is not constant */
    vec3 active_lo, active_hi;
} iso_field;

struct iso_volume {
    atomic_uint refs;            /* kinds + the creator's reference until released */
    iso_field now;               /* the step shown; changes only in iso_volume_set_step (a serial
                                    section), read by every query */
    /* TIME STEPS: NULL: one field. The loader thread reads only `first`,
     * macrocell_k and read, which never change once the series is attached */
    series *series;
    volume_file_reader *read;    /* how a step's file is read */
    volume first;                /* step 0's layout (no samples: data, map, buffer NULL) */
    uint32_t macrocell_k;        /* every step's grid block edge: step 0's */
    iso_volume_watcher *watchers; /* told of every swap; changed only where nothing traces */
};

struct iso_kind {
    iso_volume *shared;   /* one reference held */
    float iso;            /* the value as set; written only where nothing traces */
    float iso_traced;     /* the value the walks use (traced_value): iso, or just above it */
    vec3 colour;          /* linear RGB of every hit */
    uint32_t material_id; /* scene material */
    iso_method method;    /* how a cell's root is found (iso_cell.h) */
    uint8_t *leap;        /* leap field of the grid for iso_traced (marked: cannot reach it); rebuilt with
                             the value, O(macrocells), where nothing traces */
};

/* the walks' leap field for the kind's current value (iso_cell.h) */
static void build_leap(iso_kind *k)
{
    const macrocell_grid *g = k->shared->now.grid;
    size_t count = macrocell_count(g);
    for (size_t m = 0; m < count; m++)
        k->leap[m] = macrocell_may_reach(g, m, k->iso_traced) ? 0 : MACROCELL_LEAP_MARK;
    macrocell_leap_build(g, k->leap);
}

/* ---- the shared volume ------------------------------------------------- */

static void note_range(const volume *v, uint32_t i, uint32_t j, uint32_t k, float *lo, float *hi)
{
    float s = volume_sample(v, i, j, k);
    *lo = s < *lo ? s : *lo;
    *hi = s > *hi ? s : *hi;
}

/* min and max over the samples of the box's faces (each face sample once or
 * twice: a few n^2 reads) */
static void boundary_range(const volume *v, float *lo, float *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (uint32_t k = 0; k < v->nz; k++)
        for (uint32_t j = 0; j < v->ny; j++) {
            note_range(v, 0, j, k, lo, hi);
            note_range(v, v->nx - 1, j, k, lo, hi);
        }
    for (uint32_t k = 0; k < v->nz; k++)
        for (uint32_t i = 0; i < v->nx; i++) {
            note_range(v, i, 0, k, lo, hi);
            note_range(v, i, v->ny - 1, k, lo, hi);
        }
    for (uint32_t j = 0; j < v->ny; j++)
        for (uint32_t i = 0; i < v->nx; i++) {
            note_range(v, i, j, 0, lo, hi);
            note_range(v, i, j, v->nz - 1, lo, hi);
        }
}

static void active_box(iso_field *s)
{
    const macrocell_grid *g = s->grid;
    uint32_t lo[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi[3] = {0, 0, 0};
    s->active = false;
    for (uint32_t c = 0; c < g->m[2]; c++)
        for (uint32_t b = 0; b < g->m[1]; b++)
            for (uint32_t a = 0; a < g->m[0]; a++) {
                size_t i = macrocell_index(g, a, b, c);
                if (!(g->min[i] < g->max[i]))
                    continue;
                const uint32_t m[3] = {a, b, c};
                for (int x = 0; x < 3; x++) {
                    lo[x] = m[x] < lo[x] ? m[x] : lo[x];
                    hi[x] = m[x] > hi[x] ? m[x] : hi[x];
                }
                s->active = true;
            }
    if (!s->active)
        return;
    float wlo[3], whi[3];
    for (int x = 0; x < 3; x++) {
        /* macrocell m spans cells m k .. min((m + 1) k, cells) */
        uint32_t c0 = lo[x] * g->k, c1 = (hi[x] + 1) * g->k;
        c1 = c1 < g->cells[x] ? c1 : g->cells[x];
        wlo[x] = nextafterf((float)(g->origin[x] + c0 * g->spacing[x]), -INFINITY);
        whi[x] = nextafterf((float)(g->origin[x] + c1 * g->spacing[x]), INFINITY);
    }
    s->active_lo = v3(wlo[0], wlo[1], wlo[2]);
    s->active_hi = v3(whi[0], whi[1], whi[2]);
}

static void field_free(iso_field *f)
{
    macrocell_grid_destroy(f->owned_grid);
    volume_destroy(f->owned_v);
}

static iso_volume *shared_make(const volume *v, const macrocell_grid *grid, tess_error *err)
{
    iso_volume *s = calloc(1, sizeof *s);
    if (!s) {
        tess_error_set(err, "iso surface: out of memory");
        return NULL;
    }
    atomic_init(&s->refs, 1u);
    s->now.v = v;
    s->now.grid = grid;
    boundary_range(v, &s->now.boundary_min, &s->now.boundary_max);
    active_box(&s->now);
    return s;
}

iso_volume *iso_volume_create(volume *v, macrocell_grid *grid, tess_error *err)
{
    if (!v) {
        macrocell_grid_destroy(grid);
        tess_error_set(err, "iso surface: no volume");
        return NULL;
    }
    if (!grid)
        grid = macrocell_grid_create(v, MACROCELL_DEFAULT_K, err);
    iso_volume *s = grid ? shared_make(v, grid, err) : NULL;
    if (!s) {
        macrocell_grid_destroy(grid);
        volume_destroy(v);
        return NULL;
    }
    s->now.owned_v = v;
    s->now.owned_grid = grid;
    return s;
}

iso_volume *iso_volume_borrow(const volume *v, const macrocell_grid *grid, tess_error *err)
{
    if (!v || !grid) {
        tess_error_set(err, "iso surface: no volume or no macrocell grid");
        return NULL;
    }
    return shared_make(v, grid, err);
}

void iso_volume_retain(iso_volume *shared) { atomic_fetch_add_explicit(&shared->refs, 1u, memory_order_relaxed); }

void iso_volume_release(iso_volume *shared)
{
    if (!shared)
        return;
    /* acq_rel: the last releaser sees every other holder's reads finished */
    if (atomic_fetch_sub_explicit(&shared->refs, 1u, memory_order_acq_rel) != 1u)
        return;
    series_destroy(shared->series); /* first: its loader may be loading a step */
    field_free(&shared->now);
    free(shared);
}

const volume *iso_volume_data(const iso_volume *shared) { return shared->now.v; }
const macrocell_grid *iso_volume_grid(const iso_volume *shared) { return shared->now.grid; }

/* ---- time steps (series.h) ------------------------------------------------ */

static void free_step(void *ctx, void *data)
{
    (void)ctx;
    field_free(data);
    free(data);
}

/* The loader thread's work: one step's samples, checked against step 0's
 * layout, with its grid, boundary range and active box, all off the render
 * threads. Reads only the series' constant members of the shared volume. */
static void *load_step(void *ctx, const char *path, uint32_t step, tess_error *err)
{
    (void)step;
    const iso_volume *s = ctx;
    iso_field *f = calloc(1, sizeof *f);
    if (!f) {
        tess_error_set(err, "%s: out of memory", path);
        return NULL;
    }
    f->v = f->owned_v = s->read(path, err); /* its errors name the path */
    bool ok = f->v && volume_same_layout(&s->first, f->v, path, err);
    if (ok && !(f->grid = f->owned_grid = macrocell_grid_create(f->v, s->macrocell_k, err))) {
        tess_error_prefix(err, "%s: ", path);
        ok = false;
    }
    if (!ok) {
        free_step(NULL, f);
        return NULL;
    }
    boundary_range(f->v, &f->boundary_min, &f->boundary_max);
    active_box(f);
    return f;
}

bool iso_volume_attach_series(iso_volume *shared, const char *const *paths, uint32_t count, volume_file_reader *read,
                              tess_error *err)
{
    if (!shared->now.owned_v)
        return tess_error_set(err, "iso surface: a borrowed volume cannot have time steps");
    shared->first = *shared->now.v;
    shared->first.data = shared->first.map = shared->first.buffer = NULL;
    shared->first.map_bytes = 0;
    shared->macrocell_k = shared->now.grid->k;
    shared->read = read;
    shared->series = series_create(paths, count, 0, load_step, free_step, shared, err);
    if (!shared->series)
        tess_error_prefix(err, "volume: ");
    return shared->series != NULL;
}

uint32_t iso_volume_step_count(const iso_volume *shared)
{
    return shared->series ? series_step_count(shared->series) : 1;
}

uint32_t iso_volume_step(const iso_volume *shared) { return shared->series ? series_step(shared->series) : 0; }

bool iso_volume_step_ready(iso_volume *shared, uint32_t step)
{
    return shared->series ? series_ready(shared->series, step) : step == 0;
}

bool iso_volume_set_step(iso_volume *shared, uint32_t step, tess_error *err)
{
    if (!shared->series)
        return true; /* one field: every step is it */
    void *taken; /* a failed step is not read again by the other sharers (series.h) */
    if (!series_take(shared->series, step, &taken, err))
        return false;
    if (!taken)
        return true; /* shown already (another kind of this volume took it) */
    iso_field old = shared->now;
    shared->now = *(iso_field *)taken;
    free(taken);
    for (iso_volume_watcher *w = shared->watchers; w; w = w->next)
        w->swapped(w->ctx, shared->now.v, shared->now.grid);
    field_free(&old); /* after the watchers: nothing points to it now */
    series_done(shared->series); /* the old step is gone: the next one may load */
    return true;
}

void iso_volume_watch(iso_volume *shared, iso_volume_watcher *w)
{
    w->next = shared->watchers;
    shared->watchers = w;
}

void iso_volume_unwatch(iso_volume *shared, iso_volume_watcher *w)
{
    for (iso_volume_watcher **at = &shared->watchers; *at; at = &(*at)->next)
        if (*at == w) {
            *at = w->next;
            return;
        }
}

/* ---- the kind ------------------------------------------------------------ */

/* The value the walks look for. Integer samples (uint8, int16, uint16)
 * equal to an integer iso-value make f exactly 0 at those samples, and a
 * face or edge whose corners all equal it is a sheet where f == 0: a ray
 * through it touches the surface without crossing, the walk reports the
 * touch as a root, and parity (caps) breaks (the MRI at iso 60 shows it on
 * a few rays in 10^4). Tracing the next float above such a value instead
 * makes every sample differ from it (simulation of simplicity): samples
 * equal to the value count as below it, and the surface moves by one ulp
 * of the value over the gradient, far below anything a pixel shows. Float
 * data keeps the value as given. */
static float traced_value(const volume *v, float iso)
{
    if (v->type != VOLUME_FLOAT32 && iso == floorf(iso))
        return nextafterf(iso, INFINITY);
    return iso;
}

iso_kind *iso_kind_create_shared(iso_volume *shared, float iso_value, vec3 colour, uint32_t material_id,
                                 iso_method method, tess_error *err)
{
    if (!shared) {
        tess_error_set(err, "iso surface: no volume");
        return NULL;
    }
    if (!isfinite(iso_value)) {
        tess_error_set(err, "iso surface: the iso-value %g is not finite", (double)iso_value);
        return NULL;
    }
    iso_kind *k = calloc(1, sizeof *k);
    if (!k) {
        tess_error_set(err, "iso surface: out of memory");
        return NULL;
    }
    k->leap = malloc(macrocell_count(shared->now.grid));
    if (!k->leap) {
        free(k);
        tess_error_set(err, "iso surface: out of memory");
        return NULL;
    }
    iso_volume_retain(shared);
    k->shared = shared;
    k->iso = iso_value;
    k->iso_traced = traced_value(shared->now.v, iso_value);
    k->colour = colour;
    k->material_id = material_id;
    k->method = method;
    build_leap(k);
    return k;
}

iso_kind *iso_kind_create(const volume *v, const macrocell_grid *grid, float iso_value, vec3 colour,
                          uint32_t material_id, iso_method method, tess_error *err)
{
    iso_volume *shared = iso_volume_borrow(v, grid, err);
    if (!shared)
        return NULL;
    iso_kind *k = iso_kind_create_shared(shared, iso_value, colour, material_id, method, err);
    iso_volume_release(shared); /* the kind's own reference keeps it */
    return k;
}

void iso_kind_destroy(iso_kind *k)
{
    if (!k)
        return;
    iso_volume_release(k->shared);
    free(k->leap);
    free(k);
}

bool iso_kind_set_value(iso_kind *k, float iso_value)
{
    if (!isfinite(iso_value))
        return false;
    k->iso = iso_value;
    k->iso_traced = traced_value(k->shared->now.v, iso_value);
    build_leap(k);
    return true;
}

float iso_kind_value(const iso_kind *k) { return k->iso; }

void iso_kind_range(const iso_kind *k, float *lo, float *hi)
{
    *lo = k->shared->now.v->min;
    *hi = k->shared->now.v->max;
}

/* ---- geometry ops -------------------------------------------------------- */

static uint32_t kind_count(const void *data)
{
    (void)data;
    return 1u;
}

/* The active box (iso_volume ACTIVE BOX): every crossing lies inside it;
 * false when the field is constant everywhere (no surface at any value). */
static bool kind_bounds(const void *data, aabb *out)
{
    const iso_field *s = &((const iso_kind *)data)->shared->now;
    *out = (aabb){s->active_lo, s->active_hi};
    return s->active;
}

static bool kind_prim_bounds(const void *data, uint32_t prim, aabb *out)
{
    (void)prim;
    return kind_bounds(data, out);
}

/* The roots of one cell's cubic in (0, s1] by the kind's method, in order
 * (f0: the value at 0 as the walk knows it, iso_cell.h HALF-OPEN SEGMENTS). */
static int cell_roots(iso_method method, const iso_cubic *f, double f0, double s1, double tol_s, double roots[3])
{
    switch (method) {
    case ISO_METHOD_EXACT: return iso_cell_roots(f, 0.0, f0, s1, tol_s, roots);
    case ISO_METHOD_LINEAR: return iso_cell_root_linear(f, 0.0, f0, s1, roots) ? 1 : 0;
    case ISO_METHOD_REGULA_FALSI:
        return iso_cell_root_regula_falsi(f, 0.0, f0, s1, ISO_CELL_RF_STEPS, roots) ? 1 : 0;
    }
    return 0;
}

/* A group of crossings that round to one float t. */
typedef struct crossing_group {
    float t;   /* their float t */
    int count; /* how many so far; 0: no group open */
} crossing_group;

/* Close the group when the walk has passed its float t (everything later
 * rounds above it): true with *t when it holds an odd number of crossings
 * (the ray changes side there: one hit); an even number cancels (a sheet
 * thinner than the float t's resolution: the ray leaves on the side it
 * came from, and reporting one crossing would break parity). */
static bool close_group(crossing_group *g, double t_now, bool at_end, float *t)
{
    if (g->count == 0 || (!at_end && !((float)t_now > g->t)))
        return false;
    bool odd = g->count & 1;
    g->count = 0;
    if (odd)
        *t = g->t;
    return odd;
}

/* The first float t in (t_near, box exit) where the ray changes side of
 * the surface. The walk iso_volume_first_hit takes (iso_cell.h), with every
 * root of a cell taken; crossings whose float t is not above t_near were
 * reported before (or are a next-hit query's bound). */
static bool first_crossing(const iso_kind *k, const double org[3], const double dir[3], float t_near, float *t)
{
    const macrocell_grid *g = k->shared->now.grid;
    const volume *vol = k->shared->now.v;
    const float iso = k->iso_traced;
    /* the exact method's roots are the field's: a walk may start anywhere,
     * at t_near. The cheap methods' roots depend on where a cell's segment
     * starts (they interpolate between its ends): a walk from t_near would
     * move the crossing a next-hit query starts from and find it again. They
     * start two cell diagonals before t_near instead, in an earlier cell, so
     * the cell holding t_near is entered at its face, the same segment
     * (boundary t's are computed from their planes) as every query of the
     * ray sees */
    double t_start = t_near;
    if (k->method != ISO_METHOD_EXACT) {
        double diag2 = 0.0, dir2 = 0.0;
        for (int a = 0; a < 3; a++) {
            diag2 += g->spacing[a] * g->spacing[a];
            dir2 += dir[a] * dir[a];
        }
        t_start -= 2.0 * sqrt(diag2 / dir2);
    }
    iso_cell_walk walk;
    if (!iso_cell_walk_begin(&walk, vol, g, org, dir, t_start, INFINITY, iso))
        return false;
    walk.leap = k->leap;
    double tol_s = ISO_CELL_TOL / walk.dir_len; /* ISO_CELL_TOL cell widths, in t */
    crossing_group group = {0.f, 0};
    iso_cell_candidate cand;
    /* a group closes where the walk passes its t: at a candidate's entry, or
     * where the walk stops for it in skipped space (which holds no crossing) */
    for (;;) {
        walk.stop_beyond = group.count > 0 ? group.t : INFINITY;
        if (!iso_cell_walk_next(&walk, &cand)) {
            if (!walk.stopped)
                break;
            if (close_group(&group, INFINITY, true, t))
                return true;
            continue; /* an even group: the ray goes on */
        }
        if (close_group(&group, cand.te, false, t))
            return true;
        double roots[3];
        int n = cell_roots(k->method, &cand.f, cand.f0, cand.tx - cand.te, tol_s, roots);
        for (int i = 0; i < n; i++) {
            float ft = (float)(cand.te + roots[i]);
            if (!(ft > t_near))
                continue;
            if (group.count > 0 && ft != group.t && close_group(&group, cand.te + roots[i], true, t))
                return true;
            group.t = ft;
            group.count++;
        }
    }
    return close_group(&group, INFINITY, true, t);
}

/* The first crossing whose float t is in (t_near, t_far]. The walk always
 * runs on to the box's exit past t_far (t_far only accepts or refuses what
 * it found), so the t found never depends on how far other hits have
 * shortened the ray: single rays and packets agree bit for bit. */
static bool kind_intersect(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v)
{
    (void)prim;
    const double org[3] = {r->org.x, r->org.y, r->org.z}, dir[3] = {r->dir.x, r->dir.y, r->dir.z};
    float found;
    *u = *v = 0.f;
    if (!first_crossing(data, org, dir, r->t_near, &found) || !(found <= r->t_far))
        return false;
    *t = found;
    return true;
}

/* The field's gradient at sample (i, j, k) by central differences (one-sided
 * on the volume's faces), per world unit. */
static void sample_gradient(const volume *v, const double spacing[3], uint32_t i, uint32_t j, uint32_t k,
                            double out[3])
{
    const uint32_t at[3] = {i, j, k}, n[3] = {v->nx, v->ny, v->nz};
    for (int a = 0; a < 3; a++) {
        uint32_t lo[3] = {i, j, k}, hi[3] = {i, j, k};
        lo[a] = at[a] > 0 ? at[a] - 1 : at[a];
        hi[a] = at[a] + 1 < n[a] ? at[a] + 1 : at[a];
        double span = (double)(hi[a] - lo[a]) * spacing[a];
        out[a] = ((double)volume_sample(v, hi[0], hi[1], hi[2]) - volume_sample(v, lo[0], lo[1], lo[2])) / span;
    }
}

/* SHADING NORMAL: the analytic gradient of the trilinear field (the
 * geometric normal) jumps at every cell face, which shows the cells as
 * facets, and on 8-bit data as terraces; the central-difference gradients
 * of the cell's 8 samples, interpolated trilinearly at the hit, are
 * continuous across faces. False when they cancel (then the geometric
 * normal shades). */
static bool smooth_normal(const volume *v, const double spacing[3], const uint32_t cell[3], const double local[3],
                          vec3 *out)
{
    double sum[3] = {0.0, 0.0, 0.0};
    for (int c = 0; c < 8; c++) {
        double gc[3], w = 1.0;
        uint32_t at[3];
        for (int a = 0; a < 3; a++) {
            int up = c >> a & 1;
            at[a] = cell[a] + (uint32_t)up;
            w *= up ? local[a] : 1.0 - local[a];
        }
        sample_gradient(v, spacing, at[0], at[1], at[2], gc);
        for (int a = 0; a < 3; a++)
            sum[a] += w * gc[a];
    }
    double len2 = sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2];
    if (!(len2 > 0.0) || !isfinite(len2))
        return false;
    double inv = 1.0 / sqrt(len2);
    *out = v3((float)(sum[0] * inv), (float)(sum[1] * inv), (float)(sum[2] * inv));
    return true;
}

/* u = 2^-24; gamma(n) = n u / (1 - n u) (pbrt-v4 6.8.1) */
static float gamma_ulps(int n) { return (float)n * 0x1p-24f / (1.f - (float)n * 0x1p-24f); }

static void kind_describe(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                          geometry_surface *out)
{
    (void)prim;
    (void)need_position; /* the normal needs the point anyway */
    const iso_kind *k = data;
    const volume *vol = k->shared->now.v;
    const macrocell_grid *g = k->shared->now.grid;
    const double org[3] = {r->org.x, r->org.y, r->org.z}, dir[3] = {r->dir.x, r->dir.y, r->dir.z};
    double p[3], local[3], grad[3];
    uint32_t cell[3];
    const uint32_t n[3] = {vol->nx, vol->ny, vol->nz};
    float err[3];
    /* ERROR BOUND, per axis a. The point is org + t dir with t the float
     * rounding of the root t* (|t - t*| <= u |t|: |dir_a| u |t| on axis a),
     * computed in double and rounded once (u |p_a| <= u (|org_a| + |t
     * dir_a|)); gamma(SURFACE_ERROR_ULPS) of |org_a| + |t dir_a| covers both
     * many times, as it covers the double-precision test of a ray leaving
     * the point (1e-16 relative). The exact root is within ISO_CELL_TOL
     * cell widths along the ray of the crossing, at most ISO_CELL_TOL
     * spacing_a on axis a (doubled for the voxel mapping's rounding). The
     * cheap methods' roots are the linear or regula-falsi surface's, not the
     * trilinear one's: they may be anywhere in the cell, so one spacing per
     * axis (a heuristic: it keeps rays leaving the point off the cell's
     * crossing in practice, with no proof). */
    const float gam = gamma_ulps(SURFACE_ERROR_ULPS);
    for (int a = 0; a < 3; a++) {
        p[a] = org[a] + (double)h->t * dir[a];
        double root_tol = k->method == ISO_METHOD_EXACT ? 2.0 * ISO_CELL_TOL * g->spacing[a] : g->spacing[a];
        err[a] = gam * (fabsf((float)org[a]) + fabsf(h->t * (float)dir[a])) + (float)root_tol;
        /* the cell holding the point (the last one on the far faces) and the point in it */
        double vox = (p[a] - g->origin[a]) / g->spacing[a];
        double c = floor(vox);
        c = c < 0.0 ? 0.0 : (c > (double)(n[a] - 2) ? (double)(n[a] - 2) : c);
        cell[a] = (uint32_t)c;
        local[a] = vox - c;
    }
    float corner[8];
    volume_cell_corners(vol, cell[0], cell[1], cell[2], corner);
    iso_cell_gradient(corner, local, grad);
    double len2 = 0.0;
    for (int a = 0; a < 3; a++) {
        grad[a] /= g->spacing[a];
        len2 += grad[a] * grad[a];
    }
    vec3 normal;
    if (len2 > 0.0 && isfinite(len2)) {
        double inv = 1.0 / sqrt(len2);
        normal = v3((float)(grad[0] * inv), (float)(grad[1] * inv), (float)(grad[2] * inv));
    } else {
        /* a crossing where the gradient vanishes (a saddle exactly on the
         * surface): face the ray */
        normal = v3_normalize(v3_scale(r->dir, -1.f));
    }
    out->position = v3((float)p[0], (float)p[1], (float)p[2]);
    out->position_error = v3(err[0], err[1], err[2]);
    out->geometric_n = normal;
    vec3 smooth;
    /* the shading normal on the geometric normal's side (a shading normal
     * that disagrees with it would light the back of the surface) */
    out->shading_n = smooth_normal(vol, g->spacing, cell, local, &smooth) && v3_dot(smooth, normal) > 0.f ? smooth : normal;
    out->has_colour = true;
    out->colour = k->colour;
    out->material_id = k->material_id;
}

static size_t kind_bytes(const void *data)
{
    /* the volume and grid are shared (and may be borrowed): counted by
     * whoever loaded them, not once per iso-value; the leap field is the kind's */
    const iso_kind *k = data;
    return sizeof(iso_kind) + macrocell_count(k->shared->now.grid);
}

static void kind_destroy(void *data) { iso_kind_destroy(data); }

static bool kind_closed(const void *data)
{
    const iso_kind *k = data;
    return k->iso_traced < k->shared->now.boundary_min || k->iso_traced > k->shared->now.boundary_max;
}

static bool kind_set_value(void *data, float value) { return iso_kind_set_value(data, value); }

static uint32_t kind_step_count(const void *data) { return iso_volume_step_count(((const iso_kind *)data)->shared); }

static bool kind_step_ready(void *data, uint32_t step) { return iso_volume_step_ready(((iso_kind *)data)->shared, step); }

/* Every kind of the volume (and its medium) shows the shared step: the
 * first to be set swaps it, the others find it shown. */
static bool kind_set_step(void *data, uint32_t step, tess_error *err)
{
    iso_kind *k = data;
    if (!iso_volume_set_step(k->shared, step, err))
        return false;
    /* the step's macrocells (whichever kind of the volume swapped them in):
     * every kind's set_step runs in the same serial section, before any walk */
    build_leap(k);
    return true;
}

static bool kind_value(const void *data, float *value, float *lo, float *hi)
{
    const iso_kind *k = data;
    *value = k->iso;
    iso_kind_range(k, lo, hi);
    return true;
}

static const geometry_controls kind_controls = {
    .step_count = kind_step_count,
    .step_ready = kind_step_ready,
    .set_step = kind_set_step,
    .set_value = kind_set_value,
    .value = kind_value,
};

const geometry_ops iso_kind_ops = {
    .name = "iso-surface",
    .leaf = GEOMETRY_LEAF_PRIMS,
    .prim_count = kind_count,
    .bounds = kind_bounds,
    .prim_bounds = kind_prim_bounds,
    .intersect = kind_intersect,
    .describe = kind_describe,
    .bytes = kind_bytes,
    .destroy = kind_destroy,
    .closed = kind_closed,
    .controls = &kind_controls,
};
