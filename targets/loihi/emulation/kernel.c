/* The emulator's kernel in C: the same rules, program and results as kernel.py's numba kernel, compiled
 * ahead by the system's C compiler (ckernel.py) so that a run needs no numba start-up.
 *
 * One translation unit per type signature, chosen with -D when it is compiled:
 *   ACC_T    q's accumulator (int16_t, int32_t, int64_t)   W_T  a stored weight (int8_t or ACC_T)
 *   STATE_T  u and v (int32_t, int64_t)                     DECAY_SHIFT  chip.DECAY_SHIFT (12)
 * Compiled with -fwrapv: signed arithmetic wraps modulo 2**bits as numba's does (LLVM without nsw), so
 * every integer the numba kernel computes, including the narrow accumulator's modular sums, is the same
 * here. Per sample and step t (kernel.py's docstring states the rules and why the narrow types are exact):
 *   1. the input spikes of step t are delivered to layer 1's ring slot t + 1 + delay;
 *   2. per update group (layers with the same registers, side by side), one pass reads and clears ring
 *      slot t, updates u, v, the refractory counter, and marks the neurons that fire;
 *   3. each layer's spikes add their weights into the ring slots of the layers they project to.
 * Integer sums are exact modulo 2**bits, so the order in which spikes are added changes nothing.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef ACC_T
#error "ACC_T, W_T, STATE_T and DECAY_SHIFT are given with -D (ckernel.py)"
#endif

typedef ACC_T acc_t;
typedef W_T w_t;
typedef STATE_T st_t;

/* The arrays of flat.py's Flat and run_flat, as the kernel reads them (ctypes mirrors this layout). */
typedef struct {
    const uint8_t *x; int64_t steps, width;               /* x: (B, steps, width) 0/1, C order       */
    const int64_t *n, *noff, *kl, *groups, *lay;           /* kl (L, 3), groups (G, 2), lay (L, 6)    */
    int64_t layers, n_groups;
    const w_t *wflat; const int64_t *dflat;
    const int64_t *woff, *roff, *duni, *druni, *sptr; const int32_t *spost; const int64_t *wsp, *rsp;
    const int64_t *keep_u, *keep_v, *vth, *bias; const int32_t *p32;   /* p32: (4, total)            */
    int64_t ring, record_all;
    uint8_t *out_spikes; int64_t n_out;                   /* (B, steps, n_out)                       */
    uint8_t *all_s; int32_t *all_u, *all_v; int64_t units; /* (B, steps, units) when record_all       */
    int64_t *ovf; const int64_t *wraps;                   /* ovf (B, 3); wraps: qh, qm, uh, um       */
} program_t;

/* Per-thread state, allocated once for a chunk of samples. */
typedef struct {
    acc_t *buf; st_t *u, *v; int32_t *ref; uint8_t *fired; int32_t *spk; int64_t counts[3];
} state_t;

#define KEEP_MASK ((INT64_C(1) << DECAY_SHIFT) - 1)

/* sign(x) * ((|x| * keep) >> 12), the chip's truncating decay, in int64 (kernel.py's _decay: its float64
 * form for 32-bit state is this same integer, exactly, since |x * keep| < 2**43). */
static inline int64_t decay64(int64_t x, int64_t keep) {
    int64_t p = x * keep;
    return (p + ((p >> 63) & KEEP_MASK)) >> DECAY_SHIFT;
}

/* The same in 32-bit lanes (kernel.py's _decay32): |x| = a * 4096 + b, a * keep + ((b * keep) >> 12). */
static inline int32_t decay32(int32_t x, int32_t keep) {
    int32_t s = x >> 31;
    int32_t a = (x ^ s) - s;
    int32_t d = (a >> DECAY_SHIFT) * keep + (((a & (int32_t)KEEP_MASK) * keep) >> DECAY_SHIFT);
    return (d ^ s) - s;
}

/* kernel.py's _update (wraps = 1) and _update_in_range (wraps = 0) over m compartments: q read from and cleared
 * in q[0..m-1], u, v, ref and the registers at the group's first compartment; fired[0..m-1] = 0/1; adds the
 * q-wrap / u-wrap / v-clip counts; returns the spike count. reg: ref_delay, vmin, vmax, shift (lay's row). */
