"""Spikes times a weight matrix: ``snncc.spike_products``' C kernels against the BLAS products they replace, side by side
in one process, one thread.

Workload: square matrices N x N (N = 900, 1,800, 3,600), seeded; inputs: B seeded Bernoulli spike rows (SYNTHETIC)
at density p. For each (N, B, p):

  * integer: 8-bit chip-like units (-127..127) summed exactly by ``integer_sums`` against float32 BLAS on the same
    units (what ``exact_products`` ran before), checked equal;
  * float: float32-valued weights N(0, 1/N) summed by ``float_sums`` (ascending input order, the matrix read in
    float32) against float64 BLAS ``x @ w.T`` (what the IR reference ran before), checked equal to the ascending
    sum bit for bit and reported whether BLAS gave the same bits;
  * whether ``spike_products.worth_it`` takes the kernel for that case (the products use BLAS where it does not).

Best of ``--repeat`` (5) per figure, milliseconds per product and the ratio kernel / BLAS (below 1: the kernel is
faster). The kernel's cost follows the active (input, sample) pairs, BLAS's the batch; both grow with N^2.

    python bench/speed/bench_spike_products.py          # -> bench/speed/results/spike_products.json
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from snncc import spike_products  # noqa: E402

RESULTS = Path(__file__).with_name("results") / "spike_products.json"


def best_ms(fn, repeat: int) -> float:
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * min(times)


def ascending(c: np.ndarray, m_t: np.ndarray) -> np.ndarray:
    out = np.zeros((c.shape[0], m_t.shape[1]))
    for b in range(c.shape[0]):
        for i in np.flatnonzero(c[b]):
            out[b] += m_t[i].astype(np.float64)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[900, 1800, 3600])
    ap.add_argument("--batches", type=int, nargs="+", default=[1, 4, 12, 64])
    ap.add_argument("--densities", type=float, nargs="+", default=[0.05, 0.4])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args()
    if not spike_products.available():
        raise SystemExit("no C compiler builds snncc/spike_products.c here: nothing to compare")
    rng = np.random.default_rng(0)
    rows = []
    for n in args.sizes:
        units = rng.integers(-127, 128, (n, n)).astype(np.int8)          # (n_in, n_out)
        units32 = units.astype(np.float32)
        w = (rng.normal(0.0, 1.0 / np.sqrt(n), (n, n))).astype(np.float32).astype(np.float64)   # (n_out, n_in)
        w_t32 = np.ascontiguousarray(w.T).astype(np.float32)
        for batch in args.batches:
            for p in args.densities:
                x = (rng.random((batch, n)) < p).astype(np.uint8)
                xf, x32 = x.astype(np.float64), x.astype(np.float32)
                exact = spike_products.integer_sums(x, units)
                assert np.array_equal(exact, (x32 @ units32).astype(np.int32))
                floats = spike_products.float_sums(x, w_t32)
                blas = xf @ w.T
                same_as_ascending = floats.tobytes() == ascending(x, w_t32).tobytes()
                active = int(np.count_nonzero(x))
                row = {
                    "n": n, "batch": batch, "density": p,
                    "integer_kernel_ms": best_ms(lambda: spike_products.integer_sums(x, units), args.repeat),
                    "integer_blas_float32_ms": best_ms(lambda: x32 @ units32, args.repeat),
                    "float_kernel_ms": best_ms(lambda: spike_products.float_sums(x, w_t32), args.repeat),
                    "float_blas_float64_ms": best_ms(lambda: xf @ w.T, args.repeat),
                    "float_kernel_is_ascending_sum": same_as_ascending,
                    "float_blas_same_bits": bool(floats.tobytes() == blas.tobytes()),
                    "integer_kernel_taken": spike_products.worth_it("integer", n * n, batch, active, n),
                    "float_kernel_taken": spike_products.worth_it("float", n * n, batch, active, n),
                }
                row["integer_ratio"] = row["integer_kernel_ms"] / row["integer_blas_float32_ms"]
                row["float_ratio"] = row["float_kernel_ms"] / row["float_blas_float64_ms"]
                rows.append(row)
                print(f"N {n:5d}  B {batch:3d}  p {p:.2f}  integer {row['integer_kernel_ms']:7.2f} ms vs "
                      f"{row['integer_blas_float32_ms']:7.2f} ({row['integer_ratio']:.2f}x{' taken' if row['integer_kernel_taken'] else ''})  "
                      f"float {row['float_kernel_ms']:7.2f} ms vs {row['float_blas_float64_ms']:7.2f} "
                      f"({row['float_ratio']:.2f}x{' taken' if row['float_kernel_taken'] else ''}; BLAS same bits: "
                      f"{row['float_blas_same_bits']})", flush=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"threads": 1, "load_1min": load, "inputs": "SYNTHETIC seeded spikes and weights",
                                    "rows": rows}, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
