/* cluster.h (cluster) - one wall over several processes, one a machine
 * (OpenMPI: `mpirun -np N tessera run --wall W.json`, the wall file's
 * "nodes" saying which outputs each drives). Every process loads the scene
 * and builds its accel itself and renders its own outputs with its own
 * threads; they meet twice a frame:
 *
 *   Every message goes to or from the LEADER (rank 0 unless configured: it
 *   reads input), a star of point-to-point messages, so the leader always
 *   knows who is there and no collective waits for a process that is gone.
 *
 *   FRAME SYNC (the serial section, pipeline.h: the frame sync hook). Each
 *   FOLLOWER (every other process) sends its stop vote; the leader, once it
 *   has every vote, sends each the step's frame number and time, whether
 *   everybody stops after the step (any process that stops -- quit on the
 *   leader, SIGTERM, a display that failed -- stops all at the same step),
 *   and what changed its frame state this step as data records (txn.h,
 *   binary form); the followers apply the same records at the same frame,
 *   so all render the same state. Records that name a channel (a camera or
 *   a switch of one channel: an output's hotplug, a remote viewer's private
 *   view) are the process's own and are not sent. Followers run no camera
 *   path or tour of their own: the leader's cameras arrive as records.
 *
 *   PLAN SYNC (a governed pipeline: --budget-ms; pipeline.h). The leader's
 *   governor plans each frame for the slowest process (the votes carry
 *   each follower's step costs) and sends the plan; the followers render
 *   it instead of their own.
 *
 *   DISPLAY SYNC (the display thread, before the flips: pipeline.h: the
 *   display sync hook). A barrier: the followers say READY, the leader says
 *   GO, so every process flips the same frame at the same time (Tide's
 *   software swap sync).
 *
 * FAILURE. Every wait has a time-out: the leader waits timeout_s for a
 * follower, a follower twice that for the leader (so the leader's verdict on
 * another follower reaches it first). A follower that does not answer is
 * LOST: the leader tells the others through the records (a status line),
 * and cluster_config.on_loss decides: CLUSTER_STOP renders one more frame
 * everywhere with the reason in the status line and ends the run (status 3;
 * mpirun then ends the job); CLUSTER_CARRY_ON goes on without it (its
 * outputs dark or frozen: they are its machine's). A lost follower that
 * comes back (it was stopped, or slow) finds the leader's DROPPED message
 * and stops rather than show a picture out of step. A follower that loses
 * the leader stops (CLUSTER_STOP) or goes on alone without input
 * (CLUSTER_CARRY_ON). MPI_Init has no time-out of its own: a watchdog
 * thread ends the process (status 3) when starting takes longer than
 * CLUSTER_START_TIMEOUT_S (or the sync time-out, when longer). After a loss
 * MPI is not finalised (it would wait for the lost; over TCP it hangs).
 *
 * START. cluster_agree compares one value (the accel's checksum) across the
 * processes before the run: a mismatch (a different scene file, a different
 * build) refuses to run, naming the ranks that differ.
 *
 * Threading: MPI is initialised for MPI_THREAD_SERIALIZED: the frame sync
 * runs on whichever render thread runs the serial section, the display sync
 * on the display thread, start and finish on the main thread, never two at
 * once (the frame barrier orders them). The stats are written by those and
 * read after the run. */
#ifndef TESSERA_CLUSTER_CLUSTER_H
#define TESSERA_CLUSTER_CLUSTER_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "engine/base/err.h"

struct pipeline;

#define CLUSTER_DEFAULT_TIMEOUT_S 10.0
/* MPI_Init's watchdog: at least this long (starting many processes on a loaded or slow machine,
 * under a sanitizer, takes seconds), or the sync time-out when that is longer */
#define CLUSTER_START_TIMEOUT_S 60.0
#define CLUSTER_HOST_BYTES 64

typedef struct cluster cluster;

/* What the others do when a machine stops answering (--on-node-loss). */
typedef enum cluster_on_loss {
    CLUSTER_STOP,     /* every process shows why for one frame and exits (status 3) */
    CLUSTER_CARRY_ON, /* the others go on in step; the lost machine's outputs stay dark (or frozen);
                       * needs `mpirun --enable-recovery` (else mpirun ends the job when a process dies) */
} cluster_on_loss;

