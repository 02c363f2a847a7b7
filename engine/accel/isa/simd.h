/* isa/simd.h - the vector vocabulary the traversal kernels are written in,
 * for the instruction set this translation unit is compiled for:
 *   TESS_ISA_SSE2   (x86-64 baseline)   ray lanes 4,  node lanes 4 (x2)
 *   TESS_ISA_AVX2                        ray lanes 8,  node lanes 8
 *   TESS_ISA_AVX512 (F, VL, DQ, BW)      ray lanes 16, node lanes 8
 * Only IEEE-exact operations (add, sub, mul, div, sqrt, min, max, compares)
 * are exposed and nothing fuses a multiply-add, so every instruction set
 * gives bit-identical results (the tests check it). */
#ifndef TESSERA_ISA_SIMD_H
#define TESSERA_ISA_SIMD_H

#include <immintrin.h>
#include <stdint.h>

#if defined(TESS_ISA_AVX512)
#define ISA_SUFFIX(name) name##_avx512
#define ISA_NAME "avx512"
#define RAY_LANES 16
#elif defined(TESS_ISA_AVX2)
#define ISA_SUFFIX(name) name##_avx2
#define ISA_NAME "avx2"
#define RAY_LANES 8
#elif defined(TESS_ISA_SSE2)
#define ISA_SUFFIX(name) name##_sse2
#define ISA_NAME "sse2"
#define RAY_LANES 4
#else
#error "compile isa/ kernels with one of TESS_ISA_SSE2, TESS_ISA_AVX2, TESS_ISA_AVX512"
#endif

/* ---- 4 lanes (SSE), used by every ISA for 4-primitive blocks ---------- */
typedef __m128 v4;
static inline v4 v4_load(const float *p) { return _mm_load_ps(p); }
static inline v4 v4_set1(float x) { return _mm_set1_ps(x); }
static inline v4 v4_add(v4 a, v4 b) { return _mm_add_ps(a, b); }
static inline v4 v4_sub(v4 a, v4 b) { return _mm_sub_ps(a, b); }
static inline v4 v4_mul(v4 a, v4 b) { return _mm_mul_ps(a, b); }
static inline v4 v4_div(v4 a, v4 b) { return _mm_div_ps(a, b); }
static inline v4 v4_and(v4 a, v4 b) { return _mm_and_ps(a, b); }
static inline v4 v4_or(v4 a, v4 b) { return _mm_or_ps(a, b); }
static inline v4 v4_andnot(v4 a, v4 b) { return _mm_andnot_ps(b, a); } /* a & ~b */
static inline v4 v4_lt(v4 a, v4 b) { return _mm_cmplt_ps(a, b); }
static inline v4 v4_le(v4 a, v4 b) { return _mm_cmple_ps(a, b); }
static inline v4 v4_gt(v4 a, v4 b) { return _mm_cmpgt_ps(a, b); }
static inline v4 v4_eq(v4 a, v4 b) { return _mm_cmpeq_ps(a, b); }
static inline unsigned v4_bits(v4 m) { return (unsigned)_mm_movemask_ps(m); }
static inline v4 v4_abs(v4 a) { return _mm_andnot_ps(_mm_set1_ps(-0.f), a); }

/* ---- node lanes: 8 children per node --------------------------------- */
#if defined(TESS_ISA_SSE2)
#define NODE_LANES 4
typedef __m128 vn;
static inline vn vn_load(const float *p) { return _mm_load_ps(p); }
static inline vn vn_set1(float x) { return _mm_set1_ps(x); }
static inline vn vn_sub(vn a, vn b) { return _mm_sub_ps(a, b); }
static inline vn vn_mul(vn a, vn b) { return _mm_mul_ps(a, b); }
static inline vn vn_min(vn a, vn b) { return _mm_min_ps(a, b); }
static inline vn vn_max(vn a, vn b) { return _mm_max_ps(a, b); }
static inline unsigned vn_le_bits(vn a, vn b) { return (unsigned)_mm_movemask_ps(_mm_cmple_ps(a, b)); }
static inline void vn_store(float *p, vn a) { _mm_store_ps(p, a); }
#else
#define NODE_LANES 8
typedef __m256 vn;
static inline vn vn_load(const float *p) { return _mm256_load_ps(p); }
static inline vn vn_set1(float x) { return _mm256_set1_ps(x); }
static inline vn vn_sub(vn a, vn b) { return _mm256_sub_ps(a, b); }
static inline vn vn_mul(vn a, vn b) { return _mm256_mul_ps(a, b); }
static inline vn vn_min(vn a, vn b) { return _mm256_min_ps(a, b); }
static inline vn vn_max(vn a, vn b) { return _mm256_max_ps(a, b); }
static inline unsigned vn_le_bits(vn a, vn b) { return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)); }
static inline void vn_store(float *p, vn a) { _mm256_store_ps(p, a); }
#endif

