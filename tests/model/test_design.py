"""Design files (sandbox/model/design.py, docs/design-files.md): a run's goal, settings, seed and light
program kept in one file, replayed bit for bit from the command line, and every damaged or foreign file
refused in one line."""

from __future__ import annotations

import io
import json
import os
import re
import zipfile
from pathlib import Path

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.design import FORMAT, VERSION, DesignError, PatternRecorder, Replay, load, save
from sandbox.model.programs import LightProgram
from sandbox.model.simulation import Simulation
from tests.commands.test_cli import phototaxis

ROOT = Path(__file__).resolve().parents[2]
#: A quick world whose lights change often: 60 patterns in 600 steps.
QUICK = Config(robots=20, boxes=40, update_every=10, hold_steps=5)
QUICK_FLAGS = ["--robots", "20", "--boxes", "40", "--update-every", "10", "--hold-steps", "5", "--steps", "600",
               "--no-progress"]


def recorded(config: Config, steps: int, program=None) -> tuple[Simulation, PatternRecorder]:
    sim = Simulation(config.replace(steps=steps), program=program)
    recorder = PatternRecorder().attach(sim)
    sim.step(steps)
    return sim, recorder


def replayed(design, steps: int | None = None) -> Simulation:
    sim = Simulation(design.config, shape=design.shape, program=Replay(design), program_time_limit=0)
    sim.step(design.steps_run if steps is None else steps)
    return sim


@pytest.fixture(scope="module")
def star_design(tmp_path_factory) -> Path:
    """A design file from the command line: the star with switch and chase, 600 steps."""
    path = tmp_path_factory.mktemp("designs") / "star.npz"
    out = phototaxis("run", "--case", "star-switch", "--chase", "--seed", "3", *QUICK_FLAGS, "--json",
                     "--save-design", str(path))
    assert out.returncode == 0, out.stderr
    return path


# --------------------------------------------------------------- round trip
def test_a_design_saves_and_loads_whole(tmp_path):
    sim, recorder = recorded(QUICK.replace(shape="star", flare=1.75, seed=4), 300)
    design = recorder.design(sim, "paper (open loop)")
    save(design, tmp_path / "d.npz")
    back = load(tmp_path / "d.npz")
    assert back.config == design.config and back.seed == 4 and back.steps_run == 300
    assert np.array_equal(back.shape, sim.shape_vertices) and back.controller == "paper (open loop)"
    assert back.steps.tolist() == design.steps.tolist() and back.steps[0] == 0 and len(back.steps) > 20
    assert back.patterns.dtype == np.uint8 and np.array_equal(back.patterns, design.patterns)
    assert np.array_equal(back.patterns[-1], sim.light_intensities)  # the last is what is lit at the end
    assert back.result["state_digest"] == sim.state_digest()
    assert back.goal["vertices"] == sim.goal.vertices.tolist()
    assert not list(tmp_path.glob("*.part"))  # written whole, then renamed


def test_recording_changes_nothing_in_the_run():
    config = QUICK.replace(shape="star", seed=2, steps=200)
    plain = Simulation(config)
    plain.step(200)
    sim, recorder = recorded(config, 200)
    assert sim.state_digest() == plain.state_digest() and len(recorder) > 10


def test_a_reset_starts_the_recorded_program_afresh_and_a_late_start_is_refused():
    sim, recorder = recorded(QUICK.replace(seed=1), 100)
    sim.reset(seed=2)
    assert len(recorder) == 1 and recorder.patterns()[0].tolist() == [0]
    late = PatternRecorder()
    sim.step(30)
    late.attach(sim)
    with pytest.raises(DesignError, match="recorded from step 30, not from the world's start"):
        late.design(sim)


def test_a_design_records_its_cycles_only_when_one_paper_controller_lit_it_all():
    """The controller's cycle is the run's only while it lit the floor from the start: a light program
    taking over (and handing back), or a new goal's controller counting from 0, leave it uncounted."""
    config = QUICK.replace(update_every=1, hold_steps=1)  # a cycle of 211 steps
    sim, recorder = recorded(config, 250)
    assert recorder.design(sim).cycles == 1
    sim.use_program(Dimmer())
    sim.use_program(None)
    assert recorder.design(sim).result["cycles"] is None
    sim.reset()
    assert recorder.design(sim).cycles == 0  # a new world: counted afresh
    sim.set_shape(None, name="circle")
    assert recorder.design(sim).cycles is None


