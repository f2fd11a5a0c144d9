"""The recording in a real browser: `lanekeep view --web` serves a short recording on 127.0.0.1,
headless Chromium loads the web viewer, and the screenshot must show every panel drawn.

Optional: it needs Debian's `chromium` (`apt-get install -y chromium`), which CI images may
lack; without it the test is skipped with that reason. It drives Chromium through the DevTools
protocol (the `websockets` package) and polls screenshots until the viewer has drawn, since
the viewer's wasm loads asynchronously. Set LANEKEEP_SHOTS=DIR to keep the screenshots.
"""

from __future__ import annotations

import asyncio
import base64
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from helpers import small_scenario_text

from lanekeep.cli import view as cli_view

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (apt-get install -y "
                       "chromium); CI images may lack it, so this test is optional there"),
]
WINDOW = (1600, 1000)
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--hide-scrollbars")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for(url: str, timeout_s: float) -> None:
    end = time.monotonic() + timeout_s
    while True:
        try:
            with urllib.request.urlopen(url, timeout=2):
                return
        except OSError:
            if time.monotonic() > end:
                raise
            time.sleep(0.3)


async def _screenshots(debug_port: int, url: str, out: Path, ready, timeout_s: float):
    """Open `url` in a fresh tab; screenshot every 2 s until `ready(pixels)` or the timeout.
    Returns the last screenshot's pixels (H, W, 3)."""
    import cv2
    import websockets

    request = urllib.request.Request(f"http://127.0.0.1:{debug_port}/json/new?about:blank",
                                     method="PUT")
    with urllib.request.urlopen(request, timeout=10) as response:
        target = json.load(response)
    async with websockets.connect(target["webSocketDebuggerUrl"], max_size=1 << 28) as ws:
        counter = 0

        async def call(method: str, **params):
            nonlocal counter
            counter += 1
            await ws.send(json.dumps({"id": counter, "method": method, "params": params}))
            while True:
                message = json.loads(await ws.recv())
                if message.get("id") == counter:
                    return message.get("result", {})

        await call("Emulation.setDeviceMetricsOverride", width=WINDOW[0], height=WINDOW[1],
                   deviceScaleFactor=1, mobile=False)
        await call("Page.navigate", url=url)
        end, pixels = time.monotonic() + timeout_s, None
        while time.monotonic() < end:
            await asyncio.sleep(2.0)
            shot = await call("Page.captureScreenshot", format="png")
            out.write_bytes(base64.b64decode(shot["data"]))
            pixels = cv2.cvtColor(cv2.imread(str(out)), cv2.COLOR_BGR2RGB)
            if ready(pixels):
                break
        return pixels


def _drawn_share(region: np.ndarray) -> float:
    """Share of a region's pixels that differ from its most common colour (the background)."""
    flat = region.reshape(-1, 3).astype(int)
    keys = flat[:, 0] * 65536 + flat[:, 1] * 256 + flat[:, 2]
    values, counts = np.unique(keys, return_counts=True)
    background = values[np.argmax(counts)]
    bg = np.array([background // 65536, background // 256 % 256, background % 256])
    return float(np.mean(np.abs(flat - bg).sum(axis=1) > 30))


# The blueprint's panels (lanekeep/report/blueprint.py) as fractions of the window (x0, y0, x1, y1),
# inset from their borders: cameras and the 3D follow view on top; the road map over the colour
# key, offsets / errors, probabilities / residuals, car offset / steer / throttle / speed in the
# middle row; events below.
PANELS = {
    "front camera": (0.06, 0.09, 0.27, 0.27),
    "rear camera": (0.39, 0.09, 0.60, 0.27),
    "follow view": (0.70, 0.10, 0.97, 0.27),
    "road map": (0.02, 0.36, 0.16, 0.70),
    "colour key": (0.02, 0.78, 0.16, 0.87),
    "offsets": (0.20, 0.35, 0.45, 0.56),
    "errors": (0.20, 0.64, 0.45, 0.85),
    "probabilities": (0.49, 0.35, 0.72, 0.56),
    "residuals": (0.49, 0.64, 0.72, 0.85),
    "car": (0.76, 0.34, 0.98, 0.42),
    "steer": (0.76, 0.49, 0.98, 0.56),
    "throttle": (0.76, 0.63, 0.98, 0.71),
    "speed": (0.76, 0.77, 0.98, 0.85),
}
# Camera panels must show their image (most pixels drawn), not only the overlays; the map
# draws thin lines on a wide area.
MIN_DRAWN = {"front camera": 0.5, "rear camera": 0.5, "road map": 0.003}


def _panels_drawn(pixels: np.ndarray) -> dict[str, float]:
    h, w = pixels.shape[:2]
    return {name: _drawn_share(pixels[int(y0 * h): int(y1 * h), int(x0 * w): int(x1 * w)])
            for name, (x0, y0, x1, y1) in PANELS.items()}


def test_web_viewer_draws_every_panel(tmp_path):
    from lanekeep.cli.main import main

    small = tmp_path / "small.toml"
    small.write_text(small_scenario_text("clear_curve", 3.0, keep_criteria=True),
                     encoding="utf-8")
    rrd = tmp_path / "short.rrd"
    assert main(["run", str(small), "--seconds", "2", "--record", str(rrd)]) in (0, 1)
    assert rrd.stat().st_size > 0

    web_port, grpc_port, debug_port = _free_port(), _free_port(), _free_port()
    viewer = subprocess.Popen(
        [sys.executable, "-m", "lanekeep.cli", "view", str(rrd), "--web", "--port",
         str(web_port), "--grpc-port", str(grpc_port)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    profile = tempfile.mkdtemp(prefix="lanekeep-chromium-")
    browser = None
    try:
        url_line = viewer.stdout.readline()
        assert url_line.startswith("http://127.0.0.1:"), url_line
        url = url_line.split()[0]
        _wait_for(f"http://127.0.0.1:{web_port}/", 120)  # timeouts here only end a hang
        browser = subprocess.Popen(
            [CHROMIUM, *FLAGS, f"--user-data-dir={profile}",
             f"--remote-debugging-port={debug_port}", f"--window-size={WINDOW[0]},{WINDOW[1]}",
             "about:blank"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _wait_for(f"http://127.0.0.1:{debug_port}/json/version", 120)
        shots = Path(os.environ.get("LANEKEEP_SHOTS", tmp_path))
        shots.mkdir(parents=True, exist_ok=True)
        shot = shots / "viewer.png"

        def ready(pixels: np.ndarray) -> bool:
            drawn = _panels_drawn(pixels)
            return all(drawn[name] > MIN_DRAWN.get(name, 0.01) for name in PANELS)

        pixels = asyncio.run(_screenshots(debug_port, url, shot, ready, timeout_s=360))
        drawn = _panels_drawn(pixels)
        assert all(drawn[name] > MIN_DRAWN.get(name, 0.01) for name in PANELS), (drawn, shot)
    finally:
        for proc in (browser, viewer):
            if proc is not None:
                proc.terminate()
                try:  # `lanekeep view` may take 10 s (SIGTERM, then SIGKILL) to stop its group
                    proc.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    proc.kill()
        shutil.rmtree(profile, ignore_errors=True)
    # Stopping `lanekeep view` stops the viewer binary under it too (once it kept serving).
    deadline = time.monotonic() + 60  # one left serving would serve on: no need to hurry
    while cli_view._listening(web_port) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not cli_view._listening(web_port), "the web viewer outlived `lanekeep view`"
