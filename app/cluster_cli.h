/* cluster_cli.h - a wall of several machines on the command line (cluster/):
 * `mpirun -np N tessera run|render --wall W.json ...` with the wall file's
 * "nodes" saying which outputs each process drives. The same command line on
 * every process; here it becomes one process's part:
 *   - every process loads the scene and builds its accel, then they compare
 *     the accel's checksum and refuse to run on a mismatch;
 *   - a process renders only its node's outputs (their own files; no
 *     stitched image);
 *   - the leader (rank 0) reads input, serves a remote view, plays the
 *     camera path or the orbit, records; the followers do none of it: what
 *     changes the picture reaches them as the leader's records.
 * Without mpirun nothing here does anything (a wall file with nodes renders
 * every output in one process, the reference a cluster run must equal). One
 * cluster a process. */
#ifndef TESSERA_CLI_CLUSTER_CLI_H
#define TESSERA_CLI_CLUSTER_CLI_H

#include <stdbool.h>

#include "engine/scene/accel.h"
#include "pipeline_cli.h"

struct pipeline;

/* Started by mpirun: start MPI, read s's wall file, find this process's node
 * and make s this process's part (a follower: no input, no remote view, no
 * path, no recording). True (doing nothing) when not started by mpirun.
 * False after printing an error. */
bool cli_cluster_begin(cli_pipeline_spec *s);

/* Whether this process is one of a cluster, and whether it follows (not rank 0). */
bool cli_cluster_active(void);
bool cli_cluster_follower(void);

/* The outputs this process drives (WALL_MAX_OUTPUTS flags), NULL: every output. */
const bool *cli_cluster_outputs(void);

/* Compare the accel's checksum with the other processes. True without a
 * cluster; false after printing an error. */
bool cli_cluster_agree(const accel *a);

/* The frame and display syncs on p, before it runs; with outputs on a device
 * that reports flips (display_instance_set_flip_hook), their times for the
 * scan-out skew. True without a cluster. */
struct display_instance;
bool cli_cluster_attach(struct pipeline *p, struct display_instance *outputs);

/* After the run: print the cluster's counts; whether it failed (a process
 * died or stopped answering). False without a cluster. */
bool cli_cluster_report(void);

/* MPI_Finalize (unless it failed), once, at the process's end. */
void cli_cluster_end(void);

#endif
