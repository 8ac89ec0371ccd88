"""floewave.figures (the paper's Fig. 1) and ``floewave figures --out DIR``."""
import math
import sys

import numpy as np
import pytest

from floewave import cli
from floewave.config import G
from floewave.dispersion import coefficients, solve_dispersion
from floewave.figures import (
    FIELD,
    LAB,
    dispersion_curves,
    fit_power_law,
    mass_loading_cutoff,
    tail_exponent,
    tail_range,
)

PAPER_M_FIELD_EP = 2.397  # paper §3, least-squares fit for the field case
M_TOL_PAPER = 0.05  # our rule (top 2 octaves below 2 Hz) gives 2.392
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_fit_power_law_recovers_exact_power_law_and_skips_nan():
    omega = 2 * np.pi * np.geomspace(0.1, 3.0, 50)
    R = 0.37 * omega**2.6
    R[-5:] = np.nan  # like ml beyond its cutoff
    m, c = fit_power_law(omega, R, 0.2, 3.0)
    assert m == pytest.approx(2.6, rel=1e-12)
    assert c == pytest.approx(0.37, rel=1e-10)
    with pytest.raises(ValueError, match="fewer than 3"):
        fit_power_law(omega, R, 5.0, 6.0)


def test_ow_exponent_approaches_four_in_deep_water():
    # eq. 27: alpha_c,ow = 8 C_sd/(3 pi g^2) f~(kh) omega^4 with f~ -> 1 in deep water.
    m_field, *_ = tail_exponent(FIELD, "ow")  # h = 1000 m: kh > 1000 over the tail
    assert m_field == pytest.approx(4.0, abs=1e-6)
    # finite depth (lab, h = 2.5 m) is close to 4; the deviation shrinks with depth
    devs = [abs(tail_exponent(LAB.replace(h=h), "ow")[0] - 4.0) for h in (2.5, 5.0, 20.0)]
    assert devs[0] < 0.01
    assert devs[0] > devs[1] > devs[2]
    assert devs[2] < 1e-6


@pytest.mark.parametrize("params", [LAB, FIELD], ids=["lab", "field"])
def test_ml_exponent_is_faster_than_omega4(params):
    m, _c, fmin, fmax = tail_exponent(params, "ml")
    assert m > 4.2
    assert fmax < mass_loading_cutoff(params)  # the tail stays below the cutoff
    assert fmin == pytest.approx(fmax / 4)


def test_ep_field_exponent_reproduces_paper():
    m, _c, fmin, fmax = tail_exponent(FIELD, "ep")
    assert (fmin, fmax) == (0.5, 2.0)
    assert 2.0 < m < 2.5
    assert m == pytest.approx(PAPER_M_FIELD_EP, abs=M_TOL_PAPER)
    # one rule for every curve: ow and ep share the tail
    assert tail_range(FIELD, "ow") == tail_range(FIELD, "ep") == (0.5, 2.0)


def test_ml_beyond_cutoff_is_nan_not_an_error():
    fc = mass_loading_cutoff(FIELD)
    assert fc == pytest.approx(math.sqrt(G * 1025 / (910 * 1.5)) / (2 * math.pi))
    f = np.array([0.5 * fc, 0.99 * fc, fc, 1.5 * fc, 3.0])
    c = dispersion_curves(FIELD, f)
    assert np.all(np.isfinite(c["ml"].R[:2])) and np.all(c["ml"].c_g[:2] > 0)
    assert np.all(np.isnan(c["ml"].R[2:])) and np.all(np.isnan(c["ml"].c_g[2:]))
    assert np.all(np.isfinite(c["ep"].R)) and np.all(np.isfinite(c["ow"].R))


@pytest.mark.parametrize("params", [LAB, FIELD], ids=["lab", "field"])
@pytest.mark.parametrize("disp", ["ow", "ml", "ep"])
def test_R_matches_dispersion_module_and_eq26(params, disp):
    f = np.array([0.07, 0.2, 0.35, 0.8, 1.7])
    if disp == "ml":
        f = f[f < 0.95 * mass_loading_cutoff(params)]
    c = dispersion_curves(params, f, (disp,))[disp]
    b1, b2 = coefficients(params.replace(dispersion=disp))
    h = params.h
    for i, fi in enumerate(f):
        cfg = params.replace(dispersion=disp, T=1.0 / fi)
        k, cg = solve_dispersion(cfg)
        w = cfg.omega
        direct = w**3 / (cg * math.tanh(k * h) ** 3)
        assert c.R[i] == pytest.approx(direct, rel=1e-12)
        assert c.c_g[i] == pytest.approx(cg, rel=1e-12)
        # eq. 26 closed form with A = 1 + b1 k tanh kh, B = 1 + b2 k^4 / g
        t = math.tanh(k * h)
        A = 1.0 + b1 * k * t
        B = 1.0 + b2 * k**4 / G
        shallow = 1.0 + 2 * k * h / math.sinh(2 * k * h) if 2 * k * h < 700 else 1.0
        eq26 = 2 * w**4 / G * A**2 / ((B * shallow + 4 * A * (B - 1)) * t**4)
        assert c.R[i] == pytest.approx(eq26, rel=1e-10)


def test_dispersion_curves_accepts_a_mapping():
    p = {"h": 1000.0, "rho_w": 1025.0, "rho_i": 910.0, "E": 6e9, "h_i": 1.5, "nu": 0.3}
    f = np.array([0.1, 0.5])
    a = dispersion_curves(p, f, ("ep",))["ep"]
    b = dispersion_curves(FIELD, f, ("ep",))["ep"]
    np.testing.assert_array_equal(a.R, b.R)


def test_figures_cli_writes_png(run_main, tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "figs" / "nested"
    p = run_main(cli.main, ["figures", "--out", str(out)], tmp_path)
    assert p.returncode == 0, p.stderr
    png = out / "fig1_dispersion.png"
    data = png.read_bytes()
    assert data[:8] == PNG_SIGNATURE
    assert len(data) > 10_000
    assert str(png) in p.stdout
    assert "field ep: m = 2.39" in p.stdout
    assert p.stdout.count("m = ") == 6


def test_figures_cli_unwritable_out_exits_2(run_main, tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    for out in (blocker / "sub", blocker):
        p = run_main(cli.main, ["figures", "--out", str(out)], tmp_path)
        assert p.returncode == 2
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("floewave: error: cannot create")
        assert str(out) in lines[0]
        assert p.stdout == ""


def test_figures_without_matplotlib_exits_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    assert cli.main(["figures", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "matplotlib" in err[0]
    assert not (tmp_path / "o").exists()
