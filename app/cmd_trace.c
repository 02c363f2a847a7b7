/* cmd_trace.c - `tessera trace`: trace rays read from a binary file through a
 * scene and write, per ray, its closest hit or whether it is occluded.
 *
 * For users (batch queries, other tools' rays) and for tests, which compare
 * the engine against references through files. Formats (all little-endian,
 * read and written byte by byte, so the host's byte order never matters):
 *   RAYS:  32 bytes per ray: float32 ox oy oz dx dy dz t_near t_far
 *   HITS:  20 bytes per ray: float32 t (+inf on a miss), uint32 prim_id,
 *          uint32 geom_id (both 0xFFFFFFFF on a miss), float32 u, v
 *   HITS with --occluded: 1 byte per ray, 1 occluded, 0 not.
 * Rays stream through in chunks; each chunk's packets of 64 are shared among
 * the threads, and every result lands at its ray's index, so the output is
 * the same for any thread count. */
#include <errno.h>
#include <libgen.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "engine/scene/accel.h"
#include "engine/accel/packet.h"
#include "engine/scene/scene.h"

#define TRACE_RAY_BYTES 32u /* 8 float32 */
#define TRACE_HIT_BYTES 20u /* t, prim_id, geom_id, u, v */
#define TRACE_OCCLUDED_BYTES 1u
/* Rays read, traced and written at a time: 2 MiB of input, so memory stays
 * small for any file while each chunk still has work for many threads. */
#define TRACE_CHUNK_RAYS (1u << 16)
/* Most threads accepted (as for render). */
#define TRACE_MAX_THREADS 256

typedef struct trace_options {
    const char *scene_path; /* NULL: the built-in default scene */
    bool scene_given;
    const char *rays_path;
    const char *hits_path;
    bool occluded;          /* any-hit query, 1 byte per ray */
    int threads;
} trace_options;

/* One chunk of rays, shared by the threads that trace it. */
typedef struct trace_chunk {
    const accel *accel;
    const unsigned char *in; /* rays * TRACE_RAY_BYTES */
    unsigned char *out;      /* rays * (TRACE_HIT_BYTES or TRACE_OCCLUDED_BYTES) */
    size_t rays;
    bool occluded;
    atomic_size_t next_packet;   /* next packet index to claim */
    atomic_uint_fast64_t hits;   /* rays that hit (or are occluded), added once per thread */
} trace_chunk;

static uint32_t load_u32_le(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float load_f32_le(const unsigned char *b)
{
    uint32_t bits = load_u32_le(b);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

static void store_u32_le(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)v;
    b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16);
    b[3] = (unsigned char)(v >> 24);
}

static void store_f32_le(unsigned char *b, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    store_u32_le(b, bits);
}

/* Trace rays [first, first + n) of the chunk as one packet. Returns the hits. */
static uint64_t trace_packet(const trace_chunk *c, ray_packet *p, size_t first, uint32_t n)
{
    packet_reset(p, n, 0);
    for (uint32_t i = 0; i < n; i++) {
        const unsigned char *rec = c->in + (first + i) * TRACE_RAY_BYTES;
        p->org_x[i] = load_f32_le(rec + 0);
        p->org_y[i] = load_f32_le(rec + 4);
        p->org_z[i] = load_f32_le(rec + 8);
        p->dir_x[i] = load_f32_le(rec + 12);
        p->dir_y[i] = load_f32_le(rec + 16);
        p->dir_z[i] = load_f32_le(rec + 20);
        p->t_near[i] = load_f32_le(rec + 24);
        p->t_far[i] = load_f32_le(rec + 28);
    }
    packet_detect_facts(p);
    uint64_t hits = 0;
    if (c->occluded) {
        uint64_t mask = accel_occluded_packet(c->accel, packet_whole(p));
        for (uint32_t i = 0; i < n; i++) {
            unsigned char occluded = (unsigned char)(mask >> i & 1u);
            c->out[first + i] = occluded;
            hits += occluded;
        }
        return hits;
    }
    accel_intersect_packet(c->accel, packet_whole(p));
    for (uint32_t i = 0; i < n; i++) {
        unsigned char *rec = c->out + (first + i) * TRACE_HIT_BYTES;
        store_f32_le(rec + 0, p->hit_t[i]);
        store_u32_le(rec + 4, p->prim_id[i]);
        store_u32_le(rec + 8, p->geom_id[i]);
        store_f32_le(rec + 12, p->hit_u[i]);
        store_f32_le(rec + 16, p->hit_v[i]);
        hits += p->prim_id[i] != RAY_INVALID_ID;
    }
    return hits;
}

