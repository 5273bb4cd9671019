"""Placing a LoihiNetwork on cores under every per-core limit, and relays for wide fan-in.

    partition.py    map_network: the entry point
    projections.py  what each population needs (projections checked against the chip)
    resources.py    the chip's resource model and per-core design rules, as data
    usage.py        per-core usage of an assignment, counted as the chip's rules state it
    slicing.py      each layer cut into the fewest slices that fit a core
    packing.py      first-fit-decreasing packing of slices onto cores
    search.py       exact search, lower bound, output-axon repair
    coremap.py      the core map record (CoreMap, CoreRecord, CoreUsage)
    fanin.py        relay plans for fan-in wider than a core's input axons
    relays.py       relayed networks (what the bundle holds when relays are needed)
    kernels.py      the partitioner's kernels: kernels.c (C, built by the system's compiler) or numba_kernels.py
"""
