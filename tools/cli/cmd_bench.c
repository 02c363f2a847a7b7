/* cmd_bench.c - placeholder until the bench command lands in this session (being written now). */
#include "cli.h"

int cli_bench(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    cli_error("'bench' is not built yet");
    return 1;
}
