/* frame_state.c - the versioned frame state (frame_state.h). */
#include "frame_state.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"
#include "engine/base/log.h"

static size_t words(uint32_t count) { return ((size_t)count + 63) / 64; }
static bool bit(const uint64_t *set, uint32_t id) { return set && (set[id / 64] >> (id % 64) & 1u); }

/* Set bits [first, first + count) to `on`; returns how many changed. */
static uint32_t set_bits(uint64_t *set, uint32_t first, uint32_t count, bool on)
{
    uint32_t changed = 0;
    for (uint64_t id = first; id < (uint64_t)first + count; id++) {
        uint64_t *w = &set[id / 64], m = (uint64_t)1 << (id % 64);
        if (((*w & m) != 0) != on) {
            changed++;
            *w ^= m;
        }
    }
    return changed;
}

/* A bitset for the state's geometries, allocated on first use. */
static bool ensure_bits(const frame_state *st, uint64_t **set)
{
    if (!*set)
        *set = calloc(words(st->geometry_count) ? words(st->geometry_count) : 1, sizeof **set);
    return *set != NULL;
}

static void mark_dirty(frame_state *st, uint32_t first, uint32_t end)
{
    if (st->dirty_first >= st->dirty_end) {
        st->dirty_first = first;
        st->dirty_end = end;
        return;
    }
    if (first < st->dirty_first)
        st->dirty_first = first;
    if (end > st->dirty_end)
        st->dirty_end = end;
}

void frame_state_init(frame_state *st, const struct renderer *r, bool shadows, int threads, uint32_t geometry_count)
{
    memset(st, 0, sizeof *st);
    st->renderer = r;
    st->shadows = shadows;
    st->threads = threads;
    st->geometry_count = geometry_count;
    st->opacity = 1.f; /* the planes stay off (on = false) from the memset */
}

void frame_state_finish(frame_state *st)
{
    free(st->hidden);
    free(st->highlight);
    free(st->coloured);
    free(st->colour);
    free(st->moved);
    free(st->part_opacity);
    free(st->crop);
    free(st->cropped);
    free(st->value);
    free(st->valued);
    free(st->colormap);
    free(st->mapped);
    st->value = NULL;
    st->valued = st->mapped = NULL;
    st->colormap = NULL;
    st->crop = NULL;
    st->cropped = NULL;
    st->moved = NULL;
    st->part_opacity = NULL;
    st->translucent_count = 0;
    st->hidden = st->highlight = st->coloured = NULL;
    st->colour = NULL;
}

int frame_state_add_channel(frame_state *st, const camera_desc *c)
{
    if (st->channel_count == FRAME_STATE_MAX_CHANNELS)
        return -1;
    int i = st->channel_count++;
    st->cameras[i] = *c;
    st->camera_serials[i] = 0;
    st->active[i] = true;
    st->private_view[i] = false;
    return i;
}

void frame_state_set_private(frame_state *st, int channel)
{
    if (channel >= 0 && channel < st->channel_count)
        st->private_view[channel] = true;
}

bool frame_state_adopt_hidden(frame_state *st, const struct accel *a)
{
    for (uint32_t id = 0; id < st->geometry_count; id++)
        if (accel_hidden(a, id)) {
            if (!ensure_bits(st, &st->hidden))
                return false;
            st->hidden[id / 64] |= (uint64_t)1 << (id % 64);
            st->hidden_count++;
        }
    return true;
}

void frame_state_set_camera(frame_state *st, int channel, const camera_desc *c)
{
    /* the same camera again (a path player holding its last key, every frame) is no change of
     * the picture: the governor may refine behind it */
    const camera_desc *old = &st->cameras[channel];
    bool same = old->eye.x == c->eye.x && old->eye.y == c->eye.y && old->eye.z == c->eye.z &&
                old->look_at.x == c->look_at.x && old->look_at.y == c->look_at.y && old->look_at.z == c->look_at.z &&
                old->up.x == c->up.x && old->up.y == c->up.y && old->up.z == c->up.z && old->fov_deg == c->fov_deg;
    st->cameras[channel] = *c;
    st->camera_serials[channel]++;
    if (!same)
        st->picture_serial++;
    st->version++;
}

