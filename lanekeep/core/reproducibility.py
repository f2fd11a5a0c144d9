"""What decides the low bits of a result on this machine, and the pins that make two x86-64
machines with AVX2 agree bit for bit.

A closed loop grows a one-ulp difference into another drive within seconds, so a laptop, a CI
runner and a Ray worker give comparable numbers only if every kernel rounds alike. Measured
with tools/stage_hashes.py and tools/dispatch_matrix.py (docs/reproducibility.md): numpy's
AVX-512 loops, OpenBLAS's per-CPU kernels, MKL's per-CPU branches and oneDNN's convolutions
each change a detection. `pin_kernels()` caps numpy, OpenBLAS, OpenCV, ATen and llvmpipe at
AVX2 and puts MKL in its reproducible mode on the AVX2 branch (honoured on Intel CPUs; AMD CPUs
read it as AUTO, which in that mode still fixes cache sizes and reductions), through the
environment variables they read when they load; `import lanekeep` calls it first, so it takes
effect wherever lanekeep is imported before numpy and torch (the CLI, bench workers, Ray
tasks). oneDNN cannot be pinned that way (its kernels' blocking follows the CPU's vendor and
caches, which no variable sets), so `portable_torch()` takes it out of LaneNet's forward:
torch's convolutions then run as ATen's im2col and MKL's GEMM. `LANEKEEP_PIN=0` leaves the
libraries to choose; a variable the user set wins. Every report carries `settings_now()` (its
`reproducibility` key): two reports whose settings differ are not expected to agree to the bit.
"""

from __future__ import annotations

import ctypes
import functools
import os
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

PIN_ENV = "LANEKEEP_PIN"

# The highest ISA every kernel may use: AVX2 (+FMA), which every x86-64 CPU since 2013-2015
# has. Names for numpy 2.4 (X86_V4, AVX512_*) and numpy 1.26 (AVX512F, ...); unknown names
# are ignored by numpy.
PINNED: dict[str, str] = {
    "ONEDNN_MAX_CPU_ISA": "AVX2",          # torch's oneDNN, wherever a caller still uses it
    "MKL_CBWR": "AVX2,STRICT",             # torch's GEMM (LaneNet's convolutions): MKL's AVX2
                                           # branch on Intel, AUTO with fixed cache sizes on AMD;
                                           # STRICT: any thread count and alignment
    "ATEN_CPU_CAPABILITY": "avx2",         # torch's own vectorised ops
    "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR AVX512F AVX512CD AVX512_KNL "
                                "AVX512_KNM AVX512_SKX AVX512_CLX AVX512_CNL",
    "OPENBLAS_CORETYPE": "Haswell",        # numpy's and scipy's BLAS/LAPACK kernels and blocking
    "GALLIUM_OVERRIDE_CPU_CAPS": "avx",    # llvmpipe's shaders: AVX2 at most
    "LP_NATIVE_VECTOR_WIDTH": "256",       # llvmpipe's vector width (its default with AVX)
}
# OpenCV's AVX-512 dispatch targets and the CPU flags (/proc/cpuinfo) each needs. OpenCV warns
# on every import about a name this CPU lacks, so only the ones present are disabled.
_SKX = ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl")
OPENCV_AVX512: dict[str, tuple[str, ...]] = {
    "AVX512F": ("avx512f",),
    "AVX512-COMMON": ("avx512f", "avx512cd"),
    "AVX512-SKX": _SKX,
    "AVX512-CNL": (*_SKX, "avx512ifma", "avx512vbmi"),
    "AVX512-CLX": (*_SKX, "avx512_vnni"),
    "AVX512-ICL": (*_SKX, "avx512ifma", "avx512vbmi", "avx512_vbmi2", "avx512_bitalg",
                   "avx512_vpopcntdq", "avx512_vnni"),
}
CV_CPU_AVX_512F = 13  # cv::CPU_AVX_512F

# The pinned variables numpy and torch read when they load (OpenCV's, OPENCV_CPU_DISABLE,
# exists only where this CPU has AVX-512: `pin_kernels` adds it).
_READ_AT_IMPORT: dict[str, tuple[str, ...]] = {
    "numpy": ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE"),
    "torch": ("ONEDNN_MAX_CPU_ISA", "MKL_CBWR", "ATEN_CPU_CAPABILITY"),
}
# Which libraries had loaded before the pin without their variables set (they read others).
_loaded_before_pin: list[str] = []


def warn_if_loaded_before_pin() -> None:
    """One warning when `import lanekeep` came after numpy, torch or OpenCV with pinning on:
    those already read their variables, so this process computes with the CPU's own kernels
    and its episodes need not match the CLI's or another machine's to the bit (a user's
    `import numpy as np` above `import lanekeep` drove highway_cut_in seed 26 to a fused RMSE
    of 25.51 cm where the CLI gives 25.39). Reports record it too (`loaded_before_pin`)."""
    if not pinning_enabled() or not _loaded_before_pin:
        return
    import warnings

    names = ", ".join(_loaded_before_pin)
    whose = "its" if len(_loaded_before_pin) == 1 else "their"
    warnings.warn(f"lanekeep: {names} loaded before lanekeep, so {whose} kernels are not pinned "
                  "to AVX2 and results may differ from the CLI's and another machine's: import "
                  f"lanekeep first (or set {PIN_ENV}=0 to choose unpinned kernels)",
                  RuntimeWarning, stacklevel=3)


