"""``snncc run DIR --target c --backend host|qemu|auto``: the artefact's own C compiled and run on the inputs.

    host   gcc builds main.c + snn.c (the Makefile's ``host`` flags) and runs it on this machine
    qemu   arm-none-eabi-gcc builds the Cortex-M4 program (``m4``) and QEMU runs it on the MPS2 AN386 board;
           the SysTick ticks it reports (instructions, under -icount shift=0) are in the record
    auto   host where gcc is installed, else qemu

The .npz it writes has the emulator's layout (``output_spikes``, ``counts``, ``prediction``), so
``snncc emulate`` on the same inputs must write the same arrays: that is the proof a user can repeat.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from snncc.targets.kit import SnnccError
from snncc.targets.c.options import BACKENDS


def run_artefact(path, inputs, *, source: str | None = None, stream: bool = False,  # noqa: ANN001
                 backend: str = "auto", gap: int | None = None, cache: Path | None = None):
    """A ``CEmulation`` whose arrays come from the compiled C (module doc)."""
    from snncc.targets.c.artefact.written import open_artefact
    from snncc.targets.c.emulation.run_artefact import (CEmulation, artefact_inputs, check_gap, streamed,
                                                        unstreamed)
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    if backend not in BACKENDS:
        raise SnnccError(f"must be one of {', '.join(BACKENDS)} for --target c, got {backend!r}", field="--backend")
    chosen = backend if backend != "auto" else ("host" if tb.available(cmd.HOST_CC) else "qemu")
    blank = check_gap(gap, stream)
    written = open_artefact(path)
    net = written.network
    x, note = artefact_inputs(written, inputs, source)
    samples, steps = int(x.shape[0]), int(x.shape[1])
    sources = tb.artefact_sources(Path(path))
    feed = streamed(x, blank) if stream else x
    with tempfile.TemporaryDirectory(prefix="snncc-c-build-") as tmp:
        if chosen == "host":
            built = tb.build(sources, cmd.host_command(), cmd.HOST_PROGRAM, cache=cache, workdir=Path(tmp))
            ran = tb.run_program(built.path, feed, net.outputs)
            program = f"{cmd.HOST_CC} {' '.join(cmd.HOST_FLAGS)}"
        else:
            built = tb.build(sources, cmd.m4_command(), cmd.M4_PROGRAM, cache=cache, workdir=Path(tmp))
            ran = tb.run_qemu(built.path, feed, net.outputs)
            program = f"Cortex-M4 ({cmd.ARM_CC} -mcpu=cortex-m4 -mthumb -Os) in {cmd.QEMU} -M {cmd.QEMU_MACHINE}"
    out = unstreamed(ran.output_spikes, samples, steps, blank) if stream else ran.output_spikes
    result = CEmulation(out, {}, {}, note, "stream" if stream else "batch", chosen, written.sha256, program)
    if ran.ticks is not None and ran.most_ticks is not None:
        total = int(feed.shape[0] * feed.shape[1])
        result.timing = {"instructions_per_step": ran.ticks * cmd.INSTRUCTIONS_PER_TICK / max(1, total),
                         "most_instructions_in_a_step": ran.most_ticks * cmd.INSTRUCTIONS_PER_TICK,
                         "steps": total, "rule": f"SysTick ticks around snn_step x {cmd.INSTRUCTIONS_PER_TICK} "
                         "(QEMU -icount shift=0: 1 ns per instruction, SysTick at 25 MHz); resolution 40 instructions"}
    return result


__all__ = ["run_artefact"]
