"""``RealmEnvConfig``: the one typed description of a REALM env.

``gym.make("REALM-PickApple-v1", camera_width=640, shader="rt", perturbation="V-LIGHT")`` maps its
keyword arguments onto this config (``KWARG_FIELDS``: keyword -> field; an unknown keyword is an
error naming the nearest known one); ``gym.make(ID, config=RealmEnvConfig(...))`` passes one
whole. The env keeps the resolved config as ``env.unwrapped.config``; ``to_dict()`` is plain JSON
(records store it) and ``make_env(RealmEnvConfig.from_dict(d))`` re-creates the same env.
Evaluation, export and the LeRobot plugin build a cell's config once, typed (``eval.runner.cell_config``),
and hand it to ``make_env``, which passes the object itself to the env.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from realm_ms.agents.control import DroidControlConfig, ImpedanceGains, JointPhysics
from realm_ms.jsonable import jsonable
from realm_ms.rendering import CameraSettings
from realm_ms.tasks.progression import Thresholds

PerturbationSpec = str | int | tuple | None


@dataclass(frozen=True)
class RealmEnvConfig:
    """Everything that defines a REALM env, beyond the task's own declaration (``TaskSpec``).

    ``task``, ``obs_mode``, ``control_mode``, ``num_envs``, ``sim_backend``, ``render_mode`` and
    ``horizon`` are only used by :func:`make_env` (``gym.make`` takes them itself).
    """

    task: str | None = None  # env id, e.g. "REALM-PickApple-v1"
    cameras: CameraSettings = field(default_factory=CameraSettings)
    control: DroidControlConfig | None = None  # Polymetis law settings; None = defaults (or a robot model's)
    robot_model: str | dict | None = None  # MODEL.yaml path or its dict, from `realm sysid fit`
    scene: str | None = None  # None = the task's scene
    perturbation: PerturbationSpec = None  # REALM name / id / list (realm_ms.perturbations); None = Default
    horizon: int | None = None  # control steps; None = the task's (REALM: 800)
    settle_steps: int = 5  # control steps before the object reference is captured (REALM's warm-up)
    success_tail: int = 15  # steps after success before ``terminated``
    thresholds: Thresholds = field(default_factory=Thresholds)
    # Rebuild the PhysX scene at each reset after simulated steps (CPU backend), so an episode
    # depends only on its seed: PhysX keeps contact history across teleports (pair caches, pair
    # order), and a reused scene can drift ~1e-2 rad from a fresh one after a contact-rich
    # episode. Costs one scene build per reset (bench/reset_cost.py); False teleports objects.
    isolate_episodes: bool = True
    # DROID's action spaces (realm_ms.agents.droid_action_spaces), converted to the joint target of
    # droid_joint_pos; None gripper space = DROID's default (velocity for the velocity spaces)
    action_space: str = "joint_position"
    gripper_action_space: str | None = None
    obs_mode: str = "state"
    control_mode: str = "droid_joint_pos"
    num_envs: int = 1
    sim_backend: str = "auto"
    render_mode: str | None = None

    def __post_init__(self) -> None:
        for name in ("settle_steps", "success_tail"):
            _check_int(name, getattr(self, name), minimum=0)
        _check_int("num_envs", self.num_envs, minimum=1)
        if self.horizon is not None:
            _check_int("horizon (max_episode_steps)", self.horizon, minimum=1)
        from realm_ms.agents.droid_action_spaces import check_action_space, check_control_mode

        check_action_space(self.action_space, self.gripper_action_space)
        check_control_mode(self.action_space, self.gripper_action_space, self.control_mode)
        if isinstance(self.perturbation, list):
            object.__setattr__(self, "perturbation", tuple(self.perturbation))
        if isinstance(self.robot_model, Path):
            object.__setattr__(self, "robot_model", str(self.robot_model))

    # ------------------------------------------------------------------ gym.make keywords
    @classmethod
    def from_kwargs(cls, config: "RealmEnvConfig | None", kwargs: dict) -> tuple["RealmEnvConfig", dict]:
        """Fold the env keywords of ``kwargs`` into ``config``; returns it and the rest (ManiSkill's)."""
        cfg = config if config is not None else cls()
        if not isinstance(cfg, cls):
            raise TypeError(f"config must be a RealmEnvConfig, got {type(cfg).__name__}")
        rest = dict(kwargs)
        cams, top = {}, {}
        for key, (where, name) in KWARG_FIELDS.items():
            if key in rest:
                (cams if where == "cameras" else top)[name] = rest.pop(key)
        if "control" in top and isinstance(top["control"], dict):
            top["control"] = DroidControlConfig(**_control_fields(top["control"]))
        if cams:
            top["cameras"] = dataclasses.replace(cfg.cameras, **cams)
        _check_maniskill_kwargs(rest)
        return dataclasses.replace(cfg, **top), rest

    def with_kwargs(self, kwargs: dict) -> tuple["RealmEnvConfig", dict]:
        """This config with the ``gym.make`` keywords of ``kwargs`` folded in, ManiSkill's own fields
        and the horizon (``max_episode_steps``) included; returns it and the keywords it has no field
        for (ManiSkill's others, e.g. ``sim_config``), to pass on to :func:`make_env`."""
        kwargs = dict(kwargs)
        horizon = kwargs.pop("max_episode_steps", None)
        cfg, rest = self.from_kwargs(self, kwargs)
        top = {name: rest.pop(name) for name in _GYM_FIELDS if name in rest}
        if horizon is not None:
            top["horizon"] = horizon
        return dataclasses.replace(cfg, **top), rest

    # ------------------------------------------------------------------ serialisation
    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["perturbation"] = list(self.perturbation) if isinstance(self.perturbation, tuple) else self.perturbation
        return jsonable(d)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "RealmEnvConfig":
        d = dict(d)
        unknown = set(d) - {f.name for f in dataclasses.fields(cls)}
        if unknown:
            raise ValueError(f"unknown RealmEnvConfig fields {sorted(unknown)}")
        if isinstance(d.get("cameras"), dict):
            d["cameras"] = CameraSettings(**d["cameras"])
        if isinstance(d.get("control"), dict):
            d["control"] = DroidControlConfig(**_control_fields(d["control"]))
        if isinstance(d.get("thresholds"), dict):
            d["thresholds"] = Thresholds(**{k: tuple(v) if isinstance(v, list) else v for k, v in d["thresholds"].items()})
        return cls(**d)

    def gym_kwargs(self) -> dict[str, Any]:
        """``gym.make`` keyword arguments that build this env."""
        if not self.task:
            raise ValueError("RealmEnvConfig.task is not set: name the env id, e.g. 'REALM-PickApple-v1'")
        kw: dict[str, Any] = dict(
            config=dataclasses.replace(self, task=None, horizon=None, obs_mode="state", control_mode="droid_joint_pos",
                                      num_envs=1, sim_backend="auto", render_mode=None),
            obs_mode=self.obs_mode, control_mode=self.control_mode, num_envs=self.num_envs,
            sim_backend=self.sim_backend, render_mode=self.render_mode,
        )
        if self.horizon is not None:
            kw["max_episode_steps"] = self.horizon
        return kw


# gym.make keyword -> (config part, field); an unknown keyword is an error naming the nearest known one
KWARG_FIELDS: dict[str, tuple[str, str]] = {
    "camera_width": ("cameras", "width"),
    "camera_height": ("cameras", "height"),
    "shader": ("cameras", "shader"),
    "denoiser": ("cameras", "denoiser"),
    "cameras": ("top", "cameras"),
    "droid_control": ("top", "control"),
    "robot_model": ("top", "robot_model"),
    "scene": ("top", "scene"),
    "perturbation": ("top", "perturbation"),
    "settle_steps": ("top", "settle_steps"),
    "success_tail": ("top", "success_tail"),
    "thresholds": ("top", "thresholds"),
    "isolate_episodes": ("top", "isolate_episodes"),
    "action_space": ("top", "action_space"),
    "gripper_action_space": ("top", "gripper_action_space"),
}


# ManiSkill / gymnasium keywords that are fields of the config (gym.make takes them itself)
_GYM_FIELDS = ("obs_mode", "control_mode", "num_envs", "sim_backend", "render_mode")


def make_env(config: RealmEnvConfig, **overrides):
    """``gym.make`` the env that ``config`` describes (``overrides``: more ``gym.make`` keywords)."""
    import gymnasium as gym

    import realm_ms

    realm_ms.register_envs()
    return gym.make(config.task, **(config.gym_kwargs() | overrides))


def _check_maniskill_kwargs(rest: dict) -> None:
    """The keywords left for ManiSkill must be ones it takes: an unknown one is an error listing the
    known keywords (not ``BaseEnv.__init__() got an unexpected keyword argument``), and
    ``num_envs`` is a whole number >= 1 (0 fails deep inside ManiSkill with an IndexError)."""
    import difflib
    import inspect

    from mani_skill.envs.sapien_env import BaseEnv

    maniskill = [n for n in inspect.signature(BaseEnv.__init__).parameters if n != "self"]
    unknown = sorted(k for k in rest if k not in maniskill)
    if unknown:
        known = sorted(KWARG_FIELDS) + ["config"]
        near = difflib.get_close_matches(unknown[0], known + maniskill, n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise ValueError(f"unknown gym.make keyword(s) {', '.join(map(repr, unknown))}{hint}; REALM keywords: "
                         f"{', '.join(known)}; ManiSkill keywords: {', '.join(maniskill)}")
    if "num_envs" in rest:
        _check_int("num_envs", rest["num_envs"], minimum=1)


def _check_int(name: str, v: Any, minimum: int) -> None:
    if isinstance(v, bool) or not isinstance(v, int) and not (isinstance(v, float) and math.isfinite(v) and v == int(v)):
        raise ValueError(f"{name} must be a whole number >= {minimum}, got {v!r}")
    if int(v) < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {v!r}")


def _control_fields(d: dict) -> dict:
    d = dict(d)
    unknown = set(d) - {f.name for f in dataclasses.fields(DroidControlConfig)}
    if unknown:
        raise ValueError(f"unknown droid_control fields {sorted(unknown)}; known: "
                         f"{', '.join(f.name for f in dataclasses.fields(DroidControlConfig))}")
    for key, cls in (("gains", ImpedanceGains), ("joint_physics", JointPhysics)):
        if isinstance(d.get(key), dict):  # lists -> tuples; scalars (friction_velocity) as they are
            names = [f.name for f in dataclasses.fields(cls)]
            required = [f.name for f in dataclasses.fields(cls) if f.default is dataclasses.MISSING]
            if set(d[key]) - set(names) or set(required) - set(d[key]):
                optional = [n for n in names if n not in required]
                also = f" (optional: {', '.join(optional)})" if optional else ""
                raise ValueError(f"droid_control.{key}: expected the fields {', '.join(required)}{also}, got {sorted(d[key])}")
            d[key] = cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d[key].items()})
    for k, v in list(d.items()):
        if isinstance(v, list):
            d[k] = tuple(v)
    return d
