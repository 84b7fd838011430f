"""Link inertial parameters off: per link k (the body moved by joint k), its mass, centre of mass and
rotational inertia differ from the URDF's, kept physically consistent for every value in bounds.

Coordinates (``inertial.py``), per link, relative to the nominal (m0, c0, Σ0 = second moment of
the mass distribution about its CoM):

    m = m0 (1 + s)                     s > -1: positive mass
    c = c0 + (dcx, dcy, dcz)           link frame
    Σ = (1 + s) A Σ0 Aᵀ,  A = lower triangular, diagonal exp(ax, ay, az), shears (shxy, shxz, shyz)
    I_c = tr(Σ) 1 - Σ                  positive definite, triangle inequalities hold

So ``s`` alone scales mass, first moment and inertia together (a denser link: the default free
parameters); ``fit_com`` frees the CoM shift, ``fit_inertia`` the shape of the distribution (10
parameters per link in all, matching the 10 standard parameters). ``link=k`` frees link k only.

Build time: the articulation's link k gets the corrected inertial (``BuildTarget.map_link_inertial``);
the controller keeps the nominal model, and the driver is told the difference (``plant_inertia``,
``plant_load``: the standard-parameter difference through ``inertial.regressor``), so position
space and torque space (``sysid/torque/terms.py``) simulate the same plant. In the replay arm (and
the MuJoCo references) body 7 is panda_link7 with the flange and gripper lumped into it; in a
benchmark articulation with a separate gripper, body 7's correction applies to panda_link7 alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from realm_ms.agents.effects import inertial
from realm_ms.agents.effects.effect import Effect, EffectConfig
from realm_ms.agents.effects.parameter import NUM_JOINTS, ParamSpec
from realm_ms.errors import InputError

COM_KEYS = ("dcx", "dcy", "dcz")
STRETCH_KEYS = ("ax", "ay", "az")
SHEAR_KEYS = ("shxy", "shxz", "shyz")


@dataclass
class LinkMassConfig(EffectConfig):
    fit_com: bool = False  # fit the CoM shift (dcx/dcy/dcz) of the free links
    fit_inertia: bool = False  # fit the shape of the mass distribution (ax..az, shxy..shyz)
    link: int = 0  # free links: 0 = all, k = link k only (1-based, link k moves with joint k)


def corrected(m0: torch.Tensor, c0: torch.Tensor, i0: torch.Tensor, v: torch.Tensor):
    """(mass, com, inertia about the CoM) from the nominal ones and the 10 coordinates ``v`` (..., 10)
    in the order s, dcx, dcy, dcz, ax, ay, az, shxy, shxz, shyz."""
    scale = 1.0 + v[..., 0]
    a = inertial.shape_matrix(v[..., 4:7], v[..., 7:10])
    sigma = scale[..., None, None] * (a @ inertial.second_moment(i0) @ a.transpose(-1, -2))
    return m0 * scale, c0 + v[..., 1:4], inertial.inertia_of(sigma)


class LinkMass(Effect):
    name = "link_mass"
    step_cost = (13.8, 0.14)
    summary = "link inertial parameters off"
    signature = ("configuration- and acceleration-dependent residual on the joints proximal to link k "
                 "(gravity load of links above, inertia of the link itself)")
    order = 12
    build_time = True
    screened = False  # 7+ simulated parameters; position-space diagnosis screens it only on request
    Config = LinkMassConfig

    @classmethod
    def param_specs(cls, config):
        if config.link != int(config.link) or not 0 <= config.link <= NUM_JOINTS:
            raise InputError(f"link_mass: link must be 0 (all links) or a link number 1..{NUM_JOINTS}, got {config.link}")
        links = tuple(range(NUM_JOINTS)) if config.link == 0 else (int(config.link) - 1,)
        spec = lambda name, unit, nom, lo, hi, doc, fit=True: ParamSpec(  # noqa: E731
            name, unit, nom, lo, hi, 0.0, doc=doc, fit_by_default=fit, joints=links)
        return ([spec("s", "1", 0.2, -0.9, 2.0, "relative change of link k's mass (first moment and inertia scale with it)")]
                + [spec(k, "m", 0.02, -0.1, 0.1, f"shift of link k's centre of mass along its {k[-1]} axis", config.fit_com)
                   for k in COM_KEYS]
                + [spec(k, "1", 0.2, -0.7, 0.7, f"log-stretch of link k's mass distribution along its {k[-1]} axis",
                        config.fit_inertia) for k in STRETCH_KEYS]
                + [spec(k, "1", 0.2, -0.5, 0.5, f"shear {k[2:]} of link k's mass distribution (Cholesky factor)",
                        config.fit_inertia) for k in SHEAR_KEYS])

    def coords(self, row: int | None = None) -> torch.Tensor:
        """(B, 7 links, 10) coordinates (row ``row`` only: (1, 7, 10))."""
        th = self.theta if row is None else self.theta[row : row + 1]
        names = ("s",) + COM_KEYS + STRETCH_KEYS + SHEAR_KEYS
        return torch.stack([th[:, self._slices[k]] for k in names], -1)

    def changed_links(self, coords: torch.Tensor) -> list[int]:
        return [k for k in range(NUM_JOINTS) if bool((coords[:, k] != 0).any())]

    def delta_pi(self, model, like: torch.Tensor) -> dict[int, torch.Tensor]:
        """Body -> (B, 10) standard-parameter change (body frame) of the links that differ."""
        v = self.coords().to(device=like.device, dtype=like.dtype)
        out = {}
        for k in self.changed_links(v):
            m0, c0, i0 = model.masses[k].to(like.dtype), model.coms[k].to(like.dtype), model.inertias[k].to(like.dtype)
            m, c, i = corrected(m0, c0, i0, v[:, k])
            out[k] = inertial.standard(m, c, i) - inertial.standard(m0, c0, i0)
        return out

    def plant_inertia(self, state):
        parts = [inertial.body_mass_matrix(state.model, state.q, k, d) for k, d in self.delta_pi(state.model, state.q).items()]
        return sum(parts[1:], parts[0]) if parts else None

    def plant_load(self, state):
        """The changed links' extra gravity and Coriolis/centrifugal torque, which physics applies
        and the controller's nominal feed-forward does not cancel."""
        q, qd = state.q, state.qd
        parts = [-(inertial.regressor(state.model, q, qd, None, k) @ d.expand(q.shape[0], -1)[..., None])[..., 0]
                 for k, d in self.delta_pi(state.model, q).items()]
        return sum(parts[1:], parts[0]) if parts else None

    def build_target(self, target, row):
        v = self.coords(row).to(torch.float64)
        for k in self.changed_links(v):
            vk = v[0, k]

            def fn(m0, c0, i0, vk=vk):
                t = lambda x: torch.as_tensor(np.asarray(x, dtype=float), dtype=torch.float64)  # noqa: E731
                m, c, i = corrected(t(m0), t(c0), t(i0), vk)
                return float(m), c.numpy(), i.numpy()

            target.map_link_inertial(k, fn)
