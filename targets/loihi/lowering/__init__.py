"""Lowering an IR graph to Loihi 1: timing (delays, refDelay), quantization (scale rules), register
values, current biases as always-on sources, and the artefact with its compile report.

    lower.py        orchestration: lower_model / lower_artefact (checked against the IR reference)
    timing.py       IR edge delays and refractory periods -> synaptic delays and refDelay
    quantize.py     the paper's PyTorch-to-Loihi rules and snncc's finer ones, as pure functions
    scaling.py      which scale rule: global, per-layer, split, fine, or measured (auto)
    registers.py    IR graph -> LoihiNetwork (structure checks, register values)
    chip_units.py   the quantized IR restated in chip units (ties decided as on the chip)
    bias_sources.py current biases as synapses from always-on sources
    artefact.py     LoihiArtefact (write, summary); report_text.py its text
"""
