/* cluster.c (cluster) - one wall over several processes (cluster.h). */
#define _DEFAULT_SOURCE /* gethostname */
#include "cluster.h"

#include <inttypes.h>
#include <math.h>
#include <mpi.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/base/clock.h"
#include "engine/base/log.h"
#include "engine/base/sample_ring.h"
#include "engine/frame/pipeline.h"
#include "engine/frame/txn.h"

#define FLIPS_KEPT 4096
#define SPINS_BEFORE_SLEEP 200 /* MPI_Test calls before the waiter starts sleeping between them */

/* The messages of a frame, each to or from the leader (a star: the leader knows who is there). */
enum {
    TAG_VOTE = 1,  /* follower -> leader: vote_msg, in the serial section */
    TAG_FRAME,     /* leader -> follower: frame_msg then its records, in the serial section */
    TAG_READY,     /* follower -> leader: step_msg, before the flip */
    TAG_GO,        /* leader -> follower: step_msg, before the flip */
    TAG_DROPPED,   /* leader -> a follower it gave up on: step_msg; the follower must stop */
    TAG_PLAN,      /* leader -> follower: plan_msg, in the serial section (a governed wall) */
    TAG_COUNT
};

typedef struct vote_msg {
    uint64_t frame;
    uint32_t stop; /* 1: this process stops after the step */
    uint32_t reserved;
    governor_cost cost; /* what its previous step cost (pipeline_step_cost) */
} vote_msg;

/* The governor's plan of a frame (a governed wall: every process renders it alike). */
typedef struct plan_msg {
    uint64_t frame;
    int32_t kind, rung, stratum, samples; /* governor_frame */
} plan_msg;

/* What the leader sends every frame before its records. */
typedef struct frame_msg {
    uint64_t frame;
    double time_s;
    uint32_t records;    /* TXN_BINARY_BYTES each follow in the same message */
    uint32_t flags;      /* FRAME_STOP, FRAME_FAILED */
    uint32_t nodes_lost; /* machines the leader has given up on so far */
    uint32_t reserved;
} frame_msg;
#define FRAME_STOP 1u   /* every process stops after this step */
#define FRAME_FAILED 2u /* a node was lost and the wall stops: render this frame (its status line says why), then stop */

typedef struct step_msg {
    uint64_t step; /* display syncs so far (READY, GO) or the frame (DROPPED) */
} step_msg;

/* One message in flight to a peer: its own copy of the bytes until MPI is done with them. */
typedef struct send_slot {
    MPI_Request req;
    unsigned char *buf;
    size_t capacity;
} send_slot;

typedef struct peer {
    bool lost;                  /* stopped answering, or out of step: no more messages to or from it */
    bool pending;               /* gather: its message has not come yet */
    send_slot slots[TAG_COUNT]; /* by tag; a lost peer's stay MPI's (never reused) until cluster_finish */
    void *dropped_note;         /* leader: the DROPPED message sent to it once lost (MPI's until cluster_finish) */
} peer;

