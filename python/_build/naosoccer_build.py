"""The package's build backend: maturin's, with the ``naosoccer`` binary
put into the package first, so that ``pip install ./python`` installs the
simulator too (``naosoccer.binary_path()``), as a wheel from scripts/wheel
does.

The binary comes from ``cargo build --release --bin naosoccer`` in the
workspace around python/ (no libtorch), unless scripts/wheel already put
one in naosoccer/bin/. Editable installs get none: they find the checkout's
``target/`` build.
"""

import json
import os
import shutil
import subprocess
from pathlib import Path

import maturin
from maturin import (  # noqa: F401  (the rest of the backend, as maturin has it)
    build_editable,
    build_sdist,
    get_requires_for_build_editable,
    get_requires_for_build_sdist,
    get_requires_for_build_wheel,
    prepare_metadata_for_build_editable,
    prepare_metadata_for_build_wheel,
)

PACKAGE = Path(__file__).resolve().parent.parent
BUNDLED = PACKAGE / "naosoccer" / "bin" / "naosoccer"


def _build_binary() -> Path:
    manifest = PACKAGE.parent / "Cargo.toml"
    out = subprocess.run(
        ["cargo", "build", "--release", "--bin", "naosoccer", "--manifest-path", str(manifest),
         "--message-format=json-render-diagnostics"],
        check=True, stdout=subprocess.PIPE, text=True,
    )
    for line in out.stdout.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg.get("target", {}).get("name") == "naosoccer" \
                and msg.get("executable"):
            return Path(msg["executable"])
    raise RuntimeError("cargo built no naosoccer binary")


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    if BUNDLED.exists():
        return maturin.build_wheel(wheel_directory, config_settings, metadata_directory)
    BUNDLED.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(_build_binary(), BUNDLED)
    os.chmod(BUNDLED, 0o755)
    try:
        return maturin.build_wheel(wheel_directory, config_settings, metadata_directory)
    finally:
        # Left in place, the copy would shadow fresh target/ builds for
        # python/ used in place (find_binary prefers the package's own).
        shutil.rmtree(BUNDLED.parent)
