/* test_wall_hotplug.c - what a running wall does when monitors are unplugged,
 * come back or move connectors: wall_hotplug_plan fed a recorded KMS state
 * (tests/data/outputs_vm_4heads.txt, `tessera outputs` in the qemu guest of
 * tests/vm with 4 virtio-gpu heads) and synthetic connector changes of it.
 * Below the udev layer: the DRM backend reads the connectors again on a
 * HOTPLUG=1 event and applies exactly this plan. Also the mode choice for
 * "preferred" on that state (preferred, else user-defined, else largest). */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wall/drm.h"
#include "wall/wall_config.h"

#define MAX_CONNECTORS 8
#define MAX_MODES 64

/* A card's connectors as `tessera outputs` printed them, with storage. */
typedef struct recorded_card {
    wall_device_connector conns[MAX_CONNECTORS];
    char names[MAX_CONNECTORS][WALL_CONNECTOR_BYTES];
    char edid[MAX_CONNECTORS][3][64];
    wall_device_mode modes[MAX_CONNECTORS][MAX_MODES];
    size_t count;
} recorded_card;

/* Copy the quoted value after `"key": "` into out ("" if absent). */
static void edid_field(const char *line, const char *key, char *out, size_t size)
{
    char pattern[64];
    snprintf(pattern, sizeof pattern, "\"%s\": \"", key);
    const char *p = strstr(line, pattern);
    out[0] = '\0';
    if (!p)
        return;
    p += strlen(pattern);
    size_t n = strcspn(p, "\"");
    snprintf(out, size, "%.*s", (int)(n < size ? n : size - 1), p);
}

static void load_recorded(recorded_card *card, const char *file)
{
    memset(card, 0, sizeof *card);
    FILE *f = fopen(file, "r");
    cr_assert(f, "cannot open %s", file);
    char line[512];
    wall_device_connector *cur = NULL;
    size_t cur_index = 0;
    while (fgets(line, sizeof line, f)) {
        char name[WALL_CONNECTOR_BYTES], state[32];
        int w, h;
        double hz;
        int indent = (int)strspn(line, " "); /* card lines 0, connectors and CRTCs 2, modes 4 */
        if (indent == 4 && sscanf(line + indent, "%dx%d@%lf", &w, &h, &hz) == 3 && cur) {
            cr_assert(cur->mode_count < MAX_MODES);
            if (strstr(line, " preferred") && cur->preferred < 0)
                cur->preferred = (int)cur->mode_count;
            if (strstr(line, " user-defined") && cur->user_defined < 0)
                cur->user_defined = (int)cur->mode_count;
            card->modes[cur_index][cur->mode_count++] = (wall_device_mode){w, h, hz};
        } else if (indent == 2 && sscanf(line + indent, "%31[^: ]: %31[a-z]", name, state) == 2 &&
                   strncmp(name, "CRTC", 4) != 0) {
            cr_assert(card->count < MAX_CONNECTORS);
            cur_index = card->count++;
            cur = &card->conns[cur_index];
            snprintf(card->names[cur_index], WALL_CONNECTOR_BYTES, "%s", name);
            const char *keys[3] = {"manufacturer", "model", "serial"};
            for (int k = 0; k < 3; k++)
                edid_field(line, keys[k], card->edid[cur_index][k], sizeof card->edid[cur_index][k]);
            *cur = (wall_device_connector){card->names[cur_index], strcmp(state, "connected") == 0,
                                           card->edid[cur_index][0], card->edid[cur_index][1],
                                           card->edid[cur_index][2], card->modes[cur_index], 0, -1, -1};
        }
    }
    fclose(f);
}

static int find_connector(const recorded_card *card, const char *name)
{
    for (size_t k = 0; k < card->count; k++)
        if (!strcmp(card->names[k], name))
            return (int)k;
    cr_assert_fail("no connector %s in the recording", name);
    return -1;
}

/* The vm_2x2 wall matched to the recording: the state of a running wall. */
static wall_config running_wall(const recorded_card *card)
{
    wall_config w;
    tess_error err = {{0}};
    cr_assert(wall_config_load("../configs/walls/vm_2x2.json", &w, &err), "%s", err.msg);
    cr_assert(wall_config_match_device(&w, card->conns, card->count, &err), "%s", err.msg);
    return w;
}

static void all_live(const wall_config *w, bool *live, int *driving)
{
    for (int i = 0; i < w->count; i++) {
        live[i] = true;
        driving[i] = w->outputs[i].device_connector;
    }
}

