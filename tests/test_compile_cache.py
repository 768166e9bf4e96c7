"""The disk cache of compiled code goes stale with no source of the kernel: code inlined from
one file into a loop in another is recompiled when either file changes."""

import os
import subprocess
import sys

from rollball import compile_cache, kernel
from rollball.sweeps import kernel as sweep_kernel

RUN = """
import sys
sys.path.insert(0, {folder!r})
from pathlib import Path
from rollball import compile_cache
compile_cache.SOURCES = (Path({folder!r}, "steps.py").resolve(), Path({folder!r}, "loop.py").resolve())
compile_cache.install()
import loop
print(loop.run())
"""


def _write(path, text, mtime_ns):
    path.write_text(text)
    os.utime(path, ns=(mtime_ns, mtime_ns))


def _run(folder):
    result = subprocess.run([sys.executable, "-c", RUN.format(folder=str(folder))], capture_output=True,
                            text=True, timeout=300, env={**os.environ, "NUMBA_CACHE_DIR": str(folder / "cache")})
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_a_change_to_the_inlined_steps_recompiles_the_loop_that_inlines_them(tmp_path):
    _write(tmp_path / "loop.py", "from numba import njit\nfrom steps import step\n\n"
           "@njit(cache=True)\ndef run():\n    return step()\n", 1_600_000_000_000_000_000)
    _write(tmp_path / "steps.py", "from numba import njit\n\n@njit(inline='always')\ndef step():\n    return 1\n",
           1_600_000_000_000_000_000)
    assert _run(tmp_path) == "1"
    assert list((tmp_path / "cache").rglob("loop.run-*.nbi"))            # kept on disk
    # the same size, a new time: numba alone would load the loop's cached code (and answer 1)
    _write(tmp_path / "steps.py", "from numba import njit\n\n@njit(inline='always')\ndef step():\n    return 2\n",
           1_700_000_000_000_000_000)
    assert _run(tmp_path) == "2"


def test_the_kernel_and_the_sweep_loop_are_stamped_with_every_kernel_source():
    for dispatcher in (sweep_kernel.run_batch, kernel.collocation_step):
        locator = dispatcher._cache._impl.locator
        assert isinstance(locator, compile_cache.LOCATORS)
        assert locator.get_source_stamp() == compile_cache.stamp()
    assert {path.name for path in compile_cache.SOURCES} == {"kernel.py"}
    assert len(compile_cache.SOURCES) == 2 and all(path.exists() for path in compile_cache.SOURCES)
