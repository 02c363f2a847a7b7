/* render.h - the ray tracer: primary rays through a pinhole camera, Lambert
 * and Phong shading with hard shadows from every light, background colour.
 *
 * Shading model (linear RGB, per pixel):
 *   colour = ambient * kd * material.ambient
 *          + sum over lights not shadowed of
 *              E_light * (kd * max(0, N.L) + ks * max(0, R.V)^shininess [Phong])
 * where E_light = color * intensity for a directional light and
 * color * intensity / d^2 for a point light at distance d, kd is the vertex
 * colour when the mesh has one, else the material's diffuse colour. There is no
 * 1/pi: intensity is the radiance scale a white Lambert surface facing the
 * light shows. Surfaces are two-sided (normals face the viewer).
 *
 * Everything here is a pure function of (scene, camera, pixel): images are the
 * same for any thread count and tile order. */
#ifndef TESSERA_RENDER_H
#define TESSERA_RENDER_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/base/err.h"
#include "engine/accel/packet.h"
#include "engine/accel/ray.h"
#include "sampler.h"
#include "engine/base/vec3.h"

struct scene;
struct accel;

typedef enum render_shading {
    RENDER_SHADE_PHONG,    /* the shading model above */
    RENDER_SHADE_EYELIGHT, /* |dot(Ng, dir)| grey, as the Embree peer harness's shade image; with
                              shadows, x 0.2 when the scene's first light is occluded */
} render_shading;

/* Settings of the inspection renderers (pipeline config "render" object,
 * docs/pipeline-config.md): how far transparency, caps and ambient occlusion
 * go. Fixed while a pipeline runs; render_settings_default() is what a view
 * without settings (render_view.settings NULL) uses. */
typedef enum render_cap_style {
    RENDER_CAP_TINT,  /* a cut face in its part's colour, darkened (RENDER_CAP_TINT_FACTOR) */
    RENDER_CAP_HATCH, /* ... with diagonal hatching in screen space */
} render_cap_style;

typedef struct render_settings {
    /* transparency (frame state opacity < 1) */
    float min_transmittance;  /* stop blending layers once the light left is below this; (0, 1) */
    int max_layers;           /* most surfaces blended along one ray, >= 1; the last is taken as opaque */
    bool transparent_shadows; /* shadow rays pass transparent surfaces attenuated by their opacity;
                                 false: every surface casts a full shadow (faster) */
    /* cutting planes */
    bool caps;                /* draw the cut faces of closed parts */
    render_cap_style cap_style;
    /* ambient occlusion (renderers "ao" and "raytracer-ao") */
    int ao_rays;              /* rays per hit, 1..64 (default 16: render_ao.h, DEFAULTS) */
    float ao_distance;        /* world units; <= 0: RENDER_AO_DISTANCE_FRACTION x the scene's bounding-box
                                 diagonal */
    int ao_interleave;        /* K: a K x K pixel pattern of direction sets, 1..8 */
    int ao_filter_px;         /* discontinuity filter edge (odd, 1 = off), <= 9 */
    int ao_frames;            /* F: AO frames averaged per pixel sample, 1..64 (render_ao.h, FRAMES) */
    float ao_exponent;        /* renderer "ao" shows kd x A^exponent, 1..8 (render_ao.h, RESPONSE); 1: linear */
    uint32_t ao_frame_base;   /* first AO frame (render_ao.h, FRAMES); 0 but in tests */
} render_settings;

#define RENDER_MIN_TRANSMITTANCE_DEFAULT (1.f / 255.f)
#define RENDER_MAX_LAYERS_DEFAULT 16
/* ambient occlusion's defaults and limits (render_ao.h, DEFAULTS) */
#define RENDER_AO_DISTANCE_FRACTION 0.2f /* of the scene box's diagonal, when ao_distance <= 0 */
#define RENDER_AO_EXPONENT_DEFAULT 2.2f
#define RENDER_AO_EXPONENT_MAX 8.f

render_settings render_settings_default(void);

typedef struct render_view {
    const struct scene *scene;  /* read-only while rendering */
    const struct accel *accel;  /* built from scene */
    camera_basis camera;        /* includes the image size */
    bool shadows;               /* trace shadow rays (lights may also opt out) */
    render_shading shading;
    const struct frame_state *state; /* the frame's snapshot of the pipeline's frame state (frame_state.h:
                                        per-geometry highlight, colour, opacity; cutting planes);
                                        NULL outside a pipeline */
    const render_settings *settings; /* NULL: render_settings_default() */
} render_view;

/* Rays traced, for benchmarks. */
typedef struct render_counts {
    uint64_t primary_rays;
    uint64_t primary_hits; /* primary rays that hit something */
    uint64_t shadow_rays;
    uint64_t secondary_rays; /* transparency's layers past the first, caps' parity counts */
    uint64_t ao_rays;        /* ambient-occlusion rays (renderers ao and raytracer-ao) */
} render_counts;

/* Tile edge in pixels: 16 x 16 float RGB rows are 192 bytes, whole cache lines. */
#define RENDER_TILE_PX 16

