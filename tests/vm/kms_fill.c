/* kms_fill: light every connected head of a DRM device with one solid colour.
 *
 * For each connected connector (head i = i-th connector of the device) it
 * picks a mode, creates an XRGB8888 dumb buffer of that size, fills it with
 * the head's colour and shows it with a legacy drmModeSetCrtc. Then it
 * creates the marker file (-m) and keeps the picture on screen until the ack
 * file (-a) appears or the wait (-w) runs out.
 *
 * usage: kms_fill [-d DEV] [-r WxH[,WxH...]] [-c RRGGBB[,RRGGBB...]]
 *                 [-m MARKER] [-a ACK] [-w SECS] [-v]
 *   -d  device                              (default /dev/dri/card0)
 *   -r  mode of head 0, 1, ...; the last one repeats. Without -r: the mode
 *       given on the kernel command line (video=..., flagged userdef; that
 *       is what run-guest.sh -r sets), else the smallest one. Heads 1+ of a
 *       qemu virtio-gpu without a display UI list 5120x2160 first and mark
 *       no mode preferred, so never take "preferred else first" blindly.
 *   -c  colour of head 0, 1, ... (default c81e3c,1eb464,3c50dc,f0c814)
 *   -m  file to create once every head shows its colour
 *   -a  file to wait for before exiting (give up after -w seconds, exit 1)
 *   -w  seconds: the longest wait for the ack file (default 60); without -a,
 *       how long to keep the picture on screen (default 0)
 *   -v  list every connector's modes
 * Prints one line per head: "head I CONNECTOR WxH RRGGBB". Exit status 0 if
 * every connected head was lit (and the ack came, when asked), 1 otherwise.
 *
 * build: gcc -std=c11 -O2 -o kms_fill kms_fill.c $(pkg-config --cflags --libs libdrm)
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <drm_fourcc.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#define MAX_HEADS 16

struct head {
    int index;                /* connector index = qemu head */
    uint32_t connector, crtc, fb, handle;
    drmModeModeInfo mode;
    uint32_t colour;
    char name[32];
};

static int list_opt(const char *s, int max, int (*parse)(const char *, void *, size_t), void *out,
                    size_t size)
{
    int n = 0;
    char *copy = strdup(s), *save = NULL;
    for (char *tok = strtok_r(copy, ",", &save); tok && n < max; tok = strtok_r(NULL, ",", &save)) {
        if (parse(tok, (char *)out + (size_t)n * size, size)) {
            free(copy);
            return -1;
        }
        n++;
    }
    free(copy);
    return n;
}

struct size { unsigned w, h; };

static int parse_size(const char *s, void *out, size_t size)
{
    (void)size;
    struct size *sz = out;
    char tail;
    return sscanf(s, "%ux%u%c", &sz->w, &sz->h, &tail) == 2 && sz->w && sz->h ? 0 : -1;
}

static int parse_colour(const char *s, void *out, size_t size)
{
    (void)size;
    char *end;
    unsigned long v = strtoul(s, &end, 16);
    if (strlen(s) != 6 || *end || v > 0xffffff) return -1;
    *(uint32_t *)out = (uint32_t)v;
    return 0;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec / 1e9;
}

static void print_modes(const drmModeConnector *c)
{
    for (int m = 0; m < c->count_modes; m++) {
        const drmModeModeInfo *mi = &c->modes[m];
        printf("    mode %d: %ux%u@%u%s%s\n", m, mi->hdisplay, mi->vdisplay, mi->vrefresh,
               mi->type & DRM_MODE_TYPE_PREFERRED ? " preferred" : "",
               mi->type & DRM_MODE_TYPE_USERDEF ? " userdef" : "");
    }
}

/* The mode of the wanted size (userdef, then preferred, then any of that
 * size); without a wanted size the userdef mode, else the one with the
 * fewest pixels. */