typedef struct cluster_config {
    double timeout_s; /* how long the leader waits for a follower at a sync point (a follower waits twice
                       * as long for the leader); 0: the default */
    int leader;       /* the rank that reads input and leads (0..size-1; default 0) */
    cluster_on_loss on_loss;
} cluster_config;

/* Whether this process was started by mpirun (OpenMPI or PMIx set the
 * environment). Pure: no MPI call. */
bool cluster_launched(void);

/* MPI_Init_thread (MPI_THREAD_SERIALIZED), errors returned rather than
 * aborting, every rank's host name gathered. NULL with err. Once a process. */
cluster *cluster_start(int *argc, char ***argv, const cluster_config *cfg, tess_error *err);

int cluster_rank(const cluster *c);
/* The LEADER: the rank that reads input (cluster_config.leader). */
int cluster_leader(const cluster *c);
int cluster_size(const cluster *c);
/* Every rank's host name (cluster_size of them), as gethostname said. */
const char *const *cluster_hosts(const cluster *c);

/* Whether every process passed the same `value`: false with err naming
 * `what`, the values and the ranks when they differ (or when one does not
 * answer in time). A collective: every process calls it. */
bool cluster_agree(cluster *c, uint64_t value, const char *what, tess_error *err);

/* Put the frame and display syncs on p (and on the leader the record
 * observer), before pipeline_run. False with err. */
bool cluster_attach(cluster *c, struct pipeline *p, tess_error *err);

/* What the run cost: per frame, in microseconds (medians of the last 1024):
 * on the leader the wait for every follower's vote (it waits for the
 * slowest) and the sending of the header and records to each; on a follower
 * the wait for the leader's frame message (from its vote on, so the slowest
 * process's lag too) and applying it; on both the barrier before the flip.
 * Records and bytes the leader sent (or a follower applied). */
typedef struct cluster_stats {
    uint64_t frames;            /* frame syncs */
    uint64_t records, bytes;    /* sent (leader) or applied (follower) */
    double vote_us_median, vote_us_max; /* leader: every vote in; follower: the leader's frame message in */
    double send_us_median, send_us_max; /* leader: sending it to each follower; follower: applying it */
    double barrier_us_median, barrier_us_max;
    bool failed;                /* this process stops for a lost machine, or MPI failed */
    bool alone;                 /* a follower that lost the leader and carried on (CLUSTER_CARRY_ON) */
    uint64_t nodes_lost;        /* machines given up on (the leader's count, as the followers heard it) */
} cluster_stats;
cluster_stats cluster_get_stats(const cluster *c);
void cluster_print_stats(const cluster *c, FILE *out);

/* A display that knows when a frame reached the screen (DRM: the vblank of
 * its page flip) tells the cluster, once per output: `realtime_us` is that
 * moment on CLOCK_REALTIME. Call on the display thread (it writes what the
 * display sync writes), within 8 frames of the frame's display sync. */
void cluster_note_scanout(cluster *c, uint64_t frame, int64_t realtime_us);

/* FLIP SKEW: how far apart the processes passed the barrier before the flip
 * of one frame, and (when the display reported them) how far apart the
 * frame's first and last output reached the screen over all processes
 * (CLOCK_REALTIME, so on one machine exact; across machines as close as
 * their clocks), over the last frames each kept. A collective after the
 * run: every process calls it; the figures are the leader's (zero on the
 * others). False with err after a failure. */
typedef struct cluster_spread {
    uint64_t frames;                /* frames every process flipped (and, for scan-out, reported) */
    uint64_t frames_out_of_step;    /* frames where the processes' frame numbers differed (should be 0) */
    double median_us, p95_us, max_us;
} cluster_spread;
typedef struct cluster_skew {
    cluster_spread barrier;         /* passing the barrier before the flip */
    cluster_spread scanout;         /* on screen: frames 0 when the display reports none (headless) */
} cluster_skew;
bool cluster_flip_skew(cluster *c, cluster_skew *out, tess_error *err);

/* MPI_Finalize (skipped after a failure: it would wait for the dead), free.
 * NULL is fine. */
void cluster_finish(cluster *c);

#endif
