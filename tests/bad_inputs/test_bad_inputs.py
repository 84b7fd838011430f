"""Run the bad-input corpus (``bad_input_cases.py``, ``bad_input_cases_runs.py``,
``bad_input_cases_contracts.py``, ``bad_input_cases_policy.py``): a clear one-line
error with exit code 2, or accepted with its documented meaning; never a traceback, never a hang
(every case has a timeout)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from bad_input_cases import CASES as BASE_CASES, Case  # noqa: E402
from bad_input_cases_contracts import CASES as CONTRACT_CASES, make_files as make_contract_files  # noqa: E402
from bad_input_cases_policy import CASES as POLICY_CASES  # noqa: E402
from bad_input_cases_runs import CASES as RUN_CASES, make_files  # noqa: E402
from bad_input_files import make_all  # noqa: E402

CASES = BASE_CASES + RUN_CASES + CONTRACT_CASES + POLICY_CASES

REPO = Path(__file__).resolve().parents[2]
REALM = Path(sys.executable).parent / "realm"


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    r = tmp_path_factory.mktemp("bad_inputs")
    make_all(r)
    make_contract_files(r)
    make_files(r)  # runs one tiny `realm eval` (the run directory the resume cases change)
    return r


def _argv(case: Case, root: Path) -> list[str]:
    return [a.replace("{root}", str(root)) for a in case.argv]


def _cuda() -> bool:
    try:
        import torch

        return torch.cuda.is_available()
    except ImportError:  # pragma: no cover
        return False


def _params():
    out = []
    for c in CASES:
        marks = [pytest.mark.timeout(180 if c.env else 90), *c.marks]
        if c.needs_no_cuda:
            marks.append(pytest.mark.skipif(_cuda(), reason="needs a machine without a CUDA GPU"))
        out.append(pytest.param(c, id=c.id, marks=marks))
    return out


def test_corpus_size_and_shape():
    assert len(CASES) >= 250
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids)), "duplicate case ids"
    for c in CASES:
        assert (c.argv is None) != (c.call is None), c.id
        assert (c.error is None) != (c.accepted is None), f"{c.id}: give exactly one of error / accepted"


def _check_cli_result(case: Case, code: int, out: str, err: str) -> None:
    text = out + err
    assert "Traceback" not in text, f"{case.id}: traceback\n{text}"
    if case.error:
        lines = [line for line in err.splitlines() if line.strip()]
        assert lines, f"{case.id}: no error message (exit {code})\n{out}"
        last = lines[-1]
        assert code == 2, f"{case.id}: exit code {code}, expected 2; last line: {last}"
        assert re.search(case.error, last), f"{case.id}: error line does not match {case.error!r}:\n{last}"
        assert last.startswith(("realm", "usage: realm")), f"{case.id}: error is not in `realm ...: error: ...` form: {last}"
    else:
        assert code == 0, f"{case.id}: expected success, got exit {code}\n{err}"


@pytest.mark.parametrize("case", _params())
def test_bad_input(case: Case, root: Path, capsys):
    if case.argv is not None and case.subprocess:
        r = subprocess.run([str(REALM), *_argv(case, root)], capture_output=True, text=True, timeout=120, cwd=REPO,
                           env={**os.environ, "PYTHONWARNINGS": "ignore"})
        _check_cli_result(case, r.returncode, r.stdout, r.stderr)
        return
    if case.argv is not None:
        from realm_ms.cli import main

        try:
            code = main(_argv(case, root))
        except SystemExit as e:  # argparse rejects a flag
            code = e.code if isinstance(e.code, int) else 2
        cap = capsys.readouterr()
        _check_cli_result(case, code, cap.out, cap.err)
        return
    # a Python call
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = case.call(root)
        except Exception as e:  # noqa: BLE001 - the type and message are what we check
            if case.error is None:
                raise
            msg = str(e)
            assert isinstance(e, (ValueError, TypeError, KeyError, LookupError)), f"{case.id}: {type(e).__name__}: {msg}"
            assert "\n" not in msg.strip(), f"{case.id}: error spans several lines:\n{msg}"
            assert re.search(case.error, msg), f"{case.id}: message does not match {case.error!r}: {msg}"
            return
    if case.error is not None:
        messages = [str(w.message) for w in caught]
        if case.warn_ok and any(re.search(case.error, m) for m in messages):
            return  # documented: clipped with a warning
        pytest.fail(f"{case.id}: accepted silently (expected an error or warning matching {case.error!r}); warnings: {messages}")
    if case.check is not None:
        case.check(result)
