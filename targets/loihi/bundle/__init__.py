"""Loihi bundles on disk.

    layout.py        the HDF5 layout (lava-dl netx's, plus snncc's own groups), stated once
    write.py         the bundle written (atomic, byte-identical), after the reader's rules are checked
    read.py          a bundle read and validated (snncc's, netx's or SLAYER v1's)
    identify.py      the ``identify`` capability: is this file a Loihi bundle, from which model
    portability.py   what lava-dl netx runs as written (the rules bench/studies/lava_netx_agreement.py measured)
"""
