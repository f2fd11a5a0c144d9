"""The kernel pins (lanekeep/core/reproducibility.py): set before the libraries load, the
user's own values kept, reported in every document, and what makes two reports incomparable."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from lanekeep.core import reproducibility as repro
from lanekeep.core.reproducibility import (
    kernel_differences,
    library_versions,
    setting_details,
)
from lanekeep.report.json_io import with_metadata
from lanekeep.scenario.schema import load_scenario

SKX = {"avx2", "fma", "avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"}


def test_opencv_is_told_to_skip_only_the_avx512_targets_this_cpu_has():
    assert repro.opencv_disable({"avx2", "fma"}) == ""  # OpenCV warns on names a CPU lacks
    assert repro.opencv_disable(SKX) == "AVX512F,AVX512-COMMON,AVX512-SKX"
    assert repro.opencv_disable(SKX | {"avx512_vnni"}).endswith("AVX512-SKX,AVX512-CLX")


def _clear(monkeypatch):
    for key in [*repro.PINNED, "OPENCV_CPU_DISABLE", repro.PIN_ENV]:
        monkeypatch.delenv(key, raising=False)


def test_pin_sets_every_variable_and_keeps_the_users_own(monkeypatch):
    _clear(monkeypatch)
    monkeypatch.setenv("ONEDNN_MAX_CPU_ISA", "SSE41")
    repro.pin_kernels()
    assert os.environ["ONEDNN_MAX_CPU_ISA"] == "SSE41"
    for key, value in repro.PINNED.items():
        if key != "ONEDNN_MAX_CPU_ISA":
            assert os.environ[key] == value


def test_pin_can_be_turned_off(monkeypatch):
    _clear(monkeypatch)
    monkeypatch.setenv(repro.PIN_ENV, "0")
    repro.pin_kernels()
    assert not any(key in os.environ for key in repro.PINNED)


def _settings_in_a_fresh_process(first_import: str) -> dict:
    code = (f"import {first_import}; import lanekeep, json; "
            "from lanekeep.core.reproducibility import settings_now; "
            "print(json.dumps(settings_now(renderer=False)))")
    env = {k: v for k, v in os.environ.items() if k not in repro.PINNED and k != repro.PIN_ENV}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=120, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_import_lanekeep_first_pins_numpy_torch_and_the_blas():
    settings = _settings_in_a_fresh_process("sys")
    assert settings["pinned"] is True and settings["loaded_before_pin"] == []
    assert not [t for t in settings["numpy"]["simd"] if "512" in t or t == "X86_V4"]
    assert settings["numpy"]["blas_core"] == "Haswell"
    assert settings["torch"]["cpu_capability"] in ("AVX2", "DEFAULT")
    assert settings["opencv"]["avx512"] is False
    assert settings["env"]["ONEDNN_MAX_CPU_ISA"] == "AVX2"
    # MKL in its reproducible mode: Intel's AVX2 branch; an AMD CPU reads it as AUTO
    assert settings["torch"]["mkl_branch"] in ("AVX2,STRICT", "AUTO,STRICT")
    assert settings["torch"]["conv_path"] == "aten+mkl"  # oneDNN out of LaneNet's forward
    assert settings["cpu_avx2_fma"] is True


def test_numpy_loaded_before_lanekeep_is_reported_as_unpinned():
    settings = _settings_in_a_fresh_process("numpy")
    assert settings["pinned"] is False
    assert settings["loaded_before_pin"] == ["numpy"]


def _import_warnings(code: str, **env_changes: str) -> str:
    env = {k: v for k, v in os.environ.items() if k not in repro.PINNED and k != repro.PIN_ENV}
    env.update(env_changes)
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=120, check=True)
    return done.stderr


def test_numpy_before_lanekeep_warns_once_naming_it_and_lanekeep_first_is_quiet():
    """numpy read its variables before the pin: the user's episodes would silently differ
    from the CLI's (one line, pointing at their import)."""
    late = _import_warnings("import numpy\nimport lanekeep")
    assert late.count("RuntimeWarning") == 1 and "numpy loaded before lanekeep" in late, late
    assert "<string>:2" in late  # the user's `import lanekeep` line
    assert "RuntimeWarning" not in _import_warnings("import lanekeep\nimport numpy")
    # unpinned by choice: nothing to warn about
    assert "RuntimeWarning" not in _import_warnings("import numpy\nimport lanekeep",
                                                    **{repro.PIN_ENV: "0"})


def test_numpy_first_with_the_pins_already_in_the_environment_is_pinned_and_quiet():
    """A spawned worker inherits its parent's pins (and a user may export them): numpy read
    the pinned values, whatever the import order."""
    code = ("import numpy\nimport lanekeep, json\n"
            "from lanekeep.core.reproducibility import settings_now\n"
            "print(json.dumps(settings_now(renderer=False)))")
    env = {k: v for k, v in os.environ.items() if k not in repro.PINNED and k != repro.PIN_ENV}
    env.update(repro.PINNED)
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=120, check=True)
    assert "RuntimeWarning" not in done.stderr, done.stderr
    settings = json.loads(done.stdout.strip().splitlines()[-1])
    assert settings["pinned"] is True and settings["loaded_before_pin"] == []
    assert not [t for t in settings["numpy"]["simd"] if "512" in t or t == "X86_V4"]


def test_every_document_carries_its_settings():
    doc = with_metadata({}, load_scenario("clear_straight"))
    assert set(doc["reproducibility"]) >= {"pinned", "renderer", "torch", "opencv", "numpy",
                                           "env"}
    assert isinstance(doc["reproducibility"]["renderer"], str)


def test_reports_differ_in_kernels_but_not_in_thread_counts():
    a = {"pinned": True, "torch": {"cpu_capability": "AVX2", "threads": 1},
         "env": {"LP_NUM_THREADS": "1", "ONEDNN_MAX_CPU_ISA": "AVX2"}}
    threads = {**a, "torch": {"cpu_capability": "AVX2", "threads": 2},
               "env": {"LP_NUM_THREADS": "2", "ONEDNN_MAX_CPU_ISA": "AVX2"}}
    assert kernel_differences(a, threads) == []
    unpinned = {**a, "pinned": False, "torch": {"cpu_capability": "AVX512", "threads": 1}}
    assert kernel_differences(a, unpinned) == ["pinned", "torch"]
    assert kernel_differences(a, None) == []  # a report from before the key
    assert setting_details(a, unpinned) == ["pinned True -> False",
                                           "torch.cpu_capability 'AVX2' -> 'AVX512'"]
    assert setting_details(a, threads) == []


def test_library_versions_name_what_makes_another_computation():
    settings = {"renderer": "llvmpipe (LLVM 15.0.6, 256 bits); 4.5 Mesa 22.3.6",
                "torch": {"version": "2.13.0+cpu", "threads": 1}, "opencv": {"version": "5.0.0"},
                "numpy": {"version": "2.4.6", "simd": ["X86_V3"]}}
    assert library_versions(settings) == {
        "renderer": "llvmpipe (LLVM 15.0.6, 256 bits); 4.5 Mesa 22.3.6",
        "torch": "2.13.0+cpu", "opencv": "5.0.0", "numpy": "2.4.6"}
