"""The dispatch matrix: the golden runs (lanekeep/loop/golden.py) under every kernel choice
that a CPU can lead a library to, on one machine.

Why: the golden files say what one machine computed; a second machine is what the promise
"same scenario and seed, same numbers" is about, and there may be none to hand. Each library
that picks its kernels from the CPU (ISA, vendor, cache sizes, cores) can be made to pick
another path here through the variables it reads when it loads, so each alternative is run as
its own process, from an environment without the user's kernel variables (so the pins of
lanekeep/core/reproducibility.py apply), with one row's variables set.

Two kinds of row:
- `cpu`: a choice another x86-64 CPU with AVX2 and FMA can make while the pins hold (more
  ISA offered to a capped library, other cache sizes, other core counts). Each must give the
  golden files' bits: that is the claim.
- `pin`: a pin's own variable set to what the library would choose unpinned on some CPU.
  Informative: a row that differs is a library whose choice reaches the bits (the pin is what
  holds it); the golden check names the setting that differs. A row that is identical is a
  library that does not reach them in these runs.
- `outside`: a machine the pins do not cover (a CPU without AVX2 or FMA); expected to differ,
  and the check must name why.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from lanekeep.core.reproducibility import KERNEL_ENV

KINDS = ("cpu", "pin", "outside")
# Variables that choose kernels but are not the pins' (set by some machines' images, e.g.
# OPENBLAS_L2_SIZE here): dropped too, so that every row starts from the pinned default.
EXTRA_KERNEL_ENV = ("OPENBLAS_L2_SIZE", "OPENBLAS_NUM_THREADS", "MKL_ENABLE_INSTRUCTIONS",
                    "MKL_NUM_THREADS", "ONEDNN_CPU_ISA_HINTS", "OPENCV_FOR_THREADS_NUM",
                    "LANEKEEP_THREADS")


@dataclass(frozen=True)
class Row:
    """One setting of one library: its variables, what CPU it stands for, and its kind."""

    library: str
    env: dict[str, str]
    stands_for: str
    kind: str = "cpu"
    quick: bool = False  # one of the cheap rows the test suite runs

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind {self.kind!r} is not one of {KINDS}")

    @property
    def setting(self) -> str:
        return " ".join(f"{k}={v}" for k, v in self.env.items()) or "(pinned default)"


ROWS: tuple[Row, ...] = (
    Row("all", {}, "this machine, pinned (the golden files' own setting)", quick=True),
    # torch: oneDNN (convolutions, unless taken out of LaneNet's forward) and MKL (GEMM)
    Row("torch/oneDNN", {"ONEDNN_MAX_CPU_ISA": "AVX2_VNNI"}, "a CPU with AVX-VNNI (Alder Lake)",
        "pin"),
    Row("torch/oneDNN", {"ONEDNN_MAX_CPU_ISA": "AVX512_CORE"}, "a CPU with AVX-512 (Skylake-X)",
        "pin", quick=True),
    Row("torch/oneDNN", {"ONEDNN_MAX_CPU_ISA": "AVX512_CORE_BF16"},
        "a CPU with AVX-512 BF16 (Cooper Lake, Zen 4)", "pin"),
    Row("torch/oneDNN", {"ONEDNN_MAX_CPU_ISA": "SSE41"}, "a CPU with SSE4.1 only", "pin"),
    Row("torch/oneDNN", {"ONEDNN_CPU_ISA_HINTS": "PREFER_YMM"},
        "a CPU whose AVX-512 oneDNN prefers at 256 bits"),
    Row("torch/MKL", {"MKL_ENABLE_INSTRUCTIONS": "AVX2"}, "a CPU offering MKL AVX2 at most",
        quick=True),
    Row("torch/MKL", {"MKL_ENABLE_INSTRUCTIONS": "AVX512"}, "a CPU offering MKL AVX-512"),
    Row("torch/MKL", {"MKL_CBWR": "AUTO"}, "MKL's own choice for this CPU", "pin", quick=True),
    Row("torch/MKL", {"MKL_CBWR": "AVX2"},
        "MKL's AVX2 branch (honoured on Intel; AMD reads it as AUTO)", "pin"),
    Row("torch/ATen", {"ATEN_CPU_CAPABILITY": "avx512"}, "ATen's choice on an AVX-512 CPU",
        "pin"),
    Row("torch/threads", {"OMP_NUM_THREADS": "1"}, "one core"),
    Row("torch/threads", {"OMP_NUM_THREADS": "4"}, "four cores"),
    Row("numpy", {"NPY_DISABLE_CPU_FEATURES": ""}, "numpy's choice on an AVX-512 CPU", "pin"),
    Row("OpenBLAS", {"OPENBLAS_CORETYPE": "SkylakeX"}, "OpenBLAS's choice on a Skylake-X",
        "pin"),
    Row("OpenBLAS", {"OPENBLAS_CORETYPE": "Zen"}, "OpenBLAS's choice on an AMD Zen", "pin"),
    Row("OpenBLAS", {"OPENBLAS_L2_SIZE": "256"}, "a CPU with 256 KiB L2 a core", quick=True),
    Row("OpenBLAS", {"OPENBLAS_L2_SIZE": "2048"}, "a CPU with 2 MiB L2 a core"),
    Row("OpenBLAS", {"OPENBLAS_NUM_THREADS": "1"}, "one core"),
    Row("OpenBLAS", {"OPENBLAS_NUM_THREADS": "4"}, "four cores"),
    Row("OpenCV", {"OPENCV_CPU_DISABLE": ""}, "OpenCV's choice on an AVX-512 CPU", "pin"),
    Row("OpenCV", {"OPENCV_FOR_THREADS_NUM": "1"}, "one core"),
    Row("OpenCV", {"OPENCV_FOR_THREADS_NUM": "4"}, "four cores"),
    Row("llvmpipe", {"LP_NATIVE_VECTOR_WIDTH": "128"}, "llvmpipe at 128-bit vectors", "pin"),
    Row("llvmpipe", {"LP_NUM_THREADS": "1"}, "one rasteriser thread", quick=True),
    Row("llvmpipe", {"LP_NUM_THREADS": "4"}, "four rasteriser threads"),
    Row("lanekeep", {"LANEKEEP_THREADS": "1"}, "detectors on one thread (one core)"),
    Row("llvmpipe", {"GALLIUM_OVERRIDE_CPU_CAPS": "sse4.1"}, "a CPU without AVX2 and FMA",
        "outside"),
)


@dataclass(frozen=True)
class Outcome:
    """A row's golden check: identical or the first differing stage, and what the check said
    of the settings."""

    row: Row
    identical: bool
    first_difference: str = ""
    settings_named: str = ""
    detail: list[str] = field(default_factory=list)

    @property
    def as_expected(self) -> bool:
        """`cpu` rows must be identical; `outside` rows must differ and be named; `pin` rows
        are informative, but a difference must be named."""
        if self.row.kind == "cpu":
            return self.identical
        if self.row.kind == "outside":
            return not self.identical and bool(self.settings_named)
        return self.identical or bool(self.settings_named)


def pinned_environment(base: dict[str, str] | None = None) -> dict[str, str]:
    """`base` (default: this process's environment) without any kernel-choosing variable, so
    that a child's `import lanekeep` sets the pins."""
    env = dict(os.environ if base is None else base)
    for key in (*KERNEL_ENV, *EXTRA_KERNEL_ENV):
        env.pop(key, None)
    return env


_STAGE = re.compile(r"stage hashes differ from (step \d+, stage [^(]+?)\s*(\(|$)")
_SETTINGS = "settings differ from the golden file's in: "


class GoldenUnavailable(RuntimeError):
    """The golden files cannot be compared here (made with other library versions, exit 3)."""


def parse_check(row: Row, returncode: int, stdout: str, stderr: str) -> Outcome:
    """An `Outcome` from `tools/golden.py --check`'s output."""
    if returncode == 3:  # the row changed what the check counts as a library version
        if not row.env:
            raise GoldenUnavailable(stderr.strip())
        why = stderr.strip().split("library versions: ", 1)[-1].split(". Their bits")[0]
        return Outcome(row, False, "", f"not compared, other versions: {why}",
                       stderr.splitlines())
    if returncode not in (0, 1):
        raise RuntimeError(f"golden check for {row.setting} ended with exit {returncode}: "
                           + (stderr.strip().splitlines() or ["(no output)"])[-1])
    lines = stdout.splitlines()
    first = next((m.group(1).strip() for line in lines if (m := _STAGE.search(line))), "")
    named = next((line.split(_SETTINGS, 1)[1].strip() for line in lines if _SETTINGS in line),
                 "")
    return Outcome(row, returncode == 0, first, named, lines)


def run_row(row: Row, golden_tool: Path, only: Sequence[str] = (),
            python: str = sys.executable) -> Outcome:
    """One row: the golden check as its own process with the row's variables."""
    env = {**pinned_environment(), **row.env}
    args = [python, str(golden_tool), "--check", *(["--only", *only] if only else [])]
    done = subprocess.run(args, env=env, capture_output=True, text=True, timeout=1800,
                          cwd=golden_tool.parent.parent)
    return parse_check(row, done.returncode, done.stdout, done.stderr)


def run_matrix(rows: Sequence[Row], golden_tool: Path, only: Sequence[str] = (),
               on_row: Callable[[Outcome], None] | None = None,
               python: str = sys.executable) -> list[Outcome]:
    """Every row in turn (each a process of its own: the variables are read at load)."""
    out = []
    for row in rows:
        outcome = run_row(row, golden_tool, only, python)
        out.append(outcome)
        if on_row is not None:
            on_row(outcome)
    return out


def result_text(outcome: Outcome) -> str:
    if outcome.identical:
        return "identical"
    text = f"differs from {outcome.first_difference}" if outcome.first_difference else "differs"
    return text + (f"; named: {outcome.settings_named}" if outcome.settings_named else "")


def markdown_table(outcomes: Sequence[Outcome]) -> str:
    lines = ["| library | setting | stands for | kind | golden runs | as expected |",
             "|---|---|---|---|---|---|"]
    for o in outcomes:
        lines.append(f"| {o.row.library} | `{o.row.setting}` | {o.row.stands_for} | "
                     f"{o.row.kind} | {result_text(o)} | {'yes' if o.as_expected else 'NO'} |")
    return "\n".join(lines)
