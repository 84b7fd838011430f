"""Rigid-body inertial parameters kept physical, and the inverse-dynamics regressor they enter.

A body's dynamics is linear in its ten standard parameters ``pi = (m, h, I_o)``: mass, first moment
``h = m c`` and rotational inertia about the body origin (xx, xy, xz, yy, yz, zz), all in the body
frame: ``tau = Y(q, q̇, q̈) pi`` (``regressor``). The inertial effects (``link_mass``, ``payload``)
do not fit ``pi`` itself -- most of that 10-D space is no rigid body -- but physical coordinates
mapped so that every point inside their bounds is a realisable mass distribution:

- mass ``m > 0``,
- any centre of mass ``c``,
- the second moment of the mass distribution about its CoM, ``Σ = ∫ ρ r rᵀ``, positive definite.
  The rotational inertia ``I_c = tr(Σ) 1 - Σ`` then is positive definite and satisfies the
  triangle inequalities (``I_xx + I_yy >= I_zz`` ...); conversely every such ``I_c`` has
  ``Σ = tr(I_c)/2 · 1 - I_c`` positive semidefinite (Wensing, Kim, Slotine 2017, "Linear matrix
  inequalities for physically consistent inertial parameter identification").

Torch only (batched over rows), so the driver can use it every physics step.
"""

from __future__ import annotations

import torch

#: order of the six inertia entries in ``pi[4:]``
INERTIA_KEYS = ("xx", "xy", "xz", "yy", "yz", "zz")
_IJ = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def second_moment(inertia: torch.Tensor) -> torch.Tensor:
    """Σ = tr(I)/2 · 1 - I (..., 3, 3): PSD exactly when I is a physical rotational inertia."""
    eye = torch.eye(3, dtype=inertia.dtype, device=inertia.device)
    return 0.5 * torch.diagonal(inertia, dim1=-2, dim2=-1).sum(-1)[..., None, None] * eye - inertia


def inertia_of(sigma: torch.Tensor) -> torch.Tensor:
    """I = tr(Σ) 1 - Σ (..., 3, 3), the inverse of ``second_moment``."""
    eye = torch.eye(3, dtype=sigma.dtype, device=sigma.device)
    return torch.diagonal(sigma, dim1=-2, dim2=-1).sum(-1)[..., None, None] * eye - sigma


def is_physical(mass: torch.Tensor, inertia: torch.Tensor, tol: float = 1e-12) -> torch.Tensor:
    """(...,) bool: positive mass, symmetric positive-definite inertia about the CoM, triangle
    inequalities (Σ PSD)."""
    sym = (inertia - inertia.transpose(-1, -2)).abs().amax((-1, -2)) <= 1e-9 * (1 + inertia.abs().amax((-1, -2)))
    pd = torch.linalg.eigvalsh(inertia).amin(-1) > 0
    tri = torch.linalg.eigvalsh(second_moment(inertia)).amin(-1) >= -tol
    return (mass > 0) & sym & pd & tri


def standard(mass: torch.Tensor, com: torch.Tensor, inertia_c: torch.Tensor) -> torch.Tensor:
    """(..., 10) standard parameters from mass (...), CoM (..., 3) and inertia about the CoM (..., 3, 3)."""
    eye = torch.eye(3, dtype=com.dtype, device=com.device)
    m = mass[..., None, None]
    i_o = inertia_c + m * ((com * com).sum(-1)[..., None, None] * eye - com[..., :, None] * com[..., None, :])
    ent = torch.stack([i_o[..., i, j] for i, j in _IJ], -1)
    return torch.cat([mass[..., None], mass[..., None] * com, ent], -1)


def shape_matrix(stretch: torch.Tensor, shear: torch.Tensor) -> torch.Tensor:
    """A (..., 3, 3) lower triangular with positive diagonal exp(stretch): Σ -> A Σ Aᵀ keeps Σ
    positive definite for any (stretch, shear), so it parametrises every mass distribution's shape
    around the nominal one (a Cholesky factor relative to the nominal)."""
    a = torch.diag_embed(torch.exp(stretch))
    a[..., 1, 0], a[..., 2, 0], a[..., 2, 1] = shear[..., 0], shear[..., 1], shear[..., 2]
    return a


# ---------------------------------------------------------------------------- regressor
def _kinematics(arm, q: torch.Tensor, qd: torch.Tensor, qdd: torch.Tensor | None, gravity: bool, frames=None):
    """Per body: rotation, origin, joint axis (world), and ``ArmModel.motion``'s angular
    velocity/acceleration and origin acceleration (with -g as the base's)."""
    frames = arm.link_frames(q) if frames is None else frames
    links = arm.links(frames, dynamics=False)
    w, dw, a = arm.motion(links, qd, gravity, qdd)
    return frames[..., :3, :3], links.p, links.z, w, dw, a


