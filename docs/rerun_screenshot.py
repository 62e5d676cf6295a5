"""Screenshot a Rerun recording in Rerun's own web viewer, in a headless Chromium.

    python docs/rerun_screenshot.py reports/simulate/sim.rrd docs/figures/rerun_sim.png

Starts ``rerun --web-viewer`` on the recording (loopback ports), opens the viewer in the
Debian ``chromium`` through Playwright (software WebGL, no display needed), waits until the
recording has loaded and been drawn, and saves a PNG through a temporary name. This is how the
README's viewer pictures are made, and a check that a recording opens in the real viewer.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.parse
from pathlib import Path


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port: int, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.2)
    raise TimeoutError(f"nothing listens on port {port} after {timeout:.0f} s")


def screenshot(rrd: Path, out: Path, settle_s: float, size: tuple[int, int]) -> None:
    from playwright.sync_api import sync_playwright

    grpc, web = free_port(), free_port()
    rerun = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    command = [rerun, "--web-viewer", "--web-viewer-port", str(web), "--port", str(grpc), str(rrd)]
    # its own process group: the `rerun` script starts the viewer binary as a child
    server = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    try:
        wait_for_port(web, 30)
        wait_for_port(grpc, 30)
        source = urllib.parse.quote(f"rerun+http://127.0.0.1:{grpc}/proxy", safe="")
        chromium = os.environ.get("PRG_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
        with sync_playwright() as pw:
            browser = pw.chromium.launch(
                executable_path=chromium,
                headless=True,
                args=["--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
            )
            page = browser.new_page(viewport={"width": size[0], "height": size[1]})
            page.goto(f"http://127.0.0.1:{web}/?url={source}")
            time.sleep(settle_s)  # the viewer draws on a canvas: no DOM event says "done"
            tmp = out.with_name(f".{out.name}.tmp.png")
            page.screenshot(path=str(tmp))
            os.replace(tmp, out)
            browser.close()
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(timeout=10)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rrd", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--settle", type=float, default=45.0, help="seconds to let it draw")
    parser.add_argument("--size", default="1400x850", help="viewport WIDTHxHEIGHT")
    args = parser.parse_args()
    if not args.rrd.is_file():
        print(
            f"rerun_screenshot: error: no recording at {args.rrd} (run `make demo`)",
            file=sys.stderr,
        )
        return 2
    width, height = (int(v) for v in args.size.split("x"))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    screenshot(args.rrd, args.out, args.settle, (width, height))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
