"""One atomic write for every file realm-ms replaces: the old file or the new one, never half."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from realm_ms.atomic import write_bytes, write_json, write_npz, write_text


def test_each_kind_round_trips_and_makes_parents(tmp_path):
    d = tmp_path / "a" / "b"
    assert write_text(d / "t.txt", "héllo\n").read_text() == "héllo\n"
    assert write_bytes(d / "b.bin", b"\x00\xff").read_bytes() == b"\x00\xff"
    assert json.loads(write_json(d / "j.json", {"x": np.float32(1.5)}, default=float).read_text()) == {"x": 1.5}
    p = write_npz(d / "z.npz", t=np.arange(3.0), q=np.ones((3, 7)))
    assert p.name == "z.npz"  # numpy appends no second .npz
    with np.load(p) as z:
        assert z["t"].tolist() == [0.0, 1.0, 2.0] and z["q"].shape == (3, 7)
    assert sorted(f.name for f in d.iterdir()) == ["b.bin", "j.json", "t.txt", "z.npz"]  # no temporary left


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    p = write_text(tmp_path / "run.json", '{"old": true}')
    with pytest.raises(TypeError):
        write_json(p, {"bad": object()})  # fails while the new content is being made
    with pytest.raises(ValueError, match="killed"):
        _fail_midway(p)
    assert p.read_text() == '{"old": true}'
    assert [f.name for f in tmp_path.iterdir()] == ["run.json"]


def _fail_midway(path):
    """A writer killed after part of the file is out: the temporary is written, then the error."""
    from realm_ms import atomic

    def fill(f):
        f.write("half of the ")
        raise ValueError("killed")

    atomic._write(path, "w", fill)


def test_the_file_gets_the_usual_permissions(tmp_path):
    """Not the owner-only mode of a ``mkstemp`` file: reports and models stay readable by others."""
    umask = os.umask(0o022)
    try:
        mode = write_text(tmp_path / "r.html", "<html>").stat().st_mode & 0o777
    finally:
        os.umask(umask)
    assert mode == 0o644
