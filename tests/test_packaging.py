"""The wheel ships every subpackage: pyproject's explicit package list names each folder with an __init__.py
(a folder missing from it installs from a checkout and breaks in a wheel)."""

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_subpackage_is_listed_for_the_wheel():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {
        "tissuemech." + ".".join(p.parent.relative_to(ROOT).parts)
        for top in ("reduced", "fem", "compare")
        for p in (ROOT / top).rglob("__init__.py")
    }
    assert found - listed == set(), f"add to [tool.setuptools] packages: {sorted(found - listed)}"
