"""The one check of a refused command's output, shared by the CLI tests: exit code 2, one
line on stderr ("lanekeep[ CMD]: error: ..."), no traceback, and (unless said) nothing on
stdout."""

from __future__ import annotations


def one_error_line(capture, code: int, *needles: str, start: str = "lanekeep",
                   stdout_empty: bool = True) -> str:
    """The error line, after asserting its shape; `capture` is pytest's capsys or capfd, and
    the line must start with `start` and hold every one of `needles`."""
    out, err = capture.readouterr()
    assert code == 2, err
    if stdout_empty:
        assert out == "", out
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith(start) and "error: " in line and "Traceback" not in err, line
    for needle in needles:
        assert needle in line, (needle, line)
    return line
