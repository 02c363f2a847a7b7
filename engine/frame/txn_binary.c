/* txn_binary.c - the binary form of records (txn.h: txn_encode_binary,
 * txn_decode_binary): fixed TXN_BINARY_BYTES, what a cluster broadcasts. */
#include "txn.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

static void put_u32(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)v;
    b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16);
    b[3] = (unsigned char)(v >> 24);
}

static uint32_t get_u32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static void put_f32(unsigned char *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    put_u32(b, u);
}

static float get_f32(const unsigned char *b)
{
    uint32_t u = get_u32(b);
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* The binary layout of one record's arguments (encode: write t into b; decode: read b into
 * t), one description for both so they never disagree. */
static void layout(txn_record *t, unsigned char *b, bool write)
{
#define U32(off, lv)                                                                                                   \
    do {                                                                                                               \
        if (write)                                                                                                     \
            put_u32(b + (off), (uint32_t)(lv));                                                                        \
        else                                                                                                           \
            (lv) = get_u32(b + (off));                                                                                 \
    } while (0)
#define I32(off, lv)                                                                                                   \
    do {                                                                                                               \
        if (write)                                                                                                     \
            put_u32(b + (off), (uint32_t)(lv));                                                                        \
        else                                                                                                           \
            (lv) = (int32_t)get_u32(b + (off));                                                                        \
    } while (0)
#define F32(off, lv)                                                                                                   \
    do {                                                                                                               \
        if (write)                                                                                                     \
            put_f32(b + (off), (lv));                                                                                  \
        else                                                                                                           \
            (lv) = get_f32(b + (off));                                                                                 \
    } while (0)
#define U8(off, lv)                                                                                                    \
    do {                                                                                                               \
        if (write)                                                                                                     \
            b[off] = (unsigned char)((lv) ? 1 : 0);                                                                    \
        else                                                                                                           \
            (lv) = b[off] != 0;                                                                                        \
    } while (0)
    switch (t->kind) {
    case TXN_CAMERA: {
        camera_desc *c = &t->args.camera.camera;
        float *v[10] = {&c->eye.x, &c->eye.y, &c->eye.z, &c->look_at.x, &c->look_at.y, &c->look_at.z,
                        &c->up.x,  &c->up.y,  &c->up.z,  &c->fov_deg};
        I32(4, t->args.camera.channel);
        for (int i = 0; i < 10; i++)
            F32(8 + 4 * i, *v[i]);
        break;
    }
    case TXN_CURSOR:
        U8(4, t->args.cursor.on);
        F32(8, t->args.cursor.sx);
        F32(12, t->args.cursor.sy);
        break;
    case TXN_POINTER:
        I32(4, t->args.pointer.slot);
        U8(8, t->args.pointer.on);
        F32(12, t->args.pointer.sx);
        F32(16, t->args.pointer.sy);
        break;
    case TXN_STATUS:
        if (write)
            memcpy(b + 4, t->args.status.text, strnlen(t->args.status.text, TXN_TEXT_BYTES));
        else
            memcpy(t->args.status.text, b + 4, TXN_TEXT_BYTES);
        break;
    case TXN_RENDERER:
    case TXN_TRANSFER:
        if (write)
            memcpy(b + 4, t->args.renderer.name, strnlen(t->args.renderer.name, TXN_NAME_BYTES));
        else
            memcpy(t->args.renderer.name, b + 4, TXN_NAME_BYTES);
        break;
    case TXN_GOVERNOR_STATUS:
    case TXN_SHADOWS:
    case TXN_TOUR:
        U8(4, t->args.flag.on);
        break;
    case TXN_HIDE:
    case TXN_SHOW:
    case TXN_ISOLATE:
        U32(4, t->args.geoms.first);
        U32(8, t->args.geoms.count);
        break;
    case TXN_HIGHLIGHT:
        U32(4, t->args.highlight.geoms.first);
        U32(8, t->args.highlight.geoms.count);
        U8(12, t->args.highlight.on);
        break;
    case TXN_COLOUR:
        U32(4, t->args.colour.geoms.first);
        U32(8, t->args.colour.geoms.count);
        U8(12, t->args.colour.reset);
        for (int i = 0; i < 3; i++)
            F32(16 + 4 * i, t->args.colour.rgb[i]);
        break;
    case TXN_THREADS:
        I32(4, t->args.threads.count);
        break;
    case TXN_CHANNEL_ACTIVE:
        I32(4, t->args.channel.channel);
        U8(8, t->args.channel.on);
        break;
    case TXN_MOVE:
        U32(4, t->args.move.geoms.first);
        U32(8, t->args.move.geoms.count);
        for (int i = 0; i < 12; i++)
            F32(12 + 4 * i, t->args.move.m[i]);
        break;
    case TXN_OPACITY:
        U8(4, t->args.opacity.all);
        U32(8, t->args.opacity.geoms.first);
        U32(12, t->args.opacity.geoms.count);
        F32(16, t->args.opacity.a);
        break;
    case TXN_CLIP_PLANE:
        I32(4, t->args.clip_plane.index);
        U8(8, t->args.clip_plane.on);
        for (int i = 0; i < 3; i++)
            F32(12 + 4 * i, t->args.clip_plane.point[i]);
        for (int i = 0; i < 3; i++)
            F32(24 + 4 * i, t->args.clip_plane.normal[i]);
        break;
    case TXN_CROP:
        U32(4, t->args.crop.geoms.first);
        U32(8, t->args.crop.geoms.count);
        U8(12, t->args.crop.on);
        F32(16, t->args.crop.lo);
        F32(20, t->args.crop.hi);
        break;
    case TXN_TIME_STEP:
        U32(4, t->args.time_step.step);
        break;
    case TXN_VALUE:
        U32(4, t->args.value.geoms.first);
        U32(8, t->args.value.geoms.count);
        F32(12, t->args.value.v);
        break;
    case TXN_COLORMAP:
        U32(4, t->args.colormap.geoms.first);
        U32(8, t->args.colormap.geoms.count);
        if (write)
            memcpy(b + 12, t->args.colormap.name, strnlen(t->args.colormap.name, TXN_NAME_BYTES));
        else
            memcpy(t->args.colormap.name, b + 12, TXN_NAME_BYTES);
        break;
    case TXN_SHOW_ALL:
    case TXN_QUIT:
    case TXN_KIND_COUNT:
        break;
    }
#undef U32
#undef I32
#undef F32
#undef U8
}

