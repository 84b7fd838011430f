"""10 B-HOBJ: the main object's physical properties, drawn per reset from the pristine values.

REALM (later ``b_hobj.py``, the fixed version): mass = min(base * exp(U(-1, 1)), 2.0 kg) from a
pristine baseline; for articulated objects the joint properties (max velocity, effort, stiffness,
damping, friction) each x an independent exp(U(-1, 1)). Fixed here: the scale is applied once and
clipped once, always from the nominal value recorded at build (REALM's first release compounded).
Inertia is scaled with the mass (same shape, denser material). Our articulated objects are passive
(drawer slides, rocker switch): their joint damping, joint friction and the moving links' masses
(the drawer / rocker, each <= 2 kg) are scaled; stiffness, effort and velocity limits do not act
on a passive joint with zero stiffness, so they are drawn and recorded but change nothing.
"""

from __future__ import annotations

import numpy as np

from realm_ms.tasks.perturbation import Perturbation, as_float

LOG_RANGE = (-1.0, 1.0)
MAX_MASS = 2.0  # kg
JOINT_PROPS = ("mass", "damping", "friction", "stiffness", "max_effort", "max_velocity")


def _set_mass(body, nominal_mass: float, nominal_inertia, mass: float) -> None:
    body.set_mass(mass)
    body.set_inertia(np.asarray(nominal_inertia, float) * (mass / max(nominal_mass, 1e-9)))


class BHobj(Perturbation):
    pid = 10
    name = "B-HOBJ"
    acts_on = "main object mass (rigid) / moving-link masses and joint damping, friction (articulated)"
    ranges = "x exp(U(-1, 1)) each, mass clipped at 2 kg, from the pristine values"

    def draw(self, rng, ctx):
        return {f"{k}_scale": as_float(np.exp(rng.uniform(*LOG_RANGE))) for k in JOINT_PROPS}

    def on_episode_init(self, env, env_idx, params):
        obj = env.main
        if not obj.is_articulated:
            nominal = getattr(obj, "_nominal_bodies", None)
            if nominal is None:  # recorded once per build: the pristine baseline
                nominal = obj._nominal_bodies = [(float(b.mass), np.asarray(b.inertia, float)) for b in obj.entity._bodies]
            for i, p in zip([int(i) for i in env_idx], params):
                k = i if len(nominal) > 1 else 0
                m0, i0 = nominal[k]
                p["mass"] = as_float(min(m0 * p["mass_scale"], MAX_MASS))
                p["nominal_mass"] = m0
                _set_mass(obj.entity._bodies[k], m0, i0, p["mass"])
            return
        art = obj.art
        moving = [link for link in art.links if link.joint is not None and link.joint.active_index is not None]
        joints = art.active_joints
        nominal = getattr(obj, "_nominal_joints", None)
        if nominal is None:
            nominal = obj._nominal_joints = dict(
                links=[[(float(b.mass), np.asarray(b.inertia, float)) for b in link._bodies] for link in moving],
                joints=[[(float(j.damping), float(j.friction)) for j in joint._objs] for joint in joints],
            )
        for i, p in zip([int(i) for i in env_idx], params):
            masses = []
            for link, nom in zip(moving, nominal["links"]):
                m0, i0 = nom[i]
                m = min(m0 * p["mass_scale"], MAX_MASS)
                _set_mass(link._bodies[i], m0, i0, m)
                masses.append(as_float(m))
            for joint, nom in zip(joints, nominal["joints"]):
                d0, f0 = nom[i]
                joint._objs[i].set_drive_properties(0.0, d0 * p["damping_scale"])
                joint._objs[i].friction = f0 * p["friction_scale"]
            p["link_masses"] = masses
            p["nominal_damping"] = [as_float(n[i][0]) for n in nominal["joints"]]