/* Claim and trace packets of the chunk until none is left. Returns NULL, or
 * non-NULL when there was no memory for its packet (it then traced nothing). */
static void *trace_worker(void *arg)
{
    trace_chunk *c = arg;
    ray_packet *p = aligned_alloc(64, sizeof *p);
    if (!p)
        return arg;
    uint64_t hits = 0;
    size_t packets = (c->rays + PACKET_MAX_RAYS - 1) / PACKET_MAX_RAYS;
    for (;;) {
        size_t k = atomic_fetch_add_explicit(&c->next_packet, 1, memory_order_relaxed);
        if (k >= packets)
            break;
        size_t first = k * PACKET_MAX_RAYS;
        size_t left = c->rays - first;
        hits += trace_packet(c, p, first, left < PACKET_MAX_RAYS ? (uint32_t)left : PACKET_MAX_RAYS);
    }
    free(p);
    atomic_fetch_add_explicit(&c->hits, hits, memory_order_relaxed);
    return NULL;
}

/* Trace one chunk on `threads` threads (the caller's included). False only when
 * not even the calling thread could get its packet memory. */
static bool trace_chunk_run(trace_chunk *c, int threads)
{
    pthread_t ids[TRACE_MAX_THREADS];
    int started = 0;
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&ids[started], NULL, trace_worker, c) != 0)
            break; /* the threads that did start finish the chunk */
        started++;
    }
    /* a thread without packet memory claims nothing, so once the caller's own
     * worker has run, every packet of the chunk is traced */
    bool ok = trace_worker(c) == NULL;
    for (int i = 0; i < started; i++)
        pthread_join(ids[i], NULL);
    return ok;
}

static void trace_usage(FILE *f)
{
    fputs("usage: tessera trace --scene FILE --rays RAYS --hits HITS [--occluded] [--threads N]\n"
          "Trace the rays of a binary file through a scene and write what each one hits.\n"
          "  --scene FILE     JSON scene, or a mesh file (.ply, .obj, ...); 'default': the built-in scene\n"
          "  --rays RAYS      input, 32 bytes per ray: 8 little-endian float32\n"
          "                     ox oy oz dx dy dz t_near t_far\n"
          "                   a hit counts for t_near < t <= t_far, t in units of |d| (d need not be\n"
          "                   unit); a ray with a NaN or infinite coordinate, a zero direction, a NaN\n"
          "                   bound or t_near >= t_far simply misses\n"
          "  --hits HITS      output, one record per ray in the order of RAYS, little-endian:\n"
          "                     20 bytes: float32 t (+inf on a miss), uint32 prim_id, uint32 geom_id\n"
          "                     (both 0xFFFFFFFF on a miss), float32 u, v\n"
          "                   geom_id: the scene's meshes in order from 0, then the sphere set;\n"
          "                   prim_id: the triangle (or sphere) index within it (a mesh in its tree's\n"
          "                   order, not the file's); u, v: weights of the triangle's 2nd and 3rd\n"
          "                   vertex (0 for spheres and misses)\n"
          "  --occluded       any-hit query instead: HITS gets 1 byte per ray, 1 if anything is hit\n"
          "                   in (t_near, t_far], else 0\n"
          "  --threads N      tracing threads (default: the number of CPUs); the output is the same\n"
          "                   for any N\n",
          f);
}

static int default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > TRACE_MAX_THREADS ? TRACE_MAX_THREADS : (int)n;
}

/* Parse the options. Returns false when the command should stop: after
 * --help (*exit_code 0) or a bad or missing option (*exit_code 2). */
