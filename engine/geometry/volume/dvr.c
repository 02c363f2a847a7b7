/* dvr.c - the emission-absorption integrator (dvr.h).
 *
 * PRE-INTEGRATION. After Engel, Kraus and Ertl, "High-Quality
 * Pre-Integrated Volume Rendering Using Hardware-Accelerated Pixel
 * Shading" (Graphics Hardware 2001): a slab of one step d whose value runs
 * linearly from sf (front) to sb (back) has optical depth
 *     tau = d / (sb - sf) * integral_sf^sb sigma(s) ds   (d sigma(sf) when sf = sb)
 * and opacity alpha = 1 - exp(-tau). Its colour is taken as the
 * extinction-weighted mean colour over [sf, sb],
 *     cbar = integral c sigma ds / integral sigma ds,
 * times alpha. Engel et al. take the colour as d / (sb - sf) integral c
 * sigma ds, which ignores the attenuation inside the slab and may exceed
 * alpha; the weighted mean keeps colour <= alpha, is exact for a constant
 * colour (so a constant colour gives c (1 - T) exactly, as the classic path
 * does) and still ignores the order of colours inside the slab: the one
 * approximation left, whose error grows with alpha times the colour's
 * change across the slab. Both integrals come from running sums (the
 * integral-table trick), so the SIZE^2 table costs O(SIZE^2) (plus
 * O(SIZE * PREINT_SUB) for the sums), each entry a difference of two sums.
 *   The table and its error. The transfer function is integrated on a
 * fine grid (PREINT_SUB pieces per half entry, sigma and c linear on each
 * piece), so a feature a few entries wide keeps its area. The table holds
 * DVR_PREINT_SIZE^2 slabs whose ends sit on entries (16 MiB at 1024, only
 * while pre-integration is on) and is read bilinearly: rounding the two
 * ends to entries instead would turn a span of 4 entries into 3 or 5, a
 * quarter of its optical depth. Entries hold associated colour (colour
 * times opacity), so a blend with a transparent neighbour (colour 0) does
 * not darken the slab. The table has the classic table's resolution
 * (COLORMAP_TABLE_SIZE): at 256 entries the blend smoothed the transfer
 * function over 1/255 of the range (18 value units on the CT bunny, whose
 * air noise sits on the opacity ramp), and its picture converged to a FLIP
 * of 0.045 against the classic reference instead of to it.
 * What remains: the bilinear blend of a slab's opacity between entries
 * (second order in the entry spacing, 1/1023 of the range; largest where
 * the transfer function has a kink inside the slab), and the colour-order
 * approximation above. tests/test_dvr.c measures whole rays through a
 * linear field (16 value units a voxel over a range of 1024, i.e. 16
 * entries a voxel) at steps 2 .. 1/64 against the closed form: a thin
 * sheet (an opacity tent 1.3 voxels wide) is off by at most 7.5e-5 at any
 * step (classic: 4.4e-2 at step 2, 1.4e-2 at step 1), a gentle ramp by
 * 6.8e-5 at step 1 (classic: 2.6e-5, exact in its extinction), a steep
 * ramp into a constant 0.4 by 4.7e-4 at step 1 (classic: 1.5e-4: a kink
 * inside a slab is where the blend is weakest). Pre-integration pays where
 * the transfer function is narrower than what a step crosses; for smooth
 * ones on noisy data (both shared volumes) the classic
 * midpoint rule is as good and cheaper.
 *
 * SKIPPING. The macrocell walk (macrocell.h) classes each macrocell as
 * empty (cell_opacity 0) or not and leaps over whole cubes of one class
 * (LEAPS: the leap field cell_leap, rebuilt with the transfer function in
 * O(macrocells)): empty cubes are passed, non-empty ones extend the run
 * being gathered, and each run is composited when an empty span closes
 * it. A run's ends are plane t's the cell-by-cell walk gives as well, and
 * where the walk ends a run reaches tb; the slab grid is global along the
 * ray, so leaping changes only which slabs are visited, and a slab visited
 * in empty space adds exactly 0: the pictures are bitwise those without
 * skipping. Before the leaps the MRI under mri-soft stepped a ray through
 * 18 non-empty macrocells (and, the profile said, as many empty ones) one
 * DDA step each: ~40 % of its time (perf: macrocell_walk_next,
 * volume_dda_next, the walk's loop); leaping made the frame ~1.15x as fast.
 *
 * COST. The time goes per sample: the CT bunny under ct-bone has opacity
 * in its air noise, so nothing is skipped there and a ray takes ~200
 * samples. A sample is a position in double (p = org + t dir at the slab's
 * midpoint, the arithmetic the pictures were made with, kept so they stay
 * bitwise the same), a cell and fractions (no clamp inside the box), four
 * x-neighbour pair loads with the x and y lerps lane-wise in SSE2, the table
 * index in double, and the composite. Per sample type there is one inlined
 * loop (composite_slabs), so no switch runs per corner. What bounds it is
 * a sample's chain of dependent operations (conversions, loads, three
 * lerps, the index, the table load; ~100 cycles) against the out-of-order
 * window, not the instruction count alone: with the memory reads made
 * cache-resident it still costs ~14 ns of ~17. Going further would take
 * several samples a SIMD group (float positions stepped incrementally,
 * gathers): that changes the pictures' bits, and was not done. The
 * pre-integrated path did not get faster on the CT bunny (single thread,
 * 480x270, step 0.5: 0.80 -> 0.97 s in one series, even in another): its
 * 16 MiB table's reads, not the sampler, look to be its cost; unexplained. */
