"""3 V-SC: scene clutter, re-drawn per reset: 3 extra distractors and every other object swapped.

REALM: 3 extra distractors from the 833 non-DROID categories (excluding the main/target
categories); each reset every non-main/non-target object (task distractors + immutables + the 3)
is re-placed in the spawn box and replaced by a model from the DROID themes other than its
current category's, scaled so its largest extent is <= 0.12 m. Here: the extras come from the
catalog's unseen split, replacements from the seen split of other themes, all <= 0.12 m; placement
is collision-free (REALM over-subscribed its spawn region and dropped objects from above).

REALM left V-SC inert on push and drawers (no distractors). Here the 3 extras are placed next to
the switch (in the spawn box around it) and beside the cabinet (left/right of its footprint).
"""

from __future__ import annotations

from dataclasses import replace

from realm_ms.tasks.perturbation import Perturbation
from realm_ms.perturbations.common import cap_scale, widened, categories_of, object_spec, sample_ids
from realm_ms.tasks.task_spec import SceneObject

N_EXTRA = 3
MAX_EXTENT = 0.12  # m
DRAWER_SIDES = ((0.40, 0.95, 0.36, 0.66), (0.40, 0.95, -0.66, -0.36))


class VSc(Perturbation):
    pid = 3
    name = "V-SC"
    reconfigure = True
    acts_on = "scene clutter: 3 extra distractors (unseen categories) + every distractor swapped and re-placed"
    ranges = f"{N_EXTRA} extras; replacements from other themes; all scaled to max extent <= {MAX_EXTENT} m"

    def draw(self, rng, ctx):
        spec = ctx.spec
        keep = categories_of(spec)
        extras = sample_ids(rng, N_EXTRA, who=self.name, seen=False, exclude_categories=keep, distinct_categories=True)
        swaps = {}
        for o in spec.objects:
            if o.role in ("main", "target") or o.asset.startswith("articulated/"):
                continue
            theme = object_spec(o.asset).record.theme
            others = tuple(t for t in seen_themes() if t != theme)
            swaps[o.name] = sample_ids(rng, 1, who=self.name, seen=True, themes=others, exclude_categories=keep)[0]
        return dict(extras=extras, swaps=swaps)

    def edit_spec(self, spec, params, ctx):
        objs = []
        for o in spec.objects:
            if o.name in params["swaps"]:
                a = params["swaps"][o.name]
                o = replace(o, asset=a, role="distractor", pose=None, fixed=False, region=o.region, scale=cap_scale(a, MAX_EXTENT))
            objs.append(o)
        drawer = spec.skill in ("open_drawer", "close_drawer")
        for k, a in enumerate(params["extras"]):
            region = DRAWER_SIDES[k % 2] if drawer else None  # None: the (widened) spawn region
            objs.append(SceneObject(f"clutter_{k}", a, region=region, scale=cap_scale(a, MAX_EXTENT)))
        # 3 more objects on the same table: a tighter gap keeps the layout feasible (REALM dropped
        # objects from above instead)
        return replace(widened(spec), objects=tuple(objs), min_separation=min(spec.min_separation, 0.005))


def seen_themes() -> tuple[str, ...]:
    """REALM's DROID-like themes: the themes of the seen categories."""
    from asset_pipeline.procedural import REGISTRY

    return tuple(sorted({c.theme for c in REGISTRY.values() if c.seen}))
