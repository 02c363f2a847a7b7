/* option_check.h - options given on the command line that do not apply in
 * the combination they were given in are said, never silently dropped
 * (docs/command-line.md, "Errors").
 *
 * The rule: `render` and `run` warn (one line `tessera: warning: --X is
 * ignored ... (why)`) and go on, as the picture is what it would be without
 * the option (a kiosk's unit file with one option too many still lights the
 * wall); the benchmarks refuse (exit 2), as their numbers would silently
 * measure something other than what was asked (bench --wall already did).
 * Options set by a --config file are not checked: a config is shared between
 * uses (configs/pipeline/kiosk.json gives a size a wall does not use). */
#ifndef TESSERA_CLI_OPTION_CHECK_H
#define TESSERA_CLI_OPTION_CHECK_H

#include <stdbool.h>
#include <stdio.h>

#include "pipeline_cli.h"

#define CLI_GIVEN_MAX 128

/* The options the command line gave, in order (argv's strings, not copied). */
typedef struct cli_given {
    const char *names[CLI_GIVEN_MAX];
    int count;
} cli_given;

/* Record option `name` (argv[i] before its value was consumed). */
void cli_given_add(cli_given *g, const char *name);
bool cli_given_has(const cli_given *g, const char *name);

/* `tessera: warning: ...` on stderr. */
void cli_warn(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* render and run, once the spec is final (the kiosk's defaults applied):
 * warns for every given option that has no effect. */
void cli_check_ignored_render_run(const cli_given *g, const cli_pipeline_spec *s, const char *command);

/* bench --path, --scaling and --wall (`mode`: "--path", "--scaling",
 * "--wall"): false after an error line for the first given option that mode
 * cannot honour (exit 2). */
bool cli_check_ignored_bench(const cli_given *g, const cli_pipeline_spec *s, const char *mode);

#endif
