"""One compute thread for small workloads: torch and the BLAS/OpenMP pools (threadpoolctl).

Validation and check runs use batches of a few samples, which lose more to thread hand-offs than
they gain from parallelism -- badly so on a busy machine.
"""

from __future__ import annotations

import contextlib
from typing import Iterator


@contextlib.contextmanager
def one_thread() -> Iterator[None]:
    """Within the block torch and every native thread pool run on one thread; restored afterwards."""
    import torch
    from threadpoolctl import threadpool_limits

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with threadpool_limits(limits=1):
            yield
    finally:
        torch.set_num_threads(before)