static int pick_mode(const drmModeConnector *c, const struct size *want)
{
    int best = -1, score = -1;
    for (int m = 0; m < c->count_modes; m++) {
        const drmModeModeInfo *mi = &c->modes[m];
        int s;
        if (want) {
            if (mi->hdisplay != want->w || mi->vdisplay != want->h) continue;
            s = mi->type & DRM_MODE_TYPE_USERDEF ? 3 : mi->type & DRM_MODE_TYPE_PREFERRED ? 2 : 1;
        } else {
            s = 0x3fffffff - (int)((unsigned)mi->hdisplay * mi->vdisplay / 16);
            if (mi->type & DRM_MODE_TYPE_USERDEF) s = 0x7fffffff;
        }
        if (s > score) { score = s; best = m; }
    }
    return best;
}

static int make_fb(int fd, struct head *h)
{
    struct drm_mode_create_dumb create = {
        .width = h->mode.hdisplay, .height = h->mode.vdisplay, .bpp = 32 };
    if (drmIoctl(fd, DRM_IOCTL_MODE_CREATE_DUMB, &create)) {
        perror("kms_fill: CREATE_DUMB");
        return -1;
    }
    h->handle = create.handle;
    uint32_t handles[4] = { create.handle }, pitches[4] = { create.pitch }, offsets[4] = { 0 };
    if (drmModeAddFB2(fd, create.width, create.height, DRM_FORMAT_XRGB8888, handles, pitches,
                      offsets, &h->fb, 0)) {
        perror("kms_fill: AddFB2");
        return -1;
    }
    struct drm_mode_map_dumb map = { .handle = create.handle };
    if (drmIoctl(fd, DRM_IOCTL_MODE_MAP_DUMB, &map)) {
        perror("kms_fill: MAP_DUMB");
        return -1;
    }
    uint8_t *px = mmap(NULL, create.size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, map.offset);
    if (px == MAP_FAILED) {
        perror("kms_fill: mmap");
        return -1;
    }
    for (uint32_t y = 0; y < create.height; y++) {
        uint32_t *row = (uint32_t *)(px + (size_t)y * create.pitch);
        for (uint32_t x = 0; x < create.width; x++) row[x] = h->colour;
    }
    munmap(px, create.size);
    return 0;
}

static int touch(const char *path)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        fprintf(stderr, "kms_fill: cannot create %s: %s\n", path, strerror(errno));
        return -1;
    }
    return close(fd);
}

