/* soak_driver.c - the kiosk under a soak (tests/soak.sh, docs/tests.md).
 *
 * It runs `tessera run --wall WALL` in this process through cli_run_with,
 * so the options, the set-up (headless wall outputs as pipeline channels,
 * the input thread with its attract tour, a replay of recorded input through
 * the input sink), the frame loop, the SIGTERM stop and the teardown are the
 * run command's own; the driver only adds, through the hooks:
 *   - SENDERS threads that queue random transactions for `seconds` s:
 *     cameras, thread-count changes, channels switched off (and on again a
 *     moment later, as a hotplugged monitor), status lines, hiding and
 *     showing geometries, the cursor, now and then a burst that overflows
 *     the queue; a few are invalid on purpose (the setters must refuse them
 *     at the barrier). Each is a pipeline transaction whose callback calls
 *     the pipeline's own setter and counts what happened;
 *   - replayed input: a record file of random input transactions (camera,
 *     cursor, status, hide, show, isolate and highlight of instance ranges,
 *     show-all, tour on/off), generated here and
 *     given to the kiosk as --replay-input, so the sink's replay thread plays
 *     it at the recorded times as it would a person's session;
 *   - a frame clock (a serial animation: each frame's duration into a
 *     histogram, the worst one exactly; and the part of it spent outside the
 *     render stage: display, serial section, barriers, waiting for a CPU) and
 *     a monitor thread that writes one
 *     sample per second (RSS and open file descriptors from /proc/self,
 *     frames, transactions) to the samples file, aborts on a frame loop
 *     stuck for STALL_ABORT_S, and sends SIGTERM at the end, as systemd
 *     would.
 * After the run it reconciles the counts (every transaction queued was
 * applied, or refused with a counted reason, or discarded at the stop) and
 * prints PASS/FAIL lines; tests/soak.sh judges RSS and descriptors from the
 * samples file. Exit status: the kiosk's, else 1 when a check failed.
 *
 * Random choices come from --seed only (one generator per thread, seeded
 * from it), so a failure's sequence of decisions can be replayed; what the
 * threads interleave with still depends on timing. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/base/clock.h"
#include "engine/frame/pipeline.h"
#include "engine/scene/scene.h"
#include "input/record.h"
#include "input/sink.h"
#include "app/cli.h"
#include "app/input_cli.h"

#define SOAK_MAX_SENDERS 8
#define SOAK_MEAN_PAUSE_S 0.004     /* between one sender's transactions: ~250/s per sender */
#define SOAK_BURST_CHANCE 1e-4      /* per transaction: a burst that overflows the queue */
#define SOAK_BURST_COUNT (PIPELINE_QUEUE_MAX + 512)
#define SOAK_INVALID_CHANCE 0.02    /* a camera or hide transaction made invalid on purpose */
#define SOAK_REPLAY_MEAN_GAP_S 0.1  /* between replayed input transactions: ~10/s */
#define SOAK_REPLAY_END_S 3.0       /* the replay ends this long before the stop, so it all plays */
#define STALL_ABORT_S 120.0         /* no frame for this long: the loop is stuck; abort for a core */
#define GAP_SKIP_FRAMES 2           /* frame 0's duration is 0, frame 1's includes the threads starting */
/* frame-time histogram: bin b holds [HIST_T0_S * HIST_RATIO^b, ... ^(b+1)): 2 % wide, 100 us .. ~2.7 h */
#define HIST_BINS 1024
#define HIST_T0_S 1e-4
#define HIST_RATIO 1.02

typedef enum soak_kind {
    SOAK_CAMERA,   /* the wall's camera: every channel */
    SOAK_THREADS,  /* render thread count 1..max_threads */
    SOAK_CHANNEL,  /* a channel off, or on again */
    SOAK_STATUS,   /* the status line: random bytes, some too long, some "" */
    SOAK_HIDE,     /* hide or show a geometry */
    SOAK_UNHIDE,   /* show every geometry */
    SOAK_CURSOR,   /* the cursor somewhere (maybe off the plane), or hidden */
    SOAK_KIND_COUNT
} soak_kind;

static const char *const kind_names[SOAK_KIND_COUNT] = {"camera", "threads", "channel", "status",
                                                        "hide",   "unhide",  "cursor"};
/* Relative frequencies. A channel switch is a monitor unplugged and plugged in
 * again: rare (about one every 2 s per sender) and short (OFF_MIN_S..OFF_MAX_S),
 * so the wall mostly has all its outputs, as a real one does; with every
 * channel off a headless pipeline renders empty frames as fast as it can. */
static const int kind_weights[SOAK_KIND_COUNT] = {300, 40, 2, 200, 120, 40, 220};
#define SOAK_CHANNEL_OFF_MIN_S 0.02
#define SOAK_CHANNEL_OFF_MAX_S 0.3

/* One transaction's arguments (copied by the pipeline: at most PIPELINE_ARGS_MAX bytes). */
typedef struct soak_args {
    soak_kind kind;
    bool expect_valid;        /* false: made invalid on purpose; the setter must refuse it */
    bool on;                  /* channel on, geometry hidden, cursor visible */
    int channel, threads;
    uint32_t geom_id;
    float sx, sy;
    camera_desc camera;
    char text[PIPELINE_STATUS_BYTES];
} soak_args;
_Static_assert(sizeof(soak_args) <= PIPELINE_ARGS_MAX, "soak_args must fit a transaction's copy");

