#!/usr/bin/env python3
"""`brdftab view` in a real browser (headless Chromium through chromedriver).

Bakes a database of two tables in a temporary directory, serves it with `brdftab view DB
--port 0`, loads the page, selects a material, moves the θi slider with the keyboard and checks
that the polar plot's SVG changed, that each redraw took at most 100 ms (median; the page
measures from the slider's input event to the redrawn plots), and that the console has no
errors. Saves a screenshot (docs/view.png by default).

    python3 tools/brdftab/tests/browser/view_test.py [--brdftab target/release/brdftab]
        [--screenshot docs/view.png] [--preset medium]

Needs Debian's `chromium` and `chromium-driver` and the `selenium` package.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.parse

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.common.exceptions import StaleElementReferenceException
from selenium.webdriver.support.ui import Select, WebDriverWait

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
BUDGET_MS = 100.0
GOLD = '{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}'
PLASTIC = ('{"model": "sum", "terms": [{"model": "lambert", "kd": [0.05, 0.12, 0.2]}, '
           '{"model": "ggx", "alpha": 0.15, "fresnel": {"schlick": 0.04}}]}')

WARD = '{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.4}'
GLAZED = ('{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, '
          '{"model": "mirror", "fresnel": {"schlick": 0.04}}]}')


def waiter(driver):
    """A 30 s wait that retries a condition which met an element the page has
    just redrawn (the panels replace their SVG children on every update)."""
    return WebDriverWait(driver, 30, ignored_exceptions=(StaleElementReferenceException,))


def texts(driver, css):
    """The text of every element `css` selects, read in one script: the panels redraw their
    SVG while a test reads it, and an element fetched before a redraw is stale after it."""
    return driver.execute_script(
        "return [...document.querySelectorAll(arguments[0])]"
        ".map((e) => (e.innerText ?? e.textContent).trim());", css)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        sys.exit(f"FAILED: {' '.join(cmd)}\n{r.stderr}")


def start_server(brdftab, db, extra=()):
    proc = subprocess.Popen([brdftab, "view", db, *extra, "--port", "0"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    if "http://" not in line:
        proc.kill()
        sys.exit(f"FAILED: brdftab view printed no URL: {line!r} {proc.stderr.read()}")
    return proc, line[line.index("http://"):].strip()


def browser(profile):
    opts = webdriver.ChromeOptions()
    for a in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1500,1000", f"--user-data-dir={profile}"]:
        opts.add_argument(a)
    opts.binary_location = "/usr/bin/chromium"
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--brdftab", default=os.path.join(ROOT, "target", "release", "brdftab"))
    ap.add_argument("--screenshot", default=os.path.join(ROOT, "docs", "view.png"))
    ap.add_argument("--preset", default="medium", help="grid preset of the baked tables")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="brdftab-view-test-") as tmp:
        db = os.path.join(tmp, "lib.btdb")
        for name, spec in [("gold", GOLD), ("plastic", PLASTIC)]:
            run([a.brdftab, "db", "add", db, spec, "--name", name, "--preset", a.preset])
        server, url = start_server(a.brdftab, db)
        driver = None
        try:
            driver = browser(os.path.join(tmp, "profile"))
            check(driver, url, a.screenshot)
        finally:
            server.kill()
            server.wait()
        try:
            # Four materials: the database's two, a sum with a mirror term and a Lambert.
            server, url = start_server(a.brdftab, db, [GLAZED, '{"model": "lambert", "kd": 0.3}'])
            try:
                check_delta_and_four_curves(driver, url)
                check_spheres_of_four(driver, url)
                check_a_narrow_window(driver, url)
                check_a_colour_slider(driver, url)
                check_a_spec_that_is_not_an_object(driver, url)
                check_a_channel(driver, url)
                check_a_late_report(driver, url)
            finally:
                server.kill()
                server.wait()
            # An anisotropic Ward beside an isotropic Lambert: the φi slider.
            server, url = start_server(a.brdftab, WARD, ['{"model": "lambert", "kd": 0.3}'])
            try:
                check_phi_i(driver, url)
            finally:
                server.kill()
                server.wait()
        finally:
            if driver is not None:
                driver.quit()
    print("1 passed, 0 failed")


def check(driver, url, screenshot):
    wait = waiter(driver)
    driver.get(url)
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#materials li")) == 2)
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#polar polyline"))
    # Select the second material as well: two overlaid, one colour each.
    driver.find_elements(By.CSS_SELECTOR, "#materials li")[1].click()
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#polar polyline")) == 2)
    wait.until(lambda d: "m=0,1" in d.current_url)
    before = driver.find_element(By.ID, "polar").get_attribute("innerHTML")

    slider = driver.find_element(By.ID, "theta-i")
    times = []
    for _ in range(12):
        driver.execute_script("window.brdftabRedrawMs = null;")
        slider.send_keys(Keys.ARROW_RIGHT)
        wait.until(lambda d: d.execute_script("return window.brdftabRedrawMs;") is not None)
        times.append(driver.execute_script("return window.brdftabRedrawMs;"))
    after = driver.find_element(By.ID, "polar").get_attribute("innerHTML")
    assert after != before, "the polar plot did not change when θi moved"
    assert "ti=42" in driver.current_url, driver.current_url

    # The table against its source: the difference shows in the views and the error figures.
    driver.find_element(By.ID, "vs-source").click()
    wait.until(lambda d: "cos-weighted" in d.find_element(By.ID, "report").text
               and "%" in d.find_element(By.ID, "report").text)
    time.sleep(1.0)  # the slow views (albedo, slice, report) settle

    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"
    os.makedirs(os.path.dirname(screenshot), exist_ok=True)
    driver.save_screenshot(screenshot)
    check_downloads(driver, wait)
    check_spec_and_shared_url(driver, wait)
    check_scales(driver)
    check_hash_and_errors(driver, wait, url)
    check_ggx_sliders(driver, wait)
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"
    median = statistics.median(times)
    print(f"redraw after a θi step: median {median:.1f} ms, max {max(times):.1f} ms "
          f"over {len(times)} steps (budget {BUDGET_MS:.0f} ms)")
    assert median <= BUDGET_MS, f"median redraw {median:.1f} ms > {BUDGET_MS} ms"
    print(f"screenshot: {screenshot}")


def check_downloads(driver, wait):
    """Every plot's SVG and PNG buttons produce a file (PNG through a canvas, untainted)."""
    driver.execute_script(
        "window.savedFiles = []; window.save = (url, file) => window.savedFiles.push([url.slice(0, 15), file]);")
    buttons = driver.find_elements(By.CSS_SELECTOR, ".panel .dl button")
    assert len(buttons) == 10, len(buttons)
    for b in buttons:
        b.click()
    wait.until(lambda d: len(d.execute_script("return window.savedFiles;")) == len(buttons))
    for url, name in driver.execute_script("return window.savedFiles;"):
        want = "data:image/png" if name.endswith(".png") else "blob:"
        assert url.startswith(want) and name.startswith("brdftab-"), (url, name)