#include "dvr.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* opacities at or above this count as this much in the pre-integration
 * table, so that sigma = -ln(1 - a) stays finite: 27.6 per voxel, which
 * leaves a transmittance under 1e-12 after one voxel (the classic path,
 * which uses powers, needs no such cap) */
#define PREINT_MAX_OPACITY (1.0 - 1e-12)
/* levels of the range-maximum tables: 2^11 = 2048 >= COLORMAP_TABLE_SIZE */
#define RANGE_LEVELS 11

/* the range-maximum tables of both binnings, side by side */
#define RANGE_SCRATCH_FLOATS ((size_t)RANGE_LEVELS * (COLORMAP_TABLE_SIZE + DVR_PREINT_SIZE))

_Static_assert((1 << RANGE_LEVELS) >= COLORMAP_TABLE_SIZE && (1 << RANGE_LEVELS) >= DVR_PREINT_SIZE,
               "range-maximum tables cover every table");

dvr_settings dvr_settings_default(void)
{
    return (dvr_settings){
        .step_vox = 0.5, .min_transmittance = 1.0f / 255.0f, .preintegrate = false, .skip_empty = true};
}

static bool settings_valid(const dvr_settings *s, tess_error *err)
{
    if (!(s->step_vox >= DVR_STEP_MIN_VOX && s->step_vox <= DVR_STEP_MAX_VOX))
        return tess_error_set(err, "volume rendering: step %g voxels is not in [%g, %g]", s->step_vox,
                              DVR_STEP_MIN_VOX, DVR_STEP_MAX_VOX);
    if (!(s->min_transmittance >= 0.0f && s->min_transmittance < 1.0f))
        return tess_error_set(err, "volume rendering: early termination threshold %g is not in [0, 1)",
                              (double)s->min_transmittance);
    return true;
}

/* ---- table indices --------------------------------------------------------- */

/* The entry colormap_lookup reads for `value` (the same arithmetic, so the
 * macrocells' opacities and the samples agree on every entry). */
static inline int classic_index(const colormap_table *t, float value)
{
    double u = ((double)value - t->lo) * t->scale;
    if (!(u > 0.0))
        u = 0.0;
    if (u > (double)(COLORMAP_TABLE_SIZE - 1))
        u = (double)(COLORMAP_TABLE_SIZE - 1);
    return (int)(u + 0.5);
}

/* The pre-integration table's coordinate of `value`: in [0, SIZE - 1],
 * entry k at k; the table is read bilinearly at (front, back). */
static inline double preint_coord(const dvr_volume *d, float value)
{
    double u = ((double)value - d->preint_lo) * d->preint_scale;
    if (!(u > 0.0))
        u = 0.0;
    if (u > (double)(DVR_PREINT_SIZE - 1))
        u = (double)(DVR_PREINT_SIZE - 1);
    return u;
}

/* the lower of the two entries a bilinear read at coordinate u blends */
static inline int preint_cell(double u)
{
    int i = (int)u;
    return i > DVR_PREINT_SIZE - 2 ? DVR_PREINT_SIZE - 2 : i;
}

/* The slab of front value vf and back value vb: the table read bilinearly
 * (colour and opacity each), so a slab's value span is not rounded to whole
 * entries: rounding each end would make a span of 4 entries read as 3 or 5,
 * a quarter of its optical depth off. */
static inline dvr_rgba preint_lookup(const dvr_volume *d, float vf, float vb)
{
    enum { N = DVR_PREINT_SIZE };
    double uf = preint_coord(d, vf), ub = preint_coord(d, vb);
    int f = preint_cell(uf), b = preint_cell(ub);
    float xf = (float)(uf - f), xb = (float)(ub - b);
    const dvr_rgba *p = d->preint + (size_t)f * N + (size_t)b;
    const dvr_rgba e00 = p[0], e01 = p[1], e10 = p[N], e11 = p[N + 1];
    float w00 = (1.0f - xf) * (1.0f - xb), w01 = (1.0f - xf) * xb, w10 = xf * (1.0f - xb), w11 = xf * xb;
    float a = w00 * e00.a + w01 * e01.a + w10 * e10.a + w11 * e11.a;
    float inv = a > 0.0f ? 1.0f / a : 0.0f;
    return (dvr_rgba){(w00 * e00.r + w01 * e01.r + w10 * e10.r + w11 * e11.r) * inv,
                      (w00 * e00.g + w01 * e01.g + w10 * e10.g + w11 * e11.g) * inv,
                      (w00 * e00.b + w01 * e01.b + w10 * e10.b + w11 * e11.b) * inv, a};
}

/* ---- range maximum ------------------------------------------------------------ */

