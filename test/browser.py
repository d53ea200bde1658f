"""Render a page in a real headless Chromium and ask it questions (Chrome DevTools Protocol)."""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def evaluate_in_page(page: Path, expression: str, timeout_s: float = 60.0):
    """Open ``page`` in headless Chromium, wait for it to load, return ``expression``'s value."""
    from websockets.sync.client import connect

    profile = tempfile.mkdtemp(prefix="mt_chromium_")
    process = subprocess.Popen(
        [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", f"--user-data-dir={profile}", "--remote-debugging-port=0",
         "--window-size=1280,900", page.resolve().as_uri()],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + timeout_s
        port = None
        while port is None and time.monotonic() < deadline:
            line = process.stderr.readline()
            match = re.search(r"DevTools listening on ws://[^:]+:(\d+)/", line)
            port = int(match.group(1)) if match else None
        assert port, "Chromium did not open its DevTools port"
        target = None
        while target is None and time.monotonic() < deadline:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list") as answer:
                pages = [t for t in json.load(answer) if t.get("type") == "page"]
            target = pages[0]["webSocketDebuggerUrl"] if pages else None
        with connect(target, max_size=None) as socket:
            ident = 0

            def call(text: str):
                nonlocal ident
                ident += 1
                socket.send(json.dumps({"id": ident, "method": "Runtime.evaluate", "params": {
                    "expression": text, "returnByValue": True, "awaitPromise": True}}))
                while True:
                    reply = json.loads(socket.recv(timeout=timeout_s))
                    if reply.get("id") == ident:
                        return reply["result"]["result"].get("value")

            # The first page may still be about:blank, navigating to ours: wait for ours,
            # loaded, and ask again if a navigation swept the answer away.
            ready = f"{page.resolve().as_uri()}|complete"
            while time.monotonic() < deadline:
                if call("location.href + '|' + document.readyState") == ready:
                    value = call(expression)
                    if value is not None:
                        return value
                time.sleep(0.1)
            raise AssertionError(f"{page} did not load in Chromium within {timeout_s} s")
    finally:
        process.kill()
        process.wait()
        shutil.rmtree(profile, ignore_errors=True)


#: The page's images and headings, as the browser sees them.
PAGE_FACTS = """JSON.stringify({
  images: Array.from(document.images).map(i => ({src: i.getAttribute('src'),
      loaded: i.complete && i.naturalWidth > 0, width: i.naturalWidth})),
  sections: Array.from(document.querySelectorAll('section > h2')).map(h => h.textContent),
  rejected: document.querySelectorAll('tr.rejected').length,
  width: document.documentElement.scrollWidth
})"""


def page_facts(page: Path) -> dict:
    return json.loads(evaluate_in_page(page, PAGE_FACTS))


def validate_html(page: Path) -> None:
    """Raise if the HTML has any parse error (the HTML5 parsing algorithm, strict)."""
    import html5lib

    html5lib.HTMLParser(strict=True).parse(page.read_bytes())