struct cluster {
    int rank, size;
    int leader; /* the rank that reads input and sends its records (cluster_config.leader) */
    double timeout_s;
    cluster_on_loss on_loss;
    char (*host_names)[CLUSTER_HOST_BYTES]; /* size of them */
    const char **hosts;
    peer *peers;                            /* size of them (this process's own unused) */
    struct pipeline *p;
    /* leader: what its frame state took since the last frame sync (the record observer, in the
     * serial section; sent by the frame sync, in the serial section: no lock) */
    unsigned char *outbox;
    size_t out_records, out_capacity;
    bool out_overflow; /* out of memory for a record: the followers would differ, so the run stops */
    unsigned char *inbox; /* follower: one frame's message */
    size_t in_capacity;
    bool failed;       /* this process stops: it renders one more frame with the reason, then the loop ends */
    bool alone;        /* a follower that lost its leader and carries on (CLUSTER_CARRY_ON): no more syncs */
    char untold[TXN_TEXT_BYTES]; /* why this process stops or is alone, for the next frame's status line */
    int newly_lost;    /* leader: followers lost since the last frame sync (said in the status line then) */
    uint64_t display_steps; /* display syncs so far: READY and GO carry it */
    cluster_stats stats;
    sample_ring vote, send, barrier; /* see cluster_stats */
    /* the display sync: when each of the last FLIPS_KEPT frames passed the barrier
     * (CLOCK_REALTIME us: one clock on one machine, NTP-close across machines) */
    uint64_t flip_frame[FLIPS_KEPT];
    int64_t flip_us[FLIPS_KEPT];
    /* and when the display reported them on screen (cluster_note_scanout): the first and
     * the last of this process's outputs, CLOCK_REALTIME us; 0 while not reported */
    int64_t scan_first_us[FLIPS_KEPT], scan_last_us[FLIPS_KEPT];
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

static void pause_after(int spins)
{
    if (spins > SPINS_BEFORE_SLEEP)
        nanosleep(&(struct timespec){0, 20000}, NULL);
}

/* Wait for a started collective (start, agree, skew) at most timeout_s; false
 * (failed, err says what was waited for) when it does not complete or MPI fails. */
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
        pause_after(spins);
    }
}

/* ---- messages to and from peers -------------------------------------------------------- */

/* Give up on peer r: no more messages to or from it. Its sends in flight are
 * left to MPI with their buffers (freed only by cluster_finish, after the
 * last MPI call: MPI may read them until then). */
static void lose_peer(cluster *c, int r, const char *what, uint64_t frame)
{
    peer *q = &c->peers[r];
    if (q->lost)
        return;
    q->lost = true;
    for (int t = 0; t < TAG_COUNT; t++)
        if (q->slots[t].req != MPI_REQUEST_NULL)
            MPI_Request_free(&q->slots[t].req); /* the buffer stays: post() never sends to a lost peer */
    c->stats.nodes_lost++;
    log_error("cluster: rank %d lost rank %d (%s) at frame %" PRIu64 " (%s; time-out %.1f s): %s", c->rank, r,
              c->hosts[r], frame, what, c->rank == c->leader ? c->timeout_s : 2.0 * c->timeout_s,
              c->rank != c->leader             ? "the leader is gone"
              : c->on_loss == CLUSTER_CARRY_ON ? "the wall carries on without its outputs"
                                               : "the wall stops");
    if (c->rank != c->leader)
        return;
    c->newly_lost++;
    /* if it was only stopped or slow, it reads this when it comes back and stops rather than
     * show a stale picture */
    step_msg *note = malloc(sizeof *note);
    MPI_Request req;
    if (note) {
        note->step = frame;
        if (MPI_Isend(note, (int)sizeof *note, MPI_BYTE, r, TAG_DROPPED, MPI_COMM_WORLD, &req) == MPI_SUCCESS)
            MPI_Request_free(&req);
        q->dropped_note = note;
    }
}

/* Send len bytes to peer r (tag), copied: the caller's buffer is free again on
 * return. The slot's previous message must have left within the time-out, or
 * the peer is lost (false). */
static bool post(cluster *c, int r, int tag, const void *data, size_t len, uint64_t frame)
{
    peer *q = &c->peers[r];
    if (q->lost)
        return false;
    send_slot *sl = &q->slots[tag];
    double deadline = clock_monotonic_s() + c->timeout_s;
    for (int spins = 0; sl->req != MPI_REQUEST_NULL; spins++) {
        int done = 0;
        if (MPI_Test(&sl->req, &done, MPI_STATUS_IGNORE) != MPI_SUCCESS || (!done && clock_monotonic_s() > deadline)) {
            lose_peer(c, r, "taking the last message", frame);
            return false;
        }
        if (!done)
            pause_after(spins);
    }
    if (len > sl->capacity) {
        unsigned char *grown = realloc(sl->buf, len);
        if (!grown) {
            lose_peer(c, r, "out of memory for a message", frame);
            return false;
        }
        sl->buf = grown;
        sl->capacity = len;
    }
    memcpy(sl->buf, data, len);
    if (MPI_Isend(sl->buf, (int)len, MPI_BYTE, r, tag, MPI_COMM_WORLD, &sl->req) != MPI_SUCCESS) {
        sl->req = MPI_REQUEST_NULL;
        lose_peer(c, r, "sending", frame);
        return false;
    }
    return true;
}