def check_spec_and_shared_url(driver, wait):
    """An analytic spec's slider re-evaluates it; the URL restores the whole view."""
    polar = lambda d: d.find_element(By.ID, "polar").get_attribute("innerHTML")
    lines = len(driver.find_elements(By.CSS_SELECTOR, "#polar polyline"))
    driver.find_element(By.ID, "spec-on").click()
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#polar polyline")) > lines)
    before = polar(driver)
    slider = driver.find_element(By.CSS_SELECTOR, "#params input[type=range]")
    for _ in range(20):
        slider.send_keys(Keys.ARROW_RIGHT)
    wait.until(lambda d: polar(d) != before)
    url = driver.current_url
    assert "on=1" in url and "spec=" in url, url
    driver.get("about:blank")
    driver.get(url)
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#materials li.selected")) == 2)
    assert driver.find_element(By.ID, "theta-i").get_attribute("value") == "42"
    assert driver.find_element(By.ID, "spec-on").is_selected()
    assert driver.find_element(By.ID, "vs-source").is_selected()
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#polar polyline")) == lines + 1)


def check_scales(driver):
    """A few grazing samples (measured data near the horizon) do not set a plot's scale: they
    are clipped, and the plot says so."""
    legend = driver.execute_script("""
        const xs = Array.from({length: 180}, (_, k) => -89.5 + k);
        const ys = xs.map((t) => (Math.abs(t) > 89 ? 1e14 : 0.3));
        polarPlot($("polar"), [{x: xs, y: ys, color: "#000"}], {log: false, thetaI: 30, label: ""});
        const polar = [...$("polar").querySelectorAll("text")].map((t) => t.textContent).find((t) => t.startsWith("scale"));
        const rings = (log) => {
          polarPlot($("polar"), [{x: xs, y: ys, color: "#000"}], {log, thetaI: 30, label: ""});
          return [...$("polar").querySelectorAll("text.ring")].map((t) => t.textContent).join(" ");
        };
        window.ringLabels = [rings(false), rings(true)];
        const n = 10, theta = Array.from({length: n}, (_, k) => 4.5 + 9 * k);
        const y = Array.from({length: n * n}, (_, k) => (k % n === n - 1 || k >= n * (n - 1) ? 1 : 0.01));
        heatmap($("slice"), n, y, {signed: true, theta, label: ""});
        window.sliceTicks = [...$("slice").querySelectorAll("text.tick")].map((t) => t.textContent);
        return [polar, [...$("slice").querySelectorAll("text")].map((t) => t.textContent).join(" | ")];""")
    assert legend[0].startswith("scale 0.300; 2 grazing samples clipped"), legend
    assert "scale ±0.0100" in legend[1] and "19 cells clipped" in legend[1], legend
    # The polar plot's rings say their values: quarters of the scale, or decades on a log scale
    # (they said nothing, and a log plot's rings read as quarters).
    # The slice's axes say their range (they said only "θh →" and "θd ↑").
    ticks = driver.execute_script("return window.sliceTicks;")
    assert ticks == ["0°", "90°", "0°", "90°"], ticks
    rings = driver.execute_script("return window.ringLabels;")
    assert rings == ["0.075 0.15 0.22 0.30", "3.0e-4 3.0e-3 0.030 0.30"], rings


