"""Which of the paper's cases a world runs (sandbox.app.world.snapshot.running_case), asked by the panel
every frame and remembered."""

from sandbox.app.world.snapshot import running_case


def test_the_case_is_its_goal_and_exactly_its_strategies_on_the_scaled_outline():
    assert running_case("star", {"switch": 0.25, "no_corners": 0.5}) == "star-switch-nocorners"
    # strategies off (0) are not strategies on; the order they come in does not matter
    assert running_case("square", {"switch": 0.25, "flare": 1.75, "chase": 0.0}) == "square-flare-switch"
    assert running_case("star", {"chase": 0.0, "switch": 0.0}) == "star"
    # another amount, an extra strategy or another outline is not the paper's case
    assert running_case("star", {"switch": 0.3}) is None
    assert running_case("circle", {"chase": 2.0}) is None
    assert running_case("star", {"switch": 0.25}, family="offset") is None
    assert running_case("l-shape", {}) is None


def test_a_case_asked_again_is_answered_alike():
    # remembered by value: a new dict with the same strategies finds the same answer
    for _ in range(3):
        assert running_case("star", dict(switch=0.25)) == "star-switch"
    assert running_case("star", {"switch": 0.25, "flare": 1.75}) is None