/* A sparse table: level l holds the maximum of entries i .. i + 2^l - 1, so
 * any range is the maximum of two overlapping power-of-two blocks: O(1) a
 * query after O(n log n) to build. `v` is RANGE_LEVELS * n floats. */
typedef struct range_max {
    int n;
    float *v; /* level l, entry i at v[l * n + i] */
} range_max;

static void range_max_build(range_max *r, const float *values)
{
    int n = r->n;
    memcpy(r->v, values, (size_t)n * sizeof *values);
    for (int l = 1; l < RANGE_LEVELS && (1 << l) <= n; l++) {
        const float *below = r->v + (size_t)(l - 1) * n;
        float *level = r->v + (size_t)l * n;
        for (int i = 0; i + (1 << l) <= n; i++) {
            float a = below[i], b = below[i + (1 << (l - 1))];
            level[i] = a > b ? a : b;
        }
    }
}

/* the maximum of entries lo..hi (lo <= hi < n) */
static float range_max_query(const range_max *r, int lo, int hi)
{
    int l = 0;
    while ((2 << l) <= hi - lo + 1)
        l++;
    const float *level = r->v + (size_t)l * r->n;
    float a = level[lo], b = level[hi - (1 << l) + 1];
    return a > b ? a : b;
}

/* ---- tables ------------------------------------------------------------------- */

/* per classic entry: colour, and opacity over one full step */
static void build_step_table(dvr_volume *d)
{
    double steps = d->settings.step_vox; /* one step in voxels: the exponent of (1 - a) */
    for (int i = 0; i < COLORMAP_TABLE_SIZE; i++) {
        colormap_rgba e = d->table.entry[i];
        double a = e.a <= 0.0f ? 0.0 : e.a >= 1.0f ? 1.0 : 1.0 - pow(1.0 - (double)e.a, steps);
        d->step_rgba[i] = (dvr_rgba){e.r, e.g, e.b, (float)a};
    }
}

/* The transfer function on the fine grid the pre-integration table is
 * built from: PREINT_SUB pieces per half entry, 2 (SIZE - 1) half entries
 * over the range (8160 pieces at 256: finer than COLORMAP_TABLE_SIZE, so a
 * feature a few entries wide keeps its area). Running integrals are kept at
 * every half entry: half entry j is at normalised position j / (2 (SIZE - 1)),
 * entry k at half entry 2k; sigma and the colour are linear on each piece.
 * bin_max[k] is the largest opacity on the pieces within half an entry of
 * entry k: the pre-integrated path sees nothing else, so the macrocells'
 * opacities built from it are conservative for it. */
#define PREINT_SUB 16
#define PREINT_HALVES (2 * (DVR_PREINT_SIZE - 1))

struct dvr_preint_sums {
    double sigma[PREINT_HALVES + 1];     /* integral of sigma (per voxel) over [0, j], in entries */
    double col[PREINT_HALVES + 1][3];    /* integral of c sigma over the same */
    float bin_max[DVR_PREINT_SIZE];      /* largest opacity within half an entry of entry k */
};
typedef struct dvr_preint_sums preint_sums;

static void piece_value(const colormap *tf, int piece, double *sigma, double col[3], float *opacity)
{
    colormap_rgba e = colormap_eval_unit(tf, (double)piece / (PREINT_HALVES * PREINT_SUB));
    double a = e.a < 0.0f ? 0.0 : e.a > PREINT_MAX_OPACITY ? PREINT_MAX_OPACITY : (double)e.a;
    *sigma = -log1p(-a);
    col[0] = e.r;
    col[1] = e.g;
    col[2] = e.b;
    *opacity = e.a;
}

static void preint_integrate(const colormap *tf, preint_sums *p)
{
    const double width = 0.5 / PREINT_SUB; /* one piece, in entries */
    double s0, c0[3], s1, c1[3];
    float a0, a1;
    piece_value(tf, 0, &s0, c0, &a0);
    p->sigma[0] = 0.0;
    p->col[0][0] = p->col[0][1] = p->col[0][2] = 0.0;
    for (int k = 0; k < DVR_PREINT_SIZE; k++)
        p->bin_max[k] = 0.0f;
    p->bin_max[0] = a0;
    double run_sigma = 0.0, run_col[3] = {0.0, 0.0, 0.0};
    for (int piece = 0; piece < PREINT_HALVES * PREINT_SUB; piece++) {
        piece_value(tf, piece + 1, &s1, c1, &a1);
        /* c and sigma linear on the piece: the integral of their product is
         * exactly width (2 c0 s0 + c0 s1 + c1 s0 + 2 c1 s1) / 6 */
        run_sigma += width * 0.5 * (s0 + s1);
        for (int c = 0; c < 3; c++)
            run_col[c] += width * (2.0 * c0[c] * s0 + c0[c] * s1 + c1[c] * s0 + 2.0 * c1[c] * s1) / 6.0;
        int half = piece / PREINT_SUB; /* the half entry the piece lies in */
        int bin = (half + 1) / 2;      /* the entry within half an entry of it */
        float piece_max = a0 > a1 ? a0 : a1;
        if (piece_max > p->bin_max[bin])
            p->bin_max[bin] = piece_max;
        if ((piece + 1) % PREINT_SUB == 0) {
            int j = (piece + 1) / PREINT_SUB;
            p->sigma[j] = run_sigma;
            for (int c = 0; c < 3; c++)
                p->col[j][c] = run_col[c];
        }
        s0 = s1;
        a0 = a1;
        for (int c = 0; c < 3; c++)
            c0[c] = c1[c];
    }
}

