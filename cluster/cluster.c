/* cluster.c (cluster) - one wall over several processes (cluster.h). */
#define _DEFAULT_SOURCE /* gethostname */
#include "cluster/cluster.h"

#include <inttypes.h>
#include <mpi.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/clock.h"
#include "engine/log.h"
#include "engine/sample_ring.h"
#include "engine/pipeline.h"
#include "engine/txn.h"

#define FLIPS_KEPT 4096
#define SPINS_BEFORE_SLEEP 200 /* MPI_Test calls before the waiter starts sleeping between them */

/* What the leader sends every frame before its records. */
typedef struct sync_header {
    uint64_t frame;
    double time_s;
    uint32_t records; /* TXN_BINARY_BYTES each follow */
    uint32_t reserved;
} sync_header;


struct cluster {
    int rank, size;
    int leader; /* the rank that reads input and sends its records (cluster_config.leader) */
    double timeout_s;
    char (*host_names)[CLUSTER_HOST_BYTES]; /* size of them */
    const char **hosts;
    struct pipeline *p;
    /* leader: what its frame state took since the last frame sync (the record observer, in the
     * serial section; sent by the frame sync, in the serial section: no lock) */
    unsigned char *outbox;
    size_t out_records, out_capacity;
    bool out_overflow; /* out of memory for a record: the followers would differ, so the run stops */
    unsigned char *inbox; /* follower: the records of one frame */
    size_t in_capacity;
    bool failed;
    cluster_stats stats;
    sample_ring vote, send, barrier; /* the stop vote (it waits for the slowest process), the leader's
                                  header and records (everybody is there), the barrier before the flip */
    /* the display sync: when each of the last FLIPS_KEPT frames passed the barrier
     * (CLOCK_REALTIME us: one clock on one machine, NTP-close across machines) */
    uint64_t flip_frame[FLIPS_KEPT];
    int64_t flip_us[FLIPS_KEPT];
    uint64_t flips;
};

int cluster_leader(const cluster *c) { return c->leader; }

bool cluster_launched(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMIX_RANK") || getenv("PMI_SIZE");
}

static void mpi_text(int code, char *out, size_t bytes)
{
    char text[MPI_MAX_ERROR_STRING];
    int len = 0;
    if (MPI_Error_string(code, text, &len) != MPI_SUCCESS)
        len = snprintf(text, sizeof text, "MPI error %d", code);
    snprintf(out, bytes, "%.*s", len, text);
}

/* Wait for a started collective at most timeout_s; false (failed, err says
 * what was waited for) when it does not complete or MPI fails. */
static bool wait_for(cluster *c, MPI_Request *req, int started, const char *what, uint64_t frame, tess_error *err)
{
    if (started != MPI_SUCCESS) {
        char text[MPI_MAX_ERROR_STRING];
        mpi_text(started, text, sizeof text);
        c->failed = true;
        return tess_error_set(err, "cluster: rank %d: %s (frame %" PRIu64 "): %s", c->rank, what, frame, text);
    }
    double deadline = clock_monotonic_s() + c->timeout_s;
    for (int spins = 0;; spins++) {
        int done = 0, rc = MPI_Test(req, &done, MPI_STATUS_IGNORE);
        if (rc != MPI_SUCCESS) {
            char text[MPI_MAX_ERROR_STRING];
            mpi_text(rc, text, sizeof text);
            c->failed = true;
            return tess_error_set(err, "cluster: rank %d: %s (frame %" PRIu64 "): %s", c->rank, what, frame, text);
        }
        if (done)
            return true;
        if (clock_monotonic_s() > deadline) {
            c->failed = true;
            return tess_error_set(err,
                                  "cluster: rank %d: no answer from the other processes within %.1f s (%s, frame "
                                  "%" PRIu64 "): one of them died or stopped",
                                  c->rank, c->timeout_s, what, frame);
        }
        if (spins > SPINS_BEFORE_SLEEP)
            nanosleep(&(struct timespec){0, 20000}, NULL);
    }
}

/* ---- the leader's records ------------------------------------------------------------- */

