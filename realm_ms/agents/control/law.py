"""The Polymetis law, written once against an array backend (``backend.py``: torch or numpy).

    tau = (Kq + J^T Kx J)(q* - q) - (Kqd + J^T Kxd J) qd + C(q, qd) qd + g(q)

Here live the law's pieces that every integrator and both backends share: its stiffness and
damping, its feed-forward, its closed loop's transition over a physics step, the ticks of the
1 kHz law where it saturates, and the plan of model terms along the predicted path
(``model_rate="path"``).
"""

from __future__ import annotations

# rad: PhysX ended the last step where the exact step put it (its velocity off the predicted one by
# at most this over a step): the arm moves freely, and the step's torque may exceed the motor limit
# (``in_contact``). Measured in free motion on 4 s excitation logs, nominal and with every
# sysid effect: median 0.6-3e-5, max 2.1e-4; a joint blocked by contact misses by the step's whole
# motion (estimated ½ a h² at the limit torque: ~1e-3 rad on the shoulder, ~1e-2 on the wrist).
FREE_MOTION_TOLERANCE = 5e-4


def tick_count(dt: float, law_hz: float) -> int:
    """Ticks of the ``law_hz`` law inside one physics step dt."""
    return max(1, round(dt * law_hz))


def stiffness_damping(be, jac, gains):
    """Joint-space Kp = diag(Kq) + J^T Kx J and Kd = diag(Kqd) + J^T Kxd J."""
    jt = be.swap(jac)
    return be.diag(gains.kq) + jt @ (gains.kx[..., None] * jac), be.diag(gains.kqd) + jt @ (gains.kxd[..., None] * jac)


def feedforward(be, cfg, kin, qd):
    """Feed-forward from the robot's model: Coriolis and/or gravity, as configured."""
    if not (cfg.coriolis_feedforward or cfg.gravity_compensation):
        return be.zeros(qd.shape, qd)
    return be.bias(kin, qd if cfg.coriolis_feedforward else be.zeros(qd.shape, qd), cfg.gravity_compensation)


def transition(be, minv, kp, kd, dt: float, ticks: int):
    """Phi, the closed loop's state transition over one physics step dt, x = (q - q*, qd), batched
    (B, 2n, 2n). The law is sampled at ``ticks`` per step with a zero-order hold and the plant
    between ticks is M qdd = tau (the feed-forward cancels Coriolis and gravity), so one tick T is
    exactly  Phi_T = [[I - T^2/2 P, T I - T^2/2 D], [-T P, I - T D]],  P = M^-1 Kp, D = M^-1 Kd,
    and Phi = Phi_T^ticks with T = dt / ticks."""
    t = dt / ticks
    p, d = minv @ kp, minv @ kd
    eye = be.eye(kp.shape[1], kp)
    top = be.cat([eye - (0.5 * t * t) * p, t * eye - (0.5 * t * t) * d], 2)
    return be.matrix_power(be.cat([top, be.cat([-t * p, eye - t * d], 2)], 1), ticks)


def terms_at(be, cfg, q, qd, gains, arm, extra=None, dt: float | None = None) -> dict:
    """The law's terms at (q, qd): Kp, Kd, feed-forward; with ``dt`` also the plant's M (model +
    armature + ``extra`` known plant inertia), M^-1 and Phi over dt."""
    kin = be.kin(q)
    kp, kd = stiffness_damping(be, be.jacobian(kin), gains)
    terms = dict(kp=kp, kd=kd, bias=feedforward(be, cfg, kin, qd))
    if dt is not None:
        mass = be.mass(kin) + arm
        if extra is not None:
            mass = mass + extra
        minv = be.inv(mass)
        terms.update(mass=mass, minv=minv, phi=transition(be, minv, kp, kd, dt, tick_count(dt, cfg.law_hz)))
    return terms


def gravity_jacobian(be, cfg, q, eps: float = 1e-3):
    """d g / d q (B, n, n) by central differences, one batched evaluation."""
    b, n = q.shape
    if not cfg.gravity_compensation:
        return be.zeros((b, n, n), q)
    d = eps * be.eye(n, q)
    qs = be.cat([(q[:, None] + d).reshape(-1, n), (q[:, None] - d).reshape(-1, n)], 0)
    g = be.bias(be.kin(qs), be.zeros(qs.shape, qs)).reshape(2, b, n, n)
    return be.swap((g[0] - g[1]) / (2 * eps))


def law_ticks(be, e, v, minv, kp, kd, bias, ext, lim, t: float, ticks: int, within=None):
    """The law's ticks with its torque clipped to the effort limits ``lim``, on M qdd = tau - bias +
    ext (+ the ``within``-step effects' torque at each tick, ``within(e, v, tau, t, net)`` with net
    = tau - bias + ext). Returns the end state [e, v] and the within-step torque averaged over the
    ticks (None without ``within``)."""
    f_sum, neg_lim = None, -lim
    for _ in range(ticks):
        tau = be.clip(-(kp @ e[..., None] + kd @ v[..., None])[..., 0] + bias, neg_lim, lim)
        net = tau - bias + ext
        if within is not None:
            f = within(e, v, tau, t, net)
            f_sum = f if f_sum is None else f_sum + f
            net = net + f
        a = (minv @ net[..., None])[..., 0]
        e = e + t * v + (0.5 * t * t) * a
        v = v + t * a
    return be.cat([e, v], 1), (None if f_sum is None else f_sum / ticks)