/* The SIZE^2 pre-integration table for the current step (see
 * PRE-INTEGRATION). Entry (f, b), f != b, integrates between entries f and
 * b; entry (f, f), a value that stays within one entry, averages over the
 * half entry either side (the values that round to f). */
static void build_preint_table(dvr_volume *d)
{
    enum { N = DVR_PREINT_SIZE };
    const preint_sums *p = d->sums; /* filled by dvr_set_transfer */
    double steps = d->settings.step_vox;
    for (int f = 0; f < N; f++)
        for (int b = 0; b < N; b++) {
            int j0 = f < b ? 2 * f : 2 * b, j1 = f < b ? 2 * b : 2 * f;
            if (f == b) {
                j0 = f > 0 ? 2 * f - 1 : 0;
                j1 = f < N - 1 ? 2 * f + 1 : 2 * f;
            }
            double ds = p->sigma[j1] - p->sigma[j0];
            double mean_sigma = ds / (0.5 * (j1 - j0));
            double cbar[3];
            for (int c = 0; c < 3; c++) {
                /* a nearly transparent slab's ratio is rounding noise; its
                 * colour then hardly counts, but keep it in [0, 1] */
                double m = ds > 0.0 ? (p->col[j1][c] - p->col[j0][c]) / ds : 0.0;
                cbar[c] = m < 0.0 ? 0.0 : m > 1.0 ? 1.0 : m;
            }
            double alpha = -expm1(-steps * mean_sigma);
            d->preint[(size_t)f * N + b] = (dvr_rgba){(float)(cbar[0] * alpha), (float)(cbar[1] * alpha), (float)(cbar[2] * alpha), (float)alpha};
        }
}

/* Per macrocell, the largest opacity over the entries its [min, max]
 * reaches, in the classic binning and in the pre-integration binning (the
 * larger of the two: 0 proves both paths see nothing there). */
static void build_cell_opacity(dvr_volume *d)
{
    float classic[COLORMAP_TABLE_SIZE];
    for (int i = 0; i < COLORMAP_TABLE_SIZE; i++)
        classic[i] = d->table.entry[i].a;
    const preint_sums *p = d->sums;
    range_max rm_classic = {COLORMAP_TABLE_SIZE, d->range_scratch};
    range_max rm_pre = {DVR_PREINT_SIZE, d->range_scratch + (size_t)RANGE_LEVELS * COLORMAP_TABLE_SIZE};
    range_max_build(&rm_classic, classic);
    range_max_build(&rm_pre, p->bin_max);
    const macrocell_grid *g = d->grid;
    size_t count = macrocell_count(g);
    for (size_t m = 0; m < count; m++) {
        float lo = g->min[m], hi = g->max[m];
        float a = range_max_query(&rm_classic, classic_index(&d->table, lo), classic_index(&d->table, hi));
        /* a bilinear read blends the entries on both sides of its coordinate */
        float b = range_max_query(&rm_pre, preint_cell(preint_coord(d, lo)), preint_cell(preint_coord(d, hi)) + 1);
        d->cell_opacity[m] = a > b ? a : b;
        d->cell_leap[m] = d->cell_opacity[m] > 0.0f ? 0 : MACROCELL_LEAP_MARK;
    }
    macrocell_leap_build(g, d->cell_leap);
}

void dvr_set_transfer(dvr_volume *d, const colormap *tf)
{
    d->tf = *tf;
    colormap_fit_range(&d->tf, d->vol->min, d->vol->max);
    colormap_bake(&d->tf, &d->table);
    d->preint_lo = d->tf.lo;
    d->preint_scale = d->tf.hi > d->tf.lo ? (DVR_PREINT_SIZE - 1) / ((double)d->tf.hi - d->tf.lo) : 0.0;
    build_step_table(d);
    preint_integrate(&d->tf, d->sums);
    if (d->preint)
        build_preint_table(d);
    build_cell_opacity(d);
}

bool dvr_set_settings(dvr_volume *d, const dvr_settings *settings, tess_error *err)
{
    if (!settings_valid(settings, err))
        return false;
    if (settings->preintegrate && !d->preint) {
        d->preint = malloc((size_t)DVR_PREINT_SIZE * DVR_PREINT_SIZE * sizeof *d->preint);
        if (!d->preint)
            return tess_error_set(err, "volume rendering: out of memory for the pre-integration table");
    }
    bool step_changed = settings->step_vox != d->settings.step_vox;
    bool preint_new = settings->preintegrate && !d->settings.preintegrate;
    d->settings = *settings;
    if (step_changed)
        build_step_table(d);
    if (d->preint && (step_changed || preint_new))
        build_preint_table(d);
    return true;
}