/* Records naming one channel are this process's own (its outputs' hotplug, a
 * remote viewer's private view): channel numbers differ between processes. */
static bool shared_record(const txn_record *r)
{
    if (r->kind == TXN_CAMERA)
        return r->args.camera.channel == TXN_ALL_CHANNELS;
    return r->kind != TXN_CHANNEL_ACTIVE;
}

static void observe(void *ctx, const txn_record *r)
{
    cluster *c = ctx;
    if (!shared_record(r) || c->out_overflow)
        return;
    if (c->out_records == c->out_capacity) {
        size_t grown = c->out_capacity ? 2 * c->out_capacity : 64;
        unsigned char *more = realloc(c->outbox, grown * TXN_BINARY_BYTES);
        if (!more) {
            c->out_overflow = true;
            return;
        }
        c->outbox = more;
        c->out_capacity = grown;
    }
    if (txn_encode_binary(r, c->outbox + c->out_records * TXN_BINARY_BYTES))
        c->out_records++;
}

/* ---- the frame sync -------------------------------------------------------------------- */

static void frame_sync(void *ctx, struct pipeline *p, frame_info *info, bool *stop)
{
    cluster *c = ctx;
    tess_error err = {{0}};
    if (c->failed) { /* the frame with the message was rendered: now the loop stops */
        *stop = true;
        return;
    }
    double t0 = clock_monotonic_s();
    bool leader = c->rank == c->leader;
    if (leader && c->out_overflow) {
        log_error("cluster: out of memory for the frame's records: the run stops (the other processes would "
                  "render something else)");
        *stop = true;
    }
    /* whether anybody stops after this step */
    int mine = *stop ? 1 : 0, any = 0;
    MPI_Request req;
    if (!wait_for(c, &req, MPI_Iallreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD, &req), "the stop vote",
                  info->frame, &err))
        goto failed;
    double t1 = clock_monotonic_s();
    /* the leader's time and records */
    sync_header h = {0};
    if (leader)
        h = (sync_header){.frame = info->frame, .time_s = info->time_s, .records = (uint32_t)c->out_records};
    if (!wait_for(c, &req, MPI_Ibcast(&h, (int)sizeof h, MPI_BYTE, c->leader, MPI_COMM_WORLD, &req), "the frame header",
                  info->frame, &err))
        goto failed;
    size_t bytes = (size_t)h.records * TXN_BINARY_BYTES;
    if (!leader && bytes > c->in_capacity) {
        unsigned char *grown = realloc(c->inbox, bytes);
        if (!grown) {
            tess_error_set(&err, "cluster: rank %d: out of memory for %u records", c->rank, h.records);
            c->failed = true;
            goto failed; /* the leader's broadcast is left waiting: it times out too */
        }
        c->inbox = grown;
        c->in_capacity = bytes;
    }
    if (bytes && !wait_for(c, &req,
                           MPI_Ibcast(leader ? c->outbox : c->inbox, (int)bytes, MPI_BYTE, c->leader, MPI_COMM_WORLD,
                                      &req),
                           "the frame's records", info->frame, &err))
        goto failed;
    if (!leader) {
        if (h.frame != info->frame) {
            c->failed = true;
            tess_error_set(&err, "cluster: rank %d renders frame %" PRIu64 " while the leader renders %" PRIu64
                                 ": out of step",
                           c->rank, info->frame, h.frame);
            goto failed;
        }
        info->time_s = h.time_s;
        for (uint32_t i = 0; i < h.records; i++) {
            txn_record r;
            if (!txn_decode_binary(c->inbox + (size_t)i * TXN_BINARY_BYTES, &r, &err) || !pipeline_apply(p, &r)) {
                c->failed = true;
                if (!tess_error_is_set(&err))
                    tess_error_set(&err, "cluster: rank %d: the leader's record %u of frame %" PRIu64 " was refused",
                                   c->rank, i, info->frame);
                goto failed;
            }
        }
    }
    c->out_records = 0;
    c->stats.frames++;
    c->stats.records += h.records;
    c->stats.bytes += sizeof h + bytes;
    sample_ring_add(&c->vote, (t1 - t0) * 1e6);
    sample_ring_add(&c->send, (clock_monotonic_s() - t1) * 1e6);
    *stop = any != 0;
    return;
