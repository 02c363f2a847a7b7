/* cluster.h (cluster) - one wall over several processes, one a machine
 * (OpenMPI: `mpirun -np N tessera run --wall W.json`, the wall file's
 * "nodes" saying which outputs each drives). Every process loads the scene
 * and builds its accel itself and renders its own outputs with its own
 * threads; they meet twice a frame:
 *
 *   FRAME SYNC (the serial section, pipeline.h: the frame sync hook). The
 *   LEADER (rank 0 unless configured: it reads input) sends what changed its frame state this
 *   step as data records (txn.h, binary form) with the step's time; every
 *   other process (a FOLLOWER) applies the same records at the same frame,
 *   so all render the same state. Whether the loop stops after the step is
 *   decided together: any process that stops (quit on the leader, SIGTERM,
 *   a display that failed) stops all of them at the same step. Records that
 *   name a channel (a camera or a switch of one channel: an output's
 *   hotplug, a remote viewer's private view) are the process's own and are
 *   not sent. Followers run no camera path or tour of their own: the
 *   leader's cameras arrive as records.
 *
 *   DISPLAY SYNC (the display thread, before the flips: pipeline.h: the
 *   display sync hook). A barrier, so every process flips the same frame at
 *   the same time (Tide's software swap sync).
 *
 * FAILURE. Every collective is started non-blocking and waited for with a
 * time-out (cluster_config.timeout_s): a process that dies or stops
 * answering makes the others stop the run with an error naming what they
 * waited for and the frame, never hang: it renders one more frame on its own
 * with the reason in the status line ("cluster: out of step with the other
 * machines at frame F: this wall stops"), shows it, and the run ends.
 * MPI_Init has no time-out of its own: a watchdog thread ends the process
 * (status 3) when starting takes longer than CLUSTER_START_TIMEOUT_S (or the
 * sync time-out, when longer). After a failure MPI cannot be finalised (a
 * collective is left open): cluster_finish skips it and the process exits
 * with the error.
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

#include "engine/err.h"

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

/* What the run cost: per frame, the frame sync (its first collective, which
 * waits for the slowest process, apart from the leader's broadcast, which
 * starts when everybody is there) and the display barrier, in microseconds
 * (medians of the last 1024), records and bytes the leader sent. */
typedef struct cluster_stats {
    uint64_t frames;            /* frame syncs */
    uint64_t records, bytes;    /* sent (leader) or applied (follower) */
    double vote_us_median, vote_us_max; /* the stop vote: it also waits for the slowest process */
    double send_us_median, send_us_max; /* the leader's header and records, everybody there: the broadcast's cost */
    double barrier_us_median, barrier_us_max;
    bool failed;                /* this process stops for a lost machine, or MPI failed */
    bool alone;                 /* a follower that lost the leader and carried on (CLUSTER_CARRY_ON) */
    uint64_t nodes_lost;        /* machines given up on (the leader's count, as the followers heard it) */
} cluster_stats;
cluster_stats cluster_get_stats(const cluster *c);
void cluster_print_stats(const cluster *c, FILE *out);

/* FLIP SKEW: how far apart the processes passed the barrier before the flip
 * of one frame (CLOCK_REALTIME, so on one machine exact; across machines as
 * close as their clocks), over the last frames each kept. A collective after
 * the run: every process calls it; the figures are the leader's (zero on the
 * others). False with err after a failure. */
typedef struct cluster_skew {
    uint64_t frames;                /* frames every process flipped */
    uint64_t frames_out_of_step;    /* frames where the processes' frame numbers differed (should be 0) */
    double median_us, p95_us, max_us;
} cluster_skew;
bool cluster_flip_skew(cluster *c, cluster_skew *out, tess_error *err);

/* MPI_Finalize (skipped after a failure: it would wait for the dead), free.
 * NULL is fine. */
void cluster_finish(cluster *c);

#endif
