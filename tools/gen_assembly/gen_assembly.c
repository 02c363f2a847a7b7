/* gen_assembly.c - gen-assembly: writes a deterministic CAD-like assembly (an
 * aircraft fuselage of frames, stringers, skin panels, pipes, brackets, bolts
 * and rivets) as one binary glTF 2.0 file, for tests and benchmarks of large
 * part trees. The command line and the summary line; layout.h places the
 * parts, shapes.h tessellates them, glb.h writes the file. */
#include <errno.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glb.h"
#include "layout.h"
#include "ply.h"

#define DEFAULT_PARTS 1000
#define DEFAULT_TRIANGLES 1000000
#define MAX_TRIANGLES 10000000000ull /* placed triangles; the stored ones are far fewer */
/* the tolerances the README promises, checked after the fit */
#define PARTS_TOLERANCE 0.10
#define TRIANGLES_TOLERANCE 0.20

static void usage(FILE *f)
{
    fprintf(f,
            "usage: gen-assembly -o FILE | --ply FILE [--parts N] [--triangles T] [--seed S]\n"
            "Write an aircraft-fuselage-like assembly as binary glTF 2.0 (.glb): sections of ring frames,\n"
            "stringers, skin panels and pipes, with brackets, bolts and rivets (one mesh each, placed many\n"
            "times). The same options always give the same bytes.\n\n"
            "  -o FILE          the .glb to write\n"
            "  --ply FILE       also or instead: the assembly flattened, every placed triangle in one binary\n"
            "                   PLY mesh with the node transforms baked in (-o, --ply or both are required)\n"
            "  --parts N        nodes with a mesh, within 10 %% (%d to %d; default %d)\n"
            "  --triangles T    triangles of all placed parts, within 20 %% (default %d)\n"
            "  --seed S         the random layout (0 to 2^64-1; default 1)\n"
            "  --help           this text\n\n"
            "Prints one line: parts, nodes, meshes, instances, triangles_instanced, triangles_stored, bytes, file;\n"
            "with --ply one more: parts, triangles, vertices, bytes, file of the flattened mesh.\n",
            GA_LAYOUT_MIN_PARTS, GA_LAYOUT_MAX_PARTS, DEFAULT_PARTS, DEFAULT_TRIANGLES);
}

/* A whole number in [lo, hi] from `text` (digits only); false otherwise. */
static bool parse_count(const char *text, uint64_t lo, uint64_t hi, uint64_t *out)
{
    if (!text || text[0] < '0' || text[0] > '9')
        return false;
    errno = 0;
    char *end;
    unsigned long long v = strtoull(text, &end, 10);
    if (errno || *end || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}

/* One error line on stderr; the exit status of a command-line error. */
static int usage_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static int usage_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "gen-assembly: error: ");
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, " (see gen-assembly --help)\n");
    va_end(ap);
    return 2;
}

