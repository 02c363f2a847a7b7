/* cmd_parts.c - `tessera parts FILE`: the part tree of an assembly
 * (engine/load/assembly_load.h) with what each part holds, for finding the paths
 * a scene's overrides name. A counting sink: meshes are counted and freed as
 * they come, parts go into a part_tree (engine/scene/part_tree.h), instances are
 * counted on their part.
 *
 * Output (stdout), one header line then one line per part in preorder,
 * indented two spaces per level below the top:
 *   parts=N meshes=M materials=K instances=I triangles_stored=S triangles_instanced=T load_s=X file=PATH
 *   PATH  instances=I triangles=T subtree_triangles=U
 * triangles: of the instances directly on the part, once per instance;
 * subtree_triangles: the same summed over the part and everything under it;
 * triangles_stored: of the meshes, once each; triangles_instanced: once per
 * instance. The header counts every part, also those --depth or --match
 * leave out. With --json the same as one JSON object. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "engine/load/assembly_load.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/part_tree.h"
#include "engine/load/ply_read.h"

typedef struct parts_options {
    const char *path;
    int max_depth;       /* parts deeper than this are not printed */
    const char *pattern; /* only parts whose path matches; "**" for all */
    bool json;
} parts_options;

/* What the counting sink gathers. */
typedef struct parts_count {
    part_tree *tree;
    uint32_t *mesh_triangles; /* per sink mesh id */
    size_t mesh_count, mesh_cap;
    int material_count;
    uint64_t instances, triangles_stored, triangles_instanced;
    tess_error err; /* why the sink refused something */
} parts_count;

static int count_material(void *ctx, const char *name, const float rgb[3])
{
    (void)name;
    (void)rgb;
    return ((parts_count *)ctx)->material_count++;
}

static int count_mesh(void *ctx, mesh *m, int material, const char *name)
{
    (void)material;
    parts_count *c = ctx;
    uint32_t triangles = m->triangle_count;
    mesh_destroy(m);
    if (c->mesh_count == c->mesh_cap) {
        size_t cap = c->mesh_cap ? 2 * c->mesh_cap : 64;
        uint32_t *p = realloc(c->mesh_triangles, cap * sizeof *p);
        if (!p) {
            tess_error_set(&c->err, "out of memory counting mesh '%s'", name);
            return -1;
        }
        c->mesh_triangles = p;
        c->mesh_cap = cap;
    }
    c->mesh_triangles[c->mesh_count] = triangles;
    c->triangles_stored += triangles;
    return (int)c->mesh_count++;
}

static int count_part(void *ctx, int parent, const char *name)
{
    parts_count *c = ctx;
    return part_tree_add(c->tree, parent < 0 ? PART_ROOT : parent, name, &c->err);
}

static int count_instance(void *ctx, int part, int mesh_id, const float to_world[12])
{
    (void)to_world;
    parts_count *c = ctx;
    uint32_t triangles = c->mesh_triangles[mesh_id];
    part_counts *pc = part_tree_counts(c->tree, part);
    pc->instances++;
    pc->triangles += triangles;
    c->instances++;
    c->triangles_instanced += triangles;
    return 0;
}

static void parts_usage(FILE *f)
{
    fputs("usage: tessera parts FILE [--depth N] [--match PATTERN] [--json]\n"
          "The part tree of an assembly (glTF 2.0 nodes, OBJ groups, any format assimp reads): one line\n"
          "per part, indented by depth, with its path, the instances placed directly on it, their\n"
          "triangles (once per instance) and the triangles of its whole subtree; first a header line\n"
          "with the totals (parts, meshes stored, instances, triangles stored and instanced, load time).\n"
          "\n"
          "  --depth N         print parts down to depth N (1: the top-level parts only)\n"
          "  --match PATTERN   print only parts whose path matches PATTERN: '*' matches within one\n"
          "                    path segment, '?' one character, a segment '**' any number of\n"
          "                    segments ('**/bolt-*', 'section-2/**')\n"
          "  --json            one JSON object: the header's totals and \"parts_list\", the printed\n"
          "                    parts as {path, depth, instances, triangles, subtree_triangles}\n"
          "Errors (a missing or broken file) name the file; exit 1 (2 for a bad option).\n",
          f);
}

/* Parse the options. False when the command should stop: after --help
 * (*exit_code 0) or a bad or missing option (2). */
static bool parse_options(int argc, char **argv, parts_options *o, int *exit_code)
{
    *exit_code = 2;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            parts_usage(stdout);
            *exit_code = 0;
            return false;
        } else if (!strcmp(a, "--depth")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, PART_MAX_COUNT, &o->max_depth))
                return false;
        } else if (!strcmp(a, "--match")) {
            if (!(o->pattern = cli_option_value(argc, argv, &i)))
                return false;
        } else if (!strcmp(a, "--json")) {
            o->json = true;
        } else if (a[0] == '-' && a[1] != '\0') {
            cli_error("unknown option '%s' (see 'tessera parts --help')", a);
            return false;
        } else if (!o->path) {
            o->path = a;
        } else {
            cli_error("parts takes one FILE; '%s' is a second (see 'tessera parts --help')", a);
            return false;
        }
    }
    if (!o->path) {
        cli_error("parts needs a FILE (see 'tessera parts --help')");
        return false;
    }
    return true;
}

static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

/* What printing a part needs besides the tree. */
typedef struct parts_print {
    const parts_options *o;
    const part_tree *tree;
    const uint64_t *subtree_triangles; /* per part */
    const int *depth;                  /* per part, 0 for the root */
    long printed;
} parts_print;

