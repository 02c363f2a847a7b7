/* jpeg.c (remote) - TurboJPEG compression of XRGB8888 frames (jpeg.h). */
#include "jpeg.h"

#include <stdlib.h>
#include <string.h>
#include <turbojpeg.h>

struct remote_jpeg {
    tjhandle tj;
    unsigned char *buf;  /* tjAlloc'd, grown by TurboJPEG as needed (no TJFLAG_NOREALLOC) */
    unsigned long buf_bytes;
};

static const struct {
    const char *name;
    int tj;
} subsamplings[] = {
    [REMOTE_SUBSAMPLING_444] = {"444", TJSAMP_444},
    [REMOTE_SUBSAMPLING_422] = {"422", TJSAMP_422},
    [REMOTE_SUBSAMPLING_420] = {"420", TJSAMP_420},
};

bool remote_subsampling_parse(const char *name, remote_subsampling *out)
{
    for (size_t i = 0; i < sizeof subsamplings / sizeof subsamplings[0]; i++)
        if (name && !strcmp(name, subsamplings[i].name)) {
            *out = (remote_subsampling)i;
            return true;
        }
    return false;
}

const char *remote_subsampling_name(remote_subsampling s)
{
    return (unsigned)s < sizeof subsamplings / sizeof subsamplings[0] ? subsamplings[s].name : "?";
}

remote_jpeg *remote_jpeg_create(tess_error *err)
{
    remote_jpeg *j = calloc(1, sizeof *j);
    if (!j) {
        tess_error_set(err, "jpeg: out of memory");
        return NULL;
    }
    j->tj = tjInitCompress();
    if (!j->tj) {
        tess_error_set(err, "jpeg: TurboJPEG compressor: %s", tjGetErrorStr2(NULL));
        free(j);
        return NULL;
    }
    return j;
}

void remote_jpeg_destroy(remote_jpeg *j)
{
    if (!j)
        return;
    tjDestroy(j->tj);
    tjFree(j->buf);
    free(j);
}

bool remote_jpeg_encode(remote_jpeg *j, const uint32_t *xrgb, int width_px, int height_px, int stride_px,
                        int quality, remote_subsampling sub, const uint8_t **out, size_t *out_bytes,
                        tess_error *err)
{
    if (width_px <= 0 || height_px <= 0 || stride_px < width_px || quality < REMOTE_JPEG_QUALITY_MIN ||
        quality > REMOTE_JPEG_QUALITY_MAX || (unsigned)sub >= sizeof subsamplings / sizeof subsamplings[0]) {
        tess_error_set(err, "jpeg: invalid arguments (%dx%d, stride %d, quality %d)", width_px, height_px, stride_px,
                       quality);
        return false;
    }
    unsigned long bytes = j->buf_bytes;
    /* XRGB8888 words in memory on a little-endian machine: B, G, R, X */
    if (tjCompress2(j->tj, (const unsigned char *)xrgb, width_px, stride_px * 4, height_px, TJPF_BGRX, &j->buf,
                    &bytes, subsamplings[sub].tj, quality, TJFLAG_FASTDCT) != 0) {
        tess_error_set(err, "jpeg: compressing %dx%d: %s", width_px, height_px, tjGetErrorStr2(j->tj));
        return false;
    }
    if (bytes > j->buf_bytes)
        j->buf_bytes = bytes; /* TurboJPEG grew the buffer to at least this */
    *out = j->buf;
    *out_bytes = bytes;
    return true;
}

bool remote_jpeg_decode(const uint8_t *data, size_t bytes, uint32_t **xrgb, int *width_px, int *height_px,
                        tess_error *err)
{
    *xrgb = NULL;
    tjhandle tj = tjInitDecompress();
    if (!tj) {
        tess_error_set(err, "jpeg: TurboJPEG decompressor: %s", tjGetErrorStr2(NULL));
        return false;
    }
    int w = 0, h = 0, samp = 0, space = 0;
    bool ok = false;
    if (tjDecompressHeader3(tj, data, (unsigned long)bytes, &w, &h, &samp, &space) != 0) {
        tess_error_set(err, "jpeg: reading the header: %s", tjGetErrorStr2(tj));
    } else if (w <= 0 || h <= 0 || (size_t)w * (size_t)h > ((size_t)1 << 28)) {
        tess_error_set(err, "jpeg: %dx%d is not a frame size", w, h);
    } else if (!(*xrgb = malloc((size_t)w * (size_t)h * sizeof **xrgb))) {
        tess_error_set(err, "jpeg: out of memory for %dx%d", w, h);
    } else if (tjDecompress2(tj, data, (unsigned long)bytes, (unsigned char *)*xrgb, w, w * 4, h, TJPF_BGRX,
                             TJFLAG_ACCURATEDCT) != 0) {
        tess_error_set(err, "jpeg: decoding: %s", tjGetErrorStr2(tj));
        free(*xrgb);
        *xrgb = NULL;
    } else {
        *width_px = w;
        *height_px = h;
        ok = true;
    }
    tjDestroy(tj);
    return ok;
}
