/* test_gen_assembly.c - tools/gen_assembly end to end: the generated .glb is
 * byte-identical for the same options, parses with assimp (structure
 * validated), has the part tree, instancing, normals and materials the README
 * promises, meets --parts and --triangles within their tolerances, and every
 * mesh is a closed, consistently oriented solid facing outwards. Bad options
 * and unwritable files are refused with exit 2. tests/data/assembly-small.glb
 * must equal a fresh generation with the command in tests/data/README.md.
 *
 * Runs ../build/gen-assembly (or $TESSERA_GEN_ASSEMBLY) from tests/. */
#include <criterion/criterion.h>

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

#define PATH_BYTES 512
#define TEXT_BYTES 8192

/* The command that made tests/data/assembly-small.glb (tests/data/README.md). */
#define SMALL_ARGS "--parts 200 --triangles 20000 --seed 1"

static char scratch_dir[128];

static void scratch_create(void) { support_make_tmp_dir(scratch_dir, sizeof scratch_dir, "gen_assembly"); }

static void scratch_remove(void) { support_remove_tmp_dir(scratch_dir); }

TestSuite(gen_assembly, .init = scratch_create, .fini = scratch_remove);

static const char *gen_bin(void)
{
    const char *bin = getenv("TESSERA_GEN_ASSEMBLY");
    return bin ? bin : "../build/gen-assembly";
}

/* Run `gen-assembly ARGS`; stdout and stderr into out and err (TEXT_BYTES
 * each, may be NULL). The exit status (124: timeout, 128 + signal). */
static int gen_run(const char *args, char *out, char *err)
{
    char cmd[2048], out_path[PATH_BYTES], err_path[PATH_BYTES], text[TEXT_BYTES];
    snprintf(out_path, sizeof out_path, "%s/gen.out", scratch_dir);
    snprintf(err_path, sizeof err_path, "%s/gen.err", scratch_dir);
    snprintf(cmd, sizeof cmd, "timeout 120 %s %s > '%s' 2> '%s'", gen_bin(), args, out_path, err_path);
    int code = support_run(cmd);
    support_read_text(out_path, out ? out : text, TEXT_BYTES);
    support_read_text(err_path, err ? err : text, TEXT_BYTES);
    return code;
}

/* Generate scratch/name with `options`; the summary line into out. */
static void generate(const char *name, const char *options, char *out)
{
    char args[1024], err[TEXT_BYTES];
    snprintf(args, sizeof args, "%s -o '%s/%s'", options, scratch_dir, name);
    int code = gen_run(args, out, err);
    cr_assert_eq(code, 0, "gen-assembly %s: exit %d: %s", args, code, err);
    cr_assert(strstr(out, "gen-assembly: parts=") == out, "no summary line: %s", out);
}

