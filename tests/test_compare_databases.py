"""Comparisons over several gesture databases: each sampling seed on each database is one
unit of the bootstrap, so the intervals hold the spread of the databases' draws."""

from __future__ import annotations

import json
import shutil

import pandas as pd
import pytest


def _job(method, seed, share, draw=0):
    hist = {"1": 0, "2": 0, "3": 9, "4": 1, "5": 0}
    note = {"sustained_hops": 10, "helmholtz_share": share, "reached_helmholtz": True,
            "attack_ms": 30.0, "pitch_error_cents_median": 0.0, "level_error_db_median": 0.0,
            "sustained_class_histogram": hist, "failures": ["slow attack"] if draw else [],
            "contexts": ["attack"],
            "excerpt": "x", "seed": seed, "database": draw, "part": "violin I",
            "measure": 1, "pitch": "A4", "instrument": "violin"}
    return {"excerpt": "x", "method": method, "seed": seed, "draw": draw, "media": None,
            "figures": {"render_seconds": 1.0, "real_time_factor": 2.0, "audio_seconds": 2.0,
                        "helmholtz_share": share},
            "notes": [note] * 6}


def _done(draws):
    """rules plays 0.9; sampling 0.95 on the first database and 0.80 on the second."""
    share = {0: 0.95, 1: 0.80}
    return ([_job("rules", s, 0.9) for s in (0, 1)]
            + [_job("sampling", s, share[d], d) for s in (0, 1) for d in draws])


def test_the_second_database_widens_the_interval_and_undoes_the_win(tmp_path):
    from pipelines.reports.html import results_frame, write_report
    from pipelines.reports.summary import summarise

    one = summarise(_done([0]), excerpts=[{"name": "x"}], methods=["rules", "sampling"],
                    seeds=[0, 1], databases=["A"])
    two = summarise(_done([0, 1]), excerpts=[{"name": "x"}], methods=["rules", "sampling"],
                    seeds=[0, 1], databases=["A", "B"])
    # one database: every unit plays 0.95, a point interval above the rules' 0.9
    assert one["summary"]["sampling"]["helmholtz_share"] == pytest.approx(
        {"mean": 0.95, "low": 0.95, "high": 0.95})
    assert one["winners"]["helmholtz_share"] == "sampling"
    assert one["verdict"].startswith("On 1 excerpt x 2 seeds, sampling beats rules")
    # two databases: four units, two at 0.95 and two at 0.80 (mean 0.875); a resample of
    # four units all from one database has probability 1/16 > 2.5 %, so the interval reaches
    # both draws' figures and holds the rules' 0.9
    iv = two["summary"]["sampling"]["helmholtz_share"]
    assert iv["mean"] == pytest.approx((2 * 0.95 + 2 * 0.80) / 4)
    assert iv["low"] == pytest.approx(0.80) and iv["high"] == pytest.approx(0.95)
    assert two["winners"]["helmholtz_share"] is None
    assert two["verdict"].startswith(
        "On 1 excerpt x 2 seeds (x 2 gesture databases for sampling), rules and sampling "
        "do not separate on Helmholtz share")
    assert two["instruments"]["violin"]["verdict"].startswith(
        "On the violin parts of 1 excerpt x 2 seeds (x 2 gesture databases for sampling)")
    assert set(two["runs"]["sampling"]["x"]) == {"0", "1", "0@db1", "1@db1"}
    assert set(two["runs"]["rules"]["x"]) == {"0", "1"}
    assert two["setup"]["databases"] == ["A", "B"] and "databases' spread" in \
        two["setup"]["interval"]
    frame = results_frame(two)
    sampled = frame[frame["method"] == "sampling"].sort_values(["database", "seed"])
    assert sampled[["seed", "database"]].values.tolist() == [[0, 0], [1, 0], [0, 1], [1, 1]]
    assert sampled["helmholtz_share"].tolist() == [0.95, 0.95, 0.80, 0.80]
    write_report(two, tmp_path)
    assert pd.read_csv(tmp_path / "results.csv")["database"].max() == 1
    page = (tmp_path / "index.html").read_text()
    assert "gesture databases A, B" in page and "<td>0 (db 1)</td>" in page


def test_arco_compare_plays_sampling_on_each_database(tiny_db, tmp_path, capsys,
                                                      monkeypatch):
    from importlib import resources

    import pipelines.reports.compare as compare
    from pipelines.cli.main import main

    copy = tmp_path / "copy"
    shutil.copytree(tiny_db / "db", copy)
    opened = []
    real = compare._database

    def spy(db, search_config):
        opened.append(db)
        return real(db, search_config)

    monkeypatch.setattr(compare, "_database", spy)
    score = str(resources.files("pipelines").joinpath("data/mozart-k421.mxl"))
    out = tmp_path / "report"
    assert main(["compare", score, "--methods", "rules,sampling-open", "--db",
                 str(tiny_db / "db"), "--db", str(copy), "-o", str(out), "--start-measure",
                 "1", "--end-measure", "2", "--seeds", "1", "--quiet"]) == 0
    assert "(x 2 gesture databases for sampling)" in capsys.readouterr().out
    # each database opened up front (a bad one fails before any work), then by its job
    assert opened == [str(tiny_db / "db"), str(copy), str(tiny_db / "db"), str(copy)]
    results = json.loads((out / "results.json").read_text())
    runs = results["runs"]["sampling-open"]["mozart-k421"]
    assert set(runs) == {"0", "0@db1"} and set(results["runs"]["rules"]["mozart-k421"]) == {"0"}
    # the same database under another path plays the same notes
    same = ("helmholtz_share", "notes", "sustained_class3_share", "attack_ms_p90")
    assert {k: runs["0"][k] for k in same} == {k: runs["0@db1"][k] for k in same}


def test_a_database_given_twice_is_a_one_line_error(tiny_db, tmp_path, capsys):
    from importlib import resources

    from pipelines.cli.main import main

    score = str(resources.files("pipelines").joinpath("data/mozart-k421.mxl"))
    db = str(tiny_db / "db")
    assert main(["compare", score, "--methods", "sampling-open", "--db", db, "--db", db,
                 "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "given twice" in err
    assert not (tmp_path / "r").exists()
