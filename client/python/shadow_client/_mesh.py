"""Meshes from numpy arrays, in the wire's layout (shadow.proto, message Mesh)."""

from __future__ import annotations

from typing import Optional

import numpy as np

from ._proto.shadow.v1 import shadow_pb2 as pb


def mesh(positions: np.ndarray, indices: np.ndarray, normals: Optional[np.ndarray] = None
         ) -> pb.Mesh:
    """positions (N, 3) and optional normals (N, 3) as little-endian float32, indices (T, 3) as
    little-endian uint32. Values are converted, never clipped: an index that does not fit uint32
    raises ValueError."""
    p = np.asarray(positions, dtype=np.float64)
    i = np.asarray(indices)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"positions: shape {p.shape}, expected (N, 3)")
    if i.ndim != 2 or i.shape[1] != 3:
        raise ValueError(f"indices: shape {i.shape}, expected (T, 3)")
    if i.size and (i.min() < 0 or i.max() > 0xFFFFFFFF):
        raise ValueError("indices: outside uint32")
    out = pb.Mesh(positions=p.astype("<f4").tobytes(), indices=i.astype("<u4").tobytes())
    if normals is not None:
        n = np.asarray(normals, dtype=np.float64)
        if n.shape != p.shape:
            raise ValueError(f"normals: shape {n.shape}, expected {p.shape}")
        out.normals = n.astype("<f4").tobytes()
    return out