# ------------------------------------------------------------------ replay
@pytest.mark.parametrize("case, chase", [("star-switch", 0.0), ("star-switch", 2.0), ("circle", 2.0)])
def test_a_replay_rebuilds_the_run_bit_for_bit(case, chase):
    from sandbox.model.config import CASES

    sim, recorder = recorded(QUICK.replace(**CASES[case], chase=chase, seed=3), 300)
    design = recorder.design(sim)
    assert replayed(design).state_digest() == sim.state_digest()


def test_a_replay_one_step_late_is_not_the_same_run():
    """The replay test can fail: the same patterns, each a step late (an off-by-one), build another world."""
    sim, recorder = recorded(QUICK.replace(shape="star", seed=3), 300)
    design = recorder.design(sim)
    late = design.steps.copy()
    late[1:] += 1
    from dataclasses import replace

    assert replayed(replace(design, steps=late)).state_digest() != sim.state_digest()


class Dimmer(LightProgram):
    """Lights a disc at 0.37 and the rest at 0.05: intensities other than on and off."""

    every = 7

    def update(self, observation):
        d = np.linalg.norm(observation.light_centres - 32.5, axis=-1)
        return np.where(d < 4 + (observation.step // 7) % 9, 0.37, 0.05)


def test_a_programs_dimmed_lights_are_kept_exactly_and_replay_without_it(tmp_path):
    sim, recorder = recorded(QUICK.replace(seed=5), 300, program=Dimmer())
    save(recorder.design(sim, "Dimmer"), tmp_path / "dim.npz")
    design = load(tmp_path / "dim.npz")
    assert design.patterns.dtype == np.float64 and set(np.unique(design.patterns)) == {0.0, 0.05, 0.37}  # dark first
    assert replayed(design).state_digest() == sim.state_digest()


def test_the_command_line_replays_a_closed_loop_design_exactly(star_design):
    design = load(star_design)
    assert design.controller == "paper (closed loop: chase)" and design.config.chase == 2.0
    out = phototaxis("run", "--design", str(star_design), "--json", "--no-progress")
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["replayed_exactly"] is True and result["senses"] == []  # open loop: it looks at nothing
    assert result["steps"] == 600 and result["fraction_in_goal"] == design.result["fraction_in_goal"]
    assert replayed(design).state_digest() == design.result["state_digest"]
    text = phototaxis("run", "--design", str(star_design), "--no-progress")
    assert "replayed exactly:          yes" in text.stdout


# --------------------------------------------------------------- refusals
def write_npz(path: Path, **arrays) -> Path:
    with path.open("wb") as handle:
        np.savez_compressed(handle, **arrays)
    return path


def altered(source: Path, target: Path, *, edit=None, **arrays) -> Path:
    """``source``'s arrays with some changed (None: left out), and its header changed by ``edit(dict)``."""
    with np.load(source) as archive:
        content = {name: archive[name] for name in archive.files}
    if edit is not None:
        parsed = json.loads(str(content["header"]))
        edit(parsed)
        content["header"] = np.array(json.dumps(parsed))
    content.update(arrays)
    return write_npz(target, **{k: v for k, v in content.items() if v is not None})


def refused(path: Path, *flags: str) -> str:
    """The one line ``run --design path`` answers with (exit code 2)."""
    out = phototaxis("run", "--design", str(path), *flags)
    assert out.returncode == 2, out
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("phototaxis run: error: ") and "Traceback" not in out.stderr
    return lines[0]


def test_damaged_and_foreign_files_are_refused_in_one_line(star_design, tmp_path):
    raw = star_design.read_bytes()
    cut = tmp_path / "cut.npz"
    cut.write_bytes(raw[: len(raw) // 2])
    assert "is damaged (cut short or altered?)" in refused(cut)
    noise = tmp_path / "noise.npz"
    noise.write_bytes(np.random.default_rng(0).bytes(5000))
    assert "is not a design file: it is not a NumPy .npz archive" in refused(noise)
    png = tmp_path / "picture.npz"
    png.write_bytes((ROOT / "static" / "sandbox.png").read_bytes())
    assert "is not a design file: it is a PNG image" in refused(png)
    empty = tmp_path / "empty.npz"
    empty.write_bytes(b"")
    assert "it is empty" in refused(empty)
    foreign = write_npz(tmp_path / "weights.npz", w=np.zeros(3), b=np.ones(2))
    assert "a NumPy archive without a header (it holds w, b)" in refused(foreign)
    assert "no such file" in refused(tmp_path / "missing.npz").lower()


def test_a_designs_bytes_load_as_its_file_does_and_are_refused_in_the_same_words(star_design):
    """load_bytes (a page's upload, issue 56 item 7): the same design as load, the same one-line refusals,
    named after the upload."""
    from sandbox.model.design import MAX_FILE_BYTES, load_bytes

    raw = star_design.read_bytes()
    design, on_disk = load_bytes(raw, "up.npz"), load(star_design)
    assert design.config == on_disk.config and np.array_equal(design.patterns, on_disk.patterns)
    assert design.steps.tolist() == on_disk.steps.tolist() and design.result == on_disk.result
    for content, said in ((raw[: len(raw) // 2], "up.npz is damaged (cut short or altered?)"),
                          (b"", "up.npz is not a design file: it is empty"),
                          ((ROOT / "static" / "sandbox.png").read_bytes(), "up.npz is not a design file: it is a PNG image"),
                          (b"PK" + bytes(MAX_FILE_BYTES), "up.npz is too large: ")):
        with pytest.raises(DesignError) as caught:
            load_bytes(content, "up.npz")
        assert str(caught.value).startswith(said) and "\n" not in str(caught.value), str(caught.value)


def test_a_changed_byte_is_caught_by_the_archives_checksums(star_design, tmp_path):
    raw = bytearray(star_design.read_bytes())
    with zipfile.ZipFile(io.BytesIO(bytes(raw))) as archive:
        info = archive.getinfo("patterns.npy")
    middle = info.header_offset + 30 + len(info.filename) + len(info.extra) + info.compress_size // 2
    raw[middle] ^= 0xFF
    flipped = tmp_path / "flipped.npz"
    flipped.write_bytes(bytes(raw))
    assert "is damaged" in refused(flipped)


@pytest.mark.parametrize("change, said", [
    (dict(edit=lambda h: h.update(version=2)), "format version 2; this program reads version 1"),
    (dict(edit=lambda h: h.update(format="something-else")), "its header does not say format"),
    (dict(edit=lambda h: h.pop("steps_run")), "its header's 'steps_run' is NoneType, not int"),
    (dict(edit=lambda h: h["config"].update(robots=-5)), "its settings are refused: robots"),
    (dict(edit=lambda h: h["config"].update(wings=2)), "its settings are refused: unknown parameter(s): wings"),
    (dict(edit=lambda h: h.update(seed=99)), "its seed 99 is not its settings' 3"),
    (dict(edit=lambda h: h["light_field"].update(pitch_m=0.5)), "light field's pitch_m disagree"),
    (dict(edit=lambda h: h["goal"].update(given=[[0, 0], [1, 1]])), "its goal is not a polygon"),
    (dict(patterns=None), "it has no 'patterns' array"),
    (dict(steps=None), "it has no 'steps' array"),
    (dict(steps=np.arange(61) * 10 + 5), "must start at 0 and never go back"),
    (dict(steps=np.arange(61)[::-1].copy()), "must start at 0 and never go back"),
    (dict(patterns=np.zeros((61, 32, 32), np.uint8)), "'patterns' is (61, 32, 32)"),
    (dict(patterns=np.full((61, 64, 64), 3, np.uint8)), "on / off patterns hold values other than 0 and 1"),
    (dict(patterns=np.full((61, 64, 64), -1.0)), "finite and not negative"),
    (dict(patterns=np.zeros((61, 64, 64), np.float32)), "uint8 0 / 1 or float64"),
    (dict(steps=np.zeros(61)), "'steps' must be a list of whole steps"),
])
def test_inconsistent_designs_are_refused_in_one_line(star_design, tmp_path, change, said):
    design = load(star_design)
    assert len(design.steps) == 61  # the numbers above are this design's
    assert said in refused(altered(star_design, tmp_path / "bad.npz", **change))


def test_a_header_that_is_not_json_is_damage(star_design, tmp_path):
    bad = altered(star_design, tmp_path / "bad.npz", **{"header": np.array("{not json")})
    assert "its header is not valid JSON" in refused(bad)
    pickled = altered(star_design, tmp_path / "pickled.npz", **{"header": np.array([{"format": FORMAT}], dtype=object)})
    assert "is damaged" in refused(pickled)  # numpy would need a pickle to read it: never unpickled


def test_a_refused_design_leaves_a_file_being_written_untouched(star_design, tmp_path):
    """Nothing running is lost: a refused --design does not start, so --save-design writes nothing."""
    target = tmp_path / "out.npz"
    target.write_bytes(b"the designer's earlier work")
    cut = tmp_path / "cut.npz"
    cut.write_bytes(star_design.read_bytes()[:100])
    refused(cut, "--save-design", str(target))
    assert target.read_bytes() == b"the designer's earlier work"


# ------------------------------------------------------------------- flags
@pytest.mark.parametrize("flags, named", [
    (["--shape", "star"], "--shape"), (["--seed", "4"], "--seed"), (["--case", "circle"], "--case"),
    (["--controller", "examples/shrinking_ring.py:ShrinkingRing"], "--controller"),
    (["--robots", "10", "--flare"], "--robots, --flare"),
])
def test_design_refuses_flags_that_would_choose_the_world(star_design, flags, named):
    line = refused(star_design, *flags)
    assert line.endswith(f"--design brings the file's own goal, settings and seed: leave out {named}")


def test_save_design_refuses_a_place_it_could_not_write_before_running(tmp_path):
    out = phototaxis("run", *QUICK_FLAGS, "--save-design", str(tmp_path))
    assert out.returncode == 2 and "that is a directory" in out.stderr and out.stdout == ""


def test_serve_opens_the_designs_goal_settings_and_seed(star_design, monkeypatch):
    from sandbox.commands import serve as server

    opened = {}

    def app(config, **kwargs):  # stands in for the App: what it would be started with
        opened.update(config=config, **kwargs)
        raise OSError(98, "stopped here by the test")

    monkeypatch.setattr(server, "App", app)
    out = phototaxis("serve", "--design", str(star_design), "--port", "0")
    design = load(star_design)
    assert out.returncode == 2 and opened["config"] == design.config and opened["config"].seed == 3
    assert np.array_equal(opened["shape"], design.shape) and opened["controller"] is None
    assert opened["design"].steps_run == design.steps_run  # its recorded light program plays in the page
    compared = phototaxis("serve", "--design", str(star_design), "--compare", "star", "circle")
    assert compared.returncode == 2 and "leave out --compare" in compared.stderr


# -------------------------------------------------------------------- docs
def test_the_docs_python_and_numpy_snippets_run(tmp_path, monkeypatch):
    text = (ROOT / "docs" / "design-files.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    exec(compile(blocks[0], "design-files.md (Python)", "exec"), {})  # records, saves, loads and replays
    names: dict = {}
    exec(compile(blocks[1], "design-files.md (numpy)", "exec"), names)
    design = load(tmp_path / "star.npz")
    grid = names["grid"]
    assert (grid["rows"], grid["cols"], grid["pitch_m"], grid["step_seconds"]) == (64, 64, 1.0, 1 / 30)
    for step in (0, 1, 99, 100, 550, 999):
        k = np.searchsorted(design.steps, step, side="right") - 1
        assert np.array_equal(names["pattern_at"](step), design.patterns[k])
    lit = names["lit"]  # the last pattern's lit lights, in metres
    assert np.array_equal(lit, (np.argwhere(design.patterns[-1] > 0) + 0.5) * 1.0)
    header = json.loads(str(np.load(tmp_path / "star.npz")["header"]))
    assert header["format"] == FORMAT and header["version"] == VERSION


def test_the_format_is_linked_from_the_readme_and_the_cli_page():
    assert "docs/design-files.md" in (ROOT / "README.md").read_text(encoding="utf-8")
    assert "design-files.md" in (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    assert os.path.exists(ROOT / "docs" / "design-files.md")
