"""Loihi 1's arithmetic as differentiable torch operations, to train through it (capability ``arithmetic``).

``straight_through.py``: the paper's global-scale quantization of weights, threshold and decays, with
straight-through rounding (what ``snncc train --qat-from`` fine-tunes through).
"""
