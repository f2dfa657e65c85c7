"""The build (meson.build) installs every module of the package and builds every compiled
kernel module (issue 23): meson has no glob, so a module added under src/occtrack but not named
in src/occtrack/meson.build would be missing from a wheel."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import occtrack

SRC = Path(__file__).resolve().parents[1] / "src" / "occtrack"
BUILD = (SRC / "meson.build").read_text()


def test_meson_build_names_every_module():
    listed = set(re.findall(r"^\s*'([^']+\.py|py\.typed)',$", BUILD, re.M))
    present = {p.relative_to(SRC).as_posix() for p in SRC.rglob("*.py")
               if "__pycache__" not in p.parts} | {"py.typed"}
    assert present - listed == set(), "modules missing from src/occtrack/meson.build"
    assert listed - present == set(), "src/occtrack/meson.build names modules that are gone"


def _extensions() -> list[tuple[str, str]]:
    return re.findall(r"^\s*\['([^']+)', '(_\w+)'\],$", BUILD, re.M)


def test_each_compiled_module_is_built_and_named_after_its_package():
    """One extension a package at most, named after it (filters/gmpmb/_gmpmb.pyx), and every
    _*.pyx under src/occtrack built."""
    built = {(SRC / package / f"{name}.pyx").resolve() for package, name in _extensions()}
    present = {p.resolve() for p in SRC.rglob("_*.pyx")}
    assert built == present
    for pyx in present:
        assert pyx.stem == "_" + pyx.parent.name
        assert len(list(pyx.parent.glob("*.pyx"))) == 1


def test_the_installed_kernels_are_compiled():
    """Every extension imports as a compiled module (the installed package, not src/, which
    holds no built module)."""
    for package, name in _extensions():
        where = "" if package == "." else "." + package.replace("/", ".")
        dotted = f"occtrack{where}.{name}"
        module = importlib.import_module(dotted)
        assert Path(module.__file__).suffix in (".so", ".pyd"), module.__file__
    print("occtrack from", Path(occtrack.__file__).parent)