def check_hash_and_errors(driver, wait, url):
    """URL values are clamped to the controls; bad material indices are dropped; a view's error
    stays on its panel when other views succeed."""
    base = url.split("#")[0]
    driver.get("about:blank")
    driver.get(base + "#m=0&ti=90&lt=200&ev=-20")
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#polar polyline"))
    assert driver.find_element(By.ID, "theta-i").get_attribute("value") == "89"
    assert driver.find_element(By.ID, "theta-i-val").text == "89°"
    assert "ti=89" in driver.current_url and "lt=90" in driver.current_url, driver.current_url
    assert "ev=-4" in driver.current_url, driver.current_url
    for h, want in [("#m=0.5", 0), ("#m=1,1,1,1", 1), ("#m=-1,1", 1)]:
        driver.get("about:blank")
        driver.get(base + h)
        wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#materials li"))
        time.sleep(0.5)
        assert len(driver.find_elements(By.CSS_SELECTOR, "#materials li.selected")) == want, h
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"
    err = driver.execute_async_script("""
        const done = arguments[arguments.length - 1];
        (async () => {
          await view("polar", "theta_i=95&n=180", () => {});
          await sphereView(48);
          return document.querySelector('.panel[data-plot="polar"] .error').textContent;
        })().then(done);""")
    assert "theta_i" in err, err
    driver.get_log("browser")  # that 400 was asked for


def check_ggx_sliders(driver, wait):
    """GGX offers alpha or alpha_x and alpha_y, never the three: every slider gives a valid
    spec."""
    labels = lambda d: [l.text.split("\n")[0].split(" ")[0] for l in d.find_elements(By.CSS_SELECTOR, "#params label")]
    Select(driver.find_element(By.ID, "model")).select_by_value("ggx")
    wait.until(lambda d: "alpha" in labels(d))
    assert "alpha_x" not in labels(driver), labels(driver)
    Select(driver.find_element(By.CSS_SELECTOR, "#params select")).select_by_index(1)
    wait.until(lambda d: "alpha_x" in labels(d) and "alpha_y" in labels(d) and "alpha" not in labels(d))
    if not driver.find_element(By.ID, "spec-on").is_selected():
        driver.find_element(By.ID, "spec-on").click()
    slider = driver.find_element(By.CSS_SELECTOR, "#params input[type=range]")
    for _ in range(10):
        slider.send_keys(Keys.ARROW_RIGHT)
    time.sleep(1.5)
    assert '"alpha_x"' in driver.find_element(By.ID, "spec-json").get_attribute("value")
    errs = [e.text for e in driver.find_elements(By.CSS_SELECTOR, ".panel .error") if e.text]
    assert not errs, errs


