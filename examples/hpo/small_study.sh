#!/usr/bin/env bash
# A small real study that fits in ~15 minutes of a shared CPU: SYNTHETIC Braille data (threshold 1),
# a 64-neuron RSNN, 5 epochs per trial, a stratified subset of 810 samples, 12 annealing trials
# (re-initialisations at 4 and 8) then the 3 x 3 grid, three objectives (accuracy, ESTIMATED energy,
# cores), emulated accuracy on 32 held-out samples. Stopped with Ctrl-C after LIMIT seconds (default
# 1080); rerun to continue. On a GPU drop --hidden/--subset/--epochs for the paper's network and
# budget, and add --device cuda.
set -euo pipefail
OUT=${1:-hpo-small}
LIMIT=${LIMIT:-1080}
mkdir -p "$OUT"
[ -d "$OUT/braille" ] || snncc data synth -o "$OUT/braille" -n 200 --thresholds 1
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMBA_NUM_THREADS=1
timeout -s INT "$LIMIT" snncc hpo run real-th1 --data "$OUT/braille" --threshold 1 --step both --trials 12 \
    --epochs 5 --hidden 64 --subset 810 --range time_bin_size=3:10 --objectives pareto \
    --energy-samples 16 --emulate 32 --dir "$OUT/w" --device cpu || true
snncc hpo report real-th1 --dir "$OUT/w"
snncc hpo report real-th1-grid --dir "$OUT/w" || true   # absent until step 1 is complete
