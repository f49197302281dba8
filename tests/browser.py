"""A real browser for the book's test: headless Chromium driven over the DevTools protocol
(websocket-client).

:func:`find_chromium` finds the executable (``REPLICATION_CHROMIUM``, else ``chromium`` on the
path); :class:`Chromium` starts it with a fresh profile and the flags a machine without network
needs; :func:`serve` serves a folder on loopback; :meth:`Chromium.check_page` loads a page and
returns every problem a reader would meet: a console error or uncaught exception (a resource that
fails to load is logged as one), an image that did not load (``naturalWidth`` 0), a local link whose
page is missing or whose ``#anchor`` names no element of that page.
"""
from __future__ import annotations

import base64
import contextlib
import functools
import http.server
import json
import os
import shutil
import subprocess
import tempfile
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from html.parser import HTMLParser
from pathlib import Path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-extensions",
         "--remote-debugging-port=0", "--window-size=1280,900"]


def find_chromium() -> str | None:
    """The Chromium executable: ``REPLICATION_CHROMIUM`` (an executable path or name), else
    ``chromium`` or ``chromium-browser`` on the path; ``None`` if there is none."""
    given = os.environ.get("REPLICATION_CHROMIUM")
    if given:
        return shutil.which(given)
    return shutil.which("chromium") or shutil.which("chromium-browser")


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@contextlib.contextmanager
def serve(folder):
    """Serve ``folder`` on 127.0.0.1 (a free port) in a thread; yields the base URL, ending in
    ``/``."""
    handler = functools.partial(_Quiet, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


class _Ids(HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids = set()

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name == "id" or (tag == "a" and name == "name"):
                self.ids.add(value)


class Chromium:
    """Headless Chromium with a fresh profile, driven over the DevTools protocol; a context manager
    that ends the process it started."""

    def __init__(self, executable: str, *, timeout: float = 30.0):
        self.executable, self.timeout = executable, timeout
        self._next_id, self._events, self._pages = 0, [], {}

    def __enter__(self):
        import websocket  # websocket-client (the docs extra); imported here so that collecting this file needs nothing

        self._profile = tempfile.mkdtemp(prefix="replication-chromium-")
        self._process = subprocess.Popen([self.executable, *FLAGS, f"--user-data-dir={self._profile}", "about:blank"],
                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port_file = Path(self._profile) / "DevToolsActivePort"
        deadline = time.monotonic() + self.timeout
        while not (port_file.exists() and len(port_file.read_text().splitlines()) >= 2):
            if self._process.poll() is not None or time.monotonic() > deadline:
                self.__exit__(None, None, None)
                raise RuntimeError(f"{self.executable} did not start (exit code {self._process.returncode}) within "
                                   f"{self.timeout:g} s")
            time.sleep(0.05)
        port = int(port_file.read_text().splitlines()[0])
        targets = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10).read())
        page = next(t for t in targets if t["type"] == "page")
        self._socket = websocket.create_connection(page["webSocketDebuggerUrl"], timeout=self.timeout,
                                                   suppress_origin=True)
        for domain in ("Page", "Runtime", "Log"):
            self.send(f"{domain}.enable")
        self.send("Emulation.setDeviceMetricsOverride", width=1280, height=900, deviceScaleFactor=1, mobile=False)
        return self

    def __exit__(self, *exc):
        with contextlib.suppress(Exception):
            self._socket.close()
        if self._process.poll() is None:
            self._process.terminate()
            try:
                self._process.wait(10)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        shutil.rmtree(self._profile, ignore_errors=True)

    def send(self, method: str, **params) -> dict:
        """Send one command and return its result; the events received meanwhile are kept."""
        self._next_id += 1
        self._socket.send(json.dumps({"id": self._next_id, "method": method, "params": params}))
        while True:
            message = json.loads(self._socket.recv())
            if message.get("id") == self._next_id:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self._events.append(message)

    def _wait_for(self, event: str) -> None:
        deadline = time.monotonic() + self.timeout
        while not any(e.get("method") == event for e in self._events):
            if time.monotonic() > deadline:
                raise RuntimeError(f"no {event} within {self.timeout:g} s")
            self._events.append(json.loads(self._socket.recv()))

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page (a promise is awaited)."""
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression[:60]}...: {result['exceptionDetails']}")
        return result["result"].get("value")

    def _ids_of(self, page_url: str):
        """The ids of a served page, or None if it cannot be fetched."""
        if page_url not in self._pages:
            try:
                with urllib.request.urlopen(page_url, timeout=10) as response:
                    parser = _Ids()
                    parser.feed(response.read().decode("utf-8", "replace"))
                    self._pages[page_url] = parser.ids
            except (urllib.error.URLError, OSError):
                self._pages[page_url] = None
        return self._pages[page_url]

    def check_page(self, url: str, *, settle: float = 0.3) -> tuple[list[str], list[str]]:
        """Load ``url``; return ``(problems, local pages it links to)``. Problems: console errors
        and uncaught exceptions, images that did not load, local links to a missing page or a
        missing ``#anchor``."""
        self._events.clear()
        self.send("Page.navigate", url=url)
        self._wait_for("Page.loadEventFired")
        # every image loaded (a lazy one too), then a moment for late console messages
        broken = self.evaluate("""(async () => {
            const imgs = Array.from(document.images);
            imgs.forEach(i => { i.loading = 'eager'; });
            await Promise.all(imgs.map(i => i.complete ? null : new Promise(r => { i.onload = i.onerror = r; })));
            return imgs.filter(i => i.naturalWidth === 0).map(i => i.getAttribute('src'));
        })()""")
        time.sleep(settle)
        self.send("Runtime.evaluate", expression="0")  # collects the events that arrived meanwhile
        problems = [f"image not loaded: {src}" for src in broken]
        for event in self._events:
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                text = " ".join(str(a.get("value", a.get("description", ""))) for a in params.get("args", []))
                problems.append(f"console error: {text}")
            elif method == "Runtime.exceptionThrown":
                details = params.get("exceptionDetails", {})
                problems.append("uncaught exception: "
                                + str(details.get("exception", {}).get("description", details.get("text"))))
            elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
                entry = params["entry"]
                problems.append(f"console error: {entry.get('text')} {entry.get('url', '')}".rstrip())
        origin = "{0.scheme}://{0.netloc}".format(urllib.parse.urlsplit(url))
        hrefs = self.evaluate("Array.from(document.querySelectorAll('a[href]')).map(a => a.href)")
        pages = []
        for href in sorted(set(hrefs)):
            if not href.startswith(origin + "/"):
                continue
            page, _, anchor = href.partition("#")
            ids = self._ids_of(page)
            if ids is None:
                problems.append(f"link to a missing page: {href}")
                continue
            if anchor and urllib.parse.unquote(anchor) not in ids:
                problems.append(f"link to a missing anchor: {href}")
            pages.append(page)
        return problems, sorted(set(pages))

    def screenshot(self, path) -> None:
        """A PNG of the current page's first screen, written atomically."""
        from replication._io import write_atomic

        write_atomic(Path(path), base64.b64decode(self.send("Page.captureScreenshot", format="png")["data"]))
