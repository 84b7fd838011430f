"""15 VSB-NOBJ: the main object is replaced by one of an unseen category; the instruction names it.

REALM: any model of the 833 non-DROID categories, scaled down to max extent <= 0.15 m, original
orientation; push: an ``electric_switch`` or ``thermostat`` model; drawers: one of 14 hand-picked
``bottom_cabinet`` models (max extent 0.5 m). The +0.3 m spawn offset REALM applied to all tasks
(meant for its drawer asset) is not copied: objects are placed resting on the table.

Here: rigid tasks draw from the catalog's unseen split (the procedural non-DROID categories when no
catalog is built) until the object is one the skill can act on (graspable; for put at most 0.8 of
the receptacle's width; for stack at most 5 cm so it can rest on the 3 cm block), capped at
0.15 m. Push: another switch model (housing / rocker proportions and colours); drawers: another
cabinet model (per-axis proportions U(0.8, 1.25), colours, max extent <= 0.5 m).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from realm_ms.tasks.perturbation import Perturbation, as_float
from realm_ms.perturbations.common import cap_scale, categories_of, graspable, main_noun, object_spec, replace_noun, sample_ids, set_query, with_object

MAX_EXTENT = 0.15
STACK_MAX = 0.05
CABINET_MAX = 0.5
CABINET_DIMS = (0.36, 0.44, 0.30)
PROPORTIONS = (0.8, 1.25)
SWITCH_NOUNS = {1: "power switch", 2: "rocker switch", 3: "wall switch"}
TRIES = 50


def cap_for(spec) -> float:
    if spec.skill == "stack":
        return STACK_MAX
    if spec.skill == "put":
        t = spec.by_role("target")[0]
        text = object_spec(t.asset).extents * np.asarray(t.scale, float)
        return min(MAX_EXTENT, 0.8 * float(min(text[0], text[1])))
    return MAX_EXTENT


class VsbNobj(Perturbation):
    pid = 15
    name = "VSB-NOBJ"
    reconfigure = True
    acts_on = "the main object's identity (unseen category) + the instruction noun"
    ranges = f"uniform over unseen categories, max extent <= {MAX_EXTENT} m; switch / cabinet: another model"

    def draw(self, rng, ctx):
        spec = ctx.spec
        main = spec.main
        if "drawer_cabinet" in main.asset:
            s = rng.uniform(*PROPORTIONS, 3)
            dims = np.asarray(CABINET_DIMS) * s
            s = s * min(1.0, CABINET_MAX / float(dims.max()))
            return dict(look=int(rng.integers(1, 4)), scale=[as_float(v) for v in s])
        if "light_switch" in main.asset:
            look = int(rng.integers(1, 4))
            return dict(look=look, scale=[as_float(v) for v in rng.uniform(0.85, 1.3, 3)], noun=SWITCH_NOUNS[look])
        cap = cap_for(spec)
        exclude = categories_of(spec, roles=("main", "target", "distractor", "fixture"))
        for k in range(1, TRIES + 1):
            (oid,) = sample_ids(rng, 1, seen=False, exclude_categories=exclude)
            scale = cap_scale(oid, cap)
            if graspable(object_spec(oid).extents * np.asarray(scale)):
                o = object_spec(oid)
                return dict(asset=oid, category=o.category, noun=o.noun, scale=list(scale), tries=k)
        raise RuntimeError(f"VSB-NOBJ: no graspable unseen object in {TRIES} draws")

    def edit_spec(self, spec, params, ctx):
        main = spec.main
        if "asset" not in params:
            sx, sy, sz = params["scale"]
            spec = with_object(spec, main.name, asset=set_query(main.asset, look=params["look"], sx=sx, sy=sy, sz=sz))
            if "noun" in params:
                spec = replace(spec, instruction=replace_noun(spec.instruction, main_noun(spec), params["noun"]))
            return spec
        text = replace_noun(spec.instruction, main_noun(spec), params["noun"])
        return replace(with_object(spec, main.name, asset=params["asset"], scale=tuple(params["scale"])), instruction=text)