void frame_state_set_active(frame_state *st, int channel, bool on)
{
    if (st->active[channel] != on)
        st->picture_serial++;
    st->active[channel] = on;
    st->version++;
}

void frame_state_set_threads(frame_state *st, int threads)
{
    st->threads = threads;
    st->version++;
}

void frame_state_set_status(frame_state *st, const char *text)
{
    size_t n = strnlen(text, sizeof st->status - 1);
    memcpy(st->status, text, n);
    st->status[n] = '\0';
    st->version++;
}

void frame_state_set_cursor(frame_state *st, bool on, float sx, float sy)
{
    if (on != st->cursor_visible || sx != st->cursor_sx || sy != st->cursor_sy)
        st->overlay_serial++;
    st->cursor_visible = on;
    st->cursor_sx = sx;
    st->cursor_sy = sy;
    st->version++;
}

void frame_state_set_pointer(frame_state *st, int slot, bool on, float sx, float sy)
{
    if (on != st->pointer_visible[slot] || (on && (sx != st->pointer_sx[slot] || sy != st->pointer_sy[slot])))
        st->overlay_serial++;
    st->pointer_visible[slot] = on;
    st->pointer_sx[slot] = sx;
    st->pointer_sy[slot] = sy;
    st->version++;
}

void frame_state_set_governor_status(frame_state *st, bool shown)
{
    st->governor_status_shown = shown;
    st->version++;
}

void frame_state_set_shadows(frame_state *st, bool on)
{
    if (st->shadows != on)
        st->picture_serial++;
    st->shadows = on;
    st->version++;
}

void frame_state_set_renderer(frame_state *st, const struct renderer *r)
{
    if (st->renderer != r)
        st->picture_serial++;
    st->renderer = r;
    st->version++;
}

bool frame_state_set_hidden(frame_state *st, uint32_t first, uint32_t count, bool hidden)
{
    if (!st->hidden && !hidden) { /* nothing is hidden: showing changes nothing */
        st->version++;
        return true;
    }
    if (!ensure_bits(st, &st->hidden))
        return false;
    uint32_t changed = set_bits(st->hidden, first, count, hidden);
    if (hidden)
        st->hidden_count += changed;
    else
        st->hidden_count -= changed;
    if (changed) {
        st->picture_serial++;
        mark_dirty(st, first, first + count);
    }
    st->version++;
    return true;
}

bool frame_state_isolate(frame_state *st, uint32_t first, uint32_t count)
{
    if (!ensure_bits(st, &st->hidden))
        return false;
    uint32_t changed = set_bits(st->hidden, 0, first, true);
    changed += set_bits(st->hidden, first, count, false);
    uint32_t end = first + count;
    changed += set_bits(st->hidden, end, st->geometry_count - end, true);
    st->hidden_count = st->geometry_count - count;
    if (changed) {
        st->picture_serial++;
        mark_dirty(st, 0, st->geometry_count);
    }
    st->version++;
    return true;
}

void frame_state_show_all(frame_state *st)
{
    if (st->hidden)
        memset(st->hidden, 0, words(st->geometry_count) * sizeof *st->hidden);
    st->hidden_count = 0;
    st->accel_unhide_all = true;
    st->dirty_first = st->dirty_end = 0; /* unhide-all covers every id */
    st->picture_serial++;                /* always, as the pipeline's unhide-all did */
    st->version++;
}

bool frame_state_set_highlight(frame_state *st, uint32_t first, uint32_t count, bool on)
{
    if (!st->highlight && !on) {
        st->version++;
        return true;
    }
    if (!ensure_bits(st, &st->highlight))
        return false;
    if (set_bits(st->highlight, first, count, on))
        st->picture_serial++;
    st->version++;
    return true;
}

