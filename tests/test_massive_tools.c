/* test_massive_tools.c - the two programs that make `make bench-massive`'s
 * meshes, end to end on small inputs:
 *   gen-assembly --ply: the assembly flattened into one binary PLY; mesh_load
 *     reads it with every placed triangle and vertex the summary counts, in
 *     the same place as assimp's flattening of the .glb (the bounds and the
 *     mean triangle centroid agree), the same bytes for the same options,
 *     and tessera bench traces it;
 *   ply-replicate: a tiny PLY (ascii, with normals) copied onto a grid: the
 *     counts, every copy's offset and index base, a binary little-endian
 *     file that tessera bench traces; bad options and inputs refused.
 *
 * Runs ../build/gen-assembly and ../build/ply-replicate (or
 * $TESSERA_GEN_ASSEMBLY, $TESSERA_PLY_REPLICATE) and ../tessera from tests/. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/err.h"
#include "engine/geometry/triangles/mesh.h"
#include "support.h"
#include "engine/load/mesh_load.h"

#define TEXT_BYTES 8192
#define PATH_BYTES 512

static char dir[128];

static void scratch_create(void) { support_make_tmp_dir(dir, sizeof dir, "massive_tools"); }

static void scratch_remove(void) { support_remove_tmp_dir(dir); }

TestSuite(massive_tools, .init = scratch_create, .fini = scratch_remove);

static const char *env_or(const char *name, const char *fallback)
{
    const char *v = getenv(name);
    return v ? v : fallback;
}

/* Run `BIN ARGS` (a time limit of 120 s); stdout and stderr into out and err. */
static int run_tool(const char *bin, const char *args, char *out, char *err)
{
    char cmd[2048], out_path[PATH_BYTES], err_path[PATH_BYTES];
    snprintf(out_path, sizeof out_path, "%s/tool.out", dir);
    snprintf(err_path, sizeof err_path, "%s/tool.err", dir);
    snprintf(cmd, sizeof cmd, "timeout 120 %s %s > '%s' 2> '%s'", bin, args, out_path, err_path);
    int code = support_run(cmd);
    support_read_text(out_path, out, TEXT_BYTES);
    support_read_text(err_path, err, TEXT_BYTES);
    return code;
}

static int gen(const char *args, char *out, char *err)
{
    return run_tool(env_or("TESSERA_GEN_ASSEMBLY", "../build/gen-assembly"), args, out, err);
}

static int replicate(const char *args, char *out, char *err)
{
    return run_tool(env_or("TESSERA_PLY_REPLICATE", "../build/ply-replicate"), args, out, err);
}

/* A number field `key=` of a summary line (after `after`, when given). */
static unsigned long long field(const char *text, const char *after, const char *key)
{
    char needle[64];
    const char *from = after ? strstr(text, after) : text;
    cr_assert(from, "no '%s' in: %s", after, text);
    snprintf(needle, sizeof needle, " %s=", key);
    const char *p = strstr(from, needle);
    cr_assert(p, "no %s in: %s", key, text);
    return strtoull(p + strlen(needle), NULL, 10);
}

static mesh *load(const char *name)
{
    char path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    tess_error err = {{0}};
    mesh *m = mesh_load(path, &err);
    cr_assert(m, "mesh_load %s: %s", path, err.msg);
    return m;
}

static bool same_bytes(const char *a, const char *b)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "cmp -s '%s/%s' '%s/%s'", dir, a, dir, b);
    return support_run(cmd) == 0;
}

/* The mean of the triangles' centroids. */
static void mean_centroid(const mesh *m, double c[3])
{
    c[0] = c[1] = c[2] = 0.0;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                c[a] += m->positions[3 * m->indices[3 * t + (uint32_t)k] + (uint32_t)a];
    for (int a = 0; a < 3; a++)
        c[a] /= 3.0 * m->triangle_count;
}

/* tessera bench traces `name`: exit 0 and a BENCH line with `triangles` triangles. */
static void expect_traced(const char *name, unsigned long long triangles)
{
    char out[TEXT_BYTES], err[TEXT_BYTES], args[PATH_BYTES];
    snprintf(args, sizeof args, "--scene '%%s/%s' --size 64x48 --threads 1 --frames 1 --warmup 0", name);
    int code = support_tessera_bench(dir, 120, out, err, sizeof out, args);
    cr_assert_eq(code, 0, "tessera bench %s: exit %d: %s", name, code, err);
    cr_expect_eq(field(out, "BENCH ", "triangles"), triangles, "%s", out);
    cr_expect_gt(field(out, "BENCH ", "hits"), 0, "%s", out);
}

/* ---- gen-assembly --ply ---------------------------------------------------- */

