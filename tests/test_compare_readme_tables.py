"""report.readme_tables: the deterministic result tables of the README and the validation page are what their
commands print.

Each generated block of README.md and docs/validation.md (between ``<!-- readme_tables:NAME -->`` markers) is
recomputed and must match exactly. The blastula and Hertz blocks take seconds; the spheroid block runs the 12 FE
checks cases (slow).
"""

from pathlib import Path

import pytest

from tissuemech.compare.report import readme_tables

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "validation.md"
README = ROOT / "README.md"


def _readme_block(name: str) -> str:
    blocks = readme_tables.blocks_in(PAGE.read_text())
    assert name in blocks, f"docs/validation.md lacks the generated block {name!r} (tissuemech readme-tables)"
    return blocks[name]


def test_the_readme_shows_the_spheroid_block_of_the_validation_page():
    assert list(readme_tables.blocks_in(README.read_text())) == ["spheroid"]
    assert readme_tables.blocks_in(README.read_text())["spheroid"] == _readme_block("spheroid")


def test_blocks_round_trip_through_the_parser():
    text = "intro\n" + readme_tables.render("hertz") + "\nmore\n"
    assert list(readme_tables.blocks_in(text)) == ["hertz"]
    row = [ln for ln in readme_tables.render("hertz").splitlines() if ln.startswith("| 0.3 |")][0]
    assert row.count("|") == 6  # delta/(2 a0) and four alphas


@pytest.mark.parametrize("name", ["hertz", "blastula"])
def test_readme_fast_tables_match_their_commands(name):
    assert _readme_block(name) == readme_tables.render(name)


@pytest.mark.slow
def test_readme_spheroid_table_matches_its_command():
    assert _readme_block("spheroid") == readme_tables.render("spheroid")


def test_unknown_block_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown README table"):
        readme_tables.render("bogus")
