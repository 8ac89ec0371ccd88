"""The campaign report: one self-contained HTML page of a store (``sweep report``).

``sweep report STORE --out report.html [--max N]`` writes a single file
that opens offline in any browser (figures embedded as base64 PNG, no network, no
JavaScript framework; a small inline script sorts the tables and checks that every figure
decoded). In order it shows:

1. what ran: the campaign file, the grid (swept values), every ``sweep run`` on the store
   with its provenance (host, ranks, git commit, versions, compute function), the first
   start and last end, and the core-hours of the stored points (sum of their wall times);
2. the status counts, and every point that did not converge or has no result, with its
   swept values and its reason (the error message, or iterations and residual);
3. the paper's figures that the grid allows (:func:`sweep.analysis.figures.make_figures`, at most
   ``--max`` per kind) and, for those it does not allow, why;
4. the collision-zone statistics per floe size, dispersion relation and eps
   (:func:`sweep.collision_stats`: mean ± standard deviation over the pooled points and,
   for ensembles, ± the propagated standard error);
5. any extra sections a caller passes (``sections``: functions returning an
   :data:`Section`, e.g. a study's table; sweep knows nothing of them).

:func:`table`, :func:`text_cell`, :func:`number_cell` and :func:`escape` make the HTML of
such a section as the report's own.
"""
from __future__ import annotations

import base64
import html
import json
import math
import os
import tempfile
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from sweep.analysis.figures import make_figures
from sweep.analysis.load import journal_points, load, store_attrs, store_runs
from sweep.analysis.stats import collision_stats
from sweep.errors import EXIT_OK, ConfigError

__all__ = ["build_report", "write_report", "command", "PROBLEM_STATUSES", "Section", "table",
           "text_cell", "number_cell", "escape"]

#: An extra section of a report: (anchor id, title in the contents line, its HTML).
Section = tuple[str, str, str]

#: Statuses listed point by point: every status that is not a converged result.
PROBLEM_STATUSES = ("not_converged", "failed", "invalid", "crashed", "timeout")

#: What each figure shows (by file-name prefix), shown under it.
CAPTIONS = {
    "fig2": "Fig. 2: a/a₀ versus x per ε, one panel per dispersion relation; dots at "
            "x = W_c, dashed: compact ice from there, solid black: eq. 25.",
    "fig3": "Fig. 3: mean gap (log axis, dotted: the W_c threshold), |F_w|, |F_c|, |F_d| "
            "versus x per ε.",
    "fig5": "Fig. 5: a/a₀ per floe size; line style by dispersion relation.",
    "fig6_df": "Fig. 6: a/a₀ per mean gap d_f, one panel per wave period.",
    "fig6_a0": "Fig. 6: a/a₀ per incident amplitude a₀, one panel per wave period.",
    "collision_zone": "Collision-zone width W_c versus ε (crosses at the top: no compact "
                      "zone).",
    "collision_stats": "W_c / L_sheet and α_inner / α_c versus ε, pooled over the other "
                       "parameters (bars: ±1 standard deviation).",
    "alpha_omega": "Attenuation rate versus angular frequency with fitted exponents m.",
}

STYLE = """
body{font-family:system-ui,sans-serif;max-width:1180px;margin:1em auto;padding:0 1em;
color:#222;line-height:1.4}
h1{font-size:1.5em}h2{border-bottom:1px solid #ccc;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0;font-size:.86em}
th,td{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}
th{background:#eee;cursor:pointer;user-select:none}td.n{text-align:right}
.bad{background:#fde2e2}.warn{background:#fff4d6}.ok{background:#e3f5e1}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:.86em;color:#444}pre{background:#f6f6f6;padding:.5em;overflow:auto}
"""