def check_delta_and_four_curves(driver, url):
    """A material with a mirror lobe says that no plot of f_r shows it; with four materials
    selected the spec waits for a free place instead of dropping one of them."""
    wait = waiter(driver)
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=2")
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#materials li")) == 4)
    items = driver.find_elements(By.CSS_SELECTOR, "#materials li")
    assert "delta lobe" in items[2].text and "delta lobe" not in items[3].text, [i.text for i in items]
    note = lambda d: d.find_element(By.CSS_SELECTOR, '.panel[data-plot="polar"] .note').text
    wait.until(lambda d: "delta" in note(d))
    for k in [0, 1, 3]:
        driver.find_elements(By.CSS_SELECTOR, "#materials li")[k].click()
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#materials li.selected")) == 4)
    driver.find_element(By.ID, "spec-on").click()
    time.sleep(0.3)
    assert not driver.find_element(By.ID, "spec-on").is_selected()
    assert "four curves" in driver.find_element(By.ID, "spec-error").text
    assert len(driver.find_elements(By.CSS_SELECTOR, "#materials li.selected")) == 4
    assert "on=1" not in driver.current_url, driver.current_url
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"



def check_spheres_of_four(driver, url):
    """Four materials against their sources show every sphere (the panel showed the first six
    images: two materials were missing)."""
    wait = waiter(driver)
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0,1,2,3&src=1")
    # The two tables with their sources and differences, the two specs alone.
    wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#sphere image")) == 8)
    labels = texts(driver, "#sphere text")
    assert sum("source" in t for t in labels) == 4 and labels[-2:] == ["sum", "lambert"], labels


def check_a_narrow_window(driver, url):
    """In a narrow window (a phone, half a screen) every panel fits the page's width: beside
    the material list they had less than their width and ran off the right edge."""
    wait = waiter(driver)
    driver.set_window_size(480, 900)
    try:
        driver.get("about:blank")
        driver.get(url.split("#")[0] + "#m=0")
        wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#polar polyline"))
        width, overflow = driver.execute_script("""
            const w = document.documentElement.clientWidth;
            const right = [...document.querySelectorAll(".panel, #controls, aside")]
              .map((e) => e.getBoundingClientRect().right);
            return [w, Math.max(...right) - w];""")
        assert overflow <= 0.5, f"the panels run {overflow:.0f} px past a {width} px page"
    finally:
        driver.set_window_size(1500, 1000)


def check_a_colour_slider(driver, url):
    """A slider on an RGB value scales the colour, keeping its hue (it set a grey)."""
    wait = waiter(driver)
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0&spec=" + urllib.parse.quote(
        '{"model": "lambert", "kd": [0.1, 0.2, 0.4]}'))
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#params input[type=range]"))
    slider = driver.find_element(By.CSS_SELECTOR, "#params input[type=range]")
    for _ in range(20):
        slider.send_keys(Keys.ARROW_LEFT)
    kd = json.loads(driver.find_element(By.ID, "spec-json").get_attribute("value"))["kd"]
    assert isinstance(kd, list) and len(kd) == 3, kd
    # 20 steps of 1/400 down from 0.4; the hue's ratios 1 : 2 : 4 kept.
    assert abs(kd[2] - 0.35) < 1e-9 and abs(kd[0] * 4 - kd[2]) < 1e-9 and abs(kd[1] * 2 - kd[2]) < 1e-9, kd


def check_a_spec_that_is_not_an_object(driver, url):
    """`null` typed in the spec editor is not a spec: it is refused there, and a URL holding it
    (the editor wrote one) still opens (the page stopped at a TypeError and drew nothing)."""
    wait = waiter(driver)
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0&spec=null&on=1")
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#polar polyline"))
    assert not driver.find_element(By.ID, "spec-on").is_selected()
    editor = driver.find_element(By.ID, "spec-json")
    editor.clear()
    editor.send_keys("null")
    wait.until(lambda d: "JSON object" in d.find_element(By.ID, "spec-error").text)
    assert "spec=null" not in driver.current_url, driver.current_url
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"


