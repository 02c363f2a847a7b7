/* fuzz_volume_header.c - volume headers (engine/load/volume_read.c): NRRD
 * (detached or attached) when the input starts with "NRRD", else the text
 * header of a raw file. The input is written to in.nrrd or in.txt in a
 * scratch directory; a line "#--data--" splits it, and what follows goes to
 * d.raw beside it (seeds name "file: d.raw" or "data file: d.raw"), so
 * sizes, offsets and byte orders meet real data. Without the line, d.raw
 * holds 64 bytes of a ramp.
 *
 * A loaded volume must keep what volume.h promises: dims in 1..
 * VOLUME_MAX_DIM, positive finite spacing, finite origin, min and max equal
 * to a scan of every sample (which also lets ASan see a short buffer). A
 * volume with a cell on every axis is then traced: a macrocell grid and one
 * ray through its middle at the mid value, whose hit must lie on the ray's
 * clipped span and in its cell. */
#define _GNU_SOURCE /* memmem */
#include "fuzz.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/geometry/volume/iso_cell.h"
#include "engine/geometry/volume/macrocell.h"
#include "engine/geometry/volume/volume.h"
#include "engine/load/volume_read.h"

#define DATA_SPLIT "\n#--data--\n"

static void check_volume(const volume *v, const char *name)
{
    const uint32_t n[3] = {v->nx, v->ny, v->nz};
    for (int a = 0; a < 3; a++) {
        if (n[a] == 0 || n[a] > VOLUME_MAX_DIM)
            fuzz_fail("%s: size %u along axis %d accepted", name, n[a], a);
        if (!(v->spacing[a] > 0.0) || !isfinite(v->spacing[a]) || !isfinite(v->origin[a]))
            fuzz_fail("%s: spacing %g or origin %g along axis %d accepted", name, v->spacing[a], v->origin[a], a);
    }
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < volume_count(v); i++) {
        float s = volume_sample_at(v, i);
        if (!isfinite(s))
            fuzz_fail("%s: sample %zu is not finite", name, i);
        lo = s < lo ? s : lo;
        hi = s > hi ? s : hi;
    }
    if (lo != v->min || hi != v->max)
        fuzz_fail("%s: range [%g, %g], the samples span [%g, %g]", name, v->min, v->max, lo, hi);
    if (n[0] < 2 || n[1] < 2 || n[2] < 2)
        return;
    tess_error err = {{0}};
    macrocell_grid *g = macrocell_grid_create(v, 2, &err);
    if (!g)
        fuzz_fail("%s: no macrocell grid: %s", name, err.msg);
    double org[3], dir[3] = {0.31, 0.83, -0.47};
    for (int a = 0; a < 3; a++)
        org[a] = v->origin[a] + 0.5 * (n[a] - 1) * v->spacing[a] - 1e3 * dir[a] * v->spacing[a];
    for (int a = 0; a < 3; a++)
        dir[a] *= v->spacing[a];
    iso_hit hit;
    float iso = 0.5f * (v->min + v->max);
    if (iso_volume_first_hit(v, g, org, dir, 0.0, INFINITY, iso, ISO_METHOD_EXACT, &hit)) {
        for (int a = 0; a < 3; a++)
            if (hit.cell[a] + 1 >= n[a] || !(hit.local[a] >= -1e-6 && hit.local[a] <= 1.0 + 1e-6))
                fuzz_fail("%s: hit in cell %u along axis %d at local %g", name, hit.cell[a], a, hit.local[a]);
        if (!(hit.t >= 0.0) || !isfinite(hit.t))
            fuzz_fail("%s: hit at t %g", name, hit.t);
    }
    macrocell_grid_destroy(g);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char nrrd_path[512], txt_path[512], raw_path[512];
    if (!nrrd_path[0]) {
        snprintf(nrrd_path, sizeof nrrd_path, "%s/in.nrrd", fuzz_scratch_dir());
        snprintf(txt_path, sizeof txt_path, "%s/in.txt", fuzz_scratch_dir());
        snprintf(raw_path, sizeof raw_path, "%s/d.raw", fuzz_scratch_dir());
    }
    bool nrrd = size >= 4 && memcmp(data, "NRRD", 4) == 0;
    const char *path = nrrd ? nrrd_path : txt_path;
    size_t header_bytes = size;
    const uint8_t *split = memmem(data, size, DATA_SPLIT, strlen(DATA_SPLIT));
    if (split)
        header_bytes = (size_t)(split - data) + 1;
    fuzz_write(path, data, header_bytes);
    if (split) {
        size_t at = header_bytes + strlen(DATA_SPLIT) - 1;
        fuzz_write(raw_path, data + at, size - at);
    } else {
        uint8_t ramp[64];
        for (int i = 0; i < 64; i++)
            ramp[i] = (uint8_t)(i * 4);
        fuzz_write(raw_path, ramp, sizeof ramp);
    }
    tess_error err = {{0}};
    volume *v = nrrd ? volume_load_nrrd(path, &err) : volume_load_raw_txt(path, &err);
    if (v)
        check_volume(v, path);
    else
        fuzz_check_error(&err, path);
    volume_destroy(v);
    return 0;
}
