"""make bench cannot break unnoticed: every benchmark imports and has a main()
(scripts/bench.py --list), and the runner's options parse."""

from __future__ import annotations

import subprocess
import sys

from torqueloop.spec.repo import REPO_ROOT


def test_every_benchmark_imports() -> None:
    r = subprocess.run([sys.executable, str(REPO_ROOT / "scripts" / "bench.py"), "--list"],
                       capture_output=True, text=True, cwd=REPO_ROOT, timeout=300)
    assert r.returncode == 0, r.stderr
    listed = {line.split()[0] for line in r.stdout.splitlines() if line.strip()}
    files = {p.stem for p in (REPO_ROOT / "scripts" / "benches").glob("bench_*.py")}
    assert listed == files


def test_a_broken_benchmark_is_reported(tmp_path) -> None:
    """The check can fail: a benchmark importing a name that is gone (as
    bench_firmware once did) makes --list exit 1 and name it."""
    # a copy of the runner beside a benches/ folder of its own (the real one is
    # read by the test above, maybe at the same time on another xdist worker)
    (tmp_path / "benches").mkdir()
    (tmp_path / "bench.py").write_text((REPO_ROOT / "scripts" / "bench.py").read_text())
    (tmp_path / "benches" / "bench_ok.py").write_text("def main():\n    return 0\n")
    (tmp_path / "benches" / "bench_zz_planted.py").write_text(
        "from torqueloop.spec.system import NO_SUCH_NAME\n\ndef main():\n    return 0\n")
    r = subprocess.run([sys.executable, str(tmp_path / "bench.py"), "--list"],
                       capture_output=True, text=True, cwd=REPO_ROOT, timeout=120)
    assert "bench_ok" in r.stdout
    assert r.returncode == 1 and "bench_zz_planted" in r.stderr and "NO_SUCH_NAME" in r.stderr
