"""The page at `GET /` in a real headless browser (Chromium through Selenium).

Starts the service binary on a free loopback port, opens the page, uploads a dataset
photo through the file input, segments it, and checks what a person would see: numbered
cables drawn over the photo, one table row per cable, the downloads offered, and no
request leaving the service. Then clicks two ends on the photo and segments again with
them. Run by `scripts/browser-test.sh` (part of `make test`):

    python tests/browser/page_test.py BINARY
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

DATASET = Path(os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables"))
PHOTO = DATASET / "simple" / "00000.jpg"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_ready(base: str, server: subprocess.Popen, seconds=60.0):
    end = time.time() + seconds
    while time.time() < end:
        if server.poll() is not None:
            raise SystemExit(f"the service exited with {server.returncode}")
        try:
            with urllib.request.urlopen(f"{base}/readyz", timeout=2) as r:
                if r.status == 200:
                    return
        except OSError:
            pass
        time.sleep(0.2)
    raise SystemExit("the service did not become ready")


def browser() -> webdriver.Chrome:
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--window-size=1200,1600"):
        options.add_argument(arg)
    options.binary_location = os.environ.get("CHROMIUM", "/usr/bin/chromium")
    driver = os.environ.get("CHROMEDRIVER", "/usr/bin/chromedriver")
    return webdriver.Chrome(service=Service(executable_path=driver), options=options)


def segment_and_wait(driver, previous_status: str) -> str:
    driver.find_element(By.ID, "run").click()
    wait = WebDriverWait(driver, 60)
    wait.until(lambda d: d.find_element(By.ID, "status").text not in
               (previous_status, "segmenting…", ""))
    return driver.find_element(By.ID, "status").text


def check(condition: bool, what: str):
    if not condition:
        raise AssertionError(what)
    print(f"ok: {what}")


def main():
    binary = sys.argv[1]
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    server = subprocess.Popen([binary, "serve", "--bind", f"127.0.0.1:{port}", "--workers", "1"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    driver = None
    try:
        wait_ready(base, server)
        driver = browser()
        driver.get(f"{base}/")
        check(driver.title.startswith("Ariadne"), f"the page loads (title {driver.title!r})")
        presets = [o.text for o in driver.find_elements(By.CSS_SELECTOR, "#preset option")]
        check(presets[0] == "default" and "paper" in presets, f"presets listed: {presets}")

        driver.find_element(By.ID, "file").send_keys(str(PHOTO.resolve()))
        WebDriverWait(driver, 20).until(
            lambda d: not d.find_element(By.ID, "run").get_attribute("disabled"))
        loaded = driver.find_element(By.ID, "status").text
        check("640x480" in loaded, f"the photo is shown: {loaded!r}")

        status = segment_and_wait(driver, loaded)
        rows = driver.find_elements(By.CSS_SELECTOR, "#cables tbody tr")
        check(status.startswith(f"{len(rows)} cables in") and len(rows) >= 2,
              f"cables found and listed: {status!r}, {len(rows)} rows")
        ids = [r.find_elements(By.TAG_NAME, "td")[0].text for r in rows]
        check(ids == [str(i) for i in range(len(rows))], f"rows numbered by id: {ids}")
        drawn = driver.execute_script(
            "const c = document.getElementById('view').getContext('2d');"
            "const d = c.getImageData(0, 0, c.canvas.width, c.canvas.height).data;"
            "const palette = [[230,25,75],[60,180,75],[67,99,216]];"
            "let n = 0; for (let i = 0; i < d.length; i += 4)"
            "  for (const [r, g, b] of palette)"
            "    if (d[i] === r && d[i+1] === g && d[i+2] === b) n++;"
            "return n;")
        check(drawn > 500, f"centrelines drawn over the photo ({drawn} px in cable colours)")
        for link in ("json", "maskpng"):
            check(driver.find_element(By.ID, link).is_displayed(), f"download {link} offered")
        mask_width = driver.execute_script("return document.getElementById('mask').naturalWidth")
        check(mask_width == 640, f"mask shown at the photo's width ({mask_width})")
        foreign = driver.execute_script(
            "return performance.getEntriesByType('resource').map(e => e.name)"
            ".filter(n => !n.startsWith(location.origin) && !n.startsWith('blob:')"
            " && !n.startsWith('data:'))")
        check(foreign == [], f"nothing fetched from elsewhere ({foreign})")

        # The interactive use: click the two ends of the first cable on the photo,
        # segment with them.
        canvas = driver.find_element(By.ID, "view")
        ends = driver.execute_script("return result.cables[0].endpoints")
        ends = [[round(x), round(y)] for x, y in ends]
        scale = canvas.size["width"] / 640
        for x, y in ends:
            driver.execute_script(
                "const c = arguments[0], r = c.getBoundingClientRect();"
                "c.dispatchEvent(new MouseEvent('click', {clientX: r.left + arguments[1],"
                " clientY: r.top + arguments[2], bubbles: true}));",
                canvas, x * scale, y * scale)
        check(driver.find_element(By.ID, "ends").text == "ends: 2 clicked", "two ends clicked")
        segment_and_wait(driver, status)
        given = driver.execute_script(
            "return result.endpoints.filter(e => e.confidence === 1)"
            ".map(e => [Math.round(e.point[0]), Math.round(e.point[1]), e.cable])")
        check(len(given) == 2 and all(abs(g[0] - e[0]) <= 1.5 and abs(g[1] - e[1]) <= 1.5
                                      for g, e in zip(given, ends)),
              f"the clicked ends {ends} were sent: {given}")
        check(given[0][2] is not None and given[0][2] == given[1][2],
              f"one cable joins the two clicked ends: {given}")
    finally:
        if driver is not None:
            driver.quit()
        server.terminate()
        server.wait(timeout=30)
    print("browser test: page works")


if __name__ == "__main__":
    main()