def pinning_enabled() -> bool:
    return os.environ.get(PIN_ENV, "1").strip().lower() not in ("0", "false", "no", "off")


def pin_kernels() -> None:
    """Cap every numeric library at AVX2 (see the module's docstring); the user's own values
    of these variables are kept. Call before numpy, torch, cv2 and the renderer load."""
    if not pinning_enabled():
        return
    opencv = opencv_disable(_cpu_flags())
    reads = {**_READ_AT_IMPORT, "cv2": ("OPENCV_CPU_DISABLE",) if opencv else ()}
    # A library loaded already read its variables: unpinned unless each was set before it
    # loaded (a spawned worker inherits its parent's pins; a user may export them).
    _loaded_before_pin[:] = [m for m, keys in reads.items() if m in sys.modules
                             and any(k not in os.environ for k in keys)]
    for key, value in PINNED.items():
        os.environ.setdefault(key, value)
    if opencv:
        os.environ.setdefault("OPENCV_CPU_DISABLE", opencv)


_TORCH_SWITCH = threading.Lock()


@contextmanager
def portable_torch() -> Iterator[None]:
    """torch's convolutions on a path that every x86-64 CPU computes alike: ATen's im2col and
    MKL's GEMM on its pinned branch, instead of oneDNN, whose kernels and blocking follow the
    CPU (an Intel Xeon and an AMD EPYC, both capped at AVX2, gave other rear-camera detections
    at step 0). torch's switch is process-wide, so the computations that need it hold a lock:
    two at once would restore each other's switch mid-forward. Unpinned (`LANEKEEP_PIN=0`)
    it changes nothing."""
    if not pinning_enabled():
        yield
        return
    import torch

    with _TORCH_SWITCH:
        before = torch.backends.mkldnn.enabled
        torch.backends.mkldnn.enabled = False
        try:
            yield
        finally:
            torch.backends.mkldnn.enabled = before


# MKL's CNR branch codes (mkl_cbwr_get), as named in MKL's documentation.
_MKL_BRANCHES = {0: "OFF", 1: "BRANCH_OFF", 2: "AUTO", 3: "COMPATIBLE", 4: "SSE2",
                 6: "SSSE3", 7: "SSE4_1", 8: "SSE4_2", 9: "AVX", 10: "AVX2", 11: "AVX512_MIC",
                 12: "AVX512", 13: "AVX512_MIC_E1", 14: "AVX512_E1"}
_MKL_STRICT = 0x10000


def mkl_branch() -> str | None:
    """The CNR branch MKL (inside torch) runs on, as MKL reports it, e.g. "COMPATIBLE,STRICT";
    None where torch carries no MKL. A branch that this CPU's vendor does not honour reads
    AUTO (MKL_CBWR=AVX2 on an AMD CPU)."""
    import torch

    path = os.path.join(os.path.dirname(torch.__file__), "lib", "libtorch_cpu.so")
    try:
        get = ctypes.CDLL(path).mkl_serv_cbwr_get
    except (OSError, AttributeError):
        return None
    get.restype = ctypes.c_int
    code = get(ctypes.c_int(-1))  # MKL_CBWR_ALL: the branch and the STRICT flag
    name = _MKL_BRANCHES.get(code & ~_MKL_STRICT, str(code & ~_MKL_STRICT))
    return name + (",STRICT" if code & _MKL_STRICT else "")


def cpu_has_avx2_fma() -> bool:
    """Whether this CPU takes the pinned paths (AVX2 and FMA): one without them computes other
    bits whatever is pinned."""
    flags = _cpu_flags()
    return not flags or {"avx2", "fma"} <= flags


def kernel_env() -> dict[str, str]:
    """The pinning variables as set in this process, for processes that do not inherit its
    environment (Ray workers on other nodes), so that they compute as this one does."""
    keys = [*PINNED, "OPENCV_CPU_DISABLE", PIN_ENV]
    return {k: os.environ[k] for k in keys if k in os.environ}


def _cpu_flags() -> set[str]:
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def opencv_disable(flags: set[str]) -> str:
    """OPENCV_CPU_DISABLE's value for a CPU with these flags: its AVX-512 targets."""
    return ",".join(name for name, needs in OPENCV_AVX512.items()
                    if all(flag in flags for flag in needs))


# Environment variables that choose kernels, read by the libraries when they load.
KERNEL_ENV = ("LP_NATIVE_VECTOR_WIDTH", "LP_NUM_THREADS", "ATEN_CPU_CAPABILITY",
              "ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA", "MKL_ENABLE_INSTRUCTIONS", "MKL_CBWR",
              "OPENCV_CPU_DISABLE", "NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE",
              "OMP_NUM_THREADS", "GALLIUM_OVERRIDE_CPU_CAPS", PIN_ENV)


