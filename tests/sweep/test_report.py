"""``sweep report``: the HTML page of a small hand-built store, and that page in Chromium."""
import base64
import os
import re
import shutil
import subprocess

import pytest

from sweep import parse_campaign, run_campaign
from sweep.cli import main
from sweep.testing import power_point

pytest.importorskip("matplotlib")

TOML = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5, 1.0]
eps = [0.2, 0.4, 0.8]
dispersion = ["ep", "ml"]
"""
PNG = b"\x89PNG\r\n\x1a\n"


def mixed_point(cfg):
    """``power_point`` (not converged for eps >= 0.7), but failing for eps = 0.4 with L_x = 1."""
    if cfg.eps == 0.4 and cfg.L_x == 1.0:
        raise RuntimeError(f"deliberate failure for L_x = {cfg.L_x}")
    return power_point(cfg)


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("report") / "mixed.h5"
    run_campaign(parse_campaign(TOML, "mixed.toml"), str(path),
                 compute="tests.sweep.test_report:mixed_point", progress_bar=False)
    return path


@pytest.fixture(scope="module")
def page(store, tmp_path_factory):
    out = tmp_path_factory.mktemp("html") / "report.html"
    assert main(["report", str(store), "--out", str(out), "--max", "1"]) == 0
    return out


def _rows(html, status):
    return re.findall(rf"<tr[^>]*><td>[0-9a-f]{{12}}</td><td>{status}</td>(.*?)</tr>", html,
                      re.S)


def test_status_counts_and_every_problem_point_with_its_values(page):
    html = page.read_text()
    # 12 points: 2 failed (eps 0.4, L_x 1), 4 not converged (eps 0.8), 6 converged
    for status, n in (("converged", 6), ("not_converged", 4), ("failed", 2)):
        assert re.search(rf"<td>{status}</td><td class=\"n\" data-v=\"{n}.0\">{n}</td>", html)
    failed = _rows(html, "failed")
    assert len(failed) == 2
    assert all("deliberate failure for L_x = 1.0" in r and ">0.4<" in r and ">1<" in r
               for r in failed)
    assert {"ep", "ml"} == {re.search(r"<td>(ep|ml)</td>", r).group(1) for r in failed}
    not_conv = _rows(html, "not_converged")
    assert len(not_conv) == 4 and all("error bars above their targets" in r for r in not_conv)
    assert "Points that did not converge or have no result (6)" in html


def test_what_ran_grid_runs_and_core_hours(page, store):
    html = page.read_text()
    assert "<td>eps</td><td>0.2, 0.4, 0.8</td>" in html
    assert "tests.sweep.test_report:mixed_point" in html       # the run's compute function
    assert "12 grid points, 12 stored" in html
    assert re.search(r"<b>[0-9.e+-]+ core-hours</b>", html)
    assert "[sweep]" in html                                      # the campaign file


def test_figures_are_embedded_and_decode(page):
    html = page.read_text()
    images = re.findall(r'<img alt="([^"]+)" src="data:image/png;base64,([^"]+)"', html)
    names = [n for n, _ in images]
    # --max 1: fig2, fig3, fig5 and collision_zone and collision_stats (one T: no fig6,
    # no alpha_omega, and the page says why)
    assert sum(n.startswith("fig2_") for n in names) == 1
    assert {"collision_zone.png", "collision_stats.png"} <= set(names)
    assert len(images) == 5, names
    assert all(base64.b64decode(data)[:8] == PNG for _, data in images)
    assert "alpha_omega not drawn: needs &gt;= 3 wave periods" in html
    assert "fig6_df not drawn" in html


def test_the_page_needs_no_network(page):
    html = page.read_text()
    assert not re.search(r"(src|href)=\"(https?:)?//", html)
    assert "<script src" not in html and "@import" not in html


def test_an_extra_section_from_outside_and_missing_store(tmp_path, store, capsys):
    """A caller's section (a study's table: ``herman2019 report``) goes last, in the
    contents line too; sweep knows nothing of it."""
    from sweep.report import number_cell, table, text_cell, write_report

    out = tmp_path / "r.html"
    made = []

    def extra():
        made.append(1)
        return ("extra", "Extra", '<h2 id="extra">Extra</h2>'
                + table(["k", "n"], [[text_cell("a<b"), number_cell(2.0)]], classes=["ok"]))

    write_report(store, out, sections=[extra], max_figures=1)
    html = out.read_text()
    assert made == [1] and ">Extra</h2>" in html and 'href="#extra"' in html
    assert html.index('id="collision"') < html.index('id="extra"')
    assert '<tr class="ok"><td>a&lt;b</td><td class="n" data-v="2.0">2</td></tr>' in html
    assert main(["report", str(store), "--out", str(out), "--max", "1"]) == 0
    assert 'href="#extra"' not in out.read_text()
    assert main(["report", str(tmp_path / "nope.h5"), "--out", str(out)]) == 3
    assert "no such store" in capsys.readouterr().err
    assert main(["report", str(store), "--out", str(tmp_path / "no" / "r.html")]) == 2


# ---------------------------------------------------------------------- a real browser
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--enable-logging=stderr",
                  "--v=0", "--window-size=1280,2000"]


def _chromium():
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        message = "chromium not installed (apt-get install -y chromium)"
        if os.environ.get("FLOEWAVE_REQUIRE_CHROMIUM") == "1":
            pytest.fail(message + " and FLOEWAVE_REQUIRE_CHROMIUM=1")
        pytest.skip(message)
    return exe


def _browse(exe, tmp_path, page, *args):
    run = subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
                          *args, page.resolve().as_uri()],
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr[-2000:]
    console = [ln for ln in run.stderr.splitlines() if ":CONSOLE" in ln]
    assert not console, console                   # no console message, error or otherwise
    return run


def test_report_renders_in_headless_chromium(page, tmp_path):
    import matplotlib.image

    exe = _chromium()
    n_images = page.read_text().count("<img ")
    dom = _browse(exe, tmp_path, page, "--dump-dom").stdout
    # the page's own check: every <img> complete with naturalWidth > 0
    assert re.search(r"<title>([^<]*)</title>", dom).group(1) == f"ok {n_images}"
    shot = tmp_path / "shot.png"
    _browse(exe, tmp_path, page, f"--screenshot={shot}")
    pixels = matplotlib.image.imread(shot)[..., :3]
    assert pixels.shape[:2] == (2000, 1280)
    colours = {tuple(p) for p in pixels[::7, ::7].reshape(-1, 3)}
    assert len(colours) > 20                      # text, tables and figures, not blank
    assert (pixels.min(axis=2) < 0.5).mean() > 0.01     # some dark ink on the page


def test_the_browser_check_catches_a_broken_image(tmp_path):
    """The check above can fail: a page with an undecodable image gets an error title."""
    from sweep.report import SCRIPT

    exe = _chromium()
    bad = tmp_path / "bad.html"
    bad.write_text('<html><head><title>t</title></head><body><img alt="broken" '
                   f'src="data:image/png;base64,AAAA"><script>{SCRIPT}</script></body></html>')
    dom = _browse(exe, tmp_path, bad, "--dump-dom").stdout
    assert "<title>error: not decoded: broken</title>" in dom


def test_a_store_without_results_still_reports(tmp_path):
    """Every point failed: the page lists them and says why there are no figures."""
    store = tmp_path / "failed.h5"
    run_campaign(parse_campaign("[base]\nL_sheet = 6.0\n[sweep]\neps = [0.4]\n"
                                "L_x = [0.5, 1.0]\n", "f.toml"), str(store),
                 compute="sweep.testing:raising_point", progress_bar=False)
    out = tmp_path / "r.html"
    assert main(["report", str(store), "--out", str(out)]) == 0
    html = out.read_text()
    assert len(_rows(html, "failed")) == 2
    assert "no stored results to plot" in html and "<img" not in html
    assert "No point with a result." in html


def test_a_header_click_sorts_its_table_in_chromium(page, tmp_path):
    """The inline sort: the problem points' eps column, ascending then descending."""
    exe = _chromium()
    probe = """<script>window.addEventListener('load', function(){
      var t = document.querySelectorAll('table.sortable')[3], th = t.tHead.rows[0].cells[4];
      var col = function(){ return [].map.call(t.tBodies[0].rows,
                                               function(r){ return r.cells[4].textContent; }); };
      th.click(); var up = col(); th.click(); var down = col();
      setTimeout(function(){ document.title = up.join(',') + ' / ' + down.join(','); }, 0);
    });</script></body>"""
    sortable = tmp_path / "sort.html"
    sortable.write_text(page.read_text().replace("</body>", probe))
    dom = _browse(exe, tmp_path, sortable, "--dump-dom").stdout
    title = re.search(r"<title>([^<]*)</title>", dom).group(1)
    up, down = (part.split(",") for part in title.split(" / "))
    assert sorted(up, key=float) == up and up[::-1] == down and len(up) == 6, title
    assert up[0] != up[-1]


