"""The build and run command lines, stated once: the artefact's Makefile is rendered from them and the
toolchain modules run them (so what the tests prove is what a user's ``make`` does).

    host      gcc -O2 -std=c99 -Wall -Wextra -Werror -pedantic                  main.c snn.c -> snn
    strict    the same flags, -O0 and -c: snn.c alone as strict C99
    m4        arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -Os, newlib's semihosting library (rdimon.specs),
              no start files: startup_mps2.c and mps2_an386.ld place the image on QEMU's MPS2 AN386 board;
              -DSNN_SYSTICK reads SysTick around every snn_step
    m0        arm-none-eabi-gcc -mcpu=cortex-m0 -mthumb -mfloat-abi=soft -Os -c snn.c: the object a Cortex-M0
              links, checked for floating-point helpers (__aeabi_f*, __aeabi_d*) with arm-none-eabi-nm
    qemu      qemu-system-arm -M mps2-an386 -nographic -semihosting-config enable=on,target=native
              -icount shift=0 -kernel snn_m4.elf   (one instruction = 1 ns of virtual time: SysTick at the
              board's 25 MHz then counts 40 instructions per tick)
"""

from __future__ import annotations

HOST_CC = "gcc"
HOST_FLAGS = ("-O2", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic")
STRICT_FLAGS = ("-O0", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-c")
ARM_CC = "arm-none-eabi-gcc"
ARM_NM = "arm-none-eabi-nm"
ARM_SIZE = "arm-none-eabi-size"
M4_FLAGS = ("-mcpu=cortex-m4", "-mthumb", "-Os", "-std=c99", "-Wall", "-Wextra", "-Werror")
M4_LINK = ("--specs=rdimon.specs", "-nostartfiles", "-T", "mps2_an386.ld")
M4_DEFINES = ("-DSNN_SYSTICK",)
M0_FLAGS = ("-mcpu=cortex-m0", "-mthumb", "-mfloat-abi=soft", "-Os", "-std=c99", "-Wall", "-Wextra", "-Werror",
            "-pedantic", "-c")
QEMU = "qemu-system-arm"
QEMU_MACHINE = "mps2-an386"
QEMU_ARGS = ("-M", QEMU_MACHINE, "-nographic", "-semihosting-config", "enable=on,target=native",
             "-icount", "shift=0")
SYSTICK_HZ = 25_000_000                  # MPS2 AN386's SysTick clock in QEMU
INSTRUCTIONS_PER_TICK = 40               # -icount shift=0: 1 ns per instruction; one 25 MHz tick = 40 ns
FLOAT_HELPER_PREFIXES = ("__aeabi_f", "__aeabi_d")
HOST_PROGRAM = "snn"
M4_PROGRAM = "snn_m4.elf"
M0_OBJECT = "snn_m0.o"
INPUT_FILE, OUTPUT_FILE, TRACE_FILE = "input.bin", "output.bin", "trace.bin"


def host_command(output: str = HOST_PROGRAM, trace: bool = False) -> list[str]:
    return [HOST_CC, *HOST_FLAGS, *(["-DSNN_TRACE"] if trace else []), "-o", output, "main.c", "snn.c"]


def strict_command(output: str = "snn_strict.o") -> list[str]:
    return [HOST_CC, *STRICT_FLAGS, "-o", output, "snn.c"]


def m4_command(output: str = M4_PROGRAM, trace: bool = False) -> list[str]:
    return [ARM_CC, *M4_FLAGS, *M4_DEFINES, *(["-DSNN_TRACE"] if trace else []), *M4_LINK, "-o", output,
            "startup_mps2.c", "main.c", "snn.c"]


def m0_command(output: str = M0_OBJECT) -> list[str]:
    return [ARM_CC, *M0_FLAGS, "-o", output, "snn.c"]


def qemu_command(program: str = M4_PROGRAM) -> list[str]:
    return [QEMU, *QEMU_ARGS, "-kernel", program]


__all__ = ["host_command", "strict_command", "m4_command", "m0_command", "qemu_command", "HOST_CC", "ARM_CC",
           "ARM_NM", "ARM_SIZE", "QEMU", "QEMU_MACHINE", "SYSTICK_HZ", "INSTRUCTIONS_PER_TICK",
           "FLOAT_HELPER_PREFIXES", "HOST_PROGRAM", "M4_PROGRAM", "M0_OBJECT", "INPUT_FILE", "OUTPUT_FILE",
           "TRACE_FILE"]
