"""Builds pelage's shared library with cargo and bundles it in the package.

Everything static is in pyproject.toml; this file adds the two steps
setuptools cannot declare: `build_py` also runs
`cargo build --release --locked -p pelage-capi` in the repository this
folder belongs to and copies the shared library next to the package's
modules, and the wheel is tagged `py3-none-<platform>`, since the package
loads the library through cffi's ABI mode and holds no extension compiled
against a Python.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

try:
    from setuptools.command.bdist_wheel import bdist_wheel
except ImportError:  # setuptools < 70.1
    from wheel.bdist_wheel import bdist_wheel

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
LIBRARY = {"win32": "pelage.dll", "darwin": "libpelage.dylib"}.get(sys.platform, "libpelage.so")


def workspace_version() -> str:
    """The version of the Cargo workspace, so the package and the library agree."""
    text = (REPO / "Cargo.toml").read_text(encoding="utf-8")
    match = re.search(r'^\[workspace\.package\][^\[]*?^version\s*=\s*"([^"]+)"', text, re.M | re.S)
    if not match:
        raise RuntimeError("no [workspace.package] version in Cargo.toml")
    return match.group(1)


def cargo_build() -> Path:
    """Builds the C API's shared library and returns its path."""
    cargo = os.environ.get("CARGO", "cargo")
    if shutil.which(cargo) is None:
        raise RuntimeError("pelage: cargo is needed to build the library (https://rustup.rs)")
    subprocess.run([cargo, "build", "--release", "--locked", "-p", "pelage-capi"], cwd=REPO, check=True)
    meta = subprocess.run(
        [cargo, "metadata", "--format-version", "1", "--no-deps", "--locked"],
        cwd=REPO, check=True, capture_output=True, text=True,
    )
    return Path(json.loads(meta.stdout)["target_directory"]) / "release" / LIBRARY


class BuildWithCargo(build_py):
    """build_py that also bundles the cargo-built shared library."""

    def run(self) -> None:
        super().run()
        library = cargo_build()
        target = Path(self.build_lib) / "pelage" / LIBRARY
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(library, target)
        if sys.platform.startswith("linux") and shutil.which("strip"):
            # the release profile keeps line tables (debug = 1): 10 MB of them
            subprocess.run(["strip", "--strip-debug", str(target)], check=True)
        # the declarations cargo just regenerated (build.rs) are the ones bundled
        shutil.copyfile(HERE / "pelage" / "_cdef.h", target.parent / "_cdef.h")


class BinaryDistribution(Distribution):
    """A distribution with a native library: a platform wheel."""

    def has_ext_modules(self) -> bool:
        return True


class PlatformWheel(bdist_wheel):
    """Tags the wheel py3-none-<platform>: any CPython 3 (or PyPy) on this platform."""

    def get_tag(self):  # type: ignore[no-untyped-def]
        _, _, platform = super().get_tag()
        return "py3", "none", platform


setup(
    version=workspace_version(),
    cmdclass={"build_py": BuildWithCargo, "bdist_wheel": PlatformWheel},
    distclass=BinaryDistribution,
)