static inline __attribute__((always_inline)) int64_t update64_loop(acc_t *restrict q, st_t *restrict u,
        st_t *restrict v,
        int32_t *restrict ref, uint8_t *restrict fired, const int64_t *restrict ku, const int64_t *restrict kv,
        const int64_t *restrict th, const int64_t *restrict bs, int64_t m, const int64_t *restrict reg,
        const int64_t *restrict wr, int64_t *restrict counts, const int wraps) {
    const int64_t ref_delay = reg[0], vmin = reg[1], vmax = reg[2], shift = reg[3];
    const int64_t qh = wr[0], qm = wr[1], uh = wr[2], um = wr[3];
    int64_t cq = 0, cu = 0, cv = 0, nf = 0;
    for (int64_t j = 0; j < m; j++) {
        int64_t qv = (int64_t)((uint64_t)(int64_t)q[j] << shift);
        q[j] = 0;
        int64_t un;
        if (wraps) {
            int64_t qw = ((qv + qh) & qm) - qh;
            int64_t ur = decay64((int64_t)u[j], ku[j]) + qw;
            un = ((ur + uh) & um) - uh;
            cq += qw != qv;
            cu += un != ur;
        } else {
            un = decay64((int64_t)u[j], ku[j]) + qv;
        }
        int64_t vr = decay64((int64_t)v[j], kv[j]) + un + bs[j];
        int64_t vn = vr < vmin ? vmin : vr;
        vn = vn > vmax ? vmax : vn;
        cv += vn != vr;
        int64_t r = ref[j];
        int refractory = r > 0;
        vn = refractory ? 0 : vn;
        r = refractory ? r - 1 : r;
        int s = vn > th[j];
        vn = s ? 0 : vn;
        ref[j] = (int32_t)(s ? ref_delay - 1 : r);
        u[j] = (st_t)un;
        v[j] = (st_t)vn;
        fired[j] = (uint8_t)s;
        nf += s;
    }
    counts[0] += cq;
    counts[1] += cu;
    counts[2] += cv;
    return nf;
}

/* update64_loop compiled twice, with and without the wraps (each loop vectorised on its own). */
static __attribute__((noinline)) int64_t update64(acc_t *restrict q, st_t *restrict u, st_t *restrict v,
        int32_t *restrict ref, uint8_t *restrict fired, const int64_t *restrict ku, const int64_t *restrict kv,
        const int64_t *restrict th, const int64_t *restrict bs, int64_t m, const int64_t *restrict reg,
        const int64_t *restrict wr, int64_t *restrict counts, const int wraps) {
    if (wraps)
        return update64_loop(q, u, v, ref, fired, ku, kv, th, bs, m, reg, wr, counts, 1);
    return update64_loop(q, u, v, ref, fired, ku, kv, th, bs, m, reg, wr, counts, 0);
}

/* kernel.py's _update32: every intermediate in 32 bits (the layer's values provably fit, Flat.fits32); the
 * registers ku, kv, th, bs are the int32 rows of p32. */
static inline __attribute__((always_inline)) int64_t update32_loop(acc_t *restrict q, st_t *restrict u,
        st_t *restrict v,
        int32_t *restrict ref, uint8_t *restrict fired, const int32_t *restrict ku, const int32_t *restrict kv,
        const int32_t *restrict th, const int32_t *restrict bs, int64_t m, const int64_t *restrict reg,
        const int64_t *restrict wr, int64_t *restrict counts, const int wraps) {
    const int32_t sh = (int32_t)(reg[3] & 31);
    const int32_t lo32 = (int32_t)reg[1], hi32 = (int32_t)reg[2], rd = (int32_t)(reg[0] - 1);
    const int32_t qh = (int32_t)wr[0], qm = (int32_t)wr[1], uh = (int32_t)wr[2], um = (int32_t)wr[3];
    int32_t cq = 0, cu = 0, cv = 0, nf = 0;
    for (int64_t j = 0; j < m; j++) {
        int32_t qv = (int32_t)((uint32_t)(int32_t)q[j] << sh);
        q[j] = 0;
        int32_t un;
        if (wraps) {
            int32_t qw = ((qv + qh) & qm) - qh;
            int32_t ur = decay32((int32_t)u[j], ku[j]) + qw;
            un = ((ur + uh) & um) - uh;
            cq += qw != qv;
            cu += un != ur;
        } else {
            un = decay32((int32_t)u[j], ku[j]) + qv;
        }
        int32_t vr = decay32((int32_t)v[j], kv[j]) + un + bs[j];
        int32_t vn = vr < lo32 ? lo32 : vr;
        vn = vn > hi32 ? hi32 : vn;
        cv += vn != vr;
        int32_t r = ref[j];
        int32_t refractory = r > 0;
        vn = refractory ? 0 : vn;
        r = refractory ? r - 1 : r;
        int32_t s = vn > th[j];
        ref[j] = s ? rd : r;
        u[j] = (st_t)un;
        v[j] = (st_t)(s ? 0 : vn);
        fired[j] = (uint8_t)s;
        nf += s;
    }
    counts[0] += cq;
    counts[1] += cu;
    counts[2] += cv;
    return nf;
}