/* Counts per kind: senders add attempted/accepted/refused, the serial section
 * applied/invalid/mismatch. All atomics (several senders, the pipeline). */
typedef struct kind_counts {
    atomic_uint_fast64_t attempted;
    atomic_uint_fast64_t accepted;        /* pipeline_transaction returned true */
    atomic_uint_fast64_t refused_running; /* refused before the stop: the queue was full */
    atomic_uint_fast64_t refused_stopping;/* refused once the stop was asked for */
    atomic_uint_fast64_t applied;         /* its callback ran at a barrier */
    atomic_uint_fast64_t invalid;         /* ... and the setter refused it (made invalid on purpose) */
    atomic_uint_fast64_t mismatch;        /* the setter's answer was not the expected one */
} kind_counts;

typedef struct sender {
    struct soak *soak;
    int index;
    uint64_t rng;
    pthread_t thread;
    /* channels this sender switched off, and when to switch each on again (0: not off) */
    double channel_on_at_s[PIPELINE_MAX_CHANNELS];
} sender;

typedef struct soak {
    /* fixed before the run */
    double seconds;
    uint64_t seed;
    int max_threads, sender_count;
    FILE *samples;
    vec3 scene_lo, scene_hi;
    uint32_t geometry_count;
    uint64_t replay_generated[TXN_KIND_COUNT];
    uint64_t replay_total;

    /* set by the started hook, read by the threads */
    pipeline *p;
    input_sink *sink;
    int channel_count;
    double start_s;

    sender senders[SOAK_MAX_SENDERS];
    pthread_t monitor;
    bool threads_started;
    atomic_bool senders_stop, monitor_stop;

    kind_counts counts[SOAK_KIND_COUNT];

    /* frame clock: written in the serial section, read by the monitor */
    atomic_uint_fast64_t frames_seen;
    atomic_uint_fast64_t last_frame_us;   /* clock_monotonic_us of the latest serial section */
    uint64_t hist[HIST_BINS];             /* serial section only until the run returns */
    uint64_t hist_count;
    double worst_frame_s;                 /* serial section only */
    uint64_t worst_frame_index;
    atomic_uint_fast64_t stall_worst_us;  /* the monitor: longest time it saw without a frame */
    atomic_uint_fast64_t second_worst_us; /* worst frame in the current sample second (reset by the monitor) */
    atomic_uint_fast64_t second_worst_outside_us; /* ... and the most of one frame outside its render stage */
    double worst_outside_s;               /* serial section only: the run's most outside a render stage */

    /* results, after the run */
    pipeline_stats pstats;
    input_sink_stats sstats;
    bool finished;
    int failed, passed;
} soak;

/* ---------------------------------------------------------------- randomness */

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *rng) { return (double)(splitmix64(rng) >> 11) * 0x1.0p-53; }
static int below(uint64_t *rng, int n) { return (int)(uniform(rng) * n); }
static double exponential(uint64_t *rng, double mean_s) { return -mean_s * log(1.0 - uniform(rng)); }

static soak_kind pick_kind(uint64_t *rng)
{
    int total = 0;
    for (int k = 0; k < SOAK_KIND_COUNT; k++)
        total += kind_weights[k];
    int r = below(rng, total);
    for (int k = 0; k < SOAK_KIND_COUNT; k++) {
        if (r < kind_weights[k])
            return (soak_kind)k;
        r -= kind_weights[k];
    }
    return SOAK_CAMERA;
}

/* A camera that frames the scene, as people steer the wall: looking near the
 * centre of its box from 0.6..1.5 box diagonals away at fov 30..60 degrees, so
 * every frame costs about the same (a view of empty sky would render many
 * times faster and make the frame-time median meaningless). */
static camera_desc random_camera(const soak *s, uint64_t *rng)
{
    vec3 size = v3_sub(s->scene_hi, s->scene_lo);
    float diag = v3_length(size);
    if (!(diag > 0.f))
        diag = 1.f;
    vec3 jitter = v3((float)(uniform(rng) - 0.5), (float)(uniform(rng) - 0.5), (float)(uniform(rng) - 0.5));
    vec3 at = v3_add(v3_scale(v3_add(s->scene_lo, s->scene_hi), 0.5f), v3_scale(v3_mul(size, jitter), 0.2f));
    double az = 6.283185307179586 * uniform(rng), el = 0.1 + 0.9 * uniform(rng);
    float dist = diag * (float)(0.6 + 0.9 * uniform(rng));
    vec3 dir = v3((float)(cos(el) * cos(az)), (float)sin(el), (float)(cos(el) * sin(az)));
    camera_desc c = {.eye = v3_add(at, v3_scale(dir, dist)), .look_at = at, .up = v3(0.f, 1.f, 0.f),
                     .fov_deg = (float)(30.0 + 30.0 * uniform(rng))};
    return c;
}

/* Random text: mostly printable, sometimes any byte but NUL, sometimes
 * longer than the line holds (cut), sometimes "" (hides the line). */
static void random_text(uint64_t *rng, char *out, size_t out_bytes)
{
    size_t n = (size_t)below(rng, 10) == 0 ? 0 : (size_t)below(rng, 200);
    bool any_byte = below(rng, 20) == 0;
    if (n >= out_bytes)
        n = out_bytes - 1;
    for (size_t i = 0; i < n; i++)
        out[i] = any_byte ? (char)(1 + below(rng, 255)) : (char)(' ' + below(rng, 95));
    out[n] = '\0';
}

