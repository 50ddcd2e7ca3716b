"""``phototaxis bench --hosted K`` (sandbox.commands.hosted_bench): K worlds in world hosts, each world's
speed and frames, each host's CPU and memory, and the memory each world adds beyond the first."""

from __future__ import annotations

import pytest

from sandbox.cli import UserError
from sandbox.commands import build_parser, hosted_bench
from sandbox.model.config import Config

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)


def test_the_flags_reach_the_benchmark():
    args = build_parser("bench").parse_args(["bench", "--hosted", "30", "--hosts", "2", "--skip", "20000"])
    assert (args.hosted, args.hosts, args.skip) == (30, 2, 20000)


@pytest.mark.slow
def test_it_reports_each_world_and_host(monkeypatch):
    """A fork server, a host and three worlds: seconds (the flags' test above is its fast neighbour)."""
    monkeypatch.setattr(hosted_bench, "WARM_UP", 0.3)
    result = hosted_bench.run(SMALL, 3, 0.6, hosts=1, skip=300)
    assert result["worlds"] == 3 and result["hosts"] == 1 and result["per_host"][0]["worlds"] == 3
    assert result["target_steps_per_second"] == 90.0 and result["restarts"] == 0
    assert 0 < result["steps_per_second"]["min"] <= result["steps_per_second"]["max"]
    assert result["frames_per_second"]["min"] > 0 and result["rss_per_world_beyond_first_mb"] is not None
    assert result["host_cpu_us_per_step"] > 0 and result["per_host"][0]["rss_mb"] > 0


def test_no_world_is_refused_in_a_line():
    with pytest.raises(UserError, match="at least one world"):
        hosted_bench.run(SMALL, 0, 1.0)