dvr_volume *dvr_create(const volume *vol, const macrocell_grid *grid, const colormap *tf,
                       const dvr_settings *settings, tess_error *err)
{
    dvr_settings s = settings ? *settings : dvr_settings_default();
    if (!settings_valid(&s, err))
        return NULL;
    dvr_volume *d = calloc(1, sizeof *d);
    if (!d) {
        tess_error_set(err, "volume rendering: out of memory");
        return NULL;
    }
    d->vol = vol;
    d->settings = s;
    d->voxel_world = fmin(vol->spacing[0], fmin(vol->spacing[1], vol->spacing[2]));
    if (grid) {
        const uint32_t n[3] = {vol->nx, vol->ny, vol->nz};
        for (int a = 0; a < 3; a++)
            if (grid->cells[a] != n[a] - 1 || grid->spacing[a] != vol->spacing[a] ||
                grid->origin[a] != vol->origin[a]) {
                tess_error_set(err, "volume rendering: the macrocell grid was built for another volume");
                goto fail;
            }
        d->grid = grid;
    } else {
        d->grid = macrocell_grid_create(vol, MACROCELL_DEFAULT_K, err);
        if (!d->grid)
            goto fail;
        d->own_grid = true;
    }
    d->cell_opacity = malloc(macrocell_count(d->grid) * sizeof *d->cell_opacity);
    d->cell_leap = malloc(macrocell_count(d->grid) * sizeof *d->cell_leap);
    if (!d->cell_opacity || !d->cell_leap) {
        tess_error_set(err, "volume rendering: out of memory for %zu macrocells", macrocell_count(d->grid));
        goto fail;
    }
    d->range_scratch = malloc(RANGE_SCRATCH_FLOATS * sizeof *d->range_scratch);
    d->sums = malloc(sizeof *d->sums);
    if (!d->range_scratch || !d->sums) {
        tess_error_set(err, "volume rendering: out of memory");
        goto fail;
    }
    if (s.preintegrate) {
        d->preint = malloc((size_t)DVR_PREINT_SIZE * DVR_PREINT_SIZE * sizeof *d->preint);
        if (!d->preint) {
            tess_error_set(err, "volume rendering: out of memory for the pre-integration table");
            goto fail;
        }
    }
    dvr_set_transfer(d, tf);
    return d;
fail:
    dvr_destroy(d);
    return NULL;
}

void dvr_destroy(dvr_volume *d)
{
    if (!d)
        return;
    if (d->own_grid)
        macrocell_grid_destroy((macrocell_grid *)d->grid);
    free(d->preint);
    free(d->cell_opacity);
    free(d->cell_leap);
    free(d->range_scratch);
    free(d->sums);
    free(d);
}

/* ---- sampling ------------------------------------------------------------------- */

/* Sampling is specialised per sample type: the functions below that take a
 * volume_type are always inlined with it a constant (composite_run switches
 * on the type once per run of slabs), so no switch and no call sits in the
 * per-sample loop. */
#define DVR_INLINE static inline __attribute__((always_inline))

/* The volume as the samplers read it, set up once per ray. */
typedef struct field_view {
    const void *data;     /* the volume's samples */
    size_t sy, sz;        /* index strides of one sample along y and along z */
    double top[3];        /* n - 1 per axis: the field's box is [0, top] */
    uint32_t cell_max[3]; /* n - 2 per axis: the last cell's low corner */
} field_view;

static void field_view_init(field_view *fv, const volume *v)
{
    const uint32_t n[3] = {v->nx, v->ny, v->nz};
    fv->data = v->data;
    fv->sy = v->nx;
    fv->sz = (size_t)v->nx * v->ny;
    for (int a = 0; a < 3; a++) {
        fv->top[a] = (double)(n[a] - 1);
        fv->cell_max[a] = n[a] - 2;
    }
}

#if !defined(__SSE2__) /* the SSE2 corner fetch reads the samples itself */
DVR_INLINE float sample_value(const void *data, volume_type type, size_t index)
{
    switch (type) {
    case VOLUME_UINT8: return (float)((const uint8_t *)data)[index];
    case VOLUME_INT16: return (float)((const int16_t *)data)[index];
    case VOLUME_UINT16: return (float)((const uint16_t *)data)[index];
    case VOLUME_FLOAT32: return ((const float *)data)[index];
    }
    return 0.0f;
}
#endif

#if defined(__SSE2__)
/* The two samples at index i and i + 1 as one load (x86 is little-endian:
 * sample i in the low half). */
DVR_INLINE uint32_t pair_u32(const void *data, size_t bytes, size_t i)
{
    uint32_t v = 0;
    memcpy(&v, (const char *)data + i * bytes, 2 * bytes);
    return v;
}
#endif

/* The trilinear field in the cell whose low corner has index `base`, at
 * fractions f. The SSE2 form loads the four x-neighbour pairs at once and
 * does the four x lerps, then the two y lerps, lane-wise: the same IEEE
 * operations on the same values as the scalar form, so the same result. */