bool frame_state_set_move(frame_state *st, uint32_t first, uint32_t count, const affine3 *m)
{
    if (!st->moved) {
        if (affine3_is_identity(m)) { /* nothing was ever moved: nothing to put back */
            st->version++;
            return true;
        }
        st->moved = malloc((size_t)(st->geometry_count ? st->geometry_count : 1) * sizeof *st->moved);
        if (!st->moved)
            return false;
        for (uint32_t i = 0; i < st->geometry_count; i++)
            st->moved[i] = affine3_identity();
    }
    bool changed = false;
    for (uint64_t id = first; id < (uint64_t)first + count; id++) {
        changed = changed || memcmp(&st->moved[id], m, sizeof *m) != 0;
        st->moved[id] = *m;
    }
    if (changed) {
        st->picture_serial++;
        if (st->moved_first >= st->moved_end) {
            st->moved_first = first;
            st->moved_end = first + count;
        } else {
            st->moved_first = first < st->moved_first ? first : st->moved_first;
            st->moved_end = first + count > st->moved_end ? first + count : st->moved_end;
        }
    }
    st->version++;
    return true;
}

bool frame_state_set_colour(frame_state *st, uint32_t first, uint32_t count, const float *rgb)
{
    if (!st->coloured && !rgb) {
        st->version++;
        return true;
    }
    if (!st->colour) {
        vec3 *c = calloc(st->geometry_count ? st->geometry_count : 1, sizeof *c);
        if (!c || !ensure_bits(st, &st->coloured)) {
            free(c);
            return false;
        }
        st->colour = c;
    }
    bool changed = set_bits(st->coloured, first, count, rgb != NULL) > 0;
    if (rgb)
        for (uint64_t id = first; id < (uint64_t)first + count; id++) {
            vec3 *c = &st->colour[id];
            changed = changed || c->x != rgb[0] || c->y != rgb[1] || c->z != rgb[2];
            *c = (vec3){rgb[0], rgb[1], rgb[2]};
        }
    if (changed)
        st->picture_serial++;
    st->version++;
    return true;
}

void frame_state_set_global_opacity(frame_state *st, float opacity)
{
    if (st->opacity != opacity)
        st->picture_serial++;
    st->opacity = opacity;
    st->version++;
}

bool frame_state_set_opacity(frame_state *st, uint32_t first, uint32_t count, float opacity)
{
    if (!st->part_opacity) {
        if (opacity == 1.f) { /* every part is opaque already: nothing to allocate */
            st->version++;
            return true;
        }
        float *a = malloc((size_t)(st->geometry_count ? st->geometry_count : 1) * sizeof *a);
        if (!a)
            return false;
        for (uint32_t i = 0; i < st->geometry_count; i++)
            a[i] = 1.f;
        st->part_opacity = a;
    }
    bool changed = false;
    for (uint64_t id = first; id < (uint64_t)first + count; id++) {
        float *o = &st->part_opacity[id];
        if (*o == opacity)
            continue;
        changed = true;
        /* translucent_count counts entries below 1: it moves when one crosses 1 */
        if (*o < 1.f && !(opacity < 1.f))
            st->translucent_count--;
        else if (!(*o < 1.f) && opacity < 1.f)
            st->translucent_count++;
        *o = opacity;
    }
    if (changed)
        st->picture_serial++;
    st->version++;
    return true;
}

bool frame_state_set_crop(frame_state *st, uint32_t first, uint32_t count, geometry_crop crop)
{
    if (!st->crop) {
        geometry_crop *c = calloc((size_t)(st->geometry_count ? st->geometry_count : 1), sizeof *c);
        if (!c)
            return false;
        if (!ensure_bits(st, &st->cropped)) {
            free(c);
            return false;
        }
        st->crop = c;
    }
    bool changed = false;
    for (uint64_t id = first; id < (uint64_t)first + count; id++) {
        geometry_crop *c = &st->crop[id];
        if (!bit(st->cropped, (uint32_t)id) || c->active != crop.active || c->lo != crop.lo || c->hi != crop.hi)
            changed = true;
        *c = crop;
        st->cropped[id / 64] |= 1ull << (id % 64);
    }
    if (count > 0) {
        uint32_t end = (uint32_t)((uint64_t)first + count);
        if (st->crop_first == st->crop_end)
            st->crop_first = first, st->crop_end = end;
        else
            st->crop_first = first < st->crop_first ? first : st->crop_first,
            st->crop_end = end > st->crop_end ? end : st->crop_end;
    }
    if (changed)
        st->picture_serial++;
    st->version++;
    return true;
}