/* Receive the message (tag) waiting from peer r into *buf (grown as needed);
 * its size; -1 on an MPI error or no memory. */
static long take(int r, int tag, unsigned char **buf, size_t *capacity)
{
    MPI_Status st;
    int count = 0;
    if (MPI_Probe(r, tag, MPI_COMM_WORLD, &st) != MPI_SUCCESS || MPI_Get_count(&st, MPI_BYTE, &count) != MPI_SUCCESS ||
        count < 0)
        return -1;
    if ((size_t)count > *capacity) {
        unsigned char *grown = realloc(*buf, (size_t)count);
        if (!grown)
            return -1;
        *buf = grown;
        *capacity = (size_t)count;
    }
    if (MPI_Recv(*buf, count, MPI_BYTE, r, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE) != MPI_SUCCESS)
        return -1;
    return count;
}

/* Votes merged: any stop, the slowest process's costs. */
static void merge_vote(vote_msg *into, const vote_msg *v)
{
    into->stop |= v->stop;
    into->cost.step_s = fmax(into->cost.step_s, v->cost.step_s);
    into->cost.render_s = fmax(into->cost.render_s, v->cost.render_s);
    into->cost.upscale_s = fmax(into->cost.upscale_s, v->cost.upscale_s);
}

/* Leader: one message (tag, exactly `len` bytes, starting with a uint64_t
 * equal to `expect`) from every follower not lost, within the time-out; the
 * ones that do not send it are lost. Votes are merged into *votes when given. */
static void gather(cluster *c, int tag, size_t len, uint64_t expect, const char *what, uint64_t frame,
                   vote_msg *votes)
{
    int left = 0;
    for (int r = 0; r < c->size; r++) {
        c->peers[r].pending = r != c->rank && !c->peers[r].lost;
        left += c->peers[r].pending;
    }
    double deadline = clock_monotonic_s() + c->timeout_s;
    for (int spins = 0; left > 0; spins++) {
        for (int r = 0; r < c->size; r++) {
            if (!c->peers[r].pending)
                continue;
            int here = 0;
            if (MPI_Iprobe(r, tag, MPI_COMM_WORLD, &here, MPI_STATUS_IGNORE) != MPI_SUCCESS) {
                lose_peer(c, r, what, frame);
            } else if (here) {
                long got = take(r, tag, &c->inbox, &c->in_capacity);
                uint64_t said = 0;
                if (got == (long)len)
                    memcpy(&said, c->inbox, sizeof said);
                if (got != (long)len || said != expect) {
                    log_error("cluster: rank %d (%s) is out of step (%s: %" PRIu64 ", here %" PRIu64 ")", r,
                              c->hosts[r], what, said, expect);
                    lose_peer(c, r, what, frame);
                } else if (votes) {
                    vote_msg v;
                    memcpy(&v, c->inbox, sizeof v);
                    merge_vote(votes, &v);
                }
            } else {
                continue;
            }
            c->peers[r].pending = false;
            left--;
        }
        if (left > 0 && clock_monotonic_s() > deadline)
            for (int r = 0; r < c->size; r++)
                if (c->peers[r].pending) {
                    lose_peer(c, r, what, frame);
                    c->peers[r].pending = false;
                    left--;
                }
        if (left > 0)
            pause_after(spins);
    }
}

/* Follower: the leader's next message of `tag` into c->inbox; its size, or -1
 * when it does not come within twice the time-out (or MPI fails), or -2 when
 * the leader said this process was dropped. Twice: when another follower
 * dies the leader gives up on it after one time-out, and its verdict (stop,
 * or carry on) must reach this process before it blames the leader. */
