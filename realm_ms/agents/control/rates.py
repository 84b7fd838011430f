"""Where the law's model terms (J, M, C(q, qd), g(q)) come from: one strategy per
``DroidControlConfig.model_rate``, on either backend. The feedback on q, qd runs every physics step
whatever the rate; a rate only decides at which state the terms are evaluated.

Each returns the step's terms as ``StepTerms`` ("kp", "kd", "bias", and for the exact integrator
"mass", "minv", "phi"), whose ``bias_at(q)`` is the feed-forward corrected to first order in gravity
for the measured q. ``extend(terms, dt)`` (optional; for "path" it receives the whole plan) adds
what an integrator derives from the terms once per evaluation (the folded exact step's affine map). ``extra``: a function giving the plant
inertia the actuation stages add (or None), called only where the terms are evaluated.
"""

from __future__ import annotations

from realm_ms.agents.control.law import gravity_jacobian, plan_path, terms_at


class StepTerms:
    """A physics step's model terms by name; ``dg`` (dg/dq) and ``q_ref`` correct gravity for the measured q."""

    def __init__(self, terms: dict, dg=None, q_ref=None):
        self.terms, self.dg, self.q_ref = terms, dg, q_ref

    def __getitem__(self, key):
        return self.terms[key]

    def __setitem__(self, key, value):
        self.terms[key] = value

    def bias_at(self, q):
        bias = self["bias"]
        return bias if self.dg is None else bias + (self.dg @ (q - self.q_ref)[..., None])[..., 0]


class PlanStep(StepTerms):
    """The plan's terms at each row's current step, indexed on first use."""

    def __init__(self, plan: dict, r, k):
        super().__init__({}, plan["dg"])
        self.plan, self.r, self.k = plan, r, k

    def __getitem__(self, key):
        if key not in self.terms:
            self.terms[key] = self.plan[key][self.r, self.k]
        return self.terms[key]

    def bias_at(self, q):
        self.q_ref = self["q"]
        return super().bias_at(q)


class PhysicsRate:
    """At the measured state, every physics step (as Polymetis at 1 kHz)."""

    def __init__(self, cfg, extend=None):
        self.cfg, self.extend = cfg, extend

    def reset(self) -> None:
        """Forget all state (an env reset, a new batch shape)."""

    def retarget(self) -> None:
        """A new target: forget terms taken for the old one."""

    def terms(self, be, q, qd, q_t, gains, arm, extra, ext, dt: float, exact: bool, off=None) -> StepTerms:
        t = self._evaluate(be, q, qd, gains, arm, extra, dt, exact)
        if self.extend is not None:
            self.extend(t, dt)
        return t

    def _evaluate(self, be, q, qd, gains, arm, extra, dt, exact) -> StepTerms:
        extra = (extra() if callable(extra) else extra) if exact else None
        return StepTerms(terms_at(be, self.cfg, q, qd, gains, arm, extra, dt if exact else None))


class ControlRate(PhysicsRate):
    """Once per target, gravity corrected to first order in between (cheaper, ~1-2 mrad RMS further
    from the 1 kHz law)."""

    def __init__(self, cfg, extend=None):
        super().__init__(cfg, extend)
        self.cached = None

    def reset(self) -> None:
        self.cached = None

    retarget = reset

    def terms(self, be, q, qd, q_t, gains, arm, extra, ext, dt: float, exact: bool, off=None) -> StepTerms:
        if self.cached is None:
            self.cached = super().terms(be, q, qd, q_t, gains, arm, extra, ext, dt, exact)
        return self.cached

    def _evaluate(self, be, q, qd, gains, arm, extra, dt, exact) -> StepTerms:
        t = super()._evaluate(be, q, qd, gains, arm, extra, dt, exact)
        t.dg, t.q_ref = gravity_jacobian(be, self.cfg, q), be.copy(q)
        return t


