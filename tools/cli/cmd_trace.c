/* cmd_trace.c - placeholder until the trace command lands in this session (being written now). */
#include "cli.h"

int cli_trace(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    cli_error("'trace' is not built yet");
    return 1;
}
