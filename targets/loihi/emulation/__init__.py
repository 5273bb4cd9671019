"""Bit-exact emulation of Loihi 1 compartments.

    emulator.py     the chip's arithmetic, readable, and the entry point ``emulate`` (``PreparedNetwork``)
    flat.py         a network flattened once into the kernel's arrays; ``run_flat`` starts a run (numpy only)
    kernel.py       the same rules in numba, event-driven (the fast path; numba code only)
    result.py       what a run returns (``EmulationResult``) and a sparse projection (``SparseBlock``)
    run_bundle.py   ``snncc emulate``'s work: a bundle on 0/1 inputs in chunks, outputs' timing shift applied
    fit.py          data shaped to a bundle's input layer (input copies, tSample)
"""
