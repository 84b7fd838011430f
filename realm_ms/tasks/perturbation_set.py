"""``PerturbationSet``: the perturbation(s) an env runs, their per-sub-env draws and the record.

The env holds one set (``env.perturbations``) and calls it from small hooks in ``RealmEnv``. Every
reset draws afresh for each reset sub-env from its own stream, seeded by the episode seed and the
perturbation id (independent of the placement RNG, so a perturbation leaves the layout of the
unperturbed task untouched), and always starting from the pristine ``TaskSpec``.
"""

from __future__ import annotations

import copy
import importlib
from collections.abc import Sequence

import numpy as np

from realm_ms.task_index import PERTURBATION_PACKAGE
from realm_ms.tasks.perturbation import DEFAULT, PERTURBATIONS, DrawContext, Perturbation
from realm_ms.tasks.task_spec import TaskSpec

PerturbationLike = str | int | Perturbation | Sequence


class PerturbationSet:
    """An ordered composition of perturbations (``Default`` = the empty composition)."""

    def __init__(self, perturbations: Sequence[Perturbation] = ()):
        self.items: list[Perturbation] = list(perturbations)
        self.params: list[list[dict]] = []  # per sub-env, per item
        self.specs: list[TaskSpec] = []  # per sub-env effective task
        self.seeds: list[int] = []
        self.override: list[dict] | None = None  # replay: params per sub-env keyed by name

    # ------------------------------------------------------------------ construction
    @classmethod
    def resolve(cls, spec: PerturbationLike | None) -> "PerturbationSet":
        """``None``/``"Default"``/``0``, a name, an id, a ``Perturbation`` or a list of those."""
        if isinstance(spec, PerturbationSet):
            return cls(spec.items)
        if spec is None or (isinstance(spec, (str, int)) and str(spec).lower() in (DEFAULT.lower(), "0")):
            return cls()  # the empty composition
        if isinstance(spec, (str, int, Perturbation)) or not isinstance(spec, Sequence):
            spec = [spec]
        items: list[Perturbation] = []
        for s in spec:
            if isinstance(s, str) and "+" in s:  # "V-LIGHT+VB-POSE"
                items.extend(cls.resolve(s.split("+")).items)
                continue
            p = s if isinstance(s, Perturbation) else _perturbation_class(s)()
            if p.pid != 0 and all(q.name != p.name for q in items):
                items.append(p)
        return cls(items)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.items] or [DEFAULT]

    @property
    def name(self) -> str:
        return "+".join(self.names)

    @property
    def needs_reconfigure(self) -> bool:
        return any(p.reconfigure for p in self.items)

    def __contains__(self, name: str) -> bool:
        return name in [p.name for p in self.items]

    # ------------------------------------------------------------------ drawing
    def rng(self, episode_seed: int, p: Perturbation, batch: bool = False) -> np.random.Generator:
        """The sub-env's stream for ``p`` (``batch``: one stream shared by all sub-envs, for choices
        a batch must agree on, e.g. SB-VRB's verb)."""
        return np.random.default_rng([int(episode_seed) % 2**63, 0xBA7C if batch else 0x5EA1, int(p.pid)])

    def draw(self, env, env_idx, scene_changing_only: bool = False) -> None:
        """Draw params for the sub-envs ``env_idx`` and compute their effective task specs.

        At reconfiguration every sub-env is drawn; a plain reset redraws the reset sub-envs. With
        ``scene_changing_only`` (a reset that does not rebuild) the scene-changing params of the
        last build are kept: they describe what exists in the scene."""
        pristine = env.task_spec
        n = env.num_envs
        if len(self.params) != n:
            self.params = [[{} for _ in self.items] for _ in range(n)]
            self.specs = [pristine] * n
            self.seeds = [0] * n
        for i in [int(i) for i in env_idx]:
            seed = int(env._episode_seed[i]) if env._episode_seed is not None else 0
            self.seeds[i] = seed
            spec = pristine
            for k, p in enumerate(self.items):
                batch_rng = self.rng(int(env._episode_seed[0]) if env._episode_seed is not None else 0, p, batch=True)
                ctx = DrawContext(spec=spec, pristine=pristine, env_id=pristine.env_id, camera_uids=tuple(c.uid for c in pristine.cameras),
                                  extra=dict(batch_rng=batch_rng))
                keep = scene_changing_only and p.reconfigure
                if self.override is not None:
                    params = copy.deepcopy(self.override[i][p.name])
                elif keep:
                    params = self.params[i][k]
                else:
                    params = p.draw(self.rng(seed, p), ctx)
                self.params[i][k] = params
                spec = p.edit_spec(spec, params, ctx)
            self.specs[i] = spec

    def per_item(self, k: int, env_idx=None) -> list[dict]:
        idx = range(len(self.params)) if env_idx is None else [int(i) for i in env_idx]
        return [self.params[i][k] for i in idx]

    # ------------------------------------------------------------------ hooks
    def on_episode_init(self, env, env_idx) -> None:
        for k, p in enumerate(self.items):
            p.on_episode_init(env, env_idx, self.per_item(k, env_idx))

    def on_observation(self, env, sensor_data: dict) -> dict:
        for k, p in enumerate(self.items):
            sensor_data = p.on_observation(env, sensor_data, self.per_item(k))
        return sensor_data

    def camera_pose(self, uid: str, pose):
        for k, p in enumerate(self.items):
            pose = p.camera_pose(uid, pose, self.per_item(k))
        return pose

    # ------------------------------------------------------------------ record
    def record(self) -> dict:
        """``info["perturbation"]``: names, ids, episode seeds and every drawn parameter per sub-env
        (``params[i][name]``); ``reset(options={"perturbation_params": rec["params"]})`` replays it."""
        return dict(
            name=self.name,
            names=self.names,
            ids=[p.pid for p in self.items] or [0],
            episode_seed=list(self.seeds),
            instruction=[s.instruction for s in self.specs],
            skill=[s.skill for s in self.specs],
            params=[{p.name: copy.deepcopy(self.params[i][k]) for k, p in enumerate(self.items)} for i in range(len(self.params))],
        )


def _perturbation_class(name: str | int) -> type[Perturbation]:
    """The registered class of ``name``; the perturbation package registers them when imported,
    so an env made before anything imported it (a task module imported directly) loads it here."""
    if name not in PERTURBATIONS:
        importlib.import_module(PERTURBATION_PACKAGE)
    return PERTURBATIONS.get(name)