def regressor(arm, q: torch.Tensor, qd: torch.Tensor, qdd: torch.Tensor | None, body: int,
              gravity: bool = True, frames=None) -> torch.Tensor:
    """Y (B, n, 10): joint torques of body ``body`` (0-based) per unit of each standard parameter,
    ``tau = Y @ pi`` (``pi`` in the body frame, ``standard``). ``qdd=None``: zero acceleration."""
    rot, p, z, w, dw, a = _kinematics(arm, q, qd, qdd, gravity, frames)
    r, o, wk, dwk, ak = rot[:, body], p[:, body], w[:, body], dw[:, body], a[:, body]
    cross = torch.linalg.cross
    b = q.shape[0]
    f = torch.zeros(b, 10, 3, dtype=q.dtype, device=q.device)
    n = torch.zeros_like(f)
    f[:, 0] = ak  # mass
    h = r.transpose(1, 2)  # (B, 3 columns, 3): h = R e_j for a unit first moment along body axis j
    wk3, dwk3 = wk[:, None].expand_as(h), dwk[:, None].expand_as(h)
    f[:, 1:4] = cross(dwk3, h, dim=-1) + cross(wk3, cross(wk3, h, dim=-1), dim=-1)
    n[:, 1:4] = cross(h, ak[:, None].expand_as(h), dim=-1)
    wb, dwb = (r.transpose(1, 2) @ wk[..., None])[..., 0], (r.transpose(1, 2) @ dwk[..., None])[..., 0]
    for c, (i, j) in enumerate(_IJ):  # unit inertia E_ij (symmetric), body frame: n = E dw + w x E w
        e = torch.zeros(3, 3, dtype=q.dtype, device=q.device)
        e[i, j] = e[j, i] = 1.0
        nb = dwb @ e.T + cross(wb, wb @ e.T, dim=-1)
        n[:, 4 + c] = (r @ nb[..., None])[..., 0]
    lever = (o[:, None] - p)[:, :, None].expand(b, p.shape[1], 10, 3)  # origin of body k from joint j
    mom = n[:, None] + cross(lever, f[:, None].expand_as(lever), dim=-1)
    y = (z[:, :, None] * mom).sum(-1)
    return y * (torch.arange(p.shape[1], device=q.device) <= body).to(q.dtype)[None, :, None]


def body_mass_matrix(arm, q: torch.Tensor, body: int, pi: torch.Tensor, frames=None) -> torch.Tensor:
    """(B, n, n) joint-space inertia of ``pi`` (B or 1, 10) on body ``body``: Jᵀ M_s J with the
    body origin's Jacobian J and the spatial inertia [[m 1, -S(h)], [S(h), I_o]] (world axes)."""
    frames = arm.link_frames(q) if frames is None else frames
    rot, p = frames[..., :3, :3], frames[..., :3, 3]
    z = (rot @ arm.axes.to(q.dtype)[..., None])[..., 0]
    cols = (torch.arange(p.shape[1], device=q.device) <= body).to(q.dtype)[None, :, None]
    jv = torch.linalg.cross(z, (p[:, body][:, None] - p), dim=-1) * cols  # (B, n, 3)
    jw = z * cols
    r = rot[:, body]
    pi = pi.to(q.dtype).expand(q.shape[0], -1)
    h = (r @ pi[:, 1:4, None])[..., 0]
    i_b = torch.zeros(q.shape[0], 3, 3, dtype=q.dtype, device=q.device)
    for c, (i, j) in enumerate(_IJ):
        i_b[:, i, j] = i_b[:, j, i] = pi[:, 4 + c]
    i_o = r @ i_b @ r.transpose(1, 2)
    sh = torch.zeros_like(i_o)  # S(h): S(h) x = h x x
    sh[:, 0, 1], sh[:, 0, 2], sh[:, 1, 0] = -h[:, 2], h[:, 1], h[:, 2]
    sh[:, 1, 2], sh[:, 2, 0], sh[:, 2, 1] = -h[:, 0], -h[:, 1], h[:, 0]
    m = pi[:, 0, None, None]
    vv = m * (jv @ jv.transpose(1, 2))
    vw = -(jv @ sh @ jw.transpose(1, 2))
    return vv + vw + vw.transpose(1, 2) + jw @ i_o @ jw.transpose(1, 2)
