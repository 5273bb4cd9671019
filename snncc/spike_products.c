/* Products of spike inputs by a large matrix over the nonzero inputs only (spike_products.py builds, caches and
 * calls these; BLAS runs where no compiler builds them):
 *
 *     out[b, j] = sum over i ascending with x[b, i] != 0 of  x[b, i] * m[i, j]
 *
 * x: (batch, n_in) integers 0..255 (spikes, spike counts); m: (n_in, n_out) row-major. The matrix is read once per
 * call, a row for every input that some sample has nonzero, and the rows of the silent inputs cost nothing.
 *
 * Integer weights (int8, int16) sum in int32: the caller guarantees max|x| * max_j sum_i |m[i, j]| < 2**24, so no
 * sum overflows and each is the float64 product's exact integer. Float weights (float, double) sum in double, one
 * input after another in ascending order, each term x * m exact (8-bit x times float m fits double's 53 bits; the
 * caller passes double weights only with x of 0 and 1). */
#include <stdint.h>
#include <string.h>

#define MAX_BATCH 256

#define PRODUCT(NAME, T, ACC)                                                                                  \
    int64_t NAME(const uint8_t *restrict x, int64_t batch, int64_t n_in, const T *restrict m, int64_t n_out,  \
                 ACC *restrict out) {                                                                          \
        if (batch > MAX_BATCH || batch < 0) return -1;                                                         \
        memset(out, 0, sizeof(ACC) * (size_t)(batch * n_out));                                                \
        int64_t active[MAX_BATCH];                                                                             \
        for (int64_t i = 0; i < n_in; i++) {                                                                   \
            int64_t k = 0;                                                                                     \
            for (int64_t b = 0; b < batch; b++)                                                                \
                if (x[b * n_in + i]) active[k++] = b;                                                          \
            if (!k) continue;                                                                                  \
            const T *restrict row = m + i * n_out;                                                             \
            for (int64_t a = 0; a < k; a++) {                                                                  \
                ACC *restrict o = out + active[a] * n_out;                                                     \
                const ACC times = (ACC)x[active[a] * n_in + i];                                                \
                if (times == (ACC)1)                                                                           \
                    for (int64_t j = 0; j < n_out; j++) o[j] += (ACC)row[j];                                   \
                else                                                                                           \
                    for (int64_t j = 0; j < n_out; j++) o[j] += times * (ACC)row[j];                           \
            }                                                                                                  \
        }                                                                                                      \
        return 0;                                                                                              \
    }

PRODUCT(snncc_spike_product_i8, int8_t, int32_t)
PRODUCT(snncc_spike_product_i16, int16_t, int32_t)
PRODUCT(snncc_spike_product_f32, float, double)
PRODUCT(snncc_spike_product_f64, double, double)
