"""Loihi 1's number formats and limits, stated once (docs/loihi.md explains them).

Every Loihi module (quantizer, timing pass, bundle reader and checker, emulator, mapper, fan-in
relays, lowering) reads these names from here, as ``chip.NAME`` at call time where a run can
reach the rule, so changing a limit is a change of one line below. Sources: Davies et al., IEEE
Micro 2018; nengo-loihi 1.1 (``block.py``, hardware builder); lava-dl ``netx``.

Some users copy values when they are built: ``resources.ChipSpec()`` when it is constructed (so
``resources.LOIHI1`` at import), ``LoihiLayer`` its vmin / vmax when a layer is made, module
constants derived at import (``fanin.COPY_WEIGHT``, the kernel's wrap masks), and the numba kernel
(``emulation/kernel.py``) when numba compiles it. Numba's on-disk cache is keyed on ``emulation/kernel.py`` alone,
so after changing a value the kernel uses (DECAY_SHIFT, DECAY_ONE) remove its cache files. The C kernel
(``emulation/kernel.c``) gets DECAY_SHIFT when it is built, and its cache is keyed on it.
"""

from __future__ import annotations

# -- synapses: one weight format, 8-bit even mantissas with a per-projection (or per-synapse) exponent ---------
WEIGHT_BITS = 8                      # a weight mantissa: 8 bits, signed, even (the low bit is always 0)
WEIGHT_MIN, WEIGHT_MAX = -256, 254   # w_q: even integers in [-256, 254]
WEIGHT_SPAN = -WEIGHT_MIN            # 256: the scale rules map max|W| onto it (w_scale = floor(256 / max|W|))
WEIGHT_SHIFT = 6                     # w_chip = w_q * 2**(6 + wgtExp)
WGT_EXP_MIN, WGT_EXP_MAX = -6, 7     # wgtExp; below -6 the chip weight w_q * 2**(6 + e) stops being an integer

# -- compartment registers -----------------------------------------------------------------------------
V_TH_MANT_MIN, V_TH_MANT_MAX = 1, 2**17 - 1   # vThMant: 17-bit unsigned, at least 1
V_TH_SHIFT = 6                       # threshold on chip = vThMant * 2**6 (SLAYER's theta is that product)
BIAS_MANT_MAX = 2**12 - 1            # bias mantissa: 13 bits signed, |b| <= 4095
BIAS_EXP_MAX = 7                     # the quantizer's bias exponent: bias on chip = b * 2**e, e in 0..7
NETX_BIAS_EXP = 6                    # netx reads a bias with exponent 6 (a bundle without biasExp)
BIAS_EXP_STORED_MAX = BIAS_EXP_MAX + NETX_BIAS_EXP   # a bundle's biasExp: 0..13
DECAY_SHIFT = 12                     # decays are fractions of 2**12: x <- sign(x) * ((|x| * (4096 - d)) >> 12)
DECAY_ONE = 1 << DECAY_SHIFT         # iDecay / vDecay registers lie in 0..4096 (4096: all of it decays each step)
REF_DELAY_MIN, REF_DELAY_MAX = 1, 63  # refDelay: steps silent after a spike, the spike's included (1 = none)

# -- state widths ----------------------------------------------------------------------------------------
Q_BITS = 21                          # q (a step's synaptic input): 21 magnitude bits + sign, wraps (two's complement)
U_BITS = 23                          # u (the current): 23 magnitude bits + sign, wraps (two's complement)
V_MAX = 2**23 - 1                    # v is clipped to [vmin, vmax]; default [-(2**23 - 1), 2**23 - 1]
V_MIN = -V_MAX

# -- timing --------------------------------------------------------------------------------------------------
MAX_EXTRA_DELAY = 62                 # synaptic delay 0..62 steps on top of the one-step delivery (netx clips at 62)

# -- per chip and per core ----------------------------------------------------------------------------------
CORES_PER_CHIP = 128                 # neuro cores per chip
CORES_PER_TILE = 4                   # tiles on an 8 east-west x 4 north-south mesh (assumed placement)
MESH_TILES_EW, MESH_TILES_NS = 8, 4
COMPARTMENTS_PER_CORE = 1024         # neurons (compartments) per core
INPUT_AXONS_PER_CORE = 4096          # distinct sources a core's compartments listen to (fan-in)
OUTPUT_AXONS_PER_CORE = 4096         # (source on the core, destination core) pairs (fan-out entries)
SYNAPSE_WORDS_PER_CORE = 16384       # synapse memory: 16,384 words of 64 bits = 1,048,576 bits
SYNAPSE_WORD_BITS = 64
SYNAPSES_PER_CHUNK = 64              # a synapse list is cut into chunks of <= 64, each n*b + 4 + 6 bits
CHUNK_HEADER_BITS = 4 + 6            # ... 4-bit synapse-format id and 6-bit synapse count, rounded up to words
INDEX_BITS_MIN, INDEX_BITS_MAX = 6, 12   # sparse format: bits of a synapse's compartment index
VTH_PROFILES_PER_CORE = 8            # threshold profiles (nengo-loihi's hardware builder asserts 8)
COMPARTMENT_PROFILES_PER_CORE = 32   # compartment (decay) profiles
VOLTAGE_LIMITS_PER_CORE = 1          # vmin/vmax are one setting per core
