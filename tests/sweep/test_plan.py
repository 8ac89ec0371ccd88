"""sweep.run.plan: kernel shapes, the projection at given rates, and the plan of a campaign."""
import math

import pytest

from sweep import parse_campaign
from sweep.run.plan import core_seconds, given_rate, kernel_shape, plan

# two floe counts (L_sheet / L_x), each twice (two eps), drag by quadrature (cells count)
TOML = """\
[base]
L_sheet = 6.0
drag_integration = "quadrature"
[sweep]
L_x = [0.5, 1.5]
eps = [0.2, 0.6]
"""


def test_kernel_shape_is_floes_drag_cells_mode_confinement_and_chains():
    c = parse_campaign(TOML)
    shapes = {kernel_shape(p.config) for p in c.points()}
    # eps does not change the kernel's speed; floe count and drag mode do
    assert len(shapes) == 2 and all(s[1] > 0 for s in shapes)
    for p in c.points():
        cfg = p.config
        n_x = cfg.n_x if cfg.drag_integration == "quadrature" else 0
        assert kernel_shape(cfg) == (cfg.n_floes, n_x, cfg.drag_integration, cfg.confined,
                                     cfg.n_chains, cfg.drag_every)
    cfg = c.points()[0].config
    assert kernel_shape(cfg.replace(confined=True))[3] is True
    assert kernel_shape(cfg.replace(confined=True))[4] == 1      # confined: one chain
    assert kernel_shape(cfg.replace(drag_integration="exact"))[1:3] == (0, "exact")
    # the ensemble kernel's speed per replica-floe-step depends on R
    assert kernel_shape(cfg.replace(replicas=4))[4] == 4
    assert kernel_shape(cfg.replace(replicas=1))[4] == 1
    # and on how often the drag is evaluated (drag_every: the drag is most of a step)
    assert kernel_shape(cfg.replace(drag_every=2))[5] == 2


def test_projection_is_cost_over_rate_of_each_shape():
    points = parse_campaign(TOML).points()
    rates = {shape: 1e6 * (i + 1) for i, shape in
             enumerate(sorted({kernel_shape(p.config) for p in points}, key=str))}
    expected = sum(p.cost / rates[kernel_shape(p.config)] for p in points)
    assert core_seconds(points, rates) == pytest.approx(expected, rel=1e-12)
    assert math.isnan(core_seconds(points, {}))          # a shape without a rate
    assert core_seconds(points, given_rate(points, 2e6)) == pytest.approx(
        sum(p.cost for p in points) / 2e6, rel=1e-12)


def test_plan_at_a_given_rate():
    points = parse_campaign(TOML).points()
    pl = plan(points, 1e7)
    assert pl.points == 4 and pl.invalid_points == 0
    assert pl.floe_steps == sum(p.cost for p in points)
    assert pl.calibration == "rate given with --rate"
    assert pl.core_hours == pytest.approx(pl.floe_steps / 1e7 / 3600, rel=1e-12)
    assert pl.floe_steps_per_s == pytest.approx(1e7, rel=1e-12)