Test(massive_tools, flattened_ply_matches_the_glb, .timeout = 120)
{
    char args[1024], out[TEXT_BYTES], err[TEXT_BYTES];
    snprintf(args, sizeof args, "--parts 300 --triangles 60000 -o '%s/a.glb' --ply '%s/a.ply'", dir, dir);
    cr_assert_eq(gen(args, out, err), 0, "%s", err);
    unsigned long long placed = field(out, "gen-assembly: parts=", "triangles_instanced");
    unsigned long long tris = field(out, "flattened", "triangles"), verts = field(out, "flattened", "vertices");
    cr_expect_eq(tris, placed, "%s", out);

    mesh *p = load("a.ply");
    cr_expect_eq(p->triangle_count, tris);
    cr_expect_eq(p->vertex_count, verts);
    cr_expect_null(p->normals, "the PLY has no normals");
    /* assimp's flattening of the .glb (what tessera bench --flatten loads) */
    mesh *g = load("a.glb");
    cr_expect_eq(g->triangle_count, p->triangle_count);
    float plo[3], phi[3], glo[3], ghi[3];
    cr_assert(mesh_bounds(p, plo, phi) && mesh_bounds(g, glo, ghi));
    double cp[3], cg[3];
    mean_centroid(p, cp);
    mean_centroid(g, cg);
    for (int a = 0; a < 3; a++) {
        cr_expect(fabsf(plo[a] - glo[a]) < 1e-4f && fabsf(phi[a] - ghi[a]) < 1e-4f,
                  "axis %d: bounds [%g, %g] against the glb's [%g, %g]", a, plo[a], phi[a], glo[a], ghi[a]);
        cr_expect(fabs(cp[a] - cg[a]) < 1e-4, "axis %d: mean centroid %.9g against the glb's %.9g", a, cp[a], cg[a]);
    }
    mesh_destroy(p);
    mesh_destroy(g);
    expect_traced("a.ply", tris);

    /* the same options, the same bytes; --ply alone writes no .glb */
    snprintf(args, sizeof args, "--parts 300 --triangles 60000 --ply '%s/b.ply'", dir);
    cr_assert_eq(gen(args, out, err), 0, "%s", err);
    cr_expect(same_bytes("a.ply", "b.ply"));
    cr_expect_null(strstr(out, "triangles_instanced"), "no .glb line without -o: %s", out);
    cr_expect(strstr(out, "gen-assembly: flattened parts=") == out, "%s", out);
}

Test(massive_tools, gen_assembly_ply_refusals)
{
    char args[1024], out[TEXT_BYTES], err[TEXT_BYTES];
    cr_expect_eq(gen("--parts 100", out, err), 2);
    cr_expect(strstr(err, "--ply"), "the message names --ply: %s", err);
    cr_expect_eq(gen("--parts 100 --ply", out, err), 2);
    snprintf(args, sizeof args, "--parts 100 --ply '%s/missing/x.ply'", dir);
    cr_expect_eq(gen(args, out, err), 2);
    cr_expect(strstr(err, "missing/x.ply"), "%s", err);
    /* an unwritable PLY leaves no .glb behind */
    snprintf(args, sizeof args, "--parts 100 -o '%s/c.glb' --ply '%s/missing/x.ply'", dir, dir);
    cr_expect_eq(gen(args, out, err), 2);
    char path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/c.glb", dir);
    FILE *f = fopen(path, "rb");
    cr_expect_null(f, "c.glb was left behind");
    if (f)
        fclose(f);
}

/* ---- ply-replicate ---------------------------------------------------------- */

/* Two triangles of a unit square at height 2, with normals the copy drops. */
static const char small_ply[] = "ply\n"
                                "format ascii 1.0\n"
                                "element vertex 4\n"
                                "property float x\nproperty float y\nproperty float z\n"
                                "property float nx\nproperty float ny\nproperty float nz\n"
                                "element face 2\n"
                                "property list uchar int vertex_indices\n"
                                "end_header\n"
                                "1 2 3 0 1 0\n"
                                "2 2 3 0 1 0\n"
                                "2 2 5 0 1 0\n"
                                "1 2 5 0 1 0\n"
                                "3 0 1 2\n"
                                "3 0 2 3\n";

