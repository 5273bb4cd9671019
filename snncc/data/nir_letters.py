"""Labelled inputs in the NIR paper's Braille layout, from snncc's SYNTHETIC Braille generator (``snncc data nir``:
what ``check --data`` and ``compare --data`` measure the NIR Braille graphs' accuracy on; fine-tuning's task-like sets).

As the NIR paper's Braille data: the letters Space, A, E, I, O, U, Y (class 0..6 in that order);
sigma-delta events at threshold 1 of the inverted frames (``snncc.data.sigma_delta``); ON and OFF
events merged per taxel into 12 channels; the recording (54 frames, 1.35 s) cut into 256 equal
steps, step = min(floor(t / 1.35 s * 256), 255); a channel is 1 in a step with at least one event.
The frames come from ``snncc.data.synth.generate`` (the default generator version, seeded), so the
inputs are synthetic stand-ins for real recordings: agreement on them says how well the deployed
graph follows the float graph on Braille-like spike statistics, not what it scores on real data.
"""

from __future__ import annotations

import numpy as np

NIR_LETTERS = ("Space", "A", "E", "I", "O", "U", "Y")
NIR_STEPS = 256
NIR_THRESHOLD = 1.0


def nir_braille_inputs(samples: int, seed: int = 0, steps: int = NIR_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """(inputs (N, steps, 12) uint8, labels (N,) in 0..6), N = ``samples`` (balanced over the letters)."""
    from snncc.data.letters import CLASSES, FRAME_RATE_HZ
    from snncc.data.sigma_delta import encode
    from snncc.data.synth import generate
    from snncc.errors import SnnccError

    if samples < 1:
        raise SnnccError(f"need at least one sample, got {samples}", field="samples")
    reps = -(-samples // len(NIR_LETTERS))
    frames, labels = generate(repetitions=reps, seed=seed)
    keep = np.concatenate([np.flatnonzero(labels == CLASSES.index(letter)) for letter in NIR_LETTERS])
    frames = frames[keep]
    new_labels = np.repeat(np.arange(len(NIR_LETTERS)), reps)
    inverted = 255 - frames.astype(np.int64)
    ev = encode(inverted, NIR_THRESHOLD)
    record_s = frames.shape[1] / FRAME_RATE_HZ
    step = np.minimum(np.floor(ev.times / record_s * steps).astype(np.int64), steps - 1)
    x = np.zeros((frames.shape[0], steps, ev.n_taxels), np.uint8)
    x[ev.sample, step, ev.taxel] = 1
    order = np.random.default_rng(seed).permutation(x.shape[0])[:samples]
    return x[order], new_labels[order]


def write_nir_letters(path, samples: int, seed: int = 0, steps: int = NIR_STEPS) -> dict:
    """``nir_braille_inputs`` written as the .npz ``snncc check --data`` reads (``inputs`` (N, steps, 12) uint8,
    ``labels`` (N,), ``classes``, ``synthetic`` True), atomically; what was written."""
    from snncc.atomic import write_npz_atomic

    x, y = nir_braille_inputs(samples, seed, steps)
    write_npz_atomic(path, {"inputs": x, "labels": y.astype(np.int64), "classes": np.asarray(NIR_LETTERS),
                            "synthetic": np.asarray(True)})
    return {"out": str(path), "samples": int(x.shape[0]), "steps": int(steps), "channels": int(x.shape[2]),
            "classes": list(NIR_LETTERS), "seed": int(seed), "synthetic": True,
            "events_per_sample": float(x.sum() / max(1, x.shape[0]))}
