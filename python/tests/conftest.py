"""What the package's tests share: the repository's programs they run, each built once per
session with cargo (finger-sim, the emulator firmware image, the Rust reference printer)."""

import os
import subprocess
from pathlib import Path

import pytest

PYTHON_DIR = Path(__file__).resolve().parents[1]
ROOT = PYTHON_DIR.parent


def cargo(*args, cwd):
    out = subprocess.run([os.environ.get("CARGO", "cargo"), *args], cwd=cwd, capture_output=True, text=True)
    assert out.returncode == 0, f"cargo {' '.join(args)} failed:\n{out.stderr}"
    return out


def host_target_dir(base: Path, profile: str) -> Path:
    """Where a `--target host-tuple` build puts its binaries."""
    host = subprocess.run(["rustc", "--print", "host-tuple"], capture_output=True, text=True, check=True).stdout.strip()
    return base / host / profile


@pytest.fixture(scope="session")
def sim_program() -> Path:
    """finger-sim, built at the top (host)."""
    cargo("build", "--quiet", "-p", "finger-sim", "--target", "host-tuple", "--bin", "finger-sim", cwd=ROOT)
    p = host_target_dir(ROOT / "target", "debug") / "finger-sim"
    assert p.is_file(), p
    return p


@pytest.fixture(scope="session")
def fw_elf() -> Path:
    """The emulator firmware image (`cargo build --release` at the top)."""
    cargo("build", "--release", "--quiet", "--bin", "finger-fw", cwd=ROOT)
    p = ROOT / "target" / "thumbv7em-none-eabihf" / "release" / "finger-fw"
    assert p.is_file(), p
    return p


@pytest.fixture(scope="session")
def reference_lines():
    """python/reference's output: the f64 model on the bench scenes, shortest round-trip digits."""
    out = cargo("run", "--quiet", "--release", "-p", "softfinger-reference", cwd=PYTHON_DIR)
    lines = [l for l in out.stdout.splitlines() if l.strip()]
    assert lines, "the reference printed nothing"
    return lines
