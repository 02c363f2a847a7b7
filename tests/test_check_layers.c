/* test_check_layers.c - tools/check_layers.sh (make check-layers) on small
 * planted trees: an include or a call up the layers, or across two geometry
 * kinds, fails and names the file, the use and both rooms; uses down the
 * layers pass. (make test runs the check on the real tree.) */
#include <criterion/criterion.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "support.h"

#define CHECK_SCRIPT "../tools/check_layers.sh"

/* Make dir/sub (and its parents) and write `text` to dir/sub/name. */
static void plant(const char *dir, const char *sub, const char *name, const char *text)
{
    char cmd[1024], path[320];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s/%s'", dir, sub);
    cr_assert_eq(support_run(cmd), 0);
    snprintf(path, sizeof path, "%s/%s", dir, sub);
    support_write_file(path, name, text);
}

/* Run the check on the tree at dir (extra: "" or "--objects ..."), its output in out. */
static int check(const char *dir, const char *extra, char *out, size_t out_bytes)
{
    char cmd[2048], log[600];
    snprintf(log, sizeof log, "%s/check.log", dir);
    snprintf(cmd, sizeof cmd, "sh %s --root '%s' %s > '%s' 2>&1", CHECK_SCRIPT, dir, extra, log);
    int rc = support_run(cmd);
    support_read_text(log, out, out_bytes);
    return rc;
}

Test(check_layers, an_upward_include_fails_naming_file_include_and_rooms)
{
    char dir[256], out[4096];
    support_make_tmp_dir(dir, sizeof dir, "layers-up");
    plant(dir, "engine/render", "shade.h", "int shade(void);\n");
    plant(dir, "engine/base", "low.h", "#include \"engine/render/shade.h\"\n");
    cr_expect_eq(check(dir, "", out, sizeof out), 1, "%s", out);
    cr_expect(strstr(out, "engine/base/low.h uses #include \"engine/render/shade.h\""), "%s", out);
    cr_expect(strstr(out, "room engine/base may not use room engine/render"), "%s", out);
    support_remove_tmp_dir(dir);
}

Test(check_layers, downward_and_same_folder_includes_pass)
{
    char dir[256], out[4096];
    support_make_tmp_dir(dir, sizeof dir, "layers-down");
    plant(dir, "engine/base", "err.h", "int err(void);\n");
    plant(dir, "engine/base", "log.h", "#include \"err.h\"\n");
    plant(dir, "engine/render", "shade.h", "#include \"engine/base/log.h\"\n#include <stdio.h>\n");
    plant(dir, "engine/frame", "pipe.c", "#include \"engine/render/shade.h\"\n#include \"gen/none.h\"\n");
    plant(dir, "wall", "out.c", "#include \"engine/frame/pipe.c\"\n");
    cr_expect_eq(check(dir, "", out, sizeof out), 0, "%s", out);
    support_remove_tmp_dir(dir);
}

Test(check_layers, geometry_kinds_are_peers)
{
    char dir[256], out[4096];
    support_make_tmp_dir(dir, sizeof dir, "layers-peers");
    plant(dir, "engine/geometry/volume", "volume.h", "int volume(void);\n");
    plant(dir, "engine/geometry/triangles", "mesh.h", "#include \"engine/geometry/volume/volume.h\"\n");
    cr_expect_eq(check(dir, "", out, sizeof out), 1, "%s", out);
    cr_expect(strstr(out, "room engine/geometry/triangles may not use room engine/geometry/volume"), "%s", out);
    /* the scene above them may use both */
    plant(dir, "engine/geometry/triangles", "mesh.h", "int mesh(void);\n");
    plant(dir, "engine/scene", "scene.h", "#include \"engine/geometry/volume/volume.h\"\n"
                                          "#include \"engine/geometry/triangles/mesh.h\"\n");
    cr_expect_eq(check(dir, "", out, sizeof out), 0, "%s", out);
    support_remove_tmp_dir(dir);
}

Test(check_layers, the_engine_uses_no_outer_room)
{
    char dir[256], out[4096];
    support_make_tmp_dir(dir, sizeof dir, "layers-outer");
    plant(dir, "wall", "drm.h", "int drm(void);\n");
    plant(dir, "engine/frame", "pipeline.c", "#include \"engine/../wall/drm.h\"\n#include \"wall/drm.h\"\n");
    cr_expect_eq(check(dir, "", out, sizeof out), 1, "%s", out);
    cr_expect(strstr(out, "room engine/frame may not use room wall"), "%s", out);
    support_remove_tmp_dir(dir);
}

/* A call up the layers through a header that does not say so: seen in the objects. */
Test(check_layers, an_upward_call_fails_naming_the_symbol)
{
    char dir[256], out[4096], cmd[1024];
    support_make_tmp_dir(dir, sizeof dir, "layers-call");
    plant(dir, "engine/load", "reader.c", "int read_the_file(void) { return 7; }\n");
    plant(dir, "engine/scene", "scene.c", "int read_the_file(void);\nint scene_load(void) { return read_the_file(); }\n");
    plant(dir, "engine/base", "log.c", "int log_it(void) { return 1; }\n");
    plant(dir, "engine/render", "shade.c", "int log_it(void);\nint shade(void) { return log_it(); }\n");
    snprintf(cmd, sizeof cmd,
             "cd '%s' && mkdir -p b/engine/load b/engine/scene b/engine/base b/engine/render && "
             "cc -c engine/load/reader.c -o b/engine/load/reader.o && cc -c engine/scene/scene.c -o b/engine/scene/scene.o && "
             "cc -c engine/base/log.c -o b/engine/base/log.o && cc -c engine/render/shade.c -o b/engine/render/shade.o",
             dir);
    cr_assert_eq(support_run(cmd), 0, "cc");
    cr_expect_eq(check(dir, "--objects b/engine/base/log.o b/engine/render/shade.o", out, sizeof out), 0, "%s", out);
    cr_expect_eq(check(dir, "--objects b/engine/load/reader.o b/engine/scene/scene.o b/engine/base/log.o", out,
                       sizeof out),
                 1, "%s", out);
    cr_expect(strstr(out, "engine/scene/scene.c uses read_the_file (engine/load/reader.c)"), "%s", out);
    cr_expect(strstr(out, "room engine/scene may not use room engine/load"), "%s", out);
    support_remove_tmp_dir(dir);
}
