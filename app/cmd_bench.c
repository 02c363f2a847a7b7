/* cmd_bench.c - `tessera bench`: ray throughput, build time and memory of one
 * scene, printed as one machine-readable BENCH line.
 *
 * The measurement follows the Embree peer harness (../shared/tools/peer) so
 * that the two compare run for run: the same camera rule for a bare mesh, the
 * same eyelight shade (|dot(Ng, dir)|, one shadow ray per hit with --shadows),
 * untimed warm-up frames first, and cpu_other, the CPU that other programs
 * took during the timed frames, so that a noisy run can be rejected. Unlike
 * the peer, which reports rays / total time, each timed frame is timed on its
 * own and the BENCH line gives medians over the frames. */
#include <errno.h>
#include <math.h>
#include <libgen.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

/* Under callgrind (tools/scaling_model.sh's cache model, --instr-atstart=no) the warm-up
 * frames are simulated but not counted, the timed frames counted, the rest (loading,
 * building) not simulated at all; natively the client requests are a few no-op
 * instructions, run three times per process outside the timed frames. */
#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#endif
#endif
#ifndef CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_START_INSTRUMENTATION ((void)0)
#define CALLGRIND_ZERO_STATS ((void)0)
#define CALLGRIND_STOP_INSTRUMENTATION ((void)0)
#endif

#include "cli.h"
#include "engine/scene/accel.h"
#include "engine/accel/kernels.h"
#include "engine/scene/frame_state.h"
#include "engine/geometry/triangles/mesh_cache.h"
#include "engine/scene/part_tree.h"
#include "engine/render/render.h"
#include "engine/render/render_ao.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "engine/frame/txn.h"
#include "wall/dump.h"
#include "engine/load/mesh_load.h"

/* Defaults: the size, frames and warm-up of the peer's 1920x1080 runs
 * (tools/bench.sh asks for more frames, see there). */
#define BENCH_DEFAULT_WIDTH_PX 1920
#define BENCH_DEFAULT_HEIGHT_PX 1080
#define BENCH_DEFAULT_FRAMES 5
#define BENCH_DEFAULT_WARMUP 1
/* --renderer ao: the Embree peer's workload (tools/bench_ao.sh, BENCHMARKS.md), not the renderer's
 * look defaults (render.h): 8 rays of 0.1 x the scene box's diagonal unless asked otherwise */
#define BENCH_AO_RAYS 8
#define BENCH_AO_DISTANCE_FRACTION 0.1f
#define BENCH_MAX_FRAMES 100000
#define BENCH_MAX_PART_TXNS 100000
/* --part-txns: the checks trace a grid of this many rays across the image */
#define BENCH_CHECK_COLS 160
#define BENCH_CHECK_ROWS 90

typedef struct bench_options {
    const char *scene_path; /* NULL: the built-in default scene */
    int width_px, height_px;
    int threads;            /* build and render threads */
    int frames;             /* timed frames, >= 1 */
    int warmup;             /* untimed frames rendered first, >= 0 */
    bool shadows;           /* one shadow ray per hit toward the scene's first light */
    bool single_rays;       /* every ray traced alone (accel_set_single_rays), not in packets */
    bool have_camera;       /* --camera given */
    camera_desc camera;
    const char *out;        /* image file for the last frame, or NULL */
    const char *isa;        /* kernels to use ("sse2", "avx2", "avx512"), or NULL: the engine's choice */
    bool flatten;           /* load the file as one mesh (mesh_load), not as an assembly */
    int part_txns;          /* > 0: time this many rounds of part transactions instead of frames */
    bool ao;                /* --renderer ao: the ambient-occlusion renderer instead of eyelight */
    render_settings settings; /* ao_rays, ao_distance, ao_interleave, ao_filter_px for --renderer ao */
    float opacity;          /* --opacity: every surface's opacity (1: opaque, the plain path) */
    int tile_px;            /* --tile-size: tile edge in pixels */
    bool spatial_splits;    /* --spatial-splits: meshes' trees with spatial splits (bvh_spatial.h) */
} bench_options;

/* One timed frame. */
typedef struct frame_sample {
    double seconds;         /* wall time of render_image alone */
    uint64_t primary_rays, shadow_rays;
    uint64_t primary_hits; /* primary rays that hit something */
    uint64_t secondary_rays; /* --opacity < 1: the layers traced past each ray's first surface */
    uint64_t ao_rays;        /* --renderer ao: its AO rays; its primary rays include the filter's apron
                                pixels traced again (render_ao.h) */
} frame_sample;

/* Memory of the process right after load + build, MiB (2^20 bytes); -1 when unknown. */
typedef struct memory_use {
    double peak_mb;        /* VmHWM: the high-water mark so far, i.e. of loading and building */
    double after_build_mb; /* VmRSS: resident then */
} memory_use;

