"""Evaluation protocols (presets) and the episode plan: which (task, perturbation, seed) keys to run.

``realm``: every task x every perturbation x 25 episodes x 800 control steps, seed 1234 (REALM
paper), early stop 15 steps after success, actions re-planned every 8 steps. Each episode has its
own seed (``seed + i``, REALM's single RNG stream for all repeats is pitfall 17), and the same seeds
are used under every perturbation so each perturbation is paired with Default.
``quick``: a smoke run (a few tasks, Default + a few perturbations when available, 2 episodes,
120 steps). Any field can be overridden from the command line.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from realm_ms.task_index import DEFAULT  # noqa: F401  (re-exported for eval's modules)


@dataclass(frozen=True)
class Protocol:
    name: str
    tasks: tuple[str, ...] | None = None  # None: every registered task
    perturbations: tuple[str, ...] | None = None  # None: every available perturbation
    episodes: int = 25
    max_steps: int = 800
    seed: int = 1234
    replan_every: int = 8
    success_tail: int = 15

    def with_overrides(self, **kw) -> "Protocol":
        return replace(self, **{k: v for k, v in kw.items() if v is not None})


PRESETS: dict[str, Protocol] = {
    "realm": Protocol("realm"),
    "quick": Protocol(
        "quick",
        tasks=("REALM-PickApple-v1", "REALM-PushSwitch-v1", "REALM-PutGreenBlockInBowl-v1"),
        perturbations=(DEFAULT, "V-AUG", "S-LANG", "VB-POSE"),
        episodes=2,
        max_steps=120,
    ),
}


@dataclass(frozen=True, order=True)
class EpisodeKey:
    """One episode of the plan; records are keyed (and resumed) by it."""

    task: str
    perturbation: str
    seed: int

    def id(self) -> str:
        return f"{self.task}|{self.perturbation}|{self.seed}"

    def cell(self) -> tuple[str, str]:
        return self.task, self.perturbation


def available_perturbations() -> list[str]:
    """Registered perturbation names (Default first)."""
    from realm_ms.perturbations import PERTURBATIONS

    return [DEFAULT] + [n for n in PERTURBATIONS.names() if n != DEFAULT]


def canonical_perturbation(name: str) -> str:
    """Registered spelling of a perturbation name or alias (a numeric id; any case: "default" and "0"
    are ``DEFAULT``); raises ``ValueError`` (``UnknownNameError``, listing the known names)."""
    from realm_ms.perturbations import PERTURBATIONS

    return PERTURBATIONS.canonical(name)


def factor_groups(perturbation: str) -> tuple[str, ...]:
    """REALM factor groups of a perturbation from its prefix: 'VB-POSE' -> ('V', 'B'); Default -> ()."""
    if perturbation == DEFAULT or "-" not in perturbation:
        return ()
    return tuple(g for g in "VSB" if g in perturbation.split("-", 1)[0])


def plan(tasks: list[str], perturbations: list[str], episodes: int, seed: int) -> list[EpisodeKey]:
    """Task-major, then perturbation, then seed: consecutive keys share an env (workers reuse it)."""
    return [EpisodeKey(t, p, seed + i) for t in tasks for p in perturbations for i in range(episodes)]
