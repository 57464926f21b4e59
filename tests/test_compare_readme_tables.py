"""compare.readme_tables: the README's deterministic result tables are what their commands print.

Each generated block of README.md (between ``<!-- readme_tables:NAME -->`` markers) is recomputed and
must match exactly. The blastula and Hertz blocks take seconds; the spheroid block runs the 12 FE
checks cases (slow).
"""

from pathlib import Path

import pytest

from tissuemech.compare.report import readme_tables

README = Path(__file__).resolve().parent.parent / "README.md"


def _readme_block(name: str) -> str:
    blocks = readme_tables.blocks_in(README.read_text())
    assert blocks, (
        "README.md has no readme_tables blocks: paste the output of python -m tissuemech.compare.readme_tables"
    )
    assert name in blocks, f"README.md lacks the generated block {name!r} (python -m tissuemech.compare.readme_tables)"
    return blocks[name]


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
