/* display_backend.c (wall) - the table of display backends (display_backend.h). */
#include "display_backend.h"

#include <stdio.h>
#include <string.h>

#include "display.h"
#include "drm_backend.h"
#include "wall_headless.h"

/* The headless displays' constructors, as the table calls them: their own
 * create functions report nothing but NULL when out of memory. */
static image_display *named_or_oom(image_display *d, const char *name, tess_error *err)
{
    if (!d)
        tess_error_set(err, "%s display: out of memory", name);
    return d;
}

static image_display *null_create(const display_backend_args *a, tess_error *err)
{
    (void)a;
    return named_or_oom(display_null_create(), "null", err);
}

static image_display *convert_create(const display_backend_args *a, tess_error *err)
{
    (void)a;
    return named_or_oom(display_convert_create(), "convert", err);
}

static image_display *convert_tiles_create(const display_backend_args *a, tess_error *err)
{
    (void)a;
    return named_or_oom(display_convert_tiles_create(), "convert-tiles", err);
}

static image_display *dump_create(const display_backend_args *a, tess_error *err)
{
    return display_dump_create(a->out_pattern, a->sequence, err);
}

static bool dump_create_wall(const wall_config *w, const display_backend_args *a, image_display **displays,
                             tess_error *err)
{
    return wall_headless_displays(w, a->out_pattern, a->sequence, a->present, displays, err);
}

/* A new backend is one row here (its code in its own file of wall/: a headless one's `create`, a
 * device's display_lifecycle as drm_backend.c's). */
const display_backend display_backends[] = {
    {"null", "drops each frame (rendering alone)", 0, 0, null_create, NULL, NULL},
    {"convert", "encodes to 8-bit sRGB XRGB8888 as scan-out would, then drops (no device)", 0, 0,
     convert_create, NULL, NULL},
    {"convert-tiles", "the same, by the render threads tile by tile (as drm does)", 0, 0, convert_tiles_create,
     NULL, NULL},
    {"dump", "writes each frame to files: --out (.png 8-bit sRGB, .exr linear float)", DISPLAY_OPTION_OUT,
     DISPLAY_NEEDS_OIIO, dump_create, dump_create_wall, NULL},
    {"drm", "scan-out on the wall's monitors through DRM/KMS (needs --wall; --card)", DISPLAY_OPTION_CARD,
     DISPLAY_NEEDS_DEVICE, NULL, NULL, &drm_display_lifecycle},
};
const size_t display_backend_count = sizeof display_backends / sizeof display_backends[0];
_Static_assert(sizeof display_backends / sizeof display_backends[0] <= DISPLAY_BACKENDS_MAX,
               "DISPLAY_BACKENDS_MAX: room for every backend");

const display_backend *display_backend_by_name(const char *name)
{
    for (size_t i = 0; i < display_backend_count; i++)
        if (!strcmp(display_backends[i].name, name))
            return &display_backends[i];
    return NULL;
}

void display_backend_names(unsigned options, const char *separator, char *out, size_t out_bytes)
{
    size_t used = 0;
    if (out_bytes)
        out[0] = '\0';
    for (size_t i = 0; i < display_backend_count && used < out_bytes; i++) {
        if ((display_backends[i].options & options) != options)
            continue;
        int n = snprintf(out + used, out_bytes - used, "%s%s", used ? separator : "", display_backends[i].name);
        used += n < 0 ? out_bytes - used : (size_t)n;
    }
}

image_display *display_create(const char *name, const char *out_pattern, bool sequence, tess_error *err)
{
    const display_backend *b = display_backend_by_name(name);
    if (!b) {
        char names[256];
        display_backend_names(0, ", ", names, sizeof names);
        tess_error_set(err, "unknown display '%s' (known: %s)", name, names);
        return NULL;
    }
    if (!b->create) {
        tess_error_set(err, "the %s display shows a wall's outputs on a card: it needs --wall", name);
        return NULL;
    }
    display_backend_args a = {out_pattern, sequence, NULL};
    return b->create(&a, err);
}

