# Two entry points for a fresh machine: `make demo` and `make test`. Both set up first (idempotent).
PY := .venv/bin/python
export MS_SKIP_ASSET_DOWNLOAD_PROMPT := 1
export PYTHONUNBUFFERED := 1

.PHONY: setup demo test test-slow bench bench-expert clean

setup:
	@bash scripts/setup.sh

demo: setup
	$(PY) -m realm_ms.cli demo

test: setup
	$(PY) -m pytest -q

test-slow: setup
	$(PY) -m pytest -q -m slow --run-slow

bench: setup
	$(PY) bench/step_rate.py

bench-expert: setup
	$(PY) bench/expert_success.py

clean:
	rm -rf outputs .pytest_cache