DVR_INLINE float cell_lerp(const field_view *fv, volume_type type, size_t base, const float f[3])
{
    const size_t sy = fv->sy, sz = fv->sz;
    const void *q = fv->data;
#if defined(__SSE2__)
    __m128 lo, hi; /* corners (x0, x1) of the rows y0z0, y1z0, y0z1, y1z1 */
    if (type == VOLUME_FLOAT32) {
        const float *p = (const float *)q + base;
        __m128 r01 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), (const __m64 *)p), (const __m64 *)(p + sy));
        __m128 r23 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), (const __m64 *)(p + sz)),
                                  (const __m64 *)(p + sz + sy));
        lo = _mm_shuffle_ps(r01, r23, _MM_SHUFFLE(2, 0, 2, 0));
        hi = _mm_shuffle_ps(r01, r23, _MM_SHUFFLE(3, 1, 3, 1));
    } else {
        const size_t bytes = type == VOLUME_UINT8 ? 1 : 2;
        __m128i v = _mm_setr_epi32((int)pair_u32(q, bytes, base), (int)pair_u32(q, bytes, base + sy),
                                   (int)pair_u32(q, bytes, base + sz), (int)pair_u32(q, bytes, base + sz + sy));
        __m128i l, h;
        if (type == VOLUME_UINT8) {
            l = _mm_and_si128(v, _mm_set1_epi32(0xff));
            h = _mm_srli_epi32(v, 8);
        } else if (type == VOLUME_UINT16) {
            l = _mm_and_si128(v, _mm_set1_epi32(0xffff));
            h = _mm_srli_epi32(v, 16);
        } else {
            l = _mm_srai_epi32(_mm_slli_epi32(v, 16), 16);
            h = _mm_srai_epi32(v, 16);
        }
        lo = _mm_cvtepi32_ps(l);
        hi = _mm_cvtepi32_ps(h);
    }
    __m128 x = _mm_add_ps(lo, _mm_mul_ps(_mm_set1_ps(f[0]), _mm_sub_ps(hi, lo))); /* x00 x10 x01 x11 */
    __m128 y0s = _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 0, 2, 0));                  /* x00 x01 */
    __m128 y1s = _mm_shuffle_ps(x, x, _MM_SHUFFLE(3, 1, 3, 1));                  /* x10 x11 */
    __m128 y = _mm_add_ps(y0s, _mm_mul_ps(_mm_set1_ps(f[1]), _mm_sub_ps(y1s, y0s))); /* y0 y1 */
    float y0 = _mm_cvtss_f32(y), y1 = _mm_cvtss_f32(_mm_shuffle_ps(y, y, _MM_SHUFFLE(1, 1, 1, 1)));
#else
    float s0 = sample_value(q, type, base), s1 = sample_value(q, type, base + 1);
    float s2 = sample_value(q, type, base + sy), s3 = sample_value(q, type, base + sy + 1);
    float s4 = sample_value(q, type, base + sz), s5 = sample_value(q, type, base + sz + 1);
    float s6 = sample_value(q, type, base + sz + sy), s7 = sample_value(q, type, base + sz + sy + 1);
    float x00 = s0 + f[0] * (s1 - s0), x10 = s2 + f[0] * (s3 - s2);
    float x01 = s4 + f[0] * (s5 - s4), x11 = s6 + f[0] * (s7 - s6);
    float y0 = x00 + f[1] * (x10 - x00), y1 = x01 + f[1] * (x11 - x01);
#endif
    return y0 + f[2] * (y1 - y0);
}

/* The trilinear field at voxel position p, clamped to the field's box (a
 * slab end may round a hair outside it). A point inside [0, top) on every
 * axis, nearly all of them, needs no clamp: its cell is its floor and the
 * clamped arithmetic would give the same cell and fractions. */
DVR_INLINE float field_sample(const field_view *fv, volume_type type, const double p[3])
{
    /* scalars, not arrays: an array here went through the stack, a store
     * and a reload in every sample's chain */
    uint32_t cx, cy, cz;
    if (p[0] >= 0.0 && p[0] < fv->top[0] && p[1] >= 0.0 && p[1] < fv->top[1] && p[2] >= 0.0 &&
        p[2] < fv->top[2]) {
        cx = (uint32_t)p[0];
        cy = (uint32_t)p[1];
        cz = (uint32_t)p[2];
        const float f[3] = {(float)(p[0] - (double)cx), (float)(p[1] - (double)cy), (float)(p[2] - (double)cz)};
        return cell_lerp(fv, type, cx + fv->sy * cy + fv->sz * cz, f);
    }
    uint32_t c[3];
    float f[3];
    for (int a = 0; a < 3; a++) {
        double x = p[a] > 0.0 ? p[a] : 0.0; /* NaN goes to 0 too */
        x = x < fv->top[a] ? x : fv->top[a];
        uint32_t i = (uint32_t)x;
        c[a] = i > fv->cell_max[a] ? fv->cell_max[a] : i;
        f[a] = (float)(x - (double)c[a]);
    }
    return cell_lerp(fv, type, c[0] + fv->sy * c[1] + fv->sz * c[2], f);
}

/* ---- integration ------------------------------------------------------------------ */

/* One ray's state. Slab k spans [max(ta, tv + k dt), min(tb, tv + (k + 1) dt)],
 * k in [0, slab_count); tv = ta - (1 - jitter) dt, so slab 0 is the jitter
 * fraction of a step and every slab but the first and last is a full step.
 * Slabs are composited in increasing k, each at most once (next_slab). */
