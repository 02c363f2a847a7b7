/* remote_cli.h - the remote view on the command line (--remote PORT,
 * --remote-bind ADDR, --remote-token TOKEN) and in a pipeline config (the
 * "remote" object: docs/pipeline-config.md), and its place in a command's
 * life (remote/remote.h, Life): the follow channel is added by
 * cli_pipeline_create, the server starts after input, stops before it. One
 * remote view per process at a time. */
#ifndef TESSERA_CLI_REMOTE_CLI_H
#define TESSERA_CLI_REMOTE_CLI_H

#include <stdbool.h>
#include <stdio.h>

#include "engine/base/camera.h"
#include "engine/base/json_read.h"
#include "input/source.h"
#include "remote/remote.h"

struct pipeline;

/* If argv[*i] is a remote option, parse it (*handled). False after an error. */
bool cli_remote_option(int argc, char **argv, int *i, remote_config *c, bool *handled);
void cli_remote_usage(FILE *f);
/* The config's "remote" object, if any, into c. */
bool cli_remote_config_load(jr_ctx *jc, json_object *root, remote_config *c);

/* With c->port >= 0: create the view and add its follow channel to p, the
 * whole plane of `camera` at plane_aspect, sized to fit c's width x height,
 * then its private channels (the same; as many as the pipeline has room for).
 * True (doing nothing) when off. False after printing an error. */
bool cli_remote_add_channel(struct pipeline *p, const remote_config *c, const camera_desc *camera,
                            float plane_aspect);
/* The follow channel's index, or -1 without a remote view. */
int cli_remote_channel(void);
/* The view's input source for the input runner (NULL without a view; once). */
input_source *cli_remote_take_source(void);
/* Start serving (prints the URL). True when there is no view. */
bool cli_remote_start(struct pipeline *p);
/* Stop serving and print the view's counts (before the input runner stops). */
void cli_remote_stop(void);
/* Free the view (after pipeline_destroy: the pipeline owns its display). */
void cli_remote_release(void);

#endif