static long await_leader(cluster *c, int tag)
{
    double deadline = clock_monotonic_s() + 2.0 * c->timeout_s;
    for (int spins = 0;; spins++) {
        int here = 0, dropped = 0;
        if (MPI_Iprobe(c->leader, TAG_DROPPED, MPI_COMM_WORLD, &dropped, MPI_STATUS_IGNORE) != MPI_SUCCESS ||
            MPI_Iprobe(c->leader, tag, MPI_COMM_WORLD, &here, MPI_STATUS_IGNORE) != MPI_SUCCESS)
            return -1;
        if (dropped)
            return -2;
        if (here)
            return take(c->leader, tag, &c->inbox, &c->in_capacity);
        if (clock_monotonic_s() > deadline)
            return -1;
        pause_after(spins);
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
        unsigned char *more = realloc(c->outbox, sizeof(frame_msg) + grown * TXN_BINARY_BYTES);
        if (!more) {
            c->out_overflow = true;
            return;
        }
        c->outbox = more;
        c->out_capacity = grown;
    }
    if (txn_encode_binary(r, c->outbox + sizeof(frame_msg) + c->out_records * TXN_BINARY_BYTES))
        c->out_records++;
}

/* ---- the frame sync -------------------------------------------------------------------- */

/* Put `text` in this process's status line (on the leader also sent: the observer takes it). */
static void say(struct pipeline *p, const char *text)
{
    txn_record why = txn_status(text);
    pipeline_apply(p, &why);
}

static void leader_frame_sync(cluster *c, struct pipeline *p, frame_info *info, bool *stop)
{
    double t0 = clock_monotonic_s();
    if (c->out_overflow) {
        log_error("cluster: out of memory for the frame's records: the run stops (the other processes would "
                  "render something else)");
        *stop = true;
    }
    vote_msg votes = {.frame = info->frame, .stop = *stop ? 1u : 0u, .cost = pipeline_step_cost(p)};
    gather(c, TAG_VOTE, sizeof(vote_msg), info->frame, "the stop vote", info->frame, &votes);
    bool any = votes.stop != 0;
    if (pipeline_governed(p)) /* the governor plans for the slowest process (its pixels are this one's) */
        pipeline_set_step_cost(p, &votes.cost);
    double t1 = clock_monotonic_s();
    uint32_t flags = any ? FRAME_STOP : 0u;
    if (c->newly_lost > 0) {
        char text[TXN_TEXT_BYTES];
        if (c->on_loss == CLUSTER_CARRY_ON) {
            snprintf(text, sizeof text, "cluster: %" PRIu64 " machine%s lost at frame %" PRIu64 ": the wall carries on",
                     c->stats.nodes_lost, c->stats.nodes_lost == 1 ? "" : "s", info->frame);
        } else {
            snprintf(text, sizeof text, "cluster: a machine was lost at frame %" PRIu64 ": this wall stops",
                     info->frame);
            flags = FRAME_FAILED;
            c->failed = true;
        }
        say(p, text); /* into the outbox: the others show it too */
        c->newly_lost = 0;
    }
    frame_msg h = {.frame = info->frame, .time_s = info->time_s, .records = (uint32_t)c->out_records,
                   .flags = flags, .nodes_lost = (uint32_t)c->stats.nodes_lost};
    size_t bytes = sizeof h + c->out_records * TXN_BINARY_BYTES;
    if (!c->outbox && !(c->outbox = malloc(sizeof h))) { /* no record yet: room for the header */
        log_error("cluster: out of memory for the frame header: the run stops");
        *stop = true;
        return;
    }
    memcpy(c->outbox, &h, sizeof h);
    for (int r = 0; r < c->size; r++) /* one that cannot take it is lost (said next frame) */
        if (r != c->rank && !c->peers[r].lost)
            post(c, r, TAG_FRAME, c->outbox, bytes, info->frame);
    c->out_records = 0;
    c->stats.frames++;
    c->stats.records += h.records;
    c->stats.bytes += bytes;
    sample_ring_add(&c->vote, (t1 - t0) * 1e6);
    sample_ring_add(&c->send, (clock_monotonic_s() - t1) * 1e6);
    *stop = c->failed ? false : any; /* failed: one more frame, with the message; the next step stops */
}