/* update32_loop compiled twice, with and without the wraps (each loop vectorised on its own). */
static __attribute__((noinline)) int64_t update32(acc_t *restrict q, st_t *restrict u, st_t *restrict v,
        int32_t *restrict ref, uint8_t *restrict fired, const int32_t *restrict ku, const int32_t *restrict kv,
        const int32_t *restrict th, const int32_t *restrict bs, int64_t m, const int64_t *restrict reg,
        const int64_t *restrict wr, int64_t *restrict counts, const int wraps) {
    if (wraps)
        return update32_loop(q, u, v, ref, fired, ku, kv, th, bs, m, reg, wr, counts, 1);
    return update32_loop(q, u, v, ref, fired, ku, kv, th, bs, m, reg, wr, counts, 0);
}

/* One pass over an update group of m compartments from lo: 32-bit lanes where the layer's values fit (reg[5]),
 * the wraps skipped where q and u stay in range (reg[4]). The pointers go in as restrict parameters, so gcc
 * vectorises the loops without run-time alias checks. */
static inline int64_t update(const program_t *P, state_t *S, acc_t *q, int64_t lo, int64_t m, const int64_t *reg) {
    const int wraps = reg[4] ? 0 : 1;
    if (reg[5]) {
        const int64_t total = P->kl[(P->layers - 1) * 3] + P->kl[(P->layers - 1) * 3 + 1];
        const int32_t *p = P->p32 + lo;
        return update32(q, S->u + lo, S->v + lo, S->ref + lo, S->fired, p, p + total, p + 2 * total, p + 3 * total,
                        m, reg, P->wraps, S->counts, wraps);
    }
    return update64(q, S->u + lo, S->v + lo, S->ref + lo, S->fired, P->keep_u + lo, P->keep_v + lo, P->vth + lo,
                    P->bias + lo, m, reg, P->wraps, S->counts, wraps);
}

/* Indices j < m with fired[j] = 1 (every byte 0 or 1) into spk, lowest first; returns how many (kernel.py's
 * _spike_list_at). 64 neurons at a time: their 0/1 bytes packed into one 64-bit mask (a multiply gathers a
 * word's 8 bytes into 8 bits, no carries reach the top byte), then the set bits visited lowest first: the cost
 * follows the spikes. */
#define PACK UINT64_C(0x0102040810204080)
static inline int64_t spike_list(const uint8_t *fired, int64_t m, int32_t *spk) {
    int64_t c = 0;
    for (int64_t g = 0; g < m; g += 64) {
        uint64_t mask = 0;
        const int64_t rest = m - g;
        if (rest >= 64) {
            for (int q = 0; q < 8; q++) {
                uint64_t word;
                memcpy(&word, fired + g + 8 * q, 8);
                mask |= ((word * PACK) >> 56) << (8 * q);
            }
        } else {
            for (int64_t j = 0; j < rest; j++) mask |= (uint64_t)(fired[g + j] != 0) << j;
        }
        while (mask) {
            spk[c++] = (int32_t)(g + __builtin_ctzll(mask));
            mask &= mask - 1;
        }
    }
    return c;
}

/* The rows base + spk[c] * m of wflat added into dst[0..m-1]: four spikes' rows a pass, the last one to three rows
 * in one more pass (each pass loads and stores the slot once). Not inlined: gcc vectorises it with its restrict
 * parameters, and not once it is inlined. */
