/* test_drm_flips.c - what a DRM wall does when page flips fail
 * (drm_flip_judge, wall/drm.h): refused commits (an atomic commit is refused
 * for every output in it; a legacy page flip for one CRTC), flip events that
 * never come (a monitor gone mid-frame, a wedged CRTC), and outputs not
 * flipped in a stage. The DRM backend feeds it each display stage's outcomes
 * and applies the verdict: probe the connectors, switch a failing output off
 * while the others go on, or give the card up when nothing completes. */
#include <criterion/criterion.h>
#include <string.h>

#include "wall/drm.h"

static const char *const names[] = {"Virtual-1", "Virtual-2", "Virtual-3", "Virtual-4"};

/* One stage with every one of `count` outputs at outcome `all`, except
 * output `odd` (if >= 0) at `odd_outcome`. */
static drm_flip_verdict stage(drm_flip_health *h, int count, drm_flip_outcome all, int odd, drm_flip_outcome odd_outcome)
{
    drm_flip_outcome out[WALL_MAX_OUTPUTS];
    for (int o = 0; o < count; o++)
        out[o] = o == odd ? odd_outcome : all;
    return drm_flip_judge(h, out, names, count);
}

static bool nothing_given_up(const drm_flip_verdict *v)
{
    for (int o = 0; o < WALL_MAX_OUTPUTS; o++)
        if (v->give_up[o])
            return false;
    return true;
}

Test(drm_flips, completed_flips_need_nothing)
{
    drm_flip_health h = {{0}, {0}};
    for (int i = 0; i < 3 * DRM_FLIP_FAILS_LIMIT; i++) {
        drm_flip_verdict v = stage(&h, 4, DRM_FLIP_DONE, -1, DRM_FLIP_NONE);
        cr_assert(!v.probe && !v.fatal && nothing_given_up(&v) && !tess_error_is_set(&v.why));
    }
}

/* An atomic commit refused every stage: each refusal probes the connectors
 * (an output may be gone); the limit-th in a row gives the card up, not one
 * before. */
Test(drm_flips, refused_commits_give_the_card_up_at_the_limit)
{
    drm_flip_health h = {{0}, {0}};
    for (int i = 1; i <= DRM_FLIP_FAILS_LIMIT; i++) {
        drm_flip_verdict v = stage(&h, 4, DRM_FLIP_REFUSED, -1, DRM_FLIP_NONE);
        cr_assert(v.probe, "stage %d: no probe", i);
        cr_assert(nothing_given_up(&v), "stage %d: an output given up while none completes", i);
        cr_assert_eq(v.fatal, i == DRM_FLIP_FAILS_LIMIT, "stage %d: fatal %d", i, v.fatal);
        if (v.fatal)
            cr_assert_str_eq(v.why.msg, "5 page flips in a row were refused and no output's completed");
        else
            cr_assert_str_empty(v.why.msg);
    }
}

/* Time-outs and refusals count together; the message says both. */
Test(drm_flips, timeouts_and_refusals_count_together)
{
    drm_flip_health h = {{0}, {0}};
    drm_flip_verdict v;
    for (int i = 1; i <= DRM_FLIP_FAILS_LIMIT; i++)
        v = stage(&h, 2, i % 2 ? DRM_FLIP_TIMED_OUT : DRM_FLIP_REFUSED, -1, DRM_FLIP_NONE);
    cr_assert(v.fatal);
    cr_assert_str_eq(v.why.msg, "5 page flips in a row were refused or never completed and no output's completed");
}

/* One completed stage between failures starts the count again: failures
 * that come and go never add up to giving up. */
Test(drm_flips, a_completed_flip_resets_the_count)
{
    drm_flip_health h = {{0}, {0}};
    for (int round = 0; round < 4; round++) {
        for (int i = 0; i < DRM_FLIP_FAILS_LIMIT - 1; i++) {
            drm_flip_verdict v = stage(&h, 4, DRM_FLIP_TIMED_OUT, -1, DRM_FLIP_NONE);
            cr_assert(v.probe && !v.fatal && nothing_given_up(&v));
        }
        drm_flip_verdict v = stage(&h, 4, DRM_FLIP_DONE, -1, DRM_FLIP_NONE);
        cr_assert(!v.probe && !v.fatal);
    }
}

/* Stages without a flip (no new frame, every output dark) neither count
 * nor reset. */
Test(drm_flips, stages_without_flips_do_not_count)
{
    drm_flip_health h = {{0}, {0}};
    for (int i = 0; i < DRM_FLIP_FAILS_LIMIT - 1; i++) {
        cr_assert(stage(&h, 3, DRM_FLIP_REFUSED, -1, DRM_FLIP_NONE).probe);
        drm_flip_verdict quiet = stage(&h, 3, DRM_FLIP_NONE, -1, DRM_FLIP_NONE);
        cr_assert(!quiet.probe && !quiet.fatal);
    }
    cr_assert(stage(&h, 3, DRM_FLIP_REFUSED, -1, DRM_FLIP_NONE).fatal, "the NONE stages reset the count");
}

