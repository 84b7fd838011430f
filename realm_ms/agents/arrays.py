"""The two array namespaces the robot's model (``arm_model.py``) and the control law
(``control/law.py``) are written against: batched torch (GPU, many envs, actuation stages, the sysid
replay) or float64 numpy (the nominal law on CPU for a few envs, where numpy's per-op overhead is
~5x below eager torch's on these tiny arrays).

A namespace holds only the operations whose spelling differs between the two libraries; everything
else (``@``, slicing, ``+``, ``.reshape``, ``.sum``, ``.cumsum``, ``.any``) is spelled alike and used
directly. ``like`` arguments give the device and dtype of a new array (numpy: float64 on the CPU).
"""

from __future__ import annotations

import numpy as np
import torch

_P1, _P2 = np.array([1, 2, 0]), np.array([2, 0, 1])


class TorchOps:
    name = "torch"
    cat, stack, sin, cos = staticmethod(torch.cat), staticmethod(torch.stack), staticmethod(torch.sin), staticmethod(torch.cos)
    inv, matrix_power = staticmethod(torch.linalg.inv), staticmethod(torch.linalg.matrix_power)
    abs, tanh, where, diag = staticmethod(torch.abs), staticmethod(torch.tanh), staticmethod(torch.where), staticmethod(torch.diag_embed)

    @staticmethod
    def cross(a, b):
        return torch.linalg.cross(a, b, dim=-1)

    @staticmethod
    def suffix_sum(x):
        """Sum over i..n-1 along axis 1: what link i carries of the links after it."""
        return torch.flip(torch.cumsum(torch.flip(x, [1]), 1), [1])

    @staticmethod
    def solve(a, b):
        return torch.linalg.solve(a, b[..., None])[..., 0]

    @staticmethod
    def eye(n: int, like):
        return torch.eye(n, device=like.device, dtype=like.dtype)

    @staticmethod
    def zeros(shape, like):
        return torch.zeros(shape, device=like.device, dtype=like.dtype)

    @staticmethod
    def steps(b: int, like):  # per-row step counters
        return torch.zeros(b, dtype=torch.long, device=like.device)

    @staticmethod
    def arange(b: int, like):
        return torch.arange(b, device=like.device)

    @staticmethod
    def swap(x):
        return x.transpose(-1, -2)

    @staticmethod
    def repeat(x, k: int):
        return x.repeat_interleave(k, 0)

    @staticmethod
    def clip(x, lo, hi):
        return torch.maximum(torch.minimum(x, hi), lo)

    @staticmethod
    def at_most(x, c: int):
        return x.clamp(max=c)

    @staticmethod
    def rows(mask):
        return torch.nonzero(mask)[:, 0]

    @staticmethod
    def copy(x):
        return x.clone()


class NumpyOps:
    name = "numpy"
    cat, stack, sin, cos = staticmethod(np.concatenate), staticmethod(np.stack), staticmethod(np.sin), staticmethod(np.cos)
    inv, matrix_power = staticmethod(np.linalg.inv), staticmethod(np.linalg.matrix_power)
    abs, tanh, where = staticmethod(np.abs), staticmethod(np.tanh), staticmethod(np.where)
    at_most = staticmethod(np.minimum)

    @staticmethod
    def cross(a, b):
        """a x b over the last axis, as permuted products (7 array ops; ~3x faster than np.cross and
        than a Levi-Civita einsum on the (B*steps, 7, 3) arrays of a batched plan)."""
        return a[..., _P1] * b[..., _P2] - a[..., _P2] * b[..., _P1]

    @staticmethod
    def suffix_sum(x):
        return x[:, ::-1].cumsum(1)[:, ::-1]

    @staticmethod
    def solve(a, b):
        return np.linalg.solve(a, b[..., None])[..., 0]

    @staticmethod
    def eye(n: int, like):
        return np.eye(n)

    @staticmethod
    def zeros(shape, like):
        return np.zeros(shape)

    @staticmethod
    def steps(b: int, like):
        return np.zeros(b, dtype=np.int64)

    @staticmethod
    def arange(b: int, like):
        return np.arange(b)

    @staticmethod
    def diag(v):
        return v[..., :, None] * np.eye(v.shape[-1])

    @staticmethod
    def clip(x, lo, hi):  # np.clip costs ~3x more on these tiny arrays
        return np.maximum(np.minimum(x, hi), lo)

    @staticmethod
    def swap(x):
        return x.swapaxes(-1, -2)

    @staticmethod
    def repeat(x, k: int):
        return np.repeat(x, k, 0)

    @staticmethod
    def rows(mask):
        return np.nonzero(mask)[0]

    @staticmethod
    def copy(x):
        return x.copy()