static void bench_usage(FILE *f)
{
    fputs("usage: tessera bench [options]\n"
          "Measure ray throughput, BVH build time and memory of one scene and print one\n"
          "machine-readable line on stdout (key=value fields, described below). The scene is\n"
          "shaded as the Embree peer harness shades it (../shared/tools/peer, its --out-shade\n"
          "image): grey |dot(Ng, dir)| at hits, 0 at misses; with --shadows one shadow ray per\n"
          "hit toward the scene's first light (a mesh file's: direction 0.4,1,0.3), x 0.2 when\n"
          "occluded. Status lines (scene size, the camera in embree_bench's syntax) go to stderr.\n"
          "\n"
          "options:\n"
          "  --scene FILE     JSON scene or mesh file (.ply, .obj, ...); a mesh file (or a scene\n"
          "                   without a camera) is framed by the peer's rule, as 'tessera render'\n"
          "                   does; 'default' or no --scene: the built-in scene\n"
          "  --size WxH       image size in pixels (default 1920x1080)\n"
          "  --threads N      BVH build and render threads (default: the number of CPUs)\n"
          "  --frames N       timed frames, each timed on its own (default 5)\n"
          "  --warmup N       untimed frames rendered first (default 1)\n"
          "  --shadows        trace a shadow ray per hit (default: primary rays only)\n"
          "  --single-rays    trace every ray alone (the single-ray kernels from the root, as\n"
          "                   Embree's rtcIntersect1 / embree_bench -m single), not in packets:\n"
          "                   the same image, for timing the packet path against single rays\n"
          "  --spatial-splits build the meshes' trees with spatial splits (SBVH): a mesh file,\n"
          "                   --flatten's mesh, and JSON \"meshes\" entries without their own\n"
          "                   \"spatial_splits\" (default: off)\n"
          "  --opacity A      every surface's opacity, 0..1 (default 1): below 1 rays blend the\n"
          "                   surfaces they cross front to back (docs/inspection.md), with the\n"
          "                   default limits (transmittance 1/255, 16 layers)\n"
          "  --renderer NAME  eyelight (the default: the peer's shade) or ao: the ambient-occlusion\n"
          "                   renderer (engine/render/render_ao.h), the peer's --ao workload: per hit N\n"
          "                   cosine-distributed any-hit rays\n"
          "  --tile-size N    tile edge in pixels, 4..256, as the pipeline's (default 16)\n"
          "  --ao-rays N      AO rays per hit, 1..64 (default 8)\n"
          "  --ao-dist D      AO ray length in world units (default: 0.1 x the scene box's diagonal,\n"
          "                   as the peer's --ao-dist)\n"
          "  --ao-filter PX   discontinuity filter edge, odd 1..9 (default 5; 1 = off: the peer's\n"
          "                   workload exactly, no apron pixels traced twice)\n"
          "  --ao-interleave K  K x K direction sets, 1..8 (default 4)\n"
          "  --camera ex,ey,ez,lx,ly,lz,ux,uy,uz,fov\n"
          "                   eye, look-at point, up vector, vertical field of view in degrees\n"
          "  --isa NAME       traversal kernels: sse2, avx2 or avx512 (default: the best this CPU\n"
          "                   runs, or the environment's TESSERA_ISA)\n"
          "  --flatten        load the scene file's geometry as ONE mesh, node transforms baked in\n"
          "                   (mesh_load: assimp's PreTransformVertices), not as parts and instances:\n"
          "                   the same triangles as the assembly, traced without instancing\n"
          "  --part-txns N    instead of frames: N rounds of part transactions on the loaded scene and\n"
          "                   built accel (an assembly), each as a pipeline's serial section does it\n"
          "                   (txn_apply on a frame state, then frame_state_sync_accel, which commits):\n"
          "                   hide a section's subtree, isolate one bolt, show all, hide one part,\n"
          "                   show it again; prints one PARTTXN line (below) instead of BENCH\n"
          "  --path FILE, --scaling  the pipeline benchmarks: see 'tessera bench --scaling --help'\n"
          "  --wall FILE      frame time of a display wall, whole and output by output, per display\n"
          "                   kind: see 'tessera bench --wall --help'\n"
          "  --out FILE       write the last timed frame's image: .pfm is grey float written as\n"
          "                   embree_bench writes it, to compare value by value with its\n"
          "                   --out-shade image (or, with --shadows, its --out-lit image without\n"
          "                   --ao); any other extension goes through the dump backend (.exr:\n"
          "                   linear float RGB, .png: 8-bit sRGB)\n"
          "\n"
          "Loading and building a large scene report progress on stderr (a bar on a terminal,\n"
          "a line per 10 % otherwise; nothing for what takes under a second, nothing with\n"
          "TESSERA_LOG=warn); the result goes to stdout.\n"
          "\n"
          "output: one line, fields in this order:\n"
          "  BENCH scene=PATH size=WxH threads=N frames=N warmup=N shadows=0|1 isa=NAME single_rays=0|1\n"
          "        triangles=N spheres=N load_s= build_s= prim_mrays= total_mrays= frame_ms_median=\n"
          "        frame_ms_min= frame_ms_max= hit_rate= bytes_per_tri= mesh_bytes= accel_bytes=\n"
          "        cpu_other= hits= instances= geometries= triangles_instanced= bytes_per_instanced_tri=\n"
          "        renderer=NAME opacity= secondary_rays_frame= tile_px= points= point_bytes=\n"
          "        bytes_per_point= peak_rss_mb= rss_after_build_mb= cache= spatial_splits= references=\n"
          "        and, with --renderer ao, ao_rays=\n"
          "        ao_interleave= ao_filter= ao_dist=\n"
          "        ao_rays_frame= ao_mrays= primary_rays_frame=\n"
          "  scene            the --scene value ('default' for the built-in scene); whitespace and\n"
          "                   '%' in it are written as %XX so that fields split on spaces\n"
          "  isa              the instruction set of the traversal kernels that ran\n"
          "  triangles        triangles stored, over all meshes (a mesh placed many times counts\n"
          "                   once); spheres: spheres in the scene\n"
          "  load_s           seconds to load the scene file (or create the built-in scene)\n"
          "  build_s          seconds of accel_build with --threads threads (wall clock)\n"
          "  prim_mrays       median over the timed frames of (primary rays of the frame /\n"
          "                   seconds of the frame) / 1e6; primary rays = W x H per frame\n"
          "  total_mrays      the same for primary + shadow rays (= prim_mrays without --shadows)\n"
          "  frame_ms_*       median, fastest and slowest timed frame, milliseconds; a frame is\n"
          "                   one render_image call, from the call to its return\n"
          "  hit_rate         fraction of the last frame's primary rays that hit something\n"
          "  bytes_per_tri    (mesh_bytes + accel_bytes) / triangles (stored), 0 when there are none\n"
          "  mesh_bytes       sum of mesh_bytes() over the meshes: positions and indices, plus\n"
          "                   normals, colours and per-triangle materials when the mesh has them\n"
          "                   (counts, not capacities); spheres and the scene struct not counted\n"
          "  accel_bytes      accel_bytes(): the acceleration structure of every geometry and the\n"
          "                   top level (nodes, primitive blocks), not the scene\n"
          "  cpu_other        CPUs' worth of time other programs used during the timed frames:\n"
          "                   (busy CPU seconds of the machine from /proc/stat - this process's\n"
          "                   getrusage) / wall seconds, as embree_bench computes it; 0 = quiet,\n"
          "                   -1 = /proc/stat unreadable. Reject runs above ~0.05. /proc/stat counts in\n"
          "                   ticks (1/100 s), so the figure is only meaningful when the timed frames\n"
          "                   take about a second or more\n"
          "  hits             primary rays of the last frame that hit something\n"
          "  instances        instances in the scene (a mesh file: 1; parts placing a mesh: one each)\n"
          "  geometries       geometries stored (meshes, the sphere set)\n"
          "  triangles_instanced  triangles over all instances: what the picture holds\n"
          "  bytes_per_instanced_tri  (mesh_bytes + accel_bytes) / triangles_instanced\n"
          "  cache            the structure cache (docs/scenes.md, \"Structure cache\") over the meshes:\n"
          "                   hit (every cached mesh and its tree mapped from it), written (built,\n"
          "                   then written), failed (built; writing failed), unused (none cached)\n"
          "  spatial_splits   1 with --spatial-splits, else 0\n"
          "  references       triangles the meshes store: one per leaf holding a triangle, so\n"
          "                   more than `triangles` where spatial splits repeated some\n"
          "  renderer         eyelight or ao\n"
          "  opacity          --opacity's value (1: opaque)\n"
          "  secondary_rays_frame  rays of the last frame traced past their first surface (transparency)\n"
          "  points           particles (points of every particle set, each stored once)\n"
          "  point_bytes      their own data: positions and attributes (counts, not capacities)\n"
          "  bytes_per_point  (point_bytes + accel_bytes) / points, 0 when there are none: the\n"
          "                   whole cost of a particle when the scene holds particles only\n"
          "  peak_rss_mb      the process's peak resident memory (VmHWM, /proc/self/status) read right\n"
          "                   after load + build, before any frame: the memory high-water mark of\n"
          "                   loading and building, in MiB (2^20 bytes); -1 if unknown\n"
          "  rss_after_build_mb  resident memory at that moment (VmRSS), MiB; -1 if\n"
          "                   unknown. peak - after: what loading and building held only while working\n"
          "  ao_rays, ao_interleave, ao_filter  the AO settings used; ao_dist: the ray length used\n"
          "  ao_rays_frame    AO rays of the last frame (apron pixels included)\n"
          "  ao_mrays         median over the timed frames of (AO rays of the frame / seconds) / 1e6\n"
          "  primary_rays_frame  primary rays of the last frame: W x H plus the apron pixels traced\n"
          "                   again (with --ao-filter 1: W x H); prim_mrays and total_mrays count them\n"
          "--part-txns N prints instead, after the scene's status lines:\n"
          "  PARTTXN scene=PATH threads=N instances=N parts=N rounds=N check=ok|failed\n"
          "          section=PATH section_instances=N bolt=PATH bolt_instances=N part_instance=ID\n"
          "          section_hits=N then, per kind K of hide_section, isolate_bolt, show_all,\n"
          "          hide_part, show_part: K_us_median= K_us_max=\n"
          "  K_us_*           microseconds of txn_apply + frame_state_sync_accel for that record,\n"
          "                   median and slowest over the rounds\n"
          "  section          the part hidden: the middle one of the parts one level under the top\n"
          "                   (under the single top-level part, if there is only one)\n"
          "  bolt             the part isolated: the first named bolt-* with instances (else the\n"
          "                   last part with instances); part_instance: the instance hidden alone\n"
          "  section_hits     of a grid of 160x90 camera rays, those that hit the section before it\n"
          "                   is hidden; check=ok: after the hide none of them hits it, after the\n"
          "                   isolate every hit is on the bolt, after show-all every ray hits what it\n"
          "                   hit first (exit status 1 otherwise)\n"
          "Exit status: 0, or 2 for a command-line error, 1 for any other error (one line on stderr).\n",
          f);
}

