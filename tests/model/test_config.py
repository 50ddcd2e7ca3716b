"""The parameter declaration, config files and cases."""

import json
import time

import pytest

from sandbox.model.config import CASES, Config, ConfigError, case_config, load_config_file, param_names, params


def test_every_parameter_is_documented():
    for p in params():
        assert p.help and p.group
        if p.type in (int, float):
            assert p.low is not None and p.high is not None
            assert p.low <= p.default <= p.high, p.name


def test_spec_defaults():
    c = Config()
    assert (c.arena_size, c.construction_size, c.robots, c.boxes) == (64, 16, 200, 500)
    assert (c.k_drive, c.k_turn, c.command_period) == (5, 20, 50)
    assert (c.eta_in, c.metabolic, c.eta_out, c.capacity, c.start_charge) == (0.4, 0.01, 0.1, 20, 0)
    assert (c.update_every, c.scale_rate, c.light_range) == (100, 0.975, 12.8)
    assert c.lights_per_side == 64


def test_default_profile_is_the_authors_program():
    """SPEC §9: every row has its own parameter, and the default profile takes the program's values."""
    c = Config()
    assert c.profile == "authors-code"
    assert (c.light_height, c.light_falloff, c.light_angle, c.light_window) == (2.0, 2.0, "squared-offsets", "cells")
    assert (c.box_size_is, c.photocells, c.steering, c.motor) == ("circumradius", "corners", "front", "set-once")
    assert (c.energy_turn_cost, c.box_damping_model, c.min_size_rule) == ("signed", "box2d", "inradius")
    assert (c.hold_steps, c.flare_mode, c.switch_mode) == (100, "scaled-outline", "inradius")
    assert (c.size_schedule, c.polygon_max_rule, c.centre) == ("program", "grow", 32.5)


def test_paper_text_profile():
    c = Config(profile="paper-text")
    assert (c.light_height, c.light_falloff, c.light_angle, c.light_window) == (1.0, 1.0, "elevation", "range")
    assert (c.box_size_is, c.photocells, c.steering, c.motor) == ("apothem", "axes", "sides", "continuous")
    assert (c.energy_turn_cost, c.box_damping_model, c.min_size_rule) == ("absolute", "exponential", "equal-area")
    assert (c.hold_steps, c.flare_mode, c.switch_mode) == (25, "on-goal", "fraction")
    assert (c.size_schedule, c.polygon_max_rule, c.centre) == ("clamped", "fit", 32.0)
    assert c.differences_from_profile() == {}


def test_explicit_values_win_over_the_profile():
    c = Config(profile="paper-text", light_height=2.0)
    assert (c.light_height, c.light_falloff) == (2.0, 1.0)
    assert c.differences_from_profile() == {"light_height": 2.0}
    # Changing the profile takes the new profile's values, except those given with it.
    back = c.replace(profile="authors-code", motor="continuous")
    assert (back.light_height, back.motor, back.photocells) == (2.0, "continuous", "corners")
    assert Config().replace(profile="paper-text").light_height == 1.0


def test_a_profile_and_overrides_from_files_and_flags(tmp_path):
    from sandbox.cli import config_from_args
    from sandbox.commands import build_parser

    f = tmp_path / "c.toml"
    f.write_text('light_height = 3.0\n')
    args = build_parser("run").parse_args(["run", "--config", str(f), "--profile", "paper-text", "--k-turn", "7"])
    c = config_from_args(args)
    # The flag's profile does not undo the file's explicit value.
    assert (c.profile, c.light_height, c.light_falloff, c.k_turn) == ("paper-text", 3.0, 1.0, 7.0)


def test_a_result_file_reproduces_its_profile_and_values(tmp_path):
    original = Config(profile="paper-text", light_falloff=2.0)
    js = tmp_path / "r.json"
    js.write_text(json.dumps({"config": original.to_dict()}))
    assert load_config_file(js) == original


def test_bad_profile():
    with pytest.raises(ConfigError, match="profile"):
        Config().replace(profile="mine")


