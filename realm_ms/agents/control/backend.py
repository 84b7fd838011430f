"""The array backend the law is written against: an array namespace (``agents/arrays.py``: batched
torch, or float64 numpy for the nominal law on CPU with a few envs) plus the robot's model behind
one interface: ``kin(q)`` (per-link kinematics, opaque; ``take`` slices its first rows), then
``jacobian``, ``mass`` and ``bias`` (C(q, qd) qd [+ g(q)]) of it. The model is one implementation
on either namespace (``ArmModel``), so the two backends differ only in their namespace.
"""

from __future__ import annotations

from realm_ms.agents.arm_model import ArmModel, Links
from realm_ms.agents.arrays import NumpyOps, TorchOps


class _ModelTerms:
    """The robot's model terms at a ``kin`` (the per-link world quantities all three share)."""

    def __init__(self, model: ArmModel):
        self.model = model

    def kin(self, q) -> Links:
        return self.model.links(self.model.link_frames(q))

    @staticmethod
    def take(kin: Links, m: int) -> Links:
        return Links(*(x[:m] for x in kin))

    def jacobian(self, kin: Links):
        return self.model.jacobian_at(kin)

    def mass(self, kin: Links):
        return self.model.mass_at(kin)

    def bias(self, kin: Links, qd, gravity: bool = True):
        return self.model.bias_at(kin, qd, gravity)


class TorchBackend(TorchOps, _ModelTerms):
    pass


class NumpyBackend(NumpyOps, _ModelTerms):
    def __init__(self, model: ArmModel):
        super().__init__(model.numpy())