typedef struct ray_state {
    const dvr_volume *d;
    field_view field;       /* d->vol, as the samplers read it */
    double org[3], dir[3];  /* the ray in voxel coordinates (same t as the world ray) */
    double ta, tb;          /* the clipped segment */
    double tv, dt;          /* the slab grid: origin and step, in t */
    int64_t slab_count;
    int64_t next_slab;      /* first slab not yet composited */
    int64_t front_slab;     /* the slab whose front value front_value holds; -1 for none */
    float front_value;
    double rgb[3], T;       /* associated colour so far; transmittance */
    bool done;              /* T fell below the threshold */
    uint64_t samples, slabs;
} ray_state;

static inline int64_t slab_of(const ray_state *r, double t)
{
    double k = floor((t - r->tv) / r->dt);
    if (!(k > 0.0))
        return 0;
    return k >= (double)(r->slab_count - 1) ? r->slab_count - 1 : (int64_t)k;
}

/* opacity `a` of a full step over `fraction` of a step */
static inline double part_step(double a, double fraction)
{
    if (a <= 0.0)
        return 0.0;
    if (a >= 1.0)
        return 1.0;
    return -expm1(fraction * log1p(-a));
}

/* Composite slabs k .. k1 for one sample type and path, both constants
 * after inlining; returns the first slab not composited. The ray's running
 * sums live in locals for the loop (the samples are read through a char
 * pointer for uint8, which would otherwise make every store to *r a reload). */
DVR_INLINE int64_t composite_slabs(ray_state *r, int64_t k, int64_t k1, volume_type type, bool pre)
{
    const dvr_volume *d = r->d;
    const field_view *fv = &r->field;
    const double threshold = d->settings.min_transmittance;
    const double ox = r->org[0], oy = r->org[1], oz = r->org[2];
    const double dx = r->dir[0], dy = r->dir[1], dz = r->dir[2];
    const double ta = r->ta, tb = r->tb, tv = r->tv, dt = r->dt;
    double cr = r->rgb[0], cg = r->rgb[1], cb = r->rgb[2], T = r->T;
    int64_t front_slab = r->front_slab;
    float front_value = r->front_value;
    uint64_t samples = 0, slabs = 0;
    for (; k <= k1; k++) {
        double a = k == 0 ? ta : tv + (double)k * dt;
        double b = tv + (double)(k + 1) * dt;
        bool full = k > 0;
        if (b >= tb) {
            b = tb;
            full = false;
        }
        if (!(b > a))
            continue;
        dvr_rgba e;
        if (pre) {
            float vf = front_value;
            if (front_slab != k) {
                const double pa[3] = {ox + a * dx, oy + a * dy, oz + a * dz};
                vf = field_sample(fv, type, pa);
                samples++;
            }
            const double pb[3] = {ox + b * dx, oy + b * dy, oz + b * dz};
            float vb = field_sample(fv, type, pb);
            samples++;
            front_slab = k + 1;
            front_value = vb;
            e = preint_lookup(d, vf, vb);
        } else {
            double t = 0.5 * (a + b);
            const double p[3] = {ox + t * dx, oy + t * dy, oz + t * dz};
            e = d->step_rgba[classic_index(&d->table, field_sample(fv, type, p))];
            samples++;
        }
        double alpha = full ? e.a : part_step(e.a, (b - a) / dt);
        slabs++;
        /* no branch on alpha == 0 (a coin toss on noise near a ramp's
         * foot): a transparent slab adds exactly 0 and leaves T as it was */
        double w = T * alpha;
        cr += w * e.r;
        cg += w * e.g;
        cb += w * e.b;
        T *= 1.0 - alpha;
        if (T < threshold) {
            r->done = true;
            k++;
            break;
        }
    }
    r->rgb[0] = cr;
    r->rgb[1] = cg;
    r->rgb[2] = cb;
    r->T = T;
    r->front_slab = front_slab;
    r->front_value = front_value;
    r->samples += samples;
    r->slabs += slabs;
    return k;
}

#define DVR_COMPOSITE_TYPE(r, k0, k1, type, pre)                                                                     \
    ((pre) ? composite_slabs(r, k0, k1, type, true) : composite_slabs(r, k0, k1, type, false))

/* Composite the slabs that meet [run0, run1] and were not composited yet. */
static void composite_run(ray_state *r, double run0, double run1)
{
    int64_t k0 = slab_of(r, run0), k1 = slab_of(r, run1);
    if (k0 < r->next_slab)
        k0 = r->next_slab;
    if (k0 > k1)
        return;
    const bool pre = r->d->settings.preintegrate;
    int64_t k = k0;
    switch (r->d->vol->type) {
    case VOLUME_UINT8: k = DVR_COMPOSITE_TYPE(r, k0, k1, VOLUME_UINT8, pre); break;
    case VOLUME_INT16: k = DVR_COMPOSITE_TYPE(r, k0, k1, VOLUME_INT16, pre); break;
    case VOLUME_UINT16: k = DVR_COMPOSITE_TYPE(r, k0, k1, VOLUME_UINT16, pre); break;
    case VOLUME_FLOAT32: k = DVR_COMPOSITE_TYPE(r, k0, k1, VOLUME_FLOAT32, pre); break;
    }
    if (k > r->next_slab)
        r->next_slab = k;
}
#undef DVR_COMPOSITE_TYPE

