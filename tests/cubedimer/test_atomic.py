"""The atomic writer: results get the permissions of an ordinary new file (the umask is respected)."""
import json
import os
import stat
from contextlib import contextmanager

import pytest

from cubedimer.atomic import (atomic_save, atomic_write_text, default_dir_mode, default_file_mode, save_figure,
                              write_json)


@contextmanager
def umask(mask: int):
    old = os.umask(mask)
    try:
        yield
    finally:
        os.umask(old)


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.mark.parametrize("mask, expected", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_every_writer_respects_the_umask(tmp_path, mask, expected):
    import matplotlib.pyplot as plt

    with umask(mask):
        atomic_write_text(tmp_path / "a.txt", "x\n")
        write_json(tmp_path / "b.json", {"v": float("nan")})
        atomic_save(tmp_path / "c.bin", lambda tmp: open(tmp, "wb").write(b"\0"))
        fig, ax = plt.subplots()
        save_figure(fig, tmp_path / "d.png", dpi=20)
        assert default_file_mode() == expected
        assert default_dir_mode() == 0o777 & ~mask
    for name in ("a.txt", "b.json", "c.bin", "d.png"):
        assert _mode(tmp_path / name) == expected, name
    assert json.loads((tmp_path / "b.json").read_text()) == {"v": None}
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary file left


def test_failing_writer_leaves_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "r.txt"
    atomic_write_text(target, "old\n")

    def boom(tmp):
        open(tmp, "w").write("partial")
        raise RuntimeError("writer failed")

    with pytest.raises(RuntimeError):
        atomic_save(target, boom)
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["r.txt"]


def test_atomic_directory_replaces_only_on_success(tmp_path):
    """A folder built in the block replaces the old one when the block succeeds; on an error the old one stays
    and no temporary folder is left behind."""
    import os

    import pytest

    from cubedimer.atomic import atomic_directory, default_dir_mode

    out = tmp_path / "set"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_directory(out) as tmp:
            (tmp / "new.txt").write_text("new")
            raise RuntimeError("fails half-way")
    assert sorted(p.name for p in out.iterdir()) == ["old.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["set"]
    with atomic_directory(out) as tmp:
        (tmp / "new.txt").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == ["new.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["set"]
    assert os.stat(out).st_mode & 0o777 == default_dir_mode()
