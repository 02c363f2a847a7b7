/* tile_contention.c - the cost of handing out one tile with the pipeline's
 * dynamic load balancer (engine/render/traverser.c, the "tiled" traverser: one
 * atomic counter over every channel's tiles), at several thread counts.
 *
 * The real code path: a tiled traverser from traverser_tiled_create, its
 * begin_frame and render, run by N threads at once. Only the renderer is a
 * stub: its render_tile counts the tile and spins for --work-ns nanoseconds
 * (0: nothing, so the counter's cache line goes from core to core on almost
 * every tile, the worst case). With more threads than CPUs the threads take
 * turns on the CPUs; the counter is lock-free, so a thread preempted between
 * two tiles holds nothing up, and what is measured is the CPUs' own traffic
 * on the line plus switching: it shows the dispenser neither convoys nor
 * loses tiles when oversubscribed, not what 64 cores hitting one line cost
 * (tools/scaling_model.sh and BENCHMARKS.md, "Scaling past this machine").
 *
 *   build/tile-contention [--threads 1,2,4,...] [--size WxH] [--tile-size N]
 *                         [--work-ns NS] [--frames F] [--rounds R]
 *
 * Prints one line per thread count:
 *   TILES threads=N work_ns=W tiles_per_frame=T frames=F rounds=R
 *         wall_ns_per_tile= cpu_ns_per_tile= min_share= max_share= cpus=C
 * wall_ns_per_tile: a frame's wall time (first thread starting to last one
 * finishing, all of them started before the first tile) / tiles, median over rounds; cpu_ns_per_tile: the process's CPU
 * time (user + system) over the frames / tiles handed out, median over rounds;
 * min_share / max_share: the smallest and largest share of a frame's tiles
 * one thread took, times N (1: even); thread_ns_per_tile: frame time x the
 * threads that can run at once / tiles, median over the frames in which every
 * thread took at least 0.8 of an even share (side_by_side_frames of them: the
 * threads really ran side by side, not kept off a CPU by other programs),
 * every frame when oversubscribed; -1 if there was none. */
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "engine/render/traverser.h"

#define MAX_THREADS 256
#define MAX_COUNTS 32
#define MAX_ROUNDS 1001

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

/* Spin iterations per nanosecond, measured once before any thread starts. */
static double spin_per_ns;
static uint64_t spin_iters;
static volatile uint64_t spin_sink;

static uint64_t spin(uint64_t iters)
{
    uint64_t x = 88172645463325252ull;
    for (uint64_t i = 0; i < iters; i++)
        x = x * 6364136223846793005ull + 1442695040888963407ull;
    return x;
}

static void calibrate(void)
{
    uint64_t iters = 1u << 20;
    double t0 = now_s();
    spin_sink = spin(iters);
    double t = now_s() - t0;
    for (int i = 0; i < 3; i++) { /* the fastest of a few: the least disturbed */
        t0 = now_s();
        spin_sink = spin(iters);
        double ti = now_s() - t0;
        t = ti < t ? ti : t;
    }
    spin_per_ns = (double)iters / (t * 1e9);
}

/* The stub renderer: one "primary ray" per tile (the tile count), then the work. */
static void stub_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                      render_counts *counts)
{
    (void)v, (void)s, (void)x0, (void)y0, (void)x1, (void)y1, (void)rgb;
    counts->primary_rays++;
    if (spin_iters)
        spin_sink = spin(spin_iters);
}

static const renderer stub_renderer = {"stub", RENDER_SHADE_PHONG, stub_tile};

typedef struct shared {
    image_traverser *t;
    pthread_barrier_t start, end;
    int threads;
    int frames;
    atomic_int quit;
    atomic_int ready; /* threads started in the current frame: nobody takes a tile before all have */
    bool oversubscribed; /* more threads than CPUs */
    double t_start[MAX_THREADS], t_end[MAX_THREADS];
    uint64_t tiles[MAX_THREADS];
} shared;

typedef struct worker {
    shared *sh;
    int id;
} worker;

