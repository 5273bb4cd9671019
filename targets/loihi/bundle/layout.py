"""The bundle's layout on disk: HDF5 in the lava-dl netx layout (which SLAYER v1 also wrote), plus snncc's own groups.

    /simulation/Ts = 1, /simulation/tSample = T
    /layer/0/{type="input", shape=[1, 1, C]}
    /layer/i/{type="dense"|"dense_rec", shape=[n, 1, 1], weight (out, in), weight_rec (n, n),
              delay (out, in), bias, neuron/{type="LOIHI", vThMant, iDecay, vDecay, refDelay, wgtExp}}
    snncc extensions (netx ignores them): /layer/i/delay_rec, neuron/{wgtExpRec, biasExp},
    /layer/i/alwaysOn (the layer's last k units are bias sources: input axons held at 1 every step,
    or compartments that fire on their own; see lowering/bias_sources.py)
    /snncc/{version, quantization, timing, validation, metadata (JSON strings), source_sha256,
            core_map (JSON, when mapped), netx_compat (what netx would run differently),
            portability (JSON: netx_runnable, line, reasons, best_netx_rule; bundle/portability.py),
            liveness (JSON: every population's activity on the calibration inputs, float and Loihi),
            model (JSON: kit.artefact.model_record of the graph compiled: fingerprint, dt, resets; what
            ``identify`` returns as ``identity.model``), finetune (JSON, a fine-tuned bundle's record)}
    metadata holds compile_options (timing, scale, allow_reset_change, time_steps: what check re-lowers
    with), input_copies / base_inputs (the data's channels, tiled by snncc) and input_shape (C, H, W)

``write.py`` writes it (atomic, byte-identical for identical input: no timestamps, fixed order);
``read.py`` reads and validates it, and also accepts SLAYER v1 files as the paper's authors wrote
them (a ``flatten`` layer after the input, type ``recurrent`` with ``recWeight``, float-typed even
weights, ``neuron/theta`` = vThMant * 2**6 when vThMant is absent, ``tauRho``/``scaleRho`` ignored):
one SnnccError line naming the file, the HDF5 path and the rule. The ranges both check are
``chip.py``'s, read at call time (the reader and ``write.check_network``, which the writer runs, agree).
Imports nothing heavy.
"""

from __future__ import annotations

SNNCC_GROUP = "snncc"
MAX_TEXT_BYTES = 64 * 2**20    # a text field (type, JSON record) of a bundle: one string of at most 64 MiB
FORMAT_VERSION = 1
RECORDS = ("metadata", "quantization", "timing", "validation", "netx_compat", "core_map", "portability", "liveness",
           "model")
KIND = "a Loihi bundle (.net, an HDF5 file)"
