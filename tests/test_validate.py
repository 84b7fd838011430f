"""realm_ms.validate: the shared checks behind every flag, field and file (docs/validation.md)."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from realm_ms.errors import UserError
from realm_ms.registry import UnknownNameError
from realm_ms.sysid.timeseries import DataError
from realm_ms.validate import (
    InputError,
    check_int,
    check_non_negative,
    check_number,
    check_output_dir,
    check_output_file,
    check_positive,
    integer,
    positive,
)


@pytest.mark.parametrize("bad", [0, -1, -1e-12, math.nan, math.inf, -math.inf, "abc", None, True, np.zeros(3), [1.0]])
def test_positive_rejects(bad):
    with pytest.raises(InputError, match=r"^--segment: "):
        check_positive(bad, "--segment", "s")


def test_numbers_accepted_and_converted():
    assert check_positive("2.5", "x") == 2.5
    assert check_positive(np.float32(3.0), "x") == 3.0
    assert check_non_negative(0, "x") == 0.0
    assert check_number(-4, "x", minimum=-5, maximum=0) == -4.0
    with pytest.raises(InputError, match="must be <= 0"):
        check_number(1, "x", maximum=0)
    with pytest.raises(InputError, match="shape \\(3,\\)"):
        check_number(np.ones(3), "control_hz", "Hz")


def test_integers():
    assert check_int("3", "--n") == 3 and check_int(4.0, "--n") == 4 and check_int(0, "--seed", minimum=0) == 0
    for bad in (1.5, "x", math.nan, True, 0):
        with pytest.raises(InputError, match="^--n: "):
            check_int(bad, "--n")


def test_output_paths(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "f").write_text("x")
    assert check_output_file(tmp_path / "new" / "m.yaml", "--out") == tmp_path / "new" / "m.yaml"
    with pytest.raises(InputError, match="is a directory"):
        check_output_file(tmp_path / "d", "--out")
    with pytest.raises(InputError, match="is a file"):
        check_output_file(tmp_path / "f" / "m.yaml", "--out")
    assert check_output_dir(tmp_path / "d", "--out") == tmp_path / "d"
    assert check_output_dir(tmp_path / "d" / "new" / "deeper", "--out")
    with pytest.raises(InputError, match="exists and is a file"):
        check_output_dir(tmp_path / "f", "--out")


def test_argparse_types_name_the_flag(capsys):
    p = argparse.ArgumentParser(prog="realm x")
    p.add_argument("--segment", type=positive("s"))
    p.add_argument("--workers", type=integer(1))
    assert p.parse_args(["--segment", "8", "--workers", "2"]).segment == 8.0
    for argv, msg in ((["--segment", "0"], "argument --segment: must be > 0 s, got 0"),
                      (["--segment", "nan"], "argument --segment: must be a finite number s, got 'nan'"),
                      (["--workers", "0"], "argument --workers: must be >= 1, got 0")):
        with pytest.raises(SystemExit) as e:
            p.parse_args(argv)
        assert e.value.code == 2 and msg in capsys.readouterr().err


@pytest.mark.parametrize("script", ["eval_throughput", "render_rate", "reset_cost", "step_rate", "sysid"])
def test_bench_scripts_refuse_a_folder_as_out_before_they_run(tmp_path, script):
    """Every bench script that writes a JSON ``--out`` checks it first (exit 2, one line), instead
    of failing when it writes, after its measurements."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    r = subprocess.run([sys.executable, str(root / "bench" / f"{script}.py"), "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert f"--out: {tmp_path} is a directory; give a file path" in r.stderr


def _raise(exc):
    def handler(args):
        raise exc

    return handler


@pytest.mark.parametrize("exc", [
    UserError("give --tasks"),
    InputError("--segment: must be > 0 s, got 0"),
    UnknownNameError("unknown task 'X'; known: A, B"),
    DataError("d/traj.npz: missing key(s) ['q']"),
], ids=lambda e: type(e).__name__)
def test_every_user_error_is_one_line_and_exit_2(exc, monkeypatch, capsys):
    """One root: whatever kind of user error a command raises, `realm` prints one line and exits 2."""
    from realm_ms import cli
    from realm_ms.sysid import cli as sysid_cli

    monkeypatch.setattr(sysid_cli, "_effects", _raise(exc))
    assert cli.main(["sysid", "effects"]) == 2
    assert capsys.readouterr().err.splitlines() == [f"realm sysid effects: error: {exc}"]


def test_input_errors_stay_value_errors_for_python_callers():
    assert issubclass(InputError, UserError) and issubclass(InputError, ValueError)
    assert issubclass(UnknownNameError, InputError) and issubclass(DataError, InputError)


def test_other_errors_are_not_user_errors(monkeypatch):
    """A ValueError that is not a user error is a bug: it keeps its traceback."""
    from realm_ms import cli
    from realm_ms.sysid import cli as sysid_cli

    monkeypatch.setattr(sysid_cli, "_effects", _raise(ValueError("a bug")))
    with pytest.raises(ValueError, match="a bug"):
        cli.main(["sysid", "effects"])
