/* kernels.h - the traversal kernels of one instruction set, as a table
 * resolved once and called once per ray or packet (never NULL entries).
 *
 * Each ISA's table comes from engine/accel/isa/traverse.c compiled with that ISA's
 * flags; kernels_select() picks the best one the CPU supports at run time
 * (TESSERA_ISA=sse2|avx2|avx512 forces one, for tests and comparisons). All
 * tables give bit-identical results.
 *
 * TESSERA_ISA_MAX=sse2|avx2|avx512 caps the instruction sets tessera may use:
 * above the cap an ISA is as unusable as on a CPU that lacks it (kernels_for
 * gives NULL, kernels_select and accel_use_isa pass it by), so a machine with
 * AVX-512 runs as one with only AVX2 (or only SSE2) would: CI runs the kernel,
 * robustness and image tests under each cap (make test-isa-caps). Unset or
 * empty: no cap. Both variables are read when asked, never cached, except by
 * kernels_default (once per process). */
#ifndef TESSERA_KERNELS_H
#define TESSERA_KERNELS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"
#include "packet.h"
#include "ray.h"
#include "wbvh.h"

struct camera_basis;

typedef struct kernel_table {
    const char *isa_name; /* "sse2", "avx2", "avx512" */
    /* One ray against one geometry. Closest hit (any = false): improves *h by
     * (t, geom_id, prim_id) order and shrinks r->t_far; any hit: stops at the
     * first. Returns whether a hit was recorded. */
    bool (*intersect1)(const wbvh *w, uint32_t geom_id, ray *r, const ray_derived *d, hit *h, bool any);
    /* The rays of `mask` in p against one geometry (p's inverse directions must
     * be derived). Closest hit: updates hit_* and t_far of rays that improve,
     * returns the mask of those. Any hit: returns the mask of rays that hit
     * (the caller stops tracing them). */
    uint64_t (*intersect_packet)(const wbvh *w, uint32_t geom_id, ray_packet *p, uint64_t mask, bool any);
    /* The rays of `mask` that may be traced (not ray_is_degenerate). */
    uint64_t (*traceable)(const ray_packet *p, uint64_t mask);
    /* Directions of packet_primary's rays [0, w*h): the arithmetic of
     * camera_pixel_direction + v3_normalize, lane by lane. */
    void (*primary_directions)(ray_packet *p, const struct camera_basis *cam, int x0, int y0, int w, int h);
} kernel_table;

typedef enum kernel_isa { KERNEL_ISA_SSE2, KERNEL_ISA_AVX2, KERNEL_ISA_AVX512, KERNEL_ISA_COUNT } kernel_isa;

/* The ISA of this name ("sse2", "avx2", "avx512"); KERNEL_ISA_COUNT when none. */
kernel_isa kernels_isa_by_name(const char *name);
/* The name of an ISA ("?" for none), whether or not it is usable here. */
const char *kernels_isa_name(kernel_isa isa);
/* Whether tessera may use isa here: the CPU runs it and TESSERA_ISA_MAX does
 * not cap it. If not and why is given, why says so in a phrase ("this CPU
 * lacks avx512", "TESSERA_ISA_MAX=avx2 caps it"). */
bool kernels_usable(kernel_isa isa, char *why, size_t why_bytes);
/* TESSERA_ISA_MAX and TESSERA_ISA, when set, name an ISA; else false and err
 * names the variable, its value and the choices (the CLI refuses to start). */
bool kernels_check_env(tess_error *err);
/* The table for an ISA, or NULL when it is not usable (kernels_usable). */
const kernel_table *kernels_for(kernel_isa isa);
/* The best usable table, or the one TESSERA_ISA names (if usable). */
const kernel_table *kernels_select(void);
/* kernels_select(), resolved once per process (thread-safe). */
const kernel_table *kernels_default(void);

extern const kernel_table kernel_table_sse2, kernel_table_avx2, kernel_table_avx512;

#endif
