"""The left hand's expression in the rules: vibrato contour and intonation per note."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from data_schemas.errors import ParameterError
from data_schemas.instruments import finger_ratio
from pipelines.methods.feedback import scale_notes
from pipelines.perform.config import load_config, validate_config
from pipelines.perform.rules import perform_part
from pipelines.reports.vibrato import contour_figures, pitch_track

RATE, EXTENT = 6.0, 12.0


def plain_vibrato(**changes) -> dict:
    """Config with one fixed vibrato (no random or expressive variation), no intonation."""
    cfg = load_config()
    cfg["vibrato"].update(rate=RATE, extent=EXTENT, rate_sigma=0.0, extent_sigma=0.0,
                          performer_rate_sigma=0.0, performer_extent_sigma=0.0,
                          dynamic_rate=0.0, dynamic_extent=0.0, length_extent=0.0,
                          phrase_end_extent=1.0, **changes)
    cfg["intonation"].update(sigma=0.0, semitone_step=0.0, by_ear=False)
    return cfg


@pytest.fixture(scope="module")
def scale():
    """G3..G4 in 2 s notes: open G, D and A strings among stopped notes."""
    return scale_notes(tonic=55, octaves=1, tempo=30.0)


def note_rows(perf, k: int) -> pd.DataFrame:
    """Bowed rows of event ``k`` (its own string), sorted by time; the previous note's last
    row, at the same time as this note's first, left out."""
    ev = perf.events.iloc[k]
    a = perf.actions
    m = (a["time"] > ev["t0"] + 1e-4) & (a["time"] < ev["played_end"]) & \
        (a["string"] == ev["string"]) & (a["bow_force"] > 0)
    return a[m].sort_values("time")


def cents_of(rows: pd.DataFrame, semis: float) -> np.ndarray:
    """Finger ratio -> pitch deviation (cents) from the note ``semis`` above the open string."""
    r = rows["finger_ratio"].to_numpy(np.float64)
    return 1200.0 * np.log2((1.0 - finger_ratio(semis)) / (1.0 - r))


def open_and_stopped(perf) -> tuple[list[int], list[int]]:
    ratios = [note_rows(perf, k)["finger_ratio"].iloc[0] for k in range(len(perf.events))]
    return ([k for k, r in enumerate(ratios) if r == 0],
            [k for k, r in enumerate(ratios) if r > 0])


def test_the_finger_carries_the_configured_rate_and_extent(scale):
    cfg = plain_vibrato()
    perf = perform_part(scale, cfg)
    _, stopped = open_and_stopped(perf)
    assert stopped
    vib = cfg["vibrato"]
    for k in stopped:
        rows = note_rows(perf, k)
        t = rows["time"].to_numpy()
        t0 = perf.events["t0"].iloc[k]
        assert t[0] < t0 + vib["onset_delay"]  # the first row holds the note's own finger
        cents = cents_of(rows, round(-12.0 * np.log2(1.0 - float(rows["finger_ratio"].iloc[0]))))
        before = t < t0 + vib["onset_delay"]
        assert np.abs(cents[before]).max() < 0.01
        full = t > t0 + vib["onset_delay"] + vib["fade_in"]
        assert np.abs(cents[full]).max() == pytest.approx(EXTENT, abs=0.1)
        extent, rate, offset = contour_figures(cents[full], 1.0 / np.median(np.diff(t[full])))
        assert extent == pytest.approx(EXTENT / np.sqrt(2), rel=0.03)
        assert rate == pytest.approx(RATE, abs=0.15)
        assert abs(offset) < 1.5


def test_open_strings_have_no_vibrato_unless_asked(scale):
    perf = perform_part(scale, plain_vibrato())
    opened, _ = open_and_stopped(perf)
    assert len(opened) >= 2
    for k in opened:
        assert np.all(note_rows(perf, k)["finger_ratio"] == 0)
    asked = perform_part(scale, plain_vibrato(open_strings=True))
    for k in opened:
        r = note_rows(asked, k)["finger_ratio"].to_numpy(np.float64)
        cents = 1200.0 * np.log2(1.0 / (1.0 - r))
        assert cents.min() >= 0.0 and cents.max() == pytest.approx(EXTENT, abs=0.1)


def test_short_notes_and_switched_off_vibrato_hold_the_finger():
    fast = scale_notes(tonic=55, octaves=1, tempo=300.0)  # 0.2 s notes
    perf = perform_part(fast, plain_vibrato())
    for k in range(len(perf.events)):
        assert note_rows(perf, k)["finger_ratio"].nunique() == 1
    off = perform_part(scale_notes(tonic=55, octaves=1, tempo=30.0),
                       plain_vibrato(enabled=False))
    for k in range(len(off.events)):
        assert note_rows(off, k)["finger_ratio"].nunique() == 1


def test_the_seed_fixes_vibrato_and_intonation(scale):
    cfg = load_config()
    run = [perform_part(scale, cfg, rng=np.random.default_rng(s)).actions for s in (1, 1, 2)]
    pd.testing.assert_frame_equal(run[0], run[1])
    assert not np.allclose(run[0]["finger_ratio"], run[2]["finger_ratio"])


def test_intonation_spreads_stopped_notes_by_sigma_and_leaves_open_strings():
    cfg = plain_vibrato(enabled=False)
    cfg["intonation"]["sigma"] = 8.0
    notes = scale_notes(tonic=55, octaves=2, tempo=240.0, repeats=7)
    perf = perform_part(notes, cfg, rng=np.random.default_rng(3))
    offsets = []
    for k in range(len(perf.events)):
        r = float(note_rows(perf, k)["finger_ratio"].iloc[0])
        semis = -12.0 * np.log2(1.0 - r)
        if r == 0:
            continue
        offsets.append(100.0 * (semis - round(semis)))
    assert len(offsets) > 60
    assert np.std(offsets) == pytest.approx(8.0, rel=0.25)
    assert abs(np.mean(offsets)) < 3.0
    assert sum(r == 0 for r in [note_rows(perf, k)["finger_ratio"].iloc[0]
                                for k in range(len(perf.events))]) > 10


def test_a_rendered_note_sounds_the_vibrato():
    from synth.render import render_actions

    note = scale_notes(tonic=71, octaves=0, tempo=20.0)  # B4 for 3 s, stopped on the A string
    perf = perform_part(note, plain_vibrato())
    audio = render_actions(perf.actions, instrument="violin", seed=0)
    f0, times = pitch_track(audio, 44100)
    m = (times > 0.8) & (times < 2.6)
    cents = 1200.0 * np.log2(f0[m] / (440.0 * 2 ** (2 / 12)))
    extent, rate, _ = contour_figures(cents, 44100 / 256)
    assert extent == pytest.approx(EXTENT / np.sqrt(2), rel=0.25)
    assert rate == pytest.approx(RATE, abs=0.3)


@pytest.mark.parametrize(("section", "key", "value", "message"), [
    ("vibrato", "rate", 12.0, "vibrato.rate"),
    ("vibrato", "extent", -1.0, "vibrato.extent"),
    ("vibrato", "enabled", "yes", "vibrato.enabled"),
    ("vibrato", "onset_delay", 0.0, "vibrato.onset_delay"),
    ("intonation", "sigma", -2.0, "intonation.sigma"),
    ("intonation", "semitone_step", float("nan"), "intonation.semitone_step"),
    ("frames", "interval", 0.05, "too coarse"),
])
def test_bad_expression_settings_are_named(section, key, value, message):
    cfg = load_config()
    cfg[section][key] = value
    with pytest.raises(ParameterError, match=message):
        validate_config(cfg)
