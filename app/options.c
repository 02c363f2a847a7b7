#include "cli.h"
#include "engine/base/clock.h"
#include "engine/render/upscale.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

void cli_say(const char *severity, const char *fmt, va_list ap)
{
    char msg[1024];
    vsnprintf(msg, sizeof msg, fmt, ap);
    fprintf(stderr, "tessera: %s: %s\n", severity, msg);
}

void cli_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cli_say("error", fmt, ap);
    va_end(ap);
}

double cli_now_s(void) { return clock_monotonic_s(); }

const char *cli_option_value(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) {
        cli_error("option %s needs a value", argv[*i]);
        return NULL;
    }
    return argv[++*i];
}

bool cli_parse_int(const char *option, const char *text, int min, int max, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE || v < min || v > max) {
        cli_error("%s: expected a whole number from %d to %d, got '%s'", option, min, max, text);
        return false;
    }
    *out = (int)v;
    return true;
}

bool cli_parse_double(const char *option, const char *text, double min, double max, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !isfinite(v) || v < min || v > max) {
        cli_error("%s: expected a number from %g to %g, got '%s'", option, min, max, text);
        return false;
    }
    *out = v;
    return true;
}

bool cli_parse_size(const char *option, const char *text, int *width_px, int *height_px)
{
    char *end;
    errno = 0;
    long w = strtol(text, &end, 10);
    long h = -1;
    if (end != text && (*end == 'x' || *end == 'X')) {
        const char *hs = end + 1;
        h = strtol(hs, &end, 10);
        if (end == hs)
            h = -1;
    }
    if (h < 0 || *end != '\0' || errno == ERANGE || text[0] == '-' || text[0] == '+') {
        cli_error("%s: expected WIDTHxHEIGHT in pixels (e.g. 1920x1080), got '%s'", option, text);
        return false;
    }
    if (w < 1 || h < 1 || w > CLI_MAX_IMAGE_EDGE_PX || h > CLI_MAX_IMAGE_EDGE_PX) {
        cli_error("%s: image size %ldx%ld: width and height must be from 1 to %d", option, w, h,
                  CLI_MAX_IMAGE_EDGE_PX);
        return false;
    }
    *width_px = (int)w;
    *height_px = (int)h;
    return true;
}

bool cli_parse_camera(const char *option, const char *text, camera_desc *out)
{
    float v[10];
    const char *p = text;
    for (int k = 0; k < 10; k++) {
        char *end;
        v[k] = strtof(p, &end);
        if (end == p || !isfinite(v[k]) || (k < 9 && *end != ',') || (k == 9 && *end != '\0')) {
            cli_error("%s: expected 10 finite numbers ex,ey,ez,lx,ly,lz,ux,uy,uz,fov_deg; value %d of '%s' is "
                      "wrong",
                      option, k + 1, text);
            return false;
        }
        p = end + 1;
    }
    camera_desc c = {v3(v[0], v[1], v[2]), v3(v[3], v[4], v[5]), v3(v[6], v[7], v[8]), v[9]};
    tess_error err = {{0}};
    if (!camera_validate(&c, &err)) {
        cli_error("%s: %s", option, err.msg);
        return false;
    }
    *out = c;
    return true;
}

/* An unsigned decimal number (digits with at most one '.') at *p; advances *p. */
static bool parse_unsigned_decimal(const char **p, double *out)
{
    const char *s = *p;
    size_t digits = strspn(s, "0123456789");
    if (s[digits] == '.')
        digits += 1 + strspn(s + digits + 1, "0123456789");
    if (digits == 0 || (digits == 1 && s[0] == '.'))
        return false;
    char number[64];
    if (digits >= sizeof number)
        return false;
    memcpy(number, s, digits);
    number[digits] = '\0';
    *out = strtod(number, NULL);
    *p = s + digits;
    return true;
}

bool cli_parse_scale(const char *option, const char *text, double *out)
{
    const char *p = text;
    double numerator, denominator = 1.0;
    bool ok = parse_unsigned_decimal(&p, &numerator);
    if (ok && *p == '/') {
        p++;
        ok = parse_unsigned_decimal(&p, &denominator);
    }
    if (!ok || *p != '\0') {
        cli_error("%s: expected a render scale in (0, 1], a fraction such as 3/4 or a decimal such as 0.75, "
                  "got '%s'",
                  option, text);
        return false;
    }
    double scale = denominator > 0.0 ? numerator / denominator : INFINITY;
    tess_error err = {{0}};
    if (!upscale_scale_validate(scale, &err)) {
        cli_error("%s: '%s' is %s: a render scale must be in (0, 1] (a fraction of the output size)", option,
                  text, denominator > 0.0 ? (scale > 1.0 ? "more than 1" : "0") : "a division by 0");
        return false;
    }
    *out = scale;
    return true;
}

double cli_machine_busy_s(void)
{
    FILE *f = fopen("/proc/stat", "r");
    if (!f)
        return -1.0;
    unsigned long long v[8] = {0};
    int n = fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                   &v[7]);
    fclose(f);
    long ticks_per_s = sysconf(_SC_CLK_TCK);
    if (n < 8 || ticks_per_s <= 0)
        return -1.0;
    return (double)(v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / (double)ticks_per_s;
}

double cli_own_cpu_s(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0.0;
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double cli_quantile(double *values, size_t n, double q)
{
    if (n == 0)
        return 0.0;
    qsort(values, n, sizeof *values, compare_doubles);
    double at = q * (double)(n - 1); /* linear between the two nearest order statistics */
    size_t lo = (size_t)floor(at), hi = lo + 1 < n ? lo + 1 : lo;
    return values[lo] + (at - (double)lo) * (values[hi] - values[lo]);
}

double cli_median(double *values, size_t n)
{
    if (n == 0)
        return 0.0;
    qsort(values, n, sizeof *values, compare_doubles);
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}
