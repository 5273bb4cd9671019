"""Hardware-aware hyper-parameter search: the paper's two-step HPO on Optuna (``snncc hpo``).

Step 1 anneals the nine hyper-parameters (``space.SEARCH_SPACE``, ``annealing.AnnealingSampler``
with the paper's two evenly spaced re-initialisations); step 2 is a grid over time_bin_size x
nb_input_copies around step 1's best. Every trial trains with ``snncc.training``, reports each
epoch to a pruner, and is compiled for Loihi (cores, synaptic ops, ESTIMATED energy and delay per
sample, optionally the bit-exact emulated accuracy). Studies live in an Optuna storage (SQLite by
default, PostgreSQL for many machines) and resume where they stopped. See docs/hpo.md.
"""

from snncc.hpo.run import HpoRequest, run_hpo

__all__ = ["HpoRequest", "run_hpo"]