static int online_cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 256 ? 256 : (int)n;
}

/* Returns false when the command should stop: after --help (*exit_code 0) or
 * a bad option (*exit_code 2). */
static bool parse_options(int argc, char **argv, bench_options *o, int *exit_code)
{
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            bench_usage(stdout);
            *exit_code = 0;
            return false;
        } else if (!strcmp(a, "--scene")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            o->scene_path = strcmp(val, "default") ? val : NULL;
        } else if (!strcmp(a, "--size")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_size(a, val, &o->width_px, &o->height_px))
                goto bad;
        } else if (!strcmp(a, "--threads")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 256, &o->threads))
                goto bad;
        } else if (!strcmp(a, "--tile-size")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 4, 256, &o->tile_px))
                goto bad;
        } else if (!strcmp(a, "--frames")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, BENCH_MAX_FRAMES, &o->frames))
                goto bad;
        } else if (!strcmp(a, "--warmup")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 0, BENCH_MAX_FRAMES, &o->warmup))
                goto bad;
        } else if (!strcmp(a, "--camera")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_camera(a, val, &o->camera))
                goto bad;
            o->have_camera = true;
        } else if (!strcmp(a, "--out")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            o->out = val;
        } else if (!strcmp(a, "--isa")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            if (strcmp(val, "sse2") && strcmp(val, "avx2") && strcmp(val, "avx512")) {
                cli_error("--isa: expected sse2, avx2 or avx512, got '%s'", val);
                goto bad;
            }
            o->isa = val;
        } else if (!strcmp(a, "--shadows")) {
            o->shadows = true;
        } else if (!strcmp(a, "--single-rays")) {
            o->single_rays = true;
        } else if (!strcmp(a, "--renderer")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            if (strcmp(val, "eyelight") && strcmp(val, "ao")) {
                cli_error("--renderer: expected eyelight or ao, got '%s'", val);
                goto bad;
            }
            o->ao = !strcmp(val, "ao");
        } else if (!strcmp(a, "--ao-rays")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 64, &o->settings.ao_rays))
                goto bad;
        } else if (!strcmp(a, "--ao-interleave")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 8, &o->settings.ao_interleave))
                goto bad;
        } else if (!strcmp(a, "--ao-filter")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 9, &o->settings.ao_filter_px))
                goto bad;
            if (o->settings.ao_filter_px % 2 == 0) {
                cli_error("--ao-filter: expected an odd edge 1..9, got %d", o->settings.ao_filter_px);
                goto bad;
            }
        } else if (!strcmp(a, "--ao-dist")) {
            double d;
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_double(a, val, 1e-30, 1e30, &d))
                goto bad;
            o->settings.ao_distance = (float)d;
        } else if (!strcmp(a, "--opacity")) {
            double op;
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_double(a, val, 0.0, 1.0, &op))
                goto bad;
            o->opacity = (float)op;
        } else if (!strcmp(a, "--flatten")) {
            o->flatten = true;
        } else if (!strcmp(a, "--spatial-splits")) {
            o->spatial_splits = true;
        } else if (!strcmp(a, "--part-txns")) {
            if (!(val = cli_option_value(argc, argv, &i)) ||
                !cli_parse_int(a, val, 1, BENCH_MAX_PART_TXNS, &o->part_txns))
                goto bad;
        } else {
            cli_error("unknown option '%s' (see 'tessera bench --help')", a);
            goto bad;
        }
    }
    if (o->ao && o->shadows) {
        cli_error("--shadows is for the eyelight renderer; --renderer ao traces AO rays only");
        goto bad;
    }
    if (o->flatten && !o->scene_path) {
        cli_error("--flatten needs --scene FILE (a mesh or assembly file)");
        goto bad;
    }
    return true;