static void *worker_main(void *arg)
{
    worker *w = arg;
    shared *sh = w->sh;
    const pixel_sampler single = pixel_sampler_single();
    for (;;) {
        pthread_barrier_wait(&sh->start);
        if (atomic_load(&sh->quit))
            return NULL;
        render_counts counts = {0};
        /* all threads running (or, oversubscribed, all scheduled once) before the first tile:
         * otherwise a frame can be over before a late thread wakes, and nothing contends */
        atomic_fetch_add(&sh->ready, 1);
        while (atomic_load(&sh->ready) < sh->threads) {
            if (sh->oversubscribed)
                sched_yield(); /* let the threads that have not started run */
            else
                __builtin_ia32_pause(); /* stay on the CPU: a yield can lose it to other programs */
        }
        sh->t_start[w->id] = now_s();
        sh->t->ops->render(sh->t, &stub_renderer, &single, &counts);
        sh->t_end[w->id] = now_s();
        sh->tiles[w->id] = counts.primary_rays;
        pthread_barrier_wait(&sh->end);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int parse_list(const char *text, int *out, int max)
{
    char buf[512];
    snprintf(buf, sizeof buf, "%s", text);
    int n = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok && n < max; tok = strtok_r(NULL, ",", &save)) {
        int v = atoi(tok);
        if (v < 1 || v > MAX_THREADS)
            return 0;
        out[n++] = v;
    }
    return n;
}

static void usage(FILE *f)
{
    fputs("usage: tile-contention [--threads 1,2,4,...] [--size WxH] [--tile-size N] [--work-ns NS]\n"
          "                       [--frames F] [--rounds R]\n"
          "The cost per tile of the tiled traverser's atomic tile counter at each thread count\n"
          "(defaults: threads 1,2,4,8,16,32,64; 4096x4096 pixels in 16-pixel tiles = 65536 tiles\n"
          "a frame; work 0 ns per tile; 40 frames a round; 5 rounds).\n",
          f);
}

int main(int argc, char **argv)
{
    int counts[MAX_COUNTS] = {1, 2, 4, 8, 16, 32, 64}, n_counts = 7;
    int width = 4096, height = 4096, tile_px = 16, frames = 40, rounds = 5;
    double work_ns = 0.0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        }
        if (!v) {
            usage(stderr);
            return 2;
        }
        i++;
        if (!strcmp(a, "--threads")) {
            if (!(n_counts = parse_list(v, counts, MAX_COUNTS))) {
                fprintf(stderr, "tile-contention: --threads: counts 1..%d, comma-separated\n", MAX_THREADS);
                return 2;
            }
        } else if (!strcmp(a, "--size")) {
            if (sscanf(v, "%dx%d", &width, &height) != 2 || width < 1 || height < 1) {
                fprintf(stderr, "tile-contention: --size WxH\n");
                return 2;
            }
        } else if (!strcmp(a, "--tile-size")) {
            tile_px = atoi(v);
        } else if (!strcmp(a, "--work-ns")) {
            work_ns = atof(v);
        } else if (!strcmp(a, "--frames")) {
            frames = atoi(v);
        } else if (!strcmp(a, "--rounds")) {
            rounds = atoi(v);
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (tile_px < 1 || frames < 1 || frames > 100000 || rounds < 1 || rounds > MAX_ROUNDS || work_ns < 0.0) {
        usage(stderr);
        return 2;
    }
    calibrate();
    spin_iters = (uint64_t)(work_ns * spin_per_ns + 0.5);
    tess_error err = {{0}};
    image_traverser *t = traverser_tiled_create(tile_px, TILE_ORDER_ROWS, 1, &width, &height, 1, &err);
    if (!t) {
        fprintf(stderr, "tile-contention: %s\n", err.msg);
        return 1;
    }
    const uint64_t tiles = (uint64_t)((width + tile_px - 1) / tile_px) * (uint64_t)((height + tile_px - 1) / tile_px);
    static float pixel[3]; /* the stub writes nothing; the traverser skips a channel whose rgb is NULL */
    render_view view;
    memset(&view, 0, sizeof view);
    const traverser_target target = {.view = &view, .rgb = pixel};
    printf("# tile-contention: %dx%d px, %d-px tiles, %llu tiles a frame, work %.0f ns a tile (%llu spin "
           "iterations), %d frames x %d rounds, %ld CPUs online\n",
           width, height, tile_px, (unsigned long long)tiles, work_ns, (unsigned long long)spin_iters, frames,
           rounds, sysconf(_SC_NPROCESSORS_ONLN));
    for (int k = 0; k < n_counts; k++) {
        const int n = counts[k];
        shared *sh = calloc(1, sizeof *sh);
        worker *ws = calloc((size_t)n, sizeof *ws);
        pthread_t *ids = calloc((size_t)n, sizeof *ids);
        if (!sh || !ws || !ids) {
            fprintf(stderr, "tile-contention: out of memory\n");
            return 1;
        }
        sh->t = t;
        sh->threads = n;
        sh->oversubscribed = n > sysconf(_SC_NPROCESSORS_ONLN);
        pthread_barrier_init(&sh->start, NULL, (unsigned)n + 1);
        pthread_barrier_init(&sh->end, NULL, (unsigned)n + 1);
        atomic_init(&sh->quit, 0);
        for (int i = 0; i < n; i++) {
            ws[i] = (worker){sh, i};
            if (pthread_create(&ids[i], NULL, worker_main, &ws[i]) != 0) {
                fprintf(stderr, "tile-contention: could not start thread %d\n", i);
                return 1;
            }
        }
        double wall[MAX_ROUNDS], cpu[MAX_ROUNDS], min_share = 1e300, max_share = 0.0;
        const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
        const int running = n < cpus ? n : (int)cpus; /* threads that can run at once */
        double *busy = calloc((size_t)rounds * (size_t)frames, sizeof *busy);
        int kept = 0;
        if (!busy) {
            fprintf(stderr, "tile-contention: out of memory\n");
            return 1;
        }
        for (int r = 0; r < rounds; r++) {
            double wall_sum = 0.0, c0 = cpu_s();
            for (int f = 0; f < frames; f++) {
                t->ops->begin_frame(t, &target); /* as the serial section does: resets the counter */
                atomic_store(&sh->ready, 0);
                pthread_barrier_wait(&sh->start);
                pthread_barrier_wait(&sh->end);
                double first = sh->t_start[0], last = sh->t_end[0], frame_min_share = 1e300;
                uint64_t total = 0;
                for (int i = 0; i < n; i++) {
                    first = sh->t_start[i] < first ? sh->t_start[i] : first;
                    last = sh->t_end[i] > last ? sh->t_end[i] : last;
                    total += sh->tiles[i];
                    double share = (double)sh->tiles[i] * n / (double)tiles;
                    min_share = share < min_share ? share : min_share;
                    max_share = share > max_share ? share : max_share;
                    frame_min_share = share < frame_min_share ? share : frame_min_share;
                }
                /* a frame in which every thread took at least 0.8 of an even share ran them
                 * side by side (up to the CPUs) nearly all along: its thread time a tile is the
                 * cost with the line shared; frames where other programs kept a thread off its
                 * CPU are left out (oversubscribed: every frame) */
                if (n > cpus || frame_min_share >= 0.8)
                    busy[kept++] = 1e9 * (last - first) * running / (double)tiles;
                if (total != tiles) {
                    fprintf(stderr, "tile-contention: %llu tiles rendered of %llu\n", (unsigned long long)total,
                            (unsigned long long)tiles);
                    return 1;
                }
                wall_sum += last - first;
            }
            /* (the main thread's CPU while it sleeps in the barriers is nil) */
            cpu[r] = 1e9 * (cpu_s() - c0) / ((double)tiles * frames);
            wall[r] = 1e9 * wall_sum / ((double)tiles * frames);
        }
        atomic_store(&sh->quit, 1);
        pthread_barrier_wait(&sh->start);
        for (int i = 0; i < n; i++)
            pthread_join(ids[i], NULL);
        pthread_barrier_destroy(&sh->start);
        pthread_barrier_destroy(&sh->end);
        printf("TILES threads=%d work_ns=%.0f tiles_per_frame=%llu frames=%d rounds=%d wall_ns_per_tile=%.2f "
               "cpu_ns_per_tile=%.2f min_share=%.3f max_share=%.3f cpus=%ld side_by_side_frames=%d "
               "thread_ns_per_tile=%.2f\n",
               n, work_ns, (unsigned long long)tiles, frames, rounds, median(wall, rounds), median(cpu, rounds),
               min_share, max_share, cpus, kept, kept ? median(busy, kept) : -1.0);
        free(busy);
        fflush(stdout);
        free(sh);
        free(ws);
        free(ids);
    }
    image_traverser_destroy(t);
    return 0;
}
