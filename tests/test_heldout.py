"""The held-out protocol file: its shape is checked, its scores found or clearly missing."""

from __future__ import annotations

import tomllib

import pytest

from data_schemas.errors import ArcoError, ParameterError, SchemaError
from pipelines.reports.heldout import (
    EXCERPT_KEYS,
    default_protocol_path,
    load_protocol,
    resolve,
    shared_data_dir,
)

GOOD = """
[protocol]
name = "t"
seeds = 2

[[excerpt]]
id = "a"
file = "A.mxl"
start_measure = 1
end_measure = 4
reason = "because"
period = "classical"
texture = "four parts"
techniques = ["slurs"]
"""


def _write(tmp_path, text):
    path = tmp_path / "p.toml"
    path.write_text(text)
    return path


def test_the_shipped_protocol_is_valid_and_names_quartet_excerpts():
    p = load_protocol()
    assert p.seeds == 5 and len(p.excerpts) >= 6
    assert len({e.file for e in p.excerpts}) == len(p.excerpts)  # six different works
    raw = tomllib.loads(default_protocol_path().read_text())
    assert [e.id for e in p.excerpts] == [t["id"] for t in raw["excerpt"]]
    assert all(len(e.reason) > 40 for e in p.excerpts)
    techniques = {t for e in p.excerpts for t in e.techniques}
    assert {"pizzicato", "double stops", "fast passages", "dynamics range"} <= techniques
    # never the works the project has already looked at
    for looked_at in ("K.421", "Op.64-No.3", "Op.76-No.2", "Borodin", "Op.18-No.1",
                      "Op.74-No.1"):
        assert not any(looked_at in e.file for e in p.excerpts), looked_at


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('seeds = 2', 'seeds = 0'), "seeds must be at least 1"),
    (lambda t: t.replace('seeds = 2', 'seeds = "2"'), "seeds = '2' must be a int"),
    (lambda t: t.replace('name = "t"\n', ''), "missing key 'name'"),
    (lambda t: t.replace('reason = "because"', 'reason = " "'), "reason must not be empty"),
    (lambda t: t.replace('reason = "because"\n', ''), "missing key 'reason'"),
    (lambda t: t.replace('end_measure = 4', 'end_measure = 0'), "start_measure <= end_measure"),
    (lambda t: t.replace('"A.mxl"', '"../A.mxl"'), "must be a MusicXML file name"),
    (lambda t: t.replace('"A.mxl"', '"A.pdf"'), "must be a MusicXML file name"),
    (lambda t: t.replace('["slurs"]', '["juggling"]'), "techniques ['juggling']"),
    (lambda t: t.replace('["slurs"]', '[]'), "non-empty list"),
    (lambda t: t + 'colour = "red"\n', "unknown key(s) ['colour']"),
    (lambda t: t + '[extra]\nx = 1\n', "unknown table(s) ['extra']"),
    (lambda t: t + t[t.index("[[excerpt]]"):], "repeated: ['a']"),
    (lambda t: t[:t.index("[[excerpt]]")], "no [[excerpt]] entries"),
    (lambda t: t.replace("[protocol]", "[protocol"), "not a TOML file"),
])
def test_a_bad_protocol_is_one_clear_schema_error(tmp_path, edit, message):
    path = _write(tmp_path, edit(GOOD))
    with pytest.raises(SchemaError) as err:
        load_protocol(path)
    assert message in str(err.value) and str(path) in str(err.value)
    assert "\n" not in str(err.value)


def test_a_good_protocol_loads_and_a_missing_one_is_named(tmp_path):
    p = load_protocol(_write(tmp_path, GOOD))
    assert (p.name, p.seeds, p.excerpts[0].techniques) == ("t", 2, ("slurs",))
    assert set(EXCERPT_KEYS) >= {"id", "file", "reason"}
    with pytest.raises(ParameterError, match="no such file"):
        load_protocol(tmp_path / "nowhere.toml")


def test_missing_shared_data_and_missing_files_are_clear_errors(tmp_path, monkeypatch):
    p = load_protocol(_write(tmp_path, GOOD))
    with pytest.raises(ParameterError, match="shared data not found"):
        resolve(p, tmp_path)
    (tmp_path / "openscore-quartets").mkdir()
    with pytest.raises(ParameterError, match="not in .*openscore-quartets: A.mxl"):
        resolve(p, tmp_path)
    (tmp_path / "openscore-quartets" / "A.mxl").write_text("x")
    assert resolve(p, tmp_path) == [tmp_path / "openscore-quartets" / "A.mxl"]
    monkeypatch.setenv("ARCO_SHARED_DATA", str(tmp_path))
    assert shared_data_dir() == tmp_path


def test_arco_compare_heldout_without_shared_data_is_one_line(tmp_path, monkeypatch, capsys):
    import pipelines.shared_data as shared
    from pipelines.cli.main import main


    monkeypatch.setattr(shared, "candidates", lambda: [tmp_path / "none"])
    assert main(["compare", "--heldout", "--methods", "rules", "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("arco compare: error: shared data not found") and "\n" not in err
    assert "ARCO_SHARED_DATA" in err
    assert issubclass(ParameterError, ArcoError)


def test_arco_compare_needs_scores_or_heldout_not_both(tmp_path, capsys):
    from pipelines.cli.main import main

    assert main(["compare", "--methods", "rules", "-o", str(tmp_path / "r")]) == 2
    assert "give SCORE files or --heldout" in capsys.readouterr().err
    assert main(["compare", "x.mxl", "--heldout", "--methods", "rules",
                 "-o", str(tmp_path / "r")]) == 2
    assert "not both" in capsys.readouterr().err
    assert main(["compare", "x.mxl", "--measures", "2", "--methods", "rules",
                 "-o", str(tmp_path / "r")]) == 2
    assert "apply to --heldout" in capsys.readouterr().err