/* Widen [*first, *end) to hold [first, first + count). */
static void widen(uint32_t *lo, uint32_t *hi, uint32_t first, uint32_t count)
{
    if (count == 0)
        return;
    uint32_t end = (uint32_t)((uint64_t)first + count);
    if (*lo == *hi) {
        *lo = first, *hi = end;
        return;
    }
    *lo = first < *lo ? first : *lo;
    *hi = end > *hi ? end : *hi;
}

bool frame_state_set_value(frame_state *st, uint32_t first, uint32_t count, float v)
{
    if (!st->value) {
        float *a = calloc((size_t)(st->geometry_count ? st->geometry_count : 1), sizeof *a);
        if (!a || !ensure_bits(st, &st->valued)) {
            free(a);
            return false;
        }
        st->value = a;
    }
    bool changed = false;
    for (uint64_t id = first; id < (uint64_t)first + count; id++) {
        changed |= !bit(st->valued, (uint32_t)id) || st->value[id] != v;
        st->value[id] = v;
        st->valued[id / 64] |= 1ull << (id % 64);
    }
    widen(&st->value_first, &st->value_end, first, count);
    if (changed)
        st->picture_serial++;
    st->version++;
    return true;
}

bool frame_state_set_colormap(frame_state *st, uint32_t first, uint32_t count, const char *name)
{
    if (!st->colormap) {
        char(*a)[FRAME_STATE_NAME_BYTES] = calloc((size_t)(st->geometry_count ? st->geometry_count : 1), sizeof *a);
        if (!a || !ensure_bits(st, &st->mapped)) {
            free(a);
            return false;
        }
        st->colormap = a;
    }
    bool changed = false;
    for (uint64_t id = first; id < (uint64_t)first + count; id++) {
        changed |= !bit(st->mapped, (uint32_t)id) || strcmp(st->colormap[id], name) != 0;
        snprintf(st->colormap[id], FRAME_STATE_NAME_BYTES, "%s", name);
        st->mapped[id / 64] |= 1ull << (id % 64);
    }
    widen(&st->map_first, &st->map_end, first, count);
    if (changed)
        st->picture_serial++;
    st->version++;
    return true;
}

bool frame_state_value(const frame_state *st, uint32_t id, float *v)
{
    if (id >= st->geometry_count || !bit(st->valued, id))
        return false;
    if (v)
        *v = st->value[id];
    return true;
}

bool frame_state_colormap(const frame_state *st, uint32_t id, const char **name)
{
    if (id >= st->geometry_count || !bit(st->mapped, id))
        return false;
    if (name)
        *name = st->colormap[id];
    return true;
}

void frame_state_set_transfer(frame_state *st, const char *name)
{
    if (strcmp(st->transfer, name) != 0) {
        snprintf(st->transfer, sizeof st->transfer, "%s", name);
        st->picture_serial++;
    }
    st->transfer_dirty = true;
    st->version++;
}

void frame_state_set_time_step(frame_state *st, uint32_t step)
{
    if (step != st->time_step) {
        st->time_step = step;
        st->time_step_dirty = true;
        st->picture_serial++;
    }
    st->version++;
}

bool frame_state_crop(const frame_state *st, uint32_t id, geometry_crop *out)
{
    if (id >= st->geometry_count || !bit(st->cropped, id))
        return false;
    if (out)
        *out = st->crop[id];
    return true;
}

