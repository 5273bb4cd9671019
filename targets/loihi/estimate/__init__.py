"""ESTIMATEs of energy and delay per sample.

    energy.py       the published pre-silicon cost table applied to an emulation and a core map
    report.py       ``snncc report --energy``: bundle (or model) mapped, emulated and estimated
"""
