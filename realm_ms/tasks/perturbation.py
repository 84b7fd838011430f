"""The perturbation interface: one class per REALM factor, five small hooks, all batched per sub-env.

A perturbation never mutates anything it was not handed: every episode starts from the pristine
``TaskSpec`` (and the pristine masses / light colours recorded at load), so nothing compounds
across resets. The hooks, in the order the env calls them on ``reset``:

``draw(rng, ctx) -> params``
    One sub-env's parameters (a JSON-able dict) from that sub-env's perturbation RNG. Called once
    per sub-env per reset; ``ctx.spec`` is the task as earlier perturbations of a composition left
    it. The params are recorded in ``info["perturbation"]`` and are enough to re-create the episode.
``edit_spec(spec, params, ctx) -> TaskSpec``
    Pure: returns the sub-env's task (objects, instruction, skill). Perturbations with
    ``reconfigure = True`` may change objects (what exists in the scene); the env rebuilds the
    scene through ManiSkill reconfiguration. Others may only change instruction text.
``on_episode_init(env, env_idx, params)``
    After objects are placed (masses, poses, light colours), ``params`` holds one dict per reset
    sub-env; may add drawn values that depend on the placement (e.g. VB-POSE's final pose).
``on_observation(env, sensor_data, params)``
    Camera images after rendering (V-AUG); ``params`` holds one dict per sub-env.
``camera_pose(uid, pose, params)``
    External camera extrinsics at reconfiguration (V-VIEW); ``pose`` is batched over sub-envs.

The interface and its registry live in the tasks layer, which runs them; the perturbations
themselves (``realm_ms.perturbations``, one module each) register into ``PERTURBATIONS`` when that
package is imported, as ManiSkill's envs register on import. Making an env through gymnasium or
``make_env`` imports it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from realm_ms.task_index import DEFAULT  # noqa: F401  (re-exported beside the registry)
from realm_ms.registry import Registry
from realm_ms.tasks.task_spec import TaskSpec


@dataclass
class DrawContext:
    """What a draw may read: the task as the composition left it so far, and the env's facts."""

    spec: TaskSpec  # current (possibly already edited) spec of this sub-env
    pristine: TaskSpec  # the registered task, never edited
    env_id: str
    camera_uids: tuple[str, ...] = ()
    extra: dict = field(default_factory=dict)


class Perturbation:
    """Base class; subclasses set the class attributes and override the hooks they need."""

    pid: ClassVar[int]
    name: ClassVar[str]
    reconfigure: ClassVar[bool] = False  # changes what exists in the scene -> ManiSkill reconfiguration
    acts_on: ClassVar[str] = ""  # what it changes, for `realm perturbations list`
    ranges: ClassVar[str] = ""  # the drawn parameters and their ranges

    def draw(self, rng: np.random.Generator, ctx: DrawContext) -> dict[str, Any]:
        return {}

    def edit_spec(self, spec: TaskSpec, params: dict, ctx: DrawContext) -> TaskSpec:
        return spec

    def on_episode_init(self, env, env_idx, params: list[dict]) -> None:
        pass

    def on_observation(self, env, sensor_data: dict, params: list[dict]) -> dict:
        return sensor_data

    def camera_pose(self, uid: str, pose, params: list[dict]):
        return pose

    def describe(self) -> dict:
        return dict(id=self.pid, name=self.name, reconfigure=self.reconfigure, when=self.when, acts_on=self.acts_on, ranges=self.ranges)

    @property
    def when(self) -> str:
        """Where it acts: ``reconfigure`` (scene rebuilt), ``observation`` or ``episode`` (init)."""
        if self.reconfigure:
            return "reconfigure"
        return "observation" if type(self).on_observation is not Perturbation.on_observation else "episode"

    def __repr__(self) -> str:
        return f"<perturbation {self.pid} {self.name}>"


#: every perturbation class by name, with its numeric id as an alias (filled by realm_ms.perturbations)
PERTURBATIONS: Registry[type[Perturbation]] = Registry("perturbation")


def register_perturbation(cls: type[Perturbation]) -> type[Perturbation]:
    """Class decorator: register ``cls`` under its ``name`` and its ``pid``."""
    PERTURBATIONS.register(cls.name, cls, aliases=(str(cls.pid),))
    return cls


def as_float(x) -> float:
    """Plain Python float for JSON-able params."""
    return float(np.asarray(x).item())
