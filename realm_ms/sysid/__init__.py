"""System-identification workbench for the DROID Panda.

Compare the benchmark's simulated robot with measurements, see where it fails, rank the missing
physical effect, add it, fit it, and watch the held-out error fall. Verbs (CLI ``realm sysid``
and :mod:`realm_ms.sysid.api`): ``effects``, ``excite``, ``synth``, ``compare``, ``diagnose``, ``fit``,
``report``. A fitted ``MODEL.yaml`` loads into the benchmark with :func:`load_actuation_model`.

The effects themselves (one file each, registry ``EFFECTS``, parameters with units and bounds) and
the ``MODEL.yaml`` format live below this package, in :mod:`realm_ms.agents.effects` and
:mod:`realm_ms.agents.robot_model`, because the benchmark's controller runs them too.

Module map (small modules, one job each)::

    effect_spec.py  EFFECT[:param=value,...] specs of --hidden / --add
    timeseries.py   Trajectory, validation, seeded split;  data_io.py: npz + LeRobot v3.0
    locked_urdf.py  locked-gripper replay URDF;  simulator.py: PhysX CPU batch replay
    gpu.py          physx_cuda batch replay;  engine.py: make_simulator, chunking, worker processes
    replay.py       multiple-shooting segments, sampling at data timestamps, scores
    signatures.py   residual features, evidence sentences, noise floor
    optimize.py     linearised (LM) screening step, CMA-ES loop
    diagnose.py     ranking;  fit.py: add + fit, compare;  synth.py / excite.py: data
    report/         HTML report sections;  api.py / cli.py: the verbs
"""

from __future__ import annotations

__all__ = ["RobotModel", "load_actuation_model", "load_robot_model"]


def __getattr__(name: str):  # lazy: `realm --help` must not import torch
    if name in __all__:
        from realm_ms.agents import robot_model

        return getattr(robot_model, name)
    raise AttributeError(name)
