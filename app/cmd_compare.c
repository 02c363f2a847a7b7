/* cmd_compare.c - `tessera compare A B`: how much an image differs from a
 * reference, as one line of numbers: LDR-FLIP (metrics/flip.h) pooled over
 * the image, RMSE and PSNR of the linear RGB values, and the count of pixels
 * that differ at all; optionally the FLIP error map as a picture.
 *
 * Like the benchmarks, compare refuses (exit 2) options that would silently
 * change what is measured (--ppd given twice over by --wall, a --distance-m
 * without its wall), and it never guesses a viewing distance. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "metrics/error_map.h"
#include "metrics/flip.h"
#include "metrics/image_stats.h"
#include "option_check.h"
#include "wall/dump.h"
#include "wall/wall_config.h"

#define COMPARE_MAX_THREADS 256
/* Viewing distances accepted with --wall, in metres: 1 cm to 1 km. */
#define COMPARE_MIN_DISTANCE_M 0.01
#define COMPARE_MAX_DISTANCE_M 1000.0
/* Outputs whose pixel pitches differ by less than this (relative) count as equal. */
#define COMPARE_PITCH_TOLERANCE 1e-3

typedef struct compare_options {
    const char *paths[2];   /* reference, test */
    int path_count;
    const char *map_path;   /* NULL: no map */
    double ppd;
    bool ppd_given;
    const char *wall_path;  /* NULL: no wall */
    double distance_m;
    bool distance_given;
    int threads;
} compare_options;

static void compare_usage(FILE *f)
{
    fprintf(f,
            "usage: tessera compare REFERENCE TEST [--map OUT] [--ppd N | --wall FILE --distance-m D]\n"
            "                       [--threads N]\n"
            "How much TEST differs from REFERENCE (two images of the same size, any format OpenImageIO\n"
            "reads). Prints one line:\n"
            "  flip_mean=F flip_median=F flip_q3=F rmse=R psnr=P differing_pixels=N\n"
            "  flip_*            LDR-FLIP (Andersson et al., HPG 2020) per pixel, in [0, 1]: its mean,\n"
            "                    median and third quartile (plain percentiles, linearly interpolated;\n"
            "                    NVlabs' tool prints error-weighted ones, its mean is this mean)\n"
            "  rmse, psnr        over the LINEAR RGB values as read (not clamped, all 3 channels):\n"
            "                    psnr = 10 log10(1 / rmse^2) dB, peak 1.0; 'inf' for identical images\n"
            "  differing_pixels  pixels whose linear RGB values are not bit-identical\n"
            "Files stored as floating point (EXR, HDR) are linear; integer formats (PNG, JPEG, 16-bit\n"
            "TIFF...) are sRGB-encoded and decoded. Grey becomes RGB, alpha is dropped. FLIP clamps\n"
            "the linear values to [0, 1] (LDR-FLIP: what a display shows).\n"
            "\n"
            "  --map OUT         write the FLIP error map as a picture: the magma colour map (black 0,\n"
            "                    pale yellow 1) with a legend strip from 0 to 1 under it; the format\n"
            "                    follows the extension, as for render --out\n"
            "  --ppd N           the viewer's pixels per degree, %g..%g (default %.2f, FLIP's: 0.7 m\n"
            "                    from a 0.7 m wide monitor of 3840 pixels). More pixels per degree\n"
            "                    make fine detail, and so fine noise, less visible\n"
            "  --wall FILE --distance-m D\n"
            "                    the pixels per degree of a viewer D metres from the wall FILE (a wall\n"
            "                    config, docs/wall-format.md, with explicit modes): D * pixels per\n"
            "                    metre * pi / 180, as FLIP computes its default, from the finest pixel\n"
            "                    pitch of the outputs (said on stderr when the outputs differ)\n"
            "  --threads N       threads, 1..%d (default: the number of CPUs); the numbers are the\n"
            "                    same for any N\n",
            FLIP_MIN_PPD, FLIP_MAX_PPD, FLIP_DEFAULT_PPD, COMPARE_MAX_THREADS);
}

