"""Headless Chromium driven over the DevTools protocol, with no package beyond the standard library.

Chromium is started with ``--remote-debugging-pipe``: it reads protocol
messages (JSON, each ended by a NUL byte) on file descriptor 3 and writes on 4.
:func:`render` opens each URL in a fresh tab, waits for the load event and a
quiet moment, and returns the screenshot with everything that went wrong: console
errors, uncaught exceptions, failed requests and requests that left the machine.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from typing import Any

__all__ = ["CHROMIUM", "Page", "render"]

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
"""Debian's ``chromium`` package, if installed."""

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
    "--remote-debugging-pipe",
)


@dataclass
class Page:
    """What one URL rendered to."""

    url: str
    screenshot: bytes = b""
    title: str = ""
    heading: str = ""
    errors: list[str] = field(default_factory=list)
    outside_requests: list[str] = field(default_factory=list)


class _Pipe:
    def __init__(self, write_fd: int, read_fd: int) -> None:
        self.write_fd, self.read_fd = write_fd, read_fd
        self.buffer = b""
        self.next_id = 0
        self.events: list[dict[str, Any]] = []

    def send(
        self, method: str, params: dict[str, Any] | None = None, session: str | None = None
    ) -> Any:
        self.next_id += 1
        message: dict[str, Any] = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self.write_fd, json.dumps(message).encode() + b"\0")
        while True:
            reply = self._receive(timeout=30.0)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def _receive(self, timeout: float) -> dict[str, Any]:
        deadline = time.monotonic() + timeout
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.read_fd], [], [], left)[0]:
                raise TimeoutError("Chromium did not answer")
            chunk = os.read(self.read_fd, 1 << 16)
            if not chunk:
                raise RuntimeError("Chromium closed the pipe")
            self.buffer += chunk
        raw, self.buffer = self.buffer.split(b"\0", 1)
        return dict(json.loads(raw))

    def wait_for(self, method: str, session: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while not any(
            e.get("method") == method and e.get("sessionId") == session for e in self.events
        ):
            self.events.append(self._receive(max(0.01, deadline - time.monotonic())))

    def drain(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            try:
                self.events.append(self._receive(deadline - time.monotonic()))
            except TimeoutError:
                return


def _high(fd: int) -> int:
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
    os.close(fd)
    return moved


def _problems(
    events: list[dict[str, Any]], session: str, origin: str
) -> tuple[list[str], list[str]]:
    errors, outside = [], []
    for event in events:
        if event.get("sessionId") != session:
            continue
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            errors.append(
                f"exception: {details.get('exception', {}).get('description') or details.get('text')}"
            )
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            args = " ".join(
                str(a.get("value", a.get("description", ""))) for a in params.get("args", [])
            )
            errors.append(f"console.{params['type']}: {args}")
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            entry = params["entry"]
            errors.append(
                f"log ({entry.get('source')}): {entry.get('text')} {entry.get('url', '')}".strip()
            )
        elif method == "Network.loadingFailed" and not params.get("canceled"):
            errors.append(f"request failed: {params.get('errorText')}")
        elif method == "Network.requestWillBeSent":
            url = params.get("request", {}).get("url", "")
            if url.startswith(("http:", "https:", "ws:", "wss:")) and not url.startswith(origin):
                outside.append(url)
    return errors, outside


def render(
    urls: list[str], width: int = 1280, height: int = 900, settle: float = 1.0
) -> list[Page]:
    """Open each URL in headless Chromium; its screenshot and what went wrong."""
    if CHROMIUM is None:
        raise RuntimeError("Chromium is not installed")
    to_chrome_r, to_chrome_w = (_high(fd) for fd in os.pipe())
    from_chrome_r, from_chrome_w = (_high(fd) for fd in os.pipe())

    def wire() -> None:  # in the child: its fd 3 reads our commands, fd 4 writes its answers
        os.dup2(to_chrome_r, 3)
        os.dup2(from_chrome_w, 4)

    with tempfile.TemporaryDirectory() as profile:
        process = subprocess.Popen(
            [CHROMIUM, *FLAGS, f"--user-data-dir={profile}", f"--window-size={width},{height}"],
            pass_fds=(3, 4, to_chrome_r, from_chrome_w),
            preexec_fn=wire,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        pipe = _Pipe(to_chrome_w, from_chrome_r)
        pages = []
        try:
            for url in urls:
                origin = url.split("/", 3)
                target = pipe.send("Target.createTarget", {"url": "about:blank"})["targetId"]
                session = pipe.send("Target.attachToTarget", {"targetId": target, "flatten": True})[
                    "sessionId"
                ]
                for domain in ("Runtime", "Log", "Page", "Network"):
                    pipe.send(f"{domain}.enable", session=session)
                pipe.send(
                    "Emulation.setDeviceMetricsOverride",
                    {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
                    session=session,
                )
                pipe.send("Page.navigate", {"url": url}, session=session)
                pipe.wait_for("Page.loadEventFired", session, timeout=30.0)
                pipe.drain(settle)
                page = Page(url)

                def evaluate(expression: str, session: str = session) -> str:
                    result = pipe.send(
                        "Runtime.evaluate",
                        {"expression": expression, "returnByValue": True},
                        session=session,
                    )
                    return str(result.get("result", {}).get("value", ""))

                page.title = evaluate("document.title")
                page.heading = evaluate(
                    "(document.querySelector('article h1') || {}).textContent || ''"
                )
                shot = pipe.send("Page.captureScreenshot", {"format": "png"}, session=session)
                page.screenshot = base64.b64decode(shot["data"])
                page.errors, page.outside_requests = _problems(
                    pipe.events, session, "/".join(origin[:3]) + "/"
                )
                pipe.send("Target.closeTarget", {"targetId": target})
                pages.append(page)
            with contextlib.suppress(RuntimeError, TimeoutError):
                pipe.send("Browser.close")
        finally:
            os.close(to_chrome_w)
            os.close(from_chrome_r)
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
    return pages