Test(massive_tools, replicated_grid, .timeout = 60)
{
    support_write_file(dir, "in.ply", small_ply);
    char args[1024], out[TEXT_BYTES], err[TEXT_BYTES];
    snprintf(args, sizeof args, "--grid 3x2 --gap 0.5 -o '%s/out.ply' '%s/in.ply'", dir, dir);
    cr_assert_eq(replicate(args, out, err), 0, "%s", err);
    cr_expect_eq(field(out, NULL, "copies"), 6, "%s", out);
    cr_expect_eq(field(out, NULL, "triangles"), 12, "%s", out);
    cr_expect_eq(field(out, NULL, "vertices"), 24, "%s", out);
    cr_expect(strstr(out, " step=1.5,3 "), "x extent 1, z extent 2, gap 0.5: %s", out);

    char head[TEXT_BYTES], path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/out.ply", dir);
    support_read_text(path, head, 200);
    cr_expect(strstr(head, "format binary_little_endian 1.0\n"), "%s", head);
    cr_expect(strstr(head, "element vertex 24\n") && strstr(head, "element face 12\n"), "%s", head);

    mesh *in = load("in.ply"), *m = load("out.ply");
    cr_assert_eq(m->vertex_count, 24);
    cr_assert_eq(m->triangle_count, 12);
    cr_expect_null(m->normals);
    for (uint32_t k = 0; k < 6; k++) {
        float dx = 1.5f * (float)(k % 3), dz = 3.0f * (float)(k / 3);
        for (uint32_t v = 0; v < 4; v++) {
            const float *a = in->positions + 3 * v, *b = m->positions + 3 * (4 * k + v);
            cr_expect(b[0] == a[0] + dx && b[1] == a[1] && b[2] == a[2] + dz,
                      "copy %u vertex %u: (%g %g %g), expected (%g %g %g)", k, v, b[0], b[1], b[2], a[0] + dx, a[1],
                      a[2] + dz);
        }
        for (uint32_t i = 0; i < 6; i++)
            cr_expect_eq(m->indices[6 * k + i], 4 * k + in->indices[i], "copy %u index %u", k, i);
    }
    mesh_destroy(in);
    mesh_destroy(m);
    expect_traced("out.ply", 12);

    /* 1x1: the input itself, as binary */
    snprintf(args, sizeof args, "--grid 1x1 -o '%s/one.ply' '%s/in.ply'", dir, dir);
    cr_assert_eq(replicate(args, out, err), 0, "%s", err);
    cr_expect_eq(field(out, NULL, "triangles"), 2, "%s", out);
}

Test(massive_tools, replicate_refusals)
{
    support_write_file(dir, "in.ply", small_ply);
    support_write_file(dir, "bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n");
    char args[1024], out[TEXT_BYTES], err[TEXT_BYTES];
    static const char *const bad_grids[] = {"0x3", "3", "3x", "x3", "3x0", "1001x1", "2x2x2", "-1x2"};
    for (size_t i = 0; i < sizeof bad_grids / sizeof *bad_grids; i++) {
        snprintf(args, sizeof args, "--grid %s -o '%s/o.ply' '%s/in.ply'", bad_grids[i], dir, dir);
        cr_expect_eq(replicate(args, out, err), 2, "--grid %s", bad_grids[i]);
        cr_expect(strstr(err, "--grid"), "%s", err);
    }
    snprintf(args, sizeof args, "--gap -1 -o '%s/o.ply' '%s/in.ply'", dir, dir);
    cr_expect_eq(replicate(args, out, err), 2);
    snprintf(args, sizeof args, "'%s/in.ply'", dir);
    cr_expect_eq(replicate(args, out, err), 2, "no -o");
    cr_expect(strstr(err, "-o"), "%s", err);
    snprintf(args, sizeof args, "-o '%s/o.ply'", dir);
    cr_expect_eq(replicate(args, out, err), 2, "no input");
    cr_expect_eq(replicate("--bogus", out, err), 2);
    /* inputs and outputs that fail: exit 1, one error line, no file left */
    snprintf(args, sizeof args, "-o '%s/o.ply' '%s/none.ply'", dir, dir);
    cr_expect_eq(replicate(args, out, err), 1);
    cr_expect(strstr(err, "ply-replicate: error: "), "%s", err);
    snprintf(args, sizeof args, "-o '%s/o.ply' '%s/bad.ply'", dir, dir);
    cr_expect_eq(replicate(args, out, err), 1, "%s", err);
    snprintf(args, sizeof args, "-o '%s/missing/o.ply' '%s/in.ply'", dir, dir);
    cr_expect_eq(replicate(args, out, err), 1);
    cr_expect(strstr(err, "missing/o.ply"), "%s", err);
    char path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/o.ply", dir);
    FILE *f = fopen(path, "rb");
    cr_expect_null(f, "o.ply was left behind");
    if (f)
        fclose(f);
    cr_expect_eq(replicate("--help", out, err), 0);
    cr_expect(strstr(out, "--grid") && strstr(out, "--gap"), "%s", out);
}