bad:
    *exit_code = 2;
    return false;
}

/* Fail before the (long) run when the output directory is missing or read-only. */
static bool output_dir_ok(const char *path)
{
    char copy[4096];
    if (snprintf(copy, sizeof copy, "%s", path) >= (int)sizeof copy) {
        cli_error("--out: path too long: %.64s...", path);
        return false;
    }
    const char *dir = dirname(copy);
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        cli_error("%s: cannot write: '%s' is not an existing directory", path, dir);
        return false;
    }
    if (access(dir, W_OK) != 0) {
        cli_error("%s: cannot write: directory '%s' is not writable: %s", path, dir, strerror(errno));
        return false;
    }
    return true;
}

/* The scene path for a space-separated line: whitespace and '%' as %XX. */
static void print_field_path(FILE *f, const char *path)
{
    for (const unsigned char *p = (const unsigned char *)path; *p; p++) {
        if (*p <= ' ' || *p == '%' || *p == 0x7f)
            fprintf(f, "%%%02X", *p);
        else
            fputc(*p, f);
    }
}

static bool has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && !strcasecmp(s + n - k, suffix);
}

/* Write channel 0 of the image as a grey PFM the way embree_bench does (rows
 * bottom to top, native float order, scale sign giving the byte order), so
 * the two images compare value by value. */
static bool write_pfm_grey(const char *path, int width_px, int height_px, const float *rgb)
{
    const uint16_t probe = 1;
    bool little_endian = *(const uint8_t *)&probe == 1;
    FILE *f = fopen(path, "wb");
    if (!f) {
        cli_error("%s: cannot write: %s", path, strerror(errno));
        return false;
    }
    float *row = malloc((size_t)width_px * sizeof *row);
    bool have_row = row != NULL;
    bool ok = have_row && fprintf(f, "Pf\n%d %d\n%s\n", width_px, height_px, little_endian ? "-1.0" : "1.0") > 0;
    for (int y = height_px - 1; ok && y >= 0; y--) {
        const float *src = rgb + 3 * (size_t)y * (size_t)width_px;
        for (int x = 0; x < width_px; x++)
            row[x] = src[3 * x];
        ok = fwrite(row, sizeof *row, (size_t)width_px, f) == (size_t)width_px;
    }
    free(row);
    if (fclose(f) != 0)
        ok = false;
    if (!ok)
        cli_error("%s: cannot write: %s", path, have_row ? strerror(errno) : "out of memory");
    return ok;
}

/* --flatten: the file's geometry as one mesh (mesh_load bakes the node
 * transforms), in a scene made as scene_load makes one of a mesh file: the
 * default material and light. Timed and reported like cli_scene_prepare. */