static __attribute__((noinline)) void add_rows(acc_t *restrict dst, const w_t *restrict w, int64_t base,
                                               const int32_t *spk, int64_t nspk, int64_t m) {
    int64_t c = 0;
    for (; c + 4 <= nspk; c += 4) {
        const w_t *r0 = w + base + spk[c] * m, *r1 = w + base + spk[c + 1] * m;
        const w_t *r2 = w + base + spk[c + 2] * m, *r3 = w + base + spk[c + 3] * m;
        for (int64_t j = 0; j < m; j++)
            dst[j] = (acc_t)(dst[j] + (acc_t)((acc_t)r0[j] + (acc_t)r1[j] + (acc_t)r2[j] + (acc_t)r3[j]));
    }
    const int64_t rest = nspk - c;
    if (rest == 3) {
        const w_t *r0 = w + base + spk[c] * m, *r1 = w + base + spk[c + 1] * m, *r2 = w + base + spk[c + 2] * m;
        for (int64_t j = 0; j < m; j++)
            dst[j] = (acc_t)(dst[j] + (acc_t)((acc_t)r0[j] + (acc_t)r1[j] + (acc_t)r2[j]));
    } else if (rest == 2) {
        const w_t *r0 = w + base + spk[c] * m, *r1 = w + base + spk[c + 1] * m;
        for (int64_t j = 0; j < m; j++)
            dst[j] = (acc_t)(dst[j] + (acc_t)((acc_t)r0[j] + (acc_t)r1[j]));
    } else if (rest == 1) {
        const w_t *r0 = w + base + spk[c] * m;
        for (int64_t j = 0; j < m; j++)
            dst[j] = (acc_t)(dst[j] + r0[j]);
    }
}

/* One spike's row with a delay per synapse: synapse j goes to ring slot (t + 1 + d[src + j]) mod ring. */
static inline void add_row_delays(const program_t *P, acc_t *buf, int64_t t, int64_t total, int64_t post_off,
                                  int64_t src, int64_t m) {
    for (int64_t j = 0; j < m; j++) {
        int64_t slot = (t + 1 + P->dflat[src + j]) % P->ring;
        buf[slot * total + post_off + j] = (acc_t)(buf[slot * total + post_off + j] + P->wflat[src + j]);
    }
}

/* The spikes through a sparse block whose pointers start at sptr[sp]: source k's synapses
 * sptr[sp + k] .. sptr[sp + k + 1] - 1, each to its own post neuron (and delay, when uniform < 0). */
static inline void deliver_sparse(const program_t *P, acc_t *buf, int64_t t, int64_t total, const int32_t *spk,
                                  int64_t nspk, int64_t post_off, int64_t uniform, int64_t sp) {
    const w_t *w = P->wflat;
    const int32_t *post = P->spost;
    for (int64_t c = 0; c < nspk; c++) {
        int64_t k = spk[c], a = P->sptr[sp + k], b = P->sptr[sp + k + 1];
        if (uniform >= 0) {
            acc_t *dst = buf + ((t + 1 + uniform) % P->ring) * total + post_off;
            for (int64_t s = a; s < b; s++) dst[post[s]] = (acc_t)(dst[post[s]] + w[s]);
        } else {
            for (int64_t s = a; s < b; s++) {
                int64_t at = ((t + 1 + P->dflat[s]) % P->ring) * total + post_off + post[s];
                buf[at] = (acc_t)(buf[at] + w[s]);
            }
        }
    }
}

/* The spikes spk[0..nspk-1] of a layer of m neurons into the layer at post_off (m_post neurons) through the
 * block at (dense offset, sparse pointer start, uniform delay or -1). */
static inline void deliver(const program_t *P, acc_t *buf, int64_t t, int64_t total, const int32_t *spk,
                           int64_t nspk, int64_t post_off, int64_t m_post, int64_t dense_off, int64_t sparse_at,
                           int64_t uniform) {
    if (sparse_at >= 0) {
        deliver_sparse(P, buf, t, total, spk, nspk, post_off, uniform, sparse_at);
    } else if (uniform >= 0) {
        add_rows(buf + ((t + 1 + uniform) % P->ring) * total + post_off, P->wflat, dense_off, spk, nspk, m_post);
    } else {
        for (int64_t c = 0; c < nspk; c++)
            add_row_delays(P, buf, t, total, post_off, dense_off + spk[c] * m_post, m_post);
    }
}