int main(int argc, char **argv)
{
    struct ga_layout_params params = {DEFAULT_PARTS, DEFAULT_TRIANGLES, 1};
    const char *path = NULL, *ply_path = NULL;
    for (int i = 1; i < argc; i++) {
        const char *opt = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(opt, "--help") || !strcmp(opt, "-h")) {
            usage(stdout);
            return 0;
        }
        bool ok;
        if (!strcmp(opt, "-o")) {
            ok = val && val[0];
            path = val;
        } else if (!strcmp(opt, "--ply")) {
            ok = val && val[0];
            ply_path = val;
        } else if (!strcmp(opt, "--parts")) {
            ok = parse_count(val, GA_LAYOUT_MIN_PARTS, GA_LAYOUT_MAX_PARTS, &params.parts);
            if (!ok && val)
                return usage_error("--parts: expected a whole number from %d to %d, got '%s'", GA_LAYOUT_MIN_PARTS,
                                   GA_LAYOUT_MAX_PARTS, val);
        } else if (!strcmp(opt, "--triangles")) {
            ok = parse_count(val, 1, MAX_TRIANGLES, &params.triangles);
            if (!ok && val)
                return usage_error("--triangles: expected a whole number from 1 to %llu, got '%s'", MAX_TRIANGLES, val);
        } else if (!strcmp(opt, "--seed")) {
            ok = parse_count(val, 0, UINT64_MAX, &params.seed);
            if (!ok && val)
                return usage_error("--seed: expected a whole number from 0 to %llu, got '%s'",
                                   (unsigned long long)UINT64_MAX, val);
        } else {
            return usage_error("unknown option '%s'", opt);
        }
        if (!ok)
            return usage_error("%s needs a value", opt);
        i++;
    }
    if (!path && !ply_path)
        return usage_error("-o FILE or --ply FILE is required: where to write the assembly");

    /* open first, so an unwritable path costs no generation */
    FILE *out = NULL, *ply_out = NULL;
    if (path && !(out = fopen(path, "wb"))) {
        fprintf(stderr, "gen-assembly: error: cannot write %s: %s\n", path, strerror(errno));
        return 2;
    }
    if (ply_path && !(ply_out = fopen(ply_path, "wb"))) {
        fprintf(stderr, "gen-assembly: error: cannot write %s: %s\n", ply_path, strerror(errno));
        if (out) {
            fclose(out);
            remove(path);
        }
        return 2;
    }

    struct ga_layout layout;
    struct ga_glb_stats stats = {0};
    struct ga_ply_stats ply_stats = {0};
    char err[512] = "";
    bool ok = ga_layout_fit(&layout, &params);
    if (!ok)
        snprintf(err, sizeof err, "out of memory laying out %llu parts", (unsigned long long)params.parts);
    if (ok && out)
        ok = ga_glb_write(&layout, out, path, &stats, err, sizeof err);
    if (ok && ply_out)
        ok = ga_ply_write(&layout, ply_out, ply_path, &ply_stats, err, sizeof err);
    if (out && fclose(out) != 0 && ok) {
        snprintf(err, sizeof err, "cannot write %s: %s", path, strerror(errno));
        ok = false;
    }
    if (ply_out && fclose(ply_out) != 0 && ok) {
        snprintf(err, sizeof err, "cannot write %s: %s", ply_path, strerror(errno));
        ok = false;
    }
    if (!ok) {
        if (path)
            remove(path);
        if (ply_path)
            remove(ply_path);
        fprintf(stderr, "gen-assembly: error: %s\n", err);
        ga_layout_finish(&layout);
        return 1;
    }
    if (path)
        printf("gen-assembly: parts=%zu nodes=%zu meshes=%llu instances=%llu triangles_instanced=%llu "
               "triangles_stored=%llu bytes=%llu file=%s\n",
               layout.part_count, layout.node_count, (unsigned long long)stats.meshes,
               (unsigned long long)stats.instances, (unsigned long long)layout.triangles_placed,
               (unsigned long long)stats.triangles_stored, (unsigned long long)stats.bytes, path);
    if (ply_path)
        printf("gen-assembly: flattened parts=%zu triangles=%llu vertices=%llu bytes=%llu file=%s\n",
               layout.part_count, (unsigned long long)ply_stats.triangles, (unsigned long long)ply_stats.vertices,
               (unsigned long long)ply_stats.bytes, ply_path);
    double parts_off = (double)layout.part_count / (double)params.parts - 1.0;
    double tris_off = (double)layout.triangles_placed / (double)params.triangles - 1.0;
    if (parts_off > PARTS_TOLERANCE || parts_off < -PARTS_TOLERANCE)
        fprintf(stderr, "gen-assembly: warning: %zu parts for --parts %llu (more than 10 %% off)\n",
                layout.part_count, (unsigned long long)params.parts);
    if (tris_off > TRIANGLES_TOLERANCE || tris_off < -TRIANGLES_TOLERANCE)
        fprintf(stderr,
                "gen-assembly: warning: %llu triangles for --triangles %llu (more than 20 %% off: the tessellation "
                "limits of %llu parts)\n",
                (unsigned long long)layout.triangles_placed, (unsigned long long)params.triangles,
                (unsigned long long)params.parts);
    ga_layout_finish(&layout);
    return 0;
}