static bool prepare_flat(const char *path, int threads, bool spatial_splits, cli_scene *cs)
{
    *cs = (cli_scene){.name = path};
    tess_error err = {{0}};
    double t0 = cli_now_s();
    mesh *m = mesh_load(path, &err);
    if (!m) {
        cli_error("%s", err.msg);
        return false;
    }
    if (m->triangle_count == 0) {
        mesh_destroy(m);
        cli_error("%s: --flatten: the file has no triangles", path);
        return false;
    }
    material mat = material_default();
    light sun = light_default_directional();
    cs->scene = scene_create();
    int mat_id = cs->scene ? scene_add_material(cs->scene, &mat) : -1;
    if (mat_id < 0)
        mesh_destroy(m); /* scene_add_mesh takes it, also on failure */
    if (mat_id < 0 || scene_add_mesh(cs->scene, m, (uint32_t)mat_id, "flattened") < 0 ||
        scene_add_light(cs->scene, &sun) < 0) {
        cli_error("%s: out of memory building the scene", path);
        return false;
    }
    cs->scene->meshes[0]->spatial_splits = spatial_splits;
    double t1 = cli_now_s();
    cs->accel = accel_build(cs->scene, threads, &err);
    if (!cs->accel) {
        cli_error("%s", err.msg);
        return false;
    }
    cs->load_s = t1 - t0;
    cs->build_s = cli_now_s() - t1;
    fprintf(stderr, "tessera: scene %s flattened: %zu triangles in one mesh; loaded in %.3f s, BVH built in %.3f s "
            "(%s kernels)\n", path, scene_triangle_count(cs->scene), cs->load_s, cs->build_s,
            accel_isa_name(cs->accel));
    return true;
}

/* Load the scene, build its accel (timed), switch kernels if asked, and
 * choose the camera as 'tessera render' does; print the camera in
 * embree_bench's syntax. On failure prints the error and returns false. */
static bool prepare(bench_options *o, cli_scene *cs)
{
    scene_load_options load = {.spatial_splits = o->spatial_splits};
    if (!(o->flatten ? prepare_flat(o->scene_path, o->threads, o->spatial_splits, cs)
                     : cli_scene_prepare_with(o->scene_path, &load, o->threads, cs)))
        return false;
    if (o->isa && !accel_use_isa(cs->accel, o->isa)) {
        char why[96];
        kernels_usable(kernels_isa_by_name(o->isa), why, sizeof why);
        cli_error("--isa %s: cannot use these kernels here: %s", o->isa, why);
        return false;
    }
    if (!cli_scene_camera(cs, o->have_camera ? &o->camera : NULL, o->width_px, o->height_px, &o->camera))
        return false;
    const camera_desc *c = &o->camera;
    fprintf(stderr, "tessera: camera --eye %g,%g,%g --lookat %g,%g,%g --up %g,%g,%g --fov %g\n", c->eye.x, c->eye.y,
            c->eye.z, c->look_at.x, c->look_at.y, c->look_at.z, c->up.x, c->up.y, c->up.z, c->fov_deg);
    return true;
}


/* One frame: the renderer's tiles of --tile-size pixels on --threads threads. */
static void render_frame(const bench_options *o, const render_view *view, float *rgb, render_counts *counts)
{
    const pixel_sampler single = pixel_sampler_single();
    render_image_tiles(renderer_by_name(o->ao ? "ao" : "eyelight"), view, &single, o->threads, o->tile_px, rgb,
                       counts);
}

/* Render the warm-up and timed frames; fills samples[0..frames) and
 * *cpu_other. The image of the last frame stays in rgb. */
static void measure(const bench_options *o, const render_view *view, float *rgb, frame_sample *samples,
                    double *cpu_other)
{
    CALLGRIND_START_INSTRUMENTATION;
    for (int f = 0; f < o->warmup; f++)
        render_frame(o, view, rgb, NULL);
    CALLGRIND_ZERO_STATS; /* the caches stay warm */
    double busy0 = cli_machine_busy_s(), own0 = cli_own_cpu_s(), wall0 = cli_now_s();
    for (int f = 0; f < o->frames; f++) {
        render_counts counts = {0};
        double t0 = cli_now_s();
        render_frame(o, view, rgb, &counts);
        samples[f].seconds = cli_now_s() - t0;
        samples[f].primary_rays = counts.primary_rays;
        samples[f].shadow_rays = counts.shadow_rays;
        samples[f].primary_hits = counts.primary_hits;
        samples[f].secondary_rays = counts.secondary_rays;
        samples[f].ao_rays = counts.ao_rays;
    }
    double busy1 = cli_machine_busy_s(), own1 = cli_own_cpu_s(), wall1 = cli_now_s();
    CALLGRIND_STOP_INSTRUMENTATION;
    if (busy0 < 0.0 || busy1 < 0.0 || !(wall1 > wall0))
        *cpu_other = -1.0;
    else {
        double other = ((busy1 - busy0) - (own1 - own0)) / (wall1 - wall0);
        *cpu_other = other > 0.0 ? other : 0.0;
    }
}

/* Read right after load + build, before anything is rendered: VmHWM and
 * VmRSS of one read of /proc/self/status (one snapshot of the kernel's
 * counters, so peak >= resident), else getrusage's ru_maxrss for the peak. */
static memory_use measure_memory(void)
{
    memory_use m = {-1.0, -1.0};
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    unsigned long kib;
    while (f && fgets(line, sizeof line, f)) {
        if (sscanf(line, "VmHWM: %lu kB", &kib) == 1)
            m.peak_mb = (double)kib / 1024.0;
        else if (sscanf(line, "VmRSS: %lu kB", &kib) == 1)
            m.after_build_mb = (double)kib / 1024.0;
    }
    if (f)
        fclose(f);
    struct rusage ru;
    if (m.peak_mb < 0.0 && getrusage(RUSAGE_SELF, &ru) == 0)
        m.peak_mb = (double)ru.ru_maxrss / 1024.0; /* Linux counts it in KiB */
    return m;
}

