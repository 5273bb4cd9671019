/* The partitioner's kernels in C: numba_kernels.py's rules, one pass over a projection's synapses (O(nnz), no
 * sort), compiled by the system's C compiler (kernels.py builds, caches and calls them; numba where none builds).
 * Synapses are read in CSC order (by source, destinations ascending): cptr[j] .. cptr[j + 1] - 1 are source j's,
 * cidx their destinations. Every count is an int64; no arithmetic here can overflow it. */
#include <stdint.h>

/* CSC (cptr, cidx) of a CSR pattern (indptr, indices) of n_rows rows and n_cols columns; rows ascend within each
 * column. cptr: n_cols + 1 zeros on entry; fill: n_cols scratch entries. */
void snncc_loihi_transpose_indices(const int64_t *indptr, const int32_t *indices, int64_t n_rows, int64_t n_cols,
                                   int64_t *cptr, int32_t *cidx, int64_t *fill) {
    const int64_t nnz = indptr[n_rows];
    for (int64_t e = 0; e < nnz; e++) cptr[indices[e] + 1] += 1;
    for (int64_t j = 0; j < n_cols; j++) cptr[j + 1] += cptr[j];
    for (int64_t j = 0; j < n_cols; j++) fill[j] = cptr[j];
    for (int64_t r = 0; r < n_rows; r++)
        for (int64_t e = indptr[r]; e < indptr[r + 1]; e++) cidx[fill[indices[e]]++] = (int32_t)r;
}

/* For each of n_pre sources: how many distinct destination slices its synapses reach (slice_of ascending). */
void snncc_loihi_distinct_per_source(const int64_t *cptr, const int32_t *cidx, int64_t n_pre, const int64_t *slice_of,
                                     int64_t *out) {
    for (int64_t j = 0; j < n_pre; j++) {
        int64_t prev = -1, count = 0;
        for (int64_t e = cptr[j]; e < cptr[j + 1]; e++) {
            const int64_t c = slice_of[cidx[e]];
            if (c != prev) {
                count++;
                prev = c;
            }
        }
        out[j] = count;
    }
}

/* (input axons, synapse bits, output axons) per core, added into axons / bits / out (zeros on entry), for cores
 * of destinations non-decreasing: each run of one source's synapses onto one core is one (core, source) pair:
 * an input axon on the core, a synapse list of table[m_core[core] * cols + count] bits, an output axon on the
 * source's core (src_core[j] < 0: source j is off-chip). */
void snncc_loihi_pair_usage(const int64_t *cptr, const int32_t *cidx, int64_t n_pre, const int64_t *cores_dst,
                            const int64_t *m_core, const int64_t *table, int64_t cols, const int64_t *src_core,
                            int64_t *axons, int64_t *bits, int64_t *out) {
    for (int64_t j = 0; j < n_pre; j++) {
        int64_t prev = -1, count = 0;
        for (int64_t e = cptr[j]; e < cptr[j + 1]; e++) {
            const int64_t c = cores_dst[cidx[e]];
            if (c != prev) {
                if (prev >= 0) {
                    axons[prev] += 1;
                    bits[prev] += table[m_core[prev] * cols + count];
                    if (src_core[j] >= 0) out[src_core[j]] += 1;
                }
                prev = c;
                count = 0;
            }
            count++;
        }
        if (prev >= 0) {
            axons[prev] += 1;
            bits[prev] += table[m_core[prev] * cols + count];
            if (src_core[j] >= 0) out[src_core[j]] += 1;
        }
    }
}