class PathRate:
    """For every physics step, at the state the closed loop is predicted to reach then: a plan of
    ``steps`` steps in one batched evaluation (``law.plan_path``). Each row has its own step index
    and gets a new plan when its plan is used up, its target changed or its arm left the path by
    more than ``path_tolerance`` (contact, saturation, latency): a row's plans depend on its own
    history only, so batched rows equal single runs. Needs the exact integrator's prediction."""

    def __init__(self, cfg, extend=None, targets_move: bool = True):
        self.cfg, self.extend = cfg, extend
        self.steps = cfg.path_steps
        self.horizon = self.steps  # steps of the current plan (1 while the target moves at every step)
        self._all_moved = False  # every row's target moved at the last step
        self.plan = self.dt = self._r = None
        self.plans = 0  # plans made (full or for some rows): a diagnostic
        # True: the tracked target may change without ``retarget`` (command stages such as latency),
        # so every step compares it with the plan's; False: only after ``retarget``
        self.targets_move = targets_move
        self._retargeted = True

    def reset(self) -> None:
        self.plan, self._all_moved = None, False

    def retarget(self) -> None:
        """Rows whose target changed re-plan on their next step (``terms`` compares the targets)."""
        self._retargeted = True

    def terms(self, be, q, qd, q_t, gains, arm, extra, ext, dt: float, exact: bool = True, off=None) -> PlanStep:
        """``off``: rows known to be off the path (None: measure the distance here)."""
        p, steps, b = self.plan, self.steps, q.shape[0]
        if self._r is None or len(self._r) != b:
            self._r = be.arange(b, q)
        r = self._r
        full, rows, pred, moving = p is None or self.dt != dt, None, None, False
        if not full:
            j = be.at_most(p["k"], self.horizon - 1)
            if off is None:
                off = (be.abs(q - p["q"][r, j]) > self.cfg.path_tolerance).any(-1)
            need = (p["k"] >= self.horizon) | off
            all_moved = False
            if self.targets_move or self._retargeted:
                moved = (q_t != p["target"]).any(-1)
                need = need | moved
                all_moved = bool(moved.all())
                # every row's target moved at this step and the last: the target moves at every step
                # (a command filter), each plan is replaced after its first step, and the rest of a
                # longer one would be evaluated for nothing
                moving = all_moved and self._all_moved and bool((p["k"] == 1).all())
            self._all_moved = all_moved
            if need.any():
                rows = be.rows(need)
                full = len(rows) == b
                pred = (p["phi"][r, j], p["kp"][r, j])  # the previous plan's step nearest to now predicts the new path
        if full or rows is not None:
            self.plans += 1
            extra = extra() if callable(extra) else extra
            if full:
                self.horizon = 1 if moving else steps
                self.plan, self.dt = self._make(be, q, qd, q_t, gains, arm, extra, ext, dt, pred), dt
                p = self.plan
            else:
                pick = lambda x: None if x is None else x[rows]  # noqa: E731
                new = self._make(be, q[rows], qd[rows], q_t[rows], gains.map(pick), arm, pick(extra), ext[rows], dt,
                                 tuple(x[rows] for x in pred))
                for key, v in new.items():
                    p[key][rows] = v
        self._retargeted = False
        k = p["k"]
        p["k"] = k + 1
        return PlanStep(p, r, k)

    def _make(self, be, q, qd, q_t, gains, arm, extra, ext, dt, pred) -> dict:
        # a plan cut to one step is used only at the q it was taken at: no gravity correction to prepare
        plan = plan_path(be, self.cfg, q, qd, q_t, gains, arm, extra, ext, dt, self.horizon, pred,
                         correct_gravity=self.horizon == self.steps)
        if self.extend is not None:
            self.extend(plan, dt)
        return plan


def rate_for(cfg, extend=None, targets_move: bool = True):
    """The strategy for ``cfg.model_rate`` ("path" needs the exact integrator: else "physics")."""
    if cfg.follows_path:
        return PathRate(cfg, extend, targets_move)
    return ControlRate(cfg, extend) if cfg.model_rate == "control" else PhysicsRate(cfg, extend)
