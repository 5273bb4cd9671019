"""What a ``Conv`` node computes, in two equivalent forms.

* ``conv_apply``: the reference simulator's form, PyTorch's ``convNd`` on the (..., C*prod(spatial))
  vectors reshaped to (-1, C, *spatial) and flattened back (C order).
* ``conv_matrix``: the same linear map as an explicit sparse matrix A (out_size, in_size), built
  from the index rule in ``Conv``'s docstring (y = A x + bias_vector), for targets whose synapses
  are a plain connection matrix (Loihi). Tests check the two against each other.
"""

from __future__ import annotations

import numpy as np

from snncc.ir.nodes import Conv


def conv_apply(op: Conv, x, weight, bias=None):
    """y = conv(x) for x (..., in_size) -> (..., size), with torch tensors ``weight`` and ``bias``."""
    from torch.nn import functional as F

    conv = (F.conv1d, F.conv2d, F.conv3d)[op.spatial_dims - 1]
    lead = x.shape[:-1]
    y = conv(x.reshape((-1,) + op.in_shape), weight, bias, stride=op.stride, padding=op.padding,
             dilation=op.dilation, groups=op.groups)
    return y.reshape(tuple(lead) + (op.size,))


def conv_matrix(op: Conv):
    """The connection matrix A (out_size, in_size) as scipy CSR: A[o*P + p, c*Q + q] = W[o, c', k]
    for every output position p whose tap k lands on input position q (zeros from padding dropped)."""
    import scipy.sparse as sp

    out_ch, cin_g = op.weight.shape[:2]
    in_spatial, out_spatial = op.in_shape[1:], op.out_shape[1:]
    per_group = out_ch // op.groups
    rows, cols, vals = [], [], []
    # every (output position, kernel tap) pair, per spatial dim: input index and whether it is inside
    taps = np.stack(np.meshgrid(*[np.arange(k) for k in op.kernel], indexing="ij"), -1).reshape(-1, op.spatial_dims)
    pos = np.stack(np.meshgrid(*[np.arange(n) for n in out_spatial], indexing="ij"), -1).reshape(-1, op.spatial_dims)
    src = (pos[:, None, :] * np.asarray(op.stride) - np.asarray(op.padding)
           + taps[None, :, :] * np.asarray(op.dilation))                    # (P, K, dims)
    inside = np.all((src >= 0) & (src < np.asarray(in_spatial)), axis=2)    # (P, K)
    p_idx, k_idx = np.nonzero(inside)
    q_flat = np.ravel_multi_index(tuple(src[p_idx, k_idx].T), in_spatial) if p_idx.size else np.zeros(0, np.int64)
    n_pos_out, n_pos_in = int(np.prod(out_spatial)), int(np.prod(in_spatial))
    w_flat = op.weight.reshape(out_ch, cin_g, -1)
    for o in range(out_ch):
        g = o // per_group
        for c in range(cin_g):
            w = w_flat[o, c, k_idx]
            keep = w != 0
            rows.append(o * n_pos_out + p_idx[keep])
            cols.append((g * cin_g + c) * n_pos_in + q_flat[keep])
            vals.append(w[keep])
    a = sp.csr_matrix((np.concatenate(vals) if vals else np.zeros(0), (np.concatenate(rows) if rows else np.zeros(0, int),
                       np.concatenate(cols) if cols else np.zeros(0, int))), shape=(op.size, op.in_size))
    a.sum_duplicates()
    return a


def conv_bias_vector(op: Conv) -> np.ndarray | None:
    """The per-channel bias repeated over every output position (C order), or None."""
    if op.bias is None:
        return None
    return np.repeat(op.bias, int(np.prod(op.out_shape[1:])))
