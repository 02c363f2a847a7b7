/* cli.h - the tessera command line: strict parsing of option values and the
 * commands. Every parse_* returns false after printing one line naming the
 * option, the value and what was expected. */
#ifndef TESSERA_CLI_H
#define TESSERA_CLI_H

#include <stdbool.h>

#include "engine/camera.h"

/* Largest image edge accepted, in pixels (a 16K wall output). */
#define CLI_MAX_IMAGE_EDGE_PX 16384

bool cli_parse_int(const char *option, const char *text, int min, int max, int *out);
bool cli_parse_size(const char *option, const char *text, int *width_px, int *height_px);
bool cli_parse_camera(const char *option, const char *text, camera_desc *out);
/* The value after argv[*i] (advancing *i), or NULL with a message when missing. */
const char *cli_option_value(int argc, char **argv, int *i);
void cli_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
double cli_now_s(void); /* monotonic seconds */

int cli_render(int argc, char **argv); /* tessera render ... */
int cli_run(int argc, char **argv);    /* tessera run ... */
int cli_trace(int argc, char **argv);  /* tessera trace ... (cmd_trace.c) */
int cli_bench(int argc, char **argv);  /* tessera bench ... (cmd_bench.c) */

#endif
