"""Headless Chromium driven over the Chrome DevTools Protocol, through the pipe Chromium opens with
--remote-debugging-pipe (NUL-terminated JSON messages: commands on file descriptor 3, answers on 4): a page
is opened, its elements are clicked where they show, and the page is read back with JavaScript and
screenshots. Nothing but the standard library and Chromium."""
from __future__ import annotations

import base64
import json
import os
import select
import subprocess
import time


class Browser:
    """One headless Chromium with one page of `width` x `height` CSS pixels; a context manager."""

    def __init__(self, exe: str, flags: tuple[str, ...], profile, width=1400, height=1000, timeout=60.0):
        # the pipe to the browser first: its read end is the lowest descriptor and the other pipe's write end
        # the highest (at least 6), so moving them to 3 and 4 overwrites no descriptor still to be moved
        to_browser, self._out = os.pipe()
        self._in, from_browser = os.pipe()

        def descriptors_3_and_4():
            os.dup2(to_browser, 3)
            os.dup2(from_browser, 4)

        self.proc = subprocess.Popen([exe, *flags, "--remote-debugging-pipe", f"--user-data-dir={profile}",
                                      "about:blank"], pass_fds=(3, 4), preexec_fn=descriptors_3_and_4,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser)
        os.close(from_browser)
        self.timeout, self._buffer, self._id, self.session = timeout, b"", 0, None
        target = self.send("Target.createTarget", url="about:blank")["targetId"]
        self.session = self.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        self.send("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                  mobile=False)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.proc.kill()
        self.proc.wait()
        os.close(self._in)
        os.close(self._out)

    def send(self, method: str, **params) -> dict:
        """One protocol command (on the page once attached); its result. Events are read past."""
        self._id += 1
        message = {"id": self._id, "method": method, "params": params}
        if self.session:
            message["sessionId"] = self.session
        os.write(self._out, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            while b"\0" not in self._buffer:
                left = deadline - time.monotonic()
                assert left > 0 and select.select([self._in], [], [], left)[0], f"no answer to {method}"
                chunk = os.read(self._in, 1 << 20)
                assert chunk, f"chromium closed the pipe ({method})"
                self._buffer += chunk
            raw, self._buffer = self._buffer.split(b"\0", 1)
            answer = json.loads(raw)
            if answer.get("id") == self._id:
                assert "error" not in answer, (method, answer["error"])
                return answer["result"]

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page."""
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        assert "exceptionDetails" not in result, (expression, result["exceptionDetails"])
        return result["result"].get("value")

    def wait_for(self, expression: str, what: str):
        """Poll a JavaScript expression until its value is truthy; that value (fails naming `what`)."""
        deadline = time.monotonic() + self.timeout
        while not (value := self.evaluate(expression)):
            assert time.monotonic() < deadline, f"timed out waiting for {what}"
            time.sleep(0.1)
        return value

    def open(self, url: str, ready: str):
        """Load `url` and wait until the JavaScript expression `ready` holds."""
        self.send("Page.navigate", url=url)
        self.wait_for(f"document.readyState === 'complete' && !!({ready})", f"{url} to load")

    def click(self, element: str, what: str):
        """Click the element a JavaScript expression finds, once it shows (scrolled into view, the topmost
        element at its centre); fails naming `what` if it does not. The click event is dispatched on the element
        by JavaScript, not sent as mouse input: one run clicking with Input.dispatchMouseEvent lost a click."""
        self.wait_for(
            f"(() => {{ const el = {element}; if (!el) return false; el.scrollIntoView({{block: 'center'}});"
            " const r = el.getBoundingClientRect();"
            " if (!el.contains(document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2))) return false;"
            " el.click(); return true; })()", f"{what} to click")

    def screenshot(self, clip: dict) -> bytes:
        """PNG of the region `clip` {x, y, width, height} of the page, in CSS pixels."""
        return base64.b64decode(self.send("Page.captureScreenshot", format="png", clip={**clip, "scale": 1})["data"])