bool display_backend_create_wall(const display_backend *b, const wall_config *w, const display_backend_args *a,
                                 image_display **displays, tess_error *err)
{
    if (!b->create) /* DISPLAY_NEEDS_DEVICE */
        return tess_error_set(err, "the %s display is not headless: its outputs are a card's", b->name);
    bool ok = true;
    int made = 0;
    if (b->create_wall)
        ok = b->create_wall(w, a, displays, err); /* undoes itself on failure */
    else
        for (; ok && made < w->count; made++) { /* only the outputs this process drives */
            bool mine = !a->present || a->present[made];
            displays[made] = mine ? b->create(a, err) : NULL;
            ok = !mine || displays[made] != NULL;
        }
    for (int i = 0; !ok && i < w->count; i++) {
        if (i < made)
            image_display_destroy(displays[i]);
        displays[i] = NULL;
    }
    return ok;
}

const display_backend *display_backend_kiosk(void)
{
    for (size_t i = 0; i < display_backend_count; i++) {
        const display_lifecycle *l = display_backends[i].lifecycle;
        if (l && l->device_present && l->device_present())
            return &display_backends[i];
    }
    return NULL;
}

const display_backend *display_backend_kiosk_kind(void)
{
    for (size_t i = 0; i < display_backend_count; i++)
        if (display_backends[i].lifecycle && display_backends[i].lifecycle->device_present)
            return &display_backends[i];
    return NULL;
}

int display_backends_print_outputs(FILE *f)
{
    int devices = 0;
    for (size_t i = 0; i < display_backend_count; i++)
        if (display_backends[i].lifecycle && display_backends[i].lifecycle->print_outputs)
            devices += display_backends[i].lifecycle->print_outputs(f);
    return devices;
}

display_instance *display_backend_start(const display_backend *b, const display_start_args *a, const bool *present,
                                        wall_config *w, image_display **displays, tess_error *err)
{
    if (!b->lifecycle) {
        tess_error_set(err, "the %s display is headless: it has no device to start", b->name);
        return NULL;
    }
    /* the outputs this process drives (mine) and the other machines' (others) */
    bool mask_mine[WALL_MAX_OUTPUTS], mask_others[WALL_MAX_OUTPUTS];
    for (int i = 0; i < WALL_MAX_OUTPUTS; i++) {
        mask_mine[i] = !present || present[i];
        mask_others[i] = !mask_mine[i];
    }
    wall_config mine, others;
    int mine_index[WALL_MAX_OUTPUTS], other_index[WALL_MAX_OUTPUTS];
    int mine_count = wall_config_subset(w, mask_mine, &mine, mine_index);
    int other_count = wall_config_subset(w, mask_others, &others, other_index);
    for (int j = 0; j < other_count; j++)
        if (others.outputs[j].mode_preferred) {
            char label[WALL_LABEL_BYTES];
            tess_error_set(err, "outputs[%d] (%s, another machine's): a wall of several machines needs every "
                                "output's mode in the file (\"mode\": \"WxH\"): each machine sees only its "
                                "own monitors",
                           other_index[j], wall_output_label(w, other_index[j], label, sizeof label));
            return NULL;
        }
    if (!wall_config_headless_sizes(&others, err)) /* explicit modes: cannot fail */
        return NULL;
    image_display *mine_displays[WALL_MAX_OUTPUTS] = {NULL};
    display_instance *d = b->lifecycle->start(b, a, &mine, mine_displays, err);
    if (!d)
        return NULL;
    d->backend = b; /* display_instance_* reach the lifecycle through it */
    for (int j = 0; j < mine_count; j++) {
        w->outputs[mine_index[j]] = mine.outputs[j];
        displays[mine_index[j]] = mine_displays[j];
    }
    for (int j = 0; j < other_count; j++)
        w->outputs[other_index[j]] = others.outputs[j];
    return d;
}

void display_instance_attach(display_instance *d, struct pipeline *p, int first_channel)
{
    if (d && d->backend->lifecycle->attach)
        d->backend->lifecycle->attach(d, p, first_channel);
}

bool display_instance_set_pause_hook(display_instance *d, display_pause_fn fn, void *ctx)
{
    if (!d || !d->backend->lifecycle->set_pause_hook)
        return false;
    d->backend->lifecycle->set_pause_hook(d, fn, ctx);
    return true;
}

bool display_instance_set_flip_hook(display_instance *d, display_flip_fn fn, void *ctx)
{
    if (!d || !d->backend->lifecycle->set_flip_hook)
        return false;
    d->backend->lifecycle->set_flip_hook(d, fn, ctx);
    return true;
}

struct session *display_instance_seat(const display_instance *d)
{
    return d && d->backend->lifecycle->seat ? d->backend->lifecycle->seat(d) : NULL;
}

void display_instance_destroy(display_instance *d)
{
    if (d)
        d->backend->lifecycle->destroy(d);
}
