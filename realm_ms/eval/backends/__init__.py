"""Execution backends of ``realm eval`` and ``realm export``: where the episode slots' envs live and step.

One protocol (``base.Backend``, with the control signals ``Unsupported`` and ``Failed``) and one
module per backend:

- ``inline.py``: slots in this process (one slot: the expert bench, the demo, Ray shards);
- ``processes.py``: N worker processes, observations through shared memory (its wire format there);
- ``batched.py``: the sub-envs of ManiSkill envs with ``num_envs = N`` (GPU simulation);
- ``ray.py``: (task, perturbation) cells sharded over a Ray cluster, and the one Ray connection;
- ``choose.py``: the GPU PhysX probe and ``--backend NAME`` -> a backend (``choose_backend``).
"""
