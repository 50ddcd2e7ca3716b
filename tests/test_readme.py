"""README.md stays true to the code it documents."""

from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def test_readme_names_the_test_command_ci_runs():
    ci = (README.parent / ".ci" / "run").read_text(encoding="utf-8")
    assert "python -m pytest -q" in README.read_text(encoding="utf-8")
    assert "python -m pytest -q" in ci


def test_readme_shows_the_example_light_program_as_it_is():
    example = (README.parent / "examples" / "shrinking_ring.py").read_text(encoding="utf-8")
    assert example in README.read_text(encoding="utf-8")
    assert len(example.strip().splitlines()) <= 25