/* A follower that did not get the leader's message at `where` (got: await_leader's -1, or -2
 * when the leader had dropped this process): log why, and leave the status line's text for the
 * next frame (c->untold). */
static void leader_silent(cluster *c, long got, const char *where, uint64_t frame)
{
    if (got == -2) { /* the others went on without this process: its picture would be out of step */
        log_error("cluster: rank %d: the leader gave up waiting for this process at frame %" PRIu64
                  " (%s; it was stopped or too slow): this part of the wall stops",
                  c->rank, frame, where);
        snprintf(c->untold, sizeof c->untold, "cluster: this machine fell behind the wall at frame %" PRIu64
                 ": it stops", frame);
        c->failed = true;
        return;
    }
    lose_peer(c, c->leader, where, frame);
    if (c->on_loss == CLUSTER_CARRY_ON) {
        c->alone = true;
        snprintf(c->untold, sizeof c->untold,
                 "cluster: the leader (input) was lost at frame %" PRIu64 ": this part of the wall carries on", frame);
    } else {
        c->failed = true;
        snprintf(c->untold, sizeof c->untold,
                 "cluster: out of step with the other machines at frame %" PRIu64 ": this wall stops", frame);
    }
}

/* Put c->untold in the status line: this step renders it; a process that failed stops after it. */
static void tell(cluster *c, struct pipeline *p, bool *stop)
{
    say(p, c->untold);
    c->untold[0] = '\0';
    if (c->failed)
        *stop = false; /* one more frame, with the message; the next frame sync stops */
}

static void follower_frame_sync(cluster *c, struct pipeline *p, frame_info *info, bool *stop)
{
    double t0 = clock_monotonic_s();
    vote_msg v = {.frame = info->frame, .stop = *stop ? 1u : 0u, .cost = pipeline_step_cost(p)};
    long got = post(c, c->leader, TAG_VOTE, &v, sizeof v, info->frame) ? await_leader(c, TAG_FRAME) : -1;
    double t1 = clock_monotonic_s();
    if (got < 0) {
        leader_silent(c, got, "the leader's frame", info->frame);
        tell(c, p, stop);
        return;
    }
    frame_msg h;
    const char *wrong = NULL;
    if ((size_t)got < sizeof h)
        wrong = "a short frame message";
    if (!wrong) {
        memcpy(&h, c->inbox, sizeof h);
        if ((size_t)got != sizeof h + (size_t)h.records * TXN_BINARY_BYTES)
            wrong = "a frame message of the wrong size";
        else if (h.frame != info->frame)
            wrong = "another frame";
    }
    tess_error err = {{0}};
    for (uint32_t i = 0; !wrong && i < h.records; i++) {
        txn_record r;
        if (!txn_decode_binary(c->inbox + sizeof h + (size_t)i * TXN_BINARY_BYTES, &r, &err) ||
            !pipeline_apply(p, &r))
            wrong = "a record this process refused";
    }
    if (wrong) {
        log_error("cluster: rank %d at frame %" PRIu64 ": the leader sent %s%s%s: this wall stops", c->rank,
                  info->frame, wrong, err.msg[0] ? ": " : "", err.msg);
        snprintf(c->untold, sizeof c->untold,
                 "cluster: out of step with the other machines at frame %" PRIu64 ": this wall stops", info->frame);
        c->failed = true;
        tell(c, p, stop);
        return;
    }
    info->time_s = h.time_s;
    if (h.nodes_lost > c->stats.nodes_lost)
        c->stats.nodes_lost = h.nodes_lost;
    c->stats.frames++;
    c->stats.records += h.records;
    c->stats.bytes += (uint64_t)got;
    sample_ring_add(&c->vote, (t1 - t0) * 1e6);
    sample_ring_add(&c->send, (clock_monotonic_s() - t1) * 1e6);
    if (h.flags & FRAME_FAILED) { /* the leader's message is among the records */
        c->failed = true;
        *stop = false;
        return;
    }
    *stop = (h.flags & FRAME_STOP) != 0;
}

