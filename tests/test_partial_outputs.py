"""A failed run leaves no partial output set; db info plots beside the database."""

from __future__ import annotations

import pytest

from pipelines.cli.main import main
from tests.test_bad_inputs import _MUSICXML, _arco_fails, _recording


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    from data_schemas.recording import write_recording
    from gesture_db.build import build_database

    base = tmp_path_factory.mktemp("partial_db")
    rec = write_recording(_recording(), base / "take.parquet")
    build_database([rec], base / "db", workers=1, progress=False)
    return base / "db"


def _score(tmp_path, name="ok.musicxml", per_minute="120"):
    path = tmp_path / name
    path.write_text(_MUSICXML.format(per_minute=per_minute))
    return path


def test_render_bad_actions_suffix_writes_nothing(tmp_path, capsys):
    score = _score(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    err = _arco_fails(capsys, "render", score, "-o", out / "a.wav", "--actions", out / "a.txt")
    assert "--actions" in err and "a.txt" in err and ".parquet" in err
    assert list(out.iterdir()) == []


def test_render_failing_write_removes_the_files_it_made(tmp_path, capsys, monkeypatch):
    import pipelines.reports.plots as plots
    from data_schemas.errors import ParameterError

    def broken(*_a, **_k):
        raise ParameterError("plot failed")

    monkeypatch.setattr(plots, "plot_bowing", broken)
    score = _score(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    _arco_fails(capsys, "render", score, "-o", out / "a.wav", "--actions", out / "a.parquet",
                "--plot", out / "a.png", "--quiet")
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]


def test_compare_later_score_fails_leaves_no_report(tmp_path, capsys):
    good = _score(tmp_path)
    bad = tmp_path / "bad.mid"
    bad.write_bytes(b"MThd\x00\x00\x00\x06garbage")
    report = tmp_path / "report"
    err = _arco_fails(capsys, "compare", good, bad, "--methods", "rules", "-o", report,
                      "--quiet")
    assert str(bad) in err
    assert not report.exists()


def test_db_info_plots_beside_the_database(db, capsys):
    assert main(["db", "info", str(db), "--json"]) == 0
    plots = db.parent / "db-plots"
    assert sorted(plots.glob("*.png")) and not (db / "plots").exists()


def test_db_info_failure_leaves_no_plots(db, tmp_path, capsys, monkeypatch):
    import matplotlib.figure

    from data_schemas.errors import ParameterError

    calls = []
    real = matplotlib.figure.Figure.savefig

    def savefig(self, *a, **k):
        calls.append(1)
        if len(calls) > 1:
            raise ParameterError("disk full")
        return real(self, *a, **k)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)
    plots = tmp_path / "plots"
    _arco_fails(capsys, "db", "info", db, "--plots", plots, "--json")
    assert len(calls) == 2 and not plots.exists()
