"""planners.kernel_cache: numba's cache is cleared when any planners source changed."""

import os
import subprocess
import sys
from pathlib import Path

from planners import kernel_cache
from planners.kernel_cache import STAMP, refresh, sources_digest


def _package(tmp_path: Path) -> tuple[Path, Path]:
    pkg = tmp_path / "pkg"
    cache = pkg / "__pycache__"
    cache.mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "b.py").write_text("y = 2\n")
    for name in ("a.f-3.py311.nbi", "a.f-3.py311.1.nbc", "a.cpython-311.pyc"):
        (cache / name).write_text("old")
    return pkg, cache


def test_refresh_clears_the_cache_once_per_change_of_any_source(tmp_path):
    pkg, cache = _package(tmp_path)
    assert refresh(pkg, cache)  # no stamp: the cache's sources are unknown
    assert sorted(p.name for p in cache.iterdir()) == ["a.cpython-311.pyc", STAMP]
    (cache / "a.f-3.py311.nbi").write_text("new")
    assert not refresh(pkg, cache)  # same sources: the cache stays
    assert (cache / "a.f-3.py311.nbi").exists()
    before = sources_digest(pkg)
    (pkg / "b.py").write_text("y = 3\n")  # another file than the kernel's own
    assert sources_digest(pkg) != before
    assert refresh(pkg, cache)
    assert not (cache / "a.f-3.py311.nbi").exists()
    assert (cache / STAMP).read_text().strip() == sources_digest(pkg)


def test_the_planners_cache_is_stamped_with_the_current_sources():
    directory = kernel_cache.cache_dir()
    if directory is None or not os.access(directory, os.W_OK):
        return  # numba caches nothing here
    # importing planners refreshed it (and whatever ran since changed no source)
    assert (directory / STAMP).read_text().strip() == sources_digest()


CALLEE = "import numba\n\n@numba.njit(cache=True)\ndef f():\n    return {}\n"
CALLER = ("import numba\nfrom pkg.callee import f\n\n"
          "@numba.njit(cache=True)\ndef g():\n    return f()\n")
SCRIPT = """
import sys
from pathlib import Path
sys.path.insert(0, sys.argv[1])
from planners.kernel_cache import refresh
refresh(Path(sys.argv[1]) / "pkg")
from pkg.caller import g
print(g())
"""


def test_a_kernel_sees_its_callees_edit_in_another_file(tmp_path):
    # numba alone would load g's cached code with the old f compiled in
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "caller.py").write_text(CALLER)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}

    def run() -> str:
        out = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path)], env=env,
                             capture_output=True, text=True, check=True)
        return out.stdout.strip()

    (pkg / "callee.py").write_text(CALLEE.format(1))
    assert run() == "1"
    assert run() == "1"  # from the cache
    (pkg / "callee.py").write_text(CALLEE.format(2))
    assert run() == "2"