static void frame_sync(void *ctx, struct pipeline *p, frame_info *info, bool *stop)
{
    cluster *c = ctx;
    if (c->untold[0]) { /* the display sync found the leader gone or this process dropped */
        tell(c, p, stop);
        return;
    }
    if (c->failed) { /* the frame with the message was rendered: now the loop stops */
        *stop = true;
        return;
    }
    if (c->alone)
        return;
    if (c->rank == c->leader)
        leader_frame_sync(c, p, info, stop);
    else
        follower_frame_sync(c, p, info, stop);
}

/* A governed wall: the leader's plan for every process. */
static void plan_sync(void *ctx, uint64_t frame, governor_frame *plan)
{
    cluster *c = ctx;
    if (c->failed || c->alone || c->untold[0])
        return;
    if (c->rank == c->leader) {
        plan_msg m = {frame, (int32_t)plan->kind, plan->rung, plan->stratum, plan->samples};
        for (int r = 0; r < c->size; r++)
            if (r != c->rank && !c->peers[r].lost)
                post(c, r, TAG_PLAN, &m, sizeof m, frame);
    } else {
        long got = await_leader(c, TAG_PLAN);
        plan_msg m;
        if (got != (long)sizeof m || (memcpy(&m, c->inbox, sizeof m), m.frame != frame) || m.kind < 0 ||
            m.kind > GOVERNOR_FRAME_IDLE || m.rung < 0 || m.rung >= GOVERNOR_RUNGS) {
            leader_silent(c, got == -2 ? -2 : -1, "the governor's plan", frame); /* said next frame */
            return;
        }
        *plan = (governor_frame){(governor_frame_kind)m.kind, m.rung, m.stratum, m.samples};
    }
    log_debug("cluster: rank %d frame %" PRIu64 ": plan kind %d rung %d stratum %d", c->rank, frame, (int)plan->kind,
              plan->rung, plan->stratum);
}

/* The barrier before the flip: every follower says it is READY, then the leader says GO. */
static bool display_sync(void *ctx, uint64_t frame, tess_error *err)
{
    (void)err; /* never fails the display: a lost leader or a drop is said on the next frame */
    cluster *c = ctx;
    if (c->failed || c->alone) /* nobody to wait for */
        return true;
    double t0 = clock_monotonic_s();
    step_msg m = {.step = ++c->display_steps};
    if (c->rank == c->leader) {
        gather(c, TAG_READY, sizeof m, m.step, "the barrier before the flip", frame, NULL);
        for (int r = 0; r < c->size; r++)
            if (r != c->rank && !c->peers[r].lost)
                post(c, r, TAG_GO, &m, sizeof m, frame);
    } else {
        long got = post(c, c->leader, TAG_READY, &m, sizeof m, frame) ? await_leader(c, TAG_GO) : -1;
        uint64_t said = 0;
        if (got == (long)sizeof m)
            memcpy(&said, c->inbox, sizeof said);
        if (got != (long)sizeof m || said != m.step) { /* the frame is shown; the next one says why */
            leader_silent(c, got == -2 ? -2 : -1, "the barrier before the flip", frame);
            return true;
        }
    }
    sample_ring_add(&c->barrier, (clock_monotonic_s() - t0) * 1e6);
    if (frame != UINT64_MAX) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        c->flip_frame[c->flips % FLIPS_KEPT] = frame;
        c->flip_us[c->flips % FLIPS_KEPT] = (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
        c->scan_first_us[c->flips % FLIPS_KEPT] = c->scan_last_us[c->flips % FLIPS_KEPT] = 0;
        c->flips++;
    }
    return true;
}