failed:
    /* the others are gone or stuck: no more syncs. This step renders one more frame, on this
     * process's own, with the reason in the status line, so the wall says why it stops; the
     * next step stops */
    log_error("%s", err.msg);
    char text[TXN_TEXT_BYTES];
    snprintf(text, sizeof text, "cluster: out of step with the other machines at frame %" PRIu64 ": this wall stops",
             info->frame);
    txn_record why = txn_status(text);
    pipeline_apply(p, &why);
    *stop = false;
}

static bool display_sync(void *ctx, uint64_t frame, tess_error *err)
{
    cluster *c = ctx;
    if (c->failed) /* nobody to wait for: the frame with the message is shown alone */
        return true;
    double t0 = clock_monotonic_s();
    MPI_Request req;
    if (!wait_for(c, &req, MPI_Ibarrier(MPI_COMM_WORLD, &req), "the barrier before the flip", frame, err))
        return false;
    sample_ring_add(&c->barrier, (clock_monotonic_s() - t0) * 1e6);
    if (frame != UINT64_MAX) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        c->flip_frame[c->flips % FLIPS_KEPT] = frame;
        c->flip_us[c->flips % FLIPS_KEPT] = (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
        c->flips++;
    }
    return true;
}

/* ---- life ------------------------------------------------------------------------------ */

/* MPI_Init has no time-out: a process that dies or stops while the others start would leave
 * them waiting in it for ever. A watchdog thread ends this process if starting takes longer
 * than the sync time-out. */
typedef struct start_watchdog {
    pthread_mutex_t lock;
    pthread_cond_t done_cond;
    bool done; /* lock */
    double timeout_s;
} start_watchdog;

static void *watch_start(void *arg)
{
    start_watchdog *w = arg;
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_sec += (time_t)w->timeout_s;
    until.tv_nsec += (long)((w->timeout_s - (double)(time_t)w->timeout_s) * 1e9);
    if (until.tv_nsec >= 1000000000L) {
        until.tv_sec++;
        until.tv_nsec -= 1000000000L;
    }
    pthread_mutex_lock(&w->lock);
    while (!w->done)
        if (pthread_cond_timedwait(&w->done_cond, &w->lock, &until) != 0 && !w->done) {
            log_error("cluster: the processes did not all start within %.1f s (one of them died or stopped "
                      "while starting): giving up",
                      w->timeout_s);
            _exit(3);
        }
    pthread_mutex_unlock(&w->lock);
    return NULL;
}

