"""The array backend the law is written against: batched torch (GPU, many envs, actuation stages,
the sysid replay) or float64 numpy (the nominal law on CPU for a few envs, where numpy's per-op
overhead is ~5x below eager torch's on these tiny arrays).

A backend is the few array operations whose spelling differs between the two libraries, plus the
robot's model behind one interface: ``kin(q)`` (per-link kinematics, opaque), then ``jacobian``,
``mass`` and ``bias`` (C(q, qd) qd [+ g(q)]) of it. Everything else (``@``, slicing, ``+``,
``.reshape``, ``.any``) is spelled alike in both and used directly.
"""

from __future__ import annotations

import numpy as np
import torch

from realm_ms.agents.arm_model import ArmModel, NumpyArmModel


class TorchBackend:
    name = "torch"
    cat, inv, matrix_power = staticmethod(torch.cat), staticmethod(torch.linalg.inv), staticmethod(torch.linalg.matrix_power)
    abs, tanh, where, diag = staticmethod(torch.abs), staticmethod(torch.tanh), staticmethod(torch.where), staticmethod(torch.diag_embed)

    def __init__(self, model: ArmModel):
        self.model = model

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

    # the robot's model: kin = (q, link frames)
    def kin(self, q):
        return q, self.model.link_frames(q)

    @staticmethod
    def take(kin, m: int):
        return kin[0][:m], kin[1][:m]

    def jacobian(self, kin):
        return self.model.jacobian(*kin)

    def mass(self, kin):
        return self.model.mass_matrix(*kin)

    def bias(self, kin, qd, gravity: bool = True):
        return self.model.rnea(kin[0], qd, gravity=gravity, frames=kin[1])


class NumpyBackend:
    name = "numpy"
    cat, inv, matrix_power = staticmethod(np.concatenate), staticmethod(np.linalg.inv), staticmethod(np.linalg.matrix_power)
    abs, tanh, where = staticmethod(np.abs), staticmethod(np.tanh), staticmethod(np.where)
    at_most = staticmethod(np.minimum)

    def __init__(self, model: ArmModel):
        self.model = NumpyArmModel(model)

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

    # the robot's model: kin = (link frames, per-link world quantities shared by mass and bias)
    def kin(self, q):
        frames = self.model.link_frames(q)
        return frames, self.model.world(frames)

    @staticmethod
    def take(kin, m: int):
        return kin[0][:m], tuple(w[:m] for w in kin[1])

    def jacobian(self, kin):
        return self.model.jacobian(kin[0])

    def mass(self, kin):
        return self.model.mass(kin[1])

    def bias(self, kin, qd, gravity: bool = True):
        return self.model.bias(kin[1], qd, gravity)
