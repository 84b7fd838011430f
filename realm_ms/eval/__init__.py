"""Policy evaluation under the REALM protocol: ``realm eval``, metrics, reports, real-vs-sim validation.

Layout (one concept per module):

- ``policies/``: the policy interface and registry (expert, zero, random, lerobot, openpi);
- ``protocol.py``: presets (``realm``, ``quick``) and the episode plan ((task, perturbation, seed) keys);
- ``slots.py``: a cell's env on the episode engine (``tasks.episode``), ``EpisodeRunner`` its one-slot case;
- ``runner.py``: run settings, the record schema and the driver that batches the policy over slots;
- ``workers.py``: execution backends (in-process, N CPU worker processes with shared-memory
  observations, ManiSkill GPU simulation where SAPIEN's GPU PhysX exists, Ray sharding);
- ``records.py``: append-only JSONL records, resume; ``quality.py``: trajectory quality;
- ``metrics.py``: success / progression with intervals, failure stages; ``validate.py``: Pearson,
  MMRV, RMSD; ``report.py``: HTML report; ``cli.py``: ``realm eval``.
"""