def test_problem_points_carry_their_whole_message_and_counts_come_in_order(page):
    html = page.read_text()
    assert re.search(r'<td title="[^"]*RuntimeError: deliberate failure[^"]*">', html)
    statuses = re.findall(r'<tr class="\w+"><td>(\w+)</td><td class="n"', html)
    assert statuses[:3] == ["converged", "not_converged", "failed"]


@pytest.mark.slow   # the fast tier proves the page and its browser check on 12 points
def test_the_report_of_a_whole_grid_opens_in_chromium(tmp_path):
    """The paper's grid, 24,192 points (a cheap compute on a 6 m sheet): the report is one
    page a browser opens, its every figure decoded, its size a few MB (the figures are
    capped per kind, the problem points listed once each)."""
    from pathlib import Path

    exe = _chromium()
    text = (Path(__file__).parents[2] / "configs" / "herman2019.toml").read_text()
    assert "L_sheet = 42.0" in text
    small = parse_campaign(text.replace("L_sheet = 42.0", "L_sheet = 6.0"), "herman2019.toml")
    assert len(small.points()) == 24192
    store = tmp_path / "grid.h5"
    run_campaign(small, str(store), compute="sweep.testing:fake_point", progress_bar=False)
    out = tmp_path / "grid.html"
    assert main(["report", str(store), "--out", str(out)]) == 0
    html = out.read_text()
    assert "24192" in html.replace(",", "")
    assert out.stat().st_size < 10e6
    n_images = html.count("<img ")
    assert n_images >= 5
    dom = _browse(exe, tmp_path, out, "--dump-dom").stdout
    assert re.search(r"<title>([^<]*)</title>", dom).group(1) == f"ok {n_images}"
