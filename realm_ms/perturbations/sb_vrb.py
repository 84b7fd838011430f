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

from realm_ms.perturbations.perturbation import Perturbation
from realm_ms.perturbations.common import WIDE_REGION, cap_scale, widened, main_noun, sample_ids, set_query, target_noun, with_object
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
PUT_RECEIVERS = ("bowl",)
STACK_RECEIVERS = ("box", "cracker_box", "notebook", "toy_block")


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
            cats = PUT_RECEIVERS if verb == "put" else STACK_RECEIVERS
            (oid,) = sample_ids(rng, 1, categories=cats)
            out.update(receiver=oid, receiver_scale=list(cap_scale(oid, RECEIVER_MAX)))
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
            from realm_ms.perturbations.common import object_spec

            y = object_spec(params["receiver"]).noun
        elif verb in ("pick", "rotate"):  # the target stays on the table as a distractor
            objs = [replace(o, role="distractor") if o.role == "target" else o for o in objs]
        else:
            y = target_noun(spec)
        return replace(spec, objects=tuple(objs), skill=as_skill(verb), instruction=sentence(verb, x, y))