/* A vm_2x2 wall running on the recorded card, every output live, and the plan's steps. */
typedef struct running {
    recorded_card card;
    wall_config w;
    bool live[WALL_MAX_OUTPUTS];
    int driving[WALL_MAX_OUTPUTS];
    wall_hotplug_step steps[WALL_MAX_OUTPUTS];
} running;

static void start_running(running *r)
{
    load_recorded(&r->card, "data/outputs_vm_4heads.txt");
    r->w = running_wall(&r->card);
    all_live(&r->w, r->live, r->driving);
}

static void plan(running *r)
{
    wall_hotplug_plan(&r->w, r->live, r->driving, r->card.conns, r->card.count, r->steps);
}

/* Output o was unplugged earlier: dark, driving nothing. */
static void dark(running *r, int o)
{
    r->live[o] = false;
    r->driving[o] = -1;
}

Test(wall_hotplug, the_recording_reads_as_four_connected_heads)
{
    recorded_card card;
    load_recorded(&card, "data/outputs_vm_4heads.txt");
    cr_assert_eq(card.count, 4);
    for (int k = 0; k < 4; k++) {
        cr_expect(card.conns[k].connected);
        size_t modes = k == 0 ? 26 : 25; /* head 1 also has its xres x yres mode, 640x480@75 */
        cr_expect_eq(card.conns[k].mode_count, modes, "%s: %zu modes", card.names[k], card.conns[k].mode_count);
        cr_expect_str_eq(card.conns[k].edid_manufacturer, "RHT");
        cr_expect_geq(card.conns[k].user_defined, 0);
    }
    cr_expect_eq(card.conns[0].preferred, 0);
    cr_expect_eq(card.conns[1].preferred, -1, "heads 2+ mark no mode preferred");
    wall_config w = running_wall(&card);
    for (int i = 0; i < 4; i++) {
        const wall_device_mode *m = &card.conns[w.outputs[i].device_connector].modes[w.outputs[i].device_mode];
        cr_expect(m->width_px == 640 && m->height_px == 480, "outputs[%d]: %dx%d", i, m->width_px, m->height_px);
    }
}

Test(wall_hotplug, an_unplugged_monitor_is_gone_and_the_others_stay)
{
    running r;
    start_running(&r);
    r.card.conns[find_connector(&r.card, "Virtual-2")].connected = false; /* the synthetic change */
    plan(&r);
    cr_assert_eq(r.steps[1].action, WALL_HOTPLUG_GONE);
    cr_expect(strstr(r.steps[1].reason.msg, "outputs[1]: connector 'Virtual-2' has no monitor connected"), "%s",
              r.steps[1].reason.msg);
    for (int i = 0; i < 4; i++)
        if (i != 1) {
            cr_expect_eq(r.steps[i].action, WALL_HOTPLUG_KEEP, "outputs[%d]", i);
            cr_expect_str_empty(r.steps[i].reason.msg, "outputs[%d]: %s", i, r.steps[i].reason.msg);
        }
}

Test(wall_hotplug, a_vanished_connector_is_gone)
{
    running r;
    start_running(&r);
    r.card.count = 3; /* Virtual-4 is no longer listed (an MST branch went away) */
    r.driving[3] = -1;
    plan(&r);
    cr_assert_eq(r.steps[3].action, WALL_HOTPLUG_GONE);
    cr_expect(strstr(r.steps[3].reason.msg, "connector 'Virtual-4' not found (the card has: Virtual-1, Virtual-2, "
                                          "Virtual-3)"), "%s", r.steps[3].reason.msg);
    cr_expect_eq(r.steps[0].action, WALL_HOTPLUG_KEEP);
}

Test(wall_hotplug, a_monitor_plugged_back_comes_back_in_its_mode)
{
    running r;
    start_running(&r);
    dark(&r, 2); /* Virtual-3 was unplugged earlier ... */
    int v3 = find_connector(&r.card, "Virtual-3");
    r.card.conns[v3].connected = false;
    plan(&r);
    cr_expect_eq(r.steps[2].action, WALL_HOTPLUG_KEEP, "still unplugged: stays dark");
    cr_expect(strstr(r.steps[2].reason.msg, "has no monitor connected"), "%s", r.steps[2].reason.msg);
    r.card.conns[v3].connected = true; /* ... and is back */
    plan(&r);
    cr_assert_eq(r.steps[2].action, WALL_HOTPLUG_BACK, "%s", r.steps[2].reason.msg);
    cr_expect_eq(r.steps[2].connector, v3);
    cr_expect_eq(r.steps[2].mode, r.w.outputs[2].device_mode, "the mode it started in");
    for (int i = 0; i < 4; i++)
        if (i != 2)
            cr_expect_eq(r.steps[i].action, WALL_HOTPLUG_KEEP);
}

