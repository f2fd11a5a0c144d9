"""`lanekeep view FILE.rrd [--web] [--port N]`: open a recording in rerun's viewer.

Native: the viewer binary that ships with rerun-sdk (`python -m rerun`), in a window; it needs
a display. `--web`: the same binary serves its web viewer and a gRPC proxy, bound to
127.0.0.1 only (a recording shows the scenario and its camera images: nothing for other
hosts); this command then sends the recording into that proxy as an SDK client would, and
prints the URL to open; Ctrl-C stops it. The recording carries its own blueprint
(lanekeep/report/record.py), so both open on the same layout.

Why the file is not handed to the binary (`rerun --serve-web FILE.rrd`): rerun's proxy then
reads the file through a receiver set whose loop never notices that the file's source has run
dry, and spins a core for as long as it serves (measured: 88-98 % of a core with no browser
connected, rerun 0.41; see rerun's `re_grpc_server::spawn_from_rx_set`). Sent over gRPC, the
proxy only keeps the messages for the viewers that connect, and idles.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import quote

from lanekeep.core.config_io import ConfigError

RRD_MAGIC = b"RRF"  # every .rrd begins with "RRF" and a format digit ("RRF2" in rerun 0.41)
HOST = "127.0.0.1"
START_TIMEOUT_S = 30.0
RENDERER = "webgl"  # the web viewer's `renderer` URL parameter: webgl or webgpu


def check_recording(path: Path) -> None:
    """One clear error for a path that is not a rerun recording (before starting a viewer)."""
    if not path.exists():
        raise ConfigError(str(path), "", "no such file")
    if not path.is_file():
        raise ConfigError(str(path), "", "not a file")
    with path.open("rb") as f:
        head = f.read(len(RRD_MAGIC))
    if head != RRD_MAGIC:
        raise ConfigError(str(path), "", "not a rerun recording (.rrd): it does not begin "
                                         "with rerun's header (write one with `lanekeep run "
                                         "SCENARIO --record FILE.rrd`)")


def grpc_url(grpc_port: int) -> str:
    """The proxy's address, as rerun's SDK and viewer spell it."""
    return f"rerun+http://{HOST}:{grpc_port}/proxy"


def web_url(web_port: int, grpc_port: int) -> str:
    """The address that opens the web viewer on the served recording. WebGL, not the default
    WebGPU: headless and software-GL browsers (Chromium with SwiftShader) crash on WebGPU."""
    return (f"http://{HOST}:{web_port}/?url=" + quote(grpc_url(grpc_port), safe="")
            + f"&renderer={RENDERER}")


def _listening(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.5)
        return s.connect_ex((HOST, port)) == 0


def _port_free(port: int) -> bool:
    with socket.socket() as s:
        try:
            s.bind((HOST, port))
        except OSError:
            return False
    return True


def _viewer_command(*args: str) -> list[str]:
    return [sys.executable, "-m", "rerun", *args]


def server_memory_limit(path: Path) -> str:
    """What the proxy may buffer: at least rerun's default (1 GiB), and room for the whole
    recording twice over, so that a viewer opened late still gets its beginning."""
    return f"{max(1024, math.ceil(2 * path.stat().st_size / 2**20))}MiB"


def send_recording(path: Path, grpc_port: int) -> None:
    """Send the recording's messages (its blueprint included) to the proxy, then hang up."""
    import rerun as rr

    rec = rr.RecordingStream("lanekeep-view")
    rec.connect_grpc(grpc_url(grpc_port))
    rr.log_file_from_path(path, recording=rec)
    rec.flush()
    rec.disconnect()


def serve_web(path: Path, web_port: int, grpc_port: int) -> int:
    """Serve the web viewer and the recording until the viewer exits or Ctrl-C."""
    for port, option in ((web_port, "--port"), (grpc_port, "--grpc-port")):
        if not _port_free(port):
            raise ConfigError(option, str(port), f"port {port} on {HOST} is in use")
    proc = subprocess.Popen(
        _viewer_command("--serve-web", "--bind", HOST, "--web-viewer-port", str(web_port),
                        "--port", str(grpc_port),
                        "--server-memory-limit", server_memory_limit(path)),
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        start_new_session=True)  # its own group: `python -m rerun` runs the viewer binary
    try:
        end = time.monotonic() + START_TIMEOUT_S
        while not (_listening(web_port) and _listening(grpc_port)):
            if proc.poll() is not None:
                lines = [ln for ln in proc.stderr.read().splitlines() if ln.strip()]
                raise RuntimeError("the rerun web viewer did not start: "
                                   + (lines[-1] if lines else f"exit {proc.returncode}"))
            if time.monotonic() > end:
                raise RuntimeError(f"the rerun web viewer did not listen on {HOST}:{web_port} "
                                   f"within {START_TIMEOUT_S:g} s")
            time.sleep(0.2)
        proc.stderr.close()  # rerun logs on; nobody reads it now
        send_recording(path, grpc_port)
        print(web_url(web_port, grpc_port), flush=True)
        print(f"serving {path} on {HOST} only; Ctrl-C stops", file=sys.stderr, flush=True)
        return 0 if proc.wait() == 0 else 1
    finally:
        _stop_group(proc)


def _stop_group(proc: subprocess.Popen) -> None:
    """Stop the viewer and the binary `python -m rerun` started under it: terminating the
    wrapper alone left the web viewer serving (and spinning a core) after we exited."""
    for sig, wait_s in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            return  # the whole group is gone
        try:
            proc.wait(timeout=wait_s)
        except subprocess.TimeoutExpired:
            continue
        if sig == signal.SIGTERM:
            time.sleep(0.2)  # the binary ends after its wrapper; a last SIGKILL finds none


def open_native(path: Path) -> int:
    """The native viewer in a window (blocks until it is closed)."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        raise ConfigError("view", "", "no display for the native viewer (neither DISPLAY nor "
                                      "WAYLAND_DISPLAY is set): use --web and open its URL")
    return 0 if subprocess.call(_viewer_command(str(path))) == 0 else 1


def _cmd_view(args: argparse.Namespace) -> int:
    path = Path(args.file)
    check_recording(path)
    for option, port in (("--port", args.port), ("--grpc-port", args.grpc_port)):
        if not 1 <= port <= 65535:
            raise ConfigError(option, str(port), "must be a port number, 1..65535")
    if args.web:
        return serve_web(path, args.port, args.grpc_port)
    return open_native(path)


def register(sub) -> None:
    p = sub.add_parser("view", help="open a recording (.rrd) in rerun's viewer (--web: a web "
                                    "viewer on 127.0.0.1)", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="a recording written by `lanekeep run --record FILE.rrd`")
    p.add_argument("--web", action="store_true",
                   help="serve the web viewer on 127.0.0.1 and print its URL")
    p.add_argument("--port", type=int, default=9090,
                   help="port of the web viewer with --web (default 9090)")
    p.add_argument("--grpc-port", type=int, default=9876,
                   help="port the recording is served on with --web (default 9876)")
    p.set_defaults(func=_cmd_view)
