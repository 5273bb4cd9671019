"""SynSense Xylo target (Xylo Audio 2 SYNS61201, Xylo IMU SYNS63300, Xylo Audio 3 SYNS65302).

``chip`` states each chip's limits and the v2 core's arithmetic as data, ``spec`` the network
record (``XyloSpec``: the keyword arguments of Rockpool's ``XyloSim.from_specification``) with its
checks and its .npz file, ``emulator`` a bit-exact emulation of the core (``emulate``, and the
literal numpy statement ``reference_run``). See docs/xylo.md.
"""