static int default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > COMPARE_MAX_THREADS ? COMPARE_MAX_THREADS : (int)n;
}

/* Parse the options. Returns false when the command should stop: after
 * --help (*exit_code 0) or a bad, missing or conflicting option (2). */
static bool parse_options(int argc, char **argv, compare_options *o, int *exit_code)
{
    *exit_code = 2;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            compare_usage(stdout);
            *exit_code = 0;
            return false;
        } else if (!strcmp(a, "--map")) {
            if (!(o->map_path = cli_option_value(argc, argv, &i)))
                return false;
        } else if (!strcmp(a, "--ppd")) {
            if (!(val = cli_option_value(argc, argv, &i)) ||
                !cli_parse_double(a, val, FLIP_MIN_PPD, FLIP_MAX_PPD, &o->ppd))
                return false;
            o->ppd_given = true;
        } else if (!strcmp(a, "--wall")) {
            if (!(o->wall_path = cli_option_value(argc, argv, &i)))
                return false;
        } else if (!strcmp(a, "--distance-m")) {
            if (!(val = cli_option_value(argc, argv, &i)) ||
                !cli_parse_double(a, val, COMPARE_MIN_DISTANCE_M, COMPARE_MAX_DISTANCE_M, &o->distance_m))
                return false;
            o->distance_given = true;
        } else if (!strcmp(a, "--threads")) {
            if (!(val = cli_option_value(argc, argv, &i)) ||
                !cli_parse_int(a, val, 1, COMPARE_MAX_THREADS, &o->threads))
                return false;
        } else if (a[0] == '-' && a[1] != '\0') {
            cli_error("unknown option '%s' (see 'tessera compare --help')", a);
            return false;
        } else if (o->path_count < 2) {
            o->paths[o->path_count++] = a;
        } else {
            cli_error("compare takes two images, REFERENCE and TEST; '%s' is a third (see 'tessera compare --help')",
                      a);
            return false;
        }
    }
    if (o->path_count < 2) {
        cli_error("compare needs two images, REFERENCE and TEST (see 'tessera compare --help')");
        return false;
    }
    if (o->ppd_given && o->wall_path) {
        cli_error("--ppd: not an option with --wall (--wall and --distance-m give the pixels per degree)");
        return false;
    }
    if (o->wall_path && !o->distance_given) {
        cli_error("--wall needs --distance-m D: the viewer's distance from the wall in metres");
        return false;
    }
    if (o->distance_given && !o->wall_path) {
        cli_error("--distance-m: not an option without --wall (it is the distance from the wall's monitors)");
        return false;
    }
    return true;
}

/* The pixels per degree of a viewer distance_m from the wall: from the
 * finest pitch among the outputs (horizontal or vertical). */
static bool wall_ppd(const char *file, double distance_m, double *ppd)
{
    wall_config *wall = malloc(sizeof *wall);
    if (!wall) {
        cli_error("%s: out of memory", file);
        return false;
    }
    tess_error err = {{0}};
    if (!wall_config_load(file, wall, &err) || !wall_config_headless_sizes(wall, &err)) {
        /* the headless check names the output, not the file */
        cli_error("%s%s%s", strstr(err.msg, file) ? "" : file, strstr(err.msg, file) ? "" : ": ", err.msg);
        free(wall);
        return false;
    }
    double finest = 0.0, coarsest = INFINITY; /* pixels per mm */
    int finest_i = 0, coarsest_i = 0;
    for (int i = 0; i < wall->count; i++) {
        const wall_output *o = &wall->outputs[i];
        double px_per_mm = fmax(o->width_px / o->width_mm, o->height_px / o->height_mm);
        if (px_per_mm > finest) {
            finest = px_per_mm;
            finest_i = i;
        }
        if (px_per_mm < coarsest) {
            coarsest = px_per_mm;
            coarsest_i = i;
        }
    }
    *ppd = flip_ppd_of_viewer(distance_m, finest * 1000.0);
    if (finest > coarsest * (1.0 + COMPARE_PITCH_TOLERANCE))
        cli_warn("%s: the outputs' pixel pitches differ (%s %.4f px/mm, %s %.4f px/mm); using the finest, %.4f "
                 "px/mm",
                 file, wall->outputs[finest_i].connector, finest, wall->outputs[coarsest_i].connector, coarsest,
                 finest);
    fprintf(stderr, "tessera: %s at %g m: %.4f px/mm, %.2f pixels per degree\n", file, distance_m, finest, *ppd);
    free(wall);
    if (!(*ppd >= FLIP_MIN_PPD && *ppd <= FLIP_MAX_PPD)) {
        cli_error("--wall %s --distance-m %g: %.2f pixels per degree is outside %g..%g", file, distance_m, *ppd,
                  FLIP_MIN_PPD, FLIP_MAX_PPD);
        return false;
    }
    return true;
}

