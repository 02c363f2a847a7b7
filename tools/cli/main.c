/* main.c - wires the engine and the outputs into the tessera command. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "engine/accel/kernels.h"
#include "engine/base/progress.h"
#include "wall/drm.h"

/* tessera outputs: what the cards offer, to help write a wall config. */
static int cli_outputs(int argc, char **argv)
{
    (void)argv;
    if (argc > 1) {
        printf("usage: tessera outputs\n"
               "List every DRM card, its connectors (names as wall configs use them), the EDID identity\n"
               "of each connected monitor and its modes.\n");
        return strcmp(argv[1], "--help") && strcmp(argv[1], "-h") ? 2 : 0;
    }
    return drm_print_outputs(stdout) > 0 ? 0 : 1;
}

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv); /* argv[0] is the command name */
    const char *summary;
} command;

static const command commands[] = {
    {"run", cli_run, "the main job: render the scene (headless: frames to out/) and report the frame rate"},
    {"render", cli_render, "render a scene headless and write image files"},
    {"trace", cli_trace, "trace rays from a binary file and write their hits (for users and tests)"},
    {"bench", cli_bench, "measure ray throughput, build time and memory (machine-readable lines)"},
    {"compare", cli_compare, "how much an image differs from a reference: FLIP, RMSE, PSNR (one line)"},
    {"robust", cli_robust, "wrong hits and leaks of the kernels on hard cases, and their speed (one line a case)"},
    {"parts", cli_parts, "the part tree of an assembly (glTF nodes, OBJ groups): paths, instances, triangles"},
    {"outputs", cli_outputs, "list DRM cards, connectors, monitors (EDID) and modes, for wall configs"},
};

static void usage(FILE *f)
{
    fputs("usage: tessera COMMAND [options]\n"
          "tessera - an interactive ray tracer for display walls.\n\ncommands:\n",
          f);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-8s %s\n", commands[i].name, commands[i].summary);
    fputs("\n'tessera COMMAND --help' describes the options of each command.\n", f);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return 0;
    }
    tess_error env_err = {{0}};
    if (!kernels_check_env(&env_err)) {
        cli_error("%s", env_err.msg);
        return 2;
    }
    progress_set_quiet(false); /* loading and building report progress on stderr (engine/base/progress.h) */
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name))
            return commands[i].run(argc - 1, argv + 1);
    cli_error("unknown command '%s' (expected one of: run, render, trace, bench, compare, robust, parts, outputs; see 'tessera --help')",
              argv[1]);
    return 2;
}
