"""README.md stays true to the code it documents."""

from pathlib import Path

from sandbox.model.config import markdown_table

README = Path(__file__).resolve().parent.parent / "README.md"


def test_parameter_table_matches_the_declaration():
    text = README.read_text(encoding="utf-8")
    table = text.split("<!-- params:begin -->")[1].split("<!-- params:end -->")[0].strip()
    assert table == markdown_table(), "regenerate with: python -c 'from sandbox.model.config import markdown_table; print(markdown_table())'"


def test_readme_names_the_test_command_ci_runs():
    ci = (README.parent / ".ci" / "run").read_text(encoding="utf-8")
    assert "python -m pytest -q" in README.read_text(encoding="utf-8")
    assert "python -m pytest -q" in ci


def test_readme_shows_the_example_light_program_as_it_is():
    example = (README.parent / "examples" / "shrinking_ring.py").read_text(encoding="utf-8")
    assert example in README.read_text(encoding="utf-8")
    assert len(example.strip().splitlines()) <= 25
