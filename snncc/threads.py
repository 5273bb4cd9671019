"""One compute thread for small workloads: torch (where it is loaded) and the BLAS/OpenMP pools (threadpoolctl).

Validation and check runs use batches of a few samples, which lose more to thread hand-offs than
they gain from parallelism -- badly so on a busy machine, where idle pool threads spin. torch is
limited only when something already imported it: this module never loads it.
"""

from __future__ import annotations

import contextlib
import sys
from typing import Iterator


@contextlib.contextmanager
def one_thread() -> Iterator[None]:
    """Within the block torch (if loaded) and every native thread pool run on one thread; restored afterwards."""
    from threadpoolctl import threadpool_limits

    torch = sys.modules.get("torch")
    before = torch.get_num_threads() if torch is not None else None
    if torch is not None:
        torch.set_num_threads(1)
    try:
        with threadpool_limits(limits=1):
            yield
    finally:
        if torch is not None and before is not None:
            torch.set_num_threads(before)