/* ---------------------------------------------------------------- transactions */

/* The one soak of this process: the transactions' callback counts into it (a
 * transaction's argument copy holds only its arguments). */
static soak the_soak;

/* At the barrier: the pipeline's own setter, and what it said. */
static void apply_soak(pipeline *p, void *args)
{
    const soak_args *a = args;
    bool ok = true;
    switch (a->kind) {
    case SOAK_CAMERA:
        for (int i = 0; i < pipeline_channel_count(p); i++)
            ok = pipeline_set_camera(p, i, &a->camera) && ok;
        break;
    case SOAK_THREADS:
        ok = pipeline_set_threads(p, a->threads);
        break;
    case SOAK_CHANNEL:
        ok = pipeline_set_channel_active(p, a->channel, a->on);
        break;
    case SOAK_STATUS:
        ok = pipeline_set_status(p, a->text);
        break;
    case SOAK_HIDE:
        ok = pipeline_set_hidden(p, a->geom_id, a->on);
        break;
    case SOAK_UNHIDE:
        ok = pipeline_unhide_all(p);
        break;
    case SOAK_CURSOR:
        ok = pipeline_set_cursor(p, a->on, a->sx, a->sy);
        break;
    default:
        ok = false;
        break;
    }
    kind_counts *c = &the_soak.counts[a->kind];
    atomic_fetch_add(&c->applied, 1);
    if (!ok)
        atomic_fetch_add(&c->invalid, 1);
    if (ok != a->expect_valid)
        atomic_fetch_add(&c->mismatch, 1);
}

static void send(soak *s, const soak_args *a)
{
    kind_counts *c = &s->counts[a->kind];
    atomic_fetch_add(&c->attempted, 1);
    /* the stop flag read before the call: a refusal with it unset was for a full queue
     * (pipeline_transaction refuses for a full queue or a stop; the arguments always fit) */
    bool stopping = pipeline_stop_requested(s->p);
    if (pipeline_transaction(s->p, kind_names[a->kind], apply_soak, a, sizeof *a))
        atomic_fetch_add(&c->accepted, 1);
    else if (stopping || pipeline_stop_requested(s->p))
        atomic_fetch_add(&c->refused_stopping, 1);
    else
        atomic_fetch_add(&c->refused_running, 1);
}

static void make_transaction(sender *t, soak_kind kind, soak_args *a)
{
    soak *s = t->soak;
    uint64_t *rng = &t->rng;
    memset(a, 0, sizeof *a);
    a->kind = kind;
    a->expect_valid = true;
    switch (kind) {
    case SOAK_CAMERA:
        a->camera = random_camera(s, rng);
        if (uniform(rng) < SOAK_INVALID_CHANCE) {
            a->camera.look_at = a->camera.eye; /* no view direction */
            a->expect_valid = false;
        }
        break;
    case SOAK_THREADS:
        a->threads = 1 + below(rng, s->max_threads);
        break;
    case SOAK_CHANNEL:
        break; /* the sender picks the channel (sender_main) */
    case SOAK_STATUS:
        random_text(rng, a->text, sizeof a->text);
        break;
    case SOAK_HIDE:
        a->on = below(rng, 3) != 0;
        a->geom_id = (uint32_t)below(rng, (int)s->geometry_count);
        if (uniform(rng) < SOAK_INVALID_CHANCE) {
            a->geom_id = s->geometry_count + (uint32_t)below(rng, 3); /* no such geometry */
            a->expect_valid = false;
        }
        break;
    case SOAK_UNHIDE:
        break;
    case SOAK_CURSOR:
        a->on = below(rng, 8) != 0;
        a->sx = (float)(-1.5 + 3.0 * uniform(rng));
        a->sy = (float)(-1.5 + 3.0 * uniform(rng));
        break;
    default:
        break;
    }
}