void cluster_note_scanout(cluster *c, uint64_t frame, int64_t realtime_us)
{
    /* the flip of frame F completes after F's display sync, before a few more have passed */
    for (uint64_t back = 1; back <= 8 && back <= c->flips; back++) {
        uint64_t k = (c->flips - back) % FLIPS_KEPT;
        if (c->flip_frame[k] != frame)
            continue;
        if (!c->scan_first_us[k] || realtime_us < c->scan_first_us[k])
            c->scan_first_us[k] = realtime_us;
        if (realtime_us > c->scan_last_us[k])
            c->scan_last_us[k] = realtime_us;
        return;
    }
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
    c->on_loss = cfg ? cfg->on_loss : CLUSTER_STOP;
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
    c->peers = calloc((size_t)c->size, sizeof *c->peers);
    for (int r = 0; c->peers && r < c->size; r++)
        for (int t = 0; t < TAG_COUNT; t++)
            c->peers[r].slots[t].req = MPI_REQUEST_NULL; /* not all-bits-zero in OpenMPI */
    char mine[CLUSTER_HOST_BYTES] = "";
    if (gethostname(mine, sizeof mine - 1) != 0)
        snprintf(mine, sizeof mine, "unknown");
    MPI_Request req;
    if (!c->host_names || !c->hosts || !c->peers ||
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
              (!pipeline_governed(p) || pipeline_set_plan_sync(p, plan_sync, c)) &&
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
    s.alone = c->alone;
    return s;
}

void cluster_print_stats(const cluster *c, FILE *out)
{
    cluster_stats s = cluster_get_stats(c);
    fprintf(out,
            "tessera: cluster: rank %d of %d (%s): %" PRIu64 " frames in step, %" PRIu64 " records %s (%" PRIu64
            " bytes); us a frame, median (max): stop vote %.0f (%.0f), leader's records %.0f (%.0f), barrier "
            "before the flip %.0f (%.0f)%s%s\n",
            c->rank, c->size, c->hosts ? c->hosts[c->rank] : "?", s.frames, s.records,
            c->rank == c->leader ? "sent" : "applied", s.bytes, s.vote_us_median, s.vote_us_max, s.send_us_median,
            s.send_us_max, s.barrier_us_median, s.barrier_us_max, s.failed ? "; FAILED" : "",
            s.failed  ? ""
            : s.alone ? "; carried on alone (the leader was lost)"
            : s.nodes_lost ? "; carried on without a lost machine"
                           : "");
}

/* Over the n frames of every process (all_*[r * n + i]: process r's frame i):
 * how far apart the processes' times of one frame are, max(hi) - min(lo), for
 * the frames every process numbered alike and timed (lo != 0). */
static void spread_of(const uint64_t *all_frames, const int64_t *lo, const int64_t *hi, size_t n, int size,
                      cluster_spread *out)
{
    double *spreads = malloc((n ? n : 1) * sizeof *spreads);
    size_t m = 0;
    for (size_t i = 0; spreads && i < n; i++) {
        int64_t first = lo[i], last = hi[i];
        bool same = true, timed = lo[i] != 0;
        for (int r = 1; r < size; r++) {
            size_t k = (size_t)r * n + i;
            same = same && all_frames[k] == all_frames[i];
            timed = timed && lo[k] != 0;
            first = lo[k] < first ? lo[k] : first;
            last = hi[k] > last ? hi[k] : last;
        }
        if (!same)
            out->frames_out_of_step++;
        else if (timed)
            spreads[m++] = (double)(last - first);
    }
    if (spreads && m) {
        out->frames = m;
        out->median_us = median_sorting(spreads, m); /* sorts them */
        out->p95_us = spreads[(size_t)((double)(m - 1) * 0.95)];
        out->max_us = spreads[m - 1];
    }
    free(spreads);
}

bool cluster_flip_skew(cluster *c, cluster_skew *out, tess_error *err)
{
    *out = (cluster_skew){{0}, {0}};
    if (c->failed || c->alone || c->stats.nodes_lost > 0)
        return tess_error_set(err, "cluster: a machine was lost: no skew to measure");
    /* the frames every process kept: the last min(flips, FLIPS_KEPT) of each; rank 0 compares */
    uint64_t kept = c->flips < FLIPS_KEPT ? c->flips : FLIPS_KEPT, fewest = kept;
    MPI_Request req;
    if (!wait_for(c, &req, MPI_Iallreduce(&kept, &fewest, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD, &req),
                  "the skew's frame count", 0, err))
        return false;
    size_t n = (size_t)fewest;
    /* mine: n barrier times, then n first and n last scan-out times */
    int64_t *mine = malloc((n ? 3 * n : 1) * sizeof *mine), *all = NULL;
    uint64_t *frames = malloc((n ? n : 1) * sizeof *frames), *all_frames = NULL;
    bool ok = mine && frames;
    for (size_t i = 0; ok && i < n; i++) { /* oldest first */
        uint64_t k = (c->flips - n + i) % FLIPS_KEPT;
        mine[i] = c->flip_us[k];
        mine[n + i] = c->scan_first_us[k];
        mine[2 * n + i] = c->scan_last_us[k];
        frames[i] = c->flip_frame[k];
    }
    if (ok && c->rank == c->leader) {
        all = malloc((n ? 3 * n : 1) * (size_t)c->size * sizeof *all);
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
                  MPI_Igather(mine, (int)(3 * n), MPI_INT64_T, all, (int)(3 * n), MPI_INT64_T, c->leader,
                              MPI_COMM_WORLD, &req),
                  "the flip times", 0, err) &&
         ok;
    if (ok && c->rank == c->leader && n > 0) {
        int64_t *barrier = malloc(n * (size_t)c->size * sizeof *barrier);
        int64_t *first = malloc(n * (size_t)c->size * sizeof *first);
        int64_t *last = malloc(n * (size_t)c->size * sizeof *last);
        for (int r = 0; barrier && first && last && r < c->size; r++) /* [r][kind][i] -> [kind][r][i] */
            for (size_t i = 0; i < n; i++) {
                barrier[(size_t)r * n + i] = all[(size_t)r * 3 * n + i];
                first[(size_t)r * n + i] = all[(size_t)r * 3 * n + n + i];
                last[(size_t)r * n + i] = all[(size_t)r * 3 * n + 2 * n + i];
            }
        if (barrier && first && last) {
            spread_of(all_frames, barrier, barrier, n, c->size, &out->barrier);
            spread_of(all_frames, first, last, n, c->size, &out->scanout);
        }
        free(barrier);
        free(first);
        free(last);
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
    /* after a loss MPI cannot be finalised: it would wait for the lost (over TCP it hangs) */
    bool whole = !c->failed && !c->alone && c->stats.nodes_lost == 0;
    for (int r = 0; whole && c->peers && r < c->size; r++)
        for (int t = 0; t < TAG_COUNT; t++)
            if (c->peers[r].slots[t].req != MPI_REQUEST_NULL)
                whole = wait_for(c, &c->peers[r].slots[t].req, MPI_SUCCESS, "the last messages", c->stats.frames,
                                 &(tess_error){{0}});
    if (whole)
        MPI_Finalize();
    /* MPI is done with (or, after a loss, no longer called for) every buffer: no MPI call follows */
    for (int r = 0; c->peers && r < c->size; r++) {
        for (int t = 0; t < TAG_COUNT; t++)
            free(c->peers[r].slots[t].buf);
        free(c->peers[r].dropped_note);
    }
    free(c->peers);
    free(c->outbox);
    free(c->inbox);
    free(c->host_names);
    free(c->hosts);
    free(c);
}
