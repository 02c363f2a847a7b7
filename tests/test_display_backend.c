/* test_display_backend.c - the table of display backends (wall/display_backend.h):
 * every headless backend is made by its name and its display carries that
 * name; the card backends are refused one channel at a time; an unknown name's
 * error lists every name of the table. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "wall/display_backend.h"

Test(display_backend, every_headless_backend_made_by_name)
{
    char dir[] = "/tmp/tessera-backend-XXXXXX", pattern[128];
    cr_assert_not_null(mkdtemp(dir));
    snprintf(pattern, sizeof pattern, "%s/f_####.png", dir);
    int headless = 0;
    for (size_t i = 0; i < display_backend_count; i++) {
        const display_backend *b = &display_backends[i];
        cr_assert_eq(display_backend_by_name(b->name), b, "%s", b->name);
        tess_error err = {{0}};
        image_display *d = display_create(b->name, pattern, true, &err);
        if (b->needs & DISPLAY_NEEDS_CARD) {
            cr_assert_null(b->create, "%s", b->name);
            cr_assert_null(d, "%s", b->name);
            cr_assert(strstr(err.msg, "--wall"), "%s: %s", b->name, err.msg);
            continue;
        }
        cr_assert_not_null(d, "%s: %s", b->name, err.msg);
        cr_assert_str_eq(d->ops->name, b->name);
        image_display_destroy(d);
        headless++;
    }
    cr_assert_geq(headless, 4); /* null, convert, convert-tiles, dump */
    rmdir(dir);
}

Test(display_backend, options_and_needs)
{
    /* the backends that take --out are the ones that refuse to be made without it */
    for (size_t i = 0; i < display_backend_count; i++) {
        const display_backend *b = &display_backends[i];
        if (!b->create)
            continue;
        tess_error err = {{0}};
        image_display *d = display_create(b->name, NULL, false, &err);
        cr_assert_eq(d == NULL, (b->options & DISPLAY_OPTION_OUT) != 0, "%s: %s", b->name, err.msg);
        image_display_destroy(d);
    }
    cr_assert(display_backend_by_name("drm")->options & DISPLAY_OPTION_CARD);
    cr_assert(display_backend_by_name("dump")->needs & DISPLAY_NEEDS_OIIO);
    cr_assert_null(display_backend_by_name("drmm"));
}

Test(display_backend, unknown_name_lists_the_table)
{
    tess_error err = {{0}};
    cr_assert_null(display_create("bogus", NULL, false, &err));
    cr_assert(strstr(err.msg, "'bogus'"), "%s", err.msg);
    for (size_t i = 0; i < display_backend_count; i++)
        cr_assert(strstr(err.msg, display_backends[i].name), "%s lacks %s", err.msg, display_backends[i].name);
    char names[256];
    display_backend_names(DISPLAY_OPTION_OUT, " or ", names, sizeof names);
    cr_assert_str_eq(names, "dump");
    display_backend_names(0, ", ", names, sizeof names);
    cr_assert_str_eq(names, "null, convert, convert-tiles, dump, drm");
}
