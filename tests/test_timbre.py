"""Timbre figures (pipelines.reports.timbre), aligned recordings (.recordings), the sawtooth
baseline (.baselines) and the bench/timbre.py driver, on synthesized signals."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import scipy.io.wavfile

from data_schemas.errors import ParameterError
from pipelines.reports import baselines, recordings, timbre

ROOT = Path(__file__).resolve().parents[1]
SR = 44100


def one_note(pitch: int, seconds: float) -> pd.DataFrame:
    return pd.DataFrame({"start_s": [0.0], "end_s": [seconds], "midi_pitch": [pitch],
                         "velocity": [64]})


def hz(pitch: float) -> float:
    return 440.0 * 2.0 ** ((pitch - 69.0) / 12.0)


def tone(f: float, seconds: float = 1.0) -> np.ndarray:
    return np.sin(2 * np.pi * f * np.arange(int(seconds * SR)) / SR)


# --- Frechet distance -------------------------------------------------------------------

def test_frechet_distance_of_a_set_with_itself_is_zero():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(4000, 6)) @ rng.normal(size=(6, 6))
    assert timbre.frechet_distance(x, x) == pytest.approx(0.0, abs=1e-6)


def test_frechet_distance_grows_with_a_mean_shift_as_its_square():
    rng = np.random.default_rng(2)
    x = rng.normal(size=(3000, 4)) * np.array([1.0, 2.0, 0.5, 3.0])
    direction = np.array([1.0, -2.0, 0.5, 1.0])
    for scale in (0.5, 1.0, 3.0):
        shift = scale * direction
        # same covariance exactly, so the trace term vanishes
        assert timbre.frechet_distance(x + shift, x) == pytest.approx(
            np.sum(shift ** 2), rel=1e-6, abs=1e-6)


def test_gaussian_frechet_matches_the_closed_form_for_diagonal_covariances():
    s1, s2 = np.array([1.0, 4.0, 9.0]), np.array([4.0, 1.0, 0.25])
    mu = np.array([1.0, 2.0, -1.0])
    # commuting covariances: Tr(S1 + S2 - 2 sqrt(S1 S2)) = sum (sqrt s1 - sqrt s2)^2
    truth = np.sum(mu ** 2) + np.sum((np.sqrt(s1) - np.sqrt(s2)) ** 2)
    got = timbre.gaussian_frechet(mu, np.diag(s1), np.zeros(3), np.diag(s2))
    assert got == pytest.approx(truth, rel=1e-9)


def test_frechet_distance_rejects_too_few_frames():
    with pytest.raises(ParameterError):
        timbre.frechet_distance(np.zeros((1, 3)), np.zeros((5, 3)))


# --- harmonics ----------------------------------------------------------------------------

def analytic_ratio_db(amplitude, first: int, last: int) -> float:
    """10 log10 of the mean power of harmonics first..last re harmonic 1."""
    k = np.arange(first, last + 1)
    return float(10 * np.log10(np.mean(amplitude(k) ** 2) / amplitude(1) ** 2))


@pytest.mark.parametrize("pitch, detune_cents", [(55, 0.0), (62, 23.0), (69, -31.0)])
def test_harmonic_levels_of_a_sawtooth_match_the_analytic_values(pitch, detune_cents):
    f0 = hz(pitch) * 2 ** (detune_cents / 1200)
    m = timbre.measure(baselines.sawtooth(f0, SR, SR), SR, one_note(pitch, 1.0))
    saw = lambda k: 1.0 / np.asarray(k, dtype=float)  # noqa: E731
    assert m.figures["h6_10_db"] == pytest.approx(analytic_ratio_db(saw, 6, 10), abs=1.0)
    assert m.figures["h11_20_db"] == pytest.approx(analytic_ratio_db(saw, 11, 20), abs=1.0)


def test_harmonic_levels_follow_any_spectrum_not_only_a_sawtooth():
    f0 = hz(57)
    amp = lambda k: np.exp(-0.3 * np.asarray(k, dtype=float))  # noqa: E731
    t = np.arange(SR) / SR
    audio = sum(amp(k) * np.sin(2 * np.pi * k * f0 * t + k) for k in range(1, 40))
    m = timbre.measure(audio, SR, one_note(57, 1.0))
    assert m.figures["h6_10_db"] == pytest.approx(analytic_ratio_db(amp, 6, 10), abs=1.0)
    assert m.figures["h11_20_db"] == pytest.approx(analytic_ratio_db(amp, 11, 20), abs=1.0)


def test_harmonics_above_fmax_are_left_out():
    pitch = 96  # C7, 2093 Hz: harmonics 7+ lie above 14 kHz
    m = timbre.measure(baselines.sawtooth(hz(pitch), SR, SR), SR, one_note(pitch, 1.0))
    assert m.figures["h11_20_db"] is None
    # only harmonics 6 (12.6 kHz) counts in 6..10
    assert m.figures["h6_10_db"] == pytest.approx(10 * np.log10(1 / 36), abs=1.0)


def test_harmonic_to_noise_drops_by_the_added_noise_power():
    rng = np.random.default_rng(3)
    saw = baselines.sawtooth(hz(60), SR, SR)
    noise = rng.normal(size=SR)
    table = one_note(60, 1.0)
    # noise well above the window's leakage floor (a clean sawtooth gives ~39 dB)
    quiet = timbre.measure(saw + 0.1 * noise, SR, table).figures["hnr_db"]
    loud = timbre.measure(saw + 0.1 * np.sqrt(10) * noise, SR, table).figures["hnr_db"]
    clean_saw = timbre.measure(saw, SR, table).figures["hnr_db"]
    assert clean_saw > quiet + 5.0 > 30.0
    assert quiet - loud == pytest.approx(10.0, abs=1.0)


# --- centroid, flatness, LTAS -----------------------------------------------------------------

@pytest.mark.parametrize("f", [440.0, 1000.0, 3150.0])
def test_centroid_of_a_pure_tone_is_its_frequency(f):
    spec = timbre.power_spectrogram(tone(f), SR)
    assert np.median(timbre.spectral_centroid(spec)) == pytest.approx(f, rel=0.02)


def test_flatness_of_white_noise_is_near_0_db_and_of_a_tone_far_below():
    noise = np.random.default_rng(4).normal(size=SR)
    flat_noise = np.median(timbre.spectral_flatness_db(timbre.power_spectrogram(noise, SR)))
    flat_tone = np.median(timbre.spectral_flatness_db(timbre.power_spectrogram(tone(700), SR)))
    # Gaussian noise: the power of a bin is exponential, so E[log] = log(mean) - gamma
    assert flat_noise == pytest.approx(10 * np.log10(np.exp(-np.euler_gamma)), abs=0.5)
    assert flat_tone < -40.0


@pytest.mark.parametrize("f, band", [(150.0, "100-200"), (300.0, "200-400"),
                                     (5000.0, "3200-6400"), (9000.0, "6400-12800")])
def test_ltas_octave_bands_of_a_tone_put_it_in_its_band(f, band):
    levels = timbre.ltas_bands_db(timbre.power_spectrogram(tone(f), SR))
    assert list(levels) == ["100-200", "200-400", "400-800", "800-1600", "1600-3200",
                            "3200-6400", "6400-12800"]
    assert levels[band] == pytest.approx(0.0, abs=0.1)
    assert max(v for k, v in levels.items() if k != band) < -30.0


def test_loudness_normalisation_sets_the_rms_of_the_sounding_span():
    audio = np.concatenate([np.zeros(SR), 0.3 * tone(500)])
    table = pd.DataFrame({"start_s": [1.0], "end_s": [2.0], "midi_pitch": [71]})
    out = timbre.normalise_loudness(audio, SR, table)
    assert np.sqrt(np.mean(out[SR:] ** 2)) == pytest.approx(timbre.TARGET_RMS, rel=1e-6)


def test_monophonic_frames_exclude_chords_and_note_edges():
    table = pd.DataFrame({"start_s": [0.0, 1.0, 1.0], "end_s": [1.0, 2.0, 2.0],
                          "midi_pitch": [69, 60, 64]})
    f0 = timbre.monophonic_f0(np.array([0.5, 0.99, 1.5]), table)
    assert f0[0] == pytest.approx(440.0)
    assert np.isnan(f0[1]) and np.isnan(f0[2])


# --- recordings ---------------------------------------------------------------------------

def write_csvs(tmp_path: Path, starts, ends, pitches, *, extra_alignment_row=False):
    notes = tmp_path / "rec_notes.csv"
    align = tmp_path / "rec_align.csv"
    ticks = np.arange(len(pitches)) * 12
    pd.DataFrame({"onset": ticks, "offset": ticks + 12, "pitch": pitches,
                  "velocity": 64}).to_csv(notes, index=False)
    rows = list(zip(starts, ends, strict=True)) + ([(9.0, 9.5)] if extra_alignment_row else [])
    pd.DataFrame(rows, columns=["start", "end"]).to_csv(align, index=False)
    return notes, align


def test_the_alignment_reader_rejects_mismatched_row_counts_naming_the_file(tmp_path):
    notes, align = write_csvs(tmp_path, [0.1, 0.5], [0.5, 0.9], [67, 69],
                              extra_alignment_row=True)
    with pytest.raises(ParameterError, match="rec_align.csv: 3 alignment rows.*2 notes"):
        recordings.read_aligned_notes(notes, align)


def test_the_alignment_reader_names_a_file_with_a_missing_column_or_missing(tmp_path):
    notes, align = write_csvs(tmp_path, [0.1], [0.5], [67])
    pd.DataFrame({"begin": [0.1], "end": [0.5]}).to_csv(align, index=False)
    with pytest.raises(ParameterError, match="rec_align.csv: missing column.*start"):
        recordings.read_aligned_notes(notes, align)
    with pytest.raises(ParameterError, match="nowhere.csv: file not found"):
        recordings.read_aligned_notes(tmp_path / "nowhere.csv", align)


def test_aligned_notes_drop_empty_notes_and_cut_at_the_window(tmp_path):
    notes, align = write_csvs(tmp_path, [0.2, 0.6, 0.6, 2.5], [0.6, 0.6, 3.0, 3.5],
                              [67, 69, 71, 72])
    table = recordings.read_aligned_notes(notes, align)
    assert table.attrs["dropped"] == 1 and table["midi_pitch"].tolist() == [67, 71, 72]
    first = recordings.first_seconds(table, 2.0)
    assert first["midi_pitch"].tolist() == [67, 71]
    assert first["end_s"].tolist() == [0.6, 2.0]


def test_the_aligned_midi_plays_at_the_aligned_times(tmp_path):
    from pipelines.score import read_score

    table = pd.DataFrame({"start_s": [0.25, 0.25, 0.8, 1.3], "end_s": [0.8, 0.8, 1.3, 2.016],
                          "midi_pitch": [62, 69, 69, 76], "velocity": [64, 64, 80, 64]})
    notes = read_score(recordings.write_aligned_midi(table, tmp_path / "a.mid"))
    notes = notes.sort_values(["onset", "midi_pitch"])
    assert notes["instrument"].unique().tolist() == ["violin"]
    np.testing.assert_allclose(notes["onset"], table["start_s"], atol=1e-9)
    np.testing.assert_allclose(notes["onset"] + notes["duration"], table["end_s"], atol=1e-9)
    assert notes["midi_pitch"].tolist() == [62, 69, 69, 76]


def test_an_unreadable_audio_file_is_named(tmp_path):
    bad = tmp_path / "broken.mp3"
    bad.write_bytes(b"not audio at all")
    with pytest.raises(ParameterError, match="broken.mp3: cannot read audio"):
        recordings.read_audio(bad, seconds=1.0)


def test_read_audio_mixes_to_mono_resamples_and_fits_the_length(tmp_path):
    path = tmp_path / "st.wav"
    t = np.arange(48000) / 48000
    stereo = np.stack([np.sin(2 * np.pi * 1000 * t), np.zeros_like(t)], axis=1)
    scipy.io.wavfile.write(path, 48000, stereo.astype(np.float32))
    audio = recordings.read_audio(path, seconds=1.5, sample_rate=SR)
    assert audio.shape == (int(1.5 * SR),) and np.all(audio[SR + 100:] == 0.0)
    spec = timbre.power_spectrogram(audio[:SR], SR)
    assert np.median(timbre.spectral_centroid(spec)) == pytest.approx(1000.0, rel=0.02)
    assert np.sqrt(np.mean(audio[1000:SR - 1000] ** 2)) == pytest.approx(0.5 / np.sqrt(2),
                                                                         rel=0.01)


def test_sawtooth_notes_sound_only_inside_their_aligned_spans():
    table = pd.DataFrame({"start_s": [0.1, 0.6], "end_s": [0.3, 0.9], "midi_pitch": [60, 67]})
    audio = baselines.sawtooth_notes(table, SR, SR)
    t = np.arange(SR) / SR
    inside = ((t >= 0.1) & (t < 0.3)) | ((t >= 0.6) & (t < 0.9))
    assert np.all(audio[~inside] == 0.0) and np.sqrt(np.mean(audio[inside] ** 2)) > 0.5


# --- the driver -----------------------------------------------------------------------------

def run_driver(args, env_path: str | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    if env_path is not None:
        env["PATH"] = env_path
    return subprocess.run([sys.executable, str(ROOT / "bench" / "timbre.py"), *args],
                          capture_output=True, text=True, env=env, timeout=120, cwd=ROOT)


def test_the_driver_measures_a_given_recording_and_reports_a_missing_peer(tmp_path):
    starts, ends, pitches = [0.1, 0.6, 1.1], [0.6, 1.1, 1.9], [62, 69, 74]
    notes, align = write_csvs(tmp_path, starts, ends, pitches)
    table = recordings.read_aligned_notes(notes, align)
    wav = tmp_path / "rec.wav"
    scipy.io.wavfile.write(wav, SR, (0.1 * baselines.sawtooth_notes(table, 2 * SR, SR))
                           .astype(np.float32))
    run = run_driver(["--recording", str(wav), str(notes), str(align), "--seconds", "2",
                      "--sources", "fluidr3,sawtooth", "--json"], env_path="/nonexistent")
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    rec = report["recordings"]["rec"]
    assert rec["notes"] == 3
    # the "render" is the recording itself: no distance, no spectral difference
    assert rec["figures"]["sawtooth"]["mfcc_frechet"] == pytest.approx(0.0, abs=1e-3)
    assert all(abs(v) < 0.01 for v in rec["ltas_diff_db"]["sawtooth"].values())
    assert rec["figures"]["fluidr3"]["centroid_hz"] is None
    assert "fluidsynth" in rec["figures"]["fluidr3"]["reason"]
    assert rec["figures"]["real"]["mfcc_frechet"] is None  # no other performer
    assert report["mean"]["figures"]["sawtooth"]["h6_10_db"] == pytest.approx(
        rec["figures"]["sawtooth"]["h6_10_db"])


def test_the_driver_fails_in_one_line_naming_the_bad_file(tmp_path):
    notes, align = write_csvs(tmp_path, [0.1, 0.5], [0.5, 0.9], [67, 69],
                              extra_alignment_row=True)
    run = run_driver(["--recording", str(tmp_path / "rec.wav"), str(notes), str(align),
                      "--json"])
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr.strip().splitlines() == [f"timbre: error: {tmp_path / 'rec.wav'}: "
                                               "file not found"]
    (tmp_path / "rec.wav").write_bytes(b"")
    run = run_driver(["--recording", str(tmp_path / "rec.wav"), str(notes), str(align),
                      "--json"])
    assert run.returncode == 2
    assert len(run.stderr.strip().splitlines()) == 1 and "rec_align.csv" in run.stderr