int main(int argc, char **argv)
{
    const char *dev = "/dev/dri/card0", *marker = NULL, *ack = NULL;
    struct size sizes[MAX_HEADS];
    uint32_t colours[MAX_HEADS] = { 0xc81e3c, 0x1eb464, 0x3c50dc, 0xf0c814 };
    int nsizes = 0, ncolours = 4, verbose = 0, opt;
    double wait_secs = -1;

    while ((opt = getopt(argc, argv, "d:r:c:m:a:w:v")) != -1) {
        switch (opt) {
        case 'd': dev = optarg; break;
        case 'r':
            nsizes = list_opt(optarg, MAX_HEADS, parse_size, sizes, sizeof sizes[0]);
            if (nsizes <= 0) { fprintf(stderr, "kms_fill: -r: WxH[,WxH...] expected\n"); return 2; }
            break;
        case 'c':
            ncolours = list_opt(optarg, MAX_HEADS, parse_colour, colours, sizeof colours[0]);
            if (ncolours <= 0) { fprintf(stderr, "kms_fill: -c: RRGGBB[,...] expected\n"); return 2; }
            break;
        case 'm': marker = optarg; break;
        case 'a': ack = optarg; break;
        case 'w': wait_secs = atof(optarg); break;
        case 'v': verbose = 1; break;
        default:
            fprintf(stderr, "usage: kms_fill [-d DEV] [-r WxH,...] [-c RRGGBB,...] [-m MARKER] "
                            "[-a ACK] [-w SECS] [-v]\n");
            return 2;
        }
    }

    int fd = open(dev, O_RDWR | O_CLOEXEC);
    if (fd < 0) {
        fprintf(stderr, "kms_fill: %s: %s\n", dev, strerror(errno));
        return 1;
    }
    drmModeRes *res = drmModeGetResources(fd);
    if (!res) {
        fprintf(stderr, "kms_fill: %s is not a KMS device\n", dev);
        return 1;
    }

    struct head heads[MAX_HEADS];
    int nheads = 0, failed = 0;
    uint32_t crtcs_used = 0;
    for (int ci = 0; ci < res->count_connectors && nheads < MAX_HEADS; ci++) {
        drmModeConnector *c = drmModeGetConnector(fd, res->connectors[ci]);
        if (!c) continue;
        struct head *h = &heads[nheads];
        memset(h, 0, sizeof *h);
        h->index = ci;
        h->connector = c->connector_id;
        snprintf(h->name, sizeof h->name, "%s-%u",
                 drmModeGetConnectorTypeName(c->connector_type), c->connector_type_id);
        int connected = c->connection == DRM_MODE_CONNECTED;
        if (verbose) {
            printf("connector %d %s: %s, %d modes\n", ci, h->name,
                   connected ? "connected" : "not connected", c->count_modes);
            print_modes(c);
        }
        if (!connected) { drmModeFreeConnector(c); continue; }

        const struct size *want = nsizes ? &sizes[ci < nsizes ? ci : nsizes - 1] : NULL;
        int m = pick_mode(c, want);
        if (m < 0) {
            fprintf(stderr, "kms_fill: %s has no mode %ux%u; it has:\n", h->name,
                    want ? want->w : 0, want ? want->h : 0);
            print_modes(c);
            drmModeFreeConnector(c);
            failed = 1;
            continue;
        }
        h->mode = c->modes[m];
        h->colour = colours[ci < ncolours ? ci : ncolours - 1];

        for (int e = 0; e < c->count_encoders && !h->crtc; e++) {
            drmModeEncoder *enc = drmModeGetEncoder(fd, c->encoders[e]);
            for (int k = 0; enc && k < res->count_crtcs && k < 32; k++) {
                if ((enc->possible_crtcs & (1u << k)) && !(crtcs_used & (1u << k))) {
                    h->crtc = res->crtcs[k];
                    crtcs_used |= 1u << k;
                    break;
                }
            }
            drmModeFreeEncoder(enc);
        }
        drmModeFreeConnector(c);
        if (!h->crtc) {
            fprintf(stderr, "kms_fill: no free CRTC for %s\n", h->name);
            failed = 1;
            continue;
        }
        if (make_fb(fd, h)) return 1;
        if (drmModeSetCrtc(fd, h->crtc, h->fb, 0, 0, &h->connector, 1, &h->mode)) {
            fprintf(stderr, "kms_fill: SetCrtc on %s: %s\n", h->name, strerror(errno));
            failed = 1;
            continue;
        }
        printf("head %d %s %ux%u %06x\n", h->index, h->name, h->mode.hdisplay, h->mode.vdisplay,
               h->colour);
        nheads++;
    }
    fflush(stdout);
    if (!nheads) {
        fprintf(stderr, "kms_fill: no connected head could be lit\n");
        return 1;
    }
    if (failed) return 1;

    if (marker && touch(marker)) return 1;
    if (wait_secs < 0) wait_secs = ack ? 60 : 0;
    if (ack || wait_secs > 0) {
        struct stat st;
        double end = now() + wait_secs;
        while (!(ack && stat(ack, &st) == 0)) {
            if (now() >= end) {
                if (!ack) break; /* only holding the picture */
                fprintf(stderr, "kms_fill: no %s after %.0f s\n", ack, wait_secs);
                return 1;
            }
            nanosleep(&(struct timespec){ .tv_nsec = 20000000 }, NULL);
        }
    }
    for (int i = 0; i < nheads; i++) {
        drmModeRmFB(fd, heads[i].fb);
        struct drm_mode_destroy_dumb d = { .handle = heads[i].handle };
        drmIoctl(fd, DRM_IOCTL_MODE_DESTROY_DUMB, &d);
    }
    drmModeFreeResources(res);
    close(fd);
    return 0;
}
