"""Headless Chromium for the live views' tests and bench: Debian's chromium and
chromium-driver through Selenium, software WebGL2 (SwiftShader).

``browser()`` starts one Chromium (its performance log records every request
the page makes); ``open_page(driver, path)`` loads a saved page and waits for
``window.mechpyLive``; ``network_requests(driver)`` lists the URLs of the
requests since the last call that went beyond the page itself.
"""
from __future__ import annotations

import json
import os
import shutil
import time

CHROMIUM = os.environ.get("MECHPY_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = os.environ.get("MECHPY_CHROMEDRIVER") or shutil.which("chromedriver") or "/usr/bin/chromedriver"

#: software WebGL2 with float render targets (no GPU on the test machines)
FLAGS = ["--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--window-size=1000,800",
         "--disable-background-timer-throttling", "--disable-renderer-backgrounding"]


def available() -> str | None:
    """None when Chromium, its driver and Selenium are here, else what is missing."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (the test extra)"
    for what, path in (("chromium", CHROMIUM), ("chromedriver", DRIVER)):
        if not (path and os.path.exists(path)):
            return f"{what} not found (Debian: apt-get install chromium chromium-driver)"
    return None


def browser():
    """A headless Chromium driven by Selenium (the caller quits it)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in FLAGS:
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"performance": "ALL", "browser": "ALL"})
    # the browser is not under test: none of the sanitizers' preloads (scripts/sanitize.sh)
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "ASAN_OPTIONS")}
    return webdriver.Chrome(service=Service(DRIVER, env=env), options=opts)


def wait_for(driver, script: str, timeout: float = 30.0):
    """Poll ``return <script>`` until it is truthy; its value."""
    t0 = time.monotonic()
    while True:
        v = driver.execute_script("return " + script)
        if v:
            return v
        if time.monotonic() - t0 > timeout:
            logs = [e["message"] for e in driver.get_log("browser")]
            raise TimeoutError(f"{script!r} stayed false for {timeout} s; console: {logs[-10:]}")
        time.sleep(0.05)


def open_page(driver, path, timeout: float = 60.0):
    """Load a saved page and wait for its live view (the request log starts
    afresh: network_requests then tells this page's own)."""
    driver.get_log("performance")
    driver.get(f"file://{os.path.abspath(path)}")
    wait_for(driver, "window.mechpyLive && window.mechpyLive.ready", timeout)


def network_requests(driver) -> list:
    """URLs requested since the last call, other than the page's own file
    (the driver's current URL), data: and blob: URLs (which never leave the
    browser)."""
    page = driver.current_url
    out = []
    for entry in driver.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg.get("method") != "Network.requestWillBeSent":
            continue
        url = msg["params"]["request"]["url"]
        if url == page or url.split(":", 1)[0] in ("data", "blob", "about"):
            continue
        out.append(url)
    return out
