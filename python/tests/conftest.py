"""Shared fixtures of the photopose Python tests: where the shared datasets, the examples and the
photopose executable are (set by ctest, python/CMakeLists.txt), scratch folders, a CLI runner."""

import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("PHOTOPOSE_SOURCE_DIR",
                                         pathlib.Path(__file__).resolve().parents[2]))
SHARED_DATA = pathlib.Path(os.environ.get("PHOTOPOSE_SHARED_DATA_DIR",
                                          SOURCE_DIR.parent / "shared" / "data"))


@pytest.fixture
def shared_data():
    if not SHARED_DATA.is_dir():
        pytest.fail(f"the shared datasets are not at {SHARED_DATA} (PHOTOPOSE_SHARED_DATA_DIR)")
    return SHARED_DATA


@pytest.fixture
def source_dir():
    return SOURCE_DIR


@pytest.fixture
def cli():
    """Runs the photopose executable; returns the CompletedProcess."""
    path = os.environ.get("PHOTOPOSE_CLI_PATH")
    if path is None and "PHOTOPOSE_BINARY_DIR" in os.environ:
        pytest.skip("configured with PHOTOPOSE_BUILD_TOOLS=OFF: no photopose executable to compare with")
    if not path or not os.path.exists(path):
        pytest.fail("PHOTOPOSE_CLI_PATH does not name the photopose executable (run under ctest)")

    def run(*args, check=True):
        done = subprocess.run([path, *map(str, args)], capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"photopose {' '.join(map(str, args))} exited "
                                 f"{done.returncode}:\n{done.stderr}")
        return done

    return run


@pytest.fixture
def assert_releases_gil():
    """Runs call() on a thread while this one counts 1 ms sleeps: a call that holds the GIL lets
    the loop run at most a few times (a C++ call never yields it); released, about once per ms."""
    import threading
    import time

    def check(call):
        done = threading.Event()
        ticks = 0
        worker = threading.Thread(target=lambda: (call(), done.set()))
        start = time.perf_counter()
        worker.start()
        while not done.is_set():
            ticks += 1
            time.sleep(0.001)
        worker.join()
        elapsed = time.perf_counter() - start
        assert elapsed > 0.05, "too quick to tell"
        assert ticks > elapsed / 0.001 * 0.2, f"{ticks} ticks in {elapsed:.3f} s: the GIL was held"

    return check
