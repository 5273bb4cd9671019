"""Lowering: an IR graph placed on a Xylo chip as a network spec (``lower.lower`` -> ``XyloLowered``).

The stages, one module each (docs/xylo_lowering.md): ``structure`` (the chain Xylo holds), ``timing`` (chip
delays), ``design_rules``, ``calibration`` (the float graph's traces), ``candidates`` (the rules tried),
``chip_form`` (a population in the chip's form, float), ``decays`` (the dash grid and kernel fits),
``regression`` (weights fitted to the float graph's voltages), ``sigma_delta`` and ``relay_plan`` (relays),
``replicas`` (``--replicas``), ``integers`` (gains, shifts, rounding: the integer spec), ``twin`` (a spec as
an IR graph), ``lower`` (runs them, describes the result).
"""
