"""Model terms shared by torque-path effects: the controller model's gravity and bias torques at
the true state, computed once per physics step for the whole batch, and row scattering."""

from __future__ import annotations

import torch

from realm_ms.agents.actuation import ControlState


def _model_terms(state: ControlState) -> tuple[torch.Tensor, torch.Tensor]:
    """(C(q, qd) qd + g(q), g(q)) of the controller's model at the true state for the whole batch,
    in one batched RNEA call, cached for this physics step. Computing all rows once is cheaper than
    per-effect subsets: at these batch sizes the call overhead dominates."""
    terms = state.extra.get("_sysid_terms")
    if terms is None:
        b = state.q.shape[0]
        out = state.model.rnea(torch.cat([state.q, state.q]), torch.cat([state.qd, torch.zeros_like(state.qd)]))
        terms = state.extra["_sysid_terms"] = (out[:b], out[b:])
    return terms


def model_gravity(state: ControlState, rows: torch.Tensor | None = None) -> torch.Tensor:
    """g_model(q) of the controller's own model at the true state (``rows`` only), cached per step."""
    g = _model_terms(state)[1]
    return g if rows is None else g[rows]


def model_bias(state: ControlState, rows: torch.Tensor | None = None) -> torch.Tensor:
    """C(q, qd) qd + g(q) of the controller's model; the driver's own value when it shares it
    (``state.extra["bias"]``, at the measured state), else computed here."""
    b = state.extra.get("bias")
    if b is None:
        b = _model_terms(state)[0]
    return b if rows is None else b[rows]


def scatter_rows(full_like: torch.Tensor, rows: torch.Tensor | None, part: torch.Tensor) -> torch.Tensor:
    if rows is None:
        return part
    out = torch.zeros_like(full_like)
    out[rows] = part
    return out