/* One output's flip event never comes (its monitor went mid-frame without a
 * hotplug event, or its CRTC is wedged) while the others flip: each stage
 * probes (the hotplug plan switches it off if its monitor is gone); if the
 * probe finds it still there, the limit-th failure switches it alone off and
 * the rest of the wall goes on: never fatal. */
Test(drm_flips, one_output_failing_is_switched_off_and_the_rest_goes_on)
{
    const drm_flip_outcome kinds[] = {DRM_FLIP_TIMED_OUT, DRM_FLIP_REFUSED};
    const char *const texts[] = {"never completed", "were refused"};
    for (int k = 0; k < 2; k++) {
        drm_flip_health h = {{0}, {0}};
        for (int i = 1; i <= DRM_FLIP_FAILS_LIMIT; i++) {
            drm_flip_verdict v = stage(&h, 4, DRM_FLIP_DONE, 2, kinds[k]);
            cr_assert(v.probe && !v.fatal, "stage %d", i);
            for (int o = 0; o < 4; o++)
                cr_assert_eq(v.give_up[o], o == 2 && i == DRM_FLIP_FAILS_LIMIT, "stage %d output %d", i, o);
            if (i < DRM_FLIP_FAILS_LIMIT) {
                cr_assert_str_empty(v.why.msg);
                continue;
            }
            char want[256];
            snprintf(want, sizeof want,
                     "outputs[2] (Virtual-3): 5 page flips in a row %s while the other outputs' completed; "
                     "switched off, the rest of the wall goes on",
                     texts[k]);
            cr_assert_str_eq(v.why.msg, want);
        }
        /* switched off, it is not flipped any more: the rest goes on and nothing fails */
        for (int i = 0; i < 2 * DRM_FLIP_FAILS_LIMIT; i++) {
            drm_flip_verdict v = stage(&h, 4, DRM_FLIP_DONE, 2, DRM_FLIP_NONE);
            cr_assert(!v.probe && !v.fatal && nothing_given_up(&v));
        }
        /* lit again (its monitor replugged), it starts afresh: one failure is not the limit */
        drm_flip_verdict v = stage(&h, 4, DRM_FLIP_DONE, 2, kinds[k]);
        cr_assert(v.probe && nothing_given_up(&v));
    }
}

/* Two outputs reaching the limit in the same stage: one message names both. */
Test(drm_flips, two_outputs_given_up_together)
{
    drm_flip_health h = {{0}, {0}};
    drm_flip_outcome out[4] = {DRM_FLIP_TIMED_OUT, DRM_FLIP_DONE, DRM_FLIP_REFUSED, DRM_FLIP_DONE};
    drm_flip_verdict v;
    for (int i = 0; i < DRM_FLIP_FAILS_LIMIT; i++)
        v = drm_flip_judge(&h, out, names, 4);
    cr_assert(v.give_up[0] && v.give_up[2] && !v.give_up[1] && !v.give_up[3] && !v.fatal);
    cr_assert_str_eq(v.why.msg, "outputs[0] (Virtual-1), outputs[2] (Virtual-3): 5 page flips in a row were refused "
                                "or never completed while the other outputs' completed; switched off, the rest of "
                                "the wall goes on");
    /* without names (NULL), outputs by index alone */
    drm_flip_health h2 = {{0}, {0}};
    for (int i = 0; i < DRM_FLIP_FAILS_LIMIT; i++)
        v = drm_flip_judge(&h2, out, NULL, 4);
    cr_assert(strncmp(v.why.msg, "outputs[0], outputs[2]: ", 24) == 0, "%s", v.why.msg);
}

/* A one-output wall has no rest to go on: its failing flips give the card up. */
Test(drm_flips, a_single_output_is_never_switched_off_but_given_up)
{
    drm_flip_health h = {{0}, {0}};
    drm_flip_verdict v;
    for (int i = 0; i < DRM_FLIP_FAILS_LIMIT; i++)
        v = stage(&h, 1, DRM_FLIP_TIMED_OUT, -1, DRM_FLIP_NONE);
    cr_assert(v.fatal && !v.give_up[0]);
    cr_assert_str_eq(v.why.msg, "5 page flips in a row never completed and no output's completed");
}

/* A wedged output does not hold back the verdict on a healthy one: after
 * the failing one is off, a later refusal of all (atomic) counts afresh. */
Test(drm_flips, counts_are_per_output)
{
    drm_flip_health h = {{0}, {0}};
    for (int i = 0; i < DRM_FLIP_FAILS_LIMIT - 1; i++)
        stage(&h, 3, DRM_FLIP_DONE, 1, DRM_FLIP_TIMED_OUT);
    /* output 1 at limit-1; now every output refused once: output 1 reaches the limit, nothing completed */
    drm_flip_verdict v = stage(&h, 3, DRM_FLIP_REFUSED, -1, DRM_FLIP_NONE);
    cr_assert(v.fatal, "output 1 at the limit and nothing completed");
    cr_assert_str_eq(v.why.msg, "5 page flips in a row were refused or never completed and no output's completed");
}