static bool parse_options(int argc, char **argv, trace_options *o, int *exit_code)
{
    *exit_code = 2;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            trace_usage(stdout);
            *exit_code = 0;
            return false;
        } else if (!strcmp(a, "--scene")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                return false;
            o->scene_path = strcmp(val, "default") ? val : NULL;
            o->scene_given = true;
        } else if (!strcmp(a, "--rays")) {
            if (!(o->rays_path = cli_option_value(argc, argv, &i)))
                return false;
        } else if (!strcmp(a, "--hits")) {
            if (!(o->hits_path = cli_option_value(argc, argv, &i)))
                return false;
        } else if (!strcmp(a, "--occluded")) {
            o->occluded = true;
        } else if (!strcmp(a, "--threads")) {
            if (!(val = cli_option_value(argc, argv, &i)) ||
                !cli_parse_int(a, val, 1, TRACE_MAX_THREADS, &o->threads))
                return false;
        } else {
            cli_error("unknown option '%s' (see 'tessera trace --help')", a);
            return false;
        }
    }
    const char *missing = !o->scene_given ? "--scene FILE"
                          : !o->rays_path ? "--rays RAYS"
                          : !o->hits_path ? "--hits HITS"
                                          : NULL;
    if (missing) {
        cli_error("trace needs %s (see 'tessera trace --help')", missing);
        return false;
    }
    return true;
}

/* Fail before the (slow) scene load when HITS cannot be written: a directory,
 * a read-only file, or a directory that is missing or read-only. */
static bool check_hits_path(const char *path)
{
    struct stat st;
    if (stat(path, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            cli_error("%s: cannot write hits: it is a directory", path);
            return false;
        }
        if (access(path, W_OK) != 0) {
            cli_error("%s: cannot write hits: %s", path, strerror(errno));
            return false;
        }
        return true;
    }
    char copy[4096];
    snprintf(copy, sizeof copy, "%s", path);
    const char *dir = dirname(copy);
    if (stat(dir, &st) != 0) {
        cli_error("%s: cannot write hits: directory '%s' does not exist", path, dir);
        return false;
    }
    if (!S_ISDIR(st.st_mode)) {
        cli_error("%s: cannot write hits: '%s' is not a directory", path, dir);
        return false;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        cli_error("%s: cannot write hits: directory '%s' is not writable: %s", path, dir, strerror(errno));
        return false;
    }
    return true;
}

/* Open RAYS and check its size (for a regular file; a pipe is checked as it
 * is read). */
static FILE *open_rays(const trace_options *o, struct stat *st)
{
    FILE *f = fopen(o->rays_path, "rb");
    if (!f) {
        cli_error("%s: cannot read rays: %s", o->rays_path, strerror(errno));
        return NULL;
    }
    if (fstat(fileno(f), st) != 0) {
        cli_error("%s: cannot read rays: %s", o->rays_path, strerror(errno));
        fclose(f);
        return NULL;
    }
    if (S_ISDIR(st->st_mode)) {
        cli_error("%s: cannot read rays: it is a directory", o->rays_path);
        fclose(f);
        return NULL;
    }
    if (S_ISREG(st->st_mode) && st->st_size % TRACE_RAY_BYTES != 0) {
        cli_error("%s: %lld bytes is not a whole number of %u-byte ray records", o->rays_path,
                  (long long)st->st_size, TRACE_RAY_BYTES);
        fclose(f);
        return NULL;
    }
    return f;
}

/* Read up to `max` bytes, retrying short reads; returns the bytes read, or
 * (size_t)-1 on a read error. */
static size_t read_fully(FILE *f, unsigned char *buf, size_t max)
{
    size_t got = 0;
    while (got < max) {
        size_t n = fread(buf + got, 1, max - got, f);
        if (n == 0)
            return ferror(f) ? (size_t)-1 : got;
        got += n;
    }
    return got;
}

/* Stream RAYS through the accel into HITS. Returns the exit code; counts the
 * rays and their hits. */
