"""The replay URDF: gripper locked and lumped, same rigid-body dynamics as the benchmark URDF."""

import xml.etree.ElementTree as ET

import numpy as np
import torch

from realm_ms.agents.arm_model import ArmModel
from realm_ms.sysid.locked_urdf import ARM_JOINTS, flange_offset_in_link7, locked_arm_urdf_path, source_urdf_path


def test_locked_urdf_has_only_the_arm_and_same_dynamics():
    src = source_urdf_path()[0]
    locked = locked_arm_urdf_path(src)
    root = ET.parse(locked).getroot()
    moving = [j.get("name") for j in root.findall("joint") if j.get("type") != "fixed"]
    assert moving == list(ARM_JOINTS)
    assert not root.findall(".//visual") and not root.findall(".//collision")
    a = ArmModel.from_urdf(src, "panda_link0", "panda_link8")
    b = ArmModel.from_urdf(locked, "panda_link0", "panda_link7")
    q = torch.randn(6, 7, generator=torch.Generator().manual_seed(0))
    qd, qdd = 2 * torch.randn(6, 7), torch.randn(6, 7)
    torch.testing.assert_close(a.rnea(q, qd, qdd), b.rnea(q, qd, qdd), atol=1e-4, rtol=1e-4)
    assert abs(float(a.masses.sum()) - float(b.masses.sum())) < 1e-5
    assert np.allclose(flange_offset_in_link7(src), [0, 0, 0.107], atol=1e-3)
