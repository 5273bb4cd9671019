"""A spiking classifier's size, checked before torch allocates anything (``snncc.limits``' rule).

Training an RSNN/FFSNN builds, in float32: the input weights (n_inputs * input_copies, n_hidden),
the recurrent weights (n_hidden, n_hidden) of an RSNN, the readout (n_hidden, n_outputs), and per
batch the hidden layer's spikes (batch, steps, n_hidden). Each of these arrays may take at most
``snncc.limits.memory_cap()`` bytes, so ``--hidden 1000000000`` is refused at once instead of
asking torch for hundreds of GB.
"""

from __future__ import annotations

from snncc.limits import check_memory

FLOAT32 = 4


def check_snn_size(n_inputs: int, input_copies: int, n_hidden: int, n_outputs: int, recurrent: bool, batch: int,
                   steps: int, *, file: str | None = None, hidden_field: str | None = "--hidden",
                   batch_field: str | None = "--batch-size") -> None:
    """Raise SnnccError if one of the arrays training this model builds exceeds the memory rule
    (``hidden_field`` names the weights' cause, ``batch_field`` the batch's)."""
    width = int(n_inputs) * int(input_copies)
    h, b, t = int(n_hidden), int(batch), int(steps)
    arrays = [(width * h, f"the input weights ({width:,} x {h:,})", hidden_field)]
    if recurrent:
        arrays.append((h * h, f"the recurrent weights ({h:,} x {h:,})", hidden_field))
    arrays += [(h * int(n_outputs), f"the readout weights ({h:,} x {int(n_outputs):,})", hidden_field),
               (b * t * h, f"one batch's hidden spikes ({b:,} x {t:,} steps x {h:,})", batch_field)]
    for count, what, field in arrays:
        check_memory(FLOAT32 * count, f"{h:,} hidden neurons: {what}", file=file, field=field)
