"""The DROID arm controller: Polymetis ``HybridJointImpedanceControl`` computed every physics step.

    tau = (Kq + J^T Kx J)(q* - q) - (Kqd + J^T Kxd J) qd + C(q, qd) qd + g(q)

with J the flange Jacobian, C and g from the robot's own model (``ArmModel``; libfranka compensates
gravity on the real robot, so the simulated arm keeps gravity and the controller cancels it with
its model), and the torque clipped to the Franka limits (87 / 12 N.m).

- ``presets.py``: gain and joint-physics presets; ``config.py``: ``DroidControlConfig``.
- ``law.py``: the law, written once against an array backend (``backend.py``: the torch or numpy
  namespace of ``agents/arrays.py`` and the robot's model, itself one code on both).
- ``rates.py``: where the model terms are taken (``model_rate``: along the predicted path, every
  physics step, once per target); ``integrators.py``: how the law is integrated over a 120 Hz
  physics step (``integrator``: step-exact, implicit drive damping, explicit); ``folded.py``: the
  nominal exact step as one affine map (numpy, CPU, few envs).
- ``driver.py``: ``DroidArmDriver``, the backend-free core; ``maniskill.py``: its ManiSkill binding
  (physx_cpu and physx_cuda) and the PhysX joint setup the sysid replay shares.
"""

from realm_ms.agents.control.config import INTEGRATORS, MODEL_RATES, DroidControlConfig
from realm_ms.agents.control.driver import DroidArmDriver
from realm_ms.agents.control.presets import (
    FRANKA_EFFORT_LIMITS,
    GAIN_PRESETS,
    JOINT_PHYSICS_PRESETS,
    BatchedGains,
    ImpedanceGains,
    JointPhysics,
    resolve,
)

__all__ = ["BatchedGains", "DroidArmDriver", "DroidControlConfig", "FRANKA_EFFORT_LIMITS", "GAIN_PRESETS", "INTEGRATORS",
           "ImpedanceGains", "JOINT_PHYSICS_PRESETS", "JointPhysics", "MODEL_RATES", "resolve"]