Test(wall_hotplug, a_monitor_back_without_the_mode_stays_dark_and_says_why)
{
    running r;
    start_running(&r);
    dark(&r, 3);
    r.card.conns[find_connector(&r.card, "Virtual-4")].mode_count = 3; /* a different monitor: 5K and 4K modes only */
    plan(&r);
    cr_expect_eq(r.steps[3].action, WALL_HOTPLUG_KEEP);
    cr_expect(strstr(r.steps[3].reason.msg, "outputs[3]: mode 640x480 not offered by Virtual-4 (it offers: "
                                          "5120x2160@50, 4096x2160@50, 3840x2160@60)"), "%s", r.steps[3].reason.msg);
}

static const char edid_wall[] =
    "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
    "{\"connector\": \"Virtual-1\", \"mode\": \"640x480\", \"grid\": [0, 0], \"size_mm\": [160, 120]},"
    "{\"connector\": \"Virtual-2\", \"edid\": {\"manufacturer\": \"RHT\", \"serial\": \"B\"}, \"mode\": \"640x480\","
    " \"grid\": [1, 0], \"size_mm\": [160, 120]}]}";

/* A wall from JSON text, matched to the card (its running state). */
static wall_config matched_wall(const char *name, const char *text, const recorded_card *card)
{
    wall_config w;
    tess_error err = {{0}};
    cr_assert(wall_config_parse(name, text, strlen(text), &w, &err), "%s: %s", name, err.msg);
    cr_assert(wall_config_match_device(&w, card->conns, card->count, &err), "%s: %s", name, err.msg);
    return w;
}

/* The recording with Virtual-2's monitor given serial B, and edid_wall matched to it. */
static wall_config edid_wall_on_card(recorded_card *card)
{
    load_recorded(card, "data/outputs_vm_4heads.txt");
    card->conns[find_connector(card, "Virtual-2")].edid_serial = "B";
    return matched_wall("edid_wall", edid_wall, card);
}

Test(wall_hotplug, a_monitor_that_moved_connectors_is_gone_then_back_on_the_new_one)
{
    recorded_card card;
    wall_config w = edid_wall_on_card(&card);
    int v2 = find_connector(&card, "Virtual-2"), v3 = find_connector(&card, "Virtual-3");
    cr_assert_eq(w.outputs[1].device_connector, v2);
    bool live[WALL_MAX_OUTPUTS];
    int driving[WALL_MAX_OUTPUTS];
    all_live(&w, live, driving);
    /* the monitor with serial B moves from Virtual-2 to Virtual-3 */
    card.conns[v2].connected = false;
    card.conns[v2].edid_serial = "";
    card.conns[v3].edid_serial = "B";
    wall_hotplug_step steps[WALL_MAX_OUTPUTS];
    wall_hotplug_plan(&w, live, driving, card.conns, card.count, steps);
    cr_assert_eq(steps[1].action, WALL_HOTPLUG_GONE);
    cr_expect(strstr(steps[1].reason.msg, "outputs[1]: its monitor is now on Virtual-3"), "%s", steps[1].reason.msg);
    cr_expect_eq(steps[0].action, WALL_HOTPLUG_KEEP);
    live[1] = false; /* the caller applied the first plan */
    driving[1] = -1;
    wall_hotplug_plan(&w, live, driving, card.conns, card.count, steps);
    cr_assert_eq(steps[1].action, WALL_HOTPLUG_BACK, "%s", steps[1].reason.msg);
    cr_expect_eq(steps[1].connector, v3);
    cr_expect_eq(card.conns[v3].modes[steps[1].mode].width_px, 640);
}