static bool write_map(const char *path, const float *error, int w, int h)
{
    float *rgb = NULL;
    int map_h = 0;
    tess_error err = {{0}};
    bool ok = error_map_render(error, w, h, &rgb, &map_h, &err) && dump_write_rgb(path, w, map_h, rgb, &err);
    free(rgb);
    if (!ok) {
        cli_error("--map %s: %s", path, err.msg);
        return false;
    }
    fprintf(stderr, "tessera: wrote %s (%dx%d: the %dx%d map and a %d-pixel legend)\n", path, w, map_h, w, h,
            map_h - h);
    return true;
}

int cli_compare(int argc, char **argv)
{
    compare_options o = {.ppd = FLIP_DEFAULT_PPD, .threads = default_threads()};
    int code;
    if (!parse_options(argc, argv, &o, &code))
        return code;
    if (o.wall_path && !wall_ppd(o.wall_path, o.distance_m, &o.ppd))
        return 1;

    float *rgb[2] = {NULL, NULL};
    int w[2] = {0, 0}, h[2] = {0, 0};
    float *error = NULL;
    code = 1;
    for (int i = 0; i < 2; i++) {
        tess_error err = {{0}};
        if (!dump_read_linear_rgb(o.paths[i], &w[i], &h[i], &rgb[i], &err)) {
            cli_error("%s", err.msg);
            goto done;
        }
    }
    if (w[0] != w[1] || h[0] != h[1]) {
        cli_error("%s is %dx%d but %s is %dx%d: the images must be the same size", o.paths[0], w[0], h[0], o.paths[1],
                  w[1], h[1]);
        goto done;
    }
    const size_t pixels = (size_t)w[0] * (size_t)h[0];
    error = malloc(pixels * sizeof *error);
    if (!error) {
        cli_error("out of memory for the %dx%d error map", w[0], h[0]);
        goto done;
    }
    tess_error err = {{0}};
    stats_pooled flip;
    if (!flip_ldr_map(rgb[0], rgb[1], w[0], h[0], o.ppd, o.threads, error, &err) ||
        !stats_pool(error, pixels, &flip, &err)) {
        cli_error("%s", err.msg);
        goto done;
    }
    stats_rgb_diff diff;
    stats_rgb_diff_compute(rgb[0], rgb[1], pixels, &diff);
    if (o.map_path && !write_map(o.map_path, error, w[0], h[0]))
        goto done;
    char psnr[32];
    if (isinf(diff.psnr_db))
        snprintf(psnr, sizeof psnr, "inf");
    else
        snprintf(psnr, sizeof psnr, "%.3f", diff.psnr_db);
    printf("flip_mean=%.6f flip_median=%.6f flip_q3=%.6f rmse=%.6g psnr=%s differing_pixels=%zu\n", flip.mean,
           flip.median, flip.q3, diff.rmse, psnr, diff.differing_pixels);
    code = fflush(stdout) == 0 ? 0 : 1;
done:
    free(error);
    free(rgb[0]);
    free(rgb[1]);
    return code;
}