def land(x1, err, qd_held, mass, ext, dt: float):
    """The exact step's landing: the motor torque (without feed-forward) that takes PhysX's
    semi-implicit Euler step from ``err`` with the velocity it holds (``qd_held``) to the closed
    loop's position x1[:n] after dt under the load ``ext``; also the predicted end and step-average
    velocities."""
    n = err.shape[1]
    v_avg = (x1[:, :n] - err) / dt
    return (mass @ ((v_avg - qd_held) / dt)[..., None])[..., 0] - ext, x1[:, n:], v_avg


def in_contact(be, tau, clamped, qd_held, predicted_velocity, dt: float):
    """Rows whose exact-step torque exceeds the motor limit while the arm did not move as the last
    step predicted. The exact step's torque is the law's motion over the step folded into one PhysX
    step, not the motor's instantaneous torque (the law's ticks are clipped to the limits inside the
    prediction): at a new target it can exceed the limit while the 1 kHz motor does not. It is
    applied in full while the arm moves as predicted; in contact it is clipped, the prediction no
    longer holds there and its velocity correction is dropped."""
    limited = (be.abs(clamped - tau) >= 1e-4).any(-1)
    free = (be.abs(qd_held - predicted_velocity) * dt <= FREE_MOTION_TOLERANCE).all(-1)
    return limited & ~free


def friction(be, neg_friction, qd, velocity: float, inertia_lower_bound, dt: float):
    """Smooth Coulomb friction on the true velocity, clamped so it can at most stop a joint within
    one step: explicit friction with a steep slope at qd = 0 is unstable on light joints (h * slope
    / I > 2); bounding it by the impulse I |qd| / h (I a lower bound of the joint's effective
    inertia) keeps it dissipative."""
    cap = inertia_lower_bound * be.abs(qd) / dt
    return be.clip(neg_friction * be.tanh(qd / velocity), -cap, cap)


def plan_path(be, cfg, q, qd, q_t, gains, arm, extra, ext, dt: float, steps: int, predictor=None, eps: float = 1e-3,
              correct_gravity: bool = True) -> dict:
    """Model terms for the next ``steps`` physics steps, each at the state the closed loop is
    predicted to reach at that step: one batched evaluation instead of one per step.

    The path is predicted with the terms at q held (the model moves little over a control step,
    and the prediction only decides where the terms are taken); the terms along it are then the
    model's own. ``dg`` (dg/dq at q, its 2n configurations in the same batch) corrects gravity to
    first order for the measured q. ``predictor``: (Phi, Kp) from the previous plan at the state it
    predicted for now (saves a model evaluation). ``correct_gravity=False``: no ``dg`` (zeros), for a
    plan used only at the q it was taken at (its first step, which is exact), where the correction
    is zero. Returns "q", "bias", "mass", "minv", "phi", "kp", "kd" (B, steps, ...) and per row
    "target", "dg", "k" (the step index)."""
    (b, n), ticks = q.shape, tick_count(dt, cfg.law_hz)
    if predictor is None:
        t = terms_at(be, cfg, q, qd, gains, arm, extra, dt)
        phi, kp = t["phi"], t["kp"]
    else:
        phi, kp = predictor
    e_star = be.solve(kp, ext)  # a constant load shifts the equilibrium
    x = be.cat([q - q_t - e_star, qd], 1)[..., None]
    xs = [x]
    for _ in range(steps - 1):
        x = phi @ x
        xs.append(x)
    xs = be.swap(be.cat(xs, -1))  # (b, steps, 2n)
    q_path = xs[..., :n] + (q_t + e_star)[:, None]
    q_path[:, 0] = q  # exact at the first step
    m = b * steps
    qs = q_path.reshape(m, n)
    qds = xs[..., n:].reshape(m, n) if cfg.coriolis_feedforward else be.zeros((m, n), q)
    correct = cfg.gravity_compensation and correct_gravity
    if correct:  # dg/dq at q by central differences, in the same batch
        d = eps * be.eye(n, q)
        qs = be.cat([qs, (q[:, None] + d).reshape(-1, n), (q[:, None] - d).reshape(-1, n)], 0)
        qds = be.cat([qds, be.zeros((2 * b * n, n), q)], 0)
    kin = be.kin(qs)
    path = be.take(kin, m)
    kp, kd = stiffness_damping(be, be.jacobian(path), gains.map(lambda g: be.repeat(g, steps)))
    mass = be.mass(path) + arm
    if extra is not None:
        mass = mass + be.repeat(extra, steps)
    minv = be.inv(mass)
    dg = be.zeros((b, n, n), q)
    if cfg.coriolis_feedforward or cfg.gravity_compensation:
        ff = be.bias(kin, qds, cfg.gravity_compensation)
        bias = ff[:m]
        if correct:
            dg = be.swap(((ff[m : m + b * n] - ff[m + b * n :]) / (2 * eps)).reshape(b, n, n))
    else:
        bias = be.zeros((m, n), q)
    terms = dict(bias=bias, mass=mass, minv=minv, phi=transition(be, minv, kp, kd, dt, ticks), kp=kp, kd=kd)
    plan = {key: v.reshape(b, steps, *v.shape[1:]) for key, v in terms.items()}
    plan.update(q=q_path, target=be.copy(q_t), dg=dg, k=be.steps(b, q))
    return plan
