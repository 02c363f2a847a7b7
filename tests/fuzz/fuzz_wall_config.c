/* fuzz_wall_config.c - wall files (wall/wall_config.c) through
 * wall_config_parse, then what a run does next with a parsed wall: headless
 * pixel sizes, matching against a card's connectors, and a hotplug plan (pure
 * functions over a fixed fake card). */
#include "fuzz.h"

#include <math.h>
#include <string.h>

#include "wall/wall_config.h"

static const wall_device_mode modes_a[] = {{1920, 1080, 60.0}, {1920, 1080, 50.0}, {1280, 720, 60.0}, {1920, 1200, 59.95}};
static const wall_device_mode modes_b[] = {{2560, 1440, 59.951}, {2560, 1440, 144.0}, {1080, 1920, 60.0}};
static const wall_device_connector card[] = {
    {"Virtual-1", true, "DEL", "U2415", "ABC123", modes_a, 4, 0, -1},
    {"Virtual-2", true, "DEL", "U2415", "XYZ789", modes_a, 4, 1, 2},
    {"HDMI-A-1", true, "GSM", "LG HDR 4K", NULL, modes_b, 3, -1, -1},
    {"DP-1", false, NULL, NULL, NULL, NULL, 0, -1, -1},
    {"DP-2", true, NULL, NULL, NULL, modes_b, 3, 2, -1},
};
#define CARD_CONNECTORS (sizeof card / sizeof card[0])

static void check_wall(const wall_config *w, const char *name)
{
    if (w->count < 1 || w->count > WALL_MAX_OUTPUTS)
        fuzz_fail("%s: %d outputs", name, w->count);
    if (!(w->width_mm > 0.0) || !(w->height_mm > 0.0) || !isfinite(w->width_mm + w->height_mm))
        fuzz_fail("%s: wall size %g x %g mm", name, w->width_mm, w->height_mm);
    for (int i = 0; i < w->count; i++) {
        const wall_output *o = &w->outputs[i];
        if (!memchr(o->connector, '\0', sizeof o->connector) || !memchr(o->edid.model, '\0', sizeof o->edid.model) ||
            !memchr(o->edid.serial, '\0', sizeof o->edid.serial) || !memchr(o->edid.manufacturer, '\0', sizeof o->edid.manufacturer))
            fuzz_fail("%s: output %d: a name is not terminated", name, i);
        if (!(o->width_mm > 0.0) || !(o->height_mm > 0.0) || !(o->x_mm >= -1e-6) || !(o->y_mm >= -1e-6) ||
            !(o->x_mm + o->width_mm <= w->width_mm + 1e-6 * w->width_mm) ||
            !(o->y_mm + o->height_mm <= w->height_mm + 1e-6 * w->height_mm))
            fuzz_fail("%s: output %d lies outside the wall", name, i);
        if (o->rotation_deg % 90 != 0 || o->rotation_deg < 0 || o->rotation_deg > 270)
            fuzz_fail("%s: output %d: rotation %d", name, i, o->rotation_deg);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = "wall.json";
    wall_config w;
    tess_error err = {{0}};
    if (!wall_config_parse(name, (const char *)data, size, &w, &err)) {
        fuzz_check_error(&err, name);
        return 0;
    }
    check_wall(&w, name);

    wall_config headless = w;
    tess_error why = {{0}};
    if (wall_config_headless_sizes(&headless, &why)) {
        for (int i = 0; i < headless.count; i++)
            if (headless.outputs[i].width_px < 1 || headless.outputs[i].height_px < 1)
                fuzz_fail("%s: output %d: headless size %dx%d", name, i, headless.outputs[i].width_px,
                          headless.outputs[i].height_px);
    } else if (!why.msg[0]) {
        fuzz_fail("%s: wall_config_headless_sizes failed without a message", name);
    }

    tess_error no = {{0}};
    if (wall_config_match_device(&w, card, CARD_CONNECTORS, &no)) {
        bool live[WALL_MAX_OUTPUTS];
        int driving[WALL_MAX_OUTPUTS];
        for (int i = 0; i < w.count; i++) {
            const wall_output *o = &w.outputs[i];
            if (o->device_connector < 0 || (size_t)o->device_connector >= CARD_CONNECTORS || o->device_mode < 0 ||
                (size_t)o->device_mode >= card[o->device_connector].mode_count)
                fuzz_fail("%s: output %d matched connector %d mode %d", name, i, o->device_connector, o->device_mode);
            live[i] = i % 2 == 0;
            driving[i] = live[i] ? o->device_connector : -1;
        }
        wall_hotplug_step steps[WALL_MAX_OUTPUTS];
        /* the card after a change: the first connector unplugged */
        wall_device_connector after[CARD_CONNECTORS];
        memcpy(after, card, sizeof after);
        after[0].connected = false;
        wall_hotplug_plan(&w, live, driving, after, CARD_CONNECTORS, steps);
        for (int i = 0; i < w.count; i++)
            if (steps[i].action == WALL_HOTPLUG_BACK &&
                (steps[i].connector < 0 || (size_t)steps[i].connector >= CARD_CONNECTORS || steps[i].mode < 0 ||
                 (size_t)steps[i].mode >= after[steps[i].connector].mode_count))
                fuzz_fail("%s: output %d comes back on connector %d mode %d", name, i, steps[i].connector, steps[i].mode);
    } else if (!no.msg[0]) {
        fuzz_fail("%s: wall_config_match_device failed without a message", name);
    }
    return 0;
}
