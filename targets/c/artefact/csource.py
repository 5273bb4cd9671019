"""``snn.h`` and ``snn.c`` from a ``CNetwork``: dependency-free C99, the emulator's arithmetic line for line.

No allocation, no floating point, no library beyond ``<stdint.h>`` and ``<string.h>``; weights and constants
``static const`` (flash). No implementation-defined behaviour: right shifts apply to non-negative values only
(``floor_shift`` writes floor division of a negative value through ``~``, exact for the two's-complement
``int64_t`` that C99 guarantees), left shifts to the constant 1, narrowing conversions happen only after a
clamp into range. The state is one caller-owned struct (``snn_state_t``): int32 current and voltage per
neuron, per-projection int32 accumulators (scratch), per spike source a ring of event lists (the neurons that
spiked, with their counts where a population may fire more than once per step) as long as its longest delay.
"""

from __future__ import annotations

import re

import numpy as np

from snncc.targets.c.lowering.network import CNetwork, CPopulation, CProjection
from snncc.targets.c.options import COUNT_LIMIT, DECAY_BITS

PER_LINE = 20
GENERATOR = 3               # the text this module emits for a network; bumped whenever it changes
UNROLL = 4                  # dense fan-out rows are added 4 weights per loop iteration


def _comment(text: str) -> str:
    """Text safe inside a C comment (no comment delimiters, no control characters)."""
    return re.sub(r"[^\x20-\x7e]", "?", str(text)).replace("*/", "*_/").replace("/*", "/_*")


def _array(ctype: str, name: str, values: np.ndarray) -> list[str]:
    vals = [str(int(v)) for v in np.asarray(values).reshape(-1)]
    out = [f"static const {ctype} {name}[{len(vals)}] = {{"]
    for i in range(0, len(vals), PER_LINE):
        out.append("    " + ", ".join(vals[i:i + PER_LINE]) + ("," if i + PER_LINE < len(vals) else ""))
    out.append("};")
    return out


def index_type(n: int) -> str:
    return "uint16_t" if n <= 0xFFFF else "uint32_t"


def _uniform(values: np.ndarray) -> bool:
    v = np.asarray(values)
    return bool(v.size and np.all(v == v.reshape(-1)[0]))


class _Names:
    """C names of a network's parts (sources: ``in``, ``p0``, ``p1``, ...)."""

    def __init__(self, net: CNetwork) -> None:
        self.net = net

    @staticmethod
    def src(source: int) -> str:
        return "in" if source < 0 else f"p{source}"

    def slots(self, source: int) -> int:
        return self.net.max_delay(source) + 1


def state_members(net: CNetwork) -> list[tuple[int, str, str, str]]:
    """(alignment, C type, declarator, comment) of every member of ``snn_state_t``, in declaration order (widest
    first, so the struct has no inner padding)."""
    names = _Names(net)
    members: list[tuple[int, str, str, str]] = [(4, "uint32_t", "t", "steps since snn_reset (saturates)")]
    for i, p in enumerate(net.populations):
        members.append((4, "int32_t", f"p{i}_i[{p.n}]", f"population {i} '{_comment(p.name)}': current I"))
        members.append((4, "int32_t", f"p{i}_v[{p.n}]", "voltage V (after reset)"))
    for k, q in enumerate(net.projections):
        members.append((4, "int32_t", f"acc{k}[{net.populations[q.target].n}]",
                        f"projection {k}: this step's weighted events (scratch, zero between steps)"))
    for i, p in enumerate(net.populations):
        if p.refractory > 1:
            members.append((2, "uint16_t", f"p{i}_ref[{p.n}]", "refractory steps left"))
    for source in range(-1, len(net.populations)):
        n = net.source_size(source)
        it = index_type(n)
        size = 2 if it == "uint16_t" else 4
        s = names.src(source)
        slots = names.slots(source)
        members.append((size, it, f"ev_{s}[{slots}][{n}]", f"{'input' if source < 0 else s} events, ring of {slots} "
                                                             "step(s): indices"))
        members.append((size, it, f"nev_{s}[{slots}]", "events per slot"))
        if source >= 0 and net.populations[source].counts:
            members.append((1, "uint8_t", f"cnt_{s}[{slots}][{n}]", "spikes per event"))
        members.append((1, "uint8_t", f"pos_{s}", "ring slot of the current step"))
    members.append((1, "uint8_t", f"out_spikes[{net.outputs}]", "this step's output spikes"))
    return sorted(members, key=lambda m: -m[0])


