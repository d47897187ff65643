"""The package's types (inline annotations and the native module's .pyi stub) pass
`mypy --strict`, alone and as a typed caller uses them."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import pytest

import pelage

HERE = pathlib.Path(__file__).parent


def _mypy(*args: str) -> subprocess.CompletedProcess[str]:
    try:
        import mypy  # noqa: F401
    except ImportError:
        if os.environ.get("PELAGE_REQUIRE_MYPY") == "1":
            pytest.fail("mypy is not installed (pip install mypy)")
        pytest.skip("needs mypy (pip install mypy)")
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", *args],
        capture_output=True,
        text=True,
        cwd=HERE,
    )


def test_the_package_passes_mypy_strict() -> None:
    package = pathlib.Path(pelage.__file__).parent
    assert (package / "py.typed").is_file() and (package / "_pelage.pyi").is_file()
    done = _mypy("-p", "pelage")  # the package as installed, stub and all
    assert done.returncode == 0, done.stdout + done.stderr
    assert "6 source files" in done.stdout, done.stdout
    source = HERE.parent / "python" / "pelage"
    if source.is_dir():  # and the sources in the repository
        done = _mypy(str(source))
        assert done.returncode == 0, done.stdout + done.stderr


def test_a_typed_caller_passes_mypy_strict() -> None:
    done = _mypy(str(HERE / "typed_usage.py"))
    assert done.returncode == 0, done.stdout + done.stderr