static bool print_part(void *ctx, int32_t id, const char *path)
{
    parts_print *p = ctx;
    int depth = p->depth[id];
    if (depth > p->o->max_depth)
        return true;
    const part_counts *pc = part_tree_counts_const(p->tree, id);
    if (p->o->json) {
        fputs(p->printed ? ",\n  {\"path\": " : "\n  {\"path\": ", stdout);
        json_string(stdout, path);
        printf(", \"depth\": %d, \"instances\": %" PRIu32 ", \"triangles\": %" PRIu64 ", \"subtree_triangles\": %" PRIu64
               "}",
               depth, pc->instances, pc->triangles, p->subtree_triangles[id]);
    } else {
        printf("%*s%s  instances=%" PRIu32 " triangles=%" PRIu64 " subtree_triangles=%" PRIu64 "\n", 2 * (depth - 1),
               "", path, pc->instances, pc->triangles, p->subtree_triangles[id]);
    }
    p->printed++;
    return true;
}

static bool print_tree(const parts_options *o, const parts_count *c, double load_s)
{
    const part_tree *t = c->tree;
    int32_t n = part_tree_count(t);
    uint64_t *subtree = malloc((size_t)n * sizeof *subtree);
    int *depth = malloc((size_t)n * sizeof *depth);
    if (!subtree || !depth) {
        free(subtree);
        free(depth);
        cli_error("%s: out of memory for %ld parts", o->path, (long)n);
        return false;
    }
    depth[PART_ROOT] = 0;
    for (int32_t id = 0; id < n; id++) {
        subtree[id] = part_tree_counts_const(t, id)->triangles;
        if (id != PART_ROOT)
            depth[id] = depth[part_tree_parent(t, id)] + 1;
    }
    for (int32_t id = n - 1; id > PART_ROOT; id--) /* preorder: descendants come after */
        subtree[part_tree_parent(t, id)] += subtree[id];
    if (o->json) {
        fputs("{\"file\": ", stdout);
        json_string(stdout, o->path);
        printf(", \"parts\": %ld, \"meshes\": %zu, \"materials\": %d, \"instances\": %" PRIu64
               ", \"triangles_stored\": %" PRIu64 ", \"triangles_instanced\": %" PRIu64 ", \"load_s\": %.6f,\n"
               " \"parts_list\": [",
               (long)n - 1, c->mesh_count, c->material_count, c->instances, c->triangles_stored,
               c->triangles_instanced, load_s);
    } else {
        printf("parts=%ld meshes=%zu materials=%d instances=%" PRIu64 " triangles_stored=%" PRIu64
               " triangles_instanced=%" PRIu64 " load_s=%.6f file=%s\n",
               (long)n - 1, c->mesh_count, c->material_count, c->instances, c->triangles_stored,
               c->triangles_instanced, load_s, o->path);
    }
    parts_print p = {.o = o, .tree = t, .subtree_triangles = subtree, .depth = depth};
    long matched = part_tree_match(t, o->pattern, print_part, &p);
    if (o->json)
        fputs(p.printed ? "\n ]}\n" : "]}\n", stdout);
    free(subtree);
    free(depth);
    if (matched < 0) {
        cli_error("%s: out of memory printing %ld parts", o->path, (long)n);
        return false;
    }
    return true;
}

/* A PLY without faces is a point set: no part tree (assimp would only say "Mesh contains no
 * faces"). False after saying so; true for any other file (a broken header too: the loader
 * then says what is wrong with it). */
static bool not_a_point_set(const char *path)
{
    size_t n = strlen(path);
    if (n < 4 || strcasecmp(path + n - 4, ".ply") != 0)
        return true;
    uint64_t vertices;
    int64_t faces;
    tess_error err = {{0}};
    if (!ply_probe_counts(path, &vertices, &faces, &err)) {
        cli_error("%s", err.msg);
        return false;
    }
    if (faces > 0)
        return true;
    if (vertices == 0)
        cli_error("%s: no geometry (0 vertices, %s): it has no parts", path, faces < 0 ? "no faces" : "0 faces");
    else
        cli_error("%s: a point set (%" PRIu64 " points, %s) has no parts: 'tessera render --scene %s' draws it as "
                  "particles",
                  path, vertices, faces < 0 ? "no faces" : "0 faces", path);
    return false;
}

int cli_parts(int argc, char **argv)
{
    parts_options o = {.max_depth = PART_MAX_COUNT, .pattern = "**"};
    int code;
    if (!parse_options(argc, argv, &o, &code))
        return code;
    if (!not_a_point_set(o.path))
        return 1;
    parts_count c = {.tree = part_tree_create()};
    if (!c.tree) {
        cli_error("out of memory");
        return 1;
    }
    assembly_sink sink = {.ctx = &c,
                          .material = count_material,
                          .mesh = count_mesh,
                          .part = count_part,
                          .instance = count_instance};
    tess_error err = {{0}};
    double t0 = cli_now_s();
    bool loaded = assembly_load(o.path, &sink, &err);
    double load_s = cli_now_s() - t0;
    if (!loaded) {
        if (tess_error_is_set(&c.err)) /* the sink's own reason, after the loader's */
            cli_error("%s (%s)", err.msg, c.err.msg);
        else
            cli_error("%s", err.msg);
    }
    bool ok = loaded && print_tree(&o, &c, load_s);
    part_tree_destroy(c.tree);
    free(c.mesh_triangles);
    if (ok && fflush(stdout) != 0) {
        cli_error("writing the output failed");
        ok = false;
    }
    return ok ? 0 : 1;
}
