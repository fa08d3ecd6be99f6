"""report.html in a real headless browser (Playwright driving Debian's chromium, which .ci/run
installs): loaded from file:// with no network, the page logs no console error and throws
none, every plotly figure is drawn, the verdict table has one row per comparison of the JSON
written beside it and the counts shown are the JSON's tallies (counted here from the JSON),
sorting orders the rows and filtering shows the rows the JSON says match. A run, a modes
study, and a campaign page (composed from those two folders; a real `xval campaign` in the
slow test)."""
import json
import os
import shutil
from collections import Counter
from pathlib import Path

import pytest

from tests.conftest import xval

CHROMIUM = os.environ.get("XVAL_CHROMIUM", "/usr/bin/chromium")


def _need_browser():
    why = None
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        why = "playwright is not installed (pip install -e '.[test]')"
    if why is None and not Path(CHROMIUM).exists():
        why = f"{CHROMIUM} is missing (apt-get install -y chromium; .ci/run installs it)"
    if why:
        if os.environ.get("CI") == "true":
            pytest.fail(f"the browser test must run in CI: {why}")
        pytest.skip(why)


@pytest.fixture(scope="module")
def browser():
    _need_browser()
    from playwright.sync_api import sync_playwright
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    """A run and a modes study written by the command line, and a campaign page over both."""
    root = tmp_path_factory.mktemp("html")
    run, modes = root / "camp" / "spin", root / "camp" / "whirl"
    rc, _, se = xval("run", "rotor-spinup", "--set", "t_end=0.5", "--solver", "euler-vector",
                     "--solver", "quaternion", "--solver", "exudyn", "--out", run)
    assert rc == 0, se
    rc, _, se = xval("modes", "rotor-whirl", "--solver", "closed-form", "--solver",
                     "euler-vector", "--out", modes)
    assert rc == 0, se
    from compare.output.html_report import write_campaign_html
    cases = [{"case": f.name, **json.loads((f / "result.json").read_text())}
             for f in (run, modes)]
    summary = {"name": "composed", "n_jobs": 5, "n_run": 5, "n_reused": 0, "n_failed": 0,
               "n_crashed": 0, "wall_s": 1.0, "cases": cases}
    (root / "camp" / "summary.json").write_text(json.dumps(summary))
    write_campaign_html(root / "camp", summary)
    return {"run": run, "modes": modes, "campaign": root / "camp"}


def _open(browser, page_path):
    page = browser.new_page(viewport={"width": 1300, "height": 900})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
    # offline: any request that is not a local file fails the test
    page.route("**/*", lambda r: r.continue_() if r.request.url.startswith("file://")
               else (errors.append(f"network: {r.request.url}"), r.abort()))
    page.goto(page_path.as_uri())
    page.wait_for_load_state("load")
    return page, errors


def _figures_drawn(page, errors):
    n = page.locator(".xval-figure").count()
    assert n > 0
    try:
        page.wait_for_function("n => document.querySelectorAll('.xval-figure .main-svg')"
                               ".length >= n", arg=n, timeout=15000)
    except Exception as e:
        pytest.fail(f"{n} figures not drawn in 15 s; the page said {errors} ({e})")
    sizes = page.eval_on_selector_all(
        ".xval-figure", "els => els.map(e => { const s = e.querySelector('.main-svg');"
        " if (!s) return 0; const r = s.getBoundingClientRect(); return r.width * r.height; })")
    assert len(sizes) == n and all(s > 0 for s in sizes), sizes
    return n


def _visible_rows(page):
    return page.locator("#verdict-table tbody tr:not([hidden])")


def _check_table(page, comparisons):
    """Rows and counts against the JSON's comparisons."""
    rows = page.locator("#verdict-table tbody tr")
    assert rows.count() == len(comparisons)
    want = Counter(c["verdict"] for c in comparisons)
    shown = {e.get_attribute("data-verdict"): int(e.get_attribute("data-count"))
             for e in page.locator("#verdict-counts [data-verdict]").all()}
    assert shown == dict(want)
    assert int(page.get_attribute("#verdict-counts", "data-total")) == len(comparisons)
    got = Counter(page.eval_on_selector_all("#verdict-table tbody tr",
                                            "rows => rows.map(r => r.dataset.verdict)"))
    assert got == want


def _column(page, name):
    heads = page.locator("#verdict-table thead th").all_inner_texts()
    i = [h.strip() for h in heads].index(name)
    return i, page.eval_on_selector_all(
        "#verdict-table tbody tr:not([hidden])", "(rows, i) => rows.map(r => "
        "r.cells[i].textContent)", i)


def _check_sort_and_filter(page, comparisons, solver):
    i, before = _column(page, "Δ/bound")
    page.locator("#verdict-table thead th").nth(i).click()
    _, up = _column(page, "Δ/bound")
    nums = [float(x.replace("−", "-")) for x in up if x not in ("—", "")]
    assert nums == sorted(nums) and sorted(up) == sorted(before)
    page.locator("#verdict-table thead th").nth(i).click()
    _, down = _column(page, "Δ/bound")
    nums = [float(x.replace("−", "-")) for x in down if x not in ("—", "")]
    assert nums == sorted(nums, reverse=True)
    # the solver's rows: those the JSON names it in
    page.fill("#verdict-filter", solver)
    mine = sum(solver in (c["a"], c["b"]) for c in comparisons)
    assert 0 < mine < len(comparisons)
    assert _visible_rows(page).count() == mine
    assert page.inner_text("#verdict-shown") == str(mine)
    page.select_option("#verdict-select", "agree")
    assert _visible_rows(page).count() == sum(solver in (c["a"], c["b"]) and
                                              c["verdict"] == "agree" for c in comparisons)
    page.fill("#verdict-filter", "")
    page.select_option("#verdict-select", "")
    assert _visible_rows(page).count() == len(comparisons)


