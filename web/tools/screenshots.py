#!/usr/bin/env python3
"""README screenshots: the sweep and case pages of a running knotsweep server, in headless chromium.

Usage: web/tools/screenshots.py BASE_URL SWEEP_ID CASE_ID OUT_DIR
(e.g. after `knotsweep serve` and submitting the fig9 preset: web/tools/screenshots.py http://127.0.0.1:8080 1 3 docs/screenshots)
"""
import base64, json, socket, subprocess, sys, time, urllib.request

base, sweep, case, out = sys.argv[1:5]


def call(port, method, path, body=None):
    r = urllib.request.Request(f"http://127.0.0.1:{port}{path}", data=json.dumps(body).encode() if body is not None else None,
                               method=method, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(r, timeout=60) as f:
        return json.loads(f.read())


s = socket.socket(); s.bind(("127.0.0.1", 0)); port = s.getsockname()[1]; s.close()
driver = subprocess.Popen(["chromedriver", f"--port={port}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
try:
    for _ in range(50):
        try: call(port, "GET", "/status"); break
        except Exception: time.sleep(0.2)
    shots = [("sweep", f"#/sweeps/{sweep}", 1280, 1500), ("case", f"#/cases/{case}", 1280, 1500)]
    for name, route, w, h in shots:
        args = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--enable-unsafe-swiftshader",
                f"--window-size={w},{h}", "--hide-scrollbars"]
        sid = call(port, "POST", "/session", {"capabilities": {"alwaysMatch": {"goog:chromeOptions": {"args": args}}}})["value"]["sessionId"]
        call(port, "POST", f"/session/{sid}/url", {"url": f"{base}/{route}"})
        time.sleep(6)
        png = call(port, "GET", f"/session/{sid}/screenshot")["value"]
        with open(f"{out}/{name}.png", "wb") as f:
            f.write(base64.b64decode(png))
        call(port, "DELETE", f"/session/{sid}")
        print(f"{out}/{name}.png")
finally:
    driver.terminate()