/* Shade the ray's closest hit (or the background); adds the shadow rays it
 * traced to *shadow_rays. */
vec3 render_shade(const render_view *v, const ray *r, uint64_t *shadow_rays);

/* Render pixels [x0, x1) x [y0, y1) into rgb (3 floats per pixel, the whole
 * image, row-major, top row first). */
void render_tile(const render_view *v, int x0, int y0, int x1, int y1, float *rgb, render_counts *counts);

/* Render pixels [x0, x1) x [y0, y1) with a pixel sampler (sampler.h; must be
 * valid): single gives exactly render_tile's result; jittered traces k^2
 * packets per 8 x 8 block, one per stratum, and stores each pixel's mean
 * colour. Pixel values do not depend on how the image is split into tiles.
 * `counts` receives every ray traced (k^2 primary rays per pixel). */
void render_tile_sampled(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                         render_counts *counts);

/* Render the whole image with `threads` threads (the caller's included)
 * pulling tiles from an atomic counter. Threads the system refuses are logged
 * and the image is finished by the others. `counts` (may be NULL) receives
 * the rays traced. */
void render_image(const render_view *v, int threads, float *rgb, render_counts *counts);

/* The renderer component, chosen by name (configs, --renderer): renders a
 * tile of a view with a pixel sampler. The pipeline puts `shading` into the
 * views it hands to render_tile. More renderers (transparency, ambient
 * occlusion, volumes) come with the visualization issues. */
typedef struct renderer {
    const char *name;       /* RENDERER_NAMES */
    render_shading shading;
    void (*render_tile)(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                        render_counts *counts);
} renderer;

#define RENDERER_NAMES "raytracer, eyelight, ao, raytracer-ao"

/* The tile functions of the ambient-occlusion renderers (engine/render/render_ao.h):
 * "ao" (occlusion alone) and "raytracer-ao" (the raytracer with its ambient
 * term scaled by the occlusion). */
void render_ao_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                    render_counts *counts);
void render_raytracer_ao_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1,
                              float *rgb, render_counts *counts);

/* What the raytracer's AO term (render_raytracer_ao_tile) needs of the first
 * surface each primary ray shows: the surface the raytracer shaded first (a
 * cap where a plane cuts a closed part; the nearest surface, transparent or
 * not, otherwise). Set for the rays of `hits` only. */
typedef struct render_first_surfaces {
    uint64_t hits;                            /* rays that met a surface (after the cutting planes) */
    uint32_t geom_id[PACKET_MAX_RAYS];        /* its instance (a cap: its part's) */
    float t[PACKET_MAX_RAYS];                 /* along the ray (its hit_t; a cap: where it meets the plane) */
    vec3 position[PACKET_MAX_RAYS];           /* world */
    vec3 position_error[PACKET_MAX_RAYS];     /* rounding allowance of position (ray.h surface_point) */
    vec3 normal[PACKET_MAX_RAYS];             /* unit geometric normal facing the ray's origin */
    vec3 ambient[PACKET_MAX_RAYS];            /* the part of the ray's colour that is this surface's ambient
                                                 light, times the surface's weight in the blend (its opacity,
                                                 layer 0): what occlusion darkens */
} render_first_surfaces;

/* The raytracer's colours of primary packet p (rays [0, p->count), set up
 * and not yet traced: everything render_tile does to a packet, transparency
 * and cutting planes included) into colour[], and the first surface of every
 * ray into *first. Uses the calling thread's render scratch. */
void render_trace_primary(const render_view *v, ray_packet *p, vec3 colour[PACKET_MAX_RAYS],
                          render_first_surfaces *first, render_counts *counts);

/* The stretches of ray r (world space) through the scene's participating
 * media (scene.h, PARTICIPATING MEDIA), nearest entry first, as the renderers
 * composite them: at most RENDER_MEDIA_SPANS_MAX; their count. */
#define RENDER_MEDIA_SPANS_MAX 8
typedef struct render_media_span {
    float enter, leave; /* along r */
    uint32_t medium;    /* index into the scene's media */
} render_media_span;
uint32_t render_media_spans(const struct scene *s, const ray *r, render_media_span spans[RENDER_MEDIA_SPANS_MAX]);

/* The renderer called `name`, or NULL. */
const renderer *renderer_by_name(const char *name);

/* render_image with a pixel sampler (render_tile_sampled for each tile). */
void render_image_sampled(const render_view *v, const pixel_sampler *s, int threads, float *rgb,
                          render_counts *counts);

/* The threaded driver of the two above with renderer r's tile function and
 * tiles of tile_px pixels (benchmarks and tests; a pipeline has its image
 * traverser): `threads` threads, the caller's included, pull tiles from one
 * atomic counter; `counts` (may be NULL) gets every ray the tiles counted.
 * The shading in v is what r's tile function reads (render_tile_sampled:
 * v->shading), not r->shading. */
void render_image_tiles(const renderer *r, const render_view *v, const pixel_sampler *s, int threads, int tile_px,
                        float *rgb, render_counts *counts);

#endif
