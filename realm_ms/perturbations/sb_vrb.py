"""12 SB-VRB: another verb for the same object; the rubric switches to the new verb's.

REALM's compatibility matrix: put -> {pick, rotate, stack}, pick -> {put, rotate, stack},
rotate -> {put, pick, stack}, stack -> {put, pick, rotate}, open <-> close, push -> {} (unsupported
there, as were drawers, through a key mismatch). Templates: "pick up the X", "rotate the X",
"stack the X on top of the Y", "put the X into the Y". A new verb that needs a receiver gets one:
put -> a bowl (REALM: bowl / wineglass), stack -> a flat-topped object (REALM: any non-DROID
object; a stack target must have a top to stack on), scaled to max extent <= 0.185 m; for a task
whose own target does not fit the new verb, the target is replaced (REALM's ``replace_obj``).

Drawers: open <-> close with the drawer re-homed (closed for open, fully open for close). Push:
"turn off the light switch" with the switch starting on (the rubric's last stage is the goal
state of the switch). Batched sub-envs share one verb per reset (their rubric is one tracker);
the receiver models are drawn per sub-env.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from realm_ms.tasks.perturbation import Perturbation
from realm_ms.perturbations.common import WIDE_REGION, CatalogTooSmall, catalog_extents, main_noun, object_spec, set_query, target_noun, widened, with_object
from realm_ms.tasks.progression import Thresholds
from realm_ms.tasks.skills import as_skill
from realm_ms.tasks.task_spec import SceneObject

VERBS = {
    "put": ("pick", "rotate", "stack"),
    "pick": ("put", "rotate", "stack"),
    "rotate": ("put", "pick", "stack"),
    "stack": ("put", "pick", "rotate"),
    "open_drawer": ("close_drawer",),
    "close_drawer": ("open_drawer",),
    "push": ("push_off",),
}
RECEIVER_MAX = 0.185  # m
INTO_RIM_BAND = 0.02  # m above the rim the PLACE_INTO check still counts as inside
BOWL_FLOOR = 0.006  # m, bottom thickness of the catalog's bowls
FIT_MARGIN = 0.005  # m of slack for settling / tilt
PUT_RECEIVERS = ("bowl",)
STACK_RECEIVERS = ("box", "cracker_box", "notebook", "toy_block")


def receiver_fits(verb: str, main_ext, recv_ext) -> bool:
    """Whether the main object (extents ``main_ext``) can end the new verb's rubric on a receiver of
    extents ``recv_ext``: put -> its narrow side goes in (a long spoon may rest across the rim) and,
    standing inside, its centre is below the rim band the PLACE_INTO check allows (rim + 2 cm: a
    17 cm bottle needs a deep bowl); stack -> its narrow side fits on the receiver's top (centred,
    it may overhang) and, stacked, the two centres are within MOVE_CLOSE's distance."""
    m, r = np.asarray(main_ext, float), np.asarray(recv_ext, float)
    narrow_in = float(min(m[0], m[1])) <= (0.8 if verb == "put" else 1.0) * float(min(r[0], r[1]))
    if verb == "put":
        return narrow_in and m[2] / 2 + BOWL_FLOOR + FIT_MARGIN <= r[2] + INTO_RIM_BAND
    return narrow_in and (m[2] + r[2]) / 2 + FIT_MARGIN <= Thresholds().move_close_dist


def fitting_receiver(rng, verb: str, main_ext) -> tuple[str, tuple[float, float, float]]:
    """A receiver of the verb's categories (max extent <= ``RECEIVER_MAX``) that fits the main
    object: a category uniformly among those with a fitting model, then a model uniformly."""
    cats = PUT_RECEIVERS if verb == "put" else STACK_RECEIVERS
    by_cat: dict[str, list] = {}
    for oid, scale, ext in catalog_extents(cats, RECEIVER_MAX):
        if receiver_fits(verb, main_ext, ext):
            by_cat.setdefault(object_spec(oid).category, []).append((oid, scale))
    if not by_cat:
        raise CatalogTooSmall(f"SB-VRB: no {'/'.join(cats)} in the object catalog fits an object of extents "
                              f"{np.round(main_ext, 3).tolist()} m for '{verb}' (max extent {RECEIVER_MAX} m); add such "
                              "receivers to the catalog's source meshes, or build the procedural set, which has them: "
                              "`realm assets build --source procedural --out CATALOG`")
    pool = by_cat[sorted(by_cat)[int(rng.integers(len(by_cat)))]]
    return pool[int(rng.integers(len(pool)))]


def sentence(verb: str, x: str, y: str | None) -> str:
    return {
        "pick": f"pick up the {x}",
        "rotate": f"rotate the {x}",
        "stack": f"stack the {x} on top of the {y}",
        "put": f"put the {x} into the {y}",
    }[verb]


class SbVrb(Perturbation):
    pid = 12
    name = "SB-VRB"
    reconfigure = True
    acts_on = "the verb (instruction + rubric), a receiver when the new verb needs one"
    ranges = "uniform over the verb matrix; receiver: bowl (put) / flat-topped object (stack), max extent <= 0.185 m"

    def draw(self, rng, ctx):
        skill = ctx.spec.skill
        verbs = VERBS[skill]
        shared = ctx.extra.get("batch_rng", rng)  # one verb for a batch of sub-envs
        verb = verbs[int(shared.integers(len(verbs)))]
        out = dict(verb=verb)
        if verb in ("put", "stack") and not (verb == skill):
            main = ctx.spec.main
            main_ext = object_spec(main.asset).extents * np.asarray(main.scale, float)
            oid, scale = fitting_receiver(rng, verb, main_ext)
            out.update(receiver=oid, receiver_scale=list(scale))
        return out

    def edit_spec(self, spec, params, ctx):
        verb = params["verb"]
        main = spec.main
        if verb in ("open_drawer", "close_drawer"):
            opening = verb == "open_drawer"
            spec = with_object(spec, main.name, asset=set_query(main.asset, open=0 if opening else 1))
            text = spec.instruction.replace("close" if opening else "open", "open" if opening else "close", 1)
            return replace(spec, skill=as_skill(verb), instruction=text)
        if verb == "push_off":
            spec = with_object(spec, main.name, asset=set_query(main.asset, on=1, goal="off"))
            return replace(spec, instruction=spec.instruction.replace("push", "turn off", 1))
        x = main_noun(spec)
        objs = list(spec.objects)
        y = None
        if "receiver" in params:
            old = spec.by_role("target")
            if old:  # the task's target does not suit the new verb: it is replaced (REALM's replace_obj)
                t = old[0]
                objs = [replace(o, asset=params["receiver"], scale=tuple(params["receiver_scale"])) if o.name == t.name else o for o in objs]
            else:
                objs.append(SceneObject("receiver", params["receiver"], role="target", region=WIDE_REGION, scale=tuple(params["receiver_scale"])))
                spec = widened(spec)
            y = object_spec(params["receiver"]).noun
        elif verb in ("pick", "rotate"):  # the target stays on the table as a distractor
            objs = [replace(o, role="distractor") if o.role == "target" else o for o in objs]
        else:
            y = target_noun(spec)
        return replace(spec, objects=tuple(objs), skill=as_skill(verb), instruction=sentence(verb, x, y))
