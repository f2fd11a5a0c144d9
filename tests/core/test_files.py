"""lanekeep/core/files.py: a file written atomically is complete or absent; a failing write
leaves the file already there untouched and no temporary file behind; new files get the mode
0666 & ~umask."""

from __future__ import annotations

import os
import stat

import pytest

from lanekeep.core.files import atomic_path, atomic_write, temp_beside


def test_a_written_file_holds_exactly_the_data_and_nothing_else_is_left(tmp_path):
    path = atomic_write(tmp_path / "a.json", "{\"é\": 1}\n")
    assert path.read_bytes() == "{\"é\": 1}\n".encode()
    atomic_write(path, b"\x00\x01")  # bytes, over an existing file
    assert path.read_bytes() == b"\x00\x01"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


class _Boom(Exception):
    pass


def test_a_failing_write_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "report.json"
    path.write_text("old")
    with pytest.raises(_Boom), atomic_path(path) as tmp:
        tmp.write_text("half of the new")
        raise _Boom
    assert path.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_a_failing_first_write_leaves_no_file_at_all(tmp_path, monkeypatch):
    path = tmp_path / "new.bin"

    def fail(*_args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", fail)
    with pytest.raises(OSError, match="No space left"):
        atomic_write(path, b"data")
    assert list(tmp_path.iterdir()) == []


def test_the_file_appears_only_when_complete(tmp_path):
    path = tmp_path / "table.parquet"
    with atomic_path(path) as tmp:
        tmp.write_bytes(b"part")
        assert not path.exists()  # a reader sees nothing until the write is done
        with tmp.open("ab") as f:
            f.write(b" and the rest")
    assert path.read_bytes() == b"part and the rest"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.parquet"]


def test_the_temporary_keeps_the_suffix_and_is_hidden(tmp_path):
    tmp = temp_beside(tmp_path / "video.avi")
    assert tmp.parent == tmp_path and tmp.name.startswith(".video.") and tmp.suffix == ".avi"
    assert tmp.is_file() and tmp.stat().st_size == 0
    assert temp_beside(tmp_path / "video.avi") != tmp  # never the same name twice


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_new_files_get_0666_less_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        path = atomic_write(tmp_path / f"m{umask:o}.txt", "x")
        with atomic_path(tmp_path / f"p{umask:o}.bin") as tmp:
            tmp.write_bytes(b"y")
    finally:
        os.umask(old)
    for name in (path.name, f"p{umask:o}.bin"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~umask
