"""11 SB-NOUN: another object of the scene becomes the one to manipulate; the instruction names it.

REALM: pop a random object from the distractors (+ immutables); it becomes the main object, the old
main joins the distractors; the instruction's noun becomes the new object's category. Drawers:
"top" -> random {middle, top}, joints re-homed. Push and stack were unsupported; primitive objects
gave degenerate nouns ("put the object in the bowl").

Here: the noun is the task author's name for the object ("can of soda", "blue block"), never a
bare category; only objects the skill can act on are candidates (graspable for pick / rotate; for
put also small enough for the receptacle; for stack at most 5 cm, so it can rest on the 3 cm
block); the main and the chosen distractor swap assets (slots keep their names, so sub-envs with
different picks stay one batched actor). Drawers: REALM's {middle, top}, on a cabinet whose handles
are staggered sideways (top-down, a lower handle is otherwise under the one above it and no
gripper reaches it; the bottom drawer's handle, 5 cm above the table, is left out for the same
reason). Push: a second switch (another model) is added and becomes the one to
push, the light switch stays as a distractor.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from realm_ms.tasks.perturbation import Perturbation
from realm_ms.perturbations.common import graspable, main_noun, object_spec, replace_noun, set_query, slot_noun, with_object
from realm_ms.tasks.task_spec import SceneObject

DRAWERS = ("middle", "top")
SWITCH_LOOKS = {1: "black switch", 2: "red switch", 3: "blue switch"}
STACKABLE_MAX = 0.05  # m


def candidate_ok(spec, o: SceneObject) -> bool:
    if o.role not in ("distractor", "fixture") or o.asset.startswith("articulated/"):
        return False
    ext = object_spec(o.asset).extents * np.asarray(o.scale, float)
    if not graspable(ext):
        return False
    if spec.skill == "stack":
        return float(ext.max()) <= STACKABLE_MAX
    if spec.skill == "put":
        (t,) = spec.by_role("target")[:1]
        text = object_spec(t.asset).extents * np.asarray(t.scale, float)
        return float(max(ext[0], ext[1])) <= 0.8 * float(min(text[0], text[1])) and float(ext[2]) <= 0.15
    if spec.skill == "pick":
        return float(ext[2]) <= 0.2
    return True


class SbNoun(Perturbation):
    pid = 11
    name = "SB-NOUN"
    reconfigure = True
    acts_on = "which object is manipulated (+ the instruction noun); drawers: which drawer; push: which switch"
    ranges = "uniform among the scene's objects the skill can act on; drawers {middle, top}; push: 1 of 3 switch models"

    def draw(self, rng, ctx):
        spec = ctx.spec
        if spec.skill in ("open_drawer", "close_drawer"):
            return dict(drawer=DRAWERS[int(rng.integers(len(DRAWERS)))])
        if spec.skill == "push":
            look = int(rng.integers(1, 1 + len(SWITCH_LOOKS)))
            return dict(look=look, noun=SWITCH_LOOKS[look])
        cands = [o.name for o in spec.objects if candidate_ok(spec, o)]
        if not cands:
            raise RuntimeError(f"SB-NOUN: no object in {spec.env_id} the '{spec.skill}' skill can act on")
        name = cands[int(rng.integers(len(cands)))]
        return dict(swap_with=name, noun=slot_noun(next(o for o in spec.objects if o.name == name)))

    def edit_spec(self, spec, params, ctx):
        main = spec.main
        if "drawer" in params:
            text = spec.instruction.replace("top", params["drawer"], 1)
            return replace(with_object(spec, main.name, asset=set_query(main.asset, drawer=params["drawer"], stagger=1)), instruction=text)
        if "look" in params:
            text = replace_noun(spec.instruction, main_noun(spec), params["noun"])
            old = replace(main, name=f"{main.name}_0", role="distractor")
            spec = with_object(spec, main.name, asset=set_query(main.asset, look=params["look"]))
            return replace(spec, objects=spec.objects + (old,), instruction=text)
        other = next(o for o in spec.objects if o.name == params["swap_with"])
        text = replace_noun(spec.instruction, main_noun(spec), params["noun"])
        spec = with_object(spec, main.name, asset=other.asset, scale=other.scale)
        spec = with_object(spec, other.name, asset=main.asset, scale=main.scale)
        return replace(spec, instruction=text)
