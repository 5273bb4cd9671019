"""Comparisons of a lowered network with a reference, each named by what it compares.

    exactness.py    the bundle against the IR reference at compile time (bit-exact; a mismatch is an error)
    written.py      a written bundle opened for measuring: read from its file, the lowering's stages re-derived
    stages.py       the stages both checks run, chunk by chunk, and what they share (the kit's stages, liveness)
    accuracy.py     ``check``: float vs stages vs the emulated bundle on a labelled data set, loss by cause
    agreement.py    ``agree``: the emulated bundle against the float graph without labels, loss by cause, ceiling
"""
