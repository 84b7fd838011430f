"""Ray: (task, perturbation) cells sharded over a Ray cluster, each cell one Ray task running the
in-process backend with its own policy; and the one connection to the cluster (``connect_ray``)."""

from __future__ import annotations

import os

from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.runner import RunConfig


def check_ray_address(address: str) -> None:
    """``local``, ``auto`` or ``ray://HOST:PORT`` (Ray Client: needs ``ray[client]``)."""
    import importlib.util

    from realm_ms.errors import UserError

    if importlib.util.find_spec("ray") is None:
        raise UserError(f"--ray-address {address}: Ray is not installed (pip install 'ray[default]')")
    if address.startswith("ray://"):
        host, _, port = address[len("ray://"):].rpartition(":")
        if not host:
            raise UserError(f"--ray-address {address}: expected ray://HOST:PORT (e.g. ray://10.0.0.1:10001)")
        from realm_ms.validate import check_port

        check_port(port, f"--ray-address {address}: port")
        if importlib.util.find_spec("grpc") is None:
            raise UserError(f"--ray-address {address}: Ray Client needs the `ray[client]` extra (pip install 'ray[client]'), "
                            "or run on a cluster node with --ray-address auto")


def connect_ray(address: str) -> None:
    """Connect to Ray once (``local``: a cluster in this machine); a bad address is one line, not a traceback."""
    import ray

    from realm_ms.errors import UserError

    if ray.is_initialized():
        return
    try:
        ray.init(address=None if address == "local" else address, include_dashboard=False, log_to_driver=False,
                 num_cpus=os.cpu_count() if address == "local" else None)
    except (ConnectionError, ValueError, RuntimeError, TimeoutError) as e:
        msg = " ".join(str(e).split())[:300]
        raise UserError(f"--ray-address {address}: cannot connect to Ray ({type(e).__name__}: {msg})") from None


def run_ray(keys: list[EpisodeKey], policy_spec: str, policy_options: dict, cfg: RunConfig, address: str, on_record, progress_bar: bool = True) -> int:
    """Shard (task, perturbation) cells over Ray (``address``: ``local``, ``auto`` or ``ray://...``);
    each cell runs in-process in one Ray task with its own policy; records stream back as cells end."""
    import ray
    from tqdm import tqdm

    connect_ray(address)

    @ray.remote(num_cpus=1)
    def run_cell(cell_keys, spec, options, run_cfg):
        from realm_ms.eval.backends.inline import InlineBackend
        from realm_ms.eval.policies import make_policy
        from realm_ms.eval.runner import run_plan

        recs: list = []
        policy = make_policy(spec, **options)
        backend = InlineBackend(run_cfg, 1)
        try:
            run_plan(cell_keys, policy, backend, recs.append, progress_bar=False, replan_every=run_cfg.replan_every,
                     policy_latency=run_cfg.policy_latency, env_kwargs=run_cfg.env_kwargs)
        finally:
            backend.close()
            policy.close()
        return recs

    cells: dict = {}
    for k in keys:
        cells.setdefault(k.cell(), []).append(k)
    refs = [run_cell.remote(v, policy_spec, policy_options, cfg) for v in cells.values()]
    n = 0
    with tqdm(total=len(keys), desc="episodes (ray)", unit="ep", disable=not progress_bar) as bar:
        while refs:
            done, refs = ray.wait(refs, num_returns=1)
            for rec in ray.get(done[0]):
                on_record(rec)
                n += 1
                bar.update(1)
    return n


__all__ = ["run_ray", "connect_ray", "check_ray_address"]