cluster *cluster_start(int *argc, char ***argv, const cluster_config *cfg, tess_error *err)
{
    double sync_s = cfg && cfg->timeout_s > 0.0 ? cfg->timeout_s : CLUSTER_DEFAULT_TIMEOUT_S;
    start_watchdog w = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, false,
                        sync_s > CLUSTER_START_TIMEOUT_S ? sync_s : CLUSTER_START_TIMEOUT_S};
    pthread_t watchdog;
    bool watching = pthread_create(&watchdog, NULL, watch_start, &w) == 0;
    int provided = 0, rc = MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided);
    if (watching) {
        pthread_mutex_lock(&w.lock);
        w.done = true;
        pthread_cond_signal(&w.done_cond);
        pthread_mutex_unlock(&w.lock);
        pthread_join(watchdog, NULL);
    }
    if (rc != MPI_SUCCESS) {
        char text[MPI_MAX_ERROR_STRING];
        mpi_text(rc, text, sizeof text);
        tess_error_set(err, "cluster: MPI_Init_thread failed: %s", text);
        return NULL;
    }
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    cluster *c = calloc(1, sizeof *c);
    if (!c) {
        tess_error_set(err, "cluster: out of memory");
        MPI_Finalize();
        return NULL;
    }
    c->timeout_s = cfg && cfg->timeout_s > 0.0 ? cfg->timeout_s : CLUSTER_DEFAULT_TIMEOUT_S;
    MPI_Comm_rank(MPI_COMM_WORLD, &c->rank);
    MPI_Comm_size(MPI_COMM_WORLD, &c->size);
    c->leader = cfg ? cfg->leader : 0;
    if (c->leader < 0 || c->leader >= c->size) {
        tess_error_set(err, "cluster: the input rank %d is not one of the %d processes (0..%d)", c->leader, c->size,
                       c->size - 1);
        cluster_finish(c);
        return NULL;
    }
    if (provided < MPI_THREAD_SERIALIZED) {
        tess_error_set(err, "cluster: this MPI gives thread level %d, below MPI_THREAD_SERIALIZED (the frame and "
                            "display syncs run on different threads)",
                       provided);
        cluster_finish(c);
        return NULL;
    }
    c->host_names = calloc((size_t)c->size, sizeof *c->host_names);
    c->hosts = calloc((size_t)c->size, sizeof *c->hosts);
    char mine[CLUSTER_HOST_BYTES] = "";
    if (gethostname(mine, sizeof mine - 1) != 0)
        snprintf(mine, sizeof mine, "unknown");
    MPI_Request req;
    if (!c->host_names || !c->hosts ||
        !wait_for(c, &req,
                  MPI_Iallgather(mine, CLUSTER_HOST_BYTES, MPI_CHAR, c->host_names, CLUSTER_HOST_BYTES, MPI_CHAR,
                                 MPI_COMM_WORLD, &req),
                  "the host names", 0, err)) {
        if (!tess_error_is_set(err))
            tess_error_set(err, "cluster: out of memory");
        cluster_finish(c);
        return NULL;
    }
    for (int i = 0; i < c->size; i++) {
        c->host_names[i][CLUSTER_HOST_BYTES - 1] = '\0';
        c->hosts[i] = c->host_names[i];
    }
    return c;
}

int cluster_rank(const cluster *c) { return c->rank; }
int cluster_size(const cluster *c) { return c->size; }
const char *const *cluster_hosts(const cluster *c) { return c->hosts; }

bool cluster_agree(cluster *c, uint64_t value, const char *what, tess_error *err)
{
    uint64_t *all = calloc((size_t)c->size, sizeof *all);
    if (!all)
        return tess_error_set(err, "cluster: out of memory");
    MPI_Request req;
    bool ok = wait_for(c, &req,
                       MPI_Iallgather(&value, 1, MPI_UINT64_T, all, 1, MPI_UINT64_T, MPI_COMM_WORLD, &req), what,
                       0, err);
    for (int i = 1; ok && i < c->size; i++)
        if (all[i] != all[0])
            ok = tess_error_set(err,
                                "cluster: %s differs: rank 0 (%s) has %016" PRIx64 ", rank %d (%s) %016" PRIx64
                                " (the same scene files and the same tessera build on every machine?)",
                                what, c->hosts[0], all[0], i, c->hosts[i], all[i]);
    free(all);
    return ok;
}

bool cluster_attach(cluster *c, struct pipeline *p, tess_error *err)
{
    c->p = p;
    bool ok = pipeline_set_frame_sync(p, frame_sync, c) && pipeline_set_display_sync(p, display_sync, c) &&
              (c->rank != c->leader || pipeline_set_record_observer(p, observe, c));
    return ok || tess_error_set(err, "cluster: the pipeline's sync hooks are taken, or it runs already");
}

cluster_stats cluster_get_stats(const cluster *c)
{
    cluster_stats s = c->stats;
    s.vote_us_median = sample_ring_median(&c->vote);
    s.vote_us_max = c->vote.max;
    s.send_us_median = sample_ring_median(&c->send);
    s.send_us_max = c->send.max;
    s.barrier_us_median = sample_ring_median(&c->barrier);
    s.barrier_us_max = c->barrier.max;
    s.failed = c->failed;
    return s;
}