bool dvr_integrate_stats(const dvr_volume *d, const double org[3], const double dir[3], double t0, double t1,
                         double jitter, float rgb_out[3], float *transmittance_out, dvr_stats *stats)
{
    rgb_out[0] = rgb_out[1] = rgb_out[2] = 0.0f;
    *transmittance_out = 1.0f;
    const macrocell_grid *g = d->grid;
    ray_state r = {.d = d, .front_slab = -1, .T = 1.0};
    field_view_init(&r.field, d->vol);
    volume_ray_to_voxel(g->origin, g->spacing, org, dir, r.org, r.dir);
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    /* t0 and t1 may be infinite (the box clip makes them finite), not NaN */
    bool finite = isfinite(len) && !isnan(t0) && !isnan(t1);
    for (int a = 0; a < 3; a++)
        finite &= isfinite(r.org[a]) && isfinite(r.dir[a]);
    if (!finite || !(len > 0.0))
        return false;
    const double lo[3] = {0.0, 0.0, 0.0};
    const double hi[3] = {g->cells[0], g->cells[1], g->cells[2]};
    r.ta = t0;
    r.tb = t1;
    if (!volume_clip_box(r.org, r.dir, lo, hi, &r.ta, &r.tb) || !(r.ta < r.tb))
        return false;
    if (!(jitter >= 0.0 && jitter < 1.0))
        jitter = 0.0;
    r.dt = d->settings.step_vox * d->voxel_world / len;
    r.tv = r.ta - (1.0 - jitter) * r.dt;
    double count = ceil((r.tb - r.tv) / r.dt);
    r.slab_count = count >= 1.0 ? (int64_t)count : 1;

    uint64_t skipped = 0;
    if (!d->settings.skip_empty)
        composite_run(&r, r.ta, r.tb);
    else {
        /* runs of non-empty spans, each composited when an empty span (or
         * the end) closes it; from any span the walk leaps over the
         * macrocells of its class around it (macrocell.h LEAPS). A leap's
         * exit is the plane t the full walk would give there; where the
         * walk ends the run reaches tb, as the full walk's last span may
         * (slabs past the last non-empty span add exactly 0, so taking
         * more of them changes no bit) */
        macrocell_walk w;
        macrocell_span span;
        bool in_run = false;
        double run0 = 0.0, run1 = 0.0;
        macrocell_walk_begin(&w, g, org, dir, r.ta, r.tb);
        while (!r.done && macrocell_walk_next(&w, &span)) {
            uint8_t leap = d->cell_leap[span.index];
            macrocell_walk_leap(&w, &span, macrocell_leap_dist(leap));
            if (!(leap & MACROCELL_LEAP_MARK)) {
                if (!in_run)
                    run0 = span.t_enter;
                run1 = w.dda.done ? r.tb : w.dda.t;
                in_run = true;
                continue;
            }
            skipped++;
            if (in_run) {
                composite_run(&r, run0, run1);
                in_run = false;
            }
        }
        if (in_run && !r.done)
            composite_run(&r, run0, run1);
    }

    rgb_out[0] = (float)r.rgb[0];
    rgb_out[1] = (float)r.rgb[1];
    rgb_out[2] = (float)r.rgb[2];
    *transmittance_out = (float)r.T;
    if (stats) {
        stats->samples += r.samples;
        stats->slabs += r.slabs;
        stats->spans_skipped += skipped;
        stats->terminated += r.done;
    }
    return true;
}

bool dvr_integrate(const dvr_volume *d, const double org[3], const double dir[3], double t0, double t1,
                   double jitter, float rgb_out[3], float *transmittance_out)
{
    return dvr_integrate_stats(d, org, dir, t0, t1, jitter, rgb_out, transmittance_out, NULL);
}

/* ---- another volume of the same layout (a time step) ---------------------------- */

bool dvr_set_volume(dvr_volume *d, const volume *vol, const macrocell_grid *grid, tess_error *err)
{
    const macrocell_grid *old = d->grid;
    const uint32_t n[3] = {vol->nx, vol->ny, vol->nz};
    bool same = grid && grid->k == old->k;
    for (int a = 0; same && a < 3; a++)
        same = grid->cells[a] == n[a] - 1 && grid->cells[a] == old->cells[a] && grid->spacing[a] == vol->spacing[a] &&
               grid->spacing[a] == old->spacing[a] && grid->origin[a] == vol->origin[a] &&
               grid->origin[a] == old->origin[a];
    if (!same)
        return tess_error_set(err, "volume rendering: the new volume or its macrocell grid is not laid out as the "
                                   "old one");
    if (d->own_grid)
        macrocell_grid_destroy((macrocell_grid *)d->grid);
    d->own_grid = false;
    d->vol = vol;
    d->grid = grid;
    /* the tables stay (the transfer function and its range as they were);
     * what empty space is follows the new values */
    build_cell_opacity(d);
    return true;
}
