"""sweep.run.warmup: one shrunken configuration per kernel variant, only for the model's
own compute function; a failing warm-up is reported, not raised."""
from __future__ import annotations

import pytest

from floewave import ModelConfig
from floewave.model import kernel_mode
from sweep import parse_campaign
from sweep.run.warmup import WARMED, warm_up, warm_up_configs

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4]\n"


@pytest.mark.parametrize("base", ["", "confined = true\n", 'drag_integration = "exact"\n'])
def test_one_small_configuration_per_kernel_variant(base):
    points = parse_campaign(TOML.replace("[base]\n", "[base]\n" + base)).points()
    configs = warm_up_configs(points, WARMED)
    assert len(configs) == 1  # L_x and eps do not change the kernel
    assert kernel_mode(ModelConfig.from_dict(configs[0])) == kernel_mode(points[0].config)
    for c in configs:
        cfg = ModelConfig.from_dict(c)
        assert (cfg.n0, cfg.nT, cfg.max_iterations, cfg.replicas) == (1, 1, 1, 1)
        assert cfg.L_sheet == 4 * cfg.L_x  # four floes


def test_other_compute_functions_are_not_warmed(campaign):
    assert warm_up_configs(campaign.points(), "sweep.testing:fake_point") == []


def test_a_failing_warm_up_is_reported_not_raised(campaign):
    configs = [p.config.to_dict() for p in campaign.points() if p.config.eps == 0.4][:1]
    seconds, problem = warm_up(configs, "sweep.testing:raising_point")
    assert seconds >= 0 and problem == "RuntimeError: deliberate failure for eps = 0.4"
    assert warm_up([], "sweep.testing:raising_point") == (0.0, "")
    assert warm_up(configs, "sweep.testing:fake_point")[1] == ""
