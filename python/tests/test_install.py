"""`cmake --install` puts the package where docs/python.md says, and it imports from there with
nothing but PYTHONPATH set."""

import os
import pathlib
import subprocess
import sys

import pytest


def test_installed_package_imports(tmp_path):
    binary_dir = os.environ.get("PHOTOPOSE_BINARY_DIR")
    cmake = os.environ.get("PHOTOPOSE_CMAKE_COMMAND", "cmake")
    if not binary_dir:
        pytest.fail("PHOTOPOSE_BINARY_DIR is not set (run under ctest)")
    prefix = tmp_path / "prefix"
    done = subprocess.run([cmake, "--install", binary_dir, "--prefix", str(prefix)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    site = prefix / os.environ["PHOTOPOSE_PYTHON_INSTALL_DIR"]
    package = site / "photopose"
    for name in ("__init__.py", "__init__.pyi", "py.typed"):
        assert (package / name).is_file(), name
    assert list(package.glob("_photopose*.so")), "the extension module is not installed"
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "PYTHONPATH": str(site)}
    code = ("import photopose; b, _ = photopose.simulate_block(num_lines=1, images_per_line=3); "
            "print(photopose.__file__, b.num_images)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    where, images = done.stdout.split()
    assert pathlib.Path(where).parent == package and images == "3"
