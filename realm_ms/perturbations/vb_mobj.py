"""14 VB-MOBJ: the main object's size, per axis, drawn per reset from its pristine bounding box.

REALM: s1, s2, s3 ~ U(0.5, 1.5), rejected until s1 s2 s3 <= 1.5; dataset objects get
``bbox = clip(bbox_orig * s, 0.02, 0.175)`` m, anchored on the config bbox (no compounding).
Added (documented): for skills that grasp, draws whose narrower horizontal side exceeds what the
2F-85 can close around (7.5 cm) are rejected too (REALM could make an object nobody can pick up).
REALM left drawers and the switch out; here the cabinet's carcass is scaled per axis (dimensions
clipped to [0.25, 0.55] m, the analogue of REALM's planned [0.4, 0.75] m for its larger cabinet)
and the switch housing + rocker likewise (clipped to x0.6 .. x1.6 of the nominal).
"""

from __future__ import annotations

import numpy as np

from realm_ms.tasks.perturbation import Perturbation, as_float
from realm_ms.perturbations.common import graspable, is_articulated, object_spec, set_query, with_object

SCALE = (0.5, 1.5)
MAX_PRODUCT = 1.5
BBOX_CLIP = (0.02, 0.175)  # m
CABINET_CLIP = (0.25, 0.55)  # m
CABINET_DIMS = (0.36, 0.44, 0.30)  # nominal depth, width, height (CabinetGeometry)
SWITCH_CLIP = (0.6, 1.6)  # x nominal
GRASP_SKILLS = ("pick", "put", "stack", "rotate")


def draw_scales(rng, accept=lambda s: True, tries: int = 1000) -> tuple[np.ndarray, int]:
    for k in range(1, tries + 1):
        s = rng.uniform(*SCALE, 3)
        if np.prod(s) <= MAX_PRODUCT and accept(s):
            return s, k
    raise RuntimeError("VB-MOBJ: no acceptable scale in 1000 draws")


class VBMobj(Perturbation):
    pid = 14
    name = "VB-MOBJ"
    reconfigure = True
    acts_on = "the main object's extents (per axis)"
    ranges = f"s_i ~ U{SCALE}, prod <= {MAX_PRODUCT}; bbox clip {BBOX_CLIP} m; cabinet dims clip {CABINET_CLIP} m"

    def draw(self, rng, ctx):
        main = ctx.spec.main
        if is_articulated(main):
            s, tries = draw_scales(rng)
            if "drawer_cabinet" in main.asset:
                dims = np.clip(np.asarray(CABINET_DIMS) * s, *CABINET_CLIP)
                s = dims / np.asarray(CABINET_DIMS)
            else:
                s = np.clip(s, *SWITCH_CLIP)
            return dict(scale=[as_float(v) for v in s], tries=tries)
        bbox = object_spec(main.asset).extents * np.asarray(main.scale, float)

        def scaled(s):
            return np.clip(bbox * s, *BBOX_CLIP)

        need_grasp = ctx.spec.skill in GRASP_SKILLS
        s, tries = draw_scales(rng, (lambda s: graspable(scaled(s))) if need_grasp else (lambda s: True))
        ext = scaled(s)
        return dict(draw=[as_float(v) for v in s], tries=tries, extents=[as_float(v) for v in ext],
                    scale=[as_float(v) for v in ext / bbox * np.asarray(main.scale, float)])

    def edit_spec(self, spec, params, ctx):
        main = spec.main
        if is_articulated(main):
            sx, sy, sz = params["scale"]
            return with_object(spec, main.name, asset=set_query(main.asset, sx=sx, sy=sy, sz=sz))
        return with_object(spec, main.name, scale=tuple(params["scale"]))
