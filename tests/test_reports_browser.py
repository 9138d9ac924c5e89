"""The reports as a person sees them: analysis, gap and demo pages in headless Chromium.

The pages are written by the commands themselves (``vidiscover analyze``, ``vidiscover
gap``, :func:`vidiscover.demo.run_demo` on one short clearance), served over http from
their folder on localhost, and opened in Debian's Chromium through chromedriver
(selenium). For every page: each figure loads (``naturalWidth > 0``, as many images as
figures written), each relative link answers HTTP 200 and each in-page anchor names an
element, the browser console has no error, and at a laptop window (1366 x 768) nothing
scrolls sideways and no text is smaller than 12 px. The demo index's linked reports
are checked the same way.

Skipped, with the reason, where Chromium, chromedriver or selenium is absent
(``.ci/run`` installs them: ``apt-get install chromium chromium-driver``).
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import shutil
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest
from click.testing import CliRunner

from vidiscover import preset
from vidiscover.cli import main
from vidiscover.io import write_recording
from vidiscover.report import FIGURES
from vidiscover.workflows import simulate_to_memory

#: Laptop window (CSS px) the pages must fit without sideways scrolling.
WINDOW = (1366, 768)
#: Smallest readable text (CSS px).
MIN_FONT_PX = 12.0
CHROME_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking",
                "--disable-component-update", "--disable-sync")


def _which(*names: str) -> str | None:
    for name in names:
        path = shutil.which(name) or next(
            (p for p in (f"/usr/bin/{name}", f"/usr/lib/chromium/{name}") if Path(p).is_file()),
            None)
        if path:
            return path
    return None


CHROMIUM = _which("chromium", "chromium-browser", "google-chrome")
CHROMEDRIVER = _which("chromedriver")
_MISSING = [what for what, ok in (
    ("chromium (apt-get install chromium)", CHROMIUM),
    ("chromedriver (apt-get install chromium-driver)", CHROMEDRIVER),
    ("selenium (pip install -e '.[dev]')", importlib.util.find_spec("selenium"))) if not ok]

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(bool(_MISSING), reason="browser test needs " + ", ".join(_MISSING)),
]


# ------------------------------------------------------------------------------ fixtures
@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """One folder with an analysis report, a gap report and a one-clearance demo."""
    from vidiscover.demo import run_demo

    root = tmp_path_factory.mktemp("site")
    rec, truth, _ = simulate_to_memory(preset("paper", b=0.009),
                                       ("asymmetric_restitution=0.8782,0.2018",), seed=2,
                                       settle=2.0, duration=1.2, name="b9")
    write_recording(rec, root / "b9.csv", truth=truth)
    runner = CliRunner()
    for args in (["analyze", str(root / "b9.csv"), "--out", str(root / "analysis")],
                 ["gap", str(root / "b9.csv"), "--out", str(root / "gap"), "--n-jobs", "1"]):
        res = runner.invoke(main, args)
        assert res.exit_code == 0, res.output
    run_demo(root / "demo", clearances_mm=(9.0,), settle=2.0, duration=1.2, progress=False)
    return root


@contextlib.contextmanager
def _served(directory: Path):
    """``directory`` served over http on localhost; yields its base URL."""

    class Quiet(SimpleHTTPRequestHandler):
        def log_message(self, *args):          # keep the test output clean
            pass

    srv = ThreadingHTTPServer(("127.0.0.1", 0),
                              functools.partial(Quiet, directory=str(directory)))
    thread = threading.Thread(target=srv.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{srv.server_address[1]}/"
    finally:
        srv.shutdown()
        srv.server_close()
        thread.join(5)


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    """Headless Chromium at a laptop window size, console messages recorded."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in (*CHROME_FLAGS, f"--user-data-dir={tmp_path_factory.mktemp('chrome')}",
                 f"--window-size={WINDOW[0]},{WINDOW[1]}"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


# ------------------------------------------------------------------------------ checks
_TEXT_SIZES = """
const out = [];
const walk = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
while (walk.nextNode()) {
  const node = walk.currentNode, el = node.parentElement;
  if (!node.textContent.trim() || !el.getClientRects().length) continue;
  out.push([parseFloat(getComputedStyle(el).fontSize), node.textContent.trim().slice(0, 40)]);
}
return out;
"""


def _status(url: str) -> int:
    try:
        with urllib.request.urlopen(url, timeout=10) as resp:
            return resp.status
    except urllib.error.HTTPError as err:
        return err.code


