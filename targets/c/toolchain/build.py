"""Building and running an artefact's C: the host compiler, the Cortex-M4 build run in QEMU, the Cortex-M0 object.

Every build happens in a work directory of its own (the artefact directory is only read). ``cache`` (a directory)
keeps builds by the SHA-256 of their sources and command, so the same C is compiled once (the tests share one
per session); without it the work directory is temporary. A missing tool is refused in one line naming it and
the Debian package that provides it.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.c.toolchain import commands as cmd
from snncc.targets.c.toolchain.files import input_bytes, read_outputs, read_trace

PACKAGES = {cmd.HOST_CC: "gcc", cmd.ARM_CC: "gcc-arm-none-eabi and libnewlib-arm-none-eabi",
            cmd.ARM_NM: "binutils-arm-none-eabi", cmd.ARM_SIZE: "binutils-arm-none-eabi",
            cmd.QEMU: "qemu-system-arm"}
SOURCES = ("snn.c", "snn.h", "main.c", "startup_mps2.c", "mps2_an386.ld")
BUILD_TIMEOUT_S = 600
RUN_TIMEOUT_S = 3600


def available(tool: str) -> bool:
    return shutil.which(tool) is not None


def require(tool: str) -> str:
    found = shutil.which(tool)
    if found is None:
        raise SnnccError(f"not found on PATH (Debian: apt-get install {PACKAGES.get(tool, tool)})", field=tool)
    return found


def artefact_sources(directory: Path) -> dict[str, bytes]:
    """The artefact's C sources and board files, read through ``kit.artefact.member`` (regular files inside)."""
    from snncc.targets.kit.artefact import member

    return {name: member(directory, name).read_bytes() for name in SOURCES}


def _first_error(text: str) -> str:
    for line in text.splitlines():
        if re.search(r"error|undefined reference", line):
            return line.strip()[:300]
    return (text.strip().splitlines() or ["(no output)"])[-1][:300]


@dataclass
class Build:
    path: Path                      # the program or object built
    directory: Path                 # its work directory
    command: list[str]


def build(sources: Mapping[str, bytes], command: list[str], output: str, *, cache: Path | None = None,
          workdir: Path | None = None) -> Build:
    """Run the compiler ``command`` (writing ``output``) on ``sources`` in a work directory: ``cache / <sha256>``
    (reused when already built), else ``workdir``."""
    require(command[0])
    key = hashlib.sha256(repr((sorted(sources.items()), command)).encode()).hexdigest()[:32]
    where = (cache / key) if cache is not None else workdir
    if where is None:
        raise ValueError("build needs a cache or a work directory")
    done = where / output
    if cache is not None and done.is_file():
        return Build(done, where, command)
    where.mkdir(parents=True, exist_ok=True)
    for name, data in sources.items():
        (where / name).write_bytes(data)
    proc = subprocess.run(command, cwd=where, capture_output=True, text=True, timeout=BUILD_TIMEOUT_S)
    if proc.returncode != 0 or not done.is_file():
        raise SnnccError(f"{' '.join(command[:1])} failed: {_first_error(proc.stderr + proc.stdout)}",
                         field=output)
    return Build(done, where, command)


@dataclass
class ProgramRun:
    output_spikes: np.ndarray                   # (B, T, N) uint8
    stdout: str
    trace: list[dict[str, np.ndarray]] | None = None
    ticks: int | None = None                    # SysTick ticks inside snn_step, summed (Cortex-M4 build in QEMU)
    most_ticks: int | None = None               # the most in one step


def _run(command: list[str], x: np.ndarray, outputs: int, sizes: list[int] | None, cwd: Path) -> ProgramRun:
    samples, steps = int(x.shape[0]), int(x.shape[1])
    (cwd / cmd.INPUT_FILE).write_bytes(input_bytes(x))
    for name in (cmd.OUTPUT_FILE, cmd.TRACE_FILE):
        (cwd / name).unlink(missing_ok=True)
    proc = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=RUN_TIMEOUT_S)
    if proc.returncode != 0 or not (cwd / cmd.OUTPUT_FILE).is_file():
        raise SnnccError(f"the program failed (status {proc.returncode}): {_first_error(proc.stdout + proc.stderr)}",
                         field=os.path.basename(command[-1]))
    out = read_outputs(cwd / cmd.OUTPUT_FILE, samples, steps, outputs)
    trace = read_trace(cwd / cmd.TRACE_FILE, samples, steps, sizes) if sizes is not None else None
    run = ProgramRun(out, proc.stdout, trace)
    found = re.search(r"systick: \d+ steps, ticks (\d+) (\d+) \(high, low word\), most (\d+)", proc.stdout)
    if found:
        run.ticks = (int(found.group(1)) << 32) + int(found.group(2))
        run.most_ticks = int(found.group(3))
    return run


def run_program(program: Path, x: np.ndarray, outputs: int, *, sizes: list[int] | None = None) -> ProgramRun:
    """Run a host build of ``main.c`` on ``x`` (B, T, C); ``sizes`` (population sizes): a trace build's trace."""
    with tempfile.TemporaryDirectory(prefix="snncc-c-run-") as tmp:
        return _run([str(program), cmd.INPUT_FILE, cmd.OUTPUT_FILE, cmd.TRACE_FILE], x, outputs, sizes, Path(tmp))


def run_qemu(elf: Path, x: np.ndarray, outputs: int, *, sizes: list[int] | None = None) -> ProgramRun:
    """Run the Cortex-M4 build in QEMU (MPS2 AN386, semihosting files in a temporary working directory,
    ``-icount shift=0``)."""
    require(cmd.QEMU)
    with tempfile.TemporaryDirectory(prefix="snncc-c-qemu-") as tmp:
        return _run(cmd.qemu_command(str(elf)), x, outputs, sizes, Path(tmp))


def float_helpers(obj: Path) -> list[str]:
    """The floating-point helper symbols (``__aeabi_f*``, ``__aeabi_d*``) an ARM object refers to."""
    proc = subprocess.run([require(cmd.ARM_NM), str(obj)], capture_output=True, text=True, timeout=60, check=True)
    names = [line.split()[-1] for line in proc.stdout.splitlines() if line.strip()]
    return sorted(n for n in names if n.startswith(cmd.FLOAT_HELPER_PREFIXES))


def section_sizes(obj: Path) -> dict[str, int]:
    """text, data and bss bytes of an ARM object or program (``arm-none-eabi-size``, Berkeley format)."""
    proc = subprocess.run([require(cmd.ARM_SIZE), str(obj)], capture_output=True, text=True, timeout=60, check=True)
    text, data, bss = (int(v) for v in proc.stdout.splitlines()[1].split()[:3])
    return {"text": text, "data": data, "bss": bss}


def cache_dir() -> Path:
    """A per-user cache of builds under the temporary directory (used by tests and benches)."""
    path = Path(tempfile.gettempdir()) / f"snncc-c-builds-{os.getuid()}"
    path.mkdir(parents=True, exist_ok=True)
    return path


__all__ = ["available", "require", "artefact_sources", "build", "Build", "ProgramRun", "run_program", "run_qemu",
           "float_helpers", "section_sizes", "cache_dir", "SOURCES"]
