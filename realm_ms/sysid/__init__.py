"""System-identification workbench for the DROID Panda.

Compare the benchmark's simulated robot with measurements, see where it fails, rank the missing
physical effect, add it, fit it, and watch the held-out error fall. Verbs (CLI ``realm sysid``
and :mod:`realm_ms.sysid.api`): ``effects``, ``excite``, ``synth``, ``compare``, ``diagnose``, ``fit``,
``auto``, ``report``, ``align``. A fitted ``MODEL.yaml`` loads into the benchmark with
:func:`load_actuation_model`.

The effects themselves (one file each, registry ``EFFECTS``, parameters with units and bounds) and
the ``MODEL.yaml`` format live below this package, in :mod:`realm_ms.agents.effects` and
:mod:`realm_ms.agents.robot_model`, because the benchmark's controller runs them too.

Module map (small modules, one job each)::

    api.py / cli.py    the verbs (Python / ``realm sysid``); the API picks the space once
    space.py           PositionSpace (replay of q_cmd, rad) and SPACES; torque/space.py: TorqueSpace (N·m)
    auto.py            the one diagnose -> fit -> re-diagnose loop over a space; AutoResult
    diagnose.py        ranking in named steps; Diagnosis, Suspect, verdicts
    fit.py             add + fit (CMA-ES), compare; FitResult, CompareResult
    optimize.py        linearised (LM) screening step, CMA-ES loop; GroupScores, LinearStep
    signatures.py      residual features, evidence sentences (SENTENCES, by effect name), noise floor
    effect_spec.py     EFFECT[:param=value,...] specs of --hidden / --add
    timeseries.py      Trajectory, validation, seeded split;  data_io.py: npz + LeRobot v3.0
    droid_formats.py   DROID logs (npz, json, csv, h5, LeRobot) and their commands
    closed_loop.py     DROID commands converted at the simulated state inside a rollout
    interaction.py     grasps, stalls, near-singular IK targets a replay does not score; saturation.py: torque-saturated bursts
    locked_urdf.py     locked-gripper replay URDF;  simulator.py: PhysX CPU batch replay
    gpu.py             physx_cuda batch replay;  engine.py: make_simulator, chunking, worker processes
    replay.py          multiple-shooting segments, sampling at data timestamps, scores
    synth.py / excite.py  data with hidden effects / identification commands
    reference_mujoco.py   independent MuJoCo reference plant; reference_native.py: MuJoCo-native effects
    reference_friction.py friction laws of that plant;  sweep.py: the hidden-effect sweep
    alignment.py       real-DROID alignment (flange error, lag, response per episode and lab)
    torque/            residual.py (inverse-dynamics residual, least squares), terms.py (TERMS: each
                       effect's torque), smoothing.py, spectrum.py, space.py (TorqueSpace)
    report/            HTML report sections (position, torque, auto, alignment)
"""

from __future__ import annotations

__all__ = ["RobotModel", "load_actuation_model", "load_robot_model"]


def __getattr__(name: str):  # lazy: `realm --help` must not import torch
    if name in __all__:
        from realm_ms.agents import robot_model

        return getattr(robot_model, name)
    raise AttributeError(name)
