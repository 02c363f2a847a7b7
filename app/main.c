/* main.c - wires the engine and the outputs into the tessera command. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "engine/accel/kernels.h"
#include "engine/base/progress.h"
#include "wall/display_backend.h"

/* tessera outputs: what the display backends' devices offer, to help write a wall config. */
static int cli_outputs(int argc, char **argv)
{
    (void)argv;
    if (argc > 1) {
        printf("usage: tessera outputs\n");
        for (size_t i = 0; i < display_backend_count; i++) {
            const display_lifecycle *l = display_backends[i].lifecycle;
            if (l && l->print_outputs)
                fputs(l->outputs_help, stdout);
        }
        return strcmp(argv[1], "--help") && strcmp(argv[1], "-h") ? 2 : 0;
    }
    return display_backends_print_outputs(stdout) > 0 ? 0 : 1;
}

/* The summary of `tessera outputs`: what the backends that list devices list. */
static void outputs_summary(char *out, size_t out_bytes)
{
    size_t used = snprintf(out, out_bytes, "list ");
    for (size_t i = 0, listed = 0; i < display_backend_count && used < out_bytes; i++) {
        const display_lifecycle *l = display_backends[i].lifecycle;
        if (!l || !l->print_outputs)
            continue;
        int n = snprintf(out + used, out_bytes - used, "%s%s", listed++ ? "; " : "", l->outputs_what);
        used += n < 0 ? out_bytes - used : (size_t)n;
    }
    if (used < out_bytes)
        snprintf(out + used, out_bytes - used, ", for wall configs");
}

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv); /* argv[0] is the command name */
    const char *summary; /* NULL: made from the display-backend table (outputs_summary) */
} command;

static const command commands[] = {
    {"run", cli_run, "the main job: render the scene (headless: frames to out/) and report the frame rate"},
    {"render", cli_render, "render a scene headless and write image files"},
    {"trace", cli_trace, "trace rays from a binary file and write their hits (for users and tests)"},
    {"bench", cli_bench, "measure ray throughput, build time and memory (machine-readable lines)"},
    {"compare", cli_compare, "how much an image differs from a reference: FLIP, RMSE, PSNR (one line)"},
    {"robust", cli_robust, "wrong hits and leaks of the kernels on hard cases, and their speed (one line a case)"},
    {"parts", cli_parts, "the part tree of an assembly (glTF nodes, OBJ groups): paths, instances, triangles"},
    {"outputs", cli_outputs, NULL}, /* outputs_summary */
};

static void usage(FILE *f)
{
    fputs("usage: tessera COMMAND [options]\n"
          "tessera - an interactive ray tracer for display walls.\n\ncommands:\n",
          f);
    char summary[256];
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++) {
        if (!commands[i].summary)
            outputs_summary(summary, sizeof summary);
        fprintf(f, "  %-8s %s\n", commands[i].name, commands[i].summary ? commands[i].summary : summary);
    }
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