#: Sortable tables (click a header) and the self-check: every <img> must have decoded;
#: the title becomes "ok N" (N images) or "error: ..." (the browser test reads it).
SCRIPT = """
document.querySelectorAll('table.sortable th').forEach(function(th){
  th.addEventListener('click', function(){
    var col = th.cellIndex;
    var body = th.closest('table').tBodies[0];
    var rows = Array.prototype.slice.call(body.rows);
    var up = th.dataset.dir !== 'up'; th.dataset.dir = up ? 'up' : 'down';
    rows.sort(function(a, b){
      var x = a.cells[col].dataset.v || a.cells[col].textContent;
      var y = b.cells[col].dataset.v || b.cells[col].textContent;
      var p = parseFloat(x), q = parseFloat(y);
      var c = (isNaN(p) || isNaN(q)) ? x.localeCompare(y) : p - q;
      return up ? c : -c;
    });
    rows.forEach(function(r){ body.appendChild(r); });
  });
});
window.addEventListener('load', function(){
  var imgs = document.images, bad = [];
  for (var i = 0; i < imgs.length; i++) {
    if (!imgs[i].complete || imgs[i].naturalWidth === 0) { bad.push(imgs[i].alt); }
  }
  document.title = bad.length ? 'error: not decoded: ' + bad.join(', ')
                              : 'ok ' + imgs.length;
});
"""


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _num(value: Any) -> str:
    """A table cell for a number (right-aligned, sortable by value); '—' for NaN."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return f"<td>{_e(value)}</td>"
    if not math.isfinite(v):
        return '<td class="n" data-v="">—</td>'
    text = f"{int(v)}" if v.is_integer() and abs(v) < 1e15 else f"{v:.4g}"
    return f'<td class="n" data-v="{v!r}">{text}</td>'


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], *, classes: Sequence[str]
           = ()) -> str:
    """A sortable table; ``rows`` hold ready-made ``<td>`` cells."""
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = []
    for i, cells in enumerate(rows):
        cls = f' class="{classes[i]}"' if i < len(classes) and classes[i] else ""
        body.append(f"<tr{cls}>{''.join(cells)}</tr>")
    return (f'<table class="sortable"><thead><tr>{head}</tr></thead><tbody>'
            f"{''.join(body)}</tbody></table>")


def _td(value: Any) -> str:
    return f"<td>{_e(value)}</td>"


#: The report's own makers of HTML, for an extra section that looks like the rest: a
#: sortable table of ready-made cells, a text cell, a number cell, text escaped.
table, text_cell, number_cell, escape = _table, _td, _num, _e


def _when(text: Any) -> str:
    """An ISO time as ``YYYY-MM-DD HH:MM:SS UTC`` ('—' if unset)."""
    text = str(text or "")
    return f"{text[:19].replace('T', ' ')} UTC" if text else "—"


# ---------------------------------------------------------------------- sections
def _what_ran(path: Path, attrs: dict[str, Any], runs: list[dict[str, Any]],
              df: pd.DataFrame, sweep: dict[str, list], total: int) -> str:
    grid = _table(["parameter", "values", "n"],
                  [[_td(k), _td(", ".join(str(v) for v in vals)), _num(len(vals))]
                   for k, vals in sweep.items()])
    run_rows = []
    for r in runs:
        dirty = " (dirty)" if bool(r.get("git_dirty", False)) else ""
        run_rows.append([_num(r["index"]), _td(_when(r.get("started"))),
                         _td(_when(r.get("ended")) if r.get("ended") else "(running or killed)"),
                         _td(r.get("outcome", "")), _num(r.get("mpi_size", 1)),
                         _td(r.get("host", "")),
                         _td(f"{str(r.get('git_commit', ''))[:12]}{dirty}"),
                         _td(f"floewave {r.get('floewave_version', '?')}, model "
                             f"{r.get('model_version', '?')}; numba {r.get('numba', '?')}, "
                             f"numpy {r.get('numpy', '?')}, python {r.get('python', '?')}"),
                         _td(r.get("compute", "")), _td(r.get("command", ""))])
    runs_html = _table(["run", "started", "ended", "outcome", "ranks", "host", "git commit",
                        "versions", "compute", "command"], run_rows)
    wall = float(df["wall_time"].sum()) if len(df) else 0.0
    starts = [r["started"] for r in runs if r.get("started")]
    ends = [r["ended"] for r in runs if r.get("ended")]
    allocated = sum((datetime.fromisoformat(r["ended"]) - datetime.fromisoformat(r["started"]))
                    .total_seconds() * int(r.get("mpi_size", 1))
                    for r in runs if r.get("started") and r.get("ended"))
    span = (f"First start {_when(min(starts)) if starts else '—'}, last end "
            f"{_when(max(ends)) if ends else '—'}")
    return (f"<h2 id=\"what-ran\">What ran</h2><p>Store <code>{_e(path)}</code> (schema "
            f"{_e(attrs.get('schema_version', '?'))}, created {_e(_when(attrs.get('created')))}"
            f"); {total} grid points, {len(df)} stored. {span}. Compute: "
            f"<b>{wall / 3600:.3g} core-hours</b> ({wall:.4g} s, the sum of the stored "
            f"points' wall times); allocated {allocated / 3600:.3g} core-hours (each run's"
            " duration times its ranks, the master's included).</p><h3>Grid</h3>" + grid
            + "<h3>Runs on this store</h3>" + runs_html
            + "<details><summary>campaign file</summary><pre>"
            + _e(attrs.get("campaign_toml", "")) + "</pre></details>")


def _status(df: pd.DataFrame, dims: Sequence[str], total: int, journaled: int | None) -> str:
    found = df["status"].astype(str).value_counts()
    order = [s for s in ("converged", "converged_noisy", *PROBLEM_STATUSES) if s in found]
    counts = found[order + [s for s in found.index if s not in order]]
    cls = {"converged": "ok", "converged_noisy": "ok", "not_converged": "warn"}
    rows = [[_td(s), _num(n)] for s, n in counts.items()]
    rows.append([_td("not yet computed"), _num(max(total - len(df), 0))])
    classes = [cls.get(str(s), "bad") for s in counts.index] + [""]
    out = '<h2 id="status">Status</h2>' + _table(["status", "points"], rows, classes=classes)
    if journaled is not None and journaled > len(df):
        out += (f"<p>The journal holds {journaled} points, {journaled - len(df)} more than the "
                "file: a live run mid-commit, or a killed one (its next run writes them).</p>")
    bad = df[df["status"].astype(str).isin(PROBLEM_STATUSES)]
    if bad.empty:
        return out + "<p>Every stored point converged.</p>"
    rows, classes = [], []
    for _, r in bad.sort_values(["status", *dims]).iterrows():
        status = str(r["status"])
        if status == "not_converged":
            reason = (f"error bars above their targets or no stationary stretch after "
                      f"{int(r['iterations'])} iterations, "
                      f"residual {float(r['residual']):.3g} (its estimate so far is stored,"
                      " with its error bars)")
        else:
            lines = str(r.get("message", "")).strip().splitlines()
            reason = lines[-1] if lines else "(no message)"
        full = str(r.get("message", "")).strip() or reason
        rows.append([_td(str(r["hash"])[:12]), _td(status)]
                    + [_num(r[d]) if d != "dispersion" else _td(r[d]) for d in dims]
                    + [f'<td title="{_e(full)}">{_e(reason)}</td>'])
        classes.append(cls.get(status, "bad"))
    return (out + f"<h3>Points that did not converge or have no result ({len(bad)})</h3>"
            + _table(["hash", "status", *dims, "reason"], rows, classes=classes))


def _img(png: Path, name: str | None = None) -> str:
    """One figure, captioned with ``name`` (default its file name; a seed's figures:
    ``seed=<S>/<file>``)."""
    name = name or png.name
    data = base64.b64encode(png.read_bytes()).decode("ascii")
    prefix = next((p for p in sorted(CAPTIONS, key=len, reverse=True)
                   if png.name.startswith(p)), "")
    return (f'<figure><img alt="{_e(name)}" src="data:image/png;base64,{data}">'
            f"<figcaption><b>{_e(name)}</b> — {_e(CAPTIONS.get(prefix, ''))}"
            "</figcaption></figure>")


def _figures(path: Path, max_figures: int) -> str:
    notes: list[str] = []
    with tempfile.TemporaryDirectory(prefix="sweep-report-") as tmp:
        try:
            files = make_figures(path, tmp, max_figures=max_figures, log=notes.append)
        except ConfigError as exc:   # nothing drawable, no results, no matplotlib
            files = []
            notes = notes or [str(exc)]
        imgs = "".join(_img(f, str(Path(f).relative_to(tmp))) for f in files)
    why = "".join(f"<li>{_e(n)}</li>" for n in notes)
    return ('<h2 id="figures">Figures</h2>'
            + (f"<p>Not drawn:</p><ul>{why}</ul>" if why else "")
            + (imgs or "<p>No figure can be drawn from this store.</p>"))


def _pm(mean: Any, spread: Any) -> str:
    m, s = float(mean), float(spread)
    if not math.isfinite(m):
        return '<td class="n" data-v="">—</td>'
    text = f"{m:.3g} ± {s:.2g}" if math.isfinite(s) else f"{m:.3g}"
    return f'<td class="n" data-v="{m!r}">{_e(text)}</td>'


def _collision(df: pd.DataFrame) -> str:
    by = [k for k in ("L_x", "dispersion", "eps") if k in df.columns]
    st = collision_stats(df, by=by)
    if st.empty:
        return '<h2 id="collision">Collision-zone statistics</h2><p>No point with a result.</p>'
    rows, classes = [], []
    for _, r in st.iterrows():
        rows.append([_num(r[k]) if k != "dispersion" else _td(r[k]) for k in by]
                    + [_num(r["n_points"]), _num(r["n_not_converged"]), _num(r["n_W_c"]),
                       _num(r["frac_no_compact_zone"]), _pm(r["W_c_mean"], r["W_c_std"]),
                       _pm(r["W_c_mean"], r["W_c_mean_stderr"]),
                       _pm(r["W_c_rel_mean"], r["W_c_rel_std"]),
                       _pm(r["inner_over_c_mean"], r["inner_over_c_mean_stderr"]),
                       _num(r["inner_over_c_median"])])
        classes.append("warn" if r["n_not_converged"] else "")
    return ('<h2 id="collision">Collision-zone statistics</h2><p>One row per L_x,'
            " dispersion and ε, pooled"
            " over the other swept parameters (<code>sweep.collision_stats</code>). ± std:"
            " spread over the pooled points; ± SE: standard error of the mean from the"
            " points' ensemble standard errors (— for single-trajectory points). Rows with"
            " not-converged points are shaded.</p>"
            + _table([*by, "points", "not converged", "with W_c", "share without compact "
                      "zone", "W_c [m] ± std", "W_c [m] ± SE", "W_c / L_sheet ± std",
                      "α_inner/α_c ± SE", "α_inner/α_c median"], rows, classes=classes))


# ---------------------------------------------------------------------- the page
def build_report(store: str | Path, *, sections: Sequence[Callable[[], Section]] = (),
                 max_figures: int = 3) -> str:
    """The HTML text of the report of ``store`` (see the module docstring).

    Parameters
    ----------
    store : the HDF5 store of a campaign.
    sections : functions each returning an extra :data:`Section`, called in order after
        the report's own sections are made (e.g. a study's table of its own).
    max_figures : at most this many figures per kind (groups closest to the paper first).
    """
    path = Path(store)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such store")
    attrs = store_attrs(path)
    campaign = json.loads(attrs.get("campaign_json", "{}"))
    dims = list(campaign.get("sweep", {}))
    df = load(path)
    total = int(np.prod([len(v) for v in campaign.get("sweep", {}).values()])) if dims else 1
    now = datetime.now(UTC).isoformat(timespec="seconds")
    parts = [_what_ran(path, attrs, store_runs(path), df, campaign.get("sweep", {}), total),
             _status(df, dims, total, journal_points(path)), _figures(path, max_figures),
             _collision(df)]
    toc_items = [("what-ran", "What ran"), ("status", "Status"), ("figures", "Figures"),
                 ("collision", "Collision-zone statistics")]
    for make in sections:
        anchor, title, text = make()
        parts.append(text)
        toc_items.append((anchor, title))
    toc = " · ".join(f'<a href="#{i}">{t}</a>' for i, t in toc_items)
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>report {_e(path.name)}</title><style>{STYLE}</style></head><body>"
            f"<h1>Campaign report: {_e(path.name)}</h1><p>Written {_e(_when(now))} by "
            f"<code>sweep report</code>. {toc}</p>" + "".join(parts)
            + f"<script>{SCRIPT}</script></body></html>\n")


def write_report(store: str | Path, out: str | Path, *,
                 sections: Sequence[Callable[[], Section]] = (), max_figures: int = 3) -> Path:
    """Write :func:`build_report` of ``store`` to ``out`` (replaced atomically)."""
    out = Path(out)
    text = build_report(store, sections=sections, max_figures=max_figures)
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, out)
    return out


def command(args: Any, *, sections: Sequence[Callable[[], Section]] = (),
            prog: str = "sweep") -> int:
    """``sweep report STORE --out FILE [--max N]`` (status 0; 2 for a bad argument, 3 for a
    missing or unreadable store); ``sections`` as :func:`build_report`'s, ``prog`` names
    the command in its last line."""
    if args.max < 1:
        raise ConfigError(f"--max {args.max}: must be at least 1")
    out = Path(args.out)
    if out.is_dir() or not out.parent.is_dir():
        raise ConfigError(f"--out {out}: expected a file name in an existing directory")
    write_report(args.store, out, sections=sections, max_figures=args.max)
    print(f"{prog}: wrote {out}")
    return EXIT_OK
