"""kill -9 (and Ctrl-C) of a parallel ``build-db`` or ``train``: no worker outlives it 5 s.

The run starts in its own session; its workers are found through ``/proc`` (children whose
parent is the run), the run is killed, and each worker must be gone (or a zombie) in 5 s.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from data_schemas.io import atomic_path, remove_stale_temps

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")

ROOT = Path(__file__).resolve().parents[1]


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, parent pid) of a process, or None when it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text.rsplit(")", 1)[1].split()
    return fields[0], int(fields[1])


def _children(parent: int) -> set[int]:
    out = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            got = _stat(int(entry.name))
            if got is not None and got[1] == parent and got[0] != "Z":
                out.add(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    got = _stat(pid)
    return got is not None and got[0] != "Z"


def _as_a_terminal_starts_it() -> None:
    """In the child before exec: Ctrl-C at its default, as a shell starts a foreground job.

    An ignored SIGINT is inherited through exec, and Python then installs no handler of its
    own; the test runner's worker (pytest-xdist under ``make test``) may be such a process.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(argv: list[str], tmp_path: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "pipelines.cli.main", *argv], cwd=tmp_path,
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True, preexec_fn=_as_a_terminal_starts_it)


def _ignores_sigint(pid: int) -> bool:
    """Whether process ``pid`` ignores SIGINT (its /proc status SigIgn mask)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigIgn:"):
            return bool(int(line.split()[1], 16) & (1 << (signal.SIGINT - 1)))
    return False


def _workers_of(proc: subprocess.Popen, want: int, timeout: float = 90.0,
                settle: float = 1.0) -> set[int]:
    deadline = time.monotonic() + timeout
    seen: set[int] = set()
    while time.monotonic() < deadline and proc.poll() is None:
        seen |= _children(proc.pid)
        if len(seen) >= want:
            time.sleep(settle)  # let the workers start their jobs
            return seen | _children(proc.pid)
        time.sleep(0.1)
    proc.kill()
    pytest.fail(f"no {want} workers appeared: {proc.stderr.read().decode()[-2000:]}")


def _assert_gone(workers: set[int], within: float = 5.0) -> None:
    deadline = time.monotonic() + within
    while time.monotonic() < deadline and any(_alive(p) for p in workers):
        time.sleep(0.1)
    left = [p for p in workers if _alive(p)]
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived the run by {within} s"


@pytest.fixture(scope="module")
def takes(tmp_path_factory):
    from gesture_db.simulate import simulate_recordings

    rec = tmp_path_factory.mktemp("rec") / "rec"
    simulate_recordings(3000, 1, rec, seed=3, notes_per_take=150)  # 20 takes: seconds of work
    return rec


def _build_db(takes, tmp_path) -> subprocess.Popen:
    return _start(["build-db", str(takes), "-o", str(tmp_path / "db"), "--workers", "2"],
                  tmp_path)


def _train(tmp_path) -> subprocess.Popen:
    return _start(["train", "-o", str(tmp_path / "models"), "--workers", "2", "--quick",
                   "--pairs", "1:mf,2:mf", "--quiet"], tmp_path)


@pytest.mark.parametrize("command", ["build-db", "train"])
def test_kill_9_leaves_no_workers(takes, tmp_path, command):
    proc = _build_db(takes, tmp_path) if command == "build-db" else _train(tmp_path)
    workers = _workers_of(proc, 2)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    _assert_gone(workers)


def test_ctrl_c_stops_the_workers(takes, tmp_path):
    proc = _build_db(takes, tmp_path)
    workers = _workers_of(proc, 2, settle=1.0)  # the pool is working on the 20 takes
    assert proc.poll() is None, "the build ended before it could be interrupted"
    assert not _ignores_sigint(proc.pid), "the run was started with SIGINT ignored"
    os.killpg(proc.pid, signal.SIGINT)  # what the terminal sends on Ctrl-C
    code = proc.wait(timeout=30)
    err = proc.stderr.read().decode()
    assert code == 130 and "interrupted" in err and "Traceback" not in err, err
    _assert_gone(workers)


def test_killed_writes_temp_files_are_removed_on_the_next_write(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    stale = tmp_path / f".out.wav.{int(dead.stdout)}.abc123.tmp"
    stale.write_bytes(b"x" * 100)
    old_style = tmp_path / ".out.wav.q1w2e3.tmp"  # before the writer's pid was in the name
    old_style.write_bytes(b"x")
    mine = tmp_path / f".out.wav.{os.getpid()}.zzz.tmp"  # a write in progress (this process)
    mine.write_bytes(b"x")
    with atomic_path(tmp_path / "out.wav") as tmp:
        tmp.write_bytes(b"audio")
    assert not stale.exists() and not old_style.exists() and mine.exists()
    assert (tmp_path / "out.wav").read_bytes() == b"audio"
    sub = tmp_path / "db" / "sources"
    sub.mkdir(parents=True)
    (sub / f".a.parquet.{int(dead.stdout)}.x.tmp").write_bytes(b"x")
    assert remove_stale_temps(tmp_path / "db", recursive=True) == 1


def test_outputs_follow_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        with atomic_path(tmp_path / "report.html") as tmp:
            tmp.write_text("<p>")
    finally:
        os.umask(old)
    assert (tmp_path / "report.html").stat().st_mode & 0o777 == 0o640