static int trace_stream(const trace_options *o, const accel *a, FILE *rays, FILE *hits, uint64_t *ray_count,
                        uint64_t *hit_count)
{
    size_t out_bytes = o->occluded ? TRACE_OCCLUDED_BYTES : TRACE_HIT_BYTES;
    unsigned char *in = malloc((size_t)TRACE_CHUNK_RAYS * TRACE_RAY_BYTES);
    unsigned char *out = malloc((size_t)TRACE_CHUNK_RAYS * out_bytes);
    int code = 1;
    if (!in || !out) {
        cli_error("out of memory for the ray buffers");
        goto done;
    }
    uint64_t bytes_total = 0;
    for (;;) {
        size_t got = read_fully(rays, in, (size_t)TRACE_CHUNK_RAYS * TRACE_RAY_BYTES);
        if (got == (size_t)-1) {
            cli_error("%s: read error after %llu bytes: %s", o->rays_path, (unsigned long long)bytes_total,
                      strerror(errno));
            goto done;
        }
        bytes_total += got;
        if (got % TRACE_RAY_BYTES != 0) { /* a pipe, or a file that changed while read */
            cli_error("%s: %llu bytes is not a whole number of %u-byte ray records", o->rays_path,
                      (unsigned long long)bytes_total, TRACE_RAY_BYTES);
            goto done;
        }
        if (got == 0)
            break;
        trace_chunk c = {.accel = a, .in = in, .out = out, .rays = got / TRACE_RAY_BYTES, .occluded = o->occluded};
        atomic_init(&c.next_packet, 0);
        atomic_init(&c.hits, 0);
        if (!trace_chunk_run(&c, o->threads)) {
            cli_error("out of memory for a ray packet");
            goto done;
        }
        *ray_count += c.rays;
        *hit_count += atomic_load(&c.hits);
        if (fwrite(out, out_bytes, c.rays, hits) != c.rays) {
            cli_error("%s: cannot write hits: %s", o->hits_path, strerror(errno));
            goto done;
        }
        if (got < (size_t)TRACE_CHUNK_RAYS * TRACE_RAY_BYTES)
            break; /* end of file */
    }
    code = 0;
done:
    free(in);
    free(out);
    return code;
}

int cli_trace(int argc, char **argv)
{
    trace_options o = {.threads = default_threads()};
    int code;
    if (!parse_options(argc, argv, &o, &code))
        return code;
    struct stat rays_st, hits_st;
    FILE *rays = open_rays(&o, &rays_st);
    if (!rays)
        return 1;
    if (stat(o.hits_path, &hits_st) == 0 && hits_st.st_dev == rays_st.st_dev && hits_st.st_ino == rays_st.st_ino) {
        cli_error("%s: HITS is the same file as RAYS; it would overwrite the rays", o.hits_path);
        fclose(rays);
        return 1;
    }
    if (!check_hits_path(o.hits_path)) {
        fclose(rays);
        return 1;
    }
    cli_scene cs;
    if (!cli_scene_prepare(o.scene_path, o.threads, &cs)) {
        cli_scene_finish(&cs);
        fclose(rays);
        return 1;
    }
    accel *a = cs.accel;
    double t1 = cli_now_s();
    uint64_t ray_count = 0, hit_count = 0;
    FILE *hits = fopen(o.hits_path, "wb");
    if (!hits) {
        cli_error("%s: cannot write hits: %s", o.hits_path, strerror(errno));
        code = 1;
    } else {
        struct stat out_st;
        bool regular = fstat(fileno(hits), &out_st) == 0 && S_ISREG(out_st.st_mode);
        code = trace_stream(&o, a, rays, hits, &ray_count, &hit_count);
        if (fclose(hits) != 0 && code == 0) {
            cli_error("%s: cannot write hits: %s", o.hits_path, strerror(errno));
            code = 1;
        }
        if (code != 0 && regular)
            remove(o.hits_path); /* no partial file that looks complete (devices and pipes stay) */
    }
    double t2 = cli_now_s();
    if (code == 0)
        printf("traced %llu rays (%s): %llu %s; %d thread%s, %.3f s (%.2f Mrays/s); wrote %s\n",
               (unsigned long long)ray_count, o.occluded ? "any hit" : "closest hit", (unsigned long long)hit_count,
               o.occluded ? "occluded" : "hit", o.threads, o.threads == 1 ? "" : "s", t2 - t1,
               t2 > t1 ? (double)ray_count / (t2 - t1) * 1e-6 : 0.0, o.hits_path);
    fclose(rays);
    cli_scene_finish(&cs);
    return code;
}