void frame_state_set_clip_plane(frame_state *st, int index, const clip_plane *p)
{
    clip_plane *old = &st->clip[index];
    /* a plane that is off clips nothing: changing one that stays off changes no picture */
    bool moved = old->point.x != p->point.x || old->point.y != p->point.y || old->point.z != p->point.z ||
                 old->normal.x != p->normal.x || old->normal.y != p->normal.y || old->normal.z != p->normal.z;
    if (old->on != p->on || (p->on && moved))
        st->picture_serial++;
    *old = *p;
    st->version++;
}

void frame_state_bump_overlay(frame_state *st) { st->overlay_serial++; }

bool frame_state_hidden(const frame_state *st, uint32_t id)
{
    return id < st->geometry_count && bit(st->hidden, id);
}

bool frame_state_highlighted(const frame_state *st, uint32_t id)
{
    return id < st->geometry_count && bit(st->highlight, id);
}

bool frame_state_colour(const frame_state *st, uint32_t id, vec3 *rgb)
{
    if (id >= st->geometry_count || !bit(st->coloured, id))
        return false;
    if (rgb)
        *rgb = st->colour[id];
    return true;
}

float frame_state_opacity(const frame_state *st, uint32_t id)
{
    if (!st->part_opacity || id >= st->geometry_count)
        return st->opacity;
    return st->opacity * st->part_opacity[id];
}

bool frame_state_transparent(const frame_state *st) { return st->opacity < 1.f || st->translucent_count > 0; }

const clip_plane *frame_state_clip_planes(const frame_state *st) { return st->clip; }

uint32_t frame_state_sync_accel(frame_state *st, const struct accel *a)
{
    uint32_t calls = 0;
    if (st->accel_unhide_all) {
        accel_unhide_all(a);
        st->accel_unhide_all = false;
        calls++;
    }
    /* runs of ids that change the same way go as one range: showing refits
     * the accel's instance level once per call, so a subtree shown is one
     * refit, not one per instance */
    for (uint32_t id = st->dirty_first; id < st->dirty_end;) {
        bool want = bit(st->hidden, id);
        if (accel_hidden(a, id) == want) {
            id++;
            continue;
        }
        uint32_t run = id + 1;
        while (run < st->dirty_end && bit(st->hidden, run) == want && accel_hidden(a, run) != want)
            run++;
        accel_set_hidden_range(a, id, run - id, want);
        calls++;
        id = run;
    }
    st->dirty_first = st->dirty_end = 0;
    if (st->moved && st->moved_first < st->moved_end) {
        accel_set_placement(a, st->moved_first, st->moved_end - st->moved_first, st->moved + st->moved_first);
        calls++;
    }
    st->moved_first = st->moved_end = 0;
    for (uint32_t id = st->crop_first; id < st->crop_end; id++)
        if (bit(st->cropped, id)) {
            accel_set_crop(a, id, st->crop[id]);
            calls++;
        }
    st->crop_first = st->crop_end = 0;
    for (uint32_t id = st->value_first; id < st->value_end; id++)
        if (bit(st->valued, id)) {
            accel_set_value(a, id, st->value[id]);
            calls++;
        }
    st->value_first = st->value_end = 0;
    for (uint32_t id = st->map_first; id < st->map_end; id++)
        if (bit(st->mapped, id)) {
            accel_set_colormap(a, id, st->colormap[id]);
            calls++;
        }
    st->map_first = st->map_end = 0;
    if (st->transfer_dirty) {
        accel_set_transfer(a, st->transfer);
        st->transfer_dirty = false;
        calls++;
    }
    if (st->time_step_dirty) {
        tess_error err = {{0}};
        if (!accel_set_time_step(a, st->time_step, &err))
            log_warn("time step %u: %s (the step shown stays)", st->time_step, err.msg);
        st->time_step_dirty = false;
        calls++;
    }
    /* what was hidden leaves the instance level's boxes (one refit) */
    accel_commit(a);
    return calls;
}