@functools.cache
def gl_renderer() -> str:
    """The OpenGL renderer and version strings, e.g. "llvmpipe (LLVM 15.0.6, 256 bits); 4.5
    (Compatibility Profile) Mesa 22.3.6": llvmpipe names its LLVM and vector width, the version
    its Mesa. Made from a tiny offscreen context once per process."""
    import mujoco
    from OpenGL import GL

    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    renderer = mujoco.Renderer(model, 8, 8)
    try:
        renderer._gl_context.make_current()
        return (f"{GL.glGetString(GL.GL_RENDERER).decode()}; "
                f"{GL.glGetString(GL.GL_VERSION).decode()}")
    finally:
        renderer.close()


def _numpy_dispatch() -> list[str]:
    """The SIMD targets numpy dispatches to here (its baseline plus the enabled extras)."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # numpy < 2
        from numpy.core import _multiarray_umath as umath
    features = umath.__cpu_features__
    return list(umath.__cpu_baseline__) + [d for d in umath.__cpu_dispatch__ if features.get(d)]


def _openblas_core() -> str | None:
    """The core type OpenBLAS chose (or was told), from the library numpy loaded."""
    import numpy  # noqa: F401 - loads its OpenBLAS

    try:
        with open("/proc/self/maps") as maps:
            paths = {line.split()[-1] for line in maps if "openblas" in line.lower()}
    except OSError:
        return None
    for path in sorted(paths):
        lib = ctypes.CDLL(path)
        for name in ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename",
                     "openblas_get_corename"):
            fn = getattr(lib, name, None)
            if fn is not None:
                fn.restype = ctypes.c_char_p
                return fn().decode()
    return None


def settings_now(renderer: bool = True) -> dict[str, Any]:
    """The settings in effect in this process (what a report's `reproducibility` key holds)."""
    import cv2
    import numpy as np
    import torch

    unpinned = list(_loaded_before_pin)
    out: dict[str, Any] = {
        "pinned": pinning_enabled() and not unpinned,
        "loaded_before_pin": unpinned,
        "renderer": gl_renderer() if renderer else None,
        "cpu_avx2_fma": cpu_has_avx2_fma(),
        "torch": {"version": torch.__version__,
                  "cpu_capability": torch.backends.cpu.get_cpu_capability(),
                  "conv_path": "aten+mkl" if pinning_enabled() else "onednn",
                  "mkl_branch": mkl_branch(),
                  "threads": torch.get_num_threads()},
        "opencv": {"version": cv2.__version__, "optimized": bool(cv2.useOptimized()),
                   "avx512": bool(cv2.checkHardwareSupport(CV_CPU_AVX_512F)),
                   "threads": cv2.getNumThreads()},
        "numpy": {"version": np.__version__, "simd": _numpy_dispatch(),
                  "blas_core": _openblas_core()},
        "env": {k: os.environ[k] for k in KERNEL_ENV if k in os.environ},
    }
    return out


def kernel_differences(a: dict | None, b: dict | None) -> list[str]:
    """Which parts of two `settings_now()` records differ (pinned, cpu_avx2_fma, renderer,
    torch, opencv, numpy, env), thread counts aside; [] when either is missing (a report from
    before them)."""
    if not isinstance(a, dict) or not isinstance(b, dict):
        return []
    return [k for k in ("pinned", "cpu_avx2_fma", "renderer", "torch", "opencv", "numpy", "env")
            if _kernels_only(a.get(k)) != _kernels_only(b.get(k))]


def setting_details(a: dict | None, b: dict | None) -> list[str]:
    """What differs between two `settings_now()` records, key by key, in words ("torch.
    mkl_branch 'AUTO,STRICT' -> 'AVX2,STRICT'"), thread counts aside: the golden check names
    these, so that a machine that computes otherwise says which library chose otherwise."""
    if not isinstance(a, dict) or not isinstance(b, dict):
        return []
    out = []
    for key in ("pinned", "cpu_avx2_fma", "renderer", "torch", "opencv", "numpy", "env"):
        x, y = _kernels_only(a.get(key)), _kernels_only(b.get(key))
        if x == y:
            continue
        if isinstance(x, dict) and isinstance(y, dict):
            out += [f"{key}.{k} {x.get(k)!r} -> {y.get(k)!r}" for k in sorted(set(x) | set(y))
                    if x.get(k) != y.get(k)]
        else:
            out.append(f"{key} {x!r} -> {y!r}")
    return out


def _kernels_only(value: Any) -> Any:
    """A setting without its thread counts: the loop gives the same numbers on any number of
    threads (docs/reproducibility.md), so those do not make two runs incomparable."""
    if isinstance(value, dict):
        return {k: v for k, v in value.items() if k != "threads" and not k.endswith("_THREADS")}
    return value


def library_versions(settings: dict) -> dict[str, Any]:
    """The library versions a `settings_now()` record names: another version of any of them is
    another computation, not a drift (the renderer string holds Mesa's and LLVM's)."""
    return {"renderer": settings.get("renderer"),
            **{lib: (settings.get(lib) or {}).get("version") for lib in ("torch", "opencv",
                                                                           "numpy")}}