static void print_result(const bench_options *o, const render_view *view, double load_s, double build_s,
                         const memory_use *memory, const frame_sample *samples, double cpu_other, double *scratch)
{
    const scene *s = view->scene;
    const accel *a = view->accel;
    int n = o->frames;
    double prim_mrays, total_mrays, ms_median, ms_min = samples[0].seconds, ms_max = samples[0].seconds;
    for (int f = 0; f < n; f++) {
        double sec = samples[f].seconds > 0.0 ? samples[f].seconds : 1e-9;
        scratch[f] = 1e-6 * (double)samples[f].primary_rays / sec;
        ms_min = samples[f].seconds < ms_min ? samples[f].seconds : ms_min;
        ms_max = samples[f].seconds > ms_max ? samples[f].seconds : ms_max;
    }
    prim_mrays = cli_median(scratch, (size_t)n);
    for (int f = 0; f < n; f++) {
        double sec = samples[f].seconds > 0.0 ? samples[f].seconds : 1e-9;
        scratch[f] = 1e-6 * (double)(samples[f].primary_rays + samples[f].shadow_rays + samples[f].ao_rays) / sec;
    }
    total_mrays = cli_median(scratch, (size_t)n);
    for (int f = 0; f < n; f++)
        scratch[f] = samples[f].seconds;
    ms_median = cli_median(scratch, (size_t)n);

    const frame_sample *last = &samples[n - 1];
    double hit_rate = last->primary_rays ? (double)last->primary_hits / (double)last->primary_rays : 0.0;

    size_t triangles = scene_triangle_count(s), mesh_total = 0, accel_total = accel_bytes(a);
    for (uint32_t i = 0; i < s->mesh_count; i++)
        mesh_total += mesh_bytes(s->meshes[i]->mesh);
    double bytes_per_tri = triangles ? (double)(mesh_total + accel_total) / (double)triangles : 0.0;

    printf("BENCH scene=");
    print_field_path(stdout, o->scene_path ? o->scene_path : "default");
    printf(" size=%dx%d threads=%d frames=%d warmup=%d shadows=%d isa=%s single_rays=%d", o->width_px, o->height_px,
           o->threads, o->frames, o->warmup, o->shadows ? 1 : 0, accel_isa_name(a), o->single_rays ? 1 : 0);
    printf(" triangles=%zu spheres=%u load_s=%.3f build_s=%.3f", triangles, s->spheres.count, load_s, build_s);
    printf(" prim_mrays=%.3f total_mrays=%.3f frame_ms_median=%.2f frame_ms_min=%.2f frame_ms_max=%.2f", prim_mrays,
           total_mrays, 1e3 * ms_median, 1e3 * ms_min, 1e3 * ms_max);
    size_t instanced = scene_instanced_triangle_count(s);
    double bytes_per_instanced = instanced ? (double)(mesh_total + accel_total) / (double)instanced : 0.0;
    printf(" hit_rate=%.4f bytes_per_tri=%.1f mesh_bytes=%zu accel_bytes=%zu cpu_other=%.3f",
           hit_rate, bytes_per_tri, mesh_total, accel_total, cpu_other);
    printf(" hits=%llu instances=%u geometries=%u triangles_instanced=%zu bytes_per_instanced_tri=%.2f",
           (unsigned long long)last->primary_hits, s->instance_count, s->geometry_count, instanced,
           bytes_per_instanced);
    printf(" renderer=%s opacity=%g secondary_rays_frame=%llu tile_px=%d", o->ao ? "ao" : "eyelight",
           (double)o->opacity, (unsigned long long)last->secondary_rays, o->tile_px);
    size_t points = scene_point_count(s), point_bytes = scene_point_bytes(s);
    printf(" points=%zu point_bytes=%zu bytes_per_point=%.2f", points, point_bytes,
           points ? (double)(point_bytes + accel_total) / (double)points : 0.0);
    printf(" peak_rss_mb=%.1f rss_after_build_mb=%.1f", memory->peak_mb, memory->after_build_mb);
    unsigned by_state[MESH_CACHE_FAILED + 1] = {0};
    for (uint32_t i = 0; i < s->mesh_count; i++)
        if (s->meshes[i]->cache_state >= 0 && s->meshes[i]->cache_state <= MESH_CACHE_FAILED)
            by_state[s->meshes[i]->cache_state]++;
    printf(" cache=%s", by_state[MESH_CACHE_FAILED]    ? "failed"
                        : by_state[MESH_CACHE_WRITTEN] ? "written"
                        : by_state[MESH_CACHE_HIT]     ? "hit"
                                                       : "unused");
    size_t references = 0;
    for (uint32_t i = 0; i < s->mesh_count; i++)
        references += s->meshes[i]->mesh->triangle_count;
    printf(" spatial_splits=%d references=%zu", o->spatial_splits ? 1 : 0, references);
    if (o->ao) {
        for (int f = 0; f < n; f++) {
            double sec = samples[f].seconds > 0.0 ? samples[f].seconds : 1e-9;
            scratch[f] = 1e-6 * (double)samples[f].ao_rays / sec;
        }
        printf(" ao_rays=%d ao_interleave=%d ao_filter=%d ao_dist=%g ao_rays_frame=%llu ao_mrays=%.3f"
               " primary_rays_frame=%llu", o->settings.ao_rays, o->settings.ao_interleave, o->settings.ao_filter_px,
               (double)render_ao_distance(view), (unsigned long long)last->ao_rays,
               cli_median(scratch, (size_t)n), (unsigned long long)last->primary_rays);
    }
    printf("\n");
    fflush(stdout);
}

/* ---- --part-txns ---------------------------------------------------------- */

enum { PT_HIDE_SECTION, PT_ISOLATE_BOLT, PT_SHOW_ALL, PT_HIDE_PART, PT_SHOW_PART, PT_KINDS };
static const char *const part_txn_names[PT_KINDS] = {"hide_section", "isolate_bolt", "show_all", "hide_part",
                                                      "show_part"};

