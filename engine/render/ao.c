/* ao.c - ambient-occlusion directions (ao.h). */
#include "ao.h"

#include <math.h>

/* Sobol's second dimension: generator column j is V[j] = V[j-1] XOR (V[j-1] >> 1),
 * V[0] = 2^31 (direction numbers m_j = 1, 3, 5, 15, 17, ... of the polynomial x + 1). */
void ao_sequence(uint32_t j, uint32_t *u_bits, uint32_t *v_bits)
{
    /* first dimension: the bits of j reversed (van der Corput) */
    uint32_t r = j;
    r = (r >> 16) | (r << 16);
    r = ((r & 0xff00ff00u) >> 8) | ((r & 0x00ff00ffu) << 8);
    r = ((r & 0xf0f0f0f0u) >> 4) | ((r & 0x0f0f0f0fu) << 4);
    r = ((r & 0xccccccccu) >> 2) | ((r & 0x33333333u) << 2);
    r = ((r & 0xaaaaaaaau) >> 1) | ((r & 0x55555555u) << 1);
    *u_bits = r;
    uint32_t v = 0, column = 1u << 31;
    for (uint32_t bits = j; bits; bits >>= 1, column ^= column >> 1)
        if (bits & 1u)
            v ^= column;
    *v_bits = v;
}

/* Smallest power of 2 >= n (n >= 1, n <= 2^31). */
static uint32_t power_of_two_at_least(uint32_t n)
{
    uint32_t p = 1;
    while (p < n)
        p <<= 1;
    return p;
}

void ao_set_point(int ray_count, uint32_t frame, int set, int ray_index, float *u, float *v)
{
    uint32_t n = (uint32_t)ray_count;
    uint32_t own_u, own_v, shift_u, shift_v;
    ao_sequence(frame * n + (uint32_t)ray_index, &own_u, &own_v);
    ao_sequence((uint32_t)set * power_of_two_at_least(n), &shift_u, &shift_v);
    uint32_t bu = own_u ^ shift_u ^ AO_SEQUENCE_SHIFT_U, bv = own_v ^ shift_v ^ AO_SEQUENCE_SHIFT_V;
    /* the top 24 bits: exact in float, and < 1 */
    *u = (float)(bu >> 8) * 0x1p-24f;
    *v = (float)(bv >> 8) * 0x1p-24f;
}

vec3 ao_cosine_direction(float u, float v)
{
    /* concentric map of [-1, 1]^2 onto the unit disk: square rings to circles */
    const float quarter_pi = 0.78539816339744831f;
    float a = 2.f * u - 1.f, b = 2.f * v - 1.f;
    float r, phi;
    if (a == 0.f && b == 0.f) {
        r = 0.f;
        phi = 0.f;
    } else if (fabsf(a) > fabsf(b)) {
        r = a;
        phi = quarter_pi * (b / a);
    } else {
        r = b;
        phi = 2.f * quarter_pi - quarter_pi * (a / b);
    }
    float x = r * cosf(phi), y = r * sinf(phi);
    float z2 = 1.f - x * x - y * y;
    /* the disk point's rounding can put it a hair outside: keep z > 0 (a direction on the
     * tangent plane would be a ray along the surface) */
    float z = z2 > 0x1p-24f ? sqrtf(z2) : 0x1p-12f;
    return v3_normalize(v3(x, y, z));
}

ao_basis ao_basis_from_normal(vec3 n)
{
    float sign = copysignf(1.f, n.z);
    float a = -1.f / (sign + n.z);
    float b = n.x * n.y * a;
    ao_basis f;
    f.t = v3(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.b = v3(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}

void ao_direction_sets_fill(ao_direction_sets *d, int interleave, int ray_count, uint32_t frame)
{
    interleave = interleave < 1 ? 1 : interleave > AO_MAX_INTERLEAVE ? AO_MAX_INTERLEAVE : interleave;
    ray_count = ray_count < 1 ? 1 : ray_count > AO_MAX_RAYS ? AO_MAX_RAYS : ray_count;
    d->interleave = interleave;
    d->ray_count = ray_count;
    d->frame = frame;
    for (int c = 0; c < interleave * interleave; c++)
        for (int s = 0; s < ray_count; s++) {
            float u, v;
            ao_set_point(ray_count, frame, c, s, &u, &v);
            vec3 w = ao_cosine_direction(u, v);
            int i = c * ray_count + s;
            d->x[i] = w.x;
            d->y[i] = w.y;
            d->z[i] = w.z;
        }
}
