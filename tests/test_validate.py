"""realm_ms.validate: the shared checks behind every flag, field and file (docs/validation.md)."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

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