/* Whole file into memory (caller frees); fails the test if unreadable. */
static unsigned char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    cr_assert(f, "cannot read %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *data = malloc(n > 0 ? (size_t)n : 1);
    cr_assert(data);
    cr_assert_eq(fread(data, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return data;
}

static bool same_files(const char *a, const char *b)
{
    size_t na, nb;
    unsigned char *da = read_all(a, &na), *db = read_all(b, &nb);
    bool same = na == nb && !memcmp(da, db, na);
    free(da);
    free(db);
    return same;
}

/* A number field `key=` of the summary line. */
static unsigned long long summary_field(const char *line, const char *key)
{
    char needle[64];
    snprintf(needle, sizeof needle, " %s=", key);
    const char *p = strstr(line, needle);
    cr_assert(p, "summary lacks %s: %s", key, line);
    return strtoull(p + strlen(needle), NULL, 10);
}

static const struct aiScene *import(const char *path)
{
    const struct aiScene *scene = aiImportFile(path, aiProcess_ValidateDataStructure);
    cr_assert(scene, "assimp cannot read %s: %s", path, aiGetErrorString());
    return scene;
}

/* ---- the part tree -------------------------------------------------------- */

struct tree_stats {
    unsigned long long parts;       /* nodes with a mesh */
    unsigned long long mesh_refs;   /* mesh references of all nodes */
    unsigned long long triangles;   /* faces of all referenced meshes, each reference counted */
    unsigned long long sections, bolts, rivets, brackets;
    bool bolt_path;                 /* assembly/section-K/frame-N/bracket-M/bolt-J seen */
};

static bool starts_with(const char *s, const char *prefix) { return !strncmp(s, prefix, strlen(prefix)); }

static void walk(const struct aiScene *scene, const struct aiNode *node, int depth, const char *path[8],
                 struct tree_stats *st)
{
    const char *name = node->mName.data;
    if (depth < 8)
        path[depth] = name;
    if (node->mNumMeshes)
        st->parts++;
    st->mesh_refs += node->mNumMeshes;
    for (unsigned i = 0; i < node->mNumMeshes; i++)
        st->triangles += scene->mMeshes[node->mMeshes[i]]->mNumFaces;
    st->sections += depth == 1 && starts_with(name, "section-");
    st->brackets += starts_with(name, "bracket-");
    st->rivets += starts_with(name, "rivet-");
    if (starts_with(name, "bolt-")) {
        st->bolts++;
        st->bolt_path |= depth == 4 && starts_with(path[1], "section-") && starts_with(path[2], "frame-") &&
                         starts_with(path[3], "bracket-");
    }
    /* names are unique among siblings */
    for (unsigned i = 0; i < node->mNumChildren; i++)
        for (unsigned j = i + 1; j < node->mNumChildren; j++)
            cr_assert(strcmp(node->mChildren[i]->mName.data, node->mChildren[j]->mName.data),
                      "two children of %s are named %s", name, node->mChildren[i]->mName.data);
    for (unsigned i = 0; i < node->mNumChildren; i++)
        walk(scene, node->mChildren[i], depth + 1, path, st);
}

static struct tree_stats tree_of(const struct aiScene *scene)
{
    struct tree_stats st = {0};
    const char *path[8] = {0};
    cr_assert_str_eq(scene->mRootNode->mName.data, "assembly");
    walk(scene, scene->mRootNode, 0, path, &st);
    return st;
}

/* ---- closedness ----------------------------------------------------------- */

struct keyed {
    float p[3];
    uint32_t index;
};

static int cmp_keyed(const void *a, const void *b)
{
    const struct keyed *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->p[i] != y->p[i])
            return x->p[i] < y->p[i] ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Every undirected edge in exactly two triangles and every directed edge in
 * one (consistent orientation) once vertices with equal positions are
 * merged, and a positive enclosed volume (facing outwards). */
static void expect_closed(const struct aiMesh *mesh)
{
    unsigned nv = mesh->mNumVertices, nf = mesh->mNumFaces;
    struct keyed *k = malloc(sizeof *k * nv);
    uint32_t *id = malloc(sizeof *id * nv);
    uint64_t *und = malloc(sizeof *und * 3 * nf), *dir = malloc(sizeof *dir * 3 * nf);
    cr_assert(k && id && und && dir);
    for (unsigned v = 0; v < nv; v++) {
        k[v] = (struct keyed){{mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z}, v};
        for (int a = 0; a < 3; a++)
            k[v].p[a] += 0.0f; /* -0 and 0 are one position */
    }
    qsort(k, nv, sizeof *k, cmp_keyed);
    uint32_t next = 0;
    for (unsigned v = 0; v < nv; v++) {
        if (v && memcmp(k[v].p, k[v - 1].p, sizeof k[v].p))
            next++;
        id[k[v].index] = next;
    }
    double volume = 0.0;
    for (unsigned f = 0; f < nf; f++) {
        const struct aiFace *face = &mesh->mFaces[f];
        cr_assert_eq(face->mNumIndices, 3, "mesh %s: a face of %u vertices", mesh->mName.data, face->mNumIndices);
        for (int e = 0; e < 3; e++) {
            uint32_t a = id[face->mIndices[e]], b = id[face->mIndices[(e + 1) % 3]];
            cr_assert_neq(a, b, "mesh %s: a degenerate edge in face %u", mesh->mName.data, f);
            und[3 * f + (unsigned)e] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
            dir[3 * f + (unsigned)e] = (uint64_t)a << 32 | b;
        }
        const struct aiVector3D *p0 = &mesh->mVertices[face->mIndices[0]], *p1 = &mesh->mVertices[face->mIndices[1]],
                                *p2 = &mesh->mVertices[face->mIndices[2]];
        volume += (double)p0->x * ((double)p1->y * p2->z - (double)p1->z * p2->y) -
                  (double)p0->y * ((double)p1->x * p2->z - (double)p1->z * p2->x) +
                  (double)p0->z * ((double)p1->x * p2->y - (double)p1->y * p2->x);
    }
    qsort(und, 3 * (size_t)nf, sizeof *und, cmp_u64);
    qsort(dir, 3 * (size_t)nf, sizeof *dir, cmp_u64);
    for (size_t i = 0; i < 3 * (size_t)nf;) {
        size_t j = i;
        while (j < 3 * (size_t)nf && und[j] == und[i])
            j++;
        cr_assert_eq(j - i, 2, "mesh %s: an edge in %zu triangles", mesh->mName.data, j - i);
        i = j;
    }
    for (size_t i = 1; i < 3 * (size_t)nf; i++)
        cr_assert_neq(dir[i], dir[i - 1], "mesh %s: two triangles run along one edge the same way (orientation)",
                      mesh->mName.data);
    cr_assert_gt(volume, 0.0, "mesh %s: encloses a negative volume (faces inwards)", mesh->mName.data);
    free(k);
    free(id);
    free(und);
    free(dir);
}

/* ---- tests ---------------------------------------------------------------- */

Test(gen_assembly, same_options_same_bytes_other_seed_other_bytes)
{
    char out[TEXT_BYTES], a[PATH_BYTES], b[PATH_BYTES], c[PATH_BYTES];
    generate("a.glb", "--parts 300 --triangles 60000 --seed 7", out);
    generate("b.glb", "--parts 300 --triangles 60000 --seed 7", out);
    generate("c.glb", "--parts 300 --triangles 60000 --seed 8", out);
    snprintf(a, sizeof a, "%s/a.glb", scratch_dir);
    snprintf(b, sizeof b, "%s/b.glb", scratch_dir);
    snprintf(c, sizeof c, "%s/c.glb", scratch_dir);
    cr_expect(same_files(a, b), "the same options gave different files");
    cr_expect(!same_files(a, c), "seeds 7 and 8 gave the same file");
}

Test(gen_assembly, glb_container_is_well_formed)
{
    char out[TEXT_BYTES], path[PATH_BYTES];
    generate("f.glb", "--parts 100 --triangles 10000", out);
    snprintf(path, sizeof path, "%s/f.glb", scratch_dir);
    size_t n;
    unsigned char *d = read_all(path, &n);
    uint32_t w[5];
    cr_assert_geq(n, 28u);
    memcpy(w, d, sizeof w);
    cr_expect_eq(w[0], 0x46546C67u, "magic");
    cr_expect_eq(w[1], 2u, "version");
    cr_expect_eq(w[2], (uint32_t)n, "length");
    cr_expect_eq(w[3] % 4, 0u, "JSON chunk length a multiple of 4");
    cr_expect_eq(w[4], 0x4E4F534Au, "JSON chunk type");
    uint32_t bin[2];
    memcpy(bin, d + 20 + w[3], sizeof bin);
    cr_expect_eq(bin[1], 0x004E4942u, "BIN chunk type");
    cr_expect_eq(bin[0] % 4, 0u);
    cr_expect_eq(20 + w[3] + 8 + bin[0], (uint32_t)n, "the chunks fill the file");
    cr_expect_eq(summary_field(out, "bytes"), n);
    free(d);
}

Test(gen_assembly, tree_instancing_normals_materials)
{
    char out[TEXT_BYTES], path[PATH_BYTES];
    generate("t.glb", "--parts 800 --triangles 200000 --seed 3", out);
    snprintf(path, sizeof path, "%s/t.glb", scratch_dir);
    const struct aiScene *scene = import(path);
    struct tree_stats st = tree_of(scene);
    cr_expect_geq(st.sections, 2, "sections: %llu", st.sections);
    cr_expect_gt(st.bolts, 0);
    cr_expect_gt(st.rivets, 0);
    cr_expect_gt(st.brackets, 0);
    cr_expect(st.bolt_path, "no bolt at assembly/section-K/frame-N/bracket-M/bolt-J");
    cr_expect_eq(st.parts, summary_field(out, "parts"));
    cr_expect_eq(st.triangles, summary_field(out, "triangles_instanced"));
    cr_expect_eq(scene->mNumMeshes, summary_field(out, "meshes"));
    /* instancing: far fewer meshes than references to them */
    cr_expect_geq(st.mesh_refs, 10ull * scene->mNumMeshes, "%llu references to %u meshes", st.mesh_refs,
                  scene->mNumMeshes);
    unsigned long long stored = 0;
    for (unsigned m = 0; m < scene->mNumMeshes; m++) {
        const struct aiMesh *mesh = scene->mMeshes[m];
        cr_expect(mesh->mNormals != NULL, "mesh %s has no normals", mesh->mName.data);
        cr_expect_eq(mesh->mPrimitiveTypes, aiPrimitiveType_TRIANGLE, "mesh %s", mesh->mName.data);
        stored += mesh->mNumFaces;
    }
    cr_expect_eq(stored, summary_field(out, "triangles_stored"));

    static const struct {
        const char *name;
        float rgb[3];
    } expect[] = {
        {"aluminium", {0.77f, 0.78f, 0.80f}}, {"primer-green", {0.42f, 0.58f, 0.33f}},
        {"steel", {0.28f, 0.29f, 0.31f}},     {"pipe-orange", {0.93f, 0.45f, 0.08f}},
        {"bracket-blue", {0.16f, 0.33f, 0.74f}},
    };
    for (size_t e = 0; e < sizeof expect / sizeof expect[0]; e++) {
        bool found = false;
        for (unsigned i = 0; i < scene->mNumMaterials; i++) {
            struct aiString name;
            if (aiGetMaterialString(scene->mMaterials[i], AI_MATKEY_NAME, &name) != aiReturn_SUCCESS ||
                strcmp(name.data, expect[e].name))
                continue;
            struct aiColor4D c;
            cr_assert_eq(aiGetMaterialColor(scene->mMaterials[i], AI_MATKEY_BASE_COLOR, &c), aiReturn_SUCCESS,
                         "material %s has no base colour", expect[e].name);
            cr_expect(fabsf(c.r - expect[e].rgb[0]) < 1e-4f && fabsf(c.g - expect[e].rgb[1]) < 1e-4f &&
                          fabsf(c.b - expect[e].rgb[2]) < 1e-4f,
                      "material %s: base colour %g %g %g", expect[e].name, c.r, c.g, c.b);
            found = true;
        }
        cr_expect(found, "no material %s", expect[e].name);
    }
    aiReleaseImport(scene);
}

/* Parts within 10 % and placed triangles within 20 % of what was asked, as
 * counted from the file itself. */
static void expect_knobs(unsigned long long parts, unsigned long long triangles)
{
    char out[TEXT_BYTES], options[256], path[PATH_BYTES];
    snprintf(options, sizeof options, "--parts %llu --triangles %llu", parts, triangles);
    generate("k.glb", options, out);
    snprintf(path, sizeof path, "%s/k.glb", scratch_dir);
    const struct aiScene *scene = import(path);
    struct tree_stats st = tree_of(scene);
    cr_expect(st.parts >= parts * 0.9 && st.parts <= parts * 1.1, "%s: %llu parts", options, st.parts);
    cr_expect(st.triangles >= triangles * 0.8 && st.triangles <= triangles * 1.2, "%s: %llu triangles", options,
              st.triangles);
    cr_expect_lt(summary_field(out, "triangles_stored"), st.triangles / 4, "%s: %s", options, out);
    aiReleaseImport(scene);
}

Test(gen_assembly, knobs_within_tolerance_small) { expect_knobs(500, 150000); }

Test(gen_assembly, knobs_within_tolerance_large, .timeout = 120) { expect_knobs(4000, 3000000); }

Test(gen_assembly, every_mesh_closed_and_outward)
{
    char out[TEXT_BYTES], path[PATH_BYTES];
    /* both stringer profiles and pipes with one and two bends appear by seed 5 at this size */
    generate("c.glb", "--parts 1500 --triangles 400000 --seed 5", out);
    snprintf(path, sizeof path, "%s/c.glb", scratch_dir);
    const struct aiScene *scene = import(path);
    bool box = false, z = false;
    for (unsigned m = 0; m < scene->mNumMeshes; m++) {
        const struct aiMesh *mesh = scene->mMeshes[m];
        expect_closed(mesh);
        if (starts_with(mesh->mName.data, "stringer-")) {
            box |= mesh->mNumFaces == 12;
            z |= mesh->mNumFaces == 28;
        }
    }
    cr_expect(box && z, "both stringer profiles should appear (box %d, Z %d)", box, z);
    aiReleaseImport(scene);
}

Test(gen_assembly, shipped_small_assembly_is_current)
{
    char out[TEXT_BYTES], path[PATH_BYTES];
    generate("small.glb", SMALL_ARGS, out);
    snprintf(path, sizeof path, "%s/small.glb", scratch_dir);
    cr_expect(same_files("data/assembly-small.glb", path),
              "tests/data/assembly-small.glb differs from gen-assembly " SMALL_ARGS
              ": regenerate it with the command in tests/data/README.md");
    const struct aiScene *scene = import("data/assembly-small.glb");
    for (unsigned m = 0; m < scene->mNumMeshes; m++)
        expect_closed(scene->mMeshes[m]);
    aiReleaseImport(scene);
}

static void expect_refused(const char *args, const char *needle)
{
    char out[TEXT_BYTES], err[TEXT_BYTES];
    int code = gen_run(args, out, err);
    cr_expect_eq(code, 2, "'%s': exit %d, 2 expected: %s", args, code, err);
    cr_expect(strstr(err, "error") && strstr(err, needle), "'%s': message lacks '%s': %s", args, needle, err);
    cr_expect_str_empty(out, "'%s' printed: %s", args, out);
}

Test(gen_assembly, bad_options_refused)
{
    char args[PATH_BYTES + 64];
    snprintf(args, sizeof args, "-o '%s/x.glb'", scratch_dir);
    char with[PATH_BYTES + 128];
    snprintf(with, sizeof with, "%s --parts -3", args);
    expect_refused(with, "--parts");
    snprintf(with, sizeof with, "%s --parts abc", args);
    expect_refused(with, "--parts");
    snprintf(with, sizeof with, "%s --parts 12x", args);
    expect_refused(with, "--parts");
    snprintf(with, sizeof with, "%s --triangles 0", args);
    expect_refused(with, "--triangles");
    snprintf(with, sizeof with, "%s --seed -1", args);
    expect_refused(with, "--seed");
    snprintf(with, sizeof with, "%s --bogus 1", args);
    expect_refused(with, "--bogus");
    snprintf(with, sizeof with, "%s --parts", args);
    expect_refused(with, "--parts");
    expect_refused("--parts 100", "-o");
    expect_refused("--parts 100 -o", "-o");
}

Test(gen_assembly, unwritable_file_refused)
{
    char args[PATH_BYTES + 64], needle[PATH_BYTES];
    snprintf(needle, sizeof needle, "%s/missing/x.glb", scratch_dir);
    snprintf(args, sizeof args, "--parts 100 -o '%s'", needle);
    expect_refused(args, needle);
    /* a directory is not writable as a file */
    snprintf(args, sizeof args, "--parts 100 -o '%s'", scratch_dir);
    expect_refused(args, scratch_dir);
}

Test(gen_assembly, help)
{
    char out[TEXT_BYTES], err[TEXT_BYTES];
    cr_expect_eq(gen_run("--help", out, err), 0);
    cr_expect(strstr(out, "--parts") && strstr(out, "--triangles") && strstr(out, "--seed") && strstr(out, "-o"),
              "%s", out);
}
