"""Shared machinery of the S-* perturbations: one of the task's 10 cached instruction variants.

The variants are task data (``realm_ms.tasks.language``), written per task and factor; REALM picks
one uniformly per reset, with no runtime generation. Only the instruction text changes.
"""

from __future__ import annotations

from dataclasses import replace

from realm_ms.tasks.perturbation import Perturbation


def variants(env_id: str, factor: str) -> tuple[str, ...]:
    from realm_ms.tasks.language import instruction_variants

    out = tuple(instruction_variants(env_id, factor))
    if not out:
        raise ValueError(f"no {factor} instruction variants for {env_id}")
    return out


class InstructionVariant(Perturbation):
    """Base of S-PROP, S-LANG, S-MO, S-AFF, S-INT."""

    acts_on = "instruction text"
    ranges = "uniform pick among the task's 10 cached variants"

    def draw(self, rng, ctx):
        vs = variants(ctx.env_id, self.name)
        k = int(rng.integers(len(vs)))
        return dict(index=k, instruction=vs[k])

    def edit_spec(self, spec, params, ctx):
        return replace(spec, instruction=params["instruction"])
