"""Near-singular postures in real DROID episodes: how often, and what they do to IK-built joint targets.

    python bench/droid_singularity.py DATA_DIR [--closed-loop]

Per sample: sigma_min, the smallest singular value of the 6x7 flange Jacobian at the measured
joints (``interaction.sigma_min``). Binned by it: how much of the commanded flange step (clipped
as DROID clips it) the rebuilt joint target misses (``closed_loop`` mode's rebuilt ``q_cmd``);
with ``--closed-loop`` also how fast the nominal closed-loop replay's joints drift from the real
ones (mrad per step), and for candidate thresholds the share of samples masked (held ``MIN_S``,
padded ``PAD_S``, as ``interaction.detect`` masks) against the share of all joint-error growth
they hold. DATA_DIR as ``bench/droid_alignment.py`` reads it.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from realm_ms.errors import UserError

EDGES = (0.0, 0.02, 0.05, 0.08, 0.10, 0.12, 0.15, 0.20, 0.30)
THRESHOLDS = (0.05, 0.08, 0.10, 0.12, 0.15, 0.20)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data")
    ap.add_argument("--closed-loop", action="store_true", help="also replay every episode closed loop (nominal robot)")
    args = ap.parse_args(argv)
    from realm_ms.agents.droid_action_spaces import DroidIK, cartesian_delta_to_velocity, cartesian_velocity_to_delta, pose_diff
    from realm_ms.sysid.alignment import read_droid_episodes, replay_closed_loop
    from realm_ms.sysid.interaction import PAD_S, SINGULAR_SIGMA, _pad, _runs, held_samples, sigma_min

    try:
        eps, skipped = read_droid_episodes(args.data)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    ik = DroidIK()
    sig, miss = [], []
    for e in eps:
        sig.append(sigma_min(e.q, ik))
        pose = ik.pose(e.q)
        want = cartesian_velocity_to_delta(cartesian_delta_to_velocity(pose_diff(e.cartesian_cmd, pose)))[:, :3]
        got = pose_diff(ik.pose(e.traj.q_cmd), pose)[:, :3]
        miss.append(np.linalg.norm(got - want, axis=1) / np.maximum(np.linalg.norm(want, axis=1), 1e-3))
    s_all = np.concatenate(sig)
    print(f"{len(eps)} episodes ({len(skipped)} set aside), {len(s_all)} samples; SINGULAR_SIGMA = {SINGULAR_SIGMA}")
    print("sigma_min percentiles 1/5/25/50/95: " + " ".join(f"{x:.3f}" for x in np.percentile(s_all, [1, 5, 25, 50, 95])))
    grow = None
    if args.closed_loop:
        sims = replay_closed_loop(eps)
        grow = np.concatenate([np.r_[0.0, np.diff(np.linalg.norm(e.q - qs, axis=1))] * 1e3 for e, qs in zip(eps, sims)])
    miss_all = np.concatenate(miss)
    head = "sigma_min bin    samples  rebuilt-target miss (median share of the step)"
    print(head + ("  joint-error growth mrad/step (mean)" if grow is not None else ""))
    for lo, hi in zip(EDGES[:-1], EDGES[1:]):
        m = (s_all >= lo) & (s_all < hi)
        if m.any():
            row = f"[{lo:.2f}, {hi:.2f})   {m.sum():7d}  {np.median(miss_all[m]):.2f}"
            print(row + (f"{grow[m].mean():37.1f}" if grow is not None else ""))
    pos = None if grow is None else np.clip(grow, 0.0, None)
    print("threshold  masked share  episodes" + ("  share of joint-error growth" if pos is not None else ""))
    for th in THRESHOLDS:
        runs = [_runs(s < th, held_samples(e.traj.rate_hz)) for s, e in zip(sig, eps)]  # as interaction.detect holds them
        m = np.concatenate([_pad(r, e.traj.t, PAD_S) for r, e in zip(runs, eps)])
        n_eps = sum(r.any() for r in runs)
        row = f"{th:9.2f}  {m.mean():12.1%}  {n_eps:8d}"
        print(row + (f"  {pos[m].sum() / pos.sum():.1%}" if pos is not None else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
