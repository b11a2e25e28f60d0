"""Browser check of a `surftrack view` page, driven by Selenium through chromedriver.

Usage: view_page.py PAGE.html MATERIAL_A MATERIAL_B

Opens the page in headless Chromium (software WebGL), and checks that
  1. WebGL really draws: the canvas has mesh pixels, not only background;
  2. the outer surfaces of materials A and B both show in their own colours;
  3. moving the frame slider to the last frame changes the picture;
  4. unticking material A in the legend removes its colour, while B stays;
  5. the browser console shows no error.
Prints one line per check and exits 0 only when all pass (1 on a failed check, 2 on
setup errors such as a missing browser). Colours are told apart by chromaticity
(r/(r+g+b), g/(r+g+b)), which Lambert shading under white light keeps.
"""
import json
import pathlib
import sys

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.ui import WebDriverWait

# Pixel census of the first panel's canvas, run in the page: counts of background
# pixels, of pixels per pair colour (nearest chromaticity within a tolerance) and a
# coarse signature of the picture.
CENSUS_JS = """
const canvas = document.querySelector('canvas[data-run="0"]');
const c2 = document.createElement('canvas');
c2.width = canvas.width; c2.height = canvas.height;
const ctx = c2.getContext('2d');
ctx.drawImage(canvas, 0, 0);
const data = ctx.getImageData(0, 0, c2.width, c2.height).data;
const meta = JSON.parse(document.getElementById('surftrack-meta').textContent);
const hex = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
const chroma = (r, g, b) => { const s = r + g + b + 1e-9; return [r / s, g / s]; };
const pairs = meta.pairs.map(([lo, hi, colour]) => [lo + '-' + hi, chroma(...hex(colour))]);
const counts = {}; for (const [k] of pairs) counts[k] = 0;
let background = 0, mesh = 0;
const signature = new Array(64).fill(0);
for (let i = 0; i < data.length; i += 4) {
  const r = data[i], g = data[i + 1], b = data[i + 2];
  const px = (i / 4) % c2.width, py = Math.floor(i / 4 / c2.width);
  if (r > 250 && g > 250 && b > 250) { background++; continue; }
  mesh++;
  signature[Math.floor(8 * py / c2.height) * 8 + Math.floor(8 * px / c2.width)]++;
  const c = chroma(r, g, b);
  if (r + g + b < 60) continue;
  let best = null, dist = 0.03;
  for (const [k, q] of pairs) {
    const d = Math.hypot(c[0] - q[0], c[1] - q[1]);
    if (d < dist) { dist = d; best = k; }
  }
  if (best) counts[best]++;
}
return {width: c2.width, height: c2.height, background, mesh, counts, signature};
"""


def main():
    page = pathlib.Path(sys.argv[1]).resolve()
    a, b = sys.argv[2], sys.argv[3]
    key_a, key_b = f"0-{a}", f"0-{b}"
    options = webdriver.ChromeOptions()
    for arg in ["--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--window-size=1000,900", "--force-device-scale-factor=1"]:
        options.add_argument(arg)
    for binary in ["/usr/bin/chromium", "/usr/bin/chromium-browser"]:
        if pathlib.Path(binary).exists():
            options.binary_location = binary
            break
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver_path = next((p for p in ["/usr/bin/chromedriver", "/usr/lib/chromium/chromedriver"]
                        if pathlib.Path(p).exists()), None)
    if driver_path is None:
        print("setup: no chromedriver", file=sys.stderr)
        return 2
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    try:
        driver.get(page.as_uri())
        WebDriverWait(driver, 60).until(lambda d: d.execute_script(
            "return window.surftrackView && (window.surftrackView.ready || window.surftrackView.error)"))
        state = driver.execute_script("return window.surftrackView")
        check(state.get("error") is None, f"the page started (error: {state.get('error')})")
        webgl = driver.execute_script(
            "const c = document.querySelector('canvas[data-run=\"0\"]');"
            "const gl = c.getContext('webgl2') || c.getContext('webgl');"
            "return gl ? gl.getParameter(gl.RENDERER) : null")
        check(webgl is not None, f"WebGL renderer: {webgl}")
        first = driver.execute_script(CENSUS_JS)
        total = first["width"] * first["height"]
        print("first frame:", json.dumps({k: first[k] for k in ["width", "height", "background", "mesh", "counts"]}))
        check(0.02 * total < first["mesh"] < 0.95 * total, "the canvas shows the mesh")
        check(first["counts"][key_a] > 0.005 * total, f"material {a}'s colour shows")
        check(first["counts"][key_b] > 0.005 * total, f"material {b}'s colour shows")

        slider = driver.find_element(By.ID, "frame")
        slider.send_keys(Keys.END)
        last_step = driver.execute_script(
            "const m = JSON.parse(document.getElementById('surftrack-meta').textContent);"
            "return Math.max(...m.runs[0].frames.map(f => f.step))")
        WebDriverWait(driver, 30).until(
            lambda d: d.execute_script("return window.surftrackView.step") == last_step)
        last = driver.execute_script(CENSUS_JS)
        changed = sum(abs(x - y) for x, y in zip(first["signature"], last["signature"]))
        print("last frame:", json.dumps({k: last[k] for k in ["background", "mesh", "counts"]}),
              "signature change", changed)
        check(changed > 0.002 * total, "moving the slider changes the picture")

        driver.find_element(By.CSS_SELECTOR, f'input.material[data-material="{a}"]').click()
        hidden = driver.execute_script(CENSUS_JS)
        print("material hidden:", json.dumps(hidden["counts"]))
        check(hidden["counts"][key_a] < 0.0005 * total, f"unticking material {a} removes its colour")
        check(hidden["counts"][key_b] > 0.005 * total, f"material {b} stays")

        logs = driver.get_log("browser")
        errors = [entry for entry in logs if entry.get("level") == "SEVERE"]
        for entry in logs:
            print("console:", entry.get("level"), entry.get("message")[:300])
        check(not errors, "no console error")
        timings = driver.execute_script("return window.surftrackView.timings")
        print("timings (ms):", json.dumps(timings))
    finally:
        driver.quit()
    print(f"{9 - len(failures)} checks passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