typedef struct part_pick {
    int32_t section, bolt;
    uint32_t section_first, section_end, bolt_first, bolt_end, part_instance;
} part_pick;

typedef struct bolt_search {
    const scene *s;
    int32_t found;
} bolt_search;

static bool find_bolt(void *ctx, int32_t id, const char *path)
{
    (void)path;
    bolt_search *b = ctx;
    uint32_t first, end;
    scene_part_instances(b->s, (uint32_t)id, &first, &end);
    if (end > first) {
        b->found = id;
        return false;
    }
    return true;
}

/* The parts the transactions act on (see the usage); false when the scene
 * has no parts with instances. */
static bool pick_parts(const scene *s, part_pick *p)
{
    const part_tree *t = s->parts;
    if (!t || s->instance_count == 0)
        return false;
    int32_t count = part_tree_count(t), top_level = 0;
    for (int32_t id = 1; id < count; id++)
        top_level += part_tree_parent(t, id) == 0;
    int level = top_level == 1 ? 2 : 1, sections = 0;
    for (int32_t id = 1; id < count; id++)
        sections += part_tree_depth(t, id) == level;
    if (sections == 0) {
        level = 1;
        sections = top_level;
    }
    p->section = -1;
    for (int32_t id = 1, k = 0; id < count && p->section < 0; id++)
        if (part_tree_depth(t, id) == level && k++ == sections / 2)
            p->section = id;
    bolt_search b = {s, -1};
    if (part_tree_match(t, "**/bolt-*", find_bolt, &b) < 0)
        return false;
    for (int32_t id = count - 1; b.found < 0 && id > 0; id--)
        find_bolt(&b, id, NULL);
    if (p->section < 0 || b.found < 0)
        return false;
    p->bolt = b.found;
    scene_part_instances(s, (uint32_t)p->section, &p->section_first, &p->section_end);
    scene_part_instances(s, (uint32_t)p->bolt, &p->bolt_first, &p->bolt_end);
    p->part_instance = s->instance_count / 2;
    return p->section_end > p->section_first && p->bolt_end > p->bolt_first;
}

/* Trace the check grid: the instance each ray hits (RAY_INVALID_ID: none). */
static void trace_grid(const accel *a, const camera_basis *b, uint32_t *ids)
{
    for (int y = 0; y < BENCH_CHECK_ROWS; y++)
        for (int x = 0; x < BENCH_CHECK_COLS; x++) {
            int px = (int)(((long)x * b->width_px + b->width_px / 2) / BENCH_CHECK_COLS);
            int py = (int)(((long)y * b->height_px + b->height_px / 2) / BENCH_CHECK_ROWS);
            ray r = {b->eye, camera_pixel_direction(b, px, py), 0.f, INFINITY};
            hit h = hit_none();
            accel_intersect(a, &r, &h);
            ids[y * BENCH_CHECK_COLS + x] = h.geom_id;
        }
}

/* One record at the barrier: txn_apply + frame_state_sync_accel (which
 * commits); returns microseconds, or -1 when txn_apply refused it. */
static double timed_txn(const txn_record *r, frame_state *st, const accel *a)
{
    tess_error err = {{0}};
    double t0 = cli_now_s();
    if (!txn_apply(r, st, &err)) {
        cli_error("--part-txns: %s: %s", txn_kind_name(r->kind), err.msg);
        return -1.0;
    }
    frame_state_sync_accel(st, a);
    return 1e6 * (cli_now_s() - t0);
}

static int run_part_txns(const bench_options *o, const cli_scene *cs)
{
    const scene *s = cs->scene;
    const accel *a = cs->accel;
    part_pick p;
    if (!pick_parts(s, &p)) {
        cli_error("%s: --part-txns needs an assembly with parts that have instances", cs->name);
        return 1;
    }
    size_t grid = (size_t)BENCH_CHECK_COLS * BENCH_CHECK_ROWS;
    uint32_t *before = malloc(grid * sizeof *before), *now = malloc(grid * sizeof *now);
    double *us = malloc((size_t)PT_KINDS * (size_t)o->part_txns * sizeof *us);
    double *scratch = malloc((size_t)o->part_txns * sizeof *scratch);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, o->threads, accel_geometry_count(a));
    int code = 1;
    if (!before || !now || !us || !scratch) {
        cli_error("out of memory for %d rounds", o->part_txns);
        goto done;
    }
    camera_basis basis = camera_basis_make(&o->camera, o->width_px, o->height_px);
    trace_grid(a, &basis, before);
    uint32_t section_hits = 0;
    bool ok = true;
    for (size_t i = 0; i < grid; i++)
        section_hits += before[i] >= p.section_first && before[i] < p.section_end;
    txn_record recs[PT_KINDS] = {
        txn_geoms_record(TXN_HIDE, p.section_first, p.section_end - p.section_first),
        txn_geoms_record(TXN_ISOLATE, p.bolt_first, p.bolt_end - p.bolt_first),
        txn_simple(TXN_SHOW_ALL),
        txn_geoms_record(TXN_HIDE, p.part_instance, 1),
        txn_geoms_record(TXN_SHOW, p.part_instance, 1),
    };
    for (int round = 0; round < o->part_txns; round++)
        for (int k = 0; k < PT_KINDS; k++) {
            double t = timed_txn(&recs[k], &st, a);
            if (t < 0.0)
                goto done;
            us[(size_t)k * (size_t)o->part_txns + (size_t)round] = t;
            if (round > 0 || k == PT_HIDE_PART)
                continue;
            /* first round: what the picture shows now (outside the timing) */
            trace_grid(a, &basis, now);
            for (size_t i = 0; i < grid; i++) {
                uint32_t id = now[i];
                if (k == PT_HIDE_SECTION)
                    ok &= !(id >= p.section_first && id < p.section_end) && (id == RAY_INVALID_ID || !accel_hidden(a, id));
                else if (k == PT_ISOLATE_BOLT)
                    ok &= id == RAY_INVALID_ID || (id >= p.bolt_first && id < p.bolt_end);
                else
                    ok &= id == before[i];
            }
        }
    char section_path[512], bolt_path[512];
    part_tree_path(s->parts, p.section, section_path, sizeof section_path);
    part_tree_path(s->parts, p.bolt, bolt_path, sizeof bolt_path);
    printf("PARTTXN scene=");
    print_field_path(stdout, o->scene_path ? o->scene_path : "default");
    printf(" threads=%d instances=%u parts=%d rounds=%d check=%s section=", o->threads, s->instance_count,
           (int)part_tree_count(s->parts) - 1, o->part_txns, ok ? "ok" : "failed");
    print_field_path(stdout, section_path);
    printf(" section_instances=%u bolt=", p.section_end - p.section_first);
    print_field_path(stdout, bolt_path);
    printf(" bolt_instances=%u part_instance=%u section_hits=%u", p.bolt_end - p.bolt_first, p.part_instance,
           section_hits);
    for (int k = 0; k < PT_KINDS; k++) {
        const double *v = us + (size_t)k * (size_t)o->part_txns;
        double max = v[0];
        for (int r = 0; r < o->part_txns; r++) {
            scratch[r] = v[r];
            max = v[r] > max ? v[r] : max;
        }
        printf(" %s_us_median=%.1f %s_us_max=%.1f", part_txn_names[k], cli_median(scratch, (size_t)o->part_txns),
               part_txn_names[k], max);
    }
    printf("\n");
    fflush(stdout);
    if (!ok)
        cli_error("%s: --part-txns: a hide, isolate or show-all did not change the picture as it should", cs->name);
    code = ok ? 0 : 1;
