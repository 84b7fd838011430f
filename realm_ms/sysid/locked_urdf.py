"""The arm the replay simulator loads: the benchmark's URDF with the gripper locked.

The sysid replay simulator needs the *same* rigid body as the benchmark (``panda_droid``: Panda +
Robotiq 2F-85), but not its gripper linkage or collision meshes: every non-arm joint is turned
into a fixed joint (the gripper is held open, at its zero configuration, exactly how the
controller's ``ArmModel`` lumps it) and visual/collision geometry is dropped, so many arm copies
share one PhysX scene without touching each other and without loading meshes. Inertials are kept
verbatim. The result is cached next to the source URDF's cache, keyed by a content hash.
"""

from __future__ import annotations

import hashlib
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

from realm_ms.agents.urdf import ARM_JOINTS
from realm_ms.atomic import write_text

if TYPE_CHECKING:
    import numpy as np

BASE_LINK = "panda_link0"
TIP_LINK = "panda_link8"  # the flange; in the locked URDF it is lumped into panda_link7
MODEL_TIP_LINK = "panda_link7"


def source_urdf_path() -> tuple[Path, str]:
    """(path, name) of the benchmark robot's URDF: ``panda_droid`` when available, else ManiSkill's
    ``panda_v2`` (Franka hand instead of the 2F-85)."""
    try:
        from realm_ms.agents.urdf import panda_droid_urdf_path

        return Path(panda_droid_urdf_path()), "panda_droid"
    except Exception:  # noqa: BLE001 - the DROID URDF module is optional in partial checkouts
        import mani_skill

        p = Path(mani_skill.__file__).parent / "assets/robots/panda/panda_v2.urdf"
        return p, "panda_v2"


def _cache_dir() -> Path:
    d = os.environ.get("REALM_MS_CACHE")
    return (Path(d).expanduser() if d else Path.home() / ".cache" / "realm_ms") / "sysid"


def _fmt(v) -> str:
    return " ".join(f"{float(x):.10g}" for x in v)


def _lump_fixed_links(root: ET.Element) -> None:
    """Merge every link hanging off a fixed joint into its parent (mass, CoM, inertia), so PhysX
    simulates 8 links instead of ~22. Same lumping as ``ArmModel`` uses for the controller's model."""
    from realm_ms.agents.arm_model import _Inertial, _origin

    links = {l.get("name"): l for l in root.findall("link")}
    while True:
        fixed = [j for j in root.findall("joint") if j.get("type") == "fixed"]
        parents_of_fixed = {j.find("parent").get("link") for j in fixed}
        # merge leaves first: a fixed joint whose child has no fixed children of its own
        leaf = next((j for j in fixed if j.find("child").get("link") not in parents_of_fixed
                     and not any(k.find("parent").get("link") == j.find("child").get("link") for k in root.findall("joint"))), None)
        if leaf is None:
            break
        parent, child = links[leaf.find("parent").get("link")], links[leaf.find("child").get("link")]
        merged = _Inertial.merge([_Inertial.parse(parent), _Inertial.parse(child).transformed(_origin(leaf.find("origin")))])
        for el in parent.findall("inertial"):
            parent.remove(el)
        inertial = ET.SubElement(parent, "inertial")
        ET.SubElement(inertial, "origin", xyz=_fmt(merged.com), rpy="0 0 0")
        ET.SubElement(inertial, "mass", value=f"{merged.mass:.10g}")
        i = merged.inertia
        ET.SubElement(inertial, "inertia", ixx=f"{i[0,0]:.10g}", ixy=f"{i[0,1]:.10g}", ixz=f"{i[0,2]:.10g}",
                      iyy=f"{i[1,1]:.10g}", iyz=f"{i[1,2]:.10g}", izz=f"{i[2,2]:.10g}")
        root.remove(leaf)
        root.remove(child)
        del links[child.get("name")]


def locked_arm_urdf_text(src: str) -> str:
    root = ET.fromstring(src)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    for joint in root.findall("joint"):
        if joint.get("name") not in ARM_JOINTS and joint.get("type") != "fixed":
            joint.set("type", "fixed")
            for tag in ("mimic", "limit", "axis", "dynamics"):
                for el in joint.findall(tag):
                    joint.remove(el)
    for el in root.findall("transmission"):
        root.remove(el)
    _lump_fixed_links(root)
    return ET.tostring(root, encoding="unicode")


def locked_arm_urdf_path(src: str | Path | None = None) -> Path:
    """Path of the locked-gripper, geometry-free copy of ``src`` (default: :func:`source_urdf_path`)."""
    src = Path(src) if src is not None else source_urdf_path()[0]
    text = locked_arm_urdf_text(src.read_text())
    key = hashlib.sha1(text.encode()).hexdigest()[:12]
    out = _cache_dir() / f"{src.stem}_locked_{key}.urdf"
    if not out.exists():
        write_text(out, text)
    return out


def flange_offset_in_link7(src: str | Path | None = None) -> "np.ndarray":
    """Position of the flange (``panda_link8``) in ``panda_link7`` (m), from the source URDF."""
    import numpy as np

    src = Path(src) if src is not None else source_urdf_path()[0]
    root = ET.parse(str(src)).getroot()
    for j in root.findall("joint"):
        if j.find("child").get("link") == TIP_LINK and j.find("parent").get("link") == MODEL_TIP_LINK:
            o = j.find("origin")
            xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
            return np.array(xyz)
    raise ValueError(f"{src}: no fixed joint panda_link7 -> panda_link8")
