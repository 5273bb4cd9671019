"""The Typer application every verb module registers on (one module per verb)."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="snncc",
    help=(
        "snncc: compile trained spiking networks (CUBA LIF RSNN/FFSNN, conv SNNs) and LSTMs for every installed "
        "target (neuromorphic chips, GPUs, microcontrollers: snncc compile --help lists them), and prove what each "
        "loses against one reference simulation."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


@app.callback()
def _verbs() -> None:
    # A group even when only the invoked verb is registered (``main.build_app``): without a
    # callback, typer would run a lone command as the program itself.
    pass