done:
    frame_state_finish(&st);
    free(scratch);
    free(us);
    free(now);
    free(before);
    return code;
}

int cli_bench(int argc, char **argv)
{
    /* the pipeline benchmarks have their own options (cmd_bench_path.c) */
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--path") || !strcmp(argv[i], "--scaling"))
            return cli_bench_path(argc, argv);
    for (int i = 1; i < argc; i++) /* (so --wall with --path / --scaling stays theirs) */
        if (!strcmp(argv[i], "--wall"))
            return cli_bench_wall(argc, argv);
    bench_options o = {.width_px = BENCH_DEFAULT_WIDTH_PX, .height_px = BENCH_DEFAULT_HEIGHT_PX,
                       .threads = online_cpus(), .frames = BENCH_DEFAULT_FRAMES, .warmup = BENCH_DEFAULT_WARMUP,
                       .settings = render_settings_default(), .opacity = 1.f, .tile_px = RENDER_TILE_PX};
    o.settings.ao_rays = BENCH_AO_RAYS;
    int code = 0;
    if (!parse_options(argc, argv, &o, &code))
        return code;
    if (o.out && !output_dir_ok(o.out))
        return 1;

    cli_scene cs = {0};
    float *rgb = NULL;
    frame_sample *samples = NULL;
    double *scratch = NULL;
    double cpu_other = -1.0;
    code = 1;
    if (!prepare(&o, &cs))
        goto done;
    memory_use memory = measure_memory();
    if (o.part_txns > 0) {
        code = run_part_txns(&o, &cs);
        goto done;
    }
    size_t pixels = (size_t)o.width_px * (size_t)o.height_px;
    rgb = malloc(pixels * 3 * sizeof *rgb);
    samples = calloc((size_t)o.frames, sizeof *samples);
    scratch = calloc((size_t)o.frames, sizeof *scratch);
    if (!rgb || !samples || !scratch) {
        cli_error("out of memory for a %dx%d image and %d frames", o.width_px, o.height_px, o.frames);
        goto done;
    }
    accel_set_single_rays(cs.accel, o.single_rays);
    if (o.ao && o.settings.ao_distance <= 0.f) { /* the peer's length, not the renderer's default */
        vec3 lo, hi;
        if (accel_scene_bounds(cs.accel, &lo, &hi))
            o.settings.ao_distance = BENCH_AO_DISTANCE_FRACTION * v3_length(v3_sub(hi, lo));
    }
    render_view view = {cs.scene, cs.accel, camera_basis_make(&o.camera, o.width_px, o.height_px), o.shadows,
                        RENDER_SHADE_EYELIGHT, NULL, &o.settings};
    frame_state opacity_state;
    bool have_state = o.opacity < 1.f;
    if (have_state) { /* the frame state the pipeline would hold after an `opacity all A` */
        frame_state_init(&opacity_state, renderer_by_name("eyelight"), o.shadows, o.threads,
                         accel_geometry_count(cs.accel));
        frame_state_set_global_opacity(&opacity_state, o.opacity);
        view.state = &opacity_state;
    }
    measure(&o, &view, rgb, samples, &cpu_other);
    print_result(&o, &view, cs.load_s, cs.build_s, &memory, samples, cpu_other, scratch);
    if (have_state)
        frame_state_finish(&opacity_state);
    if (o.out) {
        tess_error err = {{0}};
        if (has_suffix(o.out, ".pfm")) {
            if (!write_pfm_grey(o.out, o.width_px, o.height_px, rgb))
                goto done;
        } else if (!dump_write_rgb(o.out, o.width_px, o.height_px, rgb, &err)) {
            cli_error("%s", err.msg);
            goto done;
        }
        fprintf(stderr, "tessera: wrote %s\n", o.out);
    }
    code = 0;
done:
    free(scratch);
    free(samples);
    free(rgb);
    cli_scene_finish(&cs);
    return code;
}