static void sleep_s(double seconds)
{
    if (seconds <= 0.0)
        return;
    struct timespec ts = {(time_t)seconds, (long)((seconds - floor(seconds)) * 1e9)};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

static void *sender_main(void *arg)
{
    sender *t = arg;
    soak *s = t->soak;
    soak_args a;
    while (!atomic_load(&s->senders_stop)) {
        double now = clock_monotonic_s();
        /* channels switched off a moment ago come back (a monitor plugged in again) */
        for (int ch = 0; ch < s->channel_count; ch++)
            if (t->channel_on_at_s[ch] > 0.0 && now >= t->channel_on_at_s[ch]) {
                make_transaction(t, SOAK_CHANNEL, &a);
                a.channel = ch;
                a.on = true;
                send(s, &a);
                t->channel_on_at_s[ch] = 0.0;
            }
        soak_kind kind = pick_kind(&t->rng);
        make_transaction(t, kind, &a);
        if (kind == SOAK_CHANNEL) {
            int ch = below(&t->rng, s->channel_count);
            if (t->channel_on_at_s[ch] > 0.0)
                continue; /* already off by this sender: it comes back on its own */
            a.channel = ch;
            a.on = false;
            t->channel_on_at_s[ch] =
                now + SOAK_CHANNEL_OFF_MIN_S + (SOAK_CHANNEL_OFF_MAX_S - SOAK_CHANNEL_OFF_MIN_S) * uniform(&t->rng);
        }
        send(s, &a);
        if (uniform(&t->rng) < SOAK_BURST_CHANCE) {
            /* a flood: more than the queue holds, as fast as possible */
            for (int i = 0; i < SOAK_BURST_COUNT && !atomic_load(&s->senders_stop); i++) {
                make_transaction(t, SOAK_CAMERA, &a);
                send(s, &a);
            }
        }
        sleep_s(exponential(&t->rng, SOAK_MEAN_PAUSE_S));
    }
    return NULL;
}

/* ---------------------------------------------------------------- frame clock and monitor */

static void frame_clock(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    soak *s = ctx;
    uint64_t now_us = clock_monotonic_us();
    atomic_store(&s->last_frame_us, now_us);
    atomic_fetch_add(&s->frames_seen, 1);
    if (fi->frame < GAP_SKIP_FRAMES)
        return;
    double t = fi->last_frame_s;
    int bin = t > HIST_T0_S ? (int)(log(t / HIST_T0_S) / log(HIST_RATIO)) : 0;
    bin = bin < 0 ? 0 : bin >= HIST_BINS ? HIST_BINS - 1 : bin;
    s->hist[bin]++;
    s->hist_count++;
    if (t > s->worst_frame_s) {
        s->worst_frame_s = t;
        s->worst_frame_index = fi->frame;
    }
    uint64_t t_us = (uint64_t)(t * 1e6);
    if (t_us > atomic_load(&s->second_worst_us))
        atomic_store(&s->second_worst_us, t_us);
    /* what the step spent not rendering: a view that costs 10 x more to render
     * (a close-up after the tour's wide shots) is not a stall; a loop held up
     * by a transaction, a display or a lock is */
    double outside = t > fi->last_render_s ? t - fi->last_render_s : 0.0;
    if (outside > s->worst_outside_s)
        s->worst_outside_s = outside;
    uint64_t outside_us = (uint64_t)(outside * 1e6);
    if (outside_us > atomic_load(&s->second_worst_outside_us))
        atomic_store(&s->second_worst_outside_us, outside_us);
}

/* The median frame time: the upper edge of the histogram bin holding it (2 % resolution). */
static double median_frame_s(const soak *s)
{
    uint64_t half = (s->hist_count + 1) / 2, seen = 0;
    for (int b = 0; b < HIST_BINS; b++) {
        seen += s->hist[b];
        if (seen >= half && s->hist_count)
            return HIST_T0_S * pow(HIST_RATIO, b + 1);
    }
    return 0.0;
}

/* Resident set in KiB (/proc/self/statm) and open descriptors (/proc/self/fd,
 * less the one reading it); -1 when unreadable. */
static long rss_kib(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long pages_total = 0, pages_resident = -1;
    if (!f)
        return -1;
    if (fscanf(f, "%ld %ld", &pages_total, &pages_resident) != 2)
        pages_resident = -1;
    fclose(f);
    return pages_resident < 0 ? -1 : pages_resident * (sysconf(_SC_PAGESIZE) / 1024);
}

static int open_fds_once(void)
{
    DIR *d = opendir("/proc/self/fd");
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (e->d_name[0] != '.')
            n++;
    closedir(d);
    return n - 1;
}

/* Whether a task of this process is one of the pipeline's threads: the one
 * that runs the frame loop (this process's main thread: cli_run_with is called
 * from main) and the render threads it starts (engine/base/thread_name.h). */
static bool pipeline_task(const char *tid)
{
    if (strtol(tid, NULL, 10) == (long)getpid())
        return true;
    char path[64], comm[32] = "";
    snprintf(path, sizeof path, "/proc/self/task/%.20s/comm", tid);
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    bool render = fgets(comm, sizeof comm, f) && strncmp(comm, "tess-render-", 12) == 0;
    fclose(f);
    return render;
}

/* Per pipeline thread, the nanoseconds it had waited for a CPU at the last
 * reading (field 2 of /proc/self/task/N/schedstat). Only the monitor thread
 * reads and writes it. */
#define WAIT_TASKS_MAX 128
typedef struct task_wait {
    long tid;
    uint64_t waited_ns;
} task_wait;
typedef struct wait_book {
    task_wait task[WAIT_TASKS_MAX];
    int count;
} wait_book;

/* Nanoseconds the pipeline's threads waited for a CPU since the last call
 * (per thread, so a render thread that leaves at a thread-count change takes
 * nothing away; one that came counts from its start). A diagnostic for frame
 * gaps: a frame loop whose threads waited for the machine is not a stuck
 * loop; the waits of the other threads (the soak's senders, input) excuse
 * nothing. 0 when unreadable. */
static uint64_t pipeline_wait_delta_ns(wait_book *book)
{
    DIR *d = opendir("/proc/self/task");
    if (!d)
        return 0;
    wait_book now = {.count = 0};
    uint64_t delta = 0;
    struct dirent *e;
    while ((e = readdir(d)) && now.count < WAIT_TASKS_MAX) {
        if (e->d_name[0] == '.' || !pipeline_task(e->d_name))
            continue;
        char path[64];
        snprintf(path, sizeof path, "/proc/self/task/%.20s/schedstat", e->d_name);
        FILE *f = fopen(path, "r");
        unsigned long long on_cpu_ns, waited_ns;
        bool read = f && fscanf(f, "%llu %llu", &on_cpu_ns, &waited_ns) == 2;
        if (f)
            fclose(f);
        if (!read)
            continue;
        long tid = strtol(e->d_name, NULL, 10);
        uint64_t before = 0;
        for (int i = 0; i < book->count; i++)
            if (book->task[i].tid == tid)
                before = book->task[i].waited_ns;
        if (waited_ns > before)
            delta += waited_ns - before;
        now.task[now.count++] = (task_wait){tid, waited_ns};
    }
    closedir(d);
    *book = now;
    return delta;
}

/* The least of FD_READINGS counts FD_READING_GAP_S apart: a descriptor another
 * thread holds for a moment (the input thread's device retry every second,
 * libinput's and udev's look at sysfs) is not a leak; a leaked one stays. */
#define FD_READINGS 3
#define FD_READING_GAP_S 0.005
static int open_fds(void)
{
    int least = open_fds_once();
    for (int i = 1; i < FD_READINGS; i++) {
        sleep_s(FD_READING_GAP_S);
        int n = open_fds_once();
        least = n < least ? n : least;
    }
    return least;
}

static uint64_t accepted_total(soak *s)
{
    uint64_t n = 0;
    for (int k = 0; k < SOAK_KIND_COUNT; k++)
        n += atomic_load(&s->counts[k].accepted);
    return n;
}

/* Once a second: a sample line; at `seconds` SIGTERM (the kiosk's stop);
 * a loop without frames for STALL_ABORT_S: abort. Samples stop with the stop. */
static void *monitor_main(void *arg)
{
    soak *s = arg;
    fprintf(s->samples, "# t_s rss_kib fds frames txn_accepted txn_applied worst_frame_ms_this_second "
                        "pipeline_runqueue_wait_ms_this_second worst_outside_render_ms_this_second\n");
    fflush(s->samples);
    bool stop_sent = false;
    static wait_book waits; /* the monitor thread's alone */
    pipeline_wait_delta_ns(&waits);
    for (int second = 1; !atomic_load(&s->monitor_stop); second++) {
        /* sleep to the next whole second since the start, in short steps (stop promptly) */
        for (;;) {
            double wait_s = s->start_s + second - clock_monotonic_s();
            if (wait_s <= 0.0 || atomic_load(&s->monitor_stop))
                break;
            sleep_s(wait_s < 0.05 ? wait_s : 0.05);
        }
        if (atomic_load(&s->monitor_stop))
            break;
        double now_s = clock_monotonic_s();
        uint64_t last_us = atomic_load(&s->last_frame_us), now_us = clock_monotonic_us();
        uint64_t stall_us = last_us && now_us > last_us ? now_us - last_us : 0;
        if (stall_us > atomic_load(&s->stall_worst_us))
            atomic_store(&s->stall_worst_us, stall_us);
        if (stop_sent)
            continue; /* only the stall watch after the stop: samples end there */
        if ((double)stall_us * 1e-6 > STALL_ABORT_S) {
            fprintf(stderr, "soak: FAIL: no frame for %.0f s: the frame loop is stuck; aborting for a core\n",
                    (double)stall_us * 1e-6);
            fflush(NULL);
            abort();
        }
        pipeline_stats ps = pipeline_get_stats(s->p);
        double waited_ms = 1e-6 * (double)pipeline_wait_delta_ns(&waits);
        fprintf(s->samples, "%.0f %ld %d %llu %llu %llu %.1f %.0f %.1f\n", now_s - s->start_s, rss_kib(),
                open_fds(), (unsigned long long)atomic_load(&s->frames_seen), (unsigned long long)accepted_total(s),
                (unsigned long long)ps.transactions_applied, 1e-3 * (double)atomic_exchange(&s->second_worst_us, 0),
                waited_ms, 1e-3 * (double)atomic_exchange(&s->second_worst_outside_us, 0));
        fflush(s->samples);
        if (now_s - s->start_s >= s->seconds) {
            kill(getpid(), SIGTERM); /* as systemd stops the kiosk: the run command's handler */
            stop_sent = true;
        }
    }
    return NULL;
}

/* ---------------------------------------------------------------- the hooks */

static bool started(void *ctx, pipeline *p, struct cli_input *in)
{
    soak *s = ctx;
    s->p = p;
    s->sink = cli_input_sink(in);
    s->channel_count = pipeline_channel_count(p);
    if (!s->sink) {
        fprintf(stderr, "soak: the kiosk has no input sink (input off?)\n");
        return false;
    }
    if (!pipeline_add_serial_animation(p, "soak frame clock", frame_clock, s)) {
        fprintf(stderr, "soak: cannot register the frame clock\n");
        return false;
    }
    s->start_s = clock_monotonic_s();
    atomic_store(&s->last_frame_us, clock_monotonic_us());
    int made = 0;
    bool ok = pthread_create(&s->monitor, NULL, monitor_main, s) == 0;
    for (; ok && made < s->sender_count; made++) {
        sender *t = &s->senders[made];
        t->soak = s;
        t->index = made;
        t->rng = s->seed * 1000003u + (uint64_t)made + 1;
        ok = pthread_create(&t->thread, NULL, sender_main, t) == 0;
    }
    if (!ok) {
        fprintf(stderr, "soak: cannot start threads\n");
        atomic_store(&s->senders_stop, true);
        atomic_store(&s->monitor_stop, true);
        /* (threads that did start are joined by finished(), which then never runs: leave them) */
        return false;
    }
    s->threads_started = true;
    fprintf(stderr, "soak: %d senders and the monitor started; %.0f s to go\n", s->sender_count, s->seconds);
    return true;
}

static void finished(void *ctx, pipeline *p, struct cli_input *in, bool ran)
{
    (void)in;
    (void)ran;
    soak *s = ctx;
    atomic_store(&s->senders_stop, true);
    atomic_store(&s->monitor_stop, true);
    if (s->threads_started) {
        for (int i = 0; i < s->sender_count; i++)
            pthread_join(s->senders[i].thread, NULL);
        pthread_join(s->monitor, NULL);
    }
    /* the senders are joined and the pipeline closed: the pipeline's counts are final; the
     * replay thread has played its record (it ends SOAK_REPLAY_END_S before the stop) */
    s->pstats = pipeline_get_stats(p);
    s->sstats = input_sink_get_stats(s->sink);
    s->finished = true;
}

/* ---------------------------------------------------------------- the replayed input */

/* A record of random input transactions over [0.5, seconds - SOAK_REPLAY_END_S] s. */
static bool write_replay(soak *s, const char *file)
{
    FILE *f = fopen(file, "w");
    if (!f) {
        fprintf(stderr, "soak: %s: %s\n", file, strerror(errno));
        return false;
    }
    uint64_t rng = s->seed ^ 0x5eed5eed5eed5eedull;
    bool ok = fprintf(f, "%s\n# the soak's replayed input, seed %llu\n", INPUT_RECORD_HEADER,
                      (unsigned long long)s->seed) > 0;
    double t = 0.5, end = s->seconds - SOAK_REPLAY_END_S;
    while (ok && t < end) {
        int repeat = below(&rng, 100) == 0 ? 20 : 1; /* now and then a burst at one instant */
        for (int i = 0; ok && i < repeat; i++) {
            int r = below(&rng, 100);
            camera_desc cam = random_camera(s, &rng);
            bool on = below(&rng, 2) != 0;
            float sx = (float)(-1.2 + 2.4 * uniform(&rng)), sy = (float)(-1.2 + 2.4 * uniform(&rng));
            uint32_t geom = (uint32_t)below(&rng, (int)s->geometry_count);
            /* a part's instance range, as the part commands of input make them */
            uint32_t span = 1 + (uint32_t)below(&rng, (int)(s->geometry_count - geom));
            char text[TXN_TEXT_BYTES];
            random_text(&rng, text, sizeof text);
            input_txn x = r < 40   ? txn_camera(TXN_ALL_CHANNELS, &cam)
                          : r < 65 ? txn_cursor(on, sx, sy)
                          : r < 80 ? txn_status(text)
                          : r < 84 ? txn_geoms_record(TXN_HIDE, geom, below(&rng, 2) ? 1 : span)
                          : r < 85 ? txn_geoms_record(TXN_SHOW, geom, span)
                          : r < 86 ? txn_geoms_record(TXN_ISOLATE, geom, span)
                          : r < 88 ? txn_highlight(geom, span, on)
                          : r < 93 ? txn_simple(TXN_SHOW_ALL)
                                   : txn_flag(TXN_TOUR, on);
            ok = input_record_write(f, t, &x);
            s->replay_generated[x.kind]++;
            s->replay_total++;
        }
        t += exponential(&rng, SOAK_REPLAY_MEAN_GAP_S);
    }
    ok = fclose(f) == 0 && ok;
    if (!ok)
        fprintf(stderr, "soak: %s: write failed\n", file);
    return ok;
}

/* ---------------------------------------------------------------- the verdict */

static void check(soak *s, bool ok, const char *name, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void check(soak *s, bool ok, const char *name, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("%s %s: ", ok ? "PASS" : "FAIL", name);
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    if (ok)
        s->passed++;
    else
        s->failed++;
}

static void report(soak *s)
{
    const pipeline_stats *ps = &s->pstats;
    const input_sink_stats *ss = &s->sstats;
    uint64_t attempted = 0, accepted = 0, refused = 0, refused_running = 0, applied = 0, discarded = 0;
    uint64_t mismatches = 0, inconsistent = 0;
    printf("soak: transactions by kind (sent from %d threads):\n", s->sender_count);
    printf("soak:   %-8s %10s %10s %10s %10s %10s %10s %10s\n", "kind", "queued", "applied", "invalid", "refused:full",
           "refused:stop", "discarded", "sent");
    for (int k = 0; k < SOAK_KIND_COUNT; k++) {
        kind_counts *c = &s->counts[k];
        uint64_t at = atomic_load(&c->attempted), ac = atomic_load(&c->accepted), ap = atomic_load(&c->applied);
        uint64_t rr = atomic_load(&c->refused_running), rs = atomic_load(&c->refused_stopping);
        uint64_t dk = ac >= ap ? ac - ap : 0;
        printf("soak:   %-8s %10llu %10llu %10llu %12llu %12llu %10llu %10llu\n", kind_names[k],
               (unsigned long long)ac, (unsigned long long)ap, (unsigned long long)atomic_load(&c->invalid),
               (unsigned long long)rr, (unsigned long long)rs, (unsigned long long)dk, (unsigned long long)at);
        if (at != ac + rr + rs || ap > ac)
            inconsistent++;
        attempted += at;
        accepted += ac;
        refused += rr + rs;
        refused_running += rr;
        applied += ap;
        discarded += dk;
        mismatches += atomic_load(&c->mismatch);
    }
    printf("soak: replayed input: %llu generated (camera %llu, cursor %llu, status %llu, hide %llu, show %llu, "
           "isolate %llu, highlight %llu, show-all %llu, tour %llu); sink: %llu replayed, %llu emitted live, %llu pipeline transactions queued, %llu refused, "
           "%llu camera changes applied in %llu transactions\n",
           (unsigned long long)s->replay_total, (unsigned long long)s->replay_generated[TXN_CAMERA],
           (unsigned long long)s->replay_generated[TXN_CURSOR],
           (unsigned long long)s->replay_generated[TXN_STATUS],
           (unsigned long long)s->replay_generated[TXN_HIDE],
           (unsigned long long)s->replay_generated[TXN_SHOW],
           (unsigned long long)s->replay_generated[TXN_ISOLATE],
           (unsigned long long)s->replay_generated[TXN_HIGHLIGHT],
           (unsigned long long)s->replay_generated[TXN_SHOW_ALL],
           (unsigned long long)s->replay_generated[TXN_TOUR], (unsigned long long)ss->replayed,
           (unsigned long long)ss->emitted, (unsigned long long)ss->queued, (unsigned long long)ss->refused,
           (unsigned long long)ss->camera_changes, (unsigned long long)ss->camera_applied);
    printf("soak: pipeline: %llu frames rendered, %llu displayed, %llu transactions applied, %llu rejected "
           "(%llu queue full, %llu stopping), %llu discarded at the stop, %llu slow, %llu thread changes\n",
           (unsigned long long)ps->frames_rendered, (unsigned long long)ps->frames_displayed,
           (unsigned long long)ps->transactions_applied, (unsigned long long)ps->transactions_rejected,
           (unsigned long long)ps->rejected_queue_full, (unsigned long long)ps->rejected_stopped,
           (unsigned long long)ps->transactions_discarded, (unsigned long long)ps->slow_callbacks,
           (unsigned long long)ps->thread_changes);

    check(s, inconsistent == 0, "per-kind counts",
          "every kind: sent = queued + refused (full or stopping), applied <= queued (%llu sent, %llu queued, "
          "%llu refused)",
          (unsigned long long)attempted, (unsigned long long)accepted, (unsigned long long)refused);
    check(s, mismatches == 0, "setters",
          "every applied transaction's setter accepted it exactly when it was valid (%llu mismatches)",
          (unsigned long long)mismatches);
    uint64_t queued_all = accepted + ss->queued, ran_all = ps->transactions_applied + ps->transactions_discarded;
    check(s, queued_all == ran_all, "queued = applied + discarded",
          "driver %llu + input sink %llu queued = %llu; pipeline %llu applied + %llu discarded = %llu",
          (unsigned long long)accepted, (unsigned long long)ss->queued, (unsigned long long)queued_all,
          (unsigned long long)ps->transactions_applied, (unsigned long long)ps->transactions_discarded,
          (unsigned long long)ran_all);
    check(s, applied <= ps->transactions_applied && discarded <= ps->transactions_discarded, "driver's share",
          "driver applied %llu <= pipeline applied %llu, driver discarded %llu <= pipeline discarded %llu",
          (unsigned long long)applied, (unsigned long long)ps->transactions_applied, (unsigned long long)discarded,
          (unsigned long long)ps->transactions_discarded);
    check(s,
          refused + ss->refused == ps->transactions_rejected &&
              ps->transactions_rejected == ps->rejected_queue_full + ps->rejected_stopped &&
              refused_running <= ps->rejected_queue_full,
          "refused with a reason",
          "driver %llu + input sink %llu refused = pipeline %llu rejected = %llu queue full + %llu stopping",
          (unsigned long long)refused, (unsigned long long)ss->refused, (unsigned long long)ps->transactions_rejected,
          (unsigned long long)ps->rejected_queue_full, (unsigned long long)ps->rejected_stopped);
    check(s, ss->replayed == s->replay_total && ss->camera_changes >= s->replay_generated[TXN_CAMERA],
          "replayed input", "%llu of %llu recorded input transactions played through the sink, %llu camera changes "
          "(%llu recorded)",
          (unsigned long long)ss->replayed, (unsigned long long)s->replay_total,
          (unsigned long long)ss->camera_changes, (unsigned long long)s->replay_generated[TXN_CAMERA]);
    check(s, ss->emitted + ss->replayed >= ss->queued + ss->refused, "input sink counts",
          "%llu emitted + %llu replayed >= %llu queued + %llu refused (the rest coalesced in the mailbox)",
          (unsigned long long)ss->emitted, (unsigned long long)ss->replayed, (unsigned long long)ss->queued,
          (unsigned long long)ss->refused);

    double median = median_frame_s(s);
    double stall_s = 1e-6 * (double)atomic_load(&s->stall_worst_us);
    double worst = s->worst_frame_s > stall_s ? s->worst_frame_s : stall_s;
    printf("soak-figures: frames=%llu median_frame_ms=%.2f worst_frame_ms=%.1f worst_frame_index=%llu "
           "worst_outside_render_ms=%.1f worst_stall_seen_ms=%.0f fps=%.2f\n",
           (unsigned long long)s->hist_count, 1e3 * median, 1e3 * s->worst_frame_s,
           (unsigned long long)s->worst_frame_index, 1e3 * s->worst_outside_s, 1e3 * stall_s,
           ps->run_s > 0 ? (double)ps->frames_rendered / ps->run_s : 0.0);
    check(s, s->hist_count > 0 && ps->frames_rendered > 0, "frames", "%llu frames rendered in %.0f s",
          (unsigned long long)ps->frames_rendered, ps->run_s);
    /* the gaps themselves are judged by tests/soak.sh from the samples (each second's most
     * outside a render stage beside the run-queue wait of that second) against this median */
    (void)worst;
}

/* ---------------------------------------------------------------- main */

static void usage(FILE *f)
{
    fputs("usage: soak_driver --seconds S --seed N --work DIR --samples FILE [--threads N] [--senders K]\n"
          "                   [--wall FILE] [-- more tessera run options]\n"
          "Runs the kiosk (tessera run --wall, headless, convert-tiles display, input on with a replay)\n"
          "in this process for S seconds under random transactions from K threads (default 3); writes\n"
          "one sample a second to FILE and prints PASS/FAIL lines (tests/soak.sh).\n",
          f);
}

int main(int argc, char **argv)
{
    soak *s = &the_soak;
    s->seconds = 3600.0;
    s->seed = 1;
    s->max_threads = 2;
    s->sender_count = 3;
    const char *work = NULL, *samples = NULL, *wall = "tests/soak/wall_2x2.json";
    int extra = argc;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--")) {
            extra = i + 1;
            break;
        } else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!v) {
            usage(stderr);
            return 2;
        } else if (!strcmp(a, "--seconds"))
            s->seconds = atof(v);
        else if (!strcmp(a, "--seed"))
            s->seed = strtoull(v, NULL, 10);
        else if (!strcmp(a, "--threads"))
            s->max_threads = atoi(v);
        else if (!strcmp(a, "--senders"))
            s->sender_count = atoi(v);
        else if (!strcmp(a, "--work"))
            work = v;
        else if (!strcmp(a, "--samples"))
            samples = v;
        else if (!strcmp(a, "--wall"))
            wall = v;
        else {
            usage(stderr);
            return 2;
        }
        i++;
    }
    if (!work || !samples || !(s->seconds >= 10.0) || s->max_threads < 1 || s->max_threads > PIPELINE_MAX_THREADS ||
        s->sender_count < 1 || s->sender_count > SOAK_MAX_SENDERS) {
        usage(stderr);
        return 2;
    }
    /* the built-in scene's size and geometries (the kiosk loads its own copy) */
    tess_error err = {{0}};
    scene *sc = scene_create_default(&err);
    if (!sc || !scene_bounds(sc, &s->scene_lo, &s->scene_hi)) {
        fprintf(stderr, "soak: built-in scene: %s\n", err.msg);
        return 1;
    }
    s->geometry_count = sc->instance_count; /* hit ids name instances (scene.h) */
    scene_destroy(sc);

    char replay[4096], absent[4096], threads[16];
    snprintf(replay, sizeof replay, "%s/replay.rec", work);
    snprintf(absent, sizeof absent, "%s/no-such-input-device", work);
    snprintf(threads, sizeof threads, "%d", s->max_threads);
    if (!write_replay(s, replay))
        return 1;
    s->samples = fopen(samples, "w");
    if (!s->samples) {
        fprintf(stderr, "soak: %s: %s\n", samples, strerror(errno));
        return 1;
    }
    /* the kiosk: run --wall as on a card, but headless (convert-tiles: render threads convert
     * each tile as the DRM display does), real time, until stopped, input on: the input thread
     * retries a missing device and /dev/null (not an input device) every second, the idle tour
     * runs, and the generated record is replayed at its times through the sink */
    const char *kiosk[64] = {"run", "--wall", wall, "--display", "convert-tiles", "--time", "real", "--frames",
                             "100000000", "--threads", threads, "--input", "on", "--input-device", absent,
                             "--input-device", "/dev/null", "--idle-timeout", "5", "--replay-input", replay,
                             "--replay-speed", "recorded"};
    int kargc = 0;
    while (kiosk[kargc])
        kargc++;
    for (int i = extra; i < argc && kargc < 63; i++)
        kiosk[kargc++] = argv[i];
    kiosk[kargc] = NULL;
    printf("soak: seed %llu, %.0f s, %d sender threads, at most %d render threads\nsoak: kiosk: tessera",
           (unsigned long long)s->seed, s->seconds, s->sender_count, s->max_threads);
    for (int i = 0; i < kargc; i++)
        printf(" %s", kiosk[i]);
    printf("\n");
    fflush(stdout);

    cli_run_hooks hooks = {.ctx = s, .started = started, .finished = finished};
    int code = cli_run_with(kargc, (char **)kiosk, &hooks);
    fclose(s->samples);
    if (!s->finished) {
        printf("FAIL kiosk: the run ended before its frame loop finished (exit code %d)\n", code);
        return code ? code : 1;
    }
    report(s);
    check(s, code == 0, "kiosk exit", "tessera run returned %d", code);
    printf("soak-driver: %d passed, %d failed\n", s->passed, s->failed);
    return s->failed ? 1 : 0;
}
