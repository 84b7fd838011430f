"""REALM's 16 perturbation settings (0 Default + 15 factors) as hooks on the REALM envs.

``gym.make("REALM-PickApple-v1", perturbation="V-LIGHT")`` (or an id, ``perturbation=4``, or a list
for a deliberate composition, ``["V-LIGHT", "VB-POSE"]``); ``info["perturbation"]`` after ``reset``
holds the names and every drawn parameter. One module per perturbation; importing this package
registers each into ``PERTURBATIONS`` (names, with the numeric ids as aliases), the registry the
tasks layer owns beside the interface; ``PerturbationSet`` is what an env runs.
"""

from __future__ import annotations

from realm_ms.perturbations.b_hobj import BHobj
from realm_ms.perturbations.default import Default
from realm_ms.perturbations.s_aff import SAff
from realm_ms.perturbations.s_int import SInt
from realm_ms.perturbations.s_lang import SLang
from realm_ms.perturbations.s_mo import SMo
from realm_ms.perturbations.s_prop import SProp
from realm_ms.perturbations.sb_noun import SbNoun
from realm_ms.perturbations.sb_vrb import SbVrb
from realm_ms.perturbations.v_aug import VAug
from realm_ms.perturbations.v_light import VLight
from realm_ms.perturbations.v_sc import VSc
from realm_ms.perturbations.v_view import VView
from realm_ms.perturbations.vb_mobj import VBMobj
from realm_ms.perturbations.vb_pose import VBPose
from realm_ms.perturbations.vsb_nobj import VsbNobj
from realm_ms.tasks.perturbation import PERTURBATIONS, DrawContext, Perturbation, register_perturbation
from realm_ms.tasks.perturbation_set import PerturbationSet

for _cls in (Default, VAug, VView, VSc, VLight, SProp, SLang, SMo, SAff, SInt, BHobj, SbNoun, SbVrb, VBPose, VBMobj, VsbNobj):
    register_perturbation(_cls)


def all_perturbations() -> list[Perturbation]:
    """One instance of each, in id order (0 .. 15)."""
    return sorted((cls() for cls in PERTURBATIONS.values()), key=lambda p: p.pid)


__all__ = ["PERTURBATIONS", "DrawContext", "Perturbation", "PerturbationSet", "all_perturbations"]
