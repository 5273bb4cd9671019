"""Flash and RAM of a C artefact, counted from what it declares, and set against a part's limits.

    flash (data)   every ``static const`` array of snn.c, by its declared type and length (weights, row pointers
                   and indices, per-neuron exponents, thresholds, decays, biases): exact
    flash (code)   the code of snn.c: measured where arm-none-eabi-gcc is installed (``-mcpu=cortex-m4 -mthumb
                   -Os``, arm-none-eabi-size's text of snn.o, which holds the constants too); else not counted
    RAM            sizeof(snn_state_t) (current, voltage, accumulators, refractory counters, event rings), exact
                   for an ARM EABI core; snn_step's own stack frame (a few dozen bytes) is not counted
"""

from __future__ import annotations

import re
from typing import Any

SIZES = {"int8_t": 1, "uint8_t": 1, "int16_t": 2, "uint16_t": 2, "int32_t": 4, "uint32_t": 4}
DECLARED = re.compile(r"^static const (\w+) (\w+)\[(\d+)\]", re.M)


def const_bytes(source: str) -> dict[str, int]:
    """Bytes of snn.c's constant arrays: ``weights`` (w*: weights, CSR pointers and indices) and ``constants``."""
    out = {"weights": 0, "constants": 0}
    for ctype, name, count in DECLARED.findall(source):
        out["weights" if re.match(r"w\d+", name) else "constants"] += SIZES[ctype] * int(count)
    return out


def memory_record(net, source: str) -> dict[str, Any]:   # noqa: ANN001 (a CNetwork)
    """Flash data and RAM of an artefact (module doc), from its network and its snn.c text."""
    from snncc.targets.c.artefact.csource import state_bytes

    data = const_bytes(source)
    return {"flash_weights_bytes": data["weights"], "flash_constants_bytes": data["constants"],
            "flash_data_bytes": data["weights"] + data["constants"], "ram_state_bytes": state_bytes(net),
            "weights": int(sum(q.weights.size if q.layout == "dense" else int((q.weights != 0).sum())
                               for q in net.projections)),
            "rule": "flash data: snn.c's static const arrays by declared type and length; RAM: sizeof(snn_state_t) "
                    "(ARM EABI alignment); code and snn_step's stack frame not included"}


def fit(memory: dict[str, Any], part: dict[str, Any], code_bytes: int | None = None) -> dict[str, Any]:
    """The artefact against ``part``'s flash and RAM: bytes, share of the part, fits or not. ``code_bytes``: the
    measured text of snn.o (code and constants), which then replaces the data-only flash figure."""
    flash = code_bytes if code_bytes is not None else memory["flash_data_bytes"]
    ram = memory["ram_state_bytes"]
    return {"part": part["name"], "flash_bytes": int(flash),
            "flash_counted": "snn.o text (code + constants), measured" if code_bytes is not None
            else "constant data only (code not measured: no arm-none-eabi-gcc)",
            "flash_limit": part["flash_bytes"], "flash_share": flash / part["flash_bytes"],
            "ram_bytes": int(ram), "ram_limit": part["ram_bytes"], "ram_share": ram / part["ram_bytes"],
            "fits": bool(flash <= part["flash_bytes"] and ram <= part["ram_bytes"]), "source": part["source"]}


__all__ = ["const_bytes", "memory_record", "fit", "SIZES"]
