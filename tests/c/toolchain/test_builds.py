"""The artefact's C builds as the issue asks, and the Cortex-M4 build run in QEMU equals the emulator:

* strict C99 (``-std=c99 -Wall -Wextra -Werror -pedantic``), snn.c alone;
* a Cortex-M0 object with soft float that calls no floating-point helper (``arm-none-eabi-nm``: no __aeabi_f*,
  __aeabi_d*);
* the Cortex-M4 program (``-mcpu=cortex-m4 -mthumb -Os``) in ``qemu-system-arm -M mps2-an386`` with
  semihosting: output spikes and every population's spikes, current and voltage equal the emulator's, on a
  Braille graph and a random graph with delays, both resets, multi-spike events and saturation;
* the artefact's own Makefile (``make host strict m0``).

In CI (CI=true) the cross toolchain is installed by .ci/run and these tests never skip.
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np

from c_test_graphs import NIR_DIR, assert_trace_equal, need, network, random_graph, sources, spikes


def test_strict_c99_build(build_cache):
    need("gcc")
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    net = network(random_graph(11, spikes=3), "per-neuron-16")
    tb.build(sources(net), cmd.strict_command(), "snn_strict.o", cache=build_cache)


def test_cortex_m0_soft_float_object_has_no_float_helpers(build_cache):
    need("arm-none-eabi-gcc", "arm-none-eabi-nm")
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    for seed in (4, 5):
        net = network(random_graph(seed, spikes=3, big=seed == 5), "per-neuron")
        obj = tb.build(sources(net), cmd.m0_command(), cmd.M0_OBJECT, cache=build_cache).path
        assert tb.float_helpers(obj) == []
    # the check can fail: a float in the C is seen
    planted = dict(sources(net))
    planted["snn.c"] = planted["snn.c"] + b"\nfloat snn_planted(float a, int b);\nfloat snn_planted(float a, int b) " \
                                          b"{ return a * (float)b; }\n"
    obj = tb.build(planted, cmd.m0_command(), cmd.M0_OBJECT, cache=build_cache).path
    assert any(name.startswith("__aeabi_f") for name in tb.float_helpers(obj))


def test_qemu_cortex_m4_equals_emulator(build_cache):
    need("arm-none-eabi-gcc", "qemu-system-arm")
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    braille = load_model(NIR_DIR / "braille_noDelay_noBias_subtract.nir", LoadOptions(dt=1e-4, reset="subtract"))
    cases = [(network(braille, "per-neuron", 60), spikes(6, 60, 12, 0.08, 3)),
             (network(random_graph(21, n_hidden=9, spikes=3, big=True), "per-layer-16", 30), spikes(3, 30, 5, 0.5, 4))]
    for net, x in cases:
        emulated = emulate_network(net, x, record=True)
        elf = tb.build(sources(net), cmd.m4_command(trace=True), cmd.M4_PROGRAM, cache=build_cache).path
        ran = tb.run_qemu(elf, x, net.outputs, sizes=[p.n for p in net.populations])
        np.testing.assert_array_equal(ran.output_spikes, emulated.output_spikes)
        assert_trace_equal(net, emulated, ran.trace)
        assert ran.ticks and ran.ticks > 0              # SysTick counted under -icount


def test_systick_counts_instructions():
    """Under -icount shift=0 one 25 MHz SysTick tick is 40 instructions: a loop of a known length reads so."""
    need("arm-none-eabi-gcc", "qemu-system-arm")
    import tempfile
    from pathlib import Path

    from snncc.targets.c.artefact import support
    from snncc.targets.c.toolchain import commands as cmd

    program = r"""
#include <stdio.h>
#include <stdint.h>
#define CSR (*(volatile uint32_t *)0xE000E010u)
#define RVR (*(volatile uint32_t *)0xE000E014u)
#define CVR (*(volatile uint32_t *)0xE000E018u)
int main(int argc, char **argv) {
    uint32_t a, b, n = 100000u;
    (void)argc; (void)argv;
    RVR = 0xFFFFFFu; CVR = 0u; CSR = 5u;
    a = CVR;
    __asm__ volatile("1: subs %0, %0, #1\n bne 1b" : "+r"(n));
    b = CVR;
    printf("ticks %lu\n", (unsigned long)((a - b) & 0xFFFFFFu));
    return 0;
}
"""
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        (d / "loop.c").write_text(program)
        (d / "startup_mps2.c").write_text(support.STARTUP_C)
        (d / "mps2_an386.ld").write_text(support.LINKER_SCRIPT)
        subprocess.run([cmd.ARM_CC, *cmd.M4_FLAGS, *cmd.M4_LINK, "-o", "loop.elf", "startup_mps2.c", "loop.c"],
                       cwd=d, check=True, capture_output=True)
        out = subprocess.run(cmd.qemu_command("loop.elf"), cwd=d, check=True, capture_output=True, text=True,
                             timeout=60).stdout
    ticks = int(out.split()[1])
    # 2 instructions per iteration (subs, bne) + a few around: 200,000 instructions = 5,000 ticks
    assert abs(ticks * cmd.INSTRUCTIONS_PER_TICK - 200_000) <= 2 * cmd.INSTRUCTIONS_PER_TICK


def test_the_artefacts_makefile_builds(braille_artefact, tmp_path):
    need("gcc", "make", "arm-none-eabi-gcc", "arm-none-eabi-nm")
    work = tmp_path / "copy"
    shutil.copytree(braille_artefact, work)
    done = subprocess.run(["make", "-s", "host", "strict", "m0"], cwd=work, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (work / "snn").is_file() and (work / "snn_m0.o").is_file()


def test_the_cmake_snippet_builds_a_program(braille_artefact, tmp_path):
    """``include(snn.cmake)`` + ``target_link_libraries(app PRIVATE snn)``, as its header says (skipped without
    cmake, which CI does not install: the snippet is a convenience, the Makefile the tested build)."""
    if shutil.which("cmake") is None or shutil.which("gcc") is None:
        import pytest

        pytest.skip("cmake or gcc not installed")
    (tmp_path / "CMakeLists.txt").write_text(
        "cmake_minimum_required(VERSION 3.13)\nproject(app C)\n"
        f"include({braille_artefact.as_posix()}/snn.cmake)\n"
        f"add_executable(app {braille_artefact.as_posix()}/main.c)\ntarget_link_libraries(app PRIVATE snn)\n")
    build = tmp_path / "build"
    for command in (["cmake", "-S", str(tmp_path), "-B", str(build)], ["cmake", "--build", str(build)]):
        done = subprocess.run(command, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stdout + done.stderr
    assert (build / "app").is_file()
