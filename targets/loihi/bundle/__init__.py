"""Loihi bundles on disk.

    hdf5.py         the HDF5 bundle in the lava-dl netx layout: read, write, check
    load.py         what ``map`` and ``report`` read: a bundle, or a model lowered for Loihi first
"""