bool txn_encode_binary(const txn_record *r, unsigned char out[TXN_BINARY_BYTES])
{
    tess_error err = {{0}};
    memset(out, 0, TXN_BINARY_BYTES);
    if (!txn_validate(r, &err))
        return false;
    txn_record copy = *r; /* layout takes a writable record (it reads it here) */
    put_u32(out, (uint32_t)r->kind);
    layout(&copy, out, true);
    return true;
}

bool txn_decode_binary(const unsigned char in[TXN_BINARY_BYTES], txn_record *out, tess_error *err)
{
    uint32_t kind = get_u32(in);
    if (kind >= TXN_KIND_COUNT)
        return tess_error_set(err, "kind: %u is not a transaction kind", kind);
    txn_record t = txn_simple((txn_kind)kind);
    unsigned char bytes[TXN_BINARY_BYTES];
    memcpy(bytes, in, sizeof bytes);
    layout(&t, bytes, false);
    /* every byte the layout does not use must be zero; so must flag bytes other than 0/1 and the
     * padding inside the layout: re-encode and compare */
    unsigned char again[TXN_BINARY_BYTES];
    if (!txn_validate(&t, err))
        return false;
    txn_encode_binary(&t, again);
    if (memcmp(again, in, TXN_BINARY_BYTES) != 0)
        return tess_error_set(err, "%s: bytes that must be zero (or a flag that is not 0 or 1) are not",
                              txn_kind_name(t.kind));
    *out = t;
    return true;
}
