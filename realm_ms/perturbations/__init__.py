"""REALM's 16 perturbation settings (0 Default + 15 factors) as hooks on the REALM envs.

``gym.make("REALM-PickApple-v1", perturbation="V-LIGHT")`` (or an id, ``perturbation=4``, or a list
for a deliberate composition, ``["V-LIGHT", "VB-POSE"]``); ``info["perturbation"]`` after ``reset``
holds the names and every drawn parameter. One module per perturbation; ``PERTURBATIONS`` is the
registry (names, with the numeric ids as aliases); ``PerturbationSet`` is what an env runs.
"""

from __future__ import annotations

from realm_ms.perturbations.b_hobj import BHobj
from realm_ms.perturbations.perturbation import DrawContext, Perturbation
from realm_ms.perturbations.default import Default
from realm_ms.perturbations.runtime import PerturbationSet
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
from realm_ms.registry import Registry

PERTURBATIONS: Registry[type[Perturbation]] = Registry("perturbation")
for _cls in (Default, VAug, VView, VSc, VLight, SProp, SLang, SMo, SAff, SInt, BHobj, SbNoun, SbVrb, VBPose, VBMobj, VsbNobj):
    PERTURBATIONS.register(_cls.name, _cls, aliases=(str(_cls.pid),))


def all_perturbations() -> list[Perturbation]:
    """One instance of each, in id order (0 .. 15)."""
    return sorted((cls() for cls in PERTURBATIONS.values()), key=lambda p: p.pid)


def _install() -> None:
    # the envs (a lower layer) call back through this resolver; see RealmEnv's perturbation hooks
    from realm_ms.tasks import env

    env.PERTURBATION_RESOLVER = PerturbationSet.resolve


_install()

__all__ = ["PERTURBATIONS", "DrawContext", "Perturbation", "PerturbationSet", "all_perturbations"]