def check_a_channel(driver, url):
    """The channel chosen (here blue) is what the plots show and say, and the URL keeps it."""
    wait = waiter(driver)
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0")
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#polar polyline"))
    Select(driver.find_element(By.ID, "channel")).select_by_value("b")
    label = lambda d: " ".join(texts(d, "#polar text"))
    wait.until(lambda d: "f_r, B (1/sr)" in label(d) and "ch=b" in d.current_url)
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0&ch=b")
    wait.until(lambda d: "f_r, B (1/sr)" in label(d))
    assert Select(driver.find_element(By.ID, "channel")).first_selected_option.get_attribute("value") == "b"


def check_a_late_report(driver, url):
    """A report that answers after a newer one (its figures took seconds) does not replace it
    with materials no longer selected."""
    wait = waiter(driver)
    rows = lambda d: texts(d, "#report tr")[1:]
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0")
    wait.until(lambda d: len(rows(d)) == 1 and "…" not in rows(d)[0])
    # Material 1's plausibility answers 1.5 s late; it is selected, then deselected at once.
    driver.execute_script("""
        const orig = getJSON;
        window.getJSON = (p) => (p.startsWith("/api/plausibility?m=1")
          ? new Promise((r) => setTimeout(r, 1500)).then(() => orig(p)) : orig(p));""")
    items = driver.find_elements(By.CSS_SELECTOR, "#materials li")
    items[1].click()
    time.sleep(0.3)
    driver.find_elements(By.CSS_SELECTOR, "#materials li")[1].click()
    time.sleep(2.5)
    assert len(rows(driver)) == 1 and rows(driver)[0].startswith("gold"), rows(driver)
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"


def check_phi_i(driver, url):
    """φi turns the plane of incidence of an anisotropic material (Ward α = 0.1 × 0.4): its polar
    curve changes and the URL keeps φi; with only isotropic materials shown the slider is
    disabled, saying why, and with one anisotropic among them it is enabled again."""
    wait = waiter(driver)
    points = lambda d: d.execute_script(
        "return [...document.querySelectorAll('#polar polyline')].map((p) => p.getAttribute('points'));")
    slider = lambda d: d.find_element(By.ID, "phi-i")
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=0")
    wait.until(lambda d: len(points(d)) == 1 and slider(d).is_enabled())
    assert "φi" in driver.find_element(By.ID, "phi-i-label").get_attribute("title")
    before = points(driver)
    for _ in range(90):
        slider(driver).send_keys(Keys.ARROW_RIGHT)
    wait.until(lambda d: "pi=90" in d.current_url and "φi = 90°" in " ".join(texts(d, "#polar text")))
    # The plane along α_y (the wide axis): the curve is another one, not a redrawn copy.
    wait.until(lambda d: points(d) != before)
    assert driver.find_element(By.ID, "phi-i-val").text == "90°"
    wait.until(lambda d: "φi = 90°" in " ".join(texts(d, "#albedo text")))
    # The Lambert alone: nothing to turn.
    items = lambda d: d.find_elements(By.CSS_SELECTOR, "#materials li")
    items(driver)[1].click()
    items(driver)[0].click()
    wait.until(lambda d: "m=1&" in d.current_url and not slider(d).is_enabled())
    assert "isotropic" in driver.find_element(By.ID, "phi-i-label").get_attribute("title")
    # With the slider disabled, the URL's φi = 90° turns nothing: the plots say φi = 0° and the
    # lobe is the one drawn at φi = 0 (a Lambert's values are the same at every azimuth).
    lobe = lambda d: d.find_element(By.ID, "lobe").get_attribute("innerHTML")
    wait.until(lambda d: "φi = 0°" in " ".join(texts(d, "#polar text")))
    wait.until(lambda d: "φi = 0°" in " ".join(texts(d, "#albedo text")))
    turned = lobe(driver)
    assert "pi=90" in driver.current_url
    driver.get("about:blank")
    driver.get(url.split("#")[0] + "#m=1")
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#lobe path") and not slider(d).is_enabled())
    time.sleep(0.5)
    assert lobe(driver) == turned, "an isotropic lobe turned with the disabled slider's φi"
    items(driver)[0].click()
    wait.until(lambda d: slider(d).is_enabled())
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"console errors: {errors}"


if __name__ == "__main__":
    main()