def _visit(driver, url: str) -> dict:
    """Open ``url`` and return what a reader would meet there."""
    driver.get_log("browser")                                   # drop earlier messages
    driver.get(url)
    # a busy machine (CI's two test workers) may return from get() before every figure
    # has arrived: wait for them (up to 20 s) instead of reading a half-loaded page
    deadline = time.monotonic() + 20.0
    while (not driver.execute_script("return Array.from(document.images).every(i => i.complete)")
           and time.monotonic() < deadline):
        time.sleep(0.1)
    images = driver.execute_script(
        "return Array.from(document.images).map(i => "
        "[(i.getAttribute('src') || '').slice(0, 60), i.complete, i.naturalWidth])")
    links = driver.execute_script(
        "return Array.from(document.querySelectorAll('a[href]')).map(a => "
        "[a.getAttribute('href'), a.href])")
    anchors_missing = [href for href, _ in links if href.startswith("#") and not
                       driver.execute_script("return !!document.getElementById(arguments[0])",
                                             urllib.parse.unquote(href[1:]))]
    relative = [(href, absolute) for href, absolute in links
                if not href.startswith("#") and not urllib.parse.urlparse(href).scheme
                and not href.startswith("//")]
    width = driver.execute_script(
        "return [document.documentElement.scrollWidth, document.documentElement.clientWidth]")
    return {
        "images": images,
        "links": links,
        "anchors_missing": anchors_missing,
        "relative": relative,
        "broken": [(h, _status(a)) for h, a in relative if _status(a) != 200],
        "errors": [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"],
        "width": width,
        "small_text": [t for t in driver.execute_script(_TEXT_SIZES) if t[0] < MIN_FONT_PX],
        "title": driver.title,
    }


def _assert_readable(page: dict, url: str, n_images: int | None) -> None:
    if n_images is not None:
        assert len(page["images"]) == n_images, f"{url}: {len(page['images'])} images"
    unloaded = [src for src, done, w in page["images"] if not (done and w > 0)]
    assert not unloaded, f"{url}: figures that did not load: {unloaded}"
    assert not page["anchors_missing"], f"{url}: anchors with no target {page['anchors_missing']}"
    assert not page["broken"], f"{url}: links that do not resolve {page['broken']}"
    assert not page["errors"], f"{url}: console errors {page['errors']}"
    scroll, client = page["width"]
    assert scroll <= client, f"{url}: {scroll} px wide in a {client} px window (scrolls sideways)"
    assert not page["small_text"], f"{url}: text below {MIN_FONT_PX} px {page['small_text'][:5]}"
    assert page["title"], f"{url}: no title"


# ------------------------------------------------------------------------------ tests
# One test over all pages: the pages are built once (about 20 s of CPU) even when
# pytest-xdist spreads the tests of this module over several workers.
def test_reports_read_in_a_browser(browser, site):
    n_gap = len(list((site / "gap" / "figures").glob("*.png")))
    assert n_gap == 3
    with _served(site) as base:
        url = base + "analysis/report.html"
        page = _visit(browser, url)
        _assert_readable(page, url, n_images=len(FIGURES))
        # the figure menu links every figure, and each anchor was found on the page
        assert sum(h.startswith("#fig-") for h, _ in page["links"]) == len(FIGURES)

        url = base + "gap/report.html"
        page = _visit(browser, url)
        _assert_readable(page, url, n_images=n_gap)
        assert all(src.startswith("figures/") for src, _, _ in page["images"])

        url = base + "demo/index.html"
        page = _visit(browser, url)
        _assert_readable(page, url, n_images=None)
        reports = [a for h, a in page["relative"] if h.endswith("report.html")]
        assert len(reports) == 1, page["links"]          # one row per simulated clearance
        for report in reports:
            _assert_readable(_visit(browser, report), report, n_images=len(FIGURES))


def test_the_checks_catch_a_page_a_reader_could_not_use(browser, tmp_path):
    """A page with each fault: every check above must see its own."""
    (tmp_path / "bad.html").write_text(
        '<!DOCTYPE html><html><head><title>bad</title><link rel="icon" href="data:,"></head>'
        '<body><img src="missing.png" alt="x"><a href="nowhere.html">dead</a>'
        '<a href="#nothing">anchor</a><div style="width:3000px">wide</div>'
        '<p style="font-size:9px">tiny</p><script>undefined_function()</script></body></html>',
        encoding="utf-8")
    with _served(tmp_path) as base:
        page = _visit(browser, base + "bad.html")
    assert [w for _, _, w in page["images"]] == [0]
    assert page["broken"] == [("nowhere.html", 404)]
    assert page["anchors_missing"] == ["#nothing"]
    assert page["width"][0] > page["width"][1]
    assert [t for _, t in page["small_text"]] == ["tiny"]
    assert any("undefined_function" in e for e in page["errors"])
    with pytest.raises(AssertionError):
        _assert_readable(page, "bad.html", n_images=1)