Test(wall_hotplug, a_dark_output_never_takes_a_connector_a_live_one_keeps)
{
    recorded_card card;
    wall_config w = edid_wall_on_card(&card);
    int v1 = find_connector(&card, "Virtual-1"), v2 = find_connector(&card, "Virtual-2");
    bool live[WALL_MAX_OUTPUTS] = {true, false};
    int driving[WALL_MAX_OUTPUTS] = {v1, -1};
    /* monitor B now hangs on Virtual-1, which outputs[0] drives by name */
    card.conns[v2].connected = false;
    card.conns[v1].edid_serial = "B";
    wall_hotplug_step steps[WALL_MAX_OUTPUTS];
    wall_hotplug_plan(&w, live, driving, card.conns, card.count, steps);
    cr_expect_eq(steps[0].action, WALL_HOTPLUG_KEEP);
    cr_expect_eq(steps[1].action, WALL_HOTPLUG_KEEP);
    cr_expect(strstr(steps[1].reason.msg, "outputs[1]: connector Virtual-1 is driven by outputs[0]"), "%s",
              steps[1].reason.msg);
}

static const char preferred_wall[] =
    "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
    "{\"connector\": \"Virtual-2\", \"mode\": \"preferred\", \"grid\": [0, 0], \"size_mm\": [160, 120]}]}";

Test(wall_hotplug, preferred_takes_the_user_defined_mode_when_none_is_marked_preferred)
{
    recorded_card card;
    load_recorded(&card, "data/outputs_vm_4heads.txt");
    wall_config w = matched_wall("preferred_wall", preferred_wall, &card);
    const wall_device_connector *v2 = &card.conns[find_connector(&card, "Virtual-2")];
    cr_expect_eq(w.outputs[0].device_mode, v2->user_defined, "not the largest, 5120x2160");
    cr_expect_eq(w.outputs[0].width_px, 640);
    /* without a user-defined mode: the largest, which must then fit the aspect (it does not: 5120x2160) */
    card.conns[find_connector(&card, "Virtual-2")].user_defined = -1;
    tess_error err = {{0}};
    cr_expect_not(wall_config_match_device(&w, card.conns, card.count, &err));
    cr_expect(strstr(err.msg, "the preferred mode of Virtual-2, 5120x2160@50"), "%s", err.msg);
}

Test(wall_hotplug, a_preferred_monitor_back_at_another_size_stays_dark)
{
    recorded_card card;
    load_recorded(&card, "data/outputs_vm_4heads.txt");
    wall_config w = matched_wall("preferred_wall", preferred_wall, &card);
    bool live[1] = {false};
    int driving[1] = {-1};
    /* back, but now a 1024x768 mode is the user-defined one: same aspect, another size */
    wall_device_connector *v2 = &card.conns[find_connector(&card, "Virtual-2")];
    for (size_t k = 0; k < v2->mode_count; k++)
        if (v2->modes[k].width_px == 1024)
            v2->user_defined = (int)k;
    wall_hotplug_step steps[1];
    wall_hotplug_plan(&w, live, driving, card.conns, card.count, steps);
    cr_expect_eq(steps[0].action, WALL_HOTPLUG_KEEP);
    cr_expect(strstr(steps[0].reason.msg, "Virtual-2 is back with mode 1024x768@60 (1024 x 768 px as mounted), but "
                                          "the wall started at 640 x 480 px; restart tessera"), "%s",
              steps[0].reason.msg);
}

/* ---- CRTC assignment (drm_match_crtcs): a matching, not first fit ---- */
Test(wall_hotplug, crtcs_are_matched_so_no_output_is_starved_by_an_earlier_one)
{
    /* output 0 can use CRTC 0 or 1, output 1 only CRTC 0: first fit would leave output 1 without */
    uint32_t masks[3] = {0x3, 0x1, 0x6};
    int crtc[3];
    cr_assert_eq(drm_match_crtcs(masks, 3, 3, crtc), -1);
    cr_expect_eq(crtc[1], 0);
    cr_expect_neq(crtc[0], crtc[1]);
    cr_expect_neq(crtc[2], crtc[0]);
    for (int o = 0; o < 3; o++)
        cr_expect(masks[o] & (1u << crtc[o]), "output %d got CRTC %d outside its mask", o, crtc[o]);
    /* three outputs that can only share two CRTCs: the third is named */
    uint32_t tight[3] = {0x3, 0x3, 0x3};
    cr_expect_eq(drm_match_crtcs(tight, 3, 2, crtc), 2);
    /* an output whose encoders reach no CRTC at all */
    uint32_t none[2] = {0x1, 0x0};
    cr_expect_eq(drm_match_crtcs(none, 2, 4, crtc), 1);
}