def test_run_report_page(browser, folders, tmp_path):
    run = folders["run"]
    obj = json.loads((run / "result.json").read_text())
    page, errors = _open(browser, run / "report.html")
    n = _figures_drawn(page, errors)
    assert n >= len(obj["runs"][0]["final"])          # one figure per channel at least
    _check_table(page, obj["comparisons"])
    _check_sort_and_filter(page, obj["comparisons"], "exudyn")
    header = page.inner_text("table.facts")
    assert "t_end = 0.5 s" in header and "euler-vector, quaternion, exudyn" in header
    href = page.get_attribute("#recordings a", "href")
    assert href == "run.rrd" and (run / href).exists()
    page.screenshot(path=str(tmp_path / "run.png"))          # to look at: pytest --basetemp
    assert errors == []


def test_modes_report_page(browser, folders):
    modes = folders["modes"]
    obj = json.loads((modes / "result.json").read_text())
    page, errors = _open(browser, modes / "report.html")
    _figures_drawn(page, errors)
    assert page.locator("#campbell .main-svg").count() > 0
    _check_table(page, obj["comparisons"])
    assert (modes / page.get_attribute("#recordings a", "href")).exists()
    assert errors == []


def _check_campaign(browser, folder, case_pages=True):
    summary = json.loads((folder / "summary.json").read_text())
    page, errors = _open(browser, folder / "report.html")
    comps = [c for case in summary["cases"] for c in case.get("comparisons", [])]
    _check_table(page, comps)
    if comps:
        _figures_drawn(page, errors)
    links = page.eval_on_selector_all("#case-table a[href$='report.html']",
                                      "els => els.map(e => e.getAttribute('href'))")
    assert len(links) == len(summary["cases"])
    assert all((folder / h).exists() for h in links)
    n_agree = sum(c["verdict"] == "agree" for c in comps)
    line = page.inner_text("#campaign-verdict")
    assert f"{n_agree} of {len(comps)} comparisons agree" in line
    assert line.startswith("overall: " + ("agree" if n_agree == len(comps) else ""))
    assert errors == []
    for h in links if case_pages else ():              # each case's own page loads clean
        page, errors = _open(browser, folder / h)
        _figures_drawn(page, errors)
        assert errors == []


def test_campaign_page(browser, folders):
    _check_campaign(browser, folders["campaign"], case_pages=False)   # checked above


def test_a_page_copied_elsewhere_still_works(browser, folders, tmp_path):
    """Self-contained: the folder moved on its own keeps its plotly.js and its figures."""
    moved = tmp_path / "moved"
    shutil.copytree(folders["run"], moved)
    page, errors = _open(browser, moved / "report.html")
    _figures_drawn(page, errors)
    assert errors == []


@pytest.mark.slow
def test_a_real_campaign_page(browser, tmp_path):
    camp = tmp_path / "camp.json"
    camp.write_text(json.dumps({"name": "tiny", "cases": [
        {"name": "spin", "scene": "rotor-spinup", "set": {"t_end": 0.2},
         "solvers": ["euler-vector", "quaternion"]},
        {"name": "whirl", "scene": "rotor-whirl", "solvers": ["closed-form", "euler-vector"]}]}))
    out = tmp_path / "out"
    rc, _, se = xval("campaign", camp, "--out", out)
    assert rc == 0, se
    folder = next(p.parent for p in out.rglob("summary.json"))
    _check_campaign(browser, folder)


def test_the_campaign_verdict_is_never_agree_with_an_answer_missing():
    """The overall line: the worst verdict, `incomplete` where a solver failed, a job crashed,
    a case has an error or nothing was compared (no browser needed)."""
    from compare.output.html_report import campaign_verdict_line
    ok = {"case": "a", "comparisons": [{"verdict": "agree"}] * 3}
    base = {"n_failed": 0, "n_crashed": 0}
    assert campaign_verdict_line({**base, "cases": [ok]}).startswith(
        "overall: agree — 3 of 3 comparisons agree in 1 cases")
    for broken in ({**base, "n_failed": 1, "cases": [ok]},
                   {**base, "n_crashed": 1, "cases": [ok]},
                   {**base, "cases": [ok, {"case": "b", "error": "no result file"}]},
                   {**base, "cases": [{"case": "a", "comparisons": []}]}):
        assert campaign_verdict_line(broken).startswith("overall: incomplete"), broken
    worse = {**base, "n_failed": 1,
             "cases": [{"case": "a", "comparisons": [{"verdict": "agree"},
                                                     {"verdict": "disagree"}]}]}
    assert campaign_verdict_line(worse).startswith("overall: disagree — 1 of 2")
