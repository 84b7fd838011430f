"""Policy evaluation under the REALM protocol: ``realm eval``, metrics, reports, real-vs-sim validation.

``from realm_ms.eval import evaluate``: a whole ``realm eval`` run from Python (``evaluation.py``).

Layout (one concept per module):

- ``policies/``: the policy interface and registry (expert, zero, random, lerobot, openpi);
- ``protocol.py``: presets (``realm``, ``quick``) and the episode plan ((task, perturbation, seed) keys);
- ``slots.py``: a cell's env on the episode engine (``tasks.episode``), ``EpisodeRunner`` its one-slot case;
- ``runner.py``: run settings, a cell's env config, the record schema and the driver (``run_plan``)
  that batches the policy over slots; ``realm export`` runs its episodes through it too;
- ``backends/``: where slots live (``base.py``: the protocol; ``inline.py``, ``processes.py`` with its
  shared-memory wire format, ``batched.py`` for GPU simulation, ``ray.py``; ``choose.py``: the GPU
  probe and ``--backend``);
- ``evaluation.py``: ``evaluate()``, a whole run (run directory, resume, backend, metrics);
- ``records.py``: append-only JSONL records, resume; ``quality.py``: trajectory quality;
- ``metrics.py``: success / progression with intervals, failure stages; ``real_vs_sim.py``: Pearson,
  MMRV, RMSD; ``report.py``: HTML report; ``cli.py``: ``realm eval``.
"""

from realm_ms.eval.evaluation import evaluate  # cheap: its imports are inside the function

__all__ = ["evaluate"]
