"""Comparisons of a lowered network with a reference, each named by what it compares.

    exactness.py    the bundle against the IR reference at compile time (bit-exact; a mismatch is an error)
    accuracy.py     float vs quantized vs emulated accuracy on a labelled data set, and why it differs
    agreement.py    the emulated bundle against the float graph without labels
"""
