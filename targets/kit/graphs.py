"""Pure Graph -> Graph passes a target may apply to the IR it is handed before lowering (``snncc.passes``).

    fold_linear(graph)              chains of Dense nodes folded into one
    current_biases(graph)           the current biases a LIF receives (Affine biases placed on its current)
    change_reset(graph, reset)      the graph with every LIF's reset replaced (what a reset change deploys)
"""

from __future__ import annotations

from snncc.passes.current_bias import BiasTerm, current_biases, max_abs_bias, restore_biases
from snncc.passes.fold_linear import fold_linear
from snncc.passes.reset_change import change_reset

__all__ = ["fold_linear", "current_biases", "BiasTerm", "max_abs_bias", "restore_biases", "change_reset"]
