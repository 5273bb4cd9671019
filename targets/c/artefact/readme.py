"""The artefact's README.md: what it is, its API, its arithmetic, how to build, run and check it."""

from __future__ import annotations

from typing import Any

from snncc.targets.c.options import DECAY_BITS


def readme(net, manifest: dict[str, Any]) -> str:   # noqa: ANN001 (a CNetwork)
    mem = manifest["memory"]
    part = manifest["part"]
    tb = manifest["time_base"]
    pops = "\n".join(f"| {i} | {p.name} | {p.n} | {p.reset} | {p.refractory} | V {p.fire_test} theta, at most "
                     f"{p.max_spikes}/step | {p.frac_bits} |" for i, p in enumerate(net.populations))
    projs = "\n".join(f"| {'input' if q.source < 0 else net.populations[q.source].name} | "
                      f"{net.populations[q.target].name} | {q.delay} | int{q.bits} | "
                      f"{'per-layer' if q.per_layer else 'per-neuron'} | {q.layout} |" for q in net.projections)
    return f"""# A spiking network in C99 (snncc, target `c`)

Compiled from `{manifest['source'].get('file') or 'a model'}` (graph SHA-256 `{manifest['model']['graph_sha256']}`)
with weight rule `{manifest['arithmetic']['rule']}`: {manifest['selection']['reason']}.

* `snn.h`, `snn.c`: the network. No allocation, no floating point, nothing beyond `<stdint.h>` and
  `<string.h>`; weights and constants are `static const` (flash).
* `main.c`: an example driver that reads spikes from a file and prints each sample's output counts.
* `Makefile`: `make host` (this machine), `make strict` (strict C99), `make m4` / `make run-qemu` (Cortex-M4 on
  QEMU's MPS2 AN386 board), `make m0` (Cortex-M0, soft float: fails if a floating-point helper is called);
  `snn.cmake` adds the network to a CMake build as the library `snn`.
* `network.npz`: the same integers, for `snncc emulate` (bit-exact) and `snncc check`.

## API

```c
#include "snn.h"
static snn_state_t state;               /* {mem['ram_state_bytes']} bytes of RAM */
uint16_t counts[SNN_OUTPUTS] = {{0}};
snn_reset(&state);                       /* before each sample */
snn_step(&state, in_spikes, counts);     /* once per time step: SNN_INPUTS bytes in, counts += output spikes */
```

`in_spikes[i]` nonzero is a spike on input channel i at this step. `snn_step` adds this step's output spikes
to `out_counts` (saturating at 65535; NULL is allowed) and leaves them in `state.out_spikes`. The class is
the output with the most spikes over a sample (ties to the lowest index). One step is dt = {tb['dt']} s;
a sample lasts {tb['steps']} steps ({tb['rule']}).

## Network

| population | name | neurons | reset | refractory | spike rule | F |
|---|---|---|---|---|---|---|
{pops}

| from | to | delay (steps) | weights | scale | storage |
|---|---|---|---|---|---|
{projs}

## Arithmetic (docs/c.md in snncc)

State I and V are int32 in units of 2^-F of the model's units. Each step, population by population in the
order above, for every neuron: I = sat32(rnd(alpha * I) + sum_k acc_k * 2^e_k + current biases),
V = sat32(rnd(beta * V) + I + voltage bias), V held at 0 while refractory, spikes while V passes the
threshold (subtracted each time), then the reset. alpha and beta are Q{DECAY_BITS} multipliers,
rnd(a * x) = floor((a * x + 2^{DECAY_BITS - 1}) / 2^{DECAY_BITS}) (round half up), computed without shifting a
negative number right; sat32 clamps an exact 64-bit value to the int32 range. acc_k sums the int8/int16
weights of the source's neurons that spiked d_k steps earlier (event lists, so the work follows the spikes).

## Memory

Flash for constant data: {mem['flash_data_bytes']:,} bytes (weights {mem['flash_weights_bytes']:,}); RAM for the
state: {mem['ram_state_bytes']:,} bytes. Against {part['part']} ({part['source']}): flash
{100 * part['flash_share']:.1f} %, RAM {100 * part['ram_share']:.1f} % (code not included; `snncc map` measures it
where arm-none-eabi-gcc is installed).

## Check it yourself

```
snncc emulate THIS_DIRECTORY --input spikes.npy -o emulated.npz
snncc run THIS_DIRECTORY --input spikes.npy --backend host -o host.npz
snncc run THIS_DIRECTORY --input spikes.npy --backend qemu -o qemu.npz
```

The three .npz files hold the same `output_spikes`, `counts` and `prediction`, bit for bit.
"""


__all__ = ["readme"]