@pytest.mark.parametrize("bad", [dict(robots=-1), dict(k_drive=float("nan")), dict(box_size_is="side"),
                                 dict(flare=11), dict(construction_size=70), dict(arena_size=64.5)])
def test_bad_values_are_refused_with_a_message(bad):
    with pytest.raises(ConfigError) as err:
        Config().replace(**bad)
    assert "\n" not in str(err.value)


def test_unknown_parameter():
    with pytest.raises(ConfigError, match="unknown parameter"):
        Config().replace(robotz=3)


def test_strings_are_coerced():
    c = Config().replace(robots="12", k_drive="2.5")
    assert c.robots == 12 and c.k_drive == 2.5
    with pytest.raises(ConfigError, match="whole number"):
        Config().replace(robots="1.5")


def test_toml_and_json_files(tmp_path):
    toml = tmp_path / "c.toml"
    toml.write_text('robots = 10\n[controller]\nshape = "star"\nhold_steps = 3\n')
    c = load_config_file(toml)
    assert (c.robots, c.shape, c.hold_steps) == (10, "star", 3)
    js = tmp_path / "c.json"
    js.write_text(json.dumps({"config": Config(boxes=7).to_dict()}))  # a result file
    assert load_config_file(js).boxes == 7


@pytest.mark.parametrize("text, message", [("robots = ", "not valid"), ("robotz = 1", "unknown"),
                                           ("robots = 'many'", "whole number")])
def test_bad_files(tmp_path, text, message):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config_file(f)


def test_cases():
    assert len(CASES) == 7
    c = case_config("star-switch-nocorners")
    assert (c.shape, c.switch, c.no_corners, c.flare) == ("star", 0.25, 0.5, 0.0)
    with pytest.raises(ConfigError, match="unknown case"):
        case_config("hexagon")
    assert "seed" in param_names()


def test_result_files_from_before_profiles_are_read_as_paper_text(tmp_path):
    """Results written before profiles existed hold today's paper-text model without saying so."""
    old = Config(profile="paper-text").to_dict()
    for name in ("profile", "assembly_centre", "photocells", "motor"):  # keys the old files did not have
        old.pop(name)
    js = tmp_path / "old.json"
    js.write_text(json.dumps({"config": old, "seed": 0, "steps": 100, "samples": []}))
    assert load_config_file(js) == Config(profile="paper-text")


def test_a_config_table_in_a_config_file_is_a_group_like_any_other(tmp_path):
    """Only a result file's [config] is read as a record; in a config file it is a group of values, the
    profile stays the default and an unknown name is an error."""
    f = tmp_path / "c.toml"
    f.write_text("[config]\nlight_falloff = 2.0\n")
    assert load_config_file(f) == Config(light_falloff=2.0)
    assert load_config_file(f).profile == Config().profile
    f.write_text("robots = 120\n[config]\nboxes = 300\n")
    assert (load_config_file(f).robots, load_config_file(f).boxes) == (120, 300)  # neither replaces the other
    f.write_text("[config]\nrobots = 120\nnope = 1\n")
    with pytest.raises(ConfigError, match="unknown parameter.*nope"):
        load_config_file(f)


@pytest.mark.parametrize("name, content, message", [
    ("deep.json", "[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ("deep2.json", '{"a":' * 100_000 + "1" + "}" * 100_000, "nested too deeply"),
    ("tables.toml", "[a.b.c.d]\nrobots = 1\n", "nested more than 3 deep"),
    ("big.toml", "# " + "x" * 1_100_000 + "\n", "larger than 1 MB"),
])
def test_a_config_file_that_is_not_one_is_refused_in_one_line(tmp_path, name, content, message):
    f = tmp_path / name
    f.write_text(content)
    with pytest.raises(ConfigError, match=message):
        load_config_file(f)


def test_a_config_path_that_is_not_a_file_is_refused_before_reading():
    started = time.monotonic()
    with pytest.raises(ConfigError, match="not a regular file"):
        load_config_file("/dev/zero")
    assert time.monotonic() - started < 1.0