/* ---- ray lanes: RAY_LANES rays of a packet --------------------------- */
#if defined(TESS_ISA_AVX512)
typedef __m512 vr;
typedef __mmask16 vm;
static inline vr vr_load(const float *p) { return _mm512_load_ps(p); }
static inline void vr_store(float *p, vr a) { _mm512_store_ps(p, a); }
static inline vr vr_set1(float x) { return _mm512_set1_ps(x); }
static inline vr vr_add(vr a, vr b) { return _mm512_add_ps(a, b); }
static inline vr vr_sub(vr a, vr b) { return _mm512_sub_ps(a, b); }
static inline vr vr_mul(vr a, vr b) { return _mm512_mul_ps(a, b); }
static inline vr vr_div(vr a, vr b) { return _mm512_div_ps(a, b); }
static inline vr vr_min(vr a, vr b) { return _mm512_min_ps(a, b); }
static inline vr vr_max(vr a, vr b) { return _mm512_max_ps(a, b); }
static inline vr vr_sqrt(vr a) { return _mm512_sqrt_ps(a); }
static inline vm vr_lt(vr a, vr b) { return _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ); }
static inline vm vr_le(vr a, vr b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
static inline vm vr_gt(vr a, vr b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
static inline vm vr_eq(vr a, vr b) { return _mm512_cmp_ps_mask(a, b, _CMP_EQ_OQ); }
static inline vm vm_and(vm a, vm b) { return (vm)(a & b); }
static inline vm vm_or(vm a, vm b) { return (vm)(a | b); }
static inline vm vm_andnot(vm a, vm b) { return (vm)(a & ~b); }
static inline unsigned vm_bits(vm m) { return (unsigned)m; }
static inline vm vm_from_bits(unsigned bits) { return (vm)bits; }
static inline vr vr_select(vm m, vr a, vr b) { return _mm512_mask_blend_ps(m, b, a); }
static inline vr vr_abs(vr a) { return _mm512_andnot_ps(_mm512_set1_ps(-0.f), a); }
static inline vr vr_load_u32_as_ps(const uint32_t *p) { return _mm512_castsi512_ps(_mm512_load_si512(p)); }
static inline vr vr_loadu(const float *p) { return _mm512_loadu_ps(p); }
static inline vr vr_neg(vr a) { return _mm512_xor_ps(a, _mm512_set1_ps(-0.f)); }
/* |mag| with the sign of sign (copysignf lane by lane) */
static inline vr vr_copysign(vr mag, vr sign)
{
    const vr s = _mm512_set1_ps(-0.f);
    return _mm512_or_ps(_mm512_andnot_ps(s, mag), _mm512_and_ps(s, sign));
}
static inline void vr_store_ps_as_u32(uint32_t *p, vr a) { _mm512_store_si512(p, _mm512_castps_si512(a)); }
#elif defined(TESS_ISA_AVX2)
typedef __m256 vr;
typedef __m256 vm;
static inline vr vr_load(const float *p) { return _mm256_load_ps(p); }
static inline void vr_store(float *p, vr a) { _mm256_store_ps(p, a); }
static inline vr vr_set1(float x) { return _mm256_set1_ps(x); }
static inline vr vr_add(vr a, vr b) { return _mm256_add_ps(a, b); }
static inline vr vr_sub(vr a, vr b) { return _mm256_sub_ps(a, b); }
static inline vr vr_mul(vr a, vr b) { return _mm256_mul_ps(a, b); }
static inline vr vr_div(vr a, vr b) { return _mm256_div_ps(a, b); }
static inline vr vr_min(vr a, vr b) { return _mm256_min_ps(a, b); }
static inline vr vr_max(vr a, vr b) { return _mm256_max_ps(a, b); }
static inline vr vr_sqrt(vr a) { return _mm256_sqrt_ps(a); }
static inline vm vr_lt(vr a, vr b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
static inline vm vr_le(vr a, vr b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
static inline vm vr_gt(vr a, vr b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
static inline vm vr_eq(vr a, vr b) { return _mm256_cmp_ps(a, b, _CMP_EQ_OQ); }
static inline vm vm_and(vm a, vm b) { return _mm256_and_ps(a, b); }
static inline vm vm_or(vm a, vm b) { return _mm256_or_ps(a, b); }
static inline vm vm_andnot(vm a, vm b) { return _mm256_andnot_ps(b, a); }
static inline unsigned vm_bits(vm m) { return (unsigned)_mm256_movemask_ps(m); }
static inline vm vm_from_bits(unsigned bits)
{
    const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    __m256i b = _mm256_and_si256(_mm256_set1_epi32((int)bits), lane_bit);
    return _mm256_castsi256_ps(_mm256_cmpeq_epi32(b, lane_bit));
}
static inline vr vr_select(vm m, vr a, vr b) { return _mm256_blendv_ps(b, a, m); }
static inline vr vr_abs(vr a) { return _mm256_andnot_ps(_mm256_set1_ps(-0.f), a); }
static inline vr vr_load_u32_as_ps(const uint32_t *p) { return _mm256_load_ps((const float *)(const void *)p); }
static inline vr vr_loadu(const float *p) { return _mm256_loadu_ps(p); }
static inline vr vr_neg(vr a) { return _mm256_xor_ps(a, _mm256_set1_ps(-0.f)); }
static inline vr vr_copysign(vr mag, vr sign)
{
    const vr s = _mm256_set1_ps(-0.f);
    return _mm256_or_ps(_mm256_andnot_ps(s, mag), _mm256_and_ps(s, sign));
}
static inline void vr_store_ps_as_u32(uint32_t *p, vr a) { _mm256_store_ps((float *)(void *)p, a); }
#else
typedef __m128 vr;
typedef __m128 vm;
static inline vr vr_load(const float *p) { return _mm_load_ps(p); }
static inline void vr_store(float *p, vr a) { _mm_store_ps(p, a); }
static inline vr vr_set1(float x) { return _mm_set1_ps(x); }
static inline vr vr_add(vr a, vr b) { return _mm_add_ps(a, b); }
static inline vr vr_sub(vr a, vr b) { return _mm_sub_ps(a, b); }
static inline vr vr_mul(vr a, vr b) { return _mm_mul_ps(a, b); }
static inline vr vr_div(vr a, vr b) { return _mm_div_ps(a, b); }
static inline vr vr_min(vr a, vr b) { return _mm_min_ps(a, b); }
static inline vr vr_max(vr a, vr b) { return _mm_max_ps(a, b); }
static inline vr vr_sqrt(vr a) { return _mm_sqrt_ps(a); }
static inline vm vr_lt(vr a, vr b) { return _mm_cmplt_ps(a, b); }
static inline vm vr_le(vr a, vr b) { return _mm_cmple_ps(a, b); }
static inline vm vr_gt(vr a, vr b) { return _mm_cmpgt_ps(a, b); }
static inline vm vr_eq(vr a, vr b) { return _mm_cmpeq_ps(a, b); }
static inline vm vm_and(vm a, vm b) { return _mm_and_ps(a, b); }
static inline vm vm_or(vm a, vm b) { return _mm_or_ps(a, b); }
static inline vm vm_andnot(vm a, vm b) { return _mm_andnot_ps(b, a); }
static inline unsigned vm_bits(vm m) { return (unsigned)_mm_movemask_ps(m); }
static inline vm vm_from_bits(unsigned bits)
{
    const __m128i lane_bit = _mm_setr_epi32(1, 2, 4, 8);
    __m128i b = _mm_and_si128(_mm_set1_epi32((int)bits), lane_bit);
    return _mm_castsi128_ps(_mm_cmpeq_epi32(b, lane_bit));
}
static inline vr vr_select(vm m, vr a, vr b) { return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)); }
static inline vr vr_abs(vr a) { return _mm_andnot_ps(_mm_set1_ps(-0.f), a); }
static inline vr vr_load_u32_as_ps(const uint32_t *p) { return _mm_load_ps((const float *)(const void *)p); }
static inline vr vr_loadu(const float *p) { return _mm_loadu_ps(p); }
static inline vr vr_neg(vr a) { return _mm_xor_ps(a, _mm_set1_ps(-0.f)); }
static inline vr vr_copysign(vr mag, vr sign)
{
    const vr s = _mm_set1_ps(-0.f);
    return _mm_or_ps(_mm_andnot_ps(s, mag), _mm_and_ps(s, sign));
}
static inline void vr_store_ps_as_u32(uint32_t *p, vr a) { _mm_store_ps((float *)(void *)p, a); }
#endif

#endif