def state_bytes(net: CNetwork) -> int:
    """sizeof(snn_state_t) on a target where int32 aligns to 4 and int16 to 2 (every ARM EABI core)."""
    total = 0
    for align, _, decl, _ in state_members(net):
        count = 1
        for dim in re.findall(r"\[(\d+)\]", decl):
            count *= int(dim)
        total += align * count
    return -(-total // 4) * 4


def header(net: CNetwork, meta: dict) -> str:
    lines = [
        "/* snn.h: a spiking network compiled by snncc for microcontrollers (C99, integer arithmetic only).",
        f" * model: {_comment(meta.get('model', ''))}",
        f" * rule: {_comment(net.rule)}; dt = {net.dt!r} s per step; a sample lasts {net.steps} steps.",
        " * API: snn_reset(&state) before a sample; snn_step(&state, in_spikes, out_counts) once per time step:",
        " *   in_spikes  SNN_INPUTS bytes, nonzero = a spike on that channel at this step",
        " *   out_counts SNN_OUTPUTS counters the step adds its output spikes to (saturating at 65535), or NULL;",
        " *   state.out_spikes holds this step's output spikes.  See README.md. */",
        "#ifndef SNN_H", "#define SNN_H", "", "#include <stdint.h>", "",
        f"#define SNN_INPUTS {net.inputs}",
        f"#define SNN_OUTPUTS {net.outputs}",
        f"#define SNN_POPULATIONS {len(net.populations)}",
        f"#define SNN_NEURONS {sum(p.n for p in net.populations)}",
        f"#define SNN_STEPS {net.steps}",
        f"#define SNN_DT_NS {int(round(net.dt * 1e9))}",
        "", "typedef struct {"]
    for _, ctype, decl, comment in state_members(net):
        lines.append(f"    {ctype} {decl};   /* {comment} */")
    lines += ["} snn_state_t;", "",
              "void snn_reset(snn_state_t *state);",
              "void snn_step(snn_state_t *state, const uint8_t *in_spikes, uint16_t *out_counts);",
              "", "#ifdef SNN_TRACE",
              f"#define SNN_TRACE_VALUES {3 * sum(p.n for p in net.populations)}",
              "/* every population's spikes, current and voltage at this step, population by population */",
              "void snn_trace(const snn_state_t *state, int32_t *out);", "#endif", "", "#endif", ""]
    return "\n".join(lines)


def _constant(name: str, ctype: str, values: np.ndarray, j: str = "j") -> tuple[str, list[str]]:
    """(the C expression of a per-neuron constant at index ``j``, its definition lines): a macro when uniform."""
    if _uniform(values):
        return f"(({ctype}){int(np.asarray(values).reshape(-1)[0])})", []
    return f"{name}[{j}]", _array(ctype, name, values)


def _weights(k: int, q: CProjection) -> list[str]:
    ctype = "int8_t" if q.bits == 8 else "int16_t"
    if q.layout == "dense":
        return _array(ctype, f"w{k}", q.weights)
    ptr, idx, val = q.csr()
    if not val.size:
        return []
    return (_array("uint32_t", f"w{k}_ptr", ptr) + _array(index_type(q.weights.shape[1]), f"w{k}_idx", idx)
            + _array(ctype, f"w{k}_val", val))


def _deliver(net: CNetwork, k: int, q: CProjection) -> list[str]:
    """Add the events of projection k's source, d steps back, into acc{k}."""
    names = _Names(net)
    s = names.src(q.source)
    slots = names.slots(q.source)
    n_t = net.populations[q.target].n
    if q.layout == "sparse" and not np.any(q.weights):
        return [f"    /* projection {k}: all weights are zero */"]
    slot = f"state->pos_{s}" if q.delay == 0 else \
        f"(state->pos_{s} >= {q.delay}u ? state->pos_{s} - {q.delay}u : state->pos_{s} + {slots - q.delay}u)"
    counted = q.source >= 0 and net.populations[q.source].counts
    lines = [f"    /* projection {k}: {'input' if q.source < 0 else s} -> p{q.target}, delay {q.delay}, {q.bits}-bit "
             f"{q.layout} ({_comment(q.origin)}) */",
             "    {", f"        const uint32_t slot = {slot};",
             f"        const uint32_t n = state->nev_{s}[slot];",
             "        uint32_t k;", "        for (k = 0; k < n; k++) {",
             f"            const uint32_t i = state->ev_{s}[slot][k];"]
    mult = "c * " if counted else ""
    if counted:
        lines.append(f"            const int32_t c = state->cnt_{s}[slot][k];")
    if q.layout == "dense":
        ctype = "int8_t" if q.bits == 8 else "int16_t"
        lines += [f"            const {ctype} *row = &w{k}[i * {n_t}u];", f"            int32_t *acc = state->acc{k};"]
        whole = n_t - n_t % UNROLL
        if whole:
            lines += ["            uint32_t u;", f"            for (u = 0; u < {whole}u; u += {UNROLL}u) {{"]
            lines += [f"                acc[u + {r}u] += {mult}row[u + {r}u];" for r in range(UNROLL)]
            lines += ["            }"]
        lines += [f"            acc[{r}] += {mult}row[{r}];" for r in range(whole, n_t)]
    else:
        lines += ["            uint32_t e;",
                  f"            for (e = w{k}_ptr[i]; e < w{k}_ptr[i + 1u]; e++) state->acc{k}[w{k}_idx[e]] += "
                  f"{mult}w{k}_val[e];"]
    lines += ["        }", "    }"]
    return lines


def _population(net: CNetwork, i: int, pop: CPopulation, consts: list[str]) -> list[str]:
    th, d1 = _constant(f"p{i}_th", "int32_t", pop.threshold)
    al, d2 = _constant(f"p{i}_alpha", "int32_t", pop.alpha)
    be, d3 = _constant(f"p{i}_beta", "int32_t", pop.beta)
    consts += d1 + d2 + d3
    body = [f"/* population {i} '{_comment(pop.name)}': {pop.n} neurons, reset {pop.reset}, refractory "
            f"{pop.refractory}, spike when V {pop.fire_test} threshold (at most {pop.max_spikes} per step), "
            f"F = {pop.frac_bits} */", f"static void update_p{i}(snn_state_t *state)", "{",
            f"    const uint32_t here = state->pos_p{i};", "    uint32_t nev = 0, j;"]
    terms = []
    for k, q in enumerate(net.projections):
        if q.target != i:
            continue
        body += _deliver(net, k, q)
        if _uniform(q.exponent):
            terms.append((k, f"((int64_t)1 << {int(q.exponent[0])})"))
        else:                               # per-neuron scales as int32 multipliers 2**e: one multiply-accumulate
            consts += _array("int32_t", f"m{k}", np.left_shift(1, q.exponent.astype(np.int64)))
            terms.append((k, f"m{k}[j]"))
    for t, term in enumerate(pop.bias_i):
        consts += _array("int32_t", f"p{i}_bi{t}", term.values)
    if pop.bias_v is not None:
        consts += _array("int32_t", f"p{i}_bv", pop.bias_v)
    body += [f"    for (j = 0; j < {pop.n}u; j++) {{",
             f"        int64_t x = decay({al}, state->p{i}_i[j]);", "        int32_t v;"]
    for k, scale in terms:
        body += [f"        x += (int64_t)state->acc{k}[j] * {scale};", f"        state->acc{k}[j] = 0;"]
    for t, term in enumerate(pop.bias_i):
        body.append(f"        x += p{i}_bi{t}[j];" if term.start == 0 else
                    f"        if (state->t >= {term.start}u) x += p{i}_bi{t}[j];")
    body += [f"        state->p{i}_i[j] = sat32(x);",
             f"        x = decay({be}, state->p{i}_v[j]) + state->p{i}_i[j];"]
    if pop.bias_v is not None:
        body.append(f"        x += p{i}_bv[j];")
    body.append("        v = sat32(x);")
    if pop.refractory > 1:
        body.append(f"        if (state->p{i}_ref[j] > 0u) {{ v = 0; state->p{i}_ref[j]--; }}")
    if pop.fires:
        op = pop.fire_test
        refr = [f"            state->p{i}_ref[j] = {pop.refractory - 1}u;"] if pop.refractory > 1 else []
        if pop.counts:
            body += ["        {", "            uint32_t c = 0;",
                     f"            while (c < {pop.max_spikes}u && v {op} {th}) {{ v -= {th}; c++; }}",
                     "            if (c > 0u) {"]
            body += (["                v = 0;"] if pop.reset == "zero" else [])
            body += ["    " + r for r in refr]
            body += [f"                state->ev_p{i}[here][nev] = ({index_type(pop.n)})j;",
                     f"                state->cnt_p{i}[here][nev] = (uint8_t)c;", "                nev++;",
                     "            }", "        }"]
        else:
            body += [f"        if (v {op} {th}) {{",
                     f"            v = {'0' if pop.reset == 'zero' else f'v - {th}'};"] + refr + \
                    [f"            state->ev_p{i}[here][nev++] = ({index_type(pop.n)})j;", "        }"]
    body += [f"        state->p{i}_v[j] = v;", "    }", f"    state->nev_p{i}[here] = ({index_type(pop.n)})nev;"]
    if i == net.output:
        body += ["    memset(state->out_spikes, 0, sizeof state->out_spikes);",
                 "    for (j = 0; j < nev; j++)",
                 f"        state->out_spikes[state->ev_p{i}[here][j]] = "
                 + (f"state->cnt_p{i}[here][j];" if pop.counts else "1u;")]
    body += ["}", ""]
    return body


PRELUDE = f"""
/* floor(x / 2**q): x >> q for x >= 0; for x < 0, ~x = -x - 1 >= 0 and ~(~x >> q) = floor(x / 2**q)
   (int64_t is two's complement by C99 7.18.1.1, so this is defined, unlike >> of a negative value) */
static int64_t floor_shift(int64_t x, unsigned q)
{{
    return x >= 0 ? x >> q : ~(~x >> q);
}}

/* a * x in Q{DECAY_BITS}, rounded half up: floor((a * x + 2**{DECAY_BITS - 1}) / 2**{DECAY_BITS}) */
static int64_t decay(int32_t a, int32_t x)
{{
    return floor_shift((int64_t)a * (int64_t)x + ((int64_t)1 << {DECAY_BITS - 1}), {DECAY_BITS}u);
}}

static int32_t sat32(int64_t x)
{{
    return x > INT32_MAX ? INT32_MAX : (x < INT32_MIN ? INT32_MIN : (int32_t)x);
}}
"""


def source(net: CNetwork, meta: dict) -> str:
    names = _Names(net)
    consts: list[str] = []
    for k, q in enumerate(net.projections):
        consts += _weights(k, q)
    updates: list[str] = []
    for i, pop in enumerate(net.populations):
        updates += _population(net, i, pop, consts)
    sources = range(-1, len(net.populations))
    step = ["void snn_step(snn_state_t *state, const uint8_t *in_spikes, uint16_t *out_counts)", "{",
            "    uint32_t i, n = 0;"]
    for src in sources:
        s, slots = names.src(src), names.slots(src)
        step.append(f"    state->pos_{s} = (uint8_t)(state->pos_{s} + 1u == {slots}u ? 0u : state->pos_{s} + 1u);")
    step += [f"    for (i = 0; i < {net.inputs}u; i++)",
             f"        if (in_spikes[i]) state->ev_in[state->pos_in][n++] = ({index_type(net.inputs)})i;",
             f"    state->nev_in[state->pos_in] = ({index_type(net.inputs)})n;"]
    step += [f"    update_p{i}(state);" for i in range(len(net.populations))]
    step += ["    if (out_counts) {", f"        for (i = 0; i < {net.outputs}u; i++) {{",
             "            uint32_t c = (uint32_t)out_counts[i] + state->out_spikes[i];",
             f"            out_counts[i] = (uint16_t)(c > {COUNT_LIMIT}u ? {COUNT_LIMIT}u : c);", "        }", "    }",
             "    if (state->t < UINT32_MAX) state->t++;", "}", ""]
    trace = ["#ifdef SNN_TRACE", "void snn_trace(const snn_state_t *state, int32_t *out)", "{", "    uint32_t j;"]
    for i, pop in enumerate(net.populations):
        cnt = f"state->cnt_p{i}[state->pos_p{i}][j]" if pop.counts else "1"
        trace += [f"    for (j = 0; j < {pop.n}u; j++) out[j] = 0;",
                  f"    for (j = 0; j < state->nev_p{i}[state->pos_p{i}]; j++) out[state->ev_p{i}[state->pos_p{i}][j]] "
                  f"= {cnt};",
                  f"    for (j = 0; j < {pop.n}u; j++) out[{pop.n}u + j] = state->p{i}_i[j];",
                  f"    for (j = 0; j < {pop.n}u; j++) out[{2 * pop.n}u + j] = state->p{i}_v[j];",
                  f"    out += {3 * pop.n}u;"]
    trace += ["}", "#endif", ""]
    head = ["/* snn.c: generated by snncc from the integer network in network.npz; the emulator (snncc emulate) runs",
            " * the same arithmetic (docs/c.md). Integer arithmetic only, no allocation, no library beyond",
            " * <stdint.h> and <string.h>. */", "#include <string.h>", "", "#include \"snn.h\"", PRELUDE]
    reset = ["void snn_reset(snn_state_t *state)", "{", "    memset(state, 0, sizeof *state);", "}", ""]
    return "\n".join(head + consts + [""] + updates + reset + step + trace)


__all__ = ["header", "source", "state_members", "state_bytes", "index_type", "GENERATOR"]