void cluster_print_stats(const cluster *c, FILE *out)
{
    cluster_stats s = cluster_get_stats(c);
    fprintf(out,
            "tessera: cluster: rank %d of %d (%s): %" PRIu64 " frames in step, %" PRIu64 " records %s (%" PRIu64
            " bytes); us a frame, median (max): stop vote %.0f (%.0f), leader's records %.0f (%.0f), barrier "
            "before the flip %.0f (%.0f)%s\n",
            c->rank, c->size, c->hosts ? c->hosts[c->rank] : "?", s.frames, s.records,
            c->rank == c->leader ? "sent" : "applied", s.bytes, s.vote_us_median, s.vote_us_max, s.send_us_median,
            s.send_us_max, s.barrier_us_median, s.barrier_us_max, s.failed ? "; FAILED" : "");
}

bool cluster_flip_skew(cluster *c, cluster_skew *out, tess_error *err)
{
    *out = (cluster_skew){0};
    if (c->failed)
        return tess_error_set(err, "cluster: failed before: no skew to measure");
    /* the frames every process kept: the last min(flips, FLIPS_KEPT) of each; rank 0 compares */
    uint64_t kept = c->flips < FLIPS_KEPT ? c->flips : FLIPS_KEPT, fewest = kept;
    MPI_Request req;
    if (!wait_for(c, &req, MPI_Iallreduce(&kept, &fewest, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD, &req),
                  "the skew's frame count", 0, err))
        return false;
    size_t n = (size_t)fewest;
    int64_t *mine = malloc((n ? n : 1) * sizeof *mine), *all = NULL;
    uint64_t *frames = malloc((n ? n : 1) * sizeof *frames), *all_frames = NULL;
    bool ok = mine && frames;
    for (size_t i = 0; ok && i < n; i++) { /* oldest first */
        uint64_t k = (c->flips - n + i) % FLIPS_KEPT;
        mine[i] = c->flip_us[k];
        frames[i] = c->flip_frame[k];
    }
    if (ok && c->rank == c->leader) {
        all = malloc((n ? n : 1) * (size_t)c->size * sizeof *all);
        all_frames = malloc((n ? n : 1) * (size_t)c->size * sizeof *all_frames);
        ok = all && all_frames;
    }
    /* every process takes part in both gathers, also one out of memory (its count is then 0:
     * the leader sees frames that do not match and says so) */
    ok = wait_for(c, &req,
                  MPI_Igather(frames, (int)n, MPI_UINT64_T, all_frames, (int)n, MPI_UINT64_T, c->leader, MPI_COMM_WORLD,
                              &req),
                  "the flip frames", 0, err) &&
         wait_for(c, &req,
                  MPI_Igather(mine, (int)n, MPI_INT64_T, all, (int)n, MPI_INT64_T, c->leader, MPI_COMM_WORLD, &req),
                  "the flip times", 0, err) &&
         ok;
    if (ok && c->rank == c->leader && n > 0) {
        double *skews = malloc(n * sizeof *skews);
        size_t m = 0;
        for (size_t i = 0; skews && i < n; i++) {
            int64_t lo = all[i], hi = all[i];
            bool same = true;
            for (int r = 1; r < c->size; r++) {
                same = same && all_frames[(size_t)r * n + i] == all_frames[i];
                int64_t t = all[(size_t)r * n + i];
                lo = t < lo ? t : lo;
                hi = t > hi ? t : hi;
            }
            if (same)
                skews[m++] = (double)(hi - lo);
            else
                out->frames_out_of_step++;
        }
        if (skews && m) {
            out->frames = m;
            out->median_us = median_sorting(skews, m); /* sorts them */
            out->p95_us = skews[(size_t)((double)(m - 1) * 0.95)];
            out->max_us = skews[m - 1];
        }
        free(skews);
    }
    free(mine);
    free(frames);
    free(all);
    free(all_frames);
    return ok;
}

void cluster_finish(cluster *c)
{
    if (!c)
        return;
    if (!c->failed)
        MPI_Finalize();
    free(c->outbox);
    free(c->inbox);
    free(c->host_names);
    free(c->hosts);
    free(c);
}