/* One sample from zero state (kernel.py's _sample). */
static void run_sample(const program_t *P, state_t *S, int64_t b) {
    const int64_t last = P->layers - 1;
    const int64_t *kl = P->kl, *n = P->n;
    const int64_t total = kl[last * 3] + kl[last * 3 + 1];
    const int64_t steps = P->steps, width = P->width;
    memset(S->buf, 0, sizeof(acc_t) * (size_t)(P->ring * total));
    memset(S->u, 0, sizeof(st_t) * (size_t)total);
    memset(S->v, 0, sizeof(st_t) * (size_t)total);
    memset(S->ref, 0, sizeof(int32_t) * (size_t)total);
    S->counts[0] = S->counts[1] = S->counts[2] = 0;
    for (int64_t t = 0; t < steps; t++) {
        const uint8_t *row = P->x + (b * steps + t) * width;
        for (int64_t k = 0; k < width; k++) S->fired[k] = row[k] != 0;   /* spike_list reads 0/1 bytes */
        int64_t nspk = spike_list(S->fired, width, S->spk);
        if (P->record_all)
            for (int64_t c = 0; c < nspk; c++)
                P->all_s[(b * steps + t) * P->units + S->spk[c]] = 1;
        deliver(P, S->buf, t, total, S->spk, nspk, kl[3], n[1], P->woff[1], P->wsp[1], P->duni[1]);
        const int64_t base = (t % P->ring) * total;
        for (int64_t g = 0; g < P->n_groups; g++) {
            const int64_t first = P->groups[2 * g], end = P->groups[2 * g + 1];
            const int64_t lo = kl[first * 3];
            const int64_t mu = kl[(end - 1) * 3] + kl[(end - 1) * 3 + 2] - lo;
            const int64_t *reg = P->lay + first * 6;
            int64_t nf = update(P, S, S->buf + base + lo, lo, mu, reg);
            for (int64_t i = first; i < end; i++) {
                const int64_t klo = kl[i * 3], at = klo - lo, m = n[i];
                if (P->record_all) {
                    const int64_t out = (b * steps + t) * P->units + P->noff[i];
                    for (int64_t j = 0; j < m; j++) {
                        P->all_s[out + j] = S->fired[at + j];
                        P->all_u[out + j] = (int32_t)S->u[klo + j];
                        P->all_v[out + j] = (int32_t)S->v[klo + j];
                    }
                }
                if (nf == 0) continue;
                nspk = spike_list(S->fired + at, m, S->spk);
                if (nspk == 0) continue;
                if (i == last)
                    for (int64_t c = 0; c < nspk; c++)
                        P->out_spikes[(b * steps + t) * P->n_out + S->spk[c]] = 1;
                if (P->rsp[i] >= 0 || P->roff[i] >= 0)        /* to itself (recurrent) */
                    deliver(P, S->buf, t, total, S->spk, nspk, klo, m, P->roff[i], P->rsp[i], P->druni[i]);
                if (i == last) continue;
                deliver(P, S->buf, t, total, S->spk, nspk, kl[(i + 1) * 3], n[i + 1], P->woff[i + 1], P->wsp[i + 1],
                        P->duni[i + 1]);
            }
        }
    }
    P->ovf[b * 3] = S->counts[0];
    P->ovf[b * 3 + 1] = S->counts[1];
    P->ovf[b * 3 + 2] = S->counts[2];
}

/* Samples lo_b..hi_b-1, state allocated once. Returns 0, or -1 when memory could not be allocated.
 * Called without Python's GIL (ctypes releases it): chunks of a batch run on several threads. */
int snncc_loihi_run_chunk(const program_t *P, int64_t lo_b, int64_t hi_b) {
    const int64_t last = P->layers - 1;
    const int64_t total = P->kl[last * 3] + P->kl[last * 3 + 1];
    const int64_t wide = (total > P->width ? total : P->width) + 64;
    state_t S;
    memset(&S, 0, sizeof S);
    S.buf = calloc((size_t)(P->ring * total), sizeof(acc_t));
    S.u = calloc((size_t)total, sizeof(st_t));
    S.v = calloc((size_t)total, sizeof(st_t));
    S.ref = calloc((size_t)total, sizeof(int32_t));
    S.fired = calloc((size_t)wide, 1);
    S.spk = calloc((size_t)wide, sizeof(int32_t));
    int status = (S.buf && S.u && S.v && S.ref && S.fired && S.spk) ? 0 : -1;
    if (status == 0)
        for (int64_t b = lo_b; b < hi_b; b++) run_sample(P, &S, b);
    free(S.buf); free(S.u); free(S.v); free(S.ref); free(S.fired); free(S.spk);
    return status;
}

/* The layout of program_t as this compiler laid it out, checked by ckernel.py against ctypes' own. */
int64_t snncc_loihi_program_size(void) { return (int64_t)sizeof(program_t); }
